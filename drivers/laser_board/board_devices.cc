#include "laser_board/board_devices.h"

#include <cmath>

#include "common/error.h"

namespace hgrasp::drivers {

using device::Status;

BoardStripeLaser::BoardStripeLaser(std::shared_ptr<LaserBoard> board) : board_(std::move(board)) {
  HGRASP_DEMAND(board_ != nullptr);
}

Status BoardStripeLaser::Read(device::StripeLaserState* state) {
  laser_board::EncoderReading r;
  if (const Status s = board_->ReadEncoder(&r); s != Status::kOk) return s;
  state->t_s = r.board_time_ms * 1e-3;
  state->encoder_count = r.count;
  state->laser_on = r.laser_on;
  state->moving = r.moving;
  return Status::kOk;
}

Status BoardStripeLaser::SetLaser(bool on) { return board_->SetLaser(on); }

Status BoardStripeLaser::MoveTo(std::int32_t count, double speed_counts_s) {
  if (!(speed_counts_s > 0)) return Status::kRejected;  // also NaN
  const double speed = std::min(speed_counts_s, board_->options().max_speed_counts_s);
  const auto wire = static_cast<std::uint32_t>(std::max(1.0, std::round(speed)));
  return board_->MotorGoTo(count, wire);
}

Status BoardStripeLaser::Stop() { return board_->SetMotorVelocity(0); }

BoardLeds::BoardLeds(std::shared_ptr<LaserBoard> board) : board_(std::move(board)) {
  HGRASP_DEMAND(board_ != nullptr);
}

int BoardLeds::Count(device::Side side) const { return board_->LedCount(side); }

Status BoardLeds::Set(device::Side side, std::uint32_t mask) { return board_->SetLeds(side, mask); }

LatchSource BoardLatchSource(std::shared_ptr<LaserBoard> board) {
  return [board = std::move(board)](std::optional<std::uint32_t> frame, ExposureLatch* out) {
    FrameLatch l;
    const Status status = frame ? board->FrameLatchOf(*frame, &l) : board->LatestFrameLatch(&l);
    out->frame = l.frame;
    out->encoder_count = l.encoder_count;
    out->laser_on = l.laser_on;
    return status;
  };
}

}  // namespace hgrasp::drivers
