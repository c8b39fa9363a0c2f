/*
 * test_gather_hessian.c — the occlusion-aware translational gradient and tangent-plane Hessian of
 * irradiance (Schwarzhaupt et al. 2012; src/gather/gather_hessian.c) and the record extent it implies.
 *
 * References are exact: the irradiance of a rectangle by Lambert's polygon formula, and of the part of
 * it an occluder leaves visible, which is again a polygon: behind a vertical black wall (a fixed clip)
 * and under a horizontal black occluder whose shadow edge on the emitter moves with the point (the case
 * an occlusion-unaware Hessian gets wrong). Gradients and Hessians of the exact irradiance come from
 * central differences (δ = 10⁻³, error O(δ²) ≈ 10⁻⁶ relative). The gathers average K record keys so
 * that the checks measure the formula, not the noise of one record. Tolerances are stated at each
 * check and were set from the measured values printed beside them.
 */
#include "test_gather_scene.h"

/* Exact irradiance of one configuration at p (normal +z). */
typedef double (*exact_fn)(const double p[3]);

static gs_rect g_emitter;                 /* the emitter of the current configuration (radiance 10) */
static double g_clip_x;                   /* wall: visible part x <= g_clip_x */
static double g_occ_x, g_occ_h;           /* occluder: black for x >= g_occ_x at height g_occ_h */

static double clipped_rect(double x1, const double p[3])
{
    const double x0 = g_emitter.corner.x, y0 = g_emitter.corner.y, y1 = y0 + g_emitter.e2.y, z = g_emitter.corner.z;
    const double xe = fmin(x1, x0 + g_emitter.e1.x);
    if (xe <= x0)
        return 0.0;
    const double v[4][3] = {{x0, y0, z}, {xe, y0, z}, {xe, y1, z}, {x0, y1, z}};
    const double n[3] = {0, 0, 1};
    return 10.0 * gs_polygon_irradiance(v, 4, p, n);
}

static double exact_open(const double p[3]) { return clipped_rect(INFINITY, p); }
static double exact_wall(const double p[3]) { return clipped_rect(g_clip_x, p); }
/* The occluder's edge x = g_occ_x at height h_o shadows emitter points with
 * q_x > p_x + (g_occ_x − p_x)·h_e/h_o. */
static double exact_occluder(const double p[3])
{
    return clipped_rect(p[0] + (g_occ_x - p[0]) * g_emitter.corner.z / g_occ_h, p);
}

/* Gradient (x, y) and Hessian (xx, xy, yy) of f at p by central differences. */
static void finite_differences(exact_fn f, ic_vec3 pv, double grad[2], double hess[3])
{
    const double d = 1e-3;
    double p[3] = {pv.x, pv.y, pv.z};
    double v[3][3];
    for (int i = -1; i <= 1; ++i)
        for (int j = -1; j <= 1; ++j) {
            double q[3] = {p[0] + i * d, p[1] + j * d, p[2]};
            v[i + 1][j + 1] = f(q);
        }
    grad[0] = (v[2][1] - v[0][1]) / (2 * d);
    grad[1] = (v[1][2] - v[1][0]) / (2 * d);
    hess[0] = (v[2][1] - 2 * v[1][1] + v[0][1]) / (d * d);
    hess[1] = (v[2][2] - v[2][0] - v[0][2] + v[0][0]) / (4 * d * d);
    hess[2] = (v[1][2] - 2 * v[1][1] + v[1][0]) / (d * d);
}

/* Mean over K keys of the green channel's gradient (world x, y) and Hessian (world xx, xy, yy). */
static void mean_second_order(ic_gatherer *g, ic_vec3 p, int K, double grad[2], double hess[3], double *E)
{
    grad[0] = grad[1] = hess[0] = hess[1] = hess[2] = *E = 0.0;
    for (int k = 0; k < K; ++k) {
        ic_gather_result r = gs_gather(g, p, v3(0, 0, 1), 4000 + (uint64_t)k);
        CHECK(r.has_hessian == 1, "has_hessian");
        /* World-space Hessian from the tangent frame: H = h_tt t tᵀ + h_tb (t bᵀ + b tᵀ) + h_bb b bᵀ. */
        const ic_vec3 t = r.hessian_t, b = r.hessian_b;
        const float *h = r.hessian[1];
        hess[0] += (h[0] * t.x * t.x + 2 * h[1] * t.x * b.x + h[2] * b.x * b.x) / K;
        hess[1] += (h[0] * t.x * t.y + h[1] * (t.x * b.y + b.x * t.y) + h[2] * b.x * b.y) / K;
        hess[2] += (h[0] * t.y * t.y + 2 * h[1] * t.y * b.y + h[2] * b.y * b.y) / K;
        grad[0] += r.trans_grad[1].x / K;
        grad[1] += r.trans_grad[1].y / K;
        *E += r.irradiance.y / K;
    }
}

static double norm2(const double *a, int n)
{
    double s = 0;
    for (int i = 0; i < n; ++i)
        s += a[i] * a[i];
    return sqrt(s);
}

/* Relative error of a symmetric 2×2 (xx, xy, yy) in the Frobenius norm. */
static double hess_rel_err(const double *h, const double *ref)
{
    const double d[4] = {h[0] - ref[0], h[1] - ref[1], h[1] - ref[1], h[2] - ref[2]};
    const double r[4] = {ref[0], ref[1], ref[1], ref[2]};
    return norm2(d, 4) / norm2(r, 4);
}

typedef struct config {
    const char *name;
    exact_fn exact;
    ic_vec3 points[3];
    double tol_grad, tol_hess;      /* stated tolerances, relative */
} config;

static void run_config(gs_scene *s, const config *c)
{
    ic_gather_opts os = {.theta_strata = 48, .with_hessian = 1};
    ic_gather_opts oh = {.method = IC_GATHER_HEMICUBE, .hemicube_resolution = 64, .with_hessian = 1};
    ic_gatherer *gs = gs_gatherer(&os, s), *gh = gs_gatherer(&oh, s);
    if (!gs || !gh)
        return;
    for (int q = 0; q < 3; ++q) {
        const ic_vec3 p = c->points[q];
        double fg[2], fh[3];
        finite_differences(c->exact, p, fg, fh);
        double pd[3] = {p.x, p.y, p.z};
        const double E = c->exact(pd);
        for (int m = 0; m < 2; ++m) {
            double sg[2], sh[3], sE;
            mean_second_order(m ? gh : gs, p, m ? 4 : 16, sg, sh, &sE);
            const double dg[2] = {sg[0] - fg[0], sg[1] - fg[1]};
            const double eg = norm2(dg, 2) / norm2(fg, 2), eh = hess_rel_err(sh, fh);
            printf("%-9s p%d %s: E %.4f (exact %.4f)  ∇E (%.3f %.3f) fd (%.3f %.3f) err %.3f  "
                   "H (%.2f %.2f %.2f) fd (%.2f %.2f %.2f) err %.3f\n",
                   c->name, q, m ? "hemicube-64  " : "strat-48x151", sE, E, sg[0], sg[1], fg[0], fg[1], eg, sh[0], sh[1],
                   sh[2], fh[0], fh[1], fh[2], eh);
            CHECK(eg < c->tol_grad, "%s p%d method %d: gradient rel err %g", c->name, q, m, eg);
            CHECK(eh < c->tol_hess, "%s p%d method %d: Hessian rel err %g", c->name, q, m, eh);
        }
    }
    ic_gatherer_destroy(gs);
    ic_gatherer_destroy(gh);
}

static void test_open_emitter(void)
{
    gs_scene s = {.n_rects = 1};
    g_emitter = s.rects[0] = (gs_rect){{-1.0f, -0.8f, 1.0f}, {2.2f, 0, 0}, {0, 1.6f, 0}, {10, 10, 10}};
    /* Under the middle, under an edge, and outside past a corner. */
    const config c = {"open", exact_open, {{0.1f, 0.1f, 0}, {1.1f, -0.3f, 0}, {1.6f, 1.2f, 0}}, 0.05, 0.10};
    run_config(&s, &c);
}

static void test_wall(void)
{
    /* The emitter of test_open_emitter, and a black vertical wall x = 0.3 (height 2) next to the points:
     * the visible emitter is clipped at x = 0.3, the wall's top edge at the emitter's height. The
     * split sphere would take the wall's small distance as the record radius; the irradiance next to
     * the wall in fact varies smoothly along it. */
    gs_scene s = {.n_rects = 2};
    g_emitter = s.rects[0] = (gs_rect){{-1.5f, -1.0f, 1.0f}, {3.0f, 0, 0}, {0, 2.2f, 0}, {10, 10, 10}};
    s.rects[1] = (gs_rect){{0.3f, -5.0f, 0.0f}, {0, 10.0f, 0}, {0, 0, 2.0f}, {0, 0, 0}};
    g_clip_x = 0.3;
    /* Stated: gradient within 25%, Hessian within 30%. The points see the wall at grazing incidence
     * (p2 is 0.1 from it): a cell's hit on the wall lies well above the emitter's edge, so the nearer
     * distance of the two cells at the edge is not the edge's own distance. That bias of the cell model
     * is shared by the first-order gradient (measured 3–18%) and shrinks with finer cells (the hemicube's
     * 64² beats the 48×151 grid at every point); 7–23% measured for the Hessian. */
    const config c = {"wall", exact_wall, {{0.1f, 0.0f, 0}, {-0.2f, 0.3f, 0}, {0.2f, -0.5f, 0}}, 0.25, 0.30};
    run_config(&s, &c);
}

static void test_occluder(void)
{
    /* Emitter at height 1.2; a black horizontal occluder at height 0.5 covering x >= 0.2: its edge casts
     * a shadow edge on the emitter that moves 1.4× faster than the point, at the occluder's depth. */
    gs_scene s = {.n_rects = 2};
    g_emitter = s.rects[0] = (gs_rect){{-1.0f, -1.0f, 1.2f}, {2.5f, 0, 0}, {0, 2.0f, 0}, {10, 10, 10}};
    s.rects[1] = (gs_rect){{0.2f, -10.0f, 0.5f}, {10.0f, 0, 0}, {0, 20.0f, 0}, {0, 0, 0}};
    g_occ_x = 0.2;
    g_occ_h = 0.5;
    const config c = {"occluder", exact_occluder, {{0.0f, 0.0f, 0}, {-0.1f, 0.2f, 0}, {0.05f, -0.3f, 0}}, 0.05, 0.15};
    run_config(&s, &c);
}

static void test_sky_and_off(void)
{
    gs_scene s = {.sky = {1, 2, 3}};
    for (int m = 0; m < 2; ++m) {
        ic_gather_opts o = {.method = m ? IC_GATHER_HEMICUBE : IC_GATHER_STRATIFIED, .with_hessian = 1};
        ic_gatherer *g = gs_gatherer(&o, &s);
        if (!g)
            return;
        ic_gather_result r = gs_gather(g, v3(0, 0, 0), v3_norm(v3(0.2f, 0.1f, 1)), 9);
        int zero = 1;
        for (int c = 0; c < 3; ++c)
            for (int i = 0; i < 3; ++i)
                zero &= r.hessian[c][i] == 0.0f;
        CHECK(r.has_hessian == 1 && zero, "method %d: uniform sky Hessian exactly 0", m);
        CHECK(fabs(v3_dot(r.hessian_t, r.hessian_b)) < 1e-6 && fabs(gs_len(r.hessian_t) - 1) < 1e-6, "frame");
        ic_gatherer_destroy(g);
        /* Off (default): the fields are zero, whatever the struct held before. */
        o.with_hessian = 0;
        g = gs_gatherer(&o, &s);
        if (!g)
            return;
        r = gs_gather(g, v3(0, 0, 0), v3(0, 0, 1), 9);
        zero = r.has_hessian == 0 && r.hessian_t.x == 0.0f && r.hessian_b.y == 0.0f;
        for (int c = 0; c < 3; ++c)
            for (int i = 0; i < 3; ++i)
                zero &= r.hessian[c][i] == 0.0f;
        CHECK(zero, "method %d: no Hessian by default, fields zeroed", m);
        ic_gatherer_destroy(g);
    }
    /* The progressive sampler has no Hessian: has_hessian stays 0. */
    ic_gather_opts o = {.method = IC_GATHER_PROGRESSIVE, .with_hessian = 1};
    ic_gatherer *g = gs_gatherer(&o, &s);
    if (!g)
        return;
    ic_gather_point pt = {v3(0, 0, 0), v3(0, 0, 1), 1};
    ic_gather_result r;
    memset(&r, 0x7F, sizeof r);
    CHECK(ic_gather_progressive(g, &pt, 1, &r) == IC_OK && r.has_hessian == 0, "progressive: no Hessian");
    ic_gatherer_destroy(g);
}

/* A result holding a given luminance Hessian (all channels equal: the Rec. 709 weights sum to 1). */
static ic_gather_result synthetic(double l0, double l1, double angle, float E)
{
    ic_gather_result r;
    memset(&r, 0, sizeof r);
    r.has_hessian = 1;
    r.hessian_t = v3_norm(v3(1, 0.2f, 0));
    r.hessian_b = v3_norm(v3_cross(v3(0, 0, 1), r.hessian_t));
    const double c = cos(angle), s = sin(angle);
    const double h[3] = {c * c * l0 + s * s * l1, c * s * (l0 - l1), s * s * l0 + c * c * l1};
    for (int ch = 0; ch < 3; ++ch)
        for (int i = 0; i < 3; ++i)
            r.hessian[ch][i] = (float)h[i];
    r.irradiance = v3s(E);
    return r;
}

/* ½ dᵀHd for a world-space tangent d. */
static double second_order(const ic_gather_result *r, ic_vec3 d)
{
    const double dt = v3_dot(d, r->hessian_t), db = v3_dot(d, r->hessian_b);
    const float *h = r->hessian[1];
    return 0.5 * (h[0] * dt * dt + 2 * h[1] * dt * db + h[2] * db * db);
}

static void test_extent(void)
{
    const float E = 5.0f, eps = 0.1f;
    ic_gather_extent_opts o = {.rel_error = eps};
    ic_gather_extent x;
    /* A saddle: λ = −8 and 2, turned by 0.7 rad. */
    ic_gather_result r = synthetic(-8.0, 2.0, 0.7, E);
    CHECK(ic_gather_hessian_extent(&r, &o, &x) == IC_OK, "extent");
    CHECK_NEAR(x.eigenvalue[0], -8.0, 1e-5, "λ0");
    CHECK_NEAR(x.eigenvalue[1], 2.0, 1e-5, "λ1");
    CHECK_NEAR(x.semi_axis[0], sqrt(2 * 0.1 * 5 / 8.0), 1e-6, "semi-axis 0 = √(2εE/|λ0|)");
    CHECK_NEAR(x.semi_axis[1], sqrt(2 * 0.1 * 5 / 2.0), 1e-6, "semi-axis 1");
    CHECK_NEAR(x.radius, x.semi_axis[0], 0, "radius = the smaller semi-axis");
    CHECK(fabs(v3_dot(x.axis[0], x.axis[1])) < 1e-6 && fabs(gs_len(x.axis[0]) - 1) < 1e-6, "orthonormal axes");
    /* On the ellipse boundary the second-order error is ε·E in magnitude. */
    for (int k = 0; k < 2; ++k) {
        double e2 = fabs(second_order(&r, v3_scale(x.axis[k], x.semi_axis[k])));
        CHECK_NEAR(e2, eps * E, 1e-5, "½ dᵀHd = εE at the end of each axis");
    }
    /* A bowl (λ = 6 and 1.5): every boundary point of the ellipse has ½ dᵀHd = εE. */
    r = synthetic(1.5, 6.0, -0.3, E);
    CHECK(ic_gather_hessian_extent(&r, &o, &x) == IC_OK, "bowl extent");
    double worst = 0;
    for (int k = 0; k < 16; ++k) {
        double a = 2 * GS_PI * k / 16;
        ic_vec3 d = v3_add(v3_scale(x.axis[0], x.semi_axis[0] * (float)cos(a)), v3_scale(x.axis[1], x.semi_axis[1] * (float)sin(a)));
        worst = fmax(worst, fabs(second_order(&r, d) - eps * E));
    }
    CHECK(worst < 1e-5, "ellipse boundary: ½ dᵀHd − εE up to %g", worst);
    CHECK_NEAR(x.radius, sqrt(2 * 0.1 * 5 / 6.0), 1e-6, "isotropic radius from max |λ|");

    /* Clamps: a flat environment gives max_radius, min_radius floors, min_irradiance floors E. */
    r = synthetic(0, 0, 0, E);
    o = (ic_gather_extent_opts){.rel_error = eps, .max_radius = 3};
    CHECK(ic_gather_hessian_extent(&r, &o, &x) == IC_OK && x.radius == 3.0f && x.semi_axis[1] == 3.0f, "flat: max_radius");
    o = (ic_gather_extent_opts){0};
    CHECK(ic_gather_hessian_extent(&r, &o, &x) == IC_OK && x.radius == INFINITY, "flat, no clamp: unbounded");
    r = synthetic(-8, 2, 0.7, E);
    o = (ic_gather_extent_opts){.rel_error = eps, .min_radius = 0.5f};
    CHECK(ic_gather_hessian_extent(&r, &o, &x) == IC_OK && x.radius == 0.5f && x.semi_axis[1] > 0.5f, "min_radius");
    r = synthetic(-8, 2, 0.7, 0.0f);
    o = (ic_gather_extent_opts){.rel_error = eps, .min_irradiance = 5.0f};
    CHECK(ic_gather_hessian_extent(&r, &o, &x) == IC_OK && fabs(x.radius - sqrt(2 * 0.1 * 5 / 8.0)) < 1e-6,
          "black record: E floored by min_irradiance");
    o = (ic_gather_extent_opts){.rel_error = -1};
    CHECK(ic_gather_hessian_extent(&r, &o, &x) == IC_ERR_INVALID_ARG, "negative ε rejected");
    o = (ic_gather_extent_opts){.min_radius = 2, .max_radius = 1};
    CHECK(ic_gather_hessian_extent(&r, &o, &x) == IC_ERR_INVALID_ARG, "min > max rejected");
    r.has_hessian = 0;
    CHECK(ic_gather_hessian_extent(&r, NULL, &x) == IC_ERR_INVALID_ARG, "no Hessian rejected");

    /* From a gather: next to the open emitter's edge, the exact irradiance at the extent's radius along
     * axis 0 departs from its first-order extrapolation by about ε·E. */
    gs_scene s = {.n_rects = 1};
    g_emitter = s.rects[0] = (gs_rect){{-1.0f, -0.8f, 1.0f}, {2.2f, 0, 0}, {0, 1.6f, 0}, {10, 10, 10}};
    ic_gather_opts go = {.theta_strata = 48, .with_hessian = 1};
    ic_gatherer *g = gs_gatherer(&go, &s);
    if (!g)
        return;
    const ic_vec3 p = v3(1.1f, -0.3f, 0);
    r = gs_gather(g, p, v3(0, 0, 1), 11);
    o = (ic_gather_extent_opts){.rel_error = 0.02f};
    CHECK(ic_gather_hessian_extent(&r, &o, &x) == IC_OK, "gather extent");
    double fg[2], fh[3], pd[3] = {p.x, p.y, 0};
    finite_differences(exact_open, p, fg, fh);
    const double E0 = exact_open(pd);
    double ratio[2];
    for (int k = 0; k < 2; ++k) {
        /* Both directions ±axis: the odd third-order term cancels in the mean. */
        double err = 0;
        for (int sgn = -1; sgn <= 1; sgn += 2) {
            ic_vec3 d = v3_scale(x.axis[k], sgn * x.semi_axis[k]);
            double q[3] = {p.x + d.x, p.y + d.y, 0};
            err += 0.5 * fabs(exact_open(q) - E0 - (fg[0] * d.x + fg[1] * d.y));
        }
        ratio[k] = err / (0.02 * v3_lum(r.irradiance));
    }
    printf("extent at the emitter's edge: radius %.4f, semi-axes %.4f %.4f; exact second-order error / εE "
           "along them %.3f %.3f\n", (double)x.radius, (double)x.semi_axis[0], (double)x.semi_axis[1], ratio[0], ratio[1]);
    /* Stated: within 25% of εE along the major-curvature axis (measured above). */
    CHECK(fabs(ratio[0] - 1.0) < 0.25, "second-order error at the radius / εE = %g", ratio[0]);
    ic_gatherer_destroy(g);
}

static void test_determinism(void)
{
    gs_scene s = {.n_rects = 2, .sky = {0.2f, 0.3f, 0.4f}};
    s.rects[0] = (gs_rect){{-0.5f, -1.0f, 1.2f}, {2.0f, 0, 0}, {0, 2.0f, 0}, {10, 8, 6}};
    s.rects[1] = (gs_rect){{0.1f, -2.0f, 0.5f}, {2.0f, 0, 0}, {0, 1.8f, 0}, {0.1f, 0.1f, 0.1f}};
    enum { NP = 27 };
    ic_gather_point pts[NP];
    for (int i = 0; i < NP; ++i)
        pts[i] = (ic_gather_point){v3(0.05f * i - 0.9f, 0.03f * i - 0.5f, 0), v3_norm(v3(0.02f * i, 0, 1)), (uint64_t)i * 7919u};
    ic_gather_opts o = {.theta_strata = 12, .seed = 42, .with_hessian = 1};
    ic_gather_result a[NP], b[NP];
    memset(a, 0xAB, sizeof a);
    memset(b, 0xCD, sizeof b);
    ic_error err;
    CHECK(ic_gather_batch(&o, gs_trace, &s, 1, pts, NP, a, &err) == IC_OK, "batch 1 thread");
    CHECK(ic_gather_batch(&o, gs_trace, &s, 2, pts, NP, b, &err) == IC_OK, "batch 2 threads");
    int same = 1, has = 1;
    for (int i = 0; i < NP; ++i) {
        same &= memcmp(&a[i], &b[i], sizeof a[i]) == 0;
        has &= a[i].has_hessian == 1;
    }
    CHECK(same && has, "stratified with Hessian: 1 vs 2 threads bit-identical");
}

int main(void)
{
    test_sky_and_off();
    test_open_emitter();
    test_wall();
    test_occluder();
    test_extent();
    test_determinism();
    TEST_MAIN_END();
}
