// Host image files for the encoder: the image I/O library (vds/io/image.h)
// under the encoder's names.
#pragma once
#include "vds/io/image.h"

namespace vds::enc {

using io::decode_image;
using io::Image;
using io::load_image;
using io::mse;
using io::psnr;
using io::save_png;
using io::side_by_side;

}  // namespace vds::enc
