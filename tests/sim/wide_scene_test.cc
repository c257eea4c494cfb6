// The wide box scenes (issue 37): deterministic per seed; on 300 seeds every draw within its
// range and every promise kept (target width, gaps, colour names, valid scenario files); the
// families the generator promises actually occur (close pairs, near-square boxes, stripes,
// walls, specular boxes, off-palette colours); and, rendered by the twin, every box seen by both
// cameras from the look pose.

#include "sim/wide_scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>

#include "common/error.h"
#include "common/geometry.h"
#include "scan/scanner.h"
#include "sim/random_scene.h"
#include "sim/stereo_rig.h"
#include "sim/world.h"
#include "tests/sim/sim_test_util.h"

namespace hgrasp::sim {
namespace {

const NamedColor& PaletteColour(const std::string& name) {
  for (const NamedColor& c : RandomScenePalette()) {
    if (c.name == name) return c;
  }
  throw std::invalid_argument(name);
}

TEST(WideSceneTest, HsvRoundTripsAndKnownValues) {
  EXPECT_TRUE(RgbToHsv({1, 0, 0}).isApprox(Eigen::Vector3d(0, 1, 1)));
  EXPECT_TRUE(RgbToHsv({0, 0.5, 0.5}).isApprox(Eigen::Vector3d(180, 1, 0.5)));
  EXPECT_TRUE(RgbToHsv({0.25, 0.25, 0.25}).isApprox(Eigen::Vector3d(0, 0, 0.25)));
  for (const NamedColor& c : RandomScenePalette()) {
    EXPECT_TRUE(HsvToRgb(RgbToHsv(c.rgb)).isApprox(c.rgb, 1e-12)) << c.name;
  }
}

TEST(WideSceneTest, SameSeedSameScene) {
  EXPECT_EQ(ScenarioYaml(WideBoxScene(7)), ScenarioYaml(WideBoxScene(7)));
  EXPECT_NE(ScenarioYaml(WideBoxScene(7)), ScenarioYaml(WideBoxScene(8)));
}

// The counts of what the family promises to draw, over 300 seeds.
struct Seen {
  int scenes = 0, boxes = 0, close_pairs = 0, square = 0, interference = 0, walls = 0, specular = 0,
      off_palette = 0, heavy = 0;
};

void CheckScene(const Scenario& s, Seen* seen) {
  const WideSceneOptions o;
  const std::string where = s.name;
  // A valid scenario file that reads back to the same colour names.
  const Scenario back = ParseScenario(ScenarioYaml(s), where + ".yaml");
  ASSERT_EQ(back.objects.size(), s.objects.size()) << where;
  ASSERT_TRUE(s.task.has_value()) << where;
  EXPECT_EQ(s.task->target_color, s.objects[0].color_name) << where;
  EXPECT_LE(std::min(s.objects[0].size_O.x(), s.objects[0].size_O.y()), o.max_target_width_m)
      << where;
  EXPECT_GE(s.ambient, o.min_ambient) << where;
  EXPECT_LE(s.ambient, o.max_ambient) << where;
  EXPECT_LE(s.camera_noise, o.max_camera_noise) << where;
  std::set<std::string> names;
  for (std::size_t i = 0; i < s.objects.size(); ++i) {
    const ObjectSpec& b = s.objects[i];
    EXPECT_EQ(back.objects[i].color_name, b.color_name) << where;
    EXPECT_EQ(b.name, b.color_name + "_box") << where;
    EXPECT_TRUE(names.insert(b.color_name).second) << where << ": colour twice";
    EXPECT_GE(b.mass, o.min_mass_kg) << where;
    EXPECT_LE(b.mass, o.max_mass_kg) << where;
    // The colour lies near the palette colour it is named after: hue within hue_deg for the
    // chromatic ones, value in its band for white, grey and black.
    const Eigen::Vector3d hsv = RgbToHsv(b.color_rgb);
    const Eigen::Vector3d ref = RgbToHsv(PaletteColour(b.color_name).rgb);
    if (b.color_name == "white" || b.color_name == "grey" || b.color_name == "black") {
      EXPECT_LE(hsv[1], 0.06 + 1e-9) << where;
    } else {
      const double dh = std::abs(std::remainder(hsv[0] - ref[0], 360.0));
      EXPECT_LE(dh, o.hue_deg + 1e-9) << where << " " << b.name;
    }
    seen->off_palette += (b.color_rgb - PaletteColour(b.color_name).rgb).norm() > 0.02;
    seen->square += std::abs(b.size_O.x() / b.size_O.y() - 1.0) <= 0.031;
    seen->specular += b.specular;
    seen->heavy += b.mass > 0.35;
    EXPECT_TRUE(BoxInBothViews(b, o.view_margin_px)) << where;
    for (std::size_t k = i + 1; k < s.objects.size(); ++k) {
      const double gap = FootprintDistance(ObjectFootprint(b), ObjectFootprint(s.objects[k]));
      EXPECT_GE(gap, o.min_gap_m - 1e-12) << where;
      seen->close_pairs += gap <= o.close_gap_m;
    }
    ++seen->boxes;
  }
  seen->interference += !s.interference.empty();
  seen->walls += s.wall_x.has_value();
  ++seen->scenes;
}

TEST(WideSceneTest, ThreeHundredSeedsKeepEveryPromiseAndDrawEveryKind) {
  Seen seen;
  for (std::uint64_t seed = 1; seed <= 300; ++seed) CheckScene(WideBoxScene(seed), &seen);
  std::printf(
      "300 scenes: %d boxes, %d close pairs, %d near-square, %d specular, %d heavy, "
      "%d off-palette; %d with a stripe, %d with a wall\n",
      seen.boxes, seen.close_pairs, seen.square, seen.specular, seen.heavy, seen.off_palette,
      seen.interference, seen.walls);
  // Each kind the issue lists occurs often enough to be measured (the chances are 25-50 %).
  EXPECT_GE(seen.close_pairs, 50);
  EXPECT_GE(seen.square, 60);
  EXPECT_GE(seen.specular, 40);
  EXPECT_GE(seen.heavy, 60);
  EXPECT_GE(seen.off_palette, seen.boxes * 9 / 10);
  EXPECT_GE(seen.interference, 60);
  EXPECT_GE(seen.walls, 40);
}

// A scene whose boxes the target_graspable hook refuses is drawn again; a hook that refuses
// every scene leaves none to draw.
TEST(WideSceneTest, TheTargetHookChoosesTheScenesKept) {
  WideSceneOptions o;
  int asked = 0;
  o.target_graspable = [&asked](const std::vector<ObjectSpec>& boxes) {
    ++asked;
    return boxes.size() == 1 && boxes[0].size_O.z() < 0.06;
  };
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const Scenario s = WideBoxScene(seed, o);
    ASSERT_EQ(s.objects.size(), 1u);
    EXPECT_LT(s.objects[0].size_O.z(), 0.06);
  }
  EXPECT_GT(asked, 5);
  o.target_graspable = [](const std::vector<ObjectSpec>&) { return false; };
  EXPECT_THROW(WideBoxScene(1, o), std::runtime_error);
}

// The colour name in a scenario file is read, written and checked.
TEST(WideSceneTest, ColourNameIsPartOfTheScenarioFile) {
  const std::string yaml =
      "name: t\nobjects:\n  - {name: a, shape: box, size: [0.05, 0.05, 0.05], position: [0.3, "
      "0], color: [0.5, 0.1, 0.1], color_name: red}\n";
  EXPECT_EQ(ParseScenario(yaml, "t.yaml").objects[0].color_name, "red");
  std::string bad = yaml;
  bad.replace(bad.find("red"), 3, "pink");
  EXPECT_THROW(ParseScenario(bad, "t.yaml"), InputError);
}

// A box behind a taller one is not seen past it; beside it, it is.
TEST(WideSceneTest, TopSeenPastIsALineOfSight) {
  ObjectSpec near, far;
  near.size_O = {0.05, 0.15, 0.15};
  near.position_W = {0.31, 0.0};
  far.size_O = {0.04, 0.04, 0.04};
  far.position_W = {0.37, 0.0};
  EXPECT_FALSE(TopSeenPast(far, near));
  EXPECT_TRUE(TopSeenPast(near, far));
  far.position_W = {0.37, 0.14};
  EXPECT_TRUE(TopSeenPast(far, near));
}

// Rendered by the twin with the head at the look pose, every box of seeds 1..10 covers at least
// 300 pixels of each camera's label image (the other boxes, the robot and a wall in the way).
TEST(WideSceneTest, EveryBoxIsSeenByBothCamerasFromTheLookPose) {
  constexpr int kMinPixels = 300;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    World world(WideBoxScene(seed));
    testing::SetJoint(&world, "head_pan", scan::kLookHead.pan);
    testing::SetJoint(&world, "head_tilt", scan::kLookHead.tilt);
    testing::SetJoint(&world, "head_verge_left", scan::kLookHead.verge);
    testing::SetJoint(&world, "head_verge_right", scan::kLookHead.verge);
    StereoRig rig(&world);
    for (int cam : {kLeft, kRight}) {
      const cv::Mat& label = rig.View(cam).images.label;
      for (const SimObject& o : world.objects()) {
        const int pixels = testing::LabelPixels(label, o.geom);
        EXPECT_GE(pixels, kMinPixels) << "seed " << seed << " camera " << cam << " " << o.spec.name;
      }
    }
  }
}

}  // namespace
}  // namespace hgrasp::sim
