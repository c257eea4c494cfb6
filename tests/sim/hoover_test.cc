// Hoover et al. (1996) segmentation comparison on small hand-made label vectors: one case per
// category, the tolerance boundary, the precedence between categories, small truth regions and
// unlabelled cells.

#include "sim/hoover.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace hgrasp::sim {
namespace {

// `n` copies of `label` appended to `v`.
void Add(std::vector<int>* v, int n, int label) { v->insert(v->end(), n, label); }

// Truth and machine labels built run by run: `n` cells labelled t in truth and m in machine.
struct Cells {
  std::vector<int> truth, machine;
  Cells& Run(int n, int t, int m) {
    Add(&truth, n, t);
    Add(&machine, n, m);
    return *this;
  }
};

std::string KindOf(const HooverCounts& c, int truth_code) {
  for (const HooverCounts::Entry& e : c.entries) {
    if (e.truth_code == truth_code) return e.kind;
  }
  return "absent";
}

TEST(HooverTest, IdenticalSegmentationsAreAllCorrect) {
  Cells c;
  c.Run(10, 0, 7).Run(20, 1, 3).Run(5, 4, 9);
  const HooverCounts h = CompareSegmentations(c.truth, c.machine);
  EXPECT_EQ(h.truth_regions, 3);
  EXPECT_EQ(h.correct, 3);
  EXPECT_EQ(h.over + h.under + h.missed + h.noise, 0);
  ASSERT_EQ(h.entries.size(), 3u);
  EXPECT_EQ(h.entries[0].truth_code, 0);
  EXPECT_EQ(h.entries[0].cells, 10);
  EXPECT_EQ(h.entries[2].truth_code, 4);
  EXPECT_EQ(h.entries[2].cells, 5);
  for (const auto& e : h.entries) EXPECT_EQ(e.kind, "correct");
}

TEST(HooverTest, OverSegmentation) {
  // Truth 0 (12 cells) split into machine 1 (6) and 2 (6): each O = |M|, sum 12 >= 0.8 * 12.
  Cells c;
  c.Run(6, 0, 1).Run(6, 0, 2).Run(8, 5, 3);
  const HooverCounts h = CompareSegmentations(c.truth, c.machine);
  EXPECT_EQ(h.over, 1);
  EXPECT_EQ(h.correct, 1);  // truth 5
  EXPECT_EQ(h.under + h.missed + h.noise, 0);
  EXPECT_EQ(KindOf(h, 0), "over");
  EXPECT_EQ(KindOf(h, 5), "correct");
}

TEST(HooverTest, UnderSegmentation) {
  // Truth 0 (5) and 1 (5) merged into machine 4 (10).
  Cells c;
  c.Run(5, 0, 4).Run(5, 1, 4);
  const HooverCounts h = CompareSegmentations(c.truth, c.machine);
  EXPECT_EQ(h.truth_regions, 2);
  EXPECT_EQ(h.under, 1);  // one instance
  EXPECT_EQ(h.correct + h.over + h.missed + h.noise, 0);
  EXPECT_EQ(KindOf(h, 0), "under");
  EXPECT_EQ(KindOf(h, 1), "under");
}

TEST(HooverTest, MissedAndNoise) {
  // Truth 0 (10) scattered over three machine regions that each mostly hold truth 1 (30): no
  // instance holds it. Machine 8 lies on cells of no truth region: noise.
  Cells c;
  c.Run(4, 0, 1).Run(3, 0, 2).Run(3, 0, 3);
  c.Run(10, 1, 1).Run(10, 1, 2).Run(10, 1, 3);
  c.Run(6, -1, 8);
  const HooverCounts h = CompareSegmentations(c.truth, c.machine);
  EXPECT_EQ(KindOf(h, 0), "missed");
  // Nor is truth 1 over-segmented: its share of each machine region, 10/14, 10/13, 10/13, is
  // below 0.8.
  EXPECT_EQ(KindOf(h, 1), "missed");
  EXPECT_EQ(h.missed, 2);
  EXPECT_EQ(h.noise, 4);  // machine 1, 2, 3 and 8
}

TEST(HooverTest, UnlabelledMachineCellsCountAgainstTheTruthRegion) {
  // Machine 1 holds 7 of truth 0's 10 cells, the other 3 unlabelled: 7 < 0.8 * 10.
  Cells c;
  c.Run(7, 0, 1).Run(3, 0, -1);
  HooverCounts h = CompareSegmentations(c.truth, c.machine);
  EXPECT_EQ(KindOf(h, 0), "missed");
  EXPECT_EQ(h.noise, 1);
  // At T = 0.7 it is a correct detection.
  h = CompareSegmentations(c.truth, c.machine, 0, 0.7);
  EXPECT_EQ(KindOf(h, 0), "correct");
  EXPECT_EQ(h.noise, 0);
}

TEST(HooverTest, UnlabelledTruthCellsCountInTheMachineRegion) {
  // Machine 1: 8 cells of truth 0 and 2 cells on no true surface: |M| = 10, O = 8.
  Cells c;
  c.Run(8, 0, 1).Run(2, -1, 1);
  EXPECT_EQ(KindOf(CompareSegmentations(c.truth, c.machine, 0, 0.8), 0), "correct");
  c.Run(1, -1, 1);  // |M| = 11: 8 < 0.8 * 11
  EXPECT_EQ(KindOf(CompareSegmentations(c.truth, c.machine, 0, 0.8), 0), "missed");
}

TEST(HooverTest, ToleranceBoundaryIsInclusive) {
  // O = 8 of |G| = 10 and |M| = 10: correct at T = 0.8 exactly, not above.
  Cells c;
  c.Run(8, 0, 1).Run(2, 0, 2).Run(2, 3, 1).Run(20, 3, 4);
  HooverCounts h = CompareSegmentations(c.truth, c.machine, 0, 0.8);
  EXPECT_EQ(KindOf(h, 0), "correct");
  h = CompareSegmentations(c.truth, c.machine, 0, 0.8000001);
  EXPECT_EQ(KindOf(h, 0), "missed");
  // Over-segmentation at its boundary: parts 4 + 4 of 10 cells (2 left unlabelled) with each
  // part wholly inside: sum 8 >= 0.8 * 10, not >= 0.81 * 10.
  Cells o;
  o.Run(4, 0, 1).Run(4, 0, 2).Run(2, 0, -1);
  EXPECT_EQ(KindOf(CompareSegmentations(o.truth, o.machine, 0, 0.8), 0), "over");
  EXPECT_EQ(KindOf(CompareSegmentations(o.truth, o.machine, 0, 0.81), 0), "missed");
  // Under-segmentation at its boundary: truths of 4 + 4 cells in a machine region of 10.
  Cells u;
  u.Run(4, 0, 1).Run(4, 1, 1).Run(2, -1, 1);
  HooverCounts hu = CompareSegmentations(u.truth, u.machine, 0, 0.8);
  EXPECT_EQ(hu.under, 1);
  EXPECT_EQ(hu.noise, 0);
  hu = CompareSegmentations(u.truth, u.machine, 0, 0.81);
  EXPECT_EQ(hu.under, 0);
  EXPECT_EQ(hu.missed, 2);
  EXPECT_EQ(hu.noise, 1);
  // T = 1: only perfect agreement.
  EXPECT_EQ(CompareSegmentations(c.truth, c.truth, 0, 1.0).correct, 2);
}

TEST(HooverTest, CorrectTakesPrecedenceOverOver) {
  // Truth 0 (10): machine 1 holds 9 of it (correct), machine 2 the 10th cell. Both parts lie
  // wholly inside truth 0 and sum to 10, so it is an over-segmentation too: it counts as
  // correct, and machine 2, part of an instance, is not noise.
  Cells c;
  c.Run(9, 0, 1).Run(1, 0, 2);
  const HooverCounts h = CompareSegmentations(c.truth, c.machine);
  EXPECT_EQ(KindOf(h, 0), "correct");
  EXPECT_EQ(h.correct, 1);
  EXPECT_EQ(h.over, 0);
  EXPECT_EQ(h.noise, 0);
}

TEST(HooverTest, CorrectTakesPrecedenceOverUnderAndSmallRegionsAreIgnored) {
  // Truth 0 (10) and truth 1 (1 cell) in machine 1 (11): truth 0 is correct (10 >= 8.8) and the
  // pair is an under-segmentation; truth 1 is "under" (merged into truth 0's region).
  Cells c;
  c.Run(10, 0, 1).Run(1, 1, 1);
  HooverCounts h = CompareSegmentations(c.truth, c.machine);
  EXPECT_EQ(KindOf(h, 0), "correct");
  EXPECT_EQ(KindOf(h, 1), "under");
  EXPECT_EQ(h.correct, 1);
  EXPECT_EQ(h.under, 1);
  // With min_truth_cells 2, truth 1 is left out, and its cell too.
  h = CompareSegmentations(c.truth, c.machine, 2);
  EXPECT_EQ(h.truth_regions, 1);
  EXPECT_EQ(KindOf(h, 1), "absent");
  EXPECT_EQ(h.correct, 1);
  EXPECT_EQ(h.under, 0);
}

TEST(HooverTest, SmallTruthRegionCellsDoNotCountInMachineRegions) {
  // Machine 1: 8 cells of truth 0 (10) and 3 of truth 1 (3): |M| = 11, 8 < 8.8: truth 0 and 1
  // are an under-segmentation. With truth 1 left out (min 5 cells): |M| = 8, truth 0 correct.
  Cells c;
  c.Run(8, 0, 1).Run(2, 0, 2).Run(3, 1, 1).Run(20, 2, 2);
  HooverCounts h = CompareSegmentations(c.truth, c.machine);
  EXPECT_EQ(KindOf(h, 0), "under");
  EXPECT_EQ(KindOf(h, 1), "under");
  EXPECT_EQ(KindOf(h, 2), "correct");
  h = CompareSegmentations(c.truth, c.machine, 5);
  EXPECT_EQ(h.truth_regions, 2);
  EXPECT_EQ(KindOf(h, 0), "correct");
  EXPECT_EQ(KindOf(h, 2), "correct");
  EXPECT_EQ(h.under + h.over + h.missed + h.noise, 0);
  // A machine region only on left-out cells is ignored, not noise.
  c.Run(2, 7, 9);
  h = CompareSegmentations(c.truth, c.machine, 5);
  EXPECT_EQ(h.noise, 0);
  EXPECT_EQ(CompareSegmentations(c.truth, c.machine, 0).correct, 2);  // truth 2 and 7
}

TEST(HooverTest, AMixedScene) {
  // Truth:  0 correct (machine 10), 1 over (11, 12), 2 + 3 under (13), 4 missed, noise 14.
  Cells c;
  c.Run(50, 0, 10).Run(2, 0, -1);
  c.Run(20, 1, 11).Run(19, 1, 12).Run(1, 1, 10);
  c.Run(15, 2, 13).Run(12, 3, 13).Run(1, 3, 12);
  c.Run(3, 4, 11).Run(3, 4, 12).Run(9, 4, -1);
  c.Run(7, -1, 14);
  const HooverCounts h = CompareSegmentations(c.truth, c.machine);
  EXPECT_EQ(h.truth_regions, 5);
  EXPECT_EQ(KindOf(h, 0), "correct");
  EXPECT_EQ(KindOf(h, 1), "over");
  EXPECT_EQ(KindOf(h, 2), "under");
  EXPECT_EQ(KindOf(h, 3), "under");
  EXPECT_EQ(KindOf(h, 4), "missed");
  EXPECT_EQ(h.correct, 1);
  EXPECT_EQ(h.over, 1);
  EXPECT_EQ(h.under, 1);
  EXPECT_EQ(h.missed, 1);
  EXPECT_EQ(h.noise, 1);
  EXPECT_EQ(h.entries[1].cells, 40);
}

TEST(HooverTest, BadArgumentsThrow) {
  EXPECT_THROW(CompareSegmentations({0, 1}, {0}), std::invalid_argument);
  EXPECT_THROW(CompareSegmentations({0}, {0}, -1), std::invalid_argument);
  EXPECT_THROW(CompareSegmentations({0}, {0}, 0, 0.5), std::invalid_argument);
  EXPECT_THROW(CompareSegmentations({0}, {0}, 0, 1.01), std::invalid_argument);
  const HooverCounts empty = CompareSegmentations({}, {});
  EXPECT_EQ(empty.truth_regions, 0);
  EXPECT_TRUE(empty.entries.empty());
}

}  // namespace
}  // namespace hgrasp::sim
