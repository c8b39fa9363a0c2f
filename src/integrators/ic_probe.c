/*
 * ic_probe.c — adaptive construction alone, without a final render, with what a test needs to check its
 * convergence independently (ic_adaptive_probe).
 */
#include "ic_internal.h"

#include <stdlib.h>
#include <string.h>

ic_result ic_ic_adaptive_probe_run(const ic_scene *scene, const ic_render_options *opt, ic_adaptive_probe *out,
                                   ic_error *err)
{
    memset(out, 0, sizeof *out);
    ic_accel *accel = NULL;
    ic_result r = ic_accel_create(scene, &accel, err);
    if (r != IC_OK)
        return r;
    ic_tracer tr;
    tr.scene = scene;
    tr.accel = accel;
    tr.pt.max_depth = opt->max_depth;
    tr.pt.rr_depth = 0;
    tr.pt = ic_pt_params_resolve(tr.pt);
    ic_render_options o = *opt;
    o.ic.strategy = IC_STRATEGY_ADAPTIVE;
    ic_ctx *c = NULL;
    r = ic_ic_ctx_create(&tr, &o, &c, NULL, err);
    if (r == IC_OK) {
        ic_render_stats st;
        memset(&st, 0, sizeof st);
        phase_times pt = {0};
        r = ic_ic_build_adaptive_probed(c, &o, &st, &pt, out, err);
        if (r == IC_OK) {
            out->cache = c->cache; /* handed over: the context must not free it */
            c->cache = NULL;
            out->weber = c->o.weber;
            out->accuracy = c->o.cache.accuracy;
        }
    }
    ic_ic_ctx_destroy(c);
    ic_accel_destroy(accel);
    if (r != IC_OK)
        ic_ic_adaptive_probe_free(out);
    return r;
}

void ic_ic_adaptive_probe_free(ic_adaptive_probe *p)
{
    ic_cache_destroy(p->cache);
    free(p->position);
    free(p->normal);
    free(p->albedo);
    free(p->direct);
    memset(p, 0, sizeof *p);
}
