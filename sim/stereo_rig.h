#pragma once
/// @file The simulated stereo head's image formation: ambient-lit scene rendered once per head
/// pose, laser stripes composited per frame, camera noise from the scenario seed.

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "sim/renderer.h"
#include "sim/stripe.h"
#include "sim/world.h"

namespace hgrasp::sim {

enum CameraIndex { kLeft = 0, kRight = 1 };

/// Both images of one exposure and the stripe crossings drawn in each.
struct StereoImages {
  std::array<cv::Mat, 2> image;  ///< (240 x 320) CV_8UC3 BGR, with stripes and noise
  std::array<std::vector<StripeCrossing>, 2> crossings;
};

class StereoRig {
 public:
  static constexpr int kWidth = 320, kHeight = 240;
  /// Fraction of a specular surface's light reflected as a mirror (the rest is diffuse).
  static constexpr double kSpecularReflectance = 0.6;

  explicit StereoRig(World* world, StripeOptics optics = {});

  /// The camera's view at the current state, rendered anew only when the scene changed (any
  /// joint but the laser's moved by more than 1 um or 1 urad since the last render, or an LED
  /// switched); with the cache off, rendered every call.
  const CameraView& View(int camera);

  /// The camera's ambient colour image at the current state (cached as View is, but rendered
  /// colour only when no full view is at hand): Expose uses it when no light sheet is lit.
  const cv::Mat& Color(int camera);

  /// The light sheets at the current state and time: our laser (when on), the scenario's
  /// interference stripes, and their mirror images in specular objects.
  std::vector<LightSheet> Sheets() const;

  /// Our laser's light plane in W at laser angle `laser_rad` with the head where it is now.
  Plane LaserPlaneAt(double laser_rad) const;
  /// The laser generator's origin (on its rotation axis) in W, now.
  Eigen::Vector3d LaserSource() const;

  /// Composes one exposure: ambient + stripes + Gaussian noise (scenario camera_noise) drawn
  /// from the scenario seed and `frame_key`, saturated to 0-255.
  StereoImages Expose(std::uint64_t frame_key);

  /// An exposure nobody looks at (a frame grabbed only to wait for a motion to end): no images.
  /// The renders Expose would make now are not made but left pending with a copy of the world's
  /// state, made from it only when a later exposure or view needs them: every later image is
  /// exactly what it would be had this been an Expose (the cache keeps a render made anywhere
  /// within its tolerance of the state it was made at). Empties last_crossings().
  void SkipExposure();

  /// The stripe crossings drawn in the last exposure, per camera (ground truth for tests).
  const std::array<std::vector<StripeCrossing>, 2>& last_crossings() const {
    return last_crossings_;
  }

  void set_cache_enabled(bool on) { cache_enabled_ = on; }
  /// Full scene renders made so far (each one renders both colour/depth and labels).
  int full_renders() const { return full_renders_; }
  /// Colour-only renders made so far.
  int color_renders() const { return color_renders_; }
  const StripeOptics& optics() const { return optics_; }
  Renderer& renderer() { return *renderer_; }
  int camera_id(int camera) const { return camera_ids_[camera]; }

 private:
  /// A copy of the world's state (mjData) for a pending render.
  using Snapshot = std::shared_ptr<mjData>;

  std::vector<double> SceneKey() const;
  /// Drops the cached and pending renders when the scene moved since they were made.
  void CheckCache();
  std::vector<double> RedReflectance() const;
  /// The world's state now, in a copy no pending render holds (reused: mj_makeData is costly).
  Snapshot TakeSnapshot();

  World* world_;
  StripeOptics optics_;
  std::unique_ptr<Renderer> renderer_;
  std::array<int, 2> camera_ids_;
  int laser_site_, laser_joint_, laser_joint_qpos_;
  std::array<CameraView, 2> views_;
  std::array<bool, 2> valid_ = {false, false};
  std::array<cv::Mat, 2> colors_;
  std::array<bool, 2> color_valid_ = {false, false};
  // Renders that skipped exposures left to be made, from the state they would have been made at.
  std::array<Snapshot, 2> pending_view_, pending_color_;
  std::vector<Snapshot> snapshots_;
  std::vector<double> key_;
  std::array<std::vector<StripeCrossing>, 2> last_crossings_;
  bool cache_enabled_ = true;
  int full_renders_ = 0;
  int color_renders_ = 0;
};

}  // namespace hgrasp::sim
