#!/usr/bin/env bash
# The vds image codec and the client's baseline JPEG decoder against
# libjpeg-turbo, written to bench/results/texture.md and texture_*.png:
#   1. rate-distortion on a fixed public set: 26 textures (23 OpenArena from
#      pak4-textures.pk3, 3 glmark2) and 10 rendered views (5 at 240x180, 5 at
#      512x512, ray-cast rooms built from the OpenArena textures), over
#      0.25-2 bits/pixel: vds (default settings) vs cjpeg -optimize and
#      cjpeg -arithmetic (decoded by djpeg -dct int), BD-rate (Bjontegaard,
#      PCHIP) per image and per set; the same for other perceptual slopes;
#   2. client decode cost of the five 240x180 views: the JPEG cjpeg -quality 85
#      writes, and the vds stream at the same RGB PSNR (as the client decodes
#      the JPEG), both to an RGB565 frame: Cortex-M4 instructions of the board
#      firmware vds_fw_bench_texture (firmware_sim/app/bench_texture.cpp) under
#      QEMU mps2-an386 -icount, with a cross-target CRC check, and x86-64
#      instructions from callgrind;
#   3. decoder workspace and Cortex-M4 .text of each decoder (arm-none-eabi-g++
#      -O2, --gc-sections, arm-none-eabi-size).
#
# Usage: bench/run_texture.sh [BUILD_DIR]      (default build/host-release)
#   BUILD_DIR must hold bench/bench_texture (a release build: cmake --preset
#   host-release && cmake --build --preset host-release --target bench_texture).
#   The firmware is built in the Cortex-M4 build CM4_BUILD (default
#   BUILD_DIR/cm4, the host presets' sub-build; configured here with
#   toolchain/arm-none-eabi-cortex-m4.cmake if it does not exist yet).
#   QUICK=1 uses a coarser quality ladder (for trying changes).
#   bench/run_texture.sh --train [BUILD_DIR] regenerates the trained context
#   starting probabilities (decoder/src/image_model_init.inc) from the training
#   textures below (never the benchmark set); the stream format changes with
#   them, so tests/golden/image-v1.vds must then be regenerated on purpose.
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
TRAIN=0
if [[ "${1:-}" == "--train" ]]; then
  TRAIN=1
  shift
fi
BUILD=${1:-build/host-release}
case "$BUILD" in /*) ;; *) BUILD="$ROOT/$BUILD" ;; esac
BENCH="$BUILD/bench/bench_texture"
PK3=/usr/share/games/openarena/baseoa/pak4-textures.pk3
GLMARK=/usr/share/glmark2/textures
PY=/usr/bin/python3
OUT="$ROOT/bench/results"

for t in cjpeg djpeg "$PY"; do command -v "$t" >/dev/null || { echo "run_texture.sh: $t is required" >&2; exit 1; }; done
[[ -f "$PK3" && -d "$GLMARK" ]] || { echo "run_texture.sh: OpenArena/glmark2 data missing (scripts/fetch-data.sh)" >&2; exit 1; }

WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

# The benchmark textures (OpenArena pak4-textures.pk3 members, then glmark2).
BENCH_OA=(
  acc_dm3/comp_up acc_dm3/ind_wall1 base_floor/concretefloor1 base_floor/metaltechfloor01final
  base_floor/proto_rustygrate base_floor/rusty_pentagrate base_support/x_support base_wall/concrete_ow
  base_wall/metalfloor_wall_15ow base_wall/patch10_beatup4_alpha bubctf1/e8_jumppad02 clown/fleshy
  clown/vegetation cosmo_block/rock05 cosmo_wall/brickwall1 czest3ctf/grass_lush gothic_block/blocks17_ow
  gothic_wall/proto_brik liquids/lavahell2 nki/nki_forest2 organics/dirt proto2/concrete01wetwall
  sfx2/jump_pad02
)
BENCH_GLMARK=(crate-base.png nasa1.png effect-2d.png)
# Training textures for the context starting probabilities: disjoint from the above.
TRAIN_OA=(
  acc_dm3/grind base_door/c_ggrate8_b base_floor/clang_floor3blava base_floor/proto_rustygrate2
  base_support/x_support2 base_wall/bluemetal1b_shiny base_wall/concrete_ow2 bubctf1/e8_launchpad1
  clown/steel_bev cosmo_block/beton2 cosmo_block/rock06 cosmo_trim/beton3 cosmo_wall/brickwall2
  czest3ctf/tile_teracota evil3_floors/cemdrk gothic_block/blocks18b_ow gothic_floor/largerblock3b3dim
  liquids/lavahell4 nki/nki_forest3 nki/nki_ground1 organics/dirt2 proto2/marble02b_s
  sfx/metalfloor_wall_14b skies/s17
)

extract() {  # extract NAME... from the pk3 into $WORK/tex (flat)
  mkdir -p "$WORK/tex"
  "$PY" - "$PK3" "$WORK/tex" "$@" <<'PY'
import sys, zipfile, os
pk3, dest, names = sys.argv[1], sys.argv[2], sys.argv[3:]
with zipfile.ZipFile(pk3) as z:
    for n in names:
        with open(os.path.join(dest, os.path.basename(n) + '.tga'), 'wb') as f:
            f.write(z.read('textures/' + n + '.tga'))
PY
}

if [[ $TRAIN == 1 ]]; then
  TRAINER="$BUILD/bench/bench_texture_train"
  [[ -x "$TRAINER" ]] || { echo "run_texture.sh: $TRAINER not found" >&2; exit 1; }
  extract "${TRAIN_OA[@]}"
  for n in "${TRAIN_OA[@]}"; do echo "$(basename "$n") $WORK/tex/$(basename "$n").tga"; done >"$WORK/train.txt"
  "$TRAINER" "$WORK/train.txt" "$ROOT/decoder/src/image_model_init.inc"
  echo "wrote decoder/src/image_model_init.inc: rebuild, run once more (the encoder's decisions depend on it), then"
  echo "regenerate tests/golden/image-v1.vds with VDS_REGENERATE_GOLDEN=1 and update its pinned figures"
  exit 0
fi

[[ -x "$BENCH" ]] || { echo "run_texture.sh: $BENCH not found; build it first (see the header)" >&2; exit 1; }
QUICKARG=()
[[ "${QUICK:-0}" == 1 ]] && QUICKARG=(--quick)

# --- 1. rate-distortion ---------------------------------------------------------
echo "== textures and views"
extract "${BENCH_OA[@]}"
LIST="$WORK/list.txt"
: >"$LIST"
for n in "${BENCH_OA[@]}"; do echo "$(basename "$n") $WORK/tex/$(basename "$n").tga" >>"$LIST"; done
for n in "${BENCH_GLMARK[@]}"; do echo "${n%.png} $GLMARK/$n" >>"$LIST"; done
mkdir -p "$WORK/views"
"$BENCH" views "$WORK/tex" "$WORK/views" >/dev/null
for f in "$WORK"/views/view*.png; do echo "$(basename "${f%.png}") $f" >>"$LIST"; done
echo "$(wc -l <"$LIST") images"

echo "== rate-distortion (vds default, cjpeg -optimize, cjpeg -arithmetic)"
"$BENCH" rd "$LIST" "$WORK/rd.csv" "${QUICKARG[@]}"
"$BENCH" bd "$WORK/rd.csv" "$WORK/bd.md" "$WORK/plot.csv" | tee "$WORK/bd_summary.txt"
cp "$WORK/rd.csv" "$OUT/texture_rd.csv"

# Other perceptual slopes, vds only, against the same anchors.
for slope in 0 8 16; do
  echo "== slope $slope"
  "$BENCH" rd "$LIST" "$WORK/rd_s$slope.csv" --no-anchors --slope=$slope "${QUICKARG[@]}"
  (grep -v ',vds,' "$WORK/rd.csv"; tail -n +2 "$WORK/rd_s$slope.csv") >"$WORK/m_s$slope.csv"
  "$BENCH" bd "$WORK/m_s$slope.csv" "$WORK/bd_s$slope.md" "$WORK/plot_s$slope.csv" | tee "$WORK/bd_s$slope.txt"
done

echo "== plots"
"$PY" - "$WORK/plot.csv" "$WORK/bd.md" "$OUT" <<'PY'
import csv, sys, collections, math
import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt
plot_csv, bd_md, out = sys.argv[1], sys.argv[2], sys.argv[3]
data = collections.defaultdict(lambda: collections.defaultdict(list))
order = []
for r in csv.DictReader(open(plot_csv)):
    if r['image'] not in data: order.append(r['image'])
    data[r['image']][r['codec']].append((float(r['bpp']), float(r['psnr_rgb'])))
style = {'vds': ('tab:red', 'vds'), 'jpeg-opt': ('tab:blue', 'libjpeg-turbo -optimize'),
         'jpeg-arith': ('tab:green', 'libjpeg-turbo -arithmetic')}
n = len(order); cols = 6; rows = math.ceil(n / cols)
fig, axes = plt.subplots(rows, cols, figsize=(cols * 3.2, rows * 2.6))
for ax, img in zip(axes.flat, order):
    for codec, (col, label) in style.items():
        pts = sorted(p for p in data[img][codec] if 0.15 <= p[0] <= 2.6)
        if pts: ax.plot([p[0] for p in pts], [p[1] for p in pts], '-', color=col, lw=1.2, label=label)
    ax.axvspan(0.25, 2.0, color='0.93', zorder=0)
    ax.set_title(img, fontsize=8); ax.tick_params(labelsize=6); ax.grid(alpha=0.3)
for ax in list(axes.flat)[n:]: ax.axis('off')
axes.flat[0].legend(fontsize=6)
fig.supxlabel('bits per pixel (shaded: 0.25-2, the BD-rate range)'); fig.supylabel('RGB PSNR (dB)')
fig.tight_layout(); fig.savefig(out + '/texture_rd_all.png', dpi=80)
# Four examples, large.
ex = [i for i in ('concrete_ow', 'grass_lush', 'crate-base', 'view03_240x180') if i in data]
fig, axes = plt.subplots(1, len(ex), figsize=(4.2 * len(ex), 3.6))
for ax, img in zip(axes, ex):
    for codec, (col, label) in style.items():
        pts = sorted(p for p in data[img][codec] if 0.15 <= p[0] <= 2.6)
        ax.plot([p[0] for p in pts], [p[1] for p in pts], 'o-', ms=2.5, color=col, lw=1.4, label=label)
    ax.axvspan(0.25, 2.0, color='0.93', zorder=0)
    ax.set_title(img); ax.set_xlabel('bits per pixel'); ax.grid(alpha=0.3)
axes[0].set_ylabel('RGB PSNR (dB)'); axes[0].legend(fontsize=8)
fig.tight_layout(); fig.savefig(out + '/texture_rd_examples.png', dpi=90)
# BD-rate per image.
names, opt, ari = [], [], []
for line in open(bd_md):
    cells = [c.strip() for c in line.strip().strip('|').split('|')]
    if len(cells) == 5 and cells[1].endswith('%') and cells[0] in data:
        names.append(cells[0]); opt.append(float(cells[1].rstrip(' %'))); ari.append(float(cells[2].rstrip(' %')))
fig, ax = plt.subplots(figsize=(12, 4))
x = range(len(names))
ax.bar([i - 0.2 for i in x], opt, 0.4, color='tab:blue', label='vs libjpeg-turbo -optimize')
ax.bar([i + 0.2 for i in x], ari, 0.4, color='tab:green', label='vs libjpeg-turbo -arithmetic')
ax.axhline(-15, color='k', ls='--', lw=1, label='goal -15 %')
ax.set_xticks(list(x)); ax.set_xticklabels(names, rotation=75, fontsize=7)
ax.set_ylabel('BD-rate of vds (%, RGB PSNR)'); ax.legend(fontsize=8); ax.grid(axis='y', alpha=0.3)
fig.tight_layout(); fig.savefig(out + '/texture_bdrate.png', dpi=90)
PY

# --- 2. client decode cost -----------------------------------------------------------
echo "== decode cost (240x180 views: JPEG quality 85 and vds at equal PSNR)"
mkdir -p "$WORK/m4"
CASES="$WORK/cases.txt"
: >"$CASES"
i=0
for v in 0 1 2 3 4; do
  src="$WORK/views/view0${v}_240x180.png"
  "$PY" -c "from PIL import Image; Image.open('$src').convert('RGB').save('$WORK/v$v.ppm')"
  cjpeg -quality 85 -outfile "$WORK/v$v.jpg" "$WORK/v$v.ppm"
  djpeg -dct int -nosmooth -ppm -outfile "$WORK/v$v.dec.ppm" "$WORK/v$v.jpg"
  psnr=$("$BENCH" psnr "$src" "$WORK/v$v.dec.ppm")
  mk=$("$BENCH" make-vds "$src" "$WORK/v$v.vds" "$psnr")
  vpsnr=$(echo "$mk" | sed -n 's/.*RGB PSNR \([0-9.]*\) dB.*/\1/p')
  jcrc=$("$BENCH" m4-case "$WORK/v$v.jpg" "$WORK/m4/texture_case$i.bin" 3 | sed -n 's/.*host_crc=//p')
  vcrc=$("$BENCH" m4-case "$WORK/v$v.vds" "$WORK/m4/texture_case$((i + 1)).bin" 3 | sed -n 's/.*host_crc=//p')
  jx=$(valgrind --tool=callgrind --callgrind-out-file="$WORK/cg.j$v" --collect-atstart=no \
        --toggle-collect='vds::Player::feed*' "$BENCH" decode "$WORK/v$v.jpg" 1 2>&1 >/dev/null |
       sed -n 's/.*Collected : \([0-9]*\).*/\1/p')
  vx=$(valgrind --tool=callgrind --callgrind-out-file="$WORK/cg.v$v" --collect-atstart=no \
        --toggle-collect='vds::Player::feed*' "$BENCH" decode "$WORK/v$v.vds" 1 2>&1 >/dev/null |
       sed -n 's/.*Collected : \([0-9]*\).*/\1/p')
  echo "view0$v $psnr $(stat -c %s "$WORK/v$v.jpg") $jcrc $jx $vpsnr $(stat -c %s "$WORK/v$v.vds") $vcrc $vx" | tee -a "$CASES"
  i=$((i + 2))
done

ARM_FLAGS=(-std=c++20 -mcpu=cortex-m4 -mthumb -mfloat-abi=soft -O2 -ffreestanding -fno-exceptions -fno-rtti
  -fno-threadsafe-statics -ffunction-sections -fdata-sections -I"$ROOT/decoder/include")
HAVE_M4=0
if command -v arm-none-eabi-g++ >/dev/null && command -v qemu-system-arm >/dev/null; then
  HAVE_M4=1
  # The Cortex-M4 build: the host build's sub-build when there is one (the
  # presets make it), else configured here.
  CM4=${CM4_BUILD:-$BUILD/cm4}
  case "$CM4" in /*) ;; *) CM4="$ROOT/$CM4" ;; esac
  if [[ ! -f "$CM4/build.ninja" ]]; then
    cmake -S "$ROOT" -B "$CM4" -G Ninja -DCMAKE_TOOLCHAIN_FILE="$ROOT/toolchain/arm-none-eabi-cortex-m4.cmake" \
      -DCMAKE_BUILD_TYPE=Release >/dev/null
  fi
  cmake --build "$CM4" --target vds_fw_bench_texture >/dev/null
  ELF="$CM4/firmware_sim/vds_fw_bench_texture.elf"
  echo "== Cortex-M4 ($ELF on QEMU mps2-an386 -icount shift=0)"
  # The firmware reads texture_case<N>.bin from its working directory through
  # semihosting; its console output arrives on QEMU's stderr.
  (cd "$WORK/m4" && timeout 600 qemu-system-arm -M mps2-an386 -cpu cortex-m4 -nographic -monitor none -serial none \
     -semihosting-config enable=on,target=native -icount shift=0 -kernel "$ELF") 2>&1 | grep '^m4 ' | tee "$WORK/m4.txt"
  grep -q '^m4 done' "$WORK/m4.txt" || { echo "run_texture.sh: the Cortex-M4 run failed" >&2; exit 1; }

  # .text of each decoder alone: a probe that uses only it, linked with --gc-sections.
  cat >"$WORK/m4/probe_vds.cpp" <<'CPP'
#include "vds/image.h"
alignas(8) unsigned char ws[vds::ImageDecoder::kWorkspaceBytes];
extern "C" int probe(const unsigned char* h, const unsigned char* d, unsigned n, unsigned char* px) {
  vds::Arena a(ws, sizeof ws);
  vds::ImageDecoder dec;
  dec.init(a);
  dec.start(h, 12, vds::ImageTarget::frame(vds::PixelFormat::rgb565, px, 480));
  return static_cast<int>(dec.feed(d, n));
}
extern "C" [[noreturn]] void reset_handler() { for (;;) probe(nullptr, nullptr, 0, nullptr); }
CPP
  cat >"$WORK/m4/probe_jpeg.cpp" <<'CPP'
#include "vds/jpeg.h"
alignas(8) unsigned char ws[vds::JpegDecoder::kWorkspaceBytes];
extern "C" int probe(const unsigned char* d, unsigned n, unsigned char* px) {
  vds::Arena a(ws, sizeof ws);
  vds::JpegDecoder dec;
  dec.init(a);
  return static_cast<int>(dec.decode(d, n, vds::ImageTarget::frame(vds::PixelFormat::rgb565, px, 480)));
}
extern "C" [[noreturn]] void reset_handler() { for (;;) probe(nullptr, 0, nullptr); }
CPP
  (cd "$WORK/m4" &&
   for p in vds jpeg; do
     arm-none-eabi-g++ "${ARM_FLAGS[@]}" -c probe_$p.cpp -o probe_$p.o.p
     arm-none-eabi-g++ -mcpu=cortex-m4 -mthumb -mfloat-abi=soft -nostartfiles -nostdlib -Wl,-e,reset_handler \
       -Wl,--gc-sections probe_$p.o.p "$CM4/decoder/libvds_decoder.a" -lc -lgcc -o probe_$p.elf
     echo "$p $(arm-none-eabi-size probe_$p.elf | tail -1)"
   done) | tee "$WORK/sizes.txt"
fi

# --- 3. the report -------------------------------------------------------------------
echo "== writing $OUT/texture.md"
"$PY" - "$WORK" "$OUT/texture.md" "$HAVE_M4" "$BENCH" <<'PY'
import sys, re, subprocess, platform, datetime
work, out, have_m4, bench = sys.argv[1], sys.argv[2], sys.argv[3] == '1', sys.argv[4]
def read(p):
    try: return open(p).read()
    except OSError: return ''
bd = read(work + '/bd.md')
summary = read(work + '/bd_summary.txt').strip()
slopes = {s: read(f'{work}/bd_s{s}.txt').strip() for s in (0, 8, 16)}
cases = [l.split() for l in read(work + '/cases.txt').splitlines() if l.strip()]
m4 = {}
m4sizes = {}
for l in read(work + '/m4.txt').splitlines():
    f = dict(kv.split('=') for kv in l.split()[1:] if '=' in kv)
    if 'case' in f: m4[int(f['case'])] = f
    elif l.startswith('m4 sizes'): m4sizes = f
sizes = dict((l.split()[0], l.split()[1:]) for l in read(work + '/sizes.txt').splitlines() if l.strip())
ws = subprocess.run([bench, 'workspace'], capture_output=True, text=True).stdout.strip()
def tool(cmd):
    try: return subprocess.run(cmd, capture_output=True, text=True, shell=True).stdout.splitlines()[0]
    except Exception: return 'n/a'
L = []
L.append('# Texture codec: the vds image codec and baseline JPEG against libjpeg-turbo\n')
L.append(f'Produced by `bench/run_texture.sh` on {datetime.date.today()}. Codec design: `docs/texture-codec.md`.\n')
L.append('## Machine and tools\n')
L.append(f'- host: {platform.processor() or platform.machine()}, {platform.system()} {platform.release()}')
L.append(f'- libjpeg-turbo: {tool("cjpeg -version 2>&1")}')
L.append(f'- Cortex-M4 compiler: {tool("arm-none-eabi-g++ --version")}')
L.append(f'- QEMU: {tool("qemu-system-arm --version")}')
L.append(f'- valgrind: {tool("valgrind --version")}\n')
L.append('## Rate-distortion (goal: BD-rate <= -15 % against libjpeg-turbo with optimised Huffman tables)\n')
L.append('Images: 23 OpenArena textures (`pak4-textures.pk3`, lossless TGA sources) and 3 glmark2 textures (PNG), plus 10 '
         'views rendered from OpenArena textures by `bench_texture views` (ray-cast rooms, bilinear filtering, 2x2 '
         'supersampling, two point lights): 5 at 240x180, 5 at 512x512. Alpha is dropped.\n')
L.append('- **vds**: default settings (4:2:0, perceptual slope 4, trellis quantisation), the quantiser index stepped '
         'over 8..232; size = the IMGH and IMGD chunks with their 12-byte chunk framing (what the image adds to a stream).')
L.append('- **jpeg-opt**: `cjpeg -optimize -quality Q` (4:2:0, default tables, islow DCT), size = the whole .jpg file.')
L.append('- **jpeg-arith**: `cjpeg -arithmetic -quality Q`.')
L.append('- Both JPEGs decoded by `djpeg -dct int` with its default (fancy) upsampling, its best PSNR; vds decoded by the '
         'client decoder (replicated chroma), and checked bit-exact against the encoder\'s reconstruction on every point.')
L.append('- Distortion: PSNR over the R, G and B samples against the source (primary); Y\' PSNR (JFIF luma of both '
         'RGB images) as a second measure.')
L.append('- BD-rate: per image, log10(bits/pixel) as a monotone piecewise-cubic (PCHIP) function of PSNR for each codec, '
         'each curve cut to 0.25..2 bits/pixel, mean difference over the overlapping PSNR interval; the set figures '
         'are means of the per-image figures.\n')
L.append('Summary (`bench_texture bd`): ' + summary + '\n')
L.append('Per image:\n')
L.append(bd.strip() + '\n')
L.append('![rate-distortion, four examples](texture_rd_examples.png)\n')
L.append('![BD-rate per image](texture_bdrate.png)\n')
L.append('All curves: [texture_rd_all.png](texture_rd_all.png). Raw points: [texture_rd.csv](texture_rd.csv).\n')
L.append('### The perceptual slope\n')
L.append('The quantisation tables are the T.81 Annex K shapes scaled by a slope (0 = flat, 16 = the full Annex K '
         'shape; default 4). PSNR rewards flat tables; the eye prefers coarser high frequencies. Same images, same anchors:\n')
L.append('| slope | result |\n|---|---|')
L.append('| 4 (default) | ' + summary + ' |')
for s in (0, 8, 16): L.append(f'| {s} | {slopes[s]} |')
L.append('')
L.append('## Client decode cost (goals: baseline JPEG <= 80, vds <= 100 instructions/pixel)\n')
L.append('Each 240x180 view coded by `cjpeg -quality 85` (4:2:0, standard Huffman tables, as the TJpgDec anchor: '
         '12,464 bytes at 155 instructions/pixel, 132 with its lookup tables) and by vds at the smallest size whose '
         'RGB PSNR reaches that of the JPEG as the client decodes it (no fancy upsampling). Both decoded by the client '
         'library to an RGB565 frame, each as an images stream played by `vds::Player` as the client plays it (the JPEG '
         'in 4096-byte JPEG chunks): counts are the parse and decode of the player\'s frame record (chunk framing and '
         'CRC-32C checks, entropy decoding, IDCT, colour conversion into the band; `decode_stages` off, so no clock '
         'reads per block), the band copies and the frame CRC excluded. Cortex-M4: '
         'executed instructions of the board firmware `vds_fw_bench_texture` (`firmware_sim/app/bench_texture.cpp`, '
         'the Cortex-M4 build: arm-none-eabi-g++ -O2) on the QEMU board mps2-an386 with `-icount shift=0` '
         '(`board::instructions()`, 40 instructions per tick), mean of 3 plays; input, chunk buffer and decoder '
         'workspace inside the board\'s 128 KiB workspace budget; x86-64: callgrind Ir '
         '(clang -O3) inside `vds::Player::feed`, band copies and the frame CRC included.\n')
L.append('| view | JPEG bytes | JPEG PSNR | M4 instr/px | x86 instr/px | vds bytes | vds PSNR | M4 instr/px | x86 instr/px | M4 = host output |')
L.append('|---|---:|---:|---:|---:|---:|---:|---:|---:|---|')
px = 240 * 180
worst = [0, 0]
for k, c in enumerate(cases):
    name, jp, jb, jcrc, jx, vp, vb, vcrc, vx = c
    jm = m4.get(2 * k, {}); vm = m4.get(2 * k + 1, {})
    jmi = int(jm['instr']) / px if jm else float('nan'); vmi = int(vm['instr']) / px if vm else float('nan')
    same = 'yes' if jm.get('crc') == jcrc and vm.get('crc') == vcrc else ('n/a' if not jm else 'NO')
    worst = [max(worst[0], jmi), max(worst[1], vmi)]
    L.append(f'| {name} | {jb} | {float(jp):.2f} | {jmi:.1f} | {int(jx)/px:.1f} | {vb} | {float(vp):.2f} | {vmi:.1f} | {int(vx)/px:.1f} | {same} |')
L.append(f'\nLargest Cortex-M4 cost: baseline JPEG {worst[0]:.1f}, vds {worst[1]:.1f} instructions/pixel.\n')
L.append('## Memory and code size\n')
L.append('Client memory per decoder: the decoder object (the caller allocates it) plus a workspace carved from the '
         'caller\'s Arena at init(); both are constants, independent of the image size. A stream client also needs '
         'the stream parser and its chunk buffer (max_chunk_payload, 4096 bytes for the streams `vds encode-image` '
         'writes by default).\n')
if m4sizes:
    L.append('| decoder | workspace bytes | object bytes (Cortex-M4) |\n|---|---:|---:|')
    L.append(f'| vds image (`vds::ImageDecoder`) | {m4sizes["image_workspace"]} | {m4sizes["image_object"]} |')
    L.append(f'| baseline JPEG (`vds::JpegDecoder`) | {m4sizes["jpeg_workspace"]} | {m4sizes["jpeg_object"]} |')
    L.append(f'| stream parser (`vds::StreamParser`) | chunk buffer | {m4sizes["parser_object"]} |')
    L.append(f'| the player (`vds::Player`, both decoders and the parser inside) | chunk buffer + band buffer + a decoder\'s | {m4sizes.get("player_object", "n/a")} |\n')
L.append('Host view (`bench_texture workspace`):\n\n```\n' + ws + '\n```\n')
if sizes:
    L.append('Cortex-M4 `.text` of a program that uses only one decoder (`arm-none-eabi-g++ -O2 -ffunction-sections`, '
             '`--gc-sections`; the vds decoder without the stream parser, which the client links anyway):\n')
    L.append('| decoder | text | data | bss (workspace array included) |\n|---|---:|---:|---:|')
    for k, v in sizes.items(): L.append(f'| {k} | {v[0]} | {v[1]} | {v[2]} |')
    L.append('')
L.append('## Reproduce\n')
L.append('```sh\ncmake --preset host-release && cmake --build --preset host-release --target bench_texture\n'
         'bench/run_texture.sh build/host-release\n```\n')
L.append('Pieces by hand: `bench_texture views|rd|bd|decode|make-vds|m4-case|psnr|workspace` (usage at the top of '
         '`bench/src/texture.cpp`); the firmware build and the QEMU command line are in `bench/run_texture.sh`, '
         'step 2 (`CM4_BUILD=dir` picks the Cortex-M4 build).\n')
open(out, 'w').write('\n'.join(L))
PY
echo "done: $OUT/texture.md"
