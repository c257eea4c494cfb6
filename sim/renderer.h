#pragma once
/// @file Off-screen rendering of MuJoCo cameras: colour, metric depth and per-pixel labels.

#include <mujoco/mujoco.h>

#include <memory>
#include <opencv2/core/mat.hpp>
#include <string>

#include "common/geometry.h"
#include "common/pinhole_camera.h"

namespace hgrasp::sim {

class EglContext;

/// What one camera sees of the ambient-lit scene (no laser light, no noise).
struct CameraImages {
  cv::Mat color;  ///< (H x W) CV_8UC3, BGR
  cv::Mat depth;  ///< (H x W) CV_32F, z of the surface along the optical axis (m); 0: nothing
  cv::Mat label;  ///< (H x W) CV_32S, MuJoCo geom id of the surface; -1: nothing
};

/// Renders the cameras of one model through a process-wide EGL context (GPU device when there
/// is one, Mesa's software renderer otherwise). Not thread-safe; one per model.
class Renderer {
 public:
  /// @param model  the model whose cameras are rendered; must outlive the renderer and allow
  ///               an off-screen buffer of at least width x height (visual/global/offwidth).
  /// @param color_samples  samples a pixel of the colour-only renders (RenderColor), on a
  ///               regular grid: 1, 4, 9 or 16 (Scenario::camera_samples); more than 1
  ///               antialiases edges as a sensor's pixel does. Throws std::invalid_argument
  ///               otherwise.
  Renderer(const mjModel* model, int width, int height, int color_samples = 1);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Renders camera `camera_id` of the model in state `data` (kinematics must be current).
  CameraImages Render(const mjData* data, int camera_id);

  /// Colour only (one render pass, no depth read-back, shadows from a map of at most
  /// kColorShadowSize^2 texels): what a camera sees when no light sheet needs the scene's
  /// geometry, at about a third of Render's cost. Draws only the geoms that can change the image
  /// (in view, or casting a shadow on what is in view): the same pixels as drawing them all.
  cv::Mat RenderColor(const mjData* data, int camera_id);

  /// Whether RenderColor leaves out the geoms that cannot change its image (default on; off, it
  /// draws them all: the reference the tests compare with).
  void set_culling_enabled(bool on) { culling_enabled_ = on; }
  /// Geoms the last RenderColor left out.
  int culled_geoms() const { return culled_geoms_; }

  /// Intrinsics of camera `camera_id` for this renderer's image size (from cam_fovy).
  PinholeCamera Intrinsics(int camera_id) const;

  /// Pose X_WC of the camera's optical frame C (x right, y down, z forward) in state `data`.
  static Pose3 OpticalFramePose(const mjData* data, int camera_id);

  /// What renders: "EGL device 0 (...)" or "Mesa surfaceless (llvmpipe ...)".
  std::string DeviceDescription() const;

  /// Largest shadow map of the colour-only renders (texels a side).
  static constexpr int kColorShadowSize = 1024;

  int width() const { return width_; }
  int height() const { return height_; }

 private:
  const mjModel* model_;
  int width_, height_;
  std::shared_ptr<EglContext> egl_;
  mjvScene scene_;
  mjvOption option_;
  mjrContext context_;
  mjrContext color_context_;  // the same, with a smaller shadow map (RenderColor)
  int supersample_ = 1;  // RenderColor renders at this many times the resolution a side
  std::vector<unsigned char> rgb_;
  std::vector<unsigned char> supersampled_;
  std::vector<float> depth_;
  bool culling_enabled_ = true;
  int culled_geoms_ = 0;
};

}  // namespace hgrasp::sim
