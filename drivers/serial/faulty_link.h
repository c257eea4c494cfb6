#pragma once
/// @file A ByteLink decorator that damages traffic the way a noisy serial line does, for the
/// fault-injection tests: corrupted bytes, inserted garbage, dropouts (both directions silent
/// for a while) and a cut cable. Every draw comes from the seed.

#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <random>
#include <span>
#include <vector>

#include "common/clock.h"
#include "serial/byte_link.h"

namespace hgrasp::drivers {

struct FaultPlan {
  double corrupt_probability = 0.0;  ///< per byte and direction: replaced by another value
  double garbage_probability = 0.0;  ///< per byte and direction: a random byte inserted after it
  double dropouts_per_s = 0.0;       ///< mean rate at which dropouts start (Poisson)
  double dropout_s = 0.2;            ///< length of a dropout: every byte, both ways, is lost
  /// The line works at least this long between two dropouts (s). At 0, a dropout may follow
  /// the last at once: two make one longer outage (0.4 s of two 0.2 s dropouts), which a driver
  /// rightly reports as a lost link.
  double min_dropout_gap_s = 0.0;
  std::uint64_t seed = 1;
};

struct FaultCounts {
  std::uint64_t bytes = 0;      ///< bytes that went through, both directions
  std::uint64_t corrupted = 0;  ///< of which altered
  std::uint64_t inserted = 0;   ///< garbage bytes added
  std::uint64_t dropped = 0;    ///< bytes lost in dropouts or to the cut
  std::uint64_t dropouts = 0;   ///< dropouts begun
};

/// The faults of one serial line, without the line: what FaultyLink does to the bytes that pass
/// it, for any code that moves bytes itself (the twin's device end of a line, SimLine). Dropouts
/// follow `clock` (the wall clock on a real line; the SimClock of a simulated one; it must
/// outlive this). Thread-safe.
class LineFaults {
 public:
  explicit LineFaults(const FaultPlan& plan, const Clock& clock = Clock::Wall());

  /// Passes `in` through the faults into *out (appended). `from_device`: the bytes travel from
  /// the device to the host (the direction CutFromDevice cuts).
  void Pass(std::span<const std::uint8_t> in, bool from_device, std::vector<std::uint8_t>* out);
  /// Cuts the cable (every byte lost from now on) or mends it.
  void Cut(bool cut);
  /// Cuts only the device's transmit wire or mends it.
  void CutFromDevice(bool cut);
  bool cut() const;
  FaultCounts counts() const;
  const FaultPlan& plan() const { return plan_; }

 private:
  bool InDropout(Clock::TimePoint now);

  FaultPlan plan_;
  const Clock* clock_;
  mutable std::mutex mu_;
  std::mt19937_64 rng_;
  bool cut_ = false;
  bool cut_from_device_ = false;
  Clock::TimePoint next_dropout_, dropout_end_;
  FaultCounts counts_;
};

class FaultyLink final : public ByteLink {
 public:
  FaultyLink(std::unique_ptr<ByteLink> inner, const FaultPlan& plan,
             const Clock& clock = Clock::Wall());

  device::Status Write(std::span<const std::uint8_t> bytes) override;
  device::Status Read(std::span<std::uint8_t> buf, double timeout_s, std::size_t* n) override;
  void Discard() override { inner_->Discard(); }

  /// Cuts the cable (every byte lost from now on) or mends it.
  void Cut(bool cut) { faults_.Cut(cut); }
  /// Cuts only the device's transmit wire (what the device sends is lost, what the host sends
  /// still arrives: a broken receive line at the host) or mends it.
  void CutFromDevice(bool cut) { faults_.CutFromDevice(cut); }
  FaultCounts counts() const { return faults_.counts(); }

 private:
  std::unique_ptr<ByteLink> inner_;
  const Clock* clock_;
  LineFaults faults_;
};

}  // namespace hgrasp::drivers
