// CRC-32C against published check values (RFC 3720 appendix B.4) and
// piecewise continuation.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "vds/crc32c.h"

namespace {

TEST(Crc32c, CheckValue) { EXPECT_EQ(vds::crc32c("123456789", 9), 0xE3069283u); }

TEST(Crc32c, Rfc3720Vectors) {
  uint8_t zeros[32] = {};
  uint8_t ones[32];
  uint8_t inc[32];
  uint8_t dec[32];
  memset(ones, 0xFF, sizeof ones);
  for (int i = 0; i < 32; ++i) {
    inc[i] = static_cast<uint8_t>(i);
    dec[i] = static_cast<uint8_t>(31 - i);
  }
  EXPECT_EQ(vds::crc32c(zeros, 32), 0x8A9136AAu);
  EXPECT_EQ(vds::crc32c(ones, 32), 0x62A8AB43u);
  EXPECT_EQ(vds::crc32c(inc, 32), 0x46DD794Eu);
  EXPECT_EQ(vds::crc32c(dec, 32), 0x113FDB5Cu);
}

TEST(Crc32c, EmptyIsZero) { EXPECT_EQ(vds::crc32c(nullptr, 0), 0u); }

TEST(Crc32c, PiecewiseEqualsWhole) {
  std::mt19937 rng(7);
  std::vector<uint8_t> data(1000);
  for (auto& b : data) b = static_cast<uint8_t>(rng());
  const uint32_t whole = vds::crc32c(data.data(), data.size());
  for (size_t split = 0; split <= data.size(); split += 37) {
    uint32_t c = vds::crc32c_update(0, data.data(), split);
    c = vds::crc32c_update(c, data.data() + split, data.size() - split);
    EXPECT_EQ(c, whole) << "split at " << split;
  }
}

TEST(Crc32c, DetectsEverySingleBitFlip) {
  std::vector<uint8_t> data(64);
  for (size_t i = 0; i < data.size(); ++i) data[i] = static_cast<uint8_t>(i * 7 + 3);
  const uint32_t ref = vds::crc32c(data.data(), data.size());
  for (size_t bit = 0; bit < data.size() * 8; ++bit) {
    data[bit / 8] ^= static_cast<uint8_t>(1u << (bit % 8));
    EXPECT_NE(vds::crc32c(data.data(), data.size()), ref) << "bit " << bit;
    data[bit / 8] ^= static_cast<uint8_t>(1u << (bit % 8));
  }
}

}  // namespace

// Every length and alignment against the bit-at-a-time definition, so the
// word-wise path, its byte tail and any start offset agree with it.
TEST(Crc32c, MatchesBitwiseDefinitionAtEveryLengthAndOffset) {
  auto bitwise = [](const uint8_t* p, size_t n) {
    uint32_t c = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; ++i) {
      c ^= p[i];
      for (int b = 0; b < 8; ++b) c = (c & 1u) ? (c >> 1) ^ 0x82F63B78u : c >> 1;
    }
    return ~c;
  };
  uint8_t buf[80];
  uint32_t x = 12345u;
  for (uint8_t& b : buf) {
    x = x * 1103515245u + 12345u;
    b = static_cast<uint8_t>(x >> 24);
  }
  for (size_t off = 0; off < 4; ++off)
    for (size_t n = 0; off + n <= sizeof buf; ++n) ASSERT_EQ(vds::crc32c(buf + off, n), bitwise(buf + off, n)) << off << " " << n;
}
