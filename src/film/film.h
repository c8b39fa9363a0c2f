/*
 * film.h — the film: the image loop shared by every integrator: camera rays with a tent pixel filter
 * (filter importance sampling), tiles handed to all threads, progressive passes under an optional
 * wall-time budget, progress reports, and per-phase statistics.
 *
 * Determinism: sample s of pixel i draws from the counter-based stream (seed, i, s), so the image
 * never depends on the thread count or on which thread rendered a tile.
 *
 * Several processes (loop.comm): tile t is rendered by rank t mod size (a static interleave: neighbouring
 * tiles cost alike, so every rank gets a fair mix of cheap and expensive regions; the adaptive second
 * pass shares its tiles out by their measured cost, keeping each on its pilot's rank where the load
 * allows), and every rank's finished pixels are all-gathered, each copied from the one rank that
 * rendered it, so the image is bit-identical to one process's. Every rank returns the whole image.
 */
#ifndef IC_FILM_FILM_H
#define IC_FILM_FILM_H

#include "core/comm.h"
#include "core/rng.h"
#include "geom/accel.h"
#include "irrcache/image.h"

/* Estimates the radiance of one camera sample. `thread` indexes per-thread scratch; rays counts rays. */
typedef ic_vec3 (*ic_sample_fn)(void *ctx, const ic_ray *camera_ray, uint32_t pixel, ic_rng *rng, int thread,
                                uint64_t *rays);

typedef struct ic_image_loop {
    const ic_camera *camera;
    int spp;               /* samples per pixel (0 with a time budget: as many as fit) */
    double time_budget;    /* seconds; 0 = none */
    int threads;           /* 0 = all cores */
    uint64_t seed;
    int random_sampler;    /* 1: independent draws; 0: scrambled Sobol' pairs per pixel */
    int adaptive;          /* 1: spp is a mean; a pilot pass of spp/4 per pixel, the rest where the noise is
                              (needs spp ≥ 8 and no time budget) */
    const char *phase;     /* progress phase name */
    ic_progress_fn progress;
    void *progress_user;
    ic_comm *comm;         /* the processes sharing the image; NULL: one */
    const volatile sig_atomic_t *cancel; /* ic_render_options.cancel (ignored with a shared comm): the pass
                              skips its tiles not begun, and no pass follows */
    /* Checkpoints (ignored with a shared comm): every checkpoint_seconds of the loop's wall time, the
     * threads finish the tiles they hold, checkpoint gets the image so far on the calling thread, and the
     * rest of the pass goes on. Tiles are independent, so the image is the same with or without them. */
    double checkpoint_seconds;
    void (*checkpoint)(void *user, const ic_image *image, double completed);
    void *checkpoint_user;
    /* Called (NULL: not) with the sample function's ctx on the thread about to render a tile, before its
     * first sample: what the sample function keeps per thread from one pixel to the next starts afresh,
     * so that what it traces and counts is a function of the tile, not of the tiles that thread rendered
     * before (which depends on scheduling, the thread count and the passes). */
    void (*tile_begin)(void *ctx, int thread);
} ic_image_loop;

typedef struct ic_image_loop_result {
    int spp_done;          /* samples per pixel actually taken (adaptive: the mean) */
    int spp_max;           /* the most samples a pixel took (adaptive, or a budgeted pass cut short) */
    int spp_min;           /* the fewest (0 where a tile was skipped in the first pass) */
    uint64_t rays;         /* rays traced by the sample function (this process's) */
    uint64_t samples;      /* pixel samples this process took */
    double seconds;
    double busy_seconds;   /* of those, rendering this process's tiles (not waiting for other ranks) */
    int cancelled;         /* 1: loop.cancel cut the image short */
    double completed;      /* share of the samples of the passes begun that were taken (1 uninterrupted, 0 for
                              the one-sample preview) */
} ic_image_loop_result;

/* Primary ray through film position (fx, fy) in pixels (0,0 = top-left corner), of the camera's
 * projection. Returns 0 (and a ray that must not be traced) where the position lies outside what the
 * projection covers: outside a fisheye's circle, whose pixels are black. */
int ic_camera_ray(const ic_camera *cam, float fx, float fy, ic_ray *ray);
/* World-space width of the pixel at film position (fx, fy) at distance t along its ray (for pixel-sized
 * radii): t · pixel angle for perspective (as the cache always measured it), the constant pixel width of a
 * parallel view, and for the other projections the local angle across that pixel (the geometric mean of
 * the horizontal and vertical ones) times the distance. */
float ic_camera_footprint(const ic_camera *cam, float fx, float fy, float t);
/* Film position of world point p, and the distance at which to evaluate ic_camera_footprint there (the
 * depth along the axis for perspective and parallel views, the distance from the eye otherwise). Returns 0
 * if the projection does not see p (behind the camera, or behind a hemispherical fisheye). */
int ic_camera_project(const ic_camera *cam, ic_vec3 p, float *fx, float *fy, float *depth);

/* Renders into out (allocated here, width×height of the camera). */
ic_result ic_render_image(const ic_image_loop *loop, ic_sample_fn fn, void *ctx, ic_image *out,
                          ic_image_loop_result *res, ic_error *err);

/* Monotonic clock in seconds. */
double ic_seconds(void);

#endif
