#include "fpgacnc/gcode/interpreter.h"

#include <fmt/format.h>

#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

namespace fpgacnc {

SourceError::SourceError(std::string file, int line, int column, std::string message)
    : std::runtime_error(
          line > 0 ? (column > 0 ? fmt::format("{}:{}:{}: error: {}", file, line, column, message)
                                 : fmt::format("{}:{}: error: {}", file, line, message))
                   : fmt::format("{}: error: {}", file, message)),
      file_(std::move(file)),
      line_(line),
      column_(column),
      message_(std::move(message)) {}

}  // namespace fpgacnc

namespace fpgacnc::gcode {
namespace {

constexpr double kMaxValue = 1e6;  // |value| limit for every word (mm, mm/min, s)
constexpr int kMaxWords = 64;

struct Word {
  char letter = 0;
  double value = 0.0;
  int col = 0;
  bool integer = true;  // no '.' in the number
};

struct LineWords {
  std::array<Word, kMaxWords> words;
  int count = 0;
};

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r';
}
bool is_digit(char c) {
  return c >= '0' && c <= '9';
}

}  // namespace

Interpreter::Interpreter(std::string file_name, Options options)
    : file_(std::move(file_name)), opt_(options), feed_(options.default_feed_mm_min) {}

void Interpreter::parse_line(std::string_view text, int line_number, std::vector<Command>& out) {
  ++stats_.lines;
  auto fail = [&](int col, const std::string& msg) -> Error {
    return Error(file_, line_number, col, msg);
  };

  // 1. Non-printable bytes (binary garbage), and locate a checksum '*' outside comments.
  size_t star = std::string_view::npos;
  {
    bool in_paren = false, in_semi = false;
    for (size_t i = 0; i < text.size(); ++i) {
      const auto c = static_cast<unsigned char>(text[i]);
      if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7F) {
        throw fail(static_cast<int>(i) + 1, fmt::format("non-printable byte 0x{:02X}", c));
      }
      if (c >= 0x80 && !in_paren && !in_semi) {
        throw fail(static_cast<int>(i) + 1, fmt::format("non-ASCII byte 0x{:02X}", c));
      }
      if (in_semi) continue;
      if (in_paren) {
        if (c == ')') in_paren = false;
        continue;
      }
      if (c == '(') in_paren = true;
      if (c == ';') in_semi = true;
      if (c == '*' && star == std::string_view::npos) star = i;
    }
  }
  if (star != std::string_view::npos) {
    unsigned x = 0;
    for (size_t i = 0; i < star; ++i) x ^= static_cast<unsigned char>(text[i]);
    size_t i = star + 1;
    unsigned given = 0;
    size_t digits = 0;
    while (i < text.size() && is_digit(text[i]) && digits < 4) {
      given = given * 10 + static_cast<unsigned>(text[i] - '0');
      ++i;
      ++digits;
    }
    size_t rest = i;
    while (rest < text.size() && is_space(text[rest])) ++rest;
    if (digits == 0 || given > 255 || (rest < text.size() && text[rest] != ';')) {
      throw fail(static_cast<int>(star) + 1, "malformed checksum (expected *0..255)");
    }
    if (given != x) {
      throw fail(static_cast<int>(star) + 1,
                 fmt::format("checksum mismatch: line says {}, computed {}", given, x));
    }
    text = text.substr(0, star);
  }

  // 2. '%' program delimiter lines.
  {
    size_t a = 0, b = text.size();
    while (a < b && is_space(text[a])) ++a;
    while (b > a && is_space(text[b - 1])) --b;
    if (b - a == 1 && text[a] == '%') return;
  }

  // 3. Tokenize into words.
  LineWords lw;
  size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    if (is_space(c)) {
      ++i;
      continue;
    }
    if (c == ';') break;
    if (c == '(') {
      const size_t close = text.find(')', i);
      if (close == std::string_view::npos) {
        throw fail(static_cast<int>(i) + 1, "unterminated comment '('");
      }
      i = close + 1;
      continue;
    }
    const int col = static_cast<int>(i) + 1;
    char letter = c;
    if (letter >= 'a' && letter <= 'z') letter = static_cast<char>(letter - 'a' + 'A');
    if (letter < 'A' || letter > 'Z') {
      throw fail(col, fmt::format("unexpected character '{}'", c));
    }
    ++i;
    while (i < text.size() && is_space(text[i])) ++i;
    bool neg = false;
    if (i < text.size() && (text[i] == '+' || text[i] == '-')) {
      neg = text[i] == '-';
      ++i;
    }
    const size_t num_start = i;
    size_t ndig = 0;
    bool dot = false;
    while (i < text.size() && (is_digit(text[i]) || (text[i] == '.' && !dot))) {
      if (text[i] == '.') {
        dot = true;
      } else {
        ++ndig;
      }
      ++i;
    }
    if (ndig == 0) {
      throw fail(col, fmt::format("expected a number after '{}'", letter));
    }
    if (i < text.size() && (text[i] == '.' || text[i] == '+' || text[i] == '-')) {
      throw fail(static_cast<int>(i) + 1, fmt::format("garbage in the number of '{}'", letter));
    }
    double v = 0.0;
    const char* first = text.data() + num_start;
    const char* last = text.data() + i;
    if (*first == '.') {
      // from_chars accepts ".5"; keep it explicit for clarity.
    }
    auto res = std::from_chars(first, last, v);
    if (res.ec != std::errc() || res.ptr != last || !std::isfinite(v)) {
      throw fail(col, fmt::format("invalid number for '{}'", letter));
    }
    if (neg) v = -v;
    if (lw.count == kMaxWords) throw fail(col, "too many words on one line");
    lw.words[static_cast<size_t>(lw.count++)] = Word{letter, v, col, !dot};
  }
  if (lw.count == 0) return;

  // 4. Classify words.
  const Word* letters[26] = {};
  const Word* motion_word = nullptr;
  const Word* nonmodal_word = nullptr;  // G4 / G28 / G92
  std::optional<Motion> new_motion;
  int nonmodal = 0;
  std::optional<double> new_unit;
  std::optional<bool> new_absolute;
  int heater_m = 0;
  const Word* heater_word = nullptr;
  std::optional<bool> spindle;
  std::optional<bool> e_abs;

  for (int w = 0; w < lw.count; ++w) {
    const Word& wd = lw.words[static_cast<size_t>(w)];
    if (wd.letter == 'G' || wd.letter == 'M') {
      if (!wd.integer || wd.value < 0 || wd.value > 1000) {
        throw fail(wd.col, fmt::format("only integer {} codes are accepted", wd.letter));
      }
      const int code = static_cast<int>(wd.value);
      if (wd.letter == 'G') {
        switch (code) {
          case 0:
          case 1:
          case 2:
          case 3:
            if (motion_word) throw fail(wd.col, "two motion G codes on one line");
            motion_word = &wd;
            new_motion = static_cast<Motion>(code);
            break;
          case 4:
          case 28:
          case 92:
            if (nonmodal_word) throw fail(wd.col, "two of G4/G28/G92 on one line");
            nonmodal_word = &wd;
            nonmodal = code;
            break;
          case 17:
          case 54:  // the only coordinate system
          case 94:  // units per minute feed mode (the only one)
            break;
          case 18:
          case 19:
            throw fail(wd.col, fmt::format("G{} not supported: only the XY plane (G17)", code));
          case 20:
            new_unit = 25.4;
            break;
          case 21:
            new_unit = 1.0;
            break;
          case 90:
            new_absolute = true;
            break;
          case 91:
            new_absolute = false;
            break;
          default:
            throw fail(wd.col, fmt::format("unsupported G code G{}", code));
        }
      } else {
        switch (code) {
          case 3:
          case 4:
            spindle = true;
            break;
          case 5:
            spindle = false;
            break;
          case 82:
            e_abs = true;
            break;
          case 83:
            e_abs = false;
            break;
          case 2:   // program end
          case 30:  // program end
          case 84:  // motors off
            break;
          case 104:
          case 109:
          case 140:
          case 190:
            if (heater_word) throw fail(wd.col, "two heater M codes on one line");
            heater_word = &wd;
            heater_m = code;
            break;
          default:
            throw fail(wd.col, fmt::format("unsupported M code M{}", code));
        }
      }
      continue;
    }
    switch (wd.letter) {
      case 'N':
        if (!wd.integer || wd.value < 0) throw fail(wd.col, "N must be a non-negative integer");
        break;
      case 'X':
      case 'Y':
      case 'Z':
      case 'E':
      case 'I':
      case 'J':
      case 'R':
      case 'F':
      case 'S':
      case 'P':
        break;
      case 'K':
        throw fail(wd.col, "K not supported: only the XY plane (G17)");
      default:
        throw fail(wd.col, fmt::format("unsupported word '{}'", wd.letter));
    }
    const int idx = wd.letter - 'A';
    if (letters[idx]) {
      throw fail(wd.col, fmt::format("two '{}' words on one line", wd.letter));
    }
    if (wd.letter != 'N' && std::fabs(wd.value) > kMaxValue) {
      throw fail(wd.col, fmt::format("value of '{}' out of range (|value| > 1e6)", wd.letter));
    }
    letters[idx] = &wd;
  }
  auto word = [&](char l) { return letters[l - 'A']; };

  // 5. Execute in RS274/NGC order: F, S, M3/4/5, heaters, dwell, units, distance, G28/G92,
  // motion.
  if (new_unit) unit_ = *new_unit;
  auto to_mm = [&](const Word* w) {
    const double v = w->value * unit_;
    if (std::fabs(v) > kMaxValue) {
      throw fail(w->col, fmt::format("value of '{}' out of range (|value| > 1e6 mm)", w->letter));
    }
    return v;
  };
  bool did_command = false;
  if (const Word* f = word('F')) {
    if (f->value < 0) throw fail(f->col, "negative feed");
    feed_ = to_mm(f);
  }
  if (const Word* s = word('S')) {
    if (s->value < 0) throw fail(s->col, "negative S value");
    if (!heater_word) spindle_s_ = s->value;
  }
  if (spindle) {
    spindle_on_ = *spindle;
    did_command = true;
  }
  if (e_abs) e_absolute_ = *e_abs;
  if (heater_word) {
    Heater h;
    h.mcode = heater_m;
    if (const Word* s = word('S')) h.s = s->value;
    h.line = line_number;
    out.emplace_back(h);
    did_command = true;
  }
  if (const Word* p = word('P'); p && nonmodal != 4) {
    throw fail(p->col, "P word without G4");
  }
  if (new_absolute) absolute_ = *new_absolute;

  const bool has_axis = word('X') || word('Y') || word('Z') || word('E');
  auto target_of = [&](const Vec4& from) {
    Vec4 t = from;
    static constexpr char names[4] = {'X', 'Y', 'Z', 'E'};
    for (int a = 0; a < 4; ++a) {
      const Word* w = word(names[a]);
      if (!w) continue;
      const double v = to_mm(w);
      const bool rel = !absolute_ || (a == 3 && !e_absolute_);
      t[static_cast<size_t>(a)] =
          rel ? from[static_cast<size_t>(a)] + v : v + offset_[static_cast<size_t>(a)];
      if (std::fabs(t[static_cast<size_t>(a)]) > 1e9) {
        throw fail(w->col, "position out of range");
      }
    }
    return t;
  };
  auto rapid_to = [&](const Vec4& t) {
    Move m;
    m.motion = Motion::kRapid;
    m.start = pos_;
    m.end = t;
    m.feed_mm_min = feed_;
    m.spindle_on = spindle_on_;
    m.spindle_s = spindle_s_;
    m.line = line_number;
    out.emplace_back(m);
    pos_ = t;
    ++stats_.moves;
  };

  if (nonmodal == 4) {
    const Word* p = word('P');
    if (!p) throw fail(nonmodal_word->col, "G4 needs a P word (seconds)");
    if (p->value < 0) throw fail(p->col, "negative dwell time");
    out.emplace_back(Dwell{p->value, line_number});
    did_command = true;
  }
  if (nonmodal == 28 || nonmodal == 92) {
    if (motion_word) {
      throw fail(motion_word->col,
                 fmt::format("G{} and a motion G code on the same line", nonmodal));
    }
    for (char l : {'I', 'J', 'R'}) {
      if (const Word* w = word(l)) {
        throw fail(w->col, fmt::format("'{}' word not allowed with G{}", l, nonmodal));
      }
    }
  }
  if (nonmodal == 92) {
    if (!has_axis) throw fail(nonmodal_word->col, "G92 needs at least one axis word");
    static constexpr char names[4] = {'X', 'Y', 'Z', 'E'};
    for (int a = 0; a < 4; ++a) {
      if (const Word* w = word(names[a])) {
        offset_[static_cast<size_t>(a)] = pos_[static_cast<size_t>(a)] - to_mm(w);
      }
    }
    ++stats_.commands;
    return;
  }
  if (nonmodal == 28) {
    Vec4 home = pos_;
    if (has_axis) {
      const Vec4 via = target_of(pos_);
      rapid_to(via);
      static constexpr char names[4] = {'X', 'Y', 'Z', 'E'};
      for (int a = 0; a < 4; ++a) {
        if (word(names[a])) home[static_cast<size_t>(a)] = 0.0;
      }
    } else {
      home[0] = home[1] = home[2] = 0.0;  // E has no origin to return to
    }
    rapid_to(home);
    produced_ = true;
    return;
  }

  if (new_motion) motion_ = new_motion;
  const Word* ij_word = word('I') ? word('I') : word('J');
  const Word* r_word = word('R');
  const bool arc_words = ij_word || r_word;
  const bool wants_motion =
      has_axis ||
      (arc_words && motion_ && (*motion_ == Motion::kArcCw || *motion_ == Motion::kArcCcw));
  if (!wants_motion) {
    if (arc_words) {
      throw fail((ij_word ? ij_word : r_word)->col, "I/J/R words without an arc (G2/G3)");
    }
    if (did_command || new_motion || new_unit || new_absolute || e_abs || word('F') || word('S')) {
      ++stats_.commands;
    }
    if (did_command) produced_ = true;
    return;
  }
  const int motion_col = motion_word ? motion_word->col : [&] {
    for (int w = 0; w < lw.count; ++w) {
      const char l = lw.words[static_cast<size_t>(w)].letter;
      if (l == 'X' || l == 'Y' || l == 'Z' || l == 'E' || l == 'I' || l == 'J' || l == 'R') {
        return lw.words[static_cast<size_t>(w)].col;
      }
    }
    return 1;
  }();
  if (!motion_) throw fail(motion_col, "axis words with no motion mode (G0/G1/G2/G3) active");

  Move m;
  m.motion = *motion_;
  m.start = pos_;
  m.end = target_of(pos_);
  m.feed_mm_min = feed_;
  m.spindle_on = spindle_on_;
  m.spindle_s = spindle_s_;
  m.line = line_number;
  if (m.motion != Motion::kRapid && feed_ <= 0.0) {
    const Word* f = word('F');
    throw fail(f ? f->col : motion_col, "feed is 0: a G1/G2/G3 move needs F > 0");
  }
  if (m.motion == Motion::kArcCw || m.motion == Motion::kArcCcw) {
    if (!arc_words) {
      if (motion_word) throw fail(motion_word->col, "arc without centre (no I, J or R)");
      // Modal G2/G3 repeated with axis words only: run as a straight cutting line.
      m.motion = Motion::kLinear;
      ++stats_.modal_arc_as_line;
    } else if (r_word) {
      if (ij_word) throw fail(r_word->col, "R and I/J on the same arc");
      const double r = to_mm(r_word);
      const double x = m.end[0] - m.start[0];
      const double y = m.end[1] - m.start[1];
      const double d = std::hypot(x, y);
      if (d < 1e-9) throw fail(r_word->col, "R-form arc with end point equal to start point");
      double disc = 4.0 * r * r - x * x - y * y;
      if (disc < 0.0) {
        constexpr double kRTolerance = 1e-3;  // mm: rounding in the file's decimals
        if (d / 2.0 - std::fabs(r) > kRTolerance) {
          throw fail(r_word->col, fmt::format("impossible arc: radius {:.6g} mm is smaller than "
                                              "half the chord ({:.6g} mm)",
                                              std::fabs(r), d / 2.0));
        }
        disc = 0.0;
      }
      double h = -std::sqrt(disc) / d;
      if (m.motion == Motion::kArcCcw) h = -h;
      if (r < 0) h = -h;
      m.center = {m.start[0] + 0.5 * (x - y * h), m.start[1] + 0.5 * (y + x * h)};
    } else {
      const double ci = word('I') ? to_mm(word('I')) : 0.0;
      const double cj = word('J') ? to_mm(word('J')) : 0.0;
      m.center = {m.start[0] + ci, m.start[1] + cj};
      const double r0 = std::hypot(m.start[0] - m.center[0], m.start[1] - m.center[1]);
      const double r1 = std::hypot(m.end[0] - m.center[0], m.end[1] - m.center[1]);
      if (r0 < 1e-6) throw fail(ij_word->col, "arc with zero radius");
      // Start and end radius differ: real files have this (Circle_Diamond_Square_Calibration
      // line 624 differs by 5%). The planner blends the radius linearly (a spiral ending exactly
      // at the programmed end) and it is counted as a warning; a gross mismatch is an error.
      if (std::fabs(r1 - r0) > 0.005 && std::fabs(r1 - r0) > 0.001 * r0) {
        if (std::fabs(r1 - r0) > 0.5 * r0) {
          throw fail(motion_col,
                     fmt::format("arc end point is not on the circle (start radius {:.6g} mm, "
                                 "end radius {:.6g} mm)",
                                 r0, r1));
        }
        ++stats_.arc_radius_mismatch;
      }
      m.full_circle = std::hypot(m.end[0] - m.start[0], m.end[1] - m.start[1]) < 1e-9;
    }
  } else if (arc_words) {
    throw fail((ij_word ? ij_word : r_word)->col, "I/J/R words on a G0/G1 move");
  }
  pos_ = m.end;
  out.emplace_back(m);
  ++stats_.moves;
  produced_ = true;
}

void Interpreter::finish() {
  if (!produced_) {
    throw Error(file_, static_cast<int>(std::max<uint64_t>(stats_.lines, 1)), 1,
                "empty job (no motion and no commands)");
  }
}

Stats parse_stream(std::istream& in, const std::string& file_name, Options options,
                   const std::function<void(const Command&)>& sink) {
  Interpreter interp(file_name, options);
  std::string line;
  std::vector<Command> out;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    out.clear();
    interp.parse_line(line, n, out);
    for (const auto& c : out) sink(c);
  }
  if (in.bad()) throw Error(file_name, n, 0, "read error");
  interp.finish();
  return interp.stats();
}

Program parse_stream(std::istream& in, const std::string& file_name, Options options) {
  Program p;
  p.file_name = file_name;
  Interpreter interp(file_name, options);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    interp.parse_line(line, n, p.commands);
  }
  if (in.bad()) throw Error(file_name, n, 0, "read error");
  interp.finish();
  p.stats = interp.stats();
  return p;
}

Program parse_file(const std::string& path, Options options) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw Error(path, 0, 0, "cannot open file");
  return parse_stream(f, path, options);
}

Program parse_string(std::string_view text, const std::string& file_name, Options options) {
  std::istringstream s{std::string(text)};
  return parse_stream(s, file_name, options);
}

}  // namespace fpgacnc::gcode
