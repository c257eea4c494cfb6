// The devices block typed per backend: each driver's settings and every option of its Options
// struct reach the driver's configuration; a bad option is named with its line, value and range.

#include "config/device_config.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "common/error.h"
#include "common/yaml_file.h"

namespace hgrasp::drivers {
namespace {

DevicesConfig Parse(const std::string& text) {
  const yaml::Reader reader("devices.yaml");
  const YAML::Node root = yaml::LoadDocument(text, "devices.yaml", "a devices map");
  return ParseDevices(reader, root["devices"]);
}

InputError ErrorOf(const std::string& text) {
  try {
    Parse(text);
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return InputError("", "", "", "");
}

TEST(DeviceConfig, NothingListedIsAllSimulated) {
  const DevicesConfig c = Parse("devices: {}\n");
  EXPECT_TRUE(c.AllSimulated());
  EXPECT_TRUE(c.AnySimulated());
  for (std::string_view key : kDeviceKeys) EXPECT_TRUE(c.Simulated(key)) << key;
}

TEST(DeviceConfig, EveryDeviceRealIsNoneSimulated) {
  const DevicesConfig c = Parse(
      "devices:\n"
      "  arm_left: {driver: val2, port: /dev/ttyS0}\n"
      "  arm_right: {driver: val2, port: /dev/ttyS1}\n"
      "  hand_left: {driver: sensorhand, port: /dev/ttyS2}\n"
      "  hand_right: {driver: sensorhand, port: /dev/ttyS3}\n"
      "  head: {driver: biclops, port: /dev/ttyS4}\n"
      "  laser: {driver: laser_board, port: /dev/ttyUSB0}\n"
      "  leds: {driver: laser_board, port: /dev/ttyUSB0}\n"
      "  cameras: {driver: gstreamer, left: 'videotestsrc ! appsink', right: 'videotestsrc ! "
      "appsink'}\n");
  EXPECT_FALSE(c.AnySimulated());
  EXPECT_FALSE(c.AllSimulated());
  EXPECT_EQ(c.Find("head")->driver(), "biclops");
  EXPECT_EQ(c.Find("cameras")->driver(), "gstreamer");
  EXPECT_EQ(c.Find("cameras")->line, 9);
  EXPECT_EQ(c.Backend<SensorHandBackend>("hand_right")->serial.baud, 19200);  // its default
  EXPECT_EQ(c.Backend<LaserBoardBackend>("leds")->serial.baud, 115200);
  EXPECT_EQ(c.Backend<Val2Backend>("head"), nullptr);  // another driver's type
}

TEST(DeviceConfig, EveryDriverOptionReachesItsDriver) {
  const DevicesConfig c = Parse(
      "devices:\n"
      "  arm_right:\n"
      "    driver: val2\n"
      "    port: /dev/ttyS0\n"
      "    options: {reply_timeout_s: 0.25, max_errors: 7, confirm_reads: true,\n"
      "              max_joint_speed_deg_s: [10, 20, 30, 40, 50, 60], moved_mm: 0.8}\n"
      "  hand_left: {driver: sensorhand, port: /dev/ttyS2, options: {full_speed_m_s: 0.2}}\n"
      "  head:\n"
      "    driver: biclops\n"
      "    port: /dev/ttyS4\n"
      "    options: {silence_timeout_s: 0.6, max_resends: 3,\n"
      "              tilt: {min_rad: -0.5, max_rad: 0.7, max_speed_rad_s: 2.0}}\n"
      "  laser: {driver: laser_board, port: /dev/ttyUSB0, options: {call_timeout_s: 0.5}}\n"
      "  cameras: {driver: gstreamer, left: a ! appsink, right: b ! appsink,\n"
      "            options: {width: 640, height: 480, frame_timeout_s: 0.8,\n"
      "                      latch_pairing: offset, frame_offset: -2}}\n");
  const Val2Options& arm = c.Backend<Val2Backend>("arm_right")->options;
  EXPECT_EQ(arm.reply_timeout_s, 0.25);
  EXPECT_EQ(arm.max_errors, 7);
  EXPECT_TRUE(arm.confirm_reads);
  EXPECT_EQ(arm.max_joint_speed_deg_s[5], 60.0);
  EXPECT_EQ(arm.moved_mm, 0.8);
  EXPECT_EQ(arm.echo_timeout_s, Val2Options{}.echo_timeout_s);  // not named: the default
  EXPECT_EQ(c.Backend<SensorHandBackend>("hand_left")->options.full_speed_m_s, 0.2);
  const BiclopsOptions& head = c.Backend<BiclopsBackend>("head")->options;
  const BiclopsOptions defaults = DefaultBiclopsOptions();
  EXPECT_EQ(head.silence_timeout_s, 0.6);
  EXPECT_EQ(head.max_resends, 3);
  EXPECT_EQ(head.axes[1].min_rad, -0.5);
  EXPECT_EQ(head.axes[1].max_rad, 0.7);
  EXPECT_EQ(head.axes[1].max_speed_rad_s, 2.0);
  EXPECT_EQ(head.axes[1].counts_per_rad, defaults.axes[1].counts_per_rad);
  EXPECT_EQ(head.axes[0].max_rad, defaults.axes[0].max_rad);  // pan untouched
  EXPECT_EQ(c.Backend<LaserBoardBackend>("laser")->options.call_timeout_s, 0.5);
  const GstCameraConfig& cameras = c.Backend<GstreamerBackend>("cameras")->cameras;
  EXPECT_EQ(cameras.width, 640);
  EXPECT_EQ(cameras.height, 480);
  EXPECT_EQ(cameras.left, "a ! appsink");
  EXPECT_EQ(cameras.frame_timeout_s, 0.8);
  EXPECT_EQ(cameras.latch_pairing, LatchPairing::kOffset);
  EXPECT_EQ(cameras.frame_offset, -2);
}

TEST(DeviceConfig, CameraOptionsDefaultToTheNewestLatchAndAHalfSecondTimeout) {
  const DevicesConfig c = Parse(
      "devices:\n"
      "  laser: {driver: laser_board, port: /dev/ttyUSB0}\n"
      "  cameras: {driver: gstreamer, left: a ! appsink, right: b ! appsink}\n");
  const GstCameraConfig& cameras = c.Backend<GstreamerBackend>("cameras")->cameras;
  EXPECT_EQ(cameras.frame_timeout_s, 0.5);
  EXPECT_EQ(cameras.latch_pairing, LatchPairing::kLatest);
  EXPECT_EQ(cameras.frame_offset, 0);
}

TEST(DeviceConfig, BadOptionsAreNamedWithLineValueAndRange) {
  struct Case {
    const char* yaml;
    const char* field;
    const char* value;
    const char* expected;  // a piece of the expectation
  };
  const Case cases[] = {
      {"devices:\n  arm_left: {driver: val2, port: p, options: {reply_timeout_s: 0}}\n",
       "devices.arm_left.options.reply_timeout_s", "0", "(0, 600]"},
      {"devices:\n  arm_left: {driver: val2, port: p, options: {reply_timeout_s: '0.2'}}\n",
       "devices.arm_left.options.reply_timeout_s", "0.2", "quotes"},
      {"devices:\n  arm_left: {driver: val2, port: p, options: {max_errors: 2.5}}\n",
       "devices.arm_left.options.max_errors", "2.5", "an integer"},
      {"devices:\n  arm_left: {driver: val2, port: p, options: {confirm_reads: 1}}\n",
       "devices.arm_left.options.confirm_reads", "1", "true or false"},
      {"devices:\n  arm_left: {driver: val2, port: p, options: {max_joint_speed_deg_s: [1, 2]}}\n",
       "devices.arm_left.options.max_joint_speed_deg_s", "[1, 2]", "a list of 6 numbers"},
      {"devices:\n  arm_left: {driver: val2, port: p, options: {bogus: 1}}\n",
       "devices.arm_left.options.bogus", "bogus", "reply_timeout_s"},
      {"devices:\n  head: {driver: biclops, port: p, options: {pan: {min_rad: 1, max_rad: 0.5}}}\n",
       "devices.head.options.pan.max_rad", "", "above min_rad"},
      {"devices:\n  head: {driver: biclops, port: p, options: {roll: {}}}\n",
       "devices.head.options.roll", "roll", "pan, tilt, verge"},
      {"devices:\n  head: {driver: biclops, port: p, options: {tilt: {counts_per_rad: 0}}}\n",
       "devices.head.options.tilt.counts_per_rad", "", "non-zero"},
      {"devices:\n  hand_left: {driver: sensorhand, port: p, options: {max_opening_m: 2}}\n",
       "devices.hand_left.options.max_opening_m", "2", "(0, 0.5]"},
      {"devices:\n  laser: {driver: laser_board, port: p, options: {leds_per_gripper: 0}}\n",
       "devices.laser.options.leds_per_gripper", "0", "[1, 32]"},
      {"devices:\n  cameras: {driver: gstreamer, left: a, right: b, options: "
       "{frame_timeout_s: 0}}\n",
       "devices.cameras.options.frame_timeout_s", "0", "(0, 10]"},
      {"devices:\n  cameras: {driver: gstreamer, left: a, right: b, options: "
       "{frame_timeout_s: 11}}\n",
       "devices.cameras.options.frame_timeout_s", "11", "the longest wait"},
      {"devices:\n  cameras: {driver: gstreamer, left: a, right: b, options: "
       "{latch_pairing: nearest}}\n",
       "devices.cameras.options.latch_pairing", "nearest", "latest (the newest at grab time) or"},
      {"devices:\n  cameras: {driver: gstreamer, left: a, right: b, options: "
       "{frame_offset: 1.5}}\n",
       "devices.cameras.options.frame_offset", "1.5", "an integer in [-100000, 100000]"},
      {"devices:\n  cameras: {driver: gstreamer, left: a, right: b, options: {gain: 1}}\n",
       "devices.cameras.options.gain", "gain", "latch_pairing"},
      {"devices:\n  head: {driver: sim, options: {}}\n", "devices.head.options", "options",
       "one of: driver"},
      {"devices:\n  arm_left: {driver: val2, port: p, options: [1]}\n",
       "devices.arm_left.options", "[1]", "the options of the VAL II driver"},
  };
  for (const Case& c : cases) {
    const InputError e = ErrorOf(c.yaml);
    EXPECT_EQ(e.file(), "devices.yaml:2") << c.yaml;
    EXPECT_EQ(e.field(), c.field) << c.yaml;
    if (*c.value != '\0') {
      EXPECT_EQ(e.value(), c.value) << c.yaml;
    }
    EXPECT_NE(std::string(e.what()).find(c.expected), std::string::npos) << e.what();
  }
}

TEST(DeviceConfig, TheLaserAndTheLedsShareTheBoardsPortAndSettings) {
  EXPECT_EQ(ErrorOf("devices:\n  laser: {driver: laser_board, port: /dev/a}\n"
                    "  leds: {driver: laser_board, port: /dev/b}\n")
                .field(),
            "devices.leds.port");
  EXPECT_EQ(ErrorOf("devices:\n  laser: {driver: laser_board, port: /dev/a}\n"
                    "  leds: {driver: laser_board, port: /dev/a, baud: 9600}\n")
                .field(),
            "devices.leds.port");
  EXPECT_EQ(ErrorOf("devices:\n  arm_left: {driver: val2, port: /dev/a}\n"
                    "  head: {driver: biclops, port: /dev//a}\n")
                .field(),
            "devices.head.port");
}

TEST(DeviceConfig, FramingIsReadIntoTheSerialSettings) {
  const DevicesConfig c = Parse("devices:\n  arm_left: {driver: val2, port: p, framing: 7O2}\n");
  const SerialConfig& s = c.Backend<Val2Backend>("arm_left")->serial;
  EXPECT_EQ(s.data_bits, 7);
  EXPECT_EQ(s.parity, Parity::kOdd);
  EXPECT_EQ(s.stop_bits, 2);
  EXPECT_EQ(Framing(s), "7O2");
}

}  // namespace
}  // namespace hgrasp::drivers
