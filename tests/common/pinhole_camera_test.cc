#include "common/pinhole_camera.h"

#include <gtest/gtest.h>

#include <cmath>

namespace hgrasp {
namespace {

TEST(PinholeCameraTest, FromFovyMatchesTheFieldOfView) {
  const auto c = PinholeCamera::FromFovy(320, 240, 2.0 * std::atan(0.5));  // tan(fovy/2) = 0.5
  EXPECT_DOUBLE_EQ(c.fy, 240.0);
  EXPECT_DOUBLE_EQ(c.fx, 240.0);
  EXPECT_DOUBLE_EQ(c.cx, 159.5);
  EXPECT_DOUBLE_EQ(c.cy, 119.5);
}

TEST(PinholeCameraTest, ProjectAndRayAreInverse) {
  const auto c = PinholeCamera::FromFovy(320, 240, 0.9);
  const Eigen::Vector3d p(0.1, -0.05, 0.7);
  const auto uv = c.Project(p);
  ASSERT_TRUE(uv.has_value());
  EXPECT_TRUE((c.Ray(uv->x(), uv->y()) * p.z()).isApprox(p, 1e-12));
  EXPECT_FALSE(c.Project({0, 0, -1}).has_value());
  // The top-left image corner.
  EXPECT_TRUE(c.Contains({-0.5, -0.5}));
  EXPECT_FALSE(c.Contains({-0.51, 0}));
}

}  // namespace
}  // namespace hgrasp
