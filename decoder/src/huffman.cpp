// vds client library: canonical Huffman table construction and the slow
// decoding path (canonical codes as in ITU-T T.81 Annex C, RFC 1951 3.2.2).
#include "vds/huffman.h"

#include <cstring>

namespace vds {

namespace {
constexpr int kMaxLen = HuffmanTable::kMaxCodeLength;
constexpr size_t kLookupSize = size_t{1} << HuffmanTable::kLookupBits;
}  // namespace

Status HuffmanTable::reserve(Arena& arena, size_t max_symbols) {
  if (max_symbols > kMaxSymbols) return Status::invalid_argument;
  const size_t mark = arena.mark();
  uint16_t* lookup = arena.alloc_array<uint16_t>(kLookupSize);
  uint16_t* symbols = arena.alloc_array<uint16_t>(max_symbols == 0 ? 1 : max_symbols);
  if (lookup == nullptr || symbols == nullptr) {
    arena.rewind(mark);
    return Status::workspace_too_small;
  }
  lookup_ = lookup;
  symbols_ = symbols;
  capacity_ = max_symbols;
  // A reserved table decodes nothing until it is built.
  std::memset(lookup_, 0, kLookupSize * sizeof(uint16_t));
  std::memset(limit_, 0, sizeof(limit_));
  std::memset(offset_, 0, sizeof(offset_));
  num_symbols_ = 0;
  max_length_ = 0;
  built_ = false;
  return Status::ok;
}

Status HuffmanTable::build_from_counts(const uint16_t counts[kMaxCodeLength], const uint16_t* symbols,
                                       size_t num_symbols) {
  if (lookup_ == nullptr || counts == nullptr || (symbols == nullptr && num_symbols != 0))
    return Status::invalid_argument;
  if (num_symbols > capacity_) return Status::workspace_too_small;
  size_t total = 0;
  for (int i = 0; i < kMaxLen; ++i) total += counts[i];
  if (total != num_symbols) return Status::invalid_argument;
  for (size_t i = 0; i < num_symbols; ++i)
    if (symbols[i] >= kMaxSymbols) return Status::invalid_argument;
  std::memcpy(symbols_, symbols, num_symbols * sizeof(uint16_t));
  return build(counts, num_symbols);
}

Status HuffmanTable::build_from_counts(const uint8_t counts[kMaxCodeLength], const uint8_t* symbols,
                                       size_t num_symbols) {
  if (lookup_ == nullptr || counts == nullptr || (symbols == nullptr && num_symbols != 0))
    return Status::invalid_argument;
  if (num_symbols > capacity_) return Status::workspace_too_small;
  uint16_t wide[kMaxLen];
  size_t total = 0;
  for (int i = 0; i < kMaxLen; ++i) {
    wide[i] = counts[i];
    total += counts[i];
  }
  if (total != num_symbols) return Status::invalid_argument;
  for (size_t i = 0; i < num_symbols; ++i) symbols_[i] = symbols[i];
  return build(wide, num_symbols);
}

Status HuffmanTable::build_from_lengths(const uint8_t* lengths, size_t alphabet_size) {
  if (lookup_ == nullptr || (lengths == nullptr && alphabet_size != 0)) return Status::invalid_argument;
  if (alphabet_size > kMaxSymbols) return Status::invalid_argument;
  uint16_t counts[kMaxLen] = {};
  size_t used = 0;
  for (size_t s = 0; s < alphabet_size; ++s) {
    const uint8_t len = lengths[s];
    if (len == 0) continue;
    if (len > kMaxLen) return Status::malformed;
    ++counts[len - 1];
    ++used;
  }
  if (used > capacity_) return Status::workspace_too_small;
  // Counting sort by length; equal lengths keep symbol order (canonical rule).
  uint16_t next[kMaxLen];
  uint16_t start = 0;
  for (int i = 0; i < kMaxLen; ++i) {
    next[i] = start;
    start = static_cast<uint16_t>(start + counts[i]);
  }
  for (size_t s = 0; s < alphabet_size; ++s) {
    const uint8_t len = lengths[s];
    if (len != 0) symbols_[next[len - 1]++] = static_cast<uint16_t>(s);
  }
  return build(counts, used);
}

Status HuffmanTable::build(const uint16_t counts[kMaxCodeLength], size_t num_symbols) {
  built_ = false;
  // Validate the whole description before touching the tables: a code of
  // length L is an L-bit number, so the codes of length L must end at or
  // below 2^L (Kraft sum <= 1).
  uint32_t code = 0;
  for (int len = 1; len <= kMaxLen; ++len) {
    code = (code << 1) + counts[len - 1];
    if (code > (uint32_t{1} << len)) {
      // Leave an empty table behind: decoding with it reports malformed.
      std::memset(lookup_, 0, kLookupSize * sizeof(uint16_t));
      std::memset(limit_, 0, sizeof(limit_));
      num_symbols_ = 0;
      max_length_ = 0;
      return Status::malformed;
    }
  }

  std::memset(lookup_, 0, kLookupSize * sizeof(uint16_t));
  code = 0;
  int32_t index = 0;
  max_length_ = 0;
  limit_[0] = 0;
  offset_[0] = 0;
  for (int len = 1; len <= kMaxLen; ++len) {
    const uint32_t n = counts[len - 1];
    const uint32_t first = code;
    offset_[len] = index - static_cast<int32_t>(first);
    limit_[len] = (first + n) << (kMaxLen - len);
    if (n != 0) max_length_ = len;
    if (len <= kLookupBits) {
      // Every window whose top `len` bits are this code resolves here.
      const int spare = kLookupBits - len;
      for (uint32_t j = 0; j < n; ++j) {
        const uint16_t entry =
            static_cast<uint16_t>((symbols_[index + j] << kEntrySymbolShift) | static_cast<uint16_t>(len));
        uint16_t* dst = lookup_ + ((first + j) << spare);
        for (uint32_t k = 0; k < (uint32_t{1} << spare); ++k) dst[k] = entry;
      }
    }
    index += static_cast<int32_t>(n);
    code = (first + n) << 1;
  }
  num_symbols_ = num_symbols;
  built_ = true;
  return Status::ok;
}

int HuffmanTable::decode_window(uint32_t window, int& length) const {
  window &= 0xFFFFu;
  const uint16_t e = lookup_[window >> (kMaxLen - kLookupBits)];
  const int len = e & kEntryLengthMask;
  if (len != 0) {
    length = len;
    return e >> kEntrySymbolShift;
  }
  // The lookup covers every code of length <= kLookupBits, so a miss is a
  // longer code: the first length whose left-aligned limit lies above the
  // window is the code's length.
  for (int l = kLookupBits + 1; l <= max_length_; ++l) {
    if (window < limit_[l]) {
      length = l;
      return symbols_[offset_[l] + static_cast<int32_t>(window >> (kMaxLen - l))];
    }
  }
  length = 0;
  return -1;
}

int HuffmanTable::decode_slow(BitReader& br, uint32_t window) const {
  int length = 0;
  const int sym = decode_window(window, length);
  if (sym < 0) {
    br.fail(Status::malformed);
    return -1;
  }
  br.skip(length);
  return sym;
}

}  // namespace vds
