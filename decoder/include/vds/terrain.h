// vds client library: the terrain mode's data, shared bit for bit by the
// client and the host server (vds/enc/terrain_server.h).
//
// A terrain is an elevation grid of (cells_x + 1) x (cells_y + 1) points and
// a colour texture of 8 x 8 texels per cell, held as Y'CbCr 4:2:0 in 8x8 DCT
// blocks aligned with the cells: one luma block per cell, one Cb and one Cr
// block per 2 x 2 cells. The server sends each block's DCT coefficients as
// the viewer's pose first needs them (docs/terrain.md):
//
//   the elevation   (decode_elevation) before any texture, coarse points
//                   first: the grid coded losslessly, each height predicted
//                   from its neighbours (the median predictor of LOCO-I) and
//                   the residual coded with the adaptive arithmetic coder.
//   texture updates (TextureUpdateReader) as the pose changes: blocks that
//                   the client must drop or shrink, then blocks whose held
//                   coefficient set (their *mask*) grows, with the quantised
//                   coefficients the growth adds.
//
// A block's content is a function of its mask alone (every coefficient is
// quantised once, with a fixed step), so the server knows what the client
// holds from the masks it has sent, and a coefficient is sent again only
// after the client was told to drop it.
//
// Freestanding: no heap, no float, no exceptions.
#pragma once
#include <stddef.h>
#include <stdint.h>

#include "vds/arith.h"
#include "vds/status.h"

namespace vds::terrain {

// --- Block masks ------------------------------------------------------------
//
// Which coefficients of an 8x8 block are held: row v (vertical frequency)
// holds the coefficients u < extent(v). Extents never grow with v (the
// shrinking masks of the paper's rule all have this staircase shape), and a
// non-empty mask holds the DC. Packed as 8 nibbles, row v in bits 4v..4v+3;
// 0 is the empty mask and kFullMask every coefficient.
using Mask = uint32_t;
inline constexpr Mask kFullMask = 0x88888888u;

constexpr int mask_extent(Mask m, int v) { return static_cast<int>((m >> (4 * v)) & 15u); }
constexpr Mask mask_with_extent(Mask m, int v, int e) {
  return (m & ~(Mask{15} << (4 * v))) | (static_cast<Mask>(e) << (4 * v));
}
constexpr bool mask_holds(Mask m, int u, int v) { return u < mask_extent(m, v); }
// Valid: every extent 0..8 and no row longer than the row above.
bool mask_valid(Mask m);
// Coefficients held.
int mask_count(Mask m);
// Row-wise maximum and minimum: the masks holding what either / both hold.
Mask mask_union(Mask a, Mask b);
Mask mask_intersection(Mask a, Mask b);
// a holds everything b holds.
inline bool mask_covers(Mask a, Mask b) { return mask_union(a, b) == a; }

// --- Blocks -------------------------------------------------------------------

// Blocks come in two levels. Level 0: the texture's 8x8 blocks, one luma
// block per cell and a Cb and a Cr block per 2 x 2 cells. Level 1: 8x8
// blocks of the level-0 DC planes (a plane of each component's block
// means, in DC levels), so one level-1 block stands for 8 x 8 level-0
// blocks: the coarse picture far terrain is drawn from, and what a level-0
// block shows before it holds anything.
//
// Block ids: level 1 (Y', Cb, Cr, each in raster order), then level 0.
struct BlockPlace {
  uint8_t level = 0, comp = 0;  // comp: 0 Y', 1 Cb, 2 Cr
  uint16_t bx = 0, by = 0;      // in blocks of its plane
};
struct BlockGrid {
  uint16_t cells_x = 0, cells_y = 0;
  // A plane's size in blocks.
  uint16_t plane_w(int level, int comp) const {
    const int w = comp == 0 ? cells_x : (cells_x + 1) / 2;
    return static_cast<uint16_t>(level == 0 ? w : (w + 7) / 8);
  }
  uint16_t plane_h(int level, int comp) const {
    const int h = comp == 0 ? cells_y : (cells_y + 1) / 2;
    return static_cast<uint16_t>(level == 0 ? h : (h + 7) / 8);
  }
  uint32_t plane_blocks(int level, int comp) const { return uint32_t{plane_w(level, comp)} * plane_h(level, comp); }
  // The id of a plane's first block.
  // (Level 1's Y', Cb, Cr, then level 0's; Cb and Cr planes have one size.)
  uint32_t first(int level, int comp) const {
    const uint32_t at = level == 1 ? 0 : plane_blocks(1, 0) + 2 * plane_blocks(1, 1);
    return comp == 0 ? at : at + plane_blocks(level, 0) + static_cast<uint32_t>(comp - 1) * plane_blocks(level, 1);
  }
  uint32_t id(int level, int comp, int bx, int by) const {
    return first(level, comp) + static_cast<uint32_t>(by) * plane_w(level, comp) + static_cast<uint32_t>(bx);
  }
  uint32_t blocks() const { return first(0, 0) + plane_blocks(0, 0) + 2 * plane_blocks(0, 1); }
  // The level-0 luma block of cell (i, j).
  uint32_t cell(int i, int j) const { return id(0, 0, i, j); }
  BlockPlace place(uint32_t id) const;  // id < blocks()
  int component(uint32_t id) const { return place(id).comp; }
  // The level-1 block over level-0 block `id`, and (in *sample) the index
  // of the level-0 block's sample in that block's DC plane (8 * y + x).
  uint32_t coarse(uint32_t id, int* sample) const {
    const BlockPlace p = place(id);
    *sample = (p.by % 8) * 8 + p.bx % 8;
    return this->id(1, p.comp, p.bx / 8, p.by / 8);
  }
};

// Limits a client accepts (the stream's header is refused past them).
inline constexpr int kMaxCells = 1024;  // per side: 8192 texels
inline constexpr int kMinQuantiser = 1;
inline constexpr int kMaxQuantiser = 62;

// Dequantisation: MPEG-2's default intra matrix (natural order) times the
// quantiser scale / 16 for the AC coefficients, step 8 for the DC; results
// saturate to the inverse DCT's 12-bit domain.
extern const uint8_t kIntraMatrix[64];
int16_t dequantise(int level, int natural_index, int quantiser);
// The coefficients of a block that `held` holds, dequantised (natural
// order), the others 0: what the inverse DCT of a block takes.
void dequantise_held(const int16_t levels[64], Mask held, int quantiser, int16_t coef[64]);
// The largest |level| a coefficient may have (a larger one is malformed).
inline constexpr int kMaxLevel = 2047;

// --- Elevation ----------------------------------------------------------------

// The elevation goes in two passes so that the client can draw the ground
// long before it holds all of it: the coarse points (every kCoarseStep-th
// column of every kCoarseStep-th row, the last column and row included),
// then the rest in raster order. Each height is predicted from its left,
// upper and upper-left neighbours (in the coarse pass, its neighbours on
// the coarse grid) by the median predictor of LOCO-I, and the residual is
// coded with the adaptive arithmetic coder in four context classes by the
// neighbours' activity.
inline constexpr int kCoarseStep = 8;
enum class ElevationPass : uint8_t { coarse = 0, fine = 1 };

// Decodes one pass of a (w x h)-point grid coded by the host's
// encode_elevation into out[y * w + x]; the fine pass needs the coarse
// pass's points in `out`. malformed for a residual that leaves 0..65535 or
// bytes no encoder produces, truncated when the data ends first.
// The fine pass may be sent in pieces of whole rows, rows [y0, y1) each
// coded on its own (fresh contexts), in order: a piece needs the rows above
// it. The coarse pass takes the whole grid (y0 = 0, y1 = h).
Status decode_elevation(const uint8_t* data, size_t size, int w, int h, ElevationPass pass, uint16_t* out,
                        int y0 = 0, int y1 = -1);
// The points the fine pass will send, interpolated (bilinear) from the
// coarse ones: what the client draws until then.
void fill_from_coarse(int w, int h, uint16_t* out);
// The client's level of detail (docs/terrain.md, "The client"): the
// largest height error, in height steps rounded up (at most 65535), of
// drawing the ni x nj cells from grid point (i0, j0) of a w-point-wide
// elevation at step s (a power of two): every grid point against the
// coarse triangles over it, a coarse quad a b / c d split along b-c. A
// point on a coarse line belongs to the quad right of it and below it; the
// last column (row) counts only where a quad narrower (lower) than s ends
// there.
uint16_t step_error(const uint16_t* heights, int w, int i0, int j0, int ni, int nj, int s);
constexpr bool elevation_coarse(int x, int y, int w, int h) {
  return (x % kCoarseStep == 0 || x == w - 1) && (y % kCoarseStep == 0 || y == h - 1);
}

// The contexts of the elevation coder (both sides).
struct ElevationContexts {
  ArithContext zero[4];
  ArithContext mag[4][8];
};
void init_elevation_contexts(ElevationContexts& c);
// The median predictor: min(a, b) if c >= max(a, b), max(a, b) if c <=
// min(a, b), else a + b - c; with no upper row the left value (0 for the
// first point), with no left column the upper value.
int elevation_median(int a, int b, int c, bool has_left, bool has_up);
// Context class from the activity |a - c| + |b - c| (3 without both
// neighbours).
int elevation_class(int a, int b, int c, bool both);

// Visits the points of a pass in coding order: f(x, y, prediction, class)
// with the prediction from what `out` holds when it is called; f returns
// false to stop. The fine pass visits rows [y0, y1) only. Shared by the
// decoder and the host encoder.
template <class F>
void for_each_elevation_point(int w, int h, ElevationPass pass, const uint16_t* out, F f, int y0 = 0, int y1 = -1) {
  auto at = [&](int x, int y) { return static_cast<int>(out[static_cast<size_t>(y) * w + x]); };
  if (pass == ElevationPass::coarse) {
    const int cw = (w - 1 + kCoarseStep - 1) / kCoarseStep + 1, ch = (h - 1 + kCoarseStep - 1) / kCoarseStep + 1;
    auto cx = [&](int i) { return i * kCoarseStep < w - 1 ? i * kCoarseStep : w - 1; };
    auto cy = [&](int j) { return j * kCoarseStep < h - 1 ? j * kCoarseStep : h - 1; };
    for (int j = 0; j < ch; ++j)
      for (int i = 0; i < cw; ++i) {
        const int a = i > 0 ? at(cx(i - 1), cy(j)) : 0, b = j > 0 ? at(cx(i), cy(j - 1)) : 0;
        const int c = i > 0 && j > 0 ? at(cx(i - 1), cy(j - 1)) : 0;
        if (!f(cx(i), cy(j), elevation_median(a, b, c, i > 0, j > 0), elevation_class(a, b, c, i > 0 && j > 0))) return;
      }
    return;
  }
  if (y1 < 0 || y1 > h) y1 = h;
  for (int y = y0 < 0 ? 0 : y0; y < y1; ++y)
    for (int x = 0; x < w; ++x) {
      if (elevation_coarse(x, y, w, h)) continue;
      const int a = x > 0 ? at(x - 1, y) : 0, b = y > 0 ? at(x, y - 1) : 0, c = x > 0 && y > 0 ? at(x - 1, y - 1) : 0;
      if (!f(x, y, elevation_median(a, b, c, x > 0, y > 0), elevation_class(a, b, c, x > 0 && y > 0))) return;
    }
}

// The DC plane a level-1 block stands for: the integer IDCT of the
// coefficients `held` holds of `levels` (natural order), out[8 * y + x] in
// DC levels (a level-0 block's mean minus 128, rounded).
void coarse_plane(const int16_t levels[64], Mask held, int quantiser, int16_t out[64]);

// --- Texture updates ------------------------------------------------------------

// The contexts of the texture update coder (both sides).
struct TextureContexts {
  ArithContext id_gap[8];            // Exp-Golomb prefix of the gap to the next block id
  ArithContext extent[2][8];         // [shrink / grow] truncated unary of an extent change
  ArithContext dc_zero[2][3];        // DC residual, [level][component]
  ArithContext dc_mag[2][3][6];
  // [class] below: luma, chroma, level-1 luma, level-1 chroma.
  ArithContext cbf[2][4];            // [intra / inter][class] any nonzero AC
  ArithContext sig[4][6];            // [class][position class]
  ArithContext last[4][6];
  ArithContext level[4][6];          // |level| - 1, prefix contexts
};
void init_texture_contexts(TextureContexts& c);
// Position class of zig-zag index k (1..63): 1-2, 3-5, 6-9, 10-20, 21-35, 36-63.
int position_class(int k);
// Context class of a block's coefficients: luma, chroma, level-1 luma,
// level-1 chroma.
constexpr int coefficient_class(const BlockPlace& p) { return (p.comp == 0 ? 0 : 1) + 2 * p.level; }
// A level-0 DC's prediction: what the block shows, as a DC level.
constexpr int dc_prediction(int shown) { return shown < -128 ? -128 : (shown > 127 ? 127 : shown); }
// The AC positions (zig-zag indices 1..63, ascending) `mask` holds and
// `held` does not: what a grow from `held` to `mask` codes. Returns how many.
int added_positions(Mask held, Mask mask, uint8_t pos[63]);

// One block of an update, as the reader hands it over.
struct BlockUpdate {
  uint32_t id = 0;
  Mask held = 0;  // what the client held before (the caller's state)
  Mask mask = 0;  // what it holds after
  // Shrinks: nothing more. Grows: levels[natural index] for every
  // coefficient mask holds and held does not; other entries 0.
  int16_t levels[64] = {};
};

// Reads one texture update (docs/terrain.md), a TTEX chunk's payload:
//   u32 pose frame it answers, u16 shrinks, u16 grows, then the arith data:
//   shrinks by ascending id (gap, new mask <= held), grows by ascending id
//   (gap, new mask >= held, coefficients).
// The caller owns the masks: `held(ctx, id)` gives a block's current mask,
// and every block the reader returns must be applied before the next.
//
// A level-0 block grown from nothing codes its DC against what the client
// shows there (`shown_dc(ctx, id)`: the DC plane of its level-1 block as
// the client holds it when the block is read, 0 if it holds nothing); a
// level-1 block grown from nothing against the previous one of its
// component in the update.
class TextureUpdateReader {
 public:
  using HeldFn = Mask (*)(void* ctx, uint32_t id);
  using ShownDcFn = int (*)(void* ctx, uint32_t id);
  // invalid_argument for a bad grid; malformed for a header that cannot be.
  Status init(const uint8_t* data, size_t size, const BlockGrid& grid, HeldFn held, ShownDcFn shown_dc, void* ctx);
  uint32_t pose_frame() const { return pose_frame_; }
  uint32_t shrinks() const { return shrinks_; }
  uint32_t grows() const { return grows_; }
  // The next block: ok with *out filled, more_input when every block has
  // been read and the data ends where it should (then done), or the error
  // (latched).
  Status next(BlockUpdate* out);
  bool done() const { return done_; }

 private:
  Status read_mask(Mask held, bool grow, Mask* out);
  Status fail(Status s) {
    status_ = s;
    return s;
  }
  ArithDecoder dec_{};
  TextureContexts ctx_{};
  BlockGrid grid_{};
  HeldFn held_ = nullptr;
  ShownDcFn shown_dc_ = nullptr;
  void* held_ctx_ = nullptr;
  uint32_t pose_frame_ = 0, shrinks_ = 0, grows_ = 0, read_ = 0;
  int64_t last_id_ = -1;
  int dc_prev_[3] = {};
  bool done_ = false;
  Status status_ = Status::invalid_argument;
};

}  // namespace vds::terrain
