// The two sides of a front end (`fpgacnc grbl`, `fpgacnc marlin`): the sender's (a
// pseudo-terminal a sender opens, and what is still to be written to it) and the FPGA's (a real
// port or a simulated board, chosen by the same options in both commands).
#pragma once

#include <CLI/CLI.hpp>
#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fpgacnc/config/machine.h"
#include "fpgacnc/link/link.h"

namespace fpgacnc::cli {

// Where the FPGA is: --port, else the simulated board of --model (tlm: the twins, rtl: the
// Verilated cnc_core); --realtime paces the twin board to the wall clock.
struct BoardChoice {
  std::string port;
  std::string model = "tlm";
  bool realtime = false;
  double speed = 1.0;                 // with realtime: simulated seconds per wall second
  std::vector<std::string> endstops;  // --endstop (rtl): simulated endstops
  std::string limit_switches;         // --limit-switches (--port): the switches the board wires
  std::string probe_plate;            // --probe-plate (rtl): a simulated probe plate
};
// Adds --port, --model (with `model_help`), --endstop, --probe-plate and --limit-switches to a
// front end's subcommand.
void add_board_options(CLI::App* sub, BoardChoice& choice, const std::string& model_help);

// The FPGA behind a front end, opened.
struct BoardBehind {
  std::unique_ptr<link::Link> link;
  std::string description;  // "/dev/ttyUSB0", "the simulated board (tlm)", "... (rtl)"
  bool rtl = false;         // the Verilated board (its heaters' plants and e-stop are modelled)
  // Press / release the board's e-stop; empty where the board has no e-stop input (tlm, a port).
  std::function<void()> estop_press, estop_release;
  // The board's limit switches (simboard::Board::limit_switches; 0 for tlm and a port).
  uint16_t limit_switches = 0;
  // The operator pulls the carriages off their simulated endstops (rtl with --endstop; SIGHUP).
  std::function<void()> pull_off;
  // The board has the probe input and the trigger (rtl, a port; not the twin board).
  bool probe = false;
};
// Opens the board of `choice` (throws std::invalid_argument for --realtime without tlm, and for
// --endstop or --probe-plate without rtl).
BoardBehind open_board_behind(const config::MachineConfig& cfg, const BoardChoice& choice);

// A sender's end: the pty master or a TCP connection, with what is still to be written.
struct Peer {
  int fd = -1;
  bool connected = false;
  std::string pending;
};

void set_nonblocking(int fd);
// A new pty, raw and 8-bit clean at 115200; `path` gets its slave's path. No slave is kept open
// here, so POLLHUP on the returned master tells whether a sender has it open. Throws
// std::runtime_error naming the call that failed.
int open_sender_pty(std::string& path);
// Writes what it can of p.pending (non-blocking).
void flush_peer(Peer& p);
// Whether a sender has the pty of `master` open now.
bool sender_present(int master);
// Follows whether a sender has the pty open (connected, pending cleared on close) and says when
// to greet it: 100 ms after it opened the port, once it has set the port up (termios, flushes),
// as a board's banner comes after the reset that opening its port causes.
class SenderWatch {
 public:
  // Call once per loop; true in the one call where the banner is due.
  bool poll(Peer& pty);
  bool banner_pending() const { return banner_at_.has_value(); }

 private:
  std::optional<std::chrono::steady_clock::time_point> banner_at_;
};

// Where the senders connect: the pty (unless --no-pty) and --listen tcp:HOST:PORT.
struct SenderChoice {
  std::string listen;
  bool no_pty = false;
};
// Adds --listen and --no-pty to a front end's subcommand.
void add_sender_options(CLI::App* sub, SenderChoice& choice);
// Throws std::invalid_argument naming `command` for --no-pty without --listen.
void check_sender_choice(const SenderChoice& choice, const std::string& command);

// "tcp:HOST:PORT" -> a listening socket (non-blocking); `where` gets the bound address
// ("127.0.0.1:5123", PORT 0: the port chosen). Throws std::invalid_argument for a malformed
// spec or an unknown host, std::runtime_error when it cannot listen.
int listen_tcp(const std::string& spec, std::string& where);

// The senders' side of a front end: its pty (unless none) and, with a listen spec, a TCP
// listener whose one connection at a time is a second sender (a new one replaces it). Every
// answer goes to every connected sender.
class SenderSide {
 public:
  // Opens the pty (unless no_pty) and the listener (listen: "" or tcp:HOST:PORT); throws as
  // open_sender_pty() and listen_tcp().
  explicit SenderSide(const SenderChoice& choice);
  ~SenderSide();
  SenderSide(const SenderSide&) = delete;
  SenderSide& operator=(const SenderSide&) = delete;
  const std::string& pty_path() const { return pty_path_; }  // "" without a pty
  const std::string& tcp_where() const { return where_; }    // "" without a listener
  // Waits up to `timeout_ms` (less while a banner is due) for a sender's bytes or connection;
  // calls `opened(peer)` when a sender has opened the pty (banner time, SenderWatch) or a TCP
  // client was accepted, and `received(bytes)` for what senders wrote.
  void poll(int timeout_ms, const std::function<void(Peer&)>& opened,
            const std::function<void(std::string_view)>& received);
  // Queues `out` to every connected sender and writes what it can.
  void send(const std::string& out);

 private:
  Peer pty_, tcp_;
  int listen_fd_ = -1;
  std::string pty_path_, where_;
  SenderWatch watch_;
};

// SIGINT and SIGTERM end serve() (SIGPIPE is ignored: a sender that goes away is seen by poll);
// SIGHUP is taken as a pull-off request (take_hangup()).
void stop_on_signals();
bool stop_requested();
bool take_hangup();

// A front end's loop until SIGINT or SIGTERM: the senders' bytes to the engine, the engine
// stepped (waiting up to 5 ms for the board while it is busy, else for the senders up to 20 ms),
// its output to every sender. `opened(peer)` greets a sender that opened the port; `hangup`
// runs on SIGHUP (BoardBehind::pull_off).
template <typename Engine>
void serve(SenderSide& senders, Engine& engine, const std::function<void(Peer&)>& opened,
           const std::function<void()>& hangup = {}) {
  stop_on_signals();
  while (!stop_requested()) {
    if (take_hangup() && hangup) hangup();
    senders.poll(engine.busy() ? 0 : 20, opened,
                 [&](std::string_view bytes) { engine.receive(bytes); });
    engine.step(std::chrono::milliseconds(engine.busy() ? 5 : 0));
    senders.send(engine.take_output());
  }
}

}  // namespace fpgacnc::cli
