/*
 * bench_hsh.c — hemispherical-harmonics rotation and BRDF lobe figures (include/irrcache/hsh.h).
 *
 * 1. Speed: nanoseconds per rotation of an RGB coefficient vector (3 channels) at orders 3, 5, 8, 10 for
 *    the reference rotation (HSH → SH, y-rotation as X⁻¹·Z(β)·X, back by least squares; Gautron et al. 2004,
 *    Ivanic & Ruedenberg 1996, Kautz et al. 2002), the fast approximation of Křivánek et al. 2008 at second
 *    and first order, and the z-rotation alone. Random frames with β uniform in [0°, 45°]; median of 9 runs
 *    of 4000 rotations (the methods interleaved run by run), one thread.
 * 2. Accuracy: relative L2 error of the fast rotation against the reference at β = 5°…45° (mean over 32
 *    random frames and functions), for two families: "bump", x³ bumps of 35° radius centred within 15° of
 *    the normal (vanish 40° above the horizon); "sky", 1 + 0.8·(a·ω) with a within 30° of the normal (does
 *    not vanish at the horizon). The reference's own round trip (R then R⁻¹) and its error against the
 *    true rotation (the rotated, zero-filled function projected by quadrature) are listed for both.
 * 3. Lobes: truncation error (relative L2, ‖g − P_n g‖/‖g‖ with g = f·cosθ_i) of the normalised modified
 *    Phong lobe (Lafortune & Willems 1994) against exponent, order and view angle; the white furnace
 *    (Λ·C/L against the albedo by importance-sampled brute force); quadrature cost; the lobe table's
 *    interpolation error and look-up time.
 * 4. Evaluation: nanoseconds per ic_hsh_eval at orders 5, 10, 16.
 *
 * Usage: bench_hsh [--quick]. Prints tables; asserts nothing.
 */
#include "irrcache/hsh.h"

#include "core/rng.h"
#include "core/sampling.h"
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

static ic_hsh_basis *make_basis(uint32_t order)
{
    ic_hsh_opts o = {order, 0};
    ic_hsh_basis *b = NULL;
    ic_error err;
    if (ic_hsh_basis_create(&o, &b, &err) != IC_OK) {
        fprintf(stderr, "bench_hsh: %s\n", err.message);
        exit(1);
    }
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

/* ---- test functions ------------------------------------------------------------------------------ */

typedef struct family {
    int is_sky;
    double axis[3];
    double cos_edge;
} family;

static double fn_family(void *user, const double d[3])
{
    const family *f = user;
    double c = f->axis[0] * d[0] + f->axis[1] * d[1] + f->axis[2] * d[2];
    if (f->is_sky)
        return 1.0 + 0.8 * c;
    if (c <= f->cos_edge)
        return 0.0;
    double x = (c - f->cos_edge) / (1.0 - f->cos_edge);
    return x * x * x * (1.0 + 0.5 * d[0]);
}

/* The family member seen through a rotation, zero where it comes from below the horizon: g(ω) = f(r⁻¹ω). */
typedef struct rotated {
    const family *f;
    const ic_hsh_rotation *r;
} rotated;

static double fn_rotated(void *user, const double d[3])
{
    const rotated *g = user;
    double p[3];
    for (int i = 0; i < 3; ++i)
        p[i] = g->r->m[0][i] * d[0] + g->r->m[1][i] * d[1] + g->r->m[2][i] * d[2];
    return p[2] < 0.0 ? 0.0 : fn_family((void *)g->f, p);
}

static void random_family(ic_rng *r, int is_sky, family *f)
{
    double th = (is_sky ? 30.0 : 15.0) * PI_D / 180.0 * ic_rng_double(r), ph = 2 * PI_D * ic_rng_double(r);
    f->is_sky = is_sky;
    f->axis[0] = sin(th) * cos(ph);
    f->axis[1] = sin(th) * sin(ph);
    f->axis[2] = cos(th);
    f->cos_edge = cos(35.0 * PI_D / 180.0);
}

/* ---- 1. speed ------------------------------------------------------------------------------------ */

#define ROTATIONS 4000
#define RUNS 9

static void bench_speed(int quick)
{
    static const uint32_t orders[] = {3, 5, 8, 10};
    printf("\n## Rotation speed (ns per RGB rotation, median of %d runs of %d; one thread)\n\n", RUNS, ROTATIONS);
    printf("| order | SH order | reference | fast, 2nd order | fast, 1st order | z only | reference / fast 2nd |\n");
    printf("|---|---|---|---|---|---|---|\n");
    int rotations = quick ? ROTATIONS / 10 : ROTATIONS;
    for (size_t oi = 0; oi < sizeof orders / sizeof orders[0]; ++oi) {
        ic_hsh_basis *b = make_basis(orders[oi]);
        uint32_t cnt = ic_hsh_count(b);
        float *in = malloc(3 * cnt * sizeof *in), *out = malloc(3 * cnt * sizeof *out);
        double *scratch = malloc(ic_hsh_rotate_exact_scratch(b) * sizeof *scratch);
        ic_hsh_rotation *rots = malloc(rotations * sizeof *rots);
        ic_rng r = ic_rng_make(1, orders[oi], 0, 0);
        for (uint32_t k = 0; k < 3 * cnt; ++k)
            in[k] = (float)(ic_rng_double(&r) - 0.5) / (1.0f + (float)k);
        for (int i = 0; i < rotations; ++i)
            ic_hsh_rotation_from_euler(2 * PI_D * ic_rng_double(&r), 45.0 * PI_D / 180.0 * ic_rng_double(&r),
                                       2 * PI_D * ic_rng_double(&r), &rots[i]);
        /* Runs interleave the methods, so that a change of load on the shared machine hits all of them. */
        double t[4][RUNS], med[4];
        volatile float sink = 0.0f;
        for (int run = 0; run < RUNS; ++run)
            for (int method = 0; method < 4; ++method) {
                double t0 = now();
                for (int i = 0; i < rotations; ++i) {
                    if (method == 0)
                        ic_hsh_rotate_exact(b, &rots[i], in, 3, out, scratch);
                    else if (method == 1)
                        ic_hsh_rotate_fast(b, &rots[i], IC_HSH_TAYLOR_SECOND, in, 3, out);
                    else if (method == 2)
                        ic_hsh_rotate_fast(b, &rots[i], IC_HSH_TAYLOR_FIRST, in, 3, out);
                    else
                        ic_hsh_rotate_z(b, rots[i].alpha, in, 3, out);
                    sink += out[i % cnt];
                }
                t[method][run] = (now() - t0) / rotations * 1e9;
            }
        for (int method = 0; method < 4; ++method) {
            qsort(t[method], RUNS, sizeof t[method][0], cmp_double);
            med[method] = t[method][RUNS / 2];
        }
        (void)sink;
        printf("| %u | %u | %.0f | %.0f | %.0f | %.0f | %.1f |\n", orders[oi], ic_hsh_sh_order(b), med[0], med[1], med[2],
               med[3], med[0] / med[1]);
        free(in);
        free(out);
        free(scratch);
        free(rots);
        ic_hsh_basis_destroy(b);
    }
}

/* ---- 2. accuracy --------------------------------------------------------------------------------- */

static void bench_accuracy(int quick)
{
    static const uint32_t orders[] = {3, 5, 8, 10};
    static const double betas[] = {5, 10, 15, 20, 30, 45};
    const int nb = 6, trials = quick ? 4 : 32, true_trials = quick ? 2 : 8;
    printf("\n## Fast rotation error against the reference (relative L2, mean of %d random frames and functions; "
           "the reference against the true rotation: the first %d)\n", trials, true_trials);
    for (int is_sky = 0; is_sky < 2; ++is_sky) {
        printf("\n%s\n\n| order | method |", is_sky ? "sky: 1 + 0.8·(a·ω), a within 30° of the normal"
                                                  : "bump: x³ of 35° radius, centre within 15° of the normal");
        for (int i = 0; i < nb; ++i)
            printf(" %g° |", betas[i]);
        printf("\n|---|---|");
        for (int i = 0; i < nb; ++i)
            printf("---|");
        printf("\n");
        for (size_t oi = 0; oi < sizeof orders / sizeof orders[0]; ++oi) {
            ic_hsh_basis *b = make_basis(orders[oi]);
            uint32_t cnt = ic_hsh_count(b);
            double e2[6] = {0}, e1[6] = {0}, rt[6] = {0}, tr[6] = {0};
            ic_rng r = ic_rng_make(2, orders[oi], (uint64_t)is_sky, 0);
            float lam[IC_HSH_MAX_COUNT], ex[IC_HSH_MAX_COUNT], fa[IC_HSH_MAX_COUNT], back[IC_HSH_MAX_COUNT];
            ic_error err;
            for (int t = 0; t < trials; ++t) {
                family f;
                random_family(&r, is_sky, &f);
                ic_hsh_quad_opts q = {.tolerance = 1e-5};
                ic_hsh_project_function(b, fn_family, &f, &q, lam, NULL, &err);
                for (int bi = 0; bi < nb; ++bi) {
                    ic_hsh_rotation rot, inv;
                    ic_hsh_rotation_from_euler(2 * PI_D * ic_rng_double(&r), betas[bi] * PI_D / 180.0,
                                               2 * PI_D * ic_rng_double(&r), &rot);
                    ic_hsh_rotation_invert(&rot, &inv);
                    ic_hsh_rotate_exact(b, &rot, lam, 1, ex, NULL);
                    ic_hsh_rotate_exact(b, &inv, ex, 1, back, NULL);
                    ic_hsh_rotate_fast(b, &rot, IC_HSH_TAYLOR_SECOND, lam, 1, fa);
                    e2[bi] += rel_l2(fa, ex, cnt) / trials;
                    ic_hsh_rotate_fast(b, &rot, IC_HSH_TAYLOR_FIRST, lam, 1, fa);
                    e1[bi] += rel_l2(fa, ex, cnt) / trials;
                    rt[bi] += rel_l2(back, lam, cnt) / trials;
                    /* Against the true rotation: the rotated, zero-filled function projected by quadrature
                     * (the first 8 trials only: the zero fill's jump makes this quadrature slow). */
                    if (t < true_trials) {
                        rotated g = {&f, &rot};
                        ic_hsh_project_function(b, fn_rotated, &g, &q, back, NULL, &err);
                        tr[bi] += rel_l2(ex, back, cnt) / true_trials;
                    }
                }
            }
            const char *names[4] = {"fast, 2nd order", "fast, 1st order", "reference: R then R⁻¹",
                                    "reference vs true rotation"};
            double *rows[4] = {e2, e1, rt, tr};
            for (int m = 0; m < 4; ++m) {
                printf("| %u | %s |", orders[oi], names[m]);
                for (int bi = 0; bi < nb; ++bi)
                    printf(" %.1e |", rows[m][bi]);
                printf("\n");
            }
            ic_hsh_basis_destroy(b);
        }
    }
}

/* ---- 3. lobes ------------------------------------------------------------------------------------ */

typedef struct phong {
    double exponent, ks;
} phong;

static double brdf_phong(void *user, const double wi[3], const double wo[3])
{
    const phong *p = user;
    double c = -wi[0] * wo[0] - wi[1] * wo[1] + wi[2] * wo[2];
    return c > 0.0 ? p->ks * (p->exponent + 2.0) / (2.0 * PI_D) * pow(c, p->exponent) : 0.0;
}

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

typedef struct residual {
    phong p;
    double wo[3];
    const ic_hsh_basis *b;
    const float *c;
    uint32_t count;
} residual;

static double fn_residual(void *user, const double d[3])
{
    const residual *l = user;
    double v = brdf_phong((void *)&l->p, d, l->wo) * d[2], h[IC_HSH_MAX_COUNT];
    if (l->count) {
        ic_hsh_eval_d(l->b, d, h);
        for (uint32_t k = 0; k < l->count; ++k)
            v -= l->c[k] * h[k];
    }
    return v * v;
}

static void bench_lobes(int quick)
{
    static const double exps[] = {1, 10, 20, 50, 100, 200}, views[] = {0, 30, 60};
    static const uint32_t orders[] = {3, 5, 8, 10, 16};
    const int ne = quick ? 3 : 6, no = 5;
    ic_hsh_basis *b = make_basis(16), *b1 = make_basis(1);
    ic_error err;
    printf("\n## Modified Phong lobe f·cosθ_i: truncation error (relative L2) against order\n\n");
    printf("| exponent | view | albedo (brute force) | furnace Λ·C/L − albedo | quadrature calls |");
    for (int o = 0; o < no; ++o)
        printf(" n = %u |", orders[o]);
    printf("\n|---|---|---|---|---|");
    for (int o = 0; o < no; ++o)
        printf("---|");
    printf("\n");
    double L = 1.0;
    float lam[IC_HSH_MAX_COUNT];
    for (uint32_t k = 0; k < ic_hsh_count(b); ++k)
        lam[k] = 0.0f;
    lam[0] = (float)(L * sqrt(2.0 * PI_D)); /* a constant environment: only H_0 (checked by test_hsh) */
    for (int e = 0; e < ne; ++e)
        for (int v = 0; v < 3; ++v) {
            phong p = {exps[e], 1.0};
            double th = views[v] * PI_D / 180.0;
            ic_vec3 wo = v3((float)sin(th), 0.0f, (float)cos(th));
            float c[IC_HSH_MAX_COUNT];
            ic_hsh_quad_stats st;
            ic_hsh_lobe_project(b, brdf_phong, &p, wo, NULL, c, &st, &err);
            double albedo = albedo_brute_force(&p, wo), furnace = ic_hsh_dot(lam, c, ic_hsh_count(b)) / L;
            residual q = {p, {wo.x, wo.y, wo.z}, b, c, 0};
            ic_hsh_quad_opts qo = {.tolerance = 1e-5};
            float i0, i1;
            ic_hsh_project_function(b1, fn_residual, &q, &qo, &i0, NULL, &err);
            printf("| %g | %g° | %.5f | %+.1e | %llu |", exps[e], views[v], albedo, furnace - albedo,
                   (unsigned long long)st.evaluations);
            for (int o = 0; o < no; ++o) {
                q.count = orders[o] * orders[o];
                ic_hsh_project_function(b1, fn_residual, &q, &qo, &i1, NULL, &err);
                printf(" %.1e |", sqrt(fmax(0.0, i1) / i0));
            }
            printf("\n");
        }
    /* Sharper lobes: the quadrature alone (the furnace), order 16. */
    static const double sharp[] = {500.0, 1000.0};
    for (int e = 0; e < (quick ? 1 : 2); ++e)
        for (int v = 0; v < 3; ++v) {
            phong p = {sharp[e], 1.0};
            double th = views[v] * PI_D / 180.0;
            ic_vec3 wo = v3((float)sin(th), 0.0f, (float)cos(th));
            float c[IC_HSH_MAX_COUNT];
            ic_hsh_quad_stats st;
            ic_hsh_lobe_project(b, brdf_phong, &p, wo, NULL, c, &st, &err);
            double albedo = albedo_brute_force(&p, wo), furnace = ic_hsh_dot(lam, c, ic_hsh_count(b)) / L;
            printf("| %g | %g° | %.5f | %+.1e | %llu | — | — | — | — | — |\n", sharp[e], views[v], albedo, furnace - albedo,
                   (unsigned long long)st.evaluations);
        }
    /* Cost of a table: order 10, exponent 50, the default 46 entries. */
    ic_hsh_basis *b10 = make_basis(10);
    phong p = {50.0, 1.0};
    ic_hsh_lobe_table *t;
    double t0 = now();
    ic_hsh_lobe_table_create(b10, brdf_phong, &p, NULL, &t, &err);
    double t1 = now();
    float c[IC_HSH_MAX_COUNT];
    ic_rng r = ic_rng_make(5, 5, 5, 5);
    const int lookups = 200000;
    volatile float sink = 0.0f;
    double t2 = now();
    for (int i = 0; i < lookups; ++i) {
        ic_vec3 wo = ic_warp_uniform_hemisphere(ic_rng_float(&r), ic_rng_float(&r));
        ic_hsh_lobe_table_eval(t, wo, c);
        sink += c[i % 100];
    }
    double t3 = now();
    (void)sink;
    /* Interpolation error of the table against direct projection at random outgoing directions. */
    double worst = 0.0, mean = 0.0;
    const int probes = quick ? 4 : 24;
    for (int i = 0; i < probes; ++i) {
        ic_vec3 wo = ic_warp_uniform_hemisphere(ic_rng_float(&r), ic_rng_float(&r));
        float direct[IC_HSH_MAX_COUNT];
        ic_hsh_lobe_project(b10, brdf_phong, &p, wo, NULL, direct, NULL, &err);
        ic_hsh_lobe_table_eval(t, wo, c);
        double e = rel_l2(c, direct, 100);
        worst = fmax(worst, e);
        mean += e / probes;
    }
    printf("\nLobe table against direct projection (%d random outgoing directions): relative L2 error mean %.1e, "
           "worst %.1e\n", probes, mean, worst);
    printf("\nLobe table, order 10, exponent 50, 46 entries: built in %.2f s; ic_hsh_lobe_table_eval %.0f ns\n", t1 - t0,
           (t3 - t2) / lookups * 1e9);
    ic_hsh_lobe_table_destroy(t);
    ic_hsh_basis_destroy(b10);
    ic_hsh_basis_destroy(b);
    ic_hsh_basis_destroy(b1);
}

/* ---- 4. evaluation ------------------------------------------------------------------------------- */

static void bench_eval(void)
{
    static const uint32_t orders[] = {5, 10, 16};
    enum { DIRS = 4096, REPS = 64 };
    ic_vec3 *dirs = malloc(DIRS * sizeof *dirs);
    ic_rng r = ic_rng_make(6, 6, 6, 6);
    for (int i = 0; i < DIRS; ++i)
        dirs[i] = ic_warp_uniform_hemisphere(ic_rng_float(&r), ic_rng_float(&r));
    printf("\nic_hsh_eval (all n² values, float output), ns per direction:");
    for (size_t oi = 0; oi < sizeof orders / sizeof orders[0]; ++oi) {
        ic_hsh_basis *b = make_basis(orders[oi]);
        float v[IC_HSH_MAX_COUNT];
        volatile float sink = 0.0f;
        double t[RUNS];
        for (int run = 0; run < RUNS; ++run) {
            double t0 = now();
            for (int k = 0; k < REPS; ++k)
                for (int i = 0; i < DIRS; ++i) {
                    ic_hsh_eval(b, dirs[i], v);
                    sink += v[i % ic_hsh_count(b)];
                }
            t[run] = (now() - t0) / (DIRS * REPS) * 1e9;
        }
        (void)sink;
        qsort(t, RUNS, sizeof t[0], cmp_double);
        printf(" order %u: %.0f;", orders[oi], t[RUNS / 2]);
        ic_hsh_basis_destroy(b);
    }
    printf("\n");
    free(dirs);
}

int main(int argc, char **argv)
{
    int quick = argc > 1 && strcmp(argv[1], "--quick") == 0;
    printf("# bench_hsh%s\n", quick ? " --quick" : "");
    bench_speed(quick);
    bench_accuracy(quick);
    bench_lobes(quick);
    bench_eval();
    return 0;
}
