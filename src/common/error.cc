#include "common/error.h"

#include <cstdio>
#include <cstdlib>

namespace hgrasp {
namespace {
std::string Compose(const std::string& file, const std::string& field, const std::string& value,
                    const std::string& expected) {
  // Appended piece by piece (GCC 12 warns falsely on chained operator+ of strings).
  std::string msg;
  if (!file.empty()) msg.append(file).append(": ");
  if (!field.empty()) msg.append(field).append(": ");
  if (value.empty()) {
    msg.append("missing or empty");
  } else {
    msg.append("got '").append(value).append("'");
  }
  if (!expected.empty()) msg.append("; expected ").append(expected);
  return msg;
}

}  // namespace

InputError::InputError(std::string file, std::string field, std::string value, std::string expected)
    : std::runtime_error(Compose(file, field, value, expected)),
      file_(std::move(file)),
      field_(std::move(field)),
      value_(std::move(value)) {}

void DemandFailed(const char* condition, const char* file, int line, const std::string& detail) {
  std::fprintf(stderr, "hgrasp: internal invariant failed at %s:%d: %s %s\n", file, line, condition,
               detail.c_str());
  std::abort();
}

}  // namespace hgrasp
