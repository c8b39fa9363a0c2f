/*
 * portals.c — sampling the environment through portals: parallelogram openings (windows) that the scene
 * declares, through which an interior sees its sky. A point uniform over the portals' total area seen
 * from p gives a direction whose solid-angle pdf is dist² / (A · |cos θ_q|) (θ_q at the portal), summed
 * over every portal the direction leaves through; directions through no portal have pdf 0 and are left
 * to other sampling (BSDF sampling under MIS). This is the portal idea of production renderers in its
 * plainest form, uniform sampling of the portals' area (the baseline Bitterli et al. 2015 compare their
 * environment-aware portal sampling against); its variance stays low wherever an opening is not seen
 * edge-on, but it ignores how the sky's radiance varies across the opening.
 * A portal's normal points into the interior: only points on that side of a portal see light through
 * it, and a point outside every portal (the ground in front of the house) samples the sky as if there
 * were no portals.
 */
#include "scene/scene_internal.h"

#include <math.h>
#include <stdlib.h>

/* p lies on the interior side of portal pt (its normal's). */
static int inside_of(const ic_portal *pt, ic_vec3 p)
{
    return v3_dot(v3_sub(p, pt->corner), pt->normal) > 0.0f;
}

/* The ray p + t·wi (t > 0) leaves through portal pt (p on its interior side): its distance, else 0. */
static float portal_hit(const ic_portal *pt, ic_vec3 p, ic_vec3 wi)
{
    float den = v3_dot(wi, pt->normal);
    if (!(den < -1e-12f) || !inside_of(pt, p))
        return 0.0f;
    float t = v3_dot(v3_sub(pt->corner, p), pt->normal) / den;
    if (!(t > 0.0f) || !isfinite(t))
        return 0.0f;
    ic_vec3 d = v3_sub(v3_madd(p, wi, t), pt->corner);
    /* d = a·edge1 + b·edge2: a and b from the cross products with the other edge, over the area. */
    float a = v3_dot(v3_cross(d, pt->edge2), pt->normal) / pt->area;
    float b = v3_dot(v3_cross(pt->edge1, d), pt->normal) / pt->area;
    return a >= 0.0f && a <= 1.0f && b >= 0.0f && b <= 1.0f ? t : 0.0f;
}

int ic_scene_portals_apply(const ic_scene *scene, ic_vec3 p)
{
    const ic_environment *env = &scene->env;
    for (uint32_t k = 0; k < env->portal_count; ++k)
        if (inside_of(&env->portals[k], p))
            return 1;
    return 0;
}

float ic_scene_portal_crossing(const ic_scene *scene, ic_vec3 p, ic_vec3 wi)
{
    const ic_environment *env = &scene->env;
    float nearest = INFINITY;
    for (uint32_t k = 0; k < env->portal_count; ++k) {
        float t = portal_hit(&env->portals[k], p, wi);
        if (t > 0.0f && t < nearest)
            nearest = t;
    }
    return nearest;
}

float ic_scene_portal_pdf(const ic_scene *scene, ic_vec3 p, ic_vec3 wi)
{
    const ic_environment *env = &scene->env;
    if (!env->portal_count || !(env->portal_area > 0.0f))
        return 0.0f;
    float pdf = 0.0f;
    for (uint32_t k = 0; k < env->portal_count; ++k) {
        const ic_portal *pt = &env->portals[k];
        float t = portal_hit(pt, p, wi);
        if (t > 0.0f)
            pdf += t * t / (env->portal_area * fabsf(v3_dot(wi, pt->normal)));
    }
    return isfinite(pdf) ? pdf : 0.0f;
}

int ic_scene_sample_portal(const ic_scene *scene, ic_vec3 p, float u0, float u1, float u2, ic_vec3 *wi, ic_vec3 *q,
                           float *pdf)
{
    const ic_environment *env = &scene->env;
    *pdf = 0.0f;
    if (!env->portal_count || !(env->portal_area > 0.0f))
        return 0;
    uint32_t k = 0;
    while (k + 1 < env->portal_count && u0 >= env->portal_cdf[k + 1])
        ++k;
    const ic_portal *pt = &env->portals[k];
    if (!inside_of(pt, p))
        return 0; /* a portal p is outside of: no light through it */
    *q = v3_madd(v3_madd(pt->corner, pt->edge1, u1), pt->edge2, u2);
    ic_vec3 d = v3_sub(*q, p);
    float dist = v3_len(d);
    if (!(dist > 0.0f))
        return 0;
    *wi = v3_scale(d, 1.0f / dist);
    if (!(fabsf(v3_dot(*wi, pt->normal)) > 1e-6f))
        return 0; /* the opening seen edge-on */
    *pdf = ic_scene_portal_pdf(scene, p, *wi);
    return *pdf > 0.0f && isfinite(*pdf);
}

ic_result ic_scene_build_portals(ic_scene *s, ic_error *err)
{
    ic_environment *env = &s->env;
    free(env->portal_cdf);
    env->portal_cdf = NULL;
    env->portal_area = 0.0f;
    if (!env->portal_count)
        return IC_OK;
    env->portal_cdf = malloc(sizeof(float) * (env->portal_count + 1));
    if (!env->portal_cdf)
        return ic_error_set(err, IC_ERR_OOM, "out of memory for the portals");
    double total = 0.0;
    env->portal_cdf[0] = 0.0f;
    for (uint32_t k = 0; k < env->portal_count; ++k) {
        total += env->portals[k].area;
        env->portal_cdf[k + 1] = (float)total;
    }
    for (uint32_t k = 1; k <= env->portal_count; ++k)
        env->portal_cdf[k] = (float)(env->portal_cdf[k] / total);
    env->portal_cdf[env->portal_count] = 1.0f;
    env->portal_area = (float)total;
    return IC_OK;
}

ic_result ic_scene_add_portal(ic_scene *s, const ic_vec3 corners[4], ic_error *err)
{
    ic_vec3 e1 = v3_sub(corners[1], corners[0]), e2 = v3_sub(corners[3], corners[0]);
    ic_vec3 c = v3_cross(e1, e2);
    float area = v3_len(c), scale = v3_len(e1) + v3_len(e2);
    if (!(area > 0.0f) || !isfinite(area) || !(area > 1e-6f * scale * scale))
        return ic_error_set(err, IC_ERR_INVALID_ARG,
                            "a portal's corners are degenerate (zero area or not finite); give its four corners "
                            "in order around it");
    ic_vec3 far = v3_add(corners[0], v3_add(e1, e2));
    if (v3_len(v3_sub(far, corners[2])) > 1e-3f * scale)
        return ic_error_set(err, IC_ERR_INVALID_ARG,
                            "a portal must be a parallelogram (a rectangle, usually) with its corners in order "
                            "around it: the third corner is %g away from where the other three put it",
                            (double)v3_len(v3_sub(far, corners[2])));
    ic_environment *env = &s->env;
    if (env->portal_count >= IC_MAX_PORTALS)
        return ic_error_set(err, IC_ERR_INVALID_ARG,
                            "more than %d portals: every light sample looks at each of them; cover "
                            "neighbouring windows with one portal",
                            IC_MAX_PORTALS);
    ic_portal *grown = realloc(env->portals, sizeof *grown * (env->portal_count + 1));
    if (!grown)
        return ic_error_set(err, IC_ERR_OOM, "out of memory for the portals");
    env->portals = grown;
    ic_portal *pt = &env->portals[env->portal_count++];
    pt->corner = corners[0];
    pt->edge1 = e1;
    pt->edge2 = e2;
    pt->normal = v3_scale(c, 1.0f / area);
    pt->area = area;
    return IC_OK;
}
