#!/usr/bin/env python3
"""End to end: `fpgacnc grbl` as a sender meets it, through its real pty and its TCP port.

Usage: grbl_pty_e2e.py FPGACNC SETTINGS_FILE
The first stdout line is the pty path, the second the TCP address (--listen tcp:127.0.0.1:0).
A short job is streamed send-response through the pty and `?` polled until Idle; the final MPos
must be the job's end. Then the same through TCP (the server serves one sender at a time).
Timeouts only catch a hang: the verdict never depends on how fast the machine is.
"""
import os
import re
import select
import socket
import subprocess
import sys
import time
import tty

FPGACNC, SETTINGS = sys.argv[1], sys.argv[2]
JOB = ["G21 G90", "G1 X10 Y5 F3000", "G2 X20 Y5 I5 J0", "G0 Z2", "G0 X12.5 Y-3.25"]
END = (12.5, -3.25, 2.0)
HANG = 120.0  # seconds of wall time before a missing answer is a failure


class Sender:
    def __init__(self, read, write):
        self.read, self.write, self.buf = read, write, b""

    def line(self):
        end = time.time() + HANG
        while b"\n" not in self.buf:
            if time.time() > end:
                raise SystemExit(f"FAIL: no answer (have {self.buf!r})")
            chunk = self.read(0.05)
            if chunk:
                self.buf += chunk
        l, self.buf = self.buf.split(b"\n", 1)
        return l.decode().rstrip("\r")

    def until(self, pred):
        while True:
            l = self.line()
            if l and pred(l):
                return l

    def command(self, text):
        self.write(text.encode() + b"\n")
        return self.until(lambda l: l == "ok" or l.startswith("error:"))

    def status(self):
        self.write(b"?")
        return self.until(lambda l: l.startswith("<"))


def run_job(s, where):
    banner = s.until(lambda l: l.startswith("Grbl"))
    assert banner == "Grbl 1.1h ['$' for help]", banner
    assert s.command("$I") == "ok"
    for l in JOB:
        a = s.command(l)
        assert a == "ok", f"{where}: {l} -> {a}"
    end = time.time() + HANG
    while True:
        r = s.status()
        m = re.match(r"<(\w+)\|MPos:([-\d.]+),([-\d.]+),([-\d.]+)", r)
        assert m, r
        if m.group(1) == "Idle":
            break
        assert time.time() < end, f"{where}: not idle: {r}"
        time.sleep(0.05)
    pos = tuple(float(m.group(i)) for i in (2, 3, 4))
    assert all(abs(a - b) < 0.001 for a, b in zip(pos, END)), f"{where}: MPos {pos} != {END}"
    print(f"{where}: {len(JOB)} lines ok, final MPos {pos}")


if os.path.exists(SETTINGS):
    os.remove(SETTINGS)  # the machine's defaults, whatever an earlier run left
proc = subprocess.Popen([FPGACNC, "grbl", "--settings", SETTINGS, "--listen", "tcp:127.0.0.1:0"],
                        stdout=subprocess.PIPE, text=True)
try:
    pty_path = proc.stdout.readline().strip()
    tcp_line = proc.stdout.readline().strip()
    assert pty_path.startswith("/dev/"), pty_path
    m = re.match(r"grbl on tcp (\S+):(\d+)$", tcp_line)
    assert m, tcp_line
    fd = os.open(pty_path, os.O_RDWR | os.O_NOCTTY)
    tty.setraw(fd)

    def pty_read(t):
        r, _, _ = select.select([fd], [], [], t)
        return os.read(fd, 4096) if r else b""

    run_job(Sender(pty_read, lambda b: os.write(fd, b)), "pty")
    os.close(fd)
    sock = socket.create_connection((m.group(1), int(m.group(2))), timeout=HANG)

    def tcp_read(t):
        r, _, _ = select.select([sock], [], [], t)
        return sock.recv(4096) if r else b""

    # The machine is at END already: the job's moves to the same targets end there again.
    run_job(Sender(tcp_read, sock.sendall), "tcp")
    sock.close()
finally:
    proc.send_signal(2)
    out, _ = proc.communicate(timeout=HANG)
    print(out.strip())
print("PASS")
