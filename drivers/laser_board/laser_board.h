#pragma once
/// @file The laser board driver core: one serial link to the board that drives the stripe
/// laser's diode and motor, reads its encoder, latches the encoder count at each camera frame
/// and switches the grippers' LEDs (drivers/laser_board/PROTOCOL.md). Thread-safe: one request
/// at a time under a mutex, so the seam adapters (board_devices.h) and the camera driver
/// (LatestFrameLatch) may share one LaserBoard.
///
/// Never executed twice: every command carries a sequence number; the board answers a
/// retransmission of its last sequence number with its stored reply instead of executing it
/// again. The driver retransmits a command with the same number, takes a new number only for a
/// new command, and after any failure learns the board's last number (an unsequenced
/// GET_STATUS) before it sends anything else, so that a command whose outcome it does not know
/// is either answered from the board's memory or sent afresh, never run twice.

#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/clock.h"
#include "device/status.h"
#include "laser_board/laser_board_codec.h"
#include "serial/byte_link.h"
#include "serial/command_log.h"
#include "serial/serial_port.h"

namespace hgrasp::drivers {

/// Driver options. Defaults: the robot's board (models/humanoid.xml) and 115200 8N1 timing.
struct LaserBoardOptions {
  /// LEDs per gripper. 8: models/humanoid.xml has left_led0..left_led7 and right_led0..right_led7
  /// (read once from the model and hard-coded here; change it if the model changes).
  int leds_per_gripper = 8;
  /// Fastest motor speed, encoder counts/s; MoveTo clamps to it as the simulation does. 9000:
  /// models/humanoid.urdf's laser joint velocity limit 1.5708 rad/s (90 deg/s) at 0.01
  /// deg/count (sim::kLaserRadPerCount).
  double max_speed_counts_s = 9000.0;
  /// How long one attempt waits for its reply before retransmitting (s). The board answers
  /// within 1 ms; a request/reply pair is about 2 ms on the wire.
  double reply_timeout_s = 0.08;
  /// How long one call may take, all retries included (s): a cut link is reported after it.
  double call_timeout_s = 0.35;
};

/// Counters of the link's behaviour since the driver was made.
struct LaserBoardStats {
  std::uint64_t calls = 0;            ///< API calls that reached the link
  std::uint64_t sends = 0;            ///< frames written (first sends and retransmissions)
  std::uint64_t retransmissions = 0;  ///< of which retransmissions
  std::uint64_t syncs = 0;            ///< sequence-number syncs (unsequenced GET_STATUS)
  std::uint64_t replayed = 0;         ///< commands re-sent with the number the board executed
  std::uint64_t bad_frames = 0;       ///< received candidates failing CRC or parsing
  std::uint64_t naks = 0;             ///< NAK replies (bad-CRC NAKs included)
  std::uint64_t failures = 0;         ///< calls that returned a failure status
};

class LaserBoard {
 public:
  /// Takes the link (a SerialPort at 115200 8N1, possibly wrapped in a FaultyLink). Throws
  /// hgrasp::InputError for invalid options.
  /// `clock`: every time the driver reads and every wait it times (the link's own Read waits
  /// on the link's clock, the same one): the wall clock on a real robot, a SimClock in
  /// simulated time (it must outlive the driver).
  explicit LaserBoard(std::unique_ptr<ByteLink> link, const LaserBoardOptions& options = {},
                      Clock& clock = Clock::Wall());

  /// Opens `port` at 115200 8N1 and makes a driver; nullptr and *error on failure.
  static std::shared_ptr<LaserBoard> Open(const std::string& port, const LaserBoardOptions& options,
                                          std::string* error);

  /// Status and version.
  device::Status GetStatus(laser_board::BoardStatus* status);
  device::Status SetLaser(bool on);
  /// Runs the motor at `counts_s` (signed encoder counts/s; 0 stops) until a limit.
  device::Status SetMotorVelocity(std::int32_t counts_s);
  /// Moves the motor to `count` (encoder counts) cruising at `speed_counts_s` (> 0).
  /// kRejected when the board finds either outside its limits.
  device::Status MotorGoTo(std::int32_t count, std::uint32_t speed_counts_s);
  /// The encoder count now, with the laser and motor state and the board's clock.
  device::Status ReadEncoder(laser_board::EncoderReading* reading);
  /// The latch of the most recent camera frame. kRejected before the first frame.
  device::Status LatestFrameLatch(FrameLatch* latch);
  /// The latch of camera frame `frame`; kRejected when it has aged out of the board's ring
  /// (the last 16 frames) or has not happened yet.
  device::Status FrameLatchOf(std::uint32_t frame, FrameLatch* latch);
  /// Switches one gripper's LEDs: bit i of `mask` lights LED i. kRejected for bits at or above
  /// LedCount(side).
  device::Status SetLeds(device::Side side, std::uint32_t mask);

  /// LEDs on one gripper (the option leds_per_gripper).
  int LedCount(device::Side side) const { return options_.leds_per_gripper; }
  const LaserBoardOptions& options() const { return options_; }
  LaserBoardStats stats() const;
  /// The state-changing commands (laser_board::ChangesState) the board executed, in order,
  /// each once: the board's own log (LaserBoardEmulator::log) as laser_board::CodeOf and
  /// CommandPayload give them. Confirmed at the command's ACK (a retransmission's ACK comes
  /// from the board's memory: still once); a NAK removes it. A failed command whose answer was
  /// lost: confirmed when the sync before the next command shows the board's last sequence
  /// number to be the one it was sent with and the next command is not its retry (a retry is
  /// answered from the board's memory, and judged by that answer), removed when the number is
  /// another. (The board also takes the number of a command it refuses, a value outside its
  /// limits: such a command, its NAK lost and not retried, is confirmed although it did not
  /// run.) A failed command that nothing follows stays unconfirmed.
  const CommandLog<laser_board::Command>& command_log() const { return command_log_; }

 private:
  /// Runs one command: sequence-number bookkeeping, retries until call_timeout_s. On kOk,
  /// *reply is the board's ACK or NAK for it.
  device::Status Transact(const laser_board::Command& command, laser_board::Reply* reply);
  /// Transact for a command whose ACK carries `data_size` bytes; maps NAKs to kRejected.
  device::Status Run(const laser_board::Command& command, std::vector<std::uint8_t>* data,
                     std::size_t data_size);
  /// Learns the board's last sequence number with an unsequenced GET_STATUS.
  device::Status SyncLocked(Clock::TimePoint deadline, laser_board::BoardStatus* status);
  /// Sends one frame and collects its reply, retransmitting until `deadline`.
  device::Status Exchange(std::uint8_t seq, const laser_board::Command& command,
                          Clock::TimePoint deadline, laser_board::Reply* reply);
  static std::uint8_t NextSeq(std::uint8_t seq) {
    return seq == 255 ? 1 : static_cast<std::uint8_t>(seq + 1);  // 0 is kUnsequenced
  }

  const LaserBoardOptions options_;
  Clock* clock_;
  mutable std::mutex mu_;
  std::unique_ptr<ByteLink> link_;
  laser_board::FrameDecoder decoder_;
  /// The last sequence number the board is known to have, or that we sent since.
  std::uint8_t seq_ = 0;
  /// After a failure: the board's last sequence number is unknown until a sync.
  bool unsure_ = true;
  /// The command whose outcome is unknown (it failed), and the number it was sent with.
  std::optional<laser_board::Command> pending_;
  std::uint8_t pending_seq_ = 0;
  std::optional<CommandLog<laser_board::Command>::Id> pending_logged_;  ///< its log entry
  std::uint8_t token_ = 0;  ///< the last GET_STATUS token sent
  LaserBoardStats stats_;
  CommandLog<laser_board::Command> command_log_;
};

}  // namespace hgrasp::drivers
