// Terrain maps: Trigger Rally levels and heightmap + colour image pairs
// (vds/enc/terrain_map.h).
#include "vds/enc/terrain_map.h"

#include <tinyxml2.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

#include "vds/enc/scene.h"
#include "vds/enc/stream_writer.h"

namespace vds::enc {

namespace {

[[noreturn]] void refuse(const std::string& what, const std::string& why) { throw std::runtime_error(what + ": " + why); }

// The largest map read: the client's cell limit (8 texels a cell) on a
// side, and one more elevation sample than cells.
constexpr int kMaxColourSide = 8192;
constexpr int kMaxSide = kMaxColourSide + 1;
// A .level file larger than this is not a level.
constexpr size_t kMaxLevelBytes = 1u << 20;

double scale_attribute(const tinyxml2::XMLElement* e, const char* attr, const std::string& name) {
  const char* text = e->Attribute(attr);
  if (text == nullptr) refuse(name, std::string("<terrain> has no ") + attr);
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  while (end != nullptr && (*end == ' ' || *end == '\t')) ++end;
  if (end == text || end == nullptr || *end != '\0' || !std::isfinite(v) || v <= 0 || v > 1e6)
    refuse(name, std::string("<terrain> ") + attr + "=\"" + text + "\" is not a positive number up to 1e6");
  return v;
}

// A file name from the level: a plain name beside the .level (no folders,
// which a level has no need of and a hostile one could use to escape).
std::string map_file(const tinyxml2::XMLElement* e, const char* attr, const std::string& name) {
  const char* text = e->Attribute(attr);
  if (text == nullptr || *text == '\0') refuse(name, std::string("<terrain> has no ") + attr);
  const std::string f = text;
  if (f.find('/') != std::string::npos || f.find('\\') != std::string::npos || f == "." || f == ".." ||
      f.size() > 255)
    refuse(name, std::string("<terrain> ") + attr + "=\"" + f + "\" is not a file name beside the level");
  return f;
}

}  // namespace

double TerrainMap::height_at(double gx, double gy) const {
  gx = std::clamp(gx, 0.0, static_cast<double>(width - 1));
  gy = std::clamp(gy, 0.0, static_cast<double>(height - 1));
  const int x0 = std::min(static_cast<int>(gx), width - 2 < 0 ? 0 : width - 2);
  const int y0 = std::min(static_cast<int>(gy), height - 2 < 0 ? 0 : height - 2);
  const int x1 = std::min(x0 + 1, width - 1), y1 = std::min(y0 + 1, height - 1);
  const double fx = gx - x0, fy = gy - y0;
  auto h = [&](int x, int y) { return static_cast<double>(heights[static_cast<size_t>(y) * width + x]); };
  const double top = h(x0, y0) * (1 - fx) + h(x1, y0) * fx;
  const double bottom = h(x0, y1) * (1 - fx) + h(x1, y1) * fx;
  return (top * (1 - fy) + bottom * fy) * metres_per_unit;
}

TerrainLevel parse_level(const uint8_t* data, size_t size, const std::string& name) {
  if (size == 0) refuse(name, "the file is empty");
  if (size > kMaxLevelBytes) refuse(name, "a level file of " + std::to_string(size) + " bytes (at most 1 MiB is read)");
  tinyxml2::XMLDocument doc;
  if (doc.Parse(reinterpret_cast<const char*>(data), size) != tinyxml2::XML_SUCCESS)
    refuse(name, std::string("not an XML document (") + doc.ErrorStr() + ")");
  const tinyxml2::XMLElement* level = doc.FirstChildElement("level");
  if (level == nullptr) refuse(name, "no <level> element");
  const tinyxml2::XMLElement* terrain = level->FirstChildElement("terrain");
  if (terrain == nullptr) refuse(name, "<level> has no <terrain> element");
  TerrainLevel t;
  t.heightmap = map_file(terrain, "heightmap", name);
  t.colormap = map_file(terrain, "colormap", name);
  t.horizontal_scale = scale_attribute(terrain, "horizontalscale", name);
  t.vertical_scale = scale_attribute(terrain, "verticalscale", name);
  return t;
}

TerrainMap read_terrain(const uint8_t* height_data, size_t height_size, const std::string& height_name,
                        const uint8_t* colour_data, size_t colour_size, const std::string& colour_name,
                        double horizontal_scale, double vertical_scale) {
  if (!std::isfinite(horizontal_scale) || horizontal_scale <= 0 || !std::isfinite(vertical_scale) || vertical_scale <= 0)
    refuse(height_name, "the scales must be positive numbers");
  io::Heightmap hm = io::decode_heightmap(height_data, height_size, height_name);
  if (hm.width < 2 || hm.height < 2 || hm.width > kMaxSide || hm.height > kMaxSide)
    refuse(height_name, "a " + std::to_string(hm.width) + "x" + std::to_string(hm.height) +
                            " heightmap (2 to " + std::to_string(kMaxSide) + " samples on a side are read)");
  TerrainMap m;
  m.width = hm.width;
  m.height = hm.height;
  m.heights = std::move(hm.values);
  m.horizontal_scale = horizontal_scale;
  m.metres_per_unit = vertical_scale / hm.units_per_level;
  m.colour = io::decode_image(colour_data, colour_size, colour_name, 3);
  if (m.colour.width < 8 || m.colour.height < 8 || m.colour.width > kMaxColourSide || m.colour.height > kMaxColourSide)
    refuse(colour_name, "a " + std::to_string(m.colour.width) + "x" + std::to_string(m.colour.height) +
                            " colour map (8 to " + std::to_string(kMaxColourSide) + " pixels on a side are read)");
  return m;
}

TerrainMap load_terrain_files(const std::string& heightmap, const std::string& colour, double horizontal_scale,
                              double vertical_scale) {
  const std::vector<uint8_t> h = read_file(heightmap);
  const std::vector<uint8_t> c = read_file(colour);
  TerrainMap m = read_terrain(h.data(), h.size(), heightmap, c.data(), c.size(), colour, horizontal_scale, vertical_scale);
  m.name = std::filesystem::path(heightmap).parent_path().filename().string();
  if (m.name.empty()) m.name = std::filesystem::path(heightmap).stem().string();
  return m;
}

std::string trigger_rally_zip() {
  const char* env = std::getenv("VDS_TRIGGER_RALLY_ZIP");
  return env != nullptr && *env != '\0' ? env : "/usr/share/games/trigger-rally/data.zip";
}

TerrainMap load_terrain(const std::string& what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path level_path;
  if (fs::is_directory(what, ec)) {
    for (const auto& e : fs::directory_iterator(what, ec))
      if (e.path().extension() == ".level") {
        if (!level_path.empty()) refuse(what, "holds more than one .level file");
        level_path = e.path();
      }
    if (level_path.empty()) refuse(what, "holds no .level file");
  } else if (fs::path(what).extension() == ".level") {
    level_path = what;
  }
  if (!level_path.empty()) {
    const std::vector<uint8_t> bytes = read_file(level_path.string());
    const TerrainLevel t = parse_level(bytes.data(), bytes.size(), level_path.string());
    const fs::path dir = level_path.parent_path();
    TerrainMap m = load_terrain_files((dir / t.heightmap).string(), (dir / t.colormap).string(), t.horizontal_scale,
                                      t.vertical_scale);
    m.name = level_path.stem().string();
    return m;
  }
  // NAME or ZIP:NAME in a Trigger Rally archive.
  std::string zip = trigger_rally_zip(), name = what;
  const size_t colon = what.rfind(':');
  if (colon != std::string::npos) {
    zip = what.substr(0, colon);
    name = what.substr(colon + 1);
  }
  if (name.empty() || name.find('/') != std::string::npos || name.find("..") != std::string::npos)
    refuse(what, "not a .level file, a folder with one, or a map name");
  if (!fs::is_regular_file(zip, ec))
    refuse(what, "not a .level file or a folder, and no Trigger Rally archive at " + zip +
                     " to look it up in (install trigger-rally-data: scripts/fetch-data.sh)");
  Pk3Set archive(zip);
  const std::string dir = "maps/" + name + "/";
  std::vector<uint8_t> level;
  if (!archive.read(dir + name + ".level", &level, nullptr, kMaxLevelBytes))
    refuse(zip, "holds no map " + name + " (" + dir + name + ".level)");
  const TerrainLevel t = parse_level(level.data(), level.size(), zip + ":" + dir + name + ".level");
  std::vector<uint8_t> h, c;
  if (!archive.read(dir + t.heightmap, &h)) refuse(zip, "holds no " + dir + t.heightmap);
  if (!archive.read(dir + t.colormap, &c)) refuse(zip, "holds no " + dir + t.colormap);
  TerrainMap m = read_terrain(h.data(), h.size(), zip + ":" + dir + t.heightmap, c.data(), c.size(),
                              zip + ":" + dir + t.colormap, t.horizontal_scale, t.vertical_scale);
  m.name = name;
  return m;
}

}  // namespace vds::enc
