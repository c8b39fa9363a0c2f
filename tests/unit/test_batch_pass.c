/*
 * test_batch_pass.c — how a batch construction pass ends (ic_ic_batch_pass_end). A pass whose gathering an
 * interrupt or the time budget cut short adds few records because it stopped, not because the cache needs
 * few: it must end construction as stopped (cut short, cut_by_time), never as converged; before this rule
 * such a pass passed the "added few records" test and the stats said the cache had converged, with no
 * warning. The time check, a collective call when processes share the render, is asked exactly when the
 * pass did not converge, as every process decides alike.
 */
#include "test_util.h"

#include "integrators/ic_internal.h"

static int calls, out;

static int out_of_time_stub(ic_ctx *c)
{
    (void)c;
    ++calls;
    return out;
}

int main(void)
{
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
