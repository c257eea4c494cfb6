// `hgrasp generate`: the scenario files of a scene family over a seed range.

#include <spdlog/spdlog.h>

#include <string>

#include "app/commands.h"
#include "app/output_dir.h"
#include "common/error.h"
#include "common/write_file.h"
#include "sim/random_scene.h"
#include "sim/scenario.h"

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

std::string FamilyScene(const std::string& family, std::uint64_t seed, std::string* yaml) {
  const sim::Scenario scene = sim::RandomBoxScene(seed);  // random_boxes: the only family yet
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
