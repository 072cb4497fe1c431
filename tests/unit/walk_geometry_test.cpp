// The walkthrough's geometry schedule (vds/enc/walk_geometry.h): a worked
// example; on random visibility, a client replaying the sends holds every
// hot polygon in the slot the plan names, never more than its slots, and
// resends no more than a least-recently-used cache would; on a tour of
// oa_dm4, the schedule the ground truth's visibility gives.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <list>
#include <set>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include "vds/enc/camera_tour.h"
#include "vds/enc/scene.h"
#include "vds/enc/scene_rays.h"
#include "vds/enc/scene_render.h"
#include "vds/arena.h"
#include "vds/enc/walk_geometry.h"
#include "vds/walk_geometry.h"
#include "walk_tour.h"
#include "xorshift.h"

namespace {

using vds::enc::plan_walk_geometry;
using Visible = std::vector<std::vector<uint32_t>>;

TEST(WalkGeometry, AWorkedExample) {
  // Two slots. Frame 1 needs 3: polygon 1 (next hot at frame 3) goes before
  // polygon 2 (hot now). Frame 2 needs 4: 2 is never hot again. Frame 3
  // needs 1 again: 3 and 4 are never hot again; the slot after the last
  // send's (slot 1, frame 2) goes: slot 0, wrapping round.
  const auto p = plan_walk_geometry({{1, 2}, {2, 3}, {3, 4}, {1}}, 2, 0);
  ASSERT_EQ(p.sends.size(), 4u);
  ASSERT_EQ(p.sends[0].size(), 2u);
  EXPECT_EQ(p.sends[0][0].id, 1u);
  EXPECT_EQ(p.sends[0][0].slot, 0u);
  EXPECT_EQ(p.sends[0][1].slot, 1u);
  ASSERT_EQ(p.sends[1].size(), 1u);
  EXPECT_EQ(p.sends[1][0].id, 3u);
  EXPECT_EQ(p.sends[1][0].slot, 0u);
  ASSERT_EQ(p.sends[2].size(), 1u);
  EXPECT_EQ(p.sends[2][0].id, 4u);
  EXPECT_EQ(p.sends[2][0].slot, 1u);
  ASSERT_EQ(p.sends[3].size(), 1u);
  EXPECT_EQ(p.sends[3][0].id, 1u);
  EXPECT_EQ(p.sends[3][0].slot, 0u);
  EXPECT_EQ(p.first_sends, 4u);
  EXPECT_EQ(p.resends, 1u);
  EXPECT_EQ(p.hot[3], std::vector<uint32_t>{0});
  // A window of one frame makes frame 1 need 1, 2, 3 and 4 at once.
  EXPECT_THROW(plan_walk_geometry({{1, 2}, {2, 3}, {3, 4}, {1}}, 3, 1), std::runtime_error);
  EXPECT_EQ(plan_walk_geometry({{1, 2}, {2, 3}, {3, 4}, {1}}, 4, 1).peak_hot, 4u);
}

// Resends of a cache that evicts the least recently hot polygon (what a
// client deciding for itself could do).
size_t lru_resends(const Visible& hot, size_t slots) {
  std::list<uint32_t> order;  // most recent first
  std::set<uint32_t> seen;
  size_t resends = 0;
  for (const auto& frame : hot) {
    for (uint32_t id : frame) {
      auto it = std::find(order.begin(), order.end(), id);
      if (it != order.end()) {
        order.erase(it);
      } else {
        if (seen.count(id)) ++resends;
        seen.insert(id);
        // Evict the least recent one not hot now.
        if (order.size() == slots) {
          for (auto r = order.rbegin(); r != order.rend(); ++r)
            if (std::find(frame.begin(), frame.end(), *r) == frame.end()) {
              order.erase(std::next(r).base());
              break;
            }
        }
      }
      order.push_front(id);
    }
  }
  return resends;
}

TEST(WalkGeometry, AClientReplayingTheSendsHoldsEveryHotPolygon) {
  vds::test::Xorshift32 rng;
  size_t total_moved = 0;
  for (int round = 0; round < 40; ++round) {
    // A walk: polygons come into view and leave, some come back.
    Visible vis(120);
    const uint32_t pool = 40 + rng.next() % 200;
    uint32_t centre = 0;
    for (auto& f : vis) {
      centre += rng.next() % 3;
      for (int k = 0; k < 12; ++k) f.push_back((centre + rng.next() % 25) % pool);
      std::sort(f.begin(), f.end());
      f.erase(std::unique(f.begin(), f.end()), f.end());
    }
    const int window = static_cast<int>(rng.next() % 3);
    const auto probe = plan_walk_geometry(vis, 1u << 20, window);
    const uint32_t slots = static_cast<uint32_t>(probe.peak_hot + rng.next() % 20);
    const auto p = plan_walk_geometry(vis, slots, window);
    // The same with bursts spread: sends ahead of their frame, never drawn
    // where they are sent.
    const size_t limit = 1 + rng.next() % 6;
    const auto spread = plan_walk_geometry(vis, slots, window, limit);
    Visible hot_ids(vis.size());
    size_t sends = 0, moved = 0;
    for (const auto* plan : {&p, &spread}) {
      std::vector<uint32_t> client(slots, std::numeric_limits<uint32_t>::max());
      for (size_t f = 0; f < vis.size(); ++f) {
        for (const auto& s : plan->sends[f]) {
          ASSERT_LT(s.slot, slots);
          client[s.slot] = s.id;
          if (plan == &p) ++sends;
          if (!s.hot) {
            ++moved;
            ASSERT_FALSE(std::binary_search(plan->hot[f].begin(), plan->hot[f].end(), s.slot)) << "round " << round;
          }
        }
        // The hot slots hold exactly the polygons visible within the window.
        std::set<uint32_t> want;
        for (size_t g = f >= static_cast<size_t>(window) ? f - window : 0; g <= std::min(vis.size() - 1, f + window); ++g)
          want.insert(vis[g].begin(), vis[g].end());
        std::set<uint32_t> got;
        for (uint32_t s : plan->hot[f]) got.insert(client[s]);
        ASSERT_EQ(got, want) << "round " << round << " frame " << f << (plan == &p ? "" : " (spread)");
        hot_ids[f].assign(want.begin(), want.end());
      }
    }
    total_moved += moved;
    EXPECT_EQ(sends, p.first_sends + p.resends);
    EXPECT_LE(p.resends, lru_resends(hot_ids, slots)) << "round " << round;
    // Slots for every polygon: nothing is sent twice.
    EXPECT_EQ(plan_walk_geometry(vis, pool, window).resends, 0u);
  }
  EXPECT_GT(total_moved, 0u);  // the limit moved sends ahead
}

TEST(WalkGeometry, TheScheduleOfATourOfOaDm4) {
  const vds::test::TourVisibility tv = vds::test::tour_visibility("oa_dm4", 300);
  Visible vis;
  for (const auto& frame : tv.visible) {
    vis.emplace_back();
    for (const auto& [id, px] : frame) vis.back().push_back(id);
  }
  const auto all = plan_walk_geometry(vis, 1u << 20, 2);
  const auto tight = plan_walk_geometry(vis, static_cast<uint32_t>(all.peak_hot), 2);
  std::printf("oa_dm4, 300 frames, window 2: %zu triangles sent, peak hot %zu; with %zu slots %zu resent\n",
              all.first_sends, all.peak_hot, all.peak_hot, tight.resends);
  EXPECT_EQ(all.resends, 0u);
  EXPECT_EQ(tight.first_sends, all.first_sends);
  EXPECT_LT(all.peak_hot, 600u);  // a cache of a few hundred triangles draws the tour
}

}  // namespace

namespace {

// The geometry records of a plan (each a payload of its own), with the scene's triangles as the sends.
struct CodedPlan {
  std::vector<std::vector<uint8_t>> chunks;
  std::vector<std::vector<std::array<std::array<double, 3>, 3>>> sent;  // per frame, per send
};

int32_t kQuantum = 65536 / 8;  // 1/8 map unit, or what choose_walk_quantum finds

CodedPlan code_plan(const vds::enc::Scene& s, const vds::enc::WalkGeometryPlan& p) {
  vds::enc::WalkGeometryEncoder enc(p.slots, kQuantum);
  CodedPlan out;
  for (size_t f = 0; f < p.sends.size(); ++f) {
    std::vector<vds::enc::WalkGeometryEncoder::Send> sends;
    for (const auto& snd : p.sends[f]) {
      vds::enc::WalkGeometryEncoder::Send e{snd.slot, true, {}};
      for (int c = 0; c < 3; ++c)
        for (int a = 0; a < 3; ++a)
          e.vertices[static_cast<size_t>(c)][static_cast<size_t>(a)] =
              s.vertices[s.indices[3 * snd.id + static_cast<uint32_t>(c)]].pos[static_cast<size_t>(a)];
      sends.push_back(e);
    }
    out.chunks.push_back(enc.encode(sends, p.hot[f]));
  }
  return out;
}

TEST(WalkGeometryRecord, TheClientHoldsWhatThePlanSaysOnATourOfOaDm4) {
  const vds::test::TourVisibility tv = vds::test::tour_visibility("oa_dm4", 300);
  Visible vis;
  for (const auto& frame : tv.visible) {
    vis.emplace_back();
    for (const auto& [id, px] : frame) vis.back().push_back(id);
  }
  const auto probe = plan_walk_geometry(vis, 1u << 14, 2);
  const auto plan = plan_walk_geometry(vis, static_cast<uint32_t>(probe.peak_hot + 16), 2);
  kQuantum = vds::enc::choose_walk_quantum(tv.scene, 1.0 / 16);
  const CodedPlan coded = code_plan(tv.scene, plan);
  std::vector<uint8_t> work(vds::WalkGeometry::workspace_bytes(plan.slots));
  vds::Arena arena(work.data(), work.size());
  vds::WalkGeometry client;
  ASSERT_EQ(client.init(arena, plan.slots, kQuantum), vds::Status::ok);
  std::vector<uint32_t> held(plan.slots, UINT32_MAX);
  size_t bytes = 0;
  for (size_t f = 0; f < coded.chunks.size(); ++f) {
    bytes += coded.chunks[f].size();
    ASSERT_EQ(client.consume(coded.chunks[f].data(), static_cast<uint32_t>(coded.chunks[f].size())), vds::Status::ok) << f;
    for (const auto& snd : plan.sends[f]) held[snd.slot] = snd.id;
    ASSERT_EQ(std::vector<uint32_t>(client.hot(), client.hot() + client.hot_count()), plan.hot[f]) << "frame " << f;
    for (uint32_t slot : plan.hot[f]) {
      const auto* t = client.triangle(slot);
      ASSERT_NE(t, nullptr);
      // The scene's triangle, on the grid (each vertex within the
      // tolerance), its winding kept: the encoder may turn it so that an
      // edge it shares with the triangle before it comes first.
      int turns = 0;
      for (int turn = 0; turn < 3; ++turn) {
        bool same = true;
        for (int c = 0; c < 3; ++c) {
          const auto& v = tv.scene.vertices[tv.scene.indices[3 * held[slot] + static_cast<uint32_t>((c + turn) % 3)]].pos;
          same = same && std::fabs(t[c].x.raw() / 65536.0 - v[0]) <= 1.0 / 16 + 1e-9 &&
                 std::fabs(t[c].y.raw() / 65536.0 - v[1]) <= 1.0 / 16 + 1e-9 && std::fabs(t[c].z.raw() / 65536.0 - v[2]) <= 1.0 / 16 + 1e-9;
        }
        turns += same;
      }
      EXPECT_GE(turns, 1) << "frame " << f << " slot " << slot;
    }
  }
  // Each slot's quad with the next (joins_next) is walk_quad of what both
  // hold now, kept as sends replace either; most of a map's triangles
  // pair up (rectangles sent as two triangles).
  uint32_t joined = 0, filled = 0;
  for (uint32_t slot = 0; slot < plan.slots; ++slot) {
    const auto* a = client.triangle(slot);
    const auto* b = slot + 1 < plan.slots ? client.triangle(slot + 1) : nullptr;
    filled += a != nullptr;
    const uint8_t want = a && b ? vds::walk_quad(a, b, kQuantum) : 0;
    ASSERT_EQ(client.joins_next(slot), want) << "slot " << slot;
    joined += want != 0;
  }
  EXPECT_GT(joined * 5, filled) << joined << " of " << filled << " slots join the next";
  const double kbps = bytes * 8.0 / (coded.chunks.size() / tv.path.fps) / 1000;
  std::printf("oa_dm4, 300 frames: %zu triangles in %u slots, %zu bytes of geometry (%.2f kbit/s, %.1f bits a triangle sent)\n",
              plan.first_sends + plan.resends, plan.slots, bytes, kbps, bytes * 8.0 / (plan.first_sends + plan.resends));
  EXPECT_LT(kbps, 3.0);  // measured 2.24 kbit/s (docs/walkthrough.md)
}

// Two triangles make one quad when they share an edge, lie in one plane
// (within the tolerance) and turn one way at all four corners; the code
// names the outline. Large coordinates do not overflow.
TEST(WalkQuad, RectanglesInAnyPlaneJoinDartsAndFoldsDoNot) {
  using P = vds::Vec3<vds::Q16_16>;
  const auto at = [](double x, double y, double z) {
    return P{vds::Q16_16::from_raw(static_cast<int32_t>(std::lround(x * 65536))),
             vds::Q16_16::from_raw(static_cast<int32_t>(std::lround(y * 65536))),
             vds::Q16_16::from_raw(static_cast<int32_t>(std::lround(z * 65536)))};
  };
  const auto same = [](const P& p, const P& q) { return p.x.raw() == q.x.raw() && p.y.raw() == q.y.raw() && p.z.raw() == q.z.raw(); };
  // The outline a code names: a[i], b[j], a[i + 1], a[i + 2].
  const auto outline = [](const P* a, const P* b, uint8_t code) {
    const int i = (code - 1) / 3, j = (code - 1) % 3;
    return std::array<P, 4>{a[i], b[j], a[(i + 1) % 3], a[(i + 2) % 3]};
  };
  // A rectangle in z = 5 split along its diagonal, either way round.
  const P a[3] = {at(0, 0, 5), at(4, 0, 5), at(4, 3, 5)};
  const P b[3] = {at(0, 0, 5), at(4, 3, 5), at(0, 3, 5)};
  const uint8_t q = vds::walk_quad(a, b, 4096);
  ASSERT_EQ(q, 1 + 3 * 2 + 2);
  const auto o = outline(a, b, q);
  EXPECT_TRUE(same(o[0], a[2]) && same(o[1], b[2]) && same(o[2], a[0]) && same(o[3], a[1]));
  EXPECT_NE(vds::walk_quad(b, a, 4096), 0);
  // The third corner off the plane: by less than the tolerance, by more.
  const P near_b[3] = {b[0], b[1], at(0, 3, 5 + 1.0 / 32)};
  const P off_b[3] = {b[0], b[1], at(0, 3, 5.25)};
  EXPECT_NE(vds::walk_quad(a, near_b, 4096), 0);
  EXPECT_EQ(vds::walk_quad(a, off_b, 4096), 0);
  // A dart (concave at b's third corner), a fold over the shared edge,
  // one shared corner only, and the same triangle twice.
  const P dart[3] = {at(4, 3, 5), at(0, 0, 5), at(3, 1, 5)};
  EXPECT_EQ(vds::walk_quad(a, dart, 4096), 0);
  const P fold[3] = {at(0, 0, 5), at(4, 3, 5), at(4, -3, 5)};
  EXPECT_EQ(vds::walk_quad(a, fold, 4096), 0);
  const P corner[3] = {at(0, 0, 5), at(-4, 0, 5), at(-4, -3, 5)};
  EXPECT_EQ(vds::walk_quad(a, corner, 4096), 0);
  EXPECT_EQ(vds::walk_quad(a, a, 4096), 0);
  // Rectangles in random planes far from the origin, on a 1/16 grid:
  // their halves join (within the grid's rounding), and not once a
  // corner leaves the plane by 40 grid steps.
  vds::test::Xorshift32 rng{99};
  const auto uni = [&](double lo, double hi) { return lo + (hi - lo) * (rng.next() % 1000001) / 1e6; };
  int joined = 0;
  for (int trial = 0; trial < 200; ++trial) {
    double u[3] = {uni(-1, 1), uni(-1, 1), uni(-1, 1)}, w[3] = {uni(-1, 1), uni(-1, 1), uni(-1, 1)};
    const double nu = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (double& c : u) c /= nu;
    const double d = w[0] * u[0] + w[1] * u[1] + w[2] * u[2];
    for (int c = 0; c < 3; ++c) w[c] -= d * u[c];
    const double nw = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    if (nw < 0.1) continue;
    for (double& c : w) c /= nw;
    const double o3[3] = {uni(-20000, 20000), uni(-20000, 20000), uni(-20000, 20000)};
    const double su = uni(8, 400), sw = uni(8, 400);
    const auto corner_at = [&](double s, double t, double lift) {
      const double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
      double p[3];
      for (int c = 0; c < 3; ++c) p[c] = std::round((o3[c] + s * u[c] + t * w[c] + lift * n[c]) * 16) / 16;
      return at(p[0], p[1], p[2]);
    };
    const P ta[3] = {corner_at(0, 0, 0), corner_at(su, 0, 0), corner_at(su, sw, 0)};
    const P tb[3] = {corner_at(0, 0, 0), corner_at(su, sw, 0), corner_at(0, sw, 0)};
    const P lifted[3] = {tb[0], tb[1], corner_at(0, sw, 40.0 / 16)};
    const uint8_t code = vds::walk_quad(ta, tb, 4096);
    joined += code != 0;
    EXPECT_EQ(vds::walk_quad(ta, lifted, 4096), 0) << "trial " << trial;
  }
  EXPECT_GE(joined, 150);
}

TEST(WalkGeometryRecord, PrefixesAndGarbageAreRefused) {
  // A small plan coded, then each frame's every prefix given to a client
  // that has read the frames before it.
  kQuantum = 65536 / 8;
  const Visible vis = {{1, 2, 3}, {2, 3, 4, 5}, {4, 5, 6}, {1, 6}, {7}};
  const auto plan = plan_walk_geometry(vis, 6, 0);
  vds::enc::Scene s;
  for (uint32_t i = 0; i < 8 * 3; ++i) {
    vds::enc::SceneVertex v;
    v.pos = {static_cast<float>(i * 3 % 17), static_cast<float>(i * 5 % 13), static_cast<float>(i)};
    s.vertices.push_back(v);
    s.indices.push_back(i);
  }
  const CodedPlan coded = code_plan(s, plan);
  size_t prefixes = 0, accepted = 0;
  for (size_t f = 0; f < coded.chunks.size(); ++f) {
    for (size_t n = 0; n < coded.chunks[f].size(); ++n) {
      std::vector<uint8_t> work(vds::WalkGeometry::workspace_bytes(plan.slots));
      vds::Arena arena(work.data(), work.size());
      vds::WalkGeometry client;
      ASSERT_EQ(client.init(arena, plan.slots, kQuantum), vds::Status::ok);
      for (size_t g = 0; g < f; ++g)
        ASSERT_EQ(client.consume(coded.chunks[g].data(), static_cast<uint32_t>(coded.chunks[g].size())), vds::Status::ok);
      // Refused, or read as if the missing bytes were the coder's end
      // padding (the chunk's length and CRC guard a payload's end); either
      // way every hot slot holds a triangle.
      if (client.consume(coded.chunks[f].data(), static_cast<uint32_t>(n)) == vds::Status::ok) {
        ++accepted;
        for (uint32_t i = 0; i < client.hot_count(); ++i) ASSERT_NE(client.triangle(client.hot()[i]), nullptr);
      }
      ++prefixes;
    }
  }
  EXPECT_LT(accepted * 4, prefixes) << accepted << " of " << prefixes << " prefixes read";
  // Random bytes: a status, never a crash; a hot slot always holds a triangle.
  vds::test::Xorshift32 rng;
  for (int round = 0; round < 2000; ++round) {
    std::vector<uint8_t> work(vds::WalkGeometry::workspace_bytes(64));
    vds::Arena arena(work.data(), work.size());
    vds::WalkGeometry client;
    ASSERT_EQ(client.init(arena, 64, kQuantum), vds::Status::ok);
    for (int f = 0; f < 4; ++f) {
      std::vector<uint8_t> junk(1 + rng.next() % 40);
      for (auto& b : junk) b = static_cast<uint8_t>(rng.next());
      if (client.consume(junk.data(), static_cast<uint32_t>(junk.size())) != vds::Status::ok) break;
      for (uint32_t i = 0; i < client.hot_count(); ++i) ASSERT_NE(client.triangle(client.hot()[i]), nullptr);
    }
  }
}

TEST(WalkGeometryRecord, ACornerMadeOfCoordinatesNamedBeforeCostsLessThanANewOne) {
  // Axis-aligned rooms repeat a few coordinates on each axis: a vertex
  // that is new as a point but whose x, y and z were each named lately
  // (among the last kWalkAxisValues distinct values of their axis) is
  // named by three short places, and arrives exactly where it was.
  constexpr int32_t kQ = 65536 / 8;
  const double xs[] = {0, 64.5, 192, 320.125}, ys[] = {-256, 0, 128}, zs[] = {0, 96, 200.25};
  std::vector<vds::enc::WalkGeometryEncoder::Send> base;
  vds::test::Xorshift32 rng;
  for (uint32_t i = 0; i < 12; ++i) {
    vds::enc::WalkGeometryEncoder::Send snd{i, true, {}};
    for (auto& v : snd.vertices) v = {xs[rng.next() % 4], ys[rng.next() % 3], zs[rng.next() % 3]};
    base.push_back(snd);
  }
  const auto cost = [&](const std::array<double, 3>& corner) {
    auto sends = base;
    vds::enc::WalkGeometryEncoder::Send last{12, true, {}};
    last.vertices = {{{1000, 1000, 1000}, {1016, 1000, 1000}, corner}};
    sends.push_back(last);
    std::vector<uint32_t> hot(13);
    for (uint32_t i = 0; i < 13; ++i) hot[i] = i;
    const auto head = vds::enc::WalkGeometryEncoder(13, kQ).encode(base, std::vector<uint32_t>(hot.begin(), hot.end() - 1));
    const auto all = vds::enc::WalkGeometryEncoder(13, kQ).encode(sends, hot);
    std::vector<uint8_t> work(vds::WalkGeometry::workspace_bytes(13));
    vds::Arena arena(work.data(), work.size());
    vds::WalkGeometry client;
    EXPECT_EQ(client.init(arena, 13, kQ), vds::Status::ok);
    EXPECT_EQ(client.consume(all.data(), static_cast<uint32_t>(all.size())), vds::Status::ok);
    const auto* t = client.triangle(12);
    EXPECT_NE(t, nullptr);
    if (t != nullptr) {
      EXPECT_EQ(t[2].x.raw(), static_cast<int32_t>(std::lround(corner[0] * 65536)));
      EXPECT_EQ(t[2].y.raw(), static_cast<int32_t>(std::lround(corner[1] * 65536)));
      EXPECT_EQ(t[2].z.raw(), static_cast<int32_t>(std::lround(corner[2] * 65536)));
    }
    return static_cast<double>(all.size()) - static_cast<double>(head.size());
  };
  const double seen = cost({xs[3], ys[0], zs[2]});
  const double fresh = cost({-1187.375, 733.625, -419.875});
  std::printf("a corner of coordinates named before: %.0f bytes a triangle, of new ones: %.0f\n", seen, fresh);
  EXPECT_LT(seen + 2, fresh);
}

TEST(WalkGeometryRecord, AVertexNamedAgainComesFromTheRingUpToItsSize) {
  // A frame of 400 triangles with distinct random vertices, then, a
  // triangle whose vertices are those of triangle k (sent 3 * (399 - k)
  // vertices back): from the ring while they are within it — far fewer
  // bits than new positions — and always at the right place.
  constexpr int32_t kQ = 65536 / 8;
  vds::test::Xorshift32 rng;
  std::vector<vds::enc::WalkGeometryEncoder::Send> base;
  for (uint32_t i = 0; i < 400; ++i) {
    vds::enc::WalkGeometryEncoder::Send snd{i, true, {}};
    for (auto& v : snd.vertices)
      for (double& c : v) c = static_cast<double>(rng.next() % 4096) - 2048 + (rng.next() % 8) / 8.0;
    base.push_back(snd);
  }
  const auto cost = [&](uint32_t k, bool check) {
    auto sends = base;
    auto again = base[k];
    again.slot = 400;
    sends.push_back(again);
    vds::enc::WalkGeometryEncoder enc(401, kQ);
    std::vector<uint32_t> hot(401);
    for (uint32_t i = 0; i < 401; ++i) hot[i] = i;
    const auto head = vds::enc::WalkGeometryEncoder(401, kQ).encode(base, std::vector<uint32_t>(hot.begin(), hot.end() - 1));
    const auto all = enc.encode(sends, hot);
    if (check) {
      std::vector<uint8_t> work(vds::WalkGeometry::workspace_bytes(401));
      vds::Arena arena(work.data(), work.size());
      vds::WalkGeometry client;
      EXPECT_EQ(client.init(arena, 401, kQ), vds::Status::ok);
      EXPECT_EQ(client.consume(all.data(), static_cast<uint32_t>(all.size())), vds::Status::ok);
      const auto* t = client.triangle(400);
      EXPECT_NE(t, nullptr);
      if (t != nullptr)
        for (int c = 0; c < 3; ++c) EXPECT_EQ(t[c].x.raw(), static_cast<int32_t>(std::lround(again.vertices[static_cast<size_t>(c)][0] * 65536)));
    }
    return static_cast<double>(all.size()) - static_cast<double>(head.size());
  };
  const double fresh = [&] {
    // A triangle of new vertices, for comparison.
    auto sends = base;
    vds::enc::WalkGeometryEncoder::Send snd{400, true, {}};
    for (auto& v : snd.vertices)
      for (double& c : v) c = static_cast<double>(rng.next() % 4096) - 2048;
    sends.push_back(snd);
    std::vector<uint32_t> hot(401);
    for (uint32_t i = 0; i < 401; ++i) hot[i] = i;
    const auto head = vds::enc::WalkGeometryEncoder(401, kQ).encode(base, std::vector<uint32_t>(hot.begin(), hot.end() - 1));
    return static_cast<double>(vds::enc::WalkGeometryEncoder(401, kQ).encode(sends, hot).size()) - static_cast<double>(head.size());
  }();
  // Triangle 399 is 3 vertices back, 100 is 900 back (inside the ring of
  // 1024), 10 is 1170 back (fallen out of it).
  const double near = cost(399, true), inside = cost(100, true), outside = cost(10, true);
  std::printf("a triangle named again: 3 back %.0f bytes, 900 back %.0f, 1170 back %.0f; new vertices %.0f\n", near, inside, outside, fresh);
  EXPECT_LE(inside * 2, fresh);
  EXPECT_LE(near, inside);
  EXPECT_GT(outside, inside * 2);
}

}  // namespace
