/*
 * ic_final.c — the final render's pixel sample: direct light by next-event estimation, indirect diffuse
 * from the cache (or one hemisphere ray where no record reaches), the first glossy lobe from radiance
 * records where they reach, other glossy and specular paths traced.
 */
#include "ic_internal.h"

#include "core/sampling.h"

/* The records' irradiance, keyed on the interpolated normal, turned to the mapped normal n by each
 * contribution's rotational gradient (Ward & Heckbert 1992 §3): E_i + (n_i × (n − n_c))·∇r E_i, the record's
 * value at n_c being E_i + (n_i × n_c)·∇r E_i. */
static ic_vec3 rotate_to_mapped(const ic_ctx *c, const ic_cache_contribution *contrib, uint32_t count, ic_vec3 n_c,
                                ic_vec3 n, ic_vec3 fallback)
{
    float acc[3] = {0.0f, 0.0f, 0.0f}, wsum = 0.0f;
    ic_vec3 dn = v3_sub(n, n_c);
    for (uint32_t i = 0; i < count; ++i) {
        ic_record r;
        if (ic_cache_get_record(c->cache, contrib[i].record, &r) != IC_OK)
            return fallback;
        ic_vec3 rot = v3_cross(r.normal, dn);
        const float v[3] = {contrib[i].value.x, contrib[i].value.y, contrib[i].value.z};
        for (int ch = 0; ch < 3; ++ch)
            acc[ch] += contrib[i].weight * fmaxf(v[ch] + v3_dot(rot, r.grad_rot[ch]), 0.0f);
        wsum += contrib[i].weight;
    }
    return wsum > 0.0f ? v3_scale(v3(acc[0], acc[1], acc[2]), 1.0f / wsum) : fallback;
}

/* Indirect diffuse irradiance at a camera path's vertex `depth`: the cache (final acceptance), or,
 * where no record reaches (points seen only through glossy paths, sub-pixel samples at silhouettes), one
 * cosine-distributed hemisphere ray that returns what a record's ray would: E ≈ π·L.
 *
 * The bounce count stays the path tracer's at every vertex, not only the first: a record holds the light
 * of B bounces after its point, right for a vertex seen directly; a vertex seen in a glossy reflection or
 * through glass (depth d) may take only B − d of them, the interpolation of the records' level T_{B−d}
 * (ic_ic_level_estimates). Taking the full value there added one bounce per glass or glossy vertex: +5 %
 * behind a glass panel of a white hall, where each bounce returns most of the light.
 *
 * A normal-mapped point looks the cache up with its interpolated normal (b->cache_n, which the records are
 * keyed on) and turns the value to the mapped normal (rotate_to_mapped; not where a deeper vertex takes a
 * bounce level, nor in a pile-up beyond LOOKUP_CAPACITY); its fallback ray is drawn about the mapped normal. */
static ic_vec3 cached_irradiance(const ic_ctx *c, const ic_surface *s, const ic_bsdf *b, int depth,
                                 ic_cache_hint *hint, ic_rng *rng, uint64_t *rays, int *from_cache)
{
    ic_cache_contribution contrib[LOOKUP_CAPACITY];
    ic_vec3 n = b->frame.n;
    ic_cache_lookup q = ic_cache_lookup_at(s->p, b->cache_n, IC_ACCEPT_FINAL);
    const int level = c->levels - depth;
    const int mapped = b->cache_n.x != n.x || b->cache_n.y != n.y || b->cache_n.z != n.z;
    if ((depth > 0 && c->levels) || mapped) {
        q.contributions = contrib;
        q.contribution_capacity = LOOKUP_CAPACITY;
    }
    ic_cache_estimate e;
    if (ic_cache_query_hinted(c->cache, &q, hint, &e)) {
        *from_cache = 1;
        ic_vec3 E;
        if (depth > 0 && c->levels &&
            ic_ic_level_estimates(c, contrib, e.contributions_written, level > 0 ? level : 0, 1, &E, NULL))
            return E;
        if (mapped && e.contributions_written == e.contributor_count)
            return rotate_to_mapped(c, contrib, e.contributions_written, b->cache_n, n, e.irradiance);
        return e.irradiance;
    }
    *from_cache = 0;
    ic_frame f = ic_frame_from_normal(n);
    ic_vec3 d = ic_frame_to_world(&f, ic_warp_cosine_hemisphere(ic_rng_float(rng), ic_rng_float(rng)));
    /* below the surface (about a mapped normal): the BSDF passes nothing */
    if (c->tr->scene->materials[s->material].normal_texture > 0 && v3_dot(d, b->ng) <= 0.0f)
        return v3s(0.0f);
    ic_ray ray = ic_spawn_ray(s, d);
    ic_hit hit;
    ++*rays;
    ic_accel_intersect1(c->tr->accel, &ray, &hit);
    if (hit.triangle == IC_NO_HIT)
        return v3_scale(ic_scene_env_radiance(c->tr->scene, d), IC_PI);
    ic_path_start st = {depth + 1, 0.0f, 1, 1, NULL, NULL, NULL, NULL, NULL, NULL, 0};
    ic_vec3 L = v3_add(ic_pt_li_hit(&c->gather_tr, ray, &hit, &st, rng, rays), ic_ic_cached_emission(c, &ray, &hit));
    return v3_scale(L, IC_PI);
}

/* One path from the camera: at each vertex with a smooth lobe, direct light plus kd/π·E from the cache,
 * then the glossy lobe's sample continues the path; delta lobes are followed. Kept as one function (84
 * lines): the MIS state carried from vertex to vertex (prev_glossy, prev_pdf, prev_p, prev_sel) reads
 * more clearly in one loop than spread over helpers that would have to pass it all back and forth. */
ic_vec3 ic_ic_final_sample(void *p, const ic_ray *camera_ray, uint32_t pixel, ic_rng *rng, int thread,
                            uint64_t *rays)
{
    const ic_final_ctx *fc = p;
    /* Hints change speed only, never a result (cache.h), so images stay thread-count independent. */
    ic_cache_hint *hint = thread >= 0 && thread < fc->hint_count ? &fc->hints[thread] : NULL;
    const ic_ctx *c = fc->c;
    const ic_scene *scene = c->tr->scene;
    ic_ray ray = *camera_ray;
    ic_vec3 L = v3s(0.0f), beta = v3s(1.0f);
    int prev_glossy = 0; /* 0: camera or delta lobe, emission counts fully */
    float prev_pdf = 0.0f;
    ic_vec3 prev_p = ray.org;
    /* The first shading point samples lights by the local distribution of the pixel's block (built at
     * the cache shading point of the block's centre pixel, a function of the block alone); later
     * vertices by power. */
    ic_light_selection local;
    const ic_light_selection *sel = NULL, *prev_sel = &c->light_sel;
    const int one_term = fc->indirect_only || fc->glossy_only; /* an AOV: one term of the first vertex */
    if (!one_term && fc->lights.count && pixel < (uint32_t)c->g.width * (uint32_t)c->g.height) {
        int have = 0;
        ic_vec3 ap = v3s(0.0f), an = v3s(0.0f);
        if (ic_pixel_lights_need_point(&fc->lights, thread, pixel))
            have = ic_ic_gbuffer_point(c, ic_pixel_lights_anchor(&fc->lights, pixel), &ap, &an, NULL);
        sel = ic_pixel_lights_get(&fc->lights, scene, thread, pixel, have, ap, an, &local);
    }
    if (!sel)
        sel = &c->light_sel;
    for (int depth = 0; depth <= c->tr->pt.max_depth; ++depth) {
        ic_hit hit;
        ++*rays;
        ic_accel_intersect1(c->tr->accel, &ray, &hit);
        if (hit.triangle == IC_NO_HIT) {
            /* The environment is never light-sampled in this integrator: full weight. The sun's disc is,
             * at every vertex (ic_direct.c): a glossy sample that finds it is weighted against that. */
            if (!one_term) {
                L = v3_add(L, v3_mul(beta, ic_scene_env_radiance(scene, ray.dir)));
                ic_vec3 sun = ic_scene_sun_radiance(scene, ray.dir);
                if (!v3_is_black(sun)) {
                    float w = prev_glossy ? ic_power_heuristic(prev_pdf, ic_scene_sun_disc_pdf(scene, ray.dir)) : 1.0f;
                    L = v3_add(L, v3_scale(v3_mul(beta, sun), w));
                }
            }
            break;
        }
        ic_surface s;
        ic_scene_surface(scene, hit.triangle, hit.u, hit.v, &s);
        ic_vec3 wo = v3_neg(ray.dir);
        ic_vec3 le = ic_scene_emission(scene, &s, wo);
        if (!v3_is_black(le) && !one_term) {
            float w = prev_glossy ? ic_power_heuristic(prev_pdf, ic_scene_light_pdf_triangle_sel(
                                                                     scene, prev_sel, prev_p, hit.triangle, ray.dir, hit.t))
                                  : 1.0f;
            L = v3_add(L, v3_scale(v3_mul(beta, le), w));
        }
        /* As the path tracer: the last vertex adds its emission only. */
        if (depth >= c->tr->pt.max_depth)
            break;
        ic_bsdf b;
        ic_bsdf_init(&b, scene, &s, wo);
        ic_bsdf_sample bs;
        if (!ic_bsdf_has_smooth(&b)) {
            float u0 = ic_rng_1d(rng), u1, u2;
            ic_rng_2d(rng, &u1, &u2);
            if (!ic_bsdf_sample_dir(&b, wo, u0, u1, u2, &bs))
                break;
            beta = v3_mul(beta, bs.weight);
            prev_glossy = 0;
        } else {
            int from_cache;
            ic_vec3 E = cached_irradiance(c, &s, &b, depth, hint, rng, rays, &from_cache);
            ic_vec3 indirect = v3_mul(v3_scale(b.kd, IC_INV_PI), E);
            if (fc->indirect_only)
                return v3_mul(beta, indirect);
            /* Radiance records serve the glossy lobe of the first vertex only: they hold every bounce
             * after their point, one too many behind a specular or glossy vertex. */
            ic_vec3 glossy = v3s(0.0f);
            int glossy_cached = depth == 0 && ic_bsdf_has_glossy(&b) &&
                                ic_ic_radiance_lookup(c, s.p, b.frame.n, s.material, wo, hint, &glossy);
            if (fc->glossy_only)
                return v3_mul(beta, glossy);
            /* Several light samples per shading point: with indirect light from the cache, the direct
             * light's noise is what is left, and shadow rays are the cheapest rays there are. */
            ic_vec3 direct = v3s(0.0f);
            const int glossy_mode = glossy_cached ? IC_GLOSSY_FULL : IC_GLOSSY_MIS;
            for (int k = 0; k < c->o.light_samples; ++k)
                direct = v3_add(direct, ic_ic_direct_light_lobes(c, &s, &b, wo, sel, glossy_mode, rng, rays));
            prev_sel = sel;
            sel = &c->light_sel;
            direct = v3_scale(direct, 1.0f / (float)c->o.light_samples);
            L = v3_add(L, v3_mul(beta, v3_add(v3_add(indirect, direct), glossy)));
            if (glossy_cached)
                break;
            float u1, u2;
            ic_rng_2d(rng, &u1, &u2);
            if (!ic_bsdf_has_glossy(&b) || !ic_bsdf_sample_glossy(&b, wo, u1, u2, &bs))
                break;
            beta = v3_mul(beta, bs.weight);
            prev_glossy = !bs.is_specular; /* a translucent sheet's straight transmission: no MIS */
            prev_pdf = bs.pdf;
        }
        prev_p = s.p;
        if (!ic_russian_roulette(&beta, depth, c->tr->pt.rr_depth, rng))
            break;
        ray = ic_spawn_ray(&s, bs.wi);
    }
    return L;
}
