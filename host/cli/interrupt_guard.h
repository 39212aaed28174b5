// SIGINT for the commands that move a machine (`stream`, `jog`): counted, acted on by the
// command's loop.
#pragma once

#include <signal.h>

#include <csignal>

namespace fpgacnc::cli {

inline volatile std::sig_atomic_t g_interrupts = 0;
inline void on_interrupt(int) {
  g_interrupts = g_interrupts + 1;
}

// SIGINT counted while the guard lives (the command acts on it: a controlled hold or a jog
// cancel, never an abrupt stop); the previous handler back after.
class InterruptGuard {
 public:
  InterruptGuard() {
    struct sigaction sa {};
    sa.sa_handler = on_interrupt;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = 0;  // no SA_RESTART: a question's read ends on a second interrupt
    ::sigaction(SIGINT, &sa, &old_);
    g_interrupts = 0;
  }
  ~InterruptGuard() { ::sigaction(SIGINT, &old_, nullptr); }
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
  // Interrupts since the last call.
  int take() {
    const int n = g_interrupts;
    g_interrupts = g_interrupts - n;
    return n;
  }

 private:
  struct sigaction old_ {};
};

}  // namespace fpgacnc::cli
