/*
 * bench_lookup.c — look-ups per second on a real cache: the records the batch strategy builds for a
 * scene, queried at the scene's own shading points (one per pixel centre, raster order, as the final
 * render queries them), with and without validity-radius clamping (seed 004 §4.2, Table 1).
 *
 * usage: bench_lookup SCENE [width height] — prints one row per setting; asserts nothing.
 * Single thread (= per core), median of 5 passes over all shading points.
 */
#include "geom/accel.h"
#include "integrators/ic_internal.h"
#include "render/render.h"
#include "scene/scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void measure(const char *label, const ic_ctx *c, double build_seconds)
{
    size_t npix = (size_t)c->g.width * c->g.height, points = 0;
    double runs[5], refs = 0.0, contrib = 0.0;
    for (int r = 0; r < 5; ++r) {
        double t0 = ic_seconds();
        for (size_t i = 0; i < npix; ++i) {
            if (!c->g.valid[i])
                continue;
            ic_cache_lookup q;
            memset(&q, 0, sizeof q);
            q.position = c->g.p[i];
            q.normal = c->g.n[i];
            q.acceptance = IC_ACCEPT_FINAL;
            ic_cache_estimate e;
            ic_cache_query(c->cache, &q, &e);
            if (r == 0) {
                ++points;
                refs += e.records_tested;
                contrib += e.contributor_count;
            }
        }
        runs[r] = ic_seconds() - t0;
    }
    qsort(runs, 5, sizeof runs[0], cmp_double);
    printf("%-22s %8u records  build %7.2f s  %7.2f M look-ups/s/core  %6.1f refs/look-up  %5.2f contributors\n",
           label, ic_cache_count(c->cache), build_seconds, (double)points / runs[2] * 1e-6, refs / (double)points,
           contrib / (double)points);
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: bench_lookup SCENE [width height]\n");
        return 2;
    }
    ic_scene_load_options lo = {0};
    lo.width = argc > 3 ? atoi(argv[2]) : 320;
    lo.height = argc > 3 ? atoi(argv[3]) : 180;
    ic_error err;
    ic_scene *scene;
    ic_accel *accel;
    if (ic_scene_load(argv[1], &lo, &scene, &err) != IC_OK || ic_accel_create(scene, &accel, &err) != IC_OK) {
        fprintf(stderr, "bench_lookup: %s\n", err.message);
        return 1;
    }
    ic_tracer tr;
    tr.scene = scene;
    tr.accel = accel;
    tr.pt.max_depth = 8;
    tr.pt.rr_depth = 0;
    tr.pt = ic_pt_params_resolve(tr.pt);
    printf("scene %s, %dx%d, batch strategy, default settings, final acceptance\n", argv[1], lo.width, lo.height);
    for (int validity = 1; validity >= 0; --validity) {
        ic_render_options opt = {0};
        opt.integrator = IC_INTEGRATOR_IC;
        opt.seed = 1;
        opt.ic.cache.validity_clamp = validity ? IC_CACHE_ON : IC_CACHE_OFF;
        ic_ctx *c;
        ic_render_stats st;
        memset(&st, 0, sizeof st);
        phase_times pt = {0, 0};
        double t0 = ic_seconds();
        if (ic_ic_ctx_create(&tr, &opt, &c, NULL, &err) != IC_OK || ic_ic_build(c, &opt, &st, &pt, &err) != IC_OK ||
            ic_cache_rebuild_index(c->cache, &err) != IC_OK) {
            fprintf(stderr, "bench_lookup: %s\n", err.message);
            return 1;
        }
        measure(validity ? "validity clamp on" : "validity clamp off", c, ic_seconds() - t0);
        ic_ic_ctx_destroy(c);
    }
    ic_accel_destroy(accel);
    ic_scene_free(scene);
    return 0;
}
