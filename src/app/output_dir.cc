#include "app/output_dir.h"

#include <stdlib.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "common/error.h"

namespace hgrasp::app {

void CheckOutputFile(const std::string& path, const std::string& flag,
                     const std::string& expected) {
  namespace fs = std::filesystem;
  const fs::path out(path);
  if (path.empty()) throw InputError("", flag, "", expected);
  std::error_code ec;
  if (fs::is_directory(out, ec)) throw InputError("", flag, path, expected + " (it is a folder)");
  for (fs::path p = out.parent_path(); !p.empty(); p = p.parent_path()) {
    if (fs::exists(p, ec)) {
      if (!fs::is_directory(p, ec)) {
        throw InputError("", flag, path, expected + " (" + p.string() + " is a file)");
      }
      break;
    }
    if (p == p.parent_path()) break;
  }
}

void CreateOutputFileParents(const std::string& path, const std::string& flag,
                             const std::string& expected) {
  namespace fs = std::filesystem;
  const fs::path out(path);
  if (!out.has_parent_path()) return;
  std::error_code ec;
  fs::create_directories(out.parent_path(), ec);
  if (ec) {
    throw InputError("", flag, path,
                     expected + " (cannot create " + out.parent_path().string() + ": " +
                         ec.message() + ")");
  }
}
namespace {

namespace fs = std::filesystem;

[[noreturn]] void Refuse(const std::string& dir, const std::string& why) {
  throw InputError("", "--out", dir, "a folder hgrasp can write into (" + why + ")");
}

}  // namespace

OutputDir::OutputDir(std::string dir) : dir_(std::move(dir)) {
  if (dir_.empty()) throw InputError("", "--out", "", "an output folder");
  const fs::path p(dir_);
  std::error_code ec;
  const fs::file_status status = fs::status(p, ec);
  if (fs::exists(status)) {
    if (!fs::is_directory(status)) Refuse(dir_, "it is a file, not a folder");
  } else {
    // Create it, remembering which folders are new so that a failure can take them away again.
    std::vector<fs::path> missing;
    for (fs::path q = p; !q.empty(); q = q.parent_path()) {
      const fs::file_status s = fs::status(q, ec);
      if (fs::exists(s)) {
        if (!fs::is_directory(s)) Refuse(dir_, q.string() + " is a file, not a folder");
        break;
      }
      missing.push_back(q);
      if (q == q.parent_path()) break;
    }
    for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
      if (!fs::create_directory(*it, ec) || ec) {
        const std::string why = ec ? ec.message() : "it could not be created";
        RemoveCreated();
        Refuse(dir_, "cannot create " + it->string() + ": " + why);
      }
      created_.push_back(it->string());
    }
  }
  // The staging folder: proves the folder can be written into, before any work starts.
  std::string tmpl = (p / ".hgrasp-partial-XXXXXX").string();
  if (mkdtemp(tmpl.data()) == nullptr) {
    const std::string why = std::strerror(errno);
    RemoveCreated();
    Refuse(dir_, "cannot write into it: " + why);
  }
  staging_ = tmpl;
}

OutputDir::~OutputDir() {
  std::error_code ec;
  if (!staging_.empty()) fs::remove_all(staging_, ec);
  if (!committed_) RemoveCreated();
}

void OutputDir::RemoveCreated() {
  std::error_code ec;
  for (auto made = created_.rbegin(); made != created_.rend(); ++made) {
    fs::remove(*made, ec);  // only when empty: a folder someone else filled stays
  }
  created_.clear();
}

std::string OutputDir::Path(std::string_view name) const {
  return (fs::path(staging_) / std::string(name)).string();
}

void OutputDir::Commit() {
  std::error_code ec;
  std::vector<fs::path> staged;
  for (const fs::directory_entry& e : fs::directory_iterator(staging_, ec)) {
    staged.push_back(e.path());
  }
  if (ec) throw std::runtime_error(staging_ + ": cannot list the staged outputs: " + ec.message());
  // Every target must be free or a file before anything moves.
  for (const fs::path& from : staged) {
    const fs::path to = fs::path(dir_) / from.filename();
    const fs::file_status s = fs::symlink_status(to, ec);
    if (fs::exists(s) && !fs::is_regular_file(s) && !fs::is_symlink(s)) {
      throw InputError(to.string(), "--out", to.string(),
                       "a path where hgrasp can write its output file (a folder or other "
                       "non-file is in the way)");
    }
  }
  for (const fs::path& from : staged) {
    const fs::path to = fs::path(dir_) / from.filename();
    fs::rename(from, to, ec);
    if (ec) throw std::runtime_error(to.string() + ": cannot move the output into place: " + ec.message());
  }
  committed_ = true;
}

}  // namespace hgrasp::app
