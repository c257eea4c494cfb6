#include "servo/led_detector.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <tuple>
#include <vector>

namespace hgrasp::servo {

std::vector<LedBlob> DetectLeds(const cv::Mat& bgr, const LedDetectorConfig& config) {
  std::vector<LedBlob> blobs;
  if (bgr.empty() || bgr.type() != CV_8UC3) return blobs;
  // Redness R - max(G, B) per pixel, and the mask of candidate pixels.
  cv::Mat redness(bgr.size(), CV_32F), mask(bgr.size(), CV_8U);
  for (int v = 0; v < bgr.rows; ++v) {
    const cv::Vec3b* row = bgr.ptr<cv::Vec3b>(v);
    float* r_out = redness.ptr<float>(v);
    std::uint8_t* m_out = mask.ptr<std::uint8_t>(v);
    for (int u = 0; u < bgr.cols; ++u) {
      const double red = row[u][2];
      const double r = red - std::max(row[u][0], row[u][1]);
      r_out[u] = static_cast<float>(r);
      m_out[u] = (r >= config.min_redness && red >= config.min_red) ? 255 : 0;
    }
  }
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
  for (int i = 1; i < n; ++i) {
    const int area = stats.at<int>(i, cv::CC_STAT_AREA);
    if (area < config.min_area_px || area > config.max_area_px) continue;
    const int u0 = stats.at<int>(i, cv::CC_STAT_LEFT), v0 = stats.at<int>(i, cv::CC_STAT_TOP);
    const int w = stats.at<int>(i, cv::CC_STAT_WIDTH), h = stats.at<int>(i, cv::CC_STAT_HEIGHT);
    if (std::max(w, h) > config.max_elongation * std::min(w, h)) continue;
    // Centroid over the blob's box grown by `margin` px, pixels of other blobs left out,
    // weighted by redness above the floor and by red above the background's: the mask's
    // threshold would cut the blob's rim unevenly and bias a centroid over the mask alone by up
    // to a tenth of a pixel; the background term keeps a red surface around the LED out of it.
    const int m = config.centroid_margin_px;
    const int ua = std::max(0, u0 - m), ub = std::min(bgr.cols - 1, u0 + w - 1 + m);
    const int va = std::max(0, v0 - m), vb = std::min(bgr.rows - 1, v0 + h - 1 + m);
    // The background's red level: the median red of the grown box's rim (not this blob).
    std::vector<int> rim;
    for (int v = va; v <= vb; ++v) {
      const int* l = labels.ptr<int>(v);
      const cv::Vec3b* px = bgr.ptr<cv::Vec3b>(v);
      for (int u = ua; u <= ub; ++u) {
        if ((v == va || v == vb || u == ua || u == ub) && l[u] == 0) rim.push_back(px[u][2]);
      }
    }
    double red_background = 0.0;
    if (!rim.empty()) {
      std::nth_element(rim.begin(), rim.begin() + rim.size() / 2, rim.end());
      red_background = rim[rim.size() / 2];
    }
    double sw = 0, su = 0, sv = 0, peak = 0;
    for (int v = va; v <= vb; ++v) {
      const int* l = labels.ptr<int>(v);
      const float* r = redness.ptr<float>(v);
      for (int u = ua; u <= ub; ++u) {
        if (l[u] != 0 && l[u] != i) continue;
        if (l[u] == i) peak = std::max(peak, static_cast<double>(r[u]));
        // Red above the background's red too: a red surface around the LED adds no weight.
        const double wt =
            std::min(r[u] - config.weight_floor, bgr.at<cv::Vec3b>(v, u)[2] - red_background);
        if (wt <= 0) continue;
        sw += wt;
        su += wt * u;
        sv += wt * v;
      }
    }
    if (peak < config.min_peak || sw <= 0) continue;
    blobs.push_back({Eigen::Vector2d(su / sw, sv / sw), static_cast<double>(area), peak});
  }
  std::sort(blobs.begin(), blobs.end(), [](const LedBlob& a, const LedBlob& b) {
    return std::tie(a.px.y(), a.px.x()) < std::tie(b.px.y(), b.px.x());
  });
  return blobs;
}

Eigen::Vector2d RectifyPoint(const scan::Rectification& rect, int camera, const PinholeCamera& k,
                             const Eigen::Vector2d& px) {
  const Eigen::Vector3d p_R = rect.R_RC[camera] * k.Ray(px.x(), px.y());
  return {rect.f * p_R.x() / p_R.z() + rect.cx, rect.f * p_R.y() / p_R.z() + rect.cy};
}

std::vector<LedPoint> MatchAndTriangulate(const std::vector<LedBlob>& left,
                                          const std::vector<LedBlob>& right,
                                          const robot::StereoIntrinsics& cameras,
                                          const scan::Rectification& rect,
                                          const LedMatchConfig& config) {
  std::vector<Eigen::Vector2d> xl, xr;
  for (const LedBlob& b : left) xl.push_back(RectifyPoint(rect, 0, cameras.left, b.px));
  for (const LedBlob& b : right) xr.push_back(RectifyPoint(rect, 1, cameras.right, b.px));
  // Every admissible pair, closest rows first.
  struct Candidate {
    double row_diff;
    int i, j;
  };
  std::vector<Candidate> candidates;
  for (int i = 0; i < static_cast<int>(xl.size()); ++i) {
    for (int j = 0; j < static_cast<int>(xr.size()); ++j) {
      const double d = xr[j].y() - xl[i].y();
      if (std::abs(d) > config.max_row_diff_px) continue;
      if (xl[i].x() - xr[j].x() < config.min_disparity_px) continue;
      candidates.push_back({d, i, j});
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return std::abs(a.row_diff) < std::abs(b.row_diff);
  });
  std::vector<bool> used_l(xl.size(), false), used_r(xr.size(), false);
  std::vector<LedPoint> points;
  for (const Candidate& c : candidates) {
    if (used_l[c.i] || used_r[c.j]) continue;
    used_l[c.i] = used_r[c.j] = true;
    const double y = 0.5 * (xl[c.i].y() + xr[c.j].y()) - rect.cy;
    const Eigen::Vector3d p_M = rect.Triangulate(xl[c.i].x() - rect.cx, xr[c.j].x() - rect.cx, y);
    points.push_back({rect.X_CLM * p_M, left[c.i].px, right[c.j].px, c.row_diff});
  }
  std::sort(points.begin(), points.end(), [](const LedPoint& a, const LedPoint& b) {
    return std::tie(a.left_px.y(), a.left_px.x()) < std::tie(b.left_px.y(), b.left_px.x());
  });
  return points;
}

}  // namespace hgrasp::servo
