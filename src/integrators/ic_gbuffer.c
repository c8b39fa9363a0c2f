/*
 * ic_gbuffer.c — the cache's shading points: one per pixel centre, after ideal specular chains (the
 * G-buffer every strategy starts from), and cache look-ups over all of them.
 */
#include "ic_internal.h"

#include "core/select.h"
#include "core/threads.h"
#include "film/film.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

/* Follows a camera ray through ideal specular surfaces to the first surface with a smooth lobe.
 * Glass takes the more likely branch (refraction unless Fresnel reflection dominates): the shading
 * points of the cache must be a deterministic function of the pixel. */
int ic_ic_shading_point(const ic_tracer *tr, ic_ray ray, ic_surface *s, ic_bsdf *b, ic_vec3 *wo, float *t_primary,
                        uint64_t *rays)
{
    for (int k = 0; k <= MAX_SPECULAR_CHAIN; ++k) {
        ic_hit hit;
        ++*rays;
        ic_accel_intersect1(tr->accel, &ray, &hit);
        if (hit.triangle == IC_NO_HIT)
            return 0;
        if (k == 0 && t_primary)
            *t_primary = hit.t;
        ic_scene_surface(tr->scene, hit.triangle, hit.u, hit.v, s);
        *wo = v3_neg(ray.dir);
        ic_bsdf_init(b, tr->scene, s, *wo);
        if (ic_bsdf_has_smooth(b))
            return 1;
        ic_bsdf_sample bs;
        float F = ic_bsdf_reflect_probability(b, *wo);
        if (!ic_bsdf_sample_dir(b, *wo, F > 0.5f ? 0.0f : 0.999f, 0.5f, 0.5f, &bs))
            return 0;
        ray = ic_spawn_ray(s, bs.wi);
    }
    return 0;
}

typedef struct gbuffer_job {
    ic_ctx *c;
    uint64_t *rays;            /* per thread, padded */
    int first_row;             /* the rows to compute start here */
} gbuffer_job;

#define PAD 8

/* Pixel (x, y)'s shading point: the one definition the G-buffer and ic_ic_gbuffer_point share. */
static int shade_pixel(const ic_ctx *c, int x, int y, ic_vec3 *p, ic_vec3 *n, float *footprint, uint64_t *rays)
{
    const ic_camera *cam = &c->tr->scene->camera;
    ic_ray ray;
    ic_surface s;
    ic_bsdf b;
    ic_vec3 wo;
    float t_primary = 0.0f;
    if (!ic_camera_ray(cam, (float)x + 0.5f, (float)y + 0.5f, &ray) ||
        !ic_ic_shading_point(c->tr, ray, &s, &b, &wo, &t_primary, rays))
        return 0;
    *p = s.p;
    *n = b.cache_n;
    *footprint = ic_camera_footprint(cam, (float)x + 0.5f, (float)y + 0.5f, t_primary);
    return 1;
}

static void gbuffer_row(void *p, int64_t item, int thread)
{
    gbuffer_job *j = p;
    int y = j->first_row + (int)item;
    ic_ctx *c = j->c;
    for (int x = 0; x < c->g.width; ++x) {
        size_t i = (size_t)y * c->g.width + x;
        c->g.valid[i] = (uint8_t)shade_pixel(c, x, y, &c->g.p[i], &c->g.n[i], &c->g.footprint[i],
                                             &j->rays[thread * PAD]);
    }
}

int ic_ic_gbuffer_point(const ic_ctx *c, uint32_t pixel, ic_vec3 *p, ic_vec3 *n, float *footprint)
{
    if (!c->g.valid[pixel])
        return 0;
    const int y = (int)(pixel / (uint32_t)c->g.width), x = (int)(pixel % (uint32_t)c->g.width);
    float fp;
    if (y >= c->g_rows[0] && y < c->g_rows[1]) {
        *p = c->g.p[pixel];
        *n = c->g.n[pixel];
        fp = c->g.footprint[pixel];
    } else {
        uint64_t rays = 0;
        shade_pixel(c, x, y, p, n, &fp, &rays);
    }
    if (footprint)
        *footprint = fp;
    return 1;
}

ic_result ic_ic_gbuffer_build(ic_ctx *c, int full, ic_error *err)
{
    const ic_camera *cam = &c->tr->scene->camera;
    size_t n = (size_t)cam->width * cam->height;
    c->g.width = cam->width;
    c->g.height = cam->height;
    c->g.p = calloc(n, sizeof *c->g.p);
    c->g.n = calloc(n, sizeof *c->g.n);
    c->g.footprint = calloc(n, sizeof *c->g.footprint);
    c->g.valid = calloc(n, 1);
    c->has_record = calloc(n, 1);
    uint64_t *rays = calloc((size_t)c->threads * PAD, sizeof *rays);
    if (!c->g.p || !c->g.n || !c->g.footprint || !c->g.valid || !c->has_record || !rays) {
        free(rays);
        return ic_error_set(err, IC_ERR_OOM, "out of memory for the shading-point buffers");
    }
    /* Several processes (c->comm): a block of rows each, and the band around it unless full. */
    uint64_t first, rows;
    ic_comm_block((uint64_t)cam->height, ic_comm_size(c->comm), ic_comm_rank(c->comm), &first, &rows);
    const int shared = ic_comm_is_shared(c->comm), band = shared && !full;
    const int y0 = (int)first, y1 = (int)(first + rows);
    /* What this process will hold once the exchange below is done. */
    c->g_rows[0] = band ? (y0 - IC_SCREEN_HALO > 0 ? y0 - IC_SCREEN_HALO : 0) : 0;
    c->g_rows[1] = band ? (y1 + IC_SCREEN_HALO < cam->height ? y1 + IC_SCREEN_HALO : cam->height) : cam->height;
    /* This block's rows, counted; the band's other rows are the neighbours' (counted there). */
    gbuffer_job j = {c, rays, y0};
    ic_result r = ic_parallel_for(c->threads, (int64_t)(y1 - y0), gbuffer_row, &j);
    for (int t = 0; t < c->threads; ++t)
        atomic_fetch_add(&c->rays, rays[t * PAD]);
    if (r == IC_OK && band) {
        j.first_row = c->g_rows[0];
        r = ic_parallel_for(c->threads, (int64_t)(y0 - c->g_rows[0]), gbuffer_row, &j);
        j.first_row = y1;
        if (r == IC_OK)
            r = ic_parallel_for(c->threads, (int64_t)(c->g_rows[1] - y1), gbuffer_row, &j);
    }
    free(rays);
    if (r != IC_OK)
        return ic_error_set(err, r, "could not start threads");
    const size_t row_px = (size_t)cam->width;
    if (band) /* whether each pixel has a point: every process's block of rows */
        return ic_comm_allgather_blocks(c->comm, c->g.valid, (uint64_t)cam->height, row_px,
                                        "exchanging shading points", err);
    void *buf[4] = {c->g.p, c->g.n, c->g.footprint, c->g.valid};
    const size_t bytes[4] = {sizeof *c->g.p, sizeof *c->g.n, sizeof *c->g.footprint, 1};
    for (int k = 0; k < 4 && r == IC_OK; ++k)
        r = ic_comm_allgather_blocks(c->comm, buf[k], (uint64_t)cam->height, bytes[k] * row_px,
                                     "exchanging shading points", err);
    return r;
}

#define VIEW_SAMPLES 65536u

ic_result ic_ic_view_extent(const ic_ctx *c, float *extent, ic_error *err)
{
    *extent = 0.0f;
    const size_t width = (size_t)c->g.width, npix = width * (size_t)c->g.height;
    size_t valid = 0;
    for (size_t i = 0; i < npix; ++i)
        valid += c->g.valid[i];
    if (valid == 0)
        return IC_OK;
    /* The samples: every stride-th valid pixel in raster order. Several processes each take those of their
     * own rows (their points are in their G-buffers) and exchange them; rows are in rank order, so every
     * process gets the samples in raster order. */
    const size_t stride = valid / VIEW_SAMPLES + 1, cap = valid / stride + 1;
    const int ranks = ic_comm_size(c->comm), rank = ic_comm_rank(c->comm);
    ic_vec3 *pts = malloc(sizeof *pts * cap);
    float *v = malloc(sizeof *v * cap);
    uint64_t *bytes = malloc(sizeof *bytes * (size_t)ranks);
    if (!pts || !v || !bytes) {
        free(pts);
        free(v);
        free(bytes);
        return ic_error_set(err, IC_ERR_OOM, "out of memory for the view's extent");
    }
    size_t m = 0, k = 0;
    for (int q = 0; q < ranks; ++q) {
        uint64_t first, rows;
        ic_comm_block((uint64_t)c->g.height, ranks, q, &first, &rows);
        const size_t before = m;
        for (size_t i = (size_t)first * width; i < (size_t)(first + rows) * width; ++i) {
            if (!c->g.valid[i] || k++ % stride)
                continue;
            if (q == rank) {
                ic_vec3 nn;
                ic_ic_gbuffer_point(c, (uint32_t)i, &pts[m], &nn, NULL);
            }
            ++m;
        }
        bytes[q] = (m - before) * sizeof *pts;
    }
    ic_result r = ic_comm_allgather_sized(c->comm, pts, bytes, "exchanging the view's sample points", err);
    float d2 = 0.0f;
    for (int axis = 0; axis < 3 && r == IC_OK; ++axis) {
        for (size_t j = 0; j < m; ++j)
            v[j] = v3_get(pts[j], axis);
        const float high = ic_kth_smallest(v, m, (m - 1) * 95 / 100), low = ic_kth_smallest(v, m, (m - 1) * 5 / 100);
        float span = high - low;
        d2 += span * span;
    }
    free(pts);
    free(v);
    free(bytes);
    *extent = sqrtf(d2);
    return r;
}

void ic_ic_gbuffer_free(ic_ctx *c)
{
    free(c->g.p);
    free(c->g.n);
    free(c->g.footprint);
    free(c->g.valid);
    free(c->has_record);
}

typedef struct lookup_job {
    ic_ctx *c;
    float *lum;                /* per pixel luminance of the look-up */
    uint8_t *covered;          /* per pixel: some record contributes */
    ic_cache_acceptance acceptance;
    int first_row;             /* this process's block of rows starts here */
} lookup_job;

/* One row's look-ups, in batches of up to LOOKUP_BATCH pixels with a hint carried along the row
 * (ic_cache_query_batch: the answers of one look-up each, without the per-call costs). */
enum { LOOKUP_BATCH = 64 };

static void lookup_row(void *p, int64_t item, int thread)
{
    (void)thread;
    lookup_job *j = p;
    int64_t y = j->first_row + item;
    const ic_gbuffer *g = &j->c->g;
    ic_cache_hint hint = {0};
    ic_cache_lookup q[LOOKUP_BATCH];
    ic_cache_estimate e[LOOKUP_BATCH];
    size_t pixel[LOOKUP_BATCH], m = 0;
    for (int x = 0; x < g->width; ++x) {
        size_t i = (size_t)y * g->width + x;
        j->covered[i] = 0;
        j->lum[i] = 0.0f;
        if (g->valid[i]) {
            q[m] = ic_cache_lookup_at(g->p[i], g->n[i], j->acceptance);
            pixel[m++] = i;
        }
        if (m == LOOKUP_BATCH || (x + 1 == g->width && m > 0)) {
            ic_cache_query_batch(j->c->cache, q, m, &hint, e);
            for (size_t k = 0; k < m; ++k) {
                j->covered[pixel[k]] = (uint8_t)(e[k].contributor_count > 0);
                j->lum[pixel[k]] = v3_lum(e[k].irradiance);
            }
            m = 0;
        }
    }
}

/* Several processes: rank q's block of rows [b[q], b[q + 1]) goes to every other rank whose band (its
 * block widened by IC_SCREEN_HALO rows each way, what its need map reads) it meets. The rows of q's block
 * inside t's band: [*a, *z), empty when *z <= *a. Each block's rows stay in order, so the all-to-all's
 * blocks land row after row. */
static void band_part(const uint64_t *b, int q, int t, int height, int64_t *a, int64_t *z)
{
    int64_t lo = (int64_t)b[t] - IC_SCREEN_HALO > 0 ? (int64_t)b[t] - IC_SCREEN_HALO : 0;
    int64_t hi = (int64_t)b[t + 1] + IC_SCREEN_HALO < height ? (int64_t)b[t + 1] + IC_SCREEN_HALO : height;
    *a = lo > (int64_t)b[q] ? lo : (int64_t)b[q];
    *z = hi < (int64_t)b[q + 1] ? hi : (int64_t)b[q + 1];
}

static ic_result exchange_band(ic_ctx *c, float *lum)
{
    const int n = ic_comm_size(c->comm), me = ic_comm_rank(c->comm), h = c->g.height;
    const size_t row = sizeof *lum * (size_t)c->g.width;
    uint64_t *b = malloc(sizeof *b * ((size_t)n + 1)), *matrix = malloc(sizeof *matrix * (size_t)n * (size_t)n);
    float *send = NULL, *recv = NULL;
    ic_result r = b && matrix ? IC_OK : IC_ERR_OOM;
    uint64_t out_rows = 0, in_rows = 0;
    for (int q = 0; r == IC_OK && q <= n; ++q) {
        uint64_t first, rows;
        ic_comm_block((uint64_t)h, n, q < n ? q : n - 1, &first, &rows);
        b[q] = q < n ? first : first + rows;
    }
    /* matrix[q][t]: the rows of q's block inside t's band (none to itself). */
    for (int q = 0; r == IC_OK && q < n; ++q)
        for (int t = 0; t < n; ++t) {
            int64_t a, z;
            band_part(b, q, t, h, &a, &z);
            uint64_t rows = q != t && z > a ? (uint64_t)(z - a) : 0;
            matrix[(size_t)q * n + t] = rows * row;
            out_rows += q == me ? rows : 0;
            in_rows += t == me ? rows : 0;
        }
    if (r == IC_OK) {
        send = malloc(out_rows ? out_rows * row : 1);
        recv = malloc(in_rows ? in_rows * row : 1);
        r = send && recv ? IC_OK : IC_ERR_OOM;
    }
    if (r == IC_OK) {
        char *put = (char *)send;
        for (int t = 0; t < n; ++t) {
            int64_t a, z;
            band_part(b, me, t, h, &a, &z);
            uint64_t bytes = matrix[(size_t)me * n + t];
            memcpy(put, lum + (size_t)a * c->g.width, bytes);
            put += bytes;
        }
        r = ic_comm_alltoall(c->comm, send, matrix, recv, "exchanging look-ups", NULL);
    }
    if (r == IC_OK) {
        const char *get = (const char *)recv;
        for (int q = 0; q < n; ++q) {
            int64_t a, z;
            band_part(b, q, me, h, &a, &z);
            uint64_t bytes = matrix[(size_t)q * n + me];
            memcpy(lum + (size_t)a * c->g.width, get, bytes);
            get += bytes;
        }
    }
    free(b);
    free(matrix);
    free(send);
    free(recv);
    return r;
}

/* Several processes (c->comm): a block of rows each. The luminances, when asked for, go to the processes
 * whose need maps read them (a band of IC_SCREEN_HALO rows around each block, the pyramid's coarse levels'
 * reach); rows outside this process's band keep whatever they held, which its need map never reads.
 * `covered` stays on the rows' own process, which alone reads it. */
ic_result ic_ic_lookup_all(ic_ctx *c, float *lum, uint8_t *covered, ic_cache_acceptance acc, int want_lum)
{
    uint64_t first, rows;
    ic_comm_block((uint64_t)c->g.height, ic_comm_size(c->comm), ic_comm_rank(c->comm), &first, &rows);
    lookup_job j = {c, lum, covered, acc, (int)first};
    ic_result r = ic_parallel_for(c->threads, (int64_t)rows, lookup_row, &j);
    if (r == IC_OK && want_lum && ic_comm_is_shared(c->comm))
        r = exchange_band(c, lum);
    return r;
}
