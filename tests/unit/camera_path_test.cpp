// Camera path and keyframe files (vds/enc/camera_path.h): round trips,
// comments and settings, refusals naming the line, and keyframe
// interpolation that passes every key, moves smoothly and turns the short
// way round.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "vds/enc/camera_path.h"

namespace {

using vds::enc::CameraPath;

std::string refusal_path(const std::string& text) {
  try {
    vds::enc::read_camera_path(text, "p.txt");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

std::string refusal_keys(const std::string& text) {
  try {
    vds::enc::read_camera_keys(text, "k.txt");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(CameraPath, RoundTripsWithItsSettings) {
  const CameraPath p = vds::enc::read_camera_path(
      "# a tour\n# hfov 75\n# fps 25\n0 1 2 3 90 -10\n\n1 1.5 2 3 95.25 -9.5\n2 2 2 3 100 0\n", "p.txt");
  EXPECT_EQ(p.hfov_deg, 75);
  EXPECT_EQ(p.fps, 25);
  ASSERT_EQ(p.frames.size(), 3u);
  EXPECT_EQ(p.frames[1].x, 1.5);
  EXPECT_EQ(p.frames[1].yaw_deg, 95.25);
  const CameraPath back = vds::enc::read_camera_path(vds::enc::write_camera_path(p), "again");
  ASSERT_EQ(back.frames.size(), 3u);
  EXPECT_EQ(back.hfov_deg, 75);
  EXPECT_EQ(back.fps, 25);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(back.frames[i].x, p.frames[i].x);
    EXPECT_EQ(back.frames[i].pitch_deg, p.frames[i].pitch_deg);
  }
}

TEST(CameraPath, BadLinesAreRefusedWithTheirNumber) {
  EXPECT_EQ(refusal_path("0 0 0 0 0 0\n2 0 0 0 0 0\n"), "p.txt: frame 2 where frame 1 comes next (line 2)");
  EXPECT_EQ(refusal_path("0 0 0 0 0\n"), "p.txt: 5 values where 6 are needed (line 1)");
  EXPECT_EQ(refusal_path("0 0 0 0 0 0 7\n"), "p.txt: more than 6 values (line 1)");
  EXPECT_EQ(refusal_path("# c\n0 0 x 0 0 0\n"), "p.txt: a value that is not a number (line 2)");
  EXPECT_EQ(refusal_path("0 0 0 0 0 nan\n"), "p.txt: a value that is not finite (line 1)");
  EXPECT_EQ(refusal_path("0 0 0 0 0 91\n"), "p.txt: a pitch outside [-90, 90] degrees (line 1)");
  EXPECT_EQ(refusal_path("# hfov 200\n0 0 0 0 0 0\n"), "p.txt: a horizontal field of view outside (1, 179) degrees (line 1)");
  EXPECT_EQ(refusal_path(std::string("0 0 0\0 0 0 0\n", 14)), "p.txt: a control byte (line 1)");
  EXPECT_EQ(refusal_path("# nothing\n"), "p.txt: no frames");
  EXPECT_EQ(refusal_keys("0 0 0 0 0 0\n0 1 0 0 0 0\n"), "k.txt: a time that does not rise (line 2)");
  EXPECT_EQ(refusal_keys("0 0 0 0 0 0\n"), "k.txt: fewer than two keys");
  EXPECT_EQ(refusal_keys("0 0 0 0 0 0\n80000 0 0 0 0 0\n"), "k.txt: more than 1048576 frames at 20.000000 frames/s");
}

TEST(CameraPath, EveryPrefixIsReadOrRefusedByLine) {
  // A line-based text format cannot tell a file cut at a line end from a
  // shorter file: such a prefix reads its whole frames. A prefix whose last
  // line lost values is refused, naming that line.
  const std::string path = "# hfov 75\n0 1 2 3 90 -10\n1 1.5 2 3 95.25 -9.5\n";
  for (size_t n = 0; n <= path.size(); ++n) {
    const std::string p = path.substr(0, n), why = refusal_path(p);
    const size_t last = p.rfind('\n') == std::string::npos ? 0 : p.rfind('\n') + 1;
    const std::string tail = p.substr(last);
    size_t values = 0;
    for (size_t k = 0; k < tail.size(); ++k) values += tail[k] != ' ' && (k == 0 || tail[k - 1] == ' ');
    if (!tail.empty() && tail[0] != '#' && values < 6) {
      EXPECT_NE(why.find("(line "), std::string::npos) << "prefix " << n << ": " << why;
    } else if (tail.empty() && n >= 25) {
      ASSERT_EQ(why, "") << "prefix " << n;
      EXPECT_EQ(vds::enc::read_camera_path(p, "p").frames.size(), n == path.size() ? 2u : 1u) << "prefix " << n;
    }
  }
}

TEST(CameraPath, KeyframesArePassedSmoothlyAndTurnTheShortWay) {
  const vds::enc::CameraKeys k = vds::enc::read_camera_keys(
      "# fps 10\n0 0 0 0 350 0\n1 10 0 0 10 0\n2 10 10 0 20 10\n3 0 10 5 20 0\n", "k.txt");
  const CameraPath p = vds::enc::interpolate_keyframes(k);
  ASSERT_EQ(p.frames.size(), 31u);  // 0 .. 3 s at 10 frames/s
  // Every key is passed exactly.
  EXPECT_NEAR(p.frames[10].x, 10, 1e-9);
  EXPECT_NEAR(p.frames[20].y, 10, 1e-9);
  EXPECT_NEAR(p.frames[30].z, 5, 1e-9);
  EXPECT_NEAR(p.frames[20].pitch_deg, 10, 1e-9);
  // 350 -> 10 degrees turns through 0, not back through 180.
  for (int f = 0; f <= 10; ++f) {
    const double y = p.frames[static_cast<size_t>(f)].yaw_deg;
    EXPECT_TRUE(y >= 340 || y <= 20) << "frame " << f << " yaw " << y;
  }
  // Smooth: no step between frames much larger than its neighbours'.
  for (size_t f = 1; f + 1 < p.frames.size(); ++f) {
    const double d1 = std::hypot(p.frames[f].x - p.frames[f - 1].x, p.frames[f].y - p.frames[f - 1].y);
    const double d2 = std::hypot(p.frames[f + 1].x - p.frames[f].x, p.frames[f + 1].y - p.frames[f].y);
    EXPECT_LT(std::fabs(d2 - d1), 0.6) << "frame " << f;
  }
}

}  // namespace
