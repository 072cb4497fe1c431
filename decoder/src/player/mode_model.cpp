// Player mode "model": the progressive mesh (vds/mesh.h) drawn by the model
// view (vds/model_view.h) once its base is in and after every level, the
// camera a step further round it each frame (vds::ModelFrames). Set up at
// the mesh header (MSHH) for as much of the model as the workspace holds: a
// client smaller than the full resolution plays the levels that fit and
// says at once when it holds no more.
#include "vds/player.h"

namespace vds {
namespace {

bool start(Player& p, const StreamHeader&) {
  if (p.config().format != PixelFormat::rgb565) {
    p.fail(Status::unsupported_feature, "the model view draws RGB565 bands only");
    return false;
  }
  p.model_started = false;
  p.level_mark = 0;
  p.model_frames = ModelFrames{};
  return true;  // the decoder and the view are set up when MSHH arrives
}

bool start_mesh(Player& p, const uint8_t* mshh, uint32_t size) {
  ModelViewConfig vc;
  vc.width = p.header().width;
  vc.height = p.header().height;
  vc.band_height = p.config().band_rows;
  ModelCapacity cap;
  const size_t left = p.arena().remaining();
  const Status s = start_model(p.arena(), mshh, size, vc, p.mesh, p.view, &cap);
  PlayerPlan plan = p.plan();
  plan.known = true;
  plan.available = left;
  plan.vertices = cap.vertices;
  plan.of_vertices = p.header().max_vertices;
  plan.triangles = cap.triangles;
  plan.bytes = cap.bytes;
  p.set_plan(plan);
  if (s == Status::workspace_too_small && cap.bytes > 0) {
    p.notice(PlayerNotice::model_base_too_big, static_cast<uint32_t>(cap.bytes), static_cast<uint32_t>(left), 0);
    p.fail(s, "the base mesh does not fit the workspace");
    return false;
  }
  if (s != Status::ok) {
    p.fail(s, "the mesh header was refused");
    return false;
  }
  if (cap.vertices < p.header().max_vertices)
    p.notice(PlayerNotice::model_partial, cap.vertices, p.header().max_vertices, 0);
  // A level's chunk can take long to decode: keep the I/O moving meanwhile.
  if (p.config().mesh_service_items != 0 && p.callbacks().service != nullptr)
    p.mesh.set_progress([](void* ctx) { static_cast<Player*>(ctx)->service(); }, &p, p.config().mesh_service_items);
  p.model_started = true;
  return true;
}

ChunkResult on_chunk(Player& p, uint32_t type, const uint8_t* payload, uint32_t size) {
  if (!MeshDecoder::handles(type)) return ChunkResult::unknown;
  if (!p.model_started) {
    if (type != chunk::kMeshHeader) {
      p.fail(Status::malformed, "the first mesh chunk is not MSHH");
      return ChunkResult::abort;
    }
    if (!start_mesh(p, payload, size)) return ChunkResult::abort;
  }
  const uint64_t t0 = p.enter_chunk();
  const bool had_base = p.mesh.drawable();
  const uint32_t levels_before = p.mesh.levels_done();
  const Status s = p.mesh.consume(type, payload, size);
  const uint64_t t1 = p.work_clock();
  p.add_decode(t1 - t0);
  p.level_mark += t1 - t0;
  ChunkResult result = ChunkResult::consumed;
  if (!is_error(s) && ((!had_base && p.mesh.drawable()) || p.mesh.levels_done() != levels_before)) {
    PlayedLevel l;
    l.level = p.mesh.levels_done();
    l.vertices = p.mesh.mesh().vertex_count();
    l.triangles = p.mesh.mesh().triangle_count();
    l.decode = p.level_mark;
    p.level_mark = 0;
    if (p.callbacks().level != nullptr) p.callbacks().level(p.callbacks().ctx, l);
  }
  if (is_error(s)) {
    p.fail(s, "the mesh decoder refused a chunk");
    result = ChunkResult::abort;
  } else if (p.mesh.capacity_reached() && !p.workspace_full()) {
    p.set_full();
    p.notice(PlayerNotice::model_full, p.mesh.levels_done(), p.mesh.header().levels, p.mesh.mesh().vertex_count());
  }
  // The level a chunk completed is drawn even when the decoder knows at once
  // that the next one will not fit (a version-2 stream's tail).
  if (result == ChunkResult::consumed && p.model_frames.due(p.mesh)) {
    if (!p.begin_frame()) {
      result = ChunkResult::abort;
    } else {
      const uint64_t display_before = p.display_total();
      const uint64_t d0 = p.work_clock();
      const Status d = p.view.draw(p.mesh.mesh(), p.model_frames.angle(), detail::render_band_to_player, &p);
      p.model_frames.mark_drawn(p.mesh);
      // Drawing counts as display: the bands have added their part, add the renderer's.
      p.add_display((p.work_clock() - d0) - (p.display_total() - display_before));
      if (d != Status::ok) {
        p.fail(d, "the model view could not draw");
        result = ChunkResult::abort;
      } else if (!p.end_frame()) {
        result = ChunkResult::abort;
      }
    }
  }
  p.leave_chunk();
  return result;
}

// A frame can complete at any chunk: a model draws after every level, and
// a coarse level can be one small chunk.
size_t feed_limit(const Player&, uint32_t frames_room) { return detail::chunk_per_frame_feed_limit(frames_room); }

}  // namespace

namespace detail {
extern const PlayerMode kModelMode;
const PlayerMode kModelMode{StreamMode::model, start, on_chunk, feed_limit};
}  // namespace detail

}  // namespace vds
