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
  t.half_log2 = p[22];
  t.frame_budget = p[23];
  if (t.cells_x == 0 || t.cells_y == 0 || t.cells_x > kMaxCells || t.cells_y > kMaxCells ||
      t.quantiser < kMinQuantiser || t.quantiser > kMaxQuantiser || t.cache_log2 < kMinCacheLog2 ||
      t.cache_log2 > kMaxCacheLog2 || t.max_cells == 0 || t.max_cells > kMaxDrawnCells || t.store_units == 0 ||
      t.store_units > (1u << 28) || t.cell_q16 <= 0 || t.height_step_q16 < 0 || t.half_log2 > kMaxHalfLog2 ||
      t.frame_budget < kMinFrameBudget || t.frame_budget > kMaxFrameBudget)
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
  out[22] = t.half_log2;
  out[23] = t.frame_budget;
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

WalkPose steer_pose(const WalkPose& p, const SteerInput& in, int32_t step_q16) {
  WalkPose out = p;
  out.yaw = static_cast<uint16_t>(p.yaw + in.turn);
  int32_t pitch = static_cast<int16_t>(p.pitch) + int32_t{in.tilt};
  if (pitch > kMaxSteerPitch) pitch = kMaxSteerPitch;
  if (pitch < -int32_t{kMaxSteerPitch}) pitch = -int32_t{kMaxSteerPitch};
  out.pitch = static_cast<uint16_t>(pitch);
  const int64_t step = int64_t{step_q16} * (in.fast ? 4 : 1);
  // Heading (cos, sin) of the new yaw in Q1.15; right of it is (sin, -cos).
  const int64_t c = cos_q1_15(out.yaw).raw(), s = sin_q1_15(out.yaw).raw();
  const int64_t dx = (in.forward * c + in.right * s) * step >> 15;
  const int64_t dy = (in.forward * s - in.right * c) * step >> 15;
  const int64_t dz = in.up * step / 2;
  const auto add = [](Q16_16 v, int64_t d) { return Q16_16::from_raw(sat_s32(int64_t{v.raw()} + d)); };
  out.position = {add(p.position.x, dx), add(p.position.y, dy), add(p.position.z, dz)};
  return out;
}

// --- BlockStore ---------------------------------------------------------------
//
// One buffer: the entries (sorted by id) from its start, the coefficients
// from its end downward, block k's coefficients ending off_k units below
// the end (off_k: the coefficients of the blocks before it), each block's
// in raster order of its mask. Changes are staged (up to kStaged, in
// ascending id order) and merged in one pass: the runs of entries between
// the changed blocks move by the change in the number of entries before
// them, the runs of coefficients by the change in the number of
// coefficients before them, then the changed blocks are written into the
// room left for them.

Status BlockStore::init(Arena& arena, const BlockGrid& grid, uint32_t units) {
  if (grid.cells_x == 0 || grid.cells_y == 0 || units == 0) return Status::invalid_argument;
  uint8_t* buf = static_cast<uint8_t*>(arena.alloc(size_t{units} * 2u, alignof(Entry)));
  stage_ = arena.alloc_array<Staged>(kStaged);
  if (buf == nullptr || stage_ == nullptr) return Status::workspace_too_small;
  entries_ = reinterpret_cast<Entry*>(buf);
  pool_end_ = reinterpret_cast<int16_t*>(buf + size_t{units} * 2u);
  n_ = coefficients_ = used_ = staged_ = 0;
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

Status BlockStore::stage(const BlockUpdate& b, MergedFn merged, void* ctx) {
  if (b.id >= blocks_ || !mask_valid(b.mask)) return Status::malformed;
  if (staged_ == kStaged || (staged_ != 0 && b.id <= stage_[staged_ - 1].id)) {
    const Status s = merge(merged, ctx);
    if (s != Status::ok) return s;
  }
  const Mask old = held(b.id);
  if (old != b.held) return Status::malformed;
  if (b.mask == old) return Status::ok;
  const uint32_t used = used_ - store_cost(old) + store_cost(b.mask);
  if (used > units_) return Status::malformed;
  // The block's levels after the change: what it keeps, and what the
  // update adds.
  Staged& st = stage_[staged_++];
  st.id = b.id;
  st.old_mask = old;
  st.mask = b.mask;
  levels(b.id, st.levels);
  for (int v = 0; v < 8; ++v)
    for (int u = 0; u < 8; ++u) {
      const int i = 8 * v + u;
      if (!mask_holds(b.mask, u, v)) st.levels[i] = 0;
      else if (!mask_holds(old, u, v)) st.levels[i] = b.levels[i];
    }
  used_ = used;
  return Status::ok;
}

namespace {

// Moves runs of elements within one array: run r ([start_r, start_r + len_r)
// in the array's index space) moves by shift_r; runs keep their order and
// end up apart, so moving those that go down in ascending order and those
// that go up in descending order never overwrites one not yet moved.
// `at(i)` is the address of index i, `bytes` an element's size; for an
// array that grows downward in memory (the coefficients), at(i) is the
// address of its last byte's element.
template <class At>
void move_runs(const uint32_t* start, const uint32_t* len, const int32_t* shift, uint32_t runs, size_t bytes, At at) {
  for (uint32_t r = 0; r < runs; ++r)
    if (shift[r] < 0 && len[r] != 0) memmove(at(start[r] + shift[r], len[r]), at(start[r], len[r]), len[r] * bytes);
  for (uint32_t r = runs; r-- > 0;)
    if (shift[r] > 0 && len[r] != 0) memmove(at(start[r] + shift[r], len[r]), at(start[r], len[r]), len[r] * bytes);
}

}  // namespace

Status BlockStore::merge(MergedFn merged, void* ctx) {
  if (staged_ == 0) return Status::ok;
  // Where each staged block stands among the entries, and the runs between.
  // Run r (r = 0..staged) is the entries after staged block r - 1 and
  // before staged block r.
  uint32_t pos[kStaged], e_start[kStaged + 1], e_len[kStaged + 1], c_start[kStaged + 1], c_len[kStaged + 1];
  int32_t e_shift[kStaged + 1], c_shift[kStaged + 1];
  uint32_t at = 0, coef_at = 0;
  int32_t de = 0, dc = 0;
  for (uint32_t i = 0; i <= staged_; ++i) {
    const uint32_t k = i < staged_ ? lower_bound(stage_[i].id) : n_;
    const uint32_t c = k < n_ ? entries_[k].off : coefficients_;
    e_start[i] = at, e_len[i] = k - at, e_shift[i] = de;
    c_start[i] = coef_at, c_len[i] = c - coef_at, c_shift[i] = dc;
    if (i == staged_) break;
    pos[i] = k;
    const bool present = stage_[i].old_mask != 0;
    at = k + (present ? 1u : 0u);
    coef_at = c + static_cast<uint32_t>(mask_count(stage_[i].old_mask));
    de += (stage_[i].mask != 0 ? 1 : 0) - (present ? 1 : 0);
    dc += mask_count(stage_[i].mask) - mask_count(stage_[i].old_mask);
  }
  const uint32_t n_after = static_cast<uint32_t>(static_cast<int32_t>(n_) + de);
  auto move_entries = [&] {
    move_runs(e_start, e_len, e_shift, staged_ + 1, sizeof(Entry), [&](uint32_t i, uint32_t) { return &entries_[i]; });
  };
  // Coefficient index o (offset from the end) of a run of `len` starts at pool_end_ - o - len.
  auto move_coefficients = [&] {
    move_runs(c_start, c_len, c_shift, staged_ + 1, sizeof(int16_t),
              [&](uint32_t o, uint32_t len) { return pool_end_ - o - len; });
  };
  // The entries first when there will be fewer (they leave room the
  // coefficients may need), else the coefficients first.
  if (n_after < n_) move_entries(), move_coefficients();
  else move_coefficients(), move_entries();
  // The moved entries' offsets, then the staged blocks themselves.
  for (uint32_t r = 1; r <= staged_; ++r)
    for (uint32_t j = 0; j < e_len[r]; ++j) {
      Entry& e = entries_[static_cast<uint32_t>(static_cast<int32_t>(e_start[r]) + e_shift[r]) + j];
      e.off = static_cast<uint32_t>(static_cast<int32_t>(e.off) + c_shift[r]);
    }
  for (uint32_t i = 0; i < staged_; ++i) {
    const Staged& st = stage_[i];
    if (st.mask == 0) continue;
    const uint32_t k = static_cast<uint32_t>(static_cast<int32_t>(pos[i]) + e_shift[i]);
    const uint32_t off = static_cast<uint32_t>(static_cast<int32_t>(c_start[i] + c_len[i]) + c_shift[i]);
    entries_[k] = Entry{st.id, st.mask, off};
    int16_t* dst = pool_end_ - off - mask_count(st.mask);
    for (int v = 0; v < 8; ++v)
      for (int u = 0; u < mask_extent(st.mask, v); ++u) *dst++ = st.levels[8 * v + u];
  }
  n_ = n_after;
  coefficients_ = static_cast<uint32_t>(static_cast<int32_t>(coefficients_) + dc);
  const uint32_t count = staged_;
  staged_ = 0;
  if (merged != nullptr)
    for (uint32_t i = 0; i < count; ++i) merged(ctx, stage_[i].id);
  return Status::ok;
}

}  // namespace vds::terrain
