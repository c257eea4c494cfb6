// A sweep's comparison with its baseline (app/sweep/baseline.h): rows and baselines built by hand.
#include "app/sweep/baseline.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hgrasp::app::sweep {
namespace {

using nlohmann::json;

json Row(const char* scene, bool ok, const char* failure, double true_rise_mm, double rms_mm) {
  return {{"scene", scene},
          {"ok", ok},
          {"failure", failure ? json(failure) : json(nullptr)},
          {"range", {{"rms_mm", rms_mm}}},
          {"lift", {{"true_rise_mm", true_rise_mm}}}};
}

std::vector<std::string> Regressed(const Comparison& c) {
  std::vector<std::string> r;
  for (const Regression& g : c.regressions) r.push_back(g.scene + " " + g.figure);
  return r;
}

TEST(SweepBaseline, ARiseIsARegressionOnlyWhereTheBaselineLifted) {
  const json baseline = MakeBaseline(
      "run", {Row("held", true, nullptr, 49.0, 0.9), Row("struck", false, "grasp_slipped", 10.3, 0.9)});
  CheckBaseline(baseline, "baseline.json");
  // The same scenes, the same figures: nothing.
  EXPECT_TRUE(Regressed(CompareWithBaseline(
                  baseline, {Row("held", true, nullptr, 49.0, 0.9),
                             Row("struck", false, "grasp_slipped", 10.3, 0.9)}))
                  .empty());
  // The lifted box now 6 mm lower (tolerance 5) is a regression; the box a failing hand struck,
  // pushed over now (-23 mm) and failing otherwise, is not: its `ok` did not change.
  EXPECT_EQ(Regressed(CompareWithBaseline(baseline, {Row("held", true, nullptr, 43.0, 0.9),
                                                     Row("struck", false, "servo_timeout", -23.3, 0.9)})),
            std::vector<std::string>{"held lift.true_rise_mm"});
  // The failing scene's other figures still count: its scan is worse by 0.2 mm (tolerance 0.1).
  EXPECT_EQ(Regressed(CompareWithBaseline(baseline, {Row("held", true, nullptr, 49.0, 0.9),
                                                     Row("struck", false, "servo_timeout", 10.3, 1.1)})),
            std::vector<std::string>{"struck range.rms_mm"});
  // A scene that passed and now fails is one, whatever its rise.
  EXPECT_EQ(Regressed(CompareWithBaseline(baseline, {Row("held", false, "grasp_slipped", 49.0, 0.9),
                                                     Row("struck", false, "servo_timeout", 10.3, 0.9)})),
            std::vector<std::string>{"held ok"});
}

}  // namespace
}  // namespace hgrasp::app::sweep
