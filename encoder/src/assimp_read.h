// vds encoder: model files read with assimp after the project's own checks
// (shared by mesh import and scene import). Private to encoder/src.
#pragma once
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include <assimp/Importer.hpp>
#include <assimp/scene.h>

namespace vds::enc {

// A file a model names, relative to the model's folder `root`, as an
// absolute path inside that folder; "" if it lies outside it (an absolute
// path elsewhere, or one leading out with ".."), or if root is empty.
std::string confined_path(const std::filesystem::path& root, const std::string& file);

// Reads `data` (a model file named `name`, of the format `hint`: its
// extension, lower case) with `importer` and post-processing `steps`. PLY
// and GLB are checked by the project's own readers first; only the loader
// of that one format is registered; the importer may open only files in
// `root` or below it (none when root is empty). The scene lives as long as
// the importer. Throws std::runtime_error "NAME: what".
const aiScene* read_with_assimp(Assimp::Importer& importer, const uint8_t* data, size_t size, const std::string& name,
                                const std::string& hint, const std::filesystem::path& root, unsigned steps);

}  // namespace vds::enc
