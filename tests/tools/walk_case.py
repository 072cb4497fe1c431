#!/usr/bin/env python3
"""A walkthrough small enough for either board, end to end: a textured room
(an OBJ scene with its material library and PPM textures, Y up, metres)
and a 40-frame camera path are written to WORK, `vds encode-walk` makes
the stream at 64x48, and e2e_boards.py serves it to the host-native board
and the Cortex-M4 board in QEMU: every frame each board displays must have
the CRC the encoder's replay of the client gives.

With --play it plays the stream with `vds play` on both boards instead:
every frame equal to the replay, the host board's frames written as PNGs;
and `vds play` refuses a damaged stream and a missing firmware.

Usage: walk_case.py --vds VDS --work DIR [e2e_boards.py options...]
       walk_case.py --play --vds VDS --work DIR --host-board EXE --qemu QEMU --elf ELF"""
import os
import subprocess
import sys


def ppm(path, w, h, colour_a, colour_b, cell):
    px = bytearray()
    for y in range(h):
        for x in range(w):
            px += bytes(colour_a if ((x // cell) + (y // cell)) % 2 else colour_b)
    with open(path, "wb") as f:
        f.write(b"P6\n%d %d\n255\n" % (w, h) + bytes(px))


def main():
    args = sys.argv[1:]
    vds = args[args.index("--vds") + 1]
    work = args[args.index("--work") + 1]
    os.makedirs(work, exist_ok=True)
    # Six walls of a room 8 x 3 x 8 m, each with its own checkerboard.
    walls = [  # corners (Y up), inward normal, texture colours
        ([(-4, 0, -4), (4, 0, -4), (4, 0, 4), (-4, 0, 4)], (0, 1, 0), (200, 180, 140), (90, 80, 60)),     # floor
        ([(-4, 3, -4), (-4, 3, 4), (4, 3, 4), (4, 3, -4)], (0, -1, 0), (230, 230, 230), (150, 150, 170)),  # ceiling
        ([(-4, 0, -4), (-4, 3, -4), (4, 3, -4), (4, 0, -4)], (0, 0, 1), (180, 60, 50), (240, 200, 60)),   # z = -4
        ([(4, 0, 4), (4, 3, 4), (-4, 3, 4), (-4, 0, 4)], (0, 0, -1), (40, 90, 180), (200, 220, 250)),     # z = 4
        ([(-4, 0, 4), (-4, 3, 4), (-4, 3, -4), (-4, 0, -4)], (1, 0, 0), (50, 150, 70), (220, 240, 200)),  # x = -4
        ([(4, 0, -4), (4, 3, -4), (4, 3, 4), (4, 0, 4)], (-1, 0, 0), (120, 40, 140), (250, 180, 240)),    # x = 4
    ]
    obj = ["mtllib room.mtl"]
    mtl = []
    for i, (corners, n, a, b) in enumerate(walls):
        ppm(os.path.join(work, f"wall{i}.ppm"), 32, 32, a, b, 4 + 2 * i)
        mtl += [f"newmtl wall{i}", "Kd 1 1 1", f"map_Kd wall{i}.ppm"]
        for c in corners:
            obj.append("v %g %g %g" % c)
    obj += ["vt 0 0", "vt 1 0", "vt 1 1", "vt 0 1"]
    for i, (corners, n, a, b) in enumerate(walls):
        obj.append("vn %g %g %g" % n)
    for i in range(len(walls)):
        obj.append(f"usemtl wall{i}")
        v = 4 * i + 1
        obj.append(f"f {v}/1/{i + 1} {v + 1}/2/{i + 1} {v + 2}/3/{i + 1} {v + 3}/4/{i + 1}")
    with open(os.path.join(work, "room.obj"), "w") as f:
        f.write("\n".join(obj) + "\n")
    with open(os.path.join(work, "room.mtl"), "w") as f:
        f.write("\n".join(mtl) + "\n")
    # 40 frames: across the room at eye height (Z up here: the scene's Y), turning.
    with open(os.path.join(work, "path.txt"), "w") as f:
        f.write("# hfov 90\n# fps 20\n")
        for k in range(40):
            f.write("%d %.4f %.4f 1.5 %.3f %.3f\n" % (k, -2 + 0.1 * k, -1 + 0.05 * k, 30 + 3 * k, -5 + 0.25 * k))
    stream = os.path.join(work, "walk.vds")
    per_frame = os.path.join(work, "walk.csv")
    subprocess.run([vds, "encode-walk", os.path.join(work, "room.obj"), "--path", os.path.join(work, "path.txt"),
                    "--size", "64x48", "--rate", "64", "-o", stream, "--per-frame", per_frame], check=True)
    # Each frame's bytes and PSNR: 40 rows whose bytes add up to the stream.
    rows = [line.split(",") for line in open(per_frame).read().split("\n")[1:] if line]
    if len(rows) != 40 or sum(int(r[1]) for r in rows) != os.path.getsize(stream) or not all(10 < float(r[2]) < 99 for r in rows):
        sys.exit(f"walk_case: --per-frame wrote {len(rows)} rows, not 40 adding up to the stream's {os.path.getsize(stream)} bytes")
    if "--play" in args:
        sys.exit(play(vds, work, stream, args))
    rest = [a for i, a in enumerate(args) if a != "--vds" and (i == 0 or args[i - 1] != "--vds")]
    e2e = os.path.join(os.path.dirname(os.path.abspath(__file__)), "e2e_boards.py")
    sys.exit(subprocess.run([sys.executable, e2e, "--vds", vds, "--stream", stream] + rest).returncode)


def play(vds, work, stream, args):
    """`vds play` on both boards, a damaged stream, a missing firmware."""
    opt = lambda k: args[args.index(k) + 1]
    fails = []
    for board, firmware in (("host", opt("--host-board")), ("qemu", opt("--elf"))):
        out = os.path.join(work, "play_" + board)
        r = subprocess.run([vds, "play", stream, "--board", board, "--firmware", firmware, "--qemu", opt("--qemu"),
                            "--baud", "115200", "--out", out, "--timeout", "300"], capture_output=True, text=True)
        if r.returncode != 0 or f"40 frames; the {board} board showed 40, 40 of them equal to the replay's" not in r.stdout:
            fails.append(f"vds play --board {board}: exit {r.returncode}\n{r.stdout[-3000:]}{r.stderr[-3000:]}")
        if board == "host" and len([f for f in os.listdir(os.path.join(out, "frames")) if f.endswith(".png")]) != 40:
            fails.append("vds play --board host did not write 40 PNG frames")
    # A payload byte flipped in the stream's last chunk: refused before any board starts.
    data = bytearray(open(stream, "rb").read())
    data[-20] ^= 0x40
    bad = os.path.join(work, "damaged.vds")
    open(bad, "wb").write(bytes(data))
    r = subprocess.run([vds, "play", bad, "--board", "host", "--firmware", opt("--host-board")], capture_output=True, text=True)
    if r.returncode != 1 or "damaged.vds" not in r.stderr:
        fails.append(f"a damaged stream: exit {r.returncode}, {r.stderr!r}")
    r = subprocess.run([vds, "play", stream, "--board", "qemu", "--firmware", os.path.join(work, "no-such.elf")],
                       capture_output=True, text=True)
    if r.returncode != 2 or "no-such.elf" not in r.stderr:
        fails.append(f"a missing firmware: exit {r.returncode}, {r.stderr!r}")
    for f in fails:
        print("FAIL " + f)
    print("vds play: both boards showed the replay's 40 frames; damaged stream and missing firmware refused" if not fails else "")
    return 1 if fails else 0


if __name__ == "__main__":
    main()
