/*
 * api.c — ic_render (irrcache/render.h): builds the accelerator, resolves options against the
 * scene file's settings and the defaults, runs the chosen integrator, and fills the statistics.
 */
#include "irrcache/render.h"

#include "core/threads.h"
#include "integrators/ic.h"
#include "integrators/pt.h"
#include "render/render.h"
#include "scene/scene.h"

#include <string.h>

void ic_scene_resolution(const ic_scene *scene, int *width, int *height)
{
    *width = scene->camera.width;
    *height = scene->camera.height;
}

float ic_scene_exposure(const ic_scene *scene) { return scene->settings.has_exposure ? scene->settings.exposure : 0.0f; }

static void add_phase(ic_render_stats *st, const char *name, double seconds)
{
    if (st->phase_count < IC_MAX_PHASES) {
        st->phases[st->phase_count].name = name;
        st->phases[st->phase_count].seconds = seconds;
        ++st->phase_count;
    }
}

typedef struct pt_ctx {
    const ic_tracer *tr;
    ic_pixel_lights lights;
} pt_ctx;

static ic_vec3 pt_sample(void *p, const ic_ray *ray, uint32_t pixel, ic_rng *rng, int thread, uint64_t *rays)
{
    pt_ctx *c = p;
    const ic_scene *scene = c->tr->scene;
    ic_light_selection local;
    const ic_light_selection *sel = NULL;
    if (c->lights.count) {
        /* The block's local light distribution, built at the first hit of its centre pixel's centre
         * (one ray per block and thread; a function of the block alone, so images do not depend on
         * the thread count). */
        int have = 0;
        ic_vec3 hp = v3s(0.0f), hn = v3s(0.0f);
        if (ic_pixel_lights_need_point(&c->lights, thread, pixel)) {
            const ic_camera *cam = &scene->camera;
            uint32_t a = ic_pixel_lights_anchor(&c->lights, pixel);
            ic_ray centre = ic_camera_ray(cam, (float)(a % (uint32_t)cam->width) + 0.5f,
                                          (float)(a / (uint32_t)cam->width) + 0.5f);
            ic_hit hit;
            ++*rays;
            ic_accel_intersect1(c->tr->accel, &centre, &hit);
            if (hit.triangle != IC_NO_HIT) {
                ic_surface s;
                ic_scene_surface(scene, hit.triangle, hit.u, hit.v, &s);
                have = 1;
                hp = s.p;
                hn = v3_dot(s.ns, centre.dir) > 0.0f ? v3_neg(s.ns) : s.ns;
            }
        }
        sel = ic_pixel_lights_get(&c->lights, scene, thread, pixel, have, hp, hn, &local);
    }
    return ic_pt_li(c->tr, *ray, sel, rng, rays);
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
    if (opt.spp < 0 || opt.max_depth < 0 || opt.threads < 0 || opt.time_budget < 0.0)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "negative --spp, --max-depth, --threads or --time; give values >= 0");
    if (opt.adaptive_sampling < -1 || opt.adaptive_sampling > 1)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "adaptive_sampling %d: use 1 (on), -1 (off) or 0 (default)",
                            opt.adaptive_sampling);
    if (opt.sampler != IC_SAMPLER_SOBOL && opt.sampler != IC_SAMPLER_RANDOM)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "unknown sampler %d; use sobol or random", (int)opt.sampler);
    /* A cache render's samples are cheap (a camera ray, a light sample, a look-up): it defaults to more. */
    if (opt.spp == 0)
        opt.spp = scene->settings.spp > 0       ? scene->settings.spp
                  : opt.time_budget > 0.0         ? 0
                  : opt.integrator == IC_INTEGRATOR_IC ? 64
                                                  : 16;
    if (opt.max_depth == 0)
        opt.max_depth = scene->settings.max_depth > 0 ? scene->settings.max_depth : 8;
    if (!opt.has_seed && opt.seed == 0)
        opt.seed = scene->settings.seed ? scene->settings.seed : 1;
    st->threads = ic_resolve_threads(opt.threads);

    double t0 = ic_seconds();
    ic_accel *accel = NULL;
    ic_result r = ic_accel_create(scene, &accel, err);
    if (r != IC_OK)
        return r;
    add_phase(st, "accel", ic_seconds() - t0);

    ic_tracer tr;
    tr.scene = scene;
    tr.accel = accel;
    tr.pt.max_depth = opt.max_depth;
    tr.pt.rr_depth = 0;
    tr.pt = ic_pt_params_resolve(tr.pt);

    ic_image_loop loop;
    memset(&loop, 0, sizeof loop);
    loop.camera = &scene->camera;
    loop.spp = opt.spp;
    loop.time_budget = opt.time_budget;
    loop.threads = opt.threads;
    loop.seed = opt.seed;
    loop.random_sampler = opt.sampler == IC_SAMPLER_RANDOM;
    loop.adaptive = opt.adaptive_sampling > 0; /* the reference path tracer samples evenly by default */
    loop.progress = opt.progress;
    loop.progress_user = opt.progress_user;
    ic_image_loop_result lr;
    memset(&lr, 0, sizeof lr);
    switch (opt.integrator) {
    case IC_INTEGRATOR_PT:
        loop.phase = "path tracing";
        {
            pt_ctx pc = {&tr, {0}};
            r = ic_pixel_lights_init(&pc.lights, scene, scene->light_select, ic_resolve_threads(opt.threads),
                                     scene->camera.width, scene->camera.height);
            if (r != IC_OK)
                ic_error_set(err, r, "out of memory for the per-thread light tables");
            else
                r = ic_render_image(&loop, pt_sample, &pc, out, &lr, err);
            ic_pixel_lights_free(&pc.lights);
        }
        break;
    case IC_INTEGRATOR_IC:
        r = ic_render_ic(&tr, &opt, out, st, err);
        break;
    default:
        r = ic_error_set(err, IC_ERR_UNSUPPORTED, "integrator %d is not available in this build", (int)opt.integrator);
        break;
    }
    if (r == IC_OK && opt.integrator == IC_INTEGRATOR_PT) {
        add_phase(st, "render", lr.seconds);
        st->rays = lr.rays;
        st->spp = lr.spp_done;
        st->spp_max = lr.spp_max;
    }
    ic_accel_destroy(accel);
    st->seconds = ic_seconds() - t0;
    st->rays_per_second = st->seconds > 0.0 ? (double)st->rays / st->seconds : 0.0;
    return r;
}
