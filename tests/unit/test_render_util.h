/*
 * test_render_util.h — helpers for tests that write small scenes and render them through the public
 * API (irrcache/render.h), exactly as the command does.
 */
#ifndef IC_TEST_RENDER_UTIL_H
#define IC_TEST_RENDER_UTIL_H

#include "test_util.h"

#include "irrcache/points.h"
#include "irrcache/render.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Writes text to path or aborts the test program. */
static inline void test_write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "cannot write %s\n", path);
        exit(1);
    }
    fputs(text, f);
    fclose(f);
}

/* Writes dir/window.json (with window.obj and window.mtl): a 4 × 3 × 4 m room, 64 × 48 pixels, lit only through
 * a 1 × 1 m window by an emitting quad of 44 × 44 m outside it, a large emitter mostly hidden behind the
 * opening, which the records carry by default (ic_ic_options.large_emitters). */
static inline void test_write_window_scene(const char *dir)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/window.mtl", dir);
    test_write_file(path, "newmtl wall\nKd 0.7 0.7 0.7\nnewmtl sky\nKd 0 0 0\nKe 3 3 3\n");
    snprintf(path, sizeof path, "%s/window.obj", dir);
    test_write_file(path,
                    "mtllib window.mtl\nusemtl wall\n"
                    /* floor, ceiling, the walls x = 0, x = 4 and z = 0 */
                    "v 0 0 0\nv 4 0 0\nv 4 0 4\nv 0 0 4\nv 0 3 0\nv 4 3 0\nv 4 3 4\nv 0 3 4\n"
                    "f 1 4 3 2\nf 5 6 7 8\nf 1 5 8 4\nf 2 3 7 6\nf 1 2 6 5\n"
                    /* the wall z = 4 around a window x in [1.5, 2.5], y in [1, 2] */
                    "v 1.5 0 4\nv 1.5 3 4\nv 2.5 0 4\nv 2.5 3 4\nv 1.5 1 4\nv 2.5 1 4\nv 1.5 2 4\nv 2.5 2 4\n"
                    "f 4 8 10 9\nf 11 12 7 3\nf 9 13 14 11\nf 15 10 12 16\n"
                    "usemtl sky\n"
                    /* outside, facing the room (−z) */
                    "v -20 -20 5\nv -20 24 5\nv 24 24 5\nv 24 -20 5\nf 17 18 19 20\n");
    snprintf(path, sizeof path, "%s/window.json", dir);
    test_write_file(path,
                    "{\n  \"camera\": {\"eye\": [3.6, 2.6, 0.3], \"target\": [1.8, 0.6, 3.2], \"up\": [0, 1, 0],\n"
                    "             \"fov_y\": 70, \"width\": 64, \"height\": 48},\n"
                    "  \"meshes\": [{\"path\": \"window.obj\"}]\n}\n");
}

/* Loads the scene file at path into *out (NULL on failure, err set) at width × height pixels (0: the file's),
 * with the view file view (NULL: none), reading files outside its folder when allow_outside_paths is 1. */
static inline ic_result test_load_scene(const char *path, const char *view, int width, int height,
                                        int allow_outside_paths, ic_scene **out, ic_error *err)
{
    ic_scene_load_options lo = {0};
    lo.view = view;
    lo.width = width;
    lo.height = height;
    lo.allow_outside_paths = allow_outside_paths;
    *out = NULL;
    return ic_scene_load(path, &lo, out, err);
}

/* Writes IC_TEST_TMP/NAME.rad holding rad and, unless view is NULL, NAME.vf holding view, and loads the first
 * from the second at size × size pixels (test_load_scene); NULL (err set) on failure. */
static inline ic_scene *test_load_rad_text(const char *name, const char *rad, const char *view, int size,
                                           int allow_outside_paths, ic_error *err)
{
    char path[512], vpath[512];
    snprintf(path, sizeof path, IC_TEST_TMP "/%s.rad", name);
    snprintf(vpath, sizeof vpath, IC_TEST_TMP "/%s.vf", name);
    test_write_file(path, rad);
    if (view)
        test_write_file(vpath, view);
    ic_scene *s;
    test_load_scene(path, view ? vpath : NULL, size, size, allow_outside_paths, &s, err);
    return s;
}

/* Checks that a load failed (s is NULL; freed all the same) with a one-line message holding every string of
 * want (NULL-terminated); name labels the checks. */
static inline void test_check_refused(const char *name, ic_scene *s, const ic_error *err, const char *const *want)
{
    CHECK(s == NULL, "%s is refused", name);
    ic_scene_free(s);
    int ok = !strchr(err->message, '\n');
    for (int i = 0; want[i]; ++i)
        ok &= strstr(err->message, want[i]) != NULL;
    CHECK(ok, "%s: one line naming what is wrong and where: %s", name, err->message);
}

/* Render options of spp samples a pixel on threads threads, seeded with seed; the rest defaults. */
static inline ic_render_options test_seeded_options(int spp, int threads, uint64_t seed)
{
    ic_render_options opt = {0};
    opt.spp = spp;
    opt.threads = threads;
    opt.seed = seed;
    opt.has_seed = 1;
    return opt;
}

/* Loads scene_path (with an optional resolution override) and renders it with opt into img.
 * Returns 1 on success; on failure prints the error and returns 0. */
static inline int test_render(const char *scene_path, int width, int height, const ic_render_options *opt,
                              ic_image *img, ic_render_stats *stats)
{
    ic_error err = {0};
    ic_scene *scene = NULL;
    ic_scene_load_options lo = {0};
    lo.width = width;
    lo.height = height;
    if (ic_scene_load(scene_path, &lo, &scene, &err) != IC_OK) {
        fprintf(stderr, "load %s: %s\n", scene_path, err.message);
        return 0;
    }
    ic_render_stats local;
    ic_result r = ic_render(scene, opt, img, stats ? stats : &local, &err);
    if (r != IC_OK)
        fprintf(stderr, "render %s: %s\n", scene_path, err.message);
    ic_scene_free(scene);
    return r == IC_OK;
}

/* Renders a loaded scene with opt into img; 0 (the error printed) on failure. */
static inline int test_render_loaded(const ic_scene *scene, const ic_render_options *opt, ic_image *img)
{
    ic_render_stats st;
    ic_error err = {0};
    if (ic_render(scene, opt, img, &st, &err) == IC_OK)
        return 1;
    fprintf(stderr, "render: %s\n", err.message);
    return 0;
}

/* Renders scene with opt and returns the mean of channel over the size × size pixels from (x0, y0); -1 if
 * the render fails (the error is printed). The scene is freed. */
static inline double test_scene_box_mean(ic_scene *scene, const ic_render_options *opt, int x0, int y0, int size,
                                         int channel)
{
    ic_image img = {0};
    double mean = -1.0;
    if (test_render_loaded(scene, opt, &img)) {
        mean = 0.0;
        for (int y = y0; y < y0 + size; ++y)
            for (int x = x0; x < x0 + size; ++x)
                mean += img.rgb[3 * ((size_t)y * img.width + x) + channel] / ((double)size * size);
    }
    ic_image_free(&img);
    ic_scene_free(scene);
    return mean;
}

/* Mean of all channels; *finite is 0 if any value is NaN or infinite. */
static inline double test_image_mean(const ic_image *img, int *finite)
{
    double s = 0.0;
    *finite = 1;
    size_t n = (size_t)img->width * img->height * 3;
    for (size_t i = 0; i < n; ++i) {
        if (!isfinite(img->rgb[i]))
            *finite = 0;
        s += img->rgb[i];
    }
    return s / (double)n;
}

/* Renders scene (a light near the radiance limit, IC_SCENE_MAX_RADIANCE) with the path tracer and with the
 * cache, one sample a pixel: every pixel finite and some lit (a sample that overflowed was dropped, and read
 * 0), and, when want_max > 0, the brightest pixel want_max within 0.1 % (a light seen directly, or a surface
 * lit evenly: an analytic value). name labels the checks; the scene is freed. */
static inline void test_check_renders_finite(const char *name, ic_scene *scene, double want_max)
{
    CHECK(scene != NULL, "%s loads", name);
    for (int k = 0; scene && k < 2; ++k) {
        ic_render_options opt = test_seeded_options(1, 2, 5);
        opt.integrator = k ? IC_INTEGRATOR_IC : IC_INTEGRATOR_PT;
        ic_image img = {0};
        int finite = 0;
        const int ok = test_render_loaded(scene, &opt, &img);
        const double mean = ok ? test_image_mean(&img, &finite) : 0.0;
        double most = 0.0;
        for (size_t i = 0; ok && i < (size_t)img.width * img.height * 3; ++i)
            most = fmax(most, img.rgb[i]);
        CHECK(ok && finite && mean > 0.0, "%s (%s): renders finite and lit (mean %g)", name, k ? "ic" : "pt", mean);
        if (want_max > 0.0)
            CHECK(fabs(most - want_max) <= 1e-3 * want_max, "%s (%s): brightest pixel %g, expected %g", name,
                  k ? "ic" : "pt", most, want_max);
        ic_image_free(&img);
    }
    ic_scene_free(scene);
}

/* A sphere of radius r about the origin as an OBJ with its faces turned inwards (nu × nv quads, split
 * into triangles at the poles), using material `usemtl` of `mtllib`: a closed furnace room. */
static inline void test_write_inward_sphere(const char *path, const char *mtllib, const char *usemtl, float r, int nu,
                                            int nv)
{
    FILE *f = fopen(path, "w");
    if (!f)
        exit(1);
    fprintf(f, "mtllib %s\nusemtl %s\n", mtllib, usemtl);
    const double pi = 3.14159265358979323846;
    for (int j = 0; j <= nv; ++j) {
        double th = pi * j / nv;
        for (int i = 0; i < nu; ++i) {
            double ph = 2.0 * pi * i / nu;
            fprintf(f, "v %.7f %.7f %.7f\n", r * sin(th) * cos(ph), r * cos(th), r * sin(th) * sin(ph));
        }
    }
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            int a = j * nu + i + 1, b = j * nu + (i + 1) % nu + 1, c = (j + 1) * nu + i + 1,
                d = (j + 1) * nu + (i + 1) % nu + 1;
            if (j > 0)
                fprintf(f, "f %d %d %d\n", a, c, b);
            if (j < nv - 1)
                fprintf(f, "f %d %d %d\n", b, c, d);
        }
    fclose(f);
}

/* The irradiance (green) and its σ at one sensor (position p, normal n) by the integrator, with `samples`
 * path-traced samples (pt) and two threads; 0 (a failed check) when computing fails. */
static inline int test_sensor_irradiance(const ic_scene *s, ic_vec3 p, ic_vec3 n, ic_integrator integrator,
                                         uint32_t samples, double *E, double *sigma)
{
    ic_sensor_point pt = {p, n};
    ic_points_options opt = {0};
    opt.integrator = integrator;
    opt.samples = samples;
    opt.threads = 2;
    ic_point_result r;
    ic_error err = {0};
    if (ic_points_compute(s, &pt, 1, &opt, &r, NULL, &err) != IC_OK) {
        CHECK(0, "sensor: %s", err.message);
        return 0;
    }
    *E = r.irradiance.y;
    *sigma = r.irradiance_sigma.y;
    return 1;
}

#endif
