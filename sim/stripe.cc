#include "sim/stripe.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace hgrasp::sim {
namespace {

double Phi(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

// Depth step between pixels c and c+1 of a row that still counts as one surface.
bool Continuous(const float* z, int width, int c, const StripeOptics& optics) {
  const double step = std::abs(z[c + 1] - z[c]);
  double neighbour = 0.0;
  bool any = false;
  if (c > 0 && z[c - 1] > 0) {
    neighbour = std::max(neighbour, static_cast<double>(std::abs(z[c] - z[c - 1])));
    any = true;
  }
  if (c + 2 < width && z[c + 2] > 0) {
    neighbour = std::max(neighbour, static_cast<double>(std::abs(z[c + 2] - z[c + 1])));
    any = true;
  }
  return step <= (any ? optics.jump_factor * neighbour : 0.0) + optics.jump_slack_m;
}

}  // namespace

CameraView CameraView::Make(const PinholeCamera& camera, const Pose3& X_WC, CameraImages images,
                            std::vector<double> red_reflectance) {
  CameraView v;
  v.camera = camera;
  v.X_WC = X_WC;
  v.images = std::move(images);
  v.red_reflectance = std::move(red_reflectance);
  const int h = v.images.depth.rows, w = v.images.depth.cols;
  v.points_W = cv::Mat(h, w, CV_64FC3, cv::Scalar::all(0));
  v.normals_W = cv::Mat(h, w, CV_64FC3, cv::Scalar::all(0));
  for (int r = 0; r < h; ++r) {
    const float* z = v.images.depth.ptr<float>(r);
    auto* p = v.points_W.ptr<cv::Vec3d>(r);
    for (int c = 0; c < w; ++c) {
      if (z[c] <= 0) continue;
      const Eigen::Vector3d p_W = X_WC * (camera.Ray(c, r) * z[c]);
      p[c] = cv::Vec3d(p_W.x(), p_W.y(), p_W.z());
    }
  }
  // Normals from the neighbour on the side with the smaller depth step, so that a pixel next
  // to an edge takes the normal of its own surface.
  const Eigen::Vector3d camera_W = X_WC.translation();
  auto point = [&](int r, int c) {
    const cv::Vec3d& q = v.points_W.at<cv::Vec3d>(r, c);
    return Eigen::Vector3d(q[0], q[1], q[2]);
  };
  auto depth = [&](int r, int c) { return v.images.depth.at<float>(r, c); };
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      const float z = depth(r, c);
      if (z <= 0) continue;
      auto pick = [&](int dr, int dc) -> std::optional<Eigen::Vector3d> {
        const int r0 = r - dr, c0 = c - dc, r1 = r + dr, c1 = c + dc;
        const bool lo = r0 >= 0 && c0 >= 0 && depth(r0, c0) > 0;
        const bool hi = r1 < h && c1 < w && depth(r1, c1) > 0;
        if (!lo && !hi) return std::nullopt;
        const double step_lo = lo ? std::abs(depth(r0, c0) - z) : 1e9;
        const double step_hi = hi ? std::abs(depth(r1, c1) - z) : 1e9;
        return step_hi <= step_lo ? point(r1, c1) - point(r, c) : point(r, c) - point(r0, c0);
      };
      const auto du = pick(0, 1), dv = pick(1, 0);
      if (!du || !dv) continue;
      Eigen::Vector3d n = du->cross(*dv);
      if (n.norm() < 1e-12) continue;
      n.normalize();
      if (n.dot(camera_W - point(r, c)) < 0) n = -n;
      v.normals_W.at<cv::Vec3d>(r, c) = cv::Vec3d(n.x(), n.y(), n.z());
    }
  }
  return v;
}

std::vector<StripeCrossing> AddStripes(const CameraView& view,
                                       const std::vector<LightSheet>& sheets,
                                       const StripeOptics& optics, cv::Mat* radiance) {
  std::vector<StripeCrossing> crossings;
  const PinholeCamera& cam = view.camera;
  const int h = view.images.depth.rows, w = view.images.depth.cols;
  const Pose3 X_CW = view.X_WC.inverse();
  const double norm = std::sqrt(2.0 * kPi);
  for (size_t sheet_index = 0; sheet_index < sheets.size(); ++sheet_index) {
    const LightSheet& sheet = sheets[sheet_index];
    const Plane plane_C = sheet.plane_W.TransformedBy(X_CW);
    if (std::abs(plane_C.d) < 1e-9) continue;  // the camera centre lies in the sheet: edge-on
    for (int r = 0; r < h; ++r) {
      const float* z = view.images.depth.ptr<float>(r);
      const int* label = view.images.label.ptr<int>(r);
      // n.ray(u) = a*u + b along this row, with ray = ((u-cx)/fx, (r-cy)/fy, 1).
      const double a = plane_C.n.x() / cam.fx;
      const double b = plane_C.n.y() * (r - cam.cy) / cam.fy + plane_C.n.z() - a * cam.cx;
      // g(u) = 1/z(u) + n.ray(u)/d is zero where the surface meets the sheet; along a row of a
      // plane both terms are linear in u, so the root between two pixels is exact for planes.
      auto g = [&](int c) { return 1.0 / z[c] + (a * c + b) / plane_C.d; };
      // Each pixel's g is computed once: the right end of one pair is the left end of the next.
      double g1 = w > 0 && z[0] > 0 ? g(0) : 0.0;
      for (int c = 0; c + 1 < w; ++c) {
        const double g0 = g1;
        g1 = z[c + 1] > 0 ? g(c + 1) : 0.0;
        if (z[c] <= 0 || z[c + 1] <= 0) continue;
        if ((g0 > 0) == (g1 > 0)) continue;
        if (!Continuous(z, w, c, optics)) continue;
        const double t = g0 / (g0 - g1);
        const double u = c + t;
        const Eigen::Vector3d ray = cam.Ray(u, r);
        const Eigen::Vector3d p_C = ray * (-plane_C.d / plane_C.n.dot(ray));
        const Eigen::Vector3d p_W = view.X_WC * p_C;
        const int nearest = t < 0.5 ? c : c + 1;
        const int geom = label[nearest];
        if (geom < 0 || geom >= static_cast<int>(view.red_reflectance.size())) continue;
        if (sheet.reaches && !sheet.reaches(p_W)) continue;

        const cv::Vec3d& nv = view.normals_W.at<cv::Vec3d>(r, nearest);
        const Eigen::Vector3d to_source = sheet.source_W - p_W;
        const double range = to_source.norm();
        const double cos_incidence =
            std::abs(Eigen::Vector3d(nv[0], nv[1], nv[2]).dot(to_source)) / range;
        // Width: the sheet's thickness as it lies across the surface, seen from the camera.
        auto plane_distance = [&](int k) {
          const cv::Vec3d& q = view.points_W.at<cv::Vec3d>(r, k);
          return sheet.plane_W.SignedDistance(Eigen::Vector3d(q[0], q[1], q[2]));
        };
        const double s0 = plane_distance(c), s1 = plane_distance(c + 1);
        const double sigma_sheet_px =
            std::min(optics.sheet_sigma_m / std::max(std::abs(s1 - s0), 1e-9), 20.0);
        const double sigma = std::hypot(sigma_sheet_px, optics.psf_sigma_px);
        // Radiance of a Lambertian surface lit by a fan of light: falls as 1/range, follows the
        // cosine of incidence and the red reflectance; the lens blur spreads it (energy kept).
        const double peak = optics.gain * sheet.gain_scale * view.red_reflectance[geom] *
                            cos_incidence * (optics.reference_range_m / range) *
                            (sigma_sheet_px / sigma);
        crossings.push_back({static_cast<int>(sheet_index), r, u, p_W, peak, sigma});
        if (radiance == nullptr || peak <= 0) continue;

        // Draw across the pixels of the same surface around the crossing.
        auto* out = radiance->ptr<cv::Vec3f>(r);
        const int reach = static_cast<int>(std::ceil(4.0 * sigma)) + 1;
        auto draw = [&](int k) {
          const double v =
              peak * norm * sigma * (Phi((k + 0.5 - u) / sigma) - Phi((k - 0.5 - u) / sigma));
          for (int ch = 0; ch < 3; ++ch)
            out[k][ch] += static_cast<float>(v * optics.channel_response[ch]);
        };
        draw(nearest);
        for (int k = nearest + 1; k < w && k <= nearest + reach; ++k) {
          if (z[k] <= 0 || !Continuous(z, w, k - 1, optics)) break;
          draw(k);
        }
        for (int k = nearest - 1; k >= 0 && k >= nearest - reach; --k) {
          if (z[k] <= 0 || !Continuous(z, w, k, optics)) break;
          draw(k);
        }
      }
    }
  }
  return crossings;
}

}  // namespace hgrasp::sim
