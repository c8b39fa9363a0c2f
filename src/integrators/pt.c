/*
 * pt.c — unidirectional path tracing with next-event estimation and MIS (Veach 1997, ch. 9: power
 * heuristic, one light sample and one BSDF sample per vertex), Russian roulette on throughput.
 */
#include "pt.h"

#include "core/sampling.h"

#include <stdlib.h>
#include <string.h>

ic_pt_params ic_pt_params_resolve(ic_pt_params p)
{
    if (p.max_depth <= 0)
        p.max_depth = 8;
    if (p.rr_depth <= 0)
        p.rr_depth = 3;
    return p;
}

/* One light sample at s by sel, reflected towards wo by b's non-delta lobes (glossy_only: by its glossy
 * lobe alone) and MIS-weighted against sampling what it reflects by. */
static ic_vec3 light_sample(const ic_tracer *tr, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo,
                            const ic_light_selection *sel, int glossy_only, ic_rng *rng, uint64_t *rays)
{
    float u0 = ic_rng_1d(rng), u1, u2;
    ic_rng_2d(rng, &u1, &u2);
    if (!ic_bsdf_has_smooth(b))
        return v3s(0.0f);
    ic_light_sample ls;
    if (!ic_scene_sample_light_sel(tr->scene, sel, s->p, u0, u1, u2, &ls) || ls.pdf <= 0.0f)
        return v3s(0.0f);
    ic_vec3 f, fd;
    if (glossy_only)
        ic_bsdf_eval_lobes(b, wo, ls.wi, &fd, &f);
    else
        f = ic_bsdf_eval(b, wo, ls.wi);
    if (v3_is_black(f) || v3_is_black(ls.radiance))
        return v3s(0.0f);
    ic_ray shadow = ic_shadow_ray(s, &ls);
    ++*rays;
    if (ic_accel_occluded1(tr->accel, &shadow))
        return v3s(0.0f);
    float cos_i = fabsf(v3_dot(ls.wi, b->frame.n));
    float pdf_b = glossy_only ? ic_bsdf_pdf_glossy(b, wo, ls.wi) : ic_bsdf_pdf(b, wo, ls.wi);
    float w = ls.is_delta ? 1.0f : ic_power_heuristic(ls.pdf, pdf_b);
    return v3_scale(v3_mul(f, ls.radiance), cos_i * w / ls.pdf);
}

ic_vec3 ic_direct_light(const ic_tracer *tr, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo,
                        const ic_light_selection *sel, ic_rng *rng, uint64_t *rays)
{
    return light_sample(tr, s, b, wo, sel, 0, rng, rays);
}

ic_vec3 ic_direct_light_glossy(const ic_tracer *tr, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo,
                               const ic_light_selection *sel, ic_rng *rng, uint64_t *rays)
{
    return light_sample(tr, s, b, wo, sel, 1, rng, rays);
}

/* Light arriving along an escaping ray, times the path throughput beta: the environment and the sun's
 * disc, each weighted against the light sampling that could have picked it (bsdf_pdf: the BSDF sample's
 * pdf; 0 for a camera ray or a delta lobe, which light sampling cannot reproduce: full weight). */
static ic_vec3 escaped_light(const ic_scene *scene, ic_vec3 org, ic_vec3 dir, ic_vec3 beta, float bsdf_pdf,
                             const ic_light_selection *sel)
{
    ic_vec3 c = v3s(0.0f), env = ic_scene_env_radiance(scene, dir), sun = ic_scene_sun_radiance(scene, dir);
    if (!v3_is_black(env)) {
        float w = bsdf_pdf > 0.0f ? ic_power_heuristic(bsdf_pdf, ic_scene_light_pdf_env_at(scene, org, dir)) : 1.0f;
        c = v3_scale(v3_mul(beta, env), w);
    }
    if (!v3_is_black(sun)) {
        float w = bsdf_pdf > 0.0f ? ic_power_heuristic(bsdf_pdf, ic_scene_light_pdf_sun(scene, sel, dir)) : 1.0f;
        c = v3_add(c, v3_scale(v3_mul(beta, sun), w));
    }
    return c;
}

ic_vec3 ic_pt_li_from(const ic_tracer *tr, ic_ray ray, const ic_path_start *st, ic_rng *rng, uint64_t *rays)
{
    return ic_pt_li_hit(tr, ray, NULL, st, rng, rays);
}

ic_vec3 ic_pt_li_hit(const ic_tracer *tr, ic_ray ray, const ic_hit *first_hit, const ic_path_start *st, ic_rng *rng,
                     uint64_t *rays)
{
    const ic_scene *scene = tr->scene;
    ic_vec3 L = v3s(0.0f), beta = v3s(1.0f);
    /* The vertex's light selection, and the previous vertex's (the MIS weight of emission found by
     * the BSDF sample uses the pdf with which that vertex would have sampled the light). */
    const ic_light_selection *sel = st->first_sel ? st->first_sel : &scene->light_select, *prev_sel = sel;
    float prev_pdf = st->pdf;
    int prev_specular = st->is_specular;
    int skip_emission = st->skip_first_emission;
    ic_vec3 prev_p = ray.org;
    ic_vec3 *levels = st->levels;
    const ic_surface *given_s = first_hit ? st->first_surface : NULL;
    const ic_bsdf *given_b = given_s ? st->first_bsdf : NULL;
    for (int depth = st->depth;; ++depth) {
        ic_hit hit;
        if (first_hit) {
            hit = *first_hit;
            first_hit = NULL;
        } else {
            ++*rays;
            ic_accel_intersect1(tr->accel, &ray, &hit);
        }
        if (hit.triangle == IC_NO_HIT) {
            int mis = !prev_specular && prev_pdf > 0.0f;
            ic_vec3 c = escaped_light(scene, ray.org, ray.dir, beta, mis ? prev_pdf : 0.0f, prev_sel);
            if (!v3_is_black(c)) {
                L = v3_add(L, c);
                if (levels)
                    levels[depth - st->depth] = v3_add(levels[depth - st->depth], c);
            }
            break;
        }
        ic_surface s;
        if (given_s)
            s = *given_s;
        else
            ic_scene_surface(scene, hit.triangle, hit.u, hit.v, &s);
        given_s = NULL;
        ic_vec3 wo = v3_neg(ray.dir);
        ic_vec3 le = skip_emission ? v3s(0.0f) : ic_scene_emission(scene, &s, wo);
        skip_emission = 0;
        if (!v3_is_black(le)) {
            float w = 1.0f;
            if (!prev_specular && prev_pdf > 0.0f)
                w = ic_power_heuristic(prev_pdf, ic_scene_light_pdf_triangle_sel(scene, prev_sel, prev_p, hit.triangle,
                                                                                  ray.dir, hit.t));
            ic_vec3 c = v3_scale(v3_mul(beta, le), w);
            L = v3_add(L, c);
            if (levels)
                levels[depth - st->depth] = v3_add(levels[depth - st->depth], c);
        }
        if (depth >= tr->pt.max_depth)
            break;
        ic_bsdf b;
        if (given_b)
            b = *given_b;
        else
            ic_bsdf_init(&b, scene, &s, wo);
        given_b = NULL;
        const int remaining = tr->pt.max_depth - depth;
        if (st->cached && (depth > st->depth || st->cached_at_first) && remaining <= IC_PT_CACHED_MAX) {
            ic_vec3 inc[IC_PT_CACHED_MAX + 1];
            if (st->cached(st->cached_user, &s, &b, wo, remaining, rng, rays, inc)) {
                for (int j = 1; j <= remaining; ++j) {
                    ic_vec3 c = v3_mul(beta, inc[j]);
                    L = v3_add(L, c);
                    if (levels)
                        levels[depth - st->depth + j] = v3_add(levels[depth - st->depth + j], c);
                }
                break;
            }
        }
        ic_vec3 direct = v3_mul(beta, ic_direct_light(tr, &s, &b, wo, sel, rng, rays));
        L = v3_add(L, direct);
        if (levels)
            levels[depth - st->depth + 1] = v3_add(levels[depth - st->depth + 1], direct);
        prev_sel = sel;
        sel = &scene->light_select;
        ic_bsdf_sample bs;
        float u0 = ic_rng_1d(rng), u1, u2;
        ic_rng_2d(rng, &u1, &u2);
        if (!ic_bsdf_sample_dir(&b, wo, u0, u1, u2, &bs))
            break;
        beta = v3_mul(beta, bs.weight);
        prev_pdf = bs.pdf;
        prev_specular = bs.is_specular;
        prev_p = s.p;
        if (!ic_russian_roulette(&beta, depth, tr->pt.rr_depth, rng))
            break;
        ray = ic_spawn_ray(&s, bs.wi);
    }
    return L;
}

ic_vec3 ic_pt_li(const ic_tracer *tr, ic_ray ray, const ic_light_selection *sel, ic_rng *rng, uint64_t *rays)
{
    ic_path_start st = {0, 0.0f, 1, 0, sel, NULL, NULL, NULL, NULL, NULL, 0};
    return ic_pt_li_from(tr, ray, &st, rng, rays);
}

ic_result ic_pixel_lights_init(ic_pixel_lights *pl, const ic_scene *scene, ic_light_selection base, int threads,
                               int width, int height)
{
    memset(pl, 0, sizeof *pl);
    pl->base = base;
    pl->threads = threads;
    pl->width = width;
    pl->height = height;
    if (scene->tri_light_count == 0 || scene->tri_light_count > IC_LOCAL_LIGHTS_MAX || !(base.tri > 0.0f) ||
        width <= 0 || height <= 0)
        return IC_OK;
    size_t per = 2 * (size_t)scene->tri_light_count + 1, slots = (size_t)threads * IC_LIGHT_SLOTS;
    pl->buf = malloc(sizeof *pl->buf * per * slots);
    pl->key = calloc(slots, sizeof *pl->key);
    pl->ok = calloc(slots, sizeof *pl->ok);
    if (!pl->buf || !pl->key || !pl->ok) {
        ic_pixel_lights_free(pl);
        return IC_ERR_OOM;
    }
    pl->count = scene->tri_light_count;
    return IC_OK;
}

void ic_pixel_lights_free(ic_pixel_lights *pl)
{
    free(pl->buf);
    free(pl->key);
    free(pl->ok);
    pl->buf = NULL;
    pl->key = NULL;
    pl->ok = NULL;
    pl->count = 0;
}

/* Block index and the slot it uses (the block's column within a row of 8 blocks). */
static uint32_t block_of(const ic_pixel_lights *pl, uint32_t pixel, uint32_t *slot)
{
    uint32_t x = pixel % (uint32_t)pl->width, y = pixel / (uint32_t)pl->width;
    uint32_t bx = x / IC_LIGHT_BLOCK, by = y / IC_LIGHT_BLOCK;
    uint32_t bw = ((uint32_t)pl->width + IC_LIGHT_BLOCK - 1) / IC_LIGHT_BLOCK;
    *slot = bx % IC_LIGHT_SLOTS;
    return by * bw + bx;
}

uint32_t ic_pixel_lights_anchor(const ic_pixel_lights *pl, uint32_t pixel)
{
    uint32_t x = pixel % (uint32_t)pl->width, y = pixel / (uint32_t)pl->width;
    uint32_t ax = x / IC_LIGHT_BLOCK * IC_LIGHT_BLOCK + IC_LIGHT_BLOCK / 2;
    uint32_t ay = y / IC_LIGHT_BLOCK * IC_LIGHT_BLOCK + IC_LIGHT_BLOCK / 2;
    if (ax >= (uint32_t)pl->width)
        ax = (uint32_t)pl->width - 1;
    if (ay >= (uint32_t)pl->height)
        ay = (uint32_t)pl->height - 1;
    return ay * (uint32_t)pl->width + ax;
}

void ic_pixel_lights_forget(const ic_pixel_lights *pl, int thread)
{
    if (pl->count && thread >= 0 && thread < pl->threads)
        memset(pl->key + (size_t)thread * IC_LIGHT_SLOTS, 0, sizeof *pl->key * IC_LIGHT_SLOTS);
}

int ic_pixel_lights_need_point(const ic_pixel_lights *pl, int thread, uint32_t pixel)
{
    if (!pl->count || thread < 0 || thread >= pl->threads)
        return 0;
    uint32_t slot, block = block_of(pl, pixel, &slot);
    return pl->key[(size_t)thread * IC_LIGHT_SLOTS + slot] != block + 1;
}

const ic_light_selection *ic_pixel_lights_get(const ic_pixel_lights *pl, const ic_scene *scene, int thread,
                                              uint32_t pixel, int have_point, ic_vec3 p, ic_vec3 n,
                                              ic_light_selection *out)
{
    if (!pl->count || thread < 0 || thread >= pl->threads)
        return NULL;
    uint32_t slot, block = block_of(pl, pixel, &slot);
    size_t k = (size_t)thread * IC_LIGHT_SLOTS + slot;
    float *pmf = pl->buf + (2 * (size_t)pl->count + 1) * k, *cdf = pmf + pl->count;
    if (pl->key[k] != block + 1) {
        pl->key[k] = block + 1;
        pl->ok[k] = (int8_t)(have_point && ic_scene_local_lights(scene, p, n, pl->base.tri_pmf, pmf, cdf));
    }
    if (!pl->ok[k])
        return NULL;
    *out = pl->base;
    out->tri_pmf = pmf;
    out->tri_cdf = cdf;
    return out;
}
