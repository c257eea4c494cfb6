// `hgrasp generate`: the scenario files of a scene family over a seed range.

#include <spdlog/spdlog.h>

#include <array>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/output_dir.h"
#include "common/error.h"
#include "common/paths.h"
#include "common/write_file.h"
#include "grasp/grasp_planner.h"
#include "model/box_fit.h"
#include "robot/arm_kinematics.h"
#include "robot/kinematic_tree.h"
#include "sim/random_scene.h"
#include "sim/scenario.h"
#include "sim/wide_scene.h"

namespace hgrasp::app {

void CheckFamily(const std::string& family, std::uint64_t first_seed, std::uint64_t last_seed) {
  bool known = false;
  std::string families;
  for (const char* f : kSceneFamilies) {
    known = known || family == f;
    families += (families.empty() ? "" : ", ") + std::string(f);
  }
  if (!known) throw InputError("", "--family", family, "a scene family, one of: " + families);
  if (last_seed < first_seed || last_seed - first_seed >= kMaxGenerate) {
    throw InputError("", "--seeds", std::to_string(first_seed) + ".." + std::to_string(last_seed),
                     "a seed range FIRST..LAST with FIRST <= LAST, at most " +
                         std::to_string(kMaxGenerate) + " seeds");
  }
}

namespace {

// Whether the robot's model can grasp the first of these true boxes among the others (the
// planner the task runs, on the truth, the target grown by 5 mm a side).
bool TargetGraspable(const std::vector<sim::ObjectSpec>& objects) {
  static const robot::KinematicTree tree =
      robot::KinematicTree::FromUrdfFile(ResolveDataPath("models/humanoid.urdf"));
  static const std::array<robot::ArmKinematics, 2> arms = {
      robot::ArmKinematics::FromTree(tree, "left"), robot::ArmKinematics::FromTree(tree, "right")};
  std::vector<model::BoxModel> boxes;
  for (const sim::ObjectSpec& o : objects) boxes.push_back(model::MakeBox(o.X_WO(), o.size_O));
  // Grasped as the scan will see it: a fitted box's edges are off by up to a few millimetres.
  boxes[0] = model::MakeBox(boxes[0].X_WO, boxes[0].size_O + Eigen::Vector3d(0.005, 0.005, 0));
  return grasp::PlanGrasp(boxes, 0, {&arms[0], &arms[1]}).has_value();
}

}  // namespace

sim::Scenario FamilyScenario(const std::string& family, std::uint64_t seed) {
  if (family == "wide_boxes") {
    sim::WideSceneOptions wide;
    wide.target_graspable = TargetGraspable;
    return sim::WideBoxScene(seed, wide);
  }
  return sim::RandomBoxScene(seed);
}

std::string FamilyScene(const std::string& family, std::uint64_t seed, std::string* yaml) {
  const sim::Scenario scene = FamilyScenario(family, seed);
  *yaml = "# hgrasp generate --family " + family + ", seed " + std::to_string(seed) + "\n" +
          sim::ScenarioYaml(scene);
  return scene.name;
}

int Generate(const GenerateOptions& o) {
  CheckFamily(o.family, o.first_seed, o.last_seed);
  OutputDir out(o.out_dir);
  for (std::uint64_t seed = o.first_seed;; ++seed) {
    std::string yaml;
    const std::string name = FamilyScene(o.family, seed, &yaml);
    WriteFileWhole(out.Path(name + ".yaml"), yaml);
    if (seed == o.last_seed) break;
  }
  out.Commit();
  spdlog::info("generate: {} scenes of {} (seeds {}..{}) in {}", o.last_seed - o.first_seed + 1,
               o.family, o.first_seed, o.last_seed, o.out_dir);
  return 0;
}

}  // namespace hgrasp::app
