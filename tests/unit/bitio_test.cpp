// Bit reader / bit writer: golden bits, round trips, Exp-Golomb limits,
// end-of-buffer rules and prefix sweeps on exact-size heap buffers.
#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <random>
#include <vector>

#include "vds/bitreader.h"
#include "vds/enc/bitwriter.h"

namespace {

using vds::BitReader;
using vds::Status;
using vds::enc::BitWriter;

// A heap copy of exactly `n` bytes so ASan flags any read past the end.
struct ExactBuffer {
  // new uint8_t[0] is a distinct zero-byte allocation: ASan flags any read.
  explicit ExactBuffer(const std::vector<uint8_t>& v, size_t n) : size(n), data(new uint8_t[n]) {
    if (n) std::memcpy(data.get(), v.data(), n);
  }
  explicit ExactBuffer(const std::vector<uint8_t>& v) : ExactBuffer(v, v.size()) {}
  const uint8_t* ptr() const { return data.get(); }
  size_t size;
  std::unique_ptr<uint8_t[]> data;
};

TEST(BitReaderTest, GoldenMsbFirst) {
  const std::vector<uint8_t> bytes = {0xA5, 0x3C, 0xFF, 0x01, 0x80};
  ExactBuffer buf(bytes);
  BitReader br(buf.ptr(), buf.size);
  EXPECT_EQ(br.read(1), 1u);
  EXPECT_EQ(br.read(3), 0x2u);   // 010
  EXPECT_EQ(br.read(4), 0x5u);   // 0101
  EXPECT_EQ(br.peek(8), 0x3Cu);
  EXPECT_EQ(br.read(12), 0x3CFu);
  EXPECT_EQ(br.bit_position(), 20u);
  EXPECT_FALSE(br.byte_aligned());
  br.align_to_byte();
  EXPECT_EQ(br.bit_position(), 24u);
  EXPECT_EQ(br.read(9), 0x003u);  // 0000 0001 1
  EXPECT_EQ(br.bits_left(), 7u);
  EXPECT_EQ(br.read(7), 0u);
  EXPECT_EQ(br.bits_left(), 0u);
  EXPECT_EQ(br.status(), Status::ok);
}

TEST(BitReaderTest, ThirtyTwoBitReads) {
  const std::vector<uint8_t> bytes = {0xDE, 0xAD, 0xBE, 0xEF, 0x12, 0x34, 0x56, 0x78, 0x9A};
  ExactBuffer buf(bytes);
  BitReader br(buf.ptr(), buf.size);
  EXPECT_EQ(br.read(4), 0xDu);
  EXPECT_EQ(br.read(32), 0xEADBEEF1u);
  EXPECT_EQ(br.read(28), 0x2345678u);
  EXPECT_EQ(br.read(8), 0x9Au);
  EXPECT_EQ(br.status(), Status::ok);
  EXPECT_EQ(br.read(0), 0u);
  EXPECT_EQ(br.status(), Status::ok);
}

TEST(BitReaderTest, RandomFieldsRoundTrip) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<std::pair<uint32_t, int>> fields;
    BitWriter bw;
    const int count = 1 + static_cast<int>(rng() % 400);
    for (int i = 0; i < count; ++i) {
      const int n = static_cast<int>(rng() % 33);
      const uint32_t v = n == 32 ? static_cast<uint32_t>(rng()) : static_cast<uint32_t>(rng()) & ((1u << n) - 1);
      fields.emplace_back(v, n);
      bw.put_bits(v, n);
    }
    const size_t bits = bw.bit_count();
    ExactBuffer buf(bw.finish());
    ASSERT_EQ(buf.size, (bits + 7) / 8);
    BitReader br(buf.ptr(), buf.size);
    for (size_t i = 0; i < fields.size(); ++i) {
      const auto [v, n] = fields[i];
      if (n >= 1 && n <= BitReader::kMaxPeekBits && (i % 3) == 0) EXPECT_EQ(br.peek(n), v);
      ASSERT_EQ(br.read(n), v) << "field " << i << " width " << n;
    }
    EXPECT_EQ(br.status(), Status::ok);
    EXPECT_EQ(br.bit_position(), bits);
  }
}

TEST(BitReaderTest, ExpGolombRoundTripAndExtremes) {
  std::mt19937 rng(11);
  std::vector<uint32_t> us = {0, 1, 2, 3, 254, 255, 256, 65535, 0x7FFFFFFFu, 0x80000000u, 0xFFFFFFFDu, 0xFFFFFFFEu};
  std::vector<int32_t> ss = {0, 1, -1, 2, -2, 1000, -1000, INT32_MAX, -INT32_MAX};
  for (int i = 0; i < 500; ++i) {
    us.push_back(static_cast<uint32_t>(rng()) >> (rng() % 32));
    ss.push_back(static_cast<int32_t>(rng()) >> (rng() % 31));
  }
  for (int32_t& s : ss)
    if (s == INT32_MIN) s = 0;
  BitWriter bw;
  for (size_t i = 0; i < us.size(); ++i) {
    bw.put_ue(us[i]);
    bw.put_se(ss[i]);
  }
  ExactBuffer buf(bw.finish());
  BitReader br(buf.ptr(), buf.size);
  for (size_t i = 0; i < us.size(); ++i) {
    ASSERT_EQ(br.read_ue(), us[i]);
    ASSERT_EQ(br.read_se(), ss[i]);
  }
  EXPECT_EQ(br.status(), Status::ok);
  // Golden: ue(0) = 1, ue(1) = 010, ue(4) = 00101, se(-1) = ue(2) = 011.
  BitWriter g;
  g.put_ue(0);
  g.put_ue(1);
  g.put_ue(4);
  g.put_se(-1);
  EXPECT_EQ(g.finish(), (std::vector<uint8_t>{0xA2, 0xB0}));  // 1 010 00101 011 0000
  EXPECT_THROW(bw.put_ue(0xFFFFFFFFu), std::invalid_argument);
  EXPECT_THROW(bw.put_se(INT32_MIN), std::invalid_argument);
}

TEST(BitReaderTest, ExpGolombPrefixTooLongIsMalformed) {
  // 32 zero bits then ones: no 32-bit value has a 32-zero prefix.
  const std::vector<uint8_t> bytes = {0, 0, 0, 0, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
  ExactBuffer buf(bytes);
  BitReader br(buf.ptr(), buf.size);
  br.read_ue();
  EXPECT_EQ(br.status(), Status::malformed);
  // Same with only zeros: the data runs out first, so truncated wins.
  const std::vector<uint8_t> zeros = {0, 0, 0};
  ExactBuffer zbuf(zeros);
  BitReader bz(zbuf.ptr(), zbuf.size);
  bz.read_ue();
  EXPECT_EQ(bz.status(), Status::truncated);
}

TEST(BitReaderTest, PastTheEndReturnsZerosAndLatches) {
  const std::vector<uint8_t> bytes = {0xFF, 0xFF, 0xFF};
  ExactBuffer buf(bytes);
  BitReader br(buf.ptr(), buf.size);
  EXPECT_EQ(br.read(20), 0xFFFFFu);
  // Peeking past the end is legal and shows zero padding.
  EXPECT_EQ(br.peek(16), 0xF000u);
  EXPECT_EQ(br.status(), Status::ok);
  EXPECT_EQ(br.read(4), 0xFu);
  EXPECT_EQ(br.status(), Status::ok);
  EXPECT_EQ(br.bits_left(), 0u);
  EXPECT_EQ(br.read(1), 0u);
  EXPECT_EQ(br.status(), Status::truncated);
  // Reading on is safe and keeps returning zeros; the latch stays.
  for (int i = 0; i < 1000; ++i) ASSERT_EQ(br.read(32), 0u);
  EXPECT_EQ(br.status(), Status::truncated);
  br.fail(Status::malformed);
  EXPECT_EQ(br.status(), Status::truncated);
}

TEST(BitReaderTest, EmptyAndNullBuffers) {
  BitReader empty(nullptr, 0);
  EXPECT_EQ(empty.peek(25), 0u);
  EXPECT_EQ(empty.status(), Status::ok);
  EXPECT_EQ(empty.read(1), 0u);
  EXPECT_EQ(empty.status(), Status::truncated);
  BitReader bad(nullptr, 10);
  EXPECT_EQ(bad.status(), Status::invalid_argument);
  EXPECT_EQ(bad.read(8), 0u);
  EXPECT_EQ(bad.bits_left(), 0u);
}

TEST(BitReaderTest, PrefixSweepLatchesTruncatedAtTheRightField) {
  std::mt19937 rng(3);
  BitWriter bw;
  std::vector<std::pair<uint32_t, int>> fields;
  std::vector<size_t> end_bit;  // bit position after each field
  for (int i = 0; i < 120; ++i) {
    const int n = 1 + static_cast<int>(rng() % 32);
    const uint32_t v = n == 32 ? static_cast<uint32_t>(rng()) : static_cast<uint32_t>(rng()) & ((1u << n) - 1);
    fields.emplace_back(v, n);
    bw.put_bits(v, n);
    end_bit.push_back(bw.bit_count());
  }
  const std::vector<uint8_t> full = bw.finish();
  for (size_t len = 0; len <= full.size(); ++len) {
    ExactBuffer buf(full, len);
    BitReader br(buf.ptr(), buf.size);
    for (size_t i = 0; i < fields.size(); ++i) {
      const uint32_t v = br.read(fields[i].second);
      const bool fits = end_bit[i] <= len * 8;
      // A field inside the prefix reads correctly; the first that is not
      // latches truncated, and the latch stays.
      if (fits) {
        ASSERT_EQ(v, fields[i].first) << "len " << len << " field " << i;
        ASSERT_EQ(br.status(), Status::ok);
      } else {
        ASSERT_EQ(br.status(), Status::truncated) << "len " << len << " field " << i;
      }
    }
  }
}

TEST(BitWriterTest, AlignAndBytes) {
  BitWriter bw;
  bw.put_bits(0x5, 3);
  EXPECT_EQ(bw.bytes(), std::vector<uint8_t>{0xA0});
  bw.align_to_byte();
  EXPECT_EQ(bw.bit_count(), 8u);
  bw.put_bits(0xFFFFFFFFu, 32);
  bw.put_bit(1);
  EXPECT_EQ(bw.bit_count(), 41u);
  EXPECT_EQ(bw.finish(), (std::vector<uint8_t>{0xA0, 0xFF, 0xFF, 0xFF, 0xFF, 0x80}));
  EXPECT_EQ(bw.bit_count(), 0u);
  EXPECT_THROW(bw.put_bits(0, 33), std::invalid_argument);
}

}  // namespace
