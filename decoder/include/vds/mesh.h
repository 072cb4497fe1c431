// vds client library: progressive mesh decoder (Qin, Liu, Bao, Peng,
// "Progressive geometry compression of meshes", 2002): a base mesh, then
// levels of vertex splits whose removed vertices form an independent set,
// each level coded as its split vertices (in index order), the split shapes
// and the position corrections from a predictor. The stream format is in
// docs/stream-format.md ("Progressive mesh chunks"), the algorithms in
// docs/mesh-codec.md.
//
// The application interface: the mesh chunks, the mesh header and
// MeshDecoder, which reads the chunks into a MeshState (vds/mesh_model.h,
// the internals the decoder shares with the encoder).
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/arena.h"
#include "vds/container.h"
#include "vds/mesh_model.h"
#include "vds/status.h"

namespace vds {

namespace chunk {
constexpr uint32_t kMeshHeader = fourcc('M', 'S', 'H', 'H');  // mesh codec parameters, once, before MSHB
constexpr uint32_t kMeshBase = fourcc('M', 'S', 'H', 'B');    // base mesh (one or more chunks)
constexpr uint32_t kMeshLevel = fourcc('M', 'S', 'H', 'L');   // one refinement level (one or more chunks)
constexpr uint32_t kMeshTail = fourcc('M', 'S', 'H', 'T');    // the single-rate last level (one or more chunks)
}  // namespace chunk

constexpr uint8_t kMeshCodecVersion = 1;
// MSHH version of a stream whose last level is a single-rate tail (MSHT).
constexpr uint8_t kMeshCodecVersionTail = 2;

enum class MeshCoder : uint8_t {
  huffman = 0,  // the paper's coding: per-level canonical Huffman tables, sent as unary length deltas
  arith = 1,    // context-adaptive binary arithmetic coding (vds/arith.h) with geometric contexts
};

// Which grid axis points up when the model is shown (MSHH's view block;
// streams without one are +y, as glTF). A viewer hint only: the decoded
// positions are the same either way.
enum class MeshUp : uint8_t { y_plus = 0, z_plus = 1, x_plus = 2, y_minus = 3, z_minus = 4, x_minus = 5 };

// MSHH payload (docs/stream-format.md).
struct MeshHeader {
  // kMeshCodecVersion, or kMeshCodecVersionTail when the last of `levels`
  // is a single-rate tail (MSHT chunks) instead of vertex splits.
  uint8_t version = kMeshCodecVersion;
  constexpr bool tail() const { return version == kMeshCodecVersionTail; }
  MeshCoder coder = MeshCoder::arith;
  MeshPredictor predictor = MeshPredictor::parallelogram;
  uint8_t bits = 10;        // quantisation bits per axis, 2..16
  uint16_t levels = 0;      // refinement levels after the base
  uint16_t max_degree = 0;  // largest ring while decoding, 3..kMeshMaxDegree
  uint32_t base_vertices = 0;
  uint32_t base_triangles = 0;
  uint32_t vertices = 0;    // after the last level
  uint32_t triangles = 0;
  // Model-space placement, informative for hosts: position = origin + q·step
  // as IEEE-754 binary32 bit patterns. The client never interprets them.
  uint32_t origin_f32[3] = {0, 0, 0};
  uint32_t step_f32 = 0;
  MeshUp up = MeshUp::y_plus;  // the view block, present when not +y
  // Version 2, the tail block: what the tail needs beyond `vertices` and
  // `triangles` (one dummy vertex per hole and its fan of triangles) and
  // the most border edges its traversal keeps at once.
  uint32_t tail_dummy_vertices = 0;
  uint32_t tail_dummy_triangles = 0;
  uint32_t tail_max_border = 0;
};
constexpr uint32_t kMeshHeaderBytes = 40;      // without the view block
constexpr uint32_t kMeshHeaderViewBytes = 44;  // with it: up axis, three zero bytes
constexpr uint32_t kMeshHeaderTailBytes = 56;  // version 2: the view block, then the tail block
// Bytes mesh_header_to_bytes writes for `h`: 40, or 44 when up is not +y;
// 56 for version 2.
constexpr uint32_t mesh_header_size(const MeshHeader& h) {
  return h.tail() ? kMeshHeaderTailBytes : (h.up == MeshUp::y_plus ? kMeshHeaderBytes : kMeshHeaderViewBytes);
}
void mesh_header_to_bytes(const MeshHeader& h, uint8_t out[kMeshHeaderTailBytes]);
Status mesh_header_from_bytes(const uint8_t* p, uint32_t size, MeshHeader* out);

// --- Decoder ---------------------------------------------------------------------

// Per-level numbers as decoded (for statistics and the renderer).
struct MeshLevelInfo {
  uint32_t level = 0;
  uint32_t vertices_added = 0;
  uint32_t triangles_added = 0;
  uint32_t connectivity_bytes = 0;  // entropy-coded payload bytes, both substreams
  uint32_t geometry_bytes = 0;
};

class MeshDecoder {
 public:
  // Workspace for streams of up to max_vertices / max_triangles (HEAD's
  // budgets) whose base mesh has up to max_base_triangles (scratch used once
  // to connect the base) with the given coder (Huffman adds its tables).
  // An encoder writes this into HEAD.workspace_bytes.
  // A version-2 stream adds its TailContexts and the tail's border of
  // `tail_border` edges (MSHH's tail_max_border); its max_vertices and
  // max_triangles include the tail's dummies (HEAD's budgets).
  static size_t workspace_bytes(uint32_t max_vertices, uint32_t max_triangles, uint32_t max_base_triangles,
                                MeshCoder coder, uint32_t tail_border = 0);
  // What the tail carves when it starts: its contexts and its border.
  static size_t tail_workspace_bytes(uint32_t tail_border) {
    return sizeof(TailContexts) + alignof(TailContexts) + MeshTail::workspace_bytes(tail_border);
  }

  // Carves the mesh, the contexts and the split flags from `arena` for a
  // mesh of up to max_vertices / max_triangles (the stream's full counts, or
  // fewer: see capacity_reached()); the Huffman tables and the base scratch
  // are carved when MSHH / the base arrive (workspace_too_small then if the
  // arena cannot hold them).
  Status init(Arena& arena, uint32_t max_vertices, uint32_t max_triangles);

  // True for the chunk types this decoder consumes.
  static bool handles(uint32_t type) {
    return type == chunk::kMeshHeader || type == chunk::kMeshBase || type == chunk::kMeshLevel ||
           type == chunk::kMeshTail;
  }
  // Consumes one verified chunk payload (MSHH, then MSHB chunks, then MSHL
  // chunks level by level, then for version 2 the MSHT chunks). The first error is latched and returned again.
  Status consume(uint32_t type, const uint8_t* payload, uint32_t size);
  // ok once every level of the header is in, or once the workspace is full
  // (capacity_reached()); truncated before that.
  Status finish() const;

  Status status() const { return status_; }
  bool have_header() const { return have_header_; }
  const MeshHeader& header() const { return header_; }
  // The base is complete: the arrays hold a drawable mesh.
  bool drawable() const { return base_done_; }
  // Complete levels applied after the base.
  uint32_t levels_done() const { return levels_done_; }
  bool complete() const { return base_done_ && levels_done_ == header_.levels; }
  // A level did not fit init's counts (for a version-2 stream's tail, as
  // soon as the level before it is in: MSHH says what the tail needs, its
  // dummies, contexts and border included): the mesh stays at
  // levels_done() and every later level chunk is skipped unread. Only the base has to fit
  // (workspace_too_small otherwise), so a small client plays a prefix.
  bool capacity_reached() const { return full_; }
  const MeshState& mesh() const { return mesh_; }
  // Numbers of the level completed last (level 0 = the base).
  const MeshLevelInfo& last_level() const { return last_; }

  // Calls fn(user) after every `every_items` level items (split flags and
  // vertex splits) while consume() decodes a chunk: a full chunk can take a
  // third of a second on a 100 MHz microcontroller, and a client may have
  // other work meanwhile (its link). fn must not call this decoder. nullptr
  // or 0 turns it off (the default).
  void set_progress(void (*fn)(void* user), void* user, uint32_t every_items) {
    progress_ = every_items != 0 ? fn : nullptr;
    progress_user_ = user;
    progress_every_ = every_items;
    progress_count_ = 0;
  }

 private:
  Status fail(Status s) {
    if (status_ == Status::ok) status_ = s;
    return status_;
  }
  Status on_header(const uint8_t* p, uint32_t size);
  Status on_base(const uint8_t* p, uint32_t size);
  Status on_level(const uint8_t* p, uint32_t size);
  Status on_tail(const uint8_t* p, uint32_t size);
  // Before the tail: capacity_reached() if this client cannot hold it.
  void check_tail_fits();
  Status tail_items(const uint8_t* conn, uint32_t conn_size, const uint8_t* geom, uint32_t geom_size,
                    uint32_t first, uint32_t count);
  void progress_tick() {
    if (progress_ != nullptr && ++progress_count_ >= progress_every_) {
      progress_count_ = 0;
      progress_(progress_user_);
    }
  }
  Status base_items(const uint8_t* data, uint32_t size, uint32_t first, uint32_t count);
  Status level_items(const uint8_t* conn, uint32_t conn_size, const uint8_t* geom, uint32_t geom_size,
                     uint32_t first, uint32_t count);
  Status read_table(BitReader& br, HuffmanTable& table, uint32_t alphabet_max);
  Status decode_split_arith(ArithDecoder& ad, uint32_t u, SplitChoice* ch);
  Status decode_split_huffman(BitReader& br, uint32_t u, SplitChoice* ch);
  Status decode_position_arith(ArithDecoder& ad, uint32_t v);
  Status decode_position_huffman(BitReader& br, uint32_t v);
  void start_level();

  Arena* arena_ = nullptr;
  MeshState mesh_;
  MeshContexts* ctx_ = nullptr;
  TailContexts* tctx_ = nullptr;  // carved when the tail starts
  MeshTail tail_;
  bool in_tail_ = false;
  uint8_t* marks_ = nullptr;    // one bit per vertex: split vertices of the current level
  uint8_t* lengths_ = nullptr;  // code lengths while a Huffman table is read
  HuffmanTable huff_delta_, huff_shape_, huff_pos_, huff_geo_;
  uint32_t cap_v_ = 0, cap_t_ = 0;
  MeshHeader header_{};
  Status status_ = Status::invalid_argument;
  bool have_header_ = false;
  bool base_done_ = false;
  bool full_ = false;
  uint32_t base_items_ = 0;  // base items decoded
  uint32_t base_next_ = 0;   // next base vertex a triangle may introduce
  uint32_t levels_done_ = 0;
  // The level being decoded.
  bool in_level_ = false;
  uint32_t items_ = 0;        // items decoded in this level
  uint32_t pass_a_ = 0;       // items of pass A (split flags or index deltas)
  uint32_t dv_ = 0, dt_ = 0;  // declared vertices and triangles added
  uint32_t old_v_ = 0, old_t_ = 0;
  uint32_t marked_ = 0;       // split vertices found in pass A
  uint32_t last_mark_ = 0;    // Huffman: previous split vertex index
  uint32_t cursor_ = 0;       // pass B: next vertex to test for a split flag
  int weight_q4_ = 0;
  MeshLevelInfo last_{};
  MeshLevelInfo cur_{};
  void (*progress_)(void*) = nullptr;
  void* progress_user_ = nullptr;
  uint32_t progress_every_ = 0;
  uint32_t progress_count_ = 0;
};

}  // namespace vds
