#pragma once
/// @file The colour of a box (Taylor & Kleeman, section 6: the target is identified by the colour
/// histogram of its model): each colour sample is named by one of ten colour words (HSV
/// thresholds), and a box's colour is the most frequent name among its range cells.

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string_view>
#include <vector>

#include "scan/range_image.h"
#include "segment/segment.h"

namespace hgrasp::model {

/// Number of colour names.
inline constexpr int kNumColours = 10;

/// The colour names a target can be chosen by (the scenario's task.target.color uses the same
/// list).
inline constexpr std::array<std::string_view, kNumColours> kColourNames = {
    "red", "orange", "yellow", "green", "cyan", "blue", "magenta", "white", "grey", "black"};

/// A prototype albedo (RGB, 0-1) per kColourNames entry, in the same order: each is named right
/// by ColourIndex when observed at 0.6-0.8 times its albedo (the simulator's ambient lighting)
/// with +-0.02 noise per channel. The random-scene generator paints boxes with these.
inline constexpr std::array<std::array<float, 3>, kNumColours> kColourPrototypes = {{
    {0.85f, 0.10f, 0.10f},  // red
    {0.95f, 0.50f, 0.08f},  // orange
    {0.95f, 0.85f, 0.10f},  // yellow
    {0.15f, 0.70f, 0.20f},  // green
    {0.10f, 0.75f, 0.80f},  // cyan
    {0.15f, 0.30f, 0.85f},  // blue
    {0.80f, 0.15f, 0.75f},  // magenta
    {0.92f, 0.92f, 0.90f},  // white
    {0.50f, 0.50f, 0.50f},  // grey
    {0.15f, 0.15f, 0.15f},  // black
}};

/// Index into kColourNames of a colour name, -1 if it is none of them (case-sensitive).
int ColourNameIndex(std::string_view name);

/// Index into kColourNames of one colour sample (RGB 0-1 as measured in ambient light; values
/// outside [0, 1] are clamped). In HSV (value = max channel, saturation = (max - min) / max, hue
/// in deg): value < 0.18 is black whatever the hue; else saturation < 0.25 is white (value >
/// 0.48) or grey; else the hue sector names it: red [340, 15), orange [15, 40), yellow [40, 70),
/// green [70, 160), cyan [160, 200), blue [200, 260), magenta [260, 340). See colour.cc for why.
int ColourIndex(const Eigen::Vector3f& rgb);

/// A colour histogram over kColourNames and its winner.
struct ColourSummary {
  std::array<int, kNumColours> histogram{};  ///< samples per kColourNames entry
  /// Per-channel median (RGB, 0-1) of the samples in the winning bin; zero when there are none.
  Eigen::Vector3f rgb = Eigen::Vector3f::Zero();
  int name_index = -1;  ///< the bin with most samples (the lowest index on a tie); -1: no samples
  int samples = 0;      ///< total samples

  /// kColourNames[name_index], or "" when there are no samples.
  std::string_view name() const;
};

/// Histogram of the samples' ColourIndex, the winning bin and its median colour.
ColourSummary SummariseColour(const std::vector<Eigen::Vector3f>& rgb);

/// The albedo of the table (the paper's white table): the white reference's true lightness.
inline constexpr float kTableAlbedo = 0.85f;

/// The table as the cameras see it, the white reference of BoxColour: the per-channel median of
/// the valid cells of the horizontal regions (|n.z| > 0.95) among floor_or_wall
/// (segment::Grouping); nullopt when there are none.
std::optional<Eigen::Vector3f> TableColour(const segment::SegmentResult& s,
                                           const std::vector<int>& floor_or_wall,
                                           const scan::RangeImage& range);

/// The colour of a box from the range cells of its regions (unknown ids match no cell). s must
/// come from segment::SegmentPlanes on range (aborts on a size mismatch).
///
/// Without a table reference: SummariseColour over those cells (ColourIndex's fixed thresholds,
/// which hold only for the light they were set in).
///
/// With the table's colour (TableColour) as the white reference, whatever the light: each
/// sample is white-balanced and scaled to the albedo it would have lit as the table is
/// (rgb / table_rgb x kTableAlbedo, per channel). A balanced sample darker than 0.10 or with
/// saturation under 0.25 is achromatic; else its hue sector (ColourIndex's) names it. The most
/// frequent of the seven hue names and "achromatic" wins; an achromatic box is then named by its
/// lightness, the median balanced value of its top face (the horizontal region lit as the table
/// is; the brightest region when none is horizontal, since side faces are lit less): black under
/// 0.31, white above 0.71, grey between (the midpoints between the names' albedos: black
/// 0.08-0.22, grey 0.40-0.60, white 0.82-0.97). The histogram counts the achromatic samples
/// under that name.
ColourSummary BoxColour(const segment::SegmentResult& s, const std::vector<int>& region_ids,
                        const scan::RangeImage& range,
                        const std::optional<Eigen::Vector3f>& table_rgb = std::nullopt);

/// Per-channel median (RGB) of samples, zero when empty; an even count averages the middle two.
Eigen::Vector3f MedianColour(const std::vector<Eigen::Vector3f>& rgb);

/// The target among boxes of the given colours (paper section 6: the target is identified by
/// the colour histogram of its model): the box whose colour is named `colour_name` (one of
/// kColourNames), the one with the most samples of that colour if several; nullopt if none is.
std::optional<int> ChooseByColour(const std::vector<ColourSummary>& colours,
                                  std::string_view colour_name);

/// The colour a task's target name refers to: the name itself when it is a colour name, else its
/// leading word before '_' when that is one ("yellow_box" -> "yellow"); nullopt otherwise. The
/// robot knows objects only by what it sees; a name is resolved through its colour word.
std::optional<std::string_view> ColourOfName(std::string_view name);

}  // namespace hgrasp::model
