// Player mode "images": each image is one frame, a vds image (IMGH + IMGD
// chunks, vds/image.h) or a baseline JPEG (JPEG chunks, vds/jpeg.h),
// decoded by MCU rows straight into the band buffer and shown band by band.
// Each decoder is carved from the workspace when the first image of its
// kind arrives.
#include "vds/player.h"

namespace vds {

namespace {

size_t band_bytes(uint16_t width, const PlayerConfig& config) {
  // The alignment slack included, as Arena::alloc_array carves it.
  return static_cast<size_t>(width) * config.band_rows * static_cast<size_t>(bytes_per_pixel(config.format)) + 16u;
}

}  // namespace

size_t Player::image_workspace_bytes(uint16_t width, const PlayerConfig& config) {
  return ImageDecoder::kWorkspaceBytes + band_bytes(width, config);
}

size_t Player::jpeg_workspace_bytes(uint16_t width, const PlayerConfig& config) {
  return JpegDecoder::kWorkspaceBytes + band_bytes(width, config);
}

namespace {

bool image_band(void* ctx, const PixelRect& r) { return static_cast<Player*>(ctx)->band(r); }

bool start(Player& p, const StreamHeader& h) {
  p.image_ready = p.jpeg_ready = p.jpeg_open = false;
  const size_t bytes = band_bytes(h.width, p.config()) - 16u;
  uint8_t* band = static_cast<uint8_t*>(p.arena().alloc(bytes, alignof(uint16_t)));
  if (band == nullptr) {
    p.fail(Status::workspace_too_small, "the band buffer does not fit the workspace");
    return false;
  }
  p.band_buffer = band;
  if (p.counting()) {
    p.stages() = StageClock{};
    p.stages().now = [](void* ctx) { return static_cast<Player*>(ctx)->work_clock(); };
    p.stages().ctx = &p;
  }
  return true;
}

ImageTarget band_target(Player& p) {
  ImageTarget t = ImageTarget::bands(p.config().format, p.band_buffer,
                                     static_cast<ptrdiff_t>(p.header().width) * bytes_per_pixel(p.config().format),
                                     image_band, &p);
  t.predict = p.callbacks().predict;
  t.predict_ctx = p.callbacks().ctx;
  return t;
}

// A vds image's chunk. false: refused (p.fail has said why).
bool vds_chunk(Player& p, uint32_t type, const uint8_t* payload, uint32_t size, Status* s) {
  if (p.jpeg_open) {
    p.fail(Status::malformed, "a vds image chunk inside a JPEG image");
    return false;
  }
  if (type == chunk::kImageHeader && p.image_open) {
    p.fail(Status::malformed, "an image header inside an image");
    return false;
  }
  if (!p.image_ready) {
    if (p.image.init(p.arena()) != Status::ok) {
      p.fail(Status::workspace_too_small, "the image decoder does not fit the workspace");
      return false;
    }
    if (p.counting() && p.config().decode_stages) p.image.set_stage_clock(&p.stages());
    p.image_ready = true;
  }
  *s = p.image.on_chunk(type, payload, size, band_target(p));
  if (is_error(*s)) {
    p.fail(*s, "the image decoder refused a chunk");
    return false;
  }
  p.image_open = *s == Status::more_input;
  if (type == chunk::kImageHeader &&
      (p.image.header().width != p.header().width || p.image.header().height != p.header().height)) {
    // The header chunk only sets the decoder up; the band buffer and the
    // display are the stream's frame size, so an image of another size is
    // refused before a pixel of it is decoded.
    p.fail(Status::malformed, "an image's size differs from the stream's frame size");
    return false;
  }
  return true;
}

bool same_size_as_stream(Player& p, const JpegInfo& i) {
  if (i.width == p.header().width && i.height == p.header().height) return true;
  p.fail(Status::malformed, "an image's size differs from the stream's frame size");
  return false;
}

// A JPEG's frame opens at its first band: its frame header may lie in any
// of its chunks, and the size it declares is checked before a band is shown.
bool jpeg_band(void* ctx, const PixelRect& r) {
  Player& p = *static_cast<Player*>(ctx);
  if (!p.jpeg_begun) {
    if (!same_size_as_stream(p, p.jpeg.info()) || !p.begin_frame()) return false;
    p.jpeg_begun = true;
  }
  return p.band(r);
}

// The first chunk of a JPEG opens the image. false: refused (p.fail has
// said why).
bool open_jpeg(Player& p) {
  if (p.image_open) {
    p.fail(Status::malformed, "a JPEG chunk inside a vds image");
    return false;
  }
  if (!p.jpeg_ready) {
    if (p.jpeg.init(p.arena()) != Status::ok) {
      p.fail(Status::workspace_too_small, "the JPEG decoder does not fit the workspace");
      return false;
    }
    p.jpeg_ready = true;
  }
  ImageTarget t = band_target(p);
  t.emit = jpeg_band;
  const Status st = p.jpeg.start(t);
  if (st != Status::ok) {
    p.fail(st, "the JPEG decoder refused the band target");
    return false;
  }
  p.jpeg_open = true;
  p.jpeg_begun = false;
  return true;
}

ChunkResult on_chunk(Player& p, uint32_t type, const uint8_t* payload, uint32_t size) {
  const bool is_vds = type == chunk::kImageHeader || type == chunk::kImageData;
  if (!is_vds && type != chunk::kJpeg) return ChunkResult::unknown;
  const uint64_t parse_before = p.parse_total();
  const uint64_t t0 = p.enter_chunk();
  const uint64_t display_before = p.display_total();
  Status s = Status::more_input;
  bool ok = true;
  bool go = true;
  if (is_vds) {
    ok = vds_chunk(p, type, payload, size, &s);
    // An image's counts start at its header chunk, whose CRC the parser
    // checked before the call; the header chunk decodes no pixel.
    if (ok && type == chunk::kImageHeader) {
      p.restart_counts(parse_before);
      go = p.begin_frame();
    }
  } else {
    if (!p.jpeg_open) {
      ok = open_jpeg(p);
      // An image's counts start at its first chunk.
      if (ok) p.restart_counts(parse_before);
    }
    if (ok) {
      s = p.jpeg.feed(payload, size);
      if (is_error(s)) {
        // A larger image than the band buffer is refused by the decoder at
        // its frame header; a callback's false is the caller's abort or a
        // refusal already said.
        // (the decoder has read the frame header when it refuses the target)
        const bool wrong_size =
            (p.jpeg.have_info() || s == Status::invalid_argument) && !same_size_as_stream(p, p.jpeg.info());
        if (!wrong_size && s != Status::aborted)
          p.fail(s, p.jpeg.error_detail()[0] != 0 ? p.jpeg.error_detail() : "the JPEG decoder refused a chunk");
        ok = false;
      } else if (s == Status::ok) {
        p.jpeg_open = false;
        // A JPEG with no scan shows no band: its frame is refused.
        if (!p.jpeg_begun) {
          p.fail(Status::malformed, "a JPEG image without pixels");
          ok = false;
        }
      }
    }
  }
  p.add_decode((p.work_clock() - t0) - (p.display_total() - display_before));
  ChunkResult result = ok && go ? ChunkResult::consumed : ChunkResult::abort;
  if (result == ChunkResult::consumed && s == Status::ok && !p.end_frame()) result = ChunkResult::abort;
  p.leave_chunk();
  return result;
}

}  // namespace

namespace detail {
extern const PlayerMode kImagesMode;
const PlayerMode kImagesMode{StreamMode::images, start, on_chunk, nullptr};
}  // namespace detail

}  // namespace vds
