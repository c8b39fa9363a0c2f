/*
 * hsh.c — the hemispherical-harmonics basis (Gautron, Křivánek, Pattanaik & Bouatouch 2004),
 * projection, reconstruction, and BRDF lobe coefficients for radiance caching (Křivánek et al. 2005 (TVCG)).
 *
 * H_l^m(θ, φ) is the spherical harmonic Y_l^m with cosθ ∈ [−1, 1] replaced by the shifted argument
 * 2cosθ − 1, so that the associated Legendre functions are orthogonal over cosθ ∈ [0, 1], and a
 * normalisation doubled to make the functions orthonormal over the upper hemisphere (Gautron et al.
 * 2004). Here H = √2·Θ_l^m(2cosθ − 1)·Φ_m(φ) with Θ the associated Legendre function
 * normalised over [−1, 1] and Φ_m = 1/√(2π), cos(mφ)/√π, sin(|m|φ)/√π: the normalised three-term
 * recurrences below (no factorials, no pow) stay accurate in double far beyond the orders used here.
 *
 * BRDF lobes and callback functions are projected by adaptive cubature over (t, φ) with
 * cosθ = sin²(πt/2): odd-m functions carry √cosθ near the horizon and √(1 − cosθ) near the pole, and the
 * substitution makes both smooth (sin and cos of πt/2), so each cell's tensor Gauss–Legendre rule
 * converges quickly; cells are split where a sharp lobe makes the split change the coefficients.
 */
#include "hsh_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* cos θ_o of a lobe table's last entry (θ_o = 90° less 0.006°): see ic_hsh_lobe_table_create. */
#define LOBE_HORIZON_Z 1e-4f

static const double PI_D = 3.14159265358979323846;

void ic_hsh_opts_default(ic_hsh_opts *o, uint32_t order)
{
    *o = (ic_hsh_opts){0};
    o->order = order ? order : 10;
    o->sh_order = 2 * o->order + 8;
}

/* ---- Legendre recurrences and Gauss–Legendre nodes ---------------------------------------- */

void hsh_legendre(const ic_hsh_basis *b, uint32_t lmax, double x, double s, double *theta)
{
    double mm = sqrt(0.5); /* Θ_0^0 */
    for (uint32_t m = 0; m < lmax; ++m) {
        if (m > 0)
            mm *= b->diag[m] * s;
        theta[hsh_tri(m, m)] = mm;
        if (m + 1 >= lmax)
            break;
        double p2 = mm, p1 = b->sub[m] * x * mm;
        theta[hsh_tri(m + 1, m)] = p1;
        for (uint32_t l = m + 2; l < lmax; ++l) {
            size_t i = hsh_tri(l, m);
            double p = b->rec_a[i] * (x * p1 - b->rec_b[i] * p2);
            theta[i] = p;
            p2 = p1;
            p1 = p;
        }
    }
}

void hsh_gauss_legendre(uint32_t n, double *x, double *w)
{
    /* Newton's iteration on P_n from the usual asymptotic first guesses, then mapped to [0, 1]. */
    for (uint32_t i = 0; i < (n + 1) / 2; ++i) {
        double z = cos(PI_D * ((double)i + 0.75) / ((double)n + 0.5)), dp = 1.0;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1.0, p1 = z;
            for (uint32_t k = 2; k <= n; ++k) {
                double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / (double)k;
                p0 = p1;
                p1 = p2;
            }
            if (n == 1)
                p0 = 1.0;
            dp = (double)n * (z * p1 - p0) / (z * z - 1.0);
            double dz = p1 / dp;
            z -= dz;
            if (fabs(dz) < 1e-16)
                break;
        }
        double wt = 2.0 / ((1.0 - z * z) * dp * dp);
        x[i] = 0.5 * (1.0 - z);
        x[n - 1 - i] = 0.5 * (1.0 + z);
        w[i] = w[n - 1 - i] = 0.5 * wt;
    }
}

/* ---- lifecycle ---------------------------------------------------------------------------- */

ic_result ic_hsh_basis_create(const ic_hsh_opts *opts, ic_hsh_basis **out, ic_error *err)
{
    if (!out)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "hsh: NULL output pointer");
    *out = NULL;
    ic_hsh_opts o;
    ic_hsh_opts_default(&o, opts ? opts->order : 0);
    if (opts && opts->sh_order)
        o.sh_order = opts->sh_order;
    if (o.order > IC_HSH_MAX_ORDER)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "hsh: order %u exceeds the maximum %d", o.order,
                            IC_HSH_MAX_ORDER);
    if (o.sh_order < o.order || o.sh_order > 4 * IC_HSH_MAX_ORDER)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "hsh: SH order %u must lie in [order %u, %d]", o.sh_order,
                            o.order, 4 * IC_HSH_MAX_ORDER);
    ic_hsh_basis *b = calloc(1, sizeof *b);
    if (!b)
        return ic_error_set(err, IC_ERR_OOM, "hsh: out of memory");
    b->order = o.order;
    b->count = o.order * o.order;
    b->sh_order = o.sh_order;
    b->legendre_order = o.sh_order > o.order ? o.sh_order : o.order;
    uint32_t lm = b->legendre_order;
    size_t tri = hsh_tri(lm, 0);
    b->rec_a = calloc(tri, sizeof *b->rec_a);
    b->rec_b = calloc(tri, sizeof *b->rec_b);
    b->diag = calloc(lm, sizeof *b->diag);
    b->sub = calloc(lm, sizeof *b->sub);
    if (!b->rec_a || !b->rec_b || !b->diag || !b->sub) {
        ic_hsh_basis_destroy(b);
        return ic_error_set(err, IC_ERR_OOM, "hsh: out of memory");
    }
    /* Normalised recurrences: Θ_m^m = √((2m+1)/(2m))·s·Θ_{m−1}^{m−1}, Θ_{m+1}^m = √(2m+3)·x·Θ_m^m,
     * Θ_l^m = a(x·Θ_{l−1}^m − b·Θ_{l−2}^m), a = √((4l²−1)/(l²−m²)), b = √(((l−1)²−m²)/(4(l−1)²−1)). */
    for (uint32_t m = 0; m < lm; ++m) {
        b->diag[m] = m ? sqrt((2.0 * m + 1.0) / (2.0 * m)) : 1.0;
        b->sub[m] = sqrt(2.0 * m + 3.0);
        for (uint32_t l = m + 2; l < lm; ++l) {
            double L = l, M = m;
            b->rec_a[hsh_tri(l, m)] = sqrt((4.0 * L * L - 1.0) / (L * L - M * M));
            b->rec_b[hsh_tri(l, m)] = sqrt(((L - 1.0) * (L - 1.0) - M * M) / (4.0 * (L - 1.0) * (L - 1.0) - 1.0));
        }
    }
    ic_result r = hsh_build_rotation(b, err);
    if (r != IC_OK) {
        ic_hsh_basis_destroy(b);
        return r;
    }
    *out = b;
    return IC_OK;
}

void ic_hsh_basis_destroy(ic_hsh_basis *b)
{
    if (!b)
        return;
    hsh_free_rotation(b);
    free(b->rec_a);
    free(b->rec_b);
    free(b->diag);
    free(b->sub);
    free(b);
}

uint32_t ic_hsh_order(const ic_hsh_basis *b) { return b->order; }
uint32_t ic_hsh_count(const ic_hsh_basis *b) { return b->count; }
uint32_t ic_hsh_sh_order(const ic_hsh_basis *b) { return b->sh_order; }

/* ---- evaluation --------------------------------------------------------------------------- */

void ic_hsh_eval_d(const ic_hsh_basis *b, const double dir[3], double *values)
{
    uint32_t n = b->order;
    double z = dir[2];
    if (!(z >= 0.0)) {
        memset(values, 0, b->count * sizeof *values);
        return;
    }
    if (z > 1.0)
        z = 1.0;
    /* Shifted argument u = 2z − 1 and its s = √(1 − u²) = 2√(z(1 − z)), exact near both ends. */
    double theta[IC_HSH_MAX_ORDER * (IC_HSH_MAX_ORDER + 1) / 2];
    hsh_legendre(b, n, 2.0 * z - 1.0, 2.0 * sqrt(z * (1.0 - z)), theta);
    double rxy = sqrt(dir[0] * dir[0] + dir[1] * dir[1]);
    double c1 = 1.0, s1 = 0.0;
    if (rxy > 0.0) {
        c1 = dir[0] / rxy;
        s1 = dir[1] / rxy;
    }
    const double k0 = 1.0 / sqrt(PI_D), km = sqrt(2.0 / PI_D);
    for (uint32_t l = 0; l < n; ++l)
        values[ic_hsh_index((int)l, 0)] = k0 * theta[hsh_tri(l, 0)];
    double cm = 1.0, sm = 0.0; /* cos mφ, sin mφ by the angle-addition recurrence */
    for (uint32_t m = 1; m < n; ++m) {
        double c = cm * c1 - sm * s1;
        sm = sm * c1 + cm * s1;
        cm = c;
        for (uint32_t l = m; l < n; ++l) {
            double t = km * theta[hsh_tri(l, m)];
            values[ic_hsh_index((int)l, (int)m)] = t * cm;
            values[ic_hsh_index((int)l, -(int)m)] = t * sm;
        }
    }
}

void ic_hsh_eval(const ic_hsh_basis *b, ic_vec3 dir, float *values)
{
    double d[3] = {dir.x, dir.y, dir.z}, v[IC_HSH_MAX_COUNT];
    ic_hsh_eval_d(b, d, v);
    for (uint32_t k = 0; k < b->count; ++k)
        values[k] = (float)v[k];
}

void ic_hsh_reconstruct(const ic_hsh_basis *b, const float *coeffs, uint32_t channels, ic_vec3 dir, float *out)
{
    double d[3] = {dir.x, dir.y, dir.z}, v[IC_HSH_MAX_COUNT];
    ic_hsh_eval_d(b, d, v);
    for (uint32_t c = 0; c < channels; ++c) {
        double s = 0.0;
        for (uint32_t k = 0; k < b->count; ++k)
            s += v[k] * coeffs[c * b->count + k];
        out[c] = (float)s;
    }
}

float ic_hsh_dot(const float *a, const float *b, uint32_t count)
{
    double s = 0.0;
    for (uint32_t k = 0; k < count; ++k)
        s += (double)a[k] * b[k];
    return (float)s;
}

ic_vec3 ic_hsh_shade(const ic_hsh_basis *b, const float *radiance_rgb, const float *lobe)
{
    uint32_t k = b->count;
    ic_vec3 r = {ic_hsh_dot(radiance_rgb, lobe, k), ic_hsh_dot(radiance_rgb + k, lobe, k),
                 ic_hsh_dot(radiance_rgb + 2 * k, lobe, k)};
    return r;
}

/* ---- Monte Carlo projection ------------------------------------------------------------------ */

void ic_hsh_accumulate(const ic_hsh_basis *b, ic_vec3 dir, ic_vec3 radiance, double weight, double *sum)
{
    if (!(dir.z >= 0.0f) || weight == 0.0)
        return;
    double d[3] = {dir.x, dir.y, dir.z}, v[IC_HSH_MAX_COUNT];
    ic_hsh_eval_d(b, d, v);
    double lr = weight * radiance.x, lg = weight * radiance.y, lb = weight * radiance.z;
    uint32_t n = b->count;
    for (uint32_t k = 0; k < n; ++k) {
        sum[k] += lr * v[k];
        sum[n + k] += lg * v[k];
        sum[2 * n + k] += lb * v[k];
    }
}

/* One routine for both estimators: pdf NULL with is_cosine selects cosθ/π, NULL alone 1/2π. */
static void project_samples(const ic_hsh_basis *b, const ic_vec3 *dirs, const ic_vec3 *radiance, const float *pdf,
                            int is_cosine, uint32_t count, float *coeffs)
{
    double sum[3 * IC_HSH_MAX_COUNT] = {0};
    for (uint32_t i = 0; i < count; ++i) {
        double p = pdf ? pdf[i] : (is_cosine ? dirs[i].z / PI_D : 1.0 / (2.0 * PI_D));
        if (!(p > 0.0) || !(dirs[i].z >= 0.0f))
            continue;
        ic_hsh_accumulate(b, dirs[i], radiance[i], 1.0 / ((double)count * p), sum);
    }
    for (uint32_t k = 0; k < 3 * b->count; ++k)
        coeffs[k] = (float)sum[k];
}

void ic_hsh_project(const ic_hsh_basis *b, const ic_vec3 *dirs, const ic_vec3 *radiance, const float *pdf,
                    uint32_t count, float *coeffs_rgb)
{
    project_samples(b, dirs, radiance, pdf, 0, count, coeffs_rgb);
}

void ic_hsh_project_cosine(const ic_hsh_basis *b, const ic_vec3 *dirs, const ic_vec3 *radiance, uint32_t count,
                           float *coeffs_rgb)
{
    project_samples(b, dirs, radiance, NULL, 1, count, coeffs_rgb);
}

/* ---- adaptive cubature ----------------------------------------------------------------------- */

/* A leaf of the partition: its value is the sum of its four children's Gauss–Legendre integrals, and
 * error the L2 norm of that sum minus its own integral (a standard nested-rule estimate). */
typedef struct quad_leaf {
    double t0, t1, p0, p1;
    double error;
    uint32_t depth;
} quad_leaf;

typedef struct quad_ctx {
    const ic_hsh_basis *b;
    ic_hsh_function_fn fn;
    void *user;
    uint32_t q;
    double gx[16], gw[16];
    uint64_t evaluations;
} quad_ctx;

/* ∫ fn·H_k over one (t, φ) cell, added to out: z = sin²(πt/2), dω = dz dφ = (π/2)·sin(πt) dt dφ,
 * tensor Gauss–Legendre. */
static void cell_integral(quad_ctx *c, double t0, double t1, double p0, double p1, double *out)
{
    uint32_t n = c->b->count;
    double dt = t1 - t0, dp = p1 - p0;
    double v[IC_HSH_MAX_COUNT];
    for (uint32_t i = 0; i < c->q; ++i) {
        double t = t0 + dt * c->gx[i], sz = sin(0.5 * PI_D * t), cz = cos(0.5 * PI_D * t);
        double z = sz * sz, r = cz * sqrt(1.0 + z), jac = 0.5 * PI_D * sin(PI_D * t);
        for (uint32_t j = 0; j < c->q; ++j) {
            double phi = p0 + dp * c->gx[j];
            double dir[3] = {r * cos(phi), r * sin(phi), z};
            double f = c->fn(c->user, dir);
            ++c->evaluations;
            if (f == 0.0 || !isfinite(f))
                continue;
            double w = c->gw[i] * c->gw[j] * dt * dp * jac * f;
            ic_hsh_eval_d(c->b, dir, v);
            for (uint32_t k = 0; k < n; ++k)
                out[k] += w * v[k];
        }
    }
}

/* Evaluates a leaf: adds (children − own) to `total` with sign, returns the error estimate. With
 * sign = +1 the leaf's value enters the total; −1 removes it again before the leaf is split. */
static double leaf_eval(quad_ctx *c, const quad_leaf *l, double *own, double *kids, double *total, double sign)
{
    uint32_t n = c->b->count;
    double tm = 0.5 * (l->t0 + l->t1), pm = 0.5 * (l->p0 + l->p1);
    memset(own, 0, n * sizeof *own);
    memset(kids, 0, n * sizeof *kids);
    cell_integral(c, l->t0, l->t1, l->p0, l->p1, own);
    cell_integral(c, l->t0, tm, l->p0, pm, kids);
    cell_integral(c, tm, l->t1, l->p0, pm, kids);
    cell_integral(c, l->t0, tm, pm, l->p1, kids);
    cell_integral(c, tm, l->t1, pm, l->p1, kids);
    double e = 0.0;
    for (uint32_t k = 0; k < n; ++k) {
        e += (kids[k] - own[k]) * (kids[k] - own[k]);
        total[k] += sign * kids[k];
    }
    return sqrt(e);
}

/* Max-heap on error. */
static void heap_push(quad_leaf *h, size_t *size, quad_leaf l)
{
    size_t i = (*size)++;
    while (i > 0 && h[(i - 1) / 2].error < l.error) {
        h[i] = h[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    h[i] = l;
}

static quad_leaf heap_pop(quad_leaf *h, size_t *size)
{
    quad_leaf top = h[0], last = h[--*size];
    size_t i = 0;
    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= *size)
            break;
        if (c + 1 < *size && h[c + 1].error > h[c].error)
            ++c;
        if (h[c].error <= last.error)
            break;
        h[i] = h[c];
        i = c;
    }
    if (*size)
        h[i] = last;
    return top;
}

ic_result ic_hsh_project_function(const ic_hsh_basis *b, ic_hsh_function_fn fn, void *user,
                                  const ic_hsh_quad_opts *opts, float *coeffs, ic_hsh_quad_stats *stats,
                                  ic_error *err)
{
    if (!b || !fn || !coeffs)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "hsh: NULL basis, function or output");
    ic_hsh_quad_opts o = opts ? *opts : (ic_hsh_quad_opts){0};
    if (o.tolerance == 0.0)
        o.tolerance = 1e-6;
    if (!o.nodes)
        o.nodes = 6;
    if (!o.t_cells)
        o.t_cells = 8;
    if (!o.phi_cells)
        o.phi_cells = 16;
    if (!o.max_depth)
        o.max_depth = 12;
    if (!o.max_leaves)
        o.max_leaves = 1u << 16;
    if (!(o.tolerance > 0.0) || o.nodes < 2 || o.nodes > 16 || o.t_cells > 1024 || o.phi_cells > 1024 ||
        o.max_depth > 30 || (uint64_t)o.t_cells * o.phi_cells > o.max_leaves)
        return ic_error_set(err, IC_ERR_INVALID_ARG,
                            "hsh: quadrature options out of range (tolerance > 0, 2 ≤ nodes ≤ 16, at most 1024 "
                            "cells per side and no more than max_leaves initial cells, max_depth ≤ 30)");
    quad_ctx c = {.b = b, .fn = fn, .user = user, .q = o.nodes};
    hsh_gauss_legendre(o.nodes, c.gx, c.gw);
    uint32_t n = b->count;
    /* Splitting a leaf adds three, so the heap never holds more than max_leaves + 3. */
    quad_leaf *heap = malloc(((size_t)o.max_leaves + 4) * sizeof *heap);
    double *total = calloc(n, sizeof *total);
    if (!heap || !total) {
        free(heap);
        free(total);
        return ic_error_set(err, IC_ERR_OOM, "hsh: out of memory for the quadrature");
    }
    double own[IC_HSH_MAX_COUNT], kids[IC_HSH_MAX_COUNT];
    size_t size = 0;
    double sum_error = 0.0, stuck_error = 0.0; /* stuck: leaves at max_depth, never split again */
    uint32_t leaves = 0;
    for (uint32_t i = 0; i < o.t_cells; ++i)
        for (uint32_t j = 0; j < o.phi_cells; ++j) {
            quad_leaf l = {(double)i / o.t_cells, (double)(i + 1) / o.t_cells, 2.0 * PI_D * j / o.phi_cells,
                           2.0 * PI_D * (j + 1) / o.phi_cells, 0.0, 0};
            l.error = leaf_eval(&c, &l, own, kids, total, 1.0);
            sum_error += l.error;
            heap_push(heap, &size, l);
            ++leaves;
        }
    double scale = 0.0;
    for (uint32_t k = 0; k < n; ++k)
        scale += total[k] * total[k];
    double tol = o.tolerance * sqrt(scale);
    /* Global adaptivity: always split the leaf with the largest error estimate, until the sum of the
     * estimates (a bound on the L2 error of the vector if each estimate is) meets the tolerance. */
    while (size > 0 && sum_error - stuck_error > 0.0 && sum_error > tol && leaves + 3 <= o.max_leaves) {
        quad_leaf p = heap_pop(heap, &size);
        if (p.depth >= o.max_depth) {
            stuck_error += p.error;
            continue;
        }
        sum_error -= p.error;
        double tm = 0.5 * (p.t0 + p.t1), pm = 0.5 * (p.p0 + p.p1);
        /* The parent's value was its children's sum: remove it, then add each child's refined value. */
        quad_leaf kid[4] = {{p.t0, tm, p.p0, pm, 0.0, p.depth + 1}, {tm, p.t1, p.p0, pm, 0.0, p.depth + 1},
                            {p.t0, tm, pm, p.p1, 0.0, p.depth + 1}, {tm, p.t1, pm, p.p1, 0.0, p.depth + 1}};
        for (int q = 0; q < 4; ++q) {
            kid[q].error = leaf_eval(&c, &kid[q], own, kids, total, 1.0);
            for (uint32_t k = 0; k < n; ++k)
                total[k] -= own[k];
            sum_error += kid[q].error;
            heap_push(heap, &size, kid[q]);
        }
        leaves += 3;
    }
    for (uint32_t k = 0; k < n; ++k)
        coeffs[k] = (float)total[k];
    if (stats) {
        stats->evaluations = c.evaluations;
        stats->leaves = leaves;
        stats->error_estimate = scale > 0.0 ? sum_error / sqrt(scale) : sum_error;
        stats->is_converged = sum_error <= tol;
    }
    free(heap);
    free(total);
    return IC_OK;
}

/* ---- BRDF lobes ------------------------------------------------------------------------------- */

typedef struct lobe_ctx {
    ic_hsh_brdf_fn brdf;
    void *user;
    double wo[3];
} lobe_ctx;

static double lobe_integrand(void *user, const double dir[3])
{
    const lobe_ctx *l = user;
    return l->brdf(l->user, dir, l->wo) * dir[2];
}

ic_result ic_hsh_lobe_project(const ic_hsh_basis *b, ic_hsh_brdf_fn brdf, void *user, ic_vec3 wo,
                              const ic_hsh_quad_opts *opts, float *c, ic_hsh_quad_stats *stats, ic_error *err)
{
    if (!brdf)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "hsh: NULL BRDF callback");
    if (!(wo.z >= 0.0f))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "hsh: outgoing direction (%g, %g, %g) is below the horizon",
                            (double)wo.x, (double)wo.y, (double)wo.z);
    lobe_ctx l = {brdf, user, {wo.x, wo.y, wo.z}};
    return ic_hsh_project_function(b, lobe_integrand, &l, opts, c, stats, err);
}

struct ic_hsh_lobe_table {
    const ic_hsh_basis *basis;
    uint32_t theta_count;
    double step;           /* θ_o spacing, radians */
    float *entries;        /* theta_count × n² */
};

ic_result ic_hsh_lobe_table_create(const ic_hsh_basis *b, ic_hsh_brdf_fn brdf, void *user,
                                   const ic_hsh_lobe_table_opts *opts, ic_hsh_lobe_table **out, ic_error *err)
{
    if (!b || !brdf || !out)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "hsh: NULL basis, BRDF or output");
    *out = NULL;
    ic_hsh_lobe_table_opts o = opts ? *opts : (ic_hsh_lobe_table_opts){0};
    if (!o.theta_count)
        o.theta_count = 46;
    if (o.theta_count < 2 || o.theta_count > 100000)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "hsh: lobe table needs 2..100000 entries over θ_o, not %u",
                            o.theta_count);
    ic_hsh_lobe_table *t = calloc(1, sizeof *t);
    if (!t)
        return ic_error_set(err, IC_ERR_OOM, "hsh: out of memory");
    t->basis = b;
    t->theta_count = o.theta_count;
    t->step = 0.5 * PI_D / (o.theta_count - 1);
    t->entries = malloc((size_t)o.theta_count * b->count * sizeof *t->entries);
    if (!t->entries) {
        free(t);
        return ic_error_set(err, IC_ERR_OOM, "hsh: out of memory");
    }
    for (uint32_t i = 0; i < o.theta_count; ++i) {
        double th = i * t->step;
        ic_vec3 wo = {(float)sin(th), 0.0f, (float)cos(th)};
        /* The last entry, θ_o = 90°, is taken a hair above the horizon: a BRDF is zero for a view at or
         * below it (the renderer's are), while its limit from above is not (a microfacet lobe's
         * f·cosθ_i stays finite as G ∝ cosθ_o cancels 1/cosθ_o); a zero entry pulled the
         * interpolation to zero from about 88° on. */
        if (i == o.theta_count - 1)
            wo.z = LOBE_HORIZON_Z;
        ic_result r = ic_hsh_lobe_project(b, brdf, user, wo, &o.quad, t->entries + (size_t)i * b->count, NULL, err);
        if (r != IC_OK) {
            ic_hsh_lobe_table_destroy(t);
            return r;
        }
    }
    *out = t;
    return IC_OK;
}

void ic_hsh_lobe_table_destroy(ic_hsh_lobe_table *t)
{
    if (!t)
        return;
    free(t->entries);
    free(t);
}

void ic_hsh_lobe_table_eval(const ic_hsh_lobe_table *t, ic_vec3 wo, float *c)
{
    const ic_hsh_basis *b = t->basis;
    uint32_t n = b->count, last = t->theta_count - 1;
    double z = wo.z < 0.0f ? 0.0 : (wo.z > 1.0f ? 1.0 : wo.z);
    double rxy = sqrt((double)wo.x * wo.x + (double)wo.y * wo.y);
    double th = atan2(rxy, z), x = th / t->step;
    uint32_t i = (uint32_t)x;
    if (i >= last)
        i = last - 1;
    double f = x - i;
    /* Catmull–Rom weights for entries i−1, i, i+1, i+2. Below θ_o = 0 the lobe at −θ is the lobe at θ
     * turned by π about z, which flips the sign of odd-m coefficients; past 90° the last entry repeats. */
    double w[4] = {0.5 * (-f + 2 * f * f - f * f * f), 0.5 * (2 - 5 * f * f + 3 * f * f * f),
                   0.5 * (f + 4 * f * f - 3 * f * f * f), 0.5 * (-f * f + f * f * f)};
    for (uint32_t l = 0; l < b->order; ++l)
        for (int m = -(int)l; m <= (int)l; ++m) {
            uint32_t k = ic_hsh_index((int)l, m);
            double s = 0.0;
            for (int j = 0; j < 4; ++j) {
                int e = (int)i - 1 + j;
                double sign = 1.0;
                if (e < 0) {
                    e = -e;
                    sign = (m & 1) ? -1.0 : 1.0;
                }
                if (e > (int)last)
                    e = (int)last;
                s += w[j] * sign * t->entries[(size_t)e * n + k];
            }
            c[k] = (float)s;
        }
    if (rxy > 0.0)
        ic_hsh_rotate_z(b, atan2((double)wo.y, (double)wo.x), c, 1, c);
}
