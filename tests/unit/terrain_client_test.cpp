// Terrain mode, the client and the stream: the block store against a
// reference, the client's store against the server's mirror after every
// frame of a stream (with poses lost, stale and duplicated on the way up),
// the flight's interpolation, malformed records refused, and every prefix
// of a stream waited for or refused.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "terrain_maps.h"
#include "vds/bytes.h"
#include "vds/enc/frames.h"
#include "vds/enc/stream_writer.h"
#include "vds/enc/terrain_stream.h"
#include "vds/player.h"
#include "vds/terrain_client.h"
#include "xorshift.h"

namespace {

using vds::Status;
using vds::terrain::Mask;
namespace enc = vds::enc;
namespace terrain = vds::terrain;

// --- The block store --------------------------------------------------------------

Mask random_mask(vds::test::Xorshift32& r) {
  // A staircase: extents that never grow down the rows, the DC held.
  Mask m = 0;
  int above = 1 + static_cast<int>(r.next() % 8);
  for (int v = 0; v < 8; ++v) {
    const int e = v == 0 ? above : static_cast<int>(r.next() % (above + 1));
    m = terrain::mask_with_extent(m, v, e);
    above = e;
  }
  return m;
}

TEST(TerrainStore, HoldsWhatEveryUpdateLeavesAndRefusesOverflow) {
  terrain::BlockGrid g;
  g.cells_x = 40;
  g.cells_y = 24;
  constexpr uint32_t kUnits = 3000;
  std::vector<uint8_t> ws(terrain::BlockStore::workspace_bytes(kUnits) + 64);
  vds::Arena arena(ws.data(), ws.size());
  terrain::BlockStore store;
  ASSERT_EQ(store.init(arena, g, kUnits), Status::ok);
  std::map<uint32_t, std::pair<Mask, std::array<int16_t, 64>>> ref;
  vds::test::Xorshift32 r{7};
  uint32_t used = 0, refused = 0;
  for (int step = 0; step < 4000; ++step) {
    terrain::BlockUpdate u;
    u.id = static_cast<uint32_t>(r.next() % g.blocks());
    u.held = store.held(u.id);
    const int kind = static_cast<int>(r.next() % 4);
    u.mask = kind == 0 ? 0 : (kind == 1 ? terrain::mask_intersection(u.held, random_mask(r)) : terrain::mask_union(u.held, random_mask(r)));
    for (int i = 0; i < 64; ++i) u.levels[i] = static_cast<int16_t>(static_cast<int>(r.next() % 401) - 200);
    const uint32_t after = used - terrain::store_cost(u.held) + terrain::store_cost(u.mask);
    const Status s = store.apply(u);
    if (after > kUnits) {
      ASSERT_EQ(s, Status::malformed);
      ++refused;
      continue;
    }
    ASSERT_EQ(s, Status::ok);
    used = after;
    auto& e = ref[u.id];
    for (int i = 0; i < 64; ++i) {
      const bool had = terrain::mask_holds(e.first, i & 7, i >> 3), has = terrain::mask_holds(u.mask, i & 7, i >> 3);
      if (!has) e.second[i] = 0;
      else if (!had) e.second[i] = u.levels[i];
    }
    e.first = u.mask;
    if (step % 97 == 0 || step == 3999) {
      ASSERT_EQ(store.used_units(), used);
      for (const auto& [id, v] : ref) {
        ASSERT_EQ(store.held(id), v.first) << id;
        int16_t lv[64];
        store.levels(id, lv);
        for (int i = 0; i < 64; ++i) ASSERT_EQ(lv[i], v.second[i]) << id << " " << i;
      }
    }
  }
  EXPECT_GT(refused, 0u);  // the store did fill up
  // A change from a mask the store does not hold is refused.
  terrain::BlockUpdate bad;
  bad.id = 3;
  bad.held = store.held(3) == terrain::kFullMask ? 1 : terrain::kFullMask;
  bad.mask = terrain::kFullMask;
  EXPECT_EQ(store.apply(bad), Status::malformed);
}

TEST(TerrainStore, StagedChangesMergeToWhatOneByOneWouldHold) {
  terrain::BlockGrid g;
  g.cells_x = 30;
  g.cells_y = 20;
  constexpr uint32_t kUnits = 5000;
  std::vector<uint8_t> ws_a(terrain::BlockStore::workspace_bytes(kUnits) + 64), ws_b(ws_a.size());
  vds::Arena arena_a(ws_a.data(), ws_a.size()), arena_b(ws_b.data(), ws_b.size());
  terrain::BlockStore one, batched;
  ASSERT_EQ(one.init(arena_a, g, kUnits), Status::ok);
  ASSERT_EQ(batched.init(arena_b, g, kUnits), Status::ok);
  vds::test::Xorshift32 r{11};
  std::vector<uint32_t> merged;
  const auto on_merged = [](void* ctx, uint32_t id) { static_cast<std::vector<uint32_t>*>(ctx)->push_back(id); };
  uint32_t changes = 0;
  for (int pass = 0; pass < 300; ++pass) {
    // A pass: blocks in ascending order, each shrunk, dropped or grown.
    uint32_t id = r.next() % 40;
    while (id < g.blocks()) {
      terrain::BlockUpdate u;
      u.id = id;
      u.held = one.held(id);
      const int kind = static_cast<int>(r.next() % 3);
      u.mask = kind == 0 ? 0 : (kind == 1 ? terrain::mask_intersection(u.held, random_mask(r)) : terrain::mask_union(u.held, random_mask(r)));
      for (int i = 0; i < 64; ++i) u.levels[i] = static_cast<int16_t>(static_cast<int>(r.next() % 2001) - 1000);
      if (one.apply(u) == Status::ok) {
        ASSERT_EQ(batched.stage(u, on_merged, &merged), Status::ok) << pass << " " << id;
        changes += u.mask != u.held;
      }
      id += 1 + r.next() % 60;
    }
    if (pass % 3 == 0) ASSERT_EQ(batched.merge(on_merged, &merged), Status::ok);
  }
  ASSERT_EQ(batched.merge(on_merged, &merged), Status::ok);
  EXPECT_EQ(merged.size(), changes);
  EXPECT_EQ(batched.used_units(), one.used_units());
  EXPECT_EQ(batched.held_blocks(), one.held_blocks());
  for (uint32_t id = 0; id < g.blocks(); ++id) {
    ASSERT_EQ(batched.held(id), one.held(id)) << id;
    int16_t a[64], b[64];
    one.levels(id, a);
    batched.levels(id, b);
    for (int i = 0; i < 64; ++i) ASSERT_EQ(a[i], b[i]) << id << " " << i;
  }
}

TEST(TerrainFlightPose, InterpolatesBetweenKeysTheShortWayRound) {
  vds::WalkPose keys[3];
  keys[0].position = {vds::Q16_16::from_raw(0), vds::Q16_16::from_raw(10 << 16), vds::Q16_16::from_raw(-4 << 16)};
  keys[0].yaw = 65000;  // just short of a full turn
  keys[0].pitch = 0;
  keys[1] = keys[0];
  keys[1].position.x = vds::Q16_16::from_raw(100 << 16);
  keys[1].yaw = 500;  // 1036 units on, across zero
  keys[1].pitch = 65036;  // 500 down
  keys[2] = keys[1];
  const vds::WalkPose mid = terrain::flight_pose(keys, 3, 4, 2);
  EXPECT_EQ(mid.position.x.raw(), 50 << 16);
  EXPECT_EQ(mid.position.y.raw(), 10 << 16);
  EXPECT_EQ(mid.yaw, static_cast<uint16_t>(65000 + 518));
  EXPECT_EQ(mid.pitch, static_cast<uint16_t>(65536 - 250));
  EXPECT_EQ(terrain::flight_pose(keys, 3, 4, 4).position.x.raw(), 100 << 16);
  EXPECT_EQ(terrain::flight_pose(keys, 3, 4, 1000).yaw, 500);  // past the last key: the last key
}

// --- The stream -------------------------------------------------------------------

enc::CameraPath circle_flight(const enc::TerrainCoding& t, int frames) { return vds::test::terrain_test_flight(t, frames); }
enc::TerrainStreamOptions small_client() { return vds::test::terrain_test_client(3000); }

// A player fed a stream as it is made.
struct Feeder {
  std::vector<uint8_t> ws = std::vector<uint8_t>(2u << 20);
  vds::Arena arena{ws.data(), ws.size()};
  vds::Player player;
  std::vector<std::vector<uint8_t>> poses_up;
  uint32_t frames = 0;
  std::vector<uint32_t> crcs;
  // The viewer's controls, one entry a frame (none past the end).
  std::vector<terrain::SteerInput> controls;
  Feeder() {
    vds::PlayerCallbacks cb;
    cb.ctx = this;
    cb.frame_shown = [](void* ctx, const vds::PlayedFrame& f) {
      ++static_cast<Feeder*>(ctx)->frames;
      static_cast<Feeder*>(ctx)->crcs.push_back(f.crc);
    };
    cb.steer = [](void* ctx, terrain::SteerInput* in) {
      Feeder& me = *static_cast<Feeder*>(ctx);
      if (me.frames - 1 >= me.controls.size()) return false;
      *in = me.controls[me.frames - 1];
      return true;
    };
    cb.send_up = [](void* ctx, uint8_t kind, const uint8_t* d, size_t n) {
      if (kind == terrain::kSendPose) static_cast<Feeder*>(ctx)->poses_up.emplace_back(d, d + n);
      return true;
    };
    EXPECT_EQ(player.init(arena, vds::kClientPlayerConfig, cb), Status::ok);
  }
};

// The client's store equals the server's mirror: every mask, and every held
// coefficient is the coded one.
void expect_mirror(const enc::TerrainCoding& t, const enc::TerrainLive& live, const vds::Player& p, uint32_t frame) {
  const terrain::BlockStore* store = p.terrain_store();
  ASSERT_NE(store, nullptr);
  const std::vector<Mask>& held = live.sender().server().held();
  ASSERT_EQ(store->used_units(), live.sender().server().used()) << frame;
  for (uint32_t id = 0; id < held.size(); ++id) {
    ASSERT_EQ(store->held(id), held[id]) << "frame " << frame << " block " << id;
    if (held[id] == 0) continue;
    int16_t lv[64];
    store->levels(id, lv);
    for (int i = 0; i < 64; ++i)
      ASSERT_EQ(lv[i], terrain::mask_holds(held[id], i & 7, i >> 3) ? t.levels[id][static_cast<size_t>(i)] : 0) << id;
  }
}

// Plays a flight live: the client's poses go up as the player sends them
// and reach the server `latency` frames later, except those `lose` drops;
// `stale` sends an old pose again after each new one.
struct LiveRun {
  uint32_t frames = 0, poses_sent = 0, poses_lost = 0;
  std::vector<uint8_t> stream;
  std::vector<uint32_t> crcs, shown;  // the replay's, the player's own
  std::vector<std::vector<uint8_t>> poses;  // every pose sent up
  uint32_t refused = 0, updates = 0, steered = 0;
  int32_t cell_q16 = 0;  // the stream's cell size, world units
};
LiveRun play_live(const enc::TerrainCoding& t, const enc::CameraPath& path, double lose, bool stale, uint64_t seed,
                  const std::vector<terrain::SteerInput>& controls = {}) {
  enc::TerrainLive live(t, path, small_client());
  Feeder client;
  client.controls = controls;
  vds::test::Xorshift32 r{static_cast<uint32_t>(seed)};
  LiveRun run;
  std::vector<std::pair<uint32_t, std::vector<uint8_t>>> in_flight;  // (arrival frame, message)
  std::vector<uint8_t> made, last_good;
  for (uint32_t f = 0; f < live.sender().frames(); ++f) {
    for (size_t k = 0; k < in_flight.size();) {
      if (in_flight[k].first <= f) {
        const std::vector<uint8_t>& m = in_flight[k].second;
        live.pose(m.data(), m.size());
        if (stale && !last_good.empty()) live.pose(last_good.data(), last_good.size());
        last_good = m;
        in_flight.erase(in_flight.begin() + static_cast<long>(k));
      } else {
        ++k;
      }
    }
    live.next_frame();
    const size_t before = made.size();
    live.produce(0, made);  // what next_frame wrote
    const Status s = client.player.feed(made.data() + before, made.size() - before);
    EXPECT_TRUE(s == Status::more_input || s == Status::ok) << vds::status_name(s) << " " << client.player.error_detail();
    expect_mirror(t, live, client.player, f);
    for (std::vector<uint8_t>& m : client.poses_up) {
      ++run.poses_sent;
      run.poses.push_back(m);
      if ((r.next() % 1000) < lose * 1000) {
        ++run.poses_lost;
        continue;
      }
      in_flight.emplace_back(f + 2, std::move(m));
    }
    client.poses_up.clear();
  }
  EXPECT_EQ(client.player.finish(), Status::ok) << client.player.error_detail();
  run.frames = client.frames;
  run.shown = client.crcs;
  run.stream = made;
  run.refused = live.poses_refused();
  run.steered = live.steered_frames();
  run.cell_q16 = live.sender().params().cell_q16;
  for (const enc::TerrainStreamFrame& tf : live.frames()) run.updates += tf.texture_bytes != 0;
  run.crcs = enc::client_frame_crcs(made);
  return run;
}

TEST(TerrainStream, TheClientsStoreIsTheServersMirrorAfterEveryFrame) {
  const enc::TerrainCoding t = enc::code_terrain(vds::test::terrain_test_map(), 6);
  const enc::CameraPath path = circle_flight(t, 80);
  const LiveRun run = play_live(t, path, 0.0, false, 1);
  EXPECT_EQ(run.frames, 80u);
  EXPECT_EQ(run.poses_sent, 20u);  // every 4th frame at 20 frames/s, 5 poses a second
  EXPECT_EQ(run.refused, 0u);
  EXPECT_GT(run.updates, 10u);
  // The same flight written ahead (poses arriving 2 frames late, none lost)
  // is the same stream, frame for frame.
  const enc::TerrainStreamResult w = enc::write_terrain_stream(t, path, small_client());
  EXPECT_EQ(w.bytes, run.stream);
}

TEST(TerrainStream, PosesLostStaleOrRepeatedStillPlayBitExactly) {
  const enc::TerrainCoding t = enc::code_terrain(vds::test::terrain_test_map(), 6);
  const enc::CameraPath path = circle_flight(t, 80);
  const LiveRun clean = play_live(t, path, 0.0, false, 1);
  const LiveRun lossy = play_live(t, path, 0.5, true, 3);
  EXPECT_EQ(lossy.frames, 80u);
  EXPECT_GT(lossy.poses_lost, 3u);
  EXPECT_LT(lossy.poses_lost, lossy.poses_sent);
  // Every stale repeat is refused; the server answers only newer poses.
  EXPECT_GE(lossy.refused, lossy.poses_sent - lossy.poses_lost - 1);
  // A different pose history makes a different stream; each plays as its
  // own replay says (checked frame by frame against the mirror above).
  EXPECT_NE(lossy.stream, clean.stream);
  EXPECT_EQ(lossy.crcs.size(), 80u);
}

// A viewer steers from frame 20 to 49 (forward, turning left, climbing):
// its poses go up marked as steered every frame the controls move it, the
// server draws the newest (TFRM with a pose) from the frame after one
// arrives, and the client's frames are still its replay's.
TEST(TerrainStream, AViewerWhoSteersIsDrawnWhereTheControlsTakeIt) {
  const enc::TerrainCoding t = enc::code_terrain(vds::test::terrain_test_map(), 6);
  const enc::CameraPath path = circle_flight(t, 80);
  terrain::SteerInput ahead;
  ahead.forward = 1;
  ahead.up = 1;
  ahead.turn = 182;  // a degree a frame, to the left
  std::vector<terrain::SteerInput> controls(20);
  controls.insert(controls.end(), 30, ahead);
  const LiveRun flown = play_live(t, path, 0.0, false, 1);
  const LiveRun steered = play_live(t, path, 0.0, false, 1, controls);
  ASSERT_EQ(steered.frames, 80u);
  EXPECT_EQ(steered.shown, steered.crcs);  // the client showed what the stream alone gives
  EXPECT_EQ(flown.steered, 0u);
  // Poses reach the server 2 frames after they are sent: the first steered
  // one (sent after frame 20) is drawn from frame 22 on.
  EXPECT_EQ(steered.steered, 80u - 22u);
  for (uint32_t f = 0; f < 22; ++f) EXPECT_EQ(steered.shown[f], flown.shown[f]) << f;
  for (uint32_t f = 23; f < 80; ++f) EXPECT_NE(steered.shown[f], flown.shown[f]) << f;
  // Up the link: the flight's poses every 4th frame until frame 20, then a
  // steered pose every frame the controls move the viewer (20..49), then
  // every 4th frame again, still steered.
  uint32_t flight = 0, marked = 0;
  vds::WalkPose last{};
  for (const std::vector<uint8_t>& m : steered.poses) {
    ASSERT_EQ(m.size(), terrain::kPoseMessageBytes);
    const uint32_t word = vds::load_le32(m.data()), frame = word & ~terrain::kPoseSteered;
    if ((word & terrain::kPoseSteered) == 0) {
      ++flight;
      EXPECT_LT(frame, 20u);
      continue;
    }
    ++marked;
    const vds::WalkPose p = terrain::pose_from_bytes(m.data() + 4);
    if (frame > 20 && frame < 50) {
      // Each frame turns a degree and moves a quarter of a cell forward.
      EXPECT_EQ(static_cast<uint16_t>(p.yaw - last.yaw), 182u) << frame;
      const double step = std::hypot(p.position.x.raw() - last.position.x.raw(), p.position.y.raw() - last.position.y.raw());
      EXPECT_NEAR(step, steered.cell_q16 / 4, steered.cell_q16 / 1000.0) << frame;
    }
    last = p;
  }
  EXPECT_EQ(flight, 5u);        // frames 0, 4, ..., 16
  EXPECT_EQ(marked, 30u + 7u);  // frames 20..49, then 52, 56, ..., 76
}

TEST(TerrainSteer, MovesAlongTheHeadingTurnsAndKeepsThePitchInRange) {
  vds::WalkPose p;
  p.position = {vds::Q16_16::from_raw(100 << 16), vds::Q16_16::from_raw(50 << 16), vds::Q16_16::from_raw(20 << 16)};
  p.yaw = 16384;  // facing +Y
  terrain::SteerInput in;
  in.forward = 1;
  vds::WalkPose q = terrain::steer_pose(p, in, 2 << 16);
  EXPECT_EQ(q.position.x.raw(), 100 << 16);
  EXPECT_NEAR(q.position.y.raw(), 52 << 16, 4);  // two units along +Y (cos/sin in Q1.15)
  EXPECT_EQ(q.position.z.raw(), 20 << 16);
  in = {};
  in.right = 1;
  in.fast = true;
  q = terrain::steer_pose(p, in, 2 << 16);  // to the right of +Y is +X, four times as far
  EXPECT_NEAR(q.position.x.raw(), 108 << 16, 32);
  EXPECT_NEAR(q.position.y.raw(), 50 << 16, 32);
  in = {};
  in.up = -1;
  in.turn = -16384;  // a quarter turn to the right: facing +X
  q = terrain::steer_pose(p, in, 2 << 16);
  EXPECT_EQ(q.position.z.raw(), 19 << 16);
  EXPECT_EQ(q.yaw, 0);
  in = {};
  in.tilt = 30000;
  EXPECT_EQ(terrain::steer_pose(p, in, 1 << 16).pitch, terrain::kMaxSteerPitch);
  in.tilt = -30000;
  EXPECT_EQ(terrain::steer_pose(p, in, 1 << 16).pitch, static_cast<uint16_t>(-terrain::kMaxSteerPitch));
  EXPECT_FALSE(terrain::SteerInput{}.any());
}

// --- Malformed records -----------------------------------------------------------------

struct Parts {
  vds::StreamHeader header;
  std::vector<enc::TerrainChunk> chunks;  // the opening and every frame's chunks
};

Parts parts_of(const std::vector<uint8_t>& stream) {
  Parts p;
  size_t at = vds::kPreambleBytes;
  while (at + vds::kChunkHeadBytes <= stream.size()) {
    const uint32_t type = vds::load_le32(stream.data() + at), len = vds::load_le32(stream.data() + at + 4);
    const std::vector<uint8_t> payload(stream.begin() + static_cast<long>(at + 8), stream.begin() + static_cast<long>(at + 8 + len));
    if (type == vds::chunk::kHeader) {
      EXPECT_EQ(vds::header_from_bytes(payload.data(), len, stream[4], stream[5], &p.header), Status::ok);
    } else if (type != vds::chunk::kEnd) {
      p.chunks.push_back({type, payload});
    }
    at += vds::kChunkHeadBytes + len + vds::kChunkTailBytes;
  }
  return p;
}

std::vector<uint8_t> rebuild(const Parts& p) {
  enc::StreamWriter w(p.header);
  for (const enc::TerrainChunk& c : p.chunks) w.add_chunk(c.type, c.payload);
  return w.finish();
}

Status play(const std::vector<uint8_t>& s, std::string* detail = nullptr) {
  Feeder f;
  Status st = f.player.feed(s.data(), s.size());
  if (st == Status::more_input) st = f.player.finish();
  if (detail != nullptr) *detail = f.player.error_detail() != nullptr ? f.player.error_detail() : "";
  return st;
}

TEST(TerrainStream, MalformedRecordsAreRefused) {
  const enc::TerrainCoding t = enc::code_terrain(vds::test::terrain_test_map(), 6);
  const Parts good = parts_of(enc::write_terrain_stream(t, circle_flight(t, 40), small_client()).bytes);
  ASSERT_EQ(play(rebuild(good)), Status::ok);
  auto find = [&](const Parts& p, uint32_t type, int nth = 0) {
    for (size_t i = 0; i < p.chunks.size(); ++i)
      if (p.chunks[i].type == type && nth-- == 0) return i;
    ADD_FAILURE() << "no such chunk";
    return size_t{0};
  };
  struct Case {
    const char* what;
    std::function<void(Parts&)> spoil;
  };
  const std::vector<Case> cases = {
      {"TERH with no cells", [&](Parts& p) { p.chunks[find(p, vds::chunk::kTerrainParams)].payload[0] = 0, p.chunks[find(p, vds::chunk::kTerrainParams)].payload[1] = 0; }},
      {"TERH with quantiser 0", [&](Parts& p) { p.chunks[find(p, vds::chunk::kTerrainParams)].payload[4] = 0; }},
      {"TERH with a cache of 2^7", [&](Parts& p) { p.chunks[find(p, vds::chunk::kTerrainParams)].payload[5] = 7; }},
      {"TERH with a frame budget of 1", [&](Parts& p) { p.chunks[find(p, vds::chunk::kTerrainParams)].payload[23] = 1; }},
      {"TERH with a half window of 2^8", [&](Parts& p) { p.chunks[find(p, vds::chunk::kTerrainParams)].payload[22] = 8; }},
      {"TERH of another length", [&](Parts& p) { p.chunks[find(p, vds::chunk::kTerrainParams)].payload.push_back(0); }},
      {"a second TERH", [&](Parts& p) { p.chunks.insert(p.chunks.begin() + 1, p.chunks[0]); }},
      {"TFLY short of the frames", [&](Parts& p) {
         auto& f = p.chunks[find(p, vds::chunk::kTerrainFlight)].payload;
         f.resize(f.size() - terrain::kPoseBytes * 2);
       }},
      {"TFLY with spacing 0", [&](Parts& p) { p.chunks[find(p, vds::chunk::kTerrainFlight)].payload[0] = 0; }},
      {"a second TFLY", [&](Parts& p) { p.chunks.insert(p.chunks.begin() + 2, p.chunks[find(p, vds::chunk::kTerrainFlight)]); }},
      {"a fine piece before the coarse pass", [&](Parts& p) { std::swap(p.chunks[find(p, vds::chunk::kTerrainElevation)], p.chunks[find(p, vds::chunk::kTerrainElevation, 1)]); }},
      {"a fine piece out of row order", [&](Parts& p) {
         p.chunks.erase(p.chunks.begin() + static_cast<long>(find(p, vds::chunk::kTerrainElevation, 1)));
       }},
      {"a coarse pass of the wrong rows", [&](Parts& p) { p.chunks[find(p, vds::chunk::kTerrainElevation)].payload[3] ^= 1; }},
      {"a frame out of order", [&](Parts& p) { vds::store_le32(p.chunks[find(p, vds::chunk::kTerrainFrame, 3)].payload.data(), 7); }},
      {"a frame before the flight", [&](Parts& p) { std::swap(p.chunks[1], p.chunks[find(p, vds::chunk::kTerrainFrame)]); }},
      {"a frame past the header's count", [&](Parts& p) { p.chunks.push_back(p.chunks[find(p, vds::chunk::kTerrainFrame)]), vds::store_le32(p.chunks.back().payload.data(), 40); }},
      {"an update cut short", [&](Parts& p) { p.chunks[find(p, vds::chunk::kTerrainTexture)].payload.resize(9); }},
      {"an update repeated (its blocks are not what the store holds)", [&](Parts& p) {
         const size_t k = find(p, vds::chunk::kTerrainTexture);
         p.chunks.insert(p.chunks.begin() + static_cast<long>(k), p.chunks[k]);
       }},
      {"a terrain chunk before TERH", [&](Parts& p) { std::swap(p.chunks[0], p.chunks[1]); }},
  };
  for (const Case& c : cases) {
    Parts p = good;
    c.spoil(p);
    std::string detail;
    const Status s = play(rebuild(p), &detail);
    EXPECT_TRUE(s == Status::malformed || s == Status::truncated) << c.what << ": " << vds::status_name(s) << " (" << detail << ")";
    EXPECT_FALSE(detail.empty()) << c.what;
  }
  // A store smaller than the server filled: the update overflows it.
  Parts small = good;
  vds::store_le32(small.chunks[find(small, vds::chunk::kTerrainParams)].payload.data() + 8, 200);
  EXPECT_EQ(play(rebuild(small)), Status::malformed);
}

TEST(TerrainStream, EveryPrefixWaitsForMoreOrIsRefused) {
  const enc::TerrainCoding t = enc::code_terrain(vds::test::terrain_test_map(), 6);
  const std::vector<uint8_t> s = enc::write_terrain_stream(t, circle_flight(t, 12), small_client()).bytes;
  for (size_t n = 0; n < s.size(); n += 1 + n / 64) {
    Feeder f;
    const Status st = f.player.feed(s.data(), n);
    ASSERT_TRUE(st == Status::more_input || vds::is_error(st)) << n;
    ASSERT_NE(f.player.finish(), Status::ok) << n;
  }
}

}  // namespace
