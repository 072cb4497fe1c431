// libFuzzer: Quake III shader scripts (vds/enc/scene.h, read_shader_script),
// read from a map's archives. Invariants: no crash, sanitizer report or
// hang; a refusal is a std::runtime_error naming the script; every shader
// read has a lower-case name and at most as many stages as the text has
// opening braces.
#include <algorithm>
#include <cctype>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

#include <fstream>

#include "seed_corpus.h"
#include "vds/enc/scene.h"

namespace {

void seed(const std::filesystem::path& dir) {
  std::ofstream(dir / "seed_script") << "// seed\ntextures/a/lit\n{\n\tqer_editorimage textures/a/e.tga\n\tsurfaceparm sky\n"
                                        "\tskyparms env/x - -\n\tcull none\n\t{\n\t\tmap $lightmap\n\t}\n\t{\n\t\tmap "
                                        "\"textures/a/w.tga\"\n\t\tblendFunc GL_ONE GL_ONE\n\t\trgbGen vertex\n\t\talphaFunc GE128\n"
                                        "\t}\n\t/* c */\n\t{\n\t\tanimMap 2 a.tga b.tga\n\t}\n}\n";
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  vds::test::seed_corpus_if_empty(*argc, *argv, seed);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  vds::enc::ShaderTable table;
  try {
    vds::enc::read_shader_script(text, "input", &table);
  } catch (const std::runtime_error& e) {
    if (std::strncmp(e.what(), "input: ", 7) != 0) abort();
    return 0;
  }
  const auto braces = static_cast<int>(std::count(text.begin(), text.end(), '{'));
  for (const auto& [name, info] : table) {
    for (char c : name)
      if (std::isupper(static_cast<unsigned char>(c))) abort();
    if (info.stages < 0 || info.stages > braces) abort();
  }
  return 0;
}
