#include "scan/stripe_detector.h"

#include <algorithm>
#include <cmath>

namespace hgrasp::scan {

void DetectStripeCandidates(const std::uint8_t* row, int width, const StripeDetectorConfig& cfg,
                            std::vector<StripeCandidate>* out, const std::uint8_t* ambient) {
  out->clear();
  // The signal: the row less the ambient image where one is given. A clipped pixel keeps its
  // clip flag: its signal is only a lower bound.
  thread_local std::vector<int> signal;
  thread_local std::vector<char> clipped;
  signal.resize(width);
  clipped.resize(width);
  for (int x = 0; x < width; ++x) {
    signal[x] = row[x] - (ambient != nullptr ? ambient[x] : 0);
    clipped[x] = row[x] >= cfg.saturation;
  }
  const int* s = signal.data();
  const int k = cfg.half_width;
  for (int x = k; x < width - k; ++x) {
    const int v = s[x];
    // Local maximum; on a plateau (a saturated run), only its first pixel.
    if (s[x - 1] >= v || s[x + 1] > v) {
      if (!clipped[x] || clipped[x - 1]) continue;
    }
    // A saturated run is one candidate: its background lies half_width beyond its far end.
    int end = x;
    if (clipped[x]) {
      while (end + 1 < width && clipped[end + 1]) ++end;
    }
    if (end + k >= width) break;
    const int peak = clipped[x] ? *std::max_element(s + x, s + end + 1) : v;
    // Background on both sides, half_width out. Where the two differ by more than the step
    // test allows, an edge of the surface may lie between the stripe and one of them (a dark box
    // against the bright table): the nearest sample on that side that is clear of the stripe's
    // core (2 pixels out) stands in for it when it agrees with the other side.
    int left = s[x - k], right = s[end + k];
    const auto step_ok = [&](int l, int r) {
      return std::abs(l - r) <= cfg.max_background_step * (peak - 0.5 * (l + r));
    };
    if (!step_ok(left, right) && k > 2) {
      if (step_ok(s[x - 2], right)) {
        left = s[x - 2];
      } else if (step_ok(left, s[end + 2])) {
        right = s[end + 2];
      } else {
        continue;
      }
    }
    if (peak - left < cfg.min_contrast || peak - right < cfg.min_contrast) continue;
    if (!step_ok(left, right)) continue;
    const double background = 0.5 * (left + right);
    double centre = x;
    if (clipped[x]) {
      // Clipped: the centroid of what stands above the background around the run.
      double sw = 0, sx = 0;
      for (int i = x - k + 1; i <= end + k - 1; ++i) {
        const double w = s[i] - background;
        if (w > 0) sw += w, sx += w * i;
      }
      centre = sx / sw;
      x = end;
    } else {
      const double a = s[x - 1] - background, c = s[x + 1] - background;
      const double m = v - background;
      if (a > 0.5 && c > 0.5) {
        // Gaussian through three samples: parabola through their logarithms.
        const double la = std::log(a), lm = std::log(m), lc = std::log(c);
        const double denom = la - 2 * lm + lc;
        if (denom < 0) centre = x + 0.5 * (la - lc) / denom;
      } else {
        const double denom = a - 2 * m + c;
        if (denom < 0) centre = x + 0.5 * (a - c) / denom;
      }
    }
    out->push_back({centre, peak - background});
  }
  if (static_cast<int>(out->size()) > cfg.max_candidates) {
    std::partial_sort(
        out->begin(), out->begin() + cfg.max_candidates, out->end(),
        [](const StripeCandidate& p, const StripeCandidate& q) { return p.contrast > q.contrast; });
    out->resize(cfg.max_candidates);
  } else {
    std::sort(out->begin(), out->end(), [](const StripeCandidate& p, const StripeCandidate& q) {
      return p.contrast > q.contrast;
    });
  }
}

}  // namespace hgrasp::scan
