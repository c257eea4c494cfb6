// `hgrasp sweep`: many scenes, each in its own process, scored against the simulator's truth;
// summary.json, summary.csv, junit.xml and report.html; baselines; resuming; Slurm job arrays.
//
// The sweep's folder DIR holds everything, so a stopped sweep resumes from it and Slurm's array
// tasks share it:
//   DIR/sweep.json          the manifest: stage, lockstep, scenes (name and file), calibration
//                           files
//   DIR/scenarios/          the scenario files of generated scenes (--family, --seeds)
//   DIR/scenes/<scene>/     each scene's outputs (report.json, pictures)
//   DIR/logs/<scene>.log    each scene's output
//   DIR/rows/<scene>.json   each finished scene's row: a scene with a row is done
//   DIR/slurm/              the job script and the array tasks' logs
//   DIR/summary.json, summary.csv, junit.xml, report.html, regressions.json

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>

#include "app/commands.h"
#include "app/safe_stop.h"
#include "app/sweep/baseline.h"
#include "app/sweep/report_html.h"
#include "app/sweep/scene_process.h"
#include "app/sweep/scene_row.h"
#include "app/sweep/summary.h"
#include "common/error.h"
#include "common/paths.h"
#include "common/write_file.h"
#include "fmt/format.h"

namespace hgrasp::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using sweep::SceneEntry;
using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

std::string UtcNow() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

// "1h02m", "4m10s", "12s".
std::string Duration(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  const long t = std::lround(s);
  if (t >= 3600) return fmt::format("{}h{:02}m", t / 3600, (t % 3600) / 60);
  if (t >= 60) return fmt::format("{}m{:02}s", t / 60, t % 60);
  return fmt::format("{}s", t);
}

std::optional<json> ReadJson(const fs::path& path) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  try {
    return json::parse(in);
  } catch (const json::exception&) {
    return std::nullopt;
  }
}

// This program's own path: what scenes run with unless --hgrasp names another.
std::string SelfPath() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("sweep: cannot find this program's path (/proc/self/exe)");
  return p.string();
}

bool IsScenarioFile(const fs::path& p) {
  return p.extension() == ".yaml" || p.extension() == ".yml";
}

// The scenes of the inputs (files, and folders' *.yaml files) and the generated family,
// generated files written into DIR/scenarios (once: a resumed sweep reuses them).
std::vector<SceneEntry> CollectScenes(const SweepOptions& o, const fs::path& dir) {
  std::vector<SceneEntry> scenes;
  for (const std::string& input : o.inputs) {
    std::error_code ec;
    const fs::path p = fs::absolute(input);
    if (fs::is_directory(p, ec)) {
      std::vector<fs::path> files;
      for (const fs::directory_entry& e : fs::directory_iterator(p, ec)) {
        if (e.is_regular_file() && IsScenarioFile(e.path())) files.push_back(e.path());
      }
      if (files.empty()) {
        throw InputError("", "scenarios", input, "a folder with scenario files (*.yaml)");
      }
      std::sort(files.begin(), files.end());
      for (const fs::path& f : files) scenes.push_back({f.stem().string(), f.string()});
    } else if (fs::is_regular_file(p, ec)) {
      scenes.push_back({p.stem().string(), p.string()});
    } else {
      throw InputError("", "scenarios", input, "a scenario file or a folder of them");
    }
  }
  if (o.seeds) {
    CheckFamily(o.family, o.seeds->first, o.seeds->second);
    const fs::path folder = dir / "scenarios";
    fs::create_directories(folder);
    for (std::uint64_t seed = o.seeds->first;; ++seed) {
      std::string yaml;
      const std::string name = FamilyScene(o.family, seed, &yaml);
      const fs::path file = folder / (name + ".yaml");
      if (!fs::exists(file)) WriteFileWhole(file.string(), yaml);
      scenes.push_back({name, file.string()});
      if (seed == o.seeds->second) break;
    }
  }
  std::map<std::string, std::string> seen;
  for (const SceneEntry& s : scenes) {
    const auto [it, fresh] = seen.emplace(s.scene, s.file);
    if (!fresh) {
      throw InputError("", "scenarios", s.file,
                       "scenes of distinct names (file stems): " + it->second + " has it too");
    }
  }
  if (scenes.empty()) {
    throw InputError("", "scenarios", "",
                     "scenario files or folders, or --family and --seeds for generated scenes");
  }
  return scenes;
}

json Manifest(const SweepOptions& o, const std::vector<SceneEntry>& scenes,
              const std::string& program) {
  json list = json::array();
  for (const SceneEntry& s : scenes) list.push_back({{"scene", s.scene}, {"file", s.file}});
  return {{"hgrasp_sweep", 1},
          {"stage", o.stage},
          {"lockstep", o.lockstep},
          {"time_limit_s", o.time_limit_s},
          {"hgrasp", program},
          {"calibration",
           {{"cameras", o.files.cameras}, {"laser", o.files.laser}, {"leds", o.files.leds}}},
          {"family", o.seeds ? json(o.family) : json()},
          {"seeds", o.seeds ? json({o.seeds->first, o.seeds->second}) : json()},
          {"scenes", list}};
}

std::vector<SceneEntry> ManifestScenes(const json& m) {
  std::vector<SceneEntry> scenes;
  for (const json& s : m.at("scenes")) {
    scenes.push_back({s.at("scene").get<std::string>(), s.at("file").get<std::string>()});
  }
  return scenes;
}

json ReadManifest(const fs::path& dir) {
  const std::optional<json> m = ReadJson(dir / "sweep.json");
  if (!m || !m->is_object() || m->value("hgrasp_sweep", 0) != 1 || !m->contains("scenes")) {
    throw InputError((dir / "sweep.json").string(), "", "",
                     "a sweep's manifest (the folder of an `hgrasp sweep`)");
  }
  return *m;
}

// The rows of the manifest's scenes that have finished, in the manifest's order.
std::vector<json> LoadRows(const fs::path& dir, const std::vector<SceneEntry>& scenes) {
  std::vector<json> rows;
  for (const SceneEntry& s : scenes) {
    if (std::optional<json> row = ReadJson(dir / "rows" / (s.scene + ".json"))) {
      rows.push_back(std::move(*row));
    }
  }
  return rows;
}

// The progress of a running sweep on stderr: a redrawn bar on a terminal, a line per finished
// scene otherwise (a log file, CI).
class Progress {
 public:
  Progress(int total, int done_before)
      : total_(total),
        done_(done_before),
        before_(done_before),
        tty_(isatty(2) == 1),
        start_(Clock::now()) {}

  void Finished(const json& row) {
    ++done_;
    failed_ += !row.value("ok", false);
    if (tty_) {
      Draw();
      return;
    }
    const std::string what = row["ok"].get<bool>() ? "ok" : row["failure"].get<std::string>();
    std::fprintf(stderr, "sweep: [%d/%d] %s: %s (%.1f s); %d failed; %s\n", done_, total_,
                 row["scene"].get<std::string>().c_str(), what.c_str(), row.value("wall_s", 0.0),
                 failed_, Rate().c_str());
  }
  void Tick() {
    if (tty_ && Since(last_draw_) > 0.5) Draw();
  }
  void End() {
    if (tty_) std::fprintf(stderr, "\n");
  }

 private:
  std::string Rate() const {
    const double s = Since(start_);
    const int ran = done_ - before_;
    if (ran == 0 || s <= 0) return "rate ?";
    const double per_hour = 3600.0 * ran / s;
    return fmt::format("{:.0f} scenes/h, {} left", per_hour, Duration((total_ - done_) * s / ran));
  }
  void Draw() {
    last_draw_ = Clock::now();
    constexpr int kWidth = 30;
    const int fill = total_ > 0 ? kWidth * done_ / total_ : kWidth;
    std::fprintf(stderr, "\r\x1b[Ksweep [%s%s] %d/%d, %d failed, %s",
                 std::string(fill, '#').c_str(), std::string(kWidth - fill, '.').c_str(), done_,
                 total_, failed_, Rate().c_str());
    std::fflush(stderr);
  }

  int total_, done_, before_, failed_ = 0;
  bool tty_;
  Clock::time_point start_, last_draw_{};
};

// The command line of one scene.
std::vector<std::string> SceneCommand(const json& manifest, const SceneEntry& s,
                                      const fs::path& scene_dir) {
  const std::string stage = manifest["stage"];
  std::vector<std::string> argv = {manifest["hgrasp"].get<std::string>(), stage, s.file, "--out",
                                   scene_dir.string()};
  argv.push_back("--lean");
  if (manifest.value("lockstep", false)) argv.push_back("--lockstep");
  const json& cal = manifest["calibration"];
  const CalibrationFiles defaults;
  const auto pass = [&](const char* key, const char* option, const std::string& fallback) {
    const std::string v = cal.value(key, fallback);
    if (v != fallback) argv.insert(argv.end(), {option, v});
  };
  pass("cameras", "--cameras", defaults.cameras);
  pass("laser", "--laser", defaults.laser);
  if (stage != "scan") pass("leds", "--leds", defaults.leds);
  return argv;
}

struct RunStats {
  int ran = 0;
  bool stopped = false;
  double wall_s = 0;
};

// Runs `todo` (`jobs` at a time), writing each finished scene's row.
RunStats RunScenes(const fs::path& dir, const json& manifest, const std::vector<SceneEntry>& todo,
                   int jobs, int total, int done_before) {
  const StopSignals signals;
  const std::string stage = manifest["stage"];
  const double limit = manifest["time_limit_s"];
  fs::create_directories(dir / "rows");
  fs::create_directories(dir / "logs");
  fs::create_directories(dir / "scenes");
  Progress progress(total, done_before);
  struct Running {
    SceneEntry entry;
    std::unique_ptr<sweep::SceneProcess> process;
  };
  std::vector<Running> running;
  size_t next = 0;
  RunStats stats;
  const auto t0 = Clock::now();
  while ((!stats.stopped && next < todo.size()) || !running.empty()) {
    const bool stop = signals.request()->requested();
    if (stop && !stats.stopped) {
      stats.stopped = true;
      for (Running& r : running) r.process->Stop();
    }
    while (!stop && next < todo.size() && static_cast<int>(running.size()) < jobs) {
      const SceneEntry& s = todo[next++];
      const fs::path scene_dir = dir / "scenes" / s.scene;
      fs::remove_all(scene_dir);  // a stopped earlier try's outputs
      running.push_back({s, std::make_unique<sweep::SceneProcess>(
                                SceneCommand(manifest, s, scene_dir),
                                (dir / "logs" / (s.scene + ".log")).string(), limit)});
    }
    bool any = false;
    for (auto it = running.begin(); it != running.end();) {
      if (!it->process->Poll()) {
        ++it;
        continue;
      }
      any = true;
      const sweep::ProcessOutcome& outcome = it->process->outcome();
      if (!outcome.stopped) {
        const SceneEntry& s = it->entry;
        const fs::path scene_dir = dir / "scenes" / s.scene;
        const std::string rel = "scenes/" + s.scene;
        std::vector<std::string> pictures;
        for (const std::string& name : sweep::PictureNames(stage)) {
          if (fs::exists(scene_dir / name)) pictures.push_back(rel + "/" + name);
        }
        const json row = sweep::MakeRow(
            s, stage, outcome, ReadJson(scene_dir / "report.json"),
            sweep::Tail((dir / "logs" / (s.scene + ".log")).string(), 5), rel, pictures);
        WriteFileWhole((dir / "rows" / (s.scene + ".json")).string(), row.dump(1) + "\n");
        ++stats.ran;
        progress.Finished(row);
      }
      it = running.erase(it);
    }
    if (!any) {
      progress.Tick();
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  progress.End();
  stats.wall_s = Since(t0);
  return stats;
}

// summary.json, summary.csv, junit.xml, report.html; the baseline compared and written.
// Returns the exit status: 1 when a figure regressed or the sweep is not complete.
int WriteOutputs(const fs::path& dir, const json& manifest, const RunStats* stats,
                 const std::string& baseline_path, const std::string& write_baseline, int jobs) {
  const std::vector<SceneEntry> scenes = ManifestScenes(manifest);
  const std::vector<json> rows = LoadRows(dir, scenes);
  const bool complete = rows.size() == scenes.size();
  const std::string stage = manifest["stage"];
  std::optional<json> baseline;
  if (!baseline_path.empty()) {
    const std::optional<json> b = ReadJson(baseline_path);
    if (!b) throw InputError(baseline_path, "", "", "a readable JSON sweep baseline");
    sweep::CheckBaseline(*b, baseline_path);
    baseline = *b;
  }
  json info = {{"stage", stage},
               {"lockstep", manifest.value("lockstep", false)},
               {"scenes", scenes.size()},
               {"complete", complete},
               {"jobs", jobs > 0 ? json(jobs) : json()},
               {"time_limit_s", manifest["time_limit_s"]},
               {"family", manifest["family"]},
               {"seeds", manifest["seeds"]},
               {"calibration", manifest["calibration"]},
               {"written_utc", UtcNow()},
               {"started_utc", manifest.value("started_utc", json())}};
  json summary = sweep::Summary(info, rows);
  json& totals = summary["totals"];
  totals["sweep_wall_s"] = stats ? json(stats->wall_s) : json();
  totals["scenes_run"] = stats ? json(stats->ran) : json();
  totals["scenes_per_hour"] = stats && stats->ran > 0 && stats->wall_s > 0
                                  ? json(3600.0 * stats->ran / stats->wall_s)
                                  : json();
  int status = complete ? 0 : 1;
  if (baseline) {
    const sweep::Comparison c = sweep::CompareWithBaseline(*baseline, rows);
    summary["baseline"] = {
        {"file", baseline_path}, {"regressions", c.regressions.size()}, {"notes", c.notes}};
    WriteFileWhole((dir / "regressions.json").string(), c.Json().dump(2) + "\n");
    for (const std::string& n : c.notes) std::fprintf(stderr, "sweep: baseline: %s\n", n.c_str());
    for (const sweep::Regression& g : c.regressions) {
      std::fprintf(stderr, "sweep: REGRESSION %s: %s: %s\n", g.scene.c_str(), g.figure.c_str(),
                   g.what.c_str());
    }
    if (!c.regressions.empty()) status = 1;
    std::fprintf(stderr, "sweep: %zu regressions against %s\n", c.regressions.size(),
                 baseline_path.c_str());
  }
  WriteFileWhole((dir / "summary.json").string(), summary.dump(1) + "\n");
  WriteFileWhole((dir / "summary.csv").string(), sweep::SummaryCsv(rows));
  WriteFileWhole((dir / "junit.xml").string(), sweep::JunitXml(stage, rows));
  WriteFileWhole((dir / "report.html").string(), sweep::ReportHtml(summary, dir));
  if (!write_baseline.empty()) {
    WriteFileWhole(write_baseline, sweep::MakeBaseline(stage, rows).dump(1) + "\n");
    std::fprintf(stderr, "sweep: wrote the baseline %s (%zu scenes)\n", write_baseline.c_str(),
                 rows.size());
  }
  std::string failures;
  for (const auto& [name, n] : totals["failures"].items()) {
    failures += fmt::format("{}{} {}", failures.empty() ? "" : ", ", n.get<int>(), name);
  }
  std::fprintf(stderr,
               "sweep: %zu of %zu scenes%s: %d ok, %d failed%s%s; boxes %d found of %d, %d within "
               "tolerance; %d lifted; wrote %s\n",
               rows.size(), scenes.size(), complete ? "" : " (not complete)",
               totals["ok"].get<int>(), totals["failed"].get<int>(), failures.empty() ? "" : " (",
               failures.empty() ? "" : (failures + ")").c_str(), totals["boxes_found"].get<int>(),
               totals["boxes"].get<int>(), totals["boxes_within_tolerance"].get<int>(),
               totals["lifted"].get<int>(), (dir / "report.html").c_str());
  return status;
}

// The Slurm job script of the sweep in `dir`: an array of `shards` tasks, each running its
// shard of the manifest's scenes with this hgrasp, logs in DIR/slurm/.
std::string JobScript(const fs::path& dir, const std::string& program, int shards) {
  const auto quote = [](const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
  };
  const char* root = std::getenv("HGRASP_ROOT");
  return fmt::format(
      "#!/bin/bash\n"
      "# hgrasp sweep: one array task per shard of the scenes in {dir}.\n"
      "# Each task runs its scenes one at a time and writes their rows into the shared folder;\n"
      "# `hgrasp sweep merge {dir}` then writes the summary.\n"
      "#SBATCH --job-name=hgrasp-sweep\n"
      "#SBATCH --array=0-{last}\n"
      "#SBATCH --cpus-per-task=1\n"
      "#SBATCH --output={dir}/slurm/shard_%a.log\n"
      "set -e\n"
      "{root}"
      "exec {program} sweep --out {qdir} --shard \"$SLURM_ARRAY_TASK_ID/{shards}\"\n",
      fmt::arg("dir", dir.string()), fmt::arg("last", shards - 1),
      fmt::arg("root", root ? "export HGRASP_ROOT=" + quote(root) + "\n" : ""),
      fmt::arg("program", quote(program)), fmt::arg("qdir", quote(dir.string())),
      fmt::arg("shards", shards));
}

// Runs a command to its end (sbatch), its output into `log`; returns the outcome.
sweep::ProcessOutcome RunToEnd(const std::vector<std::string>& argv, const std::string& log) {
  sweep::SceneProcess p(argv, log, 0);
  while (!p.Poll()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  return p.outcome();
}

// The path of `name` found on PATH, or "".
std::string OnPath(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/bin:/bin";
  size_t start = 0;
  while (start <= dirs.size()) {
    const size_t end = std::min(dirs.find(':', start), dirs.size());
    const fs::path candidate = fs::path(dirs.substr(start, end - start)) / name;
    if (access(candidate.c_str(), X_OK) == 0) return candidate.string();
    start = end + 1;
  }
  return "";
}

int SubmitToSlurm(const SweepOptions& o, const fs::path& dir, const json& manifest) {
  const int scenes = static_cast<int>(manifest["scenes"].size());
  const int shards = std::min(scenes, o.shards > 0 ? o.shards : kDefaultShards);
  fs::create_directories(dir / "slurm");
  const fs::path script = dir / "slurm" / "sweep.sbatch";
  WriteFileWhole(script.string(), JobScript(dir, manifest["hgrasp"], shards));
  const std::string sbatch = OnPath("sbatch");
  if (sbatch.empty()) {
    throw InputError("", "--slurm", "", "Slurm's sbatch on PATH (Debian: slurm-client)");
  }
  std::vector<std::string> argv = {sbatch, "--parsable"};
  argv.insert(argv.end(), o.sbatch_args.begin(), o.sbatch_args.end());
  argv.push_back(script.string());
  const std::string log = (dir / "slurm" / "sbatch.out").string();
  std::fprintf(stderr, "sweep: submitting %d scenes as %d array tasks: %s\n", scenes, shards,
               script.c_str());
  const sweep::ProcessOutcome out = RunToEnd(argv, log);
  std::string job = sweep::Tail(log, 1);
  job = job.substr(0, job.find(';'));  // --parsable: "ID" or "ID;CLUSTER"
  if (out.exit_code != 0 || job.empty()) {
    std::fprintf(stderr, "sweep: sbatch failed (%s): %s\n",
                 out.exit_code ? ("exit " + std::to_string(*out.exit_code)).c_str() : "signal",
                 sweep::Tail(log, 20).c_str());
    return 1;
  }
  std::fprintf(stderr, "sweep: submitted job %s\n", job.c_str());
  if (!o.slurm_wait) {
    std::fprintf(stderr, "sweep: when it has finished: hgrasp sweep merge %s\n", dir.c_str());
    return 0;
  }
  // Waits by asking squeue every second until none of the array's tasks is queued or running
  // (sbatch --wait asks at 2, 10, 42 s and then every 32 s: a short sweep would wait for it).
  const std::string squeue = OnPath("squeue");
  if (squeue.empty()) throw InputError("", "--slurm-wait", "", "Slurm's squeue on PATH");
  const StopSignals signals;
  const std::string poll_log = (dir / "slurm" / "squeue.out").string();
  for (int failures = 0;;) {
    if (signals.request()->requested()) {
      std::fprintf(stderr, "sweep: stopped waiting; job %s goes on (scancel %s stops it)\n",
                   job.c_str(), job.c_str());
      return 1;
    }
    const sweep::ProcessOutcome q = RunToEnd({squeue, "-h", "-j", job, "-o", "%i %T"}, poll_log);
    if (q.exit_code == 0 && sweep::Tail(poll_log, 1).empty()) break;
    // squeue fails for a job it no longer knows (it ended long ago): then it has ended too.
    if (q.exit_code != 0 && ++failures >= 5) break;
    std::this_thread::sleep_for(std::chrono::seconds(1));
  }
  std::fprintf(stderr, "sweep: job %s has ended; merging\n", job.c_str());
  return WriteOutputs(dir, manifest, nullptr, o.baseline, o.write_baseline, 0);
}

void CheckOptions(const SweepOptions& o) {
  if (std::find_if(std::begin(sweep::kStages), std::end(sweep::kStages),
                   [&](const char* s) { return o.stage == s; }) == std::end(sweep::kStages)) {
    throw InputError("", "--stage", o.stage, "one of scan, model, plan, run");
  }
  if (o.jobs < 1 || o.jobs > kMaxJobs) {
    throw InputError("", "--jobs", std::to_string(o.jobs),
                     "1 to " + std::to_string(kMaxJobs) + " scene processes at once");
  }
  if (!(o.time_limit_s > 0) || !std::isfinite(o.time_limit_s)) {
    throw InputError("", "--time-limit", fmt::format("{}", o.time_limit_s),
                     "a scene's time limit in seconds, > 0");
  }
  if (o.shards < 0) throw InputError("", "--shards", std::to_string(o.shards), "a count >= 1");
  if (o.shard && (o.shard->second < 1 || o.shard->first < 0 || o.shard->first >= o.shard->second)) {
    throw InputError("", "--shard", fmt::format("{}/{}", o.shard->first, o.shard->second),
                     "INDEX/COUNT with 0 <= INDEX < COUNT");
  }
  if (o.shard && (!o.inputs.empty() || o.seeds)) {
    throw InputError("", "--shard", "", "no scenes: a shard runs those of DIR's manifest");
  }
  if (!o.hgrasp.empty() && access(o.hgrasp.c_str(), X_OK) != 0) {
    throw InputError("", "--hgrasp", o.hgrasp, "an executable program");
  }
}

}  // namespace

int Sweep(const SweepOptions& o) {
  CheckOptions(o);
  const fs::path dir = fs::absolute(o.out_dir);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir) || access(dir.c_str(), W_OK) != 0) {
    throw InputError("", "--out", o.out_dir, "a folder the sweep can write");
  }
  json manifest;
  if (o.shard) {
    manifest = ReadManifest(dir);
  } else {
    const std::string program = o.hgrasp.empty() ? SelfPath() : fs::absolute(o.hgrasp).string();
    manifest = Manifest(o, CollectScenes(o, dir), program);
    if (fs::exists(dir / "sweep.json")) {
      // The same sweep resumes; another one does not mix into this folder.
      const json old = ReadManifest(dir);
      // (A manifest written before --lockstep has no such key: it ran on simulated devices.)
      for (const char* key : {"stage", "lockstep", "scenes", "calibration"}) {
        if (old.value(key, json(false)) != manifest.value(key, json(false))) {
          throw InputError(
              "", "--out", o.out_dir,
              fmt::format(
                  "the folder of this sweep, or a new one: it holds another sweep (its {} "
                  "differ{}); remove it or choose another --out",
                  key, std::string(key) == "stage" || std::string(key) == "lockstep" ? "s" : ""));
        }
      }
      manifest["started_utc"] = old.value("started_utc", UtcNow());
    } else {
      manifest["started_utc"] = UtcNow();
    }
    WriteFileWhole((dir / "sweep.json").string(), manifest.dump(1) + "\n");
    if (o.slurm) return SubmitToSlurm(o, dir, manifest);
    if (o.prepare) {
      std::fprintf(stderr,
                   "sweep: prepared %zu scenes in %s; run shards with `hgrasp sweep --out %s "
                   "--shard I/K`, then `hgrasp sweep merge %s`\n",
                   manifest["scenes"].size(), dir.c_str(), dir.c_str(), dir.c_str());
      return 0;
    }
  }

  const std::vector<SceneEntry> scenes = ManifestScenes(manifest);
  std::vector<SceneEntry> todo;
  int done = 0, total = 0;
  for (size_t i = 0; i < scenes.size(); ++i) {
    if (o.shard && static_cast<int>(i % o.shard->second) != o.shard->first) continue;
    ++total;
    if (fs::exists(dir / "rows" / (scenes[i].scene + ".json"))) {
      ++done;
    } else {
      todo.push_back(scenes[i]);
    }
  }
  if (done > 0) {
    std::fprintf(stderr, "sweep: resuming: %d of %d scenes done, %zu to run\n", done, total,
                 todo.size());
  }
  const RunStats stats = RunScenes(dir, manifest, todo, o.jobs, total, done);
  if (stats.stopped) {
    std::fprintf(stderr,
                 "sweep: stopped: %d of %d scenes done; the same command resumes the sweep\n",
                 done + stats.ran, total);
  }
  if (o.shard) return stats.stopped ? 1 : 0;
  const int status = WriteOutputs(dir, manifest, &stats, o.baseline, o.write_baseline, o.jobs);
  return stats.stopped ? 1 : status;
}

int SweepMerge(const SweepMergeOptions& o) {
  const fs::path dir = fs::absolute(o.dir);
  const json manifest = ReadManifest(dir);
  return WriteOutputs(dir, manifest, nullptr, o.baseline, o.write_baseline, 0);
}

}  // namespace hgrasp::app
