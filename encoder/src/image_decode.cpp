// vds encoder (host tools): runs the client's StreamParser and image decoders
// on a whole stream held in memory, as a device would, and collects the
// pixels (vds images to planes and RGB; JPEG chunks to RGB).
#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

#include "vds/enc/image_codec.h"
#include "vds/jpeg.h"

namespace vds::enc {

namespace {

// One pass of the client over the stream with a given target.
struct Pass {
  const Planes* prediction = nullptr;
  Planes blank;  // the destination's prior content when none is given
  ImageTarget target;
  bool want_planes = false;
  Planes* planes = nullptr;
  Image* rgb = nullptr;
  ImageDecoder* img = nullptr;
  JpegDecoder* jpeg = nullptr;
  Arena* arena = nullptr;
  bool started = false;
  bool finished = false;
  std::string kind;
  Status status = Status::ok;
  std::string error;
  std::string message;  // a host-side problem, reported as it is
};

bool predict_from_planes(void* ctx, uint16_t x, uint16_t y, uint16_t w, uint16_t h, uint8_t* yo, ptrdiff_t ys,
                         uint8_t* cbo, uint8_t* cro, ptrdiff_t cs) {
  const Planes& p = *static_cast<const Planes*>(ctx);
  for (int r = 0; r < h; ++r) std::memcpy(yo + r * ys, p.row(0, y + r) + x, w);
  if (cbo != nullptr && p.components() == 3) {
    const int s = p.chroma == ChromaFormat::yuv420 ? 1 : 0;
    const int cx = x >> s, cy = y >> s;
    const int cw = ((x + w + s) >> s) - cx, ch = ((y + h + s) >> s) - cy;
    for (int r = 0; r < ch; ++r) {
      std::memcpy(cbo + r * cs, p.row(1, cy + r) + cx, cw);
      std::memcpy(cro + r * cs, p.row(2, cy + r) + cx, cw);
    }
  }
  return true;
}

ChunkResult on_chunk(void* ctx, uint32_t type, const uint8_t* payload, uint32_t size) {
  Pass& p = *static_cast<Pass*>(ctx);
  if (p.finished) return ChunkResult::unknown;  // only the first image
  if (type == chunk::kImageHeader) {
    ImageHeader h;
    const Status hs = image_header_from_bytes(payload, size, &h);
    if (hs != Status::ok) {
      p.status = hs;
      p.error = "IMGH";
      return ChunkResult::abort;
    }
    p.kind = "vds";
    if (p.prediction != nullptr &&
        (p.prediction->width != h.width || p.prediction->height != h.height || p.prediction->chroma != h.chroma)) {
      // No exception may cross the client library's frames (built without
      // exception support): report through the pass, abort the parser.
      p.status = Status::invalid_argument;
      p.message = "the prediction does not match the image (" + std::to_string(h.width) + "x" +
                  std::to_string(h.height) + ", " +
                  (h.chroma == ChromaFormat::yuv420 ? "4:2:0" : h.chroma == ChromaFormat::yuv444 ? "4:4:4" : "grey") + ")";
      return ChunkResult::abort;
    }
    if (p.want_planes) {
      *p.planes = p.prediction != nullptr ? *p.prediction : Planes(h.width, h.height, h.chroma);
      Planes& pl = *p.planes;
      p.target = ImageTarget::planes(pl.plane[0].data(), pl.plane_width(0),
                                     h.components() == 3 ? pl.plane[1].data() : nullptr, pl.plane_width(1),
                                     h.components() == 3 ? pl.plane[2].data() : nullptr, pl.plane_width(2));
    } else {
      // Without a prediction the destination starts as the planes pass's
      // does: Y' 0, Cb = Cr = 128 (black).
      if (p.prediction == nullptr) p.blank = Planes(h.width, h.height, h.chroma);
      const Planes& prior = p.prediction != nullptr ? *p.prediction : p.blank;
      *p.rgb = planes_to_rgb(prior);
      p.target = ImageTarget::frame(PixelFormat::rgb888, p.rgb->pixels.data(), static_cast<ptrdiff_t>(h.width) * 3);
      p.target.predict = predict_from_planes;
      p.target.predict_ctx = const_cast<Planes*>(&prior);
    }
    const Status s = p.img->start(payload, size, p.target);
    if (s != Status::ok) {
      p.status = s;
      p.error = "IMGH";
      return ChunkResult::abort;
    }
    p.started = true;
    return ChunkResult::consumed;
  }
  if (type == chunk::kImageData) {
    if (!p.started) {
      p.status = Status::malformed;
      p.error = "IMGD before IMGH";
      return ChunkResult::abort;
    }
    const Status s = p.img->feed(payload, size);
    if (s == Status::ok) p.finished = true;
    if (is_error(s)) {
      p.status = s;
      p.error = "IMGD";
      return ChunkResult::abort;
    }
    return ChunkResult::consumed;
  }
  if (type == chunk::kJpeg) {
    if (p.want_planes) return ChunkResult::consumed;  // JPEG planes are not collected
    if (!p.started) {
      JpegInfo info;
      const Status is = jpeg_peek_info(payload, size, &info);
      if (is != Status::ok) {
        p.status = is;
        p.error = "JPEG header (it must lie in the first JPEG chunk)";
        return ChunkResult::abort;
      }
      *p.rgb = Image(info.width, info.height, 3);
      p.target = ImageTarget::frame(PixelFormat::rgb888, p.rgb->pixels.data(), static_cast<ptrdiff_t>(info.width) * 3);
      p.jpeg->start(p.target);
      p.started = true;
      p.kind = "jpeg";
    }
    const Status s = p.jpeg->feed(payload, size);
    if (s == Status::ok) p.finished = true;
    if (is_error(s)) {
      p.status = s;
      p.error = "JPEG";
      return ChunkResult::abort;
    }
    return ChunkResult::consumed;
  }
  return ChunkResult::unknown;
}

bool on_header(void* ctx, const StreamHeader&) {
  // A device carves its decoders once the header has declared what the
  // stream needs (the parser has checked it fits).
  Pass& p = *static_cast<Pass*>(ctx);
  return p.img->init(*p.arena) == Status::ok && p.jpeg->init(*p.arena) == Status::ok;
}

void run_pass(std::span<const uint8_t> stream, Pass& p) {
  // No chunk is larger than the stream; the decoders' workspaces follow.
  const uint32_t capacity = static_cast<uint32_t>(std::clamp<size_t>(stream.size(), kHeaderPayloadMax, 1u << 24));
  std::vector<uint8_t> ws(capacity + ImageDecoder::kWorkspaceBytes + JpegDecoder::kWorkspaceBytes + 64);
  Arena arena(ws.data(), ws.size());
  ImageDecoder img;
  JpegDecoder jpeg;
  p.img = &img;
  p.jpeg = &jpeg;
  p.arena = &arena;
  StreamParser parser;
  ChunkSink sink;
  sink.ctx = &p;
  sink.on_header = on_header;
  sink.on_chunk = on_chunk;
  if (parser.init(arena, capacity, sink) != Status::ok) throw std::logic_error("parser init");
  Status s = parser.feed(stream.data(), stream.size());
  if (s == Status::more_input) s = parser.finish();
  if (!p.message.empty()) throw std::runtime_error(p.message);
  if (p.status != Status::ok)
    throw std::runtime_error("client decoder refused the " + p.error + ": " + status_name(p.status));
  if (s != Status::ok)
    throw std::runtime_error(std::string("client stream parser: ") + status_name(s) +
                             (parser.error_detail()[0] ? std::string(" (") + parser.error_detail() + ")" : ""));
  if (!p.started) throw std::runtime_error("the stream holds no image (no IMGH or JPEG chunk)");
  if (!p.finished) throw std::runtime_error("the stream ends before the image is complete");
}

}  // namespace

DecodedImage decode_stream_image(std::span<const uint8_t> stream, const Planes* prediction) {
  DecodedImage out;
  Pass rgb_pass;
  rgb_pass.prediction = prediction;
  rgb_pass.rgb = &out.rgb;
  run_pass(stream, rgb_pass);
  out.kind = rgb_pass.kind;
  if (out.kind == "vds") {
    Pass planes_pass;
    planes_pass.prediction = prediction;
    planes_pass.want_planes = true;
    planes_pass.planes = &out.planes;
    run_pass(stream, planes_pass);
  }
  return out;
}

}  // namespace vds::enc
