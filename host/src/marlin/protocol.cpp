#include "fpgacnc/marlin/protocol.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>

namespace fpgacnc::marlin {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

// Digits (and a leading '-') at the start of `s`: the number and how many characters it took.
std::optional<std::pair<long, size_t>> leading_number(std::string_view s) {
  size_t i = 0;
  const bool neg = i < s.size() && s[i] == '-';
  if (neg) ++i;
  const size_t start = i;
  long v = 0;
  while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i])) && i - start < 10)
    v = v * 10 + (s[i++] - '0');
  if (i == start) return std::nullopt;
  return std::make_pair(neg ? -v : v, i);
}

bool is_m110(std::string_view cmd) {
  if (cmd.size() < 4 || std::toupper(static_cast<unsigned char>(cmd[0])) != 'M') return false;
  const auto n = leading_number(cmd.substr(1));
  return n && n->first == 110;
}

}  // namespace

uint8_t checksum(std::string_view s) {
  uint8_t c = 0;
  for (char ch : s) c ^= static_cast<uint8_t>(ch);
  return c;
}

Accepted LineChecker::accept(std::string_view raw) {
  Accepted a;
  std::string_view line = trim(raw);
  auto refuse = [&](std::string_view why) {
    a.refused = true;
    a.answers.push_back(fmt::format("Error:{}, Last Line: {}", why, last_));
    a.answers.push_back(fmt::format("Resend: {}", last_ + 1));
    a.answers.push_back("ok");
    return a;
  };
  const size_t star = line.rfind('*');
  std::string_view body = star == std::string_view::npos ? line : line.substr(0, star);
  const bool numbered = !line.empty() && (line[0] == 'N' || line[0] == 'n');
  if (numbered) {
    const auto n = leading_number(line.substr(1));
    if (!n) return refuse("Line Number is not Last Line Number+1");
    const std::string_view cmd = trim(body.substr(1 + n->second));
    const bool m110 = is_m110(cmd);
    if (!m110 && n->first != last_ + 1) return refuse("Line Number is not Last Line Number+1");
    if (star == std::string_view::npos) return refuse("No Checksum with line number");
    const auto sum = leading_number(trim(line.substr(star + 1)));
    if (!sum || sum->first != checksum(body)) return refuse("checksum mismatch");
    last_ = n->first;
    a.line_number = n->first;
    body = cmd;
  } else if (star != std::string_view::npos) {
    return refuse("No Line Number with checksum");
  }
  if (const size_t semi = body.find(';'); semi != std::string_view::npos)
    body = body.substr(0, semi);
  a.command = std::string(trim(body));
  return a;
}

std::string temperature_report(const HeaterReading& hotend,
                               const std::optional<HeaterReading>& bed) {
  auto power = [](double duty) {
    return static_cast<int>(std::lround(std::clamp(duty, 0.0, 1.0) * 127.0));
  };
  std::string r = fmt::format("T:{:.2f} /{:.2f}", hotend.temp_c, hotend.target_c);
  if (bed) r += fmt::format(" B:{:.2f} /{:.2f}", bed->temp_c, bed->target_c);
  r += fmt::format(" @:{}", power(hotend.duty));
  if (bed) r += fmt::format(" B@:{}", power(bed->duty));
  return r;
}

std::string position_report(const std::array<double, 4>& mm, const std::array<int64_t, 3>& steps) {
  return fmt::format("X:{:.2f} Y:{:.2f} Z:{:.2f} E:{:.2f} Count X:{} Y:{} Z:{}", mm[0], mm[1],
                     mm[2], mm[3], steps[0], steps[1], steps[2]);
}

}  // namespace fpgacnc::marlin
