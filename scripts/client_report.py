#!/usr/bin/env python3
"""Writes the client report (markdown) of an end-to-end run: the stream,
the link, the frames, Cortex-M4 instructions per frame and per stage, and
the firmware's flash and RAM by component (from the linker map).

Usage: client_report.py --run RUN.json --elf vds_fw_client.elf --map vds_fw_client.map
       [--mhz 100] [--title T] [--images-dir DIR] > report.md
RUN.json is what tests/tools/e2e_boards.py --report writes."""
import argparse
import json
import os
import re
import subprocess

ANCHOR_TJPGDEC = 155  # instructions/pixel, TJpgDec on a 240x180 q85 4:2:0 JPEG (QEMU mps2-an386, -icount)


def component(path):
    p = path.replace("\\", "/")
    if "libvds_decoder.a" in p:
        return "client library (decoder/)"
    if "libvds_transport_core.a" in p:
        return "link (transport/core/)"
    if "libvds_board_qemu.a" in p:
        return "board (boards/qemu_mps2_an386/)"
    if "/app/" in p:
        return "application (app/)"
    if "libgcc" in p:
        return "libgcc (integer helpers)"
    return "other"


def map_sizes(map_path):
    """{component: {"flash": bytes, "ram": bytes}} from a GNU ld map file."""
    text = open(map_path).read()
    start = text.find("Linker script and memory map")
    lines = text[start:].splitlines()
    sizes = {}
    pending = None
    for line in lines:
        m = re.match(r"^ (\.(?:text|rodata|data|bss|ARM\.exidx)[^\s]*)(?:\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S.*))?$", line)
        if m:
            if m.group(2) is None:
                pending = m.group(1)
                continue
            sec, size, path = m.group(1), int(m.group(3), 16), m.group(4)
        elif pending:
            m2 = re.match(r"^\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S.*)$", line)
            pending_sec, pending = pending, None
            if not m2:
                continue
            sec, size, path = pending_sec, int(m2.group(2), 16), m2.group(3)
        else:
            continue
        if size == 0:
            continue
        kind = "ram" if sec.startswith((".data", ".bss")) else "flash"
        if sec.startswith(".data"):
            sizes.setdefault(component(path), {"flash": 0, "ram": 0})["flash"] += size  # its initial values
        c = sizes.setdefault(component(path), {"flash": 0, "ram": 0})
        c[kind] += size
    return sizes


def stats_line(serve):
    m = re.search(r"client stats\s+(\d+) frames shown, (\d+) late, (\d+) stream bytes, workspace (\d+) of (\d+) B, stack (\d+) B",
                  serve)
    return tuple(int(v) for v in m.groups()) if m else None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--run", required=True)
    ap.add_argument("--elf", required=True)
    ap.add_argument("--map", required=True)
    ap.add_argument("--mhz", type=float, default=100)
    ap.add_argument("--title", default="vds end-to-end report")
    ap.add_argument("--images-dir", default="", help="where frames/ and contact_sheet.png are, relative to the report")
    ap.add_argument("--budget", default="", help="JSON of the workspace bisection (bench/run_firmware.sh)")
    a = ap.parse_args()
    r = json.load(open(a.run))
    out = [f"# {a.title}", ""]
    n = r["frames"]
    pixels = 240 * 180
    m = re.search(r"(\d+) frames (\d+)x(\d+)", r["encoder"])
    if m:
        pixels = int(m.group(2)) * int(m.group(3))
    out.append(f"Stream: {n} frames of {m.group(2)}x{m.group(3) if m else '?'}, {r['stream_bytes']:,} bytes "
               f"({r['stream_bytes'] / n:,.0f} bytes/frame).")
    out.append("")
    out.append("```")
    out.append(r["encoder"].rstrip())
    out.append("```")
    out.append("")
    link_bps = r["baud"] / 10
    out.append(f"## The link: {r['baud']:,} baud ({link_bps:,.0f} bytes/s)")
    out.append("")
    out.append("| board | link | seconds | goodput | frames/s the link allowed | frame CRCs = encoder |")
    out.append("|---|---|---:|---:|---:|---|")
    for name, key, link, crcs in (("host-native", "serve_host", "pty", r["host_crcs"]),
                                  ("Cortex-M4 (QEMU)", "serve_qemu", "TCP", r["qemu_crcs"])):
        s = r[key]
        t = re.search(r"time\s+([\d.]+) s, goodput ([\d.]+) %", s)
        secs, good = (float(t.group(1)), float(t.group(2))) if t else (0.0, 0.0)
        fps = n / secs if secs else 0
        out.append(f"| {name} | {link} | {secs:.2f} | {good:.1f} % | {fps:.2f} | "
                   f"{'yes' if crcs == r['encoder_crcs'] else 'NO'} ({len(crcs)} of {n}) |")
    out.append("")
    ins = r["qemu_instructions"]
    if ins:
        out.append(f"## Cortex-M4 instructions per frame (QEMU mps2-an386, -icount shift=0, arm-none-eabi-g++ -O2)")
        out.append("")
        out.append("Parse: the stream parser (chunk framing and CRC-32C checks); entropy: the image decoder's "
                   "arithmetic decoding of coefficients; transform: dequantisation and the integer IDCT; colour: "
                   "colour conversion to RGB565 bands and the rest of the decoder; display: the CRC-32C of every "
                   "displayed band (this board has no panel).")
        out.append("")
        out.append("| frame | parse | entropy | transform | colour | display | total | instr/pixel | frames/s at %g MHz |"
                   % a.mhz)
        out.append("|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        sums = [0] * 5
        for i, (p, d, s, e, t) in enumerate(ins):
            tot = p + d + s
            row = (p, e, t, d - e - t, s)
            sums = [x + y for x, y in zip(sums, row)]
            out.append(f"| {i} | " + " | ".join(f"{v:,}" for v in row) +
                       f" | {tot:,} | {tot / pixels:.1f} | {a.mhz * 1e6 / tot:.1f} |")
        mean = [v / len(ins) for v in sums]
        tot = sum(mean)
        out.append("| mean | " + " | ".join(f"{v:,.0f}" for v in mean) +
                   f" | {tot:,.0f} | {tot / pixels:.1f} | {a.mhz * 1e6 / tot:.1f} |")
        out.append("")
        mp, me, mt, mc, ms = (v / pixels for v in mean)
        out.append(f"Per pixel: parse {mp:.1f}, entropy {me:.1f}, transform {mt:.1f}, colour {mc:.1f}, display {ms:.1f} "
                   f"instructions. Anchor: TJpgDec decodes a 240x180 baseline JPEG at {ANCHOR_TJPGDEC} "
                   f"instructions/pixel; parse + decode here is {(mp + me + mt + mc) / ANCHOR_TJPGDEC:.2f} x that.")
        out.append("")
    st = stats_line(r["serve_qemu"])
    size = subprocess.run(["arm-none-eabi-size", "-A", a.elf], capture_output=True, text=True).stdout
    secs = {m.group(1): int(m.group(2)) for m in re.finditer(r"^(\.\w+)\s+(\d+)", size, re.M)}
    flash = sum(secs.get(s, 0) for s in (".vectors", ".text", ".rodata", ".data", ".ARM.exidx"))
    ram = secs.get(".data", 0) + secs.get(".bss", 0)
    out.append("## Flash and RAM of the client firmware (Cortex-M4 build)")
    out.append("")
    out.append("| component | flash bytes | RAM bytes (static) |")
    out.append("|---|---:|---:|")
    for comp, v in sorted(map_sizes(a.map).items(), key=lambda kv: -kv[1]["flash"]):
        out.append(f"| {comp} | {v['flash']:,} | {v['ram']:,} |")
    out.append(f"| **total** (`arm-none-eabi-size`) | **{flash:,}** | **{ram:,}** |")
    out.append("")
    if st:
        shown, late, sbytes, ws_hw, ws_budget, stack_hw = st
        other = ram - ws_budget  # link state, ring buffers, application state
        minimum = other + ws_hw + stack_hw
        out.append(f"Static RAM (.data + .bss) holds the {ws_budget:,}-byte workspace (`VDS_WORKSPACE_BYTES`); the "
                   f"{secs.get('.stack', 0):,}-byte stack region comes on top. Measured in this run: workspace "
                   f"high-water {ws_hw:,} bytes (link buffers, stream parser with its chunk buffer, image decoder, "
                   f"one band of RGB565), stack high-water {stack_hw:,} bytes.")
        out.append("")
        out.append(f"**Minimum RAM for this stream: {minimum:,} bytes ({minimum / 1024:.1f} KiB)** = static data "
                   f"outside the workspace ({other:,}) + workspace high-water ({ws_hw:,}) + stack high-water "
                   f"({stack_hw:,}).")
        out.append("")
        if a.budget:
            b = json.load(open(a.budget))
            m4 = b["cortex-m4"]["plays"]
            out += ["## The smallest budget the stream plays in", "",
                    "Found by bisection on each board (`scripts/sim.py` with a workspace budget: `--workspace` on the "
                    "host board, a semihosting argument on the QEMU board), every frame's CRC checked at each step:",
                    "", "| board | plays with | refused with |", "|---|---:|---:|"]
            for name in ("host", "cortex-m4"):
                out.append(f"| {name} | {b[name]['plays']:,} bytes | {b[name]['refused']:,} bytes |")
            out += ["", f"On the Cortex-M4 the whole client then needs {other:,} bytes of other static data + {m4:,} of "
                    f"workspace + the stack (high-water above): **{other + m4:,} bytes plus stack**. (The host "
                    "board's workspace is larger: pointers are 8 bytes there.)", ""]
    if a.images_dir:
        out.append("## Frames")
        out.append("")
        out.append(f"![contact sheet]({a.images_dir}/contact_sheet.png)")
        out.append("")
    print("\n".join(out))


if __name__ == "__main__":
    main()
