/*
 * portals.c — sampling the environment through portals: parallelogram openings (windows) that the scene
 * declares, through which an interior sees its sky. From a point p inside of some portals, a portal is
 * picked by the solid angle it subtends at p, then a direction through it: uniform in its solid angle for
 * a rectangle (the spherical rectangle of Ureña et al. 2013), or towards a point uniform over its area
 * for another parallelogram (pdf dist² / (A · |cos θ_q|)). A direction's pdf sums this over every portal
 * it leaves through; directions through no portal have pdf 0 and are left to other sampling (BSDF
 * sampling under MIS). This is portal sampling as production renderers do it, uniform over the opening's
 * solid angle — the baseline Bitterli et al. 2015 compare their environment-aware portal sampling
 * against; it ignores how the sky's radiance varies across the opening.
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

/* A rectangle seen from p as a spherical rectangle (Ureña et al. 2013 §3): p's coordinates in the
 * rectangle's frame (x0 … x1 along its first edge, y0 … y1 along its second, z0 < 0 off its plane), the
 * constants of its inversion and its solid angle S. */
typedef struct srect {
    ic_vec3 o, x, y, z;          /* p, and the frame: x, y along the edges, z towards p's side negated */
    double x0, x1, y0, y1, z0;
    double b0, b1, k, S;
} srect;

static double angle_between(const double a[3], const double b[3])
{
    double c = -(a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
    return acos(c < -1.0 ? -1.0 : (c > 1.0 ? 1.0 : c));
}

static void unit_cross(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
    double l = sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2]);
    for (int i = 0; i < 3 && l > 0.0; ++i)
        out[i] /= l;
}

/* Fills r for rectangle pt seen from p; returns its solid angle (0 when p lies in its plane). */
static double srect_init(const ic_portal *pt, ic_vec3 p, srect *r)
{
    double ex = pt->len1, ey = pt->len2;
    r->o = p;
    r->x = pt->unit1;
    r->y = pt->unit2;
    r->z = pt->unit_normal;
    ic_vec3 d = v3_sub(pt->corner, p);
    r->z0 = v3_dot(d, r->z);
    if (r->z0 > 0.0) {
        r->z = v3_neg(r->z);
        r->z0 = -r->z0;
    }
    if (!(r->z0 < -1e-7 * (ex + ey)))
        return r->S = 0.0;
    r->x0 = v3_dot(d, r->x);
    r->y0 = v3_dot(d, r->y);
    r->x1 = r->x0 + ex;
    r->y1 = r->y0 + ey;
    const double v00[3] = {r->x0, r->y0, r->z0}, v01[3] = {r->x0, r->y1, r->z0}, v10[3] = {r->x1, r->y0, r->z0},
                 v11[3] = {r->x1, r->y1, r->z0};
    double n0[3], n1[3], n2[3], n3[3];
    unit_cross(v00, v10, n0);
    unit_cross(v10, v11, n1);
    unit_cross(v11, v01, n2);
    unit_cross(v01, v00, n3);
    double g0 = angle_between(n0, n1), g1 = angle_between(n1, n2), g2 = angle_between(n2, n3),
           g3 = angle_between(n3, n0);
    r->b0 = n0[2];
    r->b1 = n2[2];
    r->k = 2.0 * 3.14159265358979323846 - g2 - g3;
    r->S = g0 + g1 - r->k;
    return r->S > 0.0 && isfinite(r->S) ? r->S : (r->S = 0.0);
}

/* The direction for (u, v) in [0,1)², uniform in the spherical rectangle's solid angle (Ureña et al. 2013
 * §4: the first coordinate inverts the area of the sub-rectangle left of xu, the second the height along
 * the chosen column). *q is where it meets the rectangle. */
static ic_vec3 srect_sample(const srect *r, double u, double v, ic_vec3 *q)
{
    double au = u * r->S + r->k;
    double fu = (cos(au) * r->b0 - r->b1) / sin(au);
    double cu = (fu >= 0.0 ? 1.0 : -1.0) / sqrt(fu * fu + r->b0 * r->b0);
    cu = cu < -1.0 ? -1.0 : (cu > 1.0 ? 1.0 : cu);
    double xu = -(cu * r->z0) / fmax(sqrt(1.0 - cu * cu), 1e-300);
    xu = xu < r->x0 ? r->x0 : (xu > r->x1 ? r->x1 : xu);
    double dd = sqrt(xu * xu + r->z0 * r->z0);
    double h0 = r->y0 / sqrt(dd * dd + r->y0 * r->y0), h1 = r->y1 / sqrt(dd * dd + r->y1 * r->y1);
    double hv = h0 + v * (h1 - h0), hv2 = hv * hv;
    double yv = hv2 < 1.0 - 1e-12 ? hv * dd / sqrt(1.0 - hv2) : r->y1;
    ic_vec3 local = v3_add(v3_add(v3_scale(r->x, (float)xu), v3_scale(r->y, (float)yv)), v3_scale(r->z, (float)r->z0));
    *q = v3_add(r->o, local);
    return v3_norm(local);
}

/* How much of the sampling portal pt gets at p: its solid angle (a rectangle), or the area estimate
 * A |cos θ| / d² at its centre (another parallelogram), at most 2π; 0 when p is not inside of it. A
 * rectangle's spherical rectangle is left in *r (when r is not NULL), for the sample that may follow. */
static double portal_weight(const ic_portal *pt, ic_vec3 p, srect *r)
{
    if (!inside_of(pt, p))
        return 0.0;
    if (pt->rectangle) {
        srect own;
        return srect_init(pt, p, r ? r : &own);
    }
    ic_vec3 c = v3_add(pt->corner, v3_scale(v3_add(pt->edge1, pt->edge2), 0.5f));
    ic_vec3 d = v3_sub(c, p);
    double d2 = v3_len2(d);
    if (!(d2 > 0.0))
        return 0.0;
    double w = pt->area * fabs(v3_dot(d, pt->normal)) / (d2 * sqrt(d2));
    return fmin(w, 2.0 * 3.14159265358979323846);
}

/* A light sample keeps the spherical rectangles of the first PORTALS_HELD portals from their weights, so
 * that the portal it picks is not set up twice (sky-room, 2 portals: a third fewer set-ups per sample). */
#define PORTALS_HELD 8

/* Every portal's weight at p (portal_weight) into w[], and their sum; held (NULL, or PORTALS_HELD of
 * them) gets the first portals' spherical rectangles. */
static double portal_weights(const ic_environment *env, ic_vec3 p, double *w, srect *held)
{
    double total = 0.0;
    for (uint32_t k = 0; k < env->portal_count; ++k)
        total += w[k] = portal_weight(&env->portals[k], p, held && k < PORTALS_HELD ? &held[k] : NULL);
    return total;
}

/* The pdf of ic_scene_portal_pdf from the weights portal_weights gave at p. */
static float portals_pdf(const ic_environment *env, ic_vec3 p, ic_vec3 wi, const double *w, double total)
{
    double pdf = 0.0;
    for (uint32_t k = 0; k < env->portal_count; ++k) {
        const ic_portal *pt = &env->portals[k];
        if (!(w[k] > 0.0))
            continue;
        float t = portal_hit(pt, p, wi);
        if (!(t > 0.0f))
            continue;
        /* within the portal: 1/Ω (rectangle) or the area pdf, times the portal's share (below) */
        pdf += pt->rectangle ? 1.0 : w[k] * (double)t * t / (pt->area * fabs(v3_dot(wi, pt->normal)));
    }
    /* Σ_k (w_k / W) pdf_k: for a rectangle pdf_k = 1/w_k, so its term is 1/W. */
    pdf = total > 0.0 ? pdf / total : 0.0;
    return isfinite(pdf) ? (float)pdf : 0.0f;
}

float ic_scene_portal_pdf(const ic_scene *scene, ic_vec3 p, ic_vec3 wi)
{
    const ic_environment *env = &scene->env;
    /* A direction through none of the portals has pdf 0 whatever their weights: most directions from a
     * room's surfaces meet a wall, so the weights are only set up for those that leave through one. */
    uint32_t k = 0;
    while (k < env->portal_count && !(portal_hit(&env->portals[k], p, wi) > 0.0f))
        ++k;
    if (k == env->portal_count)
        return 0.0f;
    double w[IC_MAX_PORTALS];
    double total = portal_weights(env, p, w, NULL);
    return portals_pdf(env, p, wi, w, total);
}

int ic_scene_sample_portal(const ic_scene *scene, ic_vec3 p, float u0, float u1, float u2, ic_vec3 *wi, ic_vec3 *q,
                           float *pdf)
{
    const ic_environment *env = &scene->env;
    *pdf = 0.0f;
    if (!env->portal_count)
        return 0;
    double w[IC_MAX_PORTALS];
    srect held[PORTALS_HELD];
    double total = portal_weights(env, p, w, held);
    if (!(total > 0.0))
        return 0;
    uint32_t k = 0;
    double acc = w[0], target = (double)u0 * total;
    while (k + 1 < env->portal_count && (acc <= target || !(w[k] > 0.0)))
        acc += w[++k];
    if (!(w[k] > 0.0))
        return 0;
    const ic_portal *pt = &env->portals[k];
    if (pt->rectangle) {
        srect r;
        if (k >= PORTALS_HELD)
            srect_init(pt, p, &r);
        *wi = srect_sample(k < PORTALS_HELD ? &held[k] : &r, u1, u2, q);
    } else {
        *q = v3_madd(v3_madd(pt->corner, pt->edge1, u1), pt->edge2, u2);
        ic_vec3 d = v3_sub(*q, p);
        float dist = v3_len(d);
        if (!(dist > 0.0f))
            return 0;
        *wi = v3_scale(d, 1.0f / dist);
    }
    if (!(fabsf(v3_dot(*wi, pt->normal)) > 1e-6f))
        return 0; /* the opening seen edge-on */
    *pdf = portals_pdf(env, p, *wi, w, total); /* the weights at p, not computed twice */
    return *pdf > 0.0f && isfinite(*pdf);
}

ic_result ic_scene_build_portals(ic_scene *s, ic_error *err)
{
    (void)err;
    ic_environment *env = &s->env;
    double total = 0.0;
    for (uint32_t k = 0; k < env->portal_count; ++k)
        total += env->portals[k].area;
    env->portal_area = (float)total;
    return IC_OK;
}

ic_result ic_scene_add_portal(ic_scene *s, const ic_vec3 corners[4], ic_error *err)
{
    ic_vec3 e1 = v3_sub(corners[1], corners[0]), e2 = v3_sub(corners[3], corners[0]);
    ic_vec3 c = v3_cross(e1, e2);
    float area = v3_len_any(c), scale = v3_len(e1) + v3_len(e2); /* |c|² overflows for edges beyond 4e9 */
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
    pt->normal = v3_norm_any(c);
    pt->area = area;
    pt->rectangle = fabsf(v3_dot(e1, e2)) <= 1e-4f * v3_len(e1) * v3_len(e2);
    pt->len1 = v3_len(e1);
    pt->len2 = v3_len(e2);
    pt->unit1 = v3_scale(e1, (float)(1.0 / pt->len1));
    pt->unit2 = v3_scale(e2, (float)(1.0 / pt->len2));
    pt->unit_normal = v3_cross(pt->unit1, pt->unit2);
    return IC_OK;
}
