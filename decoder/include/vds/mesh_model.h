// vds client library: the progressive mesh's model, shared bit for bit by
// the client decoder (mesh_decoder.cpp, mesh_state.cpp, mesh_tail.cpp) and
// the host encoder (encoder/src/mesh_encoder.cpp), which runs the same code
// to reconstruct exactly what the client sees: the mesh and its operations
// (MeshState: ring walk, vertex split, predictors, split ranking), the
// single-rate tail's traversal, and the context modelling. Not an
// application interface: applications use vds/mesh.h (or vds/player.h).
//
// Everything lives in the caller's workspace: positions are integers on the
// stream's quantisation grid (0 .. 2^bits - 1 per axis), the connectivity a
// corner table (Rossignac's "Corner Table", 2001): three vertex indices and
// three opposite corners per triangle. After each complete level the arrays
// hold a valid mesh the renderer can draw.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/arena.h"
#include "vds/arith.h"
#include "vds/bitreader.h"
#include "vds/config.h"
#include "vds/huffman.h"
#include "vds/status.h"

namespace vds {

// Largest vertex degree (ring size) the decoder handles; the stream's
// MSHH declares its own maximum and is refused above this.
constexpr uint32_t kMeshMaxDegree = VDS_CONFIG_MESH_MAX_DEGREE;
constexpr uint32_t kMeshNone = 0xFFFFFFFFu;
// Face elongation score offset, Q4 log2 units: 26/16 = 1.625, a squared
// length ratio of about 3.1, between a well-shaped face (sides at the apex
// against the base 2 : 1, log2 = 1) and one whose apex moved by about an
// edge length (about 5 : 1, log2 = 2.3).
constexpr int32_t kMeshElongationBias = 26;
// Q4 log2 of x (16 per octave, linear between powers of two); 0 for 0.
int32_t mesh_log2_q4(uint64_t x);

enum class MeshPredictor : uint8_t {
  laplacian = 0,      // the paper's eq. 13: w = 1/m Σ (u_j + L(u_j))
  parallelogram = 1,  // ring centroid moved toward the mean parallelogram prediction by a per-level weight
  area = 2,           // the same with the ring's area centroid in place of its vertex centroid
};

// LEB128 unsigned varints as used in the mesh chunk headers (at most 5
// bytes; overlong or > 32-bit encodings are malformed).
Status read_varint(const uint8_t*& p, const uint8_t* end, uint32_t* out);

// How a vertex split divides the split vertex u's fan (docs/mesh-codec.md,
// "Vertex splits on the client"). The ring r_0..r_{d-1} of u runs counter-clockwise from
// the corner MeshState keeps for u; for a boundary vertex it is the path
// from one boundary neighbour to the other and has d - 1 faces. Faces
// first .. first + count - 1 (modulo d for an interior u) move to the new
// vertex v.
enum class SplitKind : uint8_t {
  interior = 0,  // v interior: wings F = r_first, L = r_{first+count}; two new faces
  tail = 1,      // v on the boundary after u (boundary u only): F = r_first, count = d - 1 - first; one new face
  head = 2,      // v on the boundary before u (boundary u only): first = 0, L = r_count; one new face
};
struct SplitChoice {
  SplitKind kind = SplitKind::interior;
  uint32_t first = 0;
  uint32_t count = 0;
};

// An index table in the caller's arena, in 16-bit entries when every index
// it will hold is below `limit` <= 0xFFFF (half the bytes: what lets a small
// client hold more of a model), in 32-bit entries otherwise. kMeshNone (and
// so an int32 -1) is stored as 0xFFFF in 16 bits.
class IndexTable {
 public:
  static bool narrow_for(uint64_t limit) { return limit <= 0xFFFFu; }
  // Bytes init() carves for n entries below `limit`, alignment included.
  static uint64_t workspace_bytes(uint64_t n, uint64_t limit) {
    return n * (narrow_for(limit) ? sizeof(uint16_t) : sizeof(uint32_t)) + alignof(uint32_t);
  }
  // false if the arena cannot hold it.
  bool init(Arena& arena, uint32_t n, uint64_t limit) {
    n16_ = nullptr;
    n32_ = nullptr;
    if (narrow_for(limit)) n16_ = arena.alloc_array<uint16_t>(n);
    else n32_ = arena.alloc_array<uint32_t>(n);
    return n == 0 || n16_ != nullptr || n32_ != nullptr;
  }
  uint32_t get(uint32_t i) const {
    if (n16_ == nullptr) return n32_[i];
    const uint32_t x = n16_[i];
    return x == 0xFFFFu ? kMeshNone : x;
  }
  void set(uint32_t i, uint32_t value) {
    if (n16_ != nullptr) n16_[i] = static_cast<uint16_t>(value);
    else n32_[i] = value;
  }
  // The 16-bit entries, or nullptr when the table is 32-bit; the 32-bit
  // entries, or nullptr when it is 16-bit.
  const uint16_t* narrow() const { return n16_; }
  const uint32_t* wide() const { return n32_; }

 private:
  uint16_t* n16_ = nullptr;
  uint32_t* n32_ = nullptr;
};

// The ring of a vertex as MeshState::ring() returns it.
struct Ring {
  uint32_t degree = 0;     // ring vertices
  bool boundary = false;
  uint32_t* vertex = nullptr;  // r_0 .. r_{degree-1}
  uint32_t* corner = nullptr;  // corner of the vertex in face j (degree faces, degree - 1 on the boundary)
  uint32_t faces() const { return boundary ? degree - 1 : degree; }
};

class MeshState {
 public:
  // Workspace for a mesh of up to max_vertices / max_triangles, alignment included.
  static size_t workspace_bytes(uint32_t max_vertices, uint32_t max_triangles);

  Status init(Arena& arena, uint32_t max_vertices, uint32_t max_triangles);
  // Forgets the mesh (keeps the storage).
  void clear(int bits);

  // --- Building the base mesh -------------------------------------------------
  Status add_vertex(const int32_t p[3]);
  Status add_triangle(uint32_t a, uint32_t b, uint32_t c);
  // Builds the opposite corners and checks the base is an oriented manifold
  // (each edge in one face, or in two in opposite directions; one fan per
  // vertex; degrees within max_degree): malformed otherwise. Uses scratch
  // from `arena` (4 bytes per corner) and gives it back.
  Status finish_base(Arena& arena, uint32_t max_degree);

  // --- Queries ------------------------------------------------------------------
  uint32_t vertex_count() const { return nv_; }
  uint32_t triangle_count() const { return nt_; }
  int bits() const { return bits_; }
  const uint16_t* positions() const { return pos_; }  // x, y, z per vertex
  // The corner table: corner c is corner c % 3 of triangle c / 3; its
  // vertex, and its opposite corner (-1 across a boundary edge).
  uint32_t corner_vertex(uint32_t c) const { return corner_vertex_.get(c); }
  int32_t opposite(uint32_t c) const { return static_cast<int32_t>(opposite_.get(c)); }
  // Three vertex indices per triangle in 16 bits, what the renderer takes;
  // nullptr if init() was given more than 65,535 vertices (32-bit table).
  const uint16_t* triangles16() const { return corner_vertex_.narrow(); }
  uint32_t vertex_corner(uint32_t v) const { return vertex_corner_.get(v); }
  // The corners after and before c in its triangle (counter-clockwise).
  static uint32_t next(uint32_t c) { return c % 3 == 2 ? c - 2 : c + 1; }
  static uint32_t prev(uint32_t c) { return c % 3 == 0 ? c + 2 : c - 1; }
  void position(uint32_t v, int32_t out[3]) const {
    out[0] = pos_[3 * v];
    out[1] = pos_[3 * v + 1];
    out[2] = pos_[3 * v + 2];
  }
  // Sets a position; invalid_argument outside 0 .. 2^bits - 1.
  Status set_position(uint32_t v, const int32_t p[3]);

  // Ring of x into the state's scratch A (valid until the next ring() into
  // the same scratch). malformed if the walk exceeds max_degree.
  Status ring(uint32_t x, Ring* out, int scratch = 0);

  // --- Vertex split ---------------------------------------------------------------
  // Checks the choice against u's ring (malformed if impossible) and splits:
  // the new vertex gets index vertex_count() (position 0 until set), new
  // faces are appended (A = (v, L, u) then B = (v, u, F)).
  Status split(uint32_t u, const SplitChoice& choice, uint32_t* new_vertex);
  // The number of valid choices of each kind for a ring (for range checks).
  static bool choice_valid(const Ring& r, const SplitChoice& c);

  // --- Prediction -----------------------------------------------------------------
  // Predicted position of v from its ring (all ring positions known, v's
  // own ignored). `weight_q4` is the parallelogram weight (0..16 sixteenths).
  Status predict(uint32_t v, MeshPredictor predictor, int weight_q4, int32_t out[3]);

  // Split ranking on this mesh (mesh_candidate_scores).
  uint32_t candidate_scores(const Ring& r, uint32_t u, SplitKind kind, uint32_t count, int64_t* score) const;
  // Face elongation scores of u's fan (mesh_face_llr).
  void face_llr(const Ring& r, uint32_t u, int32_t* llr) const;

  uint32_t max_degree() const { return max_degree_; }
  // The area predictor's base point (docs/mesh-codec.md); s = sum of the ring.
  bool area_centroid_q8(const Ring& r, const int64_t s[3], int64_t out[3]) const;
  // Largest ring seen by ring() since clear() (the encoder declares it).
  uint32_t max_degree_seen() const { return max_degree_seen_; }

 private:
  friend class MeshTail;
  // ring()'s walk for tables of the given entry types (mesh_state.cpp).
  template <typename VertexIndex, typename CornerIndex>
  static uint32_t walk_ring(const VertexIndex* cv, const CornerIndex* opp, uint32_t x, uint32_t c0,
                            uint32_t max_degree, uint32_t* rv, uint32_t* rc, bool* boundary);
  void fix_vertex_corner(uint32_t x, uint32_t any_corner);
  void set_opp(uint32_t c, int32_t o) { opposite_.set(c, static_cast<uint32_t>(o)); }
  void link(int32_t a, int32_t b) {
    if (a >= 0) set_opp(static_cast<uint32_t>(a), b);
    if (b >= 0) set_opp(static_cast<uint32_t>(b), a);
  }

  // The tables are 16-bit when the capacity allows (IndexTable): vertex
  // indices below 65,535 for corner_vertex_, corner indices below 65,535
  // (21,845 triangles) for vertex_corner_ and opposite_.
  uint16_t* pos_ = nullptr;
  IndexTable vertex_corner_;
  IndexTable corner_vertex_;
  IndexTable opposite_;
  uint32_t cap_v_ = 0, cap_t_ = 0;
  uint32_t nv_ = 0, nt_ = 0;
  int bits_ = 0;
  uint32_t max_degree_ = kMeshMaxDegree;
  uint32_t max_degree_seen_ = 0;
  // Two ring scratches of kMeshMaxDegree + 1 entries (the Laplacian
  // predictor walks the rings of ring vertices).
  uint32_t* ring_vertex_[2] = {nullptr, nullptr};
  uint32_t* ring_corner_[2] = {nullptr, nullptr};
};

// --- Single-rate tail (docs/mesh-codec.md, "The single-rate tail") -------------
//
// The last level of a version-2 stream is not a set of vertex splits but
// the whole mesh again, coded single-rate: an Edgebreaker traversal
// (Rossignac 1999) builds the corner table one triangle at a time, then the
// positions follow in the order the traversal created the vertices, each
// predicted from the parallelograms across its already decoded neighbours.
// Holes are closed for the traversal by one dummy vertex each, fanned to the
// hole's border; dummy vertices and triangles live above the real ones
// (indices vertices .. and triangles ..) and are dropped once the
// connectivity is complete, so the real ones end up contiguous.
//
// Each triangle after the first of a component is attached to the current
// gate, a border edge of what is built so far, and says where its third
// vertex (the tip) is: a new vertex (C), the border vertex before the gate
// (L), the one after it (R), both (E: the border loop closes), or another
// vertex of the border loop, given as a direction and a count of border
// edges (S: the loop splits in two, one half waits on a stack), or a
// vertex of a loop waiting on the stack, given as its depth there and a
// count of border edges (M: a handle; the two loops merge into one).
struct TailCounts {
  uint32_t vertices = 0, triangles = 0;              // real, = MSHH's
  uint32_t dummy_vertices = 0, dummy_triangles = 0;  // closing the holes
  uint32_t max_border = 0;                           // most border edges at once, every loop counted
};
enum class TailSymbol : uint8_t { C = 0, L = 1, R = 2, E = 3, S = 4, M = 5 };

// Arithmetic-coder contexts of the tail, one flat array (as MeshContexts;
// carved and reset when the tail starts). Groups:
//   left      the tip is the border vertex before the gate: by both gate fans
//   right     ... after the gate: by the fan after it and whether `left` held
//   fresh     neither: a new vertex (C) rather than a split (S), by the fans' sum
//   dummy     a new vertex is a dummy: seed vertices, C vertices
//   direction, offset   where an S vertex lies on the border
//   merge, depth        the tip lies on a waiting loop (M), and which
//   geo_zero, geo_mag   position corrections by axis and prediction context
struct TailContexts {
  static constexpr uint32_t kFanClasses = 9;  // conquered triangles around a gate vertex, 0..8+
  static constexpr uint32_t kOffsetBins = 12;
  static constexpr uint32_t kGeoScales = 6;  // log2 classes 0..5 (mesh_tail_log_class)
  // Position contexts: no parallelogram; one, by the length of its edge;
  // two or more, by how far apart they land (mesh_tail_predict).
  static constexpr uint32_t kGeoClasses = 1 + 2 * kGeoScales;
  static constexpr uint32_t kGeoBins = 12;
  static constexpr uint32_t kLeft = 0;
  static constexpr uint32_t kRight = kLeft + kFanClasses * kFanClasses;
  static constexpr uint32_t kFresh = kRight + kFanClasses * 2;
  static constexpr uint32_t kDummy = kFresh + kFanClasses;
  static constexpr uint32_t kDirection = kDummy + 2;
  static constexpr uint32_t kOffset = kDirection + 1;
  static constexpr uint32_t kMerge = kOffset + kOffsetBins;
  static constexpr uint32_t kDepth = kMerge + 1;
  static constexpr uint32_t kGeoZero = kDepth + kOffsetBins;
  static constexpr uint32_t kGeoMag = kGeoZero + 3 * kGeoClasses;
  static constexpr uint32_t kCount = kGeoMag + 3 * kGeoClasses * kGeoBins;

  static constexpr uint32_t left(uint32_t fx, uint32_t fy) { return kLeft + fx * kFanClasses + fy; }
  static constexpr uint32_t right(uint32_t fy, bool l) { return kRight + fy * 2 + (l ? 1 : 0); }
  static constexpr uint32_t fresh(uint32_t fx, uint32_t fy) {
    return kFresh + (fx + fy < kFanClasses - 1 ? fx + fy : kFanClasses - 1);
  }
  static constexpr uint32_t geo_zero(uint32_t axis, uint32_t cls) { return kGeoZero + axis * kGeoClasses + cls; }
  static constexpr uint32_t geo_mag(uint32_t axis, uint32_t cls) {
    return kGeoMag + (axis * kGeoClasses + cls) * kGeoBins;
  }

  ArithContext c[kCount];
  void reset();
};
constexpr uint32_t kTailOffsetCutoff = 8;
constexpr int kTailOffsetEgK = 1;
constexpr uint32_t kTailGeoCutoff = 12;
constexpr int kTailGeoEgK = 1;

// Builds the tail's connectivity into a MeshState (decoder and encoder).
// The border loops are kept as linked lists of border edges (a pool of
// max_border nodes): where loops touch, a vertex's built triangles fall
// apart into several fans, and turning around it cannot tell which loop an
// open edge belongs to.
class MeshTail {
 public:
  // Bytes begin() carves for max_border border edges, alignment included.
  static size_t workspace_bytes(uint32_t max_border) {
    return 3 * (size_t{max_border} * sizeof(uint32_t) + alignof(uint32_t));
  }
  // Forgets m's mesh and prepares to build one of n's size: malformed if
  // it would not fit m's capacity, workspace_too_small if `arena` cannot
  // hold the border. The loop stack uses m's vertex-corner table and the
  // conquered-triangle counts its position array, until finish().
  Status begin(MeshState& m, Arena& arena, const TailCounts& n);
  uint32_t total() const { return n_.triangles + n_.dummy_triangles; }
  // The next triangle starts a new component (three new vertices).
  bool needs_seed() const { return gate_ == kMeshNone; }
  // For the next attached triangle: triangles built so far around the
  // gate's first and second vertex (capped at TailContexts::kFanClasses - 1).
  uint32_t fan_before() const { return fan_x_; }
  uint32_t fan_after() const { return fan_y_; }
  Status seed(const bool dummy[3]);
  // `dummy`: the C vertex is a dummy; `backward`, `offset`: the S vertex is
  // `offset` (>= 2) border edges before the gate (backward) or after it;
  // `depth`, `offset`: the M vertex is reached `offset` (>= 1) border edges
  // after the edge waiting `depth` entries below the top of the stack.
  Status attach(TailSymbol s, bool dummy, bool backward, uint32_t offset, uint32_t depth = 0);
  // For the encoder: the waiting loops (entry 0 is the top of the stack).
  uint32_t waiting() const { return depth_; }
  uint32_t waiting_edge(uint32_t depth) const { return m_->vertex_corner_.get(depth_ - 1 - depth); }
  // The corner a border edge faces.
  uint32_t edge_corner(uint32_t e) const { return corner_[e]; }
  // After total() triangles: checks the mesh is closed, drops the dummies,
  // sets every vertex's corner; malformed if anything is left open.
  Status finish();
  // Most border edges alive at once so far (what an encoder declares).
  uint32_t border_peak() const { return peak_; }

  // For the encoder, before attach(): the gate corner, the border vertices
  // before and after it, and the border walk attach() makes for S: the
  // first border edge before (backward) or after the gate, the next one,
  // and the vertex that edge reaches going that way.
  uint32_t gate() const { return gate_ == kMeshNone ? kMeshNone : corner_[gate_]; }
  uint32_t vertex_before() const { return x_; }
  uint32_t vertex_after() const { return y_; }
  uint32_t border_first(bool backward) const { return backward ? prev_[gate_] : next_[gate_]; }
  uint32_t border_next(uint32_t e, bool backward) const { return backward ? prev_[e] : next_[e]; }
  uint32_t border_reach(uint32_t e, bool backward) const {
    return m_->corner_vertex(backward ? MeshState::next(corner_[e]) : MeshState::prev(corner_[e]));
  }
  // The triangle index the next new one gets.
  uint32_t next_triangle(bool dummy) const { return dummy ? n_.triangles + dummy_t_ : real_t_; }

 private:
  Status new_triangle(uint32_t a, uint32_t b, uint32_t c, uint32_t* t);
  Status new_vertex(bool dummy, uint32_t* v);
  uint32_t new_edge(uint32_t corner);  // kMeshNone when the pool is empty
  void free_edge(uint32_t e);
  void join(uint32_t a, uint32_t b) {  // b follows a
    next_[a] = b;
    prev_[b] = a;
  }
  void prepare();  // x_, y_ and the fan counts of the current gate
  bool push(uint32_t e);
  bool pop(uint32_t* e);

  MeshState* m_ = nullptr;
  TailCounts n_{};
  uint32_t* corner_ = nullptr;  // border edge -> the corner facing it
  uint32_t* next_ = nullptr;    // along its loop (the built side on the left)
  uint32_t* prev_ = nullptr;
  uint32_t free_ = kMeshNone, live_ = 0, peak_ = 0;
  uint32_t built_ = 0, real_v_ = 0, dummy_v_ = 0, real_t_ = 0, dummy_t_ = 0;
  uint32_t gate_ = kMeshNone;  // border edge
  uint32_t x_ = kMeshNone, y_ = kMeshNone;
  uint32_t fan_x_ = 0, fan_y_ = 0;
  uint32_t depth_ = 0;  // stack entries
};

// Predicted position of tail vertex v from its neighbours below v: the
// mean of the parallelograms across its fan's far edges whose three
// vertices are below v, else the mean of those neighbours, else vertex
// v - 1 (the grid centre for v = 0). *context is the position context
// (TailContexts::kGeoClasses). malformed if v's fan cannot be walked.
Status mesh_tail_predict(MeshState& m, uint32_t v, int32_t out[3], uint32_t* context);
// 0 for x < 2, then one class per octave up to kGeoScales - 1.
uint32_t mesh_tail_log_class(int64_t x);

// --- Split ranking (docs/mesh-codec.md, "Split ranking") ------------------------
// Smaller score = likelier. Positions are x, y, z per vertex; `r` needs only
// vertex, degree and boundary. Each candidate predicts v at the centroid of
// its ring and scores the squared offset of u from the centroid of u's new
// ring. mesh_candidate_scores: kind interior -> one score per valid `first`
// for the given count; tail -> one per `first`; head -> one per `count`.
// `common_scale` puts scores of different counts on one scale (Q4 offsets).
// Writes at most kMeshMaxDegree scores and returns how many.
uint32_t mesh_candidate_scores(const uint16_t* pos, const Ring& r, uint32_t u, SplitKind kind, uint32_t count,
                               int64_t* score, bool common_scale = false);

// --- Context modelling shared by the decoder and the encoder -------------------

// Arithmetic-coder contexts of the mesh codec, one flat array (the encoder
// records context indices and replays them); reset at MSHH. Groups:
//   mark      split flag: degree class x earlier split neighbours x edge-length ratio class
//   kind      boundary split vertex: interior / boundary new vertex, then tail / head
//   arc       arc length (faces moving to the new vertex), by degree class, one per unary bin
//   rank      rank of the true rotation among the candidates, by candidate count, per unary bin
//   edge_rank the same for tail / head splits
//   geo_zero  position correction is zero, by role (normal axis, tangent axes) x scale class
//   geo_mag   its magnitude, by role x scale class, per unary bin
//   base_*    base mesh: coordinate deltas, new-vertex flags, back references
struct MeshContexts {
  static constexpr uint32_t kMarkDegree = 7, kMarkNeighbours = 3, kMarkShape = 4;
  static constexpr uint32_t kArcDegree = 10, kArcBins = 8;
  static constexpr uint32_t kRankBins = 6, kRankClasses = 6;
  static constexpr uint32_t kGeoRoles = 2, kGeoScales = 12, kGeoMagBins = 12;
  static constexpr uint32_t kBaseMagBins = 12;

  static constexpr uint32_t kMark = 0;
  static constexpr uint32_t kKind = kMark + kMarkDegree * kMarkNeighbours * kMarkShape;
  static constexpr uint32_t kArc = kKind + 2;
  static constexpr uint32_t kRank = kArc + kArcDegree * kArcBins;
  static constexpr uint32_t kEdgeRank = kRank + kRankClasses * kRankBins;
  static constexpr uint32_t kGeoZero = kEdgeRank + kRankBins;
  static constexpr uint32_t kGeoMag = kGeoZero + kGeoRoles * kGeoScales;
  static constexpr uint32_t kBaseZero = kGeoMag + kGeoRoles * kGeoScales * kGeoMagBins;
  static constexpr uint32_t kBaseMag = kBaseZero + 3;
  static constexpr uint32_t kBaseNew = kBaseMag + 3 * kBaseMagBins;
  static constexpr uint32_t kBaseRef = kBaseNew + 3;
  static constexpr uint32_t kCount = kBaseRef + kBaseMagBins;

  static constexpr uint32_t arc(uint32_t degree_class) { return kArc + degree_class * kArcBins; }
  // Rotation rank contexts by the number of candidates n.
  static constexpr uint32_t rank(uint32_t n) {
    return kRank + (n <= 4 ? 0 : (n >= 9 ? kRankClasses - 1 : n - 4)) * kRankBins;
  }
  static constexpr uint32_t geo_zero(uint32_t role, uint32_t scale) { return kGeoZero + role * kGeoScales + scale; }
  static constexpr uint32_t geo_mag(uint32_t role, uint32_t scale) {
    return kGeoMag + (role * kGeoScales + scale) * kGeoMagBins;
  }
  static constexpr uint32_t base_mag(uint32_t axis) { return kBaseMag + axis * kBaseMagBins; }

  ArithContext c[kCount];
  void reset();
};

// Context of the split flag of vertex x (marks: bit per vertex, set for the
// vertices before x that are split in this level). `ring` is x's ring.
uint32_t mesh_mark_context(const MeshState& s, uint32_t x, const Ring& ring, const uint8_t* marks);
// Geometry frame of a new vertex: which axis is closest to its ring's
// normal, the normal's sign on it, and a scale class from the ring size.
struct GeoFrame {
  int normal_axis = 2;
  bool flip = false;
  uint32_t scale = 0;
};
GeoFrame mesh_geo_frame(const MeshState& s, uint32_t v, const Ring& ring);
// Binarisation parameters shared with the encoder (docs/mesh-codec.md).
constexpr uint32_t kMeshGeoCutoff = 12;  // position corrections: decode_signed(cutoff, k)
constexpr int kMeshGeoEgK = 1;
constexpr uint32_t kMeshBaseDeltaCutoff = 8;  // base coordinate deltas
constexpr int kMeshBaseDeltaEgK = 2;
constexpr uint32_t kMeshBaseRefCutoff = 8;  // base back references
constexpr int kMeshBaseRefEgK = 2;
// Huffman coder alphabets.
constexpr uint32_t kMeshHuffEscape = 63;          // delta / correction symbols 0..62, 63 = escape + Exp-Golomb
constexpr uint32_t kMeshHuffDeltaAlphabet = 64;
constexpr uint32_t kMeshHuffGeoAlphabet = 64;
constexpr uint32_t kMeshHuffShapeAlphabet = kMeshMaxDegree + 1;  // 0 tail, 1..max-1 arc length, max head
constexpr uint32_t kMeshHuffPosAlphabet = kMeshMaxDegree;

}  // namespace vds
