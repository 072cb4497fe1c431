// The renderer's mesh-colors shading (Shading::mesh_colors, vds/render.h):
// a triangle facing the camera, whose barycentric coordinates are affine in
// the screen, drawn with random samples on its lattice, against the mesh
// colors filters evaluated in double at every pixel centre; faces whose
// indices leave the planes are not drawn; a model's mesh colors address
// their samples as the codec lays them out.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "vds/enc/mesh_colors.h"
#include "vds/mesh_colors.h"
#include "vds/ref/render.h"
#include "vds/ref/scene.h"
#include "vds/render.h"

namespace vds {
namespace {

constexpr int kW = 96, kH = 72;

// One face of resolution 2^r with every sample its own: vertices 0..2, the
// edges' R - 1 samples each (edge 1 stored from its far end, to test the
// reversed direction), then the face's rows.
struct OneFace {
  int r;
  uint32_t R;
  std::array<std::vector<uint8_t>, 3> planes;
  LatticeFace face{};
  uint32_t index(uint32_t i, uint32_t j) const {  // the layout above, written out
    if (j == 0 && i == 0) return 0;
    if (j == 0 && i == R) return 1;
    if (i == 0 && j == R) return 2;
    if (j == 0) return 3 + (i - 1);
    if (i + j == R) return 3 + (R - 1) + (R - 1 - j);
    if (i == 0) return 3 + 2 * (R - 1) + (R - j - 1);
    uint32_t at = 3 + 3 * (R - 1);
    for (uint32_t row = 1; row < j; ++row) at += R - 1 - row;
    return at + i - 1;
  }
};

OneFace make_face(int r, uint32_t seed) {
  OneFace f;
  f.r = r;
  f.R = 1u << r;
  const uint32_t total = 3 + 3 * (f.R - 1) + (f.R > 2 ? (f.R - 1) * (f.R - 2) / 2 : 0);
  std::mt19937 rng(seed);
  for (auto& p : f.planes) {
    p.resize(total);
    for (auto& v : p) v = static_cast<uint8_t>(rng() % 256);
  }
  f.face.res_log2 = static_cast<uint8_t>(r);
  f.face.vertex[0] = 0;
  f.face.vertex[1] = 1;
  f.face.vertex[2] = 2;
  // edge k at step p from corner k: 0 forward, 1 reversed, 2 forward.
  f.face.edge_base[0] = 3 - 1;
  f.face.edge_step[0] = 1;
  f.face.edge_base[1] = 3 + (f.R - 1) - 1 + f.R;
  f.face.edge_step[1] = -1;
  f.face.edge_base[2] = 3 + 2 * (f.R - 1) - 1;
  f.face.edge_step[2] = 1;
  f.face.face_base = 3 + 3 * (f.R - 1);
  return f;
}

// The mesh colors filters in double at lattice coordinates (u, v) (i, j units).
std::array<double, 3> filter(const OneFace& f, double u, double v, bool nearest) {
  const double R = f.R;
  u = std::max(0.0, u);
  v = std::max(0.0, v);
  if (u + v > R) {
    const double e = u + v - R;
    u -= e / 2;
    v -= e / 2;
  }
  std::array<double, 3> out{};
  if (nearest) {
    uint32_t i = static_cast<uint32_t>(std::lround(u)), j = static_cast<uint32_t>(std::lround(v));
    while (i + j > f.R) (i >= j ? i : j) -= 1;
    for (int c = 0; c < 3; ++c) out[c] = f.planes[c][f.index(i, j)];
    return out;
  }
  double i0 = std::floor(u), j0 = std::floor(v);
  if (i0 + j0 >= R) i0 > 0 ? i0 -= 1 : j0 -= 1;
  const double fu = u - i0, fv = v - j0;
  const uint32_t a = static_cast<uint32_t>(i0), b = static_cast<uint32_t>(j0);
  for (int c = 0; c < 3; ++c) {
    const auto& p = f.planes[c];
    out[c] = fu + fv <= 1 ? (1 - fu - fv) * p[f.index(a, b)] + fu * p[f.index(a + 1, b)] + fv * p[f.index(a, b + 1)]
                          : (fu + fv - 1) * p[f.index(a + 1, b + 1)] + (1 - fu) * p[f.index(a, b + 1)] +
                                (1 - fv) * p[f.index(a + 1, b)];
  }
  return out;
}

std::array<double, 3> to_rgb(const std::array<double, 3>& ycc) {
  const double y = ycc[0], cb = ycc[1] - 128, cr = ycc[2] - 128;
  return {y + 1.402 * cr, y - 0.344136 * cb - 0.714136 * cr, y + 1.772 * cb};
}

struct Drawn {
  std::vector<uint8_t> rgb;  // kW x kH x 3
  Status status;
};

Drawn draw(const OneFace& f, const std::array<ref::Vec3d, 3>& corners, const ref::CameraD& cam, Filter filt,
           bool valid = true) {
  std::vector<Vec3<Q16_16>> pos;
  for (const auto& p : corners)
    pos.push_back({Q16_16::from_raw(static_cast<int32_t>(std::lround(p.x * 65536))), Q16_16::from_raw(static_cast<int32_t>(std::lround(p.y * 65536))), Q16_16::from_raw(static_cast<int32_t>(std::lround(p.z * 65536)))});
  const uint16_t idx[3] = {0, 1, 2};
  struct Ctx {
    LatticeFace face;
  } ctx{f.face};
  if (!valid) ctx.face.face_base = 1u << 30;
  MeshColorsSurface s;
  s.y = f.planes[0].data();
  s.cb = f.planes[1].data();
  s.cr = f.planes[2].data();
  s.samples = static_cast<uint32_t>(f.planes[0].size());
  s.face = [](const void* c, uint32_t t, LatticeFace* out) {
    *out = static_cast<const Ctx*>(c)->face;
    return t == 0;
  };
  s.ctx = &ctx;
  Mesh m;
  m.indices = idx;
  m.num_triangles = 1;
  m.shading = Shading::mesh_colors;
  m.filter = filt;
  m.cull = Cull::none;
  m.surface = &s;
  DrawList list{pos.data(), 3, &m, 1};
  RenderConfig cfg;
  cfg.width = kW;
  cfg.height = kH;
  cfg.band_height = 8;
  cfg.format = PixelFormat::rgb888;
  std::vector<uint8_t> ws(render_workspace_size(cfg));
  Arena arena(ws.data(), ws.size());
  Renderer r;
  Drawn d;
  EXPECT_EQ(r.init(cfg, arena), Status::ok);
  d.status = r.render(
      ref::to_client(cam), list, 0,
      [](void* c, const Band& b) {
        auto* out = static_cast<std::vector<uint8_t>*>(c);
        for (int y = 0; y < b.height; ++y) out->insert(out->end(), b.pixels + y * b.stride, b.pixels + y * b.stride + 3 * b.width);
        return true;
      },
      &d.rgb);
  return d;
}

TEST(RenderMeshColors, NearestAndLinearFiltersMatchTheLatticeInDouble) {
  const ref::CameraD cam = ref::CameraD::look_at({0, 0, 0}, {0, 0, 1}, {0, 1, 0}, kW, kH, 60, 0.1, 20);
  const std::array<ref::Vec3d, 3> corners{ref::Vec3d{-1.2, -0.8, 2}, ref::Vec3d{1.1, -0.9, 2}, ref::Vec3d{-0.3, 0.95, 2}};
  double sx[3], sy[3];
  for (int k = 0; k < 3; ++k) ASSERT_TRUE(ref::project(cam, corners[k], &sx[k], &sy[k]));
  const double det = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sx[2] - sx[0]) * (sy[1] - sy[0]);
  for (int r : {0, 1, 2, 3, 5}) {
    const OneFace f = make_face(r, 11 + r);
    for (Filter filt : {Filter::nearest, Filter::bilinear}) {
      const Drawn d = draw(f, corners, cam, filt);
      ASSERT_EQ(d.status, Status::ok);
      ASSERT_EQ(d.rgb.size(), size_t{3} * kW * kH);
      int inside = 0, off = 0;
      double worst = 0, sum = 0;
      for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
          const double px = x + 0.5, py = y + 0.5;
          const double b1 = ((px - sx[0]) * (sy[2] - sy[0]) - (sx[2] - sx[0]) * (py - sy[0])) / det;
          const double b2 = ((sx[1] - sx[0]) * (py - sy[0]) - (px - sx[0]) * (sy[1] - sy[0])) / det;
          // Pixels well inside: away from the edges by a pixel's reach in lattice units.
          const double margin = 0.02;
          if (b1 < margin || b2 < margin || b1 + b2 > 1 - margin) continue;
          ++inside;
          const auto rgb = to_rgb(filter(f, b1 * f.R, b2 * f.R, filt == Filter::nearest));
          const uint8_t* p = d.rgb.data() + 3 * (y * kW + x);
          double e = 0;
          for (int c = 0; c < 3; ++c) e = std::max(e, std::fabs(std::clamp(rgb[c], 0.0, 255.0) - p[c]));
          worst = std::max(worst, e);
          sum += e;
          // Nearest: a pixel centre within rounding of a Voronoi border may pick the neighbour.
          if (e > 3) ++off;
        }
      EXPECT_GT(inside, kW * kH / 5) << "r " << r;
      if (filt == Filter::nearest)
        EXPECT_LE(off, inside / 50 + 2) << "r " << r << " nearest: pixels off by more than 3 levels";
      else {
        // Samples rounded to 8 bits in Y', Cb, Cr before the conversion
        // (about 1 level in G), 8-bit weights, on random samples that
        // change by up to 255 levels from one lattice point to the next.
        EXPECT_LE(worst, 6.0) << "r " << r << " linear";
        EXPECT_LE(sum / inside, 1.5) << "r " << r << " linear: mean of the largest channel error";  // measured 0.8-1.1
      }
    }
  }
}

TEST(RenderMeshColors, AFaceWhoseIndicesLeaveThePlanesIsNotDrawn) {
  const ref::CameraD cam = ref::CameraD::look_at({0, 0, 0}, {0, 0, 1}, {0, 1, 0}, kW, kH, 60, 0.1, 20);
  const std::array<ref::Vec3d, 3> corners{ref::Vec3d{-1.2, -0.8, 2}, ref::Vec3d{1.1, -0.9, 2}, ref::Vec3d{-0.3, 0.95, 2}};
  const OneFace f = make_face(4, 5);
  const Drawn good = draw(f, corners, cam, Filter::bilinear);
  const Drawn bad = draw(f, corners, cam, Filter::bilinear, false);
  ASSERT_EQ(bad.status, Status::ok);
  size_t lit = 0;
  for (uint8_t v : good.rgb) lit += v != 0;
  EXPECT_GT(lit, 1000u);
  for (uint8_t v : bad.rgb) ASSERT_EQ(v, 0);
  // Without a surface the mesh is refused.
  Mesh m;
  const uint16_t idx[3] = {0, 1, 2};
  m.indices = idx;
  m.num_triangles = 1;
  m.shading = Shading::mesh_colors;
  const Vec3<Q16_16> pos[3]{};
  DrawList list{pos, 3, &m, 1};
  RenderConfig cfg;
  cfg.width = 16;
  cfg.height = 16;
  cfg.band_height = 16;
  std::vector<uint8_t> ws(render_workspace_size(cfg));
  Arena arena(ws.data(), ws.size());
  Renderer r;
  ASSERT_EQ(r.init(cfg, arena), Status::ok);
  EXPECT_EQ(r.render(ref::to_client(cam), list, 0, [](void*, const Band&) { return true; }, nullptr), Status::malformed);
}

// A model's mesh colors (the codec's layout) seen through face_lattice:
// every lattice point of every face at every level addresses the sample
// MeshColors::sample_index names.
TEST(RenderMeshColors, FaceLatticeAddressesTheCodecsSamples) {
  enc::TexturedModel t;
  // An octahedron with a random texture: every edge shared, both directions.
  t.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  t.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  enc::Image tex(64, 64, 3);
  std::mt19937 rng(2);
  for (auto& p : tex.pixels) p = static_cast<uint8_t>(rng() % 256);
  t.textures = {tex};
  t.texture_files = {"random"};
  t.materials = {enc::TexturedMaterial{0, {1, 1, 1}}};
  for (size_t f = 0; f < t.triangles.size(); ++f) {
    t.uv.push_back({{{0.1 * f, 0.1}, {0.1 * f + 0.3 + 0.05 * f, 0.2}, {0.1 * f, 0.5 + 0.05 * f}}});
    t.colour.push_back({{{1, 1, 1}, {1, 1, 1}, {1, 1, 1}}});
    t.material.push_back(0);
  }
  const enc::MeshColorsModel m = enc::to_mesh_colors(t);
  ASSERT_GT(m.max_res, 2);
  std::vector<uint8_t> ws(mc::MeshColors::init_bytes(8, 6));
  Arena arena(ws.data(), ws.size());
  mc::MeshColors colours;
  ASSERT_EQ(colours.init(arena, m.triangles.data(), 8, 6), Status::ok);
  ASSERT_EQ(colours.set(m.face_res.data(), m.vertex_ycc.data(), 256, mc::kModeVds), Status::ok);
  for (int level = 0; level <= m.max_res; ++level) {
    const uint32_t total = colours.layout_level(level);
    for (uint32_t f = 0; f < 8; ++f) {
      LatticeFace lf;
      colours.face_lattice(f, &lf);
      const uint32_t R = 1u << lf.res_log2;
      ASSERT_EQ(R, mc::resolution(mc::level_res(m.face_res[f], level)));
      for (uint32_t j = 0; j <= R; ++j)
        for (uint32_t i = 0; i + j <= R; ++i) {
          uint32_t k;
          if (j == 0)
            k = i == 0 ? lf.vertex[0] : (i == R ? lf.vertex[1] : lf.edge_base[0] + i * lf.edge_step[0]);
          else if (i == 0)
            k = j == R ? lf.vertex[2] : lf.edge_base[2] + (R - j) * lf.edge_step[2];
          else if (i + j == R)
            k = lf.edge_base[1] + j * lf.edge_step[1];
          else {
            k = lf.face_base + (i - 1);
            for (uint32_t row = 1; row < j; ++row) k += R - 1 - row;
          }
          ASSERT_EQ(k, colours.sample_index(f, level, i, j)) << "level " << level << " face " << f << " (" << i << ", " << j << ")";
          ASSERT_LT(k, total);
        }
    }
  }
}

}  // namespace
}  // namespace vds
