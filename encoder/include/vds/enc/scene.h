// vds encoder: scenes for walkthroughs. A Quake III Arena / OpenArena map
// (.bsp, read straight from the game's .pk3 archives when given by name)
// becomes triangles with their textures, lightmaps and spawn points.
//
// What is kept, by rule:
// - the faces of every model of the map: the world (model 0) and the brush
//   entities (doors, lifts) where the map places them at rest;
// - polygon and mesh faces as their triangles; Bezier patches tessellated
//   so that no point of the tessellation is further than
//   SceneOptions::patch_tolerance (map units) from the curved surface;
// - billboards (flares) are dropped;
// - a face is drawn, sky, or skipped by its texture's surface flags: nodraw
//   (0x80) and hint/skip (0x100, 0x200) faces are skipped, sky (0x4) faces
//   are kept as sky (drawn by the renderer's sky rule), and faces inside
//   fog (contents 0x40) are kept as fog.
// Every count and index the file declares is checked against the file before
// it is used: a bad file is refused with its name, the lump and the element.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace vds::enc {

struct SceneVertex {
  std::array<float, 3> pos{};     // map units (Quake: Z up)
  std::array<float, 2> uv{};      // texture coordinates (repeating)
  std::array<float, 2> lm_uv{};   // lightmap coordinates, [0, 1] of its lightmap
  std::array<float, 3> normal{};
  std::array<uint8_t, 4> color{};  // vertex colour (RGBA)
};

// How a surface is drawn: opaque (alpha-tested when its texture says so),
// sky (the sky's colour), fog (a fog volume's side: not drawn), additive
// (an effect added onto what lies behind it, no depth written).
enum class SurfaceKind : uint8_t { opaque, sky, fog, additive };

// A run of triangles with one texture and one lightmap.
struct SceneSurface {
  int texture = -1;   // into Scene::textures
  int lightmap = -1;  // into Scene::lightmaps, -1 for none (vertex lit)
  SurfaceKind kind = SurfaceKind::opaque;
  uint32_t first_index = 0, index_count = 0;  // into Scene::indices (whole triangles)
  uint8_t face_type = 0;                      // the BSP face type (1 polygon, 2 patch, 3 mesh)
};

// A shader script's definition, reduced to what a walkthrough draws (the
// rule: encoder/src/scene_shader.cpp and docs/walkthrough.md).
enum class ShaderBlend : uint8_t { opaque, alpha_test, additive };
struct ShaderInfo {
  std::string image;  // the first stage's image ("" if none)
  ShaderBlend blend = ShaderBlend::opaque;
  bool sky = false, fog = false, nodraw = false, two_sided = false;
  bool lightmapped = false;    // a stage draws $lightmap
  bool vertex_colour = false;  // the image's stage is lit by vertex colours
  int stages = 0;
};
// Shaders by lower-case name.
using ShaderTable = std::unordered_map<std::string, ShaderInfo>;
// Adds one script's shaders to `table`, replacing earlier definitions of
// the same name. Throws std::runtime_error "NAME: what (line N)".
void read_shader_script(const std::string& text, const std::string& name, ShaderTable* table);

struct SceneTexture {
  std::string name;     // as the map names it ("textures/base_wall/concrete")
  uint32_t flags = 0;   // surface flags
  uint32_t contents = 0;
  bool scripted = false;  // a shader script defines it (the fields below are its)
  ShaderBlend blend = ShaderBlend::opaque;
  bool two_sided = false;
  bool vertex_colour = false;  // lit by vertex colours where it has no lightmap
  std::string file;     // the image file that supplies it ("" if none does)
  std::string archive;  // the archive holding it ("" for a file on disk)
  uint64_t bytes = 0;   // the file's size
  std::vector<uint8_t> embedded;  // the image file's bytes when the scene file holds them (GLB)
};

struct SpawnPoint {
  std::array<float, 3> origin{};
  float yaw_deg = 0;
  std::string classname;
};

constexpr int kLightmapSide = 128;

struct Scene {
  std::string name;
  std::string kind = "Quake III map";
  double metres_per_unit = 1.0 / 32;  // Quake: a player (56 units) is 1.75 m
  bool overbright = true;             // lightmaps and vertex colours brightened as the game does
  std::vector<SceneVertex> vertices;
  std::vector<uint32_t> indices;  // triangles
  std::vector<SceneSurface> surfaces;
  std::vector<SceneTexture> textures;
  std::vector<std::vector<uint8_t>> lightmaps;  // kLightmapSide^2 RGB each
  std::vector<SpawnPoint> spawns;
  // The BSP's faces by type, as read (before any is skipped).
  uint32_t polygons = 0, patches = 0, meshes = 0, billboards = 0, skipped = 0;
  std::array<float, 3> min{}, max{};  // bounds of the kept vertices

  size_t triangles() const { return indices.size() / 3; }
};

struct SceneOptions {
  double patch_tolerance = 1.0;  // map units
  int patch_max_steps = 16;      // per 3x3 patch and direction
};

// Reads a .bsp held in memory. Throws std::runtime_error "NAME: what (where)".
Scene read_bsp(const uint8_t* data, size_t size, const std::string& name, const SceneOptions& o = SceneOptions{});

// A set of Quake III .pk3 archives (zip files), searched as the game does:
// an archive later in name order overrides an earlier one.
class Pk3Set {
 public:
  // Every .pk3 in `dir` (throws if there is none or one is not a zip), or
  // the one zip file `dir` names.
  explicit Pk3Set(const std::string& dir);
  ~Pk3Set();
  Pk3Set(const Pk3Set&) = delete;
  Pk3Set& operator=(const Pk3Set&) = delete;
  // The entry's bytes from the archive that overrides all others; false if
  // no archive holds it. Throws on an entry larger than `max_bytes` or a
  // damaged one (CRC).
  bool read(const std::string& entry, std::vector<uint8_t>* out, std::string* archive = nullptr,
            uint64_t max_bytes = uint64_t{64} << 20) const;
  // The entry's size and archive without reading it; false if none holds it.
  bool find(const std::string& entry, uint64_t* bytes, std::string* archive) const;
  // Every entry (lower case) that starts with `prefix` and ends with `suffix`, in name order.
  std::vector<std::string> entries(const std::string& prefix, const std::string& suffix) const;

 private:
  struct Archive;
  void close_all();
  std::vector<Archive*> archives_;  // in override order: the last wins
  std::unordered_map<std::string, std::pair<size_t, uint64_t>> index_;  // lower-case name -> (archive, entry)
};

// The directory of the installed OpenArena data: $VDS_OPENARENA_DIR, else
// Debian's /usr/share/games/openarena/baseoa.
std::string openarena_dir();

// A textured glTF 2.0 (.gltf, .glb) or OBJ (+ MTL) scene through assimp,
// by rule: Y up in the file becomes Z up (x, -z, y); metres; each material's
// base colour (glTF) or diffuse (OBJ) texture, from the file (GLB) or a
// file beside the scene or below its folder (anything else is refused);
// vertex colours, else the material's colour, multiply the texture; no
// lightmaps and no overbright (the scene is drawn as its colours say);
// faces that are not triangles dropped. Spawn points: none (a tour starts
// at the centre of the scene's bounds). Throws naming the file.
Scene load_model_scene(const std::string& path);
// The same from memory (`name` gives the format by its extension); it may
// open no other file, so a texture outside the bytes is missing.
Scene read_model_scene(const uint8_t* data, size_t size, const std::string& name);

// A scene named on the command line: a .gltf, .glb or .obj file (above), a .bsp file, or a map name looked up
// as maps/NAME.bsp in the installed OpenArena archives. The archives'
// shader scripts (scripts/*.shader, in name order, a later definition
// replacing an earlier) reduce each texture to one image; images are
// resolved in the archives (TGA, then JPEG, then PNG, as the game tries
// them). Throws std::runtime_error naming the scene and the problem.
Scene load_scene(const std::string& scene, const SceneOptions& o = SceneOptions{});

}  // namespace vds::enc
