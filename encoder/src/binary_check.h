// vds encoder: the refusal the project's checks of binary model files (GLB,
// IQM, MD3) throw before assimp sees them. Private to encoder/src.
#pragma once
#include <cstddef>
#include <stdexcept>
#include <string>

namespace vds::enc {

// Throws std::runtime_error "NAME: what (byte AT)".
[[noreturn]] inline void refuse_at_byte(const std::string& name, const std::string& what, size_t at) {
  throw std::runtime_error(name + ": " + what + " (byte " + std::to_string(at) + ")");
}

}  // namespace vds::enc
