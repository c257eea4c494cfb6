// The planar segmentation of real (simulated) scans against the simulator's label images, with
// Hoover et al.'s counts (correct, over-, under-segmented, missed): of the visible faces larger
// than 15 cm^2, at least 95% must be segmented correctly (issue 4's acceptance), over the default
// scenario and seeded random scenes.

#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <vector>

#include "common/paths.h"
#include "robot/calibration.h"
#include "robot/head_kinematics.h"
#include "scan/scanner.h"
#include "segment/segment.h"
#include "sim/hoover.h"
#include "sim/random_scene.h"
#include "sim/sim_devices.h"
#include "sim/truth.h"
#include "tests/scan/sim_scan.h"

namespace hgrasp::segment {
namespace {

constexpr double kMinFaceAreaM2 = 15e-4;  // 15 cm^2
constexpr int kMinVisibleCells = 50;      // a face with fewer scanned points is not "visible"

struct Tally {
  int faces = 0, correct = 0, over = 0, under = 0, missed = 0;
};

// Scans `scenario`, segments the scan and tallies Hoover's kinds over the large visible faces.
Tally SegmentAgainstTruth(const sim::Scenario& scenario) {
  sim::SimRobot robot(scenario);
  const scan::RangeImage range = scan::testing::ScanInSim(&robot);
  const SegmentResult s = SegmentPlanes(range);

  std::vector<Eigen::Vector3d> points;
  std::vector<int> machine;
  for (int r = 0; r < range.rows(); ++r) {
    for (int c = 0; c < range.cols(); ++c) {
      if (!range.at(r, c).valid) continue;
      points.push_back(range.at(r, c).p_W);
      machine.push_back(s.labels[r * range.cols() + c]);
    }
  }
  // The head has not moved since the scan: the label images are those the scan was taken with.
  const std::vector<int> truth =
      sim::TrueFaceLabels(robot.world(), &robot.rig(), sim::kLeft, points);
  const sim::HooverCounts h = sim::CompareSegmentations(truth, machine, kMinVisibleCells);

  Tally t;
  for (const auto& e : h.entries) {
    double area = 1.0;  // the table and the wall are large
    if (e.truth_code >= 2) {
      const int object = (e.truth_code - 2) / 6, face = (e.truth_code - 2) % 6;
      const Eigen::Vector3d& size = scenario.objects[object].size_O;
      const int axis = face / 2;
      area = size[(axis + 1) % 3] * size[(axis + 2) % 3];
    }
    if (area < kMinFaceAreaM2) continue;
    ++t.faces;
    t.correct += e.kind == "correct";
    t.over += e.kind == "over";
    t.under += e.kind == "under";
    t.missed += e.kind == "missed";
    if (e.kind != "correct") {
      // Where its cells went: the machine region holding most of them, and none.
      std::map<int, int> where;
      for (size_t i = 0; i < truth.size(); ++i) {
        if (truth[i] == e.truth_code) ++where[machine[i]];
      }
      int best = -1, best_n = 0;
      for (const auto& [label, n] : where) {
        if (label >= 0 && n > best_n) best = label, best_n = n;
      }
      int region_size = 0;
      std::map<int, int> made_of;  // the region's cells by truth code
      for (size_t i = 0; i < machine.size(); ++i) {
        if (machine[i] == best && best >= 0) ++region_size, ++made_of[truth[i]];
      }
      for (const auto& [code, n] : made_of)
        std::printf("    region %d: %d cells of truth %d\n", best, n, code);
      std::printf("  %s: truth %d (%d cells) %s: %d in region %d (of %d cells), %d in none\n",
                  scenario.name.c_str(), e.truth_code, e.cells, e.kind.c_str(), best_n, best,
                  region_size, where.count(-1) ? where[-1] : 0);
    }
  }
  return t;
}

TEST(SegmentAgainstTruth, LargeVisibleFacesAreSegmentedCorrectly) {
  std::vector<sim::Scenario> scenarios = {
      sim::LoadScenario(ResolveDataPath("scenarios/default.yaml"))};
  for (int seed = 1; seed <= 20; ++seed) scenarios.push_back(sim::RandomBoxScene(seed));
  Tally all;
  for (const sim::Scenario& scenario : scenarios) {
    const Tally t = SegmentAgainstTruth(scenario);
    std::printf("%-12s faces %2d: correct %2d, over %d, under %d, missed %d\n",
                scenario.name.c_str(), t.faces, t.correct, t.over, t.under, t.missed);
    all.faces += t.faces, all.correct += t.correct, all.over += t.over;
    all.under += t.under, all.missed += t.missed;
  }
  std::printf(
      "all: %d faces > 15 cm^2 visible; correct %d (%.1f%%), over %d, under %d, missed %d\n",
      all.faces, all.correct, 100.0 * all.correct / std::max(all.faces, 1), all.over, all.under,
      all.missed);
  ASSERT_GT(all.faces, 20);
  EXPECT_GE(all.correct, 0.95 * all.faces);
}

}  // namespace
}  // namespace hgrasp::segment
