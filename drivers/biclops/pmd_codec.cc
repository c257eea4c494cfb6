#include "biclops/pmd_codec.h"

#include <algorithm>

namespace hgrasp::drivers::pmd {

namespace {

// Argument and result word counts follow libPMD's PMD.cpp and PMDTransport.cpp, by the transport
// call each command uses: SendCommand (0 out, 0 back), SendCommandWord (1, 0), SendCommandLong
// (2, 0), SendCommandWordWord (2, 0), SendCommandWordLong (3, 0), SendCommandGetWord (0, 1),
// SendCommandGetLong and SendCommandGetWordWord (0, 2), SendCommandWordGetWord (1, 1),
// SendCommandWordGetLong (1, 2). Opcodes of PMDOPCodes.h that PMD.cpp does not send (several
// Magellan-only ones) are not in the table: they are framed by their checksum (CommandDecoder).
constexpr OpcodeInfo kOpcodes[] = {
    {0x00, "NoOperation", 0, 0, false, true},
    {0x02, "SetMotorType", 1, 0, true, true},
    {0x03, "GetMotorType", 0, 1, false, true},
    {0x06, "SetMotorLimit", 1, 0, true, true},
    {0x07, "GetMotorLimit", 0, 1, false, true},
    {0x0F, "SetMotorBias", 1, 0, true, true},
    {0x10, "SetPosition", 2, 0, true, true},
    {0x11, "SetVelocity", 2, 0, true, true},
    {0x13, "SetJerk", 2, 0, true, true},
    {0x14, "SetGearRatio", 2, 0, true, true},
    {0x1A, "Update", 0, 0, true, true},
    {0x1D, "GetCommandedPosition", 0, 2, false, true},
    {0x1E, "GetCommandedVelocity", 0, 2, false, true},
    {0x25, "SetKp", 1, 0, true, true},
    {0x26, "SetKi", 1, 0, true, true},
    {0x27, "SetKd", 1, 0, true, true},
    {0x2B, "SetKvff", 1, 0, true, true},
    {0x2C, "GetPhaseAngle", 0, 1, false, true},
    {0x2D, "GetMotorBias", 0, 1, false, true},
    {0x2E, "RestoreOperatingMode", 0, 0, true, true},
    {0x2F, "SetInterruptMask", 1, 0, true, true},
    {0x31, "GetEventStatus", 0, 1, false, true},
    {0x34, "ResetEventStatus", 1, 0, true, true},
    {0x36, "GetCaptureValue", 0, 2, true, true},
    {0x37, "GetActualPosition", 0, 2, false, true},
    {0x38, "SetSampleTime", 1, 0, true, true},
    {0x39, "Reset", 0, 0, true, false},
    {0x3A, "GetCurrentMotorCommand", 0, 1, false, true},
    {0x3E, "GetTime", 0, 2, false, true},
    {0x47, "ClearPositionError", 0, 0, true, true},
    {0x48, "SetEventAction", 2, 0, true, true},
    {0x49, "GetEventAction", 0, 2, false, true},
    {0x4A, "GetPosition", 0, 2, false, true},
    {0x4B, "GetVelocity", 0, 2, false, true},
    {0x4C, "GetAcceleration", 0, 2, false, true},
    {0x4D, "SetActualPosition", 2, 0, true, true},
    {0x50, "GetKp", 0, 1, false, true},
    {0x51, "GetKi", 0, 1, false, true},
    {0x52, "GetKd", 0, 1, false, true},
    {0x54, "GetKvff", 0, 1, false, true},
    {0x56, "GetInterruptMask", 0, 1, false, true},
    {0x58, "GetJerk", 0, 2, false, true},
    {0x59, "GetGearRatio", 0, 2, false, true},
    {0x5B, "MultiUpdate", 1, 0, true, true},
    {0x61, "GetSampleTime", 0, 1, false, true},
    {0x65, "SetOperatingMode", 1, 0, true, true},
    {0x66, "GetOperatingMode", 0, 1, false, true},
    {0x69, "GetMotorCommand", 0, 1, false, true},
    {0x6A, "SetStartVelocity", 2, 0, true, true},
    {0x6B, "GetStartVelocity", 0, 2, false, true},
    {0x6E, "GetOutputMode", 0, 1, false, true},
    {0x72, "SetPhaseInitializeTime", 1, 0, true, true},
    {0x75, "SetPhaseCounts", 1, 0, true, true},
    {0x76, "SetPhaseOffset", 1, 0, true, true},
    {0x77, "SetMotorCommand", 1, 0, true, true},
    {0x7A, "InitializePhase", 0, 0, true, true},
    {0x7B, "GetPhaseOffset", 0, 1, false, true},
    {0x7C, "GetPhaseInitializeTime", 0, 1, false, true},
    {0x7D, "GetPhaseCounts", 0, 1, false, true},
    {0x80, "SetLimitSwitchMode", 1, 0, true, true},
    {0x81, "GetLimitSwitchMode", 0, 1, false, true},
    {0x82, "WriteIO", 2, 0, true, true},
    {0x83, "ReadIO", 1, 1, false, true},
    {0x84, "SetPhaseAngle", 1, 0, true, true},
    {0x85, "SetNumberPhases", 1, 0, true, true},
    {0x86, "GetNumberPhases", 0, 1, false, true},
    {0x87, "SetAxisMode", 1, 0, true, true},
    {0x88, "GetAxisMode", 0, 1, false, true},
    {0x89, "SetDiagnosticPortMode", 1, 0, true, true},
    {0x8A, "GetDiagnosticPortMode", 0, 1, false, true},
    {0x8B, "SetSerialPortMode", 1, 0, true, true},
    {0x8C, "GetSerialPortMode", 0, 1, false, true},
    {0x8D, "SetEncoderModulus", 1, 0, true, true},
    {0x8E, "GetEncoderModulus", 0, 1, false, true},
    {0x8F, "GetVersion", 0, 2, false, true},
    {0x90, "SetAcceleration", 2, 0, true, true},
    {0x91, "SetDeceleration", 2, 0, true, true},
    {0x92, "GetDeceleration", 0, 2, false, true},
    {0x93, "SetKaff", 1, 0, true, true},
    {0x94, "GetKaff", 0, 1, false, true},
    {0x95, "SetIntegrationLimit", 2, 0, true, true},
    {0x96, "GetIntegrationLimit", 0, 2, false, true},
    {0x97, "SetPositionErrorLimit", 2, 0, true, true},
    {0x98, "GetPositionErrorLimit", 0, 2, false, true},
    {0x99, "GetPositionError", 0, 2, false, true},
    {0x9A, "GetIntegral", 0, 2, false, true},
    {0x9B, "GetDerivative", 0, 1, false, true},
    {0x9C, "SetDerivativeTime", 1, 0, true, true},
    {0x9D, "GetDerivativeTime", 0, 1, false, true},
    {0x9E, "SetKout", 1, 0, true, true},
    {0x9F, "GetKout", 0, 1, false, true},
    {0xA0, "SetProfileMode", 1, 0, true, true},
    {0xA1, "GetProfileMode", 0, 1, false, true},
    {0xA2, "SetSignalSense", 1, 0, true, true},
    {0xA3, "GetSignalSense", 0, 1, false, true},
    {0xA4, "GetSignalStatus", 0, 1, false, true},
    {0xA5, "GetHostIOError", 0, 1, false, true},
    {0xA6, "GetActivityStatus", 0, 1, false, true},
    {0xA7, "GetCommandedAcceleration", 0, 2, false, true},
    {0xA8, "SetTrackingWindow", 1, 0, true, true},
    {0xA9, "GetTrackingWindow", 0, 1, false, true},
    {0xAA, "SetSettleTime", 1, 0, true, true},
    {0xAB, "GetSettleTime", 0, 1, false, true},
    {0xAC, "ClearInterrupt", 0, 0, true, true},
    {0xAD, "GetActualVelocity", 0, 2, false, true},
    {0xAE, "SetGearMaster", 1, 0, true, true},
    {0xAF, "GetGearMaster", 0, 1, false, true},
    {0xB0, "SetTraceMode", 1, 0, true, true},
    {0xB1, "GetTraceMode", 0, 1, false, true},
    {0xB2, "SetTraceStart", 1, 0, true, true},
    {0xB3, "GetTraceStart", 0, 1, false, true},
    {0xB4, "SetTraceStop", 1, 0, true, true},
    {0xB5, "GetTraceStop", 0, 1, false, true},
    {0xB6, "SetTraceVariable", 2, 0, true, true},
    {0xB7, "GetTraceVariable", 1, 1, false, true},
    {0xB8, "SetTracePeriod", 1, 0, true, true},
    {0xB9, "GetTracePeriod", 0, 1, false, true},
    {0xBA, "GetTraceStatus", 0, 1, false, true},
    {0xBB, "GetTraceCount", 0, 2, false, true},
    {0xBC, "SetSettleWindow", 1, 0, true, true},
    {0xBD, "GetSettleWindow", 0, 1, false, true},
    {0xBE, "SetActualPositionUnits", 1, 0, true, true},
    {0xBF, "GetActualPositionUnits", 0, 1, false, true},
    {0xC0, "SetBufferStart", 3, 0, true, true},
    {0xC1, "GetBufferStart", 1, 2, false, true},
    {0xC2, "SetBufferLength", 3, 0, true, true},
    {0xC3, "GetBufferLength", 1, 2, false, true},
    {0xC4, "SetBufferWriteIndex", 3, 0, true, true},
    {0xC5, "GetBufferWriteIndex", 1, 2, false, true},
    {0xC6, "SetBufferReadIndex", 3, 0, true, true},
    {0xC7, "GetBufferReadIndex", 1, 2, false, true},
    {0xC8, "WriteBuffer", 3, 0, true, true},
    {0xC9, "ReadBuffer", 1, 2, true, true},
    {0xCA, "SetBufferFunction", 2, 0, true, true},
    {0xCB, "GetBufferFunction", 1, 1, false, true},
    {0xCE, "GetStepRange", 0, 1, false, true},
    {0xCF, "SetStepRange", 1, 0, true, true},
    {0xD0, "SetStopMode", 1, 0, true, true},
    {0xD1, "GetStopMode", 0, 1, false, true},
    {0xD2, "SetAutoStopMode", 1, 0, true, true},
    {0xD3, "GetAutoStopMode", 0, 1, false, true},
    {0xD4, "SetBreakpoint", 2, 0, true, true},
    {0xD5, "GetBreakpoint", 1, 1, false, true},
    {0xD6, "SetBreakpointValue", 3, 0, true, true},
    {0xD7, "GetBreakpointValue", 1, 2, false, true},
    {0xD8, "SetCaptureSource", 1, 0, true, true},
    {0xD9, "GetCaptureSource", 0, 1, false, true},
    {0xDA, "SetEncoderSource", 1, 0, true, true},
    {0xDB, "GetEncoderSource", 0, 1, false, true},
    {0xDC, "SetMotorMode", 1, 0, true, true},
    {0xDD, "GetMotorMode", 0, 1, false, true},
    {0xDE, "SetEncoderToStepRatio", 2, 0, true, true},
    {0xDF, "GetEncoderToStepRatio", 0, 2, false, true},
    {0xE0, "SetOutputMode", 1, 0, true, true},
    {0xE1, "GetInterruptAxis", 0, 1, false, true},
    {0xE2, "SetCommutationMode", 1, 0, true, true},
    {0xE3, "GetCommutationMode", 0, 1, false, true},
    {0xE4, "SetPhaseInitializeMode", 1, 0, true, true},
    {0xE5, "GetPhaseInitializeMode", 0, 1, false, true},
    {0xE6, "SetPhasePrescale", 1, 0, true, true},
    {0xE7, "GetPhasePrescale", 0, 1, false, true},
    {0xE8, "SetPhaseCorrectionMode", 1, 0, true, true},
    {0xE9, "GetPhaseCorrectionMode", 0, 1, false, true},
    {0xEA, "GetPhaseCommand", 1, 1, false, true},
    {0xEB, "SetMotionCompleteMode", 1, 0, true, true},
    {0xEC, "GetMotionCompleteMode", 0, 1, false, true},
    {0xED, "SetAxisOutSource", 1, 0, true, true},
    {0xEE, "GetAxisOutSource", 0, 1, false, true},
    {0xEF, "ReadAnalog", 1, 1, false, true},
    {0xF5, "AdjustActualPosition", 2, 0, true, true},
    {0xF8, "GetChecksum", 0, 2, false, true},
};

}  // namespace

const OpcodeInfo* FindOpcode(std::uint8_t opcode) {
  for (const OpcodeInfo& info : kOpcodes) {
    if (info.opcode == opcode) return &info;
  }
  return nullptr;
}

std::span<const OpcodeInfo> AllOpcodes() { return kOpcodes; }

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

Command WithWord(std::uint8_t axis, std::uint8_t opcode, std::uint16_t word) {
  Command c = Simple(axis, opcode);
  c.words[0] = word;
  c.word_count = 1;
  return c;
}

Command WithLong(std::uint8_t axis, std::uint8_t opcode, std::uint32_t value) {
  Command c = Simple(axis, opcode);
  const std::array<std::uint16_t, 2> w = SplitLong(value);
  c.words[0] = w[0];
  c.words[1] = w[1];
  c.word_count = 2;
  return c;
}

Command WithWords(std::uint8_t axis, std::uint8_t opcode, std::span<const std::uint16_t> words) {
  Command c = Simple(axis, opcode);
  c.word_count = static_cast<int>(std::min(words.size(), kMaxArgumentWords));
  std::copy(words.begin(), words.begin() + c.word_count, c.words.begin());
  return c;
}

std::vector<std::uint8_t> Encode(const Command& command) {
  // libPMD PMDSerial::BuildCommandBuffer: address, checksum placeholder, axis, opcode, the
  // words high byte first; then the checksum byte is the negated sum of the others.
  std::vector<std::uint8_t> bytes = {command.address, 0, command.axis, command.opcode};
  const int n = std::clamp(command.word_count, 0, static_cast<int>(kMaxArgumentWords));
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
    case op::kSetActualPosition:
    case op::kAdjustActualPosition:
      return static_cast<std::int32_t>(JoinLong(command.words[0], command.words[1]));
    default:
      break;
  }
  // Other commands: one word as it is, two words as an unsigned long, three words (a word and
  // a long) as their long.
  switch (command.word_count) {
    case 1:
      return command.words[0];
    case 2:
      return JoinLong(command.words[0], command.words[1]);
    case 3:
      return static_cast<std::int32_t>(JoinLong(command.words[1], command.words[2]));
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
    // No opcode of the table: the length is unknown (0 here) and the checksum ends the packet.
    expected_ = info != nullptr ? 4 + 2 * static_cast<std::size_t>(info->argument_words) : 0;
  }
  if (size_ < 4) return false;
  if (expected_ == 0) {
    // An unknown opcode: the packet ends at the first whole word whose sum is 0, at most at the
    // longest packet; so the next packet is framed right whatever the unknown one carried.
    const bool whole = (size_ - 4) % 2 == 0;
    if (!(whole && SumIsZero({buf_.data(), size_})) && size_ < kMaxCommandBytes) return false;
  } else if (size_ < expected_) {
    return false;
  }

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
  expected_ = 0;
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
