/*
 * irrcache/defaults.h — the one place every default of the renderer and the cache library is written.
 * The cache library (cache.h, gather.h) fills its zero fields from here, the renderer (render.h) does
 * the same, and the command line's option table prints them in --help and the README, so a default
 * can only change here.
 */
#ifndef IRRCACHE_DEFAULTS_H
#define IRRCACHE_DEFAULTS_H

/* Image and sampling (render.h). */
#define IC_DEFAULT_WIDTH 512             /* pixels, when neither the scene file nor an option gives it */
#define IC_DEFAULT_HEIGHT 512
#define IC_DEFAULT_SPP_PT 16             /* samples per pixel, path tracer */
#define IC_DEFAULT_SPP_IC 32             /* samples per pixel, cache render (its samples are cheap; beyond 32 the
                                            records' error dominates: chosen at equal rays, BENCHMARKS.md) */
#define IC_DEFAULT_MAX_DEPTH 8           /* scattering events */
#define IC_DEFAULT_SEED 1
#define IC_ADAPTIVE_SAMPLING_MIN_SPP 8   /* adaptive sampling needs a pilot pass of spp/4 ≥ 2 */

/* Largest values accepted from a scene file's "render" section, the command line and ic_render_options
 * alike (render.h): a cap keeps sample counts and their products far from integer overflow. */
#define IC_MAX_SPP (1 << 24)             /* samples per pixel */
#define IC_MAX_LIGHT_SAMPLES (1 << 16)   /* light samples per shading point (cache render) */
#define IC_MAX_MAX_DEPTH 1024            /* scattering events */
#define IC_MAX_THREADS 4096              /* worker threads (ic_render_options, ic_points_options, ic_cache_params):
                                            per-thread buffers are sized by it, and no result depends on it */
/* The largest image rendered unless ic_render_options.max_image_pixels (--max-image-pixels) says more:
 * 16384 x 8192. The film takes about 32 bytes a pixel, a cache render about 80 (its screen maps and
 * passes; measured on the Cornell box at 2048 x 2048: 165 and 372 MB), so about 11 GB at the limit. */
#define IC_DEFAULT_MAX_IMAGE_PIXELS (1ull << 27)

/* Resource limits of scene loading (render.h's ic_scene_load_options): checked from the files' headers
 * before anything is allocated for them. */
#define IC_DEFAULT_MAX_TEXTURE_PIXELS (1 << 26) /* a texture or environment map: 8192 x 8192 */
#define IC_DEFAULT_MAX_MESH_ELEMENTS (1 << 24)  /* the vertices, or the faces, one mesh file declares (about
                                                   11 GiB to import at the limit: README) */
/* Input files' sizes, checked with fstat before they are read (ic_scene_load_options, ic_cache_params). */
#define IC_DEFAULT_MAX_SCENE_FILE_BYTES (64ull << 20) /* a JSON scene file: 64 MiB (geometry is in mesh files) */
#define IC_DEFAULT_MAX_CACHE_FILE_BYTES (4ull << 30)  /* a cache file: 4 GiB, 27 million records (a 512x512
                                                         Cornell box makes 5,500) */

/* Error heat maps (image.h, irrcache diff). */
#define IC_DEFAULT_HEATMAP_MAX_ERROR 0.5f /* relative error shown as full red: one fixed scale, so heat maps of
                                             different images against one reference compare (bench/run's too) */
#define IC_DEFAULT_BLOTCH_MAX_ERROR 0.05f /* blotch maps: the low-pass relative error shown at full colour (a
                                             cache's blotches are a few per cent; pixel noise is blurred away) */

/* Irradiance cache (cache.h, render.h's ic_ic_options). */
#define IC_DEFAULT_ACCURACY_WARD 0.15f   /* a of Ward's weight (0.3 before: at equal time its interpolation error left the low-pass error no better than the path tracer's on the Cornell box and stair-hall; BENCHMARKS.md) */
#define IC_MAX_ELLIPSE_ASPECT 4.0f     /* elliptical records: major over minor semi-axis at most this (render.h: IC_SHAPE_ELLIPTICAL) */
#define IC_DEFAULT_ACCURACY_TL 1.0f      /* a of the Tabellion–Lamorlette weight (κ = 1/a = 1) */
#define IC_DEFAULT_MIN_RADIUS_PX 3.0f    /* smallest influence radius a·R, pixels at the primary hit */
#define IC_DEFAULT_MAX_RADIUS_PX 48.0f   /* largest influence radius a·R, pixels at the primary hit */
#define IC_DEFAULT_MAX_RADIUS_DIAG 8.0f  /* largest R: the scene diagonal over this */
#define IC_DEFAULT_FINAL_ACCURACY_SCALE 1.0f
#define IC_DEFAULT_THETA_STRATA 16       /* hemisphere gathering (gather.h): M × N strata, N ≈ π·M */
#define IC_DEFAULT_PHI_STRATA 50
#define IC_DEFAULT_RAYS (IC_DEFAULT_THETA_STRATA * IC_DEFAULT_PHI_STRATA) /* rays per record */
#define IC_DEFAULT_LIGHT_SAMPLES 1       /* final render: light samples per shading point */
#define IC_DEFAULT_LARGE_EMITTERS 0.01f  /* hemisphere share of a large emitter (ic_ic_options) */
#define IC_DEFAULT_RECORD_FILTER 3.0f    /* neighbourhood of the record filter, in influence radii */
#define IC_DEFAULT_RECORD_SETS 1         /* hemisphere sets a record may gather */
#define IC_DEFAULT_RECORD_NOISE 0.05f    /* relative σ the sets aim at */
#define IC_CONSTRUCTION_TIME_SHARE 0.5 /* with a time budget: construction stops after this share of it */
#define IC_DEFAULT_MAX_PASSES 30         /* batch construction: a safety bound */
#define IC_MAX_MAX_PASSES 1000           /* the largest max_passes the command takes (--max-passes) */
/* Construction passes the per-pass statistics hold (ic_render_stats.records_per_pass and the rank_comm
 * arrays): batch's most from the command, pass 0 and IC_MAX_MAX_PASSES after it; adaptive's bound
 * (IC_DEFAULT_ADAPTIVE_MAX_PASSES) is far within. Passes beyond it (a library caller's larger bound)
 * are counted in `passes` but have no entry. */
#define IC_STATS_PASSES (IC_MAX_MAX_PASSES + 1)
#define IC_DEFAULT_UNCOVERED 0.001f      /* batch: converged below this share of uncovered look-up points */
#define IC_DEFAULT_MIN_CANDIDATES 16
#define IC_DEFAULT_PASS_GROWTH 0.02f     /* batch: converged when a pass adds fewer than this share of the image's records */
#define IC_DEFAULT_SCREEN_PASSES 3
#define IC_DEFAULT_DITHER_THRESHOLD 0.5f
#define IC_DEFAULT_NORMAL_WEIGHT 4.0f
#define IC_DEFAULT_WORLD_STRIDE 2
#define IC_DEFAULT_CLUSTER_SIZE 0.05f
#define IC_DEFAULT_WEBER 0.02f           /* adaptive construction */
#define IC_DEFAULT_ADAPTIVE_GROWTH 1.4f
#define IC_DEFAULT_ADAPTIVE_MAX_PASSES 64
/* Radiance caching: order 10 (100 coefficients per channel) represents the normalised Phong lobe up to
 * exponent 30 within a few per cent at most views (docs/radiance-caching.md, truncation table). */
#define IC_DEFAULT_HSH_ORDER 10u
#define IC_DEFAULT_RADIANCE_MAX_EXPONENT 30.0f
/* A radiance record's rays, in multiples of an irradiance record's: its n² coefficients need more than
 * the irradiance's one, and radiance records are few (on the glossy-floor Cornell box at 160×160, 4× lowered
 * the image's low-pass relMSE from 5.4·10⁻⁵ to 4.0·10⁻⁵ for 8 % more rays in all). */
#define IC_DEFAULT_RADIANCE_RAYS_FACTOR 4

#endif
