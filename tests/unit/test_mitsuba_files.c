/*
 * test_mitsuba_files.c — what a Mitsuba scene reads from other files. Serialized meshes (<shape
 * type="serialized">), written here with zlib in the layout Mitsuba 0.6 documents:
 *   1. a version-4 file of two shapes (a single-precision quad; a double-precision box with normals,
 *      texture coordinates and colours to skip) and its table of offsets: shapeIndex picks each, the
 *      transform applies, every vertex lands where it should;
 *   2. a version-3 file (u32 offsets, no names) reads alike;
 *   3. bad input gives one-line errors naming the XML file:line and what to do: a shapeIndex beyond the
 *      file's shapes, a file cut short (its table lost; a shape's stream cut), an index past the vertices,
 *      a file that is not serialized.
 * And <include>: 4. an included file's shapes, BSDFs (referenced by id from the including file) and
 *    defaults apply, and messages about its elements name it and its line; a file that includes itself
 *    stops at the depth limit with a one-line error; a missing included file names the <include>'s line.
 */
#include "test_util.h"
#include "test_files.h"
#include "test_render_util.h"

#include "scene/scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

typedef struct buf {
    unsigned char *d;
    size_t n, cap;
} buf;

static void put(buf *b, const void *p, size_t n)
{
    if (b->n + n > b->cap) {
        b->cap = (b->n + n) * 2 + 256;
        b->d = realloc(b->d, b->cap);
    }
    memcpy(b->d + b->n, p, n);
    b->n += n;
}
static void put_u16(buf *b, uint16_t v) { unsigned char c[2] = {(unsigned char)v, (unsigned char)(v >> 8)}; put(b, c, 2); }
static void put_u32(buf *b, uint32_t v)
{
    unsigned char c[4];
    for (int k = 0; k < 4; ++k)
        c[k] = (unsigned char)(v >> (8 * k));
    put(b, c, 4);
}
static void put_u64(buf *b, uint64_t v)
{
    put_u32(b, (uint32_t)v);
    put_u32(b, (uint32_t)(v >> 32));
}
static void put_f32(buf *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put_u32(b, u);
}
static void put_f64(buf *b, double f)
{
    uint64_t u;
    memcpy(&u, &f, 8);
    put_u64(b, u);
}

/* The box [0,1]³ as 8 vertices and 12 triangles; the quad [0,1]² at z = 0 as 4 and 2. */
static const float box_v[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
static const uint32_t box_t[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                      {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};

/* One shape: header, then its zlib stream. version 4 writes a name; box: doubles, normals, uv, colours.
 * bad_index: a vertex index for the box's second triangle; nan_normal: vertex 3's normal x is NaN. */
static void put_shape(buf *file, unsigned version, int box, uint32_t bad_index, int nan_normal)
{
    buf raw = {0};
    uint32_t flags = box ? 0x2000 | 0x0001 | 0x0002 | 0x0008 : 0x1000;
    put_u32(&raw, flags);
    if (version >= 4)
        put(&raw, box ? "box" : "quad", box ? 4 : 5);
    uint64_t nv = box ? 8 : 4, nt = box ? 12 : 2;
    put_u64(&raw, nv);
    put_u64(&raw, nt);
    for (uint64_t i = 0; i < nv; ++i)
        for (int k = 0; k < 3; ++k) {
            if (box)
                put_f64(&raw, box_v[i][k]);
            else
                put_f32(&raw, k == 2 ? 0.0f : box_v[i][k]);
        }
    if (box) {
        for (uint64_t i = 0; i < nv; ++i) /* normals: outward-ish, unit */
            for (int k = 0; k < 3; ++k)
                put_f64(&raw, nan_normal && i == 2 && k == 0 ? NAN : (box_v[i][k] - 0.5) / (0.5 * sqrt(3.0)));
        for (uint64_t i = 0; i < nv; ++i)
            for (int k = 0; k < 2; ++k)
                put_f64(&raw, 0.25 * (double)k);
        for (uint64_t i = 0; i < nv; ++i)
            for (int k = 0; k < 3; ++k)
                put_f64(&raw, 0.5);
    }
    for (uint64_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k)
            put_u32(&raw, t == 1 && k == 2 && bad_index ? bad_index : box ? box_t[t][k] : (uint32_t[]){0, 1, 2, 0, 2, 3}[3 * t + k]);
    uLongf zn = compressBound(raw.n);
    unsigned char *z = malloc(zn);
    compress2(z, &zn, raw.d, raw.n, 6);
    put_u16(file, 0x041C);
    put_u16(file, (uint16_t)version);
    put(file, z, zn);
    free(z);
    free(raw.d);
}

/* A file of the quad then the box, with the table of offsets; its bytes to path (truncated to `keep` if
 * non-zero). */
static void write_serialized(const char *path, unsigned version, uint32_t bad_index, int nan_normal, size_t keep)
{
    buf f = {0};
    uint64_t off[2];
    off[0] = f.n;
    put_shape(&f, version, 0, 0, 0);
    off[1] = f.n;
    put_shape(&f, version, 1, bad_index, nan_normal);
    for (int k = 0; k < 2; ++k) {
        if (version >= 4)
            put_u64(&f, off[k]);
        else
            put_u32(&f, (uint32_t)off[k]);
    }
    put_u32(&f, 2);
    FILE *fp = fopen(path, "wb");
    if (fp) {
        fwrite(f.d, 1, keep ? keep : f.n, fp);
        fclose(fp);
    }
    free(f.d);
}

static ic_result load_shape(const char *mesh, int shape_index, ic_scene **s, ic_error *err)
{
    char xml[1024];
    snprintf(xml, sizeof xml,
             "<scene version=\"0.6.0\">\n"
             "  <shape type=\"serialized\">\n"
             "    <string name=\"filename\" value=\"%s\"/>\n"
             "    <integer name=\"shapeIndex\" value=\"%d\"/>\n"
             "    <transform name=\"toWorld\"><scale value=\"2\"/><translate x=\"10\"/></transform>\n"
             "  </shape>\n"
             "</scene>\n",
             mesh, shape_index);
    *s = NULL;
    if (!test_write_text(IC_TEST_TMP "/ser.xml", xml))
        return IC_ERR_IO;
    return test_load_scene(IC_TEST_TMP "/ser.xml", NULL, 0, 0, 1, s, err);
}

/* Every vertex of the loaded shape is 2·v + (10, 0, 0) for a vertex v of the expected shape. */
static void check_shape(const ic_scene *s, int box, const char *what)
{
    uint32_t want = box ? 12 : 2, off = 0;
    CHECK(s->triangle_count == want, "%s: %u triangles, expected %u", what, s->triangle_count, want);
    for (uint32_t t = 0; t < s->triangle_count; ++t)
        for (int k = 0; k < 3; ++k) {
            ic_vec3 p = s->positions[s->triangles[3 * t + k]];
            float x = (p.x - 10.0f) / 2.0f, y = p.y / 2.0f, z = p.z / 2.0f;
            int on_grid = fabsf(x - roundf(x)) < 1e-6f && fabsf(y - roundf(y)) < 1e-6f && fabsf(z - roundf(z)) < 1e-6f;
            off += !on_grid || x < -1e-6f || x > 1.000001f || (!box && z != 0.0f);
        }
    CHECK(off == 0, "%s: %u vertices not where the transform puts the file's", what, off);
    CHECK(!box || s->normals, "%s: the file's vertex normals are used", what);
}

static void test_include(void)
{
    test_write_text(IC_TEST_TMP "/inc_materials.xml",
               "<scene version=\"0.6.0\">\n"
               "  <default name=\"refl\" value=\"0.25\"/>\n"
               "  <bsdf type=\"diffuse\" id=\"grey\"><float name=\"reflectance\" value=\"$refl\"/></bsdf>\n"
               "  <shape type=\"rectangle\"><transform name=\"toWorld\"><translate z=\"-3\"/></transform></shape>\n"
               "  <shape type=\"hair\"/>\n"
               "</scene>\n");
    test_write_text(IC_TEST_TMP "/inc_main.xml",
               "<scene version=\"0.6.0\">\n"
               "  <include filename=\"inc_materials.xml\"/>\n"
               "  <shape type=\"cube\"><ref id=\"grey\"/></shape>\n"
               "</scene>\n");
    ic_error err = {0};
    ic_scene *s = NULL;
    CHECK(test_load_scene(IC_TEST_TMP "/inc_main.xml", NULL, 0, 0, 1, &s, &err) == IC_OK,
          "a scene with an include loads: %s", err.message);
    if (s) {
        CHECK(s->triangle_count == 12 + 2, "the included rectangle and the cube: %u triangles", s->triangle_count);
        int grey = 0, below = 0;
        for (uint32_t t = 0; t < s->triangle_count; ++t) {
            grey += s->materials[s->triangle_material[t]].kd.x == 0.25f;
            below += s->positions[s->triangles[3 * t]].z == -3.0f;
        }
        CHECK(grey == 12 && below == 2, "the cube takes the included BSDF with the included default (%d), the "
              "rectangle its transform (%d)", grey, below);
        const char *w = ic_scene_warnings(s);
        CHECK(strstr(w, "inc_materials.xml:5:") && strstr(w, "hair"), "a warning names the included file's line: %s", w);
        ic_scene_free(s);
    }
    test_write_text(IC_TEST_TMP "/inc_self.xml", "<scene version=\"0.6.0\">\n  <include filename=\"inc_self.xml\"/>\n</scene>\n");
    s = NULL;
    ic_result r = test_load_scene(IC_TEST_TMP "/inc_self.xml", NULL, 0, 0, 1, &s, &err);
    CHECK(r != IC_OK && strstr(err.message, "inc_self.xml:2") && strstr(err.message, "nest too deep") &&
              !strchr(err.message, '\n'), "a file including itself stops: %s", err.message);
    ic_scene_free(s);
    test_write_text(IC_TEST_TMP "/inc_missing.xml", "<scene version=\"0.6.0\">\n\n  <include filename=\"nowhere.xml\"/>\n</scene>\n");
    s = NULL;
    r = test_load_scene(IC_TEST_TMP "/inc_missing.xml", NULL, 0, 0, 1, &s, &err);
    CHECK(r == IC_ERR_IO && strstr(err.message, "inc_missing.xml:3") && strstr(err.message, "nowhere.xml"),
          "a missing included file: %s", err.message);
    ic_scene_free(s);
}

int main(void)
{
    test_include();
    const char *path = IC_TEST_TMP "/ser_v4.serialized";
    write_serialized(path, 4, 0, 0, 0);
    ic_error err = {0};
    ic_scene *s = NULL;
    for (int shape = 0; shape < 2; ++shape) {
        CHECK(load_shape(path, shape, &s, &err) == IC_OK, "version 4, shape %d loads: %s", shape, err.message);
        if (s)
            check_shape(s, shape, shape ? "version 4, the box" : "version 4, the quad");
        ic_scene_free(s);
    }
    write_serialized(IC_TEST_TMP "/ser_v3.serialized", 3, 0, 0, 0);
    CHECK(load_shape(IC_TEST_TMP "/ser_v3.serialized", 1, &s, &err) == IC_OK, "version 3 loads: %s", err.message);
    if (s)
        check_shape(s, 1, "version 3, the box");
    ic_scene_free(s);

    /* Bad input: one line, naming ser.xml:2 (the shape) and what to do. */
    struct {
        const char *file;
        int shape;
        const char *says;
    } bad[6] = {{path, 2, "holds 2 shapes"},
                {IC_TEST_TMP "/ser_trunc.serialized", 1, "no table of shapes"},
                {IC_TEST_TMP "/ser_cut.serialized", 0, "corrupt or truncated"},
                {IC_TEST_TMP "/ser_index.serialized", 1, "vertex 99 of 8"},
                {IC_TEST_TMP "/ser.xml", 0, "not a Mitsuba serialized mesh"},
                /* a NaN normal would make NaN shading samples: refused as a NaN position is */
                {IC_TEST_TMP "/ser_nan_normal.serialized", 1, "has a non-finite normal at vertex 3; fix or remove it"}};
    FILE *fp = fopen(path, "rb");
    long full = 0;
    if (fp) {
        fseek(fp, 0, SEEK_END);
        full = ftell(fp);
        fclose(fp);
    }
    write_serialized(bad[1].file, 4, 0, 0, (size_t)full - 40); /* the box's stream cut short, table gone */
    write_serialized(bad[2].file, 4, 0, 0, 20); /* the quad's own stream cut short */
    write_serialized(bad[3].file, 4, 99, 0, 0);
    write_serialized(bad[5].file, 4, 0, 1, 0);
    for (int k = 0; k < 6; ++k) {
        ic_result r = load_shape(bad[k].file, bad[k].shape, &s, &err);
        CHECK(r != IC_OK && strstr(err.message, "ser.xml:2") && strstr(err.message, bad[k].says) &&
                  !strchr(err.message, '\n'),
              "bad serialized input %d refused with a one-line message naming the shape: %s", k, err.message);
        ic_scene_free(s);
    }
    TEST_MAIN_END();
}
