#include "common/yaml_file.h"

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>
#include <system_error>
#include <vector>

#include <yaml-cpp/anchor.h>
#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/emitterstyle.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/parser.h>

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

// The offset of the first byte of `text` that is not printable UTF-8 as YAML 1.2 (5.1) allows
// it: tab, line feed, carriage return, U+0020-U+007E, U+0085, U+00A0-U+D7FF, U+E000-U+FFFD,
// U+10000-U+10FFFF, each in its shortest UTF-8 form; nullopt when there is none.
std::optional<std::size_t> FirstNonText(std::string_view text) {
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(text[i]); };
  for (std::size_t i = 0; i < text.size();) {
    const unsigned char c = byte(i);
    if (c < 0x80) {
      if (c < 0x20 && c != '\t' && c != '\n' && c != '\r') return i;
      if (c == 0x7f) return i;
      ++i;
      continue;
    }
    int extra = 0;
    std::uint32_t cp = 0;
    if (c >= 0xc2 && c <= 0xdf) {
      extra = 1, cp = c & 0x1f;
    } else if (c >= 0xe0 && c <= 0xef) {
      extra = 2, cp = c & 0x0f;
    } else if (c >= 0xf0 && c <= 0xf4) {
      extra = 3, cp = c & 0x07;
    } else {
      return i;  // a continuation byte first, an overlong lead, or beyond U+10FFFF
    }
    if (i + static_cast<std::size_t>(extra) >= text.size()) return i;  // cut short
    for (int k = 1; k <= extra; ++k) {
      const unsigned char d = byte(i + k);
      if ((d & 0xc0) != 0x80) return i;
      cp = (cp << 6) | (d & 0x3f);
    }
    const bool shortest =
        extra == 1 || (extra == 2 && cp >= 0x800) || (extra == 3 && cp >= 0x10000);
    const bool printable = cp == 0x85 || (cp >= 0xa0 && cp <= 0xd7ff) ||
                           (cp >= 0xe000 && cp <= 0xfffd) || (cp >= 0x10000 && cp <= 0x10ffff);
    if (!shortest || !printable) return i;
    i += static_cast<std::size_t>(extra) + 1;
  }
  return std::nullopt;
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
  return text;
}

YAML::Node LoadDocument(const std::string& text, const std::string& path,
                        const std::string& expected) {
  // YAML is printable Unicode text (YAML 1.2, 5.1), here UTF-8: checked before the parser sees
  // it, since yaml-cpp 0.7 loops without end, allocating, on a control character inside a flow
  // collection and on bytes that are no UTF-8 (both found by the loaders' fuzzer).
  if (const std::optional<std::size_t> bad = FirstNonText(text)) {
    const std::size_t i = *bad;
    const auto c = static_cast<unsigned char>(text[i]);
    const auto line = std::count(text.begin(), text.begin() + static_cast<long>(i), '\n') + 1;
    char what[80];
    if (c == 0) {
      std::snprintf(what, sizeof what, "a NUL byte at byte %zu (binary data)", i);
    } else if (c < 0x80) {
      std::snprintf(what, sizeof what, "the control character 0x%02x at byte %zu", c, i);
    } else {
      std::snprintf(what, sizeof what, "the byte 0x%02x at byte %zu, no UTF-8 text", c, i);
    }
    throw InputError(path + ":" + std::to_string(line), "", what,
                     expected + ", as UTF-8 text (YAML allows no control characters but tab and "
                                "line ends)");
  }
  // The documents' starts, from the parser's events alone, at most two: YAML::LoadAll loops
  // without end on a stray ',' before a document (yaml-cpp 0.7: each call finds "a document"
  // without consuming it; the loaders' fuzzer found it). A document that starts where the one
  // before it did is that stray token.
  class DocumentStarts : public YAML::EventHandler {
   public:
    std::vector<YAML::Mark> starts;
    void OnDocumentStart(const YAML::Mark& mark) override { starts.push_back(mark); }
    void OnDocumentEnd() override {}
    void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
    void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
    void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t,
                  const std::string&) override {}
    void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                         YAML::EmitterStyle::value) override {}
    void OnSequenceEnd() override {}
    void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                    YAML::EmitterStyle::value) override {}
    void OnMapEnd() override {}
  };
  const auto syntax = [&](const YAML::Mark& mark, const std::string& msg) {
    // The offending line as written, so the user sees what the parser choked on.
    const std::string line = mark.line >= 0 ? Excerpt(text, mark.line) : "";
    return InputError(Where(path, mark), "YAML syntax", line.empty() ? msg : line,
                      "well-formed YAML (" + msg + ")");
  };
  YAML::Node root;
  try {
    std::istringstream in(text);
    YAML::Parser parser(in);
    DocumentStarts documents;
    while (documents.starts.size() < 2 && parser.HandleNextDocument(documents)) {
    }
    if (documents.starts.size() > 1) {
      const YAML::Mark& second = documents.starts[1];
      if (second.pos == documents.starts[0].pos) {
        throw syntax(second, "a token outside any document, such as a stray ','");
      }
      throw InputError(Where(path, second), "top level", "---", "a single YAML document");
    }
    root = YAML::Load(text);
  } catch (const YAML::DeepRecursion& e) {
    throw InputError(Where(path, e.mark), "",
                     "nesting deeper than " + std::to_string(e.depth()) + " levels",
                     "maps and lists nested at most " + std::to_string(kMaxDepth) + " deep");
  } catch (const YAML::Exception& e) {
    throw syntax(e.mark, e.msg);
  }
  if (!root.IsDefined() || root.IsNull()) {
    throw InputError(path, "top level", "", expected + " (the file is empty)");
  }
  ShapeCheck(path).Walk(root, 0);
  return root;
}

}  // namespace hgrasp::yaml
