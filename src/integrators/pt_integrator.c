/*
 * pt_integrator.c — the path-traced reference behind the integrator interface (integrator.h): each
 * pixel sample is one path (pt.c), its first vertex sampling lights by the local distribution of its
 * pixel block.
 */
#include "integrators/integrator.h"

#include "core/threads.h"
#include "scene/scene.h"

#include <stdlib.h>

typedef struct pt_state {
    const ic_tracer *tr;
    int threads;
    ic_pixel_lights lights;
} pt_state;

static ic_result pt_prepare(void *self, ic_render_stats *st, ic_error *err)
{
    (void)st;
    pt_state *p = self;
    const ic_scene *scene = p->tr->scene;
    ic_result r = ic_pixel_lights_init(&p->lights, scene, scene->light_select, p->threads, scene->camera.width,
                                       scene->camera.height);
    return r == IC_OK ? IC_OK : ic_error_set(err, r, "out of memory for the per-thread light tables");
}

static ic_vec3 pt_sample(void *self, const ic_ray *ray, uint32_t pixel, ic_rng *rng, int thread, uint64_t *rays)
{
    pt_state *p = self;
    const ic_scene *scene = p->tr->scene;
    ic_light_selection local;
    const ic_light_selection *sel = NULL;
    if (p->lights.count) {
        /* The block's local light distribution, built at the first hit of its centre pixel's centre
         * (one ray per block and thread; a function of the block alone, so images do not depend on
         * the thread count). */
        int have = 0;
        ic_vec3 hp = v3s(0.0f), hn = v3s(0.0f);
        if (ic_pixel_lights_need_point(&p->lights, thread, pixel)) {
            const ic_camera *cam = &scene->camera;
            uint32_t a = ic_pixel_lights_anchor(&p->lights, pixel);
            ic_ray centre;
            ic_hit hit;
            hit.triangle = IC_NO_HIT;
            if (ic_camera_ray(cam, (float)(a % (uint32_t)cam->width) + 0.5f, (float)(a / (uint32_t)cam->width) + 0.5f,
                              &centre)) {
                ++*rays;
                ic_accel_intersect1(p->tr->accel, &centre, &hit);
            }
            if (hit.triangle != IC_NO_HIT) {
                ic_surface s;
                ic_scene_surface(scene, hit.triangle, hit.u, hit.v, &s);
                have = 1;
                hp = s.p;
                hn = v3_dot(s.ns, centre.dir) > 0.0f ? v3_neg(s.ns) : s.ns;
            }
        }
        sel = ic_pixel_lights_get(&p->lights, scene, thread, pixel, have, hp, hn, &local);
    }
    return ic_pt_li(p->tr, *ray, sel, rng, rays);
}

/* A tile builds its blocks' distributions afresh (one anchor ray each), even those its thread still holds
 * from an earlier pass over the same tile: how many rays a tile traces depends on it alone, not on which
 * thread rendered it before (the distributions are the same either way). */
static void pt_tile_begin(void *self, int thread)
{
    pt_state *p = self;
    ic_pixel_lights_forget(&p->lights, thread);
}

static void pt_destroy(void *self)
{
    pt_state *p = self;
    ic_pixel_lights_free(&p->lights);
    free(p);
}

static const ic_integrator_ops pt_ops = {
    .loop_phase = "path tracing",
    .stats_phase = "render",
    .adaptive_by_default = 0, /* the reference samples evenly unless asked */
    .prepare = pt_prepare,
    .sample = pt_sample,
    .tile_begin = pt_tile_begin,
    .aovs = NULL,
    .destroy = pt_destroy,
};

ic_result ic_pt_integrator_create(const ic_tracer *tr, const ic_render_options *opt, ic_integrator_obj *out,
                                  ic_error *err)
{
    out->ops = &pt_ops;
    pt_state *p = calloc(1, sizeof *p);
    out->self = p;
    if (!p)
        return ic_error_set(err, IC_ERR_OOM, "out of memory");
    p->tr = tr;
    p->threads = ic_resolve_threads(opt->threads);
    return IC_OK;
}
