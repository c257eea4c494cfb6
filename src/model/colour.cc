#include "model/colour.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include "common/error.h"

namespace hgrasp::model {
namespace {

// Thresholds of ColourIndex. The simulator's ambient lighting shows a surface at about 0.65-0.78
// times its albedo (a white table of albedo 0.85 reads (141, 138, 130) / 255, value 0.55), side
// faces somewhat darker than tops; kColourPrototypes observed at 0.6-0.8 x albedo, +-0.02 noise
// per channel, must each get their own name.

// Below this value every sample is black: black (albedo 0.08) reads at most 0.064 + 0.02, grey
// (albedo 0.5) at least 0.30 - 0.02; 0.18 lies between them with room for a shadowed grey side.
// Noise makes a dark sample's hue and saturation meaningless (0.02 on a value of 0.06 is a
// saturation of 0.6), so the value test comes before the chromatic one.
constexpr float kBlackMaxValue = 0.18f;
// Below this saturation a sample is achromatic. The white table reads 0.08, the white and grey
// prototypes at most 0.13 with noise; the least saturated chromatic prototype (green) reads 0.79,
// at least 0.72 with noise. A painted colour of saturation under 0.25 (pastel) is not among
// the names and is called white or grey, by its value.
constexpr float kAchromaticMaxSaturation = 0.25f;
// Above this value an achromatic sample is white: grey reads at most 0.40 + 0.02 (0.8 x 0.5),
// white at least 0.55 - 0.02 (0.6 x 0.92); 0.48 is about their geometric mean.
constexpr float kWhiteMinValue = 0.48f;

// Upper hue bounds (deg) of the chromatic sectors, the usual colour-wheel names. The prototypes'
// hues are red 0, orange 29, yellow 53, green 126, cyan 184, blue 227, magenta 305, at least 11
// deg from a bound; noise of 0.02 per channel moves them by at most 8 deg, so with it each stays
// at least 6 deg inside its sector. The default scenario's yellow box reads 53 deg, the blue 228.
struct HueSector {
  float below_deg;
  int index;  // into kColourNames
};
constexpr std::array<HueSector, 7> kHueSectors = {{
    {15, 0},   // red [0, 15): orange starts where the green channel reaches 1/4 of red
    {40, 1},   // orange [15, 40): between orange (29) and yellow (53)
    {70, 2},   // yellow [40, 70): pure yellow is 60; lime-green beyond 70 is green
    {160, 3},  // green [70, 160)
    {200, 4},  // cyan [160, 200): pure cyan is 180
    {260, 5},  // blue [200, 260): pure blue is 240
    {340, 6},  // magenta [260, 340): pure magenta is 300; crimson beyond 340 is red
}};
constexpr int kRed = 0, kWhite = 7, kGrey = 8, kBlack = 9;

// BoxColour against the table. A region is the top (lit as the table is) when its normal is
// this near vertical.
constexpr double kHorizontalMinNz = 0.95;
// A balanced sample darker than this is achromatic: noise of 3 grey levels on the darkest
// chromatic albedo seen (0.2) is a saturation error of 0.1, on a black side of 0.05 of 0.3.
constexpr float kBalancedDarkValue = 0.10f;
// Lightness bounds of an achromatic box (balanced value of its top): the midpoints between the
// names' albedos, black 0.08-0.22, grey 0.40-0.60, white 0.82-0.97.
constexpr float kBlackMaxLightness = 0.31f;
constexpr float kWhiteMinLightness = 0.71f;
// A reference channel below this (a table in the dark) is not divided by.
constexpr float kMinReference = 0.02f;

int HueIndex(const Eigen::Vector3f& rgb);

// A valid cell of one of a box's regions: the region's id and the cell's colour.
struct Sample {
  int region;
  Eigen::Vector3f rgb;
};

// The valid cells of the given regions, in raster order.
std::vector<Sample> CellSamples(const segment::SegmentResult& s, const std::vector<int>& region_ids,
                                const scan::RangeImage& range) {
  HGRASP_DEMAND(s.rows == range.rows() && s.cols == range.cols());
  HGRASP_DEMAND(static_cast<int>(s.labels.size()) == s.rows * s.cols);
  const std::unordered_set<int> ids(region_ids.begin(), region_ids.end());
  std::vector<Sample> samples;
  for (int r = 0; r < s.rows; ++r) {
    for (int c = 0; c < s.cols; ++c) {
      const int label = s.labels[r * s.cols + c];
      if (label < 0 || !ids.contains(label)) continue;
      const scan::RangeCell& cell = range.at(r, c);
      if (cell.valid) samples.push_back({label, cell.rgb});
    }
  }
  return samples;
}

std::vector<Eigen::Vector3f> Colours(const std::vector<Sample>& samples) {
  std::vector<Eigen::Vector3f> rgb;
  rgb.reserve(samples.size());
  for (const Sample& x : samples) rgb.push_back(x.rgb);
  return rgb;
}

// A white-balanced sample (albedo as if lit as the table): kGrey for every achromatic one, else
// its hue sector.
int BalancedIndex(const Eigen::Vector3f& albedo) {
  const float value = albedo.maxCoeff();
  if (!(value >= kBalancedDarkValue)) return kGrey;  // also NaN
  if ((value - albedo.minCoeff()) / value < kAchromaticMaxSaturation) return kGrey;
  return HueIndex(albedo);
}

// White, grey or black by the lightness of the box's top face (or brightest face), from the
// box's samples.
int LightnessName(const segment::SegmentResult& s, const std::vector<Sample>& samples,
                  const Eigen::Vector3f& gain) {
  std::unordered_map<int, std::vector<Eigen::Vector3f>> balanced;  // per region
  for (const Sample& x : samples) balanced[x.region].push_back(x.rgb.cwiseProduct(gain));
  float lightness = -1.0f;
  bool best_is_top = false;
  for (const segment::PlaneRegion& region : s.regions) {
    const auto found = balanced.find(region.id);
    if (found == balanced.end()) continue;
    const float value = MedianColour(found->second).maxCoeff();
    const bool top = std::abs(region.normal_W.z()) > kHorizontalMinNz;
    // A top face wins over any side; among tops, or among sides, the brighter.
    if ((top && !best_is_top) || (top == best_is_top && value > lightness)) {
      lightness = value;
      best_is_top = top;
    }
  }
  if (lightness < kBlackMaxLightness) return kBlack;
  return lightness > kWhiteMinLightness ? kWhite : kGrey;
}

}  // namespace

int ColourNameIndex(std::string_view name) {
  for (int i = 0; i < kNumColours; ++i) {
    if (kColourNames[i] == name) return i;
  }
  return -1;
}

int ColourIndex(const Eigen::Vector3f& rgb) {
  const float r = std::clamp(rgb.x(), 0.0f, 1.0f);
  const float g = std::clamp(rgb.y(), 0.0f, 1.0f);
  const float b = std::clamp(rgb.z(), 0.0f, 1.0f);
  const float value = std::max({r, g, b});
  const float chroma = value - std::min({r, g, b});
  if (!(value >= kBlackMaxValue)) return kBlack;  // also NaN
  if (chroma / value < kAchromaticMaxSaturation) {
    return value > kWhiteMinValue ? kWhite : kGrey;
  }
  return HueIndex(Eigen::Vector3f(r, g, b));
}

namespace {

int HueIndex(const Eigen::Vector3f& rgb) {
  const float r = rgb.x(), g = rgb.y(), b = rgb.z();
  const float value = std::max({r, g, b});
  const float chroma = value - std::min({r, g, b});
  float hue_deg;
  if (value == r) {
    hue_deg = 60.0f * (g - b) / chroma;
  } else if (value == g) {
    hue_deg = 60.0f * (2.0f + (b - r) / chroma);
  } else {
    hue_deg = 60.0f * (4.0f + (r - g) / chroma);
  }
  if (hue_deg < 0) hue_deg += 360.0f;
  for (const HueSector& s : kHueSectors) {
    if (hue_deg < s.below_deg) return s.index;
  }
  return kRed;  // [340, 360)
}

}  // namespace

std::string_view ColourSummary::name() const {
  if (name_index < 0 || name_index >= kNumColours) return "";
  return kColourNames[name_index];
}

Eigen::Vector3f MedianColour(const std::vector<Eigen::Vector3f>& rgb) {
  Eigen::Vector3f out = Eigen::Vector3f::Zero();
  if (rgb.empty()) return out;
  std::vector<float> channel(rgb.size());
  const size_t mid = rgb.size() / 2;
  for (int k = 0; k < 3; ++k) {
    for (size_t i = 0; i < rgb.size(); ++i) channel[i] = rgb[i][k];
    std::nth_element(channel.begin(), channel.begin() + mid, channel.end());
    float m = channel[mid];
    if (rgb.size() % 2 == 0) {
      // The lower middle is the largest of the elements before mid.
      m = 0.5f * (m + *std::max_element(channel.begin(), channel.begin() + mid));
    }
    out[k] = m;
  }
  return out;
}

ColourSummary SummariseColour(const std::vector<Eigen::Vector3f>& rgb) {
  ColourSummary out;
  std::vector<int> index(rgb.size());
  for (size_t i = 0; i < rgb.size(); ++i) {
    index[i] = ColourIndex(rgb[i]);
    ++out.histogram[index[i]];
  }
  out.samples = static_cast<int>(rgb.size());
  if (rgb.empty()) return out;
  out.name_index = static_cast<int>(std::max_element(out.histogram.begin(), out.histogram.end()) -
                                    out.histogram.begin());
  std::vector<Eigen::Vector3f> winners;
  winners.reserve(out.histogram[out.name_index]);
  for (size_t i = 0; i < rgb.size(); ++i) {
    if (index[i] == out.name_index) winners.push_back(rgb[i]);
  }
  out.rgb = MedianColour(winners);
  return out;
}

std::optional<Eigen::Vector3f> TableColour(const segment::SegmentResult& s,
                                           const std::vector<int>& floor_or_wall,
                                           const scan::RangeImage& range) {
  std::vector<int> floors;
  for (const segment::PlaneRegion& region : s.regions) {
    const bool listed =
        std::find(floor_or_wall.begin(), floor_or_wall.end(), region.id) != floor_or_wall.end();
    if (listed && std::abs(region.normal_W.z()) > kHorizontalMinNz) floors.push_back(region.id);
  }
  const std::vector<Eigen::Vector3f> rgb = Colours(CellSamples(s, floors, range));
  if (rgb.empty()) return std::nullopt;
  return MedianColour(rgb);
}

ColourSummary BoxColour(const segment::SegmentResult& s, const std::vector<int>& region_ids,
                        const scan::RangeImage& range,
                        const std::optional<Eigen::Vector3f>& table_rgb) {
  const std::vector<Sample> samples = CellSamples(s, region_ids, range);
  const std::vector<Eigen::Vector3f> rgb = Colours(samples);
  if (!table_rgb) return SummariseColour(rgb);
  const Eigen::Vector3f gain = kTableAlbedo * table_rgb->cwiseMax(kMinReference).cwiseInverse();
  std::vector<int> index(rgb.size());
  std::array<int, kNumColours> votes{};
  for (size_t i = 0; i < rgb.size(); ++i) {
    index[i] = BalancedIndex(rgb[i].cwiseProduct(gain));
    ++votes[index[i]];
  }
  ColourSummary out;
  out.samples = static_cast<int>(rgb.size());
  if (rgb.empty()) return out;
  // kGrey stands for every achromatic sample until the box's lightness names them.
  const int winner = static_cast<int>(std::max_element(votes.begin(), votes.end()) - votes.begin());
  const int achromatic_name = winner == kGrey ? LightnessName(s, samples, gain) : kGrey;
  for (size_t i = 0; i < rgb.size(); ++i) {
    if (index[i] == kGrey) index[i] = achromatic_name;
    ++out.histogram[index[i]];
  }
  out.name_index = winner == kGrey ? achromatic_name : winner;
  std::vector<Eigen::Vector3f> winners;
  for (size_t i = 0; i < rgb.size(); ++i) {
    if (index[i] == out.name_index) winners.push_back(rgb[i]);
  }
  out.rgb = MedianColour(winners);
  return out;
}

std::optional<int> ChooseByColour(const std::vector<ColourSummary>& colours,
                                  std::string_view colour_name) {
  const int wanted = ColourNameIndex(colour_name);
  std::optional<int> best;
  for (int i = 0; i < static_cast<int>(colours.size()); ++i) {
    if (wanted < 0 || colours[i].name_index != wanted) continue;
    if (!best || colours[i].histogram[wanted] > colours[*best].histogram[wanted]) best = i;
  }
  return best;
}

std::optional<std::string_view> ColourOfName(std::string_view name) {
  if (ColourNameIndex(name) >= 0) return kColourNames[ColourNameIndex(name)];
  const size_t underscore = name.find('_');
  if (underscore == std::string_view::npos) return std::nullopt;
  const int index = ColourNameIndex(name.substr(0, underscore));
  if (index < 0) return std::nullopt;
  return kColourNames[index];
}

}  // namespace hgrasp::model
