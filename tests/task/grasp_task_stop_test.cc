// How the task ends when it is asked to stop (SIGINT, SIGTERM: a StopRequest) and when a
// device's read fails while the task waits for a motion to end (issue 16, items 2 and 3).

#include <gtest/gtest.h>

#include <functional>
#include <memory>

#include "common/paths.h"
#include "common/stop_request.h"
#include "tests/task/task_sim_util.h"

namespace hgrasp::task {
namespace {

using device::Status;

// Calls `on_grab(n)` before the n-th grab (1-based).
class WatchedCamera final : public device::StereoCamera {
 public:
  WatchedCamera(std::unique_ptr<device::StereoCamera> inner, std::function<void(int)> on_grab)
      : inner_(std::move(inner)), on_grab_(std::move(on_grab)) {}
  Status Grab(device::StereoFrame* frame) override {
    on_grab_(++grabs_);
    return inner_->Grab(frame);
  }

 private:
  std::unique_ptr<device::StereoCamera> inner_;
  std::function<void(int)> on_grab_;
  int grabs_ = 0;
};

// Calls `on_move()` at every MoveJoints.
class WatchedArm final : public device::Arm {
 public:
  WatchedArm(std::unique_ptr<device::Arm> inner, std::function<void()> on_move)
      : inner_(std::move(inner)), on_move_(std::move(on_move)) {}
  Status Read(device::ArmState* s) override { return inner_->Read(s); }
  Status MoveJoints(const device::Joint6& q) override {
    on_move_();
    return inner_->MoveJoints(q);
  }
  Status MoveRelative(const Pose3& X) override { return inner_->MoveRelative(X); }
  Status SetSpeed(double f) override { return inner_->SetSpeed(f); }
  Status Stop() override { return inner_->Stop(); }

 private:
  std::unique_ptr<device::Arm> inner_;
  std::function<void()> on_move_;
};

// A hand whose every read after its first Open times out (a hand that went silent).
class SilentAfterOpenHand final : public device::Hand {
 public:
  explicit SilentAfterOpenHand(std::unique_ptr<device::Hand> inner) : inner_(std::move(inner)) {}
  Status Read(device::HandState* s) override {
    return opened_ ? Status::kTimeout : inner_->Read(s);
  }
  Status Open(double opening_m) override {
    opened_ = true;
    return inner_->Open(opening_m);
  }
  Status Close(double force_n) override { return inner_->Close(force_n); }

 private:
  std::unique_ptr<device::Hand> inner_;
  bool opened_ = false;
};

sim::Scenario Default() { return sim::LoadScenario(ResolveDataPath("scenarios/default.yaml")); }

TEST(GraspTaskStop, AStopDuringTheScanEndsTheLookAsInterrupted) {
  const sim::Scenario scenario = Default();
  sim::SimRobot robot(scenario);
  device::RobotDevices dev = robot.TakeDevices();
  StopRequest stop;
  dev.cameras = std::make_unique<WatchedCamera>(std::move(dev.cameras), [&](int n) {
    if (n == 50) stop.Request(SIGINT);  // mid-sweep: a sweep is 300 frames
  });
  TaskConfig config = testing::ConfigFor(scenario);
  config.stop = &stop;
  GraspTask task(&dev, testing::SimRobotModel(), config);
  EXPECT_FALSE(task.Look());
  EXPECT_EQ(task.result().failure, Failure::kInterrupted);
  EXPECT_EQ(task.result().message, "SIGINT during the scan");
  ASSERT_TRUE(task.result().scan.has_value());
  EXPECT_EQ(task.result().scan->status, Status::kInterrupted);
  EXPECT_TRUE(task.result().failed_device.empty());
  EXPECT_FALSE(task.result().scene.has_value());
  device::StripeLaserState laser;
  ASSERT_EQ(dev.laser->Read(&laser), Status::kOk);
  EXPECT_FALSE(laser.laser_on);
}

TEST(GraspTaskStop, AStopDuringAnArmMoveEndsTheApproachAsInterrupted) {
  const sim::Scenario scenario = Default();
  sim::SimRobot robot(scenario);
  device::RobotDevices dev = robot.TakeDevices();
  StopRequest stop;
  for (auto& arm : dev.arm) {
    arm = std::make_unique<WatchedArm>(std::move(arm), [&] { stop.Request(SIGTERM); });
  }
  TaskConfig config = testing::ConfigFor(scenario);
  config.stop = &stop;
  GraspTask task(&dev, testing::SimRobotModel(), config);
  ASSERT_TRUE(task.Look() && task.Plan());
  EXPECT_FALSE(task.Approach());
  EXPECT_EQ(task.result().failure, Failure::kInterrupted);
  EXPECT_EQ(task.result().message, "SIGTERM during the approach");
  EXPECT_EQ(task.result().stages.back().name, "approach");
}

// Issue 16: a hand that stopped answering while the arm moved to the pre-grasp was taken for a
// hand still moving, and the task waited out move_timeout_s and said "arm move did not end
// within 20 s". Now it ends at the first failed read, naming the hand and what it said.
TEST(GraspTaskStop, AHandThatStopsAnsweringDuringTheApproachIsNamed) {
  const sim::Scenario scenario = Default();
  sim::SimRobot robot(scenario);
  device::RobotDevices dev = robot.TakeDevices();
  for (auto& hand : dev.hand) hand = std::make_unique<SilentAfterOpenHand>(std::move(hand));
  GraspTask task(&dev, testing::SimRobotModel(), testing::ConfigFor(scenario));
  ASSERT_TRUE(task.Look() && task.Plan());
  const std::string side(device::ToString(task.result().plan->side));
  EXPECT_FALSE(task.Approach());
  EXPECT_EQ(task.result().failure, Failure::kDeviceError);
  EXPECT_EQ(task.result().failed_device, "hand_" + side);
  EXPECT_EQ(task.result().message, "hand_" + side + ": timeout (read)");
  EXPECT_LT(task.result().stages.back().device_s, 1.0);  // at once, not after 20 s
}

}  // namespace
}  // namespace hgrasp::task
