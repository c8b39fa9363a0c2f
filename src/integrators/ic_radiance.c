/*
 * ic_radiance.c — radiance caching on glossy surfaces (ic_radiance.h): the lobe tables, construction
 * of radiance records over the image's glossy first hits, and their interpolation in the final render.
 */
#include "ic_internal.h"

#include "core/threads.h"
#include "irrcache/defaults.h"
#include "irrcache/hsh.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#define RADIANCE_KEY_TAG 0x726164696e6365ULL /* keys of radiance records, apart from the irradiance ones */
/* Most SH order of the exact rotation a look-up runs with its scratch on the stack (the basis of order
 * 16 uses 2·16 + 8 = 40). */
#define MAX_SH_ORDER 40
/* Below this angle between a record's normal and the shading normal, the two frames are taken as
 * equal up to a turn about the normal (exact): the lobe is read straight in the record's frame. */
#define SAME_NORMAL_COS 0.9999995f

struct ic_radiance {
    ic_hsh_basis *basis;
    uint32_t k;                  /* n²: coefficients per channel */
    int32_t (*table_of)[3];      /* per material and colour channel: its lobe table, −1 if not served */
    ic_vec3 *scale;              /* per material: the factor of the tabulated lobes (k_s for Phong, 1 else) */
    ic_hsh_lobe_table **tables;
    float *exponent;             /* per table: the Phong exponent it is for, 0 for a lobe of its own */
    uint32_t table_count;
};

uint32_t ic_ic_radiance_payload_floats(const ic_radiance *r) { return r ? 9u * r->k : 0u; }

/* The normalised modified Phong lobe with k_s = 1 in the local frame (Lafortune & Willems 1994):
 * (e + 2)/(2π) cos^e α, α between ω_i and the mirror direction of ω_o. */
static double phong_lobe(void *user, const double wi[3], const double wo[3])
{
    double e = *(const float *)user;
    double c = -wi[0] * wo[0] - wi[1] * wo[1] + wi[2] * wo[2];
    return c > 0.0 ? (e + 2.0) / (2.0 * IC_PI) * pow(c, e) : 0.0;
}

/* Any other glossy model: one colour channel of the BSDF's own glossy lobe in the local frame
 * (ic_bsdf_glossy_local), so a new model needs nothing here. */
typedef struct bsdf_lobe {
    ic_bsdf b;
    int channel;
} bsdf_lobe;

static double bsdf_lobe_channel(void *user, const double wi[3], const double wo[3])
{
    const bsdf_lobe *l = user;
    ic_vec3 f = ic_bsdf_glossy_local(&l->b, v3((float)wi[0], (float)wi[1], (float)wi[2]),
                                     v3((float)wo[0], (float)wo[1], (float)wo[2]));
    return l->channel == 0 ? f.x : l->channel == 1 ? f.y : f.z;
}

void ic_ic_radiance_destroy(ic_radiance *r)
{
    if (!r)
        return;
    for (uint32_t t = 0; t < r->table_count; ++t)
        ic_hsh_lobe_table_destroy(r->tables[t]);
    free(r->tables);
    free(r->exponent);
    free(r->table_of);
    free(r->scale);
    ic_hsh_basis_destroy(r->basis);
    free(r);
}

/* The lobe tables of a microfacet material (conductor, plastic's coat): one per colour channel, or one
 * for all when the channels agree at a few direction pairs. The BSDF is set up for the material at an
 * untextured point facing +z. */
static ic_result microfacet_tables(ic_radiance *r, const ic_scene *s, uint32_t m, ic_error *err)
{
    ic_surface surf;
    memset(&surf, 0, sizeof surf);
    surf.material = m;
    surf.ng = surf.ns = surf.ns_smooth = v3(0.0f, 0.0f, 1.0f);
    surf.triangle = IC_NO_HIT;
    bsdf_lobe lobe[3];
    ic_bsdf_init(&lobe[0].b, s, &surf, v3(0.0f, 0.0f, 1.0f));
    lobe[0].b.frame = ic_frame_from_normal(v3(0.0f, 0.0f, 1.0f));
    lobe[1] = lobe[2] = lobe[0];
    for (int ch = 0; ch < 3; ++ch)
        lobe[ch].channel = ch;
    int grey = 1;
    for (int k = 0; k < 16 && grey; ++k) {
        double th_o = 0.1 * k, th_i = 0.05 * k + 0.02, ph = 0.7 * k;
        double wo[3] = {sin(th_o), 0.0, cos(th_o)}, wi[3] = {sin(th_i) * cos(ph), sin(th_i) * sin(ph), cos(th_i)};
        double f0 = bsdf_lobe_channel(&lobe[0], wi, wo);
        grey = fabs(bsdf_lobe_channel(&lobe[1], wi, wo) - f0) <= 1e-6 * fabs(f0) &&
               fabs(bsdf_lobe_channel(&lobe[2], wi, wo) - f0) <= 1e-6 * fabs(f0);
    }
    for (int ch = 0; ch < (grey ? 1 : 3); ++ch) {
        uint32_t t = r->table_count;
        r->exponent[t] = 0.0f;
        ic_result rc = ic_hsh_lobe_table_create(r->basis, bsdf_lobe_channel, &lobe[ch], NULL, &r->tables[t], err);
        if (rc != IC_OK)
            return rc;
        ++r->table_count;
        r->table_of[m][ch] = (int32_t)t;
    }
    if (grey)
        r->table_of[m][1] = r->table_of[m][2] = r->table_of[m][0];
    r->scale[m] = v3s(1.0f);
    return IC_OK;
}

ic_gather_opts ic_ic_radiance_gather_opts(const ic_ic_options *o)
{
    /* The radiance records' own ray count, as M × N strata with N ≈ πM (the gather uses their product). */
    ic_gather_opts go = o->gather;
    double irradiance_rays = go.theta_strata && go.phi_strata ? (double)go.theta_strata * go.phi_strata : IC_DEFAULT_RAYS;
    double rays = o->radiance_rays > 0 ? o->radiance_rays
                                       : fmin(IC_DEFAULT_RADIANCE_RAYS_FACTOR * irradiance_rays, IC_MAX_RECORD_RAYS);
    go.theta_strata = (uint32_t)fmax(1.0, round(sqrt(rays / IC_PI)));
    go.phi_strata = (uint32_t)fmax(1.0, round(rays / go.theta_strata));
    return go;
}

ic_result ic_ic_radiance_create(ic_ctx *c, ic_error *err)
{
    c->rad = NULL;
    if (c->o.radiance_cache != IC_CACHE_ON)
        return IC_OK;
    const ic_scene *s = c->tr->scene;
    ic_radiance *r = calloc(1, sizeof *r);
    if (!r)
        return ic_error_set(err, IC_ERR_OOM, "out of memory for the radiance cache");
    size_t mats = s->material_count ? s->material_count : 1;
    r->table_of = malloc(sizeof *r->table_of * mats);
    r->scale = malloc(sizeof *r->scale * mats);
    r->tables = calloc(3 * mats, sizeof *r->tables);
    r->exponent = calloc(3 * mats, sizeof *r->exponent);
    if (!r->table_of || !r->scale || !r->tables || !r->exponent) {
        ic_ic_radiance_destroy(r);
        return ic_error_set(err, IC_ERR_OOM, "out of memory for the radiance cache");
    }
    ic_hsh_opts ho;
    ic_hsh_opts_default(&ho, (uint32_t)c->o.hsh_order);
    ic_result rc = ic_hsh_basis_create(&ho, &r->basis, err);
    /* A GGX lobe of roughness α is about as wide as a Phong lobe of exponent 2/α² − 2 (Walter et al. 2007
     * §5.2), so the exponent bound is a roughness bound for the microfacet models. */
    float alpha_min = sqrtf(2.0f / (c->o.radiance_max_exponent + 2.0f));
    int served = 0;
    for (uint32_t m = 0; rc == IC_OK && m < s->material_count; ++m) {
        const ic_material *mat = &s->materials[m];
        r->table_of[m][0] = r->table_of[m][1] = r->table_of[m][2] = -1;
        if ((mat->type == IC_MAT_CONDUCTOR || mat->type == IC_MAT_PLASTIC) && mat->kd_texture < 0 &&
            mat->roughness_texture <= 0 && mat->metallic_texture <= 0 && mat->alpha >= alpha_min) {
            rc = microfacet_tables(r, s, m, err);
            served = 1;
            continue;
        }
        if (mat->type != IC_MAT_GLOSSY || !(v3_maxc(mat->ks) > 0.0f))
            continue;
        float e = mat->ns > 0.0f ? mat->ns : 1.0f;
        if (e > c->o.radiance_max_exponent)
            continue; /* too sharp for the order: path traced */
        uint32_t t = 0;
        while (t < r->table_count && r->exponent[t] != e)
            ++t;
        if (t == r->table_count) {
            r->exponent[t] = e;
            rc = ic_hsh_lobe_table_create(r->basis, phong_lobe, &r->exponent[t], NULL, &r->tables[t], err);
            if (rc != IC_OK)
                break;
            ++r->table_count;
        }
        r->table_of[m][0] = r->table_of[m][1] = r->table_of[m][2] = (int32_t)t;
        r->scale[m] = mat->ks;
        served = 1;
    }
    if (rc != IC_OK || !served) {
        ic_ic_radiance_destroy(r);
        return rc;
    }
    r->k = ic_hsh_count(r->basis);
    if (ic_hsh_sh_order(r->basis) > MAX_SH_ORDER) {
        ic_ic_radiance_destroy(r);
        return ic_error_set(err, IC_ERR_INVALID_ARG, "HSH order %d is too high for radiance records; use at most %d",
                            c->o.hsh_order, (MAX_SH_ORDER - 8) / 2);
    }
    c->rad = r;
    return IC_OK;
}

int ic_ic_radiance_serves(const ic_ctx *c, uint32_t material)
{
    return c->rad && material < c->tr->scene->material_count && c->rad->table_of[material][0] >= 0;
}

/* The lobe of one shading point in a shading frame, computed once and turned into each record's frame. */
typedef struct shading_lobe {
    const ic_hsh_lobe_table *table[3]; /* per colour channel (the same table thrice for a grey lobe) */
    int lobes;                 /* distinct tables: 1 (grey) or 3 */
    ic_vec3 scale;             /* the material's factor on the tabulated lobes */
    ic_vec3 p, n, wo;
    int have_here;
    ic_hsh_frame here;
    float lobe_here[3][IC_HSH_MAX_COUNT];
} shading_lobe;

/* ---- construction ------------------------------------------------------------------------------ */

/* The image's first hits on served materials, one per pixel centre. */
typedef struct glossy_points {
    ic_vec3 *p, *n, *wo;
    float *footprint;
    uint32_t *material;
    uint8_t *valid;            /* 1: a served glossy first hit */
    uint8_t *gathered;         /* 1: a record was gathered here */
} glossy_points;

typedef struct points_job {
    const ic_ctx *c;
    glossy_points *g;
} points_job;

static void points_row(void *p, int64_t y, int thread)
{
    (void)thread;
    points_job *j = p;
    const ic_ctx *c = j->c;
    const ic_camera *cam = &c->tr->scene->camera;
    for (int x = 0; x < cam->width; ++x) {
        size_t i = (size_t)y * cam->width + x;
        ic_ray ray;
        j->g->valid[i] = j->g->gathered[i] = 0;
        if (!ic_camera_ray(cam, (float)x + 0.5f, (float)y + 0.5f, &ray))
            continue;
        ic_hit hit;
        ic_accel_intersect1(c->tr->accel, &ray, &hit);
        if (hit.triangle == IC_NO_HIT)
            continue;
        ic_surface s;
        ic_scene_surface(c->tr->scene, hit.triangle, hit.u, hit.v, &s);
        if (!ic_ic_radiance_serves(c, s.material))
            continue;
        ic_bsdf b;
        ic_bsdf_init(&b, c->tr->scene, &s, v3_neg(ray.dir));
        j->g->p[i] = s.p;
        j->g->n[i] = b.frame.n;
        j->g->wo[i] = v3_neg(ray.dir);
        j->g->material[i] = s.material;
        j->g->footprint[i] = ic_camera_footprint(cam, (float)x + 0.5f, (float)y + 0.5f, hit.t);
        j->g->valid[i] = 1;
    }
}

/* One candidate's gather: the result's buffers point into the pass's payload array. */
typedef struct rad_job {
    ic_ctx *c;
    ic_gather_worker *workers;
    ic_gatherer **gatherers;
    const ic_candidate *cand;
    ic_gather_radiance_result *res;
    atomic_int status;
    atomic_int skipped;          /* 1: the render was cancelled before every candidate was gathered */
} rad_job;

static void rad_item(void *p, int64_t item, int thread)
{
    rad_job *j = p;
    if (ic_ic_cancelled(j->c)) {
        atomic_store(&j->skipped, 1);
        return;
    }
    const ic_candidate *cd = &j->cand[item];
    ic_gather_point gp = ic_ic_gather_point_of(j->c, cd);
    ic_frame f = ic_frame_from_normal(cd->n);
    ic_hsh_frame hf = {f.t, f.b, f.n};
    memset(j->workers[thread].sum, 0, sizeof j->workers[thread].sum);
    ic_result r = ic_gather_radiance(j->gatherers[thread], j->c->rad->basis, &gp, &hf, &j->res[item]);
    if (r != IC_OK) {
        int expected = IC_OK;
        atomic_compare_exchange_strong(&j->status, &expected, (int)r);
    }
}

/* The record of a gathered candidate: the irradiance and its gradient from the same rays (they set
 * the weights and the cache's clamps), R_i also bounded by the coefficients' own relative gradient,
 * R_i ≤ ‖Λ‖/‖∇Λ‖ (Křivánek et al. 2006 §5.1, the gradient clamp applied to the radiance record). */
static void record_of(const ic_ctx *c, const ic_candidate *cd, const ic_gather_radiance_result *g, uint32_t k,
                      ic_record *rec)
{
    memset(rec, 0, sizeof *rec);
    rec->position = cd->p;
    rec->normal = cd->n;
    rec->tangent = ic_frame_from_normal(cd->n).t;
    rec->irradiance = g->irradiance;
    rec->sigma = g->sigma;
    double l2 = 0.0, g2 = 0.0;
    for (uint32_t i = 0; i < 3 * k; ++i) {
        l2 += (double)g->coeffs[i] * g->coeffs[i];
        g2 += (double)g->grad_t[i] * g->grad_t[i] + (double)g->grad_b[i] * g->grad_b[i];
    }
    float R = isfinite(g->harmonic_mean_dist) && g->harmonic_mean_dist > 0.0f ? g->harmonic_mean_dist : c->scene_diag;
    if (!c->o.no_gradients) {
        for (int ch = 0; ch < 3; ++ch)
            rec->grad_trans[ch] = g->trans_grad[ch];
        if (g2 > 0.0 && l2 > 0.0)
            R = fminf(R, (float)sqrt(l2 / g2));
    }
    rec->harmonic_mean_dist = R > 0.0f ? R : c->scene_diag;
    rec->pixel_footprint = cd->footprint;
    rec->bounce = (uint8_t)IC_BOUNCE_RADIANCE;
}

/* Points n results at their rows of `floats` coefficients in coeffs: Λ, then its t and b gradients. */
static void point_results(ic_gather_radiance_result *res, float *coeffs, uint64_t n, uint32_t floats)
{
    for (uint64_t i = 0; i < n; ++i) {
        res[i].coeffs = coeffs + i * floats;
        res[i].grad_t = res[i].coeffs + floats / 3;
        res[i].grad_b = res[i].coeffs + 2 * (floats / 3);
    }
}

/* What gather_block gathers candidates with. */
typedef struct rad_share {
    rad_job *j;
    int threads;
    uint32_t floats; /* coefficients a result */
} rad_share;

/* ic_comm_gather_fn of gather_shared: n candidates on the job's threads into out[1] (results), whose
 * coefficients go to out[0]. */
static ic_result gather_block(void *user, const void *cand, uint64_t n, void *const *out, ic_error *err)
{
    rad_share *u = user;
    rad_job *j = u->j;
    const ic_candidate *all_cand = j->cand;
    ic_gather_radiance_result *all_res = j->res;
    j->cand = cand;
    j->res = out[1];
    point_results(j->res, out[0], n, u->floats);
    int t = u->threads < (int)n ? u->threads : (int)n;
    ic_result r = IC_OK;
    if (n) {
        r = ic_parallel_for(t > 0 ? t : 1, (int64_t)n, rad_item, j);
        if (r != IC_OK)
            ic_error_set(err, r, "could not start %d gathering threads", t);
        else if ((r = (ic_result)atomic_load(&j->status)) != IC_OK)
            ic_error_set(err, r, "gathering a radiance record failed (%s)", ic_result_name(r));
    }
    j->cand = all_cand;
    j->res = all_res;
    return r;
}

/* Gathers the job's count candidates with its threads into j->res (whose coefficient buffers are
 * payload's rows of `floats`). Ranks sharing the render split them as ic_ic_gather_points does
 * (ic_comm_share_gather): rank r gathers candidates r, r + N, …, the results and coefficients are
 * exchanged, and every rank holds every one, bit for bit what one process gathers (a result depends only
 * on the seed and its key). */
static ic_result gather_shared(ic_ctx *c, rad_job *j, uint32_t count, int threads, float *payload, uint32_t floats,
                               ic_error *err)
{
    rad_share u = {j, threads, floats};
    void *const outs[2] = {payload, j->res};
    const size_t sizes[2] = {sizeof *payload * floats, sizeof *j->res};
    uint64_t own;
    ic_result r = ic_comm_share_gather(c->comm, j->cand, sizeof *j->cand, count, 2, outs, sizes, NULL, gather_block,
                                       &u, "radiance records", &own, err);
    c->gathered += own;
    point_results(j->res, payload, count, floats); /* the exchanged results' pointers were their senders' */
    return r;
}

/* Gathers count candidates in parallel and inserts them, with their coefficients, as one batch. */
static ic_result gather_insert(ic_ctx *c, const ic_candidate *cand, uint32_t count, phase_times *pt, ic_error *err)
{
    const uint32_t k = c->rad->k, floats = 9u * k;
    int threads = c->threads < (int)count ? c->threads : (int)count;
    rad_job j;
    memset(&j, 0, sizeof j);
    j.c = c;
    j.cand = cand;
    atomic_init(&j.status, IC_OK);
    atomic_init(&j.skipped, 0);
    float *payload = malloc(sizeof *payload * floats * count);
    ic_record *recs = malloc(sizeof *recs * count);
    j.res = calloc(count, sizeof *j.res);
    j.workers = calloc((size_t)threads, sizeof *j.workers);
    j.gatherers = calloc((size_t)threads, sizeof *j.gatherers);
    ic_result r = payload && recs && j.res && j.workers && j.gatherers
                      ? IC_OK
                      : ic_error_set(err, IC_ERR_OOM, "out of memory for %u radiance records", count);
    if (r == IC_OK)
        point_results(j.res, payload, count, floats);
    ic_gather_opts go = ic_ic_radiance_gather_opts(&c->o);
    for (int t = 0; t < threads && r == IC_OK; ++t) {
        j.workers[t].c = c;
        r = ic_gatherer_create(&go, ic_ic_gather_trace, &j.workers[t], &j.gatherers[t], err);
    }
    double t0 = ic_seconds();
    if (r == IC_OK)
        r = gather_shared(c, &j, count, threads, payload, floats, err);
    double t1 = ic_seconds();
    pt->gather += t1 - t0;
    uint32_t first = 0;
    /* Interrupted: the batch is dropped, and construction ends. */
    if (r == IC_OK && atomic_load(&j.skipped))
        count = 0;
    if (r == IC_OK) {
        for (uint32_t i = 0; i < count; ++i)
            record_of(c, &cand[i], &j.res[i], k, &recs[i]);
        r = ic_cache_insert_batch(c->cache, recs, count, &first, err);
    }
    for (uint32_t i = 0; c->o.no_gradients && i < count; ++i)
        memset(payload + (size_t)i * floats + 3 * k, 0, sizeof *payload * 6 * k); /* interpolation without gradients */
    for (uint32_t i = 0; r == IC_OK && i < count; ++i)
        r = ic_cache_set_payload(c->cache, first + i, payload + (size_t)i * floats, floats, err);
    pt->insert += ic_seconds() - t1;
    for (int t = 0; j.gatherers && t < threads; ++t)
        ic_gatherer_destroy(j.gatherers[t]);
    free(j.gatherers);
    free(j.workers);
    free(j.res);
    free(recs);
    free(payload);
    return r;
}

static void glossy_points_free(glossy_points *g)
{
    free(g->p);
    free(g->n);
    free(g->wo);
    free(g->footprint);
    free(g->material);
    free(g->valid);
    free(g->gathered);
}

static shading_lobe shading_lobe_at(const ic_ctx *c, ic_vec3 p, ic_vec3 n, uint32_t material, ic_vec3 wo);
static int record_outgoing(const ic_ctx *c, shading_lobe *sl, uint32_t index, ic_vec3 *out);

/* Coarse to fine: a pass gathers the grid points no radiance record accepts yet; the next, finer grid
 * sees those records. Spacing 2 is the last: a pixel between records' points that none of them accepts
 * is rendered by the path tracer's glossy bounce. Returns the records made in *made. */
static ic_result cover(ic_ctx *c, const ic_render_options *opt, glossy_points *g, ic_candidate *cand, phase_times *pt,
                       uint32_t *made, ic_error *err)
{
    static const int spacing[] = {32, 16, 8, 4, 2};
    const int steps = (int)(sizeof spacing / sizeof spacing[0]);
    const ic_camera *cam = &c->tr->scene->camera;
    ic_result r = IC_OK;
    for (int s = 0; r == IC_OK && s < steps && !ic_ic_cancelled(c); ++s) {
        int sp = spacing[s];
        uint32_t count = 0;
        for (int y = sp / 2; y < cam->height; y += sp)
            for (int x = sp / 2; x < cam->width; x += sp) {
                size_t i = (size_t)y * cam->width + x;
                if (!g->valid[i] || g->gathered[i])
                    continue;
                ic_cache_lookup q = ic_cache_lookup_at(g->p[i], g->n[i], IC_ACCEPT_CONSTRUCTION);
                q.bounce = IC_BOUNCE_RADIANCE;
                ic_cache_estimate e;
                if (ic_cache_query(c->cache, &q, &e))
                    continue;
                g->gathered[i] = 1; /* gathered once at most */
                cand[count].p = g->p[i];
                cand[count].n = g->n[i];
                cand[count].footprint = g->footprint[i];
                cand[count].key = ic_hash4(RADIANCE_KEY_TAG, i, 0, 0);
                ++count;
            }
        if (count)
            r = gather_insert(c, cand, count, pt, err);
        *made += count;
        ic_ic_report(opt, "radiance records", (double)(s + 1) / (double)steps);
    }
    return r;
}

/* Křivánek et al. 2006 §4.1 and §4.3 on the glossy lobe's outgoing radiance: at every point of the
 * spacing-2 grid, while removing one of the radiance records that accept it would be discernible
 * (Weber's law on the luminance of k_s ⊙ Σ w_i L_i / Σ w_i plus the diffuse indirect light there, the
 * records' σ scaled from their irradiance's), the lowest-weight one is shrunk to leave the point. A
 * sharper lobe sees a record's neighbours' light differently, so its records shrink more and more are
 * made (fig. 10 of the paper). Points are visited in raster order by one thread: the result depends on
 * the records alone. Returns the refinements made. */
static uint32_t refine(ic_ctx *c, const glossy_points *g)
{
    const ic_camera *cam = &c->tr->scene->camera;
    const ic_scene *scene = c->tr->scene;
    uint32_t refinements = 0;
    for (int y = 1; y < cam->height; y += 2)
        for (int x = 1; x < cam->width; x += 2) {
            size_t i = (size_t)y * cam->width + x;
            if (!g->valid[i])
                continue;
            const ic_material *mat = &scene->materials[g->material[i]];
            ic_cache_lookup qd = ic_cache_lookup_at(g->p[i], g->n[i], IC_ACCEPT_CONSTRUCTION);
            ic_cache_estimate ed;
            float rest = ic_cache_query(c->cache, &qd, &ed) ? v3_lum(v3_mul(v3_scale(mat->kd, IC_INV_PI), ed.irradiance))
                                                             : 0.0f;
            for (int round = 0; round < LOOKUP_CAPACITY; ++round) {
                ic_cache_contribution contrib[LOOKUP_CAPACITY];
                ic_cache_lookup q = ic_cache_lookup_at(g->p[i], g->n[i], IC_ACCEPT_CONSTRUCTION);
                q.bounce = IC_BOUNCE_RADIANCE;
                q.contributions = contrib;
                q.contribution_capacity = LOOKUP_CAPACITY;
                ic_cache_estimate e;
                if (!ic_cache_query(c->cache, &q, &e) || e.contributions_written < 2)
                    break;
                float weight[LOOKUP_CAPACITY], yk[LOOKUP_CAPACITY], sigma[LOOKUP_CAPACITY], acc[LOOKUP_CAPACITY];
                uint32_t rec_of[LOOKUP_CAPACITY], m = 0;
                shading_lobe sl = shading_lobe_at(c, g->p[i], g->n[i], g->material[i], g->wo[i]);
                for (uint32_t k = 0; k < e.contributions_written; ++k) {
                    ic_vec3 v;
                    ic_record rec;
                    if (!record_outgoing(c, &sl, contrib[k].record, &v) ||
                        ic_cache_get_record(c->cache, contrib[k].record, &rec) != IC_OK)
                        continue;
                    float y_rec = v3_lum(v), e_lum = v3_lum(rec.irradiance);
                    weight[m] = contrib[k].weight;
                    yk[m] = y_rec;
                    sigma[m] = e_lum > 0.0f ? y_rec * v3_lum(rec.sigma) / e_lum : 0.0f;
                    rec_of[m] = contrib[k].record;
                    acc[m] = rec.accuracy;
                    ++m;
                }
                int best = m >= 2 ? ic_ic_discernible(weight, yk, sigma, rec_of, m, rest, c->o.weber) : -1;
                if (best < 0)
                    break;
                float a = ic_ic_exclusion_accuracy(c, weight[best], acc[best]);
                if (!(a > 0.0f) || a >= acc[best] || ic_cache_set_record_accuracy(c->cache, rec_of[best], a) != IC_OK)
                    break;
                ++refinements;
            }
        }
    return refinements;
}

ic_result ic_ic_radiance_build(ic_ctx *c, const ic_render_options *opt, phase_times *pt, uint32_t *made,
                               uint32_t *refinements, ic_error *err)
{
    *made = *refinements = 0;
    if (!c->rad)
        return IC_OK;
    const ic_camera *cam = &c->tr->scene->camera;
    size_t n = (size_t)cam->width * cam->height;
    glossy_points g = {malloc(sizeof *g.p * n), malloc(sizeof *g.n * n), malloc(sizeof *g.wo * n),
                       malloc(sizeof *g.footprint * n), malloc(sizeof *g.material * n), malloc(n), malloc(n)};
    ic_candidate *cand = malloc(sizeof *cand * n);
    ic_result r = g.p && g.n && g.wo && g.footprint && g.material && g.valid && g.gathered && cand
                      ? IC_OK
                      : ic_error_set(err, IC_ERR_OOM, "out of memory for the glossy shading points");
    if (r == IC_OK) {
        points_job pj = {c, &g};
        r = ic_parallel_for(c->threads, cam->height, points_row, &pj);
        if (r != IC_OK)
            ic_error_set(err, r, "could not start threads");
    }
    if (r == IC_OK)
        r = cover(c, opt, &g, cand, pt, made, err);
    /* The adaptive strategy refines the radiance records too, until a pass neither shrinks nor adds one. */
    for (int pass = 0; r == IC_OK && c->o.strategy == IC_STRATEGY_ADAPTIVE && pass < c->o.adaptive_max_passes &&
                       !ic_ic_cancelled(c);
         ++pass) {
        double t0 = ic_seconds();
        uint32_t refined = refine(c, &g), added = 0;
        pt->insert += ic_seconds() - t0;
        *refinements += refined;
        if (refined == 0)
            break;
        r = cover(c, opt, &g, cand, pt, &added, err);
        *made += added;
    }
    glossy_points_free(&g);
    free(cand);
    return r;
}

/* ---- look-up ----------------------------------------------------------------------------------- */

/* Coefficient vector a·b over k coefficients of channel ch of a planar RGB vector. */
static float dot_channel(const float *rgb, uint32_t ch, const float *lobe, uint32_t k)
{
    return ic_hsh_dot(rgb + ch * k, lobe, k);
}

/* The lobe's coefficients for the shading point's ω_o in a record's frame (t, b = n_i × t, n_i): one
 * vector per distinct table, lobe[0 … sl->lobes − 1]. */
static int lobe_in_frame(const ic_ctx *c, shading_lobe *sl, ic_vec3 t, ic_vec3 b, ic_vec3 n_rec,
                         float lobe[3][IC_HSH_MAX_COUNT])
{
    if (v3_dot(n_rec, sl->n) >= SAME_NORMAL_COS) {
        /* The shading frame is the record's: the lobe for wo read in it. */
        ic_vec3 wl = v3_norm(v3(v3_dot(sl->wo, t), v3_dot(sl->wo, b), v3_dot(sl->wo, n_rec)));
        for (int l = 0; l < sl->lobes; ++l)
            ic_hsh_lobe_table_eval(sl->table[l], wl, lobe[l]);
        return 1;
    }
    /* The lobe in a shading frame (n, and the record's tangent projected onto n's plane), turned into the
     * record's frame by the inverse of the record-to-shading rotation: with the reference rotation,
     * (M Λ)·C = Λ·(Mᵀ C) and Mᵀ is the inverse rotation's matrix (SH rotations are orthogonal), so the
     * lobe is rotated instead of the three channels of Λ. */
    if (!sl->have_here) {
        ic_vec3 ht = v3_sub(t, v3_scale(sl->n, v3_dot(t, sl->n)));
        ht = v3_len2(ht) > 1e-12f ? v3_norm(ht) : ic_frame_from_normal(sl->n).t;
        sl->here.normal = sl->n;
        sl->here.tangent = ht;
        sl->here.bitangent = v3_cross(sl->n, ht);
        ic_vec3 wl = v3_norm(v3(v3_dot(sl->wo, ht), v3_dot(sl->wo, sl->here.bitangent), v3_dot(sl->wo, sl->n)));
        for (int l = 0; l < sl->lobes; ++l)
            ic_hsh_lobe_table_eval(sl->table[l], wl, sl->lobe_here[l]);
        sl->have_here = 1;
    }
    double scratch[2 * MAX_SH_ORDER * MAX_SH_ORDER];
    ic_hsh_frame from = {t, b, n_rec};
    ic_hsh_rotation rot, inv;
    ic_hsh_rotation_from_frames(&from, &sl->here, &rot);
    ic_hsh_rotation_invert(&rot, &inv);
    for (int l = 0; l < sl->lobes; ++l)
        if (ic_hsh_rotate_exact(c->rad->basis, &inv, sl->lobe_here[l], 1, lobe[l], scratch) != IC_OK)
            return 0;
    return 1;
}

/* Record `index`'s coefficients extrapolated to the shading point, Λ_i + d_t ∂Λ_i/∂t + d_b ∂Λ_i/∂b
 * (3·n² planar RGB), scaled by w and added to acc; its frame to *t, *b, *n. Returns 0 when the record has
 * no coefficients of this basis. */
static int add_extrapolated(const ic_ctx *c, const shading_lobe *sl, uint32_t index, float w, float *acc, ic_vec3 *t,
                            ic_vec3 *b, ic_vec3 *n)
{
    const uint32_t k = c->rad->k;
    ic_record rec;
    uint32_t len;
    const float *pay = ic_cache_payload(c->cache, index, &len);
    if (!pay || len != 9u * k || ic_cache_get_record(c->cache, index, &rec) != IC_OK)
        return 0;
    *t = rec.tangent;
    *b = v3_cross(rec.normal, rec.tangent);
    *n = rec.normal;
    ic_vec3 d = v3_sub(sl->p, rec.position);
    float dt = v3_dot(d, *t), db = v3_dot(d, *b);
    const float *gt = pay + 3 * k, *gb = pay + 6 * k;
    for (uint32_t i = 0; i < 3 * k; ++i)
        acc[i] += w * (pay[i] + dt * gt[i] + db * gb[i]);
    return 1;
}

/* Per channel max(acc·C, 0) for a planar RGB vector and the lobe vectors of lobe_in_frame, times the
 * material's scale. */
static ic_vec3 shade_clamped(const ic_ctx *c, const shading_lobe *sl, const float *acc,
                             float lobe[3][IC_HSH_MAX_COUNT])
{
    const uint32_t k = c->rad->k;
    const int l1 = sl->lobes > 1 ? 1 : 0, l2 = sl->lobes > 1 ? 2 : 0;
    return v3_mul(sl->scale, v3(fmaxf(dot_channel(acc, 0, lobe[0], k), 0.0f), fmaxf(dot_channel(acc, 1, lobe[l1], k), 0.0f),
                                fmaxf(dot_channel(acc, 2, lobe[l2], k), 0.0f)));
}

/* Record `index`'s outgoing radiance through the material's lobe at the shading point, per channel and
 * clamped at zero: (Λ_i + d_t ∂Λ_i/∂t + d_b ∂Λ_i/∂b)·C_i(ω_o). Returns 0 when the record has no
 * coefficients of this basis. */
static int record_outgoing(const ic_ctx *c, shading_lobe *sl, uint32_t index, ic_vec3 *out)
{
    float acc[3 * IC_HSH_MAX_COUNT], lobe[3][IC_HSH_MAX_COUNT];
    memset(acc, 0, sizeof(float) * 3 * c->rad->k);
    ic_vec3 t, b, n;
    if (!add_extrapolated(c, sl, index, 1.0f, acc, &t, &b, &n) || !lobe_in_frame(c, sl, t, b, n, lobe))
        return 0;
    *out = shade_clamped(c, sl, acc, lobe);
    return 1;
}

static shading_lobe shading_lobe_at(const ic_ctx *c, ic_vec3 p, ic_vec3 n, uint32_t material, ic_vec3 wo)
{
    shading_lobe sl;
    const int32_t *t = c->rad->table_of[material];
    for (int ch = 0; ch < 3; ++ch)
        sl.table[ch] = c->rad->tables[t[ch]];
    sl.lobes = t[1] == t[0] && t[2] == t[0] ? 1 : 3;
    sl.scale = c->rad->scale[material];
    sl.p = p;
    sl.n = n;
    sl.wo = wo;
    sl.have_here = 0;
    return sl;
}

/* Records whose frames agree (a plane's records share one) are summed before the lobe is applied:
 * Σ_i w_i Λ_i(p)·C = (Σ_i w_i Λ_i(p))·C, one lobe evaluation and one dot product per frame; the zero
 * clamp then applies to each frame's sum rather than to each record. */
#define FRAME_GROUPS 4

int ic_ic_radiance_lookup(const ic_ctx *c, ic_vec3 p, ic_vec3 n, uint32_t material, ic_vec3 wo,
                          ic_cache_hint *hint, ic_vec3 *L)
{
    if (!ic_ic_radiance_serves(c, material))
        return 0;
    ic_cache_contribution contrib[LOOKUP_CAPACITY];
    ic_cache_lookup q = ic_cache_lookup_at(p, n, IC_ACCEPT_FINAL);
    q.bounce = IC_BOUNCE_RADIANCE;
    q.contributions = contrib;
    q.contribution_capacity = LOOKUP_CAPACITY;
    ic_cache_estimate e;
    if (!ic_cache_query_hinted(c->cache, &q, hint, &e) || e.contributions_written == 0)
        return 0;
    shading_lobe sl = shading_lobe_at(c, p, n, material, wo);
    const uint32_t k = c->rad->k;
    float acc[FRAME_GROUPS][3 * IC_HSH_MAX_COUNT], lobe[3][IC_HSH_MAX_COUNT], one[3 * IC_HSH_MAX_COUNT];
    ic_vec3 gt[FRAME_GROUPS], gb[FRAME_GROUPS], gn[FRAME_GROUPS];
    int groups = 0;
    double sum[3] = {0.0, 0.0, 0.0}, wsum = 0.0;
    for (uint32_t i = 0; i < e.contributions_written; ++i) {
        /* The record's frame decides its group: the same normal and tangent within 10⁻⁷ in cosine (records
         * on one plane), else a new group, else (all groups taken) the record alone. */
        ic_record rec;
        if (ic_cache_get_record(c->cache, contrib[i].record, &rec) != IC_OK)
            continue;
        int gi = 0;
        while (gi < groups && !(v3_dot(gn[gi], rec.normal) >= 1.0f - 1e-7f && v3_dot(gt[gi], rec.tangent) >= 1.0f - 1e-7f))
            ++gi;
        float *dst = gi < FRAME_GROUPS ? acc[gi] : one;
        if (gi == groups && gi < FRAME_GROUPS)
            memset(acc[gi], 0, sizeof(float) * 3 * k);
        if (gi >= FRAME_GROUPS)
            memset(one, 0, sizeof(float) * 3 * k);
        ic_vec3 t, b, nn;
        if (!add_extrapolated(c, &sl, contrib[i].record, contrib[i].weight, dst, &t, &b, &nn))
            continue;
        wsum += contrib[i].weight;
        if (gi == groups && gi < FRAME_GROUPS) {
            gt[gi] = t;
            gb[gi] = b;
            gn[gi] = nn;
            ++groups;
        } else if (gi >= FRAME_GROUPS && lobe_in_frame(c, &sl, t, b, nn, lobe)) {
            ic_vec3 v = shade_clamped(c, &sl, one, lobe);
            sum[0] += v.x;
            sum[1] += v.y;
            sum[2] += v.z;
        }
    }
    for (int g = 0; g < groups; ++g) {
        if (!lobe_in_frame(c, &sl, gt[g], gb[g], gn[g], lobe))
            continue;
        ic_vec3 v = shade_clamped(c, &sl, acc[g], lobe);
        sum[0] += v.x;
        sum[1] += v.y;
        sum[2] += v.z;
    }
    if (!(wsum > 0.0))
        return 0;
    *L = v3((float)(sum[0] / wsum), (float)(sum[1] / wsum), (float)(sum[2] / wsum));
    return 1;
}
