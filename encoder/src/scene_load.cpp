// vds encoder: scenes by name (vds/enc/scene.h): the game's .pk3 archives
// (zip, read with libzip) searched in the game's override order, maps
// looked up in them, textures resolved in them.
#include <zip.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "text.h"
#include "vds/enc/scene.h"
#include "vds/enc/scene_render.h"
#include "vds/io/image.h"
#include "vds/enc/stream_writer.h"

namespace vds::enc {

struct Pk3Set::Archive {
  std::string path;
  zip_t* zip = nullptr;
};

namespace {

// The shaders of the archives applied to the scene's textures, and each
// used texture's image resolved as the game does.
void apply_shaders(const Pk3Set& pk3, Scene* s) {
  std::vector<bool> used(s->textures.size(), false);
  for (const SceneSurface& f : s->surfaces) used[static_cast<size_t>(f.texture)] = true;
  ShaderTable shaders;
  for (const std::string& script : pk3.entries("scripts/", ".shader")) {
    std::vector<uint8_t> text;
    std::string archive;
    pk3.read(script, &text, &archive, uint64_t{8} << 20);
    read_shader_script(std::string(text.begin(), text.end()), archive + ":" + script, &shaders);
  }
  for (size_t k = 0; k < s->textures.size(); ++k) {
    if (!used[k]) continue;
    SceneTexture& t = s->textures[k];
    std::string image = t.name;
    const auto it = shaders.find(ascii_lower(t.name));
    if (it != shaders.end()) {
      const ShaderInfo& sh = it->second;
      t.scripted = true;
      t.blend = sh.blend;
      t.two_sided = sh.two_sided;
      t.vertex_colour = sh.vertex_colour || sh.stages == 0;
      if (sh.sky) t.flags |= 0x4;
      if (sh.nodraw) t.flags |= 0x80;
      if (sh.fog) t.contents |= 0x40;
      if (!sh.image.empty()) image = sh.image;
    } else {
      t.vertex_colour = true;  // the game's implicit shader: lightmap, else vertex colours
    }
    // The image's own extension is a hint only: the game tries TGA, then JPEG, then PNG.
    const std::filesystem::path ip(image);
    const std::string ext = ascii_lower(ip.extension().string());
    if (ext == ".tga" || ext == ".jpg" || ext == ".jpeg" || ext == ".png") image = image.substr(0, image.size() - ext.size());
    for (const char* e : {".tga", ".jpg", ".png"}) {
      uint64_t bytes = 0;
      std::string archive;
      if (pk3.find(image + e, &bytes, &archive)) {
        t.file = image + e;
        t.archive = archive;
        t.bytes = bytes;
        break;
      }
    }
  }
  // Surfaces by their shader: nodraw ones removed, sky, fog and additive ones marked.
  std::vector<uint32_t> indices;
  std::vector<SceneSurface> kept;
  for (SceneSurface f : s->surfaces) {
    const SceneTexture& t = s->textures[static_cast<size_t>(f.texture)];
    if (t.flags & 0x80) {
      ++s->skipped;
      continue;
    }
    if (t.flags & 0x4) f.kind = SurfaceKind::sky;
    else if (t.contents & 0x40) f.kind = SurfaceKind::fog;
    else if (t.blend == ShaderBlend::additive) f.kind = SurfaceKind::additive;
    const uint32_t first = static_cast<uint32_t>(indices.size());
    indices.insert(indices.end(), s->indices.begin() + f.first_index, s->indices.begin() + f.first_index + f.index_count);
    f.first_index = first;
    kept.push_back(f);
  }
  s->indices.swap(indices);
  s->surfaces.swap(kept);
}

}  // namespace

Pk3Set::Pk3Set(const std::string& dir) {
  std::vector<std::string> paths;
  std::error_code ec;
  if (std::filesystem::is_regular_file(dir, ec)) {
    paths.push_back(dir);  // one archive
  } else {
    for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
      const std::string ext = ascii_lower(e.path().extension().string());
      if (e.is_regular_file() && ext == ".pk3") paths.push_back(e.path().string());
    }
  }
  if (ec) throw std::runtime_error(dir + ": cannot list (" + ec.message() + ")");
  if (paths.empty()) throw std::runtime_error(dir + ": holds no .pk3 archive");
  // The game loads archives in name order; a later one overrides.
  std::sort(paths.begin(), paths.end());
  for (const std::string& p : paths) {
    int err = 0;
    zip_t* z = zip_open(p.c_str(), ZIP_RDONLY, &err);
    if (z == nullptr) {
      zip_error_t ze;
      zip_error_init_with_code(&ze, err);
      const std::string why = zip_error_strerror(&ze);
      zip_error_fini(&ze);
      close_all();
      throw std::runtime_error(p + ": not a readable .pk3 (zip) archive: " + why);
    }
    archives_.push_back(new Archive{p, z});
    // One index of every name (lower case; the game ignores case): a later
    // archive's entry replaces an earlier one's.
    const zip_int64_t n = zip_get_num_entries(z, 0);
    for (zip_int64_t i = 0; i < n; ++i) {
      const char* entry = zip_get_name(z, static_cast<zip_uint64_t>(i), 0);
      if (entry != nullptr) index_[ascii_lower(entry)] = {archives_.size() - 1, static_cast<uint64_t>(i)};
    }
  }
}

Pk3Set::~Pk3Set() { close_all(); }

void Pk3Set::close_all() {
  for (Archive* a : archives_) {
    zip_discard(a->zip);
    delete a;
  }
  archives_.clear();
}

bool Pk3Set::find(const std::string& entry, uint64_t* bytes, std::string* archive) const {
  const auto it = index_.find(ascii_lower(entry));
  if (it == index_.end()) return false;
  const Archive& a = *archives_[it->second.first];
  zip_stat_t st;
  zip_stat_init(&st);
  if (zip_stat_index(a.zip, it->second.second, 0, &st) != 0 || !(st.valid & ZIP_STAT_SIZE))
    throw std::runtime_error(a.path + ": " + entry + ": no size in the archive's directory");
  if (bytes) *bytes = st.size;
  if (archive) *archive = a.path;
  return true;
}

bool Pk3Set::read(const std::string& entry, std::vector<uint8_t>* out, std::string* archive, uint64_t max_bytes) const {
  const auto found = index_.find(ascii_lower(entry));
  if (found == index_.end()) return false;
  {
    const Archive& a = *archives_[found->second.first];
    zip_t* z = a.zip;
    const zip_uint64_t i = found->second.second;
    const std::string where = a.path + ": " + entry;
    zip_stat_t st;
    zip_stat_init(&st);
    if (zip_stat_index(z, i, 0, &st) != 0 || !(st.valid & ZIP_STAT_SIZE))
      throw std::runtime_error(where + ": no size in the archive's directory");
    if (st.size > max_bytes)
      throw std::runtime_error(where + ": " + std::to_string(st.size) + " bytes (the most read is " +
                               std::to_string(max_bytes) + ")");
    zip_file_t* f = zip_fopen_index(z, i, 0);
    if (f == nullptr) throw std::runtime_error(where + ": cannot open (" + zip_strerror(z) + ")");
    out->assign(st.size, 0);
    zip_int64_t got = 0;
    while (static_cast<zip_uint64_t>(got) < st.size) {
      const zip_int64_t n = zip_fread(f, out->data() + got, st.size - static_cast<zip_uint64_t>(got));
      if (n <= 0) break;
      got += n;
    }
    // Reading on to the end makes libzip check the entry's CRC.
    uint8_t extra;
    const zip_int64_t more = static_cast<zip_uint64_t>(got) == st.size ? zip_fread(f, &extra, 1) : -1;
    const std::string why = zip_file_strerror(f);
    zip_fclose(f);
    if (static_cast<zip_uint64_t>(got) != st.size || more != 0)
      throw std::runtime_error(where + ": damaged in the archive (" + why + ")");
    if (archive) *archive = a.path;
  }
  return true;
}

std::vector<std::string> Pk3Set::entries(const std::string& prefix, const std::string& suffix) const {
  const std::string p = ascii_lower(prefix), x = ascii_lower(suffix);
  std::vector<std::string> out;
  for (const auto& e : index_)
    if (e.first.size() >= p.size() + x.size() && e.first.compare(0, p.size(), p) == 0 &&
        e.first.compare(e.first.size() - x.size(), x.size(), x) == 0)
      out.push_back(e.first);
  std::sort(out.begin(), out.end());
  return out;
}

std::string openarena_dir() {
  const char* env = std::getenv("VDS_OPENARENA_DIR");
  return env != nullptr && env[0] != '\0' ? env : "/usr/share/games/openarena/baseoa";
}

Scene load_scene(const std::string& scene, const SceneOptions& o) {
  const std::string ext = ascii_lower(std::filesystem::path(scene).extension().string());
  std::unique_ptr<Pk3Set> pk3;
  const auto archives = [&]() -> const Pk3Set& {
    if (!pk3) pk3 = std::make_unique<Pk3Set>(openarena_dir());
    return *pk3;
  };
  Scene s;
  if (ext == ".bsp") {
    const std::vector<uint8_t> bytes = read_file(scene);
    s = read_bsp(bytes.data(), bytes.size(), scene, o);
  } else if (ext.empty() && scene.find('/') == std::string::npos) {
    std::vector<uint8_t> bytes;
    const std::string entry = "maps/" + scene + ".bsp";
    std::string archive;
    if (!archives().read(entry, &bytes, &archive, uint64_t{256} << 20))
      throw std::runtime_error(scene + ": no map of that name (" + entry + ") in the archives of " + openarena_dir() +
                               " (install openarena-data, or set VDS_OPENARENA_DIR)");
    s = read_bsp(bytes.data(), bytes.size(), archive + ":" + entry, o);
    s.name = scene;
  } else if (ext == ".gltf" || ext == ".glb" || ext == ".obj") {
    return load_model_scene(scene);
  } else {
    throw std::runtime_error(scene + ": not a scene this tool reads (a .bsp, .gltf, .glb or .obj file, or an OpenArena map name)");
  }
  if (std::filesystem::exists(openarena_dir())) apply_shaders(archives(), &s);
  return s;
}

std::vector<io::Image> load_scene_images(const Scene& s) {
  std::vector<io::Image> out(s.textures.size());
  std::unique_ptr<Pk3Set> pk3;
  for (size_t t = 0; t < s.textures.size(); ++t) {
    const SceneTexture& tex = s.textures[t];
    if (tex.file.empty()) continue;
    if (!tex.embedded.empty()) {
      out[t] = io::decode_image(tex.embedded.data(), tex.embedded.size(), s.name + ":" + tex.file, 4);
      continue;
    }
    if (tex.archive.empty()) {
      out[t] = io::load_image(tex.file, 4);
      continue;
    }
    if (!pk3) pk3 = std::make_unique<Pk3Set>(openarena_dir());
    std::vector<uint8_t> bytes;
    std::string archive;
    if (!pk3->read(tex.file, &bytes, &archive))
      throw std::runtime_error(s.name + ": texture " + tex.file + " is no longer in the archives of " + openarena_dir());
    out[t] = io::decode_image(bytes.data(), bytes.size(), archive + ":" + tex.file, 4);
  }
  return out;
}

}  // namespace vds::enc
