#include "scan/stripe_frame.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

namespace hgrasp::scan {

std::optional<RowMatch> MatchRow(const std::vector<StripeCandidate>& left,
                                 const std::vector<StripeCandidate>& right, double cx, double y,
                                 double f, const LaserCoefficients& c, double max_residue) {
  std::optional<RowMatch> best;
  for (int i = 0; i < static_cast<int>(left.size()); ++i) {
    for (int j = 0; j < static_cast<int>(right.size()); ++j) {
      const double xL = left[i].x - cx, xR = right[j].x - cx;
      if (xL <= xR) continue;  // in front of the cameras only: positive disparity
      const double r = c.Residue(xL, xR, y, f);
      if (std::abs(r) < max_residue && (!best || std::abs(r) < std::abs(best->residue))) {
        best = RowMatch{i, j, r};
      }
    }
  }
  return best;
}

Eigen::Vector3d ReconstructOnPlane(double xL, double xR, double y, const LaserCoefficients& c,
                                   const Rectification& rect) {
  // With equal noise on xL and xR, the maximum-likelihood pair on the line
  // xL + alpha xR + k = 0 is the orthogonal projection of the measured one.
  const double r = c.Residue(xL, xR, y, rect.f);
  const double s = 1.0 + c.alpha * c.alpha;
  return rect.Triangulate(xL - r / s, xR - c.alpha * r / s, y);
}

Eigen::Vector3d IntersectLeftRay(double xL, double y, const Plane& plane_M,
                                 const Rectification& rect) {
  // Left camera centre at (-b, 0, 0) in M, ray direction (xL, y, f).
  const Eigen::Vector3d o(-rect.b, 0, 0), d(xL, y, rect.f);
  const double t = -plane_M.SignedDistance(o) / plane_M.n.dot(d);
  return o + t * d;
}

StripeFrameProcessor::StripeFrameProcessor(const Rectification* rect, StripeFrameConfig config)
    : rect_(rect), config_(config) {}

void StripeFrameProcessor::Rectify(const cv::Mat& left, const cv::Mat& right) {
  const cv::Mat* images[2] = {&left, &right};
  for (int cam = 0; cam < 2; ++cam) {
    cv::extractChannel(*images[cam], red_[cam], 2);  // BGR: the laser is red
    cv::remap(red_[cam], rectified_[cam], rect_->map1[cam], rect_->map2[cam], cv::INTER_LINEAR,
              cv::BORDER_CONSTANT, cv::Scalar(0));
  }
}

void StripeFrameProcessor::Process(const cv::Mat& left, const cv::Mat& right,
                                   const LaserCoefficients& c, StripeFrameResult* out) {
  out->points.clear();
  out->rejected = 0;
  Rectify(left, right);
  const Rectification& R = *rect_;
  const Plane plane_M = config_.stereo ? Plane{} : PlaneFromCoefficients(c, R.b);
  for (int row = 0; row < R.height; ++row) {
    const double y = row - R.cy;
    DetectStripeCandidates(rectified_[0].ptr<std::uint8_t>(row), R.width, config_.detector,
                           &candidates_[0]);
    if (candidates_[0].empty()) continue;
    if (!config_.stereo) {
      const double xL = candidates_[0].front().x - R.cx;
      out->points.push_back({row, xL, 0.0, 0.0, IntersectLeftRay(xL, y, plane_M, R)});
      continue;
    }
    DetectStripeCandidates(rectified_[1].ptr<std::uint8_t>(row), R.width, config_.detector,
                           &candidates_[1]);
    if (candidates_[1].empty()) continue;
    const auto m =
        MatchRow(candidates_[0], candidates_[1], R.cx, y, R.f, c, config_.max_residue_px);
    if (!m) {
      ++out->rejected;
      continue;
    }
    const double xL = candidates_[0][m->left].x - R.cx, xR = candidates_[1][m->right].x - R.cx;
    const Eigen::Vector3d p_M = ReconstructOnPlane(xL, xR, y, c, R);
    if (p_M.z() < config_.min_range_m || p_M.norm() > config_.max_range_m) {
      ++out->rejected;
      continue;
    }
    out->points.push_back({row, xL, xR, m->residue, p_M});
  }
}

void StripeFrameProcessor::CandidatePairs(int per_image,
                                          std::vector<std::vector<Eigen::Vector3d>>* rows) {
  const Rectification& R = *rect_;
  rows->assign(R.height, {});
  for (int row = 0; row < R.height; ++row) {
    DetectStripeCandidates(rectified_[0].ptr<std::uint8_t>(row), R.width, config_.detector,
                           &candidates_[0]);
    DetectStripeCandidates(rectified_[1].ptr<std::uint8_t>(row), R.width, config_.detector,
                           &candidates_[1]);
    for (int i = 0; i < std::min<int>(per_image, candidates_[0].size()); ++i) {
      for (int j = 0; j < std::min<int>(per_image, candidates_[1].size()); ++j) {
        const double xL = candidates_[0][i].x - R.cx, xR = candidates_[1][j].x - R.cx;
        if (xL > xR) (*rows)[row].push_back({xL, xR, row - R.cy});
      }
    }
  }
}

}  // namespace hgrasp::scan
