/*
 * test_hsh.c — hemispherical harmonics (include/irrcache/hsh.h) against analytic answers and brute force.
 *
 *   - the basis: Gram matrix by exact Gauss–Legendre × uniform-φ quadrature (written here, independent of
 *     the library's) equals the identity; the first functions equal their closed forms (Gautron et al.
 *     2004); zero below the horizon;
 *   - projection: a constant and cosθ projected by quadrature reconstruct exactly; the Monte Carlo
 *     projection of a smooth function converges to the quadrature projection as samples grow;
 *   - rotation: for functions that vanish within 45° of the horizon, the reference rotation inverts and
 *     composes, and commutes with projection (up to the function's own truncation error, measured);
 *     the fast approximation (Křivánek et al. 2008) stays within a stated bound for β ≤ 20°;
 *   - lobes: white furnace with the normalised modified Phong lobe (Lafortune & Willems 1994): Λ of a
 *     constant environment dotted with C(ω_o) equals the directional albedo found by importance-sampled
 *     brute force; the lobe table matches direct projection; the truncation error table is printed.
 * Tolerances are stated at each check and were set from the measured errors with a margin.
 */
#include "irrcache/hsh.h"

#include "core/rng.h"
#include "core/sampling.h"
#include "core/vecmath.h"
#include "test_util.h"

#include <string.h>

static const double PI_D = 3.14159265358979323846;

/* ---- independent quadrature ------------------------------------------------------------------ */

/* Gauss–Legendre on [0, 1] by Newton on the three-term recurrence. */
static void gauss01(int n, double *x, double *w)
{
    for (int i = 0; i < n; ++i) {
        double z = cos(PI_D * (i + 0.75) / (n + 0.5)), dp = 1.0;
        for (int it = 0; it < 60; ++it) {
            double p0 = 1.0, p1 = z;
            for (int k = 2; k <= n; ++k) {
                double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (z * p1 - p0) / (z * z - 1.0);
            z -= p1 / dp;
        }
        x[i] = 0.5 * (1.0 - z);
        w[i] = 1.0 / ((1.0 - z * z) * dp * dp);
    }
}

static ic_hsh_basis *make_basis(uint32_t order, uint32_t sh_order)
{
    ic_hsh_opts o = {order, sh_order};
    ic_hsh_basis *b = NULL;
    ic_error err;
    ic_result r = ic_hsh_basis_create(&o, &b, &err);
    CHECK(r == IC_OK, "create order %u: %s", order, r == IC_OK ? "" : err.message);
    return b;
}

static double rel_l2(const float *a, const float *b, uint32_t n)
{
    double e = 0.0, s = 0.0;
    for (uint32_t k = 0; k < n; ++k) {
        e += ((double)a[k] - b[k]) * ((double)a[k] - b[k]);
        s += (double)b[k] * b[k];
    }
    return sqrt(e / (s > 0.0 ? s : 1.0));
}

/* ---- basis ----------------------------------------------------------------------------------- */

static void test_orthonormality(void)
{
    static const uint32_t orders[] = {1, 3, 10, 16, 24};
    for (size_t oi = 0; oi < sizeof orders / sizeof orders[0]; ++oi) {
        uint32_t n = orders[oi];
        ic_hsh_basis *b = make_basis(n, 0);
        if (!b)
            return;
        uint32_t cnt = n * n;
        /* Products H_k H_k' with equal m are polynomials in z of degree ≤ 2n − 2 (the half-integer powers
         * pair up), so n + 2 Gauss nodes in z are exact; 2n + 2 uniform φ nodes integrate the trigonometric
         * products of degree ≤ 2n − 2 exactly. */
        int nz = (int)n + 2, np = 2 * (int)n + 2;
        double gx[64], gw[64];
        gauss01(nz, gx, gw);
        double *gram_d = calloc((size_t)cnt * cnt, sizeof *gram_d), *gram_f = calloc((size_t)cnt * cnt, sizeof *gram_f);
        double vd[IC_HSH_MAX_COUNT];
        float vf[IC_HSH_MAX_COUNT];
        for (int i = 0; i < nz; ++i)
            for (int j = 0; j < np; ++j) {
                double z = gx[i], r = sqrt(1.0 - z * z), phi = 2.0 * PI_D * (j + 0.37) / np;
                double d[3] = {r * cos(phi), r * sin(phi), z}, w = gw[i] * 2.0 * PI_D / np;
                ic_hsh_eval_d(b, d, vd);
                ic_hsh_eval(b, v3((float)d[0], (float)d[1], (float)d[2]), vf);
                for (uint32_t a = 0; a < cnt; ++a)
                    for (uint32_t c = 0; c < cnt; ++c) {
                        gram_d[a * cnt + c] += w * vd[a] * vd[c];
                        gram_f[a * cnt + c] += w * (double)vf[a] * vf[c];
                    }
            }
        double worst_d = 0.0, worst_f = 0.0;
        for (uint32_t a = 0; a < cnt; ++a)
            for (uint32_t c = 0; c < cnt; ++c) {
                double want = a == c ? 1.0 : 0.0;
                worst_d = fmax(worst_d, fabs(gram_d[a * cnt + c] - want));
                worst_f = fmax(worst_f, fabs(gram_f[a * cnt + c] - want));
            }
        printf("orthonormality, order %2u: max |Gram − I| = %.2e (double), %.2e (float)\n", n, worst_d, worst_f);
        CHECK(worst_d < 1e-10, "order %u: double Gram matrix off the identity by %.3g", n, worst_d);
        CHECK(worst_f < 2e-5, "order %u: float Gram matrix off the identity by %.3g", n, worst_f);
        free(gram_d);
        free(gram_f);
        ic_hsh_basis_destroy(b);
    }
}

static void test_closed_forms(void)
{
    ic_hsh_basis *b = make_basis(3, 0);
    if (!b)
        return;
    ic_rng r = ic_rng_make(7, 1, 2, 3);
    double worst = 0.0;
    for (int i = 0; i < 200; ++i) {
        ic_vec3 w = ic_warp_uniform_hemisphere(ic_rng_float(&r), ic_rng_float(&r));
        double d[3] = {w.x, w.y, w.z}, v[9];
        ic_hsh_eval_d(b, d, v);
        double z = w.z, u = 2.0 * z - 1.0, phi = atan2(w.y, w.x), s = 2.0 * sqrt(z * (1.0 - z));
        /* Gautron et al. 2004: H_0^0 = 1/√(2π), H_1^0 = √(3/2π)·u, H_1^{±1} = √(3/2π)·√(1 − u²)·(cos, sin)φ,
         * H_2^0 = √(5/2π)·(3u² − 1)/2, H_2^{±2} = √(15/8π)·(1 − u²)·(cos, sin)2φ (no Condon–Shortley phase). */
        double want[9] = {1.0 / sqrt(2 * PI_D),
                          sqrt(3 / (2 * PI_D)) * s * sin(phi),
                          sqrt(3 / (2 * PI_D)) * u,
                          sqrt(3 / (2 * PI_D)) * s * cos(phi),
                          sqrt(15 / (8 * PI_D)) * s * s * sin(2 * phi),
                          sqrt(15 / (2 * PI_D)) * s * u * sin(phi),
                          sqrt(5 / (2 * PI_D)) * 0.5 * (3 * u * u - 1),
                          sqrt(15 / (2 * PI_D)) * s * u * cos(phi),
                          sqrt(15 / (8 * PI_D)) * s * s * cos(2 * phi)};
        for (int k = 0; k < 9; ++k)
            worst = fmax(worst, fabs(v[k] - want[k]));
    }
    CHECK(worst < 1e-12, "closed forms of the first 9 functions: max error %.3g", worst);
    float below[9];
    ic_hsh_eval(b, v3(0.6f, 0.0f, -0.8f), below);
    int all_zero = 1;
    for (int k = 0; k < 9; ++k)
        all_zero &= below[k] == 0.0f;
    CHECK(all_zero, "basis not zero below the horizon");
    ic_hsh_basis_destroy(b);
}

/* ---- projection ------------------------------------------------------------------------------ */

static double fn_constant(void *user, const double d[3])
{
    (void)d;
    return *(const double *)user;
}

static double fn_cosine(void *user, const double d[3])
{
    (void)user;
    return d[2];
}

/* A smooth function with every order of HSH present. */
static double fn_smooth(void *user, const double d[3])
{
    (void)user;
    return 1.0 + 0.5 * d[0] - 0.3 * d[1] + d[2] * d[2] + 0.4 * exp(2.0 * d[0] * d[2]);
}

static void test_exact_projection(void)
{
    ic_hsh_basis *b = make_basis(6, 0);
    if (!b)
        return;
    float cc[36], cz[36];
    double L = 2.5;
    ic_error err;
    CHECK(ic_hsh_project_function(b, fn_constant, &L, NULL, cc, NULL, &err) == IC_OK, "project constant");
    CHECK(ic_hsh_project_function(b, fn_cosine, NULL, NULL, cz, NULL, &err) == IC_OK, "project cosine");
    /* Exactly: a constant is L·√(2π)·H_0; cosθ = (u + 1)/2 = √(π/2)·H_0 + √(π/6)·H_1^0. */
    CHECK_NEAR(cc[0], L * sqrt(2 * PI_D), 1e-5, "constant: coefficient 0");
    CHECK_NEAR(cz[0], sqrt(PI_D / 2), 1e-6, "cosine: coefficient 0");
    CHECK_NEAR(cz[2], sqrt(PI_D / 6), 1e-6, "cosine: coefficient (1, 0)");
    double worst_c = 0.0, worst_z = 0.0, other = 0.0;
    for (int k = 1; k < 36; ++k) {
        other = fmax(other, fabs(cc[k]));
        if (k != 2)
            other = fmax(other, fabs(cz[k]));
    }
    ic_rng r = ic_rng_make(7, 2, 2, 3);
    for (int i = 0; i < 500; ++i) {
        ic_vec3 w = ic_warp_uniform_hemisphere(ic_rng_float(&r), ic_rng_float(&r));
        float vc, vz;
        ic_hsh_reconstruct(b, cc, 1, w, &vc);
        ic_hsh_reconstruct(b, cz, 1, w, &vz);
        worst_c = fmax(worst_c, fabs(vc - L));
        worst_z = fmax(worst_z, fabs(vz - w.z));
    }
    CHECK(other < 1e-6, "constant and cosine: other coefficients up to %.3g", other);
    CHECK(worst_c < 1e-5 * L, "constant reconstructs with error %.3g", worst_c);
    CHECK(worst_z < 1e-6, "cosine reconstructs with error %.3g", worst_z);
    ic_hsh_basis_destroy(b);
}

static void test_monte_carlo_convergence(void)
{
    ic_hsh_basis *b = make_basis(5, 0);
    if (!b)
        return;
    float ref[25];
    ic_error err;
    CHECK(ic_hsh_project_function(b, fn_smooth, NULL, NULL, ref, NULL, &err) == IC_OK, "reference projection");
    static const uint32_t sides[] = {8, 32, 128}; /* 64, 1024, 16384 samples */
    double rms_cos[3], rms_uni[3];
    ic_vec3 *dirs = malloc(128 * 128 * sizeof *dirs), *rad = malloc(128 * 128 * sizeof *rad);
    float *pdf = malloc(128 * 128 * sizeof *pdf);
    for (int s = 0; s < 3; ++s) {
        double ec = 0.0, eu = 0.0;
        for (uint64_t seed = 0; seed < 8; ++seed) {
            ic_rng r = ic_rng_make(seed, 11, s, 0);
            uint32_t side = sides[s], count = side * side;
            float rgb[75];
            /* Jittered strata in the unit square, warped to the cosine-weighted hemisphere. */
            for (uint32_t i = 0; i < count; ++i) {
                float u1 = ((i % side) + ic_rng_float(&r)) / side, u2 = ((i / side) + ic_rng_float(&r)) / side;
                dirs[i] = ic_warp_cosine_hemisphere(u1, u2);
                double d[3] = {dirs[i].x, dirs[i].y, dirs[i].z};
                float f = (float)fn_smooth(NULL, d);
                rad[i] = v3(f, 2.0f * f, 0.0f);
            }
            ic_hsh_project_cosine(b, dirs, rad, count, rgb);
            ec += pow(rel_l2(rgb, ref, 25), 2.0);
            float g[25];
            for (int k = 0; k < 25; ++k)
                g[k] = 0.5f * rgb[25 + k];
            CHECK(rel_l2(g, rgb, 25) < 1e-6 && fabs(rgb[50]) == 0.0, "channels are independent");
            /* Plain uniform random directions with explicit pdfs. */
            for (uint32_t i = 0; i < count; ++i) {
                dirs[i] = ic_warp_uniform_hemisphere(ic_rng_float(&r), ic_rng_float(&r));
                pdf[i] = 1.0f / (2.0f * (float)PI_D);
                double d[3] = {dirs[i].x, dirs[i].y, dirs[i].z};
                rad[i] = v3s((float)fn_smooth(NULL, d));
            }
            ic_hsh_project(b, dirs, rad, pdf, count, rgb);
            eu += pow(rel_l2(rgb, ref, 25), 2.0);
        }
        rms_cos[s] = sqrt(ec / 8);
        rms_uni[s] = sqrt(eu / 8);
    }
    printf("Monte Carlo projection, relative L2 error (order 5, RMS of 8 seeds): 64 / 1024 / 16384 samples:\n"
           "  cosine, jittered: %.2e / %.2e / %.2e;  uniform, random: %.2e / %.2e / %.2e\n",
           rms_cos[0], rms_cos[1], rms_cos[2], rms_uni[0], rms_uni[1], rms_uni[2]);
    /* Random sampling: error ∝ N^−1/2, so ×16 samples give ÷4; jittered strata do better. Allow ÷2.5. */
    for (int s = 0; s < 2; ++s) {
        CHECK(rms_cos[s + 1] < rms_cos[s] / 2.5, "cosine projection does not converge: %.3g then %.3g", rms_cos[s],
              rms_cos[s + 1]);
        CHECK(rms_uni[s + 1] < rms_uni[s] / 2.5, "uniform projection does not converge: %.3g then %.3g", rms_uni[s],
              rms_uni[s + 1]);
    }
    /* Scale of the uniform estimator: the n² coefficient variances sum to about n²·‖f‖²/N (Σ_k H_k² averages
     * n²/2π), so the relative error is about n/√N; allow twice that. */
    CHECK(rms_uni[2] < 2.0 * 5.0 / 128.0, "16384 uniform samples: error %.3g above 2n/√N", rms_uni[2]);
    free(dirs);
    free(rad);
    free(pdf);
    ic_hsh_basis_destroy(b);
}

/* ---- rotation -------------------------------------------------------------------------------- */

/* A smooth bump around `axis`, zero beyond the cone cos_edge: x³ with x the normalised cosine distance
 * (twice continuously differentiable at its edge), times (1 + x/2) so that it is not symmetric about z. */
typedef struct bump {
    double axis[3];
    double cos_edge;
} bump;

static double fn_bump(void *user, const double d[3])
{
    const bump *p = user;
    double c = p->axis[0] * d[0] + p->axis[1] * d[1] + p->axis[2] * d[2];
    if (c <= p->cos_edge)
        return 0.0;
    double x = (c - p->cos_edge) / (1.0 - p->cos_edge);
    return x * x * x * (1.0 + 0.5 * d[0]);
}

/* ‖f − Σ c_k H_k‖² integrand, to measure a function's own truncation error. */
typedef struct residual {
    ic_hsh_function_fn f;
    void *user;
    const ic_hsh_basis *b;
    const float *c;
} residual;

static double fn_residual(void *user, const double d[3])
{
    const residual *r = user;
    double v = r->f(r->user, d), h[IC_HSH_MAX_COUNT];
    if (r->c) {
        ic_hsh_eval_d(r->b, d, h);
        for (uint32_t k = 0; k < ic_hsh_count(r->b); ++k)
            v -= r->c[k] * h[k];
    }
    return v * v;
}

/* ‖f − P_n f‖ / ‖f‖ by quadrature on the order-1 basis (coefficient 0 is ∫·/√(2π)). */
static double truncation_error(const ic_hsh_basis *b, ic_hsh_function_fn f, void *user, const float *c)
{
    ic_hsh_basis *b1 = make_basis(1, 0);
    ic_hsh_quad_opts q = {.tolerance = 1e-5};
    residual r0 = {f, user, b, NULL}, r1 = {f, user, b, c};
    float i0 = 0.0f, i1 = 0.0f;
    ic_error err;
    ic_hsh_project_function(b1, fn_residual, &r0, &q, &i0, NULL, &err);
    ic_hsh_project_function(b1, fn_residual, &r1, &q, &i1, NULL, &err);
    ic_hsh_basis_destroy(b1);
    return sqrt(fmax(0.0, i1) / i0);
}

/* The bump seen through a rotation: g(ω) = f(r⁻¹ω). */
typedef struct rotated {
    const bump *f;
    const ic_hsh_rotation *r;
} rotated;

static double fn_rotated(void *user, const double d[3])
{
    const rotated *g = user;
    double p[3];
    for (int i = 0; i < 3; ++i)
        p[i] = g->r->m[0][i] * d[0] + g->r->m[1][i] * d[1] + g->r->m[2][i] * d[2];
    if (p[2] < 0.0)
        return 0.0;
    return fn_bump((void *)g->f, p);
}

static void random_rotation(ic_rng *r, double beta_deg, ic_hsh_rotation *out)
{
    double a = 2 * PI_D * ic_rng_double(r), g = 2 * PI_D * ic_rng_double(r);
    ic_hsh_rotation_from_euler(a, beta_deg * PI_D / 180.0, g, out);
}

static void compose(const ic_hsh_rotation *a, const ic_hsh_rotation *b, ic_hsh_rotation *out) /* a·b */
{
    double m[9];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            m[i * 3 + j] = a->m[i][0] * b->m[0][j] + a->m[i][1] * b->m[1][j] + a->m[i][2] * b->m[2][j];
    ic_hsh_rotation_from_matrix(m, out);
}

static void test_rotation_exact(void)
{
    const uint32_t n = 12;
    ic_hsh_basis *b = make_basis(n, 0);
    if (!b)
        return;
    uint32_t cnt = n * n;
    /* Vanishes below 40° of elevation: rotations of up to 2 × 20° keep it above the horizon. */
    bump f = {{0.0, 0.0, 1.0}, cos(50.0 * PI_D / 180.0)};
    float lam[IC_HSH_MAX_COUNT], a[IC_HSH_MAX_COUNT], c[IC_HSH_MAX_COUNT], d[IC_HSH_MAX_COUNT];
    ic_error err;
    ic_hsh_project_function(b, fn_bump, &f, NULL, lam, NULL, &err);
    double trunc = truncation_error(b, fn_bump, &f, lam);
    double *scratch = malloc(ic_hsh_rotate_exact_scratch(b) * sizeof *scratch);
    ic_rng rng = ic_rng_make(3, 3, 3, 3);
    double worst_inv = 0.0, worst_comp = 0.0, worst_proj = 0.0;
    for (int trial = 0; trial < 6; ++trial) {
        ic_hsh_rotation r1, r2, r12, inv;
        random_rotation(&rng, 5.0 + 15.0 * ic_rng_double(&rng), &r1);
        random_rotation(&rng, 5.0 + 15.0 * ic_rng_double(&rng), &r2);
        ic_hsh_rotation_invert(&r1, &inv);
        CHECK(ic_hsh_rotate_exact(b, &r1, lam, 1, a, scratch) == IC_OK, "rotate");
        ic_hsh_rotate_exact(b, &inv, a, 1, c, NULL);
        worst_inv = fmax(worst_inv, rel_l2(c, lam, cnt));
        /* R1 then R2 against R2·R1 in one step. */
        ic_hsh_rotate_exact(b, &r2, a, 1, c, scratch);
        compose(&r2, &r1, &r12);
        ic_hsh_rotate_exact(b, &r12, lam, 1, d, scratch);
        worst_comp = fmax(worst_comp, rel_l2(c, d, cnt));
        /* Rotating the projection against projecting the rotated function. */
        rotated g = {&f, &r1};
        ic_hsh_project_function(b, fn_rotated, &g, NULL, c, NULL, &err);
        worst_proj = fmax(worst_proj, rel_l2(a, c, cnt));
    }
    printf("exact rotation, order %u, SH order %u, bump vanishing below 40° elevation (its own truncation error "
           "%.2e), β ≤ 20°:\n  R⁻¹ after R %.2e, R2 after R1 vs R2·R1 %.2e, rotate∘project vs project∘rotate %.2e\n",
           n, ic_hsh_sh_order(b), trunc, worst_inv, worst_comp, worst_proj);
    /* What is lost is the truncated expansion's ripple that the rotation moves below the horizon, of the
     * size of the truncation error itself: allow twice that (the measured errors are below it). */
    CHECK(worst_inv < 2.0 * trunc, "R⁻¹ after R: relative error %.3g (truncation %.3g)", worst_inv, trunc);
    CHECK(worst_comp < 2.0 * trunc, "R2 after R1 against R2·R1: relative error %.3g (truncation %.3g)", worst_comp, trunc);
    CHECK(worst_proj < 2.0 * trunc, "rotated projection against projection of the rotated bump: %.3g (truncation %.3g)",
          worst_proj, trunc);
    CHECK(trunc < 0.01, "the bump is not resolved at order %u (%.3g): the checks above say little", n, trunc);
    /* A pure z-rotation is exact both ways and agrees with ic_hsh_rotate_z. */
    ic_hsh_rotation rz;
    ic_hsh_rotation_from_euler(0.7, 0.0, 0.4, &rz);
    ic_hsh_rotate_exact(b, &rz, lam, 1, a, scratch);
    ic_hsh_rotate_z(b, 1.1, lam, 1, c);
    CHECK(rel_l2(a, c, cnt) < 1e-5, "z-rotation through SH against the direct one: %.3g", rel_l2(a, c, cnt));
    /* RGB: channels rotate independently and alias in place. */
    float rgb[3 * IC_HSH_MAX_COUNT], one[IC_HSH_MAX_COUNT];
    for (uint32_t k = 0; k < cnt; ++k) {
        rgb[k] = lam[k];
        rgb[cnt + k] = 2.0f * lam[k];
        rgb[2 * cnt + k] = -lam[k];
    }
    ic_hsh_rotation r;
    random_rotation(&rng, 15.0, &r);
    ic_hsh_rotate_exact(b, &r, lam, 1, one, scratch);
    ic_hsh_rotate_exact(b, &r, rgb, 3, rgb, scratch);
    for (uint32_t k = 0; k < cnt; ++k)
        c[k] = 0.5f * rgb[cnt + k];
    CHECK(rel_l2(rgb, one, cnt) < 1e-6 && rel_l2(c, one, cnt) < 1e-6, "RGB rotation in place differs per channel");
    free(scratch);
    ic_hsh_basis_destroy(b);
}

static void test_rotation_fast(void)
{
    static const uint32_t orders[] = {3, 5, 8};
    /* Stated bounds on the worst relative L2 error against the reference rotation, for bumps of 35° radius
     * within 15° of the normal, at β = 5°, 10°, 20° (measured values are about 2/3 of these). Past 10° the
     * expansion is no longer an approximation worth the name for such lobes: the bounds say so. */
    static const double bound2[3][3] = {{0.007, 0.06, 0.45}, {0.02, 0.14, 1.0}, {0.025, 0.18, 1.25}};
    static const double bound1[3][3] = {{0.05, 0.19, 0.7}, {0.09, 0.35, 1.2}, {0.11, 0.42, 1.5}};
    ic_error err;
    for (size_t oi = 0; oi < 3; ++oi) {
        uint32_t n = orders[oi], cnt = n * n;
        ic_hsh_basis *b = make_basis(n, 0);
        if (!b)
            return;
        float lam[IC_HSH_MAX_COUNT], ex[IC_HSH_MAX_COUNT], fa[IC_HSH_MAX_COUNT], f1[IC_HSH_MAX_COUNT];
        ic_rng rng = ic_rng_make(5, n, 0, 0);
        double worst2[3] = {0}, worst1[3] = {0}, mean2[3] = {0}, mean1[3] = {0};
        static const double betas[3] = {5.0, 10.0, 20.0};
        const int trials = 8;
        for (int trial = 0; trial < trials; ++trial) {
            double th = 15.0 * PI_D / 180.0 * ic_rng_double(&rng), ph = 2 * PI_D * ic_rng_double(&rng);
            bump f = {{sin(th) * cos(ph), sin(th) * sin(ph), cos(th)}, cos(35.0 * PI_D / 180.0)};
            ic_hsh_project_function(b, fn_bump, &f, NULL, lam, NULL, &err);
            for (int bi = 0; bi < 3; ++bi) {
                ic_hsh_rotation r;
                random_rotation(&rng, betas[bi], &r);
                ic_hsh_rotate_exact(b, &r, lam, 1, ex, NULL);
                ic_hsh_rotate_fast(b, &r, IC_HSH_TAYLOR_SECOND, lam, 1, fa);
                ic_hsh_rotate_fast(b, &r, IC_HSH_TAYLOR_FIRST, lam, 1, f1);
                double e2 = rel_l2(fa, ex, cnt), e1 = rel_l2(f1, ex, cnt);
                worst2[bi] = fmax(worst2[bi], e2);
                worst1[bi] = fmax(worst1[bi], e1);
                mean2[bi] += e2 / trials;
                mean1[bi] += e1 / trials;
            }
        }
        printf("fast rotation, order %u: worst relative L2 error vs exact at β = 5°/10°/20°: second order "
               "%.2e / %.2e / %.2e, first order %.2e / %.2e / %.2e\n",
               n, worst2[0], worst2[1], worst2[2], worst1[0], worst1[1], worst1[2]);
        for (int bi = 0; bi < 3; ++bi) {
            CHECK(worst2[bi] < bound2[oi][bi], "order %u, β %g°: second-order error %.3g above %.3g", n, betas[bi],
                  worst2[bi], bound2[oi][bi]);
            CHECK(worst1[bi] < bound1[oi][bi], "order %u, β %g°: first-order error %.3g above %.3g", n, betas[bi],
                  worst1[bi], bound1[oi][bi]);
        }
        /* A Taylor expansion's remainder: halving β divides the error by about 8 (second order) and 4 (first). */
        CHECK(mean2[0] / mean2[1] > 0.08 && mean2[0] / mean2[1] < 0.2, "order %u: second-order error ratio %.3g, "
              "expected about 1/8", n, mean2[0] / mean2[1]);
        CHECK(mean1[0] / mean1[1] > 0.18 && mean1[0] / mean1[1] < 0.35, "order %u: first-order error ratio %.3g, "
              "expected about 1/4", n, mean1[0] / mean1[1]);
        /* Identity and pure z-rotations are exact. */
        ic_hsh_rotation rz;
        ic_hsh_rotation_from_euler(0.3, 0.0, -1.2, &rz);
        ic_hsh_rotate_fast(b, &rz, IC_HSH_TAYLOR_SECOND, lam, 1, fa);
        ic_hsh_rotate_z(b, -0.9, lam, 1, ex);
        CHECK(rel_l2(fa, ex, cnt) < 1e-6, "order %u: fast z-rotation off by %.3g", n, rel_l2(fa, ex, cnt));
        ic_hsh_basis_destroy(b);
    }
}

static void test_frames(void)
{
    /* A record frame and a shading frame 25° apart: a direction's local coordinates in the two frames are
     * related by the rotation from the frames, and rotating its delta-like bump moves the peak there. */
    ic_hsh_frame from = {v3(1, 0, 0), v3(0, 1, 0), v3(0, 0, 1)};
    double a = 25.0 * PI_D / 180.0;
    ic_hsh_frame to = {v3((float)cos(a), 0, (float)-sin(a)), v3(0, 1, 0), v3((float)sin(a), 0, (float)cos(a))};
    ic_hsh_rotation r;
    ic_hsh_rotation_from_frames(&from, &to, &r);
    CHECK_NEAR(r.beta, a, 1e-6, "angle between the normals");
    ic_vec3 w = v3_norm(v3(0.3f, -0.2f, 0.9f)); /* world = from-local */
    ic_vec3 in_to = v3(v3_dot(w, to.tangent), v3_dot(w, to.bitangent), v3_dot(w, to.normal));
    double rw[3];
    for (int i = 0; i < 3; ++i)
        rw[i] = r.m[i][0] * w.x + r.m[i][1] * w.y + r.m[i][2] * w.z;
    CHECK(fabs(rw[0] - in_to.x) + fabs(rw[1] - in_to.y) + fabs(rw[2] - in_to.z) < 1e-6,
          "rotation from frames maps from-local to to-local coordinates");
    ic_hsh_rotation e;
    ic_hsh_rotation_from_euler(r.alpha, r.beta, r.gamma, &e);
    double dm = 0.0;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            dm = fmax(dm, fabs(e.m[i][j] - r.m[i][j]));
    CHECK(dm < 1e-6, "ZYZ angles rebuild the matrix (off by %.3g)", dm);
}

/* ---- lobes and the white furnace ----------------------------------------------------------------- */

typedef struct phong {
    double exponent, ks;
} phong;

/* Normalised modified Phong: ks·(n + 2)/(2π)·cos^n α, α between ω_i and the mirror direction of ω_o. */
static double brdf_phong(void *user, const double wi[3], const double wo[3])
{
    const phong *p = user;
    double c = -wi[0] * wo[0] - wi[1] * wo[1] + wi[2] * wo[2];
    return c > 0.0 ? p->ks * (p->exponent + 2.0) / (2.0 * PI_D) * pow(c, p->exponent) : 0.0;
}

/* Directional albedo ∫ f cosθ_i by importance sampling the cos^n α lobe around the mirror direction
 * (pdf (n+1)/(2π) cos^n α): ks·(n+2)/(n+1)·E[max(0, cosθ_i)], 512×512 jittered strata. */
static double albedo_brute_force(const phong *p, ic_vec3 wo)
{
    ic_frame fr = ic_frame_from_normal(v3(-wo.x, -wo.y, wo.z));
    ic_rng r = ic_rng_make(99, 1, 1, 1);
    double s = 0.0;
    const int side = 512;
    for (int i = 0; i < side; ++i)
        for (int j = 0; j < side; ++j) {
            ic_vec3 l = ic_warp_phong_lobe((i + ic_rng_float(&r)) / side, (j + ic_rng_float(&r)) / side,
                                           (float)p->exponent);
            ic_vec3 wi = ic_frame_to_world(&fr, l);
            s += wi.z > 0.0f ? wi.z : 0.0;
        }
    return p->ks * (p->exponent + 2.0) / (p->exponent + 1.0) * s / ((double)side * side);
}

/* (f·cosθ_i − its order-n projection)², integrated to measure the truncation error. */
typedef struct lobe_residual {
    phong p;
    double wo[3];
    const ic_hsh_basis *b;
    const float *c;
    uint32_t count;        /* coefficients kept: n² (0: the lobe itself) */
} lobe_residual;

static double fn_lobe_residual(void *user, const double d[3])
{
    const lobe_residual *l = user;
    double v = brdf_phong((void *)&l->p, d, l->wo) * d[2], h[IC_HSH_MAX_COUNT];
    if (l->count) {
        ic_hsh_eval_d(l->b, d, h);
        for (uint32_t k = 0; k < l->count; ++k)
            v -= l->c[k] * h[k];
    }
    return v * v;
}

static void test_white_furnace(void)
{
    const uint32_t nmax = 16;
    ic_hsh_basis *b = make_basis(nmax, 0), *b1 = make_basis(1, 0);
    if (!b || !b1)
        return;
    ic_error err;
    static const double exps[3] = {1.0, 10.0, 50.0}, views[3] = {0.0, 30.0, 60.0};
    static const uint32_t orders[5] = {3, 5, 8, 10, 16};
    double L = 1.7;
    float lam[IC_HSH_MAX_COUNT];
    CHECK(ic_hsh_project_function(b, fn_constant, &L, NULL, lam, NULL, &err) == IC_OK, "project L");
    printf("white furnace and truncation of the Phong lobe f·cosθ_i (relative L2 error of its order-n "
           "projection):\n  exp  view  albedo(brute)  Λ·C/L   ");
    for (int o = 0; o < 5; ++o)
        printf("  n=%-5u", orders[o]);
    printf("\n");
    for (int e = 0; e < 3; ++e)
        for (int v = 0; v < 3; ++v) {
            phong p = {exps[e], 0.8};
            double th = views[v] * PI_D / 180.0;
            ic_vec3 wo = v3((float)sin(th), 0.0f, (float)cos(th));
            float c[IC_HSH_MAX_COUNT];
            ic_hsh_quad_stats st;
            CHECK(ic_hsh_lobe_project(b, brdf_phong, &p, wo, NULL, c, &st, &err) == IC_OK, "lobe projection");
            double want = albedo_brute_force(&p, wo);
            double got = ic_hsh_dot(lam, c, ic_hsh_count(b)) / L; /* only Λ_0 is non-zero */
            CHECK(fabs(got - want) < 2e-4 * want, "exp %g view %g°: Λ·C/L = %.6f, brute-force albedo %.6f", exps[e],
                  views[v], got, want);
            CHECK(st.is_converged, "exp %g: quadrature stopped at %.3g", exps[e], st.error_estimate);
            /* ‖g‖² and ‖g − P_n g‖² by the same quadrature on the order-1 basis (H_0 = 1/√(2π)). */
            lobe_residual q = {p, {wo.x, wo.y, wo.z}, b, c, 0};
            ic_hsh_quad_opts qo = {.tolerance = 1e-5};
            float i0;
            ic_hsh_project_function(b1, fn_lobe_residual, &q, &qo, &i0, NULL, &err);
            double norm2 = i0 * sqrt(2.0 * PI_D), prev = 2.0;
            printf("  %-4g %-4g  %.6f       %.6f", exps[e], views[v], want, got);
            for (int o = 0; o < 5; ++o) {
                double cap = 0.0;
                q.count = orders[o] * orders[o];
                for (uint32_t k = 0; k < q.count; ++k)
                    cap += (double)c[k] * c[k];
                ic_hsh_project_function(b1, fn_lobe_residual, &q, &qo, &i0, NULL, &err);
                double rel = sqrt(fmax(0.0, i0 * sqrt(2.0 * PI_D)) / norm2);
                printf("  %.2e", rel);
                /* Bessel's inequality: the captured energy never exceeds the lobe's, the error shrinks with
                 * order, and Parseval: captured + residual = total. */
                CHECK(cap <= norm2 * (1.0 + 1e-5), "exp %g: projection has more energy than the lobe", exps[e]);
                CHECK(rel <= prev + 1e-6, "exp %g: truncation error grows with order", exps[e]);
                CHECK(fabs(cap + rel * rel * norm2 - norm2) < 1e-4 * norm2, "exp %g: Parseval off by %.3g", exps[e],
                      (cap + rel * rel * norm2 - norm2) / norm2);
                prev = rel;
            }
            printf("\n");
        }
    ic_hsh_basis_destroy(b);
    ic_hsh_basis_destroy(b1);
}

static void test_lobe_table(void)
{
    const uint32_t n = 6;
    ic_hsh_basis *b = make_basis(n, 0);
    if (!b)
        return;
    phong p = {20.0, 1.0};
    ic_hsh_lobe_table *t = NULL;
    ic_error err;
    CHECK(ic_hsh_lobe_table_create(b, brdf_phong, &p, NULL, &t, &err) == IC_OK, "lobe table");
    if (!t) {
        ic_hsh_basis_destroy(b);
        return;
    }
    ic_rng r = ic_rng_make(4, 4, 4, 4);
    double worst = 0.0;
    for (int i = 0; i < 12; ++i) {
        double th = (i == 0 ? 0.0 : 85.0 * ic_rng_double(&r)) * PI_D / 180.0, ph = 2 * PI_D * ic_rng_double(&r);
        ic_vec3 wo = v3((float)(sin(th) * cos(ph)), (float)(sin(th) * sin(ph)), (float)cos(th));
        float direct[36], table[36];
        ic_hsh_lobe_project(b, brdf_phong, &p, wo, NULL, direct, NULL, &err);
        ic_hsh_lobe_table_eval(t, wo, table);
        worst = fmax(worst, rel_l2(table, direct, n * n));
    }
    printf("lobe table (Phong exponent 20, order %u, 46 entries): worst relative L2 error vs direct %.2e\n", n, worst);
    CHECK(worst < 2e-3, "lobe table against direct projection: %.3g", worst);
    ic_hsh_lobe_table_destroy(t);
    ic_hsh_basis_destroy(b);
}

/* A Lambertian lobe that, like the renderer's BSDFs, is zero for a view at or below the horizon: its
 * lobe vector is the same at every view above it, so a table must reproduce it up to grazing. A last
 * entry built exactly at θ_o = 90° read zero and pulled the interpolation to zero above ~88° (and over
 * the true value at 86–88°). */
static double brdf_lambert_above(void *user, const double wi[3], const double wo[3])
{
    (void)user;
    return wi[2] > 0.0 && wo[2] > 0.0 ? 1.0 / PI_D : 0.0;
}

static void test_lobe_table_grazing(void)
{
    const uint32_t n = 6;
    ic_hsh_basis *b = make_basis(n, 0);
    if (!b)
        return;
    ic_hsh_lobe_table *t = NULL;
    ic_error err;
    CHECK(ic_hsh_lobe_table_create(b, brdf_lambert_above, NULL, NULL, &t, &err) == IC_OK, "lobe table");
    if (!t) {
        ic_hsh_basis_destroy(b);
        return;
    }
    static const double views[] = {80.0, 86.5, 87.0, 88.5, 89.0, 89.9, 90.0};
    for (size_t i = 0; i < sizeof views / sizeof views[0]; ++i) {
        const double th = views[i] * PI_D / 180.0;
        ic_vec3 wo = v3((float)sin(th), 0.0f, (float)fmax(cos(th), 1e-6));
        float direct[36], table[36];
        ic_hsh_lobe_project(b, brdf_lambert_above, NULL, wo, NULL, direct, NULL, &err);
        ic_hsh_lobe_table_eval(t, wo, table);
        const double e = rel_l2(table, direct, n * n);
        printf("lobe table, Lambertian above the horizon, view %.1f°: albedo %.5f (direct %.5f), relative L2 "
               "error %.2e\n", views[i], table[0] * sqrt(2.0 * PI_D), direct[0] * sqrt(2.0 * PI_D), e);
        CHECK(e < 1e-3, "grazing view %.1f°: the table's lobe is the direct one (relative L2 error %.3g)", views[i], e);
    }
    ic_hsh_lobe_table_destroy(t);
    ic_hsh_basis_destroy(b);
}

static void test_bad_input(void)
{
    ic_hsh_basis *b = NULL;
    ic_error err;
    ic_hsh_opts o = {IC_HSH_MAX_ORDER + 1, 0};
    CHECK(ic_hsh_basis_create(&o, &b, &err) == IC_ERR_INVALID_ARG && !b, "order too large accepted");
    o = (ic_hsh_opts){8, 4};
    CHECK(ic_hsh_basis_create(&o, &b, &err) == IC_ERR_INVALID_ARG && !b, "SH order below the order accepted");
    CHECK(ic_hsh_basis_create(NULL, &b, &err) == IC_OK && b && ic_hsh_order(b) == 10 && ic_hsh_count(b) == 100,
          "defaults: order 10");
    float c[IC_HSH_MAX_COUNT];
    phong p = {5.0, 1.0};
    CHECK(ic_hsh_lobe_project(b, brdf_phong, &p, v3(0, 0.6f, -0.8f), NULL, c, NULL, &err) == IC_ERR_INVALID_ARG,
          "outgoing direction below the horizon accepted");
    ic_hsh_quad_opts q = {.nodes = 40};
    CHECK(ic_hsh_lobe_project(b, brdf_phong, &p, v3(0, 0, 1), &q, c, NULL, &err) == IC_ERR_INVALID_ARG,
          "40 quadrature nodes accepted");
    ic_hsh_basis_destroy(b);
    ic_hsh_basis_destroy(NULL);
    ic_hsh_lobe_table_destroy(NULL);
}

int main(void)
{
    test_orthonormality();
    test_closed_forms();
    test_exact_projection();
    test_monte_carlo_convergence();
    test_rotation_exact();
    test_rotation_fast();
    test_frames();
    test_white_furnace();
    test_lobe_table();
    test_lobe_table_grazing();
    test_bad_input();
    TEST_MAIN_END();
}
