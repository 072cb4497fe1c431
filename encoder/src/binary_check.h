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
