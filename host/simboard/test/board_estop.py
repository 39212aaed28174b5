#!/usr/bin/env python3
"""The e-stop of `fpgacnc board --model rtl` pressed and released from outside (SIGUSR1 /
SIGUSR2), seen by a protocol v2 client written from docs/protocol.md alone (its own CRC, framing
and field offsets; standard library only).

usage: board_estop.py FPGACNC        exit status 0 when every check passes, 1 otherwise

Checks (docs/protocol.md "E-stop" and "The simulated board"):
  1. IDENT gives N_AXES; STATUS shows no e-stop (state bit 3, faults bit 4 clear).
  2. A long LINE runs (STATUS shows its first steps); SIGUSR1 presses the e-stop: STATUS shows
     state bit 3 and faults bit 4, the board idle (state bit 0 clear) with an empty FIFO, X short
     of the move's end and no longer moving, and no DONE for the move (segments done unchanged).
  3. A LINE sent while the e-stop is latched is ACKed but not executed.
  4. SIGUSR2 releases it: state bit 3 clears, faults bit 4 stays latched until FAULT_CLEAR.
  5. After FAULT_CLEAR a LINE runs to its end (DONE, X advanced by its steps).
Every wait is for an answer or a printed line; the wall-clock limits only end a hung run.
"""
import os
import re
import select
import signal
import subprocess
import sys
import time
import tty

SYNC = 0xA5
HELLO, STATUS_QUERY, FAULT_CLEAR, LINE = 0x01, 0x02, 0x03, 0x10
ACK, NAK, DONE, STATUS, IDENT = 0x80, 0x81, 0x82, 0x83, 0x84
WAIT_S = 300.0  # a hung board, not a slow one: the checks never depend on how long a wait took


def crc16(data):
    """CRC-16/CCITT-FALSE: polynomial 0x1021, initial 0xFFFF, no reflection, no final XOR."""
    crc = 0xFFFF
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else (crc << 1)
            crc &= 0xFFFF
    return crc


def frame(seq, typ, payload=b""):
    body = bytes([len(payload), seq, typ]) + payload
    c = crc16(body)
    return bytes([SYNC]) + body + bytes([c >> 8, c & 0xFF])


def line(seq, t_clocks, x_steps):
    """LINE, code 0 (no laser), int32 steps for axis 0 only (k = 1)."""
    return frame(seq, LINE, bytes([0x00, 0x00]) + t_clocks.to_bytes(4, "big") +
                 x_steps.to_bytes(4, "big", signed=True))


class Failed(Exception):
    pass


def check(cond, what):
    if not cond:
        raise Failed(what)
    print(f"ok: {what}")


class Client:
    def __init__(self, path):
        self.fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
        tty.setraw(self.fd)
        self.buf = bytearray()

    def send(self, data):
        os.write(self.fd, data)

    def next_frame(self, deadline):
        """The next device frame with a good CRC (type, payload); resyncs on 0xA5."""
        while True:
            while self.buf and self.buf[0] != SYNC:
                del self.buf[0]
            if len(self.buf) >= 6 and len(self.buf) >= 6 + self.buf[1]:
                n = self.buf[1]
                f = bytes(self.buf[:6 + n])
                if crc16(f[1:4 + n]) == (f[4 + n] << 8 | f[5 + n]):
                    del self.buf[:6 + n]
                    return f[3], f[4:4 + n]
                del self.buf[0]
                continue
            left = deadline - time.monotonic()
            if left <= 0:
                raise Failed("no answer from the board")
            r, _, _ = select.select([self.fd], [], [], left)
            if r:
                self.buf += os.read(self.fd, 4096)

    def await_type(self, typ, seen=None):
        deadline = time.monotonic() + WAIT_S
        while True:
            t, p = self.next_frame(deadline)
            if seen is not None:
                seen.append((t, p))
            if t == typ:
                return p
            if t == NAK:
                raise Failed(f"NAK seq {p[0]} reason {p[1]}")


def be(p, off, n, signed=False):
    return int.from_bytes(p[off:off + n], "big", signed=signed)


class Status:
    def __init__(self, p, n_axes):
        self.state, self.faults = p[0], p[1]
        self.level, self.next_seq, self.done = be(p, 2, 2), p[4], be(p, 5, 4)
        self.pos = [be(p, 9 + 4 * a, 4, signed=True) for a in range(n_axes)]


def main():
    if len(sys.argv) != 2:
        print(__doc__.strip(), file=sys.stderr)
        return 1
    board = subprocess.Popen([sys.argv[1], "board", "--model", "rtl"], stdout=subprocess.PIPE)
    out = []
    pending = bytearray()  # the board's stdout read so far and not yet split into lines

    def read_line(pattern):
        """The next printed line matching pattern (the lines before it are skipped)."""
        deadline = time.monotonic() + WAIT_S
        while True:
            while b"\n" in pending:
                k = pending.index(b"\n")
                s = pending[:k].decode()
                del pending[:k + 1]
                out.append(s + "\n")
                m = re.search(pattern, s)
                if m:
                    return m
            left = deadline - time.monotonic()
            r = select.select([board.stdout], [], [], left)[0] if left > 0 else []
            chunk = os.read(board.stdout.fileno(), 4096) if r else b""
            if not chunk:
                raise Failed(f"the board never printed /{pattern}/")
            pending.extend(chunk)

    try:
        m = read_line(r"^simulated board \(rtl\) on (/dev/pts/\d+) \((\d+) baud\)$")
        read_line(r"SIGUSR1 presses the e-stop, SIGUSR2 releases it")
        c = Client(m.group(1))

        c.send(frame(0, HELLO))
        ident = c.await_type(IDENT)
        n_axes, clk_hz = ident[1], be(ident, 4, 4)
        check(ident[0] == 2 and n_axes >= 1, f"IDENT: version 2, N_AXES {n_axes}")

        def status():
            c.send(frame(0, STATUS_QUERY))
            return Status(c.await_type(STATUS), n_axes)

        s0 = status()
        check(not s0.state & 0x08 and not s0.faults & 0x10, "STATUS before: no e-stop")
        x0, seq = s0.pos[0], s0.next_seq

        # A long move (4 000 steps over 10 s of board time), then the e-stop while it runs.
        steps = 4000
        c.send(line(seq, 10 * clk_hz, steps))
        c.await_type(ACK)
        seq = (seq + 1) & 0xFF
        running = status()
        while running.pos[0] == x0:  # until the move has made a step (board clocks, not wall time)
            running = status()
        check(running.state & 0x01 and 0 < running.pos[0] - x0 < steps,
              f"the move runs ({running.pos[0] - x0} of {steps} steps)")
        board.send_signal(signal.SIGUSR1)
        read_line(r"^e-stop pressed at board cycle \d+$")
        seen = []
        c.send(frame(0, STATUS_QUERY))
        s1 = Status(c.await_type(STATUS, seen), n_axes)
        check(s1.state & 0x08 and s1.faults & 0x10,
              "SIGUSR1: STATUS state bit 3 (e-stop active) and faults bit 4 (latched)")
        check(not s1.state & 0x01 and s1.level == 0, "e-stop: board idle, command FIFO empty")
        check(s1.pos[0] - x0 < steps, f"e-stop: X stopped short of the move ({s1.pos[0] - x0} "
              f"of {steps} steps)")
        check(status().pos == s1.pos, "e-stop: no step after the stop (the next STATUS agrees)")
        check(s1.done == s0.done and all(t != DONE for t, _ in seen),
              "e-stop: the aborted move is not counted (no DONE)")

        # While latched: ACKed, not executed.
        c.send(line(seq, clk_hz // 100, 100))
        c.await_type(ACK)
        seq = (seq + 1) & 0xFF
        s2 = status()
        check(s2.pos == s1.pos and s2.done == s1.done and s2.level == 0,
              "LINE while latched: ACKed, discarded (position and segments done unchanged)")

        board.send_signal(signal.SIGUSR2)
        read_line(r"^e-stop released at board cycle \d+$")
        s3 = status()
        check(not s3.state & 0x08 and s3.faults & 0x10,
              "SIGUSR2: state bit 3 clear, faults bit 4 still latched")

        c.send(frame(seq, FAULT_CLEAR))
        c.await_type(ACK)
        seq = (seq + 1) & 0xFF
        s4 = status()
        check(not s4.faults & 0x10, "FAULT_CLEAR after the release clears faults bit 4")

        c.send(line(seq, clk_hz // 100, 100))
        c.await_type(ACK)
        c.await_type(DONE)
        s5 = status()
        while s5.state & 0x01:  # DONE may precede the last clocks of the segment's bookkeeping
            s5 = status()
        check(s5.pos[0] == s4.pos[0] + 100 and s5.done == (s4.done + 1) & 0xFFFFFFFF,
              "a LINE after the release runs to its end (X +100, segments done +1)")

        board.send_signal(signal.SIGTERM)
        read_line(r"^stopped by SIGTERM$")
        board.wait(timeout=WAIT_S)
        check(board.returncode == 0, "the board exits with status 0 on SIGTERM")
        return 0
    except Failed as e:
        print(f"FAILED: {e}", file=sys.stderr)
        print("board output:\n" + "".join(out), file=sys.stderr)
        return 1
    finally:
        if board.poll() is None:
            board.kill()
            board.wait()


if __name__ == "__main__":
    sys.exit(main())
