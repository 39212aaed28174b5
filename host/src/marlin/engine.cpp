#include "fpgacnc/marlin/engine.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

#include "fpgacnc/frontend/motion.h"
#include "fpgacnc/gcode/dialect.h"
#include "fpgacnc/gcode/reader.h"
#include "fpgacnc/protocol/v2_job.h"

namespace fpgacnc::marlin {
namespace v2 = protocol::v2;
using std::chrono::milliseconds;

namespace {

// The number after `letter` in a command ("M155 S2" -> 2), or nullopt.
std::optional<double> word(const std::string& cmd, char letter) {
  for (size_t i = 1; i < cmd.size(); ++i) {
    if (std::toupper(static_cast<unsigned char>(cmd[i])) != letter) continue;
    if (!std::isspace(static_cast<unsigned char>(cmd[i - 1]))) continue;
    char* end = nullptr;
    const double v = std::strtod(cmd.c_str() + i + 1, &end);
    if (end != cmd.c_str() + i + 1) return v;
  }
  return std::nullopt;
}

// "M105" -> 105 for an M command, -1 otherwise.
int mcode(const std::string& cmd) {
  if (cmd.size() < 2 || std::toupper(static_cast<unsigned char>(cmd[0])) != 'M') return -1;
  if (!std::isdigit(static_cast<unsigned char>(cmd[1]))) return -1;
  return std::atoi(cmd.c_str() + 1);
}

// The command of a line without its line number, checksum and comment.
std::string command_of(std::string_view l) {
  size_t i = 0;
  while (i < l.size() && std::isspace(static_cast<unsigned char>(l[i]))) ++i;
  if (i < l.size() && (l[i] == 'N' || l[i] == 'n')) {
    ++i;
    while (i < l.size() && (std::isdigit(static_cast<unsigned char>(l[i])) || l[i] == '-')) ++i;
    while (i < l.size() && std::isspace(static_cast<unsigned char>(l[i]))) ++i;
  }
  l = l.substr(i);
  l = l.substr(0, std::min(l.find('*'), l.find(';')));
  return std::string(l);
}

// The heater setup of every enabled channel (HEATER_CONFIG, HEATER_SAFETY, thermistor table,
// watchdog), made by heat::make_heater_job from a setpoint 0 per channel.
heat::HeaterJob heater_setup(const config::MachineConfig& cfg) {
  plan::Plan p;
  p.source = "marlin";
  if (cfg.heaters.ch[heat::kHotend].enabled) p.items.push_back(plan::HeaterCommand{104, 0.0, true});
  if (cfg.heaters.ch[heat::kBed].enabled) p.items.push_back(plan::HeaterCommand{140, 0.0, true});
  heat::HeaterJob hj = heat::make_heater_job(p, cfg);
  hj.actions.clear();
  return hj;
}

}  // namespace

Engine::Engine(link::Link& link, config::MachineConfig cfg, EngineOptions opt)
    : link_(link), cfg_(std::move(cfg)), opt_(std::move(opt)) {}

Engine::~Engine() = default;

double Engine::clock_s() const {
  return opt_.v2.plant_time ? opt_.v2.plant_time() : link::seconds(link_.now());
}

void Engine::say(std::string_view line) {
  out_ += line;
  out_ += "\n";
}

std::string Engine::take_output() {
  std::string s;
  s.swap(out_);
  return s;
}

void Engine::connect() {
  ident_ = link::handshake_v2(link_, opt_.v2, rep_, std::nullopt);
  heaters_ = heater_setup(cfg_);
  opt_.v2.heaters = &heaters_;
  session_ = std::make_unique<link::V2Session>(link_, opt_.v2, ident_, rep_);
  session_->start();
  frontend::push_config_axes(*session_, ident_, cfg_);
  for (const auto& f : heaters_.setup) session_->push({f});

  params_ = std::make_unique<gcode::Params>();
  gcode::Options go = plan::gcode_options(cfg_);
  go.dialect = gcode::Dialect::kMarlin;
  go.dialect_source = "fpgacnc marlin";
  gcode::DialectChoice dc;
  dc.dialect = gcode::Dialect::kMarlin;
  dc.reason = "fpgacnc marlin";
  interp_ = std::make_unique<gcode::Interpreter>("marlin", go, dc, *params_);
  planner_ = std::make_unique<plan::Planner>(cfg_, plan::PlanOptions{});
  la_ = std::make_unique<plan::Lookahead>(plan::motion_limits(cfg_));
  // The parser and the planner start where the machine is.
  plan::Steps4 pos{};
  const auto& st = session_->last_status();
  for (size_t a = 0; a < 4 && a < st.position.size(); ++a) pos[a] = st.position[a];
  frontend::sync_to(pos, cfg_, gcode::Dialect::kMarlin, *params_, *interp_, *planner_);
  say("start");
  say("echo: fpgacnc marlin front end (docs/marlin.md)");
}

void Engine::receive(std::string_view bytes) {
  for (char ch : bytes) {
    if (ch == '\n' || ch == '\r') {
      // Emergency parser (as Marlin's): M112 acts as soon as its line is in, queued or not.
      const size_t prev = rx_.find_last_of("\r\n");
      // M108 ends a heating wait the same way (the line itself is answered `ok` when its turn
      // comes, after the wait).
      const int m = mcode(command_of(prev == std::string::npos ? rx_ : rx_.substr(prev + 1)));
      if (m == 112) halt();
      if (m == 108) cancel_heating();
    }
    if (!killed_) rx_.push_back(ch);
  }
}

void Engine::cancel_heating() {
  if (killed_ || wait_ != Wait::kHeat || !session_) return;
  if (session_->cancel_heater_wait()) session_->request_status();  // ends at this STATUS
}

std::vector<std::string> Engine::firmware_report() const {
  // Marlin's M115: the firmware line, then one Cap: line per capability (1: supported).
  const int extruders = cfg_.heaters.ch[heat::kHotend].enabled ? 1 : 0;
  std::vector<std::string> r = {fmt::format(
      "FIRMWARE_NAME:Marlin (fpgacnc front end) PROTOCOL_VERSION:1.0 MACHINE_TYPE:fpgacnc "
      "EXTRUDER_COUNT:{} UUID:00000000-0000-0000-0000-000000000000",
      extruders)};
  const std::pair<const char*, bool> caps[] = {{"SERIAL_XON_XOFF", false},
                                               {"BINARY_FILE_TRANSFER", false},
                                               {"EEPROM", false},
                                               {"VOLUMETRIC", false},
                                               {"AUTOREPORT_POS", false},
                                               {"AUTOREPORT_TEMP", true},
                                               {"PROGRESS", false},
                                               {"PRINT_JOB", false},
                                               {"AUTOLEVEL", false},
                                               {"RUNOUT", false},
                                               {"Z_PROBE", false},
                                               {"LEVELING_DATA", false},
                                               {"BUILD_PERCENT", false},
                                               {"SOFTWARE_POWER", false},
                                               {"TOGGLE_LIGHTS", false},
                                               {"CASE_LIGHT_BRIGHTNESS", false},
                                               {"EMERGENCY_PARSER", true},
                                               {"HOST_ACTION_COMMANDS", false},
                                               {"PROMPT_SUPPORT", false},
                                               {"SDCARD", false},
                                               {"REPEAT", false},
                                               {"SD_WRITE", false},
                                               {"AUTOREPORT_SD_STATUS", false},
                                               {"LONG_FILENAME", false},
                                               {"THERMAL_PROTECTION", true},
                                               {"MOTION_MODES", false},
                                               {"ARCS", true},
                                               {"BABYSTEPPING", false},
                                               {"CHAMBER_TEMPERATURE", false},
                                               {"COOLER_TEMPERATURE", false},
                                               {"MEATPACK", false}};
  for (const auto& [name, on] : caps) r.push_back(fmt::format("Cap:{}:{}", name, on ? 1 : 0));
  return r;
}

bool Engine::line_ready() const {
  return rx_.find_first_of("\r\n") != std::string::npos;
}

bool Engine::can_take_line() const {
  return !killed_ && wait_ == Wait::kNone &&
         session_->unsent() < std::max<size_t>(cfg_.lookahead_segments, 1);
}

bool Engine::busy() const {
  return !killed_ &&
         ((la_ && la_->window_size() > 0) || wait_ != Wait::kNone || auto_pending_ ||
          session_->fifo_done() < session_->fifo_pushed() || (line_ready() && can_take_line()));
}

std::array<double, 4> Engine::position_mm() const {
  std::array<double, 4> p{};
  const auto& st = session_->last_status();
  for (size_t a = 0; a < 4 && a < st.position.size(); ++a)
    p[a] = static_cast<double>(st.position[a]) / cfg_.steps_per_mm[a];
  return p;
}

std::string Engine::temps() const {
  const auto& st = session_->last_status();
  auto reading = [&](size_t c) {
    HeaterReading r;
    if (c < st.heaters.size()) {
      r.temp_c = st.heaters[c].temp_c();
      r.target_c = st.heaters[c].enabled() ? st.heaters[c].setpoint_c() : 0.0;
      r.duty = st.heaters[c].duty();
    }
    return r;
  };
  std::optional<HeaterReading> bed;
  if (cfg_.heaters.ch[heat::kBed].enabled) bed = reading(heat::kBed);
  return temperature_report(reading(heat::kHotend), bed);
}

void Engine::ask_status(After after) {
  after_ = after;
  wait_ = Wait::kStatus;
  status_answers_ = session_->status_answers();
  session_->request_status();
}

void Engine::halt() {
  if (killed_) return;
  killed_ = true;
  rx_.clear();
  if (session_) session_->abandon();
  if (opt_.estop_press) opt_.estop_press();
  say("Error:Printer halted. kill() called!");
}

void Engine::step(milliseconds wait) {
  if (killed_) {
    session_->poll(milliseconds(0));
    return;
  }
  while (line_ready() && can_take_line()) take_line();
  if (wait_ == Wait::kNone && la_->window_size() > 0 && !line_ready() &&
      session_->fifo_pushed() - session_->fifo_done() <= kLowWater)
    flush_lookahead();
  const auto now = link_.now();
  if (auto_report_.count() > 0 && !auto_pending_ && now >= auto_at_) {
    auto_pending_ = true;
    auto_answers_ = session_->status_answers();
    session_->request_status();
    auto_at_ = now + auto_report_;
  }
  try {
    session_->poll(busy() ? wait : milliseconds(0));
  } catch (const link::Error&) {
    // A hard limit while moving: the board stopped every axis and flushed its queue. Reported as
    // Marlin reports an endstop hit, then halted as after kill() (restart to go on).
    const auto& st = session_->last_status();
    if (!(st.faults & protocol::v2::kFaultLimit)) throw;
    const size_t a = st.limit & 0x0fu;
    const double mm = a < st.position.size() && a < 4
                          ? static_cast<double>(st.position[a]) / cfg_.steps_per_mm[a]
                          : 0.0;
    say(fmt::format("echo:endstops hit:  {}:{:.2f}", a < 4 ? "XYZE"[a] : '?', mm));
    killed_ = true;
    rx_.clear();
    session_->abandon();
    say(fmt::format("Error:Printer halted. kill() called! ({})",
                    protocol::v2::describe_limits(st, session_->ident().n_axes)));
    return;
  }
  const size_t answers = session_->status_answers();
  if (auto_pending_ && answers > auto_answers_) {
    auto_pending_ = false;
    ++stats_.reports;
    say(temps());
  }
  switch (wait_) {
    case Wait::kNone:
      break;
    case Wait::kStatus:
      if (answers > status_answers_) {
        wait_ = Wait::kNone;
        if (after_ == After::kTemps) {
          ++stats_.reports;
          say("ok " + temps());
        } else if (after_ == After::kEndstops) {
          // Marlin's M119: the switches wired, from the filtered levels in STATUS.
          say("Reporting endstop status");
          const uint16_t sw = session_->last_status().switches;
          for (int a = 0; a < 3; ++a) {
            for (int side = 0; side < 2; ++side) {
              const int bit = a + 8 * side;
              if (!((opt_.limit_switches >> bit) & 1u)) continue;
              say(fmt::format("{}_{}: {}", "xyz"[a], side ? "max" : "min",
                              ((sw >> bit) & 1u) ? "TRIGGERED" : "open"));
            }
          }
          say("ok");
        } else {
          const auto p = position_mm();
          const auto& st = session_->last_status();
          std::array<int64_t, 3> steps{};
          for (size_t a = 0; a < 3 && a < st.position.size(); ++a) steps[a] = st.position[a];
          say(position_report(p, steps));
          say("ok");
        }
      } else {
        session_->request_status();
      }
      break;
    case Wait::kDrain:
    case Wait::kHeat:
      if (session_->complete()) {
        wait_ = Wait::kNone;
        if (after_ == After::kPosition) {
          ask_status(After::kPosition);
        } else {
          say("ok");
        }
      } else {
        const double t = clock_s();
        if (t >= busy_at_) {
          say("echo:busy: processing");
          ++stats_.busy;
          busy_at_ = t + kBusyInterval_s;
        }
        const auto& hs = session_->last_status().heaters;
        const bool reading = !hs.empty() && hs[0].temp_q4 != INT16_MIN;  // sampled yet
        if (wait_ == Wait::kHeat && reading && t >= report_at_) {
          ++stats_.reports;
          say(temps());
          report_at_ = t + kWaitReport_s;
        }
      }
      break;
  }
}

void Engine::take_line() {
  const size_t end = rx_.find_first_of("\r\n");
  const std::string line = rx_.substr(0, end);
  rx_.erase(0, end + 1);
  const Accepted a = checker_.accept(line);
  if (a.refused) {
    ++stats_.resends;
    for (const auto& l : a.answers) say(l);
    return;
  }
  if (a.command.empty()) {
    if (a.line_number) say("ok");  // a numbered empty line
    return;
  }
  ++stats_.lines;
  run_command(a.command);
}

void Engine::run_command(const std::string& cmd) {
  const int m = mcode(cmd);
  switch (m) {
    case 105:
      ask_status(After::kTemps);
      return;
    case 114:
      ask_status(After::kPosition);
      return;
    case 119:
      ask_status(After::kEndstops);
      return;
    case 110:
      if (const auto n = word(cmd, 'N')) checker_.set_last_line(static_cast<long>(*n));
      say("ok");
      return;
    case 155: {
      const double s = word(cmd, 'S').value_or(0.0);
      auto_report_ = milliseconds(static_cast<int64_t>(std::clamp(s, 0.0, 60.0) * 1000.0));
      auto_at_ = link_.now() + auto_report_;
      say("ok");
      return;
    }
    case 400:
      flush_lookahead();
      wait_ = Wait::kDrain;
      after_ = After::kNone;
      busy_at_ = clock_s() + kBusyInterval_s;
      return;
    case 112:
      halt();
      return;
    case 108:  // acted on when its line came in (receive); nothing left to do in turn
      say("ok");
      return;
    case 115:
      for (const auto& l : firmware_report()) say(l);
      say("ok");
      return;
    default:
      break;
  }
  std::string error;
  if (!gcode(cmd, error)) {
    say(error);
    say("ok");
    return;
  }
  if (m == 109 || m == 190) {
    wait_ = Wait::kHeat;
    after_ = After::kNone;
    busy_at_ = clock_s() + kBusyInterval_s;
    report_at_ = clock_s() + kWaitReport_s;
    return;
  }
  say("ok");
}

bool Engine::gcode(const std::string& cmd, std::string& error) {
  std::vector<gcode::Command> cmds;
  try {
    const auto& syntax = gcode::dialect_rules(gcode::Dialect::kMarlin).syntax;
    gcode::Reader reader("marlin", cmd, syntax, *params_);
    gcode::Block b;
    while (reader.next(b)) {
      if (b.kind != gcode::BlockKind::kWords) continue;
      interp_->execute(b, cmds);
    }
  } catch (const gcode::Error& e) {
    error = "echo:" + e.message();
    return false;
  }
  try {
    for (const auto& c : cmds) planner_->add(c);
    push_items(planner_->take_items());
  } catch (const std::exception& e) {
    error = fmt::format("Error:{}", e.what());
    return false;
  }
  return true;
}

void Engine::push_fifo(const v2::Frame& f, int line) {
  session_->push({f, true, nullptr, nullptr, line});
  ++stats_.frames;
}

void Engine::emit_profiles() {
  for (const auto& p : la_->take()) push_fifo(v2::profile_frame(p, cfg_), p.source_line);
}

void Engine::flush_lookahead() {
  if (la_->window_size() == 0) return;
  la_->stop();
  emit_profiles();
}

void Engine::push_items(std::vector<plan::PlanItem> items) {
  for (auto& item : items) {
    if (const auto* s = std::get_if<plan::Segment>(&item)) {
      la_->push(*s, seg_index_++);
      emit_profiles();
    } else if (const auto* d = std::get_if<plan::Dwell>(&item)) {
      flush_lookahead();
      for (const auto& f : v2::dwell_frames(d->seconds, cfg_.clk_hz)) push_fifo(f, d->source_line);
    } else if (const auto* h = std::get_if<plan::HeaterCommand>(&item)) {
      const uint8_t ch = (h->mcode == 104 || h->mcode == 109) ? heat::kHotend : heat::kBed;
      const auto& hc = cfg_.heaters.ch[ch];
      if (!hc.enabled)
        throw std::invalid_argument(
            fmt::format("M{}: the {} heater is disabled in the machine configuration", h->mcode,
                        heat::kChannelNames[ch]));
      if (!h->has_s) throw std::invalid_argument(fmt::format("M{} needs S", h->mcode));
      if (h->s > hc.max_temp_c || (h->s > 0.0 && h->s < hc.min_temp_c))
        throw std::invalid_argument(fmt::format("M{} S{:g}: outside {:g}..{:g} degC", h->mcode,
                                                h->s, hc.min_temp_c, hc.max_temp_c));
      // The setpoint goes after every move before it (M109/M190: the session waits for them).
      if (h->mcode == 109 || h->mcode == 190) flush_lookahead();
      heat::HeaterAction a;
      a.channel = ch;
      a.mcode = h->mcode;
      a.target_c = h->s;
      a.target_q4 = heat::to_q4(h->s);
      a.wait = h->mcode == 109 || h->mcode == 190;
      a.source_line = h->source_line;
      actions_.push_back(a);
      session_->push({v2::heater_setpoint(0, ch, a.target_q4), false, nullptr, &actions_.back()});
    } else if (const auto* o = std::get_if<gcode::Output>(&item)) {
      flush_lookahead();
      v2::OutputSet set;
      v2::add_output(set, *o);
      if (!set.empty()) push_fifo(v2::output_frame(0, set), o->line);
    } else if (const auto* msg = std::get_if<gcode::Message>(&item)) {
      say(fmt::format("echo:{}", msg->text));
    }
    // Pauses (M0/M1, M600): a printer host drives those itself; nothing is sent.
  }
}

}  // namespace fpgacnc::marlin
