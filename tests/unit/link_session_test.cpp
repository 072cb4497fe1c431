// Link session: handshake, roles and versions, malformed frames of every
// kind counted and dropped, window violations refused, latest-wins
// datagrams, configuration checks and the client's RAM bound.
#include <gtest/gtest.h>

#include <vector>

#include "vds/crc32c.h"
#include "vds/link/cobs.h"
#include "vds/link/frame.h"
#include "vds/link/link.h"
#include "vds/link/sim.h"

namespace {

using namespace vds::link;
using vds::Status;

void establish(LinkSim& sim, uint32_t limit_ms = 5000) {
  while (sim.now_ms() < limit_ms && !(sim.host().established() && sim.device().established())) sim.step();
  ASSERT_TRUE(sim.host().established());
  ASSERT_TRUE(sim.device().established());
}

std::vector<uint8_t> frame(FrameType t, uint8_t ch, uint8_t tag, uint16_t seq, const std::vector<uint8_t>& p) {
  FrameHeader h;
  h.type = t;
  h.channel = ch;
  h.tag = tag;
  h.seq = seq;
  std::vector<uint8_t> out(frame_wire_bound(p.size()));
  size_t len = 0;
  EXPECT_EQ(frame_encode(h, p.data(), p.size(), out.data(), out.size(), &len), Status::ok);
  out.resize(len);
  return out;
}

std::vector<uint8_t> hello_payload(uint8_t major, uint8_t flags, uint32_t nonce, uint32_t echo) {
  std::vector<uint8_t> p = {major, 0, flags, 7};
  for (uint32_t v : {nonce, echo})
    for (int i = 0; i < 4; ++i) p.push_back(static_cast<uint8_t>(v >> (8 * i)));
  p.push_back(0x00);  // max payload 1024
  p.push_back(0x04);
  p.push_back(0);  // no channels
  p.push_back(0);
  p.push_back(0);  // no line buffer declared
  p.push_back(0);
  return p;
}

TEST(LinkSession, HandshakeEstablishesBothSides) {
  LinkSim sim(115200, {}, {}, host_config(1), device_config(2));
  establish(sim, 200);
  EXPECT_EQ(sim.host().session_epoch(), 1u);
  EXPECT_EQ(sim.device().session_epoch(), 1u);
  EXPECT_EQ(sim.host().peer_nonce(), sim.device().nonce());
  EXPECT_EQ(sim.device().peer_nonce(), sim.host().nonce());
  EXPECT_EQ(sim.host().session_tag(), sim.device().session_tag());
  EXPECT_NE(sim.host().nonce(), 0u);
  EXPECT_EQ(sim.host().peer_max_payload(), 1024);
  EXPECT_EQ(sim.device().peer_max_payload(), 256);
  // Idle for a while: keepalives flow, nothing resets.
  for (int i = 0; i < 5000; ++i) sim.step();
  EXPECT_EQ(sim.host().session_epoch(), 1u);
  EXPECT_GE(sim.host().last_heard_ms(), 4000u);
}

TEST(LinkSession, HandshakeSurvivesLossDuplicatesAndGarbage) {
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    FaultConfig f;
    f.seed = seed;
    f.frame_drop_rate = 0.3;
    f.frame_dup_rate = 0.2;
    f.garbage_rate = 0.2;
    f.bit_error_rate = 1e-3;
    FaultConfig g = f;
    g.seed = seed + 100;
    LinkSim sim(115200, f, g, host_config(static_cast<uint32_t>(seed)), device_config(static_cast<uint32_t>(seed) * 7));
    establish(sim, 20000);
    for (int i = 0; i < 3000; ++i) sim.step();
    EXPECT_EQ(sim.host().session_epoch(), 1u) << seed;
    EXPECT_EQ(sim.device().session_epoch(), 1u) << seed;
  }
}

TEST(LinkSession, SameRoleNeverEstablishes) {
  LinkSim sim(115200, {}, {}, host_config(1), host_config(2));
  for (int i = 0; i < 2000; ++i) sim.step();
  EXPECT_FALSE(sim.host().established());
  EXPECT_FALSE(sim.device().established());
  EXPECT_GT(sim.host().stats().bad_hello, 0u);
}

TEST(LinkSession, RefusesAnotherMajorVersion) {
  LinkSim sim(115200, {}, {}, host_config(1), device_config(2));
  Link& dev = sim.device();
  const auto f = frame(FrameType::hello, 0, 0, 0, hello_payload(kVersionMajor - 1, 0, 0x1234, 0));
  dev.receive(f.data(), f.size(), 0);
  EXPECT_EQ(dev.stats().bad_version, 1u);
  EXPECT_EQ(dev.peer_nonce(), 0u);
}

TEST(LinkSession, RestartByApplicationStartsANewSession) {
  LinkSim sim(115200, {}, {}, host_config(1), device_config(2));
  establish(sim);
  const uint32_t old = sim.host().nonce();
  sim.host().restart();
  EXPECT_FALSE(sim.host().established());
  EXPECT_NE(sim.host().nonce(), old);
  establish(sim);
  EXPECT_EQ(sim.host().session_epoch(), 2u);
  EXPECT_EQ(sim.device().session_epoch(), 2u);
  EXPECT_EQ(sim.device().last_reset(), ResetReason::peer_restarted);
  EXPECT_EQ(sim.host().last_reset(), ResetReason::local);
}

// Every kind of malformed frame reaches the device after the session is
// up; each is counted under its own reason, dropped, and the link goes on.
TEST(LinkSession, MalformedFramesOfEveryKindAreCountedAndDropped) {
  LinkSim sim(1000000, {}, {}, host_config(1), device_config(2));
  establish(sim);
  // Deliver some real stream bytes first.
  std::vector<uint8_t> data(3000);
  for (size_t i = 0; i < data.size(); ++i) data[i] = static_cast<uint8_t>(i * 7);
  size_t acc = 0;
  ASSERT_EQ(sim.host().write(channel::kStream, data.data(), data.size(), &acc), Status::ok);
  for (int i = 0; i < 200; ++i) sim.step();
  std::vector<uint8_t> got(8192);
  size_t n = 0;
  ASSERT_EQ(sim.device().read(channel::kStream, got.data(), got.size(), &n), Status::ok);
  ASSERT_EQ(n, data.size());

  Link& dev = sim.device();
  const uint8_t tag = dev.session_tag();
  const uint32_t now = static_cast<uint32_t>(sim.now_ms());
  struct Case {
    const char* name;
    std::vector<uint8_t> bytes;
    uint32_t LinkStats::*counter;
  };
  std::vector<uint8_t> too_long(2000, 0x41);
  too_long.push_back(0);
  std::vector<uint8_t> bad_crc = frame(FrameType::data, channel::kStream, tag, 3000, {1, 2, 3});
  bad_crc[2] ^= 0x01;
  const std::vector<Case> cases = {
      {"short", {0x03, 0x11, 0x22, 0x00}, &LinkStats::too_short},
      {"long", too_long, &LinkStats::too_long},
      {"bad CRC", bad_crc, &LinkStats::bad_crc},
      {"bad COBS", {0x07, 0x11, 0x22, 0x00}, &LinkStats::bad_cobs},
      {"hello without a body", frame(FrameType::hello, 0, 0, 0, {}), &LinkStats::bad_hello},
      {"unknown channel id", frame(FrameType::data, 12, tag, 3000, {1}), &LinkStats::unknown_channel},
      {"channel not received", frame(FrameType::data, channel::kChecksums, tag, 0, {1}), &LinkStats::unknown_channel},
      {"datagram on a reliable channel", frame(FrameType::datagram, channel::kStream, tag, 1, {1}),
       &LinkStats::unknown_channel},
      {"out-of-window sequence", frame(FrameType::data, channel::kStream, tag, 3000 + 5000, {9, 9}),
       &LinkStats::out_of_window},
      {"straddling the window end", frame(FrameType::data, channel::kStream, tag, 3000 + 4090, std::vector<uint8_t>(10, 9)),
       &LinkStats::out_of_window},
      {"another session's tag", frame(FrameType::data, channel::kStream, static_cast<uint8_t>(tag + 1), 3000, {1}),
       &LinkStats::bad_session},
      {"duplicate of delivered data", frame(FrameType::data, channel::kStream, tag, 100, {7, 7}),
       &LinkStats::duplicates},
      {"ack of bytes never sent", frame(FrameType::ack, channel::kControl, tag, 500, {0, 1, 0, 0, 0, 0, 0}), &LinkStats::bad_ack},
      {"ack with a ragged length", frame(FrameType::ack, channel::kControl, tag, 0, {0, 1, 2}), &LinkStats::bad_ack},
      {"hello too short", frame(FrameType::hello, 0, 0, 0, {1, 0, 0}), &LinkStats::bad_hello},
      {"hello from a device", frame(FrameType::hello, 0, 0, 0, hello_payload(kVersionMajor, 0x02, 99, 0)), &LinkStats::bad_hello},
  };
  for (const Case& c : cases) {
    const LinkStats before = dev.stats();
    dev.receive(c.bytes.data(), c.bytes.size(), now);
    EXPECT_EQ(dev.stats().*c.counter, before.*c.counter + 1) << c.name;
    EXPECT_EQ(dev.readable(channel::kStream), 0u) << c.name << " delivered nothing";
    EXPECT_TRUE(dev.established()) << c.name << " did not end the session";
  }
  // Frame types 4..15 are refused as unknown.
  const LinkStats before = dev.stats();
  for (uint8_t t = 4; t < 16; ++t) {
    std::vector<uint8_t> raw = {static_cast<uint8_t>(t << 4), tag, 0, 0};
    const uint32_t crc = vds::crc32c(raw.data(), raw.size());
    for (int i = 0; i < 4; ++i) raw.push_back(static_cast<uint8_t>(crc >> (8 * i)));
    std::vector<uint8_t> enc(vds::link::cobs_encoded_bound(raw.size()) + 1);
    size_t len = 0;
    ASSERT_EQ(vds::link::cobs_encode(raw.data(), raw.size(), enc.data(), enc.size(), &len), Status::ok);
    enc[len++] = 0;
    dev.receive(enc.data(), len, now);
  }
  EXPECT_EQ(dev.stats().unknown_type, before.unknown_type + 12);
  // The link still carries data, exactly once.
  ASSERT_EQ(sim.host().write(channel::kStream, data.data(), 500, &acc), Status::ok);
  for (int i = 0; i < 200; ++i) sim.step();
  ASSERT_EQ(dev.read(channel::kStream, got.data(), got.size(), &n), Status::ok);
  ASSERT_EQ(n, 500u);
  EXPECT_EQ(std::vector<uint8_t>(got.begin(), got.begin() + 500), std::vector<uint8_t>(data.begin(), data.begin() + 500));
  EXPECT_EQ(sim.device().session_epoch(), 1u);
}

TEST(LinkSession, DatagramsAreLatestWins) {
  LinkSim sim(115200, {}, {}, host_config(1), device_config(2));
  establish(sim);
  uint8_t pose[8] = {};
  for (uint8_t i = 1; i <= 3; ++i) {
    pose[0] = i;
    ASSERT_EQ(sim.device().send_datagram(channel::kPose, pose, sizeof pose), Status::ok);
  }
  for (int i = 0; i < 50; ++i) sim.step();
  uint8_t out[64];
  size_t n = 0;
  ASSERT_EQ(sim.host().read_datagram(channel::kPose, out, sizeof out, &n), Status::ok);
  EXPECT_EQ(n, sizeof pose);
  EXPECT_EQ(out[0], 3) << "only the newest unsent message is sent";
  EXPECT_EQ(sim.host().read_datagram(channel::kPose, out, sizeof out, &n), Status::more_input);
  // An older counter than the one held is stale.
  Link& host = sim.host();
  const auto old = frame(FrameType::datagram, channel::kPose, host.session_tag(), 0, {5});
  host.receive(old.data(), old.size(), static_cast<uint32_t>(sim.now_ms()));
  EXPECT_EQ(host.stats().stale_datagrams, 1u);
  EXPECT_EQ(host.read_datagram(channel::kPose, out, sizeof out, &n), Status::more_input);
  // Too big for the sender's slot; a channel the peer does not receive.
  uint8_t big[100] = {};
  EXPECT_EQ(sim.device().send_datagram(channel::kPose, big, sizeof big), Status::output_too_small);
  EXPECT_EQ(sim.host().write(channel::kControl, big, 10, &n), Status::ok);
  EXPECT_EQ(sim.device().write(channel::kStream, big, 10, &n), Status::invalid_argument);
}

TEST(LinkSession, WriteToAChannelThePeerDoesNotReceiveIsRefused) {
  LinkConfig dc = device_config(2);
  dc.channels[channel::kControl].rx = Mode::none;
  dc.channels[channel::kControl].rx_bytes = 0;
  LinkSim sim(115200, {}, {}, host_config(1), dc);
  establish(sim);
  uint8_t b[4] = {};
  size_t n = 0;
  EXPECT_EQ(sim.host().write(channel::kControl, b, sizeof b, &n), Status::unsupported_feature);
}

TEST(LinkSession, ConfigurationIsChecked) {
  std::vector<uint64_t> ws(4096);
  auto try_init = [&](const LinkConfig& c, size_t bytes) {
    vds::Arena a(ws.data(), bytes);
    Link l;
    return l.init(c, a);
  };
  LinkConfig c = device_config(1);
  EXPECT_EQ(try_init(c, ws.size() * 8), Status::ok);
  EXPECT_EQ(try_init(c, link_workspace_size(c)), Status::ok) << "the declared size is enough";
  EXPECT_EQ(try_init(c, link_workspace_size(c) / 2), Status::workspace_too_small);
  LinkConfig bad = c;
  bad.channels[0].rx_bytes = 20000;
  EXPECT_EQ(try_init(bad, ws.size() * 8), Status::invalid_argument);
  bad = c;
  bad.max_tx_payload = 4;
  EXPECT_EQ(try_init(bad, ws.size() * 8), Status::invalid_argument);
  bad = c;
  bad.channels[channel::kPose].tx_bytes = 200;  // above max_tx_payload 128
  EXPECT_EQ(try_init(bad, ws.size() * 8), Status::invalid_argument);
  bad = c;
  bad.rto_min_ms = 0;
  EXPECT_EQ(try_init(bad, ws.size() * 8), Status::invalid_argument);
}

// The client's link RAM with a 4 x 1 KiB window: the Link object plus its
// workspace. Pointers are 8 bytes here and 4 on the Cortex-M4, so the
// device figure (bench/results/link.md) is smaller still.
TEST(LinkSession, ClientRamWithFourKiBWindowIsAtMostEightKiB) {
  const LinkConfig c = device_config(1);
  EXPECT_EQ(c.channels[channel::kStream].rx_bytes, 4096);
  EXPECT_LE(sizeof(Link) + link_workspace_size(c), 8192u);
}

}  // namespace
