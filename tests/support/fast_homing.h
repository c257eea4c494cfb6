#pragma once
/// @file The Biclops head's homing as fast as a test can afford: 1.5 rad/s at 10 rad/s^2 on every
/// axis, near the emulated head's limits (pan and tilt 150 deg/s at 600 deg/s^2, verge 100 at
/// 400). BiclopsDefault.cfg's own profiles (pan 50 deg/s at 10 deg/s^2) take about half a minute
/// on the emulated head; these about 7-12 s.

namespace hgrasp::testing {

/// The `head` options of a scenario's devices block (or `hgrasp twin --head-options`).
inline constexpr const char* kFastHoming =
    "{pan: {homing_speed_rad_s: 1.5, homing_accel_rad_s2: 10}, "
    "tilt: {homing_speed_rad_s: 1.5, homing_accel_rad_s2: 10}, "
    "verge: {homing_speed_rad_s: 1.5, homing_accel_rad_s2: 10}}";

}  // namespace hgrasp::testing
