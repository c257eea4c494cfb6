#include "sim/hoover.h"

#include <map>
#include <stdexcept>

namespace hgrasp::sim {

HooverCounts CompareSegmentations(const std::vector<int>& truth, const std::vector<int>& machine,
                                  int min_truth_cells, double tolerance) {
  if (truth.size() != machine.size()) {
    throw std::invalid_argument(
        "CompareSegmentations: expected as many machine labels as truth "
        "labels, got " +
        std::to_string(machine.size()) + " and " + std::to_string(truth.size()));
  }
  if (min_truth_cells < 0) {
    throw std::invalid_argument("CompareSegmentations: expected min_truth_cells >= 0, got " +
                                std::to_string(min_truth_cells));
  }
  if (!(tolerance > 0.5 && tolerance <= 1.0)) {
    throw std::invalid_argument("CompareSegmentations: expected a tolerance in (0.5, 1], got " +
                                std::to_string(tolerance));
  }
  // O >= T n, with slack for T n computed in floating point (e.g. 0.8 * 10).
  auto passes = [tolerance](int overlap, int n) { return overlap >= tolerance * n - 1e-9; };

  // Truth regions considered: dense indices in ascending code order.
  std::map<int, int> truth_cells;
  for (int t : truth) {
    if (t >= 0) ++truth_cells[t];
  }
  std::map<int, int> g_index;
  std::vector<int> g_code, g_size;
  for (const auto& [code, cells] : truth_cells) {
    if (cells < min_truth_cells) continue;
    g_index[code] = static_cast<int>(g_code.size());
    g_code.push_back(code);
    g_size.push_back(cells);
  }
  const int n_g = static_cast<int>(g_code.size());

  // Machine regions and overlaps, skipping cells of the truth regions left out.
  std::map<int, int> m_index;
  std::vector<int> m_size;
  std::vector<std::map<int, int>> o_of_g(n_g);  // per G: M -> O(G, M)
  std::vector<std::map<int, int>> o_of_m;       // per M: G -> O(G, M)
  for (std::size_t i = 0; i < truth.size(); ++i) {
    int g = -1;
    if (truth[i] >= 0) {
      const auto it = g_index.find(truth[i]);
      if (it == g_index.end()) continue;  // a region too small: ignored on both sides
      g = it->second;
    }
    if (machine[i] < 0) continue;
    const auto [it, added] = m_index.emplace(machine[i], static_cast<int>(m_size.size()));
    if (added) {
      m_size.push_back(0);
      o_of_m.emplace_back();
    }
    const int m = it->second;
    ++m_size[m];
    if (g >= 0) {
      ++o_of_g[g][m];
      ++o_of_m[m][g];
    }
  }
  const int n_m = static_cast<int>(m_size.size());

  std::vector<bool> g_correct(n_g, false), g_over(n_g, false), g_under(n_g, false);
  std::vector<bool> m_in_instance(n_m, false);
  std::vector<std::vector<int>> under_members(n_m);

  for (int g = 0; g < n_g; ++g) {
    // Correct detection; and the machine regions mostly inside G, candidates for an
    // over-segmentation (taking all of them maximises the sum, so the instance exists iff they
    // qualify together).
    std::vector<int> parts;
    int sum = 0;
    for (const auto& [m, o] : o_of_g[g]) {
      if (!passes(o, m_size[m])) continue;
      if (passes(o, g_size[g])) {
        g_correct[g] = true;
        m_in_instance[m] = true;
      }
      parts.push_back(m);
      sum += o;
    }
    if (parts.size() >= 2 && passes(sum, g_size[g])) {
      g_over[g] = true;
      for (int m : parts) m_in_instance[m] = true;
    }
  }
  for (int m = 0; m < n_m; ++m) {
    std::vector<int> parts;
    int sum = 0;
    for (const auto& [g, o] : o_of_m[m]) {
      if (!passes(o, g_size[g])) continue;
      parts.push_back(g);
      sum += o;
    }
    if (parts.size() >= 2 && passes(sum, m_size[m])) {
      m_in_instance[m] = true;
      for (int g : parts) g_under[g] = true;
      under_members[m] = parts;
    }
  }

  HooverCounts counts;
  counts.truth_regions = n_g;
  for (int g = 0; g < n_g; ++g) {
    std::string kind;
    if (g_correct[g]) {
      kind = "correct";
      ++counts.correct;
    } else if (g_over[g]) {
      kind = "over";
      ++counts.over;
    } else if (g_under[g]) {
      kind = "under";
    } else {
      kind = "missed";
      ++counts.missed;
    }
    counts.entries.push_back({g_code[g], g_size[g], kind});
  }
  for (int m = 0; m < n_m; ++m) {
    bool counted = false;
    for (int g : under_members[m]) counted = counted || (!g_correct[g] && !g_over[g]);
    if (counted) ++counts.under;
    if (!m_in_instance[m]) ++counts.noise;
  }
  return counts;
}

}  // namespace hgrasp::sim
