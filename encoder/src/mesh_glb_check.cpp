// vds encoder: the GLB framing check (mesh_glb_check.h).
#include "mesh_glb_check.h"

#include <stdexcept>

#include "binary_check.h"
#include "vds/bytes.h"

namespace vds::enc {

namespace {

constexpr uint32_t kMagic = 0x46546C67;      // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
constexpr uint32_t kChunkBin = 0x004E4942;   // "BIN\0"

}  // namespace

void check_glb(const uint8_t* data, size_t size, const std::string& name) {
  if (size < 12 || load_le32(data) != kMagic) refuse_at_byte(name, "not a binary glTF file (it must start with 'glTF')", 0);
  const uint32_t version = load_le32(data + 4), length = load_le32(data + 8);
  if (version != 2) refuse_at_byte(name, "binary glTF version " + std::to_string(version) + " (2 is read)", 4);
  if (length != size)
    refuse_at_byte(name, "the header says the file is " + std::to_string(length) + " bytes, it is " + std::to_string(size), 8);
  size_t at = 12;
  int chunk = 0;
  while (at < size) {
    if (size - at < 8) refuse_at_byte(name, "the file ends inside a chunk header", at);
    const uint32_t len = load_le32(data + at), type = load_le32(data + at + 4);
    if (len % 4 != 0) refuse_at_byte(name, "a chunk length of " + std::to_string(len) + " (a multiple of 4 is required)", at);
    if (len > size - at - 8)
      refuse_at_byte(name, "a chunk of " + std::to_string(len) + " bytes where " + std::to_string(size - at - 8) + " remain", at);
    if (chunk == 0 && type != kChunkJson) refuse_at_byte(name, "the first chunk is not JSON", at + 4);
    if (chunk == 1 && type != kChunkBin) refuse_at_byte(name, "the second chunk is not BIN", at + 4);
    if (chunk >= 2) refuse_at_byte(name, "more than a JSON and a BIN chunk", at);
    at += 8 + static_cast<size_t>(len);
    ++chunk;
  }
  if (chunk == 0) refuse_at_byte(name, "no JSON chunk", 12);
}

}  // namespace vds::enc
