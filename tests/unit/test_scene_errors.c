/*
 * test_scene_errors.c — every class of bad scene input gives the right ic_result and a one-line message
 * that names the file, the line (JSON and OBJ) and what to do; *out stays NULL and nothing leaks.
 */
#include "scene/scene.h"
#include "test_util.h"

#include <errno.h>
#include <string.h>
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
    /* A header that declares more than the file holds (the fuzz target's input). */
    expect_error(IC_SOURCE_DIR "/tests/fuzz/regress/mesh_glb/assimp_2_8gb_alloc.glb", NULL, IC_ERR_PARSE,
                 "assimp_2_8gb_alloc.glb", "declares 1016 bytes", "holds 516");
}

int main(void)
{
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
                 "67108864",
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
        expect_error(SCENES "plain_quad.obj", &small, IC_ERR_UNSUPPORTED, "plain_quad.obj: 4 vertices",
                     "limit of 2", "--max-mesh-elements");
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
    /* overrides: unknown material name, unknown type */
    expect_error(SCENES "unknown_material.json", NULL, IC_ERR_INVALID_ARG, "unknown_material.json:5:", "'marble'",
                 "'grey'");
    expect_error(SCENES "bad_material_type.json", NULL, IC_ERR_INVALID_ARG, "bad_material_type.json:6:", "'plastic'",
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
    expect_error(SCENES "bad_light.json", NULL, IC_ERR_INVALID_ARG, "bad_light.json:5:", "'spot'", NULL);
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
    alarm(0);
    const char *big_json = IC_TEST_TMP "/scene_errors_big.json"; /* sparse: 65 MiB on no disk */
    FILE *fb = fopen(big_json, "wb");
    CHECK(fb && ftruncate(fileno(fb), (off_t)65 << 20) == 0, "sparse scene file");
    if (fb)
        fclose(fb);
    expect_error(big_json, NULL, IC_ERR_INVALID_ARG, "scene_errors_big.json", "64 MiB limit", "mesh files");
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
    TEST_MAIN_END();
}
