/*
 * ldr.c — 8-bit images: reading PNG through stb_image (8- or 16-bit sRGB, converted to linear) and JPEG
 * through jpeg.c (libjpeg), told apart by their first bytes, and writing 8-bit sRGB PNG through
 * stb_image_write (from linear images, or bytes as given), tagged as sRGB (sRGB, gAMA and cHRM chunks).
 *
 * Alpha is dropped on read and grey images are replicated to RGB. PNG output applies the exposure
 * (2^stops), then the sRGB curve, clamped to [0, 255]; NaN becomes 0. stb_image is compiled without its
 * JPEG decoder (stb_impl.c), so a JPEG never reaches it.
 */
#include "image_internal.h"
#include "core/read_file.h"

#include "core/atomic_file.h"

#include <inttypes.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <stb_image.h>
#include <stb_image_write.h>

static ic_result decode_failed(const char *path, ic_error *err)
{
    /* stb_image's reason, printable: it can be empty, or quote a damaged chunk type's raw bytes. */
    const char *why = stbi_failure_reason();
    char shown[64];
    size_t k = 0;
    for (; why && why[k] && k + 1 < sizeof shown; ++k)
        shown[k] = why[k] >= 0x20 && why[k] < 0x7f ? why[k] : '?';
    shown[k] = '\0';
    return ic_error_set(err, IC_ERR_PARSE, "%s: cannot decode image (%s); check that it is a valid PNG file",
                        path, k ? shown : "its data is damaged or ends early");
}

static uint32_t be32(const unsigned char *b)
{
    return (uint32_t)b[0] << 24 | (uint32_t)b[1] << 16 | (uint32_t)b[2] << 8 | b[3];
}

/* A PNG whose IDAT chunks include an empty one, as a malloc'd copy without them (*m bytes); NULL when the
 * data is not a PNG, has none, or memory runs out. An empty IDAT is valid PNG (ISO/IEC 15948 §11.2.4: the
 * image data is the concatenation of all IDAT chunks), but stb_image 2.27 offsets its NULL buffer by the
 * first IDAT's zero length ("applying zero offset to null pointer", found by the image_png fuzz target),
 * so the chunk, which carries no data, is dropped before stb_image sees the file. Chunks are walked by
 * their lengths (png_chunk_overrun has refused one that runs past the end). */
static unsigned char *png_without_empty_idat(const unsigned char *b, size_t n, size_t *m)
{
    static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
    if (n < 8 || memcmp(b, signature, 8) != 0)
        return NULL;
    int empty = 0;
    for (size_t i = 8; i + 12 <= n;) {
        uint32_t len = be32(b + i);
        if (len > n - i - 12)
            break;
        empty |= len == 0 && memcmp(b + i + 4, "IDAT", 4) == 0;
        i += 12 + (size_t)len;
    }
    unsigned char *out = empty ? malloc(n) : NULL;
    if (!out)
        return NULL;
    memcpy(out, b, 8);
    size_t o = 8, i = 8;
    while (i + 12 <= n) {
        uint32_t len = be32(b + i);
        if (len > n - i - 12)
            break;
        if (!(len == 0 && memcmp(b + i + 4, "IDAT", 4) == 0)) {
            memcpy(out + o, b + i, 12 + (size_t)len);
            o += 12 + (size_t)len;
        }
        i += 12 + (size_t)len;
    }
    memcpy(out + o, b + i, n - i); /* a truncated tail, as it was */
    *m = o + (n - i);
    return out;
}

/* The offset of the first PNG chunk before IEND whose declared length (with its type and CRC) runs past the
 * end of the data, or 0 when none does or the data is not a PNG. stb_image 2.27 grows its IDAT buffer to the
 * declared length before reading the chunk, so a 117-byte file declaring a 1 GB IDAT made it allocate 2 GB
 * (found by the image_png fuzz target); such a file is truncated or damaged (ISO/IEC 15948 §5.3: a chunk
 * holds as many bytes as its length says) and never reaches stb_image. */
static size_t png_chunk_overrun(const unsigned char *b, size_t n)
{
    static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
    if (n < 8 || memcmp(b, signature, 8) != 0)
        return 0;
    for (size_t i = 8; i + 8 <= n && memcmp(b + i + 4, "IEND", 4) != 0;) {
        uint32_t len = be32(b + i);
        if (len > n - i || n - i - len < 12)
            return i;
        i += 12 + (size_t)len;
    }
    return 0;
}

/* The CRC-32 of PNG chunks (ISO/IEC 15948 §5.3 and Annex D): its table, and the CRC of n bytes (a chunk's
 * type and data). */
static void png_crc_table(uint32_t table[256])
{
    for (uint32_t v = 0; v < 256; ++v) {
        uint32_t c = v;
        for (int k = 0; k < 8; ++k)
            c = c & 1u ? 0xEDB88320u ^ (c >> 1) : c >> 1;
        table[v] = c;
    }
}

static uint32_t png_crc(const uint32_t table[256], const unsigned char *b, size_t n)
{
    uint32_t crc = 0xFFFFFFFFu;
    for (size_t k = 0; k < n; ++k)
        crc = table[(crc ^ b[k]) & 0xFFu] ^ (crc >> 8);
    return crc ^ 0xFFFFFFFFu;
}

/* The first critical PNG chunk, up to IEND, whose CRC-32 (ISO/IEC 15948 §5.3 and Annex D: over its type
 * and data) does not match: its offset in *at and 1; 2 with *at = n when the chunks end without IEND; 0 when all
 * match or the data is not a PNG. stb_image checks neither (nor the zlib stream's Adler-32), so a flipped
 * byte in the pixel data decoded as wrong pixels. Chunks are walked by their lengths (png_chunk_overrun
 * has refused one that runs past the end). */
static int png_bad_chunk(const unsigned char *b, size_t n, size_t *at)
{
    static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
    if (n < 8 || memcmp(b, signature, 8) != 0)
        return 0;
    uint32_t table[256];
    png_crc_table(table);
    for (size_t i = 8; i + 12 <= n;) {
        uint32_t len = be32(b + i);
        if (len > n - i - 12)
            break;
        /* As libpng does: a critical chunk (its type's first letter upper case) must match; an ancillary
         * one that does not is metadata the decoder skips anyway. */
        if (png_crc(table, b + i + 4, 4 + (size_t)len) != be32(b + i + 8 + len) && !(b[i + 4] & 0x20)) {
            *at = i;
            return 1;
        }
        if (memcmp(b + i + 4, "IEND", 4) == 0)
            return 0;
        i += 12 + (size_t)len;
    }
    *at = n;
    return 2;
}

/* Bytes a PNG or JPEG may have beyond its pixels' need: 16 per declared pixel (far above either format's
 * worst case) plus room for metadata. A larger file is damaged or hostile, and is refused before it is
 * read into memory. */
#define LDR_BYTES_PER_PIXEL 16u
#define LDR_METADATA_BYTES ((size_t)16 << 20)

/* The size a PNG (its IHDR, the first chunk: ISO/IEC 15948 §11.2.2) or a JPEG (its first frame header,
 * SOF0..SOF15 but DHT, JPG and DAC: T.81 §B.2.2) declares, read through the stream's marker segments
 * without reading their contents: 1 and *w, *h if found, 0 if not. */
static int ldr_declared_size(FILE *f, uint32_t *w, uint32_t *h)
{
    unsigned char b[24];
    if (fread(b, 1, 2, f) != 2)
        return 0;
    if (b[0] == 0x89) { /* PNG: signature (8), IHDR's length (4) and type (4), width, height */
        if (fread(b + 2, 1, 22, f) != 22 || memcmp(b + 12, "IHDR", 4) != 0)
            return 0;
        *w = be32(b + 16);
        *h = be32(b + 20);
        return 1;
    }
    for (;;) { /* JPEG, after SOI: markers, each 0xFF (fill bytes allowed) and a code */
        int c = fgetc(f);
        if (c != 0xFF)
            return 0;
        while ((c = fgetc(f)) == 0xFF)
            ;
        if (c == EOF || c == 0xD9 || c == 0xDA) /* end of file, EOI or SOS before any frame header */
            return 0;
        if (c == 0x01 || (c >= 0xD0 && c <= 0xD7)) /* TEM, RSTn: no length */
            continue;
        if (fread(b, 1, 2, f) != 2)
            return 0;
        const long length = (long)b[0] << 8 | b[1]; /* includes its own two bytes */
        if (c >= 0xC0 && c <= 0xCF && c != 0xC4 && c != 0xC8 && c != 0xCC) {
            if (length < 8 || fread(b, 1, 5, f) != 5) /* precision, height, width */
                return 0;
            *h = (uint32_t)b[1] << 8 | b[2];
            *w = (uint32_t)b[3] << 8 | b[4];
            return 1;
        }
        if (length < 2 || fseek(f, length - 2, SEEK_CUR) != 0)
            return 0;
    }
}

/* Reads a PNG or JPEG file whole, once its header says it is worth reading: its declared size within the
 * limit and the file no longer than that size can need. */
static ic_result read_ldr_file(const char *path, const ic_image_limit *lim, unsigned char **out, size_t *n,
                               ic_error *err)
{
    *out = NULL;
    *n = 0;
    FILE *f;
    ic_result r = ic_open_regular_file(path, "PNG, JPEG, EXR, HDR or PFM file", &f, err);
    if (r != IC_OK)
        return r;
    uint32_t w = 0, h = 0;
    const int declared = ldr_declared_size(f, &w, &h);
    long size = fseek(f, 0, SEEK_END) == 0 ? ftell(f) : -1;
    size_t allowed = LDR_METADATA_BYTES;
    if (declared && w > 0 && h > 0 && w <= IC_IMAGE_MAX_SIDE && h <= IC_IMAGE_MAX_SIDE) {
        r = ic_image_check_size(path, (int)w, (int)h, lim, err);
        allowed += (size_t)w * h * LDR_BYTES_PER_PIXEL;
    } else if (declared)
        allowed = SIZE_MAX; /* an impossible size: the decoder reports it */
    if (r == IC_OK && (size < 0 || (unsigned long)size >= (unsigned long)INT_MAX || fseek(f, 0, SEEK_SET) != 0))
        r = ic_error_set(err, IC_ERR_IO, "%s: cannot read the image (or it is 2 GiB or larger); check the file", path);
    if (r == IC_OK && (size_t)size > allowed) {
        if (declared)
            r = ic_error_set(err, IC_ERR_PARSE,
                             "%s: %ld bytes, far more than its %" PRIu32 "x%" PRIu32 " pixels can need; the file is "
                             "damaged or carries very large metadata, re-save it",
                             path, size, w, h);
        else
            r = ic_error_set(err, IC_ERR_PARSE,
                             "%s: %ld bytes and no image size in its header; the file is damaged, re-save it", path,
                             size);
    }
    unsigned char *buf = r == IC_OK ? malloc((size_t)size + 1) : NULL;
    if (r == IC_OK && !buf)
        r = ic_error_set(err, IC_ERR_OOM, "%s: out of memory reading %ld bytes", path, size);
    if (r == IC_OK && fread(buf, 1, (size_t)size, f) != (size_t)size)
        r = ic_error_set(err, IC_ERR_IO, "%s: cannot read the image; check the file and its permissions", path);
    fclose(f);
    if (r != IC_OK) {
        free(buf);
        return r;
    }
    *out = buf;
    *n = (size_t)size;
    return IC_OK;
}

ic_result ic_image_read_ldr(const char *path, const ic_image_limit *lim, ic_image *out, ic_error *err)
{
    memset(out, 0, sizeof *out);
    size_t n = 0;
    unsigned char *bytes = NULL;
    ic_result r = read_ldr_file(path, lim, &bytes, &n, err);
    if (r != IC_OK)
        return r;
    r = ic_image_decode_ldr(bytes, n, path, lim, out, err);
    free(bytes);
    return r;
}

ic_result ic_image_decode_ldr(const unsigned char *bytes, size_t n, const char *name, const ic_image_limit *lim,
                              ic_image *out, ic_error *err)
{
    memset(out, 0, sizeof *out);
    /* SOI (T.81 §B.1.1.3): a JPEG; anything else is PNG or nothing stb_image can read. */
    if (n >= 2 && bytes[0] == 0xFF && bytes[1] == 0xD8)
        return ic_image_decode_jpeg(bytes, n, name, lim, out, err);
    if (n >= INT_MAX)
        return ic_error_set(err, IC_ERR_UNSUPPORTED, "%s: image of %zu bytes is too large to decode", name, n);
    size_t overrun = png_chunk_overrun(bytes, n);
    if (overrun)
        return ic_error_set(err, IC_ERR_PARSE, "%s: the PNG chunk at byte %zu declares %lu data bytes, but the file "
                            "ends %zu bytes after its header (data and a 4-byte CRC); the file is truncated or "
                            "damaged", name, overrun, (unsigned long)be32(bytes + overrun), n - overrun - 8);
    size_t bad = 0;
    int damaged = png_bad_chunk(bytes, n, &bad);
    if (damaged == 1) {
        char type[5] = {0};
        for (int k = 0; k < 4; ++k)
            type[k] = bytes[bad + 4 + k] >= 0x20 && bytes[bad + 4 + k] < 0x7f ? (char)bytes[bad + 4 + k] : '?';
        return ic_error_set(err, IC_ERR_CORRUPT, "%s: the PNG chunk '%s' at byte %zu fails its CRC check; the file is "
                            "damaged, re-create it", name, type, bad);
    }
    if (damaged == 2)
        return ic_error_set(err, IC_ERR_CORRUPT, "%s: the PNG ends after %zu bytes without its IEND chunk; the file is "
                            "truncated, re-create it", name, n);
    size_t m = 0;
    unsigned char *cleaned = png_without_empty_idat(bytes, n, &m);
    if (cleaned) {
        ic_result r = ic_image_decode_ldr(cleaned, m, name, lim, out, err);
        free(cleaned);
        return r;
    }
    int width = 0, height = 0, channels = 0, len = (int)n;
    if (!stbi_info_from_memory(bytes, len, &width, &height, &channels))
        return decode_failed(name, err);
    /* Validate the size before stb allocates for it; a 16-bit PNG is never bytes. */
    const int is_16_bit = stbi_is_16_bit_from_memory(bytes, len);
    ic_image_limit floats = {0, NULL, NULL};
    if (lim) {
        floats = *lim;
        floats.srgb8 = is_16_bit ? NULL : lim->srgb8;
    }
    ic_result r = ic_image_create_for_file(name, out, width, height, &floats, err);
    if (r != IC_OK)
        return r;
    const size_t count = (size_t)width * (size_t)height * 3;

    if (is_16_bit) {
        unsigned short *pixels = stbi_load_16_from_memory(bytes, len, &width, &height, &channels, 3);
        if (!pixels) {
            ic_image_free(out);
            return decode_failed(name, err);
        }
        for (size_t i = 0; i < count; ++i)
            out->rgb[i] = ic_srgb_to_linear((float)pixels[i] / 65535.0f);
        stbi_image_free(pixels);
    } else {
        unsigned char *pixels = stbi_load_from_memory(bytes, len, &width, &height, &channels, 3);
        if (!pixels) {
            ic_image_release(out, &floats);
            return decode_failed(name, err);
        }
        if (floats.srgb8) {
            memcpy(*floats.srgb8, pixels, count);
        } else {
            float to_linear[256];
            for (int v = 0; v < 256; ++v)
                to_linear[v] = ic_srgb8_to_linear((uint8_t)v);
            for (size_t i = 0; i < count; ++i)
                out->rgb[i] = to_linear[pixels[i]];
        }
        stbi_image_free(pixels);
    }
    return IC_OK;
}

static void put_be32(unsigned char *b, uint32_t v)
{
    b[0] = (unsigned char)(v >> 24);
    b[1] = (unsigned char)(v >> 16);
    b[2] = (unsigned char)(v >> 8);
    b[3] = (unsigned char)v;
}

/* The colour chunks of every PNG written, after IHDR (ISO/IEC 15948 §5.6: before IDAT): the bytes are sRGB
 * (the curve of IEC 61966-2-1 over Rec. 709 primaries, D65 white), so an sRGB chunk says so (rendering intent
 * 0, perceptual) and, for decoders that do not read it, the gAMA and cHRM chunks hold the values §11.3.3.5
 * prescribes beside it: gamma 45455 (1/2.2) and the sRGB chromaticities, times 100000. Without them a
 * reader is left to guess the colour space (stb_image_write writes none). cHRM, gAMA, sRGB: 73 bytes
 * into out. */
#define PNG_COLOUR_CHUNK_BYTES (12 + 32 + 12 + 4 + 12 + 1)
static void png_colour_chunks(unsigned char out[PNG_COLOUR_CHUNK_BYTES])
{
    static const uint32_t chrm[8] = {31270, 32900, 64000, 33000, 30000, 60000, 15000, 6000}; /* white, r, g, b */
    uint32_t table[256];
    png_crc_table(table);
    unsigned char *o = out;
    put_be32(o, 32);
    memcpy(o + 4, "cHRM", 4);
    for (int k = 0; k < 8; ++k)
        put_be32(o + 8 + 4 * k, chrm[k]);
    put_be32(o + 40, png_crc(table, o + 4, 36));
    o += 44;
    put_be32(o, 4);
    memcpy(o + 4, "gAMA", 4);
    put_be32(o + 8, 45455);
    put_be32(o + 12, png_crc(table, o + 4, 8));
    o += 16;
    put_be32(o, 1);
    memcpy(o + 4, "sRGB", 4);
    o[8] = 0;
    put_be32(o + 9, png_crc(table, o + 4, 5));
}

/* stb_image_write callback: append to the temporary file, the colour chunks after the signature and IHDR
 * (stb_image_write hands over the whole PNG at once); errors surface through ferror. */
static void write_to_file(void *context, void *data, int size)
{
    FILE *fp = context;
    const unsigned char *b = data;
    const size_t head = 8 + 12 + 13; /* the signature and IHDR (13 bytes of data) */
    if (size <= 0)
        return;
    if ((size_t)size > head && be32(b + 8) == 13 && memcmp(b + 12, "IHDR", 4) == 0) {
        unsigned char colour[PNG_COLOUR_CHUNK_BYTES];
        png_colour_chunks(colour);
        fwrite(b, 1, head, fp);
        fwrite(colour, 1, sizeof colour, fp);
        fwrite(b + head, 1, (size_t)size - head, fp);
    } else {
        fwrite(b, 1, (size_t)size, fp);
    }
}

ic_result ic_image_write_png8(const char *path, const uint8_t *rgb, int width, int height, ic_error *err)
{
    if (!path || !*path)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "empty output path; give a file name");
    /* stb_image_write sizes its buffers in int: a side of 0 overran them, a large one overflowed. */
    if (!rgb || !ic_image_size_allowed(width, height))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: a PNG of %d x %d%s; give 1 to %d pixels a side and at most %zu "
                            "in all", path, width, height, rgb ? "" : " with no pixels", IC_IMAGE_MAX_SIDE,
                            IC_IMAGE_MAX_PIXELS);
    ic_atomic_file f;
    ic_result r = ic_atomic_file_open(&f, path, err);
    if (r != IC_OK)
        return r;
    if (stbi_write_png_to_func(write_to_file, f.fp, width, height, 3, rgb, width * 3))
        return ic_atomic_file_commit(&f, err);
    ic_atomic_file_abort(&f);
    return ic_error_set(err, IC_ERR_OOM, "%s: PNG encoding failed (out of memory); free memory and retry", path);
}

ic_result ic_image_write_png(const char *path, const ic_image *img, float exposure, ic_error *err)
{
    const size_t count = (size_t)img->width * (size_t)img->height * 3;
    unsigned char *pixels = malloc(count);
    if (!pixels)
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory writing the image", path);
    const float scale = isfinite(exposure) ? exp2f(exposure) : 1.0f;
    for (size_t i = 0; i < count; ++i)
        pixels[i] = ic_linear_to_srgb8(img->rgb[i] * scale);
    ic_result r = ic_image_write_png8(path, pixels, img->width, img->height, err);
    free(pixels);
    return r;
}
