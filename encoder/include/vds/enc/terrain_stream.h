// The terrain stream (vds/terrain_client.h): what the server sends a
// client flying over a map, written ahead of time for a scripted flight
// over a modelled link (`vds encode-terrain`), or live, answering the poses
// the client sends up (`vds serve-terrain`). docs/terrain.md.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "vds/container.h"
#include "vds/enc/stream_writer.h"
#include "vds/enc/terrain_flight.h"
#include "vds/enc/terrain_server.h"
#include "vds/terrain_client.h"

namespace vds::enc {

struct TerrainStreamOptions {
  FlightLink link;
  int width = 240, height = 180;
  uint32_t store_units = 16384;  // the client's block store: 32 KiB
  int cache_log2 = 4;            // transformed blocks for a 16 x 16-cell window
  int max_cells = 64;            // cells drawn with their own texels a frame
  int key_spacing = 10;          // frames between the flight's keys
  int frame_budget = 2;          // the client's geometry a frame: 512 n vertices (2..64)
  int half_log2 = 6;             // the half-resolution window: 2^n cells a side (no larger than the map; 0: none)
  PoseOptions pose;
  uint32_t max_chunk = 4096;     // the client's chunk buffer
  std::function<void(size_t done)> progress;
};

struct TerrainChunk {
  uint32_t type = 0;
  std::vector<uint8_t> payload;
};

// What both the written and the live stream are made of: the header and
// parameters for a map and a flight, the flight as the client plays it,
// the elevation in pieces, and the server answering poses.
class TerrainSender {
 public:
  // Throws std::invalid_argument for a flight the client cannot play (more
  // keys than a TFLY holds, a pose outside the client's range).
  TerrainSender(const TerrainCoding& t, const CameraPath& path, const TerrainStreamOptions& o);
  const StreamHeader& header() const { return header_; }
  const terrain::Params& params() const { return params_; }
  uint32_t frames() const { return header_.frame_count; }
  // TERH, TFLY and the coarse elevation: what a client needs before its first frame.
  std::vector<TerrainChunk> opening() const;
  // The client's pose at frame f (the flight's keys interpolated as the
  // client does) and the camera the server sees it as (metres).
  WalkPose pose(uint32_t f) const { return terrain::flight_pose(keys_.data(), static_cast<uint32_t>(keys_.size()), spacing_, f); }
  SceneCamera camera(const WalkPose& p) const;
  CameraPose metres(const WalkPose& p) const;
  // The fine elevation's pieces (TELV), in order.
  bool elevation_left() const { return next_piece_ < pieces_.size(); }
  size_t next_elevation_bytes() const { return pieces_[next_piece_].payload.size(); }
  TerrainChunk take_elevation() { return pieces_[next_piece_++]; }
  // The update answering the newest pose (frame `pose_frame`) and, when
  // `previous` is given, where the viewer is predicted to be `ahead` pose
  // intervals later: a TTEX payload of at most `budget` bytes (empty when
  // nothing is to be sent).
  std::vector<uint8_t> answer(const WalkPose& pose, uint32_t pose_frame, const WalkPose* previous, double ahead,
                              size_t budget, UpdateStats* stats);
  const TerrainServer& server() const { return server_; }
  double hfov_deg() const { return hfov_; }

 private:
  const TerrainCoding& t_;
  TerrainStreamOptions o_;
  StreamHeader header_{};
  terrain::Params params_{};
  double units_ = 1, hfov_ = 70;
  uint32_t spacing_ = 1;
  std::vector<WalkPose> keys_;
  std::vector<TerrainChunk> pieces_;
  size_t next_piece_ = 0;
  TerrainServer server_;
};

// Chunk framing on the line (type, size, CRC).
inline constexpr size_t kChunkFraming = 12;

struct TerrainStreamFrame {
  size_t stream_bytes = 0;     // the stream's size once this frame's TFRM is written
  size_t elevation_bytes = 0;  // fine elevation sent with this frame
  size_t texture_bytes = 0;    // the update sent with it (TTEX payload)
  uint32_t pose_frame = 0;     // the newest pose the server had (frames + 1: none yet)
  bool steered = false;        // drawn from the viewer's steered pose (TFRM with a pose)
  UpdateStats update;
};

// The server's side of a flight, frame by frame: the opening, then each
// frame the fine elevation's pieces on half the link until it is whole, the
// update answering the newest pose received (and, predicting, where the
// viewer will be by this frame from the two newest), and the frame's TFRM,
// all within `rate_bytes_per_s` (0: unlimited). Poses arrive through pose()
// as the client sends them; nothing else of the flight is used. Once a
// steered pose has come (the viewer's controls move it), every TFRM carries
// the newest one, and the client draws it.
class TerrainLive {
 public:
  TerrainLive(const TerrainCoding& t, const CameraPath& path, const TerrainStreamOptions& o);
  // A message from the client's pose channel (terrain::kPoseMessageBytes):
  // false (and counted) for one that is malformed or older than the newest.
  bool pose(const uint8_t* data, size_t n);
  // Writes what is due `ms` after the start (frame f at f frame periods)
  // into `out`; true once the stream is whole (END appended).
  bool produce(uint64_t ms, std::vector<uint8_t>& out);
  // The next frame, whatever the time.
  void next_frame();
  bool finished() const { return finished_; }
  const TerrainSender& sender() const { return sender_; }
  const std::vector<TerrainStreamFrame>& frames() const { return frames_; }
  size_t opening_bytes() const { return opening_; }
  uint32_t elevation_frame() const { return elevation_frame_; }
  uint32_t poses_received() const { return poses_; }
  uint32_t poses_refused() const { return refused_; }
  // Frames written with the viewer's steered pose.
  uint32_t steered_frames() const;
  // The whole stream (after finished()).
  const std::vector<uint8_t>& bytes() const { return done_; }

 private:
  TerrainStreamOptions o_;
  TerrainSender sender_;
  std::unique_ptr<StreamWriter> w_;
  std::vector<uint8_t> done_;
  size_t handed_ = 0;  // bytes produce() has appended
  std::vector<TerrainStreamFrame> frames_;
  double credit_ = 0, elevation_bank_ = 0, per_frame_ = 0, period_ms_ = 50;
  size_t opening_ = 0;
  uint32_t elevation_frame_ = 0;
  // The two newest poses received.
  bool have_pose_ = false, have_previous_ = false;
  uint32_t pose_frame_ = 0, previous_frame_ = 0;
  WalkPose pose_{}, previous_{};
  uint32_t poses_ = 0, refused_ = 0;
  // The newest steered pose (terrain::kPoseSteered): every TFRM carries it
  // once one has come.
  bool steered_ = false;
  WalkPose steered_pose_{};
  bool finished_ = false;
};

struct TerrainStreamResult {
  std::vector<uint8_t> bytes;
  std::vector<TerrainStreamFrame> frames;
  size_t opening_bytes = 0;  // HEAD, TERH, TFLY and the coarse elevation
  uint32_t elevation_frame = 0;  // the frame the fine elevation was whole by (frames: never)
  std::vector<CameraPose> flight;  // the camera the client flies each frame (metres: its keys interpolated)
};
// The stream for a scripted flight over the link FlightLink models (as
// vds fly does): TerrainLive, given the client's pose of every
// poses_per_s-th frame latency_frames after that frame.
TerrainStreamResult write_terrain_stream(const TerrainCoding& t, const CameraPath& path, const TerrainStreamOptions& o);

}  // namespace vds::enc
