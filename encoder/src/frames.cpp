// Image sequences and the host replay of the client's display path.
#include "vds/enc/frames.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "vds/container.h"
#include "vds/crc32c.h"
#include "vds/enc/stream_writer.h"
#include "vds/image.h"
#include "vds/mesh.h"
#include "vds/model_view.h"

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
  // The client's decoder state, and its RGB565 band of one MCU row.
  h.workspace_bytes = static_cast<uint32_t>(ImageDecoder::kWorkspaceBytes + 16u * 2u * o.width + 16);
  StreamWriter w(h);
  for (const EncodedImage& e : coded) add_image_chunks(w, e);
  r.stream = w.finish();
  return r;
}

namespace {

struct Replay {
  ImageDecoder decoder;
  MeshDecoder mesh;  // model streams
  ModelView view;
  bool model = false;
  bool model_started = false;  // MSHH seen
  ModelFrames shown;
  Arena* arena = nullptr;
  std::vector<uint16_t> band;
  uint16_t width = 0, height = 0;
  uint32_t crc = 0;
  std::vector<uint32_t> crcs;
  std::vector<Image>* frames = nullptr;
  Status error = Status::ok;
};

bool on_band(void* ctx, const PixelRect& r) {
  auto* rp = static_cast<Replay*>(ctx);
  for (uint16_t row = 0; row < r.h; ++row) {
    const uint8_t* line = r.pixels + row * r.stride;
    rp->crc = crc32c_update(rp->crc, line, static_cast<size_t>(r.w) * 2);
    if (rp->frames) {
      Image& img = rp->frames->back();
      for (uint16_t x = 0; x < r.w; ++x) {
        const uint16_t p = static_cast<uint16_t>(line[2 * x] | (line[2 * x + 1] << 8));
        const uint32_t rr = (p >> 11) & 31, gg = (p >> 5) & 63, bb = p & 31;
        img.at(r.x + x, r.y + row, 0) = static_cast<uint8_t>((rr << 3) | (rr >> 2));
        img.at(r.x + x, r.y + row, 1) = static_cast<uint8_t>((gg << 2) | (gg >> 4));
        img.at(r.x + x, r.y + row, 2) = static_cast<uint8_t>((bb << 3) | (bb >> 2));
      }
    }
  }
  return true;
}

// The model view's bands, as the client's on_render_band passes them on.
bool on_render_band(void* ctx, const Band& b) {
  return on_band(ctx, PixelRect{0, b.y, b.width, b.height, b.pixels, static_cast<ptrdiff_t>(b.stride)});
}

// The client firmware's model path (firmware_sim/app/client.cpp): decoder
// and view set up at MSHH (vds::start_model), frames drawn by the same rule
// (vds::ModelFrames).
bool start_model(Replay& r, const uint8_t* p, uint32_t n) {
  ModelViewConfig vc;
  vc.width = r.width;
  vc.height = r.height;
  vc.band_height = 16;
  const Status s = vds::start_model(*r.arena, p, n, vc, r.mesh, r.view, nullptr);
  if (s != Status::ok) r.error = s;
  return s == Status::ok;
}

ChunkResult on_model_chunk(Replay& r, uint32_t type, const uint8_t* p, uint32_t n) {
  if (!MeshDecoder::handles(type)) return ChunkResult::unknown;
  if (!r.model_started) {
    if (type != chunk::kMeshHeader) r.error = Status::malformed;
    if (type != chunk::kMeshHeader || !start_model(r, p, n)) return ChunkResult::abort;
    r.model_started = true;
  }
  const Status s = r.mesh.consume(type, p, n);
  if (is_error(s)) {
    r.error = s;
    return ChunkResult::abort;
  }
  if (r.shown.due(r.mesh)) {
    r.crc = 0;
    if (r.frames) r.frames->emplace_back(r.width, r.height, 3);
    const Status d = r.view.draw(r.mesh.mesh(), r.shown.angle(), on_render_band, &r);
    r.shown.mark_drawn(r.mesh);
    if (d != Status::ok) {
      r.error = d;
      return ChunkResult::abort;
    }
    r.crcs.push_back(r.crc);
  }
  return ChunkResult::consumed;
}

}  // namespace

std::vector<uint32_t> client_frame_crcs(std::span<const uint8_t> stream, std::vector<Image>* frames) {
  auto rp = std::make_unique<Replay>();
  rp->frames = frames;
  // The chunk buffer, then what the header declares, as on a client.
  std::vector<uint8_t> ws((1u << 24) + ImageDecoder::kWorkspaceBytes + (1u << 23));  // or a model of <= 65,536 vertices
  Arena arena(ws.data(), ws.size());
  rp->arena = &arena;
  StreamParser parser;
  ChunkSink sink;
  sink.ctx = rp.get();
  sink.on_header = [](void* ctx, const StreamHeader& h) {
    auto* r = static_cast<Replay*>(ctx);
    r->width = h.width;
    r->height = h.height;
    if (h.mode == StreamMode::model) {
      r->model = true;  // decoder and view are set up when MSHH arrives
      return true;
    }
    if (h.mode != StreamMode::images) return false;
    if (r->decoder.init(*r->arena) != Status::ok) return false;
    r->band.assign(static_cast<size_t>(h.width) * 16, 0);
    return true;
  };
  sink.on_chunk = [](void* ctx, uint32_t type, const uint8_t* p, uint32_t n) {
    auto* r = static_cast<Replay*>(ctx);
    if (r->model) return on_model_chunk(*r, type, p, n);
    if (type != chunk::kImageHeader && type != chunk::kImageData) return ChunkResult::unknown;
    if (type == chunk::kImageHeader) {
      r->crc = 0;
      if (r->frames) r->frames->emplace_back(r->width, r->height, 3);
    }
    const ImageTarget t = ImageTarget::bands(PixelFormat::rgb565, reinterpret_cast<uint8_t*>(r->band.data()),
                                             static_cast<ptrdiff_t>(r->width) * 2, on_band, r);
    const Status s = r->decoder.on_chunk(type, p, n, t);
    if (is_error(s)) {
      r->error = s;
      return ChunkResult::abort;
    }
    if (type == chunk::kImageData && s == Status::ok) r->crcs.push_back(r->crc);
    return ChunkResult::consumed;
  };
  if (parser.init(arena, 1u << 24, sink) != Status::ok) throw std::runtime_error("client parser: cannot initialise");
  Status s = parser.feed(stream.data(), stream.size());
  if (s == Status::more_input) s = parser.finish();
  if (s != Status::ok) {
    const Status why = rp->error != Status::ok ? rp->error : s;
    throw std::runtime_error(std::string("client decode failed: ") + status_name(why) + " at byte " +
                             std::to_string(parser.error_offset()));
  }
  return rp->crcs;
}

}  // namespace vds::enc
