/*
 * test_cache.c — the irradiance cache library (include/irrcache/cache.h), linked with irrcache_cache
 * and ic_core only.
 *
 * Properties checked:
 *   - octree look-up equals a linear scan over 100k random records (contributor sets exactly, E to
 *     float rounding) for both weights, with no clamp, each clamp alone, and all of them;
 *   - the frozen layout (cache.h: FROZEN LOOK-UPS) answers bit-identically to the octree path (same
 *     contributors in the same order, same sums) with and without hints — hints in query order, left
 *     over from far-away look-ups, garbage — and at points outside the root, and equals the linear
 *     scan too; insertions and record changes thaw it and look-ups stay exact; a rebuild re-freezes;
 *     it is built alike on 1, 2, 3 and 8 threads (byte for byte) and its nodes, leaves and lists
 *     tile its arrays exactly;
 *   - the weights and the extrapolation follow the formulas of Křivánek et al. 2006 §3 and
 *     Tabellion–Lamorlette (checked against hand-computed values), and a linear irradiance field is
 *     reproduced exactly;
 *   - clamps never raise a radius (new or existing records); after neighbor clamping
 *     (Křivánek et al. 2006 §5.2) |R_i − R_j| ≤ |p_i − p_j| for every pair within reach; validity
 *     clamping (Frolov et al. 2012 §4.2) leaves no influence radius above the k-th distinct-direction
 *     neighbour distance, recomputed here by brute force; gradient-difference scaling (Castaño 2014)
 *     separates records with different gradients;
 *   - batch insertion gives the same cache on 1 and 2 threads;
 *   - k-nearest and radius queries equal brute force;
 *   - far from the origin with radii of a few ulps, octree and frozen look-ups equal a linear scan;
 *   - the cache file round-trips bit-exactly and refuses truncated, corrupted and mismatched files;
 *   - insertion refuses records beyond the range a file holds (1e30), what inserts loads; a needle-thin
 *     ellipse is stored with the floor ratio, contributes and loads.
 */
#include "irrcache/cache.h"

#include "cache/cache_store.h" /* ic_cache_set_lookup_path */
#include "core/rng.h"
#include "core/text.h"
#include "core/threads.h"
#include "core/vecmath.h"
#include "test_files.h"
#include "test_util.h"

#include <dirent.h>
#include <stdint.h>
#include <string.h>
#include <sys/stat.h>
#define FILE_RECORD_BYTES 172 /* bytes of a record in a version-3 or 4 cache file */
#define FILE_HEADER_BYTES 88  /* the header, up to the record count */
#define FILE_RECORDS_AT 92    /* records of a version-4 file with no settings text (its length: 0) */
#include <unistd.h>

#include <time.h>
static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

/* ---- random records ---------------------------------------------------------------------------- */

static ic_vec3 random_unit(ic_rng *r)
{
    float z = 2.0f * ic_rng_float(r) - 1.0f, phi = 2.0f * IC_PI * ic_rng_float(r);
    float s = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    return v3(s * cosf(phi), s * sinf(phi), z);
}

static ic_vec3 random_in_plane(ic_rng *r, ic_vec3 n, float scale)
{
    ic_frame f = ic_frame_from_normal(n);
    float u = 2.0f * ic_rng_float(r) - 1.0f, v = 2.0f * ic_rng_float(r) - 1.0f;
    return v3_add(v3_scale(f.t, u * scale), v3_scale(f.b, v * scale));
}

/* Records in a 20³ box: three quarters on three axis planes, a quarter anywhere with any normal.
 * R is log-uniform in [0.05, 2]; gradients are random and sometimes steep enough for eq. 2. */
static void make_record(ic_record *rec, uint64_t seed, uint32_t i)
{
    ic_rng r = ic_rng_make(seed, i, 0, 0);
    memset(rec, 0, sizeof *rec);
    float u = 20.0f * ic_rng_float(&r), v = 20.0f * ic_rng_float(&r), w = 20.0f * ic_rng_float(&r);
    switch (i % 4) {
    case 0: rec->position = v3(u, v, 1.0f); rec->normal = v3(0, 0, 1); break;
    case 1: rec->position = v3(3.0f, u, v); rec->normal = v3(-1, 0, 0); break;
    case 2: rec->position = v3(u, 7.0f, v); rec->normal = v3(0, 1, 0); break;
    default: rec->position = v3(u, v, w); rec->normal = random_unit(&r); break;
    }
    rec->tangent = ic_frame_from_normal(rec->normal).t;
    rec->irradiance = v3(0.2f + 1.8f * ic_rng_float(&r), 0.2f + 1.8f * ic_rng_float(&r), 0.2f + 1.8f * ic_rng_float(&r));
    rec->harmonic_mean_dist = expf(logf(0.05f) + ic_rng_float(&r) * logf(40.0f));
    float steep = 2.0f * ic_rng_float(&r) / rec->harmonic_mean_dist;
    for (int ch = 0; ch < 3; ++ch) {
        rec->grad_trans[ch] = random_in_plane(&r, rec->normal, steep * v3_get(rec->irradiance, ch));
        rec->grad_rot[ch] = random_in_plane(&r, rec->normal, 0.3f * v3_get(rec->irradiance, ch));
    }
    rec->sigma = v3s(0.01f * ic_rng_float(&r));
    rec->pixel_footprint = 0.01f;
}

static ic_record *make_records(uint32_t n, uint64_t seed)
{
    ic_record *r = malloc((size_t)n * sizeof *r);
    for (uint32_t i = 0; i < n; ++i)
        make_record(&r[i], seed, i);
    return r;
}

/* Inserts through every path: one big batch, many small batches, single records. */
static ic_cache *build_cache(const ic_cache_params *p, const ic_record *recs, uint32_t n)
{
    ic_cache *c = NULL;
    ic_error err;
    CHECK(ic_cache_create(p, &c, &err) == IC_OK, "create: %s", err.message);
    uint32_t big = n / 2, small_end = n - n / 10, first = 0;
    CHECK(ic_cache_insert_batch(c, recs, big, &first, &err) == IC_OK && first == 0, "batch: %s", err.message);
    for (uint32_t i = big; i < small_end; i += 1000) {
        uint32_t m = small_end - i < 1000 ? small_end - i : 1000;
        CHECK(ic_cache_insert_batch(c, recs + i, m, &first, &err) == IC_OK && first == i, "batch: %s", err.message);
    }
    for (uint32_t i = small_end; i < n; ++i) {
        uint32_t idx = 0;
        if (ic_cache_insert(c, &recs[i], &idx, &err) != IC_OK || idx != i) {
            CHECK(0, "insert %u: %s", i, err.message);
            break;
        }
    }
    CHECK(ic_cache_count(c) == n, "count %u", ic_cache_count(c));
    return c;
}

/* A query near a random record: inside (or just outside) its influence, normal slightly tilted. */
static void make_query(const ic_cache *c, uint64_t seed, uint32_t q, float scale, ic_vec3 *p, ic_vec3 *n)
{
    ic_rng r = ic_rng_make(seed, q, 1, 0);
    ic_record rec;
    ic_cache_get_record(c, ic_rng_below(&r, ic_cache_count(c)), &rec);
    float reach = 1.1f * rec.accuracy * rec.radius * scale;
    *p = v3_add(rec.position, random_in_plane(&r, rec.normal, reach));
    *p = v3_madd(*p, rec.normal, (ic_rng_float(&r) - 0.5f) * 0.1f * reach);
    *n = v3_norm(v3_add(rec.normal, v3_scale(random_unit(&r), 0.1f * ic_rng_float(&r))));
    if (q % 16 == 0) { /* now and then a point anywhere */
        *p = v3(20.0f * ic_rng_float(&r), 20.0f * ic_rng_float(&r), 20.0f * ic_rng_float(&r));
        *n = random_unit(&r);
    }
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

/* ---- look-up equals brute force ---------------------------------------------------------------- */

/*
 * The reference tests every record that could possibly contribute: records sorted by x, the slab
 * |x − p.x| ≤ max influence radius found by binary search (nothing outside it can reach p), then a
 * vectorisable distance pre-filter with a generous margin over the slab, then the library's
 * per-record weight test. The interpolated value is recomputed here from the record fields with
 * Křivánek et al. 2006 eq. 1 — independent of the octree and of the library's accumulation code.
 */
#define MAX_CONTRIB 4096

typedef struct compare_job {
    const ic_cache *cache;
    const ic_record *fin;       /* records as stored */
    const float *x, *y, *z, *r2; /* sorted by x; r2: squared influence radius with margin */
    const uint32_t *order;      /* record index of each sorted entry */
    float rmax;                 /* largest influence radius with margin */
    uint32_t n;
    uint64_t seed;
    ic_cache_acceptance acceptance;
    ic_cache_hint *hints;       /* per thread, left over from that thread's previous query; NULL: none */
    unsigned char *bad;         /* per query: 1 = sets differ, 2 = values differ */
    uint32_t *contributors;     /* per query */
} compare_job;

static ic_vec3 extrapolate(const ic_record *r, ic_vec3 p, ic_vec3 n)
{
    ic_vec3 rot = v3_cross(r->normal, n), dp = v3_sub(p, r->position);
    float e[3];
    for (int ch = 0; ch < 3; ++ch)
        e[ch] = fmaxf(0.0f, v3_get(r->irradiance, ch) + v3_dot(rot, r->grad_rot[ch]) + v3_dot(dp, r->grad_trans[ch]));
    return v3(e[0], e[1], e[2]);
}

static void compare_one(void *ctx, int64_t item, int thread)
{
    compare_job *job = ctx;
    ic_cache_contribution *a = malloc(MAX_CONTRIB * sizeof *a);
    uint32_t *ia = malloc(MAX_CONTRIB * sizeof *ia), *ib = malloc(MAX_CONTRIB * sizeof *ib);
    ic_cache_lookup q = {0};
    make_query(job->cache, job->seed, (uint32_t)item,
               job->acceptance == IC_ACCEPT_FINAL ? ic_cache_get_params(job->cache)->final_accuracy_scale : 1.0f,
               &q.position, &q.normal);
    q.acceptance = job->acceptance;
    q.contribution_capacity = MAX_CONTRIB;
    q.contributions = a;
    ic_cache_estimate ea;
    int ha = ic_cache_query_hinted(job->cache, &q, job->hints ? &job->hints[thread] : NULL, &ea);
    /* Brute force over the slab. */
    uint32_t nb = 0;
    double sum_w = 0.0, sum[3] = {0.0, 0.0, 0.0};
    const float px = q.position.x, py = q.position.y, pz = q.position.z;
    const float *x = job->x, *y = job->y, *z = job->z, *r2 = job->r2;
    uint32_t lo = 0, hi = job->n;
    while (lo < hi) { /* first entry with x ≥ px − rmax */
        uint32_t mid = lo + (hi - lo) / 2;
        if (x[mid] < px - job->rmax)
            lo = mid + 1;
        else
            hi = mid;
    }
    unsigned char flag[1024];
    for (uint32_t base = lo; base < job->n && x[base] <= px + job->rmax; base += 1024) {
        uint32_t m = job->n - base < 1024 ? job->n - base : 1024;
        for (uint32_t k = 0; k < m; ++k) {
            float dx = x[base + k] - px, dy = y[base + k] - py, dz = z[base + k] - pz;
            flag[k] = dx * dx + dy * dy + dz * dz < r2[base + k];
        }
        for (uint32_t k = 0; k < m; ++k) {
            if (!flag[k])
                continue;
            uint32_t i = job->order[base + k];
            float w;
            if (!ic_cache_record_weight(job->cache, i, q.position, q.normal, job->acceptance, &w) ||
                (job->fin[i].flags & IC_RECORD_DISABLED) || job->fin[i].bounce != q.bounce)
                continue;
            if (nb < MAX_CONTRIB)
                ib[nb] = i;
            ++nb;
            ic_vec3 e = extrapolate(&job->fin[i], q.position, q.normal);
            sum_w += w;
            sum[0] += w * e.x;
            sum[1] += w * e.y;
            sum[2] += w * e.z;
        }
    }
    qsort(ib, nb < MAX_CONTRIB ? nb : MAX_CONTRIB, sizeof *ib, cmp_u32);
    unsigned char bad = 0;
    if (ha != (nb > 0) || ea.contributor_count != nb || ea.contributions_written != nb) {
        bad = 1;
    } else if (nb) {
        for (uint32_t k = 0; k < nb; ++k)
            ia[k] = a[k].record;
        qsort(ia, nb, sizeof *ia, cmp_u32);
        if (memcmp(ia, ib, nb * sizeof *ia) != 0)
            bad = 1;
        double want[3] = {sum[0] / sum_w, sum[1] / sum_w, sum[2] / sum_w};
        double tol = 1e-4 * (1.0 + fmax(want[0], fmax(want[1], want[2])));
        if (!bad && (fabs(ea.irradiance.x - want[0]) > tol || fabs(ea.irradiance.y - want[1]) > tol ||
                     fabs(ea.irradiance.z - want[2]) > tol || fabs(ea.weight_sum - sum_w) > 1e-4 * sum_w))
            bad = 2;
    }
    job->bad[item] = bad;
    job->contributors[item] = nb;
    free(a);
    free(ia);
    free(ib);
}

static const float *sort_key;
static int cmp_by_key(const void *a, const void *b)
{
    float x = sort_key[*(const uint32_t *)a], y = sort_key[*(const uint32_t *)b];
    return x < y ? -1 : x > y;
}

static void check_lookup_equals_brute_force(const ic_cache *c, uint32_t queries, const char *what)
{
    ic_cache_hint hints[64];
    memset(hints, 0, sizeof hints);
    uint32_t n = ic_cache_count(c);
    ic_record *fin = malloc(n * sizeof *fin);
    float *px = malloc(n * sizeof *px), *x = malloc(n * sizeof *x), *y = malloc(n * sizeof *y),
          *z = malloc(n * sizeof *z), *r2 = malloc(n * sizeof *r2);
    uint32_t *order = malloc(n * sizeof *order);
    for (uint32_t i = 0; i < n; ++i) {
        ic_cache_get_record(c, i, &fin[i]);
        px[i] = fin[i].position.x;
        order[i] = i;
    }
    sort_key = px;
    qsort(order, n, sizeof *order, cmp_by_key);
    for (int acc = 0; acc < 2; ++acc) {
        float s = acc ? ic_cache_get_params(c)->final_accuracy_scale : 1.0f, rmax = 0.0f;
        for (uint32_t k = 0; k < n; ++k) {
            const ic_record *rec = &fin[order[k]];
            x[k] = rec->position.x;
            y[k] = rec->position.y;
            z[k] = rec->position.z;
            float r = 1.01f * s * rec->accuracy * rec->radius;
            r2[k] = r * r;
            rmax = fmaxf(rmax, r);
        }
        compare_job job = {c, fin, x, y, z, r2, order, rmax, n, 77, acc ? IC_ACCEPT_FINAL : IC_ACCEPT_CONSTRUCTION,
                           ic_cache_is_frozen(c) ? hints : NULL, calloc(queries, 1), calloc(queries, sizeof(uint32_t))};
        ic_parallel_for(0, queries, compare_one, &job);
        uint32_t set_bad = 0, val_bad = 0, hit = 0;
        uint64_t total = 0;
        for (uint32_t q = 0; q < queries; ++q) {
            set_bad += job.bad[q] == 1;
            val_bad += job.bad[q] == 2;
            hit += job.contributors[q] > 0;
            total += job.contributors[q];
        }
        CHECK(set_bad == 0 && val_bad == 0, "%s (%s): %u queries with other contributors, %u with other values",
              what, acc ? "final" : "construction", set_bad, val_bad);
        /* The comparison means something only if many queries find records. */
        CHECK(hit > queries / 8, "%s: only %u of %u queries found records", what, hit, queries);
        printf("  %-30s %-12s %-6s %5u queries, %5.1f%% hit, %5.2f contributors on average\n", what,
               acc ? "final" : "construction", ic_cache_is_frozen(c) ? "frozen" : "octree", queries,
               100.0 * hit / queries, (double)total / queries);
        free(job.bad);
        free(job.contributors);
    }
    free(fin);
    free(px);
    free(x);
    free(y);
    free(z);
    free(r2);
    free(order);
}

/* ---- frozen layout: the octree path's contributors; every code path the same bits ---------------- */

#define ID_CONTRIB 512

typedef struct answer {
    int hit;
    ic_cache_estimate e;
    ic_cache_contribution con[ID_CONTRIB];
} answer;

static void ask(const ic_cache *c, const ic_cache_lookup *q, ic_cache_hint *hint, answer *a)
{
    ic_cache_lookup l = *q;
    l.contributions = a->con;
    l.contribution_capacity = ID_CONTRIB;
    memset(a->con, 0, sizeof a->con);
    a->hit = ic_cache_query_hinted(c, &l, hint, &a->e);
}

/* ask() without a contributions buffer (look-ups take a shorter route then). */
static void ask_bare(const ic_cache *c, const ic_cache_lookup *q, ic_cache_hint *hint, answer *a)
{
    ic_cache_lookup l = *q;
    l.contributions = NULL;
    l.contribution_capacity = 0;
    a->hit = ic_cache_query_hinted(c, &l, hint, &a->e);
}

/* Same hit, count and sums (bitwise) as a full answer, and nothing reported written. */
static int same_sums(const answer *bare, const answer *full)
{
    return bare->hit == full->hit && bare->e.contributor_count == full->e.contributor_count &&
           bare->e.contributions_written == 0 &&
           memcmp(&bare->e.irradiance, &full->e.irradiance, sizeof bare->e.irradiance) == 0 &&
           memcmp(&bare->e.weight_sum, &full->e.weight_sum, sizeof bare->e.weight_sum) == 0;
}

/* |x − y| within the rounding that adding n positive terms in another order, and dividing two such
 * sums, can make: (4n + 2) units of 2⁻²⁴ relative. */
static int sums_close(float x, float y, uint32_t n)
{
    return fabsf(x - y) <= (4.0f * (float)n + 2.0f) * 0x1p-24f * fmaxf(fabsf(x), fabsf(y));
}

/* x and y agree up to the rounding of an extrapolation done in another (exact) arithmetic form:
 * 10⁻⁵ absolute on values of order one, relative beyond. */
static int values_close(float x, float y)
{
    return fabsf(x - y) <= 1e-5f * (1.0f + fmaxf(fabsf(x), fabsf(y)));
}

/* The frozen layout's answer a against the octree path's b: the same contributors in the same order
 * with the same weights (bitwise); values and sums equal up to rounding (cache_frozen_query.c: "Frozen look-ups":
 * another order of the additions, the rotation term as n·(∇r E_i × n_i)). */
static int octree_agrees(const answer *a, const answer *b)
{
    uint32_t n = a->e.contributor_count;
    if (a->hit != b->hit || n != b->e.contributor_count || a->e.contributions_written != b->e.contributions_written)
        return 0;
    for (uint32_t k = 0; k < a->e.contributions_written; ++k) {
        const ic_cache_contribution *x = &a->con[k], *y = &b->con[k];
        if (x->record != y->record || memcmp(&x->weight, &y->weight, sizeof x->weight) != 0 ||
            !values_close(x->value.x, y->value.x) || !values_close(x->value.y, y->value.y) ||
            !values_close(x->value.z, y->value.z))
            return 0;
    }
    float x[3] = {a->e.irradiance.x, a->e.irradiance.y, a->e.irradiance.z};
    float y[3] = {b->e.irradiance.x, b->e.irradiance.y, b->e.irradiance.z};
    for (int ch = 0; ch < 3; ++ch)
        if (!sums_close(x[ch], y[ch], n) && !values_close(x[ch], y[ch]))
            return 0;
    return sums_close(a->e.weight_sum, b->e.weight_sum, n);
}

/* Same contributors in the same order with the same weights and values, same sums (bitwise). */
static int same_answer(const answer *a, const answer *b)
{
    if (a->hit != b->hit || a->e.contributor_count != b->e.contributor_count ||
        a->e.contributions_written != b->e.contributions_written ||
        memcmp(&a->e.irradiance, &b->e.irradiance, sizeof a->e.irradiance) != 0 ||
        memcmp(&a->e.weight_sum, &b->e.weight_sum, sizeof a->e.weight_sum) != 0)
        return 0;
    return memcmp(a->con, b->con, a->e.contributions_written * sizeof a->con[0]) == 0;
}

enum { BATCH_SIZE = 37 }; /* look-ups per ic_cache_query_batch call in the checks (not a divisor of theirs) */

/* Asks q[0…total−1] through ic_cache_query_batch with one hint carried over: BATCH_SIZE at a time with
 * contributions buffers, then without; then in batches of 1 to 9 look-ups (shorter and longer than the
 * AVX2 path's look-ahead) each starting from a garbage hint. Returns how many answers differ from ref
 * (bitwise) or from the count the call returned, plus 1 for each run whose batches carried over the
 * hint end with another hint than single calls in order (want_hint). `room`: BATCH_SIZE answers of
 * scratch. */
static uint32_t batch_differs(const ic_cache *c, const ic_cache_lookup *q, uint32_t total, const answer *ref,
                              uint32_t want_hint, answer *room)
{
    uint32_t bad = 0;
    for (int run = 0; run < 3; ++run) {
        int bare = run > 0, garbage = run == 2;
        ic_cache_hint hint = {0};
        uint32_t size = BATCH_SIZE;
        for (uint32_t first = 0; first < total; first += size) {
            if (garbage) {
                size = 1 + first % 9;
                hint.leaf = first * 2654435761u;
            }
            uint32_t m = total - first < size ? total - first : size, hits = 0;
            ic_cache_lookup l[BATCH_SIZE];
            ic_cache_estimate e[BATCH_SIZE];
            for (uint32_t k = 0; k < m; ++k) {
                l[k] = q[first + k];
                l[k].contributions = bare ? NULL : room[k].con;
                l[k].contribution_capacity = bare ? 0 : ID_CONTRIB;
                memset(room[k].con, 0, sizeof room[k].con);
            }
            size_t found = ic_cache_query_batch(c, l, m, &hint, e);
            for (uint32_t k = 0; k < m; ++k) {
                room[k].e = e[k];
                room[k].hit = e[k].contributor_count > 0;
                hits += (uint32_t)room[k].hit;
                bad += bare ? !same_sums(&room[k], &ref[first + k]) : !same_answer(&room[k], &ref[first + k]);
            }
            bad += found != hits;
        }
        bad += !garbage && hint.leaf != want_hint;
    }
    return bad;
}

/* Queries as in the brute-force check, each followed by a neighbour 10⁻³ away (a renderer's next
 * pixel: the hint hits), plus points outside the root and with odd coordinates. The frozen answer
 * without a hint must agree with the octree path's (octree_agrees); then every frozen look-up must
 * give that answer bit for bit: asked in order with one hint, in a scrambled order (hints left over
 * from far-away look-ups), with garbage hints, and through every code path (portable — the SIMD
 * code's reference, used where SSE2 is absent —, SSE2, AVX2) with no hint, with hints in order,
 * without a contributions buffer and in batches (ic_cache_query_batch). Query k asks for bounce
 * level k mod `bounces`, level 3 standing for 256 (beyond the bytes levels are stored in). The cache is thawed on entry and frozen on exit. */
static void check_frozen_identical(ic_cache *c, uint32_t pairs, uint32_t bounces, const char *what)
{
    uint32_t total = 2 * pairs + 64;
    ic_cache_lookup *q = calloc(total, sizeof *q);
    answer *want = malloc(total * sizeof *want), *ref = malloc(total * sizeof *ref), *got = malloc(sizeof *got);
    answer *batch = malloc(BATCH_SIZE * sizeof *batch);
    for (uint32_t k = 0; k < pairs; ++k) {
        make_query(c, 91, k, ic_cache_get_params(c)->final_accuracy_scale, &q[2 * k].position, &q[2 * k].normal);
        q[2 * k].bounce = k % bounces == 3 ? 256 : k % bounces;
        q[2 * k + 1] = q[2 * k];
        q[2 * k + 1].position = v3_add(q[2 * k].position, v3(1e-3f, -0.5e-3f, 0.7e-3f));
    }
    for (uint32_t k = 2 * pairs; k < total; ++k) { /* far outside, on the far side, huge, tiny, NaN */
        float far[8] = {-1e6f, 1e6f, 1e30f, -40.0f, 60.0f, 1e-30f, NAN, INFINITY};
        q[k].position = v3(far[k % 8], 10.0f, far[(k / 8) % 8]);
        q[k].normal = v3(0, 0, 1);
    }
    uint32_t differ[2][8] = {{0}}, disagree[2] = {0, 0}, hint_hits = 0, found_at_level[3] = {0, 0, 0};
    uint32_t paths_run[4] = {0, 0, 0, 0};
    for (int acc = 0; acc < 2; ++acc) {
        ic_cache_thaw(c);
        for (uint32_t k = 0; k < total; ++k) {
            q[k].acceptance = acc ? IC_ACCEPT_FINAL : IC_ACCEPT_CONSTRUCTION;
            ask(c, &q[k], NULL, &want[k]);
            if (want[k].hit && q[k].bounce < 3)
                ++found_at_level[q[k].bounce];
        }
        ic_error err;
        CHECK(ic_cache_freeze(c, &err) == IC_OK && ic_cache_is_frozen(c), "freeze: %s", err.message);
        for (uint32_t k = 0; k < total; ++k) {
            ask(c, &q[k], NULL, &ref[k]);
            disagree[acc] += !octree_agrees(&ref[k], &want[k]);
        }
        ic_cache_hint in_order = {0}, scrambled = {0};
        for (uint32_t k = 0; k < total; ++k) {
            ask(c, &q[k], NULL, got);
            differ[acc][0] += !same_answer(got, &ref[k]);
            uint32_t before = in_order.leaf;
            ask(c, &q[k], &in_order, got);
            differ[acc][1] += !same_answer(got, &ref[k]);
            hint_hits += before != 0 && in_order.leaf == before;
            uint32_t j = (uint32_t)(((uint64_t)k * 7919u) % total);
            ask(c, &q[j], &scrambled, got);
            differ[acc][2] += !same_answer(got, &ref[j]);
            ic_cache_hint garbage = {k * 2654435761u};
            ask(c, &q[k], &garbage, got);
            differ[acc][3] += !same_answer(got, &ref[k]);
        }
        /* Every other code path this build and CPU have (the default is the best of them). */
        for (int path = IC_LOOKUP_PORTABLE; path <= IC_LOOKUP_AVX2; ++path) {
            if (!ic_cache_set_lookup_path(c, (ic_lookup_path)path))
                continue;
            ++paths_run[path];
            ic_cache_hint path_order = {0}, bare_order = {0};
            for (uint32_t k = 0; k < total; ++k) {
                ask(c, &q[k], NULL, got);
                differ[acc][4] += !same_answer(got, &ref[k]);
                ask(c, &q[k], &path_order, got);
                differ[acc][5] += !same_answer(got, &ref[k]);
                ask_bare(c, &q[k], &bare_order, got);
                differ[acc][6] += !same_sums(got, &ref[k]);
            }
            differ[acc][7] += batch_differs(c, q, total, ref, in_order.leaf, batch);
        }
        ic_cache_set_lookup_path(c, IC_LOOKUP_BEST);
    }
    CHECK(paths_run[IC_LOOKUP_PORTABLE] == 2, "%s: the portable path ran", what);
    for (int acc = 0; acc < 2; ++acc)
        CHECK(disagree[acc] == 0, "%s (%s): %u of %u frozen answers disagree with the octree path", what,
              acc ? "final" : "construction", disagree[acc], total);
    for (int acc = 0; acc < 2; ++acc)
        CHECK(differ[acc][0] + differ[acc][1] + differ[acc][2] + differ[acc][3] + differ[acc][4] +
                      differ[acc][5] + differ[acc][6] + differ[acc][7] == 0,
              "%s (%s): frozen look-ups differ from each other: %u without hint, %u with hints in order, %u with "
              "hints scrambled, %u with garbage hints; each code path: %u without hint, %u with hints, %u without "
              "a contributions buffer, %u in batches", what, acc ? "final" : "construction", differ[acc][0],
              differ[acc][1], differ[acc][2], differ[acc][3], differ[acc][4], differ[acc][5], differ[acc][6],
              differ[acc][7]);
    /* The hint must actually be used for the test to mean something (both acceptances: 2·pairs
     * neighbours). */
    CHECK(hint_hits > pairs, "%s: neighbours kept their leaf only %u times of %u", what, hint_hits, 2 * pairs);
    /* Every bounce level asked for must be answered somewhere, or the comparison would be of empty answers. */
    for (uint32_t level = 0; level < (bounces < 3 ? bounces : 3); ++level)
        CHECK(found_at_level[level] > 0, "%s: no look-up of bounce level %u found a record", what, level);
    free(q);
    free(want);
    free(ref);
    free(got);
    free(batch);
}

static ic_cache_params clamp_config(ic_weight_kind weight, int which)
{
    ic_cache_params p = {0};
    p.weight = weight;
    if (weight == IC_WEIGHT_TABELLION)
        p.accuracy = 0.4f; /* κ = 2.5: keeps spheres (and the test) small */
    p.final_accuracy_scale = 1.5f;
    p.gradient_clamp = which == 1 || which == 5 ? IC_CACHE_ON : IC_CACHE_OFF;
    p.neighbor_clamp = which == 2 || which == 5 ? IC_CACHE_ON : IC_CACHE_OFF;
    p.validity_clamp = which == 3 || which == 5 ? IC_CACHE_ON : IC_CACHE_OFF;
    p.gradient_difference = which == 4 || which == 5 ? IC_CACHE_ON : IC_CACHE_OFF;
    if (which == 5) {
        p.min_radius = 0.02f;
        p.max_radius_pixels = 150.0f; /* footprint 0.01 → R ≤ 1.5 */
    }
    return p;
}

static const char *clamp_name[6] = {"no clamps", "gradient clamp", "neighbor clamp", "validity clamp",
                                    "gradient difference", "all clamps + bounds"};

static void test_lookup_vs_brute_force(void)
{
    const uint32_t n = 100000;
    ic_record *recs = make_records(n, 1);
    for (int wk = 0; wk < 2; ++wk) {
        for (int which = 0; which < 6; ++which) {
            ic_cache_params p = clamp_config(wk ? IC_WEIGHT_TABELLION : IC_WEIGHT_WARD, which);
            ic_cache *c = build_cache(&p, recs, n);
            char what[96];
            snprintf(what, sizeof what, "%s, %s", wk ? "T-L" : "Ward", clamp_name[which]);
            /* 20k queries for the configurations without and with every clamp, half as many for the single
             * clamps (time: the linear scan is the test's long pole). */
            uint32_t share = which == 0 || which == 5 ? 1 : 2;
            check_lookup_equals_brute_force(c, IC_TEST_WORK(20000 / share), what);
            check_frozen_identical(c, IC_TEST_WORK(5000 / share), 1, what);
            check_lookup_equals_brute_force(c, IC_TEST_WORK(10000 / share), what);
            /* Clamps never raise R above the input (bounds off except in config 5). */
            uint32_t raised = 0;
            for (uint32_t i = 0; i < n; ++i) {
                ic_record r;
                ic_cache_get_record(c, i, &r);
                float lo = which == 5 ? 0.02f : 0.0f;
                raised += r.radius > fmaxf(recs[i].harmonic_mean_dist, lo);
                if (which == 5)
                    raised += r.radius > 1.5f * 1.00001f;
            }
            CHECK(raised == 0, "%s: %u radii above their input or bounds", what, raised);
            ic_cache_destroy(c);
        }
    }
    free(recs);
}

/* ---- formulas ---------------------------------------------------------------------------------- */

static ic_record plane_record(ic_vec3 p, float R)
{
    ic_record r;
    memset(&r, 0, sizeof r);
    r.position = p;
    r.normal = v3(0, 0, 1);
    r.tangent = v3(1, 0, 0);
    r.irradiance = v3(1.0f, 2.0f, 3.0f);
    r.harmonic_mean_dist = R;
    return r;
}

static ic_cache_params no_clamps(ic_weight_kind w, float a)
{
    ic_cache_params p = {0};
    p.weight = w;
    p.accuracy = a;
    p.gradient_clamp = p.neighbor_clamp = p.validity_clamp = p.gradient_difference = IC_CACHE_OFF;
    return p;
}

static void test_weights(void)
{
    ic_error err;
    for (int wk = 0; wk < 2; ++wk) {
        float a = wk ? 0.5f : 0.3f;
        ic_cache_params p = no_clamps(wk ? IC_WEIGHT_TABELLION : IC_WEIGHT_WARD, a);
        p.final_accuracy_scale = 2.0f;
        ic_cache *c;
        ic_cache_create(&p, &c, &err);
        ic_record r = plane_record(v3(0, 0, 0), 2.0f);
        r.grad_rot[0] = v3(0.0f, 0.5f, 0.0f);
        r.grad_trans[1] = v3(0.25f, 0.0f, 0.0f);
        ic_cache_insert(c, &r, NULL, &err);
        /* Query at distance 0.3 along x with the normal tilted about x (20° Ward, 5° T–L). */
        float th = (wk ? 5.0f : 20.0f) * IC_PI / 180.0f;
        ic_vec3 n = v3(0.0f, -sinf(th), cosf(th));
        ic_cache_contribution con[4];
        ic_cache_lookup q = ic_cache_lookup_at(v3(0.3f, 0.0f, 0.0f), n, IC_ACCEPT_CONSTRUCTION);
        q.contributions = con;
        q.contribution_capacity = 4;
        ic_cache_estimate e;
        float dist = 0.3f / 2.0f, ndev = sqrtf(1.0f - cosf(th));
        float w_expect = wk ? 1.0f - fmaxf(dist, ndev / sqrtf(1.0f - cosf(10.0f * IC_PI / 180.0f))) / a
                            : 1.0f / (dist + ndev);
        int accept = wk ? w_expect > 0.0f : w_expect > 1.0f / a;
        int got = ic_cache_query(c, &q, &e);
        CHECK(got == accept, "%s: accepted %d, expected %d (w %g)", wk ? "T-L" : "Ward", got, accept,
              (double)w_expect);
        /* The final acceptance (s = 2) must accept it either way. */
        q.acceptance = IC_ACCEPT_FINAL;
        got = ic_cache_query(c, &q, &e);
        float w_final = wk ? 1.0f - fmaxf(dist, ndev / sqrtf(1.0f - cosf(10.0f * IC_PI / 180.0f))) / (2.0f * a)
                           : w_expect;
        CHECK(got == 1, "%s: final acceptance rejected", wk ? "T-L" : "Ward");
        CHECK_NEAR(con[0].weight, w_final, 1e-5, "weight");
        /* E_i(p) = E_i + (n_i × n)·∇r E_i + (p − p_i)·∇t E_i, channel by channel. */
        ic_vec3 rot = v3_cross(v3(0, 0, 1), n);
        CHECK_NEAR(con[0].value.x, 1.0f + v3_dot(rot, r.grad_rot[0]), 1e-5, "value R (rotational)");
        CHECK_NEAR(con[0].value.y, 2.0f + 0.3f * 0.25f, 1e-5, "value G (translational)");
        CHECK_NEAR(con[0].value.z, 3.0f, 1e-6, "value B");
        CHECK_NEAR(e.irradiance.y, con[0].value.y, 1e-6, "single-record interpolation");
        /* Behind the record: a point below its plane is rejected, just above is accepted. */
        q.acceptance = IC_ACCEPT_CONSTRUCTION;
        q.position = v3(0.05f, 0.0f, -0.1f);
        q.normal = v3(0, 0, 1);
        CHECK(!ic_cache_query(c, &q, &e), "point behind the record accepted");
        q.position = v3(0.05f, 0.0f, 0.001f);
        CHECK(ic_cache_query(c, &q, &e), "point just above the record rejected");
        /* Opposite normal: rejected. */
        q.normal = v3(0, 0, -1);
        CHECK(!ic_cache_query(c, &q, &e), "opposite normal accepted");
        /* Other bounce level: ignored. */
        q.normal = v3(0, 0, 1);
        q.bounce = 1;
        CHECK(!ic_cache_query(c, &q, &e), "record of another bounce level used");
        /* Negative extrapolations clamp to zero. */
        ic_cache_destroy(c);
    }
}

/* ---- elliptical records (cache.h: ELLIPTICAL RECORDS) --------------------------------------------- */

/* Every fourth record round, the others elliptical with a ratio in [0.15, 1) along a random tangent axis. */
static ic_record *make_ellipses(uint32_t n, uint64_t seed)
{
    ic_record *r = make_records(n, seed);
    for (uint32_t i = 0; i < n; ++i) {
        if (i % 4 == 3)
            continue;
        ic_rng g = ic_rng_make(seed, i, 9, 0);
        r[i].ellipse_axis = v3_add(random_in_plane(&g, r[i].normal, 1.0f), v3_scale(r[i].normal, 0.3f));
        r[i].ellipse_ratio = 0.15f + 0.85f * ic_rng_float(&g);
    }
    return r;
}

static void test_ellipses(void)
{
    ic_error err;
    /* One record, R = 1, a = 0.5, ρ = 0.25, minor axis along x (given tilted out of the plane: projected). */
    const ic_weight_kind kinds[3] = {IC_WEIGHT_WARD, IC_WEIGHT_TABELLION, IC_WEIGHT_ERROR};
    const char *kind_name[3] = {"Ward", "T-L", "error"};
    for (int wk = 0; wk < 3; ++wk) {
        ic_cache_params p = no_clamps(kinds[wk], 0.5f);
        ic_cache *c = NULL;
        CHECK(ic_cache_create(&p, &c, &err) == IC_OK, "create: %s", err.message);
        ic_record r = plane_record(v3(0, 0, 0), 1.0f);
        r.ellipse_axis = v3(2.0f, 0.0f, 0.5f);
        r.ellipse_ratio = 0.25f;
        CHECK(ic_cache_insert(c, &r, NULL, &err) == IC_OK, "insert: %s", err.message);
        ic_record got;
        ic_cache_get_record(c, 0, &got);
        CHECK(ic_cache_ellipse_count(c) == 1 && got.ellipse_ratio == 0.25f, "%s: ratio %g, %u ellipses",
              kind_name[wk], (double)got.ellipse_ratio, ic_cache_ellipse_count(c));
        CHECK_NEAR(got.ellipse_axis.x, 1.0, 1e-6, "minor axis projected into the tangent plane");
        /* The extent: a·R = 0.5 along the major axis (y), a·ρ·R = 0.125 along the minor (x); the
         * rotational term is zero (same normal) so the edge is where the distance term reaches a. */
        const ic_vec3 n = v3(0, 0, 1);
        struct { ic_vec3 p; int in; } edge[6] = {
            {v3(0, 0.495f, 0), 1}, {v3(0, 0.505f, 0), 0}, {v3(0.12375f, 0, 0), 1},
            {v3(0.12625f, 0, 0), 0}, {v3(-0.12375f, 0, 0), 1}, {v3(0.1f, 0.4f, 0), 0}};
        for (int k = 0; k < 6; ++k) {
            float w;
            int in = ic_cache_record_weight(c, 0, edge[k].p, n, IC_ACCEPT_CONSTRUCTION, &w);
            CHECK(in == edge[k].in, "%s: point (%g, %g) %s the ellipse", kind_name[wk], (double)edge[k].p.x,
                  (double)edge[k].p.y, edge[k].in ? "inside, rejected by" : "outside, accepted by");
        }
        /* Equal metric distance 0.25 (a quarter of R along y, 0.0625 = ρ/4 along x): equal weights,
         * and what each formula gives: Ward 1/0.25, T–L 1 − 0.25/a, error 1 − (0.25/a)². */
        float wy = 0, wx = 0;
        ic_cache_record_weight(c, 0, v3(0, 0.25f, 0), n, IC_ACCEPT_CONSTRUCTION, &wy);
        ic_cache_record_weight(c, 0, v3(0.0625f, 0, 0), n, IC_ACCEPT_CONSTRUCTION, &wx);
        const float expect[3] = {4.0f, 0.5f, 0.75f};
        CHECK_NEAR(wy, expect[wk], 1e-5, "weight at 0.25 along the major axis");
        CHECK_NEAR(wx, expect[wk], 1e-5, "weight at 0.0625 along the minor axis");
        ic_cache_destroy(c);
    }
    /* The error weight's normal term: one minus the squared deviation over a², like Ward's reach. */
    {
        ic_cache_params p = no_clamps(IC_WEIGHT_ERROR, 0.5f);
        ic_cache *c = NULL;
        ic_cache_create(&p, &c, &err);
        ic_record r = plane_record(v3(0, 0, 0), 1.0f);
        ic_cache_insert(c, &r, NULL, &err);
        float th = 20.0f * IC_PI / 180.0f, w = 0;
        ic_vec3 n = v3(0.0f, -sinf(th), cosf(th));
        CHECK(ic_cache_record_weight(c, 0, v3(0.1f, 0, 0), n, IC_ACCEPT_CONSTRUCTION, &w), "error weight: 20° rejected");
        float dt = 0.1f / 0.5f, dr = sqrtf(1.0f - cosf(th)) / 0.5f;
        CHECK_NEAR(w, 1.0f - (dt * dt + dr * dr), 1e-5, "error weight with a tilted normal");
        ic_cache_destroy(c);
    }
    /* Clamp step 1 bounds both semi-axes: a ceiling of 2 turns (10, 1) into (2, 1), ρ 0.1 → 0.5; a
     * floor of 0.5 turns (1, 0.1) into (1, 0.5). */
    {
        ic_cache_params p = no_clamps(IC_WEIGHT_WARD, 0.5f);
        p.max_radius = 2.0f;
        p.min_radius = 0.5f;
        ic_cache *c = NULL;
        ic_cache_create(&p, &c, &err);
        ic_record r[3] = {plane_record(v3(0, 0, 0), 10.0f), plane_record(v3(50, 0, 0), 1.0f),
                          plane_record(v3(99, 0, 0), 4.0f)};
        r[0].ellipse_axis = r[1].ellipse_axis = r[2].ellipse_axis = v3(0, 1, 0);
        r[0].ellipse_ratio = 0.1f;
        r[1].ellipse_ratio = 0.1f;
        r[2].ellipse_ratio = 0.5f; /* (4, 2) → (2, 2): round */
        CHECK(ic_cache_insert_batch(c, r, 3, NULL, &err) == IC_OK, "insert: %s", err.message);
        ic_record g[3];
        for (int k = 0; k < 3; ++k)
            ic_cache_get_record(c, (uint32_t)k, &g[k]);
        CHECK_NEAR(g[0].radius, 2.0, 1e-6, "major axis under the ceiling");
        CHECK_NEAR(g[0].ellipse_ratio, 0.5, 1e-6, "minor axis 1 under the ceiling of 2");
        CHECK_NEAR(g[1].radius, 1.0, 1e-6, "major axis above the floor");
        CHECK_NEAR(g[1].ellipse_ratio, 0.5, 1e-6, "minor axis raised to the floor");
        CHECK(g[2].ellipse_ratio == 0.0f && ic_cache_ellipse_count(c) == 2, "an ellipse clamped round is round "
              "(ratio %g, %u ellipses)", (double)g[2].ellipse_ratio, ic_cache_ellipse_count(c));
        r[0].ellipse_ratio = 1.5f;
        CHECK(ic_cache_insert(c, &r[0], NULL, &err) == IC_ERR_INVALID_ARG && strstr(err.message, "ellipse ratio"),
              "a ratio above 1 refused: %s", err.message);
        r[0].ellipse_ratio = 0.5f;
        r[0].ellipse_axis = v3(0, 0, 1);
        CHECK(ic_cache_insert(c, &r[0], NULL, &err) == IC_ERR_INVALID_ARG && ic_cache_count(c) == 3,
              "an ellipse axis along the normal refused: %s", err.message);
        ic_cache_destroy(c);
    }
    /* A cache of ellipses: octree, frozen (every code path) and brute force agree; the file keeps them. */
    const uint32_t n = 20000;
    ic_record *recs = make_ellipses(n, 5);
    for (int wk = 0; wk < 3; wk += 2) {
        for (int which = 0; which < 6; which += 5) {
            ic_cache_params p = clamp_config(kinds[wk], which);
            ic_cache *c = build_cache(&p, recs, n);
            char what[96];
            snprintf(what, sizeof what, "ellipses, %s, %s", kind_name[wk], clamp_name[which]);
            CHECK(ic_cache_ellipse_count(c) > n / 2, "%s: only %u ellipses", what, ic_cache_ellipse_count(c));
            check_lookup_equals_brute_force(c, 6000, what);
            check_frozen_identical(c, 2000, 1, what);
            check_lookup_equals_brute_force(c, 3000, what);
            if (which == 5) {
                const char *path = IC_TEST_TMP "/test_cache_ellipses.icc";
                CHECK(ic_cache_save(c, path, 7, &err) == IC_OK, "save: %s", err.message);
                ic_cache *l = NULL;
                CHECK(ic_cache_load(path, &p, 7, &l, &err) == IC_OK, "load: %s", err.message);
                uint32_t differ = 0;
                for (uint32_t i = 0; l && i < n; ++i) {
                    ic_record a, b;
                    ic_cache_get_record(c, i, &a);
                    ic_cache_get_record(l, i, &b);
                    differ += memcmp(&a, &b, sizeof a) != 0;
                }
                CHECK(l && differ == 0 && ic_cache_ellipse_count(l) == ic_cache_ellipse_count(c),
                      "%s: %u records differ after a round trip", what, differ);
                ic_cache_destroy(l);
            }
            ic_cache_destroy(c);
        }
    }
    free(recs);
}

static void test_linear_field(void)
{
    ic_error err;
    /* E(p) = e0 + B p per channel on the plane z = 0: records carry ∇t E = B's rows. */
    const ic_vec3 e0 = v3(5.0f, 6.0f, 7.0f);
    const ic_vec3 B[3] = {v3(0.10f, -0.05f, 0), v3(-0.08f, 0.12f, 0), v3(0.02f, 0.03f, 0)};
    for (int wk = 0; wk < 2; ++wk) {
        ic_cache_params p = no_clamps(wk ? IC_WEIGHT_TABELLION : IC_WEIGHT_WARD, wk ? 0.8f : 0.4f);
        ic_cache *c;
        ic_cache_create(&p, &c, &err);
        ic_rng r = ic_rng_make(5, 0, 0, 0);
        for (int i = 0; i < 400; ++i) {
            ic_vec3 pos = v3(10.0f * ic_rng_float(&r), 10.0f * ic_rng_float(&r), 0.0f);
            ic_record rec = plane_record(pos, 1.0f + 2.0f * ic_rng_float(&r));
            rec.irradiance = v3(e0.x + v3_dot(B[0], pos), e0.y + v3_dot(B[1], pos), e0.z + v3_dot(B[2], pos));
            for (int ch = 0; ch < 3; ++ch)
                rec.grad_trans[ch] = B[ch];
            ic_cache_insert(c, &rec, NULL, &err);
        }
        double worst = 0.0;
        int hits = 0;
        for (int k = 0; k < 2000; ++k) {
            ic_vec3 pos = v3(1.0f + 8.0f * ic_rng_float(&r), 1.0f + 8.0f * ic_rng_float(&r), 0.0f);
            ic_cache_lookup q = ic_cache_lookup_at(pos, v3(0, 0, 1), IC_ACCEPT_CONSTRUCTION);
            ic_cache_estimate e;
            if (!ic_cache_query(c, &q, &e))
                continue;
            ++hits;
            ic_vec3 want = v3(e0.x + v3_dot(B[0], pos), e0.y + v3_dot(B[1], pos), e0.z + v3_dot(B[2], pos));
            worst = fmax(worst, fabs(e.irradiance.x - want.x) / want.x);
            worst = fmax(worst, fabs(e.irradiance.y - want.y) / want.y);
            worst = fmax(worst, fabs(e.irradiance.z - want.z) / want.z);
        }
        CHECK(hits > 1000, "linear field: only %d hits", hits);
        CHECK(worst < 2e-5, "%s: linear field reproduced with relative error %g", wk ? "T-L" : "Ward", worst);
        ic_cache_destroy(c);
    }
}

/* ---- clamps ------------------------------------------------------------------------------------ */

/* Records on a few planes in a 4³ box, dense enough for many neighbours. */
static ic_record *make_dense(uint32_t n, uint64_t seed)
{
    ic_record *recs = make_records(n, seed);
    for (uint32_t i = 0; i < n; ++i) {
        recs[i].position = v3_scale(recs[i].position, 0.2f);
        recs[i].harmonic_mean_dist *= 1.5f;
    }
    return recs;
}

static void test_neighbor_clamp(void)
{
    const uint32_t n = 6000;
    ic_record *recs = make_dense(n, 11);
    ic_cache_params p = no_clamps(IC_WEIGHT_WARD, 0.3f);
    p.neighbor_clamp = IC_CACHE_ON;
    for (int round = 0; round < 2; ++round) {
        if (round == 1)
            p.gradient_clamp = p.validity_clamp = p.gradient_difference = IC_CACHE_ON;
        ic_cache *c = NULL;
        ic_error err;
        ic_cache_create(&p, &c, &err);
        /* Half in one batch, then singles: existing radii must never grow. */
        ic_cache_insert_batch(c, recs, n / 2, NULL, &err);
        float *before = malloc(n * sizeof *before);
        uint32_t raised = 0;
        for (uint32_t i = n / 2; i < n; ++i) {
            if (i % 500 == 0)
                for (uint32_t j = 0; j < i; ++j) {
                    ic_record r;
                    ic_cache_get_record(c, j, &r);
                    before[j] = r.radius;
                }
            ic_cache_insert(c, &recs[i], NULL, &err);
            if (i % 500 == 0)
                for (uint32_t j = 0; j < i; ++j) {
                    ic_record r;
                    ic_cache_get_record(c, j, &r);
                    raised += r.radius > before[j];
                }
        }
        CHECK(raised == 0, "insertion raised %u existing radii", raised);
        ic_record *fin = malloc(n * sizeof *fin);
        for (uint32_t i = 0; i < n; ++i)
            ic_cache_get_record(c, i, &fin[i]);
        uint64_t pairs = 0, bad = 0, clamped = 0;
        for (uint32_t i = 0; i < n; ++i) {
            clamped += fin[i].radius < recs[i].harmonic_mean_dist;
            float ri = fin[i].accuracy * fin[i].radius;
            for (uint32_t j = i + 1; j < n; ++j) {
                float d = v3_len(v3_sub(fin[i].position, fin[j].position));
                float rj = fin[j].accuracy * fin[j].radius;
                if (!(d < fmaxf(ri, rj)))
                    continue;
                ++pairs;
                bad += fabsf(fin[i].radius - fin[j].radius) > d + 1e-5f * fmaxf(fin[i].radius, fin[j].radius);
            }
        }
        CHECK(pairs > 200 && bad == 0, "neighbor clamp: %llu of %llu pairs within reach break |Ri-Rj| <= d",
              (unsigned long long)bad, (unsigned long long)pairs);
        CHECK(clamped > n / 10, "neighbor clamp changed only %llu radii", (unsigned long long)clamped);
        printf("  neighbor clamp%s: %llu pairs within reach, %llu radii clamped\n", round ? " (+ all clamps)" : "",
               (unsigned long long)pairs, (unsigned long long)clamped);
        free(fin);
        free(before);
        ic_cache_destroy(c);
    }
    free(recs);
}

/* Independent recomputation of Frolov et al. 2012 §4.2 for record i of set recs (positions, normals). */
static int kth_distinct_distance(const ic_record *fin, uint32_t n, uint32_t i, uint32_t k, float cos_min, float *out)
{
    enum { M = 6 * 8 + 1 };
    uint32_t idx[M];
    float d2[M];
    uint32_t found = 0;
    for (uint32_t j = 0; j < n; ++j) {
        float dx = fin[i].position.x - fin[j].position.x, dy = fin[i].position.y - fin[j].position.y,
              dz = fin[i].position.z - fin[j].position.z;
        float d = dx * dx + dy * dy + dz * dz;
        if (found == M && !(d < d2[M - 1] || (d == d2[M - 1] && j < idx[M - 1])))
            continue;
        uint32_t pos = found < M ? found++ : M - 1;
        while (pos > 0 && (d < d2[pos - 1] || (d == d2[pos - 1] && j < idx[pos - 1]))) {
            d2[pos] = d2[pos - 1];
            idx[pos] = idx[pos - 1];
            --pos;
        }
        d2[pos] = d;
        idx[pos] = j;
    }
    ic_vec3 dirs[16];
    uint32_t taken = 0;
    float far = 0.0f;
    for (uint32_t q = 0; q < found && taken < k; ++q) {
        if (idx[q] == i || d2[q] <= 0.0f)
            continue;
        ic_vec3 delta = v3_sub(fin[idx[q]].position, fin[i].position);
        ic_vec3 v = v3_sub(delta, v3_scale(fin[i].normal, v3_dot(delta, fin[i].normal)));
        if (!(v3_len2(v) > 1e-12f * v3_len2(delta)))
            v = delta;
        v = v3_norm(v);
        int ok = 1;
        for (uint32_t t = 0; t < taken; ++t)
            ok = ok && v3_dot(v, dirs[t]) <= cos_min;
        if (ok) {
            dirs[taken++] = v;
            far = sqrtf(d2[q]);
        }
    }
    *out = far;
    return taken == k;
}

static void test_validity_clamp(void)
{
    const uint32_t n = 6000;
    ic_record *recs = make_dense(n, 12);
    ic_cache_params p = no_clamps(IC_WEIGHT_WARD, 0.5f);
    p.validity_clamp = IC_CACHE_ON;
    p.validity_k = 6;
    p.validity_angle_deg = 30.0f;
    ic_cache *c = NULL;
    ic_error err;
    ic_cache_create(&p, &c, &err);
    ic_cache_insert_batch(c, recs, n, NULL, &err);
    ic_record *fin = malloc(n * sizeof *fin);
    for (uint32_t i = 0; i < n; ++i)
        ic_cache_get_record(c, i, &fin[i]);
    uint32_t bad = 0, exact_bad = 0, defined = 0, clamped = 0;
    float cos_min = cosf(30.0f * IC_PI / 180.0f);
    for (uint32_t i = 0; i < n; ++i) {
        float dk;
        float r = fin[i].accuracy * fin[i].radius, r0 = fin[i].accuracy * recs[i].harmonic_mean_dist;
        clamped += fin[i].radius < recs[i].harmonic_mean_dist;
        if (!kth_distinct_distance(fin, n, i, 6, cos_min, &dk)) {
            exact_bad += fin[i].radius != recs[i].harmonic_mean_dist; /* undefined: must be untouched */
            continue;
        }
        ++defined;
        bad += r > dk * 1.00001f;
        /* With validity the only clamp, the result is exactly min(r0, d_k). */
        exact_bad += fabsf(r - fminf(r0, dk)) > 1e-5f * r0;
    }
    CHECK(bad == 0, "validity clamp: %u of %u records exceed their k-th distinct-direction distance", bad, defined);
    CHECK(exact_bad == 0, "validity clamp: %u records differ from min(r, d_k)", exact_bad);
    CHECK(defined > n / 2 && clamped > n / 10, "validity clamp: %u defined, %u clamped", defined, clamped);
    printf("  validity clamp: %u of %u records have k distinct neighbours, %u clamped\n", defined, n, clamped);
    free(fin);
    ic_cache_destroy(c);
    free(recs);
}

static void test_gradient_clamps(void)
{
    ic_error err;
    /* Gradient magnitude (Křivánek et al. 2006 eq. 2): |∇Y|/Y = 2 > 1/R = 0.5 → R = Y/|∇Y| = 0.5. */
    ic_cache_params p = no_clamps(IC_WEIGHT_WARD, 0.2f);
    p.gradient_clamp = IC_CACHE_ON;
    ic_cache *c;
    ic_cache_create(&p, &c, &err);
    ic_record r = plane_record(v3(0, 0, 0), 2.0f);
    r.irradiance = v3s(1.0f);
    for (int ch = 0; ch < 3; ++ch)
        r.grad_trans[ch] = v3(2.0f, 0.0f, 0.0f);
    ic_cache_insert(c, &r, NULL, &err);
    r.position = v3(5, 5, 0);
    r.grad_trans[0] = r.grad_trans[1] = r.grad_trans[2] = v3(0.1f, 0.0f, 0.0f); /* below the bound: kept */
    ic_cache_insert(c, &r, NULL, &err);
    ic_record out;
    ic_cache_get_record(c, 0, &out);
    CHECK_NEAR(out.radius, 0.5f, 1e-6, "gradient clamp R");
    CHECK_NEAR(out.harmonic_mean_dist, 2.0f, 0, "harmonic mean kept");
    ic_cache_get_record(c, 1, &out);
    CHECK_NEAR(out.radius, 2.0f, 0, "gradient below the bound leaves R");
    ic_cache_destroy(c);

    /* Pixel bounds: R within [2, 10] footprints of 0.01. */
    p = no_clamps(IC_WEIGHT_WARD, 0.2f);
    p.min_radius_pixels = 2.0f;
    p.max_radius_pixels = 10.0f;
    ic_cache_create(&p, &c, &err);
    r = plane_record(v3(0, 0, 0), 2.0f);
    r.pixel_footprint = 0.01f;
    ic_cache_insert(c, &r, NULL, &err);
    r.position = v3(3, 0, 0);
    r.harmonic_mean_dist = 0.001f;
    ic_cache_insert(c, &r, NULL, &err);
    ic_cache_get_record(c, 0, &out);
    CHECK_NEAR(out.radius, 0.1f, 1e-7, "pixel ceiling");
    ic_cache_get_record(c, 1, &out);
    CHECK_NEAR(out.radius, 0.02f, 1e-7, "pixel floor");
    ic_cache_destroy(c);

    /* Gradient difference (Castaño 2014): two overlapping records whose gradients differ strongly
     * end up with disjoint spheres; two with equal gradients keep their radii. */
    p = no_clamps(IC_WEIGHT_WARD, 0.5f);
    p.gradient_difference = IC_CACHE_ON;
    p.gradient_difference_threshold = 0.1f;
    ic_cache_create(&p, &c, &err);
    ic_record pair[4];
    for (int k = 0; k < 4; ++k) {
        pair[k] = plane_record(v3(k < 2 ? 0.6f * (float)k : 10.0f + 0.6f * (float)(k - 2), 0, 0), 2.0f);
        pair[k].irradiance = v3s(1.0f);
        for (int ch = 0; ch < 3; ++ch)
            pair[k].grad_trans[ch] = k == 1 ? v3(0.3f, 0, 0) : v3(0.0f, 0.05f, 0);
    }
    ic_cache_insert_batch(c, pair, 4, NULL, &err);
    ic_record o[4];
    for (uint32_t k = 0; k < 4; ++k)
        ic_cache_get_record(c, k, &o[k]);
    CHECK(o[0].accuracy * o[0].radius + o[1].accuracy * o[1].radius <= 0.6f * 1.00001f,
          "gradient difference: spheres still overlap (%g + %g > 0.6)", (double)(o[0].accuracy * o[0].radius),
          (double)(o[1].accuracy * o[1].radius));
    CHECK(o[2].radius == 2.0f && o[3].radius == 2.0f, "gradient difference shrank equal-gradient records");
    ic_cache_destroy(c);

    /* Its default τ follows the accuracy, 0.1 × a / 0.15: the first pair above (Δ = |g_0 − g_1|·d/Y = 0.18)
     * is scaled at a = 0.25 (τ = 1/6) and left alone at a = 0.5 (τ = 1/3); a fixed τ made looser accuracies
     * place more records. With the scaling off τ stays 0.1, as cache files made so keep it. */
    for (int k = 0; k < 2; ++k) {
        const float a = k ? 0.5f : 0.25f;
        p = no_clamps(IC_WEIGHT_WARD, a);
        p.gradient_difference = IC_CACHE_ON;
        ic_cache_create(&p, &c, &err);
        ic_record wide[2] = {pair[0], pair[1]};
        wide[0].harmonic_mean_dist = wide[1].harmonic_mean_dist = 4.0f; /* R: within reach, a·R > 0.6 */
        ic_cache_insert_batch(c, wide, 2, NULL, &err);
        ic_cache_get_record(c, 0, &o[0]);
        CHECK(k ? o[0].radius == 4.0f : o[0].radius < 4.0f,
              "gradient difference at a = %g with the default threshold: R %g", (double)a, (double)o[0].radius);
        ic_cache_destroy(c);
    }
    /* However many neighbours scale it, a record keeps a quarter of the radius it was inserted with: here
     * R = 4 at a = 0.5; the first neighbour (d = 0.5, its own R 4) takes it to 1 (f floored at 0.25), the
     * second (d = 0.3) would take it to 0.25, and so on without end in lazy construction. */
    p = no_clamps(IC_WEIGHT_WARD, 0.5f);
    p.gradient_difference = IC_CACHE_ON;
    p.gradient_difference_threshold = 0.01f;
    ic_cache_create(&p, &c, &err);
    const float at[3] = {0.0f, 0.5f, -0.3f};
    for (int k = 0; k < 3; ++k) {
        ic_record r = plane_record(v3(at[k], 0, 0), 4.0f);
        r.irradiance = v3s(1.0f);
        for (int ch = 0; ch < 3; ++ch)
            r.grad_trans[ch] = k == 0 ? v3(0.0f, 0.05f, 0) : v3(0.3f * (float)k, 0, 0);
        ic_cache_insert_batch(c, &r, 1, NULL, &err);
    }
    ic_cache_get_record(c, 0, &o[0]);
    CHECK(o[0].radius == 1.0f, "gradient difference, two neighbours in turn: R %g, a quarter of 4 expected",
          (double)o[0].radius);
    ic_cache_destroy(c);

    ic_cache_params resolved;
    p = no_clamps(IC_WEIGHT_WARD, 0.5f);
    CHECK(ic_cache_params_resolve(&p, &resolved, &err) == IC_OK && resolved.gradient_difference_threshold == 0.1f,
          "gradient difference off: the threshold stays 0.1 (%g)", (double)resolved.gradient_difference_threshold);
    p = no_clamps(IC_WEIGHT_TABELLION, 1.0f);
    p.gradient_difference = IC_CACHE_ON;
    CHECK(ic_cache_params_resolve(&p, &resolved, &err) == IC_OK && resolved.gradient_difference_threshold == 0.1f,
          "Tabellion-Lamorlette's default accuracy gives the default threshold (%g)",
          (double)resolved.gradient_difference_threshold);
}

/* Neighbour clamping against its definition, run by brute force: a label-correcting pass that pops the
 * queued record of least (R, index), finds who is within reach now by scanning every record (squared
 * float distances against each squared influence radius, as the cache tests them), pulls, then pushes.
 * The cache finds its new records' neighbours in parallel beforehand and keeps those still within reach
 * when popped; its radii must be the brute force's bit for bit, on 1 and 3 threads, over two large batches
 * (the second lowers records of the first, which then search the octrees as the pass reaches them) and
 * then single records (inserted into the octrees one at a time). */
typedef struct brute_clamp {
    uint32_t count;
    const ic_vec3 *pos;
    const float *acc;
    const uint8_t *level;
    float *R;
    uint8_t *queued;
    uint32_t *reach; /* scratch: count entries */
} brute_clamp;

static void brute_neighbor_pass(brute_clamp *b, uint32_t first)
{
    for (uint32_t i = first; i < b->count; ++i)
        b->queued[i] = 1;
    for (;;) {
        uint32_t i = UINT32_MAX;
        for (uint32_t k = 0; k < b->count; ++k)
            if (b->queued[k] && (i == UINT32_MAX || b->R[k] < b->R[i]))
                i = k;
        if (i == UINT32_MAX)
            return;
        b->queued[i] = 0;
        /* Who is within reach when i is popped; then pull over them, then push. */
        uint32_t m = 0;
        float ri = b->acc[i] * b->R[i];
        for (uint32_t j = 0; j < b->count; ++j) {
            float dx = b->pos[i].x - b->pos[j].x, dy = b->pos[i].y - b->pos[j].y, dz = b->pos[i].z - b->pos[j].z;
            float d2 = dx * dx + dy * dy + dz * dz, rj = b->acc[j] * b->R[j];
            if (j != i && b->level[j] == b->level[i] && (d2 < ri * ri || d2 < rj * rj))
                b->reach[m++] = j;
        }
        for (uint32_t k = 0; k < m; ++k)
            b->R[i] = fminf(b->R[i], b->R[b->reach[k]] + v3_len(v3_sub(b->pos[i], b->pos[b->reach[k]])));
        for (uint32_t k = 0; k < m; ++k) {
            uint32_t j = b->reach[k];
            float bound = b->R[i] + v3_len(v3_sub(b->pos[i], b->pos[j]));
            if (bound < b->R[j]) {
                b->R[j] = bound;
                b->queued[j] = 1;
            }
        }
    }
}

/* Records [0, a) and [a, b) as two batches, then [b, n) one at a time; 0 on a failed insertion. */
static int insert_in_steps(ic_cache *c, const ic_record *recs, uint32_t a, uint32_t b, uint32_t n, ic_error *err)
{
    int ok = ic_cache_insert_batch(c, recs, a, NULL, err) == IC_OK &&
             ic_cache_insert_batch(c, recs + a, b - a, NULL, err) == IC_OK;
    for (uint32_t k = b; ok && k < n; ++k)
        ok = ic_cache_insert(c, &recs[k], NULL, err) == IC_OK;
    return ok;
}

static void test_neighbor_clamp_brute_force(void)
{
    const uint32_t n = 3000, batch1 = 2000, batch2 = 2800; /* then singles up to n */
    ic_record *recs = make_dense(n, 17);
    for (uint32_t i = 0; i < n; ++i)
        recs[i].bounce = (uint8_t)(i % 7 == 0); /* a second bounce level, which never clamps the first */
    ic_cache_params p = no_clamps(IC_WEIGHT_WARD, 0.3f);
    p.validity_clamp = IC_CACHE_ON;
    float *R = malloc(n * sizeof *R), *pre = malloc(n * sizeof *pre), *acc = malloc(n * sizeof *acc);
    ic_vec3 *pos = malloc(n * sizeof *pos);
    uint8_t *level = malloc(n), *queued = calloc(n, 1);
    ic_error err;
    /* The radii before step 4: the validity clamp reads positions only, so they are those of the same
     * batches inserted without neighbour clamping. */
    ic_cache *c = NULL;
    int ok = ic_cache_create(&p, &c, &err) == IC_OK && insert_in_steps(c, recs, batch1, batch2, n, &err);
    CHECK(ok, "inserting without neighbour clamping: %s", err.message);
    for (uint32_t i = 0; ok && i < n; ++i) {
        ic_record r;
        ok = ic_cache_get_record(c, i, &r) == IC_OK;
        pre[i] = r.radius;
        pos[i] = r.position;
        acc[i] = r.accuracy;
        level[i] = r.bounce;
    }
    ic_cache_destroy(c);
    uint32_t *reach = malloc(n * sizeof *reach);
    brute_clamp b = {batch1, pos, acc, level, R, queued, reach};
    memcpy(R, pre, n * sizeof *R);
    brute_neighbor_pass(&b, 0);
    float *after1 = malloc(batch1 * sizeof *after1);
    memcpy(after1, R, batch1 * sizeof *after1);
    b.count = batch2;
    brute_neighbor_pass(&b, batch1);
    for (uint32_t k = batch2; k < n; ++k) {
        b.count = k + 1;
        brute_neighbor_pass(&b, k);
    }
    uint32_t lowered = 0, old_lowered = 0;
    for (uint32_t i = 0; i < n; ++i) {
        lowered += R[i] < pre[i];
        old_lowered += i < batch1 && R[i] < after1[i];
    }
    CHECK(lowered > n / 10 && old_lowered > 20, "the test needs lowered radii, also of the first batch by later insertions: %u, %u",
          lowered, old_lowered);
    p.neighbor_clamp = IC_CACHE_ON;
    for (int t = 0; t < 2; ++t) {
        p.threads = t ? 3 : 1;
        ok = ic_cache_create(&p, &c, &err) == IC_OK && insert_in_steps(c, recs, batch1, batch2, n, &err);
        CHECK(ok, "inserting with neighbour clamping: %s", err.message);
        uint32_t bad = 0, worst = 0;
        float got = 0.0f;
        for (uint32_t i = 0; ok && i < n; ++i) {
            ic_record r;
            if (ic_cache_get_record(c, i, &r) != IC_OK)
                r.radius = -1.0f;
            if (r.radius != R[i] && bad++ == 0)
                worst = i, got = r.radius;
        }
        CHECK(bad == 0, "%d thread(s): %u radii differ from the brute-force pass (record %u: %g, want %g)",
              p.threads, bad, worst, (double)got, (double)R[worst]);
        ic_cache_destroy(c);
    }
    printf("  neighbor clamp against brute force: %u of %u radii lowered, %u of the first batch's by later insertions\n",
           lowered, n, old_lowered);
    free(R);
    free(pre);
    free(acc);
    free(pos);
    free(level);
    free(queued);
    free(reach);
    free(after1);
    free(recs);
}

/* Insertion (clamps, trees built on the threads) and the index it leaves answer alike at 1 and 3
 * threads: the same radii, octree shape and look-up bits, thawed and frozen. */
static void test_thread_independence(void)
{
    const uint32_t n = 20000, queries = 2000;
    ic_record *recs = make_dense(n, 13);
    ic_cache_params p = {0};
    p.gradient_difference = IC_CACHE_ON;
    float *radius[2];
    ic_cache_estimate *est[2];
    ic_cache_index_stats shape[2];
    for (int t = 0; t < 2; ++t) {
        p.threads = t ? 3 : 1;
        ic_cache *c;
        ic_error err;
        ic_cache_create(&p, &c, &err);
        ic_cache_insert_batch(c, recs, n / 2, NULL, &err);
        ic_cache_insert_batch(c, recs + n / 2, n / 2, NULL, &err);
        radius[t] = malloc(n * sizeof(float));
        est[t] = calloc(2 * queries, sizeof **est);
        for (uint32_t i = 0; i < n; ++i) {
            ic_record r;
            ic_cache_get_record(c, i, &r);
            radius[t][i] = r.radius;
        }
        /* Look-ups at record positions (where records overlap most), through the tree insertion left
         * and through a rebuilt, frozen index. */
        for (int frozen = 0; frozen < 2; ++frozen) {
            if (frozen)
                CHECK(ic_cache_rebuild_index(c, &err) == IC_OK && ic_cache_is_frozen(c), "rebuild: %s",
                      err.message);
            for (uint32_t q = 0; q < queries; ++q) {
                const ic_record *r = &recs[(q * 7919u) % n];
                ic_cache_lookup l = ic_cache_lookup_at(v3_add(r->position, v3(0.001f, -0.002f, 0.0f)), r->normal,
                                                       IC_ACCEPT_FINAL);
                ic_cache_query(c, &l, &est[t][frozen * queries + q]);
            }
        }
        ic_cache_get_index_stats(c, &shape[t]);
        ic_cache_destroy(c);
    }
    CHECK(memcmp(radius[0], radius[1], n * sizeof(float)) == 0, "batch insertion depends on the thread count");
    CHECK(shape[0].nodes == shape[1].nodes && shape[0].references == shape[1].references &&
              shape[0].frozen_leaves == shape[1].frozen_leaves && shape[0].nodes > 64,
          "the index depends on the thread count: %u / %u nodes", shape[0].nodes, shape[1].nodes);
    uint32_t differ = 0, found = 0;
    for (uint32_t q = 0; q < 2 * queries; ++q) {
        differ += memcmp(&est[0][q], &est[1][q], sizeof **est) != 0;
        found += est[0][q].contributor_count > 0;
    }
    CHECK(differ == 0 && found > queries, "%u of %u look-ups depend on the thread count (%u found records)", differ,
          2 * queries, found);
    for (int t = 0; t < 2; ++t) {
        free(radius[t]);
        free(est[t]);
    }
    free(recs);
}

/* The frozen layout's arrays are consistent: the descent's nodes reached from the root once each, every
 * leaf reached once and numbered where leaf_at says, the leaves' lists tiling `list` exactly (no unit
 * in two, none in none). A layout put together from parts at wrong offsets fails here even where the
 * look-ups asked happen to agree. */
static int frozen_consistent(const ic_frozen *f)
{
    if (!f->has_root || f->node_count == 0)
        return 0;
    uint32_t *stack = malloc((size_t)f->node_count * sizeof *stack), top = 0, nodes = 0, leaves = 0;
    unsigned char *seen = calloc(f->leaf_count ? f->leaf_count : 1, 1), *used = calloc(f->list_len + 1, 1);
    size_t units = 0;
    int ok = stack && seen && used;
    if (ok)
        stack[top++] = f->node[0];
    while (ok && top) {
        uint32_t v = stack[--top];
        ++nodes;
        if (v & IC_FROZEN_LEAF) {
            size_t at = v & ~IC_FROZEN_LEAF;
            const ic_frozen_leaf *l = (const ic_frozen_leaf *)(f->list + at);
            ok = at + sizeof *l / 8 <= f->list_len && l->id < f->leaf_count && !seen[l->id] &&
                 f->leaf_at[l->id] == at;
            if (ok) {
                size_t len = (sizeof *l + (l->count + 7u) / 8u * sizeof(ic_frozen_block)) / 8;
                seen[l->id] = 1;
                ++leaves;
                units += len;
                ok = at + len <= f->list_len;
                for (size_t u = at; ok && u < at + len; ++u)
                    ok = !used[u]++;
            }
        } else {
            ok = v > 0 && v + 8u <= f->node_count && top + 8u <= f->node_count;
            for (unsigned o = 0; ok && o < 8; ++o)
                stack[top++] = f->node[v + o];
        }
    }
    free(stack);
    free(seen);
    free(used);
    return ok && nodes == f->node_count && leaves == f->leaf_count && units == f->list_len;
}

/* The frozen layout of a cache of many tree levels, big enough to be built on threads, is the same
 * byte for byte on 1, 2, 3 and 8 threads (params.threads, read at each freeze), consistent, and answers
 * like the octree path (check_frozen_identical freezes on 3 threads). */
static void test_frozen_threads(void)
{
    const uint32_t n = 30000;
    ic_record *recs = make_records(n, 41);
    ic_cache_params p = clamp_config(IC_WEIGHT_WARD, 5);
    p.threads = 1;
    ic_cache *c = NULL;
    ic_error err;
    CHECK(ic_cache_create(&p, &c, &err) == IC_OK && ic_cache_insert_batch(c, recs, n, NULL, &err) == IC_OK &&
              ic_cache_rebuild_index(c, &err) == IC_OK && ic_cache_is_frozen(c),
          "cache: %s", err.message);
    ic_cache_index_stats s;
    ic_cache_get_index_stats(c, &s);
    CHECK(s.nodes >= 8000 && s.depth >= 6, "the tree is too small to be frozen on threads: %u nodes, depth %u",
          s.nodes, s.depth);
    printf("  frozen on threads: %u nodes, depth %u, %u leaves of %.2f entries\n", s.nodes, s.depth,
           s.frozen_leaves, s.frozen_list_entries);
    ic_frozen one = c->frozen; /* taken over: the next freeze builds anew */
    memset(&c->frozen, 0, sizeof c->frozen);
    CHECK(frozen_consistent(&one), "1 thread: the frozen layout's arrays are inconsistent");
    const int threads[3] = {2, 3, 8};
    for (int k = 0; k < 3; ++k) {
        c->params.threads = threads[k];
        CHECK(ic_cache_freeze(c, &err) == IC_OK, "freeze: %s", err.message);
        const ic_frozen *f = &c->frozen;
        CHECK(f->node_count == one.node_count && f->leaf_count == one.leaf_count &&
                  f->list_len == one.list_len && f->entry_count == one.entry_count &&
                  memcmp(f->node, one.node, one.node_count * sizeof *one.node) == 0 &&
                  memcmp(f->leaf_at, one.leaf_at, one.leaf_count * sizeof *one.leaf_at) == 0 &&
                  memcmp(f->list, one.list, one.list_len * sizeof *one.list) == 0,
              "the frozen layout on %d threads differs from the one on 1", threads[k]);
    }
    ic_frozen_free(&one);
    c->params.threads = 3;
    check_frozen_identical(c, 4000, 1, "frozen on 3 threads");
    CHECK(frozen_consistent(&c->frozen), "3 threads: the frozen layout's arrays are inconsistent");
    ic_cache_destroy(c);
    free(recs);
}

/* ---- k-nearest and radius queries -------------------------------------------------------------- */

static void test_point_queries(void)
{
    const uint32_t n = 100000, queries = 1000, K = 16;
    ic_record *recs = make_records(n, 3);
    /* Duplicated positions exercise ties (broken by index). */
    for (uint32_t i = 0; i < 200; ++i)
        recs[n - 1 - i].position = recs[i].position;
    ic_cache_params p = no_clamps(IC_WEIGHT_WARD, 0.2f);
    ic_cache *c = build_cache(&p, recs, n);
    uint32_t knn_bad = 0, rad_bad = 0, cap = 4096;
    uint32_t *got = malloc(cap * sizeof *got), *want = malloc(cap * sizeof *want);
    for (uint32_t q = 0; q < queries; ++q) {
        ic_rng r = ic_rng_make(9, q, 0, 0);
        ic_vec3 pq = q % 3 == 0 ? recs[ic_rng_below(&r, n)].position
                                : v3(20.0f * ic_rng_float(&r), 20.0f * ic_rng_float(&r), 20.0f * ic_rng_float(&r));
        uint32_t idx[16], bidx[16];
        float d2[16], bd2[16];
        uint32_t m = ic_cache_knn(c, pq, K, idx, d2), found = 0;
        for (uint32_t j = 0; j < n; ++j) {
            float dx = pq.x - recs[j].position.x, dy = pq.y - recs[j].position.y, dz = pq.z - recs[j].position.z;
            float d = dx * dx + dy * dy + dz * dz;
            if (found == K && !(d < bd2[K - 1] || (d == bd2[K - 1] && j < bidx[K - 1])))
                continue;
            uint32_t pos = found < K ? found++ : K - 1;
            while (pos > 0 && (d < bd2[pos - 1] || (d == bd2[pos - 1] && j < bidx[pos - 1]))) {
                bd2[pos] = bd2[pos - 1];
                bidx[pos] = bidx[pos - 1];
                --pos;
            }
            bd2[pos] = d;
            bidx[pos] = j;
        }
        knn_bad += m != K || memcmp(idx, bidx, sizeof idx) != 0 || memcmp(d2, bd2, sizeof d2) != 0;
        float radius = 0.05f + 0.5f * ic_rng_float(&r);
        uint32_t total = ic_cache_radius_query(c, pq, radius, got, cap), bn = 0;
        for (uint32_t j = 0; j < n; ++j) {
            float dx = pq.x - recs[j].position.x, dy = pq.y - recs[j].position.y, dz = pq.z - recs[j].position.z;
            if (dx * dx + dy * dy + dz * dz < radius * radius)
                want[bn++] = j;
        }
        qsort(got, total < cap ? total : cap, sizeof *got, cmp_u32);
        rad_bad += total != bn || memcmp(got, want, bn * sizeof *got) != 0;
    }
    CHECK(knn_bad == 0, "knn differs from brute force in %u of %u queries", knn_bad, queries);
    CHECK(rad_bad == 0, "radius query differs from brute force in %u of %u queries", rad_bad, queries);
    /* Capacity smaller than the result: total still reported. */
    uint32_t small[2];
    uint32_t total = ic_cache_radius_query(c, recs[0].position, 1.0f, small, 2);
    CHECK(total > 2, "radius query total %u", total);
    free(got);
    free(want);
    ic_cache_destroy(c);
    free(recs);
}

/* ---- cache file -------------------------------------------------------------------------------- */

static int read_file(const char *path, unsigned char **data, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    fseek(f, 0, SEEK_END);
    *size = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    *data = malloc(*size + 1);
    size_t got = fread(*data, 1, *size, f);
    fclose(f);
    return got == *size;
}

static void write_file(const char *path, const unsigned char *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    fwrite(data, 1, size, f);
    fclose(f);
}

static void put_f32_le(unsigned char *b, float f)
{
    uint32_t v;
    memcpy(&v, &f, 4);
    for (int k = 0; k < 4; ++k)
        b[k] = (unsigned char)(v >> (8 * k));
}

/* Re-signs a cache file's bytes: the FNV-1a 64 of everything before the last 8 bytes, little-endian, as
 * the loader computes it. */
static void resign(unsigned char *d, size_t size)
{
    uint64_t h = ic_fnv1a64(IC_FNV64_OFFSET, d, size - 8);
    for (int k = 0; k < 8; ++k)
        d[size - 8 + k] = (unsigned char)(h >> (8 * k));
}

static void expect_refusal(const char *path, const ic_cache_params *p, uint64_t hash, ic_result code, const char *what)
{
    ic_cache *c = (ic_cache *)1;
    ic_error err = {0};
    ic_result rc = ic_cache_load(path, p, hash, &c, &err);
    CHECK(rc == code && c == NULL, "%s: got %s, expected %s (%s)", what, ic_result_name(rc), ic_result_name(code),
          err.message);
    CHECK(strstr(err.message, path) != NULL && !strchr(err.message, '\n'), "%s: message \"%s\" does not name %s",
          what, err.message, path);
}

static int count_temporaries(const char *dir, const char *stem)
{
    DIR *d = opendir(dir);
    int n = 0;
    struct dirent *e;
    while (d && (e = readdir(d)))
        n += strncmp(e->d_name, stem, strlen(stem)) == 0 && strstr(e->d_name, ".tmp.") != NULL;
    if (d)
        closedir(d);
    return n;
}

static void test_file(void)
{
    const char *path = IC_TEST_TMP "/test_cache.icc", *path2 = IC_TEST_TMP "/test_cache2.icc",
               *bad = IC_TEST_TMP "/test_cache_bad.icc";
    const uint64_t hash = 0x1234abcd5678ef90ULL;
    const uint32_t n = 5000;
    ic_record *recs = make_records(n, 21);
    ic_cache_params p = {0};
    p.accuracy = 0.25f;
    p.gradient_difference = IC_CACHE_ON;
    ic_cache *c = build_cache(&p, recs, n);
    ic_cache_set_record_flags(c, 7, IC_RECORD_DISABLED);
    ic_cache_set_record_accuracy(c, 8, 0.1f);
    ic_error err;
    CHECK(ic_cache_save(c, path, hash, &err) == IC_OK, "save: %s", err.message);
    ic_cache *l = NULL;
    CHECK(ic_cache_load(path, &p, hash, &l, &err) == IC_OK, "load: %s", err.message);
    if (!l) {
        ic_cache_destroy(c);
        free(recs);
        return;
    }
    CHECK(ic_cache_count(l) == n, "loaded %u records", ic_cache_count(l));
    CHECK(ic_cache_is_frozen(l), "a loaded cache is not frozen");
    uint32_t differ = 0;
    for (uint32_t i = 0; i < n; ++i) {
        ic_record a, b;
        ic_cache_get_record(c, i, &a);
        ic_cache_get_record(l, i, &b);
        differ += memcmp(&a, &b, sizeof a) != 0;
    }
    CHECK(differ == 0, "%u records differ after a round trip", differ);
    /* The loaded cache answers look-ups identically and saves to the same bytes. */
    uint32_t qdiff = 0;
    for (uint32_t q = 0; q < 2000; ++q) {
        ic_cache_lookup lk = {0};
        make_query(c, 5, q, 1.0f, &lk.position, &lk.normal);
        ic_cache_estimate ea, eb;
        ic_cache_query(c, &lk, &ea);
        ic_cache_query_linear(l, &lk, &eb);
        qdiff += ea.contributor_count != eb.contributor_count ||
                 fabsf(ea.irradiance.x - eb.irradiance.x) > 1e-4f * (1.0f + eb.irradiance.x);
    }
    CHECK(qdiff == 0, "%u look-ups differ after a round trip", qdiff);
    CHECK(ic_cache_save(l, path2, hash, &err) == IC_OK, "save again: %s", err.message);
    unsigned char *d1 = NULL, *d2 = NULL;
    size_t s1 = 0, s2 = 0;
    CHECK(read_file(path, &d1, &s1) && read_file(path2, &d2, &s2), "read back");
    CHECK(s1 == s2 && memcmp(d1, d2, s1) == 0, "second save is not bit-identical (%zu vs %zu bytes)", s1, s2);
    /* Version 4: header, settings length (0), records, the payload section (total, per-record lengths, no
     * floats here), checksum. */
    CHECK(s1 == FILE_RECORDS_AT + (size_t)n * FILE_RECORD_BYTES + 8 + 4 * (size_t)n + 8, "file size %zu", s1);

    /* Truncated, corrupted, foreign files. */
    write_file(bad, d1, s1 - 10);
    expect_refusal(bad, &p, hash, IC_ERR_CORRUPT, "truncated records");
    write_file(bad, d1, 40);
    expect_refusal(bad, &p, hash, IC_ERR_CORRUPT, "truncated header");
    write_file(bad, d1, 0);
    expect_refusal(bad, &p, hash, IC_ERR_CORRUPT, "empty file");
    d1[s1 / 2] ^= 0x10;
    write_file(bad, d1, s1);
    expect_refusal(bad, &p, hash, IC_ERR_CORRUPT, "flipped byte in records");
    d1[s1 / 2] ^= 0x10;
    d1[20] ^= 0x01; /* inside the scene hash: the checksum catches it first */
    write_file(bad, d1, s1);
    expect_refusal(bad, &p, hash, IC_ERR_CORRUPT, "flipped byte in header");
    d1[20] ^= 0x01;
    /* What to do follows what is wrong: a damaged file is deleted and rebuilt; a file that is no cache (a
     * scene or an image given by mistake) or one of a newer format is not the loader's to condemn. */
    d1[0] = 'X';
    write_file(bad, d1, s1);
    expect_refusal(bad, &p, hash, IC_ERR_PARSE, "wrong magic");
    {
        ic_cache *x = NULL;
        ic_cache_load(bad, &p, hash, &x, &err);
        CHECK(!strstr(err.message, "delete") && strstr(err.message, "give the path of a cache file"),
              "a file that is no cache is not to be deleted: %s", err.message);
    }
    d1[0] = 'I';
    const unsigned char version = d1[8];
    d1[8] = 99;
    write_file(bad, d1, s1);
    expect_refusal(bad, &p, hash, IC_ERR_MISMATCH, "other version");
    {
        ic_cache *x = NULL;
        ic_cache_load(bad, &p, hash, &x, &err);
        CHECK(!strstr(err.message, "delete") && strstr(err.message, "newer"), "a newer format is kept: %s",
              err.message);
    }
    d1[8] = version;
    expect_refusal(path, &p, hash ^ 1, IC_ERR_MISMATCH, "other scene");
    /* A valid checksum over values the octree cannot hold (issue "Hardening", item 3): a finite but huge
     * position or radius is refused naming the record, not turned into infinite bounds and a NaN cell. */
    {
        const float huge[][2] = {{1e35f, 0.0f}, {-3e38f, 0.0f}, {0.0f, 3e38f}, {9e29f, 2e29f}};
        for (int k = 0; k < 4; ++k) {
            unsigned char *d = malloc(s1);
            memcpy(d, d1, s1);
            size_t rec = FILE_RECORDS_AT + 3 * FILE_RECORD_BYTES; /* record 3: x at +0, R at +12 */
            if (huge[k][0] != 0.0f)
                put_f32_le(d + rec, huge[k][0]);
            if (huge[k][1] != 0.0f)
                put_f32_le(d + rec + 12, huge[k][1]);
            resign(d, s1);
            write_file(bad, d, s1);
            char what[64];
            snprintf(what, sizeof what, "record 3 at x %g, R %g", (double)huge[k][0], (double)huge[k][1]);
            expect_refusal(bad, &p, hash, IC_ERR_CORRUPT, what);
            ic_cache *x = NULL;
            ic_cache_load(bad, &p, hash, &x, &err);
            CHECK(strstr(err.message, "record 3 ") != NULL, "%s: names the record: %s", what, err.message);
            free(d);
        }
        /* Far but representable: accepted. */
        unsigned char *d = malloc(s1);
        memcpy(d, d1, s1);
        put_f32_le(d + FILE_RECORDS_AT + 3 * FILE_RECORD_BYTES, 1e20f);
        resign(d, s1);
        write_file(bad, d, s1);
        ic_cache *x = NULL;
        CHECK(ic_cache_load(bad, &p, hash, &x, &err) == IC_OK, "a record at x = 1e20 loads: %s", err.message);
        ic_cache_destroy(x);
        free(d);
    }
    {
        ic_cache *x = NULL;
        ic_cache_load(path, &p, hash ^ 1, &x, &err);
        CHECK(strstr(err.message, "made for another scene") && strstr(err.message, "build the cache again") &&
                  strstr(err.message, "settings it was made with") && !strstr(err.message, "delete"),
              "scene message (a sound file made for other settings is kept): %s", err.message);
    }
    ic_cache_params other = p;
    other.accuracy = 0.3f;
    expect_refusal(path, &other, hash, IC_ERR_MISMATCH, "other accuracy");
    other = p;
    other.neighbor_clamp = IC_CACHE_OFF;
    expect_refusal(path, &other, hash, IC_ERR_MISMATCH, "other clamp switch");
    {
        /* Switches and the weight said by name, not by their enum's number. */
        ic_cache *x = NULL;
        ic_cache_load(path, &other, hash, &x, &err);
        CHECK(strstr(err.message, "neighbor_clamp on in the file, off now") && !strstr(err.message, "delete"),
              "clamp switch message: %s", err.message);
        other = p;
        other.weight = IC_WEIGHT_TABELLION;
        ic_cache_load(path, &other, hash, &x, &err);
        CHECK(strstr(err.message, "weight ward in the file, tabellion now") != NULL, "weight message: %s",
              err.message);
    }
    /* Look-up-only settings may change. */
    other = p;
    other.final_accuracy_scale = 1.5f;
    other.leaf_capacity = 5;
    ic_cache *x = NULL;
    CHECK(ic_cache_load(path, &other, hash, &x, &err) == IC_OK, "look-up settings refused: %s", err.message);
    ic_cache_destroy(x);
    expect_refusal(IC_TEST_TMP "/no_such_cache.icc", &p, hash, IC_ERR_IO, "missing file");
    /* Not a file, or too big (issue "Hardening", item 4): refused before reading; a pipe must not hang
     * the load (the alarm fails the test if it does), /dev/zero must not be read without end. */
    {
        const char *fifo = IC_TEST_TMP "/test_cache_fifo.icc", *zero = IC_TEST_TMP "/test_cache_zero.icc",
                   *dir = IC_TEST_TMP "/test_cache_isdir.icc", *big = IC_TEST_TMP "/test_cache_big.icc";
        unlink(fifo);
        unlink(zero);
        rmdir(dir);
        CHECK(mkfifo(fifo, 0644) == 0 && symlink("/dev/zero", zero) == 0 && mkdir(dir, 0755) == 0, "scratch files");
        FILE *fb = fopen(big, "wb"); /* sparse: 5 GiB on no disk */
        CHECK(fb && ftruncate(fileno(fb), (off_t)5 << 30) == 0, "sparse file");
        if (fb)
            fclose(fb);
        alarm(60);
        const struct { const char *path, *says; } cases[] = {
            {fifo, "is not a regular file"}, {zero, "is not a regular file"}, {"/dev/zero", "is not a regular file"},
            {dir, "is a folder"}, {big, "is 5368709120 bytes (5.0 GiB), more than the limit of 4294967296 bytes"}};
        for (int k = 0; k < 5; ++k) {
            expect_refusal(cases[k].path, &p, hash, IC_ERR_INVALID_ARG, cases[k].says);
            ic_cache *x = NULL;
            ic_cache_load(cases[k].path, &p, hash, &x, &err);
            CHECK(strstr(err.message, cases[k].says) != NULL, "%s: says '%s': %s", cases[k].path, cases[k].says,
                  err.message);
        }
        alarm(0);
        unlink(fifo);
        unlink(zero);
        rmdir(dir);
        remove(big);
        /* The limit is the caller's (--max-cache-bytes): a file one byte over it is refused naming both sizes
         * and the option; at the limit it loads. */
        ic_cache_params limited = p;
        limited.max_file_bytes = s1 - 1;
        expect_refusal(path, &limited, hash, IC_ERR_INVALID_ARG, "one byte over --max-cache-bytes");
        ic_cache *y = NULL;
        ic_cache_load(path, &limited, hash, &y, &err);
        char want[128];
        snprintf(want, sizeof want, "is %zu bytes, more than the limit of %zu bytes; raise the limit with "
                 "--max-cache-bytes", s1, s1 - 1);
        CHECK(strstr(err.message, want) != NULL, "the message names both sizes and the option: %s", err.message);
        limited.max_file_bytes = s1;
        CHECK(ic_cache_load(path, &limited, hash, &y, &err) == IC_OK && ic_cache_count(y) == (uint32_t)n,
              "a cache file at --max-cache-bytes loads: %s", err.message);
        ic_cache_destroy(y);
    }

    /* Failed writes leave nothing behind: a missing folder, and a path that is a folder. */
    CHECK(ic_cache_save(c, IC_TEST_TMP "/no_such_dir/x.icc", hash, &err) == IC_ERR_IO, "save into missing folder");
    const char *dir = IC_TEST_TMP "/test_cache_dir.icc";
    mkdir(dir, 0755);
    ic_result rc = ic_cache_save(c, dir, hash, &err);
    CHECK(rc == IC_ERR_IO && strstr(err.message, dir), "save onto a folder: %s (%s)", ic_result_name(rc), err.message);
    CHECK(count_temporaries(IC_TEST_TMP, "test_cache_dir.icc") == 0, "temporary file left after a failed save");
    rmdir(dir);

    free(d1);
    free(d2);
    remove(path);
    remove(path2);
    remove(bad);
    ic_cache_destroy(l);
    ic_cache_destroy(c);
    free(recs);
}

/* Records of three bounce levels, every fifth disabled: the frozen layout's bounce and flag filter (SSE2
 * and portable) answers like the octree path for queries of each level and of level 256, with both
 * weights. */
static void test_frozen_bounce_levels(void)
{
    const uint32_t n = 30000;
    ic_record *recs = make_records(n, 9);
    for (uint32_t i = 0; i < n; ++i)
        recs[i].bounce = (uint8_t)(i % 3);
    for (int wk = 0; wk < 2; ++wk) {
        ic_cache_params p = clamp_config(wk ? IC_WEIGHT_TABELLION : IC_WEIGHT_WARD, 5);
        ic_cache *c = build_cache(&p, recs, n);
        for (uint32_t i = 0; i < n; i += 5)
            ic_cache_set_record_flags(c, i, IC_RECORD_DISABLED);
        ic_error err;
        CHECK(ic_cache_rebuild_index(c, &err) == IC_OK && ic_cache_is_frozen(c), "rebuild: %s", err.message);
        check_frozen_identical(c, 4000, 4, wk ? "T-L, bounce levels, disabled records"
                                              : "Ward, bounce levels, disabled records");
        ic_cache_destroy(c);
    }
    free(recs);
}

/* A look-up with a fallback level answers as a look-up of its level, then of the fallback level where
 * the first found nothing: bit for bit on the octree (one descent for both), by linear scan, frozen
 * (each code path, with hints) and in batches; and the frozen answers agree with the octree's. Level 0
 * is sparse (a quarter of the records), so that both outcomes occur; every seventh record is disabled,
 * which the frozen lists leave out. */
static void ask_fallback(const ic_cache *c, const ic_cache_lookup *q, int linear, ic_cache_hint *hint, answer *a)
{
    static ic_cache_contribution scratch[ID_CONTRIB];
    ic_cache_lookup l = *q;
    l.contributions = a->con;
    l.contribution_capacity = ID_CONTRIB;
    l.fallback_contributions = scratch;
    memset(a->con, 0, sizeof a->con);
    a->hit = linear ? ic_cache_query_linear(c, &l, &a->e) : ic_cache_query_hinted(c, &l, hint, &a->e);
}

static void two_step(const ic_cache *c, const ic_cache_lookup *q, int linear, answer *a)
{
    ic_cache_lookup l = *q;
    l.fallback = 0;
    ask_fallback(c, &l, linear, NULL, a);
    if (!a->hit) {
        l.bounce = q->fallback - 1u;
        ask_fallback(c, &l, linear, NULL, a);
    }
}

static void test_fallback_level(void)
{
    const uint32_t n = 60000, queries = 3000;
    ic_record *recs = make_records(n, 17);
    for (uint32_t i = 0; i < n; ++i) { /* (i / 4: the plane a record lies on goes with i % 4) */
        uint32_t kind = (i / 4) % 4;
        recs[i].bounce = (uint8_t)(kind == 0 ? 0 : kind == 3 ? 2 : 126);
    }
    ic_cache_params p = clamp_config(IC_WEIGHT_WARD, 5);
    ic_cache *c = build_cache(&p, recs, n);
    for (uint32_t i = 0; i < n; i += 7)
        ic_cache_set_record_flags(c, i, IC_RECORD_DISABLED);
    ic_cache_thaw(c);
    ic_cache_lookup *q = calloc(queries, sizeof *q);
    answer *oct = malloc(queries * sizeof *oct), *got = malloc(sizeof *got), *want = malloc(sizeof *want);
    ic_cache_estimate *batch = malloc(queries * sizeof *batch);
    uint32_t first = 0, second = 0, none = 0, both = 0, differ_octree = 0, differ_linear = 0;
    for (uint32_t k = 0; k < queries; ++k) {
        make_query(c, 23, k, p.final_accuracy_scale, &q[k].position, &q[k].normal);
        q[k].acceptance = k % 2 ? IC_ACCEPT_FINAL : IC_ACCEPT_CONSTRUCTION;
        q[k].fallback = 1u + 126u;
        ask_fallback(c, &q[k], 0, NULL, &oct[k]);
        two_step(c, &q[k], 0, want);
        differ_octree += !same_answer(&oct[k], want);
        ask_fallback(c, &q[k], 1, NULL, got);
        two_step(c, &q[k], 1, want);
        /* (the linear scan sums in record order: the same contributors, in another order) */
        differ_linear += !same_answer(got, want) || got->hit != oct[k].hit ||
                         got->e.contributor_count != oct[k].e.contributor_count;
        ic_cache_lookup only = q[k];
        only.fallback = 0;
        ask_fallback(c, &only, 0, NULL, want);
        if (want->hit) {
            only.bounce = 126;
            ask_fallback(c, &only, 0, NULL, want);
            both += want->hit; /* where preferring the level matters */
        }
        if (!oct[k].hit)
            ++none;
        else if (oct[k].e.contributions_written && recs[oct[k].con[0].record].bounce == 0)
            ++first;
        else
            ++second;
    }
    CHECK(differ_octree == 0 && differ_linear == 0,
          "fallback look-ups: %u octree and %u linear answers differ from two look-ups", differ_octree, differ_linear);
    CHECK(first > queries / 20 && second > queries / 20 && both > queries / 50,
          "fallback look-ups: %u answered by the level (%u where the fallback level would have answered too), %u "
          "by the fallback, %u by none (each must occur)", first, both, second, none);
    ic_error err;
    CHECK(ic_cache_freeze(c, &err) == IC_OK && ic_cache_is_frozen(c), "freeze: %s", err.message);
    uint32_t differ_frozen = 0, differ_batch = 0;
    for (int path = IC_LOOKUP_PORTABLE; path <= IC_LOOKUP_AVX2; ++path) {
        if (!ic_cache_set_lookup_path(c, (ic_lookup_path)path))
            continue;
        ic_cache_hint hint = {0};
        for (uint32_t k = 0; k < queries; ++k) {
            ask_fallback(c, &q[k], 0, &hint, got);
            two_step(c, &q[k], 0, want);
            differ_frozen += !same_answer(got, want) || !octree_agrees(got, &oct[k]);
        }
        ic_cache_hint bh = {0};
        ic_cache_query_batch(c, q, queries, &bh, batch);
        for (uint32_t k = 0; k < queries; ++k) {
            two_step(c, &q[k], 0, want);
            differ_batch += (batch[k].contributor_count > 0) != want->hit ||
                            batch[k].contributor_count != want->e.contributor_count ||
                            memcmp(&batch[k].irradiance, &want->e.irradiance, sizeof batch[k].irradiance) != 0;
        }
    }
    ic_cache_set_lookup_path(c, IC_LOOKUP_BEST);
    CHECK(differ_frozen == 0 && differ_batch == 0, "fallback look-ups, frozen: %u answers and %u in batches differ",
          differ_frozen, differ_batch);
    free(q);
    free(oct);
    free(got);
    free(want);
    free(batch);
    ic_cache_destroy(c);
    free(recs);
}

/* Payloads (radiance records' coefficients): set and read back, replaced, kept through a save and a
 * load bit for bit, refused when corrupt; a version-1 file (no payload section) still loads; records of
 * the radiance kind (bounce IC_BOUNCE_RADIANCE) never answer an irradiance look-up and vice versa. */
static void test_payloads(void)
{
    const char *path = IC_TEST_TMP "/test_cache_payload.icc", *bad = IC_TEST_TMP "/test_cache_payload_bad.icc";
    const uint64_t hash = 77;
    const uint32_t n = 400;
    ic_record *recs = make_records(n, 5);
    for (uint32_t i = 0; i < n; i += 2)
        recs[i].bounce = (uint8_t)IC_BOUNCE_RADIANCE;
    ic_cache_params p = {0};
    ic_cache *c = build_cache(&p, recs, n);
    ic_error err;
    float buf[300];
    for (uint32_t i = 0; i < n; i += 2) {
        uint32_t len = 1 + i % 300;
        for (uint32_t k = 0; k < len; ++k)
            buf[k] = (float)i + 0.001f * (float)k;
        CHECK(ic_cache_set_payload(c, i, buf, len, &err) == IC_OK, "set payload %u: %s", i, err.message);
    }
    buf[0] = 42.0f;
    CHECK(ic_cache_set_payload(c, 0, buf, 1, &err) == IC_OK, "replace a payload by a shorter one");
    buf[0] = NAN;
    CHECK(ic_cache_set_payload(c, 2, buf, 1, &err) == IC_ERR_INVALID_ARG, "a NaN payload is refused");
    CHECK(ic_cache_set_payload(c, n, buf, 1, &err) == IC_ERR_INVALID_ARG, "a payload past the records is refused");
    uint32_t len = 7;
    CHECK(ic_cache_payload(c, 1, &len) == NULL && len == 0, "a record without payload");
    const float *got = ic_cache_payload(c, 0, &len);
    CHECK(got && len == 1 && got[0] == 42.0f, "replaced payload reads back");
    got = ic_cache_payload(c, 10, &len);
    CHECK(got && len == 11 && got[10] == 10.0f + 0.010f, "payload 10 reads back");
    /* Kinds: a look-up of each kind sees only records of that kind. */
    uint32_t wrong = 0;
    for (uint32_t i = 0; i < n; ++i) {
        ic_cache_contribution ct[64];
        ic_cache_lookup q = ic_cache_lookup_at(recs[i].position, recs[i].normal, IC_ACCEPT_FINAL);
        q.bounce = (i & 1) ? 0 : IC_BOUNCE_RADIANCE;
        q.contributions = ct;
        q.contribution_capacity = 64;
        ic_cache_estimate e;
        ic_cache_query(c, &q, &e);
        for (uint32_t k = 0; k < e.contributions_written; ++k)
            wrong += (ct[k].record & 1) != (i & 1);
    }
    CHECK(wrong == 0, "%u contributions of the other kind", wrong);
    CHECK(ic_cache_save(c, path, hash, &err) == IC_OK, "save: %s", err.message);
    ic_cache *l = NULL;
    CHECK(ic_cache_load(path, &p, hash, &l, &err) == IC_OK, "load: %s", err.message);
    uint32_t diff = 0;
    for (uint32_t i = 0; l && i < n; ++i) {
        uint32_t la, lb;
        const float *a = ic_cache_payload(c, i, &la), *b = ic_cache_payload(l, i, &lb);
        diff += la != lb || (la && memcmp(a, b, la * sizeof *a) != 0);
    }
    CHECK(l && diff == 0, "%u payloads differ after a round trip", diff);
    ic_cache_destroy(l);
    unsigned char *d = NULL;
    size_t size = 0;
    CHECK(read_file(path, &d, &size), "read back");
    /* Record 0's payload length raised by one: the lengths no longer add up. */
    size_t lengths = FILE_RECORDS_AT + (size_t)n * FILE_RECORD_BYTES + 8;
    d[lengths] += 1;
    resign(d, size);
    write_file(bad, d, size);
    expect_refusal(bad, &p, hash, IC_ERR_CORRUPT, "payload lengths that do not add up");
    d[lengths] -= 1;
    /* A NaN inside a payload, checksum valid. */
    size_t floats = lengths + 4 * (size_t)n;
    put_f32_le(d + floats, NAN);
    resign(d, size);
    write_file(bad, d, size);
    expect_refusal(bad, &p, hash, IC_ERR_CORRUPT, "a NaN in a payload");
    /* The same records as a version-1 file: no payload section, no ellipse (156 bytes a record). */
    size_t v1 = FILE_HEADER_BYTES + (size_t)n * 156 + 8;
    unsigned char *o = malloc(v1);
    memcpy(o, d, FILE_HEADER_BYTES);
    for (uint32_t i = 0; i < n; ++i)
        memcpy(o + FILE_HEADER_BYTES + (size_t)i * 156, d + FILE_RECORDS_AT + (size_t)i * FILE_RECORD_BYTES, 156);
    o[8] = 1;
    resign(o, v1);
    write_file(bad, o, v1);
    l = NULL;
    CHECK(ic_cache_load(bad, &p, hash, &l, &err) == IC_OK && ic_cache_count(l) == n, "a version-1 file loads: %s",
          err.message);
    CHECK(l && ic_cache_payload(l, 0, NULL) == NULL, "a version-1 file has no payloads");
    ic_cache_destroy(l);
    free(o);
    free(d);
    ic_cache_destroy(c);
    free(recs);
}

/* The message of loading path with settings (the caller's text) and hash; IC_OK leaves it empty. */
static ic_result load_says(const char *path, const ic_cache_params *p, uint64_t hash, const char *settings,
                           ic_error *err)
{
    ic_cache *x = NULL;
    memset(err, 0, sizeof *err);
    ic_result rc = ic_cache_load_with_settings(path, p, hash, settings, &x, err);
    ic_cache_destroy(x);
    return rc;
}

/* Loads the bytes from a buffer of exactly their size (so that a sanitizer sees any read past them): the
 * result, its message in err. */
static ic_result load_exact(const unsigned char *d, size_t size, const ic_cache_params *p, uint64_t hash,
                            const char *settings, ic_error *err)
{
    unsigned char *b = malloc(size ? size : 1);
    memcpy(b, d, size);
    ic_cache *x = NULL;
    memset(err, 0, sizeof *err);
    ic_result rc = ic_cache_load_memory_with_settings("exact.icc", b, size, p, hash, settings, &x, err);
    ic_cache_destroy(x);
    free(b);
    return rc;
}

/* Format version 4's settings text (cache.h: SETTINGS TEXT): a file refused for its hash names the first
 * setting that differs, with both values; a scene that differs is said as such; version-3 files (no text)
 * still load and are refused by their hashes alone; a damaged text is refused as a damaged file, its length
 * bounded by the file's. */
static void test_file_settings(void)
{
    const char *path = IC_TEST_TMP "/test_cache_settings.icc", *bad = IC_TEST_TMP "/test_cache_settings_bad.icc";
    const uint64_t hash_a = 0x1111, hash_b = 0x2222;
    const uint32_t n = 400;
    ic_record *recs = make_records(n, 9);
    ic_cache_params p = {0};
    ic_cache *c = build_cache(&p, recs, n);
    const char *a = "scene=0123456789abcdef\nscene file=scene.json\n--strategy=batch\n--rays=4096\n--bounces=2\n";
    ic_error err;
    CHECK(ic_cache_save_with_settings(c, path, hash_a, a, &err) == IC_OK, "save: %s", err.message);
    CHECK(load_says(path, &p, hash_a, a, &err) == IC_OK, "same hash, same text: %s", err.message);
    /* The text never refuses on its own: with the hash equal, another text loads. */
    CHECK(load_says(path, &p, hash_a, "--rays=1\n", &err) == IC_OK, "same hash, other text: %s", err.message);
    CHECK(load_says(path, &p, hash_a, NULL, &err) == IC_OK, "same hash, no text: %s", err.message);
    {
        ic_cache *x = NULL;
        CHECK(ic_cache_load(path, &p, hash_a, &x, &err) == IC_OK && ic_cache_count(x) == n, "ic_cache_load: %s",
              err.message);
        ic_cache_destroy(x);
    }

    /* One option differs: named with both values and what to do; the file is sound (not "delete"). */
    const struct {
        const char *run, *says;
    } cases[] = {
        {"scene=0123456789abcdef\nscene file=scene.json\n--strategy=batch\n--rays=2048\n--bounces=2\n",
         "made with --rays 4096, this run has --rays 2048; rerun with --rays 4096, or build the cache again "
         "instead of loading it"},
        /* The order of the lines is not compared, and the scene's name is never. */
        {"--bounces=2\n--rays=2048\nscene file=elsewhere/scene.json\n--strategy=batch\nscene=0123456789abcdef\n",
         "made with --rays 4096, this run has --rays 2048"},
        /* The file's keys in its order: the first that differs is named. */
        {"scene=0123456789abcdef\n--strategy=lazy\n--rays=2048\n--bounces=2\n",
         "made with --strategy batch, this run has --strategy lazy"},
        {"scene=0123456789abcdef\n--strategy=batch\n--bounces=2\n",
         "made with --rays 4096, which this run does not give; rerun with --rays 4096"},
        /* A flag (empty value) this run gives and the file's run did not. */
        {"scene=0123456789abcdef\n--strategy=batch\n--rays=4096\n--bounces=2\n--no-gradients=\n",
         "made without --no-gradients, this run has --no-gradients; rerun without --no-gradients"},
        /* A key that is no option is said as a fact. */
        {"scene=0123456789abcdef\n--strategy=batch\n--rays=4096\n--bounces=2\ncached emitters=2\n",
         "made with cached emitters: none, this run's: 2; use the settings it was made with"},
        /* The scene: first in the file, so said first, whatever else differs. */
        {"scene=fedcba9876543210\nscene file=scene.json\n--strategy=batch\n--rays=2048\n--bounces=2\n",
         "made for another scene (scene.json, or a file it names, changed since the cache was saved); render the "
         "scene as it was, or build the cache again instead of loading it"},
        {"scene=fedcba9876543210\nscene file=other.json\n--strategy=batch\n--rays=4096\n--bounces=2\n",
         "made for another scene (saved for scene.json, this run's is other.json); render the scene it was made "
         "for"},
        {"scene=fedcba9876543210\n--strategy=batch\n--rays=4096\n--bounces=2\n",
         "made for another scene (scene.json, or a file it names, changed since"},
        /* Texts that agree (the caller's hash holds more than its text), or no text: the hashes say it. */
        {a, "made for another scene or settings that change its records (hash 0000000000001111, here "
            "0000000000002222; the settings it keeps agree with this run's); use the scene and settings it was "
            "made with"},
        {"", "(hash 0000000000001111, here 0000000000002222; this run gives no settings to compare with the "
             "file's); use"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        ic_result rc = load_says(path, &p, hash_b, cases[k].run, &err);
        CHECK(rc == IC_ERR_MISMATCH && strstr(err.message, path) && strstr(err.message, cases[k].says) &&
                  !strchr(err.message, '\n') && !strstr(err.message, "delete"),
              "case %zu: got %s \"%s\", expected \"%s\"", k, ic_result_name(rc), err.message, cases[k].says);
    }
    CHECK(load_says(path, &p, hash_b, NULL, &err) == IC_ERR_MISMATCH && strstr(err.message, "hash 0000000000001111"),
          "no text: %s", err.message);
    /* A file saved without a text is refused by its hashes, saying it has no text to name the setting. */
    CHECK(ic_cache_save(c, bad, hash_a, &err) == IC_OK, "save without a text: %s", err.message);
    CHECK(load_says(bad, &p, hash_b, a, &err) == IC_ERR_MISMATCH && strstr(err.message, "keeps no settings"),
          "a file without a text: %s", err.message);
    /* Quoted keys and values are bounded: a message stays one line within its buffer, naming the file. */
    {
        char *big = malloc(3 * 600 + 64), *run = malloc(3 * 600 + 64);
        char v[601];
        memset(v, 'x', 600);
        v[600] = '\0';
        snprintf(big, 3 * 600 + 64, "--%s=%s\n", v, v);
        snprintf(run, 3 * 600 + 64, "--%s=%sy\n", v, v);
        CHECK(ic_cache_save_with_settings(c, bad, hash_a, big, &err) == IC_OK, "save a long text: %s", err.message);
        CHECK(load_says(bad, &p, hash_b, run, &err) == IC_ERR_MISMATCH && strstr(err.message, bad) &&
                  strstr(err.message, "made with --xxx") && strlen(err.message) < sizeof err.message - 1,
              "long key and value: %s", err.message);
        free(big);
        free(run);
    }

    /* The caller's text is checked as a file's: refused before anything is written or read. */
    const char *wrong[] = {"--rays=4096", "--rays\n", "=4096\n", "--rays=40\x01" "96\n", "--rays=\xff\xfe\n",
                           "--rays=\xc3\n"};
    for (size_t k = 0; k < sizeof wrong / sizeof wrong[0]; ++k) {
        remove(bad);
        CHECK(ic_cache_save_with_settings(c, bad, hash_a, wrong[k], &err) == IC_ERR_INVALID_ARG &&
                  strstr(err.message, "the settings text") && !test_file_exists(bad),
              "text %zu refused on save: %s", k, err.message);
        CHECK(load_says(path, &p, hash_a, wrong[k], &err) == IC_ERR_INVALID_ARG, "text %zu refused on load: %s", k,
              err.message);
    }
    {
        size_t len = IC_CACHE_MAX_SETTINGS_BYTES + 1;
        char *huge = malloc(len + 1);
        memset(huge, 'v', len);
        memcpy(huge, "k=", 2);
        huge[len - 1] = '\n';
        huge[len] = '\0';
        CHECK(ic_cache_save_with_settings(c, bad, hash_a, huge, &err) == IC_ERR_INVALID_ARG &&
                  strstr(err.message, "longer"), "a text over IC_CACHE_MAX_SETTINGS_BYTES refused: %s", err.message);
        huge[len - 2] = '\n';
        huge[len - 1] = '\0'; /* exactly the limit: saved and loaded */
        CHECK(ic_cache_save_with_settings(c, bad, hash_a, huge, &err) == IC_OK &&
                  load_says(bad, &p, hash_a, NULL, &err) == IC_OK, "a text at the limit: %s", err.message);
        free(huge);
    }

    /* The file's bytes: header, settings length, text, records, payload section, checksum. */
    unsigned char *d = NULL;
    size_t size = 0;
    CHECK(read_file(path, &d, &size), "read back");
    const size_t text_len = strlen(a);
    CHECK(size == FILE_RECORDS_AT + text_len + (size_t)n * FILE_RECORD_BYTES + 8 + 4 * (size_t)n + 8 &&
              d[8] == 4 && d[FILE_HEADER_BYTES] == text_len && memcmp(d + FILE_RECORDS_AT, a, text_len) == 0,
          "version-4 layout (%zu bytes)", size);

    /* Version 3: the same file without the settings length and text still loads, refused by hash alone. */
    size_t v3 = size - 4 - text_len;
    unsigned char *o = malloc(v3);
    memcpy(o, d, FILE_HEADER_BYTES);
    memcpy(o + FILE_HEADER_BYTES, d + FILE_RECORDS_AT + text_len, size - FILE_RECORDS_AT - text_len);
    o[8] = 3;
    resign(o, v3);
    write_file(bad, o, v3);
    {
        ic_cache *x = NULL, *y = NULL;
        CHECK(ic_cache_load_with_settings(bad, &p, hash_a, a, &x, &err) == IC_OK && ic_cache_count(x) == n,
              "a version-3 file loads: %s", err.message);
        CHECK(ic_cache_load(path, &p, hash_a, &y, &err) == IC_OK, "load: %s", err.message);
        uint32_t differ = 0;
        for (uint32_t i = 0; x && y && i < n; ++i) {
            ic_record ra, rb;
            ic_cache_get_record(x, i, &ra);
            ic_cache_get_record(y, i, &rb);
            differ += memcmp(&ra, &rb, sizeof ra) != 0;
        }
        CHECK(x && y && differ == 0, "%u records of the version-3 file differ from the version-4 file's", differ);
        ic_cache_destroy(x);
        ic_cache_destroy(y);
    }
    CHECK(load_says(bad, &p, hash_b, a, &err) == IC_ERR_MISMATCH && strstr(err.message, "hash 0000000000001111") &&
              strstr(err.message, "keeps no settings"), "a version-3 file refused by its hashes: %s", err.message);
    free(o);

    /* A damaged text, checksum valid: refused as a damaged file (delete and rebuild), never read past the
     * file (load_exact's buffer ends with it). */
    unsigned char *e = malloc(size);
    const struct {
        size_t at;      /* byte of the text changed (from its start) */
        unsigned char to;
        const char *says;
    } damage[] = {
        {text_len - 1, 'x', "does not end its last line"},
        {3, 0xff, "not well-formed UTF-8"},
        {3, 0xc3, "not well-formed UTF-8"}, /* a sequence cut by the next byte */
        {3, 0x00, "control character"},
        {5, '\n', "not key=value"},
        {0, '=', "empty key"},
    };
    for (size_t k = 0; k < sizeof damage / sizeof damage[0]; ++k) {
        memcpy(e, d, size);
        e[FILE_RECORDS_AT + damage[k].at] = damage[k].to;
        resign(e, size);
        ic_result rc = load_exact(e, size, &p, hash_a, a, &err);
        CHECK(rc == IC_ERR_CORRUPT && strstr(err.message, damage[k].says) && strstr(err.message, "delete it"),
              "damage %zu: %s \"%s\"", k, ic_result_name(rc), err.message);
    }
    /* Lengths: absurd, past the end, one byte off either way, above the limit in a file long enough. */
    const uint32_t lengths[] = {0xffffffffu, 0x80000000u, (uint32_t)size, (uint32_t)(size - FILE_RECORDS_AT - 7),
                                (uint32_t)text_len + 1, (uint32_t)text_len - 1, IC_CACHE_MAX_SETTINGS_BYTES + 1};
    for (size_t k = 0; k < sizeof lengths / sizeof lengths[0]; ++k) {
        memcpy(e, d, size);
        for (int b = 0; b < 4; ++b)
            e[FILE_HEADER_BYTES + b] = (unsigned char)(lengths[k] >> (8 * b));
        resign(e, size);
        ic_result rc = load_exact(e, size, &p, hash_a, a, &err);
        CHECK(rc == IC_ERR_CORRUPT && strstr(err.message, "delete it"), "settings length %u: %s \"%s\"", lengths[k],
              ic_result_name(rc), err.message);
    }
    /* Cut inside the text, and anywhere up to it: truncated, nothing read past the cut. */
    for (size_t cut = FILE_HEADER_BYTES; cut <= FILE_RECORDS_AT + text_len + 8; ++cut)
        CHECK(load_exact(d, cut, &p, hash_a, a, &err) == IC_ERR_CORRUPT, "cut at %zu: %s", cut, err.message);
    free(e);
    free(d);
    remove(path);
    remove(bad);
    ic_cache_destroy(c);
    free(recs);
}

/* Well-formed UTF-8 throughout (a message quotes keys and values cut to a length, never inside a character). */
static int is_utf8(const char *s)
{
    for (const unsigned char *p = (const unsigned char *)s; *p;) {
        size_t n = ic_utf8_sequence(p, SIZE_MAX);
        if (!n)
            return 0;
        p += n;
    }
    return 1;
}

/* The settings text's edges (cache.h: SETTINGS TEXT): a key given twice is refused (identical texts would
 * otherwise be said to differ), a text never differs from itself, long values are quoted with their cut
 * marked and the part that differs shown, a carriage return is named. */
static void test_file_settings_edges(void)
{
    const char *path = IC_TEST_TMP "/test_cache_settings_edges.icc";
    const uint64_t hash_a = 0x1111, hash_b = 0x2222;
    const uint32_t n = 8;
    ic_record *recs = make_records(n, 3);
    ic_cache_params p = {0};
    ic_cache *c = build_cache(&p, recs, n);
    ic_error err;

    /* A key twice: refused from the caller on save and on load, before anything is written. */
    const char *twice[] = {"--a=1\n--a=2\n", "--a=1\n--b=2\n--a=1\n", "scene=1\nscene=2\n"};
    for (size_t k = 0; k < sizeof twice / sizeof twice[0]; ++k) {
        remove(path);
        CHECK(ic_cache_save_with_settings(c, path, hash_a, twice[k], &err) == IC_ERR_INVALID_ARG &&
                  strstr(err.message, "twice") && !test_file_exists(path),
              "text %zu with a key twice refused on save: %s", k, err.message);
    }
    CHECK(ic_cache_save_with_settings(c, path, hash_a, "--a=1\n--b=2\n", &err) == IC_OK, "save: %s", err.message);
    CHECK(load_says(path, &p, hash_b, twice[0], &err) == IC_ERR_INVALID_ARG && strstr(err.message, "twice"),
          "a key twice refused on load: %s", err.message);
    /* ... and in a file (checksum valid): a damaged file. */
    {
        unsigned char *d = NULL;
        size_t size = 0;
        CHECK(read_file(path, &d, &size), "read back");
        CHECK(d && d[FILE_RECORDS_AT + 8] == 'b', "the second key where expected");
        if (d) {
            d[FILE_RECORDS_AT + 8] = 'a'; /* "--a=1\n--a=2\n" */
            resign(d, size);
            CHECK(load_exact(d, size, &p, hash_b, "--a=1\n", &err) == IC_ERR_CORRUPT &&
                      strstr(err.message, "twice") && strstr(err.message, "delete it"),
                  "a file with a key twice: %s", err.message);
        }
        free(d);
    }

    /* A text never differs from itself: refused for its hash, the message names no setting but says that
     * the texts agree (what differs is something they leave out). */
    const char *own[] = {"--a=1\n--b=2\n", "scene=00ff\nscene file=x.json\n--rays=8\n--flag=\n", "k=v=w\n"};
    for (size_t k = 0; k < sizeof own / sizeof own[0]; ++k) {
        CHECK(ic_cache_save_with_settings(c, path, hash_a, own[k], &err) == IC_OK, "save %zu: %s", k, err.message);
        ic_result rc = load_says(path, &p, hash_b, own[k], &err);
        CHECK(rc == IC_ERR_MISMATCH && strstr(err.message, "hash 0000000000001111, here 0000000000002222") &&
                  strstr(err.message, "the settings it keeps agree with this run's") &&
                  !strstr(err.message, "made with -"),
              "text %zu against itself: %s \"%s\"", k, ic_result_name(rc), err.message);
    }

    /* Long values: cut with the cut marked, at the part that differs, never inside a character. */
    {
        char dir[161], a[512], b[512];
        memset(dir, 'd', sizeof dir - 1);
        dir[sizeof dir - 1] = '\0';
        snprintf(a, sizeof a, "scene=1\nscene file=/%s/one.json\n", dir);
        snprintf(b, sizeof b, "scene=2\nscene file=/%s/two.json\n", dir);
        CHECK(ic_cache_save_with_settings(c, path, hash_a, a, &err) == IC_OK, "save: %s", err.message);
        ic_result rc = load_says(path, &p, hash_b, b, &err);
        CHECK(rc == IC_ERR_MISMATCH && strstr(err.message, "d/one.json, this run's is ...") &&
                  strstr(err.message, "d/two.json)") && strstr(err.message, "saved for ...") &&
                  !strchr(err.message, '\n') && strlen(err.message) < 400 + strlen(path),
              "two long scene names that differ at their ends: \"%s\"", err.message);
        /* One long name (the other run named none): its end, where the file's name is. */
        snprintf(b, sizeof b, "scene=2\n");
        rc = load_says(path, &p, hash_b, b, &err);
        CHECK(rc == IC_ERR_MISMATCH && strstr(err.message, "made for another scene (...") &&
                  strstr(err.message, "d/one.json, or a file it names"),
              "a long scene name alone: \"%s\"", err.message);
        /* Option values that differ past the quoted length, and in their middle. */
        const char *tails[][2] = {{"1", "2"}, {"1xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx",
                                              "2xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx"}};
        for (size_t k = 0; k < 2; ++k) {
            snprintf(a, sizeof a, "--opt=%s%s\n", dir, tails[k][0]);
            snprintf(b, sizeof b, "--opt=%s%s\n", dir, tails[k][1]);
            CHECK(ic_cache_save_with_settings(c, path, hash_a, a, &err) == IC_OK, "save: %s", err.message);
            rc = load_says(path, &p, hash_b, b, &err);
            char made[32], now[32];
            snprintf(made, sizeof made, "dddd%s", tails[k][0]);
            snprintf(now, sizeof now, "dddd%s", tails[k][1]);
            made[5] = now[5] = '\0'; /* "dddd1" and "dddd2": where the values part */
            CHECK(rc == IC_ERR_MISMATCH && strstr(err.message, "made with --opt ...") && strstr(err.message, made) &&
                      strstr(err.message, "this run has --opt ...") && strstr(err.message, now) &&
                      !strchr(err.message, '\n') && strlen(err.message) < 600 + strlen(path),
                  "long values %zu: \"%s\"", k, err.message);
        }
        /* Two-byte characters: cut between them, so the message stays UTF-8 (the values part inside the
         * last character, so the quote's start falls inside one; one value alone is quoted from its start,
         * its end falling inside one). */
        char u[2 * 150 + 1];
        for (int k = 0; k < 150; ++k)
            memcpy(u + 2 * k, "\xc3\xa9", 2);
        u[300] = '\0';
        snprintf(a, sizeof a, "--opt=%s1\n", u);
        snprintf(b, sizeof b, "--opt=%.298s\xc3\xa8" "2\n", u);
        CHECK(ic_cache_save_with_settings(c, path, hash_a, a, &err) == IC_OK, "save: %s", err.message);
        rc = load_says(path, &p, hash_b, b, &err);
        CHECK(rc == IC_ERR_MISMATCH && is_utf8(err.message) && strstr(err.message, "\xc3\xa9" "1, this run has") &&
                  strstr(err.message, "\xc3\xa8" "2; rerun with"),
              "long UTF-8 values that part inside a character: \"%s\"", err.message);
        snprintf(a, sizeof a, "--opt=x%s\n", u);
        CHECK(ic_cache_save_with_settings(c, path, hash_a, a, &err) == IC_OK, "save: %s", err.message);
        rc = load_says(path, &p, hash_b, "--other=1\n", &err);
        CHECK(rc == IC_ERR_MISMATCH && is_utf8(err.message) && strstr(err.message, "made with --opt x\xc3\xa9") &&
                  strstr(err.message, "..., which this run does not give"),
              "a long UTF-8 value alone: \"%s\"", err.message);
    }

    /* A carriage return (a text with CRLF line ends) is named as such. */
    CHECK(ic_cache_save_with_settings(c, path, hash_a, "--a=1\r\n", &err) == IC_ERR_INVALID_ARG &&
              strstr(err.message, "carriage return"), "CRLF: %s", err.message);
    remove(path);
    ic_cache_destroy(c);
    free(recs);
}

/* A freeze stays exact across the cache's life: insertions and record changes thaw it (look-ups go
 * through the octree, still equal to brute force), a rebuild re-freezes it, and a loaded cache is
 * frozen and answers like the one saved. */
static void test_freeze_lifecycle(void)
{
    const uint32_t n = 100000, first = 90000;
    ic_record *recs = make_records(n, 5);
    ic_cache_params p = clamp_config(IC_WEIGHT_WARD, 5);
    ic_cache *c = build_cache(&p, recs, first);
    ic_error err;
    CHECK(!ic_cache_is_frozen(c), "frozen without a rebuild");
    CHECK(ic_cache_rebuild_index(c, &err) == IC_OK && ic_cache_is_frozen(c), "rebuild did not freeze");
    check_lookup_equals_brute_force(c, 5000, "frozen");
    /* Incremental insertions after the freeze: single records and a batch. */
    for (uint32_t i = first; i < first + 100; ++i)
        CHECK(ic_cache_insert(c, &recs[i], NULL, &err) == IC_OK, "insert: %s", err.message);
    CHECK(!ic_cache_is_frozen(c), "an insertion left the cache frozen");
    CHECK(ic_cache_insert_batch(c, recs + first + 100, n - first - 100, NULL, &err) == IC_OK, "batch: %s",
          err.message);
    check_lookup_equals_brute_force(c, 5000, "inserted after a freeze");
    CHECK(ic_cache_rebuild_index(c, &err) == IC_OK && ic_cache_is_frozen(c), "rebuild did not re-freeze");
    check_lookup_equals_brute_force(c, 5000, "re-frozen");
    /* Record changes thaw; the next rebuild freezes again. */
    CHECK(ic_cache_set_record_flags(c, 3, 0) == IC_OK && ic_cache_is_frozen(c), "unchanged flags thawed");
    for (uint32_t i = 0; i < n; i += 7)
        ic_cache_set_record_flags(c, i, IC_RECORD_DISABLED);
    CHECK(!ic_cache_is_frozen(c), "set_record_flags left the cache frozen");
    CHECK(ic_cache_freeze(c, &err) == IC_OK, "freeze: %s", err.message);
    for (uint32_t i = 1; i < n; i += 5) {
        ic_record r;
        ic_cache_get_record(c, i, &r);
        ic_cache_set_record_accuracy(c, i, 0.5f * r.accuracy);
    }
    CHECK(!ic_cache_is_frozen(c), "set_record_accuracy left the cache frozen");
    check_lookup_equals_brute_force(c, 5000, "changed records, thawed");
    CHECK(ic_cache_rebuild_index(c, &err) == IC_OK && ic_cache_is_frozen(c), "rebuild did not re-freeze");
    check_lookup_equals_brute_force(c, 5000, "changed records, frozen");
    check_frozen_identical(c, 5000, 1, "changed records");
    /* freeze = off: rebuilds leave the cache thawed; an explicit freeze still works. */
    ic_cache_params off = p;
    off.freeze = IC_CACHE_OFF;
    ic_cache *o = build_cache(&off, recs, 2000);
    CHECK(ic_cache_rebuild_index(o, &err) == IC_OK && !ic_cache_is_frozen(o), "freeze = off froze");
    CHECK(ic_cache_freeze(o, &err) == IC_OK && ic_cache_is_frozen(o), "explicit freeze refused");
    ic_cache_thaw(o);
    CHECK(!ic_cache_is_frozen(o) && ic_cache_memory_bytes(o) > 0, "thaw");
    ic_cache_destroy(o);
    ic_cache_destroy(c);
    /* An empty cache freezes and answers nothing; a one-record cache (the root is a leaf) freezes too. */
    ic_cache *e = NULL;
    CHECK(ic_cache_create(NULL, &e, &err) == IC_OK && ic_cache_rebuild_index(e, &err) == IC_OK &&
          ic_cache_is_frozen(e), "empty cache did not freeze");
    ic_cache_lookup q = ic_cache_lookup_at(recs[0].position, recs[0].normal, IC_ACCEPT_CONSTRUCTION);
    ic_cache_estimate est;
    ic_cache_hint hint = {0};
    CHECK(!ic_cache_query_hinted(e, &q, &hint, &est) && hint.leaf == 0, "empty frozen cache answered");
    CHECK(ic_cache_insert(e, &recs[0], NULL, &err) == IC_OK && ic_cache_rebuild_index(e, &err) == IC_OK,
          "one record: %s", err.message);
    CHECK(ic_cache_query_hinted(e, &q, &hint, &est) && est.contributor_count == 1 && hint.leaf == 1,
          "one-record frozen cache: %u contributors, hint %u", est.contributor_count, hint.leaf);
    ic_cache_destroy(e);
    free(recs);
}

static void test_api_edges(void)
{
    ic_error err;
    ic_cache_params p = {0};
    p.accuracy = -1.0f;
    ic_cache *c = (ic_cache *)1;
    CHECK(ic_cache_create(&p, &c, &err) == IC_ERR_INVALID_ARG && c == NULL, "negative accuracy accepted");
    ic_cache_destroy(NULL);
    CHECK(ic_cache_create(NULL, &c, &err) == IC_OK, "default create");
    CHECK(ic_cache_get_params(c)->accuracy == IC_DEFAULT_ACCURACY_WARD && ic_cache_get_params(c)->validity_k == 6,
          "defaults: the renderer's (irrcache/defaults.h)");
    ic_cache_lookup q = ic_cache_lookup_at(v3(0, 0, 0), v3(0, 0, 1), IC_ACCEPT_CONSTRUCTION);
    ic_cache_estimate e;
    CHECK(!ic_cache_query(c, &q, &e) && e.contributor_count == 0, "empty cache answered");
    uint32_t idx[4];
    CHECK(ic_cache_knn(c, v3(0, 0, 0), 4, idx, NULL) == 0, "knn on an empty cache");
    /* All-or-nothing batches. */
    ic_record r[3] = {plane_record(v3(0, 0, 0), 1.0f), plane_record(v3(1, 0, 0), 0.0f), plane_record(v3(2, 0, 0), 1.0f)};
    CHECK(ic_cache_insert_batch(c, r, 3, NULL, &err) == IC_ERR_INVALID_ARG && ic_cache_count(c) == 0,
          "invalid batch partly inserted");
    r[1].harmonic_mean_dist = 1.0f;
    r[1].irradiance.x = NAN;
    CHECK(ic_cache_insert_batch(c, r, 3, NULL, &err) == IC_ERR_INVALID_ARG, "NaN accepted");
    r[1].irradiance.x = 1.0f;
    r[1].harmonic_mean_dist = INFINITY;
    CHECK(ic_cache_insert_batch(c, r, 3, NULL, &err) == IC_ERR_INVALID_ARG, "infinite R accepted without max_radius");
    r[1].harmonic_mean_dist = 1.0f;
    CHECK(ic_cache_insert_batch(c, r, 3, NULL, &err) == IC_OK && ic_cache_count(c) == 3, "valid batch");
    CHECK(ic_cache_set_record_accuracy(c, 0, 0.5f) == IC_ERR_INVALID_ARG, "raising a_i accepted");
    CHECK(ic_cache_set_record_accuracy(c, 0, 0.1f) == IC_OK, "lowering a_i refused");
    ic_record o;
    ic_cache_get_record(c, 0, &o);
    CHECK(o.accuracy == 0.1f && o.change_count == 1, "a_i %g, changes %u", (double)o.accuracy, o.change_count);
    CHECK(ic_cache_get_record(c, 3, &o) == IC_ERR_INVALID_ARG, "out-of-range record");
    printf("  bytes per record: %zu; memory for 3 records: %zu\n", ic_cache_bytes_per_record(),
           ic_cache_memory_bytes(c));
    ic_cache_destroy(c);
}

/* What an embedding program may hand the cache at its edges: a record whose rays all missed (harmonic-mean
 * distance +inf, gather.h) under max_radius saves and loads; a NULL record is an error, not an empty
 * insertion; a look-up at a non-finite point or normal finds nothing on every path (a NaN normal passed
 * every rejection test and answered "covered" with E = 0); a few bytes that are no cache file are
 * IC_ERR_PARSE, not a truncated cache to delete; NULL buffers and handles where a count or nothing is
 * the answer. */
static void test_embedder_edges(void)
{
    const char *path = IC_TEST_TMP "/test_cache_no_hit.icc";
    ic_error err;
    ic_cache_params p = {0};
    p.max_radius = 2.0f;
    ic_cache *c = NULL;
    CHECK(ic_cache_create(&p, &c, &err) == IC_OK, "create: %s", err.message);
    ic_record r[3] = {plane_record(v3(0, 0, 0), INFINITY), plane_record(v3(0.1f, 0, 0), 1.0f),
                      plane_record(v3(0, 0.1f, 0), 1.0f)};
    uint32_t first = 99;
    CHECK(ic_cache_insert_batch(c, r, 3, &first, &err) == IC_OK && first == 0, "a sky-only record: %s", err.message);
    CHECK(ic_cache_insert(c, NULL, &first, &err) == IC_ERR_INVALID_ARG && ic_cache_count(c) == 3,
          "a NULL record inserted (%u records)", ic_cache_count(c));
    CHECK(ic_cache_save(c, path, 5, &err) == IC_OK, "save: %s", err.message);
    ic_cache *l = NULL;
    CHECK(ic_cache_load(path, &p, 5, &l, &err) == IC_OK, "a saved sky-only record does not load: %s", err.message);
    ic_record a, b;
    if (l && ic_cache_get_record(c, 0, &a) == IC_OK && ic_cache_get_record(l, 0, &b) == IC_OK)
        CHECK(b.harmonic_mean_dist == INFINITY && b.radius == a.radius && a.radius <= p.max_radius,
              "loaded harmonic-mean distance %g, radius %g (saved %g)", (double)b.harmonic_mean_dist,
              (double)b.radius, (double)a.radius);
    ic_cache_destroy(l);
    remove(path);

    /* Non-finite look-ups: none covered, the estimate zero, thawed and frozen, single and batched. */
    const float nan = NAN, inf = INFINITY;
    ic_cache_lookup bad[4] = {ic_cache_lookup_at(v3(0, 0, 0), v3(nan, nan, nan), IC_ACCEPT_CONSTRUCTION),
                              ic_cache_lookup_at(v3(0, 0, 0), v3(0, 0, inf), IC_ACCEPT_FINAL),
                              ic_cache_lookup_at(v3(nan, 0, 0), v3(0, 0, 1), IC_ACCEPT_CONSTRUCTION),
                              ic_cache_lookup_at(v3(0, 0, 0), v3(nan, 0, 1), IC_ACCEPT_FINAL)};
    ic_cache_lookup good = ic_cache_lookup_at(v3(0, 0, 0), v3(0, 0, 1), IC_ACCEPT_CONSTRUCTION);
    for (int frozen = 0; frozen < 2; ++frozen) {
        if (frozen)
            CHECK(ic_cache_rebuild_index(c, &err) == IC_OK && ic_cache_is_frozen(c), "freeze: %s", err.message);
        ic_cache_estimate e, eb[4];
        CHECK(ic_cache_query(c, &good, &e) == 1 && e.irradiance.x > 0.0f, "a finite look-up (frozen %d)", frozen);
        for (int k = 0; k < 4; ++k) {
            memset(&e, 0x55, sizeof e);
            int covered = ic_cache_query(c, &bad[k], &e);
            CHECK(!covered && e.contributor_count == 0 && e.weight_sum == 0.0f,
                  "non-finite look-up %d (frozen %d) covered by %u records, E = %g", k, frozen, e.contributor_count,
                  (double)e.irradiance.x);
            CHECK(!ic_cache_query_linear(c, &bad[k], &e) && e.contributor_count == 0, "linear look-up %d", k);
            float w = 1.0f;
            CHECK(!ic_cache_record_weight(c, 0, bad[k].position, bad[k].normal, bad[k].acceptance, &w) && w == 0.0f,
                  "record weight %g at non-finite look-up %d", (double)w, k);
        }
        ic_cache_hint hint = {0};
        CHECK(ic_cache_query_batch(c, bad, 4, &hint, eb) == 0 && eb[0].contributor_count == 0 &&
              eb[1].contributor_count == 0 && eb[2].contributor_count == 0 && eb[3].contributor_count == 0,
              "a batch of non-finite look-ups (frozen %d)",
              frozen);
    }
    uint32_t idx[4];
    float d2[4];
    CHECK(ic_cache_knn(c, v3(nan, 0, 0), 4, idx, d2) == 0, "nearest records to a NaN point");
    CHECK(ic_cache_radius_query(c, v3(0, 0, 0), 1.0f, NULL, 4) == 3, "radius query counting with no buffer");

    /* A few bytes of something else: not a cache file (IC_ERR_PARSE), whatever its length. */
    ic_cache *m = NULL;
    CHECK(ic_cache_load_memory("notes.txt", "hi\n", 3, NULL, 0, &m, &err) == IC_ERR_PARSE && !m,
          "3 bytes of text: %s (%s)", ic_result_name(err.code), err.message);
    CHECK(ic_cache_load_memory("cut.icc", "IRRC", 4, NULL, 0, &m, &err) == IC_ERR_CORRUPT,
          "a cut-off cache file: %s", ic_result_name(err.code));

    CHECK(ic_cache_get_params(NULL) == NULL && ic_cache_memory_bytes(NULL) == 0, "NULL cache getters");
    ic_cache_params many = {0};
    many.threads = IC_MAX_THREADS + 1;
    CHECK(ic_cache_create(&many, &m, &err) == IC_ERR_INVALID_ARG && !m, "threads above IC_MAX_THREADS");
    ic_cache_get_index_stats(c, NULL);
    ic_cache_destroy(c);
}

#define RUN(f) do { double t0 = now(); f(); printf("%-28s %.2f s\n", #f, now() - t0); fflush(stdout); } while (0)

/* Hundreds of records overlapping one spot: look-ups with far more contributors than one block of eight
 * or the caller's contribution buffer holds still equal the octree path and brute force, with both
 * weights. */
static void test_crowded_lookups(void)
{
    const uint32_t n = 400;
    ic_record *recs = make_records(n, 17);
    for (uint32_t i = 0; i < n; ++i) {
        ic_rng r = ic_rng_make(23, i, 0, 0);
        recs[i].position = v3(10.0f + ic_rng_float(&r) - 0.5f, 10.0f + ic_rng_float(&r) - 0.5f, 1.0f);
        recs[i].normal = v3(0, 0, 1);
        recs[i].tangent = v3(1, 0, 0);
        recs[i].harmonic_mean_dist = 4.0f + ic_rng_float(&r);
        for (int ch = 0; ch < 3; ++ch) {
            recs[i].grad_trans[ch] = random_in_plane(&r, recs[i].normal, 0.05f);
            recs[i].grad_rot[ch] = random_in_plane(&r, recs[i].normal, 0.05f);
        }
    }
    for (int wk = 0; wk < 2; ++wk) {
        ic_cache_params p = clamp_config(wk ? IC_WEIGHT_TABELLION : IC_WEIGHT_WARD, 0);
        ic_cache *c = build_cache(&p, recs, n);
        ic_error err;
        CHECK(ic_cache_rebuild_index(c, &err) == IC_OK && ic_cache_is_frozen(c), "rebuild: %s", err.message);
        ic_cache_lookup q = ic_cache_lookup_at(v3(10.0f, 10.0f, 1.0f), v3(0, 0, 1), IC_ACCEPT_FINAL);
        ic_cache_estimate e;
        ic_cache_query(c, &q, &e);
        CHECK(e.contributor_count > 300, "%s: only %u contributors at the crowded spot", wk ? "T-L" : "Ward",
              e.contributor_count);
        check_frozen_identical(c, 300, 1, wk ? "T-L, crowded" : "Ward, crowded");
        check_lookup_equals_brute_force(c, 2000, wk ? "T-L, crowded" : "Ward, crowded");
        ic_cache_destroy(c);
    }
    free(recs);
}

/* Records far from the origin with radii of a few ulps of their coordinates or less: a sphere that
 * reaches across a split plane has a reference on the other side, so the octree (grown by insertion
 * and built at once) and the frozen layout find exactly the contributors a linear scan finds at
 * points on the rims of the records' influence, where the split planes cut them. */
static uint32_t far_mismatches(const ic_cache *c, const ic_record *recs, uint32_t n, uint32_t queries)
{
    ic_cache_contribution *a = malloc(MAX_CONTRIB * sizeof *a), *b = malloc(MAX_CONTRIB * sizeof *b);
    uint32_t bad = 0;
    for (uint32_t k = 0; k < queries; ++k) {
        ic_rng r = ic_rng_make(31, k, 0, 0);
        const ic_record *rec = &recs[ic_rng_below(&r, n)];
        float phi = 2.0f * IC_PI * ic_rng_float(&r), d = IC_DEFAULT_ACCURACY_WARD * rec->harmonic_mean_dist *
                                                           (0.99f + 0.02f * ic_rng_float(&r));
        ic_cache_lookup q = ic_cache_lookup_at(
            v3(rec->position.x + d * cosf(phi), rec->position.y + d * sinf(phi), rec->position.z), v3(0, 0, 1),
            IC_ACCEPT_CONSTRUCTION);
        q.contribution_capacity = MAX_CONTRIB;
        ic_cache_estimate ea, eb;
        q.contributions = a;
        ic_cache_query(c, &q, &ea);
        q.contributions = b;
        ic_cache_query_linear(c, &q, &eb);
        int differ = ea.contributor_count != eb.contributor_count;
        for (uint32_t j = 0; !differ && j < ea.contributions_written; ++j) {
            uint32_t found = 0;
            for (uint32_t m = 0; m < eb.contributions_written; ++m)
                found |= a[j].record == b[m].record;
            differ = !found;
        }
        bad += (uint32_t)differ;
    }
    free(a);
    free(b);
    return bad;
}

static void test_far_from_origin(void)
{
    const uint32_t n = 1500, queries = IC_TEST_WORK(20000);
    const float offset = 1e4f, scales[2] = {0.005f, 0.05f}; /* ulp(1e4) ≈ 0.001 */
    ic_record *recs = malloc(n * sizeof *recs);
    for (int s = 0; s < 2; ++s) {
        for (uint32_t i = 0; i < n; ++i) {
            ic_rng r = ic_rng_make(29, i, (uint64_t)s, 0);
            recs[i] = plane_record(v3(offset + 4.0f * ic_rng_float(&r), offset + 4.0f * ic_rng_float(&r), offset),
                                   scales[s] * (0.2f + ic_rng_float(&r)));
        }
        ic_cache_params p = no_clamps(IC_WEIGHT_WARD, IC_DEFAULT_ACCURACY_WARD);
        ic_cache *c = build_cache(&p, recs, n);
        ic_error err;
        for (int built = 0; built < 2; ++built) {
            if (built)
                CHECK(ic_cache_rebuild_index(c, &err) == IC_OK, "rebuild: %s", err.message);
            ic_cache_thaw(c);
            uint32_t octree_bad = far_mismatches(c, recs, n, queries);
            CHECK(ic_cache_freeze(c, &err) == IC_OK, "freeze: %s", err.message);
            uint32_t frozen_bad = far_mismatches(c, recs, n, queries);
            CHECK(octree_bad == 0 && frozen_bad == 0,
                  "R ~ %g at %g, tree %s: %u octree and %u frozen look-ups of %u differ from the linear scan",
                  (double)scales[s], (double)offset, built ? "built" : "inserted", octree_bad, frozen_bad, queries);
        }
        ic_cache_destroy(c);
    }
    free(recs);
}

/* Insertion refuses what loading refuses: a record whose sphere (centre ± R_i plus a_i·R_i·tree_scale
 * with the margin) reaches 1e30 on an axis. Below that a record inserts, saves and loads; and an octree
 * asked to build over bounds beyond float refuses instead of growing without end. */
static void test_coordinate_range(void)
{
    ic_error err;
    ic_cache_params p = no_clamps(IC_WEIGHT_WARD, 0.15f);
    ic_cache *c = NULL;
    CHECK(ic_cache_create(&p, &c, &err) == IC_OK, "create: %s", err.message);
    ic_record near = plane_record(v3(1.0f, 2.0f, 3.0f), 1.0f);
    CHECK(ic_cache_insert(c, &near, NULL, &err) == IC_OK, "a record near the origin: %s", err.message);
    ic_record far[3] = {plane_record(v3(1e31f, 0, 0), 1.0f), plane_record(v3(0, -9e29f, 0), 1e29f),
                        plane_record(v3(0, 0, 3e38f), 1.0f)};
    int refused = 1;
    for (int k = 0; k < 3; ++k) {
        ic_result rc = ic_cache_insert(c, &far[k], NULL, &err);
        CHECK(rc == IC_ERR_INVALID_ARG && ic_cache_count(c) == 1 && strstr(err.message, "record 0"),
              "record %d beyond 1e30 inserted (%s): %s", k, ic_result_name(rc), rc ? err.message : "");
        refused = refused && rc == IC_ERR_INVALID_ARG;
        if (!refused)
            break; /* the others would exhaust memory (octree bounds beyond float) */
    }
    /* Just inside: |y| + R + a·R·margin = 9e29 + 1e28 + 1.5e27 < 1e30. */
    ic_record inside = plane_record(v3(0, -9e29f, 0), 1e28f);
    CHECK(ic_cache_insert(c, &inside, NULL, &err) == IC_OK, "a record inside the range: %s", err.message);
    const char *path = IC_TEST_TMP "/test_cache_range.icc";
    CHECK(ic_cache_save(c, path, 5, &err) == IC_OK, "save: %s", err.message);
    ic_cache *l = NULL;
    CHECK(ic_cache_load(path, &p, 5, &l, &err) == IC_OK && ic_cache_count(l) == ic_cache_count(c),
          "what inserted does not load: %s", err.message);
    ic_cache_destroy(l);
    ic_cache_destroy(c);
    remove(path);

    /* The octree's own check, on a shallow tree (bounded memory even without it). */
    ic_float4 sphere[2] = {{-3e38f, 0, 0, 1.0f}, {3e38f, 0, 0, 1.0f}}, normal[2] = {{0, 0, 1, 1.0f}, {0, 0, 1, 1.0f}};
    ic_octree_items items = {sphere, normal, 1.0f};
    ic_octree t;
    ic_octree_init(&t, 1, 4);
    t.threads = 1;
    CHECK(ic_octree_build(&t, &items, 2) == IC_ERR_INVALID_ARG && !t.has_root,
          "an octree over bounds beyond float built");
    ic_octree_free(&t);
}

/* A needle-thin ellipse (ρ far below 1e-19.5, where 1/ρ² overflows float) is stored with the floor
 * ratio: it still contributes along its major axis and not off it, and its file loads. */
static void test_needle_ellipse(void)
{
    ic_error err;
    const float ratios[3] = {1e-20f, 1e-38f, 1e-44f}; /* the last a subnormal float */
    for (int k = 0; k < 3; ++k) {
        ic_cache_params p = no_clamps(IC_WEIGHT_WARD, 0.5f);
        ic_cache *c = NULL;
        CHECK(ic_cache_create(&p, &c, &err) == IC_OK, "create: %s", err.message);
        ic_record r = plane_record(v3(0, 0, 0), 1.0f);
        r.ellipse_axis = v3(1, 0, 0);
        r.ellipse_ratio = ratios[k];
        CHECK(ic_cache_insert(c, &r, NULL, &err) == IC_OK, "insert: %s", err.message);
        ic_record got;
        ic_cache_get_record(c, 0, &got);
        CHECK(got.ellipse_ratio == IC_CACHE_MIN_ELLIPSE_RATIO, "ratio %g stored as %g", (double)ratios[k],
              (double)got.ellipse_ratio);
        /* Along the major axis (y) the extent is a·R = 0.5; across it a·ρ·R = 5e-7. */
        const ic_vec3 at[3] = {v3(0, 0, 0), v3(0, 0.4f, 0), v3(1e-3f, 0, 0)};
        const uint32_t want[3] = {1, 1, 0};
        for (int j = 0; j < 3; ++j) {
            ic_cache_lookup q = ic_cache_lookup_at(at[j], v3(0, 0, 1), IC_ACCEPT_CONSTRUCTION);
            ic_cache_estimate e;
            ic_cache_query_linear(c, &q, &e);
            CHECK(e.contributor_count == want[j], "ratio %g: %u contributors at (%g, %g), want %u",
                  (double)ratios[k], e.contributor_count, (double)at[j].x, (double)at[j].y, want[j]);
        }
        const char *path = IC_TEST_TMP "/test_cache_needle.icc";
        CHECK(ic_cache_save(c, path, 3, &err) == IC_OK, "save: %s", err.message);
        ic_cache *l = NULL;
        CHECK(ic_cache_load(path, &p, 3, &l, &err) == IC_OK, "ratio %g: the saved cache does not load: %s",
              (double)ratios[k], err.message);
        ic_cache_destroy(l);
        ic_cache_destroy(c);
        remove(path);
    }
}

/* The index statistics agree with the tree's shape: an empty cache has none; 8 children per split;
 * every record stored somewhere; a frozen list never longer than its leaf's path; thawed, no lists. */
static void test_index_stats(void)
{
    ic_cache_index_stats s;
    ic_cache *empty = NULL;
    ic_error err;
    CHECK(ic_cache_create(NULL, &empty, &err) == IC_OK, "create: %s", err.message);
    ic_cache_get_index_stats(empty, &s);
    CHECK(s.nodes == 0 && s.leaves == 0 && s.references == 0 && s.frozen_leaves == 0, "empty cache: no index");
    ic_cache_destroy(empty);
    const uint32_t n = 20000;
    ic_record *recs = make_records(n, 31);
    for (int validity = 0; validity < 2; ++validity) {
        ic_cache_params p = clamp_config(IC_WEIGHT_WARD, validity ? 3 : 0);
        ic_cache *c = build_cache(&p, recs, n);
        CHECK(ic_cache_rebuild_index(c, &err) == IC_OK && ic_cache_is_frozen(c), "rebuild: %s", err.message);
        ic_cache_get_index_stats(c, &s);
        CHECK(s.nodes >= 1 && (s.nodes - 1) % 8 == 0 && s.leaves == 1 + 7 * ((s.nodes - 1) / 8),
              "octree shape: %u nodes, %u leaves", s.nodes, s.leaves);
        CHECK(s.references >= n && fabs(s.references_per_record - (double)s.references / n) < 1e-9,
              "every record referenced: %llu references for %u records", (unsigned long long)s.references, n);
        CHECK(s.leaf_references <= s.max_leaf_references && s.path_references <= s.max_path_references &&
                  s.leaf_references <= s.path_references && s.depth <= ic_cache_get_params(c)->max_depth,
              "means within maxima: leaf %.2f ≤ %u, path %.2f ≤ %u, depth %u", s.leaf_references,
              s.max_leaf_references, s.path_references, s.max_path_references, s.depth);
        CHECK(s.frozen_leaves == s.leaves && s.frozen_list_entries > 0.0 && s.frozen_list_entries <= s.path_references &&
                  s.max_frozen_list_entries <= s.max_path_references,
              "frozen lists: %u leaves of %.2f entries (max %u) against paths of %.2f (max %u)", s.frozen_leaves,
              s.frozen_list_entries, s.max_frozen_list_entries, s.path_references, s.max_path_references);
        /* A look-up through the octree tests exactly its leaf's path: the mean over points spread like the
         * records lies within the per-leaf range. */
        ic_cache_thaw(c);
        double tested = 0.0;
        uint32_t queries = 2000, max_tested = 0;
        for (uint32_t k = 0; k < queries; ++k) {
            ic_vec3 qp, qn;
            make_query(c, 77, k, 1.0f, &qp, &qn);
            ic_cache_lookup q = ic_cache_lookup_at(qp, qn, IC_ACCEPT_CONSTRUCTION);
            ic_cache_estimate e;
            ic_cache_query(c, &q, &e);
            tested += e.records_tested;
            max_tested = e.records_tested > max_tested ? e.records_tested : max_tested;
        }
        CHECK(max_tested <= s.max_path_references, "a look-up tested %u references, more than the longest path %u",
              max_tested, s.max_path_references);
        ic_cache_index_stats thawed;
        ic_cache_get_index_stats(c, &thawed);
        CHECK(thawed.frozen_leaves == 0 && thawed.frozen_list_entries == 0.0 && thawed.references == s.references,
              "thawed: no lists, same octree");
        printf("  index, %s: %u leaves (depth %u), %.2f references per record, %.2f per leaf, %.2f on a path "
               "(look-ups: %.2f), frozen lists %.2f\n",
               validity ? "validity clamp" : "no clamps", s.leaves, s.depth, s.references_per_record,
               s.leaf_references, s.path_references, tested / queries, s.frozen_list_entries);
        ic_cache_destroy(c);
    }
    free(recs);
}

int main(void)
{
    RUN(test_api_edges);
    RUN(test_embedder_edges);
    RUN(test_weights);
    RUN(test_ellipses);
    RUN(test_linear_field);
    RUN(test_gradient_clamps);
    RUN(test_neighbor_clamp);
    RUN(test_neighbor_clamp_brute_force);
    RUN(test_validity_clamp);
    RUN(test_thread_independence);
    RUN(test_point_queries);
    RUN(test_file);
    RUN(test_payloads);
    RUN(test_file_settings);
    RUN(test_file_settings_edges);
    RUN(test_freeze_lifecycle);
    RUN(test_frozen_threads);
    RUN(test_frozen_bounce_levels);
    RUN(test_fallback_level);
    RUN(test_crowded_lookups);
    RUN(test_index_stats);
    RUN(test_far_from_origin);
    RUN(test_coordinate_range);
    RUN(test_needle_ellipse);
    RUN(test_lookup_vs_brute_force);
    TEST_MAIN_END();
}
