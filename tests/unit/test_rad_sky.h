/*
 * test_rad_sky.h — Radiance's sky functions written out again from their definitions (skybright.cal's skybr,
 * perezlum.cal's skybright), independent of the library's, for test_rad_sky.c and test_cli_rad.c; and their
 * brute-force integrals over a hemisphere.
 */
#ifndef IC_TEST_RAD_SKY_H
#define IC_TEST_RAD_SKY_H

#include <math.h>
#include <stdio.h>

#define TEST_PI 3.14159265358979323846

static inline double test_wmean(double a, double x, double b, double y) { return (a * x + b * y) / (a + b); }
static inline double test_acos(double x) { return acos(x < -1.0 ? -1.0 : x > 1.0 ? 1.0 : x); }

/* skybright.cal's skybr for real arguments A[1..7] (A[0] unused) and direction (dx, dy, dz). */
static inline double test_skybr(const double *A, double dx, double dy, double dz)
{
    double cosgamma = dx * A[5] + dy * A[6] + dz * A[7], gamma = test_acos(cosgamma);
    double zt = test_acos(A[7]), eta = test_acos(dz), sky;
    switch ((int)A[1]) {
    case 1:
        sky = A[2] * (0.91 + 10.0 * exp(-3.0 * gamma) + 0.45 * cosgamma * cosgamma) *
              (dz - 0.01 > 0.0 ? 1.0 - exp(-0.32 / dz) : 1.0) / A[4];
        break;
    case 2:
        sky = A[2] * (1.0 + 2.0 * dz) / 3.0;
        break;
    case 3:
        sky = A[2];
        break;
    default:
        sky = A[2] * ((1.35 * sin(5.631 - 3.59 * eta) + 3.12) * sin(4.396 - 2.6 * zt) + 6.37 - eta) / 2.326 *
              exp(gamma * -0.563 * ((2.629 - eta) * (1.562 - zt) + 0.812)) / A[4];
    }
    return test_wmean(pow(dz + 1.01, 10.0), sky, pow(dz + 1.01, -10.0), A[3]);
}

/* perezlum.cal's skybright for real arguments A[1..10]. */
static inline double test_perezlum(const double *A, double dx, double dy, double dz)
{
    double cosgamma = dx * A[8] + dy * A[9] + dz * A[10], gamma = test_acos(cosgamma);
    double z = dz - 0.01 > 0.0 ? dz : 0.01;
    double intersky = A[1] * (1.0 + A[3] * exp(A[4] / z)) * (1.0 + A[5] * exp(A[6] * gamma) + A[7] * cos(gamma) * cos(gamma));
    return test_wmean(pow(dz + 1.01, 10.0), intersky, pow(dz + 1.01, -10.0), A[2]);
}

typedef double (*test_sky_fn)(const double *A, double dx, double dy, double dz);

/* ∫ f(d) |d·n| dω over the hemisphere around n = (0, 0, ±1), by the midpoint rule in (|cos θ|, φ). */
static inline double test_sky_quadrature(test_sky_fn f, const double *A, int up)
{
    enum { NM = 1000, NP = 2000 };
    double sum = 0.0;
    for (int i = 0; i < NM; ++i) {
        double mu = (i + 0.5) / NM, st = sqrt(1.0 - mu * mu), row = 0.0;
        for (int k = 0; k < NP; ++k) {
            double phi = 2.0 * TEST_PI * (k + 0.5) / NP;
            row += f(A, st * cos(phi), st * sin(phi), up ? mu : -mu);
        }
        sum += row * mu;
    }
    return sum * (1.0 / NM) * (2.0 * TEST_PI / NP);
}

/* The share of the horizon blending in the irradiance of an upward (downward) sensor under skybright.cal's
 * overcast sky A: ∫ (skybr − the unblended CIE overcast sky (ground)) |cos θ| dω = 2π ∫ (…)(μ) μ dμ, by the
 * midpoint rule (the sky depends on dz alone). */
static inline double test_overcast_blend_share(const double *A, int up)
{
    enum { N = 200000 };
    double sum = 0.0;
    for (int i = 0; i < N; ++i) {
        double mu = (i + 0.5) / N, dz = up ? mu : -mu;
        double unblended = up ? A[2] * (1.0 + 2.0 * dz) / 3.0 : A[3];
        sum += (test_skybr(A, 0.0, 0.0, dz) - unblended) * mu;
    }
    return 2.0 * TEST_PI * sum / N;
}

/* gensky's output after its header, into out: sun (the solar source's lines, or ""), the brightfunc's string
 * arguments function ("skybr skybright.cal") and real arguments args (with their count), then the sky's and
 * the ground's glows ("r g b" each) and sources. */
static inline void test_gensky_text(char *out, size_t size, const char *sun, const char *function, const char *args,
                                    const char *sky_rgb, const char *ground_rgb)
{
    snprintf(out, size,
             "# pasted from gensky\n%s\n"
             "void brightfunc skyfunc\n2 %s\n0\n%s\n\n"
             "skyfunc glow sky_glow\n0\n0\n4 %s 0\n\nsky_glow source sky\n0\n0\n4 0 0 1 180\n\n"
             "skyfunc glow ground_glow\n0\n0\n4 %s 0\n\nground_glow source ground\n0\n0\n4 0 0 -1 180\n",
             sun, function, args, sky_rgb, ground_rgb);
}

#endif
