/*
 * ic_emitters.c — which large emitters the records carry instead of the final render's light sampling
 * (ic_ic_options.large_emitters), measured on the image's shading points.
 */
#include "ic_internal.h"

#include "core/sampling.h"

#include <stdlib.h>
#include <string.h>

/* Projected solid angle of triangle (a, b, c) seen from p above the plane with normal n, over π: the
 * share of p's cosine-weighted hemisphere it covers, unoccluded. The solid angle is Van Oosterom and
 * Strackee's (1983) closed form; the cosine is taken at the triangle's centroid (a small triangle's
 * exact value, a fair one for a large triangle seen from afar). */
static double hemisphere_share(ic_vec3 p, ic_vec3 n, ic_vec3 a, ic_vec3 b, ic_vec3 c)
{
    ic_vec3 ra = v3_sub(a, p), rb = v3_sub(b, p), rc = v3_sub(c, p);
    double la = v3_len(ra), lb = v3_len(rb), lc = v3_len(rc);
    double num = fabs((double)v3_dot(ra, v3_cross(rb, rc)));
    double den = la * lb * lc + v3_dot(ra, rb) * lc + v3_dot(ra, rc) * lb + v3_dot(rb, rc) * la;
    double omega = 2.0 * atan2(num, den);
    ic_vec3 d = v3_sub(v3_scale(v3_add(v3_add(a, b), c), 1.0f / 3.0f), p);
    double dl = v3_len(d), cos_r = dl > 0.0 ? v3_dot(d, n) / dl : 0.0;
    return cos_r > 0.0 && isfinite(omega) ? omega * cos_r / IC_PI : 0.0;
}

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* Of the light samples a shading point would take on material m's emitting triangles (by area, from
 * every stride-th valid pixel's shading point, 8 each), the fraction no surface hides, among those
 * that face the point and that it faces; 1 when there are none, -1 when out of memory. */
static double visible_fraction(const ic_ctx *c, const ic_scene *s, uint32_t m, size_t stride)
{
    uint32_t count = 0;
    for (uint32_t li = 0; li < s->tri_light_count; ++li)
        count += s->triangle_material[s->tri_lights[li].triangle] == m;
    uint32_t *tri = malloc(sizeof *tri * (count ? count : 1));
    double *cdf = malloc(sizeof *cdf * (count + 1));
    if (!tri || !cdf) {
        free(tri);
        free(cdf);
        return -1.0;
    }
    cdf[0] = 0.0;
    for (uint32_t li = 0, k = 0; li < s->tri_light_count; ++li)
        if (s->triangle_material[s->tri_lights[li].triangle] == m) {
            tri[k] = li;
            cdf[k + 1] = cdf[k] + s->tri_lights[li].area;
            ++k;
        }
    size_t npix = (size_t)c->g.width * c->g.height, seen = 0, open = 0;
    for (size_t i = 0, k = 0; i < npix && count; ++i) {
        if (!c->g.valid[i] || k++ % stride)
            continue;
        ic_rng rng = ic_rng_make(c->seed, 0x6c61726765ULL, i, 0);
        for (int j = 0; j < 8; ++j) {
            /* A triangle by area: the last cdf entry below u. */
            double u = ic_rng_double(&rng) * cdf[count];
            uint32_t lo = 0, hi = count - 1;
            while (lo < hi) {
                uint32_t mid = (lo + hi + 1) / 2;
                if (cdf[mid] <= u)
                    lo = mid;
                else
                    hi = mid - 1;
            }
            const ic_tri_light *l = &s->tri_lights[tri[lo]];
            float b1, b2;
            ic_warp_triangle(ic_rng_float(&rng), ic_rng_float(&rng), &b1, &b2);
            const uint32_t *v = &s->triangles[3 * l->triangle];
            ic_vec3 x = v3_add(v3_add(v3_scale(s->positions[v[0]], 1.0f - b1 - b2), v3_scale(s->positions[v[1]], b1)),
                               v3_scale(s->positions[v[2]], b2));
            ic_vec3 d = v3_sub(x, c->g.p[i]);
            float dist = v3_len(d);
            if (!(dist > 0.0f))
                continue;
            d = v3_scale(d, 1.0f / dist);
            if (v3_dot(d, c->g.n[i]) <= 0.0f || (!l->two_sided && v3_dot(d, l->normal) >= 0.0f))
                continue;
            ic_ray r = {ic_offset_ray_origin(c->g.p[i], c->g.n[i], d), d, 0.0f, dist * (1.0f - 1e-3f)};
            ++seen;
            open += !ic_accel_occluded1(c->tr->accel, &r);
        }
    }
    free(tri);
    free(cdf);
    return seen ? (double)open / (double)seen : 1.0;
}

/* Large emitters. Seed 004 §3 caches all indirect light, and renderers built on a cache leave the sky
 * to the records; this extends that to an emitting material that is large and partly hidden: one that
 * covers, at the median shading point of the image, at least large_emitters of the cosine-weighted
 * hemisphere (hemisphere_share, unoccluded) and of whose light samples at most
 * IC_LARGE_EMITTER_VISIBLE reach it (visible_fraction). Such an emitter — staircase2's window quads —
 * is where light sampling is at its worst (most samples land on hidden parts, and each visible one
 * carries a large weight), while its irradiance varies slowly (a source that large casts soft
 * shadows), which is what the cache interpolates well. It is then not light-sampled in the final
 * render; the hemisphere rays count its emission instead, so the records carry its direct light, as
 * they carry the environment's. A lamp like the Cornell box's (0.6 % of the hemisphere, 90 % of its
 * samples visible) keeps being sampled: the cache would blur its sharper shadows. Fills
 * direct_pmf/direct_cdf and narrows light_sel to the emitters left; returns 0 when out of memory. */
/* Marks in cached_mat[m] (zeroed, material_count entries) each emitting material the records carry:
 * the median over sampled shading points of its hemisphere share reaches large_emitters and at most
 * IC_LARGE_EMITTER_VISIBLE of its light samples are unblocked. Returns 0 when out of memory. */
static int choose_materials(const ic_ctx *c, const ic_scene *s, size_t valid, uint8_t *cached_mat)
{
    size_t npix = (size_t)c->g.width * c->g.height;
    /* At most ~1024 shading points, evenly through the image, and fewer where there are so many
     * emitting triangles that points × triangles would pass 2^23 (at least ~64 points). */
    size_t want = ((size_t)1 << 23) / s->tri_light_count;
    want = want < 64 ? 64 : want > 1024 ? 1024 : want;
    size_t stride = valid / want + 1, points = 0, cap = valid / stride + 1; /* cap: sampled points, at most */
    /* Shares per emitting material (slot[m]: its row, UINT32_MAX for the others) and sampled point. */
    uint32_t nm = s->material_count, ne = 0;
    uint32_t *slot = malloc(sizeof *slot * (nm ? nm : 1));
    double *row = malloc(sizeof *row * cap), *share = NULL;
    if (slot) {
        for (uint32_t m = 0; m < nm; ++m)
            slot[m] = v3_is_black(s->materials[m].emission) ? UINT32_MAX : ne++;
        share = calloc((size_t)(ne ? ne : 1) * cap, sizeof *share);
    }
    int ok = slot && share && row;
    for (size_t i = 0, k = 0; ok && i < npix; ++i) {
        if (!c->g.valid[i] || k++ % stride)
            continue;
        ic_vec3 p = c->g.p[i], n = c->g.n[i];
        for (uint32_t li = 0; li < s->tri_light_count; ++li) {
            const ic_tri_light *l = &s->tri_lights[li];
            uint32_t t = l->triangle;
            /* Only the emitting side counts. */
            if (!l->two_sided && v3_dot(l->normal, v3_sub(p, l->centroid)) <= 0.0f)
                continue;
            share[(size_t)slot[s->triangle_material[t]] * cap + points] +=
                hemisphere_share(p, n, s->positions[s->triangles[3 * t]], s->positions[s->triangles[3 * t + 1]],
                                 s->positions[s->triangles[3 * t + 2]]);
        }
        ++points;
    }
    for (uint32_t m = 0; ok && m < nm; ++m) {
        if (slot[m] == UINT32_MAX)
            continue;
        memcpy(row, &share[(size_t)slot[m] * cap], sizeof *row * points);
        qsort(row, points, sizeof *row, cmp_double);
        double v = row[points / 2] >= c->o.large_emitters.value ? visible_fraction(c, s, m, stride) : 1.0;
        ok = v >= 0.0;
        cached_mat[m] = ok && v <= IC_LARGE_EMITTER_VISIBLE;
    }
    free(slot);
    free(share);
    free(row);
    return ok;
}

/* The final render's distribution over the emitting triangles left to sample (direct_pmf/direct_cdf),
 * and light_sel narrowed to them. Returns 0 when out of memory. */
static int narrow_light_selection(ic_ctx *c, const ic_scene *s, const uint8_t *cached_mat, double kept)
{
    c->direct_pmf = malloc(sizeof *c->direct_pmf * s->tri_light_count);
    c->direct_cdf = malloc(sizeof *c->direct_cdf * (s->tri_light_count + 1));
    if (!c->direct_pmf || !c->direct_cdf)
        return 0;
    double sum = 0.0;
    c->direct_cdf[0] = 0.0f;
    for (uint32_t i = 0; i < s->tri_light_count; ++i) {
        int big = cached_mat[s->triangle_material[s->tri_lights[i].triangle]];
        c->direct_pmf[i] = big || !(kept > 0.0) ? 0.0f : (float)(s->tri_lights[i].power / kept);
        sum += c->direct_pmf[i];
        c->direct_cdf[i + 1] = (float)sum;
    }
    if (kept > 0.0)
        c->direct_cdf[s->tri_light_count] = 1.0f;
    /* The class probabilities follow the power left to sample. */
    double tri = c->light_sel.tri * kept / s->tri_light_power, point = c->light_sel.point;
    c->light_sel.tri = tri + point > 0.0 ? (float)(tri / (tri + point)) : 0.0f;
    c->light_sel.point = tri + point > 0.0 ? (float)(point / (tri + point)) : 0.0f;
    c->light_sel.tri_pmf = kept > 0.0 ? c->direct_pmf : NULL;
    c->light_sel.tri_cdf = kept > 0.0 ? c->direct_cdf : NULL;
    return 1;
}

int ic_ic_select_large_emitters(ic_ctx *c, const ic_scene *s)
{
    if (c->o.large_emitters.mode == IC_CACHE_OFF || s->tri_light_count == 0 || !(s->tri_light_power > 0.0f))
        return 1;
    size_t npix = (size_t)c->g.width * c->g.height, valid = 0;
    for (size_t i = 0; i < npix; ++i)
        valid += c->g.valid[i];
    if (valid == 0)
        return 1;
    uint8_t *cached_mat = calloc(s->material_count ? s->material_count : 1, 1);
    if (!cached_mat || !choose_materials(c, s, valid, cached_mat)) {
        free(cached_mat);
        return 0;
    }
    uint32_t cached = 0;
    double kept = 0.0;
    for (uint32_t i = 0; i < s->tri_light_count; ++i) {
        if (cached_mat[s->triangle_material[s->tri_lights[i].triangle]])
            ++cached;
        else
            kept += s->tri_lights[i].power;
    }
    int ok = cached == 0 || narrow_light_selection(c, s, cached_mat, kept);
    if (ok)
        c->cached_emitters = cached;
    free(cached_mat);
    return ok;
}
