/*
 * render.c — `irrcache render SCENE -o OUT [options]`.
 *
 * The options are declared once, in options.h. Every output path is checked for a known format and a
 * writable folder before rendering starts, so a long render is never lost to a typo.
 */
#include "cli.h"
#include "json_out.h"
#include "options.h"

#include "core/atomic_file.h"
#include "irrcache/render.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

typedef ic_cli_args render_args;

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
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "scene", a->scene);
    cJSON_AddStringToObject(o, "integrator", ic_cli_choice(a, IC_ARG_INTEGRATOR));
    cJSON_AddNumberToObject(o, "width", w);
    cJSON_AddNumberToObject(o, "height", h);
    cJSON_AddNumberToObject(o, "spp", st->spp);
    cJSON_AddNumberToObject(o, "threads", st->threads);
    cJSON_AddNumberToObject(o, "seconds", st->seconds);
    cJSON_AddItemToObject(o, "rays", ic_cli_json_u64(st->rays));
    cJSON_AddNumberToObject(o, "rays_per_second", st->rays_per_second);
    if (st->spp_max != st->spp)
        cJSON_AddNumberToObject(o, "spp_max", st->spp_max);
    if (a->render.integrator == IC_INTEGRATOR_IC) {
        cJSON_AddStringToObject(o, "strategy", ic_cli_choice(a, IC_ARG_STRATEGY));
        cJSON_AddNumberToObject(o, "records", st->records);
        cJSON_AddNumberToObject(o, "passes", st->passes);
        cJSON_AddItemToObject(o, "gather_rays", ic_cli_json_u64(st->gather_rays));
        cJSON *per = cJSON_AddArrayToObject(o, "records_per_pass");
        for (int i = 0; i < st->passes && i < 32; ++i)
            cJSON_AddItemToArray(per, cJSON_CreateNumber(st->records_per_pass[i]));
        if (a->render.ic.strategy == IC_STRATEGY_ADAPTIVE)
            cJSON_AddNumberToObject(o, "refinements", st->refinements);
        cJSON_AddNumberToObject(o, "cached_emitters", st->cached_emitters);
        cJSON_AddBoolToObject(o, "cut_short", st->cut_short);
        if (a->render.ic.strategy == IC_STRATEGY_BATCH && !a->render.ic.load_cache)
            cJSON_AddNumberToObject(o, "uncovered_share", st->uncovered_share);
    }
    cJSON *phases = cJSON_AddObjectToObject(o, "phases");
    for (int i = 0; i < st->phase_count; ++i)
        cJSON_AddNumberToObject(phases, st->phases[i].name, st->phases[i].seconds);
    cJSON_AddItemToObject(o, "settings", ic_cli_settings_json(a));
    return ic_cli_write_json("render", path, o, 1);
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
    cJSON *list = cJSON_CreateArray();
    for (uint32_t i = 0; i < aovs->record_view_count; ++i) {
        const ic_record_view *v = &aovs->record_views[i];
        cJSON *r = cJSON_CreateObject();
        cJSON_AddNumberToObject(r, "x", v->position.x);
        cJSON_AddNumberToObject(r, "y", v->position.y);
        cJSON_AddNumberToObject(r, "z", v->position.z);
        cJSON_AddNumberToObject(r, "radius", v->radius);
        cJSON_AddNumberToObject(r, "a", v->accuracy);
        cJSON_AddNumberToObject(r, "px", v->px);
        cJSON_AddNumberToObject(r, "py", v->py);
        cJSON_AddNumberToObject(r, "radius_px", v->radius_px);
        cJSON_AddBoolToObject(r, "visible", v->visible);
        cJSON_AddItemToArray(list, r);
    }
    return ic_cli_write_json("render", path, list, 1);
}

int ic_cli_render(int argc, char **argv)
{
    render_args a;
    int rc = ic_cli_parse(argc, argv, &a);
    if (rc == -1 - IC_ARG_HELP) {
        ic_cli_print_help(stdout);
        return 0;
    }
    if (rc == -1 - IC_ARG_HELP_MARKDOWN) {
        ic_cli_print_markdown(stdout);
        return 0;
    }
    if (rc)
        return rc;
    for (int i = 0; i < a.output_count; ++i)
        if (!check_writable(a.outputs[i]))
            return 1;
    if ((a.stats_path && !check_writable(a.stats_path)) ||
        (a.render.ic.save_cache && !check_writable(a.render.ic.save_cache)) ||
        (a.records_json && !check_writable(a.records_json)))
        return 1;

    progress_state prog = {0};
    prog.enabled = !a.quiet && isatty(fileno(stderr));
    prog.start = now_seconds();

    ic_error err = {0};
    ic_scene *scene = NULL;
    double t_load = now_seconds();
    if (ic_scene_load(a.scene, &a.load, &scene, &err) != IC_OK) {
        fprintf(stderr, "irrcache render: %s\n", err.message);
        return 1;
    }
    t_load = now_seconds() - t_load;

    ic_render_options opt = a.render;
    opt.progress = on_progress;
    opt.progress_user = &prog;
    ic_render_aovs aovs;
    memset(&aovs, 0, sizeof aovs);
    if (a.records_json) {
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
    wo.exposure = a.given[IC_ARG_EXPOSURE] ? (float)a.exposure : ic_scene_exposure(scene);
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
    if (ok && st.cut_short)
        fprintf(stderr, "irrcache render: warning: cache construction stopped at its pass limit (%d passes) before "
                        "it converged; with --strategy batch raise --max-passes\n", st.passes);
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
