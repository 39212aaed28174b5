#include "fpgacnc/grbl/engine.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

#include "fpgacnc/frontend/motion.h"
#include "fpgacnc/gcode/dialect.h"
#include "fpgacnc/link/stream_v2.h"

namespace fpgacnc::grbl {
namespace v2 = protocol::v2;
using std::chrono::milliseconds;

namespace {

// grbl's error code for an interpreter refusal, from what the message says (docs/grbl.md,
// "Errors"); 20 (unsupported or invalid command) when nothing more precise fits.
int error_code(const std::string& msg) {
  auto has = [&](const char* k) { return msg.find(k) != std::string::npos; };
  if (has("expected a number")) return 2;
  if (has("words on one line") || has("two '")) return 25;
  if (has("modal group")) return 21;
  if (has("integer")) return 23;
  if (has("negative")) return 4;
  if (has("radius")) return 34;
  if (has("probe target")) return 33;
  if (has("needs P") || has("needs a P") || has("needs L") || has("needs both P")) return 28;
  if (has("arc") || has("G2") || has("G3")) return 33;
  if (has("letter")) return 1;
  return 20;
}

// The line as grbl's parser sees it: no whitespace or control characters, no comments, upper
// case.
std::string strip_line(const std::string& raw) {
  std::string out;
  int paren = 0;
  for (char c : raw) {
    const auto u = static_cast<unsigned char>(c);
    if (paren) {
      if (c == ')') --paren;
      continue;
    }
    if (c == '(') {
      ++paren;
      continue;
    }
    if (c == ';') break;
    if (u <= ' ' || u >= 0x7F) continue;
    out.push_back(static_cast<char>(std::toupper(u)));
  }
  return out;
}

// What grbl 1.1's parser takes (docs/grbl.md, "G-code"): its letters, G and M codes; 0 or the
// error code for the first word outside them.
int grbl_words(const gcode::Block& b) {
  static const std::string kLetters = "FGIJKLMNPRSTXYZ";
  static const double kG[] = {0,  1,    2,    3,    4,    10,   17, 18,   19, 20,   21, 28, 28.1,
                              30, 30.1, 38.2, 38.3, 38.4, 38.5, 40, 43.1, 49, 53,   54, 55, 56,
                              57, 58,   59,   61,   80,   90,   91, 91.1, 92, 92.1, 93, 94};
  static const double kM[] = {0, 1, 2, 3, 4, 5, 7, 8, 9, 30, 56};
  bool arc = false, offsets = false;
  for (int i = 0; i < b.count; ++i) {
    const auto& w = b.words[static_cast<size_t>(i)];
    if (kLetters.find(w.letter) == std::string::npos) return 20;
    const double v = std::round(w.value * 10.0) / 10.0;
    if (w.letter == 'G') {
      if (v > 59 && v < 60) return 29;  // G59.1..G59.3
      if (std::find(std::begin(kG), std::end(kG), v) == std::end(kG)) return 20;
      arc |= v == 2 || v == 3;
    } else if (w.letter == 'M') {
      if (std::find(std::begin(kM), std::end(kM), v) == std::end(kM)) return 20;
    } else if (w.letter == 'I' || w.letter == 'J' || w.letter == 'K' || w.letter == 'R') {
      offsets = true;
    }
  }
  return arc && !offsets ? 35 : 0;
}

std::string fmt3(double v) {
  return fmt::format("{:.3f}", v);
}

// A G38.2 .. G38.5 word on the line.
bool block_probes(const gcode::Block& b) {
  for (int i = 0; i < b.count; ++i) {
    const auto& w = b.words[static_cast<size_t>(i)];
    const double v = std::round(w.value * 10.0) / 10.0;
    if (w.letter == 'G' && v >= 38.2 && v <= 38.5) return true;
  }
  return false;
}

}  // namespace

const char* state_name(State s) {
  switch (s) {
    case State::kIdle:
      return "Idle";
    case State::kRun:
      return "Run";
    case State::kHold:
      return "Hold:0";
    case State::kHolding:
      return "Hold:1";
    case State::kJog:
      return "Jog";
    case State::kAlarm:
      return "Alarm";
    case State::kCheck:
      return "Check";
    case State::kHome:
      return "Home";
    case State::kSleep:
      return "Sleep";
  }
  return "Idle";
}

Engine::Engine(link::Link& link, config::MachineConfig base, Settings settings, EngineOptions opt)
    : link_(link),
      base_(std::move(base)),
      cfg_(apply_settings(base_, settings)),
      settings_(std::move(settings)),
      opt_(std::move(opt)) {
  if (!opt_.limit_switches) {  // no switches: no hard limits, no homing
    settings_.values[21] = 0.0;
    settings_.values[22] = 0.0;
    cfg_ = apply_settings(base_, settings_);
  }
}

Engine::~Engine() = default;

void Engine::connect() {
  ident_ = link::handshake_v2(link_, opt_.v2, rep_, std::nullopt);
  // grbl with homing enabled starts in alarm until `$H` (or `$X`).
  if (settings_.values.at(22) != 0.0) alarm_ = true;
  restart();
}

void Engine::opened() {
  soft_reset();
}

void Engine::new_session() {
  session_ = std::make_unique<link::V2Session>(link_, opt_.v2, ident_, rep_);
  const auto& st = session_->start();
  // The machine's hold ramp and the rates in effect; a hold left on the board ends here (the
  // queue behind it was dropped or has run out).
  motion_ok_ = session_->configure_motion(motion_frame(false, (st.state & v2::kStateHold) != 0));
  if (motion_ok_) ++stats_.motions;
  frontend::push_config_axes(*session_, ident_, cfg_);
  if (disarm_next_) {  // a HOME left armed keeps its switches' trips suppressed
    session_->push({v2::trigger(0, v2::TriggerMode::Disarm)});
    disarm_next_ = false;
  }
  fifo_info_.clear();
  fifo_base_ = 0;
}

void Engine::restart() {
  new_session();
  plan::Steps4 pos{};
  const auto& st = session_->last_status();
  for (size_t a = 0; a < 4 && a < st.position.size(); ++a) pos[a] = st.position[a];
  rebuild_pipeline(pos);
  banner();
}

void Engine::rebuild_pipeline(const plan::Steps4& steps) {
  // Work offsets G54..G59 survive a reset (grbl keeps them in EEPROM).
  std::vector<std::string> restore;
  if (params_) {
    const double mm = modal_.units == "G20" ? 25.4 : 1.0;  // parameters are in program units
    for (int s = 0; s < 6; ++s) {
      const int base = 5221 + 20 * s;
      const double x = params_->get(base) * mm, y = params_->get(base + 1) * mm,
                   z = params_->get(base + 2) * mm;
      if (x != 0.0 || y != 0.0 || z != 0.0)
        restore.push_back(fmt::format("G21 G10 L2 P{} X{:.6f} Y{:.6f} Z{:.6f}", s + 1, x, y, z));
    }
  }
  params_ = std::make_unique<gcode::Params>();
  gcode::Options go = plan::gcode_options(cfg_);
  go.dialect = gcode::Dialect::kGrbl;
  go.dialect_source = "fpgacnc grbl";
  go.tool_change_pause = false;  // grbl 1.1 takes M6 and T and does nothing with them
  go.probing = true;             // G38.x: Probe commands, run by the probing cycle
  gcode::DialectChoice dc;
  dc.dialect = gcode::Dialect::kGrbl;
  dc.reason = "fpgacnc grbl";
  interp_ = std::make_unique<gcode::Interpreter>("grbl", go, dc, *params_);
  planner_ = std::make_unique<plan::Planner>(cfg_, plan::PlanOptions{});
  // A feed override above 100 % is the host's: the lines planned from now on (docs/grbl.md).
  if (motion_ok_ && ov_.feed > 100) planner_->set_feed_override(ov_.feed);
  la_ = std::make_unique<plan::Lookahead>(plan::motion_limits(cfg_));
  seg_index_ = 0;
  modal_ = Modal{};
  wco_changed_ = true;
  // The parser and the planner start where the machine is (grbl's gc_sync_position).
  frontend::sync_to(steps, cfg_, gcode::Dialect::kGrbl, *params_, *interp_, *planner_, restore);
  modal_ = Modal{};
}

void Engine::say(std::string_view line) {
  out_ += line;
  out_ += "\r\n";
}

void Engine::banner() {
  out_ += "\r\n";
  say(kBanner);
  // grbl's start-up check with hard limits: a switch held at reset keeps the alarm.
  if (session_->last_status().switches) {
    alarm_ = true;
    say("[MSG:Check Limits]");
  }
  if (alarm_) {
    say("[MSG:'$H'|'$X' to unlock]");
    return;
  }
  for (const auto& l : settings_.startup) {
    if (l.empty()) continue;
    const int rc = gcode_line(l, check_);
    say(rc ? fmt::format(">{}:error:{}", l, rc) : fmt::format(">{}:ok", l));
  }
}

std::string Engine::take_output() {
  std::string s;
  s.swap(out_);
  return s;
}

void Engine::receive(std::string_view bytes) {
  for (char ch : bytes) {
    const auto c = static_cast<unsigned char>(ch);
    switch (c) {
      case '?':
        report_pending_ = true;
        break;
      case 0x18:
        soft_reset();
        break;
      case '~':  // cycle start: ends a feed hold, resumes after M0
      case '!':  // feed hold
        realtime_.push_back(ch);
        break;
      default:
        // 0x80..0xFF: jog cancel (0x85), overrides (0x90..0x9D); safety door and coolant toggles
        // ignored.
        if (c >= 0x80) {
          if (c == 0x85 || (c >= 0x90 && c <= 0x9D)) realtime_.push_back(ch);
          break;
        }
        rx_.push_back(ch);
    }
  }
}

v2::Motion Engine::motion_frame(bool hold, bool resume, bool cancel) const {
  v2::Motion m = link::machine_motion(cfg_, ident_.n_axes);
  m.hold = hold;
  m.resume = resume;
  m.cancel = cancel;
  m.feed = v2::rate_from_percent(std::min(ov_.feed, 100));
  m.rapid = v2::rate_from_percent(ov_.rapid);
  return m;
}

void Engine::send_motion(bool hold, bool resume, bool cancel) {
  session_->send_motion(motion_frame(hold, resume, cancel));
  ++stats_.motions;
}

bool Engine::board_held() const {
  return hold_ || (session_ && (session_->last_status().state & v2::kStateHold) != 0);
}

void Engine::realtime(unsigned char c) {
  if (c == '~') {
    held_ = false;  // after M0
    if (motion_ok_ && board_held()) {
      hold_ = false;
      send_motion(false, true);
      ++stats_.resumes;
    }
    return;
  }
  if (c == 0x85 || (c == '!' && jog_)) {  // jog cancel; grbl's feed hold cancels a jog too
    if (jog_ && !jog_cancel_) start_jog_cancel();
    return;
  }
  if (c == '!') {
    // grbl holds a cycle in progress (Run); Idle, Alarm, Check: nothing to hold.
    if (!motion_ok_ || hold_ || alarm_ || check_ || sleep_ || !motion_pending()) return;
    hold_ = true;
    send_motion(true, false);
    ++stats_.holds;
    return;
  }
  const Overrides before = ov_;
  switch (c) {
    case 0x90:
      ov_.feed = 100;
      break;
    case 0x91:
      ov_.feed += 10;
      break;
    case 0x92:
      ov_.feed -= 10;
      break;
    case 0x93:
      ov_.feed += 1;
      break;
    case 0x94:
      ov_.feed -= 1;
      break;
    case 0x95:
      ov_.rapid = 100;
      break;
    case 0x96:
      ov_.rapid = 50;
      break;
    case 0x97:
      ov_.rapid = 25;
      break;
    case 0x99:
      ov_.spindle = 100;
      break;
    case 0x9A:
      ov_.spindle += 10;
      break;
    case 0x9B:
      ov_.spindle -= 10;
      break;
    case 0x9C:
      ov_.spindle += 1;
      break;
    case 0x9D:
      ov_.spindle -= 1;
      break;
    default:
      return;
  }
  ov_.feed = std::clamp(ov_.feed, 10, 200);
  ov_.spindle = std::clamp(ov_.spindle, 10, 200);
  if (!motion_ok_) {  // no motion rate on this board: feed and rapid stay 100 %
    ov_.feed = before.feed;
    ov_.rapid = before.rapid;
  }
  if (ov_ == before) return;
  ov_report_ = true;
  if (ov_.feed != before.feed) planner_->set_feed_override(std::max(ov_.feed, 100));
  const bool board_rates =
      std::min(ov_.feed, 100) != std::min(before.feed, 100) || ov_.rapid != before.rapid;
  if (board_rates && !resetting_) send_motion(false, false);
}

bool Engine::motion_pending() const {
  if (limit_alarm_) return false;  // the board stopped and flushed everything
  return (la_ && la_->window_size() > 0) ||
         (session_ && session_->fifo_done() < session_->fifo_pushed());
}

State Engine::state() const {
  if (sleep_) return State::kSleep;
  if (homing_) return State::kHome;
  if (probe_) return State::kRun;
  if (alarm_) return State::kAlarm;
  if (check_) return State::kCheck;
  if (jog_cancel_ || (jog_ && motion_pending())) return State::kJog;
  if (board_held()) {
    // Hold:0 once the board reports the hold complete (HOLD and STOPPED), Hold:1 before.
    const uint8_t b = session_->last_status().state;
    return (b & v2::kStateHold) && (b & v2::kStateStopped) ? State::kHold : State::kHolding;
  }
  if (held_) return State::kHold;
  if (motion_pending() || pause_pending_) return State::kRun;
  return State::kIdle;
}

bool Engine::busy() const {
  return motion_pending() || report_pending_ || resetting_ || pause_pending_ || jog_cancel_ ||
         homing_ || probe_ || (line_ready() && can_take_line());
}

std::array<double, 4> Engine::mpos() const {
  std::array<double, 4> p{};
  const auto& st = session_->last_status();
  for (size_t a = 0; a < 4 && a < st.position.size(); ++a)
    p[a] = static_cast<double>(st.position[a]) / cfg_.steps_per_mm[a];
  return p;
}

bool Engine::line_ready() const {
  return rx_.find_first_of("\r\n") != std::string::npos;
}

bool Engine::can_take_line() const {
  return !resetting_ && !jog_cancel_ && !homing_ && !probe_ && !critical_ && !held_ &&
         !pause_pending_ && !limit_alarm_ &&
         session_->unsent() < std::max<size_t>(cfg_.lookahead_segments, 1);
}

void Engine::step(milliseconds wait) {
  if (!resetting_) {
    for (const char c : realtime_) realtime(static_cast<unsigned char>(c));
  }
  realtime_.clear();
  if (resetting_) continue_reset();
  if (homing_ && !resetting_) {
    // The cycle polls its own sessions; a report shows the last STATUS it saw (state Home).
    if (report_pending_) {
      write_report();
      report_pending_ = report_asked_ = false;
    }
    continue_homing(wait);
    return;
  }
  if (probe_ && !resetting_) {
    // The cycle polls its own sessions: a report shows the last STATUS seen.
    if (report_pending_) {
      write_report();
      report_pending_ = report_asked_ = false;
    }
    continue_probe(wait);
    return;
  }
  if (jog_cancel_ && !resetting_) continue_jog_cancel();
  if (!resetting_) {
    while (line_ready() && can_take_line()) take_line();
    // Flush rule (file comment of engine.h).
    if (la_->window_size() > 0 && !line_ready() &&
        session_->fifo_pushed() - session_->fifo_done() <= kLowWater)
      flush_lookahead();
  }
  if (report_pending_) {
    if (!report_asked_) {
      // A STATUS asked for now: the answers to what is still in flight (a MOTION's, an idle
      // poll's) show the board before the '?' and come first.
      session_->request_status(true);
      report_answers_ = session_->status_answers() + session_->status_unanswered();
      report_asked_ = true;
    } else {
      session_->request_status();
    }
  }
  const bool waiting = motion_pending() || report_asked_ || resetting_ || jog_cancel_;
  try {
    session_->poll(waiting ? wait : milliseconds(0));
  } catch (const link::Error&) {
    on_session_error();
  }
  if (report_asked_ && session_->status_answers() >= report_answers_) {
    write_report();
    report_pending_ = report_asked_ = false;
  }
  if (jog_ && !jog_cancel_ && !motion_pending()) {  // the jogs have run: the parser follows
    jog_ = false;
    resync_parser(planner_->position());
  }
  if (pause_pending_ && session_->complete()) {
    pause_pending_ = false;
    held_ = true;
  }
  while (fifo_base_ < session_->fifo_done() && !fifo_info_.empty()) {
    fifo_info_.pop_front();
    ++fifo_base_;
  }
}

void Engine::take_line() {
  const size_t end = rx_.find_first_of("\r\n");
  const std::string line = rx_.substr(0, end);
  rx_.erase(0, end + 1);
  process_line(line);
}

void Engine::process_line(const std::string& raw) {
  ++stats_.lines;
  const std::string cmd = strip_line(raw);
  bool reset_after = false;
  int rc = 0;
  if (cmd.size() >= kLineMax) {
    rc = 11;
  } else if (cmd.empty()) {
    rc = 0;
  } else if (cmd[0] == '$') {
    rc = system_command(cmd);
    if (rc == -1) {  // $C off: ok, then a reset (grbl)
      rc = 0;
      reset_after = true;
    }
  } else if (alarm_ || sleep_ || jog_ || jog_cancel_) {
    rc = 9;  // grbl: G-code is locked out in Alarm, Sleep and Jog
  } else if (!std::isalpha(static_cast<unsigned char>(cmd[0]))) {
    rc = 1;  // a value without its letter
  } else {
    rc = gcode_line(raw, check_);
  }
  if (rc == kHomingStarted || rc == kProbeStarted) return;  // answered when the cycle ends
  if (rc == kSoftLimit) {  // grbl: alarm, then nothing until a reset (which sends the ok)
    ++stats_.errors;
    alarm_ = critical_ = true;
    say("ALARM:2");
    say("[MSG:Reset to continue]");
    return;
  }
  if (rc == 0) {
    ++stats_.oks;
    say("ok");
  } else {
    ++stats_.errors;
    say(fmt::format("error:{}", rc));
  }
  if (reset_after) soft_reset();
}

int Engine::gcode_line(const std::string& raw, bool check_only) {
  std::vector<gcode::Command> cmds;
  bool ended = false;
  try {
    const auto& syntax = gcode::dialect_rules(gcode::Dialect::kGrbl).syntax;
    gcode::Reader reader("grbl", raw, syntax, *params_);
    gcode::Block b;
    while (reader.next(b)) {
      if (b.kind != gcode::BlockKind::kWords) {
        if (b.kind == gcode::BlockKind::kSystem || b.kind == gcode::BlockKind::kQuery) return 3;
        continue;
      }
      if (int rc = grbl_words(b)) return rc;
      if (!opt_.probe && block_probes(b)) {
        say("[MSG:probing needs a board with the probe input and its trigger: the Verilated "
            "board (--model rtl) or a --port]");
        return 20;
      }
      if (!interp_->execute(b, cmds)) ended = true;
      track_modal(b);
    }
  } catch (const gcode::Error& e) {
    return error_code(e.message());
  }
  // A probe is the line's last command (its end is the board's).
  const gcode::Probe* probe = nullptr;
  for (const auto& c : cmds) {
    if (const auto* p = std::get_if<gcode::Probe>(&c)) probe = p;
  }
  if (probe && (ended || !std::holds_alternative<gcode::Probe>(cmds.back()))) {
    resync_parser(planner_->position());
    say("[MSG:a probe move must be the last command of its line]");
    return 20;
  }
  if (check_only) {  // grbl checks soft limits in check mode too
    for (const auto& c : cmds) {
      const auto* m = std::get_if<gcode::Move>(&c);
      if (m && plan::check_travel(*m, cfg_)) return kSoftLimit;
    }
    // A probe in check mode is checked; the parser stays at its target, as grbl's does.
    if (probe && plan::check_travel(probe->move, cfg_)) return kSoftLimit;
    return 0;
  }
  if (probe && plan::check_travel(probe->move, cfg_)) return kSoftLimit;
  try {
    for (const auto& c : cmds)
      if (!std::holds_alternative<gcode::Probe>(c)) planner_->add(c);
    push_items(planner_->take_items());
  } catch (const plan::TravelError&) {
    planner_->take_items();  // the moves of this line before the offending one are not sent
    return kSoftLimit;
  } catch (const std::invalid_argument&) {
    return 33;  // a target the planner cannot turn into frames
  }
  if (probe) return start_probe(*probe);
  if (ended) {
    flush_lookahead();
    say("[MSG:Pgm End]");
    // grbl restores the overrides at M2 / M30 (RESTORE_OVERRIDES_AFTER_PROGRAM_END).
    if (ov_ != Overrides{}) {
      const bool board_rates = ov_.feed < 100 || ov_.rapid != 100;
      ov_ = Overrides{};
      ov_report_ = true;
      if (board_rates && motion_ok_) send_motion(false, false);
    }
    rebuild_pipeline(planner_->position());
  }
  return 0;
}

void Engine::push_fifo(const v2::Frame& f, int line, double feed, double s) {
  session_->push({f, true, nullptr, nullptr, line});
  fifo_info_.emplace_back(feed, s);
  ++stats_.frames;
}

void Engine::emit_profiles() {
  for (const auto& p : la_->take())
    push_fifo(v2::profile_frame(p, cfg_), p.source_line, p.v_cruise * 60.0,
              std::max(0.0, p.spindle_s));
}

void Engine::flush_lookahead() {
  if (la_->window_size() == 0) return;
  la_->stop();
  emit_profiles();
  ++stats_.flushes;
}

void Engine::push_items(std::vector<plan::PlanItem> items) {
  for (auto& item : items) {
    if (const auto* s = std::get_if<plan::Segment>(&item)) {
      la_->push(*s, seg_index_++);
      emit_profiles();
    } else if (const auto* d = std::get_if<plan::Dwell>(&item)) {
      flush_lookahead();
      for (const auto& f : v2::dwell_frames(d->seconds, cfg_.clk_hz))
        push_fifo(f, d->source_line, 0.0, 0.0);
    } else if (std::get_if<gcode::Pause>(&item)) {
      flush_lookahead();
      pause_pending_ = true;
    } else if (const auto* o = std::get_if<gcode::Output>(&item)) {
      flush_lookahead();
      v2::OutputSet set;
      v2::add_output(set, *o);
      if (!set.empty()) push_fifo(v2::output_frame(0, set), o->line, 0.0, 0.0);
    } else if (const auto* m = std::get_if<gcode::Message>(&item)) {
      say(fmt::format("[MSG:{}]", m->text));
    }
    // Heater commands: grbl has none (the grbl dialect refuses M104/M109 before this).
  }
}

void Engine::track_modal(const gcode::Block& b) {
  for (int i = 0; i < b.count; ++i) {
    const auto& w = b.words[static_cast<size_t>(i)];
    const double v = w.value;
    const std::string g = fmt::format("G{:g}", v);
    if (w.letter == 'G') {
      if (v == 0 || v == 1 || v == 2 || v == 3 || v == 80 || (v > 38 && v < 39)) modal_.motion = g;
      if (v >= 54 && v <= 59 && v == std::trunc(v)) {
        modal_.wcs = g;
        wco_changed_ = true;
      }
      if (v == 17 || v == 18 || v == 19) modal_.plane = g;
      if (v == 20 || v == 21) modal_.units = g;
      if (v == 90 || v == 91) modal_.distance = g;
      if (v == 93 || v == 94) modal_.feed_mode = g;
      if (v == 10 || v == 92 || (v > 92 && v < 93) || v == 43.1 || v == 49) wco_changed_ = true;
    } else if (w.letter == 'M') {
      if (v == 3 || v == 4 || v == 5) modal_.spindle = fmt::format("M{:g}", v);
      if (v == 7 || v == 8 || v == 9) modal_.coolant = fmt::format("M{:g}", v);
    } else if (w.letter == 'T') {
      modal_.tool = static_cast<int>(v);
    } else if (w.letter == 'F') {
      modal_.feed = v;
    } else if (w.letter == 'S') {
      modal_.s = v;
    }
  }
}

std::array<double, 3> Engine::wco() const {
  std::array<double, 3> w{};
  const int cs = std::clamp(static_cast<int>(params_->get(5220)), 1, 9);
  const double unit = modal_.units == "G20" ? 25.4 : 1.0;
  for (int a = 0; a < 3; ++a) {
    double v = params_->get(5221 + 20 * (cs - 1) + a) + params_->get(5211 + a);
    if (a == 2) v += params_->get(5403);
    w[static_cast<size_t>(a)] = v * unit;
  }
  return w;
}

void Engine::write_report() {
  ++stats_.reports;
  const int mask = static_cast<int>(settings_.values.at(10));
  const bool inches = settings_.values.at(13) != 0.0;
  const double div = inches ? 25.4 : 1.0;
  auto vec = [&](const std::array<double, 3>& v) {
    return inches ? fmt::format("{:.4f},{:.4f},{:.4f}", v[0] / div, v[1] / div, v[2] / div)
                  : fmt::format("{},{},{}", fmt3(v[0]), fmt3(v[1]), fmt3(v[2]));
  };
  const auto m = mpos();
  const auto off = wco();
  std::array<double, 3> pos{m[0], m[1], m[2]};
  // State and position come from the same STATUS: a DONE that arrived after it (in the same
  // poll) must not make a report say Idle beside the position of a move still running.
  State st = state();
  if (st == State::kIdle && (session_->last_status().state & v2::kStateBusy)) st = State::kRun;
  std::string r = "<";
  r += state_name(st);
  if (mask & 1) {
    r += "|MPos:" + vec(pos);
  } else {
    for (size_t a = 0; a < 3; ++a) pos[a] -= off[a];
    r += "|WPos:" + vec(pos);
  }
  if (mask & 2) {
    const size_t w = std::max<size_t>(cfg_.lookahead_segments, 2) - 1;
    const size_t used = la_->window_size() + session_->unsent();
    r += fmt::format("|Bf:{},{}", used >= w ? 0 : w - used,
                     rx_.size() >= kRxBuffer ? 0 : kRxBuffer - rx_.size());
  }
  double feed = 0.0, s = 0.0;
  if ((st == State::kRun || st == State::kJog) && !fifo_info_.empty())
    std::tie(feed, s) = fifo_info_.front();
  r += fmt::format("|FS:{:.0f},{:.0f}", feed / div, s);
  // Pn: the limit pins asserted now (grbl 1.1: X, Y, Z letters; omitted when none).
  // (STATUS reports only the switches the board wires.)
  if (const uint16_t sw = session_->last_status().switches) {
    r += "|Pn:";
    for (int a = 0; a < 3; ++a)
      if ((sw >> a) & 0x101u) r += "XYZ"[a];
  }
  // WCO when it changed and every 10th report; Ov on the report after, and on the next report
  // after an override changed (grbl's refresh rule).
  const uint64_t n = report_count_++;
  bool ov = ov_report_;
  if (wco_changed_ || n % 10 == 0) {
    r += "|WCO:" + vec(off);
    wco_changed_ = false;
  } else if (n % 10 == 1) {
    ov = true;
  }
  if (ov) {
    r += fmt::format("|Ov:{},{},{}", ov_.feed, ov_.rapid, ov_.spindle);
    ov_report_ = false;
  }
  r += ">";
  say(r);
}

int Engine::system_command(const std::string& cmd) {
  const State st = state();
  const bool idle = st == State::kIdle || st == State::kAlarm || st == State::kCheck;
  auto need_idle = [&]() {
    if (idle) return 0;
    flush_lookahead();
    return 8;
  };
  if (cmd == "$") {
    say("[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]");
    return 0;
  }
  if (cmd == "$G") {
    say(fmt::format("[GC:{} {} {} {} {} {} {} {} T{} F{:.0f} S{:.0f}]", modal_.motion, modal_.wcs,
                    modal_.plane, modal_.units, modal_.distance, modal_.feed_mode, modal_.spindle,
                    modal_.coolant, modal_.tool, modal_.feed, modal_.s));
    return 0;
  }
  if (cmd == "$$") {
    if (int rc = need_idle()) return rc;
    const std::string all = format_settings(settings_);
    for (size_t b = 0, e; b < all.size(); b = e + 1) {
      e = all.find('\n', b);
      say(std::string_view(all).substr(b, e - b));
    }
    return 0;
  }
  if (cmd == "$#") {
    if (int rc = need_idle()) return rc;
    auto p3 = [&](int base) {
      return fmt::format("{},{},{}", fmt3(params_->get(base)), fmt3(params_->get(base + 1)),
                         fmt3(params_->get(base + 2)));
    };
    for (int s = 0; s < 6; ++s) say(fmt::format("[G{}:{}]", 54 + s, p3(5221 + 20 * s)));
    say(fmt::format("[G28:{}]", p3(5161)));
    say(fmt::format("[G30:{}]", p3(5181)));
    say(fmt::format("[G92:{}]", p3(5211)));
    say(fmt::format("[TLO:{}]", fmt3(params_->get(5403))));
    say(prb_line());
    return 0;
  }
  if (cmd == "$I") {
    say(fmt::format("[VER:{}:{}]", kVersion, settings_.info));
    say(fmt::format("[OPT:VNM,{},{}]", std::max<size_t>(cfg_.lookahead_segments, 2) - 1,
                    kRxBuffer));
    return 0;
  }
  if (cmd.rfind("$I=", 0) == 0) {
    if (int rc = need_idle()) return rc;
    settings_.info = cmd.substr(3);
    save();
    return 0;
  }
  if (cmd == "$N") {
    say("$N0=" + settings_.startup[0]);
    say("$N1=" + settings_.startup[1]);
    return 0;
  }
  if (cmd.rfind("$N0=", 0) == 0 || cmd.rfind("$N1=", 0) == 0) {
    if (int rc = need_idle()) return rc;
    const std::string l = cmd.substr(4);
    if (l.size() >= kLineMax) return 14;
    settings_.startup[cmd[2] == '0' ? 0 : 1] = l;
    save();
    return 0;
  }
  if (cmd == "$C") {
    if (check_) {
      say("[MSG:Disabled]");
      return -1;
    }
    if (alarm_ || !idle) return alarm_ ? 9 : need_idle();
    check_ = true;
    say("[MSG:Enabled]");
    return 0;
  }
  if (cmd == "$X") {
    if (alarm_ && (session_->last_status().faults & v2::kFaultLimit)) {
      if (int rc = clear_limit_alarm()) return rc;
    }
    if (alarm_) {
      alarm_ = false;
      say("[MSG:Caution: Unlocked]");
    }
    return 0;
  }
  if (cmd == "$H") return start_homing();
  if (cmd.rfind("$J", 0) == 0) return jog_line(cmd);
  if (cmd == "$SLP") {
    if (int rc = need_idle()) return rc;
    sleep_ = true;
    say("[MSG:Sleeping]");
    return 0;
  }
  if (cmd.rfind("$RST=", 0) == 0) {
    if (int rc = need_idle()) return rc;
    const std::string what = cmd.substr(5);
    if (what != "$" && what != "#" && what != "*") return 3;
    if (what == "$" || what == "*") {
      const Settings d = settings_from_config(base_);
      settings_.values = d.values;
      if (what == "*") {
        settings_.startup = {};
        settings_.info.clear();
      }
      cfg_ = apply_settings(base_, settings_);
    }
    const plan::Steps4 pos = planner_->position();
    if (what == "#" || what == "*") params_.reset();  // no work offsets to restore
    rebuild_pipeline(pos);
    save();
    say("[MSG:Restoring defaults]");
    return 0;
  }
  // $N=value
  const size_t eq = cmd.find('=');
  if (eq != std::string::npos && eq > 1) {
    const std::string num = cmd.substr(1, eq - 1);
    const std::string val = cmd.substr(eq + 1);
    if (num.find_first_not_of("0123456789") != std::string::npos) return 3;
    char* end = nullptr;
    const double v = std::strtod(val.c_str(), &end);
    if (val.empty() || *end) return 2;
    if (int rc = need_idle()) return rc;
    Settings next = settings_;
    if (int rc = set_value(next, std::stoi(num), v, opt_.limit_switches != 0)) return rc;
    settings_ = std::move(next);
    const plan::Steps4 pos = planner_->position();
    cfg_ = apply_settings(base_, settings_);
    // New step timing and hold ramp to the board, the planner at the same step position.
    frontend::push_config_axes(*session_, ident_, cfg_);
    if (motion_ok_) send_motion(false, false);
    rebuild_pipeline(pos);
    save();
    return 0;
  }
  return 3;
}

void Engine::save() {
  if (!opt_.settings_path.empty()) save_settings(opt_.settings_path, settings_);
}

void Engine::on_session_error() {
  const auto& st = session_->last_status();
  if (!(st.faults & v2::kFaultLimit)) throw;
  session_->abandon();  // latched faults are no longer errors; nothing more is sent
  if (alarm_) return;   // a FAULT_CLEAR refused while the switch is held: still in alarm
  // grbl's hard-limit alarm: a critical alarm; lines wait until a soft reset.
  la_ = std::make_unique<plan::Lookahead>(plan::motion_limits(cfg_));
  alarm_ = limit_alarm_ = true;
  held_ = pause_pending_ = hold_ = false;
  say("ALARM:1");
  say("[MSG:Reset to continue]");
}

int Engine::clear_limit_alarm() {
  new_session();  // its first frame is FAULT_CLEAR (V2Session::start)
  const auto end = link_.now() + opt_.v2.answer_timeout;
  try {
    while (!session_->settled() && link_.now() < end) session_->poll(milliseconds(20));
    const size_t answers = session_->status_answers();
    while (session_->status_answers() == answers && link_.now() < end) {
      session_->request_status();
      session_->poll(milliseconds(20));
    }
  } catch (const link::Error&) {
    on_session_error();
  }
  if (session_->last_status().faults & v2::kFaultLimit) {
    say("[MSG:Check Limits]");
    return 9;
  }
  plan::Steps4 pos{};
  const auto& st = session_->last_status();
  for (size_t a = 0; a < 4 && a < st.position.size(); ++a) pos[a] = st.position[a];
  rebuild_pipeline(pos);
  return 0;
}

void Engine::soft_reset() {
  ++stats_.resets;
  if (critical_) {
    say("ok");  // the line that raised ALARM:2 ends here, as in grbl
    critical_ = false;
  }
  rx_.clear();  // grbl empties its receive buffer
  realtime_.clear();
  // grbl: a reset during homing is ALARM:6 (not 3); the board is stopped below as a running job
  // (its e-stop, else MOTION CANCEL) and the next session disarms the trigger.
  const bool homing = homing_ != nullptr;
  if (homing) {
    homing_.reset();
    say("ALARM:6");
    alarm_ = true;
    disarm_next_ = true;
  }
  // A reset while probing: ALARM:3 (below) as for any motion; the next session disarms.
  const bool probing = probe_ != nullptr;
  if (probing) {
    probe_.reset();
    disarm_next_ = true;
  }
  // A hold counts as motion (grbl: a reset during a feed hold is ALARM:3 too).
  const bool moving =
      (homing || probing || motion_pending() || (motion_ok_ && board_held())) && !check_;
  limit_alarm_ = false;  // a reset ends the critical alarm (the FAULT_CLEAR comes with it)
  la_ = std::make_unique<plan::Lookahead>(plan::motion_limits(cfg_));
  stats_.aborted += session_->abandon();
  if (moving) {
    if (!alarm_) say("ALARM:3");  // not after ALARM:2: the alarm is already raised
    alarm_ = true;
    if (motion_ok_ && (board_held() || ((homing || probing) && !opt_.estop_press))) {
      // A hold in effect, or a homing move on a board without an e-stop input: MOTION CANCEL
      // drops the board's queue once it is at rest, positions kept, no fault (docs/machine.md
      // "Cancel").
      send_motion(false, false, true);
    } else if (opt_.estop_press && opt_.estop_release) {
      opt_.estop_press();  // running: the board drops its queue at once
      estop_pressed_ = true;
    }
  }
  hold_ = false;
  jog_ = jog_cancel_ = false;  // a jog cancel's CANCEL, if any, was sent: the reset waits as well
  // grbl restores the overrides at a reset (the next session's MOTION carries them).
  if (ov_ != Overrides{}) ov_report_ = true;
  ov_ = Overrides{};
  if (sleep_) {
    sleep_ = false;
    alarm_ = true;
  }
  check_ = false;
  held_ = pause_pending_ = false;
  resetting_ = true;
  reset_asked_ = false;
  continue_reset();
}

int Engine::jog_line(const std::string& cmd) {
  if (cmd.size() < 3 || cmd[2] != '=') return 3;
  const State st = state();
  if (st != State::kIdle && st != State::kJog) return 8;
  if (!motion_ok_) return 3;  // no jog cancel on a board without the motion rate
  std::optional<double> target[3], feed;
  bool inches = modal_.units == "G20", incremental = modal_.distance == "G91", machine = false;
  try {
    const auto& syntax = gcode::dialect_rules(gcode::Dialect::kGrbl).syntax;
    gcode::Reader reader("grbl", cmd.substr(3), syntax, *params_);
    gcode::Block b;
    std::string seen;
    while (reader.next(b)) {
      if (b.kind != gcode::BlockKind::kWords) return 16;
      for (int i = 0; i < b.count; ++i) {
        const auto& w = b.words[static_cast<size_t>(i)];
        if (w.letter != 'G' && seen.find(w.letter) != std::string::npos) return 25;
        seen += w.letter;
        switch (w.letter) {
          case 'G':
            if (w.value == 20 || w.value == 21) {
              inches = w.value == 20;
            } else if (w.value == 90 || w.value == 91) {
              incremental = w.value == 91;
            } else if (w.value == 53) {
              machine = true;
            } else {
              return 16;  // only units, distance mode and G53 may come with a jog
            }
            break;
          case 'X':
          case 'Y':
          case 'Z':
            target[w.letter - 'X'] = w.value;
            break;
          case 'F':
            feed = w.value;
            break;
          case 'N':
            break;
          default:
            return 16;
        }
      }
    }
  } catch (const gcode::Error& e) {
    return error_code(e.message());
  }
  if (!feed || *feed <= 0.0) return 22;  // a jog carries its own feed rate
  if (!target[0] && !target[1] && !target[2]) return 16;
  if (check_) return 0;  // check mode: parsed, nothing moves
  const double unit = inches ? 25.4 : 1.0;
  const auto off = wco();
  gcode::Move m;
  m.motion = gcode::Motion::kLinear;
  for (size_t a = 0; a < 4; ++a)
    m.start[a] = static_cast<double>(planner_->position()[a]) / cfg_.steps_per_mm[a];
  m.end = m.start;
  for (size_t a = 0; a < 3; ++a) {
    if (!target[a]) continue;
    const double v = *target[a] * unit;
    m.end[a] = incremental ? m.start[a] + v : machine ? v : v + off[a];
  }
  m.feed_mm_min = *feed * unit;
  m.spindle_on = false;  // a jog never fires the laser or turns the spindle
  try {
    planner_->add(m);
  } catch (const plan::TravelError&) {
    planner_->take_items();
    return 15;  // grbl: the jog target exceeds the machine travel; nothing moves
  }
  push_items(planner_->take_items());
  jog_ = true;
  return 0;
}

void Engine::start_jog_cancel() {
  la_ = std::make_unique<plan::Lookahead>(plan::motion_limits(cfg_));
  stats_.aborted += session_->abandon();
  send_motion(false, false, true);  // CANCEL: decelerate with the hold ramp, drop the queue
  jog_ = false;
  jog_cancel_ = true;
  jog_answers_ = session_->status_answers();
}

void Engine::continue_jog_cancel() {
  if (!session_->settled() || session_->motion_pending()) return;
  // At rest and flushed: a STATUS newer than the CANCEL's answer shows neither BUSY nor HOLD.
  session_->request_status();
  if (session_->status_answers() == jog_answers_) return;
  jog_answers_ = session_->status_answers();
  if (session_->last_status().state & (v2::kStateBusy | v2::kStateHold)) return;
  jog_cancel_ = false;
  new_session();
  plan::Steps4 pos{};
  const auto& st = session_->last_status();
  for (size_t a = 0; a < 4 && a < st.position.size(); ++a) pos[a] = st.position[a];
  resync_parser(pos);
}

int Engine::start_homing() {
  if (settings_.values.at(22) == 0.0) return 5;  // homing not enabled
  if (check_) return 8;
  const State st = state();
  if (st != State::kIdle && st != State::kAlarm) return 8;
  if (limit_alarm_ || (session_->last_status().faults & v2::kFaultLimit)) return 9;
  la_ = std::make_unique<plan::Lookahead>(plan::motion_limits(cfg_));
  // The cycle's sessions: the board keeps its MOTION rates and CONFIG_AXIS timing, so only the
  // session itself (the cycle switches the device's soft limits off in it).
  homing_ = std::make_unique<link::HomingCycle>(
      link_, cfg_, ident_, opt_.limit_switches, [this]() -> link::V2Session& {
        session_ = std::make_unique<link::V2Session>(link_, opt_.v2, ident_, rep_);
        session_->start();
        fifo_info_.clear();
        fifo_base_ = 0;
        return *session_;
      });
  if (homing_->empty()) {
    homing_.reset();
    return 5;  // no switch on any homing side: as homing not enabled
  }
  homing_started_ = false;
  return kHomingStarted;
}

void Engine::continue_homing(milliseconds wait) {
  try {
    if (!homing_started_) {
      // The frames of the session before (a `$N=` just before `$H`) go out and are acknowledged
      // before the cycle's first session starts at the board's next_seq.
      session_->poll(wait);
      if (!session_->complete()) return;
      homing_started_ = true;
    }
    if (homing_->step(wait)) finish_homing();
  } catch (const link::Error& e) {
    homing_.reset();
    if (session_->last_status().faults & v2::kFaultLimit) {
      disarm_next_ = true;  // a switch not armed tripped: ALARM:1, lines wait for a reset
      on_session_error();
      return;
    }
    // The board refused the cycle's frames or stopped answering: a homing failure.
    say("ALARM:9");
    say(fmt::format("[MSG:homing: {}]", e.what()));
    say("ok");
    alarm_ = true;
    restart();
  }
}

void Engine::finish_homing() {
  const link::HomingResult r = homing_->result();
  homing_.reset();
  ++stats_.oks;
  if (!r.ok) {
    // grbl: the alarm, the `$H` line's ok, then a reset into the alarm state.
    say(fmt::format("ALARM:{}", r.alarm));
    say(fmt::format("[MSG:{}]", r.message));
    say("ok");
    alarm_ = true;
    restart();
    return;
  }
  for (const auto& h : r.axes) {
    const double spm = cfg_.steps_per_mm[h.axis];
    say(fmt::format("[MSG:Homed {} {}: switch latched at {} (step {}), set to {}]",
                    config::kAxisNames[h.axis], h.max_side ? "max" : "min",
                    fmt3(static_cast<double>(h.latched) / spm), h.latched,
                    fmt3(static_cast<double>(h.home) / spm)));
  }
  alarm_ = false;
  // A session with the machine's soft limits again (the board kept its MOTION rates).
  session_ = std::make_unique<link::V2Session>(link_, opt_.v2, ident_, rep_);
  session_->start();
  frontend::push_config_axes(*session_, ident_, cfg_);
  plan::Steps4 pos{};
  const auto& st = session_->last_status();
  for (size_t a = 0; a < 4 && a < st.position.size(); ++a) pos[a] = st.position[a];
  rebuild_pipeline(pos);
  say("ok");
}

int Engine::start_probe(const gcode::Probe& p) {
  la_ = std::make_unique<plan::Lookahead>(plan::motion_limits(cfg_));
  link::ProbeRequest req;
  for (size_t a = 0; a < 3; ++a) req.target_mm[a] = p.move.end[a];
  req.feed_mm_min = p.move.feed_mm_min;
  req.toward = p.toward();
  req.error_on_miss = p.error_on_miss();
  // The cycle's sessions: the board keeps its MOTION rates, CONFIG_AXIS timing and travel.
  probe_ =
      std::make_unique<link::ProbeCycle>(link_, cfg_, ident_, req, [this]() -> link::V2Session& {
        session_ = std::make_unique<link::V2Session>(link_, opt_.v2, ident_, rep_);
        session_->start();
        fifo_info_.clear();
        fifo_base_ = 0;
        return *session_;
      });
  probe_started_ = false;
  return kProbeStarted;
}

void Engine::continue_probe(milliseconds wait) {
  try {
    if (!probe_started_) {
      // grbl synchronizes first: the motion queued before the probe runs out, and every frame
      // of the session is acknowledged before the cycle's first session starts.
      session_->request_status();
      session_->poll(wait);
      if (!session_->complete()) return;
      probe_started_ = true;
    }
    if (probe_->step(wait)) finish_probe();
  } catch (const link::Error& e) {
    probe_.reset();
    disarm_next_ = true;
    if (session_->last_status().faults & v2::kFaultLimit) {
      on_session_error();  // a switch tripped: ALARM:1, lines wait for a reset
      return;
    }
    // The board refused the cycle's frames or stopped answering.
    say(fmt::format("[MSG:probe: {}]", e.what()));
    ++stats_.errors;
    say("error:20");
    new_session();
    plan::Steps4 pos{};
    const auto& st = session_->last_status();
    for (size_t a = 0; a < 4 && a < st.position.size(); ++a) pos[a] = st.position[a];
    resync_parser(pos);
  }
}

void Engine::finish_probe() {
  const link::ProbeResult r = probe_->result();
  probe_.reset();
  ++stats_.oks;
  if (r.alarm == 4) {
    say("ALARM:4");
    say(fmt::format("[MSG:{}]", r.message));
    alarm_ = true;
  } else {
    for (size_t a = 0; a < 3 && a < r.latched.size(); ++a)
      prb_mm_[a] = static_cast<double>(r.latched[a]) / cfg_.steps_per_mm[a];
    prb_ok_ = r.found;
    if (r.alarm) {
      say(fmt::format("ALARM:{}", r.alarm));
      say(fmt::format("[MSG:{}]", r.message));
      alarm_ = true;
    }
    say(prb_line());
  }
  say("ok");
  // The parser and the planner at the board's position (past the contact by the stop).
  plan::Steps4 pos{};
  const auto& st = session_->last_status();
  for (size_t a = 0; a < 4 && a < st.position.size(); ++a) pos[a] = st.position[a];
  resync_parser(pos);
}

std::string Engine::prb_line() const {
  const bool inches = settings_.values.at(13) != 0.0;
  const auto v = [&](double mm) { return inches ? fmt::format("{:.4f}", mm / 25.4) : fmt3(mm); };
  return fmt::format("[PRB:{},{},{}:{}]", v(prb_mm_[0]), v(prb_mm_[1]), v(prb_mm_[2]),
                     prb_ok_ ? 1 : 0);
}

void Engine::resync_parser(const plan::Steps4& steps) {
  std::vector<std::string> lines{modal_.units + " " + modal_.distance};
  // sync_to leaves G0 in force; G38.x alone sets the probe mode again.
  if (modal_.motion == "G1" || modal_.motion.rfind("G38", 0) == 0) lines.push_back(modal_.motion);
  frontend::sync_to(steps, cfg_, gcode::Dialect::kGrbl, *params_, *interp_, *planner_, lines);
}

void Engine::continue_reset() {
  if (estop_pressed_) {
    if (session_->last_status().faults & v2::kFaultEstop) {
      opt_.estop_release();
      estop_pressed_ = false;
    } else {
      session_->request_status();
      return;
    }
  }
  if (!session_->settled()) return;
  // The board runs out what it has (no e-stop): wait until STATUS says it is not busy.
  if (!reset_asked_) {
    reset_answers_ = session_->status_answers();
    reset_asked_ = true;
  }
  session_->request_status();
  if (session_->status_answers() == reset_answers_) return;
  if (session_->last_status().state & v2::kStateBusy) {
    reset_answers_ = session_->status_answers();
    return;
  }
  reset_asked_ = false;
  resetting_ = false;
  restart();
}

}  // namespace fpgacnc::grbl
