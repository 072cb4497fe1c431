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
#include "vds/enc/scene_render.h"
#include "vds/io/image.h"

#include <unistd.h>

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

namespace {

// A textured OBJ scene written to a temporary folder: one wall 5 m in
// front of the origin (Y up in the file), its texture beside it.
std::filesystem::path write_obj_scene(const std::string& texture_ref, bool write_texture) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("vds_scene_obj_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "room.obj") << "mtllib room.mtl\nv -5 -5 -5\nv 5 -5 -5\nv 5 5 -5\nv -5 5 -5\n"
                                     "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nusemtl wall\n"
                                     "f 1/1/1 2/2/1 3/3/1 4/4/1\n";
  std::ofstream(dir / "room.mtl") << "newmtl wall\nKd 1 1 1\nmap_Kd " << texture_ref << "\n";
  if (write_texture) {
    vds::io::Image im(4, 4, 3);
    for (size_t i = 0; i < im.pixels.size(); i += 3) im.pixels[i] = 10, im.pixels[i + 1] = 200, im.pixels[i + 2] = 30;
    vds::io::save_png((dir / "wall.png").string(), im);
  }
  return dir;
}

TEST(SceneModel, ATexturedObjSceneIsReadAndDrawn) {
  const std::filesystem::path dir = write_obj_scene("wall.png", true);
  const Scene s = vds::enc::load_scene((dir / "room.obj").string());
  EXPECT_EQ(s.kind, "OBJ scene");
  EXPECT_EQ(s.triangles(), 2u);
  ASSERT_EQ(s.textures.size(), 1u);
  EXPECT_FALSE(s.textures[0].file.empty());
  // Y up in the file: the wall at z = -5 is at y = 5 here, seen looking along +Y (yaw 90).
  EXPECT_NEAR(s.min[1], 5.0f, 1e-6f);
  EXPECT_NEAR(s.max[2], 5.0f, 1e-6f);
  const vds::enc::SceneRenderer r(s, vds::enc::load_scene_images(s));
  const vds::enc::SceneFrame f = r.render({0, 0, 0, 90, 0}, 90);
  const size_t c = 90 * 240 + 120;
  EXPECT_NEAR(f.depth[c], 5.0f, 1e-4f);
  EXPECT_EQ(f.rgb.at(120, 90, 0), 10);  // no lightmap, no overbright: the texture as it is
  EXPECT_EQ(f.rgb.at(120, 90, 1), 200);
  EXPECT_EQ(f.rgb.at(120, 90, 2), 30);
  std::filesystem::remove_all(dir);
}

TEST(SceneModel, TexturesOutsideTheFolderAreRefusedAndMissingOnesAreGrey) {
  std::filesystem::path dir = write_obj_scene("../outside.png", false);
  try {
    vds::enc::load_scene((dir / "room.obj").string());
    ADD_FAILURE() << "a texture outside the scene's folder was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("names texture '../outside.png', which is not in the scene's folder"), std::string::npos)
        << e.what();
  }
  std::filesystem::remove_all(dir);
  dir = write_obj_scene("missing.png", false);
  const Scene s = vds::enc::load_scene((dir / "room.obj").string());
  ASSERT_EQ(s.textures.size(), 1u);
  EXPECT_TRUE(s.textures[0].file.empty());
  const vds::enc::SceneFrame f = vds::enc::SceneRenderer(s, vds::enc::load_scene_images(s)).render({0, 0, 0, 90, 0}, 90);
  EXPECT_EQ(f.rgb.at(120, 90, 1), 128);
  std::filesystem::remove_all(dir);
  EXPECT_THROW(vds::enc::load_scene("no_such_scene.gltf"), std::runtime_error);
  EXPECT_THROW(vds::enc::load_scene("scene.fbx"), std::runtime_error);
}

}  // namespace

namespace {

void put_u32(std::vector<uint8_t>& b, uint32_t v) {
  for (int k = 0; k < 4; ++k) b.push_back(static_cast<uint8_t>(v >> (8 * k)));
}
void put_f32(std::vector<uint8_t>& b, float f) {
  uint32_t v;
  std::memcpy(&v, &f, 4);
  put_u32(b, v);
}

TEST(SceneModel, AGlbSceneWithAnEmbeddedTextureKeepsItsOrientation) {
  // A wall 5 m ahead (Y up), texture top half red and bottom half blue,
  // texture coordinates from the top-left corner as glTF defines them.
  vds::io::Image im(4, 4, 3);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) im.at(x, y, 0) = y < 2 ? 255 : 0, im.at(x, y, 1) = 0, im.at(x, y, 2) = y < 2 ? 0 : 255;
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("vds_scene_glb_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  vds::io::save_png((dir / "t.png").string(), im);
  std::ifstream pf(dir / "t.png", std::ios::binary);
  const std::vector<uint8_t> png((std::istreambuf_iterator<char>(pf)), std::istreambuf_iterator<char>());
  std::vector<uint8_t> bin;
  const float pos[4][3] = {{-5, 5, -5}, {5, 5, -5}, {5, -5, -5}, {-5, -5, -5}};
  const float uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (const auto& p : pos)
    for (float f : p) put_f32(bin, f);
  for (const auto& t : uv)
    for (float f : t) put_f32(bin, f);
  for (uint16_t i : {0, 2, 1, 0, 3, 2}) bin.push_back(static_cast<uint8_t>(i)), bin.push_back(static_cast<uint8_t>(i >> 8));
  const size_t png_at = bin.size();
  bin.insert(bin.end(), png.begin(), png.end());
  while (bin.size() % 4) bin.push_back(0);
  std::string json =
      "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
      "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1},\"indices\":2,\"material\":0}]}],"
      "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}],"
      "\"textures\":[{\"source\":0}],\"images\":[{\"bufferView\":3,\"mimeType\":\"image/png\"}],"
      "\"buffers\":[{\"byteLength\":" + std::to_string(bin.size()) + "}],"
      "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":32},"
      "{\"buffer\":0,\"byteOffset\":80,\"byteLength\":12},{\"buffer\":0,\"byteOffset\":" + std::to_string(png_at) +
      ",\"byteLength\":" + std::to_string(png.size()) + "}],"
      "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\",\"min\":[-5,-5,-5],\"max\":[5,5,-5]},"
      "{\"bufferView\":1,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"},"
      "{\"bufferView\":2,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}]}";
  while (json.size() % 4) json += ' ';
  std::vector<uint8_t> glb;
  put_u32(glb, 0x46546C67);  // "glTF"
  put_u32(glb, 2);
  put_u32(glb, static_cast<uint32_t>(12 + 8 + json.size() + 8 + bin.size()));
  put_u32(glb, static_cast<uint32_t>(json.size()));
  put_u32(glb, 0x4E4F534A);  // "JSON"
  glb.insert(glb.end(), json.begin(), json.end());
  put_u32(glb, static_cast<uint32_t>(bin.size()));
  put_u32(glb, 0x004E4942);  // "BIN"
  glb.insert(glb.end(), bin.begin(), bin.end());
  std::ofstream(dir / "wall.glb", std::ios::binary).write(reinterpret_cast<const char*>(glb.data()), static_cast<std::streamsize>(glb.size()));

  const Scene s = vds::enc::load_scene((dir / "wall.glb").string());
  EXPECT_EQ(s.kind, "glTF scene");
  ASSERT_EQ(s.textures.size(), 1u);
  EXPECT_EQ(s.textures[0].embedded.size(), png.size());
  const vds::enc::SceneFrame f = vds::enc::SceneRenderer(s, vds::enc::load_scene_images(s)).render({0, 0, 0, 90, 0}, 90);
  // The wall fills the view: red above the middle, blue below.
  EXPECT_GT(f.rgb.at(120, 40, 0), 200);
  EXPECT_LT(f.rgb.at(120, 40, 2), 50);
  EXPECT_GT(f.rgb.at(120, 140, 2), 200);
  EXPECT_LT(f.rgb.at(120, 140, 0), 50);
  std::filesystem::remove_all(dir);
}

}  // namespace

namespace {

TEST(SceneModel, EveryPrefixOfAnObjSceneIsReadOrRefusedByName) {
  // (From memory a scene may open no other file: no material library.)
  const std::string obj =
      "v -5 -5 -5\nv 5 -5 -5\nv 5 5 -5\nv -5 5 -5\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n"
      "usemtl wall\nf 1/1/1 2/2/1 3/3/1 4/4/1\n";
  size_t read = 0;
  for (size_t n = 0; n <= obj.size(); ++n) {
    try {
      const Scene s = vds::enc::read_model_scene(reinterpret_cast<const uint8_t*>(obj.data()), n, "room.obj");
      for (uint32_t i : s.indices) ASSERT_LT(i, s.vertices.size());
      ++read;
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()).rfind("room.obj: ", 0), 0u) << e.what();
    }
  }
  // The whole file reads, with its two triangles.
  EXPECT_EQ(vds::enc::read_model_scene(reinterpret_cast<const uint8_t*>(obj.data()), obj.size(), "room.obj").triangles(), 2u);
  EXPECT_GT(read, 0u);
}

}  // namespace
