// Image sequences and the host replay of the client's display path.
#include "vds/enc/frames.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "host_player.h"
#include "vds/bytes.h"
#include "vds/container.h"
#include "vds/enc/stream_writer.h"
#include "vds/image.h"
#include "vds/io/image.h"
#include "vds/player.h"

namespace vds::enc {

Image fit_image(const Image& src, int w, int h) {
  if (w <= 0 || h <= 0) throw std::invalid_argument("frame size must be positive");
  if (src.width <= 0 || src.height <= 0) throw std::invalid_argument("empty source image");
  // Scale so the source covers the frame, then take the centre.
  const double s = std::max(static_cast<double>(w) / src.width, static_cast<double>(h) / src.height);
  const double ox = (src.width * s - w) / 2, oy = (src.height * s - h) / 2;
  Image out(w, h, 3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      // Area average of the source footprint of this output pixel.
      const double sx0 = (x + ox) / s, sx1 = (x + 1 + ox) / s, sy0 = (y + oy) / s, sy1 = (y + 1 + oy) / s;
      const int ix0 = std::clamp(static_cast<int>(std::floor(sx0)), 0, src.width - 1);
      const int ix1 = std::clamp(static_cast<int>(std::ceil(sx1)) - 1, ix0, src.width - 1);
      const int iy0 = std::clamp(static_cast<int>(std::floor(sy0)), 0, src.height - 1);
      const int iy1 = std::clamp(static_cast<int>(std::ceil(sy1)) - 1, iy0, src.height - 1);
      double acc[3] = {0, 0, 0}, wsum = 0;
      for (int iy = iy0; iy <= iy1; ++iy) {
        const double wy = std::min<double>(iy + 1, sy1) - std::max<double>(iy, sy0);
        for (int ix = ix0; ix <= ix1; ++ix) {
          const double wx = std::min<double>(ix + 1, sx1) - std::max<double>(ix, sx0);
          const double wgt = std::max(0.0, wx) * std::max(0.0, wy) + 1e-12;
          for (int c = 0; c < 3; ++c) acc[c] += wgt * src.at(ix, iy, src.channels >= 3 ? c : 0);
          wsum += wgt;
        }
      }
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = static_cast<uint8_t>(std::clamp(acc[c] / wsum + 0.5, 0.0, 255.0));
    }
  }
  return out;
}

FrameSequenceResult encode_frames(const std::vector<Image>& frames, const FrameSequenceOptions& o) {
  if (frames.empty()) throw std::invalid_argument("no frames to encode");
  if (o.width <= 0 || o.height <= 0 || o.width > 16384 || o.height > 16384)
    throw std::invalid_argument("frame size must be 1..16384 on each side");
  std::vector<EncodedImage> coded;
  FrameSequenceResult r;
  uint32_t max_payload = 0;
  for (const Image& f : frames) {
    if (f.width != o.width || f.height != o.height)
      throw std::invalid_argument("every frame must be " + std::to_string(o.width) + "x" + std::to_string(o.height));
    coded.push_back(encode_image(f, o.image));
    max_payload = std::max(max_payload, coded.back().max_payload());
    r.psnr.push_back(coded.back().psnr);
    r.frame_bytes.push_back(coded.back().coded_bytes());
  }
  StreamHeader h = default_header(StreamMode::images, static_cast<uint16_t>(o.width), static_cast<uint16_t>(o.height));
  h.frame_period_us = o.fps > 0 ? static_cast<uint32_t>(std::lround(1e6 / o.fps)) : 0;
  h.frame_count = static_cast<uint32_t>(frames.size());
  h.max_chunk_payload = std::max<uint32_t>(max_payload, kImageHeaderBytes);
  // What the client's player needs to show it: the image decoder and its band.
  h.workspace_bytes = static_cast<uint32_t>(Player::image_workspace_bytes(static_cast<uint16_t>(o.width), kClientPlayerConfig));
  StreamWriter w(h);
  for (const EncodedImage& e : coded) add_image_chunks(w, e);
  r.stream = w.finish();
  return r;
}

namespace {

// What the replay collects from the player.
struct Replay {
  std::vector<uint32_t> crcs;
  std::vector<Image>* frames = nullptr;
  std::vector<std::string>* notices = nullptr;
};

std::string notice_text(PlayerNotice what, uint32_t a, uint32_t b, uint32_t c) {
  switch (what) {
    case PlayerNotice::model_partial:
      return "model: the workspace holds " + std::to_string(a) + " of its " + std::to_string(b) +
             " vertices; later levels are skipped";
    case PlayerNotice::model_full:
      return "model: workspace full after level " + std::to_string(a) + " of " + std::to_string(b) + " (" +
             std::to_string(c) + " vertices)";
    case PlayerNotice::model_base_too_big:
      return "model: the base mesh needs " + std::to_string(a) + " bytes of workspace, " + std::to_string(b) +
             " are left";
    case PlayerNotice::model_colors_level:
      return "model: colours down to MIP level " + std::to_string(a) + " of " + std::to_string(b) + " fit the workspace";
    case PlayerNotice::model_no_colors:
      return a == 1 ? "model: the mesh is not whole: drawn without its colours"
                    : "model: no room for the colours: drawn without them";
  }
  return "model: notice " + std::to_string(static_cast<int>(what));
}

bool replay_band(void* ctx, const PixelRect& r) {
  auto* rp = static_cast<Replay*>(ctx);
  if (rp->frames == nullptr) return true;
  Image& img = rp->frames->back();
  for (uint16_t row = 0; row < r.h; ++row) {
    const uint8_t* line = r.pixels + row * r.stride;
    for (uint16_t x = 0; x < r.w; ++x) {
      io::rgb565_to_rgb888(load_le16(line + 2 * x), &img.at(r.x + x, r.y + row, 0));
    }
  }
  return true;
}

}  // namespace

// The client's own player with the boards' configuration: only its chunk
// buffer is sized to the stream (it changes no pixel).
std::vector<uint32_t> client_frame_crcs(std::span<const uint8_t> stream, std::vector<Image>* frames,
                                        const ClientArena* board, std::vector<std::string>* notices) {
  Replay rp;
  rp.frames = frames;
  rp.notices = notices;
  PlayerCallbacks cb;
  cb.ctx = &rp;
  cb.begin_frame = [](void* ctx, uint16_t w, uint16_t h) {
    auto* r = static_cast<Replay*>(ctx);
    if (r->frames) r->frames->emplace_back(w, h, 3);
    return true;
  };
  cb.band = replay_band;
  cb.frame_shown = [](void* ctx, const PlayedFrame& f) { static_cast<Replay*>(ctx)->crcs.push_back(f.crc); };
  cb.notice = [](void* ctx, PlayerNotice what, uint32_t a, uint32_t b, uint32_t c) {
    auto* r = static_cast<Replay*>(ctx);
    if (r->notices != nullptr) r->notices->push_back(notice_text(what, a, b, c));
  };
  HostPlayer host(cb, board);
  const Status s = host.play(stream);
  const Player* player = host.player.get();
  if (s != Status::ok) {
    throw std::runtime_error(std::string("client decode failed: ") + status_name(s) + " at byte " +
                             std::to_string(player->error_offset()) + " (" + player->error_detail() + ")");
  }
  return rp.crcs;
}

}  // namespace vds::enc
