// vds client library: the model mode's picture. Draws the mesh a
// MeshDecoder holds — after its base and after every level — as a shaded
// surface seen from a camera that orbits it, through the scanline renderer,
// band by band. Integer only; every buffer comes from the caller's arena.
//
// Framing depends only on the quantisation grid, not on the current level,
// so the model keeps its size and place while it refines: the grid's centre
// is the origin, 2^bits grid steps span two world units, the stream's up
// axis (MeshUp, +y unless MSHH says otherwise) is up, and the
// camera sits 3.2 units from the centre, 20 degrees above the horizon,
// looking at it. Shading is per vertex (Gouraud): an ambient term plus a
// two-sided diffuse term from a light above and to the left of the camera,
// with each vertex normal the sum of its faces' cross products. Details in
// docs/renderer.md ("Model view").
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/arena.h"
#include "vds/container.h"
#include "vds/mesh.h"
#include "vds/render.h"
#include "vds/status.h"

namespace vds {

// The camera's distance from the grid's centre, Q16.16 world units (3.2;
// its focal length is the frame height in pixels).
constexpr int32_t kModelViewDistanceQ16 = 3 * 65536 + 13107;

struct ModelViewConfig {
  uint16_t width = 0;   // frame size, pixels (1..2048)
  uint16_t height = 0;
  uint16_t band_height = 16;
  // The renderer's caches (RenderConfig), clamped to the mesh's counts:
  // projected vertices (13 bytes each), triangles' band ranges (4 bytes
  // each) and set-ups kept across bands. Smaller ones cost time — without
  // the first two every band re-tests and re-projects the whole mesh —
  // and never change the picture.
  uint32_t vertex_cache = UINT32_MAX;
  uint32_t triangle_cache = UINT32_MAX;
  uint32_t setup_cache = 16;
  // The grid axis shown up (the stream's MSHH says; start_model sets it).
  MeshUp up = MeshUp::y_plus;
  uint32_t surface_rgb = 0xD8C8A8;    // 0x00RRGGBB at full light
  uint32_t background_rgb = 0x182028;
};

class ModelView {
 public:
  // Bytes init() carves for meshes of up to max_vertices (<= 65,535) and
  // max_triangles; 0 if the configuration is invalid.
  static size_t workspace_bytes(const ModelViewConfig& cfg, uint32_t max_vertices, uint32_t max_triangles);

  // invalid_argument for a bad configuration or more than 65,535 vertices;
  // workspace_too_small if the arena cannot hold the buffers.
  Status init(const ModelViewConfig& cfg, Arena& arena, uint32_t max_vertices, uint32_t max_triangles);

  // Draws `mesh` with the camera at orbit angle `angle` (2^-16 turn, about
  // the vertical axis) and hands each finished band (RGB565) to `sink`.
  // invalid_argument before init, for a mesh larger than init's counts or
  // one whose MeshState was initialised for more than 65,535 vertices (its
  // triangles are then 32-bit: MeshState::triangles16).
  // With `colors` (mesh colors of this mesh's triangles, vds/mesh_colors.h)
  // the surface is drawn unlit in its own colours, with `filter` (nearest
  // or the linear filter), instead of shaded.
  Status draw(const MeshState& mesh, uint16_t angle, BandSink sink, void* ctx,
              const MeshColorsSurface* colors = nullptr, Filter filter = Filter::bilinear);

  // The camera and the grid's placement draw() uses for `mesh` at `angle`:
  // world = (grid << grid_shift) + grid_origin (DrawList's grid fields).
  // invalid_argument for a mesh draw() would refuse.
  Status camera(const MeshState& mesh, uint16_t angle, Camera* cam, uint8_t* grid_shift, Vec3<Q16_16>* grid_origin) const;

  // Changes the axis shown up for later frames (e.g. once MSHH is in).
  void set_up(MeshUp up) { cfg_.up = up; }
  const RenderStats& stats() const { return renderer_.stats(); }

 private:
  ModelViewConfig cfg_{};
  Renderer renderer_;
  uint32_t* colors_ = nullptr;
  uint32_t cap_v_ = 0, cap_t_ = 0;
  bool ready_ = false;
};

// --- What a client holds of a model stream ----------------------------------------
// A model stream is progressive, so a client smaller than HEAD's
// workspace_bytes (the full resolution) can still play it: up to the last
// level that fits, with later levels skipped (MeshDecoder::capacity_reached).
struct ModelCapacity {
  uint32_t vertices = 0;   // the most the mesh holds
  uint32_t triangles = 0;  // the most any level with that many vertices has
  size_t bytes = 0;        // what the mesh decoder and the view carve for them
};

// The most a client with `bytes` of workspace holds of the model whose mesh
// header is `h`: MeshDecoder::init, its Huffman tables and base scratch, and
// ModelView::init, all for `vertices` and `triangles` = base triangles plus
// two per vertex above the base (no split adds more), at most the stream's
// counts and 65,535 vertices (the view's limit). For a version-2 stream the
// whole tail when it fits (the counts with its dummies, its contexts and
// border), else the split levels that fit. workspace_too_small when not
// even the base fits (then `out->bytes` is what the base needs),
// unsupported_feature for a base above the view's limit, invalid_argument for
// a bad configuration.
Status plan_model_capacity(const MeshHeader& h, const ModelViewConfig& cfg, size_t bytes, ModelCapacity* out);

// A client's set-up when a model stream's MSHH arrives (pass it to
// mesh.consume() next): parses it, plans for what `arena` has left, then
// initialises `mesh` and `view` for that capacity, the view with the
// stream's up axis in place of cfg.up. The status of the first
// step that fails; `cap` says what was planned.
Status start_model(Arena& arena, const uint8_t* mshh, uint32_t size, const ModelViewConfig& cfg, MeshDecoder& mesh,
                   ModelView& view, ModelCapacity* cap);

// When the model mode draws, for the client firmware, its host replay
// (`vds frames`) and the mesh benchmark alike: once the base mesh is in and
// after every level completed since the previous frame, with the camera a
// further kModelOrbitStep round the model each frame.
constexpr uint16_t kModelOrbitStep = 65536 / 64;  // 1/64 turn

// A model stream's orbit script: MORB chunks anywhere after the base mesh,
// each a u16 angle (2^-16 turn round the up axis): one frame of the model
// as the client holds it, seen from there. (One frame a chunk, as every
// model chunk: a client's back-pressure counts on it.)
constexpr uint32_t kModelOrbitChunk = fourcc('M', 'O', 'R', 'B');
constexpr uint32_t kModelOrbitMaxFrames = 4096;  // what vds encode-model --orbit writes at most

struct ModelFrames {
  uint32_t drawn = 0;   // frames drawn so far
  uint32_t levels = 0;  // levels complete when the last one was drawn

  // True when the decoder holds a mesh no frame has shown yet.
  bool due(const MeshDecoder& d) const { return d.drawable() && (drawn == 0 || d.levels_done() > levels); }
  // The orbit angle of the next frame (2^-16 turn).
  uint16_t angle() const { return static_cast<uint16_t>(drawn * kModelOrbitStep); }
  // Records that the decoder's current mesh has been drawn.
  void mark_drawn(const MeshDecoder& d) {
    ++drawn;
    levels = d.levels_done();
  }
};

}  // namespace vds
