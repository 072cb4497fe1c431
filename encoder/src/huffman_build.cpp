// vds encoder: optimal length-limited Huffman code lengths by package-merge
// (Larmore & Hirschberg, JACM 37(3), 1990) and canonical code assignment
// (ITU-T T.81 Annex C, RFC 1951 3.2.2).
#include "vds/enc/huffman_build.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace vds::enc {

namespace {
// Symbols and per-length counts travel as 16-bit values.
constexpr size_t kMaxAlphabet = 65535;
constexpr int kMaxLimit = 32;
// Package weights sum at most (limit) copies of every frequency; keeping the
// total below 2^56 leaves room for 32 levels without overflow.
constexpr uint64_t kMaxTotalFrequency = uint64_t{1} << 56;
}  // namespace

std::vector<uint8_t> huffman_code_lengths(std::span<const uint64_t> freqs, int max_length) {
  if (max_length < 1 || max_length > kMaxLimit)
    throw std::invalid_argument("huffman_code_lengths: max_length must be 1..32");
  if (freqs.size() > kMaxAlphabet) throw std::invalid_argument("huffman_code_lengths: alphabet above 65535");
  std::vector<uint8_t> lengths(freqs.size(), 0);

  uint64_t total = 0;
  std::vector<uint32_t> used;  // symbols with freq > 0, by (freq, symbol)
  for (size_t s = 0; s < freqs.size(); ++s) {
    if (freqs[s] == 0) continue;
    total += freqs[s];
    if (total >= kMaxTotalFrequency) throw std::invalid_argument("huffman_code_lengths: frequencies too large");
    used.push_back(static_cast<uint32_t>(s));
  }
  const size_t n = used.size();
  if (n == 0) return lengths;
  if (n == 1) {
    lengths[used[0]] = 1;
    return lengths;
  }
  if (max_length < 32 && n > (size_t{1} << max_length))
    throw std::invalid_argument("huffman_code_lengths: too many symbols for max_length");
  std::stable_sort(used.begin(), used.end(), [&](uint32_t a, uint32_t b) { return freqs[a] < freqs[b]; });

  // No optimal code is deeper than n - 1, so deeper limits change nothing.
  const int levels = static_cast<int>(std::min<size_t>(static_cast<size_t>(max_length), n - 1));

  // Coin collector's view: at each level the list is the leaves merged with
  // the pairs ("packages") of the level below, in weight order. Only which
  // entries are packages matters afterwards, because the chosen entries of
  // every level form a prefix of its list.
  std::vector<std::vector<uint8_t>> is_package(static_cast<size_t>(levels));
  std::vector<uint64_t> below(n);  // weights of the deepest level: leaves only
  for (size_t i = 0; i < n; ++i) below[i] = freqs[used[i]];
  is_package[static_cast<size_t>(levels - 1)].assign(n, 0);
  for (int level = levels - 2; level >= 0; --level) {
    const size_t packages = below.size() / 2;
    std::vector<uint64_t> merged;
    std::vector<uint8_t>& flags = is_package[static_cast<size_t>(level)];
    merged.reserve(n + packages);
    flags.reserve(n + packages);
    size_t li = 0, pi = 0;
    while (li < n || pi < packages) {
      const bool take_leaf =
          pi == packages || (li < n && freqs[used[li]] <= below[2 * pi] + below[2 * pi + 1]);
      if (take_leaf) {
        merged.push_back(freqs[used[li++]]);
        flags.push_back(0);
      } else {
        merged.push_back(below[2 * pi] + below[2 * pi + 1]);
        ++pi;
        flags.push_back(1);
      }
    }
    below.swap(merged);
  }

  // Choose the 2n - 2 cheapest entries of the top level; every package
  // chosen at one level chooses two entries of the level below. A leaf
  // chosen at a level adds one bit to its symbol's length; since leaves
  // enter each list in frequency order, the chosen leaves are always the
  // least frequent symbols.
  size_t take = 2 * n - 2;
  for (int level = 0; level < levels; ++level) {
    const std::vector<uint8_t>& flags = is_package[static_cast<size_t>(level)];
    size_t leaves = 0, packages = 0;
    for (size_t i = 0; i < take; ++i) (flags[i] ? packages : leaves)++;
    for (size_t i = 0; i < leaves; ++i) ++lengths[used[i]];
    take = 2 * packages;
  }
  return lengths;
}

CanonicalCode huffman_canonical(std::span<const uint8_t> lengths) {
  if (lengths.size() > kMaxAlphabet) throw std::invalid_argument("huffman_canonical: alphabet above 65535");
  CanonicalCode c;
  c.lengths.assign(lengths.begin(), lengths.end());
  c.codes.assign(lengths.size(), 0);
  int max_len = 0;
  for (uint8_t l : lengths) {
    if (l > kMaxLimit) throw std::invalid_argument("huffman_canonical: code length above 32");
    max_len = std::max<int>(max_len, l);
  }
  c.max_length = max_len;
  c.counts.assign(static_cast<size_t>(std::max(16, max_len)), 0);
  for (uint8_t l : lengths)
    if (l) ++c.counts[l - 1u];
  for (uint8_t len = 1; len <= max_len; ++len)
    for (size_t s = 0; s < lengths.size(); ++s)
      if (lengths[s] == len) c.symbols.push_back(static_cast<uint16_t>(s));

  uint64_t code = 0;  // next code of the current length
  size_t k = 0;
  for (int len = 1; len <= max_len; ++len) {
    for (uint16_t i = 0; i < c.counts[static_cast<size_t>(len - 1)]; ++i) {
      if (code >= (uint64_t{1} << len)) throw std::invalid_argument("huffman_canonical: over-subscribed lengths");
      c.codes[c.symbols[k++]] = static_cast<uint32_t>(code++);
    }
    code <<= 1;
  }
  return c;
}

CanonicalCode huffman_build(std::span<const uint64_t> freqs, int max_length) {
  const std::vector<uint8_t> lengths = huffman_code_lengths(freqs, max_length);
  return huffman_canonical(lengths);
}

void CanonicalCode::write(BitWriter& bw, size_t symbol) const {
  if (symbol >= lengths.size() || lengths[symbol] == 0)
    throw std::invalid_argument("CanonicalCode::write: symbol has no code");
  bw.put_bits(codes[symbol], lengths[symbol]);
}

uint64_t CanonicalCode::cost_bits(std::span<const uint64_t> freqs) const {
  uint64_t bits = 0;
  for (size_t s = 0; s < freqs.size() && s < lengths.size(); ++s) bits += freqs[s] * lengths[s];
  return bits;
}

uint64_t CanonicalCode::kraft_sum_q32() const {
  uint64_t sum = 0;
  for (uint8_t l : lengths)
    if (l) sum += uint64_t{1} << (32 - l);
  return sum;
}

}  // namespace vds::enc
