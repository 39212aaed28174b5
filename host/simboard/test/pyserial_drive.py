#!/usr/bin/env python3
"""Drive a fpgacnc board (real or simulated) with pyserial: send the original controller's init
and motion example (docs/protocol.md "v1", "Worked examples") and expect the ACK byte 0xAA within
TIMEOUT seconds of wall time (default 5: a real board ACKs after the move's 0.1 s; a simulated
board needs 5 million clocks of simulation for it, seconds on a loaded machine).

usage: pyserial_drive.py PORT [TIMEOUT]     exit status 0 on ACK, 1 otherwise
"""
import sys
import time

import serial  # Debian: python3-serial

INIT = bytes([0xFF, 0x01, 0x1E, 0x1A, 0x30, 0x01, 0x1E, 0x1A, 0x30])
MOTION = bytes([0x01, 0x00, 0x00, 0x01, 0x40, 0xFF, 0xFF, 0xFF, 0x60, 0x04, 0xB0])


def main():
    if len(sys.argv) not in (2, 3):
        print(__doc__.strip(), file=sys.stderr)
        return 1
    port = sys.argv[1]
    timeout = float(sys.argv[2]) if len(sys.argv) == 3 else 5.0
    with serial.Serial(port, 115200, bytesize=8, parity="N", stopbits=1, timeout=0.1) as s:
        s.reset_input_buffer()
        s.write(INIT + MOTION)
        s.flush()
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            b = s.read(1)
            if not b:
                continue
            if b[0] == 0xAA:
                print(f"{port}: ACK 0xAA received")
                return 0
            print(f"{port}: unexpected byte 0x{b[0]:02X}", file=sys.stderr)
    print(f"{port}: no ACK (0xAA) within {timeout:g} s", file=sys.stderr)
    return 1


if __name__ == "__main__":
    sys.exit(main())
