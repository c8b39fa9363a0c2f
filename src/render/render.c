/* render.c — tiles, passes, pixel filter and progress for every integrator (render.h). */
#include "render.h"

#include "core/threads.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define TILE 16

double ic_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct camera_basis {
    ic_vec3 eye, forward, right, up;
    float tan_half_y, aspect;
} camera_basis;

static camera_basis basis_of(const ic_camera *c)
{
    camera_basis b;
    b.eye = c->eye;
    b.forward = v3_norm(v3_sub(c->target, c->eye));
    b.right = v3_norm(v3_cross(b.forward, c->up));
    b.up = v3_cross(b.right, b.forward);
    b.tan_half_y = tanf(0.5f * c->fov_y_deg * IC_PI / 180.0f);
    b.aspect = (float)c->width / (float)c->height;
    return b;
}

ic_ray ic_camera_ray(const ic_camera *cam, float fx, float fy)
{
    camera_basis b = basis_of(cam);
    float sx = (2.0f * fx / (float)cam->width - 1.0f) * b.tan_half_y * b.aspect;
    float sy = (1.0f - 2.0f * fy / (float)cam->height) * b.tan_half_y;
    ic_ray r;
    r.org = b.eye;
    r.dir = v3_norm(v3_add(b.forward, v3_add(v3_scale(b.right, sx), v3_scale(b.up, sy))));
    r.tnear = 0.0f;
    r.tfar = INFINITY;
    return r;
}

float ic_camera_pixel_angle(const ic_camera *cam)
{
    return 2.0f * tanf(0.5f * cam->fov_y_deg * IC_PI / 180.0f) / (float)cam->height;
}

/* Tent filter of radius 1 pixel, sampled exactly (filter importance sampling): offset in [-1, 1]. */
static float tent_sample(float u)
{
    return u < 0.5f ? sqrtf(2.0f * u) - 1.0f : 1.0f - sqrtf(2.0f - 2.0f * u);
}

typedef struct loop_ctx {
    const ic_image_loop *loop;
    ic_sample_fn fn;
    void *user;
    double *accum;         /* width*height*3 running sums */
    int tiles_x, tiles_y;
    int s_begin, s_end;    /* samples of this pass */
    uint64_t *rays;        /* per thread, padded */
    atomic_int tiles_done;
    int total_tiles_all_passes;
    int tiles_before_pass;
    double start;
} loop_ctx;

#define RAY_PAD 8 /* uint64 slots between per-thread counters: no false sharing */

static void render_tile(void *p, int64_t item, int thread)
{
    loop_ctx *c = p;
    const ic_camera *cam = c->loop->camera;
    int tx = (int)(item % c->tiles_x), ty = (int)(item / c->tiles_x);
    int x0 = tx * TILE, y0 = ty * TILE;
    int x1 = x0 + TILE < cam->width ? x0 + TILE : cam->width;
    int y1 = y0 + TILE < cam->height ? y0 + TILE : cam->height;
    uint64_t rays = 0;
    for (int y = y0; y < y1; ++y) {
        for (int x = x0; x < x1; ++x) {
            uint32_t pixel = (uint32_t)(y * cam->width + x);
            double sum[3] = {0, 0, 0};
            uint64_t lds_key = ic_hash4(c->loop->seed, pixel, 0x736f626f6cULL, 0);
            for (int s = c->s_begin; s < c->s_end; ++s) {
                ic_rng rng = ic_rng_make(c->loop->seed, pixel, (uint64_t)s, 0);
                /* The sample number indexes the pixel's sequence across passes too, so every
                 * power-of-two prefix of a pixel's samples stays a net (time-budgeted passes). */
                if (!c->loop->random_sampler)
                    ic_rng_enable_lds(&rng, lds_key, (uint32_t)s);
                float u, v;
                ic_rng_2d(&rng, &u, &v);
                float fx = (float)x + 0.5f + tent_sample(u);
                float fy = (float)y + 0.5f + tent_sample(v);
                ic_ray ray = ic_camera_ray(cam, fx, fy);
                ic_vec3 L = c->fn(c->user, &ray, pixel, &rng, thread, &rays);
                /* A NaN or Inf sample would poison the pixel forever: drop it. */
                if (v3_is_finite(L)) {
                    sum[0] += L.x;
                    sum[1] += L.y;
                    sum[2] += L.z;
                }
            }
            double *a = &c->accum[3 * (size_t)pixel];
            a[0] += sum[0];
            a[1] += sum[1];
            a[2] += sum[2];
        }
    }
    c->rays[thread * RAY_PAD] += rays;
    int done = atomic_fetch_add(&c->tiles_done, 1) + 1;
    if (thread == 0 && c->loop->progress)
        c->loop->progress(c->loop->progress_user, c->loop->phase ? c->loop->phase : "render",
                          c->total_tiles_all_passes > 0
                              ? (double)(c->tiles_before_pass + done) / (double)c->total_tiles_all_passes
                              : -1.0);
}

ic_result ic_render_image(const ic_image_loop *loop, ic_sample_fn fn, void *user, ic_image *out,
                          ic_image_loop_result *res, ic_error *err)
{
    const ic_camera *cam = loop->camera;
    memset(res, 0, sizeof *res);
    if (cam->width <= 0 || cam->height <= 0)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "image size %dx%d is invalid; give --width and --height > 0",
                            cam->width, cam->height);
    if (loop->spp <= 0 && loop->time_budget <= 0.0)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "give a sample count (--spp) or a time budget (--time)");
    int threads = ic_resolve_threads(loop->threads);
    loop_ctx c;
    memset(&c, 0, sizeof c);
    c.loop = loop;
    c.fn = fn;
    c.user = user;
    c.tiles_x = (cam->width + TILE - 1) / TILE;
    c.tiles_y = (cam->height + TILE - 1) / TILE;
    size_t npix = (size_t)cam->width * (size_t)cam->height;
    c.accum = calloc(npix * 3, sizeof(double));
    c.rays = calloc((size_t)threads * RAY_PAD, sizeof(uint64_t));
    if (!c.accum || !c.rays) {
        free(c.accum);
        free(c.rays);
        return ic_error_set(err, IC_ERR_OOM, "out of memory for a %dx%d image", cam->width, cam->height);
    }
    int tiles = c.tiles_x * c.tiles_y;
    c.start = ic_seconds();
    /* Without a budget: one pass of all samples. With a budget: passes of growing size, stopping
     * before a pass that would overrun the budget (estimated from the previous pass). */
    int spp_max = loop->spp > 0 ? loop->spp : (1 << 30);
    int done = 0, pass_spp = loop->time_budget > 0.0 ? 1 : spp_max;
    c.total_tiles_all_passes = loop->time_budget > 0.0 ? 0 : tiles;
    double per_sample = 0.0;
    ic_result r = IC_OK;
    while (done < spp_max) {
        if (pass_spp > spp_max - done)
            pass_spp = spp_max - done;
        if (loop->time_budget > 0.0 && done > 0) {
            double left = loop->time_budget - (ic_seconds() - c.start);
            int fit = per_sample > 0.0 ? (int)(left / per_sample) : pass_spp;
            if (fit < 1)
                break;
            if (pass_spp > fit)
                pass_spp = fit;
        }
        c.s_begin = done;
        c.s_end = done + pass_spp;
        atomic_store(&c.tiles_done, 0);
        double t0 = ic_seconds();
        r = ic_parallel_for(threads, tiles, render_tile, &c);
        if (r != IC_OK) {
            ic_error_set(err, r, "could not start render threads");
            break;
        }
        per_sample = (ic_seconds() - t0) / pass_spp;
        done += pass_spp;
        c.tiles_before_pass += tiles;
        if (loop->time_budget > 0.0 && loop->progress)
            loop->progress(loop->progress_user, loop->phase ? loop->phase : "render",
                           fmin(1.0, (ic_seconds() - c.start) / loop->time_budget));
        pass_spp *= 2;
    }
    if (r == IC_OK && done == 0)
        r = ic_error_set(err, IC_ERR_INVALID_ARG, "time budget too small for one sample per pixel; raise --time");
    if (r == IC_OK) {
        r = ic_image_create(out, cam->width, cam->height);
        if (r != IC_OK)
            ic_error_set(err, r, "out of memory for a %dx%d image", cam->width, cam->height);
    }
    if (r == IC_OK) {
        for (size_t i = 0; i < npix * 3; ++i)
            out->rgb[i] = (float)(c.accum[i] / done);
        for (int t = 0; t < threads; ++t)
            res->rays += c.rays[t * RAY_PAD];
        res->spp_done = done;
    }
    res->seconds = ic_seconds() - c.start;
    free(c.accum);
    free(c.rays);
    return r;
}
