/*
 * test_gather.c — hemisphere gathering (src/gather, include/irrcache/gather.h) against analytic scenes.
 *
 * The trace callback intersects a handful of emitting or black rectangles and disks above the
 * receiver plane z = 0; rays that miss everything return a uniform sky radiance. Reference values:
 *   - uniform sky L, nothing above: E = πL, gradients 0;
 *   - a rectangle of radiance L seen unoccluded: Lambert's polygon formula
 *         E(p, n) = L/2 · |Σ_i angle(a_i, a_i+1) · n · normalize(a_i × a_i+1)|,  a_i = v_i − p,
 *     cross-checked against the closed-form form factor of a parallel rectangle with a corner above p;
 *     its finite differences in p and n are the exact gradients (up to O(δ²));
 *   - a horizontal disk of radius r at height h centred above p: E = πL r² / (r² + h²);
 *   - an occluded configuration: finite differences of a dense (≈500k-ray) gather with the same seed.
 * Tolerances are stated at each check and were set from measured errors with a safety margin.
 */
#include "irrcache/gather.h"

#include "core/vecmath.h"
#include "test_util.h"

#include <string.h>

static const double PI_D = 3.14159265358979323846;

/* ---- analytic scene ------------------------------------------------------------------------- */

typedef struct rect {
    ic_vec3 corner, e1, e2;   /* e1 ⟂ e2 */
    ic_vec3 emit;
} rect;

typedef struct disk {
    ic_vec3 center;           /* horizontal disk (normal ±z) */
    float radius;
    ic_vec3 emit;
} disk;

typedef struct scene {
    rect rects[4];
    int n_rects;
    disk disks[2];
    int n_disks;
    ic_vec3 sky;
} scene;

static void trace_scene(void *user, const ic_vec3 *org, const ic_vec3 *dir, uint32_t count, float *hit_dist,
                        ic_vec3 *radiance)
{
    const scene *s = user;
    for (uint32_t r = 0; r < count; ++r) {
        float best = INFINITY;
        ic_vec3 L = s->sky;
        for (int i = 0; i < s->n_rects; ++i) {
            const rect *q = &s->rects[i];
            ic_vec3 nrm = v3_cross(q->e1, q->e2);
            float dn = v3_dot(dir[r], nrm);
            if (dn == 0.0f)
                continue;
            float t = v3_dot(v3_sub(q->corner, org[r]), nrm) / dn;
            if (!(t > 1e-6f) || t >= best)
                continue;
            ic_vec3 h = v3_sub(v3_madd(org[r], dir[r], t), q->corner);
            float a = v3_dot(h, q->e1) / v3_len2(q->e1), b = v3_dot(h, q->e2) / v3_len2(q->e2);
            if (a < 0.0f || a > 1.0f || b < 0.0f || b > 1.0f)
                continue;
            best = t;
            L = q->emit;
        }
        for (int i = 0; i < s->n_disks; ++i) {
            const disk *d = &s->disks[i];
            if (dir[r].z == 0.0f)
                continue;
            float t = (d->center.z - org[r].z) / dir[r].z;
            if (!(t > 1e-6f) || t >= best)
                continue;
            ic_vec3 h = v3_sub(v3_madd(org[r], dir[r], t), d->center);
            if (h.x * h.x + h.y * h.y > d->radius * d->radius)
                continue;
            best = t;
            L = d->emit;
        }
        hit_dist[r] = best;
        radiance[r] = L;
    }
}

/* Irradiance at (p, n) from a rectangle of unit radiance, unoccluded (Lambert's polygon formula). */
static double rect_irradiance(const rect *q, ic_vec3 p, ic_vec3 n)
{
    ic_vec3 v[4] = {q->corner, v3_add(q->corner, q->e1), v3_add(v3_add(q->corner, q->e1), q->e2),
                    v3_add(q->corner, q->e2)};
    double sum = 0.0;
    for (int i = 0; i < 4; ++i) {
        ic_vec3 a = v3_norm(v3_sub(v[i], p)), b = v3_norm(v3_sub(v[(i + 1) % 4], p));
        double ang = acos(fmax(-1.0, fmin(1.0, (double)v3_dot(a, b))));
        sum += ang * v3_dot(v3_norm(v3_cross(a, b)), n);
    }
    return 0.5 * fabs(sum);
}

/* Closed form: unit-radiance rectangle a×b parallel to the receiver at height h, corner above p. */
static double rect_corner_irradiance(double a, double b, double h)
{
    double A = a / h, B = b / h;
    double F = (A / sqrt(1 + A * A) * atan(B / sqrt(1 + A * A)) + B / sqrt(1 + B * B) * atan(A / sqrt(1 + B * B))) /
               (2.0 * PI_D);
    return PI_D * F;
}

static ic_gatherer *make_gatherer(const ic_gather_opts *o, scene *s)
{
    ic_gatherer *g = NULL;
    ic_error err;
    ic_result r = ic_gatherer_create(o, trace_scene, s, &g, &err);
    CHECK(r == IC_OK, "ic_gatherer_create: %s", r == IC_OK ? "" : err.message);
    return g;
}

static ic_gather_result stratified(ic_gatherer *g, ic_vec3 p, ic_vec3 n, uint64_t key)
{
    ic_gather_point pt = {p, n, key};
    ic_gather_result r;
    memset(&r, 0, sizeof r);
    ic_result res = ic_gather_stratified(g, &pt, &r);
    CHECK(res == IC_OK, "ic_gather_stratified: %s", ic_result_name(res));
    return r;
}

static double vlen(ic_vec3 v) { return sqrt((double)v3_dot(v, v)); }
static ic_vec3 rotate_normal(ic_vec3 n, ic_vec3 axis, float a)
{
    /* Rodrigues, axis ⟂ n: n cos a + (axis × n) sin a */
    return v3_add(v3_scale(n, cosf(a)), v3_scale(v3_cross(axis, n), sinf(a)));
}

/* ---- tests ------------------------------------------------------------------------------------ */

static void test_uniform_sky(void)
{
    scene s = {.sky = {0.5f, 1.0f, 2.0f}};
    ic_gather_opts o = {0};
    ic_gatherer *g = make_gatherer(&o, &s);
    if (!g)
        return;
    ic_gather_result r = stratified(g, v3(0.3f, -0.2f, 0.0f), v3(0, 0, 1), 7);
    /* Every sample returns L and weighs π/(MN): E = πL up to float rounding. */
    CHECK_NEAR(r.irradiance.x, PI_D * 0.5, 1e-5, "sky E.r");
    CHECK_NEAR(r.irradiance.y, PI_D * 1.0, 1e-5, "sky E.g");
    CHECK_NEAR(r.irradiance.z, PI_D * 2.0, 1e-5, "sky E.b");
    for (int c = 0; c < 3; ++c) {
        CHECK(vlen(r.rot_grad[c]) < 1e-5, "sky rot grad %d = %g", c, vlen(r.rot_grad[c]));
        CHECK(vlen(r.trans_grad[c]) == 0.0, "sky trans grad %d = %g", c, vlen(r.trans_grad[c]));
    }
    CHECK(v3_maxc(r.sigma) < 1e-5f, "sky sigma %g", (double)v3_maxc(r.sigma));
    CHECK(r.harmonic_mean_dist == INFINITY && r.min_dist == INFINITY && r.hit_count == 0, "sky distances");
    CHECK(r.ray_count == 16u * 50u, "default 16x50 strata: %u rays", r.ray_count);
    CHECK(r.is_converged == 1, "stratified always converged");

    /* A tilted normal sees the same uniform sky. */
    r = stratified(g, v3(0, 0, 0), v3_norm(v3(0.3f, 0.4f, 0.8f)), 8);
    CHECK_NEAR(r.irradiance.y, PI_D, 1e-5, "sky E tilted");
    ic_gatherer_destroy(g);
}

static void test_rect_irradiance(void)
{
    /* 2×1.5 rectangle at height 1 with a corner above the origin, radiance 10 (grey), black sky. */
    scene s = {.n_rects = 1};
    s.rects[0] = (rect){{0, 0, 1}, {2, 0, 0}, {0, 1.5f, 0}, {10, 10, 10}};
    const double exact = 10.0 * rect_corner_irradiance(2.0, 1.5, 1.0);
    CHECK_NEAR(10.0 * rect_irradiance(&s.rects[0], v3(0, 0, 0), v3(0, 0, 1)), exact, 1e-6 * exact,
               "polygon formula = closed-form rectangle form factor");

    ic_gather_opts o = {.theta_strata = 32};
    ic_gatherer *g = make_gatherer(&o, &s);
    if (!g)
        return;
    /* 32×101 = 3232 rays: stated tolerance 1.5% of E per gather (measured worst over 20 keys ≈ 0.5%). */
    double worst = 0.0;
    for (uint64_t key = 0; key < 20; ++key) {
        ic_gather_result r = stratified(g, v3(0, 0, 0), v3(0, 0, 1), key);
        worst = fmax(worst, fabs(r.irradiance.y - exact) / exact);
    }
    printf("rect corner: exact E %.5f, worst rel. error over 20 keys %.4f\n", exact, worst);
    CHECK(worst < 0.015, "rect E worst rel error %g", worst);

    /* Harmonic mean distance: all hits lie on z = 1, so 1 ≤ R, and min ≥ 1. */
    ic_gather_result r = stratified(g, v3(0, 0, 0), v3(0, 0, 1), 1);
    CHECK(r.min_dist >= 0.999f && r.harmonic_mean_dist > r.min_dist, "distances: min %g hm %g",
          (double)r.min_dist, (double)r.harmonic_mean_dist);
    CHECK(r.hit_count > 0 && r.hit_count < r.ray_count, "some rays hit, some miss: %u of %u", r.hit_count,
          r.ray_count);
    ic_gatherer_destroy(g);
}

static void test_disk_irradiance(void)
{
    scene s = {.n_disks = 1};
    s.disks[0] = (disk){{0, 0, 2}, 1.0f, {5, 5, 5}};
    const double exact = PI_D * 5.0 * 1.0 / (1.0 + 4.0);
    ic_gather_opts o = {.theta_strata = 32};
    ic_gatherer *g = make_gatherer(&o, &s);
    if (!g)
        return;
    double worst = 0.0;
    for (uint64_t key = 0; key < 20; ++key) {
        ic_gather_result r = stratified(g, v3(0, 0, 0), v3(0, 0, 1), key);
        worst = fmax(worst, fabs(r.irradiance.y - exact) / exact);
    }
    printf("disk: exact E %.5f, worst rel. error over 20 keys %.4f\n", exact, worst);
    CHECK(worst < 0.015, "disk E worst rel error %g", worst);
    ic_gatherer_destroy(g);
}

/* Averages the gradients of K gathers (different keys) to separate formula bias from noise. */
static void mean_gradients(ic_gatherer *g, ic_vec3 p, ic_vec3 n, int K, ic_vec3 *rot, ic_vec3 *trans, double *E)
{
    *rot = *trans = v3s(0.0f);
    *E = 0.0;
    for (int k = 0; k < K; ++k) {
        ic_gather_result r = stratified(g, p, n, 1000 + (uint64_t)k);
        *rot = v3_add(*rot, v3_scale(r.rot_grad[1], 1.0f / K));
        *trans = v3_add(*trans, v3_scale(r.trans_grad[1], 1.0f / K));
        *E += r.irradiance.y / K;
    }
}

static void test_gradients_unoccluded(void)
{
    /* A bright rectangle off to one side, so the gradient is large and not aligned with the axes. */
    scene s = {.n_rects = 1};
    s.rects[0] = (rect){{0.4f, -0.3f, 1.0f}, {1.5f, 0, 0}, {0, 1.0f, 0}, {10, 10, 10}};
    const ic_vec3 p = v3(0, 0, 0), n = v3(0, 0, 1);
    /* Exact gradients by central differences of the polygon formula (δ = 1e-4, error O(δ²)). */
    const float d = 1e-4f;
    ic_vec3 fd_t = v3(
        (float)(10.0 * (rect_irradiance(&s.rects[0], v3(d, 0, 0), n) - rect_irradiance(&s.rects[0], v3(-d, 0, 0), n)) / (2 * d)),
        (float)(10.0 * (rect_irradiance(&s.rects[0], v3(0, d, 0), n) - rect_irradiance(&s.rects[0], v3(0, -d, 0), n)) / (2 * d)),
        0.0f);
    /* Rotational: rotating n by angle a about axis x̂ gives n_i × n = a x̂, so ∂E/∂a = ∇r·x̂. */
    ic_vec3 fd_r = v3(
        (float)(10.0 * (rect_irradiance(&s.rects[0], p, rotate_normal(n, v3(1, 0, 0), d)) -
                        rect_irradiance(&s.rects[0], p, rotate_normal(n, v3(1, 0, 0), -d))) / (2 * d)),
        (float)(10.0 * (rect_irradiance(&s.rects[0], p, rotate_normal(n, v3(0, 1, 0), d)) -
                        rect_irradiance(&s.rects[0], p, rotate_normal(n, v3(0, 1, 0), -d))) / (2 * d)),
        0.0f);

    for (int form = 0; form < 2; ++form) {
        ic_gather_opts o = {.theta_strata = 48, .tgrad = form ? IC_GATHER_TGRAD_WARD_HECKBERT : IC_GATHER_TGRAD_IMPROVED};
        ic_gatherer *g = make_gatherer(&o, &s);
        if (!g)
            return;
        ic_vec3 rot, trans;
        double E;
        mean_gradients(g, p, n, 8, &rot, &trans, &E);
        double et = vlen(v3_sub(trans, fd_t)) / vlen(fd_t), er = vlen(v3_sub(rot, fd_r)) / vlen(fd_r);
        printf("unoccluded %s: |∇t| %.4f (fd %.4f) rel err %.4f; |∇r| %.4f (fd %.4f) rel err %.4f\n",
               form ? "WH92    " : "improved", vlen(trans), vlen(fd_t), et, vlen(rot), vlen(fd_r), er);
        /* Stated tolerances: 8 gathers of 48×151 rays; translational within 5%, rotational within 3%
         * of the exact gradient's magnitude (measured: see the printed line). */
        if (form == 0)
            CHECK(et < 0.05, "improved translational gradient rel err %g", et);
        CHECK(er < 0.03, "rotational gradient rel err %g", er);
        ic_gatherer_destroy(g);
    }
}

static void test_gradients_occluded(void)
{
    /* Receiver z = 0; bright rectangle at height 1.2; a black occluder at height 0.5 hides part of it,
     * so the gradient is dominated by the occluder's moving silhouette. */
    scene s = {.n_rects = 2};
    s.rects[0] = (rect){{-0.5f, -1.0f, 1.2f}, {2.0f, 0, 0}, {0, 2.0f, 0}, {10, 10, 10}};
    s.rects[1] = (rect){{0.1f, -2.0f, 0.5f}, {2.0f, 0, 0}, {0, 1.8f, 0}, {0, 0, 0}};
    const ic_vec3 n = v3(0, 0, 1);
    const ic_vec3 points[3] = {{0, 0, 0}, {0.15f, 0.1f, 0}, {-0.1f, -0.25f, 0}};

    ic_gather_opts dense = {.theta_strata = 400};
    ic_gatherer *gd = make_gatherer(&dense, &s);
    ic_gather_opts oi = {.theta_strata = 48}, ow = {.theta_strata = 48, .tgrad = IC_GATHER_TGRAD_WARD_HECKBERT};
    ic_gatherer *gi = make_gatherer(&oi, &s), *gw = make_gatherer(&ow, &s);
    if (!gd || !gi || !gw)
        return;
    double sum_err_i = 0, sum_err_w = 0;
    for (int q = 0; q < 3; ++q) {
        const ic_vec3 p = points[q];
        /* Reference: central differences of dense gathers, same key, so the same jitter pattern. */
        const float d = 0.01f;
        ic_vec3 fd = v3s(0.0f);
        for (int axis = 0; axis < 2; ++axis) {
            ic_vec3 off = axis ? v3(0, d, 0) : v3(d, 0, 0);
            ic_gather_result a = stratified(gd, v3_add(p, off), n, 99), b = stratified(gd, v3_sub(p, off), n, 99);
            float g = (a.irradiance.y - b.irradiance.y) / (2 * d);
            if (axis)
                fd.y = g;
            else
                fd.x = g;
        }
        ic_vec3 rot, ti, tw;
        double E;
        mean_gradients(gi, p, n, 16, &rot, &ti, &E);
        mean_gradients(gw, p, n, 16, &rot, &tw, &E);
        double ei = vlen(v3_sub(ti, fd)) / vlen(fd), ew = vlen(v3_sub(tw, fd)) / vlen(fd);
        printf("occluded p%d: E %.4f  fd ∇t (%.4f %.4f)  improved (%.4f %.4f) err %.4f  WH92 (%.4f %.4f) err %.4f\n",
               q, E, (double)fd.x, (double)fd.y, (double)ti.x, (double)ti.y, ei, (double)tw.x, (double)tw.y, ew);
        /* Stated tolerance: the improved gradient within 10% of the finite difference at each point. */
        CHECK(ei < 0.10, "occluded p%d: improved gradient rel err %g", q, ei);
        sum_err_i += ei;
        sum_err_w += ew;
    }
    CHECK(sum_err_i < sum_err_w, "improved closer to finite differences than WH92: %g vs %g", sum_err_i, sum_err_w);
    ic_gatherer_destroy(gd);
    ic_gatherer_destroy(gi);
    ic_gatherer_destroy(gw);
}

static ic_gather_result progressive_one(ic_gatherer *g, ic_vec3 p, uint64_t key)
{
    ic_gather_point pt = {p, v3(0, 0, 1), key};
    ic_gather_result r;
    memset(&r, 0, sizeof r);
    ic_result res = ic_gather_progressive(g, &pt, 1, &r);
    CHECK(res == IC_OK, "ic_gather_progressive: %s", ic_result_name(res));
    return r;
}

static void test_progressive(void)
{
    /* Uniform sky: both halves agree exactly after the first round. */
    scene sky = {.sky = {1, 1, 1}};
    ic_gather_opts o = {.method = IC_GATHER_PROGRESSIVE};
    ic_gatherer *g = make_gatherer(&o, &sky);
    if (!g)
        return;
    ic_gather_result r = progressive_one(g, v3(0, 0, 0), 3);
    CHECK(r.ray_count == 4096 && r.is_converged, "uniform sky stops after round 0: %u rays", r.ray_count);
    CHECK_NEAR(r.irradiance.y, PI_D, 1e-5, "progressive sky E");
    CHECK(vlen(r.rot_grad[1]) < 1e-5, "progressive sky rot grad %g", vlen(r.rot_grad[1]));
    ic_gatherer_destroy(g);

    /* A small, very bright square (0.1 × 0.1 at height 1, radiance 4000, off-axis and turned 30° so its
     * edges align with no stratum) over a dim sky: a high-variance integrand. (A disk centred above the
     * point would be a poor test here: it covers sin²θ < c, an exact union of Hammersley strata, so both
     * halves see exactly the same hits and σ = 0 while the quantisation error is not.) */
    scene spot = {.n_rects = 1, .sky = {0.1f, 0.1f, 0.1f}};
    const float c30 = 0.8660254f, s30 = 0.5f;
    spot.rects[0] = (rect){{0.4f, 0.2f, 1.0f}, {0.1f * c30, 0.1f * s30, 0}, {-0.1f * s30, 0.1f * c30, 0},
                           {4000, 4000, 4000}};
    const double unit = rect_irradiance(&spot.rects[0], v3(0, 0, 0), v3(0, 0, 1));
    const double exact = 4000.0 * unit + 0.1 * (PI_D - unit);
    g = make_gatherer(&o, &spot);
    if (!g)
        return;
    int within1 = 0, within2 = 0, within3 = 0, more_rays = 0;
    double worst = 0.0, sum_err2 = 0.0, sum_sig2 = 0.0;
    uint64_t total_rays = 0;
    const int trials = 50;
    for (int t = 0; t < trials; ++t) {
        r = progressive_one(g, v3(0, 0, 0), 500 + (uint64_t)t);
        double err = fabs(r.irradiance.y - exact), sig = r.sigma.y;
        worst = fmax(worst, err / exact);
        within1 += err <= sig;
        within2 += err <= 2 * sig;
        within3 += err <= 3 * sig;
        sum_err2 += err * err;
        sum_sig2 += sig * sig;
        more_rays += r.ray_count > 4096;
        total_rays += r.ray_count;
    }
    const double calib = sqrt(sum_sig2 / sum_err2);
    printf("progressive bright square: exact %.4f, worst rel err %.4f, |err| <= 1/2/3 sigma in %d/%d/%d of %d, "
           "RMS(sigma)/RMS(err) %.3f, %d/%d used more than one round, mean rays %.0f\n",
           exact, worst, within1, within2, within3, trials, calib, more_rays, trials, (double)total_rays / trials);
    CHECK(more_rays >= trials * 8 / 10, "high variance needs more rounds than the uniform sky: %d/%d", more_rays, trials);
    CHECK((double)total_rays / trials > 3.0 * 4096, "mean rays %g", (double)total_rays / trials);
    /* σ = |E − E'| is a one-degree-of-freedom estimate of the error's scale (Křivánek et al. 2006 §4.3): for
     * independent halves E[σ²] = E[err²], and a single error then lies within σ only about half the
     * time. The Hammersley halves do a little better (the full net beats its halves), but records that
     * stop early are exactly those whose halves agreed by chance. Stated, from the measured 35/38/40 of
     * 50 and RMS ratio 1.73: |err| <= σ in >= 60%, |err| <= 3σ in >= 75% of the 50 trials, RMS(σ)/RMS(err)
     * in [0.5, 2.5], worst relative error < 8%. */
    CHECK(within1 >= 30, "|err| <= sigma in %d/50 trials", within1);
    CHECK(within3 >= 38, "|err| <= 3 sigma in %d/50 trials", within3);
    CHECK(calib > 0.5 && calib < 2.5, "sigma calibration %g", calib);
    CHECK(worst < 0.08, "progressive worst rel error %g", worst);
    ic_gatherer_destroy(g);
}

static void test_determinism(void)
{
    scene s = {.n_rects = 2, .sky = {0.2f, 0.3f, 0.4f}};
    s.rects[0] = (rect){{-0.5f, -1.0f, 1.2f}, {2.0f, 0, 0}, {0, 2.0f, 0}, {10, 8, 6}};
    s.rects[1] = (rect){{0.1f, -2.0f, 0.5f}, {2.0f, 0, 0}, {0, 1.8f, 0}, {0.1f, 0.1f, 0.1f}};
    enum { NP = 37 };
    ic_gather_point pts[NP];
    for (int i = 0; i < NP; ++i)
        pts[i] = (ic_gather_point){v3(0.05f * i - 0.9f, 0.03f * i - 0.5f, 0), v3_norm(v3(0.02f * i, 0, 1)),
                                   (uint64_t)i * 7919u};
    for (int method = 0; method < 2; ++method) {
        ic_gather_opts o = {.method = (ic_gather_method)method, .theta_strata = 12, .seed = 42,
                            .first_round_rays = 256, .max_rays = 4096, .threshold = 0.01f};
        ic_gather_result a[NP], b[NP], c[NP];
        memset(a, 0xAB, sizeof a);
        memset(b, 0xCD, sizeof b);
        memset(c, 0xEF, sizeof c);
        ic_error err;
        CHECK(ic_gather_batch(&o, trace_scene, &s, 1, pts, NP, a, &err) == IC_OK, "batch 1 thread");
        CHECK(ic_gather_batch(&o, trace_scene, &s, 2, pts, NP, b, &err) == IC_OK, "batch 2 threads");
        /* Point by point with a small trace batch: a different split of both points and rays. */
        ic_gather_opts o2 = o;
        o2.batch_rays = 96;
        ic_gatherer *g = make_gatherer(&o2, &s);
        if (!g)
            return;
        for (int i = 0; i < NP; ++i) {
            memset(&c[i], 0x11, sizeof c[i]);
            ic_result res = method ? ic_gather_progressive(g, &pts[i], 1, &c[i]) : ic_gather_stratified(g, &pts[i], &c[i]);
            CHECK(res == IC_OK, "single gather");
        }
        ic_gatherer_destroy(g);
        /* Compare field by field: the struct has no padding, but be explicit about what must match. */
        int same_ab = 1, same_ac = 1, rounds = 0;
        for (int i = 0; i < NP; ++i) {
            same_ab &= memcmp(&a[i], &b[i], sizeof a[i]) == 0;
            same_ac &= memcmp(&a[i], &c[i], sizeof a[i]) == 0;
            rounds += a[i].ray_count > 256;
        }
        CHECK(same_ab, "method %d: 1 vs 2 threads bit-identical", method);
        CHECK(same_ac, "method %d: batch vs single-point with other ray batching bit-identical", method);
        if (method)
            CHECK(rounds > 0 && rounds < NP, "progressive: a mix of early and late stops (%d of %d went on)", rounds, NP);
        /* A different seed changes the result. */
        o.seed = 43;
        CHECK(ic_gather_batch(&o, trace_scene, &s, 2, pts, 1, c, &err) == IC_OK, "seed 43");
        CHECK(memcmp(&a[0], &c[0], sizeof a[0]) != 0, "method %d: another seed gives another estimate", method);
    }
}

static void test_bad_input(void)
{
    scene s = {.sky = {1, 1, 1}};
    ic_gatherer *g = NULL;
    ic_error err;
    ic_gather_opts o = {.first_round_rays = 1000};
    CHECK(ic_gatherer_create(&o, trace_scene, &s, &g, &err) == IC_ERR_INVALID_ARG && g == NULL,
          "non-power-of-two round rejected");
    o = (ic_gather_opts){.first_round_rays = 4096, .max_rays = 1024};
    CHECK(ic_gatherer_create(&o, trace_scene, &s, &g, &err) == IC_ERR_INVALID_ARG, "max < first rejected");
    o = (ic_gather_opts){.theta_strata = 5000, .phi_strata = 5000};
    CHECK(ic_gatherer_create(&o, trace_scene, &s, &g, &err) == IC_ERR_INVALID_ARG, "huge grid rejected");
    /* M strata in θ with the default N = round(π·M): for these M, π·M lies within 0.5 of 2^32, 2·2^32 and
     * 3·2^32, where a 32-bit N wrapped to 0, 2 and 2 (an empty or tiny grid; the first passed the size
     * check and the gather then overran its buffers). Every one is far past the ray limit. */
    const uint32_t wrapping_m[3] = {1367130513u, 2734261027u, 4101391540u};
    for (int k = 0; k < 3; ++k) {
        o = (ic_gather_opts){.theta_strata = wrapping_m[k]};
        g = (ic_gatherer *)&s;
        CHECK(ic_gatherer_create(&o, trace_scene, &s, &g, &err) == IC_ERR_INVALID_ARG && g == NULL,
              "%u x default strata accepted", wrapping_m[k]);
    }
    CHECK(ic_gatherer_create(NULL, NULL, &s, &g, &err) == IC_ERR_INVALID_ARG, "NULL trace rejected");
    CHECK(ic_gatherer_create(NULL, trace_scene, &s, &g, &err) == IC_OK, "defaults");
    const ic_gather_opts *eff = ic_gatherer_opts(g);
    CHECK(eff && eff->theta_strata == 16 && eff->phi_strata == 50 && eff->max_rays == 65536 &&
              eff->threshold == 0.02f, "defaults filled in");
    ic_gather_point bad = {v3(0, 0, 0), v3(0, 0, 0), 1};
    ic_gather_result r;
    CHECK(ic_gather_stratified(g, &bad, &r) == IC_ERR_INVALID_ARG, "zero normal rejected");
    CHECK(ic_gather_progressive(g, &bad, 1, &r) == IC_ERR_INVALID_ARG, "zero normal rejected (progressive)");
    CHECK(ic_gather_progressive(g, NULL, 0, NULL) == IC_OK, "empty progressive call");
    CHECK(ic_gather_batch(NULL, trace_scene, &s, 2, &bad, 1, &r, &err) == IC_ERR_INVALID_ARG,
          "batch reports a bad point");
    ic_gatherer_destroy(g);
    ic_gatherer_destroy(NULL);
}

int main(void)
{
    test_uniform_sky();
    test_rect_irradiance();
    test_disk_irradiance();
    test_gradients_unoccluded();
    test_gradients_occluded();
    test_progressive();
    test_determinism();
    test_bad_input();
    TEST_MAIN_END();
}
