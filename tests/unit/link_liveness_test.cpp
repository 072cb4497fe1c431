// Liveness of the link (docs/protocol.md, "Flow control and loss"): from
// any state, with the line working, a transfer makes progress. A device
// that takes bytes off its line at 5 %..100 % of the line rate, in bursts
// and with pauses of up to 10 s, under bit errors, always receives the
// whole stream intact, within a bound on time, without its UART ring ever
// overflowing; with no bit errors nothing is resent and frames stay at
// their largest size; and the close (DoneReport, Goodbye) completes on
// both sides. Simulated time, seeded: every run is the same.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "../conformance/link_test_util.h"
#include "link_stream.h"
#include "vds/link/serve.h"

namespace {

using namespace vds::link;
using namespace vds::link::linktest;
using vds::Status;

constexpr uint32_t kBaud = 115200;
constexpr uint32_t kRing = 4096;  // the boards' UART receive ring

struct Case {
  uint32_t rate_permille;
  uint32_t burst_ms;
  uint32_t pause_max_ms;  // 0: no pauses
  double ber;
  std::string name() const {
    return "drain " + std::to_string(rate_permille / 10) + " %, bursts every " + std::to_string(burst_ms) +
           " ms, pauses up to " + std::to_string(pause_max_ms) + " ms, BER " + std::to_string(ber);
  }
};

std::vector<Case> cases() {
  std::vector<Case> v;
  for (uint32_t rate : {50u, 100u, 250u, 500u, 1000u})
    for (uint32_t burst : {1u, 40u})
      for (uint32_t pause : {0u, 10000u})
        for (double ber : {0.0, 1e-4}) v.push_back({rate, burst, pause, ber});
  return v;
}

DrainProfile profile(const Case& c, uint64_t seed) {
  DrainProfile p;
  p.ring_bytes = kRing;
  p.rate_permille = c.rate_permille;
  p.burst_ms = c.burst_ms;
  p.pause_every_ms = c.pause_max_ms != 0 ? 3000 : 0;
  p.pause_max_ms = c.pause_max_ms;
  p.seed = seed;
  return p;
}

TEST(LinkLiveness, SlowDeviceReceivesEverythingAndIsNeverOverrun) {
  uint64_t seed = 1;
  for (const Case& c : cases()) {
    ++seed;
    FaultConfig down, up;
    down.seed = seed;
    up.seed = seed + 500;
    down.bit_error_rate = up.bit_error_rate = c.ber;
    const uint64_t total = 48 * 1024;
    LinkSim sim(kBaud, down, up, host_config(static_cast<uint32_t>(seed)),
                device_config(static_cast<uint32_t>(seed) + 3, kRing), 1, profile(c, seed));
    StreamSource src{seed, total};
    DeviceReader rd;
    rd.check.seed = seed;
    // The bound: the stream at the drain rate (at least 90 % goodput of it
    // without bit errors, the goal; 75 % at a bit-error rate of 1e-4, where
    // link.md has 83 % at the line rate), plus the pauses, plus 5 s of
    // slack for the handshake, the last round trips and timeouts.
    const double drain_bytes_per_ms = kBaud / 10.0 / 1000.0 * c.rate_permille / 1000.0;
    const double efficiency = c.ber != 0 ? 0.75 : 0.90;
    stream_down(sim, src, rd, 600000, true);
    const DrainStats& d = sim.slow_device()->stats();
    const double bound_ms = static_cast<double>(total) / (drain_bytes_per_ms * efficiency) +
                            static_cast<double>(d.paused_ms) + 5000.0;
    SCOPED_TRACE(c.name());
    EXPECT_EQ(rd.check.got, total) << "complete";
    EXPECT_TRUE(rd.check.intact) << "first bad byte at " << rd.check.first_bad;
    EXPECT_EQ(sim.host().session_epoch(), 1u) << "one session";
    EXPECT_LE(static_cast<double>(sim.now_ms()), bound_ms) << "within the time bound";
    EXPECT_EQ(d.overflow, 0u) << "the UART ring never overflowed";
    EXPECT_LE(d.peak, kRing);
    EXPECT_LE(sim.device().rx_peak(channel::kStream), sim.device().rx_window(channel::kStream));
    if (c.ber == 0) {
      EXPECT_EQ(sim.host().stats().retransmissions, 0u) << "nothing lost, nothing resent";
      EXPECT_EQ(sim.host().stats().losses, 0u);
      EXPECT_EQ(sim.host().frame_payload(), 1024u) << "frames stay at their largest";
    }
    // A frame is resent whole only once the device took it off its line
    // and did not accept it; with no errors that never happens. Under bit
    // errors an acknowledgement lost on the way up can hide an accepted
    // frame in an out-of-order range the next one does not list: rare.
    if (c.ber == 0)
      EXPECT_EQ(sim.host().stats().spurious, 0u) << "no frame the device had received intact was resent whole";
    else
      EXPECT_LE(sim.host().stats().spurious * 20, sim.host().stats().retransmissions + 20u);
    if (c.pause_max_ms != 0) EXPECT_GT(d.pauses, 0u) << "the device did pause";
  }
}

// Goodput against the rate the device drains: with no bit errors at least
// 90 % of it at 10 % and 50 % of the line rate.
TEST(LinkLiveness, GoodputFollowsTheDrainRate) {
  for (uint32_t rate : {100u, 500u}) {
    DrainProfile p;
    p.ring_bytes = kRing;
    p.rate_permille = rate;
    p.burst_ms = 20;
    LinkSim sim(kBaud, {}, {}, host_config(11), device_config(12, kRing), 1, p);
    const uint64_t total = 96 * 1024;
    StreamSource src{5, total};
    DeviceReader rd;
    rd.check.seed = 5;
    const uint64_t start = stream_down(sim, src, rd, 600000);
    const double drain = kBaud / 10.0 * rate / 1000.0;
    const double goodput = static_cast<double>(total) / (static_cast<double>(sim.now_ms() - start) / 1000.0);
    SCOPED_TRACE("drain " + std::to_string(rate / 10) + " %");
    EXPECT_TRUE(rd.check.intact);
    EXPECT_EQ(rd.check.got, total);
    EXPECT_GE(goodput / drain, 0.90);
    EXPECT_EQ(sim.host().stats().retransmissions, 0u);
    EXPECT_EQ(sim.host().frame_payload(), 1024u);
    EXPECT_EQ(sim.slow_device()->stats().overflow, 0u);
  }
}

// The whole of `vds serve` over the loopback, slow device included: the
// stream is verified, the report arrives, the Goodbye is acknowledged and
// the client reads it, in every case.
TEST(LinkLiveness, CloseCompletesOnBothSidesWithASlowDevice) {
  const std::vector<uint8_t> s = make_stream(6, 3000);
  uint64_t seed = 100;
  for (const Case& c : cases()) {
    if (c.burst_ms != 40) continue;  // the burst pattern changes nothing in the close
    ++seed;
    ServeOptions o;
    o.baud = kBaud;
    o.faults.seed = seed;
    o.faults.bit_error_rate = c.ber;
    o.drain = profile(c, seed);
    o.nonce_seed = static_cast<uint32_t>(seed);
    const ServeReport r = serve_stream(s, o);
    SCOPED_TRACE(c.name());
    EXPECT_TRUE(r.receipt);
    EXPECT_EQ(r.receipt_bytes, s.size());
    EXPECT_TRUE(r.goodbye_acked) << "the host saw its Goodbye acknowledged";
    EXPECT_TRUE(r.client_goodbye) << "the client read the Goodbye";
    EXPECT_TRUE(r.client_goodbye_verified);
    EXPECT_EQ(r.sessions, 1u);
    EXPECT_EQ(r.drain.overflow, 0u);
  }
}

}  // namespace

namespace {

// A device with the smallest line buffer a HELLO may declare (256 bytes):
// the sender caps its frames to fit it, and the stream still flows.
TEST(LinkLiveness, SmallLineBufferCapsTheFrameSize) {
  DrainProfile p;
  p.ring_bytes = 256;
  p.rate_permille = 500;
  p.burst_ms = 5;
  LinkSim sim(kBaud, {}, {}, host_config(31), device_config(32, 256), 1, p);
  const uint64_t total = 16 * 1024;
  StreamSource src{7, total};
  DeviceReader rd;
  rd.check.seed = 7;
  stream_down(sim, src, rd, 120000);
  EXPECT_EQ(rd.check.got, total);
  EXPECT_TRUE(rd.check.intact);
  EXPECT_LE(sim.host().frame_payload(), 256u - line_reserve(256));
  EXPECT_EQ(sim.slow_device()->stats().overflow, 0u);
  EXPECT_LE(sim.slow_device()->stats().peak, 256u);
  EXPECT_EQ(sim.host().stats().retransmissions, 0u);
}

}  // namespace

namespace {

// A session that carries nothing for five minutes: the keepalives and acks
// it exchanged are accounted for by the device's reports (before any data
// they count from the session's first frame), so the line is free when the
// stream starts, even with the smallest line buffer.
TEST(LinkLiveness, LongIdleSessionThenData) {
  DrainProfile p;
  p.ring_bytes = 256;
  p.rate_permille = 1000;
  LinkSim sim(kBaud, {}, {}, host_config(41), device_config(42, 256), 1, p);
  uint32_t most = 0;
  while (sim.now_ms() < 300000) {
    sim.step();
    most = std::max(most, sim.host().line_in_flight());
  }
  ASSERT_TRUE(sim.host().established());
  EXPECT_LE(most, 256u) << "never more on the line than the device declared";
  const uint64_t total = 8 * 1024;
  StreamSource src{9, total};
  DeviceReader rd;
  rd.check.seed = 9;
  const uint64_t start = sim.now_ms();
  stream_down(sim, src, rd, start + 60000);
  EXPECT_EQ(rd.check.got, total);
  EXPECT_TRUE(rd.check.intact);
  EXPECT_LT(sim.now_ms() - start, 5000u) << "the stream starts at once";
  EXPECT_EQ(sim.slow_device()->stats().overflow, 0u);
}

}  // namespace
