#include "sim/renderer.h"

#include <algorithm>
#include <mutex>
#include <stdexcept>

#include "sim/egl_context.h"
#include "sim/world.h"

namespace hgrasp::sim {
namespace {

// One GL context for the process: MuJoCo's render contexts all live in it.
std::shared_ptr<EglContext> SharedEglContext() {
  static std::mutex mutex;
  static std::weak_ptr<EglContext> shared;
  std::lock_guard<std::mutex> lock(mutex);
  auto ctx = shared.lock();
  if (!ctx) {
    ctx = std::make_shared<EglContext>();
    shared = ctx;
  } else {
    ctx->MakeCurrent();
  }
  return ctx;
}

}  // namespace

Renderer::Renderer(const mjModel* model, int width, int height)
    : model_(model), width_(width), height_(height), egl_(SharedEglContext()) {
  if (model->vis.global.offwidth < width || model->vis.global.offheight < height) {
    throw std::runtime_error("Renderer: the model's off-screen buffer is smaller than " +
                             std::to_string(width) + " x " + std::to_string(height));
  }
  mjv_defaultScene(&scene_);
  mjv_defaultOption(&option_);
  mjr_defaultContext(&context_);
  // Sites, joints, frames are modelling aids, not things a camera sees.
  for (int g = 0; g < mjNGROUP; ++g) option_.sitegroup[g] = 0;
  mjv_makeScene(model, &scene_, 2000);
  mjr_makeContext(model, &context_, mjFONTSCALE_100);
  // The colour-only frames (the servo's, the arm moving every frame) render their shadows from
  // a map of at most kColorShadowSize^2 texels instead of the model's 4096^2: in Mesa's software
  // renderer the shadow pass is most of a frame's cost (a stereo frame 55 -> 26 ms), and at
  // 320 x 240 only the shadows' edges soften by a pixel or so.
  mjModel* color_model = mj_copyModel(nullptr, model);
  color_model->vis.quality.shadowsize = std::min(color_model->vis.quality.shadowsize,
                                                 kColorShadowSize);
  mjr_defaultContext(&color_context_);
  mjr_makeContext(color_model, &color_context_, mjFONTSCALE_100);
  mj_deleteModel(color_model);
  mjr_setBuffer(mjFB_OFFSCREEN, &context_);
  rgb_.resize(3 * width * height);
  depth_.resize(width * height);
}

Renderer::~Renderer() {
  mjr_freeContext(&color_context_);
  mjr_freeContext(&context_);
  mjv_freeScene(&scene_);
}

std::string Renderer::DeviceDescription() const { return egl_->description(); }

cv::Mat Renderer::RenderColor(const mjData* data, int camera_id) {
  mjvCamera camera;
  mjv_defaultCamera(&camera);
  camera.type = mjCAMERA_FIXED;
  camera.fixedcamid = camera_id;
  const mjrRect viewport = {0, 0, width_, height_};
  mjv_updateScene(model_, const_cast<mjData*>(data), &option_, nullptr, &camera, mjCAT_ALL,
                  &scene_);
  egl_->MakeCurrent();
  mjr_setBuffer(mjFB_OFFSCREEN, &color_context_);
  scene_.flags[mjRND_SEGMENT] = 0;
  scene_.flags[mjRND_IDCOLOR] = 0;
  mjr_render(viewport, &scene_, &color_context_);
  mjr_readPixels(rgb_.data(), nullptr, viewport, &color_context_);
  cv::Mat color(height_, width_, CV_8UC3);
  for (int r = 0; r < height_; ++r) {
    const unsigned char* src = &rgb_[3 * (height_ - 1 - r) * width_];
    auto* row = color.ptr<cv::Vec3b>(r);
    for (int c = 0; c < width_; ++c) row[c] = cv::Vec3b(src[3 * c + 2], src[3 * c + 1], src[3 * c]);
  }
  return color;
}

CameraImages Renderer::Render(const mjData* data, int camera_id) {
  mjvCamera camera;
  mjv_defaultCamera(&camera);
  camera.type = mjCAMERA_FIXED;
  camera.fixedcamid = camera_id;
  const mjrRect viewport = {0, 0, width_, height_};
  mjv_updateScene(model_, const_cast<mjData*>(data), &option_, nullptr, &camera, mjCAT_ALL,
                  &scene_);

  // Several renderers share the process's GL context: bind this one's off-screen buffer.
  egl_->MakeCurrent();
  mjr_setBuffer(mjFB_OFFSCREEN, &context_);

  CameraImages out;
  out.color.create(height_, width_, CV_8UC3);
  out.depth.create(height_, width_, CV_32F);
  out.label.create(height_, width_, CV_32S);

  // Colour and depth. OpenGL rows run bottom to top: flip while copying.
  scene_.flags[mjRND_SEGMENT] = 0;
  scene_.flags[mjRND_IDCOLOR] = 0;
  mjr_render(viewport, &scene_, &context_);
  mjr_readPixels(rgb_.data(), depth_.data(), viewport, &context_);
  const double extent = model_->stat.extent;
  const double znear = model_->vis.map.znear * extent;
  const double zfar = model_->vis.map.zfar * extent;
  for (int r = 0; r < height_; ++r) {
    const int src = (height_ - 1 - r) * width_;
    auto* color_row = out.color.ptr<cv::Vec3b>(r);
    auto* depth_row = out.depth.ptr<float>(r);
    for (int c = 0; c < width_; ++c) {
      const unsigned char* p = &rgb_[3 * (src + c)];
      color_row[c] = cv::Vec3b(p[2], p[1], p[0]);
      const double d = depth_[src + c];
      // Inverse of OpenGL's perspective depth mapping; d = 1 is the far plane: no surface.
      depth_row[c] =
          d >= 1.0 ? 0.0f : static_cast<float>(znear * zfar / (zfar - d * (zfar - znear)));
    }
  }

  // Labels: MuJoCo's segmentation render colours each scene geom with its index + 1.
  scene_.flags[mjRND_SEGMENT] = 1;
  scene_.flags[mjRND_IDCOLOR] = 1;
  mjr_render(viewport, &scene_, &context_);
  mjr_readPixels(rgb_.data(), nullptr, viewport, &context_);
  scene_.flags[mjRND_SEGMENT] = 0;
  scene_.flags[mjRND_IDCOLOR] = 0;
  for (int r = 0; r < height_; ++r) {
    const int src = (height_ - 1 - r) * width_;
    auto* label_row = out.label.ptr<int>(r);
    for (int c = 0; c < width_; ++c) {
      const unsigned char* p = &rgb_[3 * (src + c)];
      const int segid = (p[0] | (p[1] << 8) | (p[2] << 16)) - 1;
      int geom = -1;
      if (segid >= 0 && segid < scene_.ngeom && scene_.geoms[segid].objtype == mjOBJ_GEOM) {
        geom = scene_.geoms[segid].objid;
      }
      label_row[c] = geom;
    }
  }
  return out;
}

PinholeCamera Renderer::Intrinsics(int camera_id) const {
  return PinholeCamera::FromFovy(width_, height_, DegToRad(model_->cam_fovy[camera_id]));
}

Pose3 Renderer::OpticalFramePose(const mjData* data, int camera_id) {
  // MuJoCo cameras look along their -z with y up; the optical frame flips y and z.
  Pose3 X_WC = PoseFromMujoco(data->cam_xpos + 3 * camera_id, data->cam_xmat + 9 * camera_id);
  X_WC.linear() = X_WC.linear() * Eigen::Vector3d(1, -1, -1).asDiagonal();
  return X_WC;
}

}  // namespace hgrasp::sim
