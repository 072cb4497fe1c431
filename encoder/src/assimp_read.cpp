// vds encoder: model files read with assimp (assimp_read.h).
#include "assimp_read.h"

#include <cstring>
#include <memory>
#include <set>
#include <stdexcept>

#include <assimp/BaseImporter.h>
#include <assimp/config.h>
#include <assimp/DefaultIOSystem.h>
#include <assimp/MemoryIOWrapper.h>

#include "mesh_glb_check.h"
#include "mesh_collada_check.h"
#include "mesh_iqm_check.h"
#include "mesh_md2_check.h"
#include "mesh_md3_check.h"
#include "mesh_ms3d_check.h"
#include "mesh_ply_check.h"
#include "text.h"

namespace vds::enc {

std::string confined_path(const std::filesystem::path& root, const std::string& file) {
  if (root.empty()) return "";
  std::filesystem::path p(file);
  std::error_code ec;
  if (p.is_relative()) p = root / p;
  const std::string a = std::filesystem::weakly_canonical(p, ec).string();
  const std::string r = root.string();
  if (ec || a.size() <= r.size() || a.compare(0, r.size(), r) != 0 || a[r.size()] != '/') return "";
  return a;
}

namespace {

// A material library's texture statement before any `newmtl` makes assimp's
// OBJ loader write through a null material: refused, with the line.
std::string check_mtl(const uint8_t* data, size_t size, const std::string& name) {
  bool material = false;
  size_t line = 1;
  for (size_t i = 0; i < size;) {
    size_t end = i;
    while (end < size && data[end] != '\n') ++end;
    size_t k = i;
    while (k < end && (data[k] == ' ' || data[k] == '\t')) ++k;
    std::string word;
    while (k < end && data[k] != ' ' && data[k] != '\t' && data[k] != '\r' && word.size() < 16) word += static_cast<char>(data[k++]);
    if (word == "newmtl") material = true;
    const bool texture = word.rfind("map_", 0) == 0 || word == "bump" || word == "disp" || word == "decal" ||
                         word == "refl" || word == "norm";
    if (texture && !material) return name + ": '" + word + "' before any 'newmtl' (line " + std::to_string(line) + ")";
    i = end + 1;
    ++line;
  }
  return "";
}

// Assimp's file access confined to the model's own folder: a file that
// references others (glTF buffers and images, OBJ materials) may open only
// files in that folder or below it, never an absolute path elsewhere or a
// path leading out with "..". The model itself is served from memory under
// `main` (its own name with its format's extension), so that a loader's
// fallback names derived from it (an OBJ's "NAME.mtl") resolve like any
// other file. A model held in memory may open no other file. Material
// libraries (check_mtl) and the further parts of an MD3 player (check_md3)
// are checked before the loader sees them.
class ConfinedIO : public Assimp::DefaultIOSystem {
 public:
  ConfinedIO(std::filesystem::path root, std::string main, const uint8_t* data, size_t size)
      : root_(std::move(root)), main_(std::move(main)), data_(data), size_(size) {}
  // Asking whether a file outside the folder exists is not refused (loaders
  // probe for optional files: an MD3's shader scripts); opening one is.
  bool Exists(const char* file) const override {
    if (file == nullptr) return false;
    if (main_ == file) return true;
    const std::string p = confined_path(root_, file);
    return !p.empty() && DefaultIOSystem::Exists(p.c_str());
  }
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    if (std::strchr(mode, 'w') != nullptr || std::strchr(mode, 'a') != nullptr) return nullptr;
    if (file != nullptr && main_ == file) return new Assimp::MemoryIOStream(data_, size_, false);
    const std::string p = resolve(file);
    if (p.empty()) return nullptr;
    const std::string ext = extension_of(p);
    if (ext != "mtl" && ext != "md3") return DefaultIOSystem::Open(p.c_str(), mode);
    std::unique_ptr<Assimp::IOStream> in(DefaultIOSystem::Open(p.c_str(), mode));
    if (!in) return nullptr;
    const size_t n = in->FileSize();
    if (n > (size_t{64} << 20)) {
      if (problem_.empty()) problem_ = std::string(file) + ": a file over 64 MiB";
      return nullptr;
    }
    auto* bytes = new uint8_t[n == 0 ? 1 : n];
    const size_t got = n == 0 ? 0 : in->Read(bytes, 1, n);
    std::string bad = got == n ? std::string() : std::string(file) + ": cannot be read whole";
    if (bad.empty() && ext == "mtl") bad = check_mtl(bytes, n, file);
    // The other parts of a multi-part MD3 player (upper, head) are checked as the first was.
    if (bad.empty() && ext == "md3") {
      try {
        check_md3(bytes, n, file);
      } catch (const std::runtime_error& e) {
        bad = e.what();
      }
    }
    if (!bad.empty()) {
      delete[] bytes;
      if (problem_.empty()) problem_ = bad;
      return nullptr;
    }
    return new Assimp::MemoryIOStream(bytes, n, true);
  }
  // What a checked file the importer opened had wrong ("" if nothing).
  const std::string& problem() const { return problem_; }
  // The first file the importer was not allowed to open.
  const std::string& refused() const { return refused_; }

 private:
  // A file the model names (relative to the model's folder), as an absolute
  // path inside that folder; "" (and noted) if it lies outside.
  // A model held in memory (no root) opens nothing else, and a loader that
  // needs another file says so itself; one on disk is told which file lay
  // outside its folder.
  std::string resolve(const char* file) const {
    if (file == nullptr) return "";
    const std::string a = confined_path(root_, file);
    if (a.empty() && refused_.empty() && !root_.empty()) refused_ = file;
    return a;
  }
  std::filesystem::path root_;
  std::string main_;
  const uint8_t* data_;
  size_t size_;
  mutable std::string refused_;
  std::string problem_;
};

// The formats assimp reads for this tool: the ones its fuzz harness covers
// (tests/fuzz/fuzz_mesh_import.cpp). Assimp reads dozens more, some of
// which trust the counts a file declares.
bool imported_format(const std::string& ext) {
  static const char* const kFormats[] = {"obj", "ply", "gltf", "glb", "3ds", "dae", "iqm", "md2", "md3", "ms3d"};
  for (const char* f : kFormats)
    if (ext == f) return true;
  return false;
}

}  // namespace

const aiScene* read_with_assimp(Assimp::Importer& importer, const uint8_t* data, size_t size, const std::string& name,
                                const std::string& hint, const std::filesystem::path& root, unsigned steps) {
  // PLY is checked by the project's own reader first: assimp's PLY loader
  // trusts the header's counts and list lengths.
  const bool ply = hint == "ply" || looks_like_ply(data, size);
  if (ply) check_ply(data, size, name);
  // Content that says PLY or GLB is checked as such whatever the name says.
  const bool glb = size >= 4 && std::memcmp(data, "glTF", 4) == 0;
  const std::string format = ply ? "ply" : glb ? "glb" : hint;
  // GLB's lengths are checked by the project's own reader first: assimp
  // allocates what they say.
  if (format == "glb") check_glb(data, size, name);
  // IQM's counts and offsets are checked by the project's own reader first:
  // assimp's loader takes them as given.
  if (format == "iqm") check_iqm(data, size, name);
  if (format == "md3") check_md3(data, size, name);
  // MD2's offsets and MS3D's chained counts too.
  if (format == "md2") check_md2(data, size, name);
  if (format == "ms3d") check_ms3d(data, size, name);
  // Collada's counts, strides and indices too.
  if (format == "dae") check_collada(data, size, name);
  // The model under its own name with its format's extension (see ConfinedIO).
  std::string stem = std::filesystem::path(name).stem().string();
  if (stem.empty() || stem.find('$') != std::string::npos) stem = "model";
  const std::string main = stem + "." + format;
  // An MD3's shader scripts live in the game's folders, outside the model's:
  // looked for in the model's folder only (the skin files beside the model
  // name its textures).
  importer.SetPropertyBool(AI_CONFIG_IMPORT_MD3_LOAD_SHADERS, false);
  // A player's parts are read one file at a time (assimp's multi-part
  // loading reads them through importers of its own, without these settings).
  importer.SetPropertyBool(AI_CONFIG_IMPORT_MD3_HANDLE_MULTIPART, false);
  if (!root.empty()) importer.SetPropertyString(AI_CONFIG_IMPORT_MD3_SHADER_SRC, root.string() + "/");
  ConfinedIO* io = new ConfinedIO(root, main, data, size);  // owned by the importer
  importer.SetIOHandler(io);
  // Only the loader of the format the name says: assimp would otherwise
  // guess from the content (any file with "ply" in its first 200 bytes
  // looks like a PLY to it) and hand the bytes to a loader nothing checked.
  if (!imported_format(format) || importer.GetImporter(format.c_str()) == nullptr)
    throw std::runtime_error(name + ": not a mesh format this tool reads ('" + format +
                             "'; it reads .obj, .ply, .gltf, .glb, .3ds, .dae, .iqm, .md2, .md3, .ms3d and .drc)");
  for (size_t i = importer.GetImporterCount(); i-- > 0;) {
    Assimp::BaseImporter* loader = importer.GetImporter(i);
    std::set<std::string> extensions;
    loader->GetExtensionList(extensions);
    // Every loader that claims the extension stays (glTF 1 and 2 share one).
    if (extensions.count(format) == 0 && importer.UnregisterLoader(loader) == aiReturn_SUCCESS)
      delete loader;  // the importer owns its loaders only while they are registered
  }
  const aiScene* scene = importer.ReadFile(main, steps);
  if (!io->problem().empty()) throw std::runtime_error(name + ": " + io->problem());
  if (!io->refused().empty())
    throw std::runtime_error(name + ": refers to '" + io->refused() +
                             "', which is not in the model's folder (only files beside the model or below it are read)");
  if (scene == nullptr) throw std::runtime_error(name + ": cannot import: " + importer.GetErrorString());
  return scene;
}

}  // namespace vds::enc
