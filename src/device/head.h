#pragma once
/// @file The Biclops pan/tilt/verge head.

#include "device/status.h"

namespace hgrasp::device {

/// Head joint angles (rad). Pan turns about the torso's vertical axis (positive to the left),
/// tilt about the pan link's y axis (positive looks down), verge turns both cameras towards
/// each other by the same angle (positive converges).
struct HeadJoints {
  double pan = 0.0;
  double tilt = 0.0;
  double verge = 0.0;
};

struct HeadState {
  double t_s = 0.0;
  HeadJoints q;
  bool moving = false;
};

class Head {
 public:
  virtual ~Head() = default;
  virtual Status Read(HeadState* state) = 0;
  /// Move every axis to its target at the axis speed limits.
  virtual Status MoveTo(const HeadJoints& target) = 0;
  /// Stop every axis where it is (the safe stop, DESIGN.md rule 8).
  virtual Status Stop() = 0;
};

}  // namespace hgrasp::device
