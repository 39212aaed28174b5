#!/usr/bin/env python3
"""`fpgacnc jog` and its Ctrl-C: a 50 mm jog at F600 on the twin board in real time (5 s of
machine time), SIGINT once it has started: the command must report the jog cancelled, stopped
short of the target (the board decelerates with its hold ramp and drops the jog), and exit 0.
The verdict does not depend on when the signal lands: any stop in [0, 50) mm passes, the whole
jog does not. Usage: jog_cancel.py FPGACNC"""
import re
import signal
import subprocess
import sys
import time


def main():
    fpgacnc = sys.argv[1]
    p = subprocess.Popen([fpgacnc, "jog", "X50", "--feed", "600", "--realtime"],
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    first = p.stdout.readline()  # the board's line: it is up
    if "simulated board" not in first:
        print(f"FAIL: unexpected first line {first!r}")
        return 1
    time.sleep(0.5)
    p.send_signal(signal.SIGINT)
    out, _ = p.communicate(timeout=600)
    print(first + out, end="")
    if p.returncode != 0:
        print(f"FAIL: exit status {p.returncode}")
        return 1
    m = re.search(r"jog cancelled at MPos X (-?[0-9.]+)", out)
    if not m:
        print("FAIL: no 'jog cancelled' report")
        return 1
    x = float(m.group(1))
    if not 0.0 <= x < 50.0:
        print(f"FAIL: stopped at X {x}, not short of the 50 mm target")
        return 1
    print(f"PASS: cancelled at X {x} mm")
    return 0


if __name__ == "__main__":
    sys.exit(main())
