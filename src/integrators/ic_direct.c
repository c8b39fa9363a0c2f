/*
 * ic_direct.c — direct light as the cache integrator estimates it (the final render, and the direct part
 * of what a hemisphere ray returns): the sun every time, one light sample by the selection, and emitting
 * triangles once more through the diffuse lobe (MIS); the environment is in the records. At a hemisphere
 * ray's hit that the records serve, the light sample alone, unless a large emitter whose light samples are
 * heavy-tailed is light-sampled (ic_ic_direct_light_at_hit).
 */
#include "ic_internal.h"

#include "core/sampling.h"

/* The glossy lobe's share of a light sample under glossy mode g (IC_GLOSSY_*, ic_internal.h): full weight, MIS
 * against the lobe's own sample (not for a delta light, which no BSDF sample finds), or none. */
static int glossy_share(int g, int is_delta)
{
    return g == IC_GLOSSY_MIS && is_delta ? IC_GLOSSY_FULL : g;
}

/* Shadow-tested contribution of one light sample; mis_diffuse: whether the diffuse lobe's share is
 * MIS-weighted against its cosine sample finding the light (ic_ic_direct_light); glossy: the glossy
 * lobe's share (IC_GLOSSY_*; the lobe's own sample is the final render's path, or the gather's). */
static ic_vec3 shade_light(const ic_ctx *c, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo, const ic_light_sample *ls,
                           int mis_diffuse, int glossy, uint64_t *rays)
{
    ic_vec3 fd, fg;
    ic_bsdf_eval_lobes(b, wo, ls->wi, &fd, &fg);
    float cos_pdf = fmaxf(v3_dot(ls->wi, b->frame.n), 0.0f) * IC_INV_PI;
    float wd = mis_diffuse ? ic_power_heuristic(ls->pdf, cos_pdf) : 1.0f;
    float wg = glossy == IC_GLOSSY_MIS    ? ic_power_heuristic(ls->pdf, ic_bsdf_pdf_glossy(b, wo, ls->wi))
               : glossy == IC_GLOSSY_NONE ? 0.0f
                                          : 1.0f;
    ic_vec3 f = v3_add(v3_scale(fd, wd), v3_scale(fg, wg));
    if (v3_is_black(f) || v3_is_black(ls->radiance))
        return v3s(0.0f);
    ic_ray shadow = ic_shadow_ray(s, ls);
    ++*rays;
    if (ic_accel_occluded1(c->tr->accel, &shadow))
        return v3s(0.0f);
    return v3_scale(v3_mul(f, ls->radiance), fabsf(v3_dot(ls->wi, b->frame.n)) / ls->pdf);
}

/* The diffuse lobe's half of the MIS pair for emitting triangles: a cosine-distributed ray that counts
 * the emission it finds, weighted against light sampling. Light sampling alone is noisy next to small
 * emitters (a close point sees a small light under a large solid angle, which the area pdf samples
 * poorly); the records exclude this emission, so nothing is counted twice. */
static ic_vec3 diffuse_emission_sample(const ic_ctx *c, const ic_light_selection *sel, const ic_surface *s,
                                       const ic_bsdf *b, ic_rng *rng, uint64_t *rays)
{
    float u1, u2;
    ic_rng_2d(rng, &u1, &u2);
    if (!(sel->tri > 0.0f) || v3_is_black(b->kd))
        return v3s(0.0f);
    ic_vec3 wi = ic_frame_to_world(&b->frame, ic_warp_cosine_hemisphere(u1, u2));
    float cos_i = v3_dot(wi, b->frame.n);
    if (cos_i <= 0.0f || v3_dot(wi, b->ng) <= 0.0f)
        return v3s(0.0f);
    ic_ray ray = ic_spawn_ray(s, wi);
    ic_hit hit;
    ++*rays;
    ic_accel_intersect1(c->tr->accel, &ray, &hit);
    if (hit.triangle == IC_NO_HIT || c->tr->scene->triangle_light[hit.triangle] < 0)
        return v3s(0.0f);
    ic_surface hs;
    ic_scene_surface(c->tr->scene, hit.triangle, hit.u, hit.v, &hs);
    ic_vec3 le = ic_scene_emission(c->tr->scene, &hs, v3_neg(wi));
    if (v3_is_black(le))
        return v3s(0.0f);
    float pl = ic_scene_light_pdf_triangle_sel(c->tr->scene, sel, s->p, hit.triangle, wi, hit.t);
    /* An emitter light sampling never picks is a large one: the records carry its light. */
    if (!(pl > 0.0f))
        return v3s(0.0f);
    /* f_d·cos/p_cos = kd (times the diffuse factor) for the cosine-sampled diffuse lobe. */
    return v3_scale(v3_mul(b->kd, le), ic_power_heuristic(cos_i * IC_INV_PI, pl) * ic_bsdf_diffuse_factor(b, cos_i));
}

/* Direct light for the final render. The environment is in the records and is not sampled here; the
 * sun, a single light, is taken every time (choosing it among the lights would only add noise): its
 * direction, or a point of its disc, whose glossy share is MIS-weighted against the final render's
 * glossy path finding the disc (ic_final.c; nothing else counts the sun: the records exclude it, so its
 * diffuse share has full weight); triangle and point lights are sampled once by power, and emitting
 * triangles once more through the diffuse lobe (MIS, power heuristic); the glossy lobe's BSDF sample is
 * the final render's path. */
ic_vec3 ic_ic_direct_light(const ic_ctx *c, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo,
                           const ic_light_selection *sel, ic_rng *rng, uint64_t *rays)
{
    return ic_ic_direct_light_lobes(c, s, b, wo, sel, IC_GLOSSY_MIS, rng, rays);
}

/* The sun (every time) and one light sample by the selection sel; weigh_diffuse: whether the light
 * sample's diffuse share is MIS-weighted against the diffuse lobe's cosine ray (diffuse_emission_sample),
 * glossy: how both glossy shares count (IC_GLOSSY_*). */
static ic_vec3 sun_and_light_sample(const ic_ctx *c, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo,
                                    const ic_light_selection *sel, int glossy, int weigh_diffuse, ic_rng *rng,
                                    uint64_t *rays)
{
    float u0 = ic_rng_1d(rng), u1, u2;
    ic_rng_2d(rng, &u1, &u2);
    ic_vec3 L = v3s(0.0f);
    const ic_scene *scene = c->tr->scene;
    if (scene->sun.enabled) {
        float v1 = 0.0f, v2 = 0.0f;
        if (scene->sun.angular_radius > 0.0f)
            ic_rng_2d(rng, &v1, &v2); /* drawn for a disc only: a directional sun's scenes keep their numbers */
        ic_light_sample sun;
        ic_scene_sample_sun(scene, v1, v2, &sun);
        L = shade_light(c, s, b, wo, &sun, 0, glossy_share(glossy, sun.is_delta), rays);
    }
    ic_light_sample ls;
    if (ic_scene_sample_light_sel(scene, sel, s->p, u0, u1, u2, &ls) && ls.pdf > 0.0f)
        L = v3_add(L, shade_light(c, s, b, wo, &ls, weigh_diffuse && !ls.is_delta, glossy_share(glossy, ls.is_delta),
                                  rays));
    return L;
}

ic_vec3 ic_ic_direct_light_lobes(const ic_ctx *c, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo,
                                 const ic_light_selection *sel, int glossy, ic_rng *rng, uint64_t *rays)
{
    if (!sel)
        sel = &c->light_sel;
    ic_vec3 L = sun_and_light_sample(c, s, b, wo, sel, glossy, 1, rng, rays);
    return v3_add(L, diffuse_emission_sample(c, sel, s, b, rng, rays));
}

ic_vec3 ic_ic_direct_light_at_hit(const ic_ctx *c, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo, int glossy,
                                  ic_rng *rng, uint64_t *rays)
{
    if (c->large_sampled)
        return ic_ic_direct_light_lobes(c, s, b, wo, &c->light_sel, glossy, rng, rays);
    return sun_and_light_sample(c, s, b, wo, &c->light_sel, glossy, 0, rng, rays);
}

ic_vec3 ic_ic_env_light(const ic_ctx *c, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo, ic_rng *rng,
                        uint64_t *rays)
{
    const ic_scene *scene = c->tr->scene;
    float u0 = ic_rng_1d(rng), u1, u2, v1, v2;
    ic_rng_2d(rng, &u1, &u2);
    ic_rng_2d(rng, &v1, &v2);
    if (!scene->env.enabled || v3_is_black(b->kd))
        return v3s(0.0f);
    ic_vec3 L = v3s(0.0f);
    /* The light sample: the environment as the only light (through the portals p is inside of). A
     * constant environment without portals has none: uniform over the sphere, it would only add noise
     * to the cosine ray, whose estimate of it varies with visibility alone. */
    const int sampled = scene->env.image.width > 0 || (scene->env.portal_count && ic_scene_portals_apply(scene, s->p));
    const ic_light_selection env_only = {0.0f, 0.0f, 0.0f, 1.0f, NULL, NULL};
    ic_light_sample ls;
    if (sampled && ic_scene_sample_light_sel(scene, &env_only, s->p, u0, u1, u2, &ls) && ls.pdf > 0.0f)
        L = shade_light(c, s, b, wo, &ls, 1, IC_GLOSSY_FULL, rays);
    /* The cosine-distributed ray: the environment where it escapes, weighted against the light sample
     * (directions through no portal have light pdf 0: the ray alone carries them, at full weight). */
    ic_vec3 wi = ic_frame_to_world(&b->frame, ic_warp_cosine_hemisphere(v1, v2));
    float cos_i = v3_dot(wi, b->frame.n);
    if (cos_i <= 0.0f || v3_dot(wi, b->ng) <= 0.0f)
        return L;
    ic_ray ray = ic_spawn_ray(s, wi);
    ic_hit hit;
    ++*rays;
    ic_accel_intersect1(c->tr->accel, &ray, &hit);
    if (hit.triangle != IC_NO_HIT)
        return L;
    float w = sampled ? ic_power_heuristic(cos_i * IC_INV_PI, ic_scene_env_pdf_at(scene, s->p, wi)) : 1.0f;
    return v3_add(L, v3_scale(v3_mul(b->kd, ic_scene_env_radiance(scene, wi)), w * ic_bsdf_diffuse_factor(b, cos_i)));
}
