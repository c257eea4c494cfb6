#include "val2/val2_arm.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

namespace hgrasp::drivers {
namespace {

using device::Status;
using val2::Reaction;

std::string RTrim(std::string s) {
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

bool StartsWith(const std::string& s, const std::string& prefix) {
  return s.size() >= prefix.size() && s.compare(0, prefix.size(), prefix) == 0;
}

std::size_t CommonPrefix(const std::string& a, const std::string& b) {
  std::size_t k = 0;
  while (k < a.size() && k < b.size() && a[k] == b[k]) ++k;
  return k;
}

// True when `line` has left the controller's input: what is there is much shorter than the line.
// A line that never ran is still there whole, give or take a few damaged, added or rubbed-out
// characters (and a retype of it may show it damaged, with bytes changed or inserted); once it
// ran or was cancelled, only the few stray characters that arrived since.
bool Gone(const std::string& buf, const std::string& line) {
  return RTrim(buf).size() * 2 <= line.size();
}

bool IsPrintable(char c) { return c >= 0x20 && c <= 0x7E; }

// Whether the CR LF at `i` of an answer is the line break of a "^U" or "^R" echo rather than a
// trace of a line that ran. In the answer to a ^R, the head ("^R" CR LF) with one of its two
// characters damaged is the retype's too, and so is a CR LF followed by the prompt and a retyped
// character (a byte inserted into the head, or the head lost): a line that ran ends its answer
// with the prompt, and nothing follows before the host sends again. (Bug fix, simulated line's
// seeds 36, 58 and 94: a retype's "^R" damaged into "<R", or into "^" and a control character, left
// a trace of a run; the line then found empty by a retype cut short after its prompt was taken as
// run at once, without the second look, and the command, still in the controller, was cancelled by
// the next call.)
bool RetypeOrCancelBreak(const std::string& answer, std::size_t i, bool retype_asked) {
  if (i >= 2 && answer[i - 2] == '^' && (answer[i - 1] == 'U' || answer[i - 1] == 'R')) {
    return true;
  }
  if (!retype_asked) return false;
  if (i == 2 && (answer[0] == '^' || answer[1] == 'R')) return true;
  return i + 3 < answer.size() && answer[i + 2] == val2::kPrompt && IsPrintable(answer[i + 3]);
}

// Bytes made readable for a trace.
std::string Visible(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c >= 0x20 && c <= 0x7E) {
      out += c;
    } else {
      char buf[8];
      std::snprintf(buf, sizeof(buf), "<%02X>", static_cast<unsigned char>(c));
      out += buf;
    }
  }
  return out + "\"";
}

// Characters typed (or rubbed out) per write before their echo is checked.
constexpr std::size_t kChunk = 16;

// The first "*...*" message among output lines (CR LF each); "" when there is none.
std::string FirstError(const std::string& output) {
  val2::OutputDecoder dec;
  dec.Feed(output);
  val2::OutputUnit u;
  while (dec.Flush(&u)) {
    if (u.kind != val2::OutputUnit::Kind::kLine) continue;
    if (auto m = val2::ParseErrorLine(u.text)) return *m;
  }
  return "";
}

// An execution in the answer to a byte other than the CR whose output is neither empty nor a
// message: a line run by a damaged byte (a ^R or a character damaged into CR) prints nothing (the
// command, an empty line) or a message (anything else). So these are late bytes of an earlier
// exchange, a WHERE report, say: nothing known ran.
bool UnexplainedOutput(const std::string& sent, const val2::Reaction& r) {
  return sent != std::string(1, val2::kCr) && !r.text.empty() && FirstError(r.text).empty();
}

// Two WHERE locations of a tool at rest: within a tenth of the check's thresholds (moved_mm,
// moved_turn_deg at their defaults), more than WHERE's last digits and an arm's creep between two
// reads (still_deg at 0.45 m: 0.08 mm), less than a corrupted digit of the tenths or above.
bool SameLocation(const val2::Trans& a, const val2::Trans& b) {
  const Pose3 A = val2::TransToPose(a), B = val2::TransToPose(b);
  return 1e3 * (A.translation() - B.translation()).norm() <= 0.1 &&
         RadToDeg(Eigen::AngleAxisd(A.linear().transpose() * B.linear()).angle()) <= 0.05;
}

// The joints from the output of WHERE: its last line, strictly parsed (its format is the joints'
// alone). The three lines before it are not required intact: on a line that corrupts 1 % of its
// bytes each way, a whole report (248 characters) arrives intact one time in ten, its last line
// (62) one time in two, and each report takes 0.27 s at 9600 baud; with the whole report
// required, one Read in seven found none intact within max_call_s. The location (for the checks
// of lost answers) is taken when a line before the joints reads as one (*located).
bool ParseWhereOutput(const std::string& output, val2::WhereReport* report, bool* located) {
  val2::OutputDecoder dec;
  dec.Feed(output);
  std::vector<std::string> lines;
  val2::OutputUnit u;
  while (dec.Flush(&u)) {
    if (u.kind != val2::OutputUnit::Kind::kLine || lines.size() == 4) return false;
    lines.push_back(u.text);
  }
  if (lines.empty() || !val2::ParseWhereJoints(lines.back(), &report->joints)) return false;
  *located = false;
  for (std::size_t k = 0; k + 1 < lines.size() && !*located; ++k) {
    *located = val2::ParseWhereLocation(lines[k], &report->location);
  }
  return true;
}

}  // namespace

Val2Arm::Val2Arm(std::unique_ptr<ByteLink> link, const Val2Options& options, Clock& clock)
    : link_(std::move(link)), opt_(options), clock_(&clock), start_(clock.Now()) {}

Val2Arm::CallClock Val2Arm::StartCall() const {
  CallClock c;
  c.start = c.last_heard = clock_->Now();
  c.silence_s = opt_.silence_budget_s;
  c.max_s = opt_.max_call_s;
  return c;
}

Clock::TimePoint Val2Arm::CallClock::Deadline() const {
  return std::min(last_heard + Clock::FromSeconds(silence_s), start + Clock::FromSeconds(max_s));
}

double Val2Arm::Now() const { return Clock::ToSeconds(clock_->Now() - start_); }

// ---------------------------------------------------------------------------------------------
// The seam.

Status Val2Arm::Read(device::ArmState* state) {
  CallClock call = StartCall();
  Status s = DrainStale();
  if (s != Status::kOk) return Fail(s);
  if (lost_) {
    s = Recover(&call);
    if (s != Status::kOk) return Fail(s);
  }
  if (pending_) {
    // A failed command still unresolved: a read is not its retry, so it must not run now.
    bool ran = false;
    s = Dispose(*pending_, &call, &ran);
    if (s != Status::kOk) return Fail(s);
    if (ran) {
      Ran(*pending_, /*inferred=*/true);
      executed_record_ = *pending_;  // recorded now: its retry only completes the call
    } else {
      ++counters_.cancelled_pending;
    }
    pending_.reset();
  }
  val2::WhereReport report;
  double t = 0.0;
  bool located = false;
  s = Where(&call, &report, &t, &located);
  if (s == Status::kOk && opt_.confirm_reads) {
    // A second report must agree with the first within the motion possible between them.
    for (;;) {
      val2::WhereReport second;
      double t2 = 0.0;
      bool located2 = false;
      s = Where(&call, &second, &t2, &located2);
      if (s != Status::kOk) break;
      const bool agree = Reachable(report.joints, t, second.joints, t2);
      report = second;
      t = t2;
      located = located2;
      if (agree) break;
      ++counters_.bad_where;
    }
  }
  if (s == Status::kRejected) return s;
  if (s != Status::kOk) return Fail(s);
  bool changed = false;
  for (int k = 0; k < 6; ++k) {
    state->q[k] = DegToRad(report.joints[k]);
    if (have_prev_ && std::abs(report.joints[k] - prev_deg_[k]) > opt_.still_deg) changed = true;
  }
  state->t_s = t;
  state->qd.setZero();
  rest_creep_deg_s_.fill(0.0);
  if (have_prev_ && t - prev_t_ > 1e-3) {
    for (int k = 0; k < 6; ++k) {
      rest_creep_deg_s_[k] = (report.joints[k] - prev_deg_[k]) / (t - prev_t_);
      state->qd[k] = DegToRad(rest_creep_deg_s_[k]);
    }
  }
  state->moving = changed || motion_since_read_;
  at_rest_ = have_prev_ && !state->moving;
  motion_since_read_ = false;
  have_prev_ = true;
  prev_t_ = t;
  prev_deg_ = report.joints;
  // The tool's rest: two location lines read at this rest that agree (a digit corrupted into
  // another passes the parse, and a rest read wrong would misjudge every check from it). Once
  // known, it holds until the arm moves.
  if (state->moving) located_ = false;
  if (located) {
    if (!state->moving && candidate_location_ &&
        SameLocation(*candidate_location_, report.location)) {
      prev_location_ = report.location;
      located_ = true;
    }
    candidate_location_ = report.location;
  } else if (state->moving) {
    candidate_location_.reset();
  }
  needs_read_ = false;
  blind_typed_ = false;
  ++counters_.reads;
  return Status::kOk;
}

Status Val2Arm::Where(CallClock* call, val2::WhereReport* report, double* t_s, bool* located) {
  bool ignored = false;
  if (located == nullptr) located = &ignored;
  const std::string line = val2::Encode(val2::WhereCommand());
  for (;;) {
    LineOutcome out;
    const Status s = Drive(line, /*state_changing=*/false, /*resume=*/false, call, &out);
    if (s != Status::kOk) return s;
    if (out.output_known && ParseWhereOutput(out.output, report, located)) {
      *t_s = Now();
      return Status::kOk;
    }
    ++counters_.bad_where;  // WHERE changes nothing: ask again
  }
}

Status Val2Arm::MoveJoints(const device::Joint6& q_target) {
  std::array<double, 6> deg;
  for (int k = 0; k < 6; ++k) {
    deg[k] = RadToDeg(q_target[k]);
    if (!std::isfinite(deg[k]) || std::abs(deg[k]) >= 10000.0) {
      last_error_ = "joint angle not representable: " + std::to_string(deg[k]) + " deg";
      return Status::kRejected;
    }
  }
  Motion motion;
  motion.joints_deg = deg;
  return Command(val2::Encode(val2::MoveJointsCommand(deg)), false, true, &motion);
}

Status Val2Arm::MoveRelative(const Pose3& X_EEnew) {
  const val2::Trans t = val2::PoseToTrans(X_EEnew);
  const std::string line = val2::Encode(val2::MoveRelativeCommand(t));
  if (!X_EEnew.matrix().allFinite() || std::abs(t.x) >= 10000.0 || std::abs(t.y) >= 10000.0 ||
      std::abs(t.z) >= 10000.0 || line.size() > val2::kMaxLineLength) {
    last_error_ = "relative move not representable: " + line;
    return Status::kRejected;
  }
  Motion motion;
  motion.X_EEnew = X_EEnew;
  return Command(line, false, true, &motion);
}

bool Val2Arm::Checkable(const Motion& motion) const {
  if (motion.joints_deg) {
    double length = 0.0;
    for (int k = 0; k < 6; ++k) length += std::pow((*motion.joints_deg)[k] - prev_deg_[k], 2);
    return std::sqrt(length) >= 2.0 * opt_.moved_deg;
  }
  return 1e3 * motion.X_EEnew.translation().norm() >= 2.0 * opt_.moved_mm ||
         RadToDeg(Eigen::AngleAxisd(motion.X_EEnew.rotation()).angle()) >=
             2.0 * opt_.moved_turn_deg;
}

double Val2Arm::Progress(const Motion& motion, const val2::WhereReport& report,
                         bool located) const {
  if (motion.joints_deg) {
    // Along the move in joint space: the projection of the joints' travel from the rest on the
    // unit vector towards the target.
    double along = 0.0, length = 0.0;
    for (int k = 0; k < 6; ++k) {
      const double d = (*motion.joints_deg)[k] - prev_deg_[k];
      along += (report.joints[k] - prev_deg_[k]) * d;
      length += d * d;
    }
    length = std::sqrt(length);
    return length > 0.0 ? along / length / opt_.moved_deg : 0.0;
  }
  if (!located_) {
    // The tool's rest not known (no location line came through intact at this rest): the
    // joints' travel from the rest, in any direction.
    double travel = 0.0;
    for (int k = 0; k < 6; ++k) travel += std::pow(report.joints[k] - prev_deg_[k], 2);
    return std::sqrt(travel) / opt_.moved_deg;
  }
  if (!located) return std::numeric_limits<double>::quiet_NaN();  // this report tells nothing
  // The tool: its move X_EEnew is in its own frame at the rest, E0.
  const Pose3 X_BE0 = val2::TransToPose(prev_location_);
  const Pose3 X_BE = val2::TransToPose(report.location);
  const Eigen::Vector3d step_mm = 1e3 * motion.X_EEnew.translation();
  if (step_mm.norm() >= 2.0 * opt_.moved_mm) {
    const Eigen::Vector3d travel_mm =
        1e3 * X_BE0.linear().transpose() * (X_BE.translation() - X_BE0.translation());
    return travel_mm.dot(step_mm.normalized()) / opt_.moved_mm;
  }
  const Eigen::AngleAxisd want(motion.X_EEnew.rotation());
  const Eigen::AngleAxisd turned(X_BE0.linear().transpose() * X_BE.linear());
  if (want.angle() <= 0.0) return 0.0;
  return RadToDeg(turned.angle() * turned.axis().dot(want.axis())) / opt_.moved_turn_deg;
}

double Val2Arm::WholeProgress(const Motion& motion) const {
  if (motion.joints_deg) {
    double length = 0.0;
    for (int k = 0; k < 6; ++k) length += std::pow((*motion.joints_deg)[k] - prev_deg_[k], 2);
    return std::sqrt(length) / opt_.moved_deg;
  }
  const double step_m = motion.X_EEnew.translation().norm();
  const double turn_rad = Eigen::AngleAxisd(motion.X_EEnew.rotation()).angle();
  if (!located_) {
    // Joint travel in any direction: the tool cannot go step_m, nor turn turn_rad, unless the
    // joints turn by step_m / reach_m, and turn_rad, in all (Euclidean norm: / sqrt(6)).
    const double joints_rad = std::max(step_m / opt_.reach_m, turn_rad) / std::sqrt(6.0);
    return RadToDeg(joints_rad) / opt_.moved_deg;
  }
  if (1e3 * step_m >= 2.0 * opt_.moved_mm) return 1e3 * step_m / opt_.moved_mm;
  return RadToDeg(turn_rad) / opt_.moved_turn_deg;
}

Status Val2Arm::SetSpeed(double fraction) {
  const double percent = fraction * 100.0;
  double printed = 0.0;
  if (!std::isfinite(fraction) || fraction > 1.0 ||
      !val2::ParseNumber(val2::FormatFixed(percent, val2::kPercentDecimals), &printed) ||
      printed <= 0.0) {
    last_error_ = "speed fraction outside (0, 1]: " + std::to_string(fraction);
    return Status::kRejected;
  }
  return Command(val2::Encode(val2::SpeedCommand(percent)), false, false);
}

Status Val2Arm::Stop() { return Command(val2::Encode(val2::AbortCommand()), true, true); }

void Val2Arm::StopAtOnce() {
  if (silent_since_ && !blind_in_this_stop_) {
    blind_in_this_stop_ = true;
    // ^U empties the console's line of whatever a lost exchange left on it.
    // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "\x15" + std::string.
    std::string blind(1, '\x15');
    blind.append(val2::Encode(val2::AbortCommand())).append("\r");
    const Status s = link_->Write(std::span<const std::uint8_t>(
        reinterpret_cast<const std::uint8_t*>(blind.data()), blind.size()));
    if (s == Status::kOk) {
      ++counters_.blind_aborts;
      command_log_.Unconfirmed(val2::Encode(val2::AbortCommand()));  // nothing answers it
      blind_typed_ = true;
    }
    known_ = false;  // what the line holds now is unknown: the next exchange finds out
  }
}

Status Val2Arm::SafeStop() {
  StopAtOnce();
  blind_in_this_stop_ = false;
  return Stop();
}

Status Val2Arm::Ready() { return Command(val2::Encode(val2::ReadyCommand()), false, true); }

// ---------------------------------------------------------------------------------------------
// Commands.

Status Val2Arm::Command(const std::string& line, bool is_stop, bool is_motion,
                        const Motion* motion) {
  CallClock call = StartCall();
  Status s = DrainStale();
  if (s != Status::kOk) return Fail(s);
  if (lost_) {
    s = Recover(&call);
    if (s != Status::kOk) return Fail(s);
    if (is_stop) return Status::kOk;  // the recovery's ABORT was this stop
  }
  if (needs_read_ && !is_stop) {
    last_error_ = "link was lost: Read() the arm before moving it";
    return Status::kDisconnected;
  }
  // A failed command found executed by a Read since: this call is its retry.
  const std::optional<std::string> record = std::exchange(executed_record_, std::nullopt);
  if (record && *record == line) {
    ++counters_.resolved_retries;
    ++counters_.commands;
    if (is_motion) motion_since_read_ = true;
    return Status::kOk;
  }
  bool resume = false;
  if (pending_) {
    if (*pending_ == line) {
      resume = true;  // the retry of the failed call: complete it, never repeat it
    } else {
      bool ran = false;
      s = Dispose(*pending_, &call, &ran);
      if (s != Status::kOk) return Fail(s);
      if (ran) {
        Ran(*pending_, /*inferred=*/true);
      } else {
        ++counters_.cancelled_pending;
      }
    }
    pending_.reset();
  }
  LineOutcome out;
  // Settled by the arm when its answer is lost whole: a move WHERE sees, from a rest.
  const bool check = motion && is_motion && at_rest_ && !motion_since_read_ && Checkable(*motion);
  s = Drive(line, /*state_changing=*/true, resume, &call, &out, check ? motion : nullptr);
  if (s == Status::kOk) {
    Ran(line, /*inferred=*/!out.output_known);
    blind_typed_ = false;
    if (resume && !out.output_known) ++counters_.resolved_retries;
    ++counters_.commands;
    if (is_motion) motion_since_read_ = true;
    return s;
  }
  if (s == Status::kRejected || s == Status::kBadReply) return s;
  return Fail(s);
}

Status Val2Arm::Drive(const std::string& line, bool state_changing, bool resume, CallClock* call,
                      LineOutcome* outcome, const Motion* check_motion) {
  *outcome = LineOutcome{};
  DriveState d{line, state_changing, check_motion, call, outcome, /*armed=*/resume};
  for (;;) {
    if (clock_->Now() >= call->Deadline()) {
      if (state_changing && d.armed) pending_ = line;
      if (opt_.trace) opt_.trace("timeout; armed " + std::to_string(d.armed));
      return Status::kTimeout;
    }
    Keys keys;
    keys.timeout_s = opt_.reply_timeout_s;
    Status s = Status::kOk;
    Turn turn = NextKeys(&d, &keys, &s);
    if (turn == Turn::kAgain) continue;
    if (turn == Turn::kDone) return s;
    d.suspect = keys.probe_again ? d.suspect + 1 : 0;
    turn = TakeAnswer(&d, keys, &s);
    if (turn == Turn::kDone) return s;
  }
}

Val2Arm::Turn Val2Arm::NextKeys(DriveState* d, Keys* k, Status* s) {
  const std::string& line = d->line;
  k->armed_before = d->armed;
  const bool gone_again = d->gone_once;
  d->gone_once = false;
  // The line has left the controller's input. Not when a retype shows the start of the line:
  // a line that ran leaves the input empty, so that is a retype cut short by a dropout (bug
  // fix, found by a simulated line's seed: "^R" damaged on its way back and cut short read as
  // a run, and the command was reported done and lost). Unless two more looks show the same
  // start after a trace of a run: no dropout cuts three retypes alike, so stray characters
  // came after the run. (Bug fix, soak seed 12 with inserted bytes: a 'D' put into the empty
  // line after the run, taken as the command's start, was typed on and ran the command twice.)
  const bool start_shown = !RTrim(buf_).empty() && StartsWith(line, buf_);
  const bool gone = known_ && Gone(buf_, line) &&
                    (!start_shown || (d->armed && d->execution_trace && d->suspect >= 2));
  if (!known_) {
    k->send = val2::kCtrlR;  // what does the controller hold?
    ++counters_.probes;
    if (d->armed && std::find(guesses_.begin(), guesses_.end(), line) == guesses_.end()) {
      guesses_.push_back(line);
    }
  } else if (d->armed && gone) {
    return GoneLine(d, gone_again, k, s);
  } else if (buf_ == line) {
    d->armed = true;
    if (d->state_changing && !d->verified) {
      k->send = val2::kCtrlR;  // check the whole line once more before it runs
      k->expected = val2::RetypeEcho(buf_);
      ++counters_.probes;
    } else {
      k->send = val2::kCr;
      k->expected = std::string("\r\n") + val2::kPrompt;
    }
  } else if (RTrim(buf_) == line) {
    k->send = val2::kDel;  // the command and a blank (which VAL would ignore): rub it out
    k->expected = std::string(val2::kRuboutEcho);
    ++counters_.rubouts;
  } else if (d->armed && d->suspect < 2) {
    k->send = val2::kCtrlR;  // not the command, if this retype is right: look again
    k->expected = val2::RetypeEcho(line);
    k->probe_again = true;
    ++counters_.probes;
  } else {
    // The controller holds something else than the command (seen more than once): it cannot
    // run as the command. Type on, rub out, or start again.
    d->armed = false;
    TypeTowards(d, k);
  }
  return Turn::kSend;
}

Val2Arm::Turn Val2Arm::GoneLine(DriveState* d, bool gone_again, Keys* k, Status* s) {
  if (d->cancel_trace && !d->execution_trace && !d->check_motion) {
    d->armed = false;  // gone, and the answers show a cancel and no execution: it did not run
    return Turn::kAgain;
  }
  if (d->message_trace && !d->check_motion) {
    // Gone, and an answer too damaged to classify held a message: the line that ran printed
    // it, so it was not the command (which runs silently; a CR damaged into a character had
    // left it with a character more) or the command refused. It did not take effect: typed
    // again. (Taken as the command's silent run, the command was reported done and lost.)
    d->armed = false;
    return Turn::kAgain;
  }
  if (d->state_changing && !d->execution_trace && !gone_again) {
    // Gone with no trace of a run: the line ran with its answer lost, or a retype's answer
    // was cut short by a dropout after its prompt ("^R" CR LF "." is also the retype of an
    // empty line). Ask once more before taking it as run. (Bug fix, found by a simulated
    // line's seed: the ^R that checks a typed command before its CR came back cut short; the
    // driver took the command as run, reported it done, and cancelled it on the next call.)
    d->gone_once = true;
    k->send = val2::kCtrlR;
    k->expected = val2::RetypeEcho("");
    ++counters_.probes;
    return Turn::kSend;
  }
  // The line has left the controller's input (seen twice, or with a trace of a run): it
  // ran, and its answer was lost. (A line that never ran is still there, give or take a
  // corrupted byte or two.)
  if (!d->state_changing) {
    d->armed = false;  // WHERE: just ask again
    return Turn::kAgain;
  }
  if (d->check_motion) {
    // The whole answer lost: a silent run, a refusal's message or a cancel's echo look
    // the same, and so do the traces of damaged answers. The arm rested and the move is
    // visible: WHERE tells, whatever the traces.
    bool moved = false;
    const Status ms = MovedFromRest(clock_->Now(), *d->check_motion, d->call, &moved);
    if (ms != Status::kOk) {
      pending_ = d->line;  // a retry resumes it, and checks again
      *s = ms;
      return Turn::kDone;
    }
    ++counters_.motion_checks;
    if (!moved) {
      ++counters_.unrun_found;
      if (opt_.trace) opt_.trace("gone, but the arm still rests: not run, typed again");
      d->armed = false;
      return Turn::kAgain;
    }
  }
  d->outcome->executed = true;
  d->outcome->output_known = false;
  *s = Status::kOk;
  return Turn::kDone;
}

void Val2Arm::TypeTowards(DriveState* d, Keys* k) {
  const std::string& line = d->line;
  if (StartsWith(line, buf_)) {
    // A command's last character goes alone, once the rest is known to be right: with the
    // rest typed in chunks, a damaged chunk can leave the line wrong but never complete (no
    // part of a command is a command), so a stray CR cannot run it.
    const std::size_t rest = line.size() - buf_.size();
    const std::size_t n = !d->state_changing ? rest : rest > 1 ? std::min(rest - 1, kChunk) : 1;
    k->send = line.substr(buf_.size(), n);
    k->expected = k->send;
    k->timeout_s = opt_.echo_timeout_s;
    if (buf_.size() + n == line.size()) d->armed = true;
    counters_.typed += static_cast<long>(n);
  } else if (buf_.size() - CommonPrefix(buf_, line) <= kChunk) {
    const std::size_t n = buf_.size() - CommonPrefix(buf_, line);
    k->send = std::string(n, val2::kDel);  // wrong characters at the end
    for (std::size_t j = 0; j < n; ++j) k->expected += val2::kRuboutEcho;
    counters_.rubouts += static_cast<long>(n);
  } else {
    k->send = val2::kCtrlU;  // start the line again
    k->expected = val2::CancelEcho();
    ++counters_.cancels;
  }
}

Val2Arm::Turn Val2Arm::TakeAnswer(DriveState* d, const Keys& k, Status* s) {
  Reaction r;
  std::optional<std::string> ran;
  const std::string before = buf_;
  if (d->armed && !k.armed_before) {
    d->cancel_trace = d->execution_trace = d->message_trace = false;  // armed just now
  }
  const Status st = Step(k.send, k.expected, k.timeout_s, d->call, &r, &ran);
  // Late bytes of an earlier exchange read as an execution (see UnexplainedOutput).
  const bool foreign = st == Status::kOk && r.kind == Reaction::Kind::kExecuted && d->armed &&
                       d->state_changing && UnexplainedOutput(k.send, r);
  // The second look at a line found gone only asks whether it is still there: a damaged
  // answer to it ("^R" CR LF "." one byte off is a cancel's echo) is no trace of a cancel.
  if (d->armed && !d->gone_once && !foreign) {
    d->cancel_trace |= saw_cancel_;
    d->execution_trace |= saw_execution_;
    d->message_trace |= saw_message_;
  }
  if (st != Status::kOk) {
    if (d->state_changing && d->armed) pending_ = d->line;
    *s = st;
    return Turn::kDone;
  }
  if (r.kind == Reaction::Kind::kRetype) {
    d->verified = r.text == d->line;
  } else if (!known_ || buf_ != before) {
    d->verified = false;
  }
  // A cancel the driver did not send (it sends ^U only unarmed): line noise made one, or an
  // answer damaged in one byte reads as one (the retype of an empty line, "^R" CR LF ".", and a
  // cancel's echo, "^U" CR LF ".", differ in one byte). When the command may have run before,
  // the cancel does not say whether it did: for a move from rest WHERE tells (the line is gone,
  // below); otherwise it is taken as not run.
  if (r.kind == Reaction::Kind::kCancel && !(d->armed && d->check_motion) && !d->gone_once) {
    d->armed = false;
  }
  if (r.kind != Reaction::Kind::kExecuted) return Turn::kAgain;
  if (d->armed && d->gone_once) {
    // The second look at a line found gone ran what was left there (a ^R damaged into CR: an
    // empty line, or stray characters): it says nothing of the command, and the line is still
    // gone. Decided as the line found gone twice. (Bug fix, creeping-rest seed 165: taken as
    // an empty line run with nothing armed, the move that had run was typed again.)
    if (opt_.trace) opt_.trace("the second look ran what was left: still gone");
    return Turn::kAgain;
  }
  if (foreign) {
    // Not this byte's answer: late bytes of an earlier exchange (a call that gave up during a
    // WHERE), no trace of anything. The line is unknown, the command perhaps run. (Bug fix,
    // creeping-rest seed 100: a retry's first ^R read the report of the failed call's last
    // WHERE as a damaged line run; the move, which had run, was typed again.)
    if (opt_.trace) opt_.trace("an answer with output of no line run: late bytes");
    if (ran) guesses_ = {*ran, ""};
    known_ = false;
    return Turn::kAgain;
  }
  if (d->armed && d->check_motion && !ran && r.text.empty()) {
    // A line ran silently while the driver did not know what the controller held (a ^R
    // damaged into a CR, after a lost answer): the command, or an empty line left by its run
    // or by a cancel. The line is gone now: for a move from rest WHERE tells (below). (Bug fix,
    // creeping-rest seed 144 at 0.035 deg/s: taken as the command's run, a move cancelled by a
    // CR damaged into ^U was lost.)
    if (opt_.trace) opt_.trace("a line not known ran silently: gone, the arm tells");
    return Turn::kAgain;
  }
  return LineRan(d, r, ran, s);
}

Val2Arm::Turn Val2Arm::LineRan(DriveState* d, const Reaction& r,
                               const std::optional<std::string>& ran, Status* s) {
  // A line ran. Only the command itself (no part of it is a command; a damaged one is not a
  // command) or an empty line runs without a message: a success from a line that was not
  // empty (as far as the driver knew, or, not knowing, with the command complete) is the
  // command's.
  const bool was_line = ran ? !RTrim(*ran).empty() : d->armed;
  d->armed = false;
  d->verified = false;
  const std::string error = FirstError(r.text);
  if (!error.empty()) last_error_ = error;
  if (!d->state_changing) {
    if (!r.text.empty() && error.empty()) {
      d->outcome->executed = true;  // the caller parses it: anything else is asked again
      d->outcome->output = r.text;
      *s = Status::kOk;
      return Turn::kDone;
    }
    if (!error.empty() && ++d->errors >= opt_.max_errors) {
      *s = Status::kBadReply;
      return Turn::kDone;
    }
    return Turn::kAgain;  // a partial or garbled WHERE ran: it changes nothing, type it again
  }
  if (r.text.empty()) {
    if (!was_line) return Turn::kAgain;  // an empty line
    d->outcome->executed = true;
    *s = Status::kOk;
    return Turn::kDone;
  }
  // A message: the line changed nothing (the commands print nothing when they succeed). A
  // refusal (as opposed to "not understood") can only be the command's: it is the only valid
  // line. Any other message, or a damaged one, is taken as a damaged line and typed again.
  if (val2::IsRefusal(error)) {
    d->outcome->error = error;
    *s = Status::kRejected;  // refused by the controller (out of range, ...)
    return Turn::kDone;
  }
  if (++d->errors >= opt_.max_errors) {
    if (error.empty()) last_error_ = "unreadable answer: " + r.text;
    *s = Status::kBadReply;
    return Turn::kDone;
  }
  return Turn::kAgain;  // a partial or garbled line ran and was refused: type it again
}

bool Val2Arm::PastTheMove(const Motion& motion, double progress) const {
  // Only where the whole is the move's own length (a tool move whose rest location is not known
  // has a lower bound for its whole).
  const bool past = !std::isnan(progress) && (motion.joints_deg || located_) &&
                    std::abs(progress) > 2.0 * WholeProgress(motion) + 2.0;
  if (past && opt_.trace)
    opt_.trace("motion check: progress " + std::to_string(progress) + ", past");
  return past;
}

bool Val2Arm::Reachable(const std::array<double, 6>& from, double from_t,
                        const std::array<double, 6>& to, double to_t) const {
  for (int k = 0; k < 6; ++k) {
    const double allowed = opt_.max_joint_speed_deg_s[k] * (to_t - from_t) * 1.5 + 0.0015;
    if (std::abs(to[k] - from[k]) > allowed) return false;
  }
  return true;
}

Status Val2Arm::MovedFromRest(Clock::TimePoint since, const Motion& motion, CallClock* call,
                              bool* moved) {
  *moved = false;
  // On its way: past the threshold and half the move (a move that ran ends at its whole).
  const double on_way_at = std::max(1.0, 0.5 * WholeProgress(motion));
  int on_way = 0, short_of = 0, still = 0;           // reports in a row
  std::optional<std::array<double, 6>> last_joints;  // of the last report counted, and when
  double last_t = 0.0;
  // The rest's creep (deg/s): first the rate between the two Reads that found the rest, then
  // that between the check's last two still reports.
  std::array<double, 6> creep = rest_creep_deg_s_;
  std::array<double, 6> on_way_joints{};  // the last report counted, when on the way
  double on_way_t = 0.0;
  for (;;) {
    // The controller reads the joints when the WHERE runs, after it was asked.
    const Clock::TimePoint asked = clock_->Now();
    val2::WhereReport report;
    double t = 0.0;
    bool located = false;
    const Status s = Where(call, &report, &t, &located);
    if (s != Status::kOk) return s;
    double progress = Progress(motion, report, located);
    if (PastTheMove(motion, progress)) continue;  // a corrupted digit: in a row, not counted
    if (std::isnan(progress)) continue;           // a report that tells nothing: likewise
    // Short of half the move with the joints where the last report had them: at rest, a move
    // that had run would be at its end (a corrupted digit moves a joint: never still).
    bool at_rest = last_joints.has_value();
    const double allowed_deg = opt_.still_deg_s * (t - last_t);
    for (int k = 0; at_rest && k < 6; ++k) {
      at_rest = std::abs(report.joints[k] - (*last_joints)[k]) <= allowed_deg;
    }
    if (at_rest) {
      for (int k = 0; k < 6; ++k) creep[k] = (report.joints[k] - (*last_joints)[k]) / (t - last_t);
    }
    if (!motion.joints_deg && !located_) {
      // The joints' travel in any direction (the tool's rest location not known) counts the
      // creep since the rest too: taken away at the rest's rate (see `creep`). Taken away only
      // at a still pair, a check begun late (the line retyped through corruption) whose reports
      // were not still in pairs (a corrupted digit, or the creep's own rounding) counted the
      // creep since the rest whole, and took a cancelled move for run (creeping-rest seeds
      // at 0.035 deg/s).
      double travel = 0.0;
      for (int k = 0; k < 6; ++k) {
        travel += std::pow(report.joints[k] - prev_deg_[k] - creep[k] * (t - prev_t_), 2);
      }
      progress = std::sqrt(travel) / opt_.moved_deg;
    }
    if (opt_.trace) {
      opt_.trace("motion check: progress " + std::to_string(progress) + (at_rest ? ", still" : ""));
    }
    last_joints = report.joints;
    last_t = t;
    // On the way in two reports that the joints' speed limits allow one after the other (a digit
    // corrupted in each, far apart, took a cancelled move for run: creeping-rest seed 76).
    const bool along = on_way > 0 && Reachable(on_way_joints, on_way_t, report.joints, t);
    on_way = progress >= on_way_at ? (along ? on_way + 1 : 1) : 0;
    on_way_joints = report.joints;
    on_way_t = t;
    short_of = progress < 1.0 ? short_of + 1 : 0;
    still = progress < on_way_at && at_rest ? still + 1 : 0;
    if (on_way >= 2) {
      *moved = true;
      return Status::kOk;
    }
    if ((short_of >= 2 || still >= 2) && Clock::ToSeconds(asked - since) >= opt_.motion_start_s) {
      return Status::kOk;
    }
  }
}

Status Val2Arm::Dispose(const std::string& pending, CallClock* call, bool* executed) {
  *executed = false;
  bool armed = true;  // the pending line may be complete in the controller, or have run
  bool cancel_trace = false, execution_trace = false, message_trace = false;
  for (;;) {
    if (clock_->Now() >= call->Deadline()) return Status::kTimeout;
    std::string send;
    std::string expected;
    if (!known_) {
      send = val2::kCtrlR;
      ++counters_.probes;
      if (armed && std::find(guesses_.begin(), guesses_.end(), pending) == guesses_.end()) {
        guesses_.push_back(pending);
      }
    } else if (buf_.empty()) {
      // Gone without our cancelling it: it ran (unless the answers show only a cancel, or a
      // message: then what ran was not the command, see Drive).
      if (armed && !(cancel_trace && !execution_trace) && !message_trace) *executed = true;
      return Status::kOk;
    } else {
      if (armed && Gone(buf_, pending) && !(cancel_trace && !execution_trace) && !message_trace) {
        *executed = true;  // it ran; stray bytes since
      }
      armed = false;  // from here on the line is being cancelled, not run
      send = val2::kCtrlU;
      expected = val2::CancelEcho();
      ++counters_.cancels;
    }
    Reaction r;
    std::optional<std::string> ran;
    const Status s = Step(send, expected, opt_.reply_timeout_s, call, &r, &ran);
    if (s != Status::kOk) return s;
    if (armed && r.kind == Reaction::Kind::kExecuted && UnexplainedOutput(send, r)) {
      if (ran) guesses_ = {*ran, ""};
      known_ = false;  // late bytes of an earlier exchange, no trace of anything (as in Drive)
      continue;
    }
    if (armed) {
      cancel_trace |= saw_cancel_;
      execution_trace |= saw_execution_;
      message_trace |= saw_message_;
    }
    if (r.kind == Reaction::Kind::kExecuted) {
      const bool was_line = ran ? !RTrim(*ran).empty() : armed;
      if (was_line && r.text.empty()) *executed = true;  // only the command runs silently
      armed = false;
    }
  }
}

Status Val2Arm::Recover(CallClock* call) {
  const std::string abort_line = val2::Encode(val2::AbortCommand());
  bool resume = false;
  if (pending_) {
    if (*pending_ == abort_line) {
      resume = true;
    } else {
      bool ran = false;  // a command from before the loss never runs now
      const Status s = Dispose(*pending_, call, &ran);
      if (s != Status::kOk) return s;
      if (ran) {
        Ran(*pending_, /*inferred=*/true);  // it had run before the loss
      } else {
        ++counters_.cancelled_pending;
      }
    }
    pending_.reset();
  }
  executed_record_.reset();
  LineOutcome out;
  const Status s = Drive(abort_line, /*state_changing=*/true, resume, call, &out);
  if (s != Status::kOk) return s;
  Ran(abort_line, /*inferred=*/!out.output_known);
  ++counters_.safety_aborts;
  lost_ = false;
  needs_read_ = true;
  motion_since_read_ = true;
  silent_since_.reset();
  return Status::kOk;
}

// ---------------------------------------------------------------------------------------------
// Bytes.

Status Val2Arm::Step(const std::string& bytes, const std::string& expected, double timeout_s,
                     CallClock* call, Reaction* reaction,
                     std::optional<std::string>* executed_line) {
  executed_line->reset();
  const bool was_known = known_;
  const std::string before = buf_;
  Status s = link_->Write(std::span<const std::uint8_t>(
      reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
  if (s != Status::kOk) {
    known_ = false;
    return s;
  }
  std::string answer;
  s = ReadAnswer(WantedAnswer(bytes, expected, was_known), timeout_s, call, &answer);
  if (s != Status::kOk) {
    known_ = false;
    return s;
  }
  if (opt_.trace) {
    opt_.trace("sent " + Visible(bytes) + " got " + Visible(answer) + " (line " +
               (was_known ? Visible(before) : std::string("unknown")) + ")");
  }
  NoteTraces(bytes, answer);
  const bool typing = IsPrintable(bytes[0]);
  if (answer == expected && (typing || bytes.size() > 1 || bytes[0] == val2::kDel)) {
    // The exact echo of characters typed or rubbed out.
    reaction->kind = typing ? Reaction::Kind::kAppended : Reaction::Kind::kRubout;
    reaction->text = typing ? answer : "";
    if (typing) {
      buf_ += bytes;
    } else {
      buf_.resize(buf_.size() - std::min(buf_.size(), bytes.size()));
    }
    return Status::kOk;
  }
  if (typing) ++counters_.echo_mismatches;
  if (bytes.size() > 1) {
    // Several characters and not their echo: the line is unknown. (A chunk never completes a
    // command, so whatever it did, it did not run or cancel the command.)
    guesses_ = {before, before + (typing ? bytes : std::string())};
    if (typing && answer.size() == bytes.size()) guesses_.push_back(before + answer);
    *reaction = Reaction{Reaction::Kind::kGarbled, ""};
    known_ = false;
    return Status::kOk;
  }
  // One character, and not its expected answer: what did it do? (A typed character may have
  // arrived as a control character: ^U cancels the line, CR runs it.)
  *reaction = val2::ClassifyReaction(answer);
  if (typing && reaction->kind == Reaction::Kind::kAppended) {
    // Another character came back: the typed one or its echo was damaged.
    guesses_ = {before + bytes, before + reaction->text};
    *reaction = Reaction{Reaction::Kind::kGarbled, ""};
    known_ = false;
    return Status::kOk;
  }
  Believe(*reaction, typing ? before + bytes : before, was_known, before, executed_line);
  return Status::kOk;
}

Val2Arm::Expect Val2Arm::WantedAnswer(const std::string& bytes, const std::string& expected,
                                      bool was_known) const {
  // The answers that are complete as they stand: the expected one; a ^R's answer (the
  // expected retype or, asking what an unknown line holds, that of each likely line) once the
  // line is quiet.
  Expect want;
  if (!expected.empty()) want.exact.push_back(expected);
  if (bytes.size() == 1 && bytes[0] == val2::kCtrlR) {
    if (!was_known) {
      for (const std::string& g : guesses_) want.exact.push_back(val2::RetypeEcho(g));
    }
    want.retype = true;
  }
  // The echo of a chunk is taken at its length: a chunk cannot complete, run or cancel the
  // command, so a longer echo (a character damaged into a control character) only leaves bytes
  // that spoil the next answer, which is then asked again.
  if (bytes.size() > 1 && IsPrintable(bytes[0])) want.min_length = bytes.size();
  return want;
}

void Val2Arm::NoteTraces(const std::string& bytes, const std::string& answer) {
  // Traces of a cancel or an execution anywhere in the answer, for answers too damaged to
  // classify (a byte inserted into the line, say): the echo of ^U, or a CR LF that is not the
  // tail of a "^U" or "^R" echo.
  saw_cancel_ = answer.find("^U\r\n") != std::string::npos;
  saw_message_ = !FirstError(answer).empty();
  saw_execution_ = false;
  const bool retype_asked = bytes.size() == 1 && bytes[0] == val2::kCtrlR;
  for (std::size_t i = answer.find("\r\n"); i != std::string::npos;
       i = answer.find("\r\n", i + 1)) {
    if (!RetypeOrCancelBreak(answer, i, retype_asked)) saw_execution_ = true;
  }
}

void Val2Arm::Believe(const Reaction& reaction, const std::string& typed, bool was_known,
                      const std::string& before, std::optional<std::string>* executed_line) {
  switch (reaction.kind) {
    case Reaction::Kind::kNothing:
    case Reaction::Kind::kGarbled:
      if (known_) guesses_ = {before, typed, ""};
      known_ = false;
      break;
    case Reaction::Kind::kAppended:
      buf_ += reaction.text;  // it arrived as a printable character
      break;
    case Reaction::Kind::kRubout:
      if (!buf_.empty()) {
        buf_.pop_back();
      } else {
        known_ = false;
      }
      break;
    case Reaction::Kind::kBell:
      break;  // refused: the line is unchanged
    case Reaction::Kind::kCancel:
      known_ = true;
      buf_.clear();
      break;
    case Reaction::Kind::kRetype:
      if (!was_known &&
          std::find(guesses_.begin(), guesses_.end(), reaction.text) == guesses_.end() &&
          reaction.text != tentative_view_) {
        // An unexpected line, perhaps a damaged retype: believed once seen twice.
        tentative_view_ = reaction.text;
        break;
      }
      known_ = true;
      buf_ = reaction.text;
      tentative_view_.clear();
      break;
    case Reaction::Kind::kExecuted:
      if (was_known) *executed_line = before;
      known_ = true;
      buf_.clear();
      break;
  }
}

Status Val2Arm::ReadAnswer(const Expect& want, double first_byte_timeout_s, CallClock* call,
                           std::string* answer) {
  answer->clear();
  std::uint8_t buf[512];
  double wait = first_byte_timeout_s;
  for (;;) {
    const double left = Clock::ToSeconds(call->Deadline() - clock_->Now());
    const double t = std::max(0.0, std::min(wait, left));
    std::size_t n = 0;
    const Status s = link_->Read(buf, t, &n);
    if (s == Status::kDisconnected) return s;
    if (s != Status::kOk || n == 0) {
      if (answer->empty() && !silent_since_) {
        silent_since_ = clock_->Now() - Clock::FromSeconds(t);
      }
      return Status::kOk;  // quiet: the answer (perhaps none) is complete
    }
    silent_since_.reset();
    call->last_heard = clock_->Now();
    answer->append(reinterpret_cast<const char*>(buf), n);
    if (answer->size() > 4096) return Status::kOk;
    // A retype has no end mark. It is complete only when the line goes quiet: an answer as
    // long as the longest likely line may still go on, the line holding a character more (a CR
    // damaged into one). Taken as complete there, the check before a CR passed, the CR ran the
    // longer line, and the rest of the retype, read with the CR's answer, hid it: the twin's
    // VAL II ran "...),00" for "...),0". At 9600 baud the next character follows within 1 ms.
    if (!want.retype) {
      for (const std::string& c : want.exact) {
        if (*answer == c) return Status::kOk;
      }
    }
    if (want.min_length > 0 && answer->size() >= want.min_length) return Status::kOk;
    if (val2::AnswerComplete(*answer, "")) return Status::kOk;  // an execution and its prompt
    // A line being executed ("\r\n" echoed, nothing printed yet) may keep the controller busy
    // for a while; other answers are complete when the line goes quiet.
    const bool thinking = *answer == "\r\n";
    wait = thinking ? opt_.reply_timeout_s : opt_.quiet_s;
  }
}

Status Val2Arm::DrainStale() {
  std::uint8_t buf[512];
  for (int k = 0; k < 64; ++k) {
    std::size_t n = 0;
    const Status s = link_->Read(buf, 0.0, &n);
    if (s == Status::kDisconnected) return s;
    if (s != Status::kOk || n == 0) return Status::kOk;
    if (known_) guesses_ = {buf_, ""};
    known_ = false;  // a late answer: the line may have changed since
    silent_since_.reset();
  }
  return Status::kOk;
}

void Val2Arm::Ran(const std::string& line, bool inferred) {
  // After a blind ^U the line may have been emptied by it: a line found gone may have been
  // cancelled as well as run.
  if (inferred && blind_typed_) {
    command_log_.Unconfirmed(line);
  } else {
    command_log_.Executed(line);
  }
}

Status Val2Arm::Fail(Status s) {
  if (s == Status::kDisconnected) lost_ = true;
  if (silent_since_ && Clock::ToSeconds(clock_->Now() - *silent_since_) >= opt_.link_lost_s) {
    lost_ = true;
  }
  if (lost_ && s == Status::kTimeout) {
    // Report the first timeout as such; once the link counts as lost, say so.
    return Status::kDisconnected;
  }
  return s;
}

}  // namespace hgrasp::drivers
