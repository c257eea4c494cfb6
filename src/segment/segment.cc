#include "segment/segment.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <queue>
#include <string>
#include <utility>

#include "common/error.h"

namespace hgrasp::segment {
namespace {

/// Moment sums of a point set, relative to a common reference point to limit cancellation.
struct Moments {
  double n = 0.0;
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  Eigen::Matrix3d ss = Eigen::Matrix3d::Zero();

  void Add(const Eigen::Vector3d& p) {
    n += 1.0;
    s += p;
    ss += p * p.transpose();
  }
  void Add(const Moments& o) {
    n += o.n;
    s += o.s;
    ss += o.ss;
  }
  Eigen::Vector3d Mean() const { return s / n; }
  Eigen::Matrix3d Covariance() const {
    const Eigen::Vector3d m = Mean();
    return ss / n - m * m.transpose();
  }
};

/// Smallest eigenvalue of a moment set's covariance (m^2); 0 for fewer than 3 points.
double Residual(const Moments& m) {
  if (m.n < 3.0) return 0.0;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
  es.computeDirect(m.Covariance(), Eigen::EigenvaluesOnly);
  return std::max(0.0, es.eigenvalues()(0));
}

/// Orients a unit normal after PlaneRegion::normal_W's convention.
Eigen::Vector3d Orient(Eigen::Vector3d n) {
  constexpr double kHorizontal = 0.70710678118654752;
  bool flip;
  if (std::abs(n.z()) >= kHorizontal) {
    flip = n.z() < 0.0;
  } else if (n.x() != 0.0) {
    flip = n.x() > 0.0;
  } else {
    flip = n.y() > 0.0;
  }
  return flip ? Eigen::Vector3d(-n) : n;
}

/// Plane fit of a moment set: unit normal (oriented) and smallest eigenvalue.
void FitPlane(const Moments& m, Eigen::Vector3d* normal, double* residual) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(m.Covariance());
  *normal = Orient(es.eigenvectors().col(0).normalized());
  *residual = std::max(0.0, es.eigenvalues()(0));
}

void CheckConfig(const SegmentConfig& c) {
  auto bad = [](const std::string& field, double v, const std::string& expected) {
    throw InputError("", "SegmentConfig." + field, std::to_string(v), expected);
  };
  if (c.patch < 3 || c.patch % 2 == 0) bad("patch", c.patch, "an odd integer >= 3");
  if (!(c.max_patch_residual_m2 > 0.0))
    bad("max_patch_residual_m2", c.max_patch_residual_m2, "> 0");
  if (!(c.alpha1 > -1.0 && c.alpha1 < 1.0)) bad("alpha1", c.alpha1, "in (-1, 1)");
  if (!(c.alpha2 > 0.0 && c.alpha2 <= 1.0)) bad("alpha2", c.alpha2, "in (0, 1]");
  if (!(c.max_merge_residual_m2 >= 0.0))
    bad("max_merge_residual_m2", c.max_merge_residual_m2, ">= 0");
  if (c.min_region_cells < 1) bad("min_region_cells", c.min_region_cells, ">= 1");
  if (!(c.max_neighbour_gap_m > 0.0)) bad("max_neighbour_gap_m", c.max_neighbour_gap_m, "> 0");
}

/// Union-find over region labels.
class UnionFind {
 public:
  explicit UnionFind(int n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  int Find(int a) {
    while (parent_[a] != a) {
      parent_[a] = parent_[parent_[a]];
      a = parent_[a];
    }
    return a;
  }
  /// Joins the sets of a and b; returns the root kept.
  int Union(int a, int b) {
    a = Find(a);
    b = Find(b);
    if (a != b) parent_[b] = a;
    return a;
  }

 private:
  std::vector<int> parent_;
};

/// Whether cells i and j are both valid and their 3-D points closer than the gap.
bool Connected(const scan::RangeCell& a, const scan::RangeCell& b, double gap) {
  return a.valid && b.valid && (a.p_W - b.p_W).squaredNorm() < gap * gap;
}

/// Candidate merge of regions a and b with the versions they had when the cost was computed.
struct Candidate {
  double cost;
  int a, b;
  int version_a, version_b;
  bool operator>(const Candidate& o) const { return cost > o.cost; }
};

}  // namespace

SegmentResult SegmentPlanes(const scan::RangeImage& range, const SegmentConfig& config) {
  CheckConfig(config);
  const int rows = range.rows(), cols = range.cols(), n_cells = rows * cols;
  SegmentResult result;
  result.rows = rows;
  result.cols = cols;
  result.labels.assign(n_cells, -1);
  if (n_cells == 0) return result;
  auto cell = [&](int i) -> const scan::RangeCell& { return range.at(i / cols, i % cols); };

  // Reference point for all moment sums (the first valid point).
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  for (int i = 0; i < n_cells; ++i) {
    if (cell(i).valid) {
      origin = cell(i).p_W;
      break;
    }
  }
  std::vector<Eigen::Vector3d> p(n_cells, Eigen::Vector3d::Zero());
  for (int i = 0; i < n_cells; ++i) {
    if (cell(i).valid) p[i] = cell(i).p_W - origin;
  }
  const double gap = config.max_neighbour_gap_m;

  // 1. Patch normals.
  const int half = config.patch / 2;
  const int min_patch_points = std::max(3, (config.patch * config.patch + 1) / 2);
  std::vector<Eigen::Vector3d> normal(n_cells, Eigen::Vector3d::Zero());
  std::vector<char> has_normal(n_cells, 0);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int i = r * cols + c;
      if (!cell(i).valid) continue;
      Moments m;
      for (int rr = std::max(0, r - half); rr <= std::min(rows - 1, r + half); ++rr) {
        for (int cc = std::max(0, c - half); cc <= std::min(cols - 1, c + half); ++cc) {
          const int j = rr * cols + cc;
          if (cell(j).valid) m.Add(p[j]);
        }
      }
      if (m.n < min_patch_points) continue;
      double residual;
      FitPlane(m, &normal[i], &residual);
      if (residual <= config.max_patch_residual_m2) has_normal[i] = 1;
    }
  }

  // 2. Initial segmentation: sequential binary connectivity (raster scan + union-find).
  auto coplanar = [&](int i, int j) {
    if (!has_normal[i] || !has_normal[j]) return false;
    if (!Connected(cell(i), cell(j), gap)) return false;
    const Eigen::Vector3d& n1 = normal[i];
    const Eigen::Vector3d& n2 = normal[j];
    // Normals are oriented by one global rule, which can disagree for normals near its switch
    // points; compare them up to sign.
    const double sign = n1.dot(n2) < 0.0 ? -1.0 : 1.0;
    if (sign * n1.dot(n2) <= config.alpha1) return false;
    const Eigen::Vector3d d = p[i] - p[j];
    const double len = d.norm();
    if (len == 0.0) return true;
    const Eigen::Vector3d r12 = d / len;
    return std::max(std::abs(r12.dot(n1)), std::abs(r12.dot(n2))) < config.alpha2;
  };
  std::vector<int> label(n_cells, -1);
  int n_labels = 0;
  UnionFind uf(n_cells);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int i = r * cols + c;
      if (!has_normal[i]) continue;
      const int up = r > 0 && coplanar(i, i - cols) ? label[i - cols] : -1;
      const int left = c > 0 && coplanar(i, i - 1) ? label[i - 1] : -1;
      if (up < 0 && left < 0) {
        label[i] = n_labels++;
      } else if (up >= 0 && left >= 0) {
        label[i] = uf.Union(up, left);
      } else {
        label[i] = std::max(up, left);
      }
    }
  }
  // Compact the roots to 0..n_regions-1.
  std::vector<int> compact(n_labels, -1);
  int n_regions = 0;
  for (int i = 0; i < n_cells; ++i) {
    if (label[i] < 0) continue;
    const int root = uf.Find(label[i]);
    if (compact[root] < 0) compact[root] = n_regions++;
    label[i] = compact[root];
  }
  std::vector<Moments> moments(n_regions);
  for (int i = 0; i < n_cells; ++i) {
    if (label[i] >= 0) moments[label[i]].Add(p[i]);
  }

  // 3. Cells without a valid normal join the neighbouring region whose plane they satisfy, in
  // waves outwards from the labelled cells. A region of fewer than patch^2 cells has no reliable
  // plane of its own; the neighbouring cell's patch plane (its normal through its point) is used.
  {
    const double max_dist = 3.0 * std::sqrt(config.max_patch_residual_m2);
    std::vector<Eigen::Vector3d> region_normal(n_regions, Eigen::Vector3d::UnitZ());
    std::vector<char> region_plane(n_regions, 0);
    for (int k = 0; k < n_regions; ++k) {
      if (moments[k].n >= config.patch * config.patch) {
        double residual;
        FitPlane(moments[k], &region_normal[k], &residual);
        region_plane[k] = 1;
      }
    }
    std::vector<int> frontier;
    for (int i = 0; i < n_cells; ++i) {
      if (cell(i).valid && label[i] < 0) frontier.push_back(i);
    }
    std::vector<std::pair<int, int>> assigned;
    bool changed = true;
    while (changed && !frontier.empty()) {
      changed = false;
      assigned.clear();
      std::vector<int> remaining;
      for (int i : frontier) {
        const int r = i / cols, c = i % cols;
        const int nb[4] = {r > 0 ? i - cols : -1, r + 1 < rows ? i + cols : -1, c > 0 ? i - 1 : -1,
                           c + 1 < cols ? i + 1 : -1};
        double best = max_dist;
        int best_label = -1;
        for (int j : nb) {
          if (j < 0 || label[j] < 0 || !Connected(cell(i), cell(j), gap)) continue;
          const int k = label[j];
          double dist;
          if (region_plane[k]) {
            dist = std::abs(region_normal[k].dot(p[i] - moments[k].Mean()));
          } else if (has_normal[j]) {
            dist = std::abs(normal[j].dot(p[i] - p[j]));
          } else {
            dist = (p[i] - p[j]).norm();
          }
          if (dist < best) {
            best = dist;
            best_label = k;
          }
        }
        if (best_label >= 0) {
          assigned.emplace_back(i, best_label);
        } else {
          remaining.push_back(i);
        }
      }
      for (const auto& [i, k] : assigned) {
        label[i] = k;
        moments[k].Add(p[i]);
        changed = true;
      }
      frontier.swap(remaining);
    }
  }

  // 4. Region merging by boundary-cost minimisation. Adjacency lists may hold ids of regions
  // merged away since; they are resolved through the union-find when a region's list is used.
  std::vector<std::vector<int>> adjacent(n_regions);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int i = r * cols + c;
      if (label[i] < 0) continue;
      for (int j : {c + 1 < cols ? i + 1 : -1, r + 1 < rows ? i + cols : -1}) {
        if (j < 0 || label[j] < 0 || label[j] == label[i]) continue;
        if (!Connected(cell(i), cell(j), gap)) continue;
        adjacent[label[i]].push_back(label[j]);
        adjacent[label[j]].push_back(label[i]);
      }
    }
  }
  UnionFind merged(n_regions);
  // Replaces each entry of a's list by its current region, without a itself or duplicates.
  auto resolve = [&](int a) {
    std::vector<int>& list = adjacent[a];
    for (int& c : list) c = merged.Find(c);
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    list.erase(std::remove(list.begin(), list.end(), a), list.end());
  };
  std::vector<int> version(n_regions, 0);
  std::priority_queue<Candidate, std::vector<Candidate>, std::greater<Candidate>> queue;
  auto push = [&](int a, int b) {
    Moments m = moments[a];
    m.Add(moments[b]);
    queue.push({Residual(m), a, b, version[a], version[b]});
  };
  for (int a = 0; a < n_regions; ++a) {
    resolve(a);
    for (int b : adjacent[a]) {
      if (a < b) push(a, b);
    }
  }
  std::vector<char> alive(n_regions, 1);
  while (!queue.empty()) {
    const Candidate top = queue.top();
    queue.pop();
    if (!alive[top.a] || !alive[top.b] || version[top.a] != top.version_a ||
        version[top.b] != top.version_b) {
      continue;  // stale
    }
    if (top.cost > config.max_merge_residual_m2) break;
    // Merge the region with the shorter adjacency list into the other.
    int a = top.a, b = top.b;
    if (adjacent[a].size() < adjacent[b].size()) std::swap(a, b);
    moments[a].Add(moments[b]);
    alive[b] = 0;
    merged.Union(a, b);  // keeps a as the root
    adjacent[a].insert(adjacent[a].end(), adjacent[b].begin(), adjacent[b].end());
    std::vector<int>().swap(adjacent[b]);
    resolve(a);
    ++version[a];
    for (int c : adjacent[a]) push(a, c);
  }

  // 5. Final labels and regions; small regions dropped.
  std::vector<int> final_id(n_regions, -1);
  for (int k = 0; k < n_regions; ++k) {
    if (!alive[k] || moments[k].n < config.min_region_cells) continue;
    final_id[k] = static_cast<int>(result.regions.size());
    PlaneRegion region;
    region.id = final_id[k];
    region.cells = static_cast<int>(moments[k].n);
    region.centroid_W = moments[k].Mean() + origin;
    FitPlane(moments[k], &region.normal_W, &region.residual_m2);
    result.regions.push_back(region);
  }
  for (int i = 0; i < n_cells; ++i) {
    if (label[i] >= 0) result.labels[i] = final_id[merged.Find(label[i])];
  }
  return result;
}

Grouping GroupObjects(const SegmentResult& s, const scan::RangeImage& range,
                      const SegmentConfig& config) {
  CheckConfig(config);
  HGRASP_DEMAND(s.rows == range.rows() && s.cols == range.cols());
  HGRASP_DEMAND(static_cast<int>(s.labels.size()) == s.rows * s.cols);
  Grouping grouping;
  const int n = static_cast<int>(s.regions.size());
  int max_id = -1;
  for (const PlaneRegion& r : s.regions) max_id = std::max(max_id, r.id);
  std::vector<int> index_of(max_id + 1, -1);  // region id -> index in s.regions
  for (int k = 0; k < n; ++k) {
    HGRASP_DEMAND(s.regions[k].id >= 0 && index_of[s.regions[k].id] < 0);
    index_of[s.regions[k].id] = k;
  }
  std::vector<char> removed(n, 0);

  constexpr double kFloorNz = 0.95, kFloorClearance = 0.005;
  constexpr double kWallNz = 0.1, kWallClearance = 0.02;
  for (bool found = true; found;) {
    found = false;
    // Floor: the lowest remaining region, horizontal, all others well above.
    int lowest = -1;
    for (int k = 0; k < n; ++k) {
      if (!removed[k] &&
          (lowest < 0 || s.regions[k].centroid_W.z() < s.regions[lowest].centroid_W.z())) {
        lowest = k;
      }
    }
    if (lowest >= 0 && std::abs(s.regions[lowest].normal_W.z()) > kFloorNz) {
      bool below_all = true;
      for (int k = 0; k < n; ++k) {
        if (k != lowest && !removed[k] &&
            s.regions[k].centroid_W.z() < s.regions[lowest].centroid_W.z() + kFloorClearance) {
          below_all = false;
        }
      }
      if (below_all) {
        removed[lowest] = 1;
        grouping.floor_or_wall.push_back(s.regions[lowest].id);
        found = true;
        continue;
      }
    }
    // Wall: the farthest remaining region in x, vertical, all others well nearer.
    int farthest = -1;
    for (int k = 0; k < n; ++k) {
      if (!removed[k] &&
          (farthest < 0 || s.regions[k].centroid_W.x() > s.regions[farthest].centroid_W.x())) {
        farthest = k;
      }
    }
    if (farthest >= 0 && std::abs(s.regions[farthest].normal_W.z()) < kWallNz) {
      bool behind_all = true;
      for (int k = 0; k < n; ++k) {
        if (k != farthest && !removed[k] &&
            s.regions[k].centroid_W.x() > s.regions[farthest].centroid_W.x() - kWallClearance) {
          behind_all = false;
        }
      }
      if (behind_all) {
        removed[farthest] = 1;
        grouping.floor_or_wall.push_back(s.regions[farthest].id);
        found = true;
      }
    }
  }

  // Connected groups of the remaining regions.
  UnionFind uf(std::max(n, 1));
  const int rows = s.rows, cols = s.cols;
  auto region_at = [&](int i) {
    const int id = s.labels[i];
    if (id < 0 || id > max_id) return -1;
    const int k = index_of[id];
    return k >= 0 && !removed[k] ? k : -1;
  };
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int i = r * cols + c;
      const int a = region_at(i);
      if (a < 0) continue;
      // Cells ahead of this one within the reach (each unordered pair looked at once).
      const int reach = config.group_reach_cells;
      for (int dr = 0; dr <= reach && r + dr < rows; ++dr) {
        for (int dc = dr == 0 ? 1 : -reach; dc <= reach; ++dc) {
          if (c + dc < 0 || c + dc >= cols) continue;
          const int b = region_at(i + dr * cols + dc);
          if (b < 0 || b == a || uf.Find(a) == uf.Find(b)) continue;
          if (Connected(range.at(r, c), range.at(r + dr, c + dc), config.max_group_gap_m)) {
            uf.Union(a, b);
          }
        }
      }
    }
  }
  std::vector<int> group_of(n, -1);
  for (int k = 0; k < n; ++k) {
    if (removed[k]) continue;
    const int root = uf.Find(k);
    if (group_of[root] < 0) {
      group_of[root] = static_cast<int>(grouping.objects.size());
      grouping.objects.emplace_back();
    }
    grouping.objects[group_of[root]].push_back(s.regions[k].id);
  }
  for (auto& object : grouping.objects) std::sort(object.begin(), object.end());
  return grouping;
}

}  // namespace hgrasp::segment
