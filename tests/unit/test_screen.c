/*
 * test_screen.c — the batch strategy's screen stage and world-stage selection (Frolov et al. 2012 §3.1)
 * against plain re-statements of their definitions:
 *   1. need maps (geometry and value discontinuity): every pixel equal, bit for bit, to a direct
 *      evaluation of the definition (a 2×2 mip pyramid of the valid pixels, at each level the largest
 *      discontinuity to a valid 4-neighbour, the levels' values at the pixel added with weight 2^-l in
 *      level order), on a g-buffer with holes and odd sizes, with 1 and 3 threads; a block of rows reads
 *      values IC_SCREEN_HALO rows away and no farther;
 *   2. world-stage selection keeps candidates in (Morton code, key) order: with clusters of one candidate
 *      each, the output is the input sorted by a comparison sort, keys using all 64 bits and many
 *      candidates sharing a Morton code;
 *   3. dithering: the chosen pixels are those of the definition (a valid pixel on the coarsest grid of
 *      spacing s ∈ {2, …, 32} it lies on is chosen when its need asks for spacing ≤ s), in raster order,
 *      and blocks of rows dithered apart and put end to end (as several processes do) give the same list.
 */
#include "test_util.h"

#include "core/rng.h"
#include "core/vecmath.h"
#include "integrators/ic_screen.h"
#include "integrators/ic_world.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define W 75
#define H 43
#define LEVELS 6

/* ---- 1. need maps, by the definition ------------------------------------------------------------- */

typedef struct ref_level {
    int w, h;
    ic_vec3 p[W * H], n[W * H];
    float fp[W * H], val[W * H];
    uint8_t valid[W * H];
} ref_level;

static float ref_disc(const ref_level *L, size_t i, size_t j, int lev, float k, int geometry)
{
    if (!geometry) {
        float a = L->val[i], b = L->val[j];
        return fabsf(a - b) / fmaxf(fmaxf(a, b), 1e-6f);
    }
    float nd = 1.0f - ic_clampf(v3_dot(L->n[i], L->n[j]), -1.0f, 1.0f);
    float pixel = L->fp[i] * (float)(1 << lev);
    float off = fabsf(v3_dot(L->n[i], v3_sub(L->p[j], L->p[i])));
    return fminf(k * nd + (pixel > 0.0f ? off / pixel : 0.0f), k);
}

static void ref_need(const ic_gbuffer *g, const float *values, float k, float *need)
{
    static ref_level lv[LEVELS];
    const int geometry = values == NULL;
    memset(lv, 0, sizeof lv);
    lv[0].w = g->width, lv[0].h = g->height;
    for (int i = 0; i < g->width * g->height; ++i) {
        lv[0].p[i] = g->p[i], lv[0].n[i] = g->n[i], lv[0].fp[i] = g->footprint[i];
        lv[0].val[i] = values ? values[i] : 0.0f, lv[0].valid[i] = g->valid[i];
    }
    int nlev = 1;
    while (nlev < LEVELS && lv[nlev - 1].w > 1 && lv[nlev - 1].h > 1) {
        ref_level *a = &lv[nlev - 1], *b = &lv[nlev];
        b->w = (a->w + 1) / 2, b->h = (a->h + 1) / 2;
        for (int y = 0; y < b->h; ++y)
            for (int x = 0; x < b->w; ++x) {
                ic_vec3 p = v3s(0), n = v3s(0);
                float fp = 0, val = 0;
                int cnt = 0;
                for (int dy = 0; dy < 2; ++dy)
                    for (int dx = 0; dx < 2; ++dx) {
                        int sx = 2 * x + dx, sy = 2 * y + dy;
                        if (sx >= a->w || sy >= a->h || !a->valid[sy * a->w + sx])
                            continue;
                        int i = sy * a->w + sx;
                        p = v3_add(p, a->p[i]), n = v3_add(n, a->n[i]);
                        fp += a->fp[i], val += a->val[i];
                        ++cnt;
                    }
                int o = y * b->w + x;
                if (cnt) {
                    float inv = 1.0f / (float)cnt;
                    b->p[o] = v3_scale(p, inv), b->n[o] = v3_norm(n);
                    b->fp[o] = fp * inv, b->val[o] = val * inv, b->valid[o] = 1;
                }
            }
        ++nlev;
    }
    for (int y = 0; y < g->height; ++y)
        for (int x = 0; x < g->width; ++x) {
            int o = y * g->width + x;
            need[o] = 0.0f;
            if (!g->valid[o])
                continue;
            for (int l = 0; l < nlev; ++l) {
                const ref_level *L = &lv[l];
                int lx = x >> l, ly = y >> l, i = ly * L->w + lx;
                if (!L->valid[i])
                    continue;
                float d = 0.0f;
                const int nx[4] = {-1, 1, 0, 0}, ny[4] = {0, 0, -1, 1};
                for (int q = 0; q < 4; ++q) {
                    int ax = lx + nx[q], ay = ly + ny[q];
                    if (ax >= 0 && ay >= 0 && ax < L->w && ay < L->h && L->valid[ay * L->w + ax])
                        d = fmaxf(d, ref_disc(L, (size_t)i, (size_t)(ay * L->w + ax), l, k, geometry));
                }
                need[o] += d / (float)(1 << l);
            }
        }
}

static void test_need_maps(void)
{
    static ic_vec3 p[W * H], n[W * H];
    static float fp[W * H], lum[W * H], got[W * H], want[W * H];
    static uint8_t valid[W * H];
    ic_rng rng = ic_rng_make(11, 0, 0, 0);
    /* Two walls meeting in a crease, a step in depth, noise, and holes (the sky, a window). */
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            int i = y * W + x;
            float z = x < 40 ? 2.0f : 2.0f + 0.05f * (float)(x - 40);
            if (y > 30)
                z += 0.7f;
            p[i] = v3(0.01f * (float)x, 0.01f * (float)y, z + 0.002f * ic_rng_float(&rng));
            n[i] = x < 40 ? v3(0, 0, 1) : v3_norm(v3(-0.6f, 0.1f * ic_rng_float(&rng), 0.8f));
            fp[i] = 0.01f * z;
            lum[i] = (x < 20 ? 0.2f : 1.0f) * (1.0f + 0.3f * ic_rng_float(&rng)) + (y == 7 ? 5.0f : 0.0f);
            valid[i] = !((x > 60 && y < 10) || (x + y) % 17 == 0);
        }
    ic_gbuffer g = {W, H, p, n, fp, valid};
    for (int kind = 0; kind < 2; ++kind) {
        const float *values = kind ? lum : NULL;
        ref_need(&g, values, 4.0f, want);
        for (int threads = 1; threads <= 3; threads += 2) {
            memset(got, 0xff, sizeof got);
            /* Threads 1: the whole map at once; threads 3: in blocks of rows, as several processes make
             * it (blocks of odd sizes, a level's texel rows shared by two blocks). */
            const int cuts[] = {0, 1, 6, 17, 18, 40, H};
            ic_result r = IC_OK;
            for (int b = 0; b < (threads == 1 ? 1 : 6) && r == IC_OK; ++b) {
                const int y0 = threads == 1 ? 0 : cuts[b], y1 = threads == 1 ? H : cuts[b + 1];
                r = kind ? ic_screen_value_need(&g, lum, threads, y0, y1, got)
                         : ic_screen_geometry_need(&g, 4.0f, threads, y0, y1, got);
            }
            CHECK(r == IC_OK, "%s need map: %s", kind ? "value" : "geometry", ic_result_name(r));
            int differ = 0, positive = 0;
            for (int i = 0; i < W * H; ++i) {
                differ += memcmp(&got[i], &want[i], sizeof got[i]) != 0;
                positive += want[i] > 0.0f;
            }
            CHECK(differ == 0, "%s need map, %d threads: %d of %d pixels differ from the definition",
                  kind ? "value" : "geometry", threads, differ, W * H);
            CHECK(positive > W * H / 10, "%s need map: only %d pixels see a discontinuity (the test scene "
                  "should show many)", kind ? "value" : "geometry", positive);
        }
    }
}

/* The value map of a block of rows reads IC_SCREEN_HALO rows of values on either side and no more, which
 * is what lets several processes exchange only that band: values outside it replaced by garbage leave the
 * block's map unchanged bit for bit. The block starts 31 rows past a 32-row boundary, where the coarsest
 * level reaches farthest, 63 rows: garbage from 62 rows away changes the map. */
static void test_halo(void)
{
    enum { W2 = 37, H2 = 320 };
    static ic_vec3 p[W2 * H2], n[W2 * H2];
    static float fp[W2 * H2], lum[W2 * H2], junk[W2 * H2], want[W2 * H2], got[W2 * H2];
    static uint8_t valid[W2 * H2];
    ic_rng rng = ic_rng_make(29, 0, 0, 0);
    for (int i = 0; i < W2 * H2; ++i) {
        int x = i % W2, y = i / W2;
        p[i] = v3(0.01f * (float)x, 0.01f * (float)y, 2.0f);
        n[i] = v3(0, 0, 1);
        fp[i] = 0.01f;
        lum[i] = 1.0f + ic_rng_float(&rng) + (y % 50 < 3 ? 4.0f : 0.0f);
        valid[i] = (x * 7 + y) % 23 != 0;
    }
    ic_gbuffer g = {W2, H2, p, n, fp, valid};
    const int y0 = 4 * 32 + 31, y1 = y0 + 45;
    ic_result r = ic_screen_value_need(&g, lum, 2, y0, y1, want);
    for (int reach = IC_SCREEN_HALO; r == IC_OK && reach >= IC_SCREEN_HALO - 2; reach -= 2) {
        /* Garbage on every row but [y0 − reach, y1 + reach). */
        for (int i = 0; i < W2 * H2; ++i) {
            int y = i / W2;
            junk[i] = y >= y0 - reach && y < y1 + reach ? lum[i] : 1e3f * ic_rng_float(&rng);
        }
        memset(got, 0, sizeof got);
        r = ic_screen_value_need(&g, junk, 2, y0, y1, got);
        int differ = 0;
        for (int i = y0 * W2; i < y1 * W2; ++i)
            differ += memcmp(&got[i], &want[i], sizeof got[i]) != 0;
        if (reach == IC_SCREEN_HALO)
            CHECK(differ == 0, "value need map of rows [%d, %d): %d pixels changed by values more than %d rows "
                  "away", y0, y1, differ, IC_SCREEN_HALO);
        else
            CHECK(differ > 0, "value need map of rows [%d, %d): values %d rows away changed nothing (the band "
                  "could be narrower than IC_SCREEN_HALO)", y0, y1, reach);
    }
    CHECK(r == IC_OK, "value need map: %s", ic_result_name(r));
    /* The geometry map likewise: positions, normals and footprints outside the band (which a process of
     * several does not compute) leave a block's map unchanged. */
    static ic_vec3 p2[W2 * H2], n2[W2 * H2];
    static float fp2[W2 * H2];
    for (int i = 0; i < W2 * H2; ++i) {
        int x = i % W2, y = i / W2;
        p[i] = v3(0.01f * (float)x, 0.01f * (float)y, 2.0f + (y % 40 < 20 ? 0.3f : 0.0f) + 0.001f * ic_rng_float(&rng));
        n[i] = v3_norm(v3(0.2f * ic_rng_float(&rng), x % 9 == 0 ? 0.5f : 0.0f, 1.0f));
    }
    r = ic_screen_geometry_need(&g, 4.0f, 2, y0, y1, want);
    for (int i = 0; i < W2 * H2; ++i) {
        int y = i / W2, in = y >= y0 - IC_SCREEN_HALO && y < y1 + IC_SCREEN_HALO;
        p2[i] = in ? p[i] : v3(ic_rng_float(&rng), 0.0f, 0.0f);
        n2[i] = in ? n[i] : v3(0.0f, 1.0f, 0.0f);
        fp2[i] = in ? fp[i] : 0.0f;
    }
    ic_gbuffer g2 = {W2, H2, p2, n2, fp2, valid};
    memset(got, 0, sizeof got);
    if (r == IC_OK)
        r = ic_screen_geometry_need(&g2, 4.0f, 2, y0, y1, got);
    int differ = 0, positive = 0;
    for (int i = y0 * W2; i < y1 * W2; ++i) {
        differ += memcmp(&got[i], &want[i], sizeof got[i]) != 0;
        positive += want[i] > 0.0f;
    }
    CHECK(r == IC_OK && differ == 0, "geometry need map of rows [%d, %d): %d pixels changed by points more than %d "
          "rows away", y0, y1, differ, IC_SCREEN_HALO);
    CHECK(positive > 0, "geometry need map of rows [%d, %d): no discontinuity (nothing tested)", y0, y1);
}

/* ---- 2. world-stage selection order ------------------------------------------------------------- */

typedef struct ref_entry {
    uint32_t morton;
    uint64_t key;
} ref_entry;

static int cmp_ref(const void *a, const void *b)
{
    const ref_entry *x = a, *y = b;
    if (x->morton != y->morton)
        return x->morton < y->morton ? -1 : 1;
    return (x->key > y->key) - (x->key < y->key);
}

static void test_world_order(void)
{
    enum { N = 3000 };
    static ic_candidate cand[N];
    static ref_entry want[N];
    ic_vec3 lo = v3(-1, -1, -1), hi = v3(1, 1, 1);
    ic_rng rng = ic_rng_make(5, 0, 0, 0);
    for (int i = 0; i < N; ++i) {
        /* A third on a coarse lattice (many share a Morton cell, told apart by the key alone), the rest
         * scattered; every position distinct, so each is a cluster of its own with max_box 0. */
        float jitter = 1e-6f * (float)(i + 1);
        ic_vec3 q = i % 3 == 0 ? v3(0.5f + jitter, -0.25f, 0.125f + jitter)
                               : v3(2 * ic_rng_float(&rng) - 1, 2 * ic_rng_float(&rng) - 1, 2 * ic_rng_float(&rng) - 1);
        cand[i].p = q;
        cand[i].n = v3(0, 0, 1);
        cand[i].footprint = 0.0f;
        /* every fifth key's high word 0: those are told apart by the low word alone */
        const uint64_t high = i % 5 ? (uint64_t)ic_rng_below(&rng, 0xffffffffu) << 32 : 0;
        cand[i].key = high ^ (uint64_t)i << 3 ^ (uint64_t)(i % 7);
        want[i].morton = ic_morton3(q, lo, hi);
        want[i].key = cand[i].key;
    }
    qsort(want, N, sizeof *want, cmp_ref);
    uint32_t kept = 0;
    CHECK(ic_world_select(cand, N, lo, hi, 0.0f, N, 30.0f, &kept) == IC_OK, "world select ran");
    CHECK(kept == N, "world select with one-candidate clusters kept %u of %d", kept, N);
    int wrong = 0;
    for (uint32_t i = 0; i < kept; ++i)
        wrong += cand[i].key != want[i].key || ic_morton3(cand[i].p, lo, hi) != want[i].morton;
    CHECK(wrong == 0, "world select: %d of %u candidates out of (Morton, key) order", wrong, kept);
}

/* ---- 3. dithering, by the definition --------------------------------------------------------------- */

static void test_dither(void)
{
    static ic_vec3 p[W * H], n[W * H];
    static float fp[W * H], need[W * H];
    static uint8_t valid[W * H];
    static uint32_t got[W * H], want[W * H], blocks[W * H];
    const float thr = 0.25f;
    ic_rng rng = ic_rng_make(17, 0, 0, 0);
    for (int i = 0; i < W * H; ++i) {
        need[i] = 10.0f * thr * ic_rng_float(&rng) * ic_rng_float(&rng);
        valid[i] = i % 13 != 0;
    }
    uint32_t m = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const int i = y * W + x;
            if (!valid[i] || x % 2 || y % 2)
                continue;
            int grid = 2;
            while (grid < 32 && x % (2 * grid) == 0 && y % (2 * grid) == 0)
                grid *= 2;
            const float v = need[i];
            const int asks = v >= 8 * thr ? 2 : v >= 4 * thr ? 4 : v >= 2 * thr ? 8 : v >= thr ? 16 : 32;
            if (asks <= grid)
                want[m++] = (uint32_t)i;
        }
    ic_gbuffer g = {W, H, p, n, fp, valid};
    uint32_t whole = ic_screen_dither(&g, need, thr, 0, H, got);
    int wrong = whole != m;
    for (uint32_t k = 0; k < m && !wrong; ++k)
        wrong = got[k] != want[k];
    CHECK(!wrong, "dithering chose %u pixels, the definition %u (or another list)", whole, m);
    CHECK(m > 40 && m < (uint32_t)(W * H / 4), "dithering test: %u chosen pixels (the need should choose some)", m);
    /* Blocks of odd sizes, and empty ones (more processes than rows), one of them past the last row. */
    const int cuts[] = {0, 1, 6, 17, 17, 18, 40, H, H};
    uint32_t at = 0;
    for (size_t b = 0; b + 1 < sizeof cuts / sizeof cuts[0]; ++b)
        at += ic_screen_dither(&g, need, thr, cuts[b], cuts[b + 1], blocks + at);
    CHECK(at == m && memcmp(blocks, want, sizeof *want * m) == 0,
          "dithering in blocks of rows: %u pixels against %u, or another list", at, m);
}

int main(void)
{
    test_need_maps();
    test_halo();
    test_world_order();
    test_dither();
    TEST_MAIN_END();
}
