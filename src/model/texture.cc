#include "model/texture.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <map>
#include <opencv2/imgproc.hpp>
#include <string>
#include <unordered_map>

#include "common/error.h"
#include "common/geometry.h"
#include "model/colour.h"

namespace hgrasp::model {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
using Eigen::Vector3f;

/// A signed axis of O: sign * e_axis.
struct SignedAxis {
  int axis;
  int sign;
};

/// Outward normal and texture axes of a face, as tabled in texture.h.
struct FaceAxes {
  SignedAxis n, u, v;
};

constexpr std::array<FaceAxes, 6> kFaceAxes = {{
    {{0, +1}, {1, +1}, {2, -1}},  // +x
    {{0, -1}, {1, -1}, {2, -1}},  // -x
    {{1, +1}, {0, -1}, {2, -1}},  // +y
    {{1, -1}, {0, +1}, {2, -1}},  // -y
    {{2, +1}, {0, +1}, {1, -1}},  // +z (top)
    {{2, -1}, {0, +1}, {1, +1}},  // -z (bottom)
}};

/// A face is accepted for a normal within this angle of its axis.
const double kMaxFaceAngleRad = DegToRad(30.0);

Vector3d Unit(SignedAxis a) {
  Vector3d e = Vector3d::Zero();
  e[a.axis] = a.sign;
  return e;
}

/// The axis of O most parallel to n_W and the component of the unit n along it in O; axis -1 when
/// that is more than kMaxFaceAngleRad off (or n is zero).
std::pair<int, double> NearestAxis(const BoxModel& box, const Vector3d& n_W) {
  const double norm = n_W.norm();
  if (!(norm > 0)) return {-1, 0.0};
  const Vector3d n_O = box.X_WO.linear().transpose() * (n_W / norm);
  int axis;
  n_O.cwiseAbs().maxCoeff(&axis);
  if (std::abs(n_O[axis]) < std::cos(kMaxFaceAngleRad)) return {-1, 0.0};
  return {axis, n_O[axis]};
}

int FaceOf(int axis, bool positive) { return 2 * axis + (positive ? 0 : 1); }

/// Key of a Subdiv2D vertex by its exact coordinates (the subdivision stores the inserted floats).
std::uint64_t PointKey(float x, float y) {
  return (static_cast<std::uint64_t>(std::bit_cast<std::uint32_t>(x)) << 32) |
         std::bit_cast<std::uint32_t>(y);
}

cv::Vec3b ToBgr(const Vector3f& rgb) {
  auto byte = [](float c) {
    return static_cast<std::uint8_t>(std::lround(std::clamp(c, 0.0f, 1.0f) * 255.0f));
  };
  return cv::Vec3b(byte(rgb.z()), byte(rgb.y()), byte(rgb.x()));
}

/// The cells of one face: positions in the face plane (m, from the top-left corner along u and
/// v) and colours.
struct FaceSamples {
  std::vector<Vector2d> p_m;
  std::vector<Vector3f> rgb;
  int region = -1;
  int region_cells = -1;
};

/// Renders one face's samples into a size x size texture; the face spans extent_m along (u, v).
FaceTexture Render(int face, const FaceSamples& f, const Vector2d& extent_m, int size,
                   double max_edge_m) {
  FaceTexture out;
  out.face = face;
  out.region = f.region;
  out.image = cv::Mat(size, size, CV_8UC3, ToBgr(MedianColour(f.rgb)));
  const Vector2d texels_per_m = Vector2d::Constant(size - 1).cwiseQuotient(extent_m);

  // Delaunay triangulation in texel coordinates. Cells far outside the face (a poor fit) are
  // dropped; those just outside stay, so triangles reach the face's edges.
  const cv::Rect bounds(-size, -size, 3 * size, 3 * size);
  cv::Subdiv2D subdiv(bounds);
  std::unordered_map<std::uint64_t, int> vertex_sample;
  for (size_t i = 0; i < f.p_m.size(); ++i) {
    const Vector2d t = f.p_m[i].cwiseProduct(texels_per_m);
    const cv::Point2f pt(static_cast<float>(t.x()), static_cast<float>(t.y()));
    if (!(pt.x > -size + 1 && pt.y > -size + 1 && pt.x < 2 * size - 1 && pt.y < 2 * size - 1)) {
      continue;
    }
    // A repeated point keeps the first sample's colour.
    if (vertex_sample.emplace(PointKey(pt.x, pt.y), static_cast<int>(i)).second) {
      subdiv.insert(pt);
    }
  }
  if (vertex_sample.size() < 3) return out;
  std::vector<cv::Vec6f> triangles;
  subdiv.getTriangleList(triangles);

  cv::Mat covered(size, size, CV_8U, cv::Scalar(0));
  for (const cv::Vec6f& tri : triangles) {
    std::array<int, 3> idx;
    bool known = true;
    for (int k = 0; k < 3; ++k) {
      const auto it = vertex_sample.find(PointKey(tri[2 * k], tri[2 * k + 1]));
      if (it == vertex_sample.end()) {
        known = false;  // one of the subdivision's outer vertices
        break;
      }
      idx[k] = it->second;
    }
    if (!known) continue;
    bool short_edges = true;
    for (int k = 0; k < 3; ++k) {
      if ((f.p_m[idx[k]] - f.p_m[idx[(k + 1) % 3]]).norm() > max_edge_m) short_edges = false;
    }
    if (!short_edges) continue;

    const double x0 = tri[0], y0 = tri[1], x1 = tri[2], y1 = tri[3], x2 = tri[4], y2 = tri[5];
    const double det = (y1 - y2) * (x0 - x2) + (x2 - x1) * (y0 - y2);
    if (std::abs(det) < 1e-12) continue;
    // Texel centres on an edge (or off it by rounding: the face's outermost cells lie on its edges)
    // belong to the triangle.
    constexpr double kEps = 1e-4;       // barycentric
    constexpr double kEpsTexel = 1e-2;  // bounding box margin, wider than kEps allows
    const int c_lo = std::max(0, static_cast<int>(std::ceil(std::min({x0, x1, x2}) - kEpsTexel)));
    const int c_hi =
        std::min(size - 1, static_cast<int>(std::floor(std::max({x0, x1, x2}) + kEpsTexel)));
    const int r_lo = std::max(0, static_cast<int>(std::ceil(std::min({y0, y1, y2}) - kEpsTexel)));
    const int r_hi =
        std::min(size - 1, static_cast<int>(std::floor(std::max({y0, y1, y2}) + kEpsTexel)));
    for (int r = r_lo; r <= r_hi; ++r) {
      for (int c = c_lo; c <= c_hi; ++c) {
        const double l0 = ((y1 - y2) * (c - x2) + (x2 - x1) * (r - y2)) / det;
        const double l1 = ((y2 - y0) * (c - x2) + (x0 - x2) * (r - y2)) / det;
        const double l2 = 1.0 - l0 - l1;
        if (l0 < -kEps || l1 < -kEps || l2 < -kEps) continue;
        const Vector3f rgb = static_cast<float>(l0) * f.rgb[idx[0]] +
                             static_cast<float>(l1) * f.rgb[idx[1]] +
                             static_cast<float>(l2) * f.rgb[idx[2]];
        out.image.at<cv::Vec3b>(r, c) = ToBgr(rgb);
        covered.at<std::uint8_t>(r, c) = 1;
      }
    }
  }
  out.coverage = static_cast<double>(cv::countNonZero(covered)) / (size * size);
  return out;
}

}  // namespace

std::array<int, 4> FaceCornerIndices(int face) {
  HGRASP_DEMAND(face >= 0 && face < 6);
  const FaceAxes& a = kFaceAxes[face];
  // Texture order: (-u, -v), (+u, -v), (+u, +v), (-u, +v).
  constexpr std::array<std::array<int, 2>, 4> kUv = {{{-1, -1}, {+1, -1}, {+1, +1}, {-1, +1}}};
  std::array<int, 4> out;
  for (int k = 0; k < 4; ++k) {
    std::array<int, 3> sign{};
    sign[a.n.axis] = a.n.sign;
    sign[a.u.axis] = a.u.sign * kUv[k][0];
    sign[a.v.axis] = a.v.sign * kUv[k][1];
    out[k] = (sign[0] > 0 ? 1 : 0) | (sign[1] > 0 ? 2 : 0) | (sign[2] > 0 ? 4 : 0);
  }
  return out;
}

std::array<Vector3d, 4> FaceCorners(const BoxModel& box, int face) {
  const std::array<int, 4> idx = FaceCornerIndices(face);
  return {box.vertices_W[idx[0]], box.vertices_W[idx[1]], box.vertices_W[idx[2]],
          box.vertices_W[idx[3]]};
}

Vector3d FaceNormal(const BoxModel& box, int face) {
  HGRASP_DEMAND(face >= 0 && face < 6);
  return box.X_WO.linear() * Unit(kFaceAxes[face].n);
}

int FaceOfNormal(const BoxModel& box, const Vector3d& n_W) {
  const auto [axis, component] = NearestAxis(box, n_W);
  if (axis < 0) return -1;
  return FaceOf(axis, component > 0);
}

std::vector<FaceTexture> MakeFaceTextures(const BoxModel& box, const segment::SegmentResult& s,
                                          const scan::RangeImage& range, int size,
                                          double max_edge_m) {
  if (size < 2) throw InputError("", "size", std::to_string(size), ">= 2 texels");
  if (!(max_edge_m > 0)) throw InputError("", "max_edge_m", std::to_string(max_edge_m), "> 0 m");
  if (!(box.size_O.minCoeff() > 0)) {
    throw InputError("", "box.size_O", std::to_string(box.size_O.minCoeff()), "edges > 0 m");
  }
  HGRASP_DEMAND(s.rows == range.rows() && s.cols == range.cols());
  HGRASP_DEMAND(static_cast<int>(s.labels.size()) == s.rows * s.cols);

  // The face of each region: the axis its normal lies along, the side its centroid is on.
  std::unordered_map<int, int> face_of_region;
  std::map<int, FaceSamples> faces;  // by face, ascending
  const Pose3 X_OW = box.X_WO.inverse();
  for (int id : box.regions) {
    const auto r = std::find_if(s.regions.begin(), s.regions.end(),
                                [id](const segment::PlaneRegion& p) { return p.id == id; });
    if (r == s.regions.end()) continue;
    const auto [axis, component] = NearestAxis(box, r->normal_W);
    if (axis < 0) continue;
    const int face = FaceOf(axis, (X_OW * r->centroid_W)[axis] >= 0);
    face_of_region[id] = face;
    FaceSamples& f = faces[face];
    if (r->cells > f.region_cells) {
      f.region = id;
      f.region_cells = r->cells;
    }
  }

  for (int row = 0; row < s.rows; ++row) {
    for (int col = 0; col < s.cols; ++col) {
      const int label = s.labels[row * s.cols + col];
      if (label < 0) continue;
      const auto it = face_of_region.find(label);
      if (it == face_of_region.end()) continue;
      const scan::RangeCell& cell = range.at(row, col);
      if (!cell.valid) continue;
      const FaceAxes& a = kFaceAxes[it->second];
      const Vector3d p_O = X_OW * cell.p_W;
      FaceSamples& f = faces[it->second];
      f.p_m.emplace_back(a.u.sign * p_O[a.u.axis] + 0.5 * box.size_O[a.u.axis],
                         a.v.sign * p_O[a.v.axis] + 0.5 * box.size_O[a.v.axis]);
      f.rgb.push_back(cell.rgb);
    }
  }

  std::vector<FaceTexture> out;
  for (const auto& [face, samples] : faces) {
    if (samples.p_m.empty()) continue;
    const FaceAxes& a = kFaceAxes[face];
    const Vector2d extent_m(box.size_O[a.u.axis], box.size_O[a.v.axis]);
    out.push_back(Render(face, samples, extent_m, size, max_edge_m));
  }
  return out;
}

}  // namespace hgrasp::model
