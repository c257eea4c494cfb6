#include "biclops/pmd_codec.h"

#include <algorithm>

namespace hgrasp::drivers::pmd {

namespace {

// Argument and result word counts follow libPMD's PMD.cpp / PMDTransport.cpp: SendCommandLong
// (2 words out), SendCommandWord (1), SendCommand (0), SendCommandGetLong (2 words back),
// SendCommandGetWord (1), SendCommandGetWordWord (GetVersion, 2).
constexpr OpcodeInfo kOpcodes[] = {
    {op::kNoOperation, "NoOperation", 0, 0, false, true},
    {op::kSetPosition, "SetPosition", 2, 0, true, true},
    {op::kSetVelocity, "SetVelocity", 2, 0, true, true},
    {op::kUpdate, "Update", 0, 0, true, true},
    {op::kGetCommandedPosition, "GetCommandedPosition", 0, 2, false, true},
    {op::kGetActualPosition, "GetActualPosition", 0, 2, false, true},
    {op::kReset, "Reset", 0, 0, true, false},
    {op::kGetPosition, "GetPosition", 0, 2, false, true},
    {op::kGetVelocity, "GetVelocity", 0, 2, false, true},
    {op::kGetAcceleration, "GetAcceleration", 0, 2, false, true},
    {op::kGetSampleTime, "GetSampleTime", 0, 1, false, true},
    {op::kGetVersion, "GetVersion", 0, 2, false, true},
    {op::kSetAcceleration, "SetAcceleration", 2, 0, true, true},
    {op::kSetProfileMode, "SetProfileMode", 1, 0, true, true},
    {op::kGetProfileMode, "GetProfileMode", 0, 1, false, true},
    {op::kGetActivityStatus, "GetActivityStatus", 0, 1, false, true},
};

Command WithLong(std::uint8_t axis, std::uint8_t opcode, std::uint32_t value) {
  Command c;
  c.axis = axis;
  c.opcode = opcode;
  c.words = SplitLong(value);
  c.word_count = 2;
  return c;
}

}  // namespace

const OpcodeInfo* FindOpcode(std::uint8_t opcode) {
  for (const OpcodeInfo& info : kOpcodes) {
    if (info.opcode == opcode) return &info;
  }
  return nullptr;
}

bool StatusNeedsResync(std::uint8_t chip_status) {
  return chip_status == status::kBadSerialChecksum || chip_status == status::kInvalidInstruction ||
         chip_status == status::kInvalidAxis;
}

std::uint8_t ChecksumFor(std::span<const std::uint8_t> bytes) {
  unsigned sum = 0;
  for (std::uint8_t b : bytes) sum += b;
  return static_cast<std::uint8_t>(0x100u - (sum & 0xFFu));
}

bool SumIsZero(std::span<const std::uint8_t> bytes) {
  unsigned sum = 0;
  for (std::uint8_t b : bytes) sum += b;
  return (sum & 0xFFu) == 0;
}

std::array<std::uint16_t, 2> SplitLong(std::uint32_t value) {
  return {static_cast<std::uint16_t>(value >> 16), static_cast<std::uint16_t>(value & 0xFFFFu)};
}

std::uint32_t JoinLong(std::uint16_t high, std::uint16_t low) {
  return (static_cast<std::uint32_t>(high) << 16) | low;
}

Command NoOperation() { return Simple(0, op::kNoOperation); }
Command Reset() { return Simple(0, op::kReset); }

Command SetPosition(std::uint8_t axis, std::int32_t position_counts) {
  return WithLong(axis, op::kSetPosition, static_cast<std::uint32_t>(position_counts));
}

Command SetVelocity(std::uint8_t axis, std::int32_t velocity_reg) {
  return WithLong(axis, op::kSetVelocity, static_cast<std::uint32_t>(velocity_reg));
}

Command SetAcceleration(std::uint8_t axis, std::uint32_t acceleration_reg) {
  return WithLong(axis, op::kSetAcceleration, acceleration_reg);
}

Command SetProfileMode(std::uint8_t axis, std::uint16_t mode) {
  Command c = Simple(axis, op::kSetProfileMode);
  c.words[0] = mode;
  c.word_count = 1;
  return c;
}

Command Update(std::uint8_t axis) { return Simple(axis, op::kUpdate); }

Command Simple(std::uint8_t axis, std::uint8_t opcode) {
  Command c;
  c.axis = axis;
  c.opcode = opcode;
  return c;
}

std::vector<std::uint8_t> Encode(const Command& command) {
  // libPMD PMDSerial::BuildCommandBuffer: address, checksum placeholder, axis, opcode, the
  // words high byte first; then the checksum byte is the negated sum of the others.
  std::vector<std::uint8_t> bytes = {command.address, 0, command.axis, command.opcode};
  const int n = std::clamp(command.word_count, 0, 2);
  for (int i = 0; i < n; ++i) {
    bytes.push_back(static_cast<std::uint8_t>(command.words[static_cast<std::size_t>(i)] >> 8));
    bytes.push_back(static_cast<std::uint8_t>(command.words[static_cast<std::size_t>(i)] & 0xFF));
  }
  bytes[1] = ChecksumFor(bytes);
  return bytes;
}

std::vector<std::uint8_t> Encode(const Reply& reply) {
  std::vector<std::uint8_t> bytes = {reply.status, 0};
  if (reply.status == status::kOk) {
    const int n = std::clamp(reply.word_count, 0, 2);
    for (int i = 0; i < n; ++i) {
      bytes.push_back(static_cast<std::uint8_t>(reply.words[static_cast<std::size_t>(i)] >> 8));
      bytes.push_back(static_cast<std::uint8_t>(reply.words[static_cast<std::size_t>(i)] & 0xFF));
    }
  }
  bytes[1] = ChecksumFor(bytes);
  return bytes;
}

std::int64_t CommandValue(const Command& command) {
  switch (command.opcode) {
    case op::kSetPosition:
    case op::kSetVelocity:
      return static_cast<std::int32_t>(JoinLong(command.words[0], command.words[1]));
    case op::kSetAcceleration:
      return JoinLong(command.words[0], command.words[1]);
    case op::kSetProfileMode:
      return command.words[0];
    default:
      return 0;
  }
}

std::int64_t ReplyLong(const Reply& reply) {
  if (reply.word_count == 2) {
    return static_cast<std::int32_t>(JoinLong(reply.words[0], reply.words[1]));
  }
  if (reply.word_count == 1) return reply.words[0];
  return 0;
}

bool CommandDecoder::Push(std::uint8_t byte, Packet* packet) {
  buf_[size_++] = byte;
  if (size_ == 4) {
    const OpcodeInfo* info = FindOpcode(buf_[3]);
    expected_ = 4 + (info != nullptr ? 2 * static_cast<std::size_t>(info->argument_words) : 0);
  }
  if (size_ < expected_) return false;

  Packet p;
  p.command.address = buf_[0];
  p.command.axis = buf_[2];
  p.command.opcode = buf_[3];
  p.command.word_count = static_cast<int>((size_ - 4) / 2);
  for (int i = 0; i < p.command.word_count; ++i) {
    const std::size_t at = 4 + 2 * static_cast<std::size_t>(i);
    p.command.words[static_cast<std::size_t>(i)] =
        static_cast<std::uint16_t>((buf_[at] << 8) | buf_[at + 1]);
  }
  p.checksum_ok = SumIsZero({buf_.data(), size_});
  p.known_opcode = FindOpcode(buf_[3]) != nullptr;
  std::copy(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(size_), p.raw.begin());
  p.size = size_;
  size_ = 0;
  expected_ = 4;
  *packet = p;
  return true;
}

void CommandDecoder::Feed(std::span<const std::uint8_t> bytes, std::vector<Packet>* packets) {
  Packet p;
  for (std::uint8_t b : bytes) {
    if (Push(b, &p)) packets->push_back(p);
  }
}

void ReplyDecoder::Expect(int result_words) {
  result_words_ = std::clamp(result_words, 0, 2);
  size_ = 0;
  done_ = false;
  reply_ = Reply{};
}

ReplyDecoder::Result ReplyDecoder::Push(std::uint8_t byte) {
  if (done_) return Result::kGarbled;
  buf_[size_++] = byte;
  if (size_ < 2) return Result::kNeedMore;
  const std::size_t full = 2 + 2 * static_cast<std::size_t>(result_words_);
  const std::span<const std::uint8_t> got(buf_.data(), size_);
  if (size_ == 2 && buf_[0] != status::kOk && SumIsZero(got)) {
    // An error status: the chip sends no data words (C-Motion PMDSerial_Send).
    done_ = true;
    reply_.status = buf_[0];
    reply_.word_count = 0;
    return Result::kReply;
  }
  if (size_ < full) return Result::kNeedMore;
  done_ = true;
  if (buf_[0] != status::kOk || !SumIsZero(got)) return Result::kGarbled;
  reply_.status = status::kOk;
  reply_.word_count = result_words_;
  for (int i = 0; i < result_words_; ++i) {
    const std::size_t at = 2 + 2 * static_cast<std::size_t>(i);
    reply_.words[static_cast<std::size_t>(i)] =
        static_cast<std::uint16_t>((buf_[at] << 8) | buf_[at + 1]);
  }
  return Result::kReply;
}

}  // namespace hgrasp::drivers::pmd
