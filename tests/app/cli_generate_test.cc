// `hgrasp generate`: a family's scenes over a seed range, as files a user can read and run.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "app/commands.h"
#include "cli_util.h"
#include "sim/random_scene.h"
#include "sim/scenario.h"

namespace hgrasp {
namespace {

namespace fs = std::filesystem;
using testing::RunHgrasp;

// Each family's files read back to the scenes its generator draws (the wide family's colour
// names included).
void ExpectFamilyWritten(const std::string& family, const std::string& prefix) {
  const fs::path dir = fs::temp_directory_path() / ("hgrasp_cli_generate_" + family);
  fs::remove_all(dir);
  const auto r = RunHgrasp("generate --family " + family + " --seeds 7..11 --out " + dir.string());
  ASSERT_EQ(r.status, 0) << r.output;
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir)) files += e.path().extension() == ".yaml";
  EXPECT_EQ(files, 5);
  for (std::uint64_t seed = 7; seed <= 11; ++seed) {
    const sim::Scenario drawn = app::FamilyScenario(family, seed);
    const sim::Scenario read =
        sim::LoadScenario((dir / (prefix + std::to_string(seed) + ".yaml")).string());
    EXPECT_EQ(read.name, drawn.name);
    EXPECT_EQ(read.seed, seed);
    EXPECT_EQ(read.ambient, drawn.ambient);
    EXPECT_EQ(read.wall_x, drawn.wall_x);
    EXPECT_EQ(read.interference.size(), drawn.interference.size());
    ASSERT_EQ(read.objects.size(), drawn.objects.size());
    for (std::size_t i = 0; i < read.objects.size(); ++i) {
      EXPECT_EQ(read.objects[i].size_O, drawn.objects[i].size_O);
      EXPECT_EQ(read.objects[i].position_W, drawn.objects[i].position_W);
      EXPECT_EQ(read.objects[i].color_rgb, drawn.objects[i].color_rgb);
      EXPECT_EQ(read.objects[i].color_name, drawn.objects[i].color_name);
      EXPECT_NEAR(read.objects[i].yaw, drawn.objects[i].yaw, 1e-12);
    }
  }
  fs::remove_all(dir);
}

TEST(CliGenerate, WritesEverySeedsSceneAsTheFamilyDrawsIt) {
  ExpectFamilyWritten("random_boxes", "random_");
  ExpectFamilyWritten("wide_boxes", "wide_");
  // The random family's scenes are RandomBoxScene's own.
  EXPECT_EQ(sim::ScenarioYaml(app::FamilyScenario("random_boxes", 9)),
            sim::ScenarioYaml(sim::RandomBoxScene(9)));
}

TEST(CliGenerate, BadFamiliesAndSeedsExitTwoAndWriteNothing) {
  const fs::path dir = fs::temp_directory_path() / "hgrasp_cli_generate_bad";
  fs::remove_all(dir);
  struct Case {
    const char* args;
    const char* named;
  };
  for (const Case& c :
       {Case{"--family wide", "--family: got 'wide'"}, Case{"--seeds 5..2", "--seeds: got '5..2'"},
        Case{"--seeds 1..x", "--seeds: got '1..x'"}, Case{"--seeds -3", "--seeds: got '-3'"},
        Case{"--seeds 1..200000", "at most 100000 seeds"}}) {
    const auto r = RunHgrasp(std::string("generate ") + c.args + " --out " + dir.string());
    EXPECT_EQ(r.status, 2) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find(c.named), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir)) << c.args;
  }
}

}  // namespace
}  // namespace hgrasp
