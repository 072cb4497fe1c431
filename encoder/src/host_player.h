// The client's player on the host, with room for any model stream (a
// workspace far above a board's and a chunk buffer for any chunk): what
// the model stream's encoder and its measures decode with.
#pragma once
#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <vector>

#include "vds/player.h"

namespace vds::enc {

struct HostPlayer {
  std::vector<uint8_t> ws = std::vector<uint8_t>((1u << 24) + (1u << 25));
  Arena arena{ws.data(), ws.size()};
  std::unique_ptr<Player> player = std::make_unique<Player>();

  explicit HostPlayer(const PlayerCallbacks& cb = PlayerCallbacks{}) {
    PlayerConfig cfg = kClientPlayerConfig;
    cfg.max_chunk_bytes = 1u << 24;
    if (player->init(arena, cfg, cb) != Status::ok) throw std::logic_error("host player: cannot initialise");
  }
  // Feeds the whole stream: its status at the end.
  Status play(std::span<const uint8_t> s) {
    Status st = player->feed(s.data(), s.size());
    if (st == Status::more_input) st = player->finish();
    return st;
  }
};

}  // namespace vds::enc
