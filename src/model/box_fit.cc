#include "model/box_fit.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "common/error.h"

namespace hgrasp::model {
namespace {

using Eigen::Vector3d;

constexpr double kMinEdgeM = 0.01;   // shortest accepted box edge (m)
constexpr double kMaxEdgeM = 0.5;    // longest accepted box edge (m)
constexpr double kMinDepthM = 0.01;  // a hidden face lies at least this far beyond its visible one

/// Appends the 3-D points of the cells labelled id that have a 4-neighbour which is invalid,
/// outside the image or labelled differently.
void AppendEdgePoints(const segment::SegmentResult& s, const scan::RangeImage& range, int id,
                      std::vector<Vector3d>* out) {
  auto other = [&](int r, int c) {
    if (r < 0 || c < 0 || r >= s.rows || c >= s.cols) return true;
    return !range.at(r, c).valid || s.labels[r * s.cols + c] != id;
  };
  for (int r = 0; r < s.rows; ++r) {
    for (int c = 0; c < s.cols; ++c) {
      if (s.labels[r * s.cols + c] != id) continue;
      if (other(r - 1, c) || other(r + 1, c) || other(r, c - 1) || other(r, c + 1)) {
        out->push_back(range.at(r, c).p_W);
      }
    }
  }
}

/// A hidden face from the edge points along its normal: their robust extreme (the 99th
/// percentile), if beyond min_t. The stripe crosses a face's far end at a slant, so its edge
/// points there are ragged over about a centimetre. The paper's vote (c_i = sum_j (d_j + 1)^-2,
/// the densest line of edge points) then picks a line inside that band, 5-8 mm short on the
/// simulated scans, where the extreme is right.
std::optional<double> Extreme(std::vector<double> t, double min_t) {
  if (t.empty()) return std::nullopt;
  std::sort(t.begin(), t.end());
  const double v = t[t.size() - 1 - t.size() / 100];
  if (!(v > min_t)) return std::nullopt;
  return v;
}

std::vector<double> Project(const std::vector<Vector3d>& points, const Vector3d& n, double sign) {
  std::vector<double> t;
  t.reserve(points.size());
  for (const Vector3d& p : points) t.push_back(sign * n.dot(p));
  return t;
}

/// Extent [lo, hi] along n of a pair whose visible face is at a, the hidden one voted among the
/// edge points; into = +1 when the box lies on the side n points to from the visible face.
std::optional<std::pair<double, double>> HiddenExtent(const std::vector<Vector3d>& edges,
                                                      const Vector3d& n, double a, double into) {
  const std::vector<double> t = Project(edges, n, into);
  const std::optional<double> v = Extreme(t, into * a + kMinDepthM);
  if (!v) return std::nullopt;
  const double b = into * *v;
  return std::make_pair(std::min(a, b), std::max(a, b));
}

}  // namespace

std::optional<BoxModel> FitBox(const segment::SegmentResult& s,
                               const std::vector<int>& object_regions,
                               const scan::RangeImage& range, const BoxFitConfig& config) {
  HGRASP_DEMAND(s.rows == range.rows() && s.cols == range.cols());
  HGRASP_DEMAND(static_cast<int>(s.labels.size()) == s.rows * s.cols);
  std::unordered_map<int, const segment::PlaneRegion*> by_id;
  for (const segment::PlaneRegion& r : s.regions) by_id[r.id] = &r;

  const double cos_tol = std::cos(DegToRad(config.max_face_angle_deg));
  const double sin_tol = std::sin(DegToRad(config.max_face_angle_deg));
  std::vector<const segment::PlaneRegion*> regions;
  for (int id : object_regions) {
    auto it = by_id.find(id);
    if (it != by_id.end()) regions.push_back(it->second);
  }

  // A1: the largest near-horizontal region; A2: the largest near-vertical one.
  const segment::PlaneRegion* top = nullptr;
  const segment::PlaneRegion* side2 = nullptr;
  for (const segment::PlaneRegion* r : regions) {
    if (std::abs(r->normal_W.z()) > cos_tol) {
      if (top == nullptr || r->cells > top->cells) top = r;
    } else if (std::abs(r->normal_W.z()) < sin_tol) {
      if (side2 == nullptr || r->cells > side2->cells) side2 = r;
    }
  }
  if (top == nullptr || side2 == nullptr) return std::nullopt;
  if (top->cells < config.min_face_cells || side2->cells < config.min_face_cells) {
    return std::nullopt;
  }

  // Orthonormal normals: n1 up from the top fit, n2 from A2 made perpendicular, n3 = n1 x n2.
  Vector3d n1 = top->normal_W.normalized();
  if (n1.z() < 0) n1 = -n1;
  Vector3d n2 = side2->normal_W - side2->normal_W.dot(n1) * n1;
  if (n2.norm() < 1e-6) return std::nullopt;
  n2.normalize();
  const Vector3d n3 = n1.cross(n2);

  // A3: the largest other near-vertical region nearly perpendicular to A2 (and so to A1).
  const segment::PlaneRegion* side3 = nullptr;
  for (const segment::PlaneRegion* r : regions) {
    if (r == top || r == side2 || std::abs(r->normal_W.z()) >= sin_tol) continue;
    if (r->cells < config.min_face_cells) continue;
    if (std::abs(r->normal_W.normalized().dot(n2)) >= sin_tol) continue;
    if (side3 == nullptr || r->cells > side3->cells) side3 = r;
  }

  std::vector<Vector3d> edges_top, edges2, edges3;
  AppendEdgePoints(s, range, top->id, &edges_top);
  AppendEdgePoints(s, range, side2->id, &edges2);
  if (side3 != nullptr) AppendEdgePoints(s, range, side3->id, &edges3);

  // Pair 1: top at n1 . c_top, bottom on the table z = 0 below the top's centroid.
  const double hi1 = n1.dot(top->centroid_W);
  const double lo1 = hi1 - top->centroid_W.z() * n1.z();

  // Pair 2: A2 visible; B2 voted over the edges of A1 and A3, beyond A2 away from the cameras
  // (the box's interior is on the top's side of A2).
  const double a2 = n2.dot(side2->centroid_W);
  const double into2 = n2.dot(top->centroid_W - side2->centroid_W) >= 0 ? 1.0 : -1.0;
  std::vector<Vector3d> edges_for_b2 = edges_top;
  edges_for_b2.insert(edges_for_b2.end(), edges3.begin(), edges3.end());
  const auto ext2 = HiddenExtent(edges_for_b2, n2, a2, into2);
  if (!ext2) return std::nullopt;

  // Pair 3: over the edges of A1 and A2.
  std::vector<Vector3d> edges_for_3 = edges_top;
  edges_for_3.insert(edges_for_3.end(), edges2.begin(), edges2.end());
  std::optional<std::pair<double, double>> ext3;
  if (side3 != nullptr) {
    const double a3 = n3.dot(side3->centroid_W);
    const double into3 = n3.dot(top->centroid_W - side3->centroid_W) >= 0 ? 1.0 : -1.0;
    ext3 = HiddenExtent(edges_for_3, n3, a3, into3);
  } else {
    // Both extremes from the vote, each among the edge points near its end of the spread.
    const std::vector<double> t = Project(edges_for_3, n3, 1.0);
    const std::vector<double> neg = Project(edges_for_3, n3, -1.0);
    const std::optional<double> hi = Extreme(t, -1e9);
    const std::optional<double> lo_neg = Extreme(neg, -1e9);
    if (hi && lo_neg && *hi + *lo_neg >= kMinDepthM) ext3 = std::make_pair(-*lo_neg, *hi);
  }
  if (!ext3) return std::nullopt;

  const Vector3d size(ext2->second - ext2->first, ext3->second - ext3->first, hi1 - lo1);
  for (int i = 0; i < 3; ++i) {
    if (!(size[i] >= kMinEdgeM && size[i] <= kMaxEdgeM)) return std::nullopt;
  }

  BoxModel box;
  Eigen::Matrix3d R_WO;
  R_WO.col(0) = n2;
  R_WO.col(1) = n3;
  R_WO.col(2) = n1;
  box.X_WO.linear() = R_WO;
  box.X_WO.translation() = 0.5 * (ext2->first + ext2->second) * n2 +
                           0.5 * (ext3->first + ext3->second) * n3 + 0.5 * (lo1 + hi1) * n1;
  box.size_O = size;
  for (int k = 0; k < 8; ++k) {
    const Vector3d corner_O(((k & 1) ? 0.5 : -0.5) * size.x(), ((k & 2) ? 0.5 : -0.5) * size.y(),
                            ((k & 4) ? 0.5 : -0.5) * size.z());
    box.vertices_W[k] = box.X_WO * corner_O;
  }
  box.regions.push_back(top->id);
  box.regions.push_back(side2->id);
  box.points = top->cells + side2->cells;
  if (side3 != nullptr) {
    box.regions.push_back(side3->id);
    box.points += side3->cells;
  }
  return box;
}

std::vector<BoxModel> FitBoxes(const segment::SegmentResult& s, const segment::Grouping& g,
                               const scan::RangeImage& range, int* failed,
                               const BoxFitConfig& config) {
  std::vector<BoxModel> boxes;
  int fails = 0;
  for (const std::vector<int>& object : g.objects) {
    std::optional<BoxModel> box = FitBox(s, object, range, config);
    if (box) {
      boxes.push_back(std::move(*box));
    } else {
      ++fails;
    }
  }
  if (failed != nullptr) *failed = fails;
  return boxes;
}

}  // namespace hgrasp::model
