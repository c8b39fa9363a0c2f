/*
 * points.c — ic_points_compute (irrcache/points.h), the sensor-point driver: checks the points and
 * options, builds the accelerator, and estimates each point's irradiance with the path tracer (Veach 1997:
 * light sampling and a cosine-distributed path per sample, MIS between them) or with the irradiance cache
 * (Ward et al. 1988: lazy records at the sensors, their interpolation for the indirect light, light
 * sampling for every emitter and the sky at every point). Each point's random numbers are a hash of
 * (seed, point, sample): the results never depend on the thread count. Several processes (opt.comm)
 * gather a share of the records each (ic_ic_gather_points) and estimate one contiguous block of the
 * points each, then exchange the results: the same bits at any number of processes.
 */
#include "irrcache/points.h"

#include "core/comm.h"
#include "core/sampling.h"
#include "core/threads.h"
#include "integrators/ic_internal.h"
#include "scene/scene.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#define STREAM_PT 0x70617468ULL     /* rng purpose: a path-traced sample */
#define STREAM_DIRECT 0x6c696768ULL /* rng purpose: a light sample of the cache estimator */

double ic_illuminance(ic_vec3 E)
{
    return IC_LUMINOUS_EFFICACY * (IC_LUMINANCE_R * E.x + IC_LUMINANCE_G * E.y + IC_LUMINANCE_B * E.z);
}

/* 1 if every glow of a Radiance scene's sky is gensky -c's (skybright.cal's overcast type). */
static int is_radiance_overcast(const ic_sky *sky)
{
    if (sky->model != IC_SKY_RADIANCE || sky->glow_count == 0)
        return 0;
    for (int k = 0; k < sky->glow_count; ++k)
        if (sky->glows[k].cal.function != IC_SKY_FUNCTION_SKYBRIGHT || sky->glows[k].cal.type != IC_SKY_TYPE_OVERCAST)
            return 0;
    return 1;
}

/* The illuminance a Radiance scene's sky gives an unobstructed plane facing +z (up, as gensky writes the
 * sky): ∫ L cos θ dω over the upper hemisphere, as ½ ∫∫ L d(sin²θ) dφ by the midpoint rule. Not 7π/9·L_z:
 * skybright.cal blends the sky into the ground near the horizon (0.14 % less for the overcast sky), and an
 * unobstructed point should read 100 %. 2048 × 64 cells: the overcast sky has no azimuth, and the sum
 * changes by less than 1e-6 from half as many. */
static double radiance_sky_horizontal_lux(const ic_sky *sky)
{
    enum { RINGS = 2048, SECTORS = 64 };
    const double pi = 3.14159265358979323846;
    double E[3] = {0.0, 0.0, 0.0};
    for (int i = 0; i < RINGS; ++i) {
        const double s2 = (i + 0.5) / RINGS, sin_t = sqrt(s2), cos_t = sqrt(1.0 - s2);
        for (int j = 0; j < SECTORS; ++j) {
            const double phi = 2.0 * pi * (j + 0.5) / SECTORS;
            const ic_vec3 L = ic_sky_radiance(sky, v3((float)(sin_t * cos(phi)), (float)(sin_t * sin(phi)), (float)cos_t));
            E[0] += L.x;
            E[1] += L.y;
            E[2] += L.z;
        }
    }
    const double cell = 0.5 * (1.0 / RINGS) * (2.0 * pi / SECTORS);
    return ic_illuminance(v3((float)(E[0] * cell), (float)(E[1] * cell), (float)(E[2] * cell)));
}

ic_result ic_points_daylight_reference(const ic_scene *scene, double *lux, ic_error *err)
{
    if (!scene || !lux)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "ic_points_daylight_reference: NULL scene or result");
    const ic_sky *sky = &scene->env.sky;
    const int radiance_overcast = scene->env.enabled && is_radiance_overcast(sky);
    if (!scene->env.enabled || (sky->model != IC_SKY_CIE_OVERCAST && !radiance_overcast))
        return ic_error_set(err, IC_ERR_INVALID_ARG,
                            "%s: the daylight factor needs a CIE overcast sky; give the scene \"environment\": "
                            "{\"sky\": \"cie-overcast\", \"zenith_luminance\": 10000} (a Radiance scene: "
                            "gensky's -c output)",
                            scene->path);
    if (scene->sun.enabled || scene->point_light_count > 0 || scene->tri_light_count > 0)
        return ic_error_set(err, IC_ERR_INVALID_ARG,
                            "%s: the daylight factor is defined under the overcast sky alone; remove the scene's "
                            "other lights (sun, point lights, emitting surfaces)",
                            scene->path);
    /* a white sky: its luminance-weighted irradiance is its irradiance */
    *lux = radiance_overcast ? radiance_sky_horizontal_lux(sky) : IC_LUMINOUS_EFFICACY * sky->horizontal;
    return IC_OK;
}

/* Running sums of independent estimates of E (RGB and luminance), for their mean and its σ. */
typedef struct sample_sums {
    double sum[4], sum2[4];
    uint64_t n;
} sample_sums;

static void sums_add(sample_sums *s, const double v[4])
{
    for (int k = 0; k < 4; ++k) {
        s->sum[k] += v[k];
        s->sum2[k] += v[k] * v[k];
    }
    ++s->n;
}

/* Mean of the estimates and the σ of that mean (from their unbiased sample variance). */
static void sums_finish(const sample_sums *s, double mean[4], double sigma[4])
{
    double n = (double)s->n;
    for (int k = 0; k < 4; ++k) {
        mean[k] = n > 0.0 ? s->sum[k] / n : 0.0;
        double var = n > 1.0 ? (s->sum2[k] - n * mean[k] * mean[k]) / (n - 1.0) : 0.0;
        sigma[k] = n > 0.0 ? sqrt(fmax(var, 0.0) / n) : 0.0;
    }
}

typedef struct points_job {
    const ic_tracer *tr;
    const ic_ctx *ic;          /* integrator IC: the built cache; NULL for the path tracer */
    const ic_vec3 *p, *n;      /* points, unit normals */
    ic_point_result *out;
    uint64_t *rays;            /* per point (summed in order afterwards) */
    uint32_t first;            /* this process's block of points starts here */
    uint64_t seed;
    int samples;               /* pt: paths; ic: light samples */
    _Atomic uint32_t uncovered; /* lowest point no record covered, + 1 (0: none); the lowest, so that the
                                   message does not depend on which thread found one first */
    ic_points_noise noise;     /* ic: the records' pooled relative variance (R, G, B, luminance) */
    _Atomic uint32_t done;     /* points estimated so far (progress) */
    uint32_t own;              /* this process's points */
    ic_progress_fn progress;
    void *progress_user;
} points_job;

/* One point estimated: the share done, reported by thread 0 alone (one thread at a time, as promised). */
static void point_done(points_job *job, int thread)
{
    uint32_t done = atomic_fetch_add(&job->done, 1) + 1;
    if (thread == 0 && job->progress)
        job->progress(job->progress_user, "sensors", (double)done / (double)job->own);
}

/* One sample of E at sensor i (surface s, BSDF b): π times the white receiver's reflected radiance. */
typedef ic_vec3 (*point_sample_fn)(const points_job *job, uint32_t i, const ic_surface *s, const ic_bsdf *b,
                                   ic_rng *rng, uint64_t *rays);

/* Path-traced: a light sample plus a cosine-distributed path, MIS between them (f = 1/π, and f·cos/p = 1
 * for the cosine path). */
static ic_vec3 sample_pt(const points_job *job, uint32_t i, const ic_surface *s, const ic_bsdf *b, ic_rng *rng,
                         uint64_t *rays)
{
    const ic_tracer *tr = job->tr;
    ic_vec3 L = ic_direct_light(tr, s, b, job->n[i], &tr->scene->light_select, rng, rays);
    float u1, u2;
    ic_rng_2d(rng, &u1, &u2);
    ic_vec3 wi = ic_frame_to_world(&b->frame, ic_warp_cosine_hemisphere(u1, u2));
    float cos_i = v3_dot(wi, b->frame.n);
    if (cos_i > 0.0f) {
        ic_path_start st;
        memset(&st, 0, sizeof st);
        st.depth = 1;
        st.pdf = cos_i * IC_INV_PI;
        L = v3_add(L, ic_pt_li_from(tr, ic_spawn_ray(s, wi), &st, rng, rays));
    }
    return v3_scale(L, IC_PI);
}

/* The cache estimator's direct part: light samples of the sun, point lights and emitting surfaces, and of
 * the environment (the sensors' records leave out the sky their rays see directly, so that its light,
 * which changes fast across a room lit through windows, is sampled at every sensor, not interpolated). */
static ic_vec3 sample_direct(const points_job *job, uint32_t i, const ic_surface *s, const ic_bsdf *b, ic_rng *rng,
                             uint64_t *rays)
{
    ic_vec3 L = ic_ic_direct_light(job->ic, s, b, job->n[i], NULL, rng, rays);
    if (job->tr->scene->env.enabled)
        L = v3_add(L, ic_ic_env_light(job->ic, s, b, job->n[i], rng, rays));
    return v3_scale(L, IC_PI);
}

/* job->samples samples of fn at sensor i as REPLICATES independent randomised quasi-Monte Carlo estimates
 * (Owen 1995): each replicate draws its 2-D pairs from its own scrambling of the Sobol' sequence
 * (src/core/rng.h), so its samples cover the light's and the hemisphere's squares evenly (lower variance
 * than independent draws), while the replicates stay independent and unbiased: the spread of their means
 * gives σ. Samples are rounded up to a multiple of the replicates (at least one each: fewer than
 * IC_POINT_REPLICATES samples would leave σ from fewer replicates, or none). A sample that is not finite
 * (NaN or Inf, from a degenerate configuration) counts as 0, as the image's film drops such samples. */
static void estimate_point(const points_job *job, uint32_t i, uint64_t purpose, point_sample_fn fn, double mean[4],
                           double sigma[4], uint64_t *rays)
{
    ic_surface s;
    ic_bsdf b;
    ic_ic_sensor(job->tr->scene, job->p[i], job->n[i], &s, &b);
    const int replicates = IC_POINT_REPLICATES;
    int per = (job->samples + replicates - 1) / replicates;
    if (per < 1)
        per = 1;
    sample_sums reps;
    memset(&reps, 0, sizeof reps);
    for (int r = 0; r < replicates; ++r) {
        double acc[4] = {0.0, 0.0, 0.0, 0.0};
        uint64_t key = ic_hash4(job->seed, i, (uint64_t)r, purpose);
        for (int k = 0; k < per; ++k) {
            ic_rng rng = ic_rng_make(job->seed, i, (uint64_t)r * (uint64_t)per + (uint64_t)k, purpose);
            ic_rng_enable_lds(&rng, key, (uint32_t)k);
            ic_vec3 E = fn(job, i, &s, &b, &rng, rays);
            if (!v3_is_finite(E))
                continue;
            acc[0] += E.x;
            acc[1] += E.y;
            acc[2] += E.z;
        }
        double m[4] = {acc[0] / per, acc[1] / per, acc[2] / per, 0.0};
        m[3] = IC_LUMINANCE_R * m[0] + IC_LUMINANCE_G * m[1] + IC_LUMINANCE_B * m[2];
        sums_add(&reps, m);
    }
    sums_finish(&reps, mean, sigma);
}

static void store(ic_point_result *r, const double e[4], const double sg[4])
{
    r->irradiance = v3((float)e[0], (float)e[1], (float)e[2]);
    r->irradiance_sigma = v3((float)sg[0], (float)sg[1], (float)sg[2]);
    r->illuminance = IC_LUMINOUS_EFFICACY * e[3];
    r->illuminance_sigma = IC_LUMINOUS_EFFICACY * sg[3];
}

static void point_pt(void *ctx, int64_t item, int thread)
{
    points_job *job = ctx;
    uint32_t i = job->first + (uint32_t)item;
    double mean[4], sigma[4];
    uint64_t rays = 0;
    estimate_point(job, i, STREAM_PT, sample_pt, mean, sigma, &rays);
    store(&job->out[i], mean, sigma);
    job->rays[i] = rays;
    point_done(job, thread);
}

/* The cache's estimate at one sensor: the records' interpolation plus the light samples; the two errors
 * are independent, so their variances add. */
static void point_ic(void *ctx, int64_t item, int thread)
{
    points_job *job = ctx;
    uint32_t i = job->first + (uint32_t)item;
    ic_vec3 E_cache;
    double sc[4];
    if (!ic_ic_points_indirect(job->ic, job->p[i], job->n[i], &job->noise, &E_cache, sc)) {
        /* Construction leaves every sensor covered; a point it missed is reported, not guessed. */
        uint32_t seen = atomic_load(&job->uncovered);
        while ((seen == 0 || seen > i + 1) && !atomic_compare_exchange_weak(&job->uncovered, &seen, i + 1)) {
        }
        point_done(job, thread);
        return;
    }
    double mean[4], sigma[4];
    uint64_t rays = 0;
    estimate_point(job, i, STREAM_DIRECT, sample_direct, mean, sigma, &rays);
    double ec[4] = {E_cache.x, E_cache.y, E_cache.z,
                    IC_LUMINANCE_R * E_cache.x + IC_LUMINANCE_G * E_cache.y + IC_LUMINANCE_B * E_cache.z};
    double e[4], sg[4];
    for (int k = 0; k < 4; ++k) {
        e[k] = mean[k] + ec[k];
        sg[k] = sqrt(sigma[k] * sigma[k] + sc[k] * sc[k]);
    }
    store(&job->out[i], e, sg);
    job->rays[i] = rays;
    point_done(job, thread);
}

static int finite3(ic_vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

/* Checks opt and fills its zero fields from the scene file and the defaults. */
static ic_result resolve_options(const ic_scene *scene, ic_points_options *o, ic_error *err)
{
    if (o->integrator != IC_INTEGRATOR_PT && o->integrator != IC_INTEGRATOR_IC)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "unknown integrator %d; use pt or ic", (int)o->integrator);
    if (o->samples < 0 || o->light_samples < 0 || o->max_depth < 0 || o->threads < 0)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "negative samples, light samples, max depth or threads; give "
                            "values >= 0");
    if (o->samples > IC_MAX_POINT_SAMPLES || o->light_samples > IC_MAX_POINT_SAMPLES ||
        o->max_depth > IC_MAX_MAX_DEPTH || o->threads > IC_MAX_THREADS)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "samples %d, light samples %d, max depth %d or threads %d is above "
                            "its limit (%d, %d, %d, %d); give smaller values", o->samples, o->light_samples,
                            o->max_depth, o->threads, IC_MAX_POINT_SAMPLES, IC_MAX_POINT_SAMPLES, IC_MAX_MAX_DEPTH,
                            IC_MAX_THREADS);
    if (o->samples == 0)
        o->samples = IC_DEFAULT_POINT_SAMPLES;
    if (o->light_samples == 0)
        o->light_samples = IC_DEFAULT_POINT_LIGHT_SAMPLES;
    const int depth_from_scene = o->max_depth == 0 && scene->settings.max_depth > 0;
    if (o->max_depth == 0)
        o->max_depth = depth_from_scene ? scene->settings.max_depth : IC_DEFAULT_MAX_DEPTH;
    if (!o->has_seed && o->seed == 0)
        o->seed = scene->settings.seed ? scene->settings.seed : IC_DEFAULT_SEED;
    /* A record's hemisphere rays return at least their hit's direct light: one bounce at the least. Where the
     * depth is the scene file's, the message says so (a render of that scene takes it). */
    if (o->integrator == IC_INTEGRATOR_IC && o->max_depth < 2)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "max depth %d (direct light only%s%s) with the cache: its "
                            "records carry at least one bounce; use the path tracer, or a max depth of 2 or more",
                            o->max_depth, depth_from_scene ? ", from the \"render\" settings of " : "",
                            depth_from_scene ? scene->path : "");
    return IC_OK;
}

ic_result ic_points_compute(const ic_scene *scene, const ic_sensor_point *points, uint32_t count,
                            const ic_points_options *opt_in, ic_point_result *out, ic_points_stats *stats,
                            ic_error *err)
{
    ic_points_stats local;
    ic_points_stats *st = stats ? stats : &local;
    memset(st, 0, sizeof *st);
    double t0 = ic_seconds();
    if (!scene || (count > 0 && (!points || !out)))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "ic_points_compute: NULL scene, points or results");
    ic_points_options opt;
    memset(&opt, 0, sizeof opt);
    if (opt_in)
        opt = *opt_in;
    ic_result r = resolve_options(scene, &opt, err);
    if (r != IC_OK)
        return r;
    st->threads = ic_resolve_threads(opt.threads);
    if (count == 0)
        return IC_OK;

    ic_vec3 *p = malloc(sizeof *p * count), *n = malloc(sizeof *n * count);
    uint64_t *rays = calloc(count, sizeof *rays);
    ic_accel *accel = NULL;
    ic_ctx *ic = NULL;
    if (!p || !n || !rays) {
        r = ic_error_set(err, IC_ERR_OOM, "out of memory for %u sensor points", count);
        goto done;
    }
    for (uint32_t i = 0; i < count; ++i) {
        ic_vec3 q = points[i].position, nn = points[i].normal;
        /* The normal's length in double: float components up to 3.4e38 square without overflow. */
        double len = sqrt((double)nn.x * nn.x + (double)nn.y * nn.y + (double)nn.z * nn.z);
        const char *why = !finite3(q) || !finite3(nn) ? "a coordinate is not a finite number"
                          : fabs(q.x) > IC_MAX_POINT_COORDINATE || fabs(q.y) > IC_MAX_POINT_COORDINATE ||
                                  fabs(q.z) > IC_MAX_POINT_COORDINATE
                              ? "a position coordinate lies beyond 1e18"
                          : !(len > 0.0) ? "its normal is zero"
                                         : NULL;
        if (why) {
            r = ic_error_set(err, IC_ERR_INVALID_ARG, "sensor points[%u] (0-based): %s; give a finite position within "
                             "1e18 and a non-zero normal", i, why);
            goto done;
        }
        p[i] = q;
        n[i] = v3((float)(nn.x / len), (float)(nn.y / len), (float)(nn.z / len));
    }
    if ((r = ic_accel_create(scene, &accel, err)) != IC_OK)
        goto done;
    ic_tracer tr;
    tr.scene = scene;
    tr.accel = accel;
    tr.pt.max_depth = opt.max_depth;
    tr.pt.rr_depth = 0;
    tr.pt = ic_pt_params_resolve(tr.pt);

    points_job job;
    memset(&job, 0, sizeof job);
    atomic_init(&job.uncovered, 0);
    atomic_init(&job.done, 0);
    job.progress = opt.progress;
    job.progress_user = opt.progress_user;
    job.tr = &tr;
    job.p = p;
    job.n = n;
    job.out = out;
    job.rays = rays;
    job.seed = opt.seed;
    uint64_t first, own;
    ic_comm_block(count, ic_comm_size(opt.comm), ic_comm_rank(opt.comm), &first, &own);
    job.first = (uint32_t)first;
    job.own = (uint32_t)own;
    uint64_t gather_rays = 0;
    if (opt.integrator == IC_INTEGRATOR_PT) {
        job.samples = opt.samples;
        if ((r = ic_parallel_for(opt.threads, (int64_t)own, point_pt, &job)) != IC_OK)
            ic_error_set(err, r, "sensor points: the worker threads could not start");
    } else {
        ic_render_options ro;
        memset(&ro, 0, sizeof ro);
        ro.integrator = IC_INTEGRATOR_IC;
        ro.max_depth = opt.max_depth;
        ro.threads = opt.threads;
        ro.seed = opt.seed;
        ro.has_seed = 1;
        ro.ic = opt.ic;
        ro.comm = opt.comm;
        ro.progress = opt.progress;
        ro.progress_user = opt.progress_user;
        r = ic_ic_points_ctx_create(&tr, &ro, &ic, err);
        if (r == IC_OK)
            r = ic_ic_points_build(ic, &ro, p, n, count, &job.noise, &st->hit_records, err);
        if (r == IC_OK) {
            st->records = ic_cache_count(ic->cache) - st->hit_records;
            gather_rays = (uint64_t)atomic_load(&ic->rays);
            job.ic = ic;
            job.samples = opt.light_samples;
            if ((r = ic_parallel_for(opt.threads, (int64_t)own, point_ic, &job)) != IC_OK)
                ic_error_set(err, r, "sensor points: the worker threads could not start");
        }
        uint32_t uncovered = atomic_load(&job.uncovered);
        if (r == IC_OK && uncovered)
            r = ic_error_set(err, IC_ERR_INTERNAL, "sensor points[%u] (0-based): no cache record covers it after "
                             "construction", uncovered - 1);
    }
    if (r == IC_OK && opt.progress)
        opt.progress(opt.progress_user, "sensors", 1.0);
    /* Every process's block of results to every process; the rays of all. */
    if (r == IC_OK)
        r = ic_comm_allgather_blocks(opt.comm, out, count, sizeof *out, "exchanging sensor results", err);
    if (r == IC_OK) {
        double total = (double)gather_rays;
        for (uint64_t i = first; i < first + own; ++i)
            total += (double)rays[i];
        if ((r = ic_comm_sum(opt.comm, &total, 1, err)) == IC_OK)
            st->rays = (uint64_t)total;
    }
done:
    ic_ic_ctx_destroy(ic);
    ic_accel_destroy(accel);
    free(p);
    free(n);
    free(rays);
    st->seconds = ic_seconds() - t0;
    return r;
}
