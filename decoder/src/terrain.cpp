// vds client library: the terrain mode's elevation and texture-update
// decoders (vds/terrain.h; the format in docs/terrain.md).
#include "vds/terrain.h"

#include "vds/bytes.h"
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

// --- Elevation -------------------------------------------------------------------

void init_elevation_contexts(ElevationContexts& c) {
  arith_init_contexts(c.zero, 4);
  arith_init_contexts(&c.mag[0][0], 4 * 8);
}

int elevation_class(int a, int b, int c) {
  const int d = (a > c ? a - c : c - a) + (b > c ? b - c : c - b);
  if (d == 0) return 0;
  if (d <= 4) return 1;
  if (d <= 32) return 2;
  return 3;
}

int elevation_predict(const uint16_t* rows, int w, int x, int y) {
  if (y == 0) return x == 0 ? 0 : rows[x - 1];
  const uint16_t* up = rows + static_cast<size_t>(y - 1) * w;
  if (x == 0) return up[0];
  const int a = rows[static_cast<size_t>(y) * w + x - 1], b = up[x], c = up[x - 1];
  const int lo = min_int(a, b), hi = max_int(a, b);
  if (c >= hi) return lo;
  if (c <= lo) return hi;
  return a + b - c;
}

namespace {
int neighbour_class(const uint16_t* rows, int w, int x, int y) {
  if (x == 0 || y == 0) return 3;
  const uint16_t* up = rows + static_cast<size_t>(y - 1) * w;
  return elevation_class(rows[static_cast<size_t>(y) * w + x - 1], up[x], up[x - 1]);
}
}  // namespace

Status decode_elevation(const uint8_t* data, size_t size, int w, int h, uint16_t* out) {
  if (out == nullptr || w <= 0 || h <= 0) return Status::invalid_argument;
  ArithDecoder dec;
  Status s = dec.init(data, size);
  if (s != Status::ok) return s;
  ElevationContexts ctx;
  init_elevation_contexts(ctx);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const int k = neighbour_class(out, w, x, y);
      const int32_t r = dec.decode_signed(ctx.zero[k], ctx.mag[k], 8, 16, 2);
      if (!dec.ok()) return dec.status();
      const int32_t v = elevation_predict(out, w, x, y) + r;
      if (v < 0 || v > 65535) return Status::malformed;
      out[static_cast<size_t>(y) * w + x] = static_cast<uint16_t>(v);
    }
  }
  return dec.finish();
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

Status TextureUpdateReader::init(const uint8_t* data, size_t size, const BlockGrid& grid, HeldFn held,
                                 void* ctx) {
  *this = TextureUpdateReader{};
  if ((data == nullptr && size > 0) || held == nullptr || grid.cells_x == 0 || grid.cells_y == 0 ||
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

  const int comp = grid_.component(u.id);
  const int cls = comp == 0 ? 0 : 1;
  const bool intra = u.held == 0;
  if (intra) {
    const int32_t r = dec_.decode_signed(ctx_.dc_zero[comp], ctx_.dc_mag[comp], 6, 8, 1);
    if (!dec_.ok()) return fail(dec_.status());
    const int32_t dc = dc_prev_[comp] + r;
    if (dc < -128 || dc > 127) return fail(Status::malformed);
    dc_prev_[comp] = dc;
    u.levels[0] = static_cast<int16_t>(dc);
  }
  // The AC positions this update adds, in zig-zag order.
  uint8_t pos[63];
  int n = 0;
  for (int k = 1; k < 64; ++k) {
    const int nat = kZigzag[k];
    if (mask_holds(u.mask, nat & 7, nat >> 3) && !mask_holds(u.held, nat & 7, nat >> 3)) {
      pos[n++] = static_cast<uint8_t>(k);
    }
  }
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
