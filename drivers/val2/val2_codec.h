#pragma once
/// @file The VAL II console protocol of the Puma controllers, as pure functions shared by the
/// driver (Val2Arm) and the emulator (Val2Emulator): command lines, the monitor's line editing
/// and echo, the WHERE report, the controller's output as a stream of lines and prompts, and the
/// classification of what the controller sent back after one byte from the host.
/// drivers/val2/PROTOCOL.md describes the protocol and its sources.
///
/// Units on the wire are VAL's: millimetres and degrees. The conversions to SI (m, rad) happen
/// in the driver and the emulator, not here, except for the pose helpers at the end.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/geometry.h"

namespace hgrasp::drivers::val2 {

// ---------------------------------------------------------------------------------------------
// Characters of the console.

inline constexpr char kCr = '\r';     ///< ends a command line (the Return key)
inline constexpr char kLf = '\n';     ///< ignored on input; ends every output line after CR
inline constexpr char kCtrlU = 0x15;  ///< cancels the line being typed
inline constexpr char kCtrlR = 0x12;  ///< retypes the line being typed
inline constexpr char kDel = 0x7F;    ///< rubs out the last character (as does backspace)
inline constexpr char kBs = 0x08;     ///< backspace
inline constexpr char kBel = 0x07;    ///< the controller's answer to a character it refuses
inline constexpr char kPrompt = '.';  ///< the monitor's prompt, at the start of a line
/// The longest command line the monitor accepts (characters before the CR).
inline constexpr std::size_t kMaxLineLength = 80;

/// Decimals printed on the wire: 0.01 mm, 0.001 deg, 0.01 % speed.
inline constexpr int kMmDecimals = 2;
inline constexpr int kDegDecimals = 3;
inline constexpr int kPercentDecimals = 2;

// ---------------------------------------------------------------------------------------------
// Numbers.

/// `value` with exactly `decimals` decimals, as printf("%.*f") (so -0.0004 gives "-0.000").
std::string FormatFixed(double value, int decimals);

/// Strict decimal number: an optional '-', one or more digits, optionally '.' and one or more
/// digits; nothing else (no '+', exponent, spaces, leading '.'). At most 15 significant digits.
bool ParseNumber(std::string_view text, double* value);

// ---------------------------------------------------------------------------------------------
// Orientation: VAL's O, A, T angles.

/// The rotation that TRANS(x, y, z, O, A, T) stands for: R = RZ(O) RY(A) RZ(T) (Z-Y-Z Euler
/// angles about the moving axes), angles in degrees. TRANS(0,0,0,0,0,0) is the identity (VAL's
/// NULL). See PROTOCOL.md, "Orientation", for the sources and the one open question.
Eigen::Matrix3d OatToRotation(double o_deg, double a_deg, double t_deg);

/// The inverse of OatToRotation: A in [0, 180], O and T in (-180, 180]; at A = 0 or 180 (O and
/// T not separable) O = 0.
void RotationToOat(const Eigen::Matrix3d& R, double* o_deg, double* a_deg, double* t_deg);

/// A VAL transformation: position in mm, orientation O, A, T in degrees.
struct Trans {
  double x = 0, y = 0, z = 0;  ///< mm
  double o = 0, a = 0, t = 0;  ///< deg
  bool operator==(const Trans&) const = default;
};

/// SI pose (m) <-> VAL transformation (mm, deg), unrounded.
Trans PoseToTrans(const Pose3& X);
Pose3 TransToPose(const Trans& t);

/// The transformation as printed on the wire: x, y, z rounded to 0.01 mm, O, A, T to 0.001 deg.
Trans RoundForWire(const Trans& t);

// ---------------------------------------------------------------------------------------------
// Command lines (host -> controller).

enum class CommandKind {
  kWhere,  ///< WHERE: print the current location
  kSpeed,  ///< SPEED (p): monitor speed, percent of the joint speed limits, 0 < p <= 100
  kMove,   ///< DO MOVE <location>: joint-interpolated motion
  kAppro,  ///< DO APPRO <transformation>,<distance>: MOVE to it, backed off along tool z
  kReady,  ///< DO READY: move to the READY position
  kAbort,  ///< ABORT: stop the robot
};

/// One factor of a compound transformation a:b:c.
struct LocationTerm {
  bool here = false;  ///< HERE (the current location) rather than TRANS(...)
  Trans trans;        ///< the TRANS(...) arguments when !here
  bool operator==(const LocationTerm&) const = default;
};

/// A parsed command line. Which fields mean something depends on `kind`.
struct Command {
  CommandKind kind = CommandKind::kWhere;
  /// kMove to a precision point #PPOINT(j1, ..., j6): `joints` in degrees.
  bool precision_point = false;
  std::array<double, 6> joints{};
  /// kMove / kAppro to a transformation: the product of these terms (at least one).
  std::vector<LocationTerm> terms;
  /// kSpeed: percent. kAppro: distance in mm.
  double value = 0.0;
  bool operator==(const Command&) const = default;
};

/// Canonical text of a command (no CR), exactly as the driver types it:
///   WHERE | SPEED (p) | DO MOVE #PPOINT(j1,...,j6) | DO MOVE t1:t2... | DO APPRO t1:t2...,d
///   | DO READY | ABORT
/// with t = HERE or TRANS(x,y,z,o,a,t). Numbers carry kMmDecimals / kDegDecimals /
/// kPercentDecimals decimals. Every command the driver sends is prefix-free: no proper prefix
/// of its text is a command the monitor would execute (PROTOCOL.md, "Why these spellings").
std::string Encode(const Command& command);

/// The commands the driver uses.
Command WhereCommand();
Command SpeedCommand(double percent);
Command MoveJointsCommand(const std::array<double, 6>& joints_deg);
/// The tool-relative move X_new = HERE:delta, spelled DO APPRO HERE:TRANS(...),0.
Command MoveRelativeCommand(const Trans& delta);
/// Absolute move to a transformation in the robot's world frame: DO MOVE TRANS(...).
Command MoveToCommand(const Trans& location);
Command ReadyCommand();
Command AbortCommand();

/// Parses one command line as the emulated monitor does (case-insensitive keywords, spaces
/// between tokens where VAL allows them). On failure returns false and sets *error to the
/// monitor's message without the asterisks, e.g. "Unknown command". Lines longer than
/// kMaxLineLength are refused.
bool ParseCommand(std::string_view line, Command* command, std::string* error);

/// The monitor's error messages (printed between asterisks). Which the driver reads as "the
/// command was refused" (kRejected) and which as "the line was not understood" (a garbled line,
/// not executed): see IsSyntaxError.
inline constexpr std::string_view kErrUnknownCommand = "Unknown command";
inline constexpr std::string_view kErrInvalidArgument = "Invalid argument";
inline constexpr std::string_view kErrMissingArgument = "Missing argument";
inline constexpr std::string_view kErrUndefinedValue = "Undefined value";
inline constexpr std::string_view kErrLineTooLong = "Line too long";
inline constexpr std::string_view kErrIllegalValue = "Illegal value";
inline constexpr std::string_view kErrOutOfRange = "Position out of range";

/// True for the messages that mean the monitor could not read the line (it executed nothing).
bool IsSyntaxError(std::string_view message);
/// True for the messages that mean the monitor read the line and refused it (kErrOutOfRange,
/// kErrIllegalValue).
bool IsRefusal(std::string_view message);

/// "*" + message + "*".
std::string ErrorLine(std::string_view message);
/// The message inside a line "*...*", or nullopt when the line is not an error line.
std::optional<std::string> ParseErrorLine(std::string_view line);

// ---------------------------------------------------------------------------------------------
// The monitor's line editing (controller side), used by the emulator to process input and by the
// driver to predict echoes.

class LineDiscipline {
 public:
  enum class Event {
    kEcho,     ///< a printable character was added and echoed
    kRubout,   ///< DEL or BS removed the last character; echo "\b \b"
    kCancel,   ///< ^U emptied the line; echo "^U\r\n."
    kRetype,   ///< ^R; echo "^R\r\n." + the line so far
    kExecute,  ///< CR; echo "\r\n"; the caller executes `line`, prints its output and kPrompt
    kBell,     ///< a byte refused (control character, 8-bit byte, full line, rubout of nothing)
    kIgnored,  ///< LF: nothing echoed
  };

  /// Processes one input byte: appends its echo to *echo; on kExecute sets *line to the line and
  /// empties the buffer.
  Event Feed(char byte, std::string* echo, std::string* line);

  const std::string& buffer() const { return buffer_; }
  void Clear() { buffer_.clear(); }

 private:
  std::string buffer_;
};

/// What the controller echoes for a ^U and for a ^R with `buffer` being typed.
std::string CancelEcho();
std::string RetypeEcho(std::string_view buffer);
inline constexpr std::string_view kRuboutEcho = "\b \b";

// ---------------------------------------------------------------------------------------------
// The WHERE report (controller -> host).

/// What WHERE prints: the tool's location in the robot's world frame (X Y Z in mm, O A T in deg)
/// and the joint angles JT1..JT6 (deg).
struct WhereReport {
  Trans location;
  std::array<double, 6> joints{};
  bool operator==(const WhereReport&) const = default;
};

/// The four lines WHERE prints (without CR LF): a header X..T, the location (fields of 10
/// characters, 2 decimals for mm, 3 for degrees), a header JT1..JT6, the joints (3 decimals).
std::array<std::string, 4> FormatWhere(const WhereReport& report);

/// Strict inverse of FormatWhere: the exact headers, fields of exactly 10 characters, each a
/// right-aligned ParseNumber with the exact number of decimals.
bool ParseWhere(const std::array<std::string, 4>& lines, WhereReport* report);
/// The joints' line alone (the last line WHERE prints), as strictly. Its format tells it from
/// every other line of the report: six fields of 3 decimals (the location's X, Y, Z have 2).
bool ParseWhereJoints(const std::string& values, std::array<double, 6>* joints);
/// The location's line alone (the second), as strictly: X, Y, Z of 2 decimals, O, A, T of 3.
bool ParseWhereLocation(const std::string& values, Trans* location);

// ---------------------------------------------------------------------------------------------
// The controller's output as a stream (driver side).

/// One unit of the controller's output.
struct OutputUnit {
  enum class Kind {
    kLine,      ///< text ended by CR LF (text excludes the CR LF)
    kPrompt,    ///< kPrompt at the start of a line
    kFragment,  ///< bytes with no CR LF after kMaxFragment of them, or flushed at the end
  };
  Kind kind = Kind::kLine;
  std::string text;
  bool operator==(const OutputUnit&) const = default;
};

/// The bytes a unit came from.
std::string EncodeUnit(const OutputUnit& unit);

/// Splits the controller's output, fed in any split, into lines and prompts. Lossless: the
/// units' EncodeUnit, concatenated, are exactly the bytes fed. Garbage cannot desynchronise it
/// for longer than one line: every CR LF ends a line, and an over-long line is cut into
/// fragments.
class OutputDecoder {
 public:
  static constexpr std::size_t kMaxFragment = 256;
  void Feed(std::string_view bytes);
  /// Next complete unit, or false when more bytes are needed.
  bool Next(OutputUnit* unit);
  /// Emits what is left (an unterminated line) as a fragment; false when nothing is left.
  bool Flush(OutputUnit* unit);

 private:
  std::string pending_;  // bytes of the current line, not yet a unit
  std::vector<OutputUnit> ready_;
  std::size_t next_ = 0;
  bool at_line_start_ = true;
};

// ---------------------------------------------------------------------------------------------
// What one byte from the host did, judged from the controller's answer (driver side).

struct Reaction {
  enum class Kind {
    kNothing,   ///< no answer at all (the byte was lost, or ignored, or its answer lost)
    kAppended,  ///< a printable character was added to the line: `text` is it
    kRubout,    ///< the last character was removed
    kCancel,    ///< the line was cancelled (^U)
    kRetype,    ///< the line was retyped: `text` is the line the controller holds
    kExecuted,  ///< a line was executed: `text` is its output (lines with CR LF), before the prompt
    kBell,      ///< the controller refused a byte
    kGarbled,   ///< none of the above
  };
  Kind kind = Kind::kNothing;
  std::string text;
};

/// Classifies everything the controller sent after one byte from the host (the answer must be
/// complete: the caller reads until the line goes quiet). The fixed answers (the echo of CR with
/// no output "\r\n.", "\b \b", "^U\r\n.", the "^R\r\n." head) are recognised with one byte
/// corrupted, so a single corrupted byte never turns one reaction into another; anything less
/// certain is kGarbled.
Reaction ClassifyReaction(std::string_view answer);

/// True when `answer` is already a complete answer of a kind that needs no wait for silence:
/// exactly `expected`, or an execution ending in "\r\n." (the prompt).
bool AnswerComplete(std::string_view answer, std::string_view expected);

}  // namespace hgrasp::drivers::val2
