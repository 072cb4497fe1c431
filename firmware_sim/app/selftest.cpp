// Firmware self-test: runs client-library kernels on fixed inputs and prints
// their checksums, so the same program on the host board and on the
// Cortex-M4 board must print identical "check" lines (bit-exactness across
// architectures); on the QEMU board it also prints instruction counts.
#include <cstdint>

#include "band_crc.h"
#include "print.h"
#include "vds/arena.h"
#include "vds/board.h"
#include "vds/container.h"
#include "vds/crc32c.h"
#include "vds/homography.h"
#include "vds/idct.h"
#include "vds/render.h"

namespace {

using vds::fw::Line;

// Deterministic pseudo-random numbers (the same on every board).
uint32_t g_rng = 0x12345678u;
uint32_t next_random() {
  g_rng = g_rng * 1664525u + 1013904223u;
  return g_rng;
}

// Sparse, realistic blocks: a DC, a few low-frequency AC coefficients.
void make_block(int16_t coef[64], int density) {
  for (int i = 0; i < 64; ++i) coef[i] = 0;
  coef[0] = static_cast<int16_t>(static_cast<int32_t>(next_random() >> 21) - 1024);
  for (int k = 0; k < density; ++k) {
    const uint32_t r = next_random();
    const int pos = static_cast<int>((r >> 8) % 64);
    coef[pos] = static_cast<int16_t>(static_cast<int32_t>((r >> 20) % 401) - 200);
  }
}

constexpr int kBlocks = 256;

void check_idct() {
  int16_t coef[64];
  int16_t out[64];
  uint8_t pixels[64];
  uint32_t crc_out = 0;
  uint32_t crc_put = 0;
  uint64_t spent = 0;
  for (int b = 0; b < kBlocks; ++b) {
    make_block(coef, 1 + b % 24);
    const uint64_t t0 = vds::board::instructions();
    vds::idct8x8(coef, out);
    spent += vds::board::instructions() - t0;
    vds::idct8x8_put(coef, pixels, 8);
    crc_out = vds::crc32c_update(crc_out, out, sizeof out);
    crc_put = vds::crc32c_update(crc_put, pixels, sizeof pixels);
  }
  vds::board::log(Line().str("check idct8x8 ").hex32(crc_out).str("\n").c_str());
  vds::board::log(Line().str("check idct8x8_put ").hex32(crc_put).str("\n").c_str());
  if (vds::board::instruction_resolution() != 0)
    vds::board::log(Line().str("count idct8x8 instructions_per_block ").dec(spent / kBlocks).str("\n").c_str());
}

void check_crc() {
  uint8_t data[1024];
  for (uint32_t i = 0; i < sizeof data; ++i) data[i] = static_cast<uint8_t>(next_random() >> 24);
  const uint64_t t0 = vds::board::instructions();
  const uint32_t c = vds::crc32c(data, sizeof data);
  const uint64_t spent = vds::board::instructions() - t0;
  vds::board::log(Line().str("check crc32c ").hex32(c).str(" ").hex32(vds::crc32c("123456789", 9)).str("\n").c_str());
  if (vds::board::instruction_resolution() != 0)
    vds::board::log(Line().str("count crc32c instructions_per_byte_x100 ").dec(spent * 100 / sizeof data).str("\n").c_str());
}

// View-mapped triangles as the walkthrough draws them (a Y'CbCr 4:2:0
// view, bilinear luma, rgb565 with 16-bit depth): random triangles at random
// depths in front of the screen, each mapped from a view camera behind it,
// so that spans of every length lie inside the view, cross chroma texels
// and hide each other. On the Cortex-M4 this is the span loop written in
// Thumb-2 (render_span.cpp), on the host the C++ loop: the same CRC.
constexpr int kViewW = 64, kViewH = 48, kViewStride = 70, kChromaStride = 35;
constexpr int kViewTriangles = 60;
uint8_t g_view_y[kViewStride * kViewH];
uint8_t g_view_cb[kChromaStride * kViewH / 2];
uint8_t g_view_cr[kChromaStride * kViewH / 2];
alignas(8) uint8_t g_render_ws[40 * 1024];
vds::Vec3<vds::Q16_16> g_tri_pos[3 * kViewTriangles];
uint16_t g_tri_idx[3 * kViewTriangles];
vds::Mesh g_tri_mesh[kViewTriangles];

vds::Q16_16 q16(int32_t raw) { return vds::Q16_16::from_raw(raw); }
vds::Camera identity_camera(int32_t x, int32_t y, int32_t z, int32_t focal, int32_t w, int32_t h) {
  vds::Camera c{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) c.rotation.m[i][j] = vds::Q2_30::from_raw(i == j ? (1 << 30) - 1 : 0);
  c.position = {q16(x), q16(y), q16(z)};
  c.fx = c.fy = vds::Q16_16::from_int(focal);
  c.cx = vds::Q16_16::from_int(w / 2);
  c.cy = vds::Q16_16::from_int(h / 2);
  c.near_z = q16(1 << 14);
  c.far_z = vds::Q16_16::from_int(60);
  return c;
}


// false when the frame was not drawn or drew too little to test the loop.
bool check_view_spans() {
  for (auto& v : g_view_y) v = static_cast<uint8_t>(next_random() >> 24);
  for (auto& v : g_view_cb) v = static_cast<uint8_t>(next_random() >> 24);
  for (auto& v : g_view_cr) v = static_cast<uint8_t>(next_random() >> 24);
  vds::Texture view;
  view.format = vds::TexFormat::ycbcr420;
  view.address = vds::TexAddress::clamp;
  view.width = kViewW;
  view.height = kViewH;
  view.stride = kViewStride;
  view.texels = g_view_y;
  view.cb = g_view_cb;
  view.cr = g_view_cr;
  view.chroma_stride = kChromaStride;
  constexpr int kW = 96, kH = 72;
  const vds::Camera screen = identity_camera(0, 0, 0, 80, kW, kH);
  const vds::Camera from = identity_camera(13107, -6554, -65536, 40, kViewW, kViewH);  // (0.2, -0.1, -1)
  for (int t = 0; t < kViewTriangles; ++t) {
    // Corners at depth 2..8 within the screen's view (x, y up to 0.55 z).
    const int32_t z = 2 * 65536 + static_cast<int32_t>(next_random() % (6u * 65536u));
    for (int k = 0; k < 3; ++k) {
      const int32_t zk = z + static_cast<int32_t>(next_random() % 65536u) - 32768;
      const int32_t fx = static_cast<int32_t>(next_random() % 1101u) - 550, fy = static_cast<int32_t>(next_random() % 1101u) - 550;
      g_tri_pos[3 * t + k] = {q16(static_cast<int32_t>(int64_t{zk} * fx / 1000)), q16(static_cast<int32_t>(int64_t{zk} * fy / 1000)),
                              q16(zk)};
      g_tri_idx[3 * t + k] = static_cast<uint16_t>(3 * t + k);
    }
    vds::Mesh& m = g_tri_mesh[t];
    m = vds::Mesh{};
    m.indices = &g_tri_idx[3 * t];
    m.num_triangles = 1;
    m.shading = vds::Shading::view_mapped;
    m.filter = vds::Filter::bilinear_luma;
    m.cull = vds::Cull::none;
    m.texture = &view;
    if (vds::plane_homography(screen, from, &g_tri_pos[3 * t], &m.view_map) != vds::Status::ok) m.num_triangles = 0;
  }
  const vds::DrawList list{g_tri_pos, 3 * kViewTriangles, g_tri_mesh, kViewTriangles};
  vds::RenderConfig cfg;
  cfg.width = kW;
  cfg.height = kH;
  cfg.band_height = 16;
  cfg.format = vds::PixelFormat::rgb565;
  cfg.depth = vds::DepthFormat::d16;
  vds::Arena arena(g_render_ws, sizeof g_render_ws);
  vds::Renderer renderer;
  uint32_t crc = 0;
  vds::Status st = renderer.init(cfg, arena);
  const uint64_t t0 = vds::board::instructions();
  if (st == vds::Status::ok) st = renderer.render(screen, list, 0, vds::fw::crc_band, &crc);
  const uint64_t spent = vds::board::instructions() - t0;
  const vds::RenderStats& s = renderer.stats();
  vds::board::log(Line().str("check view_spans status=").str(vds::status_name(st)).str(" pixels=").dec(s.pixels)
                      .str(" crc=").hex32(crc).str("\n").c_str());
  if (vds::board::instruction_resolution() != 0 && s.pixels)
    vds::board::log(Line().str("count view_spans instructions_per_pixel ").dec(spent / s.pixels).str("\n").c_str());
  // About 33,700 pixels drawn (the triangles overlap about five deep).
  if (st != vds::Status::ok || s.pixels < 20000) {
    vds::board::log("error: view_spans drew too little to test the span loop\n");
    return false;
  }
  return true;
}

// A loop of known length checks the instruction counter itself: on the
// Cortex-M4 board each iteration is exactly two instructions (subs, bne).
void check_counter() {
  if (vds::board::instruction_resolution() == 0) return;
#if defined(__arm__)
  constexpr uint32_t kIterations = 100000;
  uint32_t n = kIterations;
  const uint64_t t0 = vds::board::instructions();
  asm volatile(
      "1: subs %0, %0, #1\n"
      "bne 1b\n"
      : "+r"(n)::"cc");
  const uint64_t spent = vds::board::instructions() - t0;
  vds::board::log(Line().str("count calibration_loop measured ").dec(spent).str(" expected ").dec(2ull * kIterations)
                      .str(" resolution ").dec(vds::board::instruction_resolution()).str("\n").c_str());
#endif
}

}  // namespace

// The firmware's entry point, called by each board's start-up code.
extern "C" int vds_app_main() {
  vds::board::init();
  vds::board::log("vds selftest\n");
  check_counter();
  check_crc();
  check_idct();
  const bool spans_ok = check_view_spans();
  vds::board::log(Line().str("info stack_high_water_bytes ").dec(vds::board::stack_high_water()).str("\n").c_str());
  return spans_ok ? 0 : 1;
}
