/*
 * test_bounces.c — the cache renders exactly the bounce count the user asks for.
 *
 * With --max-depth D the path tracer gives direct light and D − 1 bounces exactly. The cache render
 * (default batch construction, whose hemisphere rays take the light after their hit from records
 * already made) must give the same image mean: a look-up at a hemisphere ray's hit may only take the
 * bounces the remaining depth allows. Checked at D = 2, 3 and 8 on the Cornell box against a path-traced
 * reference rendered as two halves with different seeds: their difference is the reference's own noise,
 * which must be well below the tolerance for the comparison to mean anything. The same holds for the
 * lazy and adaptive strategies, which use the same gathering; and --path-traced-gather, which takes no
 * look-ups, agrees with the default. A second box, with a glass tall box, a mirror short box and a
 * glossy floor, checks depth 3 where the final render's look-ups sit behind glass and in reflections; a
 * third, every wall varnished, the hemisphere rays' hits with a glossy lobe beside the diffuse one.
 */
#include "test_util.h"

#include "test_render_util.h"

#include "irrcache/image.h"

#define CORNELL IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json"
#define CORNELL_GLASS IC_SOURCE_DIR "/scenes/cornell-box/cornell-box-glass.json"
#define CORNELL_VARNISHED IC_SOURCE_DIR "/scenes/cornell-box/cornell-box-varnished.json"

/* Mean of the path tracer over two seeds, and their relative difference (its noise). */
static double reference_mean(const char *scene, int W, int H, int depth, int spp, double *noise)
{
    double m[2] = {0.0, 0.0};
    for (int k = 0; k < 2; ++k) {
        ic_render_options pt = {0};
        pt.spp = spp;
        pt.max_depth = depth;
        pt.seed = 7919 + (uint64_t)k;
        ic_image img = {0};
        int finite = 0;
        CHECK(test_render(scene, W, H, &pt, &img, NULL), "reference depth %d renders", depth);
        m[k] = test_image_mean(&img, &finite);
        CHECK(finite, "reference depth %d is finite", depth);
        ic_image_free(&img);
    }
    double mean = 0.5 * (m[0] + m[1]);
    *noise = mean > 0.0 ? fabs(m[0] - m[1]) / mean : 1.0;
    return mean;
}

static double cache_mean_gather(const char *scene, int W, int H, int depth, ic_strategy strategy, int path_traced,
                                ic_gather_method method)
{
    ic_render_options o = {0};
    o.integrator = IC_INTEGRATOR_IC;
    o.spp = 16;
    o.max_depth = depth;
    o.ic.strategy = strategy;
    o.ic.path_traced_gather = path_traced;
    o.ic.gather.method = method;
    ic_image img = {0};
    int finite = 0;
    CHECK(test_render(scene, W, H, &o, &img, NULL), "cache render depth %d renders", depth);
    double m = test_image_mean(&img, &finite);
    CHECK(finite, "cache render depth %d is finite", depth);
    ic_image_free(&img);
    return m;
}

static double cache_mean(const char *scene, int W, int H, int depth, ic_strategy strategy, int path_traced)
{
    return cache_mean_gather(scene, W, H, depth, strategy, path_traced, IC_GATHER_STRATIFIED);
}

/* depths: how many of 3, 2 and 8 (release builds); spp8: the reference's samples at depth 8; variants: at
 * depth 3, every strategy and gather too. */
static void test_scene_depths(const char *name, const char *scene, int W, int H, int spp, int depths_n, int spp8,
                              int variants)
{
    const int depths[] = {3, 2, 8};
    /* Sanitizer builds (IC_TEST_SANITIZED) look for memory errors: depth 3 runs every strategy and gather
     * method; the other depths take the same code paths and are checked by the release build. */
#ifdef IC_TEST_SANITIZED
    const int depth_count = 1;
    (void)depths_n;
#else
    const int depth_count = depths_n;
#endif
    for (int i = 0; i < depth_count; ++i) {
        int D = depths[i];
        double noise;
        double ref = reference_mean(scene, W, H, D, D == 8 ? spp8 : spp, &noise);
        CHECK(noise < 0.001, "%s depth %d: the reference's two halves differ by %.4f %% (noise too high for a "
              "0.5 %% comparison)", name, D, 100.0 * noise);
        double batch = cache_mean(scene, W, H, D, IC_STRATEGY_BATCH, 0);
        double rel = batch / ref - 1.0;
        printf("%s depth %d: reference noise %.4f %%, batch cache mean %+.4f %%\n", name, D, 100.0 * noise, 100.0 * rel);
        CHECK(fabs(rel) < 0.005, "%s depth %d: batch cache mean %+.3f %% off the path tracer's", name, D, 100.0 * rel);
        if (D == 3 && variants) {
            /* The depth where an extra bounce weighs most: every strategy, and the path-traced gather. */
            double lazy = cache_mean(scene, W, H, D, IC_STRATEGY_LAZY, 0) / ref - 1.0;
            double adaptive = cache_mean(scene, W, H, D, IC_STRATEGY_ADAPTIVE, 0) / ref - 1.0;
            double traced = cache_mean(scene, W, H, D, IC_STRATEGY_BATCH, 1) / ref - 1.0;
            printf("%s depth 3: lazy %+.4f %%, adaptive %+.4f %%, path-traced gather %+.4f %%\n", name,
                   100.0 * lazy, 100.0 * adaptive, 100.0 * traced);
            CHECK(fabs(lazy) < 0.005, "%s depth 3: lazy cache mean %+.3f %% off", name, 100.0 * lazy);
            CHECK(fabs(adaptive) < 0.005, "%s depth 3: adaptive cache mean %+.3f %% off", name, 100.0 * adaptive);
            CHECK(fabs(traced) < 0.005, "%s depth 3: path-traced gather mean %+.3f %% off", name, 100.0 * traced);
            /* The hemicube's texels have unequal weights; its bounce levels are split by ray count. */
            double cube = cache_mean_gather(scene, W, H, D, IC_STRATEGY_BATCH, 0, IC_GATHER_HEMICUBE) / ref - 1.0;
            printf("%s depth 3: hemicube gather %+.4f %%\n", name, 100.0 * cube);
            CHECK(fabs(cube) < 0.005, "%s depth 3: hemicube gather mean %+.3f %% off", name, 100.0 * cube);
        }
    }
}

int main(void)
{
    test_scene_depths("cornell", CORNELL, 96, 96, 256, 3, 256, 1);
    /* Behind glass, in a mirror and in glossy reflections the first diffuse vertex is deeper than the
     * camera's first hit: its look-up may take fewer of the records' bounces (ic_final.c). And the
     * hemisphere rays that hit the glass, the mirror or the floor are traced on, reading the records at
     * their next diffuse vertex with the levels left (ic_path_start.cached): at depth 8 several of them.
     * There the light through the glass makes the reference noisy: 2048 samples (0.24 % at 256). */
    test_scene_depths("cornell with glass, mirror and glossy floor", CORNELL_GLASS, 96, 96, 256, 3, 2048, 0);
    /* Every wall varnished (a diffuse and a Phong lobe): a hemisphere ray's hit reads the records for its
     * diffuse lobe and traces its glossy lobe on (ic_gathering.c, add_glossy_lobe), whose light must land
     * in the right bounce levels and carry the weight of the probability that traced it. */
    test_scene_depths("varnished cornell", CORNELL_VARNISHED, 96, 96, 256, 3, 1024, 0);
    TEST_MAIN_END();
}
