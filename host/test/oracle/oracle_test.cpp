// The oracle test (docs/oracle.md): LinuxCNC's own interpreter (`rs274`, package
// linuxcnc-uspace) and ours read the same rs274ngc programs - LinuxCNC sample programs, the
// corpus files of the LinuxCNC dialect, generated programs - and must agree on which they refuse
// and on the end point of every move. Programs our interpreter cannot run yet are listed with
// our exact message in expected_refusals.txt: a ratchet that fails when an outcome changes in
// either direction.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include <toml.hpp>

#include "fpgacnc/gcode/interpreter.h"
#include "generator.h"
#include "rs274.h"

namespace fs = std::filesystem;
using namespace fpgacnc;
using oracle::CanonMove;
using oracle::OracleRun;

namespace {

constexpr double kTol = 1e-6;  // mm, on every coordinate of every end point and arc centre
constexpr int kSeedsPerFamily = 3;
constexpr size_t kMaxReported = 6;  // disagreements printed per program
// expected_refusals.txt's word for "ours accepts a program rs274 refuses".
constexpr const char* kAccepted = "accepted";

const std::string kData = FPGACNC_ORACLE_DATA;
const std::string kShim = FPGACNC_ORACLE_SHIM;
const std::string kSource = FPGACNC_SOURCE_DIR;

// Options for our interpreter: LinuxCNC's dialect, the same tool table (tool.tbl, in mm) and a
// rotary A axis as the fourth (rs274 has A B C; the moves compared are X Y Z).
gcode::Options our_options() {
  gcode::Options o;
  o.dialect = gcode::Dialect::kLinuxCnc;
  o.fourth_axis = 'A';
  o.tool_table = kData + "/tool.tbl";
  return o;
}

struct Program {
  std::string name;  // "linuxcnc/<file>", "corpus/<path>", "gen/<family>-<seed>"
  std::string path;
};

struct OurRun {
  bool refused = false;
  std::string message;  // what() without the file name: "LINE:COL: error: ..."
  gcode::Program program;
};

OurRun run_ours(const std::string& path) {
  OurRun r;
  try {
    r.program = gcode::parse_file(path, our_options());
  } catch (const std::exception& e) {
    r.refused = true;
    // Stable across checkouts and temporary directories: the leading "FILE:" goes, any other
    // mention of the path becomes "<file>".
    std::string m = e.what();
    const std::string base = fs::path(path).filename().string();
    if (m.rfind(path + ":", 0) == 0) {
      m = m.substr(path.size() + 1);
    } else if (m.rfind(base + ":", 0) == 0) {
      m = m.substr(base.size() + 1);
    }
    for (size_t at; (at = m.find(path)) != std::string::npos;) m.replace(at, path.size(), "<file>");
    r.message = m;
  }
  return r;
}

// Zero-length straight moves are dropped on both sides before matching: they move nothing, and
// LinuxCNC prints one where ours may not (a bare G0 line, G28's intermediate point when it is the
// current position). Arcs are kept (a full circle ends where it starts).
constexpr double kZeroLength = 1e-9;  // mm

std::vector<const gcode::Move*> our_moves(const gcode::Program& p) {
  std::vector<const gcode::Move*> v;
  for (const auto& c : p.commands) {
    const auto* m = std::get_if<gcode::Move>(&c);
    if (!m) continue;
    const bool straight = m->motion == gcode::Motion::kRapid || m->motion == gcode::Motion::kLinear;
    bool moves = false;
    for (size_t k = 0; k < m->end.size(); ++k) {
      moves = moves || std::fabs(m->end[k] - m->start[k]) > kZeroLength;
    }
    if (straight && !moves) continue;
    v.push_back(m);
  }
  return v;
}

std::vector<const CanonMove*> oracle_moves(const OracleRun& o) {
  std::vector<const CanonMove*> v;
  oracle::Xyz at{};  // rs274 starts at machine 0, 0, 0
  for (const auto& m : o.moves) {
    const bool straight = m.kind == CanonMove::Kind::kTraverse || m.kind == CanonMove::Kind::kFeed;
    bool moves = false;
    for (size_t k = 0; k < 3; ++k) moves = moves || std::fabs(m.end[k] - at[k]) > kZeroLength;
    if (m.kind != CanonMove::Kind::kOther) at = m.end;  // a spline's end: its last point
    if (straight && !moves) continue;
    v.push_back(&m);
  }
  return v;
}

std::vector<const gcode::Dwell*> our_dwells(const gcode::Program& p) {
  std::vector<const gcode::Dwell*> v;
  for (const auto& c : p.commands) {
    if (const auto* d = std::get_if<gcode::Dwell>(&c)) v.push_back(d);
  }
  return v;
}

std::string xyz(const oracle::Xyz& p) {
  return fmt::format("({:.9g}, {:.9g}, {:.9g})", p[0], p[1], p[2]);
}

// (if, not switch: alternatives added to Motion later need no change here)
const char* motion_name(gcode::Motion m) {
  if (m == gcode::Motion::kRapid) return "rapid";
  if (m == gcode::Motion::kLinear) return "linear";
  if (m == gcode::Motion::kArcCw) return "arc cw";
  if (m == gcode::Motion::kArcCcw) return "arc ccw";
  return "other motion";
}

// A spline (rs274's NURBS_FEED) as a rational Bezier curve, sampled densely: a point's distance
// from the polyline through the samples is its distance from the curve to within
// max|C''| / (8 kSplineSamples^2) (below 1e-6 mm for the test's curves).
constexpr int kSplineSamples = 4096;
// Our pieces of a spline must stay this close to rs274's curve: the machine's arc tolerance (our
// interpreter's default Options::arc_tolerance_mm) and the comparison's rounding.
const double kSplineTol = gcode::Options{}.arc_tolerance_mm + kTol;

std::vector<oracle::Xyz> spline_samples(const CanonMove& a) {
  const size_t n = a.control.size();
  std::vector<oracle::Xyz> pts;
  pts.reserve(kSplineSamples + 1);
  for (int s = 0; s <= kSplineSamples; ++s) {
    const double t = static_cast<double>(s) / kSplineSamples;
    oracle::Xyz p{};
    double den = 0.0;
    for (size_t k = 0; k < n; ++k) {
      // Bernstein polynomial of degree n - 1.
      double bern = 1.0;
      for (size_t i = 0; i < k; ++i) bern *= t * static_cast<double>(n - 1 - i) / (i + 1.0);
      bern *= std::pow(1.0 - t, static_cast<double>(n - 1 - k));
      const double wb = bern * a.weights[k];
      den += wb;
      for (size_t c = 0; c < 3; ++c) p[c] += wb * a.control[k][c];
    }
    for (size_t c = 0; c < 3; ++c) p[c] /= den;
    pts.push_back(p);
  }
  return pts;
}

double distance_to_polyline(const std::vector<oracle::Xyz>& pl, const oracle::Xyz& p) {
  double best = 1e300;
  for (size_t k = 1; k < pl.size(); ++k) {
    const oracle::Xyz& a = pl[k - 1];
    const oracle::Xyz& b = pl[k];
    double ab2 = 0.0, apab = 0.0;
    for (size_t c = 0; c < 3; ++c) {
      ab2 += (b[c] - a[c]) * (b[c] - a[c]);
      apab += (p[c] - a[c]) * (b[c] - a[c]);
    }
    const double t = ab2 > 0 ? std::clamp(apab / ab2, 0.0, 1.0) : 0.0;
    double d2 = 0.0;
    for (size_t c = 0; c < 3; ++c) {
      const double q = a[c] + t * (b[c] - a[c]) - p[c];
      d2 += q * q;
    }
    best = std::min(best, d2);
  }
  return std::sqrt(best);
}

// Our straight pieces of one rs274 spline: from `j` on, the moves of the spline's source line up
// to the first that ends at the spline's end. Compared by the start, the end (kTol) and the
// largest distance of the pieces' ends and midpoints from rs274's curve (kSplineTol).
std::vector<std::string> compare_spline(const CanonMove& a,
                                        const std::vector<const gcode::Move*>& mv, size_t& j) {
  std::vector<std::string> why;
  const size_t first = j;
  auto end_of = [](const gcode::Move& m) { return oracle::Xyz{m.end[0], m.end[1], m.end[2]}; };
  auto dist = [](const oracle::Xyz& p, const oracle::Xyz& q) {
    return std::max({std::fabs(p[0] - q[0]), std::fabs(p[1] - q[1]), std::fabs(p[2] - q[2])});
  };
  while (j < mv.size() && mv[j]->line == a.line) {
    const bool done = dist(end_of(*mv[j]), a.end) <= kTol;
    ++j;
    if (done) break;
  }
  if (j == first) {
    why.push_back("ours makes no move for rs274's spline");
    return why;
  }
  const oracle::Xyz start{mv[first]->start[0], mv[first]->start[1], mv[first]->start[2]};
  if (dist(start, a.control.front()) > kTol)
    why.push_back(fmt::format("spline start rs274 {} ours {}", xyz(a.control.front()), xyz(start)));
  if (dist(end_of(*mv[j - 1]), a.end) > kTol)
    why.push_back(fmt::format("spline end rs274 {} ours {}", xyz(a.end), xyz(end_of(*mv[j - 1]))));
  const auto curve = spline_samples(a);
  double worst = 0.0;
  for (size_t k = first; k < j; ++k) {
    if (mv[k]->motion != gcode::Motion::kLinear)
      why.push_back(fmt::format("spline piece {} is {}", k - first, motion_name(mv[k]->motion)));
    const oracle::Xyz e = end_of(*mv[k]);
    oracle::Xyz mid{};
    for (size_t c = 0; c < 3; ++c) mid[c] = 0.5 * (mv[k]->start[c] + e[c]);
    worst = std::max({worst, distance_to_polyline(curve, e), distance_to_polyline(curve, mid)});
  }
  if (worst > kSplineTol)
    why.push_back(fmt::format("our {} pieces leave rs274's spline by {:.3g} mm (> {:.3g})",
                              j - first, worst, kSplineTol));
  return why;
}

// Every way the two runs of one accepted program differ; empty when they agree. Moves are
// matched one to one in order: STRAIGHT_TRAVERSE with a rapid, STRAIGHT_FEED with a linear
// move, ARC_FEED with an arc of the same direction (rotation > 0: G3, counter-clockwise); a
// spline (NURBS_FEED) with our straight pieces of its line (compare_spline).
std::vector<std::string> compare(const std::string& name, const OracleRun& o,
                                 const gcode::Program& ours) {
  std::vector<std::string> d;
  const auto mv = our_moves(ours);
  const auto om = oracle_moves(o);
  size_t i = 0, j = 0;
  for (; i < om.size() && j < mv.size(); ++i) {
    const CanonMove& a = *om[i];
    const gcode::Move& b = *mv[j];
    if (a.kind == CanonMove::Kind::kSpline) {
      const size_t first = j;
      const auto why = compare_spline(a, mv, j);
      if (!why.empty()) {
        std::string all;
        for (const auto& w : why) all += (all.empty() ? "" : "; ") + w;
        d.push_back(fmt::format("{}:{}: spline {} (our moves {}..{}): {}  [rs274: {}]", name,
                                a.line, i, first, j, all, a.text));
      }
      continue;
    }
    ++j;
    const oracle::Xyz be{b.end[0], b.end[1], b.end[2]};
    std::vector<std::string> why;
    bool kind_ok = false;
    switch (a.kind) {
      case CanonMove::Kind::kTraverse:
        kind_ok = b.motion == gcode::Motion::kRapid;
        break;
      case CanonMove::Kind::kFeed:
        kind_ok = b.motion == gcode::Motion::kLinear;
        break;
      case CanonMove::Kind::kArc:
        kind_ok = (a.rotation > 0 && b.motion == gcode::Motion::kArcCcw) ||
                  (a.rotation < 0 && b.motion == gcode::Motion::kArcCw);
        break;
      case CanonMove::Kind::kSpline:
      case CanonMove::Kind::kOther:
        break;
    }
    if (!kind_ok) why.push_back(fmt::format("rs274 {} vs ours {}", a.name, motion_name(b.motion)));
    if (a.kind != CanonMove::Kind::kOther) {
      double dev = 0.0;
      for (size_t k = 0; k < 3; ++k) dev = std::max(dev, std::fabs(a.end[k] - be[k]));
      if (dev > kTol) {
        why.push_back(
            fmt::format("end rs274 {} ours {} (off by {:.3g} mm)", xyz(a.end), xyz(be), dev));
      }
    }
    if (a.kind == CanonMove::Kind::kArc && kind_ok) {
      if (std::abs(a.rotation) != b.extra_turns + 1) {
        why.push_back(
            fmt::format("rs274 arc of {} turns, ours {}", std::abs(a.rotation), b.extra_turns + 1));
      }
      // Our centre is (u, v) in the plane's axis order (gcode::plane_axes).
      const gcode::PlaneAxes pa = gcode::plane_axes(b.plane);
      const bool same_plane = (a.plane == oracle::Plane::kXY && b.plane == gcode::Plane::kXY) ||
                              (a.plane == oracle::Plane::kXZ && b.plane == gcode::Plane::kZX) ||
                              (a.plane == oracle::Plane::kYZ && b.plane == gcode::Plane::kYZ);
      if (!same_plane) why.push_back("arc in another plane");
      const double dev = std::max(std::fabs(a.centre[static_cast<size_t>(pa.u)] - b.center[0]),
                                  std::fabs(a.centre[static_cast<size_t>(pa.v)] - b.center[1]));
      if (dev > kTol) {
        why.push_back(fmt::format("centre rs274 ({:.9g}, {:.9g}) ours ({:.9g}, {:.9g})",
                                  a.centre[static_cast<size_t>(pa.u)],
                                  a.centre[static_cast<size_t>(pa.v)], b.center[0], b.center[1]));
      }
    }
    if (a.line != b.line) {
      why.push_back(fmt::format("source line rs274 {} ours {}", a.line, b.line));
    }
    if (!why.empty()) {
      std::string all;
      for (const auto& w : why) all += (all.empty() ? "" : "; ") + w;
      d.push_back(fmt::format("{}:{}: move {}: {}  [rs274: {}]", name, b.line, i, all, a.text));
    }
  }
  if (i < om.size() || j < mv.size()) {
    d.push_back(fmt::format("{}: rs274 makes {} moves, ours {} (matched {} and {})", name,
                            om.size(), mv.size(), i, j));
  }
  if (i < om.size()) {
    const CanonMove& a = *om[i];
    d.push_back(fmt::format("{}:{}: move {}: only rs274 makes it: {} to {}  [rs274: {}]", name,
                            a.line, i, a.name, xyz(a.end), a.text));
  } else if (j < mv.size()) {
    const gcode::Move& b = *mv[j];
    d.push_back(fmt::format("{}:{}: move {}: only ours makes it: {} to {}", name, b.line, j,
                            motion_name(b.motion), xyz({b.end[0], b.end[1], b.end[2]})));
  }
  const auto dw = our_dwells(ours);
  if (dw.size() != o.dwells.size()) {
    d.push_back(
        fmt::format("{}: rs274 makes {} dwells, ours {}", name, o.dwells.size(), dw.size()));
  }
  for (size_t i = 0; i < std::min(dw.size(), o.dwells.size()); ++i) {
    if (std::fabs(dw[i]->seconds - o.dwells[i].seconds) > 1e-9 || dw[i]->line != o.dwells[i].line) {
      d.push_back(fmt::format("{}:{}: dwell {}: rs274 {} s (line {}), ours {} s", name, dw[i]->line,
                              i, o.dwells[i].seconds, o.dwells[i].line, dw[i]->seconds));
    }
  }
  return d;
}

// expected_refusals.txt: "<program name><TAB><our exact message>" per line, '#' comments.
std::map<std::string, std::string> read_expected(const std::string& path) {
  std::map<std::string, std::string> m;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    const size_t tab = line.find('\t');
    if (tab == std::string::npos) {
      ADD_FAILURE() << path << ": line without a TAB: " << line;
      continue;
    }
    m[line.substr(0, tab)] = line.substr(tab + 1);
  }
  return m;
}

std::vector<Program> sample_programs() {
  std::vector<Program> v;
  std::ifstream in(kData + "/samples.txt");
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    v.push_back({"linuxcnc/" + line, "/usr/share/linuxcnc/ncfiles/" + line});
  }
  return v;
}

// Hand-written programs on the edges of the language (programs/*.ngc); programs/pending/*.ngc
// (both interpreters accept them but disagree: bugs of ours, docs/oracle.md) only with
// FPGACNC_ORACLE_PENDING=1.
std::vector<Program> edge_programs() {
  std::vector<Program> v;
  const char* pending = std::getenv("FPGACNC_ORACLE_PENDING");
  const bool with_pending = pending && *pending == '1';
  for (const std::string dir : {"programs", "programs/pending"}) {
    if (dir == "programs/pending" && !with_pending) continue;
    const fs::path root = fs::path(kData) / dir;
    if (!fs::exists(root)) continue;
    std::vector<Program> here;
    for (const auto& e : fs::directory_iterator(root)) {
      if (!e.is_regular_file() || e.path().extension() != ".ngc") continue;
      here.push_back({(dir == "programs" ? "edge/" : "pending/") + e.path().filename().string(),
                      e.path().string()});
    }
    std::sort(here.begin(), here.end(),
              [](const Program& a, const Program& b) { return a.name < b.name; });
    v.insert(v.end(), here.begin(), here.end());
  }
  return v;
}

// Corpus files of the LinuxCNC dialect: the entries of corpus/manifest.toml with dialect
// "linuxcnc"; without a manifest, every *.ngc file under corpus/ (LinuxCNC's own file
// extension) and every file under a corpus directory named "linuxcnc". FPGACNC_ORACLE_CORPUS
// names another corpus directory.
std::vector<Program> corpus_programs() {
  std::vector<Program> v;
  const char* env = std::getenv("FPGACNC_ORACLE_CORPUS");
  const fs::path root = env && *env ? fs::path(env) : fs::path(kSource) / "corpus";
  if (!fs::exists(root)) return v;
  if (fs::exists(root / "manifest.toml")) {
    const auto manifest = toml::parse((root / "manifest.toml").string());
    for (const auto& f : toml::find<toml::array>(manifest, "file")) {
      if (toml::find_or<std::string>(f, "dialect", "") != "linuxcnc") continue;
      const auto rel = toml::find<std::string>(f, "path");
      v.push_back({"corpus/" + rel, (root / rel).string()});
    }
  } else {
    for (const auto& e : fs::recursive_directory_iterator(root)) {
      if (!e.is_regular_file()) continue;
      const fs::path rel = fs::relative(e.path(), root);
      const bool ngc = e.path().extension() == ".ngc";
      const bool in_linuxcnc = std::any_of(rel.begin(), rel.end(),
                                           [](const fs::path& part) { return part == "linuxcnc"; });
      const std::string fname = e.path().filename().string();
      const bool data_file = !(fname.rfind("LICENSE", 0) == 0 || fname.rfind("COPYING", 0) == 0 ||
                               e.path().extension() == ".md" || e.path().extension() == ".txt");
      if ((ngc || in_linuxcnc) && data_file) {
        v.push_back({"corpus/" + rel.string(), e.path().string()});
      }
    }
  }
  std::sort(v.begin(), v.end(), [](const Program& a, const Program& b) { return a.name < b.name; });
  return v;
}

struct Row {
  std::string name, rs274, ours, verdict, ours_note;
  size_t rs274_moves = 0, our_moves = 0;
};

class TempDir {
 public:
  TempDir() {
    char t[] = "/tmp/fpgacnc-oracle-gen-XXXXXX";
    if (::mkdtemp(t) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = t;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

oracle::Rs274Setup setup_or_fail() {
  oracle::Rs274Setup s;
  const auto rs = oracle::find_rs274();
  if (!rs) {
    throw std::runtime_error(
        "rs274 (LinuxCNC's stand-alone interpreter) not found: install the Debian package "
        "linuxcnc-uspace (scripts/install-deps.sh does), or set FPGACNC_RS274 to its path");
  }
  s.rs274 = *rs;
  s.shim = kShim;
  s.tool_mm = kData + "/tool.tbl";
  if (!fs::exists(s.shim)) throw std::runtime_error("precision library missing: " + s.shim);
  return s;
}

}  // namespace

// rs274 is there, runs, and reads through the precision library: exact numbers (rs274 alone
// prints 4 decimals), source lines, inches converted, work offsets, G92 and tool length offsets
// applied. Expected values follow from the program text and LinuxCNC's documented semantics.
TEST(Oracle, Rs274RunsAndReadsExactly) {
  oracle::Rs274Setup setup;
  try {
    setup = setup_or_fail();
  } catch (const std::exception& e) {
    FAIL() << e.what();
  }
  TempDir tmp;
  const std::string path = (tmp.path() / "probe.ngc").string();
  std::ofstream(path) << "G21 G90\n"                // 1
                         "G0 X0.1234567 Y-2\n"      // 2
                         "G20\n"                    // 3
                         "G1 X1 F10\n"              // 4
                         "G21\n"                    // 5
                         "G10 L2 P1 X10 Y20 Z30\n"  // 6
                         "G0 X1 Y1 Z1\n"            // 7
                         "G92 X0\n"                 // 8
                         "G0 X2\n"                  // 9
                         "G92.1\n"                  // 10
                         "T1 M6\n"                  // 11
                         "G43 H1\n"                 // 12
                         "G1 Z0 F100\n"             // 13
                         "G2 X5 Y1 I1 J0\n"         // 14: half circle from X3
                         "G4 P0.25\n"               // 15
                         "M2\n";
  const OracleRun o = oracle::run_rs274(setup, path);
  ASSERT_FALSE(o.refused) << o.message;
  ASSERT_EQ(o.moves.size(), 6u) << o.out;
  EXPECT_EQ(o.moves[0].end[0], 0.1234567);  // exact: rs274 alone would print 0.1235
  EXPECT_EQ(o.moves[0].line, 2);
  EXPECT_NEAR(o.moves[1].end[0], 25.4, 1e-12);  // G20: 1 inch
  EXPECT_EQ(o.moves[1].line, 4);
  EXPECT_NEAR(o.moves[2].end[0], 11, 1e-9);  // G54 offset X10 + X1
  EXPECT_NEAR(o.moves[2].end[1], 21, 1e-9);
  EXPECT_NEAR(o.moves[2].end[2], 31, 1e-9);
  EXPECT_NEAR(o.moves[3].end[0], 13, 1e-9);         // G92 X0 at machine 11: X2 is machine 13
  EXPECT_NEAR(o.moves[4].end[2], 30 + 12.7, 1e-9);  // Z0 + G54 Z30 + tool 1 (tool.tbl: 12.7)
  EXPECT_NEAR(o.moves[4].end[0], 13, 1e-9);         // G92.1 changes the frame, not the position
  EXPECT_EQ(o.moves[5].kind, CanonMove::Kind::kArc);
  EXPECT_LT(o.moves[5].rotation, 0);
  EXPECT_NEAR(o.moves[5].end[0], 15, 1e-9);  // X5 + G54 X10
  EXPECT_NEAR(o.moves[5].centre[0], 14, 1e-9);
  EXPECT_NEAR(o.moves[5].centre[1], 21, 1e-9);
  ASSERT_EQ(o.dwells.size(), 1u);
  EXPECT_EQ(o.dwells[0].seconds, 0.25);
  EXPECT_EQ(o.dwells[0].line, 15);

  // A program LinuxCNC refuses: refused, with its message.
  const std::string bad = (tmp.path() / "bad.ngc").string();
  std::ofstream(bad) << "G0 X1\nG7.3 X1\nM2\n";
  const OracleRun r = oracle::run_rs274(setup, bad);
  EXPECT_TRUE(r.refused);
  EXPECT_NE(r.message.find("Unknown g code"), std::string::npos) << r.message;
}

// The canon reader, on lines written by hand: planes, units, offsets.
TEST(Oracle, CanonReader) {
  OracleRun run;
  oracle::parse_canon(
      "    1 L0 N..... USE_LENGTH_UNITS(CANON_UNITS_INCHES)\n"
      "    2 L3 N..... SET_G5X_OFFSET(2, 1, 2, 3, 0, 0, 0)\n"
      "    3 L4 N..... SET_G92_OFFSET(0.5, 0, 0, 0, 0, 0)\n"
      "    4 L5 N0010  USE_TOOL_LENGTH_OFFSET(0 0 2, 0 0 0, 0 0 0)\n"
      " hello (1.000000)\n"  // a (PRINT, ...) comment's output: not a command
      "    5 L6 N..... STRAIGHT_FEED(1, 1, 1, 0, 0, 0)\n"
      "    6 L7 N..... SELECT_PLANE(CANON_PLANE_XZ)\n"
      "    7 L8 N..... ARC_FEED(4, 5, 6, 7, 1, 8, 0, 0, 0, 0, 0, 0)\n"
      "    8 L9 N..... DWELL(1.5)\n"
      "    9 L9 N..... FINISH()\n",
      run);
  ASSERT_EQ(run.moves.size(), 2u);
  // (1 + 0.5 + 1, 1 + 2, 1 + 3 + 2) inches
  EXPECT_NEAR(run.moves[0].end[0], 2.5 * 25.4, 1e-12);
  EXPECT_NEAR(run.moves[0].end[1], 3 * 25.4, 1e-12);
  EXPECT_NEAR(run.moves[0].end[2], 6 * 25.4, 1e-12);
  EXPECT_EQ(run.moves[0].line, 6);
  // XZ plane: first Z, second X, axis Y: end Z4 X5 Y8, centre Z6 X7.
  EXPECT_NEAR(run.moves[1].end[0], (5 + 0.5 + 1) * 25.4, 1e-12);
  EXPECT_NEAR(run.moves[1].end[1], (8 + 2) * 25.4, 1e-12);
  EXPECT_NEAR(run.moves[1].end[2], (4 + 3 + 2) * 25.4, 1e-12);
  EXPECT_NEAR(run.moves[1].centre[0], (7 + 0.5 + 1) * 25.4, 1e-12);
  EXPECT_NEAR(run.moves[1].centre[2], (6 + 3 + 2) * 25.4, 1e-12);
  EXPECT_EQ(run.moves[1].plane, oracle::Plane::kXZ);
  ASSERT_EQ(run.dwells.size(), 1u);
  EXPECT_EQ(run.dwells[0].seconds, 1.5);
  // rs274 without the precision library: no source lines, a clear error.
  OracleRun plain;
  EXPECT_THROW(oracle::parse_canon("    1 N..... STRAIGHT_FEED(1, 1, 1, 0, 0, 0)\n", plain),
               std::runtime_error);
}

// The comparison finds a wrong end point, a wrong kind of move and a missing move.
TEST(Oracle, ComparisonCatchesDifferences) {
  OracleRun o;
  oracle::parse_canon(
      "    1 L2 N..... STRAIGHT_TRAVERSE(1, 2, 3, 0, 0, 0)\n"
      "    2 L3 N..... STRAIGHT_FEED(4, 5, 6, 0, 0, 0)\n",
      o);
  const auto same = gcode::parse_string("\nG0 X1 Y2 Z3\nG1 X4 Y5 Z6 F100\n");
  EXPECT_TRUE(compare("t", o, same).empty());
  const auto off = gcode::parse_string("\nG0 X1 Y2 Z3\nG1 X4 Y5.00001 Z6 F100\n");
  const auto d1 = compare("t", o, off);
  ASSERT_EQ(d1.size(), 1u);
  EXPECT_NE(d1[0].find("t:3: move 1: end rs274 (4, 5, 6) ours (4, 5.00001, 6)"), std::string::npos)
      << d1[0];
  // A zero-length straight move on one side only is not a difference.
  OracleRun z;
  oracle::parse_canon(
      "    1 L2 N..... STRAIGHT_TRAVERSE(0, 0, 0, 0, 0, 0)\n"
      "    2 L3 N..... STRAIGHT_FEED(4, 5, 6, 0, 0, 0)\n",
      z);
  EXPECT_TRUE(compare("t", z, gcode::parse_string("\n\nG1 X4 Y5 Z6 F100\n")).empty());
  const auto kind = gcode::parse_string("\nG0 X1 Y2 Z3\nG0 X4 Y5 Z6\n");
  EXPECT_EQ(compare("t", o, kind).size(), 1u);
  const auto fewer = gcode::parse_string("\nG0 X1 Y2 Z3\n");
  const auto d2 = compare("t", o, fewer);
  ASSERT_EQ(d2.size(), 2u);
  EXPECT_NE(d2[1].find("t:3: move 1: only rs274 makes it"), std::string::npos) << d2[1];
}

// A spline: rs274's control points (as the precision library prints them) against our pieces.
// The quadratic (0,0) (5,5) (10,0) peaks at (5, 2.5): a straight line on its line is 2.5 mm off.
TEST(Oracle, ComparisonOfSplines) {
  OracleRun o;
  oracle::parse_canon("    1 L2 N..... NURBS_FEED(3, 0, 0, 1, 5, 5, 1, 10, 0, 1)\n", o);
  ASSERT_EQ(o.moves.size(), 1u);
  EXPECT_EQ(o.moves[0].kind, CanonMove::Kind::kSpline);
  ASSERT_EQ(o.moves[0].control.size(), 3u);
  EXPECT_EQ(o.moves[0].end, (oracle::Xyz{10, 0, 0}));
  const auto ours = gcode::parse_string("F100\nG5.1 X10 Y0 I5 J5\n", "t", our_options());
  EXPECT_GT(our_moves(ours).size(), 10u);
  EXPECT_TRUE(compare("t", o, ours).empty());
  const auto straight = gcode::parse_string("F100\nG1 X10 Y0\n", "t", our_options());
  const auto d1 = compare("t", o, straight);
  ASSERT_EQ(d1.size(), 1u);
  EXPECT_NE(d1[0].find("leave rs274's spline by 2.5 mm"), std::string::npos) << d1[0];
  const auto other_end = gcode::parse_string("F100\nG5.1 X10 Y0.001 I5 J5\n", "t", our_options());
  EXPECT_FALSE(compare("t", o, other_end).empty());
  // Without the library's points the line is still read, as a move nothing of ours equals.
  OracleRun plain;
  oracle::parse_canon("    1 L2 N..... NURBS_FEED(3, ...)\n", plain);
  ASSERT_EQ(plain.moves.size(), 1u);
  EXPECT_EQ(plain.moves[0].kind, CanonMove::Kind::kOther);
}

// Every program through both interpreters; a summary table; the ratchet.
TEST(Oracle, ProgramsAgree) {
  oracle::Rs274Setup setup;
  try {
    setup = setup_or_fail();
  } catch (const std::exception& e) {
    FAIL() << e.what();
  }
  const std::string expected_path = kData + "/expected_refusals.txt";
  const auto expected = read_expected(expected_path);
  const char* only = std::getenv("FPGACNC_ORACLE_ONLY");

  TempDir tmp;
  const char* keep = std::getenv("FPGACNC_ORACLE_KEEP");
  const fs::path gen_dir = keep && *keep ? fs::path(keep) : tmp.path();
  fs::create_directories(gen_dir);
  std::vector<Program> programs = sample_programs();
  for (auto& p : edge_programs()) programs.push_back(p);
  for (auto& p : corpus_programs()) programs.push_back(p);
  const char* seeds_env = std::getenv("FPGACNC_ORACLE_SEEDS");
  const int seeds = seeds_env && *seeds_env ? std::atoi(seeds_env) : kSeedsPerFamily;
  for (const auto& g : oracle::generate_all(seeds)) {
    std::string file = g.name;
    std::replace(file.begin(), file.end(), '/', '_');
    const fs::path p = gen_dir / (file + ".ngc");
    std::ofstream(p) << g.text;
    programs.push_back({g.name, p.string()});
  }

  std::vector<Row> rows;
  std::vector<std::string> failures;
  std::map<std::string, std::string> now_refused;  // for FPGACNC_ORACLE_UPDATE
  std::map<std::string, bool> seen;
  for (const auto& prog : programs) {
    if (only && *only && prog.name.find(only) == std::string::npos) continue;
    seen[prog.name] = true;
    Row row;
    row.name = prog.name;
    if (!fs::exists(prog.path)) {
      failures.push_back(prog.name + ": file missing: " + prog.path);
      row.verdict = "MISSING";
      rows.push_back(row);
      continue;
    }
    OracleRun o;
    try {
      o = oracle::run_rs274(setup, prog.path);
    } catch (const std::exception& e) {
      failures.push_back(prog.name + ": " + e.what());
      row.verdict = "RS274 FAILED";
      rows.push_back(row);
      continue;
    }
    const OurRun ours = run_ours(prog.path);
    row.rs274 = o.refused ? "refuses" : o.ended_without_end ? "accepts (no M2)" : "accepts";
    if (o.refused) row.ours_note = "rs274: " + o.message;
    row.rs274_moves = oracle_moves(o).size();
    row.ours = ours.refused ? "refuses" : "accepts";
    row.our_moves = ours.refused ? 0 : our_moves(ours.program).size();
    const auto exp = expected.find(prog.name);
    if (ours.refused && !o.refused) now_refused[prog.name] = ours.message;
    if (!ours.refused && o.refused) now_refused[prog.name] = kAccepted;

    if (exp != expected.end() && exp->second == kAccepted) {
      // Listed: ours accepts a program rs274 refuses.
      if (!o.refused) {
        failures.push_back(fmt::format(
            "{}: listed as accepted by ours and refused by rs274, but rs274 accepts it: remove "
            "the entry",
            prog.name));
        row.verdict = "LIST WRONG";
      } else if (ours.refused) {
        failures.push_back(
            fmt::format("{}: now refused by ours too ({}): remove it from expected_refusals.txt",
                        prog.name, ours.message));
        row.verdict = "NOW REFUSED";
      } else {
        row.verdict = "known: ours accepts";
      }
    } else if (exp != expected.end()) {
      if (o.refused) {
        failures.push_back(fmt::format(
            "{}: listed in expected_refusals.txt but rs274 refuses it too ({}): remove the entry",
            prog.name, o.message));
        row.verdict = "LIST WRONG";
      } else if (!ours.refused) {
        failures.push_back(fmt::format(
            "{}: now accepted by ours (listed as refused with \"{}\"): remove it from "
            "expected_refusals.txt{}",
            prog.name, exp->second, [&] {
              const auto d = compare(prog.name, o, ours.program);
              return d.empty() ? std::string(" (it agrees with rs274)")
                               : fmt::format(" (and it disagrees with rs274: {})", d[0]);
            }()));
        row.verdict = "NOW ACCEPTED";
      } else if (ours.message != exp->second) {
        failures.push_back(fmt::format("{}: our refusal changed:\n    listed: {}\n    now:    {}",
                                       prog.name, exp->second, ours.message));
        row.verdict = "MESSAGE CHANGED";
      } else {
        row.verdict = "known refusal";
        row.ours_note = "ours: " + ours.message;
      }
    } else if (o.refused && prog.name.rfind("gen/", 0) == 0) {
      failures.push_back(fmt::format(
          "{}: rs274 refuses a generated program ({}): the generator writes invalid rs274ngc",
          prog.name, o.message));
      row.verdict = "GENERATOR BUG";
    } else if (o.refused && ours.refused) {
      row.verdict = "agree (both refuse)";
    } else if (o.refused) {
      failures.push_back(
          fmt::format("{}: rs274 refuses ({}) but ours accepts it (not in expected_refusals.txt)",
                      prog.name, o.message));
      row.verdict = "DISAGREE";
    } else if (ours.refused) {
      failures.push_back(
          fmt::format("{}: ours refuses ({}) but rs274 accepts it (not in expected_refusals.txt)",
                      prog.name, ours.message));
      row.verdict = "DISAGREE";
      row.ours_note = "ours: " + ours.message;
    } else {
      const auto d = compare(prog.name, o, ours.program);
      if (d.empty()) {
        row.verdict = "agree";
      } else {
        row.verdict = fmt::format("DISAGREE ({})", d.size());
        std::string msg = fmt::format("{}: {} disagreements with rs274:", prog.name, d.size());
        for (size_t i = 0; i < std::min(d.size(), kMaxReported); ++i) msg += "\n    " + d[i];
        failures.push_back(msg);
      }
    }
    rows.push_back(row);
  }
  for (const auto& [name, msg] : expected) {
    if (!seen.count(name) && !(only && *only)) {
      failures.push_back(name + ": listed in expected_refusals.txt but no such program");
    }
  }

  // Summary table.
  size_t w = 8;
  for (const auto& r : rows) w = std::max(w, r.name.size());
  std::string table = fmt::format("{:<{}}  {:<16} {:>6}  {:<8} {:>6}  {:<20}  {}\n", "program", w,
                                  "rs274", "moves", "ours", "moves", "verdict", "message");
  std::map<std::string, int> counts;
  for (const auto& r : rows) {
    table += fmt::format("{:<{}}  {:<16} {:>6}  {:<8} {:>6}  {:<20}  {}\n", r.name, w, r.rs274,
                         r.rs274_moves, r.ours, r.our_moves, r.verdict, r.ours_note);
    ++counts[r.verdict.substr(0, r.verdict.find(" ("))];
  }
  table += fmt::format("{} programs:", rows.size());
  for (const auto& [v, n] : counts) table += fmt::format(" {} {};", v, n);
  std::cout << table << "\n";

  if (const char* up = std::getenv("FPGACNC_ORACLE_UPDATE"); up && *up == '1') {
    std::ofstream out(expected_path);
    out << "# The oracle test's ratchet (docs/oracle.md): programs on which our interpreter and\n"
           "# LinuxCNC's rs274 disagree on refusing. <program><TAB><our exact message, file name\n"
           "# removed> when ours refuses a program rs274 accepts; <program><TAB>accepted when "
           "ours\n"
           "# accepts a program rs274 refuses. Written by FPGACNC_ORACLE_UPDATE=1\n"
           "# host_oracle_tests; review the diff before committing.\n";
    for (const auto& [name, msg] : now_refused) out << name << '\t' << msg << '\n';
    std::cout << "wrote " << expected_path << " (" << now_refused.size() << " entries)\n";
  }

  for (const auto& f : failures) ADD_FAILURE() << f;
}
