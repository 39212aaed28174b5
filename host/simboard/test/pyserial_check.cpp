// Starts a simulated board in its own thread and runs test/pyserial_drive.py (a pyserial client,
// Debian python3-serial, run with /usr/bin/python3 when present) on its pty path; exits with the
// script's status (0: the board answered the original example with 0xAA).
#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>

#include "fpgacnc/simboard/sim_board.h"

extern char** environ;

int main() {
  try {
    fpgacnc::simboard::SimBoard board;
    board.start();
    // The system interpreter has Debian's python3-serial; a python3 first on PATH may not.
    const char* python = ::access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3";
    std::string script = PYSERIAL_SCRIPT;
    std::string path = board.path();
    // The pyserial client is a plain serial client with a wall-clock timeout of its own (no
    // board clock): 600 s for the 5 million clocks the move takes, a safety net far above the
    // 2-7 s it needs at 0.7-2 M clocks/s.
    std::string timeout = "600";
    char* argv[] = {const_cast<char*>(python), script.data(), path.data(), timeout.data(), nullptr};
    pid_t pid = 0;
    if (::posix_spawnp(&pid, python, nullptr, nullptr, argv, environ) != 0) {
      fmt::print(stderr, "cannot run {}\n", python);
      return 1;
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    board.wait_quiet(std::chrono::milliseconds(2000));
    board.stop();
    fmt::print("{}\n", board.stats_line());
    const auto n = board.net_steps();
    fmt::print("net steps from edges: X {} Y {}\n", n[0], n[1]);
    const int rc = WIFEXITED(status) ? WEXITSTATUS(status) : 1;
    if (rc == 0 && (n[0] != 320 || n[1] != -160)) {
      fmt::print(stderr, "edges do not show 320 X / -160 Y steps\n");
      return 1;
    }
    fmt::print("pyserial client exit status {}\n", rc);
    return rc;
  } catch (const std::exception& e) {
    fmt::print(stderr, "{}\n", e.what());
    return 1;
  }
}
