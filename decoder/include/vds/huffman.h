// vds client library: table-driven canonical Huffman decoder (canonical code
// assignment as in ITU-T T.81 Annex C / RFC 1951 3.2.2).
//
// A table is described either JPEG-style (how many codes of each length
// 1..16, then the symbols in code order) or per symbol (a code length for
// each symbol, 0 = absent; symbols of equal length take codes in symbol
// order). Both give the same canonical code for the same lengths.
//
// Limits: code lengths 1..16 (kMaxCodeLength), alphabets of up to 4096
// symbols (kMaxSymbols, values 0..4095). Over-subscribed descriptions are
// rejected (Status::malformed); incomplete ones are accepted and decoding a
// bit pattern no code covers latches Status::malformed on the reader.
//
// Memory: the HuffmanTable object itself (160 bytes on Cortex-M4, 176 on
// x86-64) plus, from the caller's Arena, 2^VDS_CONFIG_HUFF_LOOKUP_BITS
// 16-bit lookup entries and one 16-bit slot per symbol: workspace_bytes().
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/arena.h"
#include "vds/bitreader.h"
#include "vds/config.h"
#include "vds/status.h"

namespace vds {

class HuffmanTable {
 public:
  static constexpr int kMaxCodeLength = 16;
  static constexpr size_t kMaxSymbols = 4096;
  static constexpr int kLookupBits = VDS_CONFIG_HUFF_LOOKUP_BITS;

  // Workspace reserve() takes for `max_symbols` symbols, alignment included.
  static constexpr size_t workspace_bytes(size_t max_symbols) {
    return (size_t{1} << kLookupBits) * sizeof(uint16_t) + max_symbols * sizeof(uint16_t) +
           2 * alignof(uint16_t);
  }

  // Carves storage for tables of up to `max_symbols` symbols from `arena`.
  // Call once; then build any number of times (a JPEG stream may redefine a
  // table). workspace_too_small if the arena cannot hold it, invalid_argument
  // if max_symbols > kMaxSymbols.
  Status reserve(Arena& arena, size_t max_symbols);

  // JPEG-style description: counts[i] codes of length i + 1 (i = 0..15), then
  // `num_symbols` symbols in code order. num_symbols must equal the sum of the
  // counts (invalid_argument otherwise), symbols must be < kMaxSymbols.
  Status build_from_counts(const uint16_t counts[kMaxCodeLength], const uint16_t* symbols,
                           size_t num_symbols);
  Status build_from_counts(const uint8_t counts[kMaxCodeLength], const uint8_t* symbols,
                           size_t num_symbols);

  // Per-symbol description: lengths[s] is the code length of symbol s
  // (0 = not in the code, 1..16 otherwise; larger values are malformed).
  Status build_from_lengths(const uint8_t* lengths, size_t alphabet_size);

  // Decodes one symbol. On a bit pattern no code covers it latches
  // Status::malformed on `br`, consumes nothing and returns -1. Past the end
  // of the data the reader supplies zeros and latches truncated.
  int decode(BitReader& br) const {
    const uint32_t window = br.peek(kMaxCodeLength);
    const uint16_t e = lookup_[window >> (kMaxCodeLength - kLookupBits)];
    const int len = e & kEntryLengthMask;
    if (len != 0) {
      br.skip(len);
      return e >> kEntrySymbolShift;
    }
    return decode_slow(br, window);
  }

  // For callers with their own bit reader (e.g. a JPEG scan with byte
  // stuffing): `window` holds the next 16 bits, first bit in bit 15. Returns
  // the symbol and sets `length` to its code length, or returns -1 with
  // length 0 if no code covers the pattern.
  int decode_window(uint32_t window, int& length) const;

  bool built() const { return built_; }
  size_t num_symbols() const { return num_symbols_; }
  int max_length() const { return max_length_; }

 private:
  // Lookup entry: symbol << 4 | code length; length 0 = longer code or no code.
  static constexpr int kEntrySymbolShift = 4;
  static constexpr uint16_t kEntryLengthMask = 0xF;
  static_assert(kLookupBits <= 15, "a lookup length must fit kEntryLengthMask");
  static_assert(kMaxSymbols <= (size_t{1} << (16 - kEntrySymbolShift)), "a symbol must fit a lookup entry");

  Status build(const uint16_t counts[kMaxCodeLength], size_t num_symbols);
  int decode_slow(BitReader& br, uint32_t window) const;

  uint16_t* lookup_ = nullptr;   // 2^kLookupBits entries
  uint16_t* symbols_ = nullptr;  // symbols in code order
  size_t capacity_ = 0;
  size_t num_symbols_ = 0;
  // limit_[L]: one past the last code of length <= L, left-aligned to 16 bits
  // (codes of length L occupy [limit_[L-1], limit_[L]) as 16-bit windows).
  uint32_t limit_[kMaxCodeLength + 1] = {};
  // offset_[L]: index in symbols_ of the first length-L symbol minus the
  // first length-L code, so symbol index = offset_[L] + (window >> (16 - L)).
  int32_t offset_[kMaxCodeLength + 1] = {};
  int max_length_ = 0;
  bool built_ = false;
};

}  // namespace vds
