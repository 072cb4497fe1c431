#!/usr/bin/env python3
"""The `vds` command as a user meets it: help, pack, info, and clear errors
(naming the file and what is wrong, non-zero exit, nothing on stdout that
pretends success) for bad input."""
import os
import subprocess
import sys

VDS, TMP = sys.argv[1], sys.argv[2]
os.makedirs(TMP, exist_ok=True)
failures = []


def run(*args):
    r = subprocess.run([VDS, *args], capture_output=True, text=True)
    return r.returncode, r.stdout, r.stderr


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


code, out, err = run("--help")
check(code == 0 and "info" in out and "pack" in out, "vds --help lists the verbs")
code, out, err = run("info", "--help")
check(code == 0 and "FILE" in out, "vds info --help")
code, out, err = run()
check(code == 2, "no verb is a usage error (exit 2)")

payload = os.path.join(TMP, "payload.bin")
with open(payload, "wb") as f:
    f.write(bytes(range(256)) * 4)
stream = os.path.join(TMP, "cli.vds")
code, out, err = run("pack", "-o", stream, "--mode", "model", "--size", "320x240", "--fps", "20",
                     "--max-chunk", "2048", "--workspace", "5000", "--chunk", f"DATA={payload}",
                     "--meta", "title=cli test")
check(code == 0 and os.path.exists(stream), "vds pack writes a stream")

code, out, err = run("info", stream)
check(code == 0, "vds info accepts the packed stream")
check("mode               model" in out and "320x240" in out, "vds info prints mode and size")
check("50000 us per frame" in out, "vds info prints timing")
check("max chunk payload 2048 B" in out and "decoder workspace 5000 B" in out, "vds info prints budgets")
check("DATA" in out and "1024" in out, "vds info lists the chunk and its size")
check("title=cli test" in out, "vds info prints metadata")

code, out, err = run("info", stream, "--workspace", "4096", "--chunk-buffer", "1024")
check(code == 1 and "workspace too small" in err and stream in err,
      "a client too small for the stream is refused with the reason")

with open(stream, "rb") as f:
    data = bytearray(f.read())
bad = os.path.join(TMP, "corrupt.vds")
data[40] ^= 0x10
with open(bad, "wb") as f:
    f.write(data)
code, out, err = run("info", bad)
check(code == 1 and "CRC mismatch" in err and bad in err and "at byte" in err, "corrupt stream: CRC error names file and offset")

trunc = os.path.join(TMP, "truncated.vds")
with open(stream, "rb") as f:
    whole = f.read()
with open(trunc, "wb") as f:
    f.write(whole[:-3])
code, out, err = run("info", trunc)
check(code == 1 and "truncated" in err, "truncated stream is reported as truncated")

notvds = os.path.join(TMP, "not.vds")
with open(notvds, "wb") as f:
    f.write(b"hello world, not a stream")
code, out, err = run("info", notvds)
check(code == 1 and "bad magic" in err, "a file that is not a stream says so")

code, out, err = run("info", os.path.join(TMP, "missing.vds"))
check(code == 1 and "cannot open" in err, "a missing file is named")

before = os.path.getsize(stream)
code, out, err = run("pack", "-o", stream, "--chunk", "TOOLONG=" + payload)
check(code == 2 and "exactly 4 characters" in err and os.path.getsize(stream) == before,
      "bad chunk type is a usage error and leaves the existing output untouched")
code, out, err = run("pack", "-o", stream, "--size", "0x10")
check(code == 2 and "--size" in err, "bad size is a usage error")
code, out, err = run("pack", "-o", stream, "--max-chunk", "100", "--chunk", f"DATA={payload}")
check(code == 1 and "do not fit" in err and os.path.getsize(stream) == before, "oversized chunk refused, output untouched")

# A model with its up axis: stored in MSHH, shown by `info`; a bad axis is a
# usage error that writes nothing.
obj = os.path.join(TMP, "cli_octahedron.obj")
with open(obj, "w") as f:
    f.write("v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n"
            "f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n")
model = os.path.join(TMP, "cli_model.vds")
code, out, err = run("encode-mesh", obj, "-o", model, "--up", "z")
check(code == 0 and "up +z" in out, "encode-mesh --up z reports the axis")
code, out, err = run("info", model)
check(code == 0 and "up +z" in out, "info shows the stored up axis")
code, out, err = run("encode-mesh", obj, "-o", model + ".bad", "--up", "w")
check(code == 2 and "--up must be" in err and not os.path.exists(model + ".bad"), "a bad --up is refused, nothing written")

# The single-rate tail: with the paper's coding it is a usage error that
# writes nothing; --tail 0 splits all the way.
code, out, err = run("encode-mesh", obj, "-o", model + ".paper", "--paper", "--tail", "0.1")
check(code == 2 and "--tail needs the arithmetic coder" in err and not os.path.exists(model + ".paper"),
      "--tail with --paper is refused, nothing written")
code, out, err = run("encode-mesh", obj, "-o", model + ".splits", "--tail", "0")
check(code == 0 and "single-rate tail" not in out, "--tail 0 splits all the way")

# vds mesh-colors: the octahedron has no texture (vertex samples only, no
# level to code); a missing model names the file; a resolution beyond the
# format's is a usage error.
code, out, err = run("mesh-colors", obj, "--quality", "1")
check(code == 0 and "R=1: 8 faces" in out, "mesh-colors on an untextured model: resolution 1 everywhere")
code, out, err = run("mesh-colors", os.path.join(TMP, "no_such.obj"))
check(code == 1 and "no_such.obj" in err, "mesh-colors on a missing file names it (exit 1)")
code, out, err = run("mesh-colors", obj, "--max-res", "11")
check(code == 2, "mesh-colors --max-res beyond 10 is a usage error")
anchors = os.path.join(TMP, "anchors.csv")
with open(anchors, "w") as f:
    f.write("jpeg,50,1000\n")
code, out, err = run("mesh-colors", obj, "--views", "1", "--size", "16", "--anchors", anchors)
check(code == 1 and "anchors.csv: line 1" in err, "a malformed anchors line is refused naming the file and line")

# vds encode-model: an untextured model is its mesh and its vertex colours
# (a client draws one more frame once they are in); a missing model names
# the file; --quality and --bytes exclude each other; a byte budget below
# the geometry is refused, nothing written.
textured = os.path.join(TMP, "octa.vds")
code, out, err = run("encode-model", obj, "-o", textured)
check(code == 0 and "colour header" in out, "encode-model on an untextured model")
code, frames, err = run("frames", textured)
code2, mesh_frames, err2 = run("frames", model)
check(code == 0 and code2 == 0 and len(frames.split()) >= 2, "its stream plays: the mesh, then its colours")
code, out, err = run("encode-model", os.path.join(TMP, "no_such.obj"), "-o", textured + ".x")
check(code == 1 and "no_such.obj" in err and not os.path.exists(textured + ".x"), "encode-model on a missing file names it (exit 1)")
code, out, err = run("encode-model", obj, "-o", textured + ".x", "--quality", "2", "--bytes", "5000")
check(code == 2 and not os.path.exists(textured + ".x"), "encode-model: --quality with --bytes is a usage error")
code, out, err = run("encode-model", obj, "-o", textured + ".x", "--bytes", "50")
check(code == 1 and "no quality fits 50 bytes" in err and not os.path.exists(textured + ".x"),
      "encode-model: a byte budget no quality meets is refused, nothing written")

code, out, err = run("encode-model", obj, "-o", textured + ".x", "--bytes", "5000", "--psnr", "30")
check(code == 2 and not os.path.exists(textured + ".x"), "encode-model: --bytes with --psnr is a usage error")
code, out, err = run("encode-model", obj, "-o", textured + ".x", "--psnr", "30")
check(code == 1 and "no quality reaches" in err and not os.path.exists(textured + ".x"),
      "encode-model: a PSNR no quality reaches is refused, nothing written")

# vds play and encode-walk: options checked before anything runs.
code, out, err = run("play", stream, "--board", "fpga")
check(code == 2 and "--board" in err, "vds play refuses a board it does not have")
code, out, err = run("play", os.path.join(TMP, "no-such.vds"), "--board", "host")
check(code == 1 and "no-such.vds" in err, "vds play names a missing stream")
code, out, err = run("encode-walk", "scene.obj", "--path", "p.txt", "-o", os.path.join(TMP, "w.vds"), "--preroll", "700000")
check(code == 2 and "--preroll" in err and not os.path.exists(os.path.join(TMP, "w.vds")),
      "encode-walk refuses a pre-roll over ten minutes, nothing written")
code, out, err = run("encode-walk", "scene.obj", "--path", "p.txt", "-o", os.path.join(TMP, "w.vds"), "--window", "16")
check(code == 2 and "--window" in err, "encode-walk refuses a window under 256 bytes")


# vds fly: a user's heightmap and colour map, a short flight; refusals name the file.
hm = os.path.join(TMP, "fly_heights.pgm")
with open(hm, "wb") as f:
    f.write(b"P5\n33 33\n65535\n")
    for y in range(33):
        for x in range(33):
            v = 20000 + 300 * ((x * 7 + y * 3) % 17)
            f.write(bytes([v >> 8, v & 255]))
col = os.path.join(TMP, "fly_colour.ppm")
with open(col, "wb") as f:
    f.write(b"P6\n64 64\n255\n" + bytes(((x * 4) & 255, (y * 4) & 255, ((x ^ y) * 8) & 255)[c]
                                          for y in range(64) for x in range(64) for c in range(3)))
flyout = os.path.join(TMP, "fly")
code, out, err = run("fly", "--heightmap", hm, "--colour", col, "--scale", "4,0.001", "--frames", "12", "--rate", "0",
                     "--out", flyout)
check(code == 0 and "8x8 cells" in out and "overall:" in out and os.path.exists(os.path.join(flyout, "sheet.png"))
      and len(open(os.path.join(flyout, "frames.csv")).read().splitlines()) == 13, "vds fly replays a flight over a user's map")
code, out, err = run("fly", "--heightmap", hm, "--colour", col, "--scale", "4,0.001", "--frames", "12", "--rate", "2000",
                     "--tiles", "webp64", "--out", flyout + "_tiles")
check(code == 0 and "WebP tiles of 64 texels" in out and "mean" in out
      and len(open(os.path.join(flyout + "_tiles", "frames.csv")).read().splitlines()) == 13,
      "vds fly replays the same flight with the tile-pyramid baseline")
code, out, err = run("fly", "--heightmap", hm, "--colour", col, "--scale", "4,0.001", "--tiles", "png64")
check(code == 2 and "--tiles" in err, "vds fly refuses a tile variant it does not have")
code, out, err = run("fly", "--heightmap", hm, "--colour", col, "--frames", "12")
check(code == 2 and "--scale" in err, "vds fly asks for the scales of a user's heightmap")
# vds encode-terrain: the same map's stream, replayed through the client library; vds serve-terrain
# needs a client.
tstream = os.path.join(TMP, "terrain.vds")
code, out, err = run("encode-terrain", "--heightmap", hm, "--colour", col, "--scale", "4,0.001", "--frames", "12",
                     "-o", tstream, "--psnr", "--out", flyout + "_stream")
check(code == 0 and "the client library plays it: 12 frames" in out and "ground truth: mean" in out
      and os.path.exists(os.path.join(flyout + "_stream", "sheet.png")), "vds encode-terrain writes a stream the client plays")
code, out, err = run("frames", tstream)
check(code == 0, "vds frames replays a terrain stream")
code, out, err = run("encode-terrain", "--heightmap", hm, "--colour", col, "--scale", "4,0.001", "-o", tstream, "--cache-log2", "9")
check(code == 2 and "--cache-log2" in err, "vds encode-terrain refuses a cache it cannot have")
code, out, err = run("serve-terrain", "--heightmap", hm, "--colour", col, "--scale", "4,0.001", "--frames", "12")
check(code == 2 and "--board" in err, "vds serve-terrain asks for a board or a link")
code, out, err = run("fly", os.path.join(TMP, "no-such.level"))
check(code == 1 and "no-such.level" in err, "vds fly names a missing level")
with open(os.path.join(TMP, "bad.level"), "w") as f:
    f.write("<level><terrain heightmap='h.png' colormap='../c.jpg' horizontalscale='1' verticalscale='1'/></level>")
code, out, err = run("fly", os.path.join(TMP, "bad.level"))
check(code == 1 and "bad.level" in err and "not a file name beside the level" in err, "vds fly refuses a level that points outside its folder")

print(f"{len(failures)} failed" if failures else "all CLI checks passed")
sys.exit(1 if failures else 0)
