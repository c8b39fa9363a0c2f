/*
 * radiance_material.c — a Radiance modifier as irrcache sees it: materials mapped onto irrcache's, the
 * modifiers that only name another (alias, illum, the mixtures), and patterns and textures, which are not
 * rendered. The mapping follows the definitions of Radiance's material reference (Larson & Shakespeare 1998) and is
 * documented in docs/scene-format.md:
 *
 *   plastic, metal (red green blue spec rough): Radiance reflects spec specularly (white for plastic,
 *   coloured for metal) and colour·(1 − spec) diffusely. spec 0 is a Lambertian colour. Otherwise a
 *   GGX-coated plastic (Walter et al. 2007) whose coat reflects spec at normal incidence (index n with
 *   ((n − 1)/(n + 1))² = spec), tinted by the colour for metal, over a Lambertian base of the colour (the
 *   coat passes it 1 − spec of the light: colour·(1 − spec) again), with GGX α = rough (Ward's rough is an
 *   rms slope, as Beckmann's and GGX's α are). A metal with spec ≥ 0.99 is a GGX conductor of F0 colour.
 *   trans: a translucent sheet: Lambertian reflection colour·(1 − spec)·(1 − trans), Lambertian transmission
 *   colour·(1 − spec)·trans·(1 − tspec), straight-through transmission colour·(1 − spec)·trans·tspec (its
 *   specular reflection left out, warned). glass: irrcache's thin pane, of the colour's
 *   transmissivity and the index (1.52 by default), as Radiance's glass computes it. dielectric: irrcache's
 *   refracting dielectric. mirror: a mirror. light, glow: area emitters of that radiance; spotlight: the same
 *   within its cone (half its angle about its direction), dark outside.
 *
 *   A brightfunc of skybright.cal or perezlum.cal is the sky gensky or gendaylit wrote (sky.h, ic_sky_cal):
 *   it is read here and passed on to the light, glow or illum it modifies, whose distant sources then
 *   carry the sky's distribution (radiance_scene.c).
 */
#include "scene/radiance_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static const char *const pattern_types[] = {"texfunc",  "texdata",   "colorfunc", "brightfunc", "colordata",
                                            "brightdata", "colorpict", "colortext", "brighttext", "specfunc",
                                            "specdata", "specpict"};
static const char *const mixture_types[] = {"mixfunc", "mixdata", "mixpict", "mixtext"};
static int in_list(const char *type, const char *const *list, size_t count)
{
    for (size_t i = 0; i < count; ++i)
        if (!strcmp(type, list[i]))
            return 1;
    return 0;
}

#define IN_LIST(type, list) in_list(type, list, sizeof list / sizeof list[0])

/* The count of real arguments must lie in [lo, hi]; names lists them for the message. */
static ic_result need_reals(ic_rad_ctx *c, size_t lo, size_t hi, const char *names)
{
    if (c->real_count >= lo && c->real_count <= hi)
        return IC_OK;
    return ic_rad_fail(c, c->prim_line, IC_ERR_PARSE, "%s '%s' needs %zu real arguments (%s), has %zu; fix its argument list",
                       c->type, c->id, lo, names, c->real_count);
}

/* The colour of the first three reals: finite and >= 0. */
static ic_result colour(ic_rad_ctx *c, ic_vec3 *out)
{
    *out = v3((float)c->reals[0], (float)c->reals[1], (float)c->reals[2]);
    if (!(out->x >= 0.0f && out->y >= 0.0f && out->z >= 0.0f) || !v3_is_finite(*out))
        return ic_rad_fail(c, c->prim_line, IC_ERR_INVALID_ARG, "%s '%s': colour values must be finite and >= 0", c->type,
                           c->id);
    return IC_OK;
}

/* plastic or metal (or their reflected part, trans): colour, specularity, roughness as the header says. */
static ic_result specular_material(ic_rad_ctx *c, ic_vec3 col, double spec, double rough, int is_metal, ic_material *m)
{
    if (!(spec >= 0.0 && spec <= 1.0) || !(rough >= 0.0))
        return ic_rad_fail(c, c->prim_line, IC_ERR_INVALID_ARG,
                           "%s '%s': specularity must be in [0, 1] and roughness >= 0 (given %g and %g)", c->type, c->id,
                           spec, rough);
    m->alpha = (float)fmin(rough, 1.0);
    if (spec <= 0.0) {
        m->type = IC_MAT_DIFFUSE;
        m->kd = col;
    } else if (is_metal && spec >= 0.99) {
        m->type = IC_MAT_CONDUCTOR;
        m->ks = col;
    } else {
        double s = sqrt(fmin(spec, 0.99));
        m->type = IC_MAT_PLASTIC;
        m->kd = col;
        m->ks = is_metal ? col : v3s(1.0f);
        m->ior = (float)((1.0 + s) / (1.0 - s));
    }
    return IC_OK;
}

/* A light's radiance: at most IC_SCENE_MAX_RADIANCE. */
static ic_result radiance_limit(ic_rad_ctx *c, ic_vec3 radiance)
{
    if (!ic_radiance_too_large(radiance))
        return IC_OK;
    return ic_rad_fail(c, c->prim_line, IC_ERR_INVALID_ARG, "%s '%s': its radiance is " IC_RADIANCE_LIMIT_FMT "; "
                       IC_RADIANCE_LIMIT_FIX, c->type, c->id, IC_RADIANCE_LIMIT_ARGS(radiance));
}

static ic_result emitter(ic_rad_ctx *c, ic_rad_modifier *out)
{
    ic_material *m = &out->material;
    out->is_emitter = 1;
    m->type = IC_MAT_DIFFUSE;
    m->kd = v3s(0.0f);
    ic_result r = colour(c, &m->emission);
    return r == IC_OK ? radiance_limit(c, m->emission) : r;
}

/* The modifier another one names (alias, illum's alternate, a mixture's first): copied into out. */
static ic_result copy_named(ic_rad_ctx *c, const char *name, ic_rad_modifier *out)
{
    if (!strcmp(name, "void")) {
        out->kind = IC_RAD_INVISIBLE;
        return IC_OK;
    }
    const ic_rad_modifier *t = ic_rad_find(c, name);
    if (!t)
        return ic_rad_fail(c, c->prim_line, IC_ERR_PARSE,
                           "%s '%s' names '%s', which is not defined above; define it before this line", c->type, c->id,
                           name);
    out->kind = t->kind;
    out->material = t->material;
    out->is_illum = t->is_illum; /* an alias of an illum is one: a source it modifies emits its colour */
    out->source_radiance = t->source_radiance;
    out->is_emitter = t->is_emitter;
    out->has_sky = t->has_sky;
    out->sky = t->sky;
    out->sky_line = t->sky_line;
    snprintf(out->material.name, sizeof out->material.name, "%.127s", c->id);
    return IC_OK;
}

/* A brightfunc of Radiance's skybright.cal or perezlum.cal (gensky's and gendaylit's sky): *is_sky 1 and out's
 * sky read from its arguments. Any other brightfunc is a pattern like the others (*is_sky 0). Another function
 * of those files, a transform or arguments the file would misread are refused: the sky would be wrong by the
 * ratio of its brightness to the glow's colour, tens of times. */
static ic_result sky_function(ic_rad_ctx *c, ic_rad_modifier *out, int *is_sky)
{
    *is_sky = 0;
    if (strcmp(c->type, "brightfunc") || c->string_count < 2)
        return IC_OK;
    const char *file = c->strings[1], *base = file;
    for (const char *p = file; *p; ++p)
        if (*p == '/' || *p == '\\')
            base = p + 1;
    const int perez = !strcmp(base, "perezlum.cal");
    if (!perez && strcmp(base, "skybright.cal"))
        return IC_OK;
    *is_sky = 1;
    const char *function = perez ? "skybright" : "skybr", *generator = perez ? "gendaylit" : "gensky";
    if (strcmp(c->strings[0], function))
        return ic_rad_fail(c, c->prim_line, IC_ERR_UNSUPPORTED,
                           "brightfunc '%s': irrcache evaluates %s's function '%s' (as %s writes it), not '%s'; paste "
                           "the output of a current %s",
                           c->id, base, function, generator, c->strings[0], generator);
    if (c->string_count > 2)
        return ic_rad_fail(c, c->prim_line, IC_ERR_UNSUPPORTED,
                           "brightfunc '%s': the sky function's transform ('%s' ...) is not supported; give %s the sun "
                           "position you want instead",
                           c->id, c->strings[2], generator);
    char why[256];
    if (!ic_sky_cal_init(&out->sky, perez ? IC_SKY_FUNCTION_PEREZLUM : IC_SKY_FUNCTION_SKYBRIGHT, c->reals,
                         c->real_count, why, sizeof why))
        return ic_rad_fail(c, c->prim_line, IC_ERR_INVALID_ARG, "brightfunc '%s' (%s of %s) %s%s; fix it or paste %s's "
                           "output again", c->id, function, base, strncmp(why, "has ", 4) ? ": " : "", why, generator);
    out->has_sky = 1;
    out->sky_line = c->prim_line;
    return IC_OK;
}

static ic_result define_modifier(ic_rad_ctx *c, ic_rad_modifier *out);

ic_result ic_rad_define_modifier(ic_rad_ctx *c, ic_rad_modifier *out)
{
    /* looked up before the definition: a name may be defined again, modified by its earlier self */
    const ic_rad_modifier *by = strcmp(c->modifier, "void") ? ic_rad_find(c, c->modifier) : NULL;
    ic_result r = define_modifier(c, out);
    if (r != IC_OK || !by || !by->has_sky || out->has_sky)
        return r;
    if (out->is_emitter || out->is_illum) { /* its sources take the sky's distribution, its colour the scale */
        out->has_sky = 1;
        out->sky = by->sky;
        out->sky_line = by->sky_line;
    } else {
        ic_rad_warn_once(c, c->prim_line, "a sky function (skybright.cal, perezlum.cal) modifying no light, glow or "
                         "illum", "is applied to sources only: what it modifies is used without it");
    }
    return IC_OK;
}

static ic_result define_modifier(ic_rad_ctx *c, ic_rad_modifier *out)
{
    memset(out, 0, sizeof *out);
    snprintf(out->name, sizeof out->name, "%s", c->id);
    out->kind = IC_RAD_MATERIAL;
    out->index = -1;
    out->line = c->prim_line;
    ic_material *m = &out->material;
    snprintf(m->name, sizeof m->name, "%.127s", c->id);
    m->type = IC_MAT_DIFFUSE;
    m->kd = v3s(0.5f);
    m->kd_texture = -1;
    m->ior = 1.5f;
    const char *t = c->type;
    char kind[96];
    snprintf(kind, sizeof kind, "%.40s", t);
    /* "inherit alias new original": the new name takes the original's modifier too (Radiance 5) */
    const int inherit = !strcmp(c->modifier, "inherit") && !strcmp(t, "alias");
    if (strcmp(c->modifier, "void") && !inherit && !ic_rad_find(c, c->modifier))
        return ic_rad_fail(c, c->prim_line, IC_ERR_PARSE,
                           "%s '%s' is modified by '%s', which is not defined above; define it before this line", t,
                           c->id, c->modifier);
    if (IN_LIST(t, pattern_types)) {
        out->kind = IC_RAD_PATTERN;
        int is_sky;
        ic_result r = sky_function(c, out, &is_sky);
        if (r != IC_OK || is_sky)
            return r;
        ic_rad_warn_once(c, c->prim_line, kind, "(a pattern or texture) is not supported: the materials it modifies are "
                                                "rendered without it");
        return IC_OK;
    }
    if (IN_LIST(t, mixture_types)) {
        if (c->string_count < 1)
            return ic_rad_fail(c, c->prim_line, IC_ERR_PARSE, "%s '%s' needs its two materials as string arguments", t,
                               c->id);
        ic_rad_warn_once(c, c->prim_line, kind, "(a mixture) is not supported: its first material is used alone");
        return copy_named(c, c->strings[0], out);
    }
    if (!strcmp(t, "alias"))
        return copy_named(c, c->strings[0], out);
    if (!strcmp(t, "illum")) {
        ic_result r = need_reals(c, 3, 3, "red green blue");
        if (r != IC_OK)
            return r;
        ic_rad_warn_once(c, c->prim_line, kind,
                         "is rendered as its alternate material (invisible without one): the light it stands for is "
                         "found by sampling what lies behind it");
        r = copy_named(c, c->string_count >= 1 ? c->strings[0] : "void", out);
        out->is_illum = 1;
        out->source_radiance = v3((float)c->reals[0], (float)c->reals[1], (float)c->reals[2]);
        return r == IC_OK ? radiance_limit(c, out->source_radiance) : r;
    }
    if (!strcmp(t, "mist") || !strcmp(t, "antimatter")) {
        out->kind = IC_RAD_INVISIBLE;
        ic_rad_warn_once(c, c->prim_line, kind, "is not supported: the surfaces it modifies are left out");
        return IC_OK;
    }
    ic_result r = IC_OK;
    ic_vec3 col;
    int is_metal = !strcmp(t, "metal") || !strcmp(t, "metal2") || !strcmp(t, "metfunc") || !strcmp(t, "metdata");
    if (!strcmp(t, "plastic") || !strcmp(t, "metal") || !strcmp(t, "plasfunc") || !strcmp(t, "metfunc") ||
        !strcmp(t, "plasdata") || !strcmp(t, "metdata")) {
        if (strcmp(t, "plastic") && strcmp(t, "metal"))
            ic_rad_warn_once(c, c->prim_line, kind,
                             "is rendered as plain plastic or metal of its colour, specularity and roughness");
        if ((r = need_reals(c, 5, 5, "red green blue specularity roughness")) == IC_OK && (r = colour(c, &col)) == IC_OK)
            r = specular_material(c, col, c->reals[3], c->reals[4], is_metal, m);
    } else if (!strcmp(t, "plastic2") || !strcmp(t, "metal2")) {
        ic_rad_warn_once(c, c->prim_line, kind, "is rendered isotropic, with roughness sqrt(u-roughness * v-roughness)");
        if ((r = need_reals(c, 6, 6, "red green blue specularity u-roughness v-roughness")) == IC_OK &&
            (r = colour(c, &col)) == IC_OK)
            r = specular_material(c, col, c->reals[3], sqrt(fabs(c->reals[4] * c->reals[5])), is_metal, m);
    } else if (!strcmp(t, "trans") || !strcmp(t, "transfunc") || !strcmp(t, "transdata")) {
        if ((r = need_reals(c, 7, 7, "red green blue specularity roughness transmissivity transmitted-specular")) ==
                IC_OK &&
            (r = colour(c, &col)) == IC_OK) {
            double spec = c->reals[3], trans = c->reals[5], tspec = c->reals[6];
            if (!(trans >= 0.0 && trans <= 1.0 && tspec >= 0.0 && tspec <= 1.0 && spec >= 0.0 && spec <= 1.0))
                return ic_rad_fail(c, c->prim_line, IC_ERR_INVALID_ARG,
                                   "trans '%s': specularity, transmissivity and transmitted specular must be in [0, 1]",
                                   c->id);
            if (spec > 0.0 || (c->reals[4] > 0.0 && trans * tspec > 0.0))
                ic_rad_warn_once(c, c->prim_line, "trans with specularity or roughness",
                                 "is rendered without its specular reflection (the sheet reflects spec less) and with "
                                 "its specular transmission unblurred (straight through)");
            /* Radiance's split: of the light not reflected specularly (1 − spec), trans is transmitted, tspec
             * of that straight through; the colour tints all but the specular reflection */
            m->type = IC_MAT_TRANSLUCENT;
            m->kd = v3_scale(col, (float)((1.0 - spec) * (1.0 - trans)));
            m->kt = v3_scale(col, (float)((1.0 - spec) * trans * (1.0 - tspec)));
            m->kt_specular = v3_scale(col, (float)((1.0 - spec) * trans * tspec));
        }
    } else if (!strcmp(t, "glass") || !strcmp(t, "dielectric")) {
        int glass = !strcmp(t, "glass");
        if ((r = glass ? need_reals(c, 3, 4, "red green blue [index]") : need_reals(c, 5, 5, "red green blue index hartmann")) ==
                IC_OK &&
            (r = colour(c, &col)) == IC_OK) {
            if (!glass && (col.x != 1.0f || col.y != 1.0f || col.z != 1.0f))
                ic_rad_warn_once(c, c->prim_line, "dielectric with a colour", "is rendered colourless (no absorption)");
            double n = glass ? (c->real_count == 4 ? c->reals[3] : 1.52) : c->reals[3];
            if (!(n >= 1.0 && n <= 10.0))
                return ic_rad_fail(c, c->prim_line, IC_ERR_INVALID_ARG,
                                   "%s '%s': the index of refraction must be in [1, 10] (given %g)", t, c->id, n);
            if (glass && !(col.x <= 1.0f && col.y <= 1.0f && col.z <= 1.0f))
                return ic_rad_fail(c, c->prim_line, IC_ERR_INVALID_ARG,
                                   "glass '%s': the transmissivity must be in [0, 1] per channel (given %g %g %g)",
                                   c->id, (double)col.x, (double)col.y, (double)col.z);
            m->type = glass ? IC_MAT_THIN_GLASS : IC_MAT_GLASS;
            m->ks = glass ? col : v3s(1.0f);
            m->ior = (float)n;
        }
    } else if (!strcmp(t, "mirror")) {
        if ((r = need_reals(c, 3, 3, "red green blue")) == IC_OK && (r = colour(c, &m->ks)) == IC_OK)
            m->type = IC_MAT_MIRROR;
    } else if (!strcmp(t, "light")) {
        if ((r = need_reals(c, 3, 3, "red green blue")) == IC_OK)
            r = emitter(c, out);
    } else if (!strcmp(t, "glow")) {
        if ((r = need_reals(c, 4, 4, "red green blue maximum-radius")) == IC_OK)
            r = emitter(c, out);
    } else if (!strcmp(t, "spotlight")) {
        if ((r = need_reals(c, 7, 7, "red green blue angle x-direction y-direction z-direction")) == IC_OK &&
            (r = emitter(c, out)) == IC_OK) {
            /* Radiance's spotlight: the light's radiance towards directions within half the (full) cone angle of
             * the direction, none outside (a hard edge); the direction's length, a focal distance, matters
             * only for Radiance's virtual sources */
            const double angle = c->reals[3];
            const ic_vec3 axis = v3((float)c->reals[4], (float)c->reals[5], (float)c->reals[6]);
            if (!(angle > 0.0 && angle <= 360.0) || !(v3_len2(axis) > 0.0f) || !v3_is_finite(axis))
                return ic_rad_fail(c, c->prim_line, IC_ERR_INVALID_ARG,
                                   "spotlight '%s' needs a cone angle in (0, 360] degrees and a non-zero direction "
                                   "(given %g and %g %g %g)",
                                   c->id, angle, c->reals[4], c->reals[5], c->reals[6]);
            m->emission_cone = 1;
            m->emission_axis = v3_norm(axis);
            m->emission_cos_cone = (float)cos(0.5 * angle * 3.14159265358979323846 / 180.0);
        }
    } else {
        ic_rad_warn_once(c, c->prim_line, kind, "is not supported: a diffuse grey 0.5 is used");
    }
    return r;
}
