#pragma once
/// @file Segmentation against ground truth after Hoover et al., "An experimental comparison of
/// range image segmentation algorithms" (IEEE PAMI 18(7), 1996): correct detections,
/// over-segmentations, under-segmentations, missed and noise regions at an overlap tolerance T.
///
/// Definitions (G a truth region, M a machine region, |R| its cell count, O(G, M) the cells in
/// both; 0.5 < T <= 1):
///  - correct detection of G by M: O >= T |M| and O >= T |G|;
///  - over-segmentation of G into M_1..M_x (x >= 2): O(G, M_i) >= T |M_i| for each i and
///    sum_i O(G, M_i) >= T |G|;
///  - under-segmentation of G_1..G_x (x >= 2) into M: O(G_i, M) >= T |G_i| for each i and
///    sum_i O(G_i, M) >= T |M|;
///  - missed: a G in no instance of the three kinds; noise: an M in no instance of the three.
/// With T > 0.5 a region takes part in at most one instance of each kind (Hoover), but may take
/// part in one of each. Each truth region is classified once, with precedence correct > over >
/// under: a G that is correctly detected is "correct" even if it is also over-segmented or part
/// of an under-segmentation; a G in an under-segmentation instance whose other members are
/// correct or over-segmented is still "under" (it was merged into M). Counts of correct and over
/// are truth regions (one instance each); `under` counts instances, i.e. machine regions that
/// merge two or more truth regions, at least one of them classified "under" (as in Hoover's
/// tables); machine regions in any instance (counted or not) are not noise.

#include <string>
#include <vector>

namespace hgrasp::sim {

struct HooverCounts {
  int truth_regions = 0;  ///< ground-truth regions considered (>= min_truth_cells cells)
  int correct = 0;        ///< truth regions correctly detected
  int over = 0;           ///< truth regions over-segmented (and not correctly detected)
  int under = 0;          ///< under-segmentation instances (machine regions; see the file comment)
  int missed = 0;         ///< truth regions in no instance
  int noise = 0;          ///< machine regions in no correct/over/under instance
  /// One per truth region considered, by ascending truth code.
  struct Entry {
    int truth_code;    ///< the truth label
    int cells;         ///< |G|
    std::string kind;  ///< "correct", "over", "under" or "missed"
  };
  std::vector<Entry> entries;
};

/// Compares a machine segmentation with the truth, cell by cell. truth[i] and machine[i] are the
/// labels of cell i (e.g. a range point; TrueFaceLabels gives truth codes); a label < 0 means no
/// region on that side:
///  - a cell with no truth label belongs to no truth region but still counts in its machine
///    region's size |M| (a region made of points on no true surface is noise);
///  - a cell with no machine label belongs to no machine region but counts in its truth region's
///    size |G| (cells the machine left out count against it).
/// Truth regions of fewer than `min_truth_cells` cells are left out (neither counted nor
/// classified), and their cells are ignored on both sides: the comparison does not judge how a
/// segmenter treats surfaces too small to be expected as regions. Machine regions with no cell
/// left are ignored too. Overlap tests compare integer counts with T times a count, with a
/// 1e-9 slack against rounding, so O = T |R| passes exactly at the boundary.
///
/// Throws std::invalid_argument when the lengths differ, min_truth_cells < 0 or `tolerance` is
/// not in (0.5, 1].
HooverCounts CompareSegmentations(const std::vector<int>& truth, const std::vector<int>& machine,
                                  int min_truth_cells = 0, double tolerance = 0.8);

}  // namespace hgrasp::sim
