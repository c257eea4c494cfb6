#pragma once
/// @file A ByteLink decorator that damages traffic the way a noisy serial line does, for the
/// fault-injection tests: corrupted bytes, inserted garbage, dropouts (both directions silent
/// for a while) and a cut cable. Every draw comes from the seed.

#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <random>
#include <vector>

#include "serial/byte_link.h"

namespace hgrasp::drivers {

struct FaultPlan {
  double corrupt_probability = 0.0;  ///< per byte and direction: replaced by another value
  double garbage_probability = 0.0;  ///< per byte and direction: a random byte inserted after it
  double dropouts_per_s = 0.0;       ///< mean rate at which dropouts start (Poisson)
  double dropout_s = 0.2;            ///< length of a dropout: every byte, both ways, is lost
  std::uint64_t seed = 1;
};

struct FaultCounts {
  std::uint64_t bytes = 0;      ///< bytes that went through, both directions
  std::uint64_t corrupted = 0;  ///< of which altered
  std::uint64_t inserted = 0;   ///< garbage bytes added
  std::uint64_t dropped = 0;    ///< bytes lost in dropouts or to the cut
  std::uint64_t dropouts = 0;   ///< dropouts begun
};

class FaultyLink final : public ByteLink {
 public:
  FaultyLink(std::unique_ptr<ByteLink> inner, const FaultPlan& plan);

  device::Status Write(std::span<const std::uint8_t> bytes) override;
  device::Status Read(std::span<std::uint8_t> buf, double timeout_s, std::size_t* n) override;
  void Discard() override { inner_->Discard(); }

  /// Cuts the cable (every byte lost from now on) or mends it.
  void Cut(bool cut);
  /// Cuts only the device's transmit wire (what the device sends is lost, what the host sends
  /// still arrives: a broken receive line at the host) or mends it.
  void CutFromDevice(bool cut);
  FaultCounts counts() const;

 private:
  using Clock = std::chrono::steady_clock;
  /// Passes `in` through the faults into *out.
  void Damage(std::span<const std::uint8_t> in, bool from_device, std::vector<std::uint8_t>* out);
  bool InDropout(Clock::time_point now);

  std::unique_ptr<ByteLink> inner_;
  FaultPlan plan_;
  mutable std::mutex mu_;
  std::mt19937_64 rng_;
  bool cut_ = false;
  bool cut_from_device_ = false;
  Clock::time_point next_dropout_, dropout_end_;
  FaultCounts counts_;
};

}  // namespace hgrasp::drivers
