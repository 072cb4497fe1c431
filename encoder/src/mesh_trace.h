// vds encoder, progressive mesh coding (mesh_encoder.cpp and its stages):
// the trace of binarised coding operations each level is recorded as, the
// entropy coders that replay it, the tail's closed mesh, and the Encoder
// that runs the stages. Internal to the encoder library.
#pragma once
#include "vds/enc/mesh_encoder.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <unordered_map>
#include <stdexcept>
#include "vds/enc/arith_encoder.h"
#include "vds/enc/bitwriter.h"
#include "vds/enc/huffman_build.h"
#include "vds/enc/stream_writer.h"
#include <array>
#include <string>
#include <vector>

namespace vds::enc::mesh_trace {


enum class OpKind : uint8_t { bit, bypass, unary, ueg, sgn, hsym, raw, ue, table };
enum Table : uint8_t { kTabDelta = 0, kTabShape = 1, kTabPos = 2, kTabGeo = 3, kTables = 4 };

// What an operation codes, for MeshBitBreakdown.
enum Cat : uint8_t { kCatBase, kCatFlags, kCatShape, kCatRotation, kCatGeoNormal, kCatGeo, kCatTailConn, kCatTailGeo, kCats };

struct Op {
  OpKind kind;
  uint8_t cat = kCatBase;
  uint8_t table = 0;
  uint16_t nctx = 0;
  uint32_t ctx = 0;
  uint32_t ctx2 = 0;
  int32_t value = 0;
  uint32_t max = 0;  // unary max, ueg/signed cutoff, raw/bypass width
  int k = 0;
};

// The coded decisions of one segment (the base or one level), per item.
struct Segment {
  bool base = false;
  bool tail = false;  // the single-rate tail (MSHT; TailContexts)
  TailCounts counts;
  uint32_t level = 0;
  uint32_t items = 0;
  uint32_t dv = 0, dt = 0;
  int weight_q4 = 0;
  std::vector<Op> conn, geom;
  std::vector<uint32_t> conn_at{0}, geom_at{0};  // op ranges per item
  CanonicalCode codes[kTables];
  std::vector<uint8_t> table_lengths[kTables];

  void end_item() {
    conn_at.push_back(static_cast<uint32_t>(conn.size()));
    geom_at.push_back(static_cast<uint32_t>(geom.size()));
    ++items;
  }
};

inline Op with(Cat c, Op o) {
  o.cat = c;
  return o;
}
inline Op op_bit(uint32_t ctx, int bin) {
  Op o{OpKind::bit};
  o.ctx = ctx;
  o.value = bin;
  return o;
}
inline Op op_bypass(uint32_t value, int n) {
  Op o{OpKind::bypass};
  o.value = static_cast<int32_t>(value);
  o.max = static_cast<uint32_t>(n);
  return o;
}
inline Op op_unary(uint32_t ctx, uint32_t nctx, uint32_t value, uint32_t max) {
  Op o{OpKind::unary};
  o.ctx = ctx;
  o.nctx = static_cast<uint16_t>(nctx);
  o.value = static_cast<int32_t>(value);
  o.max = max;
  return o;
}
inline Op op_ueg(uint32_t ctx, uint32_t nctx, uint32_t value, uint32_t cutoff, int k) {
  Op o{OpKind::ueg};
  o.ctx = ctx;
  o.nctx = static_cast<uint16_t>(nctx);
  o.value = static_cast<int32_t>(value);
  o.max = cutoff;
  o.k = k;
  return o;
}
inline Op op_signed(uint32_t zero_ctx, uint32_t mag_ctx, uint32_t nctx, int32_t value, uint32_t cutoff, int k) {
  Op o{OpKind::sgn};
  o.ctx = zero_ctx;
  o.ctx2 = mag_ctx;
  o.nctx = static_cast<uint16_t>(nctx);
  o.value = value;
  o.max = cutoff;
  o.k = k;
  return o;
}
inline Op op_hsym(uint8_t table, uint32_t sym) {
  Op o{OpKind::hsym};
  o.table = table;
  o.value = static_cast<int32_t>(sym);
  return o;
}
inline Op op_raw(uint32_t value, int n) {
  Op o{OpKind::raw};
  o.value = static_cast<int32_t>(value);
  o.max = static_cast<uint32_t>(n);
  return o;
}
inline Op op_ue(uint32_t value) {
  Op o{OpKind::ue};
  o.value = static_cast<int32_t>(value);
  return o;
}
inline Op op_table(uint8_t table) {
  Op o{OpKind::table};
  o.table = table;
  return o;
}

inline void put_varint(std::vector<uint8_t>& out, uint32_t v) {
  do {
    uint8_t b = v & 0x7F;
    v >>= 7;
    if (v) b |= 0x80;
    out.push_back(b);
  } while (v);
}
inline size_t varint_size(uint32_t v) {
  size_t n = 1;
  while (v >= 0x80) {
    v >>= 7;
    ++n;
  }
  return n;
}

inline uint32_t zigzag(int32_t v) { return v >= 0 ? static_cast<uint32_t>(v) << 1 : (static_cast<uint32_t>(-v) << 1) - 1; }

inline uint32_t rank_of(const int64_t* score, uint32_t n, uint32_t i) {
  uint32_t better = 0;
  for (uint32_t j = 0; j < n; ++j)
    if (score[j] < score[i] || (score[j] == score[i] && j < i)) ++better;
  return better;
}

// The paper's code-length table: alphabet size, then per symbol the
// difference from the previous length: 0 / 1 0^d 1 / 1 1^d 0.
inline void write_length_table(BitWriter& bw, const std::vector<uint8_t>& lengths) {
  bw.put_ue(static_cast<uint32_t>(lengths.size()));
  int prev = 0;
  for (uint8_t l : lengths) {
    const int d = static_cast<int>(l) - prev;
    prev = l;
    if (d == 0) {
      bw.put_bit(0);
    } else if (d > 0) {
      bw.put_bit(1);
      for (int i = 0; i < d; ++i) bw.put_bit(0);
      bw.put_bit(1);
    } else {
      bw.put_bit(1);
      for (int i = 0; i < -d; ++i) bw.put_bit(1);
      bw.put_bit(0);
    }
  }
}

// Entropy coders of one chunk substream.
struct Coder {
  bool arith = true;
  ArithEncoder ae;
  BitWriter bw;
  bool used = false;
  size_t size() const {
    if (!used) return 0;
    return arith ? ae.finished_size() : (bw.bit_count() + 7) / 8;
  }
  std::vector<uint8_t> finish() {
    if (!used) return {};
    return arith ? ae.finish() : bw.finish();
  }
};

inline uint32_t ue_bits(uint32_t v) {
  int n = 0;
  while ((uint64_t{v} + 1) >> (n + 1)) ++n;
  return static_cast<uint32_t>(2 * n + 1);
}

inline uint32_t length_table_bits(const std::vector<uint8_t>& lengths) {
  uint32_t bits = ue_bits(static_cast<uint32_t>(lengths.size()));
  int prev = 0;
  for (uint8_t l : lengths) {
    const int d = static_cast<int>(l) - prev;
    prev = l;
    bits += d == 0 ? 1 : static_cast<uint32_t>(2 + (d > 0 ? d : -d));
  }
  return bits;
}

// Codes one operation; returns its cost in bits (the arithmetic coder's
// estimate from the context states before coding, exact for Huffman).
inline double replay(const Op& o, Coder& c, ArithContext* cc, const Segment& seg) {
  c.used = true;
  double bits = 0;
  switch (o.kind) {
    case OpKind::bit: bits = arith_bin_cost_q8(cc[o.ctx], o.value); break;
    case OpKind::unary: bits = arith_cost_unary_q8(cc + o.ctx, o.nctx, static_cast<uint32_t>(o.value), o.max); break;
    case OpKind::ueg:
      bits = arith_cost_ueg_q8(cc + o.ctx, o.nctx, static_cast<uint32_t>(o.value), o.max, o.k);
      break;
    case OpKind::sgn: bits = arith_cost_signed_q8(cc[o.ctx], cc + o.ctx2, o.nctx, o.value, o.max, o.k); break;
    case OpKind::bypass: bits = o.max * double(kCostOneBitQ8); break;
    case OpKind::hsym: bits = seg.codes[o.table].lengths[static_cast<size_t>(o.value)] * double(kCostOneBitQ8); break;
    case OpKind::raw: bits = o.max * double(kCostOneBitQ8); break;
    case OpKind::ue: bits = ue_bits(static_cast<uint32_t>(o.value)) * double(kCostOneBitQ8); break;
    case OpKind::table: bits = length_table_bits(seg.table_lengths[o.table]) * double(kCostOneBitQ8); break;
  }
  bits /= double(kCostOneBitQ8);
  switch (o.kind) {
    case OpKind::bit: c.ae.encode_bit(cc[o.ctx], o.value); break;
    case OpKind::bypass: c.ae.encode_bits_bypass(static_cast<uint32_t>(o.value), static_cast<int>(o.max)); break;
    case OpKind::unary: c.ae.encode_unary(cc + o.ctx, o.nctx, static_cast<uint32_t>(o.value), o.max); break;
    case OpKind::ueg: c.ae.encode_ueg(cc + o.ctx, o.nctx, static_cast<uint32_t>(o.value), o.max, o.k); break;
    case OpKind::sgn: c.ae.encode_signed(cc[o.ctx], cc + o.ctx2, o.nctx, o.value, o.max, o.k); break;
    case OpKind::hsym: seg.codes[o.table].write(c.bw, static_cast<size_t>(o.value)); break;
    case OpKind::raw: c.bw.put_bits(static_cast<uint32_t>(o.value), static_cast<int>(o.max)); break;
    case OpKind::ue: c.bw.put_ue(static_cast<uint32_t>(o.value)); break;
    case OpKind::table: write_length_table(c.bw, seg.table_lengths[o.table]); break;
  }
  return bits;
}


// The input mesh closed for the tail's traversal: every hole fanned to a
// dummy vertex (nv + hole index), the corner table built over both.
struct ClosedMesh {
  std::vector<uint32_t> cv;  // corner vertex
  std::vector<int32_t> opp;  // opposite corner
  uint32_t real_t = 0, holes = 0;
  uint32_t max_degree = 0;  // largest ring of the real mesh
};

// "" or why the tail's traversal cannot take the mesh.
inline std::string close_mesh(uint32_t nv, const std::vector<std::array<uint32_t, 3>>& tris, ClosedMesh* out) {
  ClosedMesh& m = *out;
  m.real_t = static_cast<uint32_t>(tris.size());
  for (const auto& t : tris) m.cv.insert(m.cv.end(), t.begin(), t.end());
  auto key = [](uint32_t a, uint32_t b) { return uint64_t{a} << 32 | b; };
  std::unordered_map<uint64_t, uint32_t> edge;  // directed edge n(c) -> p(c) of corner c
  auto add_edges = [&](uint32_t from) {
    for (uint32_t c = from; c < m.cv.size(); ++c)
      if (!edge.emplace(key(m.cv[MeshState::next(c)], m.cv[MeshState::prev(c)]), c).second) return false;
    return true;
  };
  if (!add_edges(0)) return "an edge used twice in one direction";
  // Border edges a -> b (no b -> a), chained into holes by their start.
  std::unordered_map<uint32_t, uint32_t> border_from;
  for (uint32_t c = 0; c < m.cv.size(); ++c) {
    const uint32_t a = m.cv[MeshState::next(c)], b = m.cv[MeshState::prev(c)];
    if (edge.count(key(b, a)) == 0 && !border_from.emplace(a, c).second) return "a vertex on two holes";
  }
  std::vector<uint32_t> ring_size(nv, 0);
  for (uint32_t v : m.cv) ++ring_size[v];
  for (const auto& [a, c] : border_from) ++ring_size[a];
  for (uint32_t n : ring_size) m.max_degree = std::max(m.max_degree, n);
  std::unordered_map<uint32_t, bool> done;
  std::vector<uint32_t> starts;
  for (const auto& [a, c] : border_from) starts.push_back(a);
  std::sort(starts.begin(), starts.end());
  for (uint32_t a0 : starts) {
    if (done[a0]) continue;
    const uint32_t d = nv + m.holes++;
    uint32_t a = a0, len = 0;
    do {
      done[a] = true;
      const auto it = border_from.find(a);
      if (it == border_from.end()) return "a hole that does not close";
      const uint32_t b = m.cv[MeshState::prev(it->second)];
      m.cv.insert(m.cv.end(), {b, a, d});
      a = b;
      if (++len > border_from.size()) return "a hole that does not close";
    } while (a != a0);
    if (len < 3) return "a hole of two edges";
  }
  if (!add_edges(3 * m.real_t)) return "a hole that touches itself";
  m.opp.assign(m.cv.size(), -1);
  for (uint32_t c = 0; c < m.cv.size(); ++c) {
    const auto it = edge.find(key(m.cv[MeshState::prev(c)], m.cv[MeshState::next(c)]));
    if (it == edge.end()) return "an edge left open after closing the holes";
    m.opp[c] = static_cast<int32_t>(it->second);
  }
  // Every vertex one fan.
  std::vector<uint32_t> fan(nv + m.holes, 0);
  for (uint32_t c = 0; c < m.cv.size(); ++c) ++fan[m.cv[c]];
  for (uint32_t c0 = 0; c0 < m.cv.size(); ++c0) {
    // Walk c0's fan; it must hold every corner of its vertex.
    const uint32_t x = m.cv[c0];
    if (fan[x] == 0) continue;
    uint32_t c = c0, n = 0;
    do {
      c = MeshState::next(static_cast<uint32_t>(m.opp[MeshState::next(c)]));
      if (++n > fan[x]) break;
    } while (c != c0);
    if (n != fan[x]) return "a vertex where two sheets of the surface meet";
    fan[x] = 0;
  }
  return "";
}

class Encoder {
 public:
  Encoder(const Mesh& mesh, const MeshEncodeOptions& o) : mesh_(mesh), opt_(o) {}

  MeshEncodeResult run();

 private:
  void build_base(const SimplifyResult& sr);
  void trace_level(const SimplifyLevel& lvl, uint32_t level_index, Segment& seg);
  void trace_tail(const ClosedMesh& cm, uint32_t level_index, Segment& seg);
  void finish_tables(Segment& seg, const std::vector<uint64_t> freqs[kTables]);
  void emit(const Segment& seg, StreamWriter& w, MeshLevelStats& stats);
  uint32_t dec(uint32_t orig) const {
    const uint32_t d = dec_of_[orig];
    if (d == kMeshNone) throw std::logic_error("encode_mesh: vertex used before it exists");
    return d;
  }

  const Mesh& mesh_;
  MeshEncodeOptions opt_;
  Quantisation quant_;
  std::vector<std::array<int32_t, 3>> q_;
  std::vector<uint8_t> workspace_;
  Arena arena_;
  MeshState st_;
  MeshContexts ctx_{};
  TailContexts tctx_{};
  std::vector<uint32_t> dec_of_, orig_of_;
  Segment base_seg_;
  MeshBitBreakdown bits_;
};

}  // namespace vds::enc::mesh_trace
