// Player mode "model": the progressive mesh (vds/mesh.h) drawn by the model
// view (vds/model_view.h) once its base is in and after every level, the
// camera a step further round it each frame (vds::ModelFrames). Set up at
// the mesh header (MSHH) for as much of the model as the workspace holds: a
// client smaller than the full resolution plays the levels that fit and
// says at once when it holds no more.
//
// A textured model's colour follows its geometry as mesh colors
// (vds/mesh_colors.h): an MCVX after each level colours the vertices it
// added (the level is drawn then, in those colours; after the single-rate
// tail, which numbers the vertices anew, every vertex again); MCLH, once
// the mesh is whole, carries every face's resolution (and the vertex
// samples, unless they are those colours), then MCLV chunks its MIP
// levels coarsest first, each replacing the one shown. The planes are
// carved at MCLH for the finest level the workspace holds; finer levels
// are skipped, so a small client shows the colour it can rather than none.
// MORB chunks draw the model as held from a given angle (the orbit script).
#include "vds/bytes.h"
#include "vds/mesh_colors.h"
#include "vds/player.h"

namespace vds {

struct ModelColors {
  mc::MeshColors mc;
  mc::Planes planes;
  MeshColorsSurface surface;
  int finest = 0;  // the finest level the planes hold
  int shown = 0;   // the level in the planes (max_res_log2: vertex samples only)
};

// Colours of the vertices, arriving with them (MCVX) before MCLH: drawn
// as faces of resolution 1 (each face its corners' colours, blended).
struct VertexColours {
  mc::Planes planes;
  uint32_t capacity = 0;
  uint32_t coloured = 0;
  bool valid = true;  // false once the single-rate tail has renumbered the vertices
  const MeshState* mesh = nullptr;
  MeshColorsSurface surface;
};

namespace {

bool vertex_lattice_of(const void* ctx, uint32_t t, LatticeFace* out) {
  const auto* c = static_cast<const VertexColours*>(ctx);
  const uint16_t* tri = c->mesh->triangles16();
  if (tri == nullptr || t >= c->mesh->triangle_count()) return false;
  *out = LatticeFace{};
  for (int k = 0; k < 3; ++k) out->vertex[k] = tri[3 * t + k];
  return true;
}

bool lattice_of(const void* ctx, uint32_t t, LatticeFace* out) {
  const auto* c = static_cast<const ModelColors*>(ctx);
  if (t >= c->mc.topology().faces) return false;
  c->mc.face_lattice(t, out);
  return true;
}

bool start(Player& p, const StreamHeader&) {
  if (p.config().format != PixelFormat::rgb565) {
    p.fail(Status::unsupported_feature, "the model view draws RGB565 bands only");
    return false;
  }
  p.model_started = false;
  p.colors = nullptr;
  p.vertex_colours = nullptr;
  p.level_mark = 0;
  p.model_frames = ModelFrames{};
  p.model_angle = p.model_turn = 0;
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

// Draws the current mesh (with its colours once they are in) into the
// frame begun, from the stream's angle `model_angle` turned by the viewer's
// `model_turn`.
Status draw_model(Player& p) {
  const uint64_t display_before = p.display_total();
  const uint64_t d0 = p.work_clock();
  const uint16_t at = static_cast<uint16_t>(p.model_angle + p.model_turn);
  const Status d = p.view.draw(p.mesh.mesh(), at, detail::render_band_to_player, &p, p.model_colors());
  // Drawing counts as display: the bands have added their part, add the renderer's.
  p.add_display((p.work_clock() - d0) - (p.display_total() - display_before));
  return d;
}

// The stream's next frame, from `angle` (2^-16 turn), or the orbit's next
// one when negative.
ChunkResult draw_frame(Player& p, int32_t angle = -1) {
  if (!p.begin_frame()) return ChunkResult::abort;
  p.model_angle = angle >= 0 ? static_cast<uint16_t>(angle) : p.model_frames.angle();
  const Status d = draw_model(p);
  p.model_frames.mark_drawn(p.mesh);
  if (d != Status::ok) {
    p.fail(d, "the model view could not draw");
    return ChunkResult::abort;
  }
  return p.end_frame() ? ChunkResult::consumed : ChunkResult::abort;
}

// MCLH: the mesh colors of the whole mesh, set up for the finest level the
// workspace holds; the model is drawn with its vertex samples.
ChunkResult start_colors(Player& p, const uint8_t* payload, uint32_t size) {
  const MeshState& m = p.mesh.mesh();
  if (!p.mesh.complete() || m.vertex_count() != p.mesh.header().vertices || m.triangles16() == nullptr) {
    p.notice(PlayerNotice::model_no_colors, 1, 0, 0);  // they belong to the whole mesh
    return ChunkResult::consumed;
  }
  Arena& a = p.arena();
  const size_t mark = a.mark();
  auto* c = a.alloc_array<ModelColors>(1);
  Status s = c != nullptr ? Status::ok : Status::workspace_too_small;
  if (s == Status::ok) {
    *c = ModelColors{};
    s = c->mc.init(a, m.triangles16(), m.triangle_count(), m.vertex_count());
  }
  // The vertex samples may be the colours that came with the vertices.
  const VertexColours* vc = p.vertex_colours;
  const bool whole = vc != nullptr && vc->valid && vc->coloured == m.vertex_count();
  if (s == Status::ok) s = c->mc.read_header(payload, size, whole ? &vc->planes : nullptr);
  if (s != Status::ok && s != Status::workspace_too_small) {
    p.fail(s, "the mesh colors header was refused");
    return ChunkResult::abort;
  }
  // The finest level whose three planes fit what is left.
  int level = -1;
  if (s == Status::ok) {
    for (int l = 0; l <= c->mc.max_res_log2(); ++l) {
      if (size_t{3} * c->mc.layout_level(l) + 8 <= a.remaining()) {
        level = l;
        break;
      }
    }
  }
  if (level < 0) {
    a.rewind(mark);
    p.notice(PlayerNotice::model_no_colors, 2, 0, 0);
    return ChunkResult::consumed;
  }
  const uint32_t total = c->mc.layout_level(level);
  c->planes.y = a.alloc_array<uint8_t>(total);
  c->planes.cb = a.alloc_array<uint8_t>(total);
  c->planes.cr = a.alloc_array<uint8_t>(total);
  c->finest = level;
  if (level > 0) p.notice(PlayerNotice::model_colors_level, static_cast<uint32_t>(level), static_cast<uint32_t>(c->mc.max_res_log2()), 0);
  // Shown first: the vertex samples alone (every face at R = 1).
  const int coarsest = c->mc.max_res_log2();
  c->mc.layout_level(coarsest);
  const uint8_t* vs = c->mc.vertex_samples();
  for (uint32_t v = 0; v < m.vertex_count(); ++v)
    for (int k = 0; k < 3; ++k) c->planes.plane(k)[v] = vs[3 * v + k];
  c->shown = coarsest;
  c->surface.y = c->planes.y;
  c->surface.cb = c->planes.cb;
  c->surface.cr = c->planes.cr;
  c->surface.samples = total;
  c->surface.face = lattice_of;
  c->surface.ctx = c;
  p.colors = c;
  return ChunkResult::consumed;
}

// MCLV: the chunks of a level finer than the one shown and no finer than
// the planes hold replace it (drawn when the level is whole); others are
// skipped.
ChunkResult colors_level(Player& p, const uint8_t* payload, uint32_t size, bool* drawn) {
  ModelColors* c = p.colors;
  *drawn = false;
  if (c == nullptr) return ChunkResult::consumed;  // colours not shown (noticed at MCLH)
  mc::LevelChunk lc;
  Status s = mc::level_chunk_info(payload, size, &lc);
  if (s == Status::ok && lc.level >= c->mc.max_res_log2()) s = Status::malformed;
  if (s != Status::ok) {
    p.fail(s, "a mesh colors level chunk was refused");
    return ChunkResult::abort;
  }
  const bool wanted = lc.first == 0 ? lc.level >= c->finest && lc.level < c->shown : c->mc.decoding_level() == lc.level;
  if (!wanted) return ChunkResult::consumed;
  s = c->mc.decode_level(payload, size, c->planes);
  if (s != Status::ok) {
    p.fail(s, "the mesh colors decoder refused a level");
    return ChunkResult::abort;
  }
  if (c->mc.level_complete()) {
    c->shown = lc.level;
    *drawn = true;
  }
  return ChunkResult::consumed;
}

// MCVX: the colours of the vertices the last level added.
ChunkResult vertex_colours(Player& p, const uint8_t* payload, uint32_t size, bool* drawn) {
  *drawn = false;
  const MeshState& m = p.mesh.mesh();
  if (p.colors != nullptr || !p.mesh.drawable() || m.triangles16() == nullptr) {
    p.fail(Status::malformed, "vertex colours without a mesh to colour");
    return ChunkResult::abort;
  }
  VertexColours* c = p.vertex_colours;
  if (c == nullptr) {
    const uint32_t cap = p.plan().vertices;
    c = p.arena().alloc_array<VertexColours>(1);
    uint8_t* planes = c != nullptr ? p.arena().alloc_array<uint8_t>(size_t{3} * cap) : nullptr;
    if (planes == nullptr) {
      p.fail(Status::workspace_too_small, "no room for the vertex colours");
      return ChunkResult::abort;
    }
    *c = VertexColours{};
    c->planes = mc::Planes{planes, planes + cap, planes + 2 * size_t{cap}};
    c->capacity = cap;
    c->mesh = &m;
    c->surface.y = c->planes.y;
    c->surface.cb = c->planes.cb;
    c->surface.cr = c->planes.cr;
    c->surface.face = vertex_lattice_of;
    c->surface.ctx = c;
    p.vertex_colours = c;
  }
  if (!c->valid) {
    // After the single-rate tail: every vertex's colour again, from the first.
    if (size < mc::kVertexChunkHeadBytes || load_le32(payload) != 0) return ChunkResult::consumed;
    c->valid = true;
    c->coloured = 0;
  }
  if (m.vertex_count() > c->capacity) {
    p.fail(Status::malformed, "vertex colours beyond the mesh's capacity");
    return ChunkResult::abort;
  }
  const Status s = mc::decode_vertex_colours(payload, size, m, c->planes, &c->coloured);
  if (s != Status::ok) {
    p.fail(s, "the vertex colours were refused");
    return ChunkResult::abort;
  }
  c->surface.samples = c->coloured;
  *drawn = true;
  return ChunkResult::consumed;
}

ChunkResult on_colors_chunk(Player& p, uint32_t type, const uint8_t* payload, uint32_t size) {
  if (!p.model_started) {
    p.fail(Status::malformed, "mesh colors before the mesh");
    return ChunkResult::abort;
  }
  const uint64_t t0 = p.enter_chunk();
  ChunkResult r;
  bool draw = false;
  if (type == mc::kChunkVertices) {
    r = vertex_colours(p, payload, size, &draw);
  } else if (type == mc::kChunkHeader) {
    if (p.colors != nullptr) {
      p.fail(Status::malformed, "a second mesh colors header");
      r = ChunkResult::abort;
    } else {
      r = start_colors(p, payload, size);
      draw = r == ChunkResult::consumed && p.colors != nullptr;
    }
  } else {
    r = colors_level(p, payload, size, &draw);
  }
  p.add_decode(p.work_clock() - t0);
  if (r == ChunkResult::consumed && draw && p.mesh.drawable()) r = draw_frame(p);
  p.leave_chunk();
  return r;
}

// MORB: one frame of the model as it is held, from the script's angle.
ChunkResult orbit(Player& p, const uint8_t* payload, uint32_t size) {
  if (!p.model_started || !p.mesh.drawable()) {
    p.fail(Status::malformed, "an orbit before the base mesh");
    return ChunkResult::abort;
  }
  if (size != 2) {
    p.fail(Status::malformed, "an orbit chunk is one u16 angle");
    return ChunkResult::abort;
  }
  (void)p.enter_chunk();
  const ChunkResult r = draw_frame(p, static_cast<int32_t>(load_le16(payload)));
  p.leave_chunk();
  return r;
}

// The viewer turns the model (Player::view_input): the controls' turn
// (2^-16 turn) is added to the orbit angle of every frame drawn from now
// on, and the model is drawn again at once, as a frame that is not the
// stream's, when what it holds is what the stream last showed (not a
// level whose colours have not come yet, nor a colour level half decoded
// over the one shown): else the stream's next frame shows the turn.
bool view_input(Player& p) {
  if (!p.model_started || !p.mesh.drawable() || p.mesh.mesh().triangles16() == nullptr) return false;
  terrain::SteerInput in;
  if (!p.callbacks().steer(p.callbacks().ctx, &in) || in.turn == 0) return false;
  p.model_turn = static_cast<uint16_t>(p.model_turn + static_cast<uint16_t>(in.turn));
  p.mark_steered();
  const bool shown = !p.model_frames.due(p.mesh) &&
                     (p.colors == nullptr || p.colors->mc.decoding_level() < 0 || p.colors->mc.level_complete());
  if (!shown) return false;
  if (!p.begin_frame(false)) return false;
  const Status d = draw_model(p);
  const bool closed = p.end_frame(false);  // the frame is closed even if the view could not draw it
  return d == Status::ok && closed;
}

ChunkResult on_chunk(Player& p, uint32_t type, const uint8_t* payload, uint32_t size) {
  if (type == kModelOrbitChunk) return orbit(p, payload, size);
  if (type == mc::kChunkHeader || type == mc::kChunkLevel || type == mc::kChunkVertices)
    return on_colors_chunk(p, type, payload, size);
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
  // A model whose vertices come with their colours is drawn when their
  // colours are in (the MCVX after each level; after the single-rate tail,
  // which numbers the vertices anew, the MCVX that colours them all again).
  VertexColours* vc = p.vertex_colours;
  if (vc != nullptr && vc->valid && p.mesh.header().tail() && p.mesh.complete()) vc->valid = false;
  const bool colour_follows = vc != nullptr && p.colors == nullptr;
  if (result == ChunkResult::consumed && p.model_frames.due(p.mesh) && !colour_follows) result = draw_frame(p);
  p.leave_chunk();
  return result;
}

// A frame can complete at any chunk: a model draws after every level, and
// a coarse level can be one small chunk.
size_t feed_limit(const Player&, uint32_t frames_room) { return detail::chunk_per_frame_feed_limit(frames_room); }

}  // namespace

size_t Player::model_colors_workspace_bytes(uint32_t faces, uint32_t vertices, uint32_t samples) {
  return sizeof(ModelColors) + alignof(ModelColors) + mc::MeshColors::init_bytes(faces, vertices) + size_t{3} * samples +
         64;
}

const MeshColorsSurface* Player::model_colors() const {
  if (colors != nullptr) return &colors->surface;
  return vertex_colours != nullptr && vertex_colours->valid ? &vertex_colours->surface : nullptr;
}
int Player::model_colors_level() const {
  if (colors != nullptr) return colors->shown;
  return vertex_colours != nullptr && vertex_colours->valid ? kModelVertexColours : -1;
}

namespace detail {
extern const PlayerMode kModelMode;
const PlayerMode kModelMode{StreamMode::model, start, on_chunk, feed_limit, view_input};
}  // namespace detail

}  // namespace vds
