#pragma once
/// @file Surface textures of a fitted box (Taylor & Kleeman, section 5.2, last paragraph): each
/// visible face gets a texture image of fixed size, rendered from the range cells of its region
/// projected onto the face, Delaunay-triangulated and filled with their colours.
///
/// Face texture convention. Face f of a box has outward normal n_f and texture axes u_f (texel
/// column, image right) and v_f (texel row, image down), unit vectors of O with u_f x v_f = -n_f:
/// seen from outside the box (looking along -n_f) u_f points right and v_f down, so the texture
/// is not mirrored. Side faces have v_f = -z_O (image top is up); the top is seen as a plan view
/// with x_O right and y_O up, the bottom from below with x_O right and y_O down:
///
///   face      n_f    u_f    v_f
///   0 +x     +x_O   +y_O   -z_O
///   1 -x     -x_O   -y_O   -z_O
///   2 +y     +y_O   -x_O   -z_O
///   3 -y     -y_O   +x_O   -z_O
///   4 +z top +z_O   +x_O   -y_O
///   5 -z     -z_O   +x_O   +y_O
///
/// Texel (i, j) (column i, row j) of a size x size texture has its centre at face coordinates
/// (i / (size - 1), j / (size - 1)) of the face's extent along (u_f, v_f), so the face corners lie
/// at the centres of the corner texels.

#include <Eigen/Core>
#include <array>
#include <opencv2/core.hpp>
#include <vector>

#include "model/box_fit.h"
#include "scan/range_image.h"
#include "segment/segment.h"

namespace hgrasp::model {

/// The texture of one face of a box.
struct FaceTexture {
  int face = -1;    ///< 0 +x, 1 -x, 2 +y, 3 -y, 4 +z (top), 5 -z (bottom), in O
  int region = -1;  ///< the segment region id it was made from (the largest, if several)
  /// CV_8UC3 BGR, size x size, laid out as in the file comment; texels no triangle covers are
  /// filled with the face's median colour.
  cv::Mat image;
  double coverage = 0;  ///< fraction of texels covered by the triangulation, 0-1
};

/// Indices into BoxModel::vertices_W of face `face`'s corners in texture order: corner 0 at texel
/// (0, 0) (top-left), 1 at (size-1, 0) (top-right), 2 at (size-1, size-1), 3 at (0, size-1). Seen
/// from outside the order is clockwise; reversed (0, 3, 2, 1) it is counter-clockwise. face must
/// be 0-5 (aborts otherwise).
std::array<int, 4> FaceCornerIndices(int face);

/// The corners of face `face` in W (m), in texture order (see FaceCornerIndices).
std::array<Eigen::Vector3d, 4> FaceCorners(const BoxModel& box, int face);

/// Outward unit normal of face `face` in W.
Eigen::Vector3d FaceNormal(const BoxModel& box, int face);

/// Which face of `box` a surface with outward normal n_W (any length > 0) belongs to: the face
/// whose outward normal is most parallel to it; -1 if that is more than 30 deg away.
int FaceOfNormal(const BoxModel& box, const Eigen::Vector3d& n_W);

/// Textures of the visible faces. Each region id in box.regions (ids not in s are ignored) is
/// assigned the face along whose axis its normal lies (within 30 deg, else it is skipped), on the
/// side of the box centre its centroid is on: region normals are not outward. The valid range
/// cells of a face's regions are projected onto the face (texel coordinates as in the file
/// comment), Delaunay-triangulated (cv::Subdiv2D), and each triangle with all edges (in the face
/// plane) no longer than max_edge_m is filled, texel centre by texel centre, with its vertices'
/// colours interpolated barycentrically; longer triangles bridge gaps and are left out. Texels
/// left uncovered get the per-channel median colour of the face's cells. Faces come in ascending
/// face order, one per face (regions on one face are pooled). Throws InputError when size < 2 or
/// max_edge_m <= 0; s must come from segment::SegmentPlanes on range (aborts on a size mismatch).
std::vector<FaceTexture> MakeFaceTextures(const BoxModel& box, const segment::SegmentResult& s,
                                          const scan::RangeImage& range, int size = 64,
                                          double max_edge_m = 0.01);

}  // namespace hgrasp::model
