#!/usr/bin/env python3
"""`fpgacnc marlin` through its real pty, as a printer host uses it: waits for "start", sends
numbered, checksummed lines (one corrupted on purpose: the front end must ask for it again with
Resend), M105, a move, M400 and M114. Prints PASS or FAIL: why. Usage: marlin_pty_e2e.py FPGACNC"""
import os
import select
import subprocess
import sys
import termios
import time
import tty


def checksum(s):
    x = 0
    for c in s.encode():
        x ^= c
    return x


def numbered(n, cmd):
    body = f"N{n} {cmd}"
    return f"{body}*{checksum(body)}"


def main():
    exe = sys.argv[1]
    proc = subprocess.Popen([exe, "marlin"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        path = proc.stdout.readline().strip()
        fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
        tty.setraw(fd)
        buf = b""

        def line(timeout=30.0):
            nonlocal buf
            end = time.monotonic() + timeout
            while b"\n" not in buf:
                left = end - time.monotonic()
                if left <= 0:
                    raise RuntimeError(f"no answer (have {buf!r})")
                r, _, _ = select.select([fd], [], [], left)
                if r:
                    buf += os.read(fd, 4096)
            l, buf = buf.split(b"\n", 1)
            return l.decode().strip()

        def until_ok(cmd):
            os.write(fd, (cmd + "\n").encode())
            out = []
            while True:
                out.append(line())
                if out[-1].startswith("ok"):
                    return out

        while line() != "start":
            pass
        a = until_ok(numbered(0, "M110 N0"))
        if a[-1] != "ok":
            raise RuntimeError(f"M110: {a}")
        prog = ["G21", "G90", "G1 X2 Y1 F3000", "G1 X4 Y3"]
        n, resent, corrupted = 0, 0, False
        while n < len(prog):
            wire = numbered(n + 1, prog[n])
            if n == 2 and not corrupted:
                wire = wire.replace("X2", "X7")
                corrupted = True
            ans = until_ok(wire)
            r = [a for a in ans if a.startswith("Resend:")]
            if r:
                n = int(r[0].split(":")[1]) - 1
                resent += 1
            else:
                n += 1
        if resent != 1:
            raise RuntimeError(f"expected one Resend, got {resent}")
        t = until_ok("M105")
        if not t[-1].startswith("ok T:") or " B:" not in t[-1] or " @:" not in t[-1]:
            raise RuntimeError(f"M105: {t}")
        until_ok("M400")
        p = until_ok("M114")
        if p[0] != "X:4.00 Y:3.00 Z:0.00 E:0.00 Count X:640 Y:480 Z:0":
            raise RuntimeError(f"M114: {p}")
        print("PASS")
        return 0
    except Exception as e:  # noqa: BLE001
        print(f"FAIL: {e}")
        return 1
    finally:
        proc.terminate()
        proc.wait(timeout=30)


if __name__ == "__main__":
    sys.exit(main())
