/* fuzz_image_exr.c — ic_image_read_exr: OpenEXR (through the OpenEXR core C API). */
#include "fuzz_image.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_image_read("img.exr", ic_image_read_exr, 0, data, size);
}
