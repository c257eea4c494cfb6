#include "sim/stereo_rig.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>

namespace hgrasp::sim {
namespace {

// Points of a box face: the face's outward plane, centre and in-plane half axes.
struct Face {
  Plane plane;
  Eigen::Vector3d centre, u, v;  // u, v: half-extent vectors
  bool Contains(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d d = p - centre;
    return std::abs(d.dot(u)) <= u.squaredNorm() && std::abs(d.dot(v)) <= v.squaredNorm();
  }
};

std::vector<Face> BoxFaces(const Pose3& X_WO, const Eigen::Vector3d& size_O) {
  std::vector<Face> faces;
  const Eigen::Vector3d h = 0.5 * size_O;
  for (int axis = 0; axis < 3; ++axis) {
    for (int sign : {-1, 1}) {
      Face f;
      const Eigen::Vector3d n = sign * X_WO.linear().col(axis);
      f.centre = X_WO.translation() + h[axis] * n;
      f.plane.n = n;
      f.plane.d = -n.dot(f.centre);
      f.u = h[(axis + 1) % 3] * X_WO.linear().col((axis + 1) % 3);
      f.v = h[(axis + 2) % 3] * X_WO.linear().col((axis + 2) % 3);
      faces.push_back(f);
    }
  }
  return faces;
}

}  // namespace

StereoRig::StereoRig(World* world, StripeOptics optics)
    : world_(world),
      optics_(optics),
      renderer_(std::make_unique<Renderer>(world->model(), kWidth, kHeight,
                                           world->scenario().camera_samples)),
      camera_ids_{world->Id(mjOBJ_CAMERA, "camera_left"), world->Id(mjOBJ_CAMERA, "camera_right")},
      laser_site_(world->Id(mjOBJ_SITE, "laser_plane")),
      laser_joint_(world->Id(mjOBJ_JOINT, "laser")),
      laser_joint_qpos_(world->model()->jnt_qposadr[laser_joint_]) {}

std::vector<double> StereoRig::SceneKey() const {
  const mjModel* m = world_->model();
  std::vector<double> key(world_->data()->qpos, world_->data()->qpos + m->nq);
  // The laser generator sits above and behind the lenses, out of both views: its angle does not
  // change what the cameras see of the scene.
  key[laser_joint_qpos_] = 0.0;
  const mjData* d = world_->data();
  key.insert(key.end(), d->mocap_pos, d->mocap_pos + 3 * m->nmocap);
  key.insert(key.end(), d->mocap_quat, d->mocap_quat + 4 * m->nmocap);
  // Any LED switch changes this entry by at least 1: never within the tolerance.
  key.push_back(static_cast<double>(world_->appearance_version()));
  return key;
}

std::vector<double> StereoRig::RedReflectance() const {
  const mjModel* m = world_->model();
  std::vector<double> red(m->ngeom);
  for (int g = 0; g < m->ngeom; ++g) {
    const int mat = m->geom_matid[g];
    red[g] = mat >= 0 ? m->mat_rgba[4 * mat] : m->geom_rgba[4 * g];
  }
  for (const SimObject& o : world_->objects()) {
    if (o.spec.specular) red[o.geom] *= 1.0 - kSpecularReflectance;
  }
  return red;
}

void StereoRig::CheckCache() {
  const std::vector<double> key = SceneKey();
  // A render stays valid until something moved more than 10 um or about 10 urad (a joint angle;
  // a quaternion component) since it was made: at fy = 230 px (fovy 55 deg, 240 rows) that moves
  // a point 0.25 m from the lenses by at most 0.01 px, a point on an arm joint's 0.6 m lever
  // 6 um. Resting objects creep as their contacts converge, and a box held in the fingers creeps
  // about 1.1e-6 a frame (a coordinate of its free joint): at the earlier 1e-6 bound every frame
  // of the rise scan after the lift was rendered in full (105 stereo frames of random_5, 11 s of
  // its 16 s). Aliased edges flip the few pixels whose centres they cross (a test).
  constexpr double kStill = 1e-5;
  bool same = cache_enabled_ && key.size() == key_.size();
  for (size_t i = 0; same && i < key.size(); ++i) same = std::abs(key[i] - key_[i]) <= kStill;
  if (!same) {
    valid_ = {false, false};
    color_valid_ = {false, false};
    pending_view_ = {};
    pending_color_ = {};
    key_ = key;
  }
}

StereoRig::Snapshot StereoRig::TakeSnapshot() {
  const auto free = std::find_if(snapshots_.begin(), snapshots_.end(),
                                 [](const Snapshot& s) { return s.use_count() == 1; });
  if (free == snapshots_.end()) {
    snapshots_.emplace_back(mj_makeData(world_->model()), mj_deleteData);
    mj_copyData(snapshots_.back().get(), world_->model(), world_->data());
    return snapshots_.back();
  }
  mj_copyData(free->get(), world_->model(), world_->data());
  return *free;
}

const cv::Mat& StereoRig::Color(int camera) {
  CheckCache();
  if (valid_[camera] || pending_view_[camera]) return View(camera).images.color;
  if (!color_valid_[camera]) {
    const mjData* state = pending_color_[camera] ? pending_color_[camera].get() : world_->data();
    colors_[camera] = renderer_->RenderColor(state, camera_ids_[camera]);
    color_valid_[camera] = true;
    pending_color_[camera].reset();
    ++color_renders_;
  }
  return colors_[camera];
}

const CameraView& StereoRig::View(int camera) {
  CheckCache();
  if (!valid_[camera]) {
    const int id = camera_ids_[camera];
    const mjData* state = pending_view_[camera] ? pending_view_[camera].get() : world_->data();
    CameraImages images = renderer_->Render(state, id);
    // With more than one sample a pixel, the frames with the stripe start from the same
    // antialiased colour as the frames without it (the full render's labels and depth keep one
    // sample a pixel): else every edge would differ between a lit and a dark frame.
    if (world_->scenario().camera_samples > 1) {
      images.color = renderer_->RenderColor(state, id);
      ++color_renders_;
    }
    views_[camera] =
        CameraView::Make(renderer_->Intrinsics(id), Renderer::OpticalFramePose(state, id),
                         std::move(images), RedReflectance());
    valid_[camera] = true;
    pending_view_[camera].reset();
    ++full_renders_;
  }
  return views_[camera];
}

Eigen::Vector3d StereoRig::LaserSource() const {
  return world_->SitePose(laser_site_).translation();
}

Plane StereoRig::LaserPlaneAt(double laser_rad) const {
  // Turn the current laser site pose about the laser joint's axis by the angle difference.
  const int joint = laser_joint_;
  const double now = world_->data()->qpos[laser_joint_qpos_];
  const Eigen::Vector3d axis_W(world_->data()->xaxis[3 * joint],
                               world_->data()->xaxis[3 * joint + 1],
                               world_->data()->xaxis[3 * joint + 2]);
  const Eigen::Vector3d anchor_W(world_->data()->xanchor[3 * joint],
                                 world_->data()->xanchor[3 * joint + 1],
                                 world_->data()->xanchor[3 * joint + 2]);
  Pose3 turn = Pose3::Identity();
  turn.linear() = Eigen::AngleAxisd(laser_rad - now, axis_W.normalized()).toRotationMatrix();
  turn.translation() = anchor_W - turn.linear() * anchor_W;
  const Pose3 X_WS = turn * world_->SitePose(laser_site_);
  Plane plane;
  plane.n = X_WS.linear().col(1);  // the sheet is the x-z plane of S
  plane.d = -plane.n.dot(X_WS.translation());
  return plane;
}

std::vector<LightSheet> StereoRig::Sheets() const {
  std::vector<LightSheet> sheets;
  const World* world = world_;
  const double kHousing = 0.05;  // the generator's own housing around its origin
  if (world_->laser_on()) {
    const Eigen::Vector3d source = LaserSource();
    LightSheet own;
    own.plane_W = LaserPlaneAt(world_->data()->qpos[laser_joint_qpos_]);
    own.source_W = source;
    own.reaches = [world, source, kHousing](const Eigen::Vector3d& p) {
      return world->PathClear(p, source, kHousing);
    };
    sheets.push_back(own);
    // Mirror images in the faces of specular objects that the sheet falls on.
    for (const SimObject& o : world_->objects()) {
      if (!o.spec.specular) continue;
      for (const Face& f : BoxFaces(world_->BodyPose(o.body), o.spec.size_O)) {
        if (f.plane.SignedDistance(source) <= 0) continue;  // the face looks away
        int above = 0;
        for (int su : {-1, 1})
          for (int sv : {-1, 1})
            above += own.plane_W.SignedDistance(f.centre + su * f.u + sv * f.v) > 0;
        if (above == 0 || above == 4) continue;  // the sheet misses this face
        LightSheet mirror;
        mirror.plane_W = f.plane.Reflect(own.plane_W);
        mirror.source_W = f.plane.Reflect(source);
        mirror.gain_scale = kSpecularReflectance;
        const Eigen::Vector3d image = mirror.source_W;
        mirror.reaches = [world, f, image, source, kHousing](const Eigen::Vector3d& p) {
          const double dp = f.plane.SignedDistance(p), di = f.plane.SignedDistance(image);
          if (dp <= 1e-4 || di >= 0) return false;
          const Eigen::Vector3d hit = image + (p - image) * (di / (di - dp));  // on the mirror
          return f.Contains(hit) && world->PathClear(hit, source, kHousing) &&
                 world->PathClear(p, hit, 0.002);
        };
        sheets.push_back(mirror);
      }
    }
  }
  for (const InterferenceSpec& s : world_->scenario().interference) {
    // Angle 0 points from the source towards the middle of DESIGN.md's workspace.
    Eigen::Vector3d ahead = Eigen::Vector3d(0.30, 0.0, 0.0) - s.origin_W;
    ahead.z() = 0;
    ahead.normalize();
    const Eigen::Vector3d dir = RotZ(s.AngleAt(world_->time())) * ahead;
    LightSheet other;
    other.plane_W.n = dir.cross(Eigen::Vector3d::UnitZ()).normalized();
    other.plane_W.d = -other.plane_W.n.dot(s.origin_W);
    other.source_W = s.origin_W;
    const Eigen::Vector3d origin = s.origin_W;
    other.reaches = [world, origin](const Eigen::Vector3d& p) {
      return world->PathClear(p, origin, 0.0);
    };
    sheets.push_back(other);
  }
  return sheets;
}

StereoImages StereoRig::Expose(std::uint64_t frame_key) {
  StereoImages out;
  const std::vector<LightSheet> sheets = Sheets();
  for (int cam = 0; cam < 2; ++cam) {
    cv::Mat radiance;
    if (sheets.empty()) {
      // No light but the ambient: the colour image alone (the servo's frames, arm moving).
      Color(cam).convertTo(radiance, CV_32FC3);
    } else {
      const CameraView& view = View(cam);
      view.images.color.convertTo(radiance, CV_32FC3);
      out.crossings[cam] = AddStripes(view, sheets, optics_, &radiance);
    }
    if (world_->scenario().camera_noise > 0) {
      // One stream per scenario seed, frame and camera: the same run gives the same images.
      cv::RNG rng(world_->scenario().seed * 0x9E3779B97F4A7C15ull ^ (frame_key * 2 + cam + 1));
      cv::Mat noise(radiance.size(), CV_32FC3);
      rng.fill(noise, cv::RNG::NORMAL, 0.0, world_->scenario().camera_noise);
      radiance += noise;
    }
    radiance.convertTo(out.image[cam], CV_8UC3);  // rounds and saturates at 0 and 255
  }
  last_crossings_ = out.crossings;
  return out;
}

void StereoRig::SkipExposure() {
  // What Expose would render now: a full view when a light sheet is lit, else the colour image
  // (or the colour of a full view at hand), each only when the cache holds none.
  const bool lit = !Sheets().empty();
  CheckCache();
  Snapshot now;  // one copy of the state for both cameras
  for (int cam = 0; cam < 2; ++cam) {
    const bool view_at_hand = valid_[cam] || pending_view_[cam];
    const bool color_at_hand = view_at_hand || color_valid_[cam] || pending_color_[cam];
    if (lit ? view_at_hand : color_at_hand) continue;
    if (!now) now = TakeSnapshot();
    (lit ? pending_view_ : pending_color_)[cam] = now;
  }
  last_crossings_ = {};
}

}  // namespace hgrasp::sim
