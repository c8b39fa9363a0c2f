/* fuzz_image_png.c — ic_image_read_stb: PNG and JPEG (through stb_image). */
#include "fuzz_image.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_image_read("img.png", ic_image_read_stb, data, size);
}
