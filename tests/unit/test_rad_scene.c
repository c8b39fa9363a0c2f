/*
 * test_rad_scene.c — Radiance scene files (.rad) and view files, against the JSON scene and analytic answers:
 *   1. scenes/cornell-box/cornell-box.rad with cornell-box.vf renders as the JSON scene whose light reflects
 *      nothing (a Radiance light does not), image for image; against scenes/cornell-box/cornell-box.json
 *      itself, its squared difference stays within 1.5 times that of two JSON renders with other seeds
 *      (pooled over four pairs; the ratio lies in 0.7–1.3 across seeds), while a light 10 % brighter exceeds
 *      it; 1 and 2 threads give the same image;
 *   2. a floor (plastic without specularity, ρ = 0.5) under a 360° glow source of radiance 2 shows ρ·L = 1;
 *      under a small source (the sun), ρ·L·Ω/π; under a light sphere, ρ·L·sin²α (the sphere's irradiance);
 *   3. geometry: a concave polygon keeps its area (ear clipping), sphere vertices lie on the sphere, ring and
 *      cylinder areas are within the tessellation's 0.16 % of the true ones, cones face out and tubes in, and
 *      no shape leaves a triangle of zero area (dropped with a warning), nor a polygon with a vertex on an
 *      edge or one given twice (one on a line is reported);
 *   4. materials and modifiers: plastic, metal, glass, mirror, trans, alias, illum, a mixture, a pattern;
 *      a mesh through its OBJ file with a transform;
 *   5. errors: "!" command lines, instance, undefined modifiers, wrong argument counts, a truncated file and
 *      bad views name file:line; unsupported kinds warn once.
 */
#include "test_util.h"
#include "test_render_util.h"

#include "irrcache/points.h"
#include "irrcache/render.h"
#include "scene/scene.h"

#include <stdio.h>
#include <string.h>

#define PI_D 3.14159265358979323846
#ifndef RAD_SEED
#define RAD_SEED 100
#endif


/* The scene at path, size × size pixels, from the view file view (NULL: none); NULL (err set) on failure. */
static ic_scene *load_view(const char *path, const char *view, int size, ic_error *err)
{
    ic_scene *s;
    test_load_scene(path, view, size, size, 1, &s, err);
    return s;
}

static int render(const ic_scene *s, int spp, uint64_t seed, int threads, ic_image *img)
{
    ic_render_options opt = test_seeded_options(spp, threads, seed);
    return test_render_loaded(s, &opt, img);
}

/* Σ(a − b)² / Σ b² over every channel. */
static double rel_sq_error(const ic_image *a, const ic_image *b)
{
    double num = 0.0, den = 0.0;
    for (size_t i = 0; i < (size_t)a->width * a->height * 3; ++i) {
        num += (a->rgb[i] - b->rgb[i]) * (double)(a->rgb[i] - b->rgb[i]);
        den += b->rgb[i] * (double)b->rgb[i];
    }
    return den > 0.0 ? num / den : 0.0;
}

static void test_cornell(void)
{
    char json[1024];
    snprintf(json, sizeof json,
             "{\"camera\": {\"eye\": [0, 1, 3.9], \"target\": [0, 1, 0], \"up\": [0, 1, 0], \"fov_y\": 39.3, "
             "\"width\": 32, \"height\": 32},\n \"meshes\": [{\"path\": \"%s/scenes/cornell-box/CornellBox-Original.obj\"}],\n"
             " \"materials\": {\"light\": {\"kd\": [0, 0, 0]}}}\n",
             IC_SOURCE_DIR);
    test_write_file(IC_TEST_TMP "/cornell_rad.json", json);
    ic_error err = {0};
    ic_scene *a = load_view(IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.rad",
                            IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.vf", 32, &err);
    CHECK(a != NULL, "Radiance Cornell box loads: %s", err.message);
    ic_scene *b = load_view(IC_TEST_TMP "/cornell_rad.json", NULL, 32, &err);
    CHECK(b != NULL, "JSON Cornell box loads: %s", err.message);
    ic_scene *c = load_view(IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json", NULL, 32, &err);
    CHECK(c != NULL, "scenes/cornell-box/cornell-box.json loads: %s", err.message);
    /* a control the comparison must catch: the same box with a light 10 % brighter */
    char *text = NULL;
    FILE *f = fopen(IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.rad", "rb");
    size_t len = 0;
    if (f && (text = calloc(1, 65536)) != NULL)
        len = fread(text, 1, 65535, f);
    if (f)
        fclose(f);
    char *light = text ? strstr(text, "3 17 12 4") : NULL, *edited = calloc(1, 65536 + 16);
    ic_scene *bright = NULL;
    if (light && edited && len > 0) {
        snprintf(edited, 65536 + 16, "%.*s3 18.7 13.2 4.4%s", (int)(light - text), text, light + 9);
        test_write_file(IC_TEST_TMP "/cornell_bright.rad", edited);
        bright = load_view(IC_TEST_TMP "/cornell_bright.rad", IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.vf", 32, &err);
    }
    free(text);
    free(edited);
    CHECK(bright != NULL, "the brighter control loads: %s", err.message);
    if (a && b && c) {
        CHECK(a->camera.width == 32 && a->camera.height == 32 && fabsf(a->camera.fov_y_deg - 39.3f) < 1e-4f,
              "view: 32x32 (square view), fov 39.3: %dx%d %g", a->camera.width, a->camera.height,
              (double)a->camera.fov_y_deg);
        CHECK(a->triangle_count == b->triangle_count && a->tri_light_count == b->tri_light_count,
              "the same triangles and emitters: %u/%u %u/%u", a->triangle_count, b->triangle_count,
              a->tri_light_count, b->tri_light_count);
        ic_image ia = {0}, ib = {0}, ic = {0}, i2 = {0};
        if (render(a, 4, 1, 2, &ia) && render(b, 4, 1, 2, &ib)) {
            double e = rel_sq_error(&ia, &ib);
            printf("cornell .rad vs JSON (black light), same seed: relative squared error %g\n", e);
            CHECK(e <= 1e-6, "the .rad scene renders as the JSON one with a black light (relative squared error %g)",
                  e);
        }
        if (render(a, 4, 1, 1, &i2))
            CHECK(rel_sq_error(&i2, &ia) == 0.0, "1 and 2 threads: the same image");
        /* against the scene file as it is (its light reflects 0.78): pairs of renders with independent seeds,
         * .rad against JSON and JSON against JSON, pooled over four pairs each (one pair's error varies by
         * ±30 % from seed to seed) */
        double diff = 0.0, noise = 0.0, control = 0.0;
        for (int k = 0; k < 4; ++k) {
            ic_image_free(&ia);
            ic_image_free(&ib);
            ic_image_free(&ic);
            if (!render(a, 64, RAD_SEED + k, 2, &ia) || !render(c, 64, RAD_SEED + 10 + k, 2, &ib) ||
                !render(c, 64, RAD_SEED + 20 + k, 2, &ic))
                break;
            diff += rel_sq_error(&ia, &ib) / 4.0;
            noise += rel_sq_error(&ic, &ib) / 4.0;
            ic_image_free(&ia);
            if (bright && render(bright, 64, RAD_SEED + k, 2, &ia))
                control += rel_sq_error(&ia, &ib) / 4.0;
        }
        printf("cornell .rad vs cornell-box.json: %g; JSON vs JSON, other seeds: %g (ratio %.3f); a light 10 %% "
               "brighter: %g (ratio %.3f)\n",
               diff, noise, noise > 0.0 ? diff / noise : 0.0, control, noise > 0.0 ? control / noise : 0.0);
        CHECK(noise > 0.0 && diff <= 1.5 * noise, "rad vs JSON: relative squared error %g, JSON vs JSON %g", diff, noise);
        CHECK(!bright || control > 1.5 * noise, "the comparison sees a light 10 %% brighter: %g, noise %g", control, noise);
        ic_image_free(&ia);
        ic_image_free(&ib);
        ic_image_free(&ic);
        ic_image_free(&i2);
    }
    ic_scene_free(a);
    ic_scene_free(b);
    ic_scene_free(c);
    ic_scene_free(bright);
}

/* A 2000 m floor (ρ = 0.5, facing +z) seen from 2 m above; extra: the lights. Mean of the centre pixels. */
static double floor_centre(const char *name, const char *lights, int spp)
{
    char rad[2048], path[512];
    snprintf(rad, sizeof rad,
             "void plastic grey\n0\n0\n5 .5 .5 .5 0 0\n"
             "grey polygon floor\n0\n0\n12\n -1000 -1000 0\n 1000 -1000 0\n 1000 1000 0\n -1000 1000 0\n%s",
             lights);
    snprintf(path, sizeof path, IC_TEST_TMP "/%s.rad", name);
    test_write_file(path, rad);
    test_write_file(IC_TEST_TMP "/floor.vf", "# looking down\nrpict -x 100 -vtv -vp 0 0 2 -vd 0 0 -1 -vu 0 1 0 -vh 10 -vv 10 -ab 2\n");
    ic_error err = {0};
    ic_scene *s = load_view(path, IC_TEST_TMP "/floor.vf", 16, &err);
    CHECK(s != NULL, "%s loads: %s", name, err.message);
    ic_render_options opt = {0};
    opt.spp = spp;
    opt.threads = 2;
    return s ? test_scene_box_mean(s, &opt, 6, 6, 4, 1) : -1.0;
}

static void test_analytic(void)
{
    double sky = floor_centre("rad_sky", "void glow skyglow\n0\n0\n4 2 2 2 0\nskyglow source sky\n0\n0\n4 0 0 1 360\n", 4);
    CHECK(fabs(sky - 1.0) < 0.03, "floor under a 360-degree glow source: %g, expected rho L = 1", sky);
    /* An illum as a source's modifier gives its own radiance (its alternate material is for surfaces): with
     * none it was refused, with one the alternate's 10 was used. */
    double illum = floor_centre("rad_illum", "void light alt\n0\n0\n3 10 10 10\nvoid illum skyillum\n1 alt\n0\n3 2 2 2\n"
                                             "skyillum source sky\n0\n0\n4 0 0 1 360\n", 4);
    double bare = floor_centre("rad_illum0", "void illum skyillum\n0\n0\n3 2 2 2\nskyillum source sky\n0\n0\n4 0 0 1 360\n",
                               4);
    CHECK(fabs(illum - 1.0) < 0.03 && fabs(bare - 1.0) < 0.03,
          "floor under a 360-degree illum source, with and without an alternate: %g, %g, expected rho L = 1", illum, bare);
    /* An alias of an illum is one (it was refused as a source's modifier: "needs a light, glow or illum"), and
     * Radiance 5's "inherit alias" is an alias (it was refused: "modified by 'inherit', which is not defined"). */
    double aliased = floor_centre("rad_illum_alias", "void illum skyillum\n0\n0\n3 2 2 2\nvoid alias sky2 skyillum\n"
                                                     "sky2 source sky\n0\n0\n4 0 0 1 360\n", 4);
    double inherited = floor_centre("rad_inherit", "void glow skyglow\n0\n0\n4 2 2 2 0\ninherit alias sky2 skyglow\n"
                                                   "sky2 source sky\n0\n0\n4 0 0 1 360\n", 4);
    CHECK(fabs(aliased - 1.0) < 0.03 && fabs(inherited - 1.0) < 0.03,
          "floor under a 360-degree source of an alias of an illum, and of an inherit alias of a glow: %g, %g, expected "
          "rho L = 1", aliased, inherited);
    /* the sun: 0.5° across, radiance 1e5: irradiance L Ω */
    double omega = 2.0 * PI_D * (1.0 - cos(0.25 * PI_D / 180.0));
    double sun = floor_centre("rad_sun", "void light sunlight\n0\n0\n3 1e5 1e5 1e5\nsunlight source sun\n0\n0\n4 0 0 1 0.5\n", 4);
    double want = 0.5 * 1e5 * omega / PI_D;
    CHECK(fabs(sun - want) < 1e-3 * want, "floor under a small source: %g, expected rho L Omega / pi = %g", sun, want);
    /* a light sphere of radius 0.5 centred 3 m above: E = π L sin²α, sin α = 0.5/3 */
    double ball = floor_centre("rad_ball", "void light bulb\n0\n0\n3 10 10 10\nbulb sphere ball\n0\n0\n4 0 0 3 0.5\n", 64);
    double want_ball = 0.5 * 10.0 * (0.5 / 3.0) * (0.5 / 3.0);
    printf("floor: glow source %g (1), sun %g (%g), light sphere %g (%g)\n", sky, sun, want, ball, want_ball);
    CHECK(fabs(ball - want_ball) < 0.01 * want_ball, "floor under a light sphere: %g, expected rho L sin^2(alpha) = %g",
          ball, want_ball);
}

static double triangle_area(const ic_scene *s, uint32_t t)
{
    ic_vec3 a = s->positions[s->triangles[3 * t]], b = s->positions[s->triangles[3 * t + 1]],
            c = s->positions[s->triangles[3 * t + 2]];
    return 0.5 * v3_len(v3_cross(v3_sub(b, a), v3_sub(c, a)));
}

static const ic_material *material_named(const ic_scene *s, const char *name)
{
    for (uint32_t m = 0; m < s->material_count; ++m)
        if (!strcmp(s->materials[m].name, name))
            return &s->materials[m];
    return NULL;
}

/* A ring's normal is a direction whatever its length: (1, 2, 3) given 1e20, 1e-23 or 1e39 times over (squares
 * beyond a float's range, or the normal itself) makes the ring that (1, 2, 3) makes, vertex for vertex within
 * float rounding (the long ones had made a ring of zero area, dropped without a word, or refused it as beyond
 * the largest coordinate; the short one's direction, from a denormal squared length, was 1e-3 off). */
static void test_ring_normal_length(void)
{
    static const double scale[4] = {1.0, 1e20, 1e-23, 1e39};
    ic_scene *s[4] = {NULL};
    for (int k = 0; k < 4; ++k) {
        char rad[256], path[256];
        snprintf(rad, sizeof rad, "void plastic m 0 0 5 .5 .5 .5 0 0\nm ring r 0 0 8  1 2 3  %.17g %.17g %.17g  0.5 2\n",
                 1.0 * scale[k], 2.0 * scale[k], 3.0 * scale[k]);
        snprintf(path, sizeof path, IC_TEST_TMP "/rad_ring_normal%d.rad", k);
        test_write_file(path, rad);
        ic_error err = {0};
        CHECK(ic_scene_load(path, NULL, &s[k], &err) == IC_OK, "a ring whose normal is %g times (1, 2, 3) loads: %s",
              scale[k], err.message);
    }
    for (int k = 1; k < 4 && s[0]; ++k) {
        if (!s[k])
            continue;
        float worst = 0.0f;
        for (uint32_t i = 0; i < s[0]->vertex_count && i < s[k]->vertex_count; ++i)
            worst = fmaxf(worst, v3_len(v3_sub(s[0]->positions[i], s[k]->positions[i])));
        CHECK(s[k]->triangle_count == s[0]->triangle_count && s[0]->triangle_count == 128 &&
                  s[k]->vertex_count == s[0]->vertex_count && worst < 1e-5f,
              "the normal %g times (1, 2, 3): %u triangles (128), the vertices of the unit one's (off by %g)", scale[k],
              s[k]->triangle_count, (double)worst);
    }
    for (int k = 0; k < 4; ++k)
        ic_scene_free(s[k]);
}

static void test_geometry_and_materials(void)
{
    char rad[8192];
    snprintf(rad, sizeof rad,
             "# every shape, each with its own material\n"
             "void plastic cpoly 0 0 5 .5 .5 .5 0 0\n"
             "void plastic cball 0 0 5 .5 .5 .5 .05 .1\n"
             "void metal cring 0 0 5 .8 .6 .2 .9 .05\n"
             "void metal ccyl 0 0 5 .8 .8 .8 1 0\n"
             "void glass cglass 0 0 3 .9 .9 .9\n"
             "void mirror ctube 0 0 3 .7 .7 .7\n"
             "void brightfunc dirt 2 dirt dirt.cal 0 0\n"
             "void brightfunc dirt2 2 dirt dirt.cal 0 0\n"
             "dirt trans ctrans 0 0 7 .6 .6 .6 .04 0 .5 .5\n"
             "void alias cpoly2 cpoly\n"
             "void illum window 1 cglass 0 3 100 100 100\n"
             "void illum hole 0 0 3 100 100 100\n"
             "void mixfunc mix 4 cball cring mixer . 0 0\n"
             "cpoly polygon C\n0\n0\n24  0 0 0  3 0 0  3 1 0  1 1 0  1 2 0  3 2 0  3 3 0  0 3 0\n"
             "cball sphere ball\n0\n0\n4 1 2 3 0.5\n"
             "cring ring ring\n0\n0\n8 0 0 5  0 0 1  1 2\n"
             "ccyl cylinder cyl\n0\n0\n7 10 0 0  10 0 4  1\n"
             "ctube tube tube\n0\n0\n7 20 0 0  20 0 4  1\n"
             "cglass cone cone\n0\n0\n8 30 0 0  30 0 2  1 0\n"
             "ctrans polygon t 0 0 9 0 0 9 1 0 9 0 1 9\n"
             "cpoly2 polygon a 0 0 9 0 0 8 1 0 8 0 1 8\n"
             "window polygon w 0 0 9 0 0 7 1 0 7 0 1 7\n"
             "hole polygon h 0 0 9 0 0 6 1 0 6 0 1 6\n"
             "void polygon v 0 0 9 0 0 5 1 0 5 0 1 5\n"
             "mix polygon m 0 0 9 0 0 4 1 0 4 0 1 4\n"
             "void mesh box 5 %s/scenes/cornell-box/CornellBox-Original.obj -t 100 0 0 0 0\n",
             IC_SOURCE_DIR);
    test_write_file(IC_TEST_TMP "/rad_shapes.rad", rad);
    ic_error err = {0};
    ic_scene *s = load_view(IC_TEST_TMP "/rad_shapes.rad", NULL, 16, &err);
    CHECK(s != NULL, "shapes scene loads: %s", err.message);
    if (!s)
        return;
    ic_vec3 look = v3_sub(s->camera.target, s->camera.eye);
    CHECK(look.x == 0.0f && look.y > 0.0f && look.z == 0.0f && s->camera.up.z == 1.0f,
          "without a view: a fitted camera looking along +y with +z up");
    double area[16] = {0};
    int sphere_off = 0, cone_in = 0, tube_out = 0, poly_down = 0, mesh_tris = 0;
    const char *names[] = {"cpoly", "cball", "cring", "ccyl", "ctube", "cglass"};
    for (uint32_t t = 0; t < s->triangle_count; ++t) {
        const ic_material *m = &s->materials[s->triangle_material[t]];
        ic_vec3 a = s->positions[s->triangles[3 * t]], b = s->positions[s->triangles[3 * t + 1]],
                c = s->positions[s->triangles[3 * t + 2]];
        ic_vec3 ng = v3_cross(v3_sub(b, a), v3_sub(c, a)), centroid = v3_scale(v3_add(a, v3_add(b, c)), 1.0f / 3.0f);
        for (int k = 0; k < 6; ++k)
            if (!strcmp(m->name, names[k]))
                area[k] += triangle_area(s, t);
        if (!strcmp(m->name, "cpoly") && centroid.z == 0.0f)
            poly_down += ng.z <= 0.0f;
        if (!strcmp(m->name, "cball"))
            for (int k = 0; k < 3; ++k)
                sphere_off |= fabsf(v3_len(v3_sub(s->positions[s->triangles[3 * t + k]], v3(1, 2, 3))) - 0.5f) > 1e-5f;
        if (!strcmp(m->name, "ccyl"))
            cone_in += v3_dot(ng, v3_sub(centroid, v3(10, 0, centroid.z))) <= 0.0f;
        if (!strcmp(m->name, "ctube"))
            tube_out += v3_dot(ng, v3_sub(centroid, v3(20, 0, centroid.z))) >= 0.0f;
        mesh_tris += centroid.x > 90.0f;
    }
    CHECK(fabs(area[0] - 7.0) < 1e-5, "the C-shaped polygon: area 7, nothing overlapping: %g", area[0]);
    CHECK(!poly_down, "every polygon triangle faces +z (counter-clockwise vertices)");
    CHECK(!sphere_off && fabs(area[1] / (PI_D) - 1.0) < 0.005, "sphere: vertices on it, area %g of pi", area[1]);
    CHECK(fabs(area[2] / (3.0 * PI_D) - 1.0) < 0.002, "ring: area %g of 3 pi", area[2]);
    CHECK(fabs(area[3] / (8.0 * PI_D) - 1.0) < 0.002 && !cone_in, "cylinder: area %g of 8 pi, facing out", area[3]);
    CHECK(fabs(area[4] / (8.0 * PI_D) - 1.0) < 0.002 && !tube_out, "tube: area %g of 8 pi, facing in", area[4]);
    double cone_area = PI_D * 1.0 * sqrt(1.0 + 4.0);
    printf("areas / true: sphere %.5f ring %.5f cylinder %.5f tube %.5f cone %.5f\n", area[1] / PI_D,
           area[2] / (3.0 * PI_D), area[3] / (8.0 * PI_D), area[4] / (8.0 * PI_D), area[5] / cone_area);
    CHECK(area[5] > 0.99 * cone_area && area[5] < cone_area, "cone: area %g of pi r l = %g", area[5], cone_area);
    CHECK(mesh_tris > 20, "the mesh's OBJ moved by -t 100 0 0: %d triangles", mesh_tris);
    /* no shape's tessellation has a triangle of zero area for the scene to drop and warn about */
    CHECK(s->dropped_degenerate == 0 && !strstr(ic_scene_warnings(s), "zero area"), "%u triangles dropped: '%s'",
          s->dropped_degenerate, ic_scene_warnings(s));

    const ic_material *m = material_named(s, "cball");
    CHECK(m && m->type == IC_MAT_PLASTIC && fabsf(m->alpha - 0.1f) < 1e-6f &&
              fabsf(powf((m->ior - 1.0f) / (m->ior + 1.0f), 2.0f) - 0.05f) < 1e-5f && m->ks.x == 1.0f,
          "plastic: a coat reflecting spec = 0.05 at normal incidence, alpha = roughness");
    m = material_named(s, "cring");
    CHECK(m && m->type == IC_MAT_PLASTIC && m->ks.y == 0.6f && m->kd.z == 0.2f, "metal (spec 0.9): a coat tinted by the colour");
    m = material_named(s, "ccyl");
    CHECK(m && m->type == IC_MAT_CONDUCTOR && m->ks.x == 0.8f, "metal (spec 1): a conductor of F0 = colour");
    m = material_named(s, "ctube");
    CHECK(m && m->type == IC_MAT_MIRROR && m->ks.x == 0.7f, "mirror");
    m = material_named(s, "cglass");
    CHECK(m && m->type == IC_MAT_THIN_GLASS && fabsf(m->ior - 1.52f) < 1e-6f && m->ks.x == 0.9f,
          "glass: a thin pane of index 1.52, transmissivity the colour");
    m = material_named(s, "ctrans");
    CHECK(m && m->type == IC_MAT_TRANSLUCENT && fabsf(m->kd.x - 0.288f) < 1e-6f && fabsf(m->kt.x - 0.144f) < 1e-6f &&
              fabsf(m->kt_specular.x - 0.144f) < 1e-6f,
          "trans: reflection colour (1 - spec)(1 - trans), diffuse and straight transmission colour (1 - spec) trans "
          "(1 -/· tspec)");
    m = material_named(s, "window");
    CHECK(m && m->type == IC_MAT_THIN_GLASS, "illum with an alternate: rendered as it");
    m = material_named(s, "mix");
    CHECK(m && m->type == IC_MAT_PLASTIC && fabsf(m->alpha - 0.1f) < 1e-6f, "a mixture: its first material");
    CHECK(!material_named(s, "hole") && !material_named(s, "v"), "void and an illum without alternate: left out");
    const char *w = ic_scene_warnings(s);
    const char *bf = strstr(w, "brightfunc");
    CHECK(bf && !strstr(bf + 1, "brightfunc"), "one warning for the two patterns: %s", w);
    CHECK(strstr(w, "rad_shapes.rad:8:") && strstr(w, "rad_shapes.rad:10: trans") && strstr(w, "void"),
          "warnings name file:line: %s", w);
    ic_scene_free(s);
}

/* Loads text as a scene (and view as its view file, when given); the error must hold each of want[]. */
static void expect_error(const char *name, const char *text, const char *view, const char *const *want)
{
    ic_error err = {0};
    ic_scene *s = test_load_rad_text(name, text, view, 16, 1, &err);
    test_check_refused(name, s, &err, want);
}

static void test_errors(void)
{
    ic_error err = {0};
    const char *good = "void light l 0 0 3 1 1 1\nl polygon p 0 0 9 0 0 0 1 0 0 0 1 0\n";
    expect_error("rad_cmd", "# a generator\nvoid plastic p 0 0 5 .5 .5 .5 0 0\n!xform -t 1 0 0 other.rad\n", NULL,
                 (const char *[]){"rad_cmd.rad:3:", "!xform -t 1 0 0 other.rad", "runs a command", NULL});
    expect_error("rad_inst", "void instance i 1 model.oct 0 0\n", NULL,
                 (const char *[]){"rad_inst.rad:1:", "instance 'i'", "octree", NULL});
    expect_error("rad_undef", "\nnosuch polygon p 0 0 9 0 0 0 1 0 0 0 1 0\n", NULL,
                 (const char *[]){"rad_undef.rad:2:", "'nosuch'", "not defined", NULL});
    expect_error("rad_count", "void plastic p\n0\n0\n4 .5 .5 .5 0\n", NULL,
                 (const char *[]){"rad_count.rad:1:", "needs 5 real arguments", NULL});
    expect_error("rad_nan", "void plastic p 0 0 5 .5 .5 x 0 0\n", NULL,
                 (const char *[]){"rad_nan.rad:1:", "'x'", "not a finite number", NULL});
    expect_error("rad_trunc", "\nvoid plastic p 0 0 5 .5 .5\n", NULL,
                 (const char *[]){"rad_trunc.rad:2:", "ends where a real argument of plastic 'p'", NULL});
    expect_error("rad_poly", "void plastic p 0 0 5 .5 .5 .5 0 0\np polygon q 0 0 6 0 0 0 1 0 0\n", NULL,
                 (const char *[]){"rad_poly.rad:2:", "at least 3 vertices", NULL});
    expect_error("rad_fisheye", good, "rview -vta -vp 0 0 1 -vd 0 0 -1 -vu 0 1 0 -vh 400\n",
                 (const char *[]){"rad_fisheye.vf:1:", "-vh", "angular fisheye", NULL});
    expect_error("rad_noview", good, "just words\n", (const char *[]){"rad_noview.vf", "no view", NULL});

    /* a word too many in a list: the next primitive would start with it; the message names the word's line and
     * the primitive it follows (it had named the following line, with the words shifted: "the number of string
     * arguments of l 'polygon' is 'p'") */
    expect_error("rad_stray", "void light l\n0\n0\n3 1 1 1 1\n\nl polygon p 0 0 9 0 0 0 1 0 0 0 1 0\n", NULL,
                 (const char *[]){"rad_stray.rad:4:", "'1' stands where a primitive should start",
                                  "light 'l' (line 1) hold more words than their counts say", NULL});
    expect_error("rad_lead", "# a count without its primitive\n3\nvoid light l 0 0 3 1 1 1\n", NULL,
                 (const char *[]){"rad_lead.rad:2:", "'3' stands where the first primitive should start", NULL});
    expect_error("rad_word", "void plastic p 0 0 5 .5 .5 .5 0 0\n\nvoid\n", NULL,
                 (const char *[]){"rad_word.rad:3:", "the type of this primitive", NULL});
    FILE *f = fopen(IC_TEST_TMP "/rad_nul.rad", "wb"); /* a NUL byte is no white space, nor the end */
    if (f) {
        static const char nul[] = "void plastic p 0 0 5 .5 .5 .5 0 0\n\0 x\n";
        fwrite(nul, 1, sizeof nul - 1, f);
        fclose(f);
    }
    ic_scene *s = load_view(IC_TEST_TMP "/rad_nul.rad", NULL, 16, &err);
    CHECK(!s && strstr(err.message, "rad_nul.rad:2:") && strstr(err.message, "NUL"), "a NUL byte: %s", err.message);
    ic_scene_free(s);

    /* a view file is for .rad scenes */
    ic_scene_load_options lo = {0};
    lo.view = IC_TEST_TMP "/floor.vf";
    s = NULL;
    ic_result r = ic_scene_load(IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json", &lo, &s, &err);
    CHECK(r == IC_ERR_INVALID_ARG && strstr(err.message, "--view"), "--view on a JSON scene: %s", err.message);
    ic_scene_free(s);

    /* unsupported kinds warn once, naming the first place */
    test_write_file(IC_TEST_TMP "/rad_warn.rad",
               "void light l 0 0 3 1 1 1\nvoid plasfunc f 2 a b 0 5 .5 .5 .5 0 0\nvoid plasfunc g 2 a b 0 5 .5 .5 .5 0 0\n"
               "l polygon p 0 0 9 0 0 0 1 0 0 0 1 0\nvoid prism1 z 0 0 0\nvoid prism1 y 0 0 0\n");
    s = load_view(IC_TEST_TMP "/rad_warn.rad", NULL, 16, &err);
    CHECK(s != NULL, "warned scene loads: %s", err.message);
    if (s) {
        const char *w = ic_scene_warnings(s), *pf = strstr(w, "plasfunc"), *pr = strstr(w, "prism1");
        CHECK(pf && !strstr(pf + 1, "plasfunc") && strstr(w, "rad_warn.rad:2: plasfunc"), "plasfunc once: %s", w);
        CHECK(pr && !strstr(pr + 1, "prism1") && strstr(w, "rad_warn.rad:5: prism1"), "prism1 once: %s", w);
    }
    ic_scene_free(s);
}

/* A scene and a view file saved with a UTF-8 byte-order mark first (as some Windows editors do) load as without
 * it: the scene's first modifier had been "\xEF\xBB\xBFvoid" (not defined), the view file had "no view". */
static void test_byte_order_mark(void)
{
    ic_error err = {0};
    ic_scene *s = test_load_rad_text("rad_bom", "\xEF\xBB\xBFvoid light l 0 0 3 1 1 1\nl polygon p 0 0 9 0 0 0 1 0 0 0 1 0\n",
                                     "\xEF\xBB\xBFrview -vtv -vp 0.25 0.25 3 -vd 0 0 -1 -vu 0 1 0 -vh 20 -vv 20\n", 16, 1,
                                     &err);
    CHECK(s != NULL, "a scene and view with byte-order marks load: %s", err.message);
    if (s)
        CHECK(s->triangle_count == 1 && s->camera.eye.x == 0.25f && s->camera.eye.z == 3.0f,
              "the triangle (%u) and the view's eye (%g %g %g)", s->triangle_count, (double)s->camera.eye.x,
              (double)s->camera.eye.y, (double)s->camera.eye.z);
    ic_scene_free(s);
}

/* A polygon with a vertex on an edge (a wall split where a window meets it) or one vertex given twice is an
 * ordinary polygon: its triangulation leaves out the pieces of zero area rather than have the scene drop
 * and report them as slivers; one whose vertices all lie on a line covers nothing and still is reported. */
static void test_polygon_zero_area_pieces(void)
{
    test_write_file(IC_TEST_TMP "/rad_collinear.rad",
                    "void plastic m 0 0 5 .5 .5 .5 0 0\n"
                    "m polygon split 0 0 15  0 0 0  1 0 0  2 0 0  2 1 0  0 1 0\n"
                    "m polygon twice 0 0 15  0 0 5  1 0 5  1 0 5  1 1 5  0 1 5\n"
                    "m polygon line 0 0 9  0 0 9  1 0 9  2 0 9\n");
    ic_error err = {0};
    ic_scene *s = NULL;
    CHECK(ic_scene_load(IC_TEST_TMP "/rad_collinear.rad", NULL, &s, &err) == IC_OK, "loads: %s", err.message);
    if (!s)
        return;
    double area = 0.0;
    for (uint32_t t = 0; t < s->triangle_count; ++t)
        area += triangle_area(s, t);
    const char *w = ic_scene_warnings(s);
    CHECK(fabs(area - 3.0) < 1e-6 && s->dropped_degenerate == 1 && strstr(w, "rad_collinear.rad: 1 triangle of zero area"),
          "the split and doubled polygons keep their areas 2 and 1 (%g), only the line's triangle is dropped (%u): '%s'",
          area, s->dropped_degenerate, w);
    ic_scene_free(s);
}

/* The share of a receiver's cosine-weighted hemisphere (the configuration factor) that the rectangle
 * [0, x] × [0, z] in the plane at distance h above it covers, corner over the receiver; odd in x and in z. */
static double corner_factor(double x, double z, double h)
{
    double X = x / h, Z = z / h, a = sqrt(1.0 + X * X), b = sqrt(1.0 + Z * Z);
    return (X / a * atan(Z / a) + Z / b * atan(X / b)) / (2.0 * PI_D);
}

/* The same for the rectangle [x0, x1] × [z0, z1]. */
static double rect_factor(double x0, double x1, double z0, double z1, double h)
{
    return corner_factor(x1, z1, h) - corner_factor(x0, z1, h) - corner_factor(x1, z0, h) + corner_factor(x0, z0, h);
}

/* 1 if p lies inside a triangle of the scene (in the plane y = 0). */
static int covered(const ic_scene *s, double x, double z)
{
    for (uint32_t t = 0; t < s->triangle_count; ++t) {
        double sgn[3];
        for (int k = 0; k < 3; ++k) {
            ic_vec3 a = s->positions[s->triangles[3 * t + k]], b = s->positions[s->triangles[3 * t + (k + 1) % 3]];
            sgn[k] = (b.x - a.x) * (z - a.z) - (b.z - a.z) * (x - a.x);
        }
        if ((sgn[0] > 0 && sgn[1] > 0 && sgn[2] > 0) || (sgn[0] < 0 && sgn[1] < 0 && sgn[2] < 0))
            return 1;
    }
    return 0;
}

/* A wall with two windows, as Radiance gives a polygon holes: the outline, then from a point on it a seam to
 * each hole, around the hole the other way and back along the seam. The wall keeps its area 16 − 1 − 2 with
 * nothing over the windows, and a sensor 1 m in front of it, facing it, receives π L times the configuration
 * factor of the wall less the windows' (Lambert). Ear clipping had taken the seam's far end, where the
 * outline passes twice, for a vertex inside every ear there, given up and made the rest a fan: one window
 * was covered, the wall's light 29 % too high (a sensor under a 4 × 4 m light with a 2 × 2 m hole read 19.0
 * for 8.7). */
static void test_polygon_holes(void)
{
    ic_error err = {0};
    ic_scene *s = test_load_rad_text("rad_holes",
                                     "void light wall 0 0 3 10 10 10\n"
                                     "wall polygon w\n0\n0\n54\n"
                                     " -2 0 -2   2 0 -2   2 0 2   -2 0 2\n"
                                     " -2 0 .5   -1.5 0 .5   -1.5 0 1.5   -.5 0 1.5   -.5 0 .5   -1.5 0 .5   -2 0 .5\n"
                                     " -2 0 -.5   -1 0 -.5   1 0 -.5   1 0 -1.5   -1 0 -1.5   -1 0 -.5   -2 0 -.5\n",
                                     NULL, 16, 1, &err);
    CHECK(s != NULL, "a polygon with two holes loads: %s", err.message);
    if (!s)
        return;
    double area = 0.0;
    int down = 0;
    for (uint32_t t = 0; t < s->triangle_count; ++t) {
        area += triangle_area(s, t);
        ic_vec3 a = s->positions[s->triangles[3 * t]], b = s->positions[s->triangles[3 * t + 1]],
                c = s->positions[s->triangles[3 * t + 2]];
        down += v3_cross(v3_sub(b, a), v3_sub(c, a)).y > 0.0f;
    }
    CHECK(fabs(area - 13.0) < 1e-5 && !down, "the wall: area %g (13), %d triangles facing +y (0)", area, down);
    CHECK(!covered(s, -1.0, 1.0) && !covered(s, 0.0, -1.0) && covered(s, 1.5, 1.5) && covered(s, 0.0, 0.0),
          "the windows are open, the wall between them is not");
    CHECK(strstr(ic_scene_warnings(s), "ear clipping") == NULL, "no warning: %s", ic_scene_warnings(s));
    ic_sensor_point pt = {{0.0f, -1.0f, 0.0f}, {0.0f, 1.0f, 0.0f}};
    ic_points_options opt = {0};
    opt.samples = 4096;
    ic_point_result res;
    CHECK(ic_points_compute(s, &pt, 1, &opt, &res, NULL, &err) == IC_OK, "points: %s", err.message);
    double want = PI_D * 10.0 *
                  (rect_factor(-2, 2, -2, 2, 1) - rect_factor(-1.5, -.5, .5, 1.5, 1) - rect_factor(-1, 1, -1.5, -.5, 1));
    printf("wall with two windows: E %g +- %g, Lambert %g\n", (double)res.irradiance.x, (double)res.irradiance_sigma.x,
           want);
    CHECK(fabs(res.irradiance.x - want) < 4.0 * res.irradiance_sigma.x + 1e-3 * want,
          "the sensor in front of the wall: E %g, expected %g", (double)res.irradiance.x, want);
    ic_scene_free(s);
}

/* A light's radiance above IC_SCENE_MAX_RADIANCE (1e30) is refused with its line (samples that overflowed were
 * dropped: a light of 3e38 read 0); 1e29 loads and renders finite, its brightest pixel the radiance seen
 * directly. light, glow, spotlight and illum; wide sources summed into one environment are checked as the
 * sum. */
static void test_radiance_limit(void)
{
    static const char *const view = "rview -vtv -vp 0 0 3 -vd 0 0 -1 -vu 0 1 0 -vh 60 -vv 60\n";
    /* the square [-1, 1]² facing +z, the camera's side, made of the modifier named first */
    static const char *const square = "\n%s polygon p\n0\n0\n12 -1 -1 0 1 -1 0 1 1 0 -1 1 0\n";
    static const struct {
        const char *name, *modifier, *type, *first, *says;
    } cases[] = {
        {"rad_limit_light", "void light hot\n0\n0\n3 1 %s 1\n", "hot", "", "light 'hot': its radiance is 1e+31"},
        {"rad_limit_glow", "void glow hot\n0\n0\n4 %s 1 1 0\n", "hot", "", "glow 'hot': its radiance is 1e+31"},
        /* pointing at the camera (+z): outside its cone a spotlight is dark */
        {"rad_limit_spot", "void spotlight hot\n0\n0\n7 %s %s %s 90 0 0 1\n", "hot", "",
         "spotlight 'hot': its radiance is 1e+31"},
        /* an illum seen as a 360-degree source: the environment, of its radiance */
        {"rad_limit_illum", "void illum hot\n0\n0\n3 %s 1 1\nhot source sky\n0\n0\n4 0 0 1 360\n", "grey",
         "void plastic grey\n0\n0\n5 .5 .5 .5 0 0\n", "illum 'hot': its radiance is 1e+31"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k)
        for (int ok = 0; ok < 2; ++ok) {
            const char *v = ok ? "1e29" : "1e31";
            char modifier[256], geometry[256], rad[1024], name[64];
            snprintf(modifier, sizeof modifier, cases[k].modifier, v, v, v);
            snprintf(geometry, sizeof geometry, square, cases[k].type);
            snprintf(rad, sizeof rad, "%s%s%s", cases[k].first, modifier, geometry);
            snprintf(name, sizeof name, "%s%s", cases[k].name, ok ? "_ok" : "");
            ic_error err = {0};
            ic_scene *sc = test_load_rad_text(name, rad, view, 16, 1, &err);
            if (ok) {
                CHECK(sc != NULL, "%s loads: %s", name, err.message);
                test_check_renders_finite(name, sc, 1e29);
                continue;
            }
            char where[96];
            snprintf(where, sizeof where, "%s.rad:%d:", name, cases[k].first[0] ? 5 : 1);
            test_check_refused(name, sc, &err, (const char *[]){where, cases[k].says, "above 1e+30", "; ", NULL});
        }
    /* Two sources of 9e29 each, within the limit alone, make an environment of 1.8e30 together. */
    ic_error err = {0};
    ic_scene *sc = test_load_rad_text("rad_limit_sum", "void glow sky\n0\n0\n4 9e29 9e29 9e29 0\n"
                                      "sky source a\n0\n0\n4 0 0 1 360\nsky source b\n0\n0\n4 0 0 1 360\n"
                                      "void plastic grey\n0\n0\n5 .5 .5 .5 0 0\n"
                                      "grey polygon p\n0\n0\n12 -1 -1 0 1 -1 0 1 1 0 -1 1 0\n",
                                      view, 16, 1, &err);
    test_check_refused("rad_limit_sum", sc, &err,
                       (const char *[]){"rad_limit_sum.rad: the environment's radiance is 1.8e+30, above 1e+30", "; ",
                                        NULL});
}

/* Many modifiers (their names found through a hash table): each surface takes the latest definition of its
 * modifier's name read so far, as in Radiance, whatever the names' hashes. 3000 plastics m0 … m2999 of
 * reflectance 0.1 + k/4000, a square of each at x = k; then m1500 defined again (0.95) and one more square
 * at x = 3000 made of it: it has 0.95, the square at x = 1500 keeps the first definition's. */
static void test_many_modifiers(void)
{
    const char *path = IC_TEST_TMP "/rad_many.rad";
    FILE *f = fopen(path, "w");
    CHECK(f != NULL, "write %s", path);
    if (!f)
        return;
    fputs("void light lamp\n0\n0\n3 1 1 1\nlamp polygon top\n0\n0\n12 0 0 5  3001 0 5  3001 1 5  0 1 5\n", f);
    for (int k = 0; k < 3000; ++k)
        fprintf(f, "void plastic m%d\n0\n0\n5 %.6f %.6f %.6f 0 0\n", k, 0.1 + k / 4000.0, 0.1 + k / 4000.0,
                0.1 + k / 4000.0);
    for (int k = 0; k < 3000; ++k)
        fprintf(f, "m%d polygon p%d\n0\n0\n12 %d 0 0  %d 0 0  %d 1 0  %d 1 0\n", k, k, k, k + 1, k + 1, k);
    fputs("void plastic m1500\n0\n0\n5 0.95 0.95 0.95 0 0\nm1500 polygon late\n0\n0\n12 3000 0 0  3001 0 0  "
          "3001 1 0  3000 1 0\n", f);
    fclose(f);
    ic_error err = {0};
    ic_scene *s = load_view(path, NULL, 16, &err);
    CHECK(s != NULL, "3000 modifiers load: %s", err.message);
    if (!s)
        return;
    int wrong = 0, floor_tris = 0;
    for (uint32_t t = 0; t < s->triangle_count; ++t) {
        ic_vec3 a = s->positions[s->triangles[3 * t]], b = s->positions[s->triangles[3 * t + 1]],
                c = s->positions[s->triangles[3 * t + 2]];
        if (a.z != 0.0f)
            continue;
        ++floor_tris;
        int k = (int)floorf((a.x + b.x + c.x) / 3.0f);
        double want = k == 3000 ? 0.95 : 0.1 + k / 4000.0;
        wrong += fabs(s->materials[s->triangle_material[t]].kd.y - want) > 1e-5;
    }
    CHECK(floor_tris == 2 * 3001 && wrong == 0, "each square has its modifier's reflectance (%d triangles, %d wrong)",
          floor_tris, wrong);
    ic_scene_free(s);
}

int main(void)
{
    test_many_modifiers();
    test_radiance_limit();
    test_polygon_zero_area_pieces();
    test_polygon_holes();
    test_byte_order_mark();
    test_ring_normal_length();
    test_cornell();
    test_analytic();
    test_geometry_and_materials();
    test_errors();
    TEST_MAIN_END();
}
