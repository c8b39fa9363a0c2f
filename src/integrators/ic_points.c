/*
 * ic_points.c — the irradiance cache at sensor points (include/irrcache/points.h, driven by
 * src/render/points.c): a context without the image's shading points, construction over the sensors
 * (Ward et al. 1988 §3: a look-up at each point, a record gathered and inserted where none is accepted),
 * in passes whose records are gathered in parallel, and per point the interpolated indirect irradiance with the Monte Carlo σ
 * the interpolation carries over from its records (Křivánek et al. 2006 §4.3 for a record's σ).
 */
#include "ic_internal.h"

#include "irrcache/points.h"

#include "core/sampling.h"
#include "core/select.h"
#include "integrators/ic_world.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#define POINT_KEY_TAG 0x73656e736f72ULL /* keys of sensor records, apart from the image's */
/* The hit records' strata: a sensor record's over this, in θ and in φ (1/64 of its rays; at least 4 × 13,
 * ic_hit_stage.c). A sensor's rays read hundreds of them, so their noise averages out; measured on the
 * overcast sky-room (BENCHMARKS.md, "A daylit room"), 1/16 and 1/256 of the rays both took longer to a 2 %
 * error. */
#define HIT_STRATA_DIV 8
#define MAX_ROUNDS 8                    /* most records gathered at one point (neighbour clamping) */
#define CONTRIBUTION_CAPACITY 256
/* The sensors' records are a kind of their own (the cache's bounce field): a sensor reads only sensor
 * records, and the hit stage's records, which serve the hemisphere rays' hits, never stand in for a
 * sensor's own gather (they have 1/64 of its rays). */
#define SENSOR_BOUNCE (IC_BOUNCE_RADIANCE - 1u)
/* Degrees of freedom the records' relative variance rests on at the least, as many as the light samples'
 * replicates have (IC_POINT_REPLICATES − 1 each); fewer sensor records than this get repeated gathers
 * (repeat_variance). */
#define VARIANCE_DOF IC_POINT_REPLICATES
#define REPEAT_KEY_TAG 0x726570656174ULL /* keys of the repeated gathers, apart from the records' own */
/* Records below this fraction of the median sensor record are left out of the pooled relative variance
 * and keep their own σ (ic_ic_points_build). Measured on the Cornell box's grids and the sky-room's
 * (BENCHMARKS.md, "The sensors' σ and the records they read"): the 2σ coverage of 11 × 11 sensors facing
 * the floor went from 96 % with σ 10 times the seeds' spread to 94.6 % with σ equal to it, the others
 * unchanged. */
#define DARK_FRACTION 0.05

/* v's R, G, B and, in v[3], their luminance (Radiance's weights). For σs of channels that share their rays
 * the weighted sum is the luminance's σ at full correlation, its upper bound. */
static void rgb_lum(double r, double g, double b, double v[4])
{
    v[0] = r;
    v[1] = g;
    v[2] = b;
    v[3] = IC_LUMINANCE_R * v[0] + IC_LUMINANCE_G * v[1] + IC_LUMINANCE_B * v[2];
}

/* Record i's irradiance and own σ as R, G, B and luminance; 0 if it cannot be read. */
static int sensor_record(const ic_ctx *c, uint32_t i, double e[4], double sg[4])
{
    ic_record rec;
    if (ic_cache_get_record(c->cache, i, &rec) != IC_OK)
        return 0;
    rgb_lum(rec.irradiance.x, rec.irradiance.y, rec.irradiance.z, e);
    rgb_lum(rec.sigma.x, rec.sigma.y, rec.sigma.z, sg);
    return 1;
}

void ic_ic_sensor(const ic_scene *scene, ic_vec3 p, ic_vec3 n, ic_surface *s, ic_bsdf *b)
{
    memset(s, 0, sizeof *s);
    s->offset_floor = scene->ray_offset_floor;
    s->p = p;
    s->ng = n;
    s->ns = s->ns_smooth = n;
    s->triangle = IC_NO_HIT;
    memset(b, 0, sizeof *b);
    b->type = IC_MAT_DIFFUSE;
    b->kd = v3s(1.0f);
    b->ior = 1.0f;
    b->p_diffuse = 1.0f;
    b->frame = ic_frame_from_normal(n);
    b->ng = n;
}

ic_result ic_ic_points_ctx_create(const ic_tracer *tr, const ic_render_options *opt, ic_ctx **out, ic_error *err)
{
    ic_render_options o = *opt;
    o.integrator = IC_INTEGRATOR_IC;
    o.time_budget = 0.0;
    o.ic.strategy = IC_STRATEGY_LAZY;
    o.ic.recursive = 0;
    o.ic.load_cache = NULL;
    o.ic.save_cache = NULL;
    /* Every emitter is light-sampled at each sensor: the records carry the environment and indirect
     * light only. */
    o.ic.large_emitters.mode = IC_CACHE_OFF;
    o.ic.record_filter.mode = IC_CACHE_OFF;
    /* Sensors are the only shading points: the context, which traces one shading point per pixel of the
     * camera, is made over a copy of the scene whose camera has a single pixel (the copy shares the
     * scene's arrays and is read only during the call), then pointed at the scene itself. */
    ic_scene *one_pixel = malloc(sizeof *one_pixel);
    if (!one_pixel)
        return ic_error_set(err, IC_ERR_OOM, "out of memory");
    *one_pixel = *tr->scene;
    one_pixel->camera.width = 1;
    one_pixel->camera.height = 1;
    ic_tracer one_pixel_tr = *tr;
    one_pixel_tr.scene = one_pixel;
    ic_result r = ic_ic_ctx_create(&one_pixel_tr, &o, out, NULL, err);
    free(one_pixel);
    if (r != IC_OK)
        return r;
    ic_ctx *c = *out;
    c->tr = tr;
    c->gather_tr.scene = tr->scene;
    c->gather_tr.accel = tr->accel;
    ic_ic_gbuffer_free(c);
    memset(&c->g, 0, sizeof c->g);
    /* The hit stage's records take the sky through portals by light samples (IC_ENV_PORTAL_SAMPLES); the
     * sensors' own records leave the sky out: each sensor samples it (ic_ic_env_light), so that direct
     * light is never interpolated between sensors. */
    c->env_mode = IC_ENV_PORTAL_SAMPLES;
    c->has_record = NULL;
    return IC_OK;
}

/* The points taken in one construction pass, hashed by the cube of side `reach` each lies in: whether a
 * taken point lies within reach of p is then a look at the 27 cubes around p, not at every taken point. */
typedef struct taken_grid {
    float cell;            /* cube side: the reach */
    uint32_t mask;         /* slots − 1; slots a power of two ≥ 2 × points, so the table never fills */
    uint64_t *key;         /* per slot: hash of its cube (never 0), 0 when empty */
    uint32_t *head;        /* per slot: first taken point in the cube, + 1 */
    uint32_t *next;        /* per point: the next taken point in its cube, + 1 (0: none) */
} taken_grid;

static int64_t cube_coord(float x, float cell)
{
    double v = floor((double)x / (double)cell);
    return (int64_t)fmax(fmin(v, 4.0e18), -4.0e18);
}

static uint64_t cube_key(int64_t x, int64_t y, int64_t z)
{
    uint64_t k = ic_hash4((uint64_t)x, (uint64_t)y, (uint64_t)z, 0x63756265ULL);
    return k ? k : 1;
}

/* The head of cube `key`'s list: created empty when insert is 1, else NULL if the cube holds nothing. */
static uint32_t *grid_head(taken_grid *g, uint64_t key, int insert)
{
    for (uint32_t s = (uint32_t)key & g->mask;; s = (s + 1) & g->mask) {
        if (g->key[s] == key)
            return &g->head[s];
        if (g->key[s] == 0) {
            if (!insert)
                return NULL;
            g->key[s] = key;
            g->head[s] = 0;
            return &g->head[s];
        }
    }
}

/* 1 if a point taken this pass lies closer to p than the reach. */
static int grid_near(taken_grid *g, const ic_vec3 *pts, ic_vec3 p)
{
    float reach2 = g->cell * g->cell;
    int64_t cx = cube_coord(p.x, g->cell), cy = cube_coord(p.y, g->cell), cz = cube_coord(p.z, g->cell);
    for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                uint32_t *head = grid_head(g, cube_key(cx + dx, cy + dy, cz + dz), 0);
                for (uint32_t k = head ? *head : 0; k; k = g->next[k - 1])
                    if (v3_len2(v3_sub(pts[k - 1], p)) < reach2)
                        return 1;
            }
    return 0;
}

static void grid_add(taken_grid *g, const ic_vec3 *pts, uint32_t i)
{
    ic_vec3 p = pts[i];
    uint32_t *head = grid_head(g, cube_key(cube_coord(p.x, g->cell), cube_coord(p.y, g->cell),
                                           cube_coord(p.z, g->cell)), 1);
    g->next[i] = *head;
    *head = i + 1;
}

/* The ray from sensor point p (facing n) to the sensor record rec; 0 if the two are one point (nothing can
 * lie between). The weights alone would let a record serve a point on the far side of a thin surface (a
 * sensor under a desk top read the record above it), as in Ward's and Radiance's caches. The ray joins
 * where the two points' hemisphere rays start (ic_ic_gather_origin: each moved off any surface it lies
 * on, to the side its normal faces), so that it tests what the two gathers see: moved towards each other
 * instead, a record lying on the floor itself was moved under it, to the side of a sensor under the floor,
 * and served it. */
static int ray_to_record(const ic_ctx *c, ic_vec3 p, ic_vec3 n, const ic_record *rec, ic_ray *r)
{
    const ic_vec3 a = ic_ic_gather_origin(c, p, n), ab = v3_sub(ic_ic_gather_origin(c, rec->position, rec->normal), a);
    const float dist = v3_len(ab);
    if (!(dist > 0.0f))
        return 0;
    r->org = a;
    r->dir = v3_scale(ab, 1.0f / dist);
    r->tnear = 0.0f;
    r->tfar = dist * (1.0f - 1e-4f);
    return 1;
}

/* The sensors' look-up at (p, n): the sensor records the weights accept (acceptance), those out of view
 * left out (ray_to_record). contrib (CONTRIBUTION_CAPACITY entries) gets the ones kept, *kept their
 * count and *E their interpolation. Returns 0 if none is kept. With `any`, stops at the first kept one
 * (construction asks only whether a point is covered; *E is then not set). */
static int sensor_lookup(const ic_ctx *c, ic_vec3 p, ic_vec3 n, ic_cache_acceptance acceptance, int any,
                         ic_cache_contribution *contrib, uint32_t *kept, ic_vec3 *E)
{
    ic_cache_lookup q = ic_cache_lookup_at(p, n, acceptance);
    q.bounce = SENSOR_BOUNCE;
    q.contributions = contrib;
    q.contribution_capacity = CONTRIBUTION_CAPACITY;
    ic_cache_estimate e;
    *kept = 0;
    if (!ic_cache_query(c->cache, &q, &e))
        return 0;
    /* The records' rays, traced together (a ray stream); without a ray (the point itself) a record is in view. */
    ic_ray rays[CONTRIBUTION_CAPACITY];
    uint8_t blocked[CONTRIBUTION_CAPACITY];
    uint32_t traced = 0;
    int16_t ray_of[CONTRIBUTION_CAPACITY];
    for (uint32_t k = 0; k < e.contributions_written; ++k) {
        ic_record rec;
        ray_of[k] = -1;
        if (ic_cache_get_record(c->cache, contrib[k].record, &rec) != IC_OK)
            ray_of[k] = -2;
        else if (ray_to_record(c, p, n, &rec, &rays[traced])) {
            if (any && !ic_accel_occluded1(c->tr->accel, &rays[traced]))
                return *kept = 1;
            ray_of[k] = (int16_t)traced++;
        } else if (any) {
            return *kept = 1;
        }
    }
    if (any)
        return 0;
    ic_accel_occluded_n(c->tr->accel, rays, blocked, traced, 0);
    double sum[3] = {0.0, 0.0, 0.0}, wsum = 0.0;
    for (uint32_t k = 0; k < e.contributions_written; ++k) {
        if (ray_of[k] == -2 || (ray_of[k] >= 0 && blocked[ray_of[k]]))
            continue;
        const ic_cache_contribution ct = contrib[k];
        contrib[(*kept)++] = ct;
        sum[0] += (double)ct.weight * ct.value.x;
        sum[1] += (double)ct.weight * ct.value.y;
        sum[2] += (double)ct.weight * ct.value.z;
        wsum += ct.weight;
    }
    if (*kept == 0)
        return 0;
    /* All in view (the usual case): the cache's own estimate, which also counts contributors beyond the
     * buffer, if any. */
    *E = *kept == e.contributions_written ? e.irradiance
                                          : v3((float)(sum[0] / wsum), (float)(sum[1] / wsum), (float)(sum[2] / wsum));
    return 1;
}

/* A record's own σ is one half-set difference |E − E_half| (one degree of freedom): on its own it is often
 * far from the truth, and a σ built from it alone covered the error at 2σ for about 80 % of the points.
 * Records made with the same rays have about the same relative noise, so its mean square over the records
 * (an unbiased estimate of the relative variance) serves every record; but not over the nearly dark ones
 * (below DARK_FRACTION of the median record), whose relative noise is of another order and says nothing
 * of the rest: one sensor inside a box, at 10⁻⁵ of the others and σ/E = 3, had raised every sensor's σ
 * tenfold. A dark record keeps its own σ (ic_ic_points_indirect). */
ic_result ic_ic_points_pool(const ic_ctx *c, uint32_t first, uint32_t records, ic_points_noise *noise, ic_error *err)
{
    memset(noise, 0, sizeof *noise);
    const uint32_t sensors = records > first ? records - first : 0;
    if (sensors == 0)
        return IC_OK;
    /* Each record read once: its four values and σs (a record that cannot be read counts as dark, 0). */
    float *value = malloc(sizeof *value * sensors);
    double *e = malloc(sizeof *e * 4 * sensors), *sg = malloc(sizeof *sg * 4 * sensors);
    if (!value || !e || !sg) {
        free(value);
        free(e);
        free(sg);
        return ic_error_set(err, IC_ERR_OOM, "out of memory for %u sensor records", sensors);
    }
    for (uint32_t k = 0; k < sensors; ++k)
        if (!sensor_record(c, first + k, &e[4 * k], &sg[4 * k]))
            memset(&e[4 * k], 0, sizeof *e * 4);
    for (int ch = 0; ch < 4; ++ch) {
        uint32_t lit = 0;
        for (uint32_t k = 0; k < sensors; ++k)
            if (e[4 * k + ch] > 0.0)
                value[lit++] = (float)e[4 * k + ch];
        noise->dark[ch] = lit ? DARK_FRACTION * ic_kth_smallest(value, lit, lit / 2) : 0.0;
        double sum = 0.0;
        uint32_t used = 0;
        for (uint32_t k = 0; k < sensors; ++k) {
            const double ek = e[4 * k + ch], sk = sg[4 * k + ch];
            if (ek > 0.0 && ek >= noise->dark[ch]) {
                sum += (sk / ek) * (sk / ek);
                ++used;
            }
        }
        noise->rel_var[ch] = used ? sum / used : 0.0;
    }
    free(value);
    free(e);
    free(sg);
    return IC_OK;
}

/* The relative variance of a sensor record's E (R, G, B, luminance) from its spread over independent gathers
 * at the records first … records − 1 themselves: each is gathered again ⌈VARIANCE_DOF / records⌉ times
 * (keys of its own), and a record with its repeats, m + 1 values of mean Ē, adds Σ (E_j − Ē)² / Ē² and m
 * degrees of freedom to the pool. With few records their half-set differences (one degree of freedom each)
 * are too few: a single sideways sensor on an open plane under a uniform sky, whose one record's σ then
 * set the interpolation's, fell within 2σ of the closed form at 25 of 40 seeds. */
static ic_result repeat_variance(ic_ctx *c, uint32_t first, uint32_t records, ic_points_noise *noise, ic_error *err)
{
    uint32_t n = records - first, m = (VARIANCE_DOF + n - 1) / n, total = n * m;
    ic_record *rec = malloc(sizeof *rec * n);
    ic_gather_point *pts = malloc(sizeof *pts * total);
    ic_gather_result *res = malloc(sizeof *res * total);
    uint8_t *gathered = calloc(total, 1);
    ic_result r = rec && pts && res && gathered ? IC_OK
                                                : ic_error_set(err, IC_ERR_OOM, "out of memory for %u gathers", total);
    for (uint32_t k = 0; r == IC_OK && k < n; ++k) {
        if ((r = ic_cache_get_record(c->cache, first + k, &rec[k])) != IC_OK) {
            ic_error_set(err, r, "sensor record %u cannot be read", first + k);
            break;
        }
        for (uint32_t j = 0; j < m; ++j) {
            ic_candidate cd;
            memset(&cd, 0, sizeof cd);
            cd.p = rec[k].position;
            cd.n = rec[k].normal;
            cd.key = ic_hash4(REPEAT_KEY_TAG, k, j, 0);
            pts[k * m + j] = ic_ic_gather_point_of(c, &cd);
        }
    }
    if (r == IC_OK) {
        c->record_bounce = SENSOR_BOUNCE;
        c->env_mode = IC_ENV_AT_POINT;
        r = ic_ic_gather_points(c, pts, total, res, NULL, NULL, gathered, err);
        c->record_bounce = 0;
        c->env_mode = IC_ENV_PORTAL_SAMPLES;
    }
    double sum[4] = {0.0, 0.0, 0.0, 0.0}, dof[4] = {0.0, 0.0, 0.0, 0.0};
    for (uint32_t k = 0; r == IC_OK && k < n; ++k) {
        double v[IC_POINT_REPLICATES + 1][4], mean[4] = {0.0, 0.0, 0.0, 0.0};
        uint32_t got = 0;
        for (uint32_t j = 0; j <= m; ++j) {
            if (j > 0 && !gathered[k * m + j - 1])
                continue;
            ic_vec3 e = j == 0 ? rec[k].irradiance : res[k * m + j - 1].irradiance;
            double *x = v[got++];
            x[0] = e.x;
            x[1] = e.y;
            x[2] = e.z;
            x[3] = IC_LUMINANCE_R * e.x + IC_LUMINANCE_G * e.y + IC_LUMINANCE_B * e.z;
            for (int ch = 0; ch < 4; ++ch)
                mean[ch] += x[ch];
        }
        for (int ch = 0; ch < 4 && got > 1; ++ch) {
            mean[ch] /= got;
            if (!(mean[ch] > 0.0) || mean[ch] < noise->dark[ch])
                continue;
            for (uint32_t j = 0; j < got; ++j)
                sum[ch] += (v[j][ch] - mean[ch]) * (v[j][ch] - mean[ch]) / (mean[ch] * mean[ch]);
            dof[ch] += got - 1;
        }
    }
    for (int ch = 0; ch < 4 && r == IC_OK; ++ch)
        noise->rel_var[ch] = dof[ch] > 0.0 ? sum[ch] / dof[ch] : 0.0;
    free(rec);
    free(pts);
    free(res);
    free(gathered);
    return r;
}

ic_result ic_ic_points_build(ic_ctx *c, const ic_render_options *opt, const ic_vec3 *p, const ic_vec3 *n,
                             uint32_t count, ic_points_noise *noise, uint32_t *hit_records, ic_error *err)
{
    /* A record accepts a look-up only within a_i·R_i of itself (both weights' distance term), and R_i is at
     * most the larger of the radius bounds: sensors farther apart than that can never share a record, so
     * their records are gathered together without loss. */
    float reach = c->o.cache.accuracy * fmaxf(c->o.cache.max_radius, c->o.cache.min_radius) * 1.0001f;
    /* Without a finite reach (no radius bound) any two points might share: one record per pass. */
    int bounded = isfinite(reach) && reach > 0.0f && reach < 1e30f;
    taken_grid grid;
    memset(&grid, 0, sizeof grid);
    grid.cell = reach;
    uint32_t slots = 16;
    while (slots < 2u * count && slots < (1u << 31))
        slots *= 2;
    grid.mask = slots - 1;
    uint8_t *gathered = calloc(count, 1);          /* records gathered at each point so far */
    ic_candidate *cand = malloc(sizeof *cand * count);
    if (bounded) {
        grid.key = malloc(sizeof *grid.key * slots);
        grid.head = malloc(sizeof *grid.head * slots);
        grid.next = malloc(sizeof *grid.next * count);
    }
    ic_result r = gathered && cand && (!bounded || (grid.key && grid.head && grid.next))
                      ? IC_OK
                      : ic_error_set(err, IC_ERR_OOM, "out of memory for %u sensors", count);
    phase_times times = {0};
    if (r == IC_OK && c->hit_lookups)
        ic_ic_report(opt, "hit records", -1.0);
    if (r == IC_OK)
        r = ic_ic_hit_stage(c, p, n, count, POINT_KEY_TAG, 0, HIT_STRATA_DIV, 1, &times, err);
    const uint32_t first_sensor_record = r == IC_OK ? ic_cache_count(c->cache) : 0;
    *hit_records = first_sensor_record;
    /* Passes: the uncovered points in input order, each taken unless it lies within reach of one already
     * taken this pass (it waits for the next pass, where their record may cover it); the pass's records
     * are gathered in parallel and inserted as one batch. What is taken depends only on the points and the
     * records, never on the thread count. A point is gathered at most MAX_ROUNDS times (a later record's
     * neighbour clamping can take its cover away, as in lazy construction). */
    ic_cache_contribution contrib[CONTRIBUTION_CAPACITY];
    while (r == IC_OK) {
        uint32_t taken = 0, served = 0;
        if (bounded)
            memset(grid.key, 0, sizeof *grid.key * slots);
        for (uint32_t i = 0; i < count; ++i) {
            if (gathered[i] >= MAX_ROUNDS)
                continue;
            uint32_t kept;
            if (sensor_lookup(c, p[i], n[i], IC_ACCEPT_CONSTRUCTION, 1, contrib, &kept, NULL)) {
                ++served;
                continue;
            }
            if (bounded ? grid_near(&grid, p, p[i]) : taken > 0)
                continue;
            if (bounded)
                grid_add(&grid, p, i);
            ic_candidate *cd = &cand[taken];
            cd->p = p[i];
            cd->n = n[i];
            cd->footprint = 0.0f; /* no pixel: only the world-space radius bounds apply */
            cd->key = ic_hash4(POINT_KEY_TAG, i, gathered[i], 0);
            ++taken;
            ++gathered[i];
        }
        ic_ic_report(opt, "sensor records", (double)served / (double)count);
        if (taken == 0)
            break;
        c->record_bounce = SENSOR_BOUNCE;
        c->env_mode = IC_ENV_AT_POINT;
        c->track_noise = 1;
        r = ic_ic_gather_and_insert(c, cand, taken, &times, err);
        c->track_noise = 0;
        c->record_bounce = 0;
        c->env_mode = IC_ENV_PORTAL_SAMPLES;
    }
    free(gathered);
    free(cand);
    free(grid.key);
    free(grid.head);
    free(grid.next);
    if (r == IC_OK)
        r = ic_cache_freeze(c->cache, err);
    uint32_t records = r == IC_OK ? ic_cache_count(c->cache) : 0;
    const uint32_t sensors = records > first_sensor_record ? records - first_sensor_record : 0;
    if (r == IC_OK)
        r = ic_ic_points_pool(c, first_sensor_record, records, noise, err);
    if (r == IC_OK && sensors > 0 && sensors < VARIANCE_DOF)
        r = repeat_variance(c, first_sensor_record, records, noise, err);
    return r;
}

int ic_ic_points_indirect(const ic_ctx *c, ic_vec3 p, ic_vec3 n, const ic_points_noise *noise, ic_vec3 *E,
                          double sigma[4])
{
    ic_cache_contribution contrib[CONTRIBUTION_CAPACITY];
    uint32_t kept;
    if (!sensor_lookup(c, p, n, IC_ACCEPT_FINAL, 0, contrib, &kept, E))
        return 0;
    /* The estimate is Σ w_i E_i / Σ w_i. A record's noise has two parts. That of its own rays is
     * independent of its neighbours' (each gathered its own): Σ w_i² σ_i² / (Σ w_i)², σ_i the pooled
     * relative σ times its value (a dark record's own σ). That of the records its rays read (c->record_noise) is shared
     * with its neighbours, which read the same ones: taken as fully correlated, its σ is Σ w_i s_i / Σ w_i
     * (the bound; neighbours 1–2 records apart read mostly the same records). Only the first
     * CONTRIBUTION_CAPACITY contributors are weighed; the rest, if any, change the weights little. */
    double var[4] = {0.0, 0.0, 0.0, 0.0}, shared[4] = {0.0, 0.0, 0.0, 0.0}, wsum = 0.0;
    for (uint32_t k = 0; k < kept; ++k) {
        const uint32_t i = contrib[k].record;
        double v[4], own[4];
        if (!sensor_record(c, i, v, own))
            continue;
        double w = contrib[k].weight;
        for (int ch = 0; ch < 4; ++ch)
            var[ch] += w * w * (v[ch] < noise->dark[ch] ? own[ch] * own[ch] : noise->rel_var[ch] * v[ch] * v[ch]);
        if (i < c->record_noise_count) {
            const ic_vec3 sv = c->record_noise[i];
            double s[4]; /* the channels read the same records with the same rays */
            rgb_lum(sqrt(fmax(sv.x, 0.0f)), sqrt(fmax(sv.y, 0.0f)), sqrt(fmax(sv.z, 0.0f)), s);
            for (int ch = 0; ch < 4; ++ch)
                shared[ch] += w * s[ch];
        }
        wsum += w;
    }
    for (int ch = 0; ch < 4; ++ch)
        sigma[ch] = wsum > 0.0 ? sqrt(var[ch] + shared[ch] * shared[ch]) / wsum : 0.0;
    return 1;
}
