/*
 * options.h — every option of the irrcache commands, declared once.
 *
 * IC_RENDER_OPTIONS is an X-macro: one row per option, from which come the parser (--name VALUE,
 * --name=VALUE, the alias, `--` ends the options), the range checks, --help (wrapped within 100
 * columns; a number's range as the checks use it), the README's tables (--help-markdown) and the
 * settings echoed in the --stats JSON. A
 * numeric default is the constant of irrcache/defaults.h that the library itself falls back to, so
 * the help cannot disagree with what is rendered. IC_POINTS_OPTIONS and IC_DIFF_OPTIONS are the
 * options of `irrcache points` and `irrcache diff` that render does not take, in rows of the same
 * form, from which come those commands' parsers, checks, defaults, --help and README tables alike
 * (the options points shares with render are render's rows: ic_cli_parse_shared_option).
 *
 * Row: X(ID, "--name", "alias" or NULL, kind, member of the command's args struct, min, max (a number's
 *        range, which the parser checks and --help shows; 0, 0 for the other kinds), "VALUE" (for a
 *        choice: "a|b|c", in the order of the enum it sets; for a number "E|word": the word is taken for
 *        min, as in --max-error E|auto), numeric default or NAN, "default text" ("%g" takes the numeric
 *        default), "unit", scope, "help")
 */
#ifndef IC_CLI_OPTIONS_H
#define IC_CLI_OPTIONS_H

#include "irrcache/points.h"
#include "irrcache/render.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>

#define IC_CLI_MAX_OUTPUTS 8
#define IC_CLI_HELP_COLUMNS 100

typedef enum ic_opt_kind {
    IC_OPT_INT,        /* int */
    IC_OPT_SEED,       /* uint64_t; also sets render.has_seed (render only) */
    IC_OPT_SIZE,       /* uint64_t, a size or count: a whole number, K, M, G or T after it (either case)
                          multiplying by 2^10 ... 2^40 (ic_cli_parse_size; --help lists those up to max) */
    IC_OPT_SIZE_INT,   /* int, the same */
    IC_OPT_FLOAT,      /* float */
    IC_OPT_DOUBLE,     /* double */
    IC_OPT_FLOAT_ABOVE,  /* float in (min, max]: min itself refused (as stored: 1e-50 is 0 as a float) */
    IC_OPT_DOUBLE_ABOVE, /* double in (min, max] */
    IC_OPT_NUMBERS,    /* double[n]: n numbers in [min, max], one argument each after the option, n the
                          words of VALUE ("X0 Y0 Z0 X1 Y1 Z1") */
    IC_OPT_CHOICE,     /* an enum: the index of the value in "a|b|c" */
    IC_OPT_ON_OFF,     /* ic_cache_switch from on|off */
    IC_OPT_FLAG,       /* int set to 1 */
    IC_OPT_FLAG_OFF,   /* ic_cache_switch set to IC_CACHE_OFF */
    IC_OPT_FLAG_ON,    /* ic_cache_switch set to IC_CACHE_ON */
    IC_OPT_STRING,     /* const char * */
    IC_OPT_OUT_FILE,   /* const char *, a file the command writes (an empty path is refused as one) */
    IC_OPT_OUTPUT,     /* appended to outputs[] (render only) */
    IC_OPT_RAYS,       /* a ray count, stored as M×N strata (ic_gather_opts) */
    IC_OPT_NUMBER_OFF, /* ic_switched_value: a number in (min, max], or off */
    IC_OPT_LIST,       /* comma-separated names of those in VALUE "a,b,c" */
    IC_OPT_HELP        /* prints something and exits 0 */
} ic_opt_kind;

/* Who an option is for: an irradiance-cache option needs --integrator ic. */
typedef enum ic_opt_scope { IC_SCOPE_ALL, IC_SCOPE_IC, IC_SCOPE_BATCH, IC_SCOPE_LAZY, IC_SCOPE_ADAPTIVE } ic_opt_scope;

/* clang-format off */
/* The last rows of every command's table: --help, and --help-markdown, which prints `tables`. */
#define IC_HELP_OPTIONS(X, tables) \
    X(HELP, "--help", "-h", IC_OPT_HELP, none, 0, 0, "", NAN, "", "", IC_SCOPE_ALL, "show this help and exit") \
    X(HELP_MARKDOWN, "--help-markdown", NULL, IC_OPT_HELP, none, 0, 0, "", NAN, "", "", IC_SCOPE_ALL, \
      "print " tables " (Markdown) and exit")

#define IC_RENDER_OPTIONS(X) \
    X(OUTPUT, "--output", "-o", IC_OPT_OUTPUT, outputs, 0, 0, "PATH", NAN, "(required)", "", IC_SCOPE_ALL, \
      "output image; the format follows the extension: .exr (linear float), .png (tone-mapped sRGB), " \
      ".pfm, .hdr; repeatable") \
    X(WIDTH, "--width", NULL, IC_OPT_INT, load.width, 1, 65536, "N", IC_DEFAULT_WIDTH, "scene file, else %g", "px", \
      IC_SCOPE_ALL, "image width") \
    X(HEIGHT, "--height", NULL, IC_OPT_INT, load.height, 1, 65536, "N", IC_DEFAULT_HEIGHT, "scene file, else %g", \
      "px", IC_SCOPE_ALL, "image height") \
    X(SPP, "--spp", NULL, IC_OPT_INT, render.spp, 1, IC_MAX_SPP, "N", NAN, "scene file, else 16 (pt) or 32 (ic)", "", \
      IC_SCOPE_ALL, "samples per pixel (with --time: the most to take)") \
    X(TIME, "--time", NULL, IC_OPT_DOUBLE, render.time_budget, 0, 1e9, "SECONDS", NAN, "none", "s", IC_SCOPE_ALL, \
      "wall-time budget of the whole render (equal-time comparisons), from building the ray-tracing " \
      "structure to the last sample; loading the scene and writing the outputs are outside it. Cache " \
      "construction stops gathering when half of it is spent (batch and adaptive: inside a pass, or with " \
      "several MPI processes at the end of the pass; lazy: after that shading point; a warning and " \
      "cut_by_time in the stats say so); the final render takes progressive passes until the " \
      "rest is spent, at least one sample per pixel. Radiance records and the --aov indirect and glossy " \
      "re-renders come on top. A budget that runs out makes the result depend on the wall clock (the " \
      "machine, its load, the threads and ranks): same seed, same image only while it does not") \
    X(CHECKPOINT, "--checkpoint", NULL, IC_OPT_DOUBLE, render.checkpoint_seconds, 0, 1e9, "SECONDS", NAN, "none", \
      "s", IC_SCOPE_ALL, "every SECONDS of the final render's wall time, write every -o output with the image " \
      "so far (unrendered tiles black; atomically; EXR marked irrcache:partial \"checkpoint\"); the final " \
      "image replaces it and is the same as without. Cache construction has no image yet: the clock starts " \
      "with the final render. AOVs come with the final image only") \
    X(INTEGRATOR, "--integrator", NULL, IC_OPT_CHOICE, render.integrator, 0, 0, "pt|ic", NAN, "pt", "", \
      IC_SCOPE_ALL, "pt: path-traced reference; ic: irradiance caching (indirect diffuse from the cache)") \
    X(MAX_DEPTH, "--max-depth", NULL, IC_OPT_INT, render.max_depth, 1, IC_MAX_MAX_DEPTH, "N", IC_DEFAULT_MAX_DEPTH, \
      "scene file, else %g", "", IC_SCOPE_ALL, "maximum number of scattering events (direct light is 1)") \
    X(THREADS, "--threads", NULL, IC_OPT_INT, render.threads, 0, IC_MAX_THREADS, "N", NAN, "0 (all cores)", "", IC_SCOPE_ALL, \
      "worker threads; no result depends on it: same seed, same image or values") \
    X(SEED, "--seed", NULL, IC_OPT_SEED, render.seed, 0, 18446744073709551615.0, "N", IC_DEFAULT_SEED, \
      "scene file, else %g", "", IC_SCOPE_ALL, "random seed") \
    X(SAMPLER, "--sampler", NULL, IC_OPT_CHOICE, render.sampler, 0, 0, "sobol|random", NAN, "sobol", "", \
      IC_SCOPE_ALL, "where each pixel's sample pairs (position, light, BSDF) come from: Owen-scrambled Sobol' " \
      "points per pixel (less noise at equal samples) or independent random numbers") \
    X(ADAPTIVE_SAMPLING, "--adaptive-sampling", NULL, IC_OPT_ON_OFF, render.adaptive_sampling, 0, 0, "on|off", NAN, \
      "off (pt), on (ic with --spp >= 8 and no --time)", "", IC_SCOPE_ALL, \
      "on: --spp becomes a mean; a pilot pass of spp/4 samples in every pixel, then the rest shared out by " \
      "each pixel's relative noise (needs --spp >= 8 and no --time)") \
    X(EXPOSURE, "--exposure", NULL, IC_OPT_DOUBLE, exposure, -100, 100, "STOPS", NAN, "scene file, else 0", "stops", \
      IC_SCOPE_ALL, "exposure applied to .png outputs (not to --aov records and amap, whose colours are codes)") \
    X(HALF, "--half", NULL, IC_OPT_FLAG, exr_half, 0, 0, "", NAN, "off", "", IC_SCOPE_ALL, \
      "write .exr outputs (and EXR AOVs) as 16-bit half floats: half the size, about 3 significant digits, " \
      "values up to 65504 (larger ones are clamped to it; Inf and NaN kept)") \
    X(STATS, "--stats", NULL, IC_OPT_STRING, stats_path, 0, 0, "FILE.json", NAN, "none", "", IC_SCOPE_ALL, \
      "write run statistics: the settings, seconds, rays, rays per second, spp, per-phase times and, for " \
      "ic, records, passes and the records' extents a*R (record_extent: min, mean, max); the keys: docs/outputs.md") \
    X(SCENES_DIR, "--scenes-dir", NULL, IC_OPT_STRING, load.shared_scenes_dir, 0, 0, "DIR", NAN, \
      "$IRRCACHE_SCENES, else ../shared/scenes", "", IC_SCOPE_ALL, "where 'shared:' mesh paths of scene files " \
      "resolve") \
    X(CAMERA, "--camera", NULL, IC_OPT_STRING, load.camera, 0, 0, "NAME", NAN, "the file's first", "", \
      IC_SCOPE_ALL, "a glTF scene's camera to render from, by its node's or its own name (glTF files only)") \
    X(VIEW, "--view", NULL, IC_OPT_STRING, load.view, 0, 0, "FILE.vf", NAN, "a fitted camera", "", IC_SCOPE_ALL, \
      "a Radiance view file to render a .rad scene from (rview/rpict options -vt -vp -vd -vu -vh -vv -vs -vl -vo)") \
    X(MAX_TEXTURE_PIXELS, "--max-texture-pixels", NULL, IC_OPT_SIZE_INT, load.max_texture_pixels, 1, 1 << 28, "N", \
      IC_DEFAULT_MAX_TEXTURE_PIXELS, "67108864 (8192 x 8192)", "px", IC_SCOPE_ALL, "largest texture or " \
      "environment map accepted, checked from the file's header before it is read") \
    X(MAX_MESH_ELEMENTS, "--max-mesh-elements", NULL, IC_OPT_SIZE_INT, load.max_mesh_elements, 1, 1 << 30, "N", \
      IC_DEFAULT_MAX_MESH_ELEMENTS, "16777216", "", IC_SCOPE_ALL, "largest vertex or face count of one mesh " \
      "file, checked from a PLY header or counted in an OBJ file before it is imported, and on the meshes imported (for a .rad scene: the " \
      "vertices of all its surfaces)") \
    X(MAX_SCENE_BYTES, "--max-scene-bytes", NULL, IC_OPT_SIZE, load.max_scene_bytes, 1, 1099511627776.0, "N", \
      IC_DEFAULT_MAX_SCENE_FILE_BYTES, "67108864 (64M)", "bytes", IC_SCOPE_ALL, "largest scene file (JSON, Mitsuba, " \
      "Radiance) read, checked before it is read (mesh files have --max-mesh-elements)") \
    X(MAX_IMAGE_PIXELS, "--max-image-pixels", NULL, IC_OPT_SIZE, render.max_image_pixels, 1, \
      (double)IC_IMAGE_MAX_PIXELS, "N", (double)IC_DEFAULT_MAX_IMAGE_PIXELS, "134217728 (16384 x 8192)", "px", \
      IC_SCOPE_ALL, "largest image rendered (width x height), checked before anything is allocated for it; about " \
      "80 bytes a pixel; at most 268435456 (16384 x 16384), the largest image the library holds") \
    X(ALLOW_OUTSIDE_PATHS, "--allow-outside-paths", NULL, IC_OPT_FLAG, load.allow_outside_paths, 0, 0, "", NAN, \
      "off", "", IC_SCOPE_ALL, "let a scene read files outside its own folder tree and the shared scenes folder " \
      "(meshes, MTL files, glTF buffers, textures, environment maps; symbolic links resolved)") \
    X(QUIET, "--quiet", "-q", IC_OPT_FLAG, quiet, 0, 0, "", NAN, "off", "", IC_SCOPE_ALL, \
      "no progress line and no summary (the progress line is shown only when stderr is a terminal)") \
    X(STRATEGY, "--strategy", NULL, IC_OPT_CHOICE, render.ic.strategy, 0, 0, "batch|lazy|adaptive", NAN, "batch", \
      "", IC_SCOPE_IC, "cache construction: batch (Frolov et al. 2012, multi-pass, gathered in parallel), " \
      "lazy (Ward et al. 1988, serial) or adaptive (Krivanek et al. 2006: each record's a refined until no " \
      "discontinuity is visible; docs/adaptive.md)") \
    X(ACCURACY, "--accuracy", "-a", IC_OPT_FLOAT, render.ic.cache.accuracy, 0.001, 100, "A", NAN, \
      "0.15 (ward, error), 1 (tl)", "", IC_SCOPE_IC, "error bound a of the weights; smaller means more records") \
    X(WEIGHT, "--weight", NULL, IC_OPT_CHOICE, render.ic.cache.weight, 0, 0, "ward|tl|error", NAN, "ward", "", \
      IC_SCOPE_IC, "interpolation weights: Ward's, Tabellion-Lamorlette's, or error: one minus the second-order error's " \
      "share of its value at the record's edge, 1 - delta^2, zero at the edge (after Schwarzhaupt et al. 2012; " \
      "for --error hessian)") \
    X(RAYS, "--rays", NULL, IC_OPT_RAYS, render.ic.gather, 16, IC_MAX_RECORD_RAYS, "N", IC_DEFAULT_RAYS, "%g", "", IC_SCOPE_IC, \
      "hemisphere rays per record (stratified M x N, N about pi M)") \
    X(GATHER, "--gather", NULL, IC_OPT_CHOICE, render.ic.gather.method, 0, 0, "stratified|progressive|hemicube", \
      NAN, "stratified", "", IC_SCOPE_IC, "hemisphere sampler; progressive: Hammersley rounds of 4096 to 65536 " \
      "rays until converged; hemicube: one ray per texel of a five-face hemicube with --rays texels (3N^2, " \
      "N even, at most 512: 786,432 rays) and exact per-texel weights (Castano 2014)") \
    X(ERROR, "--error", NULL, IC_OPT_CHOICE, render.ic.error, 0, 0, "split-sphere|hessian", NAN, "split-sphere", \
      "", IC_SCOPE_IC, "what sets a record's extent: Ward's split sphere (harmonic mean of the hit distances), or " \
      "the irradiance Hessian (Schwarzhaupt et al. 2012): records as dense as the square root of its relative " \
      "curvature, semi-axes a*sqrt(L*l), l = sqrt(2E/|eigenvalue|), L = 1/8 of the scene's diagonal (at most 2.5 " \
      "x the view's extent), a = " \
      "--accuracy (0.15 x --accuracy with --weight tl) (stratified or hemicube gather)") \
    X(RECORD_SHAPE, "--record-shape", NULL, IC_OPT_CHOICE, render.ic.record_shape, 0, 0, "round|elliptical", NAN, \
      "round", "", IC_SCOPE_IC, "with --error hessian: round records (the smaller semi-axis everywhere) or " \
      "ellipses along the Hessian's eigenvectors, aspect at most 4") \
    X(RADIANCE_CACHE, "--radiance-cache", NULL, IC_OPT_ON_OFF, render.ic.radiance_cache, 0, 0, "on|off", NAN, \
      "off", "", IC_SCOPE_IC, "radiance caching (Krivanek et al. 2005): records of incoming radiance in " \
      "hemispherical harmonics serve the glossy lobe of first shading points whose Phong exponent is at most " \
      "--radiance-max-exponent; sharper lobes and vertices behind specular ones are path traced " \
      "(docs/radiance-caching.md)") \
    X(HSH_ORDER, "--hsh-order", NULL, IC_OPT_INT, render.ic.hsh_order, 1, 16, "N", IC_DEFAULT_HSH_ORDER, "%g", "", \
      IC_SCOPE_IC, "order of a radiance record's hemispherical harmonics (N^2 coefficients per colour)") \
    X(RADIANCE_MAX_EXPONENT, "--radiance-max-exponent", NULL, IC_OPT_FLOAT, render.ic.radiance_max_exponent, 0.001, \
      1e6, "E", IC_DEFAULT_RADIANCE_MAX_EXPONENT, "%g", "", IC_SCOPE_IC, "sharpest Phong lobe radiance records " \
      "serve (the order's limit: docs/radiance-caching.md)") \
    X(RADIANCE_RAYS, "--radiance-rays", NULL, IC_OPT_INT, render.ic.radiance_rays, 16, IC_MAX_RECORD_RAYS, "N", \
      NAN, "4 x --rays, at most 1e7", "", IC_SCOPE_IC, "hemisphere rays per radiance record") \
    X(BOUNCES, "--bounces", NULL, IC_OPT_INT, render.ic.bounces, 1, 1000, "N", NAN, "max-depth - 1", "", \
      IC_SCOPE_IC, "bounces in the light a record gathers") \
    X(RECURSIVE, "--recursive", NULL, IC_OPT_FLAG, render.ic.recursive, 0, 0, "", NAN, "off", "", IC_SCOPE_LAZY, \
      "one cache level per bounce, as Radiance's -ab (then --bounces is the number of levels)") \
    X(LIGHT_SAMPLES, "--light-samples", NULL, IC_OPT_INT, render.ic.light_samples, 1, IC_MAX_LIGHT_SAMPLES, "N", \
      IC_DEFAULT_LIGHT_SAMPLES, "%g", "", IC_SCOPE_IC, "light samples per shading point in the final render") \
    X(LARGE_EMITTERS, "--large-emitters", NULL, IC_OPT_NUMBER_OFF, render.ic.large_emitters, 0, 1, "F|off", \
      IC_DEFAULT_LARGE_EMITTERS, "%g", "", IC_SCOPE_IC, "an emitting material that covers at least F of the " \
      "cosine-weighted hemisphere at the image's median shading point, and whose light samples a pilot " \
      "measures to leave more error than the records' hemisphere rays, once its noise is averaged over the " \
      "~50 pixels the eye sees together (a large source mostly hidden behind an opening), " \
      "lights the scene through the records instead of being light-sampled; off: sample every emitter (about " \
      "twice the per-pixel noise where a cached window lit the scene, and fewer soft stains on some scenes: " \
      "BENCHMARKS.md). The summary line and the stats (cached_emitters) say when it happens") \
    X(RECORD_FILTER, "--record-filter", NULL, IC_OPT_NUMBER_OFF, render.ic.record_filter, 0, 16, "S|off", \
      IC_DEFAULT_RECORD_FILTER, "%g", "", IC_SCOPE_IC, "record noise control: after construction each record's " \
      "value moves towards the kernel mean of its neighbours' within S times its influence radius, as far " \
      "as their noise explains their spread (docs/architecture.md); off: the records as gathered") \
    X(RECORD_SETS, "--record-sets", NULL, IC_OPT_INT, render.ic.record_sets, 1, 64, "N", IC_DEFAULT_RECORD_SETS, \
      "%g", "", IC_SCOPE_IC, "record noise control: a record whose relative noise is above --record-noise " \
      "gathers up to N independent hemisphere sets and keeps their mean") \
    X(RECORD_NOISE, "--record-noise", NULL, IC_OPT_FLOAT, render.ic.record_noise, 0.001, 1, "F", \
      IC_DEFAULT_RECORD_NOISE, "%g", "", IC_SCOPE_IC, "the relative noise (sigma / E) --record-sets aims at") \
    X(MIN_RADIUS_PX, "--min-radius-px", NULL, IC_OPT_FLOAT, render.ic.min_radius_px, 0, 1e6, "P", \
      IC_DEFAULT_MIN_RADIUS_PX, "%g", "px", IC_SCOPE_IC, "smallest influence radius a*R of a record, in pixels " \
      "at its primary hit; 0: no floor") \
    X(MAX_RADIUS_PX, "--max-radius-px", NULL, IC_OPT_FLOAT, render.ic.max_radius_px, 0.001, 1e6, "P", \
      IC_DEFAULT_MAX_RADIUS_PX, "%g", "px", IC_SCOPE_IC, "largest influence radius a*R of a record, in pixels " \
      "at its primary hit") \
    X(MIN_RADIUS, "--min-radius", NULL, IC_OPT_FLOAT, render.ic.cache.min_radius, 0, 1e30, "R", 0, "%g", \
      "world units", IC_SCOPE_IC, "smallest record radius R") \
    X(MAX_RADIUS, "--max-radius", NULL, IC_OPT_FLOAT, render.ic.cache.max_radius, 1e-30, 1e30, "R", NAN, \
      "scene diagonal / 8", "world units", IC_SCOPE_IC, "largest record radius R") \
    X(FINAL_ACCURACY_SCALE, "--final-accuracy-scale", NULL, IC_OPT_FLOAT, render.ic.cache.final_accuracy_scale, 1, \
      100, "S", IC_DEFAULT_FINAL_ACCURACY_SCALE, "%g", "", IC_SCOPE_IC, "the final render accepts records up " \
      "to S times the construction error bound") \
    X(NO_GRADIENTS, "--no-gradients", NULL, IC_OPT_FLAG, render.ic.no_gradients, 0, 0, "", NAN, "off", "", \
      IC_SCOPE_IC, "interpolate without gradients (a weighted average)") \
    X(PATH_TRACED_GATHER, "--path-traced-gather", NULL, IC_OPT_FLAG, render.ic.path_traced_gather, 0, 0, "", NAN, \
      "off", "", IC_SCOPE_IC, "hemisphere rays path-trace every bounce after their hit; by default, where " \
      "records of earlier passes cover a diffuse hit, they give its indirect light and only its direct light " \
      "is sampled (Ward's multiple-bounce scheme)") \
    X(NO_GRADIENT_CLAMP, "--no-gradient-clamp", NULL, IC_OPT_FLAG_OFF, render.ic.cache.gradient_clamp, 0, 0, "", \
      NAN, "off", "", IC_SCOPE_IC, "switch off gradient-magnitude clamping of R (Krivanek et al. 2006 §5.1)") \
    X(NO_NEIGHBOR_CLAMP, "--no-neighbor-clamp", NULL, IC_OPT_FLAG_OFF, render.ic.cache.neighbor_clamp, 0, 0, "", \
      NAN, "off", "", IC_SCOPE_IC, "switch off neighbour clamping (Krivanek et al. 2006 §5.2)") \
    X(NO_VALIDITY_CLAMP, "--no-validity-clamp", NULL, IC_OPT_FLAG_OFF, render.ic.cache.validity_clamp, 0, 0, "", \
      NAN, "off", "", IC_SCOPE_IC, "switch off validity-radius clamping (Frolov et al. 2012 §4.2)") \
    X(GRADIENT_DIFFERENCE, "--gradient-difference", NULL, IC_OPT_FLAG_ON, render.ic.cache.gradient_difference, 0, 0, \
      "", NAN, "off", "", IC_SCOPE_IC, "gradient-difference record scaling (Castano 2014)") \
    X(HIT_RECORDS, "--hit-records", NULL, IC_OPT_ON_OFF, render.ic.hit_records, 0, 0, "on|off", NAN, "on", "", \
      IC_SCOPE_BATCH, "before the first pass, records where probe rays from the shading points land (1/4 of " \
      "the rays each), read only by the hemisphere rays of the image's records, which then path-trace fewer " \
      "bounces (no effect with --path-traced-gather or --bounces 1)") \
    X(MAX_PASSES, "--max-passes", NULL, IC_OPT_INT, render.ic.max_passes, 1, IC_MAX_MAX_PASSES, "N", IC_DEFAULT_MAX_PASSES, "%g", \
      "", IC_SCOPE_BATCH, "most construction passes after pass 0 (the geometry's candidates): a safety bound (a " \
      "warning says when it stops construction); the stats' passes count pass 0 too, at most N + 1") \
    X(MIN_CANDIDATES, "--min-candidates", NULL, IC_OPT_INT, render.ic.min_candidates, 1, 1e9, "N", \
      IC_DEFAULT_MIN_CANDIDATES, "%g", "", IC_SCOPE_BATCH, "construction stops when a pass finds fewer new " \
      "candidates") \
    X(UNCOVERED, "--uncovered", NULL, IC_OPT_FLOAT, render.ic.uncovered, 0.000001, 1, "F", IC_DEFAULT_UNCOVERED, \
      "%g", "", IC_SCOPE_BATCH, "construction has converged when fewer than F of a pass's eye-path look-up " \
      "points (where the final render reads the cache) find no record; the stats report the last pass's share") \
    X(PASS_GROWTH, "--pass-growth", NULL, IC_OPT_NUMBER_OFF, render.ic.pass_growth, 0, 1, "F|off", \
      IC_DEFAULT_PASS_GROWTH, "%g", "", IC_SCOPE_BATCH, "construction has also converged when a pass after the " \
      "screen stage adds fewer than F times the image's records already made: later passes cover ever fewer look-ups " \
      "(they fall back to a path-traced bounce) for the same rays; off: --uncovered alone decides") \
    X(WEBER, "--weber", NULL, IC_OPT_FLOAT, render.ic.weber, 0.0001, 1, "F", IC_DEFAULT_WEBER, "%g", "", \
      IC_SCOPE_ADAPTIVE, "Weber fraction of the discontinuity test; smaller means more records") \
    X(ADAPTIVE_GROWTH, "--adaptive-growth", NULL, IC_OPT_FLOAT, render.ic.adaptive_growth, 1, 100, "F", \
      IC_DEFAULT_ADAPTIVE_GROWTH, "%g", "", IC_SCOPE_ADAPTIVE, "a new record starts from the nearest " \
      "record's a times F (at most --accuracy)") \
    X(SAVE_CACHE, "--save-cache", NULL, IC_OPT_STRING, render.ic.save_cache, 0, 0, "FILE", NAN, "none", "", \
      IC_SCOPE_IC, "keep the records in a versioned, checksummed cache file (docs/outputs.md)") \
    X(LOAD_CACHE, "--load-cache", NULL, IC_OPT_STRING, render.ic.load_cache, 0, 0, "FILE", NAN, "none", "", \
      IC_SCOPE_IC, "render from the records in FILE instead of building them; refused if made for another " \
      "scene or with other settings that shape the records: --strategy, --gather, --rays, --bounces (--max-depth), " \
      "--recursive, --path-traced-gather, --error, --record-shape, --no-gradients, --record-filter, --record-sets, " \
      "--record-noise, --large-emitters, --radiance-cache and its options, --weight, --accuracy, the radius bounds, " \
      "the clamps and --gradient-difference (another --seed, --spp, --threads, view or --final-accuracy-scale is " \
      "fine; docs/outputs.md)") \
    X(MAX_CACHE_BYTES, "--max-cache-bytes", NULL, IC_OPT_SIZE, render.ic.cache.max_file_bytes, 1, \
      1099511627776.0, "N", IC_DEFAULT_MAX_CACHE_FILE_BYTES, "4294967296 (4G)", "bytes", IC_SCOPE_IC, \
      "largest --load-cache file read, checked before it is read") \
    X(RECORDS_JSON, "--records-json", NULL, IC_OPT_STRING, records_json, 0, 0, "FILE", NAN, "none", "", \
      IC_SCOPE_IC, "write the image's records (not the hit stage's) as a JSON list: position, R, a, visibility " \
      "and, for a record in front of the camera, its image position and a*R in pixels (docs/outputs.md)") \
    X(AOV, "--aov", NULL, IC_OPT_LIST, aov, 0, 0, "indirect,glossy,records,density,amap", NAN, "none", "", \
      IC_SCOPE_IC, "extra images next to the first output: <stem>.indirect.exr, <stem>.glossy.exr (the glossy " \
      "lobe's indirect light from radiance records), <stem>.density.exr (records per pixel) - when the first " \
      "output is an .exr, these three are its layers instead (channels indirect.R ...) -, <stem>.records.png " \
      "(dots and radii over the image scaled so that the median luminance of its lit pixels is 0.18, mid-grey, " \
      "however dim or bright the scene; radiance records yellow in blue rings), <stem>.amap.png (a of " \
      "the heaviest record, blue = --accuracy to red = accuracy/32); these two without --exposure") \
    IC_HELP_OPTIONS(X, "the option tables of README.md")
/* clang-format on */

#define IC_OPT_ID(id, ...) IC_ARG_##id,
typedef enum ic_arg_id { IC_RENDER_OPTIONS(IC_OPT_ID) IC_ARG_COUNT } ic_arg_id;
#undef IC_OPT_ID

/* What the command line says: the library's options, the scene's load options, and the CLI's own. */
typedef struct ic_cli_args {
    const char *scene;
    const char *outputs[IC_CLI_MAX_OUTPUTS];
    int output_count;
    const char *stats_path, *records_json, *aov;
    double exposure;
    int exr_half;
    int quiet;
    int none;                          /* target of options that set nothing */
    ic_scene_load_options load;
    ic_render_options render;
    const char *given[IC_ARG_COUNT];   /* the value as written ("" for a flag), NULL if not given */
} ic_cli_args;

/* Parses argv (argv[0] is the command's name) into a. Returns 0, 2 on a usage error (one line on
 * stderr), or −1 − ID of a help option that was given (the caller prints it and exits 0). */
int ic_cli_parse(int argc, char **argv, ic_cli_args *a);
/* For other commands that take some of render's options (the same names, values and meaning): parses
 * argv[*i] into a if it is one of ids; *i moves past its value. Returns 1 if it was one, 0 if not, -1
 * after a one-line message "irrcache COMMAND: ...". */
int ic_cli_parse_shared_option(int argc, char **argv, int *i, ic_cli_args *a, const char *command,
                               const ic_arg_id *ids, size_t count);
/* The options that limit or confine what a scene reads, which every command that loads a scene takes. */
#define IC_CLI_LOAD_OPTION_IDS                                                                                      \
    IC_ARG_MAX_TEXTURE_PIXELS, IC_ARG_MAX_MESH_ELEMENTS, IC_ARG_MAX_SCENE_BYTES, IC_ARG_ALLOW_OUTSIDE_PATHS
/* One option's line of --help, as render's: its name from column 2, its help (wrapped) from left_width. */
void ic_cli_print_option(FILE *f, ic_arg_id id, int left_width);
/* The same row with another default (a command that takes the option with a default of its own). */
void ic_cli_print_option_default(FILE *f, ic_arg_id id, double value, int left_width);
/* --help and --help-markdown. */
void ic_cli_print_help(FILE *f);
void ic_cli_print_markdown(FILE *f);
/* A size or count as the limits take it (IC_OPT_SIZE): a whole number, optionally followed by K, M, G or T
 * in either case, which multiply by 2^10, 2^20, 2^30, 2^40 ("64k" = "64K" = 65536). 1 and *out, or 0 if
 * it is not one or exceeds 2^64 - 1. */
int ic_cli_parse_size(const char *text, uint64_t *out);
/* The suffixes a size up to max may end in, for help and messages: "K, M or G (either case): times 2^10,
 * 2^20 or 2^30" (those whose multiplier is at most max; ic_cli_parse_size takes all four). */
void ic_cli_size_suffixes(double max, char *buf, size_t size);
/* The settings of a run for the --stats JSON: every option but the outputs and the help, with its
 * value as given or else its default (a number, a name, true/false for a switch, null for none; a
 * default that depends on the scene is given as its text). */
struct cJSON *ic_cli_settings_json(const ic_cli_args *a);
/* The name a choice option was given (or its default, the first), for messages and the stats. */
const char *ic_cli_choice(const ic_cli_args *a, ic_arg_id id);

/* The longest line of a points file (points.c reads no further: /dev/zero ends there). */
#define IC_CLI_MAX_POINT_LINE 4096
#define IC_CLI_STR_(x) #x
#define IC_CLI_STR(x) IC_CLI_STR_(x)

/* clang-format off */
/* `irrcache points`: its own options (members of ic_points_args). */
#define IC_POINTS_OPTIONS(X) \
    X(POINTS, "--points", NULL, IC_OPT_STRING, points, 0, 0, "FILE", NAN, "none", "", IC_SCOPE_ALL, \
      "the points, one 'x y z nx ny nz' a line ('-': standard input); required unless --grid") \
    X(OUTPUT, "--output", "-o", IC_OPT_OUT_FILE, output, 0, 0, "FILE", NAN, "standard output", "", IC_SCOPE_ALL, \
      "write the results there, atomically ('-': standard output)") \
    X(FORMAT, "--format", NULL, IC_OPT_CHOICE, format, 0, 0, "text|csv|json|rtrace", NAN, "text", "", IC_SCOPE_ALL, \
      "text (space-separated), csv (with a header line), json, or rtrace: the irradiance alone, 'E_r E_g E_b' " \
      "a line, each %e and a tab, as Radiance's rtrace -I -h- prints it, for the scripts that read its output") \
    X(GRID, "--grid", NULL, IC_OPT_NUMBERS, grid, -1e18, 1e18, "X0 Y0 Z0 X1 Y1 Z1", NAN, "none", "", IC_SCOPE_ALL, \
      "instead of --points: a work-plane grid over the floor x0..x1, z0..z1 of that box (the room's floor " \
      "corner and the opposite top corner, +y up), one upward sensor at the centre of each whole cell, " \
      "centred; each output row then starts with its point 'x y z nx ny nz'; the range is each number's") \
    X(SPACING, "--spacing", NULL, IC_OPT_DOUBLE_ABOVE, spacing, 0, 1e18, "S", NAN, "(required with --grid)", "", \
      IC_SCOPE_ALL, "the grid's cell size") \
    X(HEIGHT, "--height", NULL, IC_OPT_DOUBLE, height, 0, 1e18, "H", IC_DEFAULT_GRID_HEIGHT, "%g", "", \
      IC_SCOPE_ALL, "the grid's height above y0") \
    X(MAP, "--map", NULL, IC_OPT_OUT_FILE, map, 0, 0, "FILE.png", NAN, "none", "", IC_SCOPE_ALL, \
      "with --grid: a false-colour map of the grid (lux, or the daylight factor), seen from above with +x " \
      "to the right and -z up, and a legend") \
    X(MAP_MAX, "--map-max", NULL, IC_OPT_DOUBLE_ABOVE, map_max, 0, 1e18, "V", NAN, "the largest value", "", \
      IC_SCOPE_ALL, "the top of the map's scale") \
    X(DAYLIGHT_FACTOR, "--daylight-factor", NULL, IC_OPT_FLAG, daylight_factor, 0, 0, "", NAN, "off", "", \
      IC_SCOPE_ALL, "two more columns: the daylight factor (%), 100 x lux / (the unobstructed horizontal " \
      "illuminance of the scene's sky, 179 x 7 pi/9 x L_z), and its sigma; the scene must be lit by a " \
      "cie-overcast sky alone (or, in a Radiance scene, gensky -c's)") \
    X(INTEGRATOR, "--integrator", NULL, IC_OPT_CHOICE, integrator, 0, 0, "pt|ic", NAN, "ic", "", IC_SCOPE_ALL, \
      "ic: irradiance cache, records gathered at the sensors and shared by neighbours, direct light sampled " \
      "at every point; pt: path-traced reference") \
    X(SAMPLES, "--samples", NULL, IC_OPT_INT, samples, 1, IC_MAX_POINT_SAMPLES, "N", IC_DEFAULT_POINT_SAMPLES, \
      "%g", "", IC_SCOPE_ALL, "pt: paths per point, rounded up to a multiple of " IC_CLI_STR(IC_POINT_REPLICATES)) \
    X(LIGHT_SAMPLES, "--light-samples", NULL, IC_OPT_INT, light_samples, 1, IC_MAX_POINT_SAMPLES, "N", \
      IC_DEFAULT_POINT_LIGHT_SAMPLES, "%g", "", IC_SCOPE_ALL, "ic: samples per point for the direct light " \
      "(emitters and sky), rounded up to a multiple of " IC_CLI_STR(IC_POINT_REPLICATES)) \
    X(MAX_POINTS, "--max-points", NULL, IC_OPT_SIZE, max_points, 1, 4294967295.0, "N", 16777216, "%.0f", "", \
      IC_SCOPE_ALL, "most points read from --points; a line is at most " IC_CLI_STR(IC_CLI_MAX_POINT_LINE) \
      " bytes") \
    IC_HELP_OPTIONS(X, "the option table of README.md's section on points")

/* `irrcache diff`: its options (members of ic_diff_args). */
#define IC_DIFF_OPTIONS(X) \
    X(JSON, "--json", NULL, IC_OPT_FLAG, json, 0, 0, "", NAN, "a table", "", IC_SCOPE_ALL, \
      "print one JSON object: width, height, rmse, relmse, relmse_lowpass, psnr_hdr, psnr_ldr, ssim, " \
      "nonfinite; with --heatmap also heatmap, heatmap_max_error (the scale used) and heatmap_scale " \
      "(\"fixed\" or \"p99\"); with --blotch-map also blotch_map and blotch_max_error (the table prints the " \
      "scale on its heat-map line)") \
    X(HEATMAP, "--heatmap", NULL, IC_OPT_OUT_FILE, heatmap, 0, 0, "FILE", NAN, "none", "", IC_SCOPE_ALL, \
      "write a false-colour map of the per-pixel relative luma error |a-b|/(|b|+0.01): blue = 0 ... red = " \
      "--max-error and above (.png, .exr, .pfm or .hdr; magenta = NaN/Inf)") \
    X(MAX_ERROR, "--max-error", NULL, IC_OPT_FLOAT, max_error, 0, 3e38, "E|auto", IC_DEFAULT_HEATMAP_MAX_ERROR, "%g", \
      "", IC_SCOPE_ALL, "relative error shown as full red in the heat map: a fixed scale, so the heat maps of " \
      "two images against one reference compare (a pixel with the same error has the same colour); auto " \
      "(or 0): the 99th percentile of this image's errors, which does not compare") \
    X(BLOTCH_MAP, "--blotch-map", NULL, IC_OPT_OUT_FILE, blotch_map, 0, 0, "FILE", NAN, "none", "", IC_SCOPE_ALL, \
      "write a map of the low-pass error that relMSE lp measures, signed: both images blurred (sigma = 2 " \
      "pixels), then (a-b)/(|b|+0.01) of their luma, red where A is brighter, blue where darker, black where " \
      "they agree; pixel noise is blurred away, blotches and bias stay (.png, .exr, .pfm or .hdr)") \
    X(BLOTCH_MAX_ERROR, "--blotch-max-error", NULL, IC_OPT_FLOAT_ABOVE, blotch_max_error, 0, 3e38, "E", \
      IC_DEFAULT_BLOTCH_MAX_ERROR, "%g", "", IC_SCOPE_ALL, "the blotch map's full colour, a fixed scale") \
    IC_HELP_OPTIONS(X, "the option table of README.md's section on diff")
/* clang-format on */

#define IC_OPT_ID(id, ...) IC_POINTS_ARG_##id,
typedef enum ic_points_arg_id { IC_POINTS_OPTIONS(IC_OPT_ID) IC_POINTS_ARG_COUNT } ic_points_arg_id;
#undef IC_OPT_ID
#define IC_OPT_ID(id, ...) IC_DIFF_ARG_##id,
typedef enum ic_diff_arg_id { IC_DIFF_OPTIONS(IC_OPT_ID) IC_DIFF_ARG_COUNT } ic_diff_arg_id;
#undef IC_OPT_ID

/* What points' own options say (ic_cli_command_defaults: each declared default). */
typedef struct ic_points_args {
    const char *points, *output, *map;
    int format;            /* 0 text, 1 csv, 2 json */
    int integrator;        /* ic_integrator */
    int samples, light_samples, daylight_factor;
    uint64_t max_points;
    double grid[6];        /* x0 y0 z0 x1 y1 z1 */
    double spacing, height, map_max;
    int none;
    const char *given[IC_POINTS_ARG_COUNT]; /* the value as written (--grid: its first), NULL if not given */
} ic_points_args;

typedef struct ic_diff_args {
    const char *heatmap, *blotch_map;
    int json;
    float max_error;       /* 0: --max-error auto */
    float blotch_max_error;
    int none;
    const char *given[IC_DIFF_ARG_COUNT];
} ic_diff_args;

/* The commands with an option table: their args are ic_cli_args, ic_points_args, ic_diff_args. */
typedef enum ic_cli_command { IC_CLI_RENDER, IC_CLI_POINTS, IC_CLI_DIFF } ic_cli_command;

/* Clears args and sets each option's declared default (a number; a choice's default text). For the
 * tables of points and diff: render's defaults come from the scene and the library. */
void ic_cli_command_defaults(ic_cli_command cmd, void *args);
/* Parses argv[*i], an option of cmd's own table, into args; *i moves past its value(s). Returns 0, 2
 * after a one-line usage error "irrcache COMMAND: ..." (an unknown option too), or −1 − ID of a help
 * option. */
int ic_cli_parse_command_option(ic_cli_command cmd, int argc, char **argv, int *i, void *args);
/* Every row of cmd's table as --help gives it (ic_cli_print_option's layout). */
void ic_cli_print_command_options(FILE *f, ic_cli_command cmd, int left_width);
/* cmd's table (its help options left out) as README.md has it: | option | range | default | meaning |. */
void ic_cli_print_command_markdown(FILE *f, ic_cli_command cmd);
/* Render's option id as the README's tables write it: "`--rays N`". */
void ic_cli_option_markdown(ic_arg_id id, char *buf, size_t size);

#endif
