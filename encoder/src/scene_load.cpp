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

Pk3Set::Pk3Set(const std::string& dir) {
  std::vector<std::string> paths;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    std::string ext = e.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
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
  for (auto it = archives_.rbegin(); it != archives_.rend(); ++it) {
    const zip_int64_t i = zip_name_locate((*it)->zip, entry.c_str(), ZIP_FL_NOCASE);
    if (i < 0) continue;
    zip_stat_t st;
    zip_stat_init(&st);
    if (zip_stat_index((*it)->zip, static_cast<zip_uint64_t>(i), 0, &st) != 0 || !(st.valid & ZIP_STAT_SIZE))
      throw std::runtime_error((*it)->path + ": " + entry + ": no size in the archive's directory");
    if (bytes) *bytes = st.size;
    if (archive) *archive = (*it)->path;
    return true;
  }
  return false;
}

bool Pk3Set::read(const std::string& entry, std::vector<uint8_t>* out, std::string* archive, uint64_t max_bytes) const {
  for (auto it = archives_.rbegin(); it != archives_.rend(); ++it) {
    zip_t* z = (*it)->zip;
    const zip_int64_t i = zip_name_locate(z, entry.c_str(), ZIP_FL_NOCASE);
    if (i < 0) continue;
    const std::string where = (*it)->path + ": " + entry;
    zip_stat_t st;
    zip_stat_init(&st);
    if (zip_stat_index(z, static_cast<zip_uint64_t>(i), 0, &st) != 0 || !(st.valid & ZIP_STAT_SIZE))
      throw std::runtime_error(where + ": no size in the archive's directory");
    if (st.size > max_bytes)
      throw std::runtime_error(where + ": " + std::to_string(st.size) + " bytes (the most read is " +
                               std::to_string(max_bytes) + ")");
    zip_file_t* f = zip_fopen_index(z, static_cast<zip_uint64_t>(i), 0);
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
    if (archive) *archive = (*it)->path;
    return true;
  }
  return false;
}

std::string openarena_dir() {
  const char* env = std::getenv("VDS_OPENARENA_DIR");
  return env != nullptr && env[0] != '\0' ? env : "/usr/share/games/openarena/baseoa";
}

Scene load_scene(const std::string& scene, const SceneOptions& o) {
  std::string ext = std::filesystem::path(scene).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
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
  // Textures as the game finds them: TGA, then JPEG, then PNG.
  if (std::filesystem::exists(openarena_dir())) {
    for (SceneTexture& t : s.textures) {
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
