// vds client library: the walkthrough's polygons (vds/walk_geometry.h).
#include "vds/walk_geometry.h"

#include <cstdint>

namespace vds {

static_assert(sizeof(WalkGeometryContexts) % sizeof(ArithContext) == 0, "the contexts are an array of ArithContext");

void WalkGeometryContexts::reset() {
  arith_init_contexts(&count[0], sizeof(*this) / sizeof(ArithContext));
}

bool walk_predict(const WalkVertexRing& ring, const int32_t prev[3][3], const int32_t cur[3][3], int c, int32_t out[3]) {
  // The third vertex of a triangle sharing an edge with the one before it:
  // the parallelogram across that edge (exact for the second half of a
  // rectangle).
  if (c == 2) {
    int shared[2] = {-1, -1};
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 3; ++j)
        if (prev[j][0] == cur[k][0] && prev[j][1] == cur[k][1] && prev[j][2] == cur[k][2]) shared[k] = j;
    if (shared[0] >= 0 && shared[1] >= 0 && shared[0] != shared[1]) {
      const int other = 3 - shared[0] - shared[1];
      for (int a = 0; a < 3; ++a) {
        const int64_t p = static_cast<int64_t>(cur[0][a]) + cur[1][a] - prev[other][a];
        out[a] = p < -(int64_t{1} << 30) ? -(1 << 30) : p > (int64_t{1} << 30) ? (1 << 30) : static_cast<int32_t>(p);
      }
      return true;
    }
  }
  for (int a = 0; a < 3; ++a) out[a] = ring.size > 0 ? ring.at(0)[a] : 0;
  return false;
}

uint32_t walk_get_place(ArithDecoder& d, ArithContext* bucket, uint32_t bits) {
  const uint32_t b = d.decode_unary(bucket, static_cast<int>(bits + 1), bits);
  if (!d.ok()) return 1u << bits;
  if (b <= 1) return b;
  return (1u << (b - 1)) | d.decode_bits_bypass(static_cast<int>(b - 1));
}

uint32_t walk_get_ring_index(ArithDecoder& d, ArithContext* ring_bucket) {
  return walk_get_place(d, ring_bucket, kWalkRingBits);
}

namespace {
bool same_point(const Vec3<Q16_16>& p, const Vec3<Q16_16>& q) {
  return p.x.raw() == q.x.raw() && p.y.raw() == q.y.raw() && p.z.raw() == q.z.raw();
}
}  // namespace

uint8_t walk_quad(const Vec3<Q16_16>* a, const Vec3<Q16_16>* b, int32_t tolerance) {
  // The shared edge: a's corners i, i + 1 are b's corners other than j.
  int qi = -1, qj = -1;
  for (int i = 0; i < 3 && qi < 0; ++i)
    for (int j = 0; j < 3; ++j) {
      const Vec3<Q16_16>& e0 = a[i];
      const Vec3<Q16_16>& e1 = a[(i + 1) % 3];
      const Vec3<Q16_16>& b1 = b[(j + 1) % 3];
      const Vec3<Q16_16>& b2 = b[(j + 2) % 3];
      if (((same_point(b1, e0) && same_point(b2, e1)) || (same_point(b1, e1) && same_point(b2, e0))) &&
          !same_point(b[j], a[0]) && !same_point(b[j], a[1]) && !same_point(b[j], a[2])) {
        qi = i;
        qj = j;
        break;
      }
    }
  if (qi < 0) return 0;
  // The outline p0..p3 as differences from p0, brought below 2^20 by one
  // shift (arithmetic, the same on every board).
  const Vec3<Q16_16>* p[4] = {&a[qi], &b[qj], &a[(qi + 1) % 3], &a[(qi + 2) % 3]};
  int64_t d[4][3] = {};
  uint64_t most = 0;
  for (int k = 1; k < 4; ++k)
    for (int c = 0; c < 3; ++c) {
      d[k][c] = int64_t{(&p[k]->x)[c].raw()} - (&p[0]->x)[c].raw();
      most = abs64(d[k][c]) > most ? abs64(d[k][c]) : most;
    }
  const int s = bitlen64(most) > 20 ? bitlen64(most) - 20 : 0;
  for (int k = 1; k < 4; ++k)
    for (int c = 0; c < 3; ++c) d[k][c] >>= s;
  // a's normal from p0: (p2 - p0) x (p3 - p0), each entry below 2^41.
  const int64_t n[3] = {d[2][1] * d[3][2] - d[2][2] * d[3][1], d[2][2] * d[3][0] - d[2][0] * d[3][2],
                        d[2][0] * d[3][1] - d[2][1] * d[3][0]};
  int axis = 0;
  for (int c = 1; c < 3; ++c) axis = abs64(n[c]) > abs64(n[axis]) ? c : axis;
  const uint64_t nmax = abs64(n[axis]);
  if (nmax == 0) return 0;
  // b's third corner within the tolerance of the plane: |n . d1| / |n| <=
  // tol, tested as |n . d1| <= tol max|n_c| (|n| >= max|n_c|).
  int64_t tol = tolerance >> s;
  tol = tol < 2 ? 2 : (tol > (int64_t{1} << 20) ? (int64_t{1} << 20) : tol);
  const int64_t off = n[0] * d[1][0] + n[1] * d[1][1] + n[2] * d[1][2];  // < 3 * 2^61
  if (abs64(off) > static_cast<uint64_t>(tol) * nmax) return 0;
  // Convex: the turns at the four corners all one way, in the plane of the
  // two axes other than the normal's largest.
  const int u = axis == 0 ? 1 : 0, v = axis == 2 ? 1 : 2;
  int sign = 0;
  for (int k = 0; k < 4; ++k) {
    const int64_t* q0 = d[k];
    const int64_t* q1 = d[(k + 1) % 4];
    const int64_t* q2 = d[(k + 2) % 4];
    const int64_t turn = (q1[u] - q0[u]) * (q2[v] - q1[v]) - (q1[v] - q0[v]) * (q2[u] - q1[u]);  // < 2^43
    const int t = turn > 0 ? 1 : (turn < 0 ? -1 : 0);
    if (t == 0 || (sign != 0 && t != sign)) return 0;
    sign = t;
  }
  return static_cast<uint8_t>(1 + 3 * qi + qj);
}

void WalkGeometry::join(uint32_t slot) {
  uint8_t code = 0;
  if (slot + 1 < slots_ && (filled_[slot] & 1) && (filled_[slot + 1] & 1))
    code = walk_quad(&positions_[3 * static_cast<size_t>(slot)], &positions_[3 * static_cast<size_t>(slot) + 3], quantum_);
  filled_[slot] = static_cast<uint8_t>((filled_[slot] & 1) | (code << 4));
}

size_t WalkGeometry::workspace_bytes(uint32_t slots) {
  return 3 * static_cast<size_t>(slots) * sizeof(Vec3<Q16_16>) + alignof(Vec3<Q16_16>) + 2 * slots + 2 * 2 * slots + 8 +
         kWalkVertexRing * 3 * sizeof(int32_t) + alignof(int32_t);
}

Status WalkGeometry::init(Arena& arena, uint32_t slots, int32_t quantum_raw) {
  if (slots == 0 || slots > kWalkMaxSlots || !walk_quantum_valid(quantum_raw))
    return Status::invalid_argument;
  positions_ = arena.alloc_array<Vec3<Q16_16>>(3 * static_cast<size_t>(slots));
  filled_ = arena.alloc_array<uint8_t>(slots);
  mark_ = arena.alloc_array<uint8_t>(slots);
  hot_ = arena.alloc_array<uint16_t>(slots);
  next_hot_ = arena.alloc_array<uint16_t>(slots);
  int32_t(*ring)[3] = static_cast<int32_t(*)[3]>(arena.alloc(kWalkVertexRing * 3 * sizeof(int32_t), alignof(int32_t)));
  if (!positions_ || !filled_ || !mark_ || !hot_ || !next_hot_ || !ring) return Status::workspace_too_small;
  for (uint32_t s = 0; s < slots; ++s) filled_[s] = 0, mark_[s] = 0;
  // Drawn from directly (positions()), empty slots included.
  for (size_t i = 0; i < 3 * static_cast<size_t>(slots); ++i) positions_[i] = Vec3<Q16_16>{};
  slots_ = slots;
  quantum_ = quantum_raw;
  fraction_bits_ = walk_fraction_bits(quantum_raw);
  hot_count_ = 0;
  last_slot_ = slots - 1;
  frames_ = 0;
  ctx_.reset();
  ring_.reset(ring);
  axes_.reset();
  for (int c = 0; c < 3; ++c)
    for (int a = 0; a < 3; ++a) prev_[c][a] = cur_[c][a] = INT32_MIN;
  return Status::ok;
}

Status WalkGeometry::consume(const uint8_t* payload, uint32_t size) {
  if (slots_ == 0) return Status::invalid_argument;
  ArithDecoder d;
  Status s = d.init(payload, size);
  if (s == Status::ok) s = decode(d);
  return s == Status::ok ? d.finish() : s;
}

Status WalkGeometry::decode(ArithDecoder& d) {
  if (slots_ == 0) return Status::invalid_argument;
  // Marks: 1 = hot this frame.
  for (uint32_t i = 0; i < slots_; ++i) mark_[i] = 0;
  const uint32_t sends = d.decode_ueg(ctx_.count, 4, 8, 2);
  if (!d.ok()) return d.status();
  if (sends > slots_) return Status::malformed;
  const int bits = walk_slot_bits(slots_);
  for (uint32_t k = 0; k < sends; ++k) {
    uint32_t slot;
    if (d.decode_bit(ctx_.next_slot)) {
      slot = last_slot_ + 1 == slots_ ? 0 : last_slot_ + 1;
    } else {
      slot = d.decode_bits_bypass(bits);
      if (slot >= slots_) return Status::malformed;
    }
    last_slot_ = slot;
    const int hot_now = d.decode_bit(ctx_.hot_now);
    for (int c = 0; c < 3; ++c) {
      int32_t g[3];
      if (ring_.size > 0 && d.decode_bit(ctx_.cached[c])) {
        const uint32_t i = walk_get_ring_index(d, ctx_.ring_bucket);
        if (i >= ring_.size) return d.ok() ? Status::malformed : d.status();
        for (int a = 0; a < 3; ++a) g[a] = ring_.at(i)[a];
      } else {
        int32_t pred[3];
        const bool across = walk_predict(ring_, prev_, cur_, c, pred);
        for (int a = 0; a < 3; ++a) {
          if (!across && d.decode_bit(ctx_.axis_seen[a])) {
            const uint32_t i = walk_get_place(d, ctx_.axis_bucket[a], kWalkAxisBits);
            if (i >= axes_.size[a]) return d.ok() ? Status::malformed : d.status();
            g[a] = axes_.v[a][i];
            continue;
          }
          const int32_t base = pred[a];
          // Whole map units, then the fraction in grid steps.
          const int64_t whole = d.decode_signed(ctx_.delta_zero[a], ctx_.delta_mag[a], 6, 6, 3);
          int64_t fraction = 0;
          for (int b = 0; b < fraction_bits_; ++b) fraction = (fraction << 1) | d.decode_bit(ctx_.fraction[b]);
          const int64_t v = static_cast<int64_t>(base) + whole * (int64_t{1} << fraction_bits_) + fraction;
          if (v < -(int64_t{1} << 30) || v > (int64_t{1} << 30)) return d.ok() ? Status::malformed : d.status();
          g[a] = static_cast<int32_t>(v);
        }
      }
      ring_.push(g);
      axes_.touch(g);
      for (int a = 0; a < 3; ++a) cur_[c][a] = g[a];
      for (int a = 0; a < 3; ++a) {
        const int64_t raw = static_cast<int64_t>(g[a]) * quantum_;
        if (raw < INT32_MIN || raw > INT32_MAX) return d.ok() ? Status::malformed : d.status();
        (&positions_[3 * static_cast<size_t>(slot) + static_cast<size_t>(c)].x)[a] = Q16_16::from_raw(static_cast<int32_t>(raw));
      }
    }
    if (!d.ok()) return d.status();
    for (int c = 0; c < 3; ++c)
      for (int a = 0; a < 3; ++a) prev_[c][a] = cur_[c][a];
    filled_[slot] |= 1;
    if (slot > 0) join(slot - 1);
    join(slot);
    if (hot_now) mark_[slot] = 1;
  }
  // Slots hot before that stay hot.
  for (uint32_t i = 0, stayed = 1; i < hot_count_; ++i) {
    stayed = static_cast<uint32_t>(d.decode_bit(ctx_.stays[stayed]));
    if (stayed) mark_[hot_[i]] = 1;
  }
  // Slots turning hot again without a send.
  const uint32_t again = d.decode_ueg(ctx_.again_count, 4, 8, 2);
  if (!d.ok()) return d.status();
  if (again > slots_) return Status::malformed;
  uint32_t at = 0;
  for (uint32_t k = 0; k < again; ++k) {
    const uint32_t gap = d.decode_ueg(ctx_.again_gap, 4, 8, 4);
    if (!d.ok()) return d.status();
    const uint64_t slot = static_cast<uint64_t>(k == 0 ? 0 : at + 1) + gap;
    if (slot >= slots_ || !(filled_[slot] & 1)) return Status::malformed;
    at = static_cast<uint32_t>(slot);
    mark_[at] = 1;
  }
  if (!d.ok()) return d.status();
  // The new hot set, ascending.
  uint32_t n = 0;
  for (uint32_t slot = 0; slot < slots_; ++slot)
    if (mark_[slot]) {
      if (!(filled_[slot] & 1)) return Status::malformed;
      next_hot_[n++] = static_cast<uint16_t>(slot);
    }
  uint16_t* t = hot_;
  hot_ = next_hot_;
  next_hot_ = t;
  hot_count_ = n;
  ++frames_;
  return Status::ok;
}

}  // namespace vds
