// The one translation unit that compiles stb_image's implementation
// (Debian's libstb-dev ships the header-only library).
#define STB_IMAGE_IMPLEMENTATION
#define STBI_FAILURE_USERMSG
#include <stb_image.h>
