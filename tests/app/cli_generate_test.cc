// `hgrasp generate`: a family's scenes over a seed range, as files a user can read and run.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "cli_util.h"
#include "sim/random_scene.h"
#include "sim/scenario.h"

namespace hgrasp {
namespace {

namespace fs = std::filesystem;
using testing::RunHgrasp;

TEST(CliGenerate, WritesEverySeedsSceneAsTheFamilyDrawsIt) {
  const fs::path dir = fs::temp_directory_path() / "hgrasp_cli_generate";
  fs::remove_all(dir);
  const auto r = RunHgrasp("generate --family random_boxes --seeds 7..11 --out " + dir.string());
  ASSERT_EQ(r.status, 0) << r.output;
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir)) files += e.path().extension() == ".yaml";
  EXPECT_EQ(files, 5);
  for (std::uint64_t seed = 7; seed <= 11; ++seed) {
    const sim::Scenario drawn = sim::RandomBoxScene(seed);
    const sim::Scenario read =
        sim::LoadScenario((dir / ("random_" + std::to_string(seed) + ".yaml")).string());
    EXPECT_EQ(read.name, drawn.name);
    EXPECT_EQ(read.seed, seed);
    ASSERT_EQ(read.objects.size(), drawn.objects.size());
    for (std::size_t i = 0; i < read.objects.size(); ++i) {
      EXPECT_EQ(read.objects[i].size_O, drawn.objects[i].size_O);
      EXPECT_EQ(read.objects[i].position_W, drawn.objects[i].position_W);
      EXPECT_NEAR(read.objects[i].yaw, drawn.objects[i].yaw, 1e-12);
    }
  }
  fs::remove_all(dir);
}

TEST(CliGenerate, BadFamiliesAndSeedsExitTwoAndWriteNothing) {
  const fs::path dir = fs::temp_directory_path() / "hgrasp_cli_generate_bad";
  fs::remove_all(dir);
  struct Case {
    const char* args;
    const char* named;
  };
  for (const Case& c : {Case{"--family wide", "--family: got 'wide'"},
                        Case{"--seeds 5..2", "--seeds: got '5..2'"},
                        Case{"--seeds 1..x", "--seeds: got '1..x'"},
                        Case{"--seeds -3", "--seeds: got '-3'"},
                        Case{"--seeds 1..200000", "at most 100000 seeds"}}) {
    const auto r = RunHgrasp(std::string("generate ") + c.args + " --out " + dir.string());
    EXPECT_EQ(r.status, 2) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find(c.named), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir)) << c.args;
  }
}

}  // namespace
}  // namespace hgrasp
