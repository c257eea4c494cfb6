#pragma once
/// @file The device seam (src/device/) over the laser board: its stripe laser and its gripper
/// LEDs, two thin adapters sharing one LaserBoard, and the cameras' source of its latches.

#include <memory>

#include "camera/exposure_pairing.h"
#include "device/leds.h"
#include "device/stripe_laser.h"
#include "laser_board/laser_board.h"

namespace hgrasp::drivers {

/// device::StripeLaser on the laser board: laser diode, motor and encoder.
class BoardStripeLaser final : public device::StripeLaser {
 public:
  /// `board` must not be null.
  explicit BoardStripeLaser(std::shared_ptr<LaserBoard> board);

  /// The encoder count now; t_s is the board's clock (s since its power-up, 1 ms steps).
  device::Status Read(device::StripeLaserState* state) override;
  device::Status SetLaser(bool on) override;
  /// `speed_counts_s` (> 0, else kRejected) is clamped to the motor's top speed (the option
  /// max_speed_counts_s) as in the simulation and rounded to whole counts/s (at least 1); the
  /// board rejects a count outside its travel (kRejected).
  device::Status MoveTo(std::int32_t count, double speed_counts_s) override;
  /// SET_MOTOR_VELOCITY 0: the motor stops where it is.
  device::Status Stop() override;
  /// The board (shared with the LEDs and the cameras' latches).
  const std::shared_ptr<LaserBoard>& board() const { return board_; }

 private:
  std::shared_ptr<LaserBoard> board_;
};

/// device::Leds on the laser board: the red LEDs on both grippers.
class BoardLeds final : public device::Leds {
 public:
  /// `board` must not be null.
  explicit BoardLeds(std::shared_ptr<LaserBoard> board);

  int Count(device::Side side) const override;
  device::Status Set(device::Side side, std::uint32_t mask) override;
  /// The board (shared with the laser and the cameras' latches).
  const std::shared_ptr<LaserBoard>& board() const { return board_; }

 private:
  std::shared_ptr<LaserBoard> board_;
};

/// What a stereo camera asks the board for each frame (camera/exposure_pairing.h): the latch of
/// one board frame (FrameLatchOf), or the newest (LatestFrameLatch).
LatchSource BoardLatchSource(std::shared_ptr<LaserBoard> board);

}  // namespace hgrasp::drivers
