#!/usr/bin/env python3
"""End to end: a sequence of frames is encoded into one stream, served over
a pseudo-terminal at 115,200 baud to the client firmware on the host-native
board, and over TCP to the same firmware on the Cortex-M4 board in QEMU. The
CRC-32C of every frame each board displayed must equal the encoder's own
reconstruction (the client library's decode replayed on the host): the
client is bit-exact across architectures.

With --stream, an existing stream (e.g. a progressive model) is served
instead, and the encoder side is `vds frames STREAM`. With --prefix and a
--workspace too small for the whole model, each board must show the
replay's frames up to the level where it reports its workspace full, and
the host must stop the stream on that report.

Usage: e2e_boards.py --vds VDS --host-board EXE --qemu QEMU --elf ELF --work DIR
       [--frames N | --inputs IMAGE... | --stream VDS_STREAM] [--report FILE.json]"""
import argparse
import json
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import sim  # noqa: E402


def write_ppm(path, w, h, k):
    """A synthetic frame: moving gradients, a checkerboard and a disc."""
    px = bytearray()
    cx, cy, r = (w * (k + 2)) // 8, h // 2, h // 4
    for y in range(h):
        for x in range(w):
            checker = 255 if ((x + 4 * k) // 12 + y // 12) % 2 else 40
            inside = (x - cx) ** 2 + (y - cy) ** 2 < r * r
            px += bytes((255, 200, 30) if inside else ((x * 255) // w, checker, (y * 255) // h))
    with open(path, "wb") as f:
        f.write(b"P6\n%d %d\n255\n" % (w, h) + bytes(px))


def encode_frames(a, failures):
    """Encodes the input images (or synthetic frames) into one stream:
    (stream, the encoder's frame CRCs or None, its output)."""
    inputs = list(a.inputs)
    if not inputs:
        for k in range(a.frames):
            p = os.path.join(a.work, f"src{k}.ppm")
            write_ppm(p, 240, 180, k)
            inputs.append(p)
    stream = os.path.join(a.work, "e2e.vds")
    crc_file = os.path.join(a.work, "encoder.crc")
    rate = ["--psnr", str(a.psnr)] if a.psnr else ["--quality", str(a.quality)]
    enc = subprocess.run([a.vds, "encode-frames", *inputs, "-o", stream, "--size", "240x180", *rate,
                          "--max-chunk", "1024", "--crc-out", crc_file], capture_output=True, text=True)
    print(enc.stdout + enc.stderr)
    if enc.returncode != 0:
        return stream, None, enc.stdout
    want = open(crc_file).read().split()
    if len(want) != len(inputs) or not want:
        failures.append(f"the encoder reports {len(want)} frames for {len(inputs)} inputs")
    return stream, want, enc.stdout


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--vds", required=True)
    ap.add_argument("--host-board", required=True)
    ap.add_argument("--qemu", required=True)
    ap.add_argument("--elf", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--frames", type=int, default=4)
    ap.add_argument("--baud", type=int, default=115200)
    ap.add_argument("--quality", type=int, default=60)
    ap.add_argument("--psnr", type=float, default=0, help="encode each frame to this PSNR instead of --quality")
    ap.add_argument("--inputs", nargs="*", default=[], help="images to use instead of synthetic frames")
    ap.add_argument("--stream", default="", help="serve this stream instead of encoding frames")
    ap.add_argument("--model", default="", help="serve this textured model, encoded by `vds encode-model`, instead; "
                    "each board must show every level, each frame the replay of that board (its own workspace)")
    ap.add_argument("--model-args", default="", help="options for `vds encode-model` (one string)")
    ap.add_argument("--partial-colours", action="store_true",
                    help="with --model: a model whose faces' samples do not fit the boards: each board must show "
                         "the frames of its own replay, fewer than the stream has, and say why")
    ap.add_argument("--report", default="", help="write the measurements as JSON")
    ap.add_argument("--timeout", type=float, default=300)
    ap.add_argument("--workspace", type=int, default=0, help="both boards' workspace budget, bytes (default: theirs)")
    ap.add_argument("--prefix", action="store_true",
                    help="a model stream larger than the workspace: each board must show the replay's first frames, "
                         "one per level it reports holding, and not all of them")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    failures = []

    if a.model:
        a.stream = os.path.join(a.work, "model.vds")
        enc = subprocess.run([a.vds, "encode-model", a.model, "-o", a.stream, *a.model_args.split()],
                             capture_output=True, text=True)
        print("== vds encode-model\n" + enc.stdout + enc.stderr)
        if enc.returncode != 0:
            print("the encoder side failed")
            return 1
    if a.stream:
        stream, want, encoder_log = a.stream, sim.replay_crcs(a.vds, a.stream), ""
        if not want:
            failures.append("`vds frames` gave no frames for the stream")
    else:
        stream, want, encoder_log = encode_frames(a, failures)
    if want is None:
        print("the encoder side failed")
        return 1

    # The live window too, on SDL's headless video driver.
    env = dict(os.environ, SDL_VIDEODRIVER="dummy")
    host = sim.run_host(a.vds, a.host_board, stream, a.baud, a.timeout, os.path.join(a.work, "host"), window=True,
                        env=env, workspace=a.workspace)
    print("== vds serve over a pty (host-native board)\n" + host.serve.stdout + host.serve.stderr)
    print("== host-native board\n" + host.board_log)
    qemu = sim.run_qemu(a.vds, a.qemu, a.elf, stream, a.baud, a.timeout, workspace=a.workspace)
    print("== vds serve over TCP (Cortex-M4 board in QEMU)\n" + qemu.serve.stdout + qemu.serve.stderr)
    print("== Cortex-M4 board\n" + qemu.board_log)

    for name, run in (("host-native", host), ("Cortex-M4", qemu)):
        if run.failure:
            failures.append(f"{name} board: {run.failure}")
        if not run.ok:
            failures.append(f"{name} board run failed (serve {run.serve.returncode}, board {run.board_rc})")
        if "client: the host said goodbye: report verified" not in run.board_log:
            failures.append(f"{name} board did not receive the host's Goodbye for a verified report")
    host_crcs = sim.frame_crcs(host.serve.stdout)
    qemu_crcs = sim.frame_crcs(qemu.serve.stdout)
    print(f"encoder  : {' '.join(want)}")
    print(f"host     : {' '.join(host_crcs)}")
    print(f"cortex-m4: {' '.join(qemu_crcs)}")
    shown = {"host-native": (host_crcs, host), "Cortex-M4": (qemu_crcs, qemu)}
    for name, (crcs, run) in shown.items():
        log = run.board_log
        expect = want
        if a.prefix:
            # The client says where its workspace ran out; it shows the base
            # and every level up to there, as the replay does.
            prefix = sim.model_prefix(log)
            if not prefix:
                failures.append(f"{name} board did not report a full workspace")
            else:
                expect = want[:prefix["level"] + 1]
                if len(expect) >= len(want):
                    failures.append(f"{name} board held every level: the stream does not test a prefix")
            # It then says so, and the host stops the stream.
            full = sim.full_report(run.serve.stdout)
            if not full:
                failures.append(f"{name} board: vds serve shows no verified workspace-full report")
            else:
                took = re.search(r"client: ok, \d+ frames, (\d+) stream bytes \(workspace full; (\d+) bytes in "
                                 r"flight dropped\)", log)
                if not took or int(took.group(1)) != full["bytes"]:
                    failures.append(f"{name} board's log does not show the {full['bytes']} bytes it reported")
                elif int(took.group(1)) + int(took.group(2)) >= full["stream"] or full["acked"] >= full["stream"]:
                    failures.append(f"{name} board received all {full['stream']} bytes: the host did not stop")
        if a.model:
            # The replay of this board: its workspace decides how fine the colours are.
            ws = re.search(r"client: ready, workspace (\d+) bytes, player from byte (\d+)", log)
            if not ws:
                failures.append(f"{name} board did not state its workspace")
            else:
                expect = sim.replay_crcs(a.vds, stream, workspace=(int(ws.group(1)), int(ws.group(2))))
                if a.partial_colours:
                    if expect is None or len(expect) >= len(want):
                        failures.append(f"{name} board's replay shows every frame: the stream does not test "
                                        "a client too small for its colours")
                    if "colours down to MIP level" not in log and "no room for the colours" not in log:
                        failures.append(f"{name} board did not say which colours it holds")
                elif expect != want:
                    failures.append(f"{name} board holds fewer colour levels than the stream has: "
                                    f"{len(expect or [])} of {len(want)} frames")
        if crcs != expect:
            failures.append(f"{name} board frame CRCs differ from the encoder's reconstruction")
    instr = sim.frame_instructions(qemu.serve.stdout)
    # Image frames split their decode into entropy and transform; a model's
    # frames (mesh decoding, then drawing) have no such split.
    # (A textured model's orbit frames decode nothing: they draw the model held.)
    if len(instr) != len(qemu_crcs) or any((d == 0 and not a.model) or (not a.stream and (e == 0 or t == 0)) or e + t > d
                                      for _, d, _, e, t in instr):
        failures.append("the Cortex-M4 board's per-stage instruction counts are missing or inconsistent")
    if "window:" in host.board_log:
        failures.append("the host board could not show its live window")
    png = os.path.join(a.work, "host", "frames", "frame0000.png")
    if not os.path.exists(png) or not os.path.exists(os.path.join(a.work, "host", "contact_sheet.png")):
        failures.append("the host board wrote no frame PNGs or contact sheet")
    if a.report:
        with open(a.report, "w") as f:
            json.dump({"stream_bytes": os.path.getsize(stream), "frames": len(want), "encoder_crcs": want,
                       "host_crcs": host_crcs, "qemu_crcs": qemu_crcs, "baud": a.baud,
                       "host_seconds": host.seconds, "qemu_seconds": qemu.seconds,
                       "qemu_instructions": instr, "encoder": encoder_log,
                       "serve_host": host.serve.stdout, "serve_qemu": qemu.serve.stdout,
                       "qemu_log": qemu.board_log}, f, indent=1)
    for f in failures:
        print("FAIL " + f)
    print("end-to-end: all boards agree with the encoder" if not failures else "end-to-end: FAILED")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
