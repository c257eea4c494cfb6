#include "task/box_rise.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "model/colour.h"

namespace hgrasp::task {
namespace {

// The q-quantile of `v` (nearest rank, 0 <= q <= 1); v non-empty, reordered.
double Quantile(std::vector<double>* v, double q) {
  const auto k = static_cast<std::ptrdiff_t>(
      std::lround(std::clamp(q, 0.0, 1.0) * static_cast<double>(v->size() - 1)));
  std::nth_element(v->begin(), v->begin() + k, v->end());
  return (*v)[k];
}

bool Inside(const grasp::OrientedBox& b, const Eigen::Vector3d& p_W) {
  const Eigen::Vector3d p = b.R.transpose() * (p_W - b.centre);
  return (p.cwiseAbs().array() <= 0.5 * b.size.array()).all();
}

}  // namespace

std::vector<grasp::OrientedBox> HandRegion(const Pose3& X_WE, double opening_m,
                                           const grasp::HandGeometry& hand,
                                           const BoxRiseConfig& config) {
  const std::array<grasp::OrientedBox, 3> parts = grasp::HandBoxes(X_WE, opening_m, hand);
  std::vector<grasp::OrientedBox> region(parts.begin(), parts.end());
  // The palm over the wrist: its box grown back along -z of E.
  region[0].centre -= 0.5 * config.wrist_m * X_WE.linear().col(2);
  region[0].size.z() += config.wrist_m;
  for (grasp::OrientedBox& b : region) {
    b.size += Eigen::Vector3d::Constant(2 * config.hand_margin_m);
  }
  return region;
}

std::optional<BoxHeights> MeasureBoxHeights(const scan::RangeImage& range,
                                            const model::BoxModel& box, int colour_index,
                                            double lift_m, const BoxRiseConfig& config,
                                            std::span<const grasp::OrientedBox> not_box) {
  double bottom = std::numeric_limits<double>::infinity();
  double top = -bottom;
  for (const Eigen::Vector3d& v : box.vertices_W) {
    bottom = std::min(bottom, v.z());
    top = std::max(top, v.z());
  }
  const double z_lo = bottom + config.table_clearance_m;
  const double z_hi = top + std::max(lift_m, 0.0) + config.above_m;
  const Eigen::Vector2d half = 0.5 * box.size_O.head<2>() +
                               Eigen::Vector2d::Constant(config.footprint_margin_m);
  const Pose3 X_OW = box.X_WO.inverse();
  const bool counts = static_cast<int>(range.encoder_counts.size()) == range.cols();
  std::vector<double> z;
  int first_col = -1, last_col = -1;
  for (int col = 0; col < range.cols(); ++col) {
    for (int row = 0; row < range.rows(); ++row) {
      const scan::RangeCell& c = range.at(row, col);
      if (!c.valid || c.p_W.z() < z_lo || c.p_W.z() > z_hi) continue;
      // The footprint in O's xy: O's z is vertical (the box fit's top normal).
      const Eigen::Vector3d p_O = X_OW * c.p_W;
      if (std::abs(p_O.x()) > half.x() || std::abs(p_O.y()) > half.y()) continue;
      if (model::ColourIndex(c.rgb) != colour_index) continue;
      if (std::any_of(not_box.begin(), not_box.end(),
                      [&](const grasp::OrientedBox& b) { return Inside(b, c.p_W); })) {
        continue;
      }
      z.push_back(c.p_W.z());
      if (first_col < 0) first_col = col;
      last_col = col;
    }
  }
  if (static_cast<int>(z.size()) < config.min_cells || !counts) return std::nullopt;
  BoxHeights h;
  h.cells = static_cast<int>(z.size());
  h.low_z = Quantile(&z, config.low_quantile);
  h.high_z = Quantile(&z, config.high_quantile);
  h.first_count = range.encoder_counts[first_col];
  h.last_count = range.encoder_counts[last_col];
  return h;
}

std::pair<std::int32_t, std::int32_t> CountsLightingBox(const model::BoxModel& box,
                                                        double lift_m,
                                                        const robot::LaserCalibration& laser,
                                                        const Pose3& X_WH,
                                                        const scan::SweepConfig& look_sweep,
                                                        const BoxRiseConfig& config) {
  const std::int32_t lo = std::min(look_sweep.start_count, look_sweep.end_count);
  const std::int32_t hi = std::max(look_sweep.start_count, look_sweep.end_count);
  const Pose3 X_HW = X_WH.inverse();
  const Eigen::Vector3d half = 0.5 * box.size_O + Eigen::Vector3d(config.footprint_margin_m,
                                                                  config.footprint_margin_m, 0);
  std::int32_t first = hi, last = lo;
  for (const double dz : {-config.below_m, std::max(lift_m, 0.0) + config.above_m}) {
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d c_O((k & 1 ? 1 : -1) * half.x(), (k & 2 ? 1 : -1) * half.y(),
                                (k & 4 ? 1 : -1) * half.z());
      const Eigen::Vector3d p_H = X_HW * (box.X_WO * c_O + Eigen::Vector3d(0, 0, dz));
      // The count where the plane's signed distance to the corner changes sign (the plane
      // turns monotonically over a sweep of less than 180 deg), else the nearer end.
      constexpr std::int32_t kStep = 4;
      std::int32_t at = std::abs(laser.PlaneH(lo).SignedDistance(p_H)) <
                                std::abs(laser.PlaneH(hi).SignedDistance(p_H))
                            ? lo
                            : hi;
      double d0 = laser.PlaneH(lo).SignedDistance(p_H);
      for (std::int32_t e = lo + kStep; e <= hi; e += kStep) {
        const double d1 = laser.PlaneH(e).SignedDistance(p_H);
        if ((d0 <= 0) != (d1 <= 0)) {
          at = std::abs(d0) < std::abs(d1) ? e - kStep : e;
          break;
        }
        d0 = d1;
      }
      first = std::min(first, at);
      last = std::max(last, at);
    }
  }
  return {first, last};
}

scan::SweepConfig RiseSweep(std::int32_t first, std::int32_t last,
                            const scan::SweepConfig& look_sweep, const BoxRiseConfig& config) {
  const std::int32_t dir = look_sweep.end_count < look_sweep.start_count ? -1 : 1;
  const double spacing = std::abs(look_sweep.end_count - look_sweep.start_count) /
                         static_cast<double>(std::max(look_sweep.positions, 1));
  // Within the look's sweep: the laser's range as the scenario set it.
  const std::int32_t lo = std::max(std::min(first, last) - config.sweep_margin_counts,
                                   std::min(look_sweep.start_count, look_sweep.end_count));
  const std::int32_t hi = std::min(std::max(first, last) + config.sweep_margin_counts,
                                   std::max(look_sweep.start_count, look_sweep.end_count));
  scan::SweepConfig s = look_sweep;
  s.start_count = dir < 0 ? hi : lo;
  s.end_count = dir < 0 ? lo : hi;
  s.positions = std::max(2, static_cast<int>(std::lround((hi - lo) / std::max(spacing, 1.0))));
  return s;
}

namespace {

// Whether the segment from a to b (in the box's frame) enters the axis-aligned box |p| <= half
// (slab test).
bool SegmentEntersBox(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                      const Eigen::Vector3d& half) {
  double t0 = 0.0, t1 = 1.0;
  const Eigen::Vector3d d = b - a;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-12) {
      if (std::abs(a[i]) > half[i]) return false;
      continue;
    }
    double ta = (-half[i] - a[i]) / d[i], tb = (half[i] - a[i]) / d[i];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

}  // namespace

BoxRise MeasureRise(const scan::RangeImage& after, const model::BoxModel& box, int colour_index,
                    const Eigen::Vector3d& camera_W, double lift_m, const BoxRiseConfig& config,
                    const BoxHeights* before, std::span<const grasp::OrientedBox> hand) {
  BoxRise r;
  double bottom = std::numeric_limits<double>::infinity();
  double top = -bottom;
  for (const Eigen::Vector3d& v : box.vertices_W) {
    bottom = std::min(bottom, v.z());
    top = std::max(top, v.z());
  }
  const std::optional<BoxHeights> seen = MeasureBoxHeights(after, box, colour_index, lift_m, config, hand);
  if (seen) {
    r.box_cells = seen->cells;
    r.bottom_z = seen->low_z;
    r.top_z = seen->high_z;
  }
  // Every cell and the camera in the box's frame: a rise is a shift along W's z, which is O's
  // z only as far as the fitted top is level, so it is carried into O as it is.
  const Pose3 X_OW = box.X_WO.inverse();
  const Eigen::Vector3d camera_O = X_OW * camera_W;
  const Eigen::Vector3d up_O = X_OW.linear() * Eigen::Vector3d::UnitZ();
  std::vector<Eigen::Vector3d> cells_O;
  for (int col = 0; col < after.cols(); ++col) {
    for (int row = 0; row < after.rows(); ++row) {
      const scan::RangeCell& c = after.at(row, col);
      if (c.valid) cells_O.push_back(X_OW * c.p_W);
    }
  }
  r.cells = static_cast<int>(cells_O.size());
  const Eigen::Vector3d half =
      (0.5 * box.size_O - Eigen::Vector3d::Constant(config.shrink_m)).cwiseMax(0.001);
  const int steps = static_cast<int>(
      std::floor((std::max(lift_m, 0.0) + config.above_m + config.below_m) / config.step_m));
  r.min_m = std::numeric_limits<double>::infinity();
  r.max_m = -r.min_m;
  for (int k = 0; k <= steps; ++k) {
    const double dz = -config.below_m + k * config.step_m;
    ++r.candidates;
    if (seen && (seen->high_z > top + dz + config.cell_tolerance_m ||
                 seen->low_z < bottom + dz - config.cell_tolerance_m)) {
      continue;
    }
    // The highest cells against the same quantile of the look's: the model's errors and the
    // head's cancel, only the two quantiles' noise is left.
    if (seen && before != nullptr && seen->high_z > before->high_z + dz + config.top_tolerance_m) {
      continue;
    }
    // The box raised by dz: the camera and the cells relative to it.
    const Eigen::Vector3d shift = dz * up_O;
    int hidden = 0;
    for (const Eigen::Vector3d& p : cells_O) {
      if (SegmentEntersBox(camera_O - shift, p - shift, half) && ++hidden > config.max_hidden_cells) {
        break;
      }
    }
    if (hidden > config.max_hidden_cells) continue;
    ++r.left;
    r.min_m = std::min(r.min_m, dz);
    r.max_m = std::max(r.max_m, dz);
  }
  if (r.left == 0) r.min_m = 0, r.max_m = -1;
  return r;
}

double RiseShortfall(const BoxRise& rise, double lift_m, double min_rise_m, double tolerance_m,
                     double max_step_m, int min_cells) {
  if (!rise.consistent() || rise.box_cells < min_cells) return 0.0;
  const double short_m =
      std::max(lift_m - 0.5 * (rise.min_m + rise.max_m), min_rise_m - rise.min_m);
  if (short_m <= tolerance_m) return 0.0;
  return std::min(short_m, max_step_m);
}

}  // namespace hgrasp::task
