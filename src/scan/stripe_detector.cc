#include "scan/stripe_detector.h"

#include <algorithm>
#include <cmath>

namespace hgrasp::scan {

void DetectStripeCandidates(const std::uint8_t* row, int width, const StripeDetectorConfig& cfg,
                            std::vector<StripeCandidate>* out) {
  out->clear();
  const int k = cfg.half_width;
  for (int x = k; x < width - k; ++x) {
    const int v = row[x];
    // Local maximum; on a plateau (a saturated run), only its first pixel.
    if (row[x - 1] >= v || row[x + 1] > v) continue;
    // A saturated run is one candidate: its background lies half_width beyond its far end.
    int end = x;
    if (v >= cfg.saturation) {
      while (end + 1 < width && row[end + 1] >= cfg.saturation) ++end;
    }
    if (end + k >= width) break;
    const int left = row[x - k], right = row[end + k];
    if (v - left < cfg.min_contrast || v - right < cfg.min_contrast) continue;
    const double background = 0.5 * (left + right);
    if (std::abs(left - right) > cfg.max_background_step * (v - background)) continue;
    double centre = x;
    if (v >= cfg.saturation) {
      // Clipped: the centroid of what stands above the background around the run.
      double sw = 0, sx = 0;
      for (int i = x - k + 1; i <= end + k - 1; ++i) {
        const double w = row[i] - background;
        if (w > 0) sw += w, sx += w * i;
      }
      centre = sx / sw;
      x = end;
    } else {
      const double a = row[x - 1] - background, c = row[x + 1] - background;
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
    out->push_back({centre, v - background});
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
