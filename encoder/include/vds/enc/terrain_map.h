// Terrain maps for the terrain mode: an elevation grid and a colour map
// over the same ground, with their scales.
//
// Read from Trigger Rally's levels (Debian's trigger-rally-data: maps in
// data.zip, each a `<name>.level` XML file naming the heightmap, the colour
// map and the horizontal and vertical scales) or from any heightmap (8- or
// 16-bit grey PNG or PGM, or a colour image whose R + G + B is the height)
// with any colour image. Every error names the file and what is wrong.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "vds/io/image.h"

namespace vds::enc {

struct TerrainMap {
  std::string name;
  // Elevation samples, row-major: row 0 is the colour map's top row, and
  // sample (x, y) lies at ground position (x, y) * horizontal_scale.
  int width = 0, height = 0;
  std::vector<uint16_t> heights;
  double horizontal_scale = 1;  // metres between neighbouring samples
  double metres_per_unit = 1;   // metres per height unit
  // Colour (R'G'B') over the same ground: its corners on the grid's corners.
  io::Image colour;

  double width_m() const { return (width - 1) * horizontal_scale; }
  double depth_m() const { return (height - 1) * horizontal_scale; }
  // Height in metres at ground position (gx, gy) in samples (bilinear,
  // clamped to the grid).
  double height_at(double gx, double gy) const;
};

// What a Trigger Rally .level file says about its terrain.
struct TerrainLevel {
  std::string heightmap, colormap;          // file names beside the .level
  double horizontal_scale = 1, vertical_scale = 1;  // metres per sample, per height level
};
// Parses a .level file held in memory; throws std::runtime_error
// "NAME: what" for anything but an XML document with a <terrain> element
// naming both maps with finite positive scales.
TerrainLevel parse_level(const uint8_t* data, size_t size, const std::string& name);

// Builds a map from a heightmap and a colour image held in memory.
// vertical_scale is metres per level of the heightmap's file (a colour
// heightmap's level is a third of a unit). Throws naming the files.
TerrainMap read_terrain(const uint8_t* height_data, size_t height_size, const std::string& height_name,
                        const uint8_t* colour_data, size_t colour_size, const std::string& colour_name,
                        double horizontal_scale, double vertical_scale);

// A terrain named on the command line:
//   a .level file (its maps beside it),
//   a folder holding one .level file,
//   NAME or ZIP:NAME: maps/NAME/NAME.level in Trigger Rally's data.zip
//   (trigger_rally_zip() when ZIP is not given).
TerrainMap load_terrain(const std::string& what);
// A heightmap file and a colour file with their scales.
TerrainMap load_terrain_files(const std::string& heightmap, const std::string& colour, double horizontal_scale,
                              double vertical_scale);

// $VDS_TRIGGER_RALLY_ZIP, else Debian's /usr/share/games/trigger-rally/data.zip.
std::string trigger_rally_zip();

}  // namespace vds::enc
