// Cortex-M4 run of the client image decoders under QEMU (mps2-an386,
// -icount shift=0): instructions per decode from SysTick, and a CRC-32C of
// the decoded RGB565 frame to compare with the host (bit-exactness across
// targets).
//
// Reads texture_case0.bin, texture_case1.bin, ... (written by
// `bench_texture m4-case`) from QEMU's working directory through semihosting
// until one is missing; prints one line per case. bench/run_texture.sh builds
// and runs it; results in bench/results/texture.md.
//
// Case file: "VTX1", u8 kind (0 = vds stream, 1 = JPEG file), u8 reps,
// u16 width, u16 height, u16 target (0 = RGB565 frame, 1 = Y'CbCr planes),
// u32 size, then the bytes.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "vds/container.h"
#include "vds/crc32c.h"
#include "vds/image.h"
#include "vds/jpeg.h"

namespace {

// ---- semihosting (ARM semihosting spec, BKPT 0xAB on M-profile) ----------
constexpr int kSysOpen = 0x01, kSysClose = 0x02, kSysWrite0 = 0x04, kSysRead = 0x06, kSysFlen = 0x0c, kSysExit = 0x18;
constexpr uint32_t kExitOk = 0x20026, kExitError = 0x20023;

int semihost(int op, const void* arg) {
  register int r0 asm("r0") = op;
  register const void* r1 asm("r1") = arg;
  asm volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

struct Text {
  char buf[200];
  size_t n = 0;
  Text& s(const char* t) {
    while (*t && n + 1 < sizeof buf) buf[n++] = *t++;
    buf[n] = 0;
    return *this;
  }
  Text& u(uint32_t v) {
    char tmp[12];
    int k = 0;
    do {
      tmp[k++] = static_cast<char>('0' + v % 10);
      v /= 10;
    } while (v);
    while (k && n + 1 < sizeof buf) buf[n++] = tmp[--k];
    buf[n] = 0;
    return *this;
  }
  Text& x(uint32_t v) {
    for (int i = 7; i >= 0 && n + 1 < sizeof buf; --i) buf[n++] = "0123456789abcdef"[(v >> (4 * i)) & 15];
    buf[n] = 0;
    return *this;
  }
  void print() { semihost(kSysWrite0, buf); }
};

[[noreturn]] void finish(bool ok) {
  semihost(kSysExit, reinterpret_cast<const void*>(ok ? kExitOk : kExitError));
  for (;;) {
  }
}

// ---- SysTick as an instruction counter (QEMU -icount: time per instruction)
volatile uint32_t* const kSystCsr = reinterpret_cast<volatile uint32_t*>(0xe000e010);
volatile uint32_t* const kSystRvr = reinterpret_cast<volatile uint32_t*>(0xe000e014);
volatile uint32_t* const kSystCvr = reinterpret_cast<volatile uint32_t*>(0xe000e018);
constexpr uint32_t kSystMask = 0x00ffffff;

uint32_t now() { return *kSystCvr; }
uint32_t ticks_since(uint32_t t0) { return (t0 - now()) & kSystMask; }

// 1000 x (100 NOPs + SUBS + BNE) = 102000 instructions.
__attribute__((noinline)) uint32_t calibrate() {
  const uint32_t t0 = now();
  uint32_t n = 1000;
  asm volatile(
      "1:\n"
      ".rept 100\n nop\n .endr\n"
      "subs %0, %0, #1\n"
      "bne 1b\n"
      : "+r"(n)
      :
      : "cc");
  return ticks_since(t0);
}
constexpr uint32_t kCalibInstructions = 102000;

alignas(8) uint8_t g_file[1 << 20];
// What a device would reserve: one chunk buffer and the decoders' workspace.
alignas(8) uint8_t g_workspace[65536 + vds::ImageDecoder::kWorkspaceBytes + vds::JpegDecoder::kWorkspaceBytes];
alignas(4) uint16_t g_frame[512 * 512];
uint8_t* g_planes[3] = {reinterpret_cast<uint8_t*>(g_frame), reinterpret_cast<uint8_t*>(g_frame) + 512 * 256,
                        reinterpret_cast<uint8_t*>(g_frame) + 512 * 256 + 256 * 128};
bool g_planar = false;

vds::ImageTarget target_for(uint16_t width) {
  if (g_planar) return vds::ImageTarget::planes(g_planes[0], width, g_planes[1], (width + 1) / 2, g_planes[2], (width + 1) / 2);
  return vds::ImageTarget::frame(vds::PixelFormat::rgb565, reinterpret_cast<uint8_t*>(g_frame), width * 2);
}

int load(const char* file) {
  struct {
    const char* name;
    uint32_t mode;
    uint32_t len;
  } args = {file, 1, static_cast<uint32_t>(std::strlen(file))};
  const int fd = semihost(kSysOpen, &args);
  if (fd < 0) return -1;
  const uint32_t fa[1] = {static_cast<uint32_t>(fd)};
  const int len = semihost(kSysFlen, fa);
  if (len <= 0 || static_cast<size_t>(len) > sizeof g_file) return -1;
  const uint32_t ra[3] = {static_cast<uint32_t>(fd), reinterpret_cast<uint32_t>(g_file), static_cast<uint32_t>(len)};
  const int left = semihost(kSysRead, ra);
  semihost(kSysClose, fa);
  return left == 0 ? len : -1;
}

struct VdsCtx {
  vds::ImageDecoder* dec;
  vds::Arena* arena;
  vds::ImageTarget target;
  vds::Status status;
};

bool on_header(void* ctx, const vds::StreamHeader&) {
  VdsCtx& c = *static_cast<VdsCtx*>(ctx);
  return c.dec->init(*c.arena) == vds::Status::ok;
}

vds::ChunkResult on_chunk(void* ctx, uint32_t type, const uint8_t* p, uint32_t size) {
  VdsCtx& c = *static_cast<VdsCtx*>(ctx);
  const vds::Status s = c.dec->on_chunk(type, p, size, c.target);
  if (vds::is_error(s)) {
    c.status = s;
    return vds::ChunkResult::abort;
  }
  return vds::ChunkResult::consumed;
}

// One decode of a vds stream: the stream parser (chunk CRCs included) and
// the image decoder, as the client firmware runs them.
vds::Status decode_vds(const uint8_t* data, uint32_t size, uint16_t width) {
  vds::Arena arena(g_workspace, sizeof g_workspace);
  vds::ImageDecoder dec;
  VdsCtx ctx{&dec, &arena, target_for(width), vds::Status::ok};
  vds::ChunkSink sink;
  sink.ctx = &ctx;
  sink.on_header = on_header;
  sink.on_chunk = on_chunk;
  vds::StreamParser parser;
  vds::Status s = parser.init(arena, 65536, sink);
  if (s != vds::Status::ok) return s;
  s = parser.feed(data, size);
  if (ctx.status != vds::Status::ok) return ctx.status;
  if (s != vds::Status::ok) return s;
  return dec.done() ? vds::Status::ok : vds::Status::truncated;
}

vds::Status decode_jpeg(const uint8_t* data, uint32_t size, uint16_t width) {
  vds::Arena arena(g_workspace, sizeof g_workspace);
  vds::JpegDecoder dec;
  const vds::Status s = dec.init(arena);
  if (s != vds::Status::ok) return s;
  return dec.decode(data, size, target_for(width));
}

bool run_case(int index, uint32_t calib) {
  char file[32] = "texture_case";
  size_t n = std::strlen(file);
  if (index >= 10) file[n++] = static_cast<char>('0' + index / 10);
  file[n++] = static_cast<char>('0' + index % 10);
  std::memcpy(file + n, ".bin", 5);
  const int len = load(file);
  if (len < 0) return false;
  if (len < 16 || std::memcmp(g_file, "VTX1", 4) != 0) {
    Text().s("m4 error: bad case file ").s(file).s("\n").print();
    finish(false);
  }
  const uint8_t kind = g_file[4], reps = g_file[5];
  uint16_t w, h;
  uint32_t size;
  std::memcpy(&w, g_file + 6, 2);
  std::memcpy(&h, g_file + 8, 2);
  std::memcpy(&size, g_file + 12, 4);
  g_planar = g_file[10] == 1;
  const uint8_t* data = g_file + 16;
  if (size + 16 > static_cast<uint32_t>(len) || static_cast<uint32_t>(w) * h > sizeof g_frame / 2 || reps == 0) {
    Text().s("m4 error: bad case header ").s(file).s("\n").print();
    finish(false);
  }
  uint64_t ticks = 0;
  vds::Status s = vds::Status::ok;
  for (int r = 0; r < reps && s == vds::Status::ok; ++r) {
    std::memset(g_frame, 0, sizeof g_frame);
    const uint32_t t0 = now();
    s = kind == 0 ? decode_vds(data, size, w) : decode_jpeg(data, size, w);
    ticks += ticks_since(t0);
  }
  if (s != vds::Status::ok) {
    Text().s("m4 error: ").s(file).s(" status ").s(vds::status_name(s)).s("\n").print();
    finish(false);
  }
  const uint32_t crc = vds::crc32c(reinterpret_cast<const uint8_t*>(g_frame), static_cast<size_t>(w) * h * 2);
  const uint64_t instr = ticks * kCalibInstructions / calib / reps;
  Text()
      .s("m4 case=")
      .u(static_cast<uint32_t>(index))
      .s(kind == 0 ? " kind=vds" : " kind=jpeg")
      .s(g_planar ? " target=planes" : " target=rgb565")
      .s(" bytes=")
      .u(size)
      .s(" instr=")
      .u(static_cast<uint32_t>(instr))
      .s(" crc=")
      .x(crc)
      .s("\n")
      .print();
  return true;
}

}  // namespace

int bench_main() {
  *kSystRvr = kSystMask;
  *kSystCvr = 0;
  *kSystCsr = 5;  // enable, processor clock
  const uint32_t calib = calibrate();
  if (calib == 0) {
    Text().s("m4 error: SysTick does not advance (run QEMU with -icount shift=0)\n").print();
    finish(false);
  }
  Text()
      .s("m4 sizes image_workspace=")
      .u(static_cast<uint32_t>(vds::ImageDecoder::kWorkspaceBytes))
      .s(" image_object=")
      .u(static_cast<uint32_t>(sizeof(vds::ImageDecoder)))
      .s(" jpeg_workspace=")
      .u(static_cast<uint32_t>(vds::JpegDecoder::kWorkspaceBytes))
      .s(" jpeg_object=")
      .u(static_cast<uint32_t>(sizeof(vds::JpegDecoder)))
      .s(" parser_object=")
      .u(static_cast<uint32_t>(sizeof(vds::StreamParser)))
      .s("\n")
      .print();
  int i = 0;
  while (run_case(i, calib)) ++i;
  if (i == 0) {
    Text().s("m4 error: no texture_case0.bin\n").print();
    finish(false);
  }
  finish(true);
}

extern "C" {
extern uint32_t __stack_top;
[[noreturn]] void reset_handler() {
  bench_main();
  finish(true);
}
[[noreturn]] void fault_handler() {
  Text().s("m4 error: fault\n").print();
  finish(false);
}
__attribute__((section(".vectors"), used)) const void* const g_vectors[16] = {
    &__stack_top,
    reinterpret_cast<const void*>(reset_handler),
    reinterpret_cast<const void*>(fault_handler),
    reinterpret_cast<const void*>(fault_handler),
    reinterpret_cast<const void*>(fault_handler),
    reinterpret_cast<const void*>(fault_handler),
    reinterpret_cast<const void*>(fault_handler),
};
}
