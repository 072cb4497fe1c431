// vds encoder: a binary glTF (GLB) file's framing checked before assimp sees
// it: assimp takes the lengths in its header and chunk headers as given and
// allocates them (a 558-byte file asked for 1.7 GB). The layout: Khronos,
// "glTF 2.0 Specification", section 4.4 (GLB File Format Specification).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

namespace vds::enc {

// Throws std::runtime_error "NAME: what is wrong (byte N)" unless the file
// is a 12-byte header ("glTF", version 2, the file's length) followed by
// chunks that exactly fill it, the first a JSON chunk, at most one BIN chunk
// after it, each length a multiple of 4.
void check_glb(const uint8_t* data, size_t size, const std::string& name);

}  // namespace vds::enc
