// Self-calibration against models worked out by hand: planes and points generated from a known
// rotating plane must give that plane back.

#include "scan/laser_self_calibration.h"

#include <gtest/gtest.h>

#include <random>

namespace hgrasp::scan {
namespace {

// Like the simulated robot's laser: a sheet rolled 0.4 deg about its emission direction (so its
// normal sweeps a cone), 1.5 mm off the axis, turning about z of H at 0.01 deg per count.
robot::LaserCalibration TrueLaser() {
  robot::LaserCalibration c;
  c.axis_H = Eigen::Vector3d(0.01, -0.02, 1.0).normalized();
  const Eigen::Vector3d n =
      Eigen::AngleAxisd(DegToRad(0.4), Eigen::Vector3d::UnitX()) * Eigen::Vector3d::UnitY();
  c.normal0_H = (n - 0.0 * c.axis_H).normalized();
  c.point_H = Eigen::Vector3d(0.03, 0.0, 0.0);
  c.offset_m = 0.0015;
  c.rad_per_count = 2 * kPi / 36000;
  return c;
}

double WorstDistanceMm(const robot::LaserCalibration& a, const robot::LaserCalibration& b) {
  // Over the sweep, at points 0.3-0.7 m out along the sheet where the scene is.
  double worst = 0;
  for (int count = -2400; count <= 2400; count += 100) {
    const Plane pa = a.PlaneH(count), pb = b.PlaneH(count);
    for (double x : {0.3, 0.5, 0.7})
      for (double z : {-0.2, 0.0, 0.2}) {
        Eigen::Vector3d q(x, 0, z);
        q = Eigen::AngleAxisd(count * a.rad_per_count, a.axis_H) * q;
        q -= pa.SignedDistance(q) * pa.n;  // on plane a
        worst = std::max(worst, 1e3 * std::abs(pb.SignedDistance(q)));
      }
  }
  return worst;
}

TEST(LaserSelfCalibrationTest, RotatingPlaneFromExactPlanes) {
  const robot::LaserCalibration truth = TrueLaser();
  std::vector<std::pair<std::int32_t, Plane>> planes;
  for (int count = -2400; count <= 2400; count += 16)
    planes.emplace_back(count, truth.PlaneH(count));
  const robot::LaserCalibration fit = FitRotatingPlane(planes);
  std::printf("planes only: worst %.3f mm\n", WorstDistanceMm(truth, fit));
  EXPECT_NEAR(fit.rad_per_count, truth.rad_per_count, 1e-3 * truth.rad_per_count);
  EXPECT_LT(WorstDistanceMm(truth, fit), 1.0);  // before the cone is refined
}

TEST(LaserSelfCalibrationTest, RefinementOnNoisyPointsRecoversTheCone) {
  const robot::LaserCalibration truth = TrueLaser();
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.001);
  std::uniform_real_distribution<double> along(0.3, 0.7), up(-0.25, 0.05);
  std::vector<std::pair<std::int32_t, Plane>> planes;
  std::vector<CountedPoint> points;
  for (int count = -2400; count <= 2400; count += 16) {
    const Plane p = truth.PlaneH(count);
    planes.emplace_back(count, p);
    for (int i = 0; i < 60; ++i) {
      Eigen::Vector3d q = Eigen::AngleAxisd(count * truth.rad_per_count, truth.axis_H) *
                          Eigen::Vector3d(along(rng), 0, up(rng));
      q -= p.SignedDistance(q) * p.n;
      points.push_back({count, q + noise(rng) * p.n});
    }
  }
  double rms = 0;
  const robot::LaserCalibration fit = RefineOnPoints(FitRotatingPlane(planes), points, &rms);
  std::printf("refined: worst %.3f mm, rms %.3f mm\n", WorstDistanceMm(truth, fit), 1e3 * rms);
  EXPECT_LT(WorstDistanceMm(truth, fit), 0.3);
  EXPECT_NEAR(rms, 0.001, 0.0001);
}

}  // namespace
}  // namespace hgrasp::scan
