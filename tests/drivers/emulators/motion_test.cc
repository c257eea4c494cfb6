#include "emulators/motion.h"

#include <gtest/gtest.h>

#include <cmath>

namespace hgrasp::drivers {
namespace {

// Runs the axis to rest (or `max_s`), returning the time taken and the top speed seen.
double RunToRest(TrapezoidAxis* axis, double max_s, double* top_speed) {
  double t = 0.0;
  *top_speed = 0.0;
  while (axis->moving() && t < max_s) {
    axis->Advance(0.01);
    t += 0.01;
    *top_speed = std::max(*top_speed, std::abs(axis->velocity()));
  }
  return t;
}

TEST(TrapezoidAxis, ReachesTargetInTheTrapezoidTime) {
  // 1 rad at 2 rad/s, 4 rad/s^2: 0.5 s up (0.5 rad), 0 s cruise, hmm: accelerating to 2 rad/s
  // takes 0.5 s and 0.5 rad, so a 1 rad move is a triangle of 1 s reaching exactly 2 rad/s.
  // A 2 rad move: 0.5 s up, 0.5 s cruise (1 rad), 0.5 s down: 1.5 s.
  TrapezoidAxis axis({-10, 10, 2.0, 4.0});
  axis.MoveTo(2.0, 2.0, 4.0);
  double top;
  const double t = RunToRest(&axis, 5.0, &top);
  EXPECT_DOUBLE_EQ(axis.position(), 2.0);
  EXPECT_NEAR(t, 1.5, 0.02);
  EXPECT_NEAR(top, 2.0, 1e-9);
}

TEST(TrapezoidAxis, TriangleWhenTheMoveIsShort) {
  TrapezoidAxis axis({-10, 10, 2.0, 4.0});
  axis.MoveTo(0.25, 2.0, 4.0);  // peak sqrt(a d) = 1 rad/s after 0.25 s; 0.5 s in all
  double top;
  const double t = RunToRest(&axis, 5.0, &top);
  EXPECT_DOUBLE_EQ(axis.position(), 0.25);
  EXPECT_NEAR(t, 0.5, 0.02);
  EXPECT_NEAR(top, 1.0, 0.02);
}

TEST(TrapezoidAxis, ClampsTargetSpeedAndAcceleration) {
  TrapezoidAxis axis({-1, 1, 1.0, 1.0});
  axis.MoveTo(5.0, 10.0, 10.0);
  EXPECT_DOUBLE_EQ(axis.target(), 1.0);
  double top;
  RunToRest(&axis, 10.0, &top);
  EXPECT_DOUBLE_EQ(axis.position(), 1.0);
  EXPECT_LE(top, 1.0 + 1e-12);
}

TEST(TrapezoidAxis, NewTargetFromMotionAndStop) {
  TrapezoidAxis axis({-10, 10, 1.0, 2.0});
  axis.MoveTo(5.0, 1.0, 2.0);
  for (int i = 0; i < 100; ++i) axis.Advance(0.01);  // 1 s: cruising at 1 rad/s
  EXPECT_NEAR(axis.velocity(), 1.0, 1e-9);
  axis.MoveTo(0.0, 1.0, 2.0);  // turn back: decelerate through zero, return
  double top;
  RunToRest(&axis, 10.0, &top);
  EXPECT_DOUBLE_EQ(axis.position(), 0.0);

  axis.MoveAt(-1.0, 2.0);
  for (int i = 0; i < 100; ++i) axis.Advance(0.01);
  axis.Stop();  // from 1 rad/s at 2 rad/s^2: 0.5 s and 0.25 rad to rest
  const double x_stop = axis.position();
  RunToRest(&axis, 10.0, &top);
  EXPECT_NEAR(axis.position() - x_stop, -0.25, 0.01);
  EXPECT_FALSE(axis.moving());
}

TEST(TrapezoidAxis, VelocityModeStopsAtTheLimit) {
  TrapezoidAxis axis({-0.5, 0.5, 1.0, 10.0});
  axis.MoveAt(1.0, 10.0);
  double top;
  RunToRest(&axis, 5.0, &top);
  EXPECT_DOUBLE_EQ(axis.position(), 0.5);
  EXPECT_DOUBLE_EQ(axis.velocity(), 0.0);
}

}  // namespace
}  // namespace hgrasp::drivers
