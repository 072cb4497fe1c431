// libFuzzer: the progressive mesh decoder on hostile input, three ways
// (first byte): raw chunk records straight into MeshDecoder; byte flips in
// the chunks of valid streams (both coders, and with the single-rate tail),
// past any CRC; and round trips of small meshes built from the input, with
// and without the tail, which must come back exactly, in full and in a
// client that holds only the levels that fit.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "vds/container.h"
#include "vds/enc/mesh_encoder.h"
#include "vds/enc/mesh_import.h"
#include "vds/mesh.h"

namespace {

constexpr uint32_t kMaxVertices = 2048, kMaxTriangles = 4096;

struct Chunk {
  uint32_t type;
  std::vector<uint8_t> payload;
};

vds::enc::Mesh grid(int nx, int ny, const uint8_t* z, size_t zn) {
  vds::enc::Mesh m;
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x) {
      const size_t i = static_cast<size_t>(y * nx + x);
      const double h = zn ? z[i % zn] : 0;
      m.positions.push_back({double(x), double(y), h / 16.0});
    }
  for (int y = 0; y + 1 < ny; ++y)
    for (int x = 0; x + 1 < nx; ++x) {
      const uint32_t a = static_cast<uint32_t>(y * nx + x), b = a + 1, c = a + static_cast<uint32_t>(nx), d = c + 1;
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
    }
  return m;
}

std::vector<Chunk> mesh_chunks(const std::vector<uint8_t>& stream) {
  std::vector<Chunk> out;
  size_t at = vds::kPreambleBytes;
  while (at + vds::kChunkHeadBytes <= stream.size()) {
    uint32_t type = 0, len = 0;
    std::memcpy(&type, stream.data() + at, 4);
    std::memcpy(&len, stream.data() + at + 4, 4);
    if (vds::MeshDecoder::handles(type))
      out.push_back({type, std::vector<uint8_t>(stream.begin() + static_cast<long>(at + 8),
                                                stream.begin() + static_cast<long>(at + 8 + len))});
    at += vds::kChunkHeadBytes + len + vds::kChunkTailBytes;
  }
  return out;
}

// 0 arithmetic, 1 Huffman, 2 arithmetic with the tail.
const std::vector<Chunk>& reference(int variant) {
  static std::vector<Chunk> refs[3];
  if (refs[variant].empty()) {
    vds::enc::MeshEncodeOptions o;
    o.coder = variant == 1 ? vds::MeshCoder::huffman : vds::MeshCoder::arith;
    o.max_chunk_payload = 512;
    if (variant == 2) {
      o.tail_fraction = 0.3;
      o.tail_min_levels = 2;
    }
    const uint8_t z[] = {3, 9, 1, 7, 12, 0, 5, 8, 2, 11, 6};
    refs[variant] = mesh_chunks(vds::enc::encode_mesh(grid(9, 8, z, sizeof z), o).stream);
  }
  return refs[variant];
}

// Feeds the chunks to a fresh decoder in an exactly sized copy each.
void decode(const std::vector<Chunk>& chunks) {
  static std::vector<uint8_t> ws(vds::MeshDecoder::workspace_bytes(kMaxVertices, kMaxTriangles, kMaxTriangles,
                                                                    vds::MeshCoder::huffman, 3 * kMaxTriangles));
  vds::Arena arena(ws.data(), ws.size());
  vds::MeshDecoder dec;
  if (dec.init(arena, kMaxVertices, kMaxTriangles) != vds::Status::ok) __builtin_trap();
  for (const Chunk& c : chunks) {
    std::vector<uint8_t> copy(c.payload);
    const vds::Status s = dec.consume(c.type, copy.data(), static_cast<uint32_t>(copy.size()));
    if (vds::is_error(s)) {
      // Latched: the same error again.
      if (dec.consume(c.type, copy.data(), static_cast<uint32_t>(copy.size())) != s) __builtin_trap();
      return;
    }
    const vds::MeshState& m = dec.mesh();
    if (m.vertex_count() > kMaxVertices || m.triangle_count() > kMaxTriangles) __builtin_trap();
  }
  if (dec.complete() && dec.finish() != vds::Status::ok) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 3) return 0;
  const int mode = data[0] % 3;
  data += 1;
  size -= 1;
  if (mode == 0) {
    // Records: type selector, 16-bit length, payload.
    static const uint32_t types[4] = {vds::chunk::kMeshHeader, vds::chunk::kMeshBase, vds::chunk::kMeshLevel,
                                      vds::chunk::kMeshTail};
    std::vector<Chunk> chunks;
    size_t at = 0;
    while (at + 3 <= size) {
      const uint32_t type = types[data[at] % 4];
      const size_t len = std::min<size_t>(size - at - 3, size_t{data[at + 1]} | size_t{data[at + 2]} << 8);
      chunks.push_back({type, std::vector<uint8_t>(data + at + 3, data + at + 3 + len)});
      at += 3 + len;
    }
    decode(chunks);
  } else if (mode == 1) {
    // Byte flips (chunk, offset, xor) in a valid stream's chunks.
    std::vector<Chunk> chunks = reference(data[0] % 3);
    for (size_t at = 1; at + 3 <= size; at += 3) {
      Chunk& c = chunks[data[at] % chunks.size()];
      if (c.payload.empty()) continue;
      c.payload[data[at + 1] % c.payload.size()] ^= data[at + 2];
    }
    decode(chunks);
  } else {
    // Round trip of a small grid whose heights and options come from the input.
    const int nx = 3 + data[0] % 6, ny = 3 + (data[0] >> 4) % 6;
    vds::enc::MeshEncodeOptions o;
    o.coder = (data[1] & 1) ? vds::MeshCoder::huffman : vds::MeshCoder::arith;
    o.predictor = (data[1] & 2) ? vds::MeshPredictor::laplacian
                                : ((data[1] & 0x80) ? vds::MeshPredictor::parallelogram : vds::MeshPredictor::area);
    o.bits = 4 + (data[1] >> 2) % 13;
    if ((data[1] & 0x40) && o.coder == vds::MeshCoder::arith) {
      o.tail_fraction = 0.3;
      o.tail_min_levels = 2;
    }
    const vds::enc::Mesh m = grid(nx, ny, data + 2, size > 2 ? size - 2 : 0);
    vds::enc::MeshEncodeResult r;
    try {
      r = vds::enc::encode_mesh(m, o);
    } catch (const std::invalid_argument&) {
      return 0;  // not encodable (e.g. a degree the client cannot hold): refused, fine
    } catch (const std::logic_error&) {
      __builtin_trap();  // the encoder's own reconstruction failed
    }
    decode(mesh_chunks(r.stream));
    // The full decode must match the encoder's last checksum.
    static std::vector<uint8_t> ws(8u << 20);
    vds::Arena arena(ws.data(), ws.size());
    vds::MeshDecoder dec;
    if (dec.init(arena, r.stream_header.max_vertices, r.stream_header.max_triangles) != vds::Status::ok)
      __builtin_trap();
    for (const Chunk& c : mesh_chunks(r.stream))
      if (dec.consume(c.type, c.payload.data(), static_cast<uint32_t>(c.payload.size())) != vds::Status::ok)
        __builtin_trap();
    if (!dec.complete() || vds::enc::mesh_checksum(dec.mesh()) != r.levels.back().checksum) __builtin_trap();
    // A client that holds fewer vertices (from the input) stops at the last
    // level that fits, with exactly the encoder's mesh of that level.
    const uint32_t base_v = r.levels.front().vertices, full_v = r.stream_header.max_vertices;
    const uint32_t limit = base_v + (size > 2 ? data[2] : 0) % (full_v - base_v + 1);
    vds::Arena small(ws.data(), ws.size());
    vds::MeshDecoder part;
    if (part.init(small, limit, r.stream_header.max_triangles) != vds::Status::ok) __builtin_trap();
    for (const Chunk& c : mesh_chunks(r.stream))
      if (part.consume(c.type, c.payload.data(), static_cast<uint32_t>(c.payload.size())) != vds::Status::ok)
        __builtin_trap();
    const uint32_t k = part.levels_done();
    // What level k + 1 needs: its vertices, or for the tail HEAD's count (its dummies too).
    const auto needs = [&](uint32_t l) { return r.levels[l].tail ? full_v : r.levels[l].vertices; };
    if (part.finish() != vds::Status::ok || part.mesh().vertex_count() > limit ||
        vds::enc::mesh_checksum(part.mesh()) != r.levels[k].checksum ||
        (k + 1 < r.levels.size() && needs(k + 1) <= limit) ||
        part.capacity_reached() == (k + 1 == r.levels.size()))
      __builtin_trap();
  }
  return 0;
}
