/*
 * bench_lookup.c — look-ups per second on a real cache: the records the batch strategy builds for a
 * scene, queried at the scene's own shading points (one per pixel centre, raster order, as the final
 * render queries them), with and without validity-radius clamping (seed 004 §4.2, Table 1).
 *
 * usage: bench_lookup SCENE [width height] — prints one row per setting and look-up path (the octree
 * with the cache thawed, the frozen layout, the frozen layout with a caller hint; cache.h: FROZEN
 * LOOK-UPS); asserts nothing. Single thread (= per core), median of 5 passes over all shading points.
 */
#include "cache/cache_internal.h" /* ic_cache_set_lookup_path */
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

/* Look-up paths compared on one cache: the octree (thawed), the frozen layout, frozen with a hint
 * (these two with the best code this CPU runs: AVX2 or SSE2), and frozen with a hint forced onto the
 * SSE2 and the portable code (cache_internal.h: ic_cache_set_lookup_path). */
enum { PATH_OCTREE, PATH_FROZEN, PATH_HINTED, PATH_HINTED_SSE2, PATH_HINTED_PORTABLE, PATHS };

/* One pass over all shading points in raster order; returns seconds, counts into *refs and *contrib. */
static double pass(const ic_ctx *c, int hinted, double *refs, double *contrib, size_t *points)
{
    size_t npix = (size_t)c->g.width * c->g.height;
    ic_cache_hint hint = {0};
    *refs = *contrib = 0.0;
    *points = 0;
    double t0 = ic_seconds();
    for (size_t i = 0; i < npix; ++i) {
        if (!c->g.valid[i])
            continue;
        ic_cache_lookup q = ic_cache_lookup_at(c->g.p[i], c->g.n[i], IC_ACCEPT_FINAL);
        ic_cache_estimate e;
        ic_cache_query_hinted(c->cache, &q, hinted ? &hint : NULL, &e);
        ++*points;
        *refs += e.records_tested;
        *contrib += e.contributor_count;
    }
    return ic_seconds() - t0;
}

/* Median of 5 passes per path; the paths alternate within each repetition so that load on a shared
 * machine hits them alike. */
static void measure(const char *label, const ic_ctx *c, double build_seconds)
{
    static const char *name[PATHS] = {"octree", "frozen", "frozen+hint", "frozen+hint SSE2", "frozen+hint C"};
    static const ic_lookup_path code[PATHS] = {IC_LOOKUP_BEST, IC_LOOKUP_BEST, IC_LOOKUP_BEST, IC_LOOKUP_SSE2,
                                               IC_LOOKUP_PORTABLE};
    double runs[PATHS][5], refs[PATHS] = {0}, contrib = 0.0;
    size_t points = 0;
    ic_cache *cache = c->cache;
    for (int r = 0; r < 5; ++r)
        for (int k = 0; k < PATHS; ++k) {
            ic_error err;
            if (k == PATH_OCTREE)
                ic_cache_thaw(cache);
            else if (!ic_cache_is_frozen(cache) && ic_cache_freeze(cache, &err) != IC_OK) {
                fprintf(stderr, "bench_lookup: %s\n", err.message);
                exit(1);
            }
            if (!ic_cache_set_lookup_path(cache, code[k])) {
                runs[k][r] = 0.0;
                continue;
            }
            runs[k][r] = pass(c, k >= PATH_HINTED, &refs[k], &contrib, &points);
            ic_cache_set_lookup_path(cache, IC_LOOKUP_BEST);
        }
    for (int k = 0; k < PATHS; ++k)
        qsort(runs[k], 5, sizeof runs[k][0], cmp_double);
    for (int k = 0; k < PATHS; ++k)
        if (runs[k][2] > 0.0)
            printf("%-19s %-17s %6u records  build %6.2f s  %6.2f M look-ups/s/core  x%.2f  %5.1f refs/look-up  "
               "%4.2f contributors\n",
               label, name[k], ic_cache_count(cache), build_seconds, (double)points / runs[k][2] * 1e-6,
               runs[PATH_OCTREE][2] / runs[k][2], refs[k] / (double)points, contrib / (double)points);
    size_t frozen = ic_cache_memory_bytes(cache);
    ic_cache_thaw(cache);
    size_t thawed = ic_cache_memory_bytes(cache);
    printf("%-19s memory: cache %.0f bytes/record, frozen layout %.0f more\n", label,
           (double)thawed / ic_cache_count(cache), (double)(frozen - thawed) / ic_cache_count(cache));
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
