// The ground-truth renderer (vds/enc/scene_render.h) and the camera tour
// (vds/enc/camera_tour.h): scenes built in code checked pixel by pixel
// (exact depth and triangle IDs, texture x lightmap with overbright,
// mip-mapping, back faces, alpha test, additive effects, near clipping);
// on an installed map, a reprojection test of the visibility buffers and a
// tour that stays clear of the walls.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "vds/enc/camera_tour.h"
#include "vds/enc/scene.h"
#include "vds/enc/scene_rays.h"
#include "vds/enc/scene_render.h"

namespace {

using vds::enc::CameraPose;
using vds::enc::Scene;
using vds::enc::SceneFrame;
using vds::enc::SceneRenderer;
using vds::enc::SurfaceKind;
using vds::io::Image;

// A quad a-b-c-d (two triangles) facing `normal`, texture coordinates
// 0..reps across it.
void add_quad(Scene& s, std::array<float, 3> a, std::array<float, 3> b, std::array<float, 3> c, std::array<float, 3> d,
              std::array<float, 3> normal, int texture, int lightmap = -1, SurfaceKind kind = SurfaceKind::opaque,
              float reps = 1) {
  const uint32_t base = static_cast<uint32_t>(s.vertices.size());
  const std::array<float, 3> p[4] = {a, b, c, d};
  const float uv[4][2] = {{0, 0}, {reps, 0}, {reps, reps}, {0, reps}};
  for (int k = 0; k < 4; ++k) {
    vds::enc::SceneVertex v;
    v.pos = p[k];
    v.uv = {uv[k][0], uv[k][1]};
    v.lm_uv = {uv[k][0] / reps, uv[k][1] / reps};
    v.normal = normal;
    v.color = {255, 255, 255, 255};
    s.vertices.push_back(v);
  }
  vds::enc::SceneSurface f;
  f.texture = texture;
  f.lightmap = lightmap;
  f.kind = kind;
  f.first_index = static_cast<uint32_t>(s.indices.size());
  for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) s.indices.push_back(base + i);
  f.index_count = 6;
  s.surfaces.push_back(f);
}

Image solid(int w, int h, uint8_t r, uint8_t g, uint8_t b, uint8_t a = 255) {
  Image im(w, h, 4);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) im.at(x, y, 0) = r, im.at(x, y, 1) = g, im.at(x, y, 2) = b, im.at(x, y, 3) = a;
  return im;
}

// A wall at x = 100 facing -x, 200 wide and high, centred on the X axis.
Scene wall_scene(int lightmap = -1) {
  Scene s;
  s.name = "wall";
  s.textures.resize(2);
  add_quad(s, {100, 100, -100}, {100, -100, -100}, {100, -100, 100}, {100, 100, 100}, {-1, 0, 0}, 0, lightmap);
  return s;
}

size_t centre(const SceneFrame& f) { return static_cast<size_t>(f.rgb.height / 2) * f.rgb.width + f.rgb.width / 2; }

TEST(SceneRender, DepthAndTrianglesAreExact) {
  const Scene s = wall_scene();
  const SceneRenderer r(s, {solid(8, 8, 200, 100, 50)});
  const SceneFrame f = r.render({0, 0, 0, 0, 0}, 90);
  ASSERT_EQ(f.rgb.width, 240);
  ASSERT_EQ(f.ids.size(), 240u * 180u);
  // Camera-space z is 100 everywhere on a wall facing the camera head on.
  size_t seen = 0;
  for (size_t i = 0; i < f.ids.size(); ++i)
    if (f.ids[i] != vds::enc::kNoTriangle) {
      ++seen;
      EXPECT_NEAR(f.depth[i], 100.0f, 1e-3f);
      EXPECT_LT(f.ids[i], 2u);
    } else {
      EXPECT_TRUE(std::isinf(f.depth[i]));
    }
  // Half the 90-degree view is 100 units at distance 100: the wall fills the width exactly.
  EXPECT_EQ(seen, f.ids.size());
  // Unlit (no lightmap, no vertex colours): the texture itself.
  EXPECT_EQ(f.rgb.at(120, 90, 0), 200);
  EXPECT_EQ(f.rgb.at(120, 90, 1), 100);
  EXPECT_EQ(f.rgb.at(120, 90, 2), 50);
  // Looking away: nothing.
  const SceneFrame away = r.render({0, 0, 0, 180, 0}, 90);
  for (uint32_t id : away.ids) EXPECT_EQ(id, vds::enc::kNoTriangle);
  EXPECT_EQ(away.rgb.at(120, 90, 0), 0);
}

TEST(SceneRender, ProjectionFollowsQuakeAxes) {
  // A small quad at +Y seen at yaw 90 lands in the centre; at yaw 0 it is off to the left, out of a 60-degree view.
  Scene s;
  s.textures.resize(1);
  add_quad(s, {-10, 200, -10}, {10, 200, -10}, {10, 200, 10}, {-10, 200, 10}, {0, -1, 0}, 0);
  const SceneRenderer r(s, {solid(4, 4, 255, 255, 255)});
  EXPECT_NE(r.render({0, 0, 0, 90, 0}, 60).ids[120 * 1 + 90 * 240], vds::enc::kNoTriangle);
  const SceneFrame f0 = r.render({0, 0, 0, 0, 0}, 60);
  for (uint32_t id : f0.ids) EXPECT_EQ(id, vds::enc::kNoTriangle);
  // Pitch up 45 degrees: the quad, level with the eye, moves to the lower part of the image.
  const SceneFrame up = r.render({0, 0, 0, 90, 30}, 90);
  size_t row_sum = 0, n = 0;
  for (size_t i = 0; i < up.ids.size(); ++i)
    if (up.ids[i] != vds::enc::kNoTriangle) row_sum += i / 240, ++n;
  ASSERT_GT(n, 0u);
  EXPECT_GT(row_sum / n, 90u + 40u);
}

TEST(SceneRender, LightmapsAreModulatedWithOverbright) {
  Scene s = wall_scene(0);
  s.lightmaps.assign(1, std::vector<uint8_t>(vds::enc::kLightmapSide * vds::enc::kLightmapSide * 3, 32));
  // 32 x 4 = 128: half the texture's value.
  const SceneRenderer r(s, {solid(8, 8, 200, 100, 50)});
  const SceneFrame f = r.render({0, 0, 0, 0, 0}, 90);
  EXPECT_NEAR(f.rgb.at(120, 90, 0), 100, 1);
  EXPECT_NEAR(f.rgb.at(120, 90, 1), 50, 1);
  // Overbright keeps the hue when it clamps: (100, 50, 25) x 4 would pass 255.
  for (size_t i = 0; i < s.lightmaps[0].size(); i += 3) s.lightmaps[0][i] = 100, s.lightmaps[0][i + 1] = 50, s.lightmaps[0][i + 2] = 25;
  const SceneRenderer r2(s, {solid(8, 8, 255, 255, 255)});
  const SceneFrame g = r2.render({0, 0, 0, 0, 0}, 90);
  EXPECT_EQ(g.rgb.at(120, 90, 0), 255);
  EXPECT_NEAR(g.rgb.at(120, 90, 1), 128, 1);
  EXPECT_NEAR(g.rgb.at(120, 90, 2), 64, 1);
  vds::enc::RenderOptions o;
  o.overbright_bits = 0;
  const SceneRenderer r3(s, {solid(8, 8, 255, 255, 255)}, o);
  EXPECT_NEAR(r3.render({0, 0, 0, 0, 0}, 90).rgb.at(120, 90, 0), 100, 1);
}

TEST(SceneRender, DistantDetailIsFilteredNotAliased) {
  // A 1-texel checkerboard of black and white repeated 64 times across a
  // floor: far away every pixel is close to the mean grey.
  Scene s;
  s.textures.resize(1);
  add_quad(s, {0, -2000, -20}, {4000, -2000, -20}, {4000, 2000, -20}, {0, 2000, -20}, {0, 0, 1}, 0, -1,
           SurfaceKind::opaque, 256);
  Image check(16, 16, 4);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      const uint8_t v = ((x + y) & 1) ? 255 : 0;
      check.at(x, y, 0) = check.at(x, y, 1) = check.at(x, y, 2) = v;
      check.at(x, y, 3) = 255;
    }
  const SceneRenderer r(s, {check});
  const SceneFrame f = r.render({0, 0, 0, 0, 0}, 90);
  // Rows just below the horizon see the floor 400 to 1000 units away,
  // stretched: a pixel spans 3 to 8 texels across and 15 to 90 along.
  int worst = 0, wx = 0, wy = 0;
  for (int y = 92; y < 97; ++y)
    for (int x = 0; x < 240; ++x)
      if (std::abs(f.rgb.at(x, y, 0) - 128) > worst) worst = std::abs(f.rgb.at(x, y, 0) - 128), wx = x, wy = y;
  EXPECT_LT(worst, 24) << wx << "," << wy;
  // Without anisotropic samples the far floor is blurrier, never sharper: still grey.
  vds::enc::RenderOptions o;
  o.max_aniso = 1;
  const SceneFrame g = SceneRenderer(s, {check}, o).render({0, 0, 0, 0, 0}, 90);
  for (int x = 0; x < 240; ++x) EXPECT_NEAR(g.rgb.at(x, 100, 0), 128, 24);
}

TEST(SceneRender, BackFacesAlphaTestAndAdditiveSurfaces) {
  Scene s = wall_scene();
  // Behind the wall, looking back at it: its back is culled.
  const SceneRenderer r(s, {solid(8, 8, 200, 100, 50)});
  for (uint32_t id : r.render({200, 0, 0, 180, 0}, 90).ids) EXPECT_EQ(id, vds::enc::kNoTriangle);
  // Two-sided by its shader: drawn.
  s.textures[0].two_sided = true;
  EXPECT_NE(SceneRenderer(s, {solid(8, 8, 200, 100, 50)}).render({200, 0, 0, 180, 0}, 90).ids[centre(SceneFrame{Image(240, 180, 3), {}, {}, {}})],
            vds::enc::kNoTriangle);
  // Alpha-tested with a transparent texture: cut out of the image and the visibility.
  s.textures[0].blend = vds::enc::ShaderBlend::alpha_test;
  const SceneFrame cut = SceneRenderer(s, {solid(8, 8, 200, 100, 50, 0)}).render({0, 0, 0, 0, 0}, 90);
  for (uint32_t id : cut.ids) EXPECT_EQ(id, vds::enc::kNoTriangle);
  // An additive quad in front of an opaque wall adds its colour; no triangle ID of its own.
  Scene a = wall_scene();
  a.textures.resize(2);
  add_quad(a, {50, 10, -10}, {50, -10, -10}, {50, -10, 10}, {50, 10, 10}, {-1, 0, 0}, 1, -1, SurfaceKind::additive);
  const SceneFrame add = SceneRenderer(a, {solid(8, 8, 100, 100, 100), solid(8, 8, 20, 40, 60)}).render({0, 0, 0, 0, 0}, 90);
  EXPECT_EQ(add.rgb.at(120, 90, 0), 120);
  EXPECT_EQ(add.rgb.at(120, 90, 2), 160);
  EXPECT_LT(add.ids[centre(add)], 2u);
  EXPECT_NEAR(add.depth[centre(add)], 100.0f, 1e-3f);
}

// A quad facing -x at distance x: y from y0 to y1, z from z0 to z1.
void add_facing_quad(Scene& s, float x, float y0, float y1, float z0, float z1) {
  add_quad(s, {x, y1, z0}, {x, y0, z0}, {x, y0, z1}, {x, y1, z1}, {-1, 0, 0}, 0);
}

TEST(SceneRender, SmallTrianglesLeaveTheirPixelsToTheLargeOnesBehindThemWhereNoHoleOpens) {
  Scene s;
  s.textures.resize(1);
  add_facing_quad(s, 100, -100, 100, -100, 0);  // 0, 1: a wall filling the lower half of the view
  add_facing_quad(s, 50, -1, 1, -21, -19);      // 2, 3: a small quad in front of it
  add_facing_quad(s, 50, -1, 1, 19, 21);        // 4, 5: a small quad with nothing behind it
  add_facing_quad(s, 50, 15, 17, 19, 21);       // 6, 7: a small quad ...
  add_facing_quad(s, 90, 27, 30.6f, 34.2f, 37.8f);  // 8, 9: ... hiding a larger one behind it, shown nowhere else
  vds::enc::RenderOptions o;
  o.supersample = 1;
  o.min_pixels = 16;
  const SceneFrame f = SceneRenderer(s, {solid(4, 4, 255, 255, 255)}, o).render({0, 0, 0, 0, 0}, 90);
  ASSERT_EQ(f.large_ids.size(), f.ids.size());
  const auto cover = [](const std::vector<std::pair<uint32_t, uint32_t>>& v) {
    std::vector<uint32_t> c(10, 0);
    for (const auto& [id, px] : v) {
      EXPECT_LT(id, 10u);
      if (id < 10) c[id] = px;
    }
    return c;
  };
  const std::vector<uint32_t> all = cover(vds::enc::visible_triangles(f));
  const std::vector<uint32_t> large = cover(vds::enc::visible_large_triangles(f));
  for (uint32_t id = 2; id < 8; ++id) {
    EXPECT_GT(all[id], 0u) << id;
    EXPECT_LT(all[id], 16u) << id;
  }
  EXPECT_EQ(all[8] + all[9], 0u);  // hidden
  size_t behind_small = 0;          // pixels of 6 and 7 where 8 or 9 lies behind
  for (size_t i = 0; i < f.ids.size(); ++i)
    if ((f.ids[i] == 6 || f.ids[i] == 7) && (f.large_ids[i] == 8 || f.large_ids[i] == 9)) ++behind_small;
  EXPECT_GT(behind_small, 0u);
  // The quad in front of the wall is left out: its pixels are the wall's.
  EXPECT_EQ(large[2] + large[3], 0u);
  EXPECT_EQ(large[0] + large[1], all[0] + all[1] + all[2] + all[3]);
  // The others stay (a hole where nothing is behind; a triangle the frame
  // does not otherwise show), and the one behind them is not drawn.
  for (uint32_t id = 4; id < 8; ++id) EXPECT_EQ(large[id], all[id]) << id;
  EXPECT_EQ(large[8] + large[9], 0u);
  // Without min_pixels: no large_ids, and the same triangles either way.
  const SceneFrame plain = SceneRenderer(s, {solid(4, 4, 255, 255, 255)}).render({0, 0, 0, 0, 0}, 90);
  EXPECT_TRUE(plain.large_ids.empty());
  EXPECT_EQ(vds::enc::visible_large_triangles(plain), vds::enc::visible_triangles(plain));
}

TEST(SceneRender, TrianglesCrossingTheNearPlaneAreClipped) {
  // A floor under and behind the camera: drawn in the lower half, depth positive and rising towards the horizon.
  Scene s;
  s.textures.resize(1);
  add_quad(s, {-500, -500, -30}, {500, -500, -30}, {500, 500, -30}, {-500, 500, -30}, {0, 0, 1}, 0);
  const SceneFrame f = SceneRenderer(s, {solid(4, 4, 90, 90, 90)}).render({0, 0, 0, 0, 0}, 90);
  // Rows from 97 down meet the floor within 500 units (30 * 120 / (y + 0.5 - 90) <= 500).
  for (int y = 97; y < 180; ++y) {
    const size_t i = static_cast<size_t>(y) * 240 + 120;
    ASSERT_NE(f.ids[i], vds::enc::kNoTriangle) << y;
    // The ray through row y meets z = -30 at forward distance 30 * f / (y + 0.5 - 90).
    EXPECT_NEAR(f.depth[i], 30.0 * 120 / (y + 0.5 - 90), 1e-2 * f.depth[i]);
  }
  for (int y = 0; y < 90; ++y) EXPECT_EQ(f.ids[static_cast<size_t>(y) * 240 + 120], vds::enc::kNoTriangle);
}

TEST(SceneRays, CastsClearanceAndSegments) {
  const Scene s = wall_scene();
  const vds::enc::SceneRays rays(s);
  EXPECT_NEAR(rays.cast({0, 0, 0}, {1, 0, 0}, 1000), 100, 1e-9);
  EXPECT_EQ(rays.cast({0, 0, 0}, {-1, 0, 0}, 1000), 1000);
  EXPECT_NEAR(rays.cast({200, 0, 0}, {-1, 0, 0}, 1000), 100, 1e-9);  // both sides stop a ray
  EXPECT_TRUE(rays.clear({80, 0, 0}, 12));
  EXPECT_FALSE(rays.clear({95, 0, 0}, 12));
  EXPECT_FALSE(rays.segment_clear({0, 0, 0}, {200, 0, 0}, 12));
  EXPECT_TRUE(rays.segment_clear({0, 0, 0}, {0, 300, 0}, 12));
  // Passing the wall's edge: the centre line is clear, the sideways ray is not.
  EXPECT_FALSE(rays.segment_clear({50, 105, 0}, {150, 105, 0}, 12));
  EXPECT_TRUE(rays.segment_clear({50, 125, 0}, {150, 125, 0}, 12));
}

// Projects the world point of each pixel of frame a into frame b: where b
// sees that point (its depth there agrees), it must see the same triangle.
TEST(SceneRender, VisibilityReprojectsOntoTheSameTriangles) {
  const Scene s = vds::enc::load_scene("oa_dm4");
  const vds::enc::SceneRays rays(s);
  vds::enc::TourOptions to;
  to.frames = 200;
  const vds::enc::CameraPath path = vds::enc::make_tour(s, rays, to);
  const SceneRenderer r(s, vds::enc::load_scene_images(s));
  size_t checked = 0, same = 0, within_pixel = 0;
  for (size_t t = 0; t + 1 < path.frames.size(); t += 23) {
    const SceneFrame a = r.render(path.frames[t], path.hfov_deg), b = r.render(path.frames[t + 1], path.hfov_deg);
    const auto ca = vds::enc::scene_camera(path.frames[t], path.hfov_deg, 240, 180);
    const auto cb = vds::enc::scene_camera(path.frames[t + 1], path.hfov_deg, 240, 180);
    for (int y = 0; y < 180; ++y)
      for (int x = 0; x < 240; ++x) {
        const size_t i = static_cast<size_t>(y) * 240 + x;
        if (a.ids[i] == vds::enc::kNoTriangle) continue;
        const double z = a.depth[i], dx = (x + 0.5 - ca.cx) / ca.focal * z, dy = (y + 0.5 - ca.cy) / ca.focal * z;
        std::array<double, 3> w;
        for (int k = 0; k < 3; ++k) w[k] = ca.position[k] + ca.right[k] * dx + ca.down[k] * dy + ca.forward[k] * z;
        std::array<double, 3> d;
        for (int k = 0; k < 3; ++k) d[k] = w[k] - cb.position[k];
        const double zb = d[0] * cb.forward[0] + d[1] * cb.forward[1] + d[2] * cb.forward[2];
        if (zb <= 1) continue;
        const double xb = cb.cx + cb.focal * (d[0] * cb.right[0] + d[1] * cb.right[1] + d[2] * cb.right[2]) / zb;
        const double yb = cb.cy + cb.focal * (d[0] * cb.down[0] + d[1] * cb.down[1] + d[2] * cb.down[2]) / zb;
        const int px = static_cast<int>(std::floor(xb)), py = static_cast<int>(std::floor(yb));
        if (px < 0 || py < 0 || px >= 240 || py >= 180) continue;
        const size_t j = static_cast<size_t>(py) * 240 + px;
        if (std::fabs(b.depth[j] - zb) > 0.01 * zb + 1) continue;  // hidden in b, or at a depth edge
        ++checked;
        same += b.ids[j] == a.ids[i];
        bool near = false;
        for (int ny = std::max(0, py - 1); ny <= std::min(179, py + 1) && !near; ++ny)
          for (int nx = std::max(0, px - 1); nx <= std::min(239, px + 1) && !near; ++nx)
            near = b.ids[static_cast<size_t>(ny) * 240 + nx] == a.ids[i];
        within_pixel += near;
      }
  }
  std::printf("reprojection: %zu of %zu visible points on the same triangle (%.2f %%), %zu within a pixel (%.3f %%)\n", same,
              checked, 100.0 * same / checked, within_pixel, 100.0 * within_pixel / checked);
  ASSERT_GT(checked, 100000u);
  // Differences are confined to the edges between triangles (the point lands within a pixel of its own).
  EXPECT_GT(static_cast<double>(same) / checked, 0.95) << same << " of " << checked;
  EXPECT_GT(static_cast<double>(within_pixel) / checked, 0.999) << within_pixel << " of " << checked;
}

TEST(CameraTour, StaysClearOfTheWallsAndMovesSmoothly) {
  for (const char* map : {"oa_dm4", "oa_dm5"}) {
    const Scene s = vds::enc::load_scene(map);
    const vds::enc::SceneRays rays(s);
    vds::enc::TourOptions to;
    vds::enc::TourReport rep;
    const vds::enc::CameraPath p = vds::enc::make_tour(s, rays, to, &rep);
    ASSERT_EQ(p.frames.size(), 600u) << map;
    EXPECT_GE(rep.stops.size(), 3u) << map;
    EXPECT_GE(rep.min_clearance, 0.75 * to.radius) << map;
    // Starts at the first spawn point's eye.
    EXPECT_NEAR(p.frames[0].x, s.spawns[rep.stops[0]].origin[0], 1e-9);
    EXPECT_NEAR(p.frames[0].z, s.spawns[rep.stops[0]].origin[2] + to.eye_height, 16.0 + 1e-9);
    for (size_t i = 1; i < p.frames.size(); ++i) {
      const auto& a = p.frames[i - 1];
      const auto& b = p.frames[i];
      const double step = std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z));
      EXPECT_LE(step, to.speed / to.fps * 1.01 + 1e-9) << map << " frame " << i;
      double turn = std::fabs(b.yaw_deg - a.yaw_deg);
      turn = std::min(turn, 360 - turn);
      EXPECT_LE(turn, 9.0 + 1e-6) << map << " frame " << i;  // pans and turns at most 180 degrees a second
      // The step between frames crosses no wall.
      const std::array<double, 3> pa = {a.x, a.y, a.z}, pb = {b.x, b.y, b.z};
      if (step > 0) {
        const std::array<double, 3> dir = {(b.x - a.x) / step, (b.y - a.y) / step, (b.z - a.z) / step};
        EXPECT_GE(rays.cast(pa, dir, step), step) << map << " frame " << i;
      }
      (void)pb;
    }
  }
}

}  // namespace
