#pragma once
/// @file The folder a command writes (`--out DIR`), written whole or not at all (DESIGN.md rule 5:
/// no half-written output). The folder is checked before any work starts, so a path that cannot
/// be written is a usage error (exit 2) naming it, not a failure after a minute of scanning.
/// Every output goes first to a hidden staging folder inside DIR; Commit() moves them all into
/// DIR once the command has written everything. A command that fails before, or throws, leaves
/// DIR as it found it (and removes DIR, and any parents, when it created them).

#include <string>
#include <string_view>
#include <vector>

namespace hgrasp::app {

/// A single output file (`--out FILE` of the calibrate commands), checked before any work
/// starts: not empty, not a folder, and no file where a folder of its path would be.
/// @throws hgrasp::InputError naming `flag`, the path and `expected` otherwise.
void CheckOutputFile(const std::string& path, const std::string& flag,
                     const std::string& expected);
/// Creates the folders above `path` (after the work: nothing is created for a failed one).
/// @throws hgrasp::InputError naming `flag` and the path when they cannot be made.
void CreateOutputFileParents(const std::string& path, const std::string& flag,
                             const std::string& expected);

class OutputDir {
 public:
  /// Checks `dir` and prepares to write into it, creating it (and missing parents) if needed.
  /// @throws hgrasp::InputError naming `dir` (field --out) when it is empty, is a file or
  ///         anything else that is not a folder, or cannot be created or written into (a
  ///         read-only or virtual file system such as /proc, a name too long, no permission).
  explicit OutputDir(std::string dir);
  /// Without Commit(): removes the staging folder, and the folders the constructor created.
  ~OutputDir();
  OutputDir(const OutputDir&) = delete;
  OutputDir& operator=(const OutputDir&) = delete;

  /// Where to write the output file `name` now: inside the staging folder.
  std::string Path(std::string_view name) const;
  /// The staging folder, for writers that take a folder.
  const std::string& staging() const { return staging_; }
  /// The folder as given.
  const std::string& dir() const { return dir_; }

  /// Moves every staged file into the folder, replacing files of the same names. Nothing is
  /// moved unless every one can be.
  /// @throws hgrasp::InputError naming the path when a file cannot take its place (a folder or
  ///         other non-file of that name is there); std::runtime_error when a move fails.
  void Commit();

 private:
  /// Removes the folders the constructor made, innermost first, each only while empty. (The
  /// constructor calls it before it throws: no destructor runs then.)
  void RemoveCreated();

  std::string dir_;
  std::string staging_;
  std::vector<std::string> created_;  ///< folders the constructor made, outermost first
  bool committed_ = false;
};

}  // namespace hgrasp::app
