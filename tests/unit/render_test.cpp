// The client renderer (vds/render.h) against the double-precision reference
// (vds/ref/render.h) on the shared scenes, and its contract: band height
// never changes the picture and nothing is written outside the band,
// clipping, degenerate and hostile input, validation, and golden checksums
// for comparing builds.
#include "vds/render.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <utility>
#include <tuple>
#include <vector>

#include "../../decoder/src/render_internal.h"
#include "vds/crc32c.h"
#include "vds/homography.h"
#include "vds/enc/image_io.h"
#include "vds/ref/render.h"
#include "vds/ref/scene.h"

namespace vds {
namespace {

using ref::ClientFrame;
using ref::ClientRenderSettings;
using ref::ClientScene;
using ref::Scene;

const char* tex_name(TexFormat f) {
  return f == TexFormat::rgb565 ? "rgb565" : f == TexFormat::xrgb8888 ? "xrgb8888" : "ycbcr420";
}

Scene view_mapped_cube() {
  const Scene base = ref::make_cube_scene();
  const ref::CameraD view_cam = ref::CameraD::look_at({2.8, 2.9, -4.8}, {0.2, 0.9, 0.3}, {0, 1, 0}, 240, 180, 55, 0.5, 60);
  const ref::RefFrame view = ref::ref_render(base, view_cam, 240, 180);
  std::vector<int> faces;
  for (int i = 0; i < static_cast<int>(base.meshes.size()); ++i) faces.push_back(i);
  return ref::make_view_mapped_scene(base, faces, view.image, view_cam);
}

std::vector<Scene> all_scenes() {
  std::vector<Scene> v = ref::shared_scenes();
  v.push_back(view_mapped_cube());
  return v;
}

// ---------------------------------------------------------------------------
// Accuracy
// ---------------------------------------------------------------------------
TEST(RenderAccuracy, SharedScenesReach45dBAgainstTheFloatReference) {
  for (const Scene& base : all_scenes()) {
    for (TexFormat tf : {TexFormat::xrgb8888, TexFormat::rgb565, TexFormat::ycbcr420}) {
      const Scene sc = ref::client_textures(base, tf);
      const ref::RefFrame ref = ref::ref_render(sc);
      const ClientScene cs(sc, tf);
      for (DepthFormat df : {DepthFormat::d32, DepthFormat::d16}) {
        ClientRenderSettings st;
        st.format = PixelFormat::rgb888;
        st.depth = df;
        const ClientFrame fr = ref::render_client(cs, sc.width, sc.height, st);
        ASSERT_EQ(fr.status, Status::ok);
        const double p = enc::psnr(ref.image, fr.image);
        EXPECT_GE(p, 45.0) << sc.name << " " << tex_name(tf) << (df == DepthFormat::d16 ? " d16" : " d32");
        EXPECT_GT(fr.stats.pixels, 20000u) << sc.name;  // the scene is really drawn
      }
    }
  }
}

// Every bilinear mesh of a scene drawn with Filter::bilinear_luma.
Scene with_luma_filter(Scene sc) {
  for (auto& m : sc.meshes)
    if (m.filter == Filter::bilinear) m.filter = Filter::bilinear_luma;
  return sc;
}

TEST(RenderAccuracy, BilinearLumaFilterIsBilinearInLumaAndNearestInChroma) {
  for (const Scene& base : all_scenes()) {
    Scene sc = ref::client_textures(base, TexFormat::ycbcr420);
    ClientRenderSettings st;
    st.format = PixelFormat::rgb888;
    // Against the float reference (bilinear in every channel): chroma from
    // the nearest chroma texel costs a few dB (cube 38.6, terrain 51.1,
    // room 34.8, cube-from-view 37.8), no more.
    const ref::RefFrame ref = ref::ref_render(sc);
    const ClientFrame luma = ref::render_client(ClientScene(with_luma_filter(sc), TexFormat::ycbcr420), sc.width, sc.height, st);
    ASSERT_EQ(luma.status, Status::ok);
    const double p = enc::psnr(ref.image, luma.image);
    EXPECT_GE(p, 33.0) << sc.name;
    const ClientFrame bilinear = ref::render_client(ClientScene(sc, TexFormat::ycbcr420), sc.width, sc.height, st);
    EXPECT_NE(bilinear.bytes, luma.bytes) << sc.name << ": the filter changes nothing";
    // With flat chroma, bit for bit what Filter::bilinear draws.
    for (auto& t : sc.textures) {
      std::fill(t.cb.pixels.begin(), t.cb.pixels.end(), 128);
      std::fill(t.cr.pixels.begin(), t.cr.pixels.end(), 128);
    }
    const ClientFrame a = ref::render_client(ClientScene(sc, TexFormat::ycbcr420), sc.width, sc.height, st);
    const ClientFrame b = ref::render_client(ClientScene(with_luma_filter(sc), TexFormat::ycbcr420), sc.width, sc.height, st);
    ASSERT_EQ(b.status, Status::ok);
    EXPECT_EQ(a.bytes, b.bytes) << sc.name;
    std::printf("%s: bilinear luma, nearest chroma: %.2f dB against the float reference\n", sc.name.c_str(), p);
  }
}

TEST(RenderAccuracy, Rgb565OutputMatchesTheRoundedReference) {
  // With rgb565 output the client rounds once more (5-bit bilinear weights,
  // 5/6/5 channels), so a 1-step difference in 5 bits costs 8 levels: the
  // bound is lower than for rgb888.
  for (const Scene& base : ref::shared_scenes()) {
    const Scene sc = ref::client_textures(base, TexFormat::rgb565);
    enc::Image ref = ref::ref_render(sc).image;
    for (size_t i = 0; i < ref.pixels.size(); ++i) {
      const uint32_t v = ref.pixels[i];
      const bool green = i % 3 == 1;
      const uint32_t q = green ? (v * 253 + 505) >> 10 : (v * 249 + 1014) >> 11;
      ref.pixels[i] = static_cast<uint8_t>(green ? (q << 2 | q >> 4) : (q << 3 | q >> 2));
    }
    const ClientScene cs(sc, TexFormat::rgb565);
    ClientRenderSettings st;
    st.format = PixelFormat::rgb565;
    const ClientFrame fr = ref::render_client(cs, sc.width, sc.height, st);
    ASSERT_EQ(fr.status, Status::ok);
    EXPECT_GE(enc::psnr(ref, fr.image), 40.0) << sc.name;
  }
}

TEST(RenderAccuracy, PerPixelReciprocalWithinStatedBound) {
  // -2^-31 <= y / (2^62 / (w << clz(w))) - 1 < 2^-18 over every table
  // interval, sampled densely, and at the ends of the range.
  std::vector<uint32_t> ws = {1, 2, 3, 0x7FFFFFFFu, 0x40000000u, 0x40000001u, 0x3FFFFFFFu};
  for (uint32_t k = 0; k < 256; ++k)
    for (uint32_t t = 0; t < (1u << 23); t += 9973) ws.push_back((1u << 31) + (k << 23) + t);
  for (uint32_t w : ws) {
    int z = 0;
    const int32_t y = detail::span_reciprocal(w, &z);
    ASSERT_EQ(z, __builtin_clz(w));
    const long double exact = std::ldexp(1.0L, 62) / (static_cast<long double>(w) * std::ldexp(1.0L, z));
    const long double rel = y / exact - 1;
    ASSERT_LT(rel, std::ldexp(1.0L, -18)) << w;
    ASSERT_GE(rel, -std::ldexp(1.0L, -31)) << w;
  }
}

// ---------------------------------------------------------------------------
// Bands
// ---------------------------------------------------------------------------
TEST(RenderBands, AnyBandHeightAndCacheSizesGiveTheSameFrame) {
  for (const Scene& base : {ref::make_cube_scene(), ref::make_room_scene(), ref::make_golden_scene()}) {
    const ClientScene cs(base, TexFormat::rgb565);
    for (PixelFormat of : {PixelFormat::rgb565, PixelFormat::rgb888}) {
      std::vector<uint8_t> first;
      for (int band : {1, 7, 16, 180}) {
        for (uint32_t cache : {0u, 5u, 65536u}) {
          ClientRenderSettings st;
          st.format = of;
          st.band_height = band;
          st.vertex_cache = cache;
          st.triangle_cache = cache == 5u ? 9u : cache;  // some triangles cached, some not
          // Set-ups kept across bands: none, a few slots shared by many
          // triangles (evictions), or one per triangle.
          st.setup_cache = cache == 0u ? 0u : (cache == 5u ? 3u : 4096u);
          const ClientFrame fr = ref::render_client(cs, 240, 180, st);
          ASSERT_EQ(fr.status, Status::ok);
          if (first.empty()) {
            first = fr.bytes;
          } else {
            ASSERT_EQ(fr.bytes, first) << base.name << " band " << band << " cache " << cache;
          }
        }
      }
    }
  }
}

// Renders into a caller frame with guard rows and columns around it; the sink
// checks at every band that rows not yet drawn still hold the sentinel and
// rows of finished bands have not changed since.
TEST(RenderBands, NothingIsWrittenOutsideTheCurrentBand) {
  const Scene sc = ref::make_room_scene(120, 90);
  const ClientScene cs(sc, TexFormat::xrgb8888);
  for (PixelFormat of : {PixelFormat::rgb565, PixelFormat::rgb888}) {
    for (uint16_t band : {1, 7, 16, 90}) {
      const int w = 120, h = 90, bpp = bytes_per_pixel(of);
      const int guard = 8;
      const uint32_t stride = static_cast<uint32_t>((w + 2 * guard) * bpp);
      std::vector<uint8_t> mem(static_cast<size_t>(h + 2 * guard) * stride, 0xA5);
      uint8_t* frame = mem.data() + guard * stride + guard * bpp;
      RenderConfig cfg;
      cfg.width = w;
      cfg.height = h;
      cfg.band_height = band;
      cfg.format = of;
      cfg.depth = DepthFormat::d16;
      cfg.target = frame;
      cfg.target_stride = stride;
      std::vector<uint8_t> ws(render_workspace_size(cfg));
      Arena arena(ws.data(), ws.size());
      Renderer r;
      ASSERT_EQ(r.init(cfg, arena), Status::ok);
      struct Check {
        std::vector<uint8_t>* mem;
        std::vector<uint8_t> done;  // copy of the frame after the last band
        uint8_t* frame;
        uint32_t stride;
        int w, h, bpp, guard;
        int expect_y = 0;
        int failures = 0;
      } ck{&mem, mem, frame, stride, w, h, bpp, guard};
      auto sink = [](void* p, const Band& b) {
        auto* c = static_cast<Check*>(p);
        if (b.y != c->expect_y || b.pixels != c->frame + static_cast<size_t>(b.y) * c->stride) ++c->failures;
        const size_t base = static_cast<size_t>(c->guard) * c->stride;
        for (int row = -c->guard; row < c->h + c->guard; ++row) {
          const size_t off = base + static_cast<ptrdiff_t>(row) * static_cast<ptrdiff_t>(c->stride);
          for (uint32_t k = 0; k < c->stride; ++k) {
            const bool in_band = row >= b.y && row < b.y + b.height && k >= static_cast<uint32_t>(c->guard * c->bpp) &&
                                 k < static_cast<uint32_t>((c->guard + c->w) * c->bpp);
            if (in_band) continue;
            // Everything else equals its state after the previous band.
            if ((*c->mem)[off + k] != c->done[off + k]) ++c->failures;
          }
        }
        c->done = *c->mem;
        c->expect_y = b.y + b.height;
        return true;
      };
      ASSERT_EQ(r.render(cs.camera(), cs.list(), cs.clear_color(), sink, &ck), Status::ok);
      EXPECT_EQ(ck.failures, 0) << "band " << band;
      EXPECT_EQ(ck.expect_y, h);
      // The guard area is untouched.
      for (int row = 0; row < h + 2 * guard; ++row)
        for (uint32_t k = 0; k < stride; ++k) {
          const bool inside = row >= guard && row < guard + h && k >= static_cast<uint32_t>(guard * bpp) &&
                              k < static_cast<uint32_t>((guard + w) * bpp);
          if (!inside) ASSERT_EQ(mem[static_cast<size_t>(row) * stride + k], 0xA5);
        }
    }
  }
}

TEST(RenderBands, SinkReturningFalseAborts) {
  const ClientScene cs(ref::make_cube_scene(), TexFormat::rgb565);
  RenderConfig cfg;
  cfg.width = 240;
  cfg.height = 180;
  cfg.band_height = 16;
  std::vector<uint8_t> ws(render_workspace_size(cfg));
  Arena arena(ws.data(), ws.size());
  Renderer r;
  ASSERT_EQ(r.init(cfg, arena), Status::ok);
  int calls = 0;
  auto sink = [](void* p, const Band&) { return ++*static_cast<int*>(p) < 3; };
  EXPECT_EQ(r.render(cs.camera(), cs.list(), 0, sink, &calls), Status::aborted);
  EXPECT_EQ(calls, 3);
}

// ---------------------------------------------------------------------------
// Clipping
// ---------------------------------------------------------------------------
// Texture coordinates are 24 texels per unit, or `uv_scale`: they must stay
// within the Q16.16 range (+-32768 texels).
Scene single_triangle(ref::Vec3d a, ref::Vec3d b, ref::Vec3d c, double uv_scale = 24, Cull cull = Cull::none) {
  Scene s;
  s.width = 160;
  s.height = 120;
  s.clear_color = 0x000000;
  s.textures.push_back({});
  s.textures[0].image = ref::make_checker_texture(64, 8, 0xF0E0D0, 0x304050);
  ref::MeshD m;
  m.shading = Shading::texture;
  m.texture = 0;
  m.cull = cull;
  for (const ref::Vec3d& p : {a, b, c}) m.indices.push_back(s.add_vertex(p, {p.x * uv_scale + 7, p.z * uv_scale - 3}));
  s.meshes.push_back(m);
  s.camera = ref::CameraD::look_at({0, 1.5, 0}, {0, 0.5, 4}, {0, 1, 0}, 160, 120, 70, 0.25, 50);
  return s;
}

void expect_matches_reference(const Scene& sc, double min_psnr) {
  const Scene q = ref::client_textures(sc, TexFormat::xrgb8888);
  const ref::RefFrame ref = ref::ref_render(q);
  const ClientScene cs(q, TexFormat::xrgb8888);
  ClientRenderSettings st;
  for (int band : {1, 16, sc.height}) {
    st.band_height = band;
    const ClientFrame fr = ref::render_client(cs, sc.width, sc.height, st);
    ASSERT_EQ(fr.status, Status::ok);
    EXPECT_GE(enc::psnr(ref.image, fr.image), min_psnr) << "band " << band;
  }
}

TEST(RenderClip, TriangleBehindTheCameraDrawsNothing) {
  const Scene sc = single_triangle({-1, 0, -3}, {1, 0, -3}, {0, 2, -2});
  const ClientScene cs(sc, TexFormat::rgb565);
  const ClientFrame fr = ref::render_client(cs, sc.width, sc.height, {});
  ASSERT_EQ(fr.status, Status::ok);
  EXPECT_EQ(fr.stats.pixels, 0u);
  for (uint8_t v : fr.image.pixels) ASSERT_EQ(v, 0);
}

TEST(RenderClip, NearPlaneAndGuardBandClippingMatchTheReference) {
  // Crossing the near plane (one and two vertices behind the camera).
  expect_matches_reference(single_triangle({-3, 0, -2}, {3, 0, -2}, {0, 0, 9}), 45);
  expect_matches_reference(single_triangle({-3, 0, 6}, {3, 0, 6}, {0, 0.2, -5}), 45);
  // Far beyond the guard band on both sides, and beyond the far plane.
  expect_matches_reference(single_triangle({-4000, 0, 3}, {4000, 0, 3}, {0, 1, 200}, 4), 45);
  // Vertex very close to the camera plane, off to the side.
  expect_matches_reference(single_triangle({-8, 1.49, 0.001}, {2, 0, 5}, {-1, 3, 8}), 45);
}

TEST(RenderClip, RoomWithTheCameraAgainstAWall) {
  Scene sc = ref::make_room_scene(160, 120);
  sc.camera = ref::CameraD::look_at({-3.93, 1.2, 0.3}, {3.0, 0.9, 0.9}, {0, 1, 0}, 160, 120, 80, 0.05, 20);
  expect_matches_reference(sc, 45);
}

// ---------------------------------------------------------------------------
// Degenerate and hostile input
// ---------------------------------------------------------------------------
TEST(RenderDegenerate, ZeroAreaAndTinyTrianglesDrawNothing) {
  Scene s;
  s.width = 64;
  s.height = 48;
  ref::MeshD m;
  m.shading = Shading::flat;
  m.color = 0xFFFFFF;
  m.cull = Cull::none;
  auto tri = [&](ref::Vec3d a, ref::Vec3d b, ref::Vec3d c) {
    for (const ref::Vec3d& p : {a, b, c}) m.indices.push_back(s.add_vertex(p));
  };
  tri({0, 0, 5}, {0, 0, 5}, {0, 0, 5});          // a point
  tri({-1, -1, 5}, {0, 0, 5}, {1, 1, 5});        // collinear
  tri({-1, 0, 5}, {1, 0, 5}, {1, 0, 5});         // two equal vertices
  tri({-1, 0, 4}, {0, 0, 5}, {1, 0, 6});         // edge-on plane through the camera ray
  // A sliver between pixel centres: covers no centre.
  tri({0.001, 0.001, 5}, {0.004, 0.001, 5}, {0.001, 0.004, 5});
  s.meshes.push_back(m);
  s.camera = ref::CameraD::look_at({0, 0, 0}, {0, 0, 1}, {0, 1, 0}, 64, 48, 60, 0.5, 50);
  s.camera.cx = 32.25;  // pixel centres at +-1/4 pixel around the optical axis
  s.camera.cy = 24.25;
  const ClientScene cs(s, TexFormat::rgb565);
  const ClientFrame fr = ref::render_client(cs, 64, 48, {});
  ASSERT_EQ(fr.status, Status::ok);
  EXPECT_EQ(fr.stats.pixels, 0u);
}

TEST(RenderDegenerate, HostileCoordinatesAreSafe) {
  // Raw positions anywhere in Q16.16, around a valid camera: must not crash
  // or trip the sanitizers; pictures are whatever the geometry gives.
  std::mt19937 rng(99);
  std::vector<Vec3<Q16_16>> pos(300);
  const int32_t specials[] = {INT32_MIN, INT32_MAX, 0, 1, -1, 1 << 30, -(1 << 30), 65536, 6554};
  for (auto& p : pos) {
    auto pick = [&]() {
      return (rng() & 3) == 0 ? specials[rng() % 9] : static_cast<int32_t>(rng());
    };
    p = {Q16_16::from_raw(pick()), Q16_16::from_raw(pick()), Q16_16::from_raw(pick())};
  }
  std::vector<uint16_t> idx(3 * 400);
  for (auto& i : idx) i = static_cast<uint16_t>(rng() % pos.size());
  std::vector<TexCoord> uvs(pos.size());
  for (auto& t : uvs) t = {Q16_16::from_raw(static_cast<int32_t>(rng())), Q16_16::from_raw(static_cast<int32_t>(rng()))};
  std::vector<uint32_t> cols(pos.size(), 0x123456);
  std::vector<uint16_t> tex(17 * 9, 0x7BEF);
  Texture t;
  t.width = 16;
  t.height = 8;
  t.stride = 17;
  t.texels = tex.data();
  t.address = TexAddress::repeat;
  Texture tc = t;
  tc.address = TexAddress::clamp;
  tc.apron = true;
  Mesh meshes[5];
  for (int k = 0; k < 5; ++k) {
    meshes[k].indices = idx.data() + k * 240;
    meshes[k].num_triangles = 80;
    meshes[k].cull = Cull::none;
    meshes[k].uvs = uvs.data();
    meshes[k].colors = cols.data();
    meshes[k].texture = (k & 1) ? &t : &tc;
  }
  meshes[0].shading = Shading::flat;
  meshes[1].shading = Shading::gouraud;
  meshes[2].shading = Shading::texture;
  meshes[3].shading = Shading::texture;
  meshes[3].filter = Filter::nearest;
  meshes[4].shading = Shading::view_mapped;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) meshes[4].view_map.m[i][j] = static_cast<int32_t>(rng());
  DrawList list{pos.data(), static_cast<uint32_t>(pos.size()), meshes, 5};
  const Camera cam = ref::to_client(ref::CameraD::look_at({0, 0, 0}, {0, 0, 1}, {0, 1, 0}, 80, 60, 60, 0.01, 40));
  for (PixelFormat of : {PixelFormat::rgb565, PixelFormat::rgb888}) {
    for (DepthFormat df : {DepthFormat::d16, DepthFormat::d32}) {
      RenderConfig cfg;
      cfg.width = 80;
      cfg.height = 60;
      cfg.band_height = 13;
      cfg.format = of;
      cfg.depth = df;
      cfg.vertex_cache = 100;
      std::vector<uint8_t> ws(render_workspace_size(cfg));
      Arena arena(ws.data(), ws.size());
      Renderer r;
      ASSERT_EQ(r.init(cfg, arena), Status::ok);
      EXPECT_EQ(r.render(cam, list, 0, [](void*, const Band&) { return true; }, nullptr), Status::ok);
    }
  }
}

// A clamping sampler reads only the texels of its texture, and the same
// ones whether a span lies inside it (sampled without the clamps) or
// reaches past an edge. Each texture is drawn twice: its planes in arrays of
// exactly its size (AddressSanitizer catches a read past the last row) and
// inside larger planes whose surround is noise (a read past any edge then
// changes the picture). Perspective-mapped triangles over the texture's
// edges and inside it, every filter, both mappings (texture coordinates and
// a view's homography), odd and even sizes.
TEST(RenderSpans, ClampedTexturesAreReadOnlyInsideWithOrWithoutTheClamps) {
  std::mt19937 rng(2024);
  const auto uni = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  const auto q = [](double x) { return Q16_16::from_raw(static_cast<int32_t>(std::lround(x * 65536))); };
  const ref::CameraD screen_d = ref::CameraD::look_at({0, 0, 0}, {0, 0, 1}, {0, 1, 0}, 96, 72, 60, 0.1, 60);
  const Camera screen = ref::to_client(screen_d);
  for (const auto& [w, h] : {std::pair{37, 23}, std::pair{32, 16}, std::pair{5, 3}}) {
    for (TexFormat tf : {TexFormat::rgb565, TexFormat::xrgb8888, TexFormat::ycbcr420}) {
      // Tight planes and padded ones (a border of 3 texels of noise).
      const int bpp = tf == TexFormat::rgb565 ? 2 : (tf == TexFormat::xrgb8888 ? 4 : 1);
      const int cw = (w + 1) / 2, ch = (h + 1) / 2, pad = 3;
      std::vector<uint8_t> ty(static_cast<size_t>(w * h * bpp)), tcb(static_cast<size_t>(cw * ch)), tcr(tcb.size());
      for (auto& b : ty) b = static_cast<uint8_t>(rng());
      for (auto& b : tcb) b = static_cast<uint8_t>(rng());
      for (auto& b : tcr) b = static_cast<uint8_t>(rng());
      const int pw = w + 2 * pad, ph = h + 2 * pad, pcw = cw + 2 * pad, pch = ch + 2 * pad;
      std::vector<uint8_t> py(static_cast<size_t>(pw * ph * bpp)), pcb(static_cast<size_t>(pcw * pch)), pcr(pcb.size());
      for (auto& b : py) b = static_cast<uint8_t>(rng());
      for (auto& b : pcb) b = static_cast<uint8_t>(rng());
      for (auto& b : pcr) b = static_cast<uint8_t>(rng());
      for (int r = 0; r < h; ++r)
        std::memcpy(&py[static_cast<size_t>(((r + pad) * pw + pad) * bpp)], &ty[static_cast<size_t>(r * w * bpp)], static_cast<size_t>(w * bpp));
      for (int r = 0; r < ch; ++r) {
        std::memcpy(&pcb[static_cast<size_t>((r + pad) * pcw + pad)], &tcb[static_cast<size_t>(r * cw)], static_cast<size_t>(cw));
        std::memcpy(&pcr[static_cast<size_t>((r + pad) * pcw + pad)], &tcr[static_cast<size_t>(r * cw)], static_cast<size_t>(cw));
      }
      Texture tight;
      tight.format = tf;
      tight.address = TexAddress::clamp;
      tight.width = static_cast<uint16_t>(w);
      tight.height = static_cast<uint16_t>(h);
      tight.stride = static_cast<uint32_t>(w);
      tight.texels = ty.data();
      Texture padded = tight;
      padded.stride = static_cast<uint32_t>(pw);
      padded.texels = &py[static_cast<size_t>((pad * pw + pad) * bpp)];
      if (tf == TexFormat::ycbcr420) {
        tight.cb = tcb.data();
        tight.cr = tcr.data();
        tight.chroma_stride = static_cast<uint32_t>(cw);
        padded.cb = &pcb[static_cast<size_t>(pad * pcw + pad)];
        padded.cr = &pcr[static_cast<size_t>(pad * pcw + pad)];
        padded.chroma_stride = static_cast<uint32_t>(pcw);
      }
      // Triangles in front of the screen; each mesh maps them from a view
      // camera of the texture's size near the screen's (view_mapped), or by
      // texture coordinates from just outside the texture to inside it.
      std::vector<Vec3<Q16_16>> pos;
      std::vector<TexCoord> uvs;
      std::vector<uint16_t> idx;
      std::vector<Mesh> meshes;
      const std::vector<Filter> filters = tf == TexFormat::ycbcr420
                                              ? std::vector<Filter>{Filter::nearest, Filter::bilinear, Filter::bilinear_luma}
                                              : std::vector<Filter>{Filter::nearest, Filter::bilinear};
      constexpr int kTriangles = 24;
      idx.assign(static_cast<size_t>(2 * filters.size() * kTriangles * 3), 0);
      for (size_t k = 0; k < 2 * filters.size(); ++k) {
        Mesh m;
        m.shading = k % 2 == 0 ? Shading::texture : Shading::view_mapped;
        m.filter = filters[k / 2];
        m.cull = Cull::none;
        m.indices = &idx[k * kTriangles * 3];
        m.num_triangles = kTriangles;
        const double z = uni(2, 8);
        const double corner[3][3] = {{-1, -1, z}, {1, -1, z + uni(-1, 1)}, {0, 1, z + uni(-1, 1)}};
        const Vec3<Q16_16> plane[3] = {{q(corner[0][0]), q(corner[0][1]), q(corner[0][2])},
                                       {q(corner[1][0]), q(corner[1][1]), q(corner[1][2])},
                                       {q(corner[2][0]), q(corner[2][1]), q(corner[2][2])}};
        if (m.shading == Shading::view_mapped) {
          // Behind the screen's camera, so that the plane fits its few
          // texels; a focal length the client takes (>= 32 pixels).
          const double fov_y = 2 * std::atan(h / 2.0 / uni(34, 60)) * 180 / M_PI;
          const ref::CameraD vd = ref::CameraD::look_at({uni(-0.5, 0.5), uni(-0.5, 0.5), -uni(4, 12)}, {uni(-0.3, 0.3), uni(-0.3, 0.3), z},
                                                        {0, 1, 0}, w, h, fov_y, 0.1, 60);
          EXPECT_EQ(plane_homography(screen, ref::to_client(vd), plane, &m.view_map), Status::ok);
        }
        // Points of the plane across the screen.
        const auto on_plane = [&]() {
          const double a = uni(0, 1), b = uni(0, 1 - a);
          double v[3];
          for (int c = 0; c < 3; ++c) {
            const double big = 4;  // beyond the triangle: the plane, not just the triangle
            v[c] = corner[0][c] + (a * big - 1) * (corner[1][c] - corner[0][c]) + (b * big - 1) * (corner[2][c] - corner[0][c]);
          }
          return Vec3<Q16_16>{q(v[0]), q(v[1]), q(v[2])};
        };
        for (int t = 0; t < kTriangles * 3; ++t) {
          idx[k * kTriangles * 3 + static_cast<size_t>(t)] = static_cast<uint16_t>(pos.size());
          pos.push_back(on_plane());
          uvs.push_back({q(uni(-1.5, w + 1.5)), q(uni(-1.5, h + 1.5))});
        }
        meshes.push_back(m);
      }
      for (Mesh& m : meshes) m.uvs = uvs.data();
      std::vector<uint8_t> frames[2];
      for (int variant = 0; variant < 2; ++variant) {
        for (Mesh& m : meshes) m.texture = variant == 0 ? &tight : &padded;
        DrawList list{pos.data(), static_cast<uint32_t>(pos.size()), meshes.data(), static_cast<uint32_t>(meshes.size())};
        RenderConfig cfg;
        cfg.width = 96;
        cfg.height = 72;
        cfg.band_height = 72;
        cfg.format = PixelFormat::rgb888;
        cfg.depth = DepthFormat::d32;
        std::vector<uint8_t> ws(render_workspace_size(cfg));
        Arena arena(ws.data(), ws.size());
        Renderer r;
        ASSERT_EQ(r.init(cfg, arena), Status::ok);
        struct Sink {
          std::vector<uint8_t>* out;
          static bool put(void* ctx, const Band& b) {
            auto* out = static_cast<Sink*>(ctx)->out;
            for (int y = 0; y < b.height; ++y) out->insert(out->end(), b.pixels + y * b.stride, b.pixels + y * b.stride + b.width * 3);
            return true;
          }
        } sink{&frames[variant]};
        ASSERT_EQ(r.render(screen, list, 0, &Sink::put, &sink), Status::ok);
        EXPECT_GT(r.stats().pixels, 96u * 72u / 2) << "the triangles cover the screen";
      }
      EXPECT_EQ(frames[0], frames[1]) << w << "x" << h << " " << tex_name(tf);
    }
  }
}

// ---------------------------------------------------------------------------
// API and validation
// ---------------------------------------------------------------------------
TEST(RenderApi, ValidationStatuses) {
  RenderConfig cfg;
  cfg.width = 64;
  cfg.height = 48;
  cfg.band_height = 8;
  EXPECT_GT(render_workspace_size(cfg), 0u);
  std::vector<uint8_t> ws(render_workspace_size(cfg));
  {
    RenderConfig bad = cfg;
    bad.band_height = 0;
    Arena a(ws.data(), ws.size());
    Renderer r;
    EXPECT_EQ(r.init(bad, a), Status::invalid_argument);
    EXPECT_EQ(render_workspace_size(bad), 0u);
    bad = cfg;
    bad.width = 4096;
    EXPECT_EQ(r.init(bad, a), Status::invalid_argument);
  }
  {
    Arena small(ws.data(), ws.size() - 64);
    Renderer r;
    EXPECT_EQ(r.init(cfg, small), Status::workspace_too_small);
  }
  {
    // The set-up cache: bounded, paid for in the workspace, and init needs
    // exactly what render_workspace_size says (from any alignment).
    RenderConfig sc = cfg;
    sc.setup_cache = 4097;
    EXPECT_EQ(render_workspace_size(sc), 0u);
    sc.setup_cache = 3;
    const size_t need = render_workspace_size(sc);
    EXPECT_GT(need, render_workspace_size(cfg) + 3 * 64);
    std::vector<uint8_t> big(need + 8);
    for (size_t shift = 0; shift < 8; ++shift) {
      Arena a(big.data() + shift, need);
      Renderer r;
      EXPECT_EQ(r.init(sc, a), Status::ok) << shift;
      Arena b(big.data() + shift, render_workspace_size(cfg) + 64);
      EXPECT_EQ(r.init(sc, b), Status::workspace_too_small) << shift;
    }
  }
  Arena a(ws.data(), ws.size());
  Renderer r;
  const Camera cam = ref::to_client(ref::CameraD::look_at({0, 0, 0}, {0, 0, 1}, {0, 1, 0}, 64, 48, 60, 0.5, 50));
  auto sink = [](void*, const Band&) { return true; };
  DrawList empty{};
  EXPECT_EQ(r.render(cam, empty, 0, sink, nullptr), Status::invalid_argument);  // not initialised
  ASSERT_EQ(r.init(cfg, a), Status::ok);
  EXPECT_EQ(r.render(cam, empty, 0, sink, nullptr), Status::ok);
  EXPECT_EQ(r.render(cam, empty, 0, nullptr, nullptr), Status::invalid_argument);  // no sink, no target
  Camera bad_cam = cam;
  bad_cam.near_z = Q16_16::from_raw(0);
  EXPECT_EQ(r.render(bad_cam, empty, 0, sink, nullptr), Status::invalid_argument);
  bad_cam = cam;
  bad_cam.far_z = Q16_16::from_raw(cam.near_z.raw() * 5000);
  EXPECT_EQ(r.render(bad_cam, empty, 0, sink, nullptr), Status::invalid_argument);

  Vec3<Q16_16> pos[3] = {};
  uint16_t idx[3] = {0, 1, 3};
  Mesh m;
  m.indices = idx;
  m.num_triangles = 1;
  DrawList list{pos, 3, &m, 1};
  EXPECT_EQ(r.render(cam, list, 0, sink, nullptr), Status::malformed);  // index 3 >= 3
  idx[2] = 2;
  EXPECT_EQ(r.render(cam, list, 0, sink, nullptr), Status::ok);
  // Positions from one source, and a grid shift that keeps them in 32 bits.
  const uint16_t grid[9] = {};
  DrawList both = list;
  both.grid = grid;
  EXPECT_EQ(r.render(cam, both, 0, sink, nullptr), Status::invalid_argument);
  DrawList by_grid = both;
  by_grid.positions = nullptr;
  by_grid.grid_shift = 15;
  EXPECT_EQ(r.render(cam, by_grid, 0, sink, nullptr), Status::ok);
  by_grid.grid_shift = 16;
  EXPECT_EQ(r.render(cam, by_grid, 0, sink, nullptr), Status::invalid_argument);
  by_grid.grid_shift = 0;
  by_grid.grid = nullptr;
  EXPECT_EQ(r.render(cam, by_grid, 0, sink, nullptr), Status::invalid_argument);  // neither
  m.shading = Shading::texture;
  EXPECT_EQ(r.render(cam, list, 0, sink, nullptr), Status::malformed);  // no uvs, no texture
  TexCoord uv[3] = {};
  m.uvs = uv;
  uint16_t texel = 0;
  Texture t;
  t.width = 1;
  t.height = 1;
  t.stride = 1;
  t.texels = &texel;
  m.texture = &t;
  EXPECT_EQ(r.render(cam, list, 0, sink, nullptr), Status::ok);
  t.stride = 0;
  EXPECT_EQ(r.render(cam, list, 0, sink, nullptr), Status::invalid_argument);
  t.stride = 1;
  t.apron = true;  // needs stride >= 2
  EXPECT_EQ(r.render(cam, list, 0, sink, nullptr), Status::invalid_argument);
  EXPECT_EQ(texture_fill_apron(t, &texel), Status::invalid_argument);
  t.apron = false;
  m.shading = static_cast<Shading>(9);
  EXPECT_EQ(r.render(cam, list, 0, sink, nullptr), Status::invalid_argument);
}

TEST(RenderApi, ApronAndPlainTexturesGiveTheSameFrame) {
  for (const Scene& base : {ref::make_cube_scene(), ref::make_golden_scene()}) {
    for (TexFormat tf : {TexFormat::rgb565, TexFormat::xrgb8888}) {
      const ClientScene with(base, tf, true), without(base, tf, false);
      for (PixelFormat of : {PixelFormat::rgb565, PixelFormat::rgb888}) {
        ClientRenderSettings st;
        st.format = of;
        const ClientFrame a = ref::render_client(with, 240, 180, st);
        const ClientFrame b = ref::render_client(without, 240, 180, st);
        ASSERT_EQ(a.status, Status::ok);
        EXPECT_EQ(a.bytes, b.bytes) << base.name << " " << tex_name(tf);
      }
    }
  }
}

// A mesh whose triangles ask a ViewMapSource for their view and
// homography draws what one mesh per triangle with its own texture and
// view_map draws, whatever the caches; a triangle the source refuses, or
// given a view of another form than the mesh's texture, is not drawn.
TEST(RenderApi, AViewPerTriangleFromASourceDrawsWhatAMeshPerTriangleDraws) {
  const ClientScene cs(view_mapped_cube(), TexFormat::rgb565);
  const DrawList& base = cs.list();
  // Every view-mapped triangle, one mesh each, and their indices as one mesh.
  struct Tri {
    const Mesh* from;
    uint32_t t;
  };
  std::vector<Tri> tris;
  std::vector<uint16_t> idx;
  for (uint32_t mi = 0; mi < base.num_meshes; ++mi) {
    const Mesh& m = base.meshes[mi];
    if (m.shading != Shading::view_mapped) continue;
    for (uint32_t t = 0; t < m.num_triangles; ++t) {
      tris.push_back({&m, t});
      idx.insert(idx.end(), m.indices + 3 * t, m.indices + 3 * t + 3);
    }
  }
  ASSERT_GE(tris.size(), 8u);
  const Texture* form = tris[0].from->texture;
  Texture other_form = *form;
  other_form.stride += 2;  // the same texels, another stride: not the mesh's form
  struct Source {
    const std::vector<Tri>* tris;
    const Texture* other_form;
    int refuse = 0;  // 1: odd triangles refused; 2: odd triangles given a view of another form
    static bool map(void* ctx, uint32_t t, uint32_t, const Texture** tex, Homography* out) {
      const Source& s = *static_cast<const Source*>(ctx);
      if (s.refuse == 1 && t % 2 == 1) return false;
      const Mesh& m = *(*s.tris)[t].from;
      *tex = s.refuse == 2 && t % 2 == 1 ? s.other_form : m.texture;
      *out = m.view_map;
      return true;
    }
  };
  Status status = Status::ok;  // of the last render
  const auto render = [&](const std::vector<Mesh>& meshes, uint32_t vertex_cache, uint32_t triangle_cache) {
    RenderConfig cfg;
    cfg.width = 240;
    cfg.height = 180;
    cfg.band_height = 16;
    cfg.format = PixelFormat::rgb565;
    cfg.vertex_cache = vertex_cache;
    cfg.triangle_cache = triangle_cache;
    cfg.setup_cache = 4;
    std::vector<uint8_t> ws(render_workspace_size(cfg));
    Arena arena(ws.data(), ws.size());
    Renderer r;
    EXPECT_EQ(r.init(cfg, arena), Status::ok);
    std::vector<uint8_t> out;
    const DrawList list{base.positions, base.num_positions, meshes.data(), static_cast<uint32_t>(meshes.size())};
    const auto put = [](void* ctx, const Band& b) {
      auto* o = static_cast<std::vector<uint8_t>*>(ctx);
      for (int y = 0; y < b.height; ++y) o->insert(o->end(), b.pixels + y * b.stride, b.pixels + y * b.stride + b.width * 2);
      return true;
    };
    status = r.render(cs.camera(), list, 0x203040, put, &out);
    return out;
  };
  // One mesh per triangle, the odd ones drawn or left empty.
  const auto per_triangle = [&](bool odd_too) {
    std::vector<Mesh> meshes;
    for (size_t i = 0; i < tris.size(); ++i) {
      Mesh m = *tris[i].from;
      m.indices = &idx[3 * i];
      m.num_triangles = odd_too || i % 2 == 0 ? 1 : 0;
      meshes.push_back(m);
    }
    return meshes;
  };
  Source src{&tris, &other_form};
  const ViewMapSource source{&Source::map, &src};
  Mesh one = *tris[0].from;
  one.indices = idx.data();
  one.num_triangles = static_cast<uint32_t>(tris.size());
  one.views = &source;
  // Vertex caches of every position, of a few (the rest projected where
  // needed) and of none; triangle caches of all, some and none.
  const std::vector<uint8_t> all = render(per_triangle(true), 65536, 65536);
  const std::vector<uint8_t> even = render(per_triangle(false), 65536, 65536);
  ASSERT_EQ(status, Status::ok);
  ASSERT_NE(all, even) << "the odd triangles show";
  for (const auto& [vc, tc] : {std::pair{65536u, 65536u}, std::pair{5u, 65536u}, std::pair{5u, 3u}, std::pair{0u, 0u}}) {
    src.refuse = 0;
    EXPECT_EQ(render({one}, vc, tc), all) << "vertex cache " << vc << ", triangle cache " << tc;
    EXPECT_EQ(status, Status::ok);
    src.refuse = 1;
    EXPECT_EQ(render({one}, vc, tc), even) << "vertex cache " << vc << ", triangle cache " << tc;
    src.refuse = 2;
    EXPECT_EQ(render({one}, vc, tc), even) << "vertex cache " << vc << ", triangle cache " << tc;
  }
  // A source without its function is refused.
  const ViewMapSource none{};
  one.views = &none;
  render({one}, 0, 0);
  EXPECT_EQ(status, Status::malformed);
}

// The RGB565 frame a renderer of `cfg` (its own workspace) draws of
// `list`, its status in *st and, if asked, its statistics in *stats.
std::vector<uint16_t> render_rgb565(const RenderConfig& cfg, const Camera& cam, const DrawList& list, Status* st,
                                    RenderStats* stats = nullptr) {
  std::vector<uint8_t> ws(render_workspace_size(cfg));
  Arena arena(ws.data(), ws.size());
  Renderer r;
  EXPECT_EQ(r.init(cfg, arena), Status::ok);
  std::vector<uint16_t> frame;
  *st = r.render(
      cam, list, 0,
      [](void* ctx, const Band& b) {
        auto* f = static_cast<std::vector<uint16_t>*>(ctx);
        for (int y = 0; y < b.height; ++y) {
          const auto* row = reinterpret_cast<const uint16_t*>(b.pixels + y * b.stride);
          f->insert(f->end(), row, row + b.width);
        }
        return true;
      },
      &frame);
  if (stats) *stats = r.stats();
  return frame;
}

// RenderConfig::point_face_span's scene: a plane 4 units in front of a
// 96x72 screen, of small triangles (its left: about 3 pixels a cell) and
// of narrow or flat ones (its right: 3 x 16 and 9 x 3 pixels), and a grey
// Y'CbCr view of the screen's size.
struct SmallFaceScene {
  static constexpr int kW = 96, kH = 72;
  Camera screen = ref::to_client(ref::CameraD::look_at({0, 0, 0}, {0, 0, 1}, {0, 1, 0}, kW, kH, 60, 0.1, 60));
  std::vector<uint8_t> ty = std::vector<uint8_t>(kW * kH), tc = std::vector<uint8_t>((kW / 2) * (kH / 2), 128);
  Texture view;
  std::vector<Vec3<Q16_16>> pos;
  std::vector<TexCoord> uvs;  // each vertex's own pixel position: the texture drawn 1:1
  std::vector<uint16_t> idx;
  SmallFaceScene() {
    std::mt19937 rng(77);
    for (auto& b : ty) b = static_cast<uint8_t>(rng());
    view.format = TexFormat::ycbcr420;
    view.address = TexAddress::clamp;
    view.width = kW;
    view.height = kH;
    view.stride = kW;
    view.texels = ty.data();
    view.cb = view.cr = tc.data();
    view.chroma_stride = kW / 2;
    grid(0, 3.2, -2.4, 2.4, 0.2, 0.2);  // the screen's left (x to the left)
    grid(-1.6, 0, -3, 3, 0.2, 1);
    grid(-4, -1.6, -3, 3, 0.6, 0.2);
  }
  static Q16_16 q(double x) { return Q16_16::from_raw(static_cast<int32_t>(std::lround(x * 65536))); }
  void grid(double x0, double x1, double y0, double y1, double sx, double sy) {
    const int nx = static_cast<int>(std::lround((x1 - x0) / sx)), ny = static_cast<int>(std::lround((y1 - y0) / sy));
    const uint16_t first = static_cast<uint16_t>(pos.size());
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        pos.push_back({q(x0 + i * sx), q(y0 + j * sy), q(4)});
        int32_t px = 0, py = 0;
        EXPECT_TRUE(camera_project(screen, camera_transform(screen, pos.back()), &px, &py));
        uvs.push_back({Q16_16::from_raw(px * 256), Q16_16::from_raw(py * 256)});
      }
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const uint16_t a = static_cast<uint16_t>(first + j * (nx + 1) + i), b = static_cast<uint16_t>(a + 1);
        const uint16_t c = static_cast<uint16_t>(a + nx + 1), d = static_cast<uint16_t>(c + 1);
        idx.insert(idx.end(), {a, b, c, b, d, c});
      }
  }
  Mesh mesh(Shading shading, const ViewMapSource* views) const {
    Mesh m;
    m.shading = shading;
    m.filter = Filter::nearest;
    m.cull = Cull::none;
    m.texture = &view;
    m.views = views;
    m.uvs = uvs.data();
    m.indices = idx.data();
    m.num_triangles = static_cast<uint32_t>(idx.size() / 3);
    return m;
  }
  std::vector<uint16_t> frame(const Mesh& m, uint8_t span) const {
    RenderConfig cfg;
    cfg.width = kW;
    cfg.height = kH;
    cfg.band_height = 16;
    cfg.setup_cache = 8;
    cfg.vertex_cache = 4096;
    cfg.point_face_span = span;
    Status st = Status::ok;
    std::vector<uint16_t> f = render_rgb565(cfg, screen, DrawList{pos.data(), static_cast<uint32_t>(pos.size()), &m, 1}, &st);
    EXPECT_EQ(st, Status::ok);
    return f;
  }
  // Every pixel of the screen's left half (the small faces) is c.
  static bool uniform_left(const std::vector<uint16_t>& f, uint16_t c) {
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW / 2 - 2; ++x)
        if (f[static_cast<size_t>(y * kW + x)] != c) return false;
    return true;
  }
  static bool same_right(const std::vector<uint16_t>& a, const std::vector<uint16_t>& b) {
    for (int y = 0; y < kH; ++y)
      for (int x = kW / 2 + 1; x < kW; ++x)
        if (a[static_cast<size_t>(y * kW + x)] != b[static_cast<size_t>(y * kW + x)]) return false;
    return true;
  }
};

// RenderConfig::point_face_span: view-mapped faces spanning at most that
// many pixel columns and rows are drawn in one colour, the view's sample at
// the point ViewMapSource::point gives (clamped to the view); larger faces,
// faces whose point is refused and renderers without the span draw as
// before. The view is the screen's own (the homography the identity).
TEST(RenderApi, SmallViewMappedFacesAreDrawnInTheColourOfTheirPoint) {
  const SmallFaceScene sc;
  constexpr int kW = SmallFaceScene::kW, kH = SmallFaceScene::kH;
  Homography identity;
  const Vec3<Q16_16> plane[3] = {{sc.q(0), sc.q(0), sc.q(4)}, {sc.q(1), sc.q(0), sc.q(4)}, {sc.q(0), sc.q(1), sc.q(4)}};
  ASSERT_EQ(plane_homography(sc.screen, sc.screen, plane, &identity), Status::ok);
  struct Source {
    const Texture* view;
    Homography h;
    int32_t u, v;
    bool refuse;
    static bool map(void* ctx, uint32_t, uint32_t, const Texture** tex, Homography* out) {
      const Source& s = *static_cast<const Source*>(ctx);
      *tex = s.view;
      *out = s.h;
      return true;
    }
    static bool point(void* ctx, uint32_t, uint32_t, const Texture** tex, int32_t* u, int32_t* v) {
      const Source& s = *static_cast<const Source*>(ctx);
      if (s.refuse) return false;
      *tex = s.view;
      *u = s.u;
      *v = s.v;
      return true;
    }
  };
  Source src{&sc.view, identity, 10 * 256 + 128, 20 * 256 + 128, false};
  const ViewMapSource source{&Source::map, &src, &Source::point};
  const Mesh m = sc.mesh(Shading::view_mapped, &source);
  const std::vector<uint16_t> mapped = sc.frame(m, 0);
  ASSERT_EQ(mapped.size(), size_t{kW * kH});
  // The identity map shows texel (10, 20) at pixel (10, 20): the point's colour.
  const uint16_t colour = mapped[20 * kW + 10];
  ASSERT_FALSE(SmallFaceScene::uniform_left(mapped, colour)) << "the view's texels show";
  const std::vector<uint16_t> small = sc.frame(m, 6);
  EXPECT_TRUE(SmallFaceScene::uniform_left(small, colour));
  EXPECT_TRUE(SmallFaceScene::same_right(small, mapped));
  // Every face at a span of 255; none where the point is refused.
  const std::vector<uint16_t> all = sc.frame(m, 255);
  EXPECT_TRUE(std::all_of(all.begin(), all.end(), [&](uint16_t c) { return c == colour; }));
  src.refuse = true;
  EXPECT_EQ(sc.frame(m, 6), mapped);
  // A point far outside the view takes its nearest edge texel (column 0, row 71).
  src = Source{&sc.view, identity, -5000 * 256, 99999 * 256, false};
  EXPECT_TRUE(SmallFaceScene::uniform_left(sc.frame(m, 6), mapped[(kH - 1) * kW + 0]));
}

// The same for textured faces: a small face takes the texel at the mean of
// its corners' texture coordinates. The texture drawn 1:1 shows each small
// face's texel at the face's centre pixel, so each small face is one
// colour, the mapped frame's at its centre; the right half is as before.
TEST(RenderApi, SmallTexturedFacesAreDrawnInTheColourOfTheirCentre) {
  const SmallFaceScene sc;
  constexpr int kW = SmallFaceScene::kW;
  const Mesh m = sc.mesh(Shading::texture, nullptr);
  const std::vector<uint16_t> mapped = sc.frame(m, 0), small = sc.frame(m, 6);
  EXPECT_TRUE(SmallFaceScene::same_right(small, mapped));
  // Each small triangle of the left half (the first grid's 16 x 24 cells).
  int faces = 0, checked = 0;
  for (size_t t = 0; t < 2 * 16 * 24; ++t) {
    int64_t su = 0, sv = 0;
    for (int k = 0; k < 3; ++k) su += sc.uvs[sc.idx[3 * t + k]].u.raw(), sv += sc.uvs[sc.idx[3 * t + k]].v.raw();
    const int cu = static_cast<int>((su / 3) >> 16), cv = static_cast<int>((sv / 3) >> 16);
    if (cu < 0 || cu >= kW / 2 - 2 || cv < 0 || cv >= SmallFaceScene::kH) continue;
    const uint16_t colour = mapped[static_cast<size_t>(cv * kW + cu)];
    // The pixels whose centres lie inside the triangle (screen positions = its uvs).
    const auto at = [&](int k) { return std::pair<double, double>{sc.uvs[sc.idx[3 * t + k]].u.raw() / 65536.0, sc.uvs[sc.idx[3 * t + k]].v.raw() / 65536.0}; };
    const auto [ax, ay] = at(0);
    const auto [bx, by] = at(1);
    const auto [qx, qy] = at(2);
    const auto side = [](double x0, double y0, double x1, double y1, double x, double y) { return (x1 - x0) * (y - y0) - (y1 - y0) * (x - x0); };
    ++faces;
    for (int y = 0; y < SmallFaceScene::kH; ++y)
      for (int x = 0; x < kW / 2 - 2; ++x) {
        const double px = x + 0.5, py = y + 0.5, e = 1e-3;
        const double s0 = side(ax, ay, bx, by, px, py), s1 = side(bx, by, qx, qy, px, py), s2 = side(qx, qy, ax, ay, px, py);
        if ((s0 > e && s1 > e && s2 > e) || (s0 < -e && s1 < -e && s2 < -e)) {
          ASSERT_EQ(small[static_cast<size_t>(y * kW + x)], colour) << "face " << t << " pixel " << x << "," << y;
          ++checked;
        }
      }
  }
  EXPECT_GT(faces, 600);
  EXPECT_GT(checked, 1000);
  EXPECT_NE(mapped, small);
}

// Grid positions ((g << grid_shift) + grid_origin) draw exactly what the
// same positions as Q16.16 vectors draw, with and without the vertex cache.
TEST(RenderApi, GridPositionsDrawWhatTheirWorldPositionsDraw) {
  constexpr int kSide = 17;
  std::vector<uint16_t> grid;
  std::vector<uint32_t> colors;
  std::mt19937 rng(7);
  for (int j = 0; j < kSide; ++j)
    for (int i = 0; i < kSide; ++i) {
      grid.push_back(static_cast<uint16_t>(i * 240));                 // x
      grid.push_back(static_cast<uint16_t>(1500 + rng() % 1100));      // y: a rough height field
      grid.push_back(static_cast<uint16_t>(j * 240));                 // z
      colors.push_back(rng() & 0xFFFFFF);
    }
  std::vector<uint16_t> idx;
  for (int j = 0; j + 1 < kSide; ++j)
    for (int i = 0; i + 1 < kSide; ++i) {
      const uint16_t a = static_cast<uint16_t>(j * kSide + i), b = static_cast<uint16_t>(a + 1),
                     c = static_cast<uint16_t>(a + kSide), d = static_cast<uint16_t>(c + 1);
      idx.insert(idx.end(), {a, c, b, b, c, d});
    }
  Mesh m;
  m.indices = idx.data();
  m.num_triangles = static_cast<uint32_t>(idx.size() / 3);
  m.shading = Shading::gouraud;
  m.cull = Cull::none;
  m.colors = colors.data();
  const Camera cam = ref::to_client(ref::CameraD::look_at({0, 1.6, -1.8}, {0, 0, 0}, {0, 1, 0}, 96, 72, 60, 0.1, 20));
  for (const uint8_t shift : {uint8_t{5}, uint8_t{6}}) {
    const Vec3<Q16_16> origin{Q16_16::from_raw(-(2048 << shift)), Q16_16::from_raw(-(2048 << shift)),
                              Q16_16::from_raw(-(2048 << shift))};
    std::vector<Vec3<Q16_16>> world;
    for (size_t v = 0; v < grid.size() / 3; ++v)
      world.push_back({Q16_16::from_raw((grid[3 * v] << shift) + origin.x.raw()),
                       Q16_16::from_raw((grid[3 * v + 1] << shift) + origin.y.raw()),
                       Q16_16::from_raw((grid[3 * v + 2] << shift) + origin.z.raw())});
    DrawList by_world{world.data(), static_cast<uint32_t>(world.size()), &m, 1};
    DrawList by_grid{nullptr, static_cast<uint32_t>(world.size()), &m, 1};
    by_grid.grid = grid.data();
    by_grid.grid_shift = shift;
    by_grid.grid_origin = origin;
    for (uint32_t cache : {0u, 1000u}) {
      RenderConfig cfg;
      cfg.width = 96;
      cfg.height = 72;
      cfg.band_height = 8;
      cfg.vertex_cache = cache;
      cfg.triangle_cache = cache;
      auto draw = [&](const DrawList& list) {
        Status st = Status::ok;
        std::vector<uint16_t> frame = render_rgb565(cfg, cam, list, &st);
        EXPECT_EQ(st, Status::ok);
        return frame;
      };
      const std::vector<uint16_t> a = draw(by_world), b = draw(by_grid);
      ASSERT_EQ(a.size(), 96u * 72u);
      EXPECT_EQ(a, b) << "shift " << int{shift} << " cache " << cache;
      EXPECT_GT(std::count_if(a.begin(), a.end(), [](uint16_t p) { return p != 0; }), 96 * 72 / 8)
          << "the surface should cover much of the frame";
    }
  }
}

// A mesh of convex planar quads (Mesh::corners) covers exactly the pixels
// the same quads split into triangle pairs cover, in any cache
// configuration and either winding, also where the near plane cuts them
// (clipped apart, a pair gains a corner on the cut: a pixel there may
// fall the other way; none did here, a few are allowed). A face count
// out of range is refused, and so are quads with mesh colors.
TEST(RenderApi, QuadFacesCoverWhatTheirTrianglePairsCover) {
  constexpr int kSide = 13;
  std::vector<Vec3<Q16_16>> pos;
  for (int j = 0; j < kSide; ++j)
    for (int i = 0; i < kSide; ++i) {
      const auto q = [](double x) { return Q16_16::from_raw(static_cast<int32_t>(std::lround(x * 65536))); };
      pos.push_back({q(i * 0.37 - 2.2), q(0.0), q(j * 0.41 - 2.4)});
    }
  // A checkerboard: two flat meshes, quads and the same as triangle pairs.
  std::vector<uint16_t> quads[2], pairs[2];
  for (int j = 0; j + 1 < kSide; ++j)
    for (int i = 0; i + 1 < kSide; ++i) {
      const uint16_t a = static_cast<uint16_t>(j * kSide + i), b = static_cast<uint16_t>(a + 1),
                     c = static_cast<uint16_t>(a + kSide), d = static_cast<uint16_t>(c + 1);
      const int k = (i + j) % 2;
      if ((i * 7 + j * 3) % 4 == 0) {
        quads[k].insert(quads[k].end(), {b, a, c, d});  // the other winding, from another corner
      } else {
        quads[k].insert(quads[k].end(), {a, b, d, c});
      }
      pairs[k].insert(pairs[k].end(), {a, b, d, a, d, c});
    }
  std::vector<uint8_t> fours(quads[0].size() / 4 + quads[1].size() / 4, 4);
  const auto mesh = [&](const std::vector<uint16_t>& idx, bool as_quads, uint32_t color) {
    Mesh m;
    m.indices = idx.data();
    m.num_triangles = static_cast<uint32_t>(idx.size() / (as_quads ? 4 : 3));
    m.corners = as_quads ? fours.data() : nullptr;
    m.shading = Shading::flat;
    m.cull = Cull::none;
    m.color = color;
    return m;
  };
  const Mesh q[2] = {mesh(quads[0], true, 0xE0A020), mesh(quads[1], true, 0x2040C0)};
  const Mesh t[2] = {mesh(pairs[0], false, 0xE0A020), mesh(pairs[1], false, 0x2040C0)};
  const DrawList by_quads{pos.data(), static_cast<uint32_t>(pos.size()), q, 2};
  const DrawList by_pairs{pos.data(), static_cast<uint32_t>(pos.size()), t, 2};
  RenderStats stats;  // of the last frame drawn
  const auto draw = [&](const Camera& cam, const DrawList& list, uint32_t vc, uint32_t tc, uint32_t sc, Status* st) {
    RenderConfig cfg;
    cfg.width = 96;
    cfg.height = 72;
    cfg.band_height = 8;
    cfg.vertex_cache = vc;
    cfg.triangle_cache = tc;
    cfg.setup_cache = sc;
    return render_rgb565(cfg, cam, list, st, &stats);
  };
  Status st = Status::ok;
  const Camera above = ref::to_client(ref::CameraD::look_at({0.3, 3.2, -2.9}, {0, 0, 0.2}, {0, 1, 0}, 96, 72, 60, 0.1, 20));
  const Camera inside = ref::to_client(ref::CameraD::look_at({0.1, 0.5, -1.0}, {0.4, 0, 1.5}, {0, 1, 0}, 96, 72, 70, 0.3, 20));
  for (const Camera* cam : {&above, &inside}) {
    const std::vector<uint16_t> want = draw(*cam, by_pairs, 1000, 1000, 8, &st);
    ASSERT_EQ(st, Status::ok);
    if (cam == &inside) EXPECT_GT(stats.clipped, 4u) << "the near plane cuts quads";
    EXPECT_GT(std::count_if(want.begin(), want.end(), [](uint16_t p) { return p != 0; }), 96 * 72 / 3);
    for (const auto& [vc, tc, sc] : {std::tuple{1000u, 1000u, 8u}, std::tuple{40u, 1000u, 2u}, std::tuple{40u, 30u, 0u},
                                     std::tuple{0u, 0u, 0u}, std::tuple{1000u, 1000u, 200u}}) {
      const std::vector<uint16_t> got = draw(*cam, by_quads, vc, tc, sc, &st);
      ASSERT_EQ(st, Status::ok);
      ASSERT_EQ(got.size(), want.size());
      size_t differ = 0;
      for (size_t i = 0; i < got.size(); ++i) differ += got[i] != want[i];
      if (cam == &above) {
        EXPECT_EQ(differ, 0u) << "caches " << vc << " " << tc << " " << sc;
      } else {
        EXPECT_LE(differ, 12u) << "caches " << vc << " " << tc << " " << sc;
      }
    }
  }
  fours[3] = 5;
  draw(above, by_quads, 0, 0, 0, &st);
  EXPECT_EQ(st, Status::malformed);
  fours[3] = 4;
  Mesh colours = q[0];
  colours.shading = Shading::mesh_colors;
  const DrawList mc{pos.data(), static_cast<uint32_t>(pos.size()), &colours, 1};
  draw(above, mc, 0, 0, 0, &st);
  EXPECT_NE(st, Status::ok) << "mesh colors take triangles only";
}

TEST(RenderApi, BandRenderingOf240x180In16LineBandsFitsIn16KiB) {
  RenderConfig cfg;
  cfg.width = 240;
  cfg.height = 180;
  cfg.band_height = 16;
  cfg.format = PixelFormat::rgb565;
  cfg.depth = DepthFormat::d16;
  cfg.vertex_cache = 0;
  const size_t total = render_workspace_size(cfg) + sizeof(Renderer);
  EXPECT_LE(total, 16384u) << "workspace " << render_workspace_size(cfg) << " + Renderer " << sizeof(Renderer);
  // And it really renders in exactly that much workspace.
  std::vector<uint8_t> ws(render_workspace_size(cfg));
  Arena a(ws.data(), ws.size());
  Renderer r;
  ASSERT_EQ(r.init(cfg, a), Status::ok);
  const ClientScene cs(ref::make_room_scene(), TexFormat::rgb565);
  EXPECT_EQ(r.render(cs.camera(), cs.list(), 0, [](void*, const Band&) { return true; }, nullptr), Status::ok);
}

// ---------------------------------------------------------------------------
// Golden checksums: the golden scene is built with exact arithmetic only, so
// these values hold for every correct build; the Cortex-M4 run
// (bench/run_render.sh) must reproduce them. Changing the renderer's
// arithmetic changes them on purpose: update them in the same change.
// ---------------------------------------------------------------------------
TEST(RenderGolden, FrameChecksums) {
  const Scene sc = ref::make_golden_scene();
  struct G {
    TexFormat tex;
    PixelFormat out;
    DepthFormat depth;
    int band;
    uint32_t crc;
  };
  const G golden[] = {
      {TexFormat::rgb565, PixelFormat::rgb565, DepthFormat::d16, 16, 0xb5279ebbu},
      {TexFormat::xrgb8888, PixelFormat::rgb888, DepthFormat::d32, 180, 0x8c8f9113u},
      {TexFormat::ycbcr420, PixelFormat::rgb888, DepthFormat::d16, 7, 0x53e772aau},
  };
  for (const G& g : golden) {
    const ClientScene cs(ref::client_textures(sc, g.tex), g.tex);
    ClientRenderSettings st;
    st.format = g.out;
    st.depth = g.depth;
    st.band_height = g.band;
    const ClientFrame fr = ref::render_client(cs, sc.width, sc.height, st);
    ASSERT_EQ(fr.status, Status::ok);
    EXPECT_EQ(crc32c(fr.bytes.data(), fr.bytes.size()), g.crc) << tex_name(g.tex) << std::hex;
  }
}

}  // namespace
}  // namespace vds
