// `vds pack`: wrap files as chunks of a stream (container-level tool, used to
// build test streams and to carry data the codecs do not yet produce).
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "vds/enc/stream_writer.h"

namespace vds::cli {
namespace {

struct PackOptions {
  std::string out;
  std::string mode = "images";
  std::string size = "240x180";
  double fps = 0;
  uint32_t frames = 0;
  uint32_t max_chunk = 4096;
  uint32_t workspace = 0;
  std::vector<std::string> chunks;
  std::vector<std::string> meta;
};

StreamMode parse_mode(const std::string& m) {
  if (m == "images") return StreamMode::images;
  if (m == "walkthrough") return StreamMode::walkthrough;
  if (m == "terrain") return StreamMode::terrain;
  if (m == "model") return StreamMode::model;
  throw Failure(kExitUsage, "--mode must be images, walkthrough, terrain or model, not '" + m + "'");
}

void run_pack(const PackOptions& o) {
  unsigned w = 0, h = 0;
  char tail = 0;
  if (std::sscanf(o.size.c_str(), "%ux%u%c", &w, &h, &tail) != 2 || w == 0 || h == 0 || w > 16384 || h > 16384)
    throw Failure(kExitUsage, "--size must be WIDTHxHEIGHT with sides 1..16384, not '" + o.size + "'");
  StreamHeader hdr = enc::default_header(parse_mode(o.mode), static_cast<uint16_t>(w), static_cast<uint16_t>(h));
  if (o.fps > 0) hdr.frame_period_us = static_cast<uint32_t>(1e6 / o.fps + 0.5);
  hdr.frame_count = o.frames;
  hdr.max_chunk_payload = o.max_chunk;
  hdr.workspace_bytes = o.workspace;

  // Read every input before writing anything, so a bad argument leaves no file.
  struct Item {
    uint32_t type;
    std::string path;
    std::vector<uint8_t> bytes;
  };
  std::vector<Item> items;
  for (const std::string& spec : o.chunks) {
    const size_t eq = spec.find('=');
    if (eq == std::string::npos) throw Failure(kExitUsage, "--chunk must be TYPE=FILE, not '" + spec + "'");
    uint32_t type = 0;
    try {
      type = enc::fourcc_from_string(spec.substr(0, eq));
    } catch (const std::invalid_argument& e) {
      throw Failure(kExitUsage, e.what());
    }
    if (type == chunk::kHeader || type == chunk::kEnd || type == chunk::kMeta)
      throw Failure(kExitUsage, "--chunk type " + spec.substr(0, eq) + " is reserved");
    Item it{type, spec.substr(eq + 1), {}};
    it.bytes = enc::read_file(it.path);
    if (it.bytes.size() > o.max_chunk)
      throw Failure(kExitBadInput, it.path + ": " + std::to_string(it.bytes.size()) +
                                       " bytes do not fit one chunk of --max-chunk " + std::to_string(o.max_chunk) +
                                       " bytes");
    items.push_back(std::move(it));
  }

  enc::StreamWriter writer(hdr);
  for (const std::string& kv : o.meta) {
    const size_t eq = kv.find('=');
    if (eq == std::string::npos || eq == 0) throw Failure(kExitUsage, "--meta must be KEY=VALUE, not '" + kv + "'");
    try {
      writer.add_meta(kv.substr(0, eq), kv.substr(eq + 1));
    } catch (const std::invalid_argument& e) {
      throw Failure(kExitUsage, e.what());
    }
  }
  for (const Item& it : items) writer.add_chunk(it.type, it.bytes);
  const std::vector<uint8_t> stream = writer.finish();
  enc::write_file(o.out, stream);
  std::printf("%s: %zu bytes, %zu chunks\n", o.out.c_str(), stream.size(), items.size() + o.meta.size() + 2);
}

}  // namespace

void add_pack(CLI::App& app) {
  auto o = std::make_shared<PackOptions>();
  CLI::App* sub = app.add_subcommand("pack", "Write a stream whose chunks are the given files");
  sub->add_option("-o,--output", o->out, "Stream to write")->required();
  sub->add_option("--mode", o->mode, "images | walkthrough | terrain | model")->capture_default_str();
  sub->add_option("--size", o->size, "Frame size WIDTHxHEIGHT")->capture_default_str();
  sub->add_option("--fps", o->fps, "Frame rate (0: no timing)")->check(CLI::NonNegativeNumber);
  sub->add_option("--frames", o->frames, "Frame count (0: unknown)");
  sub->add_option("--max-chunk", o->max_chunk, "Largest chunk payload, bytes (declared in the header)")
      ->capture_default_str()->check(CLI::Range(1u, 1u << 24));
  sub->add_option("--workspace", o->workspace, "Decoder workspace the stream declares, bytes");
  sub->add_option("--chunk", o->chunks, "TYPE=FILE: a chunk of four-character TYPE holding FILE (repeatable)");
  sub->add_option("--meta", o->meta, "KEY=VALUE metadata line (repeatable)");
  sub->callback([o] { run_pack(*o); });
}

}  // namespace vds::cli
