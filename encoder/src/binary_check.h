// vds encoder: the refusal the project's checks of binary model files (GLB,
// IQM, MD2, MD3, MS3D) throw before assimp sees them. Private to encoder/src.
#pragma once
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "vds/bytes.h"

namespace vds::enc {

// Throws std::runtime_error "NAME: what (byte AT)".
[[noreturn]] inline void refuse_at_byte(const std::string& name, const std::string& what, size_t at) {
  throw std::runtime_error(name + ": " + what + " (byte " + std::to_string(at) + ")");
}

// `count` items of `item` bytes at `base` plus the signed 32-bit offset
// stored at `field`: refused unless the offset is at least `min_offset`
// and the items lie inside the file. Returns where they start (0 when
// count is 0, which is never refused).
inline size_t table_in_file(const uint8_t* d, size_t size, size_t base, size_t field, uint64_t count, uint64_t item,
                            int64_t min_offset, const std::string& what, const std::string& name) {
  if (count == 0) return 0;
  const int64_t off = load_le32s(d + field);
  const int64_t at = static_cast<int64_t>(base) + off;
  if (off < min_offset || at > static_cast<int64_t>(size) || count * item > size - static_cast<size_t>(at))
    refuse_at_byte(name, what + ": " + std::to_string(count) + " of " + std::to_string(item) + " bytes at offset " + std::to_string(off) +
                             " do not fit the file's " + std::to_string(size) + " bytes",
                   field);
  return static_cast<size_t>(at);
}

// The signed little-endian 32-bit field at `at`, refused ("WHAT V (LO..HI)")
// unless within lo..hi.
inline uint32_t field_in(const uint8_t* d, size_t at, uint32_t lo, uint32_t hi, const std::string& what,
                         const std::string& name) {
  const int32_t v = load_le32s(d + at);
  if (v < 0 || static_cast<uint32_t>(v) < lo || static_cast<uint32_t>(v) > hi)
    refuse_at_byte(name, what + " " + std::to_string(v) + " (" + std::to_string(lo) + ".." + std::to_string(hi) + ")", at);
  return static_cast<uint32_t>(v);
}

}  // namespace vds::enc
