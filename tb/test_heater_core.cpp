// System bench of the heaters in cnc_core through its pins (BAUD 3 Mbaud, SAMPLE_CLKS 4096,
// heater PWM period 1024 clocks): the worked heater frames of docs/protocol.md byte exact and
// ACKed, the thermistor table loaded by frames, STATUS with the heater block (62 bytes) and the
// fault bits, every BAD_FIELD / BAD_LENGTH rule NAKed with nothing applied, and the e-stop pin:
// STEP stops, laser and heaters low within 3 clocks, FIFO flushed, fault latched until cleared.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "Vcnc_core_heat.h"
#include "common/core_pins.h"
#include "common/v2_frames.h"
#include "fpgacnc/models/ltc2308_model.h"
#include "fpgacnc/models/thermal_plant.h"
#include "fpgacnc/spec.h"

namespace {

namespace v2 = fpgacnc::tb::v2;
namespace th = fpgacnc::models::thermal;

constexpr int kAxes = 4;
constexpr uint64_t kByteClocks = 167;  // 10 bits at 3 Mbaud
constexpr uint64_t kSample = fpgacnc::spec::kBenchSampleClks;

std::vector<uint8_t> bytes(const char* hex) {
  std::vector<uint8_t> v;
  unsigned x;
  int n;
  while (std::sscanf(hex, " %2x%n", &x, &n) == 1) {
    v.push_back(static_cast<uint8_t>(x));
    hex += n;
  }
  return v;
}

class HeatCore : public fpgacnc::tb::PinHarness<Vcnc_core_heat> {
 public:
  HeatCore() : PinHarness(kAxes, fpgacnc::tb::core_pins<Vcnc_core_heat>(), true, 3'000'000) {
    adc.source = [this](int ch) { return therm.voltage(temp[ch & 1]); };
    fpgacnc::tb::reset_core(*this);
  }
  // Sends a frame and waits for its answer (the last message).
  const v2::DeviceMsg& exchange(const std::vector<uint8_t>& f) {
    send(f);
    const size_t want = msgs.size() + 1;
    for (uint64_t i = 0; i < 120 * kByteClocks && msgs.size() < want; ++i) tick();
    if (msgs.size() < want) {
      ADD_FAILURE() << "no answer to " << v2::hex(f);
      static v2::DeviceMsg none;
      return none;
    }
    return msgs.back();
  }
  void ack(const std::vector<uint8_t>& f, uint8_t next) {
    const auto& m = exchange(f);
    EXPECT_EQ(m.type, v2::kAck) << v2::hex(f);
    if (m.type == v2::kAck) {
      EXPECT_EQ(m.u8(0), next) << v2::hex(f);
    }
  }
  void nak(const std::vector<uint8_t>& f, uint8_t reason, const char* what) {
    const auto& m = exchange(f);
    EXPECT_EQ(m.type, v2::kNak) << what;
    if (m.type == v2::kNak) {
      EXPECT_EQ(m.u8(1), reason) << what;
    }
  }
  v2::DeviceMsg status() { return exchange(v2::status_query()); }

  th::Thermistor therm;
  fpgacnc::models::Ltc2308Model adc{50e6};
  double temp[2] = {20.0, 25.0};
  std::vector<v2::DeviceMsg> msgs;
  uint64_t step_rises_after = 0;  // STEP rises after `watch_from`
  uint64_t watch_from = UINT64_MAX;

 protected:
  void observe() override {
    auto& m = dut();
    m.adc_sdo = static_cast<uint8_t>(adc.tick(m.adc_convst, m.adc_sck, m.adc_sdi));
    if (tx_bytes().size() != tx_seen_) {
      tx_seen_ = tx_bytes().size();
      if (auto msg = parser_.push(tx_bytes().back().value, cycle())) msgs.push_back(*msg);
    }
    if (cycle() >= watch_from && (m.step & ~prev_step_)) ++step_rises_after;
    prev_step_ = m.step;
  }

 private:
  size_t tx_seen_ = 0;
  uint8_t prev_step_ = 0;
  v2::DeviceParser parser_;
};

// Worked examples of docs/protocol.md "Heater frames".
const char* kCfgBed =
    "A5 14 02 20 01 04 00 67 77 77 00 05 2C 60 02 05 55 55 80 00 00 10 00 00 17 D9";
const char* kSet60 = "A5 03 03 21 01 03 C0 D4 F7";
const char* kTab40 = "A5 12 04 22 01 28 04 86 04 4F 04 15 03 D7 03 96 03 4E 02 FE 02 A4 36 CC";
const char* kSafeBed = "A5 0D 05 23 01 00 50 07 80 00 40 00 28 00 20 00 3C 27 F4";
const char* kWd10 = "A5 02 06 24 00 0A 89 5A";

std::vector<uint8_t> table_frame(uint8_t seq, int ch, int first, int n, const th::Table& t) {
  std::vector<uint8_t> p{static_cast<uint8_t>(ch), static_cast<uint8_t>(first)};
  for (int i = first; i < first + n; ++i)
    v2::be16(p, static_cast<uint16_t>(t[static_cast<size_t>(i)]));
  return v2::frame(0x22, seq, p);
}

TEST(HeaterCore, WorkedFramesTableAndStatus) {
  HeatCore b;
  ASSERT_EQ(b.exchange(v2::hello()).type, v2::kIdent);
  // The worked vectors are what the frame builder makes.
  const th::Table t = th::thermistor_table();
  EXPECT_EQ(table_frame(4, 1, 40, 8, t), bytes(kTab40));
  std::vector<uint8_t> p{1, 0x03, 0xC0};
  EXPECT_EQ(v2::frame(0x21, 3, p), bytes(kSet60));
  b.ack(v2::fault_clear(0), 1);
  b.ack(v2::fault_clear(1), 2);
  b.ack(bytes(kCfgBed), 3);
  // The whole bed table (the worked frame is its entries 40..47, sent with the others).
  uint8_t seq = 3;
  for (int first = 0; first < th::kTableEntries; first += 8) {
    const int n = std::min(8, th::kTableEntries - first);
    b.ack(table_frame(seq, 1, first, n, t), static_cast<uint8_t>(seq + 1));
    ++seq;
  }
  // seq is 12 now: renumber the remaining worked frames' effects with fresh frames of equal
  // payload.
  auto payload_of = [](const char* hex) {
    auto v = bytes(hex);
    return std::vector<uint8_t>(v.begin() + 4, v.end() - 2);
  };
  b.ack(v2::frame(0x23, seq, payload_of(kSafeBed)), static_cast<uint8_t>(seq + 1));
  ++seq;
  b.ack(v2::frame(0x24, seq, payload_of(kWd10)), static_cast<uint8_t>(seq + 1));
  ++seq;
  b.idle(3 * kSample);
  b.ack(v2::frame(0x21, seq, payload_of(kSet60)), static_cast<uint8_t>(seq + 1));
  ++seq;
  b.idle(3 * kSample);
  const auto st = b.status();
  ASSERT_EQ(st.type, v2::kStatus);
  ASSERT_EQ(st.payload.size(), 62u) << "STATUS with the heater block";
  const size_t h0 = 46, h1 = 54;
  EXPECT_EQ(st.u8(1), 0u) << "no fault";
  // Bed (channel 1): 25 degC read through the ADC and the table, setpoint 60, PID enabled.
  const double bed_t = static_cast<int16_t>(st.u16(h1)) / 16.0;
  EXPECT_NEAR(bed_t, 25.0, 0.3) << "bed temperature in STATUS";
  EXPECT_EQ(st.u16(h1 + 2), 960u) << "bed setpoint";
  EXPECT_GT(st.u16(h1 + 4), 0u) << "bed duty (heating)";
  EXPECT_EQ(st.u8(h1 + 6), 0x84u) << "bed mode byte: enabled, PID";
  EXPECT_EQ(st.u8(h1 + 7), 0u) << "bed faults";
  // Hot end (channel 0): no table (reads -2048 degC, 0x8000), off.
  EXPECT_EQ(st.u16(h0), 0x8000u);
  EXPECT_EQ(st.u8(h0 + 6), 0u);
  EXPECT_EQ(b.adc.violations(), 0u) << b.adc.first_violation();
  // The watchdog (10 ticks) is fed by the STATUS queries; silence trips it (faults bit 5), both
  // heaters low, bed disabled.
  b.idle(12 * kSample);
  const auto st2 = b.status();
  EXPECT_EQ(st2.u8(1), 0x20u) << "watchdog fault bit";
  EXPECT_EQ(st2.u8(0) & 0x04, 0x04u) << "state: a fault is latched";
  EXPECT_EQ(st2.u16(h1 + 4), 0u) << "bed duty 0 after the watchdog";
  EXPECT_EQ(st2.u8(h1 + 6) & 0x80, 0u) << "bed disabled";
  EXPECT_EQ(b.dut().heater, 0u);
  b.ack(v2::fault_clear(seq), static_cast<uint8_t>(seq + 1));
  ++seq;
  EXPECT_EQ(b.status().u8(1), 0u) << "cleared";
}

TEST(HeaterCore, BadFieldsAndLengthsAreNakedAndChangeNothing) {
  HeatCore b;
  ASSERT_EQ(b.exchange(v2::hello()).type, v2::kIdent);
  auto cfg = [](uint8_t ch, uint8_t mode, uint16_t umax, uint16_t manual) {
    std::vector<uint8_t> p{ch, mode};
    for (int i = 0; i < 3; ++i) v2::be32(p, 0x00100000);
    v2::be16(p, umax);
    v2::be16(p, 16);
    v2::be16(p, manual);
    return p;
  };
  const uint8_t F = v2::kBadField, L = v2::kBadLength;
  b.nak(v2::frame(0x20, 0, cfg(2, 4, 0x8000, 0)), F, "config channel 2");
  b.nak(v2::frame(0x20, 0, cfg(0, 5, 0x8000, 0)), F, "config mode 5");
  b.nak(v2::frame(0x20, 0, cfg(0, 1, 0x8001, 0)), F, "config duty_max > 1");
  b.nak(v2::frame(0x20, 0, cfg(0, 1, 0x8000, 0x8001)), F, "config manual > 1");
  b.nak(v2::frame(0x21, 0, {2, 0, 16}), F, "setpoint channel 2");
  b.nak(v2::frame(0x22, 0, {0, 60, 0, 1, 0, 2, 0, 3, 0, 4, 0, 5, 0, 6}), F, "table 60 + 6 > 65");
  b.nak(v2::frame(0x22, 0, {0, 65, 0, 1}), F, "table first 65");
  b.nak(v2::frame(0x23, 0, {0, 0x10, 0, 0x10, 0, 0, 64, 0, 40, 0, 32, 0, 20}), F, "Tmin >= Tmax");
  b.nak(v2::frame(0x20, 0, {0, 1}), L, "config length 2");
  b.nak(v2::frame(0x21, 0, {0, 1}), L, "setpoint length 2");
  b.nak(v2::frame(0x22, 0, {0, 0, 1}), L, "table odd length");
  b.nak(v2::frame(0x22, 0, {0, 0}), L, "table without entries");
  b.nak(v2::frame(0x23, 0, {0}), L, "safety length 1");
  b.nak(v2::frame(0x24, 0, {0}), L, "watchdog length 1");
  b.nak(v2::frame(0x25, 0, {0}), v2::kUnknownType, "0x25 reserved");
  // Nothing was accepted: next_seq still 0; a good setpoint now is seq 0.
  b.ack(v2::frame(0x21, 0, {0, 0, 0}), 1);
}

TEST(HeaterCore, EstopStopsMotionLaserHeatersAndFlushes) {
  HeatCore b;
  ASSERT_EQ(b.exchange(v2::hello()).type, v2::kIdent);
  // Bed in manual 100 % (table loaded, so no MINTEMP): the heater pin is high.
  const th::Table t = th::thermistor_table();
  uint8_t seq = 0;
  for (int first = 0; first < th::kTableEntries; first += 8)
    b.ack(table_frame(seq, 1, first, std::min(8, th::kTableEntries - first), t),
          static_cast<uint8_t>(seq + 1)),
        ++seq;
  std::vector<uint8_t> p{1, 1};
  for (int i = 0; i < 3; ++i) v2::be32(p, 0);
  v2::be16(p, 0x8000);
  v2::be16(p, 16);
  v2::be16(p, 0x8000);
  b.ack(v2::frame(0x20, seq, p), static_cast<uint8_t>(seq + 1)), ++seq;
  b.ack(v2::frame(0x21, seq, {1, 0x03, 0xC0}), static_cast<uint8_t>(seq + 1)), ++seq;
  b.idle(2 * kSample);
  ASSERT_EQ(b.dut().heater, 2u) << "bed heater on";
  // Long lit moves queued: X 2000 steps over 2 000 000 clocks each.
  for (int i = 0; i < 4; ++i)
    b.ack(v2::line(seq, 1, 255, 2'000'000, {2000, 0}, false), static_cast<uint8_t>(seq + 1)), ++seq;
  b.idle(100'000);
  ASSERT_TRUE(b.dut().laser) << "laser on in the lit move";
  ASSERT_GT(b.dut().fifo_level, 0u);
  b.dut().estop = 1;
  const uint64_t t0 = b.cycle();
  uint64_t laser_low = 0, heat_low = 0;
  b.watch_from = t0 + 2;
  for (int i = 0; i < 10; ++i) {
    b.tick();
    if (!laser_low && !b.dut().laser) laser_low = b.cycle() - t0;
    if (!heat_low && b.dut().heater == 0) heat_low = b.cycle() - t0;
  }
  std::printf("e-stop pin: laser low after %llu clocks, heaters low after %llu clocks\n",
              static_cast<unsigned long long>(laser_low),
              static_cast<unsigned long long>(heat_low));
  EXPECT_GE(laser_low, 1u);
  EXPECT_LE(laser_low, 3u);
  EXPECT_LE(heat_low, 3u);
  EXPECT_EQ(b.dut().fifo_level, 0u) << "FIFO flushed";
  b.idle(3 * kSample);
  EXPECT_EQ(b.step_rises_after, 0u) << "STEP rose after the e-stop";
  EXPECT_EQ(b.dut().step, 0u);
  const auto st = b.status();
  EXPECT_EQ(st.u8(1) & 0x10, 0x10u) << "e-stop fault bit";
  EXPECT_EQ(st.u8(0) & 0x0C, 0x0Cu) << "state: fault latched, e-stop active";
  // Released: still latched until FAULT_CLEAR; then motion works again.
  b.dut().estop = 0;
  b.idle(1000);
  EXPECT_EQ(b.status().u8(1) & 0x10, 0x10u) << "latched after release";
  b.ack(v2::fault_clear(seq), static_cast<uint8_t>(seq + 1)), ++seq;
  const auto st2 = b.status();
  EXPECT_EQ(st2.u8(1), 0u);
  EXPECT_EQ(st2.u8(0) & 0x0C, 0u);
  EXPECT_EQ(b.dut().heater, 0u) << "the bed stays off until a new setpoint";
  b.watch_from = UINT64_MAX;
  const uint32_t done0 = b.dut().segments_done;
  b.ack(v2::line(seq, 1, 255, 20'000, {10, 0}, true), static_cast<uint8_t>(seq + 1)), ++seq;
  b.idle(40'000);
  EXPECT_EQ(b.dut().segments_done, done0 + 1) << "motion runs again after FAULT_CLEAR";
}

}  // namespace
