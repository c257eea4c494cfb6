#include "common/yaml_file.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>
#include <system_error>
#include <vector>

#include <yaml-cpp/depthguard.h>

#include "common/error.h"

namespace hgrasp::yaml {
namespace {

namespace fs = std::filesystem;

// What kind of thing a non-regular file is, for the message.
std::string KindOf(const fs::file_status& s) {
  switch (s.type()) {
    case fs::file_type::directory:
      return "a directory";
    case fs::file_type::character:
      return "a character device";
    case fs::file_type::block:
      return "a block device";
    case fs::file_type::fifo:
      return "a FIFO";
    case fs::file_type::socket:
      return "a socket";
    default:
      return "not a regular file";
  }
}

// Line `line` (0-based) of `text`, its leading blanks dropped, cut to 60 characters.
std::string Excerpt(const std::string& text, int line) {
  std::size_t begin = 0;
  for (int i = 0; i < line && begin != std::string::npos; ++i) {
    begin = text.find('\n', begin);
    if (begin != std::string::npos) ++begin;
  }
  if (begin == std::string::npos || begin >= text.size()) return "";
  const std::size_t end = std::min(text.find('\n', begin), text.size());
  std::string_view s(text.data() + begin, end - begin);
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  constexpr std::size_t kMaxChars = 60;
  if (s.size() > kMaxChars) return std::string(s.substr(0, kMaxChars)) + "...";
  return std::string(s);
}

// The checks of the loaded node graph. Aliases make it a graph: each alias is the node it names,
// so a walk that follows them sees every copy, as any reader of the file would.
class ShapeCheck {
 public:
  explicit ShapeCheck(const std::string& path) : path_(path) {}

  void Walk(const YAML::Node& n, int depth) {
    if (++values_ > kMaxValues) {
      Fail(n, "more than " + std::to_string(kMaxValues) + " values with its aliases expanded",
           "a file of at most " + std::to_string(kMaxValues) +
               " values (aliases of aliases multiply: a 'billion laughs' file)");
    }
    const std::string& tag = n.Tag();
    // "?": no tag (a plain scalar or a collection); "!": a quoted scalar. Anything else was
    // written by the user as a tag.
    if (!tag.empty() && tag != "?" && tag != "!") {
      Fail(n, "the tag " + tag, "a value without a YAML tag (numbers, text and lists as written)");
    }
    if (!n.IsMap() && !n.IsSequence()) return;
    if (depth >= kMaxDepth) {
      Fail(n, "nesting deeper than " + std::to_string(kMaxDepth) + " levels",
           "maps and lists nested at most " + std::to_string(kMaxDepth) + " deep");
    }
    for (const YAML::Node& a : ancestors_) {
      if (a.is(n)) {
        Fail(n, "an alias inside the node it names",
             "aliases that name a node outside themselves (e.g. not &n [*n])");
      }
    }
    ancestors_.push_back(n);
    if (n.IsMap()) {
      for (const auto& kv : n) {
        Walk(kv.first, depth + 1);
        Walk(kv.second, depth + 1);
      }
    } else {
      for (const YAML::Node& child : n) Walk(child, depth + 1);
    }
    ancestors_.pop_back();
  }

 private:
  [[noreturn]] void Fail(const YAML::Node& at, const std::string& found,
                         const std::string& expected) const {
    throw InputError(Where(path_, at.Mark()), "", found, expected);
  }

  const std::string& path_;
  std::size_t values_ = 0;
  std::vector<YAML::Node> ancestors_;
};

}  // namespace

std::string Where(const std::string& path, const YAML::Mark& mark) {
  if (mark.line < 0) return path;
  return path + ":" + std::to_string(mark.line + 1);
}

std::string ReadText(const std::string& path, const std::string& expected) {
  if (path.empty()) throw InputError("", "file name", "", expected);
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) throw InputError(path, "", path, expected + ": no such file");
  if (!fs::is_regular_file(status)) {
    throw InputError(path, "", path, expected + ", not " + KindOf(status));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", path, expected + ": " + std::strerror(errno));
  std::string text(kMaxFileBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad()) throw InputError(path, "", path, expected + ": read failed");
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxFileBytes) {
    throw InputError(path, "", "a file of more than " + std::to_string(kMaxFileBytes) + " bytes",
                     expected + " of at most " + std::to_string(kMaxFileBytes >> 10) +
                         " kB (the project's files are a few kB)");
  }
  if (const std::size_t nul = text.find('\0'); nul != std::string::npos) {
    const auto line = std::count(text.begin(), text.begin() + static_cast<long>(nul), '\n') + 1;
    throw InputError(path + ":" + std::to_string(line), "",
                     "a NUL byte at byte " + std::to_string(nul) + " (binary data)",
                     expected + ", as text");
  }
  return text;
}

YAML::Node LoadDocument(const std::string& text, const std::string& path,
                        const std::string& expected) {
  std::vector<YAML::Node> docs;
  try {
    docs = YAML::LoadAll(text);
  } catch (const YAML::DeepRecursion& e) {
    throw InputError(Where(path, e.mark), "", "nesting deeper than " + std::to_string(e.depth()) + " levels",
                     "maps and lists nested at most " + std::to_string(kMaxDepth) + " deep");
  } catch (const YAML::Exception& e) {
    // The offending line as written, so the user sees what the parser choked on.
    const std::string line = e.mark.line >= 0 ? Excerpt(text, e.mark.line) : "";
    throw InputError(Where(path, e.mark), "YAML syntax", line.empty() ? e.msg : line,
                     "well-formed YAML (" + e.msg + ")");
  }
  if (docs.empty() || docs.front().IsNull()) {
    throw InputError(path, "top level", "", expected + " (the file is empty)");
  }
  if (docs.size() > 1) {
    throw InputError(Where(path, docs[1].Mark()), "top level", "---", "a single YAML document");
  }
  ShapeCheck(path).Walk(docs.front(), 0);
  return docs.front();
}

}  // namespace hgrasp::yaml
