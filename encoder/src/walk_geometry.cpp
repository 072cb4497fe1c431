// vds encoder: the walkthrough's geometry schedule (vds/enc/walk_geometry.h).
#include "vds/enc/walk_geometry.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace vds::enc {

WalkGeometryPlan plan_walk_geometry(const std::vector<std::vector<uint32_t>>& visible, uint32_t slots, int window,
                                    size_t max_sends) {
  const size_t n = visible.size();
  WalkGeometryPlan plan;
  plan.slots = slots;
  plan.sends.resize(n);
  plan.hot.resize(n);
  if (window < 0) throw std::invalid_argument("plan_walk_geometry: a negative window");
  // Hot sets, and for each polygon the frames it is hot in (rising).
  std::vector<std::vector<uint32_t>> hot(n);
  std::unordered_map<uint32_t, std::vector<uint32_t>> hot_frames;
  for (size_t f = 0; f < n; ++f) {
    const size_t lo = f >= static_cast<size_t>(window) ? f - static_cast<size_t>(window) : 0;
    const size_t hi = std::min(n - 1, f + static_cast<size_t>(window));
    for (size_t g = lo; g <= hi; ++g) hot[f].insert(hot[f].end(), visible[g].begin(), visible[g].end());
    std::sort(hot[f].begin(), hot[f].end());
    hot[f].erase(std::unique(hot[f].begin(), hot[f].end()), hot[f].end());
    if (hot[f].size() > slots)
      throw std::runtime_error("frame " + std::to_string(f) + " needs " + std::to_string(hot[f].size()) +
                               " polygons at once, more than the " + std::to_string(slots) + " slots");
    plan.peak_hot = std::max(plan.peak_hot, hot[f].size());
    for (uint32_t id : hot[f]) hot_frames[id].push_back(static_cast<uint32_t>(f));
  }
  constexpr uint32_t kEmpty = std::numeric_limits<uint32_t>::max();
  std::vector<uint32_t> slot_id(slots, kEmpty);
  std::unordered_map<uint32_t, uint32_t> slot_of;
  std::unordered_map<uint32_t, size_t> next_use;  // index into hot_frames[id] of its next hot frame
  std::unordered_map<uint32_t, bool> sent_before;
  // Free slots, lowest first.
  std::vector<uint32_t> free_slots;
  for (uint32_t s = slots; s-- > 0;) free_slots.push_back(s);
  uint32_t cursor = slots - 1;  // the last send's slot, as the geometry record codes it
  // Held polygons by (next hot frame, slot), farthest last.
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> by_next;
  const auto next_frame = [&](uint32_t id) {
    const auto& fr = hot_frames[id];
    const size_t k = next_use[id];
    return k < fr.size() ? fr[k] : kEmpty;  // never again: farthest of all
  };
  for (size_t f = 0; f < n; ++f) {
    // Advance every hot polygon's next use past f (those held move in by_next).
    for (uint32_t id : hot[f]) {
      const auto it = slot_of.find(id);
      if (it != slot_of.end()) by_next.erase({next_frame(id), it->second});
      ++next_use[id];
      if (it != slot_of.end()) by_next[{next_frame(id), it->second}] = id;
    }
    for (uint32_t id : hot[f]) {
      if (slot_of.count(id)) continue;
      uint32_t s;
      if (!free_slots.empty()) {
        s = free_slots.back();
        free_slots.pop_back();
      } else {
        // Polygons never hot again are equally good victims: the first
        // such slot after the last send's goes (the cheapest slot to name:
        // the geometry record codes "the slot after the last" in one bin).
        // Else the farthest next use; a polygon hot at f has its next use
        // after f only if it is hot again later, but it must stay: skip those.
        s = kEmpty;
        for (uint32_t k = 1; k <= slots && s == kEmpty; ++k) {
          const uint32_t c = (cursor + k) % slots;
          if (next_frame(slot_id[c]) == kEmpty && !std::binary_search(hot[f].begin(), hot[f].end(), slot_id[c])) s = c;
        }
        if (s == kEmpty) {
          for (auto it = by_next.rbegin(); it != by_next.rend(); ++it) {
            if (!std::binary_search(hot[f].begin(), hot[f].end(), it->second)) {
              s = it->first.second;
              break;
            }
          }
        }
        if (s == kEmpty) throw std::logic_error("plan_walk_geometry: no slot to evict");
        by_next.erase({next_frame(slot_id[s]), s});
        slot_of.erase(slot_id[s]);
      }
      slot_id[s] = id;
      slot_of[id] = s;
      cursor = s;
      by_next[{next_frame(id), s}] = id;
      plan.sends[f].push_back({id, s});
      if (sent_before[id]) ++plan.resends;
      else ++plan.first_sends;
      sent_before[id] = true;
    }
    for (uint32_t id : hot[f]) plan.hot[f].push_back(slot_of[id]);
    std::sort(plan.hot[f].begin(), plan.hot[f].end());
  }
  // Bursts spread backwards, a frame at a time.
  for (size_t f = n; max_sends > 0 && f-- > 1;) {
    std::vector<WalkGeometryPlan::Send>& now = plan.sends[f];
    if (now.size() <= max_sends) continue;
    std::vector<WalkGeometryPlan::Send>& before = plan.sends[f - 1];
    const std::vector<uint32_t>& drawn = plan.hot[f - 1];
    std::vector<WalkGeometryPlan::Send> keep;
    for (const WalkGeometryPlan::Send& snd : now) {
      const bool free_before = !std::binary_search(drawn.begin(), drawn.end(), snd.slot) &&
                               std::none_of(before.begin(), before.end(), [&](const auto& b) { return b.slot == snd.slot; });
      if (keep.size() < max_sends || !free_before) {
        keep.push_back(snd);
      } else {
        before.push_back({snd.id, snd.slot, false});
      }
    }
    now = std::move(keep);
  }
  return plan;
}

int32_t choose_walk_quantum(const Scene& s, double tolerance) {
  for (int32_t q = 65536; q > 256; q /= 2) {
    const double step = q / 65536.0;
    bool fits = true;
    for (const SceneVertex& v : s.vertices) {
      for (float c : v.pos)
        if (std::fabs(c - std::round(c / step) * step) > tolerance) {
          fits = false;
          break;
        }
      if (!fits) break;
    }
    if (fits) return q;
  }
  return 256;
}

WalkGeometryEncoder::WalkGeometryEncoder(uint32_t slots, int32_t quantum_raw)
    : slots_(slots), quantum_(quantum_raw), ring_storage_(kWalkVertexRing), last_slot_(slots - 1) {
  if (slots == 0 || slots > kWalkMaxSlots || !walk_quantum_valid(quantum_raw))
    throw std::invalid_argument("WalkGeometryEncoder: slots or quantum out of range");
  ctx_.reset();
  ring_.reset(reinterpret_cast<int32_t(*)[3]>(ring_storage_.data()));
  axes_.reset();
  for (int c = 0; c < 3; ++c)
    for (int a = 0; a < 3; ++a) prev_[c][a] = cur_[c][a] = INT32_MIN;
}

namespace {

// A place in a list of 2^bits entries, as walk_get_place reads it.
void put_place(ArithEncoder& e, ArithContext* bucket, uint32_t bits, uint32_t place) {
  uint32_t b = 0;
  while ((place >> b) != 0) ++b;
  e.encode_unary(bucket, static_cast<int>(bits + 1), b, bits);
  if (b >= 2) e.encode_bits_bypass(place & ((1u << (b - 1)) - 1u), static_cast<int>(b - 1));
}

}  // namespace

std::vector<uint8_t> WalkGeometryEncoder::encode(const std::vector<Send>& sends, const std::vector<uint32_t>& hot) {
  ArithEncoder e;
  encode(e, sends, hot);
  return e.finish();
}

void WalkGeometryEncoder::encode(ArithEncoder& e, const std::vector<Send>& sends, const std::vector<uint32_t>& hot_in) {
  std::vector<uint32_t> hot = hot_in;
  std::sort(hot.begin(), hot.end());
  hot.erase(std::unique(hot.begin(), hot.end()), hot.end());
  e.encode_ueg(ctx_.count, 4, static_cast<uint32_t>(sends.size()), 8, 2);
  const int bits = walk_slot_bits(slots_);
  const double q = quantum_ / 65536.0;
  std::vector<bool> sent_hot(slots_, false);
  for (const Send& s : sends) {
    if (s.slot >= slots_) throw std::invalid_argument("WalkGeometryEncoder: a slot outside the budget");
    const uint32_t next = last_slot_ + 1 == slots_ ? 0 : last_slot_ + 1;
    e.encode_bit(ctx_.next_slot, s.slot == next);
    if (s.slot != next) e.encode_bits_bypass(s.slot, bits);
    last_slot_ = s.slot;
    e.encode_bit(ctx_.hot_now, s.hot_now);
    if (s.hot_now) sent_hot[s.slot] = true;
    // The triangle on the grid, turned (its winding kept) so that an edge
    // it shares with the triangle before it comes first: its third vertex
    // is then predicted across that edge.
    int32_t tri[3][3];
    for (int c = 0; c < 3; ++c)
      for (int a = 0; a < 3; ++a) tri[c][a] = static_cast<int32_t>(std::lround(s.vertices[static_cast<size_t>(c)][static_cast<size_t>(a)] / q));
    const auto in_prev = [&](const int32_t* v) {
      for (int j = 0; j < 3; ++j)
        if (prev_[j][0] == v[0] && prev_[j][1] == v[1] && prev_[j][2] == v[2]) return true;
      return false;
    };
    for (int turn = 0; turn < 3; ++turn) {
      const int k0 = turn, k1 = (turn + 1) % 3;
      if (in_prev(tri[k0]) && in_prev(tri[k1]) && (tri[k0][0] != tri[k1][0] || tri[k0][1] != tri[k1][1] || tri[k0][2] != tri[k1][2])) {
        int32_t t[3][3];
        for (int c = 0; c < 3; ++c)
          for (int a = 0; a < 3; ++a) t[c][a] = tri[(c + turn) % 3][a];
        std::copy(&t[0][0], &t[0][0] + 9, &tri[0][0]);
        break;
      }
    }
    for (int c = 0; c < 3; ++c) {
      int32_t g[3];
      for (int a = 0; a < 3; ++a) g[a] = tri[c][a];
      // The newest copy in the ring, if any.
      uint32_t found = kWalkVertexRing;
      for (uint32_t i = 0; i < ring_.size; ++i) {
        const int32_t* r = ring_.at(i);
        if (r[0] == g[0] && r[1] == g[1] && r[2] == g[2]) {
          found = i;
          break;
        }
      }
      if (ring_.size > 0) e.encode_bit(ctx_.cached[c], found < kWalkVertexRing);
      if (found < kWalkVertexRing) {
        put_place(e, ctx_.ring_bucket, kWalkRingBits, found);
      } else {
        const int fb = walk_fraction_bits(quantum_);
        int32_t pred[3];
        const bool across = walk_predict(ring_, prev_, cur_, c, pred);
        for (int a = 0; a < 3; ++a) {
          if (!across) {
            const uint32_t i = axes_.find(a, g[a]);
            e.encode_bit(ctx_.axis_seen[a], i < kWalkAxisValues);
            if (i < kWalkAxisValues) {
              put_place(e, ctx_.axis_bucket[a], kWalkAxisBits, i);
              continue;
            }
          }
          const int32_t base = pred[a];
          const int64_t delta = static_cast<int64_t>(g[a]) - base;
          const int64_t whole = delta >> fb;  // floor: the fraction is never negative
          const int64_t fraction = delta - whole * (int64_t{1} << fb);
          e.encode_signed(ctx_.delta_zero[a], ctx_.delta_mag[a], 6, static_cast<int32_t>(whole), 6, 3);
          for (int b = fb - 1; b >= 0; --b) e.encode_bit(ctx_.fraction[fb - 1 - b], static_cast<int>((fraction >> b) & 1));
        }
      }
      ring_.push(g);
      axes_.touch(g);
      for (int a = 0; a < 3; ++a) cur_[c][a] = g[a];
    }
    for (int c = 0; c < 3; ++c)
      for (int a = 0; a < 3; ++a) prev_[c][a] = cur_[c][a];
  }
  uint32_t stayed = 1;
  for (uint32_t s : prev_hot_) {
    const int now = std::binary_search(hot.begin(), hot.end(), s) ? 1 : 0;
    e.encode_bit(ctx_.stays[stayed], now);
    stayed = static_cast<uint32_t>(now);
  }
  std::vector<uint32_t> again;
  for (uint32_t s : hot)
    if (!sent_hot[s] && !std::binary_search(prev_hot_.begin(), prev_hot_.end(), s)) again.push_back(s);
  e.encode_ueg(ctx_.again_count, 4, static_cast<uint32_t>(again.size()), 8, 2);
  for (size_t k = 0; k < again.size(); ++k)
    e.encode_ueg(ctx_.again_gap, 4, k == 0 ? again[0] : again[k] - again[k - 1] - 1, 8, 4);
  prev_hot_ = hot;
}

}  // namespace vds::enc
