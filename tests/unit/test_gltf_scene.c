/*
 * test_gltf_scene.c — a glTF file as a whole scene: small files written here (a 200 m floor, nodes with
 * cameras and KHR_lights_punctual lights) checked against what the specification says they mean:
 *   1. the camera: eye, view direction, up and field of view through a node hierarchy; aspectRatio sets
 *      the image's height; --camera picks another by name; an unknown name is an error naming it;
 *   2. a point light through a parent node: its position and intensity; the scene has no fallback sky;
 *      rendered, a Lambertian floor under it measures L = ρ·I/(π·h²) below the light (irradiance I/d²);
 *   3. a spot light: full intensity inside the inner cone, the specification's falloff between the
 *      cones, none outside; 4. directional lights: the first is the sun, a second a far point light with
 *      the same irradiance at the scene's centre;
 *   5. metallic-roughness: a metal is a rough conductor with F0 = base colour, alpha = roughness²;
 *   6. mirroring nodes (scale −1 on an axis): the placed triangle's winding and normals are the mirror
 *      image of the file's, alone and composed with a parent's mirror and the JSON scene's matrix; one
 *      mesh in several nodes is placed once per node.
 */
#include "test_render_util.h"
#include "test_util.h"

#include "irrcache/image.h"
#include "irrcache/render.h"
#include "scene/scene.h"

#include <stdio.h>
#include <string.h>

static const float H = 2.0f; /* light and camera height above the floor */

/* Writes floor.bin (4 positions, 6 indices) and NAME.gltf with the given nodes, scene roots, cameras,
 * lights and material; returns the path. */
static const char *write_gltf(const char *name, const char *nodes, const char *roots, const char *cameras,
                              const char *lights, const char *material)
{
    static char path[512];
    FILE *f = fopen(IC_TEST_TMP "/floor.bin", "wb");
    if (!f)
        exit(1);
    float p[12] = {-100, 0, -100, 100, 0, -100, 100, 0, 100, -100, 0, 100};
    uint16_t idx[6] = {0, 2, 1, 0, 3, 2};
    fwrite(p, sizeof p, 1, f);
    fwrite(idx, sizeof idx, 1, f);
    fclose(f);
    snprintf(path, sizeof path, IC_TEST_TMP "/%s.gltf", name);
    f = fopen(path, "w");
    if (!f)
        exit(1);
    fprintf(f,
            "{\"asset\": {\"version\": \"2.0\"},\n"
            " \"extensionsUsed\": [\"KHR_lights_punctual\"],\n"
            " \"extensions\": {\"KHR_lights_punctual\": {\"lights\": [%s]}},\n"
            " \"buffers\": [{\"uri\": \"floor.bin\", \"byteLength\": 60}],\n"
            " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 48},\n"
            "                  {\"buffer\": 0, \"byteOffset\": 48, \"byteLength\": 12}],\n"
            " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC3\",\n"
            "                 \"min\": [-100, 0, -100], \"max\": [100, 0, 100]},\n"
            "                {\"bufferView\": 1, \"componentType\": 5123, \"count\": 6, \"type\": \"SCALAR\"}],\n"
            " \"materials\": [%s],\n"
            " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1, \"material\": 0}]}],\n"
            " \"cameras\": [%s],\n"
            " \"nodes\": [{\"mesh\": 0, \"name\": \"floor\"}, %s],\n"
            " \"scenes\": [{\"nodes\": [0, %s]}], \"scene\": 0}\n",
            lights, material, cameras, nodes, roots);
    fclose(f);
    return path;
}

static const char *grey =
    "{\"name\": \"grey\", \"pbrMetallicRoughness\": {\"baseColorFactor\": [0.5, 0.5, 0.5, 1], \"metallicFactor\": 0}}";
/* a camera at (0, H, 0) looking straight down (−90° about x), 10° vertical field, 2:1 */
static const char *down_camera = "{\"type\": \"perspective\", \"name\": \"down\", "
                                 "\"perspective\": {\"yfov\": 0.17453293, \"aspectRatio\": 2.0, \"znear\": 0.01}}";
#define DOWN_ROTATION "\"rotation\": [-0.70710678, 0, 0, 0.70710678]"

static ic_scene *load(const char *path, const char *camera, int width)
{
    ic_scene_load_options lo = {0};
    lo.camera = camera;
    lo.width = width;
    ic_scene *s = NULL;
    ic_error err = {0};
    if (ic_scene_load(path, &lo, &s, &err) != IC_OK) {
        fprintf(stderr, "load %s: %s\n", path, err.message);
        return NULL;
    }
    return s;
}

static void test_camera(void)
{
    char nodes[1024];
    snprintf(nodes, sizeof nodes,
             "{\"name\": \"rig\", \"translation\": [1, 0, 0], \"children\": [2]},\n"
             "{\"name\": \"cam\", \"camera\": 0, \"translation\": [-1, %g, 0], " DOWN_ROTATION "},\n"
             "{\"name\": \"side\", \"camera\": 1, \"translation\": [0, 1, 5]},\n"
             "{\"name\": \"mat\", \"camera\": 1, \"matrix\": [0, 0, -1, 0, 0, 1, 0, 0, 1, 0, 0, 0, 2, 3, 7, 1]}",
             (double)H);
    const char *cams = "{\"type\": \"perspective\", \"name\": \"down\", \"perspective\": {\"yfov\": 0.17453293, "
                       "\"aspectRatio\": 2.0, \"znear\": 0.01}},\n"
                       "{\"type\": \"perspective\", \"name\": \"sidecam\", \"perspective\": {\"yfov\": 0.5, \"znear\": 0.01}}";
    const char *path = write_gltf("cameras", nodes, "1, 3, 4", cams, "", grey);
    ic_scene *s = load(path, NULL, 0);
    CHECK(s != NULL, "glTF with cameras loads");
    if (s) {
        const ic_camera *c = &s->camera;
        ic_vec3 d = v3_norm(v3_sub(c->target, c->eye));
        CHECK(fabsf(c->eye.x) < 1e-5f && fabsf(c->eye.y - H) < 1e-5f && fabsf(c->eye.z) < 1e-5f,
              "first camera's eye through the parent: %g %g %g", c->eye.x, c->eye.y, c->eye.z);
        CHECK(d.y < -0.9999f, "looks down its node's -Z: %g %g %g", d.x, d.y, d.z);
        CHECK(c->up.z < -0.9999f, "its +Y is up: %g %g %g", c->up.x, c->up.y, c->up.z);
        CHECK_NEAR(c->fov_y_deg, 10.0, 1e-3, "yfov in degrees");
        CHECK(c->width == 512 && c->height == 256, "aspectRatio 2: %dx%d", c->width, c->height);
    }
    ic_scene_free(s);
    s = load(path, "sidecam", 64);
    CHECK(s != NULL, "--camera by the camera's name");
    if (s) {
        CHECK(fabsf(s->camera.eye.z - 5.0f) < 1e-5f && s->camera.width == 64 && s->camera.height == 512,
              "the named camera, width from the option: eye z %g, %dx%d", s->camera.eye.z, s->camera.width,
              s->camera.height);
        CHECK_NEAR(s->camera.fov_y_deg, 0.5 * 180.0 / 3.14159265358979, 1e-3, "its field of view");
    }
    ic_scene_free(s);
    s = load(path, "side", 0);
    CHECK(s && fabsf(s->camera.eye.z - 5.0f) < 1e-5f, "--camera by the node's name");
    ic_scene_free(s);
    /* a column-major matrix: a turn of 90° about +y (−Z goes to −X) and a move to (2, 3, 7) */
    s = load(path, "mat", 0);
    if (s) {
        ic_vec3 d = v3_norm(v3_sub(s->camera.target, s->camera.eye));
        CHECK(fabsf(s->camera.eye.x - 2.0f) < 1e-5f && fabsf(s->camera.eye.y - 3.0f) < 1e-5f &&
                  fabsf(s->camera.eye.z - 7.0f) < 1e-5f && d.x < -0.9999f,
              "a node's matrix read by columns: eye %g %g %g, view %g %g %g", s->camera.eye.x, s->camera.eye.y,
              s->camera.eye.z, d.x, d.y, d.z);
    }
    ic_scene_free(s);
    ic_scene_load_options lo = {0};
    lo.camera = "nosuch";
    ic_error err = {0};
    s = NULL;
    CHECK(ic_scene_load(path, &lo, &s, &err) == IC_ERR_INVALID_ARG && strstr(err.message, "nosuch") &&
              strstr(err.message, "cameras.gltf"),
          "an unknown camera name is an error naming it and the file: %s", err.message);
    ic_scene_free(s);
}

/* Mean of the green channel over the centre 4×4 pixels. */
static double centre_mean(const ic_image *img)
{
    double sum = 0.0;
    for (int y = img->height / 2 - 2; y < img->height / 2 + 2; ++y)
        for (int x = img->width / 2 - 2; x < img->width / 2 + 2; ++x)
            sum += img->rgb[3 * ((size_t)y * img->width + x) + 1];
    return sum / 16.0;
}

static void test_point_light(void)
{
    char nodes[1024];
    snprintf(nodes, sizeof nodes,
             "{\"name\": \"cam\", \"camera\": 0, \"translation\": [0, %g, 0], " DOWN_ROTATION "},\n"
             "{\"name\": \"lamp_parent\", \"translation\": [1, 0, 0], \"children\": [3]},\n"
             "{\"name\": \"lamp\", \"translation\": [-1, %g, 0], \"extensions\": {\"KHR_lights_punctual\": {\"light\": 0}}}",
             (double)H, (double)H);
    const char *path = write_gltf("point", nodes, "1, 2", down_camera,
                                  "{\"type\": \"point\", \"color\": [1, 0.5, 0.25], \"intensity\": 8}", grey);
    ic_scene *s = load(path, NULL, 48);
    CHECK(s != NULL, "glTF with a point light loads");
    if (!s)
        return;
    CHECK(s->point_light_count == 1 && !s->env.enabled, "one point light and no fallback sky");
    if (s->point_light_count == 1) {
        ic_vec3 p = s->point_lights[0].position, I = s->point_lights[0].intensity;
        CHECK(fabsf(p.x) < 1e-5f && fabsf(p.y - H) < 1e-5f && fabsf(p.z) < 1e-5f, "position through the parent");
        CHECK(I.x == 8.0f && I.y == 4.0f && I.z == 2.0f, "intensity = colour x intensity");
    }
    /* the floor Lambertian (albedo 0.5) for an analytic answer */
    s->materials[0].type = IC_MAT_DIFFUSE;
    ic_render_options opt = {0};
    opt.spp = 4;
    opt.threads = 2;
    ic_image img = {0};
    ic_render_stats st;
    ic_error err = {0};
    CHECK(ic_render(s, &opt, &img, &st, &err) == IC_OK, "renders: %s", err.message);
    if (img.rgb) {
        /* 10° field of view: the centre 4×4 pixels are within 0.2° of the axis (cos³ > 0.99998) */
        double want = 0.5 * 4.0 / (3.14159265358979 * H * H);
        CHECK(fabs(centre_mean(&img) - want) < 2e-3 * want, "floor below the light: %g, expected rho I/(pi h^2) = %g",
              centre_mean(&img), want);
    }
    ic_image_free(&img);
    ic_scene_free(s);
}

static void test_spot_and_directional(void)
{
    char nodes[1024];
    snprintf(nodes, sizeof nodes,
             "{\"name\": \"spot\", \"translation\": [0, %g, 0], " DOWN_ROTATION
             ", \"extensions\": {\"KHR_lights_punctual\": {\"light\": 0}}},\n"
             "{\"name\": \"sun\", " DOWN_ROTATION ", \"extensions\": {\"KHR_lights_punctual\": {\"light\": 1}}},\n"
             "{\"name\": \"sun2\", \"extensions\": {\"KHR_lights_punctual\": {\"light\": 2}}}",
             (double)H);
    const char *lights = "{\"type\": \"spot\", \"intensity\": 10, \"spot\": {\"innerConeAngle\": 0.17453293, "
                         "\"outerConeAngle\": 0.34906585}},\n"
                         "{\"type\": \"directional\", \"intensity\": 3},\n"
                         "{\"type\": \"directional\", \"color\": [0, 1, 0], \"intensity\": 2}";
    const char *path = write_gltf("spot", nodes, "1, 2, 3", "", lights, grey);
    ic_scene *s = load(path, NULL, 0);
    CHECK(s != NULL, "glTF with spot and directional lights loads");
    if (!s)
        return;
    CHECK(s->sun.enabled && s->sun.direction.y > 0.9999f && s->sun.irradiance.x == 3.0f,
          "the first directional light is the sun, pointing up towards it");
    CHECK(s->point_light_count == 2 && s->point_spots, "the spot and the second directional light as points");
    if (s->point_light_count == 2 && s->point_spots) {
        const ic_spot_cone *cone = &s->point_spots[0];
        CHECK(cone->axis.y < -0.9999f, "spot axis down");
        static const float angles[] = {0.0f, 5.0f, 15.0f, 25.0f};
        for (int k = 0; k < 4; ++k) {
            float a = angles[k] * IC_PI / 180.0f;
            ic_vec3 d = v3(sinf(a), -cosf(a), 0.0f);
            float t = (cosf(a) - cosf(0.34906585f)) / (cosf(0.17453293f) - cosf(0.34906585f));
            t = t < 0 ? 0 : (t > 1 ? 1 : t);
            CHECK_NEAR(ic_spot_falloff(cone, d), t * t, 1e-5, "spot falloff");
        }
        CHECK(ic_spot_falloff(cone, v3(0, -1, 0)) == 1.0f && ic_spot_falloff(cone, v3_norm(v3(1, -1, 0))) == 0.0f,
              "full inside the inner cone, none outside the outer");
        /* the far light gives the second sun's irradiance at the centre, from straight along its -Z's opposite */
        ic_vec3 d = v3_sub(s->point_lights[1].position, v3s(0.0f));
        float dist = v3_len(d);
        CHECK(v3_norm(d).z > 0.9999f, "the second sun lies towards +Z (it shines down -Z)");
        CHECK_NEAR(s->point_lights[1].intensity.y / (dist * dist), 2.0, 2e-3, "its irradiance at the centre");
        CHECK(ic_spot_falloff(&s->point_spots[1], v3(0, 0, -1)) == 1.0f, "a point light has no falloff");
    }
    ic_scene_free(s);
}

/* A node with two parents is refused (glTF nodes form trees; walking it twice could repeat without end). */
static void test_two_parents(void)
{
    const char *path = write_gltf("two_parents", "{\"children\": [3]}, {\"children\": [3]}, {\"name\": \"leaf\"}",
                                  "1, 2", "", "", grey);
    ic_scene_load_options lo = {0};
    ic_scene *s = NULL;
    ic_error err = {0};
    CHECK(ic_scene_load(path, &lo, &s, &err) == IC_ERR_PARSE && strstr(err.message, "node 3"),
          "a node reached twice is an error naming it: %s", err.message);
    ic_scene_free(s);
}

static void test_metal(void)
{
    const char *metal = "{\"name\": \"gold\", \"pbrMetallicRoughness\": {\"baseColorFactor\": [1, 0.8, 0.3, 1], "
                        "\"metallicFactor\": 1, \"roughnessFactor\": 0.4}}";
    const char *path = write_gltf("metal", "{\"name\": \"empty\"}", "1", "", "", metal);
    ic_scene *s = load(path, NULL, 0);
    CHECK(s && s->material_count >= 1, "metal glTF loads");
    if (s) {
        const ic_material *m = &s->materials[0];
        CHECK(m->type == IC_MAT_CONDUCTOR && m->ks.y == 0.8f && fabsf(m->alpha - 0.16f) < 1e-6f,
              "metal: conductor with F0 = base, alpha = roughness^2 (%d, %g, %g)", (int)m->type, m->ks.y, m->alpha);
        CHECK(s->env.enabled, "no light of any kind: the fallback sky");
    }
    ic_scene_free(s);
}

/* Appends n bytes, then zeros (bin) or spaces (json) to a multiple of 4. */
static size_t put_padded(unsigned char *dst, size_t at, const void *src, size_t n, unsigned char pad)
{
    memcpy(dst + at, src, n);
    at += n;
    while (at % 4)
        dst[at++] = pad;
    return at;
}

/* A .glb whose floor material's base colour texture is a PNG inside the file (2×2, every texel
 * (255, 128, 0)): the texture is decoded from memory and shades the floor. */
static void test_embedded_texture(void)
{
    ic_image tex = {0};
    ic_error err = {0};
    CHECK(ic_image_create(&tex, 2, 2) == IC_OK, "texture image");
    for (int i = 0; i < 4; ++i) {
        tex.rgb[3 * i] = 1.0f;
        tex.rgb[3 * i + 1] = ic_srgb8_to_linear(128);
        tex.rgb[3 * i + 2] = 0.0f;
    }
    CHECK(ic_image_write(IC_TEST_TMP "/embedded.png", &tex, NULL, &err) == IC_OK, "PNG written: %s", err.message);
    ic_image_free(&tex);
    static unsigned char png[4096], bin[8192], glb[16384];
    FILE *f = fopen(IC_TEST_TMP "/embedded.png", "rb");
    size_t png_n = f ? fread(png, 1, sizeof png, f) : 0;
    if (f)
        fclose(f);
    CHECK(png_n > 0 && png_n < sizeof png, "PNG read back");
    float pos[12] = {-100, 0, -100, 100, 0, -100, 100, 0, 100, -100, 0, 100};
    float uv[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    uint16_t idx[6] = {0, 2, 1, 0, 3, 2};
    size_t n = put_padded(bin, 0, pos, sizeof pos, 0);
    n = put_padded(bin, n, uv, sizeof uv, 0);
    n = put_padded(bin, n, idx, sizeof idx, 0);
    size_t png_at = n;
    n = put_padded(bin, n, png, png_n, 0);
    char json[4096];
    int jn = snprintf(json, sizeof json,
                      "{\"asset\": {\"version\": \"2.0\"}, \"buffers\": [{\"byteLength\": %zu}],\n"
                      " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 48},\n"
                      "  {\"buffer\": 0, \"byteOffset\": 48, \"byteLength\": 32}, {\"buffer\": 0, \"byteOffset\": 80, "
                      "\"byteLength\": 12},\n  {\"buffer\": 0, \"byteOffset\": %zu, \"byteLength\": %zu}],\n"
                      " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC3\", "
                      "\"min\": [-100, 0, -100], \"max\": [100, 0, 100]},\n"
                      "  {\"bufferView\": 1, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC2\"},\n"
                      "  {\"bufferView\": 2, \"componentType\": 5123, \"count\": 6, \"type\": \"SCALAR\"}],\n"
                      " \"images\": [{\"bufferView\": 3, \"mimeType\": \"image/png\"}], \"textures\": [{\"source\": 0}],\n"
                      " \"materials\": [{\"name\": \"tex\", \"pbrMetallicRoughness\": {\"metallicFactor\": 0, "
                      "\"baseColorTexture\": {\"index\": 0}}}],\n"
                      " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0, \"TEXCOORD_0\": 1}, "
                      "\"indices\": 2, \"material\": 0}]}],\n"
                      " \"nodes\": [{\"mesh\": 0}], \"scenes\": [{\"nodes\": [0]}], \"scene\": 0}",
                      n, png_at, png_n);
    size_t jlen = ((size_t)jn + 3) / 4 * 4, total = 12 + 8 + jlen + 8 + n;
    uint32_t head[5] = {0x46546C67u, 2u, (uint32_t)total, (uint32_t)jlen, 0x4E4F534Au};
    size_t at = put_padded(glb, 0, head, sizeof head, 0);
    at = put_padded(glb, at, json, (size_t)jn, ' ');
    uint32_t bin_head[2] = {(uint32_t)n, 0x004E4942u};
    at = put_padded(glb, at, bin_head, sizeof bin_head, 0);
    at = put_padded(glb, at, bin, n, 0);
    f = fopen(IC_TEST_TMP "/embedded.glb", "wb");
    if (f) {
        fwrite(glb, 1, at, f);
        fclose(f);
    }
    ic_scene *s = load(IC_TEST_TMP "/embedded.glb", NULL, 0);
    CHECK(s != NULL, "a .glb with an embedded PNG texture loads");
    if (!s)
        return;
    CHECK(s->texture_count == 1 && s->textures[0].width == 2 && strstr(s->textures[0].path, "embedded.glb#*0"),
          "one embedded texture, labelled by the file and its index");
    if (s->texture_count == 1 && s->material_count >= 1 && s->triangle_count >= 1) {
        ic_surface srf;
        ic_scene_surface(s, 0, 0.3f, 0.3f, &srf);
        ic_vec3 a = ic_scene_albedo(s, &srf);
        CHECK(fabsf(a.x - 1.0f) < 1e-5f && fabsf(a.y - ic_srgb8_to_linear(128)) < 1e-5f && a.z == 0.0f,
              "the floor's albedo is the texture's colour: %g %g %g", a.x, a.y, a.z);
    }
    ic_scene_free(s);
}

/* Two lamps whose meshes use glTF material 1 (B, strength 50) before material 0 (A, strength 2): assimp
 * numbers its materials by first use, so reading the strengths by glTF index swapped them. */
static void test_emissive_strength_order(void)
{
    ic_scene *s = load(IC_SOURCE_DIR "/tests/scenes/gltf_strength_order.gltf", NULL, 0);
    CHECK(s != NULL, "the two-lamp glTF loads");
    float a = -1.0f, b = -1.0f;
    for (uint32_t i = 0; s && i < s->material_count; ++i) {
        if (!strcmp(s->materials[i].name, "A"))
            a = s->materials[i].emission.x;
        if (!strcmp(s->materials[i].name, "B"))
            b = s->materials[i].emission.x;
    }
    CHECK(a == 2.0f && b == 50.0f, "each lamp its own strength: A %g (2), B %g (50)", (double)a, (double)b);
    ic_scene_free(s);
}

/* The triangle (1,0,0) (2,0,1) (1,1,0) with normal (-1,0,1)/√2 (its winding's and its vertices'), as mesh 0 of
 * mirror.gltf under NODES (the scene's roots ROOTS). */
static const char *write_mirror_gltf(const char *nodes, const char *roots)
{
    FILE *f = fopen(IC_TEST_TMP "/mirror.bin", "wb");
    if (!f)
        exit(1);
    const float r = 0.70710678f;
    float p[9] = {1, 0, 0, 2, 0, 1, 1, 1, 0}, n[9] = {-r, 0, r, -r, 0, r, -r, 0, r};
    uint16_t idx[4] = {0, 1, 2, 0};
    fwrite(p, sizeof p, 1, f);
    fwrite(n, sizeof n, 1, f);
    fwrite(idx, sizeof idx, 1, f);
    fclose(f);
    f = fopen(IC_TEST_TMP "/mirror.gltf", "w");
    if (!f)
        exit(1);
    fprintf(f,
            "{\"asset\": {\"version\": \"2.0\"},\n"
            " \"buffers\": [{\"uri\": \"mirror.bin\", \"byteLength\": 80}],\n"
            " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36},\n"
            "                  {\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 36},\n"
            "                  {\"buffer\": 0, \"byteOffset\": 72, \"byteLength\": 6}],\n"
            " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\",\n"
            "                 \"min\": [1, 0, 0], \"max\": [2, 1, 1]},\n"
            "                {\"bufferView\": 1, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\"},\n"
            "                {\"bufferView\": 2, \"componentType\": 5123, \"count\": 3, \"type\": \"SCALAR\"}],\n"
            " \"materials\": [%s],\n"
            " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0, \"NORMAL\": 1}, \"indices\": 2, "
            "\"material\": 0}]}],\n"
            " \"nodes\": [%s],\n"
            " \"scenes\": [{\"nodes\": [%s]}], \"scene\": 0}\n",
            grey, nodes, roots);
    fclose(f);
    return IC_TEST_TMP "/mirror.gltf";
}

/* The instance of the triangle whose centroid is c (the mesh's is (4/3, 1/3, 1/3)) has the normal n: its
 * winding's (ng) and its vertices' (ns), the mirror image of the file's where the placement mirrors. */
static void check_instance(const ic_scene *s, ic_vec3 c, ic_vec3 n, const char *what)
{
    int found = 0;
    for (uint32_t t = 0; t < s->triangle_count; ++t) {
        const uint32_t *v = s->triangles + 3 * t;
        ic_vec3 m = v3_scale(v3_add(v3_add(s->positions[v[0]], s->positions[v[1]]), s->positions[v[2]]), 1.0f / 3.0f);
        if (v3_len(v3_sub(m, c)) > 1e-4f)
            continue;
        ++found;
        ic_surface srf;
        ic_scene_surface(s, t, 1.0f / 3.0f, 1.0f / 3.0f, &srf);
        CHECK(v3_dot(srf.ng, n) > 0.9999f, "%s: the winding's normal %g %g %g is %g %g %g", what, srf.ng.x, srf.ng.y,
              srf.ng.z, n.x, n.y, n.z);
        CHECK(v3_dot(srf.ns, n) > 0.9999f, "%s: the vertices' normal %g %g %g is %g %g %g", what, srf.ns.x, srf.ns.y,
              srf.ns.z, n.x, n.y, n.z);
    }
    CHECK(found == 1, "%s: one triangle at %g %g %g (%d)", what, c.x, c.y, c.z, found);
}

/* A mirroring node (a negative determinant) turns the mesh's outside around with its vertices: the placed
 * triangle's winding must be swapped so that its front is the mirror image of the file's front. One mesh
 * under four nodes: as is, mirrored in x, and under a parent mirrored in x with a child mirrored in z (a
 * half turn about y: no mirror); then the whole file mirrored in x again by the scene's matrix. */
static void test_mirrored_nodes(void)
{
    const char *path = write_mirror_gltf(
        "{\"name\": \"plain\", \"mesh\": 0},\n"
        "{\"name\": \"mirror\", \"mesh\": 0, \"scale\": [-1, 1, 1]},\n"
        "{\"name\": \"parent\", \"scale\": [-1, 1, 1], \"translation\": [0, 5, 0], \"children\": [3]},\n"
        "{\"name\": \"turned\", \"mesh\": 0, \"scale\": [1, 1, -1]}",
        "0, 1, 2");
    const float r = 0.70710678f;
    const float third = 1.0f / 3.0f, c = 4.0f / 3.0f;
    ic_scene *s = load(path, NULL, 0);
    CHECK(s != NULL, "the mirrored glTF loads");
    if (s) {
        CHECK(s->triangle_count == 3, "one mesh in three nodes: three triangles (%u)", s->triangle_count);
        check_instance(s, v3(c, third, third), v3(-r, 0, r), "the node as is");
        check_instance(s, v3(-c, third, third), v3(r, 0, r), "the node mirrored in x");
        check_instance(s, v3(-c, 5 + third, -third), v3(r, 0, -r), "two mirrors, parent and child");
    }
    ic_scene_free(s);

    FILE *f = fopen(IC_TEST_TMP "/mirror_scene.json", "w");
    if (!f)
        exit(1);
    fprintf(f, "{\"meshes\": [{\"path\": \"mirror.gltf\", \"matrix\": [[-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], "
               "[0, 0, 0, 1]]}],\n"
               " \"camera\": {\"eye\": [0, 1, 9], \"target\": [0, 1, 0], \"width\": 8, \"height\": 8}}\n");
    fclose(f);
    s = load(IC_TEST_TMP "/mirror_scene.json", NULL, 0);
    CHECK(s != NULL, "the mirrored glTF in a scene with a mirroring matrix loads");
    if (s) {
        CHECK(s->triangle_count == 3, "three triangles (%u)", s->triangle_count);
        check_instance(s, v3(-c, third, third), v3(r, 0, r), "the scene's mirror on the node as is");
        check_instance(s, v3(c, third, third), v3(-r, 0, r), "the scene's mirror on the mirrored node");
        check_instance(s, v3(c, 5 + third, -third), v3(-r, 0, -r), "the scene's mirror on the two mirrors");
    }
    ic_scene_free(s);

    /* the mesh in no node of the scene: nothing to place, an error naming the file (not an empty scene) */
    path = write_mirror_gltf("{\"name\": \"empty\"}", "0");
    ic_scene_load_options lo = {0};
    ic_error err = {0};
    s = NULL;
    CHECK(ic_scene_load(path, &lo, &s, &err) == IC_ERR_PARSE && strstr(err.message, "mirror.gltf: "),
          "a mesh that no node holds is an error: %s", err.message);
    ic_scene_free(s);
}

/* An emission (emissiveFactor times KHR_materials_emissive_strength) or a light (colour times intensity)
 * above IC_SCENE_MAX_RADIANCE (1e30) is refused naming the file and the material or light (the emission's
 * product overflowed to infinity and was read as 0); 1e29 loads and renders finite, the emitting floor seen
 * directly at its radiance. */
static void test_radiance_limit(void)
{
    char cam[256];
    snprintf(cam, sizeof cam, "{\"name\": \"cam\", \"camera\": 0, \"translation\": [0, %g, 0], " DOWN_ROTATION "}",
             (double)H);
    static const char *const lamp = ",\n{\"name\": \"lamp\", \"translation\": [0, 1, 0], " DOWN_ROTATION
                                    ", \"extensions\": {\"KHR_lights_punctual\": {\"light\": 0}}}";
    static const struct {
        const char *name, *light, *material, *says;
        double brightest; /* over the value (0: not checked) */
    } cases[] = {
        {"limit_emissive", "",
         "{\"name\": \"hot\", \"emissiveFactor\": [1, 1, 1], \"extensions\": {\"KHR_materials_emissive_strength\": "
         "{\"emissiveStrength\": %s}}}",
         "material 'hot': its emission is 1e+31, above 1e+30", 1.0},
        {"limit_point", "{\"type\": \"point\", \"intensity\": %s}", NULL,
         "light 0: its colour times its intensity is 1e+31, above 1e+30", 0.0},
        {"limit_directional", "{\"type\": \"directional\", \"color\": [1, 0.5, 1], \"intensity\": %s}", NULL,
         "light 0: its colour times its intensity is 1e+31, above 1e+30", 0.0},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k)
        for (int ok = 0; ok < 2; ++ok) {
            const char *v = ok ? "1e29" : "1e31";
            char light[256], material[512], nodes[512], name[64];
            snprintf(light, sizeof light, cases[k].light, v);
            snprintf(material, sizeof material, cases[k].material ? cases[k].material : "%s", cases[k].material ? v : grey);
            snprintf(nodes, sizeof nodes, "%s%s", cam, light[0] ? lamp : "");
            snprintf(name, sizeof name, "%s%s", cases[k].name, ok ? "_ok" : "");
            const char *path = write_gltf(name, nodes, light[0] ? "1, 2" : "1", down_camera, light, material);
            ic_scene *s = NULL;
            ic_error err = {0};
            test_load_scene(path, NULL, 16, 16, 0, &s, &err);
            if (ok) {
                CHECK(s != NULL, "%s loads: %s", name, err.message);
                test_check_renders_finite(name, s, cases[k].brightest * 1e29);
                continue;
            }
            char where[96];
            snprintf(where, sizeof where, "%s.gltf: ", name);
            test_check_refused(name, s, &err, (const char *[]){where, cases[k].says, "; ", NULL});
        }
}

int main(void)
{
    test_radiance_limit();
    test_mirrored_nodes();
    test_emissive_strength_order();
    test_embedded_texture();
    test_camera();
    test_point_light();
    test_spot_and_directional();
    test_metal();
    test_two_parents();
    TEST_MAIN_END();
}
