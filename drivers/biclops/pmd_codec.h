#pragma once
/// @file The PMD motion-chip serial protocol (Navigator / Pilot / Magellan, point-to-point mode)
/// as the TRACLabs Biclops library speaks it: packets, checksums, replies, the opcodes the
/// Biclops driver uses, and incremental decoders for both directions. Pure functions and small
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

/// Opcodes used here, with the values of libPMD's PMDOPCodes.h ("Navigator command code
/// declarations", Performance Motion Devices).
namespace op {
inline constexpr std::uint8_t kNoOperation = 0x00;
inline constexpr std::uint8_t kSetPosition = 0x10;
inline constexpr std::uint8_t kSetVelocity = 0x11;
inline constexpr std::uint8_t kUpdate = 0x1A;
inline constexpr std::uint8_t kGetCommandedPosition = 0x1D;
inline constexpr std::uint8_t kGetActualPosition = 0x37;
inline constexpr std::uint8_t kReset = 0x39;
inline constexpr std::uint8_t kGetPosition = 0x4A;
inline constexpr std::uint8_t kGetVelocity = 0x4B;
inline constexpr std::uint8_t kGetAcceleration = 0x4C;
inline constexpr std::uint8_t kGetSampleTime = 0x61;
inline constexpr std::uint8_t kGetVersion = 0x8F;
inline constexpr std::uint8_t kSetAcceleration = 0x90;
inline constexpr std::uint8_t kSetProfileMode = 0xA0;
inline constexpr std::uint8_t kGetProfileMode = 0xA1;
inline constexpr std::uint8_t kGetActivityStatus = 0xA6;
}  // namespace op

/// What the protocol says about one opcode.
struct OpcodeInfo {
  std::uint8_t opcode;
  std::string_view name;
  int argument_words;  ///< 16-bit words the host sends after the opcode
  int result_words;    ///< 16-bit words the chip returns with status 0
  bool changes_state;  ///< a Set*, Update or Reset: logged by the emulator when executed
  bool replies;        ///< false for Reset only: the chip answers nothing
};

/// The opcodes of this codec (the table above), or nullptr for any other byte.
const OpcodeInfo* FindOpcode(std::uint8_t opcode);

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

/// Profile modes (SetProfileMode), libPMD PMDTypes.h tagPMDProfileMode.
inline constexpr std::uint16_t kTrapezoidalProfile = 0;

/// Velocity and acceleration registers are fixed point with 16 fraction bits: counts per cycle
/// * 2^16 and counts per cycle^2 * 2^16 (libPMD PMDVelScaling, PMDAccScaling).
inline constexpr double kVelocityScale = 65536.0;
inline constexpr double kAccelerationScale = 65536.0;

/// The point-to-point address byte (libPMD's default multidrop ID 0).
inline constexpr std::uint8_t kPointToPointAddress = 0x00;

/// Longest packet of this codec's opcodes: 4 header bytes + 2 words.
inline constexpr std::size_t kMaxCommandBytes = 8;
/// Longest reply: 2 header bytes + 2 words.
inline constexpr std::size_t kMaxReplyBytes = 6;

/// One host -> chip packet.
struct Command {
  std::uint8_t address = kPointToPointAddress;
  std::uint8_t axis = 0;    ///< 0..3 (Biclops: pan 0, tilt 1, verge 2)
  std::uint8_t opcode = 0;  ///< any byte (decoded packets may carry unknown opcodes)
  std::array<std::uint16_t, 2> words{};
  int word_count = 0;  ///< 0..2

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
/// point-to-point mode; it knows each packet's length from its opcode (unknown opcodes: the 4
/// header bytes). A packet cut short by a line fault is completed by the next bytes, which is
/// how the host's resynchronisation works: it sends single 0x00 bytes until a reply comes (a
/// 0x00 never makes a wrong packet's sum right; with nothing pending, four make a NoOperation).
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
