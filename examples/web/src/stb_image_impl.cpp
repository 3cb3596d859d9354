// stb_image's implementation for the WebAssembly build (natively it comes from Debian's libstb):
// transforms.json without w/h reads the size of its images.
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#define STBI_ONLY_JPEG
#include <stb_image.h>
