#include "common/pinhole_camera.h"

#include <cmath>

namespace hgrasp {

PinholeCamera PinholeCamera::FromFovy(int width, int height, double fovy_rad) {
  PinholeCamera c;
  c.width = width;
  c.height = height;
  c.fy = 0.5 * height / std::tan(0.5 * fovy_rad);
  c.fx = c.fy;
  // Pixel centres at integers: the optical axis passes through the image centre, which lies
  // between pixels (width-1)/2 and (height-1)/2.
  c.cx = 0.5 * (width - 1);
  c.cy = 0.5 * (height - 1);
  return c;
}

std::optional<Eigen::Vector2d> PinholeCamera::Project(const Eigen::Vector3d& p_CQ) const {
  if (p_CQ.z() <= 0.0) return std::nullopt;
  return Eigen::Vector2d(fx * p_CQ.x() / p_CQ.z() + cx, fy * p_CQ.y() / p_CQ.z() + cy);
}

Eigen::Vector3d PinholeCamera::Ray(double u, double v) const {
  return Eigen::Vector3d((u - cx) / fx, (v - cy) / fy, 1.0);
}

bool PinholeCamera::Contains(const Eigen::Vector2d& uv) const {
  return uv.x() >= -0.5 && uv.x() <= width - 0.5 && uv.y() >= -0.5 && uv.y() <= height - 0.5;
}

Eigen::Matrix3d PinholeCamera::K() const {
  Eigen::Matrix3d k;
  k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return k;
}

}  // namespace hgrasp
