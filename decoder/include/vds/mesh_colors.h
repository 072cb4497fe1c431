// vds client library: mesh colors — colour stored on the mesh itself, no UV
// map (Yuksel, Keyser and House, "Mesh colors", 2010) — and their codec,
// the mesh colors codec of Taskin ("Compression of surface data on dynamic
// topologies", 2020), shared bit for bit by the client and the host encoder
// (vds/enc/mesh_colors.h). Integer only; every buffer from the caller's
// arena. docs/model-mode.md has the representation and the codec in full.
//
// Representation. Face f has a resolution R = 2^r (r = 0..kMaxResLog2).
// Its samples sit on the lattice points (i, j) with i, j >= 0, i + j <= R,
// at barycentric weights ((R - i - j) / R, i / R, j / R) on its corners
// (a, b, c) = triangle f's three vertices in order:
//   (0, 0), (R, 0), (0, R)          the vertex samples of a, b, c (one per vertex);
//   j = 0, 0 < i < R                edge 0 (a -> b), i steps from a;
//   i + j = R, 0 < j < R            edge 1 (b -> c), j steps from b;
//   i = 0, 0 < j < R                edge 2 (c -> a), R - j steps from c;
//   the rest                        the face's own (R - 1)(R - 2) / 2 samples.
// An edge's resolution is the largest of its faces' (so every face finds its
// lattice points on it, every 2^(edge r - face r)-th sample); it holds R - 1
// samples, numbered from the end it starts at. Edges are numbered by first
// appearance, faces in order and corners in order (edge k of a face runs
// from corner k to corner k + 1), and run in the direction of the face they
// first appear in. MIP level m halves every resolution m times (down to 1);
// the vertex samples are the same at every level. A level's samples are
// held as three planes (Y', Cb, Cr; JFIF full range), each laid out as:
// every vertex, then every edge's samples, then every face's, face f's rows
// j = 1 .. R - 2 one after another, row j holding i = 1 .. R - 1 - j.
//
// The codec (paper mode; Taskin chapter 2). Per MIP level, every edge then
// every face:
//  - edges: samples in blocks of 8 from the edge's start (the last one
//    shorter), each block's three components transformed by the modified
//    DCT-II of its length — X_0 the mean, X_k = sum x_n cos(pi/N (n + 1/2) k);
//  - faces: the face's samples as a triangle of side n = R - 2 (row j - 1,
//    column i - 1), cut into 8x8 blocks from corner a; a block at block row
//    p, column q holds the positions with row + column < D = n - 8 (p + q)
//    (D >= 1; blocks by the hypotenuse miss whole anti-diagonals). Row
//    transforms first (along a -> b, each row its own length), then column
//    transforms over the row coefficients of the same index (along a -> c);
//  - quantisation: JPEG's tables (ITU-T T.81 K.1, K.2) times the quality
//    factor; edges use the first eight steps in zig-zag order times 0.1;
//    steps are kept in 1/16 (Q4) so client and encoder agree exactly;
//  - DC prediction, on quantised DCs: an edge's first block from its start
//    vertex's sample, the others from the block before; a face's first
//    block from the mean of the reconstructed first blocks of its two
//    edges at corner a, the first block of each later block row from the
//    one above, the others from the block to their left;
//  - AC: in zig-zag order (blocks by the hypotenuse end early), as
//    (run of zeros <= 255, amplitude) pairs that may span blocks; a pair
//    with amplitude 0 stands for `run` zeros only;
//  - entropy coding: the adaptive binary arithmetic coder (vds/arith.h) in
//    18 context sets: DC, run and amplitude of Y', Cb, Cr, for faces and for
//    edges.
// The vds mode (the default; docs/model-mode.md) keeps the layout, blocks
// and scan, and changes: orthonormal transforms (edges quantised with the
// tables' first row); each block's mean coded apart (step: the DC step / 8,
// predicted from the reconstructed mean of the block before it) and the
// block minus its reconstructed mean transformed, every position coded;
// levels as a nonzero count, significance and magnitudes in contexts
// (BlockContexts); block means as multiples of their step from 128
// (kMeanCentreQ4); vertex samples coded losslessly in the header.
// Either mode may code each level's chroma from the next level's samples
// (kFlagChromaHalf, the thesis's chroma sub-sampling): the client fills
// the rest of the level's chroma lattice between them.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/arena.h"
#include "vds/arith.h"
#include "vds/container.h"
#include "vds/mesh_model.h"
#include "vds/render.h"
#include "vds/status.h"

namespace vds::mc {

constexpr int kMaxResLog2 = 10;              // R up to 1024
constexpr uint32_t kMaxVertices = 65535;
constexpr uint32_t kMaxFaces = 131070;
constexpr int kBlock = 8;

constexpr uint32_t resolution(int r) { return 1u << r; }
constexpr uint32_t edge_samples(int r) { return r <= 0 ? 0 : resolution(r) - 1; }
constexpr uint32_t face_samples(int r) {
  return r <= 1 ? 0 : (resolution(r) - 1) * (resolution(r) - 2) / 2;
}
// Resolution exponent of an element of exponent r at MIP level m.
constexpr int level_res(int r, int m) { return r > m ? r - m : 0; }

// The mesh's edges and how its faces use them.
struct Topology {
  uint32_t vertices = 0;
  uint32_t faces = 0;
  uint32_t edges = 0;
  const uint16_t* tri = nullptr;   // 3 per face, the caller's
  uint32_t* face_edge = nullptr;   // 3 per face: edge id << 1, | 1 if the edge runs corner k+1 -> k
  uint16_t* edge_vertex = nullptr; // 2 per edge: where it starts, where it ends
};

// Builds the topology of `faces` triangles over `vertices` vertices (the
// triangle array is kept, not copied). Carves 3 faces x 4 bytes, at most 3
// faces x 4 bytes of edges and a hash of scratch it gives back.
// invalid_argument for counts over the limits, an index out of range or a
// face with a repeated vertex; workspace_too_small.
Status build_topology(Arena& arena, const uint16_t* tri, uint32_t faces, uint32_t vertices, Topology* out);
// Bytes build_topology needs at most (scratch included).
size_t topology_bytes(uint32_t faces);

// Every vertex's neighbours (vertices sharing an edge), compressed rows.
struct Adjacency {
  uint32_t vertices = 0;
  uint32_t* offset = nullptr;  // vertices + 1
  uint16_t* next = nullptr;    // 2 per edge
};
Status build_adjacency(Arena& arena, const Topology& t, Adjacency* out);
size_t adjacency_bytes(uint32_t vertices, uint32_t edges);
// The vds mode's prediction of vertex v's component c from the vertices
// before it: the rounded mean of its neighbours below v, else vertex v - 1's
// sample, else 128.
int32_t vertex_prediction(const Adjacency& adj, const uint8_t* ycc, uint32_t v, int c);
struct VertexContexts {
  static constexpr int kMagCtx = 8;
  ArithContext zero[2];
  ArithContext mag[2][kMagCtx];
  void reset();
};

// Y', Cb, Cr planes of one level (layout above).
struct Planes {
  uint8_t* y = nullptr;
  uint8_t* cb = nullptr;
  uint8_t* cr = nullptr;
  uint8_t* plane(int c) const { return c == 0 ? y : (c == 1 ? cb : cr); }
};

// Where a level's samples lie in its planes.
struct Layout {
  uint32_t edge_base = 0;            // = vertices
  uint32_t face_base = 0;            // edge_base + every edge's samples
  uint32_t total = 0;                // face_base + every face's samples
  uint32_t* edge_offset = nullptr;   // edges + 1, from 0
  uint32_t* face_offset = nullptr;   // faces + 1, from 0
};

// The quantiser steps in 1/16 of a level (Q4) for quality factor q8/256:
// faces the JPEG tables; edges the tables' first eight steps in zig-zag
// order x 0.1 (paper mode) or their first row (vds mode).
struct Steps {
  uint32_t face[2][64];  // luma, chroma; natural order 8 * row + column (row: the a -> c frequency)
  uint32_t edge[2][8];
};
void make_steps(uint16_t quality_q8, uint8_t mode, Steps* out);

// The modified inverse DCT of length n (1..8): in[0] the mean, in[k] the
// coefficients (Q4, any int32); out[i] the samples, Q4, each within
// +-2^24. Shared with the encoder's tests.
void inverse_dct(const int32_t* in, int n, int32_t* out, int in_stride = 1, int out_stride = 1);

// --- Block reconstruction, shared with the encoder -------------------------
// An edge block of `len` samples from its quantised values (paper mode:
// q[0] the DC, q[1..] the AC; vds mode: every coefficient of the block's
// residual from its mean), the level's steps, the mode and the block's
// reconstructed mean (vds mode; 0 for the paper's), into dst[0],
// dst[stride], ... dst[(len - 1) stride].
void reconstruct_edge_block(const int32_t* q, int len, const uint32_t* step, uint8_t mode, int64_t mean_q4,
                            uint8_t* dst, int stride = 1);
// A face block of diagonal D at block row br, column bc of a face of side n
// whose samples start at `face`, from its quantised values (natural order,
// 8 * row + column; as for edges); returns the block's reconstructed mean
// (of its samples, Q4). With scale 2 the face's lattice is the one of
// twice its resolution (side 2 (n + 2) - 2) and the block's samples go to
// their lattice points there (i, j) -> (2 i, 2 j): chroma on the next
// level's lattice (kFlagChromaHalf).
int64_t reconstruct_face_block(const int32_t* q, int32_t D, const uint32_t* step, uint8_t mode, int64_t mean_q4,
                               uint8_t* face, int32_t n, int32_t br, int32_t bc, int scale = 1);
// Positions of a face block of diagonal D (row + column < D, in 8 x 8).
int face_block_positions(int32_t D);
// The vds mode's step of a block's mean (Q4): the DC step / 8, so a full
// block's mean is quantised as JPEG quantises its DC.
uint32_t mean_step(uint32_t step0);
// The vds mode codes a block's mean as a multiple of its step from 128
// (Q4 here), as JPEG shifts samples by 128 before its DCT: neutral grey
// and neutral chroma are then exact at any step (from 0 they would land on
// the nearest multiple of a coarse step, a tint over every white surface).
constexpr int64_t kMeanCentreQ4 = 128 * 16;
// The mean of `count` samples samples[0], samples[stride], ... in Q4,
// rounded (0 for none).
int64_t mean_q4(const uint8_t* samples, uint32_t count, int stride = 1);
// a / b rounded to nearest, halves away from zero (b > 0).
int64_t div_round(int64_t a, int64_t b);

// Context sets: [component][0 face, 1 edge].
struct CodecContexts {
  static constexpr int kDcCtx = 8;
  static constexpr int kRunCtx = 12;
  static constexpr int kAmpCtx = 8;
  ArithContext dc_zero[3][2];
  ArithContext dc_mag[3][2][kDcCtx];
  ArithContext run[3][2][kRunCtx];
  ArithContext amp_zero[3][2];
  ArithContext amp_mag[3][2][kAmpCtx];
  void reset();
};
// Binarisation parameters (decode_ueg / decode_signed), shared with the encoder.
constexpr uint32_t kDcCutoff = 8, kRunCutoff = 12, kAmpCutoff = 8;
constexpr int kDcOrder = 0, kRunOrder = 2, kAmpOrder = 0;
constexpr uint32_t kMaxRun = 255;
constexpr int32_t kMaxQuantised = 1 << 20;

// The vds mode's block contexts: [class: 0 luma, 1 chroma][0 face, 1 edge].
struct BlockContexts {
  static constexpr int kDcCtx = 8;
  static constexpr int kNzCtx = 6;
  ArithContext dc_zero[2][2];
  ArithContext dc_mag[2][2][kDcCtx];
  ArithContext nz[2][2][9][kNzCtx];  // by the previous block's count (image_model::kNzBucketOf)
  ArithContext sig[2][2][22][9];     // by scan position and levels left (image_model::kSigPosOf, kSigLeftOf)
  ArithContext gt1[2][2][5][5];      // by image_model::kLevelPosOf, kLevelLeftOf
  ArithContext gt2[2][2][5][5];
  void reset();
};
constexpr uint32_t kNzCutoff = 6;
constexpr int kNzOrder = 1;

// --- The header chunk (MCLH) ------------------------------------------------
//   u8 version (1), u8 mode (0 = paper, 1 = vds), u8 max_res_log2 (0..10),
//   u8 flags (kFlagVertexColours | kFlagChromaHalf | kFlagVertexStep),
//   u16 quality factor x 256 (>= 1), u16 vertices, u32 faces,
//   with kFlagVertexStep: u8 the vertex samples' step (2..kMaxVertexStep);
//   paper mode, unless kFlagVertexColours: vertices x 3 bytes, every vertex's Y', Cb, Cr;
//   arithmetic coded: the faces' resolution exponents, face f's as a
//   truncated unary code (max max_res_log2) in the contexts of face f - 1's;
//   vds mode, unless kFlagVertexColours: then every vertex's Y', Cb, Cr as
//   signed differences from vertex_prediction (vertices in order), in
//   multiples of the step (1 without kFlagVertexStep).
constexpr uint32_t kChunkVertices = fourcc('M', 'C', 'V', 'X');  // after the base and each split level
constexpr uint32_t kChunkHeader = fourcc('M', 'C', 'L', 'H');  // after the mesh's last level
constexpr uint32_t kChunkLevel = fourcc('M', 'C', 'L', 'V');   // one MIP level, coarsest first
constexpr uint8_t kVersion = 1;
// MCLH flags: the vertex samples are the colours that came with the
// vertices (MCVX, the last one after the single-rate tail), not in MCLH.
constexpr uint8_t kFlagVertexColours = 1;
// MCLH flags: each level's chroma (Cb, Cr) is coded on the next level's
// lattice (its samples are that level's), and the client fills the rest of
// the level's lattice from them: a point between two of them (along an
// edge of the lattice; vertex samples count) is their mean, rounded up
// (Taskin section 2.3: chroma from MIP level 1). Per element the level's
// luma blocks come first, then the chroma blocks (Cb, Cr each block).
constexpr uint8_t kFlagChromaHalf = 2;
// MCLH flags (vds mode, its own vertex samples only): the vertex samples'
// differences from their predictions are multiples of a step, a u8 after
// the fixed bytes: the samples are lossy, as the blocks' means are.
constexpr uint8_t kFlagVertexStep = 4;
constexpr int kMaxVertexStep = 64;
// The components of each element of a level in MCLV order, group by group:
// components [first, end) on the lattice `shift` levels coarser.
struct ComponentGroup {
  int first, end, shift;
};
constexpr ComponentGroup kComponentsTogether[1] = {{0, 3, 0}};     // Y', Cb, Cr each block
constexpr ComponentGroup kChromaFromNextLevel[2] = {{0, 1, 0}, {1, 3, 1}};  // kFlagChromaHalf
// The groups of a level with or without kFlagChromaHalf in *out; returns their count.
inline int component_groups(bool chroma_half, const ComponentGroup** out) {
  *out = chroma_half ? kChromaFromNextLevel : kComponentsTogether;
  return chroma_half ? 2 : 1;
}
constexpr uint8_t kModePaper = 0;
constexpr uint8_t kModeVds = 1;
constexpr size_t kHeaderFixedBytes = 12;

// --- Vertex colours with their vertices (MCVX) --------------------------------
// After the base mesh and after each split level, the colours of the
// vertices it added, so that a coarse mesh is drawn in its colours before
// the faces' samples arrive (its vertices are the final mesh's, at their
// final positions); after the single-rate tail, which numbers the vertices
// anew, the colours of every vertex again (first 0):
//   u32 first vertex (the vertices coloured so far), u32 count (those the
//   mesh has beyond them), then arithmetic coded, vertices in order, Y', Cb,
//   Cr each as a signed difference from fan_prediction (VertexContexts).
constexpr size_t kVertexChunkHeadBytes = 8;
// Vertex v's prediction from its neighbours in `mesh` numbered below it
// (their values in `plane`): the rounded mean, else vertex v - 1's value,
// else 128. The fan is walked in the corner table (at most 1023 faces).
int32_t fan_prediction(const MeshState& mesh, const uint8_t* plane, uint32_t v);
// Decodes an MCVX payload into the planes (vertex v's Y', Cb, Cr at
// y[v], cb[v], cr[v]); `first` must be the vertices coloured so far and the
// chunk must colour exactly the mesh's vertices beyond them (malformed
// otherwise; truncated if it ends early). `coloured` is updated.
Status decode_vertex_colours(const uint8_t* data, size_t size, const MeshState& mesh, const Planes& out,
                             uint32_t* coloured);

// --- A level's chunks (MCLV) -------------------------------------------------
//   u8 level (0 .. max_res_log2 - 1), u32 first element, u32 elements
//   (elements: the edges 0 .. E - 1, then the faces as E + f), then the
//   arithmetic-coded data of those elements (per block Y', Cb, Cr, each its
//   DC then its AC; with kFlagChromaHalf per element its Y' blocks, then
//   its Cb, Cr blocks on the next level's lattice), every context starting
//   afresh. A level's chunks come
//   in order and cover its elements, so each fits a client's chunk buffer.
constexpr size_t kLevelHeadBytes = 9;
struct LevelChunk {
  int level = 0;
  uint32_t first = 0, count = 0;
};
// The fixed fields of an MCLV payload; truncated if it is shorter.
Status level_chunk_info(const uint8_t* data, size_t size, LevelChunk* out);

// A client's (or the encoder's) mesh colors: topology, resolutions, vertex
// samples, and the decoding of levels into caller planes.
class MeshColors {
 public:
  // Sets up for the mesh (build_topology) and carves the per-face and
  // per-edge resolutions, the vertex samples and one level's layout.
  Status init(Arena& arena, const uint16_t* tri, uint32_t faces, uint32_t vertices);
  // Bytes init() carves at most.
  static size_t init_bytes(uint32_t faces, uint32_t vertices);

  // The MCLH payload. malformed for a version, mode, count or value this
  // mesh or this decoder cannot take (unsupported_version for a newer
  // version). With kFlagVertexColours set the vertex samples are
  // `vertex_colours` (the planes the MCVX chunks filled; malformed without).
  Status read_header(const uint8_t* data, size_t size, const Planes* vertex_colours = nullptr);
  // What read_header sets, from the encoder's side: every face's resolution
  // exponent (0..kMaxResLog2), the vertex samples (3 per vertex; null
  // leaves them) and the quality factor. invalid_argument for a value out
  // of range or before init.
  Status set(const uint8_t* face_res, const uint8_t* vertex_ycc, uint16_t quality_q8, uint8_t mode = kModePaper,
             bool chroma_half = false);

  // Sets `layout` (arrays from init) for level m; returns its total samples.
  uint32_t layout_level(int m);
  const Layout& layout() const { return layout_; }

  // An MCLV payload of level m (its first byte says which) into `out`, each
  // plane at least layout_level(m) samples: a level's first chunk sets the
  // layout and writes the vertex samples, each chunk its elements' edge and
  // face samples. malformed for data no encoder writes or a chunk that does
  // not follow the last one decoded, truncated for data that ends early.
  Status decode_level(const uint8_t* data, size_t size, const Planes& out);
  // Whether the last chunk decoded completed its level, and which level that is.
  bool level_complete() const { return decoding_ >= 0 && next_element_ == topo_.edges + topo_.faces; }
  int decoding_level() const { return decoding_; }

  const Topology& topology() const { return topo_; }
  int max_res_log2() const { return max_res_; }
  uint16_t quality_q8() const { return quality_q8_; }
  uint8_t mode() const { return mode_; }
  const uint8_t* face_res() const { return face_res_; }
  const uint8_t* edge_res() const { return edge_res_; }
  const uint8_t* vertex_samples() const { return vertex_ycc_; }  // 3 per vertex
  bool has_header() const { return header_; }
  // The level-m sample of face f at lattice point (i, j) (i + j <= R_m) in a
  // level's planes: its index.
  uint32_t sample_index(uint32_t f, int m, uint32_t i, uint32_t j) const;
  // Where face f's samples lie in the planes of the level layout_level()
  // last set, as the renderer samples them (Shading::mesh_colors).
  void face_lattice(uint32_t f, LatticeFace* out) const;
  int layout_level_shown() const { return layout_m_; }
  // The first block's DC prediction of face f at level m, before halving:
  // the sum of the Q4 means of the reconstructed blocks of its edges 0 and 2
  // at corner a, in `plane` (a level's plane with those edges decoded; the
  // layout of level m set). With scale 2, of the blocks of level m + 1's
  // samples, read where they lie in level m's plane (kFlagChromaHalf).
  int64_t corner_sum_q4(uint32_t f, int m, const uint8_t* plane, int scale = 1) const;
  // kFlagChromaHalf: the points of edge e's (face f's) level-m lattice that
  // level m + 1 does not have, in plane `p` of level m (layout set), from
  // those it has (and the vertex samples; a face's from its edges' too).
  void fill_edge(uint32_t e, int m, uint8_t* p) const;
  void fill_face(uint32_t f, int m, uint8_t* p) const;

 private:
  Arena* arena_ = nullptr;  // for read_header's scratch
  Topology topo_{};
  Layout layout_{};
  int layout_m_ = -1;
  uint8_t* face_res_ = nullptr;
  uint8_t* edge_res_ = nullptr;
  uint8_t* vertex_ycc_ = nullptr;
  CodecContexts* ctx_ = nullptr;
  BlockContexts* bctx_ = nullptr;
  Steps* steps_ = nullptr;
  int max_res_ = 0;
  uint16_t quality_q8_ = 0;
  uint8_t mode_ = kModePaper;
  bool chroma_half_ = false;
  bool header_ = false;
  int decoding_ = -1;           // the level the last chunk decoded belongs to
  uint32_t next_element_ = 0;   // where its next chunk starts
};

}  // namespace vds::mc
