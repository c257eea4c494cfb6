#pragma once
// Hostile YAML for the loaders' tests: files that expand beyond any reader's means.

#include <string>

namespace hgrasp::testing {

/// A "billion laughs" document: nine levels of nine aliases of the level below, the first level
/// nine copies of `leaf`, and `key: *i` naming the last (9^9 = 387 million values once expanded,
/// in under 400 bytes).
inline std::string BillionLaughs(const std::string& key, const std::string& leaf) {
  std::string yaml = "a: &a [" + leaf;
  for (int k = 1; k < 9; ++k) yaml += ", " + leaf;
  yaml += "]\n";
  std::string previous = "a";
  for (const char* level : {"b", "c", "d", "e", "f", "g", "h", "i"}) {
    yaml += std::string(level) + ": &" + level + " [";
    for (int k = 0; k < 9; ++k) yaml += (k ? ", *" : "*") + previous;
    yaml += "]\n";
    previous = level;
  }
  return yaml + key + ": *i\n";
}

}  // namespace hgrasp::testing
