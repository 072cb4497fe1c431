// Link frame layer: golden encoding, round trips, the worst-case bound,
// every single-bit corruption detected, resynchronisation after garbage,
// and every malformed frame kind reported (never a crash).
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "vds/link/frame.h"

namespace {

using namespace vds::link;
using vds::Status;

std::vector<uint8_t> encode(const FrameHeader& h, const std::vector<uint8_t>& p) {
  std::vector<uint8_t> out(frame_wire_bound(p.size()));
  size_t len = 0;
  EXPECT_EQ(frame_encode(h, p.data(), p.size(), out.data(), out.size(), &len), Status::ok);
  out.resize(len);
  return out;
}

struct Got {
  std::vector<RxEvent> events;
  std::vector<FrameHeader> headers;
  std::vector<std::vector<uint8_t>> payloads;
};

Got feed(FrameReceiver& r, const std::vector<uint8_t>& bytes) {
  Got g;
  size_t at = 0;
  while (at < bytes.size()) {
    RxEvent ev;
    RxFrame f;
    at += r.push(bytes.data() + at, bytes.size() - at, &ev, &f);
    if (ev == RxEvent::none || ev == RxEvent::empty) continue;
    g.events.push_back(ev);
    if (ev == RxEvent::frame) {
      g.headers.push_back(f.header);
      g.payloads.emplace_back(f.payload, f.payload + f.size);
    }
  }
  return g;
}

FrameHeader hdr(FrameType t, uint8_t ch, uint8_t tag, uint16_t seq) {
  FrameHeader h;
  h.type = t;
  h.channel = ch;
  h.tag = tag;
  h.seq = seq;
  return h;
}

TEST(LinkFrame, GoldenEncoding) {
  // type data, channel 2, tag 0x5A, seq 0x0100, payload {0x11, 0x00}:
  // header 02 5A 00 01, then CRC-32C(02 5A 00 01 11 00) = 0x08B6F875
  // (bitwise reference computation) little-endian; COBS blocks 03|02 5A,
  // 03|01 11, 05|75 F8 B6 08, delimiter.
  const std::vector<uint8_t> enc = encode(hdr(FrameType::data, 2, 0x5A, 0x0100), {0x11, 0x00});
  const std::vector<uint8_t> want = {0x03, 0x02, 0x5A, 0x03, 0x01, 0x11, 0x05, 0x75, 0xF8, 0xB6, 0x08, 0x00};
  EXPECT_EQ(enc, want);
  std::vector<uint8_t> buf(frame_rx_buffer_size(16));
  FrameReceiver r;
  r.init(buf.data(), buf.size());
  const Got g = feed(r, enc);
  ASSERT_EQ(g.events.size(), 1u);
  EXPECT_EQ(g.headers[0].seq, 0x0100);
  EXPECT_EQ(g.payloads[0], (std::vector<uint8_t>{0x11, 0x00}));
}

TEST(LinkFrame, RoundTripsAndStaysWithinBound) {
  std::mt19937 rng(3);
  std::vector<uint8_t> buf(frame_rx_buffer_size(1100));
  FrameReceiver r;
  r.init(buf.data(), buf.size());
  for (size_t n = 0; n <= 1100; n += (n < 300 ? 1 : 37)) {
    for (int kind = 0; kind < 3; ++kind) {
      std::vector<uint8_t> p(n);
      for (auto& b : p) b = kind == 0 ? 0 : kind == 1 ? static_cast<uint8_t>(1 + rng() % 255) : static_cast<uint8_t>(rng());
      const FrameHeader h = hdr(static_cast<FrameType>(rng() % kFrameTypeCount), static_cast<uint8_t>(rng() % 16),
                                static_cast<uint8_t>(rng()), static_cast<uint16_t>(rng()));
      const std::vector<uint8_t> enc = encode(h, p);
      ASSERT_LE(enc.size(), frame_wire_bound(n));
      ASSERT_LE(enc.size(), n + kFrameOverhead + (n + kFrameOverhead) / 254 + 2) << "one byte per 254 + delimiter";
      for (size_t i = 0; i + 1 < enc.size(); ++i) ASSERT_NE(enc[i], 0) << "a 0x00 inside a frame";
      ASSERT_EQ(enc.back(), 0);
      const Got g = feed(r, enc);
      ASSERT_EQ(g.events.size(), 1u);
      ASSERT_EQ(g.events[0], RxEvent::frame);
      EXPECT_EQ(g.headers[0].type, h.type);
      EXPECT_EQ(g.headers[0].channel, h.channel);
      EXPECT_EQ(g.headers[0].tag, h.tag);
      EXPECT_EQ(g.headers[0].seq, h.seq);
      ASSERT_EQ(g.payloads[0], p);
    }
  }
}

TEST(LinkFrame, EncodeRefusesSmallBufferAndBadHeader) {
  std::vector<uint8_t> p(300, 7), out(frame_wire_bound(300));
  size_t len = 0;
  FrameHeader h;
  EXPECT_EQ(frame_encode(h, p.data(), p.size(), out.data(), out.size() - 1, &len), Status::output_too_small);
  EXPECT_EQ(frame_encode(h, p.data(), p.size(), out.data(), out.size(), &len), Status::ok);
  h.channel = 16;
  EXPECT_EQ(frame_encode(h, p.data(), p.size(), out.data(), out.size(), &len), Status::invalid_argument);
  h.channel = 0;
  h.type = static_cast<FrameType>(9);
  EXPECT_EQ(frame_encode(h, p.data(), p.size(), out.data(), out.size(), &len), Status::invalid_argument);
  // Split payloads encode the same bytes as a whole one.
  std::vector<uint8_t> a(out.size()), b(out.size());
  size_t la = 0, lb = 0;
  h.type = FrameType::data;
  ASSERT_EQ(frame_encode(h, p.data(), p.size(), a.data(), a.size(), &la), Status::ok);
  ASSERT_EQ(frame_encode_parts(h, p.data(), 100, p.data() + 100, 200, b.data(), b.size(), &lb), Status::ok);
  EXPECT_EQ(la, lb);
  EXPECT_EQ(a, b);
}

// Every single-bit corruption of a frame on the wire (delimiter included)
// is detected: the damaged frame is never delivered. A flipped delimiter
// merges the frame with the next, which then is lost too (resync within
// one frame); the frame after that always arrives.
TEST(LinkFrame, EverySingleBitCorruptionIsDetected) {
  std::mt19937 rng(17);
  std::vector<std::vector<uint8_t>> frames;
  auto rnd = [&](size_t n, int zero_every) {
    std::vector<uint8_t> p(n);
    for (auto& b : p) b = zero_every && rng() % zero_every == 0 ? 0 : static_cast<uint8_t>(rng());
    return p;
  };
  frames.push_back(encode(hdr(FrameType::data, 0, 0x31, 0x1234), rnd(1024, 0)));
  frames.push_back(encode(hdr(FrameType::data, 1, 0x00, 0xFFFF), rnd(300, 3)));
  frames.push_back(encode(hdr(FrameType::data, 0, 0x7F, 0x0000), std::vector<uint8_t>(64, 0)));
  frames.push_back(encode(hdr(FrameType::ack, 0, 0x31, 0x0400), rnd(14, 4)));
  frames.push_back(encode(hdr(FrameType::hello, 0, 0, 0), rnd(36, 5)));
  frames.push_back(encode(hdr(FrameType::datagram, 2, 0x31, 7), rnd(24, 0)));
  const std::vector<uint8_t> next = encode(hdr(FrameType::data, 3, 0x44, 0x5555), rnd(40, 6));
  const std::vector<uint8_t> after = encode(hdr(FrameType::data, 4, 0x45, 0x6666), rnd(40, 6));

  std::vector<uint8_t> buf(frame_rx_buffer_size(1100));
  FrameReceiver r;
  r.init(buf.data(), buf.size());
  uint64_t cases = 0;
  for (const auto& f : frames) {
    for (size_t bit = 0; bit < f.size() * 8; ++bit) {
      std::vector<uint8_t> wire = f;
      wire[bit / 8] = static_cast<uint8_t>(wire[bit / 8] ^ (1u << (bit % 8)));
      wire.insert(wire.end(), next.begin(), next.end());
      wire.insert(wire.end(), after.begin(), after.end());
      r.reset();
      const Got g = feed(r, wire);
      size_t delivered = 0;
      for (size_t i = 0; i < g.payloads.size(); ++i) {
        const bool is_next = g.headers[i].channel == 3 && g.headers[i].seq == 0x5555;
        const bool is_after = g.headers[i].channel == 4 && g.headers[i].seq == 0x6666;
        ASSERT_TRUE(is_next || is_after) << "corrupted frame delivered, bit " << bit;
        ++delivered;
      }
      ASSERT_GE(delivered, 1u) << "lost more than one frame after the damage, bit " << bit;
      ASSERT_NE(g.events.front(), RxEvent::frame) << "the damage went unreported, bit " << bit;
      ++cases;
    }
  }
  EXPECT_GT(cases, 10000u);
}

TEST(LinkFrame, ResynchronisesAfterGarbageWithinOneFrame) {
  std::mt19937 rng(23);
  std::vector<uint8_t> buf(frame_rx_buffer_size(256));
  FrameReceiver r;
  r.init(buf.data(), buf.size());
  const std::vector<uint8_t> f1 = encode(hdr(FrameType::data, 1, 9, 100), std::vector<uint8_t>(200, 0xA5));
  const std::vector<uint8_t> f2 = encode(hdr(FrameType::data, 2, 9, 200), std::vector<uint8_t>(50, 0x00));
  for (int trial = 0; trial < 2000; ++trial) {
    // Garbage of every flavour: short or longer than the buffer, with or
    // without zeros, ending on a zero or not.
    const size_t len = trial % 10 == 0 ? 300 + rng() % 3000 : rng() % 80;
    std::vector<uint8_t> wire(len);
    const int mode = trial % 3;
    for (auto& b : wire) b = mode == 0 ? static_cast<uint8_t>(1 + rng() % 255) : static_cast<uint8_t>(rng());
    const bool ends_clean = !wire.empty() && trial % 4 == 0;
    if (ends_clean) wire.back() = 0;
    wire.insert(wire.end(), f1.begin(), f1.end());
    wire.insert(wire.end(), f2.begin(), f2.end());
    r.reset();
    const Got g = feed(r, wire);
    ASSERT_FALSE(g.headers.empty()) << trial;
    EXPECT_EQ(g.headers.back().seq, 200) << "the frame after the first delimiter is always received";
    for (const auto& h : g.headers) ASSERT_TRUE(h.seq == 100 || h.seq == 200);
    if (ends_clean || wire.size() == f1.size() + f2.size()) EXPECT_EQ(g.headers.size(), 2u) << trial;
  }
}

TEST(LinkFrame, MalformedFramesAreReportedByKind) {
  std::vector<uint8_t> buf(frame_rx_buffer_size(64));
  FrameReceiver r;
  r.init(buf.data(), buf.size());
  // Too long: more bytes than the buffer before a delimiter.
  std::vector<uint8_t> lng(buf.size() + 10, 0x42);
  lng.push_back(0);
  EXPECT_EQ(feed(r, lng).events, (std::vector<RxEvent>{RxEvent::too_long}));
  // Bad COBS: a code byte pointing past the end.
  EXPECT_EQ(feed(r, {0x09, 0x01, 0x02, 0x00}).events, (std::vector<RxEvent>{RxEvent::bad_cobs}));
  // Too short: valid COBS, fewer bytes than header + CRC.
  EXPECT_EQ(feed(r, {0x04, 0x01, 0x02, 0x03, 0x00}).events, (std::vector<RxEvent>{RxEvent::too_short}));
  // Bad CRC.
  std::vector<uint8_t> f = encode(hdr(FrameType::data, 1, 2, 3), {1, 2, 3, 4});
  f[f.size() - 3] ^= 0x10;
  EXPECT_EQ(feed(r, f).events, (std::vector<RxEvent>{RxEvent::bad_crc}));
  // Idle delimiters are not errors; the receiver still works afterwards.
  EXPECT_TRUE(feed(r, {0x00, 0x00, 0x00}).events.empty());
  const Got ok = feed(r, encode(hdr(FrameType::data, 1, 2, 3), {5, 6}));
  EXPECT_EQ(ok.events, (std::vector<RxEvent>{RxEvent::frame}));
  // Every prefix of a frame followed by a delimiter fails cleanly.
  const std::vector<uint8_t> whole = encode(hdr(FrameType::ack, 5, 6, 7), std::vector<uint8_t>(40, 3));
  for (size_t cut = 1; cut + 1 < whole.size(); ++cut) {
    std::vector<uint8_t> pre(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(cut));
    pre.push_back(0);
    const Got g = feed(r, pre);
    ASSERT_EQ(g.events.size(), 1u);
    EXPECT_NE(g.events[0], RxEvent::frame) << cut;
  }
}

}  // namespace
