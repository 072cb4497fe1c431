// The host board's controls script (--controls FILE): the viewer's controls
// for one frame shown after another, as a user's keys would give them.
// Host code (the board), not the client.
//
// Lines "FRAMES FORWARD RIGHT UP TURN TILT [fast]", each holding for FRAMES
// frames (1..1,000,000; at most 1,000,000 in all): FORWARD, RIGHT and UP
// -1, 0 or 1; TURN (to the left) and TILT (up) in degrees a frame, within
// +-90; "fast" four times the speed. Blank lines and lines starting with
// '#' are skipped.
#pragma once
#include <string>
#include <vector>

#include "vds/terrain_client.h"

namespace vds::board {

constexpr long kMaxControlFrames = 1000000;

// One entry a frame. Throws std::runtime_error "NAME: line N is not ..." for
// a line that does not read so, or a script of more frames than that.
std::vector<terrain::SteerInput> parse_controls_script(const std::string& text, const std::string& name);

}  // namespace vds::board
