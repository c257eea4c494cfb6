#include "scan/scanner.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>

#include "common/error.h"
#include "scan/laser_self_calibration.h"

namespace hgrasp::scan {
namespace {

constexpr double kFramePeriodS = 0.04;    // PAL, 25 frames/s
constexpr double kSlewCountsPerS = 9000;  // fast move to the start of a sweep

// A laser whose encoder moved at most this much over a frame has settled (counts).
constexpr std::int32_t kLaserSettledCounts = 1;

// Grabs frames until the laser stops: its board says the profile has ended and, with `at_rest`,
// its encoder has since held still over a frame (SweepConfig::start_at_rest). The last frame has
// it stopped. `failed`: the device whose status ended it. The frames only keep time: grabbed
// without images.
device::Status WaitForLaser(device::RobotDevices& dev, device::StereoFrame* frame,
                            const StopRequest* stop, bool at_rest, std::string* failed) {
  device::StripeLaserState s;
  bool ended = false;         // the profile was seen ended at the last read
  std::int32_t ended_at = 0;  // the count then
  for (int i = 0; i < 1000; ++i) {
    if (const auto st = dev.cameras->GrabWithoutImages(frame); st != device::Status::kOk) {
      *failed = "cameras";
      return st;
    }
    if (StopRequested(stop)) {
      *failed = "";
      return device::Status::kInterrupted;
    }
    if (const auto st = dev.laser->Read(&s); st != device::Status::kOk) {
      *failed = "laser";
      return st;
    }
    if (s.moving) {
      ended = false;
      continue;
    }
    if (!at_rest || (ended && std::abs(s.encoder_count - ended_at) <= kLaserSettledCounts)) {
      return device::Status::kOk;
    }
    ended = true;
    ended_at = s.encoder_count;
  }
  *failed = "laser";
  return device::Status::kTimeout;
}

// Bilinear colour (RGB, 0-1) of a BGR image at pixel (u, v); nullopt outside.
std::optional<Eigen::Vector3f> Colour(const cv::Mat& bgr, double u, double v) {
  if (u < 0 || v < 0 || u > bgr.cols - 1 || v > bgr.rows - 1) return std::nullopt;
  const int u0 = std::min(static_cast<int>(u), bgr.cols - 2);
  const int v0 = std::min(static_cast<int>(v), bgr.rows - 2);
  const float a = static_cast<float>(u - u0), b = static_cast<float>(v - v0);
  Eigen::Vector3f rgb = Eigen::Vector3f::Zero();
  const float w[4] = {(1 - a) * (1 - b), a * (1 - b), (1 - a) * b, a * b};
  const cv::Vec3b* px[4] = {&bgr.at<cv::Vec3b>(v0, u0), &bgr.at<cv::Vec3b>(v0, u0 + 1),
                            &bgr.at<cv::Vec3b>(v0 + 1, u0), &bgr.at<cv::Vec3b>(v0 + 1, u0 + 1)};
  for (int i = 0; i < 4; ++i)
    for (int ch = 0; ch < 3; ++ch) rgb[ch] += w[i] * (*px[i])[2 - ch];
  return rgb / 255.0f;
}

}  // namespace

device::Status Sweep(device::RobotDevices& dev, const SweepConfig& sweep,
                     const std::function<void(const device::StereoFrame&)>& on_frame,
                     std::string* failed_device) {
  HGRASP_DEMAND(sweep.positions > 1 && sweep.end_count != sweep.start_count);
  std::string ignored;
  std::string* failed = failed_device != nullptr ? failed_device : &ignored;
  device::StereoFrame frame;
  if (auto st = dev.laser->MoveTo(sweep.start_count, kSlewCountsPerS); st != device::Status::kOk) {
    *failed = "laser";
    return st;
  }
  if (auto st = WaitForLaser(dev, &frame, sweep.stop, sweep.start_at_rest, failed);
      st != device::Status::kOk) {
    return st;
  }
  const double speed =
      std::abs(sweep.end_count - sweep.start_count) / (sweep.positions * kFramePeriodS);
  if (auto st = dev.laser->MoveTo(sweep.end_count, speed); st != device::Status::kOk) {
    *failed = "laser";
    return st;
  }
  device::StripeLaserState s;
  for (int i = 0; i < 4 * sweep.positions; ++i) {
    if (auto st = dev.cameras->Grab(&frame); st != device::Status::kOk) {
      *failed = "cameras";
      return st;
    }
    on_frame(frame);
    if (StopRequested(sweep.stop)) {
      *failed = "";
      return device::Status::kInterrupted;
    }
    if (auto st = dev.laser->Read(&s); st != device::Status::kOk) {
      *failed = "laser";
      return st;
    }
    if (!s.moving) break;
  }
  return device::Status::kOk;
}

device::Status MoveHeadForScan(device::RobotDevices& dev, const device::HeadJoints& q,
                               const StopRequest* stop, std::string* failed, double tolerance_rad,
                               int settle_frames, int timeout_frames) {
  std::string ignored;
  if (failed == nullptr) failed = &ignored;
  device::HeadState head;
  if (const auto st = dev.head->Read(&head); st != device::Status::kOk) {
    *failed = "head";
    return st;
  }
  if (std::abs(head.q.pan - q.pan) <= tolerance_rad &&
      std::abs(head.q.tilt - q.tilt) <= tolerance_rad &&
      std::abs(head.q.verge - q.verge) <= tolerance_rad) {
    return device::Status::kOk;
  }
  if (const auto st = dev.head->MoveTo(q); st != device::Status::kOk) {
    *failed = "head";
    return st;
  }
  device::StereoFrame frame;
  int still_frames = -1;  // frames since the head was seen still
  for (int i = 0; i < timeout_frames; ++i) {
    if (const auto st = dev.cameras->GrabWithoutImages(&frame); st != device::Status::kOk) {
      *failed = "cameras";
      return st;
    }
    if (StopRequested(stop)) {
      *failed = "";
      return device::Status::kInterrupted;
    }
    if (still_frames < 0) {
      if (const auto st = dev.head->Read(&head); st != device::Status::kOk) {
        *failed = "head";
        return st;
      }
      if (!head.moving) still_frames = 0;
    } else if (++still_frames >= settle_frames) {
      return device::Status::kOk;
    }
  }
  *failed = "head";
  return device::Status::kTimeout;
}

void CheckFrameSize(const robot::StereoIntrinsics& cameras, const device::StereoFrame& frame) {
  const auto check = [&](const PinholeCamera& c, const cv::Mat& image, const char* side) {
    if (image.cols == c.width && image.rows == c.height) return;
    throw InputError(cameras.path, std::string(side) + ".width, " + side + ".height",
                     std::to_string(c.width) + " x " + std::to_string(c.height),
                     "the size of the " + std::string(side) + " camera's frames, " +
                         std::to_string(image.cols) + " x " + std::to_string(image.rows) +
                         " pixels (a calibration of another camera or resolution?)");
  };
  check(cameras.left, frame.left, "left");
  check(cameras.right, frame.right, "right");
}

Scanner::Scanner(robot::HeadKinematics head, robot::StereoIntrinsics cameras,
                 robot::LaserCalibration laser, StripeFrameConfig config)
    : head_(std::move(head)),
      cameras_(std::move(cameras)),
      laser_(std::move(laser)),
      config_(config) {}

double Scanner::VergeKey(double verge) { return std::round(verge / kVergeStepRad) * kVergeStepRad; }

const Rectification& Scanner::RectificationAt(double verge) {
  verge = VergeKey(verge);
  auto& r = rectifications_[verge];
  if (!r) {
    const Pose3 X_CLCR = head_.X_HC(0, verge).inverse() * head_.X_HC(1, verge);
    r = std::make_unique<Rectification>(MakeRectification(cameras_.left, cameras_.right, X_CLCR));
  }
  return *r;
}

LaserCoefficients Scanner::CoefficientsAt(std::int32_t count, double verge) {
  verge = VergeKey(verge);
  const Rectification& rect = RectificationAt(verge);
  const Pose3 X_HM = head_.X_HC(0, verge) * rect.X_CLM;
  return CoefficientsFromPlane(laser_.PlaneH(count).TransformedBy(X_HM.inverse()), rect.b);
}

void Scanner::ProcessFrame(const device::StereoFrame& frame, const device::StereoFrame& ambient,
                           RangeImage* range, int col, StripeFrameResult* result) {
  const cv::Mat& ambient_left = ambient.left;
  const double verge = VergeKey(frame.head.verge);
  const Rectification& rect = RectificationAt(verge);
  auto& processor = processors_[verge];
  if (!processor) processor = std::make_unique<StripeFrameProcessor>(&rect, config_);
  processor->SetAmbient(ambient.left, ambient.right);
  processor->Process(frame.left, frame.right, CoefficientsAt(frame.laser_encoder_count, verge),
                     result);
  const Pose3 X_WCL = head_.X_WC(0, frame.head);
  for (const StripePoint& p : result->points) {
    RangeCell& cell = range->at(p.row, col);
    cell.valid = true;
    cell.p_C = rect.X_CLM * p.p_M;
    cell.p_W = X_WCL * cell.p_C;
    const auto uv = cameras_.left.Project(cell.p_C);
    if (uv) {
      if (const auto rgb = Colour(ambient_left, uv->x(), uv->y())) cell.rgb = *rgb;
    }
  }
}

ScanResult Scanner::Scan(device::RobotDevices& dev, const SweepConfig& sweep) {
  ScanResult out;
  // A device that fails ends the scan; the laser is told to go off whatever it said before.
  // What it answers is not kept: the failure is reported as it is, and the composition root's
  // safe stop turns the laser off again and reports that.
  const auto failed = [&](const std::string& device, device::Status st) {
    out.status = st;
    out.failed_device = device;
    static_cast<void>(dev.laser->SetLaser(false));
    return out;
  };
  device::StereoFrame ambient;
  if (const auto st = dev.laser->SetLaser(false); st != device::Status::kOk) {
    return failed("laser", st);
  }
  if (const auto st = dev.cameras->Grab(&ambient); st != device::Status::kOk) {
    return failed("cameras", st);
  }
  CheckFrameSize(cameras_, ambient);
  out.ambient_left = ambient.left.clone();
  std::vector<device::StereoFrame> frames;
  if (const auto st = dev.laser->SetLaser(true); st != device::Status::kOk) {
    return failed("laser", st);
  }
  std::string failed_device;
  const device::Status swept = Sweep(
      dev, sweep, [&](const device::StereoFrame& f) { frames.push_back(f); }, &failed_device);
  if (swept != device::Status::kOk) return failed(failed_device, swept);
  // Stripe positions the host missed are swept again, at the sweep's speed and in its
  // direction, and their frames put in their place: the columns stay in count order.
  const std::int32_t dir = sweep.end_count < sweep.start_count ? -1 : 1;
  const double step =
      std::abs(sweep.end_count - sweep.start_count) / static_cast<double>(sweep.positions);
  const auto in_order = [dir](const device::StereoFrame& a, const device::StereoFrame& b) {
    return dir * a.laser_encoder_count < dir * b.laser_encoder_count;
  };
  const auto gaps = [&] {
    std::vector<std::pair<std::int32_t, std::int32_t>> g;
    for (std::size_t i = 1; i < frames.size(); ++i) {
      const std::int32_t a = frames[i - 1].laser_encoder_count;
      const std::int32_t b = frames[i].laser_encoder_count;
      if (dir * (b - a) > kGapSteps * step) g.emplace_back(a, b);
    }
    return g;
  };
  std::stable_sort(frames.begin(), frames.end(), in_order);
  for (int pass = 0; pass < kMaxRescanPasses; ++pass) {
    const auto missing = gaps();
    if (missing.empty()) break;
    for (const auto& [a, b] : missing) {
      SweepConfig again;
      again.start_count = a;
      again.end_count = b;
      again.positions = std::max(2, static_cast<int>(std::lround(std::abs(b - a) / step)));
      again.stop = sweep.stop;
      again.start_at_rest = true;  // the gap's first frames are the ones it lacks
      int added = 0;
      const device::Status st = Sweep(
          dev, again,
          [&](const device::StereoFrame& f) {
            // Only the frames inside the gap: the slew's end and the stop repeat its edges.
            if (dir * (f.laser_encoder_count - a) > 0 && dir * (b - f.laser_encoder_count) > 0) {
              frames.push_back(f);
              ++added;
            }
          },
          &failed_device);
      if (st != device::Status::kOk) return failed(failed_device, st);
      ++out.gaps_rescanned;
      out.frames_rescanned += added;
    }
    std::stable_sort(frames.begin(), frames.end(), in_order);
  }
  out.gaps_left = static_cast<int>(gaps().size());
  if (const auto st = dev.laser->SetLaser(false); st != device::Status::kOk) {
    return failed("laser", st);
  }
  out.range = RangeImage(cameras_.left.height, static_cast<int>(frames.size()));
  StripeFrameResult result;
  for (size_t i = 0; i < frames.size(); ++i) {
    ProcessFrame(frames[i], ambient, &out.range, static_cast<int>(i), &result);
    out.range.encoder_counts.push_back(frames[i].laser_encoder_count);
    out.points += static_cast<int>(result.points.size());
    out.rejected += result.rejected;
  }
  return out;
}

std::string LaserCalibrationReport::Figures() const {
  char text[320];
  std::snprintf(
      text, sizeof text,
      "%d of %d stripe positions determined a plane, %d consistent, spanning %.0f%% of "
      "the sweep; residue RMS %.3f px, points %.3f mm RMS and planes %.3f deg (median) from "
      "the model",
      counts_fitted, frames, counts_used, 100.0 * span_fraction, rms_residue_px, rms_point_mm,
      median_plane_deg);
  return text;
}

std::optional<robot::LaserCalibration> CalibrateLaser(
    device::RobotDevices& dev, const robot::HeadKinematics& head,
    const robot::StereoIntrinsics& cameras, const SweepConfig& sweep, StripeFrameConfig config,
    LaserCalibrationReport* report_out, const LaserCalibrationQuality& quality) {
  LaserCalibrationReport ignored;
  LaserCalibrationReport& report = report_out != nullptr ? *report_out : ignored;
  report = {};
  const auto device_failed = [&](const std::string& device, device::Status st) {
    report.failed_device = device;
    report.status = st;
    report.failure = device.empty() ? std::string(device::ToString(st))
                                    : device + ": " + std::string(device::ToString(st));
    return std::nullopt;
  };
  const auto below = [&](const std::string& why) {
    report.failure = why + " (" + report.Figures() + ")";
    return std::nullopt;
  };
  device::HeadState hs;
  if (const auto st = dev.head->Read(&hs); st != device::Status::kOk) {
    return device_failed("head", st);
  }
  const double verge = hs.q.verge;
  const Pose3 X_CLCR = head.X_HC(0, verge).inverse() * head.X_HC(1, verge);
  const Rectification rect = MakeRectification(cameras.left, cameras.right, X_CLCR);
  const Pose3 X_HM = head.X_HC(0, verge) * rect.X_CLM;
  StripeFrameProcessor processor(&rect, config);
  std::vector<std::pair<std::int32_t, Plane>> planes_H;
  std::vector<std::pair<std::int32_t, std::vector<Eigen::Vector3d>>> observations;
  std::vector<CountedPoint> points_H;
  int frames = 0;
  bool size_checked = false;
  if (const auto st = dev.laser->SetLaser(true); st != device::Status::kOk) {
    return device_failed("laser", st);
  }
  std::string failed;
  const device::Status swept = Sweep(
      dev, sweep,
      [&](const device::StereoFrame& f) {
        if (!size_checked) CheckFrameSize(cameras, f), size_checked = true;
        ++frames;
        processor.Rectify(f.left, f.right);
        std::vector<std::vector<Eigen::Vector3d>> rows;
        processor.CandidatePairs(3, &rows);
        std::vector<Eigen::Vector3d> pairs;
        const auto c = FitCoefficientsRobust(rows, rect.f, 0.5, &pairs);
        if (!c) return;
        planes_H.emplace_back(f.laser_encoder_count,
                              PlaneFromCoefficients(*c, rect.b).TransformedBy(X_HM));
        // The pairs this count's fit keeps, triangulated without the plane, for the refinement.
        std::vector<double> r(pairs.size());
        double sum2 = 0;
        for (size_t i = 0; i < pairs.size(); ++i) {
          r[i] = c->Residue(pairs[i].x(), pairs[i].y(), pairs[i].z(), rect.f);
          sum2 += r[i] * r[i];
        }
        const double rms = std::sqrt(sum2 / pairs.size());
        for (size_t i = 0; i < pairs.size(); i += 2) {  // every other row is plenty
          if (std::abs(r[i]) > 2.5 * rms) continue;
          points_H.push_back({f.laser_encoder_count,
                              X_HM * rect.Triangulate(pairs[i].x(), pairs[i].y(), pairs[i].z())});
        }
        observations.emplace_back(f.laser_encoder_count, std::move(pairs));
      },
      &failed);
  const device::Status off = dev.laser->SetLaser(false);
  if (swept != device::Status::kOk) return device_failed(failed, swept);
  if (off != device::Status::kOk) return device_failed("laser", off);
  report.frames = frames;
  report.counts_fitted = static_cast<int>(planes_H.size());
  if (planes_H.size() < 3) {
    return below("only " + std::to_string(planes_H.size()) + " of " + std::to_string(frames) +
                 " stripe positions fell on a non-planar target");
  }
  // Robustly: counts whose plane disagrees with a first model (a stripe off the target, a wrong
  // pair of candidates) are dropped, then the model is refined on the points of the rest, twice,
  // trimming points beyond 3 RMS.
  // A plane is consistent when its normal lies as close to its neighbours' in the sweep as
  // neighbours typically do (the sweep turns it smoothly).
  auto angle = [&](size_t i, size_t j) {
    return std::acos(std::min(1.0, std::abs(planes_H[i].second.n.dot(planes_H[j].second.n))));
  };
  std::vector<double> spread(planes_H.size());
  for (size_t i = 0; i < planes_H.size(); ++i) {
    std::vector<double> a;
    for (int k = -2; k <= 2; ++k) {
      const long j = static_cast<long>(i) + k;
      if (k != 0 && j >= 0 && j < static_cast<long>(planes_H.size())) a.push_back(angle(i, j));
    }
    std::nth_element(a.begin(), a.begin() + a.size() / 2, a.end());
    spread[i] = a[a.size() / 2];
  }
  std::vector<double> sorted = spread;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double typical = sorted[sorted.size() / 2];
  std::vector<std::pair<std::int32_t, Plane>> consistent;
  std::set<std::int32_t> kept_counts;
  for (size_t i = 0; i < planes_H.size(); ++i) {
    if (spread[i] < 3 * typical + DegToRad(0.2)) {
      consistent.push_back(planes_H[i]);
      kept_counts.insert(planes_H[i].first);
    }
  }
  report.counts_used = static_cast<int>(consistent.size());
  if (consistent.size() < 3) {
    return below(
        "the stripe planes do not turn smoothly with the encoder; is the head still and the "
        "target non-planar?");
  }
  robot::LaserCalibration cal = FitRotatingPlane(consistent);
  std::erase_if(points_H, [&](const CountedPoint& p) { return !kept_counts.count(p.count); });
  double rms_point_m = 0;
  for (int pass = 0; pass < 3; ++pass) {
    double rms = 0;
    cal = RefineOnPoints(cal, points_H, &rms);
    rms_point_m = rms;
    std::vector<CountedPoint> kept;
    for (const CountedPoint& p : points_H) {
      if (std::abs(cal.PlaneH(p.count).SignedDistance(p.p_H)) < 3 * rms) kept.push_back(p);
    }
    points_H.swap(kept);
  }
  cal.counts_used = static_cast<int>(consistent.size());
  // Residues of the model over every pair used.
  double sum2 = 0;
  long n = 0;
  for (const auto& [count, pairs] : observations) {
    const LaserCoefficients c =
        CoefficientsFromPlane(cal.PlaneH(count).TransformedBy(X_HM.inverse()), rect.b);
    for (const auto& p : pairs) {
      const double r = c.Residue(p.x(), p.y(), p.z(), rect.f);
      if (std::abs(r) < 1.0) sum2 += r * r, ++n;  // the strays eq. 6 also dropped
    }
  }
  cal.rms_residual_px = n > 0 ? std::sqrt(sum2 / n) : 0.0;

  // The calibration's own quality: coverage of the sweep, and how well the model explains the
  // per-count planes and the points.
  const auto [lo, hi] =
      std::minmax_element(consistent.begin(), consistent.end(),
                          [](const auto& a, const auto& b) { return a.first < b.first; });
  report.span_fraction =
      static_cast<double>(hi->first - lo->first) / std::abs(sweep.end_count - sweep.start_count);
  report.rms_residue_px = cal.rms_residual_px;
  report.rms_point_mm = 1e3 * rms_point_m;
  std::vector<double> plane_deg;
  for (const auto& [count, plane] : consistent) {
    const double c = std::abs(plane.n.dot(cal.PlaneH(count).n));
    plane_deg.push_back(RadToDeg(std::acos(std::min(1.0, c))));
  }
  std::nth_element(plane_deg.begin(), plane_deg.begin() + plane_deg.size() / 2, plane_deg.end());
  report.median_plane_deg = plane_deg[plane_deg.size() / 2];
  const double fitted = static_cast<double>(report.counts_fitted) / std::max(1, frames);
  if (fitted < quality.min_fitted_fraction || report.span_fraction < quality.min_span_fraction) {
    return below(
        "too few stripe positions fell on a non-planar target: the sweep needs one "
        "across its whole width (e.g. scenarios/calibration_target.yaml)");
  }
  if (report.rms_residue_px > quality.max_rms_residue_px ||
      report.rms_point_mm > quality.max_rms_point_mm ||
      report.median_plane_deg > quality.max_median_plane_deg) {
    return below("the rotating-plane model does not fit the stripes");
  }
  return cal;
}

}  // namespace hgrasp::scan
