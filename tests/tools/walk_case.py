#!/usr/bin/env python3
"""A walkthrough small enough for either board, end to end: a textured room
(an OBJ scene with its material library and PPM textures, Y up, metres)
and a 40-frame camera path are written to WORK, `vds encode-walk` makes
the stream at 64x48, and e2e_boards.py serves it to the host-native board
and the Cortex-M4 board in QEMU: every frame each board displays must have
the CRC the encoder's replay of the client gives.

Usage: walk_case.py --vds VDS --work DIR [e2e_boards.py options...]"""
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
    subprocess.run([vds, "encode-walk", os.path.join(work, "room.obj"), "--path", os.path.join(work, "path.txt"),
                    "--size", "64x48", "--rate", "64", "-o", stream], check=True)
    rest = [a for i, a in enumerate(args) if a != "--vds" and (i == 0 or args[i - 1] != "--vds")]
    e2e = os.path.join(os.path.dirname(os.path.abspath(__file__)), "e2e_boards.py")
    sys.exit(subprocess.run([sys.executable, e2e, "--vds", vds, "--stream", stream] + rest).returncode)


if __name__ == "__main__":
    main()
