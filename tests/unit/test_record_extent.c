/*
 * test_record_extent.c — a gather result with a Hessian becomes a record whose extent is where the
 * first-order extrapolation's error ½dᵀHd reaches the error target ε·E (Schwarzhaupt et al. 2012), under
 * each interpolation weight: ε is Ward's and the error weight's accuracy a, and Tabellion–Lamorlette's a
 * mapped to Ward's in proportion (their defaults, 0.15 and 1, ask the same 15 % of E). The extent the
 * weights accept is a·R = a·harmonic_mean_dist as ic_ic_record_from_gather leaves it (the cache's clamps
 * come later); an elliptical record keeps both semi-axes.
 */
#include "test_tracer.h"
#include "test_util.h"

#include "irrcache/render.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define CORNELL IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json"

/* A result whose luminance Hessian is diag(l0, l1) in the frame of normal +y, irradiance E grey. */
static ic_gather_result result_with(double E, double l0, double l1)
{
    ic_gather_result r;
    memset(&r, 0, sizeof r);
    r.irradiance = v3s((float)E);
    r.harmonic_mean_dist = 0.5f;
    r.ray_count = 512;
    r.has_hessian = 1;
    const ic_frame f = ic_frame_from_normal(v3(0.0f, 1.0f, 0.0f));
    r.hessian_t = f.t;
    r.hessian_b = f.b;
    for (int c = 0; c < 3; ++c) { /* grey: each channel's Hessian is the luminance one */
        r.hessian[c][0] = (float)l0;
        r.hessian[c][1] = 0.0f;
        r.hessian[c][2] = (float)l1;
    }
    return r;
}

int main(void)
{
    ic_error err = {0};
    ic_scene *scene = NULL;
    ic_accel *accel = NULL;
    ic_tracer tr;
    if (!test_tracer_load(CORNELL, 0, &scene, &accel, &tr, &err)) {
        CHECK(0, "the scene loads: %s", err.message);
        return 1;
    }
    const double E = 2.0, l0 = -8.0, l1 = 0.5; /* semi-axes √(2εE/|λ|): the first the smaller */
    struct {
        const char *name;
        int weight, shape;
        float accuracy; /* 0: the weight's default */
        double eps;     /* the error target the extent must meet */
    } cases[] = {
        {"Ward, default a", IC_WEIGHT_WARD, IC_SHAPE_ROUND, 0.0f, 0.15},
        {"Ward, a = 0.3", IC_WEIGHT_WARD, IC_SHAPE_ROUND, 0.3f, 0.3},
        {"error weight, default a", IC_WEIGHT_ERROR, IC_SHAPE_ROUND, 0.0f, 0.15},
        {"Tabellion-Lamorlette, default a", IC_WEIGHT_TABELLION, IC_SHAPE_ROUND, 0.0f, 0.15},
        {"Tabellion-Lamorlette, a = 2", IC_WEIGHT_TABELLION, IC_SHAPE_ROUND, 2.0f, 0.3},
        {"Tabellion-Lamorlette, elliptical", IC_WEIGHT_TABELLION, IC_SHAPE_ELLIPTICAL, 0.0f, 0.15},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        ic_render_options opt;
        memset(&opt, 0, sizeof opt);
        opt.integrator = IC_INTEGRATOR_IC;
        opt.spp = 1;
        opt.ic.error = IC_ERROR_HESSIAN;
        opt.ic.record_shape = cases[k].shape;
        opt.ic.cache.weight = cases[k].weight;
        opt.ic.cache.accuracy = cases[k].accuracy;
        ic_ctx *c = NULL;
        if (ic_ic_ctx_create(&tr, &opt, &c, NULL, &err) != IC_OK) {
            CHECK(0, "%s: a context: %s", cases[k].name, err.message);
            continue;
        }
        const ic_gather_result gr = result_with(E, l0, l1);
        const ic_candidate cand = {{0.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, 0.0f, 1};
        ic_record rec;
        ic_ic_record_from_gather(c, &cand, &gr, &rec);
        const double a = c->o.cache.accuracy, reach = a * rec.harmonic_mean_dist;
        const double minor = sqrt(2.0 * cases[k].eps * E / fabs(l0)), major = sqrt(2.0 * cases[k].eps * E / fabs(l1));
        /* The error ½|λ|s² at the extent, against ε·E. */
        const double err_minor = 0.5 * fabs(l0) * reach * reach * (cases[k].shape ? rec.ellipse_ratio * rec.ellipse_ratio : 1.0);
        printf("%-34s a %.3g: extent %.5f (round bound %.5f, ellipse major %.5f), error at the minor extent "
               "%.4f of E\n", cases[k].name, a, reach, minor, major, err_minor / E);
        if (cases[k].shape == IC_SHAPE_ROUND) {
            CHECK(fabs(reach / minor - 1.0) < 1e-4, "%s: the extent %.5f is where ½|λ|s² = εE (%.5f)", cases[k].name,
                  reach, minor);
        } else {
            const double want = fmin(major, IC_MAX_ELLIPSE_ASPECT * minor);
            CHECK(fabs(reach / want - 1.0) < 1e-4 && fabs(rec.ellipse_ratio * reach / minor - 1.0) < 1e-4,
                  "%s: semi-axes %.5f and %.5f, as ½|λ_k|s² = εE gives (%.5f, %.5f)", cases[k].name,
                  rec.ellipse_ratio * reach, reach, minor, want);
        }
        CHECK(fabs(err_minor / E - cases[k].eps) < 1e-3, "%s: the error at the extent is %.4f of E, the target %.3g",
              cases[k].name, err_minor / E, cases[k].eps);
        ic_ic_ctx_destroy(c);
    }
    ic_accel_destroy(accel);
    ic_scene_free(scene);
    TEST_MAIN_END();
}
