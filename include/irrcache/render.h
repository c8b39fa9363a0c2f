/*
 * irrcache/render.h — load a scene and render it: the renderer's public entry points.
 *
 * Usage:
 *   1. ic_scene *scene; ic_scene_load("scene.json", NULL, &scene, &err);   (JSON scene or bare mesh)
 *   2. ic_render_options opt = {0}; opt.spp = 64;                           (zero fields = defaults)
 *   3. ic_image img = {0}; ic_render_stats st; ic_render(scene, &opt, &img, &st, &err);
 *   4. ic_image_write("out.exr", &img, NULL, &err); ic_image_free(&img); ic_scene_free(scene);
 *
 * Ownership: the caller owns the scene (ic_scene_free) and the image (ic_image_free). ic_render
 * borrows the scene for the duration of the call and may run on several threads. The library never
 * prints; progress goes to opt.progress (called from one thread at a time).
 */
#ifndef IRRCACHE_RENDER_H
#define IRRCACHE_RENDER_H

#include "irrcache/cache.h"
#include "irrcache/comm.h"
#include "irrcache/common.h"
#include "irrcache/defaults.h"
#include "irrcache/gather.h"
#include "irrcache/image.h"

#include <signal.h> /* sig_atomic_t */

#ifdef __cplusplus
extern "C" {
#endif

/* A loaded scene (opaque to users of the public API). */
typedef struct ic_scene ic_scene;

/* Options for loading; zero means default. */
typedef struct ic_scene_load_options {
    const char *shared_scenes_dir; /* where "shared:" mesh paths resolve (default: $IRRCACHE_SCENES,
                                      else ../shared/scenes next to the project) */
    int width, height;     /* override camera resolution (0: keep) */
    int max_texture_pixels;/* largest texture or environment map, in pixels, checked from its header before
                              it is read [IC_DEFAULT_MAX_TEXTURE_PIXELS] */
    int max_mesh_elements; /* largest vertex or face count a mesh file may declare, checked from its header
                              (PLY) before it is read and on the imported meshes [IC_DEFAULT_MAX_MESH_ELEMENTS] */
    uint64_t max_scene_bytes; /* largest JSON scene file, in bytes, checked with fstat before it is read
                              [IC_DEFAULT_MAX_SCENE_FILE_BYTES] */
    int allow_outside_paths; /* 1: files the scene names (meshes, MTL files, glTF buffers, textures, maps) may
                              lie anywhere; 0: only inside the scene file's folder tree and the shared scenes
                              folder (after symbolic links are resolved) */
    const char *camera;    /* a glTF scene: the name (a node's or a camera's) of the camera to render from
                              (NULL: the first perspective camera); any other scene refuses a name */
    const char *view;      /* a Radiance scene (.rad): the view file (rview/rpict options -vt -vp -vd -vu -vh -vv
                              -vs -vl -vo -va) to render from (NULL: a camera fitted to the scene); others refuse it */
} ic_scene_load_options;

/* Loads a scene file (JSON, Mitsuba .xml, Radiance .rad) or a bare mesh (.obj .gltf .glb .ply); on failure *out is NULL and err
 * holds "file:line: problem; what to do". opt may be NULL. */
ic_result ic_scene_load(const char *path, const ic_scene_load_options *opt, ic_scene **out, ic_error *err);
/* Frees a scene (NULL is a no-op). */
void ic_scene_free(ic_scene *scene);

/* Which estimator renders the image. */
typedef enum ic_integrator {
    IC_INTEGRATOR_PT = 0,  /* path tracing: the reference */
    IC_INTEGRATOR_IC       /* irradiance caching */
} ic_integrator;

/* How the irradiance cache is built (Ward et al. 1988; Frolov et al. 2012 §3.1; Křivánek et al. 2006 §4). */
typedef enum ic_strategy {
    IC_STRATEGY_BATCH = 0, /* Frolov et al. 2012 §3: passes of candidates, parallel gathering,
                              batch insertion; the default */
    IC_STRATEGY_LAZY,      /* Ward 1988: shading points in raster order, gather on a miss (serial reference) */
    IC_STRATEGY_ADAPTIVE   /* Křivánek et al. 2006 §4: per-record a_i refined until no shading point
                              sees a discernible discontinuity (docs/adaptive.md) */
} ic_strategy;

/* A setting that is a number or off: mode IC_CACHE_OFF switches it off; otherwise value, 0 meaning the
 * default value (zero-initialised: the default). */
typedef struct ic_switched_value {
    ic_cache_switch mode;
    float value;
} ic_switched_value;

/* Irradiance-cache options; zero means the renderer's default (given in brackets). */
/* What sets a record's extent. */
typedef enum ic_error_metric {
    IC_ERROR_SPLIT_SPHERE = 0, /* Ward's split sphere: R from the harmonic mean of the hit distances */
    IC_ERROR_HESSIAN = 1       /* the irradiance Hessian (Schwarzhaupt et al. 2012): semi-axes ε·√(L·ℓ_k),
                                  ℓ_k = √(2E/|λ_k|) where the second-order error ½dᵀHd would reach E, L an
                                  eighth of the scene's diagonal (at most 2.5 times the view's extent), ε the accuracy a (0.15·a under the
                                  Tabellion–Lamorlette weight): records as dense as √|λ/E| */
} ic_error_metric;

/* The shape of a record's extent under the Hessian metric. */
typedef enum ic_record_shape {
    IC_SHAPE_ROUND = 0,        /* a disc: the smaller semi-axis (the largest curvature) in every direction */
    IC_SHAPE_ELLIPTICAL = 1    /* an ellipse along the Hessian's eigenvectors (Schwarzhaupt et al. 2012; cache.h:
                                  ELLIPTICAL RECORDS), its aspect at most IC_MAX_ELLIPSE_ASPECT */
} ic_record_shape;

/* The most hemisphere rays the renderer gives a record (--rays, --radiance-rays and the radiance records'
 * default of IC_DEFAULT_RADIANCE_RAYS_FACTOR × --rays): below the gatherer's grid limit of 2^24. */
#define IC_MAX_RECORD_RAYS 10000000
typedef struct ic_ic_options {
    ic_strategy strategy;
    ic_cache_params cache; /* weights, accuracy [0.15 Ward, 1 T–L], clamps; max_radius [scene diagonal/8] bounds R in
                              world units, a negative value switches it off. min_radius_pixels and
                              max_radius_pixels are set by the renderer from the two fields below */
    float min_radius_px;   /* smallest influence radius a·R of a record, in pixels at its primary hit [3];
                              negative: no bound */
    float max_radius_px;   /* largest influence radius a·R, in pixels at its primary hit [48]; negative: none */
    ic_gather_opts gather; /* hemisphere sampling [stratified, 16×50 = 800 rays] */
    int no_gradients;      /* 1: records carry no gradients (interpolation is a weighted average) */
    int bounces;           /* indirect bounces in the radiance a hemisphere ray returns [max_depth − 1] */
    int recursive;         /* lazy: one cache level per bounce (Radiance's -ab) instead of path-traced bounces
                              behind each hemisphere ray; then `bounces` is the number of levels */
    int path_traced_gather;/* 1: hemisphere rays path-trace every bounce after their hit; default: where
                              records already cover a diffuse hit, they give its indirect light (ic_gathering.c:
                              hit_from_cache) and only its direct light is sampled */
    ic_cache_switch hit_records; /* batch, with hemisphere rays that read the bounces after their hit from
                              the cache (not path_traced_gather, bounces ≥ 2): before the first pass, records
                              of their own kind where probe rays from the shading points land, with 1/4 of the
                              rays, which only hemisphere rays read (ic_batch.c); off: none [on] */
    int light_samples;     /* final render: light samples per shading point and pixel sample [1] */
    ic_switched_value large_emitters; /* which emitters the records carry instead of light sampling: an
                              emitting material that covers at least `value` of the cosine-weighted
                              hemisphere at the image's median shading point is piloted (ic_emitters.c),
                              and where light sampling it would leave more error than the records'
                              hemisphere rays once averaged over the pixels the eye sees together (a large
                              source mostly hidden behind an opening), it lights the scene
                              through the records, as the environment does, and is not sampled in the
                              final render; off: every emitter is light-sampled [0.01] */
    ic_switched_value record_filter; /* record noise control after construction (ic_filter.c): each
                              record's value moves towards the kernel mean of its neighbours' within `value`
                              times its influence radius a_i·R_i, as far as their noise explains their
                              spread; off: none [3] */
    int record_sets;       /* record noise control while gathering: most hemisphere sets a record
                              gathers while its relative σ is above record_noise [1] */
    float record_noise;    /* the relative σ of E those sets aim at [0.05] */
    int max_passes;        /* batch: most construction passes, a safety bound [30] */
    int min_candidates;    /* batch: stop when a pass finds fewer new candidates [16] */
    float uncovered;       /* batch: converged when fewer than this share of a pass's eye-path look-up
                              points (where the final render will read the cache) find no record [0.001] */
    ic_switched_value pass_growth; /* batch: converged, too, when a pass after the screen stage adds fewer
                              records than `value` times the image's records already made (hit records do
                              not count); off: only `uncovered` and min_candidates decide [0.02] */
    int screen_passes;     /* batch: passes with the screen-space irradiance stage [3] */
    float dither_threshold;/* batch: need at which dithering goes from 32- to 16-pixel spacing [0.5] */
    float normal_weight;   /* batch: k of k·normDiff + posDiff (Frolov et al. 2012 §3.1.1) [4] */
    int world_stride;      /* batch: world stage traces one eye path per stride×stride pixels [2] */
    float cluster_size;    /* batch: largest cluster box diagonal, in units of the scene's working length
                              (the scene diagonal, at most 2.5 times what the camera sees; docs) [0.05] */
    const char *load_cache;/* read the records from this cache file instead of building them (must match
                              the scene, the gathering settings and the cache parameters) */
    const char *save_cache;/* write the records to this cache file after construction (atomically) */
    float weber;           /* adaptive: Weber fraction of the discernibility test (Křivánek et al. 2006 §4.3) [0.02] */
    float adaptive_growth; /* adaptive: a new record's a = growth × a of the nearest record, ≤ accuracy [1.4] */
    int adaptive_max_passes; /* adaptive: safety bound on convergence passes [64] */
    ic_error_metric error; /* what sets a record's extent [split sphere]; the Hessian needs the stratified
                              or hemicube gather */
    ic_record_shape record_shape; /* round or elliptical extents (elliptical needs the Hessian) [round] */
    ic_cache_switch radiance_cache; /* on: radiance records serve the glossy lobes of first shading points
                              whose Phong exponent is at most radiance_max_exponent (Křivánek et al. 2005);
                              off: glossy lobes are path traced [off] */
    int hsh_order;         /* radiance records: hemispherical-harmonics order n, n² coefficients per channel
                              (1…16) [IC_DEFAULT_HSH_ORDER] */
    float radiance_max_exponent; /* sharpest Phong lobe radiance records serve; sharper ones are path traced
                              [IC_DEFAULT_RADIANCE_MAX_EXPONENT] */
    int radiance_rays;     /* hemisphere rays of a radiance record [IC_DEFAULT_RADIANCE_RAYS_FACTOR × those of an
                              irradiance record, at most IC_MAX_RECORD_RAYS] */
} ic_ic_options;

/* A cache record as the camera sees it (for overlays and reports). */
typedef struct ic_record_view {
    ic_vec3 position;      /* world space */
    float radius;          /* clamped R_i */
    float accuracy;        /* a_i; the influence radius is a_i·R_i */
    float px, py;          /* image position in pixels (top-left origin); 0, 0 behind the camera */
    float radius_px;       /* influence radius a_i·R_i in pixels at the record's depth; 0 behind the camera
                              (the camera cannot project the record), positive otherwise */
    int visible;           /* 1 if the record lies on a surface the camera sees directly */
    int is_radiance;       /* 1 for a radiance record (ic_ic_options.radiance_cache), 0 for irradiance */
    float ellipse_ratio;   /* an elliptical record's minor over major semi-axis (0: round) */
    ic_vec3 ellipse_axis;  /* its minor axis, world space (zero for a round record) */
} ic_record_view;

/* Where the 2-D sample pairs of a pixel's samples come from. */
typedef enum ic_sampler {
    IC_SAMPLER_SOBOL = 0,  /* Owen-scrambled Sobol' pairs per pixel (src/core/rng.h): lower variance, default */
    IC_SAMPLER_RANDOM      /* independent random numbers */
} ic_sampler;

/* Extra images an irradiance-cache render can return (each allocated only if asked for). */
typedef struct ic_render_aovs {
    int want_indirect, want_records, want_density;
    int want_amap;         /* a_i map (see amap) */
    int want_glossy;       /* glossy AOV (see glossy) */
    int want_record_list;  /* fill record_views (malloc'd; the caller frees it) */
    ic_record_view *record_views;
    uint32_t record_view_count;
    ic_image indirect;     /* indirect diffuse radiance from the cache at the first shading point */
    ic_image glossy;       /* the glossy lobe's indirect light from the radiance records at the first shading
                              point (black where none serves it: path-traced lobes, no radiance caching) */
    ic_image records;      /* the image with record positions (dots) and influence radii (circles): irradiance
                              records red in green rings, radiance records yellow in blue rings; the image
                              under them scaled so that its lit pixels' median luminance is 0.18 */
    ic_image density;      /* number of records contributing at each pixel centre (grey level) */
    ic_image amap;         /* a_i of the heaviest record at each pixel centre on a colour ramp: blue = --accuracy,
                              red = accuracy/32 or less (log scale; Křivánek et al. 2006 figs. 7–9) */
} ic_render_aovs;

/* A progress report of ic_render (ic_render_options.progress_detail). */
typedef struct ic_render_progress {
    const char *phase;     /* what runs now: "cache passes", "final render", "indirect AOV", ... */
    double fraction;       /* share of that phase done, in [0, 1]; < 0 when unknown */
    double elapsed;        /* seconds since ic_render began */
    double eta;            /* estimated seconds until ic_render returns: the rest of the whole render (cache
                              construction, the final render, the AOVs it re-renders); < 0 while it cannot be
                              estimated: during cache construction without a time budget, whose length
                              depends on when the cache converges. With a time budget: what is left of it,
                              plus the AOVs' re-renders (they follow the budget) */
} ic_render_progress;
typedef void (*ic_render_progress_fn)(void *user, const ic_render_progress *p);

/* The final render's image so far, handed out by ic_render_options.checkpoint. */
typedef struct ic_render_checkpoint {
    const ic_image *image; /* borrowed for the call: each pixel the mean of the samples it holds; tiles not
                              yet rendered are black (a time budget's later passes: their earlier samples) */
    double completed;      /* share of the final render done (of its samples; with a time budget, of its time) */
    double seconds;        /* since ic_render began */
    int spp;               /* samples per pixel the final render aims at (0 with a time budget and no spp) */
    uint64_t seed;         /* the seed the render uses */
} ic_render_checkpoint;
typedef void (*ic_checkpoint_fn)(void *user, const ic_render_checkpoint *cp);

/* Render options; zero means default (or the scene file's value where it gives one). */
typedef struct ic_render_options {
    ic_integrator integrator;
    int spp;               /* samples per pixel (default: scene file, else 16; 64 for integrator IC) */
    int max_depth;         /* max scattering events (default: scene file, else 8) */
    int threads;           /* 0 = all cores; at most IC_MAX_THREADS */
    uint64_t seed;         /* random seed (default: scene file, else 1) */
    int has_seed;          /* 1: use `seed` even if it is 0 */
    double time_budget;    /* seconds; > 0 renders progressive passes until the budget is spent (the budget
                              of the whole call: construction comes off the film's share, and stops
                              gathering after IC_CONSTRUCTION_TIME_SHARE of it — batch and adaptive inside
                              a pass (several processes: at the pass's end), lazy after that shading
                              point; the film takes at least one sample per
                              pixel; radiance records and the AOVs' re-renders are not cut) */
    ic_sampler sampler;    /* pixel, light and BSDF sample pairs [IC_SAMPLER_SOBOL] */
    ic_cache_switch adaptive_sampling; /* IC_CACHE_ON: spp is a mean per pixel; a pilot pass of spp/4, the
                              rest shared out by each pixel's relative noise (Frolov et al. 2012 §3.2; needs
                              spp ≥ 8, no time budget); IC_CACHE_OFF: even; IC_CACHE_DEFAULT: on for
                              integrator IC when spp ≥ 8 and there is no time budget, else off */
    ic_progress_fn progress; /* each phase's share done (may be NULL) */
    void *progress_user;   /* for progress and progress_detail */
    ic_ic_options ic;      /* irradiance caching (integrator IC) */
    ic_render_aovs *aovs;  /* optional diagnostics (integrator IC); caller frees the images */
    ic_comm *comm;         /* the processes sharing this render (irrcache/comm.h): every one calls ic_render
                              with the same options and gets the same image; NULL: one process. Must outlive
                              the call; its traffic counters are updated */
    const volatile sig_atomic_t *cancel; /* optional flag (a signal handler's): once non-zero, cache construction
                              stops within its current pass (no new gather begins; the records gathered
                              are kept) and the final render at its next tile (with a time budget too: a
                              tile its last pass did not reach keeps the earlier passes' samples); a render
                              stopped before its final render began renders one sample per pixel from the
                              records it has. The render then returns IC_OK with stats.cancelled set and the
                              image it has: tiles with no samples are black. The AOVs rendered after the image
                              (indirect, glossy) stop at their next tile too (stats.cancelled, completed 1).
                              Ignored with a shared comm */
    ic_render_progress_fn progress_detail; /* progress's reports with the whole render's elapsed time and
                              estimated time left (may be NULL); called from one thread at a time */
    double checkpoint_seconds; /* > 0 with checkpoint: every this many seconds of the final render's wall time
                              (the clock starts with the final render: construction has no image), the
                              render threads finish the tiles they hold and checkpoint gets the image so far
                              on the calling thread (the time it takes is the render's); the final image is
                              the same as without. Ignored with a shared comm */
    ic_checkpoint_fn checkpoint;
    void *checkpoint_user;
    uint64_t max_image_pixels; /* largest width x height rendered, checked before anything is allocated for
                              the image (0: IC_DEFAULT_MAX_IMAGE_PIXELS, 16384 x 8192) */
} ic_render_options;

#define IC_MAX_PHASES 12 /* room for every phase of every integrator, and the CLI's "load" */

/* What a render cost. */
typedef struct ic_render_stats {
    double seconds;        /* wall time of ic_render */
    uint64_t rays;         /* rays traced (camera, shadow, bounce, gathering) */
    double rays_per_second;
    int spp;               /* samples per pixel taken (adaptive sampling: the mean) */
    int spp_max;           /* the most samples one pixel took (adaptive sampling; else spp) */
    int spp_min;           /* the fewest (adaptive sampling, or an interrupt; else spp) */
    int threads;           /* threads used */
    uint64_t seed;         /* the seed the render used (the option's, else the scene file's, else the default) */
    int cancelled;         /* 1: opt.cancel stopped the render early; the image is partial, or, with
                              completed 1, the image is whole and the AOVs rendered after it (indirect,
                              glossy) are: their tiles not begun are black */
    double completed;      /* share of the final render's samples taken (with a time budget, of those of
                              the passes it began): 1 for a complete image; a one-sample preview after an
                              interrupted construction counts 0 */
    uint32_t records;      /* cache records (integrator IC) */
    int passes;            /* construction passes (integrator IC) */
    uint32_t refinements;  /* adaptive: times a record's a_i was lowered */
    int cut_short;         /* 1: construction stopped at a limit (batch: max_passes; adaptive: its pass bound)
                              before its own criterion said the cache was done */
    int cut_by_time;       /* 1: construction stopped at its share of time_budget (cut_short is 1 too) */
    uint32_t cached_emitters; /* emitting triangles whose light the records carry (ic_ic_options.large_emitters) */
    uint32_t radiance_records; /* records of the radiance kind among `records` (ic_ic_options.radiance_cache) */
    uint32_t hit_records;  /* records of the hit stage among `records` (ic_ic_options.hit_records), which only
                              hemisphere rays read; record_extent leaves them out */
    uint32_t radiance_record_bytes; /* bytes one radiance record holds: the record and its coefficients */
    uint32_t records_per_pass[IC_STATS_PASSES]; /* new records of each pass (the first IC_STATS_PASSES) */
    uint32_t coverage_records; /* batch: records the closing coverage sweep added after the passes (not in
                              records_per_pass) */
    char save_error[1024]; /* ic_ic_options.save_cache could not be written: why (the render went on and
                              its image is good); empty when it was written or not asked for */
    double uncovered_share; /* batch: share of the last pass's eye-path look-up points no record covered */
    uint64_t gather_rays;  /* rays traced while gathering records (included in rays) */
    float extent_min, extent_mean, extent_max; /* records' influence radii a_i·R_i in scene units (what the
                              split sphere or the Hessian set, after the clamps; an ellipse's major semi-axis;
                              integrator IC, 0 without records) */
    uint32_t ellipse_records; /* records with an elliptical extent, hit-stage records left out */
    /* How the render's processes shared it (opt.comm); the figures after `ranks` are this process's own
     * (rays, gather_rays and the image are the whole job's). */
    int ranks;             /* processes that rendered (1 without opt.comm) */
    uint64_t rank_records_gathered; /* records whose hemispheres this process gathered */
    uint64_t rank_pixel_samples;    /* pixel samples this process rendered (the film, AOVs excluded) */
    double rank_render_seconds;     /* seconds it spent rendering them (waiting for other ranks excluded) */
    double rank_comm_seconds;       /* seconds this process spent in opt.comm's operations */
    uint64_t rank_comm_bytes;       /* bytes it received through them */
    double rank_comm_seconds_per_pass[IC_STATS_PASSES]; /* batch: of those, each construction pass's (records_per_pass's */
    uint64_t rank_comm_bytes_per_pass[IC_STATS_PASSES]; /* passes; the last also holds the final coverage sweep) */
    int phase_count;
    struct {
        const char *name;  /* "accel", "render", … */
        double seconds;
    } phases[IC_MAX_PHASES];
} ic_render_stats;

/* Renders scene with opt into out (allocated here; on failure nothing is left allocated in it). stats may
 * be NULL; a NULL scene or out is IC_ERR_INVALID_ARG. */
ic_result ic_render(const ic_scene *scene, const ic_render_options *opt, ic_image *out, ic_render_stats *stats,
                    ic_error *err);

/* Camera resolution of a loaded scene (0 x 0 for NULL; either pointer may be NULL). */
void ic_scene_resolution(const ic_scene *scene, int *width, int *height);
/* Exposure (stops) the scene file asks for LDR outputs, 0 if none. */
float ic_scene_exposure(const ic_scene *scene);
/* Light sources of a loaded scene that emit something: emitting triangles, point lights, the sun and the
 * environment (one each). 0 means every image of the scene is black (a caller may warn). */
unsigned ic_scene_light_count(const ic_scene *scene);
/* What loading approximated or left out, one line per kind ("scene.xml:12: ... is not supported; ..."),
 * "" if nothing (a Mitsuba scene's unsupported elements). Owned by the scene. */
const char *ic_scene_warnings(const ic_scene *scene);
/* The files loading read, as real paths (symbolic links resolved), each once: the scene file, then its
 * meshes, material libraries, buffers, textures, environment maps, included and view files. A caller that
 * writes files checks it overwrites none of them. index < ic_scene_file_count (else NULL); owned by the
 * scene. */
uint32_t ic_scene_file_count(const ic_scene *scene);
const char *ic_scene_file(const ic_scene *scene, uint32_t index);

#ifdef __cplusplus
}
#endif
#endif
