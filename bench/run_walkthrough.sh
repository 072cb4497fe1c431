#!/usr/bin/env bash
# The walkthrough mode against the video codecs, on the same tours and the
# same ground truth (bench/run_walk_video.sh must have run: its
# walk_anchors.json and tours are read), written to
# bench/results/walkthrough.md and walkthrough_rd.png:
#   per map, `vds encode-walk MAP --path TOUR --rate R` at 8, 16 and 32
#   kbit/s (two views, threshold THRESHOLD): the stream's kbit/s with its
#   parts (header, views, geometry, frame records), view updates, the
#   client's PSNR over R, G, B pooled and its worst frame against the
#   ground truth, next to each video codec's PSNR at the same rate; per
#   map at 16 kbit/s a contact sheet (ground truth | vds | SVT-AV1 | x264,
#   walkthrough_<map>_frames.jpg) and per-frame PSNR and bits (walkthrough_<map>_psnr.png:
#   vds's from `vds encode-walk --per-frame`, each frame's views and its part of its record; the
#   video codecs' their packets' sizes in display order, from ffprobe).
# The video encodes must be in WORK: run_walk_video.sh's rate-16 SVT-AV1 and x264 streams.
#
# Usage: bench/run_walkthrough.sh [BUILD_DIR]   (default build/host-release)
#   MAPS="oa_dm4 oa_dm5 oa_rpg3dm2"; THRESHOLD=18; WORK (default BUILD_DIR/walk).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-build/host-release}
case "$BUILD" in /*) ;; *) BUILD="$ROOT/$BUILD" ;; esac
VDS="$BUILD/encoder/vds"
WORK=${WORK:-$BUILD/walk}
RESULTS=${RESULTS:-$ROOT/bench/results}
PY=/usr/bin/python3
[ -f "$RESULTS/walk_anchors.json" ] || { echo "run_walkthrough: run bench/run_walk_video.sh first" >&2; exit 1; }
for map in ${MAPS:-oa_dm4 oa_dm5 oa_rpg3dm2}; do
  [ -f "$WORK/$map/tour.txt" ] || { echo "run_walkthrough: $WORK/$map/tour.txt missing (bench/run_walk_video.sh)" >&2; exit 1; }
  for rate in 8 16 32; do
    # REUSE=1: streams encoded by an earlier run are kept.
    [ "${REUSE:-0}" = 1 ] && [ -s "$WORK/$map/walk_$rate.txt" ] && [ -s "$WORK/$map/walk_$rate.y4m" ] && [ -s "$WORK/$map/walk_$rate.csv" ] && continue
    echo "== $map at $rate kbit/s"
    "$VDS" encode-walk "$map" --path "$WORK/$map/tour.txt" --rate "$rate" --threshold "${THRESHOLD:-18}" \
      -o "$WORK/$map/walk_$rate.vds" --y4m "$WORK/$map/walk_$rate.y4m" --per-frame "$WORK/$map/walk_$rate.csv" 2>/dev/null \
      | tee "$WORK/$map/walk_$rate.txt"
  done
done
VDS="$VDS" BENCH_DIR="$ROOT/bench" $PY - "$WORK" "$RESULTS" "${THRESHOLD:-18}" ${MAPS:-oa_dm4 oa_dm5 oa_rpg3dm2} <<'PY'
import json, math, os, re, sys
work, results, threshold, maps = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
sys.path.insert(0, os.environ["BENCH_DIR"])
from walk_anchors import at_rate  # noqa: E402  (the same reading of each codec's points)
anchors = json.load(open(os.path.join(results, "walk_anchors.json")))["maps"]

rows, plot = [], {}
for m in maps:
    for rate in (8, 16, 32):
        t = open(os.path.join(work, m, f"walk_{rate}.txt")).read()
        k = re.search(r"(\d+) bytes = ([\d.]+) kbit/s.*header (\d+), views (\d+) \((\d+) updates at quality (\d+) to (\d+), mean (\d+)"
                      r"[^)]*\), geometry (\d+), frames (\d+)", t)
        q = re.search(r"(\d+) bytes of workspace; PSNR R,G,B ([\d.]+) dB pooled, ([\d.]+) dB worst", t)
        sch = re.search(r"pre-roll ([\d.]+) s at (\d+) bytes/s", t)  # none: untimed (no schedule fits the rate)
        first = int(re.search(r"the first frame's data (\d+) bytes", t)[1])
        size, kb = int(k[1]), float(k[2])
        hdr, views, ups, qlo, qhi, qmean, geo, frm = map(int, k.groups()[2:])
        dur = anchors[m]["frames"] / 20
        part = lambda b: b * 8 / dur / 1000
        best = {c: at_rate([p for p in anchors[m]["points"] if p["codec"] == c], kb) for c in ("x264", "x265", "svt-av1", "aom-av1")}
        rows.append((m, rate, kb, part(views), part(geo), part(frm), hdr, ups, f"{qlo}-{qhi} ({qmean})", int(q[1]), float(q[2]),
                     float(q[3]), best, float(sch[1]) if sch else None, first, size))
        plot.setdefault(m, []).append((kb, float(q[2])))
L = ["# Walkthrough mode against the video codecs\n",
     f"Produced by `bench/run_walkthrough.sh` (THRESHOLD={threshold}) on the tours and ground truth of "
     "`bench/run_walk_video.sh` (`walk_anchors.md`): 600 frames, 240x180, 20 frames/s. vds: `vds encode-walk MAP --path "
     "TOUR --rate R --threshold T` (two views; each view's image quality set by the rate control: every frame's data in "
     "time with a pre-roll of at most 1 s on a link of rate R into the client's 4 KiB window, or where no quality "
     "brings every frame in time within 1 s, the least pre-roll there is plus 1 s); PSNR over R, G, B of "
     "what the client library shows (RGB565, as the boards display it) against the ground truth. Video codecs: their "
     "PSNR at vds's rate, read off each codec's points in `walk_anchors.json` (linear in log-rate; '-' outside them).\n",
     "| map | target | vds kbit/s | views | geometry | frame records | header B | view updates | quality (mean) | pre-roll s | client workspace B | vds PSNR | worst frame | x264 | x265 | SVT-AV1 | libaom |",
     "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
pre_s = lambda p: "untimed" if p is None else f"{p:.3f}"
for (m, rate, kb, v, g, f, hdr, ups, qual, ws, psnr, worst, best, pre, first, size) in rows:
    fmt = lambda x: "-" if x is None else f"{x:.2f}"
    L.append(f"| {m} | {rate} | {kb:.2f} | {v:.2f} | {g:.2f} | {f:.2f} | {hdr} | {ups} | {qual} | {pre_s(pre)} | {ws} | {psnr:.2f} | {worst:.2f} | "
             f"{fmt(best['x264'])} | {fmt(best['x265'])} | {fmt(best['svt-av1'])} | {fmt(best['aom-av1'])} |")
L.append("")
# Starting: the stream's first frame against downloading the scene's own files.
L.append("## Starting at 2 KB/s\n")
L.append("The 16 kbit/s stream's first frame needs its header, first views and first geometry; the client shows it at "
         "the stated pre-roll. Downloading the scene instead: its texture files and lightmaps as `vds info MAP` counts them, "
         "and its geometry as 32-bit floats (position, texture and lightmap coordinates) with 16-bit indices.\n")
L.append("| map | first frame's data B | pre-roll s | the scene's textures B | lightmaps B | geometry B | its download at 2 KB/s |")
L.append("|---|---:|---:|---:|---:|---:|---:|")
import subprocess as sp
at16 = [r for r in rows if r[1] == 16]
for (m, rate, kb, v, g, f, hdr, ups, qual, ws, psnr, worst, best, pre, first, size) in at16:
    info = sp.run([os.environ["VDS"], "info", m], capture_output=True, text=True).stdout
    tex = int(re.search(r"textures .* (\d+) bytes in their files", info)[1])
    lm = int(re.search(r"lightmaps .*\((\d+) bytes\)", info)[1])
    tv = re.search(r"triangles\s+(\d+) .*, (\d+) vertices", info)
    geo_b = int(tv[2]) * 28 + int(tv[1]) * 6
    L.append(f"| {m} | {first:,} | {pre_s(pre)} | {tex:,} | {lm:,} | {geo_b:,} | {(tex + lm + geo_b) / 2000 / 60:.0f} min |")
L.append("")
# The paper's Table 1 form (Cohen-Or et al.: 240x180; VDS against MPEG).
L.append("## The paper's Table 1 form\n")
L.append("Size (header: the data before the first frame), RMS over R, G, B (0-255), bits a pixel and a second, at 16 kbit/s; "
         "the video codecs at vds's rate. The paper's rows (its own VDS and MPEG-1 at two rates, 240x180) follow.\n")
L.append("| animation (frames) | codec | size (header) | RMS (0-255) | bits/pix | bits/sec |")
L.append("|---|---|---:|---:|---:|---:|")
for (m, rate, kb, v, g, f, hdr, ups, qual, ws, psnr, worst, best, pre, first, size) in at16:
    frames = anchors[m]["frames"]
    rms = lambda p: 255 / 10 ** (p / 20)
    bits = size * 8
    L.append(f"| {m} ({frames}) | vds | {size / 1000:.0f}K ({first / 1000:.1f}K) | {rms(psnr):.2f} | {bits / (frames * 240 * 180):.4f} | {bits / (frames / 20):.0f} |")
    for c in ("svt-av1", "x264"):
        if best[c] is not None:
            L.append(f"| {m} ({frames}) | {c} at the same rate | {size / 1000:.0f}K | {rms(best[c]):.2f} | {bits / (frames * 240 * 180):.4f} | {bits / (frames / 20):.0f} |")
for name, frames, rowsp in (("Arts", 435, (("VDS", "80K (23K)", 18.6, 0.034, 29511), ("MPEG", "1600K", 19.2, 1.61, 619168), ("MPEG", "200K", 31, 0.085, 73766))),
                            ("Gallery", 1226, (("VDS", "111K (30K)", 19.15, 0.0168, 14563), ("MPEG", "1830K", 20.03, 0.277, 239436), ("MPEG", "333K", 27.41, 0.05, 43523))),
                            ("Office", 1101, (("VDS", "177K (72K)", 22.47, 0.03, 25722), ("MPEG", "2000K", 22.60, 0.336, 290644), ("MPEG", "337K", 34.71, 0.056, 48937)))):
    for (c, sz, rms_, bpp, bps) in rowsp:
        L.append(f"| paper: {name} ({frames}) | {c} | {sz} | {rms_} | {bpp} | {bps} |")
L.append("")
L.append("A row whose vds kbit/s is above its target did not reach it: with the views at the lowest quality the "
         "geometry and frame records alone exceed it. 'untimed': no pre-roll brings every frame in time at the rate "
         "(what follows a frame record must fit the client's window: geometry bursts on entering large rooms), so the "
         "client shows each frame when its data is whole and the views keep only the average within the rate. The goal — at 16 kbit/s the best video codec + 1 dB — is not "
         "reached on any map; docs/walkthrough.md says where the bits go and what comes next.\n")
L.append("![rate-distortion](walkthrough_rd.png)\n")
open(os.path.join(results, "walkthrough.md"), "w").write("\n".join(L))
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
fig, axes = plt.subplots(1, len(maps), figsize=(5.5 * len(maps), 4.5), squeeze=False)
for ax, m in zip(axes[0], maps):
    for c in ("x264", "x265", "svt-av1", "aom-av1"):
        pts = sorted((p["kbps"], p["psnr_rgb"]) for p in anchors[m]["points"] if p["codec"] == c)
        ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", markersize=3, label=c)
    ax.plot([p[0] for p in plot[m]], [p[1] for p in plot[m]], "s-", color="black", label="vds walkthrough")
    ax.set_xscale("log"); ax.set_xlabel("kbit/s"); ax.set_ylabel("PSNR R,G,B (dB)"); ax.set_title(m)
    ax.grid(True, which="both", lw=0.3); ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig(os.path.join(results, "walkthrough_rd.png"), dpi=110)

# At 16 kbit/s: what each shows, side by side, and PSNR frame by frame.
import subprocess
import numpy as np
from PIL import Image
W, H = 240, 180

def y4m_rgb(path):
    raw = open(path, "rb").read()
    pos, n, out = raw.index(b"\n") + 1, W * H, []
    while pos < len(raw):
        pos = raw.index(b"\n", pos) + 1
        p = np.frombuffer(raw, np.uint8, 3 * n, pos).reshape(3, H, W).astype(np.float32)
        y, cb, cr = p[0], p[1] - 128, p[2] - 128
        out.append(np.stack([y + 1.402 * cr, y - 0.344136 * cb - 0.714136 * cr, y + 1.772 * cb], -1).clip(0, 255).round())
        pos += 3 * n
    return np.array(out, np.uint8)

def decoded(path, fmt):
    raw = subprocess.run(["ffmpeg", "-hide_banner", "-loglevel", "error", "-f", fmt, "-i", path, "-fps_mode", "passthrough",
                          "-sws_flags", "bicubic+accurate_rnd+full_chroma_int", "-f", "rawvideo", "-pix_fmt", "rgb24", "-"],
                         check=True, stdout=subprocess.PIPE).stdout
    return np.frombuffer(raw, np.uint8).reshape(-1, H, W, 3)

def packet_bits(path, fmt):
    # Each frame's packet, in display order: kbit. An AV1 temporal unit shows exactly one frame, so its
    # packets are in display order already; H.264's are reordered: the decoded frames' packet sizes.
    entry = "packet=size" if fmt == "obu" else "frame=pkt_size"
    out = subprocess.run(["ffprobe", "-hide_banner", "-loglevel", "error", "-f", fmt, "-i", path, "-select_streams", "v:0",
                          "-show_entries", entry, "-of", "csv=p=0"], check=True, stdout=subprocess.PIPE, text=True).stdout
    return np.array([int(x) for x in out.split() if x.strip().isdigit()]) * 8 / 1000

def psnr(a, b):
    m = ((a.astype(np.float32) - b.astype(np.float32)) ** 2).mean(axis=(1, 2, 3))
    return 10 * np.log10(255 ** 2 / np.maximum(m, 1e-9))

for m in maps:
    d = os.path.join(work, m)
    gt = np.fromfile(os.path.join(d, "gt.rgb"), np.uint8).reshape(-1, H, W, 3)
    rows = {"ground truth": gt, "vds walkthrough": y4m_rgb(os.path.join(d, "walk_16.y4m")),
            "SVT-AV1": decoded(os.path.join(d, "svt-av1_rate16.obu"), "obu"), "x264": decoded(os.path.join(d, "x264_rate16.h264"), "h264")}
    picks = [int(i) for i in np.linspace(0, len(gt) - 1, 5)[1:]]
    sheet = Image.new("RGB", (W * len(picks) + 4 * (len(picks) - 1), H * len(rows) + 4 * (len(rows) - 1)), (128, 128, 128))
    for r, (name, frames) in enumerate(rows.items()):
        for c, f in enumerate(picks):
            sheet.paste(Image.fromarray(frames[f]), (c * (W + 4), r * (H + 4)))
    sheet.save(os.path.join(results, f"walkthrough_{m}_frames.jpg"), quality=88)
    # The whole tour side by side (ground truth | vds | SVT-AV1), in the work directory.
    video = os.path.join(d, "side_by_side_16.mp4")
    enc = subprocess.Popen(["ffmpeg", "-hide_banner", "-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s",
                            f"{3 * W + 8}x{H}", "-r", "20", "-i", "-", "-c:v", "libx264", "-crf", "16", "-pix_fmt", "yuv420p", video],
                           stdin=subprocess.PIPE)
    gap = np.full((H, 4, 3), 128, np.uint8)
    for f in range(len(gt)):
        enc.stdin.write(np.concatenate([gt[f], gap, rows["vds walkthrough"][f], gap, rows["SVT-AV1"][f]], 1).tobytes())
    enc.stdin.close()
    if enc.wait() != 0:
        raise SystemExit("run_walkthrough: ffmpeg could not write " + video)
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(9, 5.6), sharex=True)
    for name, frames in list(rows.items())[1:]:
        ax.plot(psnr(frames, gt), lw=0.8, label=name)
    ax.set_ylabel("PSNR R,G,B (dB)"); ax.set_title(f"{m} at 16 kbit/s, frame by frame")
    ax.grid(True, lw=0.3); ax.legend(fontsize=7)
    per_frame = np.loadtxt(os.path.join(d, "walk_16.csv"), delimiter=",", skiprows=1)
    bits = {"vds walkthrough": per_frame[:, 1] * 8 / 1000, "SVT-AV1": packet_bits(os.path.join(d, "svt-av1_rate16.obu"), "obu"),
            "x264": packet_bits(os.path.join(d, "x264_rate16.h264"), "h264")}
    for name, kbit in bits.items():
        bx.plot(kbit, lw=0.8, label=name)
    bx.set_yscale("log"); bx.set_xlabel("frame"); bx.set_ylabel("kbit a frame"); bx.grid(True, lw=0.3); bx.legend(fontsize=7)
    fig.tight_layout(); fig.savefig(os.path.join(results, f"walkthrough_{m}_psnr.png"), dpi=100)
    L.append(f"## {m} at 16 kbit/s\n")
    L.append(f"Rows: ground truth, vds walkthrough, SVT-AV1, x264; columns: frames {', '.join(map(str, picks))}. The whole "
             f"tour side by side (ground truth, vds, SVT-AV1): `WORK/{m}/side_by_side_16.mp4`.\n")
    L.append(f"![{m} frames](walkthrough_{m}_frames.jpg)\n")
    L.append(f"![{m} per-frame PSNR](walkthrough_{m}_psnr.png)\n")
open(os.path.join(results, "walkthrough.md"), "w").write("\n".join(L))
print("\n".join(L))
PY
