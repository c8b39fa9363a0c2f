/* fuzz_image_pfm.c — ic_image_read_pfm: PFM (colour and grey, either byte order). */
#include "fuzz_image.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_image_read("img.pfm", ic_image_read_pfm, 0, data, size);
}
