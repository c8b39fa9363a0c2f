/*
 * integrator.h — the one interface between the driver (render/api.c) and every integrator, in the
 * spirit of pbrt-v4's ImageTileIntegrator (its Create from parameters, Render over tiles and
 * EvaluatePixelSample):
 *
 *   create   from the tracer (scene, accelerator, path depth) and the resolved render options;
 *   prepare  build whatever the image needs before its first sample (the cache: construction, or
 *            loading a cache file), adding its phases and counts to the statistics;
 *   sample   one pixel sample along a camera ray, called by the film's image loop from many threads
 *            (film.h: ic_sample_fn; it must depend only on the pixel and its random stream);
 *   tile_begin  (may be NULL) before a tile's samples, on its thread: forget what sample keeps per thread
 *            (film.h: ic_image_loop.tile_begin), so that the rays it counts depend on the tile alone;
 *   aovs     extra images after the beauty image (may be NULL: none);
 *   destroy  frees it all (NULL-safe through ic_integrator_destroy).
 *
 * A new integrator is a file in src/integrators/ with a create function, registered in the driver's
 * table (render/api.c).
 */
#ifndef IC_INTEGRATORS_INTEGRATOR_H
#define IC_INTEGRATORS_INTEGRATOR_H

#include "film/film.h"
#include "integrators/pt.h"
#include "irrcache/render.h"

typedef struct ic_integrator_ops {
    const char *loop_phase;    /* progress name of the image loop ("path tracing", "final render") */
    const char *stats_phase;   /* the image loop's phase in the statistics ("render", "final render") */
    int adaptive_by_default;   /* adaptive sampling when the options leave it at 0 (and spp ≥ 8, no time
                                  budget); otherwise only when asked for */
    ic_result (*prepare)(void *self, ic_render_stats *st, ic_error *err);
    ic_sample_fn sample;       /* ctx = self */
    void (*tile_begin)(void *self, int thread);
    /* beauty: the image just rendered; loop and lr: how it was rendered (an AOV rendered by the film
     * takes the same samples). *cancelled: 1 when loop.cancel cut an AOV the film renders short (its
     * tiles not begun are black), else left alone. */
    ic_result (*aovs)(void *self, const ic_image *beauty, const ic_image_loop *loop, const ic_image_loop_result *lr,
                      ic_render_aovs *out, int *cancelled, ic_error *err);
    void (*destroy)(void *self);
} ic_integrator_ops;

/* An integrator: its operations and its state. */
typedef struct ic_integrator_obj {
    const ic_integrator_ops *ops;
    void *self;
} ic_integrator_obj;

/* Makes an integrator for tr and opt (opt already resolved by the driver: spp, depth, seed); tr and
 * opt must outlive it. On failure out->self is NULL and err says why. */
typedef ic_result (*ic_integrator_create_fn)(const ic_tracer *tr, const ic_render_options *opt,
                                             ic_integrator_obj *out, ic_error *err);

/* The path-traced reference (pt.c). */
ic_result ic_pt_integrator_create(const ic_tracer *tr, const ic_render_options *opt, ic_integrator_obj *out,
                                  ic_error *err);
/* Irradiance caching (ic_integrator.c). */
ic_result ic_ic_integrator_create(const ic_tracer *tr, const ic_render_options *opt, ic_integrator_obj *out,
                                  ic_error *err);

/* Appends a phase to the statistics where there is room (IC_MAX_PHASES). */
static inline void ic_stats_add_phase(ic_render_stats *st, const char *name, double seconds)
{
    if (st->phase_count < IC_MAX_PHASES) {
        st->phases[st->phase_count].name = name;
        st->phases[st->phase_count].seconds = seconds;
        ++st->phase_count;
    }
}

static inline void ic_integrator_destroy(ic_integrator_obj *it)
{
    if (it->ops && it->self)
        it->ops->destroy(it->self);
    it->self = NULL;
}

#endif
