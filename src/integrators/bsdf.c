/* bsdf.c — Lambert, normalized modified Phong, mirror, smooth dielectric, and the dispatch to the rough
 * microfacet materials (bsdf.h). */
#include "bsdf.h"

#include "bsdf_microfacet.h"

#include "core/sampling.h"

void ic_bsdf_init(ic_bsdf *b, const ic_scene *scene, const ic_surface *s, ic_vec3 wo)
{
    const ic_material *m = &scene->materials[s->material];
    b->type = m->type;
    b->kd = ic_scene_albedo(scene, s);
    b->ks = m->ks;
    b->ns = m->ns > 0.0f ? m->ns : 1.0f;
    b->ior = m->ior > 0.0f ? m->ior : 1.5f;
    b->ng = s->ng;
    ic_vec3 n = s->ns;
    /* Opaque materials shade on the side the viewer is on. */
    if (b->type != IC_MAT_GLASS && b->type != IC_MAT_ROUGH_GLASS && v3_dot(wo, s->ng) < 0.0f) {
        n = v3_neg(n);
        b->ng = v3_neg(s->ng);
    }
    {
        /* A shading normal may face away from the viewer though the surface does not: a mapped normal, or
         * an interpolated one near a smooth mesh's silhouette (where every lobe returned 0: black
         * fringes). It is bent towards wo until wo stands sin 3° above its horizon: a mapped normal
         * whenever wo is lower than that, an interpolated one only when it faces away. A dielectric's
         * normal keeps pointing outside (its frame's +z is the outside, whichever side wo is on), so it is
         * bent on wo's side and turned back: bent as it was, a ray inside normal-mapped glass had its
         * normal flipped (total internal reflection lost, rough glass letting nothing out). */
        const float side = v3_dot(wo, b->ng) < 0.0f ? -1.0f : 1.0f;
        ic_vec3 sn = v3_scale(n, side);
        float c = v3_dot(wo, sn);
        if (m->normal_texture > 0 ? c < 0.0523f : c < 0.0f)
            n = v3_scale(v3_norm(v3_add(sn, v3_scale(wo, 0.0523f - c))), side);
    }
    b->frame = ic_frame_from_normal(n);
    /* records are keyed on the interpolated normal of a normal-mapped surface (docs/scene-format.md,
     * "Normal maps and the cache") */
    b->cache_n = m->normal_texture > 0 ? (v3_dot(s->ns_smooth, b->ng) < 0.0f ? v3_neg(s->ns_smooth) : s->ns_smooth) : n;
    float ld = v3_lum(b->kd), ls = v3_lum(b->ks);
    b->p_diffuse = (b->type == IC_MAT_GLOSSY) ? (ld + ls > 0.0f ? ld / (ld + ls) : 1.0f) : 1.0f;
    if (b->type == IC_MAT_TRANSLUCENT) { /* lobes picked by their albedos' luminance */
        b->kt = m->kt;
        b->kt_specular = m->kt_specular;
        float lt = v3_lum(b->kt), lst = v3_lum(b->kt_specular);
        b->p_diffuse = ld + lt + lst > 0.0f ? ld / (ld + lt + lst) : 1.0f;
        b->p_straight = lt + lst > 0.0f ? lst / (lt + lst) : 0.0f;
    }
    if (b->type == IC_MAT_CONDUCTOR || b->type == IC_MAT_PLASTIC || b->type == IC_MAT_ROUGH_GLASS) {
        float alpha = m->alpha, metallic = m->metallic;
        if (m->roughness_texture > 0 || m->metallic_texture > 0)
            ic_scene_microfacet_params(scene, s, &alpha, &metallic);
        ic_mf_init(b, m, alpha, metallic, fmaxf(v3_dot(wo, n), 0.0f), ic_scene_texture_tint(scene, s));
    }
}

void ic_thin_glass(float cos_i, float ior, ic_vec3 tn, ic_vec3 *R, ic_vec3 *T)
{
    float ci = ic_clampf(fabsf(cos_i), 1e-6f, 1.0f);
    float ct = sqrtf(1.0f - (1.0f - ci * ci) / (ior * ior)); /* inside the sheet */
    float rs = (ci - ior * ct) / (ci + ior * ct), rp = (ior * ci - ct) / (ior * ci + ct);
    float r[2] = {rs * rs, rp * rp};
    float tc[3] = {tn.x, tn.y, tn.z}, rr[3] = {0, 0, 0}, tt[3] = {0, 0, 0};
    for (int c = 0; c < 3; ++c) {
        float d = tc[c] > 0.0f ? powf(fminf(tc[c], 1.0f), 1.0f / ct) : 0.0f; /* one slanted pass */
        for (int k = 0; k < 2; ++k) {
            float denom = 1.0f - r[k] * r[k] * d * d;
            rr[c] += 0.5f * (r[k] + (1.0f - r[k]) * (1.0f - r[k]) * r[k] * d * d / denom);
            tt[c] += 0.5f * (1.0f - r[k]) * (1.0f - r[k]) * d / denom;
        }
    }
    *R = v3(rr[0], rr[1], rr[2]);
    *T = v3(tt[0], tt[1], tt[2]);
}

/* The thin pane's probability of reflecting: R's share of R + T by luminance. */
static float thin_glass_reflect(ic_vec3 R, ic_vec3 T)
{
    float lr = v3_lum(R), lt = v3_lum(T);
    return lr + lt > 0.0f ? lr / (lr + lt) : 0.0f;
}

float ic_bsdf_reflect_probability(const ic_bsdf *b, ic_vec3 wo)
{
    if (b->type == IC_MAT_GLASS || b->type == IC_MAT_ROUGH_GLASS)
        return ic_fresnel_dielectric(v3_dot(wo, b->frame.n), b->ior);
    if (b->type == IC_MAT_THIN_GLASS) {
        ic_vec3 R, T;
        ic_thin_glass(v3_dot(wo, b->frame.n), b->ior, b->ks, &R, &T);
        return thin_glass_reflect(R, T);
    }
    return 1.0f;
}

static int is_microfacet(const ic_bsdf *b) { return b->type == IC_MAT_CONDUCTOR || b->type == IC_MAT_PLASTIC; }

ic_vec3 ic_bsdf_glossy_local(const ic_bsdf *b, ic_vec3 wi_local, ic_vec3 wo_local)
{
    if (!ic_bsdf_has_glossy(b) || wi_local.z <= 0.0f || wo_local.z <= 0.0f || b->type == IC_MAT_TRANSLUCENT)
        return v3s(0.0f);
    if (is_microfacet(b))
        return ic_mf_glossy(b, wo_local, wi_local);
    ic_vec3 r = v3(-wo_local.x, -wo_local.y, wo_local.z);
    float c = fmaxf(0.0f, v3_dot(r, wi_local));
    return v3_scale(b->ks, (b->ns + 2.0f) / (2.0f * IC_PI) * powf(c, b->ns));
}

static float phong_cos(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi)
{
    ic_vec3 r = v3_reflect(wo, b->frame.n);
    return fmaxf(0.0f, v3_dot(r, wi));
}

/* Which side of the translucent sheet wi leaves on: 1 wo's, −1 the other, 0 where the shading and geometric
 * normals disagree (no light through interpolated normals). */
static int translucent_side(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi)
{
    float ci = v3_dot(wi, b->frame.n), gi = v3_dot(wi, b->ng);
    if (v3_dot(wo, b->frame.n) <= 0.0f)
        return 0;
    return ci > 0.0f && gi > 0.0f ? 1 : ci < 0.0f && gi < 0.0f ? -1 : 0;
}

void ic_bsdf_eval_lobes(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi, ic_vec3 *diffuse, ic_vec3 *glossy)
{
    *diffuse = *glossy = v3s(0.0f);
    if (b->type == IC_MAT_TRANSLUCENT) {
        int side = translucent_side(b, wo, wi);
        if (side > 0)
            *diffuse = v3_scale(b->kd, IC_INV_PI);
        else if (side < 0)
            *glossy = v3_scale(b->kt, IC_INV_PI);
        return;
    }
    if (!ic_bsdf_has_smooth(b) || v3_dot(wo, b->frame.n) <= 0.0f || v3_dot(wi, b->frame.n) <= 0.0f ||
        v3_dot(wi, b->ng) <= 0.0f)
        return;
    if (is_microfacet(b)) {
        *diffuse = v3_scale(b->kd, IC_INV_PI * ic_bsdf_diffuse_factor(b, v3_dot(wi, b->frame.n)));
        *glossy = ic_mf_glossy(b, ic_frame_to_local(&b->frame, wo), ic_frame_to_local(&b->frame, wi));
        return;
    }
    *diffuse = v3_scale(b->kd, IC_INV_PI);
    if (b->type == IC_MAT_GLOSSY)
        *glossy = v3_scale(b->ks, (b->ns + 2.0f) / (2.0f * IC_PI) * powf(phong_cos(b, wo, wi), b->ns));
}

float ic_bsdf_pdf_glossy(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi)
{
    if (b->type == IC_MAT_TRANSLUCENT) /* the diffuse transmission's cosine below the sheet */
        return ic_bsdf_has_glossy(b) && translucent_side(b, wo, wi) < 0
                   ? (1.0f - b->p_straight) * fabsf(v3_dot(wi, b->frame.n)) * IC_INV_PI
                   : 0.0f;
    if (!ic_bsdf_has_glossy(b) || v3_dot(wi, b->frame.n) <= 0.0f || v3_dot(wo, b->frame.n) <= 0.0f)
        return 0.0f;
    if (is_microfacet(b))
        return ic_mf_pdf_glossy(b, ic_frame_to_local(&b->frame, wo), ic_frame_to_local(&b->frame, wi));
    return (b->ns + 1.0f) / (2.0f * IC_PI) * powf(phong_cos(b, wo, wi), b->ns);
}

/* The GGX lobe alone, by its visible normals (weight = f_glossy·cos/pdf_glossy). */
static int sample_microfacet_glossy(const ic_bsdf *b, ic_vec3 wo, float u1, float u2, ic_bsdf_sample *out)
{
    ic_vec3 wo_l = ic_frame_to_local(&b->frame, wo);
    ic_vec3 wi_l = ic_mf_sample_glossy(b, wo_l, u1, u2);
    out->wi = ic_frame_to_world(&b->frame, wi_l);
    if (wi_l.z <= 0.0f || v3_dot(out->wi, b->ng) <= 0.0f)
        return 0;
    out->pdf = ic_mf_pdf_glossy(b, wo_l, wi_l);
    if (!(out->pdf > 0.0f))
        return 0;
    out->weight = v3_scale(ic_mf_glossy(b, wo_l, wi_l), wi_l.z / out->pdf);
    return !v3_is_black(out->weight);
}

/* The translucent sheet's transmission: straight on with probability p_straight (a delta), else a cosine
 * below the sheet (weight = f·|cos|/pdf of this lobe alone). */
static int sample_transmission(const ic_bsdf *b, ic_vec3 wo, float u1, float u2, ic_bsdf_sample *out)
{
    if (u1 < b->p_straight) {
        out->wi = v3_neg(wo);
        out->weight = v3_scale(b->kt_specular, 1.0f / b->p_straight);
        out->pdf = 1.0f;
        out->is_specular = 1;
        return 1;
    }
    ic_vec3 l = ic_warp_cosine_hemisphere(fminf((u1 - b->p_straight) / (1.0f - b->p_straight), 0.99999994f), u2);
    out->wi = ic_frame_to_world(&b->frame, v3(l.x, l.y, -l.z));
    out->pdf = ic_bsdf_pdf_glossy(b, wo, out->wi);
    if (!(out->pdf > 0.0f))
        return 0;
    out->weight = v3_scale(b->kt, 1.0f / (1.0f - b->p_straight));
    return !v3_is_black(out->weight);
}

int ic_bsdf_sample_glossy(const ic_bsdf *b, ic_vec3 wo, float u1, float u2, ic_bsdf_sample *out)
{
    out->is_specular = 0;
    if (!ic_bsdf_has_glossy(b) || v3_dot(wo, b->frame.n) <= 0.0f)
        return 0;
    if (is_microfacet(b))
        return sample_microfacet_glossy(b, wo, u1, u2, out);
    if (b->type == IC_MAT_TRANSLUCENT)
        return sample_transmission(b, wo, u1, u2, out);
    ic_frame rf = ic_frame_from_normal(v3_reflect(wo, b->frame.n));
    out->wi = ic_frame_to_world(&rf, ic_warp_phong_lobe(u1, u2, b->ns));
    float cos_i = v3_dot(out->wi, b->frame.n);
    if (cos_i <= 0.0f || v3_dot(out->wi, b->ng) <= 0.0f)
        return 0;
    out->pdf = ic_bsdf_pdf_glossy(b, wo, out->wi);
    /* f/pdf of the normalized Phong lobe sampled exactly: ks·(n+2)/(n+1)·cos θ_i. */
    out->weight = v3_scale(b->ks, (b->ns + 2.0f) / (b->ns + 1.0f) * cos_i);
    return out->pdf > 0.0f;
}

/* The rough glass's wi in the local frame, or 0 if wi crosses the geometric surface on the other side of
 * the shading normal's (which would leak light). */
static int rough_glass_local(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi, ic_vec3 *wo_l, ic_vec3 *wi_l)
{
    *wo_l = ic_frame_to_local(&b->frame, wo);
    *wi_l = ic_frame_to_local(&b->frame, wi);
    return v3_dot(wi, b->ng) * wi_l->z > 0.0f;
}

ic_vec3 ic_bsdf_eval(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi)
{
    if (b->type == IC_MAT_TRANSLUCENT) {
        ic_vec3 fd, fg;
        ic_bsdf_eval_lobes(b, wo, wi, &fd, &fg);
        return v3_add(fd, fg);
    }
    if (b->type == IC_MAT_ROUGH_GLASS) {
        ic_vec3 wo_l, wi_l;
        return rough_glass_local(b, wo, wi, &wo_l, &wi_l) ? v3s(ic_mf_dielectric_f(b, wo_l, wi_l)) : v3s(0.0f);
    }
    float cos_o = v3_dot(wo, b->frame.n), cos_i = v3_dot(wi, b->frame.n);
    /* Both directions in the upper hemisphere of the shading normal and on the same side of the
     * geometric normal (prevents light leaking through shading-normal interpolation). */
    if (cos_o <= 0.0f || cos_i <= 0.0f || v3_dot(wi, b->ng) <= 0.0f)
        return v3s(0.0f);
    switch (b->type) {
    case IC_MAT_DIFFUSE:
        return v3_scale(b->kd, IC_INV_PI);
    case IC_MAT_GLOSSY: {
        float c = phong_cos(b, wo, wi);
        float lobe = (b->ns + 2.0f) / (2.0f * IC_PI) * powf(c, b->ns);
        return v3_add(v3_scale(b->kd, IC_INV_PI), v3_scale(b->ks, lobe));
    }
    case IC_MAT_CONDUCTOR:
    case IC_MAT_PLASTIC: {
        ic_vec3 fd, fg;
        ic_bsdf_eval_lobes(b, wo, wi, &fd, &fg);
        return v3_add(fd, fg);
    }
    default:
        return v3s(0.0f);
    }
}

float ic_bsdf_pdf(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi)
{
    if (b->type == IC_MAT_TRANSLUCENT) {
        int side = translucent_side(b, wo, wi);
        return side > 0   ? b->p_diffuse * v3_dot(wi, b->frame.n) * IC_INV_PI
               : side < 0 ? (1.0f - b->p_diffuse) * ic_bsdf_pdf_glossy(b, wo, wi)
                          : 0.0f;
    }
    if (b->type == IC_MAT_ROUGH_GLASS) {
        ic_vec3 wo_l, wi_l;
        return rough_glass_local(b, wo, wi, &wo_l, &wi_l) ? ic_mf_dielectric_pdf(b, wo_l, wi_l) : 0.0f;
    }
    float cos_i = v3_dot(wi, b->frame.n);
    if (cos_i <= 0.0f || v3_dot(wo, b->frame.n) <= 0.0f)
        return 0.0f;
    switch (b->type) {
    case IC_MAT_DIFFUSE:
        return cos_i * IC_INV_PI;
    case IC_MAT_GLOSSY: {
        float c = phong_cos(b, wo, wi);
        float pd = cos_i * IC_INV_PI;
        float ps = (b->ns + 1.0f) / (2.0f * IC_PI) * powf(c, b->ns);
        return b->p_diffuse * pd + (1.0f - b->p_diffuse) * ps;
    }
    case IC_MAT_CONDUCTOR:
    case IC_MAT_PLASTIC: {
        float ps = ic_mf_pdf_glossy(b, ic_frame_to_local(&b->frame, wo), ic_frame_to_local(&b->frame, wi));
        return b->p_diffuse * cos_i * IC_INV_PI + (1.0f - b->p_diffuse) * ps;
    }
    default:
        return 0.0f;
    }
}

int ic_bsdf_sample_dir(const ic_bsdf *b, ic_vec3 wo, float u0, float u1, float u2, ic_bsdf_sample *out)
{
    out->is_specular = 0;
    switch (b->type) {
    case IC_MAT_MIRROR:
        out->wi = v3_reflect(wo, b->frame.n);
        out->weight = b->ks;
        out->pdf = 1.0f;
        out->is_specular = 1;
        return v3_dot(out->wi, b->ng) > 0.0f;
    case IC_MAT_GLASS: {
        ic_vec3 n = b->frame.n;
        float cos_o = v3_dot(wo, n);
        float F = ic_fresnel_dielectric(cos_o, b->ior);
        out->is_specular = 1;
        out->pdf = 1.0f;
        if (u0 < F) {
            out->wi = v3_reflect(wo, n);
            out->weight = v3s(1.0f);
            return 1;
        }
        /* Refraction: eta relative to the side wo is on. */
        float eta = cos_o > 0.0f ? 1.0f / b->ior : b->ior; /* n_i / n_t */
        ic_vec3 nn = cos_o > 0.0f ? n : v3_neg(n);
        float ci = fabsf(cos_o);
        float sin2_t = eta * eta * (1.0f - ci * ci);
        if (sin2_t >= 1.0f)
            return 0;
        float ct = sqrtf(1.0f - sin2_t);
        out->wi = v3_add(v3_scale(v3_neg(wo), eta), v3_scale(nn, eta * ci - ct));
        out->wi = v3_norm(out->wi);
        /* Radiance changes by (n_t/n_i)^2 across the interface, but the factors cancel over a closed
         * dielectric (in, then out), and light sources are never inside glass in our scenes; weight 1
         * keeps the estimator energy-consistent with the eye-side convention of most renderers. */
        out->weight = v3s(1.0f);
        return 1;
    }
    case IC_MAT_THIN_GLASS: { /* the frame faces wo (a pane has no inside); transmission goes straight on */
        ic_vec3 R, T;
        ic_thin_glass(v3_dot(wo, b->frame.n), b->ior, b->ks, &R, &T);
        float p = thin_glass_reflect(R, T);
        out->is_specular = 1;
        out->pdf = 1.0f;
        if (u0 < p) {
            out->wi = v3_reflect(wo, b->frame.n);
            out->weight = v3_scale(R, 1.0f / p);
            return v3_dot(out->wi, b->ng) > 0.0f;
        }
        out->wi = v3_neg(wo);
        out->weight = v3_scale(T, 1.0f / (1.0f - p));
        return p < 1.0f;
    }
    case IC_MAT_CONDUCTOR:
        return ic_bsdf_sample_glossy(b, wo, u1, u2, out);
    case IC_MAT_TRANSLUCENT: {
        if (v3_dot(wo, b->frame.n) <= 0.0f)
            return 0;
        if (u0 < b->p_diffuse) {
            out->wi = ic_frame_to_world(&b->frame, ic_warp_cosine_hemisphere(u1, u2));
        } else {
            if (!sample_transmission(b, wo, u1, u2, out))
                return 0;
            if (out->is_specular) {
                out->weight = v3_scale(out->weight, 1.0f / (1.0f - b->p_diffuse));
                return 1;
            }
        }
        out->pdf = ic_bsdf_pdf(b, wo, out->wi);
        if (!(out->pdf > 0.0f))
            return 0;
        out->weight = v3_scale(ic_bsdf_eval(b, wo, out->wi), fabsf(v3_dot(out->wi, b->frame.n)) / out->pdf);
        return !v3_is_black(out->weight);
    }
    case IC_MAT_ROUGH_GLASS: {
        /* followed like the smooth glass (is_specular: no light sampling at the vertex, so what its
         * sampled direction finds counts fully); the weight is the lobe's f·|cos|/pdf */
        ic_vec3 wo_l = ic_frame_to_local(&b->frame, wo), wi_l;
        out->is_specular = 1;
        if (!ic_mf_dielectric_sample(b, wo_l, u0, u1, u2, &wi_l))
            return 0;
        out->wi = ic_frame_to_world(&b->frame, wi_l);
        out->pdf = ic_bsdf_pdf(b, wo, out->wi);
        if (!(out->pdf > 0.0f))
            return 0;
        out->weight = v3s(ic_mf_dielectric_f(b, wo_l, wi_l) * fabsf(wi_l.z) / out->pdf);
        return 1;
    }
    case IC_MAT_DIFFUSE:
    case IC_MAT_GLOSSY:
    case IC_MAT_PLASTIC: {
        if (v3_dot(wo, b->frame.n) <= 0.0f)
            return 0;
        if (u0 < b->p_diffuse) {
            out->wi = ic_frame_to_world(&b->frame, ic_warp_cosine_hemisphere(u1, u2));
        } else if (b->type == IC_MAT_PLASTIC) {
            out->wi = ic_frame_to_world(&b->frame, ic_mf_sample_glossy(b, ic_frame_to_local(&b->frame, wo), u1, u2));
        } else {
            ic_vec3 r = v3_reflect(wo, b->frame.n);
            ic_frame rf = ic_frame_from_normal(r);
            out->wi = ic_frame_to_world(&rf, ic_warp_phong_lobe(u1, u2, b->ns));
        }
        out->pdf = ic_bsdf_pdf(b, wo, out->wi);
        if (out->pdf <= 0.0f)
            return 0;
        ic_vec3 f = ic_bsdf_eval(b, wo, out->wi);
        float cos_i = v3_dot(out->wi, b->frame.n);
        out->weight = v3_scale(f, cos_i / out->pdf);
        return !v3_is_black(out->weight);
    }
    }
    return 0;
}
