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
  const uint8_t* const end = p + size;
  uint32_t c = ~crc;
#if VDS_CONFIG_CRC32C_TABLE == 1024
  // Each table through a pointer of its own, opaque to the optimiser: it
  // would otherwise address all four from one base, an addition more for
  // each lookup (on a Cortex-M4 the loop is then 15 instructions for 4
  // bytes instead of 20).
  const uint32_t* t0 = kSlices.t[0];
  const uint32_t* t1 = kSlices.t[1];
  const uint32_t* t2 = kSlices.t[2];
  const uint32_t* t3 = kSlices.t[3];
#if defined(__GNUC__)
  __asm__("" : "+r"(t0), "+r"(t1), "+r"(t2), "+r"(t3));
#endif
  for (const uint8_t* const end4 = p + (size & ~size_t{3}); p != end4; p += 4) {
    // The bytes in stream order, first byte lowest (the reflected CRC's order):
    // one word load on a little-endian machine.
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    uint32_t w;
    __builtin_memcpy(&w, p, 4);  // -ffreestanding: ask for the inline load explicitly
    c ^= w;
#else
    c ^= static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 | static_cast<uint32_t>(p[2]) << 16 |
         static_cast<uint32_t>(p[3]) << 24;
#endif
    c = t3[c & 0xFFu] ^ t2[(c >> 8) & 0xFFu] ^ t1[(c >> 16) & 0xFFu] ^ t0[c >> 24];
  }
#endif
  for (; p != end; ++p) {
#if VDS_CONFIG_CRC32C_TABLE == 1024
    c = kSlices.t[0][(c ^ *p) & 0xFFu] ^ (c >> 8);
#elif VDS_CONFIG_CRC32C_TABLE == 256
    c = kTable.v[(c ^ *p) & 0xFFu] ^ (c >> 8);
#else
    c ^= *p;
    c = kTable.v[c & 0x0Fu] ^ (c >> 4);
    c = kTable.v[c & 0x0Fu] ^ (c >> 4);
#endif
  }
  return ~c;
}

}  // namespace vds
