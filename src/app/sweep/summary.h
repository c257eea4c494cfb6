#pragma once
/// @file What a sweep writes from its rows: summary.json (the sweep, its totals, each error
/// figure's distribution, and the rows), summary.csv (one line per scene and one per true box)
/// and junit.xml (one test case per scene, as CI servers read it).

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hgrasp::app::sweep {

/// The error figures the summary gives distributions of, each by a name and where it is in a
/// row (per scene, or per box for the box figures).
struct FigureSpec {
  const char* name;     ///< "center_mm", ...
  const char* pointer;  ///< JSON pointer into a row, or into a box of row["boxes"] when per_box
  bool per_box;
};
extern const std::vector<FigureSpec> kFigures;

/// Totals of the rows (sorted by scene): counts by status and failure, boxes found and within
/// tolerance, lifts, times, and per figure its count, median, 95th percentile and maximum.
nlohmann::json Totals(const std::vector<nlohmann::json>& rows);

/// summary.json: {"sweep": sweep, "totals": Totals(rows), "scenes": rows}.
nlohmann::json Summary(const nlohmann::json& sweep, const std::vector<nlohmann::json>& rows);

/// summary.csv: a header, then per scene a line of kind "scene", followed by a line of kind
/// "box" for each of its true boxes (RFC 4180 quoting).
std::string SummaryCsv(const std::vector<nlohmann::json>& rows);

/// junit.xml: one testsuite "hgrasp sweep (STAGE)", one testcase per scene (classname
/// "hgrasp.sweep.STAGE", time its wall time); a task failure is a <failure> (message the failure
/// name, text its detail), a crash, time-out, bad file or other error an <error>.
std::string JunitXml(const std::string& stage, const std::vector<nlohmann::json>& rows);

}  // namespace hgrasp::app::sweep
