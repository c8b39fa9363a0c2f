/*
 * ic_aov.c — the cache render's diagnostic images and lists: record positions and radii drawn over the
 * image, records per pixel, the a_i map, and the records as the camera sees them.
 */
#include "ic_internal.h"

#include "core/select.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Median luminance of the image under the records' marks (linear; 0.18, the photographic mid-grey, is
 * 46 % of white in the PNG's sRGB, dark enough for the marks' saturated colours to stand out). */
#define IC_RECORDS_BACKGROUND_GREY 0.18f

static void put(ic_image *img, int x, int y, ic_vec3 c)
{
    if (x < 0 || y < 0 || x >= img->width || y >= img->height)
        return;
    float *px = &img->rgb[3 * ((size_t)y * img->width + x)];
    px[0] = c.x;
    px[1] = c.y;
    px[2] = c.z;
}

/* Where a record appears in the image, and whether the camera sees its surface directly (the G-buffer
 * point at its pixel is next to it). */
static ic_record_view view_of(const ic_ctx *c, const ic_record *rec)
{
    const ic_camera *cam = &c->tr->scene->camera;
    ic_record_view v;
    memset(&v, 0, sizeof v);
    v.position = rec->position;
    v.radius = rec->radius;
    v.accuracy = rec->accuracy;
    v.is_radiance = rec->bounce >= IC_BOUNCE_RADIANCE;
    if (rec->ellipse_ratio > 0.0f && rec->ellipse_ratio < 1.0f) {
        v.ellipse_ratio = rec->ellipse_ratio;
        v.ellipse_axis = rec->ellipse_axis;
    }
    float z;
    if (!ic_camera_project(cam, rec->position, &v.px, &v.py, &z))
        return v;
    v.radius_px = rec->accuracy * rec->radius / ic_camera_footprint(cam, v.px, v.py, z);
    int px = (int)v.px, py = (int)v.py;
    if (px < 0 || py < 0 || px >= cam->width || py >= cam->height)
        return v;
    size_t gi = (size_t)py * cam->width + px;
    v.visible = c->g.valid[gi] &&
                v3_len(v3_sub(c->g.p[gi], rec->position)) <= 4.0f * c->g.footprint[gi] + 1e-4f * c->scene_diag;
    return v;
}

ic_result ic_ic_record_views(const ic_ctx *c, ic_record_view **out, uint32_t *count)
{
    uint32_t n = ic_cache_count(c->cache);
    *out = malloc(sizeof **out * (n ? n : 1));
    *count = 0;
    if (!*out)
        return IC_ERR_OOM;
    for (uint32_t i = 0; i < n; ++i) {
        ic_record rec;
        /* The hit stage's records serve hemisphere rays only: the image's records are listed. */
        if (ic_cache_get_record(c->cache, i, &rec) == IC_OK && rec.bounce != IC_HIT_KIND)
            (*out)[(*count)++] = view_of(c, &rec);
    }
    return IC_OK;
}

/* The outline of an elliptical record's extent: its edge in the tangent plane (semi-axes a_i·R_i and
 * a_i·ρ·R_i), projected point by point, so the ellipse appears as the camera sees it. */
static void draw_ellipse(const ic_ctx *c, ic_image *out, const ic_record *rec, const ic_record_view *v, ic_vec3 colour)
{
    const ic_camera *cam = &c->tr->scene->camera;
    float major = rec->accuracy * rec->radius, minor = major * rec->ellipse_ratio;
    ic_vec3 u = rec->ellipse_axis, w = v3_cross(rec->normal, u); /* minor and major axes */
    int steps = (int)(6.3f * v->radius_px) + 8;
    for (int k = 0; k < steps; ++k) {
        float t = 2.0f * IC_PI * (float)k / (float)steps, fx, fy, z;
        ic_vec3 q = v3_add(rec->position, v3_add(v3_scale(w, major * cosf(t)), v3_scale(u, minor * sinf(t))));
        if (ic_camera_project(cam, q, &fx, &fy, &z))
            put(out, (int)fx, (int)fy, colour);
    }
}

/* The factor that brings the median luminance of img's lit pixels (finite, above zero) to
 * IC_RECORDS_BACKGROUND_GREY; 1 where none is lit, 0 (and IC_ERR_OOM) when out of memory. The median, not
 * the mean, so that a lamp or a sunlit patch in view does not darken the rest. A double: below a median of
 * about 5e-40 (a denormal float) the factor is beyond a float's range, where it made black pixels NaN. */
static ic_result background_scale(const ic_image *img, double *scale)
{
    size_t pixels = (size_t)img->width * img->height, lit = 0;
    float *lum = malloc(sizeof *lum * (pixels ? pixels : 1));
    *scale = 0.0;
    if (!lum)
        return IC_ERR_OOM;
    for (size_t i = 0; i < pixels; ++i) {
        float y = v3_lum(v3(img->rgb[3 * i], img->rgb[3 * i + 1], img->rgb[3 * i + 2]));
        if (isfinite(y) && y > 0.0f)
            lum[lit++] = y;
    }
    *scale = 1.0;
    if (lit > 0) {
        *scale = IC_RECORDS_BACKGROUND_GREY / (double)ic_kth_smallest(lum, lit, lit / 2);
    }
    free(lum);
    return IC_OK;
}

/* Records the camera sees are drawn as a dot with a circle of their influence radius a_i·R_i (an
 * elliptical record: its ellipse, projected), over a copy of the image scaled to a fixed median grey
 * (background_scale), so that the image under the marks reads alike on dim and bright scenes, whatever
 * the exposure: irradiance records red in green rings (elliptical ones in cyan), radiance records yellow
 * in blue. */
ic_result ic_ic_records_image(const ic_ctx *c, const ic_image *beauty, ic_image *out)
{
    double scale;
    ic_result r = background_scale(beauty, &scale);
    if (r != IC_OK || (r = ic_image_create(out, beauty->width, beauty->height)) != IC_OK)
        return r;
    size_t n = (size_t)beauty->width * beauty->height * 3;
    for (size_t i = 0; i < n; ++i)
        out->rgb[i] = (float)(scale * beauty->rgb[i]);
    uint32_t count = ic_cache_count(c->cache);
    for (uint32_t i = 0; i < count; ++i) {
        ic_record rec;
        if (ic_cache_get_record(c->cache, i, &rec) != IC_OK || rec.bounce == IC_HIT_KIND)
            continue;
        ic_record_view v = view_of(c, &rec);
        if (!v.visible)
            continue;
        ic_vec3 ring = v.is_radiance ? v3(0.2f, 0.5f, 1.0f) : v3(0.1f, 1.0f, 0.2f);
        ic_vec3 dot = v.is_radiance ? v3(1.0f, 0.9f, 0.1f) : v3(1.0f, 0.15f, 0.1f);
        if (v.ellipse_ratio > 0.0f && v.radius_px >= 1.0f)
            draw_ellipse(c, out, &rec, &v, v3(0.1f, 0.9f, 0.9f));
        int steps = v.ellipse_ratio > 0.0f ? 0 : (int)(6.3f * v.radius_px) + 8;
        for (int k = 0; k < steps && v.radius_px >= 1.0f; ++k) {
            float a = 2.0f * IC_PI * (float)k / (float)steps;
            put(out, (int)(v.px + v.radius_px * cosf(a)), (int)(v.py + v.radius_px * sinf(a)), ring);
        }
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx)
                put(out, (int)v.px + dx, (int)v.py + dy, dot);
    }
    return IC_OK;
}

ic_result ic_ic_density_image(ic_ctx *c, ic_image *out)
{
    ic_result r = ic_image_create(out, c->g.width, c->g.height);
    if (r != IC_OK)
        return r;
    ic_cache_hint hint = {0}; /* raster order: neighbouring pixels mostly share a leaf */
    for (int y = 0; y < c->g.height; ++y) {
        for (int x = 0; x < c->g.width; ++x) {
            size_t i = (size_t)y * c->g.width + x;
            if (!c->g.valid[i])
                continue;
            ic_cache_lookup q = ic_cache_lookup_at(c->g.p[i], c->g.n[i], IC_ACCEPT_FINAL);
            ic_cache_estimate e;
            ic_cache_query_hinted(c->cache, &q, &hint, &e);
            out->rgb[3 * i] = out->rgb[3 * i + 1] = out->rgb[3 * i + 2] = (float)e.contributor_count;
        }
    }
    return IC_OK;
}

/* ---------------------------------------------------------------- the a_i map */

/* A blue → cyan → green → yellow → red ramp over t ∈ [0, 1]. */
static ic_vec3 ramp(float t)
{
    static const float k[5][3] = {{0.05f, 0.1f, 0.9f}, {0.0f, 0.8f, 0.9f}, {0.1f, 0.85f, 0.1f},
                                  {0.95f, 0.9f, 0.05f}, {0.9f, 0.05f, 0.05f}};
    t = ic_clampf(t, 0.0f, 1.0f) * 4.0f;
    int i = t >= 4.0f ? 3 : (int)t;
    float f = t - (float)i;
    return v3(k[i][0] + f * (k[i + 1][0] - k[i][0]), k[i][1] + f * (k[i + 1][1] - k[i][1]),
              k[i][2] + f * (k[i + 1][2] - k[i][2]));
}

ic_result ic_ic_amap_image(const ic_ctx *c, ic_image *out)
{
    ic_result r = ic_image_create(out, c->g.width, c->g.height);
    if (r != IC_OK)
        return r;
    ic_cache_contribution contrib_buf[LOOKUP_CAPACITY];
    const float a_max = c->o.cache.accuracy, span = log2f(IC_AMAP_RANGE);
    for (int y = 0; y < c->g.height; ++y) {
        for (int x = 0; x < c->g.width; ++x) {
            size_t i = (size_t)y * c->g.width + x;
            if (!c->g.valid[i])
                continue;
            ic_cache_lookup q = ic_cache_lookup_at(c->g.p[i], c->g.n[i], IC_ACCEPT_FINAL);
            q.contributions = contrib_buf;
            q.contribution_capacity = LOOKUP_CAPACITY;
            ic_cache_estimate e;
            if (!ic_cache_query(c->cache, &q, &e) || e.contributions_written == 0)
                continue;
            uint32_t best = 0;
            for (uint32_t k = 1; k < e.contributions_written; ++k)
                if (contrib_buf[k].weight > contrib_buf[best].weight)
                    best = k;
            ic_record rec;
            ic_cache_get_record(c->cache, contrib_buf[best].record, &rec);
            ic_vec3 col = ramp(log2f(a_max / rec.accuracy) / span);
            float *px = &out->rgb[3 * i];
            px[0] = col.x;
            px[1] = col.y;
            px[2] = col.z;
        }
    }
    return IC_OK;
}
