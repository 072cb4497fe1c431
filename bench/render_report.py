#!/usr/bin/env python3
"""Writes bench/results/render.md from the files bench/run_render.sh collects
in $WORK (see that script for what each holds)."""
import datetime
import os
import platform
import re

work = os.environ["WORK"]
out_path = os.environ["OUT"]


def read(name):
    p = os.path.join(work, name)
    return open(p).read() if os.path.exists(p) else ""


def kv(line):
    return dict(re.findall(r"(\w+)=([^ ]+)", line))


# label -> dict(ir, frames, pixels, crc, ...)
host = {}
order = []
for line in read("host.txt").splitlines():
    parts = line.split(" ", 3)
    label, ir, frames = parts[0], int(parts[1]), int(parts[2])
    d = kv(parts[3])
    d["x86"] = ir / frames
    host[label] = d
    order.append(label)

m4 = {}
m4_skipped = []
calib = ""
for line in read("m4.txt").splitlines():
    d = kv(line)
    if line.startswith("m4 case="):
        m4[d["case"]] = d
    elif line.startswith("skip render "):
        m4_skipped.append(d.get("case", "?"))
    elif line.startswith("m4 counter"):
        calib = f"board counter from the 25 MHz timer, {d['resolution']} instructions per tick"

cases = {l.split()[0]: l.split()[1:] for l in read("cases.txt").splitlines() if l.strip()}


def per_frame(label, target):
    if target == "x86":
        return host[label]["x86"] if label in host else None
    return float(m4[label]["instr_per_frame"]) if label in m4 else None


def pixels(label):
    return int(host[label]["pixels"]) if label in host else 0


def marginal(a, b, target):
    """Instructions per extra pixel between case a and the wider case b."""
    fa, fb = per_frame(a, target), per_frame(b, target)
    if fa is None or fb is None:
        return None
    return (fb - fa) / (pixels(b) - pixels(a))


def fmt(v, digits=1):
    return "n/a" if v is None else f"{v:,.{digits}f}"


o = []
o.append("# Client renderer: accuracy and cost\n")
o.append(f"Produced by `bench/run_render.sh {os.environ.get('BUILD_ARG', '')}` on {datetime.date.today().isoformat()}, "
         "after `cmake -S . -B <build> -G Ninja -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ "
         "-DCMAKE_BUILD_TYPE=Release -DVDS_BUILD_FIRMWARE=OFF && cmake --build <build> --target bench_render` and, "
         "for the Cortex-M4 firmware, `cmake -S . -B <cm4 build> -G Ninja "
         "-DCMAKE_TOOLCHAIN_FILE=toolchain/arm-none-eabi-cortex-m4.cmake -DCMAKE_BUILD_TYPE=Release && "
         "cmake --build <cm4 build> --target vds_fw_bench_render` (the `cortex-m4` preset does the same in "
         "build/cortex-m4). "
         "Design, fixed-point formats and error bounds: `docs/renderer.md`.\n")
o.append("## Machine and tools\n")
o.append(f"- host: {os.environ['CPU']}, {platform.machine()}, Linux {platform.release()}")
o.append(f"- host compiler: {os.environ['HOSTCXX']}, build type {os.environ.get('BUILD_TYPE') or '?'} "
         f"(`{os.path.relpath(os.environ['BENCH'])}`)")
o.append(f"- {os.environ['VG']} (callgrind, `--toggle-collect='*measured_render*'`: the render calls only)")
o.append(f"- Cortex-M4 compiler: {os.environ['ARMCXX']} (`-O2 -mcpu=cortex-m4 -mthumb -mfloat-abi=soft`, "
         "the flags of the project's Cortex-M4 build)")
o.append(f"- QEMU: {os.environ['QEMU']} (`-M mps2-an386 -icount shift=0`, the QEMU board of `firmware_sim/` "
         f"running `vds_fw_bench_render` from `{os.environ.get('ELF_REL', '?')}`; {calib or 'no counter'})\n")

o.append("## Accuracy against the double-precision reference (240x180)\n")
o.append("`bench_render accuracy`: each scene rendered by `vds::Renderer` and by `enc::ref_render` from the same "
         "texels (the reference samples what the client samples: 565-rounded texels for rgb565, the decoded planes "
         "for ycbcr420). With rgb565 output the reference is rounded to 5/6/5 bits first. `cube-from-view` draws "
         "every face of the cube scene from a stored view (an image of the scene from another camera) through the "
         "fixed-point plane homography. Goal: PSNR >= 45 dB.\n")
o.append(read("accuracy.md").strip() + "\n")
o.append("Side by side (reference | client | absolute difference x 16, 2x enlarged), rgb888 output, 32-bit depth, "
         "xrgb8888 textures: `render_cube.png`, `render_terrain.png`, `render_room.png`, "
         "`render_cube-from-view.png`. The large maximum errors are single pixels on edges where a pixel centre lies "
         "within 1/512 pixel of an edge, so the 1/256-pixel vertex positions decide it differently, and depth ties "
         "where surfaces meet.\n")

o.append("## Cost per frame and per pixel\n")
o.append("Every case is a file written by `bench_render cases` (the list is in `bench/src/render.cpp`); the "
         "x86-64 run (`bench_render frames FILE`) and the Cortex-M4 run (firmware `vds_fw_bench_render`, "
         "`firmware_sim/app/bench_render.cpp`, on the QEMU board) read the same file. Measured frames go to a band "
         "sink that does nothing (a display DMA would take the band); one more frame goes to a sink that computes "
         "the frame's CRC-32C band by band. *pixels* are pixels rasterised (z-tested); per pixel = per frame / "
         "pixels. x86-64 counts are callgrind's Ir on the host build and only a proxy: the goals are about the "
         "Cortex-M4, counted as executed instructions (not cycles) under QEMU. Cases with a set-up cache use 16 "
         "entries (`RenderConfig::setup_cache`) when the cache column is not 0. The board's RAM budget (256 KiB "
         "with the stack) holds the case file and the workspace; cases that do not fit are skipped there "
         "(n/a)" + (": " + ", ".join(m4_skipped) if m4_skipped else "") + ".\n")
o.append("| case | scene | texture | output | depth | band rows | vertex cache | filter | pixels | x86-64 instr/frame | "
         "x86-64 instr/pixel | Cortex-M4 instr/frame | Cortex-M4 instr/pixel | frame CRC-32C | M4 = x86-64 |")
o.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
all_match = True
for label in order:
    h = host[label]
    scene, tex, outf, depth, band, cache, filt = cases[label]
    px = int(h["pixels"])
    x = h["x86"]
    m = per_frame(label, "m4")
    match = "n/a"
    if label in m4:
        match = "yes" if m4[label]["crc"] == h["crc"] else "**no**"
        all_match = all_match and match == "yes"
    o.append(f"| {label} | {scene} | {tex} | {outf} | {depth} | {band} | {cache} | {filt} | {px:,} | {fmt(x, 0)} | "
             f"{fmt(x / px if px else None)} | {fmt(m, 0)} | {fmt(m / px if (m and px) else None)} | {h['crc']} | {match} |")
o.append("")
if m4:
    o.append(f"Bit-exact across targets (every frame's CRC-32C equal on x86-64/clang and Cortex-M4/gcc): "
             f"{'yes, every case run on both' if all_match else '**no**'}. The golden cases are the frames "
             "`tests/unit/render_test.cpp` (RenderGolden) checks; the ctest `render_host_equals_cortex_m4` "
             "compares every case's CRC between the host board and the Cortex-M4 board.\n")

o.append("### Against the goals (textured, per-pixel perspective-correct, z-tested pixels)\n")
o.append("The anchor: small3dlib draws a textured, per-pixel perspective-correct, 32-bit z-buffered scene at 115 "
         "Cortex-M4 instructions per shaded pixel (nearest texel), measured in QEMU mps2-an386 with -icount. "
         "*Marginal* is the cost of one more pixel (quad480 minus quad: same rows, twice the pixels); *all-in* "
         "divides the whole frame (band clearing, clipping and set-up included) by its pixels.\n")
o.append("| filter | goal (Cortex-M4 instr/pixel) | M4 marginal | M4 all-in, 32-bit depth | M4 all-in, 16-bit depth | "
         "x86-64 marginal | x86-64 all-in, 32-bit depth |")
o.append("|---|---|---|---|---|---|---|")


def all_in(label, target):
    f = per_frame(label, target)
    return f / pixels(label) if (f and pixels(label)) else None


for filt, goal in (("nearest", 58), ("bilinear", 75)):
    a, b, c = f"quad-{filt}-d32-b16", f"quad480-{filt}-d32-b16", f"quad-{filt}-d16-b16"
    o.append(f"| {filt} | <= {goal} | {fmt(marginal(a, b, 'm4'))} | {fmt(all_in(a, 'm4'))} | {fmt(all_in(c, 'm4'))} | "
             f"{fmt(marginal(a, b, 'x86'))} | {fmt(all_in(a, 'x86'))} |")
o.append("")
o.append("Settings: 16-row bands, rgb565 texture (256x256, repeat, with the one-texel apron of `vds::Texture::apron`), "
         "rgb565 output, 16-entry set-up cache. All-in divides the whole frame (band clearing, clipping, set-up, "
         "span set-up) by its pixels. A 240x180 frame at 20 frames/s on a 100 MHz Cortex-M4 has 5 M cycles per frame; "
         "the table gives instructions, and Cortex-M4 cycles per instruction are somewhat above 1 "
         "(loads, multiplies and taken branches cost extra cycles).\n")

o.append("## Cortex-M4 code size and stack\n")
o.append("`arm-none-eabi-size` of the renderer objects (`-O2`), with every format compiled in (default "
         "`vds/config.h`) and with only rgb565 textures, rgb565 output and 16-bit depth "
         "(`-DVDS_CONFIG_RENDER_TEXTURE_FORMATS=1 -DVDS_CONFIG_RENDER_OUTPUT_FORMATS=1 "
         "-DVDS_CONFIG_RENDER_DEPTH_FORMATS=1`).\n")


def size_table(text):
    rows = []
    total = 0
    for line in text.splitlines()[1:]:
        f = line.split()
        if len(f) >= 6:
            rows.append((f[5], int(f[0]), int(f[1]), int(f[2])))
            total += int(f[0])
    return rows, total


full, _ = size_table(read("size.txt"))
mini, _ = size_table(read("size_min.txt"))
mini_map = {r[0]: r[1] for r in mini}
o.append("| object | .text (all formats) | .text (rgb565 only) |")
o.append("|---|---|---|")
t_full = t_min = 0
for name, text, _, _ in full:
    small = mini_map.get(name, text)  # homography.o does not depend on the formats
    t_full += text
    t_min += small
    o.append(f"| {name} | {text:,} | {small:,} |")
o.append(f"| **total** | **{t_full:,}** | **{t_min:,}** |")
o.append("")
stack = {}
for line in read("stack.txt").splitlines():
    f = line.split("\t")
    if len(f) >= 2:
        # file:line:column:function
        name = f[0].split(":", 3)[-1]
        stack[name] = max(stack.get(name, 0), int(f[1]))


def frame_of(pattern):
    return max((n for k, n in stack.items() if pattern in k), default=0)


# The deepest path of a frame: render -> draw_mesh -> draw_faces -> draw_face
# -> draw_polygon -> a span loop -> row_piece (the largest frame of each
# step; a step the compiler inlined has none).
# draw_polygon calls prepare_polygon, then draw_prepared (which calls the
# span loops): the deeper of the two branches counts.
spans = frame_of("draw_prepared") + max(frame_of("texture_span"), frame_of("gouraud_span"), frame_of("flat_span")) \
    + frame_of("row_piece")
chain = [("Renderer::render", frame_of("Renderer::render")), ("RenderFrame::draw_mesh", frame_of("draw_mesh(")),
         ("RenderFrame::draw_faces", frame_of("draw_faces(")), ("RenderFrame::draw_face", frame_of("draw_face(")),
         ("draw_polygon", frame_of("draw_polygon"))]
chain = [(name, n) for name, n in chain if n > 0 or name == "Renderer::render"]
if frame_of("prepare_polygon") >= spans:
    chain.append(("prepare_polygon", frame_of("prepare_polygon")))
else:
    chain += [("draw_prepared", frame_of("draw_prepared")),
              ("span loop (largest)", max(frame_of("texture_span"), frame_of("gouraud_span"), frame_of("flat_span"))),
              ("row_piece", frame_of("row_piece"))]
o.append("Stack (`-fstack-usage`, bytes) along the deepest call path of a frame: "
         + " + ".join(f"{name} {n}" for name, n in chain) + f" = **{sum(n for _, n in chain):,} bytes**"
         + f" (`plane_homography`, called by the application rather than the renderer: {frame_of('plane_homography')}).\n")
undef = [u for u in read("undef.txt").splitlines() if u.strip()]
o.append("Symbols the renderer objects take from outside themselves (the fixed-point functions of "
         "`decoder/src/fixed.cpp`, integer libgcc helpers, memcpy/memset): "
         + ", ".join(f"`{u}`" for u in undef) + "\n")

o.append("## RAM (workspace from the caller's arena)\n")
o.append("`render_workspace_size()`: the band colour buffer (unless the caller renders into its own frame buffer), "
         "the band depth buffer, the projected-vertex cache (13 bytes per vertex), the triangle band-range cache "
         "(4 bytes per triangle) and the set-up cache (one set-up polygon per entry); without the caches vertices "
         "are re-projected, triangles re-tested and large triangles clipped and set up again per band "
         "(same picture; the room case without caches above shows the cost). Goal: band rendering of 240x180 with "
         "16-line bands in <= 16 KiB, bands and depth included.\n")
ram = read("ram.txt")
o.append("\n".join(l for l in ram.splitlines() if l.startswith("|")))
sz = re.search(r"sizeof\(Renderer\)=(\d+)", ram)
o.append("")
if sz:
    ws16 = re.search(r"\| 240x180 \| 16 \| rgb565 \| 16-bit \| 0 \| 0 \| 0 \| in workspace \| (\d+) \|", ram)
    ws16s = re.search(r"\| 240x180 \| 16 \| rgb565 \| 16-bit \| 0 \| 0 \| 2 \| in workspace \| (\d+) \|", ram)
    total = int(ws16.group(1)) + int(sz.group(1)) if ws16 else None
    o.append(f"`sizeof(vds::Renderer)` = {sz.group(1)} bytes (the caller's object). 240x180, 16-line bands, "
             f"rgb565, 16-bit depth, no caches: workspace + object = **{total:,} bytes** (goal 16,384: bands and "
             f"depth included); the stack of the deepest call path (previous section) comes on top."
             + (f" With a 2-entry set-up cache (enough for a large quad): {int(ws16s.group(1)) + int(sz.group(1)):,} "
                "bytes." if ws16s else "") + "\n")

open(out_path, "w").write("\n".join(o) + "\n")
