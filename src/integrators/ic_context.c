/*
 * ic_context.c — the cache integrator's shared context: options resolved against the scene, an empty
 * cache, the shading points and the large-emitter choice; the hash that ties a cache file to the scene
 * and the gathering settings; progress reports.
 */
#include "ic_internal.h"

#include "core/threads.h"
#include "core/text.h"
#include "film/film.h"
#include "irrcache/defaults.h"

#include <stdarg.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void ic_ic_report(const ic_render_options *opt, const char *phase, double f)
{
    if (opt->progress)
        opt->progress(opt->progress_user, phase, f);
}

static void resolve_options(ic_ctx *c, const ic_ic_options *in, const ic_scene *scene)
{
    ic_ic_options o = *in;
    /* Records gather as many bounces as the path tracer follows (max_depth scattering events in all,
     * the record's own point being the first): truncating earlier darkens the image measurably. */
    if (o.bounces <= 0)
        o.bounces = c->tr->pt.max_depth > 1 ? c->tr->pt.max_depth - 1 : 1;
    if (o.light_samples <= 0)
        o.light_samples = IC_DEFAULT_LIGHT_SAMPLES;
    /* The Hessian extent needs the gather's second-order terms. */
    if (o.error == IC_ERROR_HESSIAN)
        o.gather.with_hessian = 1;
    /* A hemicube of N × N texels on top and four N × N/2 sides casts 3N² rays: N even, with as many rays
     * as the stratified grid that --rays asks for (800 by default: N = 16, 768 rays). */
    if (o.gather.method == IC_GATHER_HEMICUBE && o.gather.hemicube_resolution == 0 && o.gather.theta_strata) {
        double rays = (double)o.gather.theta_strata * (double)o.gather.phi_strata;
        long n = 2 * lround(sqrt(rays / 3.0) / 2.0);
        o.gather.hemicube_resolution = (uint32_t)(n < 2 ? 2 : n > IC_GATHER_MAX_HEMICUBE ? IC_GATHER_MAX_HEMICUBE : n);
    }
    if (o.large_emitters.value == 0.0f)
        o.large_emitters.value = IC_DEFAULT_LARGE_EMITTERS;
    if (o.record_filter.value == 0.0f)
        o.record_filter.value = IC_DEFAULT_RECORD_FILTER;
    if (o.record_sets <= 0)
        o.record_sets = IC_DEFAULT_RECORD_SETS;
    if (!(o.record_noise > 0.0f))
        o.record_noise = IC_DEFAULT_RECORD_NOISE;
    if (o.max_passes <= 0)
        o.max_passes = IC_DEFAULT_MAX_PASSES;
    if (o.min_candidates <= 0)
        o.min_candidates = IC_DEFAULT_MIN_CANDIDATES;
    if (!(o.uncovered > 0.0f))
        o.uncovered = IC_DEFAULT_UNCOVERED;
    if (o.pass_growth.value == 0.0f)
        o.pass_growth.value = IC_DEFAULT_PASS_GROWTH;
    if (o.screen_passes <= 0)
        o.screen_passes = IC_DEFAULT_SCREEN_PASSES;
    if (o.dither_threshold <= 0.0f)
        o.dither_threshold = IC_DEFAULT_DITHER_THRESHOLD;
    if (o.normal_weight <= 0.0f)
        o.normal_weight = IC_DEFAULT_NORMAL_WEIGHT;
    if (o.world_stride <= 0)
        o.world_stride = IC_DEFAULT_WORLD_STRIDE;
    if (o.cluster_size <= 0.0f)
        o.cluster_size = IC_DEFAULT_CLUSTER_SIZE;
    if (!(o.weber > 0.0f))
        o.weber = IC_DEFAULT_WEBER;
    if (!(o.adaptive_growth > 0.0f))
        o.adaptive_growth = IC_DEFAULT_ADAPTIVE_GROWTH;
    if (o.adaptive_max_passes <= 0)
        o.adaptive_max_passes = IC_DEFAULT_ADAPTIVE_MAX_PASSES;
    if (o.hsh_order <= 0)
        o.hsh_order = (int)IC_DEFAULT_HSH_ORDER;
    if (!(o.radiance_max_exponent > 0.0f))
        o.radiance_max_exponent = IC_DEFAULT_RADIANCE_MAX_EXPONENT;
    if (o.cache.accuracy == 0.0f)
        o.cache.accuracy = o.cache.weight == IC_WEIGHT_TABELLION ? IC_DEFAULT_ACCURACY_TL : IC_DEFAULT_ACCURACY_WARD;
    /* Radius bounds: 0 means the renderer's default, negative switches the bound off. The pixel bounds
     * given to the renderer bound a record's influence radius a·R on screen (what a user sees: "a record
     * covers between 3 and 48 pixels"); the cache clamps R itself, hence the division by a. The floor of
     * 3 pixels, not 1.5: records closer than that mostly average their own Monte Carlo noise; on Sponza
     * at 448×252 it cut records by a quarter and lowered the error (BENCHMARKS.md). */
    float diag = v3_len(v3_sub(scene->bounds_max, scene->bounds_min));
    float min_px = o.min_radius_px == 0.0f ? IC_DEFAULT_MIN_RADIUS_PX : fmaxf(o.min_radius_px, 0.0f);
    float max_px = o.max_radius_px == 0.0f ? IC_DEFAULT_MAX_RADIUS_PX : fmaxf(o.max_radius_px, 0.0f);
    o.cache.min_radius_pixels = min_px / o.cache.accuracy;
    o.cache.max_radius_pixels = max_px / o.cache.accuracy;
    o.cache.max_radius = o.cache.max_radius == 0.0f ? diag / IC_DEFAULT_MAX_RADIUS_DIAG : (o.cache.max_radius < 0.0f ? INFINITY : o.cache.max_radius);
    o.cache.min_radius = fmaxf(o.cache.min_radius, 0.0f);
    c->o = o;
    c->scene_diag = diag > 0.0f ? diag : 1.0f;
}

ic_result ic_ic_ctx_create(const ic_tracer *tr, const ic_render_options *opt, ic_ctx **out, double *gbuffer_seconds,
                           ic_error *err)
{
    *out = NULL;
    ic_ctx *c = calloc(1, sizeof *c);
    if (!c)
        return ic_error_set(err, IC_ERR_OOM, "out of memory");
    c->tr = tr;
    c->seed = opt->seed;
    c->deadline = opt->time_budget > 0.0 ? ic_seconds() + IC_CONSTRUCTION_TIME_SHARE * opt->time_budget : 0.0;
    c->threads = ic_resolve_threads(opt->threads);
    c->comm = opt->comm;
    c->cancel = opt->cancel;
    atomic_init(&c->rays, 0);
    resolve_options(c, &opt->ic, tr->scene);
    float sel_sum = tr->scene->light_select.tri + tr->scene->light_select.point;
    if (sel_sum > 0.0f) {
        c->light_sel.tri = tr->scene->light_select.tri / sel_sum;
        c->light_sel.point = tr->scene->light_select.point / sel_sum;
    }
    c->light_sel_all = c->light_sel;
    c->gather_tr = *tr;
    c->gather_tr.pt.max_depth = c->o.bounces + 1;
    /* With one bounce a hemisphere ray returns its hit's direct light alone; records hold more. */
    c->hit_kind = -1;
    c->emitter_mis = 1;
    c->hit_lookups = !c->o.path_traced_gather && !c->o.recursive && c->o.bounces > 1 &&
                     c->o.bounces <= IC_LEVELS_MAX;
    /* The level split serves the hit look-ups and the final render's vertices behind glass or glossy
     * reflections; recursive caching keeps its levels as records of their own. */
    c->levels = !c->o.recursive && c->o.bounces <= IC_LEVELS_MAX ? c->o.bounces : 0;
    c->o.gather.seed ^= opt->seed;
    c->o.cache.threads = opt->threads;
    ic_result r = ic_cache_create(&c->o.cache, &c->cache, err);
    ic_cache_set_comm(c->cache, c->comm); /* every process makes the same insertions */
    double t0 = ic_seconds();
    /* Every pixel's shading point on every process only where something reads them all: the adaptive
     * strategy's shading points and the AOVs (the records' views among them). */
    if (r == IC_OK)
        r = ic_ic_gbuffer_build(c, c->o.strategy == IC_STRATEGY_ADAPTIVE || opt->aovs != NULL, err);
    /* Clusters of candidates scale with the scene's size, but a room inside a large ground plane (the
     * sky-room's 120 m of ground around 4 m of room) made boxes the size of the room: a few candidates a
     * pass, construction stopping with 15 % of the eye paths' points uncovered, and the final render's
     * fallback rays as white specks. At most 2.5 times what the camera sees (which leaves every bench scene
     * but the sky-room as it was: their views are 0.4–1 of their diagonals). */
    float view = 0.0f;
    if (r == IC_OK)
        r = ic_ic_view_extent(c, &view, err);
    c->work_extent = view > 0.0f ? fminf(c->scene_diag, 2.5f * view) : c->scene_diag;
    /* The large emitters' hemisphere shares are measured at the shading points, shared out like them. */
    if (r == IC_OK)
        r = ic_ic_select_large_emitters(c, tr->scene, err);
    if (gbuffer_seconds)
        *gbuffer_seconds = ic_seconds() - t0;
    if (r != IC_OK) {
        ic_ic_ctx_destroy(c);
        return r;
    }
    *out = c;
    return IC_OK;
}

void ic_ic_ctx_destroy(ic_ctx *c)
{
    if (!c)
        return;
    ic_cache_destroy(c->cache);
    ic_ic_gbuffer_free(c);
    free(c->direct_pmf);
    free(c->direct_cdf);
    free(c->cached_pmf);
    free(c->cached_cdf);
    free(c->level_irr);
    free(c->record_noise);
    free(c);
}

/* The scene's part of the records' hash, continuing h: geometry, materials, textures, lights, environment. */
static uint64_t scene_digest(const ic_scene *s, uint64_t h)
{
    h = ic_fnv1a64(h, s->positions, sizeof *s->positions * s->vertex_count);
    h = ic_fnv1a64(h, s->triangles, sizeof *s->triangles * 3 * (size_t)s->triangle_count);
    h = ic_fnv1a64(h, s->triangle_material, sizeof *s->triangle_material * s->triangle_count);
    for (uint32_t i = 0; i < s->material_count; ++i) {
        const ic_material *m = &s->materials[i];
        float f[14] = {m->kd.x, m->kd.y, m->kd.z, m->ks.x, m->ks.y, m->ks.z, m->ns, m->emission.x, m->emission.y,
                       m->emission.z, m->ior, (float)m->type, (float)m->kd_texture, (float)m->two_sided_emission};
        h = ic_fnv1a64(h, f, sizeof f);
        if (m->emission_cone) { /* a spotlight's cone (other materials' hashes stay as they were) */
            float cone[4] = {m->emission_axis.x, m->emission_axis.y, m->emission_axis.z, m->emission_cos_cone};
            h = ic_fnv1a64(h, cone, sizeof cone);
        }
        if (m->type == IC_MAT_TRANSLUCENT) { /* (other materials' hashes stay as they were) */
            float t[6] = {m->kt.x, m->kt.y, m->kt.z, m->kt_specular.x, m->kt_specular.y, m->kt_specular.z};
            h = ic_fnv1a64(h, t, sizeof t);
        }
    }
    for (uint32_t i = 0; i < s->texture_count; ++i) {
        /* The texel values as floats, however they are stored (the hash streams: same bytes, same hash). */
        const ic_texture *t = &s->textures[i];
        size_t n = 3 * (size_t)t->width * (size_t)t->height;
        if (t->rgb) {
            h = ic_fnv1a64(h, t->rgb, sizeof(float) * n);
            continue;
        }
        enum { CHUNK = 768 };
        float chunk[CHUNK];
        for (size_t at = 0; at < n; at += CHUNK) {
            size_t m = n - at < CHUNK ? n - at : CHUNK;
            for (size_t k = 0; k < m; ++k)
                chunk[k] = ic_texture_value(t, at + k);
            h = ic_fnv1a64(h, chunk, sizeof(float) * m);
        }
    }
    h = ic_fnv1a64(h, s->point_lights, sizeof *s->point_lights * s->point_light_count);
    if (s->point_spots)
        h = ic_fnv1a64(h, s->point_spots, sizeof *s->point_spots * s->point_light_count);
    float env[12] = {(float)s->sun.enabled, s->sun.direction.x, s->sun.direction.y, s->sun.direction.z,
                     s->sun.irradiance.x, s->sun.irradiance.y, s->sun.irradiance.z, (float)s->env.enabled,
                     s->env.radiance.x, s->env.radiance.y, s->env.radiance.z, s->env.rotation_deg};
    h = ic_fnv1a64(h, env, sizeof env);
    if (s->sun.enabled && s->sun.angular_radius > 0.0f) /* a disc (a directional sun's hash stays) */
        h = ic_fnv1a64(h, &s->sun.angular_radius, sizeof s->sun.angular_radius);
    if (s->env.image.rgb)
        h = ic_fnv1a64(h, s->env.image.rgb, sizeof(float) * 3 * (size_t)s->env.image.width * s->env.image.height);
    return h;
}

/* The records' hash continued from the scene's digest: how records gather (records_settings says the same
 * in words: a change here is a change there). */
static uint64_t records_hash(const ic_ctx *c, uint64_t h)
{
    const ic_scene *s = c->tr->scene;
    h = ic_fnv1a64(h, &c->cached_emitters, sizeof c->cached_emitters);
    if (c->direct_pmf)
        h = ic_fnv1a64(h, c->direct_pmf, sizeof *c->direct_pmf * s->tri_light_count);
    /* levels: hit look-ups that keep the bounce count exact (records of older builds took every bounce
     * of the records they met). */
    /* The hemicube's resolution rides with the method (zero for the other samplers, whose hashes stay). */
    int32_t method = (int32_t)c->o.gather.method |
                     (c->o.gather.method == IC_GATHER_HEMICUBE ? (int32_t)c->o.gather.hemicube_resolution << 8 : 0);
    int32_t g[10] = {c->o.bounces | (int32_t)c->o.error << 16 | (int32_t)c->o.record_shape << 20, c->o.no_gradients, method, (int32_t)c->o.gather.theta_strata,
                     (int32_t)c->o.gather.phi_strata, (int32_t)c->o.gather.max_rays, (int32_t)c->o.gather.tgrad,
                     (int32_t)c->o.strategy, c->hit_lookups, c->levels};
    /* The seed is left out on purpose: records built with one seed are as valid as any others, and a
     * cache re-used with a new seed renders an independent final image over the same records. */
    h = ic_fnv1a64(h, g, sizeof g);
    /* Record noise control changes the values (the filter) or their noise (the sets). */
    float noise[4] = {c->o.record_filter.mode == IC_CACHE_OFF ? 0.0f : c->o.record_filter.value,
                      (float)c->o.record_sets, c->o.record_sets > 1 ? c->o.record_noise : 0.0f, 0.0f};
    h = ic_fnv1a64(h, noise, sizeof noise);
    /* Radiance records: their order and which lobes they serve (nothing added when off, so the hashes
     * of irradiance-only caches stay). */
    if (c->rad) {
        float rad[3] = {(float)c->o.hsh_order, c->o.radiance_max_exponent, (float)c->o.radiance_rays};
        h = ic_fnv1a64(h, rad, sizeof rad);
    }
    return h;
}

/* ---- the same in words ------------------------------------------------------------------------------ */

/* Appends the line "key=value" (value from fmt) to out, whole or not at all. */
static void add_setting(char *out, size_t size, const char *key, const char *fmt, ...)
{
    size_t len = strlen(out);
    int n = snprintf(out + len, size - len, "%s=", key);
    va_list ap;
    va_start(ap, fmt);
    int m = n < 0 || (size_t)n >= size - len ? -1 : vsnprintf(out + len + n, size - len - (size_t)n, fmt, ap);
    va_end(ap);
    if (m < 0 || len + (size_t)n + (size_t)m + 1 >= size) {
        out[len] = '\0';
        return;
    }
    memcpy(out + len + n + m, "\n", 2);
}

static const char *on_off(int on)
{
    return on ? "on" : "off";
}

/* The settings text of ic_ic_records_identity, the scene's digest given. */
static void records_settings(const ic_ctx *c, uint64_t scene, char *out, size_t size)
{
    static const char *const strategies[] = {"batch", "lazy", "adaptive"}, *const methods[] = {"stratified",
        "progressive", "hemicube"}, *const errors[] = {"split-sphere", "hessian"}, *const shapes[] = {"round",
        "elliptical"}, *const tgrads[] = {"improved", "ward-heckbert"};
#define SAY(names, v) ((unsigned)(v) < sizeof names / sizeof names[0] ? names[v] : "?")
    const ic_ic_options *o = &c->o;
    const ic_scene *s = c->tr->scene;
    char f[32];
    out[0] = '\0';
    add_setting(out, size, "scene", "%016llx", (unsigned long long)scene);
    /* The name only for the message (the cache never compares it): a settings text is UTF-8 without
     * control characters, so any other byte of the path becomes '?'. */
    char name[sizeof s->path];
    size_t n = 0;
    for (const unsigned char *p = (const unsigned char *)s->path; *p && n + 1 < sizeof name;) {
        size_t k = *p >= 0x20 && *p != 0x7f ? ic_utf8_sequence(p, SIZE_MAX) : 0;
        if (k && n + k < sizeof name) {
            memcpy(name + n, p, k);
            n += k;
            p += k;
        } else {
            name[n++] = '?';
            p += k ? k : 1;
        }
    }
    name[n] = '\0';
    if (n)
        add_setting(out, size, "scene file", "%s", name);
    add_setting(out, size, "--strategy", "%s", SAY(strategies, o->strategy));
    if (o->gather.method == IC_GATHER_HEMICUBE && o->gather.hemicube_resolution)
        add_setting(out, size, "--gather", "hemicube (%u x %u texels on top)", o->gather.hemicube_resolution,
                    o->gather.hemicube_resolution);
    else
        add_setting(out, size, "--gather", "%s", SAY(methods, o->gather.method));
    /* Strata left at 0 (no --rays) hash apart from the same strata given: said as no --rays. */
    if (o->gather.theta_strata && o->gather.phi_strata)
        add_setting(out, size, "--rays", "%u (%u x %u strata)", o->gather.theta_strata * o->gather.phi_strata,
                    o->gather.theta_strata, o->gather.phi_strata);
    else if (o->gather.theta_strata || o->gather.phi_strata)
        add_setting(out, size, "gather strata", "%u x %u (0: the default)", o->gather.theta_strata,
                    o->gather.phi_strata);
    if (o->gather.max_rays)
        add_setting(out, size, "gather max_rays", "%u", o->gather.max_rays);
    if (o->gather.tgrad)
        add_setting(out, size, "gather tgrad", "%s", SAY(tgrads, o->gather.tgrad));
    add_setting(out, size, "--bounces", "%d", o->bounces);
    /* --recursive and --path-traced-gather count where they change the levels and hit look-ups. */
    if (o->recursive && o->bounces <= IC_LEVELS_MAX)
        add_setting(out, size, "--recursive", "");
    if (o->path_traced_gather && !o->recursive && o->bounces > 1 && o->bounces <= IC_LEVELS_MAX)
        add_setting(out, size, "--path-traced-gather", "");
    add_setting(out, size, "--error", "%s", SAY(errors, o->error));
    add_setting(out, size, "--record-shape", "%s", SAY(shapes, o->record_shape));
    if (o->no_gradients)
        add_setting(out, size, "--no-gradients", "");
    add_setting(out, size, "--record-filter", "%s",
                o->record_filter.mode == IC_CACHE_OFF ? "off" : ic_float_text(o->record_filter.value, f));
    add_setting(out, size, "--record-sets", "%d", o->record_sets);
    if (o->record_sets > 1)
        add_setting(out, size, "--record-noise", "%s", ic_float_text(o->record_noise, f));
    /* Which emitters the records carry: --large-emitters measured at the view's shading points. */
    if (c->cached_emitters || c->direct_pmf)
        add_setting(out, size, "emitters lit through the records (--large-emitters and the view decide)",
                    "%u triangles (choice %08x)", c->cached_emitters,
                    c->direct_pmf ? (unsigned)ic_fnv1a64(IC_FNV64_OFFSET, c->direct_pmf,
                                                         sizeof *c->direct_pmf * s->tri_light_count)
                                  : 0u);
    /* Radiance records last: on with no material to serve, they leave the hash alone. The exponent that
     * decides whether any material is served comes before the settings that count only then, so that a
     * file whose records served one, refused by a run whose exponent serves none, names the exponent (it
     * named --hsh-order, which this run had not changed, and asked for it). */
    add_setting(out, size, "--radiance-cache", "%s", on_off(o->radiance_cache == IC_CACHE_ON));
    if (c->rad) {
        add_setting(out, size, "--radiance-max-exponent", "%s", ic_float_text(o->radiance_max_exponent, f));
        add_setting(out, size, "--hsh-order", "%d", o->hsh_order);
        if (o->radiance_rays)
            add_setting(out, size, "--radiance-rays", "%d", o->radiance_rays);
    } else if (o->radiance_cache == IC_CACHE_ON) {
        add_setting(out, size, "--radiance-max-exponent", "%s (serves no material here)",
                    ic_float_text(o->radiance_max_exponent, f));
    }
#undef SAY
}

uint64_t ic_ic_records_identity(const ic_ctx *c, char *settings, size_t size)
{
    uint64_t scene = scene_digest(c->tr->scene, IC_FNV64_OFFSET);
    records_settings(c, scene, settings, size);
    return records_hash(c, scene);
}
