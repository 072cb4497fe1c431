// vds encoder: progressive mesh coding (Qin, Liu, Bao, Peng 2002, sections
// 3-4) on top of the client's MeshState. Each level is first simulated with
// the client's own split, ranking and prediction code, recording the coded
// decisions as a trace of binarised operations (context index + value); the
// trace is then entropy-coded and cut into chunks, replaying from a context
// snapshot whenever a chunk would overflow.
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

namespace vds::enc {
namespace {

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

Op with(Cat c, Op o) {
  o.cat = c;
  return o;
}
Op op_bit(uint32_t ctx, int bin) {
  Op o{OpKind::bit};
  o.ctx = ctx;
  o.value = bin;
  return o;
}
Op op_bypass(uint32_t value, int n) {
  Op o{OpKind::bypass};
  o.value = static_cast<int32_t>(value);
  o.max = static_cast<uint32_t>(n);
  return o;
}
Op op_unary(uint32_t ctx, uint32_t nctx, uint32_t value, uint32_t max) {
  Op o{OpKind::unary};
  o.ctx = ctx;
  o.nctx = static_cast<uint16_t>(nctx);
  o.value = static_cast<int32_t>(value);
  o.max = max;
  return o;
}
Op op_ueg(uint32_t ctx, uint32_t nctx, uint32_t value, uint32_t cutoff, int k) {
  Op o{OpKind::ueg};
  o.ctx = ctx;
  o.nctx = static_cast<uint16_t>(nctx);
  o.value = static_cast<int32_t>(value);
  o.max = cutoff;
  o.k = k;
  return o;
}
Op op_signed(uint32_t zero_ctx, uint32_t mag_ctx, uint32_t nctx, int32_t value, uint32_t cutoff, int k) {
  Op o{OpKind::sgn};
  o.ctx = zero_ctx;
  o.ctx2 = mag_ctx;
  o.nctx = static_cast<uint16_t>(nctx);
  o.value = value;
  o.max = cutoff;
  o.k = k;
  return o;
}
Op op_hsym(uint8_t table, uint32_t sym) {
  Op o{OpKind::hsym};
  o.table = table;
  o.value = static_cast<int32_t>(sym);
  return o;
}
Op op_raw(uint32_t value, int n) {
  Op o{OpKind::raw};
  o.value = static_cast<int32_t>(value);
  o.max = static_cast<uint32_t>(n);
  return o;
}
Op op_ue(uint32_t value) {
  Op o{OpKind::ue};
  o.value = static_cast<int32_t>(value);
  return o;
}
Op op_table(uint8_t table) {
  Op o{OpKind::table};
  o.table = table;
  return o;
}

void put_varint(std::vector<uint8_t>& out, uint32_t v) {
  do {
    uint8_t b = v & 0x7F;
    v >>= 7;
    if (v) b |= 0x80;
    out.push_back(b);
  } while (v);
}
size_t varint_size(uint32_t v) {
  size_t n = 1;
  while (v >= 0x80) {
    v >>= 7;
    ++n;
  }
  return n;
}

uint32_t zigzag(int32_t v) { return v >= 0 ? static_cast<uint32_t>(v) << 1 : (static_cast<uint32_t>(-v) << 1) - 1; }

uint32_t rank_of(const int64_t* score, uint32_t n, uint32_t i) {
  uint32_t better = 0;
  for (uint32_t j = 0; j < n; ++j)
    if (score[j] < score[i] || (score[j] == score[i] && j < i)) ++better;
  return better;
}

// The paper's code-length table: alphabet size, then per symbol the
// difference from the previous length: 0 / 1 0^d 1 / 1 1^d 0.
void write_length_table(BitWriter& bw, const std::vector<uint8_t>& lengths) {
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

uint32_t ue_bits(uint32_t v) {
  int n = 0;
  while ((uint64_t{v} + 1) >> (n + 1)) ++n;
  return static_cast<uint32_t>(2 * n + 1);
}

uint32_t length_table_bits(const std::vector<uint8_t>& lengths) {
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
double replay(const Op& o, Coder& c, ArithContext* cc, const Segment& seg) {
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
std::string close_mesh(uint32_t nv, const std::vector<std::array<uint32_t, 3>>& tris, ClosedMesh* out) {
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

void Encoder::build_base(const SimplifyResult& sr) {
  const bool arith = opt_.coder == MeshCoder::arith;
  const auto& tris = sr.base_triangles;
  // Triangles in breadth-first order over shared edges, so back references
  // stay short; vertices numbered by first use.
  std::map<std::pair<uint32_t, uint32_t>, std::vector<uint32_t>> by_edge;
  for (uint32_t f = 0; f < tris.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tris[f][k], b = tris[f][(k + 1) % 3];
      by_edge[{std::min(a, b), std::max(a, b)}].push_back(f);
    }
  std::vector<char> seen(tris.size(), 0);
  std::vector<uint32_t> order;
  for (uint32_t s = 0; s < tris.size(); ++s) {
    if (seen[s]) continue;
    seen[s] = 1;
    size_t head = order.size();
    order.push_back(s);
    while (head < order.size()) {
      const uint32_t f = order[head++];
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = tris[f][k], b = tris[f][(k + 1) % 3];
        for (uint32_t g : by_edge[{std::min(a, b), std::max(a, b)}])
          if (!seen[g]) {
            seen[g] = 1;
            order.push_back(g);
          }
      }
    }
  }
  std::vector<std::array<uint32_t, 3>> dtris;
  for (uint32_t f : order) {
    std::array<uint32_t, 3> t{};
    for (int k = 0; k < 3; ++k) {
      const uint32_t o = tris[f][k];
      if (dec_of_[o] == kMeshNone) {
        dec_of_[o] = static_cast<uint32_t>(orig_of_.size());
        orig_of_.push_back(o);
      }
      t[k] = dec_of_[o];
    }
    dtris.push_back(t);
  }
  if (orig_of_.size() != sr.base_vertices.size()) throw std::logic_error("encode_mesh: base vertex without a face");
  // Trace: vertices, then triangles.
  Segment& seg = base_seg_;
  seg.base = true;
  const int bits = opt_.bits;
  for (uint32_t i = 0; i < orig_of_.size(); ++i) {
    const auto& p = q_[orig_of_[i]];
    for (int k = 0; k < 3; ++k) {
      if (!arith) {
        seg.conn.push_back(op_raw(static_cast<uint32_t>(p[k]), bits));
      } else if (i == 0) {
        seg.conn.push_back(op_bypass(static_cast<uint32_t>(p[k]), bits));
      } else {
        const int32_t d = p[k] - q_[orig_of_[i - 1]][k];
        seg.conn.push_back(op_signed(MeshContexts::kBaseZero + k, MeshContexts::base_mag(k),
                                     MeshContexts::kBaseMagBins, d, kMeshBaseDeltaCutoff, kMeshBaseDeltaEgK));
      }
    }
    seg.end_item();
  }
  int index_bits = 0;
  while ((size_t{1} << index_bits) < orig_of_.size()) ++index_bits;
  uint32_t next = 0;
  for (const auto& t : dtris) {
    for (int k = 0; k < 3; ++k) {
      if (!arith) {
        seg.conn.push_back(op_raw(t[k], index_bits));
      } else if (t[k] == next) {
        seg.conn.push_back(op_bit(MeshContexts::kBaseNew + k, 1));
        ++next;
      } else {
        seg.conn.push_back(op_bit(MeshContexts::kBaseNew + k, 0));
        seg.conn.push_back(op_ueg(MeshContexts::kBaseRef, MeshContexts::kBaseMagBins, next - 1 - t[k],
                                  kMeshBaseRefCutoff, kMeshBaseRefEgK));
      }
    }
    seg.end_item();
  }
  // The client's mesh.
  for (uint32_t i = 0; i < orig_of_.size(); ++i) {
    const int32_t p[3] = {q_[orig_of_[i]][0], q_[orig_of_[i]][1], q_[orig_of_[i]][2]};
    if (st_.add_vertex(p) != Status::ok) throw std::logic_error("encode_mesh: base vertex rejected");
  }
  for (const auto& t : dtris)
    if (st_.add_triangle(t[0], t[1], t[2]) != Status::ok) throw std::logic_error("encode_mesh: base face rejected");
  const Status s = st_.finish_base(arena_, kMeshMaxDegree);
  if (s != Status::ok)
    throw std::invalid_argument(std::string("encode_mesh: base mesh rejected by the client (") + status_name(s) +
                                "): a vertex degree above " + std::to_string(kMeshMaxDegree) + "?");
}

void Encoder::trace_level(const SimplifyLevel& lvl, uint32_t level_index, Segment& seg) {
  const bool arith = opt_.coder == MeshCoder::arith;
  seg.level = level_index;
  const uint32_t nv = st_.vertex_count(), nt = st_.triangle_count();
  // Splits in the order of their split vertex on the client.
  std::vector<std::pair<uint32_t, const Collapse*>> splits;
  for (const Collapse& c : lvl.collapses) splits.emplace_back(dec(c.u), &c);
  std::sort(splits.begin(), splits.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (size_t i = 1; i < splits.size(); ++i)
    if (splits[i].first == splits[i - 1].first) throw std::logic_error("encode_mesh: vertex split twice in a level");
  seg.dv = static_cast<uint32_t>(splits.size());
  std::vector<uint64_t> freqs[kTables];
  freqs[kTabDelta].assign(kMeshHuffDeltaAlphabet, 0);
  freqs[kTabShape].assign(kMeshHuffShapeAlphabet, 0);
  freqs[kTabPos].assign(kMeshHuffPosAlphabet, 0);
  freqs[kTabGeo].assign(kMeshHuffGeoAlphabet, 0);

  // Pass A.
  std::vector<uint8_t> marks((nv + 7) / 8 + 1, 0);
  if (arith) {
    size_t si = 0;
    for (uint32_t x = 0; x < nv; ++x) {
      Ring r;
      if (st_.ring(x, &r) != Status::ok) throw std::logic_error("encode_mesh: ring walk failed");
      const uint32_t ci = mesh_mark_context(st_, x, r, marks.data());
      const bool is = si < splits.size() && splits[si].first == x;
      seg.conn.push_back(with(kCatFlags, op_bit(MeshContexts::kMark + ci, is ? 1 : 0)));
      if (is) {
        marks[x >> 3] = static_cast<uint8_t>(marks[x >> 3] | (1u << (x & 7)));
        ++si;
      }
      seg.end_item();
    }
  } else {
    uint32_t prev = 0;
    for (size_t i = 0; i < splits.size(); ++i) {
      if (i == 0) seg.conn.push_back(with(kCatFlags, op_table(kTabDelta)));
      const uint32_t delta = splits[i].first - prev;
      prev = splits[i].first;
      const uint32_t sym = std::min(delta, kMeshHuffEscape);
      ++freqs[kTabDelta][sym];
      seg.conn.push_back(with(kCatFlags, op_hsym(kTabDelta, sym)));
      if (sym == kMeshHuffEscape) seg.conn.push_back(with(kCatFlags, op_ue(delta - kMeshHuffEscape)));
      seg.end_item();
    }
  }

  // Pass B: simulate the splits; positions are coded after the weight is chosen.
  // Candidate parallelogram weights (sixteenths); one if the caller fixed it.
  std::vector<int> weights = {0, 2, 4, 6, 8, 10, 12, 14, 16};
  if (opt_.weight_q4 >= 0) weights = {opt_.weight_q4};
  struct GeoItem {
    GeoFrame frame;
    std::array<int32_t, 3> q;
    std::vector<std::array<int32_t, 3>> pred;  // per weight (one for the Laplacian predictor)
  };
  std::vector<GeoItem> geo(splits.size());
  std::vector<uint32_t> conn_end(splits.size()), geom_end(splits.size());
  int64_t score[kMeshMaxDegree + 1];
  for (size_t i = 0; i < splits.size(); ++i) {
    const uint32_t u = splits[i].first;
    const Collapse& c = *splits[i].second;
    if (!arith && i == 0) {
      seg.conn.push_back(with(kCatShape, op_table(kTabShape)));
      seg.conn.push_back(with(kCatRotation, op_table(kTabPos)));
    }
    Ring r;
    if (st_.ring(u, &r) != Status::ok) throw std::logic_error("encode_mesh: ring walk failed");
    const uint32_t d = r.degree;
    auto find = [&](int64_t orig) -> uint32_t {
      const uint32_t w = dec(static_cast<uint32_t>(orig));
      for (uint32_t j = 0; j < d; ++j)
        if (r.vertex[j] == w) return j;
      throw std::logic_error("encode_mesh: wing not in the split vertex's ring");
    };
    SplitChoice ch;
    if (c.wing_f >= 0 && c.wing_l >= 0) {
      ch.kind = SplitKind::interior;
      const uint32_t pf = find(c.wing_f), pl = find(c.wing_l);
      ch.first = pf;
      ch.count = r.boundary ? pl - pf : (pl + d - pf) % d;
      if (r.boundary && pl <= pf) throw std::logic_error("encode_mesh: wings out of order on a boundary fan");
    } else if (c.wing_f >= 0) {
      ch.kind = SplitKind::tail;
      ch.first = find(c.wing_f);
      ch.count = d - 1 - ch.first;
    } else {
      ch.kind = SplitKind::head;
      ch.first = 0;
      ch.count = find(c.wing_l);
    }
    if (!MeshState::choice_valid(r, ch)) throw std::logic_error("encode_mesh: split not representable");
    if (arith) {
      if (r.boundary) {
        seg.conn.push_back(with(kCatShape, op_bit(MeshContexts::kKind, ch.kind == SplitKind::interior ? 0 : 1)));
        if (ch.kind != SplitKind::interior)
          seg.conn.push_back(with(kCatShape, op_bit(MeshContexts::kKind + 1, ch.kind == SplitKind::head ? 1 : 0)));
      }
      if (ch.kind == SplitKind::interior) {
        const uint32_t dc = std::min<uint32_t>(d - 2, MeshContexts::kArcDegree - 1);
        seg.conn.push_back(with(kCatShape, op_unary(MeshContexts::arc(dc), MeshContexts::kArcBins, ch.count - 1, d - 2)));
        const uint32_t n = st_.candidate_scores(r, u, ch.kind, ch.count, score);
        seg.conn.push_back(with(kCatRotation, op_unary(MeshContexts::rank(n), MeshContexts::kRankBins, rank_of(score, n, ch.first), n - 1)));
      } else {
        const uint32_t n = st_.candidate_scores(r, u, ch.kind, 0, score);
        const uint32_t idx = ch.kind == SplitKind::tail ? ch.first : ch.count;
        seg.conn.push_back(with(kCatRotation, op_unary(MeshContexts::kEdgeRank, MeshContexts::kRankBins, rank_of(score, n, idx), n - 1)));
      }
    } else {
      const uint32_t shape =
          ch.kind == SplitKind::tail ? 0 : (ch.kind == SplitKind::head ? kMeshHuffShapeAlphabet - 1 : ch.count);
      const uint32_t pos = ch.kind == SplitKind::head ? ch.count : ch.first;
      ++freqs[kTabShape][shape];
      ++freqs[kTabPos][pos];
      seg.conn.push_back(with(kCatShape, op_hsym(kTabShape, shape)));
      seg.conn.push_back(with(kCatRotation, op_hsym(kTabPos, pos)));
    }
    conn_end[i] = static_cast<uint32_t>(seg.conn.size());
    uint32_t v = 0;
    if (st_.split(u, ch, &v) != Status::ok) throw std::logic_error("encode_mesh: split rejected");
    if (v != orig_of_.size()) throw std::logic_error("encode_mesh: unexpected new vertex index");
    dec_of_[c.v] = v;
    orig_of_.push_back(c.v);
    Ring rv;
    if (st_.ring(v, &rv) != Status::ok) throw std::logic_error("encode_mesh: ring of the new vertex");
    GeoItem& g = geo[i];
    g.frame = mesh_geo_frame(st_, v, rv);
    g.q = q_[c.v];
    if (opt_.predictor == MeshPredictor::laplacian) {
      int32_t p[3];
      if (st_.predict(v, MeshPredictor::laplacian, 0, p) != Status::ok) throw std::logic_error("predict failed");
      g.pred.push_back({p[0], p[1], p[2]});
    } else {
      for (const int w : weights) {
        int32_t p[3];
        if (st_.predict(v, opt_.predictor, w, p) != Status::ok)
          throw std::logic_error("predict failed");
        g.pred.push_back({p[0], p[1], p[2]});
      }
    }
    const int32_t qq[3] = {g.q[0], g.q[1], g.q[2]};
    if (st_.set_position(v, qq) != Status::ok) throw std::logic_error("encode_mesh: position out of range");
  }
  seg.dt = st_.triangle_count() - nt;

  // Weight: the one with the smallest sum of |correction| over the level.
  size_t wi = 0;
  if (opt_.predictor != MeshPredictor::laplacian && opt_.weight_q4 < 0) {
    uint64_t best = UINT64_MAX;
    for (size_t w = 0; w < weights.size(); ++w) {
      uint64_t sum = 0;
      for (const GeoItem& g : geo)
        for (int k = 0; k < 3; ++k) sum += static_cast<uint64_t>(std::llabs(int64_t{g.q[k]} - g.pred[w][k]));
      if (sum < best) {
        best = sum;
        wi = w;
      }
    }
    seg.weight_q4 = weights[wi];
  } else {
    seg.weight_q4 = opt_.predictor != MeshPredictor::laplacian ? opt_.weight_q4 : 0;
  }
  // Geometry ops per split item (the conn ops of pass B are already in
  // place item by item; the geometry substream is separate, so its ops can
  // be appended now with the same item boundaries).
  for (size_t i = 0; i < splits.size(); ++i) {
    const GeoItem& g = geo[i];
    const auto& pred = g.pred[wi];
    if (!arith && i == 0) seg.geom.push_back(with(kCatGeo, op_table(kTabGeo)));
    if (arith) {
      const int order[3] = {g.frame.normal_axis, g.frame.normal_axis == 0 ? 1 : 0, g.frame.normal_axis == 2 ? 1 : 2};
      for (int j = 0; j < 3; ++j) {
        const int axis = order[j];
        const uint32_t role = j == 0 ? 0 : 1;
        int32_t r = g.q[axis] - pred[axis];
        if (j == 0 && g.frame.flip) r = -r;
        seg.geom.push_back(with(role == 0 ? kCatGeoNormal : kCatGeo,
                                op_signed(MeshContexts::geo_zero(role, g.frame.scale),
                                          MeshContexts::geo_mag(role, g.frame.scale), MeshContexts::kGeoMagBins, r,
                                          kMeshGeoCutoff, kMeshGeoEgK)));
      }
    } else {
      for (int k = 0; k < 3; ++k) {
        const uint32_t z = zigzag(g.q[k] - pred[k]);
        const uint32_t sym = std::min(z, kMeshHuffEscape);
        ++freqs[kTabGeo][sym];
        seg.geom.push_back(with(kCatGeo, op_hsym(kTabGeo, sym)));
        if (sym == kMeshHuffEscape) seg.geom.push_back(with(kCatGeo, op_ue(z - kMeshHuffEscape)));
      }
    }
    geom_end[i] = static_cast<uint32_t>(seg.geom.size());
  }
  // Pass B items end where their split's ops end in each substream.
  for (size_t i = 0; i < splits.size(); ++i) {
    seg.conn_at.push_back(conn_end[i]);
    seg.geom_at.push_back(geom_end[i]);
    ++seg.items;
  }
  if (!arith) finish_tables(seg, freqs);
}

// The tail: the Edgebreaker traversal of the closed input mesh, run in step
// with the client's own MeshTail (so the contexts, the border walks and the
// vertex and triangle numbering are the client's), then the positions in
// the client's vertex order against its own prediction.
void Encoder::trace_tail(const ClosedMesh& cm, uint32_t level_index, Segment& seg) {
  using TC = TailContexts;
  const uint32_t nv = static_cast<uint32_t>(mesh_.positions.size());
  seg.tail = true;
  seg.level = level_index;
  seg.counts.vertices = nv;
  seg.counts.triangles = cm.real_t;
  seg.counts.dummy_vertices = cm.holes;
  seg.counts.dummy_triangles = static_cast<uint32_t>(cm.cv.size() / 3) - cm.real_t;
  seg.counts.max_border = 3 * (seg.counts.triangles + seg.counts.dummy_triangles);  // declared below: the peak
  MeshTail tail;
  if (tail.begin(st_, arena_, seg.counts) != Status::ok) throw std::logic_error("encode_mesh: tail does not fit");
  const uint32_t nt = tail.total();
  std::vector<uint32_t> dec(nv + cm.holes, kMeshNone);  // client vertex of each input vertex
  std::vector<uint32_t> input_corner(3 * size_t{nt}, kMeshNone);  // input corner of each client corner
  std::vector<char> used(nt, 0);
  uint32_t next_seed = 0;
  auto conn = [&](Op o) { seg.conn.push_back(with(kCatTailConn, o)); };
  auto record = [&](uint32_t f) {
    used[f] = 1;
    // The index the client gives the triangle it builds next.
    const bool dummy = cm.cv[3 * f] >= nv || cm.cv[3 * f + 1] >= nv || cm.cv[3 * f + 2] >= nv;
    return tail.next_triangle(dummy);
  };
  for (uint32_t item = 0; item < nt; ++item) {
    Status st;
    if (tail.needs_seed()) {
      while (used[next_seed]) ++next_seed;
      const uint32_t f = next_seed;
      bool dummy[3];
      for (uint32_t k = 0; k < 3; ++k) {
        dummy[k] = cm.cv[3 * f + k] >= nv;
        conn(op_bit(TC::kDummy, dummy[k]));
      }
      const uint32_t t = record(f);
      if ((st = tail.seed(dummy)) != Status::ok) throw std::logic_error("encode_mesh: tail seed rejected");
      for (uint32_t k = 0; k < 3; ++k) {
        input_corner[3 * t + k] = 3 * f + k;
        dec[cm.cv[3 * f + k]] = st_.corner_vertex(3 * t + k);
      }
    } else {
      const uint32_t g = tail.gate();
      const uint32_t ic = static_cast<uint32_t>(cm.opp[input_corner[g]]);  // the input corner facing the gate
      const uint32_t f = ic / 3;
      if (used[f]) throw std::logic_error("encode_mesh: tail gate faces a built triangle");
      const uint32_t tip = cm.cv[ic];
      const uint32_t fx = tail.fan_before(), fy = tail.fan_after();
      TailSymbol sym = TailSymbol::C;
      bool backward = false;
      uint32_t offset = 0, depth = 0;
      if (dec[tip] != kMeshNone) {
        const bool l = dec[tip] == tail.vertex_before(), r = dec[tip] == tail.vertex_after();
        sym = l ? (r ? TailSymbol::E : TailSymbol::L) : (r ? TailSymbol::R : TailSymbol::S);
      }
      if (sym == TailSymbol::S) {
        // Where a loop passes the tip more than once (after a handle), the
        // right pass is the one whose unbuilt wedge at the tip holds f.
        auto wedge_holds_f = [&](uint32_t e) {
          const uint32_t built = input_corner[tail.edge_corner(e)];
          uint32_t from = built / 3;
          uint32_t tri = static_cast<uint32_t>(cm.opp[built]) / 3;
          for (uint32_t steps = 0; steps <= cm.cv.size() / 3; ++steps) {
            if (tri == f) return true;
            if (used[tri]) return false;
            uint32_t k = 3 * tri;
            while (cm.cv[k] != tip) ++k;
            const uint32_t t1 = static_cast<uint32_t>(cm.opp[MeshState::next(k)]) / 3;
            const uint32_t t2 = static_cast<uint32_t>(cm.opp[MeshState::prev(k)]) / 3;
            const uint32_t to = t1 == from ? t2 : t1;
            from = tri;
            tri = to;
          }
          return false;
        };
        // The current loop, both ways at once; the nearer side is coded.
        uint32_t h[2] = {tail.border_first(false), tail.border_first(true)};
        const uint32_t stop[2] = {tail.border_first(true), tail.border_first(false)};
        bool open[2] = {true, true};
        for (uint32_t k = 2; offset == 0 && (open[0] || open[1]); ++k) {
          for (int side = 0; side < 2 && offset == 0; ++side) {
            if (!open[side]) continue;
            h[side] = tail.border_next(h[side], side == 1);
            if (h[side] == stop[side]) {
              open[side] = false;
            } else if (tail.border_reach(h[side], side == 1) == dec[tip] && wedge_holds_f(h[side])) {
              offset = k;
              backward = side == 1;
            }
          }
        }
        // Else a waiting loop: a handle.
        for (uint32_t d = 0; offset == 0 && d < tail.waiting(); ++d) {
          const uint32_t e0 = tail.waiting_edge(d);
          uint32_t e = e0;
          for (uint32_t k = 1; offset == 0; ++k) {
            if (tail.border_reach(e, false) == dec[tip] && wedge_holds_f(e)) {
              sym = TailSymbol::M;
              depth = d;
              offset = k;
            }
            e = tail.border_next(e, false);
            if (e == e0) break;
          }
        }
        if (offset == 0) throw std::logic_error("encode_mesh: tail vertex on no border loop");
      }
      conn(op_bit(TC::left(fx, fy), sym == TailSymbol::L || sym == TailSymbol::E));
      conn(op_bit(TC::right(fy, sym == TailSymbol::L || sym == TailSymbol::E), sym == TailSymbol::R || sym == TailSymbol::E));
      const bool dummy = tip >= nv;
      const bool far = sym == TailSymbol::S || sym == TailSymbol::M;
      if (sym == TailSymbol::C || far) conn(op_bit(TC::fresh(fx, fy), sym == TailSymbol::C));
      if (sym == TailSymbol::C) conn(op_bit(TC::kDummy + 1, dummy));
      if (far) conn(op_bit(TC::kMerge, sym == TailSymbol::M));
      if (sym == TailSymbol::S) {
        conn(op_bit(TC::kDirection, backward));
        conn(op_ueg(TC::kOffset, TC::kOffsetBins, offset - 2, kTailOffsetCutoff, kTailOffsetEgK));
      }
      if (sym == TailSymbol::M) {
        conn(op_ueg(TC::kDepth, TC::kOffsetBins, depth, kTailOffsetCutoff, kTailOffsetEgK));
        conn(op_ueg(TC::kOffset, TC::kOffsetBins, offset - 1, kTailOffsetCutoff, kTailOffsetEgK));
      }
      const uint32_t t = record(f);
      if ((st = tail.attach(sym, dummy, backward, offset, depth)) != Status::ok)
        throw std::logic_error("encode_mesh: tail step rejected");
      input_corner[3 * t] = ic;
      input_corner[3 * t + 1] = MeshState::next(ic);
      input_corner[3 * t + 2] = MeshState::prev(ic);
      if (sym == TailSymbol::C) dec[tip] = st_.corner_vertex(3 * t);
    }
    seg.end_item();
  }
  if (tail.finish() != Status::ok) throw std::logic_error("encode_mesh: tail not closed");
  seg.counts.max_border = tail.border_peak();
  orig_of_.assign(nv, kMeshNone);
  for (uint32_t v = 0; v < nv; ++v) {
    if (dec[v] == kMeshNone || dec[v] >= nv) throw std::logic_error("encode_mesh: tail lost a vertex");
    orig_of_[dec[v]] = v;
  }
  for (uint32_t v = 0; v < nv; ++v) {
    int32_t p[3];
    uint32_t cls = 0;
    if (mesh_tail_predict(st_, v, p, &cls) != Status::ok) throw std::logic_error("encode_mesh: tail prediction");
    const auto& q = q_[orig_of_[v]];
    for (uint32_t k = 0; k < 3; ++k)
      seg.geom.push_back(with(kCatTailGeo, op_signed(TC::geo_zero(k, cls), TC::geo_mag(k, cls), TC::kGeoBins,
                                                     q[k] - p[k], kTailGeoCutoff, kTailGeoEgK)));
    const int32_t actual[3] = {q[0], q[1], q[2]};
    if (st_.set_position(v, actual) != Status::ok) throw std::logic_error("encode_mesh: tail position");
    seg.end_item();
  }
  seg.dv = nv;
  seg.dt = cm.real_t;
}

void Encoder::finish_tables(Segment& seg, const std::vector<uint64_t> freqs[kTables]) {
  for (int t = 0; t < kTables; ++t) {
    std::vector<uint64_t> f = freqs[t];
    // Trim the alphabet after the last used symbol (the table sends its size).
    size_t n = f.size();
    while (n > 1 && f[n - 1] == 0) --n;
    f.resize(n);
    if (std::all_of(f.begin(), f.end(), [](uint64_t x) { return x == 0; })) f[0] = 1;
    seg.codes[t] = huffman_build(f, HuffmanTable::kMaxCodeLength);
    seg.table_lengths[t] = seg.codes[t].lengths;
  }
}

void Encoder::emit(const Segment& seg, StreamWriter& w, MeshLevelStats& stats) {
  double cost[kCats] = {};
  const bool arith = opt_.coder == MeshCoder::arith;
  auto header = [&](uint32_t first, uint32_t count) {
    std::vector<uint8_t> h;
    if (!seg.base && !seg.tail) put_varint(h, seg.level);
    put_varint(h, first);
    put_varint(h, count);
    if (!seg.base && !seg.tail && first == 0) {
      put_varint(h, seg.dv);
      put_varint(h, seg.dt);
      h.push_back(static_cast<uint8_t>(seg.weight_q4));
    }
    return h;
  };
  ArithContext* const contexts = seg.tail ? tctx_.c : ctx_.c;
  auto encode_item = [&](uint32_t j, Coder& cc, Coder& gc) {
    for (uint32_t o = seg.conn_at[j]; o < seg.conn_at[j + 1]; ++o)
      cost[seg.conn[o].cat] += replay(seg.conn[o], cc, contexts, seg);
    for (uint32_t o = seg.geom_at[j]; o < seg.geom_at[j + 1]; ++o)
      cost[seg.geom[o].cat] += replay(seg.geom[o], gc, contexts, seg);
  };
  const size_t limit = opt_.max_chunk_payload;
  uint32_t i = 0;
  while (i < seg.items) {
    const MeshContexts snapshot = ctx_;
    const TailContexts tail_snapshot = tctx_;
    double cost_before[kCats];
    std::copy(cost, cost + kCats, cost_before);
    Coder cc, gc;
    cc.arith = gc.arith = arith;
    uint32_t j = i;
    while (j < seg.items) {
      encode_item(j, cc, gc);
      const size_t conn = cc.size();
      const size_t size = header(i, j - i + 1).size() + (seg.base ? 0 : varint_size(static_cast<uint32_t>(conn))) +
                          conn + gc.size();
      if (size > limit) break;
      ++j;
    }
    if (j == i) throw std::invalid_argument("encode_mesh: one item does not fit --max-chunk bytes");
    if (j < seg.items) {
      // Item j overflowed: code i .. j-1 again from the snapshot.
      ctx_ = snapshot;
      tctx_ = tail_snapshot;
      std::copy(cost_before, cost_before + kCats, cost);
      cc = Coder{};
      gc = Coder{};
      cc.arith = gc.arith = arith;
      for (uint32_t k = i; k < j; ++k) encode_item(k, cc, gc);
    }
    std::vector<uint8_t> payload = header(i, j - i);
    const std::vector<uint8_t> conn = cc.finish(), geom = gc.finish();
    if (!seg.base) put_varint(payload, static_cast<uint32_t>(conn.size()));
    payload.insert(payload.end(), conn.begin(), conn.end());
    payload.insert(payload.end(), geom.begin(), geom.end());
    w.add_chunk(seg.base ? chunk::kMeshBase : (seg.tail ? chunk::kMeshTail : chunk::kMeshLevel), payload);
    stats.connectivity_bytes += conn.size();
    stats.geometry_bytes += geom.size();
    stats.chunk_bytes += payload.size() + kChunkHeadBytes + kChunkTailBytes;
    ++stats.chunks;
    i = j;
  }
  bits_.base += cost[kCatBase];
  bits_.split_flags += cost[kCatFlags];
  bits_.split_shape += cost[kCatShape];
  bits_.split_rotation += cost[kCatRotation];
  bits_.geometry_normal += cost[kCatGeoNormal];
  bits_.geometry += cost[kCatGeoNormal] + cost[kCatGeo];
  bits_.tail_connectivity += cost[kCatTailConn];
  bits_.tail_geometry += cost[kCatTailGeo];
}

MeshEncodeResult Encoder::run() {
  if (opt_.bits < 2 || opt_.bits > 16) throw std::invalid_argument("encode_mesh: bits must be 2..16");
  if (opt_.max_chunk_payload < 512 || opt_.max_chunk_payload > (1u << 24))
    throw std::invalid_argument("encode_mesh: max chunk payload must be 512 .. 16 MiB");
  if (opt_.weight_q4 > 16) throw std::invalid_argument("encode_mesh: weight must be 0..16 or -1");
  const std::string why = check_manifold(mesh_);
  if (!why.empty()) throw std::invalid_argument("encode_mesh: mesh is not manifold (repair it first): " + why);
  if (mesh_.triangles.empty()) throw std::invalid_argument("encode_mesh: no triangles");
  MeshEncodeResult res;
  quant_ = make_quantisation(mesh_bounds(mesh_), opt_.bits);
  q_ = quantise(mesh_, quant_);
  const SimplifyResult sr = simplify_progressive(q_, mesh_.triangles, mesh_simplify_options(opt_));
  const uint32_t nv = static_cast<uint32_t>(mesh_.positions.size());
  const uint32_t nt = static_cast<uint32_t>(mesh_.triangles.size());
  const uint32_t split_levels = static_cast<uint32_t>(sr.levels.size());
  // The tail: how many split levels come before it, and the closed mesh it
  // traverses.
  ClosedMesh closed;
  uint32_t levels = split_levels;  // levels after the base, the tail included
  bool tail = false;
  if (opt_.tail_fraction > 0) {
    if (opt_.coder != MeshCoder::arith) throw std::invalid_argument("encode_mesh: the tail needs the arithmetic coder");
    const std::string why = close_mesh(nv, mesh_.triangles, &closed);
    if (!why.empty()) {
      res.tail_note = "no single-rate tail: " + why;
    } else if (closed.max_degree > kMeshMaxDegree) {
      res.tail_note = "no single-rate tail: a vertex ring above " + std::to_string(kMeshMaxDegree);
    } else if (split_levels < 2) {
      res.tail_note = "no single-rate tail: fewer than two levels";
    } else {
      // Split levels while they reach at most tail_fraction of the vertices,
      // at least tail_min_levels of them, and at least one split level and
      // one level's worth of vertices left for the tail.
      uint32_t k = 0, v = static_cast<uint32_t>(sr.base_vertices.size());
      while (k + 1 < split_levels) {
        const uint32_t next_v = v + static_cast<uint32_t>(sr.levels[split_levels - 1 - k].collapses.size());
        if (next_v > opt_.tail_fraction * nv && k >= opt_.tail_min_levels) break;
        v = next_v;
        ++k;
      }
      tail = k >= 1;
      if (tail) levels = k + 1;
      else res.tail_note = "no single-rate tail: no split level before it";
    }
  }
  const uint32_t cap_v = tail ? nv + closed.holes : nv;
  const uint32_t cap_t = tail ? static_cast<uint32_t>(closed.cv.size() / 3) : nt;
  workspace_.assign(MeshState::workspace_bytes(cap_v, cap_t) + 12 * size_t{cap_t} +
                        (tail ? MeshTail::workspace_bytes(3 * cap_t) : 0) + 256,
                    0);
  arena_ = Arena(workspace_.data(), workspace_.size());
  if (st_.init(arena_, cap_v, cap_t) != Status::ok) throw std::logic_error("encode_mesh: workspace");
  st_.clear(opt_.bits);
  ctx_.reset();
  tctx_.reset();
  dec_of_.assign(nv, kMeshNone);
  orig_of_.clear();
  build_base(sr);
  const uint32_t base_t = st_.triangle_count();
  std::vector<uint64_t> sums(levels + 1);
  sums[0] = mesh_checksum(st_);
  std::vector<Segment> segs(levels);
  const uint32_t splits = tail ? levels - 1 : levels;
  for (uint32_t l = 1; l <= splits; ++l) {
    trace_level(sr.levels[split_levels - l], l, segs[l - 1]);
    sums[l] = mesh_checksum(st_);
  }
  uint32_t max_degree = st_.max_degree_seen();
  if (tail) {
    max_degree = std::max(max_degree, closed.max_degree);
    trace_tail(closed, levels, segs[levels - 1]);
    sums[levels] = mesh_checksum(st_);
  }

  // The reconstruction must be the input, on the grid.
  if (st_.vertex_count() != nv || st_.triangle_count() != nt)
    throw std::logic_error("encode_mesh: reconstruction has the wrong size");
  {
    auto canon = [](std::array<uint32_t, 3> t) {
      const int m = (t[0] < t[1] && t[0] < t[2]) ? 0 : (t[1] < t[2] ? 1 : 2);
      return std::array<uint32_t, 3>{t[m], t[(m + 1) % 3], t[(m + 2) % 3]};
    };
    std::vector<std::array<uint32_t, 3>> a, b;
    for (const auto& t : mesh_.triangles) a.push_back(canon(t));
    auto orig = [this](uint32_t c) { return orig_of_[st_.corner_vertex(c)]; };
    for (uint32_t t = 0; t < nt; ++t) b.push_back(canon({orig(3 * t), orig(3 * t + 1), orig(3 * t + 2)}));
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    if (a != b) throw std::logic_error("encode_mesh: reconstructed faces differ from the input");
    for (uint32_t v = 0; v < nv; ++v) {
      int32_t p[3];
      st_.position(v, p);
      for (int k = 0; k < 3; ++k)
        if (p[k] != q_[orig_of_[v]][k]) throw std::logic_error("encode_mesh: reconstructed position differs");
    }
  }

  MeshHeader mh;
  if (tail) mh.version = kMeshCodecVersionTail;
  mh.coder = opt_.coder;
  mh.predictor = opt_.predictor;
  mh.up = opt_.up;
  mh.bits = static_cast<uint8_t>(opt_.bits);
  if (levels > 0xFFFF) throw std::invalid_argument("encode_mesh: too many levels");
  mh.levels = static_cast<uint16_t>(levels);
  mh.max_degree = static_cast<uint16_t>(std::max<uint32_t>(3, max_degree));
  mh.base_vertices = static_cast<uint32_t>(sr.base_vertices.size());
  mh.base_triangles = base_t;
  mh.vertices = nv;
  mh.triangles = nt;
  for (int k = 0; k < 3; ++k) {
    const float f = static_cast<float>(quant_.origin[k]);
    std::memcpy(&mh.origin_f32[k], &f, 4);
  }
  {
    const float f = static_cast<float>(quant_.step);
    std::memcpy(&mh.step_f32, &f, 4);
  }
  StreamHeader hdr = default_header(StreamMode::model, opt_.width, opt_.height);
  hdr.max_chunk_payload = opt_.max_chunk_payload;
  hdr.max_vertices = cap_v;
  hdr.max_triangles = cap_t;
  const size_t ws =
      MeshDecoder::workspace_bytes(cap_v, cap_t, base_t, opt_.coder, tail ? segs[levels - 1].counts.max_border : 0);
  if (ws > 0xFFFFFFFFu) throw std::invalid_argument("encode_mesh: mesh too large for a client workspace");
  hdr.workspace_bytes = static_cast<uint32_t>(ws);
  StreamWriter w(hdr);
  if (tail) {
    const TailCounts& tc = segs[levels - 1].counts;
    mh.tail_dummy_vertices = tc.dummy_vertices;
    mh.tail_dummy_triangles = tc.dummy_triangles;
    mh.tail_max_border = tc.max_border;
  }
  uint8_t mhb[kMeshHeaderTailBytes];
  mesh_header_to_bytes(mh, mhb);
  w.add_chunk(chunk::kMeshHeader, std::span<const uint8_t>(mhb, mesh_header_size(mh)));

  ctx_.reset();
  tctx_.reset();
  res.levels.resize(levels + 1);
  MeshLevelStats& b = res.levels[0];
  b.level = 0;
  b.vertices_added = b.vertices = mh.base_vertices;
  b.triangles_added = b.triangles = base_t;
  b.checksum = sums[0];
  emit(base_seg_, w, b);
  uint32_t v_total = mh.base_vertices, t_total = base_t;
  for (uint32_t l = 1; l <= levels; ++l) {
    MeshLevelStats& s = res.levels[l];
    const Segment& seg = segs[l - 1];
    s.level = l;
    if (seg.tail) {
      s.tail = true;
      s.vertices_added = nv - v_total;  // net: the tail sends every vertex again
      s.triangles_added = nt - t_total;
      v_total = nv;
      t_total = nt;
    } else {
      s.vertices_added = seg.dv;
      s.triangles_added = seg.dt;
      v_total += seg.dv;
      t_total += seg.dt;
    }
    s.vertices = v_total;
    s.triangles = t_total;
    s.weight_q4 = seg.weight_q4;
    s.error_threshold = seg.tail ? 0 : sr.levels[split_levels - l].threshold;
    s.checksum = sums[l];
    emit(seg, w, s);
  }
  res.stream = w.finish();
  res.bits = bits_;
  res.stream_header = hdr;
  res.mesh_header = mh;
  res.quantisation = quant_;
  res.fixed_bytes = kPreambleBytes + (kChunkHeadBytes + kHeaderPayloadV1 + kChunkTailBytes) +
                    (kChunkHeadBytes + mesh_header_size(mh) + kChunkTailBytes) + (kChunkHeadBytes + 4 + kChunkTailBytes);
  res.vertex_order = orig_of_;
  res.max_degree = mh.max_degree;
  res.error_limit = sr.error_limit;
  res.tail = tail;
  if (tail) res.tail_counts = segs[levels - 1].counts;
  return res;
}

}  // namespace

uint64_t mesh_checksum(const MeshState& m) {
  uint64_t h = 0xcbf29ce484222325ull;
  auto mix = [&h](uint32_t v) {
    for (int i = 0; i < 4; ++i) {
      h ^= (v >> (8 * i)) & 0xFF;
      h *= 0x100000001b3ull;
    }
  };
  mix(m.vertex_count());
  mix(m.triangle_count());
  for (uint32_t i = 0; i < 3 * m.vertex_count(); ++i) mix(m.positions()[i]);
  for (uint32_t i = 0; i < 3 * m.triangle_count(); ++i) mix(m.corner_vertex(i));
  return h;
}

SimplifyOptions mesh_simplify_options(const MeshEncodeOptions& o) {
  SimplifyOptions so = o.simplify;
  so.max_degree = std::min<int>(so.max_degree, static_cast<int>(kMeshMaxDegree) - 2);
  so.area_centroid = o.predictor == MeshPredictor::area;
  return so;
}

const char* mesh_up_name(MeshUp up) {
  static const char* const kNames[6] = {"+y", "+z", "+x", "-y", "-z", "-x"};
  const auto i = static_cast<size_t>(up);
  return i < 6 ? kNames[i] : "unknown";
}

bool mesh_up_from_name(const std::string& name, MeshUp* up) {
  const std::string n = name.size() == 1 ? "+" + name : name;
  for (uint8_t i = 0; i < 6; ++i)
    if (n == mesh_up_name(static_cast<MeshUp>(i))) {
      *up = static_cast<MeshUp>(i);
      return true;
    }
  return false;
}

const char* mesh_predictor_name(MeshPredictor p) {
  switch (p) {
    case MeshPredictor::laplacian: return "Laplacian";
    case MeshPredictor::parallelogram: return "parallelogram";
    case MeshPredictor::area: return "area";
  }
  return "unknown";
}

MeshEncodeOptions paper_mesh_options() {
  MeshEncodeOptions o;
  o.coder = MeshCoder::huffman;
  o.predictor = MeshPredictor::laplacian;
  o.simplify.rate_weight = 0;
  o.simplify.packing_weight = 0;
  return o;
}

MeshEncodeResult encode_mesh(const Mesh& mesh, const MeshEncodeOptions& options) {
  Encoder e(mesh, options);
  return e.run();
}

std::string format_mesh_table(const std::vector<MeshLevelStats>& levels, size_t stream_bytes) {
  std::string s;
  char line[256];
  std::snprintf(line, sizeof line, "%5s %8s %8s %7s %7s %9s %9s %10s %9s\n", "level", "dV", "dT", "C/dT", "G/dT",
                "(C+G)/dT", "bytes", "cum.bytes", "vertices");
  s += line;
  uint64_t cum = 0, c_sum = 0, g_sum = 0, dt_sum = 0, dv_sum = 0;
  for (const MeshLevelStats& l : levels) {
    cum += l.chunk_bytes;
    if (l.level == 0) {
      std::snprintf(line, sizeof line, "%5s %8u %8u %7s %7s %9.2f %9llu %10llu %9u\n", "base", l.vertices_added,
                    l.triangles_added, "-", "-",
                    l.triangles_added ? 8.0 * double(l.connectivity_bytes + l.geometry_bytes) / l.triangles_added : 0.0,
                    static_cast<unsigned long long>(l.chunk_bytes), static_cast<unsigned long long>(cum), l.vertices);
    } else {
      const double dt = l.triangles_added ? double(l.triangles_added) : 1.0;
      char level[16];
      std::snprintf(level, sizeof level, l.tail ? "%uT" : "%u", l.level);
      std::snprintf(line, sizeof line, "%5s %8u %8u %7.2f %7.2f %9.2f %9llu %10llu %9u\n", level, l.vertices_added,
                    l.triangles_added, 8.0 * double(l.connectivity_bytes) / dt, 8.0 * double(l.geometry_bytes) / dt,
                    8.0 * double(l.connectivity_bytes + l.geometry_bytes) / dt,
                    static_cast<unsigned long long>(l.chunk_bytes), static_cast<unsigned long long>(cum), l.vertices);
      c_sum += l.connectivity_bytes;
      g_sum += l.geometry_bytes;
      dt_sum += l.triangles_added;
      dv_sum += l.vertices_added;
    }
    s += line;
  }
  if (dt_sum) {
    std::snprintf(line, sizeof line, "%5s %8llu %8llu %7.2f %7.2f %9.2f   (levels 1..%u)\n", "avg",
                  static_cast<unsigned long long>(dv_sum), static_cast<unsigned long long>(dt_sum),
                  8.0 * double(c_sum) / double(dt_sum), 8.0 * double(g_sum) / double(dt_sum),
                  8.0 * double(c_sum + g_sum) / double(dt_sum), levels.empty() ? 0u : levels.back().level);
    s += line;
  }
  if (!levels.empty() && levels.back().tail) {
    std::snprintf(line, sizeof line,
                  "(level %uT: the single-rate tail; it sends the whole mesh again, dV and dT are net)\n",
                  levels.back().level);
    s += line;
  }
  if (!levels.empty() && levels.back().triangles) {
    std::snprintf(line, sizeof line,
                  "total: %zu bytes = %.3f bits/triangle, %.3f bits/vertex (%u vertices, %u triangles, %zu levels)\n",
                  stream_bytes, 8.0 * double(stream_bytes) / levels.back().triangles,
                  8.0 * double(stream_bytes) / levels.back().vertices, levels.back().vertices,
                  levels.back().triangles, levels.size() - 1);
    s += line;
  }
  return s;
}

namespace {

// A level or tail chunk's two substreams, from its connectivity size on.
void count_substreams(MeshLevelStats& l, const uint8_t* p, const uint8_t* end, uint32_t size) {
  uint32_t conn = 0;
  if (read_varint(p, end, &conn) != Status::ok || conn > static_cast<uint32_t>(end - p)) return;
  l.connectivity_bytes += conn;
  l.geometry_bytes += static_cast<uint64_t>(end - p) - conn;
  l.chunk_bytes += size + kChunkHeadBytes + kChunkTailBytes;
  ++l.chunks;
}

}  // namespace

bool MeshChunkSummary::add(uint32_t type, const uint8_t* payload, uint32_t size) {
  const uint8_t* p = payload;
  const uint8_t* end = payload + size;
  if (type == chunk::kMeshHeader) {
    if (mesh_header_from_bytes(payload, size, &header_) != Status::ok) return true;
    have_header_ = true;
    levels_.assign(1, MeshLevelStats{});
    levels_[0].vertices_added = levels_[0].vertices = header_.base_vertices;
    levels_[0].triangles_added = levels_[0].triangles = header_.base_triangles;
    return true;
  }
  if (!have_header_) return type == chunk::kMeshBase || type == chunk::kMeshLevel || type == chunk::kMeshTail;
  if (type == chunk::kMeshTail) {
    uint32_t first = 0, count = 0;
    if (!header_.tail() || read_varint(p, end, &first) != Status::ok || read_varint(p, end, &count) != Status::ok)
      return true;
    const uint32_t level = header_.levels;
    if (levels_.size() <= level) levels_.resize(level + 1);
    MeshLevelStats& l = levels_[level];
    l.level = level;
    l.tail = true;
    count_substreams(l, p, end, size);
    return true;
  }
  if (type == chunk::kMeshBase) {
    uint32_t first = 0, count = 0;
    if (read_varint(p, end, &first) != Status::ok || read_varint(p, end, &count) != Status::ok) return true;
    levels_[0].connectivity_bytes += static_cast<uint64_t>(end - p);
    levels_[0].chunk_bytes += size + kChunkHeadBytes + kChunkTailBytes;
    ++levels_[0].chunks;
    return true;
  }
  if (type == chunk::kMeshLevel) {
    uint32_t level = 0, first = 0, count = 0, dv = 0, dt = 0;
    if (read_varint(p, end, &level) != Status::ok || read_varint(p, end, &first) != Status::ok ||
        read_varint(p, end, &count) != Status::ok || level == 0 || level > header_.levels)
      return true;
    if (levels_.size() <= level) levels_.resize(level + 1);
    MeshLevelStats& l = levels_[level];
    l.level = level;
    if (first == 0) {
      if (read_varint(p, end, &dv) != Status::ok || read_varint(p, end, &dt) != Status::ok || p >= end) return true;
      l.weight_q4 = *p++;
      l.vertices_added = dv;
      l.triangles_added = dt;
    }
    count_substreams(l, p, end, size);
    return true;
  }
  return false;
}

std::string MeshChunkSummary::table() const {
  if (!have_header_) return "";
  std::vector<MeshLevelStats> rows = levels_;
  uint32_t v = 0, t = 0;
  for (MeshLevelStats& r : rows) {
    if (r.tail) {  // net of the levels before it
      r.vertices_added = header_.vertices - v;
      r.triangles_added = header_.triangles - t;
    }
    v += r.vertices_added;
    t += r.triangles_added;
    r.vertices = v;
    r.triangles = t;
  }
  char line[200];
  std::snprintf(line, sizeof line,
                "progressive mesh: %u-bit grid, %s coder, %s predictor, %u levels, max degree %u, up %s\n",
                header_.bits, header_.coder == MeshCoder::arith ? "arithmetic" : "Huffman",
                mesh_predictor_name(header_.predictor), header_.levels, header_.max_degree,
                mesh_up_name(header_.up));
  uint64_t bytes = 0;
  for (const MeshLevelStats& r : rows) bytes += r.chunk_bytes;
  return std::string(line) + format_mesh_table(rows, bytes) +
         "(C, G: connectivity and geometry substream bits; bytes: the level's chunks with framing;\n"
         " the total above counts mesh chunks only, not HEAD/MSHH/END)\n";
}

}  // namespace vds::enc
