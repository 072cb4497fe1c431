#!/usr/bin/env python3
"""The model part of the demo: a mesh is encoded as a progressive stream,
served over a pseudo-terminal at 2 KB/s (19,200 baud) to the client firmware
on the host-native board, which draws it after its base and after every
level. Every frame's CRC must equal the host replay of the client's display
path (`vds frames`). Prints a markdown section for the demo report: per
level, the vertices, the bytes so far, when that is at 2 KB/s, and when the
board showed it. With --qemu and --elf, the same stream also goes to the
client on the Cortex-M4 board at 115,200 baud: its workspace holds only the
first levels, which it must show exactly as the replay does, skipping the
rest.

Usage: demo_model.py --vds VDS --host-board EXE --model MESH --out DIR [--baud B]
       [--qemu QEMU --elf CLIENT.elf]"""
import argparse
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sim  # noqa: E402


def level_table(info_stdout):
    """(level, vertices, cumulative bytes) from `vds info`'s per-level table
    (the single-rate tail's level carries a T)."""
    rows = []
    for line in info_stdout.splitlines():
        m = re.match(r"^\s*(base|\d+T?)\s+(\d+)\s+(\d+)\s+\S+\s+\S+\s+\S+\s+(\d+)\s+(\d+)\s+(\d+)\s*$", line)
        if m:
            level = 0 if m.group(1) == "base" else int(m.group(1).rstrip("T"))
            rows.append((level, int(m.group(6)), int(m.group(5))))
    return rows


def skipped_levels(n):
    return "the level" if n == 1 else f"the {n} levels"


def cortex_m4_prefix(a, stream, want):
    """The stream on the Cortex-M4 board with its own workspace: the frames
    of the levels it holds, each equal to the replay's. Returns failures."""
    run = sim.run_qemu(a.vds, a.qemu, a.elf, stream, 115200, a.timeout)
    with open(os.path.join(a.out, "serve_cortex_m4.log"), "w") as f:
        f.write(run.serve.stdout + run.serve.stderr + "\n== Cortex-M4 board\n" + run.board_log)
    got = sim.frame_crcs(run.serve.stdout)
    prefix = sim.model_prefix(run.board_log)
    full = sim.full_report(run.serve.stdout)
    budget = re.search(r"ready, workspace (\d+) bytes", run.board_log)
    failures = []
    if not run.ok:
        failures.append("Cortex-M4 board: " + (run.failure or f"the run failed (serve {run.serve.returncode})"))
    if not prefix:
        failures.append("the Cortex-M4 board did not report where its workspace ran out")
    elif got != want[:prefix["level"] + 1]:
        failures.append(f"the Cortex-M4 board's {len(got)} frames are not the replay's first {prefix['level'] + 1}")
    if prefix and not full:
        failures.append("the Cortex-M4 board's report of a full workspace was not verified")
    if prefix and budget:
        print(f"The same stream at 115,200 baud to the client on the **Cortex-M4 board** (QEMU mps2-an386), "
              f"whose {int(budget.group(1)) // 1024} KiB workspace holds {prefix['held']} of the "
              f"{prefix['vertices']} vertices: it drew the base and levels 1-{prefix['level']} "
              f"({prefix['level_vertices']} vertices), {len(got)} frames, each identical to the replay's: "
              f"{'yes' if not failures else 'NO'}. "
              + (f"It then reported its workspace full after the first {full['bytes']:,} bytes and the host "
                 f"stopped the stream: {full['acked']:,} of its {full['stream']:,} bytes had been delivered when it "
                 f"closed, so {skipped_levels(prefix['levels'] - prefix['level'])} the client could not hold cost the "
                 f"line only the {full['acked'] - full['bytes']:,} bytes already in flight "
                 if full else "It did not report its workspace full ")
              + "(log: `out/demo/model/serve_cortex_m4.log`).\n")
    return failures


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--vds", required=True)
    ap.add_argument("--host-board", required=True)
    ap.add_argument("--model", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--baud", type=int, default=19200)
    ap.add_argument("--timeout", type=float, default=600)
    ap.add_argument("--qemu", default="", help="also play the stream on the Cortex-M4 board in this QEMU")
    ap.add_argument("--elf", default="", help="the Cortex-M4 client firmware")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    name = os.path.splitext(os.path.basename(a.model))[0]
    stream = os.path.join(a.out, name + ".vds")
    enc = subprocess.run([a.vds, "encode-mesh", a.model, "-o", stream], capture_output=True, text=True)
    with open(os.path.join(a.out, "encode.log"), "w") as f:
        f.write(enc.stdout + enc.stderr)
    if enc.returncode != 0:
        print(enc.stdout + enc.stderr, file=sys.stderr)
        return 1
    info = subprocess.run([a.vds, "info", stream], capture_output=True, text=True, check=True).stdout
    levels = level_table(info)
    want = sim.replay_crcs(a.vds, stream, os.path.join(a.out, "replay"))
    if want is None:
        return 1
    # The whole model in the client's workspace: the host board can be given more than a Cortex-M4 holds.
    run = sim.run_host(a.vds, a.host_board, stream, a.baud, a.timeout, os.path.join(a.out, "host"), workspace=8 << 20)
    with open(os.path.join(a.out, "serve.log"), "w") as f:
        f.write(run.serve.stdout + run.serve.stderr + "\n== host-native board\n" + run.board_log)
    got = sim.frame_crcs(run.serve.stdout)
    times = sim.frame_times_ms(run.serve.stdout)
    failures = []
    if not run.ok:
        failures.append(run.failure or f"the run failed (serve {run.serve.returncode}, board {run.board_rc})")
    if got != want:
        failures.append(f"the board's {len(got)} frame CRCs differ from the replay's {len(want)}")
    if len(want) != len(levels):
        failures.append(f"{len(want)} frames for {len(levels)} levels (base included)")

    stream_bytes = os.path.getsize(stream)
    rate = a.baud / 10
    print(f"## A progressive model at {rate / 1024:.1f} KB/s ({a.baud} baud), host-native board\n")
    print(f"`{os.path.basename(a.model)}`: {stream_bytes} bytes, {len(levels) - 1} levels; the board drew "
          f"{len(got)} frames, each identical to the host replay: "
          f"{'yes' if got == want and not failures else 'NO'}. Link time {run.seconds:.1f} s "
          f"for {stream_bytes / rate:.1f} s of line time. Frames: `out/demo/model/host/frames/`, "
          f"contact sheet `out/demo/model/host/contact_sheet.png`.\n")
    print("| level | vertices | bytes so far | at 2 KB/s (s) | shown on the board (s after the base) |")
    print("|---:|---:|---:|---:|---:|")
    for i, (level, vertices, cum) in enumerate(levels):
        shown = f"{(times[i] - times[0]) / 1000:.2f}" if i < len(times) and times else "-"
        # Every level is listed up to 1,000 vertices, then every third, and the last.
        if vertices <= 1000 or i % 3 == 0 or i == len(levels) - 1:
            print(f"| {'base' if level == 0 else level} | {vertices} | {cum} | {cum / 2048:.2f} | {shown} |")
    print()
    if a.qemu and a.elf:
        failures += cortex_m4_prefix(a, stream, want)
    for f in failures:
        print("FAIL " + f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
