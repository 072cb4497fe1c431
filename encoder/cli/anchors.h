// The texture anchors of the model benchmarks: a model's textures coded by
// other codecs (JPEG, WebP, AVIF), decoded, listed in a CSV file, one line
// per coding: codec,parameter,bytes,decoded-file[;decoded-file...] (one
// decoded image per texture, in the model's order). Read by
// `vds mesh-colors --anchors` and `vds encode-model --anchors`.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "vds/enc/image_io.h"

namespace vds::cli {

struct Anchor {
  std::string codec, param;
  size_t bytes = 0;
  std::vector<enc::Image> textures;
};

// Throws Failure (bad input) naming the file and line.
std::vector<Anchor> read_anchors(const std::string& path, size_t textures);

}  // namespace vds::cli
