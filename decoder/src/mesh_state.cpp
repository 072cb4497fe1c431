// vds client library: the progressive mesh as a corner table (Rossignac,
// "3D compression made simple: Edgebreaker with Zip&Wrap on a corner
// table", 2001) with the vertex split of Hoppe's progressive meshes (1996),
// the split-candidate ranking and the position predictors of the mesh codec
// (docs/mesh-codec.md). Integer only; shared with the encoder.
#include <cstring>

#include "vds/fixed.h"
#include "vds/mesh.h"

namespace vds {
namespace {

// floor(n / d) for d > 0 (C++ division truncates toward zero).
int64_t div_floor(int64_t n, int64_t d) {
  const int64_t q = n / d;
  return (q * d > n) ? q - 1 : q;
}

// round(n / d), halves toward +infinity, for d > 0.
int64_t div_round(int64_t n, int64_t d) { return div_floor(2 * n + d, 2 * d); }

size_t aligned(size_t bytes) { return bytes + alignof(uint32_t); }

}  // namespace

size_t MeshState::workspace_bytes(uint32_t max_vertices, uint32_t max_triangles) {
  // Keep every product inside 32 bits so the size is right on the client too.
  if (max_vertices > 0x0FFFFFFFu || max_triangles > 0x07FFFFFFu) return SIZE_MAX;
  const uint64_t corners = uint64_t{max_triangles} * 3;
  const uint64_t total = aligned(uint64_t{max_vertices} * 3 * sizeof(uint16_t)) +
                         IndexTable::workspace_bytes(max_vertices, corners) +
                         IndexTable::workspace_bytes(corners, max_vertices) +
                         IndexTable::workspace_bytes(corners, corners) +
                         4 * aligned((kMeshMaxDegree + 1) * sizeof(uint32_t));
  return total > SIZE_MAX ? SIZE_MAX : static_cast<size_t>(total);
}

Status MeshState::init(Arena& arena, uint32_t max_vertices, uint32_t max_triangles) {
  if (workspace_bytes(max_vertices, max_triangles) == SIZE_MAX) return Status::workspace_too_small;
  const uint32_t corners = max_triangles * 3;
  pos_ = arena.alloc_array<uint16_t>(size_t{max_vertices} * 3);
  bool ok = vertex_corner_.init(arena, max_vertices, corners);
  ok = corner_vertex_.init(arena, corners, max_vertices) && ok;
  ok = opposite_.init(arena, corners, corners) && ok;
  for (int i = 0; i < 2; ++i) {
    ring_vertex_[i] = arena.alloc_array<uint32_t>(kMeshMaxDegree + 1);
    ring_corner_[i] = arena.alloc_array<uint32_t>(kMeshMaxDegree + 1);
  }
  if (!ok || (max_vertices && !pos_) || !ring_vertex_[0] || !ring_vertex_[1] || !ring_corner_[0] ||
      !ring_corner_[1])
    return Status::workspace_too_small;
  cap_v_ = max_vertices;
  cap_t_ = max_triangles;
  clear(16);
  return Status::ok;
}

void MeshState::clear(int bits) {
  nv_ = 0;
  nt_ = 0;
  bits_ = bits;
  max_degree_ = kMeshMaxDegree;
  max_degree_seen_ = 0;
}

Status MeshState::add_vertex(const int32_t p[3]) {
  if (nv_ >= cap_v_) return Status::malformed;
  const int32_t top = (1 << bits_) - 1;
  for (int k = 0; k < 3; ++k)
    if (p[k] < 0 || p[k] > top) return Status::malformed;
  for (int k = 0; k < 3; ++k) pos_[3 * nv_ + k] = static_cast<uint16_t>(p[k]);
  vertex_corner_.set(nv_, kMeshNone);
  ++nv_;
  return Status::ok;
}

Status MeshState::set_position(uint32_t v, const int32_t p[3]) {
  const int32_t top = (1 << bits_) - 1;
  if (v >= nv_) return Status::invalid_argument;
  for (int k = 0; k < 3; ++k)
    if (p[k] < 0 || p[k] > top) return Status::invalid_argument;
  for (int k = 0; k < 3; ++k) pos_[3 * v + k] = static_cast<uint16_t>(p[k]);
  return Status::ok;
}

Status MeshState::add_triangle(uint32_t a, uint32_t b, uint32_t c) {
  if (nt_ >= cap_t_) return Status::malformed;
  if (a >= nv_ || b >= nv_ || c >= nv_ || a == b || b == c || a == c) return Status::malformed;
  corner_vertex_.set(3 * nt_, a);
  corner_vertex_.set(3 * nt_ + 1, b);
  corner_vertex_.set(3 * nt_ + 2, c);
  for (uint32_t k = 0; k < 3; ++k) set_opp(3 * nt_ + k, -1);
  ++nt_;
  return Status::ok;
}

Status MeshState::finish_base(Arena& arena, uint32_t max_degree) {
  if (max_degree < 3 || max_degree > kMeshMaxDegree) return Status::unsupported_feature;
  max_degree_ = max_degree;
  const uint32_t nc = 3 * nt_;
  const size_t mark = arena.mark();
  // Per-vertex lists of corners: head in vertex_corner_, links here.
  uint32_t* link_next = arena.alloc_array<uint32_t>(nc ? nc : 1);
  if (link_next == nullptr) return Status::workspace_too_small;
  for (uint32_t v = 0; v < nv_; ++v) vertex_corner_.set(v, kMeshNone);
  for (uint32_t c = 0; c < nc; ++c) {
    const uint32_t v = corner_vertex(c);
    link_next[c] = vertex_corner_.get(v);
    vertex_corner_.set(v, c);
  }
  Status st = Status::ok;
  // No vertex may have more faces than the degree limit: this also bounds
  // the list walks below, so a hostile base costs O(corners * max_degree).
  for (uint32_t v = 0; v < nv_ && st == Status::ok; ++v) {
    uint32_t n = 0;
    for (uint32_t x = vertex_corner_.get(v); x != kMeshNone && st == Status::ok; x = link_next[x])
      if (++n > max_degree_) st = Status::malformed;
  }
  // Opposite of corner c: the face holding the reverse of c's opposite edge
  // (V[next c] -> V[prev c]), i.e. an edge V[prev c] -> V[next c].
  for (uint32_t c = 0; c < nc && st == Status::ok; ++c) {
    const uint32_t a = corner_vertex(prev(c)), b = corner_vertex(next(c));
    int32_t found = -1;
    uint32_t same_direction = 0;
    for (uint32_t x = vertex_corner_.get(a); x != kMeshNone; x = link_next[x]) {
      if (corner_vertex(next(x)) == b) {
        if (found >= 0) st = Status::malformed;  // two faces with edge a -> b
        found = static_cast<int32_t>(prev(x));
      }
    }
    for (uint32_t x = vertex_corner_.get(b); x != kMeshNone; x = link_next[x])
      if (corner_vertex(next(x)) == a) ++same_direction;
    if (same_direction != 1) st = Status::malformed;  // edge b -> a in another face too
    set_opp(c, found);
  }
  for (uint32_t c = 0; c < nc && st == Status::ok; ++c)
    if (opposite(c) >= 0 && opposite(static_cast<uint32_t>(opposite(c))) != static_cast<int32_t>(c))
      st = Status::malformed;
  // One fan per vertex, no vertex unused, degrees within the limit.
  for (uint32_t v = 0; v < nv_ && st == Status::ok; ++v) {
    uint32_t total = 0;
    for (uint32_t x = vertex_corner_.get(v); x != kMeshNone; x = link_next[x]) ++total;
    if (total == 0) {
      st = Status::malformed;
      break;
    }
    // Clockwise to the boundary start (or all the way round).
    const uint32_t c0 = vertex_corner_.get(v);
    uint32_t c = c0;
    for (uint32_t step = 0; step <= total; ++step) {
      const int32_t o = opposite(prev(c));
      if (o < 0) break;
      c = prev(static_cast<uint32_t>(o));
      if (c == c0) break;
    }
    // Counter-clockwise from there, counting faces.
    const uint32_t start = c;
    uint32_t faces = 0;
    bool boundary = false;
    do {
      ++faces;
      if (faces > total) break;
      const int32_t o = opposite(next(c));
      if (o < 0) {
        boundary = true;
        break;
      }
      c = next(static_cast<uint32_t>(o));
    } while (c != start);
    const uint32_t degree = faces + (boundary ? 1u : 0u);
    if (faces != total || degree > max_degree_) st = Status::malformed;
    if (degree > max_degree_seen_) max_degree_seen_ = degree;
    vertex_corner_.set(v, start);  // v's list is no longer needed
  }
  arena.rewind(mark);
  return st;
}

// The walk of ring() over tables of either width (uint16_t or uint32_t
// entries, all ones = none): the loop every split and prediction runs, so
// the widths are chosen once per walk, not per entry. Returns the degree,
// with *boundary set, or 0 if the walk is malformed.
template <typename VertexIndex, typename CornerIndex>
uint32_t MeshState::walk_ring(const VertexIndex* cv, const CornerIndex* opp, uint32_t x, uint32_t c0,
                              uint32_t max_degree, uint32_t* rv, uint32_t* rc, bool* boundary) {
  constexpr CornerIndex kNone = static_cast<CornerIndex>(~CornerIndex{0});
  uint32_t c = c0, d = 0;
  *boundary = false;
  while (true) {
    if (d >= max_degree || cv[c] != x) return 0;
    const uint32_t n = next(c);
    rv[d] = cv[n];
    rc[d] = c;
    ++d;
    const CornerIndex o = opp[n];
    if (o == kNone) {
      if (d >= max_degree) return 0;
      rv[d] = cv[prev(c)];
      rc[d] = kMeshNone;
      *boundary = true;
      return d + 1;
    }
    c = next(o);
    if (c == c0) return d;
  }
}

Status MeshState::ring(uint32_t x, Ring* out, int scratch) {
  if (x >= nv_) return Status::malformed;
  const uint32_t c0 = vertex_corner_.get(x);
  if (c0 == kMeshNone || c0 >= 3 * nt_) return Status::malformed;
  uint32_t* rv = ring_vertex_[scratch];
  uint32_t* rc = ring_corner_[scratch];
  bool boundary = false;
  const uint16_t* cv16 = corner_vertex_.narrow();
  const uint16_t* op16 = opposite_.narrow();
  uint32_t d;
  if (cv16 != nullptr && op16 != nullptr)
    d = walk_ring(cv16, op16, x, c0, max_degree_, rv, rc, &boundary);
  else if (cv16 != nullptr)
    d = walk_ring(cv16, opposite_.wide(), x, c0, max_degree_, rv, rc, &boundary);
  else if (op16 != nullptr)
    d = walk_ring(corner_vertex_.wide(), op16, x, c0, max_degree_, rv, rc, &boundary);
  else
    d = walk_ring(corner_vertex_.wide(), opposite_.wide(), x, c0, max_degree_, rv, rc, &boundary);
  if (d == 0 || (!boundary && d < 3)) return Status::malformed;
  if (d > max_degree_seen_) max_degree_seen_ = d;
  out->degree = d;
  out->boundary = boundary;
  out->vertex = rv;
  out->corner = rc;
  return Status::ok;
}

bool MeshState::choice_valid(const Ring& r, const SplitChoice& c) {
  const uint32_t d = r.degree;
  if (!r.boundary) return c.kind == SplitKind::interior && c.first < d && c.count >= 1 && c.count <= d - 1;
  switch (c.kind) {
    case SplitKind::interior: return c.count >= 1 && c.first <= d - 1 && c.count <= d - 1 - c.first;
    case SplitKind::tail: return c.first <= d - 1 && c.count == d - 1 - c.first;
    case SplitKind::head: return c.first == 0 && c.count <= d - 1;
  }
  return false;
}

void MeshState::fix_vertex_corner(uint32_t x, uint32_t hint) {
  uint32_t c = vertex_corner_.get(x);
  if (c >= 3 * nt_ || corner_vertex(c) != x) c = hint;
  const uint32_t c0 = c;
  for (uint32_t step = 0; step <= max_degree_; ++step) {
    const int32_t o = opposite(prev(c));
    if (o < 0) break;
    const uint32_t n = prev(static_cast<uint32_t>(o));
    if (n == c0) {
      c = c0;  // interior: keep the corner we had
      break;
    }
    c = n;
  }
  vertex_corner_.set(x, c);
}

Status MeshState::split(uint32_t u, const SplitChoice& ch, uint32_t* new_vertex) {
  Ring r;
  Status st = ring(u, &r, 0);
  if (st != Status::ok) return st;
  if (!choice_valid(r, ch)) return Status::malformed;
  const uint32_t d = r.degree;
  const bool has_f = ch.kind != SplitKind::head;
  const bool has_l = ch.kind != SplitKind::tail;
  const uint32_t new_faces = (has_f ? 1u : 0u) + (has_l ? 1u : 0u);
  if (nv_ >= cap_v_ || nt_ + new_faces > cap_t_) return Status::malformed;
  const uint32_t faces = r.faces();
  auto face = [&](uint32_t j) { return r.boundary ? j : j % d; };
  const uint32_t first = ch.first, count = ch.count;
  const uint32_t f_vertex = has_f ? r.vertex[first] : kMeshNone;
  const uint32_t l_vertex = has_l ? r.vertex[r.boundary ? first + count : (first + count) % d] : kMeshNone;
  // Neighbouring faces of the arc (kMeshNone where u's fan ends).
  const uint32_t c_first = count ? r.corner[face(first)] : kMeshNone;
  const uint32_t c_last = count ? r.corner[face(first + count - 1)] : kMeshNone;
  uint32_t c_after = kMeshNone, c_before = kMeshNone;
  if (r.boundary) {
    if (first + count <= faces - 1 && faces > 0) c_after = r.corner[first + count];
    if (first >= 1) c_before = r.corner[first - 1];
  } else {
    c_after = r.corner[(first + count) % d];
    c_before = r.corner[(first + d - 1) % d];
  }
  const uint32_t v = nv_++;
  pos_[3 * v] = pos_[3 * v + 1] = pos_[3 * v + 2] = 0;
  vertex_corner_.set(v, kMeshNone);
  for (uint32_t i = 0; i < count; ++i) corner_vertex_.set(r.corner[face(first + i)], v);
  auto corner = [](uint32_t c) { return c == kMeshNone ? -1 : static_cast<int32_t>(c); };
  int32_t a0 = -1, a1 = -1, a2 = -1, b0 = -1, b1 = -1, b2 = -1;
  if (has_l) {
    const uint32_t t = nt_++;
    corner_vertex_.set(3 * t, v);
    corner_vertex_.set(3 * t + 1, l_vertex);
    corner_vertex_.set(3 * t + 2, u);
    a0 = static_cast<int32_t>(3 * t);
    a1 = a0 + 1;
    a2 = a0 + 2;
    for (uint32_t k = 0; k < 3; ++k) set_opp(3 * t + k, -1);
  }
  if (has_f) {
    const uint32_t t = nt_++;
    corner_vertex_.set(3 * t, v);
    corner_vertex_.set(3 * t + 1, u);
    corner_vertex_.set(3 * t + 2, f_vertex);
    b0 = static_cast<int32_t>(3 * t);
    b1 = b0 + 1;
    b2 = b0 + 2;
    for (uint32_t k = 0; k < 3; ++k) set_opp(3 * t + k, -1);
  }
  if (has_l) {
    // Edge (v, L) with the last moved face, edge (L, u) with the face after.
    link(a2, c_last == kMeshNone ? -1 : corner(next(c_last)));
    link(a0, c_after == kMeshNone ? -1 : corner(prev(c_after)));
  }
  if (has_f) {
    // Edge (u, F) with the face before, edge (F, v) with the first moved face.
    link(b0, c_before == kMeshNone ? -1 : corner(next(c_before)));
    link(b1, c_first == kMeshNone ? -1 : corner(prev(c_first)));
  }
  if (has_l && has_f) link(a1, b2);
  // Corners the walks start from: boundary vertices start at their first face.
  const uint32_t v_hint = static_cast<uint32_t>(has_l ? a0 : b0);
  const uint32_t u_hint = static_cast<uint32_t>(has_l ? a2 : b1);
  vertex_corner_.set(v, v_hint);
  fix_vertex_corner(v, v_hint);
  fix_vertex_corner(u, u_hint);
  if (has_f) fix_vertex_corner(f_vertex, static_cast<uint32_t>(b2));
  if (has_l) fix_vertex_corner(l_vertex, static_cast<uint32_t>(a1));
  *new_vertex = v;
  return Status::ok;
}

// The area centroid of an interior ring in Q8: the fan of triangles
// (c, r_j, r_j+1) around the vertex centroid c = s / d, each weighted by
// its area (the largest component of the cross product, which does as well
// as its length and needs no square root) at its centroid. With
// A_j = d r_j - s (exact), triangle j's centroid is c + (A_j + A_j+1) / 3d
// and its weight |A_j x A_j+1| / d^2; the weights are shifted down to at
// most 2^20 so every sum below fits 64 bits. false for a boundary ring or a
// flat fan (the caller then uses c).
bool MeshState::area_centroid_q8(const Ring& r, const int64_t s[3], int64_t out[3]) const {
  const uint32_t d = r.degree;
  if (r.boundary || d < 3) return false;
  int64_t wgt[kMeshMaxDegree + 1];
  int64_t biggest = 0;
  for (uint32_t j = 0; j < d; ++j) {
    const uint16_t* p0 = pos_ + 3 * r.vertex[j];
    const uint16_t* p1 = pos_ + 3 * r.vertex[(j + 1) % d];
    int64_t a0[3], a1[3];
    for (int k = 0; k < 3; ++k) {
      a0[k] = int64_t{d} * p0[k] - s[k];
      a1[k] = int64_t{d} * p1[k] - s[k];
    }
    int64_t c0 = a0[1] * a1[2] - a0[2] * a1[1], c1 = a0[2] * a1[0] - a0[0] * a1[2], c2 = a0[0] * a1[1] - a0[1] * a1[0];
    if (c0 < 0) c0 = -c0;
    if (c1 < 0) c1 = -c1;
    if (c2 < 0) c2 = -c2;
    wgt[j] = c0 > c1 ? (c0 > c2 ? c0 : c2) : (c1 > c2 ? c1 : c2);
    if (wgt[j] > biggest) biggest = wgt[j];
  }
  if (biggest == 0) return false;
  int shift = 0;
  while ((biggest >> shift) >= (int64_t{1} << 20)) ++shift;
  int64_t sum_w = 0, num[3] = {0, 0, 0};
  for (uint32_t j = 0; j < d; ++j) {
    const int64_t w = wgt[j] >> shift;
    sum_w += w;
    const uint16_t* p0 = pos_ + 3 * r.vertex[j];
    const uint16_t* p1 = pos_ + 3 * r.vertex[(j + 1) % d];
    for (int k = 0; k < 3; ++k) num[k] += w * (int64_t{d} * (int64_t{p0[k]} + p1[k]) - 2 * s[k]);
  }
  if (sum_w == 0) return false;
  // a = s / d + num / (3 d sum_w) = (3 sum_w s + num) / (3 d sum_w), in Q8.
  const int64_t den = 3 * int64_t{d} * sum_w;
  for (int k = 0; k < 3; ++k) out[k] = div_round((3 * sum_w * s[k] + num[k]) * 256, den);
  return true;
}

Status MeshState::predict(uint32_t v, MeshPredictor predictor, int weight_q4, int32_t out[3]) {
  Ring r;
  Status st = ring(v, &r, 0);
  if (st != Status::ok) return st;
  const uint32_t d = r.degree;
  int64_t pred[3] = {0, 0, 0};
  if (predictor == MeshPredictor::laplacian) {
    // Eq. 13: w = 1/m Σ_j (u_j + L(u_j)) = 1/m Σ_j centroid(ring(u_j) \ {v}),
    // each centroid kept in Q8 so the sum is not rounded per term.
    constexpr int kCentroidFracBits = 8;
    int64_t acc[3] = {0, 0, 0};
    for (uint32_t j = 0; j < d; ++j) {
      const uint32_t uj = r.vertex[j];
      Ring rj;
      st = ring(uj, &rj, 1);
      if (st != Status::ok) return st;
      int64_t s[3] = {0, 0, 0};
      uint32_t m = 0;
      for (uint32_t k = 0; k < rj.degree; ++k) {
        const uint32_t w = rj.vertex[k];
        if (w == v) continue;
        for (int a = 0; a < 3; ++a) s[a] += pos_[3 * w + a];
        ++m;
      }
      for (int a = 0; a < 3; ++a)
        acc[a] += m ? div_round(s[a] << kCentroidFracBits, m) : int64_t{pos_[3 * uj + a]} << kCentroidFracBits;
    }
    for (int a = 0; a < 3; ++a) pred[a] = div_round(acc[a], int64_t{d} << kCentroidFracBits);
  } else {
    // Centroid c of the ring, and the mean p of the parallelogram
    // predictions r_j + r_{j+1} - o_j across each ring edge that has a face
    // on the far side; prediction c + w (p - c), w = weight_q4 / 16.
    constexpr int kWeightFracBits = 4;
    int64_t s[3] = {0, 0, 0}, p[3] = {0, 0, 0};
    uint32_t m = 0;
    for (uint32_t j = 0; j < d; ++j)
      for (int a = 0; a < 3; ++a) s[a] += pos_[3 * r.vertex[j] + a];
    for (uint32_t j = 0; j < r.faces(); ++j) {
      const int32_t o = opposite(r.corner[j]);
      if (o < 0) continue;
      const uint32_t ov = corner_vertex(static_cast<uint32_t>(o));
      const uint32_t a_v = r.vertex[j], b_v = r.vertex[(j + 1) % d];
      for (int a = 0; a < 3; ++a)
        p[a] += int64_t{pos_[3 * a_v + a]} + pos_[3 * b_v + a] - pos_[3 * ov + a];
      ++m;
    }
    const int64_t w = weight_q4 < 0 ? 0 : (weight_q4 > 16 ? 16 : weight_q4);
    int64_t area_q8[3];
    const bool area = predictor == MeshPredictor::area && area_centroid_q8(r, s, area_q8);
    for (int a = 0; a < 3; ++a) {
      if (area) {
        // a + w (p - a): ((16 - w) a m + w p) / (16 m), a in Q8.
        const int64_t num = ((int64_t{1} << kWeightFracBits) - w) * area_q8[a] * m + w * (p[a] << 8);
        pred[a] = m == 0 ? div_round(area_q8[a], int64_t{1} << 8)
                         : div_round(num, (int64_t{m} << kWeightFracBits) << 8);
      } else if (m == 0 || w == 0) {
        pred[a] = div_round(s[a], d);
      } else {
        // ((16 - w) s / d + w p / m) / 16 over the common denominator 16 d m.
        const int64_t num = ((int64_t{1} << kWeightFracBits) - w) * s[a] * m + w * p[a] * d;
        pred[a] = div_round(num, (int64_t{d} * m) << kWeightFracBits);
      }
    }
  }
  const int64_t top = (int64_t{1} << bits_) - 1;
  for (int a = 0; a < 3; ++a) out[a] = static_cast<int32_t>(pred[a] < 0 ? 0 : (pred[a] > top ? top : pred[a]));
  return Status::ok;
}

int32_t mesh_log2_q4(uint64_t x) {
  if (x == 0) return 0;
  const int n = 63 - __builtin_clzll(x);
  // Four bits below the leading one, linear between powers of two.
  const uint32_t frac = static_cast<uint32_t>(n >= 4 ? (x >> (n - 4)) & 15 : (x << (4 - n)) & 15);
  return 16 * n + static_cast<int32_t>(frac);
}

void MeshState::face_llr(const Ring& r, uint32_t u, int32_t* llr) const {
  // A face that came from the collapsed vertex v has its apex moved from v
  // to u: its two sides at u are long for its base (about 5:1 in squared
  // length against 2:1 for a well-shaped face). The score is the log2 ratio
  // in Q4 minus kMeshElongationBias: positive favours "moves to v".
  const uint32_t d = r.degree;
  for (uint32_t j = 0; j < r.faces(); ++j) {
    const uint32_t a = r.vertex[j], b = r.vertex[(j + 1) % d];
    uint64_t ea = 0, eb = 0, base = 0;
    for (int k = 0; k < 3; ++k) {
      const int64_t da = int64_t{pos_[3 * a + k]} - pos_[3 * u + k];
      const int64_t db = int64_t{pos_[3 * b + k]} - pos_[3 * u + k];
      const int64_t dab = int64_t{pos_[3 * a + k]} - pos_[3 * b + k];
      ea += static_cast<uint64_t>(da * da);
      eb += static_cast<uint64_t>(db * db);
      base += static_cast<uint64_t>(dab * dab);
    }
    llr[j] = mesh_log2_q4(ea + eb) - mesh_log2_q4(base ? base : 1) - kMeshElongationBias;
  }
}

namespace {

// Candidate (v ring sum sv over nv vertices, u's new ring sum su over nu
// vertices without v): v is predicted at sv / nv and the score is the
// squared distance from u to the centroid of its new ring with v there.
// The offset's numerator over nv (nu + 1) is compared exactly when all
// candidates share the denominator and the squares fit 64 bits (degree <=
// 64); otherwise it is brought to a common Q4 scale.
int64_t balance_score(const int64_t uq[3], const int64_t sv[3], uint32_t nv, const int64_t su[3], uint32_t nu,
                      bool exact) {
  constexpr int64_t kOffsetScale = 16;  // Q4
  int64_t sc = 0;
  for (int a = 0; a < 3; ++a) {
    int64_t num = su[a] * nv + sv[a] - uq[a] * nv * (nu + 1);
    if (!exact) num = div_floor(num * kOffsetScale, int64_t{nv} * (nu + 1));
    sc += num * num;
  }
  return sc;
}

constexpr uint32_t kExactDegree = 64;

}  // namespace


uint32_t mesh_candidate_scores(const uint16_t* pos, const Ring& r, uint32_t u, SplitKind kind, uint32_t count,
                               int64_t* score, bool common_scale) {
  // Each candidate predicts v at the centroid of its would-be ring and
  // scores how far u would then sit from the centroid of its own new ring:
  // the true split leaves both vertices near the middle of their rings.
  const uint32_t d = r.degree;
  int64_t uq[3];
  for (int a = 0; a < 3; ++a) uq[a] = pos[3 * u + a];
  // Prefix sums of the ring (at most 1025 * 65535 < 2^27: int32), so a
  // cyclic arc r_i .. r_{i+len-1} (i < 2d, len <= d) is one or two differences.
  int32_t prefix[3][kMeshMaxDegree + 1];
  for (int a = 0; a < 3; ++a) {
    prefix[a][0] = 0;
    for (uint32_t t = 0; t < d; ++t) prefix[a][t + 1] = prefix[a][t] + pos[3 * r.vertex[t] + a];
  }
  auto arc_sum = [&](uint32_t i, uint32_t len, int a) -> int64_t {
    if (i >= d) i -= d;
    if (i + len <= d) return prefix[a][i + len] - prefix[a][i];
    return (prefix[a][d] - prefix[a][i]) + prefix[a][i + len - d];
  };
  const bool exact = !common_scale && d <= kExactDegree;
  uint32_t n = 0;
  int64_t sv[3], su[3];
  if (kind == SplitKind::interior) {
    if (count < 1 || count + 1 > d) return 0;
    if (!r.boundary) {
      for (uint32_t first = 0; first < d; ++first) {
        for (int a = 0; a < 3; ++a) {
          sv[a] = uq[a] + arc_sum(first, count + 1, a);
          su[a] = arc_sum(first + count, d - count + 1, a);
        }
        score[n++] = balance_score(uq, sv, count + 2, su, d - count + 1, exact);
      }
    } else {
      for (uint32_t first = 0; first + count <= d - 1; ++first) {
        for (int a = 0; a < 3; ++a) {
          sv[a] = uq[a] + arc_sum(first, count + 1, a);
          su[a] = arc_sum(0, first + 1, a) + arc_sum(first + count, d - first - count, a);
        }
        score[n++] = balance_score(uq, sv, count + 2, su, d - count + 1, exact);
      }
    }
  } else if (kind == SplitKind::tail) {
    for (uint32_t first = 0; first < d; ++first) {
      for (int a = 0; a < 3; ++a) {
        sv[a] = uq[a] + arc_sum(first, d - first, a);
        su[a] = arc_sum(0, first + 1, a);
      }
      score[n++] = balance_score(uq, sv, d - first + 1, su, first + 1, false);
    }
  } else {
    for (uint32_t k = 0; k < d; ++k) {
      for (int a = 0; a < 3; ++a) {
        sv[a] = uq[a] + arc_sum(0, k + 1, a);
        su[a] = arc_sum(k, d - k, a);
      }
      score[n++] = balance_score(uq, sv, k + 2, su, d - k, false);
    }
  }
  return n;
}

uint32_t MeshState::candidate_scores(const Ring& r, uint32_t u, SplitKind kind, uint32_t count,
                                     int64_t* score) const {
  return mesh_candidate_scores(pos_, r, u, kind, count, score, false);
}

// --- Contexts -------------------------------------------------------------------

void MeshContexts::reset() {
  // Every context starts at p0 = 1/2 with the default adaptation (slower or
  // faster adaptation changed the bunny's size by under 0.1 %).
  arith_init_contexts(c, kCount);
}

uint32_t mesh_mark_context(const MeshState& s, uint32_t x, const Ring& ring, const uint8_t* marks) {
  const uint32_t d = ring.degree + (ring.boundary ? 1u : 0u);
  const uint32_t deg = d <= 4 ? 0 : (d >= 10 ? 6 : d - 4);
  uint32_t nb = 0;
  for (uint32_t j = 0; j < ring.degree; ++j) {
    const uint32_t w = ring.vertex[j];
    if (w < x && (marks[w >> 3] >> (w & 7)) & 1) ++nb;
  }
  if (nb > 2) nb = 2;
  // The best run of elongated faces (largest sum of face scores over an
  // arc a split could move: not wrapping past a boundary, not the whole
  // fan of an interior vertex): a vertex that absorbed a neighbour has one.
  int32_t llr[kMeshMaxDegree + 1];
  s.face_llr(ring, x, llr);
  const uint32_t faces = ring.faces();
  int64_t best = 0;
  for (uint32_t first = 0; first < faces; ++first) {
    const uint32_t longest = ring.boundary ? faces - first : faces - 1;
    int64_t sum = 0;
    for (uint32_t i = 0; i < longest; ++i) {
      sum += llr[(first + i) % faces];
      if (sum > best) best = sum;
    }
  }
  const uint32_t shape = best <= 0 ? 0 : (best <= 16 ? 1 : (best <= 48 ? 2 : 3));
  return (deg * MeshContexts::kMarkNeighbours + nb) * MeshContexts::kMarkShape + shape;
}

GeoFrame mesh_geo_frame(const MeshState& s, uint32_t, const Ring& ring) {
  const uint16_t* p = s.positions();
  const uint32_t d = ring.degree;
  int64_t n[3] = {0, 0, 0};
  uint64_t perimeter = 0;
  const uint32_t r0 = ring.vertex[0];
  for (uint32_t j = 0; j < d; ++j) {
    const uint32_t a = ring.vertex[j], b = ring.vertex[(j + 1) % d];
    int64_t ea[3], eb[3];
    for (int k = 0; k < 3; ++k) {
      ea[k] = int64_t{p[3 * a + k]} - p[3 * r0 + k];
      eb[k] = int64_t{p[3 * b + k]} - p[3 * r0 + k];
      perimeter += static_cast<uint64_t>(abs64(int64_t{p[3 * b + k]} - p[3 * a + k]));
    }
    n[0] += ea[1] * eb[2] - ea[2] * eb[1];
    n[1] += ea[2] * eb[0] - ea[0] * eb[2];
    n[2] += ea[0] * eb[1] - ea[1] * eb[0];
  }
  GeoFrame f;
  int best = 0;
  for (int k = 1; k < 3; ++k)
    if (abs64(n[k]) > abs64(n[best])) best = k;
  f.normal_axis = best;
  f.flip = n[best] < 0;
  // Mean L1 edge length of the ring polygon, as a log2 class.
  const uint64_t mean = perimeter / d;
  uint32_t cls = 0;
  for (uint64_t m = mean; m > 1 && cls < MeshContexts::kGeoScales - 1; m >>= 1) ++cls;
  f.scale = cls;
  return f;
}

}  // namespace vds
