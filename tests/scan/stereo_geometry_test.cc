// Rectified stereo geometry and the light-plane coefficients (Taylor & Kleeman eq. 4-5) against
// values worked out by hand: the coefficients of a frontal plane, stereo pairs generated from
// points on a plane, and ideal cameras whose rectification is known in closed form.

#include "scan/stereo_geometry.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

namespace hgrasp::scan {
namespace {

constexpr double kB = 0.07;  // half-baseline (m): cameras 0.14 m apart

// Pixel coordinates (relative to the principal point) of p_M in the two rectified cameras, as
// the header defines them: xL = (X + b) f / Z, xR = (X - b) f / Z, y = Y f / Z.
Eigen::Vector3d PairOf(const Eigen::Vector3d& p_M, double b, double f) {
  return {(p_M.x() + b) * f / p_M.z(), (p_M.x() - b) * f / p_M.z(), p_M.y() * f / p_M.z()};
}

Plane MakePlane(const Eigen::Vector3d& normal, const Eigen::Vector3d& through) {
  Plane p;
  p.n = normal.normalized();
  p.d = -p.n.dot(through);
  return p;
}

// Random planes with |A b + D| well away from zero (the coefficients are then of order one).
std::vector<Plane> RandomPlanes(int count, std::mt19937* rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Plane> planes;
  while (static_cast<int>(planes.size()) < count) {
    Plane p;
    p.n = Eigen::Vector3d(g(*rng), g(*rng), g(*rng)).normalized();
    p.d = u(*rng);
    if (std::abs(p.n.x() * kB + p.d) < 0.05) continue;
    planes.push_back(p);
  }
  return planes;
}

TEST(LaserCoefficientsTest, FrontalPlaneByHand) {
  // Z = 0.5: A = B = 0, C = 1, D = -0.5, so A b + D = -0.5 and
  // alpha = (0 + 0.5) / -0.5 = -1, beta = 0, gamma = 2 * 1 * 0.07 / -0.5 = -0.28:
  // xL - xR = 0.28 f, the disparity 2 b f / Z of a point 0.5 m away.
  Plane frontal;
  frontal.n = Eigen::Vector3d::UnitZ();
  frontal.d = -0.5;
  const LaserCoefficients c = CoefficientsFromPlane(frontal, kB);
  EXPECT_NEAR(c.alpha, -1.0, 1e-15);
  EXPECT_NEAR(c.beta, 0.0, 1e-15);
  EXPECT_NEAR(c.gamma, -0.28, 1e-15);
  // Residue by hand: xL = 100, xR = 100 - 0.28 * 200 = 44 at f = 200 lies on it; 1 px off does not.
  EXPECT_NEAR(c.Residue(100.0, 44.0, 17.0, 200.0), 0.0, 1e-12);
  EXPECT_NEAR(c.Residue(101.0, 44.0, 17.0, 200.0), 1.0, 1e-12);

  const Plane back = PlaneFromCoefficients(c, kB);
  const double sign = back.n.z() > 0 ? 1.0 : -1.0;
  EXPECT_NEAR((sign * back.n - frontal.n).norm(), 0.0, 1e-15);
  EXPECT_NEAR(sign * back.d, -0.5, 1e-15);
}

TEST(LaserCoefficientsTest, VerticalSheetByHand) {
  // The sheet X = 0.02 + 0.3 (Z - 0.5), i.e. X - 0.3 Z + 0.13 = 0 (unnormalised, s drops out):
  // A b + D = 0.07 + 0.13 = 0.2, alpha = (0.07 - 0.13) / 0.2 = -0.3, beta = 0,
  // gamma = 2 (-0.3) 0.07 / 0.2 = -0.21.
  const Plane p = MakePlane({1.0, 0.0, -0.3}, {0.02, 0.0, 0.5});
  const LaserCoefficients c = CoefficientsFromPlane(p, kB);
  EXPECT_NEAR(c.alpha, -0.3, 1e-12);
  EXPECT_NEAR(c.beta, 0.0, 1e-12);
  EXPECT_NEAR(c.gamma, -0.21, 1e-12);
}

TEST(LaserCoefficientsTest, RoundTripUpToSign) {
  std::mt19937 rng(7);
  for (const Plane& p : RandomPlanes(200, &rng)) {
    const Plane q = PlaneFromCoefficients(CoefficientsFromPlane(p, kB), kB);
    EXPECT_NEAR(q.n.norm(), 1.0, 1e-12);
    const double sign = q.n.dot(p.n) >= 0 ? 1.0 : -1.0;
    EXPECT_NEAR((sign * q.n - p.n).norm(), 0.0, 1e-9) << p.n.transpose() << " " << p.d;
    EXPECT_NEAR(sign * q.d, p.d, 1e-9) << p.n.transpose() << " " << p.d;
  }
}

TEST(LaserCoefficientsTest, PairsFromPointsOnThePlaneHaveZeroResidue) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> x(-0.4, 0.4), z(0.2, 2.0);
  const double f = 230.0;
  int checked = 0;
  for (const Plane& p : RandomPlanes(100, &rng)) {
    const LaserCoefficients c = CoefficientsFromPlane(p, kB);
    const LaserCoefficients off = CoefficientsFromPlane(MakePlane(p.n, -p.n * (p.d + 0.01)), kB);
    for (int i = 0; i < 20; ++i) {
      Eigen::Vector3d q(x(rng), x(rng), z(rng));
      q -= p.SignedDistance(q) * p.n;  // onto the plane
      if (q.z() < 0.1) continue;
      const Eigen::Vector3d pair = PairOf(q, kB, f);
      EXPECT_NEAR(c.Residue(pair.x(), pair.y(), pair.z(), f), 0.0, 1e-9);
      // The same pair against a plane 1 cm away is off it (guards against a residue that is
      // zero for everything).
      EXPECT_GT(std::abs(off.Residue(pair.x(), pair.y(), pair.z(), f)), 1e-6);
      ++checked;
    }
  }
  EXPECT_GT(checked, 500);
}

PinholeCamera IdealCamera() { return PinholeCamera::FromFovy(320, 240, DegToRad(55.0)); }

TEST(RectificationTest, ParallelIdenticalCamerasRectifyToThemselves) {
  const PinholeCamera cam = IdealCamera();
  Pose3 X_CLCR = Pose3::Identity();
  X_CLCR.translation() = Eigen::Vector3d(0.14, 0.0, 0.0);
  const Rectification r = MakeRectification(cam, cam, X_CLCR);
  EXPECT_NEAR(r.b, 0.07, 1e-9);
  EXPECT_DOUBLE_EQ(r.f, cam.fx);
  EXPECT_DOUBLE_EQ(r.cx, 159.5);
  EXPECT_DOUBLE_EQ(r.cy, 119.5);
  EXPECT_EQ(r.width, 320);
  EXPECT_EQ(r.height, 240);
  for (int c = 0; c < 2; ++c) {
    EXPECT_NEAR((r.R_RC[c] - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-9) << "camera " << c;
  }
  // M is the left camera's frame shifted by b along x: the left camera sits at (-b, 0, 0).
  EXPECT_NEAR((r.X_CLM.linear() - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-9);
  EXPECT_NEAR((r.X_CLM.translation() - Eigen::Vector3d(0.07, 0, 0)).norm(), 0.0, 1e-9);

  // The rectification maps are the identity: pixel (u, v) reads pixel (u, v).
  for (int c = 0; c < 2; ++c) {
    ASSERT_EQ(r.map1[c].type(), CV_16SC2);
    for (int v : {0, 57, 119, 239}) {
      for (int u : {0, 100, 159, 319}) {
        const cv::Vec2s m = r.map1[c].at<cv::Vec2s>(v, u);
        EXPECT_EQ(m[0], u);
        EXPECT_EQ(m[1], v);
        EXPECT_EQ(r.map2[c].at<std::uint16_t>(v, u), 0);  // no fractional part
      }
    }
  }

  // A point 0.6 m out: its projections, by hand, triangulate back to it.
  const Eigen::Vector3d p_M(0.05, -0.03, 0.6);
  const double xL = (0.05 + 0.07) * r.f / 0.6, xR = (0.05 - 0.07) * r.f / 0.6;
  const double y = -0.03 * r.f / 0.6;
  EXPECT_NEAR((r.Triangulate(xL, xR, y) - p_M).norm(), 0.0, 1e-9);
  const Eigen::Vector2d uvL = r.ProjectToCamera(0, cam, p_M);
  const Eigen::Vector2d uvR = r.ProjectToCamera(1, cam, p_M);
  EXPECT_NEAR(uvL.x(), xL + 159.5, 1e-9);
  EXPECT_NEAR(uvR.x(), xR + 159.5, 1e-9);
  EXPECT_NEAR(uvL.y(), y + 119.5, 1e-9);
  EXPECT_NEAR(uvR.y(), y + 119.5, 1e-9);
}

class VergedRectificationTest : public ::testing::TestWithParam<double> {};

TEST_P(VergedRectificationTest, RowsAlignAndTriangulationReturnsThePoint) {
  const double verge_deg = GetParam();
  const PinholeCamera cam = IdealCamera();
  Pose3 X_CLCR = Pose3::Identity();
  X_CLCR.translation() = Eigen::Vector3d(0.14, 0.0, 0.0);
  X_CLCR.linear() = Eigen::AngleAxisd(DegToRad(verge_deg), Eigen::Vector3d::UnitY()).matrix();
  const Rectification r = MakeRectification(cam, cam, X_CLCR);
  EXPECT_NEAR(r.b, 0.07, 1e-9);  // the baseline does not change with the rotation
  EXPECT_DOUBLE_EQ(r.f, cam.fx);
  EXPECT_DOUBLE_EQ(r.cx, 159.5);
  EXPECT_DOUBLE_EQ(r.cy, 119.5);
  for (int c = 0; c < 2; ++c) {
    EXPECT_NEAR((r.R_RC[c] * r.R_RC[c].transpose() - Eigen::Matrix3d::Identity()).norm(), 0.0,
                1e-9);
    EXPECT_NEAR(r.R_RC[c].determinant(), 1.0, 1e-9);
  }
  // The two rectified frames share one orientation: R_RC[0] R_CLCR = R_RC[1].
  EXPECT_NEAR((r.R_RC[0] * X_CLCR.linear() - r.R_RC[1]).norm(), 0.0, 1e-9);

  const Pose3 X_CRCL = X_CLCR.inverse();
  // Rectified pixel coordinates (relative to the principal point) of an unrectified pixel.
  auto rectify = [&](int c, const Eigen::Vector2d& uv) {
    const Eigen::Vector3d ray = r.R_RC[c] * cam.Ray(uv.x(), uv.y());
    return Eigen::Vector2d(r.f * ray.x() / ray.z(), r.f * ray.y() / ray.z());
  };
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> lateral(-0.15, 0.15), depth(0.3, 1.5);
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector3d p_CL(lateral(rng), lateral(rng), depth(rng));
    const Eigen::Vector3d p_CR = X_CRCL * p_CL;
    const auto uvL = cam.Project(p_CL), uvR = cam.Project(p_CR);
    ASSERT_TRUE(uvL && uvR);
    const Eigen::Vector2d l = rectify(0, *uvL), rr = rectify(1, *uvR);
    EXPECT_NEAR(l.y(), rr.y(), 1e-9) << "rows differ for " << p_CL.transpose();
    EXPECT_GT(l.x(), rr.x());  // positive disparity in front of the cameras
    const Eigen::Vector3d p_M = r.Triangulate(l.x(), rr.x(), l.y());
    EXPECT_NEAR((r.X_CLM * p_M - p_CL).norm(), 0.0, 1e-9) << p_CL.transpose();
    // And back into each unrectified image.
    EXPECT_NEAR((r.ProjectToCamera(0, cam, p_M) - *uvL).norm(), 0.0, 1e-9);
    EXPECT_NEAR((r.ProjectToCamera(1, cam, p_M) - *uvR).norm(), 0.0, 1e-9);
  }
}

// Converging (right camera turned towards the left one) and diverging.
INSTANTIATE_TEST_SUITE_P(Verge, VergedRectificationTest, ::testing::Values(-7.0, 7.0));

TEST(RectificationTest, LeftCameraToTheRightIsRefused) {
  const PinholeCamera cam = IdealCamera();
  Pose3 X_CLCR = Pose3::Identity();
  X_CLCR.translation() = Eigen::Vector3d(-0.14, 0.0, 0.0);
  EXPECT_DEATH(MakeRectification(cam, cam, X_CLCR), "right of the left");
}

}  // namespace
}  // namespace hgrasp::scan
