// The walkthrough's view schedule (vds/enc/walk_views.h): the client's
// fixed-point camera projects like the ground truth's; on a tour of oa_dm4
// every visible polygon is served by a held view within the threshold once
// the frame's updates have arrived, updates come at a rate that falls as
// the threshold rises and as slots are added, and a view taken at a frame
// serves that frame itself at a factor of 1.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>
#include <vector>

#include "vds/enc/camera_tour.h"
#include "vds/enc/scene.h"
#include "vds/enc/scene_rays.h"
#include "vds/enc/scene_render.h"
#include "vds/enc/walk_views.h"
#include "vds/homography.h"
#include "walk_tour.h"

namespace {

using Visible = std::vector<std::vector<std::pair<uint32_t, uint32_t>>>;

TEST(WalkViews, TheClientCameraProjectsLikeTheGroundTruth) {
  const vds::enc::CameraPose pose{100, -200, 40, 37, -12};
  const auto c = vds::enc::scene_camera(pose, 90, 240, 180);
  const vds::Camera k = vds::enc::client_camera(pose, 90, 240, 180, 1, 4096);
  ASSERT_EQ(vds::validate_camera(k), vds::Status::ok);
  for (const std::array<double, 3> w : {std::array<double, 3>{400, -100, 60}, {300, -300, 0}, {150, 50, 200}}) {
    double d[3] = {w[0] - c.position[0], w[1] - c.position[1], w[2] - c.position[2]};
    const double z = d[0] * c.forward[0] + d[1] * c.forward[1] + d[2] * c.forward[2];
    const double x = c.cx + c.focal * (d[0] * c.right[0] + d[1] * c.right[1] + d[2] * c.right[2]) / z;
    const double y = c.cy + c.focal * (d[0] * c.down[0] + d[1] * c.down[1] + d[2] * c.down[2]) / z;
    int32_t xq, yq;
    const vds::Vec3<vds::Q16_16> world = {vds::Q16_16::from_raw(static_cast<int32_t>(w[0] * 65536)),
                                          vds::Q16_16::from_raw(static_cast<int32_t>(w[1] * 65536)),
                                          vds::Q16_16::from_raw(static_cast<int32_t>(w[2] * 65536))};
    ASSERT_TRUE(vds::camera_project(k, vds::camera_transform(k, world), &xq, &yq));
    EXPECT_NEAR(xq / 256.0, x, 0.02);
    EXPECT_NEAR(yq / 256.0, y, 0.02);
  }
}

// A quad of two triangles, corners counter-clockwise about `normal`.
void add_quad(vds::enc::Scene& s, const std::array<std::array<float, 3>, 4>& c, const std::array<float, 3>& normal) {
  vds::enc::SceneSurface f;
  f.texture = 0;
  f.first_index = static_cast<uint32_t>(s.indices.size());
  const uint32_t base = static_cast<uint32_t>(s.vertices.size());
  for (const auto& p : c) {
    vds::enc::SceneVertex v;
    v.pos = p;
    v.normal = normal;
    s.vertices.push_back(v);
  }
  for (uint32_t k : {0u, 1u, 2u, 0u, 2u, 3u}) s.indices.push_back(base + k);
  f.index_count = 6;
  s.surfaces.push_back(f);
}

// A scene of one grey texture.
vds::enc::Scene grey_scene() {
  vds::enc::Scene s;
  vds::enc::SceneTexture t;
  t.name = "grey";
  s.textures.push_back(t);
  return s;
}

// A wall at x = 300 facing the origin, and a screen at x = 150 hiding its
// half y > 0 from the origin. Frame 0 looks at the wall from the origin;
// frame 1 from x = 200, in front of the screen, sees the whole wall.
vds::enc::Scene wall_and_screen(vds::enc::CameraPath* path) {
  vds::enc::Scene s = grey_scene();
  add_quad(s, {{{300, 150, -150}, {300, -150, -150}, {300, -150, 150}, {300, 150, 150}}}, {-1, 0, 0});
  add_quad(s, {{{150, 150, -150}, {150, 0, -150}, {150, 0, 150}, {150, 150, 150}}}, {-1, 0, 0});
  path->frames = {{0, 0, 0, 0, 0}, {200, 0, 0, 0, 0}};
  return s;
}

// The visibility buffers of a path for the per-pixel occlusion test: the
// screen and the views (as wide as the screen) at each frame's camera.
vds::enc::WalkViewBuffers buffers_of(const vds::enc::SceneRenderer& r, const vds::enc::CameraPath& path, Visible* vis) {
  vds::enc::WalkViewBuffers b;
  b.step = 2;
  b.width = 120;
  b.height = 90;
  for (const auto& pose : path.frames) {
    const vds::enc::SceneFrame fr = r.render(pose, path.hfov_deg);
    vis->push_back(vds::enc::visible_triangles(fr));
    b.screen_ids.push_back(vds::enc::walk_buffer_samples(fr.ids, 240, 180, 2));
    b.view_ids.push_back(b.screen_ids.back());
    b.view_depth.push_back(vds::enc::walk_buffer_samples(fr.depth, 240, 180, 2));
  }
  return b;
}

TEST(WalkViews, AViewThatSeesAPolygonOnlyPastWhatStandsInFrontOfItDoesNotServeIt) {
  // wall_and_screen: the view taken at frame 0 shows the wall's triangles
  // (half of each): drawn onto frame 1 it would paint the screen onto the
  // wall, so it cannot serve frame 1 and a view update comes there — by
  // shares of area and pixel by pixel.
  vds::enc::CameraPath path;
  const vds::enc::Scene s = wall_and_screen(&path);
  vds::enc::RenderOptions ro;
  ro.supersample = 1;
  const vds::enc::SceneRenderer r(s, {}, ro);
  Visible vis;
  for (const auto& pose : path.frames) vis.push_back(vds::enc::visible_triangles(r.render(pose, path.hfov_deg)));
  // Frame 0 sees both wall triangles, each only in part; frame 1 the wall alone.
  ASSERT_EQ(vis[0].size(), 4u);
  ASSERT_EQ(vis[1].size(), 2u);
  vds::enc::WalkViewOptions o;
  o.slots = 1;
  o.threshold = 100;
  o.lookahead = 0;
  o.occlusion_margin = 0.2;
  o.occlusion_updates = true;
  const auto plan = vds::enc::plan_walk_views(s, path, vis, o);
  ASSERT_EQ(plan.updates[0].size(), 1u);
  ASSERT_EQ(plan.updates[1].size(), 1u);
  EXPECT_EQ(plan.updates[1][0].camera_frame, 1u);
  // Without the test the view of frame 0 serves frame 1.
  o.occlusion_updates = false;
  const auto blind = vds::enc::plan_walk_views(s, path, vis, o);
  EXPECT_TRUE(blind.updates[1].empty());
  // With the test, but as many pixels as the frame has tolerated: no
  // update, and the occluded view still draws the wall.
  o.occlusion_updates = true;
  o.occlusion_tolerance_px = size_t{1} << 30;
  const auto tolerated = vds::enc::plan_walk_views(s, path, vis, o);
  EXPECT_TRUE(tolerated.updates[1].empty());
  ASSERT_EQ(tolerated.choice[1].size(), 2u);
  for (const int8_t c : tolerated.choice[1]) EXPECT_EQ(c, 0);
  // Pixel by pixel (the buffers): the view hides half of the wall's pixels
  // on frame 1's screen, more than the share that makes it occluded and
  // than the 1,000 of them tolerated.
  Visible vis2;
  const vds::enc::WalkViewBuffers b = buffers_of(r, path, &vis2);
  o.occlusion_tolerance_px = 1000;
  const auto per_pixel = vds::enc::plan_walk_views(s, path, vis2, o, nullptr, &b);
  ASSERT_EQ(per_pixel.updates[1].size(), 1u);
  EXPECT_EQ(per_pixel.updates[1][0].camera_frame, 1u);
  // Buffers of another size are refused.
  vds::enc::WalkViewBuffers wrong = b;
  wrong.width = 100;
  EXPECT_THROW(vds::enc::plan_walk_views(s, path, vis2, o, nullptr, &wrong), std::invalid_argument);
}

TEST(WalkViews, PixelByPixelAThinPostCountsTheWallPixelsItHidesAndAnEdgeHidesNone) {
  // A wall at x = 300 standing on a floor at z = -100 (a concave edge
  // where they meet), and a thin post at x = 150 in front of the wall.
  // Frame 0 looks from the origin; frame 1 from x = 200, past the post,
  // turned a little. The view taken at frame 0 hides the wall only behind
  // the post, a few percent of the wall's pixels: not occluded for it,
  // but those pixels are counted against the tolerance. Without the post
  // the view hides nothing on frame 1: the wall's pixels next to the edge
  // (where the floor's plane runs on behind the wall) are not counted.
  const auto scene = [](bool post) {
    vds::enc::Scene s = grey_scene();
    add_quad(s, {{{300, 400, -100}, {300, -400, -100}, {300, -400, 300}, {300, 400, 300}}}, {-1, 0, 0});
    add_quad(s, {{{-100, -400, -100}, {-100, 400, -100}, {300, 400, -100}, {300, -400, -100}}}, {0, 0, 1});
    if (post) add_quad(s, {{{150, 3, -100}, {150, -3, -100}, {150, -3, 300}, {150, 3, 300}}}, {-1, 0, 0});
    return s;
  };
  vds::enc::CameraPath path;
  path.frames = {{0, 0, 0, 0, -10}, {200, 20, 0, 8, -12}};
  vds::enc::RenderOptions ro;
  ro.supersample = 1;
  vds::enc::WalkViewOptions o;
  o.slots = 1;
  o.threshold = 100;
  o.lookahead = 0;
  o.occlusion_updates = true;
  for (const bool post : {false, true}) {
    SCOPED_TRACE(post ? "post" : "no post");
    const vds::enc::Scene s = scene(post);
    const vds::enc::SceneRenderer r(s, {}, ro);
    Visible vis;
    const vds::enc::WalkViewBuffers b = buffers_of(r, path, &vis);
    // The wall's pixels on frame 1.
    size_t wall_px = 0;
    for (const auto& [id, px] : vis[1]) wall_px += id < 2 ? px : 0;
    ASSERT_GT(wall_px, 10000u);
    // Every pixel the view hides counts: the post's are some, the edge's none.
    o.occlusion_tolerance_px = 0;
    const auto strict = vds::enc::plan_walk_views(s, path, vis, o, nullptr, &b);
    ASSERT_EQ(strict.updates[0].size(), 1u);
    EXPECT_EQ(strict.updates[1].size(), post ? 1u : 0u);
    if (!post) continue;
    // Not occluded for the wall (the view hides under a tenth of its
    // pixels): with the post's pixels tolerated, the view draws the wall.
    o.occlusion_tolerance_px = wall_px / 10;
    const auto tolerant = vds::enc::plan_walk_views(s, path, vis, o, nullptr, &b);
    EXPECT_TRUE(tolerant.updates[1].empty());
    for (size_t i = 0; i < vis[1].size(); ++i)
      if (vis[1][i].first < 2) EXPECT_EQ(tolerant.choice[1][i], 0);
  }
}

TEST(WalkViews, PixelByPixelAPolygonIsDrawnFromAViewThatDoesNotHideItOverOneWithASmallerFactor) {
  // A wall at x = 300 and a post at x = 250 in front of its middle. Frame
  // 0 looks at the wall from x = 200, behind the post; frame 1 from x =
  // 100, y = 300, at a slant past it; frame 2 from x = 270, between the
  // post and the wall, sees only the wall's middle. Both views serve frame
  // 2; the one from frame 0 magnifies less (nearer, head on) but sees the
  // post in front of most of that middle: the wall is drawn from the view
  // of frame 1, which the post does not hide.
  vds::enc::Scene s = grey_scene();
  add_quad(s, {{{300, 150, -150}, {300, -150, -150}, {300, -150, 150}, {300, 150, 150}}}, {-1, 0, 0});
  add_quad(s, {{{250, 15, -150}, {250, -15, -150}, {250, -15, 150}, {250, 15, 150}}}, {-1, 0, 0});
  vds::enc::CameraPath path;
  path.frames = {{200, 0, 0, 0, 0}, {100, 300, 0, -56.3, 0}, {270, 0, 0, 0, 0}};
  vds::enc::RenderOptions ro;
  ro.supersample = 1;
  const vds::enc::SceneRenderer r(s, {}, ro);
  Visible vis;
  const vds::enc::WalkViewBuffers b = buffers_of(r, path, &vis);
  // Frame 2 shows the wall's two triangles and not the post.
  ASSERT_EQ(vis[2].size(), 2u);
  for (const auto& [id, px] : vis[2]) ASSERT_LT(id, 2u);
  vds::enc::WalkViewOptions o;
  o.slots = 2;
  o.threshold = 100;
  o.lookahead = 0;
  o.occlusion_updates = true;
  o.occlusion_tolerance_px = size_t{1} << 30;  // no updates for occlusion: the views held are frame 0's and 1's
  const auto plan = vds::enc::plan_walk_views(s, path, vis, o, nullptr, &b);
  ASSERT_EQ(plan.updates[0].size(), 1u);
  ASSERT_EQ(plan.updates[1].size(), 1u);
  ASSERT_TRUE(plan.updates[2].empty());
  const int8_t slot_of_frame1 = static_cast<int8_t>(plan.updates[1][0].slot);
  for (const int8_t c : plan.choice[2]) EXPECT_EQ(c, slot_of_frame1);
  // By shares of area the view of frame 0 sees most of each wall triangle
  // (the post hides a fifth of what it shows of them): it is not
  // occluded, and its smaller factor wins.
  o.occlusion_margin = 0.5;
  const auto by_area = vds::enc::plan_walk_views(s, path, vis, o);
  ASSERT_EQ(by_area.updates[1].size(), 1u);
  for (const int8_t c : by_area.choice[2]) EXPECT_NE(c, static_cast<int8_t>(by_area.updates[1][0].slot));
}

TEST(WalkViews, ATourOfOaDm4IsServedWithinTheThreshold) {
  const vds::test::TourVisibility tv = vds::test::tour_visibility("oa_dm4", 200);
  const vds::enc::Scene& s = tv.scene;
  const vds::enc::CameraPath& path = tv.path;
  const Visible& vis = tv.visible;
  std::map<std::pair<int, double>, size_t> updates;
  for (int slots : {1, 2, 3})
    for (double threshold : {1.0, 1.35, 2.0}) {
      vds::enc::WalkViewOptions o;
      o.slots = slots;
      o.threshold = threshold;
      const auto p = vds::enc::plan_walk_views(s, path, vis, o);
      size_t n = 0;
      for (const auto& u : p.updates) n += u.size();
      updates[{slots, threshold}] = n;
      EXPECT_EQ(p.pixels_unserved, 0u);
      EXPECT_EQ(p.pixels_within, p.pixels);
      ASSERT_FALSE(p.updates[0].empty());
      EXPECT_EQ(p.updates[0][0].slot, 0u);
      std::printf("oa_dm4, 200 frames: %d slots, threshold %.2f: %zu view updates (%.2f a second), %.1f %% of pixels unmagnified\n",
                  slots, threshold, n, n * path.fps / path.frames.size(), 100.0 * p.pixels_sharp / p.pixels);
    }
  for (int slots : {1, 2, 3}) {
    const size_t at1 = updates[{slots, 1.0}], at135 = updates[{slots, 1.35}], at2 = updates[{slots, 2.0}];
    EXPECT_GE(at1, at135);
    EXPECT_GE(at135, at2);
  }
  // A view at a frame's own camera serves it at a factor of 1 (polygons wholly in front of the camera).
  const auto& pose = path.frames[50];
  const vds::Camera k = vds::enc::client_camera(pose, path.hfov_deg, 240, 180, 1, 4096);
  size_t whole = 0;
  for (const auto& [id, px] : vis[50]) {
    vds::Vec3<vds::Q16_16> poly[3];
    for (int j = 0; j < 3; ++j) {
      const auto& p = s.vertices[s.indices[3 * id + static_cast<uint32_t>(j)]].pos;
      poly[j] = {vds::Q16_16::from_raw(static_cast<int32_t>(std::lround(p[0] * 65536))),
                 vds::Q16_16::from_raw(static_cast<int32_t>(std::lround(p[1] * 65536))),
                 vds::Q16_16::from_raw(static_cast<int32_t>(std::lround(p[2] * 65536)))};
    }
    vds::Q16_16 q;
    if (vds::texture_quality(k, k, poly, 3, &q) != vds::Status::ok || q == vds::Q16_16::max()) continue;
    ++whole;
    EXPECT_NEAR(q.raw() / 65536.0, 1.0, 1e-3) << id;
  }
  EXPECT_GT(whole, 10u);
}

}  // namespace
