#pragma once
/// @file Strict YAML scalars and error-message helpers shared by the project's file loaders
/// (scenarios, calibration files): a number is a plain unquoted decimal, finite (no YAML 1.1
/// octal or hexadecimal, no .inf or .nan); a flag is true or false; every value can be shown to
/// the user as they wrote it.

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace hgrasp::yaml {

/// True when the scalar was written in quotes.
bool IsQuoted(const YAML::Node& n);
/// A finite decimal number; nullopt for anything else (quoted, hexadecimal, .inf, text).
std::optional<double> ParseNumber(const YAML::Node& n);
/// A non-negative integer that fits in 64 bits.
std::optional<std::uint64_t> ParseUnsigned(const YAML::Node& n);
/// A signed integer.
std::optional<long long> ParseInteger(const YAML::Node& n);
/// true or false (any capitalisation YAML allows), unquoted.
std::optional<bool> ParseBool(const YAML::Node& n);
/// A node as the user wrote it, for error messages: a scalar verbatim, a collection in flow
/// style; null or missing as "" (InputError then says "missing or empty").
std::string Render(const YAML::Node& n);
/// Said after "expected ..." when a number or flag was written in quotes; else empty.
std::string QuoteHint(const YAML::Node& n);
/// Field paths: Join("objects[1]", "size") is "objects[1].size"; Index("objects", 1) is
/// "objects[1]".
std::string Join(const std::string& path, std::string_view key);
std::string Index(const std::string& path, std::size_t i);

using Keys = std::vector<std::string_view>;
/// "one of: a, b, c".
std::string OneOf(const Keys& names);

}  // namespace hgrasp::yaml
