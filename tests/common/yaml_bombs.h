#pragma once
// Hostile YAML for the loaders' tests: files that expand beyond any reader's means.

#include <string>

namespace hgrasp::testing {

/// A "billion laughs" document in under 400 bytes: `holder` holds nine lists, the first of nine
/// `lol`s, each next of nine aliases of the one before; `key: *i` names the last (9^9 = 387
/// million values once expanded). A reader that checks `key` and shows its value in a message
/// expands them all.
inline std::string BillionLaughs(const std::string& holder, const std::string& key) {
  std::string yaml = holder + ":\n  - &a [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n";
  std::string previous = "a";
  for (const char* level : {"b", "c", "d", "e", "f", "g", "h", "i"}) {
    yaml += std::string("  - &") + level + " [";
    for (int k = 0; k < 9; ++k) yaml += (k ? ", *" : "*") + previous;
    yaml += "]\n";
    previous = level;
  }
  return yaml + key + ": *i\n";
}

}  // namespace hgrasp::testing
