#include "common/yaml_util.h"

#include <charconv>
#include <cmath>
#include <sstream>
#include <system_error>

namespace hgrasp::yaml {
// ---------------------------------------------------------------------------------------------
// Scalars, strictly: a number is a plain (unquoted) decimal scalar, finite; no YAML 1.1 octal or
// hexadecimal, no .inf or .nan.

bool IsQuoted(const YAML::Node& n) { return n.Tag() == "!"; }

namespace {
// A plain scalar: unquoted and untagged (yaml_file.h refuses tags when a file is read; a node
// built another way is held to the same rule).
bool Plain(const YAML::Node& n) { return n.IsScalar() && (n.Tag() == "?" || n.Tag().empty()); }
}  // namespace

std::optional<double> ParseNumber(const YAML::Node& n) {
  if (!Plain(n)) return std::nullopt;
  std::string_view s = n.Scalar();
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty() || s.front() == '+') return std::nullopt;
  double v = 0.0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::optional<std::uint64_t> ParseUnsigned(const YAML::Node& n) {
  if (!Plain(n)) return std::nullopt;
  std::string_view s = n.Scalar();
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty() || s.front() < '0' || s.front() > '9') return std::nullopt;
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v, 10);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

std::optional<long long> ParseInteger(const YAML::Node& n) {
  if (!Plain(n)) return std::nullopt;
  std::string_view s = n.Scalar();
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty() || s.front() == '+') return std::nullopt;
  long long v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v, 10);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

std::optional<bool> ParseBool(const YAML::Node& n) {
  if (!Plain(n)) return std::nullopt;
  const std::string& s = n.Scalar();
  if (s == "true" || s == "True" || s == "TRUE") return true;
  if (s == "false" || s == "False" || s == "FALSE") return false;
  return std::nullopt;
}

namespace {

// Longest rendering of a value in a message.
constexpr std::size_t kMaxRenderChars = 100;
// Deepest level rendered: the loaders' nodes are checked to be a tree of bounded depth
// (yaml_file.h), but a message must never be what runs away.
constexpr int kMaxRenderDepth = 8;

// Appends `n` in flow style, stopping once `out` is longer than a message shows.
void RenderTo(const YAML::Node& n, bool top, int depth, std::string* out) {
  if (!n.IsDefined() || n.IsNull() || out->size() > kMaxRenderChars) return;
  if (depth > kMaxRenderDepth) {
    *out += "...";
    return;
  }
  if (n.IsScalar()) {
    *out += !top && IsQuoted(n) ? "\"" + n.Scalar() + "\"" : n.Scalar();
  } else if (n.IsSequence()) {
    *out += "[";
    for (std::size_t i = 0; i < n.size() && out->size() <= kMaxRenderChars; ++i) {
      if (i > 0) *out += ", ";
      RenderTo(n[i], false, depth + 1, out);
    }
    *out += "]";
  } else if (n.IsMap()) {
    *out += "{";
    bool first = true;
    for (const auto& kv : n) {
      if (out->size() > kMaxRenderChars) break;
      if (!first) *out += ", ";
      first = false;
      RenderTo(kv.first, false, depth + 1, out);
      *out += ": ";
      RenderTo(kv.second, false, depth + 1, out);
    }
    *out += "}";
  }
}

}  // namespace

std::string Render(const YAML::Node& n) {
  std::string text;
  RenderTo(n, true, 0, &text);
  if (text.size() > kMaxRenderChars) text = text.substr(0, kMaxRenderChars - 3) + "...";
  return text;
}

// Said after "expected ..." when a number or flag was written in quotes.
std::string QuoteHint(const YAML::Node& n) {
  bool quoted = n.IsScalar() && IsQuoted(n);
  if (n.IsSequence()) {
    for (std::size_t i = 0; i < n.size(); ++i) {
      quoted = quoted || (n[i].IsScalar() && IsQuoted(n[i]));
    }
  }
  return quoted ? " (numbers and true/false go without quotes)" : "";
}

std::string Join(const std::string& path, std::string_view key) {
  return path.empty() ? std::string(key) : path + "." + std::string(key);
}

std::string Index(const std::string& path, std::size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

std::string OneOf(const Keys& names) {
  std::string s = "one of: ";
  for (std::size_t i = 0; i < names.size(); ++i) s += (i ? ", " : "") + std::string(names[i]);
  return s;
}

}  // namespace hgrasp::yaml
