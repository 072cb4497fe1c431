// The player: stream parser, mode selection by the header's mode, frame
// bookkeeping (CRC of what is displayed, instruction counts by stage) for
// every mode (vds/player.h has the contract).
#include "vds/player.h"

#include "vds/crc32c.h"

namespace vds {

namespace detail {
extern const PlayerMode kImagesMode;
extern const PlayerMode kModelMode;
extern const PlayerMode kWalkMode;
extern const PlayerMode kTerrainMode;

bool render_band_to_player(void* player, const Band& b) {
  return static_cast<Player*>(player)->band(PixelRect{0, b.y, b.width, b.height, b.pixels, static_cast<ptrdiff_t>(b.stride)});
}

RenderConfig band_render_config(const StreamHeader& h, const PlayerConfig& c, uint32_t vertex_cache,
                                uint32_t triangle_cache) {
  RenderConfig rc;
  rc.width = h.width;
  rc.height = h.height;
  rc.band_height = static_cast<uint16_t>(c.band_rows < h.height ? c.band_rows : h.height);
  rc.format = c.format;
  rc.depth = DepthFormat::d16;
  rc.vertex_cache = vertex_cache;
  rc.triangle_cache = triangle_cache;
  return rc;
}

bool header_has_camera_and_frames(Player& p, const StreamHeader& h, const char* what) {
  if (h.focal_x_q16 != 0 && h.near_q16 != 0 && h.frame_count != 0) return true;
  p.fail(Status::malformed, what);
  return false;
}

size_t chunk_per_frame_feed_limit(uint32_t frames_room) {
  constexpr size_t kMinChunk = kChunkHeadBytes + kChunkTailBytes;
  return frames_room == 0 ? 0 : kMinChunk * (frames_room - 1) + 1;
}

}  // namespace detail

namespace {

// The modes this build plays, by the stream header's mode.
const detail::PlayerMode* const kModes[] = {&detail::kImagesMode, &detail::kModelMode, &detail::kWalkMode,
                                                  &detail::kTerrainMode};

const detail::PlayerMode* find_mode(StreamMode m) {
  for (const detail::PlayerMode* mode : kModes)
    if (mode->mode == m) return mode;
  return nullptr;
}

}  // namespace

Status Player::init(Arena& arena, const PlayerConfig& config, const PlayerCallbacks& callbacks) {
  if (config.band_rows < 16 || config.band_rows > 256 || config.band_rows % 16 != 0 || config.max_chunk_bytes == 0 ||
      (config.format != PixelFormat::rgb565 && config.format != PixelFormat::rgb888))
    return Status::invalid_argument;
  arena_ = &arena;
  config_ = config;
  cb_ = callbacks;
  mode_ = nullptr;
  plan_ = PlayerPlan{};
  full_ = false;
  error_detail_ = nullptr;
  mode_status_ = Status::ok;
  stages_ = StageClock{};
  service_total_ = parse_total_ = decode_total_ = display_total_ = 0;
  feed_mark_ = 0;
  at_start_ = PlayedFrame{};
  frame_crc_ = 0;
  frames_ = 0;
  steered_ = false;
  timed_ = false;
  preroll_ms_ = 0;
  band_buffer = nullptr;
  image_ready = image_open = jpeg_ready = jpeg_open = jpeg_begun = false;
  level_mark = 0;
  model_frames = ModelFrames{};
  model_angle = model_turn = 0;
  model_started = false;
  walk = nullptr;
  terrain = nullptr;
  ChunkSink sink;
  sink.ctx = this;
  sink.on_header = on_header;
  sink.on_chunk = on_chunk;
  sink.model_prefix = true;  // a model larger than the workspace plays the levels that fit
  return parser_.init(arena, config.max_chunk_bytes, sink);
}

uint64_t Player::work_clock() const { return cb_.clock != nullptr ? cb_.clock(cb_.ctx) - service_total_ : 0; }

void Player::service() {
  if (cb_.service == nullptr) return;
  const uint64_t t0 = cb_.clock != nullptr ? cb_.clock(cb_.ctx) : 0;
  cb_.service(cb_.ctx);
  if (cb_.clock != nullptr) service_total_ += cb_.clock(cb_.ctx) - t0;
}

bool Player::on_header(void* ctx, const StreamHeader& h) {
  Player& p = *static_cast<Player*>(ctx);
  p.mode_ = find_mode(h.mode);
  if (p.mode_ == nullptr) {
    p.fail(Status::unsupported_feature, "this client plays image and model streams");
    return false;
  }
  p.plan_.needs = h.workspace_bytes;
  p.plan_.available = p.arena_->remaining();
  p.plan_.known = h.mode != StreamMode::model;  // a model's plan waits for its mesh header
  return p.mode_->start(p, h);
}

ChunkResult Player::on_chunk(void* ctx, uint32_t type, const uint8_t* payload, uint32_t size) {
  Player& p = *static_cast<Player*>(ctx);
  return p.mode_ != nullptr ? p.mode_->chunk(p, type, payload, size) : ChunkResult::abort;
}

uint64_t Player::enter_chunk() {
  const uint64_t t0 = work_clock();
  parse_total_ += t0 - feed_mark_;
  return t0;
}

void Player::leave_chunk() { feed_mark_ = work_clock(); }

void Player::restart_counts(uint64_t parse_from) {
  at_start_.parse = parse_from;
  at_start_.decode = decode_total_;
  at_start_.display = display_total_;
  at_start_.entropy = stages_.spent[StageClock::entropy];
  at_start_.transform = stages_.spent[StageClock::transform];
}

bool Player::begin_frame(bool stream_frame) {
  frame_crc_ = 0;
  if (stream_frame && timed_ && cb_.wait_until != nullptr) {
    const uint64_t w0 = cb_.clock != nullptr ? cb_.clock(cb_.ctx) : 0;
    cb_.wait_until(cb_.ctx, due_ms(frames_));
    if (cb_.clock != nullptr) service_total_ += cb_.clock(cb_.ctx) - w0;
  }
  const uint64_t t0 = work_clock();
  const bool go = cb_.begin_frame == nullptr || cb_.begin_frame(cb_.ctx, parser_.header().width, parser_.header().height);
  display_total_ += work_clock() - t0;
  return go;
}

bool Player::band(const PixelRect& r) {
  const uint64_t t0 = work_clock();
  for (uint16_t row = 0; row < r.h; ++row)
    frame_crc_ = crc32c_update(frame_crc_, r.pixels + row * r.stride,
                               static_cast<size_t>(r.w) * static_cast<size_t>(bytes_per_pixel(config_.format)));
  const bool go = cb_.band == nullptr || cb_.band(cb_.ctx, r);
  display_total_ += work_clock() - t0;
  service();
  return go;
}

bool Player::end_frame(bool stream_frame) {
  const uint64_t t0 = work_clock();
  const bool go = cb_.end_frame == nullptr || cb_.end_frame(cb_.ctx, frame_crc_);
  display_total_ += work_clock() - t0;
  if (!stream_frame) return go;
  PlayedFrame f;
  f.steered = steered_;
  f.index = frames_;
  f.crc = frame_crc_;
  f.parse = parse_total_ - at_start_.parse;
  f.decode = decode_total_ - at_start_.decode;
  f.display = display_total_ - at_start_.display;
  f.entropy = stages_.spent[StageClock::entropy] - at_start_.entropy;
  f.transform = stages_.spent[StageClock::transform] - at_start_.transform;
  ++frames_;
  if (cb_.frame_shown != nullptr) cb_.frame_shown(cb_.ctx, f);
  restart_counts(parse_total_);  // the next frame's counts start here
  return go;
}

Status Player::feed(const uint8_t* data, size_t n) {
  if (arena_ == nullptr) return Status::invalid_argument;
  if (full_ && parser_.status() == Status::more_input) return Status::ok;
  feed_mark_ = work_clock();
  Status s = parser_.feed(data, n);
  parse_total_ += work_clock() - feed_mark_;
  // A model whose workspace holds no more levels: the rest is not needed.
  if (s == Status::more_input && full_) s = Status::ok;
  // A mode that refused says why better than the parser's "aborted".
  if (s == Status::aborted && is_error(mode_status_)) s = mode_status_;
  return s;
}

Status Player::finish() {
  if (full_ && parser_.status() == Status::more_input) return Status::ok;
  return parser_.finish();
}

bool Player::view_input() {
  if (mode_ == nullptr || mode_->view_input == nullptr || cb_.steer == nullptr || is_error(mode_status_) ||
      is_error(parser_.status()))
    return false;
  // A viewer's frame counts in no frame of the stream.
  const uint64_t parse0 = parse_total_, decode0 = decode_total_, display0 = display_total_;
  const uint64_t entropy0 = stages_.spent[StageClock::entropy], transform0 = stages_.spent[StageClock::transform];
  const bool drew = mode_->view_input(*this);
  at_start_.parse += parse_total_ - parse0;
  at_start_.decode += decode_total_ - decode0;
  at_start_.display += display_total_ - display0;
  at_start_.entropy += stages_.spent[StageClock::entropy] - entropy0;
  at_start_.transform += stages_.spent[StageClock::transform] - transform0;
  return drew;
}

size_t Player::feed_limit(uint32_t frames_room) const {
  if (mode_ == nullptr || mode_->feed_limit == nullptr) return SIZE_MAX;
  return mode_->feed_limit(*this, frames_room);
}

}  // namespace vds
