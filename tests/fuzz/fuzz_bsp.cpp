// libFuzzer: the Quake III map reader (vds/enc/scene.h, read_bsp), which
// `vds info`, `vds path` and `vds render` run on maps from the internet,
// and the shape `vds encode-walk` makes of what it reads
// (vds/enc/scene_shape.h: merged, then decimated). The input is the .bsp.
// Invariants: no crash, sanitizer report, hang or allocation beyond the
// limit; a refusal is a std::runtime_error naming the input; an accepted
// scene's triangles index its vertices, its surfaces its textures and
// lightmaps, and its vertices are finite; so do the shape's, which has no
// more triangles than the scene.
//
// Seed corpus: when the corpus directory is empty, the map of
// tests/unit/bsp_builder.h is written to it (and variants: no lightmap, a
// larger patch).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "bsp_builder.h"
#include "seed_corpus.h"
#include "vds/enc/scene.h"
#include "vds/enc/scene_shape.h"

namespace {

void check(const vds::enc::Scene& s) {
  for (uint32_t i : s.indices)
    if (i >= s.vertices.size()) abort();
  if (s.indices.size() % 3 != 0) abort();
  for (const auto& f : s.surfaces) {
    if (f.texture < 0 || static_cast<size_t>(f.texture) >= s.textures.size()) abort();
    if (f.lightmap >= 0 && static_cast<size_t>(f.lightmap) >= s.lightmaps.size()) abort();
    if (static_cast<size_t>(f.first_index) + f.index_count > s.indices.size()) abort();
  }
  for (const auto& v : s.vertices)
    for (float x : v.pos)
      if (!std::isfinite(x)) abort();
}

void write(const std::filesystem::path& p, const std::vector<uint8_t>& b) {
  std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

void seed(const std::filesystem::path& dir) {
  write(dir / "seed_room", vds::test::BspBuilder().build());
  vds::test::BspBuilder b;
  b.lightmaps = 0;
  for (auto& f : b.faces) f.lightmap = -1;
  write(dir / "seed_vertex_lit", b.build());
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  vds::test::seed_corpus_if_empty(*argc, *argv, seed);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    vds::enc::SceneOptions o;
    o.patch_tolerance = 0.5;
    const vds::enc::Scene s = vds::enc::read_bsp(data, size, "input.bsp", o);
    check(s);
    vds::enc::ShapeOptions so;
    so.tolerance = 2;  // map units: the walkthrough's default
    const vds::enc::Scene shape = vds::enc::simplify_shape(s, so);
    check(shape);
    if (shape.triangles() > s.triangles()) abort();
  } catch (const std::runtime_error& e) {
    if (std::strncmp(e.what(), "input.bsp: ", 11) != 0) abort();
  }
  return 0;
}
