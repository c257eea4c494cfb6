#include "sensorhand/sensorhand_codec.h"

#include <algorithm>
#include <cmath>

namespace hgrasp::drivers::sensorhand {
namespace {

constexpr double kForceFullN = 120.0;  // source: force byte 110 -> 120 N
constexpr double kForceFullRaw = 110.0;
constexpr double kBatteryFullV = 8.4;  // source: 238 -> 8.4 V
constexpr double kBatteryFullRaw = 238.0;
constexpr double kCurrentFullA = 1.5;  // source: 141 -> 1.5 A
constexpr double kCurrentFullRaw = 141.0;
constexpr double kSpeedSteps = kSpeedMax - (kSpeedMin - 1);  // 85

std::uint8_t ClampByte(double v) {
  if (!(v > 0.0)) return 0;  // also NaN
  return static_cast<std::uint8_t>(std::min(255.0, std::round(v)));
}

enum class Parse { kNeedMore, kBad, kGood };

bool ChecksumOk(const std::uint8_t* frame, std::size_t len_and_payload, std::uint8_t cs) {
  return Checksum(std::span<const std::uint8_t>(frame, len_and_payload)) == cs;
}

// Commands: [02][73|7A][CS] or [04][75][open][close][CS].
Parse TryParse(const std::uint8_t* p, std::size_t n, std::size_t* used, Command* out) {
  if (p[0] == 2) {
    if (n < 3) return Parse::kNeedMore;
    if (p[1] != kOpDumpStart && p[1] != kOpDumpStop) return Parse::kBad;
    if (!ChecksumOk(p, 2, p[2])) return Parse::kBad;
    out->kind = p[1] == kOpDumpStart ? Command::Kind::kDumpStart : Command::Kind::kDumpStop;
    out->speed = {};
    *used = 3;
    return Parse::kGood;
  }
  if (p[0] == 4) {
    if (n < 5) return Parse::kNeedMore;
    const SpeedSetting s{p[2], p[3]};
    if (p[1] != kOpSpeed || !IsValid(s) || !ChecksumOk(p, 4, p[4])) return Parse::kBad;
    out->kind = Command::Kind::kSpeed;
    out->speed = s;
    *used = 5;
    return Parse::kGood;
  }
  return Parse::kBad;
}

// Replies: [02][73|7A][CS], [03][open][close][CS], [FF][LEN][data][CS].
Parse TryParse(const std::uint8_t* p, std::size_t n, std::size_t* used, Reply* out) {
  if (p[0] == kDumpMarker) {
    if (n < 2) return Parse::kNeedMore;
    if (p[1] != kDumpLen) return Parse::kBad;
    if (n < kDumpFrameBytes) return Parse::kNeedMore;
    if (!ChecksumOk(p + 1, 1 + kDumpDataBytes, p[kDumpFrameBytes - 1])) return Parse::kBad;
    const std::uint8_t* d = p + 2;
    DumpSample s;
    s.v_open = d[0];
    s.v_close = d[1];
    s.v_bat = d[2];
    s.state = d[3];
    s.f_bracket = d[4];
    s.f_pad = {d[5], d[6], d[7]};
    s.current = d[8];
    // Every data byte may take any value on a stock hand (its state values are not published),
    // so LEN and the checksum are the only checks.
    out->kind = Reply::Kind::kDump;
    out->speed = {};
    out->dump = s;
    *used = kDumpFrameBytes;
    return Parse::kGood;
  }
  if (p[0] == 2) {
    if (n < 3) return Parse::kNeedMore;
    if (p[1] != kOpDumpStart && p[1] != kOpDumpStop) return Parse::kBad;
    if (!ChecksumOk(p, 2, p[2])) return Parse::kBad;
    out->kind = p[1] == kOpDumpStart ? Reply::Kind::kDumpStartEcho : Reply::Kind::kDumpStopEcho;
    out->speed = {};
    out->dump = {};
    *used = 3;
    return Parse::kGood;
  }
  if (p[0] == 3) {
    if (n < 4) return Parse::kNeedMore;
    const SpeedSetting s{p[1], p[2]};
    if (!IsValid(s) || !ChecksumOk(p, 3, p[3])) return Parse::kBad;
    out->kind = Reply::Kind::kSpeedEcho;
    out->speed = s;
    out->dump = {};
    *used = 4;
    return Parse::kGood;
  }
  return Parse::kBad;
}

}  // namespace

bool IsValidSpeedByte(std::uint8_t b) { return b == 0 || (b >= kSpeedMin && b <= kSpeedMax); }

bool IsValid(const SpeedSetting& s) {
  return IsValidSpeedByte(s.open) && IsValidSpeedByte(s.close) && (s.open == 0 || s.close == 0);
}

double ForceN(std::uint8_t raw) { return raw * (kForceFullN / kForceFullRaw); }
std::uint8_t ForceRaw(double force_n) { return ClampByte(force_n * (kForceFullRaw / kForceFullN)); }

double BatteryV(std::uint8_t raw) { return raw * (kBatteryFullV / kBatteryFullRaw); }
std::uint8_t BatteryRaw(double volts) {
  return ClampByte(volts * (kBatteryFullRaw / kBatteryFullV));
}

double CurrentA(std::uint8_t raw) { return raw * (kCurrentFullA / kCurrentFullRaw); }
std::uint8_t CurrentRaw(double amps) { return ClampByte(amps * (kCurrentFullRaw / kCurrentFullA)); }

double SpeedFraction(std::uint8_t b) {
  if (b == 0) return 0.0;
  const int steps = std::clamp<int>(b, kSpeedMin, kSpeedMax) - (kSpeedMin - 1);
  return steps / kSpeedSteps;
}

std::uint8_t SpeedByteAtMost(double fraction) {
  if (!(fraction > 0.0)) return 0;
  const double steps = std::floor(std::min(fraction, 1.0) * kSpeedSteps + 1e-9);
  return static_cast<std::uint8_t>(
      std::clamp<int>(static_cast<int>(steps) + (kSpeedMin - 1), kSpeedMin, kSpeedMax));
}

std::uint8_t Checksum(std::span<const std::uint8_t> bytes) {
  unsigned sum = 0;
  for (std::uint8_t b : bytes) sum += b;
  return static_cast<std::uint8_t>(sum & 0xFF);
}

std::vector<std::uint8_t> EncodeFrame(std::span<const std::uint8_t> payload) {
  std::vector<std::uint8_t> f;
  f.reserve(payload.size() + 2);
  f.push_back(static_cast<std::uint8_t>(payload.size() + 1));
  f.insert(f.end(), payload.begin(), payload.end());
  f.push_back(Checksum(f));
  return f;
}

std::vector<std::uint8_t> EncodeSpeed(const SpeedSetting& s) {
  const std::uint8_t payload[] = {kOpSpeed, s.open, s.close};
  return EncodeFrame(payload);
}

std::vector<std::uint8_t> EncodeDumpStart() {
  const std::uint8_t payload[] = {kOpDumpStart};
  return EncodeFrame(payload);
}

std::vector<std::uint8_t> EncodeDumpStop() {
  const std::uint8_t payload[] = {kOpDumpStop};
  return EncodeFrame(payload);
}

std::vector<std::uint8_t> EncodeSpeedEcho(const SpeedSetting& s) {
  const std::uint8_t payload[] = {s.open, s.close};
  return EncodeFrame(payload);
}

std::vector<std::uint8_t> EncodeDump(const DumpSample& d) {
  const std::uint8_t data[kDumpDataBytes] = {
      d.v_open,
      d.v_close,
      d.v_bat,
      d.state,
      d.f_bracket,
      d.f_pad[0],
      d.f_pad[1],
      d.f_pad[2],
      d.current,
  };
  std::vector<std::uint8_t> f = EncodeFrame(data);  // [LEN][data][CS], CS over LEN + data
  f.insert(f.begin(), kDumpMarker);
  return f;
}

std::vector<std::uint8_t> Encode(const Command& c) {
  switch (c.kind) {
    case Command::Kind::kSpeed:
      return EncodeSpeed(c.speed);
    case Command::Kind::kDumpStart:
      return EncodeDumpStart();
    case Command::Kind::kDumpStop:
      return EncodeDumpStop();
  }
  return {};
}

std::vector<std::uint8_t> Encode(const Reply& r) {
  switch (r.kind) {
    case Reply::Kind::kSpeedEcho:
      return EncodeSpeedEcho(r.speed);
    case Reply::Kind::kDumpStartEcho:
      return EncodeDumpStart();
    case Reply::Kind::kDumpStopEcho:
      return EncodeDumpStop();
    case Reply::Kind::kDump:
      return EncodeDump(r.dump);
  }
  return {};
}

template <class Item>
void FrameDecoder<Item>::Push(std::span<const std::uint8_t> bytes, std::vector<Item>* out) {
  buf_.insert(buf_.end(), bytes.begin(), bytes.end());
  while (head_ < buf_.size()) {
    std::size_t used = 0;
    Item item{};
    const Parse r = TryParse(buf_.data() + head_, buf_.size() - head_, &used, &item);
    if (r == Parse::kNeedMore) break;
    if (r == Parse::kGood) {
      out->push_back(item);
      head_ += used;
      ++frames_;
    } else {
      // Not a frame here: resynchronise one byte further on.
      ++head_;
      ++discarded_;
    }
  }
  if (head_ == buf_.size()) {
    buf_.clear();
    head_ = 0;
  } else if (head_ > 4096) {
    buf_.erase(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(head_));
    head_ = 0;
  }
}

template <class Item>
void FrameDecoder<Item>::Reset() {
  discarded_ += buf_.size() - head_;
  buf_.clear();
  head_ = 0;
}

template class FrameDecoder<Command>;
template class FrameDecoder<Reply>;

}  // namespace hgrasp::drivers::sensorhand
