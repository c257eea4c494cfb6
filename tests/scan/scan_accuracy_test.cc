// The scanner against the simulator's ground truth: the self-calibrated light plane, range
// accuracy and coverage on the shipped scenarios, and rejection of cross-talk and reflections.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "common/paths.h"
#include "robot/calibration.h"
#include "robot/head_kinematics.h"
#include "scan/scanner.h"
#include "sim/sim_devices.h"
#include "sim/truth.h"
#include "tests/support/status.h"

namespace hgrasp::scan {
namespace {

robot::HeadKinematics Head() {
  return robot::HeadKinematics::FromUrdfFile(ResolveDataPath("models/humanoid.urdf"));
}
robot::StereoIntrinsics Cameras() {
  return robot::LoadStereoIntrinsics(ResolveDataPath("calibration/sim/cameras.yaml"));
}

sim::Scenario Scenario(const std::string& file, double camera_noise = -1) {
  sim::Scenario s = sim::LoadScenario(ResolveDataPath("scenarios/" + file));
  if (camera_noise >= 0) s.camera_noise = camera_noise;
  return s;
}

TEST(ScanAccuracyTest, SelfCalibrationRecoversTheLightPlane) {
  sim::SimRobot robot(Scenario("calibration_target.yaml"));
  auto dev = robot.TakeDevices();
  const auto head = Head();
  LaserCalibrationReport report;
  const SweepConfig sweep;
  const std::optional<robot::LaserCalibration> calibrated =
      CalibrateLaser(dev, head, Cameras(), sweep, {}, &report);
  ASSERT_TRUE(calibrated) << report.failure;
  const robot::LaserCalibration& cal = *calibrated;
  std::printf("self-calibration quality: %s\n", report.Figures().c_str());
  device::HeadState hs;
  EXPECT_OK(dev.head->Read(&hs));
  const Pose3 X_WH = head.X_WH(hs.q);
  const sim::LaserPlaneError e = sim::CompareLaserPlanes(
      robot.rig(), [&](std::int32_t c) { return cal.PlaneH(c).TransformedBy(X_WH); }, -2400, 2400);
  const double worst_deg = e.worst_deg, worst_mm = e.worst_mm;
  std::printf(
      "self-calibration: %d of %d stripe positions, residue %.3f px; worst %.4f deg, %.3f mm\n",
      report.counts_used, report.frames, report.rms_residue_px, worst_deg, worst_mm);
  EXPECT_LT(worst_deg, 0.05);
  EXPECT_LT(worst_mm, 0.5);
  EXPECT_NEAR(cal.rad_per_count, sim::kLaserRadPerCount, 1e-3 * sim::kLaserRadPerCount);
}

struct ScanFigures {
  int points = 0, beyond_5mm = 0;
  double rms_mm = 0;
  int visible_both = 0, covered = 0;  // truth stripe points seen by both cameras; found
  double coverage() const { return visible_both > 0 ? double(covered) / visible_both : 0; }
};

// A scan like Scanner::Scan, frame by frame, with the simulator's stripe points as truth.
ScanFigures ScanAgainstTruth(const sim::Scenario& scenario, bool stereo = true) {
  sim::SimRobot robot(scenario);
  auto dev = robot.TakeDevices();
  StripeFrameConfig config;
  config.stereo = stereo;
  Scanner scanner(Head(), Cameras(),
                  robot::LoadLaserCalibration(ResolveDataPath("calibration/sim/laser.yaml")),
                  config);
  device::StereoFrame ambient;
  EXPECT_OK(dev.laser->SetLaser(false));
  EXPECT_OK(dev.cameras->Grab(&ambient));
  EXPECT_OK(dev.laser->SetLaser(true));
  ScanFigures fig;
  double sum2 = 0;
  RangeImage column(240, 1);
  StripeFrameResult result;
  EXPECT_OK(Sweep(dev, {}, [&](const device::StereoFrame& frame) {
    // Truth: our own stripe's points in the left image that the right camera sees too.
    const sim::CameraView& right = robot.rig().View(sim::kRight);
    std::vector<Eigen::Vector3d> truth;
    for (const sim::StripeCrossing& x : robot.rig().last_crossings()[sim::kLeft]) {
      if (x.sheet != 0) continue;
      const Eigen::Vector3d p_CR = right.X_WC.inverse() * x.p_W;
      const auto uv = right.camera.Project(p_CR);
      if (!uv || !right.camera.Contains(*uv)) continue;
      const float z = right.images.depth.at<float>(std::lround(uv->y()), std::lround(uv->x()));
      if (z > 0 && std::abs(z - p_CR.z()) < 0.003) truth.push_back(x.p_W);
    }
    column = RangeImage(240, 1);
    scanner.ProcessFrame(frame, ambient, &column, 0, &result);
    std::vector<Eigen::Vector3d> found;
    for (int r = 0; r < 240; ++r) {
      const RangeCell& c = column.at(r, 0);
      if (!c.valid) continue;
      found.push_back(c.p_W);
      const double e = sim::DistanceToTrueSurface(robot.world(), c.p_W);
      sum2 += e * e, ++fig.points;
      fig.beyond_5mm += e > 0.005;
    }
    for (const Eigen::Vector3d& t : truth) {
      ++fig.visible_both;
      fig.covered += std::any_of(found.begin(), found.end(),
                                 [&](const Eigen::Vector3d& p) { return (p - t).norm() < 0.005; });
    }
  }));
  fig.rms_mm = fig.points > 0 ? 1e3 * std::sqrt(sum2 / fig.points) : 0;
  return fig;
}

void Print(const char* what, const ScanFigures& f) {
  std::printf(
      "%s: %d points, RMS %.3f mm to the true surfaces, %d beyond 5 mm (%.4f%%), "
      "coverage %.2f%% of %d stripe rows both cameras see\n",
      what, f.points, f.rms_mm, f.beyond_5mm, 100.0 * f.beyond_5mm / std::max(1, f.points),
      100 * f.coverage(), f.visible_both);
}

TEST(ScanAccuracyTest, RangeAccuracyAndCoverageWithoutNoise) {
  for (const char* file : {"default.yaml", "plane_wall.yaml"}) {
    const ScanFigures f = ScanAgainstTruth(Scenario(file, 0.0));
    Print((std::string(file) + ", camera_noise 0").c_str(), f);
    EXPECT_LT(f.rms_mm, 1.0) << file;
    EXPECT_GT(f.coverage(), 0.95) << file;
    EXPECT_GT(f.points, 30000) << file;
  }
}

TEST(ScanAccuracyTest, RangeAccuracyAndCoverageWithNoise2) {
  for (const char* file : {"default.yaml", "plane_wall.yaml"}) {
    const ScanFigures f = ScanAgainstTruth(Scenario(file, 2.0));
    Print((std::string(file) + ", camera_noise 2").c_str(), f);
    EXPECT_LT(f.rms_mm, 1.5) << file;
    EXPECT_GT(f.coverage(), 0.95) << file;
  }
}

TEST(ScanAccuracyTest, StereoValidationRejectsCrossTalkAndReflections) {
  // Two other robots' stripes and a specular box (scenarios/two_boxes_interference.yaml).
  const ScanFigures stereo = ScanAgainstTruth(Scenario("two_boxes_interference.yaml"));
  const ScanFigures single = ScanAgainstTruth(Scenario("two_boxes_interference.yaml"), false);
  Print("interference, stereo validation", stereo);
  Print("interference, single camera", single);
  EXPECT_LE(stereo.beyond_5mm, 0.001 * stereo.points);
  EXPECT_GT(single.beyond_5mm, 0.01 * single.points);  // what validation buys
}

}  // namespace
}  // namespace hgrasp::scan
