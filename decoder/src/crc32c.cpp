// CRC-32C (iSCSI / RFC 3720 polynomial), table-driven; the table size is a
// build option (config.h: VDS_CONFIG_CRC32C_TABLE).
#include "vds/crc32c.h"

#include "vds/config.h"

namespace vds {
namespace {

constexpr uint32_t kPolyReflected = 0x82F63B78u;

template <int kEntries>
struct CrcTable {
  uint32_t v[kEntries];
};

// Entry i is the CRC of the value i shifted through log2(kEntries) bits.
template <int kEntries, int kBits>
constexpr CrcTable<kEntries> make_table() {
  CrcTable<kEntries> t{};
  for (int i = 0; i < kEntries; ++i) {
    uint32_t c = static_cast<uint32_t>(i);
    for (int b = 0; b < kBits; ++b) c = (c & 1u) ? (c >> 1) ^ kPolyReflected : c >> 1;
    t.v[i] = c;
  }
  return t;
}

#if VDS_CONFIG_CRC32C_TABLE == 1024
// Slicing by four: table k (k = 1..3) advances entry i of table k-1 by one
// more zero byte, so four bytes fold in with four lookups.
struct SliceTables {
  uint32_t t[4][256];
};
constexpr SliceTables make_slices() {
  const CrcTable<256> t0 = make_table<256, 8>();
  SliceTables s{};
  for (int i = 0; i < 256; ++i) s.t[0][i] = t0.v[i];
  for (int k = 1; k < 4; ++k)
    for (int i = 0; i < 256; ++i) s.t[k][i] = (s.t[k - 1][i] >> 8) ^ t0.v[s.t[k - 1][i] & 0xFFu];
  return s;
}
constexpr SliceTables kSlices = make_slices();
#elif VDS_CONFIG_CRC32C_TABLE == 256
constexpr CrcTable<256> kTable = make_table<256, 8>();
#else
constexpr CrcTable<16> kTable = make_table<16, 4>();
#endif

}  // namespace

uint32_t crc32c_update(uint32_t crc, const void* data, size_t size) {
  const uint8_t* p = static_cast<const uint8_t*>(data);
  uint32_t c = ~crc;
  size_t i = 0;
#if VDS_CONFIG_CRC32C_TABLE == 1024
  for (; i + 4 <= size; i += 4) {
    // The bytes in stream order, first byte lowest (the reflected CRC's order):
    // one word load on a little-endian machine.
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    uint32_t w;
    __builtin_memcpy(&w, p + i, 4);  // -ffreestanding: ask for the inline load explicitly
    c ^= w;
#else
    c ^= static_cast<uint32_t>(p[i]) | static_cast<uint32_t>(p[i + 1]) << 8 | static_cast<uint32_t>(p[i + 2]) << 16 |
         static_cast<uint32_t>(p[i + 3]) << 24;
#endif
    c = kSlices.t[3][c & 0xFFu] ^ kSlices.t[2][(c >> 8) & 0xFFu] ^ kSlices.t[1][(c >> 16) & 0xFFu] ^ kSlices.t[0][c >> 24];
  }
#endif
  for (; i < size; ++i) {
#if VDS_CONFIG_CRC32C_TABLE == 1024
    c = kSlices.t[0][(c ^ p[i]) & 0xFFu] ^ (c >> 8);
#elif VDS_CONFIG_CRC32C_TABLE == 256
    c = kTable.v[(c ^ p[i]) & 0xFFu] ^ (c >> 8);
#else
    c ^= p[i];
    c = kTable.v[c & 0x0Fu] ^ (c >> 4);
    c = kTable.v[c & 0x0Fu] ^ (c >> 4);
#endif
  }
  return ~c;
}

}  // namespace vds
