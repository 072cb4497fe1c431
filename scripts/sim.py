#!/usr/bin/env python3
"""Plays a vds stream on a simulated client in one command: starts the
client firmware on the chosen board, connects the link and runs `vds serve`.

  host   the firmware as an ordinary process (boards/host); its UART is a new
         pseudo-terminal, paced at --baud on both sides; it writes the frames
         it displays as PNGs, a Y4M video (and an MP4 when ffmpeg is there)
         and a contact sheet;
  qemu   the Cortex-M4 firmware in qemu-system-arm -M mps2-an386 with
         -icount shift=0; UART0 is a TCP socket that `vds serve` paces at
         --baud (QEMU does not); the frame records carry the instruction
         counts of every frame.

Usage: scripts/sim.py --board host|qemu STREAM [--build build/host-release]
       [--baud 115200] [--out DIR] [--window] [--timeout S]
Exit status: 0 when the client displayed the whole stream and reported it
intact, 1 otherwise, 2 for usage errors."""
import argparse
import os
import re
import shutil
import socket
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def frame_crcs(serve_stdout):
    """The CRC of every frame the client reported, from `vds serve` output."""
    return [m.group(1) for m in re.finditer(r"^\s*frame\s+\d+\s+crc\s+([0-9a-f]{8})", serve_stdout, re.M)]


def frame_instructions(serve_stdout):
    """(parse, decode, display, entropy, transform) instructions of every frame."""
    rows = []
    for m in re.finditer(r"^\s*frame\s+\d+\s+crc\s+\S+\s+parse\s+(\d+)\s+decode\s+(\d+)\s+"
                         r"\(entropy\s+(\d+)\s+transform\s+(\d+)\)\s+display\s+(\d+)", serve_stdout, re.M):
        p, d, e, t, s = (int(v) for v in m.groups())
        rows.append((p, d, s, e, t))
    return rows


def full_report(serve_stdout):
    """A client's workspace-full report as `vds serve` printed it: a dict with
    the bytes it covers, the stream's size and the stream bytes the client
    had acknowledged when the host closed (`bytes`, `stream`, `acked`); None
    if the client reported no such thing."""
    m = re.search(r"client report\s+workspace full after the first (\d+) of (\d+) bytes, CRC-32C [0-9a-f]{8}: "
                  r"matches; the host stopped the stream: (\d+) bytes of it acknowledged", serve_stdout)
    if not m:
        return None
    return {"bytes": int(m.group(1)), "stream": int(m.group(2)), "acked": int(m.group(3))}


def frame_times_ms(serve_stdout):
    """The client's clock (ms) when it finished each frame."""
    return [int(m.group(1)) for m in re.finditer(r"^\s*frame\s+\d+\s+crc\s+\S+.*\sat\s+(\d+)\s+ms", serve_stdout, re.M)]


def model_prefix(board_log):
    """Where a client too small for a model stopped, from its log: a dict with
    the vertices its workspace holds and the stream's (`held`, `vertices`),
    the last level it applied, the stream's levels and the vertices then
    (`level`, `levels`, `level_vertices`); None if it held every level."""
    full = re.search(r"workspace full after level (\d+) of (\d+) \((\d+) vertices\)", board_log)
    held = re.search(r"the workspace holds (\d+) of its (\d+) vertices", board_log)
    if not full or not held:
        return None
    return {"held": int(held.group(1)), "vertices": int(held.group(2)), "level": int(full.group(1)),
            "levels": int(full.group(2)), "level_vertices": int(full.group(3))}


def replay_crcs(vds, stream, png_dir=None, workspace=None):
    """The CRC of every frame a client must display (`vds frames`), or None if it fails;
    with workspace=(budget, player_from), the frames of a board with that workspace."""
    cmd = [vds, "frames", stream] + (["--png", png_dir] if png_dir else [])
    if workspace:
        cmd += ["--workspace", str(workspace[0]), "--player-from", str(workspace[1])]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        print(r.stdout + r.stderr)
        return None
    return r.stdout.split()


class Run:
    """What one board run produced."""

    def __init__(self, serve, board_rc, board_log, seconds, failure=None):
        self.serve = serve
        self.board_rc = board_rc
        self.board_log = board_log
        self.seconds = seconds
        self.failure = failure

    @property
    def ok(self):
        return self.failure is None and self.serve.returncode == 0 and self.board_rc == 0


def serve_cmd(vds, stream, link, baud, timeout, unpaced=False):
    return ([vds, "serve", stream, "--link", link, "--baud", str(baud), "--timeout", str(int(timeout))] +
            (["--unpaced"] if unpaced else []))


def run_host(vds, board, stream, baud=115200, timeout=240, out_dir=None, window=False, env=None, workspace=0):
    """The host-native board over a new pseudo-terminal."""
    cmd = [board, "--uart", "pty-new", "--baud", str(baud)] + (["--window"] if window else [])
    if workspace:
        cmd += ["--workspace", str(workspace)]
    if out_dir:
        os.makedirs(out_dir, exist_ok=True)
        cmd += ["--frames", os.path.join(out_dir, "frames"), "--contact-sheet", os.path.join(out_dir, "contact_sheet.png"),
                "--y4m", os.path.join(out_dir, "frames.y4m")]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    first = proc.stderr.readline()
    m = re.match(r"uart: (\S+)", first)
    if not m:
        proc.kill()
        out, err = proc.communicate()
        return Run(subprocess.CompletedProcess(cmd, 1, "", ""), proc.returncode, first + out + err, 0,
                   "the host board did not report its pseudo-terminal")
    t0 = time.time()
    serve = subprocess.run(serve_cmd(vds, stream, "pty:" + m.group(1), baud, timeout), capture_output=True, text=True)
    seconds = time.time() - t0
    failure = None
    try:
        out, err = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
        failure = "the host board did not exit after the stream"
    if out_dir and shutil.which("ffmpeg") and os.path.exists(os.path.join(out_dir, "frames.y4m")):
        subprocess.run(["ffmpeg", "-loglevel", "error", "-y", "-i", os.path.join(out_dir, "frames.y4m"),
                        "-pix_fmt", "yuv420p", os.path.join(out_dir, "frames.mp4")])
    return Run(serve, proc.returncode, first + out + err, seconds, failure)


def run_qemu(vds, qemu, elf, stream, baud=115200, timeout=240, workspace=0, unpaced=False):
    """The Cortex-M4 board in QEMU, UART0 on a TCP socket. `workspace` lowers
    the firmware's workspace budget below its build's (semihosting argument);
    `unpaced` lets the host write as fast as the client's line reports allow."""
    port = free_port()
    semihosting = "enable=on,target=native" + (f",arg=vds_fw_client,arg=workspace={workspace}" if workspace else "")
    proc = subprocess.Popen([qemu, "-M", "mps2-an386", "-cpu", "cortex-m4", "-nographic", "-monitor", "none",
                             "-serial", f"tcp:127.0.0.1:{port},server=on,wait=on",
                             "-semihosting-config", semihosting, "-icount", "shift=0",
                             "-kernel", elf], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    t0 = time.time()
    serve = None
    for _ in range(100):  # QEMU takes a moment to listen
        serve = subprocess.run(serve_cmd(vds, stream, f"tcp:127.0.0.1:{port}", baud, timeout, unpaced),
                               capture_output=True, text=True)
        if "ECONNREFUSED" not in serve.stderr or proc.poll() is not None:
            break
        time.sleep(0.1)
    seconds = time.time() - t0
    failure = None
    try:
        out, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
        failure = "QEMU did not exit after the stream"
    return Run(serve, proc.returncode, out + err, seconds, failure)


def main():
    ap = argparse.ArgumentParser(description="Play a vds stream on a simulated client board.")
    ap.add_argument("stream")
    ap.add_argument("--board", choices=["host", "qemu"], required=True)
    ap.add_argument("--build", default=os.path.join(ROOT, "build", "host-release"),
                    help="build directory holding encoder/vds and the firmware")
    ap.add_argument("--baud", type=int, default=115200)
    ap.add_argument("--out", default="", help="host board: where frames, video and contact sheet go")
    ap.add_argument("--window", action="store_true", help="host board: show the frames in a live window (SDL2)")
    ap.add_argument("--timeout", type=float, default=600)
    ap.add_argument("--workspace", type=int, default=0, help="the client's workspace budget, bytes (default: the board's)")
    ap.add_argument("--unpaced", action="store_true",
                    help="qemu board: the host writes as fast as the client's line reports allow (how fast it drains)")
    a = ap.parse_args()
    vds = os.path.join(a.build, "encoder", "vds")
    need = [vds]
    if a.board == "host":
        board = os.path.join(a.build, "firmware_sim", "vds_fw_client_host")
        need.append(board)
    else:
        elf = os.path.join(a.build, "cm4", "firmware_sim", "vds_fw_client.elf")
        need.append(elf)
        if not shutil.which("qemu-system-arm"):
            print("sim: qemu-system-arm not found (scripts/setup.sh installs it)", file=sys.stderr)
            return 2
    for p in need:
        if not os.path.exists(p):
            print(f"sim: {p} not found: build first (make demo builds {a.build})", file=sys.stderr)
            return 2
    if not os.path.isfile(a.stream):
        print(f"sim: {a.stream}: no such stream file", file=sys.stderr)
        return 2
    if a.board == "host":
        r = run_host(vds, board, a.stream, a.baud, a.timeout, a.out or None, a.window, workspace=a.workspace)
    else:
        r = run_qemu(vds, "qemu-system-arm", elf, a.stream, a.baud, a.timeout, workspace=a.workspace,
                     unpaced=a.unpaced)
    sys.stdout.write(r.serve.stdout)
    sys.stderr.write(r.serve.stderr)
    sys.stderr.write(r.board_log)
    if r.failure:
        print("sim: " + r.failure, file=sys.stderr)
    return 0 if r.ok else 1


if __name__ == "__main__":
    sys.exit(main())
