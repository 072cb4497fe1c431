// vds encoder: the walkthrough's geometry schedule (vds/enc/walk_geometry.h).
#include "vds/enc/walk_geometry.h"

#include <algorithm>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace vds::enc {

WalkGeometryPlan plan_walk_geometry(const std::vector<std::vector<uint32_t>>& visible, uint32_t slots, int window) {
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
        // Farthest next use; a polygon hot at f has its next use after f only
        // if it is hot again later, but it must stay: skip those.
        auto victim = by_next.end();
        for (auto it = by_next.rbegin(); it != by_next.rend(); ++it) {
          if (!std::binary_search(hot[f].begin(), hot[f].end(), it->second)) {
            victim = std::prev(it.base());
            break;
          }
        }
        if (victim == by_next.end()) throw std::logic_error("plan_walk_geometry: no slot to evict");
        s = victim->first.second;
        slot_of.erase(victim->second);
        by_next.erase(victim);
      }
      slot_id[s] = id;
      slot_of[id] = s;
      by_next[{next_frame(id), s}] = id;
      plan.sends[f].push_back({id, s});
      if (sent_before[id]) ++plan.resends;
      else ++plan.first_sends;
      sent_before[id] = true;
    }
    for (uint32_t id : hot[f]) plan.hot[f].push_back(slot_of[id]);
    std::sort(plan.hot[f].begin(), plan.hot[f].end());
  }
  return plan;
}

}  // namespace vds::enc
