/* fuzz_image_png.c — ic_image_read_ldr: PNG (through stb_image) and JPEG (through libjpeg). */
#include "fuzz_image.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_image_read("img.png", ic_image_read_ldr, 1, data, size);
}
