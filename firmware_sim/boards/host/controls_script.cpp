// The host board's controls script (controls_script.h).
#include "controls_script.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace vds::board {

std::vector<terrain::SteerInput> parse_controls_script(const std::string& text, const std::string& name) {
  std::vector<terrain::SteerInput> out;
  std::istringstream lines(text);
  std::string line;
  for (long n = 1; std::getline(lines, line); ++n) {
    std::istringstream in(line);
    std::string first;
    if (!(in >> first) || first[0] == '#') continue;
    long frames = 0;
    int fwd = 0, right = 0, up = 0;
    double turn = 0, tilt = 0;
    std::string fast, extra;
    std::istringstream head(first);
    const bool ok = static_cast<bool>(head >> frames) && head.eof() && static_cast<bool>(in >> fwd >> right >> up >> turn >> tilt);
    if (ok && !(in >> fast)) fast.clear();
    if (!ok || frames < 1 || frames > kMaxControlFrames || fwd < -1 || fwd > 1 || right < -1 || right > 1 || up < -1 || up > 1 ||
        !(turn >= -90 && turn <= 90) || !(tilt >= -90 && tilt <= 90) || (!fast.empty() && fast != "fast") || (in >> extra))
      throw std::runtime_error(name + ": line " + std::to_string(n) +
                               " is not 'FRAMES FORWARD RIGHT UP TURN TILT [fast]' (frames 1..1000000, moves -1..1, degrees within 90)");
    if (static_cast<long>(out.size()) + frames > kMaxControlFrames)
      throw std::runtime_error(name + ": line " + std::to_string(n) + " takes the script past " + std::to_string(kMaxControlFrames) +
                               " frames");
    terrain::SteerInput s;
    s.forward = static_cast<int8_t>(fwd);
    s.right = static_cast<int8_t>(right);
    s.up = static_cast<int8_t>(up);
    s.turn = static_cast<int16_t>(std::lround(turn * 65536.0 / 360.0));
    s.tilt = static_cast<int16_t>(std::lround(tilt * 65536.0 / 360.0));
    s.fast = !fast.empty();
    out.insert(out.end(), static_cast<size_t>(frames), s);
  }
  return out;
}

}  // namespace vds::board
