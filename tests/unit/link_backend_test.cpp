// Host backends: the loopback wire's pacing and seeded faults (rates,
// reproducibility, cuts, stalls), and clean, named errors from opening
// pty/serial, TCP and malformed --link arguments.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>
#include <vector>

#include "vds/link/fd_backends.h"
#include "vds/link/loopback.h"

namespace {

using namespace vds::link;

std::vector<uint8_t> run_wire(const FaultConfig& f, uint32_t baud, uint64_t ms, uint64_t* written) {
  Wire w(baud, 1, f);
  std::vector<uint8_t> out, buf(1 << 16);
  uint64_t i = 0;
  *written = 0;
  for (uint64_t t = 1; t <= ms; ++t) {
    w.advance_to(t);
    std::vector<uint8_t> chunk(w.room());
    for (auto& b : chunk) {
      // 40-byte "frames" ending in a delimiter.
      b = (i % 40 == 39) ? 0 : static_cast<uint8_t>(1 + i % 200);
      ++i;
    }
    *written += w.write(chunk.data(), chunk.size());
    const size_t n = w.read(buf.data(), buf.size());
    out.insert(out.end(), buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(n));
  }
  return out;
}

TEST(LinkWire, PacesAtTenBitsPerByte) {
  uint64_t written = 0;
  const std::vector<uint8_t> out = run_wire({}, 115200, 10000, &written);
  EXPECT_NEAR(static_cast<double>(written), 115200.0, 30.0) << "10 s at 115200 baud = 115200 bytes";
  EXPECT_NEAR(static_cast<double>(out.size()), 115200.0, 60.0);
  run_wire({}, 1000000, 1000, &written);
  EXPECT_NEAR(static_cast<double>(written), 100000.0, 30.0);
}

TEST(LinkWire, FaultsAreSeededAndAtTheirRates) {
  FaultConfig f;
  f.seed = 9;
  f.bit_error_rate = 1e-3;
  f.frame_drop_rate = 0.05;
  f.frame_dup_rate = 0.02;
  f.frame_truncate_rate = 0.02;
  f.garbage_rate = 0.01;
  f.byte_drop_rate = 1e-4;
  uint64_t w1 = 0, w2 = 0, w3 = 0;
  Wire probe(1000000, 1, f);
  const std::vector<uint8_t> a = run_wire(f, 1000000, 10000, &w1);
  const std::vector<uint8_t> b = run_wire(f, 1000000, 10000, &w2);
  EXPECT_EQ(a, b) << "same seed, same faults";
  f.seed = 10;
  const std::vector<uint8_t> c = run_wire(f, 1000000, 10000, &w3);
  EXPECT_NE(a, c);
  // Rates: run once more keeping the wire to read its counters.
  Wire w(1000000, 1, f);
  std::vector<uint8_t> buf(4096);
  uint64_t i = 0;
  for (uint64_t t = 1; t <= 10000; ++t) {
    w.advance_to(t);
    std::vector<uint8_t> chunk(w.room());
    for (auto& x : chunk) {
      x = (i % 40 == 39) ? 0 : static_cast<uint8_t>(1 + i % 200);
      ++i;
    }
    w.write(chunk.data(), chunk.size());
    while (w.read(buf.data(), buf.size()) != 0) {
    }
  }
  const WireStats& s = w.stats();
  const double frames = static_cast<double>(s.frames);
  EXPECT_NEAR(frames, 1e6 / 40, 2);
  EXPECT_NEAR(static_cast<double>(s.frames_dropped) / frames, 0.05, 0.005);
  EXPECT_NEAR(static_cast<double>(s.frames_duplicated) / frames, 0.02, 0.003);
  EXPECT_NEAR(static_cast<double>(s.garbage_bursts) / frames, 0.01, 0.002);
  // Bits on the wire after drops and duplicates, about 8 per byte out.
  EXPECT_NEAR(static_cast<double>(s.bit_flips) / (8.0 * static_cast<double>(s.bytes_out)), 1e-3, 1e-4);
  EXPECT_GT(s.frames_truncated, 0u);
  EXPECT_GT(s.bytes_dropped, 0u);
}

TEST(LinkWire, CutLosesEverythingThenComesBack) {
  FaultConfig f;
  f.cuts = {{100, 200}};
  Wire w(1000000, 5, f);
  std::vector<uint8_t> buf(1 << 16);
  uint64_t got_during = 0, got_after = 0;
  for (uint64_t t = 1; t <= 400; ++t) {
    w.advance_to(t);
    std::vector<uint8_t> chunk(w.room(), 0x55);
    chunk.back() = 0;
    w.write(chunk.data(), chunk.size());
    const size_t n = w.read(buf.data(), buf.size());
    if (t >= 100 && t < 200) got_during += n;
    if (t >= 210) got_after += n;
  }
  EXPECT_EQ(got_during, 0u);
  EXPECT_GT(got_after, 15000u);
  EXPECT_GT(w.stats().cut_bytes, 9000u);
}

TEST(LinkWire, StallsDelayButKeepOrder) {
  FaultConfig f;
  f.seed = 4;
  f.stall_rate = 0.01;
  f.stall_max_ms = 30;
  Wire stalled(115200, 1, f), clean(115200, 1, {});
  std::vector<uint8_t> a, b, buf(4096);
  uint64_t lag_ms = 0, i = 0;
  for (uint64_t t = 1; t <= 3000; ++t) {
    stalled.advance_to(t);
    clean.advance_to(t);
    std::vector<uint8_t> chunk(clean.room());
    for (auto& x : chunk) x = static_cast<uint8_t>(++i % 7 == 0 ? 0 : i);
    ASSERT_EQ(stalled.room(), chunk.size()) << "a stall does not stop the sender's line";
    stalled.write(chunk.data(), chunk.size());
    clean.write(chunk.data(), chunk.size());
    a.insert(a.end(), buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(stalled.read(buf.data(), buf.size())));
    b.insert(b.end(), buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(clean.read(buf.data(), buf.size())));
    if (a.size() < b.size()) ++lag_ms;
  }
  for (uint64_t t = 3001; t <= 3100; ++t) {
    stalled.advance_to(t);
    a.insert(a.end(), buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(stalled.read(buf.data(), buf.size())));
  }
  EXPECT_GT(stalled.stats().stalls, 10u);
  EXPECT_GT(lag_ms, 100u) << "deliveries were held back";
  ASSERT_GE(a.size(), b.size());
  EXPECT_TRUE(std::equal(b.begin(), b.end(), a.begin())) << "a stall only delays: same bytes, same order";
}

void expect_error(const std::string& spec, BackendError::Kind kind, const std::string& needle) {
  try {
    open_backend(spec, 115200);
    ADD_FAILURE() << spec << " opened";
  } catch (const BackendError& e) {
    EXPECT_EQ(e.kind(), kind) << spec << ": " << e.what();
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(LinkBackends, OpeningFailsWithNamedErrors) {
  expect_error("serial", BackendError::Kind::bad_spec, "is not loopback, pty:PATH");
  expect_error("pty:", BackendError::Kind::bad_spec, "needs a path");
  expect_error("pty:/nonexistent/tty", BackendError::Kind::not_found, "/nonexistent/tty");
  expect_error("pty:/dev/null", BackendError::Kind::io, "not a terminal");
  expect_error("tcp:localhost", BackendError::Kind::bad_spec, "tcp:HOST:PORT");
  expect_error("tcp:localhost:99999", BackendError::Kind::bad_spec, "out of range");
  expect_error("usb:zz:1", BackendError::Kind::bad_spec, "VID:PID");
  {
    // A port that was just free: nobody listens there.
    uint16_t port = 0;
    {
      TcpListener l(0);
      port = l.port();
    }
    expect_error("tcp:127.0.0.1:" + std::to_string(port), BackendError::Kind::not_found, "ECONNREFUSED");
  }
  EXPECT_THROW(baud_to_speed(12345), BackendError);
  EXPECT_NO_THROW(baud_to_speed(921600));
}

TEST(LinkBackends, PtyCarriesBytesBothWaysUnchanged) {
  PtyPair p = open_pty_pair();
  auto slave = open_serial(p.slave_path, 1000000);
  std::vector<uint8_t> all(256);
  for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<uint8_t>(i);  // CR, LF, ^C, ^D, XON...: raw
  ASSERT_EQ(p.master->write(all.data(), all.size()), all.size());
  std::vector<uint8_t> got, buf(512);
  for (int i = 0; i < 100 && got.size() < all.size(); ++i) {
    const size_t n = slave->read(buf.data(), buf.size(), 10);
    got.insert(got.end(), buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(n));
  }
  EXPECT_EQ(got, all);
  ASSERT_EQ(slave->write(all.data(), all.size()), all.size());
  got.clear();
  for (int i = 0; i < 100 && got.size() < all.size(); ++i) {
    const size_t n = p.master->read(buf.data(), buf.size(), 10);
    got.insert(got.end(), buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(n));
  }
  EXPECT_EQ(got, all) << "no echo, no CR/LF translation";
}

// A pseudo-terminal takes any line rate (the modem's 14,400 included) and
// the host paces it: after a burst the room is gone, and it comes back at
// baud/10 bytes per second.
TEST(LinkBackends, PtyTakesAnyBaudAndIsPaced) {
  PtyPair p = open_pty_pair();
  auto slave = open_serial(p.slave_path, 14400);
  slave->set_pacing(14400);  // 1,440 bytes/s, a burst of at most 64 bytes
  std::vector<uint8_t> data(64, 0x55);
  size_t room = slave->write_room();
  for (int i = 0; i < 50 && room < data.size(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    room = slave->write_room();
  }
  ASSERT_EQ(room, data.size()) << "the burst is 64 bytes";
  ASSERT_EQ(slave->write(data.data(), data.size()), data.size());
  EXPECT_LT(slave->write_room(), 32u) << "a burst spends the room (it refills at 1.44 bytes/ms)";
  std::this_thread::sleep_for(std::chrono::milliseconds(25));  // 36 bytes at 1,440 bytes/s
  const size_t later = slave->write_room();
  EXPECT_GE(later, 30u);
  EXPECT_LE(later, 64u);
  EXPECT_THROW(open_serial("/dev/null", 14400), BackendError) << "a real port needs a rate the driver knows";
}

}  // namespace
