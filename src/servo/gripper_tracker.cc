#include "servo/gripper_tracker.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>
#include <utility>

#include "common/error.h"
#include "common/pinhole_camera.h"
#include "servo/gripper_pose.h"

namespace hgrasp::servo {

std::string_view ToString(TrackerStatus s) {
  switch (s) {
    case TrackerStatus::kOk:
      return "ok";
    case TrackerStatus::kDeviceError:
      return "device error";
    case TrackerStatus::kNotFound:
      return "gripper not found";
    case TrackerStatus::kNotInitialised:
      return "not initialised";
    case TrackerStatus::kNoMeasurement:
      return "no measurement";
    case TrackerStatus::kLost:
      return "lost";
  }
  return "?";
}

GripperTracker::GripperTracker(device::Side side, LedLayout layout, robot::StereoIntrinsics cameras,
                               robot::HeadKinematics head, const GripperTrackerOptions& options)
    : side_(side),
      layout_(std::move(layout)),
      cameras_(std::move(cameras)),
      head_(std::move(head)),
      options_(options),
      filter_(options.filter) {
  if (layout_.size() < 3 || layout_.size() > kMaxLeds) {
    throw InputError("", "LED layout", std::to_string(layout_.size()) + " LEDs",
                     "3 to " + std::to_string(kMaxLeds) + " LEDs");
  }
  last_leds_.resize(layout_.size());
}

Pose3 GripperTracker::X_CLCR(double verge) const {
  return head_.X_HC(robot::HeadKinematics::kLeft, verge).inverse() *
         head_.X_HC(robot::HeadKinematics::kRight, verge);
}

const scan::Rectification& GripperTracker::RectificationAt(double verge) {
  if (!rect_verge_ || *rect_verge_ != verge) {
    rect_ = scan::MakeRectification(cameras_.left, cameras_.right, X_CLCR(verge));
    rect_verge_ = verge;
  }
  return rect_;
}

std::vector<LedPoint> GripperTracker::Points(const device::StereoFrame& frame) {
  const scan::Rectification& rect = RectificationAt(frame.head.verge);
  return MatchAndTriangulate(DetectLeds(frame.left, options_.detector),
                             DetectLeds(frame.right, options_.detector), cameras_, rect,
                             options_.match);
}

TrackerStatus GripperTracker::Grab(device::StereoCamera& camera, device::StereoFrame* frame) {
  device_status_ = camera.Grab(frame);
  failed_device_ = "cameras";
  if (!device::Ok(device_status_)) return TrackerStatus::kDeviceError;
  ++frames_;
  return TrackerStatus::kOk;
}

TrackerStatus GripperTracker::GrabAfterLeds(device::StereoCamera& camera,
                                            device::StereoFrame* frame) {
  // A frame exposed before the LEDs switched may still be on its way (a real camera's
  // latency): those are passed over, so that the frame looked at shows the new LEDs.
  for (int k = 0; k < camera.frames_in_flight(); ++k) {
    const TrackerStatus s = Grab(camera, frame);
    if (s != TrackerStatus::kOk) return s;
  }
  return Grab(camera, frame);
}

TrackerStatus GripperTracker::SetLeds(device::Leds& leds, std::uint32_t mask) {
  device_status_ = leds.Set(side_, mask);
  failed_device_ = "leds";
  return device::Ok(device_status_) ? TrackerStatus::kOk : TrackerStatus::kDeviceError;
}

void GripperTracker::PredictTo(double t_s) {
  filter_.Predict(std::max(0.0, t_s - last_t_s_));
  last_t_s_ = std::max(last_t_s_, t_s);
}

bool GripperTracker::Fuse(const std::vector<LedPoint>& points, const std::vector<int>& ids,
                          bool first) {
  std::vector<Eigen::Vector3d> p_E, p_C;
  std::vector<std::optional<Eigen::Vector3d>> leds(layout_.size());
  for (std::size_t k = 0; k < points.size(); ++k) {
    if (ids[k] < 0) continue;
    p_E.push_back(layout_.p_E[ids[k]]);
    p_C.push_back(points[k].p_CL);
    leds[ids[k]] = points[k].p_CL;
  }
  if (p_E.size() < 3) return false;
  double rms = 0.0;
  std::optional<Pose3> X_CE = FitGripperPose(p_E, p_C, &rms);
  // A partly hidden LED triangulates off its centre: while there are more than 3, drop the one
  // with the largest residual when it exceeds max_led_residual, and refit.
  while (X_CE && p_E.size() > 3) {
    std::size_t worst = 0;
    double worst_r = -1.0;
    for (std::size_t k = 0; k < p_E.size(); ++k) {
      const double r = (*X_CE * p_E[k] - p_C[k]).norm();
      if (r > worst_r) std::tie(worst, worst_r) = std::make_pair(k, r);
    }
    if (worst_r <= options_.max_led_residual) break;
    for (auto& led : leds) {
      if (led && *led == p_C[worst]) led.reset();
    }
    p_E.erase(p_E.begin() + static_cast<std::ptrdiff_t>(worst));
    p_C.erase(p_C.begin() + static_cast<std::ptrdiff_t>(worst));
    X_CE = FitGripperPose(p_E, p_C, &rms);
  }
  if (!X_CE || rms > options_.max_fit_rms) return false;
  if (first) {
    filter_.Initialise(*X_CE, options_.measurement);
    has_orientation_ = true;
    last_nis_ = 0.0;
  } else {
    PoseFilter trial = filter_;
    const double nis = trial.Update(*X_CE, options_.measurement);
    if (!(nis <= options_.max_nis)) return false;
    filter_ = std::move(trial);
    last_nis_ = nis;
  }
  last_leds_ = std::move(leds);
  last_fit_rms_ = rms;
  ++measurements_;
  return true;
}

namespace {

// Greedy global nearest neighbour, one to one: the candidate pairs (distance, a, b), a < na and
// b < nb, taken in order of distance (ties by a, then b); the accepted (a, b).
std::vector<std::pair<int, int>> GreedyMatch(std::vector<std::tuple<double, int, int>> pairs,
                                             std::size_t na, std::size_t nb) {
  std::sort(pairs.begin(), pairs.end());
  std::vector<bool> a_used(na, false), b_used(nb, false);
  std::vector<std::pair<int, int>> matches;
  for (const auto& [d, a, b] : pairs) {
    if (a_used[a] || b_used[b]) continue;
    a_used[a] = b_used[b] = true;
    matches.emplace_back(a, b);
  }
  return matches;
}

}  // namespace

std::vector<int> GripperTracker::AssociateBlobs(const std::vector<LedBlob>& blobs,
                                                const PinholeCamera& camera, const Pose3& X_KCL,
                                                const Pose3& X_CE) const {
  // Blobs to projected LEDs, greedy global nearest neighbour.
  std::vector<std::tuple<double, int, int>> pairs;  // distance, blob, LED
  for (int i = 0; i < layout_.size(); ++i) {
    const auto px = camera.Project(X_KCL * (X_CE * layout_.p_E[i]));
    if (!px) continue;
    for (std::size_t b = 0; b < blobs.size(); ++b) {
      const double d = (*px - blobs[b].px).norm();
      if (d <= options_.image_gate_px) pairs.emplace_back(d, static_cast<int>(b), i);
    }
  }
  std::vector<int> blob_of_led(layout_.size(), -1);
  for (const auto& [b, i] : GreedyMatch(std::move(pairs), blobs.size(), layout_.size())) {
    blob_of_led[i] = b;
  }
  // The gripper's LEDs lie at about the same depth and image alike: a blob much smaller than
  // the median of its fellows is a partly hidden LED, whose centroid lies off the LED's centre.
  std::vector<double> areas;
  for (int b : blob_of_led) {
    if (b >= 0) areas.push_back(blobs[b].area_px);
  }
  if (areas.size() >= 3) {
    std::nth_element(areas.begin(), areas.begin() + areas.size() / 2, areas.end());
    const double median = areas[areas.size() / 2];
    for (int& b : blob_of_led) {
      if (b >= 0 && blobs[b].area_px < options_.min_blob_area_ratio * median) b = -1;
    }
  }
  return blob_of_led;
}

bool GripperTracker::MeasureTracked(const device::StereoFrame& frame) {
  PredictTo(frame.t_s);
  const std::vector<LedBlob> left = DetectLeds(frame.left, options_.detector);
  const std::vector<LedBlob> right = DetectLeds(frame.right, options_.detector);
  const scan::Rectification& rect = RectificationAt(frame.head.verge);
  const Pose3 X_CE = filter_.pose();
  // Association guided by the prediction: each blob goes to the LED whose projection lies
  // nearest in its own image (unguided row matching pairs the wrong blobs when several LEDs
  // share a row).
  const std::vector<int> in_left = AssociateBlobs(left, cameras_.left, Pose3::Identity(), X_CE);
  const std::vector<int> in_right =
      AssociateBlobs(right, cameras_.right, X_CLCR(frame.head.verge).inverse(), X_CE);
  // The pose that best reprojects every associated blob of both images (the paper's measurement:
  // each pixel weighs as much as it is worth, where a triangulated point is several times less
  // certain in depth than across).
  if (MeasureInImages(left, right, in_left, in_right, frame.head.verge)) return true;
  // The prediction may be too far off for the image gate: unguided stereo, associated in 3D.
  std::vector<LedPoint> points = MatchAndTriangulate(left, right, cameras_, rect, options_.match);
  std::vector<std::tuple<double, int, int>> pairs;  // distance, point, LED
  for (std::size_t k = 0; k < points.size(); ++k) {
    for (int i = 0; i < layout_.size(); ++i) {
      const double d = (points[k].p_CL - X_CE * layout_.p_E[i]).norm();
      if (d <= options_.association_gate) pairs.emplace_back(d, static_cast<int>(k), i);
    }
  }
  std::vector<int> ids(points.size(), -1);
  for (const auto& [k, i] : GreedyMatch(std::move(pairs), points.size(), layout_.size())) {
    ids[k] = i;
  }
  return Fuse(points, ids, /*first=*/false);
}

namespace {

// X turned and moved by d = (dtheta, dp), left perturbation in C: R' = Exp(dtheta) R, p' = p + dp.
Pose3 Perturb(const Pose3& X, const Eigen::Matrix<double, 6, 1>& d) {
  Pose3 Y = X;
  Y.linear() = ExpRotation(d.head<3>()).toRotationMatrix() * X.linear();
  Y.translation() += d.tail<3>();
  return Y;
}

}  // namespace

bool GripperTracker::MeasureInImages(const std::vector<LedBlob>& left,
                                     const std::vector<LedBlob>& right,
                                     const std::vector<int>& in_left,
                                     const std::vector<int>& in_right, double verge) {
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  const std::array<Pose3, 2> X_KCL = {Pose3::Identity(), X_CLCR(verge).inverse()};
  const std::array<const PinholeCamera*, 2> camera = {&cameras_.left, &cameras_.right};
  struct Observation {
    int camera, led;
    Eigen::Vector2d px;
  };
  std::vector<Observation> observations;
  std::vector<bool> led_seen(layout_.size(), false);
  const Pose3 X_CE0 = filter_.pose();
  for (int i = 0; i < layout_.size(); ++i) {
    if (in_left[i] >= 0) observations.push_back({0, i, left[in_left[i]].px});
    if (in_right[i] >= 0) observations.push_back({1, i, right[in_right[i]].px});
    led_seen[i] = in_left[i] >= 0 || in_right[i] >= 0;
  }
  const int distinct = static_cast<int>(std::count(led_seen.begin(), led_seen.end(), true));
  if (observations.size() < 4 || distinct < 3) return false;

  // Gauss-Newton on the reprojection error from the predicted pose (numeric Jacobian: a handful
  // of observations and 6 parameters). A partly hidden LED's blob is off its centre: while more
  // than 4 observations remain, the one with the largest residual beyond 2 pixel_std is dropped
  // and the pose refitted.
  auto residuals = [&](const Pose3& X, Eigen::VectorXd* r) {
    r->resize(2 * static_cast<int>(observations.size()));
    for (std::size_t k = 0; k < observations.size(); ++k) {
      const Observation& o = observations[k];
      const auto px = camera[o.camera]->Project(X_KCL[o.camera] * (X * layout_.p_E[o.led]));
      if (!px) return false;
      r->segment<2>(2 * static_cast<int>(k)) = *px - o.px;
    }
    return true;
  };
  Pose3 X = X_CE0;
  Eigen::VectorXd r0, r1;
  Eigen::MatrixXd J;
  for (;;) {
    X = X_CE0;
    J.resize(2 * static_cast<int>(observations.size()), 6);
    for (int iteration = 0; iteration < 10; ++iteration) {
      if (!residuals(X, &r0)) return false;
      constexpr double kStep = 1e-6;
      for (int j = 0; j < 6; ++j) {
        if (!residuals(Perturb(X, kStep * Vector6d::Unit(j)), &r1)) return false;
        J.col(j) = (r1 - r0) / kStep;
      }
      const Vector6d delta = (J.transpose() * J).ldlt().solve(-J.transpose() * r0);
      if (!delta.allFinite()) return false;
      X = Perturb(X, delta);
      if (delta.norm() < 1e-9) break;
    }
    if (!residuals(X, &r0)) return false;
    std::size_t worst = 0;
    for (std::size_t k = 1; k < observations.size(); ++k) {
      if (r0.segment<2>(2 * static_cast<int>(k)).norm() >
          r0.segment<2>(2 * static_cast<int>(worst)).norm()) {
        worst = k;
      }
    }
    if (observations.size() <= 4 ||
        r0.segment<2>(2 * static_cast<int>(worst)).norm() <= 2.0 * options_.pixel_std) {
      break;
    }
    observations.erase(observations.begin() + static_cast<std::ptrdiff_t>(worst));
  }
  led_seen.assign(layout_.size(), false);
  for (const Observation& o : observations) led_seen[o.led] = true;
  if (std::count(led_seen.begin(), led_seen.end(), true) < 3) return false;
  const double rms = std::sqrt(r0.squaredNorm() / static_cast<double>(observations.size()));
  if (rms > options_.max_reprojection_rms_px) return false;
  // Covariance of (dtheta, dp), reordered to the filter's (p, theta).
  const Eigen::Matrix<double, 6, 6> info = J.transpose() * J;
  Eigen::FullPivLU<Eigen::Matrix<double, 6, 6>> lu(info);
  if (!lu.isInvertible()) return false;
  const Eigen::Matrix<double, 6, 6> cov_tp = options_.pixel_std * options_.pixel_std * lu.inverse();
  PoseFilter::Matrix6d cov;
  cov.topLeftCorner<3, 3>() = cov_tp.bottomRightCorner<3, 3>();
  cov.bottomRightCorner<3, 3>() = cov_tp.topLeftCorner<3, 3>();
  cov.topRightCorner<3, 3>() = cov_tp.bottomLeftCorner<3, 3>();
  cov.bottomLeftCorner<3, 3>() = cov_tp.topRightCorner<3, 3>();
  cov = 0.5 * (cov + cov.transpose()).eval();
  PoseFilter trial = filter_;
  const double nis = trial.Update(X, cov);
  if (!(nis <= options_.max_nis)) return false;
  filter_ = std::move(trial);
  last_nis_ = nis;
  last_leds_.assign(layout_.size(), std::nullopt);
  for (int i = 0; i < layout_.size(); ++i) {
    if (led_seen[i]) last_leds_[i] = X * layout_.p_E[i];
  }
  last_fit_rms_ = 0.0;
  ++measurements_;
  ++image_measurements_;
  return true;
}

TrackerStatus GripperTracker::Initialise(device::Leds& leds, device::StereoCamera& camera) {
  const bool was_lost = lost_;
  filter_.Reset();
  tracking_ = false;
  lost_ = false;
  has_orientation_ = false;
  missed_ = 0;
  const int n = std::min(layout_.size(), leds.Count(side_));
  if (n < 3) return TrackerStatus::kNotFound;
  const std::uint32_t all = n >= 32 ? 0xffffffffu : (1u << n) - 1u;
  device::StereoFrame frame;
  TrackerStatus s;
  for (int cycle = 0; cycle < options_.max_init_cycles; ++cycle) {
    // All on: the filter starts from the LEDs' mean; later cycles also fuse this frame.
    if ((s = SetLeds(leds, all)) != TrackerStatus::kOk) return s;
    if ((s = GrabAfterLeds(camera, &frame)) != TrackerStatus::kOk) return s;
    if (!filter_.initialised()) {
      const std::vector<LedPoint> on = Points(frame);
      if (on.empty()) continue;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (const LedPoint& p : on) mean += p.p_CL;
      filter_.InitialisePosition(mean / static_cast<double>(on.size()),
                                 options_.initial_position_std);
      last_t_s_ = frame.t_s;
    } else if (has_orientation_) {
      MeasureTracked(frame);
    }
    // All off: the background.
    if ((s = SetLeds(leds, 0)) != TrackerStatus::kOk) return s;
    if ((s = GrabAfterLeds(camera, &frame)) != TrackerStatus::kOk) return s;
    const std::vector<LedPoint> background = Points(frame);
    // One LED at a time: the single new point near the gripper is that LED.
    std::vector<LedPoint> identified;
    std::vector<int> ids;
    for (int i = 0; i < n; ++i) {
      if ((s = SetLeds(leds, 1u << i)) != TrackerStatus::kOk) return s;
      if ((s = GrabAfterLeds(camera, &frame)) != TrackerStatus::kOk) return s;
      ++flashes_;
      std::vector<LedPoint> fresh;
      for (const LedPoint& p : Points(frame)) {
        bool old = false;
        for (const LedPoint& b : background) {
          old = old || (p.p_CL - b.p_CL).norm() < options_.background_radius;
        }
        const double from_filter = (p.p_CL - filter_.position()).norm();
        if (!old && from_filter < 3.0 * options_.initial_position_std) fresh.push_back(p);
      }
      if (fresh.size() == 1) {
        identified.push_back(fresh[0]);
        ids.push_back(i);
      }
    }
    if (!has_orientation_) {
      last_t_s_ = frame.t_s;
      Fuse(identified, ids, /*first=*/true);
    } else {
      PredictTo(frame.t_s);
      Fuse(identified, ids, /*first=*/false);
    }
    if (has_orientation_ && filter_.converged()) {
      if ((s = SetLeds(leds, all)) != TrackerStatus::kOk) return s;
      tracking_ = true;
      if (was_lost) ++recoveries_;
      return TrackerStatus::kOk;
    }
  }
  SetLeds(leds, all);
  filter_.Reset();
  has_orientation_ = false;
  lost_ = was_lost;
  return TrackerStatus::kNotFound;
}

void GripperTracker::ExpectMove(const Pose3& X_EEnew, double t_s) {
  if (!tracking_) return;
  const Pose3 X_CE0 = filter_.pose();
  filter_.MoveBy(X_EEnew, options_.move_error);
  last_t_s_ = std::max(last_t_s_, t_s);
  const Pose3 X_moved = filter_.pose() * X_CE0.inverse();
  for (std::optional<Eigen::Vector3d>& p : last_leds_) {
    if (p) p = X_moved * *p;
  }
}

void GripperTracker::CarryThroughCameraMove(const Pose3& X_CnewC) {
  if (filter_.initialised()) filter_.ChangeFrame(X_CnewC);
  for (std::optional<Eigen::Vector3d>& p : last_leds_) {
    if (p) p = X_CnewC * *p;
  }
}

TrackerStatus GripperTracker::Track(const device::StereoFrame& frame) {
  if (!tracking_) return lost_ ? TrackerStatus::kLost : TrackerStatus::kNotInitialised;
  ++frames_;
  if (MeasureTracked(frame)) {
    missed_ = 0;
    return TrackerStatus::kOk;
  }
  if (++missed_ >= options_.max_missed_frames) {
    lost_ = true;
    tracking_ = false;
    return TrackerStatus::kLost;
  }
  return TrackerStatus::kNoMeasurement;
}

}  // namespace hgrasp::servo
