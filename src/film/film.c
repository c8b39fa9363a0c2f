/* film.c — camera rays, tiles, passes, pixel filter, adaptive sampling and progress for every integrator (film.h). */
#include "film.h"

#include "core/threads.h"
#include "film/stream.h"

#include <limits.h>
#include <math.h>
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

/* Inlined into each camera ray, as it was before the other projections gave it a second caller. */
static inline __attribute__((always_inline)) camera_basis basis_of(const ic_camera *c)
{
    camera_basis b;
    b.eye = c->eye;
    b.forward = v3_norm(v3_sub(c->target, c->eye));
    b.right = v3_norm(v3_cross(b.forward, c->up));
    b.up = v3_cross(b.right, b.forward);
    if (c->is_mirrored) /* after up: the mirror turns the image's horizontal axis alone */
        b.right = v3_neg(b.right);
    b.tan_half_y = tanf(0.5f * c->fov_y_deg * IC_PI / 180.0f);
    b.aspect = (float)c->width / (float)c->height;
    return b;
}

/* The ray of the non-perspective projections through centred image coordinates (x, y) (+y up), in the
 * camera frame: forward, right, up components of the direction (not normalised for the cylinder, whose
 * fore clipping is along the axis), and for the parallel view the origin's offset. 0 outside the image's
 * projection (a fisheye's circle). After Radiance's image.c (Larson & Shakespeare 1998). */
static int local_ray(const ic_camera *c, double x, double y, double d[3], double o[2])
{
    double a = x * ic_projection_extent(c->projection, c->size_x, 1), b = y * ic_projection_extent(c->projection, c->size_y, 0);
    o[0] = o[1] = 0.0;
    switch (c->projection) {
    case IC_PROJECTION_PARALLEL:
        o[0] = a, o[1] = b;
        d[0] = 1.0, d[1] = d[2] = 0.0;
        return 1;
    case IC_PROJECTION_HEMISPHERICAL: { /* (a, b) is the direction's projection onto the image plane */
        double z2 = 1.0 - a * a - b * b;
        if (z2 < 0.0)
            return 0;
        d[0] = sqrt(z2), d[1] = a, d[2] = b;
        return 1;
    }
    case IC_PROJECTION_ANGULAR: { /* the radius is the angle from the axis over π */
        double r = sqrt(a * a + b * b);
        if (r > 1.0)
            return 0;
        double s = r > 1e-9 ? sin(3.14159265358979323846 * r) / r : 3.14159265358979323846;
        d[0] = cos(3.14159265358979323846 * r), d[1] = a * s, d[2] = b * s;
        return 1;
    }
    case IC_PROJECTION_CYLINDRICAL: /* a is the azimuth in radians, b the height on a unit-distance wall */
        d[0] = cos(a), d[1] = sin(a), d[2] = b;
        return 1;
    default: { /* stereographic: the radius is tan(θ/2), so cos θ = (1 − r²)/(1 + r²), sin θ = r (1 + cos θ) */
        double r2 = a * a + b * b, z = (1.0 - r2) / (1.0 + r2);
        d[0] = z, d[1] = a * (1.0 + z), d[2] = b * (1.0 + z);
        return 1;
    }
    }
}

int ic_camera_ray(const ic_camera *cam, float fx, float fy, ic_ray *ray)
{
    camera_basis b = basis_of(cam);
    ray->tnear = 0.0f;
    ray->tfar = INFINITY;
    if (cam->projection == IC_PROJECTION_PERSPECTIVE) {
        float sx = (2.0f * fx / (float)cam->width - 1.0f + 2.0f * cam->shift) * b.tan_half_y * b.aspect;
        float sy = (1.0f - 2.0f * fy / (float)cam->height + 2.0f * cam->lift) * b.tan_half_y;
        ic_vec3 dir = v3_add(b.forward, v3_add(v3_scale(b.right, sx), v3_scale(b.up, sy)));
        ray->org = cam->clip_near > 0.0f ? v3_add(b.eye, v3_scale(dir, cam->clip_near)) : b.eye;
        ray->dir = v3_norm(dir);
        return 1;
    }
    double x = (double)fx / cam->width - 0.5 + cam->shift, y = 0.5 - (double)fy / cam->height + cam->lift;
    double d[3], o[2];
    if (!local_ray(cam, x, y, d, o)) {
        ray->org = b.eye;
        ray->dir = b.forward;
        return 0;
    }
    ic_vec3 dir = v3_add(v3_scale(b.forward, (float)d[0]),
                         v3_add(v3_scale(b.right, (float)d[1]), v3_scale(b.up, (float)d[2])));
    ray->org = v3_add(b.eye, v3_add(v3_scale(b.right, (float)o[0]), v3_scale(b.up, (float)o[1])));
    ray->org = v3_add(ray->org, v3_scale(dir, cam->clip_near));
    ray->dir = v3_norm(dir);
    return 1;
}

/* Width of one pixel's footprint at distance 1 along the view axis of a perspective camera. */
static float pixel_angle(const ic_camera *cam)
{
    return 2.0f * tanf(0.5f * cam->fov_y_deg * IC_PI / 180.0f) / (float)cam->height;
}

/* The angle between the rays through two film positions (0 when either is outside the image). */
static float ray_angle(const ic_camera *cam, float fx0, float fy0, float fx1, float fy1)
{
    ic_ray a, b;
    if (!ic_camera_ray(cam, fx0, fy0, &a) || !ic_camera_ray(cam, fx1, fy1, &b))
        return 0.0f;
    return 2.0f * asinf(fminf(1.0f, 0.5f * v3_len(v3_sub(a.dir, b.dir))));
}

float ic_camera_footprint(const ic_camera *cam, float fx, float fy, float t)
{
    if (cam->projection == IC_PROJECTION_PERSPECTIVE)
        return t * pixel_angle(cam);
    if (cam->projection == IC_PROJECTION_PARALLEL)
        return cam->size_y / (float)cam->height;
    /* The local angle across one pixel, by central differences (one-sided at a fisheye's rim), the
     * geometric mean of the horizontal and vertical ones (pixels of these projections are not square in
     * angle: a fisheye's narrow radially near its rim). */
    float ax = ray_angle(cam, fx - 0.5f, fy, fx + 0.5f, fy), ay = ray_angle(cam, fx, fy - 0.5f, fx, fy + 0.5f);
    if (ax == 0.0f)
        ax = 2.0f * fmaxf(ray_angle(cam, fx - 0.5f, fy, fx, fy), ray_angle(cam, fx, fy, fx + 0.5f, fy));
    if (ay == 0.0f)
        ay = 2.0f * fmaxf(ray_angle(cam, fx, fy - 0.5f, fx, fy), ray_angle(cam, fx, fy, fx, fy + 0.5f));
    float a = ax > 0.0f && ay > 0.0f ? sqrtf(ax * ay) : fmaxf(ax, ay);
    return (t + cam->clip_near) * a;
}

int ic_camera_project(const ic_camera *cam, ic_vec3 p, float *fx, float *fy, float *depth)
{
    camera_basis b = basis_of(cam);
    ic_vec3 d = v3_sub(p, b.eye);
    if (cam->projection == IC_PROJECTION_PERSPECTIVE) { /* in float, as the records' views always were */
        float z = v3_dot(d, b.forward);
        if (z <= 0.0f)
            return 0;
        float sx = v3_dot(d, b.right) / (z * b.tan_half_y * b.aspect), sy = v3_dot(d, b.up) / (z * b.tan_half_y);
        *fx = (sx + 1.0f - 2.0f * cam->shift) * 0.5f * (float)cam->width;
        *fy = (1.0f - sy + 2.0f * cam->lift) * 0.5f * (float)cam->height;
        *depth = z; /* the footprint of perspective pixels grows with the depth */
        return 1;
    }
    double f = v3_dot(d, b.forward), r = v3_dot(d, b.right), u = v3_dot(d, b.up), x, y;
    double len = sqrt(f * f + r * r + u * u);
    double ex = ic_projection_extent(cam->projection, cam->size_x, 1);
    double ey = ic_projection_extent(cam->projection, cam->size_y, 0);
    if (!(len > 0.0))
        return 0;
    double cf = f / len, cr = r / len, cu = u / len;
    *depth = (float)len;
    switch (cam->projection) {
    case IC_PROJECTION_PARALLEL:
        if (f <= 0.0)
            return 0;
        x = r / ex, y = u / ey;
        *depth = (float)f;
        break;
    case IC_PROJECTION_HEMISPHERICAL:
        if (cf < 0.0)
            return 0;
        x = cr / ex, y = cu / ey;
        break;
    case IC_PROJECTION_ANGULAR: {
        double s = sqrt(cr * cr + cu * cu), th = atan2(s, cf) / 3.14159265358979323846;
        double k = s > 1e-12 ? th / s : 0.0;
        x = cr * k / ex, y = cu * k / ey;
        break;
    }
    case IC_PROJECTION_CYLINDRICAL: {
        double h = sqrt(cf * cf + cr * cr);
        if (!(h > 0.0))
            return 0;
        x = atan2(cr, cf) / ex, y = cu / h / ey;
        break;
    }
    default:
        if (cf <= -1.0 + 1e-12)
            return 0;
        x = cr / (1.0 + cf) / ex, y = cu / (1.0 + cf) / ey;
        break;
    }
    *depth -= cam->clip_near;
    *fx = (float)((x + 0.5 - cam->shift) * cam->width);
    *fy = (float)((0.5 - y + cam->lift) * cam->height);
    return 1;
}

/* Tent filter of radius 1 pixel, sampled exactly (filter importance sampling): offset in [-1, 1]. */
static float tent_sample(float u)
{
    return u < 0.5f ? sqrtf(2.0f * u) - 1.0f : 1.0f - sqrtf(2.0f - 2.0f * u);
}

static double luminance(double r, double g, double b) { return 0.2126 * r + 0.7152 * g + 0.0722 * b; }

typedef struct loop_ctx {
    const ic_image_loop *loop;
    ic_sample_fn fn;
    void *user;
    double *accum;         /* width*height*3 running sums */
    double *sumsq;         /* adaptive pilot pass: per-pixel sums of squared luminance, else NULL */
    uint32_t *extra;       /* adaptive second pass: samples of each pixel from s_begin, else NULL */
    int *tile_n;           /* not adaptive: per tile (of the whole image), the samples each of its pixels holds;
                              a tile skipped when interrupted keeps its earlier passes' */
    int tiles_x, tiles_y;
    int rank, ranks;       /* this process renders tiles rank, rank + ranks, … (or owned[]) */
    int own_tiles;         /* how many that is */
    int64_t *owned;        /* the tiles this process renders when not interleaved (NULL: interleaved) */
    int *owner;            /* with owned: each tile's rank */
    double *tile_seconds;  /* several ranks, adaptive pilot: each tile's render time (this rank's tiles) */
    int s_begin, s_end;    /* samples of this pass */
    uint64_t *rays;        /* per thread, padded */
    uint64_t *samples;     /* per thread, padded: pixel samples taken */
    atomic_int tiles_skipped; /* tiles left unrendered because loop.cancel was set */
    int skip_on_cancel;    /* 1: a set loop.cancel skips the tiles not started yet */
    atomic_ullong samples_done; /* pixel samples taken so far, all passes (progress) */
    double samples_planned;   /* pixel samples of all passes (0 with a time budget: not known) */
    uint64_t own_pixels;   /* pixels of this process's tiles */
    double start;
    /* Checkpoints (loop.checkpoint; one process): a pass is rendered in rounds over the tiles not yet
     * rendered; a round ends early when a checkpoint falls due. */
    int checkpointing;
    uint8_t *tile_state;   /* per tile, this pass: TILE_WAITING, TILE_RENDERED or TILE_SKIPPED */
    int64_t *todo;         /* the tiles of the current round */
    atomic_int pause;      /* 1: a checkpoint is due; tiles not begun wait for the next round */
    double next_checkpoint;/* ic_seconds() at which the next one falls due */
    double busy;           /* seconds in loop_pass */
    ic_stream *stream;     /* several ranks with messages: this pass's finished tiles go to the others as
                              they finish (stream.h), else NULL */
} loop_ctx;

enum { TILE_WAITING = 0, TILE_RENDERED = 1, TILE_SKIPPED = 2 };

#define RAY_PAD 8 /* uint64 slots between per-thread counters: no false sharing */

/* The pixels [x0, x1) × [y0, y1) of tile t (of the whole image). */
static void tile_rect(const loop_ctx *c, int64_t t, int *x0, int *y0, int *x1, int *y1)
{
    const ic_camera *cam = c->loop->camera;
    *x0 = (int)(t % c->tiles_x) * TILE;
    *y0 = (int)(t / c->tiles_x) * TILE;
    *x1 = *x0 + TILE < cam->width ? *x0 + TILE : cam->width;
    *y1 = *y0 + TILE < cam->height ? *y0 + TILE : cam->height;
}

/* The i-th of this process's tiles: owned[i], or the interleave's rank + i·ranks. */
static int64_t own_tile(const loop_ctx *c, int64_t i)
{
    return c->owned ? c->owned[i] : (int64_t)c->rank + i * c->ranks;
}

static void render_tile(void *p, int64_t item, int thread)
{
    loop_ctx *c = p;
    const ic_camera *cam = c->loop->camera;
    if (c->todo)
        item = c->todo[item];
    int64_t tile = own_tile(c, item);
    int x0, y0, x1, y1;
    tile_rect(c, tile, &x0, &y0, &x1, &y1);
    double tile_start = c->tile_seconds ? ic_seconds() : 0.0;
    if (c->skip_on_cancel && *c->loop->cancel) {
        /* Interrupted: the tile keeps what earlier passes gave it (the adaptive pass's extra samples
         * are taken back, so its pixels average what they have). */
        for (int y = y0; c->extra && y < y1; ++y)
            for (int x = x0; x < x1; ++x)
                c->extra[(size_t)y * cam->width + x] = 0;
        atomic_fetch_add(&c->tiles_skipped, 1);
        if (c->tile_state)
            c->tile_state[item] = TILE_SKIPPED;
        return;
    }
    if (c->checkpointing && atomic_load(&c->pause))
        return; /* a checkpoint is due: this tile waits for the next round */
    if (c->loop->tile_begin)
        c->loop->tile_begin(c->user, thread);
    uint64_t rays = 0, samples = 0;
    for (int y = y0; y < y1; ++y) {
        for (int x = x0; x < x1; ++x) {
            uint32_t pixel = (uint32_t)((size_t)y * cam->width + x);
            double sum[3] = {0, 0, 0};
            double sq = 0.0;
            uint64_t lds_key = ic_hash4(c->loop->seed, pixel, 0x736f626f6cULL, 0);
            int s_end = c->extra ? c->s_begin + (int)c->extra[pixel] : c->s_end;
            samples += (uint64_t)(s_end - c->s_begin);
            for (int s = c->s_begin; s < s_end; ++s) {
                ic_rng rng = ic_rng_make(c->loop->seed, pixel, (uint64_t)s, 0);
                /* The sample number indexes the pixel's sequence across passes too, so every
                 * power-of-two prefix of a pixel's samples stays a net (time-budgeted passes). */
                if (!c->loop->random_sampler)
                    ic_rng_enable_lds(&rng, lds_key, (uint32_t)s);
                float u, v;
                ic_rng_2d(&rng, &u, &v);
                float fx = (float)x + 0.5f + tent_sample(u);
                float fy = (float)y + 0.5f + tent_sample(v);
                ic_ray ray;
                /* Outside a fisheye's circle the image is black, as Radiance leaves it. */
                ic_vec3 L = ic_camera_ray(cam, fx, fy, &ray) ? c->fn(c->user, &ray, pixel, &rng, thread, &rays)
                                                            : v3s(0.0f);
                /* A NaN or Inf sample would poison the pixel forever: drop it. */
                if (v3_is_finite(L)) {
                    sum[0] += L.x;
                    sum[1] += L.y;
                    sum[2] += L.z;
                    if (c->sumsq) { /* adaptive pilot pass only: nothing added to other samples */
                        double lum = luminance(L.x, L.y, L.z);
                        sq += lum * lum;
                    }
                }
            }
            double *a = &c->accum[3 * (size_t)pixel];
            a[0] += sum[0];
            a[1] += sum[1];
            a[2] += sum[2];
            if (c->sumsq)
                c->sumsq[pixel] += sq;
        }
    }
    c->rays[thread * RAY_PAD] += rays;
    c->samples[thread * RAY_PAD] += samples;
    if (c->tile_n)
        c->tile_n[tile] = c->s_end;
    if (c->tile_seconds)
        c->tile_seconds[tile] = ic_seconds() - tile_start;
    if (c->stream) {
        ic_stream_finished(c->stream, item, tile);
        if (thread == 0) /* the caller's thread, the one that may call the comm */
            ic_stream_service(c->stream);
    }
    uint64_t done = atomic_fetch_add(&c->samples_done, samples) + samples;
    if (c->tile_state) {
        c->tile_state[item] = TILE_RENDERED;
        if (ic_seconds() >= c->next_checkpoint)
            atomic_store(&c->pause, 1);
    }
    /* Progress by samples (the adaptive pilot, a quarter of them, shows as a quarter), or under a time
     * budget by time. */
    if (thread == 0 && c->loop->progress) {
        double f = c->samples_planned > 0.0  ? (double)done / c->samples_planned
                   : c->loop->time_budget > 0.0 ? (ic_seconds() - c->start) / c->loop->time_budget
                                                : -1.0;
        c->loop->progress(c->loop->progress_user, c->loop->phase ? c->loop->phase : "render", fmin(1.0, f));
    }
}

/* ---------------------------------------------------------------- adaptive sampling
 *
 * The final render of Frolov et al. 2012 (§3.2) is adaptive path tracing: samples go where the image is noisy.
 * A pilot pass takes n0 = spp/4 samples in every pixel and measures each pixel's per-sample relative
 * variance v = s²/(m² + 0.01) of luminance (the relMSE metric's normalisation, so dark pixels are not
 * starved). The rest of the budget, (spp − n0) per pixel on average, is shared out in proportion to
 * sqrt(v) — the allocation n_i ∝ σ_i minimises Σ σ_i²/n_i for a fixed total — after v is averaged over
 * the pixel's 3×3 neighbourhood (a few pilot samples that happen to agree must not starve a pixel).
 * A tenth of the rest is spread evenly as insurance against variance the pilot missed, and no pixel
 * takes more than IC_ADAPTIVE_CAP × spp in all. The allocation is computed serially from the pilot's
 * sums, so it, and the image, are independent of the thread count. Each pixel continues its own
 * sample sequence (indices n0, n0+1, …), so its samples stay one low-discrepancy sequence. The
 * pixel's value is the mean of all its samples; since the count depends on the pilot, that is
 * consistent but not exactly unbiased (the smoothing keeps the dependence weak; test_ic checks the
 * image mean against the path-traced reference). */
#define IC_ADAPTIVE_CAP 8

/* The pilot's per-sample relative variance of pixel i's luminance, v = s²/(m² + 0.01). */
static double relative_variance(const double *accum, const double *sumsq, int n0, size_t i)
{
    const double *a = &accum[3 * i];
    double m = luminance(a[0], a[1], a[2]) / n0;
    double var = fmax(sumsq[i] / n0 - m * m, 0.0) * n0 / (n0 - 1);
    return var / (m * m + 0.01);
}

/* The second pass's samples of every pixel from the pilot's relative variances v (image-wide, taken over as
 * scratch). 0 when out of memory. */
static int allocate_samples(double *v, int n0, int spp, int width, int height, uint32_t *extra)
{
    size_t npix = (size_t)width * (size_t)height;
    float *sigma = malloc(npix * sizeof *sigma);
    if (!sigma)
        return 0;
    double total = 0.0;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            double sum = 0.0;
            int n = 0;
            for (int yy = y > 0 ? y - 1 : 0; yy <= y + 1 && yy < height; ++yy)
                for (int xx = x > 0 ? x - 1 : 0; xx <= x + 1 && xx < width; ++xx, ++n)
                    sum += v[(size_t)yy * width + xx];
            sigma[(size_t)y * width + x] = (float)sqrt(sum / n);
            total += sigma[(size_t)y * width + x];
        }
    /* Shares: 10 % even, 90 % by sigma; then water-filling under the cap (a few rounds suffice). */
    double rest = (double)(spp - n0) * (double)npix, room = (double)(IC_ADAPTIVE_CAP * spp - n0);
    double *x = v; /* reuse: the real-valued extra samples */
    for (size_t i = 0; i < npix; ++i)
        x[i] = rest * (0.1 / (double)npix + (total > 0.0 ? 0.9 * sigma[i] / total : 0.9 / (double)npix));
    for (int round = 0; round < 8; ++round) {
        double over = 0.0, free_weight = 0.0;
        for (size_t i = 0; i < npix; ++i) {
            if (x[i] > room) {
                over += x[i] - room;
                x[i] = room;
            } else if (x[i] < room) {
                free_weight += x[i];
            }
        }
        if (!(over > 0.0) || !(free_weight > 0.0))
            break;
        double scale = 1.0 + over / free_weight;
        for (size_t i = 0; i < npix; ++i)
            if (x[i] < room)
                x[i] *= scale;
    }
    /* Integer counts whose running sum follows the real one (no sample lost to rounding). */
    double run = 0.0;
    uint64_t given = 0;
    for (size_t i = 0; i < npix; ++i) {
        run += x[i];
        uint64_t upto = (uint64_t)llround(run);
        uint64_t e = upto > given ? upto - given : 0;
        if (e > (uint64_t)room)
            e = (uint64_t)room;
        extra[i] = (uint32_t)e;
        given += e;
    }
    free(sigma);
    return 1;
}

static void loop_free(loop_ctx *c)
{
    free(c->accum);
    free(c->rays);
    free(c->samples);
    free(c->tile_state);
    free(c->todo);
    free(c->owned);
    free(c->owner);
    free(c->tile_seconds);
    free(c->tile_n);
}

/* Allocates the loop's buffers (accumulators and per-thread ray counters). */
static ic_result loop_init(loop_ctx *c, const ic_image_loop *loop, ic_sample_fn fn, void *user, int threads,
                           ic_error *err)
{
    const ic_camera *cam = loop->camera;
    memset(c, 0, sizeof *c);
    c->loop = loop;
    c->fn = fn;
    c->user = user;
    c->tiles_x = (cam->width + TILE - 1) / TILE;
    c->tiles_y = (cam->height + TILE - 1) / TILE;
    c->rank = ic_comm_rank(loop->comm);
    c->ranks = ic_comm_size(loop->comm);
    int tiles = c->tiles_x * c->tiles_y;
    c->own_tiles = tiles > c->rank ? (tiles - c->rank + c->ranks - 1) / c->ranks : 0;
    for (int64_t t = c->rank; t < tiles; t += c->ranks) {
        int x0, y0, x1, y1;
        tile_rect(c, t, &x0, &y0, &x1, &y1);
        c->own_pixels += (uint64_t)(x1 - x0) * (uint64_t)(y1 - y0);
    }
    atomic_init(&c->samples_done, 0);
    atomic_init(&c->pause, 0);
    c->checkpointing = loop->checkpoint && loop->checkpoint_seconds > 0.0 && !ic_comm_is_shared(loop->comm);
    size_t npix = (size_t)cam->width * (size_t)cam->height;
    c->accum = calloc(npix * 3, sizeof(double));
    c->rays = calloc((size_t)threads * RAY_PAD, sizeof(uint64_t));
    c->samples = calloc((size_t)threads * RAY_PAD, sizeof(uint64_t));
    if (c->checkpointing) {
        c->tile_state = calloc((size_t)tiles, 1);
        c->todo = malloc(sizeof *c->todo * (size_t)tiles);
        c->next_checkpoint = ic_seconds() + loop->checkpoint_seconds;
    }
    if (!c->accum || !c->rays || !c->samples || (c->checkpointing && (!c->tile_state || !c->todo))) {
        loop_free(c);
        return ic_error_set(err, IC_ERR_OOM, "out of memory for a %dx%d image", cam->width, cam->height);
    }
    return IC_OK;
}

/* Hands the image so far to loop.checkpoint (between rounds: no thread renders). A pixel's value is
 * the mean of the samples it holds: those of the earlier passes, and this pass's if its tile is done;
 * a pixel with none is black. Without memory for the image the checkpoint is skipped. */
static void take_checkpoint(loop_ctx *c)
{
    const ic_camera *cam = c->loop->camera;
    ic_image img;
    if (ic_image_create(&img, cam->width, cam->height) != IC_OK)
        return;
    for (int64_t t = 0; t < c->own_tiles; ++t) {
        int x0, y0, x1, y1;
        tile_rect(c, t, &x0, &y0, &x1, &y1);
        int rendered = c->tile_state[t] == TILE_RENDERED;
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                size_t i = (size_t)y * cam->width + x;
                int n = !rendered ? c->s_begin : c->extra ? c->s_begin + (int)c->extra[i] : c->s_end;
                for (int k = 0; k < 3; ++k)
                    img.rgb[3 * i + k] = n > 0 ? (float)(c->accum[3 * i + k] / n) : 0.0f;
            }
    }
    double completed = c->loop->time_budget > 0.0 ? fmin(1.0, (ic_seconds() - c->start) / c->loop->time_budget)
                       : c->samples_planned > 0.0 ? fmin(1.0, (double)atomic_load(&c->samples_done) / c->samples_planned)
                                                  : 0.0;
    c->loop->checkpoint(c->loop->checkpoint_user, &img, completed);
    ic_image_free(&img);
}

/* Runs samples [s_begin, s_end) (or each pixel's `extra` from s_begin) over every tile. With
 * checkpoints, in rounds over the tiles still waiting, each ended early when a checkpoint falls due. */
static ic_result loop_pass_timed(loop_ctx *c, int threads, int s_begin, int s_end, ic_error *err);
static ic_result loop_pass(loop_ctx *c, int threads, int s_begin, int s_end, ic_error *err)
{
    double t0 = ic_seconds();
    ic_result r = loop_pass_timed(c, threads, s_begin, s_end, err);
    c->busy += ic_seconds() - t0;
    return r;
}

static ic_result loop_pass_timed(loop_ctx *c, int threads, int s_begin, int s_end, ic_error *err)
{
    c->s_begin = s_begin;
    c->s_end = s_end;
    if (!c->checkpointing) {
        ic_result r = ic_parallel_for(threads, c->own_tiles, render_tile, c);
        return r == IC_OK ? IC_OK : ic_error_set(err, r, "could not start render threads");
    }
    memset(c->tile_state, TILE_WAITING, (size_t)c->own_tiles);
    for (;;) {
        int64_t n = 0;
        for (int64_t t = 0; t < c->own_tiles; ++t)
            if (c->tile_state[t] == TILE_WAITING)
                c->todo[n++] = t;
        if (n == 0)
            return IC_OK;
        atomic_store(&c->pause, 0);
        ic_result r = ic_parallel_for(threads, n, render_tile, c);
        if (r != IC_OK)
            return ic_error_set(err, r, "could not start render threads");
        int waiting = 0;
        for (int64_t t = 0; t < c->own_tiles && !waiting; ++t)
            waiting = c->tile_state[t] == TILE_WAITING;
        /* Due with tiles left: the image so far. (Due at the pass's end: at the next pass's first tile,
         * or never when the render is done, whose image comes next anyway.) */
        if (atomic_load(&c->pause) && waiting) {
            take_checkpoint(c);
            c->next_checkpoint = ic_seconds() + c->loop->checkpoint_seconds;
        }
    }
}

/* The rank that renders tile t. */
static int tile_owner(const loop_ctx *c, int64_t t) { return c->owner ? c->owner[t] : (int)(t % c->ranks); }

/* Copies tile t's rows between an image-wide plane of pixel_bytes a pixel and a packed block (the tile's
 * pixels row by row); to_packed chooses the direction. Returns the bytes copied. */
static size_t copy_tile(const loop_ctx *c, int64_t t, unsigned char *plane, unsigned char *packed, size_t pixel_bytes,
                        int to_packed)
{
    const ic_camera *cam = c->loop->camera;
    int x0, y0, x1, y1;
    tile_rect(c, t, &x0, &y0, &x1, &y1);
    size_t row = (size_t)(x1 - x0) * pixel_bytes, n = 0;
    for (int y = y0; y < y1; ++y, n += row) {
        unsigned char *v = plane + ((size_t)y * cam->width + x0) * pixel_bytes;
        if (to_packed)
            memcpy(packed + n, v, row);
        else
            memcpy(v, packed + n, row);
    }
    return n;
}

/* Tiles of an image-wide plane (pixel_bytes a pixel), each held by one rank, become every rank's (a no-op
 * for one process). from[t] is the rank that holds tile t, or -1 for a tile that stays where it is; NULL:
 * each tile's renderer. Every rank packs its tiles, in tile order, into its block of one all-gather and
 * copies the other ranks' blocks into their tiles, so each pixel keeps the bits its renderer computed. */
static int tile_sender(const loop_ctx *c, const int *from, int64_t t) { return from ? from[t] : tile_owner(c, t); }

static ic_result exchange_tiles(loop_ctx *c, void *plane, size_t pixel_bytes, const int *from, const char *what,
                                ic_error *err)
{
    if (c->ranks == 1)
        return IC_OK;
    const int64_t tiles = (int64_t)c->tiles_x * c->tiles_y;
    uint64_t *bytes = calloc((size_t)c->ranks, sizeof *bytes), *at = calloc((size_t)c->ranks, sizeof *at);
    for (int64_t t = 0; bytes && t < tiles; ++t) {
        int q = tile_sender(c, from, t), x0, y0, x1, y1;
        tile_rect(c, t, &x0, &y0, &x1, &y1);
        if (q >= 0)
            bytes[q] += pixel_bytes * (size_t)(x1 - x0) * (size_t)(y1 - y0);
    }
    uint64_t total = 0;
    for (int q = 0; bytes && at && q < c->ranks; ++q) {
        at[q] = total;
        total += bytes[q];
    }
    unsigned char *all = bytes && at ? malloc(total ? total : 1) : NULL;
    if (!all) {
        free(bytes);
        free(at);
        return ic_error_set(err, IC_ERR_OOM, "out of memory for %s (%d ranks)", what, c->ranks);
    }
    size_t n = at[c->rank];
    for (int64_t t = 0; t < tiles; ++t)
        if (tile_sender(c, from, t) == c->rank)
            n += copy_tile(c, t, plane, all + n, pixel_bytes, 1);
    ic_result r = ic_comm_allgather_sized(c->loop->comm, all, bytes, what, err);
    for (int64_t t = 0; r == IC_OK && t < tiles; ++t) {
        int q = tile_sender(c, from, t);
        if (q >= 0 && q != c->rank)
            at[q] += copy_tile(c, t, plane, all + at[q], pixel_bytes, 0);
    }
    free(bytes);
    free(at);
    free(all);
    return r;
}

static ic_result create_image(const loop_ctx *c, ic_image *out, ic_error *err)
{
    const ic_camera *cam = c->loop->camera;
    ic_result r = ic_image_create(out, cam->width, cam->height);
    if (r == IC_ERR_INVALID_ARG)
        return ic_error_set(err, r, "a %dx%d image is too large (at most %d a side and %zu pixels); render it "
                            "smaller", cam->width, cam->height, IC_IMAGE_MAX_SIDE, IC_IMAGE_MAX_PIXELS);
    if (r != IC_OK)
        return ic_error_set(err, r, "out of memory for a %dx%d image", cam->width, cam->height);
    return IC_OK;
}

/* Tile t of the image from the running sums: each pixel's mean over its n samples (its tile's tile_n, or
 * n0 + extra[i], or n0 for all with both NULL; black with none), in float. */
static void fill_tile(const loop_ctx *c, int64_t t, int n0, const uint32_t *extra, ic_image *out)
{
    const int width = c->loop->camera->width;
    int x0, y0, x1, y1;
    tile_rect(c, t, &x0, &y0, &x1, &y1);
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            size_t i = (size_t)y * width + x;
            uint32_t n = c->tile_n ? (uint32_t)c->tile_n[t] : (uint32_t)n0 + (extra ? extra[i] : 0);
            for (int k = 0; k < 3; ++k)
                out->rgb[3 * i + k] = n ? (float)(c->accum[3 * i + k] / n) : 0.0f;
        }
}

/* The image from the running sums, each tile computed by the rank that rendered it and then exchanged:
 * a rank receives (N − 1)/N of the image as 12 bytes a pixel. */
static ic_result finish_image(loop_ctx *c, int n0, const uint32_t *extra, ic_image *out, ic_error *err)
{
    ic_result r = create_image(c, out, err);
    if (r != IC_OK)
        return r;
    const int64_t tiles = (int64_t)c->tiles_x * c->tiles_y;
    for (int64_t t = 0; t < tiles; ++t)
        if (tile_owner(c, t) == c->rank)
            fill_tile(c, t, n0, extra, out);
    if ((r = exchange_tiles(c, out->rgb, 3 * sizeof *out->rgb, NULL, "exchanging the image", err)) != IC_OK)
        ic_image_free(out);
    return r;
}

/* ---- planes streamed during their last pass (several ranks whose comm has messages; stream.h): a tile
 * finished is computed and sent while the next renders, so a rank's share of the exchange overlaps its
 * work instead of following it. The values are the ones the exchange at the end would move. */
typedef struct streamed_plane {
    loop_ctx *c;
    unsigned char *plane;  /* image-wide, pixel_bytes a pixel */
    size_t pixel_bytes;
    /* Computes tile t's values in the plane from the running sums (on the thread that calls the comm,
     * once the tile's worker finished it). */
    void (*compute)(struct streamed_plane *p, int64_t t);
    int n0;                /* the image: the pilot's samples (adaptive) */
    const uint32_t *extra; /* the image: the second pass's samples per pixel, or NULL */
    ic_image *image;       /* the image, whose rgb is the plane */
} streamed_plane;

static size_t pack_streamed(void *user, int64_t t, unsigned char *to)
{
    streamed_plane *p = user;
    p->compute(p, t);
    return copy_tile(p->c, t, p->plane, to, p->pixel_bytes, 1);
}

static size_t unpack_streamed(void *user, int64_t t, const unsigned char *from)
{
    streamed_plane *p = user;
    return copy_tile(p->c, t, p->plane, (unsigned char *)from, p->pixel_bytes, 0);
}

static void compute_image_tile(streamed_plane *p, int64_t t) { fill_tile(p->c, t, p->n0, p->extra, p->image); }

/* Tile t's pilot relative variances (adaptive sampling), from its sums of n0 samples. */
static void compute_variance_tile(streamed_plane *p, int64_t t)
{
    const loop_ctx *c = p->c;
    const int width = c->loop->camera->width;
    double *v = (double *)p->plane;
    int x0, y0, x1, y1;
    tile_rect(c, t, &x0, &y0, &x1, &y1);
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            size_t px = (size_t)y * width + x;
            v[px] = relative_variance(c->accum, c->sumsq, p->n0, px);
        }
}

/* 1 when this render's planes can be streamed. */
static int can_stream(const loop_ctx *c) { return c->ranks > 1 && ic_comm_has_messages(c->loop->comm); }

/* A pass whose finished tiles stream plane p to every rank (so that, when it returns, every rank holds the
 * whole plane), or a plain pass with p NULL. */
static ic_result streamed_pass(loop_ctx *c, int threads, int s_begin, int s_end, streamed_plane *p, ic_error *err)
{
    if (!p)
        return loop_pass(c, threads, s_begin, s_end, err);
    const int64_t tiles = (int64_t)c->tiles_x * c->tiles_y;
    ic_result r = ic_stream_begin(&c->stream, c->loop->comm, c->own_tiles, tiles - c->own_tiles, tiles,
                                  (size_t)TILE * TILE * p->pixel_bytes, pack_streamed, unpack_streamed, p, err);
    if (r != IC_OK)
        return r;
    r = loop_pass(c, threads, s_begin, s_end, err);
    ic_error stream_err;
    ic_result rs = ic_stream_end(c->stream, &stream_err);
    c->stream = NULL;
    if (r == IC_OK && rs != IC_OK) {
        if (err)
            *err = stream_err;
        r = rs;
    }
    return r;
}

/* This process's ray and sample counts into res. */
static void count_work(const loop_ctx *c, int threads, ic_image_loop_result *res)
{
    for (int t = 0; t < threads; ++t) {
        res->rays += c->rays[t * RAY_PAD];
        res->samples += c->samples[t * RAY_PAD];
    }
}

/* Several ranks, adaptive sampling: the pilot's interleaved split gives each rank about the same pixels,
 * but the second pass's samples follow the noise, so its cost per tile varies many times over. Each
 * tile's cost is estimated as its pilot seconds per sample times the samples the allocation gives it;
 * the pilot times are summed over the ranks (each tile was timed by one), so every rank holds the same
 * costs and makes the same split. A tile stays on the rank that rendered its pilot (its home, which holds
 * its sums) while that rank's load stays within the mean; the tiles that do not fit go, most costly first,
 * to the least loaded rank (Graham's LPT rule; ties to the lower rank), and only their pilot sums move.
 * Which rank renders a tile does not change its pixels, so the image stays the same. */
typedef struct tile_cost {
    double cost;
    int64_t tile;
} tile_cost;

/* Least costly first, ties by tile index: a total order, so every rank sorts alike. */
static int cmp_tile_cost(const void *a, const void *b)
{
    const tile_cost *x = a, *y = b;
    if (x->cost != y->cost)
        return x->cost < y->cost ? -1 : 1;
    return (x->tile > y->tile) - (x->tile < y->tile);
}

static ic_result balance_second_pass(loop_ctx *c, int n0, ic_error *err)
{
    const ic_camera *cam = c->loop->camera;
    const int tiles = c->tiles_x * c->tiles_y;
    ic_result r = ic_comm_sum(c->loop->comm, c->tile_seconds, (uint64_t)tiles, err);
    double *load = calloc((size_t)c->ranks, sizeof *load), total = 0.0;
    tile_cost *order = malloc(sizeof *order * (size_t)tiles);
    int *moved = malloc(sizeof *moved * (size_t)tiles);
    c->owner = malloc(sizeof *c->owner * (size_t)tiles);
    c->owned = malloc(sizeof *c->owned * (size_t)tiles);
    if (r == IC_OK && (!load || !order || !moved || !c->owner || !c->owned))
        r = ic_error_set(err, IC_ERR_OOM, "out of memory for sharing out %d tiles", tiles);
    for (int t = 0; r == IC_OK && t < tiles; ++t) {
        int x0, y0, x1, y1;
        tile_rect(c, t, &x0, &y0, &x1, &y1);
        double samples = 0.0;
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x)
                samples += c->extra[(size_t)y * cam->width + x];
        double pilot = (double)n0 * (x1 - x0) * (y1 - y0);
        order[t].cost = samples * c->tile_seconds[t] / pilot;
        order[t].tile = t;
        total += order[t].cost;
    }
    if (r == IC_OK)
        qsort(order, (size_t)tiles, sizeof *order, cmp_tile_cost);
    /* Home first, least costly first, up to the mean load: a rank over it sets aside its costliest tiles,
     * so few tiles move (1.4 % of Sponza's at 1280x720 and 16 ranks, against 18 % filling most costly
     * first; BENCHMARKS.md). The set-aside tiles then go most costly first to the least loaded rank. */
    const double mean = total / c->ranks;
    int aside = 0;
    for (int i = 0; r == IC_OK && i < tiles; ++i) {
        int64_t t = order[i].tile;
        int home = (int)(t % c->ranks);
        if (load[home] + order[i].cost <= mean) {
            load[home] += order[i].cost;
            c->owner[t] = home;
        } else {
            order[aside++] = order[i];
        }
    }
    for (int i = aside - 1; r == IC_OK && i >= 0; --i) {
        int best = 0;
        for (int q = 1; q < c->ranks; ++q)
            if (load[q] < load[best])
                best = q;
        load[best] += order[i].cost;
        c->owner[order[i].tile] = best;
    }
    c->own_tiles = 0;
    c->own_pixels = 0;
    for (int t = 0; r == IC_OK && t < tiles; ++t) {
        int home = t % c->ranks;
        moved[t] = c->owner[t] != home ? home : -1;
        if (c->owner[t] == c->rank) {
            int x0, y0, x1, y1;
            tile_rect(c, t, &x0, &y0, &x1, &y1);
            c->owned[c->own_tiles++] = t;
            c->own_pixels += (uint64_t)(x1 - x0) * (uint64_t)(y1 - y0);
        }
    }
    /* The moved tiles' pilot sums, from their homes. */
    if (r == IC_OK)
        r = exchange_tiles(c, c->accum, 3 * sizeof *c->accum, moved, "exchanging the pilot's sums", err);
    free(load);
    free(order);
    free(moved);
    free(c->tile_seconds);
    c->tile_seconds = NULL;
    return r;
}

static ic_result render_adaptive(const ic_image_loop *loop, ic_sample_fn fn, void *user, ic_image *out,
                                 ic_image_loop_result *res, ic_error *err)
{
    const ic_camera *cam = loop->camera;
    int threads = ic_resolve_threads(loop->threads);
    loop_ctx c;
    ic_result r = loop_init(&c, loop, fn, user, threads, err);
    if (r != IC_OK)
        return r;
    size_t npix = (size_t)cam->width * (size_t)cam->height;
    int n0 = loop->spp / 4;
    c.skip_on_cancel = loop->cancel && !ic_comm_is_shared(loop->comm);
    c.sumsq = calloc(npix, sizeof *c.sumsq);
    uint32_t *extra = malloc(npix * sizeof *extra);
    if (c.ranks > 1)
        c.tile_seconds = calloc((size_t)c.tiles_x * c.tiles_y, sizeof *c.tile_seconds);
    c.samples_planned = (double)loop->spp * (double)c.own_pixels; /* the pilot's and the rest's */
    /* Which tiles the pilot rendered (n0) or an interrupt skipped (0), so that the counts below are what
     * the pixels hold; the second pass counts per pixel (extra) instead. */
    c.tile_n = calloc((size_t)c.tiles_x * c.tiles_y, sizeof *c.tile_n);
    c.start = ic_seconds();
    if (!c.sumsq || !extra || !c.tile_n || (c.ranks > 1 && !c.tile_seconds))
        r = ic_error_set(err, IC_ERR_OOM, "out of memory for adaptive sampling of a %dx%d image", cam->width,
                         cam->height);
    /* Every rank shares out the rest from the whole pilot's relative variances (each rank computes those of
     * its own tiles and the ranks exchange them, 8 bytes a pixel, streamed during the pilot where the comm
     * can), so all make the same allocation. */
    double *v = r == IC_OK ? malloc(npix * sizeof *v) : NULL;
    if (r == IC_OK && !v)
        r = ic_error_set(err, IC_ERR_OOM, "out of memory for adaptive sampling of a %dx%d image", cam->width,
                         cam->height);
    streamed_plane variances = {&c, (unsigned char *)v, sizeof *v, compute_variance_tile, n0, NULL, NULL};
    const int streaming = can_stream(&c);
    if (r == IC_OK)
        r = streamed_pass(&c, threads, 0, n0, streaming ? &variances : NULL, err);
    int *pilot_n = c.tile_n; /* finish_image divides by n0 + extra, per pixel */
    c.tile_n = NULL;
    for (int64_t i = 0; r == IC_OK && !streaming && i < c.own_tiles; ++i)
        compute_variance_tile(&variances, own_tile(&c, i));
    if (r == IC_OK && !streaming)
        r = exchange_tiles(&c, v, sizeof *v, NULL, "exchanging the pilot's variances", err);
    if (r == IC_OK && !allocate_samples(v, n0, loop->spp, cam->width, cam->height, extra))
        r = ic_error_set(err, IC_ERR_OOM, "out of memory for adaptive sampling of a %dx%d image", cam->width,
                         cam->height);
    free(v);
    if (r == IC_OK) {
        free(c.sumsq);
        c.sumsq = NULL;
        c.extra = extra;
        double planned = (double)n0 * (double)c.own_pixels;
        if (c.ranks > 1)
            r = balance_second_pass(&c, n0, err);
        /* What progress counts now: the pilot's samples and the rest as shared out. */
        for (int64_t i = 0; r == IC_OK && i < c.own_tiles; ++i) {
            int64_t t = own_tile(&c, i);
            int x0, y0, x1, y1;
            tile_rect(&c, t, &x0, &y0, &x1, &y1);
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x)
                    planned += extra[(size_t)y * cam->width + x];
        }
        c.samples_planned = planned;
        /* The image, streamed during the second pass where the comm can. */
        streamed_plane image = {&c, NULL, 3 * sizeof(float), compute_image_tile, n0, extra, out};
        if (r == IC_OK && streaming && (r = create_image(&c, out, err)) == IC_OK)
            image.plane = (unsigned char *)out->rgb;
        if (r == IC_OK)
            r = streamed_pass(&c, threads, n0, n0, streaming ? &image : NULL, err);
        if (r != IC_OK && image.plane) /* only the image made here: the caller's may hold anything */
            ic_image_free(out);
    }
    if (r == IC_OK && !streaming)
        r = finish_image(&c, n0, extra, out, err);
    if (r == IC_OK) {
        uint64_t taken = 0;
        uint32_t most = 0, fewest = UINT32_MAX;
        for (size_t i = 0; i < npix; ++i) {
            const int tile = (int)((i % (size_t)cam->width) / TILE) +
                             (int)((i / (size_t)cam->width) / TILE) * c.tiles_x;
            /* An interrupted pilot left its skipped tiles black: they hold no samples (their extra is 0). */
            uint32_t n = (c.skip_on_cancel && pilot_n[tile] == 0 ? 0u : (uint32_t)n0) + extra[i];
            taken += n;
            most = n > most ? n : most;
            fewest = n < fewest ? n : fewest;
        }
        count_work(&c, threads, res);
        res->spp_done = (int)llround((double)taken / (double)npix);
        res->spp_max = (int)most;
        res->spp_min = (int)fewest;
        int skipped = atomic_load(&c.tiles_skipped);
        res->cancelled = skipped > 0;
        /* The share of the planned samples taken (one process: every tile is its own when it can skip). */
        res->completed = skipped > 0 && c.samples_planned > 0.0 ? fmin(1.0, (double)taken / c.samples_planned) : 1.0;
    }
    res->seconds = ic_seconds() - c.start;
    res->busy_seconds = c.busy;
    free(pilot_n);
    free(c.sumsq);
    free(extra);
    loop_free(&c);
    return r;
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
    if (loop->adaptive && (loop->spp < 8 || loop->time_budget > 0.0))
        return ic_error_set(err, IC_ERR_INVALID_ARG,
                            "adaptive sampling needs --spp of at least 8 and no --time (it shares out a fixed budget)");
    if (loop->adaptive && loop->spp > INT_MAX / IC_ADAPTIVE_CAP)
        return ic_error_set(err, IC_ERR_INVALID_ARG,
                            "--spp %d is too large for adaptive sampling (at most %d); lower it or add "
                            "--adaptive-sampling off", loop->spp, INT_MAX / IC_ADAPTIVE_CAP);
    /* Interrupted before the film began (during cache construction): one sample per pixel, every tile,
     * so that there is an image to look at. */
    const int can_cancel = loop->cancel && !ic_comm_is_shared(loop->comm);
    const int preview = can_cancel && *loop->cancel;
    if (loop->adaptive && !preview)
        return render_adaptive(loop, fn, user, out, res, err);
    int threads = ic_resolve_threads(loop->threads);
    loop_ctx c;
    ic_result r = loop_init(&c, loop, fn, user, threads, err);
    if (r != IC_OK)
        return r;
    c.tile_n = calloc((size_t)c.tiles_x * c.tiles_y, sizeof *c.tile_n);
    if (!c.tile_n) {
        loop_free(&c);
        return ic_error_set(err, IC_ERR_OOM, "out of memory for a %dx%d image", cam->width, cam->height);
    }
    c.start = ic_seconds();
    /* Once interrupted, a pass skips its tiles not yet started, and no pass follows: a skipped tile keeps
     * what the earlier passes (under a time budget) gave it, black without one. */
    c.skip_on_cancel = can_cancel && !preview;
    int stopped = 0;
    /* Without a budget: one pass of all samples. With a budget: passes of growing size, stopping
     * before a pass that would overrun the budget (estimated from the previous pass). */
    int spp_max = preview ? 1 : loop->spp > 0 ? loop->spp : (1 << 30);
    int done = 0, pass_spp = loop->time_budget > 0.0 ? 1 : spp_max;
    c.samples_planned = loop->time_budget > 0.0 ? 0.0 : (double)spp_max * (double)c.own_pixels;
    double per_sample = 0.0;
    /* Without a budget the one pass is the last: the image is streamed during it where the comm can. */
    streamed_plane image = {&c, NULL, 3 * sizeof(float), compute_image_tile, 0, NULL, out};
    const int streaming = can_stream(&c) && !(loop->time_budget > 0.0) && !preview;
    if (streaming)
        r = create_image(&c, out, err);
    if (r == IC_OK && streaming)
        image.plane = (unsigned char *)out->rgb;
    while (r == IC_OK && done < spp_max) {
        if (can_cancel && !preview && done > 0 && *loop->cancel) {
            stopped = 1;
            break;
        }
        if (pass_spp > spp_max - done)
            pass_spp = spp_max - done;
        if (loop->time_budget > 0.0 && done > 0) {
            double left = loop->time_budget - (ic_seconds() - c.start);
            /* in double first: a long budget over cheap samples exceeds an int */
            int fit = per_sample > 0.0 ? (int)fmin(fmax(left / per_sample, 0.0), (double)pass_spp) : pass_spp;
            if (pass_spp > fit)
                pass_spp = fit > 0 ? fit : 0;
            /* Rank 0's clock decides for all, so every pixel gets the same samples. */
            int32_t decided = pass_spp;
            if ((r = ic_comm_broadcast(loop->comm, &decided, sizeof decided, 0, err)) != IC_OK)
                break;
            pass_spp = decided;
            if (pass_spp < 1)
                break;
        }
        double t0 = ic_seconds();
        if ((r = streamed_pass(&c, threads, done, done + pass_spp, streaming ? &image : NULL, err)) != IC_OK)
            break;
        per_sample = (ic_seconds() - t0) / pass_spp;
        done += pass_spp;
        if (loop->time_budget > 0.0 && loop->progress)
            loop->progress(loop->progress_user, loop->phase ? loop->phase : "render",
                           fmin(1.0, (ic_seconds() - c.start) / loop->time_budget));
        pass_spp *= 2;
    }
    if (r == IC_OK && done == 0)
        r = ic_error_set(err, IC_ERR_INVALID_ARG, "time budget too small for one sample per pixel; raise --time");
    if (r == IC_OK && !streaming)
        r = finish_image(&c, done, NULL, out, err);
    else if (r != IC_OK && streaming)
        ic_image_free(out);
    if (r == IC_OK) {
        /* The samples this process's pixels hold: `done` in each unless a pass was cut short. */
        uint64_t taken = 0;
        int most = 0, fewest = done;
        for (int64_t i = 0; i < c.own_tiles; ++i) {
            int64_t t = own_tile(&c, i);
            int x0, y0, x1, y1, n = c.tile_n[t];
            tile_rect(&c, t, &x0, &y0, &x1, &y1);
            taken += (uint64_t)n * (uint64_t)(x1 - x0) * (uint64_t)(y1 - y0);
            most = n > most ? n : most;
            fewest = n < fewest ? n : fewest;
        }
        count_work(&c, threads, res);
        res->spp_done = c.own_pixels ? (int)llround((double)taken / (double)c.own_pixels) : done;
        res->spp_max = c.own_tiles ? most : done;
        res->spp_min = fewest;
        int skipped = atomic_load(&c.tiles_skipped);
        res->cancelled = preview || stopped || skipped > 0;
        /* Of the samples the passes begun would have taken. */
        res->completed = preview ? 0.0 : c.own_pixels ? (double)taken / ((double)done * (double)c.own_pixels) : 1.0;
    }
    res->seconds = ic_seconds() - c.start;
    res->busy_seconds = c.busy;
    loop_free(&c);
    return r;
}
