// The application messages of the link (vds/link/messages.h): exact bytes,
// round trips, refusal of a wrong type byte, a short message or an
// out-of-range field, and MessageReader putting messages together from the
// pieces a reliable channel hands over.
#include <gtest/gtest.h>

#include <vector>

#include "vds/link/messages.h"
#include "vds/link/sim.h"

namespace {

using namespace vds::link;
using vds::Status;

TEST(LinkMessages, GoodbyeBytesAreFixed) {
  uint8_t b[kGoodbyeBytes];
  ASSERT_EQ(encode(Goodbye{1, 0x01020304u}, b), kGoodbyeBytes);
  const std::vector<uint8_t> want = {4, 1, 0x04, 0x03, 0x02, 0x01};
  EXPECT_EQ(std::vector<uint8_t>(b, b + kGoodbyeBytes), want);
  Goodbye g{};
  ASSERT_EQ(decode(b, sizeof b, &g), Status::ok);
  EXPECT_EQ(g.verified, 1);
  EXPECT_EQ(g.frame_records, 0x01020304u);
}

TEST(LinkMessages, DoneReportBytesAreFixed) {
  uint8_t b[kDoneReportBytes];
  ASSERT_EQ(encode(DoneReport{-2, 3, 0x0A0B0C0Du, 0x11223344u, DoneReason::workspace_full}, b), kDoneReportBytes);
  const std::vector<uint8_t> want = {3,    0xFE, 0xFF, 0xFF, 0xFF, 3,    0,    0,    0, 0x0D,
                                     0x0C, 0x0B, 0x0A, 0x44, 0x33, 0x22, 0x11, 1};
  EXPECT_EQ(std::vector<uint8_t>(b, b + kDoneReportBytes), want);
}

TEST(LinkMessages, EveryMessageRoundTrips) {
  uint8_t b[64];
  const FrameRecord fr{7, 0xDEADBEEFu, 1, 2, 3, 4, 5, 6, 1};
  ASSERT_EQ(encode(fr, b), kFrameRecordBytes);
  FrameRecord fr2{};
  ASSERT_EQ(decode(b, kFrameRecordBytes, &fr2), Status::ok);
  EXPECT_EQ(fr2.index, 7u);
  EXPECT_EQ(fr2.crc, 0xDEADBEEFu);
  EXPECT_EQ(fr2.display_instructions, 5u);
  EXPECT_EQ(fr2.received_ms, 6u);
  EXPECT_EQ(fr2.late, 1);
  EXPECT_EQ(fr2.steered, 0);
  FrameRecord steered = fr;
  steered.late = 0;
  steered.steered = 1;
  ASSERT_EQ(encode(steered, b), kFrameRecordBytes);
  ASSERT_EQ(decode(b, kFrameRecordBytes, &fr2), Status::ok);
  EXPECT_EQ(fr2.late, 0);
  EXPECT_EQ(fr2.steered, 1);
  b[kFrameRecordBytes - 1] = 4;  // no such flag
  EXPECT_EQ(decode(b, kFrameRecordBytes, &fr2), Status::malformed);

  const ClientStats st{1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  ASSERT_EQ(encode(st, b), kClientStatsBytes);
  ClientStats st2{};
  ASSERT_EQ(decode(b, kClientStatsBytes, &st2), Status::ok);
  EXPECT_EQ(st2.uptime_ms, 1u);
  EXPECT_EQ(st2.instruction_resolution, 10u);

  const DoneReport d{-3, 12, 3456, 0x12345678u};
  ASSERT_EQ(encode(d, b), kDoneReportBytes);
  DoneReport d2{};
  ASSERT_EQ(decode(b, kDoneReportBytes, &d2), Status::ok);
  EXPECT_EQ(d2.status, -3);
  EXPECT_EQ(d2.frames_shown, 12u);
  EXPECT_EQ(d2.stream_bytes, 3456u);
  EXPECT_EQ(d2.stream_crc, 0x12345678u);
  EXPECT_EQ(d2.reason, DoneReason::end_of_stream) << "the default: the client read the whole stream";
  const DoneReport full{0, 4, 999, 1, DoneReason::workspace_full};
  encode(full, b);
  ASSERT_EQ(decode(b, kDoneReportBytes, &d2), Status::ok);
  EXPECT_EQ(d2.reason, DoneReason::workspace_full);
  EXPECT_EQ(d2.stream_bytes, 999u);
}

TEST(LinkMessages, WrongTypeShortOrOutOfRangeIsMalformed) {
  uint8_t b[kGoodbyeBytes];
  encode(Goodbye{0, 5}, b);
  Goodbye g{};
  for (size_t n = 0; n < kGoodbyeBytes; ++n) EXPECT_EQ(decode(b, n, &g), Status::malformed) << n << " bytes";
  EXPECT_EQ(decode(nullptr, kGoodbyeBytes, &g), Status::malformed);
  b[1] = 2;  // verified is 0 or 1
  EXPECT_EQ(decode(b, sizeof b, &g), Status::malformed);
  b[1] = 0;
  DoneReport d{};
  EXPECT_EQ(decode(b, sizeof b, &d), Status::malformed) << "a Goodbye is not a DoneReport";
  uint8_t r[kDoneReportBytes];
  encode(DoneReport{0, 0, 0, 0}, r);
  EXPECT_EQ(decode(r, sizeof r, &g), Status::malformed) << "nor a DoneReport a Goodbye";
  EXPECT_EQ(decode(r, sizeof r - 1, &d), Status::malformed) << "a report without its reason byte";
  r[kDoneReportBytes - 1] = 2;  // the reason is 0 or 1
  EXPECT_EQ(decode(r, sizeof r, &d), Status::malformed);
}

TEST(LinkMessages, ReaderAssemblesMessagesFromPieces) {
  LinkSim sim(1000000, FaultConfig{}, FaultConfig{}, host_config(5), device_config(6));
  auto settle = [&] {
    for (int i = 0; i < 2000; ++i) sim.step();
  };
  settle();  // handshake
  ASSERT_TRUE(sim.host().established());
  uint8_t a[kDoneReportBytes], b[kDoneReportBytes];
  encode(DoneReport{0, 1, 2, 3}, a);
  encode(DoneReport{-1, 4, 5, 6}, b);
  auto send = [&](const uint8_t* p, size_t n) {
    size_t took = 0;
    ASSERT_EQ(sim.device().write(channel::kControl, p, n, &took), Status::ok);
    ASSERT_EQ(took, n);
  };
  MessageReader<kDoneReportBytes> r;
  send(a, 5);
  settle();
  EXPECT_FALSE(r.next(sim.host(), channel::kControl)) << "5 of 17 bytes";
  EXPECT_EQ(r.len, 5u);
  send(a + 5, kDoneReportBytes - 5);
  send(b, 9);
  settle();
  ASSERT_TRUE(r.next(sim.host(), channel::kControl));
  DoneReport d{};
  ASSERT_EQ(decode(r.bytes, kDoneReportBytes, &d), Status::ok);
  EXPECT_EQ(d.stream_crc, 3u);
  EXPECT_FALSE(r.next(sim.host(), channel::kControl)) << "9 bytes of the second";
  send(b + 9, kDoneReportBytes - 9);
  settle();
  ASSERT_TRUE(r.next(sim.host(), channel::kControl));
  ASSERT_EQ(decode(r.bytes, kDoneReportBytes, &d), Status::ok);
  EXPECT_EQ(d.status, -1);
  EXPECT_EQ(d.stream_crc, 6u);
  EXPECT_FALSE(r.next(sim.host(), channel::kControl)) << "nothing more";
  r.reset();
  EXPECT_EQ(r.len, 0u);
}

}  // namespace
