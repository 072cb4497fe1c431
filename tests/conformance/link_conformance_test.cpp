// Link conformance (docs/protocol.md, "What the tests check"): 8 MiB
// transfers under mixed faults arrive complete, in order, byte-identical,
// with no duplicate delivered; a client reboot and a host restart mid-stream
// end in the specified state; the receive window is never exceeded; the
// same protocol over a real pseudo-terminal pair (termios raw mode) and
// over TCP. Simulated-time tests are deterministic (seeded faults).
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <thread>

#include "link_test_util.h"
#include "vds/link/fd_backends.h"

#include <termios.h>
#include <unistd.h>

namespace {

using namespace vds::link;
using namespace vds::link::linktest;
using vds::Status;

FaultConfig mixed_faults(uint64_t seed, double ber, uint64_t cut_from_ms) {
  FaultConfig f;
  f.seed = seed;
  f.bit_error_rate = ber;
  f.frame_drop_rate = 0.05;
  f.frame_dup_rate = 0.02;
  f.frame_truncate_rate = 0.02;
  f.garbage_rate = 0.01;
  f.garbage_max = 96;
  f.byte_drop_rate = 1e-5;
  f.stall_rate = 2e-4;
  f.stall_max_ms = 60;
  f.cuts = {{cut_from_ms, cut_from_ms + 2500}};
  return f;
}

struct Transfer {
  StreamSource src;
  DeviceReader rd;
  // Upward traffic during the transfer: frame checksums (reliable) and
  // pose (datagram), as a client sends them.
  uint64_t up_written = 0, up_read = 0;
  bool up_intact = true;
  uint32_t poses_sent = 0, poses_read = 0;
  uint16_t last_pose = 0;
  bool poses_ordered = true;

  void up(LinkSim& sim, uint64_t up_total) {
    Link& dev = sim.device();
    if (dev.established() && up_written < up_total) {
      uint8_t b[64];
      for (size_t i = 0; i < sizeof b; ++i) b[i] = stream_byte(99, up_written + i);
      size_t acc = 0;
      const size_t n = static_cast<size_t>(std::min<uint64_t>(sizeof b, up_total - up_written));
      if (dev.write(channel::kChecksums, b, n, &acc) == Status::ok) up_written += acc;
    }
    if (dev.established() && sim.now_ms() % 50 == 0) {
      uint8_t pose[16] = {};
      ++poses_sent;
      pose[0] = static_cast<uint8_t>(poses_sent);
      pose[1] = static_cast<uint8_t>(poses_sent >> 8);
      if (dev.send_datagram(channel::kPose, pose, sizeof pose) != Status::ok) poses_sent--;
    }
    Link& host = sim.host();
    uint8_t buf[512];
    size_t n = 0;
    while (host.read(channel::kChecksums, buf, sizeof buf, &n) == Status::ok && n != 0) {
      for (size_t i = 0; i < n; ++i) up_intact = up_intact && buf[i] == stream_byte(99, up_read + i);
      up_read += n;
    }
    if (host.read_datagram(channel::kPose, buf, sizeof buf, &n) == Status::ok) {
      const uint16_t v = static_cast<uint16_t>(buf[0] | buf[1] << 8);
      poses_ordered = poses_ordered && v > last_pose;
      last_pose = v;
      ++poses_read;
    }
  }
};

void run(LinkSim& sim, Transfer& t, uint64_t limit_ms, uint64_t up_total,
         const std::function<void(LinkSim&)>& each = {}) {
  while (sim.now_ms() < limit_ms) {
    t.src.pump(sim.host());
    sim.step();
    t.rd.pump(sim.device());
    t.up(sim, up_total);
    if (each) each(sim);
    if (t.rd.check.got == t.src.total && t.src.done(sim.host()) && t.up_read == up_total) break;
  }
}

void expect_clean_result(LinkSim& sim, const Transfer& t, uint64_t total, uint64_t up_total) {
  EXPECT_EQ(t.rd.check.got, total) << "complete";
  EXPECT_TRUE(t.rd.check.intact) << "byte-identical and in order; first bad byte at " << t.rd.check.first_bad;
  EXPECT_EQ(sim.device().readable(channel::kStream), 0u) << "nothing delivered beyond the stream (no duplicate)";
  EXPECT_EQ(sim.host().session_epoch(), 1u) << "faults never end the session";
  EXPECT_EQ(sim.device().session_epoch(), 1u);
  EXPECT_EQ(t.rd.restarts, 0u);
  EXPECT_EQ(sim.device().stats().out_of_window, 0u) << "the sender never exceeds the window";
  EXPECT_LE(sim.device().rx_peak(channel::kStream), sim.device().rx_window(channel::kStream));
  EXPECT_EQ(t.up_read, up_total);
  EXPECT_TRUE(t.up_intact) << "upward reliable channel intact";
  EXPECT_TRUE(t.poses_ordered) << "latest-wins datagrams never go back in time";
  EXPECT_GT(t.poses_read, 0u);
}

void mixed_fault_transfer(double ber, uint64_t seed) {
  const uint64_t total = 8ull << 20, up_total = 64 << 10;
  const FaultConfig down = mixed_faults(seed, ber, 10000), up = mixed_faults(seed + 1, ber, 10000);
  LinkSim sim(1000000, down, up, host_config(static_cast<uint32_t>(seed)), device_config(static_cast<uint32_t>(seed) + 5));
  Transfer t;
  t.src.seed = t.rd.check.seed = seed;
  t.src.total = total;
  run(sim, t, 600000, up_total);
  expect_clean_result(sim, t, total, up_total);
  // The faults really happened, and the receiver dropped what they broke.
  const WireStats& w = sim.wire().wire_ab().stats();
  EXPECT_GT(w.bit_flips, 0u);
  EXPECT_GT(w.frames_dropped, 0u);
  EXPECT_GT(w.frames_duplicated, 0u);
  EXPECT_GT(w.frames_truncated, 0u);
  EXPECT_GT(w.garbage_bursts, 0u);
  EXPECT_GT(w.stalls, 0u);
  EXPECT_GT(w.cut_bytes, 0u);
  const LinkStats& d = sim.device().stats();
  EXPECT_GT(d.duplicates, 0u) << "duplicates arrived and were not delivered twice";
  EXPECT_GT(d.bad_crc + d.bad_cobs + d.too_short, 0u);
  std::printf("[ info ] BER %g: %llu MiB in %.1f s simulated at 1 Mbaud, %u retransmissions, %u timeouts, "
              "%u duplicates dropped, %u frames dropped by the device\n",
              ber, static_cast<unsigned long long>(total >> 20), sim.now_ms() / 1000.0,
              sim.host().stats().retransmissions, sim.host().stats().timeouts, d.duplicates, d.dropped());
}

TEST(LinkConformance, EightMiBUnderMixedFaultsBer1e4) { mixed_fault_transfer(1e-4, 11); }
TEST(LinkConformance, EightMiBUnderMixedFaultsBer1e3) { mixed_fault_transfer(1e-3, 12); }

// Specified state after a client reboot mid-stream: the host sees the
// session end (ResetReason::peer_restarted), a new session is established,
// the host sends the stream again from byte 0 and the new client receives
// all of it, byte-identical; nothing of the old session reaches it.
void client_reboot(uint32_t reboot_seed) {
  FaultConfig down = mixed_faults(31, 1e-5, 1u << 30), up = mixed_faults(32, 1e-5, 1u << 30);
  const uint64_t total = 512 << 10;
  LinkSim sim(1000000, down, up, host_config(3), device_config(4));
  Transfer t;
  t.src.seed = t.rd.check.seed = 77;
  t.src.total = total;
  bool rebooted = false;
  uint64_t got_before = 0;
  run(sim, t, 120000, 0, [&](LinkSim& s) {
    if (!rebooted && t.rd.check.got >= total / 2) {
      rebooted = true;
      got_before = t.rd.check.got;
      s.reboot_device(device_config(reboot_seed));
      t.rd = DeviceReader{};  // the new firmware's application starts empty
      t.rd.check.seed = 77;
    }
  });
  ASSERT_TRUE(rebooted);
  EXPECT_GE(got_before, total / 2);
  EXPECT_EQ(sim.host().last_reset(), ResetReason::peer_restarted);
  EXPECT_EQ(sim.host().session_epoch(), 2u);
  EXPECT_EQ(sim.host().stats().resets, 1u);
  EXPECT_EQ(t.src.restarts, 1u) << "the host sent the stream again from the start";
  EXPECT_EQ(sim.device().session_epoch(), 1u);
  EXPECT_EQ(t.rd.check.got, total);
  EXPECT_TRUE(t.rd.check.intact) << "first bad byte at " << t.rd.check.first_bad;
  EXPECT_TRUE(t.src.done(sim.host()));
}

TEST(LinkConformance, ClientRebootMidStream) { client_reboot(1234); }
// A client without entropy comes back with the same nonce: the echo rule
// still tells the host its peer lost the session.
TEST(LinkConformance, ClientRebootWithSameNonceMidStream) { client_reboot(4); }

// Specified state after a host restart mid-stream: the client sees the
// session end (peer_restarted) and drops what it had not read; what it
// delivered before was a correct prefix; the new session delivers the
// whole stream again from byte 0.
TEST(LinkConformance, HostRestartMidStream) {
  FaultConfig down = mixed_faults(41, 1e-5, 1u << 30), up = mixed_faults(42, 1e-5, 1u << 30);
  const uint64_t total = 512 << 10;
  LinkSim sim(1000000, down, up, host_config(5), device_config(6));
  Transfer t;
  t.src.seed = t.rd.check.seed = 78;
  t.src.total = total;
  bool restarted = false;
  bool prefix_ok = false;
  run(sim, t, 120000, 0, [&](LinkSim& s) {
    if (!restarted && t.rd.check.got >= total / 3) {
      restarted = true;
      prefix_ok = t.rd.check.intact;
      s.restart_host(host_config(500));
      t.src = StreamSource{};
      t.src.seed = 78;
      t.src.total = total;
    }
  });
  ASSERT_TRUE(restarted);
  EXPECT_TRUE(prefix_ok) << "the old session delivered a correct prefix";
  EXPECT_EQ(sim.device().last_reset(), ResetReason::peer_restarted);
  EXPECT_EQ(sim.device().session_epoch(), 2u);
  EXPECT_EQ(t.rd.restarts, 1u);
  EXPECT_EQ(sim.host().session_epoch(), 1u);
  EXPECT_EQ(t.rd.check.got, total);
  EXPECT_TRUE(t.rd.check.intact) << "first bad byte at " << t.rd.check.first_bad;
}

// A slow client application: the window stays full, the sender waits, and
// the receiver never holds more than its window.
TEST(LinkConformance, WindowNeverExceededWithSlowReader) {
  FaultConfig down = mixed_faults(51, 1e-4, 1u << 30), up = mixed_faults(52, 1e-4, 1u << 30);
  LinkConfig dc = device_config(8);
  dc.channels[channel::kStream].rx_bytes = 1500;  // an odd size: no power of two assumed
  const uint64_t total = 256 << 10;
  LinkSim sim(1000000, down, up, host_config(7), dc);
  Transfer t;
  t.src.seed = t.rd.check.seed = 79;
  t.src.total = total;
  t.rd.max_chunk = 13;  // 13 bytes per ms: far slower than the line
  uint32_t peak = 0;
  run(sim, t, 400000, 0, [&](LinkSim& s) {
    const uint32_t held = static_cast<uint32_t>(s.device().readable(channel::kStream));
    ASSERT_LE(held, 1500u);
    peak = std::max(peak, s.device().rx_peak(channel::kStream));
  });
  EXPECT_EQ(t.rd.check.got, total);
  EXPECT_TRUE(t.rd.check.intact);
  EXPECT_EQ(sim.device().stats().out_of_window, 0u);
  EXPECT_GE(peak, 1500u / 2) << "the window was used";
  EXPECT_LE(peak, 1500u) << "and never more";
  EXPECT_LE(sim.device().rx_peak(channel::kStream), 1500u);
}

// Real-time transfer between two endpoints over backends, in one thread.
void real_time_transfer(Backend& host_end, Backend& dev_end, uint64_t total, uint32_t seconds,
                        const std::function<void(uint64_t)>& meddle = {}) {
  const LinkConfig hc = host_config(21), dc = device_config(22);
  std::vector<uint64_t> hw((link_workspace_size(hc) + 7) / 8), dw((link_workspace_size(dc) + 7) / 8);
  vds::Arena ha(hw.data(), hw.size() * 8), da(dw.data(), dw.size() * 8);
  Link host, dev;
  ASSERT_EQ(host.init(hc, ha), Status::ok);
  ASSERT_EQ(dev.init(dc, da), Status::ok);
  Pump hp(host, host_end), dp(dev, dev_end);
  StreamSource src;
  DeviceReader rd;
  src.seed = rd.check.seed = 88;
  src.total = total;
  const uint32_t start = monotonic_ms();
  while (monotonic_ms() - start < seconds * 1000u) {
    const uint32_t now = monotonic_ms();
    src.pump(host);
    hp.step(now, 0);
    dp.step(now, 1);
    rd.pump(dev);
    if (meddle) meddle(rd.check.got);
    if (rd.check.got == total && src.done(host)) break;
  }
  EXPECT_EQ(rd.check.got, total);
  EXPECT_TRUE(rd.check.intact);
  EXPECT_EQ(host.session_epoch(), 1u);
  EXPECT_EQ(dev.stats().out_of_window, 0u);
  std::printf("[ info ] %s: %llu KiB in %u ms real time, %u retransmissions, %u frames dropped\n",
              host_end.describe().c_str(), static_cast<unsigned long long>(total >> 10), monotonic_ms() - start,
              host.stats().retransmissions, dev.stats().dropped() + host.stats().dropped());
}

TEST(LinkConformance, PtyPairInRawModeWithGarbage) {
  PtyPair pty = open_pty_pair();
  std::unique_ptr<FdBackend> slave = open_serial(pty.slave_path, 115200);
  // The termios settings really are raw at the chosen speed.
  termios t{};
  ASSERT_EQ(tcgetattr(slave->fd(), &t), 0);
  EXPECT_EQ(cfgetospeed(&t), static_cast<speed_t>(B115200));
  EXPECT_EQ(t.c_lflag & (ICANON | ECHO | ISIG), 0u);
  EXPECT_EQ(t.c_oflag & OPOST, 0u);
  EXPECT_EQ(t.c_cflag & CSIZE, static_cast<tcflag_t>(CS8));
  bool injected = false;
  // Garbage written straight into the line mid-stream (as line noise would
  // put it) costs at most the frames it hits.
  real_time_transfer(*slave, *pty.master, 1 << 20, 30, [&](uint64_t got) {
    if (!injected && got > (256 << 10)) {
      injected = true;
      uint8_t junk[300];
      for (size_t i = 0; i < sizeof junk; ++i) junk[i] = static_cast<uint8_t>(i * 37 + 11);
      ASSERT_EQ(::write(pty.master->fd(), junk, sizeof junk), static_cast<ssize_t>(sizeof junk));
    }
  });
  EXPECT_TRUE(injected);
}

TEST(LinkConformance, TcpClientAndServer) {
  TcpListener l(0);
  std::unique_ptr<FdBackend> client = tcp_connect("127.0.0.1", l.port());
  std::unique_ptr<FdBackend> server = l.accept(2000);
  ASSERT_NE(server, nullptr);
  real_time_transfer(*client, *server, 2 << 20, 30);
}

}  // namespace
