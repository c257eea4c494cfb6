#include "common/error.h"

#include <cstdio>
#include <cstdlib>

namespace hgrasp {
namespace {

// A value as a message shows it: control characters and other bytes that are not printable
// ASCII or UTF-8 as \xNN (so binary garbage is shown, not cut at its first NUL or sent to the
// terminal raw), at most `max_chars` characters.
std::string Printable(const std::string& value, std::size_t max_chars = 200) {
  std::string out;
  for (const char ch : value) {
    if (out.size() >= max_chars) {
      out += "...";
      break;
    }
    const auto c = static_cast<unsigned char>(ch);
    if (c >= 0x20 && c != 0x7f) {
      out += ch;  // printable ASCII, or a byte of UTF-8
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    }
  }
  return out;
}

std::string Compose(const std::string& file, const std::string& field, const std::string& value,
                    const std::string& expected) {
  // Appended piece by piece (GCC 12 warns falsely on chained operator+ of strings).
  std::string msg;
  if (!file.empty()) msg.append(Printable(file, 4096)).append(": ");
  if (!field.empty()) msg.append(Printable(field)).append(": ");
  if (value.empty()) {
    msg.append("missing or empty");
  } else {
    msg.append("got '").append(Printable(value)).append("'");
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
