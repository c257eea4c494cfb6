#pragma once
/// @file A 1-DOF two-finger prosthetic hand (thumb and index close together).

#include "device/status.h"

namespace hgrasp::device {

struct HandState {
  double t_s = 0.0;         ///< time of the reading (s)
  double opening_m = 0.0;   ///< distance between thumb and index pads (m), 0 closed
  double grip_force_n = 0;  ///< force the fingers press with (N), 0 when free
  bool moving = false;
};

class Hand {
 public:
  virtual ~Hand() = default;
  virtual Status Read(HandState* state) = 0;
  /// Open to the given pad distance (m), clamped to the hand's range.
  virtual Status Open(double opening_m) = 0;
  /// Close until the fingers press with at most `max_force_n` (N) or meet each other.
  virtual Status Close(double max_force_n) = 0;
};

}  // namespace hgrasp::device
