// Player mode "images": each image (IMGH + IMGD chunks, vds/image.h) is one
// frame, decoded by MCU rows straight into the band buffer and shown band by
// band.
#include "vds/player.h"

namespace vds {

size_t Player::image_workspace_bytes(uint16_t width, const PlayerConfig& config) {
  // The band buffer's alignment slack included, as Arena::alloc_array carves it.
  return ImageDecoder::kWorkspaceBytes + static_cast<size_t>(width) * config.band_rows * 2u + 16u;
}

namespace {

bool image_band(void* ctx, const PixelRect& r) { return static_cast<Player*>(ctx)->band(r); }

bool start(Player& p, const StreamHeader& h) {
  // The parser has checked that the declared workspace fits what is left.
  if (p.image.init(p.arena()) != Status::ok) {
    p.fail(Status::workspace_too_small, "the image decoder does not fit the workspace");
    return false;
  }
  if (p.counting()) {
    p.stages() = StageClock{};
    p.stages().now = [](void* ctx) { return static_cast<Player*>(ctx)->work_clock(); };
    p.stages().ctx = &p;
    p.image.set_stage_clock(&p.stages());
  }
  uint16_t* band = p.arena().alloc_array<uint16_t>(static_cast<size_t>(h.width) * p.config().band_rows);
  if (band == nullptr) {
    p.fail(Status::workspace_too_small, "the band buffer does not fit the workspace");
    return false;
  }
  p.band_buffer = reinterpret_cast<uint8_t*>(band);
  return true;
}

ChunkResult on_chunk(Player& p, uint32_t type, const uint8_t* payload, uint32_t size) {
  if (type != chunk::kImageHeader && type != chunk::kImageData) return ChunkResult::unknown;
  const uint64_t parse_before = p.parse_total();
  const uint64_t t0 = p.enter_chunk();
  const uint64_t display_before = p.display_total();
  const ImageTarget target = ImageTarget::bands(PixelFormat::rgb565, p.band_buffer,
                                                static_cast<ptrdiff_t>(p.header().width) * 2, image_band, &p);
  const Status s = p.image.on_chunk(type, payload, size, target);
  bool ok = !is_error(s);
  if (!ok) {
    p.fail(s, "the image decoder refused a chunk");
  } else if (type == chunk::kImageHeader &&
             (p.image.header().width != p.header().width || p.image.header().height != p.header().height)) {
    // The header chunk only sets the decoder up; the band buffer and the
    // display are the stream's frame size, so an image of another size is
    // refused before a pixel of it is decoded.
    p.fail(Status::malformed, "an image's size differs from the stream's frame size");
    ok = false;
  }
  // An image's counts start at its header chunk, whose CRC the parser
  // checked before the call.
  if (ok && type == chunk::kImageHeader) p.restart_counts(parse_before);
  p.add_decode((p.work_clock() - t0) - (p.display_total() - display_before));
  ChunkResult result = ok ? ChunkResult::consumed : ChunkResult::abort;
  if (ok && type == chunk::kImageHeader && !p.begin_frame()) result = ChunkResult::abort;
  if (ok && type == chunk::kImageData && s == Status::ok && !p.end_frame()) result = ChunkResult::abort;
  p.leave_chunk();
  return result;
}

}  // namespace

namespace detail {
extern const PlayerMode kImagesMode;
const PlayerMode kImagesMode{StreamMode::images, start, on_chunk, nullptr};
}  // namespace detail

}  // namespace vds
