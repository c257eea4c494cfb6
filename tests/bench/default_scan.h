#pragma once
// One scan of scenarios/default.yaml by the simulated robot, taken once and shared by the
// segmentation benchmarks, with the simulator's true face under each cell for Hoover counts.

#include <cstdlib>
#include <vector>

#include "common/paths.h"
#include "sim/hoover.h"
#include "sim/sim_devices.h"
#include "sim/truth.h"
#include "tests/scan/sim_scan.h"

namespace hgrasp::bench {

struct DefaultScanData {
  scan::RangeImage range{0, 0};
  std::vector<int> truth;  ///< per cell (row-major): sim::TrueFaceLabels code, -1 when invalid
};

inline const DefaultScanData& DefaultScan() {
  static const DefaultScanData* const data = [] {
    setenv("HGRASP_ROOT", HGRASP_SOURCE_ROOT, 0);
    sim::SimRobot robot(sim::LoadScenario(ResolveDataPath("scenarios/default.yaml")));
    auto* d = new DefaultScanData{scan::testing::ScanInSim(&robot), {}};
    std::vector<Eigen::Vector3d> points;
    for (int r = 0; r < d->range.rows(); ++r) {
      for (int c = 0; c < d->range.cols(); ++c) {
        if (d->range.at(r, c).valid) points.push_back(d->range.at(r, c).p_W);
      }
    }
    const std::vector<int> codes = sim::TrueFaceLabels(robot.world(), &robot.rig(), 0, points);
    d->truth.assign(static_cast<size_t>(d->range.rows()) * d->range.cols(), -1);
    size_t k = 0;
    for (int i = 0; i < d->range.rows() * d->range.cols(); ++i) {
      if (d->range.at(i / d->range.cols(), i % d->range.cols()).valid) d->truth[i] = codes[k++];
    }
    return d;
  }();
  return *data;
}

/// Hoover counts (tolerance 0.8) of a labelling of the default scan's cells (row-major, -1: none)
/// over the true faces of at least 50 scanned cells, as benchmark counters.
template <typename State>
void HooverCounters(const std::vector<int>& labels, State* state) {
  const DefaultScanData& d = DefaultScan();
  std::vector<int> truth, machine;
  for (size_t i = 0; i < labels.size(); ++i) {
    if (d.truth[i] == -1 && labels[i] < 0) continue;
    truth.push_back(d.truth[i]);
    machine.push_back(labels[i]);
  }
  const sim::HooverCounts h = sim::CompareSegmentations(truth, machine, 50);
  state->counters["faces"] = h.truth_regions;
  state->counters["correct"] = h.correct;
  state->counters["over"] = h.over;
  state->counters["under"] = h.under;
  state->counters["missed"] = h.missed;
  state->counters["noise"] = h.noise;
}

}  // namespace hgrasp::bench
