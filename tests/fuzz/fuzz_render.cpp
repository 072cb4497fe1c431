// libFuzzer harness for the client renderer (vds/render.h): a scene of raw,
// hostile values (positions, camera, texture coordinates, homographies,
// indices, formats) is rendered into a caller frame with guard bytes around
// it, once in 1-row bands and once in one band, and optionally with its
// positions given on a grid (DrawList::grid) against the same positions in
// Q16.16. Traps if a guard byte changes, if two frames that must agree
// differ, or on any sanitizer report.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "vds/render.h"

namespace {

struct Bytes {
  const uint8_t* p;
  size_t n;
  uint32_t u32() {
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(u8()) << (8 * i);
    return v;
  }
  uint8_t u8() {
    if (!n) return 0;
    --n;
    return *p++;
  }
  int32_t i32() { return static_cast<int32_t>(u32()); }
};

constexpr uint8_t kGuard = 0x5A;
constexpr int kGuardBytes = 64;

// Renders into a fresh guarded frame; returns the frame (guards checked).
std::vector<uint8_t> render(const vds::RenderConfig& base, uint16_t band, const vds::Camera& cam, const vds::DrawList& list,
                            vds::Status* status) {
  vds::RenderConfig cfg = base;
  cfg.band_height = band;
  const uint32_t stride = cfg.target_stride;
  std::vector<uint8_t> mem(static_cast<size_t>(stride) * cfg.height + 2 * kGuardBytes, kGuard);
  cfg.target = mem.data() + kGuardBytes;
  std::vector<uint8_t> ws(vds::render_workspace_size(cfg));
  vds::Arena arena(ws.data(), ws.size());
  vds::Renderer r;
  if (r.init(cfg, arena) != vds::Status::ok) __builtin_trap();
  *status = r.render(cam, list, 0x102030, nullptr, nullptr);
  for (int i = 0; i < kGuardBytes; ++i) {
    if (mem[static_cast<size_t>(i)] != kGuard || mem[mem.size() - 1 - static_cast<size_t>(i)] != kGuard) __builtin_trap();
  }
  // Bytes between rows (stride padding) stay untouched too.
  const uint32_t row = cfg.width * static_cast<uint32_t>(vds::bytes_per_pixel(cfg.format));
  for (uint32_t y = 0; y < cfg.height; ++y)
    for (uint32_t k = row; k < stride; ++k)
      if (mem[kGuardBytes + static_cast<size_t>(y) * stride + k] != kGuard) __builtin_trap();
  return std::vector<uint8_t>(mem.begin() + kGuardBytes, mem.end() - kGuardBytes);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Bytes in{data, size};
  vds::RenderConfig cfg;
  cfg.width = static_cast<uint16_t>(1 + in.u8() % 48);
  cfg.height = static_cast<uint16_t>(1 + in.u8() % 40);
  cfg.format = (in.u8() & 1) ? vds::PixelFormat::rgb888 : vds::PixelFormat::rgb565;
  cfg.depth = (in.u8() & 1) ? vds::DepthFormat::d32 : vds::DepthFormat::d16;
  cfg.vertex_cache = in.u8() % 8;
  cfg.target_stride = cfg.width * static_cast<uint32_t>(vds::bytes_per_pixel(cfg.format)) + 2 * (in.u8() % 3);

  // A camera: mostly sane (so that something is drawn), sometimes raw.
  vds::Camera cam{};
  const uint8_t mode = in.u8();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const int32_t raw = (mode & 1) ? in.i32() : (i == j ? (1 << 30) : 0) + (in.i32() >> 12);
      cam.rotation.m[i][j] = vds::Q2_30::from_raw(raw);
    }
  cam.position = {vds::Q16_16::from_raw(in.i32() >> ((mode & 2) ? 0 : 10)), vds::Q16_16::from_raw(in.i32() >> ((mode & 2) ? 0 : 10)),
                  vds::Q16_16::from_raw(in.i32() >> ((mode & 2) ? 0 : 10))};
  cam.fx = vds::Q16_16::from_raw((mode & 4) ? in.i32() : (40 << 16) + (in.i32() & 0x3FFFFF));
  cam.fy = vds::Q16_16::from_raw((mode & 4) ? in.i32() : (40 << 16) + (in.i32() & 0x3FFFFF));
  cam.cx = vds::Q16_16::from_raw((mode & 8) ? in.i32() : (cfg.width << 15) + (in.i32() >> 20));
  cam.cy = vds::Q16_16::from_raw((mode & 8) ? in.i32() : (cfg.height << 15) + (in.i32() >> 20));
  cam.near_z = vds::Q16_16::from_raw((mode & 16) ? in.i32() : 256 + (in.i32() & 0xFFFF));
  cam.far_z = vds::Q16_16::from_raw((mode & 16) ? in.i32() : cam.near_z.raw() * (2 + (in.u8() & 1023)));

  // Positions: raw Q16.16, optionally shrunk so they land near the camera.
  const uint32_t np = 1 + in.u8() % 24;
  std::vector<vds::Vec3<vds::Q16_16>> pos(np);
  const int shrink = in.u8() % 16;
  for (auto& p : pos) {
    p = {vds::Q16_16::from_raw(in.i32() >> shrink), vds::Q16_16::from_raw(in.i32() >> shrink),
         vds::Q16_16::from_raw(in.i32() >> shrink)};
  }
  std::vector<vds::TexCoord> uvs(np);
  std::vector<uint32_t> colors(np);
  for (uint32_t i = 0; i < np; ++i) {
    uvs[i] = {vds::Q16_16::from_raw(in.i32()), vds::Q16_16::from_raw(in.i32())};
    colors[i] = in.u32();
  }

  // Textures: 5 x 4 (clamp-only sizes) and 8 x 4 (repeatable), with aprons.
  std::vector<uint16_t> t16(9 * 5);
  std::vector<uint32_t> t32(9 * 5);
  std::vector<uint8_t> yp(8 * 4), cb(4 * 2), cr(4 * 2);
  for (auto& v : t16) v = static_cast<uint16_t>(in.u32());
  for (auto& v : t32) v = in.u32();
  for (auto& v : yp) v = in.u8();
  for (size_t i = 0; i < cb.size(); ++i) {
    cb[i] = in.u8();
    cr[i] = in.u8();
  }
  vds::Texture tex[3];
  tex[0].format = vds::TexFormat::rgb565;
  tex[0].texels = t16.data();
  tex[1].format = vds::TexFormat::xrgb8888;
  tex[1].texels = t32.data();
  tex[2].format = vds::TexFormat::ycbcr420;
  tex[2].texels = yp.data();
  tex[2].cb = cb.data();
  tex[2].cr = cr.data();
  tex[2].chroma_stride = 4;
  const uint8_t tsel = in.u8();
  for (int k = 0; k < 3; ++k) {
    const bool small = (tsel >> k) & 1;
    tex[k].width = static_cast<uint16_t>(k == 2 ? 8 : (small ? 5 : 8));
    tex[k].height = 4;
    tex[k].stride = k == 2 ? 8 : 9;
    tex[k].address = ((tsel >> (3 + k)) & 1) ? vds::TexAddress::clamp : vds::TexAddress::repeat;
  }
  if (tsel & 0x40) vds::texture_fill_apron(tex[0], t16.data());
  if (tsel & 0x80) vds::texture_fill_apron(tex[1], t32.data());

  // Meshes: indices drawn from the input (occasionally out of range).
  const uint32_t nm = 1 + in.u8() % 4;
  std::vector<std::vector<uint16_t>> idx(nm);
  std::vector<std::vector<uint8_t>> corners(nm);
  std::vector<vds::Mesh> meshes(nm);
  for (uint32_t m = 0; m < nm; ++m) {
    const uint8_t kind = in.u8();
    vds::Mesh& mesh = meshes[m];
    mesh.shading = static_cast<vds::Shading>(kind % 4);
    mesh.filter = static_cast<vds::Filter>((kind >> 2) & 1);
    mesh.cull = static_cast<vds::Cull>(((kind >> 3) & 3) % 3);
    mesh.color = in.u32();
    mesh.colors = colors.data();
    mesh.uvs = uvs.data();
    mesh.texture = &tex[((kind >> 5) & 3) % 3];
    for (auto& row : mesh.view_map.m)
      for (int32_t& v : row) v = in.i32();
    const uint32_t nt = in.u8() % 12;
    // Faces of 3 or 4 corners (Mesh::corners) when the kind's top bit is
    // set, now and then a count out of range; room for 4 indices a face.
    if (kind & 0x80) {
      for (uint32_t t = 0; t < nt; ++t) {
        const uint8_t c = in.u8();
        corners[m].push_back(static_cast<uint8_t>(c == 255 ? 5 : (c == 254 ? 2 : 3 + (c & 1))));
      }
      mesh.corners = corners[m].data();
    }
    for (uint32_t t = 0; t < (mesh.corners ? 4 : 3) * nt; ++t) {
      const uint8_t b = in.u8();
      idx[m].push_back(static_cast<uint16_t>(b == 255 ? 1000 : b % np));
    }
    mesh.indices = idx[m].data();
    mesh.num_triangles = nt;
  }
  const vds::DrawList list{pos.data(), np, meshes.data(), nm};

  vds::Status s1, s2;
  // One-row bands keeping set-ups across bands (a few slots: evictions)
  // against the whole frame set up once.
  vds::RenderConfig banded = cfg;
  banded.setup_cache = cfg.vertex_cache % 4;
  const std::vector<uint8_t> a = render(banded, 1, cam, list, &s1);
  const std::vector<uint8_t> b = render(cfg, cfg.height, cam, list, &s2);
  if (s1 != s2) __builtin_trap();
  if (s1 == vds::Status::ok && a != b) __builtin_trap();

  // View-mapped meshes asking a ViewMapSource for each triangle's view and
  // homography (their own, as Mesh::views says) draw what they draw alone.
  struct Own {
    const vds::Mesh* mesh;
    static bool map(void* ctx, uint32_t, uint32_t, const vds::Texture** t, vds::Homography* h) {
      const vds::Mesh& m = *static_cast<const Own*>(ctx)->mesh;
      *t = m.texture;
      *h = m.view_map;
      return true;
    }
  };
  std::vector<Own> own(nm);
  std::vector<vds::ViewMapSource> sources(nm);
  std::vector<vds::Mesh> asking = meshes;
  for (uint32_t m = 0; m < nm; ++m) {
    own[m].mesh = &meshes[m];
    sources[m] = {&Own::map, &own[m]};
    if (asking[m].shading == vds::Shading::view_mapped) asking[m].views = &sources[m];
  }
  vds::Status s3;
  const std::vector<uint8_t> c = render(banded, 1, cam, vds::DrawList{pos.data(), np, asking.data(), nm}, &s3);
  if (s3 != s2) __builtin_trap();
  if (s3 == vds::Status::ok && c != b) __builtin_trap();

  // Small faces drawn in one colour from a point of their view
  // (RenderConfig::point_face_span; the point anywhere, far outside the
  // view too, or refused): the same status, and the same frame in one-row
  // bands as whole.
  struct Point {
    const vds::Mesh* mesh;
    int32_t u, v;
    uint8_t mode;  // bit 0: refuse (map is asked), bit 1: a face's own offset
    static bool map(void* ctx, uint32_t t, uint32_t first, const vds::Texture** tex, vds::Homography* h) {
      Own own{static_cast<const Point*>(ctx)->mesh};
      return Own::map(&own, t, first, tex, h);
    }
    static bool point(void* ctx, uint32_t t, uint32_t, const vds::Texture** tex, int32_t* u, int32_t* v) {
      const Point& p = *static_cast<const Point*>(ctx);
      if (p.mode & 1) return false;
      *tex = p.mesh->texture;
      *u = p.u + ((p.mode & 2) ? static_cast<int32_t>(t * 97) : 0);
      *v = p.v - ((p.mode & 2) ? static_cast<int32_t>(t * 61) : 0);
      return true;
    }
  };
  const uint8_t span = in.u8();
  std::vector<Point> points(nm);
  std::vector<vds::ViewMapSource> point_sources(nm);
  std::vector<vds::Mesh> pointing = meshes;
  for (uint32_t m = 0; m < nm; ++m) {
    points[m] = {&meshes[m], in.i32() >> (in.u8() % 32), in.i32() >> (in.u8() % 32), in.u8()};
    point_sources[m] = {&Point::map, &points[m], &Point::point};
    if (pointing[m].shading == vds::Shading::view_mapped) pointing[m].views = &point_sources[m];
  }
  vds::RenderConfig pointed = banded, pointed_whole = cfg;
  pointed.point_face_span = pointed_whole.point_face_span = span;
  vds::Status s4, s5;
  const vds::DrawList point_list{pos.data(), np, pointing.data(), nm};
  const std::vector<uint8_t> d = render(pointed, 1, cam, point_list, &s4);
  const std::vector<uint8_t> e = render(pointed_whole, cfg.height, cam, point_list, &s5);
  if (s4 != s2 || s5 != s2) __builtin_trap();
  if (s4 == vds::Status::ok && d != e) __builtin_trap();

  // Grid positions ((g << shift) + origin) against the Q16.16 positions
  // they stand for, saturated as the renderer saturates them: the same
  // status and frame; a shift above 15 is refused.
  const uint8_t gsel = in.u8();
  if (gsel & 1) {
    const uint8_t shift = static_cast<uint8_t>(gsel >> 3);
    const int32_t origin[3] = {in.i32() >> (gsel & 6), in.i32() >> (gsel & 6), in.i32() >> (gsel & 6)};
    std::vector<uint16_t> grid(3 * np);
    std::vector<vds::Vec3<vds::Q16_16>> world(np);
    for (uint32_t v = 0; v < np; ++v) {
      int32_t w[3];
      for (int k = 0; k < 3; ++k) {
        grid[3 * v + k] = static_cast<uint16_t>(in.u8() | in.u8() << 8);
        int64_t x = (int64_t{grid[3 * v + k]} << (shift & 15)) + origin[k];
        if (x > INT32_MAX) x = INT32_MAX;
        if (x < INT32_MIN) x = INT32_MIN;
        w[k] = static_cast<int32_t>(x);
      }
      world[v] = {vds::Q16_16::from_raw(w[0]), vds::Q16_16::from_raw(w[1]), vds::Q16_16::from_raw(w[2])};
    }
    vds::DrawList by_world = list, by_grid = list;
    by_world.positions = world.data();
    by_grid.positions = nullptr;
    by_grid.grid = grid.data();
    by_grid.grid_shift = shift;
    by_grid.grid_origin = {vds::Q16_16::from_raw(origin[0]), vds::Q16_16::from_raw(origin[1]),
                           vds::Q16_16::from_raw(origin[2])};
    vds::Status sw, sg;
    const std::vector<uint8_t> fw = render(cfg, cfg.height, cam, by_world, &sw);
    const std::vector<uint8_t> fg = render(cfg, cfg.height, cam, by_grid, &sg);
    if (shift > 15) {
      if (sg != vds::Status::invalid_argument) __builtin_trap();
    } else {
      if (sg != sw) __builtin_trap();
      if (sg == vds::Status::ok && fg != fw) __builtin_trap();
    }
  }
  return 0;
}
