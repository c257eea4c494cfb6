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

int Generate(const GenerateOptions& o) {
  bool known = false;
  std::string families;
  for (const char* f : kSceneFamilies) {
    known = known || o.family == f;
    families += (families.empty() ? "" : ", ") + std::string(f);
  }
  if (!known) throw InputError("", "--family", o.family, "a scene family, one of: " + families);
  if (o.last_seed < o.first_seed || o.last_seed - o.first_seed >= kMaxGenerate) {
    throw InputError("", "--seeds", std::to_string(o.first_seed) + ".." + std::to_string(o.last_seed),
                     "a seed range FIRST..LAST with FIRST <= LAST, at most " +
                         std::to_string(kMaxGenerate) + " seeds");
  }
  OutputDir out(o.out_dir);
  for (std::uint64_t seed = o.first_seed;; ++seed) {
    const sim::Scenario scene = sim::RandomBoxScene(seed);
    WriteFileWhole(out.Path(scene.name + ".yaml"),
                   "# hgrasp generate --family " + o.family + ", seed " + std::to_string(seed) +
                       "\n" + sim::ScenarioYaml(scene));
    if (seed == o.last_seed) break;
  }
  out.Commit();
  spdlog::info("generate: {} scenes of {} (seeds {}..{}) in {}", o.last_seed - o.first_seed + 1,
               o.family, o.first_seed, o.last_seed, o.out_dir);
  return 0;
}

}  // namespace hgrasp::app
