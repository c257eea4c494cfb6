#include "app/sweep/baseline.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "common/error.h"
#include "fmt/format.h"

namespace hgrasp::app::sweep {
namespace {

using nlohmann::json;

std::optional<double> Number(const json& j, const char* pointer) {
  const json::json_pointer p(pointer);
  if (!j.contains(p) || !j.at(p).is_number()) return std::nullopt;
  return j.at(p).get<double>();
}

}  // namespace

const std::vector<BaselineFigure> kBaselineFigures = {
    {"range.rms_mm", true, 0.1},
    {"range.coverage", false, 0.01},
    {"range.outlier_fraction", true, 0.002},
    {"boxes.found", false, 0.0},
    {"boxes.color_ok", false, 0.0},
    {"boxes.worst_center_mm", true, 1.0},
    {"boxes.worst_edge_mm", true, 1.5},
    {"boxes.worst_yaw_deg", true, 0.5},
    {"grasp.worst_contact_mm", true, 1.0},
    {"servo.gripper_to_plan_mm", true, 1.0},
    {"servo.gripper_to_plan_deg", true, 0.5},
    {"lift.true_rise_mm", false, 5.0, true},
};

json BaselineFigures(const json& row) {
  json f = json::object();
  const auto put = [&](const char* name, std::optional<double> v) {
    if (v) f[name] = *v;
  };
  put("range.rms_mm", Number(row, "/range/rms_mm"));
  put("range.coverage", Number(row, "/range/coverage"));
  put("range.outlier_fraction", Number(row, "/range/outlier_fraction"));
  if (row.value("boxes_total", 0) > 0) {
    int found = 0, colour_ok = 0;
    std::optional<double> centre, edge, yaw;
    const auto worst = [](std::optional<double>* w, std::optional<double> v) {
      if (v) *w = std::max(w->value_or(*v), *v);
    };
    for (const json& b : row["boxes"]) {
      found += b.value("found", false);
      colour_ok += b.value("color_ok", false);
      worst(&centre, Number(b, "/center_mm"));
      worst(&edge, Number(b, "/max_edge_mm"));
      worst(&yaw, Number(b, "/yaw_deg"));
    }
    f["boxes.found"] = found;
    f["boxes.color_ok"] = colour_ok;
    put("boxes.worst_center_mm", centre);
    put("boxes.worst_edge_mm", edge);
    put("boxes.worst_yaw_deg", yaw);
  }
  const std::optional<double> c0 = Number(row, "/grasp/contact_mm/0");
  const std::optional<double> c1 = Number(row, "/grasp/contact_mm/1");
  if (c0 && c1) f["grasp.worst_contact_mm"] = std::max(*c0, *c1);
  put("servo.gripper_to_plan_mm", Number(row, "/servo/gripper_to_plan_mm"));
  put("servo.gripper_to_plan_deg", Number(row, "/servo/gripper_to_plan_deg"));
  put("lift.true_rise_mm", Number(row, "/lift/true_rise_mm"));
  return f;
}

json MakeBaseline(const std::string& stage, const std::vector<json>& rows) {
  json tolerances = json::object();
  for (const BaselineFigure& f : kBaselineFigures) tolerances[f.name] = f.tolerance;
  json scenes = json::object();
  for (const json& row : rows) {
    scenes[row["scene"].get<std::string>()] = {
        {"ok", row.value("ok", false)}, {"failure", row["failure"]}, {"figures", BaselineFigures(row)}};
  }
  return {{"hgrasp_sweep_baseline", 1}, {"stage", stage}, {"tolerances", tolerances}, {"scenes", scenes}};
}

void CheckBaseline(const json& b, const std::string& path) {
  if (!b.is_object() || b.value("hgrasp_sweep_baseline", 0) != 1) {
    throw InputError(path, "hgrasp_sweep_baseline", b.is_object() ? b.value("hgrasp_sweep_baseline", json()).dump() : "",
                     "a sweep baseline (hgrasp sweep --write-baseline), version 1");
  }
  if (!b.contains("tolerances") || !b["tolerances"].is_object()) {
    throw InputError(path, "tolerances", "", "an object of figure: tolerance");
  }
  for (const auto& [name, t] : b["tolerances"].items()) {
    const bool known = std::any_of(kBaselineFigures.begin(), kBaselineFigures.end(),
                                   [&](const BaselineFigure& f) { return name == f.name; });
    if (!known) {
      std::string names;
      for (const BaselineFigure& f : kBaselineFigures) names += (names.empty() ? "" : ", ") + std::string(f.name);
      throw InputError(path, "tolerances." + name, "", "one of the compared figures: " + names);
    }
    if (!t.is_number() || !(t.get<double>() >= 0) || !std::isfinite(t.get<double>())) {
      throw InputError(path, "tolerances." + name, t.dump(), "a tolerance >= 0");
    }
  }
  if (!b.contains("scenes") || !b["scenes"].is_object()) {
    throw InputError(path, "scenes", "", "an object of scene: {ok, failure, figures}");
  }
  for (const auto& [scene, s] : b["scenes"].items()) {
    if (!s.is_object() || !s.contains("ok") || !s["ok"].is_boolean() || !s.contains("figures") ||
        !s["figures"].is_object()) {
      throw InputError(path, "scenes." + scene, s.dump(), "{\"ok\": bool, \"figures\": {...}}");
    }
    for (const auto& [name, v] : s["figures"].items()) {
      if (!v.is_number()) throw InputError(path, "scenes." + scene + ".figures." + name, v.dump(), "a number");
    }
  }
}

json Comparison::Json() const {
  json r = json::array();
  for (const Regression& g : regressions) {
    r.push_back({{"scene", g.scene}, {"figure", g.figure}, {"what", g.what}});
  }
  return {{"regressions", r}, {"notes", notes}};
}

Comparison CompareWithBaseline(const json& baseline, const std::vector<json>& rows) {
  Comparison c;
  const json& scenes = baseline["scenes"];
  std::map<std::string, const json*> now;
  for (const json& row : rows) now[row["scene"].get<std::string>()] = &row;
  for (const auto& [scene, base] : scenes.items()) {
    const auto it = now.find(scene);
    if (it == now.end()) {
      c.notes.push_back(scene + ": in the baseline, not in this sweep");
      continue;
    }
    const json& row = *it->second;
    const bool ok = row.value("ok", false);
    if (base["ok"].get<bool>() && !ok) {
      c.regressions.push_back(
          {scene, "ok",
           fmt::format("passed in the baseline, now fails: {}{}",
                       row["failure"].is_string() ? row["failure"].get<std::string>() : "?",
                       row["failure_detail"].is_string() ? " (" + row["failure_detail"].get<std::string>() + ")" : "")});
    } else if (!base["ok"].get<bool>() && ok) {
      c.notes.push_back(scene + ": failed in the baseline (" +
                        (base.value("failure", json()).is_string() ? base["failure"].get<std::string>() : "?") +
                        "), now passes");
    }
    const json figures = BaselineFigures(row);
    for (const BaselineFigure& f : kBaselineFigures) {
      if (!base["figures"].contains(f.name) || !figures.contains(f.name)) continue;
      if (f.only_where_ok && !base["ok"].get<bool>()) continue;
      const double was = base["figures"][f.name].get<double>();
      const double is = figures[f.name].get<double>();
      const double tol = baseline["tolerances"].value(f.name, f.tolerance);
      const double worse = f.higher_is_worse ? is - was : was - is;
      if (worse > tol) {
        c.regressions.push_back({scene, f.name,
                                 fmt::format("{:.4g} in the baseline, now {:.4g} ({} by {:.4g}; "
                                             "tolerance {:.4g})",
                                             was, is, f.higher_is_worse ? "higher" : "lower",
                                             std::abs(is - was), tol)});
      }
    }
  }
  for (const auto& [scene, row] : now) {
    if (!scenes.contains(scene)) c.notes.push_back(scene + ": not in the baseline");
  }
  return c;
}

}  // namespace hgrasp::app::sweep
