/*
 * glb_check.c — the framing of a binary glTF file checked before it is imported (Khronos glTF 2.0
 * specification §4.4, "GLB File Format Specification"): a 12-byte header (magic "glTF", version 2, the
 * total length) and chunks of an 8-byte header (length, type) and their data, the first one JSON. The
 * importer allocates what the lengths declare before it reads anything, so a 516-byte file declaring a
 * 2.8 GB JSON chunk (found by the mesh_glb fuzz target) allocated 2.8 GB; here every length is checked
 * against the bytes the file really holds.
 */
#include "scene_internal.h"

#include <stdint.h>
#include <string.h>

static uint32_t le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

ic_result ic_glb_check(FILE *fp, const char *path, ic_error *err)
{
    unsigned char h[12];
    if (fseek(fp, 0, SEEK_END) != 0)
        return IC_OK; /* not seekable: the importer reports what it finds */
    long size = ftell(fp);
    if (size < 0 || fseek(fp, 0, SEEK_SET) != 0 || fread(h, 1, sizeof h, fp) != sizeof h || memcmp(h, "glTF", 4))
        return IC_OK; /* too short or not binary glTF: the importer reports what it is */
    uint32_t total = le32(h + 8);
    if (le32(h + 4) != 2)
        return ic_error_set(err, IC_ERR_PARSE, "%s: binary glTF version %u; only version 2 is read (export it as "
                            "glTF 2.0)", path, le32(h + 4));
    if (total > (uint64_t)size)
        return ic_error_set(err, IC_ERR_PARSE, "%s: the binary glTF header declares %u bytes but the file holds %ld; "
                            "the file is truncated or corrupt: export it again", path, total, size);
    for (uint64_t at = 12; at + 8 <= total;) {
        unsigned char c[8];
        if (fseek(fp, (long)at, SEEK_SET) != 0 || fread(c, 1, sizeof c, fp) != sizeof c)
            return ic_error_set(err, IC_ERR_PARSE, "%s: cannot read the chunk header at byte %llu; export the file "
                                "again", path, (unsigned long long)at);
        uint64_t len = le32(c);
        if (at == 12 && memcmp(c + 4, "JSON", 4))
            return ic_error_set(err, IC_ERR_PARSE, "%s: the first chunk of a binary glTF must be JSON; export the "
                                "file again", path);
        if (at + 8 + len > total)
            return ic_error_set(err, IC_ERR_PARSE, "%s: the chunk at byte %llu declares %llu bytes, past the file's "
                                "%u; the file is truncated or corrupt: export it again", path,
                                (unsigned long long)at, (unsigned long long)len, total);
        at += 8 + len;
    }
    return IC_OK;
}
