// The sweep's totals (app/sweep/summary.h): the lifts counted against the truth, rows built by
// hand.
#include "app/sweep/summary.h"

#include "app/sweep/scene_row.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <vector>

namespace hgrasp::app::sweep {
namespace {

nlohmann::json Row(const char* scene, bool lifted, double true_rise_mm) {
  return {{"scene", scene},
          {"ok", lifted},
          {"status", lifted ? "ok" : "failed"},
          {"failure", lifted ? nlohmann::json(nullptr) : nlohmann::json("grasp_slipped")},
          {"lift", {{"lifted", lifted}, {"true_rise_mm", true_rise_mm}, {"task_lift_mm", 50.0}}}};
}

TEST(SweepTotals, ALiftTheTruthDeniesIsFalseAndOneTheCamerasMissedIsUnconfirmed) {
  const std::vector<nlohmann::json> rows = {
      Row("held", true, 49.0),        // said lifted, truly lifted
      Row("slipped", true, 17.0),     // said lifted, the box slid down the fingers
      Row("at_bound", true, 44.9),    // under 90 % of 50 mm: not a lift
      Row("hidden", false, 48.5),     // in the hand, but the cameras could not tell
      Row("dropped", false, 0.0)};    // honestly grasp_slipped
  const nlohmann::json t = Totals(rows);
  EXPECT_EQ(t["lifted"], 3);
  EXPECT_EQ(t["truly_lifted"], 2);
  EXPECT_EQ(t["falsely_lifted"], 2);
  EXPECT_EQ(t["truly_lifted_unconfirmed"], 1);
  EXPECT_EQ(t["failures"]["grasp_slipped"], 2);
}

TEST(SweepRow, TheServoRowGivesItsEndAndWhereTheOpenLoopApproachLeftTheGripper) {
  // A run's report as hgrasp run writes it in simulation, cut to what the servo's row reads.
  const nlohmann::json report = {
      {"ok", true},
      {"truth",
       {{"run",
         {{"servo_start", {{"gripper_to_plan_m", 0.0042}, {"gripper_to_plan_deg", 0.6}}},
          {"grasp_reached", {{"gripper_to_plan_m", 0.0009}, {"gripper_to_plan_deg", 0.2}}}}}}}};
  ProcessOutcome outcome;
  outcome.exit_code = 0;
  const nlohmann::json row =
      MakeRow({"s", "/tmp/s.yaml"}, "run", outcome, report, "", "scenes/s", {});
  ASSERT_TRUE(row["servo"].is_object()) << row.dump();
  EXPECT_NEAR(row["servo"]["gripper_to_plan_mm"].get<double>(), 0.9, 1e-9);
  EXPECT_NEAR(row["servo"]["open_loop_mm"].get<double>(), 4.2, 1e-9);
  EXPECT_NEAR(row["servo"]["open_loop_deg"].get<double>(), 0.6, 1e-12);
}

}  // namespace
}  // namespace hgrasp::app::sweep
