#!/usr/bin/env python3
"""The viewer turns a model on the host board (as with the live window's
mouse), end to end: glTF's textured box through `vds encode-model` with an
orbit of 8 frames (each 1/8 turn further), played by `vds play` on the
host-native board twice, alone and with a controls script turning 45
degrees at every poll.

- Alone: every frame equals the encoder's replay (`vds play` checks it).
- Turned: `vds play` still passes (the frames drawn as the viewer turned
  the model are marked steered and not compared; every other frame equals
  the replay); the board keeps the model in view after the stream until the
  script ends and says how many frames it drew for the viewer; the frames
  written are the stream's plus those; and each frame drawn for the viewer
  after the stream shows the finished model at a whole number of eighth
  turns, so it is one of the 8 orbit frames of the first run, and the turns
  show more than one of them.

Usage: model_viewer_case.py --vds VDS --host-board EXE --work DIR"""
import argparse
import glob
import os
import re
import shutil
import subprocess
import sys

BOX = "/usr/share/assimp/models/glTF2/BoxTextured-glTF/BoxTextured.gltf"
POLLS = 120  # the script's entries: one a viewer's poll (50 ms), each 45 degrees


def fail(msg):
    print("model_viewer_case: FAIL: " + msg)
    sys.exit(1)


def play(a, stream, out, controls=None):
    shutil.rmtree(out, ignore_errors=True)
    cmd = [a.vds, "play", stream, "--board", "host", "--firmware", a.host_board, "--out", out]
    if controls:
        cmd += ["--controls", controls]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    print(r.stdout + r.stderr)
    if r.returncode != 0:
        fail("vds play exited %d" % r.returncode)
    frames = sorted(glob.glob(os.path.join(out, "frames", "frame*.png")))
    with open(os.path.join(out, "crcs.txt")) as f:
        records = f.read().split("\n")[:-1]
    with open(os.path.join(out, "board.log")) as f:
        log = f.read()
    return frames, records, log


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--vds", required=True)
    ap.add_argument("--host-board", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    stream = os.path.join(a.work, "box.vds")
    r = subprocess.run([a.vds, "encode-model", BOX, "-o", stream, "--max-res", "4", "--orbit", "8"],
                       capture_output=True, text=True)
    if r.returncode != 0:
        fail("encode-model: " + r.stdout + r.stderr)

    alone, records, log = play(a, stream, os.path.join(a.work, "alone"))
    if len(alone) != len(records) or len(records) < 9 or any("steered" in r for r in records):
        fail("alone: %d frames written, %d reported" % (len(alone), len(records)))
    orbit = [open(p, "rb").read() for p in alone[-8:]]
    if len(set(orbit)) != 8:
        fail("the orbit's 8 frames are not 8 pictures")

    controls = os.path.join(a.work, "turn.controls")
    with open(controls, "w") as f:
        f.write("# FRAMES FORWARD RIGHT UP TURN TILT: a turn of 45 degrees at every poll\n%d 0 0 0 45 0\n" % POLLS)
    turned, records, log = play(a, stream, os.path.join(a.work, "turned"), controls)
    m = re.search(r"the viewer has gone, (\d+) frames drawn for them after the stream", log)
    if not m:
        fail("the board did not keep the model in view for the viewer:\n" + log)
    after = int(m.group(1))
    if after < 1:
        fail("no frame drawn for the viewer after the stream")
    if len(records) != len(alone):
        fail("turned: %d frames reported, the stream has %d" % (len(records), len(alone)))
    if len(turned) < len(records) + after:
        fail("turned: %d frames written, fewer than %d reported + %d for the viewer" % (len(turned), len(records), after))
    shown = [open(p, "rb").read() for p in turned[-after:]]
    for i, png in enumerate(shown):
        if png not in orbit:
            fail("the viewer's frame %d after the stream is not one of the orbit's eighth turns" % i)
    if after > 1 and len(set(shown)) < 2:
        fail("the viewer's turns did not turn the model")
    print("model_viewer_case: PASS (%d frames of the stream, %d steered, %d drawn for the viewer after it)" %
          (len(records), sum("steered" in r for r in records), after))


if __name__ == "__main__":
    main()
