#include "scan/stripe_frame.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "common/error.h"

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

namespace {

// Whether a and b hold the same pixels, byte for byte: a memory comparison, a fraction of
// cv::norm's cost. (Float images equal in value but not in bytes, +0 against -0, are merely
// processed again.)
bool SameImage(const cv::Mat& a, const cv::Mat& b) {
  if (a.empty() || a.size() != b.size() || a.type() != b.type()) return false;
  const size_t row_bytes = a.cols * a.elemSize();
  for (int r = 0; r < a.rows; ++r) {
    if (std::memcmp(a.ptr(r), b.ptr(r), row_bytes) != 0) return false;
  }
  return true;
}

}  // namespace

StripeFrameProcessor::StripeFrameProcessor(const Rectification* rect, StripeFrameConfig config)
    : rect_(rect), config_(config) {}

void StripeFrameProcessor::RectifyBand(int camera, const cv::Mat& image, std::pair<int, int> band) {
  const Rectification& R = *rect_;
  cv::extractChannel(image, red_[camera], 2);  // BGR: the laser is red
  rectified_[camera].create(R.height, R.width, CV_8U);
  rectified_[camera].setTo(0);  // outside the band: nothing searched, nothing shown
  band_[camera] = band;
  if (band.second < band.first) return;
  const cv::Rect roi(band.first, 0, band.second - band.first + 1, R.height);
  cv::Mat out = rectified_[camera](roi);
  cv::remap(red_[camera], out, R.map1[camera](roi), R.map2[camera](roi), cv::INTER_LINEAR,
            cv::BORDER_CONSTANT, cv::Scalar(0));
}

void StripeFrameProcessor::SetAmbient(const cv::Mat& left, const cv::Mat& right) {
  const Rectification& R = *rect_;
  for (int camera = 0; camera < 2; ++camera) {
    const cv::Mat& image = camera == 0 ? left : right;
    if (image.empty()) {
      ambient_[camera].release();
      ambient_rectified_[camera].release();
      continue;
    }
    // The same images again (the usual case: one ambient pair per scan) cost a comparison.
    if (SameImage(ambient_[camera], image)) continue;
    image.copyTo(ambient_[camera]);
    cv::Mat red;
    cv::extractChannel(image, red, 2);
    cv::remap(red, ambient_rectified_[camera], R.map1[camera], R.map2[camera], cv::INTER_LINEAR,
              cv::BORDER_CONSTANT, cv::Scalar(0));
  }
}

void StripeFrameProcessor::Rectify(const cv::Mat& left, const cv::Mat& right) {
  RectifyBand(0, left, {0, rect_->width - 1});
  RectifyBand(1, right, {0, rect_->width - 1});
}

std::pair<int, int> StripeFrameProcessor::StripeBand(int camera, const LaserCoefficients& c) const {
  const Rectification& R = *rect_;
  const Plane p = PlaneFromCoefficients(c, R.b);
  const double A = p.n.x(), B = p.n.y(), C = p.n.z(), D = p.d;
  if (std::abs(A) < 1e-3) return {0, R.width - 1};  // a sheet facing the cameras: anywhere
  // On the plane at depth Z, row y: xL = (-B y - C f + f (A b - D) / Z) / A and
  // xR = (-B y - C f - f (A b + D) / Z) / A; linear in y and 1/Z, so the extremes are at the
  // corners of (rows) x (depth range).
  const double k = camera == 0 ? A * R.b - D : -(A * R.b + D);
  double lo = 1e9, hi = -1e9;
  for (const double y : {-R.cy, R.height - 1 - R.cy}) {
    for (const double Z : {config_.min_range_m, config_.max_range_m}) {
      const double x = (-B * y - C * R.f + R.f * k / Z) / A;
      lo = std::min(lo, x), hi = std::max(hi, x);
    }
  }
  const int margin = config_.detector.half_width + 2;
  const int first = std::max(0, static_cast<int>(std::floor(lo + R.cx)) - margin);
  const int last = std::min(R.width - 1, static_cast<int>(std::ceil(hi + R.cx)) + margin);
  return {first, last};
}

void StripeFrameProcessor::Process(const cv::Mat& left, const cv::Mat& right,
                                   const LaserCoefficients& c, StripeFrameResult* out) {
  out->points.clear();
  out->rejected = 0;
  // Only the columns where the plane can put a stripe are rectified and searched.
  RectifyBand(0, left, StripeBand(0, c));
  if (config_.stereo) RectifyBand(1, right, StripeBand(1, c));
  const Rectification& R = *rect_;
  // Candidates of every row, down to weak_contrast; the weak ones then need the stripe to go on
  // through them on the rows above and below.
  StripeDetectorConfig weak = config_.detector;
  weak.min_contrast = std::min(config_.weak_contrast, config_.detector.min_contrast);
  for (int cam = 0; cam < (config_.stereo ? 2 : 1); ++cam) {
    const auto [first, last] = band_[cam];
    std::vector<std::vector<StripeCandidate>>& rows = rows_[cam];
    rows.resize(R.height);
    for (int row = 0; row < R.height; ++row) {
      rows[row].clear();
      if (last < first) continue;
      const std::uint8_t* ambient = ambient_rectified_[cam].empty()
                                        ? nullptr
                                        : ambient_rectified_[cam].ptr<std::uint8_t>(row) + first;
      DetectStripeCandidates(rectified_[cam].ptr<std::uint8_t>(row) + first, last - first + 1, weak,
                             &rows[row], ambient);
      for (StripeCandidate& k : rows[row]) k.x += first;
    }
  }
  const auto supported = [&](int cam, int row, double x) {
    const auto near = [&](int r) {
      if (r < 0 || r >= R.height) return false;
      const double step = std::abs(r - row) * config_.max_support_step_px;
      for (const StripeCandidate& k : rows_[cam][r]) {
        if (std::abs(k.x - x) <= step) return true;
      }
      return false;
    };
    return near(row - 1) && near(row + 1) && near(row - 2) && near(row + 2);
  };
  const auto detect = [&](int cam, int row) {
    candidates_[cam].clear();
    for (const StripeCandidate& k : rows_[cam][row]) {
      if (k.contrast >= config_.detector.min_contrast || supported(cam, row, k.x)) {
        candidates_[cam].push_back(k);
      }
    }
  };
  const Plane plane_M = config_.stereo ? Plane{} : PlaneFromCoefficients(c, R.b);
  for (int row = 0; row < R.height; ++row) {
    const double y = row - R.cy;
    detect(0, row);
    if (candidates_[0].empty()) continue;
    const auto in_range = [&](const Eigen::Vector3d& p_M) {
      return p_M.z() >= config_.min_range_m && p_M.norm() <= config_.max_range_m;
    };
    if (!config_.stereo) {
      const double xL = candidates_[0].front().x - R.cx;
      const Eigen::Vector3d p_M = IntersectLeftRay(xL, y, plane_M, R);
      if (in_range(p_M)) {
        out->points.push_back({row, xL, 0.0, 0.0, p_M});
      } else {
        ++out->rejected;
      }
      continue;
    }
    detect(1, row);
    if (candidates_[1].empty()) continue;
    const auto m =
        MatchRow(candidates_[0], candidates_[1], R.cx, y, R.f, c, config_.max_residue_px);
    if (!m) {
      ++out->rejected;
      continue;
    }
    const double xL = candidates_[0][m->left].x - R.cx, xR = candidates_[1][m->right].x - R.cx;
    const Eigen::Vector3d p_M = ReconstructOnPlane(xL, xR, y, c, R);
    if (!in_range(p_M)) {
      ++out->rejected;
      continue;
    }
    out->points.push_back({row, xL, xR, m->residue, p_M});
  }
  if (config_.stereo) RejectIsolated(out);
}

void StripeFrameProcessor::RejectIsolated(StripeFrameResult* out) const {
  // Points come in row order: the neighbours of point i are among i-2..i+2.
  std::vector<StripePoint>& points = out->points;
  const double gap2 = config_.max_neighbour_gap_m * config_.max_neighbour_gap_m;
  std::vector<char> keep(points.size(), 0);
  for (size_t i = 0; i < points.size(); ++i) {
    for (size_t j = i >= 2 ? i - 2 : 0; j < std::min(points.size(), i + 3); ++j) {
      if (j != i && std::abs(points[j].row - points[i].row) <= 2 &&
          (points[j].p_M - points[i].p_M).squaredNorm() < gap2) {
        keep[i] = 1;
        break;
      }
    }
  }
  size_t n = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    if (keep[i]) points[n++] = points[i];
  }
  out->rejected += static_cast<int>(points.size() - n);
  points.resize(n);
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
