#include "emulators/laser_board_emulator.h"

#include <algorithm>
#include <cmath>
#include <type_traits>

namespace hgrasp::drivers {

namespace lb = laser_board;

// ----- KinematicLaserBoardHardware -----

KinematicLaserBoardHardware::KinematicLaserBoardHardware(const LaserBoardEmulatorConfig& config)
    : motor_(config.motor, config.start_count),
      frame_period_s_(config.frame_period_s),
      next_frame_s_(config.first_frame_s) {}

void KinematicLaserBoardHardware::Advance(double t_s, std::vector<VsyncLatch>* latches) {
  if (!(t_s > t_s_)) return;
  // Step to each VSYNC pulse exactly, so that its latch holds the count at that instant.
  while (next_frame_s_ <= t_s) {
    motor_.Advance(next_frame_s_ - t_s_);
    t_s_ = next_frame_s_;
    latches->push_back({t_s_, EncoderCount(), laser_on_});
    next_frame_s_ += frame_period_s_;
  }
  motor_.Advance(t_s - t_s_);
  t_s_ = t_s;
}

std::int32_t KinematicLaserBoardHardware::EncoderCount() const {
  return static_cast<std::int32_t>(std::lround(motor_.position()));
}

void KinematicLaserBoardHardware::MoveAt(double counts_s) {
  if (counts_s == 0) {
    motor_.Stop();
  } else {
    motor_.MoveAt(counts_s, motor_.limits().max_accel);
  }
}

void KinematicLaserBoardHardware::MoveTo(std::int32_t count, double speed_counts_s) {
  motor_.MoveTo(count, speed_counts_s, motor_.limits().max_accel);
}

// ----- LaserBoardEmulator -----

LaserBoardEmulator::LaserBoardEmulator(const LaserBoardEmulatorConfig& config,
                                       std::unique_ptr<LaserBoardHardware> hardware)
    : config_(config), hardware_(std::move(hardware)) {
  if (!hardware_) hardware_ = std::make_unique<KinematicLaserBoardHardware>(config_);
}

std::vector<lb::Command> LaserBoardEmulator::ExecutedCommands() const {
  std::vector<lb::Command> commands;
  commands.reserve(log_.size());
  for (const auto& e : log_) commands.push_back(e.command);
  return commands;
}

void LaserBoardEmulator::Advance(double t_s, std::vector<std::uint8_t>* out) {
  t_s_ = std::max(t_s_, t_s);
  vsync_.clear();
  hardware_->Advance(t_s_, &vsync_);
  for (const VsyncLatch& v : vsync_) {
    latches_.push_back(FrameLatch{++frame_, v.encoder_count, v.laser_on});
    if (latches_.size() > kLatchRing) latches_.pop_front();
  }
  // The receiver gives up a frame whose bytes stopped coming (a false start byte, or a frame
  // cut short), and looks again at what followed its start byte.
  if (decoder_.partial() && t_s_ - last_rx_s_ > config_.interbyte_timeout_s) {
    events_.clear();
    decoder_.Expire(&events_);
    for (const auto& e : events_) Handle(e, t_s_, out);
  }
}

void LaserBoardEmulator::Receive(std::span<const std::uint8_t> in, double t_s,
                                 std::vector<std::uint8_t>* out) {
  Advance(t_s, out);
  last_rx_s_ = t_s_;
  events_.clear();
  decoder_.Feed(in, &events_);
  for (const auto& e : events_) Handle(e, t_s_, out);
}

void LaserBoardEmulator::Handle(const lb::DecodeEvent& event, double t_s,
                                std::vector<std::uint8_t>* out) {
  const lb::Frame& f = event.frame;
  if (event.kind == lb::DecodeEvent::Kind::kBadCrc) {
    ++counts_.crc_errors;
    ++counts_.naks;
    lb::AppendFrame(lb::NakFrame(f.seq, f.code, lb::ErrorCode::kBadCrc), out);
    return;
  }
  ++counts_.frames;
  const bool sequenced = f.seq != lb::kUnsequenced;
  if (sequenced && f.seq == last_seq_) {
    if (f == last_request_) {
      // A retransmission: the stored reply again, nothing executed.
      ++counts_.replayed;
      out->insert(out->end(), last_reply_.begin(), last_reply_.end());
    } else {
      ++counts_.naks;
      lb::AppendFrame(lb::NakFrame(f.seq, f.code, lb::ErrorCode::kSequenceReused), out);
    }
    return;
  }
  lb::Frame reply;
  lb::ErrorCode error{};
  const auto command = lb::ParseCommand(f, &error);
  if (!command) {
    reply = lb::NakFrame(f.seq, f.code, error);
  } else if (!sequenced && lb::ChangesState(*command)) {
    reply = lb::NakFrame(f.seq, f.code, lb::ErrorCode::kUnsequenced);
  } else {
    reply = Execute(f.seq, *command, t_s);
  }
  if (reply.code == static_cast<std::uint8_t>(lb::Code::kNak)) ++counts_.naks;
  const std::size_t at = out->size();
  lb::AppendFrame(reply, out);
  if (sequenced) {
    last_seq_ = f.seq;
    last_request_ = f;
    last_reply_.assign(out->begin() + static_cast<std::ptrdiff_t>(at), out->end());
  }
}

lb::Frame LaserBoardEmulator::Execute(std::uint8_t seq, const lb::Command& command, double t_s) {
  const AxisLimits& m = config_.motor;
  const std::uint8_t code = static_cast<std::uint8_t>(lb::CodeOf(command));
  const auto refuse = [&](lb::ErrorCode e) { return lb::NakFrame(seq, code, e); };
  std::vector<std::uint8_t> data;
  bool ok = true;
  std::visit(
      [&](const auto& c) {
        using T = std::decay_t<decltype(c)>;
        if constexpr (std::is_same_v<T, lb::GetStatus>) {
          lb::BoardStatus s;
          s.token = c.token;
          s.firmware_major = config_.firmware_major;
          s.firmware_minor = config_.firmware_minor;
          s.last_seq = last_seq_;
          s.laser_on = hardware_->LaserOn();
          s.moving = hardware_->Moving();
          s.leds_left = s.leds_right = static_cast<std::uint8_t>(config_.leds_per_gripper);
          data = lb::EncodeStatus(s);
        } else if constexpr (std::is_same_v<T, lb::SetLaser>) {
          hardware_->SetLaser(c.on);
        } else if constexpr (std::is_same_v<T, lb::MotorVelocity>) {
          ok = std::abs(static_cast<double>(c.counts_s)) <= m.max_speed;
          if (ok) hardware_->MoveAt(c.counts_s);
        } else if constexpr (std::is_same_v<T, lb::MotorGoTo>) {
          ok = c.count >= m.min && c.count <= m.max && c.speed_counts_s >= 1 &&
               c.speed_counts_s <= m.max_speed;
          if (ok) hardware_->MoveTo(c.count, c.speed_counts_s);
        } else if constexpr (std::is_same_v<T, lb::SetLeds>) {
          const int n = config_.leds_per_gripper;
          ok = c.side <= 1 && (n >= 32 || (c.mask >> n) == 0);
          if (ok) hardware_->SetLeds(c.side, c.mask);
        } else if constexpr (std::is_same_v<T, lb::GetEncoder>) {
          data = lb::EncodeEncoder(
              {static_cast<std::uint32_t>(static_cast<std::uint64_t>(t_s * 1000.0)),
               hardware_->EncoderCount(), hardware_->LaserOn(), hardware_->Moving()});
        } else if constexpr (std::is_same_v<T, lb::GetLatch>) {
          const FrameLatch* found = nullptr;
          if (c.frame == lb::kLatestFrame) {
            if (!latches_.empty()) found = &latches_.back();
          } else {
            for (const auto& l : latches_) {
              if (l.frame == c.frame) found = &l;
            }
          }
          ok = found != nullptr;
          if (ok) data = lb::EncodeLatch(*found);
        }
      },
      command);
  if (!ok) {
    return refuse(std::holds_alternative<lb::GetLatch>(command) ? lb::ErrorCode::kNoSuchFrame
                                                                : lb::ErrorCode::kOutOfRange);
  }
  ++counts_.executed;
  if (lb::ChangesState(command)) log_.push_back({t_s, seq, command});
  return lb::AckFrame(seq, lb::CodeOf(command), data);
}

std::unique_ptr<DeviceEmulator> MakeLaserBoardEmulator() {
  return std::make_unique<LaserBoardEmulator>();
}

}  // namespace hgrasp::drivers
