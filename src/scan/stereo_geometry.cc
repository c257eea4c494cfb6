#include "scan/stereo_geometry.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "common/error.h"

namespace hgrasp::scan {

LaserCoefficients CoefficientsFromPlane(const Plane& p, double b) {
  const double A = p.n.x(), B = p.n.y(), C = p.n.z(), D = p.d;
  const double s = A * b + D;
  HGRASP_DEMAND_MSG(std::abs(s) > 1e-12, "light plane through the right camera centre");
  return {(A * b - D) / s, 2 * B * b / s, 2 * C * b / s};
}

Plane PlaneFromCoefficients(const LaserCoefficients& c, double b) {
  // With s = A b + D: A = s (1 + alpha) / 2b, B = s beta / 2b, C = s gamma / 2b,
  // D = s (1 - alpha) / 2; s drops out when the normal is made unit.
  Eigen::Vector3d n((1 + c.alpha) / (2 * b), c.beta / (2 * b), c.gamma / (2 * b));
  const double d = (1 - c.alpha) / 2;
  const double norm = n.norm();
  Plane plane;
  plane.n = n / norm;
  plane.d = d / norm;
  return plane;
}

Eigen::Vector3d Rectification::Triangulate(double xL, double xR, double y) const {
  const double Z = 2 * b * f / (xL - xR);
  return {Z * (xL + xR) / (2 * f), Z * y / f, Z};
}

Eigen::Vector2d Rectification::ProjectToCamera(int camera, const PinholeCamera& k,
                                               const Eigen::Vector3d& p_M) const {
  // M -> rectified camera frame (shift by the camera's offset) -> camera frame -> pixel.
  const Eigen::Vector3d p_R = p_M + Eigen::Vector3d(camera == 0 ? b : -b, 0, 0);
  const Eigen::Vector3d p_C = R_RC[camera].transpose() * p_R;
  return {k.fx * p_C.x() / p_C.z() + k.cx, k.fy * p_C.y() / p_C.z() + k.cy};
}

Rectification MakeRectification(const PinholeCamera& left, const PinholeCamera& right,
                                const Pose3& X_CLCR) {
  cv::Mat K1, K2, R, T;
  cv::eigen2cv(Eigen::Matrix3d(left.K()), K1);
  cv::eigen2cv(Eigen::Matrix3d(right.K()), K2);
  // OpenCV wants p_CR = R p_CL + T.
  const Pose3 X_CRCL = X_CLCR.inverse();
  cv::eigen2cv(Eigen::Matrix3d(X_CRCL.linear()), R);
  cv::eigen2cv(Eigen::Vector3d(X_CRCL.translation()), T);
  const cv::Size size(left.width, left.height);
  cv::Mat R1, R2, P1, P2, Q;
  cv::stereoRectify(K1, cv::Mat(), K2, cv::Mat(), size, R, T, R1, R2, P1, P2, Q,
                    cv::CALIB_ZERO_DISPARITY, -1.0, size);
  Rectification r;
  r.width = size.width;
  r.height = size.height;
  // Keep the cameras' own focal length and the image centre: rectification then only turns the
  // images by the verge angle, resampling them almost one to one (zooming in, as
  // stereoRectify's cropping does, biases the sub-pixel stripe location).
  r.f = left.fx;
  r.cx = 0.5 * (size.width - 1);
  r.cy = 0.5 * (size.height - 1);
  // P2 = [K | K (-2b, 0, 0)]: P2(0,3) = -2 b f.
  r.b = -0.5 * P2.at<double>(0, 3) / P2.at<double>(0, 0);
  for (cv::Mat* P : {&P1, &P2}) {
    P->at<double>(0, 0) = P->at<double>(1, 1) = r.f;
    P->at<double>(0, 2) = r.cx;
    P->at<double>(1, 2) = r.cy;
  }
  P2.at<double>(0, 3) = -2.0 * r.b * r.f;
  HGRASP_DEMAND_MSG(r.b > 0, "the right camera must lie to the right of the left one");
  cv::cv2eigen(R1, r.R_RC[0]);
  cv::cv2eigen(R2, r.R_RC[1]);
  cv::initUndistortRectifyMap(K1, cv::Mat(), R1, P1, size, CV_16SC2, r.map1[0], r.map2[0]);
  cv::initUndistortRectifyMap(K2, cv::Mat(), R2, P2, size, CV_16SC2, r.map1[1], r.map2[1]);
  // M: left rectified frame shifted by +b along its x.
  r.X_CLM = Pose3::Identity();
  r.X_CLM.linear() = r.R_RC[0].transpose();
  r.X_CLM.translation() = r.R_RC[0].transpose() * Eigen::Vector3d(r.b, 0, 0);
  return r;
}

}  // namespace hgrasp::scan
