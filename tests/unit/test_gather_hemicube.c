/*
 * test_gather_hemicube.c — hemicube gathering (Castaño 2014; src/gather/gather_hemicube.c) against
 * analytic scenes: the exact per-texel weights, a uniform sky (E = πL), a half-lit sky and a rectangle
 * (exact irradiance by Lambert's formula; the discretisation error shrinks with the resolution), gradients
 * against finite differences of the exact irradiance, agreement with the stratified sampler on random
 * scenes, σ against the true error, determinism across threads and batching, and the per-record turn
 * about the normal (an environment symmetric about it gives the same result for every turn).
 * Tolerances are stated at each check and were set from the measured values printed beside them.
 */
#include "test_gather_scene.h"

#include "gather/gather_internal.h"

static void test_weights(void)
{
    const uint32_t res[4] = {2, 4, 16, 64};
    for (int k = 0; k < 4; ++k) {
        ic_gather_opts o = {.method = IC_GATHER_HEMICUBE, .hemicube_resolution = res[k]};
        gs_scene s = {.sky = {1, 1, 1}};
        ic_gatherer *g = gs_gatherer(&o, &s);
        if (!g)
            return;
        const ic_hemicube *hc = &g->hemicube;
        const uint32_t N = res[k];
        double w = 0, omega = 0, rx = 0, ry = 0, wmin = INFINITY, wmax = 0;
        for (uint32_t i = 0; i < hc->texels; ++i) {
            w += hc->weight[i];
            omega += hc->solid_angle[i];
            rx += hc->rot[i][0];
            ry += hc->rot[i][1];
            wmin = fmin(wmin, hc->weight[i]);
            wmax = fmax(wmax, hc->weight[i]);
            /* The cosine-weighted weight of a texel lies between cosθ_min·Ω and Ω. */
            CHECK(hc->weight[i] > 0.0 && hc->weight[i] <= hc->solid_angle[i] * (1.0 + 1e-12), "texel %u weight", i);
        }
        printf("hemicube %u: %u texels, %u walls, Σw − π = %.2e, ΣΩ − 2π = %.2e, weights %.3g..%.3g\n", N,
               hc->texels, hc->walls, w - GS_PI, omega - 2 * GS_PI, wmin, wmax);
        CHECK(hc->texels == 3 * N * N, "texel count");
        CHECK(hc->walls == 6 * N * N - 2 * N, "walls: %u, expected 6N² − 2N = %u", hc->walls, 6 * N * N - 2 * N);
        CHECK_NEAR(w, GS_PI, 1e-9, "Σ irradiance weights = π");
        CHECK_NEAR(omega, 2 * GS_PI, 1e-9, "Σ solid angles = 2π");
        CHECK(fabs(rx) < 1e-12 && fabs(ry) < 1e-12, "Σ rotational weights = 0: %g %g", rx, ry);
        /* Σ (left − right) over the walls of each texel: every texel has 4 walls except horizon ones. */
        ic_gatherer_destroy(g);
    }
}

static void test_uniform_sky(void)
{
    gs_scene s = {.sky = {0.5f, 1.0f, 2.0f}};
    ic_gather_opts o = {.method = IC_GATHER_HEMICUBE};
    ic_gatherer *g = gs_gatherer(&o, &s);
    if (!g)
        return;
    for (int q = 0; q < 2; ++q) {
        ic_vec3 n = q ? v3_norm(v3(0.3f, 0.4f, 0.8f)) : v3(0, 0, 1);
        ic_gather_result r = gs_gather(g, v3(0.3f, -0.2f, 0.0f), n, 7 + (uint64_t)q);
        CHECK_NEAR(r.irradiance.x, GS_PI * 0.5, 2e-6, "sky E.r");
        CHECK_NEAR(r.irradiance.y, GS_PI * 1.0, 4e-6, "sky E.g");
        CHECK_NEAR(r.irradiance.z, GS_PI * 2.0, 8e-6, "sky E.b");
        for (int c = 0; c < 3; ++c) {
            CHECK(gs_len(r.rot_grad[c]) < 1e-6, "sky rot grad %d = %g", c, gs_len(r.rot_grad[c]));
            CHECK(gs_len(r.trans_grad[c]) == 0.0, "sky trans grad %d = %g", c, gs_len(r.trans_grad[c]));
        }
        CHECK(v3_maxc(r.sigma) < 1e-5f, "sky sigma %g", (double)v3_maxc(r.sigma));
        CHECK(r.harmonic_mean_dist == INFINITY && r.min_dist == INFINITY && r.hit_count == 0, "sky distances");
        CHECK(r.ray_count == 768u, "default resolution 16: %u rays", r.ray_count);
        CHECK(r.is_converged == 1 && r.has_hessian == 0, "converged, no Hessian unless asked");
    }
    ic_gatherer_destroy(g);
}

/* Worst and mean relative error of E over `keys` record keys (the hemicube turns with the key). */
static void hemicube_errors(gs_scene *s, uint32_t N, ic_vec3 p, ic_vec3 n, double exact, int keys, double *worst,
                            double *mean)
{
    ic_gather_opts o = {.method = IC_GATHER_HEMICUBE, .hemicube_resolution = N};
    ic_gatherer *g = gs_gatherer(&o, s);
    *worst = *mean = 0.0;
    if (!g)
        return;
    for (int k = 0; k < keys; ++k) {
        ic_gather_result r = gs_gather(g, p, n, 100 + (uint64_t)k);
        double e = fabs(r.irradiance.y - exact) / exact;
        *worst = fmax(*worst, e);
        *mean += e / keys;
    }
    ic_gatherer_destroy(g);
}

static void test_half_lit_and_rect(void)
{
    /* Sky of radiance 2 where dir·x̂ > 0, black elsewhere; normal tilted by α towards +x: the lit part of
     * the hemisphere is a lune bounded by two half great circles, and Lambert's formula gives
     * E = 2 · (π/2)(1 + sin α). */
    gs_scene half = {.sky = {2, 2, 2}, .sky_half = 1, .sky_axis = {1, 0, 0}};
    const float alpha = 0.4f;
    const ic_vec3 n = v3(sinf(alpha), 0, cosf(alpha));
    const double exact_half = 2.0 * GS_PI / 2 * (1.0 + sin((double)alpha));
    /* A 2×1.5 rectangle of radiance 10 at height 1, off axis, black sky. */
    gs_scene rect = {.n_rects = 1};
    rect.rects[0] = (gs_rect){{0.3f, -0.2f, 1}, {2, 0, 0}, {0, 1.5f, 0}, {10, 10, 10}};
    const double p0[3] = {0, 0, 0}, nz[3] = {0, 0, 1};
    const double exact_rect = 10.0 * gs_rect_irradiance(&rect.rects[0], p0, nz);

    const uint32_t res[4] = {8, 16, 32, 64};
    double mh[4], mr[4];
    for (int k = 0; k < 4; ++k) {
        double wh, wr;
        hemicube_errors(&half, res[k], v3(0, 0, 0), n, exact_half, 16, &wh, &mh[k]);
        hemicube_errors(&rect, res[k], v3(0, 0, 0), v3(0, 0, 1), exact_rect, 16, &wr, &mr[k]);
        printf("hemicube %2u (%5u rays): half-lit sky mean rel err %.5f worst %.5f; rectangle mean %.5f worst %.5f\n",
               res[k], 3 * res[k] * res[k], mh[k], wh, mr[k], wr);
        /* Stated: worst within 4%/N·16 of E (measured: see the line above). */
        CHECK(wh < 0.04 * 16.0 / res[k], "half-lit worst error %g at N = %u", wh, res[k]);
        CHECK(wr < 0.04 * 16.0 / res[k], "rectangle worst error %g at N = %u", wr, res[k]);
    }
    /* The discretisation error shrinks with the resolution: 8× finer gives at least 4× less. */
    CHECK(mh[3] < mh[0] / 4 && mr[3] < mr[0] / 4, "error shrinks: half %g → %g, rect %g → %g", mh[0], mh[3], mr[0], mr[3]);
}

static void test_gradients(void)
{
    gs_scene s = {.n_rects = 1};
    s.rects[0] = (gs_rect){{0.4f, -0.3f, 1.0f}, {1.5f, 0, 0}, {0, 1.0f, 0}, {10, 10, 10}};
    const double d = 1e-5, nz[3] = {0, 0, 1};
    const gs_rect *q = &s.rects[0];
    double ft[2], fr[2];
    for (int a = 0; a < 2; ++a) {
        double pp[3] = {0, 0, 0}, pm[3] = {0, 0, 0};
        pp[a] = d;
        pm[a] = -d;
        ft[a] = 10.0 * (gs_rect_irradiance(q, pp, nz) - gs_rect_irradiance(q, pm, nz)) / (2 * d);
        /* Rotational: rotating n about axis a by ±d; n_i × n = d·axis. */
        ic_vec3 axis = a ? v3(0, 1, 0) : v3(1, 0, 0);
        ic_vec3 np = gs_rotate_normal(v3(0, 0, 1), axis, (float)d), nm = gs_rotate_normal(v3(0, 0, 1), axis, (float)-d);
        double npd[3] = {np.x, np.y, np.z}, nmd[3] = {nm.x, nm.y, nm.z};
        double p0[3] = {0, 0, 0};
        fr[a] = 10.0 * (gs_rect_irradiance(q, p0, npd) - gs_rect_irradiance(q, p0, nmd)) / (2 * (double)(float)d);
    }
    const ic_vec3 fdt = v3((float)ft[0], (float)ft[1], 0), fdr = v3((float)fr[0], (float)fr[1], 0);
    const uint32_t res[3] = {16, 32, 64};
    for (int k = 0; k < 3; ++k) {
        ic_gather_opts o = {.method = IC_GATHER_HEMICUBE, .hemicube_resolution = res[k]};
        ic_gatherer *g = gs_gatherer(&o, &s);
        if (!g)
            return;
        ic_vec3 t = v3s(0), r = v3s(0);
        const int K = 8;
        for (int key = 0; key < K; ++key) {
            ic_gather_result gr = gs_gather(g, v3(0, 0, 0), v3(0, 0, 1), 300 + (uint64_t)key);
            t = v3_add(t, v3_scale(gr.trans_grad[1], 1.0f / K));
            r = v3_add(r, v3_scale(gr.rot_grad[1], 1.0f / K));
        }
        double et = gs_len(v3_sub(t, fdt)) / gs_len(fdt), er = gs_len(v3_sub(r, fdr)) / gs_len(fdr);
        printf("hemicube %u gradients: ∇t (%.4f %.4f) fd (%.4f %.4f) rel err %.4f; ∇r (%.4f %.4f) fd (%.4f %.4f) rel err %.4f\n",
               res[k], (double)t.x, (double)t.y, ft[0], ft[1], et, (double)r.x, (double)r.y, fr[0], fr[1], er);
        /* Stated: translational within 8%, rotational within 3% at N = 16 (measured above), tighter after. */
        CHECK(et < 0.08 * 16.0 / res[k] + 0.01, "hemicube %u translational gradient rel err %g", res[k], et);
        CHECK(er < 0.03 * 16.0 / res[k] + 0.005, "hemicube %u rotational gradient rel err %g", res[k], er);
        ic_gatherer_destroy(g);
    }
}

/* Deterministic pseudo-random numbers for the scenes. */
static double lcg(uint64_t *s)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(*s >> 11) * (1.0 / 9007199254740992.0);
}

static void random_scene(gs_scene *s, uint64_t seed)
{
    memset(s, 0, sizeof *s);
    s->sky = v3(0.3f, 0.4f, 0.5f);
    s->n_rects = 8;
    for (int i = 0; i < s->n_rects; ++i) {
        ic_vec3 c = v3((float)(lcg(&seed) * 4 - 2), (float)(lcg(&seed) * 4 - 2), (float)(0.3 + lcg(&seed) * 1.5));
        float ang = (float)(lcg(&seed) * 2 * GS_PI), tilt = (float)(lcg(&seed) - 0.5);
        ic_vec3 e1 = v3_scale(v3(cosf(ang), sinf(ang), tilt), (float)(0.3 + lcg(&seed)));
        ic_vec3 e2 = v3_scale(v3_norm(v3_cross(v3(0, 0, 1), e1)), (float)(0.3 + lcg(&seed)));
        float bright = lcg(&seed) < 0.3 ? 0.0f : (float)(lcg(&seed) * 8);
        s->rects[i] = (gs_rect){c, e1, e2, v3(bright, bright * (float)lcg(&seed), bright * 0.5f)};
    }
}

static void test_agrees_with_stratified(void)
{
    /* Random scenes of 8 rectangles (some black occluders) under a sky: the hemicube (768 rays) against
     * the mean of 32 stratified gathers (800 rays each, standard error from their spread) and against a
     * 3·256² = 196608-ray hemicube as the reference for its own error and σ. */
    int agree = 0, total = 0;
    double sum_err2 = 0, sum_sig2 = 0, sum_strat_err2 = 0;
    ic_gather_opts oh = {.method = IC_GATHER_HEMICUBE}, oref = {.method = IC_GATHER_HEMICUBE, .hemicube_resolution = 256};
    ic_gather_opts os = {0};
    for (uint64_t sc = 0; sc < 6; ++sc) {
        gs_scene s;
        random_scene(&s, 1234 + sc);
        ic_gatherer *gh = gs_gatherer(&oh, &s), *gr = gs_gatherer(&oref, &s), *gs = gs_gatherer(&os, &s);
        if (!gh || !gr || !gs)
            return;
        for (int q = 0; q < 4; ++q) {
            ic_vec3 p = v3(0.4f * q - 0.6f, 0.3f * (float)sc - 0.8f, 0), n = v3_norm(v3(0.1f * q, -0.05f * (float)sc, 1));
            ic_gather_result h = gs_gather(gh, p, n, 17 + (uint64_t)q), ref = gs_gather(gr, p, n, 1);
            double m = 0, m2 = 0;
            const int K = 32;
            for (int k = 0; k < K; ++k) {
                double e = gs_gather(gs, p, n, 1000 + (uint64_t)k).irradiance.y;
                m += e / K;
                m2 += e * e / K;
                sum_strat_err2 += (e - ref.irradiance.y) * (e - ref.irradiance.y) / K;
            }
            double se = sqrt(fmax(m2 - m * m, 0.0) / (K - 1));
            double diff = fabs(h.irradiance.y - m), err = h.irradiance.y - ref.irradiance.y;
            /* Within noise: 4 standard errors of the stratified mean plus the hemicube's own σ. */
            agree += diff <= 4 * se + 2 * h.sigma.y + 1e-3 * m;
            ++total;
            sum_err2 += err * err;
            sum_sig2 += (double)h.sigma.y * h.sigma.y;
        }
        ic_gatherer_destroy(gh);
        ic_gatherer_destroy(gr);
        ic_gatherer_destroy(gs);
    }
    const double rms_err = sqrt(sum_err2 / total), rms_sig = sqrt(sum_sig2 / total), rms_strat = sqrt(sum_strat_err2 / total);
    printf("random scenes: hemicube within noise of stratified at %d/%d points; RMS error (vs 256² hemicube): "
           "hemicube-16 %.4f, stratified-16x50 %.4f; RMS σ %.4f (σ/err %.2f)\n",
           agree, total, rms_err, rms_strat, rms_sig, rms_sig / rms_err);
    CHECK(agree >= total - 1, "hemicube agrees with stratified at %d/%d points", agree, total);
    /* σ is an honest scale for the discretisation error: stated within a factor 3 either way. */
    CHECK(rms_sig / rms_err > 1.0 / 3 && rms_sig / rms_err < 3.0, "σ calibration %g", rms_sig / rms_err);
}

static void test_determinism(void)
{
    gs_scene s;
    random_scene(&s, 77);
    enum { NP = 29 };
    ic_gather_point pts[NP];
    for (int i = 0; i < NP; ++i)
        pts[i] = (ic_gather_point){v3(0.05f * i - 0.7f, 0.03f * i - 0.4f, 0), v3_norm(v3(0.02f * i, 0, 1)), (uint64_t)i * 31u};
    for (int hess = 0; hess < 2; ++hess) {
        ic_gather_opts o = {.method = IC_GATHER_HEMICUBE, .seed = 5, .with_hessian = hess};
        ic_gather_result a[NP], b[NP], c[NP];
        memset(a, 0xAB, sizeof a);
        memset(b, 0xCD, sizeof b);
        ic_error err;
        CHECK(ic_gather_batch(&o, gs_trace, &s, 1, pts, NP, a, &err) == IC_OK, "batch 1 thread");
        CHECK(ic_gather_batch(&o, gs_trace, &s, 2, pts, NP, b, &err) == IC_OK, "batch 2 threads");
        ic_gather_opts o2 = o;
        o2.batch_rays = 96;
        ic_gatherer *g = gs_gatherer(&o2, &s);
        if (!g)
            return;
        for (int i = NP - 1; i >= 0; --i) { /* reverse order too */
            memset(&c[i], 0x11, sizeof c[i]);
            CHECK(ic_gather_hemicube(g, &pts[i], &c[i]) == IC_OK, "single hemicube gather");
        }
        ic_gatherer_destroy(g);
        int same_ab = 1, same_ac = 1;
        for (int i = 0; i < NP; ++i) {
            same_ab &= memcmp(&a[i], &b[i], sizeof a[i]) == 0;
            same_ac &= memcmp(&a[i], &c[i], sizeof a[i]) == 0;
        }
        CHECK(same_ab, "hemicube (Hessian %d): 1 vs 2 threads bit-identical", hess);
        CHECK(same_ac, "hemicube (Hessian %d): batch vs single, reversed, other ray batching bit-identical", hess);
        CHECK(a[0].has_hessian == hess, "has_hessian %d", a[0].has_hessian);
    }
}

/* An environment symmetric about the axis n: a plane parallel to the tangent plane at height 1 (hit
 * distance 1/cosθ) whose radiance depends on cosθ only. Every ray direction is recorded. */
typedef struct sym_scene {
    ic_vec3 n;
    ic_vec3 dirs[3 * 16 * 16];
    uint32_t recorded;
} sym_scene;

static void sym_trace(void *user, const ic_vec3 *org, const ic_vec3 *dir, uint32_t count, float *hit_dist,
                      ic_vec3 *radiance)
{
    (void)org;
    sym_scene *s = user;
    for (uint32_t r = 0; r < count; ++r) {
        const float c = v3_dot(dir[r], s->n);
        if (s->recorded < sizeof s->dirs / sizeof s->dirs[0])
            s->dirs[s->recorded++] = dir[r];
        hit_dist[r] = c > 0.0f ? 1.0f / c : INFINITY;
        radiance[r] = v3(1.0f + 2.0f * c * c, 0.5f + c, c * c * c);
    }
}

/* The per-record turn of the hemicube about the normal (the file comment of gather_hemicube.c): the
 * turn is a rotation of the frame, so an environment symmetric about the normal gives the same E, the
 * same gradient magnitudes and the same Hessian coefficients (in the result's own frame) for every
 * record key; and the turn is really taken: the keys' first rays point to azimuths all round the normal,
 * and one key always gives the same rays. */
static void test_turn_about_normal(void)
{
    const ic_vec3 normals[2] = {v3(0, 0, 1), v3_norm(v3(0.3f, -0.5f, 0.8f))};
    enum { KEYS = 64, BINS = 8 };
    for (int q = 0; q < 2; ++q) {
        sym_scene s = {.n = normals[q]};
        ic_gather_opts o = {.method = IC_GATHER_HEMICUBE, .hemicube_resolution = 16, .with_hessian = 1, .seed = 3};
        ic_gatherer *g = NULL;
        ic_error err;
        if (ic_gatherer_create(&o, sym_trace, &s, &g, &err) != IC_OK)
            return;
        ic_gather_result first = {0};
        double worst_e = 0.0, worst_grad = 0.0, worst_h = 0.0;
        int bins[BINS] = {0};
        ic_vec3 t0 = v3s(0.0f), b0 = v3s(0.0f);
        for (int k = 0; k < KEYS; ++k) {
            s.recorded = 0;
            ic_gather_point pt = {v3(0.2f, 0.1f, -0.3f), s.n, 1000u + 17u * (uint64_t)k};
            ic_gather_result r;
            CHECK(ic_gather_hemicube(g, &pt, &r) == IC_OK, "gather key %d", k);
            /* Azimuth of the first texel's ray (a top-face texel) in the first key's frame. */
            if (k == 0) {
                first = r;
                t0 = r.hessian_t;
                b0 = r.hessian_b;
            }
            const double az = atan2(v3_dot(s.dirs[0], b0), v3_dot(s.dirs[0], t0));
            bins[(int)floor((az + GS_PI) / (2.0 * GS_PI) * BINS) % BINS]++;
            const float e[3] = {r.irradiance.x, r.irradiance.y, r.irradiance.z};
            const float e0[3] = {first.irradiance.x, first.irradiance.y, first.irradiance.z};
            for (int c = 0; c < 3; ++c) {
                worst_e = fmax(worst_e, fabs(e[c] - e0[c]) / e0[c]);
                worst_grad = fmax(worst_grad, fabs(gs_len(r.rot_grad[c]) - gs_len(first.rot_grad[c])) / e0[c]);
                worst_grad = fmax(worst_grad, fabs(gs_len(r.trans_grad[c]) - gs_len(first.trans_grad[c])) / e0[c]);
                for (int h = 0; h < 3; ++h)
                    worst_h = fmax(worst_h, fabs(r.hessian[c][h] - first.hessian[c][h]) / e0[c]);
            }
        }
        int empty = 0;
        for (int b = 0; b < BINS; ++b)
            empty += bins[b] == 0;
        printf("hemicube turn, normal %d: over %d keys E varies by %.2g, gradients by %.2g, Hessian by %.2g "
               "(relative to E); first-ray azimuths in %d of %d bins\n",
               q, KEYS, worst_e, worst_grad, worst_h, BINS - empty, BINS);
        /* Float rounding of the turned directions only (a tilted normal's cosθ is not bit-exact). */
        CHECK(worst_e < 1e-5, "symmetric environment: E independent of the turn (%g)", worst_e);
        CHECK(worst_grad < 1e-4, "symmetric environment: gradient magnitudes independent of the turn (%g)", worst_grad);
        CHECK(worst_h < 1e-4, "symmetric environment: Hessian coefficients independent of the turn (%g)", worst_h);
        CHECK(empty == 0, "the turn covers every azimuth: %d of %d bins empty", empty, BINS);
        /* The same key twice: the same rays. */
        ic_vec3 again[2][4];
        for (int rep = 0; rep < 2; ++rep) {
            s.recorded = 0;
            ic_gather_point pt = {v3(0.2f, 0.1f, -0.3f), s.n, 4242u};
            ic_gather_result r;
            CHECK(ic_gather_hemicube(g, &pt, &r) == IC_OK, "gather again");
            memcpy(again[rep], s.dirs, sizeof again[rep]);
        }
        CHECK(memcmp(again[0], again[1], sizeof again[0]) == 0, "one key, one turn");
        ic_gatherer_destroy(g);
    }
}

static void test_bad_input(void)
{
    gs_scene s = {.sky = {1, 1, 1}};
    ic_gatherer *g = NULL;
    ic_error err;
    ic_gather_opts o = {.method = IC_GATHER_HEMICUBE, .hemicube_resolution = 15};
    CHECK(ic_gatherer_create(&o, gs_trace, &s, &g, &err) == IC_ERR_INVALID_ARG && !g, "odd resolution rejected");
    o.hemicube_resolution = 514;
    CHECK(ic_gatherer_create(&o, gs_trace, &s, &g, &err) == IC_ERR_INVALID_ARG, "resolution > 512 rejected");
    o = (ic_gather_opts){.method = (ic_gather_method)3};
    CHECK(ic_gatherer_create(&o, gs_trace, &s, &g, &err) == IC_ERR_INVALID_ARG, "unknown method rejected");
    o = (ic_gather_opts){.method = IC_GATHER_HEMICUBE};
    CHECK(ic_gatherer_create(&o, gs_trace, &s, &g, &err) == IC_OK, "defaults");
    CHECK(ic_gatherer_opts(g)->hemicube_resolution == 16, "default resolution 16");
    ic_gather_point bad = {v3(0, 0, 0), v3(0, 0, 0), 1};
    ic_gather_result r;
    CHECK(ic_gather_hemicube(g, &bad, &r) == IC_ERR_INVALID_ARG, "zero normal rejected");
    CHECK(ic_gather_hemicube(NULL, &bad, &r) == IC_ERR_INVALID_ARG, "NULL gatherer rejected");
    ic_gatherer *gs = NULL;
    ic_gather_point ok = {v3(0, 0, 0), v3(0, 0, 1), 1};
    CHECK(ic_gatherer_create(NULL, gs_trace, &s, &gs, &err) == IC_OK, "stratified gatherer");
    CHECK(ic_gather_hemicube(gs, &ok, &r) == IC_ERR_INVALID_ARG, "no hemicube tables in a stratified gatherer");
    ic_gatherer_destroy(gs);
    o = (ic_gather_opts){.hemicube_resolution = 8};
    CHECK(ic_gatherer_create(&o, gs_trace, &s, &gs, &err) == IC_OK, "stratified gatherer with a resolution");
    CHECK(ic_gather_hemicube(gs, &ok, &r) == IC_OK && r.ray_count == 192, "an explicit resolution builds the tables");
    ic_gatherer_destroy(gs);
    CHECK(ic_gather_batch(&o, gs_trace, &s, 2, &bad, 1, &r, &err) == IC_ERR_INVALID_ARG, "batch reports a bad point");
    ic_gatherer_destroy(g);
}

int main(void)
{
    test_weights();
    test_uniform_sky();
    test_half_lit_and_rect();
    test_gradients();
    test_agrees_with_stratified();
    test_determinism();
    test_turn_about_normal();
    test_bad_input();
    TEST_MAIN_END();
}
