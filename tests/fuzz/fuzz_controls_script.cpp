// libFuzzer: the host board's controls script (firmware_sim/boards/host/
// controls_script.h), what `vds serve-terrain --controls FILE` hands the
// board. Invariants: no crash, sanitizer report or hang; a refusal is a
// std::runtime_error naming the input; an accepted script holds at most
// kMaxControlFrames entries, each with moves of -1, 0 or 1 and turns and
// tilts within a quarter turn.
//
// Seed corpus: when the corpus directory is empty, a valid script is
// written to it first.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>

#include "controls_script.h"
#include "seed_corpus.h"

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  vds::test::seed_corpus_if_empty(*argc, *argv, [](const std::filesystem::path& dir) {
    std::ofstream(dir / "seed_script") << "# a flight\n10 0 0 0 0 0\n20 1 0 0 2 0\n10 1 0 0 0 -1 fast\n10 0 1 -1 0 0\n";
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const char* name = "input.controls";
  try {
    const std::vector<vds::terrain::SteerInput> s = vds::board::parse_controls_script(text, name);
    if (s.size() > static_cast<size_t>(vds::board::kMaxControlFrames)) abort();
    for (const vds::terrain::SteerInput& in : s) {
      if (in.forward < -1 || in.forward > 1 || in.right < -1 || in.right > 1 || in.up < -1 || in.up > 1) abort();
      if (in.turn < -16384 || in.turn > 16384 || in.tilt < -16384 || in.tilt > 16384) abort();
    }
  } catch (const std::runtime_error& e) {
    if (std::strncmp(e.what(), name, std::strlen(name)) != 0) abort();
  }
  return 0;
}
