// Benchmark driver for the client renderer (vds/render.h) against the host
// reference renderer (vds/ref/render.h). bench/run_render.sh runs it and
// writes bench/results/render.md.
//
//   bench_render accuracy OUTDIR     PSNR of every shared scene, texture format,
//                                    depth and output format; side-by-side PNGs
//                                    (reference | client | |difference| x 16) in OUTDIR
//   bench_render quad FILTER TEX OUT DEPTH N
//                                    N frames of a textured plane filling the
//                                    240x180 screen (for callgrind); FILTER
//                                    nearest|bilinear, TEX rgb565|xrgb8888|ycbcr420,
//                                    OUT rgb565|rgb888, DEPTH d16|d32
//   bench_render empty OUT DEPTH N   N frames with nothing drawn (band clears only)
//   bench_render scene NAME TEX OUT DEPTH BAND CACHE N
//                                    N frames of a shared scene (cube, terrain,
//                                    room, cube-from-view)
//   bench_render frames FILE N       N frames of a dumped case (the file the
//                                    Cortex-M4 run reads), for callgrind
//   bench_render ram                 workspace bytes of typical configurations
//   bench_render dump LABEL SCENE TEX OUT DEPTH BAND CACHE FRAMES FILTER FILE
//                                    a scene (or quad, or empty) with render settings
//                                    as a flat binary for the board run
//                                    (firmware_sim/app/bench_render.cpp); FILTER applies
//                                    to quad; CACHE > 0 also turns on a 16-entry setup cache
//   bench_render cases DIR FRAMES    the benchmark's standard cases as
//                                    DIR/render_case<i>.bin (FRAMES measured frames each),
//                                    one line per case on stdout: i label scene tex out
//                                    depth band cache filter
// Frame commands print the pixels rasterised and a CRC-32C of the last frame.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "vds/crc32c.h"
#include "vds/enc/image_io.h"
#include "vds/ref/render.h"
#include "vds/ref/scene.h"
#include "vds/render.h"

using namespace vds;
using namespace vds::enc;
using namespace vds::ref;

namespace {

// Set-up cache entries of the measured cases that use caches.
constexpr uint32_t kBenchSetupCache = 16;

[[noreturn]] void usage() {
  std::fprintf(stderr, "usage: see the header of bench/src/render.cpp\n");
  std::exit(2);
}

TexFormat tex_format(const std::string& s) {
  if (s == "rgb565") return TexFormat::rgb565;
  if (s == "xrgb8888") return TexFormat::xrgb8888;
  if (s == "ycbcr420") return TexFormat::ycbcr420;
  usage();
}
PixelFormat out_format(const std::string& s) {
  if (s == "rgb565") return PixelFormat::rgb565;
  if (s == "rgb888") return PixelFormat::rgb888;
  usage();
}
DepthFormat depth_format(const std::string& s) {
  if (s == "d16") return DepthFormat::d16;
  if (s == "d32") return DepthFormat::d32;
  usage();
}
const char* name(TexFormat f) { return f == TexFormat::rgb565 ? "rgb565" : f == TexFormat::xrgb8888 ? "xrgb8888" : "ycbcr420"; }
const char* name(DepthFormat d) { return d == DepthFormat::d16 ? "16-bit" : "32-bit"; }

// A textured plane tilted away from the camera that covers the whole
// screen: every pixel is drawn once, perspective-correct, z-tested.
Scene make_quad_scene(Filter filter, int width = 240) {
  Scene s;
  s.name = "quad";
  s.width = width;
  s.textures.push_back({});
  s.textures[0].name = "bricks";
  s.textures[0].image = make_brick_texture(256);
  MeshD m;
  m.shading = Shading::texture;
  m.texture = 0;
  m.filter = filter;
  const Vec3d p[4] = {{-40, 0, -1}, {40, 0, -1}, {40, 0, 80}, {-40, 0, 80}};
  Vec2d uv[4];
  for (int k = 0; k < 4; ++k) uv[k] = {p[k].x * 48, p[k].z * 48};
  s.add_quad(m, p, uv, {0, 1, 0});
  s.meshes.push_back(m);
  s.camera = CameraD::look_at({0, 2.2, -1}, {0, -1.2, 6}, {0, 1, 0}, width, 180, 50, 0.1, 100);
  return s;
}

Scene scene_by_name(const std::string& n, Filter quad_filter = Filter::bilinear) {
  if (n == "cube") return make_cube_scene();
  if (n == "terrain") return make_terrain_scene();
  if (n == "room") return make_room_scene();
  if (n == "quad") return make_quad_scene(quad_filter);
  // Twice as wide at the same height: the difference to "quad" isolates the
  // per-pixel cost from per-row and per-frame costs.
  if (n == "quad480") return make_quad_scene(quad_filter, 480);
  if (n == "golden") return make_golden_scene();
  if (n == "cube-from-view") {
    const Scene base = make_cube_scene();
    // The view: the cube scene from a camera 0.6 units to the left.
    const CameraD view_cam = CameraD::look_at({2.8, 2.9, -4.8}, {0.2, 0.9, 0.3}, {0, 1, 0}, 240, 180, 55, 0.1, 60);
    const RefFrame view = ref_render(base, view_cam, 240, 180);
    std::vector<int> faces;
    for (int i = 0; i < static_cast<int>(base.meshes.size()); ++i) faces.push_back(i);
    return make_view_mapped_scene(base, faces, view.image, view_cam);
  }
  usage();
}

Image diff_image(const Image& a, const Image& b) {
  Image d(a.width, a.height, 3);
  for (size_t i = 0; i < d.pixels.size(); ++i) {
    const int v = std::abs(int(a.pixels[i]) - int(b.pixels[i])) * 16;
    d.pixels[i] = static_cast<uint8_t>(v > 255 ? 255 : v);
  }
  return d;
}

Image upscale(const Image& a, int k) {
  Image r(a.width * k, a.height * k, a.channels);
  for (int y = 0; y < r.height; ++y)
    for (int x = 0; x < r.width; ++x)
      for (int c = 0; c < a.channels; ++c) r.at(x, y, c) = a.at(x / k, y / k, c);
  return r;
}

// The reference frame with every channel rounded to 5/6/5 bits and widened
// back: what an exact renderer with rgb565 output would show.
Image quantise565(const Image& a) {
  Image r = a;
  for (size_t i = 0; i < r.pixels.size(); ++i) {
    const uint32_t v = r.pixels[i];
    const bool g = (i % 3) == 1;
    const uint32_t q = g ? (v * 253 + 505) >> 10 : (v * 249 + 1014) >> 11;
    r.pixels[i] = static_cast<uint8_t>(g ? (q << 2 | q >> 4) : (q << 3 | q >> 2));
  }
  return r;
}

int cmd_accuracy(const std::string& outdir) {
  std::vector<Scene> scenes = shared_scenes();
  scenes.push_back(scene_by_name("cube-from-view"));
  std::printf("| scene | texture format | depth | output | PSNR (dB) | max abs error | pixels differing |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (const Scene& base : scenes) {
    for (TexFormat tf : {TexFormat::xrgb8888, TexFormat::rgb565, TexFormat::ycbcr420}) {
      const Scene sc = client_textures(base, tf);
      const RefFrame ref = ref_render(sc);
      const ClientScene cs(sc, tf);
      for (DepthFormat df : {DepthFormat::d32, DepthFormat::d16}) {
        for (PixelFormat of : {PixelFormat::rgb888, PixelFormat::rgb565}) {
          if (of == PixelFormat::rgb565 && df == DepthFormat::d16) continue;
          ClientRenderSettings st;
          st.format = of;
          st.depth = df;
          const ClientFrame fr = render_client(cs, sc.width, sc.height, st);
          if (fr.status != Status::ok) {
            std::fprintf(stderr, "render failed: %s\n", status_name(fr.status));
            return 1;
          }
          const Image want = of == PixelFormat::rgb565 ? quantise565(ref.image) : ref.image;
          int maxd = 0;
          size_t ndiff = 0;
          for (size_t i = 0; i < want.pixels.size(); i += 3) {
            int d = 0;
            for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(int(want.pixels[i + c]) - int(fr.image.pixels[i + c])));
            maxd = std::max(maxd, d);
            ndiff += d != 0;
          }
          std::printf("| %s | %s | %s | %s | %.2f | %d | %.2f %% |\n", sc.name.c_str(), name(tf), name(df),
                      of == PixelFormat::rgb565 ? "rgb565 (vs reference rounded to 565)" : "rgb888",
                      psnr(want, fr.image), maxd, 100.0 * ndiff / (want.pixels.size() / 3));
          if (tf == TexFormat::xrgb8888 && df == DepthFormat::d32 && of == PixelFormat::rgb888 && !outdir.empty()) {
            const Image d = diff_image(ref.image, fr.image);
            save_png(outdir + "/render_" + sc.name + ".png", upscale(side_by_side({&ref.image, &fr.image, &d}), 2));
          }
        }
      }
    }
  }
  return 0;
}

// The frames callgrind counts (--toggle-collect on these functions).
__attribute__((noinline)) Status measured_render_raw(Renderer& r, const Camera& cam, const DrawList& list, uint32_t clear,
                                                     BandSink sink, void* ctx) {
  return r.render(cam, list, clear, sink, ctx);
}
__attribute__((noinline)) Status measured_render(Renderer& r, const ClientScene& cs, BandSink sink, void* ctx) {
  return r.render(cs.camera(), cs.list(), cs.clear_color(), sink, ctx);
}

// Runs N frames; prints pixels rasterised per frame and the last frame's CRC.
int run_frames(const ClientScene& cs, int w, int h, const ClientRenderSettings& st, int n) {
  RenderConfig cfg;
  cfg.width = static_cast<uint16_t>(w);
  cfg.height = static_cast<uint16_t>(h);
  cfg.band_height = static_cast<uint16_t>(std::min(st.band_height, h));
  cfg.format = st.format;
  cfg.depth = st.depth;
  cfg.vertex_cache = st.vertex_cache;
  cfg.triangle_cache = st.triangle_cache;
  std::vector<uint8_t> ws(render_workspace_size(cfg));
  Arena arena(ws.data(), ws.size());
  Renderer r;
  if (r.init(cfg, arena) != Status::ok) return 1;
  // Measured frames go to a sink that does nothing (a display DMA would take
  // the band); one more frame is copied out for the checksum.
  struct Ctx {
    std::vector<uint8_t> frame;
    size_t row;
  } ctx{std::vector<uint8_t>(static_cast<size_t>(w) * h * bytes_per_pixel(st.format)), static_cast<size_t>(w) * bytes_per_pixel(st.format)};
  auto discard = [](void*, const Band&) { return true; };
  auto copy = [](void* p, const Band& b) {
    auto* c = static_cast<Ctx*>(p);
    for (int y = 0; y < b.height; ++y) std::memcpy(c->frame.data() + (static_cast<size_t>(b.y) + y) * c->row, b.pixels + static_cast<size_t>(y) * b.stride, c->row);
    return true;
  };
  for (int i = 0; i <= n; ++i) {
    const Status s = i < n ? measured_render(r, cs, discard, nullptr) : r.render(cs.camera(), cs.list(), cs.clear_color(), copy, &ctx);
    if (s != Status::ok) {
      std::fprintf(stderr, "render: %s\n", status_name(s));
      return 1;
    }
  }
  const uint32_t crc = crc32c(ctx.frame.data(), ctx.frame.size());
  const RenderStats& s = r.stats();
  std::printf("pixels=%u spans=%u setups=%u clipped=%u triangles=%u reprojected=%u workspace=%zu crc=%08x\n", s.pixels,
              s.spans, s.setups, s.clipped, s.triangles, s.reprojected, arena.used(), crc);
  return 0;
}

int cmd_ram() {
  std::printf("| size | band rows | output | depth | vertex cache | triangle cache | setup cache | colour buffer | workspace bytes |\n"
              "|---|---|---|---|---|---|---|---|---|\n");
  struct C {
    int w, h, band;
    PixelFormat f;
    DepthFormat d;
    uint32_t vcache, tcache, scache;
    bool target;
  };
  const C cs[] = {
      {240, 180, 16, PixelFormat::rgb565, DepthFormat::d16, 0, 0, 0, false},
      {240, 180, 16, PixelFormat::rgb565, DepthFormat::d16, 0, 0, 2, false},
      {240, 180, 16, PixelFormat::rgb565, DepthFormat::d16, 0, 0, 0, true},
      {240, 180, 16, PixelFormat::rgb565, DepthFormat::d16, 0, 0, 16, true},
      {240, 180, 16, PixelFormat::rgb565, DepthFormat::d16, 1089, 2048, 16, false},
      {240, 180, 16, PixelFormat::rgb565, DepthFormat::d32, 0, 0, 0, false},
      {240, 180, 8, PixelFormat::rgb565, DepthFormat::d32, 0, 0, 0, false},
      {240, 180, 180, PixelFormat::rgb565, DepthFormat::d16, 0, 0, 0, false},
      {240, 180, 16, PixelFormat::rgb888, DepthFormat::d16, 0, 0, 0, false},
      {320, 240, 16, PixelFormat::rgb565, DepthFormat::d16, 0, 0, 0, false},
  };
  static uint8_t frame[320 * 240 * 3];
  for (const C& c : cs) {
    RenderConfig cfg;
    cfg.width = static_cast<uint16_t>(c.w);
    cfg.height = static_cast<uint16_t>(c.h);
    cfg.band_height = static_cast<uint16_t>(c.band);
    cfg.format = c.f;
    cfg.depth = c.d;
    cfg.vertex_cache = c.vcache;
    cfg.triangle_cache = c.tcache;
    cfg.setup_cache = c.scache;
    if (c.target) {
      cfg.target = frame;
      cfg.target_stride = static_cast<uint32_t>(c.w * bytes_per_pixel(c.f));
    }
    std::printf("| %dx%d | %d | %s | %s | %u | %u | %u | %s | %zu |\n", c.w, c.h, c.band,
                c.f == PixelFormat::rgb565 ? "rgb565" : "rgb888", name(c.d), c.vcache, c.tcache, c.scache,
                c.target ? "caller's frame" : "in workspace", render_workspace_size(cfg));
  }
  std::printf("sizeof(Renderer)=%zu\n", sizeof(Renderer));
  return 0;
}

// Flat little-endian dump of a client scene and render settings for
// firmware_sim/app/bench_render.cpp (rgb565 and xrgb8888 textures only):
//   u32 magic 'VRS3', char name[32], u8 output, u8 depth, u16 band rows,
//   u32 vertex cache, u32 triangle cache, u32 setup cache, u32 frames, u16 width, u16 height,
//   camera (18 x i32: rotation 9, position 3, fx fy cx cy near far), u32 clear colour,
//   u32 num_positions, positions (3 x i32 each),
//   u32 num_textures, per texture: u8 format, u8 address, u16 w, u16 h, u8 apron, u8 pad,
//     u32 texel bytes, texels,
//   u32 num_meshes, per mesh: u8 shading, filter, cull, pad; u32 colour; i32 texture;
//     9 x i32 view map; u32 triangles; u16 indices (3 per triangle),
//   u32 has_uvs, uvs (2 x i32 per position), u32 has_colours, colours (u32 per position).
// Every array starts on a 4-byte boundary. The vertex and triangle caches
// are cut to the scene's counts (the same picture; less RAM on the board).
int cmd_dump(const std::string& label, const Scene& sc, TexFormat tf, const ClientRenderSettings& st, int frames,
             const std::string& file) {
  if (tf == TexFormat::ycbcr420) usage();
  const Scene q = client_textures(sc, tf);
  const ClientScene cs(q, tf);
  std::vector<uint8_t> out;
  auto u32 = [&](uint32_t v) {
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
  };
  auto u16 = [&](uint32_t v) {
    out.push_back(static_cast<uint8_t>(v));
    out.push_back(static_cast<uint8_t>(v >> 8));
  };
  auto bytes = [&](const void* p, size_t n) {
    out.insert(out.end(), static_cast<const uint8_t*>(p), static_cast<const uint8_t*>(p) + n);
    while (out.size() % 4) out.push_back(0);
  };
  uint32_t num_tris = 0;
  for (uint32_t i = 0; i < cs.list().num_meshes; ++i) num_tris += cs.list().meshes[i].num_triangles;
  u32(0x33535256);
  char name32[32] = {};
  std::strncpy(name32, label.c_str(), 31);
  bytes(name32, 32);
  out.push_back(static_cast<uint8_t>(st.format));
  out.push_back(static_cast<uint8_t>(st.depth));
  u16(static_cast<uint32_t>(st.band_height));
  u32(std::min(st.vertex_cache, cs.list().num_positions));
  u32(std::min(st.triangle_cache, num_tris));
  u32(st.setup_cache);
  u32(static_cast<uint32_t>(frames));
  u16(static_cast<uint32_t>(sc.width));
  u16(static_cast<uint32_t>(sc.height));
  const Camera& c = cs.camera();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) u32(static_cast<uint32_t>(c.rotation.m[i][j].raw()));
  for (Q16_16 v : {c.position.x, c.position.y, c.position.z, c.fx, c.fy, c.cx, c.cy, c.near_z, c.far_z}) u32(static_cast<uint32_t>(v.raw()));
  u32(cs.clear_color());
  const DrawList& l = cs.list();
  u32(l.num_positions);
  bytes(l.positions, l.num_positions * sizeof(Vec3<Q16_16>));
  std::vector<const Texture*> texs;
  for (uint32_t i = 0; i < l.num_meshes; ++i) {
    const Texture* t = l.meshes[i].texture;
    if (t && std::find(texs.begin(), texs.end(), t) == texs.end()) texs.push_back(t);
  }
  u32(static_cast<uint32_t>(texs.size()));
  for (const Texture* t : texs) {
    out.push_back(static_cast<uint8_t>(t->format));
    out.push_back(static_cast<uint8_t>(t->address));
    u16(t->width);
    u16(t->height);
    out.push_back(t->apron ? 1 : 0);
    out.push_back(0);
    const size_t n = size_t{t->stride} * (t->height + (t->apron ? 1u : 0u)) * (t->format == TexFormat::rgb565 ? 2 : 4);
    u32(static_cast<uint32_t>(n));
    bytes(t->texels, n);
  }
  u32(l.num_meshes);
  for (uint32_t i = 0; i < l.num_meshes; ++i) {
    const Mesh& m = l.meshes[i];
    out.push_back(static_cast<uint8_t>(m.shading));
    out.push_back(static_cast<uint8_t>(m.filter));
    out.push_back(static_cast<uint8_t>(m.cull));
    out.push_back(0);
    u32(m.color);
    int32_t ti = -1;
    for (size_t k = 0; k < texs.size(); ++k)
      if (texs[k] == m.texture) ti = static_cast<int32_t>(k);
    u32(static_cast<uint32_t>(ti));
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) u32(static_cast<uint32_t>(m.view_map.m[a][b]));
    u32(m.num_triangles);
    bytes(m.indices, m.num_triangles * 3 * sizeof(uint16_t));
  }
  const Mesh* any = l.num_meshes ? &l.meshes[0] : nullptr;
  u32(any && any->uvs ? 1 : 0);
  if (any && any->uvs) bytes(any->uvs, l.num_positions * sizeof(TexCoord));
  u32(any && any->colors ? 1 : 0);
  if (any && any->colors) bytes(any->colors, l.num_positions * sizeof(uint32_t));
  FILE* f = std::fopen(file.c_str(), "wb");
  if (!f || std::fwrite(out.data(), 1, out.size(), f) != out.size()) return 1;
  std::fclose(f);
  return 0;
}

// A dumped case read back (the layout of cmd_dump).
struct LoadedCase {
  std::string label;
  RenderConfig cfg;
  uint32_t frames = 0;
  Camera cam{};
  uint32_t clear = 0;
  std::vector<uint8_t> file;
  std::vector<Texture> textures;
  std::vector<Mesh> meshes;
  DrawList list;
};

bool load_case(const std::string& path, LoadedCase& c) {
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  std::fseek(f, 0, SEEK_END);
  c.file.resize(static_cast<size_t>(std::ftell(f)));
  std::fseek(f, 0, SEEK_SET);
  const bool read_ok = std::fread(c.file.data(), 1, c.file.size(), f) == c.file.size();
  std::fclose(f);
  if (!read_ok) return false;
  size_t pos = 0;
  bool ok = true;
  auto need = [&](size_t n) {
    if (c.file.size() - pos < n) ok = false;
    return ok;
  };
  auto u32 = [&]() -> uint32_t {
    if (!need(4)) return 0;
    uint32_t v;
    std::memcpy(&v, c.file.data() + pos, 4);
    pos += 4;
    return v;
  };
  auto u16 = [&]() -> uint16_t {
    if (!need(2)) return 0;
    uint16_t v;
    std::memcpy(&v, c.file.data() + pos, 2);
    pos += 2;
    return v;
  };
  auto u8 = [&]() -> uint8_t { return need(1) ? c.file[pos++] : 0; };
  auto take = [&](size_t n) -> const uint8_t* {
    if (!need(n)) return c.file.data();
    const uint8_t* p = c.file.data() + pos;
    pos += n;
    while (pos % 4 && pos < c.file.size()) ++pos;
    return p;
  };
  if (u32() != 0x33535256) return false;
  c.label.assign(reinterpret_cast<const char*>(take(32)), 32);
  c.label = c.label.c_str();
  c.cfg.format = static_cast<PixelFormat>(u8());
  c.cfg.depth = static_cast<DepthFormat>(u8());
  c.cfg.band_height = u16();
  c.cfg.vertex_cache = u32();
  c.cfg.triangle_cache = u32();
  c.cfg.setup_cache = u32();
  c.frames = u32();
  c.cfg.width = u16();
  c.cfg.height = u16();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) c.cam.rotation.m[i][j] = Q2_30::from_raw(static_cast<int32_t>(u32()));
  for (Q16_16* v : {&c.cam.position.x, &c.cam.position.y, &c.cam.position.z, &c.cam.fx, &c.cam.fy, &c.cam.cx, &c.cam.cy,
                    &c.cam.near_z, &c.cam.far_z}) {
    *v = Q16_16::from_raw(static_cast<int32_t>(u32()));
  }
  c.clear = u32();
  c.list.num_positions = u32();
  c.list.positions = reinterpret_cast<const Vec3<Q16_16>*>(take(c.list.num_positions * 12));
  c.textures.resize(u32());
  for (Texture& t : c.textures) {
    t.format = static_cast<TexFormat>(u8());
    t.address = static_cast<TexAddress>(u8());
    t.width = u16();
    t.height = u16();
    t.apron = u8() != 0;
    u8();
    t.stride = t.width + (t.apron ? 1u : 0u);
    const uint32_t n = u32();
    t.texels = take(n);
  }
  c.meshes.resize(u32());
  for (Mesh& m : c.meshes) {
    m.shading = static_cast<Shading>(u8());
    m.filter = static_cast<Filter>(u8());
    m.cull = static_cast<Cull>(u8());
    u8();
    m.color = u32();
    const int32_t ti = static_cast<int32_t>(u32());
    m.texture = ti >= 0 && ti < static_cast<int32_t>(c.textures.size()) ? &c.textures[static_cast<size_t>(ti)] : nullptr;
    for (auto& row : m.view_map.m)
      for (int32_t& v : row) v = static_cast<int32_t>(u32());
    m.num_triangles = u32();
    m.indices = reinterpret_cast<const uint16_t*>(take(m.num_triangles * 6));
  }
  const TexCoord* uvs = u32() ? reinterpret_cast<const TexCoord*>(take(c.list.num_positions * 8)) : nullptr;
  const uint32_t* colors = u32() ? reinterpret_cast<const uint32_t*>(take(c.list.num_positions * 4)) : nullptr;
  for (Mesh& m : c.meshes) {
    m.uvs = uvs;
    m.colors = colors;
  }
  c.list.meshes = c.meshes.data();
  c.list.num_meshes = static_cast<uint32_t>(c.meshes.size());
  return ok;
}

// N measured frames of a case, then one copied out for the checksum (as the
// Cortex-M4 run does).
int cmd_frames(const std::string& path, int n) {
  LoadedCase c;
  if (!load_case(path, c)) {
    std::fprintf(stderr, "cannot read %s\n", path.c_str());
    return 1;
  }
  std::vector<uint8_t> ws(render_workspace_size(c.cfg));
  Arena arena(ws.data(), ws.size());
  Renderer r;
  if (r.init(c.cfg, arena) != Status::ok) return 1;
  const size_t row = static_cast<size_t>(c.cfg.width) * bytes_per_pixel(c.cfg.format);
  struct Ctx {
    std::vector<uint8_t> frame;
    size_t row;
  } ctx{std::vector<uint8_t>(row * c.cfg.height), row};
  auto discard = [](void*, const Band&) { return true; };
  auto copy = [](void* p, const Band& b) {
    auto* x = static_cast<Ctx*>(p);
    for (int y = 0; y < b.height; ++y) std::memcpy(x->frame.data() + (static_cast<size_t>(b.y) + y) * x->row, b.pixels + static_cast<size_t>(y) * b.stride, x->row);
    return true;
  };
  Status st = Status::ok;
  for (int i = 0; i < n && st == Status::ok; ++i) st = measured_render_raw(r, c.cam, c.list, c.clear, discard, nullptr);
  if (st == Status::ok) st = r.render(c.cam, c.list, c.clear, copy, &ctx);
  if (st != Status::ok) {
    std::fprintf(stderr, "render: %s\n", status_name(st));
    return 1;
  }
  const RenderStats& s = r.stats();
  std::printf("pixels=%u spans=%u setups=%u clipped=%u triangles=%u workspace=%zu crc=%08x\n", s.pixels, s.spans, s.setups,
              s.clipped, s.triangles, arena.used(), crc32c(ctx.frame.data(), ctx.frame.size()));
  return 0;
}

// The benchmark's cases: label scene texture output depth band cache filter.
// quad / quad480: a textured plane filling 240x180 (480x180) pixels, every
// pixel drawn once, perspective-correct, z-tested; their difference is the
// per-pixel cost. empty: band clearing only. The cases with one 180-row band
// and the xrgb8888 quad do not fit in the Cortex-M4 board's RAM (the board
// skips them).
struct BenchCase {
  const char *label, *scene, *tex, *out, *depth;
  int band;
  uint32_t cache;
  const char* filter;
};
const BenchCase kCases[] = {
    {"quad-nearest-d32-b16", "quad", "rgb565", "rgb565", "d32", 16, 4096, "nearest"},
    {"quad480-nearest-d32-b16", "quad480", "rgb565", "rgb565", "d32", 16, 4096, "nearest"},
    {"quad-nearest-d16-b16", "quad", "rgb565", "rgb565", "d16", 16, 4096, "nearest"},
    {"quad-bilinear-d32-b16", "quad", "rgb565", "rgb565", "d32", 16, 4096, "bilinear"},
    {"quad480-bilinear-d32-b16", "quad480", "rgb565", "rgb565", "d32", 16, 4096, "bilinear"},
    {"quad-bilinear-d16-b16", "quad", "rgb565", "rgb565", "d16", 16, 4096, "bilinear"},
    {"quad-bilinear-d16-b8", "quad", "rgb565", "rgb565", "d16", 8, 4096, "bilinear"},
    {"quad-bilinear-d32-b180", "quad", "rgb565", "rgb565", "d32", 180, 4096, "bilinear"},
    {"quad-bilinear888-d32-b16", "quad", "xrgb8888", "rgb888", "d32", 16, 4096, "bilinear"},
    {"empty-d32-b16", "empty", "rgb565", "rgb565", "d32", 16, 4096, "nearest"},
    {"empty-d16-b16", "empty", "rgb565", "rgb565", "d16", 16, 4096, "nearest"},
    {"cube-d16-b16", "cube", "rgb565", "rgb565", "d16", 16, 4096, "bilinear"},
    {"terrain-d16-b16", "terrain", "rgb565", "rgb565", "d16", 16, 4096, "bilinear"},
    {"room-d16-b16", "room", "rgb565", "rgb565", "d16", 16, 4096, "bilinear"},
    {"room-d16-b16-nocache", "room", "rgb565", "rgb565", "d16", 16, 0, "bilinear"},
    {"cube-from-view-d16-b16", "cube-from-view", "rgb565", "rgb565", "d16", 16, 4096, "bilinear"},
    {"golden-d16-b16", "golden", "rgb565", "rgb565", "d16", 16, 4096, "bilinear"},
    {"golden888-d32-b16", "golden", "xrgb8888", "rgb888", "d32", 16, 4096, "bilinear"},
};

int cmd_cases(const std::string& dir, int frames) {
  int i = 0;
  for (const BenchCase& c : kCases) {
    const std::string n = c.scene;
    const Filter f = std::string(c.filter) == "nearest" ? Filter::nearest : Filter::bilinear;
    ClientRenderSettings st;
    st.format = out_format(c.out);
    st.depth = depth_format(c.depth);
    st.band_height = c.band;
    st.vertex_cache = c.cache;
    st.triangle_cache = c.cache;
    st.setup_cache = c.cache ? kBenchSetupCache : 0;
    Scene sc = n == "empty" ? make_quad_scene(f) : scene_by_name(n, f);
    if (n == "empty") sc.meshes.clear();
    const std::string file = dir + "/render_case" + std::to_string(i) + ".bin";
    if (cmd_dump(c.label, sc, tex_format(c.tex), st, frames, file) != 0) {
      std::fprintf(stderr, "cannot write %s\n", file.c_str());
      return 1;
    }
    std::printf("%d %s %s %s %s %s %d %u %s\n", i, c.label, c.scene, c.tex, c.out, c.depth, c.band, c.cache, c.filter);
    ++i;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) usage();
  const std::string cmd = argv[1];
  if (cmd == "accuracy" && argc == 3) return cmd_accuracy(argv[2]);
  if (cmd == "ram") return cmd_ram();
  if (cmd == "frames" && argc == 4) return cmd_frames(argv[2], std::atoi(argv[3]));
  if (cmd == "quad" && argc == 7) {
    const Filter f = std::string(argv[2]) == "nearest" ? Filter::nearest : Filter::bilinear;
    const TexFormat tf = tex_format(argv[3]);
    const Scene sc = client_textures(make_quad_scene(f), tf);
    const ClientScene cs(sc, tf);
    ClientRenderSettings st;
    st.format = out_format(argv[4]);
    st.depth = depth_format(argv[5]);
    return run_frames(cs, 240, 180, st, std::atoi(argv[6]));
  }
  if (cmd == "empty" && argc == 5) {
    Scene sc = make_quad_scene(Filter::nearest);
    sc.meshes.clear();
    const ClientScene cs(sc, TexFormat::rgb565);
    ClientRenderSettings st;
    st.format = out_format(argv[2]);
    st.depth = depth_format(argv[3]);
    return run_frames(cs, 240, 180, st, std::atoi(argv[4]));
  }
  if (cmd == "scene" && argc == 9) {
    const TexFormat tf = tex_format(argv[3]);
    const Scene sc = client_textures(scene_by_name(argv[2]), tf);
    const ClientScene cs(sc, tf);
    ClientRenderSettings st;
    st.format = out_format(argv[4]);
    st.depth = depth_format(argv[5]);
    st.band_height = std::atoi(argv[6]);
    st.vertex_cache = static_cast<uint32_t>(std::atoi(argv[7]));
    return run_frames(cs, sc.width, sc.height, st, std::atoi(argv[8]));
  }
  if (cmd == "dump" && argc == 12) {
    // dump LABEL SCENE TEX OUT DEPTH BAND CACHE FRAMES FILTER FILE
    const std::string n = argv[3];
    const Filter f = std::string(argv[10]) == "nearest" ? Filter::nearest : Filter::bilinear;
    ClientRenderSettings st;
    st.format = out_format(argv[5]);
    st.depth = depth_format(argv[6]);
    st.band_height = std::atoi(argv[7]);
    st.vertex_cache = static_cast<uint32_t>(std::atoi(argv[8]));
    st.triangle_cache = st.vertex_cache;  // the same number of entries
    st.setup_cache = st.vertex_cache ? kBenchSetupCache : 0;
    Scene sc = n == "empty" ? make_quad_scene(f) : scene_by_name(n, f);
    if (n == "empty") sc.meshes.clear();
    return cmd_dump(argv[2], sc, tex_format(argv[4]), st, std::atoi(argv[9]), argv[11]);
  }
  if (cmd == "cases" && argc == 4) return cmd_cases(argv[2], std::atoi(argv[3]));
  usage();
}
