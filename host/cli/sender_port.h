// The sender's side of a front end (`fpgacnc grbl`, `fpgacnc marlin`): a pseudo-terminal a
// sender opens, and what is still to be written to it.
#pragma once

#include <string>

namespace fpgacnc::cli {

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

}  // namespace fpgacnc::cli
