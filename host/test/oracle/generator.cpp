#include "generator.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <stdexcept>

namespace fpgacnc::oracle {
namespace {

// SplitMix64 and integer arithmetic only: the same programs from every compiler and library.
class Rng {
 public:
  explicit Rng(uint64_t seed) : s_(seed * 0x9E3779B97F4A7C15ull + 0x632BE59BD9B4E019ull) {}
  uint64_t next() {
    uint64_t z = (s_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  int range(int lo, int hi) {  // inclusive
    return lo + static_cast<int>(next() % static_cast<uint64_t>(hi - lo + 1));
  }
  // A decimal with `decimals` digits in [lo, hi], as text and value (text is exact).
  double dec(int lo, int hi, int decimals = 3) {
    const int scale = decimals == 4 ? 10000 : decimals == 2 ? 100 : decimals == 1 ? 10 : 1000;
    const int v = range(lo * scale, hi * scale);
    return static_cast<double>(v) / scale;
  }
  bool coin() { return (next() & 1u) != 0; }

 private:
  uint64_t s_;
};

std::string n3(double v) {
  return fmt::format("{:.3f}", v);
}
std::string n4(double v) {
  return fmt::format("{:.4f}", v);
}

struct Gen {
  Rng r;
  std::string t;
  explicit Gen(uint64_t seed) : r(seed) {}
  void line(const std::string& s) { t += s + "\n"; }
};

constexpr double kPi = 3.14159265358979323846;

// G0/G1 moves with random axis subsets, dwells, spindle on/off: what every interpreter knows.
void fam_lines(Gen& g) {
  g.line("G21 G90");
  g.line(fmt::format("F{}", g.r.range(100, 3000)));
  g.line(fmt::format("M3 S{}", g.r.range(1000, 20000)));
  for (int i = 0; i < 20; ++i) {
    std::string s = g.r.coin() ? "G0" : "G1";
    const int axes = g.r.range(1, 7);
    if (axes & 1) s += " X" + n3(g.r.dec(-100, 100));
    if (axes & 2) s += " Y" + n3(g.r.dec(-100, 100));
    if (axes & 4) s += " Z" + n3(g.r.dec(-20, 20));
    g.line(s);
    if (g.r.range(0, 6) == 0) g.line("G4 P" + n3(g.r.dec(0, 2)));
  }
  g.line("M5");
}

// Non-moving M codes between moves: spindle, coolant, optional stop, tool change.
void fam_mcodes(Gen& g) {
  g.line("G21 G90 G0 X0 Y0 Z10");
  const std::array<const char*, 8> codes = {"M3 S1000", "M4 S2000", "M5", "M7",
                                            "M8",       "M9",       "M1", "T2 M6"};
  for (int i = 0; i < 10; ++i) {
    g.line(codes[static_cast<size_t>(g.r.range(0, static_cast<int>(codes.size()) - 1))]);
    g.line(fmt::format("G1 X{} Y{} F600", n3(g.r.dec(-50, 50)), n3(g.r.dec(-50, 50))));
  }
  g.line("M5 M9");
}

// G20/G21 switched mid-program, G90/G91 in both.
void fam_units(Gen& g) {
  g.line("G90");
  for (int i = 0; i < 12; ++i) {
    const bool inch = g.r.coin();
    g.line(inch ? "G20" : "G21");
    g.line(g.r.coin() ? "G91" : "G90");
    const double lim = inch ? 3 : 80;
    g.line(fmt::format("G1 X{} Y{} Z{} F{}", n4(g.r.dec(-static_cast<int>(lim), lim, 4)),
                       n4(g.r.dec(-static_cast<int>(lim), lim, 4)), n4(g.r.dec(-1, 1, 4)),
                       inch ? 20 : 500));
    g.line(fmt::format("G0 X{}", n4(g.r.dec(-static_cast<int>(lim), lim, 4))));
  }
  g.line("G21 G90");
}

// G91 incremental moves (and back to G90).
void fam_incremental(Gen& g) {
  g.line("G21 G90 G0 X1 Y2 Z3");
  g.line("G91");
  for (int i = 0; i < 15; ++i) {
    g.line(fmt::format("{} X{} Y{} Z{} F800", g.r.coin() ? "G0" : "G1", n3(g.r.dec(-20, 20)),
                       n3(g.r.dec(-20, 20)), n3(g.r.dec(-5, 5))));
    if (g.r.range(0, 4) == 0) {
      g.line("G90");
      g.line(fmt::format("G1 X{} Y{}", n3(g.r.dec(-20, 20)), n3(g.r.dec(-20, 20))));
      g.line("G91");
    }
  }
  g.line("G90");
}

// G92 offsets set repeatedly (no cancel).
void fam_g92(Gen& g) {
  g.line("G21 G90 F1000");
  for (int i = 0; i < 10; ++i) {
    g.line(fmt::format("G1 X{} Y{} Z{}", n3(g.r.dec(-40, 40)), n3(g.r.dec(-40, 40)),
                       n3(g.r.dec(-5, 5))));
    std::string s = "G92";
    const int axes = g.r.range(1, 7);
    if (axes & 1) s += " X" + n3(g.r.dec(-10, 10));
    if (axes & 2) s += " Y" + n3(g.r.dec(-10, 10));
    if (axes & 4) s += " Z" + n3(g.r.dec(-10, 10));
    g.line(s);
    g.line(fmt::format("G0 X{} Y{}", n3(g.r.dec(-40, 40)), n3(g.r.dec(-40, 40))));
  }
}

// G92 with G92.1 (cancel, clear), G92.2 (suspend) and G92.3 (restore).
void fam_g92_cancel(Gen& g) {
  g.line("G21 G90 F1000");
  const std::array<const char*, 3> cancels = {"G92.1", "G92.2", "G92.3"};
  for (int i = 0; i < 8; ++i) {
    g.line(fmt::format("G1 X{} Y{}", n3(g.r.dec(-40, 40)), n3(g.r.dec(-40, 40))));
    g.line(fmt::format("G92 X{} Y{}", n3(g.r.dec(-10, 10)), n3(g.r.dec(-10, 10))));
    g.line(fmt::format("G1 X{} Y{}", n3(g.r.dec(-40, 40)), n3(g.r.dec(-40, 40))));
    g.line(cancels[static_cast<size_t>(g.r.range(0, 2))]);
    g.line(fmt::format("G0 X{} Z{}", n3(g.r.dec(-40, 40)), n3(g.r.dec(-5, 5))));
  }
  g.line("G92.1");
}

// Arcs in one plane. `plane` 17/18/19; I/J/K or R; centre absolute (G90.1) or incremental.
void arcs(Gen& g, int plane, bool r_form, bool absolute_centre) {
  // (a, b) are the plane's first and second axis, h the helix axis: G17 X Y Z, G18 Z X Y (arcs
  // written with I and K), G19 Y Z X (J and K).
  const std::array<char, 3> axis = plane == 17   ? std::array<char, 3>{'X', 'Y', 'Z'}
                                   : plane == 18 ? std::array<char, 3>{'Z', 'X', 'Y'}
                                                 : std::array<char, 3>{'Y', 'Z', 'X'};
  auto centre_letter = [](char a) { return a == 'X' ? 'I' : a == 'Y' ? 'J' : 'K'; };
  g.line(fmt::format("G21 G90 G{} F700", plane));
  if (absolute_centre) g.line("G90.1");
  double a = g.r.dec(-20, 20, 4), b = g.r.dec(-20, 20, 4), h = g.r.dec(-5, 5, 4);
  g.line(fmt::format("G0 {}{} {}{} {}{}", axis[0], n4(a), axis[1], n4(b), axis[2], n4(h)));
  for (int i = 0; i < 10; ++i) {
    const bool cw = g.r.coin();
    const double sweep = (20 + g.r.range(0, 300)) * kPi / 180.0 * (cw ? -1 : 1);
    const bool helix = g.r.range(0, 2) == 0;
    const double nh = helix ? g.r.dec(-5, 5, 4) : h;
    std::string s = cw ? "G2" : "G3";
    if (!r_form) {
      const double rad = g.r.dec(2, 30, 1);
      const double phi = g.r.range(0, 359) * kPi / 180.0;
      const double ca = a - rad * std::cos(phi), cb = b - rad * std::sin(phi);
      const bool full = g.r.range(0, 7) == 0;
      double na = a, nb = b;
      if (!full) {
        na = std::round((ca + rad * std::cos(phi + sweep)) * 1e4) / 1e4;
        nb = std::round((cb + rad * std::sin(phi + sweep)) * 1e4) / 1e4;
        s += fmt::format(" {}{} {}{}", axis[0], n4(na), axis[1], n4(nb));
      }
      const double oa = absolute_centre ? ca : ca - a, ob = absolute_centre ? cb : cb - b;
      s +=
          fmt::format(" {}{} {}{}", centre_letter(axis[0]), n4(oa), centre_letter(axis[1]), n4(ob));
      a = na;
      b = nb;
    } else {
      const double da = g.r.dec(-15, 15, 4), db = g.r.dec(-15, 15, 4);
      const double d = std::hypot(da, db);
      if (d < 0.5) continue;
      double rad = std::round(d / 2 * (1.05 + g.r.range(0, 100) / 50.0) * 1e4) / 1e4;
      if (g.r.range(0, 3) == 0) rad = -rad;  // the long way round
      a += da;
      b += db;
      s += fmt::format(" {}{} {}{} R{}", axis[0], n4(a), axis[1], n4(b), n4(rad));
    }
    if (helix) s += fmt::format(" {}{}", axis[2], n4(nh));
    h = nh;
    g.line(s);
    if (g.r.range(0, 3) == 0) {
      a = g.r.dec(-20, 20, 4);
      b = g.r.dec(-20, 20, 4);
      g.line(fmt::format("G1 {}{} {}{}", axis[0], n4(a), axis[1], n4(b)));
    }
  }
  if (absolute_centre) g.line("G91.1");
  g.line("G17");
}

void fam_arcs_xy_ijk(Gen& g) {
  arcs(g, 17, false, false);
}
void fam_arcs_xy_r(Gen& g) {
  arcs(g, 17, true, false);
}
void fam_arcs_xz(Gen& g) {
  arcs(g, 18, g.r.coin(), false);
}
void fam_arcs_yz(Gen& g) {
  arcs(g, 19, g.r.coin(), false);
}
void fam_arcs_absolute_centre(Gen& g) {
  arcs(g, 17 + g.r.range(0, 2), false, true);
}

// Numbered and named parameters (local and global), parameters in words, the rule that every
// parameter on a line is read before any assignment on it takes effect.
void fam_params(Gen& g) {
  g.line("G21 G90 F900");
  g.line(fmt::format("#1 = {}", n3(g.r.dec(-30, 30))));
  g.line(fmt::format("#31 = {}", n3(g.r.dec(-30, 30))));
  g.line(fmt::format("#<xpos> = {}", n3(g.r.dec(-30, 30))));
  g.line(fmt::format("#<_ypos> = {}", n3(g.r.dec(-30, 30))));
  g.line(fmt::format("#<Mixed_Case> = {}", n3(g.r.dec(1, 9))));
  for (int i = 0; i < 8; ++i) {
    switch (g.r.range(0, 4)) {
      case 0:
        g.line("G1 X#1 Y#31");
        break;
      case 1:
        g.line("G1 X#<xpos> Y#<_ypos> Z#<mixed_case>");
        break;
      case 2:
        g.line("#1 = #31 #31 = #1");  // swap: reads happen before either assignment
        g.line("G0 X#1 Y#31");
        break;
      case 3:
        g.line(fmt::format("#2 = {} #3 = [#2 * 2]", n3(g.r.dec(-10, 10))));
        g.line("G1 X#2 Y#3");
        break;
      default:
        g.line(fmt::format("#[30 + 2] = {}", n3(g.r.dec(-10, 10))));  // computed number
        g.line("#4 = 32");
        g.line("#<xpos> = [#<xpos> + #32]");
        g.line("G1 X#<xpos> Y##4");  // ##4: the parameter whose number is #4
        break;
    }
  }
}

// Every operator and function of LinuxCNC's expressions, in coordinates.
void fam_expressions(Gen& g) {
  g.line("G21 G90 F1200");
  auto v = [&](int lo, int hi) { return n3(g.r.dec(lo, hi)); };
  std::vector<std::string> e = {
      fmt::format("[{} + {}]", v(-20, 20), v(-20, 20)),
      fmt::format("[{} - {}]", v(-20, 20), v(-20, 20)),
      fmt::format("[{} * {}]", v(-5, 5), v(-5, 5)),
      fmt::format("[{} / {}]", v(-20, 20), v(1, 9)),
      fmt::format("[{} MOD {}]", v(-50, 50), v(1, 9)),
      fmt::format("[{} ** {}]", v(0, 3), g.r.range(0, 3)),
      fmt::format("[[{} EQ {}] + 1]", g.r.range(0, 2), g.r.range(0, 2)),
      fmt::format("[[{} NE {}] + 2]", g.r.range(0, 2), g.r.range(0, 2)),
      fmt::format("[[{} GT {}] * 3]", v(-2, 2), v(-2, 2)),
      fmt::format("[[{} GE {}] * 4]", g.r.range(0, 2), g.r.range(0, 2)),
      fmt::format("[[{} LT {}] * 5]", v(-2, 2), v(-2, 2)),
      fmt::format("[[{} LE {}] * 6]", g.r.range(0, 2), g.r.range(0, 2)),
      fmt::format("[[{} AND {}] * 7]", g.r.range(0, 1), g.r.range(0, 1)),
      fmt::format("[[{} OR {}] * 8]", g.r.range(0, 1), g.r.range(0, 1)),
      fmt::format("[[{} XOR {}] * 9]", g.r.range(0, 1), g.r.range(0, 1)),
      fmt::format("ABS[{}]", v(-30, 30)),
      fmt::format("[ACOS[{}] / 10]", n3(g.r.dec(-1, 1))),
      fmt::format("[ASIN[{}] / 10]", n3(g.r.dec(-1, 1))),
      fmt::format("[ATAN[{}]/[{}] / 10]", v(-5, 5), v(-5, 5)),
      fmt::format("[COS[{}] * 10]", v(-360, 360)),
      fmt::format("EXP[{}]", v(-2, 3)),
      fmt::format("FIX[{}]", v(-20, 20)),
      fmt::format("FUP[{}]", v(-20, 20)),
      fmt::format("LN[{}]", v(1, 100)),
      fmt::format("ROUND[{}]", v(-20, 20)),
      fmt::format("[SIN[{}] * 10]", v(-360, 360)),
      fmt::format("SQRT[{}]", v(0, 400)),
      fmt::format("[TAN[{}] * 10]", v(-60, 60)),
      "[EXISTS[#<_defined>] * 10 + EXISTS[#<_never_set>]]",
      fmt::format("[-{} + -[{}] * +{}]", v(0, 5), v(-5, 5), v(0, 5)),   // unary minus and plus
      fmt::format("[{} - {} - {}]", v(-5, 5), v(-5, 5), v(-5, 5)),      // left associative
      fmt::format("[{} + {} * {} ** 2]", v(-5, 5), v(-5, 5), v(0, 2)),  // precedence
      fmt::format("[2 ** 3 ** 2 / 100]"),  // ** associates left in LinuxCNC: (2**3)**2
  };
  g.line("#<_defined> = 1");
  for (size_t i = 0; i < e.size(); ++i) {
    const std::string other = e[static_cast<size_t>(g.r.range(0, static_cast<int>(e.size()) - 1))];
    g.line(fmt::format("G1 X{} Y{}", e[i], other));
  }
}

// O-word subroutines: arguments, nested calls, return values, named-parameter scope.
void fam_subroutines(Gen& g) {
  g.line("o100 sub");
  g.line("  #<local> = [#1 * 2]");
  g.line("  G1 X#1 Y#2");
  g.line("  G1 X#<local> Y[#2 + #3]");
  g.line("o100 endsub");
  g.line("o<square> sub");
  g.line("  G1 X[#1] Y[#2] F[#4]");
  g.line("  G1 X[#1 + #3]");
  g.line("  G1 Y[#2 + #3]");
  g.line("  G1 X[#1]");
  g.line("  G1 Y[#2]");
  g.line("o<square> endsub");
  g.line("o<twice> sub");
  g.line("  o<twice_if> if [#1 GT 100]");
  g.line("    o<twice> return [100]");
  g.line("  o<twice_if> endif");
  g.line("  o<twice> return [#1 * 2]");
  g.line("o<twice> endsub");
  g.line("o<nest> sub");
  g.line("  o100 call [#1] [#1 + 1] [1]");
  g.line("  o<square> call [#1] [#1] [2] [300]");
  g.line("o<nest> endsub");
  g.line("G21 G90 F800");
  g.line("#1 = 77");  // a caller's #1..#30 are not the callee's
  for (int i = 0; i < 6; ++i) {
    switch (g.r.range(0, 3)) {
      case 0:
        g.line(fmt::format("o100 call [{}] [{}] [{}]", n3(g.r.dec(-20, 20)), n3(g.r.dec(-20, 20)),
                           n3(g.r.dec(-5, 5))));
        break;
      case 1:
        g.line(fmt::format("o<square> call [{}] [{}] [{}] [{}]", n3(g.r.dec(-20, 20)),
                           n3(g.r.dec(-20, 20)), n3(g.r.dec(1, 9)), g.r.range(200, 900)));
        break;
      case 2:
        g.line(fmt::format("o<twice> call [{}]", n3(g.r.dec(-80, 80))));
        g.line("G0 X#<_value> Y#1");
        break;
      default:
        g.line(fmt::format("o<nest> call [{}]", n3(g.r.dec(-20, 20))));
        break;
    }
  }
}

// if/elseif/else, while, do-while, repeat, continue.
void fam_control(Gen& g) {
  g.line("G21 G90 F1000");
  g.line(fmt::format("#<n> = {}", g.r.range(3, 9)));
  g.line(fmt::format("#<k> = {}", g.r.range(0, 3)));
  g.line("o1 if [#<k> EQ 0]");
  g.line("  G1 X1 Y1");
  g.line("o1 elseif [#<k> EQ 1]");
  g.line("  G1 X2 Y2");
  g.line("o1 elseif [#<k> GE 2 AND #<k> LT 3]");
  g.line("  G1 X3 Y3");
  g.line("o1 else");
  g.line("  G1 X4 Y4");
  g.line("o1 endif");
  g.line("#<i> = 0");
  g.line("o2 while [#<i> LT #<n>]");
  g.line("  #<i> = [#<i> + 1]");
  g.line(fmt::format("  o3 if [[#<i> MOD {}] EQ 0]", g.r.range(2, 3)));
  g.line("    o2 continue");
  g.line("  o3 endif");
  g.line(fmt::format("  G1 X[#<i> * {}] Y[#<i> * #<i> / 4]", n3(g.r.dec(1, 5))));
  // No 'break' here: LinuxCNC 2.9 miscounts later do/repeat loops after a 'break' in a skipped
  // body (docs/oracle.md); the reader's unit tests check break against the documented rules.
  g.r.range(4, 8);  // keeps the seeds' programs otherwise as they were
  g.line("o2 endwhile");
  g.line("#<j> = 0");
  g.line("o5 do");
  g.line(fmt::format("  G0 X[-#<j>] Y{}", n3(g.r.dec(-10, 10))));
  g.line("  #<j> = [#<j> + 1.5]");
  g.line(fmt::format("o5 while [#<j> LT {}]", g.r.range(0, 6)));
  g.line(fmt::format("o6 repeat [{}]", g.r.range(0, 4)));
  g.line(fmt::format("  G91 G1 X{} Y{}", n3(g.r.dec(-5, 5)), n3(g.r.dec(-5, 5))));
  g.line("  G90");
  g.line("o6 endrepeat");
}

// Work offsets: G10 L2 and L20, G54..G59.3.
void fam_work_offsets(Gen& g) {
  g.line("G21 G90 F1500");
  const std::array<const char*, 9> systems = {"G54", "G55",   "G56",   "G57",  "G58",
                                              "G59", "G59.1", "G59.2", "G59.3"};
  for (int i = 0; i < 8; ++i) {
    const int p = g.r.range(1, 9);
    if (g.r.coin()) {
      g.line(fmt::format("G10 L2 P{} X{} Y{} Z{}", p, n3(g.r.dec(-50, 50)), n3(g.r.dec(-50, 50)),
                         n3(g.r.dec(-10, 10))));
    } else {
      g.line(fmt::format("G10 L20 P{} X{} Y{}", p, n3(g.r.dec(-50, 50)), n3(g.r.dec(-50, 50))));
    }
    g.line(systems[static_cast<size_t>(g.r.range(0, 8))]);
    g.line(fmt::format("G1 X{} Y{} Z{}", n3(g.r.dec(-30, 30)), n3(g.r.dec(-30, 30)),
                       n3(g.r.dec(-5, 5))));
    if (g.r.range(0, 2) == 0) g.line(fmt::format("G10 L2 P0 X{}", n3(g.r.dec(-5, 5))));
    g.line(fmt::format("G0 X{} Y{}", n3(g.r.dec(-30, 30)), n3(g.r.dec(-30, 30))));
  }
  g.line("G54");
}

// Canned drilling cycles with both retract modes, repeats and incremental positions.
void fam_cycles(Gen& g) {
  g.line("G21 G90 G17 F300");
  g.line("G0 X0 Y0 Z20");
  const std::array<int, 6> cycles = {81, 82, 83, 73, 85, 89};
  for (int i = 0; i < 8; ++i) {
    const int c = cycles[static_cast<size_t>(g.r.range(0, 5))];
    const bool g98 = g.r.coin();
    const double r = g.r.dec(1, 5);
    const double z = g.r.dec(-10, -1);
    std::string s = fmt::format("{} G{} X{} Y{} Z{} R{}", g98 ? "G98" : "G99", c,
                                n3(g.r.dec(-30, 30)), n3(g.r.dec(-30, 30)), n3(z), n3(r));
    if (c == 83 || c == 73) s += " Q" + n3(g.r.dec(1, 4));
    if (c == 82 || c == 89) s += " P" + n3(g.r.dec(0, 1));
    g.line(s);
    // More holes in the same cycle, modal.
    for (int k = g.r.range(0, 2); k > 0; --k) {
      g.line(fmt::format("X{} Y{}", n3(g.r.dec(-30, 30)), n3(g.r.dec(-30, 30))));
    }
    if (g.r.range(0, 2) == 0) {  // a row of holes: G91 with L repeats
      g.line(fmt::format("G91 G{} X{} Y{} Z{} R{} L{}{}", c, n3(g.r.dec(-5, 5)), n3(g.r.dec(-5, 5)),
                         n3(g.r.dec(-6, -2)), n3(g.r.dec(-2, 0)), g.r.range(2, 4),
                         c == 83 || c == 73   ? " Q1"
                         : c == 82 || c == 89 ? " P0.2"
                                              : ""));
      g.line("G90");
    }
    g.line("G80");
    g.line(fmt::format("G0 Z{}", n3(g.r.dec(15, 25))));
  }
}

// Tool length offsets from the tool table (tool.tbl beside this file): G43 H, G43 with the
// loaded tool, G43.1, G49, tool changes.
void fam_tools(Gen& g) {
  g.line("G21 G90 F1000");
  g.line("G0 Z50");
  for (int i = 0; i < 8; ++i) {
    const int tool = g.r.range(1, 5);
    switch (g.r.range(0, 3)) {
      case 0:
        g.line(fmt::format("T{} M6", tool));
        g.line("G43");
        break;
      case 1:
        g.line(fmt::format("G43 H{}", tool));
        break;
      case 2:
        g.line(fmt::format("G43.1 Z{}", n3(g.r.dec(-20, 20))));
        break;
      default:
        g.line("G49");
        break;
    }
    g.line(fmt::format("G1 X{} Y{} Z{}", n3(g.r.dec(-30, 30)), n3(g.r.dec(-30, 30)),
                       n3(g.r.dec(-5, 20))));
    g.line(fmt::format("G0 Z{}", n3(g.r.dec(20, 40))));
  }
  g.line("G49");
}

// A bit of everything: a subroutine drilling with offsets, tools and arcs, under G20 or G21.
void fam_mixed(Gen& g) {
  const bool inch = g.r.coin();
  const double k = inch ? 1.0 / 25.4 : 1.0;
  auto v = [&](int lo, int hi) { return n4(g.r.dec(lo, hi, 4) * k); };
  g.line("o<hole> sub");
  g.line("  G0 X#1 Y#2");
  g.line("  G98 G81 Z#3 R#4");
  g.line("  G80");
  g.line("o<hole> endsub");
  g.line(inch ? "G20 G90 F20" : "G21 G90 F500");
  g.line(fmt::format("G10 L2 P2 X{} Y{} Z{}", v(-40, 40), v(-40, 40), v(-5, 5)));
  g.line("G55");
  g.line("T3 M6 G43");
  g.line(fmt::format("G0 Z{}", v(10, 20)));
  for (int i = 0; i < 5; ++i) {
    g.line(fmt::format("o<hole> call [{}] [{}] [{}] [{}]", v(-20, 20), v(-20, 20), v(-8, -1),
                       v(1, 3)));
  }
  g.line(fmt::format("G92 X{} Y{}", v(-5, 5), v(-5, 5)));
  const std::string rad = v(10, 20);
  g.line(fmt::format("G1 X{} Y0", rad));
  g.line(fmt::format("G3 X0 Y{} I-{} J0", rad, rad));
  g.line("G92.1 G49 G54");
}

// Cutter radius compensation: closed shapes (rectangles, rounded rectangles, regular polygons,
// circles) cut on a random side in a random direction with G41/G42 D (tool table diameters) or
// G41.1/G42.1 D, entered by a straight line or an arc from outside, with plunges, dwells and
// rapids in between, left by G40 and a straight move. Sizes keep every inside corner and arc
// wider than the tool, so rs274 accepts each program.
void fam_cutcomp(Gen& g) {
  g.line("G21 G17 G90 G0 X0 Y0 Z5");
  g.line(fmt::format("F{}", g.r.range(100, 2000)));
  const int shapes = g.r.range(2, 3);
  for (int k = 0; k < shapes; ++k) {
    const int form = g.r.range(0, 3);
    const double cx = g.r.dec(-60, 60, 2), cy = g.r.dec(-60, 60, 2);
    // Tool: from the table (tools 1..3: 6, 3, 10 mm) or a diameter on the line.
    const int side = g.r.range(0, 1);  // 0 left, 1 right
    double radius;
    std::string comp_on;
    if (g.r.coin()) {
      const int t = g.r.range(1, 3);
      radius = t == 1 ? 3 : t == 2 ? 1.5 : 5;
      comp_on = fmt::format("G4{} D{}", side ? "2" : "1", t);
    } else {
      const double d = g.r.dec(1, 10, 2);
      radius = d / 2;
      comp_on = fmt::format("G4{}.1 D{}", side ? "2" : "1", n3(d));
    }
    const bool ccw = g.r.coin();
    // The shape's points in travel order (polygon corners; arcs between for the rounded form).
    std::vector<std::pair<double, double>> pts;
    if (form == 0 || form == 1) {
      const double w = g.r.dec(32, 60, 2), h = g.r.dec(32, 60, 2);
      pts = {{cx - w / 2, cy - h / 2},
             {cx + w / 2, cy - h / 2},
             {cx + w / 2, cy + h / 2},
             {cx - w / 2, cy + h / 2}};
    } else if (form == 2) {
      const int n = g.r.range(3, 8);
      const double rr = g.r.dec(15, 40, 2);
      const double a0 = g.r.dec(0, 360, 1) * kPi / 180;
      for (int i = 0; i < n; ++i) {
        const double a = a0 + 2 * kPi * i / n;
        pts.push_back({std::round((cx + rr * std::cos(a)) * 1000) / 1000,
                       std::round((cy + rr * std::sin(a)) * 1000) / 1000});
      }
    }
    if (!ccw) std::reverse(pts.begin(), pts.end());
    const std::string cut = g.r.coin() ? " F" + std::to_string(g.r.range(100, 2000)) : "";
    if (form == 3) {  // a circle, entered along a radius from its centre side or from outside
      const double rr = g.r.dec(static_cast<int>(radius) + 8, 40, 2);
      const double sx = cx + rr, sy = cy;
      g.line(fmt::format("G0 X{} Y{}", n3(sx + 2 * radius + 5), n3(sy - 2 * radius - 5)));
      g.line(comp_on);
      g.line(fmt::format("G1 X{} Y{}{}", n3(sx), n3(sy), cut));
      g.line("G1 Z-1");
      g.line(fmt::format("G{} X{} Y{} I{} J0", ccw ? 3 : 2, n3(sx), n3(sy), n3(-rr)));
      g.line(fmt::format("G40 G1 X{} Y{}", n3(sx + 2 * radius + 5), n3(sy + 2 * radius + 5)));
      g.line("G0 Z5");
      continue;
    }
    // Entry along the first edge's line, from behind its first point.
    const auto& p0 = pts[0];
    const auto& p1 = pts[1];
    const double l01 = std::hypot(p1.first - p0.first, p1.second - p0.second);
    const double ex =
        std::round((p0.first - (p1.first - p0.first) / l01 * (2 * radius + 5)) * 1000) / 1000;
    const double ey =
        std::round((p0.second - (p1.second - p0.second) / l01 * (2 * radius + 5)) * 1000) / 1000;
    g.line(fmt::format("G0 X{} Y{}", n3(ex), n3(ey)));
    g.line(comp_on);
    g.line(fmt::format("G1 X{} Y{}{}", n3(p0.first), n3(p0.second), cut));
    g.line(fmt::format("G1 Z{}", n3(g.r.dec(-3, 0, 2))));
    if (g.r.range(0, 3) == 0) g.line("G4 P0.5");
    const size_t n = pts.size();
    if (form == 1) {  // rounded rectangle: fillets of radius rf at each corner, tangent
      const double rf = g.r.dec(static_cast<int>(radius) + 2, static_cast<int>(radius) + 6, 2);
      // Walk the edges: from p[i] shortened by rf at both ends, a fillet about the corner.
      for (size_t i = 0; i < n; ++i) {
        const auto& a = pts[i];
        const auto& b = pts[(i + 1) % n];
        const auto& c = pts[(i + 2) % n];
        const double lab = std::hypot(b.first - a.first, b.second - a.second);
        const double ux = (b.first - a.first) / lab, uy = (b.second - a.second) / lab;
        const double lbc = std::hypot(c.first - b.first, c.second - b.second);
        const double vx = (c.first - b.first) / lbc, vy = (c.second - b.second) / lbc;
        const double qx = b.first - rf * ux, qy = b.second - rf * uy;
        const double ox = b.first + rf * vx, oy = b.second + rf * vy;
        g.line(fmt::format("G1 X{} Y{}", n3(qx), n3(qy)));
        // Centre: from q, rf along the next edge's direction.
        g.line(fmt::format("G{} X{} Y{} I{} J{}", ccw ? 3 : 2, n3(ox), n3(oy), n3(rf * vx),
                           n3(rf * vy)));
      }
    } else {
      for (size_t i = 1; i <= n; ++i) {
        const auto& p = pts[i % n];
        g.line(fmt::format("{} X{} Y{}", g.r.range(0, 5) == 0 ? "G0" : "G1", n3(p.first),
                           n3(p.second)));
        if (g.r.range(0, 5) == 0) g.line("G1 Z" + n3(g.r.dec(-3, 0, 2)));
      }
    }
    if (g.r.coin()) {
      g.line("G40");
      g.line(fmt::format("G1 X{} Y{}", n3(ex), n3(ey)));
    } else {
      g.line(fmt::format("G40 G0 X{} Y{}", n3(ex), n3(ey)));
    }
    g.line("G0 Z5");
  }
}

// Lathe diameter mode: G7 X words are diameters (absolute, incremental, G92, G10 L2), G8
// radii; in the XZ plane with R arcs.
void fam_lathe_diameter(Gen& g) {
  g.line("G21 G18 G90 G0 X40 Z5");
  g.line(fmt::format("F{}", g.r.range(50, 500)));
  bool dia = true;
  g.line("G7");
  for (int i = 0; i < 12; ++i) {
    const int kind = g.r.range(0, 6);
    if (kind == 0) {
      dia = !dia;
      g.line(dia ? "G7" : "G8");
    } else if (kind == 1) {
      g.line(fmt::format("G91 G1 X{} Z{}", n3(g.r.dec(-10, 10)), n3(g.r.dec(-5, 5))));
      g.line("G90");
    } else if (kind == 2) {
      g.line(fmt::format("G92 X{}", n3(g.r.dec(0, 50))));
      g.line(fmt::format("G1 X{} Z{}", n3(g.r.dec(0, 60)), n3(g.r.dec(-30, 5))));
      g.line("G92.1");
    } else if (kind == 3) {
      g.line(fmt::format("G10 L2 P1 X{} Z{}", n3(g.r.dec(-5, 5)), n3(g.r.dec(-5, 5))));
      g.line(fmt::format("G0 X{} Z{}", n3(g.r.dec(0, 60)), n3(g.r.dec(-30, 5))));
    } else if (kind == 4) {
      // An R arc: R well above half the chord (X in this mode's unit, Z in mm).
      g.line(fmt::format("G{} X{} Z{} R{}", g.r.coin() ? 2 : 3, n3(g.r.dec(0, 20)),
                         n3(g.r.dec(-40, -20)), n3(g.r.dec(80, 120))));
    } else {
      g.line(
          fmt::format("G{} X{} Z{}", g.r.coin() ? 0 : 1, n3(g.r.dec(0, 60)), n3(g.r.dec(-30, 5))));
    }
  }
  g.line("G10 L2 P1 X0 Z0");
  g.line("G8");
}

// G5 cubic and G5.1 quadratic splines (XY): random control offsets, continued G5s without I J,
// G91 and G20 splines, lines between, under a work offset and G92.
void fam_splines(Gen& g) {
  g.line("G21 G90 G17 G0 X0 Y0 Z1");
  g.line(fmt::format("F{}", g.r.range(100, 2000)));
  if (g.r.coin())
    g.line(fmt::format("G10 L2 P1 X{} Y{}", n3(g.r.dec(-20, 20)), n3(g.r.dec(-20, 20))));
  if (g.r.coin()) g.line(fmt::format("G92 X{}", n3(g.r.dec(-10, 10))));
  auto xy = [&](int lim) {
    return fmt::format("X{} Y{}", n3(g.r.dec(-lim, lim)), n3(g.r.dec(-lim, lim)));
  };
  auto off = [&](char a, char b, int lim) {
    return fmt::format("{}{} {}{}", a, n3(g.r.dec(-lim, lim)), b, n3(g.r.dec(-lim, lim)));
  };
  for (int i = 0; i < 10; ++i) {
    switch (g.r.range(0, 5)) {
      case 0:
        g.line("G5.1 " + xy(60) + " " + off('I', 'J', 30));
        break;
      case 1:
      case 2:
        g.line("G5 " + xy(60) + " " + off('I', 'J', 30) + " " + off('P', 'Q', 30));
        // Continued: without I J, the curve leaves in the last G5's direction (I J = -(P Q)).
        g.line("G5 " + xy(60) + " " + off('P', 'Q', 30));
        break;
      case 3:
        g.line("G1 " + xy(60));
        break;
      case 4:
        g.line(fmt::format("G20 G5.1 X{} Y{} I{} J{}", n4(g.r.dec(-2, 2, 4)), n4(g.r.dec(-2, 2, 4)),
                           n4(g.r.dec(-1, 1, 4)), n4(g.r.dec(-1, 1, 4))));
        g.line("G21");
        break;
      default:
        g.line("G91 G5 " + xy(20) + " " + off('I', 'J', 10) + " " + off('P', 'Q', 10));
        g.line("G90");
        break;
    }
  }
  g.line("G92.1");
  g.line("G10 L2 P1 X0 Y0");
}

// M70/M71/M72 at the top level and M73 in subroutines (restored on endsub and on return, nested
// calls): units, distance mode, feed, coordinate system and spindle changed and put back, with
// moves after each restore.
void fam_modal_state(Gen& g) {
  g.line("o<inch> sub");
  g.line("M73");
  g.line("G20 G91 F20 S500 M4");
  g.line("G1 X#1 Y#2");
  g.line("o<inch-if> if [#3 GT 0]");
  g.line("o<inch-if> return");
  g.line("o<inch-if> endif");
  g.line("G1 X#2");
  g.line("o<inch> endsub");
  g.line("o<outer> sub");
  g.line("M73");
  g.line("G91 G55");
  g.line("o<inch> call [#1] [#2] [0]");
  g.line("G1 X#1 Y#2");
  g.line("o<outer> endsub");
  g.line("G21 G90 G54 G0 X0 Y0 Z0");
  g.line(fmt::format("G10 L2 P2 X{} Y{}", n3(g.r.dec(-30, 30)), n3(g.r.dec(-30, 30))));
  g.line(fmt::format("F{} S1000 M3", g.r.range(100, 2000)));
  auto small = [&] { return n4(g.r.dec(-1, 1, 4)); };
  auto abs_line = [&] {
    g.line(fmt::format("G1 X{} Y{}", n3(g.r.dec(-50, 50)), n3(g.r.dec(-50, 50))));
  };
  for (int i = 0; i < 8; ++i) {
    switch (g.r.range(0, 4)) {
      case 0:
        g.line(fmt::format("o<inch> call [{}] [{}] [{}]", small(), small(), g.r.range(0, 1)));
        abs_line();
        break;
      case 1:
        g.line("M70");
        g.line(fmt::format("G20 G91 G56 G1 X{} Y{} F{}", small(), small(), g.r.range(5, 50)));
        g.line("M72");
        abs_line();
        if (g.r.coin()) {
          g.line("G91 G1 X1");
          g.line("M72");
          abs_line();
        }
        g.line("M71");
        break;
      case 2:
        g.line(fmt::format("o<outer> call [{}] [{}]", small(), small()));
        abs_line();
        break;
      case 3:
        // On one line the restore comes before G91 (and after G20): an incremental move in mm.
        g.line("M70");
        g.line(fmt::format("G21 G91 M72 G1 X{}", n3(g.r.dec(-5, 5))));
        g.line("G90 M71");
        break;
      default:
        abs_line();
        break;
    }
  }
}

using Family = void (*)(Gen&);
const std::vector<std::pair<std::string, Family>>& families() {
  static const std::vector<std::pair<std::string, Family>> f = {
      {"lines", fam_lines},
      {"mcodes", fam_mcodes},
      {"units", fam_units},
      {"incremental", fam_incremental},
      {"g92", fam_g92},
      {"g92-cancel", fam_g92_cancel},
      {"arcs-xy-ijk", fam_arcs_xy_ijk},
      {"arcs-xy-r", fam_arcs_xy_r},
      {"arcs-xz", fam_arcs_xz},
      {"arcs-yz", fam_arcs_yz},
      {"arcs-absolute-centre", fam_arcs_absolute_centre},
      {"params", fam_params},
      {"expressions", fam_expressions},
      {"subroutines", fam_subroutines},
      {"control", fam_control},
      {"work-offsets", fam_work_offsets},
      {"cycles", fam_cycles},
      {"tools", fam_tools},
      {"mixed", fam_mixed},
      {"cutcomp", fam_cutcomp},
      {"lathe-diameter", fam_lathe_diameter},
      {"splines", fam_splines},
      {"modal-state", fam_modal_state},
  };
  return f;
}

}  // namespace

std::vector<std::string> generator_families() {
  std::vector<std::string> names;
  for (const auto& f : families()) names.push_back(f.first);
  return names;
}

GeneratedProgram generate(const std::string& family, uint64_t seed) {
  for (const auto& [name, fn] : families()) {
    if (name != family) continue;
    uint64_t h = 1469598103934665603ull;  // FNV-1a of the family name
    for (const char c : name) h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ull;
    Gen g(seed ^ h);
    g.line(fmt::format("(fpgacnc oracle test: generated program, family {}, seed {})", name, seed));
    fn(g);
    g.line("M2");
    return {fmt::format("gen/{}-{}", name, seed), g.t};
  }
  throw std::invalid_argument("unknown generator family " + family);
}

std::vector<GeneratedProgram> generate_all(int seeds_per_family) {
  std::vector<GeneratedProgram> all;
  for (const auto& name : generator_families()) {
    for (int s = 1; s <= seeds_per_family; ++s) all.push_back(generate(name, s));
  }
  return all;
}

}  // namespace fpgacnc::oracle
