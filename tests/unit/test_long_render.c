/*
 * test_long_render.c — what a long render offers its caller through irrcache/render.h (issue "An
 * installable library", long renders):
 *
 *   - checkpoints: the final render's image so far, handed out while it runs. A checkpoint of a
 *     one-pass render holds, per tile, either the final pixels exactly or black; checkpoints never change
 *     the final image (same bits with and without, on one thread or two), with adaptive sampling and
 *     with a time budget too;
 *   - progress reports with the whole render's elapsed time and time left: unknown (< 0) while the cache
 *     is built without a budget, known during the final render, and within the budget with one;
 *   - an interrupt during cache construction: every strategy stops before its next gather and renders a
 *     complete one-sample preview from the records it has (none, when the flag is set at its start);
 *   - the path tracer's rays under a time budget: every pass over a tile traces its blocks' anchor rays,
 *     whichever thread rendered it before, so that the count does not depend on scheduling;
 *   - an interrupt during a pass under a time budget (the film itself, ic_render_image): the pass skips its
 *     tiles not begun, each of which keeps its earlier passes' samples and is their mean;
 *   - an interrupt during the AOVs rendered after a whole image: the stats say the render was interrupted.
 */
#include "film/film.h"
#include "irrcache/render.h"
#include "test_render_util.h"
#include "test_util.h"

#include <string.h>

#define CORNELL IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json"
#define W 48
#define H 40

/* What the checkpoints of one render looked like. */
typedef struct checkpoints {
    int count;
    int bad_size;          /* a checkpoint of the wrong size or with a non-finite pixel */
    int completed_backwards; /* `completed` went down, or left [0, 1] */
    double last_completed;
    float *first;          /* the first checkpoint's pixels (malloc'd) */
} checkpoints;

static void on_checkpoint(void *user, const ic_render_checkpoint *cp)
{
    checkpoints *k = user;
    const ic_image *img = cp->image;
    size_t n = (size_t)W * H * 3;
    if (img->width != W || img->height != H)
        ++k->bad_size;
    for (size_t i = 0; img->width == W && img->height == H && i < n; ++i)
        if (!isfinite(img->rgb[i]))
            ++k->bad_size;
    if (cp->completed < k->last_completed || cp->completed < 0.0 || cp->completed > 1.0)
        ++k->completed_backwards;
    k->last_completed = cp->completed;
    if (!k->first && img->width == W && img->height == H && (k->first = malloc(sizeof *k->first * n)))
        memcpy(k->first, img->rgb, sizeof *k->first * n);
    ++k->count;
}

/* Renders the Cornell box with o on `threads` threads, with checkpoints as often as the film can take
 * them (every round of tiles) when k is given. */
static int render(ic_render_options o, int threads, checkpoints *k, ic_image *img, ic_render_stats *st)
{
    o.threads = threads;
    o.has_seed = 1;
    o.seed = 7;
    if (k) {
        memset(k, 0, sizeof *k);
        o.checkpoint_seconds = 1e-9;
        o.checkpoint = on_checkpoint;
        o.checkpoint_user = k;
    }
    memset(img, 0, sizeof *img);
    return test_render(CORNELL, W, H, &o, img, st);
}

static int same_pixels(const ic_image *a, const ic_image *b)
{
    return a->width == b->width && a->height == b->height && a->rgb && b->rgb &&
           !memcmp(a->rgb, b->rgb, sizeof *a->rgb * (size_t)a->width * a->height * 3);
}

/* Checkpoints leave the final image alone: the same bits with them (on 1 and 2 threads) as without. */
static void check_unchanged(const char *what, ic_render_options o, int want_partial_tiles)
{
    ic_image plain, one, two;
    ic_render_stats st;
    checkpoints k1, k2;
    CHECK(render(o, 2, NULL, &plain, &st), "%s: render", what);
    CHECK(render(o, 1, &k1, &one, &st), "%s: render with checkpoints, 1 thread", what);
    CHECK(render(o, 2, &k2, &two, &st), "%s: render with checkpoints, 2 threads", what);
    CHECK(same_pixels(&plain, &one) && same_pixels(&plain, &two),
          "%s: checkpoints do not change the final image (1 and 2 threads)", what);
    CHECK(k1.count > 0 && k2.count > 0, "%s: checkpoints were taken (%d, %d)", what, k1.count, k2.count);
    CHECK(k1.bad_size == 0 && k2.bad_size == 0, "%s: every checkpoint is a whole, finite image", what);
    CHECK(k1.completed_backwards == 0 && k2.completed_backwards == 0, "%s: completed grows within [0, 1]", what);
    /* One pass of all samples: a tile is black until it is done, then final (the same sums, the same
     * division); a checkpoint comes only with tiles left, so one is black somewhere. */
    if (want_partial_tiles && k1.first && plain.rgb) {
        int other = 0, black = 0, final = 0;
        for (int t = 0; t < W * H; ++t) {
            const float *c = &k1.first[3 * t], *f = &plain.rgb[3 * t];
            int is_black = c[0] == 0.0f && c[1] == 0.0f && c[2] == 0.0f;
            int is_final = !memcmp(c, f, sizeof *c * 3);
            black += is_black && !is_final;
            final += is_final;
            other += !is_black && !is_final;
        }
        CHECK(other == 0 && black > 0, "%s: the first checkpoint is the final pixels or black (%d final, %d black, "
              "%d other)", what, final, black, other);
    }
    free(k1.first);
    free(k2.first);
    ic_image_free(&plain);
    ic_image_free(&one);
    ic_image_free(&two);
}

/* The path tracer's rays do not depend on which thread rendered a tile before: each 4 x 4 pixel block traces
 * one ray to its centre for its light distribution (README, "Sampling") in every pass over it. A 16 x 4
 * image (one tile, four blocks) on one thread, 2 samples in two passes under a budget that never runs out,
 * traces exactly four rays more than in one pass (the same samples): the second pass's anchor rays. A thread
 * that still held the blocks from the first pass once traced none, so that the count (stats' rays, the job's
 * under MPI) depended on scheduling: 2 of 30 runs of a 48 x 36 image on 3 threads counted 4 rays fewer. */
static void check_rays_per_pass(void)
{
    ic_render_options o = test_seeded_options(2, 1, 7);
    ic_render_stats one, two;
    ic_image a = {0}, b = {0};
    CHECK(test_render(CORNELL, 16, 4, &o, &a, &one), "one pass of 2 samples");
    o.time_budget = 1e6; /* passes of 1 and 1 samples */
    CHECK(test_render(CORNELL, 16, 4, &o, &b, &two), "two passes under a time budget");
    CHECK(same_pixels(&a, &b), "the same samples in one pass and in two");
    CHECK(two.rays == one.rays + 4, "two passes trace the 4 blocks' anchor rays twice: %llu rays, one pass %llu",
          (unsigned long long)two.rays, (unsigned long long)one.rays);
    ic_image_free(&a);
    ic_image_free(&b);
}

/* Progress reports of one render. */
typedef struct reports {
    int count;
    int construction_known;   /* construction reports with eta >= 0 */
    int final_known;          /* final-render reports with eta >= 0 */
    int final_reports;
    int over_budget;          /* reports whose eta exceeds the budget left */
    int elapsed_backwards;
    double last_elapsed;
    double budget;
} reports;

static void on_report(void *user, const ic_render_progress *p)
{
    reports *r = user;
    ++r->count;
    if (p->elapsed < r->last_elapsed)
        ++r->elapsed_backwards;
    r->last_elapsed = p->elapsed;
    int final = !strcmp(p->phase, "final render");
    r->final_reports += final;
    if (final)
        r->final_known += p->eta >= 0.0;
    else
        r->construction_known += p->eta >= 0.0;
    if (r->budget > 0.0 && (p->eta < 0.0 || p->eta > fmax(r->budget - p->elapsed, 0.0) + 1e-9))
        ++r->over_budget;
}

static void check_reports(void)
{
    ic_render_options o = {0};
    o.integrator = IC_INTEGRATOR_IC;
    o.spp = 16;
    o.ic.gather.theta_strata = 8;
    o.ic.gather.phi_strata = 25;
    reports r;
    memset(&r, 0, sizeof r);
    o.progress_detail = on_report;
    o.progress_user = &r;
    ic_image img;
    ic_render_stats st;
    CHECK(render(o, 2, NULL, &img, &st), "render with progress");
    ic_image_free(&img);
    CHECK(r.count > 0 && r.final_reports > 0, "reports came (%d, %d of the final render)", r.count, r.final_reports);
    CHECK(r.construction_known == 0, "no time left is claimed while the cache is built without a budget (%d)",
          r.construction_known);
    CHECK(r.final_known == r.final_reports, "the final render's reports all know the time left (%d of %d)",
          r.final_known, r.final_reports);
    CHECK(r.elapsed_backwards == 0, "elapsed never goes back");

    /* With a budget, the time left is what is left of it, from the first report on. */
    memset(&r, 0, sizeof r);
    r.budget = o.time_budget = 2.0;
    o.spp = 0;
    CHECK(render(o, 2, NULL, &img, &st), "render with a budget");
    ic_image_free(&img);
    CHECK(r.count > 0 && r.over_budget == 0, "with a budget, every report's time left is within it (%d of %d "
          "outside)", r.over_budget, r.count);
}

/* The cancel flag, set by the first construction report: before any gather. */
typedef struct canceller {
    volatile sig_atomic_t flag;
    const char *phase;     /* the report that sets it */
} canceller;

static void cancel_at(void *user, const char *phase, double fraction)
{
    (void)fraction;
    canceller *c = user;
    if (!strcmp(phase, c->phase))
        c->flag = 1;
}

static void check_interrupted_construction(void)
{
    static const struct {
        ic_strategy strategy;
        const char *phase, *name;
    } cases[] = {{IC_STRATEGY_BATCH, "hit records", "batch"},
                 {IC_STRATEGY_ADAPTIVE, "adaptive passes", "adaptive"},
                 {IC_STRATEGY_LAZY, "lazy cache", "lazy"}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        canceller c = {0, cases[i].phase};
        ic_render_options o = {0};
        o.integrator = IC_INTEGRATOR_IC;
        o.ic.strategy = cases[i].strategy;
        o.spp = 64;
        /* Rays enough that finishing the construction would take minutes: it must not. */
        o.ic.gather.theta_strata = 80;
        o.ic.gather.phi_strata = 250;
        o.progress = cancel_at;
        o.progress_user = &c;
        o.cancel = &c.flag;
        ic_image img;
        ic_render_stats st;
        CHECK(render(o, 2, NULL, &img, &st), "%s: interrupted render returns", cases[i].name);
        int finite = 0;
        double mean = img.rgb ? test_image_mean(&img, &finite) : 0.0;
        CHECK(img.width == W && img.height == H && finite && mean > 0.0,
              "%s: a complete preview (mean %g)", cases[i].name, mean);
        CHECK(st.cancelled && st.completed == 0.0 && st.spp == 1, "%s: cancelled (%d), completed %g, %d spp",
              cases[i].name, st.cancelled, st.completed, st.spp);
        CHECK(st.records == 0, "%s: set before the first gather, no record was gathered (%u)", cases[i].name,
              st.records);
        CHECK(!st.cut_by_time, "%s: an interrupt is not a time budget", cases[i].name);
        ic_image_free(&img);
    }
}

/* An interrupt during the indirect AOV's render, after a whole final render: the image is the one an
 * uninterrupted render gives, the AOV stops at its next tile (tiles black), and the stats say the render
 * was interrupted (it returned exit status 0 and an unmarked AOV with black tiles when they did not). */
static void check_interrupted_aov(void)
{
    ic_render_options o = {0};
    o.integrator = IC_INTEGRATOR_IC;
    o.spp = 4;
    o.adaptive_sampling = IC_CACHE_OFF;
    o.ic.gather.theta_strata = 8;
    o.ic.gather.phi_strata = 25;
    ic_image img[2], aov[2];
    ic_render_stats st[2];
    for (int k = 0; k < 2; ++k) {
        ic_render_aovs aovs;
        memset(&aovs, 0, sizeof aovs);
        aovs.want_indirect = 1;
        ic_render_options ok = o;
        ok.aovs = &aovs;
        canceller c = {0, "indirect AOV"};
        if (k == 1) { /* the flag set by the AOV's first report (one thread: after its first tile) */
            ok.progress = cancel_at;
            ok.progress_user = &c;
            ok.cancel = &c.flag;
        }
        CHECK(render(ok, 1, NULL, &img[k], &st[k]), "AOV render %d returns", k);
        aov[k] = aovs.indirect;
    }
    int black[2] = {0, 0};
    for (int k = 0; k < 2; ++k)
        for (int i = 0; aov[k].rgb && i < W * H; ++i)
            black[k] += aov[k].rgb[3 * i] + aov[k].rgb[3 * i + 1] + aov[k].rgb[3 * i + 2] == 0.0f;
    CHECK(!st[0].cancelled && st[1].cancelled && st[1].completed == 1.0,
          "interrupted in the AOV: cancelled (%d, uninterrupted %d), the final render whole (completed %g)",
          st[1].cancelled, st[0].cancelled, st[1].completed);
    CHECK(img[0].rgb && img[1].rgb && same_pixels(&img[0], &img[1]), "interrupted in the AOV: the image is whole");
    CHECK(aov[1].rgb && black[1] >= 16 * 16 && black[0] < black[1],
          "interrupted in the AOV: its tiles not begun are black (%d black pixels, %d uninterrupted)", black[1],
          black[0]);
    for (int k = 0; k < 2; ++k) {
        ic_image_free(&img[k]);
        ic_image_free(&aov[k]);
    }
}

/* Every sample 1, and the cancel flag set by sample number `at` (one thread: a fixed point of the render). */
typedef struct counting {
    volatile sig_atomic_t flag;
    uint64_t calls, at;
} counting;

static ic_vec3 one_and_count(void *ctx, const ic_ray *ray, uint32_t pixel, ic_rng *rng, int thread, uint64_t *rays)
{
    (void)ray, (void)pixel, (void)rng, (void)thread, (void)rays;
    counting *k = ctx;
    if (++k->calls == k->at)
        k->flag = 1;
    return v3s(1.0f);
}

/* A 64 x 64 camera (16 tiles of 16 x 16), and a one-thread loop over it whose samples are one_and_count's. */
static ic_camera square_camera(void)
{
    ic_camera cam = {0};
    cam.target = v3(0.0f, 1.0f, 0.0f);
    cam.up = v3(0.0f, 0.0f, 1.0f);
    cam.width = cam.height = 64;
    cam.fov_y_deg = 40.0f;
    return cam;
}

static ic_image_loop counting_loop(const ic_camera *cam, counting *k, int spp)
{
    ic_image_loop loop = {0};
    loop.camera = cam;
    loop.spp = spp;
    loop.threads = 1;
    loop.seed = 1;
    loop.cancel = &k->flag;
    return loop;
}

/* An interrupt in the last of the passes 1, 2, 4, ..., 32 under a budget that never runs out (64 x 64: 16
 * tiles of 16 x 16), during its fifth tile: the render stops within that pass, its tiles not begun keep
 * their 31 samples, and every pixel is the mean of what it holds, exactly 1. */
static void check_interrupted_budget(void)
{
    const ic_camera cam = square_camera();
    const uint64_t before = 31u * 64u * 64u, tile = 32u * 16u * 16u;
    counting k = {0, 0, before + 5u * tile - 7u};
    ic_image_loop loop = counting_loop(&cam, &k, 63);
    loop.time_budget = 1e6;
    ic_image img = {0};
    ic_image_loop_result res;
    ic_error err;
    CHECK(ic_render_image(&loop, one_and_count, &k, &img, &res, &err) == IC_OK, "budgeted render: %s", err.message);
    int exact = 1;
    for (int i = 0; img.rgb && i < 64 * 64 * 3; ++i)
        exact &= img.rgb[i] == 1.0f;
    CHECK(img.rgb && exact, "interrupted under a budget: every pixel is the mean of its own samples, 1");
    uint64_t taken = before + 5u * tile;
    CHECK(res.cancelled && k.calls == taken && res.spp_min == 31 && res.spp_max == 63,
          "the pass stopped after the tile the flag was set in (%llu samples, want %llu; %d to %d a pixel)",
          (unsigned long long)k.calls, (unsigned long long)taken, res.spp_min, res.spp_max);
    CHECK(fabs(res.completed - (double)taken / (63.0 * 64 * 64)) < 1e-12 && res.completed < 1.0,
          "completed %g: the share of the passes' samples taken", res.completed);
    ic_image_free(&img);
}

/* Adaptive sampling interrupted in its pilot pass (64 x 64 at 16 spp: a pilot of 4 samples a pixel, 16 tiles),
 * during its fifth tile: the tiles after it hold no samples and are black, and the statistics say so (the
 * fewest samples a pixel holds is 0, the share taken is 5 of 16 tiles' pilots over the planned 16 a pixel). */
static void check_interrupted_pilot(void)
{
    const ic_camera cam = square_camera();
    const uint64_t tile = 4u * 16u * 16u;
    counting k = {0, 0, 5u * tile - 7u};
    ic_image_loop loop = counting_loop(&cam, &k, 16);
    loop.adaptive = 1;
    ic_image img = {0};
    ic_image_loop_result res;
    ic_error err;
    CHECK(ic_render_image(&loop, one_and_count, &k, &img, &res, &err) == IC_OK, "adaptive render: %s", err.message);
    int lit = 0, black = 0;
    for (int i = 0; img.rgb && i < 64 * 64; ++i) {
        lit += img.rgb[3 * i] == 1.0f;
        black += img.rgb[3 * i] == 0.0f;
    }
    CHECK(lit == 5 * 256 && black == 11 * 256, "interrupted pilot: 5 tiles at 1 (%d pixels) and 11 black (%d)", lit,
          black);
    const double taken = 5.0 * (double)tile;
    CHECK(res.cancelled && res.spp_min == 0 && res.spp_max == 4 && fabs(res.completed - taken / (16.0 * 64 * 64)) < 1e-12,
          "interrupted pilot: %d to %d samples a pixel, completed %g (want 0 to 4, %g)", res.spp_min, res.spp_max,
          res.completed, taken / (16.0 * 64 * 64));
    ic_image_free(&img);
}

/* An image the library cannot hold (wider than IC_IMAGE_MAX_SIDE; ic_render refuses it first, the film
 * itself only after rendering): "too large", not out of memory. */
static void check_too_large(void)
{
    ic_camera cam = {0};
    cam.target = v3(0.0f, 1.0f, 0.0f);
    cam.up = v3(0.0f, 0.0f, 1.0f);
    cam.width = IC_IMAGE_MAX_SIDE + 1;
    cam.height = 1;
    cam.fov_y_deg = 40.0f;
    counting k = {0, 0, 0};
    ic_image_loop loop = {0};
    loop.camera = &cam;
    loop.spp = 1;
    loop.threads = 1;
    ic_image img = {0};
    ic_image_loop_result res;
    ic_error err = {0};
    CHECK(ic_render_image(&loop, one_and_count, &k, &img, &res, &err) == IC_ERR_INVALID_ARG &&
              strstr(err.message, "too large") && !img.rgb,
          "an image wider than the library holds is too large: %s", err.message);
}

int main(void)
{
    check_interrupted_budget();
    check_interrupted_pilot();
    check_too_large();
    ic_render_options pt = {0};
    pt.spp = 16;
    check_unchanged("path tracing, one pass", pt, 1);

    ic_render_options ic = {0};
    ic.integrator = IC_INTEGRATOR_IC;
    ic.spp = 16; /* adaptive sampling: a pilot and the rest */
    ic.ic.gather.theta_strata = 8;
    ic.ic.gather.phi_strata = 25;
    check_unchanged("irradiance caching, adaptive sampling", ic, 0);

    ic_render_options timed = pt;
    timed.spp = 8; /* passes of 1, 2, 4, 1 samples: a budget that never runs out */
    timed.time_budget = 1e6;
    check_unchanged("path tracing, passes under a time budget", timed, 0);
    check_rays_per_pass();

    check_reports();
    check_interrupted_construction();
    check_interrupted_aov();
    TEST_MAIN_END();
}
