// libFuzzer: mesh colors, both ends.
//  - The client's decoder (vds/mesh_colors.h): the input as an MCLH header
//    for a fixed mesh, or as an MCLV level after a valid header (vds mode
//    or paper mode, chroma from the next level's lattice; or the vds mode
//    with chroma on the level's own). Invariants:
//    no crash, sanitizer report or hang; a refused header leaves no level
//    decodable; every write stays inside the level's planes (sized exactly).
//  - The host's textured import from memory and the conversion to mesh
//    colors (vds/enc/mesh_colors.h), what `vds mesh-colors` does with a
//    user's file: the first byte picks the format the name says. A refusal
//    is a std::runtime_error naming the input; an accepted model converts
//    with samples for every face.
//
// Seed corpus: when the corpus directory is empty, small valid inputs are
// written (a header, a level, an OBJ, a Collada file, an MD2, an MS3D).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "model_seeds.h"
#include "seed_corpus.h"
#include "vds/enc/mesh_colors.h"
#include "vds/mesh_colors.h"

namespace {

const char* const kNames[] = {"input.obj", "input.gltf", "input.glb", "input.dae", "input.iqm",
                              "input.3ds", "input.md3", "input.md2", "input.ms3d"};
constexpr int kFormats = 9;

// A fixed 3 x 3 grid of quads with mixed resolutions, and a valid stream for it.
struct Fixed {
  vds::enc::MeshColorsModel model;
  vds::enc::MccEncoded stream;        // the vds mode
  vds::enc::MccEncoded paper_stream;  // the paper mode
  vds::enc::MccEncoded full_stream;   // the vds mode, chroma on each level's own lattice
  Fixed() {
    const int n = 3;
    for (int y = 0; y <= n; ++y)
      for (int x = 0; x <= n; ++x) model.positions.push_back({double(x), double(y), 0});
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const uint16_t a = static_cast<uint16_t>(y * (n + 1) + x), b = a + 1, c = a + n + 1, d = c + 1;
        for (uint16_t v : {a, b, d, a, d, c}) model.triangles.push_back(v);
      }
    const size_t faces = model.triangles.size() / 3;
    for (size_t f = 0; f < faces; ++f) model.face_res.push_back(static_cast<uint8_t>(1 + f % 4));
    model.max_res = 4;
    for (size_t v = 0; v < model.positions.size(); ++v)
      for (int c = 0; c < 3; ++c) model.vertex_ycc.push_back(static_cast<uint8_t>(40 * v + 70 * c));
    std::vector<uint8_t> work(vds::mc::MeshColors::init_bytes(static_cast<uint32_t>(faces), 16));
    vds::Arena arena(work.data(), work.size());
    vds::mc::MeshColors l;
    l.init(arena, model.triangles.data(), static_cast<uint32_t>(faces), 16);
    l.set(model.face_res.data(), model.vertex_ycc.data(), 256);
    for (int m = 0; m <= 4; ++m) {
      const uint32_t total = l.layout_level(m);
      std::array<std::vector<uint8_t>, 3> p;
      for (int c = 0; c < 3; ++c) {
        p[c].resize(total);
        for (uint32_t i = 0; i < total; ++i) p[c][i] = static_cast<uint8_t>((i * (7 + c) * 13) >> 2);
      }
      model.levels.push_back(p);
    }
    vds::enc::MccOptions half;
    half.chroma_half = true;
    stream = vds::enc::encode_mesh_colors(model, 0.5, half);
    vds::enc::MccOptions paper = half;
    paper.paper = true;
    paper_stream = vds::enc::encode_mesh_colors(model, 0.5, paper);
    vds::enc::MccOptions full;
    full.chroma_half = false;
    full_stream = vds::enc::encode_mesh_colors(model, 0.5, full);
  }
};
const Fixed& fixed() {
  static const Fixed f;
  return f;
}

void write(const std::filesystem::path& p, uint8_t pick, const std::string& body) {
  std::ofstream f(p, std::ios::binary);
  f.put(static_cast<char>(pick));
  f.write(body.data(), static_cast<std::streamsize>(body.size()));
}

void seed(const std::filesystem::path& dir) {
  const Fixed& f = fixed();
  write(dir / "seed_header", 0, std::string(f.stream.header.begin(), f.stream.header.end()));
  for (size_t m = 0; m < f.stream.levels.size(); ++m) {
    write(dir / ("seed_level" + std::to_string(m)), 1, std::string(f.stream.levels[m][0].begin(), f.stream.levels[m][0].end()));
    const auto& p = f.paper_stream.levels[m][0];
    write(dir / ("seed_paper_level" + std::to_string(m)), 2, std::string(p.begin(), p.end()));
    const auto& q = f.full_stream.levels[m][0];
    write(dir / ("seed_full_chroma_level" + std::to_string(m)), 4, std::string(q.begin(), q.end()));
  }
  write(dir / "seed_obj", 3, std::string(1, '\0') +
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 3/3 2/2\nf 1/1 2/2 4/3\nf 2/2 3/3 4/1\n");
  write(dir / "seed_dae", 3, std::string(1, '\3') +
        "<?xml version=\"1.0\"?><COLLADA xmlns=\"http://www.collada.org/2005/11/COLLADASchema\" version=\"1.4.1\">"
        "<library_geometries><geometry id=\"g\"><mesh><source id=\"p\"><float_array id=\"pa\" count=\"9\">0 0 0 1 0 0 0 1 0"
        "</float_array><technique_common><accessor source=\"#pa\" count=\"3\" stride=\"3\"><param name=\"X\" type=\"float\"/>"
        "<param name=\"Y\" type=\"float\"/><param name=\"Z\" type=\"float\"/></accessor></technique_common></source>"
        "<vertices id=\"v\"><input semantic=\"POSITION\" source=\"#p\"/></vertices><triangles count=\"1\">"
        "<input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/><p>0 1 2</p></triangles></mesh></geometry>"
        "</library_geometries><library_visual_scenes><visual_scene id=\"s\"><node><instance_geometry url=\"#g\"/></node>"
        "</visual_scene></library_visual_scenes><scene><instance_visual_scene url=\"#s\"/></scene></COLLADA>");
  write(dir / "seed_md2", 3, std::string(1, '\7') + vds::test::md2_seed());
  write(dir / "seed_ms3d", 3, std::string(1, '\10') + vds::test::ms3d_seed());
}

enum class Stream { vds, paper, full_chroma };

void decode(const uint8_t* data, size_t size, bool as_level, Stream which) {
  const Fixed& f0 = fixed();
  struct View {
    const vds::enc::MeshColorsModel& model;
    const vds::enc::MccEncoded& stream;
  } f{f0.model, which == Stream::paper ? f0.paper_stream : (which == Stream::full_chroma ? f0.full_stream : f0.stream)};
  const uint32_t faces = static_cast<uint32_t>(f.model.triangles.size() / 3);
  std::vector<uint8_t> work(vds::mc::MeshColors::init_bytes(faces, 16));
  vds::Arena arena(work.data(), work.size());
  vds::mc::MeshColors mc;
  if (mc.init(arena, f.model.triangles.data(), faces, 16) != vds::Status::ok) abort();
  const std::vector<uint8_t>& header = as_level ? f.stream.header : std::vector<uint8_t>(data, data + size);
  if (mc.read_header(header.data(), header.size()) != vds::Status::ok) {
    if (!as_level) return;
    abort();  // the valid header must be taken
  }
  const std::vector<uint8_t>& level = as_level ? std::vector<uint8_t>(data, data + size) : f.stream.levels[0][0];
  if (level.empty()) return;
  if (level[0] >= mc.max_res_log2()) {
    std::vector<uint8_t> one(1);
    if (mc.decode_level(level.data(), level.size(), vds::mc::Planes{one.data(), one.data(), one.data()}) == vds::Status::ok) abort();
    return;
  }
  // Planes exactly the level's size (the sanitizers catch a write past them).
  const uint32_t total = mc.layout_level(level[0]);
  std::vector<uint8_t> y(total), cb(total), cr(total);
  mc.decode_level(level.data(), level.size(), vds::mc::Planes{y.data(), cb.data(), cr.data()});
}

void import(const uint8_t* data, size_t size) {
  if (size < 1) return;
  const char* name = kNames[data[0] % kFormats];
  try {
    const vds::enc::TexturedModel t = vds::enc::read_textured_model(data + 1, size - 1, name);
    if (t.triangles.size() > 20000) return;  // conversion time, not safety
    vds::enc::MeshColorsOptions o;
    o.max_res_log2 = 3;
    const vds::enc::MeshColorsModel m = vds::enc::to_mesh_colors(t, o);
    if (m.face_res.size() != t.triangles.size() || m.levels.empty()) abort();
  } catch (const std::runtime_error& e) {
    if (std::strncmp(e.what(), name, std::strlen(name)) != 0) abort();  // the refusal names the input
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  vds::test::seed_corpus_if_empty(*argc, *argv, seed);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  if (data[0] == 0)
    decode(data + 1, size - 1, false, Stream::vds);
  else if (data[0] == 1)
    decode(data + 1, size - 1, true, Stream::vds);
  else if (data[0] == 2)
    decode(data + 1, size - 1, true, Stream::paper);
  else if (data[0] == 4)
    decode(data + 1, size - 1, true, Stream::full_chroma);
  else
    import(data + 1, size - 1);
  return 0;
}
