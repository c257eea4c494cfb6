#pragma once
/// @file Laser self-calibration from any non-planar target (paper eq. 6): per encoder count,
/// least squares of the residues xL + alpha xR + beta y + gamma f over the stripe pairs; then a
/// physical model of the plane against encoder count, a plane turning about an axis fixed in
/// the head (frame H), fitted to the per-count planes.

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "robot/calibration.h"
#include "scan/stereo_geometry.h"

namespace hgrasp::scan {

/// Eq. 6 on pairs (xL, xR, y) (pixels relative to the principal point) with rectified focal
/// length f. Pairs beyond 2.5 RMS (stray candidates, stripes at edges) are trimmed over a few
/// passes. nullopt when the pairs do
/// not determine a plane (fewer than 20, or all on one line in space: a planar target).
std::optional<LaserCoefficients> FitCoefficients(const std::vector<Eigen::Vector3d>& pairs,
                                                 double f, double* rms_px = nullptr);

/// Eq. 6 when the stripe is not simply the strongest candidate of every row (a dark target, a
/// bright edge elsewhere): `rows` holds each row's candidate pairs (xL, xR, y). A consensus over
/// random triples of rows picks the plane most rows agree with (a pair within `inlier_px`);
/// eq. 6 then fits the agreeing pairs. Deterministic (fixed seed). `chosen`: the pairs used.
std::optional<LaserCoefficients> FitCoefficientsRobust(
    const std::vector<std::vector<Eigen::Vector3d>>& rows, double f, double inlier_px,
    std::vector<Eigen::Vector3d>* chosen, double* rms_px = nullptr);

/// The plane turning about an axis that best explains the per-count planes (in H): the normals
/// sweep a cone about the axis (a cylindrical lens a little off square turns the sheet), their
/// angle about it is linear in the count, and the plane's distance from a point on the axis is
/// constant.
robot::LaserCalibration FitRotatingPlane(
    const std::vector<std::pair<std::int32_t, Plane>>& planes_H);

/// A stripe point (triangulated by plain stereo) and the encoder count it was lit at.
struct CountedPoint {
  std::int32_t count = 0;
  Eigen::Vector3d p_H;  ///< in H (m)
};

/// Refines every parameter of the model (axis, the normal's cone about it, encoder resolution,
/// axis point, offset) by least squares on the points' distances from the model's plane at their
/// counts, starting from `initial`. `rms_m`: the points' RMS distance after the fit.
robot::LaserCalibration RefineOnPoints(const robot::LaserCalibration& initial,
                                       const std::vector<CountedPoint>& points_H,
                                       double* rms_m = nullptr);

}  // namespace hgrasp::scan
