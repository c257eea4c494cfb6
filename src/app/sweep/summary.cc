#include "app/sweep/summary.h"

#include <algorithm>
#include <cstdio>
#include <map>

#include "app/sweep/scene_row.h"

namespace hgrasp::app::sweep {
namespace {

using nlohmann::json;

const json* At(const json& j, const char* pointer) {
  const json::json_pointer p(pointer);
  if (!j.contains(p)) return nullptr;
  const json& v = j.at(p);
  return v.is_number() ? &v : nullptr;
}

std::vector<double> Values(const std::vector<json>& rows, const FigureSpec& f) {
  std::vector<double> v;
  for (const json& row : rows) {
    if (f.per_box) {
      for (const json& b : row.value("boxes", json::array())) {
        if (const json* x = At(b, f.pointer)) v.push_back(x->get<double>());
      }
    } else if (const json* x = At(row, f.pointer)) {
      v.push_back(x->get<double>());
    }
  }
  return v;
}

// The q-quantile (0..1) of sorted values, by linear interpolation between order statistics.
double Quantile(const std::vector<double>& sorted, double q) {
  const double pos = q * static_cast<double>(sorted.size() - 1);
  const size_t i = static_cast<size_t>(pos);
  if (i + 1 >= sorted.size()) return sorted.back();
  return sorted[i] + (pos - static_cast<double>(i)) * (sorted[i + 1] - sorted[i]);
}

std::string Csv(const json& v) {
  if (v.is_null()) return "";
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number_integer()) return std::to_string(v.get<std::int64_t>());
  if (v.is_number()) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v.get<double>());
    return buf;
  }
  const std::string s = v.is_string() ? v.get<std::string>() : v.dump();
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) {
    if (c == '"') q += '"';
    q += c;
  }
  return q + "\"";
}

json Get(const json& j, const char* pointer) {
  const json::json_pointer p(pointer);
  return j.contains(p) ? j.at(p) : json();
}

std::string Xml(const std::string& s) {
  std::string out;
  for (unsigned char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default:
        // XML 1.0 allows no control characters but tab, newline and carriage return.
        if (c < 0x20 && c != '\t' && c != '\n' && c != '\r') {
          out += '?';
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out;
}

}  // namespace

const std::vector<FigureSpec> kFigures = {
    {"center_mm", "/center_mm", true},
    {"max_edge_mm", "/max_edge_mm", true},
    {"yaw_deg", "/yaw_deg", true},
    {"range_rms_mm", "/range/rms_mm", false},
    {"coverage", "/range/coverage", false},
    {"outlier_fraction", "/range/outlier_fraction", false},
    {"contact_mm", "/grasp/contact_mm/0", false},
    {"contact_mm", "/grasp/contact_mm/1", false},
    {"servo_mm", "/servo/gripper_to_plan_mm", false},
    {"servo_deg", "/servo/gripper_to_plan_deg", false},
    {"true_rise_mm", "/lift/true_rise_mm", false},
    {"wall_s", "/wall_s", false},
    {"robot_s", "/robot_s", false},
};

json Totals(const std::vector<json>& rows) {
  json t = {{"scenes", rows.size()}};
  int ok = 0, boxes = 0, found = 0, within = 0, colour_ok = 0, lifted = 0, truly_lifted = 0,
      falsely_lifted = 0, unconfirmed = 0;
  double wall = 0;
  std::map<std::string, int> failures, statuses;
  json hoover = {{"truth_regions", 0}, {"correct", 0}, {"over", 0},
                 {"under", 0},         {"missed", 0},  {"noise", 0}};
  for (const json& row : rows) {
    ok += row.value("ok", false);
    ++statuses[row.value("status", "?")];
    if (row["failure"].is_string()) ++failures[row["failure"].get<std::string>()];
    for (const json& b : row.value("boxes", json::array())) {
      ++boxes;
      found += b.value("found", false);
      within += b.value("within_tolerance", false);
      colour_ok += b.value("color_ok", false);
    }
    if (row["lift"].is_object()) lifted += row["lift"].value("lifted", false);
    if (row["hoover"].is_object()) {
      for (auto& [k, v] : hoover.items()) v = v.get<int>() + row["hoover"].value(k, 0);
    }
    wall += row.value("wall_s", 0.0);
  }
  // A true lift: the box rose at least kTrueLiftFraction of the lift the task asked for;
  // counted from the rise (truth), whatever the task said.
  for (const json& row : rows) {
    const json rise = Get(row, "/lift/true_rise_mm");
    const json asked = Get(row, "/lift/task_lift_mm");
    if (rise.is_number() && asked.is_number() &&
        rise.get<double>() >= kTrueLiftFraction * asked.get<double>()) {
      ++truly_lifted;
      // In the hand by the truth, but the cameras could not tell (hidden by the forearm, say).
      if (Get(row, "/lift/lifted") != true) ++unconfirmed;
    } else if (Get(row, "/lift/lifted") == true) {
      ++falsely_lifted;  // the task said lifted, the truth says otherwise (or was not read)
    }
  }
  t["ok"] = ok;
  t["failed"] = static_cast<int>(rows.size()) - ok;
  t["statuses"] = statuses;
  t["failures"] = failures;
  t["boxes"] = boxes;
  t["boxes_found"] = found;
  t["boxes_within_tolerance"] = within;
  t["boxes_color_ok"] = colour_ok;
  t["lifted"] = lifted;
  t["truly_lifted"] = truly_lifted;
  t["falsely_lifted"] = falsely_lifted;
  t["truly_lifted_unconfirmed"] = unconfirmed;
  t["hoover"] = hoover;
  t["wall_s"] = wall;
  json figures = json::object();
  std::map<std::string, std::vector<double>> values;
  for (const FigureSpec& f : kFigures) {
    std::vector<double> v = Values(rows, f);
    values[f.name].insert(values[f.name].end(), v.begin(), v.end());
  }
  for (auto& [name, v] : values) {
    if (v.empty()) {
      figures[name] = {{"n", 0}, {"median", nullptr}, {"p95", nullptr}, {"max", nullptr}};
      continue;
    }
    std::sort(v.begin(), v.end());
    figures[name] = {{"n", v.size()},
                     {"median", Quantile(v, 0.5)},
                     {"p95", Quantile(v, 0.95)},
                     {"max", v.back()}};
  }
  t["figures"] = figures;
  return t;
}

json Summary(const json& sweep, const std::vector<json>& rows) {
  return {{"sweep", sweep}, {"totals", Totals(rows)}, {"scenes", rows}};
}

std::string SummaryCsv(const std::vector<json>& rows) {
  struct Column {
    const char* name;
    const char* pointer;
  };
  static const Column scene_columns[] = {
      {"status", "/status"},
      {"failure", "/failure"},
      {"failure_detail", "/failure_detail"},
      {"seed", "/seed"},
      {"wall_s", "/wall_s"},
      {"robot_s", "/robot_s"},
      {"range_points", "/range/points"},
      {"range_rms_mm", "/range/rms_mm"},
      {"outliers", "/range/outliers"},
      {"outlier_fraction", "/range/outlier_fraction"},
      {"coverage", "/range/coverage"},
      {"hoover_regions", "/hoover/truth_regions"},
      {"hoover_correct", "/hoover/correct"},
      {"hoover_over", "/hoover/over"},
      {"hoover_under", "/hoover/under"},
      {"hoover_missed", "/hoover/missed"},
      {"hoover_noise", "/hoover/noise"},
      {"boxes_found", "/boxes_found"},
      {"boxes_total", "/boxes_total"},
      {"target_object", "/target_object"},
      {"grasp_planned", "/grasp/planned"},
      {"arm", "/grasp/arm"},
      {"contact0_mm", "/grasp/contact_mm/0"},
      {"contact1_mm", "/grasp/contact_mm/1"},
      {"servo_mm", "/servo/gripper_to_plan_mm"},
      {"servo_deg", "/servo/gripper_to_plan_deg"},
      {"lifted", "/lift/lifted"},
      {"true_rise_mm", "/lift/true_rise_mm"},
  };
  static const Column box_columns[] = {
      {"object", "/object"},
      {"found", "/found"},
      {"box", "/box"},
      {"center_mm", "/center_mm"},
      {"edge_x_mm", "/edge_mm/0"},
      {"edge_y_mm", "/edge_mm/1"},
      {"edge_z_mm", "/edge_mm/2"},
      {"max_edge_mm", "/max_edge_mm"},
      {"yaw_deg", "/yaw_deg"},
      {"color_name", "/color_name"},
      {"true_color_name", "/true_color_name"},
      {"color_ok", "/color_ok"},
      {"within_tolerance", "/within_tolerance"},
  };
  std::string out = "kind,scene";
  for (const Column& c : scene_columns) out += std::string(",") + c.name;
  for (const Column& c : box_columns) out += std::string(",") + c.name;
  out += "\n";
  for (const json& row : rows) {
    out.append("scene,").append(Csv(row["scene"]));
    for (const Column& c : scene_columns) out.append(",").append(Csv(Get(row, c.pointer)));
    for (size_t i = 0; i < std::size(box_columns); ++i) out += ",";
    out += "\n";
    for (const json& b : row.value("boxes", json::array())) {
      out.append("box,").append(Csv(row["scene"]));
      for (size_t i = 0; i < std::size(scene_columns); ++i) out += ",";
      for (const Column& c : box_columns) out.append(",").append(Csv(Get(b, c.pointer)));
      out += "\n";
    }
  }
  return out;
}

std::string JunitXml(const std::string& stage, const std::vector<json>& rows) {
  int failures = 0, errors = 0;
  double time = 0;
  for (const json& row : rows) {
    const std::string status = row.value("status", "");
    failures += status == "failed";
    errors += status != "failed" && status != "ok";
    time += row.value("wall_s", 0.0);
  }
  char head[256];
  std::snprintf(head, sizeof head,
                "<testsuite name=\"hgrasp sweep (%s)\" tests=\"%zu\" failures=\"%d\" errors=\"%d\" "
                "skipped=\"0\" time=\"%.3f\">\n",
                Xml(stage).c_str(), rows.size(), failures, errors, time);
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites>\n";
  out += head;
  for (const json& row : rows) {
    char t[32];
    std::snprintf(t, sizeof t, "%.3f", row.value("wall_s", 0.0));
    out += "  <testcase classname=\"hgrasp.sweep." + Xml(stage) + "\" name=\"" +
           Xml(row.value("scene", "")) + "\" time=\"" + t + "\"";
    const std::string status = row.value("status", "");
    if (status == "ok") {
      out += "/>\n";
      continue;
    }
    const std::string failure = row["failure"].is_string() ? row["failure"].get<std::string>() : status;
    const std::string detail =
        row["failure_detail"].is_string() ? row["failure_detail"].get<std::string>() : "";
    const char* element = status == "failed" ? "failure" : "error";
    out += ">\n    <" + std::string(element) + " message=\"" + Xml(failure) + "\" type=\"" +
           Xml(failure) + "\">" + Xml(detail) + "</" + element + ">\n  </testcase>\n";
  }
  out += "</testsuite>\n</testsuites>\n";
  return out;
}

}  // namespace hgrasp::app::sweep
