// Grasp planning on the boxes modelled from one scan of the default scenario (target: at most
// 2 ms per scene): both arms, every face pair, approach tilt and inverse-kinematics solution.

#include <benchmark/benchmark.h>

#include "common/paths.h"
#include "grasp/grasp_planner.h"
#include "model/scene_model.h"
#include "tests/bench/default_scan.h"

namespace hgrasp::grasp {
namespace {

void BM_PlanGrasp(benchmark::State& state) {
  const model::SceneModel scene = model::ModelScene(bench::DefaultScan().range);
  const auto tree = robot::KinematicTree::FromUrdfFile(ResolveDataPath("models/humanoid.urdf"));
  const auto left = robot::ArmKinematics::FromTree(tree, "left");
  const auto right = robot::ArmKinematics::FromTree(tree, "right");
  std::vector<GraspPlan> feasible;
  int planned = 0;
  for (auto _ : state) {
    planned = 0;
    for (int target = 0; target < static_cast<int>(scene.boxes.size()); ++target) {
      planned += PlanGrasp(scene.boxes, target, {&left, &right}, {}, &feasible).has_value();
    }
  }
  state.counters["boxes"] = static_cast<double>(scene.boxes.size());
  state.counters["planned"] = planned;
}
BENCHMARK(BM_PlanGrasp)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace hgrasp::grasp
