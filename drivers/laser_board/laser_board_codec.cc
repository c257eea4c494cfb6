#include "laser_board/laser_board_codec.h"

#include <algorithm>
#include <type_traits>

#include "common/error.h"

namespace hgrasp::drivers::laser_board {
namespace {

constexpr std::uint8_t kFlagLaserOn = 0x01;
constexpr std::uint8_t kFlagMoving = 0x02;
constexpr std::uint8_t kFlagsKnown = kFlagLaserOn | kFlagMoving;

// Table-driven CRC-16/CCITT-FALSE, MSB first (no reflection).
struct CrcTable {
  std::uint16_t entry[256];
  constexpr CrcTable() : entry{} {
    for (int i = 0; i < 256; ++i) {
      std::uint16_t c = static_cast<std::uint16_t>(i << 8);
      for (int b = 0; b < 8; ++b) {
        c = (c & 0x8000) ? static_cast<std::uint16_t>((c << 1) ^ 0x1021)
                         : static_cast<std::uint16_t>(c << 1);
      }
      entry[i] = c;
    }
  }
};
constexpr CrcTable kCrcTable;

void PutU32(std::uint32_t v, std::vector<std::uint8_t>* out) {
  out->push_back(static_cast<std::uint8_t>(v >> 24));
  out->push_back(static_cast<std::uint8_t>(v >> 16));
  out->push_back(static_cast<std::uint8_t>(v >> 8));
  out->push_back(static_cast<std::uint8_t>(v));
}
void PutI32(std::int32_t v, std::vector<std::uint8_t>* out) {
  PutU32(static_cast<std::uint32_t>(v), out);
}
std::uint32_t GetU32(std::span<const std::uint8_t> b, std::size_t at) {
  return (std::uint32_t{b[at]} << 24) | (std::uint32_t{b[at + 1]} << 16) |
         (std::uint32_t{b[at + 2]} << 8) | std::uint32_t{b[at + 3]};
}
std::int32_t GetI32(std::span<const std::uint8_t> b, std::size_t at) {
  return static_cast<std::int32_t>(GetU32(b, at));  // two's complement (C++20)
}
std::uint8_t Flags(bool laser_on, bool moving) {
  return static_cast<std::uint8_t>((laser_on ? kFlagLaserOn : 0) | (moving ? kFlagMoving : 0));
}
bool KnownErrorCode(std::uint8_t e) {
  return e >= static_cast<std::uint8_t>(ErrorCode::kBadCrc) &&
         e <= static_cast<std::uint8_t>(ErrorCode::kSequenceReused);
}

}  // namespace

std::string_view ToString(ErrorCode e) {
  switch (e) {
    case ErrorCode::kBadCrc:
      return "bad CRC";
    case ErrorCode::kUnknownCommand:
      return "unknown command";
    case ErrorCode::kBadLength:
      return "bad length";
    case ErrorCode::kOutOfRange:
      return "out of range";
    case ErrorCode::kNoSuchFrame:
      return "no such frame";
    case ErrorCode::kUnsequenced:
      return "state-changing command without a sequence number";
    case ErrorCode::kSequenceReused:
      return "sequence number reused for another command";
  }
  return "unknown error";
}

std::uint16_t Crc16CcittFalse(std::span<const std::uint8_t> bytes, std::uint16_t crc) {
  for (const std::uint8_t b : bytes) {
    crc = static_cast<std::uint16_t>((crc << 8) ^ kCrcTable.entry[((crc >> 8) ^ b) & 0xFF]);
  }
  return crc;
}

void AppendFrame(const Frame& frame, std::vector<std::uint8_t>* out) {
  HGRASP_DEMAND(frame.payload.size() <= kMaxPayload);
  const std::size_t at = out->size();
  out->push_back(kStartByte);
  out->push_back(static_cast<std::uint8_t>(frame.payload.size()));
  out->push_back(frame.seq);
  out->push_back(frame.code);
  out->insert(out->end(), frame.payload.begin(), frame.payload.end());
  const std::uint16_t crc =
      Crc16CcittFalse(std::span<const std::uint8_t>(out->data() + at + 1, out->size() - at - 1));
  out->push_back(static_cast<std::uint8_t>(crc >> 8));
  out->push_back(static_cast<std::uint8_t>(crc & 0xFF));
}

std::vector<std::uint8_t> EncodeFrame(const Frame& frame) {
  std::vector<std::uint8_t> out;
  out.reserve(kMinFrameSize + frame.payload.size());
  AppendFrame(frame, &out);
  return out;
}

// ----- FrameDecoder -----

void FrameDecoder::Feed(std::span<const std::uint8_t> bytes, std::vector<DecodeEvent>* events) {
  buf_.insert(buf_.end(), bytes.begin(), bytes.end());
  Scan(events);
}

void FrameDecoder::Expire(std::vector<DecodeEvent>* events) {
  if (!partial()) return;
  // Scan() leaves the buffer starting at the candidate's start byte.
  ++head_;
  Scan(events);
}

void FrameDecoder::Reset() {
  buf_.clear();
  head_ = 0;
}

void FrameDecoder::Scan(std::vector<DecodeEvent>* events) {
  const std::size_t size = buf_.size();
  while (head_ < size) {
    // Hunt for the start byte.
    const auto start =
        std::find(buf_.begin() + static_cast<std::ptrdiff_t>(head_), buf_.end(), kStartByte);
    const std::size_t at = static_cast<std::size_t>(start - buf_.begin());
    stats_.skipped_bytes += at - head_;
    head_ = at;
    if (head_ >= size || size - head_ < 2) break;  // no start byte, or no LEN yet
    const std::size_t len = buf_[head_ + 1];
    if (len > kMaxPayload) {  // a false start: hunt on from the next byte
      ++stats_.bad_lengths;
      ++head_;
      continue;
    }
    const std::size_t total = kMinFrameSize + len;
    if (size - head_ < total) break;  // wait for the rest
    const std::span<const std::uint8_t> covered(buf_.data() + head_ + 1, kHeaderSize - 1 + len);
    const std::uint16_t got = static_cast<std::uint16_t>((buf_[head_ + kHeaderSize + len] << 8) |
                                                         buf_[head_ + kHeaderSize + len + 1]);
    DecodeEvent e;
    e.frame.seq = buf_[head_ + 2];
    e.frame.code = buf_[head_ + 3];
    e.frame.payload.assign(buf_.begin() + static_cast<std::ptrdiff_t>(head_ + kHeaderSize),
                           buf_.begin() + static_cast<std::ptrdiff_t>(head_ + kHeaderSize + len));
    if (Crc16CcittFalse(covered) == got) {
      e.kind = DecodeEvent::Kind::kFrame;
      ++stats_.frames;
      head_ += total;
    } else {
      // Not a frame (or a damaged one): a real frame may start inside it.
      e.kind = DecodeEvent::Kind::kBadCrc;
      ++stats_.crc_errors;
      ++head_;
    }
    events->push_back(std::move(e));
  }
  // Keep only the unconsumed tail (at most one incomplete candidate, < kMaxFrameSize bytes).
  buf_.erase(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(head_));
  head_ = 0;
}

// ----- commands -----

Code CodeOf(const Command& command) {
  return std::visit(
      [](const auto& c) -> Code {
        using T = std::decay_t<decltype(c)>;
        if constexpr (std::is_same_v<T, GetStatus>) return Code::kGetStatus;
        if constexpr (std::is_same_v<T, SetLaser>) return Code::kSetLaser;
        if constexpr (std::is_same_v<T, MotorVelocity>) return Code::kMotorVelocity;
        if constexpr (std::is_same_v<T, MotorGoTo>) return Code::kMotorGoTo;
        if constexpr (std::is_same_v<T, SetLeds>) return Code::kSetLeds;
        if constexpr (std::is_same_v<T, GetEncoder>) return Code::kGetEncoder;
        if constexpr (std::is_same_v<T, GetLatch>) return Code::kGetLatch;
      },
      command);
}

bool ChangesState(const Command& command) {
  return std::holds_alternative<SetLaser>(command) ||
         std::holds_alternative<MotorVelocity>(command) ||
         std::holds_alternative<MotorGoTo>(command) || std::holds_alternative<SetLeds>(command);
}

std::vector<std::uint8_t> CommandPayload(const Command& command) {
  std::vector<std::uint8_t> p;
  std::visit(
      [&p](const auto& c) {
        using T = std::decay_t<decltype(c)>;
        if constexpr (std::is_same_v<T, GetStatus>) {
          p.push_back(c.token);
        } else if constexpr (std::is_same_v<T, SetLaser>) {
          p.push_back(c.on ? 1 : 0);
        } else if constexpr (std::is_same_v<T, MotorVelocity>) {
          PutI32(c.counts_s, &p);
        } else if constexpr (std::is_same_v<T, MotorGoTo>) {
          PutI32(c.count, &p);
          PutU32(c.speed_counts_s, &p);
        } else if constexpr (std::is_same_v<T, SetLeds>) {
          p.push_back(c.side);
          PutU32(c.mask, &p);
        } else if constexpr (std::is_same_v<T, GetLatch>) {
          PutU32(c.frame, &p);
        }
      },
      command);
  return p;
}

Frame CommandFrame(std::uint8_t seq, const Command& command) {
  return Frame{seq, static_cast<std::uint8_t>(CodeOf(command)), CommandPayload(command)};
}

std::optional<Command> ParseCommand(const Frame& frame, ErrorCode* error) {
  const auto& p = frame.payload;
  auto need = [&](std::size_t n) {
    if (p.size() == n) return true;
    *error = ErrorCode::kBadLength;
    return false;
  };
  switch (static_cast<Code>(frame.code)) {
    case Code::kGetStatus:
      if (!need(1)) return std::nullopt;
      return GetStatus{p[0]};
    case Code::kSetLaser:
      if (!need(1)) return std::nullopt;
      if (p[0] > 1) {
        *error = ErrorCode::kOutOfRange;
        return std::nullopt;
      }
      return SetLaser{p[0] == 1};
    case Code::kMotorVelocity:
      if (!need(4)) return std::nullopt;
      return MotorVelocity{GetI32(p, 0)};
    case Code::kMotorGoTo:
      if (!need(8)) return std::nullopt;
      return MotorGoTo{GetI32(p, 0), GetU32(p, 4)};
    case Code::kSetLeds:
      if (!need(5)) return std::nullopt;
      return SetLeds{p[0], GetU32(p, 1)};
    case Code::kGetEncoder:
      if (!need(0)) return std::nullopt;
      return GetEncoder{};
    case Code::kGetLatch:
      if (!need(4)) return std::nullopt;
      return GetLatch{GetU32(p, 0)};
    default:
      break;
  }
  *error = ErrorCode::kUnknownCommand;
  return std::nullopt;
}

// ----- replies -----

Frame AckFrame(std::uint8_t seq, Code command, std::span<const std::uint8_t> data) {
  Frame f{seq, static_cast<std::uint8_t>(Code::kAck), {}};
  f.payload.resize(1 + data.size());
  f.payload[0] = static_cast<std::uint8_t>(command);
  std::copy(data.begin(), data.end(), f.payload.begin() + 1);
  return f;
}

Frame NakFrame(std::uint8_t seq, std::uint8_t command, ErrorCode error) {
  return Frame{
      seq, static_cast<std::uint8_t>(Code::kNak), {command, static_cast<std::uint8_t>(error)}};
}

std::optional<Reply> ParseReply(const Frame& frame) {
  Reply r;
  r.seq = frame.seq;
  if (frame.code == static_cast<std::uint8_t>(Code::kAck)) {
    if (frame.payload.empty()) return std::nullopt;
    r.ack = true;
    r.command = frame.payload[0];
    r.data.assign(frame.payload.begin() + 1, frame.payload.end());
    return r;
  }
  if (frame.code == static_cast<std::uint8_t>(Code::kNak)) {
    if (frame.payload.size() != 2 || !KnownErrorCode(frame.payload[1])) return std::nullopt;
    r.ack = false;
    r.command = frame.payload[0];
    r.error = static_cast<ErrorCode>(frame.payload[1]);
    return r;
  }
  return std::nullopt;
}

Frame ReplyFrame(const Reply& reply) {
  if (reply.ack) return AckFrame(reply.seq, static_cast<Code>(reply.command), reply.data);
  return NakFrame(reply.seq, reply.command, reply.error);
}

std::vector<std::uint8_t> EncodeStatus(const BoardStatus& s) {
  return {s.token,    s.protocol_version,          s.firmware_major, s.firmware_minor,
          s.last_seq, Flags(s.laser_on, s.moving), s.leds_left,      s.leds_right};
}

std::optional<BoardStatus> ParseStatus(std::span<const std::uint8_t> d) {
  if (d.size() != 8 || (d[5] & ~kFlagsKnown) != 0) return std::nullopt;
  BoardStatus s;
  s.token = d[0];
  s.protocol_version = d[1];
  s.firmware_major = d[2];
  s.firmware_minor = d[3];
  s.last_seq = d[4];
  s.laser_on = (d[5] & kFlagLaserOn) != 0;
  s.moving = (d[5] & kFlagMoving) != 0;
  s.leds_left = d[6];
  s.leds_right = d[7];
  return s;
}

std::vector<std::uint8_t> EncodeEncoder(const EncoderReading& r) {
  std::vector<std::uint8_t> d;
  PutU32(r.board_time_ms, &d);
  PutI32(r.count, &d);
  d.push_back(Flags(r.laser_on, r.moving));
  return d;
}

std::optional<EncoderReading> ParseEncoder(std::span<const std::uint8_t> d) {
  if (d.size() != 9 || (d[8] & ~kFlagsKnown) != 0) return std::nullopt;
  return EncoderReading{GetU32(d, 0), GetI32(d, 4), (d[8] & kFlagLaserOn) != 0,
                        (d[8] & kFlagMoving) != 0};
}

std::vector<std::uint8_t> EncodeLatch(const FrameLatch& l) {
  std::vector<std::uint8_t> d;
  PutU32(l.frame, &d);
  PutI32(l.encoder_count, &d);
  d.push_back(Flags(l.laser_on, false));
  return d;
}

std::optional<FrameLatch> ParseLatch(std::span<const std::uint8_t> d) {
  if (d.size() != 9 || (d[8] & ~kFlagLaserOn) != 0) return std::nullopt;
  return FrameLatch{GetU32(d, 0), GetI32(d, 4), (d[8] & kFlagLaserOn) != 0};
}

}  // namespace hgrasp::drivers::laser_board
