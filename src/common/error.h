#pragma once
/// @file Errors, after DESIGN.md rule 7: bad input throws InputError (file, field, value, what
/// was expected); a broken internal invariant aborts through HGRASP_DEMAND; device I/O returns a
/// device::Status.

#include <stdexcept>
#include <string>

namespace hgrasp {

/// Invalid configuration or input. what() reads "FILE: FIELD: got VALUE; expected EXPECTED"
/// (the parts that are known), so a user can find and fix the line. The `hgrasp` command turns it
/// into exit status 2.
class InputError : public std::runtime_error {
 public:
  /// @param file     the file read (may be empty when the input is not a file)
  /// @param field    where in it: a dotted path such as "objects[1].size", or "line 12"
  /// @param value    the offending value as written (may be empty, e.g. for a missing field)
  /// @param expected what was expected instead
  InputError(std::string file, std::string field, std::string value, std::string expected);

  const std::string& file() const { return file_; }
  const std::string& field() const { return field_; }
  const std::string& value() const { return value_; }

 private:
  std::string file_, field_, value_;
};

/// Aborts with file:line and the failed condition: for broken internal invariants only.
[[noreturn]] void DemandFailed(const char* condition, const char* file, int line,
                               const std::string& detail);

}  // namespace hgrasp

#define HGRASP_DEMAND(cond)                                             \
  do {                                                                  \
    if (!(cond)) ::hgrasp::DemandFailed(#cond, __FILE__, __LINE__, ""); \
  } while (0)
#define HGRASP_DEMAND_MSG(cond, msg)                                     \
  do {                                                                   \
    if (!(cond)) ::hgrasp::DemandFailed(#cond, __FILE__, __LINE__, msg); \
  } while (0)
