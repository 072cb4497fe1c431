// vds encoder: a walkthrough's schedule (vds/enc/walk_schedule.h).
#include "vds/enc/walk_schedule.h"

#include <algorithm>
#include <stdexcept>

namespace vds::enc {

namespace {

double due_s(uint32_t frame, const WalkLink& l, double preroll_s) { return preroll_s + frame * l.frame_period_s; }

}  // namespace

std::vector<double> walk_arrivals(const std::vector<WalkPiece>& pieces, const WalkLink& l, double preroll_s) {
  if (!(l.rate_bytes > 0) || !(l.frame_period_s > 0)) throw std::invalid_argument("walk_arrivals: a rate and a frame period above 0");
  std::vector<double> arrival(pieces.size());
  std::vector<size_t> end(pieces.size());
  const auto release = [&](size_t r) { return std::max(arrival[r], due_s(pieces[r].last_frame, l, preroll_s)); };
  // Stream byte y (1, 2, ...) comes no sooner than the byte before it plus
  // a byte's time, nor before the release of any record r with
  // end(r) + window < y. Releases rise with r: the latest such record is
  // the one that counts, and it changes within a piece where a record's
  // end plus the window falls inside it.
  std::vector<size_t> records;
  size_t held = 0;  // records[0, held): their windows end before the current piece
  double t = 0;
  size_t at = 0;
  for (size_t i = 0; i < pieces.size(); ++i) {
    const size_t s = at;
    at += pieces[i].bytes;
    end[i] = at;
    while (held < records.size() && end[records[held]] + l.buffer_bytes <= s) ++held;
    double a = (held > 0 ? std::max(t, release(records[held - 1])) : t) + pieces[i].bytes / l.rate_bytes;
    for (; held < records.size() && end[records[held]] + l.buffer_bytes < at; ++held) {
      const size_t r = records[held];
      a = std::max(a, release(r) + static_cast<double>(at - end[r] - l.buffer_bytes) / l.rate_bytes);
    }
    t = a;
    arrival[i] = a + l.latency_s;
    if (pieces[i].record) records.push_back(i);
  }
  return arrival;
}

double walk_lateness_s(const std::vector<WalkPiece>& pieces, const WalkLink& l, double preroll_s) {
  const std::vector<double> a = walk_arrivals(pieces, l, preroll_s);
  double late = -1e300;
  for (size_t i = 0; i < pieces.size(); ++i)
    if (pieces[i].record) late = std::max(late, a[i] - due_s(pieces[i].first_frame, l, preroll_s));
  return late;
}

uint32_t walk_preroll_ms(const std::vector<WalkPiece>& pieces, const WalkLink& l, uint32_t max_ms) {
  // Later pre-rolls shift every due time and release by the same amount and
  // arrivals by no more: on time at p, on time at every later p.
  // (A nanosecond's rounding forgiven.)
  const auto on_time = [&](uint32_t ms) { return walk_lateness_s(pieces, l, ms / 1000.0) <= 1e-9; };
  if (!on_time(max_ms)) return UINT32_MAX;
  uint32_t lo = 0, hi = max_ms;
  if (on_time(lo)) return 0;
  while (hi - lo > 1) {
    const uint32_t mid = lo + (hi - lo) / 2;
    (on_time(mid) ? hi : lo) = mid;
  }
  return hi;
}

}  // namespace vds::enc
