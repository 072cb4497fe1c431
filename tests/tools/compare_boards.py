#!/usr/bin/env python3
"""Runs one firmware program on the host board and on the Cortex-M4 board in
QEMU (mps2-an386, -icount shift=0, semihosting) and requires identical
"check" lines: the client library is bit-exact across architectures. Also
requires both to exit 0 and prints the QEMU board's "count" lines."""
import argparse
import subprocess
import sys


def qemu_cmd(qemu, elf):
    return [qemu, "-M", "mps2-an386", "-cpu", "cortex-m4", "-nographic", "-monitor", "none",
            "-serial", "null", "-semihosting-config", "enable=on,target=native",
            "-icount", "shift=0", "-kernel", elf]


def lines(kind, out):
    return [l.strip() for l in out.splitlines() if l.strip().startswith(kind + " ")]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--host", required=True)
    ap.add_argument("--qemu", required=True)
    ap.add_argument("--elf", required=True)
    ap.add_argument("--timeout", type=float, default=120)
    a = ap.parse_args()

    host = subprocess.run([a.host], capture_output=True, text=True, timeout=a.timeout)
    try:
        arm = subprocess.run(qemu_cmd(a.qemu, a.elf), capture_output=True, text=True, timeout=a.timeout)
    except subprocess.TimeoutExpired:
        print(f"QEMU board did not finish within {a.timeout} s")
        return 1
    print("host board:\n" + host.stdout)
    # QEMU prints the semihosting console on stderr.
    arm_out = arm.stdout + arm.stderr
    print("Cortex-M4 board (QEMU):\n" + arm_out)
    ok = True
    if host.returncode != 0:
        print(f"host board exited {host.returncode}")
        ok = False
    if arm.returncode != 0:
        print(f"QEMU board exited {arm.returncode}")
        ok = False
    h, m = lines("check", host.stdout), lines("check", arm_out)
    if not h:
        print("host board printed no check lines")
        ok = False
    if h != m:
        print("check lines differ between the boards:")
        n = max(len(h), len(m))
        for x, y in zip(h + [""] * (n - len(h)), m + [""] * (n - len(m))):
            if x != y:
                print(f"  host: {x!r}\n  qemu: {y!r}")
        ok = False
    # The instruction counter must measure a known loop to within its
    # resolution plus the few instructions of the two reads.
    for l in lines("count", arm_out):
        f = l.split()
        if f[1] == "calibration_loop":
            measured, expected, res = int(f[3]), int(f[5]), int(f[7])
            if abs(measured - expected) > 2 * res + 64:
                print(f"instruction counter off: measured {measured}, expected {expected}")
                ok = False
    print("boards agree" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
