#pragma once
/// @file Export of fitted, textured boxes as Wavefront OBJ with an MTL material library and PNG
/// textures (Taylor & Kleeman, Figure 6: the rendered models), for viewers such as MeshLab or
/// Blender.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "model/box_fit.h"
#include "model/texture.h"

namespace hgrasp::model {

/// Writes dir/<stem>.obj, dir/<stem>.mtl and one PNG per textured face
/// (dir/<stem>_box<i>_face<f>.png), creating dir if needed. Box i is the OBJ object "box<i>" with
/// its 8 vertices_W (W, m; in BoxModel's corner order) and 6 quads wound counter-clockwise seen
/// from outside (corners 0, 3, 2, 1 of FaceCornerIndices). A face with a texture in textures[i]
/// uses material "box<i>_face<f>" (Kd 1 1 1, map_Kd the PNG, named relative to dir) and 4 vt
/// coordinates that put each texel where MakeFaceTextures rendered it (OBJ's v runs up the
/// image); the other faces share material "box<i>" with Kd colours_rgb[i] (RGB 0-1). textures
/// and colours_rgb are empty or one entry per box (InputError otherwise); with colours_rgb empty,
/// Kd is 0.7 grey. A texture with an empty image or face outside 0-5 is ignored, as is a second
/// one of the same face. Throws std::runtime_error naming the path on an I/O failure.
void WriteObj(const std::vector<BoxModel>& boxes,
              const std::vector<std::vector<FaceTexture>>& textures,
              const std::vector<Eigen::Vector3f>& colours_rgb, const std::string& dir,
              const std::string& stem = "models");

}  // namespace hgrasp::model
