// Flights over a terrain: the scripted flyover every map gets (low and high
// altitude, turns, a dive), flight scripts, the terrain as a scene the
// reference renderer draws, and the server's replay of a flight over an
// ideal link (the client's store after each update, what was sent up and
// down) with the pictures it gives (docs/terrain.md).
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "vds/enc/camera_path.h"
#include "vds/enc/scene.h"
#include "vds/enc/terrain_server.h"

namespace vds::enc {

// The flyover of any map, `frames` long at `fps`: in over one edge low
// (15 m above the ground), a climb to a third of the map's width, a wide
// turn, a dive back to 20 m, and out low along a valley-following line.
// Heights follow the ground (never below 8 m above it).
CameraPath terrain_flyover(const TerrainCoding& t, int frames, double fps, double hfov_deg = 70);

// A flight script: camera keys (vds path's key format, vds/enc/camera_path.h)
// in metres over the terrain, interpolated to frames and kept at least 2 m
// above the ground. Throws naming the file.
CameraPath read_flight(const std::string& text, const std::string& name, const TerrainCoding& t);

// The terrain as a scene: the grid's cells as two triangles each, textured
// with `texture` (RGB, the colour map's size padded to whole cells).
Scene terrain_scene(const TerrainCoding& t);

// The pose `steps` pose intervals after b, moving as it moved from a to b
// (yaw the short way round, pitch kept within the camera's range): where
// the server predicts the viewer will be.
CameraPose extrapolate(const CameraPose& a, const CameraPose& b, double steps);

// The ground truth of a flight: the terrain drawn by the reference
// renderer with the whole colour map (mip-mapped, supersampled).
class TerrainTruth {
 public:
  TerrainTruth(const TerrainCoding& t, int width, int height, int supersample = 2, double near_m = 0.1);
  ~TerrainTruth();
  io::Image render(const CameraPose& pose, double hfov_deg) const;

 private:
  std::unique_ptr<SceneRenderer> renderer_;
};

struct FlightLink {
  double rate_bytes_per_s = 2000;  // downlink payload bytes a second; 0: unlimited (every pose answered whole)
  int latency_frames = 2;          // pose up and update down, in frames
  int poses_per_s = 5;             // how often the client sends its pose
  size_t pose_bytes = 21;          // a pose message on the line (type, frame, x, y, z, yaw, pitch; framing)
  // The server also serves where the viewer will be when the update is
  // drawn, extrapolated from its two newest poses.
  bool predict = true;
  // The server answers once the link has carried this many bytes for the
  // answer (fewer, larger updates spend less on headers).
  size_t min_update_bytes = 200;
};

struct FlightFrame {
  size_t down_bytes = 0;       // texture bytes that arrived before this frame
  size_t elevation_bytes = 0;  // fine elevation bytes that arrived with them
  size_t up_bytes = 0;     // pose bytes sent at this frame
  UpdateStats update;      // the update this frame answered (if any)
  uint32_t held = 0;       // what the client holds: coefficients (vds), cache bytes (tiles)
  double psnr = 0;         // client's frame (reference renderer, held texture) against the ground truth
  double psnr_client_renderer = 0;  // the client library's renderer with the whole texture (FlightOptions::client_renderer)
};

struct FlightOptions {
  FlightLink link;
  int width = 240, height = 180;
  uint32_t capacity = 65536;  // client store, coefficients
  PoseOptions pose;
  int supersample = 2;
  // Also draw each frame with the client library's fixed-point renderer
  // and the whole texture: the rendering loss, apart from the coding loss.
  bool client_renderer = false;
  // Called per frame with the ground truth and the client's picture.
  std::function<void(size_t frame, const io::Image& truth, const io::Image& client)> frame_sink;
  std::function<void(size_t done)> progress;
};

struct FlightResult {
  std::vector<FlightFrame> frames;
  size_t elevation_bytes = 0;         // both passes
  size_t coarse_elevation_bytes = 0;  // the coarse pass, sent before anything else
  uint32_t elevation_frame = 0;       // the frame the fine pass was whole by
  size_t first_update_bytes = 0;  // the intra data of the first pose
  uint32_t first_update_frames = 0;  // frames until the first pose's needs were all sent
  bool first_update_done = false;    // they were, within the flight
};

// What a flight sends down: vds's server, or a baseline.
class FlightSource {
 public:
  virtual ~FlightSource() = default;
  // Answers pose frame `pose` with at most `budget` bytes (more than the
  // flight can use when the link is unlimited): what any of `cameras`
  // needs (the pose's camera, then the prediction); fills ff->update and
  // returns the bytes sent.
  virtual size_t answer(const std::vector<SceneCamera>& cameras, uint32_t pose, size_t budget, FlightFrame* ff) = 0;
  // The texture the client holds now (R'G'B', the padded colour map's
  // size), and whether it changed since the last call to texture().
  virtual bool changed() const = 0;
  virtual io::Image texture() = 0;
  // What the client holds (FlightFrame::held).
  virtual uint32_t held() const = 0;
};

// The flight loop both fly() and the baselines use.
FlightResult fly_source(const TerrainCoding& t, const CameraPath& path, const FlightOptions& o, FlightSource& source);

// Plays the flight: the coarse elevation first; then each frame the
// fine elevation takes up to half the bytes the link carried (until it is
// whole; the client draws the ground interpolated from the coarse points
// until then) and the server answers the pose of latency_frames before
// with an update of at most the rest; the update is applied before the
// frame is drawn.
FlightResult fly(const TerrainCoding& t, const CameraPath& path, const FlightOptions& o);

}  // namespace vds::enc
