/*
 * tonemap.c — the sRGB transfer function (IEC 61966-2-1) used by PNG output, LDR input and the
 * LDR metrics (include/irrcache/image.h).
 */
#include "irrcache/image.h"

#include <math.h>

float ic_linear_to_srgb(float v)
{
    if (!(v > 0.0f)) /* also NaN */
        return 0.0f;
    if (v >= 1.0f)
        return 1.0f;
    return v <= 0.0031308f ? 12.92f * v : 1.055f * powf(v, 1.0f / 2.4f) - 0.055f;
}

float ic_srgb_to_linear(float v)
{
    if (!(v > 0.0f))
        return 0.0f;
    if (v >= 1.0f)
        return 1.0f;
    return v <= 0.04045f ? v / 12.92f : powf((v + 0.055f) / 1.055f, 2.4f);
}

uint8_t ic_linear_to_srgb8(float v)
{
    return (uint8_t)(ic_linear_to_srgb(v) * 255.0f + 0.5f);
}

float ic_srgb8_to_linear(uint8_t v)
{
    return ic_srgb_to_linear((float)v / 255.0f);
}
