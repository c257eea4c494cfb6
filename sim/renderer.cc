#include "sim/renderer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <vector>

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

// ---- Culling: the geoms that cannot change a colour render are left out of it ----
//
// MuJoCo draws every geom of the scene three times per camera (the lit pass, the light's shadow
// map, the shadowed pass), and in Mesa's software renderer a geom costs its vertices' work even
// where the camera does not see it (most of the robot: left out, the servo's frames render in
// about two thirds of the time). A geom can change the
// image only (1) by its own fragments, when it is in the camera's view, or (2) through the shadow
// map, when its texels there are read by a fragment the camera sees: a geom out of view whose
// footprint in the shadow map (seen from the light) is clear of every footprint of what the
// camera can see leaves every pixel as it was. Both tests below are conservative (boxes around
// the geoms, frusta and footprints grown by margins), so a culled render equals the full one
// pixel for pixel (tests/sim/render_test.cc compares them).

// A box in W that holds all a scene geom draws: centre, unit axes, half extents (m).
struct GeomBox {
  Eigen::Vector3d centre;
  std::array<Eigen::Vector3d, 3> axis;
  Eigen::Vector3d half;

  Eigen::Vector3d Corner(int k) const {  // bit i of k: the + or - side along axis i
    Eigen::Vector3d p = centre;
    for (int i = 0; i < 3; ++i) p += (((k >> i) & 1) ? half[i] : -half[i]) * axis[i];
    return p;
  }
  bool Contains(const Eigen::Vector3d& p) const {
    for (int i = 0; i < 3; ++i) {
      if (std::abs((p - centre).dot(axis[i])) > half[i]) return false;
    }
    return true;
  }
};

// The bounding box of a model geom as MuJoCo draws it (its tessellated curved surfaces lie inside
// the exact ones), grown by 1 % + 1 mm; nullopt for what has no known extent (planes, decor).
std::optional<GeomBox> BoundingBox(const mjvGeom& g) {
  if (g.objtype != mjOBJ_GEOM) return std::nullopt;
  Eigen::Vector3d half(g.size[0], g.size[1], g.size[2]);
  switch (g.type) {
    case mjGEOM_BOX:
    case mjGEOM_SPHERE:
    case mjGEOM_ELLIPSOID:
    case mjGEOM_CYLINDER:
      break;
    case mjGEOM_CAPSULE:  // the end caps' radius is the mean of the two sizes
      half.z() += 0.5 * (half.x() + half.y());
      break;
    case mjGEOM_MESH:
      if (!(g.modelrbound > 0)) return std::nullopt;
      half.setConstant(g.modelrbound);
      break;
    default:
      return std::nullopt;
  }
  GeomBox b;
  b.centre = Eigen::Vector3d(g.pos[0], g.pos[1], g.pos[2]);
  for (int i = 0; i < 3; ++i) b.axis[i] = Eigen::Vector3d(g.mat[i], g.mat[3 + i], g.mat[6 + i]);
  b.half = 1.01 * half + Eigen::Vector3d::Constant(1e-3);
  return b;
}

// n.p + d >= 0 inside.
struct HalfSpace {
  Eigen::Vector3d n;
  double d;
  double Eval(const Eigen::Vector3d& p) const { return n.dot(p) + d; }
};

// The vertices of the convex set box ∩ (all of `inside`): each face of the box clipped by every
// half-space (Sutherland-Hodgman), plus those of `corners` (the half-spaces' own vertices) that lie
// in the box. Empty when the two do not meet.
std::vector<Eigen::Vector3d> ClipBox(const GeomBox& box, const std::vector<HalfSpace>& inside,
                                     const std::vector<Eigen::Vector3d>& corners) {
  constexpr int kQuad[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};  // a face's corners in order
  std::vector<Eigen::Vector3d> out, polygon, next;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      polygon.clear();
      for (const auto& q : kQuad) {
        polygon.push_back(box.Corner(side << axis | q[0] << u | q[1] << v));
      }
      for (const HalfSpace& h : inside) {
        next.clear();
        for (size_t i = 0; i < polygon.size(); ++i) {
          const Eigen::Vector3d& p = polygon[i];
          const Eigen::Vector3d& q = polygon[(i + 1) % polygon.size()];
          const double fp = h.Eval(p), fq = h.Eval(q);
          if (fp >= 0) next.push_back(p);
          if ((fp >= 0) != (fq >= 0)) next.push_back(p + (q - p) * (fp / (fp - fq)));
        }
        polygon.swap(next);
        if (polygon.empty()) break;
      }
      out.insert(out.end(), polygon.begin(), polygon.end());
    }
  }
  for (const Eigen::Vector3d& p : corners) {
    if (box.Contains(p)) out.push_back(p);
  }
  return out;
}

// An axis-aligned rectangle of the light's image plane.
struct Footprint {
  double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL;
  void Add(double x, double y) {
    x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
  }
  bool Overlaps(const Footprint& o, double margin) const {
    return x0 - margin <= o.x1 && o.x0 <= x1 + margin && y0 - margin <= o.y1 && o.y0 <= y1 + margin;
  }
};

// Leaves out of `scene` (as mjv_updateScene made it for a render of width/height `aspect`) the
// geoms that cannot change the colour render through `context`, keeping the others in order;
// returns how many it left out.
int CullScene(mjvScene* scene, const mjrContext& context, double aspect) {
  const int n = scene->ngeom;
  // A mirror shows what the camera does not: no culling with reflections.
  if (scene->flags[mjRND_REFLECTION]) {
    for (int i = 0; i < n; ++i) {
      const mjvGeom& g = scene->geoms[i];
      if ((g.type == mjGEOM_PLANE || g.type == mjGEOM_BOX) && g.reflectance > 0) return 0;
    }
  }
  // The camera's frustum as mjr_render sets it up (the mean of the scene's two cameras; the
  // horizontal extent from the aspect), its sides opened by 5 % of its width and height.
  const mjvGLCamera cam = mjv_averageCamera(&scene->camera[0], &scene->camera[1]);
  const Eigen::Vector3d eye(cam.pos[0], cam.pos[1], cam.pos[2]);
  const Eigen::Vector3d forward =
      Eigen::Vector3d(cam.forward[0], cam.forward[1], cam.forward[2]).normalized();
  const Eigen::Vector3d up = Eigen::Vector3d(cam.up[0], cam.up[1], cam.up[2]).normalized();
  const Eigen::Vector3d right = forward.cross(up).normalized();
  const double half_width = 0.5 * aspect * (cam.frustum_top - cam.frustum_bottom);
  // Slopes x/z and y/z of the frustum's sides.
  double sx[2] = {(cam.frustum_center - half_width) / cam.frustum_near,
                  (cam.frustum_center + half_width) / cam.frustum_near};
  double sy[2] = {cam.frustum_bottom / cam.frustum_near, cam.frustum_top / cam.frustum_near};
  const double grow_x = 0.05 * (sx[1] - sx[0]), grow_y = 0.05 * (sy[1] - sy[0]);
  sx[0] -= grow_x, sx[1] += grow_x, sy[0] -= grow_y, sy[1] += grow_y;
  const double z_near = 0.999 * cam.frustum_near, z_far = 1.001 * cam.frustum_far;
  const auto side = [&](const Eigen::Vector3d& normal, double offset) {
    return HalfSpace{normal, offset - normal.dot(eye)};
  };
  const std::vector<HalfSpace> frustum = {
      side(right - sx[0] * forward, 0), side(sx[1] * forward - right, 0),
      side(up - sy[0] * forward, 0),    side(sy[1] * forward - up, 0),
      side(forward, -z_near),           side(-forward, z_far)};
  std::vector<Eigen::Vector3d> frustum_corners;
  for (const double z : {z_near, z_far}) {
    for (const double a : sx) {
      for (const double b : sy) frustum_corners.push_back(eye + z * (forward + a * right + b * up));
    }
  }

  // In view: the geoms whose box meets the frustum; `seen` bounds what the camera can see of each
  // (all of the frustum for a geom of unknown extent).
  std::vector<std::optional<GeomBox>> box(n);
  std::vector<std::vector<Eigen::Vector3d>> seen(n);
  std::vector<char> keep(n, 0);
  for (int i = 0; i < n; ++i) {
    box[i] = BoundingBox(scene->geoms[i]);
    seen[i] = box[i] ? ClipBox(*box[i], frustum, frustum_corners) : frustum_corners;
    keep[i] = !seen[i].empty();
  }

  // Out of view but in the shadow map where a seen fragment reads it: kept too.
  std::vector<char> needed = keep;
  if (scene->flags[mjRND_SHADOW] && context.shadowFBO != 0) {
    for (int l = 0; l < std::min(mjMAXLIGHT, scene->nlight); ++l) {
      const mjvLight& light = scene->lights[l];
      if (!light.castshadow) continue;
      const Eigen::Vector3d source(light.pos[0], light.pos[1], light.pos[2]);
      const Eigen::Vector3d dir =
          Eigen::Vector3d(light.dir[0], light.dir[1], light.dir[2]).normalized();
      const Eigen::Vector3d a = dir.unitOrthogonal(), b = dir.cross(a);
      // The shadow map's projection: along dir for a directional light, from the source for a
      // spot light (whose map spans at most 160 deg, MuJoCo's cap); false for a point behind it.
      const auto footprint = [&](const std::vector<Eigen::Vector3d>& points, Footprint* f) {
        for (const Eigen::Vector3d& p : points) {
          if (light.directional) {
            f->Add(p.dot(a), p.dot(b));
            continue;
          }
          const Eigen::Vector3d q = p - source;
          const double z = q.dot(dir);
          if (z <= 1e-6) return false;
          f->Add(q.dot(a) / z, q.dot(b) / z);
        }
        return true;
      };
      // 4 texels of the map: the texture filter reads a texel beyond the sample point,
      // rasterisation rounds to texel centres. (MuJoCo draws the map 1 texel in from its edges: a
      // fragment beyond it reads edge texels that nothing is drawn into.)
      const double map_width =
          light.directional ? 2.0 * context.shadowClip : 2.0 * std::tan(DegToRad(80.0));
      const double margin = 4.0 * map_width / std::max(context.shadowSize - 2, 1);
      std::vector<Footprint> receivers;
      for (int i = 0; i < n; ++i) {
        if (!keep[i]) continue;
        Footprint f;
        if (!footprint(seen[i], &f)) return 0;  // something in view behind the light: keep all
        receivers.push_back(f);
      }
      std::vector<Eigen::Vector3d> corners(8);
      for (int i = 0; i < n; ++i) {
        if (needed[i]) continue;
        for (int k = 0; k < 8; ++k) corners[k] = box[i]->Corner(k);
        Footprint f;
        needed[i] = !footprint(corners, &f) ||
                    std::any_of(receivers.begin(), receivers.end(),
                                [&](const Footprint& r) { return f.Overlaps(r, margin); });
      }
    }
  }
  int kept = 0;
  for (int i = 0; i < n; ++i) {
    if (needed[i]) scene->geoms[kept++] = scene->geoms[i];
  }
  scene->ngeom = kept;
  return n - kept;
}

}  // namespace

Renderer::Renderer(const mjModel* model, int width, int height, int color_samples)
    : model_(model), width_(width), height_(height), egl_(SharedEglContext()) {
  if (model->vis.global.offwidth < width || model->vis.global.offheight < height) {
    throw std::runtime_error("Renderer: the model's off-screen buffer is smaller than " +
                             std::to_string(width) + " x " + std::to_string(height));
  }
  supersample_ = static_cast<int>(std::lround(std::sqrt(static_cast<double>(color_samples))));
  if (color_samples < 1 || supersample_ * supersample_ != color_samples || supersample_ > 4) {
    throw std::invalid_argument("Renderer: samples a pixel must be 1, 4, 9 or 16, not " +
                                std::to_string(color_samples));
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
  // A camera integrates the light over each pixel: the colour frames take `color_samples`
  // samples a pixel on a regular grid, rendered at supersample_ times the resolution and
  // averaged over each supersample_^2 block (whose centre is the pixel's: the intrinsics hold).
  // Supersampling rather than GL multisampling: the same samples on every GL (a multisample
  // buffer's pattern and resolve are the driver's), shading and textures sampled too.
  color_model->vis.quality.offsamples = 0;
  color_model->vis.global.offwidth =
      std::max(color_model->vis.global.offwidth, supersample_ * width);
  color_model->vis.global.offheight =
      std::max(color_model->vis.global.offheight, supersample_ * height);
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
  const int k = supersample_, w = k * width_, h = k * height_;
  const mjrRect viewport = {0, 0, w, h};
  mjv_updateScene(model_, const_cast<mjData*>(data), &option_, nullptr, &camera, mjCAT_ALL,
                  &scene_);
  egl_->MakeCurrent();
  mjr_setBuffer(mjFB_OFFSCREEN, &color_context_);
  scene_.flags[mjRND_SEGMENT] = 0;
  scene_.flags[mjRND_IDCOLOR] = 0;
  culled_geoms_ = culling_enabled_
                      ? CullScene(&scene_, color_context_, static_cast<double>(width_) / height_)
                      : 0;
  mjr_render(viewport, &scene_, &color_context_);
  if (k == 1) {
    mjr_readPixels(rgb_.data(), nullptr, viewport, &color_context_);
    cv::Mat color(height_, width_, CV_8UC3);
    for (int r = 0; r < height_; ++r) {
      const unsigned char* src = &rgb_[3 * (height_ - 1 - r) * width_];
      auto* row = color.ptr<cv::Vec3b>(r);
      for (int c = 0; c < width_; ++c) {
        row[c] = cv::Vec3b(src[3 * c + 2], src[3 * c + 1], src[3 * c]);
      }
    }
    return color;
  }
  supersampled_.resize(3 * static_cast<size_t>(w) * h);
  mjr_readPixels(supersampled_.data(), nullptr, viewport, &color_context_);
  cv::Mat color(height_, width_, CV_8UC3);
  const int n = k * k;
  for (int r = 0; r < height_; ++r) {
    auto* row = color.ptr<cv::Vec3b>(r);
    for (int c = 0; c < width_; ++c) {
      int sum[3] = {0, 0, 0};
      for (int dr = 0; dr < k; ++dr) {
        const unsigned char* src = &supersampled_[3 * ((h - 1 - (k * r + dr)) * w + k * c)];
        for (int i = 0; i < 3 * k; ++i) sum[i % 3] += src[i];
      }
      // (rounded to the nearest grey level; RGB from the buffer, BGR out)
      row[c] = cv::Vec3b((sum[2] + n / 2) / n, (sum[1] + n / 2) / n, (sum[0] + n / 2) / n);
    }
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
