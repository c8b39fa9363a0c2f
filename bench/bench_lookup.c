/*
 * bench_lookup.c — look-ups per second on a real cache: the records the batch strategy builds for a
 * scene, queried at the scene's own shading points (one per pixel centre, raster order, as the final
 * render queries them), with and without validity-radius clamping (Frolov et al. 2012 §4.2,
 * Table 1).
 *
 * usage: bench_lookup [--save DIR] SCENE [width height] — prints one row per setting and look-up path
 * (the octree with the cache thawed, the frozen layout, the frozen layout with a caller hint, the same
 * in batches of 256 look-ups per call; cache.h: FROZEN LOOK-UPS) with a digest of the answers; asserts
 * nothing. Single thread (= per core), median and best of 5 passes over all shading points.
 * --save DIR also writes both caches and their shading points to DIR; bench_lookup --load DIR times those again without building the caches (the same build's files: to
 * compare code changes on the same look-ups).
 */
#include "cache/cache_store.h" /* ic_cache_set_lookup_path */
#include "core/atomic_file.h"
#include "film/film.h"
#include "geom/accel.h"
#include "integrators/ic_internal.h"
#include "scene/scene.h"

#include <errno.h>
#include "bench_index.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Look-up paths compared on one cache: the octree (thawed), the frozen layout, frozen with a hint,
 * frozen in batches of BATCH look-ups with a hint (ic_cache_query_batch) — these three with the best
 * code this CPU runs: AVX2 or SSE2 —, and frozen with a hint forced onto the SSE2 and the portable code
 * (cache_store.h: ic_cache_set_lookup_path). */
enum { PATH_OCTREE, PATH_FROZEN, PATH_HINTED, PATH_BATCH, PATH_HINTED_SSE2, PATH_HINTED_PORTABLE, PATHS };
enum { BATCH = 256 };

/* The shading points of a view: position and normal, raster order, pixels without a hit left out. */
typedef struct points {
    ic_vec3 *p, *n;
    size_t count;
} points;

/* The estimates' counts into *refs and *contrib and (with digest) their bits into *digest. */
static void tally(const ic_cache_estimate *e, double *refs, double *contrib, uint64_t *digest)
{
    *refs += e->records_tested;
    *contrib += e->contributor_count;
    if (digest)
        *digest = ic_fnv1a64(*digest, &e->irradiance, sizeof e->irradiance);
}

/* One pass over all shading points, BATCH at a time: a chunk's look-ups are prepared, timed, then
 * tallied. Only the look-up calls are timed (two clock reads per BATCH look-ups, well under 1 %):
 * building the queries and summing the answers is the benchmark's work. Returns those seconds, and
 * counts into *refs and *contrib. With digest (an untimed pass), folds the estimates' bits into
 * *digest: equal digests, equal answers. */
static double pass(const ic_cache *cache, const points *pts, int path, double *refs, double *contrib,
                   uint64_t *digest)
{
    ic_cache_hint hint = {0}, *h = path >= PATH_HINTED ? &hint : NULL;
    ic_cache_lookup q[BATCH];
    ic_cache_estimate e[BATCH];
    double seconds = 0.0;
    *refs = *contrib = 0.0;
    for (size_t first = 0; first < pts->count; first += BATCH) {
        size_t m = pts->count - first < BATCH ? pts->count - first : BATCH;
        for (size_t k = 0; k < m; ++k)
            q[k] = ic_cache_lookup_at(pts->p[first + k], pts->n[first + k], IC_ACCEPT_FINAL);
        double t0 = ic_seconds();
        if (path == PATH_BATCH)
            ic_cache_query_batch(cache, q, m, &hint, e);
        else
            for (size_t k = 0; k < m; ++k)
                ic_cache_query_hinted(cache, &q[k], h, &e[k]);
        seconds += ic_seconds() - t0;
        for (size_t k = 0; k < m; ++k)
            tally(&e[k], refs, contrib, digest);
    }
    return seconds;
}

/* Median (and best) of 5 passes per path; the paths alternate within each repetition so that load on a shared
 * machine hits them alike. */
static void measure(const char *label, ic_cache *cache, const points *pts, double build_seconds)
{
    static const char *name[PATHS] = {"octree",           "frozen",       "frozen+hint", "frozen batch",
                                      "frozen+hint SSE2", "frozen+hint C"};
    static const ic_lookup_path code[PATHS] = {IC_LOOKUP_BEST, IC_LOOKUP_BEST, IC_LOOKUP_BEST,
                                               IC_LOOKUP_BEST, IC_LOOKUP_SSE2, IC_LOOKUP_PORTABLE};
    double runs[PATHS][5], refs[PATHS] = {0}, contrib = 0.0;
    uint64_t digest[PATHS];
    for (int k = 0; k < PATHS; ++k)
        digest[k] = IC_FNV64_OFFSET;
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
            runs[k][r] = pass(cache, pts, k, &refs[k], &contrib, NULL);
            if (r == 0)
                pass(cache, pts, k, &refs[k], &contrib, &digest[k]);
            ic_cache_set_lookup_path(cache, IC_LOOKUP_BEST);
        }
    for (int k = 0; k < PATHS; ++k)
        qsort(runs[k], 5, sizeof runs[k][0], cmp_double);
    double n = (double)pts->count;
    for (int k = 0; k < PATHS; ++k)
        if (runs[k][2] > 0.0)
            printf("%-19s %-17s %6u records  build %6.2f s  %6.2f M look-ups/s/core (best %6.2f)  x%.2f  "
                   "%5.1f refs/look-up  %4.2f contributors  digest %016llx\n",
                   label, name[k], ic_cache_count(cache), build_seconds, n / runs[k][2] * 1e-6,
                   n / runs[k][0] * 1e-6, runs[PATH_OCTREE][2] / runs[k][2], refs[k] / n, contrib / n,
                   (unsigned long long)digest[k]);
    printf("%-19s", label);
    print_index_stats("", "", cache);
    size_t frozen = ic_cache_memory_bytes(cache);
    ic_cache_thaw(cache);
    size_t thawed = ic_cache_memory_bytes(cache);
    printf("%-19s memory: cache %.0f bytes/record, frozen layout %.0f more\n", label,
           (double)thawed / ic_cache_count(cache), (double)(frozen - thawed) / ic_cache_count(cache));
}

static const char *const setting_label[2] = {"validity clamp off", "validity clamp on"};
static const char *const setting_file[2] = {"validity-off", "validity-on"};

static void fail(const char *what)
{
    fprintf(stderr, "bench_lookup: %s\n", what);
    exit(1);
}

/* DIR/<setting>.points: the cache's parameters (the load must name them), then the points. Raw
 * structs: read back by the same build only. Written under a temporary name and renamed. */
static void save_points(const char *dir, int validity, const ic_cache_params *params, const points *pts)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s.points", dir, setting_file[validity]);
    ic_atomic_file f;
    ic_error err;
    uint64_t count = pts->count;
    if (ic_atomic_file_open(&f, path, &err) != IC_OK)
        fail(err.message);
    if (fwrite(params, sizeof *params, 1, f.fp) != 1 || fwrite(&count, sizeof count, 1, f.fp) != 1 ||
        fwrite(pts->p, sizeof *pts->p, pts->count, f.fp) != pts->count ||
        fwrite(pts->n, sizeof *pts->n, pts->count, f.fp) != pts->count) {
        ic_atomic_file_abort(&f);
        fprintf(stderr, "bench_lookup: %s: cannot write (%s); check the free space\n", path, strerror(errno));
        exit(1);
    }
    if (ic_atomic_file_commit(&f, &err) != IC_OK)
        fail(err.message);
}

static void load_points(const char *dir, int validity, ic_cache_params *params, points *pts)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s.points", dir, setting_file[validity]);
    FILE *f = fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "bench_lookup: %s: cannot read (%s); write it with bench_lookup --save %s SCENE\n", path,
                strerror(errno), dir);
        exit(1);
    }
    uint64_t count = 0;
    int ok = fread(params, sizeof *params, 1, f) == 1 && fread(&count, sizeof count, 1, f) == 1 &&
             count <= ((uint64_t)1 << 32);
    pts->count = ok ? (size_t)count : 0;
    pts->p = malloc((pts->count ? pts->count : 1) * sizeof *pts->p);
    pts->n = malloc((pts->count ? pts->count : 1) * sizeof *pts->n);
    ok = ok && pts->p && pts->n && fread(pts->p, sizeof *pts->p, pts->count, f) == pts->count &&
         fread(pts->n, sizeof *pts->n, pts->count, f) == pts->count;
    fclose(f);
    if (!ok) {
        fprintf(stderr, "bench_lookup: %s: truncated or not a points file; write it again with bench_lookup --save %s "
                        "SCENE, with this build\n", path, dir);
        exit(1);
    }
}

/* Builds the batch strategy's cache for the scene at width × height and times it; with save_dir,
 * also writes the cache and the points there for --load. */
static int from_scene(const char *scene_path, int width, int height, const char *save_dir)
{
    ic_scene_load_options lo = {0};
    lo.width = width;
    lo.height = height;
    ic_error err;
    ic_scene *scene = NULL;
    ic_accel *accel = NULL;
    if (ic_scene_load(scene_path, &lo, &scene, &err) != IC_OK || ic_accel_create(scene, &accel, &err) != IC_OK)
        fail(err.message);
    ic_tracer tr;
    tr.scene = scene;
    tr.accel = accel;
    tr.pt.max_depth = 8;
    tr.pt.rr_depth = 0;
    tr.pt = ic_pt_params_resolve(tr.pt);
    printf("scene %s, %dx%d, batch strategy, default settings, final acceptance\n", scene_path, width, height);
    for (int validity = 1; validity >= 0; --validity) {
        ic_render_options opt = {0};
        opt.integrator = IC_INTEGRATOR_IC;
        opt.seed = 1;
        opt.ic.cache.validity_clamp = validity ? IC_CACHE_ON : IC_CACHE_OFF;
        ic_ctx *c;
        ic_render_stats st;
        memset(&st, 0, sizeof st);
        phase_times pt = {0};
        double t0 = ic_seconds();
        if (ic_ic_ctx_create(&tr, &opt, &c, NULL, &err) != IC_OK || ic_ic_build(c, &opt, &st, &pt, &err) != IC_OK ||
            ic_cache_rebuild_index(c->cache, &err) != IC_OK)
            fail(err.message);
        double build = ic_seconds() - t0;
        size_t npix = (size_t)c->g.width * c->g.height;
        points pts = {malloc(npix * sizeof(ic_vec3)), malloc(npix * sizeof(ic_vec3)), 0};
        if (!pts.p || !pts.n)
            fail("out of memory");
        for (size_t i = 0; i < npix; ++i)
            if (c->g.valid[i]) {
                pts.p[pts.count] = c->g.p[i];
                pts.n[pts.count++] = c->g.n[i];
            }
        if (save_dir) {
            char path[4096];
            snprintf(path, sizeof path, "%s/%s.cache", save_dir, setting_file[validity]);
            if (ic_cache_save(c->cache, path, 0, &err) != IC_OK)
                fail(err.message);
            save_points(save_dir, validity, ic_cache_get_params(c->cache), &pts);
        }
        measure(setting_label[validity], c->cache, &pts, build);
        free(pts.p);
        free(pts.n);
        ic_ic_ctx_destroy(c);
    }
    ic_accel_destroy(accel);
    ic_scene_free(scene);
    return 0;
}

/* Times the caches and points a --save run wrote (the same look-ups, without building the cache). */
static int from_saved(const char *dir)
{
    printf("caches and points from %s, final acceptance\n", dir);
    for (int validity = 1; validity >= 0; --validity) {
        ic_cache_params params;
        points pts;
        load_points(dir, validity, &params, &pts);
        char path[4096];
        snprintf(path, sizeof path, "%s/%s.cache", dir, setting_file[validity]);
        ic_cache *cache;
        ic_error err;
        if (ic_cache_load(path, &params, 0, &cache, &err) != IC_OK)
            fail(err.message);
        measure(setting_label[validity], cache, &pts, 0.0);
        ic_cache_destroy(cache);
        free(pts.p);
        free(pts.n);
    }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc == 3 && !strcmp(argv[1], "--load"))
        return from_saved(argv[2]);
    const char *save_dir = NULL;
    if (argc >= 3 && !strcmp(argv[1], "--save")) {
        save_dir = argv[2];
        argc -= 2;
        argv += 2;
    }
    if (argc < 2) {
        fprintf(stderr, "usage: bench_lookup [--save DIR] SCENE [width height] | bench_lookup --load DIR\n");
        return 2;
    }
    return from_scene(argv[1], argc > 3 ? atoi(argv[2]) : 320, argc > 3 ? atoi(argv[3]) : 180, save_dir);
}
