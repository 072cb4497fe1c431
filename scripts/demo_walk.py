#!/usr/bin/env python3
"""The walkthrough part of the demo: a tour through an OpenArena map
(`vds path`), encoded as a walkthrough shaped for the link (`vds
encode-walk --rate`: 88 % of the line's bytes, the rest left to the
link's framing and the acknowledgements sharing the line), served at 2
KB/s (19,200 baud) over a pseudo-terminal to the client firmware on the
host-native board, which writes the frames it shows, and over TCP to the
same firmware on the Cortex-M4 board in QEMU, which counts the
instructions of every frame. Both show frame i the stream's pre-roll
plus i frame periods after its first byte. Every frame's CRC on both
boards must equal the host replay of the client's display path (`vds
frames`). Prints a markdown section for the demo report, with the frames
each board showed late.

Usage: demo_walk.py --vds VDS --host-board EXE --qemu QEMU --elf CLIENT.elf --out DIR
       [--map oa_dm4] [--frames 300] [--rate KBPS] [--baud 19200]"""
import argparse
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sim  # noqa: E402


def run(cmd, log):
    p = subprocess.run(cmd, capture_output=True, text=True)
    with open(log, "w") as f:
        f.write(p.stdout + p.stderr)
    if p.returncode != 0:
        print(p.stdout + p.stderr, file=sys.stderr)
        raise SystemExit(1)
    return p.stdout


def main():
    ap = argparse.ArgumentParser()
    for k in ("--vds", "--host-board", "--qemu", "--elf", "--out"):
        ap.add_argument(k, required=True)
    ap.add_argument("--map", default="oa_dm4")
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--rate", type=float, default=None)
    ap.add_argument("--baud", type=int, default=19200)
    ap.add_argument("--timeout", type=float, default=600)
    a = ap.parse_args()
    if a.rate is None:
        a.rate = round(a.baud / 10 * 0.88 * 8 / 1000, 1)
    os.makedirs(a.out, exist_ok=True)
    tour = os.path.join(a.out, "tour.txt")
    stream = os.path.join(a.out, "walk.vds")
    run([a.vds, "path", a.map, "-o", tour, "--frames", str(a.frames)], os.path.join(a.out, "path.log"))
    enc = run([a.vds, "encode-walk", a.map, "--path", tour, "--rate", str(a.rate), "-o", stream],
              os.path.join(a.out, "encode.log"))
    want = sim.replay_crcs(a.vds, stream, os.path.join(a.out, "replay"))
    if want is None:
        return 1
    failures = []
    host = sim.run_host(a.vds, a.host_board, stream, a.baud, a.timeout, os.path.join(a.out, "host"))
    m4 = sim.run_qemu(a.vds, a.qemu, a.elf, stream, a.baud, a.timeout)
    for name, r, log in (("host-native", host, "serve_host.log"), ("Cortex-M4", m4, "serve_cortex_m4.log")):
        with open(os.path.join(a.out, log), "w") as f:
            f.write(r.serve.stdout + r.serve.stderr + f"\n== {name} board\n" + r.board_log)
        got = sim.frame_crcs(r.serve.stdout)
        if not r.ok:
            failures.append(f"{name} board: " + (r.failure or f"the run failed (serve {r.serve.returncode})"))
        if got != want:
            failures.append(f"the {name} board's {len(got)} frame CRCs differ from the replay's {len(want)}")
    # The Cortex-M4 board's instructions per frame and workspace.
    counts = [sum(int(x) for x in m.groups()) for m in
              re.finditer(r"^\s*frame\s+\d+\s+crc\s+\S+\s+parse\s+(\d+)\s+decode\s+(\d+)\s+\(entropy \d+ transform \d+\)\s+"
                           r"display\s+(\d+)", m4.serve.stdout, re.M)]
    ws = re.search(r"workspace high-water (\d+) bytes", m4.board_log)
    budget = re.search(r"ready, workspace (\d+) bytes", m4.board_log)
    size = re.search(r"(\d+) bytes = ([\d.]+) kbit/s", enc)
    preroll = re.search(r"pre-roll ([\d.]+) s", enc)
    late = {}
    for name, r in (("host-native", host), ("Cortex-M4", m4)):
        m = re.search(r"client stats\s+(\d+) frames shown, (\d+) late", r.serve.stdout)
        late[name] = f"{m[2]} of {m[1]}" if m else "unknown"
    psnr = re.search(r"PSNR R,G,B ([\d.]+) dB pooled, ([\d.]+) dB worst", enc)
    print(f"## A walkthrough of {a.map} at {a.baud // 10 / 1000:.1f} KB/s ({a.baud} baud), both boards\n")
    print(f"`vds path {a.map} --frames {a.frames}` and `vds encode-walk --rate {a.rate:g}`: {int(size[1]):,} bytes, "
          f"{size[2]} kbit/s for {len(want)} frames at 20 frames/s; PSNR over R, G, B against the ground truth "
          f"{psnr[1]} dB pooled, {psnr[2]} dB the worst frame. Every frame each board showed is identical to the host "
          f"replay: {'yes' if not failures else 'NO'}. Link time {host.seconds:.1f} s (host-native board) and "
          f"{m4.seconds:.1f} s (Cortex-M4 board) for {len(want) / 20:.0f} s of video. Each board shows frame i "
          f"{preroll[1]} s (the stream's pre-roll) plus i frame periods after the first byte; frames later than a period: "
          f"{late['host-native']} (host-native board), {late['Cortex-M4']} (Cortex-M4 board). Frames: "
          f"`out/demo/walk/host/frames/`, video `out/demo/walk/host/frames.y4m`, contact sheet "
          f"`out/demo/walk/host/contact_sheet.png`.\n")
    if counts and ws and budget:
        mean = sum(counts) / len(counts)
        print(f"On the Cortex-M4 board: {mean / 1e6:.1f} M instructions a frame on average, {max(counts) / 1e6:.1f} M at "
              f"worst ({1e8 / mean:.1f} and {1e8 / max(counts):.1f} frames/s at 100 MHz); workspace high-water "
              f"{int(ws[1]):,} of its {int(budget[1]):,} bytes (logs: `out/demo/walk/serve_*.log`).\n")
    for f in failures:
        print("FAIL " + f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
