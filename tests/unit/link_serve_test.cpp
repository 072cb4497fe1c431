// `vds serve` end to end (serve_stream): over the loopback with faults the
// in-process client verifies every chunk and its end-of-stream report
// matches; over a real pty a client thread running the link core does the
// same. Either way the host answers the report with a Goodbye that says
// whether the report matched, and closes once the client acknowledged it.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "link_stream.h"
#include "vds/crc32c.h"
#include "vds/link/fd_backends.h"
#include "vds/link/messages.h"
#include "vds/link/serve.h"

namespace {

using namespace vds::link;
using vds::link::linktest::make_stream;
using vds::Status;

TEST(LinkServe, LoopbackClientVerifiesTheStream) {
  const std::vector<uint8_t> s = make_stream(20, 8000);
  ServeOptions o;
  o.baud = 1000000;
  o.faults.seed = 3;
  o.faults.bit_error_rate = 1e-4;
  o.faults.frame_drop_rate = 0.05;
  o.nonce_seed = 9;
  const ServeReport r = serve_stream(s, o);
  EXPECT_TRUE(r.receipt);
  EXPECT_EQ(r.receipt_bytes, s.size());
  EXPECT_EQ(r.receipt_crc, vds::crc32c(s.data(), s.size()));
  EXPECT_EQ(r.client_chunks, 22u) << "HEAD, 20 data chunks and END verified";
  EXPECT_EQ(r.sessions, 1u);
  EXPECT_GT(r.host.retransmissions, 0u);
  EXPECT_GT(r.goodput, 0.5);
  EXPECT_TRUE(r.client_goodbye);
  EXPECT_TRUE(r.client_goodbye_verified);
  EXPECT_TRUE(r.goodbye_acked);
}

TEST(LinkServe, RefusesWhatIsNotAStream) {
  std::vector<uint8_t> junk(5000, 0x42);
  EXPECT_THROW(serve_stream(junk, ServeOptions{}), std::runtime_error);
}

// A client thread on a pty's master end: the link core, a DoneReport once
// the whole stream is in — or, with `full_at`, a workspace-full report on
// the first `full_at` bytes or more, after which it drops what still comes,
// and which announces one frame whose record follows 1.5 s later (the host
// waits for it: long enough to have sent the whole stream had it not
// stopped) — with the CRC spoiled when `lie` is set; then it waits for the
// host's Goodbye and stops as the firmware does.
struct PtyClientResult {
  uint64_t got = 0;       // stream bytes the report covers
  uint64_t dropped = 0;   // stream bytes that came after a workspace-full report
  bool goodbye = false;
  Goodbye bye{};
};

ServeReport serve_to_pty_client(const std::vector<uint8_t>& s, bool lie, PtyClientResult* out, size_t full_at = 0) {
  PtyPair pty = open_pty_pair();
  std::atomic<bool> stop{false};
  std::thread client([&] {
    const LinkConfig dc = device_config(77);
    std::vector<uint64_t> ws((link_workspace_size(dc) + 7) / 8);
    vds::Arena a(ws.data(), ws.size() * 8);
    Link dev;
    if (dev.init(dc, a) != Status::ok) return;
    Pump pump(dev, *pty.master);
    uint32_t crc = 0;
    bool sent = false;
    bool record_sent = false;
    uint32_t sent_at = 0;
    uint8_t buf[1024];
    MessageReader<kGoodbyeBytes> ctl;
    try {
      while (!stop && !out->goodbye) {
        pump.step(monotonic_ms(), 1);
        size_t n = 0;
        while (dev.read(channel::kStream, buf, sizeof buf, &n) == Status::ok && n != 0) {
          if (sent && full_at != 0) {
            out->dropped += n;
            continue;
          }
          crc = vds::crc32c_update(crc, buf, n);
          out->got += n;
        }
        const bool full = full_at != 0 && out->got >= full_at;
        if (!sent && (out->got == s.size() || full)) {
          uint8_t r[kDoneReportBytes];
          encode(DoneReport{0, full ? 1u : 0u, static_cast<uint32_t>(out->got), lie ? crc ^ 1u : crc,
                            full ? DoneReason::workspace_full : DoneReason::end_of_stream},
                 r);
          size_t acc = 0;
          sent = dev.write(channel::kControl, r, sizeof r, &acc) == Status::ok && acc == sizeof r;
          sent_at = monotonic_ms();
        }
        if (sent && full_at != 0 && !record_sent && monotonic_ms() - sent_at > 1500) {
          uint8_t f[kFrameRecordBytes];
          encode(FrameRecord{0, 0x1234u, 0, 0, 0, 0, 0, 0, 0}, f);
          size_t acc = 0;
          record_sent = dev.write(channel::kChecksums, f, sizeof f, &acc) == Status::ok && acc == sizeof f;
        }
        while (!out->goodbye && ctl.next(dev, channel::kControl))
          out->goodbye = decode(ctl.bytes, kGoodbyeBytes, &out->bye) == Status::ok;
      }
      dev.flush_acks();
      pump.step(monotonic_ms(), 1);  // the Goodbye's acknowledgement
    } catch (const BackendError&) {
      // the host closed the pty
    }
  });
  ServeOptions o;
  o.link = "pty:" + pty.slave_path;
  o.baud = 921600;
  o.timeout_s = 30;
  ServeReport r;
  try {
    r = serve_stream(s, o);
  } catch (...) {
    stop = true;
    client.join();
    throw;
  }
  // The client stops on the Goodbye by itself; `stop` only ends a client
  // that never got one (the assertions below then fail).
  const uint32_t t0 = monotonic_ms();
  while (!out->goodbye && monotonic_ms() - t0 < 3000) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  stop = true;
  client.join();
  return r;
}

TEST(LinkServe, OverAPtyToAClientThread) {
  const std::vector<uint8_t> s = make_stream(8, 16000);
  PtyClientResult c;
  ServeReport r;
  EXPECT_NO_THROW(r = serve_to_pty_client(s, false, &c));
  EXPECT_EQ(c.got, s.size());
  EXPECT_TRUE(r.receipt);
  EXPECT_FALSE(r.simulated);
  ASSERT_TRUE(c.goodbye) << "the host answers the report with a Goodbye";
  EXPECT_EQ(c.bye.verified, 1);
  EXPECT_EQ(c.bye.frame_records, 0u);
  EXPECT_TRUE(r.goodbye_acked) << "and closes once the client acknowledged it";
}

TEST(LinkServe, AClientWhoseWorkspaceIsFullStopsTheStream) {
  // 256 KB at 921,600 baud is about 3 s of line; the client is full after
  // 16 KB and its frame record keeps the host waiting 1.5 s.
  const std::vector<uint8_t> s = make_stream(16, 16000);
  PtyClientResult c;
  ServeReport r;
  EXPECT_NO_THROW(r = serve_to_pty_client(s, false, &c, 16000));
  EXPECT_GE(c.got, 16000u);
  EXPECT_LT(c.got, s.size());
  EXPECT_TRUE(r.receipt) << "a workspace-full report proves the prefix it covers";
  EXPECT_TRUE(r.receipt_prefix);
  EXPECT_EQ(r.receipt_bytes, c.got);
  EXPECT_LT(r.bytes_written, s.size() / 2) << "the host wrote no more after the report";
  EXPECT_EQ(r.frame_records, 1u);
  EXPECT_LE(c.got + c.dropped, r.bytes_written);
  EXPECT_GE(r.bytes_acked, c.got) << "everything the report covers was acknowledged";
  EXPECT_LT(r.bytes_acked, s.size() / 2);
  ASSERT_TRUE(c.goodbye);
  EXPECT_EQ(c.bye.verified, 1);
  EXPECT_TRUE(r.goodbye_acked);
}

TEST(LinkServe, AWorkspaceFullReportMustMatchItsPrefix) {
  const std::vector<uint8_t> s = make_stream(16, 16000);
  PtyClientResult c;
  ServeReport r;
  EXPECT_NO_THROW(r = serve_to_pty_client(s, true, &c, 16000));
  EXPECT_TRUE(r.report_seen);
  EXPECT_TRUE(r.receipt_prefix);
  EXPECT_FALSE(r.receipt) << "its CRC is not the prefix's";
  ASSERT_TRUE(c.goodbye);
  EXPECT_EQ(c.bye.verified, 0);
}

TEST(LinkServe, TheGoodbyeSaysWhenTheReportDoesNotMatch) {
  const std::vector<uint8_t> s = make_stream(4, 8000);
  PtyClientResult c;
  ServeReport r;
  EXPECT_NO_THROW(r = serve_to_pty_client(s, true, &c));
  EXPECT_TRUE(r.report_seen);
  EXPECT_FALSE(r.receipt) << "a report whose CRC differs from the stream's proves nothing";
  ASSERT_TRUE(c.goodbye);
  EXPECT_EQ(c.bye.verified, 0);
}

}  // namespace
