/*
 * render.c — `irrcache render SCENE -o OUT [options]`.
 *
 * The options are declared once, in options.h. Every output (images, AOVs, --stats, --records-json,
 * --save-cache) is checked before rendering starts (outputs.h), so a long render is never lost to a
 * typo; when one output still fails at the end, the others are written and the exit status is 3 (the
 * render itself finished: a caller can tell that from 1, a failure before or during the render).
 *
 * Under mpirun (cluster.h) every rank renders its share; rank 0 alone checks and writes the outputs and
 * shows progress. A failure before the render (options, outputs, the scene on any rank) is agreed on:
 * the lowest failing rank prints it and every rank exits non-zero; a failure during the render ends
 * the job (MPI_Abort) once the failing rank has printed it, before any output is written.
 */
#include "cli.h"
#include "cluster.h"
#include "exr_meta.h"
#include "json_out.h"
#include "options.h"
#include "outputs.h"

#include "core/atomic_file.h"
#include "irrcache/render.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>
#include <unistd.h>

typedef ic_cli_args render_args;

typedef struct progress_state {
    int enabled;
    double last;
    const char *last_phase;
} progress_state;

/* The progress line: the phase and its share, the render's elapsed time and the whole render's time left
 * ('-' while the library cannot estimate it: cache construction without --time). */
static void on_progress(void *user, const ic_render_progress *r)
{
    progress_state *p = user;
    if (!p->enabled)
        return;
    double t = ic_cli_seconds();
    int new_phase = p->last_phase != r->phase;
    if (!new_phase && t - p->last < 0.1 && r->fraction < 1.0)
        return;
    p->last = t;
    p->last_phase = r->phase;
    char share[16] = "", eta[32] = "ETA      -";
    if (r->fraction >= 0.0)
        snprintf(share, sizeof share, "%5.1f%%", 100.0 * fmin(r->fraction, 1.0));
    if (r->eta >= 0.0)
        snprintf(eta, sizeof eta, "ETA %6.1fs", r->eta);
    fprintf(stderr, "\r%-16s %6s  elapsed %6.1fs  %s ", r->phase, share, r->elapsed, eta);
    fflush(stderr);
}

/* The exit status when the render finished but an output could not be written (--help). */
#define EXIT_OUTPUT_FAILED 3

/* What each rank reports of its share (ic_render_stats' rank_ fields and its wall time), gathered to rank 0. */
#define RANK_FIGURES (6 + 2 * IC_STATS_PASSES)
static void rank_figures(const ic_render_stats *st, double f[RANK_FIGURES])
{
    f[0] = (double)st->rank_records_gathered;
    f[1] = (double)st->rank_pixel_samples;
    f[2] = st->rank_comm_seconds;
    f[3] = (double)st->rank_comm_bytes;
    f[4] = st->seconds;
    f[5] = st->rank_render_seconds;
    for (int p = 0; p < IC_STATS_PASSES; ++p) {
        f[6 + p] = st->rank_comm_seconds_per_pass[p];
        f[6 + IC_STATS_PASSES + p] = (double)st->rank_comm_bytes_per_pass[p];
    }
}

static int write_stats(const char *path, const render_args *a, int w, int h, const ic_render_stats *st,
                       const double *per_rank_figures)
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
        for (int i = 0; i < st->passes && i < IC_STATS_PASSES; ++i)
            cJSON_AddItemToArray(per, cJSON_CreateNumber(st->records_per_pass[i]));
        if (st->passes > IC_STATS_PASSES) /* a library caller's larger bound: say what has no entry */
            cJSON_AddNumberToObject(o, "passes_without_entry", st->passes - IC_STATS_PASSES);
        if (a->render.ic.strategy == IC_STRATEGY_BATCH)
            cJSON_AddNumberToObject(o, "coverage_records", st->coverage_records);
        if (a->render.ic.strategy == IC_STRATEGY_ADAPTIVE)
            cJSON_AddNumberToObject(o, "refinements", st->refinements);
        cJSON *ext = cJSON_AddObjectToObject(o, "record_extent");
        cJSON_AddNumberToObject(ext, "min", st->extent_min);
        cJSON_AddNumberToObject(ext, "mean", st->extent_mean);
        cJSON_AddNumberToObject(ext, "max", st->extent_max);
        const uint32_t own = st->records - st->hit_records; /* the image's records */
        cJSON_AddNumberToObject(ext, "elliptical_share", own ? (double)st->ellipse_records / own : 0.0);
        cJSON_AddNumberToObject(o, "hit_records", st->hit_records);
        cJSON_AddNumberToObject(o, "cached_emitters", st->cached_emitters);
        if (a->render.ic.radiance_cache == IC_CACHE_ON) {
            cJSON_AddNumberToObject(o, "irradiance_records", st->records - st->radiance_records);
            cJSON_AddNumberToObject(o, "radiance_records", st->radiance_records);
            cJSON_AddNumberToObject(o, "radiance_record_bytes", st->radiance_record_bytes);
        }
        cJSON_AddBoolToObject(o, "cut_short", st->cut_short);
        cJSON_AddBoolToObject(o, "cut_by_time", st->cut_by_time);
        if (a->render.ic.strategy == IC_STRATEGY_BATCH && !a->render.ic.load_cache)
            cJSON_AddNumberToObject(o, "uncovered_share", st->uncovered_share);
    }
    cJSON *phases = cJSON_AddObjectToObject(o, "phases");
    for (int i = 0; i < st->phase_count; ++i)
        cJSON_AddNumberToObject(phases, st->phases[i].name, st->phases[i].seconds);
    if (st->cancelled) { /* SIGINT or SIGTERM: the image is partial */
        cJSON_AddBoolToObject(o, "interrupted", 1);
        cJSON_AddNumberToObject(o, "completed", st->completed);
        cJSON_AddNumberToObject(o, "spp_min", st->spp_min); /* the fewest samples a pixel holds */
    }
    /* How the ranks shared the work (MPI): only when there were several, so a single process's figures
     * read as they always did. */
    if (st->ranks > 1)
        cJSON_AddNumberToObject(o, "ranks", st->ranks);
    cJSON *per_rank = st->ranks > 1 ? cJSON_AddArrayToObject(o, "per_rank") : NULL;
    for (int k = 0; per_rank && k < st->ranks; ++k) {
        const double *f = &per_rank_figures[k * RANK_FIGURES];
        cJSON *rk = cJSON_CreateObject();
        cJSON_AddItemToObject(rk, "records_gathered", ic_cli_json_u64((uint64_t)f[0]));
        cJSON_AddItemToObject(rk, "pixel_samples", ic_cli_json_u64((uint64_t)f[1]));
        cJSON_AddNumberToObject(rk, "comm_seconds", f[2]);
        cJSON_AddItemToObject(rk, "comm_bytes", ic_cli_json_u64((uint64_t)f[3]));
        cJSON_AddNumberToObject(rk, "seconds", f[4]);
        cJSON_AddNumberToObject(rk, "render_seconds", f[5]);
        if (a->render.integrator == IC_INTEGRATOR_IC && a->render.ic.strategy == IC_STRATEGY_BATCH &&
            !a->render.ic.load_cache) {
            cJSON *sec = cJSON_AddArrayToObject(rk, "comm_seconds_per_pass");
            cJSON *bytes = cJSON_AddArrayToObject(rk, "comm_bytes_per_pass");
            for (int p = 0; p < st->passes && p < IC_STATS_PASSES; ++p) {
                cJSON_AddItemToArray(sec, cJSON_CreateNumber(f[6 + p]));
                cJSON_AddItemToArray(bytes, ic_cli_json_u64((uint64_t)f[6 + IC_STATS_PASSES + p]));
            }
        }
        cJSON_AddItemToArray(per_rank, rk);
    }
    cJSON_AddItemToObject(o, "settings", ic_cli_settings_json(a));
    return ic_cli_write_json("render", path, o, 1);
}

/* AOVs go next to the first output: <stem>.<aov>.<ext>, with .exr for linear data and .png for the
 * overlay; when the first output is itself an EXR, the linear ones are its layers instead. The images
 * that are codes, not radiance (the records' marks and the a_i map: colours whose meaning their legend
 * gives; the density: a count), are written without the image's exposure. */
typedef struct aov_file {
    const char *name, *suffix, *option;
    int code;
} aov_file;
static const aov_file aov_files[] = {{"indirect", ".indirect.exr", "--aov indirect", 0},
                                     {"glossy", ".glossy.exr", "--aov glossy", 0},
                                     {"records", ".records.png", "--aov records", 1},
                                     {"density", ".density.exr", "--aov density", 1},
                                     {"amap", ".amap.png", "--aov amap", 1}};
#define AOV_COUNT (int)(sizeof aov_files / sizeof aov_files[0])

/* 1 if path names an OpenEXR file (.exr in any case, as the writer takes it). */
static int is_exr(const char *path)
{
    size_t n = strlen(path);
    return n >= 4 && !strcasecmp(path + n - 4, ".exr");
}

/* 1 if AOV k is a layer of the first output rather than a file of its own. */
static int aov_is_layer(const char *first, int k)
{
    return is_exr(first) && is_exr(aov_files[k].suffix);
}

static void aov_path(const char *first, int k, char *path, size_t size)
{
    char stem[4096];
    snprintf(stem, sizeof stem, "%s", first);
    char *dot = strrchr(stem, '.');
    char *slash = strrchr(stem, '/');
    if (dot && (!slash || dot > slash))
        *dot = 0;
    snprintf(path, size, "%s%s", stem, aov_files[k].suffix);
}

/* Writes every AOV that was made; returns the number that failed (each reported). */
static int write_aovs(const char *first, const ic_render_aovs *aovs, const ic_image_write_options *wo)
{
    const ic_image *imgs[AOV_COUNT] = {&aovs->indirect, &aovs->glossy, &aovs->records, &aovs->density, &aovs->amap};
    int failed = 0;
    for (int k = 0; k < AOV_COUNT; ++k) {
        if (!imgs[k]->rgb || aov_is_layer(first, k))
            continue;
        char path[4200];
        aov_path(first, k, path, sizeof path);
        ic_image_write_options wo_k = *wo;
        if (aov_files[k].code)
            wo_k.exposure = 0.0f;
        ic_error err;
        if (ic_image_write(path, imgs[k], &wo_k, &err) != IC_OK) {
            ic_cli_eprintf("irrcache render: %s %s\n", aov_files[k].option, err.message);
            ++failed;
        }
    }
    return failed;
}

/* Writes img to every -o output, the first with `layers` (its EXR layers) and then wo_layers' attributes;
 * returns how many failed, each said on stderr after `what` (unless its entry of `failing` says it failed
 * last time: said once), and named in `failed` (may be NULL) after a comma. failing (may be NULL): per
 * output, 1 if its write failed, updated. */
static int write_outputs(const render_args *a, const ic_image *img, const ic_image_write_options *wo,
                         const ic_image_layer *layers, uint32_t layer_count, const ic_image_write_options *wo_layers,
                         const char *what, char *failed, size_t size, int *failing)
{
    int n = 0;
    for (int i = 0; i < a->output_count; ++i) {
        ic_image_write_options wo_i = *wo;
        if (i == 0 && layer_count) {
            wo_i.meta = wo_layers->meta;
            wo_i.meta_count = wo_layers->meta_count;
            wo_i.layers = layers;
            wo_i.layer_count = layer_count;
        }
        ic_error err;
        const int failed_before = failing && failing[i];
        if (failing)
            failing[i] = 0;
        if (ic_image_write(a->outputs[i], img, &wo_i, &err) == IC_OK)
            continue;
        if (failing)
            failing[i] = 1;
        if (!failed_before)
            ic_cli_eprintf("irrcache render: %s %s\n", what, err.message);
        if (failed)
            snprintf(failed + strlen(failed), size - strlen(failed), "%s-o %s", failed[0] ? ", " : "",
                     a->outputs[i]);
        ++n;
    }
    return n;
}

/* --checkpoint: the final render's image so far into every -o output, marked partial. A write that fails
 * is said (once, until one succeeds: a full disk would say it at every checkpoint of a long render) and the
 * render goes on (the next checkpoint, or the final image, tries again). */
typedef struct checkpoint_state {
    const render_args *a;
    ic_image_write_options wo; /* exposure and half floats of the final outputs */
    int failing[IC_CLI_MAX_OUTPUTS]; /* 1: the output's last checkpoint could not be written */
    double held[IC_CLI_MAX_OUTPUTS]; /* share of the final render in the checkpoint the output holds; 0: none */
} checkpoint_state;

static void on_checkpoint(void *user, const ic_render_checkpoint *cp)
{
    checkpoint_state *k = user;
    ic_render_stats st;
    memset(&st, 0, sizeof st);
    st.seed = cp->seed;
    st.spp = cp->spp;
    st.seconds = cp->seconds;
    ic_cli_exr_meta meta;
    ic_cli_exr_meta_make(k->a, &st, &meta);
    ic_cli_exr_meta_partial(&meta, "checkpoint", cp->completed);
    ic_image_write_options wo = k->wo;
    wo.meta = meta.items;
    wo.meta_count = meta.count;
    write_outputs(k->a, cp->image, &wo, NULL, 0, NULL, "--checkpoint: -o", NULL, 0, k->failing);
    for (int i = 0; i < k->a->output_count; ++i)
        if (!k->failing[i])
            k->held[i] = fmax(cp->completed, 1e-9); /* a checkpoint before the first tile holds one too */
    ic_cli_exr_meta_free(&meta);
}

/* After the final write: an output that failed but holds a checkpoint of this render is not the file it was
 * before the run, nor the final image; said, so that its partial image (only an EXR is marked) is not
 * taken for either. */
static void say_checkpoints_held(const checkpoint_state *k, const int *failing)
{
    for (int i = 0; i < k->a->output_count; ++i)
        if (failing[i] && k->held[i] > 0.0)
            ic_cli_eprintf("irrcache render: -o %s holds this run's last checkpoint (%.0f %% of the final render, "
                            "the other tiles black), not the final image\n", k->a->outputs[i], 100.0 * k->held[i]);
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
        /* A record behind the camera has no image position: its view's 0, 0 would read as the top-left pixel. */
        if (v->radius_px > 0.0f) {
            cJSON_AddNumberToObject(r, "px", v->px);
            cJSON_AddNumberToObject(r, "py", v->py);
            cJSON_AddNumberToObject(r, "radius_px", v->radius_px);
        }
        cJSON_AddBoolToObject(r, "visible", v->visible);
        if (v->is_radiance)
            cJSON_AddBoolToObject(r, "radiance", 1);
        if (v->ellipse_ratio > 0.0f) {
            cJSON_AddNumberToObject(r, "ellipse_ratio", v->ellipse_ratio);
            const double ax[3] = {v->ellipse_axis.x, v->ellipse_axis.y, v->ellipse_axis.z};
            cJSON_AddItemToObject(r, "minor_axis", cJSON_CreateDoubleArray(ax, 3));
        }
        cJSON_AddItemToArray(list, r);
    }
    return ic_cli_write_json("render", path, list, 1);
}

/* Parses the options; ranks other than 0 parse silently (the same command line gives every rank the
 * same verdict, and rank 0 says it once). */
static int parse_quietly_unless(int speak, int argc, char **argv, render_args *a)
{
    int saved = ic_cli_cluster_mute(!speak);
    int rc = ic_cli_parse(argc, argv, a);
    ic_cli_cluster_unmute(saved);
    return rc;
}

static int render_command(int argc, char **argv, ic_comm *comm);

static void free_results(ic_image *img, ic_render_aovs *aovs, ic_scene *scene)
{
    free(aovs->record_views);
    ic_image_free(img);
    ic_image_free(&aovs->indirect);
    ic_image_free(&aovs->records);
    ic_image_free(&aovs->density);
    ic_image_free(&aovs->amap);
    ic_image_free(&aovs->glossy);
    ic_scene_free(scene);
}

void ic_cli_scene_warnings(const char *who, const ic_scene *scene, const char *path, const char *outcome)
{
    /* what the loader approximated or left out (a Mitsuba scene's unsupported elements, dropped slivers) */
    for (const char *w = ic_scene_warnings(scene); *w;) {
        size_t len = strcspn(w, "\n");
        ic_cli_eprintf("%s: warning: %.*s\n", who, (int)len, w);
        w += len + (w[len] == '\n');
    }
    if (ic_scene_light_count(scene) == 0)
        ic_cli_eprintf("%s: warning: %s has no light (no emitting triangle, light or environment), so %s; add "
                        "an emitter, a light or an environment\n", who, path, outcome);
}

int ic_cli_render(int argc, char **argv)
{
    int failed = 0;
    ic_comm *comm = ic_cli_cluster_start(&argc, &argv, &failed);
    if (failed)
        return 1;
    int rc = render_command(argc, argv, comm);
    ic_cli_cluster_end(comm);
    return rc;
}

/* Before the render: what failed on this rank, agreed on by every rank (ic_cli_cluster_agree). */
static int agree(ic_comm *comm, int status, const char *message)
{
    return ic_cli_cluster_agree(comm, status, message, "irrcache render");
}

static int render_command(int argc, char **argv, ic_comm *comm)
{
    int rank = ic_cli_cluster_rank(comm), ranks = ic_cli_cluster_size(comm);
    render_args a;
    int rc = parse_quietly_unless(rank == 0, argc, argv, &a);
    if (rc == -1 - IC_ARG_HELP || rc == -1 - IC_ARG_HELP_MARKDOWN) {
        if (rank != 0)
            return 0;
        if (rc == -1 - IC_ARG_HELP)
            ic_cli_print_help(stdout);
        else
            ic_cli_print_markdown(stdout);
        return ic_cli_flush_stdout("irrcache render");
    }
    char message[1400] = "";
    if (rc)
        return agree(comm, rc, message);
    /* Every file the run will write, checked (by the rank that writes them) before anything is rendered. */
    ic_cli_output outs[IC_CLI_MAX_OUTPUTS + AOV_COUNT + 3];
    char aov_paths[AOV_COUNT][4200];
    int n_outs = 0;
    for (int i = 0; i < a.output_count; ++i)
        outs[n_outs++] = (ic_cli_output){"-o", a.outputs[i], NULL};
    for (int k = 0; k < AOV_COUNT && a.aov; ++k)
        if (strstr(a.aov, aov_files[k].name) && !aov_is_layer(a.outputs[0], k)) {
            aov_path(a.outputs[0], k, aov_paths[k], sizeof aov_paths[k]);
            outs[n_outs++] = (ic_cli_output){aov_files[k].option, aov_paths[k], NULL};
        }
    if (a.stats_path)
        outs[n_outs++] = (ic_cli_output){"--stats", a.stats_path, NULL};
    if (a.records_json)
        outs[n_outs++] = (ic_cli_output){"--records-json", a.records_json, NULL};
    if (a.render.ic.save_cache)
        outs[n_outs++] = (ic_cli_output){"--save-cache", a.render.ic.save_cache, NULL};
    const ic_cli_input ins[2] = {{"the scene file", a.scene, NULL},
                                 {"the --load-cache file", a.render.ic.load_cache, "--save-cache"}};
    if (rank == 0 && !ic_cli_check_outputs("irrcache render", outs, n_outs, ins, 2))
        return agree(comm, 2, message);
    /* The library refuses it too, but on every rank at once: said here, it is said once. */
    if (ranks > 1 && a.render.integrator == IC_INTEGRATOR_IC && a.render.ic.strategy == IC_STRATEGY_LAZY) {
        snprintf(message, sizeof message, "irrcache render: --strategy lazy builds the cache one shading point at a "
                 "time, each gather needing every record made before it, so %d ranks cannot share it; use "
                 "--strategy batch or adaptive, or run one process", ranks);
        return agree(comm, 2, rank == 0 ? message : "");
    }

    progress_state prog = {0};
    prog.enabled = rank == 0 && !a.quiet && isatty(fileno(stderr));

    ic_error err = {0};
    ic_scene *scene = NULL;
    double t_load = ic_cli_seconds();
    if (ic_scene_load(a.scene, &a.load, &scene, &err) != IC_OK) {
        if (ranks > 1)
            snprintf(message, sizeof message, "irrcache render: rank %d of %d: %s", rank, ranks, err.message);
        else
            snprintf(message, sizeof message, "irrcache render: %s", err.message);
        return agree(comm, 1, message);
    }
    /* The files the scene read (its meshes, textures, ...) are known now: no output may be one of them. */
    const int overwrites = rank == 0 && !ic_cli_check_scene_files("irrcache render", outs, n_outs, scene);
    if ((rc = agree(comm, overwrites ? 2 : 0, message)) != 0) {
        ic_scene_free(scene);
        return rc;
    }
    t_load = ic_cli_seconds() - t_load;
    if (rank == 0)
        ic_cli_scene_warnings("irrcache render", scene, a.scene, "the image will be black");

    ic_render_options opt = a.render;
    /* The library reads 0 as "the default" and a negative value as "none": --min-radius-px 0 asks for no
     * floor (it gave the default 3 px without a word). */
    if (a.given[IC_ARG_MIN_RADIUS_PX] && opt.ic.min_radius_px == 0.0f)
        opt.ic.min_radius_px = -1.0f;
    opt.comm = comm;
    opt.progress_detail = on_progress;
    opt.progress_user = &prog;
    ic_image_write_options wo = {0};
    wo.exposure = a.given[IC_ARG_EXPOSURE] ? (float)a.exposure : ic_scene_exposure(scene);
    wo.exr_half = a.exr_half;
    checkpoint_state checkpoints = {&a, wo, {0}, {0}};
    if (rank == 0 && opt.checkpoint_seconds > 0.0) { /* one process writes (the library ignores a shared comm) */
        opt.checkpoint = on_checkpoint;
        opt.checkpoint_user = &checkpoints;
    }
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
        aovs.want_glossy = strstr(a.aov, "glossy") != NULL;
        opt.aovs = &aovs;
    }
    ic_image img = {0};
    ic_render_stats st;
    /* One process: SIGINT or SIGTERM stops the render and the image so far is written (main.c). Under
     * mpirun every rank must agree on the image, so a signal ends the job as before. */
    if (ranks <= 1) {
        opt.cancel = &ic_cli_stop_signal;
        ic_cli_rendering = 1;
    }
    ic_result r = ic_render(scene, &opt, &img, &st, &err);
    ic_cli_rendering = 0;
    if (prog.enabled)
        fputc('\n', stderr);
    if (r != IC_OK) {
        if (ranks > 1) {
            /* The other ranks may wait in an exchange this rank will never join: end the job. A failure
             * every rank meets (a cache file that does not match) is said by rank 0, whose abort ends the
             * others within the pause they take before speaking; a failure of one rank alone is said by it. */
            if (rank != 0)
                nanosleep(&(struct timespec){1, 0}, NULL);
            ic_cli_eprintf("irrcache render: rank %d of %d: %s: %s; stopping all ranks\n", rank, ranks, a.scene,
                    err.message);
            ic_cli_cluster_abort(comm, 1);
        }
        ic_cli_eprintf("irrcache render: %s: %s\n", a.scene, err.message);
        ic_scene_free(scene);
        return 1;
    }
    double figures[RANK_FIGURES], *per_rank = malloc(sizeof *per_rank * RANK_FIGURES * (size_t)ranks);
    rank_figures(&st, figures);
    if (!per_rank) {
        ic_cli_eprintf("irrcache render: out of memory for %d ranks' statistics\n", ranks);
        ic_cli_cluster_abort(comm, 1);
        ic_scene_free(scene);
        return 1;
    }
    ic_cli_cluster_gather(comm, figures, RANK_FIGURES, per_rank);
    if (rank != 0) {
        /* Rank 0 writes every output; this rank's share is done. */
        free(per_rank);
        free_results(&img, &aovs, scene);
        return 0;
    }
    /* Loading counts as a phase of the run too. */
    if (st.phase_count < IC_MAX_PHASES) {
        memmove(&st.phases[1], &st.phases[0], sizeof st.phases[0] * (size_t)st.phase_count);
        st.phases[0].name = "load";
        st.phases[0].seconds = t_load;
        ++st.phase_count;
    }
    int w = img.width, h = img.height;
    ic_cli_exr_meta meta, aov_meta;
    ic_cli_exr_meta_make(&a, &st, &meta);
    wo.meta = meta.items;
    wo.meta_count = meta.count;
    /* The images that hold the AOVs (their files, the first output's layers) are marked partial too when
     * an interrupt cut the AOVs' renders after a whole final render. */
    const int aovs_cut = st.cancelled && st.completed >= 1.0;
    ic_image_write_options wo_aovs = wo;
    memset(&aov_meta, 0, sizeof aov_meta);
    if (aovs_cut) {
        ic_cli_exr_meta_make(&a, &st, &aov_meta);
        ic_cli_exr_meta_partial(&aov_meta, "interrupted during the --aov renders", st.completed);
        wo_aovs.meta = aov_meta.items;
        wo_aovs.meta_count = aov_meta.count;
    }
    /* One failed output does not cost the others: each is written, and the failures are named. */
    char failed[1024] = "";
    int n_failed = 0;
#define FAILED(what, path)                                                                              \
    (++n_failed, snprintf(failed + strlen(failed), sizeof failed - strlen(failed), "%s%s %s",           \
                          failed[0] ? ", " : "", what, path))
    /* The linear AOVs ride in the first output when it is an EXR, as its layers. */
    const ic_image *aov_imgs[AOV_COUNT] = {&aovs.indirect, &aovs.glossy, &aovs.records, &aovs.density, &aovs.amap};
    ic_image_layer layers[AOV_COUNT];
    uint32_t layer_count = 0;
    for (int k = 0; k < AOV_COUNT && opt.aovs && a.aov; ++k)
        if (aov_imgs[k]->rgb && aov_is_layer(a.outputs[0], k))
            layers[layer_count++] = (ic_image_layer){aov_files[k].name, aov_imgs[k]};
    int final_failing[IC_CLI_MAX_OUTPUTS] = {0};
    n_failed += write_outputs(&a, &img, &wo, layers, layer_count, &wo_aovs, "-o", failed, sizeof failed,
                              final_failing);
    say_checkpoints_held(&checkpoints, final_failing);
    if (opt.aovs && a.aov) {
        int n = write_aovs(a.outputs[0], &aovs, &wo_aovs);
        if (n)
            FAILED("--aov", a.aov);
    }
    if (a.records_json && !write_records_json(a.records_json, &aovs))
        FAILED("--records-json", a.records_json);
    if (st.save_error[0]) {
        ic_cli_eprintf("irrcache render: --save-cache %s\n", st.save_error);
        if (!st.cancelled) /* an interrupted render leaves its cache unwritten on purpose; 130/143 says why */
            FAILED("--save-cache", a.render.ic.save_cache);
    }
    ic_cli_exr_meta_free(&meta);
    ic_cli_exr_meta_free(&aov_meta);
    free_results(&img, &aovs, scene);
    if (st.cancelled) {
        const char *sig = ic_cli_stop_signal == SIGTERM ? "SIGTERM" : "SIGINT";
        const int budget = opt.time_budget > 0.0;
        if (aovs_cut)
            ic_cli_eprintf("irrcache render: interrupted by %s during the --aov renders: the image is whole; the "
                            "--aov indirect and glossy images hold the tiles they finished, the others black\n", sig);
        else if (st.completed > 0.0 && budget && st.spp_min == st.spp_max)
            ic_cli_eprintf("irrcache render: interrupted by %s between passes of the --time budget: the outputs "
                            "hold the image so far, %d samples per pixel\n", sig, st.spp_max);
        else if (st.completed > 0.0 && st.spp_min > 0 && st.spp_min < st.spp_max) /* a later pass cut short */
            ic_cli_eprintf("irrcache render: interrupted by %s: the outputs hold the image so far (the tiles its last "
                            "pass finished at %s%d samples per pixel, the others at the %d of the passes before)\n",
                    sig, budget ? "" : "up to ", st.spp_max, st.spp_min);
        else if (st.completed > 0.0)
            ic_cli_eprintf("irrcache render: interrupted by %s: the outputs hold the image so far (%.0f %% of the "
                            "final render; the other tiles are black)\n", sig, 100.0 * st.completed);
        else
            ic_cli_eprintf("irrcache render: interrupted by %s during cache construction: the outputs hold a "
                            "preview of one sample per pixel from the %u records made so far\n", sig, st.records);
    } else if (st.cut_by_time)
        ic_cli_eprintf("irrcache render: warning: cache construction stopped at its share of the --time budget "
                        "(%d passes) before it converged; give more time for a converged cache\n", st.passes);
    else if (st.cut_short && opt.ic.strategy == IC_STRATEGY_BATCH)
        /* The limit counts the passes after pass 0 (the geometry's candidates); the stats' passes count it too. */
        ic_cli_eprintf("irrcache render: warning: cache construction stopped at its pass limit, --max-passes %d "
                        "(after the geometry pass 0: %d passes in the stats), before it converged; raise "
                        "--max-passes\n", opt.ic.max_passes > 0 ? opt.ic.max_passes : IC_DEFAULT_MAX_PASSES, st.passes);
    else if (st.cut_short)
        ic_cli_eprintf("irrcache render: warning: cache construction stopped at its bound of %d passes before it "
                        "converged\n", st.passes);
    if (a.stats_path && !write_stats(a.stats_path, &a, w, h, &st, per_rank))
        FAILED("--stats", a.stats_path);
    free(per_rank);
#undef FAILED
    int ok = n_failed == 0;
    /* The outputs tried: each -o, the AOV files as one, the record list, the cache (not written on
     * purpose when interrupted) and the stats. */
    const int n_outputs = a.output_count + (opt.aovs && a.aov) + (a.records_json != NULL) +
                          (a.render.ic.save_cache != NULL && !st.cancelled) + (a.stats_path != NULL);
    if (!ok)
        ic_cli_eprintf("irrcache render: the render %s but %d output%s could not be written (%s)%s: free "
                        "disk space or fix the paths and run again\n", st.cancelled ? "was interrupted" : "finished",
                n_failed, n_failed == 1 ? "" : "s", failed,
                n_failed < n_outputs ? "; the other outputs were written" : "");
    if (ok && !a.quiet) {
        /* Interrupted, the pixels hold from spp_min to spp_max samples (the line above says how), spp their mean. */
        ic_cli_eprintf("irrcache: %dx%d, %d spp%s", w, h, st.spp,
                       st.cancelled && st.spp_min != st.spp_max ? " (mean)" : "");
        if (ranks > 1)
            ic_cli_eprintf(", %d ranks x %d threads", ranks, st.threads);
        if (st.spp_max != st.spp && !st.cancelled)
            ic_cli_eprintf(" (adaptive, up to %d in a pixel)", st.spp_max);
        ic_cli_eprintf(", %.2fs, %.2f Mrays/s", st.seconds, st.rays_per_second * 1e-6);
        if (opt.integrator == IC_INTEGRATOR_IC)
            ic_cli_eprintf(", %u records in %d passes", st.records, st.passes);
        if (st.radiance_records)
            ic_cli_eprintf(" (%u of them radiance records)", st.radiance_records);
        if (st.hit_records)
            ic_cli_eprintf(" (%u of them where hemisphere rays land)", st.hit_records);
        if (st.cached_emitters)
            ic_cli_eprintf(", %u emitting triangles lit through the records", st.cached_emitters);
        fputc('\n', stderr);
    }
    /* An interrupted render ends as the signal asked, 128 + its number, an output that failed or not (said
     * above): a caller that sent SIGTERM, or a shell loop stopped by Ctrl-C, learns of the signal. */
    if (st.cancelled)
        return 128 + (int)ic_cli_stop_signal;
    return ok ? 0 : EXIT_OUTPUT_FAILED;
}
