// PCL's region growing (pcl::RegionGrowing with pcl::NormalEstimation, the PCL tutorial's
// settings) on the same points as BM_SegmentPlanes, for comparison: time, Hoover counts against
// the simulator's faces, and the time ratio to our SegmentPlanes. Built with -DHGRASP_WITH_PCL=ON
// (Debian's libpcl-dev).

#include <benchmark/benchmark.h>
#include <pcl/features/normal_3d.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/region_growing.h>

#include <algorithm>
#include <chrono>
#include <vector>

#include "segment/segment.h"
#include "tests/bench/default_scan.h"

namespace hgrasp::bench {
namespace {

/// Labels per range cell (row-major, -1: none) from PCL's region growing over the valid cells.
std::vector<int> PclRegionGrowing(const scan::RangeImage& range) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  std::vector<int> cell_of;
  for (int i = 0; i < range.rows() * range.cols(); ++i) {
    const scan::RangeCell& c = range.at(i / range.cols(), i % range.cols());
    if (!c.valid) continue;
    cloud->push_back(pcl::PointXYZ(static_cast<float>(c.p_W.x()), static_cast<float>(c.p_W.y()),
                                   static_cast<float>(c.p_W.z())));
    cell_of.push_back(i);
  }
  pcl::search::Search<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>);
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> estimator;
  estimator.setSearchMethod(tree);
  estimator.setInputCloud(cloud);
  estimator.setKSearch(25);  // about our 5 x 5 patch
  estimator.compute(*normals);
  pcl::RegionGrowing<pcl::PointXYZ, pcl::Normal> growing;
  growing.setMinClusterSize(30);  // our min_region_cells
  growing.setSearchMethod(tree);
  growing.setNumberOfNeighbours(30);
  growing.setInputCloud(cloud);
  growing.setInputNormals(normals);
  growing.setSmoothnessThreshold(3.0 / 180.0 * M_PI);
  growing.setCurvatureThreshold(1.0);
  std::vector<pcl::PointIndices> clusters;
  growing.extract(clusters);
  std::vector<int> labels(static_cast<size_t>(range.rows()) * range.cols(), -1);
  for (size_t k = 0; k < clusters.size(); ++k) {
    for (const int i : clusters[k].indices) labels[cell_of[i]] = static_cast<int>(k);
  }
  return labels;
}

/// Median wall time (s) of `runs` calls of f.
template <typename F>
double MedianSeconds(int runs, const F& f) {
  std::vector<double> t;
  for (int k = 0; k < runs; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  std::nth_element(t.begin(), t.begin() + runs / 2, t.end());
  return t[runs / 2];
}

void BM_PclRegionGrowing(benchmark::State& state) {
  const scan::RangeImage& range = DefaultScan().range;
  std::vector<int> labels;
  for (auto _ : state) {
    labels = PclRegionGrowing(range);
    benchmark::DoNotOptimize(labels.data());
  }
  HooverCounters(labels, &state);
  int regions = 0;
  for (const int l : labels) regions = std::max(regions, l + 1);
  state.counters["regions"] = regions;
  // PCL's time over ours, on the same points, timed alike here.
  const double pcl_s = MedianSeconds(5, [&] { benchmark::DoNotOptimize(PclRegionGrowing(range)); });
  const double ours_s =
      MedianSeconds(5, [&] { benchmark::DoNotOptimize(segment::SegmentPlanes(range)); });
  state.counters["time_ratio_to_ours"] = pcl_s / ours_s;
}
BENCHMARK(BM_PclRegionGrowing)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace hgrasp::bench
