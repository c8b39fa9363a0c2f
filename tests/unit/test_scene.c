/*
 * test_scene.c — loading good scenes: the bundled Cornell box, transforms, material overrides, lights,
 * environment and render settings from JSON, fov_x conversion, "shared:" paths, bare meshes with a
 * fitted camera, dropped degenerate triangles (and kept ones 1e-15 to 1e18 across, whose squared cross
 * product leaves a float: their normal, area and light pdf, and a ray hitting a 1e12 floor), the surface queries (barycentrics, normals, uvs,
 * bilinear textures, one-sided emission), gzip-compressed meshes (.obj.gz: same triangles, MTL and
 * textures from the folder of the .gz file; a truncated or corrupt file is a one-line error naming it),
 * and a file's parts of one material joined before their vertices are (two OBJ groups sharing an edge:
 * one vertex and one tangent at each place).
 */
#include "geom/accel.h"
#include "irrcache/image.h"
#include "scene/scene.h"
#include "scene/scene_internal.h" /* ic_scene_texture_load */
#include "test_files.h"
#include "test_util.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <zlib.h>

#ifndef IC_TEST_TMP
#define IC_TEST_TMP "/tmp"
#endif

#define SCENES IC_SOURCE_DIR "/tests/scenes/"

static ic_scene *load(const char *path, const ic_scene_load_options *opt)
{
    ic_scene *s = NULL;
    ic_error err = {0};
    ic_result r = ic_scene_load(path, opt, &s, &err);
    CHECK(r == IC_OK && s, "%s: %s %s", path, ic_result_name(r), err.message);
    return r == IC_OK ? s : NULL;
}

static ic_vec3 tri_normal(const ic_scene *s, uint32_t t)
{
    ic_vec3 p0 = s->positions[s->triangles[3 * t]], p1 = s->positions[s->triangles[3 * t + 1]],
            p2 = s->positions[s->triangles[3 * t + 2]];
    return v3_norm(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
}

static int32_t find_material(const ic_scene *s, const char *name)
{
    for (uint32_t i = 0; i < s->material_count; ++i)
        if (!strcmp(s->materials[i].name, name))
            return (int32_t)i;
    return -1;
}

/* Total area of the tri lights whose material is `name`. */
static double light_area(const ic_scene *s, const char *name)
{
    double a = 0.0;
    for (uint32_t i = 0; i < s->tri_light_count; ++i)
        if (!strcmp(s->materials[s->triangle_material[s->tri_lights[i].triangle]].name, name))
            a += s->tri_lights[i].area;
    return a;
}

static void test_cornell_box(void)
{
    ic_scene *s = load(IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json", NULL);
    if (!s)
        return;
    CHECK(s->triangle_count == 36, "Cornell box triangles: %u", s->triangle_count);
    CHECK(s->dropped_degenerate == 0, "dropped %u", s->dropped_degenerate);
    CHECK(!strstr(ic_scene_warnings(s), "zero area"), "no drop warning: %s", ic_scene_warnings(s));
    CHECK(s->normals == NULL && s->uvs == NULL, "the OBJ has no normals or uvs");
    CHECK(s->tri_light_count == 2, "one emissive quad = 2 triangles, got %u", s->tri_light_count);
    /* the MTL's light quad spans x in [-0.24, 0.23], z in [-0.22, 0.16] at y = 1.98 */
    CHECK_NEAR(light_area(s, "light"), 0.47 * 0.38, 1e-5, "light area");
    for (uint32_t i = 0; i < s->tri_light_count; ++i) {
        uint32_t t = s->tri_lights[i].triangle;
        CHECK(s->triangle_light[t] == (int32_t)i, "triangle_light maps back");
        CHECK_NEAR(tri_normal(s, t).y, -1.0, 1e-5, "the light faces down into the box");
        CHECK_NEAR(s->tri_lights[i].power, IC_PI * s->tri_lights[i].area * v3_lum(v3(17, 12, 4)), 1e-3,
                   "power = pi A lum(Le)");
    }
    CHECK_NEAR(s->tri_light_cdf[s->tri_light_count], 1.0, 0, "cdf ends at 1");
    int32_t light = find_material(s, "light");
    CHECK(light >= 0 && s->materials[light].emission.x == 17.0f && s->materials[light].emission.z == 4.0f,
          "Ke 17 12 4");
    int32_t left = find_material(s, "leftWall");
    CHECK(left >= 0 && s->materials[left].type == IC_MAT_DIFFUSE && fabsf(s->materials[left].kd.x - 0.63f) < 1e-6f,
          "leftWall is red diffuse");
    CHECK(s->light_select.tri == 1.0f && s->light_select.env == 0.0f, "only triangle lights");
    CHECK(!s->env.enabled && !s->sun.enabled && s->point_light_count == 0, "no other lights");
    CHECK(s->camera.width == 512 && s->camera.height == 512, "resolution %dx%d", s->camera.width, s->camera.height);
    CHECK_NEAR(s->camera.fov_y_deg, 39.3, 1e-5, "fov_y");
    CHECK_NEAR(s->camera.eye.z, 3.9, 1e-6, "eye z");
    CHECK_NEAR(s->bounds_max.y, 1.99, 1e-6, "bounds");
    CHECK_NEAR(s->bounds_min.x, -1.02, 1e-6, "bounds");
    ic_scene_free(s);

    ic_scene_load_options opt = {0};
    opt.width = 64;
    opt.height = 32;
    s = load(IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json", &opt);
    if (s) {
        CHECK(s->camera.width == 64 && s->camera.height == 32, "resolution override");
        CHECK_NEAR(s->camera.fov_y_deg, 39.3, 1e-5, "fov_y kept under override");
    }
    ic_scene_free(s);
}

/* A mirroring transform (scale -1 along x) swaps the winding to keep the front side; the vertex normals
 * must turn with it: the cofactor matrix is det times the inverse transpose, and used as it is it turned
 * every normal of a mirrored mesh around (ng +z, the vertex normal -z). */
static void test_mirrored_normals(void)
{
    test_write_text(IC_TEST_TMP "/mirror_quad.obj", "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvn 0 0 1\n"
                                                    "f 1//1 2//1 3//1\nf 1//1 3//1 4//1\n");
    test_write_text(IC_TEST_TMP "/mirror_quad.json", "{\"meshes\": [{\"path\": \"mirror_quad.obj\", \"transform\": "
                                                     "{\"scale\": [-1, 1, 1]}}], \"environment\": {\"radiance\": 1}}\n");
    ic_scene_load_options opt = {0};
    ic_scene *s = load(IC_TEST_TMP "/mirror_quad.json", &opt);
    if (!s)
        return;
    int agree = s->normals != NULL;
    for (uint32_t t = 0; agree && t < s->triangle_count; ++t)
        for (int k = 0; k < 3; ++k)
            agree &= v3_dot(s->normals[s->triangles[3 * t + k]], tri_normal(s, t)) > 0.99f;
    CHECK(agree && tri_normal(s, 0).z > 0.99f, "a mirrored quad: its vertex normals face its front (+z) side");
    ic_scene_free(s);
}

static void test_transformed(void)
{
    ic_scene_load_options opt = {0};
    opt.allow_outside_paths = 1; /* it names the Cornell box in scenes/, outside tests/scenes */
    ic_scene *s = load(SCENES "transformed.json", &opt);
    if (!s)
        return;
    CHECK(s->triangle_count == 36 + 4, "two meshes: %u", s->triangle_count);
    /* Cornell box: scale 2, rotate 90° about y (x' = z, z' = -x), translate x + 10 */
    CHECK_NEAR(s->bounds_max.x, 10.0 + 2 * 0.99, 1e-4, "max x = 10 + 2 max z");
    CHECK_NEAR(s->bounds_max.z, 2 * 1.02, 1e-4, "max z = -2 min x");
    CHECK_NEAR(s->bounds_max.y, 2 * 1.99, 1e-4, "max y = 2 max y");
    CHECK_NEAR(s->bounds_min.y, -5.0, 1e-5, "the quad mesh moved down by 5 (matrix)");
    CHECK_NEAR(light_area(s, "light"), 4 * 0.47 * 0.38, 1e-4, "light area scaled by 4");
    CHECK_NEAR(light_area(s, "emitter"), 0.5, 1e-5, "quad emitter area");
    int found_vertex = 0; /* light corner (-0.24, 1.98, 0.16) → (10.32, 3.96, 0.48) */
    for (uint32_t i = 0; i < s->vertex_count; ++i)
        found_vertex |= v3_len(v3_sub(s->positions[i], v3(10.32f, 3.96f, 0.48f))) < 1e-4f;
    CHECK(found_vertex, "transformed light corner present");
    for (uint32_t i = 0; i < s->tri_light_count; ++i) {
        uint32_t t = s->tri_lights[i].triangle;
        const char *name = s->materials[s->triangle_material[t]].name;
        CHECK_NEAR(tri_normal(s, t).y, -1.0, 1e-5, "rotation keeps the lights facing down");
        if (!strcmp(name, "emitter"))
            CHECK_NEAR(s->positions[s->triangles[3 * t]].y, -4.0, 1e-6, "emitter moved to y = -4");
    }

    int32_t floor_m = find_material(s, "floor"), tall = find_material(s, "tallBox"), light = find_material(s, "light");
    CHECK(floor_m >= 0 && s->materials[floor_m].type == IC_MAT_GLOSSY && s->materials[floor_m].ns == 50.0f &&
              s->materials[floor_m].ks.y == 0.2f && fabsf(s->materials[floor_m].kd.x - 0.725f) < 1e-6f,
          "floor override: glossy ks 0.2 ns 50, kd kept");
    CHECK(tall >= 0 && s->materials[tall].type == IC_MAT_MIRROR && s->materials[tall].ks.x == 1.0f,
          "tallBox override: mirror, white tint");
    CHECK(light >= 0 && s->materials[light].emission.y == 2.0f && s->materials[light].two_sided_emission,
          "light override: emission and two-sided");
    for (uint32_t i = 0; i < s->tri_light_count; ++i)
        if (s->triangle_material[s->tri_lights[i].triangle] == (uint32_t)light)
            CHECK_NEAR(s->tri_lights[i].power, 2.0 * IC_PI * s->tri_lights[i].area * v3_lum(v3(1, 2, 3)), 1e-3,
                       "two-sided power doubles");

    CHECK(s->point_light_count == 1 && s->point_lights[0].position.y == 3.0f && s->point_lights[0].intensity.x == 5.0f,
          "point light");
    CHECK(s->sun.enabled && s->sun.direction.y == 1.0f && s->sun.irradiance.z == 3.0f, "sun normalized, grey");
    CHECK(s->env.enabled && s->env.image.width == 0 && s->env.radiance.z == 0.3f, "constant sky");
    ic_light_selection ls = s->light_select;
    CHECK_NEAR(ls.tri + ls.point + ls.sun + ls.env, 1.0, 1e-6, "selection sums to 1");
    CHECK(ls.tri > 0 && ls.point > 0 && ls.sun > 0 && ls.env > 0, "every class can be picked");
    CHECK_NEAR(ls.point / ls.tri, 4 * IC_PI * 5 / s->tri_light_power, 1e-4, "point vs triangle by power");
    CHECK(s->settings.spp == 16 && s->settings.max_depth == 4 && s->settings.seed == 7 && s->settings.has_exposure &&
              s->settings.exposure == -1.5f,
          "render settings");
    CHECK(s->camera.width == 512 && s->camera.fov_y_deg == 45.0f, "no camera: fitted default");
    ic_scene_free(s);
}

/* A 1×1 normal map of the unperturbed normal at map_path, and an MTL file of one material 'm' (grey, with
 * that map as its `norm`) at mtl_path, in the same folder. */
static void write_flat_normal_map(const char *map_path, const char *mtl_path)
{
    ic_image img = {0};
    ic_error err = {0};
    CHECK(ic_image_create(&img, 1, 1) == IC_OK, "normal map image");
    img.rgb[0] = 0.5f, img.rgb[1] = 0.5f, img.rgb[2] = 1.0f;
    CHECK(ic_image_write(map_path, &img, NULL, &err) == IC_OK, "normal map: %s", err.message);
    ic_image_free(&img);
    char mtl[600];
    snprintf(mtl, sizeof mtl, "newmtl m\nKd 0.5 0.5 0.5\nnorm %s\n", strrchr(map_path, '/') + 1);
    test_write_text(mtl_path, mtl);
}

/* The parts of a mesh file with one material are merged into one mesh before identical vertices are
 * joined and tangents computed (assimp's PreTransformVertices, JoinIdenticalVertices, CalcTangentSpace):
 * two OBJ groups (`o`, then `g`) of one material, squares sharing the edge x = 1, are 6 vertices, not
 * 4 + 4, so that a limit of 7 elements takes them; and with a normal map each of the seam's two vertices
 * has one tangent, not one per group (the groups' differ by about 20° there: the second square tilts and
 * its texture coordinates run at another rate). */
static void test_groups_joined(void)
{
    ic_error err = {0};
    write_flat_normal_map(IC_TEST_TMP "/seam_n.pfm", IC_TEST_TMP "/seam.mtl");
    const char *group[2] = {"o", "g"};
    for (int k = 0; k < 2; ++k) {
        char obj[1024];
        snprintf(obj, sizeof obj,
                 "mtllib seam.mtl\n"
                 "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0.5\nv 2 1 0.5\n"
                 "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 1.5 0.2\nvt 1.5 1.4\n"
                 "vn 0 0 1\nvn -0.2 0 1\nvn -0.4 0 1\n"
                 "usemtl m\n"
                 "%s A\nf 1/1/1 2/2/2 3/3/2\nf 1/1/1 3/3/2 4/4/1\n"
                 "%s B\nf 2/2/2 5/5/3 6/6/3\nf 2/2/2 6/6/3 3/3/2\n",
                 group[k], group[k]);
        test_write_text(IC_TEST_TMP "/seam.obj", obj);
        ic_scene *s = load(IC_TEST_TMP "/seam.obj", NULL);
        if (!s)
            continue;
        CHECK(s->vertex_count == 6 && s->triangle_count == 4, "`%s` groups: 6 vertices (%u), 4 triangles (%u)",
              group[k], s->vertex_count, s->triangle_count);
        /* every two triangle corners at one place have one tangent */
        int tangents = s->tangents != NULL, split = 0;
        for (uint32_t a = 0; tangents && a < 3 * s->triangle_count; ++a)
            for (uint32_t b = a + 1; b < 3 * s->triangle_count; ++b) {
                uint32_t va = s->triangles[a], vb = s->triangles[b];
                if (v3_len(v3_sub(s->positions[va], s->positions[vb])) > 0.0f)
                    continue;
                float d = 0.0f;
                for (int c = 0; c < 4; ++c)
                    d = fmaxf(d, fabsf(s->tangents[4 * va + c] - s->tangents[4 * vb + c]));
                split += d > 1e-6f;
            }
        CHECK(tangents && split == 0, "`%s` groups: one tangent at each place (%d corner pairs differ)", group[k],
              split);
        ic_scene_free(s);
        ic_scene_load_options opt = {0};
        opt.max_mesh_elements = 7;
        s = NULL;
        CHECK(ic_scene_load(IC_TEST_TMP "/seam.obj", &opt, &s, &err) == IC_OK,
              "`%s` groups under a limit of 7 elements: %s", group[k], err.message);
        ic_scene_free(s);
    }
}

static void test_fov_x_and_shared(void)
{
    ic_scene *s = load(SCENES "fov_x.json", NULL);
    if (s) {
        /* fov_x 90 at 200x100: tan(fy/2) = tan(45°)·100/200 */
        CHECK_NEAR(s->camera.fov_y_deg, 2.0 * atan(0.5) * 180.0 / 3.14159265358979, 1e-4, "fov_x → fov_y");
        CHECK(s->camera.width == 200 && s->camera.height == 100, "resolution");
    }
    ic_scene_free(s);

    ic_scene_load_options opt = {0};
    opt.shared_scenes_dir = IC_SOURCE_DIR "/tests/scenes";
    s = load(SCENES "shared_mesh.json", &opt);
    if (s)
        CHECK(s->triangle_count == 4 && s->tri_light_count == 2, "shared: mesh loaded (%u)", s->triangle_count);
    ic_scene_free(s);
}

static void test_degenerate_dropped(void)
{
    ic_scene *s = load(SCENES "degenerate.json", NULL);
    if (s) {
        CHECK(s->triangle_count == 2, "kept %u", s->triangle_count);
        CHECK(s->dropped_degenerate == 1, "dropped %u", s->dropped_degenerate);
        /* the user is told, once, with the file the triangle came from */
        const char *w = ic_scene_warnings(s);
        CHECK(strstr(w, "degenerate.obj: 1 triangle of zero area") && !strchr(strchr(w, '\n') + 1, '\n'),
              "one warning naming the mesh: '%s'", w);
    }
    ic_scene_free(s);
    s = load(SCENES "degenerate.obj", NULL);
    if (s)
        CHECK(s->dropped_degenerate == 1 && strstr(ic_scene_warnings(s), "zero area"), "bare mesh too");
    ic_scene_free(s);
}

/* Unit geometric normal of triangle t, from its corners in double (no float overflow or underflow). */
static void exact_normal(const ic_scene *s, uint32_t t, double n[3], double *area)
{
    const ic_vec3 *p = s->positions;
    const uint32_t *i = s->triangles + 3 * t;
    double e1[3] = {(double)p[i[1]].x - p[i[0]].x, (double)p[i[1]].y - p[i[0]].y, (double)p[i[1]].z - p[i[0]].z};
    double e2[3] = {(double)p[i[2]].x - p[i[0]].x, (double)p[i[2]].y - p[i[0]].y, (double)p[i[2]].z - p[i[0]].z};
    double c[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    for (int k = 0; k < 3; ++k)
        n[k] = c[k] / len;
    *area = 0.5 * len;
}

/* Every kept triangle's geometric normal (ic_scene_surface) is the double-precision one, of unit length. */
static void check_normals(const ic_scene *s, const char *what)
{
    for (uint32_t t = 0; t < s->triangle_count; ++t) {
        ic_surface srf;
        ic_scene_surface(s, t, 0.25f, 0.25f, &srf);
        double n[3], area;
        exact_normal(s, t, n, &area);
        double off = fabs(srf.ng.x - n[0]) + fabs(srf.ng.y - n[1]) + fabs(srf.ng.z - n[2]);
        CHECK(off < 1e-6 && fabs(v3_len(srf.ng) - 1.0) < 1e-6, "%s, triangle %u: ng (%g %g %g), expected (%g %g %g)",
              what, t, (double)srf.ng.x, (double)srf.ng.y, (double)srf.ng.z, n[0], n[1], n[2]);
    }
}

/* Triangles of any size within the largest coordinate keep their normal and area: the drop test and the
 * normal took the float |e1 × e2|², which overflows for edges beyond about 4e9 (a 1e12 floor vanished as
 * "zero area", an emitter of 1e18 made the scene fail as all-degenerate) and underflows for edges below
 * about 1e-10 (a 1e-15 triangle dropped although its normal is well defined). A collinear triangle, whose
 * cross product is truly zero, is still dropped and counted. Both loaders' paths: assimp (OBJ) and
 * ic_scene_append_triangles (Radiance polygons). A ray hits the 1e12 floor where it should. */
static void test_extreme_triangles(void)
{
    test_write_text(IC_TEST_TMP "/extreme.mtl", "newmtl ground\nKd 0.5 0.5 0.5\nnewmtl lamp\nKd 0 0 0\nKe 1 1 1\n");
    test_write_text(IC_TEST_TMP "/extreme.obj",
                    "mtllib extreme.mtl\nusemtl ground\n"
                    "v -1e12 0 -1e12\nv 1e12 0 -1e12\nv 1e12 0 1e12\nv 3e12 0 3e12\n"
                    "f 1 3 2\nf 1 3 4\n" /* the floor (normal +y) and a collinear one */
                    "usemtl lamp\nv 1e18 0 0\nv 0 1e18 0\nv 0 0 1e18\nf 5 7 6\n"); /* facing the origin */
    test_write_text(IC_TEST_TMP "/extreme.json", /* a camera of its own: the fitted one would stand beyond 1e18 */
                    "{\"camera\": {\"eye\": [0, 1, 5], \"target\": [0, 0, 0], \"up\": [0, 1, 0], \"fov_y\": 60,\n"
                    "            \"width\": 8, \"height\": 8},\n"
                    " \"meshes\": [{\"path\": \"extreme.obj\"}]}\n");
    ic_scene *s = load(IC_TEST_TMP "/extreme.json", NULL);
    if (s) {
        CHECK(s->triangle_count == 2 && s->dropped_degenerate == 1,
              "extreme.obj: the 1e12 floor and the 1e18 lamp kept (%u of 2), the collinear triangle dropped (%u of 1)",
              s->triangle_count, s->dropped_degenerate);
        check_normals(s, "extreme.obj");
        CHECK(s->tri_light_count == 1, "one emitting triangle (%u)", s->tri_light_count);
        if (s->tri_light_count == 1) {
            const ic_tri_light *l = &s->tri_lights[0];
            double n[3], area;
            exact_normal(s, l->triangle, n, &area);
            CHECK(fabs(l->area / area - 1.0) < 1e-5, "the lamp's area %g, expected %g", (double)l->area, area);
            CHECK(fabs(l->normal.x - n[0]) + fabs(l->normal.y - n[1]) + fabs(l->normal.z - n[2]) < 1e-6,
                  "the lamp's normal (%g %g %g)", (double)l->normal.x, (double)l->normal.y, (double)l->normal.z);
            /* From the origin straight at the lamp's plane x + y + z = 1e18 (distance 1e18/sqrt 3, cosine 1):
             * the area pdf turned into solid angle, d²/A = (1e36/3) / (sqrt(3)/2 · 1e36). */
            ic_vec3 wi = v3_norm(v3(1, 1, 1));
            float pdf = ic_scene_light_pdf_triangle(s, v3s(0.0f), l->triangle, wi, 1e18f / sqrtf(3.0f));
            double expect = s->light_select.tri * 2.0 / (3.0 * sqrt(3.0));
            CHECK(fabs(pdf / expect - 1.0) < 1e-4, "the lamp's pdf %g, expected %g", (double)pdf, expect);
            ic_light_sample ls;
            int ok = ic_scene_sample_light(s, v3s(0.0f), 0.5f, 0.3f, 0.4f, &ls);
            CHECK(ok && isfinite(ls.pdf) && ls.pdf > 0.0f && fabs(v3_len(ls.wi) - 1.0) < 1e-6,
                  "a sample of the lamp: pdf %g", (double)ls.pdf);
        }
        ic_accel *accel = NULL;
        ic_error err = {0};
        CHECK(ic_accel_create(s, &accel, &err) == IC_OK, "accel: %s", err.message);
        if (accel) {
            ic_ray ray = {v3(0.25f, 1.0f, 0.5f), v3(0.0f, -1.0f, 0.0f), 0.0f, INFINITY};
            ic_hit hit;
            ic_accel_intersect1(accel, &ray, &hit);
            CHECK(hit.triangle != IC_NO_HIT && fabs(hit.t - 1.0) < 1e-6, "a ray down hits the floor at t = 1 (%u, %g)",
                  hit.triangle, (double)hit.t);
            if (hit.triangle != IC_NO_HIT) {
                ic_surface srf;
                ic_scene_surface(s, hit.triangle, hit.u, hit.v, &srf);
                printf("1e12 floor: hit at (%g %g %g) for (0.25 0 0.5), ng (%g %g %g)\n", (double)srf.p.x,
                       (double)srf.p.y, (double)srf.p.z, (double)srf.ng.x, (double)srf.ng.y, (double)srf.ng.z);
                    /* y is exact (the floor is the plane y = 0); x and z come from float barycentrics times the
                 * floor's 2e12 edges: within a few of its ulps (2e12 · 2^-22), not of 0.25 and 0.5 */
                CHECK(srf.p.y == 0.0f && srf.ng.y == 1.0f && fabs(srf.p.x - 0.25) < 5e5 && fabs(srf.p.z - 0.5) < 5e5,
                      "on the floor, facing up");
            }
            ic_accel_destroy(accel);
        }
    }
    ic_scene_free(s);
    /* Radiance polygons: a 1e-15 triangle (|c|² = 3e-60 underflows), a 1e12 one, a collinear one. */
    test_write_text(IC_TEST_TMP "/extreme.rad",
                    "void plastic m 0 0 5 .5 .5 .5 0 0\n"
                    "m polygon tiny 0 0 9  1e-15 0 0  0 1e-15 0  0 0 1e-15\n"
                    "m polygon big 0 0 9  1e12 0 0  0 2e12 0  0 0 3e12\n"
                    "m polygon flat 0 0 9  0 0 0  1e12 1e12 0  2e12 2e12 0\n");
    s = load(IC_TEST_TMP "/extreme.rad", NULL);
    if (s) {
        CHECK(s->triangle_count == 2 && s->dropped_degenerate == 1,
              "extreme.rad: the 1e-15 and 1e12 triangles kept (%u of 2), the collinear one dropped (%u of 1)",
              s->triangle_count, s->dropped_degenerate);
        CHECK(strstr(ic_scene_warnings(s), "extreme.rad: 1 triangle of zero area"), "the drop is reported: '%s'",
              ic_scene_warnings(s));
        check_normals(s, "extreme.rad");
    }
    ic_scene_free(s);
}

/* ic_scene_light_count: 0 for a scene nothing lights (the command warns that the image will be black). */
static void test_light_count(void)
{
    ic_scene *s = load(SCENES "no_light.json", NULL);
    CHECK(s && ic_scene_light_count(s) == 0, "no_light.json: no light (%u)", s ? ic_scene_light_count(s) : 99u);
    ic_scene_free(s);
    s = load(SCENES "quad_light.obj", NULL);
    CHECK(s && ic_scene_light_count(s) == 2, "quad_light.obj: two emitting triangles (%u)",
          s ? ic_scene_light_count(s) : 0u);
    ic_scene_free(s);
    s = load(SCENES "plain_quad.obj", NULL);
    CHECK(s && ic_scene_light_count(s) == 1, "a bare mesh without emitters gets the white sky (%u)",
          s ? ic_scene_light_count(s) : 0u);
    ic_scene_free(s);
    CHECK(ic_scene_light_count(NULL) == 0, "NULL scene");
}

/* ic_render refuses sample counts above the caps the scene file and the command line share. */
static void test_render_caps(void)
{
    ic_scene *s = load(SCENES "quad_light.obj", NULL);
    if (!s)
        return;
    ic_render_options opt = {0};
    ic_image img = {0};
    ic_error err;
    opt.spp = IC_MAX_SPP + 1;
    CHECK(ic_render(s, &opt, &img, NULL, &err) == IC_ERR_INVALID_ARG && strstr(err.message, "--spp 16777217"),
          "spp above IC_MAX_SPP: %s", err.message);
    opt.spp = 1;
    opt.integrator = IC_INTEGRATOR_IC;
    opt.ic.light_samples = IC_MAX_LIGHT_SAMPLES + 1;
    CHECK(ic_render(s, &opt, &img, NULL, &err) == IC_ERR_INVALID_ARG && strstr(err.message, "--light-samples 65537"),
          "light samples above IC_MAX_LIGHT_SAMPLES: %s", err.message);
    /* A pixel limit beyond the largest image the library holds: refused before the render (it rendered the
     * whole image, then failed to make it, blaming memory). */
    opt.ic.light_samples = 0;
    opt.max_image_pixels = (uint64_t)IC_IMAGE_MAX_PIXELS + 1;
    CHECK(ic_render(s, &opt, &img, NULL, &err) == IC_ERR_INVALID_ARG && strstr(err.message, "268435457 is above"),
          "max_image_pixels above IC_IMAGE_MAX_PIXELS: %s", err.message);
    /* An embedder's slips: no scene or no image (dereferenced), a time budget that is not a number (taken as
     * none), NULL-safe getters like ic_scene_light_count's. */
    opt.max_image_pixels = 0;
    opt.integrator = IC_INTEGRATOR_PT;
    CHECK(ic_render(NULL, &opt, &img, NULL, &err) == IC_ERR_INVALID_ARG, "a NULL scene rendered");
    CHECK(ic_render(s, &opt, NULL, NULL, &err) == IC_ERR_INVALID_ARG, "a render into NULL");
    opt.time_budget = NAN;
    CHECK(ic_render(s, &opt, &img, NULL, &err) == IC_ERR_INVALID_ARG && !img.rgb, "a time budget of NaN: %s",
          ic_result_name(err.code));
    int w = 1, h = 1;
    ic_scene_resolution(NULL, &w, &h);
    CHECK(w == 0 && h == 0 && ic_scene_exposure(NULL) == 0.0f, "NULL scene getters");
    ic_scene_resolution(s, NULL, NULL);
    /* Threads beyond IC_MAX_THREADS (the command's cap too): the per-thread buffers were sized by the count
     * asked for and a billion threads ran out of memory instead of being refused. */
    opt.time_budget = 0.0;
    opt.threads = IC_MAX_THREADS + 1;
    CHECK(ic_render(s, &opt, &img, NULL, &err) == IC_ERR_INVALID_ARG && strstr(err.message, "--threads 4097"),
          "threads above IC_MAX_THREADS: %s", err.message);
    ic_image_free(&img);
    ic_scene_free(s);
}

/* An MTL in another folder than its OBJ: map_Kd is read from the MTL's folder (the MTL format's rule). */
static void test_mtl_folder(void)
{
    ic_scene *s = load(SCENES "mtl_folder/quad.obj", NULL);
    if (!s)
        return;
    int textured = 0;
    for (uint32_t m = 0; m < s->material_count; ++m)
        textured += s->materials[m].kd_texture == 0;
    CHECK(s->texture_count == 1 && s->textures[0].width == 2 && textured == 1,
          "texture beside the MTL in a subfolder loaded");
    ic_scene_free(s);
}

/* The bytes of the file at path (malloc'd; NULL if unreadable). */
static unsigned char *read_all(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    unsigned char *data = NULL;
    long n = -1;
    if (f && fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0 &&
        (data = malloc((size_t)n + 1)) != NULL && fread(data, 1, (size_t)n, f) != (size_t)n) {
        free(data);
        data = NULL;
    }
    if (f)
        fclose(f);
    *size = data ? (size_t)n : 0;
    CHECK(data != NULL, "read %s", path);
    return data;
}

static void write_all(const char *path, const unsigned char *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    CHECK(f && fwrite(data, 1, size, f) == size && fclose(f) == 0, "write %s", path);
}

/* An 8-bit texture is kept as its sRGB bytes (a quarter of the floats' memory) when every texel is one of
 * the 256 values the decoder gives, and as floats otherwise: a PNG holding every byte value in every
 * channel comes back as those bytes, each reading the decoder's value; the same texels with one value off
 * the table stay floats. */
static void test_texture_bytes(void)
{
    ic_image img = {0};
    ic_error err = {0};
    CHECK(ic_image_create(&img, 256, 2) == IC_OK, "texture image");
    for (int k = 0; k < 512; ++k)
        for (int c = 0; c < 3; ++c)
            img.rgb[3 * k + c] = ic_srgb8_to_linear((uint8_t)((k + 85 * c) % 256));
    CHECK(ic_image_write(IC_TEST_TMP "/bytes.png", &img, NULL, &err) == IC_OK, "PNG written: %s", err.message);
    img.rgb[7] = 0.5f * (ic_srgb8_to_linear(200) + ic_srgb8_to_linear(201)); /* no byte decodes to this */
    CHECK(ic_image_write(IC_TEST_TMP "/bytes.pfm", &img, NULL, &err) == IC_OK, "PFM written: %s", err.message);
    const char *obj = "mtllib bytes.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                      "usemtl png\nf 1/1 2/2 3/3\nusemtl pfm\nf 1/1 3/3 2/2\n";
    const char *mtl = "newmtl png\nKd 1 1 1\nmap_Kd bytes.png\nnewmtl pfm\nKd 1 1 1\nmap_Kd bytes.pfm\n";
    write_all(IC_TEST_TMP "/bytes.obj", (const unsigned char *)obj, strlen(obj));
    write_all(IC_TEST_TMP "/bytes.mtl", (const unsigned char *)mtl, strlen(mtl));
    ic_scene *s = load(IC_TEST_TMP "/bytes.obj", NULL);
    if (s) {
        const ic_texture *png = NULL, *pfm = NULL;
        for (uint32_t t = 0; t < s->texture_count; ++t) {
            if (strstr(s->textures[t].path, "bytes.png"))
                png = &s->textures[t];
            if (strstr(s->textures[t].path, "bytes.pfm"))
                pfm = &s->textures[t];
        }
        CHECK(png && png->srgb8 && !png->rgb, "8-bit texture kept as bytes");
        int wrong = 0;
        for (int i = 0; png && png->srgb8 && i < 3 * 512; ++i) {
            int k = i / 3, c = i % 3;
            uint8_t want = (uint8_t)((k + 85 * c) % 256);
            wrong += png->srgb8[i] != want || ic_texture_value(png, (size_t)i) != ic_srgb8_to_linear(want);
        }
        CHECK(wrong == 0, "every byte value read back (%d texels wrong)", wrong);
        CHECK(pfm && !pfm->srgb8 && pfm->rgb && pfm->rgb[7] == img.rgb[7], "a value off the table keeps the floats");
        ic_scene_free(s);
    }
    ic_image_free(&img);
}

/* A gzip copy of the file at from (zlib's gzip writer, best compression). */
static void gzip_copy(const char *from, const char *to)
{
    size_t size;
    unsigned char *data = read_all(from, &size);
    gzFile gz = gzopen(to, "wb9");
    CHECK(gz && data && gzwrite(gz, data, (unsigned)size) == (int)size, "gzip %s", to);
    if (gz)
        gzclose(gz);
    free(data);
}

static void copy_file(const char *from, const char *to)
{
    size_t size;
    unsigned char *data = read_all(from, &size);
    if (data)
        write_all(to, data, size);
    free(data);
}

/* The load fails with a one-line message that names the file and says what went wrong. */
static void check_gz_error(const char *path, const char *what)
{
    ic_scene *s = NULL;
    ic_error err = {0};
    ic_result r = ic_scene_load(path, NULL, &s, &err);
    CHECK(r == IC_ERR_PARSE && !s, "%s: %s (%s)", path, ic_result_name(r), err.message);
    CHECK(strstr(err.message, path) && strstr(err.message, what) && !strchr(err.message, '\n'),
          "one line naming %s and saying '%s': %s", path, what, err.message);
    ic_scene_free(s);
}

/* Gzip-compressed meshes: the same triangles and materials as the file itself, MTL files and textures
 * found from the .gz file's folder; truncated, corrupt and empty files are errors naming the file. */
static void test_gzip_meshes(void)
{
#define GZ IC_TEST_TMP "/gz"
    CHECK((mkdir(IC_TEST_TMP, 0755) == 0 || errno == EEXIST) && (mkdir(GZ, 0755) == 0 || errno == EEXIST) &&
              (mkdir(GZ "/materials", 0755) == 0 || errno == EEXIST),
          "scratch folders");
    gzip_copy(IC_SOURCE_DIR "/scenes/cornell-box/CornellBox-Original.obj", GZ "/cornell.obj.gz");
    copy_file(IC_SOURCE_DIR "/scenes/cornell-box/CornellBox-Original.mtl", GZ "/CornellBox-Original.mtl");
    ic_scene *plain = load(IC_SOURCE_DIR "/scenes/cornell-box/CornellBox-Original.obj", NULL);
    ic_scene *s = load(GZ "/cornell.obj.gz", NULL);
    if (s && plain) {
        CHECK(s->triangle_count == plain->triangle_count && s->triangle_count == 36, "gzip: %u triangles, plain %u",
              s->triangle_count, plain->triangle_count);
        CHECK(s->vertex_count == plain->vertex_count &&
                  !memcmp(s->positions, plain->positions, sizeof *s->positions * s->vertex_count),
              "gzip: the same vertices");
        int32_t left = find_material(s, "leftWall");
        CHECK(left >= 0 && fabsf(s->materials[left].kd.x - 0.63f) < 1e-6f, "gzip: the MTL beside the .gz is read");
        CHECK(s->tri_light_count == 2 && !s->env.enabled, "gzip: the MTL's emitter, no default sky");
    }
    ic_scene_free(plain);
    ic_scene_free(s);

    /* in a scene file, with a transform */
    static const char json[] = "{ \"meshes\": [ { \"path\": \"cornell.obj.gz\", "
                               "\"transform\": { \"translate\": [0, -5, 0] } } ] }\n";
    write_all(GZ "/scene.json", (const unsigned char *)json, sizeof json - 1);
    s = load(GZ "/scene.json", NULL);
    if (s)
        CHECK(s->triangle_count == 36 && fabsf(s->bounds_max.y - (1.99f - 5.0f)) < 1e-5f,
              "gzip mesh in a scene file: %u triangles, top %g", s->triangle_count, s->bounds_max.y);
    ic_scene_free(s);

    /* an MTL in a subfolder and its texture beside it resolve from the .gz file's folder */
    gzip_copy(SCENES "mtl_folder/quad.obj", GZ "/quad.obj.gz");
    copy_file(SCENES "mtl_folder/materials/quad.mtl", GZ "/materials/quad.mtl");
    copy_file(SCENES "mtl_folder/materials/checker.pfm", GZ "/materials/checker.pfm");
    s = load(GZ "/quad.obj.gz", NULL);
    if (s) {
        int32_t m = find_material(s, "checker");
        CHECK(s->triangle_count == 2 && s->texture_count == 1 && m >= 0 && s->materials[m].kd_texture == 0,
              "gzip: MTL in a subfolder and its texture: %u triangles, %u textures", s->triangle_count,
              s->texture_count);
    }
    ic_scene_free(s);

    /* glTF: the emissive strength assimp drops is read from the inflated JSON */
    gzip_copy(SCENES "triangle.gltf", GZ "/triangle.gltf.gz");
    s = load(GZ "/triangle.gltf.gz", NULL);
    if (s) {
        int32_t m = find_material(s, "lamp_pbr");
        CHECK(s->triangle_count == 1 && m >= 0 && s->materials[m].emission.x == 4.0f, "gzip glTF with its strength");
    }
    ic_scene_free(s);

    /* two gzip members one after the other (gzip a b > c) inflate to the two files' concatenation */
    size_t size;
    unsigned char *gz = read_all(GZ "/cornell.obj.gz", &size);
    if (gz) {
        unsigned char *twice = malloc(2 * size);
        if (twice) {
            memcpy(twice, gz, size);
            memcpy(twice + size, gz, size);
            write_all(GZ "/twice.obj.gz", twice, 2 * size);
            s = load(GZ "/twice.obj.gz", NULL);
            if (s)
                CHECK(s->triangle_count == 72, "two members: %u triangles", s->triangle_count);
            ic_scene_free(s);
        }
        free(twice);

        write_all(GZ "/truncated.obj.gz", gz, size / 2);
        check_gz_error(GZ "/truncated.obj.gz", "truncated");
        gz[size - 6] ^= 0x55; /* the CRC-32 of the trailer */
        write_all(GZ "/crc.obj.gz", gz, size);
        check_gz_error(GZ "/crc.obj.gz", "corrupt");
        gz[0] = 'x'; /* not the gzip magic */
        write_all(GZ "/magic.obj.gz", gz, size);
        check_gz_error(GZ "/magic.obj.gz", "not gzip");
    }
    free(gz);
    write_all(GZ "/empty.obj.gz", (const unsigned char *)"", 0);
    check_gz_error(GZ "/empty.obj.gz", "empty");
#undef GZ
}

static void test_bare_mesh_and_queries(void)
{
    ic_scene *s = load(SCENES "plain_quad.obj", NULL);
    if (!s)
        return;
    CHECK(s->triangle_count == 2 && s->uvs && s->normals, "textured quad with normals");
    CHECK(s->env.enabled && s->env.radiance.x == 1.0f && s->env.image.width == 0, "no emitter: white sky");
    CHECK(s->light_select.env == 1.0f, "the sky is the only light");
    CHECK_NEAR(s->camera.target.x, 0.5, 1e-6, "fitted camera looks at the centre");
    CHECK_NEAR(s->camera.target.y, 0.5, 1e-6, "fitted camera looks at the centre");
    CHECK(s->camera.eye.z > 1.0f && s->camera.fov_y_deg == 45.0f, "from +z, fov 45");
    /* distance fits the bounding sphere (radius sqrt(2)/2) in the 45° field of view */
    CHECK_NEAR(s->camera.eye.z, (sqrt(2.0) / 2) / sin(22.5 * 3.14159265358979 / 180), 1e-4, "fitted distance");
    CHECK(s->texture_count == 1 && s->textures[0].width == 2, "checker texture loaded");

    for (uint32_t t = 0; t < s->triangle_count; ++t) {
        ic_surface srf;
        float u = 0.2f, v = 0.3f;
        ic_scene_surface(s, t, u, v, &srf);
        const uint32_t *idx = s->triangles + 3 * t;
        ic_vec3 expect = v3_add(v3_add(v3_scale(s->positions[idx[0]], 1 - u - v), v3_scale(s->positions[idx[1]], u)),
                                v3_scale(s->positions[idx[2]], v));
        CHECK(v3_len(v3_sub(srf.p, expect)) < 1e-6f, "Embree barycentrics");
        CHECK_NEAR(srf.ng.z, 1.0, 1e-6, "ng from winding");
        CHECK_NEAR(srf.ns.z, 1.0, 1e-6, "ns from vertex normals");
        CHECK_NEAR(srf.uv[0], srf.p.x, 1e-6, "uv = xy on this quad");
        CHECK_NEAR(srf.uv[1], srf.p.y, 1e-6, "uv = xy on this quad");
        CHECK(srf.triangle == t && srf.material == s->triangle_material[t], "ids");
    }

    /* checker: top row red, green; bottom row blue, white; uv (0,0) = bottom-left */
    ic_surface srf;
    memset(&srf, 0, sizeof srf);
    srf.material = s->triangle_material[0];
    struct { float u, v, r, g, b; } probes[] = {
        {0.25f, 0.75f, 1, 0, 0},     {0.75f, 0.75f, 0, 1, 0},    {0.25f, 0.25f, 0, 0, 1},
        {0.75f, 0.25f, 1, 1, 1},     {0.5f, 0.5f, 0.5f, 0.5f, 0.5f}, {1.25f, -0.25f, 1, 0, 0},
        {0.5f, 0.75f, 0.5f, 0.5f, 0}, /* halfway between red and green */
    };
    for (size_t i = 0; i < sizeof probes / sizeof probes[0]; ++i) {
        srf.uv[0] = probes[i].u;
        srf.uv[1] = probes[i].v;
        ic_vec3 a = ic_scene_albedo(s, &srf);
        CHECK(fabsf(a.x - probes[i].r) < 1e-5f && fabsf(a.y - probes[i].g) < 1e-5f && fabsf(a.z - probes[i].b) < 1e-5f,
              "albedo at uv (%g, %g) = (%g, %g, %g)", probes[i].u, probes[i].v, a.x, a.y, a.z);
    }
    ic_scene_free(s);

    s = load(SCENES "flipped_normal.obj", NULL);
    if (s) {
        ic_surface f;
        ic_scene_surface(s, 0, 0.3f, 0.3f, &f);
        CHECK(f.ng.z > 0.99f && f.ns.z > 0.99f, "shading normal flipped to the ng side (%g)", f.ns.z);
    }
    ic_scene_free(s);

    s = load(SCENES "quad_light.obj", NULL);
    if (s) {
        CHECK(!s->env.enabled, "a mesh with an emitter gets no sky");
        for (uint32_t t = 0; t < s->triangle_count; ++t) {
            if (s->triangle_light[t] < 0)
                continue;
            ic_surface e;
            ic_scene_surface(s, t, 0.25f, 0.25f, &e);
            CHECK(ic_scene_emission(s, &e, v3(0, -1, 0)).x == 2.0f, "emits on its front (down)");
            CHECK(ic_scene_emission(s, &e, v3(0, 1, 0)).x == 0.0f, "dark on its back");
        }
    }
    ic_scene_free(s);
    ic_scene_free(NULL);
}

/* glTF metallic/roughness and emission mapping; PLY geometry */
static void test_gltf_and_ply(void)
{
    ic_scene *s = load(SCENES "triangle.gltf", NULL);
    if (s) {
        int32_t m = find_material(s, "lamp_pbr");
        CHECK(s->triangle_count == 1 && m >= 0, "glTF triangle and material");
        if (m >= 0) {
            const ic_material *mat = &s->materials[m];
            /* base (0.8, 0.6, 0.4), metallic 0.2, roughness 0.5: a plastic of alpha 0.25 over kd = base */
            CHECK(mat->type == IC_MAT_PLASTIC, "dielectric-ish glTF material is a rough plastic");
            CHECK_NEAR(mat->alpha, 0.25, 1e-6, "GGX alpha = roughness squared");
            CHECK_NEAR(mat->kd.x, 0.8, 1e-6, "kd = base colour");
            CHECK_NEAR(mat->ior, 1.5, 1e-6, "coat index 1.5 (F0 = 0.04)");
            /* emissiveFactor (1, 0.5, 0.25) × KHR_materials_emissive_strength 4 */
            CHECK(mat->emission.x == 4.0f && mat->emission.y == 2.0f && mat->emission.z == 1.0f,
                  "emission with strength: %g %g %g", mat->emission.x, mat->emission.y, mat->emission.z);
            CHECK(mat->two_sided_emission, "doubleSided emits both ways");
        }
        CHECK(s->tri_light_count == 1 && !s->env.enabled, "an emitter: no default sky");
        CHECK_NEAR(s->positions[s->triangles[0]].z, -2.0, 1e-6, "node translation applied");
    }
    ic_scene_free(s);
    s = load(SCENES "triangle.ply", NULL);
    if (s) {
        CHECK(s->triangle_count == 1 && s->tri_light_count == 0 && s->env.enabled, "PLY triangle under a white sky");
        ic_surface srf;
        ic_scene_surface(s, 0, 0.25f, 0.25f, &srf);
        CHECK_NEAR(srf.ng.z, 1.0, 1e-6, "PLY winding");
    }
    ic_scene_free(s);
}

/* An 8-bit PNG texture keeps its sRGB bytes: every texel value equals, bit for bit, what the file reads
 * as floats; a float texture whose values are not sRGB bytes keeps its floats. */
static void test_texture_storage(void)
{
    ic_image img;
    ic_error err;
    CHECK(ic_image_create(&img, 37, 23) == IC_OK, "create");
    for (int i = 0; i < 37 * 23 * 3; ++i)
        img.rgb[i] = (float)((i * 7919) % 1000) / 999.0f; /* all over [0, 1], then 8-bit in the file */
    char png[512], pfm[512];
    snprintf(png, sizeof png, "%s/texture_8bit.png", IC_TEST_TMP);
    snprintf(pfm, sizeof pfm, "%s/texture_float.pfm", IC_TEST_TMP);
    CHECK(ic_image_write(png, &img, NULL, &err) == IC_OK, "write png: %s", err.message);
    CHECK(ic_image_write(pfm, &img, NULL, &err) == IC_OK, "write pfm: %s", err.message);
    ic_scene *s = calloc(1, sizeof *s);
    ic_scene_builder builder = {0};
    builder.scene = s;
    int32_t a = -1, b = -1;
    CHECK(ic_scene_texture_load(&builder, png, "test", &a, &err) == IC_OK && a == 0, "load png: %s", err.message);
    CHECK(ic_scene_texture_load(&builder, pfm, "test", &b, &err) == IC_OK && b == 1, "load pfm: %s", err.message);
    /* A float texture with a negative or a NaN texel is refused, naming the texel (a negative kd gave
     * negative pixels, a NaN dark walls); nothing is added to the scene. */
    for (int k = 0; k < 2; ++k) {
        char bad[512];
        snprintf(bad, sizeof bad, "%s/texture_bad%d.pfm", IC_TEST_TMP, k);
        const float px[6] = {0.5f, 0.5f, 0.5f, 0.5f, k ? NAN : -2.0f, 0.5f}; /* 2x1, little-endian */
        FILE *f = fopen(bad, "wb");
        if (f) {
            fputs("PF\n2 1\n-1.0\n", f);
            fwrite(px, sizeof px[0], 6, f);
            fclose(f);
        }
        int32_t c = -1;
        ic_result r = ic_scene_texture_load(&builder, bad, "test", &c, &err);
        CHECK(r == IC_ERR_INVALID_ARG && strstr(err.message, "texture_bad") &&
                  strstr(err.message, k ? "texel (1, 0) has a green value of nan" : "texel (1, 0) has a green value of -2") &&
                  s->texture_count == 2,
              "a %s texel refused: %s", k ? "NaN" : "negative", err.message);
    }
    ic_image back;
    CHECK(ic_image_read(png, &back, &err) == IC_OK, "read png: %s", err.message);
    const ic_texture *t8 = &s->textures[0], *tf = &s->textures[1];
    CHECK(t8->srgb8 != NULL && t8->rgb == NULL, "the 8-bit texture keeps bytes");
    CHECK(tf->srgb8 == NULL && tf->rgb != NULL, "the float texture keeps floats");
    int differ = 0;
    for (size_t i = 0; i < (size_t)37 * 23 * 3; ++i) {
        float x = ic_texture_value(t8, i), y = ic_texture_value(tf, i);
        differ += memcmp(&x, &back.rgb[i], sizeof x) != 0 || memcmp(&y, &img.rgb[i], sizeof y) != 0;
    }
    CHECK(differ == 0, "%d texel values differ from the files' floats", differ);
    ic_image_free(&back);
    ic_image_free(&img);
    /* The bilinear look-up, through a material of each texture, against the formula written out with
     * the wrap taken as a true modulo: at the edges, just inside them, exactly on texel centres and
     * far outside [0, 1] on both sides (repeat). */
    s->materials = calloc(2, sizeof *s->materials);
    if (s->materials) {
        s->material_count = 2;
        s->materials[0].kd_texture = 0;
        s->materials[1].kd_texture = 1;
        const float fixed[] = {0.0f, 1.0f, -1.0f, -1e-9f, 1e-9f, 1.0f - 1e-7f, 0.5f / 37.0f, 36.5f / 37.0f, 0.5f / 23.0f,
                               -2.25f, 3.75f, 1e3f + 0.125f};
        const int nf = (int)(sizeof fixed / sizeof fixed[0]);
        int bad = 0;
        uint64_t state = 12345;
        for (int k = 0; k < 4000; ++k) {
            float u, v;
            if (k < nf * nf) {
                u = fixed[k % nf];
                v = fixed[k / nf];
            } else {
                state = state * 6364136223846793005ULL + 1442695040888963407ULL;
                u = (float)((double)(state >> 11) / 9007199254740992.0 * 8.0 - 4.0);
                state = state * 6364136223846793005ULL + 1442695040888963407ULL;
                v = (float)((double)(state >> 11) / 9007199254740992.0 * 8.0 - 4.0);
            }
            for (int m = 0; m < 2; ++m) {
                const ic_texture *t = &s->textures[m];
                ic_surface srf;
                memset(&srf, 0, sizeof srf);
                srf.material = (uint32_t)m;
                srf.uv[0] = u;
                srf.uv[1] = v;
                ic_vec3 got = ic_scene_texture_tint(s, &srf);
                double x = (double)((u - floorf(u)) * (float)t->width - 0.5f);
                double y = (double)((1.0f - (v - floorf(v))) * (float)t->height - 0.5f);
                double x0 = floor(x), y0 = floor(y), fx = x - x0, fy = y - y0;
                const float *g = &got.x;
                for (int ch = 0; ch < 3; ++ch) {
                    double want = 0.0;
                    for (int dy = 0; dy < 2; ++dy)
                        for (int dx = 0; dx < 2; ++dx) {
                            long xi = (((long)x0 + dx) % t->width + t->width) % t->width;
                            long yi = (((long)y0 + dy) % t->height + t->height) % t->height;
                            double w = (dx ? fx : 1.0 - fx) * (dy ? fy : 1.0 - fy);
                            want += w * ic_texture_value(t, 3 * ((size_t)yi * (size_t)t->width + (size_t)xi) + (size_t)ch);
                        }
                    bad += !(fabs(g[ch] - want) < 1e-5);
                }
            }
        }
        CHECK(bad == 0, "%d bilinear look-ups differ from the formula", bad);
    }
    ic_scene_free(s);
}

/* 1 if (x, y) lies inside the polygon of n corners xy (even-odd rule). */
static int inside_polygon(const float *xy, int n, float x, float y)
{
    int in = 0;
    for (int i = 0, j = n - 1; i < n; j = i++)
        if ((xy[2 * i + 1] > y) != (xy[2 * j + 1] > y) &&
            x < xy[2 * j] + (y - xy[2 * j + 1]) * (xy[2 * i] - xy[2 * j]) / (xy[2 * i + 1] - xy[2 * j + 1]))
            in = !in;
    return in;
}

/* Concave polygons of five or more corners (an OBJ face, a PLY face) keep their outline: the triangles cover
 * the polygon's area exactly (its shoelace area), each lies inside it and faces the side its winding gives.
 * assimp 5.2's ear clipping, which irrcache used, covered an L-shaped hexagon of area 3 with triangles of
 * area 4, one of them outside the L and facing the other way. A mirroring transform keeps the front side. A
 * normal-mapped polygon whose first three corners lie on a line still gets the tangent of its texture
 * coordinates (+x, and a bitangent −y where v runs down), not the arbitrary one assimp's tangent step takes from a line. */
static void test_concave_polygons(void)
{
    /* an L and a comb with two teeth (8 corners), counter-clockwise seen from +z, in the plane z = 0 */
    static const float l_xy[] = {0, 0, 2, 0, 2, 1, 1, 1, 1, 2, 0, 2};
    static const float comb_xy[] = {0, 0, 3, 0, 3, 2, 2, 2, 2, 1, 1, 1, 1, 2, 0, 2};
    const struct {
        const float *xy;
        int n;
    } polys[2] = {{l_xy, 6}, {comb_xy, 8}};
    for (int k = 0; k < 2; ++k) {
        const float *xy = polys[k].xy;
        int n = polys[k].n;
        double area = 0.0;
        for (int i = 0; i < n; ++i)
            area += 0.5 * (xy[2 * i] * xy[2 * ((i + 1) % n) + 1] - xy[2 * ((i + 1) % n)] * xy[2 * i + 1]);
        char obj[1024], ply[1024], face[256] = "f", ply_face[256];
        size_t used = 0, pused = 0;
        used += (size_t)snprintf(obj + used, sizeof obj - used, "# a concave polygon\n");
        pused += (size_t)snprintf(ply + pused, sizeof ply - pused,
                                  "ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
                                  "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                  "end_header\n", n);
        snprintf(ply_face, sizeof ply_face, "%d", n);
        for (int i = 0; i < n; ++i) {
            used += (size_t)snprintf(obj + used, sizeof obj - used, "v %g %g 0\n", xy[2 * i], xy[2 * i + 1]);
            pused += (size_t)snprintf(ply + pused, sizeof ply - pused, "%g %g 0\n", xy[2 * i], xy[2 * i + 1]);
            size_t fl = strlen(face), pl = strlen(ply_face);
            snprintf(face + fl, sizeof face - fl, " %d", i - n); /* negative (relative) indices */
            snprintf(ply_face + pl, sizeof ply_face - pl, " %d", i);
        }
        snprintf(obj + used, sizeof obj - used, "%s\n", face);
        snprintf(ply + pused, sizeof ply - pused, "%s\n", ply_face);
        test_write_text(IC_TEST_TMP "/concave.obj", obj);
        test_write_text(IC_TEST_TMP "/concave.ply", ply);
        test_write_text(IC_TEST_TMP "/concave_mirror.json",
                        "{\"meshes\": [{\"path\": \"concave.obj\", \"transform\": {\"scale\": [-1, 1, 1]}}]}\n");
        const char *files[3] = {IC_TEST_TMP "/concave.obj", IC_TEST_TMP "/concave.ply",
                                IC_TEST_TMP "/concave_mirror.json"};
        for (int f = 0; f < 3; ++f) {
            ic_scene *s = load(files[f], NULL);
            if (!s)
                continue;
            float sx = f == 2 ? -1.0f : 1.0f; /* the mirror: x → −x, the front stays +z */
            double covered = 0.0;
            int outside = 0, backwards = 0;
            for (uint32_t t = 0; t < s->triangle_count; ++t) {
                ic_vec3 p0 = s->positions[s->triangles[3 * t]], p1 = s->positions[s->triangles[3 * t + 1]],
                        p2 = s->positions[s->triangles[3 * t + 2]];
                ic_vec3 c = v3_cross(v3_sub(p1, p0), v3_sub(p2, p0));
                covered += 0.5 * fabs((double)c.z);
                backwards += c.z <= 0.0f;
                ic_vec3 centroid = v3_scale(v3_add(v3_add(p0, p1), p2), 1.0f / 3.0f);
                outside += !inside_polygon(xy, n, sx * centroid.x, centroid.y);
            }
            CHECK(s->triangle_count == (uint32_t)n - 2, "%s (%d corners): %u triangles, want %d", files[f], n,
                  s->triangle_count, n - 2);
            CHECK(fabs(covered - area) < 1e-5, "%s (%d corners): the triangles cover %g, the polygon %g", files[f], n,
                  covered, area);
            CHECK(outside == 0 && backwards == 0, "%s (%d corners): %d triangles outside the polygon, %d facing -z",
                  files[f], n, outside, backwards);
            ic_scene_free(s);
        }
    }

    /* a normal-mapped pentagon starting with three corners on the line y = 0, u = x and v = 1 − y: a texture
     * laid out upside down, whose bitangent (+v) is −y, the opposite of n × t = +y (sign −1) */
    write_flat_normal_map(IC_TEST_TMP "/pent_n.pfm", IC_TEST_TMP "/pent.mtl");
    test_write_text(IC_TEST_TMP "/pent.obj", "mtllib pent.mtl\nv 0 0 0\nv 1 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\n"
                                             "vt 0 1\nvt 1 1\nvt 2 1\nvt 2 0\nvt 0 0\nvn 0 0 1\nusemtl m\n"
                                             "f 1/1/1 2/2/1 3/3/1 4/4/1 5/5/1\n");
    ic_scene *s = load(IC_TEST_TMP "/pent.obj", NULL);
    if (s) {
        int good = s->tangents != NULL && s->triangle_count == 2; /* the corner on the edge adds none */
        for (uint32_t v = 0; good && v < s->vertex_count; ++v)
            good = fabsf(s->tangents[4 * v] - 1.0f) < 1e-4f && s->tangents[4 * v + 3] == -1.0f;
        CHECK(good, "normal-mapped pentagon (first three corners on a line): tangent +x, bitangent sign -1 at every "
                    "vertex (%u triangles)", s->triangle_count);
        ic_scene_free(s);
    }
}

/* What a mesh file's materials ask for that the import does not apply is warned, not dropped without a word:
 * an MTL texture's -s, -o, -t and -clamp on (assimp drops the first three; irrcache repeats every texture), with
 * the MTL file's line, options at their defaults excepted; and in a glTF file an emission texture, a texture
 * read through TEXCOORD_1, a clamping sampler and a KHR_texture_transform, each once per file. */
static void test_unread_texture_features(void)
{
    test_write_text(IC_TEST_TMP "/mapopt.mtl", "newmtl a\nKd 1 1 1\nmap_Kd -s 2 2 1 -o 0 0 0 mapopt.pfm\n"
                                               "newmtl b\nKd 1 1 1\nmap_Kd -o 0 0 0 -s 1 1 1 -clamp off mapopt.pfm\n");
    test_write_text(IC_TEST_TMP "/mapopt.obj", "mtllib mapopt.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 2 0 0\nvt 0 0\nvt 1 0\n"
                                               "vt 1 1\nusemtl a\nf 1/1 2/2 3/3\nusemtl b\nf 2/1 4/2 3/3\n");
    ic_image img = {0};
    ic_error err = {0};
    CHECK(ic_image_create(&img, 1, 1) == IC_OK, "texture");
    CHECK(ic_image_write(IC_TEST_TMP "/mapopt.pfm", &img, NULL, &err) == IC_OK, "texture: %s", err.message);
    ic_image_free(&img);
    ic_scene *s = load(IC_TEST_TMP "/mapopt.obj", NULL);
    if (s) {
        const char *w = ic_scene_warnings(s);
        CHECK(strstr(w, "mapopt.mtl:3: material 'a': the texture options -s of map_Kd are not applied") &&
                  !strstr(w, "'b'"),
              "MTL -s warned with its line, defaults (-o 0 0 0, -s 1 1 1, -clamp off) not: %s", w);
        ic_scene_free(s);
    }
    s = load(SCENES "unread_texture_features.gltf", NULL);
    if (s) {
        const char *w = ic_scene_warnings(s), *kinds[4] = {"emission texture", "second set of texture coordinates",
                                                            "clamps or mirrors", "KHR_texture_transform"};
        for (int k = 0; k < 4; ++k)
            CHECK(strstr(w, kinds[k]) && strstr(w, "material 'decal'"), "glTF: '%s' warned: %s", kinds[k], w);
        ic_scene_free(s);
    }
    s = load(SCENES "triangle.gltf", NULL);
    if (s)
        CHECK(!strstr(ic_scene_warnings(s), "material"), "a plain glTF file: no warning: %s", ic_scene_warnings(s));
    ic_scene_free(s);
}

int main(void)
{
    test_cornell_box();
    test_transformed();
    test_mirrored_normals();
    test_groups_joined();
    test_concave_polygons();
    test_unread_texture_features();
    test_fov_x_and_shared();
    test_degenerate_dropped();
    test_extreme_triangles();
    test_bare_mesh_and_queries();
    test_mtl_folder();
    test_texture_bytes();
    test_gltf_and_ply();
    test_light_count();
    test_render_caps();
    test_texture_storage();
    test_gzip_meshes();
    TEST_MAIN_END();
}
