// The box's rise by the cameras (task/box_rise.h), on range images built by hand: a box's front
// face and top as the stripe lights them, the table around it, the box raised, tipped or gone.
#include "task/box_rise.h"

#include <gtest/gtest.h>

#include "model/colour.h"

namespace hgrasp::task {
namespace {

constexpr int kRed = 0, kWhite = 7;

// A 40 x 60 x 100 mm box standing on the table (z = 0) at (0.30, 0, 0.05).
model::BoxModel StandingBox() {
  model::BoxModel b;
  b.X_WO = Pose3::Identity();
  b.X_WO.translation() = Eigen::Vector3d(0.30, 0.0, 0.05);
  b.size_O = Eigen::Vector3d(0.04, 0.06, 0.10);
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d s((k & 1) ? 0.5 : -0.5, (k & 2) ? 0.5 : -0.5, (k & 4) ? 0.5 : -0.5);
    b.vertices_W[k] = b.X_WO * s.cwiseProduct(b.size_O);
  }
  return b;
}

Eigen::Vector3f Seen(int colour) {
  const auto& p = model::kColourPrototypes[colour];
  return 0.7f * Eigen::Vector3f(p[0], p[1], p[2]);
}

// What a camera at kCamera sees of the box raised by `dz` (or of the table alone): the box's
// front face (x = 0.28) and top, and the table (z = 0) from x 0.15 to 0.55 wherever the box does
// not hide it; one cell per point, on a 5 mm grid, one column per grid line in y (encoder count
// 1000 - 10 col). `box_cells`: the box's own cells are in (they may be hidden behind an arm).
const Eigen::Vector3d kCamera(0.0, 0.0, 0.5);

bool Hides(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3d& p) {
  // Whether the segment from the camera to p crosses the box [lo, hi] (sampled finely).
  for (int i = 1; i < 2000; ++i) {
    const Eigen::Vector3d q = kCamera + (p - kCamera) * (i / 2000.0);
    if ((q.array() > lo.array()).all() && (q.array() < hi.array()).all()) return true;
  }
  return false;
}

scan::RangeImage Scene(double dz, bool box = true, bool box_cells = true) {
  const Eigen::Vector3d lo(0.28, -0.03, dz), hi(0.32, 0.03, dz + 0.1);
  std::vector<std::vector<std::pair<Eigen::Vector3d, int>>> columns;
  for (int j = 0; j <= 40; ++j) {
    const double y = -0.1 + 0.005 * j;
    std::vector<std::pair<Eigen::Vector3d, int>> col;
    const bool in_y = std::abs(y) <= 0.03 + 1e-9;
    if (box && box_cells && in_y) {
      for (int i = 0; i <= 40; ++i) col.push_back({{0.28, y, dz + 0.0025 * i}, kRed});
      for (int i = 1; i <= 8; ++i) col.push_back({{0.28 + 0.005 * i, y, dz + 0.1}, kRed});
    }
    for (int i = 0; i <= 80; ++i) {
      const Eigen::Vector3d p(0.15 + 0.005 * i, y, 0.0);
      if (box && in_y && p.x() >= 0.28 && p.x() <= 0.32 && dz < 0.001) continue;  // under it
      if (box && Hides(lo, hi, p)) continue;
      col.push_back({p, kWhite});
    }
    columns.push_back(col);
  }
  std::size_t rows = 0;
  for (const auto& c : columns) rows = std::max(rows, c.size());
  scan::RangeImage r(static_cast<int>(rows), static_cast<int>(columns.size()));
  for (std::size_t j = 0; j < columns.size(); ++j) {
    r.encoder_counts.push_back(1000 - 10 * static_cast<int>(j));
    for (std::size_t i = 0; i < columns[j].size(); ++i) {
      scan::RangeCell& c = r.at(static_cast<int>(i), static_cast<int>(j));
      c.valid = true;
      c.p_W = c.p_C = columns[j][i].first;
      c.rgb = Seen(columns[j][i].second);
    }
  }
  return r;
}

// The box's true rise lies inside what the cameras leave possible.
void ExpectInside(const BoxRise& r, double dz) {
  ASSERT_TRUE(r.consistent());
  EXPECT_LE(r.min_m, dz + 1e-9);
  EXPECT_GE(r.max_m, dz - 1e-9);
}

TEST(BoxRise, TheLooksCellsOfTheBoxAndTheirStripePositions) {
  const auto h = MeasureBoxHeights(Scene(0.0), StandingBox(), kRed, 0.0);
  ASSERT_TRUE(h);
  // 13 columns on the box (|y| <= 30 mm), 49 cells each, less the front face's two under the
  // table clearance (z = 0 and 2.5 mm).
  EXPECT_EQ(h->cells, 13 * 47);
  EXPECT_EQ(h->first_count, 1000 - 10 * 14);
  EXPECT_EQ(h->last_count, 1000 - 10 * 26);
  EXPECT_NEAR(h->high_z, 0.1, 1e-9);
  // The box's colour elsewhere is not the box; too few cells are none.
  scan::RangeImage away = Scene(0.0);
  for (int row = 0; row < away.rows(); ++row)
    for (int col = 0; col < away.cols(); ++col) away.at(row, col).p_W.x() += 0.1;
  EXPECT_FALSE(MeasureBoxHeights(away, StandingBox(), kRed, 0.0));
  BoxRiseConfig strict;
  strict.min_cells = 13 * 47 + 1;
  EXPECT_FALSE(MeasureBoxHeights(Scene(0.0), StandingBox(), kRed, 0.0, strict));
}

TEST(BoxRise, ABoxRaisedBy50mmIsKnownRisenAtLeast45mm) {
  const BoxRise r = MeasureRise(Scene(0.05), StandingBox(), kRed, kCamera, 0.05);
  ExpectInside(r, 0.05);
  EXPECT_GE(r.min_m, 0.045);
  EXPECT_LE(r.max_m, 0.055);
  EXPECT_EQ(r.box_cells, 13 * 49);
}

TEST(BoxRise, TheLooksTopBoundsTheRiseWhereTheModelsTopIsOffByMillimetres) {
  // The model 4 mm taller than the box (a fit within the sweep's tolerance): against the model's
  // top alone a box raised 48 mm could have risen 40 mm (48 - 4 - 4 mm of tolerance). Against the
  // look's own highest cells, raised by the rise, it rose at least 45 mm (48 - 3 mm).
  model::BoxModel tall = StandingBox();
  tall.size_O.z() += 0.004;
  tall.X_WO.translation().z() += 0.002;
  for (int k = 0; k < 8; ++k) tall.vertices_W[k].z() = (k & 4) ? 0.104 : 0.0;
  const auto before = MeasureBoxHeights(Scene(0.0), tall, kRed, 0.0);
  ASSERT_TRUE(before);
  const BoxRise model_only = MeasureRise(Scene(0.048), tall, kRed, kCamera, 0.05);
  ExpectInside(model_only, 0.048);
  EXPECT_LT(model_only.min_m, 0.045);
  const BoxRise r = MeasureRise(Scene(0.048), tall, kRed, kCamera, 0.05, {}, &*before);
  ExpectInside(r, 0.048);
  EXPECT_NEAR(r.min_m, 0.045, 1e-9);
}

TEST(BoxRise, ABoxThatStayedOrSlidDownTheFingersIsKnownShort) {
  for (double dz : {0.0, 0.017}) {
    const BoxRise r = MeasureRise(Scene(dz), StandingBox(), kRed, kCamera, 0.05);
    ExpectInside(r, dz);
    EXPECT_LT(r.max_m, 0.045) << dz;
  }
}

// The box raised by `box_dz` and, seen beside it, a patch of cells of the box's colour on the
// underside of a palm 10 mm over where the gripper put the top (it rose 50 mm): the hand's
// skin of an orange box, its pads of a black one. TopGrasp's palm spans z 0.16-0.20.
scan::RangeImage SceneWithPalm(double box_dz) {
  scan::RangeImage r = Scene(box_dz);
  scan::RangeImage out(r.rows() + 5, r.cols());
  out.encoder_counts = r.encoder_counts;
  for (int col = 0; col < r.cols(); ++col) {
    for (int row = 0; row < r.rows(); ++row) out.at(row, col) = r.at(row, col);
    const double y = -0.1 + 0.005 * col;
    if (std::abs(y) > 0.02 + 1e-9) continue;
    for (int i = 0; i < 5; ++i) {
      scan::RangeCell& c = out.at(r.rows() + i, col);
      c.valid = true;
      c.p_W = c.p_C = Eigen::Vector3d(0.29 + 0.005 * i, y, 0.161);
      c.rgb = Seen(kRed);
    }
  }
  return out;
}

// A grasp from above of StandingBox raised 50 mm, the fingers 60 mm apart: E's z points down,
// its origin 0.2 m up; the palm spans W z 0.16-0.20 (E z 0-0.04), the pads z 0.06-0.16 at
// x 0.30 -+ 0.036.
Pose3 TopGrasp() {
  Pose3 X_WE = Pose3::Identity();
  X_WE.linear() = Eigen::Vector3d(1, -1, -1).asDiagonal();
  X_WE.translation() = Eigen::Vector3d(0.3, 0.0, 0.2);
  return X_WE;
}

TEST(BoxRise, TheHandsCellsOfTheBoxsColourAreNotTheBoxs) {
  const std::vector<grasp::OrientedBox> hand = HandRegion(TopGrasp(), 0.06);
  for (double dz : {0.05, 0.017}) {
    // Counted as the box's, the skin reads as its top 61 mm over the model's: every rise under
    // 57 mm is ruled out, the true one with them.
    const BoxRise counted = MeasureRise(SceneWithPalm(dz), StandingBox(), kRed, kCamera, 0.05);
    EXPECT_FALSE(counted.consistent() && counted.min_m <= dz + 1e-9) << dz;
    const BoxRise r =
        MeasureRise(SceneWithPalm(dz), StandingBox(), kRed, kCamera, 0.05, {}, nullptr, hand);
    ExpectInside(r, dz);
    EXPECT_EQ(r.box_cells, 13 * 49) << dz;
    if (dz < 0.045) {
      EXPECT_LT(r.max_m, 0.045);
    }
    if (dz > 0.045) {
      EXPECT_GE(r.min_m, 0.045);
    }
  }
}

TEST(BoxRise, TheHandRegionIsTheHandsBoxesGrownAndThePalmCarriedOverTheWrist) {
  BoxRiseConfig config;
  const std::vector<grasp::OrientedBox> region = HandRegion(TopGrasp(), 0.06, {}, config);
  ASSERT_EQ(region.size(), 3u);
  // The palm, E z 0-0.04, carried back 0.08 m: W z 0.16-0.28, grown 8 mm.
  EXPECT_NEAR(region[0].centre.z(), 0.22, 1e-12);
  EXPECT_NEAR(region[0].size.z(), 0.12 + 0.016, 1e-12);
  EXPECT_NEAR(region[0].size.x(), 0.12 + 0.016, 1e-12);
  // The pads at x = -+(0.03 + 0.006), E z 0.04-0.14: W z 0.06-0.16.
  EXPECT_NEAR(region[1].centre.x(), 0.3 - 0.036, 1e-12);
  EXPECT_NEAR(region[2].centre.x(), 0.3 + 0.036, 1e-12);
  EXPECT_NEAR(region[1].centre.z(), 0.11, 1e-12);
  EXPECT_NEAR(region[1].size.y(), 0.02 + 0.016, 1e-12);
}

TEST(BoxRise, AHiddenBoxIsKnownRisenOnlyPartlyByTheEmptySpaceUnderTheHand) {
  // The arm hides the box itself; the table behind where a slipped box would hang is seen.
  // That rules out the low rises, but not all of those under 45 mm: the camera looks down at
  // 45-60 deg, so a box 100 mm tall raised 33 mm hides almost the same table as one raised
  // 50 mm (the shadows differ by a strip 17 mm x tan(30-45 deg) wide, 6 mm of it inside the
  // box's shrink). The free space alone cannot call this box lifted: the task must see it.
  const BoxRise r = MeasureRise(Scene(0.05, true, false), StandingBox(), kRed, kCamera, 0.05);
  EXPECT_EQ(r.box_cells, 0);
  ExpectInside(r, 0.05);
  EXPECT_GT(r.min_m, 0.02);
  EXPECT_LT(r.min_m, 0.045);
  // Hidden and still on the table: nothing rules a low rise out.
  const BoxRise low = MeasureRise(Scene(0.0, true, false), StandingBox(), kRed, kCamera, 0.05);
  ExpectInside(low, 0.0);
  EXPECT_LT(low.min_m, 0.045);
}

TEST(BoxRise, NothingSeenLeavesEveryRise) {
  const BoxRise r = MeasureRise(scan::RangeImage(0, 0), StandingBox(), kRed, kCamera, 0.05);
  EXPECT_EQ(r.left, r.candidates);
  EXPECT_NEAR(r.min_m, -0.01, 1e-9);
  EXPECT_NEAR(r.max_m, 0.07, 1e-9);
}

TEST(BoxRise, ABoxSeenWhereNoRaisedBoxFitsIsInconsistent) {
  // Its cells 10 cm to the side of the modelled box, inside the grown footprint's reach? No:
  // pulled 3 cm aside, its front face stands inside where the model's box would be at any rise.
  scan::RangeImage aside = Scene(0.05);
  for (int row = 0; row < aside.rows(); ++row) {
    for (int col = 0; col < aside.cols(); ++col) {
      scan::RangeCell& c = aside.at(row, col);
      if (c.valid && c.rgb == Seen(kRed)) c.p_W.x() += 0.02;
    }
  }
  const BoxRise r = MeasureRise(aside, StandingBox(), kRed, kCamera, 0.05);
  EXPECT_FALSE(r.consistent());
}

// The raise for a box seen short, worked by hand: lift 50 mm, least rise 45 mm, tolerance 2 mm,
// servo step 20 mm, 30 cells needed.
TEST(BoxRise, ABoxSeenShortOrTooVaguelyIsRaisedByWhatItLacks) {
  auto rise = [](double min_mm, double max_mm, int cells) {
    BoxRise r;
    r.min_m = 1e-3 * min_mm;
    r.max_m = 1e-3 * max_mm;
    r.left = r.min_m <= r.max_m ? 1 : 0;
    r.box_cells = cells;
    return r;
  };
  auto shortfall = [](const BoxRise& r) {
    return 1e3 * RiseShortfall(r, 0.05, 0.045, 0.002, 0.02, 30);
  };
  EXPECT_NEAR(shortfall(rise(48, 52, 100)), 0.0, 1e-9);  // middle 50: up
  EXPECT_NEAR(shortfall(rise(46, 51, 100)), 0.0, 1e-9);  // middle 48.5: within 2 mm
  EXPECT_NEAR(shortfall(rise(40, 44, 100)), 8.0, 1e-9);  // middle 42: 8 mm short
  // The middle near the lift but the low end under 45 mm (the twin's 44 mm box was seen so):
  // raised by what the low end lacks.
  EXPECT_NEAR(shortfall(rise(41, 57, 100)), 4.0, 1e-9);
  EXPECT_NEAR(shortfall(rise(0, 40, 100)), 20.0, 1e-9);  // 30 mm short: one servo step
  EXPECT_NEAR(shortfall(rise(40, 44, 29)), 0.0, 1e-9);   // too few of its cells seen
  EXPECT_NEAR(shortfall(rise(44, 40, 100)), 0.0, 1e-9);  // inconsistent: it tipped or moved
}

TEST(BoxRise, TheRiseScanCoversTheCountsGivenAtTheLooksSpacingInsideTheLooksSweep) {
  scan::SweepConfig sweep;  // 2400 to -2400 in 300 positions: 16 counts apart
  BoxRiseConfig config;
  config.sweep_margin_counts = 120;
  scan::SweepConfig s = RiseSweep(860, 740, sweep, config);
  EXPECT_EQ(s.start_count, 980);
  EXPECT_EQ(s.end_count, 620);
  EXPECT_EQ(s.positions, 23);  // 360 counts / 16 counts
  // Near the sweep's end it stops there; the other way round it runs the other way.
  s = RiseSweep(2350, 2200, sweep, config);
  EXPECT_EQ(s.start_count, 2400);
  EXPECT_EQ(s.end_count, 2080);
  std::swap(sweep.start_count, sweep.end_count);
  s = RiseSweep(2200, 2350, sweep, config);
  EXPECT_EQ(s.start_count, 2080);
  EXPECT_EQ(s.end_count, 2400);
}

TEST(BoxRise, TheCountsThatLightTheBoxAreWhereThePlanePassesItsRaisedCorners) {
  // A vertical plane turning about H's z axis through the origin, its normal H's y at count 0
  // and 0.01 deg a count: at count e it contains the points at azimuth 0.01 e deg. H is W.
  robot::LaserCalibration laser;
  laser.axis_H = Eigen::Vector3d::UnitZ();
  laser.point_H = Eigen::Vector3d::Zero();
  laser.normal0_H = Eigen::Vector3d::UnitY();
  laser.offset_m = 0;
  laser.rad_per_count = DegToRad(0.01);
  // A box 0.1 x 0.2 x 0.1 at x = 1, y = 0: its footprint grown by 15 mm spans azimuths
  // atan(0.115 / 0.935) = 7.01 deg either side. Vertical corners share their azimuth, so the
  // rise does not matter for this plane.
  model::BoxModel box;
  box.X_WO = Pose3::Identity();
  box.X_WO.translation() = Eigen::Vector3d(1.0, 0.0, 0.05);
  box.size_O = Eigen::Vector3d(0.1, 0.2, 0.1);
  scan::SweepConfig sweep;  // -2400 to 2400 counts
  const auto [first, last] =
      CountsLightingBox(box, 0.05, laser, Pose3::Identity(), sweep, BoxRiseConfig{});
  const double expected = RadToDeg(std::atan(0.115 / 0.935)) / 0.01;  // 701 counts
  EXPECT_NEAR(first, -expected, 4);
  EXPECT_NEAR(last, expected, 4);
  // A box beyond the sweep's end is lit at its nearer end only.
  box.X_WO.translation() = Eigen::Vector3d(0.7071, 0.7071, 0.05);  // azimuths 42-48 deg
  const auto [f2, l2] =
      CountsLightingBox(box, 0.05, laser, Pose3::Identity(), sweep, BoxRiseConfig{});
  EXPECT_EQ(f2, 2400);
  EXPECT_EQ(l2, 2400);
}

}  // namespace
}  // namespace hgrasp::task
