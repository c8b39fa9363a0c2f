/*
 * scene_query.c — surface attributes at a hit, albedo (texture look-up) and emission.
 *
 * Barycentrics follow Embree: p = (1-u-v)·p0 + u·p1 + v·p2. The geometric normal follows the winding,
 * normalize((p1-p0) × (p2-p0)); it decides which side of a one-sided emitter emits. The shading normal
 * is interpolated from vertex normals, or equals ng where the mesh has none (a zero vertex normal marks
 * a vertex without one, see mesh_import.c), and is flipped into ng's hemisphere so that shading and
 * geometry agree about which side is the front.
 *
 * Normal maps (a material's normal_texture): the texel c gives the tangent-space normal
 * (2c − 1) with x and y scaled by normal_scale, in the frame (T, B, n) of the interpolated shading normal n,
 * the tangent T (the mesh's, else ∂p/∂u of the triangle's texture coordinates) made orthogonal to n and
 * B = ±n × T, its sign the bitangent's handedness (the mesh's w, else that of ∂p/∂v); this is the frame
 * MikkTSpace bakes against (Mikkelsen 2008 §4). A mapped normal is kept at least sin 3° above the geometric
 * horizon (bent towards ng), so that no texel turns the front of a surface into its back.
 */
#include "scene/scene.h"

#include <math.h>

static ic_vec3 texture_lookup(const ic_texture *t, float s_coord, float t_coord);

/* Least height of a mapped normal above the geometric horizon: sin 3°. */
#define NORMAL_MAP_MIN_COS 0.0523f

/* Tangent (unit, orthogonal to n) and the bitangent's sign at barycentrics (w, u, v) of the triangle with
 * vertex indices idx; 0 if the triangle's texture coordinates are degenerate and the mesh gives none. */
static int shading_tangent(const ic_scene *scene, const uint32_t *idx, float w, float u, float v, ic_vec3 n,
                           ic_vec3 *t_out, float *sign)
{
    ic_vec3 t = v3s(0.0f);
    *sign = 1.0f;
    if (scene->tangents) {
        const float *a = scene->tangents + 4 * (size_t)idx[0], *b = scene->tangents + 4 * (size_t)idx[1],
                    *c = scene->tangents + 4 * (size_t)idx[2];
        if (a[3] != 0.0f && b[3] != 0.0f && c[3] != 0.0f) {
            t = v3(w * a[0] + u * b[0] + v * c[0], w * a[1] + u * b[1] + v * c[1], w * a[2] + u * b[2] + v * c[2]);
            *sign = w * a[3] + u * b[3] + v * c[3] < 0.0f ? -1.0f : 1.0f;
        }
    }
    if (v3_is_black(t) && scene->uvs) {
        ic_vec3 p0 = scene->positions[idx[0]];
        ic_vec3 e1 = v3_sub(scene->positions[idx[1]], p0), e2 = v3_sub(scene->positions[idx[2]], p0);
        const float *t0 = scene->uvs + 2 * (size_t)idx[0], *t1 = scene->uvs + 2 * (size_t)idx[1],
                    *t2 = scene->uvs + 2 * (size_t)idx[2];
        float du1 = t1[0] - t0[0], dv1 = t1[1] - t0[1], du2 = t2[0] - t0[0], dv2 = t2[1] - t0[1];
        float det = du1 * dv2 - du2 * dv1;
        if (det == 0.0f || !isfinite(det))
            return 0;
        ic_vec3 dpdu = v3_scale(v3_sub(v3_scale(e1, dv2), v3_scale(e2, dv1)), 1.0f / det);
        ic_vec3 dpdv = v3_scale(v3_sub(v3_scale(e2, du1), v3_scale(e1, du2)), 1.0f / det);
        t = dpdu;
        *sign = v3_dot(v3_cross(n, dpdu), dpdv) < 0.0f ? -1.0f : 1.0f;
    }
    t = v3_sub(t, v3_scale(n, v3_dot(n, t)));
    float len = v3_len(t);
    if (!(len > 1e-12f) || !isfinite(len))
        return 0;
    *t_out = v3_scale(t, 1.0f / len);
    return 1;
}

/* s->ns replaced by the material's normal map at s->uv (see the top of the file). */
static void apply_normal_map(const ic_scene *scene, const ic_material *m, const uint32_t *idx, float w, float u,
                             float v, ic_surface *s)
{
    const ic_texture *tex = &scene->textures[m->normal_texture - 1];
    ic_vec3 t;
    float sign;
    if (tex->width <= 0 || !isfinite(s->uv[0]) || !isfinite(s->uv[1]) ||
        !shading_tangent(scene, idx, w, u, v, s->ns, &t, &sign))
        return;
    ic_vec3 c = texture_lookup(tex, s->uv[0], s->uv[1]);
    float scale = m->normal_scale;
    ic_vec3 b = v3_scale(v3_cross(s->ns, t), sign);
    ic_vec3 n = v3_add(v3_add(v3_scale(t, (2.0f * c.x - 1.0f) * scale), v3_scale(b, (2.0f * c.y - 1.0f) * scale)),
                       v3_scale(s->ns, 2.0f * c.z - 1.0f));
    float h = v3_dot(n, s->ng), len = v3_len(n);
    if (!(len > 1e-12f) || !isfinite(len))
        return;
    n = v3_scale(n, 1.0f / len);
    h /= len;
    if (h < NORMAL_MAP_MIN_COS) { /* bend towards ng until it stands NORMAL_MAP_MIN_COS above the horizon */
        ic_vec3 side = v3_sub(n, v3_scale(s->ng, h));
        float sl = v3_len(side);
        n = sl > 1e-12f ? v3_add(v3_scale(side, sqrtf(1.0f - NORMAL_MAP_MIN_COS * NORMAL_MAP_MIN_COS) / sl),
                                 v3_scale(s->ng, NORMAL_MAP_MIN_COS))
                        : s->ng;
    }
    s->ns = n;
}

void ic_scene_surface(const ic_scene *scene, uint32_t tri, float u, float v, ic_surface *s)
{
    const uint32_t *idx = scene->triangles + 3 * (size_t)tri;
    float w = 1.0f - u - v;
    s->offset_floor = scene->ray_offset_floor;
    ic_vec3 p0 = scene->positions[idx[0]], p1 = scene->positions[idx[1]], p2 = scene->positions[idx[2]];
    s->p = v3_add(v3_add(v3_scale(p0, w), v3_scale(p1, u)), v3_scale(p2, v));
    /* v3_norm_any: the loaders keep triangles whose |e1 x e2|² leaves a float (edges beyond 4e9 or below 1e-10) */
    s->ng = v3_norm_any(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
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
    s->ns_smooth = s->ns;
    if (scene->has_normal_maps && scene->materials[s->material].normal_texture > 0)
        apply_normal_map(scene, &scene->materials[s->material], idx, w, u, v, s);
}

/* Bilinear texel look-up with repeat wrap; uv (0,0) is the image's bottom-left corner (OBJ/assimp
 * convention) while the image's first row is its top. The four texels' offsets are found once (one
 * wrap per axis, the second column and row by a step that wraps at the edge), and each is read as
 * three channels in a row. */
static ic_vec3 texture_lookup(const ic_texture *t, float s_coord, float t_coord)
{
    float x = (s_coord - floorf(s_coord)) * (float)t->width - 0.5f;
    float y = (1.0f - (t_coord - floorf(t_coord))) * (float)t->height - 0.5f;
    float fx0 = floorf(x), fy0 = floorf(y);
    float fx = x - fx0, fy = y - fy0;
    int x0 = (int)fx0 % t->width, y0 = (int)fy0 % t->height;
    x0 += x0 < 0 ? t->width : 0;
    y0 += y0 < 0 ? t->height : 0;
    int x1 = x0 + 1 == t->width ? 0 : x0 + 1, y1 = y0 + 1 == t->height ? 0 : y0 + 1;
    const size_t row = (size_t)t->width, i00 = 3 * ((size_t)y0 * row + (size_t)x0),
                 i01 = 3 * ((size_t)y0 * row + (size_t)x1), i10 = 3 * ((size_t)y1 * row + (size_t)x0),
                 i11 = 3 * ((size_t)y1 * row + (size_t)x1);
    float v[4][3];
    if (t->srgb8) {
        const uint8_t *b = t->srgb8;
        for (int c = 0; c < 3; ++c) {
            v[0][c] = t->linear[b[i00 + (size_t)c]];
            v[1][c] = t->linear[b[i01 + (size_t)c]];
            v[2][c] = t->linear[b[i10 + (size_t)c]];
            v[3][c] = t->linear[b[i11 + (size_t)c]];
        }
    } else {
        for (int c = 0; c < 3; ++c) {
            v[0][c] = t->rgb[i00 + (size_t)c];
            v[1][c] = t->rgb[i01 + (size_t)c];
            v[2][c] = t->rgb[i10 + (size_t)c];
            v[3][c] = t->rgb[i11 + (size_t)c];
        }
    }
    ic_vec3 r;
    float *out = &r.x;
    for (int c = 0; c < 3; ++c)
        out[c] = (1.0f - fy) * ((1.0f - fx) * v[0][c] + fx * v[1][c]) + fy * ((1.0f - fx) * v[2][c] + fx * v[3][c]);
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

void ic_scene_microfacet_params(const ic_scene *scene, const ic_surface *s, float *alpha, float *metallic)
{
    const ic_material *m = &scene->materials[s->material];
    *alpha = m->alpha;
    *metallic = m->metallic;
    if (!isfinite(s->uv[0]) || !isfinite(s->uv[1]))
        return;
    if (m->roughness_texture > 0) {
        ic_vec3 t = texture_lookup(&scene->textures[m->roughness_texture - 1], s->uv[0], s->uv[1]);
        if (m->roughness_is_alpha) /* Mitsuba: the texture is α */
            *alpha = fminf(m->alpha * (0.2126f * t.x + 0.7152f * t.y + 0.0722f * t.z), 1.0f);
        else /* glTF: roughness = factor × g, α = roughness² */
            *alpha = m->alpha * t.y * t.y;
    }
    if (m->metallic_texture > 0)
        *metallic = m->metallic * texture_lookup(&scene->textures[m->metallic_texture - 1], s->uv[0], s->uv[1]).z;
}

const float *ic_scene_coat_table(const ic_material *m, float alpha, float *average)
{
    *average = m->coat_albedo_avg;
    if (!m->coat_albedo_rough)
        return m->coat_albedo;
    int j = (int)(sqrtf(fmaxf(alpha, 0.0f)) * (IC_COAT_ROUGH_STEPS - 1) + 0.5f);
    j = j < 0 ? 0 : j > IC_COAT_ROUGH_STEPS - 1 ? IC_COAT_ROUGH_STEPS - 1 : j;
    *average = m->coat_albedo_rough[j * (IC_COAT_TABLE + 1) + IC_COAT_TABLE];
    return m->coat_albedo_rough + j * (IC_COAT_TABLE + 1);
}

ic_vec3 ic_scene_emission(const ic_scene *scene, const ic_surface *s, ic_vec3 wo)
{
    const ic_material *m = &scene->materials[s->material];
    if (v3_is_black(m->emission))
        return m->emission;
    if ((!m->two_sided_emission && v3_dot(s->ng, wo) <= 0.0f) || !ic_material_emits_towards(m, wo))
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
