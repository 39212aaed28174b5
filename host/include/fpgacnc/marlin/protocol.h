// Marlin's host protocol for printers (docs/marlin.md), the parts that need no board: line
// numbers and checksums as a host sends them ("N<n> <command>*<checksum>", the checksum the XOR of
// every byte before '*'), the answers Marlin gives to a bad line ("Error:..." then "Resend: <n>"
// then "ok"), M110, and the text of its reports (temperatures for M105 / M155, positions for
// M114, "busy: processing"). Written from Marlin's published G-code reference (marlinfw.org).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace fpgacnc::marlin {

// XOR of every byte of `s`.
uint8_t checksum(std::string_view s);

// What to do with one received line.
struct Accepted {
  // The command to run (line number, checksum and comment removed, surrounding blanks trimmed);
  // empty: nothing to run (a blank or comment-only line, or a refused line).
  std::string command;
  // Answers to write before the command's own (a refused line: "Error:...", "Resend: <n>" and
  // "ok"; then `command` is empty and `refused` is set).
  std::vector<std::string> answers;
  bool refused = false;
  // The line carried "N<n>": the number (already taken as the last line when accepted).
  std::optional<long> line_number;
};

// Line numbering state: the last accepted line number (0 after start and after M110 without N).
class LineChecker {
 public:
  // One line as received, without its line ending.
  Accepted accept(std::string_view raw);
  long last_line() const { return last_; }
  // M110 N<n>: the next line must carry n + 1.
  void set_last_line(long n) { last_ = n; }

 private:
  long last_ = 0;
};

// One heater as a temperature report shows it.
struct HeaterReading {
  double temp_c = 0.0;
  double target_c = 0.0;
  double duty = 0.0;  // 0..1
};

// "T:21.50 /0.00 B:20.25 /60.00 @:0 B@:127": the hotend (T) and bed (B) temperatures and
// targets, and their heater powers as Marlin prints them (@ and B@: 0..127 for 0..100 %). A bed
// that is absent (nullopt) is left out, as Marlin leaves it out on a printer without one.
std::string temperature_report(const HeaterReading& hotend,
                               const std::optional<HeaterReading>& bed);

// "X:10.00 Y:0.00 Z:0.20 E:0.00 Count X:1600 Y:0 Z:80": positions (mm) and the step counters.
std::string position_report(const std::array<double, 4>& mm, const std::array<int64_t, 3>& steps);

}  // namespace fpgacnc::marlin
