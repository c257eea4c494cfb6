#include "sim/scan_truth.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "sim/random_scene.h"
#include "sim/truth.h"

namespace hgrasp::sim {

void ScanTruth::AddFrame(StereoRig& rig, std::int32_t encoder_count) {
  ++frames_;
  std::vector<Eigen::Vector3d>& truth = truth_[encoder_count];
  // Our own stripe (sheet 0) as the left camera drew it, kept where the right camera sees the
  // same point: its depth image at the projection agrees with the point's depth within 3 mm.
  const CameraView& right = rig.View(kRight);
  for (const StripeCrossing& x : rig.last_crossings()[kLeft]) {
    if (x.sheet != 0) continue;
    const Eigen::Vector3d p_CR = right.X_WC.inverse() * x.p_W;
    const auto uv = right.camera.Project(p_CR);
    if (!uv || !right.camera.Contains(*uv)) continue;
    const float z = right.images.depth.at<float>(static_cast<int>(std::lround(uv->y())),
                                                 static_cast<int>(std::lround(uv->x())));
    if (z > 0 && std::abs(z - p_CR.z()) < 0.003) truth.push_back(x.p_W);
  }
}

ScanTruthFigures ScanTruth::Score(const World& world, const std::vector<Point>& points,
                                  const std::vector<std::int32_t>& frame_counts) const {
  ScanTruthFigures f;
  std::vector<double> d;
  d.reserve(points.size());
  double sum2 = 0;
  std::map<std::int32_t, std::vector<const Eigen::Vector3d*>> by_frame;
  for (const Point& p : points) {
    const double e = DistanceToTrueSurface(world, p.p_W);
    d.push_back(e);
    sum2 += e * e;
    f.outliers += e > kOutlierDistanceM;
    by_frame[p.encoder_count].push_back(&p.p_W);
  }
  f.points = static_cast<int>(points.size());
  if (!d.empty()) {
    f.rms_m = std::sqrt(sum2 / d.size());
    std::sort(d.begin(), d.end());
    f.median_m = d[(d.size() - 1) / 2];
    f.p99_m = d[static_cast<size_t>(0.99 * (d.size() - 1))];
  }
  const std::set<std::int32_t> used(frame_counts.begin(), frame_counts.end());
  for (const auto& [count, truth] : truth_) {
    if (used.count(count) == 0) continue;
    const auto found = by_frame.find(count);
    for (const Eigen::Vector3d& t : truth) {
      ++f.truth_points;
      if (found == by_frame.end()) continue;
      f.covered +=
          std::any_of(found->second.begin(), found->second.end(),
                      [&](const Eigen::Vector3d* p) { return (*p - t).norm() < kCoverageRadiusM; });
    }
  }
  return f;
}

std::string_view NearestPaletteName(const Eigen::Vector3d& rgb) {
  std::string_view best;
  double best_d = std::numeric_limits<double>::infinity();
  for (const NamedColor& c : RandomScenePalette()) {
    const double d = (c.rgb - rgb).squaredNorm();
    if (d < best_d) best_d = d, best = c.name;
  }
  return best;
}

std::string_view TrueColorName(const ObjectSpec& object) {
  if (!object.color_name.empty()) return object.color_name;
  return NearestPaletteName(object.color_rgb);
}

}  // namespace hgrasp::sim
