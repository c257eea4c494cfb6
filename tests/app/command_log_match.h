#pragma once
// The check every whole run through the real drivers ends with: each device executed what its
// driver logged, nothing lost, repeated or altered. "Equal" as drivers/serial/command_log.h
// defines it: the driver's log holds every command it sent that may have run, in order, each
// confirmed (the device executed it) or unconfirmed (it cannot know: a configuration Set*
// re-sent after a damaged reply, SafeStop's blind ABORT, the SensorHand's stream starts, sent
// again while its stream is silent). The device's log must be the driver's with each
// unconfirmed entry present once or not at all.

#include <algorithm>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

namespace hgrasp::testing {

using json = nlohmann::json;

inline bool Unconfirmed(const json& e) { return e.is_object() && e.contains("unconfirmed"); }
inline const json& Command(const json& e) { return Unconfirmed(e) ? e["unconfirmed"] : e; }

// Whether `device` is `driver` with each unconfirmed entry of it kept once or dropped; if so,
// *ran counts the unconfirmed entries kept (as many as can be), else *why shows where the two
// part.
inline bool Matches(const json& driver, const json& device, int* ran, std::string* why) {
  const std::size_t n = driver.size(), m = device.size();
  // ok[i][j]: driver[i..] matches device[j..].
  std::vector<std::vector<char>> ok(n + 1, std::vector<char>(m + 1, 0));
  ok[n][m] = 1;
  for (std::size_t i = n; i-- > 0;) {
    for (std::size_t j = m + 1; j-- > 0;) {
      const bool same = j < m && Command(driver[i]) == device[j] && ok[i + 1][j + 1];
      ok[i][j] = same || (Unconfirmed(driver[i]) && ok[i + 1][j]);
    }
  }
  *ran = 0;
  if (ok[0][0]) {
    for (std::size_t i = 0, j = 0; i < n; ++i) {
      if (j < m && Command(driver[i]) == device[j] && ok[i + 1][j + 1]) {
        if (Unconfirmed(driver[i])) ++*ran;
        ++j;
      }
    }
    return true;
  }
  // Where they part: the furthest pair of places both can reach from their starts.
  std::vector<std::vector<char>> reach(n + 1, std::vector<char>(m + 1, 0));
  reach[0][0] = 1;
  std::size_t bi = 0, bj = 0;
  for (std::size_t i = 0; i <= n; ++i) {
    for (std::size_t j = 0; j <= m; ++j) {
      if (!reach[i][j]) continue;
      if (j > bj || (j == bj && i > bi)) bi = i, bj = j;
      if (i == n) continue;
      if (j < m && Command(driver[i]) == device[j]) reach[i + 1][j + 1] = 1;
      if (Unconfirmed(driver[i])) reach[i + 1][j] = 1;
    }
  }
  std::ostringstream s;
  s << "driver " << n << " entries, device " << m << "; they part at driver entry " << bi
    << ", device entry " << bj << "\n";
  using Place = std::tuple<const char*, const json*, std::size_t>;
  for (const auto& [name, log, at] : {Place{"driver", &driver, bi}, Place{"device", &device, bj}}) {
    s << "  " << name << ":";
    for (std::size_t k = at >= 4 ? at - 4 : 0; k < std::min(log->size(), at + 6); ++k) {
      s << (k == at ? "\n    > " : "\n      ") << k << " " << (*log)[k].dump();
    }
    s << "\n";
  }
  *why = s.str();
  return false;
}

}  // namespace hgrasp::testing
