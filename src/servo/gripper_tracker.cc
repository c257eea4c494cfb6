#include "servo/gripper_tracker.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

#include "common/error.h"
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

const scan::Rectification& GripperTracker::RectificationAt(double verge) {
  if (!rect_verge_ || *rect_verge_ != verge) {
    const Pose3 X_CLCR = head_.X_HC(robot::HeadKinematics::kLeft, verge).inverse() *
                         head_.X_HC(robot::HeadKinematics::kRight, verge);
    rect_ = scan::MakeRectification(cameras_.left, cameras_.right, X_CLCR);
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
  if (!device::Ok(device_status_)) return TrackerStatus::kDeviceError;
  ++frames_;
  return TrackerStatus::kOk;
}

TrackerStatus GripperTracker::SetLeds(device::Leds& leds, std::uint32_t mask) {
  device_status_ = leds.Set(side_, mask);
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

bool GripperTracker::MeasureTracked(const device::StereoFrame& frame) {
  PredictTo(frame.t_s);
  const std::vector<LedPoint> points = Points(frame);
  // Greedy global nearest neighbour between the points and the LEDs' predicted positions.
  const Pose3 X_CE = filter_.pose();
  std::vector<std::tuple<double, int, int>> pairs;  // distance, point, LED
  for (std::size_t k = 0; k < points.size(); ++k) {
    for (int i = 0; i < layout_.size(); ++i) {
      const double d = (points[k].p_CL - X_CE * layout_.p_E[i]).norm();
      if (d <= options_.association_gate) pairs.emplace_back(d, static_cast<int>(k), i);
    }
  }
  std::sort(pairs.begin(), pairs.end());
  std::vector<int> ids(points.size(), -1);
  std::vector<bool> led_used(layout_.size(), false);
  for (const auto& [d, k, i] : pairs) {
    if (ids[k] >= 0 || led_used[i]) continue;
    ids[k] = i;
    led_used[i] = true;
  }
  return Fuse(points, ids, /*first=*/false);
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
    if ((s = Grab(camera, &frame)) != TrackerStatus::kOk) return s;
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
    if ((s = Grab(camera, &frame)) != TrackerStatus::kOk) return s;
    const std::vector<LedPoint> background = Points(frame);
    // One LED at a time: the single new point near the gripper is that LED.
    std::vector<LedPoint> identified;
    std::vector<int> ids;
    for (int i = 0; i < n; ++i) {
      if ((s = SetLeds(leds, 1u << i)) != TrackerStatus::kOk) return s;
      if ((s = Grab(camera, &frame)) != TrackerStatus::kOk) return s;
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
