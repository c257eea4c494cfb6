// Segmentation and box-fitting benchmarks on one scan of the default scenario, on one core
// (target: SegmentPlanes + GroupObjects + FitBoxes in at most 30 ms). The scan is taken once,
// with the simulated robot as `hgrasp model` takes it, and reused by every benchmark; Hoover
// counts against the simulator's faces come with the segmentation. With -DHGRASP_WITH_PCL=ON,
// pcl_bench.cc adds PCL's RegionGrowing on the same points.

#include <benchmark/benchmark.h>


#include "model/box_fit.h"
#include "segment/segment.h"
#include "tests/bench/default_scan.h"

namespace hgrasp::segment {
namespace {

const scan::RangeImage& DefaultScan() { return bench::DefaultScan().range; }

void BM_SegmentPlanes(benchmark::State& state) {
  const scan::RangeImage& range = DefaultScan();
  SegmentResult s;
  for (auto _ : state) {
    s = SegmentPlanes(range);
    benchmark::DoNotOptimize(s.labels.data());
  }
  state.counters["valid_cells"] = range.CountValid();
  state.counters["regions"] = static_cast<double>(s.regions.size());
  bench::HooverCounters(s.labels, &state);
}
BENCHMARK(BM_SegmentPlanes)->Unit(benchmark::kMillisecond);

void BM_GroupObjects(benchmark::State& state) {
  const scan::RangeImage& range = DefaultScan();
  const SegmentResult s = SegmentPlanes(range);
  Grouping g;
  for (auto _ : state) {
    g = GroupObjects(s, range);
    benchmark::DoNotOptimize(g.objects.data());
  }
  state.counters["regions"] = static_cast<double>(s.regions.size());
  state.counters["objects"] = static_cast<double>(g.objects.size());
}
BENCHMARK(BM_GroupObjects)->Unit(benchmark::kMillisecond);

// The whole modelling step after the scan: segmentation, grouping and box fitting.
void BM_SegmentGroupFitBoxes(benchmark::State& state) {
  const scan::RangeImage& range = DefaultScan();
  SegmentResult s;
  Grouping g;
  std::vector<model::BoxModel> boxes;
  for (auto _ : state) {
    s = SegmentPlanes(range);
    g = GroupObjects(s, range);
    boxes = model::FitBoxes(s, g, range);
    benchmark::DoNotOptimize(boxes.data());
  }
  state.counters["regions"] = static_cast<double>(s.regions.size());
  state.counters["objects"] = static_cast<double>(g.objects.size());
  state.counters["boxes"] = static_cast<double>(boxes.size());
}
BENCHMARK(BM_SegmentGroupFitBoxes)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace hgrasp::segment
