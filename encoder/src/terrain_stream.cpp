// The terrain stream's writer and the sender both the writer and the live
// server use (vds/enc/terrain_stream.h).
#include "vds/enc/terrain_stream.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "vds/bytes.h"
#include "vds/enc/stream_writer.h"
#include "vds/enc/walk_stream.h"
#include "vds/player.h"

namespace vds::enc {

namespace {

constexpr double kPi = 3.14159265358979323846;
// The map and everything above it within this many world units of the
// origin: camera-relative positions stay within the renderer's +-32767.
constexpr double kWorldExtent = 16384;

std::vector<uint8_t> elevation_payload(uint8_t pass, int y0, int y1, const std::vector<uint8_t>& data) {
  std::vector<uint8_t> p(terrain::kElevationHeaderBytes);
  p[0] = pass;
  store_le16(p.data() + 1, static_cast<uint32_t>(y0));
  store_le16(p.data() + 3, static_cast<uint32_t>(y1));
  p.insert(p.end(), data.begin(), data.end());
  return p;
}

}  // namespace

TerrainSender::TerrainSender(const TerrainCoding& t, const CameraPath& path, const TerrainStreamOptions& o)
    : t_(t), o_(o), hfov_(path.hfov_deg), server_(t, o.store_units) {
  if (path.frames.empty()) throw std::invalid_argument("terrain stream: the flight has no frames");
  if (o.max_cells < 1 || o.max_cells > terrain::kMaxDrawnCells || o.cache_log2 < terrain::kMinCacheLog2 ||
      o.cache_log2 > terrain::kMaxCacheLog2 || o.key_spacing < 1 || o.key_spacing > 1024 ||
      (o.half_log2 != 0 && (o.half_log2 < 3 || o.half_log2 > terrain::kMaxHalfLog2)) ||
      o.frame_budget < terrain::kMinFrameBudget || o.frame_budget > terrain::kMaxFrameBudget)
    throw std::invalid_argument("terrain stream: cache, drawn cells or key spacing out of range");
  // World units: a power of two a metre, as many as keep the map, its
  // heights and the flight within kWorldExtent.
  double extent = std::max(t.grid.cells_x, t.grid.cells_y) * t.cell_m;
  for (uint16_t h : t.heights) extent = std::max(extent, h * t.metres_per_unit);
  for (const CameraPose& p : path.frames)
    extent = std::max({extent, std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)});
  units_ = std::exp2(std::floor(std::log2(kWorldExtent / extent)));
  params_.cells_x = t.grid.cells_x;
  params_.cells_y = t.grid.cells_y;
  params_.quantiser = static_cast<uint8_t>(t.quantiser);
  params_.cache_log2 = static_cast<uint8_t>(o.cache_log2);
  params_.max_cells = static_cast<uint16_t>(o.max_cells);
  params_.store_units = o.store_units;
  params_.cell_q16 = static_cast<int32_t>(std::lround(t.cell_m * units_ * 65536));
  params_.height_step_q16 = static_cast<int32_t>(std::lround(t.metres_per_unit * units_ * 65536));
  const int pose_every = std::max(1, static_cast<int>(std::lround(path.fps / std::max(1, o.link.poses_per_s))));
  params_.pose_period = static_cast<uint16_t>(o.link.poses_per_s > 0 ? pose_every : 0);
  params_.frame_budget = static_cast<uint8_t>(o.frame_budget);
  // The half-resolution window: as asked, but no larger than the map needs
  // and at least 8 cells a side.
  if (o.half_log2 != 0) {
    int fit = 3;
    while (fit < o.half_log2 && (1 << fit) < std::max(t.grid.cells_x, t.grid.cells_y)) ++fit;
    params_.half_log2 = static_cast<uint8_t>(fit);
  }
  // The flight as keys every key_spacing frames (the last frame a key too).
  const size_t frames = path.frames.size();
  spacing_ = static_cast<uint32_t>(o.key_spacing);
  while ((frames - 1 + spacing_ - 1) / spacing_ + 1 > terrain::kMaxFlightKeys) ++spacing_;
  for (size_t f = 0;; f += spacing_) {
    const CameraPose& m = path.frames[std::min(f, frames - 1)];
    CameraPose u = m;
    u.x *= units_, u.y *= units_, u.z *= units_;
    keys_.push_back(walk_pose(u));
    if (f >= frames - 1) break;
  }
  // Header: the camera the flight gives, the depth range the map needs.
  const double far_units = std::hypot(t.grid.cells_x * t.cell_m, t.grid.cells_y * t.cell_m) * 1.5 * units_;
  const double near_units = std::max(far_units / 4000, 1.0 / 128);
  StreamHeader h = default_header(StreamMode::terrain, static_cast<uint16_t>(o.width), static_cast<uint16_t>(o.height));
  h.flags = kHeaderFlagInteractive;
  h.frame_period_us = static_cast<uint32_t>(std::lround(1e6 / path.fps));
  h.frame_count = static_cast<uint32_t>(frames);
  const double focal = o.width / 2.0 / std::tan(path.hfov_deg * kPi / 360);
  h.focal_x_q16 = h.focal_y_q16 = static_cast<int32_t>(std::lround(focal * 65536));
  h.center_x_q16 = o.width * 32768;
  h.center_y_q16 = o.height * 32768;
  h.near_q16 = static_cast<int32_t>(std::lround(near_units * 65536));
  h.far_q16 = static_cast<int32_t>(std::lround(std::min(far_units, 32000.0) * 65536));
  h.max_chunk_payload = o.max_chunk;
  h.workspace_bytes = static_cast<uint32_t>(Player::terrain_workspace_bytes(h, params_, kClientPlayerConfig));
  header_ = h;
  // The fine elevation in pieces of kCoarseStep rows.
  const int pw = t.points_x(), ph = t.points_y();
  for (int y = 0; y < ph; y += terrain::kCoarseStep) {
    const int y1 = std::min(ph, y + terrain::kCoarseStep);
    std::vector<uint8_t> data = encode_elevation(t.heights.data(), pw, ph, terrain::ElevationPass::fine, y, y1);
    if (data.size() + terrain::kElevationHeaderBytes > o.max_chunk)
      throw std::invalid_argument("terrain stream: an elevation piece exceeds the client's chunk size");
    pieces_.push_back({chunk::kTerrainElevation, elevation_payload(1, y, y1, data)});
  }
}

std::vector<TerrainChunk> TerrainSender::opening() const {
  std::vector<TerrainChunk> out;
  TerrainChunk terh{chunk::kTerrainParams, std::vector<uint8_t>(terrain::kParamsBytes)};
  terrain::params_to_bytes(params_, terh.payload.data());
  out.push_back(terh);
  TerrainChunk fly{chunk::kTerrainFlight, std::vector<uint8_t>(2 + keys_.size() * terrain::kPoseBytes)};
  store_le16(fly.payload.data(), spacing_);
  for (size_t k = 0; k < keys_.size(); ++k) terrain::pose_to_bytes(keys_[k], fly.payload.data() + 2 + k * terrain::kPoseBytes);
  out.push_back(fly);
  const std::vector<uint8_t> coarse =
      encode_elevation(t_.heights.data(), t_.points_x(), t_.points_y(), terrain::ElevationPass::coarse);
  if (coarse.size() + terrain::kElevationHeaderBytes > o_.max_chunk)
    throw std::invalid_argument("terrain stream: the coarse elevation exceeds the client's chunk size");
  out.push_back({chunk::kTerrainElevation, elevation_payload(0, 0, t_.points_y(), coarse)});
  return out;
}

CameraPose TerrainSender::metres(const WalkPose& p) const {
  CameraPose m = from_walk_pose(p);
  m.x /= units_, m.y /= units_, m.z /= units_;
  return m;
}

SceneCamera TerrainSender::camera(const WalkPose& p) const {
  return scene_camera(metres(p), hfov_, o_.width, o_.height);
}

std::vector<uint8_t> TerrainSender::answer(const WalkPose& pose, uint32_t pose_frame, const WalkPose* previous,
                                           double ahead, size_t budget, UpdateStats* stats) {
  std::vector<SceneCamera> cams = {camera(pose)};
  if (previous != nullptr && ahead > 0)
    cams.push_back(scene_camera(extrapolate(metres(*previous), metres(pose), ahead), hfov_, o_.width, o_.height));
  budget = std::min<size_t>(budget, o_.max_chunk);
  return server_.update(cams, pose_frame, budget, o_.pose, stats);
}

TerrainLive::TerrainLive(const TerrainCoding& t, const CameraPath& path, const TerrainStreamOptions& o)
    : o_(o), sender_(t, path, o) {
  w_ = std::make_unique<StreamWriter>(sender_.header());
  for (const TerrainChunk& c : sender_.opening()) w_->add_chunk(c.type, c.payload);
  opening_ = w_->size();
  const bool unlimited = !(o.link.rate_bytes_per_s > 0);
  per_frame_ = unlimited ? 0 : o.link.rate_bytes_per_s / path.fps;
  period_ms_ = 1000.0 / path.fps;
  credit_ = -static_cast<double>(opening_);
  elevation_frame_ = sender_.frames();
}

bool TerrainLive::pose(const uint8_t* data, size_t n) {
  if (data == nullptr || n != terrain::kPoseMessageBytes) return ++refused_, false;
  const uint32_t word = load_le32(data);
  const bool steered = (word & terrain::kPoseSteered) != 0;
  const uint32_t frame = word & ~terrain::kPoseSteered;
  if (frame >= sender_.frames() || (have_pose_ && frame <= pose_frame_)) return ++refused_, false;
  if (have_pose_) {
    previous_ = pose_;
    previous_frame_ = pose_frame_;
    have_previous_ = true;
  }
  pose_ = terrain::pose_from_bytes(data + 4);
  pose_frame_ = frame;
  have_pose_ = true;
  ++poses_;
  // A steered pose is drawn from the next frame written on.
  if (steered) {
    steered_ = true;
    steered_pose_ = pose_;
  }
  return true;
}

void TerrainLive::next_frame() {
  if (finished_) return;
  const uint32_t f = static_cast<uint32_t>(frames_.size());
  const bool unlimited = !(o_.link.rate_bytes_per_s > 0);
  TerrainStreamFrame tf;
  tf.pose_frame = have_pose_ ? pose_frame_ : sender_.frames() + 1;
  credit_ = unlimited ? 1e12 : credit_ + per_frame_;
  // The fine elevation on half the link until it is whole.
  if (sender_.elevation_left()) {
    elevation_bank_ += unlimited ? 1e12 : per_frame_ / 2;
    while (sender_.elevation_left() && credit_ > 0 &&
           static_cast<double>(sender_.next_elevation_bytes() + kChunkFraming) <= elevation_bank_) {
      const TerrainChunk c = sender_.take_elevation();
      w_->add_chunk(c.type, c.payload);
      const double cost = static_cast<double>(c.payload.size() + kChunkFraming);
      elevation_bank_ -= cost;
      credit_ -= cost;
      tf.elevation_bytes += c.payload.size() + kChunkFraming;
    }
    if (!sender_.elevation_left()) elevation_frame_ = f;
  }
  // The update: what the newest pose needs, and where the viewer will be by
  // this frame, moving as between the two newest poses.
  if (have_pose_ && credit_ >= std::max(1.0, static_cast<double>(o_.link.min_update_bytes))) {
    const bool predict = o_.link.predict && have_previous_ && f > pose_frame_ && pose_frame_ > previous_frame_;
    const double ahead = predict ? static_cast<double>(f - pose_frame_) / (pose_frame_ - previous_frame_) : 0;
    const size_t budget = static_cast<size_t>(std::max(0.0, credit_ - kChunkFraming));
    const std::vector<uint8_t> u =
        sender_.answer(pose_, pose_frame_, predict ? &previous_ : nullptr, ahead, budget, &tf.update);
    if (!u.empty()) {
      w_->add_chunk(chunk::kTerrainTexture, u);
      tf.texture_bytes = u.size();
      credit_ -= static_cast<double>(u.size() + kChunkFraming);
    }
    // A link with nothing to send carries nothing: no credit is saved up.
    if (tf.update.wanted == 0 || u.empty()) credit_ = std::min(credit_, per_frame_);
  }
  uint8_t frm[terrain::kSteeredFrameBytes];
  store_le32(frm, f);
  if (steered_) terrain::pose_to_bytes(steered_pose_, frm + terrain::kFrameBytes);
  const size_t frm_bytes = steered_ ? terrain::kSteeredFrameBytes : terrain::kFrameBytes;
  w_->add_chunk(chunk::kTerrainFrame, std::span<const uint8_t>(frm, frm_bytes));
  credit_ -= static_cast<double>(frm_bytes + kChunkFraming);
  tf.steered = steered_;
  tf.stream_bytes = w_->size();
  frames_.push_back(tf);
  if (o_.progress) o_.progress(frames_.size());
  if (frames_.size() == sender_.frames()) {
    done_ = w_->finish();
    finished_ = true;
  }
}

uint32_t TerrainLive::steered_frames() const {
  return static_cast<uint32_t>(std::count_if(frames_.begin(), frames_.end(), [](const TerrainStreamFrame& f) { return f.steered; }));
}

bool TerrainLive::produce(uint64_t ms, std::vector<uint8_t>& out) {
  while (!finished_ && static_cast<double>(ms) >= static_cast<double>(frames_.size()) * period_ms_) next_frame();
  const std::span<const uint8_t> all = finished_ ? std::span<const uint8_t>(done_) : w_->bytes();
  out.insert(out.end(), all.begin() + static_cast<std::ptrdiff_t>(handed_), all.end());
  handed_ = all.size();
  return finished_;
}

TerrainStreamResult write_terrain_stream(const TerrainCoding& t, const CameraPath& path, const TerrainStreamOptions& o) {
  TerrainLive live(t, path, o);
  const uint32_t every = std::max<uint32_t>(1, live.sender().params().pose_period);
  for (uint32_t f = 0; f < live.sender().frames(); ++f) {
    // The client's pose of frame p, sent every `every` frames, arrives
    // latency_frames later.
    const long p = static_cast<long>(f) - o.link.latency_frames;
    if (p >= 0 && p % every == 0) {
      uint8_t msg[terrain::kPoseMessageBytes];
      store_le32(msg, static_cast<uint32_t>(p));
      terrain::pose_to_bytes(live.sender().pose(static_cast<uint32_t>(p)), msg + 4);
      live.pose(msg, sizeof msg);
    }
    live.next_frame();
  }
  TerrainStreamResult r;
  r.bytes = live.bytes();
  r.frames = live.frames();
  r.opening_bytes = live.opening_bytes();
  r.elevation_frame = live.elevation_frame();
  for (uint32_t f = 0; f < live.sender().frames(); ++f) r.flight.push_back(live.sender().metres(live.sender().pose(f)));
  return r;
}

}  // namespace vds::enc
