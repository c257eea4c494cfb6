#include "segment/grouping.h"

#include <algorithm>

#include "common/error.h"
#include "segment/union_find.h"

namespace hgrasp::segment {
namespace {

/// Whether cells a and b are both valid and their 3-D points closer than the gap.
bool Connected(const scan::RangeCell& a, const scan::RangeCell& b, double gap) {
  return a.valid && b.valid && (a.p_W - b.p_W).squaredNorm() < gap * gap;
}

}  // namespace

std::vector<int> RegionIndexById(const std::vector<PlaneRegion>& regions) {
  const int n = static_cast<int>(regions.size());
  int max_id = -1;
  for (const PlaneRegion& r : regions) max_id = std::max(max_id, r.id);
  std::vector<int> index_of(max_id + 1, -1);
  for (int k = 0; k < n; ++k) {
    HGRASP_DEMAND(regions[k].id >= 0 && index_of[regions[k].id] < 0);
    index_of[regions[k].id] = k;
  }
  return index_of;
}

std::vector<std::vector<int>> GroupRegions(const SegmentResult& s, const scan::RangeImage& range,
                                           const std::vector<int>& index_of,
                                           const std::vector<char>& removed, int reach_cells,
                                           double max_gap_m) {
  const int n = static_cast<int>(s.regions.size());
  const int max_id = static_cast<int>(index_of.size()) - 1;
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
      for (int dr = 0; dr <= reach_cells && r + dr < rows; ++dr) {
        for (int dc = dr == 0 ? 1 : -reach_cells; dc <= reach_cells; ++dc) {
          if (c + dc < 0 || c + dc >= cols) continue;
          const int b = region_at(i + dr * cols + dc);
          if (b < 0 || b == a || uf.Find(a) == uf.Find(b)) continue;
          if (Connected(range.at(r, c), range.at(r + dr, c + dc), max_gap_m)) uf.Union(a, b);
        }
      }
    }
  }
  std::vector<std::vector<int>> objects;
  std::vector<int> group_of(n, -1);
  for (int k = 0; k < n; ++k) {
    if (removed[k]) continue;
    const int root = uf.Find(k);
    if (group_of[root] < 0) {
      group_of[root] = static_cast<int>(objects.size());
      objects.emplace_back();
    }
    objects[group_of[root]].push_back(s.regions[k].id);
  }
  for (auto& object : objects) std::sort(object.begin(), object.end());
  return objects;
}

}  // namespace hgrasp::segment
