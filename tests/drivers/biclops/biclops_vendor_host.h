#pragma once
/// @file A host program that talks to a Biclops the way TRACLabs' libBiclops / libPMD does,
/// written from that library's public source (not copied from it): the same packets in the same
/// order for Biclops::Initialize (PMDController::ConfigureController, PMDAxisControl::
/// ConfigureHardware), Biclops::HomeAxes (PMDAxisControl::FindHome with homingMode bestWay:
/// FindHomeBestWay, FindIndex, FindHomeCenter), Biclops::Move (PreMove, SendProfileToController,
/// MultiUpdate) with its motion-done wait (IsMotionDone: GetEventStatus) and position reads
/// (GetActualPosition). drivers/biclops/PROTOCOL.md names the files. It checks every reply the
/// way libPMD's PMDSerial::SendCommand does and fails on the first bad one, so that a test sees
/// what the vendor library would have seen.

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "biclops/pmd_codec.h"
#include "common/clock.h"
#include "serial/byte_link.h"

namespace hgrasp::drivers {

/// One axis as BiclopsDefault.cfg describes it (counts, counts/s, counts/s^2).
struct VendorAxisConfig {
  std::int32_t counts_per_encoder_cycle = 2000;
  std::int32_t encoder_cycles_per_axis_cycle = 6;
  std::int32_t range_of_motion = 12000;  ///< counts (libPMD rangeOfMotion: one axis cycle)
  std::int32_t home_sensor_width = 50;
  bool home_active_low = true;
  bool amp_active_low = true;
  double homing_vel = 1667.0, homing_acc = 333.0;                      ///< [homing profile]
  double run_vel = 5000.0, run_acc = 10000.0;                          ///< [run profile]
  std::array<std::uint16_t, 6> run_filter{100, 60, 150, 0, 0, 65535};  ///< kp kd ki kvff kaff kout
};

class VendorHost {
 public:
  /// `clock`: every time the host reads and every wait (its reply deadlines, its motion-done
  /// polls); a SimClock in simulated time (it must outlive the host).
  explicit VendorHost(std::unique_ptr<ByteLink> link, Clock& clock = Clock::Wall());

  /// Biclops::Initialize: the controller's version, memory and cycle time, then every axis'
  /// hardware configuration. False on the first refused or broken reply (error()).
  bool Initialize(const std::array<VendorAxisConfig, 3>& axes);
  /// Biclops::HomeAxes for tilt, verge and pan (Biclops' order), each axis' FindHome.
  bool HomeAxes();
  /// Biclops::Move for the axes in `mask`: profile per axis, one MultiUpdate, then the
  /// motion-done wait of every axis.
  bool Move(int mask, const std::array<std::int32_t, 3>& target_counts);
  /// GetActualPosition.
  bool ReadPosition(int axis, std::int32_t* counts);
  /// Sends raw bytes (an opcode libPMD does not know, say) and reads one reply of
  /// `reply_words` words: its status byte in *status.
  bool SendRaw(std::span<const std::uint8_t> bytes, int reply_words, std::uint8_t* status);

  const std::string& error() const { return error_; }
  /// Where each axis found its zero (counts from its start position).
  std::int32_t zero_position(int axis) const { return zero_[static_cast<std::size_t>(axis)]; }
  /// Packets sent, replies with a non-zero status.
  int packets() const { return packets_; }

 private:
  struct AxisState {
    VendorAxisConfig cfg;
    std::uint16_t event_status = 0;
    bool event_status_loaded = false;
    std::int32_t loaded_vel = 0;
    std::uint32_t loaded_acc = 0;
    bool loaded = false;
    std::int32_t pos = 0;
    double vel = 0.0, acc = 0.0;
  };
  /// PMDSerial::SendCommand: one packet, its reply checked; false and error() when broken or
  /// when the chip's status is not 0.
  bool Send(const pmd::Command& c, int result_words, pmd::Reply* reply = nullptr);
  bool Word(int axis, std::uint8_t op, std::uint16_t w);
  bool Long(int axis, std::uint8_t op, std::uint32_t v);
  bool GetWord(int axis, std::uint8_t op, std::uint16_t* w);
  bool GetLong(int axis, std::uint8_t op, std::int32_t* v);
  bool ConfigureHardware(int axis);
  bool FindHome(int axis);
  bool FindIndex(int axis, int move_dir, std::int32_t* index_pos);
  bool FindHomeCenter(int axis, int* move_dir, std::int32_t* center, std::int32_t ll,
                      std::int32_t ul);
  bool HomeAsserted(int axis, bool* asserted);
  bool PreMove(int axis);
  bool SendProfile(int axis);
  bool Move1(int axis, bool with_capture, bool* capture_seen);
  bool WaitMotionDone(int axis, bool include_capture);

  std::unique_ptr<ByteLink> link_;
  Clock* clock_;
  std::array<AxisState, 3> axis_{};
  std::array<std::int32_t, 3> zero_{};
  double cycle_s_ = 0.0;
  std::string error_;
  int packets_ = 0;
};

}  // namespace hgrasp::drivers
