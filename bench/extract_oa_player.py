#!/usr/bin/python3
"""Takes an OpenArena player's models, skins and textures out of
openarena-data's pak2-players.pk3 (a zip) into DIR/models/players/NAME/.

Usage: extract_oa_player.py DIR NAME
"""
import sys
import zipfile

PK3 = "/usr/share/games/openarena/baseoa/pak2-players.pk3"


def main():
    out, name = sys.argv[1:3]
    with zipfile.ZipFile(PK3) as z:
        for n in z.namelist():
            if n.startswith(f"models/players/{name}/"):
                z.extract(n, out)


if __name__ == "__main__":
    main()
