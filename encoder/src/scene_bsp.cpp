// vds encoder: the Quake III BSP reader (vds/enc/scene.h). The layout (IBSP
// version 46): a header of 17 lumps, each an offset and a length; the
// lumps used here are the entities text (0), textures (1), models (7),
// vertices (10), mesh vertices (11), faces (13) and lightmaps (14).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "vds/bytes.h"
#include "vds/enc/scene.h"

namespace vds::enc {

namespace {

constexpr int kLumps = 17;
enum Lump { kEntities = 0, kTextures = 1, kModels = 7, kVertices = 10, kMeshVerts = 11, kFaces = 13, kLightmaps = 14 };
const char* const kLumpNames[kLumps] = {"entities", "textures", "planes",     "nodes",   "leafs",     "leaf faces",
                                        "leaf brushes", "models", "brushes",  "brush sides", "vertices",
                                        "mesh vertices", "effects", "faces",  "lightmaps", "light volumes",
                                        "visibility"};
constexpr size_t kTextureBytes = 72, kModelBytes = 40, kVertexBytes = 44, kFaceBytes = 104;
constexpr size_t kLightmapBytes = size_t{kLightmapSide} * kLightmapSide * 3;
constexpr uint32_t kSurfSky = 0x4, kSurfNodraw = 0x80, kSurfHint = 0x100, kSurfSkip = 0x200;
constexpr uint32_t kContentsFog = 0x40;
constexpr int kMaxPatchSide = 65;  // control points per patch side

float load_f32(const uint8_t* p) {
  const uint32_t u = load_le32(p);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

struct Reader {
  const uint8_t* data;
  size_t size;
  std::string name;
  uint32_t offset[kLumps], length[kLumps];

  [[noreturn]] void fail(const std::string& what) const { throw std::runtime_error(name + ": " + what); }

  // The lump's elements: its length must be a whole number of them.
  size_t count(int lump, size_t element) const {
    if (length[lump] % element != 0)
      fail(std::string("the ") + kLumpNames[lump] + " lump is " + std::to_string(length[lump]) +
           " bytes, not a whole number of " + std::to_string(element) + "-byte elements");
    return length[lump] / element;
  }
  const uint8_t* at(int lump, size_t element, size_t i) const { return data + offset[lump] + i * element; }
};

SceneVertex vertex_at(const Reader& r, size_t i) {
  const uint8_t* p = r.at(kVertices, kVertexBytes, i);
  SceneVertex v;
  for (int k = 0; k < 3; ++k) v.pos[k] = load_f32(p + 4 * k);
  for (int k = 0; k < 2; ++k) v.uv[k] = load_f32(p + 12 + 4 * k);
  for (int k = 0; k < 2; ++k) v.lm_uv[k] = load_f32(p + 20 + 4 * k);
  for (int k = 0; k < 3; ++k) v.normal[k] = load_f32(p + 28 + 4 * k);
  for (int k = 0; k < 4; ++k) v.color[k] = p[40 + k];
  return v;
}

// What is wrong with a vertex ("" if nothing): positions and texture
// coordinates must be finite. Lightmap coordinates and normals of a face
// without a lightmap are not used: the game's compiler leaves them
// undefined there (some OpenArena maps hold NaNs), so they are set to 0.
std::string check_vertex(SceneVertex& v, bool lightmapped) {
  for (float f : v.pos)
    if (!std::isfinite(f) || std::fabs(f) > 1e7f) return "a position that is not finite or beyond 1e7 map units";
  for (float f : v.uv)
    if (!std::isfinite(f)) return "texture coordinates that are not finite";
  for (float& f : v.lm_uv)
    if (!std::isfinite(f)) {
      if (lightmapped) return "lightmap coordinates that are not finite";
      f = 0;
    }
  for (float& f : v.normal)
    if (!std::isfinite(f)) f = 0;
  return "";
}

// Quadratic Bernstein weights at t.
void weights(double t, double w[3]) {
  w[0] = (1 - t) * (1 - t);
  w[1] = 2 * t * (1 - t);
  w[2] = t * t;
}

SceneVertex blend(const SceneVertex* const cp[3][3], const double wu[3], const double wv[3]) {
  SceneVertex o;
  double pos[3] = {}, uv[2] = {}, lm[2] = {}, n[3] = {}, c[4] = {};
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const double w = wu[i] * wv[j];
      const SceneVertex& v = *cp[j][i];
      for (int k = 0; k < 3; ++k) pos[k] += w * v.pos[k], n[k] += w * v.normal[k];
      for (int k = 0; k < 2; ++k) uv[k] += w * v.uv[k], lm[k] += w * v.lm_uv[k];
      for (int k = 0; k < 4; ++k) c[k] += w * v.color[k];
    }
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (int k = 0; k < 3; ++k) o.pos[k] = static_cast<float>(pos[k]), o.normal[k] = static_cast<float>(len > 0 ? n[k] / len : 0);
  for (int k = 0; k < 2; ++k) o.uv[k] = static_cast<float>(uv[k]), o.lm_uv[k] = static_cast<float>(lm[k]);
  for (int k = 0; k < 4; ++k) o.color[k] = static_cast<uint8_t>(std::clamp(std::lround(c[k]), 0L, 255L));
  return o;
}

// Segments a quadratic Bezier needs so that its polyline stays within
// `tol` of the curve: the deviation of n equal segments is at most
// |P0 - 2 P1 + P2| / (4 n^2).
int steps_for(const SceneVertex& a, const SceneVertex& b, const SceneVertex& c, double tol, int max_steps) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double d = static_cast<double>(a.pos[k]) - 2.0 * b.pos[k] + c.pos[k];
    d2 += d * d;
  }
  const double need = std::ceil(std::sqrt(std::sqrt(d2) / (4 * tol)));
  return need >= max_steps ? max_steps : std::max(1, static_cast<int>(need));
}

// A patch of w x h control points (odd, >= 3) as (w-1)/2 x (h-1)/2 biquadratic
// pieces, each tessellated into a grid of triangles.
void tessellate_patch(const std::vector<SceneVertex>& cp, int w, int h, const SceneOptions& o, size_t budget,
                      const Reader& r, const std::string& where, Scene& s) {
  for (int py = 0; py + 2 < h; py += 2)
    for (int px = 0; px + 2 < w; px += 2) {
      const SceneVertex* c[3][3];
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) c[j][i] = &cp[static_cast<size_t>(py + j) * w + px + i];
      int nu = 1, nv = 1;
      for (int k = 0; k < 3; ++k) {
        nu = std::max(nu, steps_for(*c[k][0], *c[k][1], *c[k][2], o.patch_tolerance, o.patch_max_steps));
        nv = std::max(nv, steps_for(*c[0][k], *c[1][k], *c[2][k], o.patch_tolerance, o.patch_max_steps));
      }
      if (s.vertices.size() + static_cast<size_t>(nu + 1) * (nv + 1) > budget)
        r.fail(where + ": the map's patches would make more than " + std::to_string(budget) +
               " vertices (a quarter of the file's bytes)");
      const uint32_t base = static_cast<uint32_t>(s.vertices.size());
      for (int y = 0; y <= nv; ++y)
        for (int x = 0; x <= nu; ++x) {
          double wu[3], wv[3];
          weights(static_cast<double>(x) / nu, wu);
          weights(static_cast<double>(y) / nv, wv);
          s.vertices.push_back(blend(c, wu, wv));
        }
      for (int y = 0; y < nv; ++y)
        for (int x = 0; x < nu; ++x) {
          const uint32_t a = base + static_cast<uint32_t>(y * (nu + 1) + x), b = a + 1,
                         d = a + static_cast<uint32_t>(nu + 1), e = d + 1;
          s.indices.insert(s.indices.end(), {a, d, b, b, d, e});
        }
    }
}

// The entities lump: { "key" "value" ... } blocks; spawn points from the
// player start classes.
void read_spawns(const Reader& r, Scene& s) {
  const char* p = reinterpret_cast<const char*>(r.data + r.offset[kEntities]);
  const char* end = p + r.length[kEntities];
  std::string key, classname, origin, angle;
  bool in_block = false, have_key = false;
  auto is_spawn = [](const std::string& c) {
    return c == "info_player_deathmatch" || c == "info_player_start" || c == "team_CTF_redplayer" ||
           c == "team_CTF_blueplayer" || c == "team_CTF_redspawn" || c == "team_CTF_bluespawn";
  };
  while (p < end && *p != '\0') {
    const char ch = *p;
    if (ch == '{') {
      if (in_block) r.fail("entities: '{' inside an entity (byte " + std::to_string(p - reinterpret_cast<const char*>(r.data)) + ")");
      in_block = true;
      classname.clear(), origin.clear(), angle.clear(), have_key = false;
      ++p;
    } else if (ch == '}') {
      if (!in_block) r.fail("entities: '}' outside an entity");
      in_block = false;
      if (is_spawn(classname)) {
        SpawnPoint sp;
        sp.classname = classname;
        if (std::sscanf(origin.c_str(), "%f %f %f", &sp.origin[0], &sp.origin[1], &sp.origin[2]) != 3 ||
            !std::isfinite(sp.origin[0]) || !std::isfinite(sp.origin[1]) || !std::isfinite(sp.origin[2]))
          r.fail("entities: a " + classname + " without a readable origin");
        if (!angle.empty()) sp.yaw_deg = std::strtof(angle.c_str(), nullptr);
        if (!std::isfinite(sp.yaw_deg)) sp.yaw_deg = 0;
        s.spawns.push_back(sp);
      }
      ++p;
    } else if (ch == '"') {
      const char* q = static_cast<const char*>(std::memchr(p + 1, '"', static_cast<size_t>(end - p - 1)));
      if (q == nullptr) r.fail("entities: a string without its closing quote");
      const std::string tok(p + 1, q);
      if (!in_block) r.fail("entities: a string outside an entity");
      if (!have_key) {
        key = tok;
        have_key = true;
      } else {
        if (key == "classname") classname = tok;
        else if (key == "origin") origin = tok;
        else if (key == "angle") angle = tok;
        have_key = false;
      }
      p = q + 1;
    } else {
      ++p;  // whitespace
    }
  }
  if (in_block) r.fail("entities: the last entity is not closed");
}

}  // namespace

Scene read_bsp(const uint8_t* data, size_t size, const std::string& name, const SceneOptions& o) {
  if (!(o.patch_tolerance >= 1e-3) || !std::isfinite(o.patch_tolerance) || o.patch_max_steps < 1 || o.patch_max_steps > 64)
    throw std::invalid_argument("patch tolerance must be at least 0.001 map units and steps 1..64");
  Reader r{data, size, name, {}, {}};
  constexpr size_t kHeader = 8 + 8 * kLumps;
  if (size < kHeader || std::memcmp(data, "IBSP", 4) != 0) r.fail("not a Quake III map (it must start with 'IBSP')");
  const int32_t version = load_le32s(data + 4);
  if (version != 46) r.fail("BSP version " + std::to_string(version) + " (46, Quake III and OpenArena, is read)");
  for (int l = 0; l < kLumps; ++l) {
    r.offset[l] = load_le32(data + 8 + 8 * l);
    r.length[l] = load_le32(data + 12 + 8 * l);
    if (r.offset[l] > size || r.length[l] > size - r.offset[l])
      r.fail(std::string("the ") + kLumpNames[l] + " lump (" + std::to_string(r.length[l]) + " bytes at byte " +
             std::to_string(r.offset[l]) + ") is not inside the " + std::to_string(size) + "-byte file");
    if (r.offset[l] % 4 != 0)
      r.fail(std::string("the ") + kLumpNames[l] + " lump starts at byte " + std::to_string(r.offset[l]) +
             ", not on a 4-byte boundary");
  }
  Scene s;
  s.name = name;
  const size_t ntex = r.count(kTextures, kTextureBytes), nmodels = r.count(kModels, kModelBytes),
               nverts = r.count(kVertices, kVertexBytes), nmesh = r.count(kMeshVerts, 4),
               nfaces = r.count(kFaces, kFaceBytes), nlm = r.count(kLightmaps, kLightmapBytes);
  for (size_t t = 0; t < ntex; ++t) {
    const uint8_t* p = r.at(kTextures, kTextureBytes, t);
    SceneTexture tex;
    const char* n = reinterpret_cast<const char*>(p);
    tex.name.assign(n, strnlen(n, 64));
    for (char c : tex.name)
      if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7F)
        r.fail("texture " + std::to_string(t) + " has a name with a byte that is not text");
    tex.flags = load_le32(p + 64);
    tex.contents = load_le32(p + 68);
    s.textures.push_back(tex);
  }
  for (size_t l = 0; l < nlm; ++l) {
    const uint8_t* p = r.at(kLightmaps, kLightmapBytes, l);
    s.lightmaps.emplace_back(p, p + kLightmapBytes);
  }
  // Faces by model: the world and the brush entities; each face once.
  std::vector<uint8_t> taken(nfaces, 0);
  if (nmodels == 0) r.fail("no models (the world is model 0)");
  for (size_t m = 0; m < nmodels; ++m) {
    const uint8_t* p = r.at(kModels, kModelBytes, m);
    const int32_t first = load_le32s(p + 24), n = load_le32s(p + 28);
    if (first < 0 || n < 0 || static_cast<size_t>(first) > nfaces || static_cast<size_t>(n) > nfaces - first)
      r.fail("model " + std::to_string(m) + " names faces " + std::to_string(first) + "+" + std::to_string(n) + " of " +
             std::to_string(nfaces));
    for (int32_t f = first; f < first + n; ++f) taken[f] = 1;
  }
  // Output memory bounded by the input: at most a vertex per 4 bytes of the
  // file (about 68 bytes of vertices and indices each: 17 x the file).
  const size_t budget = std::max<size_t>(65536, size / 4);
  std::vector<SceneVertex> cp;
  for (size_t f = 0; f < nfaces; ++f) {
    const uint8_t* p = r.at(kFaces, kFaceBytes, f);
    const int32_t texture = load_le32s(p), type = load_le32s(p + 8), vertex = load_le32s(p + 12), nv = load_le32s(p + 16),
                  meshvert = load_le32s(p + 20), nmv = load_le32s(p + 24), lm = load_le32s(p + 28);
    const int32_t pw = load_le32s(p + 96), ph = load_le32s(p + 100);
    const std::string where = "face " + std::to_string(f) + " of " + std::to_string(nfaces);
    if (type == 1) ++s.polygons;
    else if (type == 2) ++s.patches;
    else if (type == 3) ++s.meshes;
    else if (type == 4) ++s.billboards;
    else r.fail(where + " has type " + std::to_string(type) + " (1..4)");
    if (texture < 0 || static_cast<size_t>(texture) >= ntex)
      r.fail(where + " names texture " + std::to_string(texture) + " of " + std::to_string(ntex));
    // Negative: no lightmap (-1 none, -2 2D, -3 by vertex, -4 white).
    if (lm < -4 || (lm >= 0 && static_cast<size_t>(lm) >= nlm))
      r.fail(where + " names lightmap " + std::to_string(lm) + " of " + std::to_string(nlm));
    if (vertex < 0 || nv < 0 || static_cast<size_t>(vertex) > nverts || static_cast<size_t>(nv) > nverts - vertex)
      r.fail(where + " names vertices " + std::to_string(vertex) + "+" + std::to_string(nv) + " of " + std::to_string(nverts));
    if (type == 4) continue;
    const SceneTexture& tex = s.textures[texture];
    if (!taken[f] || (tex.flags & (kSurfNodraw | kSurfHint | kSurfSkip)) != 0) {
      ++s.skipped;
      continue;
    }
    SceneSurface surf;
    surf.texture = texture;
    surf.lightmap = lm >= 0 ? lm : -1;
    surf.face_type = static_cast<uint8_t>(type);
    surf.kind = (tex.flags & kSurfSky) ? SurfaceKind::sky : (tex.contents & kContentsFog) ? SurfaceKind::fog : SurfaceKind::opaque;
    surf.first_index = static_cast<uint32_t>(s.indices.size());
    if (type == 2) {
      if (pw < 3 || ph < 3 || pw % 2 == 0 || ph % 2 == 0 || pw > kMaxPatchSide || ph > kMaxPatchSide ||
          static_cast<int64_t>(pw) * ph != nv)
        r.fail(where + ": a patch of " + std::to_string(pw) + "x" + std::to_string(ph) + " control points with " +
               std::to_string(nv) + " vertices (odd sides 3.." + std::to_string(kMaxPatchSide) + ")");
      cp.clear();
      for (int32_t i = 0; i < nv; ++i) {
        cp.push_back(vertex_at(r, static_cast<size_t>(vertex + i)));
        const std::string bad = check_vertex(cp.back(), lm >= 0);
        if (!bad.empty()) r.fail(where + ": vertex " + std::to_string(vertex + i) + " has " + bad);
      }
      tessellate_patch(cp, pw, ph, o, budget, r, where, s);
    } else {
      if (meshvert < 0 || nmv < 0 || nmv % 3 != 0 || static_cast<size_t>(meshvert) > nmesh ||
          static_cast<size_t>(nmv) > nmesh - meshvert)
        r.fail(where + " names mesh vertices " + std::to_string(meshvert) + "+" + std::to_string(nmv) + " of " +
               std::to_string(nmesh) + " (whole triangles)");
      if (s.vertices.size() + static_cast<size_t>(nv) > budget || s.indices.size() + static_cast<size_t>(nmv) > 6 * budget)
        r.fail(where + ": the map's faces would make more than " + std::to_string(budget) +
               " vertices (a quarter of the file's bytes)");
      const uint32_t base = static_cast<uint32_t>(s.vertices.size());
      for (int32_t i = 0; i < nv; ++i) {
        s.vertices.push_back(vertex_at(r, static_cast<size_t>(vertex + i)));
        const std::string bad = check_vertex(s.vertices.back(), lm >= 0);
        if (!bad.empty()) r.fail(where + ": vertex " + std::to_string(vertex + i) + " has " + bad);
      }
      for (int32_t i = 0; i < nmv; ++i) {
        const int32_t k = load_le32s(r.at(kMeshVerts, 4, static_cast<size_t>(meshvert + i)));
        if (k < 0 || k >= nv)
          r.fail(where + ": mesh vertex " + std::to_string(meshvert + i) + " is " + std::to_string(k) + ", not one of its " +
                 std::to_string(nv) + " vertices");
        s.indices.push_back(base + static_cast<uint32_t>(k));
      }
    }
    surf.index_count = static_cast<uint32_t>(s.indices.size()) - surf.first_index;
    if (surf.index_count != 0) s.surfaces.push_back(surf);
  }
  read_spawns(r, s);
  if (!s.vertices.empty()) {
    s.min = s.max = s.vertices[0].pos;
    for (const SceneVertex& v : s.vertices)
      for (int k = 0; k < 3; ++k) s.min[k] = std::min(s.min[k], v.pos[k]), s.max[k] = std::max(s.max[k], v.pos[k]);
  }
  return s;
}

}  // namespace vds::enc
