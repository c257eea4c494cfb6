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

std::optional<double> ParseNumber(const YAML::Node& n) {
  if (!n.IsScalar() || IsQuoted(n)) return std::nullopt;
  std::string_view s = n.Scalar();
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty() || s.front() == '+') return std::nullopt;
  double v = 0.0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::optional<std::uint64_t> ParseUnsigned(const YAML::Node& n) {
  if (!n.IsScalar() || IsQuoted(n)) return std::nullopt;
  std::string_view s = n.Scalar();
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty() || s.front() < '0' || s.front() > '9') return std::nullopt;
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v, 10);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

std::optional<long long> ParseInteger(const YAML::Node& n) {
  if (!n.IsScalar() || IsQuoted(n)) return std::nullopt;
  std::string_view s = n.Scalar();
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty() || s.front() == '+') return std::nullopt;
  long long v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v, 10);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

std::optional<bool> ParseBool(const YAML::Node& n) {
  if (!n.IsScalar() || IsQuoted(n)) return std::nullopt;
  const std::string& s = n.Scalar();
  if (s == "true" || s == "True" || s == "TRUE") return true;
  if (s == "false" || s == "False" || s == "FALSE") return false;
  return std::nullopt;
}

namespace {
void RenderTo(const YAML::Node& n, bool top, std::string* out) {
  if (!n.IsDefined() || n.IsNull()) return;
  if (n.IsScalar()) {
    *out += !top && IsQuoted(n) ? "\"" + n.Scalar() + "\"" : n.Scalar();
  } else if (n.IsSequence()) {
    *out += "[";
    for (std::size_t i = 0; i < n.size(); ++i) {
      if (i > 0) *out += ", ";
      RenderTo(n[i], false, out);
    }
    *out += "]";
  } else if (n.IsMap()) {
    *out += "{";
    bool first = true;
    for (const auto& kv : n) {
      if (!first) *out += ", ";
      first = false;
      RenderTo(kv.first, false, out);
      *out += ": ";
      RenderTo(kv.second, false, out);
    }
    *out += "}";
  }
}

// A node as the user wrote it, for error messages: a scalar verbatim, a collection in flow style
// with its quoted strings in quotes; null or missing as "" (InputError says "missing or empty").
}  // namespace

std::string Render(const YAML::Node& n) {
  std::string text;
  RenderTo(n, true, &text);
  constexpr std::size_t kMaxChars = 100;
  if (text.size() > kMaxChars) text = text.substr(0, kMaxChars - 3) + "...";
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
