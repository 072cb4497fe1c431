// Image sequences: a stream of frames (one vds image each) and the host
// replay of the client firmware's decode path, which gives the CRC-32C of
// every frame exactly as a client displays it (RGB565 bands).
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "vds/enc/image_codec.h"
#include "vds/enc/image_io.h"

namespace vds::enc {

struct FrameSequenceOptions {
  int width = 240;
  int height = 180;
  double fps = 20;
  ImageEncodeOptions image;  // quality / rate target per frame
};

struct FrameSequenceResult {
  std::vector<uint8_t> stream;
  std::vector<double> psnr;         // per frame, RGB, against the resized source
  std::vector<size_t> frame_bytes;  // per frame, chunks included
};

// Scales `img` to cover w x h (keeping its aspect ratio, area-averaged) and
// crops the centre. Returns RGB.
Image fit_image(const Image& img, int w, int h);

// Encodes each image as one intra frame of an images-mode stream. The
// header's max_chunk_payload and workspace_bytes are what the frames need.
FrameSequenceResult encode_frames(const std::vector<Image>& frames, const FrameSequenceOptions& o);

// What a client shows: plays the stream (any mode the client plays) through
// the client's player (vds/player.h) with the boards' configuration, and
// returns each frame's CRC-32C (and its pixels if `frames` is given).
// Throws std::runtime_error naming the client status on a bad stream.
//
// A client's workspace decides some pictures (how fine a model's colours
// it holds): `arena` replays one board exactly, its player given the
// workspace from byte `player_from` to `budget` as on the board (whose log
// says both: "client: ready, workspace B bytes, player from byte U"), with
// the boards' chunk buffer. Without it the player has room for any stream.
struct ClientArena {
  size_t budget = 0;
  size_t player_from = 0;
};
// `notices`, when given, receives what the player decided about a model
// (PlayerNotice), one line each, worded as the firmware logs them.
std::vector<uint32_t> client_frame_crcs(std::span<const uint8_t> stream, std::vector<Image>* frames = nullptr,
                                        const ClientArena* arena = nullptr, std::vector<std::string>* notices = nullptr);

}  // namespace vds::enc
