// COBS framing: round trips, the worst-case overhead bound, and rejection of
// malformed frame bodies.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "vds/link/cobs.h"

namespace {

using vds::Status;
using vds::link::cobs_decode;
using vds::link::cobs_encode;
using vds::link::cobs_encoded_bound;

std::vector<uint8_t> encode(const std::vector<uint8_t>& in) {
  std::vector<uint8_t> out(cobs_encoded_bound(in.size()));
  size_t len = 0;
  EXPECT_EQ(cobs_encode(in.data(), in.size(), out.data(), out.size(), &len), Status::ok);
  out.resize(len);
  return out;
}

void expect_round_trip(const std::vector<uint8_t>& in) {
  const std::vector<uint8_t> enc = encode(in);
  EXPECT_LE(enc.size(), cobs_encoded_bound(in.size()));
  for (uint8_t b : enc) ASSERT_NE(b, 0) << "encoded data must contain no delimiter";
  std::vector<uint8_t> dec(in.size());
  size_t len = 0;
  ASSERT_EQ(cobs_decode(enc.data(), enc.size(), dec.data(), dec.size(), &len), Status::ok);
  ASSERT_EQ(len, in.size());
  EXPECT_EQ(dec, in);
}

TEST(Cobs, KnownEncodings) {
  EXPECT_EQ(encode({}), (std::vector<uint8_t>{0x01}));
  EXPECT_EQ(encode({0x00}), (std::vector<uint8_t>{0x01, 0x01}));
  EXPECT_EQ(encode({0x11, 0x22, 0x00, 0x33}), (std::vector<uint8_t>{0x03, 0x11, 0x22, 0x02, 0x33}));
  EXPECT_EQ(encode({0x11, 0x00, 0x00}), (std::vector<uint8_t>{0x02, 0x11, 0x01, 0x01}));
}

TEST(Cobs, RoundTripsEveryLengthAroundBlockBoundaries) {
  std::mt19937 rng(11);
  for (size_t n = 0; n < 800; ++n) {
    std::vector<uint8_t> zeros(n, 0), ff(n, 0xFF), rnd(n);
    for (auto& b : rnd) b = static_cast<uint8_t>(rng() % 4 == 0 ? 0 : rng());
    expect_round_trip(zeros);
    expect_round_trip(ff);
    expect_round_trip(rnd);
  }
}

TEST(Cobs, WorstCaseOverheadIsOneBytePer254) {
  for (size_t n : {1u, 253u, 254u, 255u, 508u, 1024u, 4096u}) {
    std::vector<uint8_t> no_zeros(n, 0x5A);
    const size_t len = encode(no_zeros).size();
    EXPECT_LE(len - n, n / 254 + 1) << n;
    std::vector<uint8_t> all_zeros(n, 0);
    EXPECT_EQ(encode(all_zeros).size(), n + 1) << n;
  }
}

TEST(Cobs, EncodeRefusesAShortBuffer) {
  std::vector<uint8_t> in(300, 1), out(cobs_encoded_bound(300) - 1);
  size_t len = 0;
  EXPECT_EQ(cobs_encode(in.data(), in.size(), out.data(), out.size(), &len), Status::output_too_small);
}

TEST(Cobs, EncodeAtTheEndOfABoundSizedBuffer) {
  // The encoder must not write past the bound, even by one byte.
  std::vector<uint8_t> in(254 * 3, 0x42);
  std::vector<uint8_t> out(cobs_encoded_bound(in.size()));
  size_t len = 0;
  ASSERT_EQ(cobs_encode(in.data(), in.size(), out.data(), out.size(), &len), Status::ok);
  EXPECT_LE(len, out.size());
}

TEST(Cobs, RejectsMalformedBodies) {
  std::vector<uint8_t> out(64);
  size_t len = 0;
  const std::vector<std::vector<uint8_t>> bad = {
      {},                  // empty
      {0x00},              // delimiter inside
      {0x05, 0x11, 0x22},  // code points past the end
      {0x03, 0x11, 0x00},  // zero data byte
  };
  for (const auto& b : bad) EXPECT_TRUE(vds::is_error(cobs_decode(b.data(), b.size(), out.data(), out.size(), &len)));
  const std::vector<uint8_t> enc = encode(std::vector<uint8_t>(100, 7));
  EXPECT_EQ(cobs_decode(enc.data(), enc.size(), out.data(), 50, &len), Status::output_too_small);
}

TEST(Cobs, DecodesInPlace) {
  std::vector<uint8_t> in = {1, 0, 2, 0, 0, 3, 4, 5, 0};
  std::vector<uint8_t> buf = encode(in);
  size_t len = 0;
  ASSERT_EQ(cobs_decode(buf.data(), buf.size(), buf.data(), buf.size(), &len), Status::ok);
  buf.resize(len);
  EXPECT_EQ(buf, in);
}

}  // namespace
