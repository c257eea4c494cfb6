// `hgrasp model`: scan, segment, fit boxes; the simulator's ground truth added to the report
// (never given to the pipeline).

#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "app/commands.h"
#include "app/devices.h"
#include "app/look_report.h"
#include "app/output_dir.h"
#include "app/pictures.h"
#include "common/error.h"
#include "common/paths.h"
#include "common/write_file.h"
#include "grasp/grasp_planner.h"
#include "model/box_fit.h"
#include "model/colour.h"
#include "model/obj_io.h"
#include "model/scene_model.h"
#include "model/texture.h"
#include "robot/arm_kinematics.h"
#include "robot/calibration.h"
#include "robot/head_kinematics.h"
#include "scan/range_io.h"
#include "scan/scanner.h"
#include "segment/segment.h"
#include "sim/box_truth.h"
#include "sim/hoover.h"
#include "sim/scan_truth.h"
#include "sim/scenario.h"
#include "sim/sim_devices.h"
#include "sim/truth.h"
#include "task/grasp_task.h"

namespace hgrasp::app {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

nlohmann::json Vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::json Mat(const Eigen::Matrix3d& R) {
  nlohmann::json rows = nlohmann::json::array();
  for (int i = 0; i < 3; ++i) rows.push_back({R(i, 0), R(i, 1), R(i, 2)});
  return rows;
}

}  // namespace

ScanTruthRecorder::ScanTruthRecorder(Robot& robot) : robot_(robot) {
  if (robot_.truth() == nullptr || !robot_.lockstep) return;
  // Lockstep: the twin renders each frame a camera takes on this thread (Develop), its rig's
  // crossings then that exposure's. The look's sweep is the task's first scan.
  robot_.lockstep->set_render_observer(
      [this](sim::StereoRig& rig, std::int32_t encoder_count, bool laser_on) {
        if (recording_ && laser_on) truth_.AddFrame(rig, encoder_count);
      });
}

ScanTruthRecorder::~ScanTruthRecorder() {
  if (robot_.lockstep) robot_.lockstep->set_render_observer(nullptr);
}

void ScanTruthRecorder::OnFrame(const device::StereoFrame& frame, const task::TaskView& view) {
  // Frames without images are the laser's slew before the sweep, not the scan's.
  if (robot_.truth() == nullptr || robot_.lockstep || !recording_ || view.stage != "look" ||
      !view.moment.empty() || !frame.laser_on || frame.left.empty()) {
    return;
  }
  truth_.AddFrame(*robot_.truth()->rig, frame.laser_encoder_count);
}

void ScanTruthRecorder::Stop() { recording_ = false; }

nlohmann::json LookTruth(const TruthWorld& truth_world, const task::TaskResult& r,
                         const sim::ScanTruth& scan_truth) {
  const sim::World& world = *truth_world.world;
  nlohmann::json truth = sim::TruthJson(world, *truth_world.rig, {});
  if (!r.scan || !r.scene) return truth;  // the scan ended early (a device failed)
  const scan::RangeImage& range = r.scan->range;
  const model::SceneModel& scene = *r.scene;
  const std::vector<model::BoxModel>& boxes = scene.boxes;

  // The range against the true surfaces and the stripe both cameras truly saw.
  std::vector<sim::ScanTruth::Point> points;
  std::vector<Eigen::Vector3d> p_W;
  std::vector<int> machine;
  for (int row = 0; row < range.rows(); ++row) {
    for (int col = 0; col < range.cols(); ++col) {
      const scan::RangeCell& cell = range.at(row, col);
      if (!cell.valid) continue;
      const std::int32_t count =
          range.encoder_counts.empty() ? col : range.encoder_counts[static_cast<size_t>(col)];
      points.push_back({count, cell.p_W});
      p_W.push_back(cell.p_W);
      machine.push_back(scene.segments.labels[static_cast<size_t>(row * range.cols() + col)]);
    }
  }
  const sim::ScanTruthFigures f = scan_truth.Score(world, points, range.encoder_counts);
  truth["range"] = {{"points", f.points},
                    {"rms_to_surface_m", f.rms_m},
                    {"median_to_surface_m", f.median_m},
                    {"p99_to_surface_m", f.p99_m},
                    {"outliers", f.outliers},
                    {"outlier_fraction", f.outlier_fraction()},
                    {"outlier_distance_m", sim::kOutlierDistanceM},
                    {"truth_stripe_points", f.truth_points},
                    {"covered", f.covered},
                    {"coverage", f.coverage()}};
  spdlog::info(
      "  range: RMS {:.3f} mm to the true surfaces, {} of {} points beyond {:.0f} mm, coverage "
      "{:.1f}% of {} true stripe points",
      1e3 * f.rms_m, f.outliers, f.points, 1e3 * sim::kOutlierDistanceM, 100 * f.coverage(),
      f.truth_points);

  // The segmentation against the faces the left camera truly sees (the head has not moved since
  // the scan), after Hoover et al.
  const std::vector<int> faces = sim::TrueFaceLabels(world, truth_world.rig, sim::kLeft, p_W);
  const sim::HooverCounts h = sim::CompareSegmentations(faces, machine, kHooverMinCells);
  truth["hoover"] = {{"truth_regions", h.truth_regions},
                     {"correct", h.correct},
                     {"over", h.over},
                     {"under", h.under},
                     {"missed", h.missed},
                     {"noise", h.noise},
                     {"min_cells", kHooverMinCells}};

  // Each true object against the fitted box that models it (sim::MatchBoxes).
  std::vector<sim::PlacedBox> true_boxes, fitted;
  for (const sim::SimObject& obj : world.objects()) {
    true_boxes.push_back({world.BodyPose(obj.body), obj.spec.size_O});
  }
  for (const model::BoxModel& b : boxes) fitted.push_back({b.X_WO, b.size_O});
  const std::vector<int> match = sim::MatchBoxes(true_boxes, fitted);
  nlohmann::json matches = nlohmann::json::array();
  for (size_t i = 0; i < world.objects().size(); ++i) {
    const sim::SimObject& obj = world.objects()[i];
    const std::string true_colour(sim::TrueColorName(obj.spec));
    const int k = match[i];
    nlohmann::json m = {{"object", obj.spec.name},
                        {"box", k < 0 ? nlohmann::json(nullptr) : nlohmann::json(k)},
                        {"found", k >= 0},
                        {"true_color_name", true_colour}};
    if (k >= 0) {
      const sim::BoxError e =
          sim::CompareBox(true_boxes[i].X_WO, obj.spec.size_O, boxes[k].X_WO, boxes[k].size_O);
      const std::string colour(scene.colours[k].name());
      m["center_error_m"] = e.center_m;
      m["edge_error_m"] = Vec(e.edge_m);
      m["max_edge_error_m"] = e.max_edge_m;
      m["yaw_error_deg"] = RadToDeg(e.yaw_rad);
      m["color_name"] = colour;
      m["color_ok"] = colour == true_colour;
      spdlog::info(
          "  {}: box {} ({}) centre {:.1f} mm, edges {:.1f} {:.1f} {:.1f} mm, yaw {:.2f} deg",
          obj.spec.name, k, colour, 1e3 * e.center_m, 1e3 * e.edge_m.x(), 1e3 * e.edge_m.y(),
          1e3 * e.edge_m.z(), RadToDeg(e.yaw_rad));
    } else {
      spdlog::info("  {}: no box", obj.spec.name);
    }
    matches.push_back(m);
  }
  truth["boxes"] = matches;
  if (r.plan && r.target) {
    // How far each contact lies from the true surface of the object the target box models.
    const sim::SimObject* object = TargetObject(world, boxes[*r.target]);
    if (object != nullptr) {
      const Pose3 X_WO = world.BodyPose(object->body);
      nlohmann::json d = nlohmann::json::array();
      for (const Eigen::Vector3d& c : r.plan->contacts_W) {
        d.push_back(sim::DistanceToBoxSurface(X_WO, object->spec.size_O, c));
      }
      truth["grasp"] = {{"object", object->spec.name}, {"contact_to_surface_m", d}};
      spdlog::info("  grasp of {}: contacts {:.1f} and {:.1f} mm from its true faces",
                   object->spec.name, 1e3 * d[0].get<double>(), 1e3 * d[1].get<double>());
    }
  }
  return truth;
}

nlohmann::json LookReport(const sim::Scenario& scenario, const nlohmann::json* truth,
                          const task::TaskResult& r, const task::RobotModel& robot_model, bool plan,
                          const std::string& out_dir, bool lean) {
  nlohmann::json report;
  report["scenario"] = scenario.name;
  report["seed"] = scenario.seed;
  if (truth != nullptr) report["truth"] = *truth;
  if (!r.scan || !r.scene) return report;  // the scan ended early (a device failed)
  const scan::ScanResult& scan = *r.scan;
  const model::SceneModel& scene = *r.scene;
  const std::vector<model::BoxModel>& boxes = scene.boxes;
  const std::vector<model::ColourSummary>& colours = scene.colours;
  const std::optional<int>& target = r.target;
  const std::optional<grasp::GraspPlan>& grasp_plan = r.plan;
  report["range"] = {{"points", scan.points},
                     {"rejected", scan.rejected},
                     {"gaps_rescanned", scan.gaps_rescanned},
                     {"frames_rescanned", scan.frames_rescanned},
                     {"gaps_left", scan.gaps_left}};
  nlohmann::json jboxes = nlohmann::json::array();
  for (const model::BoxModel& b : boxes) {
    const model::ColourSummary& colour = colours[jboxes.size()];
    jboxes.push_back({{"center_W", Vec(b.X_WO.translation())},
                      {"R_WO", Mat(b.X_WO.linear())},
                      {"size", Vec(b.size_O)},
                      {"color_rgb", {colour.rgb.x(), colour.rgb.y(), colour.rgb.z()}},
                      {"color_name", std::string(colour.name())},
                      {"color_histogram", colour.histogram},
                      {"points", b.points}});
  }
  report["boxes"] = jboxes;
  report["target"] = target ? nlohmann::json(*target) : nlohmann::json(nullptr);
  if (plan) {
    if (grasp_plan) {
      const grasp::GraspPlan& g = *grasp_plan;
      nlohmann::json q = nlohmann::json::array(), q_pre = nlohmann::json::array(),
                     q_via = nlohmann::json::array();
      for (int i = 0; i < 6; ++i) {
        q.push_back(g.q[i]), q_pre.push_back(g.q_pre[i]), q_via.push_back(g.q_via[i]);
      }
      report["grasp"] = {{"arm", g.side == device::Side::kLeft ? "left" : "right"},
                         {"p_WE", Vec(g.X_WE.translation())},
                         {"R_WE", Mat(g.X_WE.linear())},
                         {"contacts_W", {Vec(g.contacts_W[0]), Vec(g.contacts_W[1])}},
                         {"q", q},
                         {"p_WE_pre", Vec(g.X_WE_pre.translation())},
                         {"q_pre", q_pre},
                         {"p_WE_via", Vec(g.X_WE_via.translation())},
                         {"q_via", q_via},
                         {"opening", g.opening_m},
                         {"comfort_deg", RadToDeg(g.comfort_rad)}};
    } else {
      report["grasp"] = nullptr;
    }
  }

  const fs::path out(out_dir);
  if (!lean) {
    scan::WritePly(scan.range, (out / "range.ply").string());
    scan::WriteRangePng(scan.range, (out / "range.png").string());
  }
  const PinholeCamera camera = robot_model.cameras.left;
  WritePng(SegmentsPicture(scene.segments, scene.groups, scan.range, camera),
           (out / "segments.png").string());
  std::vector<cv::Vec3b> colours_bgr;
  std::vector<Eigen::Vector3f> colours_rgb;
  std::vector<std::string> labels;
  for (size_t i = 0; i < boxes.size(); ++i) {
    const Eigen::Vector3f c = 255.0f * colours[i].rgb;
    colours_bgr.emplace_back(cv::saturate_cast<uchar>(c.z()), cv::saturate_cast<uchar>(c.y()),
                             cv::saturate_cast<uchar>(c.x()));
    colours_rgb.push_back(colours[i].rgb);
    labels.push_back(std::to_string(i) + " " + std::string(colours[i].name()));
  }
  const Pose3 X_CW = robot_model.head.X_WC(0, r.scan_head).inverse();
  cv::Mat models = ModelsPicture(scan.ambient_left, camera, X_CW, boxes, scene.textures,
                                 colours_bgr, labels, target.value_or(-1));
  if (!lean || !plan) WritePng(models, (out / "models.png").string());
  if (plan) {
    if (grasp_plan) {
      DrawHand(&models, camera, X_CW, grasp::HandBoxes(grasp_plan->X_WE, grasp_plan->opening_m, {}),
               cv::Scalar(40, 40, 255));
    }
    WritePng(models, (out / "grasp.png").string());
  }
  if (!lean) model::WriteObj(boxes, scene.textures, colours_rgb, out.string());
  spdlog::info(
      "model: {} points, {} regions, {} objects, {} boxes ({} not fitted), target {}; scan "
      "{:.2f} s, segment + model {:.1f} ms",
      scan.points, scene.segments.regions.size(), scene.groups.objects.size(), boxes.size(),
      scene.unfitted, target ? std::to_string(*target) : "none", r.stages[0].wall_s,
      1e3 * (scene.segment_s + scene.model_s));
  if (scan.gaps_rescanned > 0) {
    spdlog::info(
        "scan: the sweep missed {} stretches of stripe positions; {} frames swept "
        "again, {} gaps left",
        scan.gaps_rescanned, scan.frames_rescanned, scan.gaps_left);
  }
  if (grasp_plan) {
    spdlog::info("plan: {} arm, opening {:.0f} mm, tilt {:.0f} deg, wrist-forearm {:.1f} deg",
                 grasp_plan->side == device::Side::kLeft ? "left" : "right",
                 1e3 * grasp_plan->opening_m, RadToDeg(grasp_plan->tilt_rad),
                 RadToDeg(grasp_plan->comfort_rad));
  }
  return report;
}

const sim::SimObject* TargetObject(const sim::World& world, const model::BoxModel& box) {
  const sim::SimObject* object = nullptr;
  double best_d = 1e9;
  for (const sim::SimObject& obj : world.objects()) {
    const double d = (world.BodyPose(obj.body).translation() - box.X_WO.translation()).norm();
    if (d < best_d) best_d = d, object = &obj;
  }
  return object;
}

task::TaskConfig TaskConfigFor(const sim::Scenario& scenario) {
  if (!scenario.task) {
    throw InputError(scenario.path, "task", "",
                     "a task naming the target, e.g. task: {target: {color: yellow}} (model, plan "
                     "and run look for it)");
  }
  if (scenario.task->target_color.empty() && !model::ColourOfName(scenario.task->target_name)) {
    throw InputError(scenario.path, "task.target.name", scenario.task->target_name,
                     "a target whose name says its colour (e.g. yellow_box), or task.target.color: "
                     "the robot knows objects only by what it sees");
  }
  task::TaskConfig config;
  config.target_color = scenario.task->target_color;
  config.target_name = scenario.task->target_name;
  config.lift_m = scenario.task->lift_m;
  return config;
}

namespace {

// `hgrasp model`, and with `plan` also `hgrasp plan`: the task's first stages.
int LookAndPlan(const ModelOptions& o, bool plan) {
  const auto t0 = Clock::now();
  const sim::Scenario scenario = sim::LoadScenario(o.scenario);
  task::TaskConfig config = TaskConfigFor(scenario);
  task::RobotModel robot_model = task::LoadRobotModel(o.files.cameras, o.files.laser, o.files.leds);
  OutputDir out(o.out_dir);
  const StopSignals signals;
  config.stop = signals.request();
  Robot robot = OpenRobot(scenario, signals.request(), CleanLockstepWires(o.lockstep));
  if (EndedAtStart(robot, scenario, &out, plan ? "plan" : "model")) return 1;
  device::RobotDevices& dev = robot.devices;
  ScanTruthRecorder scan_truth(robot);
  config.sink_needs_every_image = false;  // the sink records the scan's truth only
  task::GraspTask task(&dev, robot_model, config,
                       [&](const device::StereoFrame& frame, const task::TaskView& view) {
                         scan_truth.OnFrame(frame, view);
                       });
  const bool looked = task.Look();
  scan_truth.Stop();
  const bool ok = looked && (!plan || task.Plan());
  const task::TaskResult& r = task.result();
  std::optional<nlohmann::json> truth;
  if (robot.truth() != nullptr) truth = LookTruth(*robot.truth(), r, scan_truth.truth());
  const SafeStopReport safe = robot.LeaveSafe();
  nlohmann::json report =
      LookReport(scenario, truth ? &*truth : nullptr, r, robot_model, plan, out.staging(), o.lean);
  report["ok"] = ok;
  report["failure"] = ok ? nlohmann::json(nullptr) : nlohmann::json(task::ToString(r.failure));
  report["failure_detail"] = ok ? nlohmann::json(nullptr) : nlohmann::json(r.message);
  report["failed_device"] =
      r.failed_device.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.failed_device);
  report["safe_stop"] = safe.Json();
  nlohmann::json timing = {{"total", Seconds(t0)}};
  if (r.scene) {
    timing["scan"] = r.stages[0].wall_s - r.scene->segment_s - r.scene->model_s;
    timing["segment"] = r.scene->segment_s;
    timing["model"] = r.scene->model_s;
  }
  if (plan && r.stages.size() > 1) timing["plan"] = r.stages[1].wall_s;
  report["timing_s"] = timing;
  WriteFileWhole(out.Path("report.json"), report.dump(2) + "\n");
  WriteTwinRecord(robot, out);
  out.Commit();
  spdlog::info("{}: total {:.2f} s; wrote {}", plan ? "plan" : "model", Seconds(t0), o.out_dir);
  if (!ok) {
    spdlog::warn("{}: {}: {}", plan ? "plan" : "model", task::ToString(r.failure), r.message);
  }
  return ok ? 0 : 1;
}

}  // namespace

int Model(const ModelOptions& o) { return LookAndPlan(o, false); }

int Plan(const ModelOptions& o) { return LookAndPlan(o, true); }

}  // namespace hgrasp::app
