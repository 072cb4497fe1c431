// The renderer benchmark on a board (bench/run_render.sh, and the ctest that
// compares the host and Cortex-M4 builds): renders the cases that
// `bench_render cases` writes (render_case0.bin, render_case1.bin, ... in the
// working directory, read through board::host_file_read until one is
// missing) and prints, per case, the CRC-32C of the frame and, on a board
// with an instruction counter, instructions per frame and per pixel.
//
// Output lines:
//   check render case=NAME pixels=N crc=XXXXXXXX          (every board)
//   m4 case=NAME frames=F instr_per_frame=I instr_per_pixel=P.P pixels=N
//      spans=S setups=U workspace=W crc=XXXXXXXX        (boards with a counter)
//   skip render case=NAME reason=...                      (does not fit in RAM)
// The file layout is the one of bench/src/render.cpp (cmd_dump).
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "band_crc.h"
#include "print.h"
#include "vds/board.h"
#include "vds/crc32c.h"
#include "vds/render.h"

namespace {

using vds::fw::Line;

constexpr uint32_t kMagic = 0x33535256;  // "VRS3"
constexpr int kMaxTextures = 16;
constexpr int kMaxMeshes = 64;

// One block for the case file and, after it, the renderer's workspace. Its
// size is what the 256 KiB RAM budget of the Cortex-M4 build leaves after
// the stack and the board (the same on every board, so every board skips
// the same cases).
constexpr uint32_t kMemBytes = 236 * 1024;
alignas(8) uint8_t g_mem[kMemBytes];

vds::Texture g_textures[kMaxTextures];
vds::Mesh g_meshes[kMaxMeshes];

// Little-endian reads from the case file; `ok` turns false at its end.
struct Reader {
  const uint8_t* begin;
  const uint8_t* p;
  const uint8_t* end;
  bool ok = true;

  uint32_t u32() {
    if (end - p < 4) return fail();
    const uint32_t v = static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 |
                       static_cast<uint32_t>(p[2]) << 16 | static_cast<uint32_t>(p[3]) << 24;
    p += 4;
    return v;
  }
  uint16_t u16() {
    if (end - p < 2) return static_cast<uint16_t>(fail());
    const uint16_t v = static_cast<uint16_t>(p[0] | p[1] << 8);
    p += 2;
    return v;
  }
  uint8_t u8() { return p < end ? *p++ : static_cast<uint8_t>(fail()); }
  // n bytes, then padding to the next 4-byte boundary of the file.
  const uint8_t* take(uint32_t n) {
    const uint8_t* r = p;
    if (static_cast<uint32_t>(end - p) < n) {
      fail();
      return begin;
    }
    p += n;
    while ((p - begin) % 4 && p < end) ++p;
    return r;
  }
  uint32_t fail() {
    ok = false;
    p = end;
    return 0;
  }
};

struct Case {
  char name[33];
  vds::RenderConfig cfg;
  uint32_t frames;
  vds::Camera cam;
  uint32_t clear;
  vds::DrawList list;
};

Case g_case;

// Parses the file in g_mem[0, len); arrays point into it.
bool parse(uint32_t len, Case& c) {
  Reader r{g_mem, g_mem, g_mem + len};
  if (r.u32() != kMagic) return false;
  std::memcpy(c.name, r.take(32), 32);
  c.name[32] = 0;
  c.cfg = vds::RenderConfig{};
  c.cfg.format = static_cast<vds::PixelFormat>(r.u8());
  c.cfg.depth = static_cast<vds::DepthFormat>(r.u8());
  c.cfg.band_height = r.u16();
  c.cfg.vertex_cache = r.u32();
  c.cfg.triangle_cache = r.u32();
  c.cfg.setup_cache = r.u32();
  c.frames = r.u32();
  c.cfg.width = r.u16();
  c.cfg.height = r.u16();
  c.cam = vds::Camera{};
  for (auto& row : c.cam.rotation.m)
    for (vds::Q2_30& v : row) v = vds::Q2_30::from_raw(static_cast<int32_t>(r.u32()));
  vds::Q16_16* const fields[] = {&c.cam.position.x, &c.cam.position.y, &c.cam.position.z, &c.cam.fx, &c.cam.fy,
                                 &c.cam.cx,         &c.cam.cy,         &c.cam.near_z,     &c.cam.far_z};
  for (vds::Q16_16* v : fields) *v = vds::Q16_16::from_raw(static_cast<int32_t>(r.u32()));
  c.clear = r.u32();
  c.list = vds::DrawList{};
  c.list.num_positions = r.u32();
  if (c.list.num_positions > 65536) return false;
  c.list.positions = reinterpret_cast<const vds::Vec3<vds::Q16_16>*>(r.take(c.list.num_positions * 12));
  const uint32_t nt = r.u32();
  if (nt > kMaxTextures) return false;
  for (uint32_t i = 0; i < nt; ++i) {
    vds::Texture& t = g_textures[i];
    t = vds::Texture{};
    t.format = static_cast<vds::TexFormat>(r.u8());
    t.address = static_cast<vds::TexAddress>(r.u8());
    t.width = r.u16();
    t.height = r.u16();
    t.apron = r.u8() != 0;
    r.u8();
    t.stride = t.width + (t.apron ? 1u : 0u);
    t.texels = r.take(r.u32());
  }
  c.list.num_meshes = r.u32();
  if (c.list.num_meshes > kMaxMeshes) return false;
  for (uint32_t i = 0; i < c.list.num_meshes; ++i) {
    vds::Mesh& m = g_meshes[i];
    m = vds::Mesh{};
    m.shading = static_cast<vds::Shading>(r.u8());
    m.filter = static_cast<vds::Filter>(r.u8());
    m.cull = static_cast<vds::Cull>(r.u8());
    r.u8();
    m.color = r.u32();
    const uint32_t ti = r.u32();
    m.texture = ti < nt ? &g_textures[ti] : nullptr;
    for (auto& row : m.view_map.m)
      for (int32_t& v : row) v = static_cast<int32_t>(r.u32());
    m.num_triangles = r.u32();
    if (m.num_triangles > 65536) return false;
    m.indices = reinterpret_cast<const uint16_t*>(r.take(m.num_triangles * 6));
  }
  const vds::TexCoord* uvs = nullptr;
  const uint32_t* colors = nullptr;
  if (r.u32()) uvs = reinterpret_cast<const vds::TexCoord*>(r.take(c.list.num_positions * 8));
  if (r.u32()) colors = reinterpret_cast<const uint32_t*>(r.take(c.list.num_positions * 4));
  for (uint32_t i = 0; i < c.list.num_meshes; ++i) {
    g_meshes[i].uvs = uvs;
    g_meshes[i].colors = colors;
  }
  c.list.meshes = g_meshes;
  return r.ok;
}

// Reads `path` into g_mem; the file's length, or -1 if it is missing, or
// kMemBytes + 1 if it does not fit.
int64_t load(const char* path) {
  uint32_t len = 0;
  for (;;) {
    if (len == kMemBytes) {
      uint8_t probe;
      return vds::board::host_file_read(path, len, &probe, 1) > 0 ? int64_t{kMemBytes} + 1 : len;
    }
    const int32_t got = vds::board::host_file_read(path, len, g_mem + len, kMemBytes - len);
    if (got < 0) return len == 0 ? -1 : int64_t{len};
    if (got == 0) return len;
    len += static_cast<uint32_t>(got);
  }
}

bool discard_band(void*, const vds::Band&) { return true; }

// Measured frames go to the sink that does nothing (a display DMA would take
// the band), so the count is the renderer's alone.
[[gnu::noinline]] vds::Status measured_frames(vds::Renderer& r, const Case& c, uint64_t* instructions) {
  vds::Status st = vds::Status::ok;
  const uint64_t t0 = vds::board::instructions();
  for (uint32_t k = 0; k < c.frames && st == vds::Status::ok; ++k) st = r.render(c.cam, c.list, c.clear, discard_band, nullptr);
  *instructions = vds::board::instructions() - t0;
  return st;
}

void skip(const char* name, const char* reason) {
  vds::board::log(Line().str("skip render case=").str(name).str(" reason=").str(reason).str("\n").c_str());
}

// Renders case file `index`; false when there is none.
bool run_case(uint32_t index, bool counting, int* status) {
  char path[32] = "render_case";
  {
    char digits[12];
    int k = 0;
    uint32_t v = index;
    do {
      digits[k++] = static_cast<char>('0' + v % 10);
      v /= 10;
    } while (v);
    size_t n = sizeof "render_case" - 1;
    while (k) path[n++] = digits[--k];
    std::memcpy(path + n, ".bin", 5);
  }
  const int64_t len = load(path);
  if (len < 0) return false;
  if (len > kMemBytes) {
    skip(path, "file-larger-than-ram");
    return true;
  }
  Case& c = g_case;
  if (!parse(static_cast<uint32_t>(len), c)) {
    vds::board::log(Line().str("error: malformed ").str(path).str("\n").c_str());
    *status = 1;
    return true;
  }
  // The workspace follows the file.
  const uint32_t used = (static_cast<uint32_t>(len) + 7u) & ~7u;
  vds::Arena arena(g_mem + used, kMemBytes - used);
  vds::Renderer renderer;
  vds::Status st = renderer.init(c.cfg, arena);
  if (st == vds::Status::workspace_too_small) {
    skip(c.name, "workspace-larger-than-ram");
    return true;
  }
  uint64_t spent = 0;
  if (st == vds::Status::ok && counting) st = measured_frames(renderer, c, &spent);
  uint32_t crc = 0;
  if (st == vds::Status::ok) st = renderer.render(c.cam, c.list, c.clear, vds::fw::crc_band, &crc);
  if (st != vds::Status::ok) {
    vds::board::log(Line().str("error: case ").str(c.name).str(" status ").str(vds::status_name(st)).str("\n").c_str());
    *status = 1;
    return true;
  }
  const vds::RenderStats& s = renderer.stats();
  vds::board::log(
      Line().str("check render case=").str(c.name).str(" pixels=").dec(s.pixels).str(" crc=").hex32(crc).str("\n").c_str());
  if (counting && c.frames) {
    const uint64_t per_frame = spent / c.frames;
    // Tenths of an instruction per pixel, rounded.
    const uint64_t tenths = s.pixels ? (spent * 10 + c.frames * uint64_t{s.pixels} / 2) / (c.frames * uint64_t{s.pixels}) : 0;
    Line l;
    l.str("m4 case=").str(c.name).str(" frames=").dec(c.frames).str(" instr_per_frame=").dec(per_frame);
    l.str(" instr_per_pixel=").dec(tenths / 10).str(".").dec(tenths % 10).str(" pixels=").dec(s.pixels);
    l.str(" spans=").dec(s.spans).str(" setups=").dec(s.setups).str(" workspace=").dec(arena.used());
    l.str(" crc=").hex32(crc).str("\n");
    vds::board::log(l.c_str());
  }
  return true;
}

}  // namespace

extern "C" int vds_app_main() {
  vds::board::init();
  const bool counting = vds::board::instruction_resolution() != 0;
  if (counting) {
    vds::board::log(Line().str("m4 counter resolution=").dec(vds::board::instruction_resolution()).str("\n").c_str());
  }
  int status = 0;
  uint32_t n = 0;
  while (run_case(n, counting, &status)) ++n;
  if (n == 0) {
    vds::board::log("error: no render_case0.bin in the working directory (bench_render cases DIR)\n");
    return 1;
  }
  return status;
}
