// vds encoder: which polygons a walkthrough client holds at each frame, and
// when each must be sent — the geometry schedule of the walkthrough mode.
//
// The client keeps polygons in a fixed number of slots (a budget the stream
// declares). At frame f it draws the *hot* polygons: those visible (in the
// ground truth's visibility buffers) within `window` frames either side of
// f, a conservative superset of what f shows. Every hot polygon must be held
// at f; one not held is sent (with the slot it goes into) by f. The encoder
// knows the whole path, so when a slot is needed and all are full it
// evicts the held polygon whose next hot frame is farthest away (never one
// hot at f; among those never hot again, the first slot after the last
// send's, which the record names in one bin) — the choice that resends the fewest
// polygons. The client never chooses: it stores what the stream puts in a
// slot, so its cache mirrors this plan by construction.
#pragma once
#include <cstddef>
#include <cstdint>
#include <array>
#include <vector>

#include "vds/enc/arith_encoder.h"
#include "vds/enc/scene.h"
#include "vds/walk_geometry.h"

namespace vds::enc {

struct WalkGeometryPlan {
  uint32_t slots = 0;
  struct Send {
    uint32_t id;      // the polygon (triangle index in the scene)
    uint32_t slot;    // where it goes, replacing what was there
    bool hot = true;  // drawn in the frame it is sent with (false: sent ahead)
  };
  std::vector<std::vector<Send>> sends;      // per frame: polygons to have arrived by that frame
  std::vector<std::vector<uint32_t>> hot;    // per frame: the slots to draw, ascending
  size_t first_sends = 0, resends = 0;       // resends: polygons sent again after an eviction
  size_t peak_hot = 0;                       // the largest hot set
};

// `visible[f]`: the polygon IDs frame f shows. Throws std::runtime_error if
// a frame's hot set exceeds `slots`. `max_sends` > 0 spreads bursts: a
// frame with more sends than that passes the rest to the frame before,
// each as long as its slot is not drawn there (the polygon it replaces is
// then evicted a frame earlier), so that entering a large room does not
// put hundreds of polygons into one frame's record.
WalkGeometryPlan plan_walk_geometry(const std::vector<std::vector<uint32_t>>& visible, uint32_t slots, int window,
                                    size_t max_sends = 0);

// The vertex grid for a scene: the largest power-of-two step from 1 map
// unit down to 1/256 (raw Q16.16) that puts every vertex within `tolerance`
// map units of a grid point (Quake maps built from whole-unit brushes: 1).
int32_t choose_walk_quantum(const Scene& s, double tolerance);

// The geometry of each frame's record (vds/walk_geometry.h), mirroring
// the client's decoder state.
class WalkGeometryEncoder {
 public:
  // `quantum_raw`: the vertex grid, a power of two in raw Q16.16 world
  // units (1..65536); std::invalid_argument otherwise.
  WalkGeometryEncoder(uint32_t slots, int32_t quantum_raw);
  WalkGeometryEncoder(const WalkGeometryEncoder&) = delete;  // the ring points into ring_storage_
  WalkGeometryEncoder& operator=(const WalkGeometryEncoder&) = delete;
  struct Send {
    uint32_t slot;
    bool hot_now;
    std::array<std::array<double, 3>, 3> vertices;  // world units, rounded to the grid
  };
  // One frame: its sends, in order, and its hot slots (any order), into the
  // record's coder — or into a payload of its own.
  void encode(ArithEncoder& e, const std::vector<Send>& sends, const std::vector<uint32_t>& hot);
  std::vector<uint8_t> encode(const std::vector<Send>& sends, const std::vector<uint32_t>& hot);

 private:
  uint32_t slots_;
  int32_t quantum_;
  WalkGeometryContexts ctx_{};
  std::vector<std::array<int32_t, 3>> ring_storage_;
  WalkVertexRing ring_{};
  WalkAxisValues axes_{};
  std::vector<uint32_t> prev_hot_;
  uint32_t last_slot_;
  int32_t prev_[3][3]{}, cur_[3][3]{};
};

}  // namespace vds::enc
