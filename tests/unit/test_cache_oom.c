/*
 * test_cache_oom.c — an insertion that runs out of memory half-way leaves a consistent cache: the new
 * records dropped, no reference to them left in either octree (even when rebuilding the trees fails
 * too), the existing records' radii and change counts that the clamps lowered restored, look-ups
 * answering from the records that stayed, and the next insertion working.
 *
 * The executable is linked with --wrap=malloc,realloc (tests/CMakeLists.txt): from the fail_from-th
 * call on, every allocation fails. Each batch is tried with its failure moved one allocation later
 * until it succeeds, so every allocation of an insertion (the octree builds, the clamps, the segment
 * growth) fails once.
 */
#include "cache/cache_store.h"
#include "test_util.h"

#include <string.h>

void *__real_malloc(size_t size);
void *__real_realloc(void *p, size_t size);
static long fail_from = -1, allocations;

void *__wrap_malloc(size_t size)
{
    if (fail_from >= 0 && allocations++ >= fail_from)
        return NULL;
    return __real_malloc(size);
}

void *__wrap_realloc(void *p, size_t size)
{
    if (fail_from >= 0 && allocations++ >= fail_from)
        return NULL;
    return __real_realloc(p, size);
}

static uint64_t state = 88172645463325252ull;
static float uniform(void)
{
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    return (float)((double)(state >> 11) * (1.0 / 9007199254740992.0));
}

static ic_record make_record(void)
{
    ic_record r;
    memset(&r, 0, sizeof r);
    r.position = v3(20.0f * uniform(), 20.0f * uniform(), 1.0f);
    r.normal = v3(0, 0, 1);
    r.tangent = v3(1, 0, 0);
    r.irradiance = v3(1, 1, 1);
    r.harmonic_mean_dist = 0.5f + 2.0f * uniform();
    r.pixel_footprint = 0.01f;
    return r;
}

/* References to items `count` and above in a tree. */
static uint32_t stale_refs(const ic_octree *t, uint32_t count)
{
    uint32_t stale = 0;
    for (uint32_t n = 0; n < t->node_count; ++n)
        for (uint32_t k = 0; k < t->nodes[n].count; ++k)
            stale += t->refs[t->nodes[n].begin + k].index >= count;
    return stale;
}

/* A batch of m records after n, failing from each allocation in turn (at least min_failures of them). */
static void check_batches(uint32_t n, uint32_t m, uint32_t min_failures)
{
    ic_record *recs = malloc((n + m) * sizeof *recs);
    for (uint32_t i = 0; i < n + m; ++i)
        recs[i] = make_record();
    uint32_t failures = 0, inconsistent = 0, wrong_answers = 0, later_failed = 0, not_restored = 0, lowered = 0;
    float *radius = malloc(n * sizeof *radius);
    uint32_t *changes = malloc(n * sizeof *changes);
    for (long f = 0; f < 100000; ++f) {
        ic_cache_params p = {0};
        p.threads = 1; /* starting threads allocates: keep the allocation sequence fixed */
        ic_cache *c = NULL;
        ic_error err;
        CHECK(ic_cache_create(&p, &c, &err) == IC_OK && ic_cache_insert_batch(c, recs, n, NULL, &err) == IC_OK,
              "setting up: %s", err.message);
        for (uint32_t i = 0; i < n; ++i) {
            radius[i] = c->sphere[i].w;
            changes[i] = c->cold[i].change_count;
        }
        allocations = 0;
        fail_from = f;
        ic_result rc = ic_cache_insert_batch(c, recs + n, m, NULL, &err);
        fail_from = -1;
        if (rc == IC_OK) {
            /* The clamps do lower existing records: what a failure must undo. */
            for (uint32_t i = 0; i < n; ++i)
                lowered += c->sphere[i].w < radius[i] && c->cold[i].change_count > changes[i];
            ic_cache_destroy(c);
            break;
        }
        ++failures;
        inconsistent += ic_cache_count(c) != n || stale_refs(&c->tree, n) || stale_refs(&c->points, n);
        /* The existing records as they were (R_i, change count), unless the message says otherwise. */
        if (!strstr(err.message, "keep the radii"))
            for (uint32_t i = 0; i < n; ++i)
                not_restored += c->sphere[i].w != radius[i] || c->cold[i].change_count != changes[i];
        /* Look-ups where the dropped records were find only records that stayed. */
        for (uint32_t i = n; i < n + m; i += 7) {
            ic_cache_contribution con[64];
            ic_cache_lookup l = ic_cache_lookup_at(recs[i].position, recs[i].normal, IC_ACCEPT_FINAL);
            l.contributions = con;
            l.contribution_capacity = 64;
            ic_cache_estimate e;
            ic_cache_query(c, &l, &e);
            for (uint32_t k = 0; k < e.contributions_written; ++k)
                wrong_answers += con[k].record >= n;
        }
        later_failed += ic_cache_insert_batch(c, recs + n, m, NULL, &err) != IC_OK || ic_cache_count(c) != n + m ||
                        stale_refs(&c->tree, n + m) || stale_refs(&c->points, n + m);
        ic_cache_destroy(c);
    }
    CHECK(failures >= min_failures, "batch of %u after %u: only %u allocations to fail", m, n, failures);
    CHECK(inconsistent == 0, "batch of %u after %u: %u of %u failed insertions left references to dropped records",
          m, n, inconsistent, failures);
    CHECK(wrong_answers == 0, "batch of %u after %u: %u look-ups found dropped records", m, n, wrong_answers);
    CHECK(later_failed == 0, "batch of %u after %u: %u insertions after a failure went wrong", m, n, later_failed);
    CHECK(lowered > 0, "batch of %u after %u: the clamps lowered no existing record", m, n);
    CHECK(not_restored == 0, "batch of %u after %u: %u existing records left lowered by failed insertions", m, n,
          not_restored);
    free(radius);
    free(changes);
    free(recs);
}

int main(void)
{
    check_batches(1500, 400, 50); /* a large batch: both trees are built again */
    check_batches(1500, 20, 1);   /* a small one: records inserted one by one */
    TEST_MAIN_END();
}
