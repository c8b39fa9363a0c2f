/*
 * test_batch_pass.c — how a batch construction pass ends (ic_ic_batch_pass_end). A pass whose gathering an
 * interrupt or the time budget cut short adds few records because it stopped, not because the cache needs
 * few: it must end construction as stopped (cut short, cut_by_time), never as converged; before this rule
 * such a pass passed the "added few records" test and the stats said the cache had converged, with no
 * warning. The time check, a collective call when processes share the render, is asked exactly when the
 * pass did not converge, as every process decides alike. And every pass's candidate keys are its own.
 */
#include "test_util.h"

#include "integrators/ic_internal.h"

#include <stdlib.h>

static int calls, out;

static int out_of_time_stub(ic_ctx *c)
{
    (void)c;
    ++calls;
    return out;
}

static int cmp_u64(const void *a, const void *b)
{
    const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Candidate keys seed a record's random streams: for one pixel, every pass of every stage (the screen
 * stage, the world stage with its hit index, the closing sweep's rounds) must have its own, up to the most
 * passes the command allows (before, the world stage's pass k + 32 reused pass k's keys); the keys of the
 * first 32 passes are the ones they always were, so images do not change. */
static void test_keys(void)
{
    enum { PASSES = IC_MAX_MAX_PASSES + 1, N = PASSES * 4 + PASSES + 16 };
    static uint64_t keys[N];
    const uint32_t pixel = 123456;
    size_t n = 0;
    int old_ok = 1;
    for (int pass = 0; pass < PASSES; ++pass) {
        for (int hit = 0; hit < 4; ++hit) {
            keys[n++] = ic_ic_world_key(pixel, pass, hit);
            if (pass < 32)
                old_ok &= keys[n - 1] == (((uint64_t)pixel << 8) | (uint64_t)(0x80 | (pass & 0x1f) << 2 | hit));
        }
        keys[n++] = ((uint64_t)pixel << 8) | ic_ic_screen_key_tag(pass);
        if (pass < 64)
            old_ok &= keys[n - 1] == (((uint64_t)pixel << 8) | (uint64_t)pass);
    }
    for (int round = 0; round < 16; ++round)
        keys[n++] = ((uint64_t)pixel << 8) | 0x40 | (uint64_t)round;
    qsort(keys, n, sizeof *keys, cmp_u64);
    size_t dup = 0;
    for (size_t i = 1; i < n; ++i)
        dup += keys[i] == keys[i - 1];
    CHECK(dup == 0, "keys: %zu of %zu candidate keys of one pixel repeat over %d passes", dup, n, PASSES);
    CHECK(old_ok, "keys: the first passes' keys are unchanged");
}

int main(void)
{
    test_keys();
    static const struct {
        int truncated, converged, out_of_time;
        ic_pass_end want;
        int want_calls;
    } cases[] = {
        {0, 1, 0, IC_PASS_CONVERGED, 0}, /* converged: no time check (as before) */
        {0, 1, 1, IC_PASS_CONVERGED, 0}, /* converged as the budget ran out: still converged */
        {0, 0, 0, IC_PASS_CONTINUE, 1},
        {0, 0, 1, IC_PASS_STOPPED, 1},
        {1, 1, 0, IC_PASS_STOPPED, 0},   /* cut short and "converged": stopped */
        {1, 1, 1, IC_PASS_STOPPED, 0},
        {1, 0, 0, IC_PASS_STOPPED, 0},
        {1, 0, 1, IC_PASS_STOPPED, 0},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        calls = 0;
        out = cases[k].out_of_time;
        const ic_pass_end got = ic_ic_batch_pass_end(cases[k].truncated, cases[k].converged, out_of_time_stub, NULL);
        CHECK(got == cases[k].want && calls == cases[k].want_calls,
              "truncated %d, converged %d, out of time %d: end %d (want %d), %d time checks (want %d)",
              cases[k].truncated, cases[k].converged, cases[k].out_of_time, (int)got, (int)cases[k].want, calls,
              cases[k].want_calls);
    }
    TEST_MAIN_END();
}
