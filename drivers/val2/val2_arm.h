#pragma once
/// @file A Puma 260 arm through its VAL II controller's console (RS-232, 9600 8N1): the
/// device::Arm seam over a ByteLink. drivers/val2/PROTOCOL.md describes the protocol.
///
/// VAL II has no checksums and no sequence numbers: the driver makes every command safe with
/// the console itself. The commands are spelled so that no part of one is a command (a stray
/// CR can only execute an invalid line). The driver types a command in short chunks, its last
/// character alone, and checks every echo; it asks the monitor to retype the finished line (^R)
/// and sends the CR only when the retyped line is exactly the command; and when the answer to a
/// CR is lost it asks (^R) what the monitor holds instead of typing the command again. So a
/// command is never altered and never executed twice.
///
/// Failed calls. A call that returns a failure status may still have been executed once (its
/// CR may have reached the controller and only the answer been lost). The next state-changing
/// call with the same arguments is taken as its retry: it completes that command (sends the CR
/// that was missing, or reports the execution it finds) and never executes it a second time.
/// Any other call first cancels such a command if it is still sitting unexecuted in the
/// controller's line.
///
/// A lost link (the port gone, or no byte from the controller for link_lost_s): VAL II goes on
/// with the motion it was last given and then holds its position (it has no watchdog on the
/// console). The driver sends nothing more while the link is down; when the link answers again
/// it first cancels any command left unexecuted, then ABORTs (the arm stops where it is), and
/// it refuses motion and speed commands with kDisconnected until a Read succeeds, so the caller
/// looks at the arm before moving it again. Stop() is always allowed.

#include <array>
#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/clock.h"
#include "device/arm.h"
#include "serial/byte_link.h"
#include "serial/command_log.h"
#include "val2/val2_codec.h"

namespace hgrasp::drivers {

/// Timing and retry settings of Val2Arm. The defaults suit VAL II at 9600 baud (one character
/// takes 1.04 ms each way) and report a silent link within 0.5 s.
struct Val2Options {
  double echo_timeout_s = 0.05;   ///< wait for the echo of one typed character (s)
  double reply_timeout_s = 0.15;  ///< wait for the first byte of the answer to CR, ^R, ^U, DEL
  double quiet_s = 0.01;          ///< silence that ends an answer of unknown length (s)
  /// A call gives up when the controller has been silent this long (s): a cut link is reported
  /// within this time. A call that keeps getting answers goes on (9600 baud is slow: a WHERE
  /// report alone takes 0.27 s) up to max_call_s.
  double silence_budget_s = 0.45;
  double max_call_s = 5.0;   ///< hard limit of one call (s), e.g. under endless corruption
  double link_lost_s = 1.0;  ///< silence after which the link counts as lost (s)
  int max_errors = 4;        ///< messages other than a known refusal tolerated for one command
  /// Read() takes two WHERE reports and accepts the second only when the joints agree within
  /// the motion possible between them (max_joint_speed_deg_s): this catches a digit corrupted
  /// into another digit, which no parse can see (VAL has no checksum). Off by default: a clean
  /// RS-232 line rarely corrupts a byte, and at 9600 baud it halves the read rate.
  bool confirm_reads = false;
  /// Joint speed limits (deg/s) for confirm_reads: the Puma 260's (DESIGN.md).
  std::array<double, 6> max_joint_speed_deg_s = {120, 120, 165, 575, 430, 400};
  /// Read() calls the arm moving when a joint changed by more than this between two reads
  /// (deg), or a motion was commanded since the last read. A position-servoed arm at rest under
  /// load (a hand pressing on a box) dithers in WHERE's third decimal; with any change counted
  /// as motion the arm of the twin never came to rest at the grasp. 0.01 deg is ten of WHERE's
  /// units and moves the gripper (0.45 m of arm) by under 0.1 mm.
  double still_deg = 0.01;
  /// A motion command whose answer was lost whole (its line gone from the controller's input,
  /// no trace of what ran) is checked by WHERE when the arm was at rest at the last Read and
  /// the move is one WHERE can see: the arm moving means it ran; the joints still where they
  /// rested this long (s) after the loss was found means it did not (refused, or its CR
  /// damaged into a ^U), and it is typed again. A move starts within the controller's
  /// trajectory cycle (28 ms); the first WHERE after a loss comes 0.1-0.3 s later.
  double motion_start_s = 0.2;
  /// How far the arm must be on its way from that rest towards the commanded target, in two
  /// WHERE reports in a row, for the check to find that the move ran: along the move in joint
  /// space (deg) for a joint move; for a tool move, along the tool's path (mm), or about its turn
  /// (deg) when it turns without going 2 moved_mm. The check finds that it did not run when
  /// two reports in a row, the second asked motion_start_s or more after the loss was found, show
  /// it short of that. Below these, two kinds of noise: a digit corrupted into another digit (one
  /// report; VAL has no checksum, a report is off a degree), and an arm settling under a load
  /// (a hand pressing on a box) that creeps under still_deg between two reads. A move is
  /// checked (visible) when it goes twice as far.
  double moved_deg = 0.05;
  double moved_mm = 0.5;
  double moved_turn_deg = 0.25;
  /// The check is decided at half the move rather than at its threshold when the move goes
  /// further (a move that ran ends at its whole length; one that did not stays at its rest), and
  /// two reports in a row below that with the joints still between them (under still_deg) mean
  /// it did not run (still_deg_s): an arm at rest that creeps, under still_deg between two reads,
  /// creeps on during a check that began late (the command retyped through corruption) and passed
  /// the threshold on a cancelled move (taken as run: lost). A tool move's length in the joints,
  /// where its rest location is not known, is bounded from below by the reach: a tool move of
  /// d mm turning by a deg turns the joints by at least max(d / reach, a) / sqrt(6) (Euclidean,
  /// rad). The tool's greatest distance from a joint axis, m (the Puma 260's is under 0.5 m).
  double reach_m = 0.6;
  /// Joints still between two reports of the check: none turned faster than this (deg/s):
  /// still_deg over the 0.27 s a WHERE report takes at 9600 baud. Reports of a check come
  /// further apart when corrupted ones are asked again (0.5-0.8 s at 1 % of the bytes), so
  /// stillness is a rate. Between two still reports the joints' rate is the rest's own creep:
  /// it is taken away from a tool move's joint travel since the rest (its location not known).
  double still_deg_s = 0.04;
  /// When set, told every exchange with the controller (bytes sent, answer, what the driver
  /// made of it), for debugging a link.
  std::function<void(const std::string&)> trace;
};

/// Diagnostics, for tests and logs.
struct Val2Counters {
  long commands = 0;           ///< state-changing commands executed (confirmed)
  long reads = 0;              ///< WHERE reports parsed
  long typed = 0;              ///< characters typed
  long echo_mismatches = 0;    ///< echoes that were not the typed character
  long probes = 0;             ///< ^R sent to learn or check the line
  long cancels = 0;            ///< ^U sent
  long rubouts = 0;            ///< DEL sent
  long resolved_retries = 0;   ///< failed calls completed by their retry without re-sending
  long cancelled_pending = 0;  ///< unexecuted commands of failed calls cancelled
  long safety_aborts = 0;      ///< ABORTs sent after a lost link
  long blind_aborts = 0;       ///< ABORTs typed blind by SafeStop to a silent controller
  long bad_where = 0;          ///< WHERE reports that failed the strict parse
  long motion_checks = 0;      ///< motion commands whose lost answer WHERE settled
  long unrun_found = 0;        ///< of which had not run (typed again)
};

class Val2Arm final : public device::Arm {
 public:
  /// `link`: the controller's console line (a SerialPort at 9600 8N1, or a FaultyLink over
  /// one). The controller must be at the VAL II monitor's "." prompt (calibrated, arm power on).
  /// `clock`: every time the driver reads and every wait it times (the link's own Read waits
  /// on the link's clock, the same one): the wall clock on a real robot, a SimClock in
  /// simulated time (must outlive the driver).
  explicit Val2Arm(std::unique_ptr<ByteLink> link, const Val2Options& options = {},
                   Clock& clock = Clock::Wall());

  /// WHERE: joint angles (rad), rates estimated from the previous Read (rad/s), and `moving`
  /// when the joints changed since the previous Read or a motion was commanded since. t_s is
  /// the driver's clock (s since construction): VAL prints no time.
  device::Status Read(device::ArmState* state) override;
  /// DO MOVE #PPOINT(JT1..JT6): joint angles in degrees, the URDF's angles one for one.
  device::Status MoveJoints(const device::Joint6& q_target) override;
  /// DO APPRO HERE:TRANS(x,y,z,O,A,T),0 (= DO MOVE HERE:TRANS(...)): X_EEnew in mm and VAL's
  /// O, A, T. kRejected when the controller answers *Position out of range*.
  device::Status MoveRelative(const Pose3& X_EEnew) override;
  /// SPEED (percent): fraction (0, 1] of the joint speed limits, to 0.01 %.
  device::Status SetSpeed(double fraction) override;
  /// ABORT.
  device::Status Stop() override;
  /// When the controller has gone silent (no answer since the last call's first wait), first
  /// types ^U ABORT CR blind, without waiting for echoes: a controller that still hears the
  /// host (a broken receive wire, a dropout on the way back) stops the arm at once. Then Stop()
  /// as always, which confirms the stop or reports why it could not.
  device::Status SafeStop() override;
  /// To a controller silent since a failed call: ^U ABORT CR typed blind (no answer awaited),
  /// once per safe stop (SafeStop types it itself when this was not called first).
  void StopAtOnce() override;
  /// DO READY: the arm's READY position (VAL's rest position, joints 0, -90, 90, 0, 0, 0 deg).
  device::Status Ready();

  /// The last message the controller printed between asterisks ("" when none yet).
  const std::string& last_error() const { return last_error_; }
  const Val2Counters& counters() const { return counters_; }
  /// The state-changing lines the controller executed (SPEED, DO MOVE, DO APPRO, DO READY,
  /// ABORT), each once, as val2::Encode spells them: the encoding of Val2Emulator's log
  /// (Val2Executed::line). Confirmed when the driver knows a line ran: its execution seen, or,
  /// for a failed call's line, found executed later (by the call's retry, a Read, the next
  /// command or the recovery after a lost link); a line refused or cancelled is not recorded.
  /// Unconfirmed (CommandLog): the ABORT that SafeStop types blind to a silent controller
  /// (nothing answers it: the controller may have heard it or not; Stop() follows with a
  /// confirmed ABORT), and, until a call succeeds after it, a line the driver finds gone from
  /// the controller's input (its usual proof that the line ran), since the blind ^U may have
  /// emptied the line instead. A failed call's line still unresolved is not recorded.
  const CommandLog<std::string>& command_log() const { return command_log_; }
  /// True while the link counts as lost (see the file comment).
  bool link_lost() const { return lost_; }

 private:
  /// Outcome of driving one command line.
  struct LineOutcome {
    bool executed = false;     ///< the line ran (once)
    bool output_known = true;  ///< false when it ran but its answer was lost
    std::string output;        ///< its output lines (CR LF each), when known
    std::string error;         ///< the message between asterisks, if any
  };

  /// The time limits of one call: it ends when the controller has been silent for
  /// silence_budget_s, or after max_call_s.
  struct CallClock {
    Clock::TimePoint start, last_heard;
    double silence_s = 0.45, max_s = 5.0;
    Clock::TimePoint Deadline() const;
  };

  CallClock StartCall() const;
  /// A motion whose progress from the arm's rest WHERE can measure: a joint target, or a move
  /// of the tool relative to itself.
  struct Motion {
    std::optional<std::array<double, 6>> joints_deg;  ///< MoveJoints' target
    Pose3 X_EEnew = Pose3::Identity();                ///< MoveRelative's move
  };
  /// Whether `motion` goes far enough from the rest of the last Read for WHERE to settle a lost
  /// answer: twice the moved_* threshold.
  bool Checkable(const Motion& motion) const;
  /// How far the arm in `report` is on its way from its rest at the last Read towards the end
  /// of `motion`, in units of the moved_* thresholds (1: the check's threshold). A tool move
  /// is measured on the tool's location (`located`: the report's location line came through
  /// intact; NaN when not), or, when the location at the rest is not known, as the joints'
  /// travel from the rest in any direction (moved_deg).
  double Progress(const Motion& motion, const val2::WhereReport& report, bool located) const;
  /// The whole of `motion` in Progress' units (the arm at the move's end: at least this; for a
  /// tool move whose rest location is not known, a lower bound through reach_m).
  double WholeProgress(const Motion& motion) const;
  /// Whether a check's report shows the arm further from its rest along `motion` than twice the
  /// move (plus two thresholds): a digit corrupted far off (a blank made a digit: tens of degrees,
  /// or metres of the tool), which tells nothing. Judged only where the whole is the move's own.
  bool PastTheMove(const Motion& motion, double progress) const;
  /// Whether the joints could go from `from` to `to` in the time between within their speed
  /// limits (max_joint_speed_deg_s, with confirm_reads' margin).
  bool Reachable(const std::array<double, 6>& from, double from_t, const std::array<double, 6>& to,
                 double to_t) const;
  /// Runs one state-changing command line (the common path of the commands). `motion`: a move
  /// that WHERE can see (it goes 2 thresholds: see moved_deg), so that a lost answer can be
  /// settled by the arm.
  device::Status Command(const std::string& line, bool is_stop, bool is_motion,
                         const Motion* motion = nullptr);
  /// Whether the arm has left the rest of the last Read on its way to `motion` (see moved_deg
  /// and reach_m): WHERE until two reports in a row show it on its way (*moved: past the
  /// threshold, and past half the move), or two in a row, the second asked motion_start_s after
  /// `since`, show it not (short of the threshold, or short of half the move with the joints
  /// still between them).
  device::Status MovedFromRest(Clock::TimePoint since, const Motion& motion, CallClock* call,
                               bool* moved);
  /// One WHERE report, parsed: the joints always; the location when `located` says so.
  device::Status Where(CallClock* call, val2::WhereReport* report, double* t_s,
                       bool* located = nullptr);
  /// Drives `line` until it has been executed once: types it, checks it, sends CR, resolves
  /// lost answers. `resume`: the line may already be complete in the controller (a retry).
  /// `check_motion`: a lost answer is settled by MovedFromRest towards it rather than taken as a
  /// run.
  device::Status Drive(const std::string& line, bool state_changing, bool resume, CallClock* call,
                       LineOutcome* outcome, const Motion* check_motion = nullptr);
  /// One Drive's state: the line, and what the answers since it was armed show of it.
  struct DriveState {
    const std::string& line;
    bool state_changing;
    const Motion* check_motion;
    CallClock* call;
    LineOutcome* outcome;
    bool armed;             ///< the whole line may be in the controller's input, or have run
    bool verified = false;  ///< a ^R answer showed exactly the line
    /// While armed: traces of a cancel, of an execution and of a message, in answers since.
    bool cancel_trace = false, execution_trace = false, message_trace = false;
    int suspect = 0;         ///< ^R answers near the line but not it, in a row
    int errors = 0;          ///< lines that ran with "not understood"
    bool gone_once = false;  ///< the line was found gone at the last turn, with no trace of a run
  };
  /// What one turn of a Drive sends, and what it expects back.
  struct Keys {
    double timeout_s = 0.0;  ///< for the whole answer
    std::string send, expected;
    bool probe_again = false;   ///< a second look at a line near the command
    bool armed_before = false;  ///< DriveState::armed before this turn
  };
  /// One turn's decision: send Keys, decide again without sending, or end the Drive.
  enum class Turn { kSend, kAgain, kDone };
  /// What to send next from what the controller is believed to hold; *s when kDone.
  Turn NextKeys(DriveState* d, Keys* k, device::Status* s);
  /// The armed line has left the controller's input: decides whether it ran.
  Turn GoneLine(DriveState* d, bool gone_again, Keys* k, device::Status* s);
  /// The controller holds something other than the line: type on, rub out, or start again.
  void TypeTowards(DriveState* d, Keys* k);
  /// Sends `k` and reads the answer into the Drive's state; *s when kDone.
  Turn TakeAnswer(DriveState* d, const Keys& k, device::Status* s);
  /// A line ran with answer `r`: the command's success, its refusal, or a damaged line.
  Turn LineRan(DriveState* d, const val2::Reaction& r, const std::optional<std::string>& ran,
               device::Status* s);
  /// Empties the controller's line without executing `pending` if it is still there. Sets
  /// *executed when `pending` turns out to have been executed.
  device::Status Dispose(const std::string& pending, CallClock* call, bool* executed);
  /// After a lost link: cancel what is pending, ABORT, require a Read.
  device::Status Recover(CallClock* call);

  /// When an answer is complete (ReadAnswer).
  struct Expect {
    std::vector<std::string> exact;  ///< answers complete as they stand
    std::size_t min_length = 0;      ///< > 0: complete at this length (a typed chunk's echo)
    bool retype = false;             ///< a ^R: complete only when the line goes quiet
  };
  /// Sends characters to type (or rub out), or one control character, and reads the
  /// controller's whole answer; updates the believed line (known_, buf_). On an execution
  /// reports the line that was executed (if known).
  device::Status Step(const std::string& bytes, const std::string& expected, double timeout_s,
                      CallClock* call, val2::Reaction* reaction,
                      std::optional<std::string>* executed_line);
  /// The answers to `bytes` that are complete as they stand (ReadAnswer stops at one).
  Expect WantedAnswer(const std::string& bytes, const std::string& expected, bool was_known) const;
  /// saw_cancel_, saw_message_ and saw_execution_ from the whole answer to `bytes`.
  void NoteTraces(const std::string& bytes, const std::string& answer);
  /// What one key's answer, classified as `reaction`, leaves in the controller's line (`typed`:
  /// the line before with the key typed into it, if it was a printable one).
  void Believe(const val2::Reaction& reaction, const std::string& typed, bool was_known,
               const std::string& before, std::optional<std::string>* executed_line);
  /// Reads until the answer is complete as `want` says, or is an execution with its prompt, or
  /// the line goes quiet.
  device::Status ReadAnswer(const Expect& want, double first_byte_timeout_s, CallClock* call,
                            std::string* answer);
  /// Throws away bytes nobody asked for (late answers).
  device::Status DrainStale();
  /// Records `line`, which ran, in command_log_; `inferred`: known from the line having gone
  /// from the controller's input, not from its execution seen.
  void Ran(const std::string& line, bool inferred);
  /// Bookkeeping of a failed call: silence, lost link. Returns the status to report.
  device::Status Fail(device::Status s);
  double Now() const;

  std::unique_ptr<ByteLink> link_;
  Val2Options opt_;
  Clock* clock_;
  Clock::TimePoint start_;

  // What the driver believes the monitor's input line holds.
  bool known_ = false;
  std::string buf_;
  std::vector<std::string> guesses_ = {""};  // likely lines while !known_
  std::string tentative_view_;               // an unexpected retype, believed when seen again
  bool saw_cancel_ = false, saw_execution_ = false;  // traces in the last answer
  bool saw_message_ = false;                         // a "*...*" message in the last answer

  std::optional<std::string> pending_;          // state-changing line of a failed call
  std::optional<std::string> executed_record_;  // a pending line found executed later

  bool lost_ = false;        // link lost: recover before anything else
  bool needs_read_ = false;  // after a recovery: motion refused until a Read succeeds
  std::optional<Clock::TimePoint> silent_since_;

  // Previous Read, for the rates and `moving`.
  bool have_prev_ = false;
  double prev_t_ = 0.0;
  std::array<double, 6> prev_deg_{};
  // The tool (VAL's world frame) where the arm rests at prev_deg_, when known (located_).
  val2::Trans prev_location_;
  bool located_ = false;
  // The location of the previous Read, when its line came through, since the arm last moved.
  std::optional<val2::Trans> candidate_location_;
  bool motion_since_read_ = false;
  // The last Read found the joints unchanged since the one before, with no motion commanded
  // in between: the arm rests at prev_deg_.
  bool at_rest_ = false;
  // The joints' rate between the last two Reads (deg/s): at a rest, its creep.
  std::array<double, 6> rest_creep_deg_s_{};

  std::string last_error_;
  Val2Counters counters_;
  CommandLog<std::string> command_log_;
  bool blind_typed_ = false;  // SafeStop typed ^U ABORT blind since the last call that succeeded
  bool blind_in_this_stop_ = false;  // StopAtOnce typed it for the SafeStop to come
};

}  // namespace hgrasp::drivers
