#pragma once
/// @file From a range image to named, textured box models: the segment/ and model/ stages in
/// order (Taylor & Kleeman, sections 5.1, 5.2 and 6).

#include <optional>
#include <vector>

#include "model/box_fit.h"
#include "model/colour.h"
#include "model/texture.h"
#include "scan/range_image.h"
#include "segment/segment.h"

namespace hgrasp::model {

struct SceneModelConfig {
  segment::SegmentConfig segment;
  BoxFitConfig box_fit;
  int texture_size = 64;  ///< texels along each side of a face texture
};

/// Everything the robot knows of the objects in one scan.
struct SceneModel {
  segment::SegmentResult segments;
  segment::Grouping groups;
  std::vector<BoxModel> boxes;
  /// The table's colour, the white reference of the boxes' colours (nullopt: no table seen).
  std::optional<Eigen::Vector3f> table_rgb;
  std::vector<ColourSummary> colours;              ///< per box
  std::vector<std::vector<FaceTexture>> textures;  ///< per box, its visible faces
  int unfitted = 0;      ///< object groups no box could be fitted to (FitBox failed)
  double segment_s = 0;  ///< wall time of segmentation and grouping (s)
  double model_s = 0;    ///< wall time of box fitting, textures and colours (s)
};

/// Planar segmentation, floor/wall removal and grouping, a box per object group, and each box's
/// face textures and colour (from the colour of its faces' range cells).
SceneModel ModelScene(const scan::RangeImage& range, const SceneModelConfig& config = {});

}  // namespace hgrasp::model
