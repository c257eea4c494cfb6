#pragma once
/// @file The Otto Bock SensorHand Speed serial protocol (drivers/sensorhand/PROTOCOL.md):
/// 19200 8N1; every frame is
///   [LEN][PAYLOAD: LEN - 1 bytes][CS]      CS = (LEN + sum of PAYLOAD) mod 256
/// and the hand's data stream ("dump mode") sends frames marked by a leading 0xFF:
///   [0xFF][LEN][DATA: LEN - 1 bytes][CS]   CS = (LEN + sum of DATA) mod 256.
/// Commands used: 0x75 open/close speeds, 0x73 start and 0x7A stop of the data stream; the hand
/// echoes each. A stream frame carries the 9 data bytes a stock hand sends (the source's layout:
/// electrode voltages, battery, state, bracket and pad forces, current; LEN 10) and nothing
/// else: no finger position (the driver estimates it, sensorhand/opening_estimator.h).
///
/// Pure functions and two small incremental decoders (one for each direction) that take bytes
/// in any split and resynchronise after garbage, used by both the driver
/// (drivers/sensorhand/sensorhand_hand.h) and the emulator
/// (drivers/emulators/sensorhand_emulator.h).

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace hgrasp::drivers::sensorhand {

/// Serial framing: 19200 8N1 (source: wiki.ros.org/Robots/sensorhand_speed).
inline constexpr int kBaud = 19200;

/// Command codes (first payload byte).
inline constexpr std::uint8_t kOpSpeed = 0x75;      ///< [0x75][open speed][close speed]
inline constexpr std::uint8_t kOpDumpStart = 0x73;  ///< start the data stream
inline constexpr std::uint8_t kOpDumpStop = 0x7A;   ///< stop the data stream
/// First byte of a data-stream frame (not counted in its checksum).
inline constexpr std::uint8_t kDumpMarker = 0xFF;

/// Speed bytes: 0 = no motion that way; otherwise kSpeedMin (slowest, weakest) to kSpeedMax
/// (fastest, strongest). Source: the ROS driver maps a 0..1 parameter to 0x31..0x85.
inline constexpr std::uint8_t kSpeedMin = 0x31;
inline constexpr std::uint8_t kSpeedMax = 0x85;

/// Data bytes of a stream frame: the 9 of the source (publish_dump reads data[0..8]).
inline constexpr std::size_t kDumpDataBytes = 9;
/// The stream frame's LEN byte (data bytes + the checksum).
inline constexpr std::uint8_t kDumpLen = static_cast<std::uint8_t>(kDumpDataBytes + 1);
/// Whole stream frame: marker, LEN, data, checksum.
inline constexpr std::size_t kDumpFrameBytes = 2 + kDumpDataBytes + 1;
/// Stream period: one frame every 12 ms (source: "every 12 ms").
inline constexpr double kDumpPeriodS = 0.012;

/// The two speed bytes of command 0x75: at most one of them non-zero.
struct SpeedSetting {
  std::uint8_t open = 0;   ///< 0 or kSpeedMin..kSpeedMax
  std::uint8_t close = 0;  ///< 0 or kSpeedMin..kSpeedMax
  bool operator==(const SpeedSetting&) const = default;
  bool stopped() const { return open == 0 && close == 0; }
};

inline constexpr SpeedSetting kStop{};

/// Whether `b` is 0 or within kSpeedMin..kSpeedMax.
bool IsValidSpeedByte(std::uint8_t b);
/// Both bytes valid and not both non-zero.
bool IsValid(const SpeedSetting& s);

/// The hand's motion states as reported in the stream's state byte. The values are OURS: the
/// source names the byte ("state number of the hand's internal state machine", no conversion)
/// but not its values; the emulator sends these and the driver reads them. A real hand's values
/// would have to be found by watching its stream (PROTOCOL.md); unknown values carry no
/// information for the driver.
enum class MotionState : std::uint8_t {
  kIdle = 0,     ///< speeds 0, fingers still
  kOpening = 1,  ///< fingers opening (or told to and not yet found blocked)
  kClosing = 2,  ///< fingers closing (or told to and not yet found blocked)
  kBlocked = 3,  ///< a speed is set but the fingers have not moved for a while (object, end stop)
};

/// One stream sample: one 0xFF frame's 9 data bytes, in the source's layout (hex_serial
/// hand_node, publish_dump), as a stock SensorHand Speed sends them.
struct DumpSample {
  std::uint8_t v_open = 0;              ///< electrode voltage, open channel (0..85 -> 0..1.5 V)
  std::uint8_t v_close = 0;             ///< electrode voltage, close channel (0..85 -> 0..1.5 V)
  std::uint8_t v_bat = 0;               ///< supply voltage (238 -> 8.4 V)
  std::uint8_t state = 0;               ///< the hand's state machine (values: MotionState, ours)
  std::uint8_t f_bracket = 0;           ///< bracket force = grip force (0..110 -> 0..120 N)
  std::array<std::uint8_t, 3> f_pad{};  ///< pad forces (same scale)
  std::uint8_t current = 0;             ///< supply current (0..141 -> 0..1.5 A)
  bool operator==(const DumpSample&) const = default;
};

// --- Units ------------------------------------------------------------------------------------

/// Grip force from a force byte (source scale: 110 -> 120 N).
double ForceN(std::uint8_t raw);
/// Force byte for a force (rounded, clamped to 0..255).
std::uint8_t ForceRaw(double force_n);
/// Supply voltage (source scale: 238 -> 8.4 V) and its byte.
double BatteryV(std::uint8_t raw);
std::uint8_t BatteryRaw(double volts);
/// Supply current (source scale: 141 -> 1.5 A) and its byte.
double CurrentA(std::uint8_t raw);
std::uint8_t CurrentRaw(double amps);

/// Fraction of full speed (and of full grip force) that a speed byte asks for: 0 for 0,
/// (b - 0x30) / (0x85 - 0x30) for kSpeedMin..kSpeedMax (85 steps; our scale, PROTOCOL.md).
double SpeedFraction(std::uint8_t b);
/// The largest speed byte whose fraction is at most `fraction`, but at least kSpeedMin;
/// 0 when fraction <= 0.
std::uint8_t SpeedByteAtMost(double fraction);

// --- Frames -----------------------------------------------------------------------------------

/// Sum of the bytes mod 256 (source: "check sum of all previously sent symbols of the current
/// frame, including the length symbol").
std::uint8_t Checksum(std::span<const std::uint8_t> bytes);

/// [LEN][payload][CS] with LEN = payload size + 1. Precondition: 1 <= payload size <= 254.
std::vector<std::uint8_t> EncodeFrame(std::span<const std::uint8_t> payload);

/// Host to hand: [04][75][open][close][CS]. Precondition: IsValid(s).
std::vector<std::uint8_t> EncodeSpeed(const SpeedSetting& s);
/// Host to hand: [02][73][75]. The hand's echo is the same three bytes.
std::vector<std::uint8_t> EncodeDumpStart();
/// Host to hand: [02][7A][7C]. The hand's echo is the same three bytes.
std::vector<std::uint8_t> EncodeDumpStop();

/// Hand to host: the echo of a 0x75 command, [03][open][close][CS].
std::vector<std::uint8_t> EncodeSpeedEcho(const SpeedSetting& s);
/// Hand to host: a stream frame [FF][0A][9 data bytes][CS].
std::vector<std::uint8_t> EncodeDump(const DumpSample& d);

// --- Decoders ---------------------------------------------------------------------------------

/// A command as the hand receives it.
struct Command {
  enum class Kind : std::uint8_t { kSpeed, kDumpStart, kDumpStop };
  Kind kind = Kind::kSpeed;
  SpeedSetting speed;  ///< kSpeed only
  bool operator==(const Command&) const = default;
};
/// The command's frame bytes.
std::vector<std::uint8_t> Encode(const Command& c);

/// A frame as the host receives it.
struct Reply {
  enum class Kind : std::uint8_t { kSpeedEcho, kDumpStartEcho, kDumpStopEcho, kDump };
  Kind kind = Kind::kDump;
  SpeedSetting speed;  ///< kSpeedEcho only
  DumpSample dump;     ///< kDump only
  bool operator==(const Reply&) const = default;
};
/// The reply's frame bytes.
std::vector<std::uint8_t> Encode(const Reply& r);

/// Incremental decoder. Feed it bytes in any split; it emits every complete frame that passes
/// its checks (length, checksum, command code, speed bytes; a stream frame has only its LEN and
/// checksum to check, as its 9 bytes may take any value) and drops one byte at a time from
/// anything else until it finds the next good frame. The same bytes give the same frames
/// whatever the split.
template <class Item>
class FrameDecoder {
 public:
  /// Appends what `bytes` completes to *out.
  void Push(std::span<const std::uint8_t> bytes, std::vector<Item>* out);
  /// Forgets a partial frame (the emulator does this after a pause in the bytes).
  void Reset();
  /// Bytes held for an incomplete frame.
  std::size_t buffered() const { return buf_.size() - head_; }
  /// Bytes thrown away while resynchronising, since construction.
  std::uint64_t discarded() const { return discarded_; }
  /// Frames emitted since construction.
  std::uint64_t frames() const { return frames_; }

 private:
  std::vector<std::uint8_t> buf_;
  std::size_t head_ = 0;
  std::uint64_t discarded_ = 0, frames_ = 0;
};

/// The hand's side: decodes commands.
using CommandDecoder = FrameDecoder<Command>;
/// The host's side: decodes echoes and stream frames.
using ReplyDecoder = FrameDecoder<Reply>;

extern template class FrameDecoder<Command>;
extern template class FrameDecoder<Reply>;

}  // namespace hgrasp::drivers::sensorhand
