// The `vds` command: each verb registers its options on a CLI11 subcommand
// and runs when selected. Errors are thrown as vds::cli::Failure and printed
// by main() as "vds VERB: message" with the failure's exit code.
#pragma once
#include <stdexcept>
#include <cstdlib>
#include <string>

#include <CLI/CLI.hpp>

namespace vds::cli {

// Exit codes of every verb.
enum Exit : int {
  kExitOk = 0,
  kExitBadInput = 1,  // a file that is missing, unreadable or not valid
  kExitUsage = 2,     // wrong options
  kExitInternal = 3,  // the tool's own failure (a bug, or memory exhausted): not the input's fault
};

// An option that must be a number above zero (0 is not "unset").
inline const CLI::Validator kPositive(
    [](std::string& v) -> std::string {
      char* end = nullptr;
      const double d = std::strtod(v.c_str(), &end);
      return end != v.c_str() && *end == '\0' && d > 0 ? std::string() : "must be a number above 0, not '" + v + "'";
    },
    "POSITIVE");

// The frames of a contact sheet: the k-th of `tiles` frames spread evenly
// over `n` (the first and the last included).
inline size_t sheet_frame(size_t k, size_t tiles, size_t n) { return tiles < 2 ? 0 : k * (n - 1) / (tiles - 1); }

// --chroma and --faces of the verbs that code mesh colors (encode-model,
// mesh-colors): both auto, the vds encoder draws its four choices and keeps
// the best (vds::enc::choose_colours); otherwise they are as given.
struct ColourChoiceArgs {
  std::string chroma = "auto";  // auto, half, full
  std::string faces = "auto";   // auto, fine, coarser
  bool look() const { return chroma == "auto" && faces == "auto"; }
  bool chroma_half() const { return chroma == "half"; }
  bool coarser_faces() const { return faces == "coarser"; }
};
inline void add_colour_choice_options(CLI::App* app, ColourChoiceArgs* a) {
  app->add_option("--chroma", a->chroma,
                  "each colour level's chroma on the next level's lattice (half) or its own (full); auto (with --faces "
                  "auto): the vds encoder draws both and keeps the better, the thesis's codec keeps its own")
      ->check(CLI::IsMember({"auto", "half", "full"}));
  app->add_option("--faces", a->faces,
                  "vds codec: faces made coarser where a coarser lattice predicts them as well as coding them "
                  "(coarser), or each at its texels' resolution (fine); auto (with --chroma auto): the encoder draws "
                  "both and keeps the better")
      ->check(CLI::IsMember({"auto", "fine", "coarser"}));
}

struct Failure : std::runtime_error {
  Failure(int code, const std::string& what) : std::runtime_error(what), exit_code(code) {}
  int exit_code;
};

void add_info(CLI::App& app);
void add_path(CLI::App& app);
void add_render(CLI::App& app);
void add_encode_walk(CLI::App& app);
void add_pack(CLI::App& app);
void add_serve(CLI::App& app);
void add_play(CLI::App& app);
void add_encode_mesh(CLI::App& app);
void add_encode_frames(CLI::App& app);
void add_frames(CLI::App& app);
void add_encode_image(CLI::App& app);
void add_decode_image(CLI::App& app);
void add_fly(CLI::App& app);
void add_encode_terrain(CLI::App& app);
void add_serve_terrain(CLI::App& app);
void add_mesh_colors(CLI::App& app);
void add_encode_model(CLI::App& app);

}  // namespace vds::cli
