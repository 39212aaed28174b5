// Pin-level model of the LTC2308 ADC (the DE1-SoC's on-board ADC) for the Verilated benches and the
// simulated board. Header-only. Driven once per FPGA clock with the master's pins (CONVST, SCK,
// SDI) as they are after the clock edge; returns SDO for the next edge. Input voltages per channel
// are set by the bench (volts[]), or supplied on demand by a callback (the closed-loop benches).
//
// Behaviour (LTC2308 data sheet, single-ended unipolar use):
// - A CONVST rising edge samples the input of the channel named by the last complete 6-bit input
//   word (S/D, O/S, S1, S0, UNI, SLP; single-ended channel = S1*4 + S0*2 + O/S) and converts for
//   tCONV (1.6 us, worst case). Code = floor(V / 1 mV) clamped to 0..4095
//   (models::thermal::adc_code).
// - After the conversion the MSB is on SDO; each SCK falling edge shifts the next bit out (12
//   bits, then 0). SDI is latched on SCK rising edges: the first 6 bits after a CONVST rise form
//   the word for the NEXT conversion.
// - The initial word (power-up) is 0 (differential, bipolar): a master must send a word before
//   its first useful conversion.
// Violations (counted, first one described): CONVST rising during a conversion; CONVST high for
// less than 40 ns; an SCK edge during a conversion or while CONVST is high; SCK high or low for
// less than 12.5 ns (40 MHz); a word that is not single-ended unipolar without sleep.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "fpgacnc/models/thermal_plant.h"

namespace fpgacnc::models {

class Ltc2308Model {
 public:
  struct Conversion {
    uint64_t cycle;  // clock of the CONVST rise
    int channel;     // -1: the word was not single-ended
    int code;
  };

  explicit Ltc2308Model(double clk_hz = 50e6) : clk_hz_(clk_hz) {
    tconv_clks_ = static_cast<uint64_t>(std::ceil(1.6e-6 * clk_hz_));
    min_convst_clks_ = static_cast<uint64_t>(std::ceil(40e-9 * clk_hz_));
    min_sck_phase_clks_ = static_cast<uint64_t>(std::ceil(12.5e-9 * clk_hz_));
    volts.fill(0.0);
  }

  std::array<double, 8> volts;                // input voltage per channel
  std::function<double(int channel)> source;  // if set, used instead of volts[] at each CONVST

  // One clock: pins after the edge. Returns SDO for the next edge.
  int tick(bool convst, bool sck, bool sdi) {
    ++cycle_;
    if (convst && !convst_) {  // rising
      if (converting()) violation("CONVST rising during a conversion");
      const int ch = channel_of(word_);
      const double v = (ch < 0) ? 0.0 : (source ? source(ch) : volts[static_cast<size_t>(ch)]);
      result_ = models::thermal::adc_code(v);
      conversions.push_back({cycle_, ch, result_});
      conv_end_ = cycle_ + tconv_clks_;
      convst_rise_ = cycle_;
      out_bit_ = 11;
      in_bits_ = 0;
      in_word_ = 0;
    }
    if (!convst && convst_ && cycle_ - convst_rise_ < min_convst_clks_)
      violation("CONVST high shorter than 40 ns");
    if (sck != sck_) {
      if (converting()) violation("SCK edge during a conversion");
      if (convst) violation("SCK edge while CONVST is high");
      if (cycle_ - sck_edge_ < min_sck_phase_clks_) violation("SCK phase shorter than 12.5 ns");
      sck_edge_ = cycle_;
      if (sck) {  // rising: latch SDI
        if (in_bits_ < 6) {
          in_word_ = (in_word_ << 1) | (sdi ? 1 : 0);
          if (++in_bits_ == 6) {
            word_ = in_word_;
            if (channel_of(word_) < 0 || (word_ & 0x2) == 0 || (word_ & 0x1) != 0)
              violation("input word not single-ended unipolar awake");
          }
        }
      } else if (out_bit_ >= 0) {  // falling: next bit out
        --out_bit_;
      }
    }
    convst_ = convst;
    sck_ = sck;
    if (converting() || out_bit_ < 0) return 0;
    return (result_ >> out_bit_) & 1;
  }

  static int channel_of(int word) {
    if (!(word & 0x20)) return -1;  // differential
    const int os = (word >> 4) & 1, s1 = (word >> 3) & 1, s0 = (word >> 2) & 1;
    return s1 * 4 + s0 * 2 + os;
  }
  // The input word a master sends for single-ended unipolar channel ch, awake.
  static int word_for(int ch) {
    return 0x20 | ((ch & 1) << 4) | ((ch >> 2 & 1) << 3) | ((ch >> 1 & 1) << 2) | 0x2;
  }

  uint64_t violations() const { return violations_; }
  const std::string& first_violation() const { return first_violation_; }
  uint64_t tconv_clks() const { return tconv_clks_; }
  std::vector<Conversion> conversions;

 private:
  bool converting() const { return cycle_ < conv_end_; }
  void violation(const char* what) {
    if (violations_++ == 0)
      first_violation_ = std::string(what) + " at clock " + std::to_string(cycle_);
  }

  double clk_hz_;
  uint64_t tconv_clks_ = 0, min_convst_clks_ = 0, min_sck_phase_clks_ = 0;
  uint64_t cycle_ = 0, conv_end_ = 0, convst_rise_ = 0, sck_edge_ = 0;
  bool convst_ = false, sck_ = false;
  int word_ = 0, in_word_ = 0, in_bits_ = 6, result_ = 0, out_bit_ = -1;
  uint64_t violations_ = 0;
  std::string first_violation_;
};

}  // namespace fpgacnc::models
