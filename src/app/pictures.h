#pragma once
/// @file Pictures of the pipeline's results for people (DESIGN.md's outputs): the planar
/// segmentation (after Taylor & Kleeman's Figure 5) and the box models over the scene (Figure 6).

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/geometry.h"
#include "common/pinhole_camera.h"
#include "grasp/grasp_planner.h"
#include "model/box_fit.h"
#include "model/texture.h"
#include "scan/range_image.h"
#include "segment/segment.h"

namespace hgrasp::app {

/// Scale of the pictures against the camera image (320 x 240 -> 640 x 480).
constexpr int kPictureScale = 2;

/// Every labelled range point drawn where the left camera sees it (p_C projected by `camera`),
/// kPictureScale times the camera's size, on black: each object region in its own colour
/// (distinct hues, by region id), floor and wall regions in dim grey, points in no region in dark
/// grey. CV_8UC3 BGR.
cv::Mat SegmentsPicture(const segment::SegmentResult& s, const segment::Grouping& g,
                        const scan::RangeImage& range, const PinholeCamera& camera);

/// The fitted boxes drawn over the left camera's ambient image (after Taylor & Kleeman's
/// Figure 6), kPictureScale times its size: each face that faces the camera is filled with its
/// texture (textures[i], by face) or, untextured, shaded in the box's colour (colours_bgr[i]);
/// edges in white, the target's (target_index, -1 for none) in red and thicker, and "i colour"
/// written by each box. X_CW maps W into the camera's optical frame. CV_8UC3 BGR.
cv::Mat ModelsPicture(const cv::Mat& ambient_bgr, const PinholeCamera& camera, const Pose3& X_CW,
                      const std::vector<model::BoxModel>& boxes,
                      const std::vector<std::vector<model::FaceTexture>>& textures,
                      const std::vector<cv::Vec3b>& colours_bgr,
                      const std::vector<std::string>& labels, int target_index);

/// Draws the hand's boxes (grasp::HandBoxes) as a wireframe on a picture made by ModelsPicture
/// (after the paper's Figure 6, its red wireframe hand).
void DrawHand(cv::Mat* picture, const PinholeCamera& camera, const Pose3& X_CW,
              const std::array<grasp::OrientedBox, 3>& hand, const cv::Scalar& colour_bgr);

/// Writes a picture as PNG; throws std::runtime_error naming the path on failure.
void WritePng(const cv::Mat& image, const std::string& path);

}  // namespace hgrasp::app
