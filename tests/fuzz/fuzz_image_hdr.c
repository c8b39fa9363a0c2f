/* fuzz_image_hdr.c — ic_image_read_hdr: Radiance RGBE (flat and run-length encoded scanlines). */
#include "fuzz_image.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_image_read("img.hdr", ic_image_read_hdr, 0, data, size);
}
