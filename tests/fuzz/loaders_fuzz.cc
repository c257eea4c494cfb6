// libFuzzer target of the project's file loaders: arbitrary bytes as the text of a scenario, a
// camera intrinsics file, a laser calibration or an LED layout (the first byte picks which),
// through the one strict YAML reading path (common/yaml_file.h) and the loader's own checks.
// A loader may only accept the text or refuse it with hgrasp::InputError; whatever it accepts
// must satisfy the loader's documented ranges. Anything else (another exception, a crash, a
// sanitizer report, a value out of range) traps.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "common/error.h"
#include "robot/calibration.h"
#include "servo/led_layout.h"
#include "sim/scenario.h"

namespace {

void Check(bool ok) {
  if (!ok) __builtin_trap();
}

void CheckScenario(const hgrasp::sim::Scenario& s) {
  namespace sim = hgrasp::sim;
  Check(s.camera_noise >= 0.0 && s.camera_noise <= sim::kMaxCameraNoise);
  Check(s.ambient >= 0.0 && s.ambient <= 1.0);
  for (const sim::ObjectSpec& o : s.objects) {
    Check((o.size_O.array() >= sim::kMinObjectEdge).all() &&
          (o.size_O.array() <= sim::kMaxObjectEdge).all());
    Check(o.mass >= sim::kMinMass && o.mass <= sim::kMaxMass);
    Check(std::isfinite(o.yaw) && std::abs(o.yaw) <= hgrasp::DegToRad(sim::kMaxYawDeg));
    Check((o.color_rgb.array() >= 0.0).all() && (o.color_rgb.array() <= 1.0).all());
    for (const Eigen::Vector2d& c : sim::ObjectFootprint(o)) {
      Check(c.x() >= sim::kTableMinX - 1e-6 && c.x() <= sim::kTableMaxX + 1e-6);
      Check(c.y() >= sim::kTableMinY - 1e-6 && c.y() <= sim::kTableMaxY + 1e-6);
    }
  }
  for (const sim::InterferenceSpec& i : s.interference) {
    Check(i.origin_W.allFinite() && i.origin_W.z() > 0.0);
    Check(i.period_s > 0.0 && i.period_s <= sim::kMaxPeriodS && i.sweep_min < i.sweep_max);
  }
  if (s.task) {
    Check(s.task->target_color.empty() != s.task->target_name.empty());
    Check(s.task->lift_m > 0.0 && s.task->lift_m <= sim::kMaxLift);
  }
}

void CheckCamera(const hgrasp::PinholeCamera& c) {
  Check(c.width > 0 && c.height > 0 && c.fx > 0.0 && c.fy > 0.0);
  Check(c.cx >= -0.5 && c.cx <= c.width - 0.5 && c.cy >= -0.5 && c.cy <= c.height - 0.5);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    switch (data[0] % 4) {
      case 0:
        CheckScenario(hgrasp::sim::ParseScenario(text, "fuzz.yaml"));
        break;
      case 1: {
        const hgrasp::robot::StereoIntrinsics s =
            hgrasp::robot::ParseStereoIntrinsics(text, "fuzz.yaml");
        CheckCamera(s.left);
        CheckCamera(s.right);
        Check(s.left.width == s.right.width && s.left.height == s.right.height);
        break;
      }
      case 2: {
        const hgrasp::robot::LaserCalibration c =
            hgrasp::robot::ParseLaserCalibration(text, "fuzz.yaml");
        Check(std::abs(c.axis_H.norm() - 1.0) <= 1e-6 && std::abs(c.normal0_H.norm() - 1.0) <= 1e-6);
        Check(c.rad_per_count > 0.0 && std::isfinite(c.offset_m) && c.point_H.allFinite());
        break;
      }
      default: {
        const hgrasp::servo::LedLayouts l = hgrasp::servo::ParseLedLayouts(text, "fuzz.yaml");
        for (const hgrasp::servo::LedLayout* side : {&l.left, &l.right}) {
          Check(side->size() >= 3 && side->size() <= hgrasp::servo::kMaxLeds);
          for (const Eigen::Vector3d& p : side->p_E) {
            Check(p.allFinite() && p.norm() <= hgrasp::servo::kMaxLedDistance);
          }
        }
        break;
      }
    }
  } catch (const hgrasp::InputError& e) {
    Check(e.what() != nullptr && std::string(e.what()).size() < 20000);  // messages stay short
  }
  return 0;
}
