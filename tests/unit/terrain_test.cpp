// Terrain mode: maps in (Trigger Rally levels, heightmaps of any depth),
// the elevation coder, the shrinking masks against a double-precision
// reading of the paper's rule, and the texture updates: the client's store
// equals the server's mirror after every update, nothing is sent twice
// unless it was dropped, nothing is missing after eviction, every update
// keeps its byte budget and every prefix of one is refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "vds/enc/stream_writer.h"
#include "vds/enc/terrain_map.h"
#include "vds/enc/terrain_server.h"
#include "vds/enc/terrain_tiles.h"
#include "vds/io/image.h"
#include "vds/terrain.h"
#include "terrain_maps.h"
#include "xorshift.h"

namespace {

using vds::Status;
using vds::terrain::Mask;
namespace enc = vds::enc;
namespace terrain = vds::terrain;

constexpr double kPi = 3.14159265358979323846;

// --- Maps -------------------------------------------------------------------------------

std::vector<uint8_t> bytes_of(const std::string& s) { return {s.begin(), s.end()}; }

std::string level_xml(const std::string& terrain_attrs) {
  return "<?xml version=\"1.0\" ?>\n<level name=\"T\">\n <terrain " + terrain_attrs + " >\n </terrain>\n</level>\n";
}

TEST(TerrainMap, ParsesATriggerRallyLevel) {
  const auto b = bytes_of(level_xml(
      "heightmap=\"h.png\" colormap=\"c.jpg\" tilesize=\"64\" horizontalscale=\"2.5\" verticalscale=\"0.3\""));
  const enc::TerrainLevel t = enc::parse_level(b.data(), b.size(), "x.level");
  EXPECT_EQ(t.heightmap, "h.png");
  EXPECT_EQ(t.colormap, "c.jpg");
  EXPECT_DOUBLE_EQ(t.horizontal_scale, 2.5);
  EXPECT_DOUBLE_EQ(t.vertical_scale, 0.3);
}

TEST(TerrainMap, RefusesBadLevelsNamingTheFileAndTheFault) {
  const struct {
    std::string text, says;
  } cases[] = {
      {"", "empty"},
      {"not xml <", "not an XML document"},
      {"<other/>", "no <level>"},
      {"<level></level>", "no <terrain>"},
      {level_xml("colormap=\"c.jpg\" horizontalscale=\"1\" verticalscale=\"1\""), "no heightmap"},
      {level_xml("heightmap=\"h.png\" colormap=\"c.jpg\" horizontalscale=\"-1\" verticalscale=\"1\""),
       "horizontalscale=\"-1\""},
      {level_xml("heightmap=\"h.png\" colormap=\"c.jpg\" horizontalscale=\"1\" verticalscale=\"nan\""),
       "verticalscale=\"nan\""},
      {level_xml("heightmap=\"h.png\" colormap=\"c.jpg\" horizontalscale=\"1x\" verticalscale=\"1\""),
       "horizontalscale=\"1x\""},
      {level_xml("heightmap=\"../h.png\" colormap=\"c.jpg\" horizontalscale=\"1\" verticalscale=\"1\""),
       "not a file name beside the level"},
      {level_xml("heightmap=\"h.png\" colormap=\"/etc/passwd\" horizontalscale=\"1\" verticalscale=\"1\""),
       "not a file name beside the level"},
  };
  for (const auto& c : cases) {
    const auto b = bytes_of(c.text);
    try {
      enc::parse_level(b.data(), b.size(), "bad.level");
      ADD_FAILURE() << "accepted: " << c.text;
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()).rfind("bad.level: ", 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << e.what();
    }
  }
}

TEST(TerrainMap, EveryPrefixOfALevelIsRefusedNamingTheFile) {
  const auto b = bytes_of(level_xml("heightmap=\"h.png\" colormap=\"c.jpg\" horizontalscale=\"2.5\" verticalscale=\"0.3\""));
  size_t accepted = 0;
  for (size_t n = 0; n < b.size(); ++n) {
    try {
      enc::parse_level(b.data(), n, "cut.level");
      ++accepted;  // a prefix that ends after </level> is the whole level
    } catch (const std::runtime_error& e) {
      ASSERT_EQ(std::string(e.what()).rfind("cut.level: ", 0), 0u) << n << ": " << e.what();
    }
  }
  EXPECT_LE(accepted, 2u);  // at most the cuts inside the trailing newline
}

// A binary PGM of 16-bit samples.
std::vector<uint8_t> pgm16(int w, int h, const std::vector<uint16_t>& v) {
  const std::string head = "P5\n" + std::to_string(w) + " " + std::to_string(h) + "\n65535\n";
  std::vector<uint8_t> out(head.begin(), head.end());
  for (uint16_t s : v) {
    out.push_back(static_cast<uint8_t>(s >> 8));
    out.push_back(static_cast<uint8_t>(s & 255));
  }
  return out;
}

std::vector<uint8_t> png_bytes(const vds::io::Image& img, const std::string& name) {
  const std::string path = std::string(VDS_TEST_TMP) + "/" + name;
  vds::io::save_png(path, img);
  return enc::read_file(path);
}

TEST(TerrainMap, ReadsSixteenBitAndColourHeightmaps) {
  std::vector<uint16_t> v(5 * 4);
  for (size_t i = 0; i < v.size(); ++i) v[i] = static_cast<uint16_t>(i * 3000 + 7);
  const auto h = pgm16(5, 4, v);
  vds::io::Image colour(16, 16, 3);
  for (size_t i = 0; i < colour.pixels.size(); ++i) colour.pixels[i] = static_cast<uint8_t>(i * 7);
  const auto c = png_bytes(colour, "terrain_colour.png");
  const enc::TerrainMap m = enc::read_terrain(h.data(), h.size(), "h.pgm", c.data(), c.size(), "c.png", 2.0, 0.01);
  EXPECT_EQ(m.width, 5);
  EXPECT_EQ(m.height, 4);
  EXPECT_EQ(m.heights, v);  // every 16-bit level kept
  EXPECT_DOUBLE_EQ(m.metres_per_unit, 0.01);
  EXPECT_NEAR(m.height_at(1, 0), v[1] * 0.01, 1e-9);
  EXPECT_NEAR(m.height_at(0.5, 0), (v[0] + v[1]) * 0.005, 1e-9);

  // A colour heightmap: R + G + B, a third of a level each.
  vds::io::Image rgb(4, 4, 3);
  for (int i = 0; i < 16; ++i) {
    rgb.pixels[3 * i] = static_cast<uint8_t>(10 * i);
    rgb.pixels[3 * i + 1] = static_cast<uint8_t>(10 * i + 1);
    rgb.pixels[3 * i + 2] = static_cast<uint8_t>(10 * i);
  }
  const auto hr = png_bytes(rgb, "terrain_rgb_heights.png");
  const enc::TerrainMap r = enc::read_terrain(hr.data(), hr.size(), "h.png", c.data(), c.size(), "c.png", 1.0, 0.3);
  EXPECT_EQ(r.heights[5], 30 * 5 + 1);
  EXPECT_DOUBLE_EQ(r.metres_per_unit, 0.1);
}

TEST(TerrainMap, EveryPrefixOfAHeightmapOrColourMapIsRefusedNamingTheFile) {
  std::vector<uint16_t> v(6 * 5);
  for (size_t i = 0; i < v.size(); ++i) v[i] = static_cast<uint16_t>(i * 999);
  const auto h = pgm16(6, 5, v);
  vds::io::Image colour(16, 16, 3);
  for (size_t i = 0; i < colour.pixels.size(); ++i) colour.pixels[i] = static_cast<uint8_t>(i * 5);
  const auto c = png_bytes(colour, "terrain_colour3.png");
  for (size_t n = 0; n < h.size(); ++n)
    EXPECT_THROW(
        try { enc::read_terrain(h.data(), n, "h.pgm", c.data(), c.size(), "c.png", 1.0, 1.0); } catch (
            const std::runtime_error& e) {
          EXPECT_EQ(std::string(e.what()).rfind("h.pgm: ", 0), 0u) << e.what();
          throw;
        },
        std::runtime_error)
        << n;
  for (size_t n = 0; n < c.size(); ++n)
    EXPECT_THROW(
        try { enc::read_terrain(h.data(), h.size(), "h.pgm", c.data(), n, "c.png", 1.0, 1.0); } catch (
            const std::runtime_error& e) {
          EXPECT_EQ(std::string(e.what()).rfind("c.png: ", 0), 0u) << e.what();
          throw;
        },
        std::runtime_error)
        << n;
}

TEST(TerrainMap, RefusesMapsItCannotUse) {
  vds::io::Image colour(16, 16, 3);
  const auto c = png_bytes(colour, "terrain_colour2.png");
  const auto one = pgm16(1, 1, {5});
  const auto ok = pgm16(2, 2, {1, 2, 3, 4});
  const auto tiny = png_bytes(vds::io::Image(4, 4, 3), "terrain_tiny.png");
  auto refuses = [&](const std::vector<uint8_t>& h, const std::vector<uint8_t>& col, double hs, const char* file,
                     const char* says) {
    try {
      enc::read_terrain(h.data(), h.size(), "h.pgm", col.data(), col.size(), "c.png", hs, 1.0);
      ADD_FAILURE() << "accepted (" << says << ")";
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()).rfind(file, 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
    }
  };
  refuses(one, c, 1.0, "h.pgm", "1x1 heightmap");
  refuses(ok, tiny, 1.0, "c.png", "4x4 colour map");
  refuses(ok, c, 0.0, "h.pgm", "scales must be positive");
  refuses({}, c, 1.0, "h.pgm", "empty");
  const std::vector<uint8_t> short_pgm = {'P', '5', '\n', '9', ' ', '9', '\n', '2', '5', '5', '\n', 1, 2};
  refuses(short_pgm, c, 1.0, "h.pgm", "follow its header");
  EXPECT_THROW(enc::load_terrain(std::string(VDS_TEST_TMP) + "/no such map.level"), std::runtime_error);
  EXPECT_THROW(enc::load_terrain("../escape"), std::runtime_error);
}

// The installed Trigger Rally maps (scripts/fetch-data.sh installs them).
TEST(TerrainMap, ReadsTriggerRallyMapsFromTheirArchive) {
  const enc::TerrainMap m = enc::load_terrain("altitude");
  EXPECT_EQ(m.name, "altitude");
  EXPECT_EQ(m.width, 1024);
  EXPECT_EQ(m.height, 1024);
  EXPECT_EQ(m.colour.width, 1024);
  EXPECT_GT(m.horizontal_scale, 0);
  const enc::TerrainMap rgb = enc::load_terrain(enc::trigger_rally_zip() + ":bender");  // an RGB heightmap
  uint16_t top = 0;
  for (uint16_t h : rgb.heights) top = std::max(top, h);
  EXPECT_GT(top, 255);  // R + G + B
  EXPECT_LE(top, 765);
  EXPECT_THROW(enc::load_terrain("no-such-map"), std::runtime_error);
}

// --- Elevation -------------------------------------------------------------------------

TEST(TerrainElevation, RoundTripsExactlyInTwoPassesAndRefusesEveryPrefix) {
  const int w = 33, h = 25;  // h - 1 a multiple of the coarse step, w - 1 too: both edge cases
  for (const int width : {w, w + 3}) {
    std::vector<uint16_t> v(static_cast<size_t>(width) * h);
    vds::test::Xorshift32 rng{5};
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < width; ++x) {
        const double s = 20000 + 15000 * std::sin(x * 0.2) * std::cos(y * 0.15);
        v[static_cast<size_t>(y) * width + x] = static_cast<uint16_t>(s + (rng.next() % 9));
      }
    v[0] = 0;
    v[5] = 65535;  // the extremes, next to each other's neighbours
    v[6] = 0;
    const auto coarse = enc::encode_elevation(v.data(), width, h, terrain::ElevationPass::coarse);
    const auto fine = enc::encode_elevation(v.data(), width, h, terrain::ElevationPass::fine);
    std::vector<uint16_t> out(v.size(), 1);
    ASSERT_EQ(terrain::decode_elevation(coarse.data(), coarse.size(), width, h, terrain::ElevationPass::coarse, out.data()),
              Status::ok);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < width; ++x)
        if (terrain::elevation_coarse(x, y, width, h)) ASSERT_EQ(out[y * width + x], v[y * width + x]) << x << "," << y;
    // Between the coarse points the client draws the interpolation.
    std::vector<uint16_t> rough = out;
    terrain::fill_from_coarse(width, h, rough.data());
    const int x0 = 8, x1 = 16, y0 = 8;
    EXPECT_NEAR(rough[y0 * width + 12], (v[y0 * width + x0] + v[y0 * width + x1]) / 2.0, 1.0);
    EXPECT_EQ(rough[(h - 1) * width + 3],
              (v[(h - 1) * width] * 5 + v[(h - 1) * width + 8] * 3 + 4) / 8);  // the last row, (h - 1) % 8 == 0
    ASSERT_EQ(terrain::decode_elevation(fine.data(), fine.size(), width, h, terrain::ElevationPass::fine, out.data()),
              Status::ok);
    EXPECT_EQ(out, v);
    EXPECT_LT(coarse.size() + fine.size(), v.size() * 2);  // under 16 bits a point, on steep ground
    for (size_t n = 0; n < fine.size(); ++n)
      EXPECT_NE(terrain::decode_elevation(fine.data(), n, width, h, terrain::ElevationPass::fine, out.data()), Status::ok) << n;
    for (size_t n = 0; n < coarse.size(); ++n)
      EXPECT_NE(terrain::decode_elevation(coarse.data(), n, width, h, terrain::ElevationPass::coarse, out.data()),
                Status::ok) << n;
    std::vector<uint8_t> longer = fine;
    longer.push_back(0x55);
    EXPECT_EQ(terrain::decode_elevation(longer.data(), longer.size(), width, h, terrain::ElevationPass::fine, out.data()),
              Status::malformed);
  }
}

// --- Masks ----------------------------------------------------------------------------------

// The paper's rule (section 4.5) coefficient by coefficient, in double, as
// written, with the DC kept.
bool reference_keeps(int u, int v, double kd, double cos_a, double beta_s, bool keep_dc = true) {
  if (u == 0 && v == 0 && keep_dc) return kd > 0;
  if (!(kd > 0)) return false;
  kd = std::min(kd, 1.0);
  const double U = (u + 0.5) / 8, V = (v + 0.5) / 8, T = kd * cos_a;
  if (U > kd || V > kd) return false;
  const double s = std::sin(beta_s);
  if (beta_s == 0 && V > T) return false;
  if (beta_s == 0) return true;
  if (beta_s == kPi / 2 && U > T) return false;
  if (beta_s == kPi / 2) return true;
  return !(U > T - (V - T) / std::tan(beta_s)) || s == 0;
}

// How far (u, v) is from changing the reference's answer (ties are where
// two correct implementations may round differently).
double boundary_distance(int u, int v, double kd, double cos_a, double beta_s) {
  kd = std::min(kd, 1.0);
  const double U = (u + 0.5) / 8, V = (v + 0.5) / 8, T = kd * cos_a;
  double d = std::min(std::fabs(U - kd), std::fabs(V - kd));
  if (beta_s > 0 && beta_s < kPi / 2) d = std::min(d, std::fabs(U - (T - (V - T) / std::tan(beta_s))));
  else d = std::min(d, beta_s == 0 ? std::fabs(V - T) : std::fabs(U - T));
  return d;
}

// The level of detail's measure in doubles: the largest distance, rounded
// up, between a grid point and the coarse surface over it. A coarse quad
// from (ia, ja) to (ib, jc) is split along its b-c diagonal; points on a
// coarse line are measured in the quad right of and below it, and the
// patch's last column (row) only where a quad narrower (lower) than s ends
// there.
int reference_step_error(const std::vector<uint16_t>& h, int w, int i0, int j0, int ni, int nj, int s) {
  double worst = 0;
  for (int j = j0; j <= j0 + nj; ++j)
    for (int i = i0; i <= i0 + ni; ++i) {
      const int ia = i0 + std::min((i - i0) / s * s, ni), ja = j0 + std::min((j - j0) / s * s, nj);
      const int ib = std::min(ia + s, i0 + ni), jc = std::min(ja + s, j0 + nj);
      if (ia == ib || ja == jc) continue;  // the last column or row after a whole quad
      const double W = ib - ia, H = jc - ja, U = (i - ia) / W, V = (j - ja) / H;
      auto at = [&](int x, int y) { return static_cast<double>(h[static_cast<size_t>(y) * w + x]); };
      const double surface = U + V <= 1 ? at(ia, ja) + U * (at(ib, ja) - at(ia, ja)) + V * (at(ia, jc) - at(ia, ja))
                                        : at(ib, jc) + (1 - U) * (at(ia, jc) - at(ib, jc)) + (1 - V) * (at(ib, ja) - at(ib, jc));
      worst = std::max(worst, std::fabs(at(i, j) - surface));
    }
  return std::min(65535, static_cast<int>(std::ceil(worst - 1e-7)));
}

TEST(TerrainElevation, StepErrorIsTheLargestDistanceToTheCoarseSurface) {
  vds::test::Xorshift32 rng{5};
  constexpr int kW = 300;
  std::vector<uint16_t> rough(kW * kW), smooth(kW * kW), flat(kW * kW, 700);
  for (int j = 0; j < kW; ++j)
    for (int i = 0; i < kW; ++i) {
      rough[static_cast<size_t>(j) * kW + i] = static_cast<uint16_t>(rng.next());
      smooth[static_cast<size_t>(j) * kW + i] =
          static_cast<uint16_t>(30000 + 20000 * std::sin(i * 0.05) * std::cos(j * 0.07) + rng.next() % 64);
    }
  // A plane: no step has an error.
  for (int j = 0; j < kW; ++j)
    for (int i = 0; i < kW; ++i) flat[static_cast<size_t>(j) * kW + i] = static_cast<uint16_t>(100 + 3 * i + 7 * j);
  int nonzero = 0;
  for (int n = 0; n < 600; ++n) {
    const std::vector<uint16_t>& h = n % 3 == 0 ? rough : (n % 3 == 1 ? smooth : flat);
    const int s = 1 << (1 + rng.next() % 7);                       // 2 .. 128
    const int ni = 1 + static_cast<int>(rng.next() % 160), nj = 1 + static_cast<int>(rng.next() % 160);
    const int i0 = static_cast<int>(rng.next() % (kW - ni)), j0 = static_cast<int>(rng.next() % (kW - nj));
    const int got = terrain::step_error(h.data(), kW, i0, j0, ni, nj, s);
    ASSERT_EQ(got, reference_step_error(h, kW, i0, j0, ni, nj, s))
        << "patch " << ni << "x" << nj << " at " << i0 << "," << j0 << " step " << s << " map " << n % 3;
    if (&h == &flat) EXPECT_EQ(got, 0);
    nonzero += got > 0;
  }
  EXPECT_GT(nonzero, 300);
  // The step of a single cell draws every point: no error.
  EXPECT_EQ(terrain::step_error(rough.data(), kW, 10, 10, 16, 16, 1), 0);
}

TEST(TerrainMask, MatchesTheDoubleReferenceOfThePapersRule) {
  vds::test::Xorshift32 rng{11};
  int compared = 0;
  for (int i = 0; i < 20000; ++i) {
    const double kd = (rng.next() % 1500) / 1000.0;
    const double cos_a = (rng.next() % 1001) / 1000.0;
    const int b = static_cast<int>(rng.next() % 92);  // 0 and 90 degrees exactly, and between
    const double beta_s = b == 91 ? kPi / 2 : b * kPi / 180;
    const Mask m = enc::shrink_mask(kd, cos_a, beta_s);
    ASSERT_TRUE(terrain::mask_valid(m)) << std::hex << m;
    const Mask paper = enc::shrink_mask(kd, cos_a, beta_s, false);  // the DC by the rule too
    ASSERT_EQ(paper & ~Mask{0xF}, m & ~Mask{0xF});
    for (int v = 0; v < 8; ++v)
      for (int u = 0; u < 8; ++u) {
        if (!(u == 0 && v == 0) && boundary_distance(u, v, kd, cos_a, beta_s) < 1e-9) continue;
        ASSERT_EQ(terrain::mask_holds(m, u, v), reference_keeps(u, v, kd, cos_a, beta_s))
            << "u " << u << " v " << v << " k/D " << kd << " cos " << cos_a << " beta_s " << beta_s;
        if (v == 0 && boundary_distance(u, v, kd, cos_a, beta_s) >= 1e-9)
          ASSERT_EQ(terrain::mask_holds(paper, u, v), reference_keeps(u, v, kd, cos_a, beta_s, false)) << u << " " << kd;
        ++compared;
      }
  }
  EXPECT_GT(compared, 1000000);
}

TEST(TerrainMask, ShapesFollowDepthTiltAndRotation) {
  EXPECT_EQ(enc::shrink_mask(1.0, 1.0, kPi / 4), terrain::kFullMask);      // a texel a pixel, facing
  EXPECT_EQ(enc::shrink_mask(3.0, 1.0, 0.3), terrain::kFullMask);          // magnified
  EXPECT_EQ(enc::shrink_mask(0.0, 1.0, 0.3), 0u);                          // nothing
  EXPECT_EQ(enc::shrink_mask(0.01, 1.0, 0.3), 0x00000001u);                // far: the DC alone
  EXPECT_EQ(enc::shrink_mask(0.01, 1.0, 0.3, false), 0u);                  // or, as the paper has it, nothing
  EXPECT_EQ(enc::shrink_mask(0.5, 1.0, kPi / 2), 0x00004444u);             // depth: a 4x4 corner
  EXPECT_EQ(enc::shrink_mask(1.0, 0.5, kPi / 2), 0x44444444u);             // tilted along u: half the u's
  EXPECT_EQ(enc::shrink_mask(1.0, 0.5, 0.0), 0x00008888u);                 // along v: half the v's
  // Nearer never needs less.
  for (double kd = 0.05; kd < 1.2; kd += 0.05)
    EXPECT_TRUE(terrain::mask_covers(enc::shrink_mask(kd + 0.05, 0.7, 0.6), enc::shrink_mask(kd, 0.7, 0.6)));
  // Union and intersection row by row.
  EXPECT_EQ(terrain::mask_union(0x00004444u, 0x00000088u), 0x00004488u);
  EXPECT_EQ(terrain::mask_intersection(0x00004444u, 0x00000088u), 0x00000044u);
  EXPECT_EQ(terrain::mask_count(terrain::kFullMask), 64);
  EXPECT_FALSE(terrain::mask_valid(0x00000010u));  // a row longer than the one above
  EXPECT_FALSE(terrain::mask_valid(0x00000009u));  // an extent past 8
}

// --- Updates -----------------------------------------------------------------------------

// A small terrain: 24 x 20 cells of a coloured, hilly map.
// A flight over it: out, a turn, a climb, and back where it began.
enc::SceneCamera flight_camera(const enc::TerrainCoding& t, int f, int frames) {
  const double w = t.grid.cells_x * t.cell_m, d = t.grid.cells_y * t.cell_m;
  const double s = static_cast<double>(f % frames) / frames;
  const double a = 2 * kPi * s;
  enc::CameraPose p;
  p.x = w * (0.5 + 0.35 * std::cos(a));
  p.y = d * (0.5 + 0.35 * std::sin(a));
  p.z = 60 + 80 * std::sin(a) * std::sin(a);
  p.yaw_deg = std::fmod(a * 180 / kPi + 90 + 360, 360);
  p.pitch_deg = -25;
  return enc::scene_camera(p, 70, 240, 180);
}

// The client side: the masks and coefficients the updates leave.
struct Client {
  std::vector<Mask> masks;
  std::vector<std::array<int16_t, 64>> levels;
  std::map<std::pair<uint32_t, int>, int> received;  // (block, coefficient) -> times
  const enc::TerrainCoding* t = nullptr;
  explicit Client(const enc::TerrainCoding& tc) : masks(tc.grid.blocks(), 0), levels(tc.grid.blocks()), t(&tc) {}
  static Mask held(void* ctx, uint32_t id) { return static_cast<Client*>(ctx)->masks[id]; }
  // What a level-0 block shows before it holds anything: its sample of its
  // level-1 block's DC plane, from what this client holds of that block.
  static int shown_dc(void* ctx, uint32_t id) {
    const Client& c = *static_cast<Client*>(ctx);
    int sample;
    const uint32_t coarse = c.t->grid.coarse(id, &sample);
    if (c.masks[coarse] == 0) return 0;
    int16_t plane[64];
    terrain::coarse_plane(c.levels[coarse].data(), c.masks[coarse], c.t->quantiser, plane);
    return plane[sample];
  }
  Status apply(const std::vector<uint8_t>& u, const terrain::BlockGrid& g) {
    terrain::TextureUpdateReader r;
    Status s = r.init(u.data(), u.size(), g, &Client::held, &Client::shown_dc, this);
    if (s != Status::ok) return s;
    terrain::BlockUpdate b;
    while ((s = r.next(&b)) == Status::ok) {
      auto& lv = levels[b.id];
      for (int n = 0; n < 64; ++n) {
        const bool had = terrain::mask_holds(b.held, n & 7, n >> 3), has = terrain::mask_holds(b.mask, n & 7, n >> 3);
        if (!has) lv[n] = 0;
        if (has && !had) {
          lv[n] = b.levels[n];
          ++received[{b.id, n}];
        }
      }
      masks[b.id] = b.mask;
    }
    return s == Status::more_input && r.done() ? Status::ok : s;
  }
};

TEST(TerrainUpdates, TheClientHoldsWhatTheServerMirrorsAndNothingIsSentTwiceUnlessDropped) {
  const enc::TerrainCoding t = enc::code_terrain(vds::test::terrain_test_map(), 6);
  const uint32_t blocks = t.grid.blocks();
  const uint32_t capacity = 6000;  // well under what the flight sees: the store evicts
  enc::TerrainServer server(t, capacity);
  Client client(t);
  std::map<std::pair<uint32_t, int>, int> dropped;
  const int frames = 120;
  const size_t budget = 600;
  uint32_t grows = 0, shrinks = 0;
  for (int f = 0; f < 2 * frames; ++f) {
    const std::vector<Mask> before = server.held();
    enc::UpdateStats st;
    const std::vector<uint8_t> u = server.update(flight_camera(t, f, frames), static_cast<uint32_t>(f), budget, {}, &st);
    ASSERT_LE(u.size(), budget);
    ASSERT_LE(server.used(), capacity);
    grows += st.grows;
    shrinks += st.shrinks;
    if (u.empty()) continue;
    ASSERT_EQ(client.apply(u, t.grid), Status::ok) << "frame " << f;
    ASSERT_EQ(client.masks, server.held()) << "frame " << f;
    for (uint32_t b = 0; b < blocks; ++b)
      for (int n = 0; n < 64; ++n)
        if (terrain::mask_holds(before[b], n & 7, n >> 3) && !terrain::mask_holds(server.held()[b], n & 7, n >> 3))
          ++dropped[{b, n}];
  }
  EXPECT_GT(grows, 500u);
  EXPECT_GT(shrinks, 50u);  // the store was full
  // What the client holds is the encoder's quantised coefficients.
  for (uint32_t b = 0; b < blocks; ++b)
    for (int n = 0; n < 64; ++n)
      ASSERT_EQ(client.levels[b][n], terrain::mask_holds(client.masks[b], n & 7, n >> 3) ? t.levels[b][n] : 0);
  // Sent n times means dropped n - 1 or n times in between.
  size_t resent = 0;
  for (const auto& [key, times] : client.received) {
    const int d = dropped.count(key) ? dropped.at(key) : 0;
    const bool held_now = terrain::mask_holds(client.masks[key.first], key.second & 7, key.second >> 3);
    ASSERT_EQ(times - (held_now ? 1 : 0), d) << "block " << key.first << " coefficient " << key.second;
    if (times > 1) ++resent;
  }
  EXPECT_GT(resent, 0u);  // the second lap resends what eviction dropped
}

TEST(TerrainUpdates, AStillViewerGetsEverythingItNeedsAndThenNothing) {
  const enc::TerrainCoding t = enc::code_terrain(vds::test::terrain_test_map(), 6);
  enc::TerrainServer server(t, 1u << 20);
  Client client(t);
  const enc::SceneCamera cam = flight_camera(t, 10, 100);
  const std::vector<Mask> need = enc::pose_masks(t, cam, {});
  uint32_t visible = 0;
  for (Mask m : need) visible += m != 0;
  EXPECT_GT(visible, 100u);
  int updates = 0;
  for (int f = 0; f < 200; ++f) {
    enc::UpdateStats st;
    const auto u = server.update(cam, static_cast<uint32_t>(f), 500, {}, &st);
    if (u.empty()) break;
    ++updates;
    ASSERT_EQ(client.apply(u, t.grid), Status::ok);
  }
  EXPECT_GT(updates, 3);  // the budget spreads the first view over several updates
  EXPECT_LT(updates, 200);
  for (uint32_t b = 0; b < t.grid.blocks(); ++b) ASSERT_TRUE(terrain::mask_covers(client.masks[b], need[b])) << b;
  EXPECT_TRUE(server.update(cam, 999, 500, {}).empty());
}

TEST(TerrainUpdates, EveryPrefixAndEveryBitFlipIsRefusedOrStaysInRange) {
  const enc::TerrainCoding t = enc::code_terrain(vds::test::terrain_test_map(), 10);
  enc::TerrainServer server(t, 1u << 20);
  const auto u = server.update(flight_camera(t, 3, 100), 3, 1500, {});
  ASSERT_GT(u.size(), 100u);
  for (size_t n = 0; n < u.size(); ++n) {
    Client c(t);
    EXPECT_NE(c.apply(std::vector<uint8_t>(u.begin(), u.begin() + static_cast<long>(n)), t.grid), Status::ok) << n;
  }
  vds::test::Xorshift32 rng{3};
  for (int i = 0; i < 300; ++i) {
    std::vector<uint8_t> bad = u;
    bad[rng.next() % bad.size()] ^= static_cast<uint8_t>(1u << (rng.next() % 8));
    Client c(t);
    c.apply(bad, t.grid);  // whatever it says, the masks it leaves are valid
    for (Mask m : c.masks) ASSERT_TRUE(terrain::mask_valid(m));
  }
}

TEST(TerrainUpdates, ReconstructionApproachesTheSourceAsMasksGrow) {
  const enc::TerrainCoding t = enc::code_terrain(vds::test::terrain_test_map(), 2);
  const uint32_t fine = t.grid.first(0, 0), n = t.grid.blocks();
  std::vector<Mask> none(n, 0), coarse_dc(n, 0), coarse(n, 0), dc(n, 0x1), full(n, terrain::kFullMask);
  for (uint32_t b = 0; b < fine; ++b) coarse_dc[b] = 0x1, coarse[b] = terrain::kFullMask;
  for (uint32_t b = 0; b < fine; ++b) dc[b] = 0;
  std::vector<double> p;
  for (const auto* m : {&none, &coarse_dc, &coarse, &dc, &full})
    p.push_back(enc::planes_psnr(enc::reconstruct_texture(t, *m), t.texture));
  // Nothing, the level-1 DCs, the whole level 1 (every block's mean,
  // bilinear between blocks), every level-0 DC (the same means exactly, flat
  // in each block), every coefficient.
  EXPECT_GT(p[1], p[0]);
  EXPECT_GT(p[2], p[1]);
  EXPECT_GT(p[3], p[1]);
  EXPECT_NEAR(p[2], p[3], 1.0);
  EXPECT_GT(p[4], 40.0);
  EXPECT_LT(p[3], p[4] - 8);
  // A level-0 block holding nothing shows its sample of the level-1 plane.
  const uint32_t b = t.grid.cell(5, 3);
  const int dcs = enc::shown_dc(t, coarse, b);
  EXPECT_NEAR(dcs, t.levels[b][0], 4);  // the level-1 plane's AC is quantised
}

TEST(TerrainUpdates, BlockIdsCoverBothLevelsOnce) {
  terrain::BlockGrid g;
  g.cells_x = 37;
  g.cells_y = 20;
  EXPECT_EQ(g.plane_w(0, 1), 19);
  EXPECT_EQ(g.plane_w(1, 0), 5);
  EXPECT_EQ(g.plane_w(1, 1), 3);
  EXPECT_EQ(g.first(1, 0), 0u);
  std::vector<int> seen(g.blocks(), 0);
  for (int l = 1; l >= 0; --l)
    for (int c = 0; c < 3; ++c)
      for (int y = 0; y < g.plane_h(l, c); ++y)
        for (int x = 0; x < g.plane_w(l, c); ++x) {
          const uint32_t id = g.id(l, c, x, y);
          ASSERT_LT(id, g.blocks());
          ++seen[id];
          const terrain::BlockPlace p = g.place(id);
          ASSERT_TRUE(p.level == l && p.comp == c && p.bx == x && p.by == y) << id;
        }
  for (int k : seen) ASSERT_EQ(k, 1);
  EXPECT_EQ(g.cell(4, 2), g.first(0, 0) + 2 * 37 + 4);
}

TEST(TerrainUpdates, SeveralCamerasGetWhatEachNeeds) {
  const enc::TerrainCoding t = enc::code_terrain(vds::test::terrain_test_map(), 6);
  enc::TerrainServer server(t, 1u << 20);
  const std::vector<enc::SceneCamera> cams = {flight_camera(t, 10, 100), flight_camera(t, 40, 100)};
  for (int f = 0; f < 400 && !server.update(cams, static_cast<uint32_t>(f), 800, {}).empty(); ++f) {
  }
  for (const enc::SceneCamera& c : cams) {
    const std::vector<Mask> need = enc::pose_masks(t, c, {});
    for (uint32_t b = 0; b < t.grid.blocks(); ++b) ASSERT_TRUE(terrain::mask_covers(server.held()[b], need[b])) << b;
  }
}

// The replay keeps the link's rate and the client's store for vds and for
// the tile pyramid alike.
TEST(TerrainFlight, BothClientsKeepTheLinkAndTheirStore) {
  const enc::TerrainCoding t = enc::code_terrain(vds::test::terrain_test_map(), 6);
  enc::CameraPath path;
  path.hfov_deg = 70;
  path.fps = 20;
  for (int f = 0; f < 40; ++f) {
    enc::CameraPose p;
    p.x = 40 + 3 * f;
    p.y = 60;
    p.z = 200;
    p.yaw_deg = 20;
    p.pitch_deg = -30;
    path.frames.push_back(p);
  }
  enc::FlightOptions o;
  o.width = 80;
  o.height = 60;
  o.supersample = 1;
  o.capacity = 3000;
  o.link.rate_bytes_per_s = 4000;
  const enc::FlightResult v = enc::fly(t, path, o);
  enc::TileOptions to = enc::parse_tile_variant("jpeg64");
  to.cache_bytes = 3 * 64 * 64 * 3 / 2;
  const enc::FlightResult tl = enc::fly_tiles(t, path, o, to);
  for (const enc::FlightResult* r : {&v, &tl}) {
    ASSERT_EQ(r->frames.size(), path.frames.size());
    double sent = static_cast<double>(r->coarse_elevation_bytes);
    for (size_t f = 0; f < r->frames.size(); ++f) {
      sent += static_cast<double>(r->frames[f].down_bytes + r->frames[f].elevation_bytes);
      ASSERT_LE(sent, 4000.0 * (f + 1) / 20 + 1) << f;  // never ahead of the line
      ASSERT_GT(r->frames[f].psnr, 5.0);
    }
    EXPECT_GT(sent, 1000.0);
  }
  for (const enc::FlightFrame& f : v.frames) ASSERT_LE(f.held, o.capacity);
  for (const enc::FlightFrame& f : tl.frames) ASSERT_LE(f.held, to.cache_bytes);
  EXPECT_THROW(enc::parse_tile_variant("jpeg128"), std::invalid_argument);
  EXPECT_THROW(enc::parse_tile_variant("png64"), std::invalid_argument);
}

}  // namespace
