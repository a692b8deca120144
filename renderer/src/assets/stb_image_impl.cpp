// The one definition of stb_image in the renderer: PNG and JPEG textures, Radiance HDR
// environments, all from memory (image_decode.cpp). Only those decoders are compiled in, which
// keeps the code that parses uploaded bytes small. stb_image's failure reason is thread-local
// (STBI_THREAD_LOCAL), so decoding is safe on several threads at once.
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#define STBI_ONLY_JPEG
#define STBI_ONLY_HDR
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wsign-compare"
#endif
#include <stb_image.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif
