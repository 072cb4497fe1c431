// `vds <verb> [options]`: the command line of the vds encoder and tools.
#include <cstdio>
#include <exception>
#include <new>
#include <stdexcept>

#include "commands.h"

int main(int argc, char** argv) {
  CLI::App app{"vds: stream texture-intensive 3D content to microcontroller-class clients"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "vds 0.1.0 (stream container 1.0)");
  vds::cli::add_info(app);
  vds::cli::add_pack(app);
  vds::cli::add_serve(app);
  vds::cli::add_play(app);
  vds::cli::add_encode_mesh(app);
  vds::cli::add_encode_frames(app);
  vds::cli::add_frames(app);
  vds::cli::add_encode_image(app);
  vds::cli::add_decode_image(app);
  vds::cli::add_path(app);
  vds::cli::add_render(app);
  vds::cli::add_encode_walk(app);
  vds::cli::add_fly(app);
  vds::cli::add_encode_terrain(app);
  vds::cli::add_serve_terrain(app);
  vds::cli::add_mesh_colors(app);
  vds::cli::add_encode_model(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return vds::cli::kExitUsage;
  } catch (const vds::cli::Failure& e) {
    const CLI::App* sub = app.get_subcommands().empty() ? nullptr : app.get_subcommands().front();
    std::fprintf(stderr, "vds %s: %s\n", sub ? sub->get_name().c_str() : "", e.what());
    return e.exit_code;
  } catch (const std::runtime_error& e) {
    // The library's refusals of an input: they name the file, what and where.
    const CLI::App* sub = app.get_subcommands().empty() ? nullptr : app.get_subcommands().front();
    std::fprintf(stderr, "vds %s: %s\n", sub ? sub->get_name().c_str() : "", e.what());
    return vds::cli::kExitBadInput;
  } catch (const std::bad_alloc&) {
    const CLI::App* sub = app.get_subcommands().empty() ? nullptr : app.get_subcommands().front();
    std::fprintf(stderr, "vds %s: internal error: out of memory\n", sub ? sub->get_name().c_str() : "");
    return vds::cli::kExitInternal;
  } catch (const std::exception& e) {
    // Misuse inside the tool (std::logic_error and the like): a bug.
    const CLI::App* sub = app.get_subcommands().empty() ? nullptr : app.get_subcommands().front();
    std::fprintf(stderr, "vds %s: internal error: %s\n", sub ? sub->get_name().c_str() : "", e.what());
    return vds::cli::kExitInternal;
  }
  return vds::cli::kExitOk;
}
