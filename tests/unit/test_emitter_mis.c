/*
 * test_emitter_mis.c — a record takes a cached large emitter's light from its hemisphere rays and from
 * light samples of the cached emitters, both weighted by the balance heuristic (ic_light_samples.c,
 * add_cached_emitter_light). Checked on a black room lit by one emitting window pane,
 * where a record's irradiance is the pane's direct light alone and Lambert's polygon formula gives it
 * exactly: the estimate is unbiased with and without the light samples, the light samples cut its
 * variance, and the result does not depend on the thread count.
 */
#include "test_gather_scene.h"
#include "test_render_util.h"
#include "test_tracer.h"
#include "test_util.h"

#include "irrcache/render.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SCENE IC_TEST_TMP "/emitter_mis.json"
#define POINTS 2
#define KEYS 400

/* A 4 × 3 × 4 m room with black walls; in the wall z = 4 a 1 × 1 m window pane (x 1.5–2.5, y 1–2) that
 * emits L = 3 into the room. */
static void write_scene(void)
{
    test_write_file(IC_TEST_TMP "/emitter_mis.mtl", "newmtl black\nKd 0 0 0\nnewmtl pane\nKd 0 0 0\nKe 3 3 3\n");
    test_write_file(IC_TEST_TMP "/emitter_mis.obj",
               "mtllib emitter_mis.mtl\nusemtl black\n"
               "v 0 0 0\nv 4 0 0\nv 4 0 4\nv 0 0 4\nv 0 3 0\nv 4 3 0\nv 4 3 4\nv 0 3 4\n"
               "f 1 4 3 2\nf 5 6 7 8\nf 1 5 8 4\nf 2 3 7 6\nf 1 2 6 5\n"
               "v 1.5 0 4\nv 1.5 3 4\nv 2.5 0 4\nv 2.5 3 4\nv 1.5 1 4\nv 2.5 1 4\nv 1.5 2 4\nv 2.5 2 4\n"
               "f 4 8 10 9\nf 11 12 7 3\nf 9 13 14 11\nf 15 10 12 16\n"
               "usemtl pane\nf 13 15 16 14\n");
    test_write_file(SCENE, "{\n  \"camera\": {\"eye\": [3.6, 2.6, 0.3], \"target\": [1.8, 0.6, 3.2], \"up\": [0, 1, 0],\n"
                      "             \"fov_y\": 70, \"width\": 32, \"height\": 24},\n"
                      "  \"meshes\": [{\"path\": \"emitter_mis.obj\"}]\n}\n");
}

/* Every emitting triangle's light carried by the records, as the large-emitter choice would leave it. */
static int cache_every_emitter(ic_ctx *c, const ic_scene *s)
{
    const uint32_t nl = s->tri_light_count;
    free(c->direct_pmf);
    free(c->direct_cdf);
    free(c->cached_pmf);
    free(c->cached_cdf);
    c->direct_pmf = calloc(nl, sizeof *c->direct_pmf);
    c->direct_cdf = calloc(nl + 1, sizeof *c->direct_cdf);
    c->cached_pmf = malloc(sizeof *c->cached_pmf * nl);
    c->cached_cdf = malloc(sizeof *c->cached_cdf * (nl + 1));
    if (!c->direct_pmf || !c->direct_cdf || !c->cached_pmf || !c->cached_cdf)
        return 0;
    double sum = 0.0;
    c->cached_cdf[0] = 0.0f;
    for (uint32_t i = 0; i < nl; ++i) {
        c->cached_pmf[i] = s->tri_lights[i].power / s->tri_light_power;
        sum += c->cached_pmf[i];
        c->cached_cdf[i + 1] = (float)sum;
    }
    c->cached_cdf[nl] = 1.0f;
    c->cached_emitters = nl;
    c->light_sel.tri = 0.0f; /* the final render's selection had pointed into the arrays freed above */
    c->light_sel.tri_pmf = NULL;
    c->light_sel.tri_cdf = NULL;
    return 1;
}

/* Gathers KEYS records at `at` (keys differ) with the cached emitters' light samples on or off; out gets
 * the luminance of each, and res (if not NULL) the records. */
static int gather(ic_ctx *c, const ic_gather_point *at, int mis, int threads, double *out, ic_gather_result *keep)
{
    ic_gather_point *pts = malloc(sizeof *pts * KEYS);
    ic_gather_result *res = malloc(sizeof *res * KEYS);
    uint8_t *done = malloc(KEYS);
    int ok = pts && res && done;
    for (uint32_t k = 0; ok && k < KEYS; ++k) {
        pts[k] = *at;
        pts[k].key = 1000u * (uint64_t)at->key + k;
    }
    c->emitter_mis = mis;
    c->threads = threads;
    ic_error err = {0};
    ok = ok && ic_ic_gather_points(c, pts, KEYS, res, NULL, NULL, done, &err) == IC_OK;
    for (uint32_t k = 0; ok && k < KEYS; ++k)
        out[k] = done[k] ? v3_lum(res[k].irradiance) : NAN;
    if (ok && keep)
        memcpy(keep, res, sizeof *res * KEYS);
    c->emitter_mis = 0;
    free(pts);
    free(res);
    free(done);
    return ok;
}

static void mean_var(const double *x, int n, double *mean, double *var)
{
    double m = 0.0, v = 0.0;
    for (int i = 0; i < n; ++i)
        m += x[i] / n;
    for (int i = 0; i < n; ++i)
        v += (x[i] - m) * (x[i] - m) / (n - 1);
    *mean = m;
    *var = v;
}

/* With the light samples, the rays' hits on the pane must still count whole in the Hessian (only the
 * irradiance takes the balance heuristic's share): the light samples add no Hessian of their own, so
 * weighted hits would leave it too small by about the rays' mean weight, and a Hessian-sized record too
 * large. The rays are the same with and without the light samples (same keys), so the Hessians must agree
 * to rounding (the weighted rays' Hessian and the removed share's are summed). */
static void check_hessians(int p, const ic_gather_result *on, const ic_gather_result *off)
{
    int hessians = 1;
    double h_on = 0.0, h_off = 0.0, worst = 0.0;
    for (int k = 0; k < KEYS; ++k) {
        hessians &= on[k].has_hessian && off[k].has_hessian;
        double scale = 0.0;
        for (int ch = 0; ch < 3; ++ch)
            for (int i = 0; i < 3; ++i)
                scale = fmax(scale, fabs(off[k].hessian[ch][i]));
        for (int ch = 0; ch < 3; ++ch)
            for (int i = 0; i < 3; ++i)
                worst = fmax(worst, fabs(on[k].hessian[ch][i] - off[k].hessian[ch][i]) / fmax(scale, 1e-30));
        h_on += fabs(on[k].hessian[1][0] + on[k].hessian[1][2]) / KEYS;
        h_off += fabs(off[k].hessian[1][0] + off[k].hessian[1][2]) / KEYS;
    }
    printf("point %d: mean |trace of the Hessian| (green) %.5f with light samples, %.5f without; largest "
           "difference %.2g of a record's largest coefficient\n", p, h_on, h_off, worst);
    CHECK(hessians, "point %d: every record has a Hessian", p);
    CHECK(worst < 1e-4, "point %d: the light samples leave the Hessian as the rays alone give it (mean |trace| "
          "%.5f against %.5f; largest difference %.2g)", p, h_on, h_off, worst);
}

int main(void)
{
    write_scene();
    ic_error err = {0};
    ic_scene *scene = NULL;
    ic_accel *accel = NULL;
    ic_tracer tr;
    if (!test_tracer_load(SCENE, 8, &scene, &accel, &tr, &err)) {
        CHECK(0, "the scene loads: %s", err.message);
        return 1;
    }
    ic_render_options opt;
    memset(&opt, 0, sizeof opt);
    opt.integrator = IC_INTEGRATOR_IC;
    opt.spp = 1;
    opt.max_depth = 8;
    opt.seed = 3;
    opt.has_seed = 1;
    opt.ic.gather.theta_strata = 4; /* 4 × 13 = 52 rays: few, where hitting the pane or not weighs most */
    opt.ic.gather.phi_strata = 13;
    opt.ic.error = IC_ERROR_HESSIAN; /* the records' Hessians too */
    ic_ctx *c = NULL;
    int ok = ic_ic_ctx_create(&tr, &opt, &c, NULL, &err) == IC_OK;
    CHECK(ok, "a context: %s", err.message);
    ok = ok && cache_every_emitter(c, scene);
    CHECK(ok && scene->tri_light_count == 2, "the pane is two emitting triangles, both cached");
    /* Two receivers that see the pane at different angles: the floor's middle and the left wall. */
    const ic_gather_point at[POINTS] = {{{2.0f, 1e-3f, 2.5f}, {0.0f, 1.0f, 0.0f}, 1},
                                        {{1e-3f, 1.5f, 3.0f}, {1.0f, 0.0f, 0.0f}, 2}};
    const double pane[4][3] = {{1.5, 1.0, 4.0}, {2.5, 1.0, 4.0}, {2.5, 2.0, 4.0}, {1.5, 2.0, 4.0}};
    static double off[KEYS], on[KEYS], on1[KEYS];
    static ic_gather_result res[KEYS], res_off[KEYS];
    for (int p = 0; ok && p < POINTS; ++p) {
        const double x[3] = {at[p].position.x, at[p].position.y, at[p].position.z};
        const double n[3] = {at[p].normal.x, at[p].normal.y, at[p].normal.z};
        const double exact = 3.0 * gs_polygon_irradiance(pane, 4, x, n);
        ok = gather(c, &at[p], 0, 2, off, NULL) && gather(c, &at[p], 1, 2, on, NULL) &&
             gather(c, &at[p], 1, 1, on1, NULL);
        CHECK(ok, "point %d: gathers", p);
        if (!ok)
            break;
        double m_off, v_off, m_on, v_on;
        mean_var(off, KEYS, &m_off, &v_off);
        mean_var(on, KEYS, &m_on, &v_on);
        printf("point %d: E exact %.5f; rays alone %.5f (sd %.5f a record); with light samples %.5f (sd %.5f)\n",
               p, exact, m_off, sqrt(v_off), m_on, sqrt(v_on));
        CHECK(fabs(m_off - exact) < 4.0 * sqrt(v_off / KEYS) + 1e-4 * exact,
              "point %d: the rays alone are unbiased (%.5f against %.5f)", p, m_off, exact);
        CHECK(fabs(m_on - exact) < 4.0 * sqrt(v_on / KEYS) + 1e-4 * exact,
              "point %d: rays and light samples together are unbiased (%.5f against %.5f, sd of the mean %.5f)",
              p, m_on, exact, sqrt(v_on / KEYS));
        CHECK(v_on < 0.25 * v_off, "point %d: the light samples cut a record's variance (%.3g against %.3g)", p,
              v_on, v_off);
        CHECK(memcmp(on, on1, sizeof on) == 0, "point %d: 1 and 2 threads give the same records", p);
    }
    ic_ic_ctx_destroy(c);
    /* The Hessians, at 24 × 75 rays and the light samples that go with them. */
    c = NULL;
    opt.ic.gather.theta_strata = 24;
    opt.ic.gather.phi_strata = 75;
    ok = ok && ic_ic_ctx_create(&tr, &opt, &c, NULL, &err) == IC_OK && cache_every_emitter(c, scene);
    CHECK(ok, "a context with finer strata: %s", err.message);
    for (int p = 0; ok && p < POINTS; ++p) {
        ok = gather(c, &at[p], 1, 2, on, res) && gather(c, &at[p], 0, 2, off, res_off);
        CHECK(ok, "point %d: gathers with finer strata", p);
        if (ok)
            check_hessians(p, res, res_off);
    }
    ic_ic_ctx_destroy(c);
    ic_accel_destroy(accel);
    ic_scene_free(scene);
    TEST_MAIN_END();
}
