// vds encoder, progressive mesh coding: the single-rate tail traced in step
// with the client's MeshTail (docs/mesh-codec.md, "The single-rate tail").
#include "mesh_trace.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <stdexcept>
#include <unordered_map>

namespace vds::enc::mesh_trace {

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


}  // namespace vds::enc::mesh_trace
