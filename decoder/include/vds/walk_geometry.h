// vds client library: the walkthrough's polygons. The client holds
// triangles in a fixed number of slots (a budget the stream declares); each
// frame's record (WFRM, vds/walk.h) starts with the geometry: it puts newly
// needed triangles into slots and says which slots are hot — the
// triangles to draw that frame. The client never
// chooses a slot: the encoder plans them (vds/enc/walk_geometry.h), so the
// client's slots mirror the encoder's at every frame by construction.
//
// The geometry, coded with the record's arithmetic decoder (vds/arith.h);
// its contexts carry over from frame to frame (docs/walkthrough.md, "The
// geometry record"):
//   sends     ueg2 count; per send: slot (a "next slot" bin, else
//             ceil(log2 slots) bypass bins), a "hot now" bin, three
//             vertices — each a "cached" bin, then its place among the
//             last kWalkVertexRing vertices named (walk_get_ring_index)
//             or a new position: across the edge it shares with the
//             triangle before it (walk_predict's parallelogram) its offset
//             from that prediction, else per axis a "seen" bin and the
//             value's place among the last kWalkAxisValues distinct values
//             named on that axis (WalkAxisValues; bit length in context
//             bins, then the bits below the leading one), or when not
//             seen the offset from the most recent vertex. An offset is
//             per axis in whole map units (signed ueg3) and then the
//             fraction in grid steps (one context bin per bit, most
//             significant first: grid points on whole units cost almost
//             nothing);
//   hot set   per slot hot in the previous frame (ascending) a "stays" bin,
//             in a context by whether the one before it stayed;
//             then ueg2 count of slots turning hot again without a send,
//             each as ueg4 of its distance from the last one.
// Vertices are integer multiples of the grid quantum (the encoder's
// choice, a power of two in Q16.16 world units).
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/arena.h"
#include "vds/arith.h"
#include "vds/container.h"
#include "vds/fixed.h"
#include "vds/status.h"

namespace vds {

constexpr uint32_t kWalkMaxSlots = 16384;
// Vertices the client remembers for reuse (a triangle's vertex may name
// one of them instead of its position): 12 bytes each.
constexpr uint32_t kWalkVertexRing = 1024;
static_assert((kWalkVertexRing & (kWalkVertexRing - 1u)) == 0, "the ring's size is a power of two");
constexpr uint32_t kWalkRingBits = 10;  // log2(kWalkVertexRing): the longest bit length of a place
static_assert((1u << kWalkRingBits) == kWalkVertexRing, "kWalkRingBits is the ring's log2");

// Distinct coordinate values remembered per axis (Quake's walls, floors
// and ceilings repeat a few planes' coordinates): 4 bytes each.
constexpr uint32_t kWalkAxisValues = 32;
constexpr uint32_t kWalkAxisBits = 5;  // log2(kWalkAxisValues): the longest bit length of a place
static_assert((1u << kWalkAxisBits) == kWalkAxisValues, "kWalkAxisBits is the list's log2");

// The contexts of the geometry coding, shared with the encoder.
struct WalkGeometryContexts {
  ArithContext count[4];
  ArithContext next_slot;
  ArithContext hot_now;
  ArithContext cached[3];     // by the vertex's place in its triangle
  ArithContext ring_bucket[kWalkRingBits + 1];  // the bit length of a vertex's place in the ring
  ArithContext delta_zero[3];  // by axis
  ArithContext delta_mag[3][6];
  ArithContext fraction[16];   // by bit of a vertex offset's fraction of a map unit
  ArithContext stays[2];  // by whether the slot before it stayed
  ArithContext axis_seen[3];
  ArithContext axis_bucket[3][kWalkAxisBits + 1];
  ArithContext again_count[4];
  ArithContext again_gap[4];
  void reset();
};

// The vertices named most recently (grid units), newest first: a ring
// that every vertex a triangle names is pushed into, a new one or one used
// again (whose older copy stays behind it; the encoder names the newest
// copy). Pushing costs the same whatever the ring holds. The storage is
// the owner's: kWalkVertexRing entries.
struct WalkVertexRing {
  int32_t (*v)[3] = nullptr;
  uint32_t size = 0;  // entries held, up to kWalkVertexRing
  uint32_t head = 0;  // where the next push goes
  void reset(int32_t (*storage)[3]) {
    v = storage;
    size = head = 0;
  }
  // Entry i, 0 the newest (i < size).
  const int32_t* at(uint32_t i) const { return v[(head - 1u - i) & (kWalkVertexRing - 1u)]; }
  void push(const int32_t p[3]) {
    int32_t* e = v[head & (kWalkVertexRing - 1u)];
    e[0] = p[0], e[1] = p[1], e[2] = p[2];
    head = (head + 1u) & (kWalkVertexRing - 1u);
    if (size < kWalkVertexRing) ++size;
  }
};

// The last kWalkAxisValues distinct values named on each axis (grid
// units), most recent first: every vertex a triangle names moves its
// three coordinates to the front of their lists.
struct WalkAxisValues {
  int32_t v[3][kWalkAxisValues];
  uint32_t size[3];
  void reset() { size[0] = size[1] = size[2] = 0; }
  // The place of `value` on `axis`, or kWalkAxisValues when not held.
  uint32_t find(int axis, int32_t value) const {
    for (uint32_t i = 0; i < size[axis]; ++i)
      if (v[axis][i] == value) return i;
    return kWalkAxisValues;
  }
  void touch(const int32_t p[3]) {
    for (int a = 0; a < 3; ++a) {
      uint32_t i = find(a, p[a]);
      if (i == kWalkAxisValues) i = size[a] < kWalkAxisValues ? size[a]++ : kWalkAxisValues - 1;
      for (; i > 0; --i) v[a][i] = v[a][i - 1];
      v[a][0] = p[a];
    }
  }
};

// A place in a list of 2^bits entries: its bit length (0 for place 0, b
// for 2^(b-1) .. 2^b - 1) as truncated unary in `bucket`'s bits + 1
// contexts, then the bits below the leading one, bypass.
uint32_t walk_get_place(ArithDecoder& d, ArithContext* bucket, uint32_t bits);

// A place in the ring: its bit length (0 for place 0, b for 2^(b-1) ..
// 2^b - 1) as truncated unary in ring_bucket's contexts, then the bits
// below the leading one, bypass. Returns the place, or kWalkVertexRing
// (and the decoder's error) when the data is bad.
uint32_t walk_get_ring_index(ArithDecoder& d, ArithContext* ring_bucket);

// The prediction of vertex c (0..2) of a triangle being sent, from what
// both ends know: for the third vertex of a triangle that shares an edge
// with the previous one sent, the parallelogram across that edge; else the
// most recent vertex (or the origin). True for the parallelogram. Shared
// with the encoder.
bool walk_predict(const WalkVertexRing& ring, const int32_t prev[3][3], const int32_t cur[3][3], int c, int32_t out[3]);

// Whether triangles a and b (world positions) form one convex planar
// quad: b shares an edge with a, its third corner lies within `tolerance`
// (raw Q16.16 world units) of a's plane, and the quad's four corners turn
// the same way. 0 if not; else 1 + 3 i + j: b's corner j lies between a's
// corners i and i + 1 (mod 3), so the quad's outline is a[i], b[j],
// a[i + 1], a[i + 2]. Integer arithmetic only (the same answer on every
// board).
uint8_t walk_quad(const Vec3<Q16_16>* a, const Vec3<Q16_16>* b, int32_t tolerance);

class WalkGeometry {
 public:
  static size_t workspace_bytes(uint32_t slots);
  // invalid_argument for 0 or more than kWalkMaxSlots slots or a quantum
  // that is not a power of two in 1..65536 (raw Q16.16: 1/65536 to 1 map
  // unit); workspace_too_small.
  Status init(Arena& arena, uint32_t slots, int32_t quantum_raw);
  // One frame's geometry from an arithmetic decoder (the first part of a
  // WFRM record, vds/walk.h). malformed: a slot outside the budget, a hot
  // slot that holds no triangle, a vertex outside Q16.16, a count beyond
  // the budget; truncated: the data ends early.
  Status decode(ArithDecoder& d);
  // The same from a payload of its own (decode, then the coder's end check:
  // malformed if bytes are left over).
  Status consume(const uint8_t* payload, uint32_t size);

  uint32_t slots() const { return slots_; }
  uint32_t hot_count() const { return hot_count_; }
  const uint16_t* hot() const { return hot_; }  // ascending
  // The slot's triangle (world positions), or nullptr if it holds none.
  const Vec3<Q16_16>* triangle(uint32_t slot) const {
    return slot < slots_ && (filled_[slot] & 1) ? &positions_[3 * static_cast<size_t>(slot)] : nullptr;
  }
  // Whether the slot's triangle and the next slot's form one quad
  // (walk_quad, within the vertex grid's quantum of one plane): 0 if not
  // (or either slot is empty), else walk_quad's outline code.
  uint8_t joins_next(uint32_t slot) const { return slot < slots_ ? static_cast<uint8_t>(filled_[slot] >> 4) : 0; }
  // Every slot's three positions (3 slots() entries; an empty slot's are
  // stale): a draw list's positions, a triangle's vertices 3 slot + k.
  const Vec3<Q16_16>* positions() const { return positions_; }
  uint32_t frames() const { return frames_; }

 private:
  uint32_t slots_ = 0;
  int32_t quantum_ = 0;
  int fraction_bits_ = 0;
  Vec3<Q16_16>* positions_ = nullptr;  // 3 per slot
  uint8_t* filled_ = nullptr;  // per slot: bit 0 holds a triangle, bits 4-7 joins_next
  void join(uint32_t slot);    // joins_next(slot) anew
  uint16_t* hot_ = nullptr;
  uint16_t* next_hot_ = nullptr;
  uint8_t* mark_ = nullptr;  // per slot, while a frame is decoded
  uint32_t hot_count_ = 0;
  uint32_t last_slot_ = 0;
  uint32_t frames_ = 0;
  WalkGeometryContexts ctx_{};
  WalkVertexRing ring_{};
  WalkAxisValues axes_{};
  int32_t prev_[3][3]{};  // the previous triangle sent (grid units)
  int32_t cur_[3][3]{};   // the one being read
};

// Grid steps in a map unit, as bits: 65536 / quantum rounded down to a
// power of two (0 for a quantum of a whole unit or more).
inline int walk_fraction_bits(int32_t quantum_raw) {
  int b = 0;
  while (b < 16 && (int32_t{65536} >> (b + 1)) >= quantum_raw) ++b;
  return b;
}

// A vertex grid quantum the client takes: a power of two in raw Q16.16
// world units, 1 (1/65536 unit) to 65536 (one unit).
constexpr bool walk_quantum_valid(int32_t quantum_raw) {
  return quantum_raw >= 1 && quantum_raw <= 65536 && (quantum_raw & (quantum_raw - 1)) == 0;
}

// Bits for a slot index in a budget of `slots` (ceil(log2 slots), at least 1).
inline int walk_slot_bits(uint32_t slots) {
  int b = 1;
  while ((1u << b) < slots) ++b;
  return b;
}

}  // namespace vds
