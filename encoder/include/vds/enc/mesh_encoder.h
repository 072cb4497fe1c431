// vds encoder: the progressive mesh codec (Qin, Liu, Bao, Peng 2002) — the
// simplification of vds/enc/mesh_simplify.h coded level by level into
// MSHH / MSHB / MSHL chunks of a model-mode stream, either as the paper does
// (per-level Huffman tables sent as unary length deltas, sorted split-vertex
// deltas, (L-F) codes, eq. 13's Laplacian predictor) or with the
// context-adaptive arithmetic coder and geometric contexts
// (docs/mesh-codec.md). The encoder reconstructs with the client's own
// MeshState, so what it measures is what the client decodes.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "vds/enc/mesh_import.h"
#include "vds/enc/mesh_simplify.h"
#include "vds/mesh.h"
#include "vds/mesh_model.h"

namespace vds::enc {

// `vds encode-mesh`'s tail_fraction: split levels up to 4 % of the
// vertices (the bunny's base and 19 levels, 1,292 vertices in 4.8 KB), then
// the single-rate tail.
constexpr double kMeshDefaultTail = 0.04;

struct MeshEncodeOptions {
  MeshEncodeOptions() {
    simplify.rate_weight = 4.0;
    simplify.packing_weight = 0.1;
  }
  int bits = 10;  // quantisation bits per axis, 2..16
  MeshCoder coder = MeshCoder::arith;
  MeshPredictor predictor = MeshPredictor::area;
  // Parallelogram weight in sixteenths; -1 picks the best per level.
  int weight_q4 = -1;
  SimplifyOptions simplify;
  uint32_t max_chunk_payload = 4096;  // >= 512
  uint16_t width = 240, height = 180;  // HEAD frame size (the client's display)
  MeshUp up = MeshUp::y_plus;          // the axis a viewer shows up (MSHH's view block)
  // The single-rate tail (docs/mesh-codec.md): after the vertex-split
  // levels that reach at most tail_fraction of the vertices (but at least
  // tail_min_levels of them, when there are that many), the whole mesh is
  // sent once more single-rate, which costs far less than the remaining
  // splits. 0 turns it off; meshes it cannot take (a component with a
  // handle, a vertex ring above kMeshMaxDegree) are coded without it, and
  // MeshEncodeResult::tail_note says why. Arithmetic coder only.
  double tail_fraction = 0;
  uint32_t tail_min_levels = 11;
};

// The paper's choices: Huffman coding, the Laplacian predictor of eq. 13
// and the vertex priority of eq. 1 alone (rate_weight 0). The default
// options instead code arithmetically with the parallelogram-weighted
// predictor, add the prediction residual to the priority and visit the
// vertices of a level so that its independent sets come out larger.
MeshEncodeOptions paper_mesh_options();

// The simplification encode_mesh runs for `o`: o.simplify with the degree
// limit the client can hold, and the priority's rate term measured from
// where the chosen predictor places a vertex.
SimplifyOptions mesh_simplify_options(const MeshEncodeOptions& o);

// "Laplacian", "parallelogram" or "area", for tables and messages.
const char* mesh_predictor_name(MeshPredictor p);

// "+y", "+z", "+x", "-y", "-z", "-x"; mesh_up_from_name also takes them
// without the sign for the positive axes, and returns false for anything else.
const char* mesh_up_name(MeshUp up);
bool mesh_up_from_name(const std::string& name, MeshUp* up);

// One row of the per-level table; row 0 is the base mesh.
struct MeshLevelStats {
  uint32_t level = 0;
  uint32_t vertices_added = 0;   // dV (the base: its vertices)
  uint32_t triangles_added = 0;  // dT
  uint32_t vertices = 0;         // after the level
  uint32_t triangles = 0;
  uint64_t connectivity_bytes = 0;  // entropy-coded connectivity (base: the whole base payload)
  uint64_t geometry_bytes = 0;      // entropy-coded positions (base: 0)
  uint64_t chunk_bytes = 0;         // everything the level's chunks take in the stream, framing included
  uint32_t chunks = 0;
  int weight_q4 = 0;                // parallelogram weight used
  uint64_t checksum = 0;            // mesh_checksum of the client's mesh after the level (encoder only)
  double error_threshold = 0;       // simplification threshold in force (grid units)
  bool tail = false;                // the single-rate tail (the last level; dV, dT net)
};

// Where the entropy-coded bits go: the arithmetic coder's estimate from its
// context states at coding time (within ~0.1 % of the bytes written), or
// the exact code lengths for Huffman. Chunk headers are not included.
struct MeshBitBreakdown {
  double base = 0;            // the base mesh
  double split_flags = 0;     // which vertices split: flags, or the paper's sorted index deltas (+ tables)
  double split_shape = 0;     // boundary kind and arc length (the paper's L-F code)
  double split_rotation = 0;  // which rotation of the arc (rank; the paper's F position)
  double geometry = 0;        // position corrections, all axes
  double geometry_normal = 0; // of which along the axis nearest the ring normal (arithmetic coder only)
  double tail_connectivity = 0;  // the single-rate tail: its traversal
  double tail_geometry = 0;      // and its positions
  double connectivity() const { return split_flags + split_shape + split_rotation; }
};

struct MeshEncodeResult {
  std::vector<uint8_t> stream;
  StreamHeader stream_header{};
  MeshHeader mesh_header{};
  Quantisation quantisation;
  std::vector<MeshLevelStats> levels;  // [0] base, [i] level i
  size_t fixed_bytes = 0;              // preamble, HEAD, MSHH and END
  // Input vertex of each decoded vertex (the decoder's order).
  std::vector<uint32_t> vertex_order;
  int max_degree = 0;
  double error_limit = 0;  // E in grid units
  MeshBitBreakdown bits;
  bool tail = false;       // the last level is the single-rate tail
  TailCounts tail_counts;  // its MSHT counts (holes closed, border edges at most)
  std::string tail_note;   // why a requested tail was not used
};

// Encodes a repaired mesh (import_mesh / repair_mesh; check_manifold must
// hold). Throws std::invalid_argument for bad options or a mesh the codec
// cannot take (not manifold, a vertex ring above kMeshMaxDegree), and
// std::logic_error if the reconstruction does not reproduce the input.
MeshEncodeResult encode_mesh(const Mesh& mesh, const MeshEncodeOptions& options);

// FNV-1a over the positions and triangle indices of a client mesh, in the
// client's order: equal checksums mean the client holds exactly this mesh.
uint64_t mesh_checksum(const MeshState& m);

// The per-level table in the paper's form (level, dV, dT, C/dT, G/dT,
// (C+G)/dT) plus the stream bytes per level and the totals.
std::string format_mesh_table(const std::vector<MeshLevelStats>& levels, size_t stream_bytes);

// Collects the mesh chunks of a stream without decoding them (the chunk
// headers give dV, dT and the two substream sizes), for `vds info`:
//   MeshChunkSummary s; ... s.add(type, payload, size) per chunk ...;
//   std::fputs(s.table().c_str(), stdout);
class MeshChunkSummary {
 public:
  // Returns true if the chunk was a mesh chunk.
  bool add(uint32_t type, const uint8_t* payload, uint32_t size);
  bool empty() const { return !have_header_; }
  std::string table() const;

 private:
  bool have_header_ = false;
  MeshHeader header_{};
  std::vector<MeshLevelStats> levels_;
};

}  // namespace vds::enc
