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

#include "mesh_trace.h"

namespace vds::enc {
namespace mesh_trace {

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


}  // namespace mesh_trace

using mesh_trace::Encoder;

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


}  // namespace vds::enc
