// vds encoder: optimal length-limited Huffman codes (package-merge,
// L. L. Larmore and D. S. Hirschberg, "A fast algorithm for optimal
// length-limited Huffman codes", JACM 1990) and their canonical form, in the
// two descriptions vds::HuffmanTable builds from.
#pragma once
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "vds/enc/bitwriter.h"

namespace vds::enc {

// Code lengths minimising sum(freq[s] * length[s]) subject to
// length[s] <= max_length, for every symbol with freq > 0 (others get 0).
// One used symbol gets length 1; none gives all zeros. Throws
// std::invalid_argument if max_length is outside 1..32, if the used symbols
// do not fit (more than 2^max_length of them), if there are more than 65535
// symbols or if the frequencies add up to 2^56 or more.
std::vector<uint8_t> huffman_code_lengths(std::span<const uint64_t> freqs, int max_length = 16);

// A canonical prefix code: codes of equal length are consecutive in symbol
// order, shorter codes numerically first (T.81 Annex C, RFC 1951 3.2.2).
struct CanonicalCode {
  std::vector<uint8_t> lengths;   // per symbol, 0 = not in the code
  std::vector<uint32_t> codes;    // per symbol, the low lengths[s] bits, sent MSB first
  std::vector<uint16_t> counts;   // counts[i] = codes of length i + 1 (at least 16 entries)
  std::vector<uint16_t> symbols;  // used symbols in code order (sorted by length, then value)
  int max_length = 0;             // longest code, 0 for an empty code

  // Writes the code of `symbol` (which must have a code).
  void write(BitWriter& bw, size_t symbol) const;
  // Bits to code symbols with these frequencies.
  uint64_t cost_bits(std::span<const uint64_t> freqs) const;
  // Kraft sum scaled by 2^32 (2^32 = complete code).
  uint64_t kraft_sum_q32() const;
};

// The canonical code for given lengths (0..32 each). Throws
// std::invalid_argument if the lengths over-subscribe the code space or an
// alphabet is larger than 65535 symbols.
CanonicalCode huffman_canonical(std::span<const uint8_t> lengths);

// huffman_canonical(huffman_code_lengths(freqs, max_length)).
CanonicalCode huffman_build(std::span<const uint64_t> freqs, int max_length = 16);

}  // namespace vds::enc
