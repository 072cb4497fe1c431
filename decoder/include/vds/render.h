// vds client library: the fixed-point scanline renderer. Transform and
// projection, clipping, exact sub-pixel edge walking with the top-left fill
// rule, perspective-correct attributes by rational linear interpolation with a
// per-pixel reciprocal, bilinear filtering, a 16- or 32-bit z-buffer, flat and
// Gouraud shading, output by horizontal bands to a display callback.
// Design, error bounds and costs: docs/renderer.md. The host reference in
// double is vds/enc/ref_render.h.
//
// ===========================================================================
// CONVENTIONS (the contract; tests/unit/render*_test.cpp check it)
// ---------------------------------------------------------------------------
// Spaces: see vds/render_camera.h. World positions are Q16.16 units; camera
//   space is x right, y down, z forward; pixel (i, j) covers [i, i+1) x
//   [j, j+1) with its centre at (i + 1/2, j + 1/2), y downward.
// Q formats: positions Q16.16 (world and camera space; the camera-relative
//   position R (P - C) must stay within +-32767 units); rotation Q2.30;
//   focal lengths and principal point Q16.16 pixels; projected vertices Q24.8
//   pixels (1/256-pixel sub-pixel precision); texture coordinates Q16.16
//   texels; colours 0x00RRGGBB with 8 bits per channel.
// Depth: the renderer interpolates q = round(2^30 near_z / z) (1/z, linear in
//   screen space) and stores q (DepthFormat::d32) or q >> 14 (d16). Larger is
//   nearer; a pixel is drawn only if its value is strictly greater than the
//   stored one (ties keep the first triangle drawn). A frame starts at 0.
// Clipping: triangles are clipped against near_z <= z <= far_z and a guard
//   band 4000 pixels around the principal point, in camera space; every
//   intersection is computed from the inside end of the edge, so an edge
//   shared by two triangles is clipped to the same point in both. Pixels are
//   then limited to the screen and to the band by exact span limits.
// Fill rule (top-left): a pixel is drawn iff its centre lies strictly inside
//   the projected triangle, or exactly on a left edge or a horizontal top
//   edge. The test is exact integer arithmetic on the Q24.8 vertices (no
//   epsilon), so triangles that share an edge never both draw a pixel and
//   leave no gap between them; a triangle of zero area draws nothing.
// Facing: a triangle whose projected vertices run counter-clockwise as seen
//   on the display ((x1-x0)(y2-y0) - (x2-x0)(y1-y0) < 0 with y down) is
//   front-facing, i.e. (P1-P0) x (P2-P0) points toward the camera.
// Attributes: texture coordinates and Gouraud colours are interpolated
//   perspective-correctly, u = (a x + b y + c) / (g x + h y + i) per pixel,
//   with one reciprocal per pixel (vds::recip_mant_fast, relative error below
//   2^-17.9) and exact span start values. A view-mapped mesh takes (a..i)
//   from its homography instead of from vertex coordinates.
// Sampling: texel (i, j) covers [i, i+1) x [j, j+1). Nearest takes the texel
//   containing (u, v); bilinear blends the four texels around (u - 1/2,
//   v - 1/2) with 8-bit weights (rgb888 output) or 5-bit weights (rgb565
//   output). Addressing wraps (repeat; power-of-two sizes only, others are
//   clamped) or clamps to the edge texels. Texel reads never leave the texture.
// Bands: the frame is drawn in horizontal bands of band_height rows (the last
//   may be shorter); a band is cleared, every triangle is drawn into it and
//   the band is handed to the BandSink. Nothing is ever written outside the
//   current band of the colour and depth buffers, and the result does not
//   depend on the band height.
// Memory: all from the caller's workspace (vds::Arena); no heap, no float.
//   Every input is validated: bad indices, cameras or textures give a status,
//   any other value (hostile coordinates, degenerate triangles) gives a
//   picture, never an out-of-bounds access or undefined behaviour.
// ===========================================================================
#pragma once
#include <cstddef>
#include <cstdint>

#include "vds/arena.h"
#include "vds/fixed.h"
#include "vds/homography.h"
#include "vds/render_camera.h"
#include "vds/status.h"

namespace vds {

constexpr int kRenderMaxSize = 2048;         // width and height limit (pixels)
constexpr int kRenderGuardBandPx = 4000;     // guard band half-width around (cx, cy), pixels
constexpr int kRenderSubpixelBits = 8;       // projected vertices in Q24.8
constexpr int kTextureMaxSize = 4096;        // texture width / height limit (texels)

enum class PixelFormat : uint8_t {
  rgb565 = 0,  // uint16_t per pixel, native endian, R in bits 15..11, G 10..5, B 4..0
  rgb888 = 1,  // 3 bytes per pixel: R, G, B
};
constexpr int bytes_per_pixel(PixelFormat f) { return f == PixelFormat::rgb565 ? 2 : 3; }

enum class DepthFormat : uint8_t {
  d16 = 0,  // uint16_t per pixel: q >> 14
  d32 = 1,  // uint32_t per pixel: q
};
constexpr int bytes_per_depth(DepthFormat f) { return f == DepthFormat::d16 ? 2 : 4; }

enum class TexFormat : uint8_t {
  rgb565 = 0,    // uint16_t texels as PixelFormat::rgb565; channels widened to 8 bits by bit replication
  xrgb8888 = 1,  // uint32_t texels 0x00RRGGBB (top byte ignored)
  ycbcr420 = 2,  // 8-bit Y' plane at full size and Cb, Cr planes at half size (rounded up) in
                 // each direction, chroma centred between luma samples (JPEG/JFIF siting),
                 // full-range BT.601 (JFIF) conversion to R'G'B'
};

enum class TexAddress : uint8_t {
  repeat = 0,  // coordinates wrap; needs power-of-two width and height (else treated as clamp)
  clamp = 1,   // coordinates clamp to the edge texels
};

// bilinear_luma: a Y'CbCr 4:2:0 texture's luma bilinear, its chroma from
// the chroma texel the sample point lies in (about a fifth fewer
// instructions a pixel than bilinear on the Cortex-M4; the eye resolves
// chroma at half the luma's detail anyway); other formats: bilinear.
enum class Filter : uint8_t { nearest = 0, bilinear = 1, bilinear_luma = 2 };

enum class Shading : uint8_t {
  flat = 0,         // Mesh::color
  gouraud = 1,      // Mesh::colors per vertex
  texture = 2,      // Mesh::texture at Mesh::uvs per vertex
  view_mapped = 3,  // Mesh::texture (a stored view) at Mesh::view_map(pixel), or Mesh::views per triangle
  mesh_colors = 4,  // Mesh::surface: samples on each face's lattice (nearest or linear)
};

enum class Cull : uint8_t { none = 0, back = 1, front = 2 };

struct Texture {
  TexFormat format = TexFormat::rgb565;
  TexAddress address = TexAddress::repeat;
  uint16_t width = 0;   // 1..4096 texels
  uint16_t height = 0;  // 1..4096 texels
  uint32_t stride = 0;  // texels (rgb565, xrgb8888) or bytes (Y' plane) per row, >= width
  const void* texels = nullptr;  // rgb565: uint16_t; xrgb8888: uint32_t; ycbcr420: the Y' plane
  const uint8_t* cb = nullptr;   // ycbcr420 only: (width + 1) / 2 x (height + 1) / 2
  const uint8_t* cr = nullptr;
  uint32_t chroma_stride = 0;    // ycbcr420 only: bytes per chroma row
  // rgb565 and xrgb8888: the array holds one more column (index width, so
  // stride >= width + 1) and one more row (index height) repeating column 0
  // and row 0 (repeat addressing) or the last column and row (clamp);
  // texture_fill_apron() writes them. Bilinear filtering then reads the
  // right and lower neighbours directly: about 10 instructions less per
  // pixel on Cortex-M4 (docs/renderer.md).
  bool apron = false;
};

// Writes the apron of an rgb565 or xrgb8888 texture whose texel array
// (height + 1 rows of stride >= width + 1 texels) is `texels`, the same
// memory as t.texels, and sets t.apron. invalid_argument if the texture
// cannot have one.
Status texture_fill_apron(Texture& t, void* texels);

struct TexCoord {
  Q16_16 u, v;  // texels
};

// Shading::mesh_colors (mesh colors, vds/mesh_colors.h): a face of
// resolution R = 2^res_log2 has its samples at lattice points (i, j),
// i, j >= 0, i + j <= R, barycentric ((R - i - j) / R, i / R, j / R) on its
// corners (a, b, c). Where they lie in the surface's planes:
//   (0, 0), (R, 0), (0, R)   vertex[0], vertex[1], vertex[2];
//   edge k (corner k -> corner k + 1; lattice step p = i, j, R - j from
//   corner k on edges 0, 1, 2)  edge_base[k] + p * edge_step[k];
//   the rest                 face_base + the row offset of j + i - 1, row j
//                            (1 .. R - 2) holding i = 1 .. R - 1 - j.
// Filter::nearest takes the lattice point nearest in (i, j); the others
// the linear filter of the mesh colors paper: the three samples of the
// lattice triangle holding the point, weighted barycentrically (8 bits).
// A face whose indices reach outside the planes is not drawn.
struct LatticeFace {
  uint32_t vertex[3];
  uint32_t edge_base[3];
  int32_t edge_step[3];
  uint32_t face_base;
  uint8_t res_log2;  // 0..10
};

// Shading::view_mapped with a view per face: face t of the mesh (its
// number in the mesh's order), whose first corner is vertex `first`, is
// drawn from *tex at homography *out, asked once per polygon set-up, so a
// caller holding many faces keeps no homography per face (it may keep
// some: the answer must be the same each time it is asked in a frame).
// false leaves the face undrawn. Every texture it gives has
// Mesh::texture's format, address mode, apron, size and strides (a
// texture that differs is not drawn).
//
// Optional `point`, for a renderer with RenderConfig::point_face_span: a
// small face is drawn in one colour, the texture's sample at texel
// position (*u_q8, *v_q8) (Q24.8, the homography's pixel positions: a
// texel's centre at +0.5; sampled as the mesh's filter samples) that
// `point` gives for it, so it costs no homography and no texture set-up.
// Asked once per polygon set-up, with the same answer each time in a
// frame; false asks `map` instead. Y'CbCr 4:2:0 textures with clamp
// addressing only (for any other form `map` is asked).
struct ViewMapSource {
  bool (*map)(void* ctx, uint32_t t, uint32_t first, const Texture** tex, Homography* out) = nullptr;
  void* ctx = nullptr;
  bool (*point)(void* ctx, uint32_t t, uint32_t first, const Texture** tex, int32_t* u_q8, int32_t* v_q8) = nullptr;
};

struct MeshColorsSurface {
  const uint8_t* y = nullptr;  // Y', Cb, Cr planes (JFIF full range), `samples` each
  const uint8_t* cb = nullptr;
  const uint8_t* cr = nullptr;
  uint32_t samples = 0;
  // Fills `out` for triangle t of the mesh (its index in Mesh::indices / 3),
  // once per polygon set-up; false leaves the triangle undrawn.
  bool (*face)(const void* ctx, uint32_t t, LatticeFace* out) = nullptr;
  const void* ctx = nullptr;
};

// The most corners a face of a mesh may have (Mesh::corners).
constexpr int kMaxFaceCorners = 4;

// Faces that share one material: triangles, or with `corners` convex
// planar polygons of 3 to kMaxFaceCorners corners (drawn as one polygon:
// one set-up, one view homography). Vertex attributes (colors, uvs) are
// indexed by the same vertex index as DrawList::positions.
// (The fields are ordered so that a 64-bit host packs them in 104 bytes.)
struct Mesh {
  const uint16_t* indices = nullptr;  // each face's corners in turn, each < DrawList::num_positions
  // Per face its number of corners, 3..kMaxFaceCorners; nullptr: 3 each.
  // Not with Shading::mesh_colors (its faces are triangles).
  const uint8_t* corners = nullptr;
  Shading shading = Shading::flat;
  Filter filter = Filter::bilinear;
  Cull cull = Cull::back;
  uint32_t color = 0;                  // flat
  const uint32_t* colors = nullptr;    // gouraud: 0x00RRGGBB per vertex
  const TexCoord* uvs = nullptr;       // texture: per vertex
  const Texture* texture = nullptr;    // texture, view_mapped
  Homography view_map{};               // view_mapped: screen pixel -> texel (plane_homography(screen, view))
  uint32_t num_triangles = 0;          // faces (triangles unless `corners` says otherwise)
  const ViewMapSource* views = nullptr;  // view_mapped: instead of texture and view_map per face (texture: their form)
  const MeshColorsSurface* surface = nullptr;  // mesh_colors
};

struct DrawList {
  const Vec3<Q16_16>* positions = nullptr;  // world positions shared by all meshes
  uint32_t num_positions = 0;               // <= 65536
  const Mesh* meshes = nullptr;
  uint32_t num_meshes = 0;
  // Instead of `positions` (which is then nullptr): unsigned grid
  // coordinates, x, y, z per vertex, taken to world as
  // (g << grid_shift) + grid_origin (Q16.16 raw, saturated), so a mesh
  // decoder's own positions are drawn without a converted copy.
  const uint16_t* grid = nullptr;
  uint8_t grid_shift = 0;  // 0..15
  Vec3<Q16_16> grid_origin{};
};

struct RenderConfig {
  uint16_t width = 0;        // 1..2048
  uint16_t height = 0;       // 1..2048
  uint16_t band_height = 0;  // 1..height rows per band; height = whole frame in one band
  PixelFormat format = PixelFormat::rgb565;
  DepthFormat depth = DepthFormat::d16;
  // Projected vertices kept per frame (13 bytes each). Vertices with a higher
  // index are transformed again for each band they are needed in: a
  // RAM/time trade-off, the picture is the same.
  uint32_t vertex_cache = 0;
  // Triangles whose band range is found once per frame (4 bytes each, counted
  // over the meshes in order): a band then skips them with two compares
  // instead of testing their vertices. Needs their vertices in the vertex
  // cache; others are tested per band. A RAM/time trade-off, same picture.
  uint32_t triangle_cache = 0;
  // Set-up polygons kept for the later bands they cross (the bytes per
  // entry: render_workspace_size). Only triangles that reach below the
  // current band are kept, first come first served, and an entry is freed
  // after the last band its polygon touches, so a large triangle is clipped
  // and set up once per frame instead of once per band. 0..4096; a RAM/time
  // trade-off, same picture.
  uint32_t setup_cache = 0;
  // Small faces in one colour: a textured or view-mapped face of a Y'CbCr
  // 4:2:0 texture whose outline spans at most this many pixel columns and
  // rows is drawn flat, in its texture's sample at one point (a textured
  // face's: the mean of its corners' texture coordinates; a view-mapped
  // face's: ViewMapSource::point's, if the source has one). 0: none. A
  // time/picture trade-off (a face of a few pixels looks the same flat).
  uint8_t point_face_span = 0;
  // Optional caller-owned whole-frame colour buffer (height rows of
  // target_stride bytes). When set, bands are drawn straight into it and the
  // workspace holds no colour band. When null, the band lives in the workspace.
  uint8_t* target = nullptr;
  uint32_t target_stride = 0;
};

// One finished band, valid during the BandSink call.
struct Band {
  const uint8_t* pixels;  // row `y` of the frame
  uint32_t stride;        // bytes between rows
  uint16_t y;             // first row
  uint16_t height;        // rows in this band
  uint16_t width;
  PixelFormat format;
};

// Returns false to stop the frame: Renderer::render then returns Status::aborted.
using BandSink = bool (*)(void* ctx, const Band& band);

struct RenderStats {
  uint32_t triangles = 0;        // triangles submitted (once per frame)
  uint32_t culled = 0;           // facing or zero-area rejections (each band counts)
  uint32_t clipped = 0;          // triangle-band pairs that took the clipping path
  uint32_t setups = 0;           // polygon set-ups (per band it is drawn in, unless kept by setup_cache)
  uint32_t spans = 0;            // non-empty spans
  uint32_t pixels = 0;           // pixels rasterised (before the depth test)
  uint32_t reprojected = 0;      // vertex transforms beyond the cache
};

// Workspace bytes init() needs for `cfg` (alignment included); 0 if cfg is invalid.
size_t render_workspace_size(const RenderConfig& cfg);

namespace detail {
struct RenderFrame;  // per-frame state (render.cpp)
struct CachedVertex {
  int32_t x, y;  // Q24.8 pixels
  int32_t q;     // 2^30 near / z
};
}  // namespace detail

class Renderer {
 public:
  Renderer() = default;

  // Validates cfg (invalid_argument) and carves the band colour buffer (unless
  // cfg.target is set), the band depth buffer and the vertex cache from
  // `arena` (workspace_too_small).
  Status init(const RenderConfig& cfg, Arena& arena);

  // Draws one frame. invalid_argument: not initialised, a bad camera, a
  // texture that breaks the limits of Texture, or no sink and no target;
  // malformed: an index >= num_positions, a missing attribute array, or more
  // than 65536 positions. aborted: the sink returned false. Nothing is drawn
  // when validation fails.
  Status render(const Camera& cam, const DrawList& list, uint32_t clear_color, BandSink sink, void* ctx);

  const RenderStats& stats() const { return stats_; }
  const RenderConfig& config() const { return cfg_; }

 private:
  friend struct detail::RenderFrame;
  RenderConfig cfg_{};
  uint8_t* color_ = nullptr;  // band buffer (or the target)
  uint32_t color_stride_ = 0;
  void* depth_ = nullptr;     // band_height rows of width entries
  detail::CachedVertex* cache_ = nullptr;
  uint8_t* cache_outcode_ = nullptr;
  uint16_t* tri_bands_ = nullptr;  // [first, last] band of each cached triangle
  // The set-up cache: setup_cache slots of setup_bytes_ each, the entries
  // kept for the next band as (triangle number + 1, slot) sorted by triangle
  // (a band finds them with one compare per triangle), entries made in the
  // current band stored from the end of the same arrays, a second pair of
  // arrays to merge into, and a stack of free slots.
  uint8_t* setups_ = nullptr;
  uint32_t* setup_tags_ = nullptr;
  uint16_t* setup_slots_ = nullptr;
  uint32_t* setup_tags2_ = nullptr;
  uint16_t* setup_slots2_ = nullptr;
  uint16_t* setup_free_ = nullptr;
  uint32_t setup_bytes_ = 0;
  RenderStats stats_{};
  bool ready_ = false;
};

}  // namespace vds
