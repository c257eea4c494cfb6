// Rendering against ground truth worked out by hand: where a known point must appear, what depth
// a plane at a known distance must have, and that each pixel's label is the geom at its depth.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

#include "sim/stereo_rig.h"
#include "tests/sim/sim_test_util.h"

namespace hgrasp::sim {
namespace {

using testing::MocapProbe;
using testing::PlaceMocap;
using testing::ScenarioFromYaml;

constexpr double kMarkerRadius = 0.02;

// Centre of the image of a sphere (centre p_C in the camera frame, radius r): the centre of the
// ellipse x^T (c c^T - (|c|^2 - r^2) I) x = 0 in normalised coordinates, mapped to pixels.
Eigen::Vector2d SphereImageCentre(const PinholeCamera& k, const Eigen::Vector3d& c, double r) {
  const Eigen::Matrix3d Q =
      c * c.transpose() - (c.squaredNorm() - r * r) * Eigen::Matrix3d::Identity();
  const Eigen::Vector2d centre = -Q.topLeftCorner<2, 2>().inverse() * Q.topRightCorner<2, 1>();
  return {k.fx * centre.x() + k.cx, k.fy * centre.y() + k.cy};
}

class RenderTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    WorldOptions options;
    options.extra_worldbody_xml =
        MocapProbe("marker", "type=\"sphere\" size=\"0.02\" rgba=\"1 1 1 1\"") +
        MocapProbe("plate", "type=\"box\" size=\"0.8 0.8 0.001\" rgba=\"0.6 0.6 0.6 1\"");
    world_ = new World(ScenarioFromYaml(testing::kEmptyScene), options);
    rig_ = new StereoRig(world_);
  }
  static void TearDownTestSuite() {
    delete rig_;
    delete world_;
  }
  static World* world_;
  static StereoRig* rig_;
};
World* RenderTest::world_ = nullptr;
StereoRig* RenderTest::rig_ = nullptr;

TEST_F(RenderTest, MarkedPointRendersWherePinholeModelPredicts) {
  const int marker = world_->Id(mjOBJ_GEOM, "marker");
  // Spread over the workspace, each marker clear of the table (z > radius).
  const Eigen::Vector3d points_W[] = {{0.30, 0.00, 0.05},  {0.22, 0.12, 0.03}, {0.40, -0.14, 0.10},
                                      {0.25, -0.10, 0.15}, {0.38, 0.15, 0.04}, {0.45, 0.0, 0.25}};
  double worst = 0.0;
  for (const Eigen::Vector3d& p_W : points_W) {
    PlaceMocap(world_, "marker", Pose3(Eigen::Translation3d(p_W)));
    for (int cam : {kLeft, kRight}) {
      const CameraView& view = rig_->View(cam);
      double su = 0, sv = 0, n = 0;
      for (int r = 0; r < view.images.label.rows; ++r)
        for (int c = 0; c < view.images.label.cols; ++c)
          if (view.images.label.at<int>(r, c) == marker) su += c, sv += r, n += 1;
      ASSERT_GT(n, 50) << "marker at " << p_W.transpose() << " not seen by camera " << cam;
      const Eigen::Vector2d predicted =
          SphereImageCentre(view.camera, view.X_WC.inverse() * p_W, kMarkerRadius);
      const double error = (Eigen::Vector2d(su / n, sv / n) - predicted).norm();
      worst = std::max(worst, error);
      EXPECT_LT(error, 0.25) << "camera " << cam << " point " << p_W.transpose();
      if (std::getenv("HGRASP_VERBOSE"))
        std::printf("  cam %d du %+.3f dv %+.3f n %.0f\n", cam, su / n - predicted.x(),
                    sv / n - predicted.y(), n);
    }
  }
  RecordProperty("worst_pixel_error", std::to_string(worst));
  std::printf("marker projection: worst error %.4f px over 12 views\n", worst);
  PlaceMocap(world_, "marker", Pose3(Eigen::Translation3d(0, 0, -3)));
}

TEST_F(RenderTest, DepthOfPlaneAtKnownDistance) {
  // Look straight ahead (tilt cancels the bracket's 20 deg) so the plate stands clear of the table.
  testing::SetJoint(world_, "head_tilt", -DegToRad(20));
  const int plate = world_->Id(mjOBJ_GEOM, "plate");
  double worst = 0.0;
  for (double distance : {0.40, 0.55, 0.70, 0.85, 1.00}) {
    for (int cam : {kLeft, kRight}) {
      const Pose3 X_WC = Renderer::OpticalFramePose(world_->data(), rig_->camera_id(cam));
      // The plate's front face lies in the plane z_C = distance, facing the camera.
      Pose3 X_CP = Pose3::Identity();
      X_CP.translation() = Eigen::Vector3d(0.05, 0.02, distance + 0.001);
      PlaceMocap(world_, "plate", X_WC * X_CP);
      const CameraView& view = rig_->View(cam);
      int n = 0;
      for (int r = 0; r < view.images.depth.rows; ++r)
        for (int c = 0; c < view.images.depth.cols; ++c)
          if (view.images.label.at<int>(r, c) == plate) {
            worst = std::max(worst, std::abs(view.images.depth.at<float>(r, c) - distance));
            ++n;
          }
      EXPECT_GT(n, 20000) << "distance " << distance;
    }
  }
  EXPECT_LT(worst, 0.0005);
  std::printf("plane depth: worst error %.3f mm over 0.40-1.00 m\n", 1e3 * worst);
  PlaceMocap(world_, "plate", Pose3(Eigen::Translation3d(0, 0, -3)));
}

TEST(RenderLabelsTest, EachPixelsLabelIsTheGeomAtItsDepth) {
  World world(ScenarioFromYaml(R"(name: labels
objects:
  - {name: a, shape: box, size: [0.06, 0.09, 0.12], position: [0.30, 0.06], yaw_deg: 25, color: [0.95, 0.85, 0.1]}
  - {name: b, shape: box, size: [0.10, 0.05, 0.05], position: [0.26, -0.09], yaw_deg: -10, color: [0.1, 0.3, 0.9]}
)"));
  StereoRig rig(&world);
  const mjtByte visible[mjNGROUP] = {1, 1, 1, 0, 0, 0};  // what the renderer shows
  for (int cam : {kLeft, kRight}) {
    const CameraView& view = rig.View(cam);
    const Eigen::Vector3d origin = view.X_WC.translation();
    int labelled = 0, agree = 0, background = 0;
    double worst_depth = 0;
    for (int r = 0; r < view.images.label.rows; ++r) {
      for (int c = 0; c < view.images.label.cols; ++c) {
        const int label = view.images.label.at<int>(r, c);
        const float z = view.images.depth.at<float>(r, c);
        ASSERT_EQ(label < 0, z <= 0)
            << "label and depth disagree on emptiness at " << r << "," << c;
        if (label < 0) {
          ++background;
          continue;
        }
        ++labelled;
        const Eigen::Vector3d ray_C = view.camera.Ray(c, r);
        const Eigen::Vector3d dir_W = (view.X_WC.linear() * ray_C).normalized();
        int geom = -1;
        const double hit =
            mj_ray(world.model(), world.data(), origin.data(), dir_W.data(), visible, 1, -1, &geom);
        if (geom != label) continue;
        ++agree;
        // Depth is exact for flat geoms; curved ones are tessellated by the renderer.
        if (world.model()->geom_type[geom] != mjGEOM_BOX) continue;
        const double z_ray = hit / ray_C.norm();  // distance along the ray -> optical-axis depth
        worst_depth = std::max(worst_depth, std::abs(z_ray - z));
      }
    }
    const double fraction = static_cast<double>(agree) / labelled;
    std::printf(
        "camera %d: %d labelled pixels, %.3f%% agree with ray casts, worst depth on boxes %.4f "
        "mm\n",
        cam, labelled, 100 * fraction, 1e3 * worst_depth);
    // Curved geoms (robot capsules) are tessellated by the renderer: their outlines may differ
    // from the exact ray cast by a pixel.
    EXPECT_GT(fraction, 0.995);
    EXPECT_LT(worst_depth, 0.0005);
  }
}

// The colour-only path (the servo's frames) gives the full render's pixels but along the
// shadows' edges (its shadow map is coarser).
TEST(RenderColorTest, ColourOnlyRenderMatchesFullRendersColour) {
  World world(ScenarioFromYaml(R"(name: colour
objects:
  - {name: a, shape: box, size: [0.06, 0.09, 0.12], position: [0.30, 0.06], yaw_deg: 25, color: [0.95, 0.85, 0.1]}
)"));
  StereoRig rig(&world);
  for (int cam : {kLeft, kRight}) {
    const cv::Mat color = rig.renderer().RenderColor(world.data(), rig.camera_id(cam));
    const cv::Mat full = rig.renderer().Render(world.data(), rig.camera_id(cam)).color;
    ASSERT_EQ(color.size(), full.size());
    cv::Mat diff;
    cv::absdiff(color, full, diff);
    cv::Mat grey;
    cv::cvtColor(diff, grey, cv::COLOR_BGR2GRAY);
    const double off = cv::countNonZero(grey > 8) / static_cast<double>(grey.total());
    std::printf("camera %d: mean difference %.3f grey levels, %.2f %% of pixels beyond 8\n", cam,
                cv::mean(grey)[0], 100.0 * off);
    EXPECT_LT(cv::mean(grey)[0], 0.5) << "camera " << cam;
    EXPECT_LT(off, 0.01) << "camera " << cam;
    EXPECT_GT(cv::norm(color, cv::NORM_L1), 0.0);
  }
  // Exposures with the laser off come from colour-only renders.
  rig.Expose(0);
  EXPECT_EQ(rig.full_renders(), 0);
  EXPECT_EQ(rig.color_renders(), 2);
}

// A frame of 4 samples a pixel is the 2x2 average of the frame rendered at twice the resolution
// (pixel for pixel, but for rounding: the blocks sit on the pixels the intrinsics describe), and
// differs from the one-sample frame only along edges, where it takes the greys between.
TEST(RenderColorTest, FourSamplesAPixelAverageTheFrameAtTwiceTheResolution) {
  World world(ScenarioFromYaml(R"(name: colour
objects:
  - {name: a, shape: box, size: [0.06, 0.09, 0.12], position: [0.30, 0.06], yaw_deg: 25, color: [0.95, 0.85, 0.1]}
)"));
  const mjModel* m = world.model();
  Renderer one(m, 320, 240, 1), four(m, 320, 240, 4), twice(m, 640, 480, 1);
  EXPECT_THROW(Renderer(m, 320, 240, 2), std::invalid_argument);
  const int camera = world.Id(mjOBJ_CAMERA, "camera_left");
  const cv::Mat sampled = four.RenderColor(world.data(), camera);
  const cv::Mat fine = twice.RenderColor(world.data(), camera);
  const cv::Mat single = one.RenderColor(world.data(), camera);
  ASSERT_EQ(sampled.size(), cv::Size(320, 240));
  cv::Mat fine16, averaged;
  fine.convertTo(fine16, CV_32FC3);
  cv::resize(fine16, averaged, sampled.size(), 0, 0, cv::INTER_AREA);
  cv::Mat sampled32;
  sampled.convertTo(sampled32, CV_32FC3);
  EXPECT_LE(cv::norm(sampled32, averaged, cv::NORM_INF), 0.51);
  cv::Mat diff, grey;
  cv::absdiff(sampled, single, diff);
  cv::cvtColor(diff, grey, cv::COLOR_BGR2GRAY);
  const double edges = cv::countNonZero(grey > 8) / static_cast<double>(grey.total());
  std::printf("4 samples a pixel: %.2f %% of pixels differ from one sample's by more than 8\n",
              100.0 * edges);
  EXPECT_GT(edges, 0.0005);  // the box's and the table's edges
  EXPECT_LT(edges, 0.05);
  EXPECT_LT(cv::mean(grey)[0], 1.0);
}

// The colour-only render leaves out the geoms that cannot change it (out of view, and no shadow
// on what is in view): its image is the one that draws them all, pixel for pixel, with the arms
// and the head anywhere within a fifth of their ranges around home and the LEDs switched at
// random (the arms in and out of view, shadows cast into it from out of view).
TEST(RenderColorTest, CulledRenderIsTheFullRenderPixelForPixel) {
  World world(ScenarioFromYaml(R"(name: culling
wall: {x: 0.9}
objects:
  - {name: a, shape: box, size: [0.06, 0.09, 0.12], position: [0.30, 0.06], yaw_deg: 25, color: [0.95, 0.85, 0.1]}
  - {name: b, shape: box, size: [0.10, 0.05, 0.05], position: [0.26, -0.09], yaw_deg: -10, color: [0.1, 0.3, 0.9], specular: true}
)"));
  StereoRig rig(&world);
  Renderer& renderer = rig.renderer();
  const mjModel* m = world.model();
  mjData* d = world.data();
  const std::vector<double> home(d->qpos, d->qpos + m->nq);
  std::mt19937 rng(7);
  int culled = 0, renders = 0;
  for (int pose = 0; pose < 40; ++pose) {
    for (int j = 0; j < m->njnt; ++j) {
      if (m->jnt_type[j] == mjJNT_FREE || !m->jnt_limited[j]) continue;
      const double lo = m->jnt_range[2 * j], hi = m->jnt_range[2 * j + 1];
      const double q = home[m->jnt_qposadr[j]], spread = 0.2 * (hi - lo);
      d->qpos[m->jnt_qposadr[j]] = std::uniform_real_distribution<double>(
          std::max(lo, q - spread), std::min(hi, q + spread))(rng);
    }
    for (const char* side : {"left", "right"}) {
      for (int i = 0; i < world.LedCount(side); ++i) world.SetLed(side, i, rng() % 2 == 0);
    }
    mj_forward(m, d);
    for (int cam : {kLeft, kRight}) {
      renderer.set_culling_enabled(false);
      const cv::Mat all = renderer.RenderColor(d, rig.camera_id(cam));
      EXPECT_EQ(renderer.culled_geoms(), 0);
      renderer.set_culling_enabled(true);
      const cv::Mat culled_image = renderer.RenderColor(d, rig.camera_id(cam));
      culled += renderer.culled_geoms();
      ++renders;
      ASSERT_EQ(cv::norm(all, culled_image, cv::NORM_INF), 0)
          << "pose " << pose << ", camera " << cam;
    }
  }
  std::printf("culling: %.1f of %d geoms left out per render on average\n",
              static_cast<double>(culled) / renders, m->ngeom);
  EXPECT_GT(culled, 10 * renders);  // most of the robot is out of view
}

// Mesa's software renderer works in the thread that renders (LP_NUM_THREADS=0, set by
// egl_context.cc unless the environment sets it): no rasteriser threads beside it.
TEST(RenderColorTest, TheSoftwareRendererMakesNoThreadsOfItsOwn) {
  const char* preset = std::getenv("LP_NUM_THREADS");
  ASSERT_NE(preset, nullptr);
  World world(ScenarioFromYaml(testing::kEmptyScene));
  StereoRig rig(&world);
  rig.Expose(0);
  if (rig.renderer().DeviceDescription().find("llvmpipe") == std::string::npos) {
    GTEST_SKIP() << "not Mesa's software renderer: " << rig.renderer().DeviceDescription();
  }
  int llvmpipe_threads = 0;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream comm(task.path() / "comm");
    std::string name;
    std::getline(comm, name);
    llvmpipe_threads += name.rfind("llvmpipe", 0) == 0;
  }
  EXPECT_STREQ(preset, "0");
  EXPECT_EQ(llvmpipe_threads, 0);
}

}  // namespace
}  // namespace hgrasp::sim
