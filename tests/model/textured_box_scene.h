#pragma once
// A box with coloured range cells on its top and one side, labelled by hand, for the texture and
// OBJ tests.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "common/geometry.h"
#include "model/box_fit.h"
#include "scan/range_image.h"
#include "segment/segment.h"
#include "tests/scan/synthetic_range.h"

namespace hgrasp::model::testing {

/// Box O: centre (0.3, 0.02, 0.05) m, yaw 60 deg, size (0.06, 0.08, 0.10) m, resting on z = 0.
/// Cells on a 5 mm grid reaching the faces' edges:
///  - top (z_O = 0.05): rows 0-12 (x_O = -0.03 + 0.005 row), cols 0-16 (y_O = -0.04 + 0.005 col);
///    y_O > 0.02 blue (region 4), else x_O < 0 red, else green (region 3);
///  - side y_O = -0.04 (face 3): rows 14-34 (z_O = 0.05 - 0.005 (row - 14)), cols 0-12 (x_O =
///    -0.03 + 0.005 col); z_O < -0.025 white, else x_O < 0 blue, else yellow (region 7, normal
///    into the box as the segmenter's orientation rule gives it); a hole of 3 x 3 invalid cells
///    at x_O 0.01-0.02, z_O 0.015-0.025;
///  - table: row 35, 18 cells at z = 0 away from the box (region 9, not the box's).
/// box.regions = {3, 4, 7, 42} (42 is no region).
struct TexturedBoxScene {
  static constexpr double kStep = 0.005;
  static inline const Eigen::Vector3f kRed = Eigen::Vector3f(200, 30, 30) / 255;
  static inline const Eigen::Vector3f kGreen = Eigen::Vector3f(30, 180, 50) / 255;
  static inline const Eigen::Vector3f kBlue = Eigen::Vector3f(40, 70, 200) / 255;
  static inline const Eigen::Vector3f kYellow = Eigen::Vector3f(220, 200, 20) / 255;
  static inline const Eigen::Vector3f kWhite = Eigen::Vector3f(210, 210, 200) / 255;

  BoxModel box;
  scan::RangeImage range{36, 18};
  segment::SegmentResult segments;

  TexturedBoxScene() {
    box.X_WO = Pose3::Identity();
    box.X_WO.linear() = RotZ(DegToRad(60));
    box.X_WO.translation() = Eigen::Vector3d(0.3, 0.02, 0.05);
    box.size_O = Eigen::Vector3d(0.06, 0.08, 0.10);
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d corner_O(((k & 1) ? 0.5 : -0.5) * box.size_O.x(),
                                     ((k & 2) ? 0.5 : -0.5) * box.size_O.y(),
                                     ((k & 4) ? 0.5 : -0.5) * box.size_O.z());
      box.vertices_W[k] = box.X_WO * corner_O;
    }
    box.regions = {3, 4, 7, 42};

    segments.rows = range.rows();
    segments.cols = range.cols();
    segments.labels.assign(segments.rows * segments.cols, -1);
    scan::testing::FillBlock(&range, 0, 13, 0, 17, box.X_WO * Eigen::Vector3d(-0.03, -0.04, 0.05),
                             R() * Eigen::Vector3d(kStep, 0, 0),
                             R() * Eigen::Vector3d(0, kStep, 0));
    scan::testing::FillBlock(&range, 14, 21, 0, 13, box.X_WO * Eigen::Vector3d(-0.03, -0.04, 0.05),
                             R() * Eigen::Vector3d(0, 0, -kStep),
                             R() * Eigen::Vector3d(kStep, 0, 0));
    scan::testing::FillBlock(&range, 35, 1, 0, 18, Eigen::Vector3d(0.5, 0.3, 0),
                             Eigen::Vector3d::Zero(), Eigen::Vector3d(kStep, 0, 0));
    for (int r = 0; r < range.rows(); ++r) {
      for (int c = 0; c < range.cols(); ++c) {
        scan::RangeCell& cell = range.at(r, c);
        if (!cell.valid) continue;
        int label = 9;
        if (r < 13) {
          cell.rgb = TopColour(r, c);
          label = cell.rgb == kBlue ? 4 : 3;
        } else if (r < 35) {
          if (InHole(c, r - 14)) {
            cell.valid = false;
            continue;
          }
          cell.rgb = SideColour(c, r - 14);
          label = 7;
        } else {
          cell.rgb = kWhite;
        }
        segments.labels[r * range.cols() + c] = label;
      }
    }
    const Eigen::Vector3d outward_side = R() * Eigen::Vector3d(0, -1, 0);
    // The segmenter's rule for vertical planes: n.x <= 0. Here that is into the box.
    const Eigen::Vector3d n_side = outward_side.x() > 0 ? -outward_side : outward_side;
    for (const auto& [id, n] : {std::pair{3, Eigen::Vector3d::UnitZ().eval()},
                                std::pair{4, Eigen::Vector3d::UnitZ().eval()}, std::pair{7, n_side},
                                std::pair{9, Eigen::Vector3d::UnitZ().eval()}}) {
      segment::PlaneRegion region;
      region.id = id;
      region.normal_W = n;
      for (int i = 0; i < segments.rows * segments.cols; ++i) {
        if (segments.labels[i] != id) continue;
        region.centroid_W += range.at(i / segments.cols, i % segments.cols).p_W;
        ++region.cells;
      }
      region.centroid_W /= region.cells;
      segments.regions.push_back(region);
    }
  }

  Eigen::Matrix3d R() const { return box.X_WO.linear(); }

  /// Colour of top cell (row i along x_O, col j along y_O).
  static Eigen::Vector3f TopColour(int i, int j) {
    if (j > 12) return kBlue;  // y_O > 0.02
    return i < 6 ? kRed : kGreen;
  }
  /// Colour of side cell (col i along x_O, row k down z_O).
  static Eigen::Vector3f SideColour(int i, int k) {
    if (k > 15) return kWhite;  // z_O < -0.025
    return i < 6 ? kBlue : kYellow;
  }
  static bool InHole(int i, int k) { return i >= 8 && i <= 10 && k >= 5 && k <= 7; }

  /// Per-channel median of the side's valid cells (an even count averages the middle two).
  Eigen::Vector3f SideMedian() const {
    std::vector<float> ch[3];
    for (int k = 0; k < 21; ++k) {
      for (int i = 0; i < 13; ++i) {
        if (InHole(i, k)) continue;
        for (int a = 0; a < 3; ++a) ch[a].push_back(SideColour(i, k)[a]);
      }
    }
    Eigen::Vector3f out;
    for (int a = 0; a < 3; ++a) {
      std::sort(ch[a].begin(), ch[a].end());
      const size_t n = ch[a].size();
      out[a] = n % 2 ? ch[a][n / 2] : 0.5f * (ch[a][n / 2 - 1] + ch[a][n / 2]);
    }
    return out;
  }

  /// The colour at p_W on face `face` (4 top, 3 side) when the four grid cells around it have one
  /// colour and are all valid; nullopt otherwise or on another face.
  std::optional<Eigen::Vector3f> UniformColourAround(int face, const Eigen::Vector3d& p_W) const {
    const Eigen::Vector3d p_O = box.X_WO.inverse() * p_W;
    double a, b;
    int na, nb;
    if (face == 4) {
      a = (p_O.x() + 0.03) / kStep, b = (p_O.y() + 0.04) / kStep, na = 13, nb = 17;
    } else if (face == 3) {
      a = (p_O.x() + 0.03) / kStep, b = (0.05 - p_O.z()) / kStep, na = 13, nb = 21;
    } else {
      return std::nullopt;
    }
    const int i0 = std::clamp(static_cast<int>(std::floor(a + 1e-9)), 0, na - 2);
    const int j0 = std::clamp(static_cast<int>(std::floor(b + 1e-9)), 0, nb - 2);
    std::optional<Eigen::Vector3f> colour;
    for (int i = i0; i <= i0 + 1; ++i) {
      for (int j = j0; j <= j0 + 1; ++j) {
        if (face == 3 && InHole(i, j)) return std::nullopt;
        const Eigen::Vector3f c = face == 4 ? TopColour(i, j) : SideColour(i, j);
        if (colour && *colour != c) return std::nullopt;
        colour = c;
      }
    }
    return colour;
  }
};

}  // namespace hgrasp::model::testing
