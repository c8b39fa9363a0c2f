/* ic_screen.c — discontinuity maps, mip pyramid, blend and dithering (ic_screen.h; Frolov et al. 2012 §3.1). */
#include "ic_screen.h"

#include "core/threads.h"
#include "core/vecmath.h"

#include <stdlib.h>
#include <string.h>


/* One level of the pyramid: the channels its discontinuity reads (p, n, fp for geometry; val for values)
 * and valid. Level 0 is the g-buffer itself (and the values), not a copy. */
typedef struct level {
    int w, h;
    ic_vec3 *p, *n;
    float *fp, *val;
    uint8_t *valid;
} level;

static void level_free(level *l)
{
    free(l->p);
    free(l->n);
    free(l->fp);
    free(l->val);
    free(l->valid);
    memset(l, 0, sizeof *l);
}

static int level_alloc(level *l, int w, int h, int geometry)
{
    size_t n = (size_t)w * (size_t)h;
    l->w = w;
    l->h = h;
    l->valid = calloc(n, 1);
    if (geometry) {
        l->p = calloc(n, sizeof *l->p);
        l->n = calloc(n, sizeof *l->n);
        l->fp = calloc(n, sizeof *l->fp);
        return l->valid && l->p && l->n && l->fp;
    }
    l->val = calloc(n, sizeof *l->val);
    return l->valid && l->val;
}

/* Rows [y_lo, y_hi] of level l+1 average the valid pixels of each 2×2 block of level l (the channels level b
 * has); the other rows stay empty. */
static void downsample(const level *a, level *b, int y_lo, int y_hi)
{
    for (int y = y_lo; y <= y_hi; ++y) {
        for (int x = 0; x < b->w; ++x) {
            ic_vec3 p = v3s(0), n = v3s(0);
            float fp = 0, val = 0;
            int cnt = 0;
            for (int dy = 0; dy < 2; ++dy) {
                for (int dx = 0; dx < 2; ++dx) {
                    int sx = 2 * x + dx, sy = 2 * y + dy;
                    if (sx >= a->w || sy >= a->h)
                        continue;
                    size_t i = (size_t)sy * a->w + sx;
                    if (!a->valid[i])
                        continue;
                    if (b->p) {
                        p = v3_add(p, a->p[i]);
                        n = v3_add(n, a->n[i]);
                        fp += a->fp[i];
                    } else {
                        val += a->val[i];
                    }
                    ++cnt;
                }
            }
            size_t o = (size_t)y * b->w + x;
            if (cnt) {
                float inv = 1.0f / (float)cnt;
                if (b->p) {
                    b->p[o] = v3_scale(p, inv);
                    b->n[o] = v3_norm(n);
                    b->fp[o] = fp * inv;
                } else {
                    b->val[o] = val * inv;
                }
                b->valid[o] = 1;
            }
        }
    }
}

typedef float (*disc_fn)(const level *l, size_t i, size_t j, int lev, float k);

static float geometry_disc(const level *l, size_t i, size_t j, int lev, float k)
{
    float nd = 1.0f - ic_clampf(v3_dot(l->n[i], l->n[j]), -1.0f, 1.0f);
    float pixel = l->fp[i] * (float)(1 << lev);
    float off = fabsf(v3_dot(l->n[i], v3_sub(l->p[j], l->p[i])));
    /* A depth step of many pixels is no more a discontinuity than a right-angle crease: cap at k. */
    return fminf(k * nd + (pixel > 0.0f ? off / pixel : 0.0f), k);
}

static float value_disc(const level *l, size_t i, size_t j, int lev, float k)
{
    (void)lev;
    (void)k;
    float a = l->val[i], b = l->val[j];
    float m = fmaxf(fmaxf(a, b), 1e-6f);
    return fabsf(a - b) / m;
}

typedef struct disc_job {
    const level *L;
    int lev, first_row;
    disc_fn disc;
    float k;
    float *d;              /* the level's texels: the largest discontinuity to a valid 4-neighbour */
} disc_job;

/* One row of a level's discontinuities. */
static void disc_row(void *p, int64_t row, int thread)
{
    (void)thread;
    const disc_job *j = p;
    const level *L = j->L;
    const int ly = j->first_row + (int)row;
    const int nx[4] = {-1, 1, 0, 0}, ny[4] = {0, 0, -1, 1};
    for (int lx = 0; lx < L->w; ++lx) {
        size_t i = (size_t)ly * L->w + lx;
        float d = 0.0f;
        if (L->valid[i]) {
            for (int q = 0; q < 4; ++q) {
                int ax = lx + nx[q], ay = ly + ny[q];
                if (ax < 0 || ay < 0 || ax >= L->w || ay >= L->h)
                    continue;
                size_t jj = (size_t)ay * L->w + ax;
                if (L->valid[jj])
                    d = fmaxf(d, j->disc(L, i, jj, j->lev, j->k));
            }
        }
        j->d[i] = d;
    }
}

typedef struct blend_job {
    const ic_gbuffer *g;
    const level *lv;
    float *const *d;       /* each level's discontinuities */
    int nlev, first_row;
    float *need;
} blend_job;

/* One row of the blend of the up-scaled levels (nearest up-scaling). A discontinuity found at level l
 * lies within about 2^l pixels, so level l is weighted 2^-l: near an edge the need is high and asks for
 * the finest spacing, and it decays with the distance to the edge rather than flooding the whole 32×32
 * block that a coarse level's texel covers. Each pixel adds its levels in order, whatever the row's
 * thread. */
static void blend_row(void *p, int64_t row, int thread)
{
    (void)thread;
    const blend_job *j = p;
    const ic_gbuffer *g = j->g;
    const int y = j->first_row + (int)row;
    for (int x = 0; x < g->width; ++x) {
        size_t o = (size_t)y * g->width + x;
        j->need[o] = 0.0f;
        if (!g->valid[o])
            continue;
        for (int l = 0; l < j->nlev; ++l) {
            const level *L = &j->lv[l];
            size_t i = (size_t)(y >> l) * L->w + (size_t)(x >> l);
            if (L->valid[i])
                j->need[o] += j->d[l][i] / (float)(1 << l);
        }
    }
}

/* Rows [y0, y1) of the need map; each level's discontinuities only on the rows those read. */
static ic_result need_map(const ic_gbuffer *g, const float *values, disc_fn disc, float k, int threads, int y0, int y1,
                          float *need)
{
    if (y0 < 0 || y1 > g->height || y0 >= y1)
        return y0 == y1 ? IC_OK : IC_ERR_INVALID_ARG;
    const int geometry = values == NULL;
    level lv[IC_SCREEN_LEVELS];
    float *d[IC_SCREEN_LEVELS] = {0};
    memset(lv, 0, sizeof lv);
    /* Level 0 reads the g-buffer and the values where they are (const: never written below). */
    level top = {g->width, g->height, g->p, g->n, g->footprint, (float *)values, g->valid};
    lv[0] = top;
    int nlev = 1;
    ic_result r = IC_OK;
    while (nlev < IC_SCREEN_LEVELS && lv[nlev - 1].w > 1 && lv[nlev - 1].h > 1) {
        if (!level_alloc(&lv[nlev], (lv[nlev - 1].w + 1) / 2, (lv[nlev - 1].h + 1) / 2, geometry)) {
            r = IC_ERR_OOM;
            goto done;
        }
        ++nlev;
    }
    /* The rows of each level that rows [y0, y1) read: its discontinuities' rows and their 4-neighbours, and
     * the rows the next level is made of; only those are made (under several processes a process's rows are a
     * small part of the image). */
    int lo[IC_SCREEN_LEVELS], hi[IC_SCREEN_LEVELS];
    for (int l = nlev - 1; l >= 1; --l) {
        lo[l] = (y0 >> l) - 1 > 0 ? (y0 >> l) - 1 : 0;
        hi[l] = ((y1 - 1) >> l) + 1 < lv[l].h - 1 ? ((y1 - 1) >> l) + 1 : lv[l].h - 1;
        if (l + 1 < nlev) {
            lo[l] = 2 * lo[l + 1] < lo[l] ? 2 * lo[l + 1] : lo[l];
            hi[l] = 2 * hi[l + 1] + 1 > hi[l] ? (2 * hi[l + 1] + 1 < lv[l].h - 1 ? 2 * hi[l + 1] + 1 : lv[l].h - 1)
                                              : hi[l];
        }
    }
    for (int l = 1; l < nlev; ++l)
        downsample(&lv[l - 1], &lv[l], lo[l], hi[l]);
    /* Each level's discontinuities once per texel, then the blend reads them. */
    for (int l = 0; l < nlev && r == IC_OK; ++l) {
        d[l] = malloc(sizeof *d[l] * (size_t)lv[l].w * (size_t)lv[l].h);
        if (!d[l]) {
            r = IC_ERR_OOM;
            break;
        }
        const int first = y0 >> l, last = (y1 - 1) >> l;
        disc_job dj = {&lv[l], l, first, disc, k, d[l]};
        r = ic_parallel_for(threads, last - first + 1, disc_row, &dj);
    }
    if (r == IC_OK) {
        blend_job j = {g, lv, d, nlev, y0, need};
        r = ic_parallel_for(threads, y1 - y0, blend_row, &j);
    }
done:
    for (int l = 0; l < IC_SCREEN_LEVELS; ++l)
        free(d[l]);
    for (int l = 1; l < IC_SCREEN_LEVELS; ++l)
        level_free(&lv[l]);
    return r;
}

ic_result ic_screen_geometry_need(const ic_gbuffer *g, float k_normal, int threads, int y0, int y1, float *need)
{
    return need_map(g, NULL, geometry_disc, k_normal, threads, y0, y1, need);
}

ic_result ic_screen_value_need(const ic_gbuffer *g, const float *luminance, int threads, int y0, int y1, float *need)
{
    return need_map(g, luminance, value_disc, 0.0f, threads, y0, y1, need);
}

uint32_t ic_screen_dither(const ic_gbuffer *g, const float *need, float threshold, int y0, int y1, uint32_t *pixels)
{
    uint32_t count = 0;
    for (int y = y0 < 0 ? 0 : y0; y < y1 && y < g->height; ++y) {
        for (int x = 0; x < g->width; ++x) {
            size_t o = (size_t)y * g->width + x;
            if (!g->valid[o] || (x & 1) || (y & 1))
                continue;
            /* Coarsest of the nested grids {x % s == 0, y % s == 0}, s = 2..32, this pixel lies on. */
            int grid = 2;
            while (grid < 32 && x % (2 * grid) == 0 && y % (2 * grid) == 0)
                grid *= 2;
            /* Spacing this pixel's need asks for. */
            int want = 32;
            for (int i = 0; i < 4 && need[o] >= threshold * (float)(1 << i); ++i)
                want = 16 >> i;
            if (want <= grid)
                pixels[count++] = (uint32_t)o;
        }
    }
    return count;
}
