// The walkthrough's geometry schedule (vds/enc/walk_geometry.h): a worked
// example; on random visibility, a client replaying the sends holds every
// hot polygon in the slot the plan names, never more than its slots, and
// resends no more than a least-recently-used cache would; on a tour of
// oa_dm4, the schedule the ground truth's visibility gives.
#include <gtest/gtest.h>

#include <algorithm>
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
#include "vds/enc/walk_geometry.h"
#include "walk_tour.h"
#include "xorshift.h"

namespace {

using vds::enc::plan_walk_geometry;
using Visible = std::vector<std::vector<uint32_t>>;

TEST(WalkGeometry, AWorkedExample) {
  // Two slots. Frame 1 needs 3: polygon 1 (next hot at frame 3) goes before
  // polygon 2 (hot now). Frame 2 needs 4: 2 is never hot again. Frame 3
  // needs 1 again: 3 and 4 are never hot again; the higher slot goes.
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
  EXPECT_EQ(p.sends[3][0].slot, 1u);
  EXPECT_EQ(p.first_sends, 4u);
  EXPECT_EQ(p.resends, 1u);
  EXPECT_EQ(p.hot[3], std::vector<uint32_t>{1});
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
    std::vector<uint32_t> client(slots, std::numeric_limits<uint32_t>::max());
    size_t sends = 0;
    Visible hot_ids(vis.size());
    for (size_t f = 0; f < vis.size(); ++f) {
      for (const auto& s : p.sends[f]) {
        ASSERT_LT(s.slot, slots);
        client[s.slot] = s.id;
        ++sends;
      }
      // The hot slots hold exactly the polygons visible within the window.
      std::set<uint32_t> want;
      for (size_t g = f >= static_cast<size_t>(window) ? f - window : 0; g <= std::min(vis.size() - 1, f + window); ++g)
        want.insert(vis[g].begin(), vis[g].end());
      std::set<uint32_t> got;
      for (uint32_t s : p.hot[f]) got.insert(client[s]);
      ASSERT_EQ(got, want) << "round " << round << " frame " << f;
      hot_ids[f].assign(want.begin(), want.end());
    }
    EXPECT_EQ(sends, p.first_sends + p.resends);
    EXPECT_LE(p.resends, lru_resends(hot_ids, slots)) << "round " << round;
    // Slots for every polygon: nothing is sent twice.
    EXPECT_EQ(plan_walk_geometry(vis, pool, window).resends, 0u);
  }
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
