#pragma once
// Joint angles between VAL's degrees and the seam's radians, for the VAL II tests.

#include <array>

#include "common/geometry.h"
#include "device/arm.h"

namespace hgrasp::drivers {

inline device::Joint6 Deg(std::array<double, 6> d) {
  device::Joint6 q;
  for (int k = 0; k < 6; ++k) q[k] = DegToRad(d[k]);
  return q;
}

inline std::array<double, 6> ToDeg(const device::Joint6& q) {
  std::array<double, 6> d;
  for (int k = 0; k < 6; ++k) d[k] = RadToDeg(q[k]);
  return d;
}

}  // namespace hgrasp::drivers
