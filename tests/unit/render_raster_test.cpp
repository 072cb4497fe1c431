// The exact edge walker of the renderer (vds/render_raster.h) and the fill
// rule as the whole renderer applies it: watertightness of abutting
// triangles at random sub-pixel positions and orientations, in screen space
// and through projection and clipping, and the pixel-exact top-left rule.
#include "vds/render_raster.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "vds/ref/scene.h"
#include "vds/render.h"

namespace vds {
namespace {

constexpr int kW = 96, kH = 72;

std::vector<int> coverage(const std::vector<RasterVertex>& verts, const std::vector<int>& tris, int w, int h) {
  std::vector<int> count(static_cast<size_t>(w) * h, 0);
  for (size_t t = 0; t + 2 < tris.size(); t += 3) {
    const RasterVertex v[3] = {verts[tris[t]], verts[tris[t + 1]], verts[tris[t + 2]]};
    raster_triangle(v, 0, h, w, [&](int32_t y, int32_t xa, int32_t xb) {
      EXPECT_GE(y, 0);
      EXPECT_LT(y, h);
      EXPECT_GE(xa, 0);
      EXPECT_LE(xb, w);
      for (int32_t x = xa; x < xb; ++x) ++count[static_cast<size_t>(y) * w + x];
    });
  }
  return count;
}

// A jittered, rotated grid much larger than the screen: every pixel must be
// covered exactly once, whatever the sub-pixel positions.
TEST(RenderRaster, JitteredGridCoversEveryPixelExactlyOnce) {
  std::mt19937 rng(12345);
  for (int trial = 0; trial < 60; ++trial) {
    const double angle = std::uniform_real_distribution<double>(0, 6.2831853)(rng);
    const double cell = std::uniform_real_distribution<double>(2.0, 23.0)(rng);
    const double ox = std::uniform_real_distribution<double>(0, 1)(rng);
    const double oy = std::uniform_real_distribution<double>(0, 1)(rng);
    const int n = static_cast<int>(2 * std::hypot(kW, kH) / cell) + 4;
    std::vector<RasterVertex> verts;
    // Up to 0.2 cell per vertex keeps every quad convex: the triangles tile
    // the plane without folding (checked below by their orientation).
    std::uniform_real_distribution<double> jitter(-0.2 * cell, 0.2 * cell);
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        // Grid centred on the screen, rotated, jittered, then snapped to 1/256.
        const double gx = (i - n / 2.0) * cell + jitter(rng), gy = (j - n / 2.0) * cell + jitter(rng);
        const double x = kW / 2.0 + ox + gx * std::cos(angle) - gy * std::sin(angle);
        const double y = kH / 2.0 + oy + gx * std::sin(angle) + gy * std::cos(angle);
        verts.push_back({static_cast<int32_t>(std::lround(x * 256)), static_cast<int32_t>(std::lround(y * 256))});
      }
    std::vector<int> tris;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
        // Alternate the diagonal so both orientations of shared edges occur.
        if ((i + j + trial) & 1) {
          tris.insert(tris.end(), {a, b, d, a, d, c});
        } else {
          tris.insert(tris.end(), {a, b, c, b, d, c});
        }
      }
    for (size_t t = 0; t < tris.size(); t += 3) {
      const RasterVertex& a = verts[tris[t]];
      const RasterVertex& b = verts[tris[t + 1]];
      const RasterVertex& c = verts[tris[t + 2]];
      const int64_t area = int64_t{b.x - a.x} * (c.y - a.y) - int64_t{c.x - a.x} * (b.y - a.y);
      ASSERT_GT(area, 0) << "the test mesh folded";
    }
    const std::vector<int> count = coverage(verts, tris, kW, kH);
    int gaps = 0, doubles = 0;
    for (int c : count) {
      gaps += c == 0;
      doubles += c > 1;
    }
    ASSERT_EQ(gaps, 0) << "trial " << trial;
    ASSERT_EQ(doubles, 0) << "trial " << trial;
  }
}

// A fan of triangles around a shared vertex placed exactly on pixel centres,
// edges and corners: still exactly once.
TEST(RenderRaster, FanAroundLatticePointsCoversOnce) {
  const int32_t centres[][2] = {{128, 128}, {0, 0}, {256 * 10 + 128, 256 * 7}, {256 * 5, 256 * 5 + 128}};
  for (const auto& c : centres) {
    for (int spokes : {3, 5, 8, 13}) {
      std::vector<RasterVertex> verts = {{c[0] + 256 * 20, c[1] + 256 * 20}};
      std::vector<int> tris;
      for (int k = 0; k < spokes; ++k) {
        const double a = 6.2831853 * k / spokes + 0.1;
        verts.push_back({static_cast<int32_t>(std::lround(verts[0].x + 256 * 400 * std::cos(a))),
                         static_cast<int32_t>(std::lround(verts[0].y + 256 * 400 * std::sin(a)))});
      }
      for (int k = 0; k < spokes; ++k) tris.insert(tris.end(), {0, 1 + k, 1 + (k + 1) % spokes});
      const std::vector<int> count = coverage(verts, tris, kW, kH);
      for (int v : count) ASSERT_EQ(v, 1);
    }
  }
}

TEST(RenderRaster, TopLeftRuleIsPixelExact) {
  // A square with corners on pixel centres (0.5, 0.5)-(4.5, 4.5): the left
  // and top edges pass through centres and own them, the right and bottom
  // do not: pixels 0..3 x 0..3.
  const std::vector<RasterVertex> sq = {{128, 128}, {128 + 1024, 128}, {128 + 1024, 128 + 1024}, {128, 128 + 1024}};
  const std::vector<int> count = coverage(sq, {0, 1, 2, 0, 2, 3}, 8, 8);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) EXPECT_EQ(count[static_cast<size_t>(y) * 8 + x], (x < 4 && y < 4) ? 1 : 0) << x << "," << y;
  // A triangle whose only pixel centre lies on its bottom edge draws nothing;
  // moved up by 1/256 pixel it draws that pixel.
  const std::vector<RasterVertex> t1 = {{2 * 256 + 128, 256}, {3 * 256 + 128, 2 * 256 + 128}, {256 + 128, 2 * 256 + 128}};
  const std::vector<int> c1 = coverage(t1, {0, 1, 2}, 8, 8);
  EXPECT_EQ(c1[2 * 8 + 2], 0);
  EXPECT_EQ(c1[1 * 8 + 2], 1);  // row 1: (2.5, 1.5) is inside
  int total1 = 0;
  for (int v : c1) total1 += v;
  EXPECT_EQ(total1, 1);
  std::vector<RasterVertex> t2 = t1;
  for (auto& v : t2) v.y += 1;
  const std::vector<int> c2 = coverage(t2, {0, 1, 2}, 8, 8);
  EXPECT_EQ(c2[2 * 8 + 2], 1);
  int total = 0;
  for (int v : c2) total += v;
  EXPECT_EQ(total, 2);  // (1.5, 2.5) and (3.5, 2.5) lie just outside the slanted edges
}

// A convex polygon's one span a row covers exactly the pixels its fan
// triangles cover (from every corner), each once, in either orientation
// and in any band of rows; a polygon of zero height draws nothing.
TEST(RenderRaster, ConvexPolygonsCoverWhatTheirFansCover) {
  std::mt19937 rng(2026);
  int tested = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int n = 4 + static_cast<int>(rng() % 5);
    // Corners on an ellipse at increasing angles, snapped to 1/256 pixel.
    const double cx = std::uniform_real_distribution<double>(-10, kW + 10)(rng);
    const double cy = std::uniform_real_distribution<double>(-10, kH + 10)(rng);
    const double rx = std::uniform_real_distribution<double>(0.3, 60)(rng);
    const double ry = std::uniform_real_distribution<double>(0.3, 60)(rng);
    std::vector<double> angle(n);
    for (double& a : angle) a = std::uniform_real_distribution<double>(0, 6.2831853)(rng);
    std::sort(angle.begin(), angle.end());
    std::vector<RasterVertex> v;
    for (double a : angle) v.push_back({static_cast<int32_t>(std::lround((cx + rx * std::cos(a)) * 256)),
                                        static_cast<int32_t>(std::lround((cy + ry * std::sin(a)) * 256))});
    if (trial % 2) std::reverse(v.begin(), v.end());
    // Strictly convex after snapping (every turn one way), else skipped.
    int sign = 0;
    bool convex = true;
    for (int k = 0; k < n && convex; ++k) {
      const RasterVertex& a = v[k];
      const RasterVertex& b = v[(k + 1) % n];
      const RasterVertex& c = v[(k + 2) % n];
      const int64_t turn = int64_t{b.x - a.x} * (c.y - b.y) - int64_t{b.y - a.y} * (c.x - b.x);
      const int t = turn > 0 ? 1 : (turn < 0 ? -1 : 0);
      convex = t != 0 && (sign == 0 || t == sign);
      sign = t;
    }
    if (!convex) continue;
    ++tested;
    const int32_t y0 = static_cast<int32_t>(rng() % kH), y1 = y0 + 1 + static_cast<int32_t>(rng() % (kH - y0));
    std::vector<int> whole(static_cast<size_t>(kW) * kH, 0);
    int32_t rows_seen = -1;
    const int32_t spans = raster_convex(v.data(), n, y0, y1, kW, [&](int32_t y, int32_t xa, int32_t xb) {
      EXPECT_GE(y, y0);
      EXPECT_LT(y, y1);
      EXPECT_GT(y, rows_seen) << "one span a row, rows in order";
      rows_seen = y;
      EXPECT_GE(xa, 0);
      EXPECT_LE(xb, kW);
      for (int32_t x = xa; x < xb; ++x) ++whole[static_cast<size_t>(y) * kW + x];
    });
    int32_t covered_rows = 0;
    for (int y = 0; y < kH; ++y) {
      bool any = false;
      for (int x = 0; x < kW; ++x) any = any || whole[static_cast<size_t>(y) * kW + x] != 0;
      covered_rows += any;
    }
    EXPECT_EQ(spans, covered_rows);
    for (int from = 0; from < n; ++from) {
      std::vector<int> tris;
      for (int k = 1; k + 1 < n; ++k) tris.insert(tris.end(), {from, (from + k) % n, (from + k + 1) % n});
      std::vector<int> fan = coverage(v, tris, kW, kH);
      for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x)
          if (y < y0 || y >= y1) fan[static_cast<size_t>(y) * kW + x] = 0;
      ASSERT_EQ(whole, fan) << "trial " << trial << ", fan from corner " << from;
    }
  }
  EXPECT_GT(tested, 300);
  const RasterVertex flat[4] = {{256, 1000}, {2000, 1000}, {3000, 1000}, {500, 1000}};
  EXPECT_EQ(raster_convex(flat, 4, 0, kH, kW, [](int32_t, int32_t, int32_t) { ADD_FAILURE(); }), 0);
}

TEST(RenderRaster, DegenerateTrianglesDrawNothing) {
  const RasterVertex same[3] = {{1000, 1000}, {1000, 1000}, {1000, 1000}};
  const RasterVertex line[3] = {{0, 0}, {5000, 5000}, {10000, 10000}};
  const RasterVertex flat[3] = {{0, 1280}, {9000, 1280}, {20000, 1280}};
  const RasterVertex two[3] = {{300, 300}, {300, 300}, {9000, 7000}};
  for (const RasterVertex* t : {same, line, flat, two}) {
    int spans = 0;
    raster_triangle(t, 0, 100, 100, [&](int32_t, int32_t, int32_t) { ++spans; });
    EXPECT_EQ(spans, 0);
  }
  // Extreme but legal coordinates: spans stay inside the limits.
  const int32_t L = kRasterCoordLimit;
  const RasterVertex huge[3] = {{-L, -L}, {L, -L + 7}, {3, L}};
  int64_t pixels = 0;
  raster_triangle(huge, 0, kH, kW, [&](int32_t y, int32_t xa, int32_t xb) {
    ASSERT_GE(xa, 0);
    ASSERT_LE(xb, kW);
    ASSERT_LT(y, kH);
    pixels += xb - xa;
  });
  EXPECT_GT(pixels, 0);
}

// The whole pipeline: a closed convex mesh, projected and clipped against
// the screen edges. Its front faces must tile exactly the region its back
// faces tile (no gap), and no pixel may be rasterised twice (pixels
// rasterised == pixels covered).
ref::Scene convex_mesh_scene(std::mt19937& rng) {
  ref::Scene s;
  s.width = kW;
  s.height = kH;
  ref::MeshD m;
  m.shading = Shading::flat;
  m.color = 0xFFFFFF;
  // An icosphere subdivided twice, squashed and rotated randomly.
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<ref::Vec3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                               {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (ref::Vec3d& p : v) p = ref::normalize(p);  // all on the unit sphere: convex
  std::vector<int> f = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
                        3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
  for (int level = 0; level < 2; ++level) {
    std::vector<int> g;
    for (size_t i = 0; i < f.size(); i += 3) {
      int mid[3];
      for (int k = 0; k < 3; ++k) {
        v.push_back(ref::normalize(v[static_cast<size_t>(f[i + k])] + v[static_cast<size_t>(f[i + (k + 1) % 3])]));
        mid[k] = static_cast<int>(v.size() - 1);
      }
      g.insert(g.end(), {f[i], mid[0], mid[2], mid[0], f[i + 1], mid[1], mid[2], mid[1], f[i + 2], mid[0], mid[1], mid[2]});
    }
    f = g;
  }
  std::uniform_real_distribution<double> u(-1, 1);
  const ref::Vec3d axis = ref::normalize({u(rng), u(rng), u(rng)});
  const double ang = 3.14159 * u(rng);
  const ref::Vec3d scale{1.0 + 0.5 * u(rng), 0.7 + 0.3 * u(rng), 1.0 + 0.4 * u(rng)};
  const ref::Vec3d centre{4.0 * u(rng), 3.0 * u(rng), 6 + 2 * u(rng)};  // often partly off screen
  for (int idx : f) {
    // Midpoints are duplicated per face: identical positions give identical
    // projections, so shared edges still match exactly.
    ref::Vec3d p = v[static_cast<size_t>(idx)];
    p = {p.x * scale.x, p.y * scale.y, p.z * scale.z};
    // Rodrigues rotation.
    const ref::Vec3d k = axis;
    p = p * std::cos(ang) + ref::cross(k, p) * std::sin(ang) + k * (ref::dot(k, p) * (1 - std::cos(ang)));
    m.indices.push_back(s.add_vertex(p + centre));
  }
  // Outward winding: flip triangles whose normal points at the centre.
  for (size_t i = 0; i < m.indices.size(); i += 3) {
    const ref::Vec3d a = s.positions[m.indices[i]], b = s.positions[m.indices[i + 1]], c = s.positions[m.indices[i + 2]];
    if (ref::dot(ref::cross(b - a, c - a), a - centre) < 0) std::swap(m.indices[i + 1], m.indices[i + 2]);
  }
  s.meshes.push_back(m);
  // Camera with a random sub-pixel principal point.
  s.camera = ref::CameraD::look_at({0, 0, 0}, {0, 0, 1}, {0, 1, 0}, kW, kH, 60, 0.5, 50);
  s.camera.cx += u(rng) * 0.5;
  s.camera.cy += u(rng) * 0.5;
  s.clear_color = 0;
  return s;
}

TEST(RenderRaster, ClosedMeshFrontAndBackTileTheSameRegionOnce) {
  std::mt19937 rng(777);
  for (int trial = 0; trial < 25; ++trial) {
    ref::Scene s = convex_mesh_scene(rng);
    ref::ClientRenderSettings st;
    st.format = PixelFormat::rgb888;
    st.band_height = 1 + trial % 17;
    ref::Scene back = s;
    back.meshes[0].cull = Cull::front;  // draw only the back faces
    const ref::ClientScene cf(s, TexFormat::rgb565), cb(back, TexFormat::rgb565);
    const ref::ClientFrame ff = ref::render_client(cf, kW, kH, st);
    const ref::ClientFrame fb = ref::render_client(cb, kW, kH, st);
    ASSERT_EQ(ff.status, Status::ok);
    ASSERT_EQ(fb.status, Status::ok);
    uint32_t covered_front = 0, covered_back = 0, mismatch = 0;
    for (size_t i = 0; i < ff.image.pixels.size(); i += 3) {
      const bool a = ff.image.pixels[i] != 0, b = fb.image.pixels[i] != 0;
      covered_front += a;
      covered_back += b;
      mismatch += a != b;
    }
    EXPECT_GT(covered_front, 20u) << "trial " << trial;
    EXPECT_EQ(mismatch, 0u) << "trial " << trial;                    // no gap in either tiling
    EXPECT_EQ(ff.stats.pixels, covered_front) << "trial " << trial;  // no pixel rasterised twice
    EXPECT_EQ(fb.stats.pixels, covered_back) << "trial " << trial;
  }
}

}  // namespace
}  // namespace vds
