// Ten scenes of the wide family (issue 37) through the whole task, robot errors on, scored
// against the twin's truth: the CI's run of the acceptance sweep. Seeds 201..210 lie outside the
// range the perception was tuned on (1..200) and the range its figures are reported on
// (10001..10300).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_util.h"

namespace hgrasp {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::RunHgrasp;

TEST(CliWideSweep, TenWideScenesAreSeenNamedAndGraspedAsTheTruthHasThem) {
  const fs::path out = fs::temp_directory_path() / "hgrasp_wide_sweep";
  fs::remove_all(out);
  const auto r = RunHgrasp(
      "sweep --family wide_boxes --seeds 201..210 --stage run --jobs 2 --out " + out.string(), 600);
  std::ifstream in(out / "summary.json");
  ASSERT_TRUE(in.good()) << r.output;
  const json totals = json::parse(in).at("totals");
  std::printf("wide 201..210: %s\n", totals.dump().c_str());
  EXPECT_EQ(totals.at("scenes_run"), 10);
  // What these ten scenes give today (a run in simulated time repeats exactly): 15 of their 16
  // boxes found, each named as the colour it was drawn around; 9 targets lifted and held by the
  // truth, none said lifted falsely. wide_202 ends no_target: its table merges with the red box
  // into one region (issue 37, open). Issue 37 asks 99 % of boxes within tolerance; that is not
  // met yet, so the geometry is reported (the printed totals), not asserted.
  EXPECT_GE(totals.at("boxes_found").get<int>(), totals.at("boxes").get<int>() - 1);
  EXPECT_EQ(totals.at("boxes_color_ok"), totals.at("boxes_found"));
  EXPECT_GE(totals.at("truly_lifted").get<int>(), 9);
  EXPECT_EQ(totals.at("falsely_lifted"), 0);
  fs::remove_all(out);
}

}  // namespace
}  // namespace hgrasp
