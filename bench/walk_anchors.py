#!/usr/bin/env python3
"""The video codecs to beat on walkthrough ground truth (bench/run_walk_video.sh).

For each map: a tour (`vds path`), its ground truth (`vds render`), then
x264, x265, SVT-AV1, libaom-av1 (through ffmpeg) and Motion-JPEG (cjpeg)
at fixed rates and quality sweeps, each decoded and measured against the
ground truth's exact RGB frames. Writes walk_anchors.md, .json, _rd.png and
a contact sheet per tour into the results folder.
"""
import argparse
import datetime
import json
import math
import os
import platform
import re
import subprocess
import sys
import time

import numpy as np

W, H, FPS = 240, 180, 20
TARGETS = [8, 16, 32]  # kbit/s
SWS = ["-sws_flags", "bicubic+accurate_rnd+full_chroma_int"]


def log(msg):
    print(msg, flush=True)


def run(cmd, **kw):
    return subprocess.run(cmd, check=True, **kw)


def frames_of(path, n):
    a = np.fromfile(path, dtype=np.uint8)
    if a.size != n * H * W * 3:
        raise SystemExit(f"{path}: {a.size} bytes, not {n} frames of {W}x{H} RGB")
    return a.reshape(n, H, W, 3)


def luma(rgb):
    f = rgb.astype(np.float32)
    return 0.299 * f[..., 0] + 0.587 * f[..., 1] + 0.114 * f[..., 2]


def gauss(x):
    """11-tap Gaussian (sigma 1.5) along the last two axes, valid region."""
    t = np.arange(11, dtype=np.float32) - 5
    k = np.exp(-(t * t) / (2 * 1.5 * 1.5))
    k /= k.sum()
    h = x.shape[-2] - 10
    w = x.shape[-1] - 10
    y = sum(k[i] * x[..., :, i:i + w] for i in range(11))
    return sum(k[i] * y[..., i:i + h, :] for i in range(11))


def ssim_sum(a, b):
    c1, c2 = (0.01 * 255) ** 2, (0.03 * 255) ** 2
    ma, mb = gauss(a), gauss(b)
    va = gauss(a * a) - ma * ma
    vb = gauss(b * b) - mb * mb
    cov = gauss(a * b) - ma * mb
    s = ((2 * ma * mb + c1) * (2 * cov + c2)) / ((ma * ma + mb * mb + c1) * (va + vb + c2))
    return float(s.sum(dtype=np.float64)), s.size


def measure(gt, dec):
    if dec.shape != gt.shape:
        raise SystemExit(f"decoded {dec.shape}, ground truth {gt.shape}")
    se_rgb = se_y = 0.0
    ss = 0.0
    count = 0
    for i in range(0, gt.shape[0], 50):
        g, d = gt[i:i + 50], dec[i:i + 50]
        diff = g.astype(np.float32) - d.astype(np.float32)
        se_rgb += float(np.square(diff, dtype=np.float32).sum(dtype=np.float64))
        yg, yd = luma(g), luma(d)
        se_y += float(np.square(yg - yd).sum(dtype=np.float64))
        s, n = ssim_sum(yg, yd)
        ss += s
        count += n
    mse_rgb = se_rgb / gt.size
    mse_y = se_y / (gt.size / 3)
    psnr = lambda m: 10 * math.log10(255 * 255 / m) if m > 0 else float("inf")
    return {"psnr_rgb": psnr(mse_rgb), "psnr_y": psnr(mse_y), "ssim": ss / count}


def obu_payload_bytes(path):
    """Bytes of an AV1 low-overhead OBU stream without temporal delimiters and padding."""
    data = open(path, "rb").read()
    i, total = 0, 0
    while i < len(data):
        start = i
        header = data[i]
        obu_type = (header >> 3) & 15
        ext = (header >> 2) & 1
        has_size = (header >> 1) & 1
        i += 1 + ext
        if not has_size:
            raise SystemExit(f"{path}: an OBU without a size field")
        size = shift = 0
        while True:
            b = data[i]
            i += 1
            size |= (b & 0x7F) << shift
            shift += 7
            if not b & 0x80:
                break
        i += size
        if obu_type not in (2, 15):
            total += i - start
    return total


def jpeg_without_app0(jpg):
    if jpg[2:4] == b"\xff\xe0":
        n = (jpg[4] << 8) | jpg[5]
        return len(jpg) - (2 + n)
    return len(jpg)


class Bench:
    def __init__(self, a):
        self.a = a
        self.results = {"maps": {}, "settings": {}}

    def decode(self, path, fmt, n):
        out = subprocess.run(["ffmpeg", "-hide_banner", "-loglevel", "error", "-f", fmt, "-i", path, "-fps_mode", "passthrough"]
                             + SWS + ["-f", "rawvideo", "-pix_fmt", "rgb24", "-"], check=True, stdout=subprocess.PIPE).stdout
        a = np.frombuffer(out, dtype=np.uint8)
        if a.size != n * H * W * 3:
            raise SystemExit(f"{path}: decoded {a.size // (H * W * 3)} frames, not {n}")
        return a.reshape(n, H, W, 3)

    def ffmpeg_encode(self, rgb, n, codec, mode, value, out_dir):
        """Encodes; returns (stream path, demuxer, stream bytes, commands)."""
        src = ["ffmpeg", "-hide_banner", "-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{W}x{H}",
               "-r", str(FPS), "-i", rgb] + SWS + ["-pix_fmt", "yuv420p"]
        tag = f"{codec}_{mode}{value}"
        log_base = os.path.join(out_dir, tag + "_pass")
        cmds = []
        if codec == "x264":
            path, fmt, bsf = os.path.join(out_dir, tag + ".h264"), "h264", ["-bsf:v", "filter_units=remove_types=6"]
            enc = ["-c:v", "libx264", "-preset", "veryslow", "-tune", "animation"]
            if mode == "rate":
                enc += ["-b:v", f"{value}k"]
                cmds.append(src + enc + ["-pass", "1", "-passlogfile", log_base, "-f", "null", "-"])
                cmds.append(src + enc + ["-pass", "2", "-passlogfile", log_base] + bsf + ["-f", fmt, path])
            else:
                cmds.append(src + enc + ["-crf", str(value)] + bsf + ["-f", fmt, path])
        elif codec == "x265":
            path, fmt, bsf = os.path.join(out_dir, tag + ".hevc"), "hevc", ["-bsf:v", "filter_units=remove_types=39|40"]
            enc = ["-c:v", "libx265", "-preset", "veryslow"]
            if mode == "rate":
                enc += ["-b:v", f"{value}k"]
                cmds.append(src + enc + ["-x265-params", f"pass=1:stats={log_base}.log:log-level=error", "-f", "null", "-"])
                cmds.append(src + enc + ["-x265-params", f"pass=2:stats={log_base}.log:log-level=error"] + bsf + ["-f", fmt, path])
            else:
                cmds.append(src + enc + ["-crf", str(value), "-x265-params", "log-level=error"] + bsf + ["-f", fmt, path])
        elif codec == "svt-av1":
            path, fmt = os.path.join(out_dir, tag + ".obu"), "obu"
            enc = ["-c:v", "libsvtav1", "-preset", str(self.a.svt_preset)]
            enc += ["-b:v", f"{value}k"] if mode == "rate" else ["-crf", str(value)]
            cmds.append(src + enc + ["-f", fmt, path])
        elif codec == "aom-av1":
            path, fmt = os.path.join(out_dir, tag + ".obu"), "obu"
            enc = ["-c:v", "libaom-av1", "-cpu-used", str(self.a.aom_cpu)]
            if mode == "rate":
                enc += ["-b:v", f"{value}k"]
                cmds.append(src + enc + ["-pass", "1", "-passlogfile", log_base, "-f", "null", "-"])
                cmds.append(src + enc + ["-pass", "2", "-passlogfile", log_base, "-f", fmt, path])
            else:
                cmds.append(src + enc + ["-crf", str(value), "-b:v", "0", "-f", fmt, path])
        else:
            raise ValueError(codec)
        for c in cmds:
            run(c, stderr=subprocess.DEVNULL if codec == "svt-av1" else None)
        size = obu_payload_bytes(path) if fmt == "obu" else os.path.getsize(path)
        return path, fmt, size, cmds

    def mjpeg(self, gt, q):
        total = 0
        dec = np.empty_like(gt)
        header = f"P6\n{W} {H}\n255\n".encode()
        for i in range(gt.shape[0]):
            jpg = run(["cjpeg", "-optimize", "-baseline", "-sample", "2x2,1x1,1x1", "-quality", str(q)],
                      input=header + gt[i].tobytes(), stdout=subprocess.PIPE).stdout
            total += jpeg_without_app0(jpg)
            ppm = run(["djpeg", "-dct", "int", "-ppm"], input=jpg, stdout=subprocess.PIPE).stdout
            dec[i] = np.frombuffer(ppm[len(ppm) - W * H * 3:], dtype=np.uint8).reshape(H, W, 3)
        return total, dec

    def map(self, name):
        a = self.a
        work = os.path.join(a.work, name)
        os.makedirs(work, exist_ok=True)
        path = os.path.join(work, "tour.txt")
        info = run([a.vds, "info", name], stdout=subprocess.PIPE, text=True).stdout
        tour = run([a.vds, "path", name, "-o", path, "--frames", str(a.frames), "--sheet", os.path.join(work, "tour.png")],
                   stdout=subprocess.PIPE, text=True).stdout
        t0 = time.time()
        render = run([a.vds, "render", name, "--path", path, "-o", os.path.join(work, "gt")], stdout=subprocess.PIPE,
                     text=True).stdout
        render_s = time.time() - t0
        log(info + tour + render)
        n = a.frames
        rgb = os.path.join(work, "gt.rgb")
        gt = frames_of(rgb, n)
        duration = n / FPS
        points = []
        plan = [("x264", "rate", r) for r in TARGETS] + [("x264", "crf", q) for q in (36, 42, 48, 51)]
        plan += [("x265", "rate", r) for r in TARGETS] + [("x265", "crf", q) for q in (36, 42, 48, 51)]
        plan += [("svt-av1", "rate", r) for r in TARGETS] + [("svt-av1", "crf", q) for q in (50, 56, 60, 63)]
        plan += [("aom-av1", "rate", r) for r in TARGETS] + [("aom-av1", "crf", q) for q in (50, 56, 60, 63)]
        if a.quick:
            plan = [p for p in plan if p[2] in (16, 48, 60)]
        for codec, mode, value in plan:
            t = time.time()
            stream, fmt, size, cmds = self.ffmpeg_encode(rgb, n, codec, mode, value, work)
            enc_s = time.time() - t
            m = measure(gt, self.decode(stream, fmt, n))
            p = {"codec": codec, "mode": mode, "value": value, "bytes": size, "kbps": size * 8 / duration / 1000,
                 "encode_s": enc_s, **m, "commands": [" ".join(c) for c in cmds]}
            points.append(p)
            log(f"{name} {codec} {mode} {value}: {p['kbps']:.2f} kbit/s, {m['psnr_rgb']:.2f} dB RGB, "
                f"{m['psnr_y']:.2f} dB Y, SSIM {m['ssim']:.4f} ({enc_s:.0f} s)")
        for q in ((1, 10) if a.quick else (1, 3, 5, 10, 20, 40)):
            t = time.time()
            size, dec = self.mjpeg(gt, q)
            m = measure(gt, dec)
            p = {"codec": "mjpeg", "mode": "quality", "value": q, "bytes": size, "kbps": size * 8 / duration / 1000,
                 "encode_s": time.time() - t, **m,
                 "commands": [f"cjpeg -optimize -baseline -sample 2x2,1x1,1x1 -quality {q} (each frame)"]}
            points.append(p)
            log(f"{name} mjpeg quality {q}: {p['kbps']:.1f} kbit/s, {m['psnr_rgb']:.2f} dB RGB")
        stats = {}
        for line in info.splitlines():
            m = re.match(r"\s+(faces|triangles|textures|lightmaps|spawn points)\s+(.*)", line)
            if m:
                stats[m.group(1)] = m.group(2)
        self.results["maps"][name] = {"info": stats, "tour": tour.strip(), "render": render.strip(), "render_s": render_s,
                                      "frames": n, "points": points}
        # The contact sheet at half size, as JPEG, for the results.
        try:
            from PIL import Image
            im = Image.open(os.path.join(work, "tour.png"))
            im = im.resize((im.width // 2, im.height // 2), Image.LANCZOS)
            im.convert("RGB").save(os.path.join(a.results, f"walk_{name}_tour.jpg"), quality=85)
        except ImportError:
            raise SystemExit("python3-pil is needed for the contact sheets (scripts/setup.sh installs it)")


def at_rate(points, kbps):
    """PSNR at `kbps` on the codec's upper envelope, linear in log-rate; None outside its range."""
    pts = sorted((p["kbps"], p["psnr_rgb"]) for p in points)
    env = []
    for r, d in pts:
        if env and d <= env[-1][1]:
            continue
        env.append((r, d))
    for (r0, d0), (r1, d1) in zip(env, env[1:]):
        if r0 <= kbps <= r1:
            t = (math.log(kbps) - math.log(r0)) / (math.log(r1) - math.log(r0))
            return d0 + t * (d1 - d0)
    if env and abs(env[0][0] - kbps) < 1e-9:
        return env[0][1]
    return None


CODECS = ["x264", "x265", "svt-av1", "aom-av1", "mjpeg"]
LABEL = {"x264": "x264 veryslow, tune animation", "x265": "x265 veryslow", "svt-av1": "SVT-AV1", "aom-av1": "libaom-av1",
         "mjpeg": "Motion-JPEG"}


def write(results, a, elapsed):
    maps = results["maps"]
    json.dump(results, open(os.path.join(a.results, "walk_anchors.json"), "w"), indent=1)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(maps), figsize=(5.5 * len(maps), 4.5), squeeze=False)
    for ax, (name, m) in zip(axes[0], maps.items()):
        for c in CODECS:
            pts = sorted((p["kbps"], p["psnr_rgb"]) for p in m["points"] if p["codec"] == c)
            if pts:
                ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", label=LABEL[c], markersize=3)
        for r in TARGETS:
            ax.axvline(r, color="grey", lw=0.5)
        ax.set_xscale("log")
        ax.set_xlabel("kbit/s")
        ax.set_ylabel("PSNR R,G,B (dB)")
        ax.set_title(f"{name}: {m['frames']} frames, 240x180, 20 frames/s")
        ax.grid(True, which="both", lw=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(a.results, "walk_anchors_rd.png"), dpi=110)

    ff = subprocess.run(["ffmpeg", "-version"], stdout=subprocess.PIPE, text=True).stdout.splitlines()[0]
    L = []
    L.append("# Walkthrough anchors: the video codecs to beat, on the ground truth\n")
    L.append(f"Produced by `bench/run_walk_video.sh` (MAPS=\"{' '.join(a.maps)}\" FRAMES={a.frames} SVT_PRESET={a.svt_preset} "
             f"AOM_CPU={a.aom_cpu}{' QUICK=1' if a.quick else ''}) on {datetime.date.today()}, {platform.machine()}, "
             f"{os.cpu_count()} cores, in {elapsed / 60:.0f} min; {ff}. Every point, with its commands: "
             "`walk_anchors.json`. How the ground truth is made and measured: `docs/walkthrough.md`.\n")
    L.append("Bitrate = bytes of the elementary stream (H.264 and HEVC Annex B with the encoders' SEI banners removed, AV1 "
             "OBUs without temporal delimiters, JPEG files without their JFIF APP0) x 8 / duration (frames / 20 s). "
             "PSNR over R, G and B pooled over all frames against the exact RGB ground truth (`OUT.rgb`); luma PSNR and "
             "SSIM (BT.601 luma, 11x11 Gaussian window, sigma 1.5) as second measures. The video codecs get the "
             "ground truth converted to Y'CbCr 4:2:0 by ffmpeg (BT.601, bicubic, accurate rounding) and are decoded back "
             "the same way. SVT-AV1 runs one pass: ffmpeg 5.1's libsvtav1 wrapper offers no second.\n")
    L.append("![rate-distortion](walk_anchors_rd.png)\n")
    L.append("## At 8, 16 and 32 kbit/s\n")
    L.append("PSNR R,G,B (dB) on each codec's upper envelope of all its points (rate-targeted and CRF), linear in "
             "log-rate between the two nearest; '-' where its points do not reach the rate.\n")
    L.append("| map | " + " | ".join(f"{LABEL[c]} {r}k" for c in CODECS[:4] for r in TARGETS) + " |")
    L.append("|---|" + "---:|" * (4 * len(TARGETS)))
    for name, m in maps.items():
        cells = []
        for c in CODECS[:4]:
            for r in TARGETS:
                v = at_rate([p for p in m["points"] if p["codec"] == c], r)
                cells.append("-" if v is None else f"{v:.2f}")
        L.append(f"| {name} | " + " | ".join(cells) + " |")
    L.append("")
    L.append("Motion-JPEG's floor (quality 1, the lowest rate cjpeg makes):\n")
    L.append("| map | kbit/s | PSNR R,G,B | PSNR Y | SSIM |")
    L.append("|---|---:|---:|---:|---:|")
    for name, m in maps.items():
        f = min((p for p in m["points"] if p["codec"] == "mjpeg"), key=lambda p: p["kbps"])
        L.append(f"| {name} | {f['kbps']:.1f} | {f['psnr_rgb']:.2f} | {f['psnr_y']:.2f} | {f['ssim']:.4f} |")
    L.append("")
    for name, m in maps.items():
        L.append(f"## {name}\n")
        L.append("Scene (`vds info`):\n")
        for k, v in m["info"].items():
            L.append(f"- {k}: {v}")
        L.append("")
        L.append(f"Tour (`vds path {name}`): {m['tour'].splitlines()[0].split(': ', 1)[1]}\n")
        L.append(f"Ground truth (`vds render`): {m['render'].split(': ', 1)[1]}\n")
        L.append(f"![tour](walk_{name}_tour.jpg)\n")
        L.append("| codec | mode | setting | kbit/s | PSNR R,G,B | PSNR Y | SSIM | encode s |")
        L.append("|---|---|---:|---:|---:|---:|---:|---:|")
        for p in m["points"]:
            L.append(f"| {LABEL[p['codec']]} | {p['mode']} | {p['value']} | {p['kbps']:.2f} | {p['psnr_rgb']:.2f} | "
                     f"{p['psnr_y']:.2f} | {p['ssim']:.4f} | {p['encode_s']:.0f} |")
        L.append("")
    L.append("## Commands\n")
    L.append("One of each kind (the rest differ in the rate or quality; all are in `walk_anchors.json`):\n")
    seen = set()
    first = next(iter(maps.values()))
    for p in first["points"]:
        key = (p["codec"], p["mode"])
        if key in seen:
            continue
        seen.add(key)
        for c in p["commands"]:
            L.append(f"    {c}")
    L.append("")
    open(os.path.join(a.results, "walk_anchors.md"), "w").write("\n".join(L))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--vds", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--results", required=True)
    ap.add_argument("--maps", nargs="+", required=True)
    ap.add_argument("--frames", type=int, default=600)
    ap.add_argument("--svt-preset", type=int, default=1)
    ap.add_argument("--aom-cpu", type=int, default=2)
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    t0 = time.time()
    b = Bench(a)
    for name in a.maps:
        b.map(name)
    write(b.results, a, time.time() - t0)
    log(f"walk anchors: {os.path.join(a.results, 'walk_anchors.md')}")


if __name__ == "__main__":
    main()
