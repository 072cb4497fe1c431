// The client's player on the host: with room for any stream (a workspace
// far above a board's and a chunk buffer for any chunk), or with exactly a
// board's workspace (ClientArena: its size, and where the player starts in
// it, as the board's log states them). What the host replay of a client
// (client_frame_crcs), the model stream's encoder and its measures decode
// with.
#pragma once
#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "vds/enc/frames.h"
#include "vds/image.h"
#include "vds/player.h"

namespace vds::enc {

class HostPlayer {
 public:
  explicit HostPlayer(const PlayerCallbacks& cb = PlayerCallbacks{}, const ClientArena* board = nullptr) {
    PlayerConfig cfg = kClientPlayerConfig;  // a board's: its chunk buffer too
    if (board != nullptr) {
      if (board->player_from >= board->budget || board->budget > (size_t{1} << 30))
        throw std::runtime_error("client player: a board workspace of " + std::to_string(board->budget) +
                                 " bytes with the player from byte " + std::to_string(board->player_from));
      ws_.resize(board->budget);  // (aligned as the board's: the offsets below are the same modulo 8)
    } else {
      // The chunk buffer, then what the header declares, as on a client.
      ws_.resize((1u << 24) + ImageDecoder::kWorkspaceBytes + (1u << 25));  // or a model of <= 65,536 vertices
      cfg.max_chunk_bytes = 1u << 24;
    }
    arena_ = Arena(ws_.data(), ws_.size());
    if (board != nullptr) arena_.alloc(board->player_from, 1);
    if (player->init(arena_, cfg, cb) != Status::ok) throw std::runtime_error("client player: cannot initialise");
  }
  HostPlayer(const HostPlayer&) = delete;
  HostPlayer& operator=(const HostPlayer&) = delete;

  // Feeds the whole stream: its status at the end.
  Status play(std::span<const uint8_t> s) {
    Status st = player->feed(s.data(), s.size());
    if (st == Status::more_input) st = player->finish();
    return st;
  }

  std::unique_ptr<Player> player = std::make_unique<Player>();

 private:
  std::vector<uint8_t> ws_;
  Arena arena_;
};

}  // namespace vds::enc
