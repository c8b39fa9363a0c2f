/*
 * stb_impl.c — the one translation unit that compiles stb_image and stb_image_write.
 *
 * Their warnings are silenced here only; the rest of the image module includes the headers
 * without the IMPLEMENTATION defines. Only the PNG decoder is compiled in: JPEG goes to libjpeg (jpeg.c).
 * STBI_ONLY_PNG already leaves stb_image's JPEG decoder out; STBI_NO_JPEG says so where it matters, as that
 * decoder (stb_image 2.27) has undefined behaviour on damaged files.
 */
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wall"
#pragma GCC diagnostic ignored "-Wextra"
#pragma GCC diagnostic ignored "-Wpedantic"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wimplicit-fallthrough"
#pragma GCC diagnostic ignored "-Wdouble-promotion"

#define STBI_ONLY_PNG
#define STBI_NO_JPEG
#define STB_IMAGE_IMPLEMENTATION
#include <stb_image.h>

#define STBI_WRITE_NO_STDIO
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb_image_write.h>

#pragma GCC diagnostic pop
