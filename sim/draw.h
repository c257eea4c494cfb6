#pragma once
/// @file Random draws for the twin (DESIGN.md rule 6: every draw derives from the scenario's
/// seed): mt19937_64 with our own, specified algorithms. The standard's distributions are
/// implementation-defined; these give the same numbers with every library.

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

namespace hgrasp::sim {

class Draw {
 public:
  explicit Draw(std::uint64_t seed) : rng_(seed) {}

  /// Uniform in [0, 1): the top 53 bits of one 64-bit draw.
  double Unit() { return static_cast<double>(rng_() >> 11) * 0x1.0p-53; }

  /// Uniform in [lo, hi).
  double Real(double lo, double hi) { return lo + (hi - lo) * Unit(); }

  /// Uniform integer in [lo, hi], unbiased (draws above the last whole multiple of the range
  /// are rejected).
  int Int(int lo, int hi) {
    const std::uint64_t range = static_cast<std::uint64_t>(hi - lo) + 1;
    const std::uint64_t limit = std::numeric_limits<std::uint64_t>::max() -
                                std::numeric_limits<std::uint64_t>::max() % range;
    std::uint64_t x;
    do {
      x = rng_();
    } while (x >= limit);
    return lo + static_cast<int>(x % range);
  }

  /// Normal with mean 0 and standard deviation `sigma` (Box-Muller, two uniform draws each).
  double Gauss(double sigma) {
    const double u1 = 1.0 - Unit();  // (0, 1]
    const double u2 = Unit();
    return sigma * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * 3.14159265358979323846 * u2);
  }

 private:
  std::mt19937_64 rng_;
};

}  // namespace hgrasp::sim
