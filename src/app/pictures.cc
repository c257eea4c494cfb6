#include "app/pictures.h"

#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>
#include <unordered_map>

namespace hgrasp::app {
namespace {

/// A saturated colour for region number k: hues spread by the golden angle.
cv::Vec3b RegionColour(int k) {
  const double hue = std::fmod(k * 137.50776405, 360.0);
  cv::Mat hsv(1, 1, CV_8UC3, cv::Scalar(hue / 2.0, 220, 255)), bgr;
  cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
  return bgr.at<cv::Vec3b>(0, 0);
}

}  // namespace

cv::Mat SegmentsPicture(const segment::SegmentResult& s, const segment::Grouping& g,
                        const scan::RangeImage& range, const PinholeCamera& camera) {
  const int k = kPictureScale;
  cv::Mat out(camera.height * k, camera.width * k, CV_8UC3, cv::Scalar::all(0));
  std::unordered_map<int, cv::Vec3b> colour;
  for (int id : g.floor_or_wall) colour[id] = cv::Vec3b(90, 90, 90);
  int n = 0;
  for (const std::vector<int>& object : g.objects) {
    for (int id : object) colour[id] = RegionColour(n++);
  }
  for (int r = 0; r < range.rows(); ++r) {
    for (int c = 0; c < range.cols(); ++c) {
      const scan::RangeCell& cell = range.at(r, c);
      if (!cell.valid) continue;
      const auto uv = camera.Project(cell.p_C);
      if (!uv) continue;
      const int id = s.labels[r * s.cols + c];
      const auto it = colour.find(id);
      const cv::Vec3b col = it != colour.end() ? it->second : cv::Vec3b(40, 40, 40);
      // The pixel centre (u, v) covers [u - 0.5, u + 0.5] of the camera image.
      const int x0 = static_cast<int>(std::floor((uv->x() + 0.5) * k));
      const int y0 = static_cast<int>(std::floor((uv->y() + 0.5) * k));
      for (int y = y0 - 1; y <= y0 + 1; ++y) {
        for (int x = x0 - 1; x <= x0 + 1; ++x) {
          if (x >= 0 && y >= 0 && x < out.cols && y < out.rows) out.at<cv::Vec3b>(y, x) = col;
        }
      }
    }
  }
  return out;
}

cv::Mat ModelsPicture(const cv::Mat& ambient_bgr, const PinholeCamera& camera, const Pose3& X_CW,
                      const std::vector<model::BoxModel>& boxes,
                      const std::vector<std::vector<model::FaceTexture>>& textures,
                      const std::vector<cv::Vec3b>& colours_bgr,
                      const std::vector<std::string>& labels, int target_index) {
  const int k = kPictureScale;
  cv::Mat out;
  cv::resize(ambient_bgr, out, cv::Size(), k, k, cv::INTER_LINEAR);
  // Camera pixel centre u lies at picture coordinate k u + (k - 1) / 2.
  const auto to_picture = [&](const Eigen::Vector3d& p_W) -> std::optional<cv::Point2f> {
    const auto uv = camera.Project(X_CW * p_W);
    if (!uv) return std::nullopt;
    return cv::Point2f(static_cast<float>(k * uv->x() + 0.5 * (k - 1)),
                       static_cast<float>(k * uv->y() + 0.5 * (k - 1)));
  };
  const Eigen::Vector3d camera_W = X_CW.inverse().translation();
  for (size_t i = 0; i < boxes.size(); ++i) {
    const model::BoxModel& box = boxes[i];
    for (int face = 0; face < 6; ++face) {
      const std::array<Eigen::Vector3d, 4> corners = model::FaceCorners(box, face);
      const Eigen::Vector3d centre = 0.25 * (corners[0] + corners[1] + corners[2] + corners[3]);
      if (model::FaceNormal(box, face).dot(camera_W - centre) <= 0) continue;  // faces away
      std::vector<cv::Point2f> dst;
      for (const Eigen::Vector3d& c : corners) {
        if (const auto p = to_picture(c)) dst.push_back(*p);
      }
      if (dst.size() != 4) continue;
      const model::FaceTexture* texture = nullptr;
      if (i < textures.size()) {
        for (const model::FaceTexture& t : textures[i]) {
          if (t.face == face && !t.image.empty()) texture = &t;
        }
      }
      cv::Mat mask(out.size(), CV_8U, cv::Scalar(0));
      std::vector<cv::Point> polygon;
      for (const cv::Point2f& p : dst) polygon.emplace_back(cvRound(p.x), cvRound(p.y));
      cv::fillConvexPoly(mask, polygon, cv::Scalar(255), cv::LINE_AA);
      cv::Mat layer;
      if (texture != nullptr) {
        const float n = static_cast<float>(texture->image.cols - 1);
        const std::vector<cv::Point2f> src = {{0, 0}, {n, 0}, {n, n}, {0, n}};
        cv::warpPerspective(texture->image, layer, cv::getPerspectiveTransform(src, dst),
                            out.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
        layer.copyTo(out, mask);
      } else {
        // An untextured face (seen by the camera, not scanned): the box's colour, half shaded.
        const cv::Vec3b c = i < colours_bgr.size() ? colours_bgr[i] : cv::Vec3b(180, 180, 180);
        layer = cv::Mat(out.size(), CV_8UC3, cv::Scalar(c[0], c[1], c[2]));
        cv::addWeighted(out, 0.5, layer, 0.5, 0, layer);
        layer.copyTo(out, mask);
      }
    }
  }
  for (size_t i = 0; i < boxes.size(); ++i) {
    const model::BoxModel& box = boxes[i];
    const bool target = static_cast<int>(i) == target_index;
    const cv::Scalar colour = target ? cv::Scalar(40, 40, 255) : cv::Scalar(255, 255, 255);
    // Edges join corners that differ in one bit of their index (BoxModel::vertices_W).
    for (int a = 0; a < 8; ++a) {
      for (int bit : {1, 2, 4}) {
        const int b = a | bit;
        if (b == a) continue;
        const auto pa = to_picture(box.vertices_W[a]), pb = to_picture(box.vertices_W[b]);
        if (pa && pb) cv::line(out, *pa, *pb, colour, target ? 2 : 1, cv::LINE_AA);
      }
    }
    if (i < labels.size()) {
      // Above the box's highest corner in the picture.
      float x = 1e9f, y = 1e9f;
      for (const Eigen::Vector3d& v : box.vertices_W) {
        if (const auto p = to_picture(v)) x = std::min(x, p->x), y = std::min(y, p->y);
      }
      if (x < 1e9f) {
        cv::putText(out, labels[i], cv::Point2f(x, y - 6), cv::FONT_HERSHEY_SIMPLEX, 0.5, colour, 1,
                    cv::LINE_AA);
      }
    }
  }
  return out;
}

void DrawHand(cv::Mat* picture, const PinholeCamera& camera, const Pose3& X_CW,
              const std::array<grasp::OrientedBox, 3>& hand, const cv::Scalar& colour_bgr) {
  const int k = kPictureScale;
  for (const grasp::OrientedBox& part : hand) {
    std::array<std::optional<cv::Point2f>, 8> corners;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d o((c & 1 ? 0.5 : -0.5) * part.size.x(),
                              (c & 2 ? 0.5 : -0.5) * part.size.y(),
                              (c & 4 ? 0.5 : -0.5) * part.size.z());
      if (const auto uv = camera.Project(X_CW * (part.centre + part.R * o))) {
        corners[c] = cv::Point2f(static_cast<float>(k * uv->x() + 0.5 * (k - 1)),
                                 static_cast<float>(k * uv->y() + 0.5 * (k - 1)));
      }
    }
    for (int a = 0; a < 8; ++a) {
      for (const int bit : {1, 2, 4}) {
        const int b = a | bit;
        if (b != a && corners[a] && corners[b]) {
          cv::line(*picture, *corners[a], *corners[b], colour_bgr, 2, cv::LINE_AA);
        }
      }
    }
  }
}

void WritePng(const cv::Mat& image, const std::string& path) {
  if (!cv::imwrite(path, image)) throw std::runtime_error("cannot write " + path);
}

}  // namespace hgrasp::app
