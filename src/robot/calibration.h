#pragma once
/// @file Calibration files of the head: the stereo cameras' intrinsics and the laser's light
/// plane. Both are YAML; a bad file throws hgrasp::InputError naming "FILE:LINE", the field, the
/// value and what was expected (DESIGN.md rule 5).

#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "common/geometry.h"
#include "common/pinhole_camera.h"

namespace hgrasp::robot {

/// The intrinsics of both cameras (ideal pinholes: no distortion).
struct StereoIntrinsics {
  PinholeCamera left, right;
  std::string path;  ///< the file they were read from (for errors found against the frames)
};

/// Reads a camera intrinsics file:
/// ```yaml
/// left:  {width: 320, height: 240, fx: 230.5, fy: 230.5, cx: 159.5, cy: 119.5}
/// right: {width: 320, height: 240, fx: 230.5, fy: 230.5, cx: 159.5, cy: 119.5}
/// ```
/// width and height are positive integers (pixels), fx and fy positive focal lengths (pixels),
/// cx, cy the principal point (pixels, inside the image; see PinholeCamera for the convention).
/// @throws hgrasp::InputError naming file:line, the field (e.g. "left.fx") and the value for a
///         missing or unreadable file, bad YAML, unknown or repeated keys, missing fields, wrong
///         types or values out of range.
///         Each camera's fy within 10% of its fx (square pixels) and a horizontal field of view
///         of 10-150 deg; both cameras of one image size, their focal lengths within 10%. That
///         the size is the frames' is checked against the first frame (scan::CheckFrameSize).
StereoIntrinsics LoadStereoIntrinsics(const std::string& path);

/// As LoadStereoIntrinsics, on the text of such a file (`path` names it in errors).
StereoIntrinsics ParseStereoIntrinsics(const std::string& text, const std::string& path);

/// Writes `s` as a camera intrinsics file that LoadStereoIntrinsics reads back to the same
/// values exactly (17 significant digits), after a header comment: the format's explanation,
/// then each line of `note` (where the values came from: `hgrasp calibrate cameras` writes its
/// views and reprojection RMS there). Written whole or not at all.
/// @throws hgrasp::InputError naming the path when it cannot be written, or naming the field
///         when `s` would not pass LoadStereoIntrinsics' checks.
void SaveStereoIntrinsics(const StereoIntrinsics& s, const std::string& path,
                          const std::string& note = "");

/// The laser's calibration: a light plane turning about an axis fixed in H (the URDF link
/// "camera_bracket"). At encoder count e:
///   theta = rad_per_count * e,  n(e) = Rot(axis_H, theta) * normal0_H,
///   the plane is {p in H : n(e).(p - point_H) - offset_m = 0} = Plane{n(e), -n(e).point_H -
///   offset_m}.
struct LaserCalibration {
  Eigen::Vector3d axis_H = Eigen::Vector3d::UnitZ();     ///< unit rotation axis, in H
  Eigen::Vector3d point_H = Eigen::Vector3d::Zero();     ///< a point on the axis, in H (m)
  Eigen::Vector3d normal0_H = Eigen::Vector3d::UnitY();  ///< unit normal at count 0 (on a cone
                                                         ///< about axis_H, at least 60 deg from it)
  double offset_m = 0.0;                                 ///< the plane's distance from the axis
  double rad_per_count = 2.0 * kPi / 36000.0;            ///< encoder resolution (rad/count)
  double rms_residual_px = 0.0;  ///< fit quality (pixels), written for information
  int counts_used = 0;           ///< how many encoder counts the fit used

  /// The light plane in H at encoder count `count`.
  Plane PlaneH(std::int32_t count) const;

  bool operator==(const LaserCalibration& other) const = default;
};

/// Reads a laser calibration file, as written by SaveLaserCalibration. Keys (all required, no
/// others): frame (must be camera_bracket), axis_H, point_H, normal0_H ([x, y, z] each),
/// offset_m, rad_per_count, rms_residual_px, counts_used.
/// @throws hgrasp::InputError naming file:line, the field and the value for a missing or
///         unreadable file, bad YAML, unknown or repeated keys, missing fields, wrong types,
///         axis_H or normal0_H not unit within 1e-6, normal0_H within 60 deg of axis_H,
///         rad_per_count <= 0, rms_residual_px or counts_used < 0, point_H or offset_m beyond
///         0.5 m (the laser is on the head).
LaserCalibration LoadLaserCalibration(const std::string& path);

/// As LoadLaserCalibration, on the text of such a file (`path` names it in errors).
LaserCalibration ParseLaserCalibration(const std::string& text, const std::string& path);

/// Writes `c` as YAML with a header comment explaining the fields, every number with 17
/// significant digits so that LoadLaserCalibration(path) == c exactly. The file is written
/// whole or not at all (through a temporary file renamed into place).
/// `c` must satisfy the checks of LoadLaserCalibration (a broken invariant aborts).
/// @throws hgrasp::InputError naming the path when it cannot be written.
void SaveLaserCalibration(const LaserCalibration& c, const std::string& path);

}  // namespace hgrasp::robot
