// vds encoder (host tools): the client's images, decoded as a device would.
// decode_stream_image plays a stream through vds::Player (the one path from
// stream bytes to display) with RGB888 bands; decode_image_planes runs the
// image decoder alone on an encoded image's chunks, for the Y'CbCr
// reconstruction the encoder must match.
#include <algorithm>
#include <cstring>
#include <exception>
#include <stdexcept>
#include <string>

#include "vds/bytes.h"
#include "vds/enc/image_codec.h"
#include "vds/player.h"

namespace vds::enc {

namespace {

// Fills the prediction of a rectangle from the destination's prior planes.
bool predict_from_planes(void* ctx, uint16_t x, uint16_t y, uint16_t w, uint16_t h, uint8_t* yo, ptrdiff_t ys,
                         uint8_t* cbo, uint8_t* cro, ptrdiff_t cs) {
  const Planes& p = *static_cast<const Planes*>(ctx);
  if (x + w > p.width || y + h > p.height) return false;
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

// What a stream's HEAD declares, if the stream starts with a valid one
// (else zeros): the band buffer and the chunk buffer are sized from it.
StreamHeader declared_header(std::span<const uint8_t> s) {
  StreamHeader h{};
  if (s.size() < kPreambleBytes + kChunkHeadBytes || std::memcmp(s.data(), kStreamMagic, sizeof kStreamMagic) != 0)
    return h;
  const uint8_t* chunk = s.data() + kPreambleBytes;
  const uint32_t size = load_le32(chunk + 4);
  if (load_le32(chunk) != chunk::kHeader || size > kHeaderPayloadMax || s.size() < kPreambleBytes + kChunkHeadBytes + size)
    return h;
  if (header_from_bytes(chunk + kChunkHeadBytes, size, s[4], s[5], &h) != Status::ok) return StreamHeader{};
  return h;
}

// The largest chunk the host replay takes: a stream declaring more is refused
// at its header ("workspace too small").
constexpr uint32_t kReplayChunkMax = 1u << 24;

// One replay of the client: the first image of a stream, to RGB888 rows.
// No exception may cross the client library's frames (built without
// exception support): the sink's is kept and thrown after the play.
struct Replay {
  const Player* player = nullptr;
  const Planes* prior = nullptr;  // the destination's prior content (null: black)
  ImageRowSink* sink = nullptr;
  std::string* kind = nullptr;
  std::string message;  // a host-side problem, reported as it is
  std::exception_ptr error;
  bool began = false, shown = false;
};

const char* chroma_name(ChromaFormat c) {
  return c == ChromaFormat::yuv420 ? "4:2:0" : c == ChromaFormat::yuv444 ? "4:4:4" : "grey";
}

bool begin_frame(void* ctx, uint16_t w, uint16_t h) {
  Replay& r = *static_cast<Replay*>(ctx);
  if (r.shown) return true;  // a later image: played, not kept
  const bool jpeg = r.player->jpeg_open;
  if (r.prior != nullptr && !jpeg) {
    const ImageHeader& ih = r.player->image.header();
    if (r.prior->width != w || r.prior->height != h || r.prior->chroma != ih.chroma) {
      r.message = "the prediction does not match the image (" + std::to_string(w) + "x" + std::to_string(h) + ", " +
                  chroma_name(ih.chroma) + ")";
      return false;
    }
  }
  *r.kind = jpeg ? "jpeg" : "vds";
  r.began = true;
  try {
    r.sink->begin(w, h);
  } catch (...) {
    r.error = std::current_exception();
    return false;
  }
  return true;
}

bool band(void* ctx, const PixelRect& b) {
  Replay& r = *static_cast<Replay*>(ctx);
  if (r.shown) return true;
  try {
    r.sink->rows(b.y, b.h, b.pixels, b.stride);
  } catch (...) {
    r.error = std::current_exception();
    return false;
  }
  return true;
}

// Only the first image is kept; the stream is played to its end, which
// must be there.
bool end_frame(void* ctx, uint32_t) {
  static_cast<Replay*>(ctx)->shown = true;
  return true;
}

// The prior content of a rectangle: the prediction's, or black (Y' 0,
// Cb = Cr = 128) without one.
bool predict(void* ctx, uint16_t x, uint16_t y, uint16_t w, uint16_t h, uint8_t* yo, ptrdiff_t ys, uint8_t* cbo,
             uint8_t* cro, ptrdiff_t cs) {
  const Replay& r = *static_cast<const Replay*>(ctx);
  if (r.prior != nullptr && !r.shown) return predict_from_planes(const_cast<Planes*>(r.prior), x, y, w, h, yo, ys, cbo, cro, cs);
  const ImageHeader& ih = r.player->image.header();
  const int s = ih.chroma == ChromaFormat::yuv420 ? 1 : 0;
  for (int row = 0; row < h; ++row) std::memset(yo + row * ys, 0, w);
  if (cbo != nullptr) {
    const int cw = ((x + w + s) >> s) - (x >> s), ch = ((y + h + s) >> s) - (y >> s);
    for (int row = 0; row < ch; ++row) {
      std::memset(cbo + row * cs, 128, cw);
      std::memset(cro + row * cs, 128, cw);
    }
  }
  return true;
}

}  // namespace

std::string play_stream_image(std::span<const uint8_t> stream, const Planes* prediction, ImageRowSink& sink) {
  std::string kind;
  // The chunk buffer the stream declares (so that a stream cut short is
  // "truncated", not "too large"), up to the host's limit.
  const StreamHeader declared = declared_header(stream);
  PlayerConfig config;
  config.format = PixelFormat::rgb888;
  config.max_chunk_bytes = std::clamp<uint32_t>(declared.max_chunk_payload, kHeaderPayloadMax, kReplayChunkMax);
  const uint16_t width = declared.width;
  std::vector<uint8_t> ws(config.max_chunk_bytes +
                          std::max(Player::image_workspace_bytes(width, config), Player::jpeg_workspace_bytes(width, config)) + 64);
  Arena arena(ws.data(), ws.size());
  Player player;
  Replay r;
  r.player = &player;
  r.prior = prediction;
  r.sink = &sink;
  r.kind = &kind;
  PlayerCallbacks cb;
  cb.ctx = &r;
  cb.begin_frame = begin_frame;
  cb.band = band;
  cb.end_frame = end_frame;
  cb.predict = predict;
  if (player.init(arena, config, cb) != Status::ok) throw std::logic_error("player init");
  Status s = player.feed(stream.data(), stream.size());
  if (s == Status::more_input) s = player.finish();
  if (r.error) std::rethrow_exception(r.error);
  if (!r.message.empty()) throw std::runtime_error(r.message);
  if (s == Status::ok && r.shown) return kind;
  if (is_error(s)) {
    const std::string detail = player.error_detail() != nullptr && player.error_detail()[0] ? player.error_detail() : "";
    throw std::runtime_error(std::string("the client refused the stream: ") + status_name(s) +
                             (detail.empty() ? "" : " (" + detail + ")") + " at byte " +
                             std::to_string(player.error_offset()));
  }
  if (!r.began) throw std::runtime_error("the stream holds no image (no IMGH or JPEG chunk)");
  throw std::runtime_error("the stream ends before the image is complete");
}

DecodedImage decode_stream_image(std::span<const uint8_t> stream, const Planes* prediction) {
  struct ToImage : ImageRowSink {
    Image* img;
    void begin(int w, int h) override { *img = Image(w, h, 3); }
    void rows(int y, int count, const uint8_t* pixels, ptrdiff_t stride) override {
      for (int row = 0; row < count; ++row)
        std::memcpy(img->row(y + row), pixels + row * stride, static_cast<size_t>(img->width) * 3);
    }
  };
  DecodedImage out;
  ToImage sink;
  sink.img = &out.rgb;
  out.kind = play_stream_image(stream, prediction, sink);
  return out;
}

Planes decode_image_planes(const EncodedImage& e, const Planes* prediction) {
  const ImageHeader& h = e.header;
  Planes out = prediction != nullptr ? *prediction : Planes(h.width, h.height, h.chroma);
  if (out.width != h.width || out.height != h.height || out.chroma != h.chroma)
    throw std::runtime_error(std::string("the prediction does not match the image (") + std::to_string(h.width) + "x" +
                             std::to_string(h.height) + ", " + chroma_name(h.chroma) + ")");
  std::vector<uint8_t> ws(ImageDecoder::kWorkspaceBytes);
  Arena arena(ws.data(), ws.size());
  ImageDecoder dec;
  if (dec.init(arena) != Status::ok) throw std::logic_error("image decoder init");
  const bool colour = h.components() == 3;
  const ImageTarget t = ImageTarget::planes(out.plane[0].data(), out.plane_width(0), colour ? out.plane[1].data() : nullptr,
                                            out.plane_width(1), colour ? out.plane[2].data() : nullptr, out.plane_width(2));
  Status s = dec.start(e.imgh.data(), static_cast<uint32_t>(e.imgh.size()), t);
  if (s == Status::ok) s = Status::more_input;
  for (size_t i = 0; i < e.imgd.size() && s == Status::more_input; ++i)
    s = dec.feed(e.imgd[i].data(), static_cast<uint32_t>(e.imgd[i].size()));
  if (s != Status::ok)
    throw std::runtime_error(std::string("the client image decoder: ") +
                             (s == Status::more_input ? "the image is incomplete" : status_name(s)));
  return out;
}

}  // namespace vds::enc
