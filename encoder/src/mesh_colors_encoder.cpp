// vds encoder: the mesh colors codec's encoder (paper mode). The bitstream
// is defined by the client's decoder (vds/mesh_colors.h); this file writes
// what it reads.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "vds/enc/arith_encoder.h"
#include "vds/enc/mesh_colors.h"
#include "vds/image_model.h"
#include "vds/mesh_colors.h"

namespace vds::enc {
namespace {

constexpr double kPi = 3.14159265358979323846;
// vertex_step_for_quality: the vertex samples' step per unit of quality
// (docs/model-mode.md, "Vertex samples").
constexpr double kVertexStepPerQuality = 0.5;

// The modified DCT-II of length n: out[0] the mean, out[k] = sum x_i cos(pi/n (i + 1/2) k).
void forward_dct(const double* x, int n, double* out, int in_stride = 1, int out_stride = 1) {
  double mean = 0;
  for (int i = 0; i < n; ++i) mean += x[i * in_stride];
  out[0] = mean / n;
  for (int k = 1; k < n; ++k) {
    double s = 0;
    for (int i = 0; i < n; ++i) s += x[i * in_stride] * std::cos(kPi / n * (i + 0.5) * k);
    out[k * out_stride] = s;
  }
}


int32_t quantise(double coef, uint32_t step_q4) { return static_cast<int32_t>(std::lround(coef * 16 / step_q4)); }


struct Block {
  uint32_t element = 0;  // edges 0 .. E - 1, then faces E + f
  int comp = 0;
  int kind = 0;  // 0 face, 1 edge
  int positions = 0;
  int32_t dc_diff = 0;
  std::vector<int32_t> ac;  // in the order the decoder reads them
};

struct Pair {
  uint32_t run;
  int32_t amp;
};

// The pairs of one context set's AC sequence (vds/mesh_colors.h).
std::vector<Pair> make_pairs(const std::vector<int32_t>& seq) {
  std::vector<Pair> out;
  uint32_t zeros = 0;
  for (int32_t v : seq) {
    if (v == 0) {
      ++zeros;
      continue;
    }
    while (zeros > mc::kMaxRun) {
      out.push_back({mc::kMaxRun, 0});
      zeros -= mc::kMaxRun;
    }
    out.push_back({zeros, v});
    zeros = 0;
  }
  while (zeros > 0) {
    const uint32_t r = std::min(zeros, mc::kMaxRun);
    out.push_back({r, 0});
    zeros -= r;
  }
  return out;
}

// The orthonormal DCT-II of length n (the vds mode).
void forward_orthonormal(const double* x, int n, double* out, int in_stride = 1, int out_stride = 1) {
  for (int k = 0; k < n; ++k) {
    double s = 0;
    for (int i = 0; i < n; ++i) s += x[i * in_stride] * std::cos(kPi / n * (i + 0.5) * k);
    out[k * out_stride] = s * (k == 0 ? std::sqrt(1.0 / n) : std::sqrt(2.0 / n));
  }
}

// The vds mode's levels of a block (lv[0 .. positions - 1], scan order):
// the mirror of the client's read_levels (decoder/src/mesh_colors.cpp).
void write_levels(ArithEncoder& enc, mc::BlockContexts& cx, int cls, int kind, int positions, uint8_t& prev_nz,
                  const std::vector<int32_t>& lv) {
  uint32_t nz = 0;
  for (int z = 0; z < positions; ++z) nz += lv[z] != 0;
  enc.encode_ueg(cx.nz[cls][kind][image_model::kNzBucketOf[prev_nz]], mc::BlockContexts::kNzCtx, nz, mc::kNzCutoff,
                 mc::kNzOrder);
  prev_nz = static_cast<uint8_t>(nz);
  uint32_t left = nz;
  int order = 0;
  for (int z = 0; z < positions && left > 0; ++z) {
    const int32_t v = lv[z];
    if (static_cast<uint32_t>(positions - z) != left)
      enc.encode_bit(cx.sig[cls][kind][image_model::kSigPosOf[z]][image_model::kSigLeftOf[left]], v != 0);
    if (v == 0) continue;
    const int lp = image_model::kLevelPosOf[z], ll = image_model::kLevelLeftOf[left];
    const uint32_t mag = static_cast<uint32_t>(v < 0 ? -v : v);
    enc.encode_bit(cx.gt1[cls][kind][lp][ll], mag > 1);
    if (mag > 1) {
      enc.encode_bit(cx.gt2[cls][kind][lp][ll], mag > 2);
      if (mag > 2) {
        const uint32_t rest = mag - 3;
        enc.encode_exp_golomb(nullptr, 0, rest, order);
        if (rest > (image_model::kRestRaise << order) && order < image_model::kRestMaxOrder) ++order;
      }
    }
    enc.encode_bypass(v < 0);
    --left;
  }
}

// Every block of level m, quantised, in the decoder's order. `layout` and
// `next` are set up alike; with chroma_half the chroma is coded from level
// m + 1's samples on its lattice (`next` holds its layout), and a block's
// predictions read that lattice's reconstruction, as the client reads
// those samples where they lie in level m's (vds::mc::kFlagChromaHalf).
std::vector<Block> level_blocks(const MeshColorsModel& model, mc::MeshColors& layout, mc::MeshColors& next,
                                const mc::Steps& steps, int m, uint8_t mode, double deadzone, bool chroma_half) {
  const mc::Topology& topo = layout.topology();
  const bool paper = mode == mc::kModePaper;
  const mc::ComponentGroup* groups = nullptr;
  const int group_count = mc::component_groups(chroma_half, &groups);
  layout.layout_level(m);
  next.layout_level(m + 1);
  // Per shift: the layout, the source planes and their reconstruction
  // (every block replaced by its reconstruction in turn).
  const mc::MeshColors* lay[2] = {&layout, &next};
  const std::array<std::vector<uint8_t>, 3>* src[2] = {&model.levels[static_cast<size_t>(m)],
                                                      &model.levels[static_cast<size_t>(chroma_half ? m + 1 : m)]};
  std::array<std::vector<uint8_t>, 3> recon[2];
  recon[0] = *src[0];
  if (chroma_half) recon[1] = *src[1];
  std::vector<Block> blocks;
  auto quantise_ac = [&](double coef, uint32_t step_q4) {
    if (paper) return quantise(coef, step_q4);
    const double a = std::fabs(coef) * 16 / step_q4;
    const int32_t q = static_cast<int32_t>(std::floor(a + 0.5 - deadzone));
    return coef < 0 ? -std::max(q, 0) : std::max(q, 0);
  };

  for (uint32_t e = 0; e < topo.edges; ++e)
    for (const mc::ComponentGroup* g = groups; g != groups + group_count; ++g) {
      const int lm = m + g->shift;
      const mc::Layout& l = lay[g->shift]->layout();
      const uint32_t n = mc::edge_samples(mc::level_res(layout.edge_res()[e], lm));
      const uint32_t base = l.edge_base + l.edge_offset[e];
      int64_t prev_q[3] = {0, 0, 0};
      for (uint32_t b = 0; 8 * b < n; ++b) {
        const int len = static_cast<int>(std::min<uint32_t>(8, n - 8 * b));
        for (int c = g->first; c < g->end; ++c) {
          const uint32_t* step = steps.edge[c == 0 ? 0 : 1];
          double x[8], X[8];
          for (int i = 0; i < len; ++i) x[i] = (*src[g->shift])[c][base + 8 * b + i];
          const int64_t vertex_q4 = int64_t{16} * model.vertex_ycc[3 * topo.edge_vertex[2 * e] + c];
          uint8_t* dst = recon[g->shift][c].data() + base + 8 * b;
          const uint32_t dc_step = paper ? step[0] : mc::mean_step(step[0]);
          const int64_t centre = paper ? 0 : mc::kMeanCentreQ4;
          const int64_t pred = paper && b > 0
                                   ? prev_q[c]
                                   : mc::div_round((b == 0 ? vertex_q4 : mc::mean_q4(dst - 8, 8)) - centre, dc_step);
          Block blk;
          blk.element = e;
          blk.comp = c;
          blk.kind = 1;
          blk.positions = len;
          int32_t q[8];
          int64_t mean_q4 = 0;
          if (paper) {
            forward_dct(x, len, X);
            q[0] = quantise(X[0], step[0]);
            blk.dc_diff = static_cast<int32_t>(q[0] - pred);
            for (int k = 1; k < len; ++k) blk.ac.push_back(q[k] = quantise(X[k], step[k]));
          } else {
            // The mean's index, from 128, rounded exactly (halves away from 0).
            int64_t sum = 0;
            for (int i = 0; i < len; ++i) sum += static_cast<int64_t>(x[i]);
            const int32_t qm = static_cast<int32_t>(mc::div_round(16 * sum - centre * len, int64_t{len} * dc_step));
            blk.dc_diff = static_cast<int32_t>(qm - pred);
            mean_q4 = centre + int64_t{qm} * dc_step;
            for (int i = 0; i < len; ++i) x[i] -= mean_q4 / 16.0;
            forward_orthonormal(x, len, X);
            for (int k = 0; k < len; ++k) blk.ac.push_back(q[k] = quantise_ac(X[k], step[k]));
          }
          const int32_t dc_index = paper ? q[0] : static_cast<int32_t>(blk.dc_diff + pred);
          mc::reconstruct_edge_block(q, len, step, mode, mean_q4, dst);
          q[0] = dc_index;
          prev_q[c] = q[0];
          blocks.push_back(std::move(blk));
        }
      }
    }

  for (uint32_t f = 0; f < topo.faces; ++f)
    for (const mc::ComponentGroup* g = groups; g != groups + group_count; ++g) {
      const int lm = m + g->shift;
      const mc::Layout& l = lay[g->shift]->layout();
      const int rf = mc::level_res(model.face_res[f], lm);
      if (mc::face_samples(rf) == 0) continue;
      const int32_t n = static_cast<int32_t>(mc::resolution(rf)) - 2;
      const uint32_t base = l.face_base + l.face_offset[f];
      int64_t corner_q4[3] = {0, 0, 0};
      for (int c = g->first; c < g->end; ++c) corner_q4[c] = lay[g->shift]->corner_sum_q4(f, lm, recon[g->shift][c].data());
      int64_t left_q[3] = {0, 0, 0}, row_q[3] = {0, 0, 0}, left_mean[3] = {0, 0, 0}, row_mean[3] = {0, 0, 0};
      for (int32_t br = 0; 8 * br < n; ++br)
        for (int32_t bc = 0; n - 8 * (br + bc) >= 1; ++bc) {
          const int32_t D = n - 8 * (br + bc);
          const int rows = std::min(D, 8);
          const int positions = mc::face_block_positions(D);
          for (int c = g->first; c < g->end; ++c) {
            const uint32_t* step = steps.face[c == 0 ? 0 : 1];
            double x[64] = {}, rowX[64] = {}, Z[64] = {};
            const uint32_t dc_step = paper ? step[0] : mc::mean_step(step[0]);
            const int64_t pred =
                paper ? (bc > 0 ? left_q[c] : (br > 0 ? row_q[c] : mc::div_round(corner_q4[c], 2 * dc_step)))
                      : mc::div_round((bc > 0 ? left_mean[c] : (br > 0 ? row_mean[c] : mc::div_round(corner_q4[c], 2))) -
                                          mc::kMeanCentreQ4,
                                      dc_step);
            double sum = 0;
            for (int r = 0; r < rows; ++r) {
              const int32_t gr = 8 * br + r;
              const int len = std::min(8, D - r);
              const uint8_t* from =
                  (*src[g->shift])[c].data() + base + static_cast<uint32_t>(gr * n - gr * (gr - 1) / 2 + 8 * bc);
              for (int i = 0; i < len; ++i) sum += x[8 * r + i] = from[i];
            }
            Block blk;
            blk.element = topo.edges + f;
            blk.comp = c;
            blk.kind = 0;
            blk.positions = positions;
            int32_t q[64] = {};
            int64_t mean_q4 = 0;
            if (paper) {
              for (int r = 0; r < rows; ++r) forward_dct(x + 8 * r, std::min(8, D - r), rowX + 8 * r);
              for (int k = 0; k < rows; ++k) forward_dct(rowX + k, std::min(8, D - k), Z + k, 8, 8);
              q[0] = quantise(Z[0], step[0]);
              blk.dc_diff = static_cast<int32_t>(q[0] - pred);
              for (int z = 1; z < positions; ++z) {
                const int pos = image_model::kZigzag[z];
                blk.ac.push_back(q[pos] = quantise(Z[pos], step[pos]));
              }
            } else {
              // The mean's index, from 128, rounded exactly (halves away from 0).
              const int32_t qm = static_cast<int32_t>(mc::div_round(
                  16 * static_cast<int64_t>(sum) - mc::kMeanCentreQ4 * positions, int64_t{positions} * dc_step));
              blk.dc_diff = static_cast<int32_t>(qm - pred);
              mean_q4 = mc::kMeanCentreQ4 + int64_t{qm} * dc_step;
              for (int r = 0; r < rows; ++r) {
                const int len = std::min(8, D - r);
                for (int i = 0; i < len; ++i) x[8 * r + i] -= mean_q4 / 16.0;
                forward_orthonormal(x + 8 * r, len, rowX + 8 * r);
              }
              for (int k = 0; k < rows; ++k) forward_orthonormal(rowX + k, std::min(8, D - k), Z + k, 8, 8);
              for (int z = 0; z < positions; ++z) {
                const int pos = image_model::kZigzag[z];
                blk.ac.push_back(q[pos] = quantise_ac(Z[pos], step[pos]));
              }
            }
            const int64_t mean =
                mc::reconstruct_face_block(q, D, step, mode, mean_q4, recon[g->shift][c].data() + base, n, br, bc);
            if (!paper) q[0] = static_cast<int32_t>(blk.dc_diff + pred);
            left_q[c] = q[0];
            left_mean[c] = mean;
            if (bc == 0) {
              row_q[c] = q[0];
              row_mean[c] = mean;
            }
            blocks.push_back(std::move(blk));
          }
        }
    }

  return blocks;
}

// The MCLV payload of blocks [b0, b1) of level m, whose elements are
// [first, first + count): the contexts start afresh in every chunk.
std::vector<uint8_t> code_chunk(const std::vector<Block>& all, size_t b0, size_t b1, int m, uint32_t first,
                                uint32_t count, bool paper) {
  const std::vector<Block> blocks(all.begin() + static_cast<std::ptrdiff_t>(b0),
                                  all.begin() + static_cast<std::ptrdiff_t>(b1));
  ArithEncoder enc;
  if (paper) {
    // The pairs of each context set, then everything in the decoder's order.
    std::vector<int32_t> seq[3][2];
    for (const Block& b : blocks) seq[b.comp][b.kind].insert(seq[b.comp][b.kind].end(), b.ac.begin(), b.ac.end());
    std::vector<Pair> pairs[3][2];
    size_t cursor[3][2] = {};
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 2; ++k) pairs[c][k] = make_pairs(seq[c][k]);
    struct State {
      uint32_t zeros = 0;
      bool has_amp = false;
    } st[3][2];
    mc::CodecContexts cx;
    cx.reset();
    for (const Block& b : blocks) {
      const int c = b.comp, k = b.kind;
      enc.encode_signed(cx.dc_zero[c][k], cx.dc_mag[c][k], mc::CodecContexts::kDcCtx, b.dc_diff, mc::kDcCutoff,
                        mc::kDcOrder);
      for (size_t i = 0; i < b.ac.size(); ++i) {
        State& s = st[c][k];
        if (s.zeros > 0) {
          --s.zeros;
          continue;
        }
        if (s.has_amp) {
          s.has_amp = false;
          continue;
        }
        const Pair p = pairs[c][k].at(cursor[c][k]++);
        enc.encode_ueg(cx.run[c][k], mc::CodecContexts::kRunCtx, p.run, mc::kRunCutoff, mc::kRunOrder);
        enc.encode_signed(cx.amp_zero[c][k], cx.amp_mag[c][k], mc::CodecContexts::kAmpCtx, p.amp, mc::kAmpCutoff,
                          mc::kAmpOrder);
        if (p.amp == 0) {
          s.zeros = p.run - 1;
        } else if (p.run > 0) {
          s.zeros = p.run - 1;
          s.has_amp = true;
        }
      }
    }
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 2; ++k)
        if (cursor[c][k] != pairs[c][k].size()) throw std::logic_error("mesh colors: pairs left unwritten");
  } else {
    mc::BlockContexts cx;
    cx.reset();
    uint8_t prev_nz[2][2] = {};
    for (const Block& b : blocks) {
      const int cls = b.comp == 0 ? 0 : 1;
      enc.encode_signed(cx.dc_zero[cls][b.kind], cx.dc_mag[cls][b.kind], mc::BlockContexts::kDcCtx, b.dc_diff,
                        mc::kDcCutoff, mc::kDcOrder);
      write_levels(enc, cx, cls, b.kind, b.positions, prev_nz[cls][b.kind], b.ac);
    }
  }
  std::vector<uint8_t> out(mc::kLevelHeadBytes);
  out[0] = static_cast<uint8_t>(m);
  for (int i = 0; i < 4; ++i) {
    out[1 + i] = static_cast<uint8_t>(first >> (8 * i));
    out[5 + i] = static_cast<uint8_t>(count >> (8 * i));
  }
  const std::vector<uint8_t> body = enc.finish();
  out.insert(out.end(), body.begin(), body.end());
  return out;
}

// Level m as chunks of at most max_chunk bytes (0: one chunk): each the
// most elements from where the last ended that fit (found by bisection).
std::vector<std::vector<uint8_t>> encode_level(const MeshColorsModel& model, mc::MeshColors& layout,
                                               mc::MeshColors& next, const mc::Steps& steps, int m, uint8_t mode,
                                               double deadzone, bool chroma_half, size_t max_chunk) {
  const std::vector<Block> blocks = level_blocks(model, layout, next, steps, m, mode, deadzone, chroma_half);
  const uint32_t n = layout.topology().edges + layout.topology().faces;
  const bool paper = mode == mc::kModePaper;
  // begin[e]: the first block of element e (blocks come in element order).
  std::vector<size_t> begin(n + 1, blocks.size());
  for (size_t i = blocks.size(); i-- > 0;) begin[blocks[i].element] = i;
  for (uint32_t e = n; e-- > 0;) begin[e] = std::min(begin[e], begin[e + 1]);
  auto chunk = [&](uint32_t a, uint32_t b) { return code_chunk(blocks, begin[a], begin[b], m, a, b - a, paper); };
  std::vector<std::vector<uint8_t>> out;
  uint32_t at = 0;
  while (at < n) {
    std::vector<uint8_t> whole = chunk(at, n);
    if (max_chunk == 0 || whole.size() <= max_chunk) {
      out.push_back(std::move(whole));
      break;
    }
    uint32_t lo = at + 1, hi = n - 1;  // the most elements that fit: at least one
    std::vector<uint8_t> best = chunk(at, lo);
    if (best.size() > max_chunk) throw std::invalid_argument("mesh colors: one face takes more than a chunk");
    while (lo < hi) {
      const uint32_t mid = lo + (hi - lo + 1) / 2;
      std::vector<uint8_t> c = chunk(at, mid);
      if (c.size() <= max_chunk) {
        lo = mid;
        best = std::move(c);
      } else {
        hi = mid - 1;
      }
    }
    out.push_back(std::move(best));
    at = lo;
  }
  return out;
}

struct Layout {
  std::vector<uint8_t> work;
  Arena arena;
  mc::MeshColors mc;
};

// Every vertex's neighbours (vds::mc::vertex_prediction's), in `scratch`.
mc::Adjacency vertex_neighbours(const mc::Topology& topo, std::vector<uint8_t>& scratch) {
  scratch.assign(mc::adjacency_bytes(topo.vertices, topo.edges), 0);
  Arena arena(scratch.data(), scratch.size());
  mc::Adjacency adj;
  if (mc::build_adjacency(arena, topo, &adj) != Status::ok) throw std::logic_error("mesh colors: adjacency");
  return adj;
}

// `model` with its vertex samples as a client reconstructs them from
// differences coded in multiples of `step` (kFlagVertexStep): vertex by
// vertex, each the prediction from the samples reconstructed before it
// plus the nearest whole number of steps inside 0..255; the same samples
// at every level.
MeshColorsModel with_stepped_vertices(const MeshColorsModel& model, const mc::Adjacency& adj, int step) {
  MeshColorsModel out = model;
  const uint32_t V = static_cast<uint32_t>(model.positions.size());
  for (uint32_t v = 0; v < V; ++v)
    for (int c = 0; c < 3; ++c) {
      const int32_t p = mc::vertex_prediction(adj, out.vertex_ycc.data(), v, c);
      int32_t k = static_cast<int32_t>(std::lround((static_cast<double>(model.vertex_ycc[3 * v + c]) - p) / step));
      while (p + k * step > 255) --k;
      while (p + k * step < 0) ++k;
      out.vertex_ycc[3 * v + c] = static_cast<uint8_t>(p + k * step);
    }
  for (auto& level : out.levels)
    for (int c = 0; c < 3; ++c)
      for (uint32_t v = 0; v < V; ++v) level[c][v] = out.vertex_ycc[3 * v + c];
  return out;
}

void set_up(const MeshColorsModel& model, uint16_t q8, uint8_t mode, bool chroma_half, Layout& l) {
  const uint32_t F = static_cast<uint32_t>(model.face_res.size());
  const uint32_t V = static_cast<uint32_t>(model.positions.size());
  l.work.assign(mc::MeshColors::init_bytes(F, V), 0);
  l.arena = Arena(l.work.data(), l.work.size());
  if (l.mc.init(l.arena, model.triangles.data(), F, V) != Status::ok ||
      l.mc.set(model.face_res.data(), model.vertex_ycc.data(), q8, mode, chroma_half) != Status::ok)
    throw std::invalid_argument("mesh colors: the model's mesh is not one a client can hold");
}

}  // namespace

namespace {
// The header and levels of encode_mesh_colors, or (only_level >= 0) the
// header and that level alone, in one chunk.
MccEncoded encode_impl(const MeshColorsModel& model, double quality, const MccOptions& o, int only_level);
}  // namespace

MeshColorsModel with_stepped_vertex_samples(const MeshColorsModel& model, int step) {
  if (step <= 1) return model;
  Layout l;
  set_up(model, 256, mc::kModeVds, false, l);
  std::vector<uint8_t> scratch;
  return with_stepped_vertices(model, vertex_neighbours(l.mc.topology(), scratch), std::min(step, mc::kMaxVertexStep));
}

int vertex_step_for_quality(double quality) {
  return static_cast<int>(std::clamp<long>(std::lround(kVertexStepPerQuality * quality), 1, mc::kMaxVertexStep));
}

MccEncoded encode_mesh_colors(const MeshColorsModel& model, double quality, const MccOptions& o) {
  return encode_impl(model, quality, o, -1);
}

namespace {
MccEncoded encode_impl(const MeshColorsModel& given, double quality, const MccOptions& o, int only_level) {
  const bool chroma_half = o.chroma_half;
  const uint16_t q8 = static_cast<uint16_t>(std::clamp<long>(std::lround(quality * 256), 1, 65535));
  const uint8_t mode = o.paper ? mc::kModePaper : mc::kModeVds;
  const bool outside = o.vertex_colours_outside;
  const int vertex_step =
      o.paper || outside ? 1 : std::clamp(o.vertex_step > 0 ? o.vertex_step : vertex_step_for_quality(quality), 1, mc::kMaxVertexStep);
  Layout l, next;
  set_up(given, q8, mode, chroma_half, l);
  // The vds mode's own vertex samples are coded from their neighbours'.
  std::vector<uint8_t> scratch;
  const bool coded_vertices = !o.paper && !outside;
  const mc::Adjacency adj = coded_vertices ? vertex_neighbours(l.mc.topology(), scratch) : mc::Adjacency{};
  // Lossy vertex samples: the model with the samples the client will
  // reconstruct, coded from there on as if they were its own.
  MeshColorsModel lossy;
  if (vertex_step > 1) {
    lossy = with_stepped_vertices(given, adj, vertex_step);
    set_up(lossy, q8, mode, chroma_half, l);
  }
  const MeshColorsModel& model = vertex_step > 1 ? lossy : given;
  set_up(model, q8, mode, chroma_half, next);
  const uint32_t F = static_cast<uint32_t>(model.face_res.size());
  const uint32_t V = static_cast<uint32_t>(model.positions.size());
  MccEncoded out;
  std::vector<uint8_t>& h = out.header;
  const uint8_t flags = static_cast<uint8_t>((outside ? mc::kFlagVertexColours : 0) | (chroma_half ? mc::kFlagChromaHalf : 0) |
                                             (vertex_step > 1 ? mc::kFlagVertexStep : 0));
  h = {mc::kVersion, mode, static_cast<uint8_t>(model.max_res), flags,
       static_cast<uint8_t>(q8 & 0xFF),
       static_cast<uint8_t>(q8 >> 8), static_cast<uint8_t>(V & 0xFF), static_cast<uint8_t>(V >> 8),
       static_cast<uint8_t>(F & 0xFF), static_cast<uint8_t>((F >> 8) & 0xFF), static_cast<uint8_t>((F >> 16) & 0xFF),
       static_cast<uint8_t>(F >> 24)};
  if (vertex_step > 1) h.push_back(static_cast<uint8_t>(vertex_step));
  if (o.paper && !outside) h.insert(h.end(), model.vertex_ycc.begin(), model.vertex_ycc.end());
  ArithEncoder enc;
  ArithContext ctx[mc::kMaxResLog2 + 1][mc::kMaxResLog2];
  arith_init_contexts(&ctx[0][0], (mc::kMaxResLog2 + 1) * mc::kMaxResLog2);
  int prev = 0;
  if (model.max_res > 0)
    for (uint32_t f = 0; f < F; ++f) {
      enc.encode_unary(ctx[prev], mc::kMaxResLog2, model.face_res[f], static_cast<uint32_t>(model.max_res));
      prev = model.face_res[f];
    }
  if (coded_vertices) {
    mc::VertexContexts vx;
    vx.reset();
    for (uint32_t v = 0; v < V; ++v)
      for (int c = 0; c < 3; ++c) {
        const int cls = c == 0 ? 0 : 1;
        // In steps: the lossy model's samples are the prediction plus whole steps.
        const int32_t r = (model.vertex_ycc[3 * v + c] - mc::vertex_prediction(adj, model.vertex_ycc.data(), v, c)) / vertex_step;
        enc.encode_signed(vx.zero[cls], vx.mag[cls], mc::VertexContexts::kMagCtx, r, mc::kDcCutoff, mc::kDcOrder);
      }
  }
  const std::vector<uint8_t> body = enc.finish();
  h.insert(h.end(), body.begin(), body.end());
  mc::Steps steps;
  mc::make_steps(q8, mode, &steps);
  if (only_level >= 0) {
    if (only_level < model.max_res) {
      const std::vector<Block> blocks = level_blocks(model, l.mc, next.mc, steps, only_level, mode, o.deadzone, chroma_half);
      const uint32_t n = l.mc.topology().edges + l.mc.topology().faces;
      out.levels.resize(static_cast<size_t>(only_level) + 1);
      out.levels.back().push_back(code_chunk(blocks, 0, blocks.size(), only_level, 0, n, o.paper));
    }
    return out;
  }
  for (int m = 0; m < model.max_res; ++m)
    out.levels.push_back(encode_level(model, l.mc, next.mc, steps, m, mode, o.deadzone, chroma_half, o.max_chunk));
  return out;
}
}  // namespace

std::array<std::vector<uint8_t>, 3> decode_mesh_colors_level(const MeshColorsModel& model, const MccEncoded& enc, int m) {
  Layout l;
  set_up(model, 256, mc::kModePaper, false, l);
  // The vertex colours a client has when they came with the vertices.
  const size_t V = model.positions.size();
  std::array<std::vector<uint8_t>, 3> vc;
  for (int c = 0; c < 3; ++c) {
    vc[c].resize(V);
    for (size_t v = 0; v < V; ++v) vc[c][v] = model.vertex_ycc[3 * v + c];
  }
  const mc::Planes vertex_colours{vc[0].data(), vc[1].data(), vc[2].data()};
  Status s = l.mc.read_header(enc.header.data(), enc.header.size(), &vertex_colours);
  if (s != Status::ok) throw std::runtime_error(std::string("mesh colors header refused: ") + status_name(s));
  const uint32_t total = l.mc.layout_level(m);
  std::array<std::vector<uint8_t>, 3> planes{std::vector<uint8_t>(total), std::vector<uint8_t>(total),
                                             std::vector<uint8_t>(total)};
  if (m == model.max_res) {  // vertices only
    for (uint32_t v = 0; v < model.positions.size(); ++v)
      for (int c = 0; c < 3; ++c) planes[c][v] = l.mc.vertex_samples()[3 * v + c];
    return planes;
  }
  for (const std::vector<uint8_t>& c : enc.levels.at(static_cast<size_t>(m))) {
    s = l.mc.decode_level(c.data(), c.size(), mc::Planes{planes[0].data(), planes[1].data(), planes[2].data()});
    if (s != Status::ok) throw std::runtime_error(std::string("mesh colors level refused: ") + status_name(s));
  }
  if (!l.mc.level_complete()) throw std::logic_error("mesh colors: a level's chunks do not cover it");
  return planes;
}

}  // namespace vds::enc

namespace vds::enc {

std::vector<uint8_t> rd_face_resolutions(const MeshColorsModel& model, double quality, const MccOptions& o) {
  const uint32_t F = static_cast<uint32_t>(model.face_res.size());
  if (model.max_res == 0) return model.face_res;
  // Level 0 as the codec codes it: each face's samples as decoded.
  const MccEncoded coded = encode_impl(model, quality, o, 0);
  const auto decoded = decode_mesh_colors_level(model, coded, 0);
  const std::vector<std::vector<double>> coarser = coarser_face_sse(model);
  Layout l;
  set_up(model, 256, mc::kModePaper, false, l);
  l.mc.layout_level(0);
  const mc::Layout& lay = l.mc.layout();
  std::vector<uint8_t> out = model.face_res;
  for (uint32_t f = 0; f < F; ++f) {
    const int r = model.face_res[f];
    if (r == 0) continue;
    const uint32_t from = lay.face_base + lay.face_offset[f], to = lay.face_base + lay.face_offset[f + 1];
    double code_sse = 0;
    for (uint32_t i = from; i < to; ++i)
      for (int c = 0; c < 3; ++c) {
        const double d = double(decoded[c][i]) - model.levels[0][c][i];
        code_sse += kComponentWeight[c] * d * d;
      }
    // The coarsest lattice whose prediction, with its own coding error
    // (about 4^-k of the face's), is no worse than coding the face's samples.
    for (int k = r; k >= 1; --k) {
      const double keep = 1.0 / double(1u << (2 * k));
      if (coarser[f][static_cast<size_t>(k)] + code_sse * keep <= code_sse) {
        out[f] = static_cast<uint8_t>(r - k);
        break;
      }
    }
  }
  return out;
}

MeshColorsModel to_mesh_colors_rd(const TexturedModel& textured, const MeshColorsOptions& mo, double quality,
                                  const MccOptions& o) {
  return to_mesh_colors_rd(textured, mo, to_mesh_colors(textured, mo), quality, o);
}

MeshColorsModel to_mesh_colors_rd(const TexturedModel& textured, const MeshColorsOptions& mo, const MeshColorsModel& fine,
                                  double quality, const MccOptions& o) {
  MeshColorsOptions again = mo;
  again.face_max_res = rd_face_resolutions(fine, quality, o);
  again.vertex_filter_res = fine.face_res;
  return to_mesh_colors(textured, again);
}

}  // namespace vds::enc
