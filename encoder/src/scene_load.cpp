// vds encoder: scenes by name (vds/enc/scene.h): the game's .pk3 archives
// (zip, read with libzip) searched in the game's override order, maps
// looked up in them, textures resolved in them.
#include <zip.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

#include "vds/enc/scene.h"
#include "vds/enc/stream_writer.h"

namespace vds::enc {

struct Pk3Set::Archive {
  std::string path;
  zip_t* zip = nullptr;
};

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

}  // namespace

Pk3Set::Pk3Set(const std::string& dir) {
  std::vector<std::string> paths;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const std::string ext = lower(e.path().extension().string());
    if (e.is_regular_file() && ext == ".pk3") paths.push_back(e.path().string());
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
      if (entry != nullptr) index_[lower(entry)] = {archives_.size() - 1, static_cast<uint64_t>(i)};
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
  const auto it = index_.find(lower(entry));
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
  const auto found = index_.find(lower(entry));
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

std::string openarena_dir() {
  const char* env = std::getenv("VDS_OPENARENA_DIR");
  return env != nullptr && env[0] != '\0' ? env : "/usr/share/games/openarena/baseoa";
}

Scene load_scene(const std::string& scene, const SceneOptions& o) {
  const std::string ext = lower(std::filesystem::path(scene).extension().string());
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
  } else {
    throw std::runtime_error(scene + ": not a scene this tool reads (a .bsp file or an OpenArena map name)");
  }
  // Textures as the game finds them: TGA, then JPEG, then PNG; only those
  // a surface uses.
  std::vector<bool> used(s.textures.size(), false);
  for (const SceneSurface& f : s.surfaces) used[static_cast<size_t>(f.texture)] = true;
  if (std::filesystem::exists(openarena_dir())) {
    for (size_t k = 0; k < s.textures.size(); ++k) {
      if (!used[k]) continue;
      SceneTexture& t = s.textures[k];
      for (const char* e : {".tga", ".jpg", ".png"}) {
        uint64_t bytes = 0;
        std::string archive;
        if (archives().find(t.name + e, &bytes, &archive)) {
          t.file = t.name + e;
          t.archive = archive;
          t.bytes = bytes;
          break;
        }
      }
    }
  }
  return s;
}

}  // namespace vds::enc
