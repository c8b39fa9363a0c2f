/*
 * test_ic.c — rendering with the irradiance cache (integrator IC) against the path-traced reference:
 *   1. the Cornell box: IC (batch, with and without gradients; lazy; the Hessian metric with round and
 *      elliptical records, Ward's and the error weight) within stated relMSE and LDR PSNR bounds of a
 *      path-traced reference, and every shading point covered after construction;
 *   2. batch and lazy, batch with adaptive sampling and with hemisphere sets, hemicube gathering with
 *      batch, lazy and adaptive, the Hessian error metric with batch and lazy, elliptical records with
 *      batch (error weight) and adaptive (the record filter is on in all): 1 and 2 threads give
 *      bit-identical images;
 *   3. a scene built to leak (a wall with a small gap above the floor, a bright light on the far side):
 *      without neighbor clamping (Křivánek et al. 2006 §5.2–5.3) records next to the gap extrapolate wrong light
 *      over the dark floor; with it the error near the gap falls;
 *   4. a thin step lit from the side: with neighbor clamping the step's indirect light is captured
 *      (the error next to the step falls).
 *   5. a room lit through a window by a large emitter outside: the records carry its light by default
 *      (ic_ic_options.large_emitters), the image mean matches the path tracer's with and without, and
 *      the error is lower with.
 *   6. batch construction stops on its own criterion (the share of eye-path look-up points without a
 *      record below --uncovered), says so in the stats, and reports a pass limit that cuts it short; a
 *      time budget stops batch and adaptive construction early and is reported (cut_by_time);
 *   7. the records AOV's background has the same median luminance, 0.18, whether the scene's light is
 *      10⁻³, 10³ or 10⁻⁴⁰ (a factor beyond a float's range, still finite pixels).
 *   8. a cache file refused for its hash names the option that differs (every option the hash holds,
 *      each changed alone), and the settings it may not hold (seed, final accuracy) still load it; test 5
 *      checks the same for the emitters the records carry.
 * Test 1 also compares the samplers and adaptive against uniform sampling, for both integrators.
 * The reference images are rendered here with the path tracer at high sample counts.
 */
#include "test_util.h"

#include "test_render_util.h"

#include "irrcache/defaults.h"
#include "irrcache/image.h"

#include <string.h>

#define CORNELL IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json"
#define CORNELL_CACHE IC_TEST_TMP "/ic_cornell.irc"

static ic_render_options ic_options(void)
{
    ic_render_options o = {0};
    o.integrator = IC_INTEGRATOR_IC;
    o.spp = 16;
    return o;
}

/* Renders scene with o; the result, and the library's message in err. */
static ic_result render_says(const char *scene_path, int width, int height, const ic_render_options *o, ic_error *err)
{
    ic_scene *scene = NULL;
    ic_scene_load_options lo = {0};
    lo.width = width;
    lo.height = height;
    memset(err, 0, sizeof *err);
    ic_result r = ic_scene_load(scene_path, &lo, &scene, err);
    ic_image img = {0};
    ic_render_stats st;
    if (r == IC_OK)
        r = ic_render(scene, o, &img, &st, err);
    ic_image_free(&img);
    ic_scene_free(scene);
    return r;
}

static void compare(const ic_image *img, const ic_image *ref, ic_image_metrics *m)
{
    ic_error err;
    memset(m, 0, sizeof *m);
    if (ic_image_compare(img, ref, m, &err) != IC_OK)
        fprintf(stderr, "compare: %s\n", err.message);
}

static void test_cornell(void)
{
    const int W = 64, H = 64;
    ic_render_options pt = {0};
    pt.spp = 1024;
    ic_image ref = {0}, ptlow = {0};
    CHECK(test_render(CORNELL, W, H, &pt, &ref, NULL), "reference renders");
    pt.spp = 16;
    CHECK(test_render(CORNELL, W, H, &pt, &ptlow, NULL), "16-spp path tracing renders");
    ic_image_metrics mpt;
    compare(&ptlow, &ref, &mpt);
    printf("cornell %dx%d: PT 16 spp relMSE %.5f PSNR-LDR %.2f\n", W, H, mpt.relmse, mpt.psnr_ldr);

    struct {
        const char *name;
        int strategy, no_gradients, recursive, bounces;
        double max_relmse, min_psnr_ldr;
        int hessian, ellipses, error_weight, hit_records; /* hit records: 0 the default, −1 off */
    } cases[] = {
        {"batch", IC_STRATEGY_BATCH, 0, 0, 0, 0.012, 33.0, 0, 0, 0, 0},
        {"batch, no hit records", IC_STRATEGY_BATCH, 0, 0, 0, 0.012, 33.0, 0, 0, 0, -1},
        {"batch, no gradients", IC_STRATEGY_BATCH, 1, 0, 0, 0.012, 33.0, 0, 0, 0, 0},
        {"lazy", IC_STRATEGY_LAZY, 0, 0, 0, 0.012, 33.0, 0, 0, 0, 0},
        {"lazy, recursive (5 levels)", IC_STRATEGY_LAZY, 0, 1, 5, 0.012, 33.0, 0, 0, 0, 0},
        {"batch, Hessian ellipses", IC_STRATEGY_BATCH, 0, 0, 0, 0.012, 33.0, 1, 1, 0, 0},
        {"lazy, ellipses, error weight", IC_STRATEGY_LAZY, 0, 0, 0, 0.012, 33.0, 1, 1, 1, 0},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        ic_render_options o = ic_options();
        o.ic.error = cases[k].hessian ? IC_ERROR_HESSIAN : IC_ERROR_SPLIT_SPHERE;
        o.ic.record_shape = cases[k].ellipses ? IC_SHAPE_ELLIPTICAL : IC_SHAPE_ROUND;
        o.ic.cache.weight = cases[k].error_weight ? IC_WEIGHT_ERROR : IC_WEIGHT_WARD;
        o.ic.strategy = cases[k].strategy;
        o.ic.no_gradients = cases[k].no_gradients;
        o.ic.recursive = cases[k].recursive;
        o.ic.bounces = cases[k].bounces;
        o.ic.hit_records = cases[k].hit_records < 0 ? IC_CACHE_OFF : IC_CACHE_DEFAULT;
        /* Batch construction makes hit records unless told not to (not for recursive levels). */
        const int hit_records = cases[k].strategy == IC_STRATEGY_BATCH && cases[k].hit_records >= 0;
        if (k == 0)
            o.threads = 2;
        ic_render_aovs aovs = {0};
        aovs.want_density = 1;
        o.aovs = &aovs;
        if (k == 0)
            o.ic.save_cache = CORNELL_CACHE; /* the sampler and adaptive-sampling checks below reuse it */
        ic_image img = {0};
        ic_render_stats st;
        if (!test_render(CORNELL, W, H, &o, &img, &st)) {
            CHECK(0, "%s renders", cases[k].name);
            continue;
        }
        ic_image_metrics m;
        compare(&img, &ref, &m);
        printf("cornell %dx%d: IC %-20s records %5u passes %2d relMSE %.5f PSNR-LDR %.2f\n", W, H, cases[k].name,
               st.records, st.passes, m.relmse, m.psnr_ldr);
        CHECK(m.relmse < cases[k].max_relmse, "%s: relMSE %.5f < %.4f", cases[k].name, m.relmse, cases[k].max_relmse);
        CHECK(m.psnr_ldr > cases[k].min_psnr_ldr, "%s: PSNR LDR %.2f > %.1f", cases[k].name, m.psnr_ldr,
              cases[k].min_psnr_ldr);
        /* IC at 16 spp is closer to the reference than the path tracer at 16 spp. */
        CHECK(m.relmse < mpt.relmse, "%s beats PT at equal spp (%.5f vs %.5f)", cases[k].name, m.relmse, mpt.relmse);
        /* Fewer records than pixels (the pixel bounds keep a·R ≥ 3 px on screen; the world stage adds
         * records where hemisphere rays land); recursive caching adds the deeper levels (off screen too). */
        const uint32_t own = st.records - st.hit_records;
        CHECK(own > 10 && own < (uint32_t)(cases[k].recursive ? 20 * W * H : W * H), "%s: %u records", cases[k].name,
              own);
        /* The hit stage's records, of their own kind, where batch construction makes them; the image's
         * records and their coverage (below) are checked without them; 1 and 2 threads the same image. */
        CHECK(hit_records ? st.hit_records > 100 : st.hit_records == 0, "%s: %u hit records", cases[k].name,
              st.hit_records);
        if (cases[k].strategy == IC_STRATEGY_BATCH) { /* every image record is in a pass or the closing sweep */
            uint32_t in_passes = 0;
            for (int p = 0; p < st.passes && p < IC_STATS_PASSES; ++p)
                in_passes += st.records_per_pass[p];
            CHECK(in_passes + st.coverage_records == own && st.coverage_records > 0,
                  "%s: %u records in passes and %u from the coverage sweep make the %u image records",
                  cases[k].name, in_passes, st.coverage_records, own);
        }
        if (k == 0) {
            ic_image one = {0};
            ic_render_options o1 = o;
            o1.threads = 1;
            o1.aovs = NULL;
            CHECK(test_render(CORNELL, W, H, &o1, &one, NULL) &&
                      memcmp(one.rgb, img.rgb, sizeof(float) * 3 * W * H) == 0,
                  "%s: 1 and %d threads give the same image", cases[k].name, o.threads);
            ic_image_free(&one);
        }
        /* The ceiling lamp covers 0.6 % of a shading point's hemisphere and is seen by 90 % of its light
         * samples: it stays light-sampled (test_window has the other case). */
        CHECK(st.cached_emitters == 0, "%s: the Cornell lamp is light-sampled (%u cached)", cases[k].name,
              st.cached_emitters);
        /* Coverage: every pixel whose centre sees a surface has a contributing record. A pixel surely
         * sees one when it and its 8 neighbours are lit in the reference (the pixel filter spreads light
         * one pixel beyond silhouettes). */
        int uncovered = 0;
        for (int y = 1; y < H - 1 && aovs.density.rgb; ++y) {
            for (int x = 1; x < W - 1; ++x) {
                int lit = 1;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        const float *r = &ref.rgb[3 * ((y + dy) * W + x + dx)];
                        lit &= r[0] + r[1] + r[2] > 0.0f;
                    }
                if (lit && aovs.density.rgb[3 * (y * W + x)] < 1.0f)
                    ++uncovered;
            }
        }
        CHECK(aovs.density.rgb && uncovered == 0, "%s: %d shading points without a record", cases[k].name, uncovered);
        ic_image_free(&aovs.density);
        ic_image_free(&img);
    }
    /* The sampler: scrambled Sobol' pairs (the default) against independent random numbers, same
     * spp. Both are unbiased (image means within 3 % of the reference); Sobol' is less noisy for the path tracer
     * and far less for IC, whose remaining noise is low-dimensional (pixel filter, direct light). */
    for (int integ = 0; integ < 2; ++integ) {
        ic_render_options o = integ ? ic_options() : pt;
        o.ic.load_cache = integ ? CORNELL_CACHE : NULL; /* the records of the "batch" case above */
        ic_image a = {0}, b = {0};
        o.sampler = IC_SAMPLER_RANDOM;
        int ok = test_render(CORNELL, W, H, &o, &a, NULL);
        o.sampler = IC_SAMPLER_SOBOL;
        ok &= test_render(CORNELL, W, H, &o, &b, NULL);
        CHECK(ok, "%s renders with both samplers", integ ? "IC" : "PT");
        if (ok) {
            ic_image_metrics ma, mb;
            compare(&a, &ref, &ma);
            compare(&b, &ref, &mb);
            int finite;
            double sa = test_image_mean(&a, &finite), sb = test_image_mean(&b, &finite),
                   sr = test_image_mean(&ref, &finite);
            printf("cornell %dx%d: %s 16 spp relMSE random %.5f, sobol %.5f; mean %.4f / %.4f (reference %.4f)\n", W, H,
                   integ ? "IC" : "PT", ma.relmse, mb.relmse, sa, sb, sr);
            CHECK(mb.relmse < (integ ? 0.6 : 0.9) * ma.relmse, "%s: Sobol' relMSE %.5f well below random's %.5f",
                  integ ? "IC" : "PT", mb.relmse, ma.relmse);
            /* 3 %: at 16 spp rare bright paths move the mean of either sampler by about 1 %. */
            CHECK(fabs(sb / sr - 1.0) < 0.03 && fabs(sa / sr - 1.0) < 0.03, "%s: both samplers unbiased", integ ? "IC" : "PT");
        }
        ic_image_free(&a);
        ic_image_free(&b);
    }
    /* Adaptive sampling (Frolov et al. 2012 §3.2; film/film.c): at the same mean spp it puts samples where the
     * noise is, so the error falls, and the image mean stays that of the reference. On for the cache
     * render by default, off for the path tracer. */
    for (int integ = 0; integ < 2; ++integ) {
        ic_render_options o = integ ? ic_options() : pt;
        o.ic.load_cache = integ ? CORNELL_CACHE : NULL; /* the records of the "batch" case above */
        o.spp = 32;
        ic_image a = {0}, b = {0};
        ic_render_stats sa, sb;
        o.adaptive_sampling = IC_CACHE_OFF;
        int ok = test_render(CORNELL, W, H, &o, &a, &sa);
        o.adaptive_sampling = IC_CACHE_ON;
        ok &= test_render(CORNELL, W, H, &o, &b, &sb);
        CHECK(ok, "%s renders with and without adaptive sampling", integ ? "IC" : "PT");
        if (ok) {
            ic_image_metrics ma, mb;
            compare(&a, &ref, &ma);
            compare(&b, &ref, &mb);
            int finite;
            double mean_a = test_image_mean(&a, &finite), mean_b = test_image_mean(&b, &finite),
                   sr = test_image_mean(&ref, &finite);
            printf("cornell %dx%d: %s 32 spp relMSE uniform %.5f, adaptive %.5f; mean %.4f / %.4f (reference %.4f); "
                   "spp %d / %d\n",
                   W, H, integ ? "IC" : "PT", ma.relmse, mb.relmse, mean_a, mean_b, sr, sa.spp, sb.spp);
            CHECK(sb.spp == 32, "adaptive: the mean spp is the budget (%d)", sb.spp);
            CHECK(sb.spp_max > 32 && sb.spp_max <= 8 * 32 && sa.spp_max == 32,
                  "adaptive: some pixels take more, none beyond the cap (%d; uniform %d)", sb.spp_max, sa.spp_max);
            CHECK(mb.relmse < (integ ? 0.85 : 0.97) * ma.relmse, "%s: adaptive relMSE %.5f below uniform %.5f",
                  integ ? "IC" : "PT", mb.relmse, ma.relmse);
            CHECK(fabs(mean_b / sr - 1.0) < 0.03, "%s: adaptive sampling keeps the mean (%.4f vs %.4f)",
                  integ ? "IC" : "PT", mean_b, sr);
        }
        ic_image_free(&a);
        ic_image_free(&b);
    }
    ic_image_free(&ref);
    ic_image_free(&ptlow);
}

static void test_threads(void)
{
    for (int variant = 0; variant < 12; ++variant) {
        /* variants 5–7: hemicube gathering with the batch, lazy and adaptive strategies; 8, 9: the
         * Hessian error metric with batch and lazy; 10, 11: elliptical records with batch (the error
         * weight) and adaptive */
        int strategy = variant == 6 || variant == 9 ? IC_STRATEGY_LAZY
                       : variant == 7 || variant == 11 ? IC_STRATEGY_ADAPTIVE
                       : variant == 0 || variant >= 3 ? IC_STRATEGY_BATCH : IC_STRATEGY_LAZY;
        ic_image a = {0}, b = {0};
        ic_render_options o = ic_options();
        o.spp = variant == 3 ? 16 : 2; /* variant 3: adaptive sampling's allocation is serial too */
        o.adaptive_sampling = variant == 3 ? IC_CACHE_ON : IC_CACHE_OFF;
        o.ic.strategy = (ic_strategy)strategy;
        o.ic.recursive = variant == 2;
        o.ic.bounces = variant == 2 ? 3 : 0;
        /* variant 4: record noise control, both kinds (the filter is on in every variant by default) */
        o.ic.record_sets = variant == 4 ? 4 : 0;
        o.ic.record_noise = variant == 4 ? 0.02f : 0.0f;
        o.ic.gather.method = variant >= 5 && variant <= 7 ? IC_GATHER_HEMICUBE : IC_GATHER_STRATIFIED;
        o.ic.error = variant >= 8 ? IC_ERROR_HESSIAN : IC_ERROR_SPLIT_SPHERE;
        o.ic.record_shape = variant >= 10 ? IC_SHAPE_ELLIPTICAL : IC_SHAPE_ROUND;
        o.ic.cache.weight = variant == 10 ? IC_WEIGHT_ERROR : IC_WEIGHT_WARD;
        /* A coarse cache (a few hundred records) is enough for the identity; the construction's cost
         * falls with the square of the accuracy. */
        o.ic.cache.accuracy = 0.4f;
        o.threads = 1;
        int ok = test_render(CORNELL, 48, 48, &o, &a, NULL);
        o.threads = 2;
        ok &= test_render(CORNELL, 48, 48, &o, &b, NULL);
        if (variant == 3) {
            /* The library refuses adaptive sampling it cannot do: spp below 8, or a time budget. */
            ic_render_options bad = o;
            bad.spp = 4;
            ic_image none = {0};
            CHECK(!test_render(CORNELL, 48, 48, &bad, &none, NULL), "adaptive sampling with 4 spp refused");
            ic_image_free(&none);
            bad.spp = 16;
            bad.time_budget = 1.0;
            CHECK(!test_render(CORNELL, 48, 48, &bad, &none, NULL), "adaptive sampling with a time budget refused");
            ic_image_free(&none);
            bad.time_budget = 0.0;
            bad.adaptive_sampling = (ic_cache_switch)7;
            CHECK(!test_render(CORNELL, 48, 48, &bad, &none, NULL), "adaptive_sampling 7 refused");
            ic_image_free(&none);
            bad = o;
            bad.ic.error = IC_ERROR_HESSIAN;
            bad.ic.gather.method = IC_GATHER_PROGRESSIVE;
            CHECK(!test_render(CORNELL, 48, 48, &bad, &none, NULL), "the Hessian metric with the progressive gather refused");
            ic_image_free(&none);
            bad = o;
            bad.ic.record_shape = IC_SHAPE_ELLIPTICAL;
            CHECK(!test_render(CORNELL, 48, 48, &bad, &none, NULL), "elliptical records without the Hessian refused");
            ic_image_free(&none);
            bad = o;
            bad.ic.recursive = 1;
            bad.ic.strategy = IC_STRATEGY_BATCH;
            CHECK(!test_render(CORNELL, 48, 48, &bad, &none, NULL), "recursive caching with the batch strategy refused");
            ic_image_free(&none);
        }
        CHECK(ok && memcmp(a.rgb, b.rgb, sizeof(float) * 3 * 48 * 48) == 0,
              "variant %d: 1 and 2 threads give identical images", variant);
        ic_image_free(&a);
        ic_image_free(&b);
    }
}

static double lum_at(const ic_image *img, int x, int y)
{
    const float *p = &img->rgb[3 * ((size_t)y * img->width + x)];
    return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
}

/* Mean luminance over rows [y0, y1). */
static double rows_mean(const ic_image *img, int y0, int y1)
{
    double s = 0.0;
    for (int y = y0; y < y1; ++y)
        for (int x = 0; x < img->width; ++x)
            s += lum_at(img, x, y);
    return s / ((double)(y1 - y0) * img->width);
}

/* Mean absolute luminance error over rows [y0, y1). */
static double rows_error(const ic_image *img, const ic_image *ref, int y0, int y1)
{
    double s = 0.0;
    for (int y = y0; y < y1; ++y)
        for (int x = 0; x < img->width; ++x)
            s += fabs(lum_at(img, x, y) - lum_at(ref, x, y));
    return s / ((double)(y1 - y0) * img->width);
}

/* Renders scene with the path tracer (reference) and with IC (lazy: Ward's serial order, where a
 * record's radius comes from its own rays alone) with and without neighbor clamping. */
static int clamp_pair(const char *scene, int W, int H, float accuracy, ic_image *ref, ic_image *on, ic_image *off)
{
    ic_render_options pt = {0};
    pt.spp = 256;
    int ok = test_render(scene, W, H, &pt, ref, NULL);
    ic_render_options o = ic_options();
    o.ic.strategy = IC_STRATEGY_LAZY;
    o.ic.cache.accuracy = accuracy;
    /* Ward's record evaluation (every bounce path-traced): with look-ups at the rays' hits, records
     * take the step's light from their neighbours and the effect of clamping is no longer isolated
     * (test_step checks that default separately). */
    o.ic.path_traced_gather = 1;
    /* Clamping alone: the record filter, which averages records over their neighbourhood, would take
     * the step's light from neighbours too. */
    o.ic.record_filter.mode = IC_CACHE_OFF;
    ok &= test_render(scene, W, H, &o, on, NULL);
    o.ic.cache.neighbor_clamp = IC_CACHE_OFF;
    ok &= test_render(scene, W, H, &o, off, NULL);
    CHECK(ok, "%s renders", scene);
    return ok;
}

static void test_leak(void)
{
    /* Křivánek et al. 2006 §5.3, fig. 5: a wall polygon that stops 0.02 above the floor polygon, a bright lamp on
     * the far side lighting the floor there, the camera on the dark side looking at the wall's foot.
     * Records next to the gap whose rays pass under the wall get large R-values and extrapolate the
     * gap's light over the dark floor; neighbor clamping bounds them by their neighbours' R. */
    test_write_file(IC_TEST_TMP "/leak.mtl", "newmtl grey\nKd 0.6 0.6 0.6\nnewmtl lamp\nKd 0 0 0\nKe 40 40 40\n");
    test_write_file(IC_TEST_TMP "/leak.obj",
                    "mtllib leak.mtl\nusemtl grey\n"
                    "v -4 0 -3\nv 4 0 -3\nv 4 0 3\nv -4 0 3\nf 1 3 2\nf 1 4 3\n"
                    "v 0 0.02 -3\nv 0 1.5 -3\nv 0 1.5 3\nv 0 0.02 3\nf 5 6 7\nf 5 7 8\n"
                    "usemtl lamp\n"
                    "v 2 1.4 -0.5\nv 3 1.4 -0.5\nv 3 1.4 0.5\nv 2 1.4 0.5\nf 9 10 11\nf 9 11 12\n");
    test_write_file(IC_TEST_TMP "/leak.json",
                    "{\n  \"camera\": {\"eye\": [-1.2, 1.2, 0], \"target\": [0, 0, 0], \"up\": [0, 1, 0],\n"
                    "             \"fov_y\": 50, \"width\": 96, \"height\": 96},\n"
                    "  \"meshes\": [{\"path\": \"leak.obj\"}]\n}\n");
    ic_image ref = {0}, on = {0}, off = {0};
    /* a = 0.3: records large enough that those by the gap reach over the dark floor. */
    if (clamp_pair(IC_TEST_TMP "/leak.json", 96, 96, 0.3f, &ref, &on, &off)) {
        /* The gap shows as the brightest row; the region is the dark side's 12 rows next to it. */
        int gap = 0;
        for (int y = 1; y < ref.height; ++y)
            if (rows_mean(&ref, y, y + 1) > rows_mean(&ref, gap, gap + 1))
                gap = y;
        int y0 = gap - 14, y1 = gap - 2;
        double r = rows_mean(&ref, y0, y1);
        double bias_on = rows_mean(&on, y0, y1) - r, bias_off = rows_mean(&off, y0, y1) - r;
        printf("leak: gap at row %d, reference %.5f, IC bias with neighbor clamping %+.5f, without %+.5f\n", gap, r,
               bias_on, bias_off);
        CHECK(fabs(bias_off) > 0.1 * r, "without neighbor clamping the light near the gap is wrong (%+.5f of %.5f)",
              bias_off, r);
        CHECK(fabs(bias_on) < 0.4 * fabs(bias_off), "neighbor clamping removes the error near the gap (%+.5f vs %+.5f)",
              bias_on, bias_off);
    }
    ic_image_free(&ref);
    ic_image_free(&on);
    ic_image_free(&off);
}

static void test_step(void)
{
    /* Křivánek et al. 2006 §5.2, fig. 4: a thin step (height 0.06) on a floor, lit from the side by a low sun; the
     * floor next to the step receives light bounced off the step's lit face, a feature the random
     * rays of distant records miss. */
    test_write_file(IC_TEST_TMP "/step.mtl", "newmtl grey\nKd 0.7 0.7 0.7\n");
    test_write_file(IC_TEST_TMP "/step.obj",
                    "mtllib step.mtl\nusemtl grey\n"
                    "v -6 0 -6\nv 6 0 -6\nv 6 0 6\nv -6 0 6\nf 1 3 2\nf 1 4 3\n"
                    /* the step: a box x in [0, 2], y in [0, 0.06], z in [-3, 3] */
                    "v 0 0 -3\nv 2 0 -3\nv 2 0 3\nv 0 0 3\nv 0 0.06 -3\nv 2 0.06 -3\nv 2 0.06 3\nv 0 0.06 3\n"
                    "f 9 11 10\nf 9 12 11\n"  /* top */
                    "f 5 8 12\nf 5 12 9\n"    /* x = 0 face */
                    "f 6 10 11\nf 6 11 7\n"   /* x = 2 face */
                    "f 5 9 10\nf 5 10 6\n"    /* z = -3 face */
                    "f 8 7 11\nf 8 11 12\n"); /* z = 3 face */
    test_write_file(IC_TEST_TMP "/step.json",
                    "{\n  \"camera\": {\"eye\": [-1.2, 0.9, 0], \"target\": [0.2, 0, 0], \"up\": [0, 1, 0],\n"
                    "             \"fov_y\": 45, \"width\": 64, \"height\": 64},\n"
                    "  \"meshes\": [{\"path\": \"step.obj\"}],\n"
                    "  \"lights\": [{\"type\": \"sun\", \"direction\": [-1, 0.35, 0], \"irradiance\": [3, 3, 3]}]\n}\n");
    ic_image ref = {0}, on = {0}, off = {0};
    /* A coarse accuracy (a = 0.5) leaves few records on the floor, so whether the step is noticed
     * depends on neighbor clamping (Křivánek et al. 2006 §5.2: without it many more records are
     * needed). */
    if (clamp_pair(IC_TEST_TMP "/step.json", 64, 64, 0.5f, &ref, &on, &off)) {
        /* Rows 36–48: the step's foot and the floor in front of it, lit by the step's face. */
        double e_on = rows_error(&on, &ref, 36, 48), e_off = rows_error(&off, &ref, 36, 48);
        double bias_on = rows_mean(&on, 36, 48) - rows_mean(&ref, 36, 48);
        double bias_off = rows_mean(&off, 36, 48) - rows_mean(&ref, 36, 48);
        printf("step: reference %.4f, error with neighbor clamping %.4f (bias %+.4f), without %.4f (bias %+.4f)\n",
               rows_mean(&ref, 36, 48), e_on, bias_on, e_off, bias_off);
        CHECK(e_on < 0.75 * e_off, "neighbor clamping captures the step's indirect light (error %.4f vs %.4f)", e_on,
              e_off);
        CHECK(fabs(bias_on) < 0.5 * fabs(bias_off), "the step's light is no longer missing (bias %+.4f vs %+.4f)",
              bias_on, bias_off);
        /* The default record evaluation (look-ups at the hemisphere rays' hits) captures it too. */
        ic_render_options o = ic_options();
        o.ic.strategy = IC_STRATEGY_LAZY;
        o.ic.cache.accuracy = 0.5f;
        ic_image dflt = {0};
        if (test_render(IC_TEST_TMP "/step.json", 64, 64, &o, &dflt, NULL)) {
            double e = rows_error(&dflt, &ref, 36, 48);
            printf("step: default record evaluation, error %.4f\n", e);
            CHECK(e < 1.25 * e_on, "default evaluation captures the step (error %.4f vs %.4f)", e, e_on);
        }
        ic_image_free(&dflt);
    }
    ic_image_free(&ref);
    ic_image_free(&on);
    ic_image_free(&off);
}

/* A room lit through a window by a large emitter outside it, a sky-like quad of 44 × 44 m of which the
 * window shows a few square metres: almost every light sample on it hits the wall (cv²_light in the
 * hundreds) while a hemisphere ray sees it through the window at a few per cent of the hemisphere
 * (cv²_gather some tens), so by default the records carry its light (ic_ic_options.large_emitters).
 * With and without that, the image's mean matches the path tracer's (the emitter's light counted once, nowhere lost),
 * and with it the error is lower at equal samples. */
static void test_window(void)
{
    test_write_window_scene(IC_TEST_TMP);
    const char *scene = IC_TEST_TMP "/window.json";
    const int W = 64, H = 48;
    ic_render_options pt = {0};
    pt.spp = 2048;
    ic_image ref = {0}, on = {0}, off = {0};
    ic_render_stats st_on, st_off;
    int ok = test_render(scene, W, H, &pt, &ref, NULL);
    ic_render_options o = ic_options();
    o.spp = 32;
    o.threads = 2;
    ok &= test_render(scene, W, H, &o, &on, &st_on);
    /* The choice is made serially on the shading points: one thread gives the same image. */
    ic_image one = {0};
    o.threads = 1;
    o.ic.save_cache = IC_TEST_TMP "/window_cached.icc"; /* for the refusal below */
    ok &= test_render(scene, W, H, &o, &one, NULL);
    o.ic.save_cache = NULL;
    CHECK(ok && memcmp(on.rgb, one.rgb, sizeof(float) * 3 * W * H) == 0,
          "window: 1 and 2 threads give the same image with the emitter cached");
    ic_image_free(&one);
    o.ic.large_emitters.mode = IC_CACHE_OFF;
    ok &= test_render(scene, W, H, &o, &off, &st_off);
    /* Light samples on the emitter are mostly blocked and the rest carry large weights: the sampled
     * render's mean is checked at more samples, where its right-skewed noise is small. */
    ic_image off_many = {0};
    o.spp = 512;
    ok &= test_render(scene, W, H, &o, &off_many, NULL);
    CHECK(ok, "window scene renders");
    if (ok) {
        int f0, f1, f2;
        double r = test_image_mean(&ref, &f0), m_on = test_image_mean(&on, &f1),
               m_off = test_image_mean(&off_many, &f2);
        ic_image_metrics e_on, e_off;
        compare(&on, &ref, &e_on);
        compare(&off, &ref, &e_off);
        printf("window: reference mean %.5f; large emitter cached: %u triangles, mean %.5f, relMSE %.5f; sampled: "
               "mean %.5f (512 spp), relMSE %.5f\n", r, st_on.cached_emitters, m_on, e_on.relmse, m_off, e_off.relmse);
        CHECK(f0 && f1 && f2, "finite images");
        CHECK(st_on.cached_emitters == 2 && st_off.cached_emitters == 0,
              "the window's emitter is cached by default (%u triangles) and not with large_emitters off (%u)",
              st_on.cached_emitters, st_off.cached_emitters);
        CHECK(fabs(m_on / r - 1.0) < 0.03, "cached: the image mean matches the path tracer's (%.5f vs %.5f)", m_on, r);
        CHECK(fabs(m_off / r - 1.0) < 0.03, "sampled: the image mean matches the path tracer's (%.5f vs %.5f)", m_off,
              r);
        CHECK(e_on.relmse < 0.8 * e_off.relmse, "cached: relMSE %.5f below sampled %.5f", e_on.relmse, e_off.relmse);
        /* Sampled, this emitter's plain light samples are heavy-tailed (cv² about 800 a sample against
         * about 70 for a cosine ray), so the hemisphere rays' hits that records serve pair each light
         * sample with a cosine ray (ic_ctx.large_sampled); without the pair a record that draws a tail
         * is a blotch. Low-pass error over seeds 1-4 at 32 spp: 0.0043 with the pair, 0.0070 without. */
        double lowpass = 0.0;
        o.spp = 32;
        for (int seed = 1; seed <= 4; ++seed) {
            ic_image img = {0};
            ic_image_metrics e;
            o.seed = (uint64_t)seed;
            if (test_render(scene, W, H, &o, &img, NULL)) {
                compare(&img, &ref, &e);
                lowpass += e.relmse_lowpass / 4.0;
            } else {
                lowpass = INFINITY;
            }
            ic_image_free(&img);
        }
        printf("window, sampled: low-pass error %.5f over seeds 1-4 at 32 spp\n", lowpass);
        CHECK(lowpass < 0.0055, "sampled: low-pass error %.5f over seeds 1-4 (0.0070 without the MIS pair at "
              "the hits the records serve)", lowpass);
    }
    /* The choice does not depend on the seed, so that a cache saved with one seed loads with another: with
     * 8 × 29 rays per record this emitter sits at the threshold, where a pilot drawn from the seed cached it
     * for some seeds and not for others (32 × 24, seeds 1–6: 0, 2, 0, 0, 0, 2 triangles). */
    ic_render_options ps = ic_options();
    ps.spp = 1;
    ps.ic.gather.theta_strata = 8;
    ps.ic.gather.phi_strata = 29;
    uint32_t cached[6];
    int loads = 0;
    for (int k = 0; k < 6; ++k) {
        ic_image img = {0};
        ic_render_stats st;
        ps.seed = (uint64_t)k + 1;
        ps.ic.save_cache = k == 0 ? IC_TEST_TMP "/window.icc" : NULL;
        ps.ic.load_cache = NULL;
        cached[k] = test_render(scene, 32, 24, &ps, &img, &st) ? st.cached_emitters : UINT32_MAX;
        ic_image_free(&img);
        if (k == 0)
            continue;
        ps.ic.load_cache = IC_TEST_TMP "/window.icc";
        loads += test_render(scene, 32, 24, &ps, &img, NULL);
        ic_image_free(&img);
    }
    CHECK(cached[1] == cached[0] && cached[2] == cached[0] && cached[3] == cached[0] && cached[4] == cached[0] &&
              cached[5] == cached[0] && cached[0] != UINT32_MAX && loads == 5,
          "the large-emitter choice is the same for seeds 1-6 (%u %u %u %u %u %u triangles), and seed 1's cache "
          "loads with the others (%d of 5)", cached[0], cached[1], cached[2], cached[3], cached[4], cached[5], loads);
    /* A load with --large-emitters off, whose records would carry none of them, is refused saying so. */
    {
        ic_error err;
        ic_render_options lo = ic_options();
        lo.spp = 1;
        lo.ic.load_cache = IC_TEST_TMP "/window_cached.icc";
        CHECK(render_says(scene, W, H, &lo, &err) == IC_OK, "the cache with the emitter cached loads: %s", err.message);
        lo.ic.large_emitters.mode = IC_CACHE_OFF;
        ic_result r = render_says(scene, W, H, &lo, &err);
        CHECK(r == IC_ERR_MISMATCH && strstr(err.message, "made with emitters lit through the records (--large-emitters "
                                                          "and the view decide): 2 triangles (choice ") &&
                  strstr(err.message, "this run's: none; use the settings it was made with"),
              "large emitters off against a cache that carries them: %s \"%s\"", ic_result_name(r), err.message);
    }
    ic_image_free(&ref);
    ic_image_free(&on);
    ic_image_free(&off);
    ic_image_free(&off_many);
}

static void test_convergence(void)
{
    ic_render_options o = ic_options();
    o.spp = 2;
    ic_image img = {0};
    ic_render_stats st, grow;
    /* By default a pass that adds fewer than 2 % of the image's records ends construction too (pass_growth): it
     * stops no later than the uncovered share alone, and its last pass is such a pass or the share's. */
    CHECK(test_render(CORNELL, 96, 96, &o, &img, &grow), "batch renders");
    ic_image_free(&img);
    o.ic.pass_growth.mode = IC_CACHE_OFF;
    CHECK(test_render(CORNELL, 96, 96, &o, &img, &st), "batch renders with --pass-growth off");
    printf("convergence: %d passes, %u records, uncovered share %.5f; with pass growth: %d passes, %u records, "
           "share %.5f\n", st.passes, st.records, st.uncovered_share, grow.passes, grow.records, grow.uncovered_share);
    /* At this size a pass's last few candidates (min_candidates) may end it before the share does. */
    CHECK(!st.cut_short && st.uncovered_share < 0.01 && st.passes < 30,
          "batch converges on the uncovered share: cut short %d, share %.5f, %d passes", st.cut_short,
          st.uncovered_share, st.passes);
    uint32_t made = 0;
    for (int p = 0; p + 1 < grow.passes && p < 32; ++p)
        made += grow.records_per_pass[p];
    const int last = grow.passes - 1;
    CHECK(!grow.cut_short && grow.passes <= st.passes && last < 32 &&
              (grow.uncovered_share < 0.001 || grow.records_per_pass[last] < 0.02 * made ||
               grow.passes == st.passes),
          "pass growth: converged in %d passes (%d without), the last adding %u records to %u", grow.passes,
          st.passes, last < 32 ? grow.records_per_pass[last] : 0u, made);
    ic_image_free(&img);
    ic_render_stats loose;
    o.ic.uncovered = 0.02f;
    CHECK(test_render(CORNELL, 96, 96, &o, &img, &loose), "batch renders with --uncovered 0.02");
    CHECK(!loose.cut_short && loose.uncovered_share < 0.02 && loose.passes < st.passes && loose.records < st.records,
          "a looser criterion stops sooner: %d passes (%u records) against %d (%u)", loose.passes, loose.records,
          st.passes, st.records);
    ic_image_free(&img);
    ic_render_stats cut;
    o.ic.uncovered = 0.0f;
    o.ic.max_passes = 2;
    CHECK(test_render(CORNELL, 96, 96, &o, &img, &cut), "batch renders with 2 passes at most");
    CHECK(cut.cut_short && cut.passes == 3 && cut.uncovered_share > 0.001,
          "a pass limit before convergence is reported: cut short %d, %d passes, share %.4f", cut.cut_short,
          cut.passes, cut.uncovered_share);
    ic_image_free(&img);
    /* A share it cannot reach: without pass growth the pass limit cuts construction short; with it,
     * construction ends on the first pass after the screen stage that adds fewer than 2 % of the image's
     * records. */
    ic_render_options strict = ic_options();
    strict.spp = 2;
    strict.ic.uncovered = 1e-6f;
    ic_render_stats ss, sl;
    CHECK(test_render(CORNELL, 96, 96, &strict, &img, &ss), "batch renders with --uncovered 1e-6");
    ic_image_free(&img);
    strict.ic.pass_growth.mode = IC_CACHE_OFF;
    strict.ic.max_passes = 12;
    CHECK(test_render(CORNELL, 96, 96, &strict, &img, &sl), "batch renders with --uncovered 1e-6, growth off");
    ic_image_free(&img);
    uint32_t before = 0; /* the image's records: hit records do not count */
    int first_slow = -1;
    for (int p = 0; p < ss.passes && p < 32; ++p) {
        if (p >= IC_DEFAULT_SCREEN_PASSES && first_slow < 0 && ss.records_per_pass[p] < 0.02 * before)
            first_slow = p;
        before += ss.records_per_pass[p];
    }
    printf("pass growth: %d passes, %u records; growth off: %d passes (cut short %d)\n", ss.passes, ss.records,
           sl.passes, sl.cut_short);
    CHECK(!ss.cut_short && first_slow > 0 && ss.passes == first_slow + 1 && sl.cut_short,
          "an unreachable share: growth ends construction at the first slow pass (%d passes, first slow %d, cut "
          "short %d); without it the limit cuts it (cut short %d)", ss.passes, first_slow, ss.cut_short, sl.cut_short);
    /* A time budget far too small: batch and adaptive construction stop after their first pass, say so, and
     * the image is still made (uncovered points take the fallback ray). */
    for (int strategy = 0; strategy < 2; ++strategy) {
        ic_render_options t = ic_options();
        t.spp = 0;
        t.time_budget = 1e-4;
        t.ic.strategy = strategy ? IC_STRATEGY_ADAPTIVE : IC_STRATEGY_BATCH;
        ic_render_stats ts;
        int ok = test_render(CORNELL, 96, 96, &t, &img, &ts);
        int finite = 0;
        double mean = ok ? test_image_mean(&img, &finite) : 0.0;
        CHECK(ok && ts.cut_by_time && ts.cut_short && ts.passes <= 2 && finite && mean > 0.0,
              "%s under a 0.1 ms budget: cut by time %d, cut short %d, %d passes, mean %.4f",
              strategy ? "adaptive" : "batch", ts.cut_by_time, ts.cut_short, ts.passes, mean);
        ic_image_free(&img);
    }
}

/* Gradient-difference scaling (Castaño 2014) with a looser accuracy makes fewer image records, not more, and
 * converges: its threshold τ follows the accuracy. With τ fixed at 0.1 the Cornell box at 64 × 64 made 6,773
 * image records in 31 passes (cut short) at a = 1 against 1,430 at a = 0.3. */
static void test_gradient_difference_accuracy(void)
{
    ic_render_options o = ic_options();
    o.spp = 2;
    o.ic.cache.gradient_difference = IC_CACHE_ON;
    ic_render_stats st[2];
    const float a[2] = {0.3f, 1.0f};
    for (int k = 0; k < 2; ++k) {
        ic_image img = {0};
        o.ic.cache.accuracy = a[k];
        CHECK(test_render(CORNELL, 64, 64, &o, &img, &st[k]), "renders with gradient-difference scaling, a = %g",
              (double)a[k]);
        ic_image_free(&img);
    }
    const uint32_t image[2] = {st[0].records - st[0].hit_records, st[1].records - st[1].hit_records};
    printf("gradient difference: %u image records (%d passes) at a = 0.3, %u (%d passes) at a = 1\n", image[0],
           st[0].passes, image[1], st[1].passes);
    CHECK(!st[1].cut_short && image[1] < image[0],
          "a = 1 with gradient-difference scaling: %u image records in %d passes (cut short %d), against %u at "
          "a = 0.3", image[1], st[1].passes, st[1].cut_short, image[0]);
}

/* A lamp stays light-sampled (ic_emitters.c: the records take an emitter only where a pilot measures
 * their hemisphere rays to be the better estimator): a plain ceiling panel over a closed room, 2.5 %
 * of a shading point's hemisphere at the median (above the pre-filter's 1 %, so the pilot decides),
 * and the same panel over a table and a partition that hide it from 44 % of its light samples from a
 * low camera (the former rule, cache a large emitter when at most 75 % of its light samples reach it,
 * cached that one and doubled relMSE). The window of test_window (whose scene files it reuses) is still
 * cached. */
static void test_panel(void)
{
    test_write_file(IC_TEST_TMP "/panel.mtl", "newmtl wall\nKd 0.7 0.7 0.7\nnewmtl lamp\nKd 0 0 0\nKe 10 10 10\n");
    /* The room x, z in [0, 4], y in [0, 3], and the panel x, z in [1.4, 2.6] just under the ceiling,
     * facing down. */
    const char *room = "mtllib panel.mtl\nusemtl wall\n"
                       "v 0 0 0\nv 4 0 0\nv 4 0 4\nv 0 0 4\nv 0 3 0\nv 4 3 0\nv 4 3 4\nv 0 3 4\n"
                       "f 1 4 3 2\nf 5 6 7 8\nf 1 5 8 4\nf 2 3 7 6\nf 1 2 6 5\nf 4 8 7 3\n"
                       "usemtl lamp\nv 1.4 2.99 1.4\nv 2.6 2.99 1.4\nv 2.6 2.99 2.6\nv 1.4 2.99 2.6\nf 9 10 11 12\n";
    test_write_file(IC_TEST_TMP "/panel.obj", room);
    char furnished[2048];
    snprintf(furnished, sizeof furnished, "%s%s", room,
             "usemtl wall\n"
             /* a table top at y = 0.8 and a partition z = 2, x in [0, 2.5], 2.2 high (both sides) */
             "v 0.8 0.8 0.8\nv 3.2 0.8 0.8\nv 3.2 0.8 3.2\nv 0.8 0.8 3.2\nf 13 16 15 14\nf 13 14 15 16\n"
             "v 0 0 2\nv 2.5 0 2\nv 2.5 2.2 2\nv 0 2.2 2\nf 17 18 19 20\nf 17 20 19 18\n");
    test_write_file(IC_TEST_TMP "/panel-table.obj", furnished);
    test_write_file(IC_TEST_TMP "/panel.json",
                    "{\n  \"camera\": {\"eye\": [3.6, 2.0, 0.4], \"target\": [1.0, 0.8, 3.0], \"up\": [0, 1, 0],\n"
                    "             \"fov_y\": 70, \"width\": 64, \"height\": 48},\n"
                    "  \"meshes\": [{\"path\": \"panel.obj\"}]\n}\n");
    test_write_file(IC_TEST_TMP "/panel-table.json",
                    "{\n  \"camera\": {\"eye\": [3.8, 0.6, 0.2], \"target\": [1.5, 0.2, 2.5], \"up\": [0, 1, 0],\n"
                    "             \"fov_y\": 70, \"width\": 64, \"height\": 48},\n"
                    "  \"meshes\": [{\"path\": \"panel-table.obj\"}]\n}\n");
    const struct {
        const char *name, *path;
        uint32_t cached;
    } cases[] = {
        {"plain ceiling panel", IC_TEST_TMP "/panel.json", 0},
        {"ceiling panel over a table", IC_TEST_TMP "/panel-table.json", 0},
        {"window (test_window)", IC_TEST_TMP "/window.json", 2},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        for (int threads = 1; threads <= 2; ++threads) {
            ic_render_options o = ic_options();
            o.spp = 2;
            o.threads = threads;
            ic_image img = {0};
            ic_render_stats st;
            int ok = test_render(cases[k].path, 64, 48, &o, &img, &st);
            CHECK(ok && st.cached_emitters == cases[k].cached,
                  "%s, %d thread(s): %u emitting triangles cached (want %u)", cases[k].name, threads,
                  ok ? st.cached_emitters : 0u, cases[k].cached);
            ic_image_free(&img);
        }
    }
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* The median luminance of img's pixels whose luminance is finite and above zero (0 if none). */
static double median_lit_luminance(const ic_image *img)
{
    size_t n = (size_t)img->width * img->height, lit = 0;
    float *lum = malloc(sizeof *lum * (n ? n : 1));
    for (size_t i = 0; lum && i < n; ++i) {
        const float *p = &img->rgb[3 * i];
        float y = 0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2];
        if (isfinite(y) && y > 0.0f)
            lum[lit++] = y;
    }
    double median = 0.0;
    if (lit > 0) {
        qsort(lum, lit, sizeof *lum, cmp_float);
        median = lum[lit / 2];
    }
    free(lum);
    return median;
}

/* The records AOV's background reads alike however bright the scene: one grey room lit by a white ceiling
 * panel of radiance 10⁻³ and of 10³ (the beauty images' medians a million times apart). Where no mark is
 * drawn (the marks' colours are not grey; the room is), the records image is the beauty image times one
 * factor, which brings the beauty's median lit luminance to the documented 0.18 at both scales. */
static void test_records_background(void)
{
    const char *room = "mtllib dimroom.mtl\nusemtl wall\n"
                       "v 0 0 0\nv 4 0 0\nv 4 0 4\nv 0 0 4\nv 0 3 0\nv 4 3 0\nv 4 3 4\nv 0 3 4\n"
                       "f 1 4 3 2\nf 5 6 7 8\nf 1 5 8 4\nf 2 3 7 6\nf 1 2 6 5\nf 4 8 7 3\n"
                       "usemtl lamp\nv 1.4 2.99 1.4\nv 2.6 2.99 1.4\nv 2.6 2.99 2.6\nv 1.4 2.99 2.6\nf 9 10 11 12\n";
    test_write_file(IC_TEST_TMP "/dimroom.obj", room);
    test_write_file(IC_TEST_TMP "/dimroom.json",
                    "{\n  \"camera\": {\"eye\": [3.6, 2.0, 0.4], \"target\": [1.0, 0.8, 3.0], \"up\": [0, 1, 0],\n"
                    "             \"fov_y\": 70, \"width\": 48, \"height\": 36},\n"
                    "  \"meshes\": [{\"path\": \"dimroom.obj\"}]\n}\n");
    static const double scales[3] = {1e-3, 1e3, 1e-40}; /* the last: 0.18 / the median is beyond a float */
    double beauty_median[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k) {
        char mtl[256];
        snprintf(mtl, sizeof mtl, "newmtl wall\nKd 0.6 0.6 0.6\nnewmtl lamp\nKd 0 0 0\nKe %g %g %g\n", scales[k],
                 scales[k], scales[k]);
        test_write_file(IC_TEST_TMP "/dimroom.mtl", mtl);
        ic_render_options o = ic_options();
        o.spp = 1;
        o.ic.cache.max_radius = -1.0f; /* few records, so that most pixels are unmarked */
        o.ic.min_radius_px = 12.0f;
        ic_render_aovs aovs = {0};
        aovs.want_records = 1;
        o.aovs = &aovs;
        ic_image img = {0};
        ic_render_stats st;
        int ok = test_render(IC_TEST_TMP "/dimroom.json", 48, 36, &o, &img, &st) && aovs.records.rgb;
        CHECK(ok, "lamp %g: renders with the records AOV", scales[k]);
        /* The factor from beauty to records image over the unmarked lit pixels: one value. */
        double lo = INFINITY, hi = 0.0;
        int unmarked = 0, not_finite = 0;
        for (int i = 0; ok && i < img.width * img.height; ++i) {
            const float *b = &img.rgb[3 * i], *r = &aovs.records.rgb[3 * i];
            not_finite += !isfinite(r[0]) || !isfinite(r[1]) || !isfinite(r[2]);
            if (b[0] > 0.0f && b[0] == b[1] && b[1] == b[2] && r[0] == r[1] && r[1] == r[2]) {
                lo = fmin(lo, (double)r[0] / b[0]); /* in double: the factor may be beyond a float */
                hi = fmax(hi, (double)r[0] / b[0]);
                ++unmarked;
            }
        }
        beauty_median[k] = ok ? median_lit_luminance(&img) : 0.0;
        double background = lo * beauty_median[k];
        printf("records background, lamp %g: beauty median %.3g, %d unmarked pixels, factor %.4g..%.4g, background "
               "median %.4f\n", scales[k], beauty_median[k], unmarked, lo, hi, background);
        CHECK(not_finite == 0, "lamp %g: every pixel of the records image finite (%d not)", scales[k], not_finite);
        CHECK(unmarked >= 100 && hi <= lo * (1.0 + 1e-5) * (k == 2 ? 1.01 : 1.0), /* denormal: fewer digits */
              "lamp %g: %d unmarked pixels, the records image the beauty times one factor (%g to %g)", scales[k],
              unmarked, lo, hi);
        CHECK(fabs(background - 0.18) < (k == 2 ? 1e-2 : 1e-3) * 0.18,
              "lamp %g: the background's median lit luminance %g is 0.18 (beauty's %g)", scales[k], background,
              beauty_median[k]);
        ic_image_free(&img);
        ic_image_free(&aovs.records);
    }
    CHECK(beauty_median[0] > 0.0 && beauty_median[1] > 1e5 * beauty_median[0],
          "the beauty images differ by the lamp's scale: medians %g and %g", beauty_median[0], beauty_median[1]);
}

/* The cache file's settings text (ic_context.c: ic_ic_records_identity) says what its hash holds: a file
 * refused for its hash names the one option changed, not two hashes. */
static void test_cache_settings(void)
{
    const char *path = IC_TEST_TMP "/ic_settings.irc";
    ic_render_options base = ic_options();
    base.spp = 1;
    base.ic.gather.theta_strata = 4;
    base.ic.gather.phi_strata = 13;
    base.ic.save_cache = path;
    ic_error err;
    CHECK(render_says(CORNELL, 12, 12, &base, &err) == IC_OK, "save: %s", err.message);
    base.ic.save_cache = NULL;
    base.ic.load_cache = path;
    CHECK(render_says(CORNELL, 12, 12, &base, &err) == IC_OK, "load: %s", err.message);
    enum { RAYS, GATHER, BOUNCES, MAX_DEPTH, NO_GRADIENTS, FILTER, SETS, PATH_TRACED, ERROR, STRATEGY, TGRAD, N_CASES };
    const char *says[N_CASES] = {
        [RAYS] = "made with --rays 52 (4 x 13 strata), this run has --rays 80 (5 x 16 strata); rerun with --rays 52",
        [GATHER] = "made with --gather stratified, this run has --gather hemicube (4 x 4 texels on top)",
        [BOUNCES] = "made with --bounces 7, this run has --bounces 2",
        [MAX_DEPTH] = "made with --bounces 7, this run has --bounces 3",
        [NO_GRADIENTS] = "made without --no-gradients, this run has --no-gradients",
        [FILTER] = "made with --record-filter 3, this run has --record-filter off",
        [SETS] = "made with --record-sets 1, this run has --record-sets 4",
        [PATH_TRACED] = "made without --path-traced-gather, this run has --path-traced-gather",
        [ERROR] = "made with --error split-sphere, this run has --error hessian",
        [STRATEGY] = "made with --strategy batch, this run has --strategy adaptive",
        [TGRAD] = "made with gather tgrad: none, this run's: ward-heckbert",
    };
    for (int k = 0; k < N_CASES; ++k) {
        ic_render_options o = base;
        switch (k) {
        case RAYS: o.ic.gather.theta_strata = 5, o.ic.gather.phi_strata = 16; break;
        case GATHER: o.ic.gather.method = IC_GATHER_HEMICUBE; break;
        case BOUNCES: o.ic.bounces = 2; break;
        case MAX_DEPTH: o.max_depth = 4; break;
        case NO_GRADIENTS: o.ic.no_gradients = 1; break;
        case FILTER: o.ic.record_filter.mode = IC_CACHE_OFF; break;
        case SETS: o.ic.record_sets = 4; break;
        case PATH_TRACED: o.ic.path_traced_gather = 1; break;
        case ERROR: o.ic.error = IC_ERROR_HESSIAN; break;
        case STRATEGY: o.ic.strategy = IC_STRATEGY_ADAPTIVE; break;
        case TGRAD: o.ic.gather.tgrad = IC_GATHER_TGRAD_WARD_HECKBERT; break;
        }
        ic_result r = render_says(CORNELL, 12, 12, &o, &err);
        CHECK(r == IC_ERR_MISMATCH && strstr(err.message, says[k]) && !strstr(err.message, "hash"),
              "case %d: %s \"%s\", expected \"%s\"", k, ic_result_name(r), err.message, says[k]);
    }
    /* What the records do not depend on: another seed, a looser final acceptance. */
    ic_render_options o = base;
    o.seed = 99;
    o.ic.cache.final_accuracy_scale = 2.0f;
    CHECK(render_says(CORNELL, 12, 12, &o, &err) == IC_OK, "another seed and final accuracy: %s", err.message);
    remove(path);
}

int main(void)
{
    test_cornell();
    test_threads();
    test_leak();
    test_step();
    test_window();
    test_panel();
    test_records_background();
    test_cache_settings();
    test_convergence();
    test_gradient_difference_accuracy();
    TEST_MAIN_END();
}
