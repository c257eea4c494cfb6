#pragma once
/// @file A sweep's baseline: per scene whether it passed and its figures, with a tolerance per
/// figure; a later sweep compared with it names each regression: a scene that passed and now
/// fails, or a figure worse than the baseline's by more than its tolerance.
///
/// The file (JSON, written by `hgrasp sweep --write-baseline`, edited by hand as needed):
///   {"hgrasp_sweep_baseline": 1, "stage": "run",
///    "tolerances": {"range.rms_mm": 0.1, ...},
///    "scenes": {"<scene>": {"ok": true, "failure": null, "figures": {"range.rms_mm": 0.41, ...}}}}
/// A figure absent from a scene (not measured, e.g. no grasp was planned) is not compared.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hgrasp::app::sweep {

/// A compared figure: its name, which way is worse, and its default tolerance.
struct BaselineFigure {
  const char* name;         ///< "range.rms_mm", ...
  bool higher_is_worse;     ///< false: lower is worse (coverage, boxes found, rise)
  double tolerance;         ///< default tolerance, in the figure's unit
  /// Compared only where the baseline's scene passed: the box's true rise in a scene that failed
  /// before or during its grasp measures what the failure did to the box (a hand that struck it,
  /// a box pushed over), which varies with any change; that scene's regression is its `ok`.
  bool only_where_ok = false;
};
extern const std::vector<BaselineFigure> kBaselineFigures;

/// A row's compared figures (only those it has), by name.
nlohmann::json BaselineFigures(const nlohmann::json& row);

/// The baseline of these rows, with the default tolerances.
nlohmann::json MakeBaseline(const std::string& stage, const std::vector<nlohmann::json>& rows);

/// Checks a baseline file's content.
/// @throws hgrasp::InputError naming `path` and the field that is wrong.
void CheckBaseline(const nlohmann::json& baseline, const std::string& path);

struct Regression {
  std::string scene;
  std::string figure;  ///< "ok" for a scene that passed and now fails
  std::string what;    ///< in words, with both values and the tolerance
};

struct Comparison {
  std::vector<Regression> regressions;
  std::vector<std::string> notes;  ///< scenes in one and not the other, scenes that now pass
  nlohmann::json Json() const;
};

/// Compares the rows with the baseline (CheckBaseline'd).
Comparison CompareWithBaseline(const nlohmann::json& baseline, const std::vector<nlohmann::json>& rows);

}  // namespace hgrasp::app::sweep
