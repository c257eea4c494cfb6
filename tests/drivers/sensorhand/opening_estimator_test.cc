// The SensorHand's opening estimate (sensorhand/opening_estimator.h) without I/O: motion worked
// out by hand (trapezoid ramps, run-on, the end stops, the motor's stall line), the fixes at the
// end stops, the uncertainty, and a cross-check against the emulator's mechanics fed the same
// commands and sampled every 12 ms as the stream is.

#include "sensorhand/opening_estimator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "emulators/sensorhand_emulator.h"

namespace hgrasp::drivers::sensorhand {
namespace {

constexpr auto kIdle = static_cast<std::uint8_t>(MotionState::kIdle);
constexpr auto kOpening = static_cast<std::uint8_t>(MotionState::kOpening);
constexpr auto kClosing = static_cast<std::uint8_t>(MotionState::kClosing);
constexpr auto kBlocked = static_cast<std::uint8_t>(MotionState::kBlocked);

HandMotionModel Exact() {
  HandMotionModel m;
  m.speed_error = 0.0;
  return m;
}

TEST(OpeningEstimator, TrapezoidRampsAndRunOn) {
  OpeningEstimator e(Exact(), 0.0, 0.02, 0.0);
  e.Execute(0.0, {kSpeedMax, 0}, 0.0);
  // 10 m/s^2 from rest: full speed (0.3 m/s) after 30 ms, 0.5 * 10 * 0.03^2 = 4.5 mm on.
  e.AdvanceTo(0.03);
  EXPECT_NEAR(e.velocity_m_s(), 0.30, 1e-12);
  EXPECT_NEAR(e.opening_m(), 0.0245, 1e-12);
  e.AdvanceTo(0.05);
  EXPECT_NEAR(e.opening_m(), 0.0245 + 0.006, 1e-12);
  // Stopping now runs on v^2 / 2a = 4.5 mm.
  EXPECT_NEAR(e.RestOpening(), 0.0305 + 0.0045, 1e-12);
  e.Execute(0.05, kStop, 0.0);
  e.AdvanceTo(0.2);
  EXPECT_NEAR(e.opening_m(), 0.035, 1e-12);
  EXPECT_EQ(e.velocity_m_s(), 0.0);
  // A slow byte: (0x3B - 0x30) / 85 of 0.3 m/s, closing.
  e.Execute(0.2, {0, 0x3B}, 0.0);
  e.AdvanceTo(0.7);
  EXPECT_NEAR(e.velocity_m_s(), -0.3 * 11.0 / 85.0, 1e-12);
  const double ramp = 0.3 * 11.0 / 85.0 / 10.0;
  EXPECT_NEAR(e.opening_m(), 0.035 - 0.3 * 11.0 / 85.0 * (0.5 - ramp / 2.0), 1e-12);
}

TEST(OpeningEstimator, StopsAtTheEndsOfTheRange) {
  OpeningEstimator e(Exact(), 0.0, 0.09, 0.0);
  e.Execute(0.0, {kSpeedMax, 0}, 0.0);
  e.AdvanceTo(1.0);
  EXPECT_EQ(e.opening_m(), 0.10);
  EXPECT_EQ(e.velocity_m_s(), 0.0);
  e.Execute(1.0, {0, kSpeedMax}, 0.0);
  e.AdvanceTo(2.0);
  EXPECT_EQ(e.opening_m(), 0.0);
  EXPECT_EQ(e.velocity_m_s(), 0.0);
}

TEST(OpeningEstimator, BlockedFixesTheEstimateAtTheEndStops) {
  // The start guess is 20 mm off; opening until blocked finds the end stop.
  HandMotionModel m = Exact();
  OpeningEstimator e(m, 0.0, 0.06, 0.02);
  EXPECT_FALSE(e.referenced());
  e.Execute(0.0, {kSpeedMax, 0}, 0.0);
  e.Observe(0.05, 0.0, kOpening);
  EXPECT_EQ(e.fixes(), 0);
  const double before = e.opening_m();
  e.Observe(0.062, 0.0, kBlocked);
  EXPECT_TRUE(e.referenced());
  EXPECT_EQ(e.fixes(), 1);
  EXPECT_EQ(e.opening_m(), 0.10);
  EXPECT_EQ(e.uncertainty_m(), 0.0);
  EXPECT_NEAR(e.last_correction_m(), 0.10 - (before + 0.3 * 0.012), 1e-12);
  // Closing with no force until blocked: the fingers meet.
  e.Execute(0.1, {0, kSpeedMax}, 0.0);
  e.Observe(0.2, 0.0, kClosing);
  e.Observe(0.212, 0.0, kBlocked);
  EXPECT_EQ(e.opening_m(), 0.0);
  EXPECT_EQ(e.fixes(), 2);
  // Idle under speed 0: the fingers are still.
  e.Execute(0.3, {0x40, 0}, 0.0);
  e.Execute(0.32, kStop, 0.0);
  e.Observe(0.325, 0.0, kIdle);
  EXPECT_EQ(e.velocity_m_s(), 0.0);
}

TEST(OpeningEstimator, StallsOnAnObjectWithoutAFix) {
  OpeningEstimator e(Exact(), 0.0, 0.05, 0.0);
  e.Execute(0.0, {0, kSpeedMax}, 0.0);  // stall force 100 N
  e.AdvanceTo(0.05);
  // 50 N on both sides of the interval: the motor runs at half its speed.
  e.Observe(0.06, 50.0, kClosing);
  e.Observe(0.07, 50.0, kClosing);
  EXPECT_NEAR(e.velocity_m_s(), -0.15, 1e-12);
  const double y = e.opening_m();
  e.Observe(0.08, 50.0, kBlocked);
  EXPECT_EQ(e.velocity_m_s(), 0.0);
  EXPECT_EQ(e.fixes(), 0);
  EXPECT_NEAR(e.opening_m(), y - 0.15 * 0.01, 1e-12);  // 10 ms more at 0.15 m/s, then still
  // A state value we do not know changes nothing.
  const OpeningEstimator copy = e;
  e.Observe(0.09, 50.0, 0x42);
  EXPECT_EQ(e.opening_m(), copy.opening_m());
  EXPECT_EQ(e.fixes(), copy.fixes());
}

TEST(OpeningEstimator, UncertaintyGrowsWithTravelTimingAndBlindGaps) {
  HandMotionModel m;
  m.speed_error = 0.02;
  OpeningEstimator e(m, 0.0, 0.0, 0.0);
  // 1 ms timing uncertainty on a step of 0.3 m/s: 0.3 mm.
  e.Execute(0.0, {kSpeedMax, 0}, 0.001);
  EXPECT_NEAR(e.uncertainty_m(), 0.0003, 1e-12);
  e.Observe(0.012, 0.0, kOpening);
  e.Observe(0.024, 0.0, kOpening);
  const double travelled = e.opening_m();
  EXPECT_NEAR(e.uncertainty_m(), 0.0003 + 0.02 * travelled, 1e-12);
  // No samples for 0.1 s: all of that travel is unseen.
  const double sigma = e.uncertainty_m();
  const double y = e.opening_m();
  e.Observe(0.124, 0.0, kOpening);
  EXPECT_NEAR(e.uncertainty_m(), sigma + 1.02 * (e.opening_m() - y), 1e-12);
  e.AddUncertainty(0.01);
  EXPECT_NEAR(e.uncertainty_m(), sigma + 1.02 * (e.opening_m() - y) + 0.01, 1e-12);
  EXPECT_FALSE(e.lost());  // opening unseen: the end stop would have shown
}

TEST(OpeningEstimator, ClosingUnseenOntoAnObjectIsLost) {
  OpeningEstimator e(Exact(), 0.0, 0.08, 0.0);
  e.Execute(0.0, {0, kSpeedMax}, 0.0);
  e.Observe(0.012, 0.0, kClosing);
  e.Observe(0.024, 0.0, kClosing);
  // 0.2 s without samples, then pressing: where they stopped nobody saw.
  e.Observe(0.224, 60.0, kBlocked);
  EXPECT_TRUE(e.lost());
  EXPECT_EQ(e.fixes(), 0);
  // The end stop finds it again.
  e.Execute(0.3, {kSpeedMax, 0}, 0.0);
  e.Observe(0.312, 0.0, kOpening);
  e.Observe(0.5, 0.0, kBlocked);
  EXPECT_FALSE(e.lost());
  EXPECT_EQ(e.opening_m(), 0.10);
  // Closing unseen with no force after: nothing stopped them (or the stream says blocked at 0).
  OpeningEstimator f(Exact(), 0.0, 0.08, 0.0);
  f.Execute(0.0, {0, 0x40}, 0.0);
  f.Observe(0.012, 0.0, kClosing);
  f.Observe(0.2, 0.0, kClosing);
  EXPECT_FALSE(f.lost());
  // Held still (stopped) on an object through a gap: not lost.
  OpeningEstimator g(Exact(), 0.0, 0.045, 0.0);
  g.Observe(0.012, 25.0, kIdle);
  g.Observe(0.3, 25.0, kIdle);
  EXPECT_FALSE(g.lost());
  g.MarkLost(0.1);
  EXPECT_TRUE(g.lost());
  EXPECT_NEAR(g.uncertainty_m(), 0.1, 1e-12);
}

// The estimator against the emulator's mechanics, both given the same commands at the same
// times, the estimator seeing only what the stream carries (force and state bytes, every
// 12 ms). Free motion agrees to the model's precision; pressing into an object costs what the
// 12 ms force samples leave out.
TEST(OpeningEstimator, AgreesWithTheEmulatorsMechanics) {
  for (double object : {0.0, 0.05}) {
    SensorHandMechanics mech;
    mech.object_width_m = object;
    auto model = std::make_unique<KinematicSensorHand>(mech);
    KinematicSensorHand* hand = model.get();
    SensorHandEmulator emu(std::move(model));
    std::vector<std::uint8_t> out;
    ReplyDecoder dec;
    OpeningEstimator e(Exact(), 0.0, 0.08, 0.0);
    double t = 0.0;
    emu.Advance(t, &out);
    emu.Receive(EncodeDumpStart(), t, &out);
    struct Step {
      double at_s;
      SpeedSetting s;
    };
    const Step steps[] = {{0.05, {0, kSpeedMax}}, {0.12, kStop},        {0.3, {0x50, 0}},
                          {0.38, kStop},          {0.5, {0, 0x60}},     {0.9, kStop},
                          {1.0, {0x3B, 0}},       {1.1, kStop},         {1.3, {0, 0x3B}},
                          {1.6, kStop}};
    double max_err = 0.0, max_rest_err = 0.0;
    std::size_t next = 0;
    while (t < 1.8) {
      t += 0.002;
      out.clear();
      if (next < std::size(steps) && t >= steps[next].at_s - 1e-9) {
        emu.Receive(EncodeSpeed(steps[next].s), t, &out);
        e.Execute(t, steps[next].s, 0.0);
        ++next;
      }
      emu.Advance(t, &out);
      std::vector<Reply> replies;
      dec.Push(out, &replies);
      for (const Reply& r : replies) {
        if (r.kind != Reply::Kind::kDump) continue;
        e.Observe(t, ForceN(r.dump.f_bracket), r.dump.state);
        const double err = std::abs(e.opening_m() - hand->opening_m());
        max_err = std::max(max_err, err);
        if (hand->velocity_m_s() == 0.0) max_rest_err = std::max(max_rest_err, err);
      }
    }
    std::printf(
        "object %.3f m: estimate within %.3f mm of the mechanics moving, %.3f mm at rest; end "
        "%.5f vs %.5f m\n",
        object, max_err * 1e3, max_rest_err * 1e3, e.opening_m(), hand->opening_m());
    if (object == 0.0) {
      // Free motion: the emulator's 1 ms Euler steps run a ramp a h T / 2 = 0.15 mm ahead of
      // the exact trapezoid and the stop's ramp as much behind, so they agree at rest.
      EXPECT_LT(max_err, 0.0002);
      EXPECT_LT(max_rest_err, 2e-5);
    } else {
      EXPECT_LT(max_err, 0.0005);
      EXPECT_LT(max_rest_err, 0.0005);
    }
  }
}

}  // namespace
}  // namespace hgrasp::drivers::sensorhand
