#!/usr/bin/env python3
"""End to end: `fpgacnc stream`'s feed hold keys and SIGINT (README.md "Feed hold and overrides
while streaming") on the Verilated board (--model rtl), as an operator meets them.

Usage: stream_hold_keys.py FPGACNC WORKDIR
1. On a terminal (a pty as stdin and stdout): once the keys line is printed, '!' holds the job,
   'c' resumes it, Ctrl-C (SIGINT) holds again and asks; Enter resumes; the job must end with the
   device position equal to the plan ("device moved: ... matches the plan") and exit 0.
2. Without a terminal (stdin a pipe): SIGINT holds, then reports where the board is and stops
   with MOTION CANCEL (the board drops its queue at rest): exit status 1 with "job stopped by the
   operator", the position and the frames dropped.
Every step waits for the command's own line before the next key; timeouts only catch a hang (the
job is long in board time, so each key arrives while it runs however fast the machine is).
"""
import os
import pty
import re
import select
import signal
import subprocess
import sys
import time

FPGACNC, WORK = sys.argv[1], sys.argv[2]
HANG = 300.0
os.makedirs(WORK, exist_ok=True)
JOB = os.path.join(WORK, "hold-job.gcode")
with open(JOB, "w") as f:
    # 3 mm at 1800 mm/min: 0.1 s of board time per move (5 M clocks, seconds of simulation), far
    # more than the few thousand clocks a key takes to arrive.
    f.write("G21 G90 F1800\nG1 X3\nG1 X0 Y1\n")
CONFIG = os.path.join(WORK, "hold-machine.toml")
with open(CONFIG, "w") as f:
    # Holds and resumes ramp in 40 ms instead of the default 200 ms (less board time to simulate).
    f.write("hold_decel_mm_s2 = 5000.0\n")


def fail(msg, out):
    print(out.decode(errors="replace"))
    raise SystemExit(f"FAIL: {msg}")


def read_until(fd, out, pattern):
    end = time.time() + HANG
    while not re.search(pattern, out.decode(errors="replace")):
        if time.time() > end:
            fail(f"no {pattern!r}", out)
        r, _, _ = select.select([fd], [], [], 0.2)
        if r:
            try:
                chunk = os.read(fd, 4096)
            except OSError:
                chunk = b""
            if not chunk:
                fail(f"ended before {pattern!r}", out)
            out += chunk
    return out


# 1. A terminal.
pid, fd = pty.fork()
if pid == 0:
    os.execv(FPGACNC, [FPGACNC, "stream", JOB, "--model", "rtl", "--config", CONFIG])
out = read_until(fd, b"", r"keys: ! or space")
os.write(fd, b"!")
out = read_until(fd, out, r"feed hold \(~ or c resumes\)")
os.write(fd, b"c")
out = read_until(fd, out, r"\nresume")
os.kill(pid, signal.SIGINT)
out = read_until(fd, out, r"interrupt: feed hold")
out = read_until(fd, out, r"held at X [-\d.]+ Y [-\d.]+ Z [-\d.]+ mm, at rest on the path")
os.write(fd, b"\n")
out = read_until(fd, out, r"device moved: X 0 Y 160 Z 0 E 0 steps: matches the plan")
try:
    while os.read(fd, 4096):
        pass
except OSError:
    pass
_, status = os.waitpid(pid, 0)
if os.waitstatus_to_exitcode(status) != 0:
    fail(f"exit status {os.waitstatus_to_exitcode(status)} after a resumed job", out)
print("terminal: hold, resume, SIGINT hold and question, resume: the job ends on the plan")

# 2. No terminal.
p = subprocess.Popen([FPGACNC, "stream", JOB, "--model", "rtl", "--config", CONFIG], stdin=subprocess.PIPE,
                     stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
out = read_until(p.stdout.fileno(), b"", r"SIGINT: feed hold, then the job stops at rest")
p.send_signal(signal.SIGINT)
out = read_until(p.stdout.fileno(), out, r"no terminal to ask: stopping here")
rest, _ = p.communicate(timeout=HANG)
out += rest
if p.returncode != 1:
    fail(f"exit status {p.returncode} for a stopped job", out)
m = re.search(rb"job stopped by the operator; the device is at (X [-\d.]+ Y [-\d.]+ Z [-\d.]+ mm)"
              rb", at rest \((\d+) frames not sent, (\d+) dropped by the device: MOTION CANCEL\)",
              out)
if not m:
    fail("no stop report", out)
print(f"no terminal: SIGINT held at {m.group(1).decode()} and stopped")
print("PASS")
