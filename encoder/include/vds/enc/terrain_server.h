// The terrain mode's server side: the terrain as it is coded (grid, DCT
// blocks, elevation), the shrinking masks a pose needs (the paper's rule,
// generalised to a grid of cells), and the server that answers poses with
// texture updates while it mirrors exactly what the client holds
// (docs/terrain.md).
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "vds/enc/image_codec.h"
#include "vds/enc/terrain_map.h"
#include "vds/enc/scene_render.h"
#include "vds/terrain.h"

namespace vds::enc {

// --- The terrain as coded ----------------------------------------------------------

struct TerrainCoding {
  terrain::BlockGrid grid;
  int quantiser = 8;
  // (cells_x + 1) x (cells_y + 1) heights in units of metres_per_unit; point
  // (i, j) lies on texel (8 i, 8 j), at x = i cell_m east and y = (cells_y
  // - j) cell_m north (the colour map's top row is north; z is up).
  std::vector<uint16_t> heights;
  double cell_m = 1, metres_per_unit = 1;
  // The colour map padded to whole cells (edges repeated), as R'G'B' and
  // in Y'CbCr 4:2:0.
  io::Image colour;
  Planes texture;
  // Every block's quantised coefficients (natural order), by block id.
  std::vector<std::array<int16_t, 64>> levels;

  int points_x() const { return grid.cells_x + 1; }
  int points_y() const { return grid.cells_y + 1; }
  double height_m(int i, int j) const {
    return heights[static_cast<size_t>(j) * points_x() + i] * metres_per_unit;
  }
  std::array<double, 3> point(int i, int j) const { return {i * cell_m, (grid.cells_y - j) * cell_m, height_m(i, j)}; }
};

// Grid, texture and coefficients of a map. Throws std::invalid_argument for
// a quantiser outside 1..62 or a map of more than terrain::kMaxCells cells
// on a side.
TerrainCoding code_terrain(const TerrainMap& map, int quantiser);

// One pass of the elevation, coded losslessly (vds/terrain.h:
// decode_elevation); of the fine pass, rows [y0, y1) (y1 < 0: to the end).
std::vector<uint8_t> encode_elevation(const uint16_t* heights, int w, int h, terrain::ElevationPass pass, int y0 = 0,
                                      int y1 = -1);

// A block's texture as the client reconstructs it from the coefficients its
// mask holds: 64 samples, row-major.
void reconstruct_block(const TerrainCoding& t, uint32_t id, terrain::Mask held, uint8_t out[64]);
// The whole texture as the client holds it: blocks it holds nothing of are
// mid-grey (Y' 128 for luma, 128 for chroma).
Planes reconstruct_texture(const TerrainCoding& t, const std::vector<terrain::Mask>& held);
// The same for the blocks whose mask differs between `before` and `held`,
// in place: `texture` held `before`'s reconstruction.
void update_texture(const TerrainCoding& t, const std::vector<terrain::Mask>& before,
                    const std::vector<terrain::Mask>& held, Planes* texture);
// The DC level a level-0 block shows while it holds nothing: its sample
// of its level-1 block's DC plane as `held` holds that (0 if nothing).
int shown_dc(const TerrainCoding& t, const std::vector<terrain::Mask>& held, uint32_t id);
// Ground height (metres) at world (x, y), bilinear over the grid, clamped to it.
double terrain_height(const TerrainCoding& t, double x, double y);

// --- Masks ------------------------------------------------------------------------------

// The shrinking mask of the paper's section 4.5 for one 8x8 block (L = 8):
// cutoff is k/D (the screen pixels per texel a texel would cover facing
// the viewer, clamped to 1), cos_alpha the cosine of the tilt, beta_s the
// shrinking angle in radians (0..pi/2: pi/2 when the block is foreshortened
// along u, 0 along v). A coefficient (u, v) with U = (u + 0.5) / 8 and
// V = (v + 0.5) / 8 is dropped when U or V exceeds the cutoff, or beyond the
// line through (T, T), T = cutoff cos alpha, of slope -1 / tan beta_s (U > T
// - (V - T) / tan beta_s; V > T at beta_s = 0, U > T at pi/2). With keep_dc
// a block with a positive cutoff keeps its DC however small the cutoff;
// cutoff <= 0 gives the empty mask.
terrain::Mask shrink_mask(double cutoff, double cos_alpha, double beta_s, bool keep_dc = true);

// How a pose sees one block.
struct BlockView {
  bool visible = false;
  double cutoff = 0;      // k/D
  double cos_alpha = 0;
  double beta_s = 0;
  double pixels = 0;      // screen pixels the block covers (estimate)
  double distance = 1e300;  // metres from the eye to the nearest point of its cells
};

struct PoseOptions {
  double detail = 1.0;   // k: scales every cutoff (above 1 sends more than the screen resolves)
  double near_m = 0.1;   // the camera's near plane, metres
};

// The masks a camera needs, one per block (empty for blocks it cannot see:
// outside the view, behind the camera or facing away), and how it sees each.
// Level-0 blocks take the paper's rule as it stands (a block too far for
// its DC needs nothing: its level-1 block stands for it); level-1 blocks
// the rule at 8 times the cutoff (their samples are blocks), their DC kept.
std::vector<terrain::Mask> pose_masks(const TerrainCoding& t, const SceneCamera& camera, const PoseOptions& o,
                                      std::vector<BlockView>* views = nullptr);

// --- The server --------------------------------------------------------------------------

struct UpdateStats {
  uint32_t shrinks = 0, grows = 0, intra = 0;  // intra: grows of blocks held empty before
  uint32_t coefficients = 0;                   // coefficients the update adds
  uint32_t dropped = 0;                        // coefficients the update drops
  uint32_t wanted = 0;                         // blocks the pose still lacks after it
  uint32_t needed = 0;                         // coefficients the pose needs (held or not)
  uint32_t needed_blocks = 0;                  // blocks it needs
  size_t bytes = 0;
};

// Mirrors the client's store: which mask each block holds, and when the
// pose last needed it. What a pose lacks is sent in stages of each block's
// need (its DC, the lowest 2x2, 4x4, 8x8 frequencies), the stages that
// remove the most squared screen error per bit first. The store holds at
// most `capacity` units (2 bytes; terrain::store_cost: a held block's
// coefficients and its 12-byte entry in the client's BlockStore); to make room the server drops, in order,
// level-0 blocks no pose has needed for a second (the longest unneeded
// first), what needed level-0 blocks hold beyond the need (the least
// visible first), level-0 blocks needed within the second, and level-1
// blocks the pose does not need. The client does what the update says, so its
// store equals held() after every update.
class TerrainServer {
 public:
  TerrainServer(const TerrainCoding& t, uint32_t capacity);
  // The update answering `camera` at pose frame `frame`, at most `budget`
  // bytes (a block is sent whole or not at all; the most visible first).
  std::vector<uint8_t> update(const SceneCamera& camera, uint32_t frame, size_t budget, const PoseOptions& o,
                              UpdateStats* stats = nullptr);
  // The same for what any of several cameras needs (the newest pose and
  // where the viewer is predicted to be when the update is drawn).
  std::vector<uint8_t> update(const std::vector<SceneCamera>& cameras, uint32_t frame, size_t budget,
                              const PoseOptions& o, UpdateStats* stats = nullptr);
  const std::vector<terrain::Mask>& held() const { return held_; }
  uint32_t used() const { return used_; }
  uint32_t capacity() const { return capacity_; }

 private:
  // Squared screen error per estimated bit of growing block b from `from`
  // to `to` where it covers `pixels` pixels and shows DC level `shown`
  // before its own DC arrives.
  double stage_score(uint32_t b, terrain::Mask from, terrain::Mask to, double pixels, int shown) const;

  static constexpr uint32_t kRecentFrames = 20;  // "needed a moment ago": a second at 20 frames/s

  const TerrainCoding& t_;
  uint32_t capacity_ = 0, used_ = 0;
  std::vector<terrain::Mask> held_;
  std::vector<uint32_t> last_needed_;
};

// One change to a block in an update.
struct BlockChange {
  uint32_t id = 0;
  terrain::Mask mask = 0;  // the mask after
};
// Encodes a TTEX payload: shrinks and grows (each by ascending id) against
// `held`, the client's masks before. The coefficients come from t.levels.
std::vector<uint8_t> encode_update(const TerrainCoding& t, const std::vector<terrain::Mask>& held, uint32_t frame,
                                   const std::vector<BlockChange>& shrinks, const std::vector<BlockChange>& grows);

}  // namespace vds::enc
