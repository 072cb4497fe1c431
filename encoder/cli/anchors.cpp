// Texture anchors for the model benchmarks (anchors.h).
#include "anchors.h"

#include <fstream>
#include <stdexcept>

#include "commands.h"

namespace vds::cli {

using enc::Image;
using enc::load_image;

std::vector<Anchor> read_anchors(const std::string& path, size_t textures) {
  std::ifstream f(path);
  if (!f) throw Failure(kExitBadInput, path + ": cannot read");
  std::vector<Anchor> out;
  std::string line;
  int n = 0;
  while (std::getline(f, line)) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> cols;
    size_t at = 0;
    for (int k = 0; k < 3; ++k) {
      const size_t comma = line.find(',', at);
      if (comma == std::string::npos) throw Failure(kExitBadInput, path + ": line " + std::to_string(n) + ": want codec,parameter,bytes,files");
      cols.push_back(line.substr(at, comma - at));
      at = comma + 1;
    }
    Anchor a;
    a.codec = cols[0];
    a.param = cols[1];
    try {
      a.bytes = std::stoul(cols[2]);
    } catch (const std::exception&) {
      throw Failure(kExitBadInput, path + ": line " + std::to_string(n) + ": bytes '" + cols[2] + "' is not a number");
    }
    std::string files = line.substr(at);
    size_t from = 0;
    while (from <= files.size()) {
      const size_t semi = files.find(';', from);
      const std::string file = files.substr(from, semi == std::string::npos ? std::string::npos : semi - from);
      try {
        a.textures.push_back(load_image(file, 3));
      } catch (const std::runtime_error& e) {
        throw Failure(kExitBadInput, path + ": line " + std::to_string(n) + ": " + e.what());
      }
      if (semi == std::string::npos) break;
      from = semi + 1;
    }
    if (a.textures.size() != textures)
      throw Failure(kExitBadInput, path + ": line " + std::to_string(n) + ": " + std::to_string(a.textures.size()) +
                                       " images for a model of " + std::to_string(textures) + " textures");
    out.push_back(std::move(a));
  }
  return out;
}

}  // namespace vds::cli
