#include "model/box_fit.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <unordered_map>

#include "common/error.h"

namespace hgrasp::model {
namespace {

using Eigen::Vector3d;

constexpr double kMinEdgeM = 0.01;   // shortest accepted box edge (m)
constexpr double kMaxEdgeM = 0.5;    // longest accepted box edge (m)
constexpr double kMinDepthM = 0.01;  // a hidden face lies at least this far beyond its visible one
// Top edge points farther off its plane than this, or 3 sigma of its points, are unsure.
constexpr double kMaxEdgeOffPlaneM = 0.002;

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

/// A hidden face from the edge points along its normal, t (m), if beyond min_t. The stripe
/// crosses a face's far end at a slant, so its edge points there are ragged over about a
/// centimetre; the paper's vote (c_i = sum_j (d_j + 1)^-2, the densest line of edge points)
/// picks a line inside that band, 5-8 mm short on the simulated scans. Here: the robust extreme
/// (the 99th percentile) of the edge points, plus a quarter of the cells' spacing along the
/// normal: the outermost cells lie inside the true edge by half a spacing on average where the
/// edge runs along the scan's lattice of cells (one line of cells at a random phase), by next to
/// nothing where it runs across it (cells at every phase); boxes stand at any yaw.
std::optional<double> Extreme(std::vector<double> t, double min_t, double spacing) {
  if (t.empty()) return std::nullopt;
  std::sort(t.begin(), t.end());
  const double edge = t[t.size() - 1 - t.size() / 100] + 0.25 * spacing;
  if (!(edge > min_t)) return std::nullopt;
  return edge;
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
                                                      const Vector3d& n, double a, double into,
                                                      double spacing) {
  const std::vector<double> t = Project(edges, n, into);
  const std::optional<double> v = Extreme(t, into * a + kMinDepthM, spacing);
  if (!v) return std::nullopt;
  const double b = into * *v;
  return std::make_pair(std::min(a, b), std::max(a, b));
}

/// The edge points that place a hidden side face: the top face's, and a side face's from its
/// upper part only (above the middle of the box's height). Near the table, a side face's region
/// can take in table cells along the line where its plane meets the table, beyond the box's
/// corner (they satisfy its plane); the top and the upper parts of the sides have no such cells.
std::vector<Vector3d> HorizontalEdges(const std::vector<Vector3d>& top,
                                      const std::vector<Vector3d>& side) {
  double top_z = 0;
  for (const Vector3d& p : top) top_z += p.z();
  top_z /= std::max<size_t>(top.size(), 1);
  std::vector<Vector3d> out = top;
  for (const Vector3d& p : side) {
    if (p.z() > 0.5 * top_z) out.push_back(p);
  }
  return out;
}

/// Both ends along n of a pair whose faces are both hidden: the edge points' robust extremes.
std::optional<std::pair<double, double>> BothExtremes(const std::vector<Vector3d>& edges,
                                                      const Vector3d& n, double spacing) {
  const std::optional<double> hi = Extreme(Project(edges, n, 1.0), -1e9, spacing);
  const std::optional<double> lo_neg = Extreme(Project(edges, n, -1.0), -1e9, spacing);
  if (!hi || !lo_neg || *hi + *lo_neg < kMinDepthM) return std::nullopt;
  return std::make_pair(-*lo_neg, *hi);
}

/// The spacing of a face's range cells along n: the scan samples a face on a lattice (image rows
/// by stripe positions, about 1.5-3 mm apart on the workspace's faces); the larger of the median
/// row and column steps along n.
double Spacing(const segment::SegmentResult& s, const scan::RangeImage& range, int id,
               const Vector3d& n) {
  std::vector<double> along_rows, along_cols;
  for (int r = 0; r < s.rows; ++r) {
    for (int c = 0; c < s.cols; ++c) {
      if (s.labels[r * s.cols + c] != id) continue;
      const Vector3d& p = range.at(r, c).p_W;
      if (c + 1 < s.cols && s.labels[r * s.cols + c + 1] == id) {
        along_cols.push_back(std::abs(n.dot(range.at(r, c + 1).p_W - p)));
      }
      if (r + 1 < s.rows && s.labels[(r + 1) * s.cols + c] == id) {
        along_rows.push_back(std::abs(n.dot(range.at(r + 1, c).p_W - p)));
      }
    }
  }
  const auto median = [](std::vector<double>& v) {
    if (v.empty()) return 0.0;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  return std::max(median(along_rows), median(along_cols));
}

/// The direction of one of the top face's outline edges (horizontal, unit, in W) when no side
/// face is seen: the minimum-area rectangle around the top's points in its plane, each of its
/// sides then refined by a line through the edge points along it. nullopt when the outline is
/// not a rectangle (its convex hull fills less than min_fill of the rectangle) or a side is under
/// kMinEdgeM: a sliver or a partly hidden top gives no box.
std::optional<Vector3d> TopOutlineAxis(const std::vector<Vector3d>& top_points,
                                       const std::vector<Vector3d>& top_edges, const Vector3d& n1,
                                       double min_fill) {
  if (top_points.size() < 3) return std::nullopt;
  Vector3d e1 = n1.cross(Vector3d::UnitY());
  if (e1.norm() < 0.5) e1 = n1.cross(Vector3d::UnitX());
  e1.normalize();
  const Vector3d e2 = n1.cross(e1);
  const auto plane_mm = [&](const Vector3d& p) {
    return cv::Point2f(static_cast<float>(1e3 * e1.dot(p)), static_cast<float>(1e3 * e2.dot(p)));
  };
  std::vector<cv::Point2f> points;
  for (const Vector3d& p : top_points) points.push_back(plane_mm(p));
  std::vector<cv::Point2f> hull;
  cv::convexHull(points, hull);
  const cv::RotatedRect rect = cv::minAreaRect(hull);
  if (std::min(rect.size.width, rect.size.height) < 1e3 * kMinEdgeM) return std::nullopt;
  if (cv::contourArea(hull) < min_fill * rect.size.area()) return std::nullopt;
  double theta = DegToRad(rect.angle);
  // Refinement: each side's edge points (within 3 mm of it) get a line; the sides' directions,
  // taken modulo 90 deg, are averaged by their point counts.
  cv::Point2f corners[4];
  rect.points(corners);
  std::vector<cv::Point2f> edges;
  for (const Vector3d& p : top_edges) edges.push_back(plane_mm(p));
  double sum_delta = 0, sum_w = 0;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector2d a(corners[k].x, corners[k].y),
        b(corners[(k + 1) % 4].x, corners[(k + 1) % 4].y);
    const Eigen::Vector2d u = (b - a).normalized(), m(-u.y(), u.x());
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    std::vector<Eigen::Vector2d> near;
    for (const cv::Point2f& q : edges) {
      const Eigen::Vector2d d = Eigen::Vector2d(q.x, q.y) - a;
      const double along = d.dot(u);
      if (std::abs(d.dot(m)) < 3.0 && along > 0 && along < (b - a).norm()) {
        near.push_back(Eigen::Vector2d(q.x, q.y));
        mean += near.back();
      }
    }
    if (near.size() < 5) continue;
    mean /= static_cast<double>(near.size());
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (const Eigen::Vector2d& q : near) cov += (q - mean) * (q - mean).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov);
    const Eigen::Vector2d dir = es.eigenvectors().col(1);
    // Angle of the fitted line against the rectangle's side, in (-90, 90] deg -> (-45, 45].
    double delta = std::atan2(u.x() * dir.y() - u.y() * dir.x(), u.dot(dir));
    while (delta > kPi / 4) delta -= kPi / 2;
    while (delta <= -kPi / 4) delta += kPi / 2;
    sum_delta += near.size() * delta;
    sum_w += static_cast<double>(near.size());
  }
  if (sum_w > 0) theta += sum_delta / sum_w;
  return (std::cos(theta) * e1 + std::sin(theta) * e2).normalized();
}

/// The faces a box is fitted to: A1, the largest near-horizontal region (the top); A2, the
/// largest near-vertical one; A3, the largest other near-vertical one nearly perpendicular to A2.
struct Faces {
  const segment::PlaneRegion* top = nullptr;
  const segment::PlaneRegion* side2 = nullptr;
  const segment::PlaneRegion* side3 = nullptr;
};

/// A1 and A2 of `regions` (side2 null when none is large enough); nullopt without a large top.
std::optional<Faces> TopAndSide(const std::vector<const segment::PlaneRegion*>& regions,
                                const BoxFitConfig& config, double cos_tol, double sin_tol) {
  Faces f;
  for (const segment::PlaneRegion* r : regions) {
    if (std::abs(r->normal_W.z()) > cos_tol) {
      if (f.top == nullptr || r->cells > f.top->cells) f.top = r;
    } else if (std::abs(r->normal_W.z()) < sin_tol) {
      if (f.side2 == nullptr || r->cells > f.side2->cells) f.side2 = r;
    }
  }
  if (f.top == nullptr || f.top->cells < config.min_face_cells) return std::nullopt;
  if (f.side2 != nullptr && f.side2->cells < config.min_face_cells) f.side2 = nullptr;
  return f;
}

/// A3: the largest near-vertical region other than A1 and A2, nearly perpendicular to n2.
const segment::PlaneRegion* ThirdSide(const std::vector<const segment::PlaneRegion*>& regions,
                                      const Faces& f, const Vector3d& n2,
                                      const BoxFitConfig& config, double sin_tol) {
  const segment::PlaneRegion* side3 = nullptr;
  if (f.side2 == nullptr) return side3;
  for (const segment::PlaneRegion* r : regions) {
    if (r == f.top || r == f.side2 || std::abs(r->normal_W.z()) >= sin_tol) continue;
    if (r->cells < config.min_face_cells) continue;
    if (std::abs(r->normal_W.normalized().dot(n2)) >= sin_tol) continue;
    if (side3 == nullptr || r->cells > side3->cells) side3 = r;
  }
  return side3;
}

/// The top's edge points on its plane: where the top's far edge occludes the table, a stripe
/// cut by the edge gives points off the plane and, along it, beyond the edge.
std::vector<Vector3d> TopEdges(const segment::SegmentResult& s, const scan::RangeImage& range,
                               const segment::PlaneRegion& top) {
  std::vector<Vector3d> edges;
  AppendEdgePoints(s, range, top.id, &edges);
  const double off_plane = std::max(kMaxEdgeOffPlaneM, 3.0 * std::sqrt(top.residual_m2));
  std::erase_if(edges, [&](const Vector3d& p) {
    return std::abs(top.normal_W.dot(p - top.centroid_W)) > off_plane;
  });
  return edges;
}

/// n2: A2's normal made perpendicular to n1 or, with no side seen, along the top's outline.
std::optional<Vector3d> SecondNormal(const segment::SegmentResult& s, const scan::RangeImage& range,
                                     const Faces& f, const std::vector<Vector3d>& edges_top,
                                     const Vector3d& n1, const BoxFitConfig& config) {
  if (f.side2 != nullptr) {
    Vector3d n2 = f.side2->normal_W - f.side2->normal_W.dot(n1) * n1;
    if (n2.norm() < 1e-6) return std::nullopt;
    return n2.normalized();
  }
  if (f.top->cells < config.min_top_only_cells) return std::nullopt;
  std::vector<Vector3d> top_points;
  for (int i = 0; i < s.rows * s.cols; ++i) {
    if (s.labels[i] == f.top->id) top_points.push_back(range.at(i / s.cols, i % s.cols).p_W);
  }
  return TopOutlineAxis(top_points, edges_top, n1, config.min_top_fill);
}

/// The box's extent along n (n2 or n3): from the visible side `side` to the hidden face voted
/// over `edges` beyond it (the box's interior is on the top's side of it) or, with no side
/// seen, both ends at the edge points' extremes. `spacing`: the top's cell spacing along n.
std::optional<std::pair<double, double>> ExtentAlong(const std::vector<Vector3d>& edges,
                                                     const segment::PlaneRegion* side,
                                                     const segment::PlaneRegion& top,
                                                     const Vector3d& n, double spacing) {
  if (side == nullptr) return BothExtremes(edges, n, spacing);
  const double a = n.dot(side->centroid_W);
  const double into = n.dot(top.centroid_W - side->centroid_W) >= 0 ? 1.0 : -1.0;
  return HiddenExtent(edges, n, a, into, spacing);
}

/// The box between the extents along n2 and n3 and from the table (z = 0 below the top's
/// centroid) to the top, with the faces' regions and cells; nullopt for an edge out of range.
std::optional<BoxModel> Assemble(const Faces& f, const Vector3d& n1, const Vector3d& n2,
                                 const Vector3d& n3, const std::pair<double, double>& ext2,
                                 const std::pair<double, double>& ext3) {
  const double hi1 = n1.dot(f.top->centroid_W);
  const double lo1 = hi1 - f.top->centroid_W.z() * n1.z();
  const Vector3d size(ext2.second - ext2.first, ext3.second - ext3.first, hi1 - lo1);
  for (int i = 0; i < 3; ++i) {
    if (!(size[i] >= kMinEdgeM && size[i] <= kMaxEdgeM)) return std::nullopt;
  }
  Pose3 X_WO = Pose3::Identity();
  Eigen::Matrix3d R_WO;
  R_WO.col(0) = n2;
  R_WO.col(1) = n3;
  R_WO.col(2) = n1;
  X_WO.linear() = R_WO;
  X_WO.translation() = 0.5 * (ext2.first + ext2.second) * n2 +
                       0.5 * (ext3.first + ext3.second) * n3 + 0.5 * (lo1 + hi1) * n1;
  BoxModel box = MakeBox(X_WO, size);
  box.regions.push_back(f.top->id);
  box.points = f.top->cells;
  for (const segment::PlaneRegion* side : {f.side2, f.side3}) {
    if (side == nullptr) continue;
    box.regions.push_back(side->id);
    box.points += side->cells;
  }
  return box;
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
  std::optional<Faces> faces = TopAndSide(regions, config, cos_tol, sin_tol);
  if (!faces) return std::nullopt;
  const segment::PlaneRegion& top = *faces->top;
  const std::vector<Vector3d> edges_top = TopEdges(s, range, top);

  // Orthonormal normals: n1 up from the top fit, n2 from A2 (SecondNormal), n3 = n1 x n2.
  Vector3d n1 = top.normal_W.normalized();
  if (n1.z() < 0) n1 = -n1;
  const std::optional<Vector3d> n2 = SecondNormal(s, range, *faces, edges_top, n1, config);
  if (!n2) return std::nullopt;
  const Vector3d n3 = n1.cross(*n2);
  faces->side3 = ThirdSide(regions, *faces, *n2, config, sin_tol);
  std::vector<Vector3d> edges2, edges3;
  if (faces->side2 != nullptr) AppendEdgePoints(s, range, faces->side2->id, &edges2);
  if (faces->side3 != nullptr) AppendEdgePoints(s, range, faces->side3->id, &edges3);

  // Pair 1 (Assemble): the top, and the table below it. Pair 2: A2 visible, B2 voted over the
  // edges of A1 and A3. Pair 3: over the edges of A1 and A2. With no side seen, both ends are
  // the top's edge points' extremes. The top's cell spacing along n2 and n3 places hidden faces
  // (see Extreme).
  const std::vector<Vector3d> edges_for_2 =
      faces->side2 != nullptr ? HorizontalEdges(edges_top, edges3) : edges_top;
  const std::optional<std::pair<double, double>> ext2 =
      ExtentAlong(edges_for_2, faces->side2, top, *n2, Spacing(s, range, top.id, *n2));
  if (!ext2) return std::nullopt;
  const std::optional<std::pair<double, double>> ext3 = ExtentAlong(
      HorizontalEdges(edges_top, edges2), faces->side3, top, n3, Spacing(s, range, top.id, n3));
  if (!ext3) return std::nullopt;
  return Assemble(*faces, n1, *n2, n3, *ext2, *ext3);
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

BoxModel MakeBox(const Pose3& X_WO, const Eigen::Vector3d& size_O) {
  BoxModel box;
  box.X_WO = X_WO;
  box.size_O = size_O;
  for (int k = 0; k < 8; ++k) {
    const Vector3d corner_O(((k & 1) ? 0.5 : -0.5) * size_O.x(),
                            ((k & 2) ? 0.5 : -0.5) * size_O.y(),
                            ((k & 4) ? 0.5 : -0.5) * size_O.z());
    box.vertices_W[k] = X_WO * corner_O;
  }
  return box;
}

}  // namespace hgrasp::model
