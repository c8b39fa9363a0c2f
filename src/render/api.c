/*
 * api.c — ic_render (irrcache/render.h), the driver: resolves the options against the scene file's
 * settings and the defaults, builds the accelerator, makes the chosen integrator (integrator.h),
 * prepares it, runs the film's image loop over its sample function, asks it for its AOVs, and fills
 * the statistics. Several processes (opt.comm, irrcache/comm.h) share construction and the image; the
 * ray counts are summed over them at the end. Progress reports pass through here on their way to the
 * caller, gaining the whole render's elapsed time and an estimate of the time left; so do the final
 * render's checkpoints, gaining the seed and the time.
 */
#include "irrcache/render.h"

#include "core/comm.h"
#include "core/threads.h"
#include "film/film.h"
#include "integrators/integrator.h"
#include "scene/scene.h"

#include <math.h>
#include <string.h>

void ic_scene_resolution(const ic_scene *scene, int *width, int *height)
{
    if (width)
        *width = scene ? scene->camera.width : 0;
    if (height)
        *height = scene ? scene->camera.height : 0;
}

float ic_scene_exposure(const ic_scene *scene)
{
    return scene && scene->settings.has_exposure ? scene->settings.exposure : 0.0f;
}

/* Where the render is, for the whole-render estimates of the progress reports. */
typedef enum render_stage { STAGE_PREPARE, STAGE_IMAGE, STAGE_AOVS } render_stage;

typedef struct render_clock {
    const ic_render_options *caller; /* the callbacks and their user pointer */
    double t0;             /* ic_seconds() when ic_render began */
    double budget;         /* time_budget, 0 for none */
    render_stage stage;
    double image_start;    /* the final render's start */
    double image_seconds;  /* its duration, once done */
    int aov_loops;         /* image loops the AOVs re-render with the final render's samples */
    int aov_started;       /* of them, begun */
    const char *aov_phase; /* the one running */
    double aov_start;
    int spp;
    uint64_t seed;
} render_clock;

/* Seconds until ic_render returns, or −1 when not known yet. An AOV loop takes the final render's
 * samples again, so each is estimated at the final render's duration (its samples cost less: this
 * errs long). */
static double time_left(const render_clock *k, double fraction, double now)
{
    double budget_left = fmax(k->t0 + k->budget - now, 0.0);
    if (k->stage == STAGE_PREPARE)
        return k->budget > 0.0 ? budget_left * (1.0 + k->aov_loops) : -1.0;
    if (k->stage == STAGE_IMAGE) {
        double spent = now - k->image_start, left;
        if (k->budget > 0.0)
            left = budget_left;
        else if (fraction > 0.0)
            left = spent / fmin(fraction, 1.0) - spent;
        else
            return -1.0;
        return left + k->aov_loops * (spent + left);
    }
    double spent = now - k->aov_start;
    double left = fraction > 0.0 ? spent / fmin(fraction, 1.0) - spent : fmax(k->image_seconds - spent, 0.0);
    return left + (k->aov_loops - k->aov_started) * k->image_seconds;
}

/* ic_progress_fn of every phase: the caller's reports, plain and detailed. */
static void report(void *user, const char *phase, double fraction)
{
    render_clock *k = user;
    if (k->caller->progress)
        k->caller->progress(k->caller->progress_user, phase, fraction);
    if (!k->caller->progress_detail)
        return;
    double now = ic_seconds();
    if (k->stage == STAGE_AOVS && phase != k->aov_phase) {
        k->aov_phase = phase;
        k->aov_start = now;
        ++k->aov_started;
    }
    ic_render_progress p = {phase, fraction, now - k->t0, time_left(k, fraction, now)};
    k->caller->progress_detail(k->caller->progress_user, &p);
}

/* The film's checkpoint, handed to the caller's. */
static void checkpoint(void *user, const ic_image *image, double completed)
{
    render_clock *k = user;
    ic_render_checkpoint cp = {image, completed, ic_seconds() - k->t0, k->spp, k->seed};
    k->caller->checkpoint(k->caller->checkpoint_user, &cp);
}

/* The integrators, by ic_integrator value. */
static const ic_integrator_create_fn integrators[] = {
    [IC_INTEGRATOR_PT] = ic_pt_integrator_create,
    [IC_INTEGRATOR_IC] = ic_ic_integrator_create,
};
#define INTEGRATOR_COUNT (sizeof integrators / sizeof integrators[0])

/* Checks opt and fills its zero fields from the scene file and the defaults. */
static ic_result resolve_options(const ic_scene *scene, ic_render_options *opt, ic_error *err)
{
    if (opt->spp < 0 || opt->max_depth < 0 || opt->threads < 0 || !(opt->time_budget >= 0.0)) /* NaN too */
        return ic_error_set(err, IC_ERR_INVALID_ARG, "negative --spp, --max-depth, --threads or --time (or a time "
                            "that is not a number); give values >= 0");
    if (opt->spp > IC_MAX_SPP || opt->max_depth > IC_MAX_MAX_DEPTH || opt->ic.light_samples > IC_MAX_LIGHT_SAMPLES ||
        opt->threads > IC_MAX_THREADS)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "--spp %d, --max-depth %d, --light-samples %d or --threads %d is "
                            "above its limit (%d, %d, %d, %d); give smaller values", opt->spp, opt->max_depth,
                            opt->ic.light_samples, opt->threads, IC_MAX_SPP, IC_MAX_MAX_DEPTH, IC_MAX_LIGHT_SAMPLES,
                            IC_MAX_THREADS);
    if (opt->adaptive_sampling != IC_CACHE_DEFAULT && opt->adaptive_sampling != IC_CACHE_ON &&
        opt->adaptive_sampling != IC_CACHE_OFF)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "adaptive_sampling %d: use IC_CACHE_ON, IC_CACHE_OFF or "
                            "IC_CACHE_DEFAULT", (int)opt->adaptive_sampling);
    if (opt->sampler != IC_SAMPLER_SOBOL && opt->sampler != IC_SAMPLER_RANDOM)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "unknown sampler %d; use sobol or random", (int)opt->sampler);
    uint64_t pixels = (uint64_t)scene->camera.width * (uint64_t)scene->camera.height;
    if (opt->max_image_pixels > IC_IMAGE_MAX_PIXELS)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "--max-image-pixels (max_image_pixels of ic_render_options) "
                            "%llu is above %llu (16384 x 16384), the largest image the library holds; give at "
                            "most that", (unsigned long long)opt->max_image_pixels,
                            (unsigned long long)IC_IMAGE_MAX_PIXELS);
    uint64_t max_pixels = opt->max_image_pixels ? opt->max_image_pixels : IC_DEFAULT_MAX_IMAGE_PIXELS;
    if (pixels > IC_IMAGE_MAX_PIXELS)
        return ic_error_set(err, IC_ERR_UNSUPPORTED, "an image of %d x %d = %llu pixels, more than %llu (16384 x "
                            "16384), the largest image the library holds; render it smaller",
                            scene->camera.width, scene->camera.height, (unsigned long long)pixels,
                            (unsigned long long)IC_IMAGE_MAX_PIXELS);
    if (pixels > max_pixels)
        return ic_error_set(err, IC_ERR_UNSUPPORTED, "an image of %d x %d = %llu pixels, more than the limit of %llu; "
                            "render it smaller, or raise the limit with --max-image-pixels (max_image_pixels of "
                            "ic_render_options) if the memory is there (about 80 bytes a pixel)",
                            scene->camera.width, scene->camera.height, (unsigned long long)pixels,
                            (unsigned long long)max_pixels);
    if ((unsigned)opt->integrator >= INTEGRATOR_COUNT || !integrators[opt->integrator])
        return ic_error_set(err, IC_ERR_UNSUPPORTED, "integrator %d is not available in this build",
                            (int)opt->integrator);
    /* A cache render's samples are cheap (a camera ray, a light sample, a look-up): it defaults to more. */
    if (opt->spp == 0)
        opt->spp = scene->settings.spp > 0              ? scene->settings.spp
                   : opt->time_budget > 0.0             ? 0
                   : opt->integrator == IC_INTEGRATOR_IC ? IC_DEFAULT_SPP_IC
                                                         : IC_DEFAULT_SPP_PT;
    if (opt->max_depth == 0)
        opt->max_depth = scene->settings.max_depth > 0 ? scene->settings.max_depth : IC_DEFAULT_MAX_DEPTH;
    if (!opt->has_seed && opt->seed == 0)
        opt->seed = scene->settings.seed ? scene->settings.seed : IC_DEFAULT_SEED;
    return IC_OK;
}

ic_result ic_render(const ic_scene *scene, const ic_render_options *opt_in, ic_image *out, ic_render_stats *stats,
                    ic_error *err)
{
    ic_render_options opt;
    memset(&opt, 0, sizeof opt);
    if (opt_in)
        opt = *opt_in;
    ic_render_stats local;
    ic_render_stats *st = stats ? stats : &local;
    memset(st, 0, sizeof *st);
    if (!scene || !out)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "ic_render: no scene or no output image given");
    ic_result r = resolve_options(scene, &opt, err);
    if (r != IC_OK)
        return r;
    st->threads = ic_resolve_threads(opt.threads);
    st->seed = opt.seed;
    st->ranks = ic_comm_size(opt.comm);
    double comm_seconds0 = opt.comm ? opt.comm->seconds : 0.0;
    uint64_t comm_bytes0 = opt.comm ? opt.comm->bytes : 0;

    double t0 = ic_seconds();
    /* Every report goes through the clock (the integrator reads opt.progress). */
    const ic_render_options caller = opt;
    render_clock clock;
    memset(&clock, 0, sizeof clock);
    clock.caller = &caller;
    clock.t0 = t0;
    clock.budget = opt.time_budget;
    clock.stage = STAGE_PREPARE;
    clock.spp = opt.spp;
    clock.seed = opt.seed;
    if (opt.aovs && opt.integrator == IC_INTEGRATOR_IC)
        clock.aov_loops = (opt.aovs->want_indirect != 0) + (opt.aovs->want_glossy != 0);
    if (opt.progress || opt.progress_detail) {
        opt.progress = report;
        opt.progress_user = &clock;
    }
    ic_accel *accel = NULL;
    if ((r = ic_accel_create(scene, &accel, err)) != IC_OK)
        return r;
    ic_stats_add_phase(st, "accel", ic_seconds() - t0);

    ic_tracer tr;
    tr.scene = scene;
    tr.accel = accel;
    tr.pt.max_depth = opt.max_depth;
    tr.pt.rr_depth = 0;
    tr.pt = ic_pt_params_resolve(tr.pt);

    ic_integrator_obj it = {NULL, NULL};
    int image_made = 0;
    r = integrators[opt.integrator](&tr, &opt, &it, err);
    if (r == IC_OK)
        r = it.ops->prepare(it.self, st, err);
    ic_image_loop loop;
    memset(&loop, 0, sizeof loop);
    ic_image_loop_result lr;
    memset(&lr, 0, sizeof lr);
    if (r == IC_OK) {
        loop.camera = &scene->camera;
        loop.spp = opt.spp;
        /* The budget is the whole render's: what the accelerator and preparation (cache construction)
         * took comes off the film's share; its first pass runs however little is left. */
        loop.time_budget = opt.time_budget > 0.0 ? fmax(opt.time_budget - (ic_seconds() - t0), 1e-3) : 0.0;
        loop.threads = opt.threads;
        loop.seed = opt.seed;
        loop.random_sampler = opt.sampler == IC_SAMPLER_RANDOM;
        loop.adaptive = opt.adaptive_sampling == IC_CACHE_ON ||
                        (it.ops->adaptive_by_default && opt.adaptive_sampling == IC_CACHE_DEFAULT &&
                         opt.spp >= IC_ADAPTIVE_SAMPLING_MIN_SPP && !(opt.time_budget > 0.0));
        loop.phase = it.ops->loop_phase;
        loop.progress = opt.progress;
        loop.progress_user = opt.progress_user;
        loop.comm = opt.comm;
        loop.cancel = opt.cancel;
        loop.tile_begin = it.ops->tile_begin;
        if (opt.checkpoint && opt.checkpoint_seconds > 0.0) {
            loop.checkpoint_seconds = opt.checkpoint_seconds;
            loop.checkpoint = checkpoint;
            loop.checkpoint_user = &clock;
        }
        clock.stage = STAGE_IMAGE;
        clock.image_start = ic_seconds();
        r = ic_render_image(&loop, it.ops->sample, it.self, out, &lr, err);
        image_made = r == IC_OK;
        clock.image_seconds = ic_seconds() - clock.image_start;
        clock.stage = STAGE_AOVS;
        loop.checkpoint = NULL; /* the AOVs are written with the final image */
    }
    if (r == IC_OK) {
        ic_stats_add_phase(st, it.ops->stats_phase, lr.seconds);
        st->rays += lr.rays;
        st->spp = lr.spp_done;
        st->spp_max = lr.spp_max;
        st->spp_min = lr.spp_min;
        st->cancelled = lr.cancelled;
        st->completed = lr.completed;
        st->rank_pixel_samples = lr.samples;
        st->rank_render_seconds = lr.busy_seconds;
        /* An interrupt during the AOVs' own renders (after a complete final render) leaves them partial:
         * said as an interrupted render whose final render completed. */
        if (opt.aovs && it.ops->aovs)
            r = it.ops->aovs(it.self, out, &loop, &lr, opt.aovs, &st->cancelled, err);
    }
    ic_integrator_destroy(&it);
    ic_accel_destroy(accel);
    /* The job's rays: every process's (exact in doubles below 2^53). */
    double rays[2] = {(double)st->rays, (double)st->gather_rays};
    if (r == IC_OK && (r = ic_comm_sum(opt.comm, rays, 2, err)) == IC_OK) {
        st->rays = (uint64_t)rays[0];
        st->gather_rays = (uint64_t)rays[1];
    }
    if (opt.comm) {
        st->rank_comm_seconds = opt.comm->seconds - comm_seconds0;
        st->rank_comm_bytes = opt.comm->bytes - comm_bytes0;
    }
    st->seconds = ic_seconds() - t0;
    st->rays_per_second = st->seconds > 0.0 ? (double)st->rays / st->seconds : 0.0;
    if (r != IC_OK && image_made) /* a failure after the film (the AOVs, the rays' sum): no image */
        ic_image_free(out);
    return r;
}
