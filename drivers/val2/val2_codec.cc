#include "val2/val2_codec.h"

#include <Eigen/Geometry>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace hgrasp::drivers::val2 {
namespace {

bool IsPrintable(char c) { return c >= 0x20 && c <= 0x7E; }

char Upper(char c) { return static_cast<char>(std::toupper(static_cast<unsigned char>(c))); }

// Number of differing bytes between two strings of equal length (else a large number).
std::size_t Distance(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return 1000;
  std::size_t d = 0;
  for (std::size_t i = 0; i < a.size(); ++i) d += a[i] != b[i];
  return d;
}

// A cursor over a command line: keywords, punctuation and numbers, with VAL's optional spaces.
class Scanner {
 public:
  explicit Scanner(std::string_view s) : s_(s) {}

  void SkipSpaces() {
    while (i_ < s_.size() && s_[i_] == ' ') ++i_;
  }
  bool AtEnd() {
    SkipSpaces();
    return i_ == s_.size();
  }
  // A keyword (case-insensitive), which must not run on into a letter, digit or '.'.
  bool Keyword(std::string_view word) {
    SkipSpaces();
    if (s_.size() - i_ < word.size()) return false;
    for (std::size_t k = 0; k < word.size(); ++k) {
      if (Upper(s_[i_ + k]) != word[k]) return false;
    }
    const std::size_t end = i_ + word.size();
    if (end < s_.size()) {
      const char c = s_[end];
      if (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_') return false;
    }
    i_ = end;
    return true;
  }
  bool Punct(char c) {
    SkipSpaces();
    if (i_ < s_.size() && s_[i_] == c) {
      ++i_;
      return true;
    }
    return false;
  }
  // A name (letters, digits, '.', '_', '#'), for the "undefined value" message.
  bool Name() {
    SkipSpaces();
    const std::size_t start = i_;
    while (i_ < s_.size()) {
      const char c = s_[i_];
      if (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '#') {
        ++i_;
      } else {
        break;
      }
    }
    return i_ > start;
  }
  bool Number(double* v) {
    SkipSpaces();
    const std::size_t start = i_;
    if (i_ < s_.size() && s_[i_] == '-') ++i_;
    while (i_ < s_.size() && (std::isdigit(static_cast<unsigned char>(s_[i_])) || s_[i_] == '.')) {
      ++i_;
    }
    if (!ParseNumber(s_.substr(start, i_ - start), v)) {
      i_ = start;
      return false;
    }
    return true;
  }
  // Six numbers separated by commas, inside parentheses.
  bool SixNumbers(std::array<double, 6>* v) {
    if (!Punct('(')) return false;
    for (int k = 0; k < 6; ++k) {
      if (k > 0 && !Punct(',')) return false;
      if (!Number(&(*v)[k])) return false;
    }
    return Punct(')');
  }

 private:
  std::string_view s_;
  std::size_t i_ = 0;
};

std::string Join6(const std::array<double, 6>& v, const int decimals[6]) {
  std::string s;
  for (int k = 0; k < 6; ++k) {
    if (k > 0) s += ',';
    s += FormatFixed(v[k], decimals[k]);
  }
  return s;
}

constexpr int kTransDecimals[6] = {kMmDecimals,  kMmDecimals,  kMmDecimals,
                                   kDegDecimals, kDegDecimals, kDegDecimals};
constexpr int kJointDecimals[6] = {kDegDecimals, kDegDecimals, kDegDecimals,
                                   kDegDecimals, kDegDecimals, kDegDecimals};

std::array<double, 6> TransArray(const Trans& t) { return {t.x, t.y, t.z, t.o, t.a, t.t}; }
Trans ArrayTrans(const std::array<double, 6>& v) { return {v[0], v[1], v[2], v[3], v[4], v[5]}; }

std::string EncodeTerms(const std::vector<LocationTerm>& terms) {
  std::string s;
  for (std::size_t k = 0; k < terms.size(); ++k) {
    if (k > 0) s += ':';
    if (terms[k].here) {
      s += "HERE";
    } else {
      s += "TRANS(" + Join6(TransArray(terms[k].trans), kTransDecimals) + ")";
    }
  }
  return s;
}

// A compound transformation: term (':' term)*, term = HERE | TRANS(6 numbers). Sets *error for a
// name that is neither (VAL would look it up as a variable: none is defined here).
bool ParseTerms(Scanner* sc, std::vector<LocationTerm>* terms, std::string* error) {
  do {
    LocationTerm term;
    if (sc->Keyword("HERE")) {
      term.here = true;
    } else if (sc->Keyword("TRANS")) {
      std::array<double, 6> v;
      if (!sc->SixNumbers(&v)) {
        *error = kErrInvalidArgument;
        return false;
      }
      term.trans = ArrayTrans(v);
    } else if (sc->Name()) {
      *error = kErrUndefinedValue;
      return false;
    } else {
      *error = sc->AtEnd() ? kErrMissingArgument : kErrInvalidArgument;
      return false;
    }
    terms->push_back(term);
  } while (sc->Punct(':'));
  return true;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

std::string FormatFixed(double value, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, value);
  return buf;
}

bool ParseNumber(std::string_view text, double* value) {
  std::size_t i = 0;
  if (i < text.size() && text[i] == '-') ++i;
  const std::size_t int_start = i;
  while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) ++i;
  if (i == int_start) return false;
  std::size_t digits = i - int_start;
  if (i < text.size() && text[i] == '.') {
    ++i;
    const std::size_t frac_start = i;
    while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) ++i;
    if (i == frac_start) return false;
    digits += i - frac_start;
  }
  if (i != text.size() || digits > 15) return false;
  const std::string copy(text);
  *value = std::strtod(copy.c_str(), nullptr);
  return true;
}

Eigen::Matrix3d OatToRotation(double o_deg, double a_deg, double t_deg) {
  using Eigen::AngleAxisd;
  using Eigen::Vector3d;
  return (AngleAxisd(DegToRad(o_deg), Vector3d::UnitZ()) *
          AngleAxisd(DegToRad(a_deg), Vector3d::UnitY()) *
          AngleAxisd(DegToRad(t_deg), Vector3d::UnitZ()))
      .toRotationMatrix();
}

void RotationToOat(const Eigen::Matrix3d& R, double* o_deg, double* a_deg, double* t_deg) {
  // R = RZ(O) RY(A) RZ(T): R(2,2) = cos A, R(0,2) = cos O sin A, R(1,2) = sin O sin A,
  // R(2,0) = -sin A cos T, R(2,1) = sin A sin T.
  const double s = std::hypot(R(0, 2), R(1, 2));
  const double a = std::atan2(s, R(2, 2));
  double o, t;
  if (s > 1e-9) {
    o = std::atan2(R(1, 2), R(0, 2));
    t = std::atan2(R(2, 1), -R(2, 0));
  } else if (R(2, 2) > 0) {
    // A = 0: R = RZ(O + T); take O = 0.
    o = 0.0;
    t = std::atan2(R(1, 0), R(0, 0));
  } else {
    // A = 180: R(0,0) = -cos(O - T), R(1,0) = -sin(O - T); take O = 0.
    o = 0.0;
    t = std::atan2(R(1, 0), -R(0, 0));
  }
  auto wrap = [](double rad) {
    double deg = RadToDeg(rad);
    if (deg <= -180.0) deg += 360.0;
    if (deg > 180.0) deg -= 360.0;
    return deg;
  };
  *o_deg = wrap(o);
  *a_deg = RadToDeg(a);
  *t_deg = wrap(t);
}

Trans PoseToTrans(const Pose3& X) {
  Trans t;
  t.x = X.translation().x() * 1000.0;
  t.y = X.translation().y() * 1000.0;
  t.z = X.translation().z() * 1000.0;
  RotationToOat(X.linear(), &t.o, &t.a, &t.t);
  return t;
}

Pose3 TransToPose(const Trans& t) {
  Pose3 X = Pose3::Identity();
  X.linear() = OatToRotation(t.o, t.a, t.t);
  X.translation() = Eigen::Vector3d(t.x, t.y, t.z) / 1000.0;
  return X;
}

Trans RoundForWire(const Trans& t) {
  std::array<double, 6> v = TransArray(t);
  for (int k = 0; k < 6; ++k) ParseNumber(FormatFixed(v[k], kTransDecimals[k]), &v[k]);
  return ArrayTrans(v);
}

// ---------------------------------------------------------------------------------------------

std::string Encode(const Command& c) {
  switch (c.kind) {
    case CommandKind::kWhere:
      return "WHERE";
    case CommandKind::kSpeed:
      return "SPEED (" + FormatFixed(c.value, kPercentDecimals) + ")";
    case CommandKind::kMove:
      if (c.precision_point) return "DO MOVE #PPOINT(" + Join6(c.joints, kJointDecimals) + ")";
      return "DO MOVE " + EncodeTerms(c.terms);
    case CommandKind::kAppro:
      return "DO APPRO " + EncodeTerms(c.terms) + "," + FormatFixed(c.value, 0);
    case CommandKind::kReady:
      return "DO READY";
    case CommandKind::kAbort:
      return "ABORT";
  }
  return "";
}

Command WhereCommand() { return Command{}; }

Command SpeedCommand(double percent) {
  Command c;
  c.kind = CommandKind::kSpeed;
  c.value = percent;
  return c;
}

Command MoveJointsCommand(const std::array<double, 6>& joints_deg) {
  Command c;
  c.kind = CommandKind::kMove;
  c.precision_point = true;
  c.joints = joints_deg;
  return c;
}

Command MoveRelativeCommand(const Trans& delta) {
  Command c;
  c.kind = CommandKind::kAppro;
  c.terms = {LocationTerm{true, {}}, LocationTerm{false, delta}};
  c.value = 0.0;
  return c;
}

Command MoveToCommand(const Trans& location) {
  Command c;
  c.kind = CommandKind::kMove;
  c.terms = {LocationTerm{false, location}};
  return c;
}

Command ReadyCommand() {
  Command c;
  c.kind = CommandKind::kReady;
  return c;
}

Command AbortCommand() {
  Command c;
  c.kind = CommandKind::kAbort;
  return c;
}

bool ParseCommand(std::string_view line, Command* command, std::string* error) {
  *command = Command{};
  if (line.size() > kMaxLineLength) {
    *error = kErrLineTooLong;
    return false;
  }
  Scanner sc(line);
  Command c;
  if (sc.Keyword("WHERE")) {
    c.kind = CommandKind::kWhere;
  } else if (sc.Keyword("ABORT")) {
    c.kind = CommandKind::kAbort;
  } else if (sc.Keyword("SPEED")) {
    c.kind = CommandKind::kSpeed;
    if (sc.AtEnd()) {
      *error = kErrMissingArgument;
      return false;
    }
    // A real-valued expression: here a number, bare or in parentheses.
    const bool paren = sc.Punct('(');
    if (!sc.Number(&c.value) || (paren && !sc.Punct(')'))) {
      *error = kErrInvalidArgument;
      return false;
    }
  } else if (sc.Keyword("DO")) {
    if (sc.Keyword("READY")) {
      c.kind = CommandKind::kReady;
    } else if (sc.Keyword("MOVE")) {
      c.kind = CommandKind::kMove;
      if (sc.AtEnd()) {
        *error = kErrMissingArgument;
        return false;
      }
      if (sc.Keyword("#PPOINT")) {
        c.precision_point = true;
        if (!sc.SixNumbers(&c.joints)) {
          *error = kErrInvalidArgument;
          return false;
        }
      } else if (!ParseTerms(&sc, &c.terms, error)) {
        return false;
      }
    } else if (sc.Keyword("APPRO")) {
      c.kind = CommandKind::kAppro;
      if (sc.AtEnd()) {
        *error = kErrMissingArgument;
        return false;
      }
      if (!ParseTerms(&sc, &c.terms, error)) return false;
      if (!sc.Punct(',')) {
        *error = sc.AtEnd() ? kErrMissingArgument : kErrInvalidArgument;
        return false;
      }
      if (sc.AtEnd()) {
        *error = kErrMissingArgument;
        return false;
      }
      if (!sc.Number(&c.value)) {
        *error = kErrInvalidArgument;
        return false;
      }
    } else {
      *error = sc.AtEnd() ? kErrMissingArgument : kErrUnknownCommand;
      return false;
    }
  } else {
    *error = kErrUnknownCommand;
    return false;
  }
  if (!sc.AtEnd()) {
    *error = kErrInvalidArgument;
    return false;
  }
  *command = c;
  return true;
}

bool IsSyntaxError(std::string_view m) {
  return m == kErrUnknownCommand || m == kErrInvalidArgument || m == kErrMissingArgument ||
         m == kErrUndefinedValue || m == kErrLineTooLong;
}

bool IsRefusal(std::string_view m) { return m == kErrOutOfRange || m == kErrIllegalValue; }

std::string ErrorLine(std::string_view message) {
  std::string line;
  line.reserve(message.size() + 2);
  line += '*';
  line.append(message);
  line += '*';
  return line;
}

std::optional<std::string> ParseErrorLine(std::string_view line) {
  if (line.size() < 2 || line.front() != '*' || line.back() != '*') return std::nullopt;
  const std::string_view inner = line.substr(1, line.size() - 2);
  if (inner.find('*') != std::string_view::npos) return std::nullopt;
  return std::string(inner);
}

// ---------------------------------------------------------------------------------------------

LineDiscipline::Event LineDiscipline::Feed(char b, std::string* echo, std::string* line) {
  if (b == kCr) {
    *echo += "\r\n";
    *line = buffer_;
    buffer_.clear();
    return Event::kExecute;
  }
  if (b == kLf) return Event::kIgnored;
  if (b == kCtrlU) {
    buffer_.clear();
    *echo += CancelEcho();
    return Event::kCancel;
  }
  if (b == kCtrlR) {
    *echo += RetypeEcho(buffer_);
    return Event::kRetype;
  }
  if (b == kDel || b == kBs) {
    if (buffer_.empty()) {
      *echo += kBel;
      return Event::kBell;
    }
    buffer_.pop_back();
    *echo += kRuboutEcho;
    return Event::kRubout;
  }
  if (IsPrintable(b) && buffer_.size() < kMaxLineLength) {
    buffer_ += b;
    *echo += b;
    return Event::kEcho;
  }
  *echo += kBel;
  return Event::kBell;
}

std::string CancelEcho() { return std::string("^U\r\n") + kPrompt; }

std::string RetypeEcho(std::string_view buffer) {
  return std::string("^R\r\n") + kPrompt + std::string(buffer);
}

// ---------------------------------------------------------------------------------------------

namespace {

constexpr int kFieldWidth = 10;

std::string Field(double v, int decimals) {
  std::string s = FormatFixed(v, decimals);
  if (s.size() < static_cast<std::size_t>(kFieldWidth)) {
    s.insert(0, static_cast<std::size_t>(kFieldWidth) - s.size(), ' ');
  }
  return s;
}

std::string Header(const char* const labels[6]) {
  std::string s;
  for (int k = 0; k < 6; ++k) {
    std::string l = labels[k];
    s += std::string(static_cast<std::size_t>(kFieldWidth) - l.size(), ' ') + l;
  }
  return s;
}

constexpr const char* kLocationLabels[6] = {"X", "Y", "Z", "O", "A", "T"};
constexpr const char* kJointLabels[6] = {"JT1", "JT2", "JT3", "JT4", "JT5", "JT6"};

bool ParseFields(const std::string& line, const int decimals[6], std::array<double, 6>* v) {
  if (line.size() != 6 * static_cast<std::size_t>(kFieldWidth)) return false;
  for (int k = 0; k < 6; ++k) {
    std::string_view f(line.data() + k * kFieldWidth, kFieldWidth);
    const std::size_t first = f.find_first_not_of(' ');
    if (first == std::string_view::npos) return false;
    const std::string_view num = f.substr(first);
    const std::size_t dot = num.find('.');
    if (dot == std::string_view::npos ||
        num.size() - dot - 1 != static_cast<std::size_t>(decimals[k])) {
      return false;
    }
    if (!ParseNumber(num, &(*v)[k])) return false;
    // Exactly what FormatWhere would print for this value (no leading zeros, "-0.000" only as
    // printf prints it).
    if (Field((*v)[k], decimals[k]) != std::string(f)) return false;
  }
  return true;
}

}  // namespace

std::array<std::string, 4> FormatWhere(const WhereReport& r) {
  std::array<std::string, 4> lines;
  lines[0] = Header(kLocationLabels);
  const std::array<double, 6> loc = TransArray(r.location);
  for (int k = 0; k < 6; ++k) lines[1] += Field(loc[k], kTransDecimals[k]);
  lines[2] = Header(kJointLabels);
  for (int k = 0; k < 6; ++k) lines[3] += Field(r.joints[k], kDegDecimals);
  return lines;
}

bool ParseWhereJoints(const std::string& values, std::array<double, 6>* joints) {
  return ParseFields(values, kJointDecimals, joints);
}

bool ParseWhereLocation(const std::string& values, Trans* location) {
  std::array<double, 6> loc;
  if (!ParseFields(values, kTransDecimals, &loc)) return false;
  *location = ArrayTrans(loc);
  return true;
}

bool ParseWhere(const std::array<std::string, 4>& lines, WhereReport* report) {
  if (lines[0] != Header(kLocationLabels) || lines[2] != Header(kJointLabels)) return false;
  std::array<double, 6> loc, joints;
  if (!ParseFields(lines[1], kTransDecimals, &loc)) return false;
  if (!ParseFields(lines[3], kJointDecimals, &joints)) return false;
  report->location = ArrayTrans(loc);
  report->joints = joints;
  return true;
}

// ---------------------------------------------------------------------------------------------

std::string EncodeUnit(const OutputUnit& u) {
  switch (u.kind) {
    case OutputUnit::Kind::kLine:
      return u.text + "\r\n";
    case OutputUnit::Kind::kPrompt:
      return std::string(1, kPrompt);
    case OutputUnit::Kind::kFragment:
      return u.text;
  }
  return "";
}

void OutputDecoder::Feed(std::string_view bytes) {
  for (char b : bytes) {
    if (at_line_start_ && pending_.empty() && b == kPrompt) {
      ready_.push_back({OutputUnit::Kind::kPrompt, ""});
      continue;
    }
    pending_ += b;
    at_line_start_ = false;
    if (pending_.size() >= 2 && pending_[pending_.size() - 2] == kCr && pending_.back() == kLf) {
      pending_.resize(pending_.size() - 2);
      ready_.push_back({OutputUnit::Kind::kLine, std::move(pending_)});
      pending_.clear();
      at_line_start_ = true;
    } else if (pending_.size() >= kMaxFragment && pending_.back() != kCr) {
      ready_.push_back({OutputUnit::Kind::kFragment, std::move(pending_)});
      pending_.clear();
    }
  }
}

bool OutputDecoder::Next(OutputUnit* unit) {
  if (next_ >= ready_.size()) {
    ready_.clear();
    next_ = 0;
    return false;
  }
  *unit = std::move(ready_[next_++]);
  return true;
}

bool OutputDecoder::Flush(OutputUnit* unit) {
  if (Next(unit)) return true;
  if (pending_.empty()) return false;
  *unit = {OutputUnit::Kind::kFragment, std::move(pending_)};
  pending_.clear();
  return true;
}

// ---------------------------------------------------------------------------------------------

Reaction ClassifyReaction(std::string_view a) {
  Reaction r;
  if (a.empty()) return r;  // kNothing
  if (a.size() == 1) {
    if (a[0] == kBel) {
      r.kind = Reaction::Kind::kBell;
    } else if (IsPrintable(a[0])) {
      r.kind = Reaction::Kind::kAppended;
      r.text = std::string(a);
    } else {
      r.kind = Reaction::Kind::kGarbled;
    }
    return r;
  }
  // Fixed answers, recognised with at most one byte corrupted. Their lengths differ, except
  // "\r\n." and "\b \b", which differ in all three bytes.
  static const std::string kExecutedEmpty = std::string("\r\n") + kPrompt;
  if (Distance(a, kExecutedEmpty) <= 1) {
    r.kind = Reaction::Kind::kExecuted;
    return r;
  }
  if (Distance(a, kRuboutEcho) <= 1) {
    r.kind = Reaction::Kind::kRubout;
    return r;
  }
  static const std::string kCancel = CancelEcho();
  static const std::string kRetypeHead = RetypeEcho("");
  // "^U\r\n." and an empty "^R\r\n." differ in one byte: only exact ones are told apart, and a
  // corrupted one is garbled (the caller asks again).
  if (a == kCancel) {
    r.kind = Reaction::Kind::kCancel;
    return r;
  }
  if (a.size() >= kRetypeHead.size() &&
      (a.substr(0, kRetypeHead.size()) == kRetypeHead ||
       (a.size() > kRetypeHead.size() &&
        Distance(a.substr(0, kRetypeHead.size()), kRetypeHead) <= 1 &&
        Distance(a.substr(0, kRetypeHead.size()), kCancel) > 1))) {
    r.kind = Reaction::Kind::kRetype;
    r.text = std::string(a.substr(kRetypeHead.size()));
    for (char c : r.text) {
      if (!IsPrintable(c)) {
        r.kind = Reaction::Kind::kGarbled;
        r.text.clear();
        return r;
      }
    }
    return r;
  }
  // One byte off a cancel's echo, and not one byte off an empty retype: "^" and a damaged letter
  // is either. (Taken for a cancel, an empty retype damaged in its letter made the driver take a
  // command that had run, its answer damaged, for cancelled, and type it again: it ran twice.)
  if (Distance(a, kCancel) <= 1 && Distance(a, kRetypeHead) > 1) {
    r.kind = Reaction::Kind::kCancel;
    return r;
  }
  // An executed line with output: "\r\n" <lines, each ending CR LF> ".".
  if (a.size() >= 5 && a.substr(0, 2) == "\r\n" && a.substr(a.size() - 3) == "\r\n." &&
      a[2] != kPrompt) {
    r.kind = Reaction::Kind::kExecuted;
    r.text = std::string(a.substr(2, a.size() - 3));
    return r;
  }
  r.kind = Reaction::Kind::kGarbled;
  return r;
}

bool AnswerComplete(std::string_view answer, std::string_view expected) {
  if (answer == expected) return true;
  return answer.size() >= 3 && answer.substr(0, 2) == "\r\n" &&
         answer.substr(answer.size() - 3) == "\r\n." &&
         (answer.size() == 3 || answer[2] != kPrompt);
}

}  // namespace hgrasp::drivers::val2
