// The terrain mode's baseline: a tile pyramid of JPEG or WebP tiles
// (vds/enc/terrain_tiles.h).
#include "vds/enc/terrain_tiles.h"

#include <turbojpeg.h>
#include <webp/decode.h>
#include <webp/encode.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

namespace vds::enc {

namespace {


// Bytes of a JPEG's DQT and DHT segments: a client with shared tables
// holds them once.
size_t jpeg_table_bytes(const unsigned char* p, size_t n) {
  size_t at = 2, tables = 0;
  while (at + 4 <= n && p[at] == 0xFF) {
    const int marker = p[at + 1];
    const size_t len = (static_cast<size_t>(p[at + 2]) << 8) | p[at + 3];
    if (marker == 0xDB || marker == 0xC4) tables += 2 + len;
    if (marker == 0xDA) break;
    at += 2 + len;
  }
  return tables;
}

struct Tile {
  int level = 0, tx = 0, ty = 0;
  size_t bytes = 0;       // on the link
  io::Image decoded;      // what the client shows once it holds the tile
};

class TileSource : public FlightSource {
 public:
  TileSource(const TerrainCoding& t, const FlightOptions& o, const TileOptions& to) : t_(t), o_(o), to_(to) {
    if (to.tile < 8 || to.quality < 1 || to.quality > 100) throw std::invalid_argument("tile options out of range");
    io::Image level = t.colour;
    for (;;) {
      const int nx = (level.width + to.tile - 1) / to.tile, ny = (level.height + to.tile - 1) / to.tile;
      levels_.push_back({nx, ny, static_cast<int>(tiles_.size())});
      for (int ty = 0; ty < ny; ++ty)
        for (int tx = 0; tx < nx; ++tx) tiles_.push_back(code(level, static_cast<int>(levels_.size()) - 1, tx, ty));
      if (nx == 1 && ny == 1) break;
      level = io::halve(level);
    }
    held_.assign(tiles_.size(), 0);
    last_wanted_.assign(tiles_.size(), 0);
  }

  size_t answer(const std::vector<SceneCamera>& cams, uint32_t pose, size_t budget, FlightFrame* ff) override {
    // The tiles the cameras want: per visible cell the coarsest level whose
    // texels stay within max_error_px, and the tiles above it.
    std::vector<double> dist(tiles_.size(), std::numeric_limits<double>::infinity());
    const int top = static_cast<int>(levels_.size()) - 1;
    for (const SceneCamera& cam : cams) {
      std::vector<BlockView> views;
      pose_masks(t_, cam, o_.pose, &views);
      for (int j = 0; j < t_.grid.cells_y; ++j)
        for (int i = 0; i < t_.grid.cells_x; ++i) {
          const BlockView& v = views[t_.grid.cell(i, j)];
          if (!v.visible) continue;
          const double ppt = v.cutoff / o_.pose.detail;  // screen pixels a full-resolution texel covers
          int level = ppt > 0 ? static_cast<int>(std::floor(std::log2(to_.max_error_px / ppt))) : top;
          level = std::clamp(level, 0, top);
          for (int l = level; l <= top; ++l) {
            const size_t id = tile_of(l, (8 * i) >> l, (8 * j) >> l);
            dist[id] = std::min(dist[id], v.distance);
          }
        }
    }
    for (size_t id = 0; id < tiles_.size(); ++id)
      if (std::isfinite(dist[id])) last_wanted_[id] = pose + 1;
    // A transfer whose tile this pose does not want is cancelled.
    if (sending_ >= 0 && !std::isfinite(dist[static_cast<size_t>(sending_)])) sending_ = -1;
    size_t spent = 0;
    for (;;) {
      if (sending_ < 0) {
        // The nearest wanted tile whose parent the client holds.
        double best = std::numeric_limits<double>::infinity();
        for (size_t id = 0; id < tiles_.size(); ++id) {
          if (held_[id] || !std::isfinite(dist[id]) || dist[id] >= best) continue;
          const Tile& tl = tiles_[id];
          if (tl.level < top && !held_[tile_of(tl.level + 1, tl.tx * to_.tile / 2, tl.ty * to_.tile / 2)]) continue;
          best = dist[id];
          sending_ = static_cast<long>(id);
        }
        if (sending_ < 0) break;
        sent_ = 0;
      }
      const Tile& tl = tiles_[static_cast<size_t>(sending_)];
      const size_t take = std::min(tl.bytes - sent_, budget - spent);
      sent_ += take;
      spent += take;
      if (sent_ < tl.bytes) break;  // the budget ends inside the tile
      // Arrived: into the cache, dropping the tiles wanted longest ago.
      const size_t need = tile_cache_bytes();
      while (cache_used_ + need > to_.cache_bytes) {
        long victim = -1;
        for (size_t id = 0; id < tiles_.size(); ++id)
          if (held_[id] && (victim < 0 || last_wanted_[id] < last_wanted_[static_cast<size_t>(victim)])) victim = static_cast<long>(id);
        if (victim < 0) break;
        held_[static_cast<size_t>(victim)] = 0;
        cache_used_ -= need;
        ++ff->update.shrinks;
        changed_ = true;
      }
      if (cache_used_ + need <= to_.cache_bytes) {
        held_[static_cast<size_t>(sending_)] = 1;
        cache_used_ += need;
        ++ff->update.grows;
        changed_ = true;
      }
      sending_ = -1;
      if (spent >= budget) break;
    }
    for (size_t id = 0; id < tiles_.size(); ++id) ff->update.wanted += std::isfinite(dist[id]) && !held_[id];
    return spent;
  }

  bool changed() const override { return changed_; }
  uint32_t held() const override { return static_cast<uint32_t>(cache_used_); }

  // Every texel from the finest held tile over it, bilinear within that
  // tile's level; mid-grey where the client holds none.
  io::Image texture() override {
    changed_ = false;
    io::Image out(t_.colour.width, t_.colour.height, 3);
    const int top = static_cast<int>(levels_.size()) - 1;
    for (int y = 0; y < out.height; ++y)
      for (int x = 0; x < out.width; ++x) {
        uint8_t* d = &out.at(x, y, 0);
        d[0] = d[1] = d[2] = 128;
        for (int l = 0; l <= top; ++l) {
          const size_t id = tile_of(l, x >> l, y >> l);
          if (!held_[id]) continue;
          const Tile& tl = tiles_[id];
          // The texel centre in the tile's level, relative to the tile.
          const double fx = (x + 0.5) / (1 << l) - 0.5 - tl.tx * to_.tile, fy = (y + 0.5) / (1 << l) - 0.5 - tl.ty * to_.tile;
          const int x0 = std::clamp(static_cast<int>(std::floor(fx)), 0, to_.tile - 1), y0 = std::clamp(static_cast<int>(std::floor(fy)), 0, to_.tile - 1);
          const int x1 = std::min(x0 + 1, to_.tile - 1), y1 = std::min(y0 + 1, to_.tile - 1);
          const double ax = std::clamp(fx - x0, 0.0, 1.0), ay = std::clamp(fy - y0, 0.0, 1.0);
          for (int c = 0; c < 3; ++c) {
            const double top_row = tl.decoded.at(x0, y0, c) * (1 - ax) + tl.decoded.at(x1, y0, c) * ax;
            const double bottom = tl.decoded.at(x0, y1, c) * (1 - ax) + tl.decoded.at(x1, y1, c) * ax;
            d[c] = static_cast<uint8_t>(std::lround(top_row * (1 - ay) + bottom * ay));
          }
          break;
        }
      }
    return out;
  }

 private:
  struct Level {
    int nx, ny, first;
  };

  size_t tile_of(int level, int x, int y) const {
    const Level& l = levels_[static_cast<size_t>(level)];
    const int tx = std::min(x / to_.tile, l.nx - 1), ty = std::min(y / to_.tile, l.ny - 1);
    return static_cast<size_t>(l.first + ty * l.nx + tx);
  }
  size_t tile_cache_bytes() const { return static_cast<size_t>(to_.tile) * to_.tile * 3 / 2; }

  Tile code(const io::Image& level, int l, int tx, int ty) {
    const int n = to_.tile;
    std::vector<uint8_t> rgb(static_cast<size_t>(n) * n * 3);
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        for (int c = 0; c < 3; ++c)
          rgb[(static_cast<size_t>(y) * n + x) * 3 + static_cast<size_t>(c)] =
              level.at(std::min(tx * n + x, level.width - 1), std::min(ty * n + y, level.height - 1), c);
    Tile t;
    t.level = l;
    t.tx = tx;
    t.ty = ty;
    t.decoded = io::Image(n, n, 3);
    if (to_.codec == TileCodec::jpeg) {
      std::unique_ptr<void, int (*)(tjhandle)> enc(tjInitCompress(), tjDestroy), dec(tjInitDecompress(), tjDestroy);
      unsigned char* jpeg = nullptr;
      unsigned long size = 0;
      if (tjCompress2(enc.get(), rgb.data(), n, 0, n, TJPF_RGB, &jpeg, &size, TJSAMP_420, to_.quality,
                      TJFLAG_ACCURATEDCT) != 0)
        throw std::runtime_error(std::string("tile pyramid: JPEG encoding failed: ") + tjGetErrorStr2(enc.get()));
      const size_t tables = jpeg_table_bytes(jpeg, size);
      t.bytes = size - (tiles_.empty() ? 0 : tables);  // the tables travel with the first tile only
      const int ok = tjDecompress2(dec.get(), jpeg, size, t.decoded.pixels.data(), n, 0, n, TJPF_RGB, TJFLAG_ACCURATEDCT);
      tjFree(jpeg);
      if (ok != 0) throw std::runtime_error("tile pyramid: JPEG decoding failed");
    } else {
      uint8_t* webp = nullptr;
      const size_t size = WebPEncodeRGB(rgb.data(), n, n, n * 3, static_cast<float>(to_.quality), &webp);
      if (size == 0) throw std::runtime_error("tile pyramid: WebP encoding failed");
      t.bytes = size;
      const bool ok = WebPDecodeRGBInto(webp, size, t.decoded.pixels.data(), t.decoded.pixels.size(), n * 3) != nullptr;
      WebPFree(webp);
      if (!ok) throw std::runtime_error("tile pyramid: WebP decoding failed");
    }
    return t;
  }

  const TerrainCoding& t_;
  const FlightOptions& o_;
  TileOptions to_;
  std::vector<Level> levels_;
  std::vector<Tile> tiles_;
  std::vector<uint8_t> held_;
  std::vector<uint32_t> last_wanted_;
  size_t cache_used_ = 0;
  long sending_ = -1;
  size_t sent_ = 0;
  bool changed_ = true;
};

}  // namespace

TileOptions parse_tile_variant(const std::string& name) {
  TileOptions o;
  std::string size;
  if (name.rfind("jpeg", 0) == 0) {
    o.codec = TileCodec::jpeg;
    size = name.substr(4);
  } else if (name.rfind("webp", 0) == 0) {
    o.codec = TileCodec::webp;
    size = name.substr(4);
  } else {
    throw std::invalid_argument("tile variant '" + name + "' (jpeg64, jpeg256, webp64 or webp256)");
  }
  if (size == "64") o.tile = 64;
  else if (size == "256") o.tile = 256;
  else throw std::invalid_argument("tile variant '" + name + "' (jpeg64, jpeg256, webp64 or webp256)");
  return o;
}

FlightResult fly_tiles(const TerrainCoding& t, const CameraPath& path, const FlightOptions& o, const TileOptions& to) {
  TileSource s(t, o, to);
  return fly_source(t, path, o, s);
}

}  // namespace vds::enc
