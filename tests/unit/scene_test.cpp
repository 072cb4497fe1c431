// Scene import (vds/enc/scene.h): a Quake III BSP built in memory read back
// face by face; patches within the tessellation tolerance; every lump,
// count and index of a damaged file refused with its name; the installed
// OpenArena maps read whole, textures found in the .pk3 archives.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <zip.h>

#include <filesystem>
#include <fstream>

#include "bsp_builder.h"
#include "vds/enc/scene.h"

namespace {

using vds::enc::Scene;

std::string refusal(const std::vector<uint8_t>& f) {
  try {
    vds::enc::read_bsp(f.data(), f.size(), "m.bsp");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

void set_lump(std::vector<uint8_t>& f, int lump, uint32_t offset, uint32_t length) {
  std::memcpy(&f[8 + 8 * lump], &offset, 4);
  std::memcpy(&f[12 + 8 * lump], &length, 4);
}

TEST(SceneBsp, ABuiltMapReadsFaceByFace) {
  const Scene s = vds::enc::read_bsp(vds::test::BspBuilder().build().data(), vds::test::BspBuilder().build().size(), "m.bsp");
  EXPECT_EQ(s.polygons, 2u);
  EXPECT_EQ(s.meshes, 1u);
  EXPECT_EQ(s.patches, 1u);
  EXPECT_EQ(s.billboards, 1u);
  ASSERT_EQ(s.surfaces.size(), 4u);  // the billboard is dropped
  EXPECT_EQ(s.surfaces[0].kind, vds::enc::SurfaceKind::opaque);
  EXPECT_EQ(s.surfaces[1].kind, vds::enc::SurfaceKind::sky);
  EXPECT_EQ(s.surfaces[1].lightmap, -1);  // -3: lit by vertex
  EXPECT_EQ(s.surfaces[0].index_count, 6u);
  EXPECT_EQ(s.lightmaps.size(), 1u);
  ASSERT_EQ(s.spawns.size(), 2u);
  EXPECT_EQ(s.spawns[0].classname, "info_player_deathmatch");
  EXPECT_FLOAT_EQ(s.spawns[0].origin[1], 32.f);
  EXPECT_FLOAT_EQ(s.spawns[0].yaw_deg, 90.f);
  for (uint32_t i : s.indices) ASSERT_LT(i, s.vertices.size());
}

TEST(SceneBsp, PatchesStayWithinTheTolerance) {
  const std::vector<uint8_t> f = vds::test::BspBuilder().build();
  for (double tol : {4.0, 1.0, 0.25}) {
    vds::enc::SceneOptions o;
    o.patch_tolerance = tol;
    const Scene s = vds::enc::read_bsp(f.data(), f.size(), "m.bsp", o);
    const vds::enc::SceneSurface& patch = s.surfaces[3];
    ASSERT_EQ(patch.face_type, 2);
    // The control net (heights 0 but 32 at its centre, x and y at 0, 32,
    // 64) makes the surface x = 64u, y = 64v, z = 32 * 2u(1-u) * 2v(1-v).
    // The centre of each flat triangle must lie within the tolerance of it.
    double worst = 0;
    for (uint32_t k = patch.first_index; k < patch.first_index + patch.index_count; k += 3) {
      double c[3] = {};
      for (int j = 0; j < 3; ++j)
        for (int a = 0; a < 3; ++a) c[a] += s.vertices[s.indices[k + j]].pos[a] / 3.0;
      const double u = c[0] / 64, v = c[1] / 64;
      const double z = 32 * (2 * u * (1 - u)) * (2 * v * (1 - v));
      worst = std::max(worst, std::fabs(z - c[2]));
    }
    EXPECT_LE(worst, tol) << "tolerance " << tol;
    if (tol == 0.25) EXPECT_GT(patch.index_count / 3, 50u);
  }
}

TEST(SceneBsp, DamagedFilesAreRefusedWithTheirLumpAndElement) {
  const std::vector<uint8_t> good = vds::test::BspBuilder().build();
  EXPECT_EQ(refusal(good), "");
  EXPECT_EQ(refusal(std::vector<uint8_t>(good.begin(), good.begin() + 40)), "m.bsp: not a Quake III map (it must start with 'IBSP')");
  std::vector<uint8_t> v47 = good;
  v47[4] = 47;
  EXPECT_NE(refusal(v47).find("BSP version 47"), std::string::npos);
  // A lump past the end of the file.
  std::vector<uint8_t> cut(good.begin(), good.end() - 1000);
  EXPECT_NE(refusal(cut).find("lump"), std::string::npos);
  std::vector<uint8_t> far = good;
  set_lump(far, 13, 0x7FFFFFF0u, 104);
  EXPECT_NE(refusal(far).find("the faces lump (104 bytes at byte 2147483632) is not inside"), std::string::npos);
  // A lump that is not a whole number of elements.
  uint32_t off, len;
  std::memcpy(&off, &good[8 + 8 * 10], 4);
  std::memcpy(&len, &good[12 + 8 * 10], 4);
  std::vector<uint8_t> ragged = good;
  set_lump(ragged, 10, off, len - 3);
  EXPECT_NE(refusal(ragged).find("the vertices lump is"), std::string::npos);
  // Faces naming what is not there.
  {
    vds::test::BspBuilder b;
    b.faces[0].texture = 9;
    EXPECT_NE(refusal(b.build()).find("face 0 of 5 names texture 9 of 2"), std::string::npos);
  }
  {
    vds::test::BspBuilder b;
    b.faces[1].n_vertices = 1000;
    EXPECT_NE(refusal(b.build()).find("face 1 of 5 names vertices"), std::string::npos);
  }
  {
    vds::test::BspBuilder b;
    b.meshverts[3] = 7;
    EXPECT_NE(refusal(b.build()).find("mesh vertex 3 is 7, not one of its 4 vertices"), std::string::npos);
  }
  {
    vds::test::BspBuilder b;
    b.faces[3].size[0] = 4;
    EXPECT_NE(refusal(b.build()).find("a patch of 4x3 control points"), std::string::npos);
  }
  {
    vds::test::BspBuilder b;
    b.faces[0].lightmap = 5;
    EXPECT_NE(refusal(b.build()).find("names lightmap 5 of 1"), std::string::npos);
  }
  {
    vds::test::BspBuilder b;
    b.vertices[0].pos[0] = INFINITY;
    EXPECT_NE(refusal(b.build()).find("a position that is not finite"), std::string::npos);
  }
  {
    vds::test::BspBuilder b;
    b.entities = "{ \"classname\" \"info_player_start\" \"origin\" \"1 2\" }";
    EXPECT_NE(refusal(b.build()).find("without a readable origin"), std::string::npos);
    b.entities = "{ \"classname\" \"worldspawn";
    EXPECT_NE(refusal(b.build()).find("closing quote"), std::string::npos);
  }
}

TEST(SceneBsp, EveryPrefixIsRefused) {
  const std::vector<uint8_t> f = vds::test::BspBuilder().build();
  for (size_t n = 0; n < f.size(); n += (n < 256 ? 1 : 97))
    EXPECT_NE(refusal(std::vector<uint8_t>(f.begin(), f.begin() + static_cast<std::ptrdiff_t>(n))), "") << "prefix " << n;
  EXPECT_NE(refusal(std::vector<uint8_t>(f.begin(), f.end() - 1)), "");
}

TEST(SceneBsp, OutputIsBoundedByTheInput) {
  // 400 faces sharing one steep patch: each would become 17 x 17 vertices,
  // more than the file's bytes allow (a vertex per 4 bytes).
  vds::test::BspBuilder b;
  b.vertices[b.faces[3].vertex + 4].pos[2] = 100000;
  for (int i = 0; i < 400; ++i) b.faces.push_back(b.faces[3]);
  EXPECT_NE(refusal(b.build()).find("the map's patches would make more than 65536 vertices"), std::string::npos);
}

TEST(SceneArchives, BrokenArchivesAndEntriesAreNamed) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "vds_scene_pk3";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  // A zip with one entry, written by libzip.
  const std::string body(5000, 'x');
  {
    int err = 0;
    zip_t* z = zip_open((dir / "pak0.pk3").c_str(), ZIP_CREATE | ZIP_TRUNCATE, &err);
    ASSERT_NE(z, nullptr);
    zip_source_t* src = zip_source_buffer(z, body.data(), body.size(), 0);
    ASSERT_GE(zip_file_add(z, "maps/x.bsp", src, 0), 0);
    ASSERT_EQ(zip_close(z), 0);
  }
  {
    vds::enc::Pk3Set set(dir.string());
    std::vector<uint8_t> got;
    ASSERT_TRUE(set.read("MAPS/X.BSP", &got));  // the game's names ignore case
    EXPECT_EQ(std::string(got.begin(), got.end()), body);
    EXPECT_FALSE(set.read("maps/y.bsp", &got));
    EXPECT_THROW(set.read("maps/x.bsp", &got, nullptr, 100), std::runtime_error);  // larger than allowed
  }
  // The entry's compressed bytes damaged: its CRC no longer matches.
  {
    std::fstream f(dir / "pak0.pk3", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(50);
    f.put('\x55');
  }
  {
    vds::enc::Pk3Set set(dir.string());
    std::vector<uint8_t> got;
    try {
      set.read("maps/x.bsp", &got);
      ADD_FAILURE() << "a damaged entry was read";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("pak0.pk3: maps/x.bsp: damaged in the archive"), std::string::npos) << e.what();
    }
  }
  // An archive that is not a zip at all.
  std::ofstream(dir / "pak1.pk3") << "not a zip";
  try {
    vds::enc::Pk3Set set(dir.string());
    ADD_FAILURE() << "a broken archive was opened";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("pak1.pk3: not a readable .pk3 (zip) archive"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

TEST(SceneBsp, TheInstalledMapsReadWhole) {
  // openarena-data (scripts/fetch-data.sh): every map the figures use.
  for (const char* map : {"oa_dm4", "oa_dm5", "czest3ctf", "oa_ctf2"}) {
    const Scene s = vds::enc::load_scene(map);
    EXPECT_GT(s.triangles(), 2000u) << map;
    EXPECT_GE(s.spawns.size(), 4u) << map;
    size_t found = 0;
    for (const auto& t : s.textures) found += !t.file.empty();
    EXPECT_GT(found, s.textures.size() / 2) << map;
  }
  EXPECT_THROW(vds::enc::load_scene("no_such_map"), std::runtime_error);
}

}  // namespace
