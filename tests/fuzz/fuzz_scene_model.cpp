// libFuzzer: textured model scenes (vds/enc/scene.h, read_model_scene): OBJ,
// glTF and GLB through the project's checks and assimp. The first byte
// picks the format. Invariants: no crash, sanitizer report or hang; a
// refusal is a std::runtime_error naming the input; an accepted scene has
// whole triangles whose indices name its vertices, surfaces inside its
// indices, and textures its surfaces name; so has the shape `vds
// encode-walk` makes of it (vds/enc/scene_shape.h: merged, then decimated),
// with no more triangles than the scene.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>

#include "seed_corpus.h"
#include "vds/enc/scene.h"
#include "vds/enc/scene_shape.h"

namespace {

void seed(const std::filesystem::path& dir) {
  std::ofstream(dir / "seed_obj", std::ios::binary)
      << '\0' << "mtllib room.mtl\nv -5 -5 -5\nv 5 -5 -5\nv 5 5 -5\nv -5 5 -5\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n"
      << "usemtl wall\nf 1/1/1 2/2/1 3/3/1 4/4/1\nf 1 2 3\n";
  std::ofstream(dir / "seed_gltf", std::ios::binary)
      << '\1'
      << "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
         "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],"
         "\"buffers\":[{\"byteLength\":36,\"uri\":\"data:application/octet-stream;base64,"
         "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}],"
         "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
         "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\",\"min\":[0,0,0],\"max\":[1,1,0]}]}";
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  vds::test::seed_corpus_if_empty(*argc, *argv, seed);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* const kNames[] = {"input.obj", "input.gltf", "input.glb"};
  const std::string name = kNames[data[0] % 3];
  try {
    const vds::enc::Scene s = vds::enc::read_model_scene(data + 1, size - 1, name);
    const auto check = [](const vds::enc::Scene& x) {
      if (x.indices.size() % 3 != 0) abort();
      for (uint32_t i : x.indices)
        if (i >= x.vertices.size()) abort();
      for (const auto& f : x.surfaces) {
        if (f.first_index + static_cast<uint64_t>(f.index_count) > x.indices.size() || f.index_count % 3 != 0) abort();
        if (f.texture >= static_cast<int>(x.textures.size())) abort();
      }
    };
    check(s);
    vds::enc::ShapeOptions so;
    so.tolerance = 1.0 / 16;  // metres: the walkthrough's default
    const vds::enc::Scene shape = vds::enc::simplify_shape(s, so);
    check(shape);
    if (shape.triangles() > s.triangles()) abort();
  } catch (const std::runtime_error& e) {
    if (std::strncmp(e.what(), name.c_str(), name.size()) != 0) abort();
  }
  return 0;
}
