#pragma once
/// @file The laser board's binary protocol (drivers/laser_board/PROTOCOL.md): frames
///   [0xA5][LEN][SEQ][CODE][PAYLOAD: LEN bytes][CRC16 hi][CRC16 lo]
/// with CRC-16/CCITT-FALSE over LEN..PAYLOAD; the commands, the ACK/NAK replies and their
/// payloads; and an incremental frame decoder that takes bytes in any split and resynchronises
/// after garbage. Pure functions and one small state machine, used by both the driver
/// (drivers/laser_board/laser_board.h) and the emulator (drivers/emulators/laser_board_emulator.h).
/// Multi-byte fields are big-endian.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <variant>
#include <vector>

namespace hgrasp::drivers {

/// The encoder count latched by the board at one camera frame (the cameras' vertical sync
/// pulse, 25 Hz, goes to the board).
struct FrameLatch {
  std::uint32_t frame = 0;         ///< the board's frame number (VSYNC pulses since power-up)
  std::int32_t encoder_count = 0;  ///< motor angle at the pulse, encoder counts (0: ahead)
  bool laser_on = false;           ///< laser state at the pulse
  bool operator==(const FrameLatch&) const = default;
};

namespace laser_board {

inline constexpr std::uint8_t kStartByte = 0xA5;
/// Longest payload a frame may announce; a larger LEN marks a false start byte.
inline constexpr std::size_t kMaxPayload = 16;
inline constexpr std::size_t kHeaderSize = 4;  ///< start, LEN, SEQ, CODE
inline constexpr std::size_t kCrcSize = 2;
inline constexpr std::size_t kMinFrameSize = kHeaderSize + kCrcSize;
inline constexpr std::size_t kMaxFrameSize = kHeaderSize + kMaxPayload + kCrcSize;
inline constexpr std::uint8_t kProtocolVersion = 1;
/// SEQ 0: an unsequenced request (read-only commands only): always executed, never
/// remembered. The driver uses it to learn the board's last sequence number.
inline constexpr std::uint8_t kUnsequenced = 0;
/// GET_LATCH's frame number that asks for the most recent latch.
inline constexpr std::uint32_t kLatestFrame = 0xFFFFFFFFu;
/// Laser board serial framing: 115200 8N1 (PROTOCOL.md says why).
inline constexpr int kBaud = 115200;

/// Frame codes: commands (host to board) and replies (board to host).
enum class Code : std::uint8_t {
  kGetStatus = 0x01,      ///< status and version
  kSetLaser = 0x10,       ///< laser diode on/off
  kMotorVelocity = 0x11,  ///< run the motor at a signed speed
  kMotorGoTo = 0x12,      ///< move the motor to a count at a speed
  kSetLeds = 0x13,        ///< one gripper's LED mask
  kGetEncoder = 0x20,     ///< the encoder count now
  kGetLatch = 0x21,       ///< the count latched at a camera frame
  kAck = 0x06,            ///< reply: done; payload [command code][data]
  kNak = 0x15,            ///< reply: refused; payload [command code][error]
};

/// NAK error codes.
enum class ErrorCode : std::uint8_t {
  kBadCrc = 0x01,          ///< the frame failed its CRC (SEQ and CODE are as received)
  kUnknownCommand = 0x02,  ///< CODE is not a command
  kBadLength = 0x03,       ///< LEN does not fit the command
  kOutOfRange = 0x04,      ///< a value outside the board's limits
  kNoSuchFrame = 0x05,     ///< GET_LATCH: the frame has aged out of the ring or not happened
  kUnsequenced = 0x06,     ///< a state-changing command with SEQ 0
  kSequenceReused = 0x07,  ///< SEQ equals the last one but the command differs
};

std::string_view ToString(ErrorCode e);

/// CRC-16/CCITT-FALSE (reveng catalogue: CRC-16/IBM-3740; poly 0x1021, init 0xFFFF, no
/// reflection, no xorout; check("123456789") = 0x29B1). `crc` continues a running value.
std::uint16_t Crc16CcittFalse(std::span<const std::uint8_t> bytes, std::uint16_t crc = 0xFFFF);

/// One frame's content, CRC checked.
struct Frame {
  std::uint8_t seq = 0;
  std::uint8_t code = 0;
  std::vector<std::uint8_t> payload;  ///< at most kMaxPayload bytes
  bool operator==(const Frame&) const = default;
};

/// Appends the frame's bytes (start, header, payload, CRC) to *out. Precondition:
/// payload.size() <= kMaxPayload.
void AppendFrame(const Frame& frame, std::vector<std::uint8_t>* out);
std::vector<std::uint8_t> EncodeFrame(const Frame& frame);

/// What the decoder found in the stream.
struct DecodeEvent {
  enum class Kind {
    kFrame,   ///< a frame that passed its CRC
    kBadCrc,  ///< a candidate (start byte, plausible LEN) that failed its CRC
  };
  Kind kind = Kind::kFrame;
  Frame frame;  ///< kBadCrc: seq and code as received (untrusted), payload as received
};

/// Incremental frame decoder. Hunts for the start byte, checks LEN <= kMaxPayload, waits for
/// the whole frame and checks the CRC. After a failed candidate it resumes the hunt at the
/// byte after that candidate's start byte, so a valid frame hidden behind a false start is
/// still found. Bytes may come in any split.
class FrameDecoder {
 public:
  struct Stats {
    std::uint64_t frames = 0;         ///< frames that passed the CRC
    std::uint64_t crc_errors = 0;     ///< candidates that failed it
    std::uint64_t bad_lengths = 0;    ///< start bytes followed by LEN > kMaxPayload
    std::uint64_t skipped_bytes = 0;  ///< bytes dropped while hunting for a start byte
  };

  /// Appends `bytes` to the stream; appends what it completes to *events.
  void Feed(std::span<const std::uint8_t> bytes, std::vector<DecodeEvent>* events);
  /// Gives up the candidate under way (a start byte whose frame has not completed: after an
  /// inter-byte timeout) and rescans the bytes after its start byte.
  void Expire(std::vector<DecodeEvent>* events);
  /// Forgets every buffered byte.
  void Reset();
  /// Whether bytes of an incomplete candidate are buffered.
  bool partial() const { return head_ < buf_.size(); }
  /// Bytes buffered (always < kMaxFrameSize between calls).
  std::size_t buffered() const { return buf_.size() - head_; }
  const Stats& stats() const { return stats_; }

 private:
  void Scan(std::vector<DecodeEvent>* events);

  std::vector<std::uint8_t> buf_;
  std::size_t head_ = 0;  ///< first unconsumed byte of buf_
  Stats stats_;
};

// ----- commands (host to board) -----

struct GetStatus {
  /// Echoed in the reply: tells it from a late answer to an earlier unsequenced request (they
  /// all carry SEQ 0).
  std::uint8_t token = 0;
  bool operator==(const GetStatus&) const = default;
};
struct SetLaser {
  bool on = false;
  bool operator==(const SetLaser&) const = default;
};
struct MotorVelocity {
  std::int32_t counts_s = 0;  ///< signed encoder counts/s; 0 stops
  bool operator==(const MotorVelocity&) const = default;
};
struct MotorGoTo {
  std::int32_t count = 0;            ///< target, encoder counts
  std::uint32_t speed_counts_s = 0;  ///< cruise speed, counts/s, > 0
  bool operator==(const MotorGoTo&) const = default;
};
struct SetLeds {
  std::uint8_t side = 0;   ///< 0 left gripper, 1 right
  std::uint32_t mask = 0;  ///< bit i: LED i on
  bool operator==(const SetLeds&) const = default;
};
struct GetEncoder {
  bool operator==(const GetEncoder&) const = default;
};
struct GetLatch {
  std::uint32_t frame = kLatestFrame;  ///< a frame number, or kLatestFrame
  bool operator==(const GetLatch&) const = default;
};

using Command =
    std::variant<GetStatus, SetLaser, MotorVelocity, MotorGoTo, SetLeds, GetEncoder, GetLatch>;

Code CodeOf(const Command& command);
/// Whether the command changes the board's state (and so must never run twice).
bool ChangesState(const Command& command);
/// The command's payload bytes.
std::vector<std::uint8_t> CommandPayload(const Command& command);
Frame CommandFrame(std::uint8_t seq, const Command& command);
/// Parses a command frame strictly (code, exact LEN, flag values). On failure returns nullopt
/// and sets *error (kUnknownCommand, kBadLength or kOutOfRange).
std::optional<Command> ParseCommand(const Frame& frame, ErrorCode* error);

// ----- replies (board to host) -----

/// An ACK or NAK, as parsed from a frame.
struct Reply {
  std::uint8_t seq = 0;
  bool ack = false;
  std::uint8_t command = 0;        ///< the code of the command answered
  ErrorCode error{};               ///< NAK only
  std::vector<std::uint8_t> data;  ///< ACK only: the command's result
  bool operator==(const Reply&) const = default;
};

Frame AckFrame(std::uint8_t seq, Code command, std::span<const std::uint8_t> data = {});
Frame NakFrame(std::uint8_t seq, std::uint8_t command, ErrorCode error);
/// Parses an ACK/NAK frame strictly: code kAck with a payload of at least the echoed command,
/// or kNak with exactly [command][known error code].
std::optional<Reply> ParseReply(const Frame& frame);
/// The frame a Reply came from (ParseReply's inverse).
Frame ReplyFrame(const Reply& reply);

/// GET_STATUS's ACK data (8 bytes).
struct BoardStatus {
  std::uint8_t token = 0;  ///< the request's token
  std::uint8_t protocol_version = kProtocolVersion;
  std::uint8_t firmware_major = 0, firmware_minor = 0;
  std::uint8_t last_seq = 0;  ///< SEQ of the last sequenced command executed; 0: none yet
  bool laser_on = false;
  bool moving = false;
  std::uint8_t leds_left = 0, leds_right = 0;  ///< LEDs wired per gripper
  bool operator==(const BoardStatus&) const = default;
};
std::vector<std::uint8_t> EncodeStatus(const BoardStatus& status);
std::optional<BoardStatus> ParseStatus(std::span<const std::uint8_t> data);

/// GET_ENCODER's ACK data (9 bytes).
struct EncoderReading {
  std::uint32_t board_time_ms = 0;  ///< board clock, ms since power-up (wraps after 49 days)
  std::int32_t count = 0;           ///< encoder counts, 0 straight ahead
  bool laser_on = false;
  bool moving = false;
  bool operator==(const EncoderReading&) const = default;
};
std::vector<std::uint8_t> EncodeEncoder(const EncoderReading& reading);
std::optional<EncoderReading> ParseEncoder(std::span<const std::uint8_t> data);

/// GET_LATCH's ACK data (9 bytes).
std::vector<std::uint8_t> EncodeLatch(const FrameLatch& latch);
std::optional<FrameLatch> ParseLatch(std::span<const std::uint8_t> data);

}  // namespace laser_board
}  // namespace hgrasp::drivers
