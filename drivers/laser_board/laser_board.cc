#include "laser_board/laser_board.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <thread>

#include "common/error.h"

namespace hgrasp::drivers {

using device::Status;
namespace lb = laser_board;

namespace {

// After bytes that were not our reply (a bad candidate, a bad-CRC NAK, a damaged reply): how
// long to keep listening for a good reply that may follow in the same burst before
// retransmitting (about 20 byte times at 115200 baud).
constexpr std::chrono::milliseconds kResendGrace{2};
// While the port is gone: how often to try again (SerialPort reopens at most every 20 ms).
constexpr std::chrono::milliseconds kReconnectPoll{20};

double Seconds(Clock::Duration d) { return Clock::ToSeconds(d); }

void Check(bool ok, const std::string& field, const std::string& value,
           const std::string& expected) {
  if (!ok) throw InputError("", "laser_board." + field, value, expected);
}

}  // namespace

LaserBoard::LaserBoard(std::unique_ptr<ByteLink> link, const LaserBoardOptions& options,
                       Clock& clock)
    : options_(options), clock_(&clock), link_(std::move(link)) {
  Check(link_ != nullptr, "port", "", "an open serial link");
  Check(options.leds_per_gripper >= 0 && options.leds_per_gripper <= 32, "leds_per_gripper",
        std::to_string(options.leds_per_gripper), "0 to 32");
  Check(options.max_speed_counts_s >= 1, "max_speed_counts_s",
        std::to_string(options.max_speed_counts_s), ">= 1 count/s");
  Check(options.reply_timeout_s > 0, "reply_timeout_s", std::to_string(options.reply_timeout_s),
        "> 0 s");
  Check(options.call_timeout_s >= options.reply_timeout_s, "call_timeout_s",
        std::to_string(options.call_timeout_s), ">= reply_timeout_s");
}

std::shared_ptr<LaserBoard> LaserBoard::Open(const std::string& port,
                                             const LaserBoardOptions& options, std::string* error) {
  SerialConfig config;
  config.port = port;
  config.baud = lb::kBaud;  // 8N1: SerialConfig's defaults
  auto link = SerialPort::Open(config, error);
  if (!link) return nullptr;
  return std::make_shared<LaserBoard>(std::move(link), options);
}

LaserBoardStats LaserBoard::stats() const {
  std::lock_guard<std::mutex> lock(mu_);
  return stats_;
}

// ----- public operations -----

Status LaserBoard::GetStatus(lb::BoardStatus* status) {
  std::vector<std::uint8_t> data;
  std::uint8_t token;
  {
    std::lock_guard<std::mutex> lock(mu_);
    token = ++token_;
  }
  if (const Status s = Run(lb::GetStatus{token}, &data, 8); s != Status::kOk) return s;
  const auto parsed = lb::ParseStatus(data);
  if (!parsed) return Status::kBadReply;
  *status = *parsed;
  return Status::kOk;
}

Status LaserBoard::SetLaser(bool on) {
  std::vector<std::uint8_t> data;
  return Run(lb::SetLaser{on}, &data, 0);
}

Status LaserBoard::SetMotorVelocity(std::int32_t counts_s) {
  std::vector<std::uint8_t> data;
  return Run(lb::MotorVelocity{counts_s}, &data, 0);
}

Status LaserBoard::MotorGoTo(std::int32_t count, std::uint32_t speed_counts_s) {
  if (speed_counts_s == 0) return Status::kRejected;
  std::vector<std::uint8_t> data;
  return Run(lb::MotorGoTo{count, speed_counts_s}, &data, 0);
}

Status LaserBoard::ReadEncoder(lb::EncoderReading* reading) {
  std::vector<std::uint8_t> data;
  if (const Status s = Run(lb::GetEncoder{}, &data, 9); s != Status::kOk) return s;
  const auto parsed = lb::ParseEncoder(data);
  if (!parsed) return Status::kBadReply;
  *reading = *parsed;
  return Status::kOk;
}

Status LaserBoard::LatestFrameLatch(FrameLatch* latch) {
  return FrameLatchOf(lb::kLatestFrame, latch);
}

Status LaserBoard::FrameLatchOf(std::uint32_t frame, FrameLatch* latch) {
  std::vector<std::uint8_t> data;
  if (const Status s = Run(lb::GetLatch{frame}, &data, 9); s != Status::kOk) return s;
  const auto parsed = lb::ParseLatch(data);
  // The board must answer for the frame asked for.
  if (!parsed || (frame != lb::kLatestFrame && parsed->frame != frame)) return Status::kBadReply;
  *latch = *parsed;
  return Status::kOk;
}

Status LaserBoard::SetLeds(device::Side side, std::uint32_t mask) {
  const int n = LedCount(side);
  if (n < 32 && (mask >> n) != 0) return Status::kRejected;
  std::vector<std::uint8_t> data;
  return Run(lb::SetLeds{static_cast<std::uint8_t>(side == device::Side::kLeft ? 0 : 1), mask},
             &data, 0);
}

// ----- transactions -----

Status LaserBoard::Run(const lb::Command& command, std::vector<std::uint8_t>* data,
                       std::size_t data_size) {
  lb::Reply reply;
  if (const Status s = Transact(command, &reply); s != Status::kOk) return s;
  if (!reply.ack) return Status::kRejected;  // the board refused it (PROTOCOL.md: NAK codes)
  if (reply.data.size() != data_size) return Status::kBadReply;
  *data = std::move(reply.data);
  return Status::kOk;
}

Status LaserBoard::Transact(const lb::Command& command, lb::Reply* reply) {
  std::lock_guard<std::mutex> lock(mu_);
  ++stats_.calls;
  const auto deadline = clock_->Now() + Clock::FromSeconds(options_.call_timeout_s);
  // Whatever is still buffered answers earlier requests.
  link_->Discard();
  decoder_.Reset();

  if (unsure_) {
    lb::BoardStatus status;
    if (const Status s = SyncLocked(deadline, &status); s != Status::kOk) {
      ++stats_.failures;
      return s;
    }
  }
  // A repeat of the command that failed, which the board did execute (its last number is the
  // one we sent it with): send it with the same number, and the board answers from memory.
  // Anything else is a new command with a new number.
  std::uint8_t seq;
  std::optional<CommandLog<lb::Command>::Id> logged;  // its place in command_log_
  if (pending_ && *pending_ == command && pending_seq_ == seq_) {
    seq = pending_seq_;
    logged = pending_logged_;
    ++stats_.replayed;
  } else {
    seq = NextSeq(seq_);
    // Not the failed command's retry: its outcome is known now (a pending command implies the
    // sync above). Its number the board's last, it ran (or was refused); else it never came.
    if (pending_logged_) command_log_.Resolve(*pending_logged_, pending_seq_ == seq_);
    if (lb::ChangesState(command)) logged = command_log_.Sent(command);
  }
  pending_.reset();
  pending_logged_.reset();
  seq_ = seq;

  const Status s = Exchange(seq, command, deadline, reply);
  if (s != Status::kOk) {
    // Outcome unknown: learn the board's last number before the next command.
    pending_ = command;
    pending_seq_ = seq;
    pending_logged_ = logged;
    unsure_ = true;
    ++stats_.failures;
    return s;
  }
  if (logged) command_log_.Resolve(*logged, reply->ack);
  if (!reply->ack) {
    ++stats_.failures;  // the caller gets kRejected
    // The board's memory and ours disagree (cannot happen with this driver alone): resync.
    if (reply->error == lb::ErrorCode::kSequenceReused) unsure_ = true;
  }
  return Status::kOk;
}

Status LaserBoard::SyncLocked(Clock::TimePoint deadline, lb::BoardStatus* status) {
  ++stats_.syncs;
  lb::Reply reply;
  if (const Status s = Exchange(lb::kUnsequenced, lb::GetStatus{++token_}, deadline, &reply);
      s != Status::kOk) {
    return s;
  }
  if (!reply.ack) return Status::kRejected;
  const auto parsed = lb::ParseStatus(reply.data);
  if (!parsed) return Status::kBadReply;
  *status = *parsed;
  seq_ = parsed->last_seq;
  unsure_ = false;
  return Status::kOk;
}

Status LaserBoard::Exchange(std::uint8_t seq, const lb::Command& command,
                            Clock::TimePoint deadline, lb::Reply* reply) {
  const std::vector<std::uint8_t> request = lb::EncodeFrame(lb::CommandFrame(seq, command));
  const auto code = static_cast<std::uint8_t>(lb::CodeOf(command));
  Status failure = Status::kTimeout;
  bool first = true;
  std::array<std::uint8_t, 256> buf;
  std::vector<lb::DecodeEvent> events;

  // Looks through decoded events for our reply. Returns true when found.
  auto examine = [&]() {
    for (lb::DecodeEvent& e : events) {
      if (e.kind == lb::DecodeEvent::Kind::kBadCrc) {
        ++stats_.bad_frames;
        failure = Status::kBadReply;
        continue;
      }
      const auto r = lb::ParseReply(e.frame);
      if (!r) {
        ++stats_.bad_frames;
        failure = Status::kBadReply;
        continue;
      }
      if (!r->ack) ++stats_.naks;
      if (r->seq != seq) continue;  // an answer to an earlier request
      if (!r->ack && r->error == lb::ErrorCode::kBadCrc) {
        continue;  // the board got our frame damaged: it is sent again (below)
      }
      if (r->command != code) continue;
      // GET_STATUS echoes its token: an earlier request's late answer (same SEQ) is not ours.
      if (const auto* status = std::get_if<lb::GetStatus>(&command);
          status && r->ack && (r->data.empty() || r->data[0] != status->token)) {
        continue;
      }
      *reply = *r;
      return true;
    }
    events.clear();
    return false;
  };

  while (clock_->Now() < deadline) {
    if (!first) ++stats_.retransmissions;
    first = false;
    ++stats_.sends;
    if (link_->Write(request) == Status::kDisconnected) {
      failure = Status::kDisconnected;
      clock_->SleepFor(std::min<Clock::Duration>(kReconnectPoll, deadline - clock_->Now()));
      continue;
    }
    auto attempt_end = std::min(
        deadline, clock_->Now() + Clock::FromSeconds(options_.reply_timeout_s));
    while (true) {
      const auto now = clock_->Now();
      if (now >= attempt_end) {
        // A complete reply may hide behind a false start byte whose LEN is still waiting for
        // bytes: give that candidate up and look again.
        decoder_.Expire(&events);
        if (examine()) return Status::kOk;
        break;
      }
      std::size_t n = 0;
      const Status s = link_->Read(buf, Seconds(attempt_end - now), &n);
      if (s == Status::kDisconnected) {
        failure = Status::kDisconnected;
        clock_->SleepFor(std::min<Clock::Duration>(kReconnectPoll, deadline - clock_->Now()));
        break;
      }
      if (s != Status::kOk || n == 0) continue;
      if (failure == Status::kDisconnected) failure = Status::kTimeout;  // it came back
      decoder_.Feed(std::span<const std::uint8_t>(buf.data(), n), &events);
      if (examine()) return Status::kOk;
      // Bytes, and no reply of ours (a damaged frame, a bad-CRC NAK for our number, a reply
      // whose corrupted start byte or LEN hides it from the decoder): the rest of a good one may
      // follow in the same burst; else the request is sent again soon, not at the attempt's end.
      // (Only damage the decoder saw used to shorten the attempt: a reply with a damaged start
      // byte right after a dropout cost 80 ms more, and with the dropout the call budget.)
      attempt_end = std::min(attempt_end, clock_->Now() + kResendGrace);
    }
  }
  return failure;
}

}  // namespace hgrasp::drivers
