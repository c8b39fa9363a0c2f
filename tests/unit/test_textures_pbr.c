/*
 * test_textures_pbr.c — roughness, metallic and normal-map textures, against analytic answers and against
 * the untextured materials they must reduce to:
 *   1. a constant roughness texture renders as the material with that roughness as a factor;
 *   2. a metallic texture 0 on one half and 1 on the other: the halves render as the plastic and as the
 *      conductor of F0 = base colour (glTF 2.0's metallic blend at its ends);
 *   3. a constant normal map tilting the normal by a known angle under a directional light: the Lambert
 *      radiance scales by the cosine between the tilted normal and the light (direct light only, exact);
 *      the same map on a mesh whose v runs the other way tilts the other way (the bitangent's sign), with
 *      tangents from the mesh's importer (MTL `norm`) and from the triangle's texture coordinates;
 *   4. normal maps in the Cornell box: the cache's final render agrees with the path tracer within the
 *      noise and 1 and 2 threads give the same image; under a uniform sky of radiance L a white bumpy
 *      surface stays below L (normal mapping creates no energy);
 *   5. the same through glTF files (assimp): a metallicRoughnessTexture of metallic 1 renders as the
 *      conductor of metallicFactor 1, and a normalTexture tilts the normal as in 3;
 *   6. a Mitsuba `normalmap` BSDF tilts the normal as in 3;
 *   7. a missing and a malformed texture give a one-line error naming the scene file and the texture.
 */
#include "test_util.h"

#include "test_render_util.h"

#include "core/microfacet.h"
#include "irrcache/image.h"
#include "scene/scene.h"

#include <stdio.h>
#include <string.h>

#define PI_F 3.14159265f

/* A w×h texture file of values (PFM: stored as given, no sRGB curve), texel (x, y) from fn. */
static void write_texture(const char *path, int w, int h, void (*fn)(int x, int y, int w, float rgb[3]))
{
    ic_image img = {0};
    if (ic_image_create(&img, w, h) != IC_OK)
        exit(1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            fn(x, y, w, &img.rgb[3 * ((size_t)y * w + x)]);
    ic_error err = {0};
    if (ic_image_write(path, &img, NULL, &err) != IC_OK) {
        fprintf(stderr, "%s\n", err.message);
        exit(1);
    }
    ic_image_free(&img);
}

static void tex_rough_half(int x, int y, int w, float c[3]) /* roughness factor × 0.5 */
{
    (void)x, (void)y, (void)w;
    c[0] = 0.0f, c[1] = 0.5f, c[2] = 0.0f;
}
static void tex_metal_halves(int x, int y, int w, float c[3]) /* metallic 0 on the left half, 1 on the right */
{
    (void)y;
    c[0] = 0.0f, c[1] = 1.0f, c[2] = x < w / 2 ? 0.0f : 1.0f;
}
static float g_tilt = 0.0f; /* normal map: tilt towards +x (tangent) when g_tilt_axis 0, +y (bitangent) if 1 */
static int g_tilt_axis = 0;
static void tex_tilt(int x, int y, int w, float c[3])
{
    (void)x, (void)y, (void)w;
    float s = sinf(g_tilt), co = cosf(g_tilt);
    c[0] = 0.5f + 0.5f * (g_tilt_axis == 0 ? s : 0.0f);
    c[1] = 0.5f + 0.5f * (g_tilt_axis == 1 ? s : 0.0f);
    c[2] = 0.5f + 0.5f * co;
}
static void tex_bumps(int x, int y, int w, float c[3]) /* tilts of up to 35° in a checker of directions */
{
    (void)w;
    float a = 0.6f * sinf(1.7f * (float)x + 0.9f * (float)y), b = 0.6f * cosf(1.3f * (float)y - 0.4f * (float)x);
    float n[3] = {a, b, 1.0f}, l = sqrtf(a * a + b * b + 1.0f);
    for (int k = 0; k < 3; ++k)
        c[k] = 0.5f + 0.5f * n[k] / l;
}

/* The plane y = 0, x and z in [-1, 1], facing +y, u = (x+1)/2 and v = (z+1)/2 (v reversed if flip_v), with
 * material "floor" (MTL text mtl_extra appended to its definition). */
static void write_plane(const char *name, int flip_v, const char *mtl_extra)
{
    char path[512], text[1024];
    snprintf(path, sizeof path, IC_TEST_TMP "/%s.mtl", name);
    snprintf(text, sizeof text, "newmtl floor\nKd 0.5 0.5 0.5\n%s", mtl_extra);
    test_write_file(path, text);
    float v0 = flip_v ? 1.0f : 0.0f, v1 = flip_v ? 0.0f : 1.0f;
    snprintf(text, sizeof text,
             "mtllib %s.mtl\nusemtl floor\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n"
             "vt 0 %g\nvt 1 %g\nvt 1 %g\nvt 0 %g\nvn 0 1 0\n"
             "f 1/1/1 3/3/1 2/2/1\nf 1/1/1 4/4/1 3/3/1\n",
             name, (double)v0, (double)v0, (double)v1, (double)v1);
    snprintf(path, sizeof path, IC_TEST_TMP "/%s.obj", name);
    test_write_file(path, text);
}

/* Writes the JSON scene `name` looking straight down at the plane mesh, with material override `mat` and
 * lights `lights`; returns its path in out. */
static void write_scene(const char *name, const char *mesh, const char *mat, const char *lights, char *out, size_t size)
{
    char text[4096];
    snprintf(text, sizeof text,
             "{\n"
             "  \"camera\": {\"eye\": [0, 1, 0], \"target\": [0, 0, 0], \"up\": [0, 0, -1],\n"
             "             \"fov_y\": 60, \"width\": 24, \"height\": 24},\n"
             "  \"meshes\": [{\"path\": \"%s.obj\"}],\n"
             "  \"materials\": {\"floor\": %s},\n"
             "  %s\n"
             "}\n",
             mesh, mat, lights);
    snprintf(out, size, IC_TEST_TMP "/%s.json", name);
    test_write_file(out, text);
}

/* Renders scene_path; returns 1 and the image, or 0. */
static int render(const char *scene_path, ic_integrator integ, int spp, int threads, ic_image *img)
{
    ic_render_options opt = {0};
    opt.integrator = integ;
    opt.spp = spp;
    opt.threads = threads;
    return test_render(scene_path, 0, 0, &opt, img, NULL);
}

/* Mean of channel c over columns [x0, x1) of the image's middle rows (the plane fills the whole view). */
static double region_mean(const ic_image *img, int x0, int x1, int c)
{
    double s = 0.0;
    int n = 0;
    for (int y = 2; y < img->height - 2; ++y)
        for (int x = x0; x < x1; ++x, ++n)
            s += img->rgb[3 * ((size_t)y * img->width + x) + c];
    return n ? s / n : 0.0;
}

static double render_mean(const char *name, const char *mesh, const char *mat, const char *lights, ic_integrator integ,
                          int spp, int x0, int x1)
{
    char path[512];
    write_scene(name, mesh, mat, lights, path, sizeof path);
    ic_image img = {0};
    if (!render(path, integ, spp, 1, &img))
        return -1.0;
    double m = region_mean(&img, x0, x1, 1);
    ic_image_free(&img);
    if (getenv("IC_TEST_VERBOSE"))
        printf("%s: %.6f\n", name, m);
    return m;
}

static const char *SKY = "\"environment\": {\"radiance\": [2, 2, 2]}";

static void test_constant_roughness(void)
{
    write_plane("tx_plane", 0, "");
    write_texture(IC_TEST_TMP "/tx_rough.pfm", 4, 4, tex_rough_half);
    /* α = alpha·g² = 0.72·0.25 = 0.18 */
    static const char *types[2] = {"conductor\", \"ks\": [0.9, 0.6, 0.3]", "plastic\", \"kd\": [0.5, 0.4, 0.3]"};
    for (int t = 0; t < 2; ++t) {
        char textured[256], plain[256];
        snprintf(textured, sizeof textured, "{\"type\": \"%s, \"alpha\": 0.72, \"roughness_texture\": \"tx_rough.pfm\"}",
                 types[t]);
        snprintf(plain, sizeof plain, "{\"type\": \"%s, \"alpha\": 0.18}", types[t]);
        double a = render_mean("tx_rough_tex", "tx_plane", textured, SKY, IC_INTEGRATOR_PT, 16, 0, 24);
        double b = render_mean("tx_rough_plain", "tx_plane", plain, SKY, IC_INTEGRATOR_PT, 16, 0, 24);
        /* the same random numbers: only rounding (and the plastic's coat table, tabulated every 1/31 in
         * roughness, 0.424 → 0.419) differ */
        double tol = t == 0 ? 1e-4 : 5e-3;
        CHECK(a > 0.0 && fabs(a - b) <= tol * b, "%s: a constant roughness texture renders %g, the factor %g",
              t == 0 ? "conductor" : "plastic", a, b);
    }
}

/* Two rough plastics with textured roughness, coat indices 1 (a coat that reflects nothing) and 1.5: each
 * gets the coat tables of its own index, the second not the first's (they are shared between materials of
 * one index only). */
static void test_coat_tables_per_index(void)
{
    test_write_file(IC_TEST_TMP "/tx_two.mtl", "newmtl one\nKd 0.5 0.5 0.5\nnewmtl glass\nKd 0.5 0.5 0.5\n");
    test_write_file(IC_TEST_TMP "/tx_two.obj",
                    "mtllib tx_two.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                    "vn 0 1 0\nusemtl one\nf 1/1/1 3/3/1 2/2/1\nusemtl glass\nf 1/1/1 4/4/1 3/3/1\n");
    write_texture(IC_TEST_TMP "/tx_rough.pfm", 4, 4, tex_rough_half);
    char text[1024];
    snprintf(text, sizeof text,
             "{\"camera\": {\"eye\": [0, 1, 0], \"target\": [0, 0, 0], \"up\": [0, 0, -1], \"width\": 8, "
             "\"height\": 8},\n \"meshes\": [{\"path\": \"tx_two.obj\"}],\n \"materials\": {"
             "\"one\": {\"type\": \"plastic\", \"ior\": 1.0, \"alpha\": 0.5, \"roughness_texture\": \"tx_rough.pfm\"}, "
             "\"glass\": {\"type\": \"plastic\", \"ior\": 1.5, \"alpha\": 0.5, \"roughness_texture\": \"tx_rough.pfm\"}},\n"
             " %s}\n", SKY);
    test_write_file(IC_TEST_TMP "/tx_two.json", text);
    ic_scene *scene = NULL;
    ic_error err = {0};
    CHECK(test_load_scene(IC_TEST_TMP "/tx_two.json", NULL, 0, 0, 0, &scene, &err) == IC_OK, "two plastics: %s",
          err.message);
    if (!scene)
        return;
    int checked = 0;
    for (uint32_t m = 0; m < scene->material_count; ++m) {
        const ic_material *mat = &scene->materials[m];
        if (mat->type != IC_MAT_PLASTIC || !mat->coat_albedo_rough)
            continue;
        ++checked;
        float want[IC_COAT_TABLE], avg, got_avg, r = 16.0f / (IC_COAT_ROUGH_STEPS - 1); /* one of the steps */
        ic_coat_albedo_table(mat->ior, r * r, want, &avg);
        const float *got = ic_scene_coat_table(mat, r * r, &got_avg);
        int same = got_avg == avg;
        for (int k = 0; k < IC_COAT_TABLE; ++k)
            same &= got[k] == want[k];
        CHECK(same, "the plastic of index %g has another index's coat table (mean %g, its own %g)", (double)mat->ior,
              (double)got_avg, (double)avg);
    }
    CHECK(checked == 2, "%d textured plastics found, 2 expected", checked);
    ic_scene_free(scene);
}

static void test_metallic_halves(void)
{
    write_texture(IC_TEST_TMP "/tx_metal.pfm", 64, 1, tex_metal_halves);
    const char *lights = "\"environment\": {\"radiance\": [2, 2, 2]}, \"lights\": [{\"type\": \"sun\", "
                         "\"direction\": [0.3, 1, 0.2], \"irradiance\": [3, 3, 3]}]";
    const char *textured = "{\"type\": \"plastic\", \"kd\": [0.8, 0.5, 0.2], \"alpha\": 0.2, "
                           "\"metallic_texture\": \"tx_metal.pfm\"}";
    const char *plastic = "{\"type\": \"plastic\", \"kd\": [0.8, 0.5, 0.2], \"alpha\": 0.2}";
    const char *conductor = "{\"type\": \"conductor\", \"ks\": [0.8, 0.5, 0.2], \"alpha\": 0.2}";
    /* image columns 3..9 see u in about (0.2, 0.45), 14..20 about (0.55, 0.8) */
    double tl = render_mean("tx_metal_tex", "tx_plane", textured, lights, IC_INTEGRATOR_PT, 32, 3, 9);
    double tr = render_mean("tx_metal_tex", "tx_plane", textured, lights, IC_INTEGRATOR_PT, 32, 15, 21);
    double pl = render_mean("tx_metal_pl", "tx_plane", plastic, lights, IC_INTEGRATOR_PT, 32, 3, 9);
    double cr = render_mean("tx_metal_co", "tx_plane", conductor, lights, IC_INTEGRATOR_PT, 32, 15, 21);
    CHECK(tl > 0.0 && fabs(tl - pl) <= 1e-4 * pl, "metallic 0 half %g = the plastic %g", tl, pl);
    CHECK(tr > 0.0 && fabs(tr - cr) <= 1e-3 * cr, "metallic 1 half %g = the conductor %g", tr, cr);
    CHECK(fabs(pl - cr) > 0.05 * pl, "the two halves differ (%g, %g): the test can tell them apart", pl, cr);
    /* the blend is linear in metallic: m = 0.5 renders the mean of the two (the sampling differs, so
     * within the noise of 128 samples per pixel over 18 x 20 pixels) */
    const char *half = "{\"type\": \"plastic\", \"kd\": [0.8, 0.5, 0.2], \"alpha\": 0.2, \"metallic\": 0.5}";
    double h = render_mean("tx_metal_half", "tx_plane", half, lights, IC_INTEGRATOR_PT, 128, 3, 21);
    double p2 = render_mean("tx_metal_pl", "tx_plane", plastic, lights, IC_INTEGRATOR_PT, 128, 3, 21);
    double c2 = render_mean("tx_metal_co", "tx_plane", conductor, lights, IC_INTEGRATOR_PT, 128, 3, 21);
    CHECK(fabs(h - 0.5 * (p2 + c2)) < 0.01 * h, "metallic 0.5: %g, the mean of plastic and conductor %g", h,
          0.5 * (p2 + c2));
}

/* Lambert radiance of the floor (kd 0.5) lit by a sun from direction sun_dir alone, normal-mapped by g_tilt. */
static double tilt_mean(const char *mesh, const char *mat, const char *sun_dir)
{
    char lights[256];
    snprintf(lights, sizeof lights, "\"lights\": [{\"type\": \"sun\", \"direction\": %s, \"irradiance\": [2, 2, 2]}]",
             sun_dir);
    return render_mean("tx_tilt", mesh, mat, lights, IC_INTEGRATOR_PT, 1, 4, 20);
}

static void test_normal_map_tilt(void)
{
    const double th = 30.0 * PI_F / 180.0;
    g_tilt = (float)th;
    g_tilt_axis = 0;
    write_texture(IC_TEST_TMP "/tx_tilt_u.pfm", 2, 2, tex_tilt);
    g_tilt_axis = 1;
    write_texture(IC_TEST_TMP "/tx_tilt_v.pfm", 2, 2, tex_tilt);
    const char *flat = "{\"type\": \"diffuse\", \"kd\": 0.5}";
    /* a sun from the zenith: E = 2; tilting the normal by 30° gives E·cos 30° */
    double e0 = tilt_mean("tx_plane", flat, "[0, 1, 0]");
    double e1 = tilt_mean("tx_plane", "{\"type\": \"diffuse\", \"kd\": 0.5, \"normal_texture\": \"tx_tilt_u.pfm\"}",
                          "[0, 1, 0]");
    double want = 0.5 / PI_F * 2.0;
    CHECK(fabs(e0 - want) < 1e-4 * want, "flat floor under the zenith sun: %g (kd/π·E = %g)", e0, want);
    CHECK(fabs(e1 - want * cos(th)) < 1e-4 * want, "tilted 30°: %g (expected %g)", e1, want * cos(th));
    /* the sun 30° from the zenith towards +x: the map tilted towards +u (+x) faces it */
    char sun_x[64], sun_z[64];
    snprintf(sun_x, sizeof sun_x, "[%g, %g, 0]", sin(th), cos(th));
    snprintf(sun_z, sizeof sun_z, "[0, %g, %g]", cos(th), sin(th));
    double ex = tilt_mean("tx_plane", "{\"type\": \"diffuse\", \"kd\": 0.5, \"normal_texture\": \"tx_tilt_u.pfm\"}",
                          sun_x);
    CHECK(fabs(ex - want) < 1e-4 * want, "normal tilted towards the sun: %g (expected %g)", ex, want);
    /* tilted towards +v: +z on the plane, −z where v runs the other way; the sun towards +z */
    write_plane("tx_plane_flip", 1, "");
    double ev = tilt_mean("tx_plane", "{\"type\": \"diffuse\", \"kd\": 0.5, \"normal_texture\": \"tx_tilt_v.pfm\"}",
                          sun_z);
    double ef = tilt_mean("tx_plane_flip",
                          "{\"type\": \"diffuse\", \"kd\": 0.5, \"normal_texture\": \"tx_tilt_v.pfm\"}", sun_z);
    CHECK(fabs(ev - want) < 1e-4 * want, "tilt along +v towards the sun: %g (expected %g)", ev, want);
    CHECK(fabs(ef - want * cos(2.0 * th)) < 1e-4 * want, "flipped v tilts away: %g (expected %g)", ef,
          want * cos(2.0 * th));
    /* the same through the MTL file (`norm`): tangents from the importer instead of the triangle */
    write_plane("tx_plane_mtl", 0, "norm tx_tilt_v.pfm\n");
    write_plane("tx_plane_mtl_flip", 1, "norm tx_tilt_v.pfm\n");
    double mv = tilt_mean("tx_plane_mtl", flat, sun_z), mf = tilt_mean("tx_plane_mtl_flip", flat, sun_z);
    CHECK(fabs(mv - want) < 1e-4 * want, "MTL norm, tilt along +v towards the sun: %g (expected %g)", mv, want);
    CHECK(fabs(mf - want * cos(2.0 * th)) < 1e-4 * want, "MTL norm, flipped v tilts away: %g (expected %g)", mf,
          want * cos(2.0 * th));
}

static void test_bumpy(void)
{
    write_texture(IC_TEST_TMP "/tx_bumps.pfm", 16, 16, tex_bumps);
    /* the Cornell box with a normal-mapped floor and back wall (the scene the cache's treatment of normal
     * maps was measured on, docs/scene-format.md) */
    const char *box = IC_SOURCE_DIR "/scenes/cornell-box-bumps/cornell-box-bumps.json";
    ic_render_options opt = {0};
    opt.integrator = IC_INTEGRATOR_PT;
    opt.spp = 256;
    opt.threads = 2;
    ic_image pt = {0}, ic1 = {0}, ic2 = {0};
    int ok = test_render(box, 32, 32, &opt, &pt, NULL);
    opt.integrator = IC_INTEGRATOR_IC;
    opt.spp = 4;
    opt.threads = 1;
    ok = ok && test_render(box, 32, 32, &opt, &ic1, NULL);
    opt.threads = 2;
    ok = ok && test_render(box, 32, 32, &opt, &ic2, NULL);
    CHECK(ok, "the normal-mapped Cornell box renders");
    if (ok) {
        int finite = 1;
        double mp = test_image_mean(&pt, &finite), mc = test_image_mean(&ic1, &finite);
        /* the path tracer's mean has a relative noise of about 0.2 % here; the cache's low-pass error on
         * this scene is about 0.7 % RMS per pixel and much less on the mean */
        CHECK(finite && fabs(mp - mc) < 0.01 * mp, "cache %g and path tracer %g agree on the normal-mapped box", mc,
              mp);
        CHECK(memcmp(ic1.rgb, ic2.rgb, sizeof(float) * 3 * (size_t)ic1.width * ic1.height) == 0,
              "1 and 2 threads give the same image");
    }
    ic_image_free(&pt);
    ic_image_free(&ic1);
    ic_image_free(&ic2);
    char path[512];
    /* white furnace: kd = 1 under L = 1, nothing else: at most L at every pixel on average */
    write_scene("tx_furnace", "tx_plane",
                "{\"type\": \"diffuse\", \"kd\": 1, \"normal_texture\": \"tx_bumps.pfm\", \"normal_scale\": 2}",
                "\"environment\": {\"radiance\": [1, 1, 1]}", path, sizeof path);
    ic_image f = {0};
    if (render(path, IC_INTEGRATOR_PT, 64, 2, &f)) {
        double m = region_mean(&f, 0, 24, 1);
        CHECK(m <= 1.0 + 0.005 && m > 0.8, "white furnace with a normal map: mean %g <= 1", m);
    }
    ic_image_free(&f);
}

/* A glTF quad (y = 0, x and z in [-1, 1], facing +y, u along +x) with material JSON mat, sharing a buffer
 * file; its scene under a sun 30° from the zenith towards +x, optionally overriding the material. */
static double gltf_mean(const char *name, const char *mat, const char *override)
{
    static const float pos[12] = {-1, 0, -1, 1, 0, -1, 1, 0, 1, -1, 0, 1}, nrm[12] = {0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0},
                       uv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    static const uint16_t idx[6] = {0, 2, 1, 0, 3, 2};
    FILE *f = fopen(IC_TEST_TMP "/tx_quad.bin", "wb");
    if (!f)
        exit(1);
    fwrite(pos, sizeof pos, 1, f);
    fwrite(nrm, sizeof nrm, 1, f);
    fwrite(uv, sizeof uv, 1, f);
    fwrite(idx, sizeof idx, 1, f);
    fclose(f);
    char text[4096], path[512];
    snprintf(text, sizeof text,
             "{\"asset\": {\"version\": \"2.0\"}, \"buffers\": [{\"byteLength\": 140, \"uri\": \"tx_quad.bin\"}],\n"
             " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 48}, {\"buffer\": 0, \"byteOffset\": 48, "
             "\"byteLength\": 48},\n  {\"buffer\": 0, \"byteOffset\": 96, \"byteLength\": 32}, {\"buffer\": 0, \"byteOffset\": 128, "
             "\"byteLength\": 12}],\n"
             " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC3\", \"min\": [-1, 0, -1], "
             "\"max\": [1, 0, 1]},\n  {\"bufferView\": 1, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC3\"},\n"
             "  {\"bufferView\": 2, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC2\"},\n"
             "  {\"bufferView\": 3, \"componentType\": 5123, \"count\": 6, \"type\": \"SCALAR\"}],\n"
             " \"images\": [{\"uri\": \"tx_mr.pfm\"}, {\"uri\": \"tx_tilt_u.pfm\"}], \"textures\": [{\"source\": 0}, "
             "{\"source\": 1}],\n"
             " \"materials\": [%s],\n"
             " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0, \"NORMAL\": 1, \"TEXCOORD_0\": 2}, "
             "\"indices\": 3, \"material\": 0}]}],\n"
             " \"nodes\": [{\"mesh\": 0}], \"scenes\": [{\"nodes\": [0]}], \"scene\": 0}\n",
             mat);
    snprintf(path, sizeof path, IC_TEST_TMP "/%s.gltf", name);
    test_write_file(path, text);
    char lights[300];
    snprintf(lights, sizeof lights, "\"lights\": [{\"type\": \"sun\", \"direction\": [0.5, 0.8660254, 0], "
             "\"irradiance\": [2, 2, 2]}]");
    char scene[1024];
    snprintf(scene, sizeof scene,
             "{\"camera\": {\"eye\": [0, 1, 0], \"target\": [0, 0, 0], \"up\": [0, 0, -1], \"fov_y\": 60, \"width\": 24, "
             "\"height\": 24},\n \"meshes\": [{\"path\": \"%s.gltf\"}],\n %s%s%s%s\n}\n",
             name, override ? "\"materials\": {\"m\": " : "", override ? override : "", override ? "},\n " : "", lights);
    snprintf(path, sizeof path, IC_TEST_TMP "/%s_scene.json", name);
    test_write_file(path, scene);
    ic_image img = {0};
    if (!render(path, IC_INTEGRATOR_PT, 4, 1, &img))
        return -1.0;
    double m = region_mean(&img, 4, 20, 1);
    ic_image_free(&img);
    if (getenv("IC_TEST_VERBOSE"))
        printf("%s: %.6f\n", name, m);
    return m;
}

static void tex_mr_metal(int x, int y, int w, float c[3]) /* glTF: roughness 1 (green), metallic 1 (blue) */
{
    (void)x, (void)y, (void)w;
    c[0] = 0.0f, c[1] = 1.0f, c[2] = 1.0f;
}

static void test_gltf(void)
{
    write_texture(IC_TEST_TMP "/tx_mr.pfm", 4, 4, tex_mr_metal); /* tx_tilt_u.pfm: from test_normal_map_tilt */
    const char *pbr = "\"pbrMetallicRoughness\": {\"baseColorFactor\": [0.8, 0.5, 0.2, 1], \"roughnessFactor\": 0.5, "
                      "\"metallicFactor\": 1";
    char textured[512], plain[512];
    snprintf(textured, sizeof textured, "{\"name\": \"m\", %s, \"metallicRoughnessTexture\": {\"index\": 0}}}", pbr);
    snprintf(plain, sizeof plain, "{\"name\": \"m\", %s}}", pbr);
    double a = gltf_mean("tx_gltf_mr", textured, NULL), b = gltf_mean("tx_gltf_plain", plain, NULL);
    CHECK(a > 0.0 && fabs(a - b) <= 1e-4 * b, "glTF metallicRoughnessTexture of metallic 1: %g, the conductor %g", a, b);
    /* A constant metallic factor between 0 and 1 blends the plastic and the conductor linearly (the
     * specification's mix), not rounded to either; the same light samples make the three renders agree
     * to float rounding. */
    double mix[3];
    for (int k = 0; k < 3; ++k) {
        char mat[512], name[64];
        snprintf(mat, sizeof mat, "{\"name\": \"m\", \"pbrMetallicRoughness\": {\"baseColorFactor\": [0.8, 0.5, 0.2, 1], "
                 "\"roughnessFactor\": 0.5, \"metallicFactor\": %s}}", k == 0 ? "0" : k == 1 ? "0.25" : "1");
        snprintf(name, sizeof name, "tx_gltf_metal%d", k);
        mix[k] = gltf_mean(name, mat, NULL);
    }
    double lin = 0.75 * mix[0] + 0.25 * mix[2];
    CHECK(mix[0] > 0.0 && fabs(mix[0] - mix[2]) > 0.05 * mix[2] && fabs(mix[1] - lin) <= 0.01 * lin,
          "glTF metallicFactor 0.25: %g, the blend of plastic %g and conductor %g is %g", mix[1], mix[0], mix[2], lin);
    /* the normal map tilts 30° towards +u = +x, the sun stands 30° from the zenith towards +x */
    const char *grey = "{\"name\": \"m\", \"pbrMetallicRoughness\": {\"metallicFactor\": 0}";
    char mapped[512], flat[512];
    snprintf(mapped, sizeof mapped, "%s, \"normalTexture\": {\"index\": 1, \"scale\": 1}}", grey);
    snprintf(flat, sizeof flat, "%s}", grey);
    const char *diffuse = "{\"type\": \"diffuse\", \"kd\": 0.5}";
    double m = gltf_mean("tx_gltf_nmap", mapped, diffuse), f = gltf_mean("tx_gltf_flat", flat, diffuse);
    double want = 0.5 / PI_F * 2.0;
    CHECK(fabs(m - want) < 1e-4 * want, "glTF normalTexture turns the normal to the sun: %g (expected %g)", m, want);
    CHECK(fabs(f - want * cos(PI_F / 6.0)) < 1e-4 * want, "glTF without it: %g (expected %g)", f,
          want * cos(PI_F / 6.0));
}

/* The mean of the middle of a Mitsuba scene: the plane tx_plane.obj with `bsdf` under a sun 30° from the
 * zenith, seen from above. */
static double mitsuba_mean(const char *name, const char *bsdf)
{
    char xml[2048], path[256];
    snprintf(xml, sizeof xml,
             "<scene version=\"0.6.0\">\n"
             "  <sensor type=\"perspective\"><float name=\"fov\" value=\"60\"/>\n"
             "    <transform name=\"toWorld\"><lookat origin=\"0, 1, 0\" target=\"0, 0, 0\" up=\"0, 0, -1\"/></transform>\n"
             "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"24\"/><integer name=\"height\" value=\"24\"/></film>\n"
             "  </sensor>\n"
             "  <shape type=\"obj\"><string name=\"filename\" value=\"tx_plane.obj\"/>\n    %s</shape>\n"
             "  <emitter type=\"directional\"><vector name=\"direction\" x=\"-0.5\" y=\"-0.8660254\" z=\"0\"/>"
             "<rgb name=\"irradiance\" value=\"2\"/></emitter>\n"
             "</scene>\n", bsdf);
    snprintf(path, sizeof path, IC_TEST_TMP "/%s.xml", name);
    test_write_file(path, xml);
    ic_image img = {0};
    double m = -1.0;
    if (render(path, IC_INTEGRATOR_PT, 1, 1, &img))
        m = region_mean(&img, 4, 20, 1);
    ic_image_free(&img);
    return m;
}

static void tex_alpha_03(int x, int y, int w, float c[3]) /* Mitsuba: α = 0.3 in every texel */
{
    (void)x, (void)y, (void)w;
    c[0] = c[1] = c[2] = 0.3f;
}

static void test_mitsuba(void)
{
    double m = mitsuba_mean("tx_mitsuba",
                            "<bsdf type=\"normalmap\"><texture name=\"normalmap\" type=\"bitmap\">"
                            "<string name=\"filename\" value=\"tx_tilt_u.pfm\"/></texture>\n"
                            "      <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.5\"/></bsdf></bsdf>");
    double want = 0.5 / PI_F * 2.0;
    CHECK(fabs(m - want) < 1e-4 * want, "Mitsuba normalmap turns the normal to the sun: %g (expected %g)", m, want);
    /* A bitmap as a rough conductor's alpha is α itself (Mitsuba's convention, not glTF's roughness²). */
    write_texture(IC_TEST_TMP "/tx_alpha.pfm", 4, 4, tex_alpha_03);
    const char *conductor = "<bsdf type=\"roughconductor\"><string name=\"distribution\" value=\"ggx\"/>"
                            "<rgb name=\"specularReflectance\" value=\"0.9\"/>%s</bsdf>";
    char a_tex[512], a_03[512], a_01[512];
    snprintf(a_tex, sizeof a_tex, conductor,
             "<texture name=\"alpha\" type=\"bitmap\"><string name=\"filename\" value=\"tx_alpha.pfm\"/></texture>");
    snprintf(a_03, sizeof a_03, conductor, "<float name=\"alpha\" value=\"0.3\"/>");
    snprintf(a_01, sizeof a_01, conductor, "<float name=\"alpha\" value=\"0.1\"/>");
    double t = mitsuba_mean("tx_mts_alpha_tex", a_tex), f = mitsuba_mean("tx_mts_alpha_03", a_03),
           g = mitsuba_mean("tx_mts_alpha_01", a_01);
    CHECK(t > 0.0 && fabs(t - f) <= 1e-4 * f && fabs(g - f) > 0.05 * f,
          "Mitsuba bitmap alpha 0.3: %g, float alpha 0.3: %g (alpha 0.1: %g)", t, f, g);
}

static void test_bad_textures(void)
{
    char path[512];
    write_scene("tx_missing", "tx_plane", "{\"type\": \"diffuse\", \"normal_texture\": \"no_such_map.png\"}", SKY, path,
                sizeof path);
    ic_scene *s = NULL;
    ic_error err = {0};
    ic_result r = ic_scene_load(path, NULL, &s, &err);
    CHECK(r != IC_OK && strstr(err.message, "tx_missing.json:") && strstr(err.message, "no_such_map.png") &&
              !strchr(err.message, '\n'),
          "missing texture: %s", err.message);
    ic_scene_free(s);
    test_write_file(IC_TEST_TMP "/tx_garbage.png", "this is not a PNG file\n");
    write_scene("tx_malformed", "tx_plane", "{\"type\": \"plastic\", \"roughness_texture\": \"tx_garbage.png\"}", SKY,
                path, sizeof path);
    s = NULL;
    r = ic_scene_load(path, NULL, &s, &err);
    CHECK(r != IC_OK && strstr(err.message, "tx_malformed.json:") && strstr(err.message, "tx_garbage.png") &&
              !strchr(err.message, '\n'),
          "malformed texture: %s", err.message);
    ic_scene_free(s);
}

int main(void)
{
    test_constant_roughness();
    test_coat_tables_per_index();
    test_metallic_halves();
    test_normal_map_tilt();
    test_bumpy();
    test_gltf();
    test_mitsuba();
    test_bad_textures();
    TEST_MAIN_END();
}
