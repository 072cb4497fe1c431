// A scene's shape in fewer triangles (vds/enc/scene_shape.h): regions in
// one plane drawn as their outline cover exactly what their triangles
// covered, face the same way, and keep every vertex a neighbour shares.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "vds/enc/scene_render.h"
#include "vds/enc/scene_shape.h"
#include "walk_room.h"
#include "xorshift.h"

namespace {

using vds::enc::Scene;

// A scene whose surface 0 is opaque; quads added as two triangles with
// their own four vertices (as a map's faces are).
struct Builder {
  Scene s;
  Builder() {
    vds::enc::SceneTexture t;
    t.name = "stone";
    s.textures.push_back(t);
  }
  uint32_t vertex(float x, float y, float z) {
    vds::enc::SceneVertex v;
    v.pos = {x, y, z};
    s.vertices.push_back(v);
    return static_cast<uint32_t>(s.vertices.size() - 1);
  }
  // Corners counter-clockwise seen from where the quad faces.
  void quad(const std::array<std::array<float, 3>, 4>& c, int texture = 0, vds::enc::SurfaceKind kind = vds::enc::SurfaceKind::opaque) {
    vds::enc::SceneSurface f;
    f.texture = texture;
    f.kind = kind;
    f.face_type = 1;
    f.first_index = static_cast<uint32_t>(s.indices.size());
    uint32_t v[4];
    for (int k = 0; k < 4; ++k) v[k] = vertex(c[static_cast<size_t>(k)][0], c[static_cast<size_t>(k)][1], c[static_cast<size_t>(k)][2]);
    for (int k : {0, 1, 2, 0, 2, 3}) s.indices.push_back(v[k]);
    f.index_count = 6;
    s.surfaces.push_back(f);
  }
  // A floor quad (z = 0, facing up) from (x0, y0) to (x1, y1).
  void floor(float x0, float y0, float x1, float y1) { quad({{{x0, y0, 0}, {x1, y0, 0}, {x1, y1, 0}, {x0, y1, 0}}}); }
};

using P = std::array<double, 2>;
double side(const P& a, const P& b, const P& p) { return (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]); }

// How many of the scene's triangles in the plane z = 0, facing up, cover
// (x, y); -1 if one there faces down.
int cover(const Scene& s, double x, double y) {
  int n = 0;
  for (size_t t = 0; t < s.triangles(); ++t) {
    P q[3];
    bool flat = true;
    for (int c = 0; c < 3; ++c) {
      const auto& v = s.vertices[s.indices[3 * t + static_cast<size_t>(c)]].pos;
      q[c] = {v[0], v[1]};
      flat = flat && v[2] == 0;
    }
    if (!flat) continue;
    if (side(q[0], q[1], q[2]) <= 0) return -1;
    if (side(q[0], q[1], {x, y}) > 0 && side(q[1], q[2], {x, y}) > 0 && side(q[2], q[0], {x, y}) > 0) ++n;
  }
  return n;
}

// Every random point covered as often after as before (points on edges,
// which both count as uncovered, aside: none falls exactly on one).
void expect_same_cover(const Scene& before, const Scene& after, double x0, double y0, double x1, double y1) {
  vds::test::Xorshift32 rng;
  for (int i = 0; i < 4000; ++i) {
    const double x = x0 + (x1 - x0) * (rng.next() % 100003) / 100003.0;
    const double y = y0 + (y1 - y0) * (rng.next() % 100019) / 100019.0;
    ASSERT_EQ(cover(after, x, y), cover(before, x, y)) << "at " << x << ", " << y;
  }
}

TEST(SceneShape, EachWallOfTheRoomBecomesTwoTriangles) {
  // Each wall is a 4 x 4 grid of quads with vertices of their own.
  const Scene room = vds::test::walk_room();
  vds::enc::ShapeStats st;
  const Scene s = vds::enc::simplify_shape(room, vds::enc::ShapeOptions{}, &st);
  EXPECT_EQ(room.triangles(), 192u);
  EXPECT_EQ(s.triangles(), 12u);
  EXPECT_EQ(st.regions, 6u);
  EXPECT_EQ(st.merged, 6u);
  EXPECT_EQ(st.triangles_out, 12u);
  EXPECT_EQ(s.textures.size(), room.textures.size());
  // Each triangle faces into the room (its normal along the wall's) and
  // the six walls' areas are whole: 2 x 512^2 + 4 x 512 x 256.
  double area = 0;
  for (size_t t = 0; t < s.triangles(); ++t) {
    std::array<double, 3> p[3];
    for (int c = 0; c < 3; ++c)
      for (int a = 0; a < 3; ++a) p[c][static_cast<size_t>(a)] = s.vertices[s.indices[3 * t + static_cast<size_t>(c)]].pos[static_cast<size_t>(a)];
    const std::array<double, 3> u{p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
    const std::array<double, 3> w{p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
    const std::array<double, 3> n{u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    const double centre[3] = {(p[0][0] + p[1][0] + p[2][0]) / 3, (p[0][1] + p[1][1] + p[2][1]) / 3, (p[0][2] + p[1][2] + p[2][2]) / 3};
    // Inward: towards the room's centre (0, 0, 128).
    EXPECT_LT(n[0] * centre[0] + n[1] * centre[1] + n[2] * (centre[2] - 128), 0) << "triangle " << t;
    area += std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) / 2;
  }
  EXPECT_NEAR(area, 2.0 * 512 * 512 + 4.0 * 512 * 256, 1e-6);
}

// The nearest depth at every pixel of a few views of the scene.
std::vector<float> depths(const Scene& s) {
  vds::enc::RenderOptions ro;
  ro.width = 64;
  ro.height = 48;
  ro.supersample = 1;
  const vds::enc::SceneRenderer r(s, {}, ro);
  std::vector<float> all;
  for (int k = 0; k < 6; ++k) {
    const vds::enc::CameraPose pose{-150.0 + 60 * k, -100.0 + 35 * k, 60.0 + 20 * k, 60.0 * k, 10.0 - 5 * k};
    const vds::enc::SceneFrame f = r.render(pose, 90);
    all.insert(all.end(), f.depth.begin(), f.depth.end());
  }
  return all;
}

TEST(SceneShape, ARendererSeesTheSameDepthsEitherWayRoundTheTrianglesWind) {
  // The renderer tells a triangle's front from its vertices' normals; a
  // map's triangles wind clockwise about them. The merged walls must face
  // the way the walls' vertices say, whichever way their triangles wound.
  Scene room = vds::test::walk_room();
  for (int wind = 0; wind < 2; ++wind) {
    if (wind == 1)
      for (size_t t = 0; t < room.triangles(); ++t) std::swap(room.indices[3 * t + 1], room.indices[3 * t + 2]);
    const Scene s = vds::enc::simplify_shape(room);
    ASSERT_EQ(s.triangles(), 12u);
    const std::vector<float> before = depths(room), after = depths(s);
    ASSERT_EQ(before.size(), after.size());
    size_t far = 0;
    for (size_t i = 0; i < before.size(); ++i) far += !(std::fabs(before[i] - after[i]) <= 1e-2f * std::max(1.0f, before[i]));
    EXPECT_EQ(far, 0u) << "winding " << wind;
  }
}

TEST(SceneShape, AFloorWithAHoleAndACornerOnAnEdgeCoversWhatItCovered) {
  // A 3 x 3 floor of unit quads with the centre missing, and beside it a
  // 2 x 1 quad whose long edge holds the corner two unit quads share (a
  // T-junction): one region with a hole.
  Builder b;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i)
      if (i != 1 || j != 1) b.floor(static_cast<float>(i), static_cast<float>(j), static_cast<float>(i + 1), static_cast<float>(j + 1));
  b.floor(3, 0, 4, 2);
  vds::enc::ShapeStats st;
  const Scene s = vds::enc::simplify_shape(b.s, vds::enc::ShapeOptions{}, &st);
  EXPECT_EQ(st.regions, 1u);
  EXPECT_EQ(st.merged, 1u);
  EXPECT_LT(s.triangles(), b.s.triangles());
  expect_same_cover(b.s, s, -0.5, -0.5, 4.5, 3.5);
  EXPECT_EQ(cover(s, 1.5, 1.5), 0);  // the hole stays open
}

TEST(SceneShape, AnOutlineCornerANeighbourUsesStays) {
  // Two unit floor quads side by side: their shared edge's ends lie on the
  // outline where it runs straight. A wall standing on the far edge uses
  // the corner (1, 1, 0): that corner stays; (1, 0, 0) goes.
  Builder b;
  b.floor(0, 0, 1, 1);
  b.floor(1, 0, 2, 1);
  b.quad({{{0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}}});
  const Scene s = vds::enc::simplify_shape(b.s);
  bool has_corner = false, has_dropped = false;
  for (size_t t = 0; t < s.triangles(); ++t)
    for (int c = 0; c < 3; ++c) {
      const auto& p = s.vertices[s.indices[3 * t + static_cast<size_t>(c)]].pos;
      if (p[2] != 0) continue;
      has_corner = has_corner || (p[0] == 1 && p[1] == 1);
      has_dropped = has_dropped || (p[0] == 1 && p[1] == 0);
    }
  EXPECT_TRUE(has_corner);
  EXPECT_FALSE(has_dropped);
  expect_same_cover(b.s, s, -0.5, -0.5, 2.5, 1.5);
  // Floor: a pentagon (3 triangles, not 4); the wall's 2 kept.
  EXPECT_EQ(s.triangles(), 5u);
}

TEST(SceneShape, SkyAlphaTestedAndRepeatedTrianglesAreNotMerged) {
  Builder b;
  vds::enc::SceneTexture grate;
  grate.name = "grate";
  grate.blend = vds::enc::ShaderBlend::alpha_test;
  b.s.textures.push_back(grate);
  b.floor(0, 0, 1, 1);
  b.floor(1, 0, 2, 1);
  b.floor(1, 0, 2, 1);  // a repeat of the one before
  b.quad({{{2, 0, 0}, {3, 0, 0}, {3, 1, 0}, {2, 1, 0}}}, 1);                                      // alpha-tested
  b.quad({{{0, 1, 0}, {1, 1, 0}, {1, 2, 0}, {0, 2, 0}}}, 0, vds::enc::SurfaceKind::sky);  // sky
  vds::enc::ShapeStats st;
  const Scene s = vds::enc::simplify_shape(b.s, vds::enc::ShapeOptions{}, &st);
  EXPECT_EQ(st.repeats, 2u);
  EXPECT_EQ(st.merged, 1u);
  // The two opaque quads: 3 triangles (the corner (1, 1) the sky uses
  // stays); the grate and the sky: 2 each.
  EXPECT_EQ(s.triangles(), 7u);
  size_t grate_tris = 0, sky_tris = 0;
  for (const auto& f : s.surfaces) {
    if (f.texture == 1) grate_tris += f.index_count / 3;
    if (f.kind == vds::enc::SurfaceKind::sky) sky_tris += f.index_count / 3;
  }
  EXPECT_EQ(grate_tris, 2u);
  EXPECT_EQ(sky_tris, 2u);
}

// A gentle bump, z = h sin(pi x / 16) sin(pi y / 16) over 16 x 16 units,
// as a model's 32 x 32 quads sharing their vertices; its normals point up.
// wind = 1: its triangles wind the other way round them.
Scene bump(double h, int wind) {
  Builder b;
  constexpr int kN = 32;
  vds::enc::SceneSurface f;
  f.texture = 0;
  f.face_type = 3;
  f.first_index = 0;
  const auto z = [h](double x, double y) { return h * std::sin(M_PI * x / 16) * std::sin(M_PI * y / 16); };
  for (int j = 0; j <= kN; ++j)
    for (int i = 0; i <= kN; ++i) {
      const double x = 16.0 * i / kN, y = 16.0 * j / kN;
      b.vertex(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z(x, y)));
      b.s.vertices.back().normal = {0, 0, 1};
    }
  for (int j = 0; j < kN; ++j)
    for (int i = 0; i < kN; ++i) {
      const uint32_t a = static_cast<uint32_t>(j * (kN + 1) + i), c = a + kN + 1;
      for (uint32_t v : {a, a + 1, c + 1, a, c + 1, c}) b.s.indices.push_back(v);
    }
  if (wind == 1)
    for (size_t t = 0; t < b.s.triangles(); ++t) std::swap(b.s.indices[3 * t + 1], b.s.indices[3 * t + 2]);
  f.index_count = static_cast<uint32_t>(b.s.indices.size());
  b.s.surfaces.push_back(f);
  return b.s;
}

TEST(SceneShape, DecimatedSurfacesStayWithinTheToleranceAndKeepTheirRims) {
  constexpr double kH = 0.3, kTol = 0.25;
  const auto height = [](double x, double y) { return kH * std::sin(M_PI * x / 16) * std::sin(M_PI * y / 16); };
  for (int wind = 0; wind < 2; ++wind) {
    const Scene in = bump(kH, wind);
    // (No plane merges the bump's nearly flat rows: the decimation alone.)
    vds::enc::ShapeOptions none;
    none.plane_tolerance = 1e-9;
    EXPECT_EQ(vds::enc::simplify_shape(in, none).triangles(), in.triangles());
    vds::enc::ShapeOptions o = none;
    o.tolerance = kTol;
    vds::enc::ShapeStats st;
    const Scene s = vds::enc::simplify_shape(in, o, &st);
    EXPECT_EQ(st.decimated_in, 2048u);
    // The same triangles as a polygon face (a map's brush face) stay.
    Scene poly = in;
    poly.surfaces[0].face_type = 1;
    EXPECT_EQ(vds::enc::simplify_shape(poly, o).triangles(), in.triangles());
    EXPECT_LT(s.triangles(), in.triangles() / 8) << "winding " << wind;
    EXPECT_EQ(st.triangles_out, s.triangles());
    // Its rim, an open edge, stays where it was: its corners are kept and
    // points just inside it are covered (below).
    for (const std::array<float, 2> r : {std::array<float, 2>{0, 0}, {16, 0}, {0, 16}, {16, 16}}) {
      bool kept = false;
      for (uint32_t v : s.indices) kept = kept || (s.vertices[v].pos[0] == r[0] && s.vertices[v].pos[1] == r[1]);
      EXPECT_TRUE(kept) << r[0] << ", " << r[1];
    }
    // Each triangle's vertex normals face the side its vertices' normals
    // faced (up), and its corners run round them as before.
    for (size_t t = 0; t < s.triangles(); ++t) {
      std::array<std::array<double, 3>, 3> p{};
      for (int c = 0; c < 3; ++c) {
        const auto& v = s.vertices[s.indices[3 * t + static_cast<size_t>(c)]];
        EXPECT_GT(v.normal[2], 0.9f);
        for (int a = 0; a < 3; ++a) p[static_cast<size_t>(c)][static_cast<size_t>(a)] = v.pos[static_cast<size_t>(a)];
      }
      const double nz = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
      EXPECT_EQ(nz > 0, wind == 0) << "triangle " << t;
    }
    // Every point of the bump is covered once, within the tolerance of
    // its height; a quarter of them lie just inside its rim.
    vds::test::Xorshift32 rng;
    for (int i = 0; i < 2000; ++i) {
      double x = 0.001 + 15.998 * (rng.next() % 100003) / 100003.0, y = 0.001 + 15.998 * (rng.next() % 100019) / 100019.0;
      if (i % 4 == 0) (i % 8 == 0 ? x : y) = (i % 16 == 0) ? 0.001 : 15.999;
      int covered = 0;
      double z = 0;
      for (size_t t = 0; t < s.triangles(); ++t) {
        P q[3];
        double zc[3];
        for (int c = 0; c < 3; ++c) {
          const auto& v = s.vertices[s.indices[3 * t + static_cast<size_t>(c)]].pos;
          q[c] = {v[0], v[1]};
          zc[c] = v[2];
        }
        if (wind == 1) {
          std::swap(q[1], q[2]);
          std::swap(zc[1], zc[2]);
        }
        const double area = side(q[0], q[1], q[2]);
        const double w0 = side(q[1], q[2], {x, y}) / area, w1 = side(q[2], q[0], {x, y}) / area, w2 = side(q[0], q[1], {x, y}) / area;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        ++covered;
        z = w0 * zc[0] + w1 * zc[1] + w2 * zc[2];
      }
      ASSERT_EQ(covered, 1) << "at " << x << ", " << y;
      EXPECT_NEAR(z, height(x, y), kTol) << "at " << x << ", " << y;
    }
  }
}

}  // namespace
