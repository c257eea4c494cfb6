// `hgrasp calibrate laser` through the real drivers against the twin (issue 17) gives the plane
// the simulated robot's calibration gives: at every count of the sweep, normals within 0.05 deg
// and the planes within 0.5 mm of each other over the workspace (points up to 0.4 m from the
// generator in the plane). The twin in lockstep (--lockstep: simulated time, in process), so the
// figures are the same every run whatever the machine's load.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "cli_util.h"
#include "robot/calibration.h"

namespace hgrasp {
namespace {

namespace fs = std::filesystem;

TEST(CliLockstepCalibrate, TheLaserPlaneThroughTheWiresIsTheSimulatedOne) {
  const fs::path dir = fs::temp_directory_path() / "hgrasp_cli_lockstep_calibrate";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string scene = std::string(HGRASP_ROOT_DIR) + "/scenarios/calibration_target.yaml";
  const fs::path sim_file = dir / "sim_laser.yaml", twin_file = dir / "twin_laser.yaml";
  const auto sim =
      testing::RunHgrasp("calibrate laser " + scene + " --out " + sim_file.string(), 300);
  ASSERT_EQ(sim.status, 0) << sim.output;
  const auto wired = testing::RunHgrasp(
      "calibrate laser " + scene + " --lockstep --out " + twin_file.string(), 300);
  ASSERT_EQ(wired.status, 0) << wired.output;
  const robot::LaserCalibration a = robot::LoadLaserCalibration(sim_file.string());
  const robot::LaserCalibration b = robot::LoadLaserCalibration(twin_file.string());
  double worst_deg = 0.0, worst_mm = 0.0;
  for (std::int32_t c = -2400; c <= 2400; c += 100) {
    const Plane pa = a.PlaneH(c), pb = b.PlaneH(c);
    const double cosine = std::clamp(pa.n.normalized().dot(pb.n.normalized()), -1.0, 1.0);
    worst_deg = std::max(worst_deg, std::acos(cosine) * 180.0 / 3.14159265358979323846);
    // Points of plane a around the foot of the head frame's origin, 0.4 m each way.
    const Eigen::Vector3d foot = -pa.d * pa.n;
    const Eigen::Vector3d u = pa.n.unitOrthogonal(), v = pa.n.cross(u);
    for (double s : {-0.4, 0.0, 0.4})
      for (double t : {-0.4, 0.0, 0.4}) {
        worst_mm = std::max(worst_mm, 1e3 * std::abs(pb.SignedDistance(foot + s * u + t * v)));
      }
  }
  EXPECT_LT(worst_deg, 0.05);
  EXPECT_LT(worst_mm, 0.5);
  std::printf(
      "calibrate laser through the twin's wires against the simulated robot's: worst "
      "%.4f deg, %.3f mm over counts -2400..2400\n",
      worst_deg, worst_mm);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace hgrasp
