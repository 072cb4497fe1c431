// Fuzzes the canonical Huffman decoder: raw code descriptions (JPEG counts +
// symbols, or per-symbol lengths) followed by raw bits, decoded until an
// error; and a round trip (frequencies -> package-merge code -> bits ->
// decoder) that traps on any mismatch.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <vector>

#include "vds/arena.h"
#include "vds/bitreader.h"
#include "vds/enc/bitwriter.h"
#include "vds/enc/huffman_build.h"
#include "vds/huffman.h"

namespace {

constexpr size_t kMaxDecodes = 1u << 14;

alignas(8) uint8_t g_work[vds::HuffmanTable::workspace_bytes(vds::HuffmanTable::kMaxSymbols)];

void check(bool ok) {
  if (!ok) __builtin_trap();
}

// Decodes from an exact-size heap copy until the reader latches an error.
void decode_all(const vds::HuffmanTable& t, const uint8_t* bits, size_t n, const uint8_t* lengths, size_t alphabet) {
  std::unique_ptr<uint8_t[]> copy(new uint8_t[n]);
  if (n) std::memcpy(copy.get(), bits, n);
  vds::BitReader br(copy.get(), n);
  for (size_t i = 0; i < kMaxDecodes && br.ok(); ++i) {
    const uint32_t window = br.peek(16);
    int len = 0;
    const int via_window = t.decode_window(window, len);
    const size_t before = br.bit_position();
    const int s = t.decode(br);
    check(s == via_window);
    if (s < 0) {
      check(br.status() == vds::Status::malformed && len == 0 && br.bit_position() == before);
    } else {
      check(len >= 1 && len <= 16 && br.bit_position() == before + static_cast<size_t>(len));
      if (lengths) check(static_cast<size_t>(s) < alphabet && lengths[s] == len);
    }
  }
}

void raw_counts(const uint8_t* data, size_t size) {
  if (size < 16) return;
  const uint8_t* counts = data;
  size_t n = 0;
  for (int i = 0; i < 16; ++i) n += counts[i];
  data += 16;
  size -= 16;
  if (n > size) n = size;  // too few symbols: the build must refuse the mismatch
  vds::Arena arena(g_work, sizeof(g_work));
  vds::HuffmanTable t;
  check(t.reserve(arena, 4096) == vds::Status::ok);
  const vds::Status st = t.build_from_counts(counts, data, n);
  if (st != vds::Status::ok) {
    check(st == vds::Status::malformed || st == vds::Status::invalid_argument);
    return;
  }
  decode_all(t, data + n, size - n, nullptr, 0);
}

void raw_lengths(const uint8_t* data, size_t size) {
  if (size < 2) return;
  size_t alphabet = (static_cast<size_t>(data[0]) << 8 | data[1]) % (vds::HuffmanTable::kMaxSymbols + 1);
  data += 2;
  size -= 2;
  if (alphabet > size) alphabet = size;
  std::vector<uint8_t> lengths(data, data + alphabet);
  for (auto& l : lengths) l &= 0x1F;  // 17..31 must be rejected
  vds::Arena arena(g_work, sizeof(g_work));
  vds::HuffmanTable t;
  check(t.reserve(arena, alphabet) == vds::Status::ok);
  const vds::Status st = t.build_from_lengths(lengths.data(), lengths.size());
  if (st != vds::Status::ok) {
    check(st == vds::Status::malformed);
    return;
  }
  decode_all(t, data + alphabet, size - alphabet, lengths.data(), lengths.size());
}

void round_trip(const uint8_t* data, size_t size) {
  if (size < 3) return;
  const int limit = 1 + data[0] % 16;
  const size_t alphabet = 1 + data[1] % 255;
  data += 2;
  size -= 2;
  std::vector<uint64_t> freqs(alphabet, 0);
  const size_t nf = size < alphabet ? size : alphabet;
  for (size_t i = 0; i < nf; ++i) freqs[i] = data[i] < 64 ? 0 : (uint64_t{1} << (data[i] % 24)) + data[i];
  freqs[0] |= 1;
  vds::enc::CanonicalCode code;
  try {
    code = vds::enc::huffman_build(freqs, limit);
  } catch (const std::invalid_argument&) {
    return;  // more symbols than 2^limit
  }
  for (uint8_t l : code.lengths) check(l <= limit);
  check(code.kraft_sum_q32() <= (uint64_t{1} << 32));
  std::vector<uint16_t> syms;
  vds::enc::BitWriter bw;
  for (size_t i = nf; i < size; ++i) {
    syms.push_back(code.symbols[data[i] % code.symbols.size()]);
    code.write(bw, syms.back());
  }
  const std::vector<uint8_t> bytes = bw.finish();
  std::unique_ptr<uint8_t[]> copy(new uint8_t[bytes.size()]);
  if (!bytes.empty()) std::memcpy(copy.get(), bytes.data(), bytes.size());
  vds::Arena arena(g_work, sizeof(g_work));
  vds::HuffmanTable t;
  check(t.reserve(arena, code.symbols.size()) == vds::Status::ok);
  uint16_t counts[16];
  for (int i = 0; i < 16; ++i) counts[i] = code.counts[static_cast<size_t>(i)];
  check(t.build_from_counts(counts, code.symbols.data(), code.symbols.size()) == vds::Status::ok);
  vds::BitReader br(copy.get(), bytes.size());
  for (uint16_t s : syms) check(t.decode(br) == s);
  check(br.status() == vds::Status::ok);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  switch (data[0] % 3) {
    case 0: raw_counts(data + 1, size - 1); break;
    case 1: raw_lengths(data + 1, size - 1); break;
    default: round_trip(data + 1, size - 1); break;
  }
  return 0;
}
