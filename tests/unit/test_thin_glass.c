/*
 * test_thin_glass.c — the thin pane (Radiance's glass) against the slab's analytic answers:
 *   1. the BSDF: without absorption, what it reflects and transmits sums to 1 at every angle (the sampled
 *      weights' mean), and at normal incidence it reflects 2r/(1 + r), r = ((n − 1)/(n + 1))²; with
 *      absorption, reflectance and transmittance equal the inter-reflection series summed term by term;
 *   2. a Radiance `glass` pane in front of a glowing wall, seen at normal and at 60° incidence: the image is
 *      the pane's transmittance times the wall's radiance (the analytic series), path tracer and cache;
 *   3. a JSON `thin_glass` sheet in a uniform sky (nothing else): every pixel on it is the sky's radiance,
 *      both integrators; a JSON pane with transmissivity 0.8 shows the same transmittance as the Radiance one;
 *   4. a skylight: an upward sensor 1 m under a horizontal pane 2 km wide (transmissivity 0.96, n = 1.52:
 *      Radiance's 88 % clear glass) over a black ground, under a uniform sky, the CIE overcast sky (JSON, no
 *      ground glow) and gensky -c's sky pasted into a .rad file (its ground brightness 0): E is the sky's
 *      radiance times the pane's transmittance, integrated over the hemisphere by quadrature (Radiance's
 *      formula, written out again here), for the path tracer and the cache, each within 3 of its σ and the
 *      two within 3 combined σ; the daylight factor under the overcast sky is the cosine- and
 *      sky-weighted mean transmittance (82.9 %, not the 88 % at normal incidence).
 */
#include "test_util.h"
#include "test_render_util.h"

#include "integrators/bsdf.h"

#include <stdio.h>
#include <string.h>

#define PI_D 3.14159265358979323846

/* One polarisation's Fresnel reflectance from air into index n at cos θ = ci (double precision). */
static double fresnel(double ci, double n, int p)
{
    double ct = sqrt(1.0 - (1.0 - ci * ci) / (n * n));
    double a = p ? (n * ci - ct) / (n * ci + ct) : (ci - n * ct) / (ci + n * ct);
    return a * a;
}

/* Reflectance and transmittance of the slab by summing its bounces: light enters (1 − r), crosses (d),
 * and at each face either leaves or reflects (r), 200 terms; averaged over the polarisations. */
static void series(double ci, double n, double tn, double *R, double *T)
{
    double ct = sqrt(1.0 - (1.0 - ci * ci) / (n * n)), d = pow(tn, 1.0 / ct);
    *R = *T = 0.0;
    for (int p = 0; p < 2; ++p) {
        double r = fresnel(ci, n, p), inside = 1.0 - r; /* flux inside, going down */
        *R += 0.5 * r;
        for (int k = 0; k < 200; ++k) {
            inside *= d;              /* crosses down */
            *T += 0.5 * inside * (1.0 - r);
            inside *= r * d;          /* reflects at the bottom, crosses up */
            *R += 0.5 * inside * (1.0 - r);
            inside *= r;              /* reflects at the top, going down again */
        }
    }
}

static ic_bsdf pane(float n, float tn)
{
    ic_bsdf b;
    memset(&b, 0, sizeof b);
    b.type = IC_MAT_THIN_GLASS;
    b.ks = v3s(tn);
    b.ior = n;
    b.frame = ic_frame_from_normal(v3(0.0f, 0.0f, 1.0f));
    b.ng = v3(0.0f, 0.0f, 1.0f);
    return b;
}

static void test_bsdf(void)
{
    static const float indices[] = {1.33f, 1.52f, 2.4f};
    static const double cosines[] = {1.0, 0.8, 0.5, 0.2, 0.05};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 5; ++j) {
            ic_bsdf b = pane(indices[i], 1.0f);
            double ci = cosines[j];
            ic_vec3 wo = v3((float)sqrt(1.0 - ci * ci), 0.0f, (float)ci);
            /* the mean weight over stratified u0: reflected and transmitted parts */
            const int N = 4096;
            double refl = 0.0, trans = 0.0;
            int specular = 1, straight = 1;
            for (int k = 0; k < N; ++k) {
                ic_bsdf_sample s;
                if (!ic_bsdf_sample_dir(&b, wo, ((float)k + 0.5f) / (float)N, 0.5f, 0.5f, &s))
                    continue;
                specular &= s.is_specular;
                if (s.wi.z > 0.0f)
                    refl += s.weight.y / N;
                else
                    trans += s.weight.y / N;
                if (s.wi.z < 0.0f)
                    straight &= fabsf(s.wi.x + wo.x) < 1e-6f && fabsf(s.wi.z + wo.z) < 1e-6f;
            }
            CHECK(specular && straight, "delta lobes, transmission straight on");
            double R, T;
            series(ci, indices[i], 1.0, &R, &T);
            CHECK(fabs(refl + trans - 1.0) < 1e-4, "n %g cos %g: reflected %g + transmitted %g = 1", (double)indices[i], ci,
                  refl, trans);
            CHECK(fabs(refl - R) < 2e-3 && fabs(trans - T) < 2e-3, "n %g cos %g: R %g T %g, series %g %g",
                  (double)indices[i], ci, refl, trans, R, T);
            if (j == 0) {
                double r = pow((indices[i] - 1.0) / (indices[i] + 1.0), 2.0);
                ic_vec3 Rv, Tv;
                ic_thin_glass(1.0f, indices[i], v3s(1.0f), &Rv, &Tv);
                CHECK(fabs(Rv.x - 2.0 * r / (1.0 + r)) < 1e-5, "n %g: at normal incidence R = 2r/(1+r) = %g: %g",
                      (double)indices[i], 2.0 * r / (1.0 + r), (double)Rv.x);
            }
        }
    /* absorbing, coloured: the closed form against the series */
    for (int j = 0; j < 5; ++j) {
        ic_vec3 tn = v3(0.96f, 0.5f, 0.1f), R, T;
        ic_thin_glass((float)cosines[j], 1.52f, tn, &R, &T);
        float tc[3] = {tn.x, tn.y, tn.z}, rv[3] = {R.x, R.y, R.z}, tv[3] = {T.x, T.y, T.z};
        for (int c = 0; c < 3; ++c) {
            double Rs, Ts;
            series(cosines[j], 1.52, tc[c], &Rs, &Ts);
            CHECK(fabs(rv[c] - Rs) < 1e-5 && fabs(tv[c] - Ts) < 1e-5,
                  "tn %g cos %g: R %g T %g, series %g %g", (double)tc[c], cosines[j], (double)rv[c], (double)tv[c], Rs,
                  Ts);
        }
    }
}

/* Mean of channel c over a rendered image. */
static double image_mean(const ic_image *img, int c)
{
    double s = 0.0;
    for (size_t i = 0; i < (size_t)img->width * img->height; ++i)
        s += img->rgb[3 * i + c];
    return s / ((double)img->width * img->height);
}

/* A Radiance scene: a glowing wall of radiance 2 at y = 10 facing the eye, a pane through (0, 5, 0) tilted
 * by `tilt` degrees about x, seen from the origin along +y through a 2° view. The wall is a band |z| ≤ 3,
 * so what the tilted pane reflects (down at 30° below the axis) misses it: the image is the transmitted
 * wall alone. */
static void pane_in_front_of_light(double tilt)
{
    double a = tilt * PI_D / 180.0, s = sin(a), c = cos(a);
    char rad[2048];
    /* the pane's plane holds x and (0, −sin, cos) */
    snprintf(rad, sizeof rad,
             "void glow wall\n0\n0\n4 2 2 2 0\n"
             "wall polygon w\n0\n0\n12\n -50 10 -3\n 50 10 -3\n 50 10 3\n -50 10 3\n"
             "void glass pane\n0\n0\n3 0.96 0.6 0.2\n"
             "pane polygon p\n0\n0\n12\n -20 %g %g\n 20 %g %g\n 20 %g %g\n -20 %g %g\n",
             5.0 + 4.0 * s, -4.0 * c, 5.0 + 4.0 * s, -4.0 * c, 5.0 - 4.0 * s, 4.0 * c, 5.0 - 4.0 * s, 4.0 * c);
    test_write_file(IC_TEST_TMP "/thin_pane.rad", rad);
    test_write_file(IC_TEST_TMP "/thin_pane.vf", "rview -vtv -vp 0 0 0 -vd 0 1 0 -vu 0 0 1 -vh 2 -vv 2\n");
    static const ic_integrator integ[2] = {IC_INTEGRATOR_PT, IC_INTEGRATOR_IC};
    for (int k = 0; k < 2; ++k) {
        ic_scene_load_options lo = {0};
        lo.view = IC_TEST_TMP "/thin_pane.vf";
        lo.width = lo.height = 16;
        ic_scene *scene = NULL;
        ic_error err = {0};
        CHECK(ic_scene_load(IC_TEST_TMP "/thin_pane.rad", &lo, &scene, &err) == IC_OK, "pane loads: %s", err.message);
        ic_render_options opt = {0};
        opt.integrator = integ[k];
        opt.spp = 64;
        opt.threads = 2;
        ic_image img = {0};
        if (scene && test_render_loaded(scene, &opt, &img)) {
            static const double tn[3] = {0.96, 0.6, 0.2};
            for (int ch = 0; ch < 3; ++ch) {
                double R, T, m = image_mean(&img, ch);
                series(cos(a), 1.52, tn[ch], &R, &T);
                CHECK(fabs(m - 2.0 * T) < 0.01 * 2.0 * T + 1e-4,
                      "%s, %g degrees, channel %d: the wall through the pane %g, expected T L = %g",
                      k ? "cache" : "path tracer", tilt, ch, m, 2.0 * T);
                if (ch == 0)
                    printf("pane at %g degrees (%s): %g, T L = %g\n", tilt, k ? "cache" : "path tracer", m, 2.0 * T);
            }
        }
        ic_image_free(&img);
        ic_scene_free(scene);
    }
}

/* A JSON sheet of `material` seen from above in a uniform sky of radiance 2: the mean of channel c. */
static double json_sheet(const char *material, ic_integrator integ, int c)
{
    test_write_file(IC_TEST_TMP "/thin_sheet.mtl", "newmtl sheet\nKd 0.5 0.5 0.5\n");
    test_write_file(IC_TEST_TMP "/thin_sheet.obj", "mtllib thin_sheet.mtl\nusemtl sheet\n"
                                                   "v -1000 0 -1000\nv 1000 0 -1000\nv 1000 0 1000\nv -1000 0 1000\n"
                                                   "f 1 3 2\nf 1 4 3\n");
    char scene[2048];
    snprintf(scene, sizeof scene,
             "{\n  \"camera\": {\"eye\": [0, 1, 0], \"target\": [0, 0, 0], \"up\": [0, 0, 1], \"fov_y\": 2,"
             " \"width\": 8, \"height\": 8},\n"
             "  \"meshes\": [{\"path\": \"thin_sheet.obj\"}],\n  \"materials\": {\"sheet\": %s},\n"
             "  \"environment\": {\"radiance\": [2, 2, 2]}\n}\n",
             material);
    test_write_file(IC_TEST_TMP "/thin_sheet.json", scene);
    ic_render_options opt = {0};
    opt.integrator = integ;
    opt.spp = 64;
    opt.threads = 2;
    ic_image img = {0};
    double m = test_render(IC_TEST_TMP "/thin_sheet.json", 0, 0, &opt, &img, NULL) ? image_mean(&img, c) : -1.0;
    ic_image_free(&img);
    return m;
}

static void test_json(void)
{
    static const ic_integrator integ[2] = {IC_INTEGRATOR_PT, IC_INTEGRATOR_IC};
    for (int k = 0; k < 2; ++k) {
        double m = json_sheet("{\"type\": \"thin_glass\", \"ior\": 1.52}", integ[k], 1);
        CHECK(fabs(m - 2.0) < 1e-4, "%s: a clear sheet in a uniform sky of 2 shows %g (reflected + transmitted sky)",
              k ? "cache" : "path tracer", m);
        /* looking straight down through the sheet at the sky below: 2 (T + R) — all sky */
        double R, T;
        series(1.0, 1.52, 0.8, &R, &T);
        m = json_sheet("{\"type\": \"thin_glass\", \"ior\": 1.52, \"ks\": 0.8}", integ[k], 0);
        CHECK(fabs(m - 2.0 * (R + T)) < 0.01 * 2.0 * (R + T), "%s: a sheet of transmissivity 0.8: %g, expected 2 (R + T) = %g",
              k ? "cache" : "path tracer", m, 2.0 * (R + T));
    }
}

/* ---- a skylight over a sensor ---- */

/* The pane's transmittance at cos θ = ci, Radiance's glass: the series of test 1, in closed form. */
static double pane_T(double ci, double n, double tn)
{
    double ct = sqrt(1.0 - (1.0 - ci * ci) / (n * n)), d = pow(tn, 1.0 / ct), T = 0.0;
    for (int p = 0; p < 2; ++p) {
        double r = fresnel(ci, n, p);
        T += 0.5 * (1.0 - r) * (1.0 - r) * d / (1.0 - r * r * d * d);
    }
    return T;
}

/* The sky's radiance at zenith angle θ (cos θ = c): 0 uniform (1), 1 CIE overcast (L_z = 1), 2 gensky -c's
 * skybright.cal with ground brightness 0 (its horizon blending, weights (c + 1.01)^±10). */
static double sky_L(int kind, double c)
{
    if (kind == 0)
        return 1.0;
    double L = (1.0 + 2.0 * c) / 3.0, w = pow(c + 1.01, 10.0);
    return kind == 1 ? L : w * L / (w + 1.0 / w);
}

/* E at an upward sensor h = 1 under the pane (half-width 1000, taken as a disc: the square's corners add 1e-7),
 * by the midpoint rule in θ; with pane 0, the open sky. */
static double skylight_E(int kind, int pane, double scale)
{
    const int N = 200000;
    const double th0 = atan(1000.0), dth = 0.5 * PI_D / N;
    double sum = 0.0;
    for (int i = 0; i < N; ++i) {
        double th = (i + 0.5) * dth, c = cos(th);
        sum += sky_L(kind, c) * (pane && th < th0 ? pane_T(c, 1.52, 0.96) : 1.0) * c * sin(th);
    }
    return 2.0 * PI_D * sum * dth * scale;
}

static void test_skylight(void)
{
    test_write_file(IC_TEST_TMP "/skylight.mtl", "newmtl pane\nKd 0 0 0\nnewmtl ground\nKd 0 0 0\n");
    test_write_file(IC_TEST_TMP "/skylight.obj", "mtllib skylight.mtl\nusemtl pane\n"
                                                 "v -1000 1 -1000\nv 1000 1 -1000\nv 1000 1 1000\nv -1000 1 1000\n"
                                                 "v -1000 -0.01 -1000\nv 1000 -0.01 -1000\nv 1000 -0.01 1000\n"
                                                 "v -1000 -0.01 1000\nf 1 4 3\nf 1 3 2\nusemtl ground\nf 5 8 7\nf 5 7 6\n");
    /* L_z = 10 000 cd/m² is 10000/179 W/(m² sr) */
    const double Lz = 10000.0 / 179.0;
    static const char *const env[2] = {"{\"radiance\": 1}",
                                       "{\"sky\": \"cie-overcast\", \"zenith_luminance\": 10000, \"ground_reflectance\": 0}"};
    static const char *const rad =
        "void glass pane\n0\n0\n3 .96 .96 .96\npane polygon skylight\n0\n0\n12 -1000 -1000 1 1000 -1000 1 "
        "1000 1000 1 -1000 1000 1\nvoid plastic black\n0\n0\n5 0 0 0 0 0\nblack polygon ground\n0\n0\n12 "
        "-1000 -1000 -0.01 1000 -1000 -0.01 1000 1000 -0.01 -1000 1000 -0.01\n"
        "void brightfunc skyfunc\n2 skybr skybright.cal\n0\n3 2 55.8659 0\n"
        "skyfunc glow sky_glow\n0\n0\n4 1 1 1 0\nsky_glow source sky\n0\n0\n4 0 0 1 180\n";
    for (int k = 0; k < 3; ++k) {
        ic_scene *s = NULL;
        ic_error err = {0};
        ic_vec3 up = k < 2 ? v3(0.0f, 1.0f, 0.0f) : v3(0.0f, 0.0f, 1.0f);
        if (k < 2) {
            char json[1024];
            snprintf(json, sizeof json,
                     "{\"meshes\": [{\"path\": \"skylight.obj\"}],\n \"materials\": {\"pane\": {\"type\": \"thin_glass\","
                     " \"ks\": 0.96, \"ior\": 1.52}},\n \"environment\": %s}\n", env[k]);
            test_write_file(IC_TEST_TMP "/skylight.json", json);
            test_load_scene(IC_TEST_TMP "/skylight.json", NULL, 16, 16, 0, &s, &err);
        } else {
            s = test_load_rad_text("skylight", rad, NULL, 16, 0, &err);
        }
        CHECK(s != NULL, "skylight %d loads: %s", k, err.message);
        if (!s)
            continue;
        const double scale = k == 0 ? 1.0 : k == 1 ? Lz : 55.8659;
        const double want = skylight_E(k, 1, scale), open = skylight_E(k, 0, scale);
        static const char *const what[3] = {"uniform sky (JSON)", "CIE overcast (JSON)", "gensky -c (.rad)"};
        double E[2], sg[2];
        for (int i = 0; i < 2; ++i) {
            if (!test_sensor_irradiance(s, v3(0.0f, 0.0f, 0.0f), up, i ? IC_INTEGRATOR_IC : IC_INTEGRATOR_PT, 2048,
                                        &E[i], &sg[i]))
                continue;
            printf("skylight, %s, %s: E %.5g +- %.3g, quadrature %.5g (%.2f sigma; %.2f %% of the open sky's %.5g)\n",
                   what[k], i ? "cache" : "path tracer", E[i], sg[i], want, (E[i] - want) / sg[i],
                   100.0 * want / open, open);
            CHECK(fabs(E[i] - want) <= 3.0 * sg[i], "skylight, %s, %s: E %g +- %g, expected %g", what[k],
                  i ? "cache" : "path tracer", E[i], sg[i], want);
        }
        CHECK(fabs(E[0] - E[1]) <= 3.0 * sqrt(sg[0] * sg[0] + sg[1] * sg[1]),
              "skylight, %s: path tracer %g and cache %g agree within their sigma", what[k], E[0], E[1]);
        if (k == 1) { /* the daylight factor: the mean transmittance over the overcast sky, weighted by cos θ */
            double ref = 0.0;
            CHECK(ic_points_daylight_reference(s, &ref, &err) == IC_OK, "daylight reference: %s", err.message);
            const double df = 100.0 * 179.0 * E[0] / ref, df_sigma = 100.0 * 179.0 * sg[0] / ref;
            const double df_want = 100.0 * want / (7.0 * PI_D / 9.0 * Lz);
            printf("skylight daylight factor: %.3f +- %.3f %%, quadrature %.3f %% (normal incidence: %.2f %%)\n", df,
                   df_sigma, df_want, 100.0 * pane_T(1.0, 1.52, 0.96));
            CHECK(fabs(df - df_want) <= 3.0 * df_sigma && fabs(df_want - 82.88) < 0.01,
                  "daylight factor under the pane %g +- %g %%, expected %g %%", df, df_sigma, df_want);
        }
        ic_scene_free(s);
    }
}

int main(void)
{
    test_bsdf();
    pane_in_front_of_light(0.0);
    pane_in_front_of_light(60.0);
    test_json();
    test_skylight();
    TEST_MAIN_END();
}
