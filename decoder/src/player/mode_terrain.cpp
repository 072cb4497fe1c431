// Player mode "terrain": view-dependent DCT texture over an elevation grid
// (vds/terrain.h, vds/terrain_client.h; docs/terrain.md, "The client").
//
// State: the elevation, the block store (masks and quantised coefficients
// as the updates leave them), the DC plane (one texel per block: the
// block's own DC where it holds one, else its sample of its level-1
// block's plane), a half-resolution window (2 x 2 texels a cell for
// 2^n x 2^n cells, slot = cell mod window) and a cache of transformed
// blocks for a window of 2^m x 2^m cells.
//
// A frame: the grid in patches of P x P cells, each patch outside the view
// dropped, the rest drawn at a step of 1, 2, 4 ... P cells (geomipmapping:
// from the coarsest step, the patch whose height error shows most on
// screen refined first, while the frame's geometry budget lasts and the
// error is over kLodPx pixels), nearest first, textured with the half-resolution window where its
// slots are free, else the DC plane; patches at step 1 draw each cell
// whose luma block the store holds with the block's own texels (the
// integer IDCT of its held coefficients, done again only when the block
// changes or leaves the cache) as long as its cache slots are free this
// frame and max_cells allows. Where two patches of different steps meet,
// the coarser edge could leave a crack: every edge whose neighbour is
// drawn at another step hangs a skirt (the edge copied down by the
// patch's height range) that covers it.
#include "vds/bytes.h"
#include "vds/fixed.h"
#include "vds/idct.h"
#include "vds/player.h"
#include "vds/render.h"
#include "vds/terrain_client.h"

namespace vds {

namespace {

using terrain::BlockGrid;
using terrain::Mask;

// A frame's budgets (beyond them patches coarsen) come from TERH's frame
// budget n: 512 n ground vertices, 512 n ground triangles, 256 n skirt
// triangles (ground_vertices() ...). Every visible patch fits at its
// coarsest step (n >= 2): at most 64 patches of 12 vertices, 2 ground and
// 8 skirt triangles each.
constexpr int kMaxPatchesSide = 8;
constexpr int kMaxStepLog2 = 7;  // patches of up to 128 cells (grids up to 1,024 cells a side)
constexpr int32_t kLodPx = 1;  // the largest height error a step may show, pixels
constexpr uint32_t kNoTag = 0xFFFFFFFFu;
constexpr uint16_t kNoHalf = 0xFFFF;
constexpr uint32_t kSky = 0;  // where no ground is drawn (black, as the reference renderer)

}  // namespace

struct TerrainPlay {
  terrain::Params params;
  BlockGrid grid;
  terrain::BlockStore store;
  Renderer renderer;
  int pw = 0, ph = 0;  // points
  uint16_t* heights = nullptr;
  bool coarse_in = false;
  int fine_next = 0;  // the next fine row expected
  // Patches: P x P cells each, at most 16 a side.
  int patch = 8, patches_x = 0, patches_y = 0;
  uint16_t *patch_lo = nullptr, *patch_hi = nullptr;
  // Per patch and step 2^l (l = 1 .. kMaxStepLog2): the largest height
  // error (elevation levels) drawing it at that step makes.
  uint16_t* patch_err = nullptr;
  uint8_t* patch_step = nullptr;  // this frame's step (0: not drawn)
  int32_t* patch_z = nullptr;     // nearest camera depth, raw Q16.16
  int64_t* patch_px = nullptr;    // this frame: its height error on screen at its step
  uint16_t* order = nullptr;      // visible patches, nearest first
  // The DC plane: one texel a level-0 block.
  uint8_t *dc_y = nullptr, *dc_cb = nullptr, *dc_cr = nullptr;
  Texture dc_tex;
  // The flight's keys.
  WalkPose* keys = nullptr;
  uint32_t key_count = 0, spacing = 0;
  // The viewer's own pose once its controls have moved it (steer()).
  bool steering = false;
  WalkPose steered{};
  // Transformed blocks: luma slots W x W, chroma (W/2) x (W/2) per component.
  uint32_t win = 0, cwin = 0;
  uint32_t* ytag = nullptr;
  uint8_t* ytex = nullptr;
  uint32_t* ctag = nullptr;  // [2][cwin^2]
  uint8_t* ctex = nullptr;
  uint32_t* yclaim = nullptr;  // the frame stamp a slot was claimed at
  uint32_t* cclaim = nullptr;
  uint32_t* cowner = nullptr;  // the Cb block that claimed a chroma slot this frame
  uint32_t stamp = 0;
  // The half-resolution window: 2 x 2 luma texels and one chroma texel a
  // cell for hwin x hwin cells (slot = cell mod hwin), a texture the
  // renderer samples with repeat addressing. A slot's tag is the cell's
  // (i / hwin, j / hwin) in a byte each (kNoHalf: empty).
  uint32_t hwin = 0;
  uint8_t *hy = nullptr, *hcb = nullptr, *hcr = nullptr;
  uint16_t* htag = nullptr;
  uint16_t* hclaim = nullptr;  // the low 16 bits of the frame stamp a slot was claimed at
  Texture half_tex;
  // Draw buffers.
  uint32_t max_vertices = 0;
  Vec3<Q16_16>* pos = nullptr;
  TexCoord* uv = nullptr;
  uint16_t* ground_idx = nullptr;  // ground_triangles() * 3
  uint16_t* skirt_idx = nullptr;   // skirt_triangles() * 3
  uint16_t* cell_idx = nullptr;    // max_cells * 6
  Mesh* meshes = nullptr;          // one per textured cell, then half, ground, half skirts, skirts
  Texture* cell_tex = nullptr;
};

namespace {

int patch_size(const terrain::Params& t) {
  const int side = t.cells_x > t.cells_y ? t.cells_x : t.cells_y;
  int p = 8;
  while (p * kMaxPatchesSide < side) p *= 2;
  return p;
}

uint32_t ground_vertices(const terrain::Params& t) { return 512u * t.frame_budget; }
uint32_t ground_triangles(const terrain::Params& t) { return 512u * t.frame_budget; }
// Faces spanning at most 8 pixel columns and rows are drawn in one colour
// (RenderConfig::point_face_span): the client's frames within 0.05 dB of
// every face mapped on the benchmark flights, 0.5 to 2.7 % fewer Cortex-M4
// instructions a frame (16: 8 % fewer drawing, up to 0.29 dB less;
// docs/terrain.md).
constexpr uint8_t kTerrainPointFaceSpan = 8;
uint32_t skirt_triangles(const terrain::Params& t) { return 256u * t.frame_budget; }

RenderConfig render_config(const StreamHeader& h, const terrain::Params& t, const PlayerConfig& c) {
  RenderConfig rc = detail::band_render_config(h, c, ground_vertices(t) + 4u * t.max_cells,
                                               ground_triangles(t) + skirt_triangles(t) + 2u * t.max_cells);
  rc.point_face_span = kTerrainPointFaceSpan;
  return rc;
}

uint32_t half_window(const terrain::Params& t) { return t.half_log2 == 0 ? 0u : 1u << t.half_log2; }
size_t half_bytes(const terrain::Params& t) {
  const size_t h = half_window(t);
  return h * h * (4 + 2 + 2 + 2) + 16;
}

// Every allocation of setup() with its alignment slack.
size_t workspace(const StreamHeader& h, const terrain::Params& t, const PlayerConfig& c) {
  const BlockGrid g = terrain::params_grid(t);
  const size_t points = (size_t{t.cells_x} + 1) * (t.cells_y + 1u);
  const int p = patch_size(t);
  const size_t patches = static_cast<size_t>((t.cells_x + p - 1) / p) * ((t.cells_y + p - 1) / p);
  const size_t luma = size_t{t.cells_x} * t.cells_y, chroma = size_t{g.plane_blocks(0, 1)};
  const size_t win = size_t{1} << t.cache_log2, cwin = win / 2;
  const size_t vertices = ground_vertices(t) + 4u * t.max_cells;
  return sizeof(TerrainPlay) + 8 + terrain::BlockStore::workspace_bytes(t.store_units) + 4 +
         render_workspace_size(render_config(h, t, c)) + 2 * points + 2 + patches * (2 + 2 + 1 + 4 + 8 + 2 + 2 * (kMaxStepLog2 + 1)) + 26 +
         luma + 2 * chroma + 4 + terrain::kMaxFlightKeys * sizeof(WalkPose) + 4 + win * win * (4 + 64 + 4) + 12 +
         2 * cwin * cwin * (4 + 64) + cwin * cwin * 8 + 16 + vertices * (sizeof(Vec3<Q16_16>) + sizeof(TexCoord)) + 8 +
         (ground_triangles(t) + skirt_triangles(t) + 2u * t.max_cells) * 6 + 6 +
         (4u + t.max_cells) * sizeof(Mesh) + 8 + t.max_cells * sizeof(Texture) + 8 + half_bytes(t);
}

bool start(Player& p, const StreamHeader& h) {
  p.terrain = nullptr;
  return detail::header_has_camera_and_frames(p, h, "a terrain stream needs a camera and a frame count in its header");  // set up at TERH
}

bool setup(Player& p, const uint8_t* payload, uint32_t size) {
  terrain::Params t;
  if (terrain::params_from_bytes(payload, size, &t) != Status::ok) {
    p.fail(Status::malformed, "TERH is not valid");
    return false;
  }
  const StreamHeader& h = p.header();
  const size_t need = workspace(h, t, p.config());
  PlayerPlan plan = p.plan();
  plan.known = true;
  plan.needs = need;
  plan.available = p.arena().remaining();
  p.set_plan(plan);
  if (need > p.arena().remaining()) {
    p.fail(Status::workspace_too_small, "the terrain's grid, store and caches do not fit the workspace");
    return false;
  }
  Arena& a = p.arena();
  TerrainPlay* tp = static_cast<TerrainPlay*>(a.alloc(sizeof(TerrainPlay), alignof(TerrainPlay)));
  if (tp == nullptr) return false;
  *tp = TerrainPlay{};
  TerrainPlay& w = *tp;
  w.params = t;
  w.grid = terrain::params_grid(t);
  w.pw = t.cells_x + 1;
  w.ph = t.cells_y + 1;
  w.patch = patch_size(t);
  w.patches_x = (t.cells_x + w.patch - 1) / w.patch;
  w.patches_y = (t.cells_y + w.patch - 1) / w.patch;
  const size_t patches = static_cast<size_t>(w.patches_x) * w.patches_y;
  Status s = w.store.init(a, w.grid, t.store_units);
  if (s == Status::ok) s = w.renderer.init(render_config(h, t, p.config()), a);
  w.heights = a.alloc_array<uint16_t>(static_cast<size_t>(w.pw) * w.ph);
  w.patch_lo = a.alloc_array<uint16_t>(patches);
  w.patch_hi = a.alloc_array<uint16_t>(patches);
  w.patch_err = a.alloc_array<uint16_t>(patches * (kMaxStepLog2 + 1));
  w.patch_step = a.alloc_array<uint8_t>(patches);
  w.patch_z = a.alloc_array<int32_t>(patches);
  w.patch_px = a.alloc_array<int64_t>(patches);
  w.order = a.alloc_array<uint16_t>(patches);
  const size_t luma = size_t{t.cells_x} * t.cells_y, chroma = w.grid.plane_blocks(0, 1);
  w.dc_y = a.alloc_array<uint8_t>(luma + 2 * chroma);
  w.keys = a.alloc_array<WalkPose>(terrain::kMaxFlightKeys);
  w.win = 1u << t.cache_log2;
  w.cwin = w.win / 2;
  w.ytag = a.alloc_array<uint32_t>(w.win * w.win);
  w.yclaim = a.alloc_array<uint32_t>(w.win * w.win);
  w.ytex = a.alloc_array<uint8_t>(w.win * w.win * 64);
  w.ctag = a.alloc_array<uint32_t>(2 * w.cwin * w.cwin);
  w.cclaim = a.alloc_array<uint32_t>(w.cwin * w.cwin);
  w.cowner = a.alloc_array<uint32_t>(w.cwin * w.cwin);
  w.ctex = a.alloc_array<uint8_t>(2 * w.cwin * w.cwin * 64);
  w.max_vertices = ground_vertices(t) + 4u * t.max_cells;
  w.pos = a.alloc_array<Vec3<Q16_16>>(w.max_vertices);
  w.uv = a.alloc_array<TexCoord>(w.max_vertices);
  w.ground_idx = a.alloc_array<uint16_t>(3 * (ground_triangles(t) + skirt_triangles(t) + 2u * t.max_cells));
  w.meshes = a.alloc_array<Mesh>(4u + t.max_cells);
  w.hwin = half_window(t);
  if (w.hwin != 0) {
    w.hy = a.alloc_array<uint8_t>(6u * w.hwin * w.hwin);
    w.htag = a.alloc_array<uint16_t>(w.hwin * w.hwin);
    w.hclaim = a.alloc_array<uint16_t>(w.hwin * w.hwin);
    if (!w.hy || !w.htag || !w.hclaim) s = Status::workspace_too_small;
  }
  w.cell_tex = a.alloc_array<Texture>(t.max_cells);
  if (s == Status::ok &&
      (!w.heights || !w.patch_lo || !w.patch_hi || !w.patch_err || !w.patch_step || !w.patch_z || !w.patch_px || !w.order || !w.dc_y || !w.keys ||
       !w.ytag || !w.yclaim || !w.ytex || !w.ctag || !w.cclaim || !w.cowner || !w.ctex || !w.pos || !w.uv || !w.ground_idx ||
       !w.meshes || !w.cell_tex))
    s = Status::workspace_too_small;
  if (s != Status::ok) {
    p.fail(s, "the terrain could not be set up");
    return false;
  }
  w.skirt_idx = w.ground_idx + 3 * ground_triangles(t);
  w.cell_idx = w.skirt_idx + 3 * skirt_triangles(t);
  w.dc_cb = w.dc_y + luma;
  w.dc_cr = w.dc_cb + chroma;
  for (size_t i = 0; i < luma + 2 * chroma; ++i) w.dc_y[i] = 128;
  for (size_t i = 0; i < static_cast<size_t>(w.pw) * w.ph; ++i) w.heights[i] = 0;
  for (uint32_t i = 0; i < w.win * w.win; ++i) w.ytag[i] = kNoTag, w.yclaim[i] = 0;
  for (uint32_t i = 0; i < 2 * w.cwin * w.cwin; ++i) w.ctag[i] = kNoTag;
  for (uint32_t i = 0; i < w.cwin * w.cwin; ++i) w.cclaim[i] = 0, w.cowner[i] = kNoTag;
  if (w.hwin != 0) {
    w.hcb = w.hy + 4u * w.hwin * w.hwin;
    w.hcr = w.hcb + w.hwin * w.hwin;
    for (uint32_t i = 0; i < w.hwin * w.hwin; ++i) w.htag[i] = kNoHalf, w.hclaim[i] = 0;
    Texture& ht = w.half_tex;
    ht.format = TexFormat::ycbcr420;
    ht.address = TexAddress::repeat;
    ht.width = ht.height = static_cast<uint16_t>(2 * w.hwin);
    ht.stride = 2 * w.hwin;
    ht.texels = w.hy;
    ht.cb = w.hcb;
    ht.cr = w.hcr;
    ht.chroma_stride = w.hwin;
  }
  Texture& d = w.dc_tex;
  d.format = TexFormat::ycbcr420;
  d.address = TexAddress::clamp;
  d.width = t.cells_x;
  d.height = t.cells_y;
  d.stride = t.cells_x;
  d.texels = w.dc_y;
  d.cb = w.dc_cb;
  d.cr = w.dc_cr;
  d.chroma_stride = w.grid.plane_w(0, 1);
  p.terrain = tp;
  return true;
}

// --- The DC plane and the block cache --------------------------------------------

uint8_t* dc_texel(TerrainPlay& w, const terrain::BlockPlace& pl) {
  uint8_t* plane = pl.comp == 0 ? w.dc_y : (pl.comp == 1 ? w.dc_cb : w.dc_cr);
  return plane + static_cast<size_t>(pl.by) * w.grid.plane_w(0, pl.comp) + pl.bx;
}

uint8_t to_texel(int dc_level) { return static_cast<uint8_t>(terrain::dc_prediction(dc_level) + 128); }

// The level-1 block `id1`'s plane as the store holds it (0 where it holds nothing).
void coarse_of(const TerrainPlay& w, uint32_t id1, int16_t plane[64]) {
  int16_t lv[64];
  w.store.levels(id1, lv);
  terrain::coarse_plane(lv, w.store.held(id1), w.params.quantiser, plane);
}

uint16_t half_tag(const TerrainPlay& w, int i, int j) {
  return static_cast<uint16_t>((static_cast<uint32_t>(i) >> (w.params.half_log2)) |
                               ((static_cast<uint32_t>(j) >> w.params.half_log2) << 8));
}
uint32_t half_slot(const TerrainPlay& w, int i, int j) {
  return (static_cast<uint32_t>(j) & (w.hwin - 1)) * w.hwin + (static_cast<uint32_t>(i) & (w.hwin - 1));
}

// The half-resolution texels of cells [i0, i0 + n) x [j0, j0 + n) are no
// longer what the store holds.
void half_forget(TerrainPlay& w, int i0, int j0, int n) {
  if (w.hwin == 0) return;
  for (int j = j0; j < j0 + n && j < w.params.cells_y; ++j)
    for (int i = i0; i < i0 + n && i < w.params.cells_x; ++i) {
      const uint32_t slot = half_slot(w, i, j);
      if (w.htag[slot] == half_tag(w, i, j)) w.htag[slot] = kNoHalf;
    }
}

// After a change to block `id`: its DC texel, or (level 1) the texels of
// the level-0 blocks under it that hold nothing; and the cache slot that
// held its texels.
void refresh(TerrainPlay& w, uint32_t id) {
  const terrain::BlockPlace pl = w.grid.place(id);
  const int span = (pl.level == 1 ? 8 : 1) * (pl.comp == 0 ? 1 : 2);  // cells a side the block covers
  half_forget(w, pl.bx * span, pl.by * span, span);
  if (pl.level == 1) {
    int16_t plane[64];
    coarse_of(w, id, plane);
    const int pw = w.grid.plane_w(0, pl.comp), ph = w.grid.plane_h(0, pl.comp);
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x) {
        const int bx = pl.bx * 8 + x, by = pl.by * 8 + y;
        if (bx >= pw || by >= ph) continue;
        const uint32_t id0 = w.grid.id(0, pl.comp, bx, by);
        const terrain::BlockPlace p0{0, pl.comp, static_cast<uint16_t>(bx), static_cast<uint16_t>(by)};
        if (w.store.held(id0) == 0) *dc_texel(w, p0) = to_texel(plane[8 * y + x]);
      }
    return;
  }
  const Mask m = w.store.held(id);
  if (m != 0) {
    int16_t lv[64];
    w.store.levels(id, lv);
    *dc_texel(w, pl) = to_texel(lv[0]);
  } else {
    int sample;
    const uint32_t id1 = w.grid.coarse(id, &sample);
    int16_t plane[64];
    coarse_of(w, id1, plane);
    *dc_texel(w, pl) = to_texel(plane[sample]);
  }
  if (pl.comp == 0) {
    const uint32_t slot = (pl.by & (w.win - 1)) * w.win + (pl.bx & (w.win - 1));
    if (w.ytag[slot] == id) w.ytag[slot] = kNoTag;
  } else {
    const uint32_t slot = (pl.comp - 1u) * w.cwin * w.cwin + (pl.by & (w.cwin - 1)) * w.cwin + (pl.bx & (w.cwin - 1));
    if (w.ctag[slot] == id) w.ctag[slot] = kNoTag;
  }
}

// A block's texels into a cache slot: the IDCT of what it holds, or its DC
// texel where it holds nothing (not kept: the DC plane may change under it).
void fill_block(TerrainPlay& w, uint32_t id, uint32_t* tag, uint8_t* px) {
  if (*tag == id) return;
  const Mask m = w.store.held(id);
  if (m == 0) {
    const uint8_t v = *dc_texel(w, w.grid.place(id));
    for (int i = 0; i < 64; ++i) px[i] = v;
    *tag = kNoTag;
    return;
  }
  int16_t lv[64], coef[64];
  w.store.levels(id, lv);
  terrain::dequantise_held(lv, m, w.params.quantiser, coef);
  idct8x8_put(coef, px, 8);
  *tag = id;
}

// The mean of a 4 x 4 quadrant (qx, qy) of 8 x 8 texels, rounded.
uint8_t quadrant_mean(const uint8_t* px, int qx, int qy) {
  uint32_t sum = 8;
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) sum += px[(4 * qy + y) * 8 + 4 * qx + x];
  return static_cast<uint8_t>(sum >> 4);
}

// Cell (i, j)'s half-resolution texels into its slot: its luma block's
// quadrant means, and its quarter of each chroma block's mean.
void fill_half(TerrainPlay& w, int i, int j) {
  const uint32_t slot = half_slot(w, i, j);
  const uint16_t tag = half_tag(w, i, j);
  if (w.htag[slot] == tag) return;
  uint8_t px[64];
  uint32_t scratch = kNoTag;
  fill_block(w, w.grid.cell(i, j), &scratch, px);
  const uint32_t x = 2 * (static_cast<uint32_t>(i) & (w.hwin - 1)), y = 2 * (static_cast<uint32_t>(j) & (w.hwin - 1));
  for (int qy = 0; qy < 2; ++qy)
    for (int qx = 0; qx < 2; ++qx) w.hy[(y + qy) * 2 * w.hwin + x + qx] = quadrant_mean(px, qx, qy);
  const int ci = i / 2, cj = j / 2;
  scratch = kNoTag;
  fill_block(w, w.grid.id(0, 1, ci, cj), &scratch, px);
  w.hcb[slot] = quadrant_mean(px, i & 1, j & 1);
  scratch = kNoTag;
  fill_block(w, w.grid.id(0, 2, ci, cj), &scratch, px);
  w.hcr[slot] = quadrant_mean(px, i & 1, j & 1);
  w.htag[slot] = tag;
}

// Claims the half-resolution slots of cells [i0, i0 + ni) x [j0, j0 + nj)
// for this frame and fills them: false (nothing claimed) when another
// cell of the frame has one of them.
bool claim_half(TerrainPlay& w, int i0, int j0, int ni, int nj) {
  if (w.hwin == 0) return false;
  const uint16_t stamp = static_cast<uint16_t>(w.stamp);
  for (int j = j0; j < j0 + nj; ++j)
    for (int i = i0; i < i0 + ni; ++i) {
      const uint32_t slot = half_slot(w, i, j);
      if (w.hclaim[slot] == stamp && w.htag[slot] != half_tag(w, i, j)) return false;
    }
  for (int j = j0; j < j0 + nj; ++j)
    for (int i = i0; i < i0 + ni; ++i) {
      w.hclaim[half_slot(w, i, j)] = stamp;
      fill_half(w, i, j);
    }
  return true;
}

// --- Updates and elevation ---------------------------------------------------------

// Changes are staged in the store and merged a batch at a time; the
// reader's questions are answered from the store with every change before
// them merged: a block's mask (a grow after the shrinks restarts at low
// ids), and what a level-0 block shows (its level-1 block may have just
// changed).
void merged_cb(void* ctx, uint32_t id) { refresh(*static_cast<TerrainPlay*>(ctx), id); }
void merge_staged(TerrainPlay& w) { w.store.merge(merged_cb, &w); }
Mask held_cb(void* ctx, uint32_t id) {
  TerrainPlay& w = *static_cast<TerrainPlay*>(ctx);
  if (w.store.staged() && id <= w.store.last_staged()) merge_staged(w);
  return w.store.held(id);
}
int shown_dc_cb(void* ctx, uint32_t id) {
  TerrainPlay& w = *static_cast<TerrainPlay*>(ctx);
  // It depends on the block's level-1 block: merge if one is staged (they
  // come first, with the lowest ids).
  if (w.store.staged() && w.store.first_staged() < w.grid.first(0, 0)) merge_staged(w);
  return *dc_texel(w, w.grid.place(id)) - 128;
}

Status apply_update(TerrainPlay& w, const uint8_t* payload, uint32_t size) {
  terrain::TextureUpdateReader r;
  Status s = r.init(payload, size, w.grid, held_cb, shown_dc_cb, &w);
  terrain::BlockUpdate u;
  while (s == Status::ok) {
    s = r.next(&u);
    if (s == Status::ok) s = w.store.stage(u, merged_cb, &w);
  }
  // What was staged before a refusal is merged too: the store stays whole.
  merge_staged(w);
  return s == Status::more_input && r.done() ? Status::ok : (s == Status::more_input ? Status::malformed : s);
}

void patch_bounds(TerrainPlay& w, int row0, int row1) {
  for (int py = 0; py < w.patches_y; ++py) {
    const int j0 = py * w.patch, j1 = j0 + w.patch < w.ph - 1 ? j0 + w.patch : w.ph - 1;
    if (j1 < row0 || j0 >= row1) continue;
    for (int px = 0; px < w.patches_x; ++px) {
      const int i0 = px * w.patch, i1 = i0 + w.patch < w.pw - 1 ? i0 + w.patch : w.pw - 1;
      uint16_t lo = 65535, hi = 0;
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
          const uint16_t v = w.heights[static_cast<size_t>(j) * w.pw + i];
          if (v < lo) lo = v;
          if (v > hi) hi = v;
        }
      const int k = py * w.patches_x + px;
      w.patch_lo[k] = lo;
      w.patch_hi[k] = hi;
      uint16_t* err = w.patch_err + k * (kMaxStepLog2 + 1);
      err[0] = 0;
      for (int l = 1; l <= kMaxStepLog2; ++l)
        err[l] = (1 << l) <= w.patch ? terrain::step_error(w.heights, w.pw, i0, j0, i1 - i0, j1 - j0, 1 << l) : 65535;
    }
  }
}

Status elevation(TerrainPlay& w, const uint8_t* p, uint32_t size) {
  if (size < terrain::kElevationHeaderBytes) return Status::malformed;
  const uint8_t pass = p[0];
  const int y0 = load_le16(p + 1), y1 = load_le16(p + 3);
  const uint8_t* data = p + terrain::kElevationHeaderBytes;
  const size_t n = size - terrain::kElevationHeaderBytes;
  if (pass == 0) {
    if (w.coarse_in || y0 != 0 || y1 != w.ph) return Status::malformed;
    const Status s = terrain::decode_elevation(data, n, w.pw, w.ph, terrain::ElevationPass::coarse, w.heights);
    if (s != Status::ok) return s;
    terrain::fill_from_coarse(w.pw, w.ph, w.heights);
    w.coarse_in = true;
    patch_bounds(w, 0, w.ph);
    return Status::ok;
  }
  if (pass != 1 || !w.coarse_in || y0 != w.fine_next || y1 <= y0 || y1 > w.ph) return Status::malformed;
  const Status s = terrain::decode_elevation(data, n, w.pw, w.ph, terrain::ElevationPass::fine, w.heights, y0, y1);
  if (s != Status::ok) return s;
  w.fine_next = y1;
  patch_bounds(w, y0, y1);
  return Status::ok;
}

// --- Drawing ---------------------------------------------------------------------

Vec3<Q16_16> point(const TerrainPlay& w, int i, int j, int32_t drop_raw = 0) {
  const int64_t z = int64_t{w.heights[static_cast<size_t>(j) * w.pw + i]} * w.params.height_step_q16 - drop_raw;
  return {Q16_16::from_raw(sat_s32(int64_t{i} * w.params.cell_q16)),
          Q16_16::from_raw(sat_s32(int64_t{w.params.cells_y - j} * w.params.cell_q16)), Q16_16::from_raw(sat_s32(z))};
}

// Outcode of a camera-space point against the view frustum.
uint32_t outcode(const Camera& c, const StreamHeader& h, const Vec3<Q16_16>& q) {
  const int64_t x = q.x.raw(), y = q.y.raw(), z = q.z.raw();
  uint32_t o = 0;
  if (z < c.near_z.raw()) o |= 1;
  if (z > c.far_z.raw()) o |= 2;
  const int64_t fx = c.fx.raw(), fy = c.fy.raw(), cx = c.cx.raw(), cy = c.cy.raw();
  if (x * fx < -cx * z) o |= 4;
  if (x * fx > (int64_t{h.width} * 65536 - cx) * z) o |= 8;
  if (y * fy < -cy * z) o |= 16;
  if (y * fy > (int64_t{h.height} * 65536 - cy) * z) o |= 32;
  return o;
}

struct Builder {
  TerrainPlay& w;
  uint32_t vertices = 0, ground = 0, skirts = 0, cells = 0;
  uint32_t half_ground = 0, half_skirts = 0;  // written from the ends of the index arrays
  uint16_t vertex(const Vec3<Q16_16>& p, int32_t u_q16, int32_t v_q16) {
    w.pos[vertices] = p;
    w.uv[vertices] = {Q16_16::from_raw(u_q16), Q16_16::from_raw(v_q16)};
    return static_cast<uint16_t>(vertices++);
  }
  void tri(uint16_t* idx, uint32_t& n, uint16_t a, uint16_t b, uint16_t c) {
    idx[3 * n] = a, idx[3 * n + 1] = b, idx[3 * n + 2] = c;
    ++n;
  }
};

// What a patch of `cells` a side takes at step s: vertices (its grid and
// skirts on every edge), ground triangles and skirt triangles (upper bounds).
struct PatchCost {
  uint32_t vertices = 0, ground = 0, skirts = 0;
  PatchCost& operator+=(const PatchCost& c) {
    vertices += c.vertices, ground += c.ground, skirts += c.skirts;
    return *this;
  }
  // What going from `from` to `to` adds (to is the larger).
  static PatchCost growth(const PatchCost& from, const PatchCost& to) {
    return {to.vertices - from.vertices, to.ground - from.ground, to.skirts - from.skirts};
  }
  bool within(const PatchCost& more, const terrain::Params& t) const {
    return vertices + more.vertices <= ground_vertices(t) && ground + more.ground <= ground_triangles(t) &&
           skirts + more.skirts <= skirt_triangles(t);
  }
};
PatchCost patch_cost(int cells, int s) {
  const uint32_t n = static_cast<uint32_t>(cells / s);
  return {(n + 1) * (n + 1) + 4 * (n + 1), 2 * n * n, 8 * n};
}

// Cell (i, j) with its own block's texels, if its slots are free this frame.
bool textured_cell(TerrainPlay& w, Builder& b, int i, int j) {
  if (b.cells >= w.params.max_cells) return false;
  const uint32_t id = w.grid.cell(i, j);
  if (w.store.held(id) == 0) return false;
  const uint32_t ys = (static_cast<uint32_t>(j) & (w.win - 1)) * w.win + (static_cast<uint32_t>(i) & (w.win - 1));
  const uint32_t ci = static_cast<uint32_t>(i) / 2, cj = static_cast<uint32_t>(j) / 2;
  const uint32_t cs = (cj & (w.cwin - 1)) * w.cwin + (ci & (w.cwin - 1));
  const uint32_t cb = w.grid.id(0, 1, static_cast<int>(ci), static_cast<int>(cj)), cr = w.grid.id(0, 2, static_cast<int>(ci), static_cast<int>(cj));
  // Another cell of this frame has the luma slot, or another chroma block the chroma slot.
  if (w.yclaim[ys] == w.stamp) return false;
  const bool chroma_claimed = w.cclaim[cs] == w.stamp;
  if (chroma_claimed && w.cowner[cs] != cb) return false;
  w.yclaim[ys] = w.stamp;
  w.cclaim[cs] = w.stamp;
  w.cowner[cs] = cb;
  fill_block(w, id, &w.ytag[ys], w.ytex + ys * 64);
  uint8_t* tb = w.ctex + cs * 64;
  uint8_t* tr = w.ctex + (w.cwin * w.cwin + cs) * 64;
  if (!chroma_claimed) {
    fill_block(w, cb, &w.ctag[cs], tb);
    fill_block(w, cr, &w.ctag[w.cwin * w.cwin + cs], tr);
  }
  Texture& t = w.cell_tex[b.cells];
  t = Texture{};
  t.format = TexFormat::ycbcr420;
  t.address = TexAddress::clamp;
  t.width = t.height = 8;
  t.stride = 8;
  t.texels = w.ytex + ys * 64;
  const uint32_t off = (static_cast<uint32_t>(j) & 1u) * 32 + (static_cast<uint32_t>(i) & 1u) * 4;
  t.cb = tb + off;
  t.cr = tr + off;
  t.chroma_stride = 8;
  constexpr int32_t k8 = 8 << 16;
  const uint16_t a = b.vertex(point(w, i, j), 0, 0), bb = b.vertex(point(w, i + 1, j), k8, 0);
  const uint16_t c = b.vertex(point(w, i, j + 1), 0, k8), d = b.vertex(point(w, i + 1, j + 1), k8, k8);
  uint16_t* idx = w.cell_idx + 6 * b.cells;
  idx[0] = a, idx[1] = c, idx[2] = bb, idx[3] = bb, idx[4] = c, idx[5] = d;
  Mesh& m = w.meshes[b.cells];
  m = Mesh{};
  m.indices = idx;
  m.num_triangles = 2;
  m.shading = Shading::texture;
  m.filter = Filter::bilinear_luma;
  m.cull = Cull::back;
  m.uvs = w.uv;
  m.texture = &t;
  ++b.cells;
  return true;
}

void draw_patch(TerrainPlay& w, Builder& b, int px, int py, int s) {
  const int i0 = px * w.patch, j0 = py * w.patch;
  const int ni = (w.patch < w.params.cells_x - i0 ? w.patch : w.params.cells_x - i0);
  const int nj = (w.patch < w.params.cells_y - j0 ? w.patch : w.params.cells_y - j0);
  // Grid points of the patch at step s (the last row and column at the
  // patch's edge even where the map's size is not a multiple of s).
  const int cols = (ni + s - 1) / s + 1, rows = (nj + s - 1) / s + 1;
  auto gi = [&](int c) { return i0 + (c * s < ni ? c * s : ni); };
  auto gj = [&](int r) { return j0 + (r * s < nj ? r * s : nj); };
  // Near patches take the half-resolution window when their cells' slots are free.
  const bool half = s <= 8 && claim_half(w, i0, j0, ni, nj);
  const int32_t texels = half ? 2 : 1;  // a cell's texels in the patch's texture
  const uint32_t first = b.vertices;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) b.vertex(point(w, gi(c), gj(r)), gi(c) * texels << 16, gj(r) * texels << 16);
  // Ground triangles: DC plane from the front of the array, half window from the back.
  auto ground_tri = [&](uint16_t a, uint16_t bb, uint16_t c) {
    if (!half) {
      b.tri(w.ground_idx, b.ground, a, bb, c);
    } else {
      uint32_t at = ground_triangles(w.params) - 1 - b.half_ground;
      b.tri(w.ground_idx, at, a, bb, c);
      ++b.half_ground;
    }
  };
  for (int r = 0; r + 1 < rows; ++r)
    for (int c = 0; c + 1 < cols; ++c) {
      if (s == 1 && textured_cell(w, b, i0 + c, j0 + r)) continue;
      const uint16_t a = static_cast<uint16_t>(first + r * cols + c), bb = static_cast<uint16_t>(a + 1);
      const uint16_t cc = static_cast<uint16_t>(a + cols), d = static_cast<uint16_t>(cc + 1);
      ground_tri(a, cc, bb);
      ground_tri(bb, cc, d);
    }
  // Skirts where a neighbour is drawn at another step.
  const int k = py * w.patches_x + px;
  const int32_t drop = static_cast<int32_t>(sat_s32(int64_t{w.patch_hi[k] - w.patch_lo[k] + 1} * w.params.height_step_q16));
  auto neighbour_differs = [&](int qx, int qy) {
    if (qx < 0 || qy < 0 || qx >= w.patches_x || qy >= w.patches_y) return false;
    const uint8_t t = w.patch_step[qy * w.patches_x + qx];
    return t != 0 && t != s;
  };
  auto skirt = [&](int count, auto at) {  // at(n) -> vertex index on the edge
    uint16_t prev_top = 0, prev_low = 0;
    for (int n = 0; n < count && b.skirts + b.half_skirts + 2 <= skirt_triangles(w.params); ++n) {
      const uint16_t top = at(n);
      const Vec3<Q16_16> p = w.pos[top];
      const uint16_t low = b.vertex({p.x, p.y, Q16_16::from_raw(sat_s32(int64_t{p.z.raw()} - drop))}, w.uv[top].u.raw(), w.uv[top].v.raw());
      if (n > 0) {
        if (!half) {
          b.tri(w.skirt_idx, b.skirts, prev_top, prev_low, top);
          b.tri(w.skirt_idx, b.skirts, top, prev_low, low);
        } else {
          uint32_t at1 = skirt_triangles(w.params) - 1 - b.half_skirts, at2 = at1 - 1;
          b.tri(w.skirt_idx, at1, prev_top, prev_low, top);
          b.tri(w.skirt_idx, at2, top, prev_low, low);
          b.half_skirts += 2;
        }
      }
      prev_top = top, prev_low = low;
    }
  };
  if (neighbour_differs(px, py - 1)) skirt(cols, [&](int n) { return static_cast<uint16_t>(first + n); });
  if (neighbour_differs(px, py + 1)) skirt(cols, [&](int n) { return static_cast<uint16_t>(first + (rows - 1) * cols + n); });
  if (neighbour_differs(px - 1, py)) skirt(rows, [&](int n) { return static_cast<uint16_t>(first + n * cols); });
  if (neighbour_differs(px + 1, py)) skirt(rows, [&](int n) { return static_cast<uint16_t>(first + n * cols + cols - 1); });
}

Status draw(Player& p, TerrainPlay& w, const WalkPose& pose) {
  Camera cam;
  if (walk_camera(p.header(), pose, &cam) != Status::ok) return Status::malformed;
  ++w.stamp;
  if ((w.stamp & 0xFFFF) == 0) {  // wrapped (the half window keeps 16 bits): no slot may look claimed
    for (uint32_t i = 0; i < w.win * w.win; ++i) w.yclaim[i] = 0;
    for (uint32_t i = 0; i < w.cwin * w.cwin; ++i) w.cclaim[i] = 0;
    for (uint32_t i = 0; i < w.hwin * w.hwin; ++i) w.hclaim[i] = 0;
    ++w.stamp;
  }
  Builder b{w};
  uint32_t visible = 0;
  if (w.coarse_in) {
    // Visible patches and their nearest depth.
    for (int py = 0; py < w.patches_y; ++py)
      for (int px = 0; px < w.patches_x; ++px) {
        const int k = py * w.patches_x + px;
        w.patch_step[k] = 0;
        const int i0 = px * w.patch, j0 = py * w.patch;
        const int i1 = i0 + w.patch < w.params.cells_x ? i0 + w.patch : w.params.cells_x;
        const int j1 = j0 + w.patch < w.params.cells_y ? j0 + w.patch : w.params.cells_y;
        uint32_t all = 0x3F;
        int32_t zmin = INT32_MAX;
        for (int c = 0; c < 8; ++c) {
          Vec3<Q16_16> q = point(w, (c & 1) ? i1 : i0, (c & 2) ? j1 : j0);
          q.z = Q16_16::from_raw(sat_s32(int64_t{(c & 4) ? w.patch_hi[k] : w.patch_lo[k]} * w.params.height_step_q16));
          const Vec3<Q16_16> v = camera_transform(cam, q);
          all &= outcode(cam, p.header(), v);
          if (v.z.raw() < zmin) zmin = v.z.raw();
        }
        if (all != 0) continue;
        w.patch_z[k] = zmin < cam.near_z.raw() ? cam.near_z.raw() : zmin;
        // Insert into the nearest-first order.
        uint32_t at = visible++;
        while (at > 0 && w.patch_z[w.order[at - 1]] > w.patch_z[k]) {
          w.order[at] = w.order[at - 1];
          --at;
        }
        w.order[at] = static_cast<uint16_t>(k);
      }
    // Steps: every visible patch starts at its coarsest step, then the
    // patch whose step shows the largest height error on screen (its error
    // at the patch's nearest depth) is halved, again and again, while the
    // frame's budget holds the finer step and the error is over kLodPx
    // pixels: the budget goes where the picture is most wrong.
    const int64_t fx = cam.fx.raw() >> 8;
    PatchCost used;
    for (uint32_t n = 0; n < visible; ++n) {
      w.patch_step[w.order[n]] = static_cast<uint8_t>(w.patch);
      used += patch_cost(w.patch, w.patch);
    }
    auto screen_error = [&](int k, int step) {  // Q16 pixels x units, against kLodPx x depth
      const uint16_t* err = w.patch_err + k * (kMaxStepLog2 + 1);
      return ((int64_t{err[ilog2(static_cast<uint32_t>(step))]} * w.params.height_step_q16) >> 8) * fx;
    };
    // Each patch's error on screen at its current step, about 2^8 pixels
    // (0: nothing to refine); only the refined patch's changes.
    auto on_screen = [&](int k) -> int64_t {
      const int st = w.patch_step[k];
      if (st <= 1) return 0;
      const int64_t e = screen_error(k, st), z = w.patch_z[k] > 0 ? w.patch_z[k] : 1;
      return e <= int64_t{kLodPx} * z ? 0 : e / ((z >> 8) + 1);  // (no overflow for any stream's values)
    };
    for (uint32_t n = 0; n < visible; ++n) w.patch_px[w.order[n]] = on_screen(w.order[n]);
    // What halving a patch's step adds.
    auto finer = [&](int k) { return PatchCost::growth(patch_cost(w.patch, w.patch_step[k]), patch_cost(w.patch, w.patch_step[k] / 2)); };
    for (;;) {
      int best = -1;
      for (uint32_t n = 0; n < visible; ++n) {
        const int k = w.order[n];
        if (w.patch_px[k] == 0 || (best >= 0 && w.patch_px[k] <= w.patch_px[best])) continue;
        if (used.within(finer(k), w.params)) best = k;
      }
      if (best < 0) break;
      used += finer(best);
      w.patch_step[best] = static_cast<uint8_t>(w.patch_step[best] / 2);
      w.patch_px[best] = on_screen(best);
    }
    for (uint32_t n = 0; n < visible; ++n) {
      const int k = w.order[n];
      if (w.patch_step[k] != 0) draw_patch(w, b, k % w.patches_x, k / w.patches_x, w.patch_step[k]);
    }
  }
  // Nearest first, so that the depth test spares the farther ones' texels:
  // the cells drawn from their own blocks, the half-resolution window's
  // patches, the DC plane's, then the skirts.
  Mesh* fixed = w.meshes + b.cells;
  Mesh& half = fixed[0];
  Mesh& ground = fixed[1];
  Mesh& half_skirts = fixed[2];
  Mesh& skirts = fixed[3];
  ground = Mesh{};
  ground.indices = w.ground_idx;
  ground.num_triangles = b.ground;
  ground.shading = Shading::texture;
  ground.filter = Filter::bilinear_luma;
  ground.cull = Cull::back;
  ground.uvs = w.uv;
  ground.texture = &w.dc_tex;
  skirts = ground;
  skirts.indices = w.skirt_idx;
  skirts.num_triangles = b.skirts;
  skirts.cull = Cull::none;
  half = ground;
  half.indices = w.ground_idx + 3 * (ground_triangles(w.params) - b.half_ground);
  half.num_triangles = b.half_ground;
  half.texture = &w.half_tex;
  half_skirts = skirts;
  half_skirts.indices = w.skirt_idx + 3 * (skirt_triangles(w.params) - b.half_skirts);
  half_skirts.num_triangles = b.half_skirts;
  half_skirts.texture = &w.half_tex;
  if (w.hwin == 0) half.texture = half_skirts.texture = &w.dc_tex;  // (never drawn)
  DrawList list;
  list.positions = w.pos;
  list.num_positions = b.vertices;
  list.meshes = w.meshes;
  list.num_meshes = 4 + b.cells;
  return w.renderer.render(cam, list, kSky, detail::render_band_to_player, &p);
}

// --- The viewer's pose, up the back-channel ------------------------------------------

// The ground's height under (x, y), world units Q16.16, from the nearest
// grid point (0 before the elevation's first pass).
int64_t ground_under(const TerrainPlay& w, Q16_16 x, Q16_16 y) {
  if (!w.coarse_in || w.params.cell_q16 <= 0) return 0;
  const int64_t cell = w.params.cell_q16;
  const int32_t i = clamp_s32(sat_s32((int64_t{x.raw()} + cell / 2) / cell), 0, w.params.cells_x);
  const int32_t j = clamp_s32(sat_s32(w.params.cells_y - (int64_t{y.raw()} + cell / 2) / cell), 0, w.params.cells_y);
  return int64_t{w.heights[static_cast<size_t>(j) * w.pw + i]} * w.params.height_step_q16;
}

// After frame `frame`, drawn from `drawn`: the viewer's controls, if they
// move it, steer the client's own pose (from the drawn one the first time),
// kept over the map and a cell above the ground under it; a steered pose
// goes up every frame the controls move it and every pose period, the
// flight's every pose period until then.
void send_pose(Player& p, TerrainPlay& w, uint32_t frame, const WalkPose& drawn) {
  const PlayerCallbacks& cb = p.callbacks();
  terrain::SteerInput in;
  const bool moved = cb.steer != nullptr && cb.steer(cb.ctx, &in) && in.any();
  if (moved) {
    if (!w.steering) w.steered = drawn;
    w.steering = true;
    // A quarter of a cell a frame (a cell when fast): about the scripted
    // flyover's speed on a map of 128 cells.
    WalkPose s = terrain::steer_pose(w.steered, in, w.params.cell_q16 / 4);
    s.position.x = Q16_16::from_raw(clamp_s32(s.position.x.raw(), 0, sat_s32(int64_t{w.params.cells_x} * w.params.cell_q16)));
    s.position.y = Q16_16::from_raw(clamp_s32(s.position.y.raw(), 0, sat_s32(int64_t{w.params.cells_y} * w.params.cell_q16)));
    const int64_t floor = ground_under(w, s.position.x, s.position.y) + w.params.cell_q16;
    if (s.position.z.raw() < floor) s.position.z = Q16_16::from_raw(sat_s32(floor));
    w.steered = s;
  }
  const bool period = w.params.pose_period != 0 && frame % w.params.pose_period == 0;
  if (cb.send_up == nullptr || !(period || (moved && w.params.pose_period != 0))) return;
  uint8_t msg[terrain::kPoseMessageBytes];
  store_le32(msg, w.steering ? frame | terrain::kPoseSteered : frame);
  terrain::pose_to_bytes(w.steering ? w.steered : terrain::flight_pose(w.keys, w.key_count, w.spacing, frame), msg + 4);
  cb.send_up(cb.ctx, terrain::kSendPose, msg, sizeof msg);
}

// --- Chunks -------------------------------------------------------------------------

ChunkResult on_chunk(Player& p, uint32_t type, const uint8_t* payload, uint32_t size) {
  const bool ours = type == chunk::kTerrainParams || type == chunk::kTerrainFlight || type == chunk::kTerrainElevation ||
                    type == chunk::kTerrainTexture || type == chunk::kTerrainFrame;
  if (!ours) return ChunkResult::unknown;
  const uint64_t t0 = p.enter_chunk();
  ChunkResult result = ChunkResult::consumed;
  const auto refuse = [&](Status s, const char* why) {
    p.fail(s, why);
    result = ChunkResult::abort;
  };
  if (p.terrain == nullptr) {
    if (type != chunk::kTerrainParams) refuse(Status::malformed, "a terrain chunk before TERH");
    else if (!setup(p, payload, size)) result = ChunkResult::abort;
    p.add_decode(p.work_clock() - t0);
    p.leave_chunk();
    return result;
  }
  TerrainPlay& w = *p.terrain;
  if (type == chunk::kTerrainParams) {
    refuse(Status::malformed, "a second TERH");
  } else if (type == chunk::kTerrainFlight) {
    const uint32_t keys = size >= 2 ? (size - 2) / terrain::kPoseBytes : 0, spacing = size >= 2 ? load_le16(payload) : 0;
    if (w.key_count != 0 || size < 2 + terrain::kPoseBytes || (size - 2) % terrain::kPoseBytes != 0 ||
        keys > terrain::kMaxFlightKeys || spacing == 0 || spacing > 1024 ||
        (keys - 1) * spacing < p.header().frame_count - 1) {
      refuse(Status::malformed, "TFLY is not a flight covering the stream's frames (or a second one)");
    } else {
      for (uint32_t k = 0; k < keys; ++k) w.keys[k] = terrain::pose_from_bytes(payload + 2 + k * terrain::kPoseBytes);
      w.key_count = keys;
      w.spacing = spacing;
    }
  } else if (type == chunk::kTerrainElevation) {
    const Status s = elevation(w, payload, size);
    if (s != Status::ok) refuse(s, "TELV was refused (a pass out of order or bad data)");
  } else if (type == chunk::kTerrainTexture) {
    const Status s = apply_update(w, payload, size);
    if (s != Status::ok) refuse(s, "TTEX was refused");
  } else {  // TFRM
    const bool has_pose = size == terrain::kSteeredFrameBytes;
    const uint32_t frame = size == terrain::kFrameBytes || has_pose ? load_le32(payload) : ~0u;
    if (frame != p.frames_shown() || frame >= p.header().frame_count || w.key_count == 0) {
      refuse(Status::malformed, "TFRM is not the next frame of the flight");
    } else {
      p.add_decode(p.work_clock() - t0);
      const WalkPose drawn = has_pose ? terrain::pose_from_bytes(payload + terrain::kFrameBytes)
                                      : terrain::flight_pose(w.keys, w.key_count, w.spacing, frame);
      if (!p.begin_frame()) {
        result = ChunkResult::abort;
      } else {
        const uint64_t display_before = p.display_total();
        const uint64_t d0 = p.work_clock();
        const Status ds = draw(p, w, drawn);
        p.add_display((p.work_clock() - d0) - (p.display_total() - display_before));
        if (ds != Status::ok) refuse(ds, "the frame could not be drawn");
        else if (!p.end_frame()) result = ChunkResult::abort;
      }
      if (result == ChunkResult::consumed) send_pose(p, w, frame, drawn);
      p.leave_chunk();
      return result;
    }
  }
  p.add_decode(p.work_clock() - t0);
  p.leave_chunk();
  return result;
}

// A frame completes at each TFRM chunk.
size_t feed_limit(const Player&, uint32_t frames_room) { return detail::chunk_per_frame_feed_limit(frames_room); }

}  // namespace

size_t Player::terrain_workspace_bytes(const StreamHeader& h, const terrain::Params& t, const PlayerConfig& c) {
  return workspace(h, t, c);
}

const terrain::BlockStore* Player::terrain_store() const { return terrain != nullptr ? &terrain->store : nullptr; }

namespace detail {
extern const PlayerMode kTerrainMode;
const PlayerMode kTerrainMode{StreamMode::terrain, start, on_chunk, feed_limit};
}  // namespace detail

}  // namespace vds
