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
// hot at f; ties: the highest slot) — the choice that resends the fewest
// polygons. The client never chooses: it stores what the stream puts in a
// slot, so its cache mirrors this plan by construction.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace vds::enc {

struct WalkGeometryPlan {
  uint32_t slots = 0;
  struct Send {
    uint32_t id;    // the polygon (triangle index in the scene)
    uint32_t slot;  // where it goes, replacing what was there
  };
  std::vector<std::vector<Send>> sends;      // per frame: polygons to have arrived by that frame
  std::vector<std::vector<uint32_t>> hot;    // per frame: the slots to draw, ascending
  size_t first_sends = 0, resends = 0;       // resends: polygons sent again after an eviction
  size_t peak_hot = 0;                       // the largest hot set
};

// `visible[f]`: the polygon IDs frame f shows. Throws std::runtime_error if
// a frame's hot set exceeds `slots`.
WalkGeometryPlan plan_walk_geometry(const std::vector<std::vector<uint32_t>>& visible, uint32_t slots, int window);

}  // namespace vds::enc
