// vds client library: the terrain mode's data, shared bit for bit by the
// client and the host server (vds/enc/terrain_server.h).
//
// A terrain is an elevation grid of (cells_x + 1) x (cells_y + 1) points and
// a colour texture of 8 x 8 texels per cell, held as Y'CbCr 4:2:0 in 8x8 DCT
// blocks aligned with the cells: one luma block per cell, one Cb and one Cr
// block per 2 x 2 cells. The server sends each block's DCT coefficients as
// the viewer's pose first needs them (docs/terrain.md):
//
//   the elevation   (decode_elevation) once, before any texture: the grid
//                   coded losslessly, each height predicted from its
//                   neighbours (the median predictor of LOCO-I) and the
//                   residual coded with the adaptive binary arithmetic coder.
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

// Block ids: the luma blocks in raster order (cells_x x cells_y), then Cb,
// then Cr ((cells_x + 1) / 2 x (cells_y + 1) / 2 each).
struct BlockGrid {
  uint16_t cells_x = 0, cells_y = 0;
  uint32_t luma_blocks() const { return uint32_t{cells_x} * cells_y; }
  uint16_t chroma_x() const { return static_cast<uint16_t>((cells_x + 1) / 2); }
  uint16_t chroma_y() const { return static_cast<uint16_t>((cells_y + 1) / 2); }
  uint32_t chroma_blocks() const { return uint32_t{chroma_x()} * chroma_y(); }
  uint32_t blocks() const { return luma_blocks() + 2 * chroma_blocks(); }
  // 0 = Y', 1 = Cb, 2 = Cr.
  int component(uint32_t id) const {
    return id < luma_blocks() ? 0 : (id < luma_blocks() + chroma_blocks() ? 1 : 2);
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
// The largest |level| a coefficient may have (a larger one is malformed).
inline constexpr int kMaxLevel = 2047;

// --- Elevation ----------------------------------------------------------------

// Decodes a (w x h)-point grid of heights coded by the host's
// encode_elevation from `data`, row by row into out[y * w + x]. malformed
// for a residual that leaves 0..65535 or bytes no encoder produces,
// truncated when the data ends first. Every decoded height is in range.
Status decode_elevation(const uint8_t* data, size_t size, int w, int h, uint16_t* out);

// The contexts of the elevation coder (both sides).
struct ElevationContexts {
  ArithContext zero[4];
  ArithContext mag[4][8];
};
void init_elevation_contexts(ElevationContexts& c);
// Context class of a point from the activity |a - c| + |b - c| of its
// neighbours (a left, b above, c above-left).
int elevation_class(int a, int b, int c);
// The median predictor: min(a, b) if c >= max(a, b), max(a, b) if c <=
// min(a, b), else a + b - c. Missing neighbours: the first point predicts
// 0, the first row from the left, the first column from above.
int elevation_predict(const uint16_t* rows, int w, int x, int y);

// --- Texture updates ------------------------------------------------------------

// The contexts of the texture update coder (both sides).
struct TextureContexts {
  ArithContext id_gap[8];            // Exp-Golomb prefix of the gap to the next block id
  ArithContext extent[2][8];         // [shrink / grow] truncated unary of an extent change
  ArithContext dc_zero[3];           // DC residual, per component class (Y', Cb, Cr)
  ArithContext dc_mag[3][6];
  ArithContext cbf[2][2];            // [intra / inter][luma / chroma] any nonzero AC
  ArithContext sig[2][6];            // [luma / chroma][position class]
  ArithContext last[2][6];
  ArithContext level[2][6];          // |level| - 1, prefix contexts
};
void init_texture_contexts(TextureContexts& c);
// Position class of zig-zag index k (1..63): 1-2, 3-5, 6-9, 10-20, 21-35, 36-63.
int position_class(int k);

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
class TextureUpdateReader {
 public:
  using HeldFn = Mask (*)(void* ctx, uint32_t id);
  // invalid_argument for a bad grid; malformed for a header that cannot be.
  Status init(const uint8_t* data, size_t size, const BlockGrid& grid, HeldFn held, void* ctx);
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
  void* held_ctx_ = nullptr;
  uint32_t pose_frame_ = 0, shrinks_ = 0, grows_ = 0, read_ = 0;
  int64_t last_id_ = -1;
  int dc_prev_[3] = {};
  bool done_ = false;
  Status status_ = Status::invalid_argument;
};

}  // namespace vds::terrain
