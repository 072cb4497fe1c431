// vds encoder, progressive mesh coding: one level of vertex splits traced
// with the client's own split, ranking and prediction code (Qin et al.
// 2002, section 3).
#include "mesh_trace.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <stdexcept>
#include <unordered_map>

namespace vds::enc::mesh_trace {

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

}  // namespace vds::enc::mesh_trace
