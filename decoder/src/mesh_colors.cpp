// vds client library: mesh colors — topology, layout and the paper mode of
// the mesh colors codec (decoder side). The rules are in vds/mesh_colors.h.
#include "vds/mesh_colors.h"

#include "vds/bytes.h"
#include "vds/image_model.h"

namespace vds::mc {
namespace {

// round(2/N cos(pi k (n + 1/2) / N) 2^14) for N = 2..8, n = 0..N-1, k = 1..N-1.
constexpr int16_t kCos[] = {
    // N = 2
    11585, -11585,
    // N = 3
    9459, 5461, 0, -10923, -9459, 5461,
    // N = 4
    7568, 5793, 3135, 3135, -5793, -7568, -3135, -5793, 7568, -7568, 5793, -3135,
    // N = 5
    6233, 5302, 3852, 2025, 3852, -2025, -6233, -5302, 0, -6554, 0, 6554, -3852, -2025, 6233, -5302, -6233, 5302,
    -3852, 2025,
    // N = 6
    5275, 4730, 3862, 2731, 1413, 3862, 0, -3862, -5461, -3862, 1413, -4730, -3862, 2731, 5275, -1413, -4730, 3862,
    2731, -5275, -3862, 0, 3862, -5461, 3862, -5275, 4730, -3862, 2731, -1413,
    // N = 7
    4564, 4218, 3660, 2919, 2031, 1042, 3660, 1042, -2031, -4218, -4564, -2919, 2031, -2919, -4564, -1042, 3660,
    4218, 0, -4681, 0, 4681, 0, -4681, -2031, -2919, 4564, -1042, -3660, 4218, -3660, 1042, 2031, -4218, 4564,
    -2919, -4564, 4218, -3660, 2919, -2031, 1042,
    // N = 8
    4017, 3784, 3406, 2896, 2276, 1567, 799, 3406, 1567, -799, -2896, -4017, -3784, -2276, 2276, -1567, -4017,
    -2896, 799, 3784, 3406, 799, -3784, -2276, 2896, 3406, -1567, -4017, -799, -3784, 2276, 2896, -3406, -1567,
    4017, -2276, -1567, 4017, -2896, -799, 3784, -3406, -3406, 1567, 799, -2896, 4017, -3784, 2276, -4017, 3784,
    -3406, 2896, -2276, 1567, -799};
static_assert(sizeof(kCos) / sizeof(kCos[0]) == 168, "sum of N (N - 1) for N = 2..8");

// Where length n's table starts in kCos.
constexpr int kCosStart[9] = {0, 0, 0, 2, 8, 20, 40, 70, 112};

constexpr int32_t kSampleLimit = int32_t{1} << 24;
constexpr int64_t kCoefLimit = int64_t{1} << 26;

int32_t clamp32(int64_t v, int64_t limit) { return static_cast<int32_t>(v < -limit ? -limit : (v > limit ? limit : v)); }


uint8_t to_sample(int32_t q4) {
  const int32_t v = (q4 + 8) >> 4;
  return static_cast<uint8_t>(v < 0 ? 0 : (v > 255 ? 255 : v));
}

uint32_t hash_pair(uint32_t lo, uint32_t hi) { return (lo * 0x9E3779B1u) ^ (hi * 0x85EBCA77u) ^ (hi >> 7); }

uint32_t hash_size(uint32_t faces) {
  uint32_t h = 8;
  while (h < 6 * faces) h <<= 1;
  return h;
}

// The run/amplitude pairs of one context set, read as coefficients are needed.
struct AcState {
  uint32_t zeros = 0;
  int32_t amp = 0;
  bool has_amp = false;
  bool bad = false;  // a pair no encoder writes
};

int32_t next_ac(ArithDecoder& dec, CodecContexts& cx, AcState& st, int c, int kind) {
  if (st.zeros > 0) {
    --st.zeros;
    return 0;
  }
  if (st.has_amp) {
    st.has_amp = false;
    return st.amp;
  }
  const uint32_t run = dec.decode_ueg(cx.run[c][kind], CodecContexts::kRunCtx, kRunCutoff, kRunOrder);
  const int32_t amp = dec.decode_signed(cx.amp_zero[c][kind], cx.amp_mag[c][kind], CodecContexts::kAmpCtx,
                                        kAmpCutoff, kAmpOrder);
  if (!dec.ok()) return 0;
  if (run > kMaxRun || (amp == 0 && run == 0) || amp > kMaxQuantised || amp < -kMaxQuantised) {
    st.bad = true;
    return 0;
  }
  if (amp == 0) {
    st.zeros = run - 1;
    return 0;
  }
  if (run == 0) return amp;
  st.zeros = run - 1;
  st.amp = amp;
  st.has_amp = true;
  return 0;
}


// The vds mode's orthonormal DCT in terms of the modified one the inverse
// runs: X_0 = Y_0 / sqrt(N), X_k = Y_k sqrt(N / 2); Q14.
constexpr int32_t kR0[9] = {0, 16384, 11585, 9459, 8192, 7327, 6689, 6193, 5793};
constexpr int32_t kR1[9] = {0, 0, 16384, 20066, 23170, 25905, 28378, 30652, 32768};
int32_t rescale(int32_t v, int n, int k) {
  const int64_t r = k == 0 ? kR0[n] : kR1[n];
  return clamp32((int64_t{v} * r + 8192) >> 14, kCoefLimit);
}


// The vds mode's levels of one block of `positions` (scan order, lv[0..]):
// the count of nonzero levels, then per position a significance bin (left
// out when every remaining position must be nonzero) and for each nonzero
// one its magnitude (> 1, > 2 in contexts, the rest Exp-Golomb in bypass
// bins of an order that grows within the block) and sign. False for a count
// no block of that size holds, or a magnitude past kMaxQuantised.
bool read_levels(ArithDecoder& dec, BlockContexts& cx, int cls, int kind, int positions, uint8_t& prev_nz, int32_t* lv) {
  const uint32_t nz = dec.decode_ueg(cx.nz[cls][kind][image_model::kNzBucketOf[prev_nz]], BlockContexts::kNzCtx,
                                     kNzCutoff, kNzOrder);
  if (!dec.ok() || nz > static_cast<uint32_t>(positions)) return false;
  prev_nz = static_cast<uint8_t>(nz);
  uint32_t left = nz;
  int order = 0;
  for (int z = 0; z < positions; ++z) {
    lv[z] = 0;
    if (left == 0) continue;
    const bool sig = static_cast<uint32_t>(positions - z) == left ||
                     dec.decode_bit(cx.sig[cls][kind][image_model::kSigPosOf[z]][image_model::kSigLeftOf[left]]) != 0;
    if (!sig) continue;
    const int lp = image_model::kLevelPosOf[z], ll = image_model::kLevelLeftOf[left];
    uint32_t mag = 1;
    if (dec.decode_bit(cx.gt1[cls][kind][lp][ll]) != 0) {
      mag = 2;
      if (dec.decode_bit(cx.gt2[cls][kind][lp][ll]) != 0) {
        const uint32_t rest = dec.decode_exp_golomb(nullptr, 0, order);
        if (rest > static_cast<uint32_t>(kMaxQuantised)) return false;
        mag = 3 + rest;
        if (rest > (image_model::kRestRaise << order) && order < image_model::kRestMaxOrder) ++order;
      }
    }
    lv[z] = dec.decode_bypass() != 0 ? -static_cast<int32_t>(mag) : static_cast<int32_t>(mag);
    --left;
  }
  return dec.ok();
}
}  // namespace

int64_t div_round(int64_t a, int64_t b) { return a >= 0 ? (a + b / 2) / b : -((-a + b / 2) / b); }

void make_steps(uint16_t quality_q8, uint8_t mode, Steps* out) {
  for (int cls = 0; cls < 2; ++cls) {
    const uint8_t* table = cls == 0 ? image_model::kAnnexKLuma : image_model::kAnnexKChroma;
    for (int i = 0; i < 64; ++i) {
      const uint32_t s = (static_cast<uint32_t>(table[i]) * quality_q8 + 8) >> 4;
      out->face[cls][i] = s < 1 ? 1 : s;
    }
    for (int k = 0; k < 8; ++k) {
      const uint32_t s = mode == kModePaper ? (static_cast<uint32_t>(table[image_model::kZigzag[k]]) * quality_q8 + 80) / 160
                                            : (static_cast<uint32_t>(table[k]) * quality_q8 + 8) >> 4;
      out->edge[cls][k] = s < 1 ? 1 : s;
    }
  }
}

void inverse_dct(const int32_t* in, int n, int32_t* out, int in_stride, int out_stride) {
  if (n < 1 || n > 8) return;
  // Most rows and columns of a coded block hold no AC coefficient: their
  // samples are the DC (what the sums below give, without them).
  bool ac = false;
  for (int k = 1; k < n && !ac; ++k) ac = in[k * in_stride] != 0;
  if (!ac) {
    const int32_t v = clamp32(in[0], kSampleLimit);
    for (int i = 0; i < n; ++i) out[i * out_stride] = v;
    return;
  }
  const int16_t* t = kCos + kCosStart[n];
  for (int i = 0; i < n; ++i) {
    int64_t acc = 0;
    for (int k = 1; k < n; ++k) acc += static_cast<int64_t>(in[k * in_stride]) * t[i * (n - 1) + (k - 1)];
    out[i * out_stride] = clamp32(in[0] + ((acc + 8192) >> 14), kSampleLimit);
  }
}

uint32_t mean_step(uint32_t step0) { return step0 < 12 ? 1 : (step0 + 4) / 8; }
int64_t mean_q4(const uint8_t* samples, uint32_t count, int stride) {
  if (count == 0) return 0;
  int64_t sum = 0;
  for (uint32_t i = 0; i < count; ++i) sum += samples[i * static_cast<uint32_t>(stride)];
  return div_round(16 * sum, count);
}

int face_block_positions(int32_t D) {
  if (D >= 15) return 64;
  int p = 0;
  for (int d = 0; d < D; ++d) p += d < 8 ? d + 1 : 15 - d;
  return p;
}

void reconstruct_edge_block(const int32_t* q, int len, const uint32_t* step, uint8_t mode, int64_t mean_q4,
                            uint8_t* dst, int stride) {
  int32_t coef[8], x[8];
  for (int k = 0; k < len; ++k) {
    coef[k] = clamp32(int64_t{q[k]} * step[k], kCoefLimit);
    if (mode != kModePaper) coef[k] = rescale(coef[k], len, k);
  }
  inverse_dct(coef, len, x);
  for (int i = 0; i < len; ++i) dst[i * stride] = to_sample(clamp32(x[i] + mean_q4, kSampleLimit));
}

int64_t reconstruct_face_block(const int32_t* q, int32_t D, const uint32_t* step, uint8_t mode, int64_t mean_q4,
                               uint8_t* face, int32_t n, int32_t br, int32_t bc, int scale) {
  // Row gr, column i of the face (lattice point (i + 1, gr + 1)) lies at
  // (scale (i + 1), scale (gr + 1)) of a lattice of side nf.
  const int32_t nf = scale * (n + 2) - 2;
  int32_t coef[64], tmp[64], x[8];
  const int rows = D < 8 ? D : 8;
  for (int i = 0; i < 64; ++i) coef[i] = (i >> 3) + (i & 7) < D ? clamp32(int64_t{q[i]} * step[i], kCoefLimit) : 0;
  // Columns first (row 0 holds as many positions as there are rows), then rows.
  for (int k = 0; k < rows; ++k) {
    const int len = D - k < 8 ? D - k : 8;
    if (mode != kModePaper)
      for (int r = 0; r < len; ++r) coef[8 * r + k] = rescale(coef[8 * r + k], len, r);
    inverse_dct(coef + k, len, tmp + k, 8, 8);
  }
  int64_t sum = 0, count = 0;
  for (int r = 0; r < rows; ++r) {
    const int len = D - r < 8 ? D - r : 8;
    if (mode != kModePaper)
      for (int k = 0; k < len; ++k) tmp[8 * r + k] = rescale(tmp[8 * r + k], len, k);
    inverse_dct(tmp + 8 * r, len, x);
    const int32_t row = scale * (8 * br + r + 1) - 1;
    uint8_t* dst = face + static_cast<uint32_t>(row * nf - row * (row - 1) / 2 + scale * (8 * bc + 1) - 1);
    for (int i = 0; i < len; ++i) {
      const uint8_t v = to_sample(clamp32(x[i] + mean_q4, kSampleLimit));
      dst[i * scale] = v;
      sum += v;
    }
    count += len;
  }
  return div_round(16 * sum, count);
}

void BlockContexts::reset() {
  arith_init_contexts(&dc_zero[0][0], 4);
  arith_init_contexts(&dc_mag[0][0][0], 4 * kDcCtx);
  arith_init_contexts(&nz[0][0][0][0], 4 * 9 * kNzCtx);
  arith_init_contexts(&sig[0][0][0][0], 4 * 22 * 9);
  arith_init_contexts(&gt1[0][0][0][0], 4 * 25);
  arith_init_contexts(&gt2[0][0][0][0], 4 * 25);
}

void CodecContexts::reset() {
  arith_init_contexts(&dc_zero[0][0], 6);
  arith_init_contexts(&dc_mag[0][0][0], 6 * kDcCtx);
  arith_init_contexts(&run[0][0][0], 6 * kRunCtx);
  arith_init_contexts(&amp_zero[0][0], 6);
  arith_init_contexts(&amp_mag[0][0][0], 6 * kAmpCtx);
}

size_t topology_bytes(uint32_t faces) {
  return 3 * static_cast<size_t>(faces) * 4 + 3 * static_cast<size_t>(faces) * 4 + hash_size(faces) * 4 + 16;
}

Status build_topology(Arena& arena, const uint16_t* tri, uint32_t faces, uint32_t vertices, Topology* out) {
  if (out == nullptr || (tri == nullptr && faces > 0) || faces > kMaxFaces || vertices > kMaxVertices)
    return Status::invalid_argument;
  Topology t;
  t.vertices = vertices;
  t.faces = faces;
  t.tri = tri;
  t.face_edge = arena.alloc_array<uint32_t>(3 * static_cast<size_t>(faces) + 1);
  t.edge_vertex = arena.alloc_array<uint16_t>(6 * static_cast<size_t>(faces) + 2);
  if (t.face_edge == nullptr || t.edge_vertex == nullptr) return Status::workspace_too_small;
  const size_t mark = arena.mark();
  const uint32_t hsize = hash_size(faces);
  uint32_t* hash = arena.alloc_array<uint32_t>(hsize);
  if (hash == nullptr) return Status::workspace_too_small;
  for (uint32_t i = 0; i < hsize; ++i) hash[i] = 0;
  Status s = Status::ok;
  for (uint32_t f = 0; f < faces && s == Status::ok; ++f) {
    const uint16_t* v = tri + 3 * f;
    if (v[0] >= vertices || v[1] >= vertices || v[2] >= vertices || v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) {
      s = Status::invalid_argument;
      break;
    }
    for (int k = 0; k < 3; ++k) {
      const uint16_t a = v[k], b = v[(k + 1) % 3];
      const uint16_t lo = a < b ? a : b, hi = a < b ? b : a;
      uint32_t h = hash_pair(lo, hi) & (hsize - 1);
      for (;;) {
        if (hash[h] == 0) {
          hash[h] = t.edges + 1;
          t.edge_vertex[2 * t.edges] = a;
          t.edge_vertex[2 * t.edges + 1] = b;
          t.face_edge[3 * f + k] = t.edges << 1;
          ++t.edges;
          break;
        }
        const uint32_t e = hash[h] - 1;
        const uint16_t ea = t.edge_vertex[2 * e], eb = t.edge_vertex[2 * e + 1];
        if ((ea == lo && eb == hi) || (ea == hi && eb == lo)) {
          t.face_edge[3 * f + k] = (e << 1) | (ea == a ? 0u : 1u);
          break;
        }
        h = (h + 1) & (hsize - 1);
      }
    }
  }
  arena.rewind(mark);
  if (s == Status::ok) *out = t;
  return s;
}

size_t adjacency_bytes(uint32_t vertices, uint32_t edges) {
  return 4 * (static_cast<size_t>(vertices) + 1) + 2 * 2 * static_cast<size_t>(edges) + 16;
}

Status build_adjacency(Arena& arena, const Topology& t, Adjacency* out) {
  uint32_t* offset = arena.alloc_array<uint32_t>(t.vertices + 1);
  uint16_t* next = arena.alloc_array<uint16_t>(2 * static_cast<size_t>(t.edges) + 1);
  if (offset == nullptr || next == nullptr) return Status::workspace_too_small;
  for (uint32_t v = 0; v <= t.vertices; ++v) offset[v] = 0;
  for (uint32_t e = 0; e < t.edges; ++e) {
    ++offset[t.edge_vertex[2 * e] + 1];
    ++offset[t.edge_vertex[2 * e + 1] + 1];
  }
  for (uint32_t v = 0; v < t.vertices; ++v) offset[v + 1] += offset[v];
  // Each range filled from its end: offset[v + 1] ends at the start of
  // vertex v's range, so shifting the array down one gives the starts.
  for (uint32_t e = 0; e < t.edges; ++e) {
    const uint16_t a = t.edge_vertex[2 * e], b = t.edge_vertex[2 * e + 1];
    next[--offset[a + 1]] = b;
    next[--offset[b + 1]] = a;
  }
  for (uint32_t v = 0; v < t.vertices; ++v) offset[v] = offset[v + 1];
  offset[t.vertices] = 2 * t.edges;
  out->offset = offset;
  out->next = next;
  out->vertices = t.vertices;
  return Status::ok;
}

int32_t vertex_prediction(const Adjacency& adj, const uint8_t* ycc, uint32_t v, int c) {
  int64_t sum = 0, count = 0;
  for (uint32_t i = adj.offset[v]; i < adj.offset[v + 1]; ++i)
    if (adj.next[i] < v) {
      sum += ycc[3 * adj.next[i] + c];
      ++count;
    }
  if (count > 0) return static_cast<int32_t>(div_round(sum, count));
  return v > 0 ? ycc[3 * (v - 1) + c] : 128;
}

int32_t fan_prediction(const MeshState& mesh, const uint8_t* plane, uint32_t v) {
  const uint32_t nc = 3 * mesh.triangle_count();
  const uint32_t c0 = mesh.vertex_corner(v);
  int64_t sum = 0, count = 0;
  auto take = [&](uint32_t n) {
    if (n < v) {
      sum += plane[n];
      ++count;
    }
  };
  if (c0 < nc) {
    // Each face's next corner, and the last face's previous one (a fan
    // that ends at a border); a closed fan comes back to c0.
    uint32_t c = c0;
    for (uint32_t faces = 0; faces < 1023; ++faces) {
      take(mesh.corner_vertex(MeshState::next(c)));
      const int32_t o = mesh.opposite(MeshState::next(c));
      if (o < 0 || static_cast<uint32_t>(o) >= nc) {
        take(mesh.corner_vertex(MeshState::prev(c)));
        break;
      }
      c = MeshState::next(static_cast<uint32_t>(o));
      if (c == c0) break;
    }
  }
  if (count > 0) return static_cast<int32_t>(div_round(sum, count));
  return v > 0 ? plane[v - 1] : 128;
}

Status decode_vertex_colours(const uint8_t* data, size_t size, const MeshState& mesh, const Planes& out,
                             uint32_t* coloured) {
  if (data == nullptr || size < kVertexChunkHeadBytes) return Status::truncated;
  const uint32_t first = load_le32(data), count = load_le32(data + 4);
  const uint32_t nv = mesh.vertex_count();
  if (first != *coloured || count == 0 || first > nv || count != nv - first) return Status::malformed;
  ArithDecoder dec;
  Status s = dec.init(data + kVertexChunkHeadBytes, size - kVertexChunkHeadBytes);
  if (s != Status::ok) return s;
  VertexContexts vx;
  vx.reset();
  for (uint32_t v = first; v < nv; ++v)
    for (int c = 0; c < 3; ++c) {
      const int cls = c == 0 ? 0 : 1;
      const int32_t r = dec.decode_signed(vx.zero[cls], vx.mag[cls], VertexContexts::kMagCtx, kDcCutoff, kDcOrder);
      if (!dec.ok()) return dec.status();
      const int32_t value = fan_prediction(mesh, out.plane(c), v) + r;
      if (value < 0 || value > 255) return Status::malformed;
      out.plane(c)[v] = static_cast<uint8_t>(value);
    }
  s = dec.finish();
  if (s == Status::ok) *coloured = nv;
  return s;
}

void VertexContexts::reset() {
  arith_init_contexts(&zero[0], 2);
  arith_init_contexts(&mag[0][0], 2 * kMagCtx);
}

size_t MeshColors::init_bytes(uint32_t faces, uint32_t vertices) {
  const size_t f = faces, v = vertices;
  return topology_bytes(faces) + f + 3 * f + 3 * v + 4 * (3 * f + 1) + 4 * (f + 1) + sizeof(CodecContexts) +
         sizeof(BlockContexts) + sizeof(Steps) + adjacency_bytes(vertices, 3 * faces) + 64;
}

Status MeshColors::init(Arena& arena, const uint16_t* tri, uint32_t faces, uint32_t vertices) {
  *this = MeshColors{};
  arena_ = &arena;
  const Status s = build_topology(arena, tri, faces, vertices, &topo_);
  if (s != Status::ok) return s;
  face_res_ = arena.alloc_array<uint8_t>(faces + 1);
  edge_res_ = arena.alloc_array<uint8_t>(topo_.edges + 1);
  vertex_ycc_ = arena.alloc_array<uint8_t>(3 * static_cast<size_t>(vertices) + 1);
  layout_.edge_offset = arena.alloc_array<uint32_t>(topo_.edges + 1);
  layout_.face_offset = arena.alloc_array<uint32_t>(faces + 1);
  ctx_ = arena.alloc_array<CodecContexts>(1);
  bctx_ = arena.alloc_array<BlockContexts>(1);
  steps_ = arena.alloc_array<Steps>(1);
  if (face_res_ == nullptr || edge_res_ == nullptr || vertex_ycc_ == nullptr || layout_.edge_offset == nullptr ||
      layout_.face_offset == nullptr || ctx_ == nullptr || bctx_ == nullptr || steps_ == nullptr)
    return Status::workspace_too_small;
  return Status::ok;
}

Status MeshColors::read_header(const uint8_t* data, size_t size, const Planes* vertex_colours) {
  header_ = false;
  layout_m_ = -1;
  if (face_res_ == nullptr) return Status::invalid_argument;
  if (data == nullptr || size < kHeaderFixedBytes) return Status::truncated;
  if (data[0] == 0) return Status::malformed;
  if (data[0] > kVersion) return Status::unsupported_version;
  if (data[1] != kModePaper && data[1] != kModeVds) return Status::malformed;
  const int max_res = data[2];
  const uint16_t q8 = static_cast<uint16_t>(data[4] | (data[5] << 8));
  const uint32_t vertices = static_cast<uint32_t>(data[6] | (data[7] << 8));
  const uint32_t faces = static_cast<uint32_t>(data[8]) | (static_cast<uint32_t>(data[9]) << 8) |
                         (static_cast<uint32_t>(data[10]) << 16) | (static_cast<uint32_t>(data[11]) << 24);
  if (max_res > kMaxResLog2 || (data[3] & ~(kFlagVertexColours | kFlagChromaHalf | kFlagVertexStep)) != 0 || q8 == 0 ||
      vertices != topo_.vertices ||
      faces != topo_.faces)
    return Status::malformed;
  const bool paper = data[1] == kModePaper;
  // The vertex samples: the colours that came with the vertices, or in here.
  const bool outside = (data[3] & kFlagVertexColours) != 0;
  size_t at = kHeaderFixedBytes;
  int32_t vertex_step = 1;
  if ((data[3] & kFlagVertexStep) != 0) {
    if (paper || outside) return Status::malformed;  // only the vds mode's own vertex samples have a step
    if (size < at + 1) return Status::truncated;
    vertex_step = data[at++];
    if (vertex_step < 2 || vertex_step > kMaxVertexStep) return Status::malformed;
  }
  if (outside) {
    if (vertex_colours == nullptr) return Status::malformed;  // no colours came with the vertices
    for (uint32_t v = 0; v < vertices; ++v)
      for (int c = 0; c < 3; ++c) vertex_ycc_[3 * v + c] = vertex_colours->plane(c)[v];
  }
  // The paper mode carries the vertex samples raw, before the coded part.
  const size_t vbytes = paper && !outside ? 3 * static_cast<size_t>(vertices) : 0;
  if (size - at < vbytes) return Status::truncated;
  for (size_t i = 0; i < vbytes; ++i) vertex_ycc_[i] = data[at + i];
  ArithDecoder dec;
  Status s = dec.init(data + at + vbytes, size - at - vbytes);
  if (s != Status::ok) return s;
  ArithContext ctx[kMaxResLog2 + 1][kMaxResLog2];
  arith_init_contexts(&ctx[0][0], (kMaxResLog2 + 1) * kMaxResLog2);
  int prev = 0, top = 0;
  for (uint32_t f = 0; f < faces; ++f) {
    const uint32_t r = max_res == 0 ? 0 : dec.decode_unary(ctx[prev], kMaxResLog2, static_cast<uint32_t>(max_res));
    if (!dec.ok()) return dec.status();
    face_res_[f] = static_cast<uint8_t>(r);
    prev = static_cast<int>(r);
    if (prev > top) top = prev;
  }
  if (!paper && !outside) {
    // The vds mode codes each vertex sample as its difference from the
    // prediction of the vertices before it (vertex_prediction), in steps.
    const size_t mark = arena_->mark();
    Adjacency adj;
    s = build_adjacency(*arena_, topo_, &adj);
    if (s != Status::ok) return s;
    VertexContexts vx;
    vx.reset();
    for (uint32_t v = 0; v < vertices && dec.ok(); ++v)
      for (int c = 0; c < 3; ++c) {
        const int cls = c == 0 ? 0 : 1;
        const int64_t value =
            vertex_prediction(adj, vertex_ycc_, v, c) +
            int64_t{dec.decode_signed(vx.zero[cls], vx.mag[cls], VertexContexts::kMagCtx, kDcCutoff, kDcOrder)} * vertex_step;
        if (value < 0 || value > 255) {
          arena_->rewind(mark);
          return Status::malformed;
        }
        vertex_ycc_[3 * v + c] = static_cast<uint8_t>(value);
      }
    arena_->rewind(mark);
    if (!dec.ok()) return dec.status();
  }
  s = dec.finish();
  if (s != Status::ok) return s;
  if (faces > 0 && top != max_res) return Status::malformed;  // max_res is the largest, exactly
  return set(face_res_, nullptr, q8, data[1], (data[3] & kFlagChromaHalf) != 0);
}

Status MeshColors::set(const uint8_t* face_res, const uint8_t* vertex_ycc, uint16_t quality_q8, uint8_t mode,
                       bool chroma_half) {
  header_ = false;
  layout_m_ = -1;
  if (face_res_ == nullptr || face_res == nullptr || quality_q8 == 0 || mode > kModeVds) return Status::invalid_argument;
  int top = 0;
  for (uint32_t f = 0; f < topo_.faces; ++f) {
    if (face_res[f] > kMaxResLog2) return Status::invalid_argument;
    if (face_res[f] > top) top = face_res[f];
  }
  if (face_res != face_res_)
    for (uint32_t f = 0; f < topo_.faces; ++f) face_res_[f] = face_res[f];
  if (vertex_ycc != nullptr)
    for (uint32_t i = 0; i < 3 * topo_.vertices; ++i) vertex_ycc_[i] = vertex_ycc[i];
  for (uint32_t e = 0; e < topo_.edges; ++e) edge_res_[e] = 0;
  for (uint32_t f = 0; f < topo_.faces; ++f)
    for (int k = 0; k < 3; ++k) {
      const uint32_t e = topo_.face_edge[3 * f + k] >> 1;
      if (face_res_[f] > edge_res_[e]) edge_res_[e] = face_res_[f];
    }
  max_res_ = top;
  quality_q8_ = quality_q8;
  mode_ = mode;
  chroma_half_ = chroma_half;
  make_steps(quality_q8, mode, steps_);
  header_ = true;
  return Status::ok;
}

uint32_t MeshColors::layout_level(int m) {
  if (!header_) return 0;
  if (m == layout_m_) return layout_.total;
  uint32_t at = 0;
  for (uint32_t e = 0; e < topo_.edges; ++e) {
    layout_.edge_offset[e] = at;
    at += edge_samples(level_res(edge_res_[e], m));
  }
  layout_.edge_offset[topo_.edges] = at;
  layout_.edge_base = topo_.vertices;
  layout_.face_base = topo_.vertices + at;
  at = 0;
  for (uint32_t f = 0; f < topo_.faces; ++f) {
    layout_.face_offset[f] = at;
    at += face_samples(level_res(face_res_[f], m));
  }
  layout_.face_offset[topo_.faces] = at;
  layout_.total = layout_.face_base + at;
  layout_m_ = m;
  return layout_.total;
}

uint32_t MeshColors::sample_index(uint32_t f, int m, uint32_t i, uint32_t j) const {
  const uint16_t* v = topo_.tri + 3 * f;
  const uint32_t R = resolution(level_res(face_res_[f], m));
  if (j == 0 && i == 0) return v[0];
  if (j == 0 && i == R) return v[1];
  if (i == 0 && j == R) return v[2];
  int k;
  uint32_t p;
  if (j == 0) {
    k = 0;
    p = i;
  } else if (i + j == R) {
    k = 1;
    p = j;
  } else if (i == 0) {
    k = 2;
    p = R - j;
  } else {
    const uint32_t n = R - 2, row = j - 1;
    return layout_.face_base + layout_.face_offset[f] + row * n - row * (row - 1) / 2 + (i - 1);
  }
  const uint32_t fe = topo_.face_edge[3 * f + k];
  const uint32_t e = fe >> 1;
  const uint32_t Re = resolution(level_res(edge_res_[e], m));
  uint32_t q = p * (Re / R);
  if (fe & 1u) q = Re - q;
  return layout_.edge_base + layout_.edge_offset[e] + q - 1;
}

void MeshColors::face_lattice(uint32_t f, LatticeFace* out) const {
  const int m = layout_m_ < 0 ? 0 : layout_m_;
  const uint16_t* v = topo_.tri + 3 * f;
  const int r = level_res(face_res_[f], m);
  out->res_log2 = static_cast<uint8_t>(r);
  for (int k = 0; k < 3; ++k) {
    out->vertex[k] = v[k];
    const uint32_t fe = topo_.face_edge[3 * f + k];
    const uint32_t e = fe >> 1;
    const int re = level_res(edge_res_[e], m);
    // sample_index's q = p 2^(re - r), reversed Re - q; the sample at q - 1.
    const uint32_t first = layout_.edge_base + layout_.edge_offset[e] - 1;
    const int32_t step = static_cast<int32_t>(resolution(re > r ? re - r : 0));
    if (fe & 1u) {
      out->edge_base[k] = first + resolution(re);
      out->edge_step[k] = -step;
    } else {
      out->edge_base[k] = first;
      out->edge_step[k] = step;
    }
  }
  out->face_base = layout_.face_base + layout_.face_offset[f];
}

int64_t MeshColors::corner_sum_q4(uint32_t f, int m, const uint8_t* plane, int scale) const {
  int64_t sum = 0;
  const int shift = scale == 2 ? 1 : 0;
  for (int k = 0; k < 3; k += 2) {
    const uint32_t fe = topo_.face_edge[3 * f + k];
    const uint32_t e = fe >> 1;
    const uint32_t ne = edge_samples(level_res(edge_res_[e], m + shift));
    // Sample t of the edge's lattice at level m + shift lies at t in level m + shift's plane, or at
    // scale (t + 1) - 1 of the edge in level m's.
    const uint8_t* src = plane + layout_.edge_base + layout_.edge_offset[e] + (scale - 1);
    // Corner a is where edge 0 starts and edge 2 ends (in the face's direction).
    const bool at_start = (k == 0) == ((fe & 1u) == 0);
    const uint32_t from = at_start ? 0 : 8 * ((ne - 1) / 8);
    const uint32_t to = at_start ? (ne < 8 ? ne : 8) : ne;
    sum += mean_q4(src + from * static_cast<uint32_t>(scale), to - from, scale);
  }
  return sum;
}

void MeshColors::fill_edge(uint32_t e, int m, uint8_t* p) const {
  const uint32_t R = resolution(level_res(edge_res_[e], m));
  if (R < 2) return;
  uint8_t* s = p + layout_.edge_base + layout_.edge_offset[e] - 1;  // s[q]: the sample at q = 1 .. R - 1
  const uint8_t first = p[topo_.edge_vertex[2 * e]], last = p[topo_.edge_vertex[2 * e + 1]];
  for (uint32_t q = 1; q < R; q += 2) {
    const uint32_t a = q == 1 ? first : s[q - 1], b = q + 1 == R ? last : s[q + 1];
    s[q] = static_cast<uint8_t>((a + b + 1) >> 1);
  }
}

void MeshColors::fill_face(uint32_t f, int m, uint8_t* p) const {
  const uint32_t R = resolution(level_res(face_res_[f], m));
  if (R < 4) return;  // no face samples (R = 2's only point, on an edge, is the edge's)
  const uint32_t n = R - 2;
  uint8_t* face = p + layout_.face_base + layout_.face_offset[f];
  for (uint32_t j = 1; j + 1 < R; ++j) {
    const uint32_t row = j - 1;
    uint8_t* dst = face + row * n - row * (row - 1) / 2 - 1;  // dst[i]: lattice point (i, j)
    for (uint32_t i = 1; i + j < R; ++i) {
      if ((i & 1u) == 0 && (j & 1u) == 0) continue;  // a point level m + 1 has
      uint32_t a, b;
      if ((j & 1u) == 0) {  // between (i - 1, j) and (i + 1, j)
        a = p[sample_index(f, m, i - 1, j)];
        b = p[sample_index(f, m, i + 1, j)];
      } else if ((i & 1u) == 0) {  // between (i, j - 1) and (i, j + 1)
        a = p[sample_index(f, m, i, j - 1)];
        b = p[sample_index(f, m, i, j + 1)];
      } else {  // between (i - 1, j + 1) and (i + 1, j - 1)
        a = p[sample_index(f, m, i - 1, j + 1)];
        b = p[sample_index(f, m, i + 1, j - 1)];
      }
      dst[i] = static_cast<uint8_t>((a + b + 1) >> 1);
    }
  }
}

Status level_chunk_info(const uint8_t* data, size_t size, LevelChunk* out) {
  if (data == nullptr || size < kLevelHeadBytes) return Status::truncated;
  out->level = data[0];
  out->first = load_le32(data + 1);
  out->count = load_le32(data + 5);
  return Status::ok;
}

Status MeshColors::decode_level(const uint8_t* data, size_t size, const Planes& out) {
  if (!header_ || out.y == nullptr || out.cb == nullptr || out.cr == nullptr) return Status::invalid_argument;
  LevelChunk lc;
  Status s = level_chunk_info(data, size, &lc);
  if (s != Status::ok) return s;
  const int m = lc.level;
  const uint32_t elements = topo_.edges + topo_.faces;
  if (m >= max_res_ || lc.count == 0 || lc.first >= elements || lc.count > elements - lc.first) return Status::malformed;
  if (lc.first == 0) {
    layout_level(m);
    for (uint32_t v = 0; v < topo_.vertices; ++v)
      for (int c = 0; c < 3; ++c) out.plane(c)[v] = vertex_ycc_[3 * v + c];
  } else if (decoding_ != m || next_element_ != lc.first) {
    return Status::malformed;  // not the chunk after the last one of this level
  }
  decoding_ = -1;  // until this chunk is whole
  const uint32_t end = lc.first + lc.count;
  const uint32_t edge_end = end < topo_.edges ? end : topo_.edges;
  const uint32_t face_first = lc.first > topo_.edges ? lc.first - topo_.edges : 0;
  const uint32_t face_end = end > topo_.edges ? end - topo_.edges : 0;
  ArithDecoder dec;
  s = dec.init(data + kLevelHeadBytes, size - kLevelHeadBytes);
  if (s != Status::ok) return s;
  const bool paper = mode_ == kModePaper;
  ctx_->reset();
  bctx_->reset();
  AcState ac[3][2];
  uint8_t prev_nz[2][2] = {};
  int32_t lv[64];

  // The component groups of every element, in order: Y', Cb, Cr on the
  // level's lattice, or (kFlagChromaHalf) Y' on it, then Cb, Cr on the next
  // level's, whose samples lie at every other lattice point (scale 2).
  const ComponentGroup* groups = nullptr;
  const int group_count = component_groups(chroma_half_, &groups);

  // Edges.
  for (uint32_t e = lc.first; e < edge_end; ++e) {
    const uint32_t base = layout_.edge_base + layout_.edge_offset[e];
    for (int g = 0; g < group_count; ++g) {
      const int scale = 1 << groups[g].shift;
      const uint32_t n = edge_samples(level_res(edge_res_[e], m + groups[g].shift));
      int64_t prev_q[3] = {0, 0, 0};
      for (uint32_t b = 0; 8 * b < n; ++b) {
        const int len = static_cast<int>(n - 8 * b < 8 ? n - 8 * b : 8);
        for (int c = groups[g].first; c < groups[g].end; ++c) {
          const int cls = c == 0 ? 0 : 1;
          const uint32_t* step = steps_->edge[cls];
          uint8_t* dst = out.plane(c) + base + static_cast<uint32_t>(scale) * (8 * b + 1) - 1;
          const int64_t vertex_q4 = int64_t{16} * vertex_ycc_[3 * topo_.edge_vertex[2 * e] + c];
          const uint32_t dc_step = paper ? step[0] : mean_step(step[0]);
          const int64_t centre = paper ? 0 : kMeanCentreQ4;
          const int64_t pred =
              paper && b > 0 ? prev_q[c]
                             : div_round((b == 0 ? vertex_q4 : mean_q4(dst - 8 * scale, 8, scale)) - centre, dc_step);
          const int64_t q = pred + (paper ? dec.decode_signed(ctx_->dc_zero[c][1], ctx_->dc_mag[c][1], CodecContexts::kDcCtx,
                                                              kDcCutoff, kDcOrder)
                                          : dec.decode_signed(bctx_->dc_zero[cls][1], bctx_->dc_mag[cls][1],
                                                              BlockContexts::kDcCtx, kDcCutoff, kDcOrder));
          if (q > kMaxQuantised || q < -kMaxQuantised) return Status::malformed;
          if (paper) {
            lv[0] = static_cast<int32_t>(q);
            for (int k = 1; k < len; ++k) lv[k] = next_ac(dec, *ctx_, ac[c][1], c, 1);
            if (ac[c][1].bad) return Status::malformed;
          } else if (!read_levels(dec, *bctx_, cls, 1, len, prev_nz[cls][1], lv)) {
            return dec.ok() ? Status::malformed : dec.status();
          }
          if (!dec.ok()) return dec.status();
          reconstruct_edge_block(lv, len, step, mode_, paper ? 0 : centre + q * dc_step, dst, scale);
          prev_q[c] = q;
        }
      }
    }
    if (chroma_half_) {
      fill_edge(e, m, out.cb);
      fill_edge(e, m, out.cr);
    }
  }

  // Faces.
  for (uint32_t f = face_first; f < face_end; ++f) {
    const uint32_t base = layout_.face_base + layout_.face_offset[f];
    for (int g = 0; g < group_count; ++g) {
      const int scale = 1 << groups[g].shift;
      const int rf = level_res(face_res_[f], m + groups[g].shift);
      if (face_samples(rf) == 0) continue;
      const int32_t n = static_cast<int32_t>(resolution(rf)) - 2;
      int64_t corner_q4[3] = {0, 0, 0};
      for (int c = groups[g].first; c < groups[g].end; ++c) corner_q4[c] = corner_sum_q4(f, m, out.plane(c), scale);
      int64_t left_q[3] = {0, 0, 0}, row_q[3] = {0, 0, 0};
      int64_t left_mean[3] = {0, 0, 0}, row_mean[3] = {0, 0, 0};
      for (int32_t br = 0; 8 * br < n; ++br) {
        for (int32_t bc = 0; n - 8 * (br + bc) >= 1; ++bc) {
          const int32_t D = n - 8 * (br + bc);
          for (int c = groups[g].first; c < groups[g].end; ++c) {
            const int cls = c == 0 ? 0 : 1;
            const uint32_t* step = steps_->face[cls];
            const uint32_t dc_step = paper ? step[0] : mean_step(step[0]);
            const int64_t pred =
                paper ? (bc > 0 ? left_q[c] : (br > 0 ? row_q[c] : div_round(corner_q4[c], 2 * dc_step)))
                      : div_round((bc > 0 ? left_mean[c] : (br > 0 ? row_mean[c] : div_round(corner_q4[c], 2))) -
                                      kMeanCentreQ4,
                                  dc_step);
            const int64_t q = pred + (paper ? dec.decode_signed(ctx_->dc_zero[c][0], ctx_->dc_mag[c][0],
                                                                CodecContexts::kDcCtx, kDcCutoff, kDcOrder)
                                            : dec.decode_signed(bctx_->dc_zero[cls][0], bctx_->dc_mag[cls][0],
                                                                BlockContexts::kDcCtx, kDcCutoff, kDcOrder));
            if (q > kMaxQuantised || q < -kMaxQuantised) return Status::malformed;
            int32_t qn[64] = {};
            const int positions = face_block_positions(D);
            if (paper) {
              qn[0] = static_cast<int32_t>(q);
              for (int z = 1; z < positions; ++z) qn[image_model::kZigzag[z]] = next_ac(dec, *ctx_, ac[c][0], c, 0);
              if (ac[c][0].bad) return Status::malformed;
            } else {
              if (!read_levels(dec, *bctx_, cls, 0, positions, prev_nz[cls][0], lv))
                return dec.ok() ? Status::malformed : dec.status();
              for (int z = 0; z < positions; ++z) qn[image_model::kZigzag[z]] = lv[z];
            }
            if (!dec.ok()) return dec.status();
            const int64_t mean = reconstruct_face_block(qn, D, step, mode_, paper ? 0 : kMeanCentreQ4 + q * dc_step,
                                                        out.plane(c) + base, n, br, bc, scale);
            left_q[c] = q;
            left_mean[c] = mean;
            if (bc == 0) {
              row_q[c] = q;
              row_mean[c] = left_mean[c];
            }
          }
        }
      }
    }
    if (chroma_half_) {
      fill_face(f, m, out.cb);
      fill_face(f, m, out.cr);
    }
  }
  s = dec.finish();
  if (s == Status::ok) {
    decoding_ = m;
    next_element_ = end;
  }
  return s;
}

}  // namespace vds::mc
