// Player mode "walkthrough": view-dependent texture streaming along a
// camera script (vds/walk.h, vds/walk_geometry.h; docs/walkthrough.md).
// Set up at WLKP for the slots and views it declares; a WFRM record brings
// one or more frames' triangles, hot slots and cameras, and each frame is
// drawn as it is read by mapping each hot triangle from the stored view
// the record names for it (Shading::view_mapped, the screen -> view
// homography of its plane).
// Views arrive as WVUP and an intra vds image decoded into the view's
// Y'CbCr 4:2:0 planes; a WVUP naming a slot's own camera again may carry a
// residual image that refines what the slot holds.
#include "vds/homography.h"
#include "vds/player.h"
#include "vds/render.h"

namespace vds {

struct WalkPlay {
  WalkParams params;
  Renderer renderer;
  Camera view_cam[kWalkMaxViews];
  bool view_ready[kWalkMaxViews];
  Texture view_tex[kWalkMaxViews];
  int pending = -1;  // the view slot a WVUP opened, until its image is whole
  Camera pending_cam;
  bool pending_refines = false;  // the WVUP names the slot's own camera: its image may be a residual
  bool image_open = false;
  Mesh* meshes = nullptr;
  Vec3<Q16_16>* positions = nullptr;
  uint16_t* indices = nullptr;
  uint8_t* view_of = nullptr;
};

namespace {

size_t plane_bytes(const StreamHeader& h) {
  const size_t cw = (h.width + 1u) / 2u, ch = (h.height + 1u) / 2u;
  return static_cast<size_t>(h.width) * h.height + 2 * cw * ch;
}

RenderConfig render_config(const StreamHeader& h, const WalkParams& w, const PlayerConfig& c) {
  RenderConfig rc;
  rc.width = h.width;
  rc.height = h.height;
  rc.band_height = static_cast<uint16_t>(c.band_rows < h.height ? c.band_rows : h.height);
  rc.format = c.format;
  rc.depth = DepthFormat::d16;
  rc.vertex_cache = 3u * w.slots;
  rc.triangle_cache = w.slots;
  return rc;
}

bool cameras_equal(const Camera& a, const Camera& b) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (a.rotation.m[r][c].raw() != b.rotation.m[r][c].raw()) return false;
  return a.position.x.raw() == b.position.x.raw() && a.position.y.raw() == b.position.y.raw() &&
         a.position.z.raw() == b.position.z.raw() && a.fx.raw() == b.fx.raw() && a.fy.raw() == b.fy.raw();
}

bool render_band(void* ctx, const Band& b) {
  return static_cast<Player*>(ctx)->band(PixelRect{0, b.y, b.width, b.height, b.pixels, static_cast<ptrdiff_t>(b.stride)});
}

bool start(Player& p, const StreamHeader& h) {
  p.walk = nullptr;
  if (h.focal_x_q16 == 0 || h.near_q16 == 0 || h.frame_count == 0) {
    p.fail(Status::malformed, "a walkthrough needs a camera and a frame count in its header");
    return false;
  }
  return true;  // set up at WLKP
}

bool setup(Player& p, const uint8_t* payload, uint32_t size) {
  WalkParams w;
  if (walk_params_from_bytes(payload, size, &w) != Status::ok || w.slots > kWalkMaxSlots) {
    p.fail(Status::malformed, "WLKP is not valid");
    return false;
  }
  const StreamHeader& h = p.header();
  const size_t need = Player::walk_workspace_bytes(h, w, p.config());
  PlayerPlan plan = p.plan();
  plan.known = true;
  plan.needs = need;
  plan.available = p.arena().remaining();
  plan.triangles = w.slots;
  p.set_plan(plan);
  if (need > p.arena().remaining()) {
    p.fail(Status::workspace_too_small, "the walkthrough's slots and views do not fit the workspace");
    return false;
  }
  WalkPlay* wp = static_cast<WalkPlay*>(p.arena().alloc(sizeof(WalkPlay), alignof(WalkPlay)));
  if (wp == nullptr) return false;
  *wp = WalkPlay{};
  wp->params = w;
  Status s = p.walk_geometry.init(p.arena(), w.slots, w.quantum_raw);
  if (s == Status::ok) s = p.image.init(p.arena());
  if (s == Status::ok) s = wp->renderer.init(render_config(h, w, p.config()), p.arena());
  wp->meshes = p.arena().alloc_array<Mesh>(w.slots);
  wp->positions = p.arena().alloc_array<Vec3<Q16_16>>(3u * w.slots);
  wp->indices = p.arena().alloc_array<uint16_t>(3u * w.slots);
  wp->view_of = p.arena().alloc_array<uint8_t>(w.slots);
  if (s == Status::ok && (!wp->meshes || !wp->positions || !wp->indices || !wp->view_of)) s = Status::workspace_too_small;
  for (uint8_t v = 0; v < w.views && s == Status::ok; ++v) {
    uint8_t* planes = static_cast<uint8_t*>(p.arena().alloc(plane_bytes(h), 4));
    if (planes == nullptr) {
      s = Status::workspace_too_small;
      break;
    }
    Texture& t = wp->view_tex[v];
    t.format = TexFormat::ycbcr420;
    t.address = TexAddress::clamp;
    t.width = h.width;
    t.height = h.height;
    t.stride = h.width;
    t.texels = planes;
    t.cb = planes + static_cast<size_t>(h.width) * h.height;
    t.chroma_stride = (h.width + 1u) / 2u;
    t.cr = t.cb + t.chroma_stride * ((h.height + 1u) / 2u);
    wp->view_ready[v] = false;
  }
  if (s != Status::ok) {
    p.fail(s, "the walkthrough could not be set up");
    return false;
  }
  for (uint32_t i = 0; i < 3u * w.slots; ++i) wp->indices[i] = static_cast<uint16_t>(i);
  for (uint32_t i = 0; i < w.slots; ++i) wp->view_of[i] = 0;
  p.walk_frames.reset();
  p.walk = wp;
  return true;
}

Status draw(Player& p, WalkPlay& w, const WalkPose& pose) {
  Camera cam;
  if (walk_camera(p.header(), pose, &cam) != Status::ok) return Status::malformed;
  const uint16_t* hot = p.walk_geometry.hot();
  const uint32_t n = p.walk_geometry.hot_count();
  for (uint32_t i = 0; i < n; ++i) {
    const Vec3<Q16_16>* tri = p.walk_geometry.triangle(hot[i]);
    for (int k = 0; k < 3; ++k) w.positions[3 * i + static_cast<uint32_t>(k)] = tri[k];
    Mesh& m = w.meshes[i];
    m = Mesh{};
    m.indices = &w.indices[3 * i];
    m.shading = Shading::view_mapped;
    m.filter = Filter::bilinear;
    m.cull = Cull::none;
    const uint8_t v = w.view_of[hot[i]];
    m.texture = &w.view_tex[v];
    m.num_triangles = w.view_ready[v] && plane_homography(cam, w.view_cam[v], tri, &m.view_map) == Status::ok ? 1 : 0;
  }
  DrawList list;
  list.positions = w.positions;
  list.num_positions = 3 * n;
  list.meshes = w.meshes;
  list.num_meshes = n;
  return w.renderer.render(cam, list, 0, render_band, &p);
}

ChunkResult on_chunk(Player& p, uint32_t type, const uint8_t* payload, uint32_t size) {
  const bool walk_chunk = type == chunk::kWalkParams || type == chunk::kWalkView || type == chunk::kWalkFrame ||
                          type == chunk::kImageHeader || type == chunk::kImageData;
  if (!walk_chunk) return ChunkResult::unknown;
  if (p.walk == nullptr) {
    if (type != chunk::kWalkParams) {
      p.fail(Status::malformed, "a walkthrough chunk before WLKP");
      return ChunkResult::abort;
    }
    const uint64_t t0 = p.enter_chunk();
    const bool ok = setup(p, payload, size);
    p.add_decode(p.work_clock() - t0);
    p.leave_chunk();
    return ok ? ChunkResult::consumed : ChunkResult::abort;
  }
  WalkPlay& w = *p.walk;
  const uint64_t t0 = p.enter_chunk();
  ChunkResult result = ChunkResult::consumed;
  const auto refuse = [&](Status s, const char* why) {
    p.fail(s, why);
    result = ChunkResult::abort;
  };
  if (type == chunk::kWalkParams) {
    refuse(Status::malformed, "a second WLKP");
  } else if (type == chunk::kWalkView) {
    uint8_t slot;
    WalkPose pose;
    if (w.pending >= 0) refuse(Status::malformed, "a view update before the last one's image is whole");
    else if (walk_view_from_bytes(payload, size, &slot, &pose) != Status::ok || slot >= w.params.views)
      refuse(Status::malformed, "WVUP is not valid");
    else if (walk_view_camera(p.header(), w.params, pose, &w.pending_cam) != Status::ok)
      refuse(Status::malformed, "WVUP's camera is not valid");
    else {
      w.pending = slot;
      w.image_open = false;
      // The slot's own camera again: a refinement, added to what the slot holds.
      w.pending_refines = w.view_ready[slot] && cameras_equal(w.view_cam[slot], w.pending_cam);
      if (!w.pending_refines) w.view_ready[slot] = false;
    }
  } else if (type == chunk::kImageHeader || type == chunk::kImageData) {
    if (w.pending < 0) {
      refuse(Status::malformed, "an image outside a view update");
    } else {
      const Texture& t = w.view_tex[w.pending];
      if (type == chunk::kImageHeader) {
        ImageHeader ih;
        if (w.image_open || image_header_from_bytes(payload, size, &ih) != Status::ok || ih.width != t.width ||
            ih.height != t.height || ih.chroma != ChromaFormat::yuv420 || ih.region() || (ih.residual() && !w.pending_refines))
          refuse(Status::malformed, "a view's image must be a 4:2:0 image of the frame's size, a residual only refining its own view");
        else
          w.image_open = true;
      }
      if (result == ChunkResult::consumed) {
        uint8_t* y = static_cast<uint8_t*>(const_cast<void*>(t.texels));
        const ImageTarget target =
            ImageTarget::planes(y, t.stride, const_cast<uint8_t*>(t.cb), t.chroma_stride, const_cast<uint8_t*>(t.cr), t.chroma_stride);
        const Status s = w.image_open ? p.image.on_chunk(type, payload, size, target) : Status::malformed;
        if (is_error(s)) {
          refuse(s, "a view's image was refused");
        } else if (s == Status::ok && p.image.done()) {
          w.view_cam[w.pending] = w.pending_cam;
          w.view_ready[w.pending] = true;
          w.pending = -1;
          w.image_open = false;
        }
      }
    }
  } else {  // WFRM: frames, each drawn as it is read
    ArithDecoder d;
    uint32_t frames = 0;
    if (w.pending >= 0) {
      refuse(Status::malformed, "a frame while a view's image is incomplete");
    } else if (d.init(payload, size) != Status::ok || (frames = p.walk_frames.read_count(d, w.params.frames_per_record)) == 0) {
      refuse(d.ok() ? Status::malformed : d.status(), "WFRM was refused");
    }
    for (uint32_t k = 0; k < frames && result == ChunkResult::consumed; ++k) {
      const uint64_t f0 = k == 0 ? t0 : p.work_clock();
      WalkPose pose;
      Status s = p.walk_geometry.decode(d);
      if (s == Status::ok)
        s = p.walk_frames.decode(d, p.walk_geometry.hot(), p.walk_geometry.hot_count(), w.view_of, w.params.views, &pose);
      if (s == Status::ok && k + 1 == frames) s = d.finish();
      p.add_decode(p.work_clock() - f0);
      if (s != Status::ok) {
        refuse(s, "WFRM was refused");
      } else if (!p.begin_frame()) {
        result = ChunkResult::abort;
      } else {
        const uint64_t display_before = p.display_total();
        const uint64_t d0 = p.work_clock();
        const Status ds = draw(p, w, pose);
        p.add_display((p.work_clock() - d0) - (p.display_total() - display_before));
        if (ds != Status::ok) refuse(ds, "the frame could not be drawn");
        else if (!p.end_frame()) result = ChunkResult::abort;
      }
    }
    p.leave_chunk();
    return result;
  }
  p.add_decode(p.work_clock() - t0);
  p.leave_chunk();
  return result;
}

// Frames complete at WFRM chunks, up to WLKP's frames-per-record each (one
// a chunk until WLKP is read): no more chunks than that many fit the room.
size_t feed_limit(const Player& p, uint32_t frames_room) {
  const uint32_t per_chunk = p.walk != nullptr ? p.walk->params.frames_per_record : 1u;
  return detail::chunk_per_frame_feed_limit(frames_room / per_chunk);
}

}  // namespace

size_t Player::walk_workspace_bytes(const StreamHeader& h, const WalkParams& w, const PlayerConfig& c) {
  const RenderConfig rc = render_config(h, w, c);
  // Each allocation of setup() with its worst alignment slack.
  return sizeof(WalkPlay) + alignof(WalkPlay) + WalkGeometry::workspace_bytes(w.slots) + ImageDecoder::kWorkspaceBytes +
         render_workspace_size(rc) + w.slots * sizeof(Mesh) + alignof(Mesh) + 3u * w.slots * sizeof(Vec3<Q16_16>) +
         alignof(Vec3<Q16_16>) + 3u * w.slots * sizeof(uint16_t) + alignof(uint16_t) + w.slots +
         w.views * (plane_bytes(h) + 4);
}

namespace detail {
extern const PlayerMode kWalkMode;
const PlayerMode kWalkMode{StreamMode::walkthrough, start, on_chunk, feed_limit};
}  // namespace detail

}  // namespace vds
