#!/usr/bin/env python3
"""Where a Cortex-M4 firmware's instructions go, function by function.

Runs the firmware on the QEMU board (mps2-an386, -icount shift=0) with
QEMU's translation and execution log (-d in_asm,exec,nochain: every
translated block's instructions once, every execution of a block once, no
chaining so none is missed), then attributes each block's instructions,
times its executions, to the function its address lies in (the ELF's
symbols, arm-none-eabi-nm). The log of a few million instructions is
tens of megabytes; keep runs short (a stream of a few dozen frames).

Usage: m4_profile.py ELF [--cwd DIR] [--top N] [--log FILE]
  DIR: where the firmware finds its host files (semihosting), default '.'.
"""
import argparse
import bisect
import collections
import os
import re
import subprocess
import sys
import tempfile


def symbols(elf):
    out = subprocess.run(["arm-none-eabi-nm", "-C", "-S", "--defined-only", elf], check=True, capture_output=True,
                         text=True).stdout
    syms = []
    for line in out.splitlines():
        parts = line.split(None, 3)
        if len(parts) == 4 and parts[2] in "tTwW":
            syms.append((int(parts[0], 16) & ~1, int(parts[1], 16), parts[3]))
    syms.sort()
    return syms


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("elf")
    ap.add_argument("--cwd", default=".")
    ap.add_argument("--top", type=int, default=40)
    ap.add_argument("--log", help="keep QEMU's log here (default: a temporary file, removed)")
    ap.add_argument("--blocks", metavar="TEXT", help="also list the blocks of the functions whose names hold TEXT")
    a = ap.parse_args()

    syms = symbols(a.elf)
    starts = [s[0] for s in syms]
    if a.log:
        log = a.log
    else:
        fd, log = tempfile.mkstemp(suffix=".qemu.log")
        os.close(fd)
    cmd = ["qemu-system-arm", "-M", "mps2-an386", "-cpu", "cortex-m4", "-nographic", "-monitor", "none", "-serial",
           "null", "-semihosting-config", "enable=on,target=native", "-icount", "shift=0", "-d",
           "in_asm,exec,nochain", "-D", log, "-kernel", os.path.abspath(a.elf)]
    print("running:", " ".join(cmd), file=sys.stderr)
    subprocess.run(cmd, cwd=a.cwd, check=True, stdout=subprocess.DEVNULL)

    # block start -> instructions. A block may be translated again shorter
    # (icount's budget ends a block early; such blocks run once and are not
    # kept), so each start keeps its longest translation.
    size = collections.Counter()
    runs = collections.Counter()  # block start -> executions
    insn = re.compile(r"^0x([0-9a-f]{8}):\s")
    trace = re.compile(r"^Trace \d+: \S+ \[[0-9a-f]+/([0-9a-f]+)/")
    block, count = None, 0
    with open(log, errors="replace") as f:
        for line in f:
            if line.startswith("Trace"):
                m = trace.match(line)
                if m:
                    runs[int(m.group(1), 16)] += 1
                continue
            m = insn.match(line)
            if m:
                if block is None:
                    block = int(m.group(1), 16)
                count += 1
            elif block is not None and not line.strip():
                size[block] = max(size[block], count)
                block, count = None, 0
    if block is not None:
        size[block] = max(size[block], count)
    if not a.log:
        os.unlink(log)

    per_fn = collections.Counter()
    blocks = []
    for pc, n in runs.items():
        i = bisect.bisect_right(starts, pc) - 1
        name = syms[i][2] if i >= 0 and pc < syms[i][0] + max(syms[i][1], 2) else "?"
        per_fn[name] += n * size.get(pc, 0)
        if a.blocks and a.blocks in name:
            blocks.append((pc, n, size.get(pc, 0)))
    if blocks:
        print(f"blocks of the functions holding '{a.blocks}': address, executions, instructions, their product")
        for pc, n, k in sorted(blocks):
            print(f"  0x{pc:08x} {n:>12,} {k:>4} {n * k:>14,}")
    total = sum(per_fn.values())
    print(f"{total:,} instructions executed")
    print(f"{'instructions':>14} {'share':>6}  function")
    for name, n in per_fn.most_common(a.top):
        print(f"{n:>14,} {100.0 * n / total:>5.1f}%  {name[:150]}")


if __name__ == "__main__":
    main()
