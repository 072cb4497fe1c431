#!/usr/bin/env python3
"""The demo reel: twelve OpenArena textures (from pak4-textures.pk3, installed
by scripts/fetch-data.sh) written as NN_name.tga into a directory, in reel
order. Used by scripts/demo.sh and bench/run_firmware.sh.

Usage: demo_reel.py OUTDIR [PK3]"""
import os
import sys
import zipfile

PK3 = "/usr/share/games/openarena/baseoa/pak4-textures.pk3"
REEL = ["acc_dm3/comp_up.tga", "base_floor/concretefloor1.tga", "base_wall/concrete_ow.tga",
        "base_wall/metalfloor_wall_15ow.tga", "bubctf1/e8_jumppad02.tga", "clown/vegetation.tga",
        "cosmo_wall/brickwall1.tga", "czest3ctf/grass_lush.tga", "gothic_block/blocks17_ow.tga",
        "gothic_wall/proto_brik.tga", "liquids/lavahell2.tga", "organics/dirt.tga"]


def main():
    if len(sys.argv) not in (2, 3):
        print(__doc__, file=sys.stderr)
        return 2
    out = sys.argv[1]
    pk3 = sys.argv[2] if len(sys.argv) == 3 else PK3
    if not os.path.isfile(pk3):
        print(f"demo_reel: {pk3} not found; run scripts/fetch-data.sh", file=sys.stderr)
        return 1
    os.makedirs(out, exist_ok=True)
    with zipfile.ZipFile(pk3) as z:
        for i, name in enumerate(REEL):
            with open(os.path.join(out, "%02d_%s" % (i, os.path.basename(name))), "wb") as f:
                f.write(z.read("textures/" + name))
    return 0


if __name__ == "__main__":
    sys.exit(main())
