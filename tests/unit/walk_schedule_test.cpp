// A walkthrough's schedule (vds/enc/walk_schedule.h): arrivals worked out by
// hand, the window holding back what a held record leaves no room for, and
// the least pre-roll.
#include <gtest/gtest.h>

#include <vector>

#include "vds/enc/walk_schedule.h"

namespace {

using vds::enc::WalkLink;
using vds::enc::WalkPiece;

// 1000 bytes a second, 20 frames a second: a 100-byte header, a record of
// frames 0..7 (100 bytes), a 1000-byte view needed by frame 8, then a
// record of frames 8..15.
std::vector<WalkPiece> pieces() { return {{100, 0, 0, false}, {100, 0, 7, true}, {1000, 8, 8, false}, {100, 8, 15, true}}; }

TEST(WalkSchedule, ArrivalsFollowTheRateWhenTheWindowHasRoom) {
  WalkLink l;
  l.rate_bytes = 1000;
  l.buffer_bytes = 1100;  // the view and the next record fit beside the held record
  l.frame_period_s = 0.05;
  const auto a = vds::enc::walk_arrivals(pieces(), l, 0.9);
  ASSERT_EQ(a.size(), 4u);
  EXPECT_DOUBLE_EQ(a[0], 0.1);
  EXPECT_DOUBLE_EQ(a[1], 0.2);
  EXPECT_DOUBLE_EQ(a[2], 1.2);
  EXPECT_DOUBLE_EQ(a[3], 1.3);
  // Frame 8 is due at 0.9 + 0.4 s: its record arrives just in time.
  EXPECT_NEAR(vds::enc::walk_lateness_s(pieces(), l, 0.9), 0, 1e-12);
  EXPECT_EQ(vds::enc::walk_preroll_ms(pieces(), l, 600000), 900u);
  // The link's framing delays every byte: the pre-roll grows by as much.
  l.latency_s = 0.25;
  EXPECT_DOUBLE_EQ(vds::enc::walk_arrivals(pieces(), l, 1.15)[3], 1.55);
  EXPECT_EQ(vds::enc::walk_preroll_ms(pieces(), l, 600000), 1150u);
}

TEST(WalkSchedule, AHeldRecordHoldsBackWhatItsWindowHasNoRoomFor) {
  WalkLink l;
  l.rate_bytes = 1000;
  l.buffer_bytes = 800;
  l.frame_period_s = 0.05;
  // The client holds the first record until frame 7 is due (p + 0.35 s);
  // the view's last 200 bytes wait for that, then take 0.2 s, and the next
  // record 0.1 s more.
  const double p = 2.0;
  const auto a = vds::enc::walk_arrivals(pieces(), l, p);
  EXPECT_DOUBLE_EQ(a[2], p + 0.35 + 0.2);
  EXPECT_DOUBLE_EQ(a[3], p + 0.35 + 0.3);
  // Frame 8 is due one period after frame 7: no pre-roll is enough.
  EXPECT_GT(vds::enc::walk_lateness_s(pieces(), l, p), 0.2);
  EXPECT_EQ(vds::enc::walk_preroll_ms(pieces(), l, 600000), UINT32_MAX);
  // What one period brings after the release (50 bytes) may wait; a byte
  // more may not.
  l.buffer_bytes = 1050;
  EXPECT_EQ(vds::enc::walk_preroll_ms(pieces(), l, 600000), 900u);
  l.buffer_bytes = 1049;
  EXPECT_EQ(vds::enc::walk_preroll_ms(pieces(), l, 600000), UINT32_MAX);
}

TEST(WalkSchedule, TheLeastPrerollBringsEveryRecordInTime) {
  // Records of one frame each, 150 bytes, at 1000 bytes a second: each
  // takes three periods to come; the n-th arrives at 0.15 n s and is due
  // at p + 0.05 (n - 1) s, so the last of 40 needs p >= 6 - 1.95 s.
  std::vector<WalkPiece> p;
  for (uint32_t f = 0; f < 40; ++f) p.push_back({150, f, f, true});
  WalkLink l;
  l.rate_bytes = 1000;
  l.buffer_bytes = 1u << 20;
  l.frame_period_s = 0.05;
  EXPECT_EQ(vds::enc::walk_preroll_ms(p, l, 600000), 4050u);
  EXPECT_GT(vds::enc::walk_lateness_s(p, l, 4.049), 0);
  EXPECT_LE(vds::enc::walk_lateness_s(p, l, 4.050), 1e-12);
  // Not within the most allowed.
  EXPECT_EQ(vds::enc::walk_preroll_ms(p, l, 4000), UINT32_MAX);
}

}  // namespace
