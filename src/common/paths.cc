#include "common/paths.h"

#include <cstdlib>
#include <filesystem>

namespace hgrasp {

std::string ProjectRoot() {
  if (const char* env = std::getenv("HGRASP_ROOT"); env != nullptr && *env != '\0') return env;
  return HGRASP_SOURCE_ROOT;
}

std::string ResolveDataPath(const std::string& relative) {
  namespace fs = std::filesystem;
  const fs::path p(relative);
  if (p.is_absolute() || fs::exists(p)) return relative;
  return (fs::path(ProjectRoot()) / p).string();
}

}  // namespace hgrasp
