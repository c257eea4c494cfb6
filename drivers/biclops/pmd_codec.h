#pragma once
/// @file The PMD motion-chip serial protocol (Navigator / Pilot / Magellan, point-to-point mode)
/// as the TRACLabs Biclops library speaks it: packets, checksums, replies, the opcodes the
/// Biclops library sends, and incremental decoders for both directions. Pure functions and small
/// state machines; no I/O. drivers/biclops/PROTOCOL.md gives the layouts and their sources.
///
/// Host -> chip packet:  [address][checksum][axis][opcode][word 1 hi][word 1 lo]...
/// Chip -> host reply:   [status][checksum][word 1 hi][word 1 lo]...   (status 0)
///                       [status][checksum]                              (status != 0)
/// Every packet's bytes sum to 0 modulo 256. 32-bit values travel as two words, high word first.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace hgrasp::drivers::pmd {

/// Opcodes named in code here, with the values of libPMD's PMDOPCodes.h ("Navigator command code
/// declarations", Performance Motion Devices). FindOpcode knows every opcode of that file whose
/// argument and result words libPMD's PMD.cpp gives (PROTOCOL.md has the whole table).
namespace op {
inline constexpr std::uint8_t kNoOperation = 0x00;
inline constexpr std::uint8_t kSetMotorType = 0x02;  ///< Magellan only
inline constexpr std::uint8_t kGetMotorType = 0x03;  ///< Magellan only
inline constexpr std::uint8_t kSetMotorLimit = 0x06;
inline constexpr std::uint8_t kSetMotorBias = 0x0F;
inline constexpr std::uint8_t kSetPosition = 0x10;
inline constexpr std::uint8_t kSetVelocity = 0x11;
inline constexpr std::uint8_t kSetJerk = 0x13;
inline constexpr std::uint8_t kUpdate = 0x1A;
inline constexpr std::uint8_t kGetCommandedPosition = 0x1D;
inline constexpr std::uint8_t kGetCommandedVelocity = 0x1E;
inline constexpr std::uint8_t kSetKp = 0x25;
inline constexpr std::uint8_t kSetKi = 0x26;
inline constexpr std::uint8_t kSetKd = 0x27;
inline constexpr std::uint8_t kSetKvff = 0x2B;
inline constexpr std::uint8_t kRestoreOperatingMode = 0x2E;  ///< Magellan only
inline constexpr std::uint8_t kGetEventStatus = 0x31;
inline constexpr std::uint8_t kResetEventStatus = 0x34;
inline constexpr std::uint8_t kGetCaptureValue = 0x36;
inline constexpr std::uint8_t kGetActualPosition = 0x37;
inline constexpr std::uint8_t kReset = 0x39;
inline constexpr std::uint8_t kClearPositionError = 0x47;
inline constexpr std::uint8_t kSetEventAction = 0x48;  ///< Magellan only
inline constexpr std::uint8_t kGetEventAction = 0x49;  ///< Magellan only
inline constexpr std::uint8_t kGetPosition = 0x4A;
inline constexpr std::uint8_t kGetVelocity = 0x4B;
inline constexpr std::uint8_t kGetAcceleration = 0x4C;
inline constexpr std::uint8_t kSetActualPosition = 0x4D;
inline constexpr std::uint8_t kMultiUpdate = 0x5B;
inline constexpr std::uint8_t kGetSampleTime = 0x61;
inline constexpr std::uint8_t kSetOperatingMode = 0x65;  ///< Magellan only
inline constexpr std::uint8_t kGetOperatingMode = 0x66;  ///< Magellan only
inline constexpr std::uint8_t kSetLimitSwitchMode = 0x80;
inline constexpr std::uint8_t kWriteIO = 0x82;
inline constexpr std::uint8_t kReadIO = 0x83;
inline constexpr std::uint8_t kSetAxisMode = 0x87;
inline constexpr std::uint8_t kGetVersion = 0x8F;
inline constexpr std::uint8_t kSetAcceleration = 0x90;
inline constexpr std::uint8_t kSetDeceleration = 0x91;
inline constexpr std::uint8_t kSetKaff = 0x93;
inline constexpr std::uint8_t kSetIntegrationLimit = 0x95;
inline constexpr std::uint8_t kSetPositionErrorLimit = 0x97;
inline constexpr std::uint8_t kGetPositionErrorLimit = 0x98;
inline constexpr std::uint8_t kSetKout = 0x9E;
inline constexpr std::uint8_t kSetProfileMode = 0xA0;
inline constexpr std::uint8_t kGetProfileMode = 0xA1;
inline constexpr std::uint8_t kSetSignalSense = 0xA2;
inline constexpr std::uint8_t kGetSignalSense = 0xA3;
inline constexpr std::uint8_t kGetSignalStatus = 0xA4;
inline constexpr std::uint8_t kGetHostIOError = 0xA5;
inline constexpr std::uint8_t kGetActivityStatus = 0xA6;
inline constexpr std::uint8_t kSetBufferStart = 0xC0;
inline constexpr std::uint8_t kSetBufferLength = 0xC2;
inline constexpr std::uint8_t kWriteBuffer = 0xC8;
inline constexpr std::uint8_t kReadBuffer = 0xC9;
inline constexpr std::uint8_t kSetStopMode = 0xD0;
inline constexpr std::uint8_t kGetStopMode = 0xD1;
inline constexpr std::uint8_t kSetAutoStopMode = 0xD2;
inline constexpr std::uint8_t kSetBreakpoint = 0xD4;
inline constexpr std::uint8_t kGetBreakpoint = 0xD5;
inline constexpr std::uint8_t kSetBreakpointValue = 0xD6;
inline constexpr std::uint8_t kGetBreakpointValue = 0xD7;
inline constexpr std::uint8_t kSetCaptureSource = 0xD8;
inline constexpr std::uint8_t kGetCaptureSource = 0xD9;
inline constexpr std::uint8_t kSetMotorMode = 0xDC;
inline constexpr std::uint8_t kGetMotorMode = 0xDD;
inline constexpr std::uint8_t kSetOutputMode = 0xE0;
inline constexpr std::uint8_t kSetAxisOutSource = 0xED;
inline constexpr std::uint8_t kAdjustActualPosition = 0xF5;
}  // namespace op

/// What the protocol says about one opcode.
struct OpcodeInfo {
  std::uint8_t opcode;
  std::string_view name;
  int argument_words;  ///< 16-bit words the host sends after the opcode (0..3)
  int result_words;    ///< 16-bit words the chip returns with status 0 (0..2)
  /// A Set*, Update, Reset or a command with a side effect (GetCaptureValue re-arms the
  /// capture, ReadBuffer moves the read index): logged by the emulator when executed.
  bool changes_state;
  bool replies;  ///< false for Reset only: the chip answers nothing
};

/// Every opcode of the Navigator command set whose word counts libPMD gives (PROTOCOL.md), or
/// nullptr for any other byte.
const OpcodeInfo* FindOpcode(std::uint8_t opcode);
/// The whole table, in opcode order.
std::span<const OpcodeInfo> AllOpcodes();

/// Chip status codes (first reply byte), libPMD PMDErrorCodes.h ("MC2xxx Chipset error codes").
namespace status {
inline constexpr std::uint8_t kOk = 0x00;
inline constexpr std::uint8_t kChipsetReset = 0x01;
inline constexpr std::uint8_t kInvalidInstruction = 0x02;
inline constexpr std::uint8_t kInvalidAxis = 0x03;
inline constexpr std::uint8_t kInvalidParameter = 0x04;
inline constexpr std::uint8_t kBadSerialChecksum = 0x09;
inline constexpr std::uint8_t kInvalidNegativeValue = 0x0B;
}  // namespace status

/// True for the statuses after which C-Motion's PMDSerial_Send resynchronises (the packet may
/// have been misframed, so it was certainly not executed as sent).
bool StatusNeedsResync(std::uint8_t chip_status);

/// Activity status bits (GetActivityStatus), libPMD PMDTypes.h.
namespace activity {
inline constexpr std::uint16_t kAtMaximumVelocity = 0x0002;
inline constexpr std::uint16_t kProfileModeMask = 0x0038;  ///< active profile mode << 3
inline constexpr std::uint16_t kAxisSettled = 0x0080;
inline constexpr std::uint16_t kMotorOn = 0x0100;
inline constexpr std::uint16_t kInMotion = 0x0400;  ///< the trajectory generator is moving
inline constexpr std::uint16_t kInPositiveLimit = 0x0800;
inline constexpr std::uint16_t kInNegativeLimit = 0x1000;
}  // namespace activity

/// Event status bits (GetEventStatus, ResetEventStatus), libPMD PMDTypes.h. Latched: set by the
/// chip, cleared only by ResetEventStatus (the bits that are 0 in its mask).
namespace event {
inline constexpr std::uint16_t kMotionComplete = 0x0001;
inline constexpr std::uint16_t kBreakpoint1 = 0x0004;
inline constexpr std::uint16_t kCaptureReceived = 0x0008;
inline constexpr std::uint16_t kMotionError = 0x0010;
inline constexpr std::uint16_t kInPositiveLimit = 0x0020;
inline constexpr std::uint16_t kInNegativeLimit = 0x0040;
inline constexpr std::uint16_t kInstructionError = 0x0080;
inline constexpr std::uint16_t kBreakpoint2 = 0x4000;
}  // namespace event

/// Signal status / signal sense bits (GetSignalStatus, Set/GetSignalSense), libPMD PMDTypes.h.
/// A status bit is the input's level XOR its sense bit. The limit inputs are active low: a
/// status bit of 0 means the limit switch is asserted (libPMD PMDAxisHoming.cpp).
namespace signal {
inline constexpr std::uint16_t kEncoderA = 0x0001;
inline constexpr std::uint16_t kEncoderB = 0x0002;
inline constexpr std::uint16_t kEncoderIndex = 0x0004;
inline constexpr std::uint16_t kHome = 0x0008;
inline constexpr std::uint16_t kPositiveLimit = 0x0010;
inline constexpr std::uint16_t kNegativeLimit = 0x0020;
inline constexpr std::uint16_t kAxisIn = 0x0040;
inline constexpr std::uint16_t kAxisOut = 0x0400;
inline constexpr std::uint16_t kMotorDirection = 0x1000;
inline constexpr std::uint16_t kStatusMask = 0x07FF;
}  // namespace signal

/// Capture sources (SetCaptureSource), libPMD PMDTypes.h tagPMDCaptureSource.
inline constexpr std::uint16_t kCaptureIndex = 0;
inline constexpr std::uint16_t kCaptureHome = 1;
/// Breakpoint actions and triggers (SetBreakpoint's second word: axis | action << 4 |
/// trigger << 8), libPMD PMDTypes.h.
inline constexpr std::uint16_t kBreakpointNoAction = 0;
inline constexpr std::uint16_t kBreakpointAbruptStop = 2;
inline constexpr std::uint16_t kBreakpointSmoothStop = 3;
inline constexpr std::uint16_t kBreakpointMotorOff = 4;
inline constexpr std::uint16_t kBreakpointDisable = 0;
inline constexpr std::uint16_t kBreakpointEventStatus = 8;
/// Stop modes (SetStopMode, executed by the next Update), libPMD PMDTypes.h tagPMDStopMode.
inline constexpr std::uint16_t kNoStop = 0;
inline constexpr std::uint16_t kAbruptStop = 1;
inline constexpr std::uint16_t kSmoothStop = 2;
/// Motor modes (SetMotorMode) and output modes (SetOutputMode), libPMD PMDTypes.h.
inline constexpr std::uint16_t kMotorOff = 0;
inline constexpr std::uint16_t kMotorOn = 1;
inline constexpr std::uint16_t kOutputPwmSignMagnitude = 1;

/// Profile modes (SetProfileMode), libPMD PMDTypes.h tagPMDProfileMode.
inline constexpr std::uint16_t kTrapezoidalProfile = 0;

/// Velocity and acceleration registers are fixed point with 16 fraction bits: counts per cycle
/// * 2^16 and counts per cycle^2 * 2^16 (libPMD PMDVelScaling, PMDAccScaling).
inline constexpr double kVelocityScale = 65536.0;
inline constexpr double kAccelerationScale = 65536.0;

/// The point-to-point address byte (libPMD's default multidrop ID 0).
inline constexpr std::uint8_t kPointToPointAddress = 0x00;

/// Longest packet: 4 header bytes + 3 words (a word and a long: SetBreakpointValue, the buffer
/// commands).
inline constexpr std::size_t kMaxArgumentWords = 3;
inline constexpr std::size_t kMaxCommandBytes = 4 + 2 * kMaxArgumentWords;
/// Longest reply: 2 header bytes + 2 words.
inline constexpr std::size_t kMaxReplyBytes = 6;

/// One host -> chip packet.
struct Command {
  std::uint8_t address = kPointToPointAddress;
  std::uint8_t axis = 0;    ///< 0..3 (Biclops: pan 0, tilt 1, verge 2)
  std::uint8_t opcode = 0;  ///< any byte (decoded packets may carry unknown opcodes)
  std::array<std::uint16_t, kMaxArgumentWords> words{};
  int word_count = 0;  ///< 0..3

  bool operator==(const Command&) const = default;
};

/// One chip -> host reply.
struct Reply {
  std::uint8_t status = status::kOk;
  std::array<std::uint16_t, 2> words{};
  int word_count = 0;  ///< 0 whenever status != 0

  bool operator==(const Reply&) const = default;
};

/// The byte that makes the sum of `bytes` plus itself 0 modulo 256.
std::uint8_t ChecksumFor(std::span<const std::uint8_t> bytes);
/// True when the bytes sum to 0 modulo 256.
bool SumIsZero(std::span<const std::uint8_t> bytes);

/// A 32-bit value as two words, high word first; and back (two's complement).
std::array<std::uint16_t, 2> SplitLong(std::uint32_t value);
std::uint32_t JoinLong(std::uint16_t high, std::uint16_t low);

/// Packet builders (argument word counts per the opcode table).
Command NoOperation();
Command Reset();  ///< axis 0: "for the reset command, the axis number MUST be zero" (libPMD)
Command SetPosition(std::uint8_t axis, std::int32_t position_counts);
Command SetVelocity(std::uint8_t axis, std::int32_t velocity_reg);
Command SetAcceleration(std::uint8_t axis, std::uint32_t acceleration_reg);
Command SetProfileMode(std::uint8_t axis, std::uint16_t mode);
Command Update(std::uint8_t axis);
/// A command without arguments (a Get*).
Command Simple(std::uint8_t axis, std::uint8_t opcode);
/// A command with one word argument (Set* of a word register, ResetEventStatus, MultiUpdate).
Command WithWord(std::uint8_t axis, std::uint8_t opcode, std::uint16_t word);
/// A command with one long argument (two words, high first).
Command WithLong(std::uint8_t axis, std::uint8_t opcode, std::uint32_t value);
/// A command with the given words (their number is the argument count).
Command WithWords(std::uint8_t axis, std::uint8_t opcode, std::span<const std::uint16_t> words);

/// The packet's bytes: address, checksum, axis, opcode, words high byte first.
std::vector<std::uint8_t> Encode(const Command& command);
/// The reply's bytes: status, checksum, then the words only when status is 0.
std::vector<std::uint8_t> Encode(const Reply& reply);

/// The value a Set* command carries, sign-extended (SetPosition/SetVelocity are signed 32-bit,
/// SetAcceleration unsigned 32-bit, SetProfileMode one word); 0 for commands without data.
std::int64_t CommandValue(const Command& command);
/// The 32-bit signed value of a two-word reply, or the word of a one-word reply.
std::int64_t ReplyLong(const Reply& reply);

/// The chip's side: splits the host's byte stream into packets. The chip has no timeout in
/// point-to-point mode; it knows each packet's length from its opcode (FindOpcode). A byte that
/// is no opcode of the table is framed by its checksum: the packet ends at the first of 4, 6, 8
/// and 10 bytes whose sum is 0 (the host's checksum covers the whole packet; an earlier zero sum
/// is a 1 in 256 chance per word), or at 10 bytes with a bad sum. A packet cut short by a line
/// fault is completed by the next bytes, which is how the host's resynchronisation works: it sends
/// single 0x00 bytes until a reply comes (a 0x00 never makes a wrong packet's sum right; with
/// nothing pending, four make a NoOperation).
class CommandDecoder {
 public:
  struct Packet {
    Command command;
    bool checksum_ok = false;
    bool known_opcode = false;
    std::array<std::uint8_t, kMaxCommandBytes> raw{};  ///< the packet's bytes as received
    std::size_t size = 0;
  };

  /// Takes one byte; true when it completed a packet (then *packet is filled).
  bool Push(std::uint8_t byte, Packet* packet);
  /// Takes any number of bytes; appends each completed packet.
  void Feed(std::span<const std::uint8_t> bytes, std::vector<Packet>* packets);
  /// Bytes of the packet received so far.
  std::size_t pending() const { return size_; }
  void Clear() { size_ = 0; }

 private:
  std::array<std::uint8_t, kMaxCommandBytes> buf_{};
  std::size_t size_ = 0;
  std::size_t expected_ = 4;
};

/// The host's side: the reply to one command. Replies are not self-delimiting; their length
/// follows from the command (result words) and the status byte (2 bytes when status != 0).
class ReplyDecoder {
 public:
  enum class Result {
    kNeedMore,  ///< not complete yet
    kReply,     ///< a well-formed reply (any status): reply()
    kGarbled,   ///< the expected length arrived and the sum is not 0: corrupted or misaligned
  };

  /// Starts on the reply to a command that returns `result_words` words (0..2).
  void Expect(int result_words);
  /// Takes one byte. After kReply or kGarbled, further bytes give kGarbled (surplus).
  Result Push(std::uint8_t byte);
  const Reply& reply() const { return reply_; }
  /// The bytes taken since Expect.
  std::span<const std::uint8_t> raw() const { return {buf_.data(), size_}; }

 private:
  std::array<std::uint8_t, kMaxReplyBytes> buf_{};
  std::size_t size_ = 0;
  int result_words_ = 0;
  bool done_ = false;
  Reply reply_;
};

}  // namespace hgrasp::drivers::pmd
