// Random box scenes: deterministic per seed, every constraint checked independently on 200 seeds
// (sizes, workspace, gaps as exact polygon distances, colours, noise), valid as scenario files,
// and every box visible to both cameras from the home pose.

#include "sim/random_scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>
#include <string>

#include "sim/stereo_rig.h"
#include "sim/world.h"
#include "tests/sim/sim_test_util.h"

namespace hgrasp::sim {
namespace {

using Polygon = std::vector<Eigen::Vector2d>;

// The footprint's corners in W, computed here from the spec (not with the library's code).
Polygon Footprint(const ObjectSpec& o) {
  const double c = std::cos(o.yaw), s = std::sin(o.yaw);
  const Eigen::Vector2d ax(c, s), ay(-s, c);
  const double hx = 0.5 * o.size_O.x(), hy = 0.5 * o.size_O.y();
  return {o.position_W + hx * ax + hy * ay, o.position_W - hx * ax + hy * ay,
          o.position_W - hx * ax - hy * ay, o.position_W + hx * ax - hy * ay};
}

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

double PointToSegment(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                      const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (a + t * ab)).norm();
}

// Segment-to-segment distance: 0 when they cross, else the nearest endpoint-segment distance.
double SegmentToSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                        const Eigen::Vector2d& c, const Eigen::Vector2d& d) {
  const double d1 = Cross(b - a, c - a), d2 = Cross(b - a, d - a);
  const double d3 = Cross(d - c, a - c), d4 = Cross(d - c, b - c);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) {
    return 0.0;
  }
  return std::min({PointToSegment(a, c, d), PointToSegment(b, c, d), PointToSegment(c, a, b),
                   PointToSegment(d, a, b)});
}

// Inside a convex counter-clockwise polygon (boundary included).
bool Inside(const Eigen::Vector2d& p, const Polygon& poly) {
  for (std::size_t i = 0; i < poly.size(); ++i) {
    if (Cross(poly[(i + 1) % poly.size()] - poly[i], p - poly[i]) < 0) return false;
  }
  return true;
}

// Exact distance between two convex polygons: 0 when one holds a vertex of the other or their
// edges cross; else the smallest distance between their edges.
double PolygonDistance(const Polygon& a, const Polygon& b) {
  if (Inside(a[0], b) || Inside(b[0], a)) return 0.0;
  double d = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (std::size_t k = 0; k < b.size(); ++k) {
      d = std::min(d, SegmentToSegment(a[i], a[(i + 1) % a.size()], b[k], b[(k + 1) % b.size()]));
    }
  }
  return d;
}

std::string Num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// The scenario as a YAML file would say it.
std::string ToYaml(const Scenario& s) {
  std::string y = "name: " + s.name + "\nseed: " + std::to_string(s.seed) +
                  "\ncamera_noise: " + Num(s.camera_noise) + "\nobjects:\n";
  for (const ObjectSpec& o : s.objects) {
    y += "  - {name: " + o.name + ", shape: " + o.shape + ", size: [" + Num(o.size_O.x()) + ", " +
         Num(o.size_O.y()) + ", " + Num(o.size_O.z()) + "], position: [" + Num(o.position_W.x()) +
         ", " + Num(o.position_W.y()) + "], yaw_deg: " + Num(RadToDeg(o.yaw)) + ", color: [" +
         Num(o.color_rgb.x()) + ", " + Num(o.color_rgb.y()) + ", " + Num(o.color_rgb.z()) +
         "], mass: " + Num(o.mass) + ", specular: " + (o.specular ? "true" : "false") + "}\n";
  }
  if (s.task) {
    y += "task: {target: {color: " + s.task->target_color + "}, lift: " + Num(s.task->lift_m) +
         "}\n";
  }
  return y;
}

void ExpectSame(const Scenario& a, const Scenario& b, double tol) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_NEAR(a.camera_noise, b.camera_noise, tol);
  EXPECT_EQ(a.ambient, b.ambient);
  EXPECT_EQ(a.wall_x.has_value(), b.wall_x.has_value());
  EXPECT_EQ(a.interference.size(), b.interference.size());
  EXPECT_EQ(a.devices.entries.size(), b.devices.entries.size());
  ASSERT_EQ(a.objects.size(), b.objects.size());
  for (std::size_t i = 0; i < a.objects.size(); ++i) {
    const ObjectSpec &p = a.objects[i], &q = b.objects[i];
    EXPECT_EQ(p.name, q.name);
    EXPECT_EQ(p.shape, q.shape);
    EXPECT_LE((p.size_O - q.size_O).cwiseAbs().maxCoeff(), tol);
    EXPECT_LE((p.position_W - q.position_W).cwiseAbs().maxCoeff(), tol);
    EXPECT_NEAR(p.yaw, q.yaw, tol);
    EXPECT_LE((p.color_rgb - q.color_rgb).cwiseAbs().maxCoeff(), tol);
    EXPECT_EQ(p.mass, q.mass);
    EXPECT_EQ(p.specular, q.specular);
  }
  ASSERT_EQ(a.task.has_value(), b.task.has_value());
  if (a.task) {
    EXPECT_EQ(a.task->target_color, b.task->target_color);
    EXPECT_EQ(a.task->target_name, b.task->target_name);
    EXPECT_EQ(a.task->lift_m, b.task->lift_m);
  }
}

TEST(RandomSceneTest, PaletteIsTheTenColourNamesInOrder) {
  const auto& palette = RandomScenePalette();
  ASSERT_EQ(palette.size(), kColorNames.size());
  for (std::size_t i = 0; i < palette.size(); ++i) EXPECT_EQ(palette[i].name, kColorNames[i]);
  EXPECT_EQ(palette[1].rgb, Eigen::Vector3d(0.95, 0.50, 0.08));  // orange
  EXPECT_EQ(palette[9].rgb, Eigen::Vector3d(0.15, 0.15, 0.15));  // black
}

TEST(RandomSceneTest, SameSeedSameScene) {
  for (std::uint64_t seed : {0ull, 1ull, 42ull, 123456789ull, ~0ull}) {
    SCOPED_TRACE(seed);
    ExpectSame(RandomBoxScene(seed), RandomBoxScene(seed), 0.0);
  }
}

TEST(RandomSceneTest, DifferentSeedsDifferentScenes) {
  std::set<std::pair<double, double>> first_positions;
  for (std::uint64_t seed = 1; seed <= 50; ++seed) {
    const Scenario s = RandomBoxScene(seed);
    first_positions.insert({s.objects[0].position_W.x(), s.objects[0].position_W.y()});
  }
  EXPECT_EQ(first_positions.size(), 50u);
}

TEST(RandomSceneTest, TwoHundredSeedsMeetEveryConstraint) {
  const RandomSceneOptions opt;
  const auto& palette = RandomScenePalette();
  int count_of[4] = {0, 0, 0, 0};
  std::set<std::string> colors_seen;
  double smallest_gap = std::numeric_limits<double>::infinity();
  double yaw_min = 10, yaw_max = -10, noise_max = 0;
  for (std::uint64_t seed = 1; seed <= 200; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Scenario s = RandomBoxScene(seed);
    const int n = static_cast<int>(s.objects.size());
    ASSERT_GE(n, 1);
    ASSERT_LE(n, 3);
    ++count_of[n];
    EXPECT_EQ(s.name, "random_" + std::to_string(seed));
    EXPECT_EQ(s.seed, seed);
    EXPECT_GE(s.camera_noise, 0.0);
    EXPECT_LE(s.camera_noise, opt.max_camera_noise);
    noise_max = std::max(noise_max, s.camera_noise);
    EXPECT_FALSE(s.wall_x.has_value());
    EXPECT_TRUE(s.interference.empty());
    EXPECT_TRUE(s.devices.entries.empty());

    const std::vector<std::string> colors = RandomSceneColorNames(s);
    ASSERT_EQ(colors.size(), s.objects.size());
    EXPECT_EQ(std::set<std::string>(colors.begin(), colors.end()).size(), colors.size());
    ASSERT_TRUE(s.task.has_value());
    EXPECT_EQ(s.task->target_color, colors[0]);
    EXPECT_TRUE(s.task->target_name.empty());
    EXPECT_EQ(s.task->lift_m, 0.05);

    for (int i = 0; i < n; ++i) {
      const ObjectSpec& o = s.objects[i];
      EXPECT_EQ(o.name, colors[i] + "_box");
      colors_seen.insert(colors[i]);
      bool in_palette = false;
      for (const NamedColor& c : palette) {
        if (c.name == colors[i]) in_palette = o.color_rgb == c.rgb;
      }
      EXPECT_TRUE(in_palette) << o.name << " " << o.color_rgb.transpose();
      EXPECT_EQ(o.shape, "box");
      EXPECT_EQ(o.mass, 0.2);
      EXPECT_FALSE(o.specular);
      EXPECT_GE(o.size_O.minCoeff(), opt.min_edge_m);
      EXPECT_LE(o.size_O.maxCoeff(), opt.max_edge_m);
      EXPECT_GE(o.yaw, -kPi);
      EXPECT_LT(o.yaw, kPi);
      yaw_min = std::min(yaw_min, o.yaw);
      yaw_max = std::max(yaw_max, o.yaw);
      EXPECT_GE(o.position_W.x(), 0.20);
      EXPECT_LE(o.position_W.x(), 0.40);
      EXPECT_GE(o.position_W.y(), -0.15);
      EXPECT_LE(o.position_W.y(), 0.15);
      for (const Eigen::Vector2d& c : Footprint(o)) {
        EXPECT_TRUE(c.x() >= kTableMinX && c.x() <= kTableMaxX && c.y() >= kTableMinY &&
                    c.y() <= kTableMaxY);
      }
      for (int k = 0; k < i; ++k) {
        const double gap = PolygonDistance(Footprint(o), Footprint(s.objects[k]));
        smallest_gap = std::min(smallest_gap, gap);
        EXPECT_GE(gap, opt.min_gap_m - 1e-12) << o.name << " - " << s.objects[k].name;
      }
    }

    // What a scenario file with these values reads back as: same scene, and it passes the file
    // checks (footprints on the table and clear of each other, unique names, known colour).
    const std::string yaml = ToYaml(s);
    Scenario parsed;
    ASSERT_NO_THROW(parsed = ParseScenario(yaml, "random.yaml")) << yaml;
    ExpectSame(parsed, s, 1e-12);
  }
  // All box counts occur, in roughly equal shares (1/3 each of 200, minus the rare retries with a
  // box fewer).
  std::printf(
      "box counts 1/2/3: %d/%d/%d; smallest gap %.4f m; yaw [%.3f, %.3f] rad; "
      "noise max %.3f; %zu colours\n",
      count_of[1], count_of[2], count_of[3], smallest_gap, yaw_min, yaw_max, noise_max,
      colors_seen.size());
  for (int n = 1; n <= 3; ++n) EXPECT_GE(count_of[n], 40) << n << " boxes";
  EXPECT_EQ(colors_seen.size(), palette.size());
  EXPECT_LT(yaw_min, -kPi + 0.5);
  EXPECT_GT(yaw_max, kPi - 0.5);
  EXPECT_GT(noise_max, 1.5);
}

TEST(RandomSceneTest, OptionsAreHonoured) {
  RandomSceneOptions opt;
  opt.min_boxes = opt.max_boxes = 10;  // every palette colour once
  opt.min_edge_m = opt.max_edge_m = 0.05;
  opt.max_camera_noise = 0.0;
  opt.min_gap_m = 0.0;  // apart, possibly touching
  for (std::uint64_t seed = 0; seed < 20; ++seed) {
    const Scenario s = RandomBoxScene(seed, opt);
    ASSERT_EQ(s.objects.size(), 10u);
    EXPECT_EQ(s.camera_noise, 0.0);
    for (const ObjectSpec& o : s.objects) EXPECT_EQ(o.size_O, Eigen::Vector3d::Constant(0.05));
    ASSERT_NO_THROW(ParseScenario(ToYaml(s), "random.yaml"));
  }
}

TEST(RandomSceneTest, FewerBoxesWhenTheyDoNotFit) {
  // Four 15 cm boxes 10 cm apart cannot fit around centres in a 20 x 30 cm workspace.
  RandomSceneOptions opt;
  opt.min_boxes = 1;
  opt.max_boxes = 4;
  opt.min_edge_m = opt.max_edge_m = 0.15;
  opt.min_gap_m = 0.10;
  for (std::uint64_t seed = 0; seed < 3; ++seed) {
    const Scenario s = RandomBoxScene(seed, opt);
    EXPECT_LT(s.objects.size(), 4u);
    ASSERT_NO_THROW(ParseScenario(ToYaml(s), "random.yaml"));
  }
  opt.min_boxes = 4;
  EXPECT_THROW(RandomBoxScene(0, opt), std::runtime_error);
}

TEST(RandomSceneTest, BadOptionsThrow) {
  auto with = [](auto change) {
    RandomSceneOptions o;
    change(o);
    return o;
  };
  EXPECT_THROW(RandomBoxScene(1, with([](auto& o) { o.min_boxes = 0; })), std::invalid_argument);
  EXPECT_THROW(RandomBoxScene(1, with([](auto& o) { o.max_boxes = 11; })), std::invalid_argument);
  EXPECT_THROW(RandomBoxScene(1, with([](auto& o) { o.min_boxes = 3, o.max_boxes = 2; })),
               std::invalid_argument);
  EXPECT_THROW(RandomBoxScene(1, with([](auto& o) { o.min_edge_m = 0.001; })),
               std::invalid_argument);
  EXPECT_THROW(RandomBoxScene(1, with([](auto& o) { o.min_edge_m = 0.2; })), std::invalid_argument);
  EXPECT_THROW(RandomBoxScene(1, with([](auto& o) { o.max_camera_noise = -1; })),
               std::invalid_argument);
  EXPECT_THROW(RandomBoxScene(1, with([](auto& o) { o.min_gap_m = -0.01; })),
               std::invalid_argument);
  Scenario s = RandomBoxScene(1);
  s.objects[0].name = "teal_box";
  EXPECT_THROW(RandomSceneColorNames(s), std::invalid_argument);
}

// Every box of seeds 1..20 covers at least 300 pixels of each camera's label image at the home
// pose (the workspace promise of DESIGN.md, with the other boxes and the robot in the way).
TEST(RandomSceneTest, EveryBoxIsVisibleToBothCamerasFromHome) {
  constexpr int kMinPixels = 300;
  int smallest = std::numeric_limits<int>::max();
  std::string smallest_where;
  const auto start = std::chrono::steady_clock::now();
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    World world(RandomBoxScene(seed));
    StereoRig rig(&world);
    for (int cam : {kLeft, kRight}) {
      const cv::Mat& label = rig.View(cam).images.label;
      for (const SimObject& o : world.objects()) {
        const int pixels = testing::LabelPixels(label, o.geom);
        const std::string where =
            "seed " + std::to_string(seed) + " camera " + std::to_string(cam) + " " + o.spec.name;
        EXPECT_GE(pixels, kMinPixels) << where;
        if (pixels < smallest) {
          smallest = pixels;
          smallest_where = where;
        }
      }
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("smallest visible box: %d pixels (%s); 20 scenes in %.1f s\n", smallest,
              smallest_where.c_str(), seconds);
  RecordProperty("smallest_visible_pixels", smallest);
}

}  // namespace
}  // namespace hgrasp::sim
