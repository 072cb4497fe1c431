// The baseline the terrain mode is measured against: what a user would
// build instead, a tile pyramid of the colour map. Levels halve the
// resolution until one tile covers the map; each tile is coded alone as
// JPEG (libjpeg-turbo, 4:2:0; its tables counted once, as a client holding
// shared tables would) or WebP (libwebp). For each pose the client wants,
// for every visible cell, the coarsest level whose texels cover at most
// `max_error_px` pixels there, and every tile above those; it requests the
// tiles whose parent it holds, nearest first, one at a time, and cancels a
// transfer whose tile the newest pose no longer wants. Decoded tiles live in
// a cache of `cache_bytes` (4:2:0 texels, 1.5 bytes each) that drops the
// tile wanted longest ago. The replay uses vds's link model, renderer and
// ground truth (vds/enc/terrain_flight.h).
#pragma once
#include <cstddef>
#include <string>

#include "vds/enc/terrain_flight.h"

namespace vds::enc {

enum class TileCodec { jpeg, webp };

struct TileOptions {
  TileCodec codec = TileCodec::jpeg;
  int tile = 64;            // texels on a side
  int quality = 75;         // the codec's quality, 1..100
  size_t cache_bytes = 98304;
  double max_error_px = 2;  // screen pixels a texel may cover
};

// "jpeg64" -> {jpeg, 64}; throws std::invalid_argument for anything but
// jpeg or webp followed by 64 or 256.
TileOptions parse_tile_variant(const std::string& name);

// The flight with the tile pyramid in place of vds's updates: the same
// frames, link (rate, latency, poses), ground truth and renderer as fly().
// FlightFrame::update.grows counts tiles arrived, .shrinks tiles dropped,
// .wanted tiles still wanted; held is the cache's bytes.
FlightResult fly_tiles(const TerrainCoding& t, const CameraPath& path, const FlightOptions& o, const TileOptions& to);

}  // namespace vds::enc
