// Cortex-M4 run of the client renderer under QEMU (mps2-an386, -icount
// shift=0): instructions per frame from SysTick and a CRC-32C of the frame,
// to compare with the host build (bit-exactness across targets).
//
// Reads render_case0.bin, render_case1.bin, ... (bench_render dump) from
// QEMU's working directory through semihosting until one is missing, and
// prints one line per case. bench/run_render.sh builds and runs it; results
// in bench/results/render.md.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "vds/crc32c.h"
#include "vds/render.h"

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

// ---- the case file -----------------------------------------------------------
alignas(8) uint8_t g_file[2 << 20];
alignas(8) uint8_t g_workspace[1 << 20];
uint8_t g_frame[480 * 360 * 3];

struct Reader {
  const uint8_t* p;
  const uint8_t* end;
  bool ok = true;
  uint32_t u32() {
    if (end - p < 4) {
      ok = false;
      return 0;
    }
    uint32_t v;
    std::memcpy(&v, p, 4);
    p += 4;
    return v;
  }
  uint16_t u16() {
    if (end - p < 2) {
      ok = false;
      return 0;
    }
    uint16_t v;
    std::memcpy(&v, p, 2);
    p += 2;
    return v;
  }
  uint8_t u8() {
    if (p >= end) {
      ok = false;
      return 0;
    }
    return *p++;
  }
  const uint8_t* take(size_t n) {
    const uint8_t* r = p;
    if (static_cast<size_t>(end - p) < n) {
      ok = false;
      return p;
    }
    p += n;
    while ((p - g_file) % 4 && p < end) ++p;
    return r;
  }
};

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

vds::Texture g_textures[16];
vds::Mesh g_meshes[64];

struct FrameCopy {
  uint32_t row_bytes;
};
bool copy_band(void* ctx, const vds::Band& b) {
  const auto* c = static_cast<const FrameCopy*>(ctx);
  for (uint32_t y = 0; y < b.height; ++y) {
    std::memcpy(g_frame + (b.y + y) * c->row_bytes, b.pixels + y * b.stride, c->row_bytes);
  }
  return true;
}

bool discard_band(void*, const vds::Band&) { return true; }

bool run_case(int index, uint32_t calib) {
  char file[32] = "render_case";
  size_t n = std::strlen(file);
  if (index >= 10) file[n++] = static_cast<char>('0' + index / 10);
  file[n++] = static_cast<char>('0' + index % 10);
  std::memcpy(file + n, ".bin", 5);
  const int len = load(file);
  if (len < 0) return false;

  Reader r{g_file, g_file + len};
  if (r.u32() != 0x32535256) {
    Text().s("m4 error: bad magic in ").s(file).s("\n").print();
    finish(false);
  }
  char name[33] = {};
  std::memcpy(name, r.take(32), 32);
  vds::RenderConfig cfg;
  cfg.format = static_cast<vds::PixelFormat>(r.u8());
  cfg.depth = static_cast<vds::DepthFormat>(r.u8());
  cfg.band_height = r.u16();
  cfg.vertex_cache = r.u32();
  cfg.triangle_cache = r.u32();
  const uint32_t frames = r.u32();
  cfg.width = r.u16();
  cfg.height = r.u16();
  vds::Camera cam{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) cam.rotation.m[i][j] = vds::Q2_30::from_raw(static_cast<int32_t>(r.u32()));
  vds::Q16_16* f[] = {&cam.position.x, &cam.position.y, &cam.position.z, &cam.fx, &cam.fy, &cam.cx, &cam.cy, &cam.near_z, &cam.far_z};
  for (vds::Q16_16* v : f) *v = vds::Q16_16::from_raw(static_cast<int32_t>(r.u32()));
  const uint32_t clear = r.u32();
  vds::DrawList list;
  list.num_positions = r.u32();
  list.positions = reinterpret_cast<const vds::Vec3<vds::Q16_16>*>(r.take(list.num_positions * 12));
  const uint32_t nt = r.u32();
  for (uint32_t i = 0; i < nt && i < 16; ++i) {
    vds::Texture& t = g_textures[i];
    t.format = static_cast<vds::TexFormat>(r.u8());
    t.address = static_cast<vds::TexAddress>(r.u8());
    t.width = r.u16();
    t.height = r.u16();
    t.apron = r.u8() != 0;
    r.u8();
    t.stride = t.width + (t.apron ? 1u : 0u);
    const uint32_t bytes = r.u32();
    t.texels = r.take(bytes);
  }
  list.num_meshes = r.u32();
  for (uint32_t i = 0; i < list.num_meshes && i < 64; ++i) {
    vds::Mesh& m = g_meshes[i];
    m.shading = static_cast<vds::Shading>(r.u8());
    m.filter = static_cast<vds::Filter>(r.u8());
    m.cull = static_cast<vds::Cull>(r.u8());
    r.u8();
    m.color = r.u32();
    const int32_t ti = static_cast<int32_t>(r.u32());
    m.texture = ti >= 0 && ti < 16 ? &g_textures[ti] : nullptr;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) m.view_map.m[a][b] = static_cast<int32_t>(r.u32());
    m.num_triangles = r.u32();
    m.indices = reinterpret_cast<const uint16_t*>(r.take(m.num_triangles * 6));
  }
  const vds::TexCoord* uvs = nullptr;
  const uint32_t* colors = nullptr;
  if (r.u32()) uvs = reinterpret_cast<const vds::TexCoord*>(r.take(list.num_positions * 8));
  if (r.u32()) colors = reinterpret_cast<const uint32_t*>(r.take(list.num_positions * 4));
  for (uint32_t i = 0; i < list.num_meshes; ++i) {
    g_meshes[i].uvs = uvs;
    g_meshes[i].colors = colors;
  }
  list.meshes = g_meshes;
  if (!r.ok || list.num_meshes > 64 || nt > 16) {
    Text().s("m4 error: truncated ").s(file).s("\n").print();
    finish(false);
  }

  vds::Arena arena(g_workspace, sizeof g_workspace);
  vds::Renderer renderer;
  vds::Status st = renderer.init(cfg, arena);
  FrameCopy copy{static_cast<uint32_t>(cfg.width) * static_cast<uint32_t>(vds::bytes_per_pixel(cfg.format))};
  // Measured frames go to a sink that does nothing (a display DMA would take
  // the band); one more frame is copied out for the checksum.
  const uint32_t t0 = now();
  for (uint32_t k = 0; k < frames && st == vds::Status::ok; ++k) st = renderer.render(cam, list, clear, discard_band, nullptr);
  const uint32_t ticks = ticks_since(t0);
  if (st == vds::Status::ok) st = renderer.render(cam, list, clear, copy_band, &copy);
  if (st != vds::Status::ok) {
    Text().s("m4 error: ").s(name).s(" status ").s(vds::status_name(st)).s("\n").print();
    finish(false);
  }
  const uint32_t crc = vds::crc32c(g_frame, copy.row_bytes * cfg.height);
  // Instructions per frame = ticks * 102000 / calib / frames.
  const uint64_t instr = static_cast<uint64_t>(ticks) * kCalibInstructions / calib / (frames ? frames : 1);
  const vds::RenderStats& s = renderer.stats();
  Text()
      .s("m4 case=")
      .s(name)
      .s(" frames=")
      .u(frames)
      .s(" instr_per_frame=")
      .u(static_cast<uint32_t>(instr))
      .s(" pixels=")
      .u(s.pixels)
      .s(" spans=")
      .u(s.spans)
      .s(" setups=")
      .u(s.setups)
      .s(" workspace=")
      .u(static_cast<uint32_t>(arena.used()))
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
  Text().s("m4 calibration instructions=").u(kCalibInstructions).s(" ticks=").u(calib).s("\n").print();
  int i = 0;
  while (run_case(i, calib)) ++i;
  if (i == 0) {
    Text().s("m4 error: no render_case0.bin\n").print();
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
