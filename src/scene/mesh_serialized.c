/*
 * mesh_serialized.c — Mitsuba's "serialized" mesh files (the binary meshes of Mitsuba 0.6 scenes).
 *
 * What the format holds (Mitsuba 0.6's documentation of the serialized shape): a file is a series of
 * shapes, each a little-endian u16 magic 0x041C and u16 version (3 or 4), then one zlib stream holding
 *   u32 flags (0x0001 vertex normals, 0x0002 texture coordinates, 0x0008 vertex colours, 0x0010 face
 *       normals wanted, 0x1000 single precision, 0x2000 double precision);
 *   (version 4) the shape's name, a NUL-terminated string;
 *   u64 vertex count V, u64 triangle count T;
 *   V positions (3 floats or doubles), then if flagged V normals, V texture coordinates (2), V colours (3);
 *   T triangles, 3 u32 indices each (u64 when V does not fit 32 bits).
 * A file of several shapes ends with a table: each shape's byte offset (u64 in version 4, u32 in version
 * 3), then the u32 shape count. Shape 0 starts at offset 0 in every file.
 *
 * What is read: positions, vertex normals (unless face normals are asked for), triangles. Texture
 * coordinates and colours are skipped. Every count and index is checked against the bytes there are and
 * against the scene's element limit before anything is allocated for it; every position and every normal
 * read must be finite.
 */
#include "scene/scene_internal.h"

#include "core/read_file.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

enum {
    SER_MAGIC = 0x041C,
    SER_NORMALS = 0x0001,
    SER_TEXCOORDS = 0x0002,
    SER_COLOURS = 0x0008,
    SER_FACE_NORMALS = 0x0010,
    SER_DOUBLE = 0x2000
};

static uint64_t get_le(const unsigned char *b, int bytes)
{
    uint64_t v = 0;
    for (int k = bytes - 1; k >= 0; --k)
        v = v << 8 | b[k];
    return v;
}

/* The byte offset of shape `index` (0: the start) from the table at the file's end. */
static ic_result shape_offset(const unsigned char *d, size_t size, unsigned version, uint32_t index, uint64_t *at,
                              const char *where, const char *path, ic_error *err)
{
    *at = 0;
    if (index == 0)
        return IC_OK;
    uint64_t count = size >= 4 ? get_le(d + size - 4, 4) : 0, entry = version >= 4 ? 8 : 4;
    /* A table is there when it fits and names offset 0 for shape 0. */
    if (count == 0 || count > (size - 4) / entry || get_le(d + size - 4 - entry * count, (int)entry) != 0)
        return ic_error_set(err, IC_ERR_PARSE, "%s: the serialized file '%s' has no table of shapes at its end "
                            "(truncated or corrupt), so shapeIndex %u cannot be found; export it again", where,
                            path, index);
    if (index >= count)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: shapeIndex %u, but the serialized file '%s' holds %llu "
                            "shape%s; use an index below that", where, index, path, (unsigned long long)count,
                            count == 1 ? "" : "s");
    *at = get_le(d + size - 4 - entry * (count - index), (int)entry);
    if (*at > size - 4)
        return ic_error_set(err, IC_ERR_PARSE, "%s: the serialized file '%s' is corrupt (shape %u starts past its "
                            "end); export it again", where, path, index);
    return IC_OK;
}

/* Inflates the zlib stream at src into a buffer of at most limit bytes (*out, malloc'd; *len its length). */
static ic_result inflate_shape(const unsigned char *src, size_t src_len, size_t limit, unsigned char **out,
                               size_t *len, const char *where, const char *path, ic_error *err)
{
    z_stream zs;
    memset(&zs, 0, sizeof zs);
    if (inflateInit(&zs) != Z_OK)
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory inflating '%s'", where, path);
    size_t cap = 1 << 16, n = 0;
    unsigned char *buf = malloc(cap);
    int rc = buf ? Z_OK : Z_MEM_ERROR;
    zs.next_in = (unsigned char *)src;
    while (rc == Z_OK) {
        if (n == cap) {
            size_t grow = cap * 2 > limit ? limit : cap * 2;
            unsigned char *b2 = grow > cap ? realloc(buf, grow) : NULL;
            if (!b2) {
                rc = grow > cap ? Z_MEM_ERROR : Z_BUF_ERROR;
                break;
            }
            buf = b2;
            cap = grow;
        }
        uInt in_chunk = src_len - (size_t)(zs.next_in - src) > (1u << 30) ? (1u << 30)
                                                                           : (uInt)(src_len - (size_t)(zs.next_in - src));
        zs.avail_in = in_chunk;
        zs.next_out = buf + n;
        zs.avail_out = (uInt)(cap - n);
        rc = inflate(&zs, Z_NO_FLUSH);
        n = cap - zs.avail_out;
        if (rc == Z_OK && zs.avail_in == 0 && zs.avail_out > 0)
            rc = Z_DATA_ERROR; /* input ended inside the stream */
    }
    inflateEnd(&zs);
    if (rc != Z_STREAM_END) {
        free(buf);
        if (rc == Z_MEM_ERROR)
            return ic_error_set(err, IC_ERR_OOM, "%s: out of memory inflating '%s'", where, path);
        if (rc == Z_BUF_ERROR)
            return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: the serialized mesh '%s' inflates beyond %zu bytes, "
                                "more than --max-mesh-elements allows; raise it if the mesh is meant to be that "
                                "large", where, path, limit);
        return ic_error_set(err, IC_ERR_PARSE, "%s: the serialized mesh '%s' is corrupt or truncated (zlib: %s); "
                            "export it again", where, path, zs.msg ? zs.msg : "stream ends early");
    }
    *out = buf;
    *len = n;
    return IC_OK;
}

/* Reads the inflated shape (d, len) into positions, normals and triangles and appends them. */
static ic_result append_shape(ic_scene_builder *b, const unsigned char *d, size_t len, unsigned version,
                              uint32_t material, const float xform[16], size_t max_elements, const char *where,
                              const char *path, ic_error *err)
{
    size_t at = 4;
    if (len < 4)
        goto truncated;
    uint32_t flags = (uint32_t)get_le(d, 4);
    if (version >= 4) {
        const unsigned char *nul = memchr(d + at, 0, len - at);
        if (!nul)
            goto truncated;
        at = (size_t)(nul - d) + 1;
    }
    if (len - at < 16)
        goto truncated;
    uint64_t nv = get_le(d + at, 8), nt = get_le(d + at + 8, 8);
    at += 16;
    if (nv > max_elements || nt > max_elements || nv > UINT32_MAX || nt > UINT32_MAX / 3)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: the serialized mesh '%s' has %llu vertices and %llu "
                            "triangles, more than --max-mesh-elements (%zu) allows; raise it if the mesh is meant "
                            "to be that large", where, path, (unsigned long long)nv, (unsigned long long)nt,
                            max_elements);
    const int real = flags & SER_DOUBLE ? 8 : 4, index_bytes = 4;
    const uint64_t per_vertex = (uint64_t)real * (3 + (flags & SER_NORMALS ? 3 : 0) + (flags & SER_TEXCOORDS ? 2 : 0) +
                                                  (flags & SER_COLOURS ? 3 : 0));
    if ((len - at) / (per_vertex ? per_vertex : 1) < nv || (len - at - nv * per_vertex) / (3 * index_bytes) < nt)
        goto truncated;
    ic_vec3 *p = malloc(sizeof *p * (nv ? nv : 1) * 2), *n = p ? p + (nv ? nv : 1) : NULL;
    uint32_t *tri = malloc(sizeof *tri * 3 * (nt ? nt : 1));
    if (!p || !tri) {
        free(p);
        free(tri);
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory for the serialized mesh '%s'", where, path);
    }
    ic_result r = IC_OK;
    /* Face normals asked for: the geometric normal (no vertex normals). */
    int use_normals = (flags & SER_NORMALS) && !(flags & SER_FACE_NORMALS);
    for (int block = 0; block < 2 && r == IC_OK; ++block) { /* positions, then normals */
        if (block == 1 && !(flags & SER_NORMALS))
            break;
        ic_vec3 *dst = block ? n : p;
        for (uint64_t i = 0; i < nv && r == IC_OK; ++i, at += 3 * (size_t)real) {
            float f[3];
            for (int k = 0; k < 3; ++k) {
                uint64_t bits = get_le(d + at + (size_t)k * real, real);
                if (real == 8) {
                    double v;
                    memcpy(&v, &bits, 8);
                    f[k] = (float)v;
                } else {
                    uint32_t b32 = (uint32_t)bits;
                    memcpy(&f[k], &b32, 4);
                }
            }
            dst[i] = v3(f[0], f[1], f[2]);
            /* a NaN normal would give NaN shading samples (black pixels once the film drops them) */
            if ((block == 0 || use_normals) && !(isfinite(f[0]) && isfinite(f[1]) && isfinite(f[2])))
                r = ic_error_set(err, IC_ERR_PARSE, "%s: the serialized mesh '%s' has a non-finite %s at vertex %llu; "
                                 "fix or remove it", where, path, block ? "normal" : "coordinate",
                                 (unsigned long long)i + 1);
        }
    }
    at += nv * (uint64_t)real * ((flags & SER_TEXCOORDS ? 2 : 0) + (flags & SER_COLOURS ? 3 : 0));
    for (uint64_t t = 0; t < 3 * nt && r == IC_OK; ++t, at += index_bytes) {
        uint64_t v = get_le(d + at, index_bytes);
        if (v >= nv)
            r = ic_error_set(err, IC_ERR_PARSE, "%s: the serialized mesh '%s' has triangle %llu using vertex %llu of "
                             "%llu; the file is corrupt: export it again", where, path, (unsigned long long)(t / 3),
                             (unsigned long long)v, (unsigned long long)nv);
        tri[t] = (uint32_t)v;
    }
    if (r == IC_OK)
        r = ic_scene_append_triangles(b, p, use_normals ? n : NULL, (uint32_t)nv, tri, (uint32_t)nt, material, xform,
                                      where, err);
    free(p);
    free(tri);
    return r;
truncated:
    return ic_error_set(err, IC_ERR_PARSE, "%s: the serialized mesh '%s' is truncated (its counts need more bytes "
                        "than it has); export it again", where, path);
}

ic_result ic_mesh_read_serialized(ic_scene_builder *b, const char *path, uint32_t shape_index, uint32_t material,
                                  const float xform[16], const char *where, ic_error *err)
{
    size_t max_elements = ic_scene_max_mesh_elements(b->opt);
    /* A file's bytes: at most 128 per element (a vertex in doubles with normals, texture coordinates and
     * colours takes 88, a triangle 12), plus headers. */
    uint64_t max_bytes = (uint64_t)max_elements * 128u + 4096u;
    char *data = NULL;
    size_t size = 0;
    char hint[128];
    snprintf(hint, sizeof hint, "raise --max-mesh-elements if the mesh is meant to be that large");
    ic_result r = ic_read_regular_file(path, "serialized mesh", max_bytes, hint, &data, &size, NULL, err);
    if (r != IC_OK)
        return r;
    const unsigned char *d = (const unsigned char *)data;
    uint64_t at = 0;
    unsigned version = size >= 4 ? (unsigned)get_le(d + 2, 2) : 0;
    if (size < 4 || get_le(d, 2) != SER_MAGIC || (version != 3 && version != 4))
        r = ic_error_set(err, IC_ERR_PARSE, "%s: '%s' is not a Mitsuba serialized mesh (version 3 or 4)", where, path);
    if (r == IC_OK)
        r = shape_offset(d, size, version, shape_index, &at, where, path, err);
    if (r == IC_OK && (size - at < 4 || get_le(d + at, 2) != SER_MAGIC || get_le(d + at + 2, 2) != version))
        r = ic_error_set(err, IC_ERR_PARSE, "%s: the serialized file '%s' is corrupt (no shape header at shape %u); "
                         "export it again", where, path, shape_index);
    unsigned char *shape = NULL;
    size_t len = 0;
    if (r == IC_OK)
        r = inflate_shape(d + at + 4, size - at - 4, (size_t)max_bytes, &shape, &len, where, path, err);
    if (r == IC_OK)
        r = append_shape(b, shape, len, version, material, xform, max_elements, where, path, err);
    free(shape);
    free(data);
    return r;
}
