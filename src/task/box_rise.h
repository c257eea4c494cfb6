#pragma once
/// @file The held box's rise as the cameras measure it (issue 19, honest success): the lift is
/// judged by the box, not by the gripper. After the hold, the stripe positions that lit the box
/// in the look are scanned again, and every rise from a little below the table to past the lift
/// is tried for the box as it was modelled, raised straight up by that much. A rise is ruled out
/// when
///  - a cell the cameras saw lies inside that box, or behind it on the left camera's line of
///    sight (the box, shrunk by shrink_m for the model's errors and a small tilt in the hand,
///    would have hidden it): the space where a slipped box would hang is seen empty;
///  - the highest cells of the box's colour in its footprint lie above that box's top, or the
///    lowest below its bottom (near-extreme quantiles, so that a stray cell decides nothing).
/// The counts swept are those at which the laser's plane lights the modelled box at some rise
/// (CountsLightingBox), not those that lit it in the look: raised 5 cm, a box is lit several
/// degrees of the laser's turn away.
/// The box rose at least the smallest rise left, at most the largest. The arm and the hand often
/// hide most of a small box from the head after the lift (the forearm lies between them), so
/// both kinds of evidence count: the space seen empty rules out low rises when the box itself
/// is hidden, and the box's own cells rule them out when it is seen. Nothing seen at all leaves
/// every rise possible: the box is not known to be lifted.
///
/// Cells of the box's colour are searched from just above the modelled bottom (the table is
/// named white, as a white box is) to above the top raised by the lift, inside the footprint
/// grown by footprint_margin_m. The hand holding the box is in that space: its pads are black
/// and its skin is named orange (model/colour.h), so a black or an orange box would count the
/// hand's cells as its own. Their top quantile would read high and rule out LOW rises it should
/// not (held-out seed 9003: an orange box truly 48.4 mm up was bounded at 51 mm; one that slid
/// down the fingers could have been called lifted). The cells inside the hand's boxes
/// (HandRegion: the gripper's pose from its LEDs, grown by hand_margin_m) are therefore not
/// the box's.

#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/geometry.h"
#include "grasp/grasp_planner.h"
#include "model/box_fit.h"
#include "robot/calibration.h"
#include "scan/range_image.h"
#include "scan/scanner.h"

namespace hgrasp::task {

struct BoxRiseConfig {
  /// The footprint searched: the modelled box's, grown by this on every side (m).
  double footprint_margin_m = 0.015;
  /// Searched from this far above the modelled bottom, clear of the table's cells (their
  /// noise is about 1 mm; the table is named white, as a white box is) (m) ...
  double table_clearance_m = 0.004;
  /// ... to this far above the modelled top raised by the lift (m).
  double above_m = 0.02;
  /// Fewer box cells than this: the box is not found.
  int min_cells = 20;
  /// The box's bottom: this quantile of the cells' heights (a face's cells are 1-3 mm apart in
  /// height, a box shows 500-3000 of them).
  double low_quantile = 0.01;
  double high_quantile = 0.99;  ///< its top
  /// The rise scan covers the counts that light the box (CountsLightingBox) and this many
  /// beyond on each side (0.3 deg: the head's pose and the laser's calibration are that good).
  std::int32_t sweep_margin_counts = 30;
  /// The box tried at each rise is the model shrunk by this on every face (m): the box fit's
  /// faces are within 1-4 mm (the sweep's edge tolerance is 4 mm) and a held box tilts a little.
  double shrink_m = 0.006;
  /// A rise is ruled out by more than this many cells seen inside or behind the box.
  int max_hidden_cells = 4;
  /// Its own cells rule out a rise when they lie this far outside it (m).
  double cell_tolerance_m = 0.004;
  /// With the look's cells of the box given, its highest cells are held against theirs, raised
  /// by the rise, within this (m): their 0.99 quantiles are each within about 1 mm, and a run
  /// through the twin's wires measured a bound 0.7 mm over the truth with 2 mm.
  double top_tolerance_m = 0.003;
  /// Rises tried: from -below_m to lift + above_m, in steps of step_m (m).
  double below_m = 0.01;
  double step_m = 0.001;
  /// The hand's boxes are grown by this on every side before their cells are left out (m):
  /// the LEDs give the gripper's pose within 1-3 mm, and the skin's cells lie on its faces.
  double hand_margin_m = 0.008;
  /// The palm's box is carried this far back along -z of E, over the flange and the wrist,
  /// which are as close to the box's footprint as the palm is (m).
  double wrist_m = 0.08;
};

/// Space whose cells are not the box's: the hand at gripper pose X_WE (W) with its fingers
/// `opening_m` apart (grasp::HandBoxes), the palm carried back over the wrist by
/// config.wrist_m, every box grown by config.hand_margin_m.
std::vector<grasp::OrientedBox> HandRegion(const Pose3& X_WE, double opening_m,
                                           const grasp::HandGeometry& hand = {},
                                           const BoxRiseConfig& config = {});

/// The box's cells in one scan.
struct BoxHeights {
  int cells = 0;
  double low_z = 0;   ///< low_quantile of the cells' heights in W (m)
  double high_z = 0;  ///< high_quantile (m)
  /// The stripe positions (encoder counts) of the first and last columns with a box cell.
  std::int32_t first_count = 0, last_count = 0;
};

/// The cells of `range` that are box `box`'s: valid, of colour `colour_index`
/// (model::ColourIndex), inside its footprint grown by config.footprint_margin_m, and from
/// table_clearance_m over its modelled bottom to above_m over its modelled top raised by
/// `lift_m`. A box that did not rise reads its bottom table_clearance_m high.
/// Cells inside one of the boxes `not_box` are left out (HandRegion).
/// nullopt when fewer than config.min_cells are; `range.encoder_counts` must be filled.
std::optional<BoxHeights> MeasureBoxHeights(const scan::RangeImage& range,
                                            const model::BoxModel& box, int colour_index,
                                            double lift_m, const BoxRiseConfig& config = {},
                                            std::span<const grasp::OrientedBox> not_box = {});

/// The encoder counts at which the laser's plane (at the head's pose X_WH) lights some part of
/// the box raised anywhere from -config.below_m to lift_m + config.above_m, its footprint grown
/// by config.footprint_margin_m: the lowest and the highest, within `look_sweep`. A raised box
/// is lit at other counts than in the look (the plane leans), so the rise scan is aimed from
/// the model, not from where the look saw the box. A corner the plane never reaches inside the
/// sweep counts as at the sweep's nearer end.
std::pair<std::int32_t, std::int32_t> CountsLightingBox(const model::BoxModel& box,
                                                        double lift_m,
                                                        const robot::LaserCalibration& laser,
                                                        const Pose3& X_WH,
                                                        const scan::SweepConfig& look_sweep,
                                                        const BoxRiseConfig& config = {});

/// The sweep that scans the box again: counts `first` to `last` (either order) and
/// config.sweep_margin_counts beyond them (within the look's sweep), in the look's direction
/// and at its spacing.
scan::SweepConfig RiseSweep(std::int32_t first, std::int32_t last,
                            const scan::SweepConfig& look_sweep,
                            const BoxRiseConfig& config = {});

/// What the cameras say the box rose.
struct BoxRise {
  /// The rises not ruled out span min_m to max_m (m); none left (the box seen where no box
  /// raised straight up can be, e.g. tipped or pulled aside): min_m > max_m.
  double min_m = 0, max_m = -1;
  int candidates = 0;       ///< rises tried
  int left = 0;             ///< of those, not ruled out
  int cells = 0;            ///< valid cells of the rise scan
  int box_cells = 0;        ///< of those, the box's (MeasureBoxHeights)
  double bottom_z = 0;      ///< their low quantile in W (m; when box_cells > 0)
  double top_z = 0;         ///< their high quantile (m)

  bool consistent() const { return left > 0; }
};

/// How far to raise a box the rise scan saw in the hand (m; 0: not at all): by what the middle
/// of its rises lacks of `lift_m`, or by what their low end lacks of `min_rise_m` (the least
/// rise the verdict accepts), whichever is more, when that is more than `tolerance_m`; never
/// more than `max_step_m`. Nothing for a rise the scan did not see (fewer than `min_cells` of
/// the box's cells) or found inconsistent (the box tipped or moved): raising that proves nothing.
/// A box truly up but seen with wide bounds ends a few mm higher; one truly short rises to the
/// lift; one not in the hand stays where it is, and the scan after says so.
double RiseShortfall(const BoxRise& rise, double lift_m, double min_rise_m, double tolerance_m,
                     double max_step_m, int min_cells);

/// Tries every rise against the rise scan `after` (its cells in W), with the left camera's
/// centre at `camera_W` during that scan. `before`, when given, is the box's cells in the look
/// (MeasureBoxHeights with lift 0): a rise is also ruled out when the highest cells now lie
/// more than top_tolerance_m above the look's raised by it, a bound that does not depend on the
/// model's top (fitted within a few mm) nor on how well the head's kinematics are known.
/// `hand` (HandRegion of the gripper's pose after the hold): cells there are not the box's.
BoxRise MeasureRise(const scan::RangeImage& after, const model::BoxModel& box, int colour_index,
                    const Eigen::Vector3d& camera_W, double lift_m,
                    const BoxRiseConfig& config = {}, const BoxHeights* before = nullptr,
                    std::span<const grasp::OrientedBox> hand = {});

}  // namespace hgrasp::task
