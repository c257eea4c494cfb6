// The laser stripe against geometry worked out by hand: its centre on a plane of known pose, its
// absence in the laser's shadow, brightness following surface colour, interference and mirror
// reflections, the per-head-pose cache giving what a full render per frame gives, and frames
// grabbed without images changing no other frame.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <vector>

#include "sim/stereo_rig.h"
#include "sim/truth.h"
#include "tests/sim/sim_test_util.h"
#include "tests/support/status.h"

namespace hgrasp::sim {
namespace {

using testing::MocapProbe;
using testing::PlaceMocap;
using testing::ScenarioFromYaml;
using testing::SetJoint;

// Red-channel difference (with stripe - without), as ints.
cv::Mat RedDifference(const cv::Mat& with, const cv::Mat& without) {
  cv::Mat out(with.size(), CV_32S);
  for (int r = 0; r < with.rows; ++r)
    for (int c = 0; c < with.cols; ++c)
      out.at<int>(r, c) = int(with.at<cv::Vec3b>(r, c)[2]) - int(without.at<cv::Vec3b>(r, c)[2]);
  return out;
}

// Both cameras' images with our laser off, then on, the scene unchanged.
std::pair<StereoImages, StereoImages> DarkAndLit(World* world, StereoRig* rig) {
  world->set_laser_on(false);
  StereoImages dark = rig->Expose(0);
  world->set_laser_on(true);
  return {std::move(dark), rig->Expose(0)};
}

// Column u on image row `row` where the camera ray meets both `surface` and `light` planes
// (bisection on the light-plane distance of the ray's surface point); nullopt if none in view.
std::optional<double> PredictedColumn(const CameraView& view, int row, const Plane& surface_W,
                                      const Plane& light_W) {
  auto s = [&](double u) {
    const Eigen::Vector3d ray_W = view.X_WC.linear() * view.camera.Ray(u, row);
    const Eigen::Vector3d o = view.X_WC.translation();
    const double t = -surface_W.SignedDistance(o) / surface_W.n.dot(ray_W);
    return light_W.SignedDistance(o + t * ray_W);
  };
  double lo = 0, hi = view.camera.width - 1;
  if ((s(lo) > 0) == (s(hi) > 0)) return std::nullopt;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    ((s(mid) > 0) == (s(lo) > 0) ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// Intensity-weighted centroid of `diff` on `row` within +-5 px of `near`.
std::optional<double> Centroid(const cv::Mat& diff, int row, double near) {
  double sw = 0, su = 0;
  for (int c = std::max(0, int(std::lround(near)) - 5);
       c <= std::min(diff.cols - 1, int(std::lround(near)) + 5); ++c) {
    const int v = diff.at<int>(row, c);
    if (v > 0) sw += v, su += v * c;
  }
  if (sw < 30) return std::nullopt;
  return su / sw;
}

// Slab test: does the segment a->b pass through the box (centre, rotation, half sizes + margin)?
bool SegmentHitsBox(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Pose3& X_WO,
                    const Eigen::Vector3d& half) {
  const Eigen::Vector3d pa = X_WO.inverse() * a, pb = X_WO.inverse() * b, d = pb - pa;
  double t0 = 0, t1 = 1;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-15) {
      if (std::abs(pa[i]) > half[i]) return false;
      continue;
    }
    double ta = (-half[i] - pa[i]) / d[i], tb = (half[i] - pa[i]) / d[i];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

TEST(StripeTest, CentreOnAPlaneOfKnownPoseIsWhereLightPlaneMeetsTheRay) {
  WorldOptions options;
  options.extra_worldbody_xml =
      MocapProbe("plate", "type=\"box\" size=\"0.3 0.3 0.001\" rgba=\"0.35 0.35 0.35 1\"");
  World world(ScenarioFromYaml(testing::kEmptyScene), options);
  StereoRig rig(&world);
  // A plate 0.15 m above the table, turned 25 deg about a diagonal from facing the head.
  const Eigen::Vector3d centre(0.32, 0.02, 0.15);
  const Eigen::Vector3d towards = (Eigen::Vector3d(0.03, 0, 0.55) - centre).normalized();
  Eigen::Matrix3d R =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), towards).toRotationMatrix();
  R = Eigen::AngleAxisd(DegToRad(25), Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix() * R;
  Pose3 X_WP = Pose3::Identity();
  X_WP.linear() = R;
  X_WP.translation() = centre;
  PlaceMocap(&world, "plate", X_WP);
  Plane surface_W;  // the plate's front face (+z side)
  surface_W.n = R.col(2);
  surface_W.d = -surface_W.n.dot(centre + 0.001 * R.col(2));
  const int plate = world.Id(mjOBJ_GEOM, "plate");

  int rows = 0;
  double worst = 0, sum2 = 0;
  for (int count : {-1200, 0, 900}) {
    SetJoint(&world, "laser", count * kLaserRadPerCount);
    const auto [dark, lit] = DarkAndLit(&world, &rig);
    const Plane light_W = rig.LaserPlaneAt(count * kLaserRadPerCount);
    for (int cam : {kLeft, kRight}) {
      const CameraView& view = rig.View(cam);
      const cv::Mat diff = RedDifference(lit.image[cam], dark.image[cam]);
      for (int row = 0; row < view.camera.height; ++row) {
        const auto u = PredictedColumn(view, row, surface_W, light_W);
        if (!u || *u < 6 || *u > view.camera.width - 7) continue;
        // Only rows where the plate itself is seen around the stripe.
        bool on_plate = true;
        for (int c = int(*u) - 5; c <= int(*u) + 6; ++c)
          on_plate &= view.images.label.at<int>(row, c) == plate;
        if (!on_plate) continue;
        const auto measured = Centroid(diff, row, *u);
        ASSERT_TRUE(measured.has_value()) << "no stripe on row " << row << " camera " << cam;
        const double e = std::abs(*measured - *u);
        worst = std::max(worst, e), sum2 += e * e, ++rows;
        EXPECT_LT(e, 0.2) << "row " << row << " camera " << cam << " count " << count;
      }
    }
  }
  EXPECT_GT(rows, 300);
  std::printf("stripe centre on a plane: %d rows, RMS %.4f px, worst %.4f px\n", rows,
              std::sqrt(sum2 / rows), worst);
}

// A narrow upright plate floating in front of the table: the laser, above the cameras, lights
// the plate and leaves a shadow on the table behind it, which the cameras, 7 cm to either
// side, see past the plate's edge. Whatever the samples a pixel (the lit frames once kept one
// sample a pixel while the dark ones had four: every edge showed in their difference).
class LaserShadow : public ::testing::TestWithParam<int> {};

TEST_P(LaserShadow, NoStripeInTheLasersShadow) {
  WorldOptions options;
  const Eigen::Vector3d half(0.002, 0.010, 0.100);
  options.extra_worldbody_xml =
      MocapProbe("plate", "type=\"box\" size=\"0.002 0.010 0.100\" rgba=\"0.9 0.9 0.9 1\"");
  World world(ScenarioFromYaml("name: empty\ncamera_samples: " + std::to_string(GetParam()) +
                               "\nobjects: []\n"),
              options);
  StereoRig rig(&world);
  const Pose3 X_WO(Eigen::Translation3d(0.25, 0.0, 0.15));
  PlaceMocap(&world, "plate", X_WO);
  const int count = 0;  // the light plane y ~ 0 cuts the plate
  SetJoint(&world, "laser", count * kLaserRadPerCount);
  const auto [dark, lit] = DarkAndLit(&world, &rig);
  const Plane light_W = rig.LaserPlaneAt(count * kLaserRadPerCount);
  const Plane table_W{Eigen::Vector3d::UnitZ(), 0.0};
  const Eigen::Vector3d source = rig.LaserSource();
  const Eigen::Vector3d grown = half + Eigen::Vector3d::Constant(0.002);
  const Eigen::Vector3d shrunk = half - Eigen::Vector3d(0.001, 0.002, 0.002);
  int shadowed = 0, lit_rows = 0;
  for (int cam : {kLeft, kRight}) {
    const CameraView& view = rig.View(cam);
    const cv::Mat diff = RedDifference(lit.image[cam], dark.image[cam]);
    for (int row = 0; row < view.camera.height; ++row) {
      const auto u = PredictedColumn(view, row, table_W, light_W);
      if (!u || *u < 5 || *u > view.camera.width - 6) continue;
      const Eigen::Vector3d ray_W = view.X_WC.linear() * view.camera.Ray(*u, row);
      const Eigen::Vector3d p =
          view.X_WC.translation() - view.X_WC.translation().z() / ray_W.z() * ray_W;
      if (p.x() < 0.1 || p.x() > 0.85) continue;  // on the table
      // Classify by exact geometry, leaving out cases within 2 mm of the plate's edges.
      if (SegmentHitsBox(view.X_WC.translation(), p, X_WO, grown)) continue;  // hidden
      int peak = 0;
      for (int c = int(*u) - 4; c <= int(*u) + 4; ++c) peak = std::max(peak, diff.at<int>(row, c));
      if (SegmentHitsBox(source, p, X_WO, shrunk)) {
        ++shadowed;
        // (at most the faint tail of the stripe on the plate itself, a few pixels away)
        EXPECT_LE(peak, 2) << "stripe in the shadow: camera " << cam << " row " << row;
      } else if (!SegmentHitsBox(source, p, X_WO, grown)) {
        ++lit_rows;
        EXPECT_GT(peak, 20) << "no stripe on the lit table: camera " << cam << " row " << row;
      }
    }
  }
  std::printf(
      "shadow, %d samples a pixel: %d rows seen in the laser's shadow (no stripe), "
      "%d lit rows\n",
      GetParam(), shadowed, lit_rows);
  EXPECT_GE(shadowed, 10);
  EXPECT_GE(lit_rows, 100);
}

INSTANTIATE_TEST_SUITE_P(SamplesAPixel, LaserShadow, ::testing::Values(1, 4));

constexpr const char* kTwoColours = R"(name: colours
camera_noise: 0
objects:
  - {name: yellow, shape: box, size: [0.08, 0.08, 0.10], position: [0.30, 0.07], color: [0.95, 0.85, 0.10]}
  - {name: blue, shape: box, size: [0.08, 0.08, 0.10], position: [0.30, -0.08], color: [0.10, 0.20, 0.90]}
)";

TEST(StripeTest, BrightnessFollowsSurfaceColourAndSaturates) {
  World world(ScenarioFromYaml(kTwoColours));
  StereoRig rig(&world);
  world.set_laser_on(true);
  const int yellow = world.objects()[0].geom, blue = world.objects()[1].geom;
  double peak_yellow = 0, peak_blue = 0;
  int n_yellow = 0, n_blue = 0, saturated = 0;
  for (int count = -2500; count <= 2500; count += 250) {
    SetJoint(&world, "laser", count * kLaserRadPerCount);
    const StereoImages img = rig.Expose(0);
    const CameraView& view = rig.View(kLeft);
    for (const StripeCrossing& x : img.crossings[kLeft]) {
      const int label = view.images.label.at<int>(x.row, std::lround(x.column));
      if (label == yellow) peak_yellow += x.peak, ++n_yellow;
      if (label == blue) peak_blue += x.peak, ++n_blue;
    }
    for (int r = 0; r < img.image[kLeft].rows; ++r)
      for (int c = 0; c < img.image[kLeft].cols; ++c)
        saturated += img.image[kLeft].at<cv::Vec3b>(r, c)[2] == 255;
  }
  ASSERT_GT(n_yellow, 50);
  ASSERT_GT(n_blue, 50);
  peak_yellow /= n_yellow, peak_blue /= n_blue;
  std::printf("mean stripe peak: yellow %.1f, blue %.1f grey levels; %d saturated pixels\n",
              peak_yellow, peak_blue, saturated);
  EXPECT_LT(peak_blue, 0.2 * peak_yellow);  // red reflectance 0.10 against 0.95
  EXPECT_GT(peak_blue, 5.0);                // faint, but there
  EXPECT_GT(saturated, 0);
}

TEST(StripeTest, InterferenceStripesAppearWithOurLaserOff) {
  const std::string base =
      "name: interference\nobjects:\n  - {name: a, shape: box, size: [0.1, 0.1, 0.1], position: "
      "[0.3, 0.0], color: [0.9, 0.9, 0.9]}\n";
  for (bool with : {false, true}) {
    World world(ScenarioFromYaml(
        base +
        (with ? "interference:\n  - {origin: [0.6, -0.8, 0.5], sweep_deg: [-20, 20], period_s: "
                "1.5}\n  - {origin: [0.5, 0.9, 0.6], sweep_deg: [-15, 15], period_s: 2.0}\n"
              : "")));
    StereoRig rig(&world);
    world.set_laser_on(false);
    int bright = 0;
    for (int k = 0; k < 5; ++k) {
      world.Step(0.3);
      const StereoImages img = rig.Expose(k);
      const cv::Mat diff = RedDifference(img.image[kLeft], rig.Color(kLeft));
      bright += cv::countNonZero(diff > 20);
    }
    if (with) {
      EXPECT_GT(bright, 100);
    } else {
      EXPECT_EQ(bright, 0);
    }
  }
}

TEST(StripeTest, SpecularBoxMirrorsTheStripeOffTheLightPlane) {
  const std::string yaml = R"(name: mirror
objects:
  - {name: shiny, shape: box, size: [0.12, 0.03, 0.10], position: [0.30, -0.02], yaw_deg: 30, color: [0.7, 0.7, 0.7], specular: SPEC}
  - {name: screen, shape: box, size: [0.04, 0.14, 0.14], position: [0.27, 0.12], yaw_deg: -20, color: [0.9, 0.9, 0.9]}
)";
  for (bool specular : {false, true}) {
    std::string y = yaml;
    y.replace(y.find("SPEC"), 4, specular ? "true" : "false");
    World world(ScenarioFromYaml(y));
    StereoRig rig(&world);
    world.set_laser_on(true);
    int mirrored = 0, off_plane = 0;
    for (int count = -2500; count <= 2500; count += 100) {
      SetJoint(&world, "laser", count * kLaserRadPerCount);
      const Plane light_W = rig.LaserPlaneAt(count * kLaserRadPerCount);
      const StereoImages images = rig.Expose(0);
      for (int cam : {kLeft, kRight}) {
        for (const StripeCrossing& x : images.crossings[cam]) {
          if (x.sheet == 0) continue;
          ++mirrored;
          off_plane += std::abs(light_W.SignedDistance(x.p_W)) > 0.005;
        }
      }
    }
    std::printf("specular %d: %d mirrored stripe rows, %d off the light plane\n", specular,
                mirrored, off_plane);
    if (specular) {
      EXPECT_GT(mirrored, 20);
      // The mirror image meets our sheet along the mirror's face: points next to the mirror lie
      // on both; the rest are spurious reflections off the light plane.
      EXPECT_GT(off_plane, 0.75 * mirrored);
    } else {
      EXPECT_EQ(mirrored, 0);
    }
  }
}

// kTwoColours with camera noise 2: the cache must hand on the same noise as a full render.
std::string TwoColoursWithNoise() {
  return std::string(kTwoColours)
      .replace(std::string(kTwoColours).find("camera_noise: 0"), 15, "camera_noise: 2");
}

TEST(StripeTest, CachedSceneGivesTheImagesOfAFullRenderPerFrame) {
  // The scene held still while the laser turns: compositing from the per-head-pose render gives
  // exactly the images of a full render every frame.
  const std::string yaml = TwoColoursWithNoise();
  World world(ScenarioFromYaml(yaml));
  StereoRig cached(&world), full(&world);
  full.set_cache_enabled(false);
  world.set_laser_on(true);
  for (int k = 0; k < 12; ++k) {
    SetJoint(&world, "laser", (-2400 + 400 * k) * kLaserRadPerCount);
    const StereoImages a = cached.Expose(k), b = full.Expose(k);
    EXPECT_EQ(cv::norm(a.image[kLeft], b.image[kLeft], cv::NORM_INF), 0) << "frame " << k;
    EXPECT_EQ(cv::norm(a.image[kRight], b.image[kRight], cv::NORM_INF), 0) << "frame " << k;
  }
  EXPECT_EQ(cached.full_renders(), 2);  // one per camera for the whole sweep
  EXPECT_EQ(full.full_renders(), 24);
}

TEST(StripeTest, CacheThroughTheDevicesStaysWithinOneGreyLevel) {
  // Through the devices the physics runs: resting boxes creep by fractions of a micrometre and
  // the laser motor's start jolts the head by about 2 urad. The cache ignores motions under
  // 10 um; the shading such motions change differs by at most one grey level.
  const std::string yaml = TwoColoursWithNoise();
  SimRobot cached(ScenarioFromYaml(yaml)), full(ScenarioFromYaml(yaml));
  full.rig().set_cache_enabled(false);
  auto a = cached.TakeDevices(), b = full.TakeDevices();
  for (auto* d : {&a, &b}) {
    EXPECT_OK(d->laser->SetLaser(true));
    EXPECT_OK(d->laser->MoveTo(-2000, 4000));
  }
  int differing = 0;
  for (int k = 0; k < 12; ++k) {
    device::StereoFrame fa, fb;
    EXPECT_OK(a.cameras->Grab(&fa));
    EXPECT_OK(b.cameras->Grab(&fb));
    ASSERT_EQ(fa.laser_encoder_count, fb.laser_encoder_count);
    EXPECT_LE(cv::norm(fa.left, fb.left, cv::NORM_INF), 1) << "frame " << k;
    EXPECT_LE(cv::norm(fa.right, fb.right, cv::NORM_INF), 1) << "frame " << k;
    cv::Mat d;
    cv::absdiff(fa.left, fb.left, d);
    differing += cv::countNonZero(d.reshape(1));
  }
  std::printf("device sweep: %d full renders for 12 frames; %d of %d channel values differ by 1\n",
              cached.rig().full_renders(), differing, 12 * 320 * 240 * 3);
  EXPECT_LT(cached.rig().full_renders(), full.rig().full_renders() / 2);
}

TEST(StripeTest, ABoxSlidingAMicrometreAFrameIsRenderedAgainOnlyEveryTenMicrometres) {
  // A box held in the fingers creeps about 1.1e-6 a frame during the rise scan after the lift.
  // The cache keeps a render until something moved 10 um (0.01 px at 0.25 m): with the box
  // sliding down 1.1 um a frame, every ninth or tenth frame is rendered again. Against a full
  // render of the box where it is, the shading differs by at most one grey level but for the
  // pixels whose centres the box's silhouette has crossed since the render (aliased edges flip
  // whole): about its outline's length times 0.01 px, a few pixels, and a stripe crossing there.
  const std::string yaml = TwoColoursWithNoise();
  World world(ScenarioFromYaml(yaml));
  StereoRig cached(&world), full(&world);
  full.set_cache_enabled(false);
  world.set_laser_on(true);
  const mjModel* m = world.model();
  const int z = m->jnt_qposadr[m->body_jntadr[world.objects()[0].body]] + 2;
  constexpr int kFrames = 40;
  constexpr double kSlideM = 1.1e-6;
  int worst_pixels = 0, flipped = 0;
  std::size_t worst_crossings = 0;
  for (int k = 0; k < kFrames; ++k) {
    world.data()->qpos[z] -= kSlideM;
    SetJoint(&world, "laser", (-2400 + 120 * k) * kLaserRadPerCount);  // and mj_forward
    const StereoImages a = cached.Expose(k), b = full.Expose(k);
    for (int cam : {kLeft, kRight}) {
      cv::Mat d;
      cv::absdiff(a.image[cam], b.image[cam], d);
      std::vector<cv::Mat> ch;
      cv::split(d, ch);
      const cv::Mat most = cv::max(cv::max(ch[0], ch[1]), ch[2]);
      const int pixels = cv::countNonZero(most > 1);
      worst_pixels = std::max(worst_pixels, pixels);
      flipped += pixels;
      const std::size_t na = a.crossings[cam].size(), nb = b.crossings[cam].size();
      worst_crossings = std::max(worst_crossings, na > nb ? na - nb : nb - na);
    }
  }
  std::printf(
      "a box sliding %.1f um a frame: %d full renders for %d stereo frames; pixels beyond one "
      "grey level at most %d a frame (%d in all), stripe crossings apart at most %zu\n",
      1e6 * kSlideM, cached.full_renders(), kFrames, worst_pixels, flipped, worst_crossings);
  // 44 um in all: the first render and one each 10 um, per camera (at a 1 um bound: 80).
  EXPECT_LE(cached.full_renders(), 2 * (1 + static_cast<int>(kFrames * kSlideM / 1e-5)));
  EXPECT_EQ(full.full_renders(), 2 * kFrames);
  // The two boxes' outlines are about 800 px long: 0.01 px of motion flips about 8 pixels.
  EXPECT_LE(worst_pixels, 10);
  EXPECT_LE(worst_crossings, 2u);
}

TEST(StripeTest, FramesGrabbedWithoutImagesLeaveTheOtherFramesAsTheyWere) {
  // Two robots on one script; one grabs the frames of each wait without images. The renders
  // those frames would have made (the laser motor's start jolts the head past the cache's
  // tolerance, the arm moves, LEDs switch) are made later from the state they would have been
  // made at: every frame both grab in full is the same to the last bit, and fewer renders are
  // made.
  const std::string yaml = TwoColoursWithNoise();
  SimRobot skipping(ScenarioFromYaml(yaml)), full(ScenarioFromYaml(yaml));
  auto a = skipping.TakeDevices(), b = full.TakeDevices();
  // `waits` frames (a: without images), then `looks` frames both grab in full, compared.
  const auto frames = [&](int waits, int looks) {
    device::StereoFrame fa, fb;
    for (int k = 0; k < waits; ++k) {
      ASSERT_EQ(a.cameras->GrabWithoutImages(&fa), device::Status::kOk);
      ASSERT_EQ(b.cameras->Grab(&fb), device::Status::kOk);
      EXPECT_TRUE(fa.left.empty() && fa.right.empty());
      EXPECT_EQ(fa.t_s, fb.t_s);
      EXPECT_EQ(fa.laser_encoder_count, fb.laser_encoder_count);
    }
    for (int k = 0; k < looks; ++k) {
      ASSERT_EQ(a.cameras->Grab(&fa), device::Status::kOk);
      ASSERT_EQ(b.cameras->Grab(&fb), device::Status::kOk);
      EXPECT_EQ(cv::norm(fa.left, fb.left, cv::NORM_INF), 0) << "frame " << fa.sequence;
      EXPECT_EQ(cv::norm(fa.right, fb.right, cv::NORM_INF), 0) << "frame " << fa.sequence;
    }
  };
  frames(1, 1);  // laser off: colour-only renders
  for (auto* d : {&a, &b}) {
    EXPECT_OK(d->laser->SetLaser(true));
    EXPECT_OK(d->laser->MoveTo(2400, 9000));  // the scan's slew to its start
  }
  frames(8, 4);
  for (auto* d : {&a, &b}) EXPECT_OK(d->laser->MoveTo(2000, 400));  // a stretch of sweep
  frames(4, 4);
  device::ArmState arm;
  EXPECT_OK(a.ArmOf(device::Side::kRight).Read(&arm));
  device::Joint6 goal = arm.q;
  goal[0] += 0.3;
  goal[1] += 0.2;
  for (auto* d : {&a, &b}) {
    EXPECT_OK(d->laser->SetLaser(false));
    ASSERT_EQ(d->ArmOf(device::Side::kRight).MoveJoints(goal), device::Status::kOk);
  }
  frames(12, 2);  // the arm moving, then settling
  for (auto* d : {&a, &b}) EXPECT_OK(d->leds->Set(device::Side::kRight, 0b101));
  frames(2, 2);
  const int renders_a = skipping.rig().full_renders() + skipping.rig().color_renders();
  const int renders_b = full.rig().full_renders() + full.rig().color_renders();
  std::printf("%d renders with the waits' frames grabbed without images, %d with them\n", renders_a,
              renders_b);
  EXPECT_LT(renders_a, renders_b);
}

}  // namespace
}  // namespace hgrasp::sim
