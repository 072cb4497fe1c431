// Canonical Huffman: the JPEG example table, package-merge optimality and
// limits, encoder/decoder round trips (lookup and slow path), malformed and
// incomplete descriptions, truncation sweeps and random garbage.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <memory>
#include <queue>
#include <random>
#include <vector>

#include "vds/arena.h"
#include "vds/bitreader.h"
#include "vds/enc/bitwriter.h"
#include "vds/enc/huffman_build.h"
#include "vds/huffman.h"

namespace {

using vds::Arena;
using vds::BitReader;
using vds::HuffmanTable;
using vds::Status;
using vds::enc::BitWriter;
using vds::enc::CanonicalCode;
using vds::enc::huffman_build;
using vds::enc::huffman_canonical;
using vds::enc::huffman_code_lengths;

struct ExactBuffer {
  // new uint8_t[0] is a distinct zero-byte allocation: ASan flags any read.
  ExactBuffer(const std::vector<uint8_t>& v, size_t n) : size(n), data(new uint8_t[n]) {
    if (n) std::memcpy(data.get(), v.data(), n);
  }
  explicit ExactBuffer(const std::vector<uint8_t>& v) : ExactBuffer(v, v.size()) {}
  const uint8_t* ptr() const { return data.get(); }
  size_t size;
  std::unique_ptr<uint8_t[]> data;
};

// A table with its own workspace.
struct Table {
  explicit Table(size_t max_symbols) : work(HuffmanTable::workspace_bytes(max_symbols)), arena(work.data(), work.size()) {
    EXPECT_EQ(t.reserve(arena, max_symbols), Status::ok);
  }
  std::vector<uint8_t> work;
  Arena arena;
  HuffmanTable t;
};

// Unconstrained Huffman cost (sum of merged weights).
uint64_t huffman_cost(const std::vector<uint64_t>& f) {
  std::priority_queue<uint64_t, std::vector<uint64_t>, std::greater<>> q;
  for (uint64_t x : f)
    if (x) q.push(x);
  if (q.size() == 1) return q.top();
  uint64_t cost = 0;
  while (q.size() > 1) {
    const uint64_t a = q.top();
    q.pop();
    const uint64_t b = q.top();
    q.pop();
    cost += a + b;
    q.push(a + b);
  }
  return cost;
}

// Depth of an unconstrained Huffman tree (merging order as above).
int huffman_depth(const std::vector<uint64_t>& f) {
  using Node = std::pair<uint64_t, int>;
  std::priority_queue<Node, std::vector<Node>, std::greater<>> q;
  for (uint64_t x : f)
    if (x) q.push({x, 0});
  if (q.size() == 1) return 1;
  while (q.size() > 1) {
    const Node a = q.top();
    q.pop();
    const Node b = q.top();
    q.pop();
    q.push({a.first + b.first, std::max(a.second, b.second) + 1});
  }
  return q.top().second;
}

// Minimal cost over all length vectors with lengths 1..L and Kraft <= 1.
uint64_t brute_force_cost(const std::vector<uint64_t>& f, int L) {
  const size_t n = f.size();
  std::vector<int> len(n, 1);
  uint64_t best = UINT64_MAX;
  for (;;) {
    uint64_t kraft = 0;
    for (int l : len) kraft += uint64_t{1} << (L - l);
    if (kraft <= (uint64_t{1} << L)) {
      uint64_t c = 0;
      for (size_t i = 0; i < n; ++i) c += f[i] * static_cast<uint64_t>(len[i]);
      best = std::min(best, c);
    }
    size_t i = 0;
    while (i < n && len[i] == L) len[i++] = 1;
    if (i == n) break;
    ++len[i];
  }
  return best;
}

void expect_valid_code(const CanonicalCode& c, int limit) {
  for (uint8_t l : c.lengths) EXPECT_LE(l, limit);
  EXPECT_LE(c.kraft_sum_q32(), uint64_t{1} << 32);
  // Prefix-free: no code is a prefix of another.
  std::vector<std::pair<uint32_t, int>> codes;
  for (size_t s = 0; s < c.lengths.size(); ++s)
    if (c.lengths[s]) codes.push_back({c.codes[s], c.lengths[s]});
  for (size_t a = 0; a < codes.size(); ++a)
    for (size_t b = 0; b < codes.size(); ++b) {
      if (a == b || codes[a].second > codes[b].second) continue;
      const uint32_t pre = codes[b].first >> (codes[b].second - codes[a].second);
      ASSERT_NE(pre, codes[a].first) << "code " << a << " is a prefix of " << b;
    }
}

TEST(HuffmanTest, JpegLuminanceDcTable) {
  // ITU-T T.81 Table K.3: BITS and HUFFVAL of the example luminance DC table.
  const uint8_t bits[16] = {0, 1, 5, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0};
  const uint8_t vals[12] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
  Table tab(256);
  ASSERT_EQ(tab.t.build_from_counts(bits, vals, 12), Status::ok);
  // Codes from Table K.3: 0 -> 00, 1 -> 010, 5 -> 110, 6 -> 1110, 11 -> 111111110.
  BitWriter bw;
  bw.put_bits(0b00, 2);
  bw.put_bits(0b010, 3);
  bw.put_bits(0b110, 3);
  bw.put_bits(0b1110, 4);
  bw.put_bits(0b111111110, 9);
  bw.put_bits(0b11110, 5);  // 7
  ExactBuffer buf(bw.finish());
  BitReader br(buf.ptr(), buf.size);
  EXPECT_EQ(tab.t.decode(br), 0);
  EXPECT_EQ(tab.t.decode(br), 1);
  EXPECT_EQ(tab.t.decode(br), 5);
  EXPECT_EQ(tab.t.decode(br), 6);
  EXPECT_EQ(tab.t.decode(br), 11);
  EXPECT_EQ(tab.t.decode(br), 7);
  EXPECT_EQ(br.status(), Status::ok);
  EXPECT_EQ(br.bit_position(), 26u);
  EXPECT_EQ(tab.t.max_length(), 9);
  // The same table from its lengths gives the same codes.
  const CanonicalCode c = huffman_canonical(std::vector<uint8_t>{2, 3, 3, 3, 3, 3, 4, 5, 6, 7, 8, 9});
  EXPECT_EQ(c.codes[11], 0b111111110u);
  EXPECT_EQ(c.codes[0], 0u);
  EXPECT_EQ(c.codes[6], 0b1110u);
  EXPECT_EQ(std::vector<uint16_t>(c.counts.begin(), c.counts.end()),
            (std::vector<uint16_t>{0, 1, 5, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0}));
}

TEST(HuffmanBuildTest, OptimalAgainstBruteForce) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 200; ++trial) {
    const size_t n = 2 + rng() % 6;  // 2..7 symbols
    std::vector<uint64_t> f(n);
    for (auto& x : f) x = 1 + rng() % (trial % 2 ? 1000 : 10);
    if (trial % 5 == 0) f[0] = 100000;  // skew so limits bind
    int min_l = 0;
    while ((size_t{1} << min_l) < n) ++min_l;
    for (int L = min_l; L <= 5; ++L) {
      const CanonicalCode c = huffman_build(f, L);
      expect_valid_code(c, L);
      ASSERT_EQ(c.cost_bits(f), brute_force_cost(f, L)) << "trial " << trial << " L " << L;
    }
  }
}

TEST(HuffmanBuildTest, MatchesHuffmanWhenTheLimitDoesNotBind) {
  std::mt19937 rng(9);
  for (int trial = 0; trial < 50; ++trial) {
    const size_t n = 2 + rng() % 300;
    std::vector<uint64_t> f(n);
    for (auto& x : f) x = rng() % 4 == 0 ? 0 : 1 + rng() % 5000;
    f[0] = 1;
    f[1] = 2;
    const int depth = huffman_depth(f);
    const CanonicalCode c = huffman_build(f, std::max(depth, 1));
    expect_valid_code(c, depth);
    EXPECT_EQ(c.cost_bits(f), huffman_cost(f));
    // A complete code (Kraft sum exactly 1) for two or more symbols.
    EXPECT_EQ(c.kraft_sum_q32(), uint64_t{1} << 32);
  }
}

TEST(HuffmanBuildTest, LimitBindsOnFibonacciFrequencies) {
  // Fibonacci weights give a Huffman tree of depth n - 1.
  std::vector<uint64_t> f = {1, 1};
  while (f.size() < 30) f.push_back(f[f.size() - 1] + f[f.size() - 2]);
  ASSERT_EQ(huffman_depth(f), 29);
  for (int L : {5, 8, 12, 16, 20, 29, 32}) {
    const CanonicalCode c = huffman_build(f, L);
    expect_valid_code(c, L);
    EXPECT_EQ(c.max_length, std::min(L, 29));
    EXPECT_EQ(c.kraft_sum_q32(), uint64_t{1} << 32);
    if (L >= 29) EXPECT_EQ(c.cost_bits(f), huffman_cost(f));
    if (L < 29) EXPECT_GT(c.cost_bits(f), huffman_cost(f));
  }
  // Monotone in the limit: a looser limit never costs more.
  uint64_t prev = UINT64_MAX;
  for (int L = 5; L <= 29; ++L) {
    const uint64_t cost = huffman_build(f, L).cost_bits(f);
    EXPECT_LE(cost, prev);
    prev = cost;
  }
}

TEST(HuffmanBuildTest, DegenerateAlphabets) {
  EXPECT_EQ(huffman_code_lengths(std::vector<uint64_t>{0, 0, 0}, 16), (std::vector<uint8_t>{0, 0, 0}));
  EXPECT_EQ(huffman_code_lengths(std::vector<uint64_t>{0, 7, 0}, 16), (std::vector<uint8_t>{0, 1, 0}));
  EXPECT_EQ(huffman_code_lengths(std::vector<uint64_t>{3, 3}, 1), (std::vector<uint8_t>{1, 1}));
  // Equal frequencies over 2^k symbols: all length k.
  const std::vector<uint8_t> l = huffman_code_lengths(std::vector<uint64_t>(256, 5), 16);
  EXPECT_TRUE(std::all_of(l.begin(), l.end(), [](uint8_t x) { return x == 8; }));
  // 2^L symbols exactly fill a limit of L.
  const std::vector<uint8_t> l4 = huffman_code_lengths(std::vector<uint64_t>{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 1000}, 4);
  EXPECT_TRUE(std::all_of(l4.begin(), l4.end(), [](uint8_t x) { return x == 4; }));
  EXPECT_THROW(huffman_code_lengths(std::vector<uint64_t>(17, 1), 4), std::invalid_argument);
  EXPECT_THROW(huffman_code_lengths(std::vector<uint64_t>{1, 1}, 0), std::invalid_argument);
  EXPECT_THROW(huffman_code_lengths(std::vector<uint64_t>{1, 1}, 33), std::invalid_argument);
  EXPECT_THROW(huffman_canonical(std::vector<uint8_t>{1, 1, 1}), std::invalid_argument);
}

// Encodes `syms` with `code`, decodes with tables built both ways.
void round_trip(const CanonicalCode& code, const std::vector<uint16_t>& syms) {
  BitWriter bw;
  for (uint16_t s : syms) code.write(bw, s);
  const size_t bits = bw.bit_count();
  ExactBuffer buf(bw.finish());

  Table by_counts(code.symbols.size());
  uint16_t counts[16];
  for (int i = 0; i < 16; ++i) counts[i] = code.counts[static_cast<size_t>(i)];
  ASSERT_EQ(by_counts.t.build_from_counts(counts, code.symbols.data(), code.symbols.size()), Status::ok);
  Table by_lengths(code.symbols.size());
  ASSERT_EQ(by_lengths.t.build_from_lengths(code.lengths.data(), code.lengths.size()), Status::ok);

  for (const HuffmanTable* t : {&by_counts.t, &by_lengths.t}) {
    BitReader br(buf.ptr(), buf.size);
    for (size_t i = 0; i < syms.size(); ++i) {
      const uint32_t window = br.peek(16);
      int len = -1;
      const int via_window = t->decode_window(window, len);
      ASSERT_EQ(via_window, syms[i]);
      ASSERT_EQ(len, code.lengths[syms[i]]);
      ASSERT_EQ(t->decode(br), syms[i]) << "symbol " << i;
    }
    EXPECT_EQ(br.status(), Status::ok);
    EXPECT_EQ(br.bit_position(), bits);
  }
}

TEST(HuffmanTest, RoundTripRandomAlphabets) {
  std::mt19937 rng(21);
  for (size_t n : {size_t{1}, size_t{2}, size_t{3}, size_t{17}, size_t{256}, size_t{1024}, size_t{4096}}) {
    for (int skew = 0; skew < 3; ++skew) {
      std::vector<uint64_t> f(n);
      for (size_t s = 0; s < n; ++s) {
        // skew 0: near-uniform; 1: geometric; 2: a few huge, many tiny (long codes).
        f[s] = skew == 0 ? 1 + rng() % 3 : skew == 1 ? (uint64_t{1} << (20 - std::min<size_t>(s % 40, 20))) : (s < 4 ? 1000000 : 1 + rng() % 2);
        if (n > 8 && rng() % 5 == 0) f[s] = 0;
      }
      f[n - 1] = std::max<uint64_t>(f[n - 1], 1);
      const CanonicalCode code = huffman_build(f, 16);
      expect_valid_code(code, 16);
      std::vector<uint16_t> used = code.symbols;
      std::discrete_distribution<size_t> pick(f.begin(), f.end());
      std::vector<uint16_t> syms;
      for (int i = 0; i < 3000; ++i) syms.push_back(static_cast<uint16_t>(i % 7 == 0 ? used[rng() % used.size()] : pick(rng)));
      round_trip(code, syms);
    }
  }
}

TEST(HuffmanTest, MaxLengthCodesUseTheSlowPath) {
  // Fibonacci weights limited to 16: codes of every length up to 16.
  std::vector<uint64_t> f = {1, 1};
  while (f.size() < 40) f.push_back(f[f.size() - 1] + f[f.size() - 2]);
  const CanonicalCode code = huffman_build(f, 16);
  ASSERT_EQ(code.max_length, 16);
  int longer_than_lookup = 0;
  for (uint8_t l : code.lengths) longer_than_lookup += l > HuffmanTable::kLookupBits;
  ASSERT_GT(longer_than_lookup, 5);
  std::vector<uint16_t> syms;
  for (int r = 0; r < 20; ++r)
    for (uint16_t s = 0; s < 40; ++s) syms.push_back(s);
  round_trip(code, syms);
  // A code using all 2^16 16-bit patterns (complete, every code of length 16)
  // is the widest a table can be: 4096 symbols of length 12 is the largest
  // alphabet, so test the all-16 corner with an incomplete code instead.
  std::vector<uint8_t> lengths(4096, 16);
  Table big(4096);
  ASSERT_EQ(big.t.build_from_lengths(lengths.data(), lengths.size()), Status::ok);
  const std::vector<uint8_t> bits = {0x0F, 0xFF, 0x00, 0x00, 0x10, 0x00};
  ExactBuffer buf(bits);
  BitReader br(buf.ptr(), buf.size);
  EXPECT_EQ(big.t.decode(br), 0x0FFF);
  EXPECT_EQ(big.t.decode(br), 0);
  EXPECT_EQ(br.status(), Status::ok);
  // 0x1000 is past the 4096 assigned codes.
  EXPECT_EQ(big.t.decode(br), -1);
  EXPECT_EQ(br.status(), Status::malformed);
}

TEST(HuffmanTest, SingleSymbolCode) {
  const CanonicalCode code = huffman_build(std::vector<uint64_t>{0, 0, 9, 0}, 16);
  ASSERT_EQ(code.lengths[2], 1);
  round_trip(code, std::vector<uint16_t>(100, 2));
  // The unused pattern "1" is malformed.
  Table tab(4);
  ASSERT_EQ(tab.t.build_from_lengths(code.lengths.data(), code.lengths.size()), Status::ok);
  const std::vector<uint8_t> bits = {0x3F};  // 0 0 1 ...
  ExactBuffer buf(bits);
  BitReader br(buf.ptr(), buf.size);
  EXPECT_EQ(tab.t.decode(br), 2);
  EXPECT_EQ(tab.t.decode(br), 2);
  EXPECT_EQ(tab.t.decode(br), -1);
  EXPECT_EQ(br.status(), Status::malformed);
  EXPECT_EQ(br.bit_position(), 2u);  // the bad pattern is not consumed
}

TEST(HuffmanTest, MalformedDescriptionsRejected) {
  Table tab(300);
  // Over-subscribed: three codes of length 1.
  const uint8_t bits3[16] = {3};
  const uint8_t vals[3] = {0, 1, 2};
  EXPECT_EQ(tab.t.build_from_counts(bits3, vals, 3), Status::malformed);
  EXPECT_FALSE(tab.t.built());
  // Over-subscribed deep down: 2 of length 1 plus one of length 16.
  uint16_t c16[16] = {2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1};
  const uint16_t v16[3] = {0, 1, 2};
  EXPECT_EQ(tab.t.build_from_counts(c16, v16, 3), Status::malformed);
  // Exactly full (Kraft = 1) is fine.
  c16[15] = 0;
  EXPECT_EQ(tab.t.build_from_counts(c16, v16, 2), Status::ok);
  // 65537 codes of length 16 cannot exist; 257 of length 8 neither.
  uint16_t c8[16] = {0, 0, 0, 0, 0, 0, 0, 257};
  std::vector<uint16_t> many(257);
  for (size_t i = 0; i < many.size(); ++i) many[i] = static_cast<uint16_t>(i);
  EXPECT_EQ(tab.t.build_from_counts(c8, many.data(), 257), Status::malformed);
  // Per-symbol lengths: over 16 is malformed, over-subscription too.
  const std::vector<uint8_t> too_long = {1, 2, 17};
  EXPECT_EQ(tab.t.build_from_lengths(too_long.data(), too_long.size()), Status::malformed);
  const std::vector<uint8_t> over = {1, 2, 2, 3};
  EXPECT_EQ(tab.t.build_from_lengths(over.data(), over.size()), Status::malformed);
  // A failed build leaves a table that decodes nothing.
  const std::vector<uint8_t> zeros = {0, 0};
  ExactBuffer buf(zeros);
  BitReader br(buf.ptr(), buf.size);
  EXPECT_EQ(tab.t.decode(br), -1);
  EXPECT_EQ(br.status(), Status::malformed);
  // Caller errors.
  const uint8_t bits1[16] = {1};
  EXPECT_EQ(tab.t.build_from_counts(bits1, vals, 2), Status::invalid_argument);  // count mismatch
  const uint16_t big_sym[1] = {4096};
  const uint16_t c1[16] = {1};
  EXPECT_EQ(tab.t.build_from_counts(c1, big_sym, 1), Status::invalid_argument);
  std::vector<uint8_t> wide(301, 9);
  EXPECT_EQ(tab.t.build_from_lengths(wide.data(), wide.size()), Status::workspace_too_small);
  HuffmanTable unreserved;
  EXPECT_EQ(unreserved.build_from_lengths(too_long.data(), 2), Status::invalid_argument);
}

TEST(HuffmanTest, WorkspaceAccounting) {
  for (size_t n : {size_t{1}, size_t{12}, size_t{162}, size_t{256}, size_t{4096}}) {
    std::vector<uint8_t> work(HuffmanTable::workspace_bytes(n) + 1);
    // Misalign the start on purpose: the stated size must include alignment.
    Arena arena(work.data() + 1, work.size() - 1);
    HuffmanTable t;
    EXPECT_EQ(t.reserve(arena, n), Status::ok) << n;
    Arena small(work.data(), HuffmanTable::workspace_bytes(n) - 2 * alignof(uint16_t) - 1);
    HuffmanTable t2;
    EXPECT_EQ(t2.reserve(small, n), Status::workspace_too_small);
    EXPECT_EQ(small.used(), 0u);  // nothing kept on failure
  }
  std::vector<uint8_t> work(64);
  Arena arena(work.data(), work.size());
  HuffmanTable t;
  EXPECT_EQ(t.reserve(arena, 4097), Status::invalid_argument);
}

TEST(HuffmanTest, RebuildReusesStorage) {
  Table tab(256);
  std::mt19937 rng(4);
  for (int round = 0; round < 20; ++round) {
    std::vector<uint64_t> f(1 + rng() % 256);
    for (auto& x : f) x = rng() % 100;
    f[0] = 1;
    const CanonicalCode code = huffman_build(f, 16);
    ASSERT_EQ(tab.t.build_from_lengths(code.lengths.data(), code.lengths.size()), Status::ok);
    BitWriter bw;
    std::vector<uint16_t> syms;
    for (int i = 0; i < 200; ++i) {
      syms.push_back(code.symbols[rng() % code.symbols.size()]);
      code.write(bw, syms.back());
    }
    ExactBuffer buf(bw.finish());
    BitReader br(buf.ptr(), buf.size);
    for (uint16_t s : syms) ASSERT_EQ(tab.t.decode(br), s);
    EXPECT_EQ(br.status(), Status::ok);
  }
}

TEST(HuffmanTest, PrefixSweep) {
  std::mt19937 rng(8);
  std::vector<uint64_t> f(200);
  for (auto& x : f) x = 1 + rng() % 1000;
  f[3] = 200000;
  const CanonicalCode code = huffman_build(f, 16);
  std::vector<uint16_t> syms;
  std::vector<size_t> end_bit;
  BitWriter bw;
  std::discrete_distribution<size_t> pick(f.begin(), f.end());
  for (int i = 0; i < 400; ++i) {
    syms.push_back(static_cast<uint16_t>(pick(rng)));
    code.write(bw, syms.back());
    end_bit.push_back(bw.bit_count());
  }
  const std::vector<uint8_t> full = bw.finish();
  Table tab(200);
  ASSERT_EQ(tab.t.build_from_lengths(code.lengths.data(), code.lengths.size()), Status::ok);
  for (size_t len = 0; len <= full.size(); ++len) {
    ExactBuffer buf(full, len);
    BitReader br(buf.ptr(), buf.size);
    for (size_t i = 0; i < syms.size(); ++i) {
      const int s = tab.t.decode(br);
      if (end_bit[i] <= len * 8) {
        ASSERT_EQ(s, syms[i]);
        ASSERT_EQ(br.status(), Status::ok);
      } else {
        // The first symbol that straddles the end reads padding: a prefix
        // code cannot end inside the real bits there, so it latches.
        ASSERT_TRUE(is_error(br.status())) << "len " << len << " symbol " << i;
      }
    }
    if (len < full.size()) EXPECT_EQ(br.status(), Status::truncated);
  }
}

TEST(HuffmanTest, RandomGarbageWithIncompleteTables) {
  std::mt19937 rng(13);
  Table tab(64);
  int malformed = 0, truncated = 0;
  for (int trial = 0; trial < 300; ++trial) {
    // Random lengths (kept only if not over-subscribed), or every other trial
    // a complete code, which can never meet an unassigned pattern.
    std::vector<uint8_t> lengths(1 + rng() % 64);
    for (auto& l : lengths) l = static_cast<uint8_t>(rng() % 3 == 0 ? 0 : (trial % 4 == 0 ? 1 + rng() % 16 : 6 + rng() % 11));
    if (trial % 2) {
      std::vector<uint64_t> f(lengths.size());
      for (auto& x : f) x = 1 + rng() % 50;
      lengths = huffman_code_lengths(f, 16);
    }
    if (tab.t.build_from_lengths(lengths.data(), lengths.size()) != Status::ok) continue;
    const bool complete = trial % 2 == 1 && lengths.size() > 1;
    std::vector<uint8_t> junk(rng() % 64);
    for (auto& b : junk) b = static_cast<uint8_t>(rng());
    ExactBuffer buf(junk);
    BitReader br(buf.ptr(), buf.size);
    for (int i = 0; i < 1000 && br.ok(); ++i) {
      const int s = tab.t.decode(br);
      if (br.ok()) {
        ASSERT_GE(s, 0);
        ASSERT_LT(static_cast<size_t>(s), lengths.size());
        ASSERT_NE(lengths[static_cast<size_t>(s)], 0);
      }
    }
    if (complete) EXPECT_NE(br.status(), Status::malformed);
    malformed += br.status() == Status::malformed;
    truncated += br.status() == Status::truncated;
  }
  // Both failure kinds occur across the trials.
  EXPECT_GT(malformed, 10);
  EXPECT_GT(truncated, 10);
}

}  // namespace
