// vds::Player: the client's one path from stream bytes to display bands.
// The firmware, the host replay (`vds frames`, `vds decode-image`), the
// benchmarks and the tests all drive it with the same configuration.
//
// CONTRACT
// - init(arena, config, callbacks) carves the stream parser (its chunk
//   buffer, config.max_chunk_bytes) from the arena. Everything a stream
//   needs later is carved from what the arena has left, when the stream's
//   header (and, for a model, its mesh header) says how much: the plan
//   (plan()) is known before any payload is decoded. To play another
//   stream, rewind the arena to where it was and call init again.
// - feed(bytes, n) takes any piece size (one byte at a time included). It
//   returns more_input while the stream goes on; ok once the stream's END
//   is read, or as soon as a model client knows its workspace holds no
//   more levels (workspace_full(): the rest of the stream is not needed);
//   otherwise the first error, latched (error_offset(), error_detail()).
// - Every displayed frame is: begin_frame(width, height), then band() for
//   each band top to bottom (at most config.band_rows rows: a model's are
//   band_rows high but the last, an image's one MCU row: 16 rows of 4:2:0,
//   8 of 4:4:4 or grey, a JPEG's 8 or 16), full width, in config.format:
//   RGB565 little-endian (bit 15..11 red, 10..5 green, 4..0 blue; the
//   boards) or RGB888 (bytes R, G, B; host tools writing image files; image
//   streams only), never outside the frame, then end_frame(crc) and
//   frame_shown(record). The record's CRC-32C covers the frame's rows as
//   displayed, top to bottom; its instruction counts come from the clock
//   callback (0 without one; any monotonic counter works, nanoseconds
//   too): parse (chunk framing and CRCs), decode (entropy decoding +
//   inverse transform + colour, or mesh decoding), display (bands,
//   end_frame and, for a model, the drawing), with the image decoder's
//   entropy and transform split out.
// - Image streams: each image is a frame, a vds image (IMGH + IMGD) or a
//   baseline JPEG (JPEG chunks, vds/jpeg.h). predict(), when given, is the
//   destination's prior content (a host with a frame store): residual
//   images add to it and a region image's uncoded MCUs show it. Without it
//   a residual image is refused (invalid_argument) and a region image's
//   uncoded MCUs keep what the band buffer held.
// - Model streams: level() after the base (level 0) and after every level,
//   with the mesh decoding spent on it; the mesh is `mesh.mesh()`.
// - A callback returning false aborts: feed returns Status::aborted. An
//   image whose size is not the stream's frame size is malformed, refused
//   before any of its pixels is decoded.
// - service() is called after every band and every
//   config.mesh_service_items mesh items, to keep I/O moving while a frame
//   is decoded or drawn; its time counts in no stage. It must not call the
//   player.
// - notice() tells the caller what the player decided about a model that
//   does not fit (vertices held of the stream's, the level after which the
//   workspace is full, the bytes a base mesh needs); the caller words it.
// - send_up() is the back-channel for what the client sends upstream
//   (poses, reports); modes that talk back use it.
// - steer(), when given, reads the viewer's controls once a frame (a
//   terrain stream, after the frame is drawn): true when they move the
//   viewer. The terrain mode then steers a pose of its own from the one
//   just drawn and sends it up as a steered pose every frame they move it
//   (else every pose period); the frames it draws still come from the
//   stream alone (the server draws the steered pose it received).
//   A model stream reads them in view_input(): the viewer turns the model.
// Bit-exact: the same stream and configuration give the same bands on
// every platform. No heap, no float, no exceptions.
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/arena.h"
#include "vds/container.h"
#include "vds/image.h"
#include "vds/jpeg.h"
#include "vds/mesh.h"
#include "vds/model_view.h"
#include "vds/render.h"
#include "vds/status.h"
#include "vds/terrain_client.h"
#include "vds/walk.h"
#include "vds/walk_geometry.h"

namespace vds {

struct PlayerConfig {
  // Rows per display band: a multiple of 16 (one 4:2:0 MCU row), 16..256.
  // The band buffer costs width x band_rows x 2 bytes.
  uint16_t band_rows = 16;
  // Largest chunk payload accepted: the parser's buffer, carved at init.
  uint32_t max_chunk_bytes = 4096;
  // Model streams: service() every this many mesh items (0: never).
  uint32_t mesh_service_items = 64;
  // Band pixels: rgb565 (the boards) or rgb888 (image streams only).
  PixelFormat format = PixelFormat::rgb565;
  // With a clock: count a vds image's entropy decoding and inverse
  // transform apart (PlayedFrame::entropy, transform). It reads the clock
  // twice per block, about 2 instructions per pixel on a Cortex-M4; false
  // counts decoding as one stage.
  bool decode_stages = true;
};

// What the client boards use. The host replay of a client uses it too, with
// max_chunk_bytes sized to the stream (the chunk buffer changes no pixel).
constexpr PlayerConfig kClientPlayerConfig{};

// One displayed frame.
struct PlayedFrame {
  uint32_t index = 0;  // 0, 1, 2, ... in display order
  uint32_t crc = 0;    // CRC-32C of its RGB565 rows, top to bottom
  uint64_t parse = 0, decode = 0, display = 0;
  uint64_t entropy = 0, transform = 0;  // of decode (images)
  // Drawn as the viewer turned it (a model: Player::view_input), not as
  // the stream alone draws it: a replay of the stream does not show it.
  bool steered = false;
};

// A model's level, complete (level 0: the base mesh).
struct PlayedLevel {
  uint32_t level = 0;
  uint32_t vertices = 0, triangles = 0;
  uint64_t decode = 0;  // mesh decoding since the previous level (clock units)
};

// What a notice reports; the values a, b, c are listed per kind.
enum class PlayerNotice : uint8_t {
  model_partial = 1,       // the workspace holds a (vertices) of the model's b: later levels are skipped
  model_full = 2,          // the workspace is full after level a of b (c vertices): the rest is not needed
  model_base_too_big = 3,  // the base mesh needs a bytes of workspace, b are left: the stream is refused
  model_colors_level = 4,  // the workspace holds mesh colors down to MIP level a (of b levels, 0 the finest): finer ones are skipped
  model_no_colors = 5,     // the model's colours cannot be shown (a: 1 the mesh is not whole, 2 no room): drawn shaded
};

struct PlayerCallbacks {
  void* ctx = nullptr;
  bool (*begin_frame)(void* ctx, uint16_t width, uint16_t height) = nullptr;
  bool (*band)(void* ctx, const PixelRect& rows) = nullptr;
  bool (*end_frame)(void* ctx, uint32_t crc) = nullptr;
  void (*frame_shown)(void* ctx, const PlayedFrame& frame) = nullptr;
  void (*service)(void* ctx) = nullptr;
  uint64_t (*clock)(void* ctx) = nullptr;
  // A timed stream (Player::timed()): called before each frame is drawn
  // with the time it is due, in milliseconds after the stream's first byte;
  // the client returns at that time (serving its link meanwhile) or at
  // once if it is past. Its time is not counted in the frame's stages.
  void (*wait_until)(void* ctx, uint64_t due_ms) = nullptr;
  void (*notice)(void* ctx, PlayerNotice what, uint32_t a, uint32_t b, uint32_t c) = nullptr;
  bool (*send_up)(void* ctx, uint8_t kind, const uint8_t* data, size_t n) = nullptr;
  bool (*steer)(void* ctx, terrain::SteerInput* in) = nullptr;
  void (*level)(void* ctx, const PlayedLevel& level) = nullptr;
  PredictFn predict = nullptr;  // called with ctx
};

// The workspace plan of the stream being played.
struct PlayerPlan {
  bool known = false;        // the header (and a model's mesh header) has been read
  size_t needs = 0;          // bytes the whole stream needs beyond the parser
  size_t available = 0;      // bytes the arena had left for it
  uint32_t vertices = 0;     // model: vertices the workspace holds ...
  uint32_t of_vertices = 0;  // ... of the stream's
  uint32_t triangles = 0;    // model: the most triangles it holds with them
  size_t bytes = 0;          // model: what the mesh decoder and the view carve for that (or a base needs)
};

class Player;

namespace detail {
// One mode of play (decoder/src/player/): what the stream header's mode
// selects. A new mode is a new file defining one of these and a line in
// the mode table (player.cpp).
struct PlayerMode {
  StreamMode mode;
  // At HEAD: set up what the mode needs from the arena. false refuses.
  bool (*start)(Player& p, const StreamHeader& h);
  // Every verified chunk after HEAD.
  ChunkResult (*chunk)(Player& p, uint32_t type, const uint8_t* payload, uint32_t size);
  // Most stream bytes to feed at once when `frames_room` more frames may
  // complete (0: no limit of the mode's own).
  size_t (*feed_limit)(const Player& p, uint32_t frames_room);
  // Player::view_input() (nullptr: the mode has no viewer's frames).
  bool (*view_input)(Player& p) = nullptr;
};
// The feed limit of a mode that may complete a frame at any chunk: no
// more bytes than can finish as many chunks (12 bytes of framing at least)
// as frames may still complete.
size_t chunk_per_frame_feed_limit(uint32_t frames_room);
// The renderer's band sink for a mode drawing a frame: hands the band to
// the player (ctx) as one of the frame's bands.
bool render_band_to_player(void* player, const Band& band);
// The renderer's configuration for a mode drawing whole frames into the
// player's bands: the frame's size, band_rows-high bands, 16-bit depth, and
// the caches given.
RenderConfig band_render_config(const StreamHeader& h, const PlayerConfig& c, uint32_t vertex_cache,
                                uint32_t triangle_cache);
// A mode that draws with a camera along a known number of frames: false
// (with `what` in the error) when the header has no camera or no frame count.
bool header_has_camera_and_frames(Player& p, const StreamHeader& h, const char* what);
}  // namespace detail

class Player {
 public:
  // Workspace an image stream of frames `width` pixels wide needs beyond the
  // parser: the image decoder and the band buffer (what its HEAD declares);
  // a stream of JPEG images, the JPEG decoder and the band buffer.
  static size_t image_workspace_bytes(uint16_t width, const PlayerConfig& config);
  static size_t jpeg_workspace_bytes(uint16_t width, const PlayerConfig& config);
  // Workspace a walkthrough needs beyond the parser for its frame size and
  // parameters (what its HEAD declares).
  static size_t walk_workspace_bytes(const StreamHeader& h, const WalkParams& w, const PlayerConfig& config);
  // Workspace a terrain stream needs beyond the parser (what its HEAD and
  // TERH declare).
  static size_t terrain_workspace_bytes(const StreamHeader& h, const terrain::Params& t, const PlayerConfig& config);
  // Workspace a model's mesh colors need beyond its mesh and view (MCLH's
  // counts) to show a level of `samples` samples.
  static size_t model_colors_workspace_bytes(uint32_t faces, uint32_t vertices, uint32_t samples);
  // A model's colours as the player draws them (nullptr: none, drawn
  // shaded), and what they are: -1 none, kModelVertexColours the colours
  // that came with the vertices (MCVX), else the mesh colors level shown.
  static constexpr int kModelVertexColours = 16;
  const MeshColorsSurface* model_colors() const;
  int model_colors_level() const;

  Status init(Arena& arena, const PlayerConfig& config, const PlayerCallbacks& callbacks);
  Status feed(const uint8_t* data, size_t n);
  // The caller has no more bytes: ok if the stream ended (or was full).
  Status finish();

  // The viewer's own frames, between the stream's: reads the controls
  // (callbacks.steer) and, for a model whose base mesh is in, turns it
  // round its up axis by their turn (the live window's mouse drag and
  // Left/Right keys). When they turn it, draws the model as held from the
  // new angle: shown (begin_frame, bands, end_frame) but not a frame of the
  // stream (no frame_shown, no index, no frame_crc record). From then on
  // the stream's frames are drawn turned the same and reported with
  // PlayedFrame::steered. true when it drew a frame; false for other
  // modes, before the base mesh, without a steer callback or an error, and
  // while the model holds what the stream has not shown yet (a level
  // whose colours follow, a colour level half decoded): the stream's next
  // frame shows the turn then. The client calls it while it waits for
  // stream bytes (every 50 ms on the boards).
  bool view_input();

  // The most bytes feed() should take next so that no more than
  // `frames_room` frames complete (a caller with a bounded queue of frame
  // records); SIZE_MAX when the mode puts no limit.
  size_t feed_limit(uint32_t frames_room) const;

  // Walkthrough: a view slot as the client holds it (nullptr before WLKP or
  // for a slot the stream does not have); between a WVUP and its image,
  // whether the slot holds the view's prediction (the image may then be a
  // residual against it). For encoders mirroring the client.
  const Texture* walk_view(uint8_t slot) const;
  bool walk_view_predicted() const;
  // Terrain: the client's block store (nullptr before TERH). For servers
  // checking their mirror.
  const terrain::BlockStore* terrain_store() const;

  bool have_header() const { return parser_.have_header(); }
  const StreamHeader& header() const { return parser_.header(); }
  const PlayerPlan& plan() const { return plan_; }
  bool workspace_full() const { return full_; }
  uint32_t frames_shown() const { return frames_; }
  // Whether the stream states a schedule (a walkthrough's WLKP): frame i is
  // due preroll_ms() + i frame periods after its first byte.
  bool timed() const { return timed_; }
  uint32_t preroll_ms() const { return preroll_ms_; }
  uint64_t due_ms(uint32_t frame) const {
    return preroll_ms_ + static_cast<uint64_t>(frame) * parser_.header().frame_period_us / 1000;
  }
  uint64_t error_offset() const { return parser_.error_offset(); }
  const char* error_detail() const { return error_detail_ != nullptr ? error_detail_ : parser_.error_detail(); }
  uint32_t chunks() const { return parser_.chunks(); }
  uint64_t bytes_consumed() const { return parser_.bytes_consumed(); }

  // --- For the modes (decoder/src/player/) ---------------------------------
  Arena& arena() { return *arena_; }
  const PlayerConfig& config() const { return config_; }
  const PlayerCallbacks& callbacks() const { return cb_; }
  // The clock less the time in service(): what every stage count reads.
  uint64_t work_clock() const;
  // Chunk bookkeeping: a mode calls enter_chunk() first (parse time up to
  // here is counted) and leave_chunk() last. A frame's counts run from the
  // end of the previous frame unless the mode calls restart_counts() (an
  // image's counts start at its header chunk: `parse_from` is the parse
  // total to charge it from); begin_frame() opens a frame, band() shows one
  // band, end_frame() closes the frame and reports it.
  uint64_t enter_chunk();
  void leave_chunk();
  void restart_counts(uint64_t parse_from);
  // A viewer's frame (view_input): begin_frame(false) does not wait for a
  // timed stream's schedule, end_frame(false) reports nothing.
  bool begin_frame(bool stream_frame = true);
  bool band(const PixelRect& r);
  bool end_frame(bool stream_frame = true);
  // The stream's frames drawn from now on are the viewer's (view_input).
  void mark_steered() { steered_ = true; }
  void add_decode(uint64_t n) { decode_total_ += n; }
  void add_display(uint64_t n) { display_total_ += n; }
  uint64_t display_total() const { return display_total_; }
  uint64_t parse_total() const { return parse_total_; }
  void set_full() { full_ = true; }
  void set_plan(const PlayerPlan& p) { plan_ = p; }
  void set_schedule(uint32_t preroll_ms) {
    timed_ = true;
    preroll_ms_ = preroll_ms;
  }
  // A mode's own failure: feed() returns `s` (not the parser's "aborted").
  void fail(Status s, const char* detail) {
    mode_status_ = s;
    error_detail_ = detail;
  }
  void notice(PlayerNotice what, uint32_t a, uint32_t b, uint32_t c) const {
    if (cb_.notice != nullptr) cb_.notice(cb_.ctx, what, a, b, c);
  }
  void service();
  StageClock& stages() { return stages_; }
  bool counting() const { return cb_.clock != nullptr; }

  // Mode state. Only the mode the header selects is used.
  ImageDecoder image;
  JpegDecoder jpeg;
  bool image_ready = false, image_open = false, jpeg_ready = false, jpeg_open = false, jpeg_begun = false;
  uint8_t* band_buffer = nullptr;
  uint64_t level_mark = 0;  // mesh decoding since the last level
  MeshDecoder mesh;
  ModelView view;
  ModelFrames model_frames;
  uint16_t model_angle = 0;  // the stream's angle of the last frame drawn (2^-16 turn)
  uint16_t model_turn = 0;   // the viewer's turn added to it (view_input)
  bool model_started = false;
  struct ModelColors* colors = nullptr;  // decoder/src/player/mode_model.cpp
  struct VertexColours* vertex_colours = nullptr;  // the same
  WalkGeometry walk_geometry;
  WalkFrameDecoder walk_frames;
  struct WalkPlay* walk = nullptr;  // decoder/src/player/mode_walk.cpp
  struct TerrainPlay* terrain = nullptr;  // decoder/src/player/mode_terrain.cpp

 private:
  static bool on_header(void* ctx, const StreamHeader& h);
  static ChunkResult on_chunk(void* ctx, uint32_t type, const uint8_t* payload, uint32_t size);

  Arena* arena_ = nullptr;
  PlayerConfig config_{};
  PlayerCallbacks cb_{};
  StreamParser parser_;
  const detail::PlayerMode* mode_ = nullptr;
  PlayerPlan plan_{};
  bool full_ = false;
  const char* error_detail_ = nullptr;
  Status mode_status_ = Status::ok;
  StageClock stages_{};
  uint64_t service_total_ = 0;
  uint64_t parse_total_ = 0, decode_total_ = 0, display_total_ = 0;
  uint64_t feed_mark_ = 0;
  PlayedFrame at_start_{};  // the totals a frame's counts start from
  uint32_t frame_crc_ = 0;
  uint32_t frames_ = 0;
  bool steered_ = false;
  bool timed_ = false;
  uint32_t preroll_ms_ = 0;
};

}  // namespace vds
