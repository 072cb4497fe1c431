// vds client library: the terrain mode's elevation and texture-update
// decoders (vds/terrain.h; the format in docs/terrain.md).
#include "vds/terrain.h"

#include "vds/bytes.h"
#include "vds/idct.h"
#include "vds/image_model.h"

namespace vds::terrain {

namespace {

using image_model::kZigzag;

constexpr int kExtentRows = 8;

int min_int(int a, int b) { return a < b ? a : b; }
int max_int(int a, int b) { return a > b ? a : b; }

}  // namespace

// MPEG-2 (ITU-T H.262) default intra quantiser matrix, natural order.
const uint8_t kIntraMatrix[64] = {
    8,  16, 19, 22, 26, 27, 29, 34,  //
    16, 16, 22, 24, 27, 29, 34, 37,  //
    19, 22, 26, 27, 29, 34, 34, 38,  //
    22, 22, 26, 27, 29, 34, 37, 40,  //
    22, 26, 27, 29, 32, 35, 40, 48,  //
    26, 27, 29, 32, 35, 40, 48, 58,  //
    26, 27, 29, 34, 38, 46, 56, 69,  //
    27, 29, 35, 38, 46, 56, 69, 83};

bool mask_valid(Mask m) {
  int above = 8;
  for (int v = 0; v < kExtentRows; ++v) {
    const int e = mask_extent(m, v);
    if (e > above) return false;
    above = e;
  }
  return true;
}

int mask_count(Mask m) {
  int n = 0;
  for (int v = 0; v < kExtentRows; ++v) n += mask_extent(m, v);
  return n;
}

Mask mask_union(Mask a, Mask b) {
  Mask r = 0;
  for (int v = 0; v < kExtentRows; ++v) r = mask_with_extent(r, v, max_int(mask_extent(a, v), mask_extent(b, v)));
  return r;
}

Mask mask_intersection(Mask a, Mask b) {
  Mask r = 0;
  for (int v = 0; v < kExtentRows; ++v) r = mask_with_extent(r, v, min_int(mask_extent(a, v), mask_extent(b, v)));
  return r;
}

int16_t dequantise(int level, int natural_index, int quantiser) {
  int32_t c;
  if (natural_index == 0) {
    c = level * 8;
  } else {
    c = (level * static_cast<int32_t>(kIntraMatrix[natural_index]) * quantiser) / 16;
  }
  if (c < -2048) c = -2048;
  if (c > 2047) c = 2047;
  return static_cast<int16_t>(c);
}

BlockPlace BlockGrid::place(uint32_t id) const {
  BlockPlace p;
  for (int l = 1; l >= 0; --l) {
    const uint32_t ny = plane_blocks(l, 0), nc = plane_blocks(l, 1);
    int c = 0;
    if (id >= ny) {
      id -= ny;
      c = 1 + (id >= nc);
      if (c == 2) id -= nc;
      if (id >= nc) {
        id -= nc;
        continue;
      }
    }
    const uint32_t w = plane_w(l, c);
    p.level = static_cast<uint8_t>(l);
    p.comp = static_cast<uint8_t>(c);
    p.bx = static_cast<uint16_t>(id % w);
    p.by = static_cast<uint16_t>(id / w);
    return p;
  }
  return p;
}

void dequantise_held(const int16_t levels[64], Mask held, int quantiser, int16_t coef[64]) {
  for (int n = 0; n < 64; ++n) coef[n] = mask_holds(held, n & 7, n >> 3) ? dequantise(levels[n], n, quantiser) : 0;
}

void coarse_plane(const int16_t levels[64], Mask held, int quantiser, int16_t out[64]) {
  int16_t coef[64];
  dequantise_held(levels, held, quantiser, coef);
  idct8x8(coef, out);
}

// --- Elevation -------------------------------------------------------------------

void init_elevation_contexts(ElevationContexts& c) {
  arith_init_contexts(c.zero, 4);
  arith_init_contexts(&c.mag[0][0], 4 * 8);
}

int elevation_class(int a, int b, int c, bool both) {
  if (!both) return 3;
  const int d = (a > c ? a - c : c - a) + (b > c ? b - c : c - b);
  if (d == 0) return 0;
  if (d <= 4) return 1;
  if (d <= 32) return 2;
  return 3;
}

int elevation_median(int a, int b, int c, bool has_left, bool has_up) {
  if (!has_up) return has_left ? a : 0;
  if (!has_left) return b;
  const int lo = min_int(a, b), hi = max_int(a, b);
  if (c >= hi) return lo;
  if (c <= lo) return hi;
  return a + b - c;
}

Status decode_elevation(const uint8_t* data, size_t size, int w, int h, ElevationPass pass, uint16_t* out, int y0,
                        int y1) {
  if (y1 < 0) y1 = h;
  if (out == nullptr || w <= 0 || h <= 0 || y0 < 0 || y0 > y1 || y1 > h) return Status::invalid_argument;
  ArithDecoder dec;
  Status s = dec.init(data, size);
  if (s != Status::ok) return s;
  ElevationContexts ctx;
  init_elevation_contexts(ctx);
  s = Status::ok;
  for_each_elevation_point(w, h, pass, out, [&](int x, int y, int predict, int k) {
    const int32_t r = dec.decode_signed(ctx.zero[k], ctx.mag[k], 8, 16, 2);
    if (!dec.ok()) {
      s = dec.status();
      return false;
    }
    const int32_t v = predict + r;
    if (v < 0 || v > 65535) {
      s = Status::malformed;
      return false;
    }
    out[static_cast<size_t>(y) * w + x] = static_cast<uint16_t>(v);
    return true;
  }, y0, y1);
  return s != Status::ok ? s : dec.finish();
}

void fill_from_coarse(int w, int h, uint16_t* out) {
  for (int y = 0; y < h; ++y) {
    const int y0 = y / kCoarseStep * kCoarseStep, y1 = y0 + kCoarseStep < h - 1 ? y0 + kCoarseStep : h - 1;
    for (int x = 0; x < w; ++x) {
      if (elevation_coarse(x, y, w, h)) continue;
      const int x0 = x / kCoarseStep * kCoarseStep, x1 = x0 + kCoarseStep < w - 1 ? x0 + kCoarseStep : w - 1;
      auto at = [&](int px, int py) { return static_cast<int64_t>(out[static_cast<size_t>(py) * w + px]); };
      // (x0, y0) == (x1, y1) in a direction only on a coarse row or column,
      // whose offset is then 0: a span of 1 weighs the one point.
      const int64_t fx = x - x0, fy = y - y0, dx = x1 > x0 ? x1 - x0 : 1, dy = y1 > y0 ? y1 - y0 : 1;
      // Bilinear in integers, rounded to nearest: the denominators are at
      // most kCoarseStep each.
      const int64_t num = (at(x0, y0) * (dx - fx) + at(x1, y0) * fx) * (dy - fy) + (at(x0, y1) * (dx - fx) + at(x1, y1) * fx) * fy;
      const int64_t den = dx * dy;
      out[static_cast<size_t>(y) * w + x] = static_cast<uint16_t>((num + den / 2) / den);
    }
  }
}

namespace {
// step_error in T: int32_t when every product fits (W H <= 2^12, heights
// below 2^16: each term below 2^28), else int64_t.
template <class T>
uint16_t step_error_in(const uint16_t* heights, int w, int i0, int j0, int ni, int nj, int s) {
  auto h = [&](int i, int j) { return T{heights[static_cast<size_t>(j) * static_cast<size_t>(w) + static_cast<size_t>(i)]}; };
  T worst = 0;
  for (int ja = j0; ja < j0 + nj; ja += s) {
    const int jc = ja + s < j0 + nj ? ja + s : j0 + nj;
    const T H = jc - ja;
    const int j_last = H < s ? jc : jc - 1;
    for (int ia = i0; ia < i0 + ni; ia += s) {
      const int ib = ia + s < i0 + ni ? ia + s : i0 + ni;
      const T W = ib - ia, WH = W * H;
      const int i_last = W < s ? ib : ib - 1;
      const T a = h(ia, ja), b = h(ib, ja), c = h(ia, jc), d = h(ib, jc);
      for (int j = ja; j <= j_last; ++j)
        for (int i = ia; i <= i_last; ++i) {
          const T U = i - ia, V = j - ja;
          // The coarse surface at (i, j), times W H.
          const T at = U * H + V * W <= WH ? a * WH + U * H * (b - a) + V * W * (c - a)
                                           : d * WH + (W - U) * H * (c - d) + (H - V) * W * (b - d);
          T e = h(i, j) * WH - at;
          if (e < 0) e = -e;
          // Divided only when it is the largest yet (e / WH > worst exactly
          // when e > worst WH).
          if (e > worst * WH) worst = (e + WH - 1) / WH;
        }
    }
  }
  return static_cast<uint16_t>(worst > 65535 ? 65535 : worst);
}
}  // namespace

uint16_t step_error(const uint16_t* heights, int w, int i0, int j0, int ni, int nj, int s) {
  if (heights == nullptr || s < 1 || ni < 1 || nj < 1) return 0;
  const int quad = s < (ni > nj ? ni : nj) ? s : (ni > nj ? ni : nj);  // the widest quad's side
  return quad <= 64 ? step_error_in<int32_t>(heights, w, i0, j0, ni, nj, s)
                    : step_error_in<int64_t>(heights, w, i0, j0, ni, nj, s);
}

// --- Texture updates ---------------------------------------------------------------

void init_texture_contexts(TextureContexts& c) {
  arith_init_contexts(reinterpret_cast<ArithContext*>(&c), sizeof(TextureContexts) / sizeof(ArithContext));
}

int position_class(int k) {
  if (k <= 2) return 0;
  if (k <= 5) return 1;
  if (k <= 9) return 2;
  if (k <= 20) return 3;
  if (k <= 35) return 4;
  return 5;
}

int added_positions(Mask held, Mask mask, uint8_t pos[63]) {
  int n = 0;
  for (int k = 1; k < 64; ++k) {
    const int nat = kZigzag[k];
    if (mask_holds(mask, nat & 7, nat >> 3) && !mask_holds(held, nat & 7, nat >> 3)) pos[n++] = static_cast<uint8_t>(k);
  }
  return n;
}

Status TextureUpdateReader::init(const uint8_t* data, size_t size, const BlockGrid& grid, HeldFn held,
                                 ShownDcFn shown_dc, void* ctx) {
  *this = TextureUpdateReader{};
  if ((data == nullptr && size > 0) || held == nullptr || shown_dc == nullptr || grid.cells_x == 0 || grid.cells_y == 0 ||
      grid.cells_x > kMaxCells || grid.cells_y > kMaxCells) {
    return fail(Status::invalid_argument);
  }
  if (size < 8) return fail(Status::truncated);
  pose_frame_ = load_le32(data);
  shrinks_ = load_le16(data + 4);
  grows_ = load_le16(data + 6);
  if (shrinks_ + grows_ > 2 * grid.blocks()) return fail(Status::malformed);
  grid_ = grid;
  held_ = held;
  shown_dc_ = shown_dc;
  held_ctx_ = ctx;
  init_texture_contexts(ctx_);
  status_ = dec_.init(data + 8, size - 8);
  return status_;
}

Status TextureUpdateReader::read_mask(Mask held, bool grow, Mask* out) {
  Mask m = 0;
  int above = 8;
  for (int v = 0; v < kExtentRows; ++v) {
    const int h = mask_extent(held, v);
    int e;
    if (grow) {
      // new extent in [held, min(8, row above)]
      const int cap = above;
      if (cap < h) return Status::malformed;
      e = h + static_cast<int>(dec_.decode_unary(&ctx_.extent[1][v], 1, static_cast<uint32_t>(cap - h)));
    } else {
      // new extent in [0, min(held, row above)]
      const int cap = min_int(h, above);
      e = cap - static_cast<int>(dec_.decode_unary(&ctx_.extent[0][v], 1, static_cast<uint32_t>(cap)));
    }
    m = mask_with_extent(m, v, e);
    above = e;
  }
  if (!dec_.ok()) return dec_.status();
  if (m == held) return Status::malformed;  // an update changes its block
  *out = m;
  return Status::ok;
}

Status TextureUpdateReader::next(BlockUpdate* out) {
  if (status_ != Status::ok) return status_;
  if (out == nullptr) return fail(Status::invalid_argument);
  if (read_ == shrinks_ + grows_) {
    done_ = true;
    const Status s = dec_.finish();
    return s == Status::ok ? Status::more_input : fail(s);
  }
  const bool grow = read_ >= shrinks_;
  if (read_ == shrinks_) last_id_ = -1;  // grows restart the id order
  // The gap to the next id.
  const uint32_t gap = dec_.decode_exp_golomb(ctx_.id_gap, 8, 0);
  if (!dec_.ok()) return fail(dec_.status());
  const int64_t id = last_id_ + 1 + static_cast<int64_t>(gap);
  if (id >= static_cast<int64_t>(grid_.blocks())) return fail(Status::malformed);
  last_id_ = id;
  BlockUpdate& u = *out;
  u.id = static_cast<uint32_t>(id);
  u.held = held_(held_ctx_, u.id);
  if (!mask_valid(u.held)) return fail(Status::invalid_argument);
  if (!grow && u.held == 0) return fail(Status::malformed);  // nothing to shrink
  Status s = read_mask(u.held, grow, &u.mask);
  if (s != Status::ok) return fail(s);
  for (int i = 0; i < 64; ++i) u.levels[i] = 0;
  ++read_;
  if (!grow) return Status::ok;

  const BlockPlace pl = grid_.place(u.id);
  const int comp = pl.comp, lv = pl.level;
  const int cls = coefficient_class(pl);
  const bool intra = u.held == 0;
  if (intra) {
    const int32_t r = dec_.decode_signed(ctx_.dc_zero[lv][comp], ctx_.dc_mag[lv][comp], 6, 8, 1);
    if (!dec_.ok()) return fail(dec_.status());
    const int32_t pred = lv == 0 ? dc_prediction(shown_dc_(held_ctx_, u.id)) : dc_prev_[comp];
    const int32_t dc = pred + r;
    if (dc < -128 || dc > 127) return fail(Status::malformed);
    if (lv == 1) dc_prev_[comp] = dc;
    u.levels[0] = static_cast<int16_t>(dc);
  }
  uint8_t pos[63];
  const int n = added_positions(u.held, u.mask, pos);
  if (n == 0) return Status::ok;
  if (dec_.decode_bit(ctx_.cbf[intra ? 0 : 1][cls]) == 0) return dec_.ok() ? Status::ok : fail(dec_.status());
  bool any = false;
  for (int i = 0; i < n; ++i) {
    const int k = pos[i];
    const int pc = position_class(k);
    const bool sig = (i == n - 1 && !any) ? true : dec_.decode_bit(ctx_.sig[cls][pc]) != 0;
    if (!sig) continue;
    const uint32_t mag = 1 + dec_.decode_ueg(&ctx_.level[cls][pc], 1, 14, 0);
    const bool neg = dec_.decode_bypass() != 0;
    if (!dec_.ok()) return fail(dec_.status());
    if (mag > static_cast<uint32_t>(kMaxLevel)) return fail(Status::malformed);
    u.levels[kZigzag[k]] = static_cast<int16_t>(neg ? -static_cast<int32_t>(mag) : static_cast<int32_t>(mag));
    any = true;
    if (i < n - 1 && dec_.decode_bit(ctx_.last[cls][pc]) != 0) break;
  }
  if (!dec_.ok()) return fail(dec_.status());
  return Status::ok;
}

}  // namespace vds::terrain
