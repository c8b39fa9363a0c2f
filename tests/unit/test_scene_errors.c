/*
 * test_scene_errors.c — every class of bad scene input gives the right ic_result and a one-line message
 * that names the file, the line (JSON and OBJ) and what to do; *out stays NULL and nothing leaks.
 */
#include "core/rng.h"
#include "irrcache/image.h"
#include "scene/mesh_check.h"
#include "scene/scene.h"
#include "test_render_util.h"
#include "test_util.h"

#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <string.h>
#include <strings.h>
#ifdef IC_TEST_WRAP_ASSIMP
#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#endif
#include <sys/stat.h>
#include <unistd.h>

#define SCENES IC_SOURCE_DIR "/tests/scenes/"

/* Loads path and checks the result code and that the message contains each of up to three strings. */
static void expect_error(const char *path, const ic_scene_load_options *opt, ic_result code, const char *s1,
                         const char *s2, const char *s3)
{
    ic_scene *scene = (ic_scene *)&scene; /* non-NULL: the loader must reset it */
    ic_error err;
    memset(&err, 0, sizeof err);
    ic_result r = ic_scene_load(path, opt, &scene, &err);
    CHECK(r == code, "%s: expected %s, got %s (%s)", path, ic_result_name(code), ic_result_name(r), err.message);
    CHECK(err.code == r, "%s: err.code matches", path);
    CHECK(scene == NULL, "%s: *out is NULL on failure", path);
    const char *want[3] = {s1, s2, s3};
    for (int i = 0; i < 3; ++i)
        if (want[i])
            CHECK(strstr(err.message, want[i]) != NULL, "%s: message lacks '%s': %s", path, want[i], err.message);
    CHECK(strchr(err.message, '\n') == NULL, "%s: one line", path);
    CHECK(strstr(err.message, "; ") != NULL, "%s: says what to do: %s", path, err.message);
    if (r == IC_OK)
        ic_scene_free(scene);
}

/* Binary glTF files whose lengths claim more than they hold: refused before the importer allocates what
 * they declare (the fuzz target's 516-byte file declared a 2.8 GB chunk). */
static void test_glb_lengths(void)
{
    static const char json[] = "{\"asset\":{\"version\":\"2.0\"}}    "; /* 32 bytes, 4-aligned */
    unsigned char b[12 + 8 + 32];
    uint32_t total = sizeof b, jlen = 32;
    memcpy(b, "glTF", 4);
    uint32_t v[2] = {2, total};
    memcpy(b + 4, v, 8); /* little-endian host, as the format */
    memcpy(b + 12, &jlen, 4);
    memcpy(b + 16, "JSON", 4);
    memcpy(b + 20, json, 32);
    const char *path = IC_TEST_TMP "/chunk_overrun.glb";
    /* A chunk longer than the file. */
    uint32_t huge = 0xab0003b0u;
    memcpy(b + 12, &huge, 4);
    FILE *f = fopen(path, "wb");
    CHECK(f && fwrite(b, 1, sizeof b, f) == sizeof b, "write %s", path);
    if (f)
        fclose(f);
    expect_error(path, NULL, IC_ERR_PARSE, "chunk_overrun.glb", "declares", "past the file");
    /* A header whose total length is 0: the chunks are still checked (a 4 GB JSON chunk went through). */
    expect_error(IC_SOURCE_DIR "/tests/fuzz/regress/mesh_glb/assimp_4gb_alloc_total_0.glb", NULL, IC_ERR_PARSE,
                 "assimp_4gb_alloc_total_0.glb: the binary glTF header declares 0 bytes, too few", NULL, NULL);
    /* A header that declares more than the file holds (the fuzz target's input). */
    expect_error(IC_SOURCE_DIR "/tests/fuzz/regress/mesh_glb/assimp_2_8gb_alloc.glb", NULL, IC_ERR_PARSE,
                 "assimp_2_8gb_alloc.glb", "declares 1016 bytes", "holds 516");
}

/* Writes text (len bytes; -1: up to its NUL) into the test folder under name; returns the path. */
static const char *write_tmp(const char *name, const char *text, long len)
{
    static char path[1024];
    snprintf(path, sizeof path, "%s/%s", IC_TEST_TMP, name);
    FILE *fp = fopen(path, "wb");
    size_t n = len < 0 ? strlen(text) : (size_t)len;
    CHECK(fp && fwrite(text, 1, n, fp) == n, "write %s", path);
    if (fp)
        fclose(fp);
    return path;
}

#define REGRESS IC_SOURCE_DIR "/tests/fuzz/regress/"

#ifdef IC_TEST_WRAP_ASSIMP
/* The library's calls of aiApplyPostProcessing come here (linked with --wrap, tests/CMakeLists.txt). With
 * fail_tangents set, the tangent step fails the way assimp's steps fail when one throws (the tangent step
 * throws only when memory runs out, so no file provokes it): the scene released, NULL returned, and
 * aiGetErrorString() left as the last failed import left it. */
const struct aiScene *__real_aiApplyPostProcessing(const struct aiScene *scene, unsigned int flags);
static int fail_tangents, tangent_steps;

const struct aiScene *__wrap_aiApplyPostProcessing(const struct aiScene *scene, unsigned int flags)
{
    if (flags & aiProcess_CalcTangentSpace) {
        ++tangent_steps;
        if (fail_tangents) {
            aiReleaseImport(scene);
            return NULL;
        }
    }
    return __real_aiApplyPostProcessing(scene, flags);
}

/* A failed tangent step is reported with the file and the step, not with the text of an earlier failed
 * import (here one of bytes assimp cannot read) that aiGetErrorString() still holds. */
static void test_tangent_step_fails(void)
{
    CHECK(aiImportFileFromMemory("not a mesh", 10, 0, "xyz") == NULL && aiGetErrorString()[0],
          "an import that fails leaves its text in aiGetErrorString()");
    char stale[256];
    snprintf(stale, sizeof stale, "%s", aiGetErrorString());
    char pfm[24] = "PF\n1 1\n-1.0\n"; /* a flat normal map: one texel (0.5, 0.5, 1), little-endian */
    memcpy(pfm + 12, (const float[3]){0.5f, 0.5f, 1.0f}, 12);
    write_tmp("tangents_n.pfm", pfm, sizeof pfm);
    write_tmp("tangents.mtl", "newmtl m\nKd 0.5 0.5 0.5\nnorm tangents_n.pfm\n", -1);
    const char *obj = write_tmp("tangents.obj",
                                "mtllib tangents.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\n"
                                "vn 0 0 1\nusemtl m\nf 1/1/1 2/2/1 3/3/1\n",
                                -1);
    ic_scene *s = NULL;
    ic_error err = {0};
    CHECK(ic_scene_load(obj, NULL, &s, &err) == IC_OK && tangent_steps == 1,
          "the normal-mapped mesh loads through the tangent step (%d): %s", tangent_steps, err.message);
    ic_scene_free(s);
    fail_tangents = 1;
    expect_error(obj, NULL, IC_ERR_OOM, "tangents.obj: out of memory computing the tangents",
                 "CalcTangentSpace step failed", "remove the normal maps");
    fail_tangents = 0;
    CHECK(tangent_steps == 2, "the failing load ran the tangent step (%d)", tangent_steps);
    memset(&err, 0, sizeof err);
    fail_tangents = 1;
    CHECK(ic_scene_load(obj, NULL, &s, &err) != IC_OK && !strstr(err.message, stale),
          "no stale assimp text ('%s'): %s", stale, err.message);
    fail_tangents = 0;
}
#endif

/* Mesh files that crashed, hung or leaked inside assimp 5.2.5 (found by the fuzz targets): refused by the
 * loader's structure checks before assimp sees them, with the file, the line or element and what to do. */
static void test_hostile_meshes(void)
{
    static const char ply_head[] = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                   "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                   "end_header\n";
    char text[1024];
    /* The fuzz inputs themselves: each names its cause. */
    expect_error(REGRESS "mesh_ply/assimp_segv_1efa1f.ply", NULL, IC_ERR_PARSE, "assimp_segv_1efa1f.ply: face 1 names "
                 "vertex 1886157066, but the file has 3 vertices", "fix the face", NULL);
    expect_error(REGRESS "mesh_ply/assimp_segv_208342.ply", NULL, IC_ERR_PARSE, "assimp_segv_208342.ply: the data "
                 "ends in element 'face' 2 of 2 (binary)", "truncated", NULL);
    expect_error(REGRESS "mesh_ply/assimp_segv_3c89c0.ply", NULL, IC_ERR_PARSE, "assimp_segv_3c89c0.ply:1: the first "
                 "line of a PLY file must be exactly 'ply'", NULL, NULL);
    expect_error(REGRESS "mesh_ply/assimp_timeout.ply", NULL, IC_ERR_PARSE, "assimp_timeout.ply:1: the first line",
                 NULL, NULL);
    expect_error(REGRESS "mesh_ply/assimp_leak.ply", NULL, IC_ERR_PARSE, "assimp_leak.ply:7: the PLY header holds "
                 "the byte 0x02", "export the mesh again", NULL);
    /* Where assimp reads a PLY otherwise than its grammar says: one \n after end_header skipped (the check
     * now reads the body from there too, so the face's count is the 0 that assimp read: it aborted), an
     * element name of digits taken as the element's count (34 GB), a lone \r ending a header line. */
    expect_error(REGRESS "mesh_ply/assimp_abort_blank_line_after_header.ply", NULL, IC_ERR_PARSE,
                 "assimp_abort_blank_line_after_header.ply: face 1 has a list 'vertex_indices' of 0 items", NULL, NULL);
    expect_error(REGRESS "mesh_ply/assimp_34gb_alloc_digit_element.ply", NULL, IC_ERR_UNSUPPORTED,
                 "assimp_34gb_alloc_digit_element.ply: PLY element '3333", "is not one the importer reads",
                 "move it after the others");
    expect_error(REGRESS "mesh_ply/assimp_segv_lone_cr.ply", NULL, IC_ERR_PARSE,
                 "assimp_segv_lone_cr.ply:5: a carriage return inside a PLY header line", NULL, NULL);
    expect_error(REGRESS "mesh_ply/assimp_segv_tristrips_list_name.ply", NULL, IC_ERR_PARSE,
                 "assimp_segv_tristrips_list_name.ply: tristrips 1 names vertex 2880154539, but the file has 3", NULL,
                 NULL);
    expect_error(REGRESS "mesh_ply/assimp_oom_digit_element_no_instances.ply", NULL, IC_ERR_UNSUPPORTED,
                 "assimp_oom_digit_element_no_instances.ply: PLY element '8888", "(0 instances)", "begins with a letter");
    {
        /* Each cause alone in a binary file: a custom element before the faces (assimp read its count as 0
         * and the faces from its bytes), a lone \r in ascii data; a blank line after end_header and \r\n
         * line ends still load, and a custom element after the faces is ignored. */
        static const char bin_head[] = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                                       "property float y\nproperty float z\n";
        static const char face_head[] = "element face 1\nproperty list uchar int vertex_indices\n";
        const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        const int32_t idx[3] = {0, 1, 2};
        char bin[1024];
        size_t n;
#define PUT(p, len) (memcpy(bin + n, (p), (len)), n += (len))
#define BODY() (PUT(xyz, sizeof xyz), bin[n++] = 3, PUT(idx, sizeof idx))
        n = 0;
        PUT(bin_head, strlen(bin_head));
        PUT("element foo 2\nproperty uchar a\n", 31);
        PUT(face_head, strlen(face_head));
        PUT("end_header\n", 11);
        PUT(xyz, sizeof xyz);
        PUT("\7\7", 2);
        bin[n++] = 3;
        PUT(idx, sizeof idx);
        expect_error(write_tmp("custom_element.ply", bin, (long)n), NULL, IC_ERR_UNSUPPORTED,
                     "custom_element.ply: PLY element 'foo' (2 instances) is not one the importer reads", NULL, NULL);
        const char *blank[3] = {"end_header\n\n", "end_header\r\n", "element foo 2\nproperty uchar a\nend_header\n"};
        for (int k = 0; k < 3; ++k) {
            n = 0;
            PUT(bin_head, strlen(bin_head));
            PUT(face_head, strlen(face_head));
            PUT(blank[k], strlen(blank[k]));
            BODY();
            if (k == 2)
                PUT("\7\7", 2);
            ic_scene *scene = NULL;
            ic_error err;
            memset(&err, 0, sizeof err);
            ic_result r = ic_scene_load(write_tmp("blank_after_header.ply", bin, (long)n), NULL, &scene, &err);
            CHECK(r == IC_OK && scene && scene->triangle_count == 1 && scene->bounds_max.x == 1.0f &&
                      scene->bounds_max.y == 1.0f && scene->bounds_min.x == 0.0f,
                  "binary PLY variant %d loads its one triangle (%s)", k, err.message);
            ic_scene_free(scene);
        }
#undef BODY
#undef PUT
        snprintf(text, sizeof text, "%s0 0 0\n1 0\r0\n0 1 0\n3 0 1 2\n", ply_head);
        expect_error(write_tmp("lone_cr_ascii.ply", text, -1), NULL, IC_ERR_PARSE,
                     "lone_cr_ascii.ply:11: a carriage return inside a line of ascii PLY data", NULL, NULL);
    }
    expect_error(REGRESS "mesh_gltf/assimp_leak.gltf", NULL, IC_ERR_PARSE, "assimp_leak.gltf: buffers[0]: character "
                 "24 of the base64 data", "not base64", NULL);
    /* Each cause alone, in an otherwise valid file. PLY: a word where a number belongs (assimp threw and
     * leaked), an index past the vertices, a truncated body, a header without end_header (assimp looped). */
    snprintf(text, sizeof text, "%s0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n", ply_head);
    expect_error(write_tmp("hostile_word.ply", text, -1), NULL, IC_ERR_PARSE, "hostile_word.ply:11: 'x' is not a "
                 "number (property 'y' of vertex 2)", NULL, NULL);
    snprintf(text, sizeof text, "%s0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", ply_head);
    expect_error(write_tmp("hostile_index.ply", text, -1), NULL, IC_ERR_PARSE, "hostile_index.ply:13: face 1 names "
                 "vertex 3, but the file has 3 vertices (0 to 2)", NULL, NULL);
    snprintf(text, sizeof text, "%s0 0 0\n1 0 0\n0 1 0\n", ply_head);
    expect_error(write_tmp("hostile_short.ply", text, -1), NULL, IC_ERR_PARSE, "hostile_short.ply: the data ends in "
                 "element 'face' 1 of 1 (ascii)", NULL, NULL);
    snprintf(text, sizeof text, "%s0 0 0\n1 0 0\n0 1 0\n3 0 1\n", ply_head);
    expect_error(write_tmp("hostile_few.ply", text, -1), NULL, IC_ERR_PARSE, "hostile_few.ply:13: face 1 ends before "
                 "its property 'vertex_indices'", NULL, NULL);
    expect_error(write_tmp("hostile_noend.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n", -1),
                 NULL, IC_ERR_PARSE, "hostile_noend.ply: PLY header without 'end_header'", NULL, NULL);
    expect_error(write_tmp("hostile_amp.ply", "ply&\nformat ascii 1.0\nend_header\n", -1), NULL, IC_ERR_PARSE,
                 "hostile_amp.ply:1: the first line of a PLY file must be exactly 'ply'", NULL, NULL);
    expect_error(write_tmp("hostile_keyword.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\n"
                           "propertyy float y\nend_header\n", -1), NULL, IC_ERR_PARSE, "hostile_keyword.ply:5: "
                 "'propertyy float y' is not a PLY header line", NULL, NULL);
    snprintf(text, sizeof text, "%s0 0 0\n1 0 0\n0 1 0\n200 0 1 2\n", ply_head);
    expect_error(write_tmp("hostile_list.ply", text, -1), NULL, IC_ERR_PARSE, "hostile_list.ply:13: face 1 ends "
                 "before its property 'vertex_indices'", NULL, NULL);
    /* OBJ: a face of the second material naming vertex 4 of 3 (assimp threw "vertex index out of range"
     * holding the first mesh, which leaked), and a negative index reaching before the first vertex. */
    expect_error(write_tmp("hostile_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\nusemtl b\nf 1 3 4\n", -1),
                 NULL, IC_ERR_PARSE, "hostile_index.obj:7: a face names vertex 4, but the file has 3",
                 "fix the face", NULL);
    expect_error(write_tmp("hostile_negative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", -1), NULL,
                 IC_ERR_PARSE, "hostile_negative.obj:4: vertex index -4 reaches before the first one", NULL, NULL);
    /* texture and normal indices past the end: assimp dropped every normal or coordinate, without a word */
    expect_error(write_tmp("hostile_vn.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//3\n", -1), NULL,
                 IC_ERR_PARSE, "hostile_vn.obj:5: a face names normal (vn) 3, but the file has 1", NULL, NULL);
    expect_error(write_tmp("hostile_vt.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/-2\n", -1), NULL,
                 IC_ERR_PARSE, "hostile_vt.obj:5: texture coordinate (vt) index -2 reaches before the first one", NULL,
                 NULL);
    expect_error(REGRESS "mesh_obj/assimp_leak.obj", NULL, IC_ERR_PARSE, "assimp_leak.obj:3: vertex 1: '2~' is not "
                 "a number", NULL, NULL);
    /* A line element of one vertex after a first mesh: assimp sized its mesh for no vertex and threw,
     * leaking the first mesh (the fuzzer's input, minimised, is the regress file: its NUL ends
     * line 6, as assimp splits lines). */
    expect_error(write_tmp("hostile_line.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no r\nl 1\n", -1), NULL,
                 IC_ERR_PARSE, "hostile_line.obj:6: a line element (l) names one vertex", "fix or remove", NULL);
    {
        /* the element limit counted before assimp reads the file: 4 vertices, 2 faces against 3 and 1 */
        ic_scene_load_options lim = {0};
        lim.max_mesh_elements = 3;
        const char *quad = write_tmp("limit.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n", -1);
        expect_error(quad, &lim, IC_ERR_UNSUPPORTED, "limit.obj:4: more than 3 vertices", "--max-mesh-elements", NULL);
        lim.max_mesh_elements = 4;
        expect_error(write_tmp("limit_faces.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\nf 1 2 3\n"
                               "f 1 3 4\nf 1 2 4\n", -1), &lim, IC_ERR_UNSUPPORTED, "limit_faces.obj:9: more than 4 faces",
                     NULL, NULL);
        ic_scene *ok = NULL;
        CHECK(ic_scene_load(IC_TEST_TMP "/limit.obj", &lim, &ok, NULL) == IC_OK,
              "4 vertices and 2 faces load at a limit of 4");
        ic_scene_free(ok);
    }
    expect_error(REGRESS "mesh_obj/assimp_leak_line_one_vertex.obj", NULL, IC_ERR_PARSE,
                 "assimp_leak_line_one_vertex.obj:7: a line element (l) names one vertex", NULL, NULL);
    /* glTF: a data URI that is not base64 (assimp's decoder leaked its output). */
    {
        static char gltf[8192];
        FILE *fp = fopen(SCENES "triangle.gltf", "rb");
        size_t n = fp ? fread(gltf, 1, sizeof gltf - 1, fp) : 0;
        if (fp)
            fclose(fp);
        gltf[n] = '\0';
        char *b64 = strstr(gltf, "base64,");
        CHECK(b64 != NULL && n < sizeof gltf - 1, "triangle.gltf has an embedded buffer");
        if (b64) {
            char orig = b64[7 + 5];
            b64[7 + 5] = '*';
            expect_error(write_tmp("hostile_base64.gltf", gltf, (long)n), NULL, IC_ERR_PARSE, "hostile_base64.gltf: "
                         "buffers[0]: character 6 of the base64 data of its URI is not base64 (0x2a)", NULL, NULL);
            /* What assimp's glTF 2 importer declines goes to every other importer by content (OpenGEX read
             * past its buffer on the fuzzer's 20-byte .gltf, and looped for ever on a variant): trailing
             * text, a control character in a string, a leading zero, glTF 1, text named .glb. */
            static char bad[8300];
            snprintf(bad, sizeof bad, "%s xyz", gltf);
            expect_error(write_tmp("trailing.gltf", bad, -1), NULL, IC_ERR_PARSE, "trailing.gltf: the glTF JSON is not "
                         "valid JSON at byte", NULL, NULL);
            b64[7 + 5] = '\001';
            expect_error(write_tmp("control.gltf", gltf, (long)n), NULL, IC_ERR_PARSE, "control.gltf: the glTF JSON "
                         "is not valid JSON at byte", NULL, NULL);
            b64[7 + 5] = orig;
            char *version = strstr(gltf, "\"2.0\"");
            CHECK(version != NULL, "triangle.gltf says version 2.0");
            if (version) {
                version[1] = '1';
                expect_error(write_tmp("version1.gltf", gltf, (long)n), NULL, IC_ERR_PARSE, "version1.gltf: not a "
                             "glTF 2.0 file", NULL, NULL);
                version[1] = '2';
            }
            char *zero = strstr(gltf, "\"byteLength\"");
            CHECK(zero != NULL, "triangle.gltf has a byteLength");
            if (zero) {
                zero = strchr(zero, ':');
                while (*++zero == ' ') {
                }
                snprintf(bad, sizeof bad, "%.*s0%s", (int)(zero - gltf), gltf, zero);
                expect_error(write_tmp("leading_zero.gltf", bad, -1), NULL, IC_ERR_PARSE, "leading_zero.gltf: the "
                             "glTF JSON is not valid JSON", NULL, NULL);
            }
            expect_error(write_tmp("text_named.glb", gltf, (long)n), NULL, IC_ERR_PARSE, "text_named.glb: not binary "
                         "glTF", "named .gltf", NULL);
            ic_scene *ok = NULL;
            CHECK(ic_scene_load(write_tmp("restored.gltf", gltf, (long)n), NULL, &ok, NULL) == IC_OK,
                  "the restored glTF loads");
            ic_scene_free(ok);
        }
    }
    expect_error(REGRESS "mesh_gltf/assimp_heap_overflow_fallback_importer.gltf", NULL, IC_ERR_PARSE,
                 "assimp_heap_overflow_fallback_importer.gltf: binary glTF in a file named .gltf", "rename it .glb",
                 NULL);
    expect_error(write_tmp("not_json.gltf", "xlTF{indexarraycene_", -1), NULL, IC_ERR_PARSE,
                 "not_json.gltf: the glTF JSON is not valid JSON at byte 1", NULL, NULL);
    expect_error(REGRESS "mesh_glb/assimp_leak_accessor_past_view.glb", NULL, IC_ERR_PARSE,
                 "assimp_leak_accessor_past_view.glb: accessors[1]: 3 elements of 6 bytes from byte 0 read to byte 18 "
                 "of bufferViews[1], which has 6", NULL, NULL);
    {
        /* Each accessor rule alone, on triangle.gltf: a view past its buffer, an accessor without a count, a
         * primitive naming no accessor. */
        static char g[8192], bad[8300];
        FILE *fp = fopen(SCENES "triangle.gltf", "rb");
        size_t n = fp ? fread(g, 1, sizeof g - 1, fp) : 0;
        if (fp)
            fclose(fp);
        g[n] = '\0';
        static const struct { const char *from, *to, *name, *want; } edits[] = {
            {"\"byteLength\": 36", "\"byteLength\": 99", "view_past_buffer.gltf", "bufferViews[0]: bytes 0 to 99, past"},
            {"\"count\": 3", "\"cuont\": 3", "no_count.gltf", "accessors[0]: needs a count"},
            {"\"indices\": 1", "\"indices\": 7", "bad_indices.gltf", "meshes[0]: a primitive's indices"},
            {"\"mesh\": 0", "\"mesh\": 5", "bad_mesh.gltf", "nodes[0]: \"mesh\" names no element of \"meshes\""},
            {"\"material\": 0", "\"material\": 9", "bad_material.gltf", "a primitive's material names no material"},
            {"\"scene\": 0", "\"scene\": 2", "bad_scene.gltf", "\"scene\" names no element of \"scenes\""},
            {"\"count\": 3,", "\"count\": 3, \"sparse\": {\"count\": 2, \"indices\": {\"bufferView\": 1, "
             "\"componentType\": 5125}, \"values\": {\"bufferView\": 1}},", "bad_sparse.gltf",
             "accessors[0]: its sparse part"},
        };
        for (size_t k = 0; k < sizeof edits / sizeof edits[0]; ++k) {
            const char *at = strstr(g, edits[k].from);
            CHECK(at != NULL, "triangle.gltf holds '%s'", edits[k].from);
            if (!at)
                continue;
            snprintf(bad, sizeof bad, "%.*s%s%s", (int)(at - g), g, edits[k].to, at + strlen(edits[k].from));
            expect_error(write_tmp(edits[k].name, bad, -1), NULL, IC_ERR_PARSE, edits[k].name, edits[k].want, NULL);
        }
    }
    expect_error(REGRESS "mesh_gltf/assimp_leak_long_data_uri_header.gltf", NULL, IC_ERR_PARSE,
                 "assimp_leak_long_data_uri_header.gltf: buffers[0]: a data URI whose media type and parameters",
                 "162 characters, more than 120", NULL);
    {
        /* A .glb whose second chunk is not BIN (the importer looks for it after the JSON padded to 4). */
        FILE *fp = fopen(IC_SOURCE_DIR "/tests/fuzz/corpus/mesh_glb/triangle.glb", "rb");
        static unsigned char glb[8192];
        size_t n = fp ? fread(glb, 1, sizeof glb, fp) : 0;
        if (fp)
            fclose(fp);
        uint32_t json_len = n > 20 ? (uint32_t)glb[12] | (uint32_t)glb[13] << 8 : 0;
        size_t bin_at = 20 + ((json_len + 3) & ~3u);
        CHECK(n > bin_at + 8 && !memcmp(glb + bin_at + 4, "BIN", 4), "triangle.glb has a BIN chunk at %zu", bin_at);
        if (n > bin_at + 8) {
            memcpy(glb + bin_at + 4, "BIX", 4);
            expect_error(write_tmp("no_bin.glb", (const char *)glb, (long)n), NULL, IC_ERR_PARSE, "no_bin.glb: the "
                         "second chunk of a binary glTF must be BIN", NULL, NULL);
        }
    }
    /* glTF: a buffer file shorter than its byteLength (assimp threw and leaked the stream it had opened). */
    {
        static const char bin[44] = {0};
        write_tmp("hostile_short.bin", bin, (long)sizeof bin);
        expect_error(write_tmp("hostile_short.gltf", "{\"asset\": {\"version\": \"2.0\"},\n\"buffers\": [{\"byteLength\": "
                               "45, \"uri\": \"hostile_short.bin\"}]}\n", -1),
                     NULL, IC_ERR_PARSE, "hostile_short.gltf: buffers[0]: byteLength is 45 but 'hostile_short.bin' "
                     "holds 44 bytes", "export the model again", NULL);
    }
    /* Valid files are still read: ascii with CRLF lines and a comment, binary in both byte orders. */
    ic_scene *ok = NULL;
    ic_error e;
    snprintf(text, sizeof text, "ply\r\nformat ascii 1.0\r\ncomment crlf\r\nelement vertex 3\r\nproperty float x\r\n"
             "property float y\r\nproperty float z\r\nelement face 1\r\nproperty list uchar int vertex_indices\r\n"
             "end_header\r\n0 0 0\r\n1 0 0\r\n0 1 0\r\n3 0 1 2\r\n");
    CHECK(ic_scene_load(write_tmp("valid_crlf.ply", text, -1), NULL, &ok, &e) == IC_OK, "CRLF PLY loads (%s)",
          e.message);
    ic_scene_free(ok);
    ok = NULL;
    CHECK(ic_scene_load(IC_SOURCE_DIR "/tests/fuzz/corpus/mesh_ply/tri_binary_be.ply", NULL, &ok, &e) == IC_OK,
          "big-endian PLY loads (%s)", e.message);
    ic_scene_free(ok);
}

/* Loads path and checks that it loads. */
static void expect_load(const char *path, const char *what)
{
    ic_scene *s = NULL;
    ic_error e;
    memset(&e, 0, sizeof e);
    CHECK(ic_scene_load(path, NULL, &s, &e) == IC_OK, "%s loads (%s)", what, e.message);
    ic_scene_free(s);
}

/* A normal-mapped glTF triangle (z = 0, normal +z, a flat map) whose vertices have the TANGENTs t (x y z w),
 * its buffer in the file name.bin beside it; returns the glTF's path. */
static const char *write_tangent_gltf(const char *name, const float t[3][4])
{
    static const float pos_nrm_uv[24] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    static const uint16_t idx[3] = {0, 1, 2};
    unsigned char bin[150];
    memcpy(bin, pos_nrm_uv, sizeof pos_nrm_uv);  /* positions, normals, texture coordinates: bytes 0-95 */
    memcpy(bin + 96, t, 48);                     /* tangents: bytes 96-143 (a little-endian host, as the file) */
    memcpy(bin + 144, idx, sizeof idx);
    char file[128], text[2048];
    snprintf(file, sizeof file, "%s.bin", name);
    write_tmp(file, (const char *)bin, (long)sizeof bin);
    char pfm[24] = "PF\n1 1\n-1.0\n"; /* one texel (0.5, 0.5, 1): the normal unchanged */
    memcpy(pfm + 12, (const float[3]){0.5f, 0.5f, 1.0f}, 12);
    write_tmp("tangent_flat_n.pfm", pfm, sizeof pfm);
    snprintf(text, sizeof text,
             "{\"asset\": {\"version\": \"2.0\"}, \"buffers\": [{\"byteLength\": 150, \"uri\": \"%s\"}],\n"
             " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36}, {\"buffer\": 0, \"byteOffset\": 36, "
             "\"byteLength\": 36},\n  {\"buffer\": 0, \"byteOffset\": 72, \"byteLength\": 24}, {\"buffer\": 0, \"byteOffset\": 96, "
             "\"byteLength\": 48},\n  {\"buffer\": 0, \"byteOffset\": 144, \"byteLength\": 6}],\n"
             " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\", \"min\": [0, 0, 0], "
             "\"max\": [1, 1, 0]},\n  {\"bufferView\": 1, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\"},\n"
             "  {\"bufferView\": 2, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC2\"},\n"
             "  {\"bufferView\": 3, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC4\"},\n"
             "  {\"bufferView\": 4, \"componentType\": 5123, \"count\": 3, \"type\": \"SCALAR\"}],\n"
             " \"images\": [{\"uri\": \"tangent_flat_n.pfm\"}], \"textures\": [{\"source\": 0}],\n"
             " \"materials\": [{\"name\": \"m\", \"normalTexture\": {\"index\": 0}}],\n"
             " \"meshes\": [{\"name\": \"tri\", \"primitives\": [{\"attributes\": {\"POSITION\": 0, \"NORMAL\": 1, "
             "\"TEXCOORD_0\": 2, \"TANGENT\": 3}, \"indices\": 4, \"material\": 0}]}],\n"
             " \"nodes\": [{\"mesh\": 0}], \"scenes\": [{\"nodes\": [0]}], \"scene\": 0}\n",
             file);
    snprintf(file, sizeof file, "%s.gltf", name);
    return write_tmp(file, text, -1);
}

/* A glTF's tangents (TANGENT: x y z and the bitangent's sign w) are refused when not finite, as its normals
 * are, not taken for none and replaced by the triangle's own; finite ones reach the scene as the unit
 * tangent and the sign of w. */
static void test_non_finite_tangents(void)
{
    const float nan = NAN, inf = INFINITY;
    const float ok[3][4] = {{2, 0, 0, 1}, {1, 0, 0, -1}, {0, 1, 0, 1}};
    ic_scene *s = NULL;
    ic_error e;
    memset(&e, 0, sizeof e);
    CHECK(ic_scene_load(write_tangent_gltf("tangents_ok", ok), NULL, &s, &e) == IC_OK && s,
          "a normal-mapped glTF with finite tangents loads (%s)", e.message);
    if (s) {
        CHECK(s->tangents != NULL && s->vertex_count == 3, "its tangents are kept (%u vertices)", s->vertex_count);
        for (uint32_t i = 0; s->tangents && i < s->vertex_count; ++i) {
            /* the file's vertex at this position: (0 0 0), (1 0 0), (0 1 0) */
            int k = s->positions[i].x == 1.0f ? 1 : s->positions[i].y == 1.0f ? 2 : 0;
            const float *t = s->tangents + 4 * i;
            float len = sqrtf(ok[k][0] * ok[k][0] + ok[k][1] * ok[k][1] + ok[k][2] * ok[k][2]);
            CHECK(fabsf(t[0] - ok[k][0] / len) < 1e-6f && fabsf(t[1] - ok[k][1] / len) < 1e-6f &&
                      fabsf(t[2] - ok[k][2] / len) < 1e-6f && t[3] == ok[k][3],
                  "vertex %d's tangent is the file's, of unit length, with its sign: (%g %g %g %g)", k + 1,
                  (double)t[0], (double)t[1], (double)t[2], (double)t[3]);
        }
        ic_scene_free(s);
    }
    const float nan_x[3][4] = {{1, 0, 0, 1}, {nan, 0, 0, 1}, {1, 0, 0, 1}};
    expect_error(write_tangent_gltf("nan_tangent", nan_x), NULL, IC_ERR_PARSE,
                 "nan_tangent.gltf: vertex 2 of mesh 'tri' has a non-finite tangent", "fix or remove it", NULL);
    const float inf_y[3][4] = {{0, inf, 0, 1}, {1, 0, 0, 1}, {1, 0, 0, 1}};
    expect_error(write_tangent_gltf("inf_tangent", inf_y), NULL, IC_ERR_PARSE,
                 "inf_tangent.gltf: vertex 1 of mesh 'tri' has a non-finite tangent", "fix or remove it", NULL);
    /* w: assimp makes the bitangent of it (the normal × the tangent times w) */
    const float nan_w[3][4] = {{1, 0, 0, 1}, {1, 0, 0, 1}, {1, 0, 0, nan}};
    expect_error(write_tangent_gltf("nan_tangent_w", nan_w), NULL, IC_ERR_PARSE,
                 "nan_tangent_w.gltf: vertex 3 of mesh 'tri' has a non-finite bitangent", "its w", "fix or remove it");
}

/* Non-finite texture coordinates and normals are refused as non-finite positions are, in every mesh format
 * that carries them: a NaN normal makes NaN shading samples (black pixels once the film drops them), a NaN
 * texture coordinate a look-up nowhere. The message names the file and the line (OBJ, ascii PLY) or the
 * vertex (binary PLY, glTF, serialized), like the position's. */
static void test_non_finite_attributes(void)
{
    /* OBJ: the line and the element's number as the file counts its kind */
    expect_error(SCENES "nan_uv.obj", NULL, IC_ERR_PARSE, "nan_uv.obj:8:", "texture coordinate (vt) 3 has a non-finite",
                 "fix or remove it");
    expect_error(SCENES "nan_normal.obj", NULL, IC_ERR_PARSE, "nan_normal.obj:7:", "normal (vn) 2 has a non-finite",
                 "fix or remove it");
    expect_error(write_tmp("attr_big_vt.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 1e39\nf 1/1 2/1 3/1\n", -1), NULL,
                 IC_ERR_PARSE, "attr_big_vt.obj:4:", "texture coordinate (vt) 1 has a non-finite", NULL);
    expect_error(write_tmp("attr_word_vn.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 one\nf 1//1 2//1 3//1\n", -1), NULL,
                 IC_ERR_PARSE, "attr_word_vn.obj:4:", "normal (vn) 1: 'one' is not a number", NULL);
    expect_load(write_tmp("attr_ok.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0 0\nvt 0 1 # w omitted\n"
                                         "vn 0 0 1\nf 1/1/1 2/2/1 3/3/1\n", -1),
                "an OBJ with finite texture coordinates and normals");
    /* Finite as a float up to FLT_MAX (3.40282347e38), whatever the spelling: the check decides most numbers
     * from their digits and converts those that may be 10^38 or more; 3.4028236e38 rounds to infinity. */
    expect_load(write_tmp("attr_near_max.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 340282340000000000000000000000000000000\n"
                                               "vt 0 99999999999999999999999999999999999999\nvt 0 0.000001e44\n"
                                               "vt 0 3.4028234e38\nvt 0 -00000000000000000000001e37\nvt 0 1e-999999999999\n"
                                               "f 1/1 2/2 3/3\n", -1),
                "an OBJ whose texture coordinates come close to FLT_MAX");
    expect_error(write_tmp("attr_past_max.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 0 340282360000000000000000000000000000000\n"
                                                "f 1/1 2/1 3/1\n", -1),
                 NULL, IC_ERR_PARSE, "attr_past_max.obj:5:", "texture coordinate (vt) 2 has a non-finite", NULL);
    expect_error(write_tmp("attr_big_exp.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0.0000000000001e999999999999\n"
                                               "f 1/1 2/1 3/1\n", -1),
                 NULL, IC_ERR_PARSE, "attr_big_exp.obj:4:", "texture coordinate (vt) 1 has a non-finite", NULL);

    /* PLY, ascii: vertex properties x y z nx ny nz u v (header lines 1-14, vertices on lines 15-17) */
    static const char header[] = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                 "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
                                 "property float u\nproperty float v\nelement face 1\n"
                                 "property list uchar int vertex_indices\nend_header\n";
    char text[1024];
    snprintf(text, sizeof text, "%s0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n0 1 0 0 0 1 0 1\n3 0 1 2\n", header);
    expect_load(write_tmp("attr_ok.ply", text, -1), "a PLY with finite normals and texture coordinates");
    snprintf(text, sizeof text, "%s0 0 0 0 0 1 0 0\n1 0 0 nan 0 1 1 0\n0 1 0 0 0 1 0 1\n3 0 1 2\n", header);
    expect_error(write_tmp("attr_nan_normal.ply", text, -1), NULL, IC_ERR_PARSE, "attr_nan_normal.ply:16:",
                 "vertex 2 has a non-finite normal (nan)", "fix or remove it");
    snprintf(text, sizeof text, "%s0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n0 1 0 0 0 1 0 -inf\n3 0 1 2\n", header);
    expect_error(write_tmp("attr_inf_uv.ply", text, -1), NULL, IC_ERR_PARSE, "attr_inf_uv.ply:17:",
                 "vertex 3 has a non-finite texture coordinate (-inf)", "fix or remove it");
    /* Blender's s, t; a face's texcoord list */
    expect_error(write_tmp("attr_nan_st.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                           "property float y\nproperty float z\nproperty float s\nproperty float t\nelement face 1\n"
                           "property list uchar int vertex_indices\nend_header\n0 0 0 0 0\n1 0 0 nan 0\n0 1 0 0 1\n"
                           "3 0 1 2\n", -1),
                 NULL, IC_ERR_PARSE, "attr_nan_st.ply:13:", "vertex 2 has a non-finite texture coordinate", NULL);
    expect_error(write_tmp("attr_nan_texcoord.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                           "property float y\nproperty float z\nelement face 1\n"
                           "property list uchar int vertex_indices\nproperty list uchar float texcoord\nend_header\n"
                           "0 0 0\n1 0 0\n0 1 0\n3 0 1 2 6 0 0 1 0 0 nan\n", -1),
                 NULL, IC_ERR_PARSE, "attr_nan_texcoord.ply:14:", "face 1 has a non-finite texture coordinate (nan)",
                 NULL);
    /* PLY, binary little-endian: x y z nx ny nz, vertex 2's nz infinite */
    {
        static const char bin_header[] = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                                         "property float y\nproperty float z\nproperty float nx\nproperty float ny\n"
                                         "property float nz\nelement face 1\nproperty list uchar int vertex_indices\n"
                                         "end_header\n";
        const float inf = INFINITY;
        float v[3][6] = {{0, 0, 0, 0, 0, 1}, {1, 0, 0, 0, 0, inf}, {0, 1, 0, 0, 0, 1}};
        unsigned char bin[sizeof bin_header + sizeof v + 13];
        size_t n = sizeof bin_header - 1;
        memcpy(bin, bin_header, n);
        memcpy(bin + n, v, sizeof v); /* a little-endian host, as the file */
        n += sizeof v;
        bin[n++] = 3;
        int32_t idx[3] = {0, 1, 2};
        memcpy(bin + n, idx, sizeof idx);
        n += sizeof idx;
        expect_error(write_tmp("attr_inf_normal_bin.ply", (const char *)bin, (long)n), NULL, IC_ERR_PARSE,
                     "attr_inf_normal_bin.ply: vertex 2 (of 3, binary) has a non-finite normal (inf)",
                     "fix or remove it", NULL);
    }

    /* glTF: the vertex and the mesh, as for a position */
    expect_load(SCENES "attrs_ok.gltf", "a glTF with finite normals and texture coordinates");
    expect_error(SCENES "nan_normal.gltf", NULL, IC_ERR_PARSE, "nan_normal.gltf: vertex 2 of mesh 'tri'",
                 "has a non-finite normal", "fix or remove it");
    expect_error(SCENES "nan_uv.gltf", NULL, IC_ERR_PARSE, "nan_uv.gltf: vertex 3 of mesh 'tri'",
                 "has a non-finite texture coordinate", "fix or remove it");
    /* the file's mesh and vertex, not those of assimp's steps (which merge the meshes of one material into one
     * and renumber the vertices without the ones no face uses) */
    expect_error(SCENES "nan_normal_second_mesh.gltf", NULL, IC_ERR_PARSE,
                 "nan_normal_second_mesh.gltf: vertex 1 of mesh 'second' has a non-finite normal", NULL, NULL);
    expect_error(SCENES "nan_normal_after_unused.gltf", NULL, IC_ERR_PARSE,
                 "nan_normal_after_unused.gltf: vertex 4 of mesh 'tri' has a non-finite normal", NULL, NULL);
}

/* Appends v in big-endian order, `size` bytes of it (a float's or an integer's bits). */
static size_t put_be(unsigned char *out, size_t at, uint64_t v, int size)
{
    for (int k = 0; k < size; ++k)
        out[at + (size_t)k] = (unsigned char)(v >> (8 * (size - 1 - k)));
    return at + (size_t)size;
}

/* A PLY face's texcoord list of 6 to 8 values is read by assimp as a u v pair per vertex of the face, through
 * its vertex indices: a face with fewer vertices than pairs had its index array read past its end (valgrind:
 * invalid read in libassimp), and a face element with the list but no vertex indices crashed (NULL read, or
 * an assertion in triangulation: found by the mesh_ply fuzz target). Each is refused with the face's place;
 * a list of as many pairs as vertices, or of a length assimp does not read, loads. */
static void test_ply_face_texcoords(void)
{
    static const char header[] = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                                 "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                 "property list uint double texcoord\nend_header\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n";
    char text[1024];
    snprintf(text, sizeof text, "%s3 0 1 2 8 0 0 1 0 0 1 1 1\n", header); /* face on line 15 */
    expect_error(write_tmp("tc_pairs.ply", text, -1), NULL, IC_ERR_PARSE, "tc_pairs.ply:15: face 1 has a list "
                 "'texcoord' of 8 values", "but 3 vertices", NULL);
    snprintf(text, sizeof text, "%s3 0 1 2 7 0 0 1 0 0 1 1\n", header);
    expect_error(write_tmp("tc_pairs7.ply", text, -1), NULL, IC_ERR_PARSE, "tc_pairs7.ply:15: face 1", "of 7 values",
                 "but 3 vertices");
    snprintf(text, sizeof text, "%s4 0 1 3 2 8 0 0 1 0 1 1 0 1\n", header);
    expect_load(write_tmp("tc_quad.ply", text, -1), "a quad with a u v pair per vertex");
    snprintf(text, sizeof text, "%s3 0 1 2 4 0 0 1 0\n", header);
    expect_load(write_tmp("tc_other_length.ply", text, -1), "a texcoord list of a length the importer ignores");
    expect_load(write_tmp("tc_first.ply", "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
                          "property float y\nproperty float z\nelement face 1\nproperty list uint double texcoord\n"
                          "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n"
                          "8 0 0 1 0 1 1 0 1 4 0 1 3 2\n", -1),
                "a texcoord list declared before the vertex indices");
    expect_error(write_tmp("tc_no_indices.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                           "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_ind\n"
                           "property list uint double texcoord\nend_header\n0 0 0\n1 0 0\n0 1 0\n"
                           "3 0 1 2 6 0 0 1 0 0 1\n", -1),
                 NULL, IC_ERR_PARSE, "tc_no_indices.ply: PLY element 'face' has a list 'texcoord' but no vertex index "
                 "list", NULL, NULL);
    /* binary big-endian: double x y z, a triangle (uchar count, uint indices) with 8 double texcoords */
    {
        static const char bin_header[] = "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\n"
                                         "property double y\nproperty double z\nelement face 1\n"
                                         "property list uchar uint vertex_indices\n"
                                         "property list ushort double texcoord\nend_header\n";
        unsigned char bin[sizeof bin_header - 1 + 9 * 8 + 1 + 3 * 4 + 2 + 8 * 8];
        size_t n = sizeof bin_header - 1;
        memcpy(bin, bin_header, n);
        const double xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, uv[8] = {0, 0, 1, 0, 0, 1, 1, 1};
        uint64_t bits;
        for (int k = 0; k < 9; ++k) {
            memcpy(&bits, &xyz[k], sizeof bits);
            n = put_be(bin, n, bits, 8);
        }
        n = put_be(bin, n, 3, 1);
        for (uint32_t k = 0; k < 3; ++k)
            n = put_be(bin, n, k, 4);
        n = put_be(bin, n, 8, 2);
        for (int k = 0; k < 8; ++k) {
            memcpy(&bits, &uv[k], sizeof bits);
            n = put_be(bin, n, bits, 8);
        }
        CHECK(n == sizeof bin, "the binary PLY is %zu bytes", n);
        expect_error(write_tmp("tc_pairs_be.ply", (const char *)bin, (long)n), NULL, IC_ERR_PARSE,
                     "tc_pairs_be.ply: face 1 (binary) has a list 'texcoord' of 8 values", "but 3 vertices", NULL);
        /* the same file with 6 values loads */
        bin[n - 8 * 8 - 1] = 6;
        expect_load(write_tmp("tc_pairs6_be.ply", (const char *)bin, (long)(n - 2 * 8)),
                    "a binary big-endian triangle with 6 texcoords");
    }
}

/* The OBJ number grammar (mesh_check_obj.c), written out on its own: [+-] digits [. digits*], or [+-] . digits
 * (unsigned only where bare_fraction), then [eE [+-] digits]; or [+-] nan / inf in any case. */
static int obj_grammar(const char *w, int bare_fraction)
{
    const char *c = w + (*w == '+' || *w == '-');
    if (!strcasecmp(c, "nan") || !strcasecmp(c, "inf"))
        return 1;
    size_t digits = strspn(c, "0123456789");
    if (!digits && !(c[0] == '.' && isdigit((unsigned char)c[1]) && (c > w || bare_fraction)))
        return 0;
    c += digits;
    if (*c == '.')
        c += 1 + strspn(c + 1, "0123456789");
    if (*c == 'e' || *c == 'E') {
        c += 1 + (c[1] == '+' || c[1] == '-');
        if (!isdigit((unsigned char)*c))
            return 0;
        c += strspn(c, "0123456789");
    }
    return *c == '\0';
}

/* Appends n random decimal digits (the first not 0 when nonzero_first) to w at *at. */
static void put_digits(ic_rng *rng, char *w, size_t *at, uint32_t n, int nonzero_first)
{
    for (uint32_t i = 0; i < n; ++i)
        w[(*at)++] = (char)('0' + (i == 0 && nonzero_first ? 1 + ic_rng_below(rng, 9) : ic_rng_below(rng, 10)));
}

/* A random word in or near the OBJ number grammar, its magnitude mostly near 10^38 and FLT_MAX (3.40282347e38)
 * whatever the spelling: leading zeros, the point anywhere in the digits, zeros after the point, the exponent
 * making up the difference (with leading zeros of its own, or out of any range), nan and inf spellings. */
static void random_obj_word(ic_rng *rng, char *w)
{
    static const char *const signs[3] = {"", "+", "-"};
    static const char *const words[] = {"nan", "NaN", "inf", "Inf", "INF", "infinity", "nan(1)", "0x1p128", "1e",
                                        "1e+", "-.", ".", "+.e5", "1.5.2", "1e5e5", "- 1", "e38", "1d38"};
    static const char *const near_max[] = {"34028234663852885981170418348451692544",
                                           "340282356779733661637539395458142568448",
                                           "3402823567797336616375393954581425684479999",
                                           "3402823567797336616375393954581425684480000001", "99999999999999999999"};
    size_t at = 0;
    const char *sign = signs[ic_rng_below(rng, 3)];
    memcpy(w, sign, strlen(sign));
    at += strlen(sign);
    if (ic_rng_below(rng, 16) == 0) {
        strcpy(w + at, words[ic_rng_below(rng, sizeof words / sizeof words[0])]);
        return;
    }
    /* the significant digits: random, or FLT_MAX's neighbourhood */
    char sig[64];
    size_t len;
    if (ic_rng_below(rng, 3) == 0) {
        const char *m = near_max[ic_rng_below(rng, sizeof near_max / sizeof near_max[0])];
        len = strlen(m);
        memcpy(sig, m, len);
    } else {
        len = 0;
        put_digits(rng, sig, &len, ic_rng_below(rng, 50), 1);
    }
    if (ic_rng_below(rng, 3) == 0) /* leading zeros */
        for (uint32_t z = ic_rng_below(rng, 45); z > 0; --z)
            w[at++] = '0';
    size_t before_point = ic_rng_below(rng, (uint32_t)len + 1);
    memcpy(w + at, sig, before_point);
    at += before_point;
    long shift = (long)before_point;
    if (before_point < len || ic_rng_below(rng, 4) == 0) {
        w[at++] = '.';
        if (ic_rng_below(rng, 3) == 0) /* zeros after the point */
            for (uint32_t z = ic_rng_below(rng, 45); z > 0; --z, --shift)
                w[at++] = '0';
        memcpy(w + at, sig + before_point, len - before_point);
        at += len - before_point;
    }
    if (ic_rng_below(rng, 5) != 0) {
        w[at++] = ic_rng_below(rng, 2) ? 'e' : 'E';
        /* the exponent that puts the value near 10^38 (the digits' magnitude is 10^shift), give or take a few */
        long e = 38 - shift + (long)ic_rng_below(rng, 9) - 4;
        uint32_t kind = ic_rng_below(rng, 8);
        if (kind == 0)
            e = (long)ic_rng_below(rng, 2000) - 1000;
        char digits[48];
        if (kind == 1) { /* out of any range */
            size_t n = 0;
            put_digits(rng, digits, &n, 1 + ic_rng_below(rng, 30), 1);
            digits[n] = '\0';
            w[at++] = ic_rng_below(rng, 2) ? '-' : '+';
        } else {
            if (e < 0 || ic_rng_below(rng, 3) == 0)
                w[at++] = e < 0 ? '-' : '+';
            snprintf(digits, sizeof digits, "%.*s%ld", kind == 2 ? (int)ic_rng_below(rng, 12) : 0,
                     "000000000000", e < 0 ? -e : e);
        }
        strcpy(w + at, digits);
        at += strlen(digits);
    }
    w[at] = '\0';
}

/* The OBJ check's numbers (a digit count decides most of them finite as floats, and only those that may
 * reach 10^38 are converted) against their definition: a word of the grammar is finite iff
 * isfinite((float)strtod(word)), and any other word is not a number; 200,000 random words in vt and vn
 * lines, most of them near FLT_MAX in every spelling. */
static void test_obj_numbers_against_strtod(void)
{
    ic_rng rng = ic_rng_make(17, 0, 0, 0);
    char word[512], text[600];
    int wrong = 0, finite_seen = 0, infinite_seen = 0, refused_seen = 0;
    for (int i = 0; i < 200000 && wrong < 10; ++i) {
        random_obj_word(&rng, word);
        if (!word[0])
            continue; /* no word at all */
        const int bare_fraction = i & 1; /* vn lines take an unsigned ".5", vt lines do not */
        const int is_number = obj_grammar(word, bare_fraction);
        const int finite = is_number && isfinite((float)strtod(word, NULL));
        int n = snprintf(text, sizeof text, bare_fraction ? "vn 0 0 %s\n" : "vt 0 %s\n", word);
        FILE *fp = fmemopen(text, (size_t)n, "r");
        ic_error err;
        memset(&err, 0, sizeof err);
        ic_result r = fp ? ic_obj_check(fp, "random.obj", 1000, &err) : IC_ERR_IO;
        if (fp)
            fclose(fp);
        const int got = r == IC_OK ? 1 : r == IC_ERR_PARSE && strstr(err.message, "non-finite") ? 0
                        : r == IC_ERR_PARSE && strstr(err.message, "is not a number") ? -1
                                                                                        : -2;
        const int want = !is_number ? -1 : finite;
        finite_seen += want == 1;
        infinite_seen += want == 0;
        refused_seen += want == -1;
        if (got != want) {
            ++wrong;
            CHECK(0, "OBJ number '%s' in a %s line: the check says %s, strtod and the grammar %s (%s)", word,
                  bare_fraction ? "vn" : "vt", got == 1 ? "finite" : got == 0 ? "not finite" : "not a number",
                  want == 1 ? "finite" : want == 0 ? "not finite" : "not a number", err.message);
        }
    }
    CHECK(finite_seen > 10000 && infinite_seen > 10000 && refused_seen > 1000,
          "random OBJ numbers: %d finite, %d not, %d refused (too few of one kind: nothing tested)", finite_seen,
          infinite_seen, refused_seen);
}

/* Valid files the non-finite checks must let through. */
/* The OBJ check reads the file in chunks of 64 KiB: line ends of every kind (\n, \r\n, \r, \f, NUL and a
 * backslash joining two lines), one \r\n split between two chunks and lines that straddle chunks still count
 * lines as assimp does, so the non-finite vertex after them is reported on its own line. */
static void test_obj_lines_across_chunks(void)
{
    enum { SIZE = 3 * 65536 };
    char *text = malloc(SIZE + 64);
    CHECK(text != NULL, "out of memory");
    if (!text)
        return;
    static const char *const ends[] = {"\n", "\r\n", "\r", "\f"};
    size_t n = 0;
    long line = 1, vertex = 0;
    for (int k = 0; n < SIZE - 64; ++k) {
        /* a vertex line whose \r\n straddles the first chunk boundary */
        const char *end = n + 40 > 65536 && n < 65536 ? "" : ends[k % 4];
        n += (size_t)sprintf(text + n, "v %d.25 %d 0%s", k, k % 7, end);
        ++vertex;
        if (!*end) { /* pad to the boundary, then \r | \n across it */
            while (n < 65535)
                text[n++] = ' ';
            text[n++] = '\r';
            text[n++] = '\n';
        }
        line += 1;
        if (k % 97 == 0) { /* a line joined to the next by a backslash: one vertex, two line ends */
            n += (size_t)sprintf(text + n, "v 1 \\\n2 3\n");
            ++vertex;
            line += 2;
        }
        if (k % 89 == 0) { /* a NUL ends a line too */
            text[n++] = '#';
            text[n++] = '\0';
            line += 1;
        }
    }
    n += (size_t)sprintf(text + n, "v 0 nan 0\n");
    ++vertex;
    char want[64];
    snprintf(want, sizeof want, "lines_across_chunks.obj:%ld:", line);
    char what[64];
    snprintf(what, sizeof what, "vertex %ld has a non-finite coordinate", vertex);
    expect_error(write_tmp("lines_across_chunks.obj", text, (long)n), NULL, IC_ERR_PARSE, want, what, NULL);
    free(text);
}

static void test_finite_attribute_variants(void)
{
    ic_scene *s = NULL;
    ic_error e;
    /* A glTF node of scale 0 hides its mesh (exporters write it so): its normals' transform is singular, and
     * the placement's triangles, all at one point, are dropped; the other placement keeps the file's normal. */
    memset(&e, 0, sizeof e);
    CHECK(ic_scene_load(SCENES "hidden_node.gltf", NULL, &s, &e) == IC_OK && s, "a glTF with a node of scale 0 loads "
          "(%s)", e.message);
    if (s) {
        CHECK(s->triangle_count == 1, "the hidden placement's triangle is dropped (%u triangles)", s->triangle_count);
        for (uint32_t i = 0; s->normals && s->triangle_count == 1 && i < 3; ++i) {
            ic_vec3 n = s->normals[s->triangles[i]];
            CHECK(n.x == 0.0f && n.y == 0.0f && n.z == 1.0f, "the visible triangle's normal is the file's (0, 0, 1): "
                  "(%g, %g, %g)", (double)n.x, (double)n.y, (double)n.z);
        }
        CHECK(s->normals != NULL, "the glTF's normals are kept");
        ic_scene_free(s);
        s = NULL;
    }
    /* OBJ numbers with no digit before the point: assimp reads a signed one ("-.5") in v, vt and vn lines and
     * an unsigned one (".8") in vn lines, whose three words it does not count; (-0.6, 0, 0.8) is of length 1 */
    memset(&e, 0, sizeof e);
    CHECK(ic_scene_load(write_tmp("attr_fraction.obj", "v -.5 0 0\nv 1 0 0\nv 0 1 0\nvt -.5 -.25\nvn -.6 0 .8\n"
                                                       "f 1/1/1 2/1/1 3/1/1\n", -1),
                        NULL, &s, &e) == IC_OK && s,
          "an OBJ with numbers such as -.5 and .8 loads (%s)", e.message);
    if (s) {
        CHECK(s->bounds_min.x == -0.5f, "v -.5 0 0 is at x = -0.5 (bounds from %g)", (double)s->bounds_min.x);
        for (uint32_t i = 0; s->normals && i < s->vertex_count; ++i)
            CHECK(fabsf(s->normals[i].x + 0.6f) < 1e-6f && s->normals[i].y == 0.0f &&
                      fabsf(s->normals[i].z - 0.8f) < 1e-6f,
                  "vn -.6 0 .8 is read as (-0.6, 0, 0.8): (%g, %g, %g)", (double)s->normals[i].x,
                  (double)s->normals[i].y, (double)s->normals[i].z);
        CHECK(s->normals != NULL, "the OBJ's normals are kept");
        ic_scene_free(s);
    }
    /* an unsigned ".5" in a vt line is counted as no component by assimp (which then reads the line wrong or
     * not at all): refused with the line, saying how to write it */
    expect_error(write_tmp("attr_bare_vt.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 .5\nf 1/1 2/1 3/1\n", -1), NULL,
                 IC_ERR_PARSE, "attr_bare_vt.obj:4:", "texture coordinate (vt) 1: '.5' is not a number",
                 "write a 0 before the point");
}

/* The scene file's size limit is the caller's (--max-scene-bytes): one byte over it is refused, naming both
 * sizes and the option, before the file is read; at the limit it loads. */
static void test_scene_size_limit(void)
{
    char text[512];
    int n = snprintf(text, sizeof text, "{\n  \"meshes\": [ { \"path\": \"%s\" } ]\n}\n", SCENES "quad_light.obj");
    const char *path = write_tmp("scene_size_limit.json", text, -1);
    ic_scene_load_options opt = {0};
    opt.allow_outside_paths = 1;
    opt.max_scene_bytes = (uint64_t)n - 1;
    char want[160];
    snprintf(want, sizeof want, "scene_size_limit.json: the scene file is %d bytes, more than the limit of %d bytes",
             n, n - 1);
    expect_error(path, &opt, IC_ERR_INVALID_ARG, want, "raise the limit with --max-scene-bytes", NULL);
    opt.max_scene_bytes = (uint64_t)n;
    ic_scene *s = NULL;
    ic_error e;
    CHECK(ic_scene_load(path, &opt, &s, &e) == IC_OK, "a scene file at --max-scene-bytes loads: %s", e.message);
    ic_scene_free(s);
}

/* A camera or a light that the ray tracer cannot start rays from (Embree asserted and the process
 * aborted) is refused whatever the format; a missing mesh is "not found", not "outside the folder". */
static void test_cameras_lights_and_paths(void)
{
    expect_error(SCENES "errors_camera_far.gltf", NULL, IC_ERR_INVALID_ARG, "errors_camera_far.gltf",
                 "the camera is unusable", "beyond 1e18");
    const char *rad = write_tmp("errors_lamp.rad", "void light l 0 0 3 1 1 1\n"
                                                   "l polygon p 0 0 12 -1 0 -1 1 0 -1 1 0 1 -1 0 1\n", -1);
    char rad_path[1024];
    snprintf(rad_path, sizeof rad_path, "%s", rad);
    ic_scene_load_options lo = {0};
    lo.view = write_tmp("errors_far.vf", "rview -vp 0 -1e30 0 -vd 0 1 0\n", -1);
    expect_error(rad_path, &lo, IC_ERR_INVALID_ARG, "errors_lamp.rad", "the camera is unusable", NULL);
    lo.view = write_tmp("errors_clip.vf", "rview -vp 0 -1 0 -vd 0 1 0 -vo 1e30\n", -1);
    expect_error(rad_path, &lo, IC_ERR_INVALID_ARG, "errors_lamp.rad", "clipping distance", NULL);
    expect_error(write_tmp("errors_nan_light.xml",
                           "<scene version=\"0.6.0\">\n  <shape type=\"rectangle\"/>\n  <emitter type=\"point\">"
                           "<point name=\"position\" x=\"nan\" y=\"0\" z=\"0\"/><rgb name=\"intensity\" "
                           "value=\"1\"/></emitter>\n</scene>\n",
                           -1),
                 NULL, IC_ERR_PARSE, "errors_nan_light.xml:3", "not a finite number", "attribute x");
    expect_error(write_tmp("errors_no_mesh.rad", "void plastic w 0 0 5 1 1 1 0 0\nw mesh m 1 nofile.obj 0 0\n", -1), NULL,
                 IC_ERR_IO, "errors_no_mesh.rad:2", "'nofile.obj' not found", NULL);
}

/* Writes the 2x1 environment map px (RGB, left to right) as a little-endian PFM at path. */
static void write_map(const char *path, const float px[6])
{
    FILE *pf = fopen(path, "wb");
    CHECK(pf != NULL, "write %s", path);
    if (!pf)
        return;
    fputs("PF\n2 1\n-1.0\n", pf);
    fwrite(px, sizeof px[0], 6, pf);
    fclose(pf);
}

/* A radiance, irradiance or intensity above IC_SCENE_MAX_RADIANCE (1e30) is refused with the line that
 * gives it (a constant environment of 3e38 read 0, one of 1e38 half its irradiance: the samples that
 * overflowed were dropped); 1e29 loads and renders finite, the brightest pixel its analytic value. JSON's
 * emission, environment, point, spot and sun lights, an MTL file's Ke, an environment map times its scale. */
static void test_radiance_limit(void)
{
    static const char *const mesh = "mtllib limit_quad.mtl\nusemtl grey\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                    "f 1 2 3 4\n"; /* the unit square facing +z, the fitted camera's side */
    write_tmp("limit_quad.mtl", "newmtl grey\nKd 0.5 0.5 0.5\n", -1);
    write_tmp("limit_quad.obj", mesh, -1);
    static const struct {
        const char *name, *section, *key;
        double brightest; /* the brightest pixel over the value given (0: not checked) */
    } cases[] = {
        {"limit_emission", "\"materials\": {\"grey\": {\"emission\": %s}}", "'emission'", 1.0},
        {"limit_env", "\"environment\": {\"radiance\": [1, %s, 1]}", "'radiance'", 1.0},
        {"limit_point", "\"lights\": [{\"type\": \"point\", \"position\": [0.5, 0.5, 1], \"intensity\": %s}]",
         "'intensity'", 0.0},
        {"limit_spot", "\"lights\": [{\"type\": \"spot\", \"position\": [0.5, 0.5, 1], \"direction\": [0, 0, -1], "
                       "\"intensity\": %s}]", "'intensity'", 0.0},
        /* a Lambertian square of albedo 0.5 lit along its normal: 0.5 E / pi */
        {"limit_sun", "\"lights\": [{\"type\": \"sun\", \"direction\": [0, 0, 1], \"irradiance\": %s}]",
         "'irradiance'", 0.5 / 3.14159265358979},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k)
        for (int ok = 0; ok < 2; ++ok) {
            char section[512], json[1024], file[64], where[80], what[80];
            snprintf(section, sizeof section, cases[k].section, ok ? "1e29" : "1e31");
            snprintf(json, sizeof json, "{\"meshes\": [{\"path\": \"limit_quad.obj\"}],\n %s}\n", section);
            snprintf(file, sizeof file, "%s%s.json", cases[k].name, ok ? "_ok" : "");
            const char *path = write_tmp(file, json, -1);
            if (!ok) {
                snprintf(where, sizeof where, "%s:2:", file);
                snprintf(what, sizeof what, "%s is 1e+31, above 1e+30", cases[k].key);
                expect_error(path, NULL, IC_ERR_INVALID_ARG, where, what, "scale the scene's lights down");
                continue;
            }
            ic_scene *sc = NULL;
            ic_error e = {0};
            CHECK(test_load_scene(path, NULL, 16, 16, 0, &sc, &e) == IC_OK, "%s loads: %s", file, e.message);
            test_check_renders_finite(file, sc, cases[k].brightest * 1e29);
        }
    /* an MTL file's emission, with its line */
    write_tmp("limit_hot.obj", "mtllib limit_hot.mtl\nusemtl grey\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n", -1);
    write_tmp("limit_hot.mtl", "newmtl grey\nKd 0.5 0.5 0.5\nKe 1 1e31 1\n", -1);
    expect_error(IC_TEST_TMP "/limit_hot.obj", NULL, IC_ERR_INVALID_ARG, "limit_hot.mtl:3:",
                 "material 'grey': Ke (emission) is 1e+31, above 1e+30", "scale the scene's lights down");
    write_tmp("limit_hot.mtl", "newmtl grey\nKd 0.5 0.5 0.5\nKe 1e29 1e29 1e29\n", -1);
    ic_scene *sc = NULL;
    ic_error e = {0};
    CHECK(test_load_scene(IC_TEST_TMP "/limit_hot.obj", NULL, 16, 16, 0, &sc, &e) == IC_OK, "Ke 1e29 loads: %s",
          e.message);
    test_check_renders_finite("Ke 1e29", sc, 1e29);
    /* an environment map's texels times its scale: 1e20 × 1e11 (within the float range) is refused */
    write_map(IC_TEST_TMP "/limit_map.pfm", (const float[6]){1e20f, 1e20f, 1e20f, 1e20f, 1e20f, 1e20f});
    expect_error(write_tmp("limit_map.json", "{\"meshes\": [{\"path\": \"limit_quad.obj\"}],\n"
                                             " \"environment\": {\"map\": \"limit_map.pfm\", \"scale\": [1, 1e11, 1]}}\n",
                           -1),
                 NULL, IC_ERR_INVALID_ARG, "limit_map.json:2:", "times the scale (1e+20 × 1e+11) is 1e+31, above 1e+30",
                 "give a smaller scale");
    const char *map_ok = write_tmp("limit_map_ok.json", "{\"meshes\": [{\"path\": \"limit_quad.obj\"}],\n"
                                                        " \"environment\": {\"map\": \"limit_map.pfm\", \"scale\": 1e9}}\n",
                                   -1);
    CHECK(test_load_scene(map_ok, NULL, 16, 16, 0, &sc, &e) == IC_OK, "the map times 1e9 loads: %s", e.message);
    test_check_renders_finite("a map of 1e20 times 1e9", sc, 1e29);
}

int main(void)
{
    test_radiance_limit();
    test_obj_numbers_against_strtod();
    test_cameras_lights_and_paths();
#ifdef IC_TEST_WRAP_ASSIMP
    test_tangent_step_fails();
#endif
    /* A scene file that is not there: the open's own reason, not one left by resolving the path. */
    expect_error(SCENES "no-such-scene.json", NULL, IC_ERR_IO, "no-such-scene.json", strerror(ENOENT),
                 "resolved to");
    /* JSON syntax: the missing comma after line 4 is found where "fov_y" starts, line 5 */
    expect_error(SCENES "malformed.json", NULL, IC_ERR_PARSE, "malformed.json:5:", "malformed JSON", NULL);
    /* one JSON object per file, each section once (issue "Hardening", item 6) */
    expect_error(SCENES "trailing_garbage.json", NULL, IC_ERR_PARSE, "trailing_garbage.json:4:", "closing brace",
                 "remove it");
    expect_error(SCENES "duplicate_section.json", NULL, IC_ERR_PARSE, "duplicate_section.json:5:",
                 "\"render\" given twice (first at line 3)", "merge");
    /* Emitters whose power leaves the float range of the light tables: refused, naming the scene and what
     * to do (a lamp 1e18 across at 1000 W/(m² sr): π·A·L ≈ 3e39). Two point lights of 2e37 W/sr (2.5e38
     * each, 5e38 together) are refused before, the first one as above the radiance limit (1e30). */
    write_tmp("huge_lamp.mtl", "newmtl lamp\nKd 0 0 0\nKe 1000 1000 1000\n", -1);
    expect_error(write_tmp("huge_lamp.obj", "mtllib huge_lamp.mtl\nusemtl lamp\nv 1e18 0 0\nv 0 1e18 0\nv 0 0 1e18\n"
                                            "f 1 3 2\n", -1),
                 NULL, IC_ERR_INVALID_ARG, "huge_lamp.obj: the emitters' power", "material 'lamp'",
                 "beyond the float range");
    {
        write_tmp("plain_tri.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 3 2\n", -1);
        char json[1024];
        snprintf(json, sizeof json,
                 "{\"meshes\": [{\"path\": \"%s\"}],\n \"lights\": [\n"
                 "  {\"type\": \"point\", \"position\": [0, 1, 0], \"intensity\": [2e37, 2e37, 2e37]},\n"
                 "  {\"type\": \"point\", \"position\": [0, 1, 1], \"intensity\": [2e37, 2e37, 2e37]}]}\n",
                 "plain_tri.obj");
        expect_error(write_tmp("huge_points.json", json, -1), NULL, IC_ERR_INVALID_ARG,
                     "huge_points.json:3: 'intensity' is 2e+37, above 1e+30", "scale the scene's lights down", NULL);
    }
    /* an environment map with a negative texel: refused, naming the map and the texel */
    {
        FILE *pf = fopen(IC_TEST_TMP "/scene_errors_negsky.pfm", "wb");
        FILE *js = fopen(IC_TEST_TMP "/scene_errors_negsky.json", "w");
        CHECK(pf && js, "write the sky and its scene");
        if (pf && js) {
            const float px[6] = {1.0f, 1.0f, 1.0f, 0.5f, -2.0f, 0.5f}; /* 2x1, little-endian (scale < 0) */
            fputs("PF\n2 1\n-1.0\n", pf);
            fwrite(px, sizeof px[0], 6, pf);
            fprintf(js, "{\n  \"meshes\": [ { \"path\": \"%s\" } ],\n  \"environment\": { \"map\": "
                        "\"scene_errors_negsky.pfm\" }\n}\n",
                    SCENES "quad_light.obj");
        }
        if (pf)
            fclose(pf);
        if (js)
            fclose(js);
        expect_error(IC_TEST_TMP "/scene_errors_negsky.json", NULL, IC_ERR_INVALID_ARG, "scene_errors_negsky.json:3:",
                     "'scene_errors_negsky.pfm': texel (1, 0) has a green value of -2", "fix the map");
        /* the same map as a Mitsuba envmap, and a negative scale */
        ic_scene_load_options outside = {0};
        outside.allow_outside_paths = 1;
        static const char *const mts[2] = {"", "    <float name=\"scale\" value=\"-1\"/>\n"};
        for (int k = 0; k < 2; ++k) {
            char xml[1024];
            snprintf(xml, sizeof xml, "<scene version=\"0.6.0\">\n  <shape type=\"obj\"><string name=\"filename\" "
                     "value=\"%s\"/></shape>\n  <emitter type=\"envmap\">\n    <string name=\"filename\" "
                     "value=\"scene_errors_negsky.pfm\"/>\n%s  </emitter>\n</scene>\n", SCENES "quad_light.obj", mts[k]);
            expect_error(write_tmp("scene_errors_negsky.xml", xml, -1), &outside, IC_ERR_INVALID_ARG,
                         "scene_errors_negsky.xml:3:", k ? "envmap: a negative or non-finite scale; give"
                                                         : "'scene_errors_negsky.pfm': texel (1, 0) has a green value of -2",
                         NULL);
        }
    }
    /* a map whose texel times the scale leaves the float range (1e30 × 1e10): refused, in JSON and Mitsuba */
    {
        write_map(IC_TEST_TMP "/scene_errors_bigsky.pfm", (const float[6]){1.0f, 1.0f, 1.0f, 1e30f, 1.0f, 1.0f});
        write_tmp("scene_errors_bigsky_tri.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 3 2\n", -1);
        expect_error(write_tmp("scene_errors_bigsky.json",
                               "{\n  \"meshes\": [ { \"path\": \"scene_errors_bigsky_tri.obj\" } ],\n"
                               "  \"environment\": { \"map\": \"scene_errors_bigsky.pfm\", \"scale\": [1e10, 1, 1] }\n}\n",
                               -1),
                     NULL, IC_ERR_INVALID_ARG, "scene_errors_bigsky.json:3:",
                     "'scene_errors_bigsky.pfm': texel (1, 0) times the scale", "give a smaller scale");
        expect_error(write_tmp("scene_errors_bigsky.xml",
                               "<scene version=\"0.6.0\">\n  <shape type=\"obj\"><string name=\"filename\" "
                               "value=\"scene_errors_bigsky_tri.obj\"/></shape>\n  <emitter type=\"envmap\">\n"
                               "    <string name=\"filename\" value=\"scene_errors_bigsky.pfm\"/>\n"
                               "    <float name=\"scale\" value=\"1e10\"/>\n  </emitter>\n</scene>\n",
                               -1),
                     NULL, IC_ERR_INVALID_ARG, "scene_errors_bigsky.xml:3:", "times the scale", "smaller scale");
        /* the same map at scale 1 loads */
        ic_scene *ok = NULL;
        ic_error e = {0};
        CHECK(ic_scene_load(write_tmp("scene_errors_bigsky1.json",
                                      "{\"meshes\": [{\"path\": \"scene_errors_bigsky_tri.obj\"}],\n"
                                      " \"environment\": {\"map\": \"scene_errors_bigsky.pfm\"}}\n",
                                      -1),
                            NULL, &ok, &e) == IC_OK,
              "the map at scale 1 loads: %s", e.message);
        ic_scene_free(ok);
    }
    /* a mesh that does not exist: the line of its "path" and the absolute path it resolved to */
    expect_error(SCENES "missing_mesh.json", NULL, IC_ERR_IO, "missing_mesh.json:5:",
                 "mesh 'does-not-exist.obj' not found", IC_SOURCE_DIR "/tests/scenes/does-not-exist.obj");
    expect_error(SCENES "shared_missing.json", NULL, IC_ERR_IO, "shared_missing.json:3:", "IRRCACHE_SCENES",
                 "no-such-scene/model.obj");
    /* a texture named by the MTL that does not exist: names the texture and the mesh */
    expect_error(SCENES "missing_texture.json", NULL, IC_ERR_IO, "missing_texture.obj", "no-such-wood.png",
                 "not found");
    /* a NaN vertex: the OBJ line and the vertex number as the file counts them */
    expect_error(SCENES "nan_vertex.json", NULL, IC_ERR_PARSE, "nan_vertex.obj:6:", "vertex 4 has a non-finite",
                 "fix or remove it");
    expect_error(SCENES "nan_vertex.obj", NULL, IC_ERR_PARSE, "nan_vertex.obj:6:", "vertex 4", NULL);
    /* PLY: a NaN vertex no face uses (assimp drops it silently), binary and ascii (issue "Hardening", item 6) */
    expect_error(SCENES "nan_vertex.ply", NULL, IC_ERR_PARSE, "nan_vertex.ply: vertex 4 (of 4, binary)",
                 "non-finite coordinate (nan)", "fix or remove it");
    {
        FILE *fp = fopen(IC_TEST_TMP "/scene_errors_nan_ascii.ply", "w");
        CHECK(fp != NULL, "write an ascii PLY");
        if (fp) {
            fputs("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n2 0 0\n0 2 0\n"
                  "1 inf 0\n3 0 1 2\n",
                  fp);
            fclose(fp);
        }
        expect_error(IC_TEST_TMP "/scene_errors_nan_ascii.ply", NULL, IC_ERR_PARSE, "scene_errors_nan_ascii.ply:13:",
                     "vertex 4 has a non-finite coordinate (inf)", NULL);
    }
    /* MTL colours that are negative or NaN: an error naming the MTL file, its line and the material, not a
     * silent zero (issue "Hardening", item 6) */
    expect_error(SCENES "bad_color.obj", NULL, IC_ERR_PARSE, "bad_color.mtl:6:", "material 'paint'",
                 "Kd (diffuse) has a negative");
    expect_error(SCENES "bad_emission.obj", NULL, IC_ERR_PARSE, "bad_emission.mtl:7:", "material 'lamp'",
                 "Ke (emission) has a negative or non-finite value (2 nan 2)");
    expect_error(SCENES "bad_color.gltf", NULL, IC_ERR_PARSE, "bad_color.gltf: material 'lamp_pbr'",
                 "has a negative or non-finite value", NULL);
    /* a mesh with no usable triangle (it would render nothing, silently): the file and the count dropped */
    expect_error(SCENES "only_degenerate.obj", NULL, IC_ERR_PARSE, "only_degenerate.obj: no usable triangle",
                 "(2 of zero area dropped", "fix the geometry");
    /* vertices a transform takes out of range: the scene line of that transform, not a "degenerate emitter" */
    expect_error(SCENES "overflow_transform.json", NULL, IC_ERR_INVALID_ARG, "overflow_transform.json:5:",
                 "the transform of '", "quad_light.obj' takes its vertex 1");
    {
        FILE *fp = fopen(IC_TEST_TMP "/scene_errors_far.obj", "w");
        CHECK(fp != NULL, "write a far OBJ");
        if (fp) {
            fputs("v 0 0 0\nv 1e30 0 0\nv 0 1 0\nf 1 2 3\n", fp);
            fclose(fp);
        }
        expect_error(IC_TEST_TMP "/scene_errors_far.obj", NULL, IC_ERR_INVALID_ARG, "scene_errors_far.obj: vertex 2",
                     "beyond the largest coordinate 1e+18", "scale the mesh down");
    }
    /* sizes from headers against the limits before anything is allocated (issue "Hardening": a 16000^2 PNG
     * texture, a PLY header claiming 10^9 vertices); the message names the limit and the option */
    expect_error(SCENES "huge_texture.obj", NULL, IC_ERR_UNSUPPORTED,
                 "huge_texture.png: 16000x16000 is 256000000 pixels, more than the limit of 67108864",
                 "material 'painted'", "--max-texture-pixels");
    expect_error(SCENES "huge_header.ply", NULL, IC_ERR_UNSUPPORTED,
                 "huge_header.ply: the PLY header declares 1000000000 of element 'vertex', more than the limit of "
                 "16777216",
                 "--max-mesh-elements", NULL);
    {
        ic_scene_load_options small = {0};
        small.max_texture_pixels = 3; /* checker2x2.pfm has 4 */
        expect_error(SCENES "plain_quad.obj", &small, IC_ERR_UNSUPPORTED, "checker2x2.pfm: 2x2 is 4 pixels",
                     "limit of 3", "--max-texture-pixels");
        small.max_texture_pixels = 0;
        small.max_mesh_elements = 2; /* triangle.ply: 3 vertices */
        expect_error(SCENES "triangle.ply", &small, IC_ERR_UNSUPPORTED, "declares 3 of element 'vertex'",
                     "limit of 2", "--max-mesh-elements");
        expect_error(SCENES "plain_quad.obj", &small, IC_ERR_UNSUPPORTED, "plain_quad.obj:5: more than 2 vertices",
                     "--max-mesh-elements", NULL);
        small.max_mesh_elements = 4;
        ic_scene *ok = NULL;
        ic_error e;
        CHECK(ic_scene_load(SCENES "plain_quad.obj", &small, &ok, &e) == IC_OK, "at the limits: loads (%s)",
              e.message);
        ic_scene_free(ok);
    }
    /* an emitter whose only triangle is degenerate */
    expect_error(SCENES "zero_area_light.json", NULL, IC_ERR_PARSE, "zero_area_light.obj", "'lamp'",
                 "zero total area");
    /* an emitter with only a line and a point (no surface), beside a point light that would light the scene */
    expect_error(SCENES "line_light.json", NULL, IC_ERR_PARSE, "line_light.obj", "'lamp'",
                 "all 2 of its faces are degenerate triangles, lines or points");
    /* overrides: unknown material name, unknown type */
    expect_error(SCENES "unknown_material.json", NULL, IC_ERR_INVALID_ARG, "unknown_material.json:5:", "'marble'",
                 "'grey'");
    expect_error(SCENES "bad_material_type.json", NULL, IC_ERR_INVALID_ARG, "bad_material_type.json:6:", "'velvet'",
                 "diffuse");
    /* camera: negative and zero resolution, fov out of (0, 180) */
    expect_error(SCENES "bad_resolution.json", NULL, IC_ERR_INVALID_ARG, "bad_resolution.json:6:", "'height' is -480",
                 NULL);
    expect_error(SCENES "zero_resolution.json", NULL, IC_ERR_INVALID_ARG, "zero_resolution.json:3:", "'width' is 0",
                 NULL);
    expect_error(SCENES "bad_fov.json", NULL, IC_ERR_INVALID_ARG, "bad_fov.json:6:", "'fov_y' = 180", "(0, 180)");
    /* unknown keys list the valid ones; unknown light type */
    expect_error(SCENES "unknown_key.json", NULL, IC_ERR_PARSE, "unknown_key.json:6:", "'samples'",
                 "valid keys: spp, max_depth, seed, exposure");
    expect_error(SCENES "bad_light.json", NULL, IC_ERR_INVALID_ARG, "bad_light.json:5:", "'laser'", NULL);
    expect_error(SCENES "env_missing.json", NULL, IC_ERR_IO, "env_missing.json:3:", "no-such-sky.exr", NULL);
    /* files and options */
    expect_error(SCENES "no-such-scene.json", NULL, IC_ERR_IO, "no-such-scene.json", "check the path", NULL);
    expect_error(SCENES "no-such-mesh.obj", NULL, IC_ERR_IO, "no-such-mesh.obj", "not found", NULL);
    expect_error(SCENES "checker2x2.pfm", NULL, IC_ERR_UNSUPPORTED, "checker2x2.pfm", ".json", NULL);
    ic_scene_load_options opt = {0};
    opt.width = -1;
    expect_error(SCENES "quad_light.obj", &opt, IC_ERR_INVALID_ARG, "quad_light.obj", "negative", NULL);

    /* Not a file (issue "Hardening", item 4): looked at before reading, so a pipe does not hang the load
     * (the alarm fails the test if it does) and a folder is called a folder. */
    alarm(60);
    const char *dir_json = IC_TEST_TMP "/scene_errors_dir.json", *fifo_json = IC_TEST_TMP "/scene_errors_fifo.json",
               *zero_json = IC_TEST_TMP "/scene_errors_zero.json", *fifo_obj = IC_TEST_TMP "/scene_errors_fifo.obj";
    rmdir(dir_json);
    unlink(fifo_json);
    unlink(zero_json);
    unlink(fifo_obj);
    CHECK(mkdir(dir_json, 0755) == 0 && mkfifo(fifo_json, 0644) == 0 && symlink("/dev/zero", zero_json) == 0 &&
              mkfifo(fifo_obj, 0644) == 0,
          "scratch folder, pipes and link");
    expect_error(dir_json, NULL, IC_ERR_INVALID_ARG, "scene_errors_dir.json", "is a folder", NULL);
    expect_error(IC_TEST_TMP, NULL, IC_ERR_INVALID_ARG, IC_TEST_TMP, "is a folder", NULL);
    expect_error(fifo_json, NULL, IC_ERR_INVALID_ARG, "scene_errors_fifo.json", "is not a regular file", NULL);
    expect_error(fifo_obj, NULL, IC_ERR_INVALID_ARG, "scene_errors_fifo.obj", "is not a regular file", NULL);
    expect_error(zero_json, NULL, IC_ERR_INVALID_ARG, "scene_errors_zero.json", "is not a regular file", NULL);
    expect_error("/dev/zero", NULL, IC_ERR_INVALID_ARG, "/dev/zero", "is not a regular file", NULL);
    {
        /* the files a scene names: an environment map and a mesh that are pipes */
        const char *fifo_pfm = IC_TEST_TMP "/scene_errors_fifo.pfm", *fifo_mesh = IC_TEST_TMP "/scene_errors_fifo2.obj";
        unlink(fifo_pfm);
        unlink(fifo_mesh);
        CHECK(mkfifo(fifo_pfm, 0644) == 0 && mkfifo(fifo_mesh, 0644) == 0, "pipes named by a scene");
        static char json[1024];
        snprintf(json, sizeof json, "{\n  \"meshes\": [ { \"path\": \"%s\" } ],\n  \"environment\": { \"map\": "
                 "\"scene_errors_fifo.pfm\" }\n}\n", SCENES "quad_light.obj");
        ic_scene_load_options outside = {0};
        outside.allow_outside_paths = 1;
        expect_error(write_tmp("scene_errors_fifo_env.json", json, -1), &outside, IC_ERR_IO,
                     "environment map 'scene_errors_fifo.pfm' is not a regular file", NULL, NULL);
        expect_error(write_tmp("scene_errors_fifo_mesh.json", "{\n  \"meshes\": [ { \"path\": "
                               "\"scene_errors_fifo2.obj\" } ]\n}\n", -1), NULL, IC_ERR_IO,
                     "mesh 'scene_errors_fifo2.obj' is not a regular file", NULL, NULL);
        ic_image img;
        ic_error ierr;
        CHECK(ic_image_read(fifo_pfm, &img, &ierr) == IC_ERR_INVALID_ARG && strstr(ierr.message, "not a regular file"),
              "ic_image_read of a pipe: refused at once: %s", ierr.message);
    }
    alarm(0);
    const char *big_json = IC_TEST_TMP "/scene_errors_big.json"; /* sparse: 65 MiB on no disk */
    FILE *fb = fopen(big_json, "wb");
    CHECK(fb && ftruncate(fileno(fb), (off_t)65 << 20) == 0, "sparse scene file");
    if (fb)
        fclose(fb);
    expect_error(big_json, NULL, IC_ERR_INVALID_ARG, "scene_errors_big.json: the scene file is 68157440 bytes (65.0 "
                 "MiB), more than the limit of 67108864 bytes (64.0 MiB)", "mesh files", "--max-scene-bytes");
    remove(big_json);
    rmdir(dir_json);
    unlink(fifo_json);
    unlink(zero_json);
    unlink(fifo_obj);

    ic_scene *s = NULL;
    ic_error err;
    CHECK(ic_scene_load(NULL, NULL, &s, &err) == IC_ERR_INVALID_ARG && s == NULL, "NULL path");
    CHECK(ic_scene_load(SCENES "quad_light.obj", NULL, NULL, NULL) == IC_ERR_INVALID_ARG, "NULL out, NULL err");
    test_glb_lengths();
    test_hostile_meshes();
    test_scene_size_limit();
    test_non_finite_attributes();
    test_non_finite_tangents();
    test_finite_attribute_variants();
    test_obj_lines_across_chunks();
    test_ply_face_texcoords();
    TEST_MAIN_END();
}
