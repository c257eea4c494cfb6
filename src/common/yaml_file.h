#pragma once
/// @file The one strict reading path of every YAML file the project loads (scenarios, camera
/// intrinsics, the laser calibration, LED layouts), with limits a careless or hostile file cannot
/// get past: a regular file of at most kMaxFileBytes, text without control characters, one
/// document, nested at most kMaxDepth deep, at most kMaxValues values once its aliases are
/// expanded (an alias inside the node it names, `&n [*n]`, or a "billion laughs" file of aliases
/// of aliases is refused in microseconds), and no YAML tags (`!!str 0.2` is not a number). Every refusal is an
/// hgrasp::InputError naming the file and line, what was found and what was expected.

#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <string>

namespace hgrasp::yaml {

/// Largest file read (bytes): the project's files are a few kB.
inline constexpr std::size_t kMaxFileBytes = 1 << 20;
/// Deepest nesting of maps and lists (the scenario's deepest value is 4 levels down).
inline constexpr int kMaxDepth = 32;
/// Most values (scalars, maps, lists, counting each alias as a copy of what it names).
inline constexpr std::size_t kMaxValues = 100000;

/// The text of the file at `path`. `expected` names the kind of file ("a readable scenario file
/// (YAML)"). Throws hgrasp::InputError for an empty path, a missing file, a directory or any
/// other file that is not a regular file (a device such as /dev/zero, a FIFO), an unreadable
/// file, or one over kMaxFileBytes.
std::string ReadText(const std::string& path, const std::string& expected);

/// The single YAML document of `text` (from `path`, which names it in errors), checked within
/// the limits above. `expected` describes the top level ("a map of scenario fields: ...").
/// Throws hgrasp::InputError for a control character (a NUL byte: binary data; the line and
/// byte are named), a syntax error (the offending line quoted, cut to 60 characters), an empty
/// file, more than one document, nesting beyond kMaxDepth, an alias
/// inside the node it names, more than kMaxValues values with aliases expanded, or a tag.
YAML::Node LoadDocument(const std::string& text, const std::string& path,
                        const std::string& expected);

/// "FILE:LINE" for a mark in the file (FILE alone when the mark has no line).
std::string Where(const std::string& path, const YAML::Mark& mark);

}  // namespace hgrasp::yaml
