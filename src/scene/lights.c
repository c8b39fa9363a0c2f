/*
 * lights.c — light tables and light sampling for next-event estimation.
 *
 * One sample picks one light class with a fixed probability proportional to an estimate of the power
 * each class brings into the scene (computed once at load; docs/scene-format.md, "Light sampling"):
 *   triangles   Σ π·A·lum(Le) (× 2 if two-sided)          — emitted power
 *   points      Σ 4π·lum(I)                               — emitted power
 *   sun         π·r²·lum(E)                               — power crossing the scene's bounding sphere
 *               (a directional sun, or a disc sampled uniformly by solid angle, PBR 3rd ed. §13.6's cone)
 *   environment 4π²·r²·mean lum(L) over the sphere         — same, for radiance arriving from all sides
 * (r = bounding-sphere radius). Within a class: triangles ∝ power (CDF, then a uniform point on the
 * triangle, PBR 3rd ed. §13.6.4), points ∝ power, the environment image ∝ lum·sin θ of texels (PBR 3rd
 * ed. §14.2.4; each texel's weight is the maximum over its 3×3 neighbourhood so that the bilinear
 * look-up never returns radiance where the pdf is zero), a constant sky uniformly over the sphere, an
 * analytic daylight sky (sky.h) by the same image tables filled with its values at the texel centres.
 * The pdf functions below reproduce exactly the densities the sampler uses, for MIS.
 */
#include "scene/scene_internal.h"

#include "core/sampling.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------------ */
/* environment mapping: direction <-> (u, v) of the lat-long image (scene.h) */

/* World direction → image (u, v) in [0,1]; the map is rotated by rotation_deg about +y. */
static void env_dir_to_uv(const ic_environment *env, ic_vec3 d, float *u, float *v)
{
    ic_vec3 m = v3_rotate_y(d, -env->rotation_deg);
    *u = 0.5f + atan2f(m.x, -m.z) * (0.5f * IC_INV_PI);
    *v = acosf(ic_clampf(m.y, -1.0f, 1.0f)) * IC_INV_PI;
}

static ic_vec3 env_uv_to_dir(const ic_environment *env, float u, float v)
{
    float phi = (u - 0.5f) * 2.0f * IC_PI, theta = v * IC_PI;
    float st = sinf(theta);
    ic_vec3 m = v3(st * sinf(phi), cosf(theta), -st * cosf(phi));
    return v3_rotate_y(m, env->rotation_deg);
}

static const float *texel(const ic_image *img, int x, int y)
{
    x %= img->width;
    if (x < 0)
        x += img->width;
    y = y < 0 ? 0 : (y >= img->height ? img->height - 1 : y);
    return img->rgb + 3 * ((size_t)y * (size_t)img->width + (size_t)x);
}

ic_vec3 ic_scene_env_radiance(const ic_scene *scene, ic_vec3 d)
{
    const ic_environment *env = &scene->env;
    if (!env->enabled)
        return v3s(0.0f);
    if (env->sky.model != IC_SKY_NONE)
        return ic_sky_radiance(&env->sky, d);
    if (env->image.width <= 0)
        return env->radiance;
    float u, v;
    env_dir_to_uv(env, d, &u, &v);
    /* bilinear between texel centres; wraps in u, clamps in v */
    float x = u * (float)env->image.width - 0.5f, y = v * (float)env->image.height - 0.5f;
    int x0 = (int)floorf(x), y0 = (int)floorf(y);
    float fx = x - (float)x0, fy = y - (float)y0;
    const float *a = texel(&env->image, x0, y0), *b = texel(&env->image, x0 + 1, y0);
    const float *c = texel(&env->image, x0, y0 + 1), *e = texel(&env->image, x0 + 1, y0 + 1);
    ic_vec3 r;
    float *out = &r.x;
    for (int k = 0; k < 3; ++k)
        out[k] = (1.0f - fy) * ((1.0f - fx) * a[k] + fx * b[k]) + fy * ((1.0f - fx) * c[k] + fx * e[k]);
    return v3_mul(r, env->radiance);
}

/* Sampling weight of texel (x, y): max luminance over its 3×3 neighbourhood × sin θ of its centre. */
static float env_texel_weight(const ic_environment *env, int x, int y)
{
    float lum = 0.0f;
    for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
            const float *t = texel(&env->image, x + dx, y + dy);
            lum = fmaxf(lum, v3_lum(v3_mul(v3(t[0], t[1], t[2]), env->radiance)));
        }
    float theta = ((float)y + 0.5f) / (float)env->image.height * IC_PI;
    return (isfinite(lum) ? lum : 0.0f) * sinf(theta);
}

/* An analytic sky tabulated at the texel centres of a lat-long image, which the image's sampling tables
 * then follow (its radiance is still evaluated exactly: ic_scene_env_radiance). 256 × 128 texels of
 * 1.4°: the sharpest feature, the clear skies' circumsolar peak e^{−3γ}, spans many of them. */
static ic_result tabulate_sky(ic_scene *scene, ic_error *err)
{
    ic_environment *env = &scene->env;
    enum { SKY_TABLE_W = 256, SKY_TABLE_H = 128 };
    if (ic_image_create(&env->image, SKY_TABLE_W, SKY_TABLE_H) != IC_OK)
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory for the sky's sampling table", scene->path);
    for (int y = 0; y < SKY_TABLE_H; ++y)
        for (int x = 0; x < SKY_TABLE_W; ++x) {
            ic_vec3 d = env_uv_to_dir(env, ((float)x + 0.5f) / SKY_TABLE_W, ((float)y + 0.5f) / SKY_TABLE_H);
            float *t = env->image.rgb + 3 * ((size_t)y * SKY_TABLE_W + (size_t)x);
            ic_vec3 L = ic_sky_radiance(&env->sky, d);
            t[0] = L.x;
            t[1] = L.y;
            t[2] = L.z;
        }
    env->radiance = v3s(1.0f);
    return IC_OK;
}

/* The sun's disc from its angular radius and irradiance (scene.h): a uniform radiance L over a cap of
 * half-angle a gives ∫ L cos θ dω = L π sin² a at normal incidence. */
static void prepare_sun_disc(ic_sun_light *sun)
{
    if (!sun->enabled || !(sun->angular_radius > 0.0f))
        return;
    double a = sun->angular_radius, sin_a = sin(a), half = sin(0.5 * a);
    sun->one_minus_cos = (float)(2.0 * half * half);
    sun->solid_angle = (float)(2.0 * 3.14159265358979323846 * 2.0 * half * half);
    sun->radiance = v3_scale(sun->irradiance, (float)(1.0 / (3.14159265358979323846 * sin_a * sin_a)));
    sun->frame = ic_frame_from_normal(sun->direction);
}

static ic_result build_env_tables(ic_scene *scene, ic_error *err)
{
    ic_environment *env = &scene->env;
    int w = env->image.width, h = env->image.height;
    env->marginal_cdf = malloc(sizeof(float) * ((size_t)h + 1));
    env->conditional_cdf = malloc(sizeof(float) * (size_t)h * ((size_t)w + 1));
    if (!env->marginal_cdf || !env->conditional_cdf)
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory for the environment map's sampling tables",
                            scene->path);
    double total = 0.0;
    env->marginal_cdf[0] = 0.0f;
    for (int y = 0; y < h; ++y) {
        float *row = env->conditional_cdf + (size_t)y * ((size_t)w + 1);
        double sum = 0.0;
        row[0] = 0.0f;
        for (int x = 0; x < w; ++x) {
            sum += env_texel_weight(env, x, y);
            row[x + 1] = (float)sum;
        }
        for (int x = 1; x <= w; ++x) /* normalise; an all-black row stays uniform (never picked) */
            row[x] = sum > 0.0 ? (float)(row[x] / sum) : (float)x / (float)w;
        row[w] = 1.0f;
        total += sum;
        env->marginal_cdf[y + 1] = (float)total;
    }
    for (int y = 1; y <= h; ++y)
        env->marginal_cdf[y] = total > 0.0 ? (float)(env->marginal_cdf[y] / total) : (float)y / (float)h;
    env->marginal_cdf[h] = 1.0f;
    env->total_weight = (float)total;
    return IC_OK;
}

/* Index i with cdf[i] <= u < cdf[i+1] among n intervals (cdf has n+1 entries, cdf[n] = 1), skipping
 * empty intervals. */
static uint32_t cdf_find(const float *cdf, uint32_t n, float u)
{
    uint32_t lo = 0, hi = n; /* invariant: answer in [lo, hi) */
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (cdf[mid] <= u)
            lo = mid;
        else
            hi = mid;
    }
    while (lo + 1 < n && cdf[lo + 1] <= cdf[lo])
        ++lo; /* u landed on an empty interval's boundary */
    return lo;
}

/* Weight (pdf in (u, v) up to 1/total) of the texel the direction falls in. */
static float env_pdf_image(const ic_environment *env, ic_vec3 d)
{
    if (!(env->total_weight > 0.0f))
        return 0.0f;
    float u, v;
    env_dir_to_uv(env, d, &u, &v);
    int w = env->image.width, h = env->image.height;
    int x = (int)(u * (float)w), y = (int)(v * (float)h);
    x = x < 0 ? 0 : (x >= w ? w - 1 : x);
    y = y < 0 ? 0 : (y >= h ? h - 1 : y);
    float sin_theta = sinf(v * IC_PI);
    if (!(sin_theta > 0.0f))
        return 0.0f;
    const float *row = env->conditional_cdf + (size_t)y * ((size_t)w + 1);
    float p_row = env->marginal_cdf[y + 1] - env->marginal_cdf[y];
    float p_col = row[x + 1] - row[x];
    float pdf_uv = p_row * p_col * (float)w * (float)h;
    return pdf_uv / (2.0f * IC_PI * IC_PI * sin_theta);
}

float ic_scene_sun_disc_pdf(const ic_scene *scene, ic_vec3 wi)
{
    const ic_sun_light *sun = &scene->sun;
    if (!sun->enabled || !(sun->angular_radius > 0.0f))
        return 0.0f;
    return ic_warp_uniform_cone_pdf(ic_frame_to_local(&sun->frame, wi), sun->one_minus_cos);
}

ic_vec3 ic_scene_sun_radiance(const ic_scene *scene, ic_vec3 wi)
{
    return ic_scene_sun_disc_pdf(scene, wi) > 0.0f ? scene->sun.radiance : v3s(0.0f);
}

float ic_scene_light_pdf_sun(const ic_scene *scene, const ic_light_selection *sel, ic_vec3 wi)
{
    return sel->sun > 0.0f ? sel->sun * ic_scene_sun_disc_pdf(scene, wi) : 0.0f;
}

int ic_scene_sample_sun(const ic_scene *scene, float u1, float u2, ic_light_sample *ls)
{
    const ic_sun_light *sun = &scene->sun;
    if (!sun->enabled)
        return 0;
    ls->dist = INFINITY;
    if (!(sun->angular_radius > 0.0f)) {
        ls->wi = sun->direction;
        ls->radiance = sun->irradiance;
        ls->pdf = 1.0f;
        ls->is_delta = 1;
        return 1;
    }
    ls->wi = ic_frame_to_world(&sun->frame, ic_warp_uniform_cone(u1, u2, sun->one_minus_cos));
    ls->radiance = sun->radiance;
    ls->pdf = ic_warp_uniform_cone_pdf(v3(0.0f, 0.0f, 1.0f), sun->one_minus_cos);
    ls->is_delta = 0;
    return 1;
}

float ic_scene_env_pdf_at(const ic_scene *scene, ic_vec3 p, ic_vec3 wi)
{
    const ic_environment *env = &scene->env;
    if (!env->enabled)
        return 0.0f;
    if (env->portal_count && ic_scene_portals_apply(scene, p))
        return ic_scene_portal_pdf(scene, p, wi);
    if (env->image.width <= 0)
        return 0.25f * IC_INV_PI;
    return env_pdf_image(env, wi);
}

float ic_scene_light_pdf_env_at(const ic_scene *scene, ic_vec3 p, ic_vec3 wi)
{
    if (!(scene->light_select.env > 0.0f))
        return 0.0f;
    return scene->light_select.env * ic_scene_env_pdf_at(scene, p, wi);
}

float ic_scene_light_pdf_env(const ic_scene *scene, ic_vec3 wi)
{
    const ic_environment *env = &scene->env;
    if (!env->enabled || !(scene->light_select.env > 0.0f))
        return 0.0f;
    if (env->image.width <= 0)
        return scene->light_select.env * (0.25f * IC_INV_PI);
    return scene->light_select.env * env_pdf_image(env, wi);
}

/* ------------------------------------------------------------------------------------------------ */
/* building */

static float tri_area(const ic_scene *s, uint32_t t)
{
    ic_vec3 p0 = s->positions[s->triangles[3 * t]], p1 = s->positions[s->triangles[3 * t + 1]],
            p2 = s->positions[s->triangles[3 * t + 2]];
    return 0.5f * v3_len_any(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
}

/* Mean luminance of the environment over the sphere (radiance scale included). */
static float env_mean_lum(const ic_environment *env)
{
    if (env->image.width <= 0)
        return v3_lum(env->radiance);
    int w = env->image.width, h = env->image.height;
    double sum = 0.0, wsum = 0.0;
    for (int y = 0; y < h; ++y) {
        double st = sin(((double)y + 0.5) / h * 3.14159265358979323846);
        for (int x = 0; x < w; ++x) {
            const float *t = texel(&env->image, x, y);
            float l = v3_lum(v3_mul(v3(t[0], t[1], t[2]), env->radiance));
            sum += (isfinite(l) ? l : 0.0) * st;
            wsum += st;
        }
    }
    return wsum > 0.0 ? (float)(sum / wsum) : 0.0f;
}

/* Turns the running sums cdf[1..n] (cdf[0] = 0) into a CDF: divided by their total (uniform when it is
 * 0), with cdf[n] exactly 1. */
static void normalise_cdf(float *cdf, uint32_t n, double total)
{
    for (uint32_t i = 1; i <= n; ++i)
        cdf[i] = total > 0.0 ? (float)(cdf[i] / total) : (float)i / (float)n;
    if (n)
        cdf[n] = 1.0f;
}

/* Triangle lights: every triangle with an emissive material, its power and CDF; *power: their total. */
static ic_result build_tri_lights(ic_scene *s, double *power, ic_error *err)
{
    uint32_t count = 0;
    for (uint32_t t = 0; t < s->triangle_count; ++t)
        if (!v3_is_black(s->materials[s->triangle_material[t]].emission))
            ++count;
    s->triangle_light = malloc(sizeof *s->triangle_light * (s->triangle_count ? s->triangle_count : 1));
    s->tri_lights = malloc(sizeof *s->tri_lights * (count ? count : 1));
    s->tri_light_cdf = malloc(sizeof *s->tri_light_cdf * (count + 1));
    if (!s->triangle_light || !s->tri_lights || !s->tri_light_cdf)
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory for the light tables", s->path);
    double total = 0.0;
    s->tri_light_count = 0;
    s->tri_light_cdf[0] = 0.0f;
    for (uint32_t t = 0; t < s->triangle_count; ++t) {
        const ic_material *m = &s->materials[s->triangle_material[t]];
        s->triangle_light[t] = -1;
        if (v3_is_black(m->emission))
            continue;
        ic_tri_light *l = &s->tri_lights[s->tri_light_count];
        l->triangle = t;
        l->area = tri_area(s, t);
        l->power = IC_PI * l->area * v3_lum(m->emission) * (m->two_sided_emission ? 2.0f : 1.0f);
        /* the light tables hold powers in float: a lamp some 1e18 across emitting 100 W/(m² sr) is beyond it
         * (its power inf here; the message gives it in double) */
        if (!(total + l->power <= FLT_MAX))
            return ic_error_set(err, IC_ERR_INVALID_ARG,
                                "%s: the emitters' power (material '%s': %g, all so far %g) is beyond the float range; "
                                "scale the scene's size or its emission down",
                                s->path, m->name,
                                IC_PI * (double)l->area * v3_lum(m->emission) * (m->two_sided_emission ? 2.0 : 1.0),
                                total);
        ic_vec3 p0 = s->positions[s->triangles[3 * t]], p1 = s->positions[s->triangles[3 * t + 1]],
                p2 = s->positions[s->triangles[3 * t + 2]];
        l->centroid = v3_scale(v3_add(v3_add(p0, p1), p2), 1.0f / 3.0f);
        ic_vec3 cr = v3_cross(v3_sub(p1, p0), v3_sub(p2, p0));
        l->normal = v3_len_any(cr) > 0.0f ? v3_norm_any(cr) : v3(0.0f, 0.0f, 1.0f);
        l->radius = sqrtf(fmaxf(v3_len2(v3_sub(p0, l->centroid)),
                                fmaxf(v3_len2(v3_sub(p1, l->centroid)), v3_len2(v3_sub(p2, l->centroid)))));
        l->two_sided = m->two_sided_emission;
        total += l->power;
        s->triangle_light[t] = (int32_t)s->tri_light_count++;
        s->tri_light_cdf[s->tri_light_count] = (float)total;
    }
    normalise_cdf(s->tri_light_cdf, s->tri_light_count, total);
    s->tri_light_power = (float)total;
    *power = total;
    return IC_OK;
}

/* Point lights: their CDF by power; *power: their total. */
static ic_result build_point_lights(ic_scene *s, double *power, ic_error *err)
{
    s->point_light_cdf = malloc(sizeof *s->point_light_cdf * (s->point_light_count + 1));
    if (!s->point_light_cdf)
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory for the light tables", s->path);
    double point_power = 0.0;
    s->point_light_cdf[0] = 0.0f;
    for (uint32_t i = 0; i < s->point_light_count; ++i) {
        /* a spot's power: that of a point times the share of the sphere its cone lights (about) */
        double share = s->point_spots ? fmin(1.0, 0.5 * (1.0 - 0.5 * (s->point_spots[i].cos_inner +
                                                                     s->point_spots[i].cos_outer))) : 1.0;
        point_power += 4.0 * IC_PI * v3_lum(s->point_lights[i].intensity) * share;
        if (!(point_power <= FLT_MAX))
            return ic_error_set(err, IC_ERR_INVALID_ARG,
                                "%s: the point lights' power (%g with point or spot light %u) is beyond the float "
                                "range; give them less intensity",
                                s->path, point_power, i + 1);
        s->point_light_cdf[i + 1] = (float)point_power;
    }
    normalise_cdf(s->point_light_cdf, s->point_light_count, point_power);
    *power = point_power;
    return IC_OK;
}

/* The light-class probabilities, proportional to each class's power (the file comment); all zero when
 * the scene has no light. */
static void select_light_classes(ic_scene *s, double w_tri, double w_point)
{
    float radius = 0.5f * v3_len(v3_sub(s->bounds_max, s->bounds_min));
    if (!(radius > 0.0f) || !isfinite(radius))
        radius = 1.0f;
    /* in double: π r² lum(E) in float passed the float range in a scene near the largest coordinate (r beyond
     * about 1e17 under a sun of 1e4), and the sum's inf left every class a probability of 0 (all black) */
    const double pi = IC_PI;
    double w_sun = s->sun.enabled ? pi * radius * radius * v3_lum(s->sun.irradiance) : 0.0;
    double w_env = 0.0;
    if (s->env.enabled && (s->env.image.width <= 0 || s->env.total_weight > 0.0f))
        w_env = 4.0 * pi * pi * radius * radius * env_mean_lum(&s->env);
    if (s->env.enabled && s->env.portal_count) {
        /* Through portals, the power that enters: the sky's over the openings' area (π L̄ A), the sun's
         * over their area facing it. */
        w_env = pi * s->env.portal_area * env_mean_lum(&s->env);
        double facing = 0.0;
        for (uint32_t k = 0; k < s->env.portal_count; ++k)
            facing += s->env.portals[k].area * fabsf(v3_dot(s->env.portals[k].normal, s->sun.direction));
        /* At least as if it met the openings at 3° (sin ≈ 0.05): a sun in the plane of every portal
         * still lights the points outside them, and a delta light has no other way in than its samples. */
        if (s->sun.enabled)
            w_sun = fmax(facing, 0.05 * s->env.portal_area) * v3_lum(s->sun.irradiance);
    }
    double sum = w_tri + w_point + w_sun + w_env;
    memset(&s->light_select, 0, sizeof s->light_select);
    if (sum > 0.0 && isfinite(sum)) {
        s->light_select.tri = (float)(w_tri / sum);
        s->light_select.point = (float)(w_point / sum);
        s->light_select.sun = (float)(w_sun / sum);
        s->light_select.env = (float)(w_env / sum);
    }
}

ic_result ic_scene_build_lights(ic_scene *s, ic_error *err)
{
    double tri_power = 0.0, point_power = 0.0;
    ic_result r = build_tri_lights(s, &tri_power, err);
    if (r != IC_OK)
        return r;
    r = build_point_lights(s, &point_power, err);
    if (r != IC_OK)
        return r;
    if (s->env.enabled && s->env.sky.model != IC_SKY_NONE) {
        r = tabulate_sky(s, err);
        if (r != IC_OK)
            return r;
    }
    if (s->env.enabled && s->env.image.width > 0) {
        r = build_env_tables(s, err);
        if (r != IC_OK)
            return r;
    }
    r = ic_scene_build_portals(s, err);
    if (r != IC_OK)
        return r;
    prepare_sun_disc(&s->sun);
    select_light_classes(s, tri_power, point_power);
    return IC_OK;
}

/* ------------------------------------------------------------------------------------------------ */
/* sampling */

float ic_scene_light_pdf_triangle(const ic_scene *scene, ic_vec3 p, uint32_t tri, ic_vec3 wi, float dist)
{
    return ic_scene_light_pdf_triangle_sel(scene, &scene->light_select, p, tri, wi, dist);
}

float ic_scene_light_pdf_triangle_sel(const ic_scene *scene, const ic_light_selection *sel, ic_vec3 p, uint32_t tri,
                                      ic_vec3 wi, float dist)
{
    (void)p;
    if (tri >= scene->triangle_count || !(scene->tri_light_power > 0.0f))
        return 0.0f;
    int32_t li = scene->triangle_light[tri];
    if (li < 0)
        return 0.0f;
    const ic_tri_light *l = &scene->tri_lights[li];
    const ic_material *m = &scene->materials[scene->triangle_material[tri]];
    ic_vec3 p0 = scene->positions[scene->triangles[3 * tri]], p1 = scene->positions[scene->triangles[3 * tri + 1]],
            p2 = scene->positions[scene->triangles[3 * tri + 2]];
    ic_vec3 ng = v3_norm_any(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
    float cos_l = -v3_dot(ng, wi);
    if (!m->two_sided_emission && cos_l <= 0.0f)
        return 0.0f;
    cos_l = fabsf(cos_l);
    if (!(cos_l > 0.0f) || !(l->area > 0.0f))
        return 0.0f;
    float select = sel->tri * (sel->tri_pmf ? sel->tri_pmf[li] : l->power / scene->tri_light_power);
    return select * dist * dist / (l->area * cos_l);
}

int ic_scene_local_lights(const ic_scene *s, ic_vec3 p, ic_vec3 n, const float *base_pmf, float *pmf, float *cdf)
{
    uint32_t count = s->tri_light_count;
    if (count == 0 || count > IC_LOCAL_LIGHTS_MAX || !(s->tri_light_power > 0.0f))
        return 0;
    double local = 0.0;
    for (uint32_t i = 0; i < count; ++i) {
        const ic_tri_light *l = &s->tri_lights[i];
        if (base_pmf && !(base_pmf[i] > 0.0f)) {
            pmf[i] = 0.0f; /* not sampled at all under the base distribution: not here either */
            continue;
        }
        ic_vec3 d = v3_sub(l->centroid, p);
        float d2 = v3_len2(d), dist = sqrtf(d2);
        /* Bounds of cos at the receiver and at the emitter over the triangle: the centre's cosine
         * widened by the triangle's angular radius (sin ≤ radius/dist), clamped to [0, 1]. */
        float spread = dist > 0.0f ? fminf(1.0f, l->radius / dist) : 1.0f;
        float cr = dist > 0.0f ? v3_dot(n, d) / dist : 1.0f;
        float ce = dist > 0.0f ? -v3_dot(l->normal, d) / dist : 1.0f;
        if (l->two_sided)
            ce = fabsf(ce);
        cr = ic_clampf(cr + spread, 0.0f, 1.0f);
        ce = ic_clampf(ce + spread, 0.0f, 1.0f);
        float w = l->power * cr * ce / fmaxf(d2, l->area);
        pmf[i] = isfinite(w) ? w : 0.0f;
        local += pmf[i];
    }
    /* Mixed 3:1 with the power distribution: a light the bounds wrongly rule out (the receiver of a
     * sample is not exactly p) keeps a quarter of its global probability. */
    double sum = 0.0;
    cdf[0] = 0.0f;
    for (uint32_t i = 0; i < count; ++i) {
        double g = base_pmf ? (double)base_pmf[i] : s->tri_lights[i].power / (double)s->tri_light_power;
        double q = local > 0.0 ? 0.75 * pmf[i] / local + 0.25 * g : g;
        pmf[i] = (float)q;
        sum += q;
        cdf[i + 1] = (float)sum;
    }
    if (!(sum > 0.0))
        return 0;
    for (uint32_t i = 1; i <= count; ++i)
        cdf[i] = (float)(cdf[i] / sum);
    cdf[count] = 1.0f;
    for (uint32_t i = 0; i < count; ++i)
        pmf[i] = (float)(pmf[i] / sum);
    return 1;
}

static int sample_triangle(const ic_scene *s, const ic_light_selection *sel, ic_vec3 p, float u1, float u2,
                           ic_light_sample *ls)
{
    /* The triangle is chosen with u1 and u1 is stretched back over [0,1) inside its interval, so a
     * well-spread (u1, u2) set stays well spread over the union of the emitters (a stratified
     * sequence loses its structure when a third, independent number picks the triangle). */
    const float *cdf = sel->tri_cdf ? sel->tri_cdf : s->tri_light_cdf;
    uint32_t li = cdf_find(cdf, s->tri_light_count, u1);
    float lo = cdf[li], width = cdf[li + 1] - lo;
    u1 = width > 0.0f ? ic_clampf((u1 - lo) / width, 0.0f, 0.99999994f) : 0.0f;
    const ic_tri_light *l = &s->tri_lights[li];
    uint32_t t = l->triangle;
    ic_vec3 p0 = s->positions[s->triangles[3 * t]], p1 = s->positions[s->triangles[3 * t + 1]],
            p2 = s->positions[s->triangles[3 * t + 2]];
    float b1, b2;
    ic_warp_triangle(u1, u2, &b1, &b2);
    ic_vec3 x = v3_add(v3_add(v3_scale(p0, 1.0f - b1 - b2), v3_scale(p1, b1)), v3_scale(p2, b2));
    ic_vec3 d = v3_sub(x, p);
    float dist2 = v3_len2(d);
    if (!(dist2 > 0.0f))
        return 0;
    float dist = sqrtf(dist2);
    ls->wi = v3_scale(d, 1.0f / dist);
    ls->dist = dist;
    ls->is_delta = 0;
    const ic_material *m = &s->materials[s->triangle_material[t]];
    ic_vec3 ng = v3_norm_any(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
    float cos_l = -v3_dot(ng, ls->wi);
    if ((!m->two_sided_emission && cos_l <= 0.0f) || cos_l == 0.0f)
        return 0; /* the point sees the back of a one-sided emitter */
    if (!ic_material_emits_towards(m, v3_neg(ls->wi)))
        return 0; /* outside a spotlight's cone */
    float select = sel->tri * (sel->tri_pmf ? sel->tri_pmf[li] : l->power / s->tri_light_power);
    ls->pdf = select * dist2 / (l->area * fabsf(cos_l));
    ls->radiance = m->emission;
    return ls->pdf > 0.0f && isfinite(ls->pdf);
}

static int sample_point(const ic_scene *s, const ic_light_selection *sel, ic_vec3 p, float u0, ic_light_sample *ls)
{
    uint32_t i = cdf_find(s->point_light_cdf, s->point_light_count, u0);
    const ic_point_light *l = &s->point_lights[i];
    ic_vec3 d = v3_sub(l->position, p);
    float dist2 = v3_len2(d);
    if (!(dist2 > 0.0f))
        return 0;
    float dist = sqrtf(dist2);
    ls->wi = v3_scale(d, 1.0f / dist);
    ls->dist = dist;
    ls->radiance = v3_scale(l->intensity, 1.0f / dist2);
    if (s->point_spots)
        ls->radiance = v3_scale(ls->radiance, ic_spot_falloff(&s->point_spots[i], v3_neg(ls->wi)));
    ls->pdf = sel->point * (s->point_light_cdf[i + 1] - s->point_light_cdf[i]);
    ls->is_delta = 1;
    return ls->pdf > 0.0f;
}

static int sample_env(const ic_scene *s, const ic_light_selection *sel, ic_vec3 p, float u0, float u1, float u2,
                      ic_light_sample *ls)
{
    const ic_environment *env = &s->env;
    ls->dist = INFINITY;
    ls->is_delta = 0;
    if (env->portal_count && ic_scene_portals_apply(s, p)) {
        ic_vec3 q;
        float pdf;
        if (!ic_scene_sample_portal(s, p, u0, u1, u2, &ls->wi, &q, &pdf))
            return 0;
        ls->pdf = sel->env * pdf;
        ls->radiance = ic_scene_env_radiance(s, ls->wi);
        return ls->pdf > 0.0f && isfinite(ls->pdf);
    }
    if (env->image.width <= 0) {
        ls->wi = ic_warp_uniform_sphere(u1, u2);
        ls->pdf = sel->env * (0.25f * IC_INV_PI);
        ls->radiance = env->radiance;
        return 1;
    }
    int w = env->image.width, h = env->image.height;
    uint32_t y = cdf_find(env->marginal_cdf, (uint32_t)h, u1);
    float dy = env->marginal_cdf[y + 1] - env->marginal_cdf[y];
    float fy = dy > 0.0f ? (u1 - env->marginal_cdf[y]) / dy : 0.5f;
    const float *row = env->conditional_cdf + (size_t)y * ((size_t)w + 1);
    uint32_t x = cdf_find(row, (uint32_t)w, u2);
    float dx = row[x + 1] - row[x];
    float fx = dx > 0.0f ? (u2 - row[x]) / dx : 0.5f;
    float u = ((float)x + ic_clampf(fx, 0.0f, 0.99999f)) / (float)w;
    float v = ((float)y + ic_clampf(fy, 0.0f, 0.99999f)) / (float)h;
    float sin_theta = sinf(v * IC_PI);
    if (!(sin_theta > 0.0f))
        return 0;
    ls->wi = env_uv_to_dir(env, u, v);
    ls->pdf = sel->env * dy * dx * (float)w * (float)h / (2.0f * IC_PI * IC_PI * sin_theta);
    ls->radiance = ic_scene_env_radiance(s, ls->wi);
    return ls->pdf > 0.0f && isfinite(ls->pdf);
}

int ic_scene_sample_light(const ic_scene *scene, ic_vec3 p, float u0, float u1, float u2, ic_light_sample *ls)
{
    return ic_scene_sample_light_sel(scene, &scene->light_select, p, u0, u1, u2, ls);
}

int ic_scene_sample_light_sel(const ic_scene *scene, const ic_light_selection *sel, ic_vec3 p, float u0, float u1,
                              float u2, ic_light_sample *ls)
{
    memset(ls, 0, sizeof *ls);
    /* pick the class with u0, then stretch the rest of u0's interval back to [0,1) for the light */
    float prob[4] = {sel->tri, sel->point, sel->sun, sel->env};
    float edge[4] = {sel->tri, sel->tri + sel->point, sel->tri + sel->point + sel->sun, 1.0f};
    for (int k = 3; k > 0 && prob[k] == 0.0f; --k)
        edge[k - 1] = 1.0f; /* rounding must not leave u0 near 1 to a class that has no light */
    float lo = 0.0f;
    int cls = 0;
    while (cls < 3 && u0 >= edge[cls]) {
        lo = edge[cls];
        ++cls;
    }
    float width = edge[cls] - lo;
    float ur = width > 0.0f ? ic_clampf((u0 - lo) / width, 0.0f, 0.99999994f) : 0.0f;
    int ok = 0;
    switch (cls) {
    case 0:
        ok = sel->tri > 0.0f && sample_triangle(scene, sel, p, u1, u2, ls);
        break;
    case 1:
        ok = sel->point > 0.0f && sample_point(scene, sel, p, ur, ls);
        break;
    case 2:
        ok = sel->sun > 0.0f && ic_scene_sample_sun(scene, u1, u2, ls);
        ls->pdf *= sel->sun;
        break;
    default:
        ok = sel->env > 0.0f && sample_env(scene, sel, p, ur, u1, u2, ls);
        break;
    }
    if (!ok)
        ls->pdf = 0.0f;
    return ok;
}
