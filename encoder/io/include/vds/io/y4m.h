// A Y4M video file written frame by frame: full-range BT.601 (JFIF)
// Y'CbCr 4:4:4, the inverse of the client's colour conversion.
#pragma once
#include <fstream>
#include <string>

#include "vds/io/image.h"

namespace vds::io {

class Y4mWriter {
 public:
  // Opens `path` (truncating it) on the first frame, which sets the size.
  explicit Y4mWriter(std::string path, int fps = 20) : path_(std::move(path)), fps_(fps) {}
  // Appends an RGB frame; every frame must have the first one's size.
  // Throws std::runtime_error naming the file.
  void write(const Image& rgb);
  // Finishes the file (also done by the destructor, which cannot report a failure).
  // Throws std::runtime_error naming the file if it could not be written whole.
  void close();

 private:
  std::string path_;
  int fps_;
  int width_ = 0, height_ = 0;
  std::ofstream out_;
};

}  // namespace vds::io
