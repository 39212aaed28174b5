// The corpus of real files (label corpus): every file of corpus/manifest.toml is planned by the
// host with the machine configuration its entry names (corpus/mill.toml, laser.toml,
// printer.toml), packed as a protocol v2 job and run on the virtual board (the SystemC twins of
// cnc_core, as `fpgacnc sim --model tlm` does); the net steps counted from the board's STEP/DIR
// edges on all four axes must equal the plan's final position in steps, and the host must have
// got every answer it waited for.
//
// FPGACNC_CORPUS_STEPS (CTest: 4 000 000, about 8 M edges): a file runs on the board up to the
// first segment end, outside an arc, at which its steps on all axes add up to this many, and
// its net steps are checked against the plan's position there; the whole plan is still made
// and checked. Unset or 0 (`make soak`): whole files (about 530 M edges in all).
//
// A ratchet: each entry says whether the file runs today (expect = "runs") or is refused, and
// then with which message (error = "FILE:LINE:COL: error: ..." relative to corpus/). A file whose
// outcome or message differs from its entry fails, in either direction, and the test prints the
// entry to put in the manifest instead. The table of every file (program, outcome, message) is
// printed at the end.
//
// Heater commands (M104/M109/M140/M190) are checked against the printer configuration's heater
// channels (heat::make_heater_job: the refusals `fpgacnc stream` gives) but not sent: the twin
// board has no heater plants, so a printer file's motion runs without them (counted in the
// table); the Verilated board with its plants is too slow for whole printer files.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <optional>
#include <ostream>
#include <set>
#include <string>
#include <toml.hpp>
#include <vector>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/error.h"
#include "fpgacnc/heat/heater_job.h"
#include "fpgacnc/models/edges.h"
#include "fpgacnc/plan/motion_plan.h"
#include "fpgacnc/plan/planner.h"
#include "fpgacnc/protocol/v2_job.h"
#include "fpgacnc/twins/virtual_board.h"

// libsystemc's main() calls sc_main(); this file has its own main(), so this only links.
extern "C" int sc_main(int, char*[]) {
  return 1;
}

namespace {

namespace cfgns = fpgacnc::config;
namespace plan = fpgacnc::plan;
namespace tw = fpgacnc::twins;

const std::string kCorpus = FPGACNC_CORPUS_ROOT;

struct Entry {
  std::string path, program, version, kind, dialect, source, licence, config, expect, error;
};

// What happened to one file.
struct Outcome {
  bool planned = false;
  std::string error;  // the refusal, paths relative to corpus/
  plan::Steps4 final_steps{};
  size_t frames = 0;
  size_t heaters = 0;  // heater commands validated, not sent
  bool ran = false;
  std::array<int64_t, 4> net{};
  std::string host_error;
  uint64_t cycles = 0, edges = 0;
  double clk_hz = 50e6;
  size_t segments = 0, segments_run = 0;  // the plan's, and those run (FPGACNC_CORPUS_STEPS)
};

// gtest prints a failing parameter with this (the file, not the object's bytes).
void PrintTo(const Entry& e, std::ostream* os) {
  *os << e.path;
}

// Entries that name no program (hand-written examples, files without a header) are not counted
// as programs; "Fusion 360 (grbl post)" and "Fusion 360 (generic post)" count as one.
bool names_a_program(const Entry& e) {
  return e.program.rfind("hand-written", 0) != 0 && e.program.rfind("unknown", 0) != 0;
}

std::vector<Entry> load_manifest() {
  const toml::value root = toml::parse(kCorpus + "/manifest.toml");
  std::vector<Entry> out;
  for (const auto& f : toml::find<std::vector<toml::value>>(root, "file")) {
    Entry e;
    e.path = toml::find<std::string>(f, "path");
    e.program = toml::find<std::string>(f, "program");
    e.kind = toml::find<std::string>(f, "kind");
    e.dialect = toml::find<std::string>(f, "dialect");
    e.source = toml::find<std::string>(f, "source");
    e.licence = toml::find<std::string>(f, "licence");
    e.config = toml::find<std::string>(f, "config");
    e.expect = toml::find<std::string>(f, "expect");
    if (f.contains("version")) e.version = toml::find<std::string>(f, "version");
    if (f.contains("error")) e.error = toml::find<std::string>(f, "error");
    out.push_back(e);
  }
  return out;
}

const std::vector<Entry>& entries() {
  static const std::vector<Entry> e = load_manifest();
  return e;
}

std::map<std::string, Outcome>& outcomes() {
  static std::map<std::string, Outcome> o;
  return o;
}

// `text` with every occurrence of "<corpus>/" removed: messages name files relative to corpus/.
std::string relative(std::string text) {
  const std::string prefix = kCorpus + "/";
  for (size_t at; (at = text.find(prefix)) != std::string::npos;) text.erase(at, prefix.size());
  return text;
}

const cfgns::MachineConfig& config(const std::string& name) {
  static std::map<std::string, cfgns::MachineConfig> cache;
  auto it = cache.find(name);
  if (it == cache.end())
    it = cache.emplace(name, cfgns::load_machine_config(kCorpus + "/" + name + ".toml")).first;
  return it->second;
}

tw::CoreParams params(const cfgns::MachineConfig& cfg) {
  tw::CoreParams p;
  p.clk_hz = cfg.clk_hz;
  p.baud = cfg.baud;
  p.watchdog_clks = cfg.clk_hz / 10;
  for (auto& t : p.timing)
    t = tw::AxisTiming{cfg.step_timing.step_high, cfg.step_timing.step_low,
                       cfg.step_timing.dir_setup, cfg.step_timing.dir_hold};
  return p;
}

// FPGACNC_CORPUS_STEPS; 0 when unset (whole files).
uint64_t steps_budget() {
  const char* v = std::getenv("FPGACNC_CORPUS_STEPS");
  return v ? std::strtoull(v, nullptr, 10) : 0;
}

// `p` up to the first segment end outside an arc (the next item is not a chord of the same arc)
// at which the segments' steps on all axes add up to `budget`, with final_steps the position
// there; `p` itself when the budget is 0 or never reached. Returns the segments kept.
size_t keep_prefix(plan::Plan& p, uint64_t budget) {
  size_t kept = 0;
  uint64_t steps = 0;
  for (size_t i = 0; i < p.items.size(); ++i) {
    const auto* s = std::get_if<plan::Segment>(&p.items[i]);
    if (!s) continue;
    ++kept;
    for (const int64_t d : s->steps) steps += static_cast<uint64_t>(d < 0 ? -d : d);
    if (budget == 0 || steps < budget) continue;
    const auto* next =
        i + 1 < p.items.size() ? std::get_if<plan::Segment>(&p.items[i + 1]) : nullptr;
    if (s->arc_id != 0 && next && next->arc_id == s->arc_id) continue;
    p.final_steps = s->target;
    p.items.resize(i + 1);
    break;
  }
  return kept;
}

// Plans every file, runs the planned ones on one virtual board (one SystemC elaboration per
// process: the board runs its jobs in order, each from reset).
void run_corpus() {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::pair<std::string, tw::TwinJob>> jobs;
  std::optional<tw::CoreParams> board_params;
  for (const Entry& e : entries()) {
    Outcome& o = outcomes()[e.path];
    const cfgns::MachineConfig& cfg = config(e.config);
    const tw::CoreParams p = params(cfg);
    if (!board_params) board_params = p;
    if (p.clk_hz != board_params->clk_hz || p.baud != board_params->baud)
      throw std::runtime_error("corpus configurations must share clk_hz and baud: " + e.config);
    tw::HostScript script;
    try {
      plan::PlanOptions po;
      po.feed_override_pct = cfg.feed_override_pct;
      plan::Plan pl = plan::plan_input_file(kCorpus + "/" + e.path, cfg, po);
      // The heater commands of the whole file are checked; the board runs the prefix.
      const fpgacnc::heat::HeaterJob heaters = fpgacnc::heat::make_heater_job(pl, cfg);
      o.segments = static_cast<size_t>(std::count_if(
          pl.items.begin(), pl.items.end(),
          [](const plan::PlanItem& i) { return std::holds_alternative<plan::Segment>(i); }));
      o.segments_run = keep_prefix(pl, steps_budget());
      // The twin board has no heater plants: the motion frames, the heater commands counted.
      const fpgacnc::protocol::v2::Job job =
          fpgacnc::protocol::v2::pack_job(plan::plan_motion(pl, cfg), cfg, {.heaters = false});
      o.heaters = heaters.actions.size();
      o.clk_hz = static_cast<double>(cfg.clk_hz);
      o.final_steps = pl.final_steps;
      o.frames = job.frames.size();
      script.v2 = tw::job_script(job);
      o.planned = true;
    } catch (const std::exception& ex) {
      o.error = relative(ex.what());
      continue;
    }
    const std::string path = e.path;
    jobs.emplace_back(path, tw::TwinJob{std::move(script), p.timing, [path](tw::RunResult&& r) {
                                          Outcome& out = outcomes()[path];
                                          out.ran = true;
                                          out.net = r.net_steps;
                                          out.host_error = r.error;
                                          out.cycles = r.end_cycle;
                                          out.edges = r.edge_count;
                                        }});
  }
  const auto t1 = std::chrono::steady_clock::now();
  if (!board_params) return;
  tw::VirtualBoard board("virtual_board", *board_params);
  board.summary_only(true);
  for (auto& j : jobs) board.add_job(std::move(j.second));
  sc_core::sc_start();
  const auto t2 = std::chrono::steady_clock::now();
  fmt::print("corpus: {} files, {} planned ({:.2f} s), run on the virtual board ({:.2f} s)\n",
             entries().size(), jobs.size(), std::chrono::duration<double>(t1 - t0).count(),
             std::chrono::duration<double>(t2 - t1).count());
}

std::string toml_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

class CorpusFile : public ::testing::TestWithParam<Entry> {};

TEST_P(CorpusFile, OutcomeAsRecordedAndNetStepsEqualThePlan) {
  const Entry& e = GetParam();
  const Outcome& o = outcomes().at(e.path);
  ASSERT_TRUE(e.expect == "runs" || e.expect == "refused")
      << e.path << ": expect must be \"runs\" or \"refused\", not " << e.expect;
  if (e.expect == "runs") {
    EXPECT_TRUE(o.planned) << e.path << " is refused now; manifest entry:\nexpect = \"refused\"\n"
                           << "error = " << toml_string(o.error);
  } else {
    EXPECT_FALSE(o.planned) << e.path << " runs now; manifest entry:\nexpect = \"runs\"";
    if (!o.planned) {
      EXPECT_EQ(o.error, e.error) << e.path << ": the refusal changed; manifest entry:\nerror = "
                                  << toml_string(o.error);
    }
  }
  if (!o.planned) return;
  ASSERT_TRUE(o.ran) << e.path << ": planned but the virtual board did not run it";
  EXPECT_EQ(o.host_error, "") << e.path;
  for (int a = 0; a < 4; ++a)
    EXPECT_EQ(o.net[a], o.final_steps[a])
        << e.path << ": axis " << cfgns::kAxisNames[a]
        << ": net steps from the board's STEP/DIR edges differ from the plan's final target";
}

// The manifest itself: one entry per file, every G-code file of corpus/ has one, and every key
// holds one of its documented values (corpus/manifest.toml's header).
TEST(CorpusManifest, EveryFileHasOneWellFormedEntry) {
  const std::set<std::string> kinds{"mill", "laser", "printer", "pcb", "lathe"};
  const std::set<std::string> dialects{"grbl",    "linuxcnc", "marlin", "reprap",
                                       "klipper", "makerbot", "generic"};
  const std::set<std::string> configs{"mill", "laser", "printer"};
  std::set<std::string> paths;
  for (const Entry& e : entries()) {
    EXPECT_TRUE(paths.insert(e.path).second) << e.path << ": two entries";
    EXPECT_TRUE(std::filesystem::is_regular_file(kCorpus + "/" + e.path)) << e.path;
    EXPECT_TRUE(kinds.count(e.kind)) << e.path << ": kind " << e.kind;
    EXPECT_TRUE(dialects.count(e.dialect)) << e.path << ": dialect " << e.dialect;
    EXPECT_TRUE(configs.count(e.config)) << e.path << ": config " << e.config;
    EXPECT_EQ(e.source.rfind("https://github.com/", 0), 0u) << e.path << ": source " << e.source;
    EXPECT_FALSE(e.licence.empty()) << e.path;
    EXPECT_FALSE(e.program.empty()) << e.path;
    EXPECT_EQ(e.expect == "refused", !e.error.empty())
        << e.path << ": an error message goes with expect = \"refused\" only";
  }
  const std::set<std::string> gcode{".gcode", ".gco", ".nc", ".ngc", ".tap"};
  for (const auto& f : std::filesystem::recursive_directory_iterator(kCorpus)) {
    if (!f.is_regular_file() || !gcode.count(f.path().extension().string())) continue;
    const std::string rel = std::filesystem::relative(f.path(), kCorpus).generic_string();
    EXPECT_TRUE(paths.count(rel)) << rel << " has no entry in corpus/manifest.toml";
  }
}

std::string test_name(const ::testing::TestParamInfo<Entry>& info) {
  std::string n;
  for (char c : info.param.path) n += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return n;
}

INSTANTIATE_TEST_SUITE_P(Corpus, CorpusFile, ::testing::ValuesIn(entries()), test_name);

void print_table() {
  fmt::print("\n{:<58} {:<30} {:<8} {}\n", "file", "program", "outcome", "details");
  size_t runs = 0, refused = 0;
  std::map<std::string, int> programs;
  for (const Entry& e : entries()) {
    const Outcome& o = outcomes().at(e.path);
    if (names_a_program(e)) ++programs[e.program.substr(0, e.program.find(" ("))];
    std::string details;
    if (o.planned) {
      ++runs;
      details = fmt::format("{} frames, {} edges, {:.1f} s of machine time", o.frames, o.edges,
                            static_cast<double>(o.cycles) / o.clk_hz);
      if (o.segments_run < o.segments)
        details += fmt::format(" (the first {} of {} segments)", o.segments_run, o.segments);
      if (o.heaters) details += fmt::format(", {} heater commands not sent", o.heaters);
    } else {
      ++refused;
      details = o.error;
    }
    const std::string program = e.version.empty() ? e.program : e.program + " " + e.version;
    fmt::print("{:<58} {:<30} {:<8} {}\n", e.path, program.substr(0, 30),
               o.planned ? "runs" : "refused", details);
  }
  fmt::print("corpus: {} files, {} programs named: {} run, {} refused\n", entries().size(),
             programs.size(), runs, refused);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  if (!::testing::GTEST_FLAG(list_tests)) run_corpus();
  const int rc = RUN_ALL_TESTS();
  if (!::testing::GTEST_FLAG(list_tests)) print_table();
  return rc;
}
