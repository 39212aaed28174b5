#!/usr/bin/env python3
"""The feed hold and cycle start buttons of `fpgacnc board --model rtl` pressed from outside
through its control socket (--control), seen by a protocol v2 client on the pty. Written from
docs/protocol.md ("The simulated board", STATUS) alone; the v2 framing is board_estop.py's
(standard library only).

usage: board_buttons.py FPGACNC        exit status 0 when every check passes, 1 otherwise

Checks:
  1. The board prints the control socket's path after the pty line; `state` answers with every
     button and the e-stop released; bad commands (an unknown word, a bad axis, a bad on/off, an
     extra word) are answered `error:` naming the bad word. That client disconnects; the next
     one connects (clients one after another).
  2. A long LINE runs; `hold` presses the hold button: STATUS shows HOLD (state bit 5) and then
     STOPPED (bit 6) with X short of the move's end; X stays put while the board's clock runs
     on for 5 000 000 clocks (0.1 s of board time, read from `state`), and the button's pin is
     released again by then.
  3. `start` presses cycle start: the move completes (DONE) at its planned position with HOLD and
     STOPPED clear.
  4. `estop on` / `estop off` show in STATUS (state bit 3); `limit x max on` shows in `state`,
     first at the pin and then, after the filter, in the core's filtered level.
  5. SIGTERM stops the board with status 0 and the socket file is gone.
  6. On the twin board (--model tlm) `hold` presses its button (answered ok with the press's
     edge and length); `estop on` is an error naming the twin board and --model rtl.
Every wait is for an answer, a printed line or the board's clock; the wall-clock limits only end
a hung run.
"""
import os
import queue
import re
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from board_estop import (ACK, DONE, HELLO, IDENT, STATUS, STATUS_QUERY, WAIT_S, Client,  # noqa: E402
                         Failed, Status, be, check, frame, line)

HOLD_BIT, STOPPED_BIT, BUSY_BIT = 0x20, 0x40, 0x01


class Control:
    """A client of the control socket: one command line, one answer line."""

    def __init__(self, path):
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.sock.settimeout(WAIT_S)
        self.sock.connect(path)
        self.buf = b""

    def ask(self, cmd):
        self.sock.sendall(cmd.encode() + b"\n")
        while b"\n" not in self.buf:
            chunk = self.sock.recv(4096)
            if not chunk:
                raise Failed(f"the control socket closed after '{cmd}'")
            self.buf += chunk
        k = self.buf.index(b"\n")
        answer = self.buf[:k].decode()
        self.buf = self.buf[k + 1:]
        print(f"  {cmd} -> {answer}")
        return answer

    def state(self):
        a = self.ask("state")
        if not a.startswith("ok "):
            raise Failed(f"state: {a}")
        return dict(kv.split("=", 1) for kv in a[3:].split() if "=" in kv)

    def close(self):
        self.sock.close()


def main():
    if len(sys.argv) != 2:
        print(__doc__.strip(), file=sys.stderr)
        return 1
    tmp = tempfile.mkdtemp(prefix="fpgacnc-buttons-")
    sock_path = os.path.join(tmp, "board.sock")
    board = subprocess.Popen([sys.argv[1], "board", "--model", "rtl", "--control", sock_path],
                             stdout=subprocess.PIPE)
    out = []
    lines = queue.Queue()

    def drain():
        """Reads the board's stdout all the time, so that its printing never blocks it."""
        for raw in board.stdout:
            s = raw.decode()
            out.append(s)
            lines.put(s.rstrip("\n"))
        lines.put(None)

    threading.Thread(target=drain, daemon=True).start()

    def read_line(pattern):
        """The next printed line matching pattern (the lines before it are skipped)."""
        deadline = time.monotonic() + WAIT_S
        while True:
            try:
                s = lines.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                s = None
            if s is None:
                raise Failed(f"the board never printed /{pattern}/")
            m = re.search(pattern, s)
            if m:
                return m

    try:
        m = read_line(r"^simulated board \(rtl\) on (/dev/pts/\d+) \((\d+) baud\)$")
        pty = m.group(1)
        m = read_line(r"^control socket: (.+)$")
        check(m.group(1) == sock_path and os.path.exists(sock_path),
              "the control socket's path is printed after the pty line and exists")

        # 1. state and bad commands, on a first connection.
        ctl = Control(sock_path)
        st = ctl.state()
        check(st.get("model") == "rtl" and st.get("hold") == "off" and st.get("start") == "off"
              and st.get("estop") == "off", "state: rtl, hold, start and e-stop released")
        for cmd, word in (("jump", "jump"), ("limit w min on", "w"), ("limit x middle on", "middle"),
                          ("estop maybe", "maybe"), ("hold now", "now")):
            a = ctl.ask(cmd)
            check(a.startswith("error: ") and f"'{word}'" in a,
                  f"'{cmd}' is answered by an error naming '{word}'")
        check(ctl.state().get("hold") == "off", "the bad commands pressed nothing")
        ctl.close()
        ctl = Control(sock_path)  # the next client, after the first has gone
        check(ctl.state().get("model") == "rtl", "a second client is served after the first")

        # 2. A long move on the pty, then the hold button.
        c = Client(pty)
        c.send(frame(0, HELLO))
        ident = c.await_type(IDENT)
        n_axes, clk_hz = ident[1], be(ident, 4, 4)
        check(ident[0] == 2 and n_axes >= 1, f"IDENT: version 2, N_AXES {n_axes}")

        def status():
            c.send(frame(0, STATUS_QUERY))
            return Status(c.await_type(STATUS), n_axes)

        def status_until(cond, what):
            """STATUS answers until cond(status) holds; a wall limit only ends a hung board."""
            deadline = time.monotonic() + WAIT_S
            s = status()
            while not cond(s):
                if time.monotonic() > deadline:
                    raise Failed(f"never: {what} (state 0x{s.state:02x}, X {s.pos[0]})")
                s = status()
            return s

        s0 = status()
        x0, seq = s0.pos[0], s0.next_seq
        # 2 000 steps over 0.3 s of board time; a hold stops within 0.1 s (the reset ramp).
        steps, t_clocks = 2000, 3 * clk_hz // 10
        c.send(line(seq, t_clocks, steps))
        c.await_type(ACK)
        running = status_until(lambda s: s.pos[0] != x0, "the move's first step")
        check(running.state & BUSY_BIT and not running.state & HOLD_BIT,
              f"the move runs ({running.pos[0] - x0} of {steps} steps), no hold")

        a = ctl.ask("hold")
        m = re.match(r"^ok hold pressed from clock edge (\d+) for (\d+) clocks \(released at "
                     r"edge (\d+)\)$", a)
        check(m is not None and int(m.group(3)) == int(m.group(1)) + int(m.group(2)),
              "hold: ok, the press's edges and length in board clocks")
        released_at = int(m.group(3))
        status_until(lambda s: s.state & HOLD_BIT, "STATUS HOLD after the hold button")
        print("ok: STATUS shows HOLD (state bit 5)")
        s = status_until(lambda s: s.state & STOPPED_BIT, "STATUS STOPPED after the hold")
        held = s.pos[0]
        check(s.state & HOLD_BIT and 0 < held - x0 < steps,
              f"STATUS shows STOPPED (state bit 6) with X short of the end ({held - x0} of "
              f"{steps} steps)")
        c0 = int(ctl.state()["cycle"])
        polls = 0
        deadline = time.monotonic() + WAIT_S
        while time.monotonic() < deadline:
            s = status()
            polls += 1
            if s.pos[0] != held or not s.state & STOPPED_BIT:
                raise Failed(f"X moved or the hold ended while held (X {s.pos[0] - x0}, state "
                             f"0x{s.state:02x})")
            st = ctl.state()
            if int(st["cycle"]) >= max(c0 + 5_000_000, released_at):
                break
        else:
            raise Failed(f"the board's clock did not run while held (cycle {st['cycle']})")
        print(f"ok: X stays at {held - x0} steps over {int(st['cycle']) - c0} board clocks "
              f"({polls} STATUS answers)")
        check(st["hold"] == "off", "the hold button's pin is released after its press")

        # 3. Cycle start.
        a = ctl.ask("start")
        check(a.startswith("ok start pressed from clock edge "), "start: ok")
        c.await_type(DONE)
        s = status_until(lambda s: not s.state & BUSY_BIT, "idle after the DONE")
        check(s.pos[0] == x0 + steps and s.done == (s0.done + 1) & 0xFFFFFFFF,
              f"after cycle start the move ends at its planned position (X +{steps}, one segment "
              f"done)")
        check(not s.state & (HOLD_BIT | STOPPED_BIT), "HOLD and STOPPED clear after the resume")

        # 4. The e-stop and a limit switch through the socket.
        check(ctl.ask("estop on").startswith("ok e-stop pressed at board cycle "), "estop on: ok")
        s = status()
        check(s.state & 0x08 and s.faults & 0x10 and ctl.state()["estop"] == "on",
              "estop on: STATUS state bit 3 and faults bit 4; state estop=on")
        check(ctl.ask("estop off").startswith("ok e-stop released"), "estop off: ok")
        s = status()
        check(not s.state & 0x08 and ctl.state()["estop"] == "off",
              "estop off: state bit 3 clear; state estop=off")
        check(ctl.ask("limit x max on").startswith("ok X max pressed from clock edge "),
              "limit x max on: ok")
        st = ctl.state()
        check(st["limit_pins"] == "x-max", "state: the X max pin is pressed")
        deadline = time.monotonic() + WAIT_S
        while st["limit_filtered"] != "x-max" and time.monotonic() < deadline:
            st = ctl.state()  # the board's clock runs through the filter without host traffic
        check(st["limit_filtered"] == "x-max", "state: the core's filtered X max level follows")
        check(ctl.ask("limit x max off").startswith("ok X max released"), "limit x max off: ok")
        ctl.close()

        # 5. Stop.
        board.send_signal(signal.SIGTERM)
        read_line(r"^stopped by SIGTERM$")
        board.wait(timeout=WAIT_S)
        check(board.returncode == 0, "the board exits with status 0 on SIGTERM")
        check(not os.path.exists(sock_path), "the control socket is removed at exit")

        # 6. The twin board has the buttons but no e-stop input: a clear error.
        tb = subprocess.Popen([sys.argv[1], "board", "--model", "tlm", "--control", sock_path],
                              stdin=subprocess.DEVNULL, stdout=subprocess.PIPE)
        try:
            # The socket exists before the board prints its lines; the second one is enough.
            for _ in range(2):
                if not tb.stdout.readline():
                    raise Failed("the twin board exited before printing its control socket")
            ctl = Control(sock_path)
            a = ctl.ask("hold")
            check(re.match(r"^ok hold pressed from clock edge \d+ for 200000 clocks", a)
                  is not None, f"tlm: hold presses the button ({a!r})")
            a = ctl.ask("estop on")
            check(a.startswith("error: estop: ") and "twin board" in a and "--model rtl" in a,
                  "tlm: estop is answered by an error naming the twin board and --model rtl")
            check(ctl.state().get("model") == "tlm", "tlm: state answers")
            ctl.close()
        finally:
            tb.send_signal(signal.SIGTERM)
            tb.wait(timeout=WAIT_S)
        check(tb.returncode == 0 and not os.path.exists(sock_path),
              "tlm: exits with status 0 on SIGTERM and removes its socket")
        return 0
    except (Failed, OSError) as e:
        print(f"FAILED: {e}", file=sys.stderr)
        print("board output:\n" + "".join(out), file=sys.stderr)
        return 1
    finally:
        if board.poll() is None:
            board.kill()
            board.wait()
        if os.path.exists(sock_path):
            os.unlink(sock_path)
        os.rmdir(tmp)


if __name__ == "__main__":
    sys.exit(main())
