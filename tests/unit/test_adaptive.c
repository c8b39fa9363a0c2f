/*
 * test_adaptive.c — adaptive caching (Křivánek et al. 2006 §4; src/integrators/ic_adaptive.c):
 *   1. full convergence checked independently: after construction, every shading point is re-read from
 *      the cache with ic_cache_query (all contributors, not the algorithm's 6-slot lists or change
 *      counters) and the Weber-law test of Křivánek et al. 2006 §4.3 is evaluated from scratch here: every point
 *      has a contribution, and no point with two or more reports a discontinuity (Ward and
 *      Tabellion–Lamorlette weights); the Cornell box converges within a bounded number of passes;
 *   2. a lower Weber fraction never gives fewer records (0.05, 0.02, 0.01);
 *   3. a smooth scene (open plane under a uniform sky) gets fewer records than the batch strategy at
 *      the same accuracy;
 *   4. 1 and 2 threads give bit-identical images.
 */
#include "test_util.h"

#include "integrators/ic_internal.h"
#include "irrcache/render.h"

#include <stdio.h>
#include <string.h>

#define CORNELL IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json"
#define MAX_CONTRIB 512

static void write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "cannot write %s\n", path);
        exit(1);
    }
    fputs(text, f);
    fclose(f);
}

static ic_scene *load(const char *path, int size)
{
    ic_error err = {0};
    ic_scene *scene = NULL;
    ic_scene_load_options lo = {0};
    lo.width = size;
    lo.height = size;
    if (ic_scene_load(path, &lo, &scene, &err) != IC_OK) {
        CHECK(0, "%s loads: %s", path, err.message);
        return NULL;
    }
    return scene;
}

static ic_render_options adaptive_options(float weber)
{
    ic_render_options opt;
    memset(&opt, 0, sizeof opt);
    opt.integrator = IC_INTEGRATOR_IC;
    opt.spp = 1;
    opt.max_depth = 8;
    opt.seed = 7;
    opt.has_seed = 1;
    opt.ic.strategy = IC_STRATEGY_ADAPTIVE;
    opt.ic.weber = weber;
    opt.ic.gather.theta_strata = 8;  /* 8×25 = 200 rays: fast, and noisy enough that σ matters */
    opt.ic.gather.phi_strata = 25;
    return opt;
}

/* The Křivánek et al. 2006 §4.3 test written independently of ic_adaptive.c: L = Σ w_i ρ/π E_i(p) / Σ w_i + L_d,
 * σ(L) = Y(ρ/π Σ w_i σ_i / Σ w_i); record i is discernible when |Y(L1) − Y(L2)| exceeds
 * weber·Y(L1) + max(σ(L1), σ(L2)). The relative slack of 1e-4 only absorbs summation order. */
static int has_discontinuity(const ic_cache *cache, const ic_cache_contribution *cb, uint32_t m, ic_vec3 albedo,
                             float direct, float weber)
{
    double W = 0.0, Y = 0.0, S = 0.0;
    double y[MAX_CONTRIB], s[MAX_CONTRIB];
    for (uint32_t k = 0; k < m; ++k) {
        ic_record rec;
        ic_cache_get_record(cache, cb[k].record, &rec);
        ic_vec3 v = cb[k].value;
        y[k] = 0.2126 * albedo.x * v.x + 0.7152 * albedo.y * v.y + 0.0722 * albedo.z * v.z;
        s[k] = 0.2126 * albedo.x * rec.sigma.x + 0.7152 * albedo.y * rec.sigma.y + 0.0722 * albedo.z * rec.sigma.z;
        W += cb[k].weight;
        Y += cb[k].weight * y[k];
        S += cb[k].weight * s[k];
    }
    double y1 = Y / W + direct, s1 = S / W;
    for (uint32_t i = 0; i < m; ++i) {
        double W2 = 0.0, Y2 = 0.0, S2 = 0.0;
        for (uint32_t k = 0; k < m; ++k) {
            if (k == i)
                continue;
            W2 += cb[k].weight;
            Y2 += cb[k].weight * y[k];
            S2 += cb[k].weight * s[k];
        }
        double y2 = Y2 / W2 + direct, s2 = S2 / W2;
        double limit = weber * y1 + (s1 > s2 ? s1 : s2);
        if (fabs(y1 - y2) > limit * (1.0 + 1e-4) + 1e-7)
            return 1;
    }
    return 0;
}

/* Runs construction only and checks the converged state; returns the record count (0 on failure). */
static uint32_t check_converged(const char *label, ic_scene *scene, const ic_render_options *opt, int max_passes)
{
    ic_adaptive_probe pr;
    ic_error err = {0};
    if (ic_ic_adaptive_probe_run(scene, opt, &pr, &err) != IC_OK) {
        CHECK(0, "%s: construction: %s", label, err.message);
        return 0;
    }
    static ic_cache_contribution cb[MAX_CONTRIB];
    uint32_t uncovered = 0, discontinuous = 0, multi = 0;
    for (uint32_t i = 0; i < pr.point_count; ++i) {
        ic_cache_lookup q;
        memset(&q, 0, sizeof q);
        q.position = pr.position[i];
        q.normal = pr.normal[i];
        q.acceptance = IC_ACCEPT_CONSTRUCTION;
        q.contributions = cb;
        q.contribution_capacity = MAX_CONTRIB;
        ic_cache_estimate e;
        if (!ic_cache_query(pr.cache, &q, &e)) {
            ++uncovered;
            continue;
        }
        if (e.contributor_count >= 2) {
            ++multi;
            discontinuous += (uint32_t)has_discontinuity(pr.cache, cb, e.contributions_written, pr.albedo[i],
                                                         pr.direct[i], pr.weber);
        }
    }
    uint32_t records = ic_cache_count(pr.cache);
    printf("%s: %u points, %u records, %d passes, %llu refinements, %u points with >= 2 contributions\n", label,
           pr.point_count, records, pr.passes, (unsigned long long)pr.refinements, multi);
    CHECK(pr.point_count > 0, "%s: shading points exist", label);
    CHECK(uncovered == 0, "%s: %u shading points without a contribution", label, uncovered);
    CHECK(discontinuous == 0, "%s: %u points with a discernible discontinuity", label, discontinuous);
    CHECK(pr.converged && pr.passes <= max_passes, "%s: converged in %d passes (bound %d)", label, pr.passes,
          max_passes);
    CHECK(pr.unresolved == 0, "%s: %u refinements found no excluding a_i", label, pr.unresolved);
    CHECK(multi > 0, "%s: records overlap somewhere (the test is not vacuous)", label);
    ic_ic_adaptive_probe_free(&pr);
    return records;
}

static void test_convergence(void)
{
    ic_scene *scene = load(CORNELL, 64);
    if (!scene)
        return;
    ic_render_options opt = adaptive_options(0.0f);
    check_converged("cornell 64x64 ward", scene, &opt, 16);
    opt.ic.cache.weight = IC_WEIGHT_TABELLION;
    check_converged("cornell 64x64 tabellion", scene, &opt, 16);
    ic_scene_free(scene);
}

static void test_weber_monotone(void)
{
    ic_scene *scene = load(CORNELL, 48);
    if (!scene)
        return;
    const float weber[3] = {0.05f, 0.02f, 0.01f};
    uint32_t records[3];
    for (int k = 0; k < 3; ++k) {
        ic_render_options opt = adaptive_options(weber[k]);
        char label[64];
        snprintf(label, sizeof label, "cornell 48x48 weber %.2f", (double)weber[k]);
        records[k] = check_converged(label, scene, &opt, 16);
    }
    CHECK(records[0] <= records[1] && records[1] <= records[2],
          "records never decrease with a lower Weber fraction: %u, %u, %u", records[0], records[1], records[2]);
    ic_scene_free(scene);
}

static uint32_t render_records(ic_scene *scene, const ic_render_options *opt)
{
    ic_image img = {0};
    ic_render_stats st;
    ic_error err = {0};
    if (ic_render(scene, opt, &img, &st, &err) != IC_OK) {
        CHECK(0, "render: %s", err.message);
        return 0;
    }
    ic_image_free(&img);
    return st.records;
}

static void test_smooth_scene(void)
{
    write_file(IC_TEST_TMP "/adaptive_plane.mtl", "newmtl ground\nKd 0.5 0.5 0.5\n");
    write_file(IC_TEST_TMP "/adaptive_plane.obj",
               "mtllib adaptive_plane.mtl\nusemtl ground\n"
               "v -1000 0 -1000\nv 1000 0 -1000\nv 1000 0 1000\nv -1000 0 1000\n"
               "f 1 3 2\nf 1 4 3\n");
    write_file(IC_TEST_TMP "/adaptive_plane.json",
               "{\n"
               "  \"camera\": {\"eye\": [0, 2, 0], \"target\": [0, 0, -4], \"up\": [0, 1, 0],\n"
               "             \"fov_y\": 60, \"width\": 64, \"height\": 64},\n"
               "  \"meshes\": [{\"path\": \"adaptive_plane.obj\"}],\n"
               "  \"environment\": {\"radiance\": [1, 1, 1]}\n"
               "}\n");
    ic_scene *scene = load(IC_TEST_TMP "/adaptive_plane.json", 64);
    if (!scene)
        return;
    ic_render_options opt = adaptive_options(0.0f);
    uint32_t adaptive = check_converged("open plane", scene, &opt, 16);
    opt.ic.strategy = IC_STRATEGY_ADAPTIVE;
    uint32_t adaptive_render = render_records(scene, &opt);
    opt.ic.strategy = IC_STRATEGY_BATCH;
    uint32_t batch = render_records(scene, &opt);
    printf("open plane: adaptive %u records, batch %u records\n", adaptive_render, batch);
    CHECK(adaptive == adaptive_render, "construction alone and the render agree: %u vs %u", adaptive,
          adaptive_render);
    CHECK(adaptive_render > 0 && adaptive_render < batch, "smooth scene: adaptive %u < batch %u records",
          adaptive_render, batch);
    ic_scene_free(scene);
}

static void test_thread_independence(void)
{
    ic_scene *scene = load(CORNELL, 48);
    if (!scene)
        return;
    ic_render_options opt = adaptive_options(0.0f);
    opt.spp = 2;
    ic_image a = {0}, b = {0};
    ic_render_stats sa, sb;
    ic_error err = {0};
    opt.threads = 1;
    CHECK(ic_render(scene, &opt, &a, &sa, &err) == IC_OK, "1 thread: %s", err.message);
    opt.threads = 2;
    CHECK(ic_render(scene, &opt, &b, &sb, &err) == IC_OK, "2 threads: %s", err.message);
    CHECK(a.rgb && b.rgb && memcmp(a.rgb, b.rgb, sizeof(float) * 3 * 48 * 48) == 0,
          "1 and 2 threads give bit-identical images");
    CHECK(sa.records == sb.records && sa.passes == sb.passes && sa.refinements == sb.refinements,
          "same records (%u, %u), passes (%d, %d), refinements (%u, %u)", sa.records, sb.records, sa.passes,
          sb.passes, sa.refinements, sb.refinements);
    ic_image_free(&a);
    ic_image_free(&b);
    ic_scene_free(scene);
}

int main(void)
{
    test_convergence();
    test_weber_monotone();
    test_smooth_scene();
    test_thread_independence();
    TEST_MAIN_END();
}
