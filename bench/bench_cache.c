/*
 * bench_cache.c — speed of the irradiance cache library (include/irrcache/cache.h).
 *
 * Scene: 400 random axis-aligned boxes in a 60³ world; records live on their faces. A lazy
 * construction (Ward 1988: look up at a random surface point, insert a record where no record
 * contributes) places ~300k records the way a renderer would, timing incremental insertion. The
 * same input records are then inserted again as one batch with and without validity-radius
 * clamping (Frolov et al. 2012 §4.2), and in batches of 10k (a batch-strategy pass), timing batch insertion.
 * Look-ups at 1M random surface points run on one thread (per-core rate; median of 5 runs) with the
 * construction and the final acceptance, and on all threads; after ic_cache_rebuild_index each cache
 * is timed through its octree (thawed), its frozen layout, the frozen layout with a hint, and in
 * batches (ic_cache_query_batch; cache.h: FROZEN LOOK-UPS), back to back in one run. Only the
 * look-up calls are timed.
 *
 * Usage: bench_cache [records] (default 300000). Prints a table; asserts nothing.
 */
#include "irrcache/cache.h"

#include "core/morton.h"
#include "core/rng.h"
#include "core/threads.h"
#include "core/vecmath.h"

#include "bench_index.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define BOXES 400
#define QUERIES 1000000
#define REPS 5

typedef struct box {
    ic_vec3 lo, hi;
} box;

typedef struct surface_point {
    ic_vec3 p, n;
} surface_point;

/* 30-bit Morton code of a point in the 64³ world: sorting look-ups by it mimics the coherence of
 * a renderer's pixel order (neighbouring pixels hit neighbouring surface points). */
static uint32_t morton(ic_vec3 p)
{
    uint32_t x = (uint32_t)ic_clampf(p.x * 16.0f, 0.0f, 1023.0f), y = (uint32_t)ic_clampf(p.y * 16.0f, 0.0f, 1023.0f),
             z = (uint32_t)ic_clampf(p.z * 16.0f, 0.0f, 1023.0f);
    return ic_morton3_cells(x, y, z);
}

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void make_boxes(box *b)
{
    ic_rng r = ic_rng_make(2026, 11, 22, 0);
    for (int k = 0; k < BOXES; ++k) {
        ic_vec3 c = v3(60.0f * ic_rng_float(&r), 60.0f * ic_rng_float(&r), 60.0f * ic_rng_float(&r));
        ic_vec3 h = v3(0.5f + 3.5f * ic_rng_float(&r), 0.5f + 3.5f * ic_rng_float(&r), 0.5f + 3.5f * ic_rng_float(&r));
        b[k].lo = v3_sub(c, h);
        b[k].hi = v3_add(c, h);
    }
}

/* A uniformly random point on a random face of a random box (faces chosen by area). */
static surface_point sample_surface(const box *boxes, ic_rng *r)
{
    const box *b = &boxes[ic_rng_below(r, BOXES)];
    ic_vec3 e = v3_sub(b->hi, b->lo);
    float area[3] = {e.y * e.z, e.x * e.z, e.x * e.y}, total = area[0] + area[1] + area[2];
    float u = ic_rng_float(r) * total;
    int axis = u < area[0] ? 0 : (u < area[0] + area[1] ? 1 : 2);
    int side = ic_rng_float(r) < 0.5f;
    float t[3] = {ic_rng_float(r), ic_rng_float(r), ic_rng_float(r)};
    float lo[3] = {b->lo.x, b->lo.y, b->lo.z}, ext[3] = {e.x, e.y, e.z}, p[3], n[3] = {0, 0, 0};
    for (int a = 0; a < 3; ++a)
        p[a] = lo[a] + t[a] * ext[a];
    p[axis] = side ? lo[axis] + ext[axis] : lo[axis];
    n[axis] = side ? 1.0f : -1.0f;
    surface_point s = {v3(p[0], p[1], p[2]), v3(n[0], n[1], n[2])};
    return s;
}

static ic_record make_record(surface_point s, ic_rng *r)
{
    ic_record rec;
    memset(&rec, 0, sizeof rec);
    rec.position = s.p;
    rec.normal = s.n;
    ic_frame f = ic_frame_from_normal(s.n);
    rec.tangent = f.t;
    rec.irradiance = v3(0.5f + ic_rng_float(r), 0.5f + ic_rng_float(r), 0.5f + ic_rng_float(r));
    /* Harmonic-mean distances log-uniform in [0.3, 3]: a few box sizes. */
    rec.harmonic_mean_dist = 0.3f * expf(ic_rng_float(r) * logf(10.0f));
    for (int ch = 0; ch < 3; ++ch) {
        float g = 0.3f * v3_get(rec.irradiance, ch) / rec.harmonic_mean_dist;
        rec.grad_trans[ch] = v3_add(v3_scale(f.t, g * (ic_rng_float(r) - 0.5f)), v3_scale(f.b, g * (ic_rng_float(r) - 0.5f)));
        rec.grad_rot[ch] = v3_scale(f.b, 0.2f * (ic_rng_float(r) - 0.5f));
    }
    return rec;
}

typedef struct lookup_stats {
    double per_second;       /* median over REPS */
    double tested;           /* references examined per look-up */
    double contributors;     /* contributors per look-up */
    double hit;              /* fraction with at least one contributor */
} lookup_stats;

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Look-up paths compared on one cache: the octree (thawed), the frozen layout, frozen with a hint, and
 * frozen in batches of CHUNK look-ups with a hint (ic_cache_query_batch). */
typedef enum path_kind { PATH_OCTREE, PATH_FROZEN, PATH_HINTED, PATH_BATCH, PATH_KINDS } path_kind;
enum { CHUNK = 256 };

/* Look-ups of q on one thread, CHUNK at a time: a chunk's requests are built, its calls timed, its
 * answers counted. Only the calls are timed (two clock reads per CHUNK look-ups), so every path is
 * measured alike. */
static lookup_stats time_lookups(const ic_cache *c, const surface_point *q, ic_cache_acceptance acc, path_kind path)
{
    lookup_stats st = {0, 0, 0, 0};
    double rates[REPS];
    uint64_t tested = 0, contributors = 0, hits = 0;
    float sink = 0.0f;
    ic_cache_lookup l[CHUNK];
    ic_cache_estimate e[CHUNK];
    for (int rep = 0; rep < REPS; ++rep) {
        tested = contributors = hits = 0;
        ic_cache_hint hint = {0}, *h = path >= PATH_HINTED ? &hint : NULL;
        double seconds = 0.0;
        for (int first = 0; first < QUERIES; first += CHUNK) {
            int m = QUERIES - first < CHUNK ? QUERIES - first : CHUNK;
            for (int k = 0; k < m; ++k)
                l[k] = ic_cache_lookup_at(q[first + k].p, q[first + k].n, acc);
            double t0 = now();
            if (path == PATH_BATCH)
                ic_cache_query_batch(c, l, (size_t)m, h, e);
            else
                for (int k = 0; k < m; ++k)
                    ic_cache_query_hinted(c, &l[k], h, &e[k]);
            seconds += now() - t0;
            for (int k = 0; k < m; ++k) {
                hits += e[k].contributor_count > 0;
                tested += e[k].records_tested;
                contributors += e[k].contributor_count;
                sink += e[k].irradiance.x;
            }
        }
        rates[rep] = QUERIES / seconds;
    }
    qsort(rates, REPS, sizeof rates[0], cmp_double);
    st.per_second = rates[REPS / 2];
    st.tested = (double)tested / QUERIES;
    st.contributors = (double)contributors / QUERIES;
    st.hit = (double)hits / QUERIES;
    if (sink < 0.0f)
        printf("impossible\n");
    return st;
}

typedef struct mt_job {
    const ic_cache *c;
    const surface_point *q;
    double *sink;
} mt_job;

static void mt_chunk(void *ctx, int64_t item, int thread)
{
    mt_job *job = ctx;
    float s = 0.0f;
    ic_cache_hint hint = {0}; /* per chunk: the result never depends on how chunks meet threads */
    for (int64_t k = item * 10000; k < (item + 1) * 10000; ++k) {
        ic_cache_lookup l = ic_cache_lookup_at(job->q[k].p, job->q[k].n, IC_ACCEPT_FINAL);
        ic_cache_estimate e;
        ic_cache_query_hinted(job->c, &l, &hint, &e);
        s += e.irradiance.x;
    }
    job->sink[thread] += s;
}

static double time_lookups_mt(const ic_cache *c, const surface_point *q)
{
    double sink[64] = {0}, rates[REPS];
    mt_job job = {c, q, sink};
    for (int rep = 0; rep < REPS; ++rep) {
        double t0 = now();
        ic_parallel_for(0, QUERIES / 10000, mt_chunk, &job);
        rates[rep] = QUERIES / (now() - t0);
    }
    qsort(rates, REPS, sizeof rates[0], cmp_double);
    return rates[REPS / 2];
}

static ic_cache *batch_build(const ic_record *recs, uint32_t n, uint32_t batch, int validity, double *seconds)
{
    ic_cache_params p = {0};
    p.validity_clamp = validity ? IC_CACHE_ON : IC_CACHE_OFF;
    p.final_accuracy_scale = 1.5f;
    ic_cache *c = NULL;
    ic_error err;
    if (ic_cache_create(&p, &c, &err) != IC_OK) {
        fprintf(stderr, "bench_cache: %s\n", err.message);
        exit(1);
    }
    double t0 = now();
    for (uint32_t i = 0; i < n; i += batch) {
        uint32_t m = n - i < batch ? n - i : batch;
        if (ic_cache_insert_batch(c, recs + i, m, NULL, &err) != IC_OK) {
            fprintf(stderr, "bench_cache: %s\n", err.message);
            exit(1);
        }
    }
    *seconds = now() - t0;
    return c;
}

typedef struct keyed_point {
    uint32_t key;
    uint32_t index;
} keyed_point;

static int cmp_key(const void *a, const void *b)
{
    const keyed_point *x = a, *y = b;
    return x->key < y->key ? -1 : x->key > y->key ? 1 : (x->index > y->index) - (x->index < y->index);
}

static void print_row(const char *cache, const char *order, const ic_cache *c, const surface_point *q,
                      ic_cache_acceptance acc)
{
    lookup_stats st = time_lookups(c, q, acc, PATH_OCTREE);
    char label[128];
    snprintf(label, sizeof label, "%s, %s, %s", cache, order, acc == IC_ACCEPT_FINAL ? "final" : "constr.");
    printf("| %-52s | %8.2f | %6.2f | %6.2f | %5.1f%% |\n", label, st.per_second * 1e-6, st.tested, st.contributors,
           100.0 * st.hit);
}

/* One row per look-up path on a rebuilt cache (octree path thawed, then frozen, frozen with a hint,
 * frozen in batches), the same queries, timed back to back; speed-ups are ratios within this run. */
static void print_paths(const char *cache, const char *order, ic_cache *c, const surface_point *q,
                        ic_cache_acceptance acc)
{
    static const char *name[PATH_KINDS] = {"octree", "frozen", "frozen+hint", "frozen batch"};
    lookup_stats st[PATH_KINDS];
    ic_error err;
    ic_cache_thaw(c);
    st[PATH_OCTREE] = time_lookups(c, q, acc, PATH_OCTREE);
    if (ic_cache_freeze(c, &err) != IC_OK) {
        fprintf(stderr, "bench_cache: %s\n", err.message);
        exit(1);
    }
    for (int k = PATH_FROZEN; k < PATH_KINDS; ++k)
        st[k] = time_lookups(c, q, acc, (path_kind)k);
    for (int k = 0; k < PATH_KINDS; ++k) {
        char label[128];
        snprintf(label, sizeof label, "%s, %s, %s, %s", cache, order, acc == IC_ACCEPT_FINAL ? "final" : "constr.",
                 name[k]);
        printf("| %-58s | %8.2f | %5.2fx | %6.2f | %6.2f | %5.1f%% |\n", label, st[k].per_second * 1e-6,
               st[k].per_second / st[PATH_OCTREE].per_second, st[k].tested, st[k].contributors, 100.0 * st[k].hit);
    }
}

/* Freezing time and the layout's size per record. */
static void print_freeze(const char *cache, ic_cache *c)
{
    ic_error err;
    ic_cache_thaw(c);
    size_t thawed = ic_cache_memory_bytes(c);
    double t0 = now();
    if (ic_cache_freeze(c, &err) != IC_OK) {
        fprintf(stderr, "bench_cache: %s\n", err.message);
        exit(1);
    }
    double t = now() - t0;
    printf("freeze, %s: %.3f s, frozen layout %.0f bytes per record (cache without it %.0f)\n", cache, t,
           (double)(ic_cache_memory_bytes(c) - thawed) / ic_cache_count(c), (double)thawed / ic_cache_count(c));
    print_index_stats("  ", cache, c);
}

int main(int argc, char **argv)
{
    uint32_t target = argc > 1 ? (uint32_t)strtoul(argv[1], NULL, 10) : 300000u;
    box *boxes = malloc(BOXES * sizeof *boxes);
    make_boxes(boxes);

    /* 1. Lazy construction: incremental insertion where the cache has no record. */
    ic_cache_params p = {0};
    p.validity_clamp = IC_CACHE_OFF;
    p.final_accuracy_scale = 1.5f;
    ic_cache *lazy = NULL;
    ic_error err;
    if (ic_cache_create(&p, &lazy, &err) != IC_OK) {
        fprintf(stderr, "bench_cache: %s\n", err.message);
        return 1;
    }
    ic_record *recs = malloc((size_t)target * sizeof *recs);
    uint32_t n = 0;
    uint64_t candidates = 0;
    double t_insert = 0.0, t_lazy0 = now();
    while (n < target) {
        ic_rng r = ic_rng_make(7, candidates++, 0, 0);
        surface_point s = sample_surface(boxes, &r);
        ic_cache_lookup l = ic_cache_lookup_at(s.p, s.n, IC_ACCEPT_CONSTRUCTION);
        ic_cache_estimate e;
        if (ic_cache_query(lazy, &l, &e))
            continue;
        recs[n] = make_record(s, &r);
        double t0 = now();
        if (ic_cache_insert(lazy, &recs[n], NULL, &err) != IC_OK) {
            fprintf(stderr, "bench_cache: %s\n", err.message);
            return 1;
        }
        t_insert += now() - t0;
        ++n;
    }
    double t_lazy = now() - t_lazy0;

    /* 2. Batch candidates as a batch pass produces them: unfiltered, overlapping, in Morton order. */
    ic_record *cand = malloc((size_t)n * sizeof *cand);
    keyed_point *keys = malloc((size_t)(n > QUERIES ? n : QUERIES) * sizeof *keys);
    for (uint32_t i = 0; i < n; ++i) {
        ic_rng r = ic_rng_make(8, i, 0, 0);
        surface_point s = sample_surface(boxes, &r);
        cand[i] = make_record(s, &r);
        /* Batch candidates are placed without look-ups, so their spheres overlap: R in [1, 10]. */
        cand[i].harmonic_mean_dist *= 3.3f;
        keys[i] = (keyed_point){morton(s.p), i};
    }
    qsort(keys, n, sizeof *keys, cmp_key);
    ic_record *sorted = malloc((size_t)n * sizeof *sorted);
    for (uint32_t i = 0; i < n; ++i)
        sorted[i] = cand[keys[i].index];
    double t_batch_v, t_batch_nv, t_batch10k;
    ic_cache *with_v = batch_build(sorted, n, n, 1, &t_batch_v);
    ic_cache *without_v = batch_build(sorted, n, n, 0, &t_batch_nv);
    ic_cache *passes = batch_build(sorted, n, 10000, 1, &t_batch10k);

    /* Look-ups: random order, and sorted on a Morton curve (renderer-like coherence). */
    surface_point *q = malloc(QUERIES * sizeof *q), *qc = malloc(QUERIES * sizeof *qc);
    for (int k = 0; k < QUERIES; ++k) {
        ic_rng r = ic_rng_make(99, (uint64_t)k, 0, 0);
        q[k] = sample_surface(boxes, &r);
        keys[k] = (keyed_point){morton(q[k].p), (uint32_t)k};
    }
    qsort(keys, QUERIES, sizeof *keys, cmp_key);
    for (int k = 0; k < QUERIES; ++k)
        qc[k] = q[keys[k].index];

    printf("irrcache cache benchmark: %u records on %d boxes' faces (60^3 world), Ward a = 0.2, final scale 1.5,\n"
           "gradient + neighbor clamps on; %d look-ups per run on 1 thread, median of %d runs\n\n",
           n, BOXES, QUERIES, REPS);
    printf("Incrementally grown octree (construction phase; never frozen):\n\n");
    printf("| %-52s | %8s | %6s | %6s | %6s |\n", "cache, look-up order, acceptance", "M look/s", "refs", "contrib",
           "hit");
    printf("|%s|%s|%s|%s|%s|\n", "------------------------------------------------------", "----------", "--------",
           "--------", "--------");
    print_row("lazy (incremental)", "coherent", lazy, qc, IC_ACCEPT_CONSTRUCTION);
    print_row("lazy (incremental)", "coherent", lazy, qc, IC_ACCEPT_FINAL);
    print_row("lazy (incremental)", "random", lazy, q, IC_ACCEPT_FINAL);
    double t_rebuild0 = now();
    ic_cache_rebuild_index(lazy, &err);
    double t_rebuild = now() - t_rebuild0;
    /* The batch caches' octrees were rebuilt by their (large) batch; rebuild anyway for equal footing. */
    ic_cache_rebuild_index(without_v, &err);
    ic_cache_rebuild_index(with_v, &err);
    printf("\nAfter ic_cache_rebuild_index: octree path (thawed) vs frozen layout vs frozen + hint vs batches,\n"
           "same queries; speed-up = rate / octree rate of the same cache, order and acceptance:\n\n");
    printf("| %-58s | %8s | %6s | %6s | %6s | %6s |\n", "cache, order, acceptance, path", "M look/s", "speed",
           "refs", "contrib", "hit");
    printf("|%s|%s|%s|%s|%s|%s|\n", "------------------------------------------------------------", "----------",
           "--------", "--------", "--------", "--------");
    const char *cname[3] = {"lazy", "batch, no validity", "batch, validity"};
    ic_cache *caches[3] = {lazy, without_v, with_v};
    for (int k = 0; k < 3; ++k) {
        print_paths(cname[k], "coherent", caches[k], qc, IC_ACCEPT_CONSTRUCTION);
        print_paths(cname[k], "coherent", caches[k], qc, IC_ACCEPT_FINAL);
        print_paths(cname[k], "random", caches[k], q, IC_ACCEPT_FINAL);
    }
    printf("\n");
    for (int k = 0; k < 3; ++k)
        print_freeze(cname[k], caches[k]);
    printf("\n%d threads, coherent, final, frozen + hint: no validity %.2f M/s, validity %.2f M/s\n",
           ic_hardware_threads(), time_lookups_mt(without_v, qc) * 1e-6, time_lookups_mt(with_v, qc) * 1e-6);
    printf("\ninsertion: incremental (lazy, %llu candidates) %.0f records/s (insertion only; whole loop %.2f s);\n"
           "  one batch of %u: %.0f records/s (validity on), %.0f records/s (off); batches of 10k: %.0f records/s;\n"
           "  octree rebuild + freeze of the lazy cache: %.3f s\n",
           (unsigned long long)candidates, n / t_insert, t_lazy, n, n / t_batch_v, n / t_batch_nv, n / t_batch10k,
           t_rebuild);
    printf("memory: %zu bytes per record (record arrays); whole cache incl. octree and point index: %.0f (lazy), "
           "%.0f (batch, no validity), %.0f (batch, validity) bytes per record\n",
           ic_cache_bytes_per_record(), (double)ic_cache_memory_bytes(lazy) / n,
           (double)ic_cache_memory_bytes(without_v) / n, (double)ic_cache_memory_bytes(with_v) / n);

    ic_cache_destroy(lazy);
    ic_cache_destroy(with_v);
    ic_cache_destroy(without_v);
    ic_cache_destroy(passes);
    free(q);
    free(qc);
    free(keys);
    free(sorted);
    free(cand);
    free(recs);
    free(boxes);
    return 0;
}
