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

#if VDS_CONFIG_CRC32C_TABLE == 256
constexpr CrcTable<256> kTable = make_table<256, 8>();
#else
constexpr CrcTable<16> kTable = make_table<16, 4>();
#endif

}  // namespace

uint32_t crc32c_update(uint32_t crc, const void* data, size_t size) {
  const uint8_t* p = static_cast<const uint8_t*>(data);
  uint32_t c = ~crc;
  for (size_t i = 0; i < size; ++i) {
#if VDS_CONFIG_CRC32C_TABLE == 256
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
