// Mesh import and repair: each rule of vds/enc/mesh_import.h on a small
// hand-made case with the exact counts it must report, a property test on
// random triangle soups (the result is always manifold, never a throw), and
// file round trips through assimp (OBJ, PLY) and libdraco (.drc).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>

#include <unistd.h>

#include "mesh_test_meshes.h"
#include "vds/enc/mesh_import.h"
#include "vds/enc/stream_writer.h"

namespace {

using vds::enc::check_manifold;
using vds::enc::Mesh;
using vds::enc::MeshRepairReport;
using vds::enc::repair_mesh;

size_t count_boundary_edges(const Mesh& m) {
  std::vector<std::pair<uint32_t, uint32_t>> e;
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) e.emplace_back(std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3]));
  std::sort(e.begin(), e.end());
  size_t n = 0;
  for (size_t i = 0; i < e.size(); ++i) {
    const bool prev = i > 0 && e[i] == e[i - 1];
    const bool next = i + 1 < e.size() && e[i] == e[i + 1];
    if (!prev && !next) ++n;
  }
  return n;
}

TEST(MeshImport, CleanMeshIsUnchanged) {
  const Mesh g = vds::test::grid_mesh(6, 5);
  MeshRepairReport r;
  const Mesh m = repair_mesh(g, &r);
  EXPECT_FALSE(r.repaired());
  EXPECT_EQ(r.welded_vertices, 0u);
  EXPECT_EQ(m.positions, g.positions);
  EXPECT_EQ(m.triangles, g.triangles);
  EXPECT_EQ(r.boundary_edges, 2u * (5 + 4));
  EXPECT_EQ(r.components, 1u);
  EXPECT_EQ(check_manifold(m), "");
}

TEST(MeshImport, WeldsIdenticalPositionsOnly) {
  // Two triangles as a soup: six vertices, two pairs at identical positions
  // (one written as -0.0), and one vertex a hair away that must stay.
  Mesh s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {1, 1, 0}, {-0.0, 1, 0}, {1e-12, 0, 0}};
  s.triangles = {{0, 1, 2}, {3, 4, 5}, {6, 4, 1}};
  MeshRepairReport r;
  const Mesh m = repair_mesh(s, &r);
  EXPECT_EQ(r.welded_vertices, 2u);
  EXPECT_EQ(m.positions.size(), 5u);
  EXPECT_EQ(m.triangles.size(), 3u);
  EXPECT_EQ(check_manifold(m), "");
}

TEST(MeshImport, DropsDegenerateAndDuplicateFaces) {
  Mesh s = vds::test::grid_mesh(3, 3);
  s.triangles.push_back({0, 0, 1});                                               // repeated index
  s.triangles.push_back(s.triangles[0]);                                          // duplicate
  s.triangles.push_back({s.triangles[1][2], s.triangles[1][1], s.triangles[1][0]});  // reversed duplicate
  s.positions.push_back(s.positions[4]);                                          // weld makes the next degenerate
  s.triangles.push_back({4, 8, 9});
  MeshRepairReport r;
  const Mesh m = repair_mesh(s, &r);
  EXPECT_EQ(r.degenerate_faces, 2u);
  EXPECT_EQ(r.duplicate_faces, 2u);
  EXPECT_EQ(r.welded_vertices, 1u);
  EXPECT_EQ(m.triangles.size(), 8u);
  EXPECT_EQ(check_manifold(m), "");
}

TEST(MeshImport, CutsNonManifoldEdge) {
  // Three triangles on edge (0, 1): a "book" with three pages.
  Mesh s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, -1, 0}, {0.5, 0, 1}};
  s.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  MeshRepairReport r;
  const Mesh m = repair_mesh(s, &r);
  EXPECT_EQ(r.non_manifold_edges, 1u);
  EXPECT_EQ(r.dropped_faces, 0u);
  EXPECT_EQ(m.triangles.size(), 3u);
  // Every page keeps its own copy of the edge's two vertices: 3 x 2 + 3 apexes.
  EXPECT_EQ(m.positions.size(), 9u);
  EXPECT_EQ(r.split_vertices, 4u);
  EXPECT_EQ(r.components, 3u);
  EXPECT_EQ(count_boundary_edges(m), 9u);
  EXPECT_EQ(check_manifold(m), "");
}

TEST(MeshImport, SplitsNonManifoldVertex) {
  // Two fans meeting in one vertex (a bow tie).
  Mesh s;
  s.positions = {{0, 0, 0}, {1, 0.5, 0}, {1, -0.5, 0}, {-1, 0.5, 0}, {-1, -0.5, 0}};
  s.triangles = {{0, 2, 1}, {0, 3, 4}};
  MeshRepairReport r;
  const Mesh m = repair_mesh(s, &r);
  EXPECT_EQ(r.split_vertices, 1u);
  EXPECT_EQ(r.non_manifold_edges, 0u);
  EXPECT_EQ(m.positions.size(), 6u);
  EXPECT_EQ(m.positions[5], s.positions[0]);  // the copy keeps the position
  EXPECT_EQ(check_manifold(m), "");
}

TEST(MeshImport, CutsOrientationConflict) {
  // Two faces on edge (0, 1) in the same direction: cut apart, no face lost.
  Mesh s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, -1, 0}};
  s.triangles = {{0, 1, 2}, {0, 1, 3}};
  MeshRepairReport r;
  const Mesh m = repair_mesh(s, &r);
  EXPECT_EQ(r.orientation_conflicts, 1u);
  EXPECT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(r.split_vertices, 2u);
  EXPECT_EQ(check_manifold(m), "");
}

TEST(MeshImport, DropsNonFiniteOutOfRangeAndUnreferenced) {
  Mesh s = vds::test::grid_mesh(3, 3);
  s.positions[8][1] = std::numeric_limits<double>::quiet_NaN();  // corner vertex: one face uses it... two
  s.positions.push_back({5, 5, 5});                              // nobody uses it
  s.triangles.push_back({0, 1, 100});                            // index out of range
  MeshRepairReport r;
  const Mesh m = repair_mesh(s, &r);
  EXPECT_EQ(r.non_finite_vertices, 1u);
  EXPECT_EQ(r.faces_with_non_finite, 3u);  // the two faces on vertex 8 and the out-of-range one
  EXPECT_EQ(r.unreferenced_vertices, 1u);
  EXPECT_EQ(m.positions.size(), 8u);
  EXPECT_EQ(m.triangles.size(), 6u);
  for (const auto& p : m.positions)
    for (double c : p) EXPECT_TRUE(std::isfinite(c));
  EXPECT_EQ(check_manifold(m), "");
}

TEST(MeshImport, HoleKeepsBoundaries) {
  const Mesh h = vds::test::with_hole(vds::test::grid_mesh(12, 12), 0.5, 0.5, 0.2);
  MeshRepairReport r;
  const Mesh m = repair_mesh(h, &r);
  EXPECT_FALSE(r.repaired());
  EXPECT_GT(r.boundary_edges, 2u * 22);  // outer rim plus the hole's rim
  EXPECT_EQ(r.boundary_edges, count_boundary_edges(m));
  EXPECT_EQ(check_manifold(m), "");
}

TEST(MeshImport, RandomSoupsAlwaysComeOutManifold) {
  std::mt19937 rng(7);
  for (int iter = 0; iter < 300; ++iter) {
    Mesh s;
    const int nv = 3 + static_cast<int>(rng() % 12);
    std::uniform_int_distribution<int> coord(0, 3);
    for (int i = 0; i < nv; ++i) s.positions.push_back({double(coord(rng)), double(coord(rng)), double(coord(rng))});
    const int nf = 1 + static_cast<int>(rng() % 40);
    for (int f = 0; f < nf; ++f)
      s.triangles.push_back({static_cast<uint32_t>(rng() % (nv + 1)), static_cast<uint32_t>(rng() % nv),
                             static_cast<uint32_t>(rng() % nv)});
    MeshRepairReport r;
    Mesh m;
    ASSERT_NO_THROW(m = repair_mesh(s, &r)) << "soup " << iter;
    ASSERT_EQ(check_manifold(m), "") << "soup " << iter;
    EXPECT_EQ(r.output_faces, m.triangles.size());
    EXPECT_EQ(r.output_vertices, m.positions.size());
    EXPECT_LE(m.triangles.size(), s.triangles.size());
  }
}

TEST(MeshImport, CheckManifoldNamesTheProblem) {
  Mesh s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, -1, 0}, {0.5, 0, 1}};
  s.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  EXPECT_NE(check_manifold(s).find("3 faces"), std::string::npos);
  s.positions.pop_back();
  s.triangles = {{0, 1, 2}, {0, 1, 3}};
  EXPECT_NE(check_manifold(s).find("same direction"), std::string::npos);
  s.triangles = {{0, 1, 2}};
  EXPECT_NE(check_manifold(s).find("unreferenced"), std::string::npos);
}

TEST(MeshImport, ObjPlyAndDracoFilesRoundTrip) {
  const Mesh g = vds::test::with_hole(vds::test::grid_mesh(9, 7, 0.2), 0.5, 0.5, 0.15);
  const std::string dir = VDS_TEST_TMP;
  vds::enc::write_obj(dir + "/mesh_import.obj", g);
  vds::enc::write_ply(dir + "/mesh_import.ply", g);
  const std::vector<uint8_t> drc = vds::enc::encode_draco(g, 14, 10);
  vds::enc::write_file(dir + "/mesh_import.drc", drc);
  for (const char* ext : {".obj", ".ply", ".drc"}) {
    MeshRepairReport r;
    const Mesh m = vds::enc::import_mesh(dir + "/mesh_import" + ext, &r);
    EXPECT_EQ(m.positions.size(), g.positions.size()) << ext;
    EXPECT_EQ(m.triangles.size(), g.triangles.size()) << ext;
    EXPECT_EQ(check_manifold(m), "") << ext;
    // Same bounds (Draco to its 14-bit grid).
    const auto a = vds::enc::mesh_bounds(g), b = vds::enc::mesh_bounds(m);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(a.min[k], b.min[k], 1e-3) << ext;
      EXPECT_NEAR(a.max[k], b.max[k], 1e-3) << ext;
    }
  }
  EXPECT_THROW(vds::enc::import_mesh(dir + "/no_such_mesh.obj"), std::runtime_error);
  vds::enc::write_file(dir + "/not_a_mesh.drc", std::vector<uint8_t>{1, 2, 3});
  EXPECT_THROW(vds::enc::import_mesh(dir + "/not_a_mesh.drc"), std::runtime_error);
}

TEST(MeshImport, QuantisationSpansTheGrid) {
  const Mesh g = vds::test::grid_mesh(5, 5);
  const auto q = vds::enc::make_quantisation(vds::enc::mesh_bounds(g), 10);
  const auto qp = vds::enc::quantise(g, q);
  int32_t mx = 0, mn = 1 << 20;
  for (const auto& p : qp)
    for (int32_t c : p) {
      mx = std::max(mx, c);
      mn = std::min(mn, c);
    }
  EXPECT_EQ(mn, 0);
  EXPECT_EQ(mx, 1023);
  for (size_t i = 0; i < qp.size(); ++i) {
    const auto back = q.to_model(qp[i]);
    for (int k = 0; k < 3; ++k) EXPECT_LE(std::fabs(back[k] - g.positions[i][k]), q.step / 2 + 1e-12);
  }
  EXPECT_THROW(vds::enc::make_quantisation(vds::enc::mesh_bounds(g), 17), std::invalid_argument);
}

}  // namespace

// --- Files a user did not make (each of these crashed, aborted or took
// gigabytes before the PLY check) -----------------------------------------------

namespace {

std::string ply_binary(uint64_t nv, uint64_t nf, const std::string& body) {
  return "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(nv) +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " + std::to_string(nf) +
         "\nproperty list uchar int vertex_indices\nend_header\n" + body;
}

std::string le(const void* p, size_t n) { return std::string(static_cast<const char*>(p), n); }

std::string quad_body(bool with_faces) {
  std::string b;
  const float v[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  for (const auto& p : v) b += le(p, 12);
  if (with_faces) {
    const int32_t f[2][3] = {{0, 1, 2}, {1, 3, 2}};
    for (const auto& t : f) b += std::string(1, '\3') + le(t, 12);
  }
  return b;
}

// The message load_mesh_bytes refuses `file` with ("" if it is accepted).
std::string refusal(const std::string& file, const std::string& name = "m.ply") {
  try {
    vds::enc::load_mesh_bytes(reinterpret_cast<const uint8_t*>(file.data()), file.size(), name);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(MeshImportHostile, AWellFormedPlyIsRead) {
  EXPECT_EQ(refusal(ply_binary(4, 2, quad_body(true))), "");
}

TEST(MeshImportHostile, PlyFaceListCutShort) {
  const std::string whole = ply_binary(4, 2, quad_body(true));
  EXPECT_NE(refusal(whole.substr(0, whole.size() - 6)).find("m.ply: face 1 of 2: its list of 3 items runs past the end"),
            std::string::npos);
}

TEST(MeshImportHostile, PlyFaceOf255IndicesCutShort) {
  const int32_t three[3] = {0, 1, 2};
  const std::string f = ply_binary(4, 1, quad_body(false)) + "\xff" + le(three, 12);
  EXPECT_NE(refusal(f).find("face 0 of 1: its list of 255 items runs past the end of the file (byte"), std::string::npos);
}

TEST(MeshImportHostile, PlyIndicesOutsideTheVertices) {
  const std::string f =
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n3 0 1 2\n3 1 3 2\n";
  EXPECT_EQ(refusal(f), "m.ply: face 0 of 2: vertex index 2 is not one of the 2 vertices (line 12)");
}

TEST(MeshImportHostile, PlyCountsBeyondTheFileAreRefusedBeforeAnyAllocation) {
  std::string huge = ply_binary(1000000000, 2, quad_body(true));
  huge.resize(4096, '\0');
  EXPECT_NE(refusal(huge).find("declares 1000000000 vertex elements (with those before, at least 12000000000 bytes) but "
                               "the file holds"),
            std::string::npos);
  EXPECT_NE(refusal(ply_binary(4, 4000000, quad_body(true))).find("declares 4000000 face elements"), std::string::npos);
}

TEST(MeshImportHostile, PlyAsciiTakesPlainNumbersOnly) {
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  EXPECT_EQ(refusal(head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"), "");
  EXPECT_NE(refusal(head + std::string("0 0 0\n1 0 0\n0\0 1 0\n3 0 1 2\n", 28)).find("is not a number"), std::string::npos);
  EXPECT_NE(refusal(head + "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n").find("'nan' is not a number"), std::string::npos);
  EXPECT_NE(refusal(head + "0 0 0\n1 0 0\n0 1 0\n3 0 +1 2\n").find("'+1' is not an integer"), std::string::npos);
  EXPECT_NE(refusal(head + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n").find("a face needs 3 to 256 vertices"), std::string::npos);
}

TEST(MeshImportHostile, OnlyTheNamedFormatIsTried) {
  // A file that starts like a PLY is checked as one whatever its name says.
  const std::string whole = ply_binary(4, 2, quad_body(true));
  EXPECT_NE(refusal(whole.substr(0, whole.size() - 6), "m.obj").find("runs past the end"), std::string::npos);
  // An OBJ whose first 200 bytes say "ply" is read by the OBJ reader alone
  // (assimp guessing from the content would take it for a PLY).
  EXPECT_EQ(refusal("# exported with ply tools\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "m.obj"), "");
  EXPECT_NE(refusal("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "m.off").find("not a mesh format this tool reads"),
            std::string::npos);
  EXPECT_NE(refusal(std::string("DRACO") + std::string(64, '\x01'), "m.drc").find("m.drc: not a Draco mesh"),
            std::string::npos);
}

TEST(MeshImportHostile, GlbLengthsAreCheckedBeforeAssimpAllocatesThem) {
  // A GLB header and a JSON chunk claiming 1.7 GB (assimp allocated it).
  auto le32 = [](uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
  const std::string json = "{\"asset\":{\"version\":\"2.0\"}}    ";
  const std::string ok = "glTF" + le32(2) + le32(static_cast<uint32_t>(20 + json.size())) +
                         le32(static_cast<uint32_t>(json.size())) + "JSON" + json;
  EXPECT_EQ(refusal(ok, "m.glb").find("m.glb: the header says"), std::string::npos);
  std::string big = ok;
  big.replace(12, 4, le32(1711276488));
  EXPECT_NE(refusal(big, "m.glb").find("m.glb: a chunk of 1711276488 bytes where"), std::string::npos);
  std::string lying = ok;
  lying.replace(8, 4, le32(135168));
  EXPECT_NE(refusal(lying, "m.glb").find("the header says the file is 135168 bytes"), std::string::npos);
}

TEST(MeshImportHostile, PlyHeaderLinesEndOnlyAtLineFeeds) {
  // end_header as the file's last bytes, with no line feed: nothing follows.
  EXPECT_NE(refusal("ply\nformat binary_little_endian 1.0\nelement vertex 100000\nproperty float x\nend_header")
                .find("declares 100000 vertex elements"),
            std::string::npos);
  // Lines ended by a lone carriage return (another reader's line ends) are refused.
  EXPECT_NE(refusal("ply\rformat ascii 1.0\relement vertex 100000000\rproperty float x\rend_header\r\n"
                    "format ascii 1.0\nelement vertex 0\nend_header\n")
                .find("m.ply: "),
            std::string::npos);
  // CR LF line ends are fine, and the last value needs no separator after it.
  EXPECT_EQ(refusal("ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty float x\r\nproperty float y\r\n"
                    "property float z\r\nelement face 1\r\nproperty list uchar int vertex_indices\r\nend_header\r\n"
                    "0 0 0\r\n1 0 0\r\n0 1 0\r\n3 0 1 2"),
            "");
  // A second element of the same name.
  EXPECT_NE(refusal("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nelement vertex 1\nproperty float x\n"
                    "end_header\n0\n0\n")
                .find("a second element 'vertex'"),
            std::string::npos);
}

TEST(MeshImportHostile, EveryPrefixOfAPlyOrGlbIsRefused) {
  // Binary PLY: every prefix short of the whole file.
  const std::string bin = ply_binary(4, 2, quad_body(true));
  EXPECT_EQ(refusal(bin), "");
  for (size_t n = 0; n < bin.size(); ++n) EXPECT_NE(refusal(bin.substr(0, n)), "") << "binary prefix " << n;
  // ASCII PLY: every prefix that cuts a value or a line (the one dropping
  // only the final line feed is the same file).
  const std::string ascii =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  EXPECT_EQ(refusal(ascii), "");
  for (size_t n = 0; n + 1 < ascii.size(); ++n) EXPECT_NE(refusal(ascii.substr(0, n)), "") << "ascii prefix " << n;
  // GLB: its header states its length, so every prefix is refused.
  auto le32 = [](uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
  const std::string json = "{\"asset\":{\"version\":\"2.0\"}}    ";
  const std::string glb = "glTF" + le32(2) + le32(static_cast<uint32_t>(20 + json.size())) +
                          le32(static_cast<uint32_t>(json.size())) + "JSON" + json;
  for (size_t n = 0; n < glb.size(); ++n) EXPECT_NE(refusal(glb.substr(0, n), "m.glb"), "") << "glb prefix " << n;
}

namespace {

TEST(MeshImportHostile, AnObjIsNeverReadAsItsOwnMaterialLibrary) {
  // The importer's fallback for a material library it cannot open is the
  // model's own name with .mtl: read from memory, that once served the OBJ
  // itself as its material library, whose texture statement before any
  // material crashed the loader.
  for (const std::string obj : {"mtllib r \nmap_Kd a\n", "mtllib x y\nmap_Kd a\n", "map_Ka\nmtllib r \n",
                                "mtllib r \nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nmap_Kd a\n"}) {
    const std::string r = refusal(obj, "m.obj");
    EXPECT_TRUE(r.empty() || r.rfind("m.obj: ", 0) == 0) << r;  // read or refused by name; never a crash
  }
}

TEST(MeshImportHostile, AMaterialLibraryWithATextureBeforeAnyMaterialIsRefused) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("vds_mtl_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "a.obj") << "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  std::ofstream(dir / "m.mtl") << "# textures\n\nmap_Kd x.png\nnewmtl a\n";
  try {
    vds::enc::load_mesh_file((dir / "a.obj").string());
    ADD_FAILURE() << "accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), (dir / "a.obj").string() + ": m.mtl: 'map_Kd' before any 'newmtl' (line 3)");
  }
  std::ofstream(dir / "m.mtl") << "newmtl a\nmap_Kd x.png\n";
  EXPECT_EQ(vds::enc::load_mesh_file((dir / "a.obj").string()).triangles.size(), 1u);
  std::filesystem::remove_all(dir);
}

}  // namespace
