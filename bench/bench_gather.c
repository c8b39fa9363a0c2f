/*
 * bench_gather.c — hemicube against stratified gathering at equal rays, and the cost of the Hessian
 * (include/irrcache/gather.h; Castaño 2014, Schwarzhaupt et al. 2012).
 *
 * Scene: four emitting rectangles of different colours side by side at height 1 (none hides another
 * from any point below), over a black sky, so the irradiance, its gradient and its Hessian at every
 * point of the plane z = 0 are exact (Lambert's polygon formula; gradient and Hessian by central
 * differences, δ = 10⁻³). 256 points on a jittered grid under and around the emitters, normal +z, one
 * record key each.
 *
 * 1. Error per record against rays per record: RMS over the points of the relative error of E (green
 *    channel), of the translational gradient (|∇E − ∇E_exact| / RMS |∇E_exact|) and of the Hessian
 *    (Frobenius, relative to the RMS exact Hessian), for the hemicube at N = 8…32 and the stratified
 *    sampler at the M whose M×round(πM) rays come nearest 3N²; mean σ/|error| for each.
 * 2. Cost: microseconds per record, median of 21 runs over the 256 points, one thread, the analytic
 *    trace callback included (4 rectangles: a cheap trace, so the gather's own arithmetic shows), with
 *    and without opts.with_hessian interleaved run by run; and the time to create a gatherer (the
 *    hemicube tables, the Hessian's wall factors).
 *
 * 3. A radiance record (ic_gather_radiance, Křivánek et al. 2005 (TVCG)) against a stratified irradiance
 *    record at the same ray count: microseconds per record, HSH orders 6 and 10, the two interleaved run
 *    by run, median of the per-run ratios; the difference is the cost of the coefficients and their
 *    gradient (the trace is the same cheap analytic one). Twice: on the exact scene, where only the walls
 *    at the emitters' edges carry a radiance difference, and with every direction's radiance varied
 *    inside a closed dome (as on textured geometry in a room), where every wall does.
 *
 * Usage: bench_gather [--quick]. Prints tables; asserts nothing.
 */
#include "irrcache/gather.h"
#include "irrcache/hsh.h"

#include "core/vecmath.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static const double PI_D = 3.14159265358979323846;

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

typedef struct rect {
    double x0, y0, x1, y1, z;
    ic_vec3 emit;
} rect;

enum { RECTS = 4 };
static const rect SCENE[RECTS] = {
    {-1.5, -1.0, -0.2, 0.4, 1.0, {12, 10, 8}},
    {-0.2, -1.0, 1.3, -0.1, 1.0, {2, 6, 12}},
    {-0.2, 0.3, 0.9, 1.2, 1.0, {20, 20, 20}},
    {-1.5, 0.6, -0.5, 1.5, 1.0, {1, 8, 2}},
};

/* user non-NULL: a closed room where every direction sees a different radiance (emitters modulated by
 * 1 + ½·dir.x, the rest a dome at distance 5 of radiance 0.2·(1 + dir.y)), so every wall between two
 * cells moves and carries a radiance difference, as on textured geometry; NULL: the exact scene above. */
static void trace(void *user, const ic_vec3 *org, const ic_vec3 *dir, uint32_t count, float *hit_dist, ic_vec3 *radiance)
{
    for (uint32_t r = 0; r < count; ++r) {
        hit_dist[r] = INFINITY;
        radiance[r] = v3s(0.0f);
        if (!(dir[r].z > 0.0f))
            continue;
        for (int i = 0; i < RECTS; ++i) {
            const rect *q = &SCENE[i];
            const float t = ((float)q->z - org[r].z) / dir[r].z;
            const float x = org[r].x + t * dir[r].x, y = org[r].y + t * dir[r].y;
            if (t > 0.0f && x >= q->x0 && x <= q->x1 && y >= q->y0 && y <= q->y1) {
                hit_dist[r] = t;
                radiance[r] = q->emit;
                break;
            }
        }
        if (user && hit_dist[r] < INFINITY) {
            radiance[r] = v3_scale(radiance[r], 1.0f + 0.5f * dir[r].x);
        } else if (user) {
            hit_dist[r] = 5.0f;
            radiance[r] = v3s(0.2f * (1.0f + dir[r].y));
        }
    }
}

/* Exact green irradiance at (x, y, 0), normal +z. */
static double exact(double px, double py)
{
    double E = 0.0;
    for (int i = 0; i < RECTS; ++i) {
        const rect *q = &SCENE[i];
        const double v[4][3] = {{q->x0 - px, q->y0 - py, q->z}, {q->x1 - px, q->y0 - py, q->z},
                                {q->x1 - px, q->y1 - py, q->z}, {q->x0 - px, q->y1 - py, q->z}};
        double sum = 0.0;
        for (int k = 0; k < 4; ++k) {
            const double *a = v[k], *b = v[(k + 1) & 3];
            const double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
            const double lc = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
            sum += atan2(lc, a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) * c[2] / lc;
        }
        E += q->emit.y * 0.5 * fabs(sum);
    }
    return E;
}

enum { POINTS = 256 };
typedef struct reference {
    ic_gather_point pt[POINTS];
    double E[POINTS], grad[POINTS][2], hess[POINTS][3];
    double rms_grad, rms_hess;
} reference;

static void make_reference(reference *ref)
{
    uint64_t s = 12345;
    double sg = 0, sh = 0;
    for (int i = 0; i < POINTS; ++i) {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        const double jx = (double)(s >> 40) / 16777216.0;
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        const double jy = (double)(s >> 40) / 16777216.0;
        const double x = -2.0 + 4.0 * ((i % 16) + jx) / 16, y = -1.6 + 3.6 * ((i / 16) + jy) / 16;
        ref->pt[i] = (ic_gather_point){v3((float)x, (float)y, 0), v3(0, 0, 1), (uint64_t)i};
        const double d = 1e-3;
        const double e0 = exact(x, y);
        ref->E[i] = e0;
        ref->grad[i][0] = (exact(x + d, y) - exact(x - d, y)) / (2 * d);
        ref->grad[i][1] = (exact(x, y + d) - exact(x, y - d)) / (2 * d);
        ref->hess[i][0] = (exact(x + d, y) - 2 * e0 + exact(x - d, y)) / (d * d);
        ref->hess[i][1] = (exact(x + d, y + d) - exact(x + d, y - d) - exact(x - d, y + d) + exact(x - d, y - d)) / (4 * d * d);
        ref->hess[i][2] = (exact(x, y + d) - 2 * e0 + exact(x, y - d)) / (d * d);
        sg += ref->grad[i][0] * ref->grad[i][0] + ref->grad[i][1] * ref->grad[i][1];
        sh += ref->hess[i][0] * ref->hess[i][0] + 2 * ref->hess[i][1] * ref->hess[i][1] + ref->hess[i][2] * ref->hess[i][2];
    }
    ref->rms_grad = sqrt(sg / POINTS);
    ref->rms_hess = sqrt(sh / POINTS);
}

static ic_gatherer *make_lit(const ic_gather_opts *o, int is_varied)
{
    static int varied;
    ic_gatherer *g = NULL;
    ic_error err;
    if (ic_gatherer_create(o, trace, is_varied ? &varied : NULL, &g, &err) != IC_OK) {
        fprintf(stderr, "bench_gather: %s\n", err.message);
        exit(1);
    }
    return g;
}

static ic_gatherer *make(const ic_gather_opts *o) { return make_lit(o, 0); }

static ic_result gather(ic_gatherer *g, const ic_gather_point *pt, ic_gather_result *r)
{
    return ic_gatherer_opts(g)->method == IC_GATHER_HEMICUBE ? ic_gather_hemicube(g, pt, r) : ic_gather_stratified(g, pt, r);
}

/* Error figures of one sampler configuration over the reference points. */
static void errors(const ic_gather_opts *o, const reference *ref, uint32_t *rays, double *eE, double *eg, double *eh,
                   double *calib)
{
    ic_gatherer *g = make(o);
    double sE = 0, sg = 0, sh = 0, ssig = 0, serr = 0;
    for (int i = 0; i < POINTS; ++i) {
        ic_gather_result r;
        gather(g, &ref->pt[i], &r);
        *rays = r.ray_count;
        const double err = r.irradiance.y - ref->E[i];
        sE += ref->E[i] > 0 ? err * err / (ref->E[i] * ref->E[i]) : 0.0;
        serr += err * err;
        ssig += (double)r.sigma.y * r.sigma.y;
        const double dgx = r.trans_grad[1].x - ref->grad[i][0], dgy = r.trans_grad[1].y - ref->grad[i][1];
        sg += dgx * dgx + dgy * dgy;
        const ic_vec3 t = r.hessian_t, b = r.hessian_b;
        const float *h = r.hessian[1];
        const double hxx = h[0] * t.x * t.x + 2 * h[1] * t.x * b.x + h[2] * b.x * b.x;
        const double hxy = h[0] * t.x * t.y + h[1] * (t.x * b.y + b.x * t.y) + h[2] * b.x * b.y;
        const double hyy = h[0] * t.y * t.y + 2 * h[1] * t.y * b.y + h[2] * b.y * b.y;
        const double dxx = hxx - ref->hess[i][0], dxy = hxy - ref->hess[i][1], dyy = hyy - ref->hess[i][2];
        sh += dxx * dxx + 2 * dxy * dxy + dyy * dyy;
    }
    *eE = sqrt(sE / POINTS);
    *eg = sqrt(sg / POINTS) / ref->rms_grad;
    *eh = sqrt(sh / POINTS) / ref->rms_hess;
    *calib = sqrt(ssig / serr);
    ic_gatherer_destroy(g);
}

/* Microseconds per record without and with the Hessian: the two interleaved run by run, median of
 * `runs` passes over the reference points each, and the median of the per-run ratios. */
static void cost(const ic_gather_opts *o, const reference *ref, int runs, double *t_off, double *t_on, double *ratio)
{
    ic_gather_opts a = *o, b = *o;
    a.with_hessian = 0;
    b.with_hessian = 1;
    ic_gatherer *g[2] = {make(&a), make(&b)};
    double t[2][32], q[32];
    ic_gather_result r;
    for (int k = 0; k < runs; ++k) {
        for (int m = 0; m < 2; ++m) {
            const double t0 = now();
            for (int i = 0; i < POINTS; ++i)
                gather(g[m], &ref->pt[i], &r);
            t[m][k] = (now() - t0) / POINTS * 1e6;
        }
        q[k] = t[1][k] / t[0][k];
    }
    ic_gatherer_destroy(g[0]);
    ic_gatherer_destroy(g[1]);
    qsort(t[0], (size_t)runs, sizeof t[0][0], cmp_double);
    qsort(t[1], (size_t)runs, sizeof t[1][0], cmp_double);
    qsort(q, (size_t)runs, sizeof q[0], cmp_double);
    *t_off = t[0][runs / 2];
    *t_on = t[1][runs / 2];
    *ratio = q[runs / 2];
}

/* Microseconds per record of ic_gather_radiance at `order` and of ic_gather_stratified with the same
 * options (the same ray count), interleaved run by run; medians and the median per-run ratio. */
static void cost_radiance(const ic_gather_opts *o, uint32_t order, int is_varied, const reference *ref, int runs,
                          double *t_strat, double *t_rad, double *ratio, uint32_t *rays)
{
    ic_hsh_opts ho = {.order = order};
    ic_hsh_basis *basis = NULL;
    ic_error err;
    if (ic_hsh_basis_create(&ho, &basis, &err) != IC_OK) {
        fprintf(stderr, "bench_gather: %s\n", err.message);
        exit(1);
    }
    static float coeffs[3 * IC_HSH_MAX_COUNT], grad_t[3 * IC_HSH_MAX_COUNT], grad_b[3 * IC_HSH_MAX_COUNT];
    const ic_hsh_frame frame = {v3(1, 0, 0), v3(0, 1, 0), v3(0, 0, 1)};
    ic_gatherer *g = make_lit(o, is_varied);
    double t[2][32], q[32];
    for (int k = 0; k < runs; ++k) {
        double t0 = now();
        ic_gather_result r;
        for (int i = 0; i < POINTS; ++i)
            gather(g, &ref->pt[i], &r);
        t[0][k] = (now() - t0) / POINTS * 1e6;
        t0 = now();
        ic_gather_radiance_result rr = {.coeffs = coeffs, .grad_t = grad_t, .grad_b = grad_b};
        for (int i = 0; i < POINTS; ++i)
            ic_gather_radiance(g, basis, &ref->pt[i], &frame, &rr);
        t[1][k] = (now() - t0) / POINTS * 1e6;
        q[k] = t[1][k] / t[0][k];
        *rays = rr.ray_count;
    }
    ic_gatherer_destroy(g);
    ic_hsh_basis_destroy(basis);
    qsort(t[0], (size_t)runs, sizeof t[0][0], cmp_double);
    qsort(t[1], (size_t)runs, sizeof t[1][0], cmp_double);
    qsort(q, (size_t)runs, sizeof q[0], cmp_double);
    *t_strat = t[0][runs / 2];
    *t_rad = t[1][runs / 2];
    *ratio = q[runs / 2];
}

int main(int argc, char **argv)
{
    const int quick = argc > 1 && strcmp(argv[1], "--quick") == 0;
    const int runs = quick ? 5 : 21;
    static reference ref;
    make_reference(&ref);

    printf("## Error per record at equal rays (%d points, one record each; RMS relative errors)\n\n", POINTS);
    printf("| sampler | rays | E | ∇t E | Hessian | RMS σ / RMS error |\n|---|---|---|---|---|---|\n");
    const uint32_t res[5] = {8, 12, 16, 24, 32};
    for (int k = 0; k < (quick ? 3 : 5); ++k) {
        const uint32_t N = res[k];
        const uint32_t M = (uint32_t)lround(sqrt(3.0 * N * N / PI_D));
        ic_gather_opts oh = {.method = IC_GATHER_HEMICUBE, .hemicube_resolution = N, .with_hessian = 1};
        ic_gather_opts os = {.theta_strata = M, .with_hessian = 1};
        uint32_t rays;
        double eE, eg, eh, cal;
        errors(&oh, &ref, &rays, &eE, &eg, &eh, &cal);
        printf("| hemicube N = %u | %u | %.4f | %.4f | %.4f | %.2f |\n", N, rays, eE, eg, eh, cal);
        errors(&os, &ref, &rays, &eE, &eg, &eh, &cal);
        printf("| stratified %u×%u | %u | %.4f | %.4f | %.4f | %.2f |\n", M, (uint32_t)lround(PI_D * M), rays, eE, eg, eh, cal);
    }

    printf("\n## Cost per record (µs, median of %d runs over %d points, one thread, analytic trace included)\n\n", runs, POINTS);
    printf("| sampler | rays | without Hessian | with Hessian | with / without − 1 (median of per-run ratios) |\n"
           "|---|---|---|---|---|\n");
    const ic_gather_opts configs[4] = {
        {.method = IC_GATHER_STRATIFIED},
        {.method = IC_GATHER_HEMICUBE},
        {.method = IC_GATHER_STRATIFIED, .theta_strata = 32},
        {.method = IC_GATHER_HEMICUBE, .hemicube_resolution = 32},
    };
    for (int k = 0; k < 4; ++k) {
        const ic_gather_opts o = configs[k];
        double t0, t1, ratio;
        cost(&o, &ref, runs, &t0, &t1, &ratio);
        ic_gatherer *g = make(&o);
        ic_gather_result r;
        gather(g, &ref.pt[0], &r);
        ic_gatherer_destroy(g);
        printf("| %s | %u | %.1f | %.1f | %+.0f %% |\n", o.method == IC_GATHER_HEMICUBE ? "hemicube" : "stratified",
               r.ray_count, t0, t1, 100.0 * (ratio - 1.0));
    }

    printf("\n## Gathering a radiance record (µs per record, median of %d runs over %d points, one thread)\n\n"
           "| radiance | rays (stratified / radiance) | HSH order | stratified | radiance | radiance / stratified |\n"
           "|---|---|---|---|---|---|\n", runs, POINTS);
    const uint32_t strata[2] = {16, 32}, orders[2] = {6, 10};
    for (int v = 0; v < 2; ++v)
        for (int k = 0; k < 2; ++k)
            for (int j = 0; j < 2; ++j) {
                const ic_gather_opts o = {.theta_strata = strata[k]};
                double ts, tr, ratio;
                uint32_t rays;
                cost_radiance(&o, orders[j], v, &ref, runs, &ts, &tr, &ratio, &rays);
                printf("| %s | %u / %u | %u | %.1f | %.1f | %.2f |\n", v ? "varied" : "piecewise constant",
                       strata[k] * (uint32_t)lround(PI_D * strata[k]), rays, orders[j], ts, tr, ratio);
            }

    printf("\n## Creating a gatherer (µs, median of %d)\n\n| options | µs |\n|---|---|\n", runs);
    const ic_gather_opts create[4] = {
        {.method = IC_GATHER_STRATIFIED},
        {.method = IC_GATHER_STRATIFIED, .with_hessian = 1},
        {.method = IC_GATHER_HEMICUBE},
        {.method = IC_GATHER_HEMICUBE, .hemicube_resolution = 64},
    };
    const char *names[4] = {"defaults (stratified)", "defaults + with_hessian",
                            "hemicube N = 16 (default)", "hemicube N = 64"};
    for (int k = 0; k < 4; ++k) {
        double t[16];
        for (int j = 0; j < runs; ++j) {
            const double t0 = now();
            ic_gatherer *g = make(&create[k]);
            t[j] = (now() - t0) * 1e6;
            ic_gatherer_destroy(g);
        }
        qsort(t, (size_t)runs, sizeof t[0], cmp_double);
        printf("| %s | %.0f |\n", names[k], t[runs / 2]);
    }
    return 0;
}
