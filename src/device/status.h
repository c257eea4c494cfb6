#pragma once
/// @file Device I/O outcome (DESIGN.md rule 7: I/O failures are returned, not thrown).

#include <string_view>

namespace hgrasp::device {

/// [[nodiscard]]: every call that returns one is handled (or dropped with a cast that says why).
// (clang-format takes the attribute for an initialiser and breaks the enum.)
// clang-format off
enum class [[nodiscard]] Status {
  kOk = 0,
  kTimeout,       ///< no reply within the device's timeout
  kBadReply,      ///< a reply arrived but failed its checksum or could not be parsed
  kRejected,      ///< the device refused the command (out of range, not ready)
  kDisconnected,  ///< the link is gone
  /// Not the device's doing: the caller gave up waiting because a stop was requested
  /// (SIGINT, SIGTERM; common/stop_request.h).
  kInterrupted,
};
// clang-format on

std::string_view ToString(Status s);

inline bool Ok(Status s) { return s == Status::kOk; }

/// Which arm, hand or LED set.
enum class Side { kLeft = 0, kRight = 1 };

inline std::string_view ToString(Side s) { return s == Side::kLeft ? "left" : "right"; }

}  // namespace hgrasp::device
