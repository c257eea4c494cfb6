// One stereo frame of the sweep against geometry worked out by hand: pair matching by the eq. 5
// residue, reconstruction on the light plane, the whole frame on synthetic images of a known
// plane meeting a known surface, and the eq. 6 fit of the coefficients from such pairs.

#include "scan/stripe_frame.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <opencv2/core.hpp>
#include <random>

#include "scan/laser_self_calibration.h"

namespace hgrasp::scan {
namespace {

Plane MakePlane(const Eigen::Vector3d& normal, const Eigen::Vector3d& through) {
  Plane p;
  p.n = normal.normalized();
  p.d = -p.n.dot(through);
  return p;
}

// The light plane of most tests: X = 0.02 + 0.3 (Z - 0.5) in M, a little tilted about Z too.
Plane LaserPlane() { return MakePlane({1.0, 0.05, -0.3}, {0.02, 0.0, 0.5}); }

PinholeCamera IdealCamera() { return PinholeCamera::FromFovy(320, 240, DegToRad(55.0)); }

// Parallel identical cameras 0.14 m apart: the rectification is the identity.
Rectification ParallelRig() {
  Pose3 X_CLCR = Pose3::Identity();
  X_CLCR.translation() = Eigen::Vector3d(0.14, 0.0, 0.0);
  return MakeRectification(IdealCamera(), IdealCamera(), X_CLCR);
}

// (xL, xR, y) of p_M, relative to the principal point.
Eigen::Vector3d PairOf(const Eigen::Vector3d& p_M, const Rectification& r) {
  return {(p_M.x() + r.b) * r.f / p_M.z(), (p_M.x() - r.b) * r.f / p_M.z(),
          p_M.y() * r.f / p_M.z()};
}

// The point of `plane` seen on rectified row coordinate y at depth given by `depth(Y)` (Z as a
// function of Y): solves Y = y Z / f by fixed-point iteration, then X from the plane.
Eigen::Vector3d PointOnRow(const Plane& plane, double y, double f,
                           const std::function<double(double)>& depth) {
  double Y = 0, Z = depth(0);
  for (int i = 0; i < 100; ++i) {
    Y = y * Z / f;
    Z = depth(Y);
  }
  const double X = -(plane.d + plane.n.y() * Y + plane.n.z() * Z) / plane.n.x();
  return {X, Y, Z};
}

// ---------------------------------------------------------------------------------------------
// MatchRow

TEST(MatchRowTest, PicksThePairOnThePlaneAmongDecoys) {
  const Rectification r = ParallelRig();
  const Plane plane = LaserPlane();
  const LaserCoefficients c = CoefficientsFromPlane(plane, r.b);
  const Eigen::Vector3d p_M = PointOnRow(plane, 20.0, r.f, [](double) { return 0.6; });
  const Eigen::Vector3d pair = PairOf(p_M, r);
  ASSERT_NEAR(c.Residue(pair.x(), pair.y(), 20.0, r.f), 0.0, 1e-9);
  // Candidates in absolute columns; the decoys are listed first and are brighter.
  const std::vector<StripeCandidate> left = {{pair.x() + r.cx + 12.0, 90}, {pair.x() + r.cx, 50}};
  const std::vector<StripeCandidate> right = {{pair.y() + r.cx - 9.0, 90}, {pair.y() + r.cx, 50}};
  const auto m = MatchRow(left, right, r.cx, 20.0, r.f, c, 0.3);
  ASSERT_TRUE(m.has_value());
  EXPECT_EQ(m->left, 1);
  EXPECT_EQ(m->right, 1);
  EXPECT_NEAR(m->residue, 0.0, 1e-9);

  // Off the plane by 0.1 px in xL: still chosen, and the residue reported is that pair's.
  std::vector<StripeCandidate> shifted = left;
  shifted[1].x += 0.1;
  const auto m2 = MatchRow(shifted, right, r.cx, 20.0, r.f, c, 0.3);
  ASSERT_TRUE(m2.has_value());
  EXPECT_EQ(m2->left, 1);
  EXPECT_EQ(m2->right, 1);
  EXPECT_NEAR(m2->residue, c.Residue(pair.x() + 0.1, pair.y(), 20.0, r.f), 1e-12);
  EXPECT_NEAR(m2->residue, 0.1, 1e-9);  // d residue / d xL = 1

  // Only the decoys: no pair within 0.3 px.
  EXPECT_FALSE(MatchRow({left[0]}, {right[0]}, r.cx, 20.0, r.f, c, 0.3).has_value());
  EXPECT_FALSE(MatchRow({left[0]}, right, r.cx, 20.0, r.f, c, 0.3).has_value());
  EXPECT_FALSE(MatchRow(left, {right[0]}, r.cx, 20.0, r.f, c, 0.3).has_value());
  // Nothing in one image.
  EXPECT_FALSE(MatchRow({}, right, r.cx, 20.0, r.f, c, 0.3).has_value());
}

TEST(MatchRowTest, BestOfSeveralWithinTolerance) {
  // Frontal plane Z = 0.5 at f = 200, b = 0.07: alpha = -1, beta = 0, gamma = -0.28, so a pair
  // is valid when xL - xR = 56. Columns below are absolute with cx = 100.
  const LaserCoefficients c{-1.0, 0.0, -0.28};
  const std::vector<StripeCandidate> left = {{160.0, 1}, {160.2, 1}};
  const std::vector<StripeCandidate> right = {{104.1, 1}, {103.95, 1}};
  // Residues: (60 - 4.1 - 56) = -0.1, (60 - 3.95 - 56) = 0.05, (60.2 - 4.1 - 56) = 0.1,
  // (60.2 - 3.95 - 56) = 0.25: the second right candidate with the first left one wins.
  const auto m = MatchRow(left, right, 100.0, 0.0, 200.0, c, 0.3);
  ASSERT_TRUE(m.has_value());
  EXPECT_EQ(m->left, 0);
  EXPECT_EQ(m->right, 1);
  EXPECT_NEAR(m->residue, 0.05, 1e-12);
  EXPECT_FALSE(MatchRow({{160.0, 1}}, {{103.5, 1}}, 100.0, 0.0, 200.0, c, 0.3).has_value());
  // "Below" the tolerance: with gamma = -0.25 (binary-exact numbers) the pair 60.25 | 10 has
  // residue exactly 0.25, valid under 0.26 and not under 0.25.
  const LaserCoefficients c2{-1.0, 0.0, -0.25};
  EXPECT_TRUE(MatchRow({{160.25, 1}}, {{110.0, 1}}, 100.0, 0.0, 200.0, c2, 0.26).has_value());
  EXPECT_FALSE(MatchRow({{160.25, 1}}, {{110.0, 1}}, 100.0, 0.0, 200.0, c2, 0.25).has_value());
}

TEST(MatchRowTest, NeverPairsWithoutPositiveDisparity) {
  // A "plane" whose pairs have xL - xR = -20 (it lies behind the cameras): its exact pairs have
  // xL < xR and must not be taken.
  const LaserCoefficients behind{-1.0, 0.0, 0.1};  // xL - xR + 0.1 f = 0, f = 200
  const auto m = MatchRow({{80.0, 1}}, {{100.0, 1}}, 100.0, 0.0, 200.0, behind, 0.3);
  EXPECT_FALSE(m.has_value());
  // gamma = 0: the exact pairs have xL = xR (infinitely far): not taken either.
  const LaserCoefficients infinite{-1.0, 0.0, 0.0};
  EXPECT_FALSE(MatchRow({{130.0, 1}}, {{130.0, 1}}, 100.0, 0.0, 200.0, infinite, 0.3).has_value());
  // ... while with a valid pair beside them that one is chosen.
  const auto m2 =
      MatchRow({{130.0, 1}}, {{130.0, 1}, {129.9, 1}}, 100.0, 0.0, 200.0, infinite, 0.3);
  ASSERT_TRUE(m2.has_value());
  EXPECT_EQ(m2->right, 1);
}

// ---------------------------------------------------------------------------------------------
// Reconstruction on the plane and the single-camera ray

TEST(ReconstructOnPlaneTest, ExactPairsReconstructExactly) {
  const Rectification r = ParallelRig();
  const Plane plane = LaserPlane();
  const LaserCoefficients c = CoefficientsFromPlane(plane, r.b);
  for (double Z : {0.3, 0.45, 0.6, 0.9, 1.4}) {
    for (double y : {-100.0, -3.0, 0.0, 57.0, 110.0}) {
      const Eigen::Vector3d p = PointOnRow(plane, y, r.f, [Z](double) { return Z; });
      const Eigen::Vector3d pair = PairOf(p, r);
      EXPECT_NEAR((ReconstructOnPlane(pair.x(), pair.y(), y, c, r) - p).norm(), 0.0, 1e-9);
      EXPECT_NEAR((r.Triangulate(pair.x(), pair.y(), y) - p).norm(), 0.0, 1e-9);
    }
  }
}

TEST(ReconstructOnPlaneTest, PerturbedPairIsMovedOntoThePlane) {
  const Rectification r = ParallelRig();
  const Plane plane = LaserPlane();
  const LaserCoefficients c = CoefficientsFromPlane(plane, r.b);
  const double a = c.alpha;
  for (double e : {0.5, -0.3, 2.0}) {
    for (double Z : {0.4, 0.6, 0.8}) {
      const double y = 35.0;
      const Eigen::Vector3d truth = PointOnRow(plane, y, r.f, [Z](double) { return Z; });
      const Eigen::Vector3d pair = PairOf(truth, r);
      const Eigen::Vector3d p = ReconstructOnPlane(pair.x() + e, pair.y(), y, c, r);
      EXPECT_NEAR(plane.SignedDistance(p), 0.0, 1e-9) << "e " << e << " Z " << Z;
      // By hand: the residue is e, the nearest pair on the line xL + alpha xR + k = 0 is the
      // measured one less e / (1 + alpha^2) (1, alpha).
      const Eigen::Vector3d hand =
          r.Triangulate(pair.x() + e - e / (1 + a * a), pair.y() - a * e / (1 + a * a), y);
      EXPECT_NEAR((p - hand).norm(), 0.0, 1e-12);
      // The error is of the order of a pixel's footprint at that depth: e Z / f (a little more
      // with this plane and depth, through the change of disparity).
      EXPECT_LT((p - truth).norm(), 2.0 * std::abs(e) * Z / r.f) << "e " << e << " Z " << Z;
      // And smaller than plain triangulation of the perturbed pair.
      EXPECT_LT((p - truth).norm(), (r.Triangulate(pair.x() + e, pair.y(), y) - truth).norm());
    }
  }
}

TEST(IntersectLeftRayTest, HitsThePlaneOnTheLeftRay) {
  const Rectification r = ParallelRig();
  const Plane plane = LaserPlane();
  for (double xL : {-80.0, 0.0, 46.1, 120.0}) {
    for (double y : {-100.0, 0.0, 33.3}) {
      const Eigen::Vector3d p = IntersectLeftRay(xL, y, plane, r);
      EXPECT_NEAR(plane.SignedDistance(p), 0.0, 1e-12);
      // On the left camera's ray through (xL, y).
      EXPECT_NEAR((p.x() + r.b) * r.f / p.z(), xL, 1e-9);
      EXPECT_NEAR(p.y() * r.f / p.z(), y, 1e-9);
    }
  }
  // With the exact pair, the same point as stereo triangulation.
  const Eigen::Vector3d truth = PointOnRow(plane, -20.0, r.f, [](double) { return 0.55; });
  const Eigen::Vector3d pair = PairOf(truth, r);
  EXPECT_NEAR((IntersectLeftRay(pair.x(), pair.z(), plane, r) - truth).norm(), 0.0, 1e-9);
}

// ---------------------------------------------------------------------------------------------
// A whole frame on synthetic images

double Phi(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

// A Gaussian ridge (sigma 0.8 px, amplitude a) integrated over pixel column u.
double PixelGaussian(int u, double c, double a) {
  constexpr double s = 0.8;
  return a * (Phi((u + 0.5 - c) / s) - Phi((u - 0.5 - c) / s)) * std::sqrt(2.0 * kPi) * s;
}

// Grey BGR images (80) with one ridge per row in the red channel at column(row) (absolute).
void DrawStripe(cv::Mat* image, const std::function<double(int)>& column, double amplitude) {
  for (int v = 0; v < image->rows; ++v) {
    const double c = column(v);
    for (int u = 0; u < image->cols; ++u) {
      cv::Vec3b& px = image->at<cv::Vec3b>(v, u);
      px[2] = cv::saturate_cast<std::uint8_t>(px[2] + PixelGaussian(u, c, amplitude));
    }
  }
}

cv::Mat Grey() { return cv::Mat(240, 320, CV_8UC3, cv::Scalar(80, 80, 80)); }

struct Scene {
  Rectification rect = ParallelRig();
  Plane plane = LaserPlane();
  std::vector<Eigen::Vector3d> truth;  // per row
  cv::Mat left = Grey(), right = Grey();
};

// The laser plane meeting the surface Z = z0 + slope Y: the stripe drawn where each row sees it.
Scene MakeScene(double z0, double slope) {
  Scene s;
  for (int v = 0; v < s.rect.height; ++v) {
    const double y = v - s.rect.cy;
    s.truth.push_back(PointOnRow(s.plane, y, s.rect.f, [=](double Y) { return z0 + slope * Y; }));
  }
  DrawStripe(
      &s.left, [&](int v) { return PairOf(s.truth[v], s.rect).x() + s.rect.cx; }, 100);
  DrawStripe(
      &s.right, [&](int v) { return PairOf(s.truth[v], s.rect).y() + s.rect.cx; }, 100);
  return s;
}

class StripeFrameTest : public ::testing::TestWithParam<double> {};

TEST_P(StripeFrameTest, EveryRowGivesItsPoint) {
  Scene s = MakeScene(0.6, GetParam());
  // The stripe lies inside both images.
  const Eigen::Vector3d pair0 = PairOf(s.truth[0], s.rect);
  ASSERT_GT(pair0.y() + s.rect.cx, 10);
  ASSERT_LT(pair0.x() + s.rect.cx, 310);
  StripeFrameProcessor proc(&s.rect, {});
  StripeFrameResult out;
  const LaserCoefficients c = CoefficientsFromPlane(s.plane, s.rect.b);
  proc.Process(s.left, s.right, c, &out);
  EXPECT_EQ(out.rejected, 0);
  ASSERT_EQ(static_cast<int>(out.points.size()), s.rect.height);
  double worst = 0;
  for (int i = 0; i < static_cast<int>(out.points.size()); ++i) {
    const StripePoint& p = out.points[i];
    EXPECT_EQ(p.row, i);
    const Eigen::Vector3d pair = PairOf(s.truth[p.row], s.rect);
    EXPECT_NEAR(p.xL, pair.x(), 0.05) << "row " << p.row;
    EXPECT_NEAR(p.xR, pair.y(), 0.05) << "row " << p.row;
    EXPECT_NEAR(p.residue, c.Residue(p.xL, p.xR, p.row - s.rect.cy, s.rect.f), 1e-12);
    EXPECT_LT(std::abs(p.residue), 0.3);
    EXPECT_NEAR(s.plane.SignedDistance(p.p_M), 0.0, 1e-9);  // reconstructed on the plane
    worst = std::max(worst, (p.p_M - s.truth[p.row]).norm());
  }
  EXPECT_LT(worst, 0.001);
  std::printf("slope %.2f: worst point error %.4f mm\n", GetParam(), 1e3 * worst);
  // Within the band where the plane can put the stripe, the rectified red channel is the red
  // channel (identity rectification); outside it nothing is rectified (0).
  cv::Mat red;
  cv::extractChannel(s.left, red, 2);
  const auto [first, last] = proc.StripeBand(0, c);
  ASSERT_LE(first, last);
  const cv::Rect band(first, 0, last - first + 1, s.rect.height);
  EXPECT_EQ(cv::norm(proc.rectified_red(0)(band), red(band), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::countNonZero(proc.rectified_red(0)), cv::countNonZero(proc.rectified_red(0)(band)));
}

TEST_P(StripeFrameTest, BrighterDecoyInOneImageIsNotChosen) {
  Scene s = MakeScene(0.6, GetParam());
  // A brighter stripe in the right image 25 px left of the true one (still positive disparity
  // with the left stripe), and one in the left image 12 px right of the true one (within the
  // band of columns where the plane can put a stripe, so single-camera mode takes it).
  DrawStripe(
      &s.right, [&](int v) { return PairOf(s.truth[v], s.rect).y() + s.rect.cx - 25; }, 150);
  DrawStripe(
      &s.left, [&](int v) { return PairOf(s.truth[v], s.rect).x() + s.rect.cx + 12; }, 150);
  StripeFrameProcessor proc(&s.rect, {});
  StripeFrameResult out;
  const LaserCoefficients c = CoefficientsFromPlane(s.plane, s.rect.b);
  proc.Process(s.left, s.right, c, &out);
  EXPECT_EQ(out.rejected, 0);
  ASSERT_EQ(static_cast<int>(out.points.size()), s.rect.height);
  for (const StripePoint& p : out.points) {
    const Eigen::Vector3d pair = PairOf(s.truth[p.row], s.rect);
    EXPECT_NEAR(p.xL, pair.x(), 0.05) << "row " << p.row;
    EXPECT_NEAR(p.xR, pair.y(), 0.05) << "row " << p.row;
    EXPECT_LT((p.p_M - s.truth[p.row]).norm(), 0.001) << "row " << p.row;
  }

  // The candidate pairs offered to the robust self-calibration: both stripes in each image,
  // every pair with positive disparity, the true one among them.
  std::vector<std::vector<Eigen::Vector3d>> rows;
  proc.Rectify(s.left, s.right);  // as the self-calibration does: whole images
  proc.CandidatePairs(2, &rows);
  ASSERT_EQ(static_cast<int>(rows.size()), s.rect.height);
  for (int v = 0; v < s.rect.height; v += 17) {
    EXPECT_EQ(rows[v].size(), 4u) << "row " << v;
    bool has_true = false;
    for (const Eigen::Vector3d& q : rows[v]) {
      EXPECT_GT(q.x(), q.y());
      EXPECT_DOUBLE_EQ(q.z(), v - s.rect.cy);
      const Eigen::Vector3d pair = PairOf(s.truth[v], s.rect);
      has_true |= std::abs(q.x() - pair.x()) < 0.05 && std::abs(q.y() - pair.y()) < 0.05;
    }
    EXPECT_TRUE(has_true) << "row " << v;
  }

  // Single-camera mode takes the strongest left candidate, the decoy: what stereo buys. Every
  // row gives a wrong point, or one so wrong that the range check refuses it.
  StripeFrameConfig single;
  single.stereo = false;
  StripeFrameProcessor mono(&s.rect, single);
  mono.Process(s.left, s.right, c, &out);
  ASSERT_EQ(static_cast<int>(out.points.size()) + out.rejected, s.rect.height);
  for (const StripePoint& p : out.points) {
    EXPECT_NEAR(p.xL, PairOf(s.truth[p.row], s.rect).x() + 12, 0.05) << "row " << p.row;
    EXPECT_GT((p.p_M - s.truth[p.row]).norm(), 0.01) << "row " << p.row;
  }
}

TEST_P(StripeFrameTest, SingleCameraOnACleanStripe) {
  Scene s = MakeScene(0.6, GetParam());
  StripeFrameConfig single;
  single.stereo = false;
  StripeFrameProcessor proc(&s.rect, single);
  StripeFrameResult out;
  proc.Process(s.left, s.right, CoefficientsFromPlane(s.plane, s.rect.b), &out);
  ASSERT_EQ(static_cast<int>(out.points.size()), s.rect.height);
  for (const StripePoint& p : out.points) {
    EXPECT_LT((p.p_M - s.truth[p.row]).norm(), 0.001) << "row " << p.row;
  }
}

TEST_P(StripeFrameTest, WrongPlaneRejectsTheRows) {
  Scene s = MakeScene(0.6, GetParam());
  // The plane turned 2 deg about the vertical through its point (0.02, 0, 0.5): 0.1 m in front
  // of that point, where the surface is, it has moved about 3.5 mm (less where the sloping
  // surface comes nearer).
  const Eigen::Vector3d n = Eigen::AngleAxisd(DegToRad(2.0), Eigen::Vector3d::UnitY()) * s.plane.n;
  const Plane wrong = MakePlane(n, {0.02, 0.0, 0.5});
  const LaserCoefficients c = CoefficientsFromPlane(wrong, s.rect.b);
  // Precondition: every row's true pair is well outside max_residue_px against it.
  for (int v = 0; v < s.rect.height; ++v) {
    const Eigen::Vector3d pair = PairOf(s.truth[v], s.rect);
    ASSERT_GT(std::abs(c.Residue(pair.x(), pair.y(), v - s.rect.cy, s.rect.f)), 0.4) << v;
  }
  StripeFrameProcessor proc(&s.rect, {});
  StripeFrameResult out;
  proc.Process(s.left, s.right, c, &out);
  EXPECT_TRUE(out.points.empty()) << out.points.size() << " points";
  EXPECT_EQ(out.rejected, s.rect.height);
}

TEST(StripeFrameProcessorTest, OutOfRangePointsAreRejected) {
  Scene s = MakeScene(0.6, 0.0);
  StripeFrameConfig config;
  config.min_range_m = 0.7;  // the surface is at 0.6 m
  StripeFrameProcessor proc(&s.rect, config);
  StripeFrameResult out;
  proc.Process(s.left, s.right, CoefficientsFromPlane(s.plane, s.rect.b), &out);
  // The stripe lies outside the band the range allows: never even a candidate.
  EXPECT_TRUE(out.points.empty());
}

TEST(StripeFrameProcessorTest, NoStripeNoPointsNoRejections) {
  const Rectification rect = ParallelRig();
  StripeFrameProcessor proc(&rect, {});
  StripeFrameResult out;
  out.rejected = 99;
  proc.Process(Grey(), Grey(), CoefficientsFromPlane(LaserPlane(), rect.b), &out);
  EXPECT_TRUE(out.points.empty());
  EXPECT_EQ(out.rejected, 0);
}

// A scene's stripe drawn only on rows [first, last] (a fragment of it), with amplitude a.
Scene FragmentScene(int first, int last, double amplitude) {
  Scene s;
  for (int v = 0; v < s.rect.height; ++v) {
    const double y = v - s.rect.cy;
    s.truth.push_back(PointOnRow(s.plane, y, s.rect.f, [](double) { return 0.6; }));
  }
  for (int cam = 0; cam < 2; ++cam) {
    cv::Mat& image = cam == 0 ? s.left : s.right;
    for (int v = first; v <= last; ++v) {
      const Eigen::Vector3d pair = PairOf(s.truth[v], s.rect);
      const double c = (cam == 0 ? pair.x() : pair.y()) + s.rect.cx;
      for (int u = 0; u < image.cols; ++u) {
        cv::Vec3b& px = image.at<cv::Vec3b>(v, u);
        px[2] = cv::saturate_cast<std::uint8_t>(px[2] + PixelGaussian(u, c, amplitude));
      }
    }
  }
  return s;
}

TEST(StripeFrameProcessorTest, LonePointsAreRejected) {
  // A stripe on one row only, in both images and on the plane: a chance pairing as far as the
  // processor can tell (no point within 1 cm on the rows around it).
  Scene lone = FragmentScene(100, 100, 100);
  StripeFrameProcessor proc(&lone.rect, {});
  StripeFrameResult out;
  const LaserCoefficients c = CoefficientsFromPlane(lone.plane, lone.rect.b);
  proc.Process(lone.left, lone.right, c, &out);
  EXPECT_TRUE(out.points.empty());
  EXPECT_EQ(out.rejected, 1);
  // Two rows of it support each other.
  Scene two = FragmentScene(100, 101, 100);
  proc.Process(two.left, two.right, c, &out);
  EXPECT_EQ(out.points.size(), 2u);
  EXPECT_EQ(out.rejected, 0);
}

TEST(StripeFrameProcessorTest, WeakStripeFoundWhereItRunsOnThroughTheRows) {
  // Amplitude 7: the peak stands about 6 grey levels up, under min_contrast (8) but over
  // weak_contrast (5). On 20 consecutive rows every row but the two at each end has support.
  Scene s = FragmentScene(100, 119, 7);
  StripeFrameProcessor proc(&s.rect, {});
  StripeFrameResult out;
  const LaserCoefficients c = CoefficientsFromPlane(s.plane, s.rect.b);
  proc.Process(s.left, s.right, c, &out);
  ASSERT_EQ(out.points.size(), 16u);
  EXPECT_EQ(out.points.front().row, 102);
  EXPECT_EQ(out.points.back().row, 117);
  for (const StripePoint& p : out.points) {
    EXPECT_LT((p.p_M - s.truth[p.row]).norm(), 0.002) << p.row;
  }
  // Without the weak threshold none is found.
  StripeFrameConfig strict;
  strict.weak_contrast = strict.detector.min_contrast;
  StripeFrameProcessor strict_proc(&s.rect, strict);
  strict_proc.Process(s.left, s.right, c, &out);
  EXPECT_TRUE(out.points.empty());
}

TEST(StripeFrameProcessorTest, AmbientSubtractionFindsTheStripeBesideADarkEdge) {
  // A dark face (red 30) whose edge lies 2 pixels left of the stripe in both images, on a bright
  // background (150): the stripe's left background sample (3 pixels out) is on the bright side.
  Scene s = MakeScene(0.6, 0.0);
  cv::Mat ambient[2] = {cv::Mat(240, 320, CV_8UC3, cv::Scalar(80, 80, 150)),
                        cv::Mat(240, 320, CV_8UC3, cv::Scalar(80, 80, 150))};
  cv::Mat frame[2] = {ambient[0].clone(), ambient[1].clone()};
  for (int cam = 0; cam < 2; ++cam) {
    for (int v = 0; v < 240; ++v) {
      const Eigen::Vector3d pair = PairOf(s.truth[v], s.rect);
      const double centre = (cam == 0 ? pair.x() : pair.y()) + s.rect.cx;
      for (int u = static_cast<int>(std::ceil(centre - 2.0)); u < 320; ++u) {
        ambient[cam].at<cv::Vec3b>(v, u)[2] = 30;
        frame[cam].at<cv::Vec3b>(v, u)[2] =
            cv::saturate_cast<std::uint8_t>(30 + PixelGaussian(u, centre, 25));
      }
    }
  }
  const LaserCoefficients c = CoefficientsFromPlane(s.plane, s.rect.b);
  StripeFrameResult out;
  StripeFrameProcessor proc(&s.rect, {});
  proc.Process(frame[0], frame[1], c, &out);
  const size_t without = out.points.size();
  proc.SetAmbient(ambient[0], ambient[1]);
  proc.Process(frame[0], frame[1], c, &out);
  EXPECT_EQ(out.points.size(), 240u);
  EXPECT_LT(without, 240u);
  for (const StripePoint& p : out.points) {
    EXPECT_LT((p.p_M - s.truth[p.row]).norm(), 0.001) << p.row;
  }
}

// Frontal surface, and one sloping back 0.2 m per m upward (the stripe then leans).
INSTANTIATE_TEST_SUITE_P(Surface, StripeFrameTest, ::testing::Values(0.0, 0.2),
                         [](const ::testing::TestParamInfo<double>& info) {
                           return info.param == 0.0 ? std::string("frontal")
                                                    : std::string("sloping");
                         });

// ---------------------------------------------------------------------------------------------
// Eq. 6: the coefficients from pairs (laser_self_calibration.h)

constexpr double kF = 230.5;
constexpr double kHalfBaseline = 0.07;

Eigen::Vector3d PairAt(const Eigen::Vector3d& p) {
  return {(p.x() + kHalfBaseline) * kF / p.z(), (p.x() - kHalfBaseline) * kF / p.z(),
          p.y() * kF / p.z()};
}

// Pairs of the laser plane over a bumpy (non-planar) surface: one per row y.
std::vector<Eigen::Vector3d> BumpyPairs(const Plane& plane, int rows) {
  std::vector<Eigen::Vector3d> pairs;
  for (int i = 0; i < rows; ++i) {
    const double y = -110.0 + 220.0 * i / (rows - 1);
    const Eigen::Vector3d p = PointOnRow(plane, y, kF, [](double Y) {
      return 0.6 + 0.08 * std::sin(40.0 * Y) + 0.3 * Y;  // ridges and a slope
    });
    pairs.push_back(PairAt(p));
  }
  return pairs;
}

TEST(FitCoefficientsTest, ExactPairsGiveThePlaneBack) {
  const Plane plane = LaserPlane();
  const LaserCoefficients truth = CoefficientsFromPlane(plane, kHalfBaseline);
  ASSERT_GT(std::abs(truth.beta), 1e-3);  // all three coefficients are exercised
  double rms = -1;
  const auto c = FitCoefficients(BumpyPairs(plane, 100), kF, &rms);
  ASSERT_TRUE(c.has_value());
  EXPECT_NEAR(c->alpha, truth.alpha, 1e-9);
  EXPECT_NEAR(c->beta, truth.beta, 1e-9);
  EXPECT_NEAR(c->gamma, truth.gamma, 1e-9);
  EXPECT_NEAR(rms, 0.0, 1e-9);
}

TEST(FitCoefficientsTest, PlanarTargetIsUndetermined) {
  // The stripe on a plane is a line in space; its pairs leave one direction of (alpha, beta,
  // gamma) free.
  const Plane plane = LaserPlane();
  std::vector<Eigen::Vector3d> pairs;
  for (int i = 0; i < 100; ++i) {
    const double y = -110.0 + 2.2 * i;
    pairs.push_back(PairAt(PointOnRow(plane, y, kF, [](double Y) { return 0.5 + 0.3 * Y; })));
  }
  EXPECT_FALSE(FitCoefficients(pairs, kF).has_value());
  // Too few pairs.
  EXPECT_FALSE(FitCoefficients(BumpyPairs(plane, 19), kF).has_value());
  EXPECT_TRUE(FitCoefficients(BumpyPairs(plane, 20), kF).has_value());
}

TEST(FitCoefficientsTest, RobustFitIgnoresDecoys) {
  const Plane plane = LaserPlane();
  const LaserCoefficients truth = CoefficientsFromPlane(plane, kHalfBaseline);
  const std::vector<Eigen::Vector3d> exact = BumpyPairs(plane, 200);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> offset(3.0, 20.0);
  std::bernoulli_distribution sign(0.5);
  auto decoy = [&](const Eigen::Vector3d& p) {
    // Shifted in xL (the residue changes by the shift), keeping positive disparity.
    const double d = sign(rng) ? offset(rng) : -std::min(offset(rng), p.x() - p.y() - 1.0);
    return Eigen::Vector3d(p.x() + d, p.y(), p.z());
  };
  std::vector<std::vector<Eigen::Vector3d>> rows(exact.size());
  int true_rows = 0;
  for (size_t i = 0; i < exact.size(); ++i) {
    const int k = static_cast<int>(i % 10);
    if (k == 0) {
      rows[i] = {decoy(exact[i])};  // 10%: only a decoy
    } else if (k <= 3) {
      rows[i] = k % 2 ? std::vector<Eigen::Vector3d>{decoy(exact[i]), exact[i]}
                      : std::vector<Eigen::Vector3d>{exact[i], decoy(exact[i])};  // 30%
      ++true_rows;
    } else {
      rows[i] = {exact[i]};
      ++true_rows;
    }
    for (const auto& q : rows[i]) ASSERT_GT(q.x(), q.y());
  }
  std::vector<Eigen::Vector3d> chosen;
  const auto c = FitCoefficientsRobust(rows, kF, 0.5, &chosen);
  ASSERT_TRUE(c.has_value());
  EXPECT_NEAR(c->alpha, truth.alpha, 1e-6);
  EXPECT_NEAR(c->beta, truth.beta, 1e-6);
  EXPECT_NEAR(c->gamma, truth.gamma, 1e-6);
  EXPECT_EQ(static_cast<int>(chosen.size()), true_rows);
  for (const auto& q : chosen) EXPECT_NEAR(truth.Residue(q.x(), q.y(), q.z(), kF), 0.0, 1e-9);
}

}  // namespace
}  // namespace hgrasp::scan
