#!/usr/bin/env python3
"""End to end: a sequence of synthetic frames is encoded into one stream,
served over a pseudo-terminal at 115,200 baud to the client firmware on the
host-native board, and over TCP to the same firmware on the Cortex-M4 board
in QEMU. The CRC-32C of every frame each board displayed must equal the
encoder's own reconstruction (the client library's decode replayed on the
host): the client is bit-exact across architectures.

Usage: e2e_boards.py --vds VDS --host-board EXE --qemu QEMU --elf ELF --work DIR
       [--frames N] [--report FILE]"""
import argparse
import json
import os
import re
import socket
import subprocess
import sys
import time


def write_ppm(path, w, h, k):
    """A synthetic frame: moving gradients, a checkerboard and a disc."""
    px = bytearray()
    cx, cy, r = (w * (k + 2)) // 8, h // 2, h // 4
    for y in range(h):
        for x in range(w):
            checker = 255 if ((x + 4 * k) // 12 + y // 12) % 2 else 40
            inside = (x - cx) ** 2 + (y - cy) ** 2 < r * r
            px += bytes((255, 200, 30) if inside else ((x * 255) // w, checker, (y * 255) // h))
    with open(path, "wb") as f:
        f.write(b"P6\n%d %d\n255\n" % (w, h) + bytes(px))


def crcs_from(text):
    return [m.group(1) for m in re.finditer(r"^\s*frame\s+\d+\s+crc\s+([0-9a-f]{8})", text, re.M)]


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--vds", required=True)
    ap.add_argument("--host-board", required=True)
    ap.add_argument("--qemu", required=True)
    ap.add_argument("--elf", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--frames", type=int, default=4)
    ap.add_argument("--baud", type=int, default=115200)
    ap.add_argument("--inputs", nargs="*", default=[], help="images to use instead of synthetic frames")
    ap.add_argument("--report", default="")
    ap.add_argument("--timeout", type=float, default=240)
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    failures = []

    inputs = a.inputs
    if not inputs:
        for k in range(a.frames):
            p = os.path.join(a.work, f"src{k}.ppm")
            write_ppm(p, 240, 180, k)
            inputs.append(p)
    stream = os.path.join(a.work, "e2e.vds")
    crc_file = os.path.join(a.work, "encoder.crc")
    enc = subprocess.run([a.vds, "encode-frames", *inputs, "-o", stream, "--size", "240x180", "--quality", "60",
                          "--max-chunk", "1024", "--crc-out", crc_file], capture_output=True, text=True)
    print(enc.stdout + enc.stderr)
    if enc.returncode != 0:
        print("encode-frames failed")
        return 1
    want = open(crc_file).read().split()

    # Host-native board over a pseudo-terminal at the chosen baud.
    frames_dir = os.path.join(a.work, "host_frames")
    board = subprocess.Popen([a.host_board, "--uart", "pty-new", "--baud", str(a.baud), "--frames", frames_dir,
                              "--contact-sheet", os.path.join(a.work, "contact_sheet.png"),
                              "--y4m", os.path.join(a.work, "host.y4m")],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    line = board.stderr.readline()
    m = re.match(r"uart: (\S+)", line)
    if not m:
        board.kill()
        print("host board did not report its pty: " + line)
        return 1
    t0 = time.time()
    serve_host = subprocess.run([a.vds, "serve", stream, "--link", "pty:" + m.group(1), "--baud", str(a.baud),
                                 "--timeout", str(int(a.timeout))], capture_output=True, text=True)
    host_seconds = time.time() - t0
    try:
        out, err = board.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        board.kill()
        out, err = board.communicate()
        failures.append("host board did not exit after the stream")
    print("== vds serve over pty (host-native board)\n" + serve_host.stdout + serve_host.stderr)
    print("== host-native board\n" + out + err)
    host_crcs = crcs_from(serve_host.stdout)
    if serve_host.returncode != 0 or board.returncode != 0:
        failures.append(f"host board run failed (serve {serve_host.returncode}, board {board.returncode})")

    # Cortex-M4 board in QEMU, its UART0 on a TCP socket.
    port = free_port()
    qemu = subprocess.Popen([a.qemu, "-M", "mps2-an386", "-cpu", "cortex-m4", "-nographic", "-monitor", "none",
                             "-serial", f"tcp:127.0.0.1:{port},server=on,wait=on",
                             "-semihosting-config", "enable=on,target=native", "-icount", "shift=0",
                             "-kernel", a.elf], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    serve_qemu = None
    for _ in range(50):
        serve_qemu = subprocess.run([a.vds, "serve", stream, "--link", f"tcp:127.0.0.1:{port}", "--baud",
                                     str(a.baud), "--timeout", str(int(a.timeout))], capture_output=True, text=True)
        if "connection refused" not in (serve_qemu.stderr.lower()):
            break
        time.sleep(0.1)
    try:
        qout, qerr = qemu.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        qemu.kill()
        qout, qerr = qemu.communicate()
        failures.append("QEMU board did not exit after the stream")
    print("== vds serve over TCP (QEMU Cortex-M4 board)\n" + serve_qemu.stdout + serve_qemu.stderr)
    print("== QEMU board\n" + qout + qerr)
    qemu_crcs = crcs_from(serve_qemu.stdout)
    if serve_qemu.returncode != 0 or qemu.returncode != 0:
        failures.append(f"QEMU board run failed (serve {serve_qemu.returncode}, qemu {qemu.returncode})")

    print(f"encoder  : {' '.join(want)}")
    print(f"host     : {' '.join(host_crcs)}")
    print(f"cortex-m4: {' '.join(qemu_crcs)}")
    if host_crcs != want:
        failures.append("host-native board frame CRCs differ from the encoder's reconstruction")
    if qemu_crcs != want:
        failures.append("Cortex-M4 board frame CRCs differ from the encoder's reconstruction")
    if a.report:
        instr = re.findall(r"^\s*frame\s+(\d+)\s+crc\s+\S+\s+parse\s+(\d+)\s+decode\s+(\d+)\s+display\s+(\d+)",
                           serve_qemu.stdout, re.M)
        with open(a.report, "w") as f:
            json.dump({"stream_bytes": os.path.getsize(stream), "frames": len(want), "encoder_crcs": want,
                       "host_crcs": host_crcs, "qemu_crcs": qemu_crcs, "host_seconds": host_seconds,
                       "baud": a.baud, "qemu_instructions": [[int(v) for v in t] for t in instr],
                       "serve_host": serve_host.stdout, "serve_qemu": serve_qemu.stdout,
                       "qemu_log": qout + qerr}, f, indent=1)
    for f in failures:
        print("FAIL " + f)
    print("end-to-end: all boards agree with the encoder" if not failures else "end-to-end: FAILED")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
