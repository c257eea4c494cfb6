#pragma once
/// @file Reading a checked YAML file's maps and scalars with errors that name the file and line,
/// the field path, the value and what was expected (DESIGN.md rule 5). Shared by every loader
/// that walks a document itself (the scenario, the devices block).

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <map>
#include <string>
#include <string_view>

#include "common/yaml_util.h"

namespace hgrasp::yaml {

/// One key: value pair of a map, by key.
struct Entry {
  YAML::Node key, value;
};
using Entries = std::map<std::string, Entry>;

/// The checks of one file; every failure throws hgrasp::InputError naming "FILE:LINE".
class Reader {
 public:
  explicit Reader(std::string path) : path_(std::move(path)) {}

  const std::string& path() const { return path_; }
  /// "FILE:LINE" of a mark.
  std::string Where(const YAML::Mark& mark) const;

  [[noreturn]] void Fail(const YAML::Mark& mark, const std::string& field, const std::string& value,
                         const std::string& expected) const;
  /// At a node: its mark, the node as written.
  [[noreturn]] void Fail(const YAML::Node& at, const std::string& field,
                         const std::string& expected) const;

  /// Checks that `n` is a map whose keys are all in `allowed`, each once; returns its entries.
  Entries MapOf(const YAML::Node& n, const std::string& field, const Keys& allowed,
                const std::string& expected) const;
  /// The value of `key`, or nullptr.
  static const YAML::Node* Find(const Entries& entries, std::string_view key);
  /// The value of `key`; missing: fails at the map.
  const YAML::Node& Require(const Entries& entries, const YAML::Node& map, const std::string& field,
                            std::string_view key, const std::string& expected) const;
  /// A finite decimal number (common/yaml_util.h ParseNumber).
  double Number(const YAML::Node& n, const std::string& field, const std::string& expected) const;
  /// A sequence of exactly `count` numbers.
  Eigen::VectorXd Numbers(const YAML::Node& n, const std::string& field, std::size_t count,
                          const std::string& expected) const;
  /// A non-empty scalar.
  std::string Text(const YAML::Node& n, const std::string& field,
                   const std::string& expected) const;

 private:
  std::string path_;
};

}  // namespace hgrasp::yaml
