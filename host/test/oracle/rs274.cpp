#include "rs274.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace fpgacnc::oracle {
namespace {

namespace fs = std::filesystem;

constexpr double kInch = 25.4;
constexpr std::string_view kNoEnd = "File ended with no percent sign or program end";

std::string read_all(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<double> numbers(std::string_view args, const std::string& line) {
  std::vector<double> v;
  size_t i = 0;
  while (i < args.size()) {
    while (i < args.size() && (args[i] == ' ' || args[i] == ',')) ++i;
    if (i >= args.size()) break;
    size_t j = i;
    while (j < args.size() && args[j] != ' ' && args[j] != ',') ++j;
    double d = 0.0;
    const auto r = std::from_chars(args.data() + i, args.data() + j, d);
    if (r.ec != std::errc() || r.ptr != args.data() + j) {
      throw std::runtime_error("rs274 output: not a number in: " + line);
    }
    v.push_back(d);
    i = j;
  }
  return v;
}

struct Frame {
  double unit = 1.0;  // mm per printed length unit
  Xyz g5x{}, g92{}, tool{};
  double rotation_deg = 0.0;
  Plane plane = Plane::kXY;

  // Program point (printed units) -> machine mm, as LinuxCNC's canon layer does: G92 offset
  // added, rotated about the work origin, work offset added, tool length offset added.
  Xyz machine(const Xyz& p) const {
    double x = p[0] * unit + g92[0];
    double y = p[1] * unit + g92[1];
    const double z = p[2] * unit + g92[2];
    if (rotation_deg != 0.0) {
      const double a = rotation_deg * M_PI / 180.0;
      const double rx = x * std::cos(a) - y * std::sin(a);
      y = x * std::sin(a) + y * std::cos(a);
      x = rx;
    }
    return {x + g5x[0] + tool[0], y + g5x[1] + tool[1], z + g5x[2] + tool[2]};
  }
};

}  // namespace

void parse_canon(std::string_view out, OracleRun& run) {
  Frame f;
  Xyz last{};  // program position (printed units), for the arc centre's axis coordinate
  size_t pos = 0;
  while (pos < out.size()) {
    size_t eol = out.find('\n', pos);
    if (eol == std::string_view::npos) eol = out.size();
    const std::string line(out.substr(pos, eol - pos));
    pos = eol + 1;
    // A command: "<counter> L<line> N<number or .....> NAME(args)". Other lines are text the
    // program printed itself ((PRINT, ...) comments), or the counter of a command rs274 never
    // finished when it stopped on an error.
    size_t i = line.find_first_not_of(' ');
    if (i == std::string::npos || !std::isdigit(static_cast<unsigned char>(line[i]))) continue;
    while (i < line.size() && std::isdigit(static_cast<unsigned char>(line[i]))) ++i;
    if (i >= line.size() || line[i] != ' ') continue;
    ++i;
    if (i < line.size() && line[i] == 'N') {
      throw std::runtime_error(
          "rs274 output has no source line numbers: the precision library (LD_PRELOAD) was not "
          "applied or does not match this rs274 (line: " +
          line + ")");
    }
    if (i >= line.size() || line[i] != 'L') continue;
    const size_t lstart = i;
    while (i < line.size() && line[i] != ' ') ++i;
    const std::string ltok = line.substr(lstart, i - lstart);
    ++i;
    if (i >= line.size() || line[i] != 'N') continue;
    ++i;
    while (i < line.size() &&
           (line[i] == '.' || std::isdigit(static_cast<unsigned char>(line[i])))) {
      ++i;
    }
    while (i < line.size() && line[i] == ' ') ++i;
    const size_t open = line.find('(', i);
    const size_t close = line.rfind(')');
    if (open == std::string::npos || close == std::string::npos || close < open) continue;
    const std::string name = line.substr(i, open - i);
    const int src = std::atoi(ltok.c_str() + 1);
    if (src < 0) {
      throw std::runtime_error(
          "rs274 output: the precision library could not read the source line (no 'pinterp' "
          "or Interp::sequence_number in this rs274): " +
          line);
    }
    const std::string_view args = std::string_view(line).substr(open + 1, close - open - 1);
    auto nums = [&] { return numbers(args, line); };
    auto need = [&](const std::vector<double>& v, size_t n) {
      if (v.size() < n) throw std::runtime_error("rs274 output: too few values in: " + line);
    };

    if (name == "USE_LENGTH_UNITS") {
      if (args == "CANON_UNITS_MM") {
        f.unit = 1.0;
      } else if (args == "CANON_UNITS_INCHES") {
        f.unit = kInch;
      } else {
        throw std::runtime_error("rs274 output: unknown units: " + line);
      }
    } else if (name == "SELECT_PLANE") {
      if (args == "CANON_PLANE_XY") {
        f.plane = Plane::kXY;
      } else if (args == "CANON_PLANE_YZ") {
        f.plane = Plane::kYZ;
      } else if (args == "CANON_PLANE_XZ") {
        f.plane = Plane::kXZ;
      } else {
        throw std::runtime_error("rs274 output: plane not modelled by the test: " + line);
      }
    } else if (name == "SET_G5X_OFFSET") {
      const auto v = nums();
      need(v, 4);
      f.g5x = {v[1] * f.unit, v[2] * f.unit, v[3] * f.unit};
    } else if (name == "SET_G92_OFFSET") {
      const auto v = nums();
      need(v, 3);
      f.g92 = {v[0] * f.unit, v[1] * f.unit, v[2] * f.unit};
    } else if (name == "SET_XY_ROTATION") {
      const auto v = nums();
      need(v, 1);
      f.rotation_deg = v[0];
    } else if (name == "USE_TOOL_LENGTH_OFFSET") {
      const auto v = nums();
      need(v, 3);
      f.tool = {v[0] * f.unit, v[1] * f.unit, v[2] * f.unit};
    } else if (name == "DWELL") {
      const auto v = nums();
      need(v, 1);
      run.dwells.push_back({v[0], src});
    } else if (name == "STRAIGHT_TRAVERSE" || name == "STRAIGHT_FEED") {
      const auto v = nums();
      need(v, 3);
      CanonMove m;
      m.kind = name == "STRAIGHT_FEED" ? CanonMove::Kind::kFeed : CanonMove::Kind::kTraverse;
      m.name = name;
      last = {v[0], v[1], v[2]};
      m.end = f.machine(last);
      m.line = src;
      m.text = line;
      run.moves.push_back(std::move(m));
    } else if (name == "ARC_FEED") {
      // ARC_FEED(first_end, second_end, first_axis, second_axis, rotation, axis_end_point, ...):
      // XY plane: first X, second Y, axis Z; XZ (G18): first Z, second X, axis Y; YZ (G19):
      // first Y, second Z, axis X. first/second_axis are the centre's coordinates.
      const auto v = nums();
      need(v, 6);
      CanonMove m;
      m.kind = CanonMove::Kind::kArc;
      m.name = name;
      m.plane = f.plane;
      m.rotation = static_cast<int>(v[4]);
      Xyz end{}, centre{};
      switch (f.plane) {
        case Plane::kXY:
          end = {v[0], v[1], v[5]};
          centre = {v[2], v[3], last[2]};
          break;
        case Plane::kXZ:
          end = {v[1], v[5], v[0]};
          centre = {v[3], last[1], v[2]};
          break;
        case Plane::kYZ:
          end = {v[5], v[0], v[1]};
          centre = {last[0], v[2], v[3]};
          break;
      }
      last = end;
      m.end = f.machine(end);
      m.centre = f.machine(centre);
      m.line = src;
      m.text = line;
      run.moves.push_back(std::move(m));
    } else if (name == "NURBS_FEED" && args.find("...") == std::string_view::npos) {
      // NURBS_FEED(n, x0, y0, w0, ..., x(n-1), y(n-1), w(n-1)) in the XY plane.
      const auto v = nums();
      need(v, 1);
      const auto n = static_cast<size_t>(v[0]);
      if (v[0] < 2 || v.size() != 1 + 3 * n)
        throw std::runtime_error("rs274 output: NURBS_FEED with a wrong count: " + line);
      CanonMove m;
      m.kind = CanonMove::Kind::kSpline;
      m.name = name;
      // Z stays where the last move left it (machine mm: `last` may be in other units).
      const double z = run.moves.empty() ? 0.0 : run.moves.back().end[2];
      for (size_t k = 0; k < n; ++k) {
        Xyz p = f.machine({v[1 + 3 * k], v[2 + 3 * k], 0.0});
        p[2] = z;
        m.control.push_back(p);
        m.weights.push_back(v[3 + 3 * k]);
      }
      last = {v[1 + 3 * (n - 1)], v[2 + 3 * (n - 1)], last[2]};
      m.end = m.control.back();
      m.line = src;
      m.text = line;
      run.moves.push_back(std::move(m));
    } else if (name == "STRAIGHT_PROBE" || name == "RIGID_TAP" || name == "NURBS_FEED" ||
               name == "SPLINE_FEED" || name == "NURBS_G5_FEED" || name == "NURBS_G6_FEED") {
      // Motion our Move cannot express (yet): counted as a move, never equal to one of ours.
      CanonMove m;
      m.kind = CanonMove::Kind::kOther;
      m.name = name;
      m.line = src;
      m.text = line;
      run.moves.push_back(std::move(m));
    }
    // Everything else (feed rates, spindle, coolant, tool selection, comments, modes,
    // PROGRAM_END, ON_RESET, ...) does not move the machine.
  }
}

std::optional<std::string> find_rs274() {
  if (const char* e = std::getenv("FPGACNC_RS274"); e && *e) {
    if (::access(e, X_OK) == 0) return std::string(e);
    return std::nullopt;
  }
  if (const char* path = std::getenv("PATH")) {
    std::string_view p(path);
    while (!p.empty()) {
      const size_t c = p.find(':');
      const std::string dir(p.substr(0, c));
      p = c == std::string_view::npos ? std::string_view{} : p.substr(c + 1);
      if (dir.empty()) continue;
      const std::string cand = dir + "/rs274";
      if (::access(cand.c_str(), X_OK) == 0) return cand;
    }
  }
  if (::access("/usr/bin/rs274", X_OK) == 0) return std::string("/usr/bin/rs274");
  return std::nullopt;
}

namespace {

// The tool table in rs274's units: its stand-alone canon layer reports inches as the machine's
// length unit, so a tool table's lengths are read as inches. Lengths (X Y Z U V W D) / 25.4.
std::string tool_table_inches(const std::string& mm_path) {
  std::ifstream in(mm_path);
  if (!in) throw std::runtime_error("cannot read tool table " + mm_path);
  std::string out, line;
  while (std::getline(in, line)) {
    const size_t semi = line.find(';');
    const std::string body = line.substr(0, semi);
    const std::string comment = semi == std::string::npos ? "" : line.substr(semi);
    std::istringstream words(body);
    std::string w, conv;
    while (words >> w) {
      const char l = static_cast<char>(std::toupper(static_cast<unsigned char>(w[0])));
      if (std::string_view("XYZUVWD").find(l) != std::string_view::npos && w.size() > 1) {
        conv += fmt::format("{}{:.17g} ", l, std::strtod(w.c_str() + 1, nullptr) / kInch);
      } else {
        conv += w + " ";
      }
    }
    out += conv + comment + "\n";
  }
  return out;
}

}  // namespace

OracleRun run_rs274(const Rs274Setup& setup, const std::string& program) {
  char tmpl[] = "/tmp/fpgacnc-oracle-XXXXXX";
  if (::mkdtemp(tmpl) == nullptr) throw std::runtime_error("mkdtemp failed");
  const fs::path dir(tmpl);
  struct Cleanup {
    fs::path d;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(d, ec);
    }
  } cleanup{dir};

  // rs274 rewrites its parameter file at exit: a fresh empty one per run keeps runs independent
  // (every work offset, G92 offset and parameter starts at 0).
  std::ofstream(dir / "oracle.var").flush();
  std::ofstream(dir / "tool.tbl") << tool_table_inches(setup.tool_mm);
  const std::string prog = fs::absolute(program).string();

  std::vector<std::string> argv_s = {setup.rs274, "-g", "-v", "oracle.var", "-t", "tool.tbl", prog};
  std::vector<char*> argv;
  for (auto& s : argv_s) argv.push_back(s.data());
  argv.push_back(nullptr);
  // HOME: rs274 keeps its tool table in $HOME/.tool.mmap; runs in parallel (CTest -j) must
  // not share one.
  std::vector<std::string> env_s;
  for (char** e = environ; *e; ++e) {
    if (std::strncmp(*e, "LD_PRELOAD=", 11) != 0 && std::strncmp(*e, "HOME=", 5) != 0) {
      env_s.emplace_back(*e);
    }
  }
  env_s.push_back("LD_PRELOAD=" + setup.shim);
  env_s.push_back("HOME=" + dir.string());
  std::vector<char*> envp;
  for (auto& s : env_s) envp.push_back(s.data());
  envp.push_back(nullptr);

  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addchdir_np(&fa, dir.c_str());
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, (dir / "stdout.txt").c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, (dir / "stderr.txt").c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
  posix_spawnattr_setpgroup(&attr, 0);
  pid_t pid = 0;
  const int err = ::posix_spawn(&pid, setup.rs274.c_str(), &fa, &attr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&fa);
  posix_spawnattr_destroy(&attr);
  if (err != 0) {
    throw std::runtime_error(fmt::format("cannot run {}: {}", setup.rs274, std::strerror(err)));
  }
  // Hang guard: a wall-clock limit on the child only, far above its normal run (tens of ms).
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::milliseconds(static_cast<int>(setup.wall_limit_s * 1000));
  int status = 0;
  for (;;) {
    const pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid) break;
    if (r < 0 && errno != EINTR) throw std::runtime_error("waitpid failed");
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(-pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      throw std::runtime_error(
          fmt::format("rs274 still running after {} s on {}: killed", setup.wall_limit_s, program));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  if (WIFSIGNALED(status)) {
    throw std::runtime_error(
        fmt::format("rs274 died on signal {} on {}", WTERMSIG(status), program));
  }
  OracleRun run;
  run.out = read_all(dir / "stdout.txt");
  const std::string errtext = read_all(dir / "stderr.txt");
  std::string msg;
  std::istringstream es(errtext);
  for (std::string l; std::getline(es, l);) {
    if (l == "executing" || l.empty()) continue;
    if (!msg.empty()) msg += " | ";
    msg += l;
  }
  const int rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.message = msg;
  if (msg.rfind(kNoEnd, 0) == 0) {
    // LinuxCNC runs every block of such a file, then reports the missing end: every move was
    // printed, so it counts as accepted (docs/oracle.md).
    run.ended_without_end = true;
  } else if (rc != 0 || !msg.empty()) {
    run.refused = true;
  }
  parse_canon(run.out, run);
  return run;
}

}  // namespace fpgacnc::oracle
