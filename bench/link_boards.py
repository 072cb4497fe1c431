#!/usr/bin/env python3
"""The link on the Cortex-M4 board in QEMU, end to end (`vds serve` over TCP
to the client firmware): how fast the board drains, the goodput at four line
rates against it, and a soak of the demo reel and the bunny model with every
core of the machine kept busy by other processes and on an idle machine.
Counts stalls (a run that did not finish), frames whose CRC differs from
`vds frames`, and closes that were not clean (the client must read the
host's Goodbye for a verified report and both processes must exit 0).

Usage: bench/link_boards.py --build build/host-release --reel REEL.vds
       --model MODEL.vds [--runs 30] [--out FILE.md]
Exit status 0 when every soak run was clean."""
import argparse
import os
import random
import re
import statistics
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import sim  # noqa: E402

BAUDS = [115200, 230400, 460800, 921600]


def stat(pattern, text, group=1, cast=int):
    m = re.search(pattern, text)
    return cast(m.group(group)) if m else None


def host_counts(out):
    """Frames sent, resent, received twice, probes from `vds serve` output."""
    m = re.search(r"frames\s+(\d+) data, (\d+) resent \((\d+) lost on the line, (\d+) received twice\), "
                  r"(\d+) probes after (\d+) timeouts", out)
    if not m:
        return None
    keys = ["data", "resent", "lost", "twice", "probes", "timeouts"]
    return dict(zip(keys, (int(v) for v in m.groups())))


class Loader:
    """Every core busy: one spinning process per CPU."""

    def __init__(self, on):
        self.procs = []
        if on:
            for _ in range(os.cpu_count() or 2):
                self.procs.append(subprocess.Popen(["sh", "-c", "while :; do :; done"]))

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        for p in self.procs:
            p.kill()
            p.wait()


def play(vds, elf, stream, baud, expected, unpaced=False, timeout=300):
    """One run on the QEMU board: a dict of what happened."""
    t0 = time.monotonic()
    r = sim.run_qemu(vds, "qemu-system-arm", elf, stream, baud, timeout, unpaced=unpaced)
    out = r.serve.stdout + r.serve.stderr
    crcs = sim.frame_crcs(r.serve.stdout)
    prefix = sim.full_report(r.serve.stdout)
    want = expected[:len(crcs)] if prefix else expected
    stalled = r.serve.returncode != 0 and "did not finish" in out or r.failure is not None
    return {
        "ok": r.ok,
        "stalled": stalled,
        "crc_ok": len(crcs) > 0 and crcs == want,
        "close_ok": r.ok and "the host said goodbye: report verified" in r.board_log,
        "seconds": stat(r"time\s+([\d.]+) s", out, cast=float),
        "goodput_bps": None,
        "bytes": os.path.getsize(stream) if not prefix else prefix["bytes"],
        "counts": host_counts(out),
        "wall": time.monotonic() - t0,
        "log": out + r.board_log,
    }


def drain_stream(vds, path, size=200000, seed=7):
    """A stream of `size` bytes in chunks the client verifies and skips: the
    link's work without any decoding."""
    rnd = random.Random(seed)
    parts = []
    d = os.path.dirname(path)
    for i in range(0, size, 4000):
        p = os.path.join(d, f"drain_{i // 4000:03d}.bin")
        with open(p, "wb") as f:
            f.write(bytes(rnd.getrandbits(8) for _ in range(min(4000, size - i))))
        parts += ["--chunk", f"SKIP={p}"]
    subprocess.run([vds, "pack", "-o", path, *parts], check=True, capture_output=True)
    return path


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(ROOT, "build", "host-release"))
    ap.add_argument("--reel", required=True)
    ap.add_argument("--model", required=True)
    ap.add_argument("--runs", type=int, default=30)
    ap.add_argument("--rate-runs", type=int, default=5)
    ap.add_argument("--work", default="/tmp/vds-link-boards")
    ap.add_argument("--out", default="")
    a = ap.parse_args()
    vds = os.path.join(a.build, "encoder", "vds")
    elf = os.path.join(a.build, "cm4", "firmware_sim", "vds_fw_client.elf")
    os.makedirs(a.work, exist_ok=True)
    lines = []

    def say(s=""):
        lines.append(s)
        print(s, flush=True)

    # 1. Drain and goodput on a stream with no decoding.
    drain = drain_stream(vds, os.path.join(a.work, "drain.vds"))
    size = os.path.getsize(drain)
    rows = []
    fast_rates = []  # runs whose line was at least twice what the board takes
    for label, baud, unpaced in [(str(b), b, False) for b in BAUDS] + [("unpaced", 921600, True)]:
        runs = [play(vds, elf, drain, baud, [], unpaced) for _ in range(a.rate_runs)]
        good = [r for r in runs if r["ok"]]
        rates = [size / r["seconds"] for r in good]
        if baud >= 460800:
            fast_rates += rates
        rate = statistics.median(rates) if rates else 0
        resent = sum(r["counts"]["resent"] for r in runs if r["counts"])
        twice = sum(r["counts"]["twice"] for r in runs if r["counts"])
        probes = sum(r["counts"]["probes"] for r in runs if r["counts"])
        rows.append((label, baud, unpaced, rate, len(good), len(runs), resent, twice, probes))
        print(f"rate {label}: {rate:.0f} B/s ({len(good)}/{len(runs)} ok)", file=sys.stderr, flush=True)
    drain_rate = statistics.median(fast_rates) if fast_rates else 0
    say("## Cortex-M4 board in QEMU: goodput against the rate the board drains")
    say()
    say(f"Stream: {size:,} bytes of chunks the client verifies and skips (no decoding), "
        f"median of {a.rate_runs} runs each. The board's drain rate is the median stream bytes per second "
        "of every run whose line was at least twice as fast as the board (460,800 and 921,600 baud, and "
        "the host unpaced): the board was then the only limit. QEMU hands its emulated UART one byte "
        "per turn of its main loop, so the rate varies from run to run with the machine (range of those "
        f"runs: {min(fast_rates or [0]):,.0f}-{max(fast_rates or [0]):,.0f} B/s): **{drain_rate:,.0f} B/s**.")
    say()
    say("| line | line rate B/s | goodput B/s | of the line rate | of the drain rate | runs ok | resent | received twice | probes |")
    say("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for label, baud, unpaced, rate, ok, n, resent, twice, probes in rows:
        line = baud / 10
        cap = min(line, drain_rate) if not unpaced else drain_rate
        say(f"| {label} baud | {'-' if unpaced else f'{line:,.0f}'} | {rate:,.0f} | "
            f"{'-' if unpaced else f'{100 * rate / line:.1f} %'} | {100 * rate / cap:.1f} % | {ok}/{n} | "
            f"{resent} | {twice} | {probes} |")
    say()

    # 2. Soak.
    expected = {}
    for name, path in [("reel", a.reel), ("model", a.model)]:
        expected[name] = sim.replay_crcs(vds, path)
        if not expected[name]:
            sys.exit(f"link_boards: vds frames {path} failed")
    plan = []
    for name, path in [("reel", a.reel), ("model", a.model)]:
        plan += [(name, path, 115200, True), (name, path, 230400, True), (name, path, 115200, False)]
    say(f"## Soak: {a.runs} runs per row on the Cortex-M4 board")
    say()
    say("Loaded: one spinning process per core for the whole row. A stall is a run that did not finish; "
        "a CRC mismatch a run whose frames differ from `vds frames` (the model client's workspace holds "
        "its first levels: the frames of those); a clean close: the client read the host's Goodbye for "
        "a verified report and both processes exited 0.")
    say()
    say("| stream | baud | machine | runs | stalls | CRC mismatches | unclean closes | resent | received twice | probes | seconds (min / median / max) |")
    say("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---|")
    bad = 0
    for name, path, baud, loaded in plan:
        results = []
        with Loader(loaded):
            for i in range(a.runs):
                r = play(vds, elf, path, baud, expected[name])
                results.append(r)
                if not (r["ok"] and r["crc_ok"] and r["close_ok"]):
                    with open(os.path.join(a.work, f"fail_{name}_{baud}_{'loaded' if loaded else 'idle'}_{i}.log"), "w") as f:
                        f.write(r["log"])
                print(f"soak {name} {baud} {'loaded' if loaded else 'idle'} {i + 1}/{a.runs}: "
                      f"{'ok' if r['ok'] and r['crc_ok'] and r['close_ok'] else 'FAILED'} {r['wall']:.1f} s",
                      file=sys.stderr, flush=True)
        stalls = sum(r["stalled"] for r in results)
        mism = sum(not r["crc_ok"] for r in results)
        unclean = sum(not r["close_ok"] for r in results)
        bad += stalls + mism + unclean
        secs = sorted(r["seconds"] for r in results if r["seconds"] is not None)
        resent = sum(r["counts"]["resent"] for r in results if r["counts"])
        twice = sum(r["counts"]["twice"] for r in results if r["counts"])
        probes = sum(r["counts"]["probes"] for r in results if r["counts"])
        span = f"{secs[0]:.1f} / {statistics.median(secs):.1f} / {secs[-1]:.1f}" if secs else "-"
        say(f"| {name} | {baud} | {'all cores busy' if loaded else 'idle'} | {len(results)} | {stalls} | {mism} | "
            f"{unclean} | {resent} | {twice} | {probes} | {span} |")
    say()
    if a.out:
        with open(a.out, "w") as f:
            f.write("\n".join(lines) + "\n")
    return 0 if bad == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
