/*
 * irrcache/points.h — irradiance and illuminance at sensor points: the lighting designer's calculation
 * (what Radiance's `rtrace -I` does with its ambient cache), with a one-sigma error estimate per point.
 *
 * Usage:
 *   1. ic_scene *scene; ic_scene_load("room.json", NULL, &scene, &err);
 *   2. ic_sensor_point pts[2] = {{{0, 0.8f, 0}, {0, 1, 0}}, {{1, 0.8f, 0}, {0, 1, 0}}};
 *   3. ic_points_options opt = {0}; opt.integrator = IC_INTEGRATOR_IC;    (zero fields = defaults)
 *   4. ic_point_result res[2]; ic_points_compute(scene, pts, 2, &opt, res, NULL, &err);
 *
 * A sensor is a small white Lambertian receiver at `position` facing `normal`: its irradiance is
 * E = ∫ L(ω) cos θ dω over the hemisphere around the normal, in the scene's radiometric units (W/m² when
 * radiances are W/(sr·m²)). It needs no surface: points may float in the air (a work plane) or lie on one.
 *
 * Two estimators:
 *   IC_INTEGRATOR_PT  the reference: per point `samples` paths from the sensor, each one light sample
 *                     (next-event estimation) plus one cosine-distributed ray path-traced onwards, MIS
 *                     between the two.
 *   IC_INTEGRATOR_IC  irradiance caching (Ward et al. 1988): a record is gathered at a sensor where a
 *                     look-up finds none (in passes over the points in input order, each pass's records
 *                     gathered in parallel), so neighbouring sensors share records; before them, with
 *                     max_depth ≥ 3, records where the sensors' hemisphere rays land (walls, ceiling),
 *                     from which those rays read the bounces after their hits; each point's
 *                     indirect light is interpolated from them, while its direct light is sampled at
 *                     every point (`light_samples` samples, never interpolated): the sun, point lights
 *                     and emitting surfaces by light sampling, the sky (environment) by a light sample
 *                     (through the portals) and a cosine ray, MIS between them.
 *                     σ adds the interpolation's variance (the records' relative variance, pooled over
 *                     the sensors' records, or with fewer than 16 from repeated gathers at them, weighed
 *                     as the interpolation weighs them) to the direct part's; it
 *                     does not include the interpolation's bias (a record's value moved to a nearby
 *                     point by its gradients), which the cache's accuracy parameter bounds.
 *
 * Both split a point's samples into IC_POINT_REPLICATES independent randomised quasi-Monte Carlo
 * replicates (each its own Owen scrambling of the Sobol' sequence): σ is the standard error of their
 * mean. docs/points.md has the details and measurements.
 *
 * Illuminance follows Radiance's convention so that numbers compare: lux = 179 lm/W × (0.265074126 R +
 * 0.670114631 G + 0.064811243 B) of the irradiance (IC_LUMINOUS_EFFICACY, IC_LUMINANCE_R/G/B).
 *
 * Results depend only on the scene, the points, the options and the seed, never on the thread count:
 * random numbers are a hash of (seed, point index, sample), and which points get records is decided
 * serially, in input order. The library never prints; failures come back as ic_result with err filled.
 */
#ifndef IRRCACHE_POINTS_H
#define IRRCACHE_POINTS_H

#include "irrcache/render.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Radiance's white-light luminous efficacy (lm/W) and RGB luminance weights (its CIE_rf, CIE_gf, CIE_bf for
 * the default primaries). */
#define IC_LUMINOUS_EFFICACY 179.0
#define IC_LUMINANCE_R 0.265074126
#define IC_LUMINANCE_G 0.670114631
#define IC_LUMINANCE_B 0.064811243

/* Defaults of the zero fields of ic_points_options. */
#define IC_DEFAULT_POINT_SAMPLES 1024       /* pt: paths per point */
#define IC_DEFAULT_POINT_LIGHT_SAMPLES 256  /* ic: light samples per point for the direct part */
#define IC_MAX_POINT_SAMPLES (1 << 24)      /* the most either may be */
#define IC_DEFAULT_GRID_HEIGHT 0.8          /* m: a work plane's height above the floor (ic_points_grid) */
#define IC_POINT_REPLICATES 16              /* independent randomised quasi-Monte Carlo estimates per point,
                                               whose spread gives σ; samples round up to a multiple */
#define IC_MAX_POINT_COORDINATE 1e18        /* a sensor's coordinates must lie within ±this: farther, the ray
                                               tracer cannot start rays (ic_points_compute refuses them) */

/* A sensor: where it is and which way it faces. */
typedef struct ic_sensor_point {
    ic_vec3 position;      /* world space */
    ic_vec3 normal;        /* any finite length > 0 (normalised here) */
} ic_sensor_point;

/* Options; zero means default (given in brackets). */
typedef struct ic_points_options {
    ic_integrator integrator; /* IC_INTEGRATOR_PT (the zero value) or IC_INTEGRATOR_IC */
    int samples;           /* pt: paths per point, rounded up to a multiple of IC_POINT_REPLICATES
                              [IC_DEFAULT_POINT_SAMPLES] */
    int light_samples;     /* ic: samples per point for the direct part (emitters and sky), rounded up likewise
                              [IC_DEFAULT_POINT_LIGHT_SAMPLES] */
    int max_depth;         /* scattering events, the sensor being the first; the light a sensor receives has
                              bounced at most max_depth − 1 times; IC needs 2 or more (its records carry at
                              least one bounce) [scene file, else 8] */
    int threads;           /* 0 = all cores, at most IC_MAX_THREADS (results do not depend on it) */
    uint64_t seed;         /* random seed [scene file, else 1] */
    int has_seed;          /* 1: use `seed` even if it is 0 */
    ic_ic_options ic;      /* the cache (integrator IC): accuracy, gathering, bounces, …; the strategy is
                              always the points' own (passes, see above); large emitters are always light-sampled; the
                              pixel radius bounds, the record filter and cache files do not apply */
    ic_comm *comm;         /* the processes sharing the computation (irrcache/comm.h): each gathers a share of
                              the records and estimates a share of the points, and every one returns all the
                              results, the same bits as one process; NULL: one process */
    ic_progress_fn progress; /* each phase's share done (may be NULL), from one thread at a time: integrator IC
                              "hit records" (share unknown: −1), then "sensor records" (the share of the
                              sensors a record already serves, at each pass), then "sensors" (the share
                              estimated; with several processes, of this process's own); results do not depend
                              on it */
    void *progress_user;
} ic_points_options;

/* One point's result. */
typedef struct ic_point_result {
    ic_vec3 irradiance;        /* E, RGB, in the scene's radiometric units (W/m²) */
    ic_vec3 irradiance_sigma;  /* one-sigma Monte Carlo error of each channel */
    double illuminance;        /* lux (IC_LUMINOUS_EFFICACY × the luminance-weighted E) */
    double illuminance_sigma;  /* one-sigma Monte Carlo error, lux */
} ic_point_result;

/* What a computation cost. */
typedef struct ic_points_stats {
    double seconds;        /* wall time of ic_points_compute */
    uint64_t rays;         /* rays traced */
    uint32_t records;      /* cache records made at the sensors (integrator IC) */
    int threads;           /* threads used */
    uint32_t hit_records;  /* records made where the sensors' hemisphere rays land (integrator IC with
                              max_depth ≥ 3: the bounces after those hits are read from them) */
} ic_points_stats;

/* Illuminance (lux) of irradiance E by Radiance's convention. */
double ic_illuminance(ic_vec3 irradiance);

/* Daylight factor (BS 8206-2; CIBSE LG10): a point's illuminance under the CIE standard overcast sky as a
 * percentage of the illuminance the same sky gives an unobstructed horizontal plane outdoors,
 * DF = 100 % × E_v / E_v,h. *lux gets E_v,h = 179 lm/W × 7π/9 × L_z (the sky's zenith radiance) for a scene
 * whose environment is a "cie-overcast" sky (docs/scene-format.md, "Skies"), or, for a Radiance scene lit
 * by gensky -c's sky (skybright.cal's overcast type, +z up), the illuminance that sky gives a plane facing
 * +z (its integral, which skybright.cal's blending into the ground near the horizon makes 0.14 % less than
 * 7π/9 × L_z), and that has no other light; fails with IC_ERR_INVALID_ARG for any other scene (the daylight
 * factor is defined for that sky alone). */
ic_result ic_points_daylight_reference(const ic_scene *scene, double *lux, ic_error *err);

/* A horizontal work-plane grid (+y up): cells of side `spacing` over the floor area x0…x1, z0…z1 of a box
 * (y0 its floor, y1 its ceiling), as many whole cells as fit along each side, centred in it; a sensor at each
 * cell's centre at height y0 + height, facing up. */
typedef struct ic_points_grid_spec {
    ic_vec3 lo, hi;        /* the box's corners (x0 y0 z0) and (x1 y1 z1), lo < hi in x and z, lo.y <= hi.y */
    double spacing;        /* > 0 */
    double height;         /* ≥ 0, above lo.y; the plane must lie in the box (y0 + height ≤ y1) */
} ic_points_grid_spec;

/* Most sensors a grid may have. */
#define IC_MAX_GRID_POINTS (1u << 24)

/* The sensors of a grid, row by row: row r (0 … *rows−1) at z = z_0 + r·spacing, column c at x = x_0 +
 * c·spacing, point index r·cols + c; *out is malloc'd (free() it). Fails with IC_ERR_INVALID_ARG (the
 * message says which value) for a box, spacing or height that gives no cell, more than IC_MAX_GRID_POINTS,
 * or a plane outside the box, and for a NULL spec or result. */
ic_result ic_points_grid(const ic_points_grid_spec *spec, ic_sensor_point **out, uint32_t *cols, uint32_t *rows,
                         ic_error *err);

/* Computes out[0 … count−1] for points[0 … count−1] in scene (borrowed for the call). opt and stats may be
 * NULL. Fails with IC_ERR_INVALID_ARG for a point that is not finite or has a zero normal (the message
 * names its index), or options out of range. */
ic_result ic_points_compute(const ic_scene *scene, const ic_sensor_point *points, uint32_t count,
                            const ic_points_options *opt, ic_point_result *out, ic_points_stats *stats,
                            ic_error *err);

#ifdef __cplusplus
}
#endif
#endif
