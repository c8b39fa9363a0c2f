/*
 * scene_query.c — surface attributes at a hit, albedo (texture look-up) and emission.
 *
 * Barycentrics follow Embree: p = (1-u-v)·p0 + u·p1 + v·p2. The geometric normal follows the winding,
 * normalize((p1-p0) × (p2-p0)); it decides which side of a one-sided emitter emits. The shading normal
 * is interpolated from vertex normals, or equals ng where the mesh has none (a zero vertex normal marks
 * a vertex without one, see mesh_import.c), and is flipped into ng's hemisphere so that shading and
 * geometry agree about which side is the front.
 */
#include "scene/scene.h"

#include <math.h>

void ic_scene_surface(const ic_scene *scene, uint32_t tri, float u, float v, ic_surface *s)
{
    const uint32_t *idx = scene->triangles + 3 * (size_t)tri;
    float w = 1.0f - u - v;
    ic_vec3 p0 = scene->positions[idx[0]], p1 = scene->positions[idx[1]], p2 = scene->positions[idx[2]];
    s->p = v3_add(v3_add(v3_scale(p0, w), v3_scale(p1, u)), v3_scale(p2, v));
    s->ng = v3_norm(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
    s->ns = s->ng;
    if (scene->normals) {
        ic_vec3 n0 = scene->normals[idx[0]], n1 = scene->normals[idx[1]], n2 = scene->normals[idx[2]];
        if (!v3_is_black(n0) && !v3_is_black(n1) && !v3_is_black(n2)) {
            ic_vec3 n = v3_add(v3_add(v3_scale(n0, w), v3_scale(n1, u)), v3_scale(n2, v));
            float len = v3_len(n);
            if (len > 1e-12f && isfinite(len)) {
                n = v3_scale(n, 1.0f / len);
                s->ns = v3_dot(n, s->ng) < 0.0f ? v3_neg(n) : n;
            }
        }
    }
    if (scene->uvs) {
        const float *t0 = scene->uvs + 2 * (size_t)idx[0], *t1 = scene->uvs + 2 * (size_t)idx[1],
                    *t2 = scene->uvs + 2 * (size_t)idx[2];
        s->uv[0] = w * t0[0] + u * t1[0] + v * t2[0];
        s->uv[1] = w * t0[1] + u * t1[1] + v * t2[1];
    } else {
        s->uv[0] = s->uv[1] = 0.0f;
    }
    s->material = scene->triangle_material[tri];
    s->triangle = tri;
}

/* Bilinear texel look-up with repeat wrap; uv (0,0) is the image's bottom-left corner (OBJ/assimp
 * convention) while the image's first row is its top. */
static ic_vec3 texture_lookup(const ic_texture *t, float s_coord, float t_coord)
{
    float x = (s_coord - floorf(s_coord)) * (float)t->width - 0.5f;
    float y = (1.0f - (t_coord - floorf(t_coord))) * (float)t->height - 0.5f;
    float fx0 = floorf(x), fy0 = floorf(y);
    float fx = x - fx0, fy = y - fy0;
    int x0 = (int)fx0, y0 = (int)fy0;
    int xs[2], ys[2];
    for (int k = 0; k < 2; ++k) {
        int xi = (x0 + k) % t->width, yi = (y0 + k) % t->height;
        xs[k] = xi < 0 ? xi + t->width : xi;
        ys[k] = yi < 0 ? yi + t->height : yi;
    }
    ic_vec3 r;
    float *out = &r.x;
    for (int c = 0; c < 3; ++c) {
        float a = ic_texture_value(t, 3 * ((size_t)ys[0] * (size_t)t->width + (size_t)xs[0]) + (size_t)c);
        float b = ic_texture_value(t, 3 * ((size_t)ys[0] * (size_t)t->width + (size_t)xs[1]) + (size_t)c);
        float d = ic_texture_value(t, 3 * ((size_t)ys[1] * (size_t)t->width + (size_t)xs[0]) + (size_t)c);
        float e = ic_texture_value(t, 3 * ((size_t)ys[1] * (size_t)t->width + (size_t)xs[1]) + (size_t)c);
        out[c] = (1.0f - fy) * ((1.0f - fx) * a + fx * b) + fy * ((1.0f - fx) * d + fx * e);
    }
    return r;
}

ic_vec3 ic_scene_albedo(const ic_scene *scene, const ic_surface *s)
{
    const ic_material *m = &scene->materials[s->material];
    if (m->kd_texture < 0 || (uint32_t)m->kd_texture >= scene->texture_count)
        return m->kd;
    const ic_texture *t = &scene->textures[m->kd_texture];
    if (t->width <= 0 || t->height <= 0 || !isfinite(s->uv[0]) || !isfinite(s->uv[1]))
        return m->kd;
    return v3_mul(m->kd, texture_lookup(t, s->uv[0], s->uv[1]));
}

ic_vec3 ic_scene_texture_tint(const ic_scene *scene, const ic_surface *s)
{
    const ic_material *m = &scene->materials[s->material];
    if (m->kd_texture < 0 || (uint32_t)m->kd_texture >= scene->texture_count)
        return v3s(1.0f);
    const ic_texture *t = &scene->textures[m->kd_texture];
    if (t->width <= 0 || t->height <= 0 || !isfinite(s->uv[0]) || !isfinite(s->uv[1]))
        return v3s(1.0f);
    return texture_lookup(t, s->uv[0], s->uv[1]);
}

ic_vec3 ic_scene_emission(const ic_scene *scene, const ic_surface *s, ic_vec3 wo)
{
    const ic_material *m = &scene->materials[s->material];
    if (v3_is_black(m->emission))
        return m->emission;
    if (!m->two_sided_emission && v3_dot(s->ng, wo) <= 0.0f)
        return v3s(0.0f);
    return m->emission;
}

unsigned ic_scene_light_count(const ic_scene *scene)
{
    if (!scene)
        return 0;
    unsigned n = scene->tri_light_count;
    for (uint32_t i = 0; i < scene->point_light_count; ++i)
        n += !v3_is_black(scene->point_lights[i].intensity);
    n += scene->sun.enabled && !v3_is_black(scene->sun.irradiance);
    n += scene->env.enabled && !v3_is_black(scene->env.radiance);
    return n;
}
