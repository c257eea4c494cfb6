#include "app/sweep/scene_row.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

namespace hgrasp::app::sweep {
namespace {

using nlohmann::json;

// The number at report[path...] (a JSON pointer), or null.
json Number(const json& j, const char* pointer, double scale = 1.0) {
  const json::json_pointer p(pointer);
  if (!j.contains(p) || !j.at(p).is_number()) return nullptr;
  return scale * j.at(p).get<double>();
}

double Or(const json& v, double fallback) { return v.is_number() ? v.get<double>() : fallback; }

bool StageAtLeast(const std::string& stage, const char* than) {
  const auto index = [](const std::string& s) {
    for (size_t i = 0; i < std::size(kStages); ++i) {
      if (s == kStages[i]) return static_cast<int>(i);
    }
    return -1;
  };
  return index(stage) >= index(than);
}

// The row's figures from report.json.
void AddFigures(const json& report, const std::string& stage, json* row) {
  json& r = *row;
  const json truth = report.value("truth", json::object());
  r["robot_s"] = Number(report, "/device_time_s");
  if (truth.contains("range")) {
    const json& t = truth["range"];
    r["range"] = {{"points", t.value("points", report.value("/range/points"_json_pointer, 0))},
                  {"rms_mm", Number(t, "/rms_to_surface_m", 1e3)},
                  {"outliers", t.contains("outliers") ? t["outliers"] : t.value("beyond_5mm", json())},
                  {"outlier_fraction", Number(t, "/outlier_fraction")},
                  {"coverage", Number(t, "/coverage")}};
    if (r["range"]["outlier_fraction"].is_null() && r["range"]["outliers"].is_number() &&
        t.value("points", 0) > 0) {
      r["range"]["outlier_fraction"] = r["range"]["outliers"].get<double>() / t["points"].get<double>();
    }
  }
  if (truth.contains("hoover")) {
    json h = truth["hoover"];
    h.erase("min_cells");
    r["hoover"] = h;
  }
  int found = 0;
  json boxes = json::array();
  for (const json& b : truth.value("boxes", json::array())) {
    const bool is_found = b.value("found", false);
    found += is_found;
    json box = {{"object", b.value("object", "")},
                {"found", is_found},
                {"box", b.value("box", json())},
                {"center_mm", Number(b, "/center_error_m", 1e3)},
                {"edge_mm", nullptr},
                {"max_edge_mm", Number(b, "/max_edge_error_m", 1e3)},
                {"yaw_deg", Number(b, "/yaw_error_deg")},
                {"color_name", b.value("color_name", json())},
                {"true_color_name", b.value("true_color_name", json())},
                {"color_ok", b.value("color_ok", false)}};
    if (b.contains("edge_error_m")) {
      json e = json::array();
      for (const json& v : b["edge_error_m"]) e.push_back(1e3 * v.get<double>());
      box["edge_mm"] = e;
    }
    box["within_tolerance"] = is_found && box["color_ok"].get<bool>() &&
                              Or(box["center_mm"], 1e9) <= kCenterToleranceMm &&
                              Or(box["max_edge_mm"], 1e9) <= kEdgeToleranceMm &&
                              Or(box["yaw_deg"], 1e9) <= kYawToleranceDeg;
    boxes.push_back(box);
  }
  r["boxes"] = boxes;
  r["boxes_found"] = found;
  r["boxes_total"] = boxes.size();
  // The target: the true object the chosen box models.
  r["target_object"] = nullptr;
  if (report.contains("target") && report["target"].is_number()) {
    for (const json& b : boxes) {
      if (b["box"] == report["target"]) r["target_object"] = b["object"];
    }
  }
  if (StageAtLeast(stage, "plan")) {
    const json g = report.value("grasp", json());
    json contact = nullptr;
    if (truth.contains("grasp")) {
      contact = json::array();
      for (const json& d : truth["grasp"]["contact_to_surface_m"]) contact.push_back(1e3 * d.get<double>());
    }
    r["grasp"] = {{"planned", g.is_object()},
                  {"arm", g.is_object() ? g.value("arm", json()) : json()},
                  {"contact_mm", contact}};
  }
  if (stage == "run") {
    const json run = truth.value("run", json::object());
    if (run.contains("grasp_reached")) {
      // The servo's end against the plan, and where the open-loop approach had left the gripper
      // against the pre-grasp (what the servo had to correct).
      r["servo"] = {{"gripper_to_plan_mm", Number(run, "/grasp_reached/gripper_to_plan_m", 1e3)},
                    {"gripper_to_plan_deg", Number(run, "/grasp_reached/gripper_to_plan_deg")},
                    {"open_loop_mm", Number(run, "/servo_start/gripper_to_plan_m", 1e3)},
                    {"open_loop_deg", Number(run, "/servo_start/gripper_to_plan_deg")}};
    }
    const json rise = Number(run, "/object_rise_m", 1e3);
    const json lifted = report.value("/result/lifted"_json_pointer, json(false));
    r["lift"] = {{"lifted", lifted},
                 {"true_rise_mm", rise},
                 {"measured_rise_mm", Number(report, "/result/lift_height", 1e3)},
                 {"task_lift_mm", Number(report, "/task/lift", 1e3)}};
  }
}

// A badness to sort by, worst first: a failure outweighs every figure; then missed boxes, then
// each figure against its tolerance.
double Score(const json& row) {
  double s = row.value("ok", false) ? 0.0 : 100.0;
  for (const json& b : row.value("boxes", json::array())) {
    if (!b.value("found", false)) {
      s += 10;
      continue;
    }
    s += std::max({Or(b["center_mm"], 0) / kCenterToleranceMm,
                   Or(b["max_edge_mm"], 0) / kEdgeToleranceMm, Or(b["yaw_deg"], 0) / kYawToleranceDeg});
    if (!b.value("color_ok", false)) s += 5;
  }
  if (row.contains("range") && row["range"].is_object()) {
    s += 1.0 - Or(row["range"]["coverage"], 1.0);
    s += Or(row["range"]["rms_mm"], 0.0);
  }
  if (row.contains("servo") && row["servo"].is_object()) {
    s += Or(row["servo"]["gripper_to_plan_mm"], 0.0) / 5.0;
  }
  return s;
}

}  // namespace

std::vector<std::string> PictureNames(const std::string& stage) {
  if (stage == "scan") return {};
  if (stage == "model") return {"segments.png", "models.png"};
  if (stage == "plan") return {"segments.png", "grasp.png"};
  return {"segments.png",
          "grasp.png",
          "servo_servo_start.png",
          "servo_pregrasp_reached.png",
          "servo_grasp_reached.png",
          "servo_lifted.png"};
}

std::string Tail(const std::string& path, int lines) {
  std::ifstream in(path);
  if (!in) return "";
  std::vector<std::string> all;
  for (std::string line; std::getline(in, line);) all.push_back(line);
  std::string out;
  for (size_t i = all.size() > static_cast<size_t>(lines) ? all.size() - lines : 0; i < all.size(); ++i) {
    out += all[i];
    if (i + 1 < all.size()) out += "\n";
  }
  return out;
}

json MakeRow(const SceneEntry& entry, const std::string& stage, const ProcessOutcome& outcome,
             const std::optional<json>& report, const std::string& log_tail,
             const std::string& dir, const std::vector<std::string>& existing_pictures) {
  json row = {{"scene", entry.scene},
              {"file", entry.file},
              {"dir", dir},
              {"seed", report ? report->value("seed", json()) : json()},
              {"stage", stage},
              {"exit_code", outcome.exit_code ? json(*outcome.exit_code) : json()},
              {"signal", outcome.signal ? json(SignalName(*outcome.signal)) : json()},
              {"wall_s", outcome.wall_s},
              {"robot_s", nullptr},
              {"range", nullptr},
              {"hoover", nullptr},
              {"boxes", json::array()},
              {"boxes_found", 0},
              {"boxes_total", 0},
              {"target_object", nullptr},
              {"grasp", nullptr},
              {"servo", nullptr},
              {"lift", nullptr}};
  // The last line the scene wrote that says what went wrong (for a crash or a bad file).
  std::string last_line;
  {
    std::istringstream in(log_tail);
    for (std::string line; std::getline(in, line);) {
      if (!line.empty()) last_line = line;
    }
  }
  std::string status, failure, detail;
  if (outcome.timed_out) {
    status = failure = "timeout";
    detail = "killed after the time limit of the sweep";
  } else if (outcome.signal) {
    status = failure = "crash";
    detail = SignalName(*outcome.signal) + (last_line.empty() ? "" : "; last output: " + last_line);
  } else if (outcome.exit_code == 0 && report) {
    status = "ok";
  } else if (outcome.exit_code == 2) {
    status = failure = "bad_input";
    detail = last_line;
  } else if (outcome.exit_code == 1 && report && report->contains("failure") &&
             (*report)["failure"].is_string()) {
    status = "failed";
    failure = (*report)["failure"].get<std::string>();
    detail = report->value("failure_detail", json("")).is_string()
                 ? report->value("failure_detail", std::string())
                 : "";
  } else {
    status = failure = "error";
    detail = "exit status " + (outcome.exit_code ? std::to_string(*outcome.exit_code) : "?") +
             (report ? "" : ", no report.json") +
             (last_line.empty() ? "" : "; last output: " + last_line);
  }
  row["status"] = status;
  row["ok"] = status == "ok";
  row["failure"] = failure.empty() ? json() : json(failure);
  row["failure_detail"] = failure.empty() ? json() : json(detail);
  if (report) AddFigures(*report, stage, &row);
  json pictures = {{"segments", nullptr}, {"grasp", nullptr}, {"servo", json::array()}};
  for (const std::string& p : existing_pictures) {
    const std::string name = p.substr(p.find_last_of('/') + 1);
    if (name == "segments.png") pictures["segments"] = p;
    else if (name == "grasp.png" || name == "models.png") pictures["grasp"] = p;
    else pictures["servo"].push_back(p);
  }
  row["pictures"] = pictures;
  row["score"] = Score(row);
  return row;
}

}  // namespace hgrasp::app::sweep
