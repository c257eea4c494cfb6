#pragma once
/// @file The gripper's pose from its LEDs (paper section 3/6): LED positions calibrated in the
/// gripper frame E and the same LEDs measured (triangulated) in the camera frame C give X_CE by a
/// least-squares rigid fit (Horn 1987 / Umeyama 1991, no scale).

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "common/geometry.h"

namespace hgrasp::servo {

/// The rigid transform X_CE that best maps the model points p_E onto the measured points p_C in
/// the least-squares sense: min sum_i |X_CE * p_E[i] - p_C[i]|^2 over proper rotations
/// (det R_CE = +1; a reflection is never returned, even when it would fit better) and
/// translations, no scale.
///
/// @param p_E     LED positions in the gripper frame E (m).
/// @param p_C     the same LEDs measured in the camera frame C (m), in the same order.
/// @param rms_m   if not null, receives the RMS residual |X_CE * p_E[i] - p_C[i]| (m) of the fit.
/// @return X_CE, or nullopt when the pose is not determined: fewer than 3 points, or the model
///         points (or the measured points) are (near-)collinear, i.e. the second singular value of
///         their centred spread is below 1e-6 of the first or below 1e-9 m.
/// @throws InputError when p_E and p_C differ in size or a coordinate is not finite.
std::optional<Pose3> FitGripperPose(const std::vector<Eigen::Vector3d>& p_E,
                                    const std::vector<Eigen::Vector3d>& p_C,
                                    double* rms_m = nullptr);

}  // namespace hgrasp::servo
