// vds client library: CRC-32C (Castagnoli, reflected polynomial 0x82F63B78),
// the checksum of stream chunks, link frames and displayed frames.
#pragma once
#include <cstddef>
#include <cstdint>

namespace vds {

// Continues a CRC: pass the previous return value (0 to start) so a checksum
// can be computed over data that arrives in pieces.
// crc32c_update(0, "123456789", 9) == 0xE3069283.
uint32_t crc32c_update(uint32_t crc, const void* data, size_t size);

inline uint32_t crc32c(const void* data, size_t size) { return crc32c_update(0, data, size); }

}  // namespace vds
