#!/usr/bin/env python3
"""CTest cncjs_stream: the real CNCjs (npm package cncjs, pinned by package-lock.json here) streams
a corpus job into `fpgacnc grbl` on the twin board; the final MPos must be the job's end.

Usage: cncjs_stream.py FPGACNC INSTALL_DIR JOB CONFIG [DRIVER_OPTIONS...]
       cncjs_stream.py --install INSTALL_DIR   (only the install: CTest fixture cncjs_install)
  INSTALL_DIR  where CNCjs is installed (`npm ci` from this folder's lock file, once: kept while
               the lock file is unchanged); the CNCjs configuration and logs go to INSTALL_DIR/run
  JOB          the G-code file; CONFIG the machine configuration for both fpgacnc commands
  DRIVER_OPTIONS  passed to drive_cncjs.js (--reset, --pause; with either the front end's twin
                  board is paced by the wall clock: --realtime, 10 times the job's real pace
                  with --reset)

The expected end is the host planner's final position for the same file (`fpgacnc plan`, its
`final position:` line in steps and mm), computed without the grbl front end, the board or CNCjs;
MPos (the FPGA's step counters, as CNCjs received them) must match it within one step per axis.
No npm or no registry is a FAIL, not a skip. Wall-clock limits only catch a hung process.
"""
import hashlib
import os
import re
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
HANG = 900  # seconds: only a hung process takes this long (the job takes about 15 s here)


def fail(msg):
    print(f"FAIL: {msg}", flush=True)
    sys.exit(1)


def install(dest):
    """npm ci of this folder's package-lock.json into dest, unless that lock is installed there."""
    lock = os.path.join(HERE, "package-lock.json")
    with open(lock, "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()
    stamp = os.path.join(dest, ".installed-lock-sha256")
    if os.path.exists(stamp) and open(stamp).read().strip() == digest and \
            os.path.isdir(os.path.join(dest, "node_modules", "cncjs")):
        print(f"CNCjs already installed in {dest}")
        return
    for tool in ("node", "npm"):
        if shutil.which(tool) is None:
            fail(f"'{tool}' not found: install nodejs and npm (scripts/install-deps.sh)")
    os.makedirs(dest, exist_ok=True)
    if os.path.exists(stamp):
        os.remove(stamp)
    for name in ("package.json", "package-lock.json"):
        shutil.copyfile(os.path.join(HERE, name), os.path.join(dest, name))
    print(f"installing CNCjs into {dest} (npm ci from {lock})", flush=True)
    t0 = time.time()
    r = subprocess.run(["npm", "ci", "--no-audit", "--no-fund", "--omit=dev"], cwd=dest,
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=HANG)
    if r.returncode != 0:
        fail("npm ci could not install CNCjs (is the npm registry reachable from here?):\n" +
             r.stdout[-3000:])
    print(f"npm ci: {time.time() - t0:.1f} s", flush=True)
    # serialport's native bindings come prebuilt in the package (npm does not run install scripts)
    r = subprocess.run(["node", "-e", "require('@serialport/bindings-cpp')"], cwd=dest,
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=HANG)
    if r.returncode != 0:
        fail("@serialport/bindings-cpp does not load (CNCjs cannot open serial ports):\n" +
             r.stdout)
    with open(stamp, "w") as f:
        f.write(digest + "\n")


def planned_end(fpgacnc, job, config):
    """The planner's final position: per axis (mm, one step in mm) from `fpgacnc plan`."""
    r = subprocess.run([fpgacnc, "plan", job, "--config", config, "-q"], stdout=subprocess.PIPE,
                       stderr=subprocess.STDOUT, text=True, timeout=HANG)
    m = re.search(r"final position: steps X (-?\d+) Y (-?\d+) Z (-?\d+).*?"
                  r"; mm X (\S+) Y (\S+) Z (\S+)", r.stdout)
    if r.returncode != 0 or not m:
        fail(f"fpgacnc plan {job} gave no final position:\n{r.stdout}")
    return [float(m.group(i)) for i in (4, 5, 6)]


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--install":
        install(os.path.abspath(sys.argv[2]))
        print("PASS")
        return
    if len(sys.argv) < 5:
        fail("usage: cncjs_stream.py FPGACNC INSTALL_DIR JOB CONFIG [DRIVER_OPTIONS...]")
    fpgacnc, dest, job, config = (os.path.abspath(a) for a in sys.argv[1:5])
    extra = sys.argv[5:]
    install(dest)
    end = planned_end(fpgacnc, job, config)
    run = os.path.join(dest, "run")
    os.makedirs(run, exist_ok=True)
    settings = os.path.join(run, "grbl-settings.txt")
    if os.path.exists(settings):
        os.remove(settings)  # the configuration's values, whatever an earlier run left
    t0 = time.time()
    grbl_cmd = [fpgacnc, "grbl", "--config", config, "--settings", settings]
    if "--pause" in extra or "--reset" in extra:
        # The twin board at the job's real pace: the front end then holds CNCjs back by its
        # window, so the machine is still running at the pause or the soft reset however fast
        # this machine is (unpaced, the board can run the whole job before CNCjs's pause or
        # reset arrives: no Alarm after a reset at rest).
        grbl_cmd.append("--realtime")
        if "--reset" in extra:
            # 60 s of board time: 6 s a run. The reset follows CNCjs's 4 Hz status report that
            # shows Run (2.5 s of board time), long before the job's end.
            grbl_cmd += ["--speed", "10"]
    grbl = subprocess.Popen(grbl_cmd, stdout=subprocess.PIPE, text=True)
    try:
        pty = grbl.stdout.readline().strip()
        if not pty.startswith("/dev/"):
            fail(f"fpgacnc grbl printed '{pty}' instead of a pty path")
        print(f"fpgacnc grbl on {pty}; job {os.path.relpath(job)}; planned end {end}", flush=True)
        cmd = ["node", os.path.join(HERE, "drive_cncjs.js"), "--modules", dest, "--pty", pty,
               "--job", job, "--workdir", run] + extra
        try:
            r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                               timeout=HANG)
        except subprocess.TimeoutExpired:
            fail(f"drive_cncjs.js hung for {HANG} s")
        print(r.stdout, end="", flush=True)
        if r.returncode != 0:
            fail(f"drive_cncjs.js exited {r.returncode}")
        m = re.search(r"^final MPos (\S+) (\S+) (\S+)$", r.stdout, re.M)
        s = re.search(r"^steps/mm (\S+) (\S+) (\S+)$", r.stdout, re.M)
        if not m or not s:
            fail("drive_cncjs.js printed no final MPos / steps/mm")
        mpos = [float(m.group(i)) for i in (1, 2, 3)]
        step = [1.0 / float(s.group(i)) for i in (1, 2, 3)]
        for axis, got, want, tol in zip("XYZ", mpos, end, step):
            # MPos has 3 decimals: one step plus the rounding of the report
            if abs(got - want) > tol + 0.0005:
                fail(f"final MPos {axis} {got} != planned {want} "
                     f"(tolerance one step, {tol:.5f} mm)")
    finally:
        grbl.send_signal(2)
        try:
            out, _ = grbl.communicate(timeout=60)
            print(out.strip())
        except subprocess.TimeoutExpired:
            grbl.kill()
            print("fpgacnc grbl did not stop on SIGINT: killed")
    print(f"final MPos {mpos} = planned end {end} within one step; {time.time() - t0:.1f} s")
    print("PASS")


if __name__ == "__main__":
    main()
