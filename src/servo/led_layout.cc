#include "servo/led_layout.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/SVD>
#include <fstream>
#include <set>
#include <sstream>

#include "common/error.h"
#include "common/yaml_file.h"
#include "common/yaml_util.h"

namespace hgrasp::servo {
namespace {

using yaml::Where;

[[noreturn]] void Fail(const std::string& path, const YAML::Node& at, const std::string& field,
                       const std::string& expected) {
  throw InputError(Where(path, at.Mark()), field, yaml::Render(at), expected + yaml::QuoteHint(at));
}

LedLayout ParseSide(const std::string& path, const YAML::Node& node, const std::string& field) {
  const std::string expected = "a list of 3 to " + std::to_string(kMaxLeds) +
                               " LED positions [x, y, z] in the gripper frame, m";
  if (!node.IsSequence() || node.size() < 3 || node.size() > kMaxLeds) {
    Fail(path, node, field, expected);
  }
  LedLayout layout;
  for (std::size_t i = 0; i < node.size(); ++i) {
    const YAML::Node p = node[i];
    const std::string f = yaml::Index(field, i);
    const std::string p_expected = "an LED position [x, y, z] in m (finite numbers)";
    if (!p.IsSequence() || p.size() != 3) Fail(path, p, f, p_expected);
    Eigen::Vector3d v;
    for (int k = 0; k < 3; ++k) {
      const std::optional<double> x = yaml::ParseNumber(p[k]);
      if (!x) Fail(path, p, f, p_expected);
      v[k] = *x;
    }
    if (v.norm() > kMaxLedDistance) {
      Fail(path, p, f,
           "an LED on the gripper, within " + std::to_string(int(1e3 * kMaxLedDistance)) +
               " mm of its frame's origin (the hand is 10 cm across)");
    }
    for (int j = 0; j < layout.size(); ++j) {
      if ((layout.p_E[j] - v).norm() < 1e-3) {
        Fail(path, p, f, "an LED at least 1 mm from LED " + std::to_string(j));
      }
    }
    layout.p_E.push_back(v);
  }
  // Not all on one line: the pose would not be determined.
  Eigen::MatrixXd d(3, layout.size());
  for (int i = 0; i < layout.size(); ++i) d.col(i) = layout.p_E[i] - layout.Centroid();
  const Eigen::Vector3d s = Eigen::JacobiSVD<Eigen::MatrixXd>(d).singularValues();
  if (s[1] < 1e-3 * s[0] || s[1] < 1e-6) {
    Fail(path, node, field, "LEDs not all on one line (the gripper's pose needs 3 off a line)");
  }
  return layout;
}

}  // namespace

Eigen::Vector3d LedLayout::Centroid() const {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : p_E) c += p;
  return p_E.empty() ? c : Eigen::Vector3d(c / static_cast<double>(p_E.size()));
}

LedLayouts LoadLedLayouts(const std::string& path) {
  return ParseLedLayouts(yaml::ReadText(path, "a readable LED layout file"), path);
}

LedLayouts ParseLedLayouts(const std::string& text, const std::string& path) {
  const std::string top_expected = "an LED layout: a map with frame: gripper, left and right";
  const YAML::Node root = yaml::LoadDocument(text, path, top_expected);
  if (!root.IsMap()) throw InputError(path, "", yaml::Render(root), top_expected);
  std::set<std::string> seen;
  for (const auto& kv : root) {
    const std::string key = kv.first.Scalar();
    if (key != "frame" && key != "left" && key != "right") {
      Fail(path, kv.first, key, "a key " + yaml::OneOf({"frame", "left", "right"}));
    }
    if (!seen.insert(key).second) Fail(path, kv.first, key, "each key once");
  }
  for (const char* key : {"frame", "left", "right"}) {
    if (!seen.count(key)) throw InputError(path, key, "", top_expected);
  }
  const YAML::Node frame = root["frame"];
  if (!frame.IsScalar() || frame.Scalar() != "gripper") {
    Fail(path, frame, "frame", "gripper (positions are in the gripper frame E)");
  }
  LedLayouts layouts;
  layouts.left = ParseSide(path, root["left"], "left");
  layouts.right = ParseSide(path, root["right"], "right");
  return layouts;
}

}  // namespace hgrasp::servo
