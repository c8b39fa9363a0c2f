/*
 * render.c — `irrcache render SCENE -o OUT [options]`.
 *
 * Options are described once, in the table below, which drives both parsing and --help, so the help
 * text can never fall out of step with what is accepted. Every output path is checked for a known
 * format and a writable folder before rendering starts, so a long render is never lost to a typo.
 */
#include "cli.h"

#include "core/atomic_file.h"
#include "irrcache/render.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define MAX_OUTPUTS 8

typedef struct render_args {
    const char *scene;
    const char *outputs[MAX_OUTPUTS];
    int output_count;
    const char *stats_path;
    const char *scenes_dir;
    const char *integrator;
    int width, height, spp, threads, max_depth;
    long long seed;
    int has_seed;
    double time_budget, exposure;
    int has_exposure;
    int quiet;
    /* irradiance caching */
    const char *sampler;
    const char *strategy, *weight, *gather, *aov, *records_json, *load_cache, *save_cache;
    double accuracy, min_radius, max_radius, min_radius_px, max_radius_px, final_scale;
    double weber, adaptive_growth;
    int rays, bounces, max_passes, min_candidates, light_samples;
    int no_gradients, no_neighbor_clamp, no_validity_clamp, gradient_difference, recursive, path_traced_gather;
    const char *adaptive_sampling;
    const char *large_emitters;
} render_args;

typedef enum opt_kind { OPT_INT, OPT_SEED, OPT_DOUBLE, OPT_STRING, OPT_OUTPUT, OPT_FLAG } opt_kind;

typedef struct opt_def {
    const char *name;
    const char *alias;
    opt_kind kind;
    size_t offset;
    double min_value;      /* numeric options: smallest accepted value */
    const char *value_name;
    const char *default_text;
    const char *help;
} opt_def;

#define OFF(f) offsetof(render_args, f)

static const opt_def options[] = {
    {"--output", "-o", OPT_OUTPUT, 0, 0, "PATH", "(required)",
     "output image; format from the extension: .exr (linear float), .png (tone-mapped sRGB), .pfm, .hdr; repeatable"},
    {"--width", NULL, OPT_INT, OFF(width), 1, "N", "scene file, else 512", "image width in pixels"},
    {"--height", NULL, OPT_INT, OFF(height), 1, "N", "scene file, else 512", "image height in pixels"},
    {"--spp", NULL, OPT_INT, OFF(spp), 1, "N", "scene file, else 16 (pt) or 64 (ic)",
     "samples per pixel (with --time: the most to take)"},
    {"--time", NULL, OPT_DOUBLE, OFF(time_budget), 0, "SECONDS", "none",
     "wall-time budget: progressive passes until it is spent (equal-time comparisons)"},
    {"--integrator", NULL, OPT_STRING, OFF(integrator), 0, "pt|ic", "pt",
     "pt: path-traced reference; ic: irradiance caching (indirect diffuse from the cache)"},
    {"--max-depth", NULL, OPT_INT, OFF(max_depth), 1, "N", "scene file, else 8", "maximum number of bounces"},
    {"--threads", NULL, OPT_INT, OFF(threads), 0, "N", "0 (all cores)", "worker threads; the image does not depend on it"},
    {"--seed", NULL, OPT_SEED, OFF(seed), 0, "N", "scene file, else 1", "random seed; same seed, same image"},
    {"--sampler", NULL, OPT_STRING, OFF(sampler), 0, "sobol|random", "sobol",
     "pixel, light and BSDF sample pairs: Owen-scrambled Sobol' per pixel (less noise) or independent random"},
    {"--adaptive-sampling", NULL, OPT_STRING, OFF(adaptive_sampling), 0, "on|off", "off (pt), on (ic, with --spp >= 8 and no --time)",
     "on: --spp becomes a mean, a pilot pass of spp/4 per pixel and the rest where the relative noise is (needs --spp >= 8, no --time)"},
    {"--exposure", NULL, OPT_DOUBLE, OFF(exposure), -100, "STOPS", "scene file, else 0", "exposure applied to .png outputs"},
    {"--stats", NULL, OPT_STRING, OFF(stats_path), 0, "FILE.json", "none",
     "write run statistics: seconds, rays, rays per second, per-phase times"},
    {"--scenes-dir", NULL, OPT_STRING, OFF(scenes_dir), 0, "DIR", "$IRRCACHE_SCENES, else ../shared/scenes",
     "where 'shared:' mesh paths in scene files resolve"},
    {"--quiet", "-q", OPT_FLAG, OFF(quiet), 0, NULL, "off", "no progress line"},
    {"--strategy", NULL, OPT_STRING, OFF(strategy), 0, "batch|lazy|adaptive", "batch",
     "ic: cache construction: batch (Frolov 2012, parallel multi-pass), lazy (Ward 1988, serial) or adaptive "
     "(Krivanek 2006: per-record a refined until no discontinuity is visible)"},
    {"--accuracy", "-a", OPT_DOUBLE, OFF(accuracy), 0.001, "A", "0.3 (Ward), 1 (T-L)",
     "ic: error bound a of the weights; smaller = more records"},
    {"--weight", NULL, OPT_STRING, OFF(weight), 0, "ward|tl", "ward", "ic: Ward or Tabellion-Lamorlette weights"},
    {"--rays", NULL, OPT_INT, OFF(rays), 16, "N", "800", "ic: hemisphere rays per record (stratified M x N)"},
    {"--gather", NULL, OPT_STRING, OFF(gather), 0, "stratified|progressive", "stratified",
     "ic: hemisphere sampler; progressive = Hammersley rounds 4096..65536 until converged"},
    {"--bounces", NULL, OPT_INT, OFF(bounces), 1, "N", "max-depth - 1", "ic: indirect bounces in the light a record gathers"},
    {"--recursive", NULL, OPT_FLAG, OFF(recursive), 0, NULL, "off",
     "ic lazy: one cache level per bounce, as Radiance's -ab (--bounces levels), instead of path tracing"},
    {"--light-samples", NULL, OPT_INT, OFF(light_samples), 1, "N", "1",
     "ic: light samples per shading point in the final render (direct light)"},
    {"--large-emitters", NULL, OPT_STRING, OFF(large_emitters), 0, "F|off", "0.01",
     "ic: an emitter covering at least F of the hemisphere at the median shading point, with over a quarter "
     "of its light samples blocked (a window seen through openings), lights the scene through the records "
     "instead of light sampling; off: sample every emitter"},
    {"--min-radius", NULL, OPT_DOUBLE, OFF(min_radius), 0, "R", "0", "ic: smallest record radius, world units"},
    {"--max-radius", NULL, OPT_DOUBLE, OFF(max_radius), 0, "R", "scene diagonal / 8",
     "ic: largest record radius, world units"},
    {"--min-radius-px", NULL, OPT_DOUBLE, OFF(min_radius_px), 0, "P", "3",
     "ic: smallest influence radius a*R of a record, in pixels at its primary hit"},
    {"--max-radius-px", NULL, OPT_DOUBLE, OFF(max_radius_px), 0, "P", "48",
     "ic: largest influence radius a*R of a record, in pixels at its primary hit"},
    {"--final-accuracy-scale", NULL, OPT_DOUBLE, OFF(final_scale), 1, "S", "1",
     "ic: the final render accepts records up to S times the construction error bound"},
    {"--no-gradients", NULL, OPT_FLAG, OFF(no_gradients), 0, NULL, "off", "ic: interpolate without gradients"},
    {"--path-traced-gather", NULL, OPT_FLAG, OFF(path_traced_gather), 0, NULL, "off",
     "ic: hemisphere rays path-trace every bounce after their hit instead of taking it from records that cover it"},
    {"--no-neighbor-clamp", NULL, OPT_FLAG, OFF(no_neighbor_clamp), 0, NULL, "off",
     "ic: disable neighbor clamping (Krivanek 2006 sec. 5.2)"},
    {"--no-validity-clamp", NULL, OPT_FLAG, OFF(no_validity_clamp), 0, NULL, "off",
     "ic: disable validity-radius clamping (Frolov 2012 sec. 4.2)"},
    {"--gradient-difference", NULL, OPT_FLAG, OFF(gradient_difference), 0, NULL, "off",
     "ic: enable gradient-difference record scaling (Castano 2014)"},
    {"--max-passes", NULL, OPT_INT, OFF(max_passes), 1, "N", "12", "ic batch: most construction passes"},
    {"--min-candidates", NULL, OPT_INT, OFF(min_candidates), 1, "N", "16",
     "ic batch: stop construction when a pass finds fewer new candidates"},
    {"--weber", NULL, OPT_DOUBLE, OFF(weber), 0.0001, "F", "0.02",
     "ic adaptive: Weber fraction of the discontinuity test; smaller = more records"},
    {"--adaptive-growth", NULL, OPT_DOUBLE, OFF(adaptive_growth), 1, "F", "1.4",
     "ic adaptive: a new record starts from the nearest record's a times F (at most --accuracy)"},
    {"--save-cache", NULL, OPT_STRING, OFF(save_cache), 0, "FILE", "none",
     "ic: write the cache records to FILE (versioned, checksummed) for re-use"},
    {"--load-cache", NULL, OPT_STRING, OFF(load_cache), 0, "FILE", "none",
     "ic: render with the records in FILE instead of building them; refused if made for another scene or settings"},
    {"--records-json", NULL, OPT_STRING, OFF(records_json), 0, "FILE", "none",
     "ic: write every record (position, radius, a, image position, visibility) as JSON"},
    {"--aov", NULL, OPT_STRING, OFF(aov), 0, "LIST", "none",
     "ic: extra images next to the first output, comma-separated: indirect (.exr), records (.png), density (.exr), "
     "amap (.png: a of the heaviest record, blue = --accuracy ... red = accuracy/32)"},
    {"--help", "-h", OPT_FLAG, 0, 0, NULL, NULL, "show this help"},
};
#define OPTION_COUNT (sizeof options / sizeof options[0])

static void print_help(FILE *f)
{
    fprintf(f, "usage: irrcache render SCENE -o OUT [options]\n\n"
               "SCENE is a JSON scene file (docs/scene-format.md) or a mesh (.obj .gltf .glb .ply).\n\noptions:\n");
    for (size_t i = 0; i < OPTION_COUNT; ++i) {
        const opt_def *o = &options[i];
        char left[64];
        snprintf(left, sizeof left, "%s%s%s%s%s", o->alias ? o->alias : "", o->alias ? ", " : "", o->name,
                 o->value_name ? " " : "", o->value_name ? o->value_name : "");
        fprintf(f, "  %-26s %s", left, o->help);
        if (o->default_text)
            fprintf(f, " [default: %s]", o->default_text);
        fputc('\n', f);
    }
}

static const opt_def *find_option(const char *arg)
{
    for (size_t i = 0; i < OPTION_COUNT; ++i)
        if (!strcmp(arg, options[i].name) || (options[i].alias && !strcmp(arg, options[i].alias)))
            return &options[i];
    return NULL;
}

/* Returns 0 on success, 2 on a usage error (message printed), -1 for --help. */
static int parse_args(int argc, char **argv, render_args *a)
{
    memset(a, 0, sizeof *a);
    a->integrator = "pt";
    for (int i = 1; i < argc; ++i) {
        const char *arg = argv[i];
        if (arg[0] != '-' || !arg[1]) {
            if (a->scene) {
                fprintf(stderr, "irrcache render: unexpected argument '%s'; give one scene file\n", arg);
                return 2;
            }
            a->scene = arg;
            continue;
        }
        const opt_def *o = find_option(arg);
        if (!o) {
            fprintf(stderr, "irrcache render: unknown option '%s'; see irrcache render --help\n", arg);
            return 2;
        }
        if (!strcmp(o->name, "--help"))
            return -1;
        char *field = (char *)a + o->offset;
        if (o->kind == OPT_FLAG) {
            *(int *)field = 1;
            continue;
        }
        if (i + 1 >= argc) {
            fprintf(stderr, "irrcache render: %s needs a value (%s)\n", o->name, o->value_name);
            return 2;
        }
        const char *val = argv[++i];
        char *end = NULL;
        errno = 0;
        switch (o->kind) {
        case OPT_INT:
        case OPT_SEED: {
            long long v = strtoll(val, &end, 10);
            if (errno || !*val || *end || v < (long long)o->min_value || (o->kind == OPT_INT && v > 1000000000LL)) {
                fprintf(stderr, "irrcache render: %s %s: expected an integer >= %g\n", o->name, val, o->min_value);
                return 2;
            }
            if (o->kind == OPT_SEED) {
                *(long long *)field = v;
                a->has_seed = 1;
            } else {
                *(int *)field = (int)v;
            }
            break;
        }
        case OPT_DOUBLE: {
            double v = strtod(val, &end);
            if (errno || !*val || *end || !isfinite(v) || v < o->min_value) {
                fprintf(stderr, "irrcache render: %s %s: expected a number >= %g\n", o->name, val, o->min_value);
                return 2;
            }
            *(double *)field = v;
            if (o->offset == OFF(exposure))
                a->has_exposure = 1;
            break;
        }
        case OPT_STRING:
            *(const char **)field = val;
            break;
        case OPT_OUTPUT:
            if (a->output_count == MAX_OUTPUTS) {
                fprintf(stderr, "irrcache render: at most %d outputs\n", MAX_OUTPUTS);
                return 2;
            }
            a->outputs[a->output_count++] = val;
            break;
        case OPT_FLAG:
            break;
        }
    }
    if (!a->scene) {
        fprintf(stderr, "irrcache render: no scene given; usage: irrcache render SCENE -o OUT (see --help)\n");
        return 2;
    }
    if (a->output_count == 0) {
        fprintf(stderr, "irrcache render: no output given; add -o out.exr (or .png, .pfm, .hdr)\n");
        return 2;
    }
    for (int i = 0; i < a->output_count; ++i) {
        if (!ic_image_is_writable_format(a->outputs[i])) {
            fprintf(stderr, "irrcache render: %s: unknown image format; use .exr, .png, .pfm or .hdr\n", a->outputs[i]);
            return 2;
        }
    }
    if (strcmp(a->integrator, "pt") != 0 && strcmp(a->integrator, "ic") != 0) {
        fprintf(stderr, "irrcache render: --integrator %s: unknown integrator; use pt or ic\n", a->integrator);
        return 2;
    }
    const struct { const char *name, *value, *choices; } choices[] = {
        {"--sampler", a->sampler, "sobol random"},
        {"--strategy", a->strategy, "batch lazy adaptive"},
        {"--weight", a->weight, "ward tl"},
        {"--gather", a->gather, "stratified progressive"},
        {"--adaptive-sampling", a->adaptive_sampling, "on off"},
    };
    for (size_t i = 0; i < sizeof choices / sizeof choices[0]; ++i) {
        if (!choices[i].value)
            continue;
        char list[64];
        snprintf(list, sizeof list, " %s ", choices[i].choices);
        char want[40];
        snprintf(want, sizeof want, " %s ", choices[i].value);
        if (strlen(choices[i].value) > 30 || !strstr(list, want)) {
            fprintf(stderr, "irrcache render: %s %s: unknown value; use one of: %s\n", choices[i].name,
                    choices[i].value, choices[i].choices);
            return 2;
        }
    }
    if (a->aov) {
        char buf[256];
        snprintf(buf, sizeof buf, "%s", a->aov);
        for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
            if (strcmp(tok, "indirect") && strcmp(tok, "records") && strcmp(tok, "density") && strcmp(tok, "amap")) {
                fprintf(stderr, "irrcache render: --aov %s: unknown AOV '%s'; use indirect, records, density, amap\n",
                        a->aov, tok);
                return 2;
            }
        }
    }
    int ic_only = a->strategy || a->weight || a->gather || a->aov || a->accuracy > 0 || a->rays || a->bounces || a->light_samples ||
                  a->min_radius > 0 || a->max_radius > 0 || a->min_radius_px > 0 || a->max_radius_px > 0 ||
                  a->final_scale > 0 || a->max_passes || a->min_candidates || a->no_gradients || a->path_traced_gather ||
                  a->no_neighbor_clamp || a->no_validity_clamp || a->gradient_difference || a->recursive || a->records_json ||
                  a->weber > 0 || a->adaptive_growth > 0 || a->large_emitters;
    if (ic_only && strcmp(a->integrator, "ic") != 0) {
        fprintf(stderr, "irrcache render: irradiance-cache options need --integrator ic\n");
        return 2;
    }
    if (a->large_emitters && strcmp(a->large_emitters, "off") != 0) {
        char *end;
        double f = strtod(a->large_emitters, &end);
        if (end == a->large_emitters || *end || !(f > 0.0) || !(f <= 1.0)) {
            fprintf(stderr, "irrcache render: --large-emitters '%s': give a hemisphere share in (0, 1] (e.g. 0.01) or off\n",
                    a->large_emitters);
            return 2;
        }
    }
    int adaptive_on = a->adaptive_sampling && !strcmp(a->adaptive_sampling, "on");
    if (adaptive_on && a->time_budget > 0) {
        fprintf(stderr, "irrcache render: --adaptive-sampling shares out a fixed --spp; drop --time\n");
        return 2;
    }
    if (adaptive_on && a->spp > 0 && a->spp < 8) {
        fprintf(stderr, "irrcache render: --adaptive-sampling needs --spp 8 or more (a pilot pass of spp/4 first)\n");
        return 2;
    }
    if (a->recursive && (!a->strategy || strcmp(a->strategy, "lazy") != 0)) {
        fprintf(stderr, "irrcache render: --recursive builds its levels lazily; add --strategy lazy\n");
        return 2;
    }
    if (a->min_radius > 0 && a->max_radius > 0 && a->min_radius > a->max_radius) {
        fprintf(stderr, "irrcache render: --min-radius %g is larger than --max-radius %g\n", a->min_radius,
                a->max_radius);
        return 2;
    }
    return 0;
}

/* Fails early (before a long render) if path's folder cannot take a new file. */
static int check_writable(const char *path)
{
    ic_atomic_file f;
    ic_error err;
    if (ic_atomic_file_open(&f, path, &err) != IC_OK) {
        fprintf(stderr, "irrcache render: %s\n", err.message);
        return 0;
    }
    ic_atomic_file_abort(&f);
    return 1;
}

typedef struct progress_state {
    int enabled;
    double start, last;
    const char *last_phase;
} progress_state;

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void on_progress(void *user, const char *phase, double fraction)
{
    progress_state *p = user;
    if (!p->enabled)
        return;
    double t = now_seconds();
    int new_phase = p->last_phase != phase;
    if (!new_phase && t - p->last < 0.1 && fraction < 1.0)
        return;
    p->last = t;
    p->last_phase = phase;
    double el = t - p->start;
    if (fraction > 0.0 && fraction <= 1.0) {
        double eta = el / fraction - el;
        fprintf(stderr, "\r%-16s %5.1f%%  elapsed %6.1fs  ETA %6.1fs ", phase, 100.0 * fraction, el, eta);
    } else {
        fprintf(stderr, "\r%-16s  elapsed %6.1fs ", phase, el);
    }
    fflush(stderr);
}

static int write_stats(const char *path, const render_args *a, int w, int h, const ic_render_stats *st)
{
    ic_atomic_file f;
    ic_error err;
    if (ic_atomic_file_open(&f, path, &err) != IC_OK) {
        fprintf(stderr, "irrcache render: %s\n", err.message);
        return 0;
    }
    FILE *o = f.fp;
    fprintf(o, "{\n  \"scene\": \"");
    for (const char *c = a->scene; *c; ++c) {
        if (*c == '"' || *c == '\\')
            fputc('\\', o);
        fputc(*c, o);
    }
    fprintf(o, "\",\n  \"integrator\": \"%s\",\n  \"width\": %d,\n  \"height\": %d,\n", a->integrator, w, h);
    fprintf(o, "  \"spp\": %d,\n  \"threads\": %d,\n  \"seconds\": %.6f,\n  \"rays\": %llu,\n", st->spp, st->threads,
            st->seconds, (unsigned long long)st->rays);
    fprintf(o, "  \"rays_per_second\": %.1f,\n", st->rays_per_second);
    if (st->spp_max != st->spp)
        fprintf(o, "  \"spp_max\": %d,\n", st->spp_max);
    if (!strcmp(a->integrator, "ic")) {
        fprintf(o, "  \"strategy\": \"%s\",\n  \"records\": %u,\n  \"passes\": %d,\n  \"gather_rays\": %llu,\n",
                a->strategy ? a->strategy : "batch", st->records, st->passes, (unsigned long long)st->gather_rays);
        fprintf(o, "  \"records_per_pass\": [");
        for (int i = 0; i < st->passes && i < 32; ++i)
            fprintf(o, "%s%u", i ? ", " : "", st->records_per_pass[i]);
        fprintf(o, "],\n");
        if (a->strategy && !strcmp(a->strategy, "adaptive"))
            fprintf(o, "  \"refinements\": %u,\n", st->refinements);
        fprintf(o, "  \"cached_emitters\": %u,\n", st->cached_emitters);
    }
    fprintf(o, "  \"phases\": {");
    for (int i = 0; i < st->phase_count; ++i)
        fprintf(o, "%s\"%s\": %.6f", i ? ", " : "", st->phases[i].name, st->phases[i].seconds);
    fprintf(o, "}\n}\n");
    if (ic_atomic_file_commit(&f, &err) != IC_OK) {
        fprintf(stderr, "irrcache render: %s\n", err.message);
        return 0;
    }
    return 1;
}

static void fill_ic_options(const render_args *a, ic_ic_options *o)
{
    memset(o, 0, sizeof *o);
    if (a->strategy && !strcmp(a->strategy, "lazy"))
        o->strategy = IC_STRATEGY_LAZY;
    if (a->strategy && !strcmp(a->strategy, "adaptive"))
        o->strategy = IC_STRATEGY_ADAPTIVE;
    o->weber = (float)a->weber;
    o->adaptive_growth = (float)a->adaptive_growth;
    if (a->weight && !strcmp(a->weight, "tl"))
        o->cache.weight = IC_WEIGHT_TABELLION;
    o->cache.accuracy = (float)a->accuracy;
    o->cache.min_radius = (float)a->min_radius;
    o->cache.max_radius = (float)a->max_radius;
    o->cache.min_radius_pixels = (float)a->min_radius_px;
    o->cache.max_radius_pixels = (float)a->max_radius_px;
    o->cache.final_accuracy_scale = (float)a->final_scale;
    o->cache.neighbor_clamp = a->no_neighbor_clamp ? IC_CACHE_OFF : IC_CACHE_DEFAULT;
    o->cache.validity_clamp = a->no_validity_clamp ? IC_CACHE_OFF : IC_CACHE_DEFAULT;
    o->cache.gradient_difference = a->gradient_difference ? IC_CACHE_ON : IC_CACHE_DEFAULT;
    if (a->gather && !strcmp(a->gather, "progressive"))
        o->gather.method = IC_GATHER_PROGRESSIVE;
    if (a->rays > 0) {
        /* M×N strata with N ≈ π·M (Ward's recommendation): M = sqrt(rays/π). */
        int m = (int)lround(sqrt(a->rays / 3.14159265358979));
        if (m < 2)
            m = 2;
        o->gather.theta_strata = (uint32_t)m;
        o->gather.phi_strata = (uint32_t)((a->rays + m / 2) / m);
    }
    o->no_gradients = a->no_gradients;
    o->path_traced_gather = a->path_traced_gather;
    o->bounces = a->bounces;
    o->recursive = a->recursive;
    o->load_cache = a->load_cache;
    o->save_cache = a->save_cache;
    o->light_samples = a->light_samples;
    if (a->large_emitters)
        o->large_emitters = !strcmp(a->large_emitters, "off") ? -1.0f : (float)strtod(a->large_emitters, NULL);
    o->max_passes = a->max_passes;
    o->min_candidates = a->min_candidates;
}

/* AOVs go next to the first output: <stem>.<aov>.<ext>, with .exr for linear data and .png for the
 * overlay. */
static int write_aovs(const char *first, const ic_render_aovs *aovs, const ic_image_write_options *wo)
{
    char stem[4096];
    snprintf(stem, sizeof stem, "%s", first);
    char *dot = strrchr(stem, '.');
    char *slash = strrchr(stem, '/');
    if (dot && (!slash || dot > slash))
        *dot = 0;
    const struct { const ic_image *img; const char *suffix; } list[] = {
        {&aovs->indirect, ".indirect.exr"}, {&aovs->records, ".records.png"}, {&aovs->density, ".density.exr"},
        {&aovs->amap, ".amap.png"}};
    for (size_t i = 0; i < sizeof list / sizeof list[0]; ++i) {
        if (!list[i].img->rgb)
            continue;
        char path[4200];
        snprintf(path, sizeof path, "%s%s", stem, list[i].suffix);
        ic_error err;
        if (ic_image_write(path, list[i].img, wo, &err) != IC_OK) {
            fprintf(stderr, "irrcache render: %s\n", err.message);
            return 0;
        }
    }
    return 1;
}

static int write_records_json(const char *path, const ic_render_aovs *aovs)
{
    ic_atomic_file f;
    ic_error err;
    if (ic_atomic_file_open(&f, path, &err) != IC_OK) {
        fprintf(stderr, "irrcache render: %s\n", err.message);
        return 0;
    }
    fprintf(f.fp, "[\n");
    for (uint32_t i = 0; i < aovs->record_view_count; ++i) {
        const ic_record_view *v = &aovs->record_views[i];
        fprintf(f.fp,
                "  {\"x\": %.6g, \"y\": %.6g, \"z\": %.6g, \"radius\": %.6g, \"a\": %.6g, \"px\": %.2f, "
                "\"py\": %.2f, \"radius_px\": %.2f, \"visible\": %s}%s\n",
                v->position.x, v->position.y, v->position.z, v->radius, v->accuracy, v->px, v->py, v->radius_px,
                v->visible ? "true" : "false", i + 1 < aovs->record_view_count ? "," : "");
    }
    fprintf(f.fp, "]\n");
    if (ic_atomic_file_commit(&f, &err) != IC_OK) {
        fprintf(stderr, "irrcache render: %s\n", err.message);
        return 0;
    }
    return 1;
}

int ic_cli_render(int argc, char **argv)
{
    render_args a;
    int rc = parse_args(argc, argv, &a);
    if (rc == -1) {
        print_help(stdout);
        return 0;
    }
    if (rc)
        return rc;
    for (int i = 0; i < a.output_count; ++i)
        if (!check_writable(a.outputs[i]))
            return 1;
    if ((a.stats_path && !check_writable(a.stats_path)) || (a.save_cache && !check_writable(a.save_cache)))
        return 1;

    progress_state prog = {0};
    prog.enabled = !a.quiet && isatty(fileno(stderr));
    prog.start = now_seconds();

    ic_error err = {0};
    ic_scene_load_options lo = {0};
    lo.shared_scenes_dir = a.scenes_dir;
    lo.width = a.width;
    lo.height = a.height;
    ic_scene *scene = NULL;
    double t_load = now_seconds();
    if (ic_scene_load(a.scene, &lo, &scene, &err) != IC_OK) {
        fprintf(stderr, "irrcache render: %s\n", err.message);
        return 1;
    }
    t_load = now_seconds() - t_load;

    ic_render_options opt = {0};
    opt.integrator = IC_INTEGRATOR_PT;
    opt.spp = a.spp;
    opt.max_depth = a.max_depth;
    opt.threads = a.threads;
    opt.seed = (uint64_t)a.seed;
    opt.has_seed = a.has_seed;
    opt.time_budget = a.time_budget;
    opt.sampler = a.sampler && !strcmp(a.sampler, "random") ? IC_SAMPLER_RANDOM : IC_SAMPLER_SOBOL;
    opt.adaptive_sampling = !a.adaptive_sampling ? 0 : !strcmp(a.adaptive_sampling, "on") ? 1 : -1;
    opt.progress = on_progress;
    opt.progress_user = &prog;
    ic_render_aovs aovs;
    memset(&aovs, 0, sizeof aovs);
    if (!strcmp(a.integrator, "ic")) {
        opt.integrator = IC_INTEGRATOR_IC;
        fill_ic_options(&a, &opt.ic);
        if (a.records_json) {
            if (!check_writable(a.records_json)) {
                ic_scene_free(scene);
                return 1;
            }
            aovs.want_record_list = 1;
            opt.aovs = &aovs;
        }
        if (a.aov) {
            aovs.want_indirect = strstr(a.aov, "indirect") != NULL;
            aovs.want_records = strstr(a.aov, "records") != NULL;
            aovs.want_density = strstr(a.aov, "density") != NULL;
            aovs.want_amap = strstr(a.aov, "amap") != NULL;
            opt.aovs = &aovs;
        }
    }
    ic_image img = {0};
    ic_render_stats st;
    ic_result r = ic_render(scene, &opt, &img, &st, &err);
    if (prog.enabled)
        fputc('\n', stderr);
    if (r != IC_OK) {
        fprintf(stderr, "irrcache render: %s: %s\n", a.scene, err.message);
        ic_scene_free(scene);
        return 1;
    }
    /* Loading counts as a phase of the run too. */
    if (st.phase_count < IC_MAX_PHASES) {
        memmove(&st.phases[1], &st.phases[0], sizeof st.phases[0] * (size_t)st.phase_count);
        st.phases[0].name = "load";
        st.phases[0].seconds = t_load;
        ++st.phase_count;
    }
    int w = img.width, h = img.height;
    ic_image_write_options wo = {0};
    wo.exposure = a.has_exposure ? (float)a.exposure : ic_scene_exposure(scene);
    int ok = 1;
    for (int i = 0; i < a.output_count && ok; ++i) {
        if (ic_image_write(a.outputs[i], &img, &wo, &err) != IC_OK) {
            fprintf(stderr, "irrcache render: %s\n", err.message);
            ok = 0;
        }
    }
    if (ok && opt.aovs)
        ok = write_aovs(a.outputs[0], &aovs, &wo);
    if (ok && a.records_json)
        ok = write_records_json(a.records_json, &aovs);
    free(aovs.record_views);
    ic_image_free(&img);
    ic_image_free(&aovs.indirect);
    ic_image_free(&aovs.records);
    ic_image_free(&aovs.density);
    ic_image_free(&aovs.amap);
    ic_scene_free(scene);
    if (ok && a.stats_path)
        ok = write_stats(a.stats_path, &a, w, h, &st);
    if (ok && !a.quiet) {
        fprintf(stderr, "irrcache: %dx%d, %d spp", w, h, st.spp);
        if (st.spp_max != st.spp)
            fprintf(stderr, " (adaptive, up to %d in a pixel)", st.spp_max);
        fprintf(stderr, ", %.2fs, %.2f Mrays/s", st.seconds, st.rays_per_second * 1e-6);
        if (opt.integrator == IC_INTEGRATOR_IC)
            fprintf(stderr, ", %u records in %d passes", st.records, st.passes);
        if (st.cached_emitters)
            fprintf(stderr, ", %u emitting triangles lit through the records", st.cached_emitters);
        fputc('\n', stderr);
    }
    return ok ? 0 : 1;
}
