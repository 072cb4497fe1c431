// vds client library: the terrain stream's records and the block store
// (vds/terrain_client.h).
#include "vds/terrain_client.h"

#include <string.h>

#include "vds/bytes.h"

namespace vds::terrain {

Status params_from_bytes(const uint8_t* p, uint32_t size, Params* out) {
  if (p == nullptr || size != kParamsBytes) return Status::malformed;
  Params t;
  t.cells_x = load_le16(p);
  t.cells_y = load_le16(p + 2);
  t.quantiser = p[4];
  t.cache_log2 = p[5];
  t.max_cells = load_le16(p + 6);
  t.store_units = load_le32(p + 8);
  t.cell_q16 = load_le32s(p + 12);
  t.height_step_q16 = load_le32s(p + 16);
  t.pose_period = load_le16(p + 20);
  if (t.cells_x == 0 || t.cells_y == 0 || t.cells_x > kMaxCells || t.cells_y > kMaxCells ||
      t.quantiser < kMinQuantiser || t.quantiser > kMaxQuantiser || t.cache_log2 < kMinCacheLog2 ||
      t.cache_log2 > kMaxCacheLog2 || t.max_cells == 0 || t.max_cells > kMaxDrawnCells || t.store_units == 0 ||
      t.store_units > (1u << 28) || t.cell_q16 <= 0 || t.height_step_q16 < 0 || load_le16(p + 22) != 0)
    return Status::malformed;
  *out = t;
  return Status::ok;
}

void params_to_bytes(const Params& t, uint8_t out[kParamsBytes]) {
  store_le16(out, t.cells_x);
  store_le16(out + 2, t.cells_y);
  out[4] = t.quantiser;
  out[5] = t.cache_log2;
  store_le16(out + 6, t.max_cells);
  store_le32(out + 8, t.store_units);
  store_le32(out + 12, static_cast<uint32_t>(t.cell_q16));
  store_le32(out + 16, static_cast<uint32_t>(t.height_step_q16));
  store_le16(out + 20, t.pose_period);
  store_le16(out + 22, 0);
}

void pose_to_bytes(const WalkPose& p, uint8_t out[kPoseBytes]) {
  store_le32(out, static_cast<uint32_t>(p.position.x.raw()));
  store_le32(out + 4, static_cast<uint32_t>(p.position.y.raw()));
  store_le32(out + 8, static_cast<uint32_t>(p.position.z.raw()));
  store_le16(out + 12, p.yaw);
  store_le16(out + 14, p.pitch);
}

WalkPose pose_from_bytes(const uint8_t* p) {
  WalkPose w;
  w.position = {Q16_16::from_raw(load_le32s(p)), Q16_16::from_raw(load_le32s(p + 4)), Q16_16::from_raw(load_le32s(p + 8))};
  w.yaw = load_le16(p + 12);
  w.pitch = load_le16(p + 14);
  return w;
}

WalkPose flight_pose(const WalkPose* keys, uint32_t count, uint32_t spacing, uint32_t frame) {
  if (count == 0 || spacing == 0) return WalkPose{};
  const uint32_t k = frame / spacing;
  if (k + 1 >= count) return keys[count - 1];
  const WalkPose& a = keys[k];
  const WalkPose& b = keys[k + 1];
  const int64_t t = frame % spacing, s = spacing;
  auto lerp = [&](Q16_16 x, Q16_16 y) {
    const int64_t d = int64_t{y.raw()} - x.raw();
    return Q16_16::from_raw(static_cast<int32_t>(x.raw() + d * t / s));
  };
  auto turn = [&](uint16_t x, uint16_t y) {
    const int32_t d = static_cast<int16_t>(static_cast<uint16_t>(y - x));  // the shorter way round
    return static_cast<uint16_t>(x + static_cast<int32_t>(d * t / s));
  };
  WalkPose p;
  p.position = {lerp(a.position.x, b.position.x), lerp(a.position.y, b.position.y), lerp(a.position.z, b.position.z)};
  p.yaw = turn(a.yaw, b.yaw);
  p.pitch = turn(a.pitch, b.pitch);
  return p;
}

// --- BlockStore ---------------------------------------------------------------
//
// One buffer: the entries (sorted by id) from its start, the coefficients
// from its end downward, block k's coefficients ending off_k units below
// the end (off_k: the coefficients of the blocks before it), each block's
// in raster order of its mask. A change to block k moves the coefficients
// of the blocks after it (below it) by the change in its count.

Status BlockStore::init(Arena& arena, const BlockGrid& grid, uint32_t units) {
  if (grid.cells_x == 0 || grid.cells_y == 0 || units == 0) return Status::invalid_argument;
  uint8_t* buf = static_cast<uint8_t*>(arena.alloc(size_t{units} * 2u, alignof(Entry)));
  if (buf == nullptr) return Status::workspace_too_small;
  entries_ = reinterpret_cast<Entry*>(buf);
  pool_end_ = reinterpret_cast<int16_t*>(buf + size_t{units} * 2u);
  n_ = coefficients_ = used_ = 0;
  units_ = units;
  blocks_ = grid.blocks();
  return Status::ok;
}

uint32_t BlockStore::lower_bound(uint32_t id) const {
  uint32_t lo = 0, hi = n_;
  while (lo < hi) {
    const uint32_t mid = lo + (hi - lo) / 2;
    if (entries_[mid].id < id) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

Mask BlockStore::held(uint32_t id) const {
  const uint32_t k = lower_bound(id);
  return k < n_ && entries_[k].id == id ? entries_[k].mask : 0;
}

void BlockStore::levels(uint32_t id, int16_t out[64]) const {
  for (int i = 0; i < 64; ++i) out[i] = 0;
  const uint32_t k = lower_bound(id);
  if (k >= n_ || entries_[k].id != id) return;
  const Entry& e = entries_[k];
  const int16_t* src = data(e, mask_count(e.mask));
  for (int v = 0; v < 8; ++v)
    for (int u = 0; u < mask_extent(e.mask, v); ++u) out[8 * v + u] = *src++;
}

Status BlockStore::apply(const BlockUpdate& b) {
  if (b.id >= blocks_ || !mask_valid(b.mask)) return Status::malformed;
  uint32_t k = lower_bound(b.id);
  const bool present = k < n_ && entries_[k].id == b.id;
  const Mask old = present ? entries_[k].mask : 0;
  if (old != b.held) return Status::malformed;
  if (b.mask == old) return Status::ok;
  const uint32_t used = used_ - store_cost(old) + store_cost(b.mask);
  if (used > units_) return Status::malformed;
  // The block's levels after the change: what it keeps, and what the
  // update adds.
  int16_t lv[64];
  levels(b.id, lv);
  for (int v = 0; v < 8; ++v)
    for (int u = 0; u < 8; ++u) {
      const int i = 8 * v + u;
      if (!mask_holds(b.mask, u, v)) lv[i] = 0;
      else if (!mask_holds(old, u, v)) lv[i] = b.levels[i];
    }
  if (!present) {
    // A new entry at k, its coefficients where block k's began.
    const uint32_t off = k < n_ ? entries_[k].off : coefficients_;
    memmove(&entries_[k + 1], &entries_[k], (n_ - k) * sizeof(Entry));
    entries_[k] = Entry{b.id, 0, off};
    ++n_;
  }
  Entry& e = entries_[k];
  const int before = mask_count(old), after = mask_count(b.mask);
  const int32_t delta = after - before;
  // The blocks after k lie below it: move them by delta.
  const uint32_t below = coefficients_ - e.off - static_cast<uint32_t>(before);
  int16_t* low = pool_end_ - coefficients_;
  memmove(low - delta, low, below * sizeof(int16_t));
  for (uint32_t j = k + 1; j < n_; ++j) entries_[j].off = static_cast<uint32_t>(static_cast<int32_t>(entries_[j].off) + delta);
  coefficients_ = static_cast<uint32_t>(static_cast<int32_t>(coefficients_) + delta);
  e.mask = b.mask;
  int16_t* dst = pool_end_ - e.off - after;
  for (int v = 0; v < 8; ++v)
    for (int u = 0; u < mask_extent(b.mask, v); ++u) *dst++ = lv[8 * v + u];
  if (b.mask == 0) {
    memmove(&entries_[k], &entries_[k + 1], (n_ - k - 1) * sizeof(Entry));
    --n_;
  }
  used_ = used;
  return Status::ok;
}

}  // namespace vds::terrain
