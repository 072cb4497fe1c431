// vds client library: the progressive mesh chunks (MSHH, MSHB, MSHL) decoded
// one chunk at a time into MeshState: the base mesh, then each level's split
// flags (or the paper's sorted index deltas), split shapes and predicted
// positions with their corrections (Qin et al. 2002, sections 3-4; the
// arithmetic-coded variant in docs/mesh-codec.md).
#include <cstring>

#include "vds/mesh.h"
#include "vds/bytes.h"

namespace vds {
namespace {

constexpr uint32_t kHuffDeltaAlphabet = kMeshHuffDeltaAlphabet;
constexpr uint32_t kHuffGeoAlphabet = kMeshHuffGeoAlphabet;
constexpr uint32_t kHuffEscape = kMeshHuffEscape;
constexpr uint32_t kHuffShapeAlphabet = kMeshHuffShapeAlphabet;
constexpr uint32_t kHuffPosAlphabet = kMeshHuffPosAlphabet;
constexpr uint32_t kHuffTableMax = kHuffShapeAlphabet;
constexpr uint32_t kBaseDeltaCutoff = kMeshBaseDeltaCutoff;
constexpr int kBaseDeltaEgK = kMeshBaseDeltaEgK;
constexpr uint32_t kBaseRefCutoff = kMeshBaseRefCutoff;
constexpr int kBaseRefEgK = kMeshBaseRefEgK;
// No correction or delta on a 16-bit grid exceeds 2^16; larger decoded
// values are malformed (and keep the sums far from overflow).
constexpr int32_t kMaxStep = 1 << 16;


// Index of the candidate holding `rank` in the order (score, index).
uint32_t select_rank(const int64_t* score, uint32_t n, uint32_t rank) {
  for (uint32_t i = 0; i < n; ++i) {
    uint32_t better = 0;
    for (uint32_t j = 0; j < n; ++j)
      if (score[j] < score[i] || (score[j] == score[i] && j < i)) ++better;
    if (better == rank) return i;
  }
  return n;
}

int32_t unzigzag(uint32_t z) { return (z & 1) ? -static_cast<int32_t>((z + 1) >> 1) : static_cast<int32_t>(z >> 1); }

bool marked(const uint8_t* marks, uint32_t v) { return (marks[v >> 3] >> (v & 7)) & 1; }

}  // namespace

void mesh_header_to_bytes(const MeshHeader& h, uint8_t out[kMeshHeaderTailBytes]) {
  out[0] = h.version;
  out[1] = static_cast<uint8_t>(h.coder);
  out[2] = static_cast<uint8_t>(h.predictor);
  out[3] = h.bits;
  store_le16(out + 4, h.levels);
  store_le16(out + 6, h.max_degree);
  store_le32(out + 8, h.base_vertices);
  store_le32(out + 12, h.base_triangles);
  store_le32(out + 16, h.vertices);
  store_le32(out + 20, h.triangles);
  for (int k = 0; k < 3; ++k) store_le32(out + 24 + 4 * k, h.origin_f32[k]);
  store_le32(out + 36, h.step_f32);
  if (h.up != MeshUp::y_plus || h.tail()) {
    out[40] = static_cast<uint8_t>(h.up);
    out[41] = out[42] = out[43] = 0;
  }
  if (h.tail()) {
    store_le32(out + 44, h.tail_dummy_vertices);
    store_le32(out + 48, h.tail_dummy_triangles);
    store_le32(out + 52, h.tail_max_border);
  }
}

Status mesh_header_from_bytes(const uint8_t* p, uint32_t size, MeshHeader* out) {
  if (p == nullptr || out == nullptr) return Status::invalid_argument;
  if (size < kMeshHeaderBytes) return Status::malformed;
  MeshHeader h;
  h.version = p[0];
  if (h.version != kMeshCodecVersion && h.version != kMeshCodecVersionTail) return Status::unsupported_version;
  if (p[1] > static_cast<uint8_t>(MeshCoder::arith) || p[2] > static_cast<uint8_t>(MeshPredictor::area))
    return Status::unsupported_feature;
  h.coder = static_cast<MeshCoder>(p[1]);
  h.predictor = static_cast<MeshPredictor>(p[2]);
  h.bits = p[3];
  h.levels = static_cast<uint16_t>(load_le16(p + 4));
  h.max_degree = static_cast<uint16_t>(load_le16(p + 6));
  h.base_vertices = load_le32(p + 8);
  h.base_triangles = load_le32(p + 12);
  h.vertices = load_le32(p + 16);
  h.triangles = load_le32(p + 20);
  for (int k = 0; k < 3; ++k) h.origin_f32[k] = load_le32(p + 24 + 4 * k);
  h.step_f32 = load_le32(p + 36);
  // The view block: absent (+y up), or the up axis and three zero bytes.
  if (size != kMeshHeaderBytes) {
    if (size < kMeshHeaderViewBytes || p[41] != 0 || p[42] != 0 || p[43] != 0) return Status::malformed;
    if (p[40] > static_cast<uint8_t>(MeshUp::x_minus)) return Status::unsupported_feature;
    h.up = static_cast<MeshUp>(p[40]);
  }
  if (h.bits < 2 || h.bits > 16) return Status::malformed;
  if (h.max_degree < 3) return Status::malformed;
  if (h.max_degree > kMeshMaxDegree) return Status::unsupported_feature;
  if (h.base_vertices < 3 || h.base_triangles < 1 || h.vertices < h.base_vertices ||
      h.triangles < h.base_triangles)
    return Status::malformed;
  if ((h.levels == 0) != (h.vertices == h.base_vertices)) return Status::malformed;
  if (h.tail()) {
    // The tail block; the tail is a level, coded arithmetically only. Each
    // dummy closes a hole of three edges or more with as many triangles.
    if (size < kMeshHeaderTailBytes) return Status::malformed;
    h.tail_dummy_vertices = load_le32(p + 44);
    h.tail_dummy_triangles = load_le32(p + 48);
    h.tail_max_border = load_le32(p + 52);
    if (h.levels == 0 || h.tail_dummy_triangles < 3 * uint64_t{h.tail_dummy_vertices} || h.tail_max_border < 3 ||
        uint64_t{h.vertices} + h.tail_dummy_vertices > 0x0FFFFFFFu ||
        uint64_t{h.triangles} + h.tail_dummy_triangles > 0x07FFFFFFu ||
        h.tail_max_border > 3 * (uint64_t{h.triangles} + h.tail_dummy_triangles))
      return Status::malformed;
    if (h.coder != MeshCoder::arith) return Status::unsupported_feature;
  }
  *out = h;
  return Status::ok;
}

Status read_varint(const uint8_t*& p, const uint8_t* end, uint32_t* out) {
  uint32_t v = 0;
  for (int i = 0; i < 5; ++i) {
    if (p >= end) return Status::malformed;
    const uint8_t b = *p++;
    if (i == 4 && (b & 0xF0)) return Status::malformed;  // beyond 32 bits
    v |= static_cast<uint32_t>(b & 0x7F) << (7 * i);
    if ((b & 0x80) == 0) {
      if (i > 0 && b == 0) return Status::malformed;  // overlong
      *out = v;
      return Status::ok;
    }
  }
  return Status::malformed;
}

size_t MeshDecoder::workspace_bytes(uint32_t max_vertices, uint32_t max_triangles, uint32_t max_base_triangles,
                                    MeshCoder coder, uint32_t tail_border) {
  const size_t mesh = MeshState::workspace_bytes(max_vertices, max_triangles);
  if (mesh == SIZE_MAX || max_base_triangles > 0x07FFFFFFu) return SIZE_MAX;
  uint64_t total = mesh;
  total += sizeof(MeshContexts) + alignof(MeshContexts);
  total += (uint64_t{max_vertices} + 7) / 8 + 4;
  total += uint64_t{max_base_triangles} * 3 * sizeof(uint32_t) + alignof(uint32_t);
  if (tail_border > 0) total += tail_workspace_bytes(tail_border);
  if (coder == MeshCoder::huffman) {
    total += kHuffTableMax + 4;
    total += HuffmanTable::workspace_bytes(kHuffDeltaAlphabet) + HuffmanTable::workspace_bytes(kHuffShapeAlphabet) +
             HuffmanTable::workspace_bytes(kHuffPosAlphabet) + HuffmanTable::workspace_bytes(kHuffGeoAlphabet);
  }
  return total > SIZE_MAX ? SIZE_MAX : static_cast<size_t>(total);
}

Status MeshDecoder::init(Arena& arena, uint32_t max_vertices, uint32_t max_triangles) {
  // Member by member: a whole temporary decoder would cost ~1 KB of stack.
  arena_ = nullptr;
  ctx_ = nullptr;
  tctx_ = nullptr;
  tail_ = MeshTail();
  in_tail_ = false;
  marks_ = lengths_ = nullptr;
  huff_delta_ = HuffmanTable();
  huff_shape_ = HuffmanTable();
  huff_pos_ = HuffmanTable();
  huff_geo_ = HuffmanTable();
  cap_v_ = cap_t_ = 0;
  header_ = MeshHeader();
  status_ = Status::invalid_argument;
  have_header_ = base_done_ = in_level_ = full_ = false;
  base_items_ = base_next_ = levels_done_ = 0;
  items_ = pass_a_ = dv_ = dt_ = old_v_ = old_t_ = marked_ = last_mark_ = cursor_ = 0;
  weight_q4_ = 0;
  last_ = cur_ = MeshLevelInfo();
  Status s = mesh_.init(arena, max_vertices, max_triangles);
  if (s != Status::ok) return status_ = s;
  ctx_ = arena.alloc_array<MeshContexts>(1);
  marks_ = arena.alloc_array<uint8_t>((size_t{max_vertices} + 7) / 8 + 1);
  if (ctx_ == nullptr || marks_ == nullptr) return status_ = Status::workspace_too_small;
  arena_ = &arena;
  cap_v_ = max_vertices;
  cap_t_ = max_triangles;
  status_ = Status::ok;
  return status_;
}

Status MeshDecoder::finish() const {
  if (status_ != Status::ok) return status_;
  return complete() || full_ ? Status::ok : Status::truncated;
}

Status MeshDecoder::consume(uint32_t type, const uint8_t* payload, uint32_t size) {
  if (status_ != Status::ok) return status_;
  if (payload == nullptr && size > 0) return fail(Status::invalid_argument);
  switch (type) {
    case chunk::kMeshHeader: return on_header(payload, size);
    case chunk::kMeshBase: return on_base(payload, size);
    case chunk::kMeshLevel: return on_level(payload, size);
    case chunk::kMeshTail: return on_tail(payload, size);
    default: return Status::invalid_argument;  // not a mesh chunk: the caller's mistake, nothing latched
  }
}

Status MeshDecoder::on_header(const uint8_t* p, uint32_t size) {
  if (have_header_) return fail(Status::malformed);
  MeshHeader h;
  Status s = mesh_header_from_bytes(p, size, &h);
  if (s != Status::ok) return fail(s);
  // Only the base must fit: a level that would not is where this client
  // stops refining (on_level).
  if (h.base_vertices > cap_v_ || h.base_triangles > cap_t_) return fail(Status::workspace_too_small);
  if (h.coder == MeshCoder::huffman) {
    lengths_ = arena_->alloc_array<uint8_t>(kHuffTableMax);
    if (lengths_ == nullptr) return fail(Status::workspace_too_small);
    if ((s = huff_delta_.reserve(*arena_, kHuffDeltaAlphabet)) != Status::ok ||
        (s = huff_shape_.reserve(*arena_, kHuffShapeAlphabet)) != Status::ok ||
        (s = huff_pos_.reserve(*arena_, kHuffPosAlphabet)) != Status::ok ||
        (s = huff_geo_.reserve(*arena_, kHuffGeoAlphabet)) != Status::ok)
      return fail(s == Status::workspace_too_small ? s : Status::workspace_too_small);
  }
  header_ = h;
  have_header_ = true;
  mesh_.clear(h.bits);
  ctx_->reset();
  return Status::ok;
}

// --- Base mesh -------------------------------------------------------------------

Status MeshDecoder::on_base(const uint8_t* p, uint32_t size) {
  if (!have_header_ || base_done_) return fail(Status::malformed);
  const uint8_t* end = p + size;
  uint32_t first = 0, count = 0;
  Status s;
  if ((s = read_varint(p, end, &first)) != Status::ok || (s = read_varint(p, end, &count)) != Status::ok)
    return fail(s);
  const uint32_t total = header_.base_vertices + header_.base_triangles;
  if (first != base_items_ || count == 0 || count > total - first) return fail(Status::malformed);
  s = base_items(p, static_cast<uint32_t>(end - p), first, count);
  if (s != Status::ok) return fail(s);
  base_items_ += count;
  if (base_items_ == total) {
    // A base vertex no face uses (the Huffman base is caught by finish_base).
    if (header_.coder == MeshCoder::arith && base_next_ != header_.base_vertices) return fail(Status::malformed);
    s = mesh_.finish_base(*arena_, header_.max_degree);
    if (s != Status::ok) return fail(s);
    base_done_ = true;
    last_ = MeshLevelInfo{};
    last_.vertices_added = header_.base_vertices;
    last_.triangles_added = header_.base_triangles;
    check_tail_fits();
  }
  return Status::ok;
}

void MeshDecoder::check_tail_fits() {
  if (!header_.tail() || levels_done_ + 1 != header_.levels) return;
  // Next comes the tail: MSHH says what it needs, so a client that cannot
  // hold it stops now rather than after the tail's first chunk.
  if (uint64_t{header_.vertices} + header_.tail_dummy_vertices > cap_v_ ||
      uint64_t{header_.triangles} + header_.tail_dummy_triangles > cap_t_ ||
      arena_->remaining() < tail_workspace_bytes(header_.tail_max_border))
    full_ = true;
}

Status MeshDecoder::base_items(const uint8_t* data, uint32_t size, uint32_t first, uint32_t count) {
  const uint32_t nv = header_.base_vertices;
  const int bits = header_.bits;
  if (header_.coder == MeshCoder::huffman) {
    // The paper sends the base as it is: fixed-width coordinates and indices.
    BitReader br(data, size);
    int index_bits = 0;
    while ((uint32_t{1} << index_bits) < nv) ++index_bits;
    for (uint32_t i = first; i < first + count; ++i) {
      if (i < nv) {
        int32_t q[3];
        for (int k = 0; k < 3; ++k) q[k] = static_cast<int32_t>(br.read(bits));
        if (!br.ok()) return br.status();
        if (mesh_.add_vertex(q) != Status::ok) return Status::malformed;
      } else {
        uint32_t t[3];
        for (int k = 0; k < 3; ++k) {
          t[k] = br.read(index_bits);
          if (t[k] >= nv) return Status::malformed;
        }
        if (!br.ok()) return br.status();
        if (mesh_.add_triangle(t[0], t[1], t[2]) != Status::ok) return Status::malformed;
      }
    }
    if (!br.ok()) return br.status();
    if (br.bits_left() >= 8) return Status::malformed;  // bytes no item used
    return Status::ok;
  }
  ArithDecoder ad;
  Status s = ad.init(data, size);
  if (s != Status::ok) return s;
  MeshContexts& c = *ctx_;
  for (uint32_t i = first; i < first + count; ++i) {
    if (i < nv) {
      int32_t q[3];
      if (i == 0) {
        for (int k = 0; k < 3; ++k) q[k] = static_cast<int32_t>(ad.decode_bits_bypass(bits));
      } else {
        int32_t prev[3];
        mesh_.position(i - 1, prev);
        for (int k = 0; k < 3; ++k) {
          const int32_t d = ad.decode_signed(c.c[MeshContexts::kBaseZero + k], c.c + MeshContexts::base_mag(k),
                                             MeshContexts::kBaseMagBins, kBaseDeltaCutoff, kBaseDeltaEgK);
          if (d > kMaxStep || d < -kMaxStep) return Status::malformed;
          q[k] = prev[k] + d;
        }
      }
      if (!ad.ok()) return ad.status();
      if (mesh_.add_vertex(q) != Status::ok) return Status::malformed;
    } else {
      uint32_t t[3];
      for (int k = 0; k < 3; ++k) {
        if (ad.decode_bit(c.c[MeshContexts::kBaseNew + k])) {
          if (base_next_ >= nv) return Status::malformed;
          t[k] = base_next_++;
        } else {
          const uint32_t back =
              ad.decode_ueg(c.c + MeshContexts::kBaseRef, MeshContexts::kBaseMagBins, kBaseRefCutoff, kBaseRefEgK);
          if (back >= base_next_) return Status::malformed;
          t[k] = base_next_ - 1 - back;
        }
      }
      if (!ad.ok()) return ad.status();
      if (mesh_.add_triangle(t[0], t[1], t[2]) != Status::ok) return Status::malformed;
    }
  }
  return ad.finish();
}

// --- Levels ------------------------------------------------------------------------

void MeshDecoder::start_level() {
  in_level_ = true;
  items_ = 0;
  old_v_ = mesh_.vertex_count();
  old_t_ = mesh_.triangle_count();
  pass_a_ = header_.coder == MeshCoder::arith ? old_v_ : dv_;
  marked_ = 0;
  last_mark_ = 0;
  cursor_ = 0;
  std::memset(marks_, 0, (size_t{old_v_} + 7) / 8);
  cur_ = MeshLevelInfo{};
  cur_.level = levels_done_ + 1;
}

Status MeshDecoder::on_level(const uint8_t* p, uint32_t size) {
  if (full_) return Status::ok;  // past what this client holds: skipped
  const uint32_t split_levels = header_.levels - (header_.tail() ? 1u : 0u);
  if (!base_done_ || levels_done_ >= split_levels) return fail(Status::malformed);
  const uint8_t* end = p + size;
  uint32_t level = 0, first = 0, count = 0;
  Status s;
  if ((s = read_varint(p, end, &level)) != Status::ok || (s = read_varint(p, end, &first)) != Status::ok ||
      (s = read_varint(p, end, &count)) != Status::ok)
    return fail(s);
  if (level != levels_done_ + 1) return fail(Status::malformed);
  if (first == 0) {
    if (in_level_) return fail(Status::malformed);
    uint32_t dv = 0, dt = 0;
    if ((s = read_varint(p, end, &dv)) != Status::ok || (s = read_varint(p, end, &dt)) != Status::ok)
      return fail(s);
    if (p >= end) return fail(Status::malformed);
    const uint8_t weight = *p++;
    const uint32_t nv = mesh_.vertex_count(), nt = mesh_.triangle_count();
    if (dv == 0 || dv > nv || dv > header_.vertices - nv || dt > 2 * dv || dt > header_.triangles - nt ||
        weight > 16)
      return fail(Status::malformed);
    if (dv > cap_v_ - nv || dt > cap_t_ - nt) {
      // The workspace is full: keep the mesh as it is, skip the rest.
      full_ = true;
      return Status::ok;
    }
    dv_ = dv;
    dt_ = dt;
    weight_q4_ = weight;
    start_level();
  } else if (!in_level_ || first != items_) {
    return fail(Status::malformed);
  }
  const uint32_t total = pass_a_ + dv_;
  if (count == 0 || count > total - items_) return fail(Status::malformed);
  uint32_t conn_size = 0;
  if ((s = read_varint(p, end, &conn_size)) != Status::ok) return fail(s);
  if (conn_size > static_cast<uint32_t>(end - p)) return fail(Status::malformed);
  const uint8_t* conn = p;
  const uint8_t* geom = p + conn_size;
  const uint32_t geom_size = static_cast<uint32_t>(end - geom);
  s = level_items(conn, conn_size, geom, geom_size, first, count);
  if (s != Status::ok) return fail(s);
  items_ += count;
  cur_.connectivity_bytes += conn_size;
  cur_.geometry_bytes += geom_size;
  if (items_ == total) {
    const uint32_t added_t = mesh_.triangle_count() - old_t_;
    if (added_t != dt_) return fail(Status::malformed);
    cur_.vertices_added = dv_;
    cur_.triangles_added = added_t;
    last_ = cur_;
    in_level_ = false;
    ++levels_done_;
    if (levels_done_ == header_.levels &&
        (mesh_.vertex_count() != header_.vertices || mesh_.triangle_count() != header_.triangles))
      return fail(Status::malformed);
    check_tail_fits();
  }
  return Status::ok;
}

Status MeshDecoder::read_table(BitReader& br, HuffmanTable& table, uint32_t alphabet_max) {
  // Alphabet size, then each code length as the difference from the
  // previous one: 0 -> same; 1 0^d 1 -> +d; 1 1^d 0 -> -d (the paper's
  // unary length deltas, section 3.2).
  const uint32_t n = br.read_ue();
  if (!br.ok()) return br.status();
  if (n == 0 || n > alphabet_max) return Status::malformed;
  int len = 0;
  for (uint32_t i = 0; i < n; ++i) {
    if (br.read_bit()) {
      const int dir = static_cast<int>(br.read_bit());
      int d = 0;
      while (static_cast<int>(br.read_bit()) == dir) {
        if (++d > HuffmanTable::kMaxCodeLength || !br.ok()) return br.ok() ? Status::malformed : br.status();
      }
      if (dir == 0) {
        d += 1;  // "1 0^d 1": the zero read as `dir` was the first of d zeros
        len += d;
      } else {
        d += 1;
        len -= d;
      }
      if (len < 0 || len > HuffmanTable::kMaxCodeLength) return Status::malformed;
    }
    lengths_[i] = static_cast<uint8_t>(len);
  }
  if (!br.ok()) return br.status();
  return table.build_from_lengths(lengths_, n) == Status::ok ? Status::ok : Status::malformed;
}

Status MeshDecoder::decode_split_arith(ArithDecoder& ad, uint32_t u, SplitChoice* ch) {
  Ring r;
  Status s = mesh_.ring(u, &r, 0);
  if (s != Status::ok) return s;
  MeshContexts& c = *ctx_;
  const uint32_t d = r.degree;
  SplitKind kind = SplitKind::interior;
  if (r.boundary) {
    if (ad.decode_bit(c.c[MeshContexts::kKind]))
      kind = ad.decode_bit(c.c[MeshContexts::kKind + 1]) ? SplitKind::head : SplitKind::tail;
  }
  int64_t score[kMeshMaxDegree + 1];
  if (kind == SplitKind::interior) {
    if (d < 2) return Status::malformed;
    const uint32_t dc = d - 2 < MeshContexts::kArcDegree ? d - 2 : MeshContexts::kArcDegree - 1;
    const uint32_t count = 1 + ad.decode_unary(c.c + MeshContexts::arc(dc), MeshContexts::kArcBins, d - 2);
    const uint32_t n = mesh_.candidate_scores(r, u, kind, count, score);
    if (n == 0) return Status::malformed;
    const uint32_t rank = ad.decode_unary(c.c + MeshContexts::rank(n), MeshContexts::kRankBins, n - 1);
    ch->kind = kind;
    ch->first = select_rank(score, n, rank);
    ch->count = count;
  } else {
    const uint32_t n = mesh_.candidate_scores(r, u, kind, 0, score);
    const uint32_t rank = ad.decode_unary(c.c + MeshContexts::kEdgeRank, MeshContexts::kRankBins, n - 1);
    const uint32_t idx = select_rank(score, n, rank);
    ch->kind = kind;
    ch->first = kind == SplitKind::tail ? idx : 0;
    ch->count = kind == SplitKind::tail ? d - 1 - idx : idx;
  }
  return ad.status();
}

Status MeshDecoder::decode_position_arith(ArithDecoder& ad, uint32_t v) {
  Ring r;
  Status s = mesh_.ring(v, &r, 0);
  if (s != Status::ok) return s;
  const GeoFrame f = mesh_geo_frame(mesh_, v, r);
  int32_t pred[3];
  s = mesh_.predict(v, header_.predictor, weight_q4_, pred);
  if (s != Status::ok) return s;
  MeshContexts& c = *ctx_;
  int32_t q[3];
  const int order[3] = {f.normal_axis, f.normal_axis == 0 ? 1 : 0, f.normal_axis == 2 ? 1 : 2};
  for (int i = 0; i < 3; ++i) {
    const int axis = order[i];
    const uint32_t role = i == 0 ? 0 : 1;
    int32_t val = ad.decode_signed(c.c[MeshContexts::geo_zero(role, f.scale)], c.c + MeshContexts::geo_mag(role, f.scale),
                                   MeshContexts::kGeoMagBins, kMeshGeoCutoff, kMeshGeoEgK);
    if (val > kMaxStep || val < -kMaxStep) return Status::malformed;
    if (i == 0 && f.flip) val = -val;
    q[axis] = pred[axis] + val;
  }
  if (!ad.ok()) return ad.status();
  return mesh_.set_position(v, q) == Status::ok ? Status::ok : Status::malformed;
}

Status MeshDecoder::decode_split_huffman(BitReader& br, uint32_t u, SplitChoice* ch) {
  Ring r;
  Status s = mesh_.ring(u, &r, 0);
  if (s != Status::ok) return s;
  const int shape = huff_shape_.decode(br);
  const int pos = huff_pos_.decode(br);
  if (shape < 0 || pos < 0) return Status::malformed;
  if (shape == 0) {
    ch->kind = SplitKind::tail;
    ch->first = static_cast<uint32_t>(pos);
    ch->count = r.degree - 1 - ch->first;  // wraps for a bad position: rejected by choice_valid
  } else if (static_cast<uint32_t>(shape) == kHuffShapeAlphabet - 1) {
    ch->kind = SplitKind::head;
    ch->first = 0;
    ch->count = static_cast<uint32_t>(pos);
  } else {
    ch->kind = SplitKind::interior;
    ch->first = static_cast<uint32_t>(pos);
    ch->count = static_cast<uint32_t>(shape);
  }
  return br.status();
}

Status MeshDecoder::decode_position_huffman(BitReader& br, uint32_t v) {
  int32_t pred[3];
  Status s = mesh_.predict(v, header_.predictor, weight_q4_, pred);
  if (s != Status::ok) return s;
  int32_t q[3];
  for (int k = 0; k < 3; ++k) {
    const int sym = huff_geo_.decode(br);
    if (sym < 0) return Status::malformed;
    uint32_t z = static_cast<uint32_t>(sym);
    if (z == kHuffEscape) {
      const uint32_t extra = br.read_ue();
      if (extra > (1u << 17)) return Status::malformed;  // beyond any 16-bit correction
      z += extra;
    }
    q[k] = pred[k] + unzigzag(z);
  }
  if (!br.ok()) return br.status();
  return mesh_.set_position(v, q) == Status::ok ? Status::ok : Status::malformed;
}

Status MeshDecoder::level_items(const uint8_t* conn, uint32_t conn_size, const uint8_t* geom, uint32_t geom_size,
                                uint32_t first, uint32_t count) {
  const bool arith = header_.coder == MeshCoder::arith;
  const bool needs_geom = first + count > pass_a_;
  if (conn_size == 0 || needs_geom != (geom_size > 0)) return Status::malformed;
  ArithDecoder ac, ag;
  BitReader bc, bg;
  Status s = Status::ok;
  if (arith) {
    if ((s = ac.init(conn, conn_size)) != Status::ok) return s;
    if (needs_geom && (s = ag.init(geom, geom_size)) != Status::ok) return s;
  } else {
    bc.init(conn, conn_size);
    if (needs_geom) bg.init(geom, geom_size);
  }
  for (uint32_t item = first; item < first + count; ++item) {
    if (progress_ != nullptr && ++progress_count_ >= progress_every_) {
      progress_count_ = 0;
      progress_(progress_user_);
    }
    if (item < pass_a_) {
      // Pass A: which vertices split.
      if (arith) {
        const uint32_t x = item;
        Ring r;
        if ((s = mesh_.ring(x, &r, 0)) != Status::ok) return s;
        const uint32_t ci = mesh_mark_context(mesh_, x, r, marks_);
        if (ac.decode_bit(ctx_->c[MeshContexts::kMark + ci])) {
          marks_[x >> 3] = static_cast<uint8_t>(marks_[x >> 3] | (1u << (x & 7)));
          if (++marked_ > dv_) return Status::malformed;
        }
        if (!ac.ok()) return ac.status();
      } else {
        if (item == 0 && (s = read_table(bc, huff_delta_, kHuffDeltaAlphabet)) != Status::ok) return s;
        const int sym = huff_delta_.decode(bc);
        if (sym < 0) return Status::malformed;
        uint32_t delta = static_cast<uint32_t>(sym);
        if (delta == kHuffEscape) {
          const uint32_t extra = bc.read_ue();
          if (extra > old_v_) return Status::malformed;
          delta += extra;
        }
        // Sorted, each vertex at most once: deltas after the first are >= 1.
        if (item > 0 && delta == 0) return Status::malformed;
        const uint64_t x = uint64_t{last_mark_} + delta;
        if (x >= old_v_) return Status::malformed;
        last_mark_ = static_cast<uint32_t>(x);
        marks_[x >> 3] = static_cast<uint8_t>(marks_[x >> 3] | (1u << (x & 7)));
        ++marked_;
        if (!bc.ok()) return bc.status();
      }
      if (item + 1 == pass_a_ && marked_ != dv_) return Status::malformed;
      continue;
    }
    // Pass B: split the next flagged vertex and place the new one.
    if (!arith && item == pass_a_) {
      if ((s = read_table(bc, huff_shape_, kHuffShapeAlphabet)) != Status::ok ||
          (s = read_table(bc, huff_pos_, kHuffPosAlphabet)) != Status::ok ||
          (s = read_table(bg, huff_geo_, kHuffGeoAlphabet)) != Status::ok)
        return s;
    }
    while (cursor_ < old_v_ && !marked(marks_, cursor_)) ++cursor_;
    if (cursor_ >= old_v_) return Status::malformed;
    const uint32_t u = cursor_++;
    SplitChoice ch;
    s = arith ? decode_split_arith(ac, u, &ch) : decode_split_huffman(bc, u, &ch);
    if (s != Status::ok) return s;
    uint32_t v = 0;
    if ((s = mesh_.split(u, ch, &v)) != Status::ok) return s;
    if (mesh_.triangle_count() - old_t_ > dt_) return Status::malformed;
    s = arith ? decode_position_arith(ag, v) : decode_position_huffman(bg, v);
    if (s != Status::ok) return s;
  }
  if (arith) {
    if ((s = ac.finish()) != Status::ok) return s;
    if (needs_geom && (s = ag.finish()) != Status::ok) return s;
  } else {
    if (!bc.ok()) return bc.status();
    if (bc.bits_left() >= 8) return Status::malformed;
    if (needs_geom) {
      if (!bg.ok()) return bg.status();
      if (bg.bits_left() >= 8) return Status::malformed;
    }
  }
  return Status::ok;
}


// --- The single-rate tail (MSHT) -------------------------------------------------

Status MeshDecoder::on_tail(const uint8_t* p, uint32_t size) {
  if (full_) return Status::ok;  // past what this client holds: skipped
  if (!header_.tail() || !base_done_ || levels_done_ + 1 != header_.levels) return fail(Status::malformed);
  const uint8_t* end = p + size;
  uint32_t first = 0, count = 0;
  Status s;
  if ((s = read_varint(p, end, &first)) != Status::ok || (s = read_varint(p, end, &count)) != Status::ok)
    return fail(s);
  if (first == 0) {
    if (in_tail_) return fail(Status::malformed);
    TailCounts n;
    n.vertices = header_.vertices;
    n.triangles = header_.triangles;
    n.dummy_vertices = header_.tail_dummy_vertices;
    n.dummy_triangles = header_.tail_dummy_triangles;
    n.max_border = header_.tail_max_border;
    if (uint64_t{n.vertices} + n.dummy_vertices > cap_v_ || uint64_t{n.triangles} + n.dummy_triangles > cap_t_) {
      full_ = true;  // the workspace cannot hold the whole mesh: keep the levels so far
      return Status::ok;
    }
    old_v_ = mesh_.vertex_count();
    old_t_ = mesh_.triangle_count();
    // The tail's contexts and border are carved only now: a client that
    // stops before the tail never needs them.
    tctx_ = arena_->alloc_array<TailContexts>(1);
    if (tctx_ == nullptr) {
      full_ = true;
      return Status::ok;
    }
    tctx_->reset();
    s = tail_.begin(mesh_, *arena_, n);
    if (s == Status::workspace_too_small) {
      full_ = true;  // nor its border: the same (the mesh is untouched)
      return Status::ok;
    }
    if (s != Status::ok) return fail(s);
    in_tail_ = true;
    items_ = 0;
    cur_ = MeshLevelInfo{};
    cur_.level = levels_done_ + 1;
  } else if (!in_tail_ || first != items_) {
    return fail(Status::malformed);
  }
  const uint32_t total = tail_.total() + header_.vertices;
  if (count == 0 || count > total - items_) return fail(Status::malformed);
  uint32_t conn_size = 0;
  if ((s = read_varint(p, end, &conn_size)) != Status::ok) return fail(s);
  if (conn_size > static_cast<uint32_t>(end - p)) return fail(Status::malformed);
  const uint8_t* geom = p + conn_size;
  const uint32_t geom_size = static_cast<uint32_t>(end - geom);
  s = tail_items(p, conn_size, geom, geom_size, first, count);
  if (s != Status::ok) return fail(s);
  items_ += count;
  cur_.connectivity_bytes += conn_size;
  cur_.geometry_bytes += geom_size;
  if (items_ == total) {
    cur_.vertices_added = header_.vertices - old_v_;
    cur_.triangles_added = header_.triangles - old_t_;
    last_ = cur_;
    in_tail_ = false;
    ++levels_done_;
  }
  return Status::ok;
}

Status MeshDecoder::tail_items(const uint8_t* conn, uint32_t conn_size, const uint8_t* geom, uint32_t geom_size,
                               uint32_t first, uint32_t count) {
  const uint32_t nt = tail_.total();
  const bool needs_conn = first < nt, needs_geom = first + count > nt;
  if (needs_conn != (conn_size > 0) || needs_geom != (geom_size > 0)) return Status::malformed;
  ArithDecoder ac, ag;
  Status s = Status::ok;
  if (needs_conn && (s = ac.init(conn, conn_size)) != Status::ok) return s;
  if (needs_geom && (s = ag.init(geom, geom_size)) != Status::ok) return s;
  ArithContext* c = tctx_->c;
  using TC = TailContexts;
  for (uint32_t item = first; item < first + count; ++item) {
    progress_tick();
    if (item < nt) {
      if (tail_.needs_seed()) {
        bool dummy[3];
        for (bool& d : dummy) d = ac.decode_bit(c[TC::kDummy]) != 0;
        if (!ac.ok()) return ac.status();
        s = tail_.seed(dummy);
      } else {
        const uint32_t fx = tail_.fan_before(), fy = tail_.fan_after();
        const bool l = ac.decode_bit(c[TC::left(fx, fy)]) != 0;
        const bool r = ac.decode_bit(c[TC::right(fy, l)]) != 0;
        TailSymbol sym = l ? (r ? TailSymbol::E : TailSymbol::L) : (r ? TailSymbol::R : TailSymbol::C);
        bool dummy = false, backward = false;
        uint32_t offset = 0, depth = 0;
        if (!l && !r) {
          if (ac.decode_bit(c[TC::fresh(fx, fy)])) {
            dummy = ac.decode_bit(c[TC::kDummy + 1]) != 0;
          } else if (!ac.decode_bit(c[TC::kMerge])) {
            sym = TailSymbol::S;
            backward = ac.decode_bit(c[TC::kDirection]) != 0;
            offset = ac.decode_ueg(c + TC::kOffset, TC::kOffsetBins, kTailOffsetCutoff, kTailOffsetEgK) + 2;
          } else {
            sym = TailSymbol::M;
            depth = ac.decode_ueg(c + TC::kDepth, TC::kOffsetBins, kTailOffsetCutoff, kTailOffsetEgK);
            offset = ac.decode_ueg(c + TC::kOffset, TC::kOffsetBins, kTailOffsetCutoff, kTailOffsetEgK) + 1;
          }
        }
        if (!ac.ok()) return ac.status();
        s = tail_.attach(sym, dummy, backward, offset, depth);
      }
      if (s != Status::ok) return s;
      if (item + 1 == nt && (s = tail_.finish()) != Status::ok) return s;
      continue;
    }
    const uint32_t v = item - nt;
    int32_t q[3];
    uint32_t context = 0;
    if ((s = mesh_tail_predict(mesh_, v, q, &context)) != Status::ok) return s;
    const uint32_t cls = context;  // a copy the loop keeps in a register: context's address escaped
    for (uint32_t k = 0; k < 3; ++k) {
      const int32_t d = ag.decode_signed(c[TC::geo_zero(k, cls)], c + TC::geo_mag(k, cls), TC::kGeoBins,
                                         kTailGeoCutoff, kTailGeoEgK);
      if (d > kMaxStep || d < -kMaxStep) return Status::malformed;
      q[k] += d;
    }
    if (!ag.ok()) return ag.status();
    if (mesh_.set_position(v, q) != Status::ok) return Status::malformed;
  }
  if (needs_conn && (s = ac.finish()) != Status::ok) return s;
  if (needs_geom && (s = ag.finish()) != Status::ok) return s;
  return Status::ok;
}

}  // namespace vds
