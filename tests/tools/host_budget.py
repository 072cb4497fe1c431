#!/usr/bin/env python3
"""Host commands on files a user did not make, each under its resource budget
(docs/security.md): every hostile file is refused with exit code 1 and one
line naming the file and what is wrong, leaves no output behind, and stays
within

    memory: 256 MiB + 16 x the input's size + 48 bytes per pixel of an
            image the input holds (a picture is decoded whole: its pixels
            are the importer's output), as peak resident memory; enforced:
            RLIMIT_AS (the budget + 512 MiB for code and libraries) without
            sanitizers, ASan's hard_rss_limit_mb under them (the budget x
            1.25 + 64 MiB: shadow memory and a 16 MiB quarantine), and the
            child's peak RSS checked after it ends;
    time:   10 s + 1 s per MB of input + 1 s per Mpixel (x3 under
            sanitizers).

Each case is one that crashed, hung or took gigabytes before: a binary PLY
whose face list is cut short, a face of 255 indices, indices outside the
vertices, a 4 KB PLY claiming 10^9 vertices, 4,000,000 faces with 4 present,
a stream declaring a 16384x16384 image, images declaring 65535x65535, and the
smaller ones (--bytes 0, a short truncated stream, vds info on image chunks).
The terrain cases (heightmaps, colour maps and levels past their limits,
a level nested 100,000 deep) guard the terrain importer the same way.

Usage: host_budget.py VDS TMPDIR SANITIZED(0|1) [--report FILE]
  --report writes one line per case: name, exit code, seconds, peak RSS (KiB).
"""
import os
import resource
import struct
import subprocess
import sys
import time
import zlib

VDS, TMP, SANITIZED = sys.argv[1], sys.argv[2], sys.argv[3] == "1"
REPORT = sys.argv[sys.argv.index("--report") + 1] if "--report" in sys.argv else None
os.makedirs(TMP, exist_ok=True)
failures = []
rows = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def write(name, data):
    path = os.path.join(TMP, name)
    with open(path, "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())
    return path


def budget_mb(input_bytes, pixels):
    return 256 + (16 * input_bytes + 48 * pixels) / (1 << 20)


def run(name, args, input_path, expect_code, expect_text="", output=None, pixels=0):
    """Runs `vds ARGS` under the budget of `input_path` (holding an image of
    `pixels`); checks the outcome."""
    size = os.path.getsize(input_path) if input_path else 0
    mb = budget_mb(size, pixels)
    rss_mb = mb * 1.25 + 64 if SANITIZED else mb
    seconds = (10 + size / 1e6 + pixels / 1e6) * (3 if SANITIZED else 1)
    env = dict(os.environ)
    preexec = None
    if SANITIZED:
        env["ASAN_OPTIONS"] = f"hard_rss_limit_mb={int(rss_mb)}:quarantine_size_mb=16:detect_leaks=0"
    else:
        limit = int(mb + 512) << 20

        def preexec():
            resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    if output:
        for p in (output, output + ".part"):
            if os.path.exists(p):
                os.remove(p)
    t0 = time.monotonic()
    with open(os.path.join(TMP, "stdout.txt"), "w+") as fo, open(os.path.join(TMP, "stderr.txt"), "w+") as fe:
        p = subprocess.Popen([VDS, *args], stdout=fo, stderr=fe, env=env, preexec_fn=preexec)
        # wait4 gives this child's own peak memory.
        timed_out = False
        while True:
            pid, status, usage = os.wait4(p.pid, os.WNOHANG)
            if pid == p.pid:
                break
            if time.monotonic() - t0 > seconds:
                p.kill()
                pid, status, usage = os.wait4(p.pid, 0)
                timed_out = True
                break
            time.sleep(0.01)
        p.returncode = os.waitstatus_to_exitcode(status)
        fo.seek(0)
        fe.seek(0)
        out, err = fo.read(), fe.read()
    spent = time.monotonic() - t0
    rss = usage.ru_maxrss
    rows.append((name, p.returncode, spent, rss))
    check(rss <= rss_mb * 1024, f"{name}: peak memory {rss / 1024:.0f} MiB within {rss_mb:.0f} MiB")
    label = f"{name}: vds {' '.join(os.path.basename(a) if os.path.sep in a else a for a in args)}"
    check(not timed_out, f"{label} ends within {seconds:.0f} s (took {spent:.1f} s)")
    check(p.returncode == expect_code,
          f"{label} exits {expect_code} (got {p.returncode}; stderr: {err.strip()[:300]})")
    if expect_code == 1:
        lines = [l for l in err.splitlines() if l.strip()]
        check(len(lines) == 1 and os.path.basename(input_path) in lines[0] and expect_text in lines[0],
              f"{label} says in one line which file and '{expect_text}' (stderr: {err.strip()[:300]})")
        check("internal error" not in err and "Sanitizer" not in err, f"{label} is a refusal, not a failure")
    if output:
        if expect_code == 0:
            check(os.path.exists(output), f"{label} writes {os.path.basename(output)}")
        else:
            check(not os.path.exists(output) and not os.path.exists(output + ".part"),
                  f"{label} leaves no output behind")
    return out, err


# --- PLY and other meshes ---------------------------------------------------------------

def ply_binary(nv, nf, verts, faces, tail=b""):
    head = (f"ply\nformat binary_little_endian 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\n"
            f"property float z\nelement face {nf}\nproperty list uchar int vertex_indices\nend_header\n").encode()
    body = b"".join(struct.pack("<3f", *v) for v in verts)
    for f in faces:
        body += struct.pack("<B", len(f)) + b"".join(struct.pack("<i", i) for i in f)
    return head + body + tail


quad = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0)]
whole = ply_binary(4, 2, quad, [(0, 1, 2), (1, 3, 2)])
mesh_out = os.path.join(TMP, "out.vds")
run("ply_valid", ["encode-mesh", write("valid.ply", whole), "-o", mesh_out], os.path.join(TMP, "valid.ply"), 0,
    output=mesh_out)
run("ply_face_list_cut", ["encode-mesh", write("cut.ply", whole[:-6]), "-o", mesh_out], os.path.join(TMP, "cut.ply"), 1,
    "runs past the end", mesh_out)
run("ply_face_of_255", ["encode-mesh", write("len255.ply", ply_binary(4, 1, quad, []) + b"\xff" + struct.pack("<3i", 0, 1, 2)),
                        "-o", mesh_out], os.path.join(TMP, "len255.ply"), 1, "face 0 of 1", mesh_out)
run("ply_255_indices_present",
    ["encode-mesh", write("big_face.ply", ply_binary(4, 1, quad, [tuple(i % 4 for i in range(255))])), "-o", mesh_out],
    os.path.join(TMP, "big_face.ply"), 0, output=mesh_out)
oob = ("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n3 0 1 2\n3 1 3 2\n")
run("ply_index_outside", ["encode-mesh", write("oob.ply", oob), "-o", mesh_out], os.path.join(TMP, "oob.ply"), 1,
    "vertex index 2 is not one of the 2 vertices (line 12)", mesh_out)
huge = ply_binary(10**9, 2, quad, [(0, 1, 2), (1, 3, 2)])
run("ply_claims_1e9_vertices", ["encode-mesh", write("huge.ply", huge + b"\0" * (4096 - len(huge))), "-o", mesh_out],
    os.path.join(TMP, "huge.ply"), 1, "declares 1000000000 vertex elements", mesh_out)
run("ply_claims_4e6_faces",
    ["encode-mesh", write("many.ply", ply_binary(4, 4000000, quad, [(0, 1, 2), (1, 3, 2), (0, 1, 3), (0, 2, 3)])), "-o",
     mesh_out], os.path.join(TMP, "many.ply"), 1, "declares 4000000 face elements", mesh_out)
run("ply_nul_in_ascii", ["encode-mesh", write("nul.ply", oob.replace("element vertex 2", "element vertex 4")
                                              .replace("1 0 0\n3", "1 0 0\n0\0 1 0\n0 0 1\n3")), "-o", mesh_out],
    os.path.join(TMP, "nul.ply"), 1, "is not a number", mesh_out)
run("obj_index_outside", ["encode-mesh", write("oob.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n"), "-o", mesh_out],
    os.path.join(TMP, "oob.obj"), 1, "oob.obj", mesh_out)
os.makedirs(os.path.join(TMP, "model"), exist_ok=True)
gltf = ('{"asset":{"version":"2.0"},"buffers":[{"byteLength":36,"uri":"%s"}],'
        '"bufferViews":[{"buffer":0,"byteLength":36}],"accessors":[{"bufferView":0,"componentType":5126,"count":3,'
        '"type":"VEC3"}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}],'
        '"scenes":[{"nodes":[0]}],"scene":0}')
write("secret.bin", b"\0" * 36)
for label, uri in (("gltf_buffer_outside_folder", os.path.join(TMP, "secret.bin")), ("gltf_buffer_dotdot", "../secret.bin")):
    path = write(os.path.join("model", label + ".gltf"), gltf % uri)
    run(label, ["encode-mesh", path, "-o", mesh_out], path, 1, "which is not in the model's folder", mesh_out)
# A glTF whose buffer lies beside it is read, whatever the working directory.
with open(os.path.join(TMP, "model", "inside.bin"), "wb") as f:
    f.write(struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0))
inside = write(os.path.join("model", "inside.gltf"), gltf % "inside.bin")
run("gltf_buffer_beside", ["encode-mesh", inside, "-o", mesh_out], inside, 0, output=mesh_out)
glb_json = b'{"asset":{"version":"2.0"}}    '
glb = b"glTF" + struct.pack("<III", 2, 20 + len(glb_json), 1711276488) + b"JSON" + glb_json
run("glb_chunk_claims_1_7_gb", ["encode-mesh", write("big.glb", glb), "-o", mesh_out], os.path.join(TMP, "big.glb"), 1,
    "a chunk of 1711276488 bytes", mesh_out)
run("draco_garbage", ["encode-mesh", write("bad.drc", b"DRACO" + bytes(range(200))), "-o", mesh_out],
    os.path.join(TMP, "bad.drc"), 1, "Draco", mesh_out)
run("format_not_read", ["encode-mesh", write("m.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"), "-o", mesh_out],
    os.path.join(TMP, "m.off"), 1, "not a mesh format this tool reads", mesh_out)


# --- Images ----------------------------------------------------------------------------------

def png_chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def png(w, h, rows_data):
    return (b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) +
            png_chunk(b"IDAT", zlib.compress(rows_data)) + png_chunk(b"IEND", b""))


# --- Textured models (vds mesh-colors) -------------------------------------------------------
# An IQM whose header claims a billion vertices: refused by the project's check before assimp.
iqm_text = b"\0m\0\0"
iqm_size = 124 + 4 + 24 + 20 + 36 + 12
iqm_header = [2, iqm_size, 0, 4, 124, 1, 128, 1, 3, 152, 1, 188 - 12 + 12, 0] + [0] * 14
iqm_header[11] = 124 + 4 + 24 + 20 + 36
iqm = (b"INTERQUAKEMODEL\0" + struct.pack("<27I", *iqm_header) + iqm_text + struct.pack("<6I", 1, 0, 0, 3, 0, 1) +
       struct.pack("<5I", 0, 0, 7, 3, 172) + struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<3I", 0, 1, 2))
run("iqm_valid", ["mesh-colors", write("ok.iqm", iqm), "--quality", "1"], os.path.join(TMP, "ok.iqm"), 0)
huge_iqm = bytearray(iqm)
struct.pack_into("<I", huge_iqm, 16 + 4 * 8, 1000000000)
run("iqm_claims_1e9_vertices", ["mesh-colors", write("huge.iqm", bytes(huge_iqm))], os.path.join(TMP, "huge.iqm"), 1,
    "do not fit the file")
# An MD3 whose header claims 100000 surfaces: refused by the project's check before assimp.
md3 = (b"IDP3" + struct.pack("<i", 15) + b"t".ljust(64, b"\0") + struct.pack("<9i", 0, 1, 0, 100000, 0, 108, 164, 164, 164) +
       b"\0" * 56)
run("md3_claims_100000_surfaces", ["mesh-colors", write("huge.md3", md3)], os.path.join(TMP, "huge.md3"), 1,
    "surfaces 100000 (0..32)")
os.makedirs(os.path.join(TMP, "textured"), exist_ok=True)
tex_obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl t\nf 1/1 2/2 3/3\n"
write(os.path.join("textured", "t.png"), png(4, 2, b"".join(b"\0" + bytes(range(12)) for _ in range(2))))
write(os.path.join("textured", "m.mtl"), "newmtl t\nmap_Kd t.png\n")
ok_obj = write(os.path.join("textured", "ok.obj"), tex_obj)
run("textured_obj_valid", ["mesh-colors", ok_obj, "--quality", "1", "--views", "2", "--size", "32"], ok_obj, 0)
write(os.path.join("textured", "out.mtl"), "newmtl t\nmap_Kd ../ok.png\n")
out_obj = write(os.path.join("textured", "out.obj"), tex_obj.replace("m.mtl", "out.mtl"))
run("textured_obj_texture_outside_folder", ["mesh-colors", out_obj], out_obj, 1, "not in the model's folder")
write(os.path.join("textured", "huge.png"), png(65535, 65535, b"\0" * 1000))
write(os.path.join("textured", "huge.mtl"), "newmtl t\nmap_Kd huge.png\n")
huge_obj = write(os.path.join("textured", "huge.obj"), tex_obj.replace("m.mtl", "huge.mtl"))
run("textured_obj_texture_claims_65535", ["mesh-colors", huge_obj], huge_obj, 1, "declares a 65535x65535 image")
# The same files through the model stream's encoder (vds encode-model).
model_out = os.path.join(TMP, "model_out.vds")
run("encode_model_textured_obj_valid", ["encode-model", ok_obj, "-o", model_out], ok_obj, 0, output=model_out)
run("encode_model_iqm_claims_1e9_vertices", ["encode-model", os.path.join(TMP, "huge.iqm"), "-o", model_out],
    os.path.join(TMP, "huge.iqm"), 1, "do not fit the file")
run("encode_model_texture_claims_65535", ["encode-model", huge_obj, "-o", model_out], huge_obj, 1,
    "declares a 65535x65535 image")


img_out = os.path.join(TMP, "out_img.vds")
small = png(4, 2, b"".join(b"\0" + bytes(range(12)) for _ in range(2)))
run("png_valid", ["encode-image", write("ok.png", small), "-o", img_out], os.path.join(TMP, "ok.png"), 0, output=img_out)
run("png_claims_65535", ["encode-image", write("huge.png", png(65535, 65535, b"\0" * 1000)), "-o", img_out],
    os.path.join(TMP, "huge.png"), 1, "declares a 65535x65535 image", img_out)
# A 12 KB PNG of 2048x2048 zeros (a thousandfold zlib expansion, within the
# limits): decoded and coded within the budget its pixels give.
bomb = png(2048, 2048, b"\0" * (2048 * (2048 * 3 + 1)))
run("png_zlib_bomb_in_limits", ["encode-image", write("bomb.png", bomb), "--quality", "10", "-o", img_out],
    os.path.join(TMP, "bomb.png"), 0, output=img_out, pixels=2048 * 2048)
tga = bytes([0, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x40, 0, 0x40, 24, 0]) + b"\x10" * 100
run("tga_claims_16384", ["encode-image", write("huge.tga", tga), "-o", img_out], os.path.join(TMP, "huge.tga"), 1,
    "declares a 16384x16384 image", img_out)
tga2 = bytes([0, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x10, 0, 0x10, 24, 0]) + b"\x10" * 100
run("tga_claims_4096", ["encode-image", write("big.tga", tga2), "-o", img_out], os.path.join(TMP, "big.tga"), 1,
    "follow its header", img_out)
run("jpeg_truncated", ["encode-image", write("cut.jpg", b"\xff\xd8\xff\xe0" + b"\0" * 20), "-o", img_out],
    os.path.join(TMP, "cut.jpg"), 1, "not a readable JPEG", img_out)
run("bmp_refused", ["encode-image", write("x.bmp", b"BM" + b"\0" * 60), "-o", img_out], os.path.join(TMP, "x.bmp"), 1,
    "BMP", img_out)
run("ppm_claims_big", ["encode-image", write("huge.ppm", b"P6\n16384 16384\n255\n" + b"\0" * 100), "-o", img_out],
    os.path.join(TMP, "huge.ppm"), 1, "declares a 16384x16384 image", img_out)
run("ppm_claims_4096", ["encode-image", write("big.ppm", b"P6\n4096 4096\n255\n" + b"\0" * 100), "-o", img_out],
    os.path.join(TMP, "big.ppm"), 1, "follow its header", img_out)
run("bytes_zero", ["encode-image", os.path.join(TMP, "ok.png"), "--bytes", "0", "-o", img_out], None, 2, output=img_out)

# --- Streams ---------------------------------------------------------------------------------
# A stream declaring a 16384x16384 image, 59 KB of data: refused in memory of one band.
imgh = write("imgh.bin", bytes([1, 1, 0, 40, 40, 4]) + struct.pack("<HHH", 16384, 16384, 0))
imgd = write("imgd.bin", struct.pack("<IH", 0, 1000) + bytes((i * 7919) & 255 for i in range(4090)))
big_stream = os.path.join(TMP, "big.vds")
run("pack_big_image", ["pack", "-o", big_stream, "--size", "16384x16384", "--chunk", f"IMGH={imgh}"] +
    [a for _ in range(14) for a in ("--chunk", f"IMGD={imgd}")], imgh, 0, output=big_stream)
png_out = os.path.join(TMP, "big.png")
run("decode_declares_16384", ["decode-image", big_stream, "-o", png_out], big_stream, 1, "big.vds", png_out)
# A short cut of a valid stream is "truncated", not "workspace too small".
ok_stream = img_out
run("encode_for_cut", ["encode-image", os.path.join(TMP, "ok.png"), "-o", ok_stream], os.path.join(TMP, "ok.png"), 0,
    output=ok_stream)
with open(ok_stream, "rb") as f:
    cut = write("cut.vds", f.read()[:100])
run("decode_short_cut", ["decode-image", cut, "-o", png_out], cut, 1, "truncated", png_out)
out, _ = run("info_names_image_chunks", ["info", ok_stream], ok_stream, 0)
check("vds image header" in out and "skipped as unknown" in out and ", 0 skipped as unknown" in out,
      "vds info names IMGH/IMGD chunks and skips none")
run("info_garbage", ["info", write("garbage.vds", bytes(range(256)) * 8)], os.path.join(TMP, "garbage.vds"), 1,
    "garbage.vds")

# --- Scenes and camera paths -----------------------------------------------------------------
# A Quake III map whose face lump claims 2^31 bytes; a camera path with a word for a number;
# a scene whose texture lies outside its folder; a good scene rendered whole.
bsp = bytearray(b"IBSP" + struct.pack("<i", 46) + b"\0" * (17 * 8))
struct.pack_into("<II", bsp, 8 + 8 * 13, 152, 0x7FFFFFF0)
bad_bsp = write("bad.bsp", bytes(bsp))
run("bsp_face_lump_past_the_end", ["info", bad_bsp], bad_bsp, 1, "bad.bsp")
path_out = os.path.join(TMP, "tour.txt")
run("path_tour_of_a_bad_map", ["path", bad_bsp, "-o", path_out], bad_bsp, 1, "bad.bsp", path_out)
scene_dir = os.path.join(TMP, "scene")
os.makedirs(scene_dir, exist_ok=True)
with open(os.path.join(scene_dir, "room.obj"), "w") as f:
    f.write("mtllib room.mtl\nv -5 -5 -5\nv 5 -5 -5\nv 5 5 -5\nv -5 5 -5\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
            "usemtl wall\nf 1/1 2/2 3/3 4/4\n")
with open(os.path.join(scene_dir, "room.mtl"), "w") as f:
    f.write("newmtl wall\nmap_Kd wall.png\n")
with open(os.path.join(scene_dir, "wall.png"), "wb") as f:
    f.write(small)
room = os.path.join(scene_dir, "room.obj")
bad_path = write("bad_path.txt", "# hfov 90\n0 0 0 0 90 0\n1 0 zero 0 90 0\n")
render_out = os.path.join(TMP, "gt")
run("render_bad_path", ["render", room, "--path", bad_path, "-o", render_out], bad_path, 1, "line 3",
    render_out + ".y4m")
good_path = write("good_path.txt", "".join(f"{i} 0 0 0 {90 + i} 0\n" for i in range(20)))
run("render_obj_scene", ["render", room, "--path", good_path, "-o", render_out], room, 0, output=render_out + ".vis")
check(os.path.getsize(render_out + ".rgb") == 20 * 240 * 180 * 3, "vds render writes 20 frames of RGB")
with open(os.path.join(scene_dir, "room.mtl"), "w") as f:
    f.write("newmtl wall\nmap_Kd ../../outside.png\n")
run("render_texture_outside_the_folder", ["render", room, "--path", good_path, "-o", render_out], room, 1,
    "not in the scene's folder", render_out + ".y4m")

if REPORT:
    with open(REPORT, "w") as f:
        for name, code, spent, rss in rows:
            f.write(f"{name} {code} {spent:.2f} {rss}\n")
# Terrain maps (vds fly): heightmaps and levels a user did not make.
fly_out = os.path.join(TMP, "fly_out")
colour_ok = write("terrain_c.png", png(16, 16, b"".join(b"\0" + bytes(48) for _ in range(16))))


def png16_grey(w, h, rows_data):
    return (b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, 0, 0, 0, 0)) +
            png_chunk(b"IDAT", zlib.compress(rows_data)) + png_chunk(b"IEND", b""))


def fly(name, heights_path, expect_text, colour=colour_ok, faulty=None):
    """`faulty`: the file the refusal names (the heightmap unless given)."""
    run(name, ["fly", "--heightmap", heights_path, "--colour", colour, "--scale", "2,0.01", "--frames", "4", "--out", fly_out],
        faulty or heights_path, 1, expect_text)
    check(not os.path.exists(fly_out), f"{name}: nothing written")


fly("heightmap16_claims_65535", write("h16_huge.png", png16_grey(65535, 65535, b"\0" * 1000)), "declares a 65535x65535 image")
fly("heightmap_past_the_cell_limit", write("h_wide.pgm", b"P5\n9000 2\n65535\n" + b"\0" * (9000 * 2 * 2)),
    "heightmap (2 to 8193 samples on a side are read)")
fly("heightmap_pgm_cut_short", write("h_cut.pgm", b"P5\n300 300\n65535\n" + b"\0" * 1000), "follow its header")
c_huge = write("c_huge.png", png(65535, 65535, b"\0" * 1000))
fly("colour_map_claims_65535", write("h_ok.pgm", b"P5\n4 4\n255\n" + bytes(16)), "declares a 65535x65535 image",
    colour=c_huge, faulty=c_huge)
big_level = write("big.level", "<level><terrain heightmap='h.png' colormap='c.png' horizontalscale='1' verticalscale='1'/>"
                  + "<!--" + "x" * (2 << 20) + "--></level>")
run("level_of_2_mib", ["fly", big_level, "--out", fly_out], big_level, 1, "at most 1 MiB is read")
deep = write("deep.level", "<level>" + "<a>" * 100000 + "</a>" * 100000 + "</level>")
run("level_nested_100000_deep", ["fly", deep, "--out", fly_out], deep, 1, "deep.level")

print(f"{len(failures)} failure(s)")
sys.exit(1 if failures else 0)
