// libFuzzer target of the VAL II console codec (drivers/val2/val2_codec.h): arbitrary bytes,
// in splits chosen by the input itself, through both sides' decoders:
//  - the driver's: OutputDecoder (lossless: its units re-encode to exactly the bytes fed),
//    ParseWhere (whatever it accepts, FormatWhere prints back exactly), ClassifyReaction and
//    AnswerComplete (no crash; a retype's line is printable);
//  - the emulator's: LineDiscipline (the line stays printable and at most kMaxLineLength) and
//    ParseCommand on every line it executes (whatever it accepts re-encodes canonically, and the
//    canonical text parses back to itself).
// Any violation traps.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "val2/val2_codec.h"

namespace {

using namespace hgrasp::drivers::val2;

void Check(bool ok) {
  if (!ok) __builtin_trap();
}

bool Small(const Command& c) {
  auto ok = [](double v) { return std::abs(v) < 1e6; };
  bool small = ok(c.value);
  for (double j : c.joints) small = small && ok(j);
  for (const LocationTerm& t : c.terms) {
    for (double v : {t.trans.x, t.trans.y, t.trans.z, t.trans.o, t.trans.a, t.trans.t}) {
      small = small && ok(v);
    }
  }
  return small;
}

void CheckCommand(std::string_view line) {
  Command c;
  std::string error;
  if (!ParseCommand(line, &c, &error)) {
    Check(!error.empty());
    return;
  }
  Check(line.size() <= kMaxLineLength);
  const std::string canonical = Encode(c);
  Command again;
  if (canonical.size() <= kMaxLineLength && Small(c)) {
    Check(ParseCommand(canonical, &again, &error));
    Check(Encode(again) == canonical);
    Check(again.kind == c.kind);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  const std::size_t step = size > 0 ? 1 + data[0] % 17 : 1;

  // Driver side: the controller's output, fed in pieces of `step` bytes.
  OutputDecoder dec;
  std::vector<OutputUnit> units;
  for (std::size_t i = 0; i < bytes.size(); i += step) {
    dec.Feed(std::string_view(bytes).substr(i, step));
    OutputUnit u;
    while (dec.Next(&u)) units.push_back(u);
  }
  OutputUnit u;
  while (dec.Flush(&u)) units.push_back(u);
  std::string rebuilt;
  for (const OutputUnit& x : units) {
    rebuilt += EncodeUnit(x);
    if (x.kind == OutputUnit::Kind::kLine) {
      Check(x.text.find("\r\n") == std::string::npos);
      if (auto m = ParseErrorLine(x.text)) Check(ErrorLine(*m) == x.text);
    }
  }
  Check(rebuilt == bytes);
  for (std::size_t k = 0; k + 3 < units.size(); ++k) {
    std::array<std::string, 4> lines;
    for (int m = 0; m < 4; ++m) lines[m] = units[k + m].text;
    WhereReport r;
    if (ParseWhere(lines, &r)) Check(FormatWhere(r) == lines);
  }
  const Reaction reaction = ClassifyReaction(bytes);
  if (reaction.kind == Reaction::Kind::kRetype) {
    for (char c : reaction.text) Check(c >= 0x20 && c <= 0x7E);
  }
  AnswerComplete(bytes, std::string_view(bytes).substr(0, size / 2));

  // Emulator side: the bytes typed at the console.
  LineDiscipline ld;
  std::string echo, line;
  for (char b : bytes) {
    echo.clear();
    if (ld.Feed(b, &echo, &line) == LineDiscipline::Event::kExecute) {
      Check(echo == "\r\n");
      CheckCommand(line);
    }
    Check(ld.buffer().size() <= kMaxLineLength);
    for (char c : ld.buffer()) Check(c >= 0x20 && c <= 0x7E);
  }
  CheckCommand(bytes);
  double v;
  if (ParseNumber(bytes, &v)) Check(std::isfinite(v));
  return 0;
}
