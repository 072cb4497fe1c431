// vds encoder: a walkthrough's schedule (docs/walkthrough.md, "Rate
// control"): when each part of a stream reaches its client over a link of a
// given rate, and the least pre-roll with which every frame's data is there
// in time.
//
// The client (firmware_sim/app/client.cpp) takes stream bytes from the
// link's window as they come, except while it plays a frame record: it
// draws each of the record's frames when it is due (the pre-roll plus i
// frame periods after the stream's first byte), and meanwhile the bytes
// after the record wait in the window, so the link carries no more than
// the window holds past the record's end. Stream byte y arrives at
//
//   A(y) = max(A(y - 1) + 1 / rate, release(r) for every record r ending before y - window)
//
// where release(r) = max(A(r's last byte), due(r's last frame)), and the
// client has the byte the link's latency after A(y); the
// model computes it piece by piece, exactly. A record is on time when it
// arrives by its first frame's due time.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace vds::enc {

// Consecutive stream bytes the client takes together.
struct WalkPiece {
  size_t bytes = 0;
  uint32_t first_frame = 0;  // the first frame drawn after it
  uint32_t last_frame = 0;   // a record: its last frame
  bool record = false;       // a WFRM record (others: header, views)
};

struct WalkLink {
  double rate_bytes = 2000;    // stream bytes a second
  size_t buffer_bytes = 4096;  // the client's stream window
  double frame_period_s = 0.05;
  // What the link's framing adds: a byte is the client's when the frame
  // carrying it is whole, up to a whole frame's time after the line
  // carried it.
  double latency_s = 0;
};

// The time each piece's last byte arrives, in seconds after the stream's
// first byte, with `preroll_s`.
std::vector<double> walk_arrivals(const std::vector<WalkPiece>& pieces, const WalkLink& link, double preroll_s);
// Seconds by which the latest record misses its first frame's due time (<= 0: every one is on time).
double walk_lateness_s(const std::vector<WalkPiece>& pieces, const WalkLink& link, double preroll_s);
// The least pre-roll in whole milliseconds with which every record is on
// time; UINT32_MAX if even `max_ms` is not enough.
uint32_t walk_preroll_ms(const std::vector<WalkPiece>& pieces, const WalkLink& link, uint32_t max_ms);

}  // namespace vds::enc
