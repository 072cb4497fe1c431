// The walkthrough stream (vds/enc/walk_stream.h and the player's
// walkthrough mode): a room built in code played end to end through the
// client library at a rate, within it and deterministic; its chunks
// refused when damaged; the pose and view records round trip; on oa_dm4
// the client's frames measured against the ground truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numeric>
#include <stdexcept>
#include <vector>

#include "vds/enc/frames.h"
#include "vds/enc/scene_shape.h"
#include "vds/enc/stream_writer.h"
#include "vds/enc/walk_stream.h"
#include "vds/bytes.h"
#include "vds/crc32c.h"
#include "vds/player.h"
#include "vds/walk.h"
#include "stream_chunks.h"
#include "walk_room.h"
#include "xorshift.h"

namespace {

TEST(WalkStream, ARoomPlaysEndToEndWithinItsRate) {
  const vds::enc::Scene room = vds::test::walk_room();
  const vds::enc::CameraPath path = vds::test::walk_room_path(60);
  vds::enc::WalkEncodeOptions o;
  o.rate_kbps = 24;
  const auto r = vds::enc::encode_walk(room, path, o, true);
  // Within the rate: no more bytes than the link carries by the last
  // frame's time, the stated pre-roll (at most the 1 s asked for) included.
  EXPECT_LE(r.preroll_ms, 1000u);
  EXPECT_LE(r.stream.size() * 8.0, 24000.0 * (r.preroll_ms / 1000.0 + 60 / path.fps));
  EXPECT_GT(r.view_updates, 0u);
  ASSERT_EQ(r.frames.size(), 60u);
  ASSERT_EQ(r.frame_crc.size(), 60u);
  EXPECT_GT(r.psnr_rgb, 24.0) << "quality " << r.quality;
  // No frame more than 6 dB below the pooled PSNR.
  for (size_t f = 0; f < r.frame_psnr.size(); ++f) EXPECT_GT(r.frame_psnr[f], r.psnr_rgb - 6) << "frame " << f;
  // Each frame's bytes add up to the stream; a frame with a view update
  // brings at least that view's image.
  ASSERT_EQ(r.bytes_by_frame.size(), 60u);
  EXPECT_EQ(std::accumulate(r.bytes_by_frame.begin(), r.bytes_by_frame.end(), size_t{0}), r.stream.size());
  size_t view_frames = 0;
  for (size_t f = 0; f < 60; ++f) view_frames += r.bytes_by_frame[f] > 200;
  EXPECT_GE(view_frames, r.view_updates > 1 ? 2u : 1u);
  // The same input makes the same stream, and the client shows the same frames.
  const auto again = vds::enc::encode_walk(room, path, o);
  EXPECT_EQ(again.stream, r.stream);
  EXPECT_EQ(vds::enc::client_frame_crcs(r.stream), r.frame_crc);
  std::printf("room, 60 frames: %.2f kbit/s, pre-roll %u ms, %zu view updates (%zu zoomed) at quality %d, PSNR %.2f dB\n", r.kbps,
              r.preroll_ms, r.view_updates, r.view_zoomed, r.quality, r.psnr_rgb);
}

// The client draws the same frames in the least workspace that plays the
// stream (its triangles projected and their homographies computed again
// in each band that needs them) as in any larger one, where more set-up
// cache entries, then a cache of projected vertices, then of
// homographies, take what is spare.
TEST(WalkStream, TheClientShowsTheSameFramesInTheLeastWorkspaceAsInAnyLarger) {
  const vds::enc::Scene room = vds::test::walk_room();
  const vds::enc::CameraPath path = vds::test::walk_room_path(40);
  vds::enc::WalkEncodeOptions o;
  o.rate_kbps = 24;
  const auto r = vds::enc::encode_walk(room, path, o);
  ASSERT_GT(r.slots, 20u);
  const auto crcs = [&](size_t budget) {
    const vds::enc::ClientArena a{budget, 0};
    return vds::enc::client_frame_crcs(r.stream, nullptr, &a);
  };
  const auto plays = [&](size_t budget) {
    try {
      crcs(budget);
      return true;
    } catch (const std::runtime_error&) {
      return false;
    }
  };
  // The least workspace that plays it (the chunk buffer and HEAD's
  // declaration: what the client needs, no cache).
  size_t lo = 1, hi = size_t{1} << 22;
  ASSERT_FALSE(plays(lo));
  ASSERT_TRUE(plays(hi));
  while (hi - lo > 1) {
    const size_t mid = lo + (hi - lo) / 2;
    (plays(mid) ? hi : lo) = mid;
  }
  EXPECT_EQ(hi, vds::kClientPlayerConfig.max_chunk_bytes + r.workspace_bytes);
  // What is spare buys set-up cache entries, then projected vertices, then
  // homographies: steps through all three, part of each, then room for all.
  ASSERT_LT(3 * r.slots * 13 + r.slots * (sizeof(vds::Homography) + 1), 20000u) << "the steps reach every cache";
  std::vector<size_t> more;
  for (size_t k = 0; k < 24; ++k) more.push_back(k * 1499);
  more.push_back(size_t{1} << 22);
  for (size_t m : more) EXPECT_EQ(crcs(hi + m), r.frame_crc) << "workspace " << hi << " + " << m;
}

TEST(WalkStream, RefinementsAddToTheViewsTheClientHolds) {
  // Residual images refining held views: the client adds them to what its
  // slots hold, and shows what the encoder's replay shows; at a fixed
  // quality they make the pictures better.
  const vds::enc::Scene room = vds::test::walk_room();
  const vds::enc::CameraPath path = vds::test::walk_room_path(60);
  vds::enc::WalkEncodeOptions o;
  o.quality = 20;
  const auto plain = vds::enc::encode_walk(room, path, o);
  o.refine_delta = 30;
  o.refine_after = 5;
  const auto refined = vds::enc::encode_walk(room, path, o);
  ASSERT_GT(refined.view_refinements, 0u);
  EXPECT_EQ(vds::enc::client_frame_crcs(refined.stream), refined.frame_crc);
  EXPECT_GT(refined.psnr_rgb, plain.psnr_rgb + 0.5) << plain.psnr_rgb << " " << refined.psnr_rgb;
  EXPECT_GT(refined.stream.size(), plain.stream.size());
}

// The room at quality 30 in records of one frame, then again with
// `change` made to the options: both streams show the same pictures.
std::pair<vds::enc::WalkEncodeResult, vds::enc::WalkEncodeResult> same_pictures(
    const std::function<void(vds::enc::WalkEncodeOptions&)>& change) {
  const vds::enc::Scene room = vds::test::walk_room();
  const vds::enc::CameraPath path = vds::test::walk_room_path(60);
  vds::enc::WalkEncodeOptions o;
  o.quality = 30;
  o.frames_per_record = 1;
  auto a = vds::enc::encode_walk(room, path, o);
  change(o);
  auto b = vds::enc::encode_walk(room, path, o);
  EXPECT_EQ(b.frame_crc, a.frame_crc);
  EXPECT_EQ(vds::enc::client_frame_crcs(b.stream), b.frame_crc);
  return {std::move(a), std::move(b)};
}

TEST(WalkStream, RegionUpdatesCodeOnlyWhatTheClientReadsAndShowTheSamePictures) {
  // A view update's image codes only the MCUs the frames it serves read:
  // fewer MCUs and bytes, and, as the rest is never read, the same pictures
  // as whole views at the same quality (up to the coded MCUs' own coding:
  // their neighbours and contexts differ).
  const vds::enc::Scene room = vds::test::walk_room();
  const vds::enc::CameraPath path = vds::test::walk_room_path(60);
  vds::enc::WalkEncodeOptions o;
  o.quality = 40;
  o.regions = false;
  const auto whole = vds::enc::encode_walk(room, path, o);
  o.regions = true;
  const auto region = vds::enc::encode_walk(room, path, o);
  ASSERT_EQ(whole.view_mcus_coded, whole.view_mcus);
  ASSERT_EQ(region.view_mcus, whole.view_mcus);
  EXPECT_LT(region.view_mcus_coded, region.view_mcus);
  EXPECT_LT(region.view_bytes, whole.view_bytes);
  EXPECT_EQ(vds::enc::client_frame_crcs(region.stream), region.frame_crc);
  EXPECT_NEAR(region.psnr_rgb, whole.psnr_rgb, 0.1);
  ASSERT_EQ(region.frame_psnr.size(), whole.frame_psnr.size());
  double most = 0;
  for (size_t f = 0; f < whole.frame_psnr.size(); ++f) {
    EXPECT_NEAR(region.frame_psnr[f], whole.frame_psnr[f], 0.05) << "frame " << f;
    most = std::max(most, std::fabs(region.frame_psnr[f] - whole.frame_psnr[f]));
  }
  std::printf("room, 60 frames at quality 40: %zu of %zu MCUs coded, views %zu bytes (whole: %zu), PSNR %.2f dB (whole: %.2f), "
              "frames within %.3f dB\n",
              region.view_mcus_coded, region.view_mcus, region.view_bytes, whole.view_bytes, region.psnr_rgb, whole.psnr_rgb, most);
}

TEST(WalkStream, ZoomedViewsShowFinerTexelsWhereTheyServeLongEnough) {
  // Zoomed view updates (a narrower view at the same size: finer texels)
  // where they serve long enough: the client draws from them what the
  // encoder's replay draws, and the frames they serve are sharper than
  // with the views' own focal length at the same quality.
  const vds::enc::Scene room = vds::test::walk_room();
  const vds::enc::CameraPath path = vds::test::walk_room_path(60);
  vds::enc::WalkEncodeOptions o;
  o.quality = 60;
  o.zoom = 16;
  const auto plain = vds::enc::encode_walk(room, path, o);
  o.zoom = 24;
  const auto zoomed = vds::enc::encode_walk(room, path, o);
  EXPECT_EQ(plain.view_zoomed, 0u);
  ASSERT_GT(zoomed.view_zoomed, 0u);
  EXPECT_EQ(vds::enc::client_frame_crcs(zoomed.stream), zoomed.frame_crc);
  EXPECT_GT(zoomed.psnr_rgb, plain.psnr_rgb + 0.2);
  // Every WVUP is 17 bytes but the zoomed ones, 18.
  size_t wvup18 = 0;
  for (const vds::test::ChunkAt& c : vds::test::stream_chunks(zoomed.stream)) {
    if (c.type != vds::chunk::kWalkView) continue;
    ASSERT_TRUE(c.size == vds::kWalkViewBytes || c.size == vds::kWalkViewMaxBytes) << c.size;
    wvup18 += c.size == vds::kWalkViewMaxBytes;
  }
  EXPECT_EQ(wvup18, zoomed.view_zoomed);
  std::printf("room, 60 frames at quality 60: %zu of %zu views zoomed, PSNR %.2f dB (none zoomed: %.2f), views %zu bytes (%zu)\n",
              zoomed.view_zoomed, zoomed.view_updates, zoomed.psnr_rgb, plain.psnr_rgb, zoomed.view_bytes, plain.view_bytes);
}

TEST(WalkStream, RecordsOfSeveralFramesShowWhatRecordsOfOneShow) {
  // The same views and decisions in records of up to 8 frames and of one:
  // the same pictures, fewer chunks, fewer bytes.
  const auto [one, eight] = same_pictures([](auto& o) { o.frames_per_record = 8; });
  // At least 12 bytes of framing saved per record merged away (60 records
  // of one frame; the records of eight break at each view update).
  const size_t records = (60 + 7) / 8 + one.view_updates;
  EXPECT_LE(eight.stream.size() + 12 * (60 - records), one.stream.size()) << one.stream.size() << " " << eight.stream.size();
}

TEST(WalkStream, PolygonsSentAheadShowWhatPolygonsSentOnTimeShow) {
  // Bursts of geometry spread to the frames before (--max-sends): the
  // client draws the same pictures, the largest record is smaller.
  const auto [plain, spread] = same_pictures([](auto& o) { o.max_sends = 2; });
  // (After the first frame's, which nothing can precede.)
  const auto largest = [](const std::vector<vds::enc::WalkPiece>& p) {
    size_t m = 0;
    for (const auto& x : p)
      if (x.record && x.first_frame > 0) m = std::max(m, x.bytes);
    return m;
  };
  EXPECT_LT(largest(spread.pieces), largest(plain.pieces));
  std::printf("room: largest frame record after the first %zu bytes, %zu with at most 2 polygons a frame\n", largest(plain.pieces),
              largest(spread.pieces));
}

TEST(WalkStream, TheFeedLimitKeepsABoundedQueueOfFramesFromOverflowing) {
  // A client with room for `room` frame records feeds no more than the
  // player's feed limit: however the records drain, no feed completes more
  // frames than there was room for, and every frame is shown.
  const vds::enc::Scene room = vds::test::walk_room();
  const vds::enc::CameraPath path = vds::test::walk_room_path(60);
  vds::enc::WalkEncodeOptions o;
  o.quality = 30;
  const auto r = vds::enc::encode_walk(room, path, o);
  std::vector<uint8_t> ws(1u << 22);
  vds::Arena arena(ws.data(), ws.size());
  vds::PlayerConfig cfg = vds::kClientPlayerConfig;
  cfg.max_chunk_bytes = 1u << 16;
  vds::Player player;
  ASSERT_EQ(player.init(arena, cfg, vds::PlayerCallbacks{}), vds::Status::ok);
  vds::test::Xorshift32 rng;
  constexpr uint32_t kQueue = 8;
  uint32_t pending = 0, most = 0;
  size_t at = 0;
  vds::Status s = vds::Status::more_input;
  while (s == vds::Status::more_input && at < r.stream.size()) {
    if (pending > 0 && rng.next() % 32 == 0) --pending;  // records leave slowly
    const size_t limit = player.feed_limit(kQueue - pending);
    const size_t n = std::min({limit, r.stream.size() - at, size_t{1} + rng.next() % 300});
    if (n == 0) continue;
    const uint32_t before = player.frames_shown();
    s = player.feed(r.stream.data() + at, n);
    at += n;
    ASSERT_LE(player.frames_shown() - before, kQueue - pending) << "at byte " << at;
    pending += player.frames_shown() - before;
    most = std::max(most, player.frames_shown() - before);
  }
  std::printf("room, 60 frames: %zu view updates; at most %u frames completed by one feed\n", r.view_updates, most);
  EXPECT_EQ(s, vds::Status::ok);
  EXPECT_EQ(player.frames_shown(), 60u);
}

TEST(WalkStream, TheViewsDrawnOntoTheSameShapeInFewerTrianglesShowTheSame) {
  // The client draws the views onto the room's walls as two triangles each
  // (vds/enc/scene_shape.h) instead of 32: the geometry takes a fraction
  // of the bytes, the client still shows what the encoder's replay shows,
  // and the pictures are as good (the views come from the room as it is).
  const vds::enc::Scene room = vds::test::walk_room();
  const vds::enc::Scene shape = vds::enc::simplify_shape(room);
  ASSERT_EQ(shape.triangles(), 12u);
  const vds::enc::CameraPath path = vds::test::walk_room_path(60);
  vds::enc::WalkEncodeOptions o;
  o.quality = 40;
  const auto plain = vds::enc::encode_walk(room, path, o);
  const auto fewer = vds::enc::encode_walk(room, path, o, false, &shape);
  EXPECT_EQ(vds::enc::client_frame_crcs(fewer.stream), fewer.frame_crc);
  EXPECT_LE(fewer.polygons_sent, 12u);
  EXPECT_GT(plain.polygons_sent, 100u);
  EXPECT_LT(fewer.geometry_bytes * 4, plain.geometry_bytes) << plain.geometry_bytes << " " << fewer.geometry_bytes;
  EXPECT_GT(fewer.psnr_rgb, plain.psnr_rgb - 0.5) << plain.psnr_rgb << " " << fewer.psnr_rgb;
  EXPECT_LT(fewer.slots, plain.slots);
  std::printf("room at quality 40: %zu triangle sends, geometry %zu bytes, %.2f dB; walls as 2 triangles: %zu, %zu bytes, %.2f dB\n",
              plain.polygons_sent, plain.geometry_bytes, plain.psnr_rgb, fewer.polygons_sent, fewer.geometry_bytes, fewer.psnr_rgb);
  // A geometry scene with other textures than the scene's is refused.
  vds::enc::Scene other = shape;
  other.textures.push_back(other.textures[0]);
  EXPECT_THROW(vds::enc::encode_walk(room, path, o, false, &other), std::invalid_argument);
}

TEST(WalkStream, PredictedViewUpdatesAreResidualsTheClientAddsToItsPrediction) {
  // With predictions, some view updates are coded as residuals against the
  // view the client draws from what it holds; the client shows what the
  // encoder's replay shows. A residual after an update that did not ask
  // for the prediction is refused.
  const vds::enc::Scene room = vds::test::walk_room();
  const vds::enc::CameraPath path = vds::test::walk_room_path(60);
  vds::enc::WalkEncodeOptions o;
  o.quality = 60;
  o.threshold = 1.35;  // updates while the old views still show much of the new one
  o.predict = true;
  const auto r = vds::enc::encode_walk(room, path, o);
  ASSERT_GT(r.view_predicted, 0u);
  EXPECT_EQ(vds::enc::client_frame_crcs(r.stream), r.frame_crc);
  o.predict = false;
  const auto plain = vds::enc::encode_walk(room, path, o);
  EXPECT_LT(r.view_bytes, plain.view_bytes);
  // Clear every WVUP's "predict" bit (and mend the chunk's CRC).
  std::vector<uint8_t> bad = r.stream;
  size_t cleared = 0;
  for (const vds::test::ChunkAt& c : vds::test::stream_chunks(bad)) {
    const size_t body = c.payload();
    if (c.type == vds::chunk::kWalkView && (bad[body] & vds::kWalkViewPredict)) {
      bad[body] &= static_cast<uint8_t>(~vds::kWalkViewPredict);
      vds::store_le32(&bad[body + c.size], vds::crc32c(&bad[c.at], vds::kChunkHeadBytes + c.size));
      ++cleared;
    }
  }
  ASSERT_GT(cleared, 0u);
  EXPECT_THROW(vds::enc::client_frame_crcs(bad), std::runtime_error);
}

// A client in simulated time, as the firmware plays a timed stream: the
// link carries `rate` bytes a second while the client's window has room
// (`window` bytes arrived and not yet taken); the client takes what has
// arrived in pieces of up to 256 bytes and holds each frame until it is
// due. Counts the frames whose data came after their time.
struct TimedClient {
  const std::vector<uint8_t>* stream = nullptr;
  double rate = 0, window = 0, preroll = 0, period = 0;
  double t = 0, link_t = 0;  // the client's time; when the link delivered its last byte
  size_t arrived = 0, taken = 0;
  uint32_t frame = 0, late = 0;
  double worst = -1e9;  // the latest a frame's data came, after its time (s)

  void advance_to(double when) {
    while (arrived < stream->size()) {
      if (arrived >= taken + static_cast<size_t>(window)) {
        link_t = std::max(link_t, when);  // the link idles while the window is full
        return;
      }
      if (link_t + 1 / rate > when) return;
      link_t += 1 / rate;
      ++arrived;
    }
  }
  static void wait_until(void* ctx, uint64_t) {
    auto& c = *static_cast<TimedClient*>(ctx);
    // The time from the simulation's own pre-roll, not the stream's.
    const double due = 1 / c.rate + c.preroll + c.frame++ * c.period;
    c.worst = std::max(c.worst, c.t - due);
    if (c.t > due + 1e-9) ++c.late;
    if (c.t < due) {
      c.t = due;
      c.advance_to(due);
    }
  }
  vds::Status play(vds::Player& player) {
    vds::Status s = vds::Status::more_input;
    while (s == vds::Status::more_input && taken < stream->size()) {
      if (arrived == taken) {
        t = std::max(t, link_t + 1 / rate);
        advance_to(t);
      }
      const size_t n = std::min<size_t>(256, arrived - taken);
      taken += n;
      s = player.feed(stream->data() + taken - n, n);
    }
    return s;
  }
};

uint32_t late_frames(const std::vector<uint8_t>& stream, double rate, double window, double preroll, uint32_t* frames = nullptr,
                     uint32_t* stated_ms = nullptr) {
  std::vector<uint8_t> ws(1u << 22);
  vds::Arena arena(ws.data(), ws.size());
  vds::PlayerConfig cfg = vds::kClientPlayerConfig;
  cfg.max_chunk_bytes = 1u << 16;
  TimedClient c;
  c.stream = &stream;
  c.rate = rate;
  c.window = window;
  c.preroll = preroll;
  vds::PlayerCallbacks cb;
  cb.ctx = &c;
  cb.wait_until = TimedClient::wait_until;
  vds::Player player;
  EXPECT_EQ(player.init(arena, cfg, cb), vds::Status::ok);
  c.period = 0;
  // The period is the header's; known once HEAD is in.
  EXPECT_EQ(player.feed(stream.data(), 0), vds::Status::more_input);
  c.period = 0.05;
  EXPECT_EQ(c.play(player), vds::Status::ok);
  EXPECT_TRUE(player.timed());
  if (frames != nullptr) *frames = player.frames_shown();
  if (stated_ms != nullptr) *stated_ms = player.preroll_ms();
  return c.late;
}

TEST(WalkStream, RateControlBringsEveryFrameInTimeWithTheStatedPreroll) {
  // The rate control shapes the stream for a link and a client window, and
  // states its pre-roll (WLKP): a client that waits that long after the
  // first byte and then shows a frame every period has every frame's data
  // in time, its window never over-full. A slower link, or views coded at
  // one high quality with the same pre-roll, bring frames late.
  const vds::enc::Scene room = vds::test::walk_room();
  const vds::enc::CameraPath path = vds::test::walk_room_path(60);
  ASSERT_DOUBLE_EQ(path.fps, 20);
  vds::enc::WalkEncodeOptions o;
  o.rate_kbps = 12;
  o.preroll_ms = 400;
  o.buffer_bytes = 1024;
  o.link_framing = false;  // the simulated link delivers byte by byte
  const double rate = 1500;
  const auto r = vds::enc::encode_walk(room, path, o);
  EXPECT_LE(r.preroll_ms, 400u);
  EXPECT_EQ(r.rate_bytes, 1500u);
  EXPECT_EQ(r.buffer_bytes, 1024u);
  uint32_t frames = 0, stated = 0;
  EXPECT_EQ(late_frames(r.stream, rate, 1024, r.preroll_ms / 1000.0, &frames, &stated), 0u);
  EXPECT_EQ(frames, 60u);
  EXPECT_EQ(stated, r.preroll_ms);
  // Views of different qualities: where the link is busy, lower.
  const auto [lo, hi] = std::minmax_element(r.view_quality.begin(), r.view_quality.end());
  ASSERT_EQ(r.view_quality.size(), r.view_updates);
  EXPECT_LT(*lo, *hi);
  EXPECT_GT(late_frames(r.stream, 0.8 * rate, 1024, r.preroll_ms / 1000.0), 0u);
  // Views at one high quality do not fit the link with any pre-roll (the
  // window bounds what a pre-roll holds back): the stream is untimed.
  o.quality = 90;
  const auto fixed = vds::enc::encode_walk(room, path, o);
  EXPECT_EQ(fixed.rate_bytes, 0u);
  EXPECT_EQ(fixed.buffer_bytes, 0u);
  EXPECT_EQ(fixed.preroll_ms, 0u);
  EXPECT_EQ(vds::enc::client_frame_crcs(fixed.stream), fixed.frame_crc);
  // With a window that holds the whole stream, only the rate binds: the
  // same quality needs a longer pre-roll, and states it.
  o.buffer_bytes = 1u << 20;
  const auto q90 = vds::enc::encode_walk(room, path, o);
  ASSERT_NE(q90.rate_bytes, 0u);
  EXPECT_GT(q90.preroll_ms, 400u);
  EXPECT_GT(late_frames(q90.stream, rate, 1 << 20, 0.4), 0u);
  EXPECT_EQ(late_frames(q90.stream, rate, 1 << 20, q90.preroll_ms / 1000.0), 0u);
  // A pre-roll no quality meets: the least there is plus the one asked
  // for, so that the views can rise above the lowest quality; still every
  // frame in time with the pre-roll stated.
  o.quality = -1;
  o.buffer_bytes = 1024;
  o.preroll_ms = 1;
  const auto tight = vds::enc::encode_walk(room, path, o);
  ASSERT_NE(tight.rate_bytes, 0u);
  EXPECT_GT(tight.preroll_ms, 1u);
  EXPECT_EQ(late_frames(tight.stream, rate, 1024, tight.preroll_ms / 1000.0), 0u);
  EXPECT_GT(*std::max_element(tight.view_quality.begin(), tight.view_quality.end()), 0);
  std::printf("room, 60 frames at 12 kbit/s: pre-roll %u ms (views at quality %d to %d, PSNR %.2f dB); at quality 90 %u ms; "
              "asked for 1 ms, %u ms\n",
              r.preroll_ms, *lo, *hi, r.psnr_rgb, q90.preroll_ms, tight.preroll_ms);
}

TEST(WalkStream, DamagedStreamsAreRefusedNotCrashed) {
  const vds::enc::Scene room = vds::test::walk_room();
  vds::enc::WalkEncodeOptions o;
  o.quality = 30;
  const auto r = vds::enc::encode_walk(room, vds::test::walk_room_path(12), o);
  // Every prefix of the stream: refused or short of frames, never a crash.
  for (size_t n = 0; n < r.stream.size(); n += 31) {
    const std::vector<uint8_t> cut(r.stream.begin(), r.stream.begin() + static_cast<std::ptrdiff_t>(n));
    try {
      EXPECT_LT(vds::enc::client_frame_crcs(cut).size(), 12u);
    } catch (const std::runtime_error&) {
    }
  }
  // Bytes flipped inside chunks (the CRC catches them: refused).
  vds::test::Xorshift32 rng;
  for (int round = 0; round < 30; ++round) {
    std::vector<uint8_t> bad = r.stream;
    bad[100 + rng.next() % (bad.size() - 100)] ^= static_cast<uint8_t>(1 + rng.next() % 255);
    EXPECT_THROW(vds::enc::client_frame_crcs(bad), std::runtime_error);
  }
}

TEST(WalkStream, RecordsRoundTripAndRefuseBadFields) {
  // Poses through the record's grid.
  const vds::enc::CameraPose p{123.4, -56.7, 89.01, 271.3, -12.5};
  const vds::enc::CameraPose q = vds::enc::from_walk_pose(vds::enc::walk_pose(p));
  EXPECT_NEAR(q.x, p.x, 1.0 / 32);
  EXPECT_NEAR(q.z, p.z, 1.0 / 32);
  EXPECT_NEAR(q.yaw_deg, p.yaw_deg, 360.0 / 65536);
  EXPECT_NEAR(q.pitch_deg, p.pitch_deg, 360.0 / 65536);
  uint8_t b[vds::kWalkParamsBytes];
  vds::WalkParams w{300, 2, 5, 8192, 80 << 16, 160, 120, 2000, 4096, 1500};
  vds::walk_params_to_bytes(w, b);
  vds::WalkParams back;
  ASSERT_EQ(vds::walk_params_from_bytes(b, sizeof b, &back), vds::Status::ok);
  EXPECT_EQ(back.slots, 300);
  EXPECT_EQ(back.views, 2);
  EXPECT_EQ(back.quantum_raw, 8192);
  EXPECT_EQ(back.view_focal_q16, 80 << 16);
  EXPECT_EQ(back.frames_per_record, 5);
  EXPECT_EQ(back.view_width, 160);
  EXPECT_EQ(back.view_height, 120);
  EXPECT_EQ(back.rate_bytes, 2000u);
  EXPECT_EQ(back.buffer_bytes, 4096u);
  EXPECT_EQ(back.preroll_ms, 1500u);
  vds::store_le32(b + 24, vds::kWalkMaxPrerollMs + 1);  // a pre-roll of more than ten minutes
  EXPECT_EQ(vds::walk_params_from_bytes(b, sizeof b, &back), vds::Status::malformed);
  vds::store_le32(b + 24, 1500);
  vds::store_le32(b + 16, 0);  // no rate, but a pre-roll
  EXPECT_EQ(vds::walk_params_from_bytes(b, sizeof b, &back), vds::Status::malformed);
  vds::store_le32(b + 16, 2000);
  b[3] = 0;  // records of no frames
  EXPECT_EQ(vds::walk_params_from_bytes(b, sizeof b, &back), vds::Status::malformed);
  b[3] = vds::kWalkMaxFramesPerRecord + 1;
  EXPECT_EQ(vds::walk_params_from_bytes(b, sizeof b, &back), vds::Status::malformed);
  b[3] = 5;
  b[2] = 9;  // more views than a client holds
  EXPECT_EQ(vds::walk_params_from_bytes(b, sizeof b, &back), vds::Status::malformed);
  b[2] = 2;
  b[4] = 3;  // a grid that is not a power of two
  EXPECT_EQ(vds::walk_params_from_bytes(b, sizeof b, &back), vds::Status::malformed);
  EXPECT_EQ(vds::walk_params_from_bytes(b, sizeof b - 1, &back), vds::Status::malformed);
  // View updates: 17 bytes at the views' own focal length, 18 with a zoom.
  vds::WalkViewUpdate vu;
  vu.slot = 1;
  vu.pose = vds::enc::walk_pose(p);
  uint8_t vb[vds::kWalkViewMaxBytes];
  ASSERT_EQ(vds::walk_view_to_bytes(vu, vb), vds::kWalkViewBytes);
  vds::WalkViewUpdate vback;
  ASSERT_EQ(vds::walk_view_from_bytes(vb, vds::kWalkViewBytes, &vback), vds::Status::ok);
  EXPECT_EQ(vback.zoom, vds::kWalkZoomUnit);
  vu.zoom = 24;
  vu.predict = true;
  ASSERT_EQ(vds::walk_view_to_bytes(vu, vb), vds::kWalkViewMaxBytes);
  ASSERT_EQ(vds::walk_view_from_bytes(vb, vds::kWalkViewMaxBytes, &vback), vds::Status::ok);
  EXPECT_EQ(vback.zoom, 24);
  EXPECT_EQ(vback.slot, 1);
  EXPECT_TRUE(vback.predict);
  EXPECT_EQ(vback.pose.yaw, vu.pose.yaw);
  EXPECT_EQ(vback.pose.position.z.raw(), vu.pose.position.z.raw());
  for (const uint8_t z : {0, 15, 16, 65, 255}) {  // a zoom byte that zooms out, does not zoom, or past 4 times
    vb[17] = z;
    EXPECT_EQ(vds::walk_view_from_bytes(vb, vds::kWalkViewMaxBytes, &vback), vds::Status::malformed) << int{z};
  }
  EXPECT_EQ(vds::walk_view_from_bytes(vb, vds::kWalkViewBytes + 2, &vback), vds::Status::malformed);
  EXPECT_EQ(vds::walk_view_from_bytes(vb, vds::kWalkViewBytes - 1, &vback), vds::Status::malformed);
  // A zoomed view's camera: the views' focal length times zoom / 16, the rest the same.
  vds::StreamHeader hh = vds::enc::default_header(vds::StreamMode::walkthrough, 240, 180);
  hh.focal_x_q16 = hh.focal_y_q16 = 120 << 16;
  hh.center_x_q16 = 120 << 16;
  hh.center_y_q16 = 90 << 16;
  hh.near_q16 = 1 << 14;
  hh.far_q16 = 1 << 26;
  vds::Camera wide, zoomed;
  ASSERT_EQ(vds::walk_view_camera(hh, w, vu.pose, &wide), vds::Status::ok);
  ASSERT_EQ(vds::walk_view_camera(hh, w, vu.pose, &zoomed, 24), vds::Status::ok);
  EXPECT_EQ(zoomed.fx.raw(), wide.fx.raw() / 16 * 24);
  EXPECT_EQ(zoomed.cx.raw(), wide.cx.raw());
  EXPECT_EQ(zoomed.position.x.raw(), wide.position.x.raw());
  EXPECT_EQ(vds::walk_view_camera(hh, w, vu.pose, &zoomed, 65), vds::Status::malformed);
  // Random frame records: a status, and views always in range.
  vds::test::Xorshift32 rng;
  const uint16_t hot[4] = {0, 3, 5, 9};
  uint8_t view_of[10] = {};
  uint16_t stamp[10] = {};
  const bool fresh[3] = {false, true, false};
  for (int round = 0; round < 3000; ++round) {
    vds::WalkFrameDecoder d;
    d.reset();
    std::vector<uint8_t> junk(1 + rng.next() % 24);
    for (auto& x : junk) x = static_cast<uint8_t>(rng.next());
    vds::WalkPose pose;
    if (d.consume(junk.data(), static_cast<uint32_t>(junk.size()), hot, 4, view_of, stamp, fresh, 3, &pose) == vds::Status::ok)
      for (uint16_t h : hot) ASSERT_LT(view_of[h], 3);
  }
}

}  // namespace
