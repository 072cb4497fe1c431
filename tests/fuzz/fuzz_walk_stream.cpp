// libFuzzer: the client's player in walkthrough mode (decoder/src/player/
// mode_walk.cpp) on hostile streams. The first byte picks the stream: a
// valid walkthrough of a small room (built once) whose chunk payloads the
// input's bytes flip (CRCs recomputed, so the mode meets the damage), or a
// valid container of walkthrough chunks (WLKP, WVUP, IMGH, IMGD, WFRM)
// whose payloads are the input's bytes. Invariants: no crash or
// sanitizer report; every band lies inside its frame; the player ends
// with ok, more_input or an error.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "vds/bytes.h"
#include "vds/container.h"
#include "vds/enc/stream_writer.h"
#include "vds/enc/walk_stream.h"
#include "vds/player.h"
#include "vds/walk.h"
#include "stream_chunks.h"
#include "walk_room.h"

namespace {

struct Stream {
  vds::StreamHeader header;
  std::vector<std::pair<uint32_t, std::vector<uint8_t>>> chunks;  // after HEAD, before END
};

Stream valid_walk() {
  vds::enc::WalkEncodeOptions o;
  o.quality = 20;
  o.width = 128;  // (views two thirds of that each side: some of their MCUs unread, region images)
  o.height = 96;
  o.refine_delta = 30;  // residual refinements too
  o.refine_after = 1;
  o.predict = true;  // and updates against the client's prediction
  o.threshold = 1.6;
  o.zoom = 20;  // and zoomed views (18-byte WVUPs; within the threshold)
  o.zoom_min_run = 1;
  o.zoom_run = 0;
  const auto r = vds::enc::encode_walk(vds::test::walk_room(), vds::test::walk_room_path(8), o);
  if (r.view_predicted == 0 || r.view_refinements == 0 || r.view_mcus_coded == r.view_mcus || r.view_zoomed == 0) {
    std::fprintf(stderr,
                 "fuzz_walk_stream: the seed stream lacks predicted updates (%zu), refinements (%zu), region images (%zu of %zu "
                 "MCUs) or zoomed views (%zu)\n",
                 r.view_predicted, r.view_refinements, r.view_mcus_coded, r.view_mcus, r.view_zoomed);
    std::abort();
  }
  Stream s;
  bool first = true;
  for (const vds::test::ChunkAt& c : vds::test::stream_chunks(r.stream)) {
    const std::vector<uint8_t> payload = c.bytes(r.stream);
    if (first) vds::header_from_bytes(payload.data(), c.size, r.stream[4], r.stream[5], &s.header);
    else if (c.type != vds::chunk::kEnd) s.chunks.emplace_back(c.type, payload);
    first = false;
  }
  return s;
}

const Stream& room() {
  static const Stream s = valid_walk();
  return s;
}

struct Watch {
  uint16_t w = 0, h = 0;
  bool open = false;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const Stream& base = room();
  vds::StreamHeader h = base.header;
  h.max_chunk_payload = 8192;
  vds::enc::StreamWriter w(h);
  if (data[0] & 1) {
    size_t at = 1;
    for (const auto& [type, payload] : base.chunks) {
      std::vector<uint8_t> p = payload;
      for (size_t i = 0; i < p.size() && at < size; i += 1 + data[at] % 16, ++at) p[i] ^= data[at];
      w.add_chunk(type, p);
    }
  } else {
    const uint32_t types[] = {vds::chunk::kWalkParams, vds::chunk::kWalkView, vds::chunk::kImageHeader,
                              vds::chunk::kImageData, vds::chunk::kWalkFrame, vds::chunk::kWalkFrame};
    // The room's WLKP first, so the mode is set up; then the input's chunks.
    w.add_chunk(base.chunks[0].first, base.chunks[0].second);
    size_t at = 1;
    while (at + 2 <= size) {
      const uint32_t type = types[data[at] % 6];
      const size_t len = data[at + 1] * 8u % 700;
      at += 2;
      const size_t n = len < size - at ? len : size - at;
      w.add_chunk(type, std::vector<uint8_t>(data + at, data + at + n));
      at += n;
    }
  }
  const std::vector<uint8_t> stream = w.finish();
  // The least workspace, or more: the player's caches of projected
  // vertices and homographies take none, part or all of what is spare.
  const size_t spare[] = {0, 1000, 4096, size_t{1} << 16};
  std::vector<uint8_t> ws(h.max_chunk_payload + h.workspace_bytes + spare[(data[0] >> 1) & 3]);
  vds::Arena arena(ws.data(), ws.size());
  vds::Player player;
  Watch watch;
  vds::PlayerCallbacks cb;
  cb.ctx = &watch;
  cb.begin_frame = [](void* ctx, uint16_t fw, uint16_t fh) {
    auto* wt = static_cast<Watch*>(ctx);
    if (wt->open) abort();
    wt->w = fw, wt->h = fh, wt->open = true;
    return true;
  };
  cb.band = [](void* ctx, const vds::PixelRect& r) {
    auto* wt = static_cast<Watch*>(ctx);
    if (!wt->open || r.x + r.w > wt->w || r.y + r.h > wt->h) abort();
    return true;
  };
  cb.end_frame = [](void* ctx, uint32_t) {
    auto* wt = static_cast<Watch*>(ctx);
    if (!wt->open) abort();
    wt->open = false;
    return true;
  };
  vds::PlayerConfig cfg;
  cfg.max_chunk_bytes = h.max_chunk_payload;
  if (player.init(arena, cfg, cb) != vds::Status::ok) abort();
  vds::Status s = player.feed(stream.data(), stream.size());
  if (s == vds::Status::more_input) s = player.finish();
  if (s != vds::Status::ok && s != vds::Status::more_input && !vds::is_error(s)) abort();
  return 0;
}
