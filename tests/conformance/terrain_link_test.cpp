// Terrain over the link: the live server (TerrainLive) on the host end of a
// simulated line, the client library's player on the device end sending
// its pose up the pose channel, with frames lost, duplicated and damaged in
// both directions. The client must play every frame, each equal to the
// replay of the stream the server sent, while poses are lost on the way up
// (latest wins: the server answers the newest that arrives).
#include <gtest/gtest.h>

#include <vector>

#include "../unit/terrain_maps.h"
#include "vds/enc/frames.h"
#include "vds/enc/terrain_stream.h"
#include "vds/link/sim.h"
#include "vds/player.h"

namespace {

using vds::Status;
namespace enc = vds::enc;
namespace link = vds::link;

struct Device {
  link::Link* link = nullptr;
  uint32_t frames = 0, poses_sent = 0, poses_refused_by_link = 0;
  std::vector<uint32_t> crcs;
};

TEST(TerrainOverTheLink, LostPosesAndDamagedFramesStillPlayEveryFrameBitExactly) {
  const enc::TerrainCoding t = enc::code_terrain(vds::test::terrain_test_map(), 6);
  const enc::CameraPath path = vds::test::terrain_test_flight(t, 60, 80);
  const enc::TerrainStreamOptions o = vds::test::terrain_test_client(6000);
  enc::TerrainLive live(t, path, o);

  link::FaultConfig down, up;
  for (link::FaultConfig* f : {&down, &up}) {
    f->frame_drop_rate = 0.15;
    f->frame_dup_rate = 0.02;
    f->bit_error_rate = 2e-5;
    f->garbage_rate = 0.01;
  }
  down.seed = 5;
  up.seed = 6;
  constexpr uint32_t kBaud = 115200;
  link::LinkSim sim(kBaud, down, up, link::host_config(7, kBaud / 10), link::device_config(8));

  Device dev;
  dev.link = &sim.device();
  std::vector<uint8_t> ws(2u << 20);
  vds::Arena arena(ws.data(), ws.size());
  vds::Player player;
  vds::PlayerCallbacks cb;
  cb.ctx = &dev;
  cb.frame_shown = [](void* ctx, const vds::PlayedFrame& f) {
    auto& dv = *static_cast<Device*>(ctx);
    ++dv.frames;
    dv.crcs.push_back(f.crc);
  };
  cb.send_up = [](void* ctx, uint8_t kind, const uint8_t* data, size_t n) {
    auto& dv = *static_cast<Device*>(ctx);
    if (kind != vds::terrain::kSendPose) return false;
    ++dv.poses_sent;
    if (dv.link->send_datagram(link::channel::kPose, data, n) != Status::ok) ++dv.poses_refused_by_link;
    return true;
  };
  ASSERT_EQ(player.init(arena, vds::kClientPlayerConfig, cb), Status::ok);

  std::vector<uint8_t> made;
  size_t written = 0;
  uint64_t start_ms = 0;
  Status played = Status::more_input;
  uint32_t poses_arrived = 0;
  while (sim.now_ms() < 120000 && played == Status::more_input) {
    link::Link& host = sim.host();
    if (host.established()) {
      if (start_ms == 0) start_ms = sim.now_ms();
      uint8_t pose[64];
      size_t n = 0;
      while (host.read_datagram(link::channel::kPose, pose, sizeof pose, &n) == Status::ok) {
        ++poses_arrived;
        live.pose(pose, n);
      }
      live.produce(sim.now_ms() - start_ms, made);
      size_t acc = 0;
      while (written < made.size() &&
             host.write(link::channel::kStream, made.data() + written, made.size() - written, &acc) == Status::ok && acc != 0)
        written += acc;
    }
    sim.step();
    uint8_t buf[1024];
    size_t got = 0;
    while (played == Status::more_input && sim.device().read(link::channel::kStream, buf, sizeof buf, &got) == Status::ok &&
           got != 0)
      played = player.feed(buf, got);
  }
  ASSERT_EQ(played, Status::ok) << vds::status_name(played) << " " << (player.error_detail() ? player.error_detail() : "");
  ASSERT_TRUE(live.finished());
  EXPECT_EQ(sim.host().session_epoch(), 1u) << "faults never end the session";
  EXPECT_EQ(dev.frames, 60u);
  EXPECT_EQ(dev.crcs, enc::client_frame_crcs(made)) << "every frame is the replay's";
  EXPECT_EQ(dev.poses_sent, 15u);  // every 4th frame
  EXPECT_EQ(dev.poses_refused_by_link, 0u);
  // Some poses were lost on the way up (or replaced by a newer one before
  // they were sent), none arrived twice or out of order, and the server
  // answered the ones that came.
  EXPECT_GT(poses_arrived, 0u);
  EXPECT_LT(poses_arrived, dev.poses_sent);
  EXPECT_EQ(live.poses_refused(), 0u);
  EXPECT_EQ(live.poses_received(), poses_arrived);
  uint32_t updates = 0;
  for (const enc::TerrainStreamFrame& f : live.frames()) updates += f.texture_bytes != 0;
  EXPECT_GT(updates, 5u);
}

}  // namespace
