// The terrain mode's server side (vds/enc/terrain_server.h).
#include "vds/enc/terrain_server.h"

#include "vds/terrain_client.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "vds/bytes.h"
#include "vds/enc/arith_encoder.h"
#include "vds/enc/dct.h"
#include "vds/idct.h"
#include "vds/image_model.h"
#include "vds/terrain_client.h"

namespace vds::enc {

using terrain::Mask;
using terrain::mask_extent;
using terrain::mask_holds;

namespace {

constexpr double kPi = 3.14159265358979323846;
using image_model::kZigzag;

using V3 = std::array<double, 3>;
V3 operator+(V3 a, V3 b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
V3 operator-(V3 a, V3 b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
V3 operator*(V3 a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
double dot(V3 a, V3 b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
V3 cross(V3 a, V3 b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
V3 normalize(V3 a) {
  const double l = std::sqrt(dot(a, a));
  return l > 0 ? a * (1 / l) : a;
}

// The sample at (x, y) of plane c, clamped to the plane (blocks past the
// padded edge repeat it).
uint8_t plane_at(const Planes& p, int c, int x, int y) {
  x = std::clamp(x, 0, p.plane_width(c) - 1);
  y = std::clamp(y, 0, p.plane_height(c) - 1);
  return p.row(c, y)[x];
}

// The level-1 DC planes as `held` holds them: what a level-0 block that
// holds nothing shows, and what its DC is predicted from. A level-1 block's
// plane is computed when first asked for (64 level-0 blocks share it) and
// again after forget() (when the caller changes its mask in `held`).
class CoarsePlanes {
 public:
  CoarsePlanes(const TerrainCoding& t, const std::vector<Mask>& held)
      : t_(t), held_(held), planes_(t.grid.first(0, 0)), known_(t.grid.first(0, 0), 0) {}
  // Level-0 block `id`'s sample, in DC levels; false (and 0) when the
  // client holds nothing of its level-1 block.
  bool sample(uint32_t id, int* v) {
    int k;
    const uint32_t c = t_.grid.coarse(id, &k);
    return lookup(c, k, v);
  }
  // The same for the level-0 block at (bx, by) of component `comp`.
  bool sample(int comp, int bx, int by, int* v) {
    return lookup(t_.grid.id(1, comp, bx / 8, by / 8), (by % 8) * 8 + bx % 8, v);
  }
  void forget(uint32_t coarse) { known_[coarse] = 0; }

 private:
  bool lookup(uint32_t c, int k, int* v) {
    *v = 0;
    if (held_[c] == 0) return false;
    if (!known_[c]) {
      terrain::coarse_plane(t_.levels[c].data(), held_[c], t_.quantiser, planes_[c].data());
      known_[c] = 1;
    }
    *v = planes_[c][static_cast<size_t>(k)];
    return true;
  }
  const TerrainCoding& t_;
  const std::vector<Mask>& held_;
  std::vector<std::array<int16_t, 64>> planes_;
  std::vector<uint8_t> known_;
};

}  // namespace

// --- The terrain as coded ------------------------------------------------------------

TerrainCoding code_terrain(const TerrainMap& map, int quantiser) {
  if (quantiser < terrain::kMinQuantiser || quantiser > terrain::kMaxQuantiser)
    throw std::invalid_argument("terrain quantiser " + std::to_string(quantiser) + " (1..62)");
  TerrainCoding t;
  t.quantiser = quantiser;
  const int cx = (map.colour.width + 7) / 8, cy = (map.colour.height + 7) / 8;
  if (cx > terrain::kMaxCells || cy > terrain::kMaxCells)
    throw std::invalid_argument(map.name + ": a colour map of more than " + std::to_string(terrain::kMaxCells * 8) +
                                " pixels on a side");
  t.grid.cells_x = static_cast<uint16_t>(cx);
  t.grid.cells_y = static_cast<uint16_t>(cy);

  // The texture, padded to whole cells by repeating the last row and column.
  io::Image padded(cx * 8, cy * 8, 3);
  for (int y = 0; y < padded.height; ++y)
    for (int x = 0; x < padded.width; ++x)
      for (int c = 0; c < 3; ++c)
        padded.at(x, y, c) = map.colour.at(std::min(x, map.colour.width - 1), std::min(y, map.colour.height - 1), c);
  t.texture = rgb_to_planes(padded, ChromaFormat::yuv420);
  t.colour = std::move(padded);

  // The elevation at the cell corners: texel X of the colour map lies at
  // sample X (width - 1) / colour width of the heightmap.
  const double sx = static_cast<double>(map.width - 1) / map.colour.width;
  const double sy = static_cast<double>(map.height - 1) / map.colour.height;
  t.cell_m = 8 * sx * map.horizontal_scale;
  t.metres_per_unit = map.metres_per_unit;
  t.heights.resize(static_cast<size_t>(cx + 1) * (cy + 1));
  for (int j = 0; j <= cy; ++j)
    for (int i = 0; i <= cx; ++i) {
      const double units = map.height_at(8 * i * sx, 8 * j * sy) / map.metres_per_unit;
      t.heights[static_cast<size_t>(j) * (cx + 1) + i] = static_cast<uint16_t>(std::clamp(std::lround(units), 0L, 65535L));
    }

  // Every block's coefficients, quantised once: level 0 from the texture,
  // level 1 from the level-0 DC planes (edges repeated).
  t.levels.resize(t.grid.blocks());
  // Rounded to nearest, halves away from zero.
  auto quantise = [&](const int16_t coef[64], std::array<int16_t, 64>& lv) {
    lv[0] = static_cast<int16_t>(std::clamp(static_cast<int>(std::lround(coef[0] / 8.0)), -128, 127));
    for (int n = 1; n < 64; ++n) {
      const double step = terrain::kIntraMatrix[n] * quantiser / 16.0;
      lv[n] = static_cast<int16_t>(
          std::clamp(static_cast<int>(std::lround(coef[n] / step)), -terrain::kMaxLevel, terrain::kMaxLevel));
    }
  };
  for (int comp = 0; comp < 3; ++comp) {
    const int w = t.grid.plane_w(0, comp), h = t.grid.plane_h(0, comp);
    for (int by = 0; by < h; ++by)
      for (int bx = 0; bx < w; ++bx) {
        uint8_t px[64];
        for (int y = 0; y < 8; ++y)
          for (int x = 0; x < 8; ++x) px[y * 8 + x] = plane_at(t.texture, comp, bx * 8 + x, by * 8 + y);
        int16_t coef[64];
        fdct8x8(px, 8, coef);
        quantise(coef, t.levels[t.grid.id(0, comp, bx, by)]);
      }
    for (int by = 0; by < t.grid.plane_h(1, comp); ++by)
      for (int bx = 0; bx < t.grid.plane_w(1, comp); ++bx) {
        int16_t dc[64], coef[64];
        for (int y = 0; y < 8; ++y)
          for (int x = 0; x < 8; ++x)
            dc[y * 8 + x] = t.levels[t.grid.id(0, comp, std::min(bx * 8 + x, w - 1), std::min(by * 8 + y, h - 1))][0];
        fdct8x8(dc, coef);
        quantise(coef, t.levels[t.grid.id(1, comp, bx, by)]);
      }
  }
  return t;
}

std::vector<uint8_t> encode_elevation(const uint16_t* heights, int w, int h, terrain::ElevationPass pass, int y0,
                                      int y1) {
  ArithEncoder ae;
  terrain::ElevationContexts ctx;
  terrain::init_elevation_contexts(ctx);
  terrain::for_each_elevation_point(w, h, pass, heights, [&](int x, int y, int predict, int k) {
    ae.encode_signed(ctx.zero[k], ctx.mag[k], 8, heights[static_cast<size_t>(y) * w + x] - predict, 16, 2);
    return true;
  }, y0, y1);
  return ae.finish();
}

void reconstruct_block(const TerrainCoding& t, uint32_t id, Mask held, uint8_t out[64]) {
  int16_t coef[64];
  terrain::dequantise_held(t.levels[id].data(), held, t.quantiser, coef);
  idct8x8_put(coef, out, 8);
}

Planes reconstruct_texture(const TerrainCoding& t, const std::vector<Mask>& held) {
  Planes p = t.texture;
  update_texture(t, std::vector<Mask>(held.size(), ~Mask{0}), held, &p);
  return p;
}

double terrain_height(const TerrainCoding& t, double x, double y) {
  const double gi = std::clamp(x / t.cell_m, 0.0, static_cast<double>(t.grid.cells_x));
  const double gj = std::clamp(t.grid.cells_y - y / t.cell_m, 0.0, static_cast<double>(t.grid.cells_y));
  const int i0 = std::min(static_cast<int>(gi), t.grid.cells_x - 1), j0 = std::min(static_cast<int>(gj), t.grid.cells_y - 1);
  const double fi = gi - i0, fj = gj - j0;
  const double top = t.height_m(i0, j0) * (1 - fi) + t.height_m(i0 + 1, j0) * fi;
  const double bottom = t.height_m(i0, j0 + 1) * (1 - fi) + t.height_m(i0 + 1, j0 + 1) * fi;
  return top * (1 - fj) + bottom * fj;
}

int shown_dc(const TerrainCoding& t, const std::vector<Mask>& held, uint32_t id) {
  int v;
  CoarsePlanes(t, held).sample(id, &v);
  return v;
}

void update_texture(const TerrainCoding& t, const std::vector<Mask>& before, const std::vector<Mask>& held,
                    Planes* texture) {
  Planes& p = *texture;
  const terrain::BlockGrid& g = t.grid;
  bool coarse_changed = false;
  for (uint32_t id = 0; id < g.first(0, 0); ++id) coarse_changed = coarse_changed || before[id] != held[id];
  // What a level-0 block holding nothing shows: the DC planes as level 1
  // gives them, bilinear between block centres, as a renderer sampling them
  // with its bilinear filter would draw them.
  CoarsePlanes planes(t, held);
  for (uint32_t id = g.first(0, 0); id < g.blocks(); ++id) {
    const bool own = held[id] != 0;
    if (before[id] == held[id] && (own || !coarse_changed)) continue;
    const terrain::BlockPlace pl = g.place(id);
    const int w = g.plane_w(0, pl.comp), h = g.plane_h(0, pl.comp);
    uint8_t px[64];
    if (own) {
      reconstruct_block(t, id, held[id], px);
    } else {
      for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
          // Texel centre in block units, relative to block centres.
          const double fx = pl.bx + (x + 0.5) / 8 - 0.5, fy = pl.by + (y + 0.5) / 8 - 0.5;
          const int x0 = std::clamp(static_cast<int>(std::floor(fx)), 0, w - 1), y0 = std::clamp(static_cast<int>(std::floor(fy)), 0, h - 1);
          const int x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
          const double ax = std::clamp(fx - x0, 0.0, 1.0), ay = std::clamp(fy - y0, 0.0, 1.0);
          // Samples whose level-1 block the client does not hold take no part.
          double sum = 0, weight = 0;
          auto take = [&](int bx, int by, double wgt) {
            int v;
            if (planes.sample(pl.comp, bx, by, &v) && wgt > 0) sum += v * wgt, weight += wgt;
          };
          take(x0, y0, (1 - ax) * (1 - ay));
          take(x1, y0, ax * (1 - ay));
          take(x0, y1, (1 - ax) * ay);
          take(x1, y1, ax * ay);
          const double v = weight > 0 ? sum / weight : 0;
          px[y * 8 + x] = static_cast<uint8_t>(std::clamp(std::lround(v) + 128, 0L, 255L));
        }
    }
    for (int y = 0; y < 8; ++y) {
      const int py = pl.by * 8 + y;
      if (py >= p.plane_height(pl.comp)) break;
      for (int x = 0; x < 8; ++x) {
        const int qx = pl.bx * 8 + x;
        if (qx < p.plane_width(pl.comp)) p.row(pl.comp, py)[qx] = px[y * 8 + x];
      }
    }
  }
}

// --- Masks --------------------------------------------------------------------------------

Mask shrink_mask(double cutoff, double cos_alpha, double beta_s, bool keep_dc) {
  if (!(cutoff > 0)) return 0;
  const double kd = std::min(cutoff, 1.0);
  const double t = kd * std::clamp(cos_alpha, 0.0, 1.0);
  const double sin_b = std::sin(beta_s), tan_b = std::tan(beta_s);
  Mask m = 0;
  for (int v = 0; v < 8; ++v) {
    const double vv = (v + 0.5) / 8;
    double limit;
    if (vv > kd) {
      limit = -1;
    } else if (!(beta_s > 0) || sin_b == 0) {
      limit = vv > t ? -1 : kd;
    } else if (beta_s >= kPi / 2 || sin_b == 1) {
      limit = std::min(kd, t);
    } else {
      limit = std::min(kd, t - (vv - t) / tan_b);
    }
    // Coefficients u with (u + 0.5) / 8 <= limit.
    const int e = limit < 0 ? 0 : std::clamp(static_cast<int>(std::floor(8 * limit - 0.5)) + 1, 0, 8);
    m = terrain::mask_with_extent(m, v, e);
  }
  if (keep_dc && mask_extent(m, 0) == 0) m = terrain::mask_with_extent(m, 0, 1);
  return m;
}

std::vector<Mask> pose_masks(const TerrainCoding& t, const SceneCamera& cam, const PoseOptions& o,
                             std::vector<BlockView>* views_out) {
  const terrain::BlockGrid& g = t.grid;
  std::vector<Mask> masks(g.blocks(), 0);
  std::vector<BlockView> views(g.blocks());
  const double texel_m = t.cell_m / 8;
  for (int j = 0; j < g.cells_y; ++j) {
    for (int i = 0; i < g.cells_x; ++i) {
      const V3 p[4] = {t.point(i, j), t.point(i + 1, j), t.point(i, j + 1), t.point(i + 1, j + 1)};
      // In front of the camera, and on the screen.
      double x0 = 1e30, y0 = 1e30, x1 = -1e30, y1 = -1e30;
      int in_front = 0;
      for (const V3& q : p) {
        const V3 r = q - cam.position;
        const double cz = dot(r, cam.forward);
        if (cz <= o.near_m) continue;
        ++in_front;
        const double sx = cam.cx + cam.focal * dot(r, cam.right) / cz;
        const double sy = cam.cy + cam.focal * dot(r, cam.down) / cz;
        x0 = std::min(x0, sx), x1 = std::max(x1, sx), y0 = std::min(y0, sy), y1 = std::max(y1, sy);
      }
      if (in_front == 0) continue;
      if (in_front == 4 && (x1 < 0 || y1 < 0 || x0 > cam.width || y0 > cam.height)) continue;
      // Facing the viewer.
      const V3 centre = (p[0] + p[1] + p[2] + p[3]) * 0.25;
      V3 n = normalize(cross(p[3] - p[0], p[2] - p[1]));
      if (n[2] < 0) n = n * -1;  // a height field faces up
      const V3 to_eye = cam.position - centre;
      if (dot(n, to_eye) <= 0) continue;
      // Distance to the nearest point of the cell's bounds.
      double d2 = 0;
      for (int k = 0; k < 3; ++k) {
        const double lo = std::min({p[0][k], p[1][k], p[2][k], p[3][k]});
        const double hi = std::max({p[0][k], p[1][k], p[2][k], p[3][k]});
        const double e = cam.position[k];
        const double dd = e < lo ? lo - e : (e > hi ? e - hi : 0);
        d2 += dd * dd;
      }
      const double dist = std::max(std::sqrt(d2), 1e-6);
      const V3 v = normalize(to_eye);
      const double cos_a = std::clamp(dot(n, v), 0.0, 1.0);
      // The direction the tilt foreshortens, in texture axes.
      const V3 d = v - n * dot(v, n);
      const V3 tu = normalize((p[1] - p[0]) + (p[3] - p[2]));
      const V3 tv = normalize((p[2] - p[0]) + (p[3] - p[1]));
      const double du = std::fabs(dot(d, tu)), dv = std::fabs(dot(d, tv));
      const double beta = (du == 0 && dv == 0) ? 0 : std::atan2(dv, du);
      const double beta_s = kPi / 2 - beta;
      const double ppt = o.detail * cam.focal * texel_m / dist;
      const double pixels = std::min(ppt * ppt * 64 * std::max(cos_a, 0.05), 1.0 * cam.width * cam.height);

      // The cell's blocks: its luma block; the chroma blocks of its 2 x 2
      // cells (texels twice the size); and the level-1 blocks over those,
      // whose samples are blocks (8 times the size), the DC always kept.
      auto add = [&](uint32_t id, Mask m, double cutoff) {
        masks[id] = terrain::mask_union(masks[id], m);
        BlockView& v = views[id];
        if (!v.visible || cutoff > v.cutoff) v = BlockView{true, cutoff, cos_a, beta_s, v.pixels, dist};
        v.pixels += pixels;
        v.distance = std::min(v.distance, dist);
      };
      add(g.cell(i, j), shrink_mask(ppt, cos_a, beta_s, false), ppt);
      add(g.id(1, 0, i / 8, j / 8), shrink_mask(8 * ppt, cos_a, beta_s, true), 8 * ppt);
      for (int comp = 1; comp <= 2; ++comp) {
        add(g.id(0, comp, i / 2, j / 2), shrink_mask(2 * ppt, cos_a, beta_s, false), 2 * ppt);
        add(g.id(1, comp, i / 16, j / 16), shrink_mask(16 * ppt, cos_a, beta_s, true), 16 * ppt);
      }
    }
  }
  if (views_out != nullptr) *views_out = std::move(views);
  return masks;
}

// --- Updates ----------------------------------------------------------------------------------

namespace {

struct UpdateWriter {
  const TerrainCoding& t;
  ArithEncoder ae;
  terrain::TextureContexts ctx{};
  int64_t last_id = -1;
  int dc_prev[3] = {};

  explicit UpdateWriter(const TerrainCoding& tc) : t(tc) { terrain::init_texture_contexts(ctx); }

  void id(uint32_t id) {
    ae.encode_exp_golomb(ctx.id_gap, 8, static_cast<uint32_t>(id - last_id - 1), 0);
    last_id = id;
  }

  void mask(Mask held, Mask m, bool grow) {
    int above = 8;
    for (int v = 0; v < 8; ++v) {
      const int h = mask_extent(held, v), e = mask_extent(m, v);
      if (grow) {
        ae.encode_unary(&ctx.extent[1][v], 1, static_cast<uint32_t>(e - h), static_cast<uint32_t>(above - h));
      } else {
        const int cap = std::min(h, above);
        ae.encode_unary(&ctx.extent[0][v], 1, static_cast<uint32_t>(cap - e), static_cast<uint32_t>(cap));
      }
      above = e;
    }
  }

  // shown: the DC level a level-0 block shows before it holds anything
  // (its prediction when it grows from nothing).
  void coefficients(uint32_t id, Mask held, Mask m, int shown) {
    const terrain::BlockPlace pl = t.grid.place(id);
    const int comp = pl.comp, lvl = pl.level, cls = terrain::coefficient_class(pl);
    const auto& lv = t.levels[id];
    const bool intra = held == 0;
    if (intra) {
      const int pred = lvl == 0 ? terrain::dc_prediction(shown) : dc_prev[comp];
      ae.encode_signed(ctx.dc_zero[lvl][comp], ctx.dc_mag[lvl][comp], 6, lv[0] - pred, 8, 1);
      if (lvl == 1) dc_prev[comp] = lv[0];
    }
    uint8_t pos[63];
    const int n = terrain::added_positions(held, m, pos);
    if (n == 0) return;
    int last = -1;
    for (int i = 0; i < n; ++i)
      if (lv[kZigzag[pos[i]]] != 0) last = i;
    ae.encode_bit(ctx.cbf[intra ? 0 : 1][cls], last >= 0 ? 1 : 0);
    if (last < 0) return;
    bool any = false;
    for (int i = 0; i <= last; ++i) {
      const int k = pos[i], pc = terrain::position_class(k);
      const int v = lv[kZigzag[k]];
      if (!(i == n - 1 && !any)) ae.encode_bit(ctx.sig[cls][pc], v != 0 ? 1 : 0);
      if (v == 0) continue;
      ae.encode_ueg(&ctx.level[cls][pc], 1, static_cast<uint32_t>(std::abs(v) - 1), 14, 0);
      ae.encode_bypass(v < 0 ? 1 : 0);
      any = true;
      if (i < n - 1) ae.encode_bit(ctx.last[cls][pc], i == last ? 1 : 0);
    }
  }
};

}  // namespace

std::vector<uint8_t> encode_update(const TerrainCoding& t, const std::vector<Mask>& held, uint32_t frame,
                                   const std::vector<BlockChange>& shrinks, const std::vector<BlockChange>& grows) {
  if (shrinks.size() > 0xFFFF || grows.size() > 0xFFFF) throw std::invalid_argument("encode_update: too many blocks");
  UpdateWriter w(t);
  // The client's masks as it reads the update: the shrinks applied, then
  // each grow in turn (a block both shrunk and grown grows from what the
  // shrink left; a level-0 block's prediction sees the level-1 grows
  // before it).
  std::vector<Mask> work = held;
  CoarsePlanes planes(t, work);
  const uint32_t fine = t.grid.first(0, 0);
  auto change = [&](uint32_t id, Mask m) {
    work[id] = m;
    if (id < fine) planes.forget(id);
  };
  for (const BlockChange& s : shrinks) {
    w.id(s.id);
    w.mask(work[s.id], s.mask, false);
    change(s.id, s.mask);
  }
  w.last_id = -1;
  for (const BlockChange& g : grows) {
    const Mask before = work[g.id];
    w.id(g.id);
    w.mask(before, g.mask, true);
    int shown = 0;
    if (g.id >= fine && before == 0) planes.sample(g.id, &shown);
    w.coefficients(g.id, before, g.mask, shown);
    change(g.id, g.mask);
  }
  std::vector<uint8_t> body = w.ae.finish();
  std::vector<uint8_t> out(8 + body.size());
  store_le32(out.data(), frame);
  store_le16(out.data() + 4, static_cast<uint32_t>(shrinks.size()));
  store_le16(out.data() + 6, static_cast<uint32_t>(grows.size()));
  std::copy(body.begin(), body.end(), out.begin() + 8);
  return out;
}

double TerrainServer::stage_score(uint32_t b, Mask from, Mask to, double pixels, int shown) const {
  double energy = 0, bits = 4;
  for (int k = 0; k < 64; ++k) {
    if (!mask_holds(to, k & 7, k >> 3) || mask_holds(from, k & 7, k >> 3)) continue;
    // A DC corrects what the block showed before it.
    const int l = k == 0 ? t_.levels[b][0] - shown : t_.levels[b][k];
    const double c = terrain::dequantise(l, k, t_.quantiser);
    energy += c * c;
    bits += l == 0 ? 0.5 : 5 + 2 * std::log2(1.0 + std::abs(l));
  }
  return pixels / 64 * energy / bits;
}

TerrainServer::TerrainServer(const TerrainCoding& t, uint32_t capacity)
    : t_(t), capacity_(capacity), held_(t.grid.blocks(), 0), last_needed_(t.grid.blocks(), 0) {}

std::vector<uint8_t> TerrainServer::update(const SceneCamera& camera, uint32_t frame, size_t budget,
                                           const PoseOptions& o, UpdateStats* stats) {
  return update(std::vector<SceneCamera>{camera}, frame, budget, o, stats);
}

std::vector<uint8_t> TerrainServer::update(const std::vector<SceneCamera>& cameras, uint32_t frame, size_t budget,
                                           const PoseOptions& o, UpdateStats* stats) {
  if (cameras.empty()) throw std::invalid_argument("TerrainServer::update: no camera");
  // What any of the cameras needs, seen as the camera that sees it best.
  std::vector<BlockView> views;
  std::vector<Mask> need = pose_masks(t_, cameras[0], o, &views);
  for (size_t k = 1; k < cameras.size(); ++k) {
    std::vector<BlockView> v;
    const std::vector<Mask> m = pose_masks(t_, cameras[k], o, &v);
    for (size_t b = 0; b < need.size(); ++b) {
      need[b] = terrain::mask_union(need[b], m[b]);
      if (v[b].visible && (!views[b].visible || v[b].pixels > views[b].pixels)) views[b] = v[b];
    }
  }
  const uint32_t n = t_.grid.blocks();
  for (uint32_t b = 0; b < n; ++b)
    if (need[b] != 0) last_needed_[b] = frame + 1;

  // What the pose lacks, in stages of each block's need (its DC, then the
  // lowest 2x2, 4x4 and 8x8 frequencies), ranked by the squared error a
  // stage removes from the screen per bit it costs (estimated): the
  // coefficients' energy (an orthonormal transform: their squares are the
  // block's squared error; a block held empty shows mid-grey, which its DC
  // corrects) times the screen pixels a texel covers.
  struct Want {
    uint32_t block;
    Mask target;
    double score;
  };
  std::vector<Want> wanted;
  constexpr Mask kBox[4] = {0x00000001u, 0x00000022u, 0x00004444u, terrain::kFullMask};
  // What each block shows before its DC arrives.
  std::vector<int> shown(n, 0);
  CoarsePlanes planes(t_, held_);
  for (uint32_t b = t_.grid.first(0, 0); b < n; ++b)
    if (held_[b] == 0 && need[b] != 0) planes.sample(b, &shown[b]);
  for (uint32_t b = 0; b < n; ++b) {
    if (terrain::mask_covers(held_[b], need[b])) continue;
    Mask prev = held_[b];
    for (int st = 0; st < 4; ++st) {
      // The stage's part of the need (what the block holds beyond it may
      // be dropped to make room before the stage is sent, and stays dropped).
      const Mask part = terrain::mask_intersection(need[b], kBox[st]);
      const Mask target = terrain::mask_union(prev, part);
      if (target != prev) wanted.push_back({b, part, stage_score(b, prev, target, views[b].pixels, shown[b])});
      prev = target;
    }
  }
  std::stable_sort(wanted.begin(), wanted.end(), [](const Want& a, const Want& b) { return a.score > b.score; });

  // Room in the store, in tiers: level-0 blocks the pose does not need and
  // no pose has needed for a second, the longest unneeded first; then what
  // needed level-0 blocks hold beyond the need, the least visible first;
  // then level-0 blocks needed within the last second; then level-1 blocks
  // the pose does not need (a few coefficients that cover much ground:
  // dropped last). A turning viewer comes back to what it saw a moment ago.
  const uint32_t recent = frame >= kRecentFrames ? frame + 1 - kRecentFrames : 0;
  const uint32_t fine = t_.grid.first(0, 0);
  struct Victim {
    uint32_t block;
    int tier;
    double order;
  };
  std::vector<Victim> victims;
  for (uint32_t b = 0; b < n; ++b) {
    if (held_[b] == 0) continue;
    if (need[b] == 0) {
      const int tier = b < fine ? 3 : (last_needed_[b] < recent ? 0 : 2);
      victims.push_back({b, tier, static_cast<double>(last_needed_[b])});
    } else if (b >= fine && held_[b] != terrain::mask_intersection(held_[b], need[b])) {
      victims.push_back({b, 1, views[b].pixels});
    }
  }
  std::stable_sort(victims.begin(), victims.end(), [](const Victim& a, const Victim& b) {
    return a.tier != b.tier ? a.tier < b.tier : a.order < b.order;
  });
  size_t next_victim = 0;

  // before[b]: the block after this update's shrinks, which its grow
  // starts from (a block this update shrinks differs from held_ there).
  std::vector<Mask> after = held_, before = held_;
  uint32_t used = used_;
  auto shrink_to = [&](uint32_t b, Mask m) {
    if (m == after[b]) return;
    used -= terrain::store_cost(after[b]) - terrain::store_cost(m);
    after[b] = before[b] = m;
  };
  std::vector<uint32_t> picked;
  std::vector<uint8_t> is_picked(n, 0);
  UpdateWriter trial(t_);
  for (const Want& w : wanted) {
    const uint32_t b = w.block;
    const Mask target = terrain::mask_union(after[b], w.target);
    if (target == after[b]) continue;
    const uint32_t add = terrain::store_cost(target) - terrain::store_cost(after[b]);
    // The cost of this block, estimated in the order of choice.
    trial.mask(after[b], target, true);
    trial.coefficients(b, after[b], target, shown[b]);
    if (8 + trial.ae.finished_size() + picked.size() / 2 > budget) break;
    while (used + add > capacity_ && next_victim < victims.size()) {
      const Victim& v = victims[next_victim++];
      if (is_picked[v.block] || v.block == b) continue;
      shrink_to(v.block, v.tier == 1 ? terrain::mask_intersection(after[v.block], need[v.block]) : 0);
    }
    if (used + add > capacity_) break;  // the store is full of what the pose needs
    used += add;
    after[b] = target;
    if (!is_picked[b]) picked.push_back(b);
    is_picked[b] = 1;
  }

  // Shrinks and grows by ascending id; trim the least visible grows while
  // the coded update is over the budget.
  // A block shrunk to make room and then grown again is sent as both.
  std::vector<BlockChange> shrinks;
  for (uint32_t b = 0; b < n; ++b)
    if (before[b] != held_[b]) shrinks.push_back({b, before[b]});
  std::vector<uint8_t> out;
  for (;;) {
    std::vector<BlockChange> grows;
    for (uint32_t b : picked) grows.push_back({b, after[b]});
    std::sort(grows.begin(), grows.end(), [](const BlockChange& a, const BlockChange& b) { return a.id < b.id; });
    if (shrinks.empty() && grows.empty()) break;
    out = encode_update(t_, held_, frame, shrinks, grows);
    if (out.size() <= budget || picked.empty()) break;
    const size_t drop = std::max<size_t>(1, picked.size() / 16);
    for (size_t k = 0; k < drop && !picked.empty(); ++k) {
      const uint32_t b = picked.back();
      picked.pop_back();
      used -= terrain::store_cost(after[b]) - terrain::store_cost(before[b]);
      after[b] = before[b];
    }
  }
  if (stats != nullptr) {
    *stats = UpdateStats{};
    stats->shrinks = static_cast<uint32_t>(shrinks.size());
    stats->grows = static_cast<uint32_t>(picked.size());
    for (const BlockChange& s : shrinks)
      stats->dropped += static_cast<uint32_t>(terrain::mask_count(held_[s.id]) - terrain::mask_count(s.mask));
    for (uint32_t b : picked) {
      if (before[b] == 0) ++stats->intra;
      stats->coefficients += static_cast<uint32_t>(terrain::mask_count(after[b]) - terrain::mask_count(before[b]));
    }
    for (uint32_t b = 0; b < n; ++b) {
      if (!terrain::mask_covers(after[b], need[b])) ++stats->wanted;
      stats->needed += static_cast<uint32_t>(terrain::mask_count(need[b]));
      stats->needed_blocks += need[b] != 0;
    }
    stats->bytes = out.size();
  }
  held_ = std::move(after);
  used_ = used;
  return out;
}

}  // namespace vds::enc
