// vds client library: the terrain stream's records and the client's block
// store (docs/terrain.md, "The terrain stream" and "The client").
//
// A terrain stream (HEAD mode terrain) carries, in order:
//   TERH  once: the grid, the world scale, the store and drawing budgets;
//   TFLY  the flight the client plays (camera keys), once;
//   TELV  the elevation: the coarse pass, then the fine pass in row pieces;
//   TTEX  texture updates (vds/terrain.h, TextureUpdateReader), each
//         applied to the store when it arrives;
//   TFRM  "draw frame n": the client draws frame n from its flight's pose n
//         with what it holds, and every pose_period frames sends that pose
//         up the back-channel (the pose datagram).
// The server writes TELV, TTEX and TFRM as the link carries them, answering
// the newest pose it has received; the client's frames depend only on the
// stream's bytes, so the server's replay of the stream through the same
// client library gives the same frames bit for bit.
//
// Freestanding: no heap, no float, no exceptions.
#pragma once
#include <stddef.h>
#include <stdint.h>

#include "vds/arena.h"
#include "vds/container.h"
#include "vds/status.h"
#include "vds/terrain.h"
#include "vds/walk.h"

namespace vds {

namespace chunk {
constexpr uint32_t kTerrainParams = fourcc('T', 'E', 'R', 'H');     // once, first
constexpr uint32_t kTerrainFlight = fourcc('T', 'F', 'L', 'Y');     // poses of the flight, from a frame on
constexpr uint32_t kTerrainElevation = fourcc('T', 'E', 'L', 'V');  // an elevation pass or a piece of the fine pass
constexpr uint32_t kTerrainTexture = fourcc('T', 'T', 'E', 'X');    // a texture update
constexpr uint32_t kTerrainFrame = fourcc('T', 'F', 'R', 'M');      // draw a frame
}  // namespace chunk

namespace terrain {

// TERH payload (24 bytes): u16 cells_x, u16 cells_y, u8 quantiser, u8
// texel cache log2 (the window of cells whose blocks the client keeps
// transformed: 2^n x 2^n), u16 the most cells drawn with their own
// block's texels a frame, u32 store units (2 bytes each; store_cost),
// i32 cell size (world units, Q16.16), i32 height step (world units per
// elevation level, Q16.16), u16 pose period (frames between the poses the
// client sends up; 0: none), u8 the half-resolution window's log2 (2 x 2
// texels a cell for 2^n x 2^n cells; 0: none), u8 the frame's geometry
// budget n (2..64: 512 n ground vertices, 512 n ground triangles, 256 n
// skirt triangles).
// World: point (i, j) of the grid lies at x = i cell, y = (cells_y - j)
// cell, z = height(i, j) step; texel row 0 is the grid's row j = 0 (north).
struct Params {
  uint16_t cells_x = 0, cells_y = 0;
  uint8_t quantiser = 0;
  uint8_t cache_log2 = 4;
  uint16_t max_cells = 128;
  uint32_t store_units = 0;
  int32_t cell_q16 = 0;
  int32_t height_step_q16 = 0;
  uint16_t pose_period = 0;
  uint8_t half_log2 = 0;
  uint8_t frame_budget = 2;
};
inline constexpr uint32_t kParamsBytes = 24;
inline constexpr uint8_t kMaxHalfLog2 = 7;
inline constexpr uint8_t kMinFrameBudget = 2, kMaxFrameBudget = 64;
inline constexpr uint8_t kMinCacheLog2 = 1, kMaxCacheLog2 = 6;
inline constexpr uint16_t kMaxDrawnCells = 4096;
Status params_from_bytes(const uint8_t* p, uint32_t size, Params* out);
void params_to_bytes(const Params& t, uint8_t out[kParamsBytes]);
inline BlockGrid params_grid(const Params& t) {
  BlockGrid g;
  g.cells_x = t.cells_x;
  g.cells_y = t.cells_y;
  return g;
}

// TFLY payload (once, after TERH): u16 key spacing S (frames, 1..1024),
// then 16 bytes a key (i32 x, y, z world Q16.16, u16 yaw, u16 pitch:
// vds::WalkPose), at most kMaxFlightKeys keys, covering HEAD's frame count
// ((keys - 1) S >= frames - 1). Frame f's pose is flight_pose(): between
// key f / S and the next, linear in position, pitch and the shorter way
// round in yaw, in integer arithmetic both sides share.
inline constexpr uint32_t kPoseBytes = 16;
inline constexpr uint32_t kMaxFlightKeys = 255;
void pose_to_bytes(const WalkPose& p, uint8_t out[kPoseBytes]);
WalkPose pose_from_bytes(const uint8_t* p);
WalkPose flight_pose(const WalkPose* keys, uint32_t count, uint32_t spacing, uint32_t frame);

// TELV payload: u8 pass (0 coarse, 1 fine), u16 first row, u16 end row
// (the coarse pass: 0 and the grid's points_y), then the coded points
// (decode_elevation). Fine pieces come in row order, after the coarse pass.
inline constexpr uint32_t kElevationHeaderBytes = 5;

// TFRM payload: u32 the frame's index (0, 1, 2, ... in order), and
// optionally a pose (16 bytes): the frame is drawn from it instead of the
// flight's (a steered viewer: the server draws the pose the client sent).
inline constexpr uint32_t kFrameBytes = 4;
inline constexpr uint32_t kSteeredFrameBytes = kFrameBytes + kPoseBytes;

// The pose the client sends up (PlayerCallbacks::send_up kind kSendPose;
// the link's pose datagram): u32 frame, then the pose (16 bytes). Bit 31
// of the frame (kPoseSteered) marks a pose the viewer steered, which the
// server then draws (TFRM with a pose) from the next frame it writes on.
inline constexpr uint8_t kSendPose = 2;
inline constexpr uint32_t kPoseMessageBytes = 4 + kPoseBytes;
inline constexpr uint32_t kPoseSteered = 0x80000000u;

// --- Steering -------------------------------------------------------------------
//
// A viewer's controls for one frame (PlayerCallbacks::steer): forward,
// right and up each -1, 0 or 1 (keys), turn and tilt in 2^-16 turn this
// frame (keys or a mouse), fast: four times the speed.
struct SteerInput {
  int8_t forward = 0, right = 0, up = 0;
  int16_t turn = 0, tilt = 0;
  bool fast = false;
  bool any() const { return forward != 0 || right != 0 || up != 0 || turn != 0 || tilt != 0; }
};
// The pose after one frame of `in` from `p`: yaw plus turn (left, seen
// from above, for turn > 0), pitch plus tilt within +-kMaxSteerPitch, the
// position moved `step` world units (Q16.16; 4 step when fast) along the
// horizontal heading for forward, to its right for right, and half that
// up. Integer arithmetic (the library's sine and cosine): every platform
// gets the same pose.
inline constexpr uint16_t kMaxSteerPitch = 14563;  // 80 degrees
WalkPose steer_pose(const WalkPose& p, const SteerInput& in, int32_t step_q16);

// --- The block store ----------------------------------------------------------
//
// What the client holds of every block: its mask and the quantised
// coefficients the mask holds, in one buffer of store_units 2-byte units.
// A held block costs store_cost(mask) units: its coefficients and a 12-byte
// entry. The server counts the same (vds/enc/terrain_server.h), so an
// update never overfills a store of the size TERH declares.
inline constexpr uint32_t kEntryUnits = 6;
inline uint32_t store_cost(Mask m) { return m == 0 ? 0u : static_cast<uint32_t>(mask_count(m)) + kEntryUnits; }

class BlockStore {
 public:
  // Changes held back before they are merged into the store together.
  static constexpr uint32_t kStaged = 16;
  static size_t workspace_bytes(uint32_t units) { return size_t{units} * 2u + 4u + sizeof(Staged) * kStaged + 8u; }
  // invalid_argument for an empty grid; workspace_too_small.
  Status init(Arena& arena, const BlockGrid& grid, uint32_t units);
  // What the store holds (changes staged and not yet merged excluded).
  Mask held(uint32_t id) const;
  // A block's levels (natural order), 0 where the mask holds nothing.
  void levels(uint32_t id, int16_t out[64]) const;
  // Applies one block of an update (vds/terrain.h, TextureUpdateReader):
  // malformed when u.held is not what the store holds or the store would
  // overflow.
  Status apply(const BlockUpdate& u) {
    const Status s = stage(u, nullptr, nullptr);
    return s == Status::ok ? merge(nullptr, nullptr) : s;
  }
  // The same, held back: changes to blocks in ascending id order are
  // merged into the store in one pass over it (an update's shrinks, then
  // its grows). A change to a block at or below the last one staged, or
  // one past kStaged, merges what is staged first; `merged(ctx, id)` is
  // called for every block once its change is in the store.
  using MergedFn = void (*)(void* ctx, uint32_t id);
  Status stage(const BlockUpdate& u, MergedFn merged, void* ctx);
  Status merge(MergedFn merged, void* ctx);
  bool staged() const { return staged_ != 0; }
  uint32_t first_staged() const { return staged_ != 0 ? stage_[0].id : 0; }
  uint32_t last_staged() const { return staged_ != 0 ? stage_[staged_ - 1].id : 0; }
  uint32_t used_units() const { return used_; }  // staged changes included
  uint32_t held_blocks() const { return n_; }
  uint32_t capacity_units() const { return units_; }

 private:
  struct Entry {
    uint32_t id;
    Mask mask;
    uint32_t off;  // coefficients of the blocks before it
  };
  struct Staged {
    uint32_t id;
    Mask old_mask, mask;
    int16_t levels[64];  // natural order, what the block holds after
  };
  uint32_t lower_bound(uint32_t id) const;
  const int16_t* data(const Entry& e, int count) const { return pool_end_ - e.off - count; }
  Entry* entries_ = nullptr;
  int16_t* pool_end_ = nullptr;  // block k's coefficients end off_k units below this
  Staged* stage_ = nullptr;
  uint32_t staged_ = 0;
  uint32_t n_ = 0, coefficients_ = 0, units_ = 0, used_ = 0, blocks_ = 0;
};

}  // namespace terrain
}  // namespace vds
