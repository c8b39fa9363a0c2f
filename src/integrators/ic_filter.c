/*
 * ic_filter.c — record noise control after construction: each record's value (irradiance and both
 * gradients) moves towards a weighted mean of its neighbours' values extrapolated to it.
 *
 * Interpolation turns a record's Monte Carlo error into a soft stain the size of its influence area;
 * where the light comes through small openings or from a few bright patches, the stains are the image's
 * main error (the low-pass error of Křivánek et al. 2006's interpolation is that of the records). The
 * error of neighbouring records is independent while the irradiance they estimate varies slowly over
 * their influence areas (that is what the error bound a promises), so averaging records over a
 * neighbourhood of `scale` times a record's influence radius a_i·R_i cuts the stains' amplitude by about
 * the square root of the neighbours averaged. Neighbours count with an Epanechnikov kernel in distance
 * over the smaller of the two records' neighbourhoods (a record is never extrapolated beyond its own),
 * only on the same bounce level, with normals within 30° and off the record's tangent plane by at most a
 * quarter of the neighbourhood (no averaging across a step or a corner), each extrapolated to the record
 * with its own gradients (Křivánek et al. 2006 §3).
 *
 * The record then moves towards that mean only as far as the noise warrants (empirical Bayes
 * shrinkage): the neighbourhood's spread around the mean is noise σ² (pooled over the neighbourhood from
 * the records' own estimates, Křivánek et al. 2006 §4.3) plus a real variation τ² that the gradients do
 * not explain, and the record moves by σ² / (σ² + τ²) — all the way where the spread is noise alone
 * (light through a door gap), hardly at all where the irradiance really varies (contact shadows under
 * thin treads, the edge of a light patch), so the filter adds almost no bias where records are already
 * good. The mean itself is a plain (linear) kernel mean: a robust one (a biweight that discounts
 * neighbours far from the estimate) is biased low under the right-skewed noise of rare bright rays — it
 * took 4.7 % off the door-ajar scene's image mean. Every record is filtered from the values before
 * filtering, in parallel with a fixed order of sums: the result does not depend on the thread count.
 */
#include "ic_internal.h"

#include "core/threads.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#define NEIGHBOURS_MAX 256
#define NORMAL_COS 0.866f  /* 30° */

typedef struct filter_job {
    ic_cache *cache;
    const ic_record *rec;      /* every record before filtering */
    ic_record *out;            /* value fields filtered */
    float scale;
    uint32_t **scratch;        /* per thread: NEIGHBOURS_MAX indices */
    float **kern;              /* per thread: kernel weights */
    ic_vec3 **val;             /* per thread: extrapolated values */
    int64_t first;             /* this process's block of records starts here */
} filter_job;

static float lum(ic_vec3 v) { return v3_lum(v); }

/* Record j's value extrapolated to record i's position and normal, clamped at zero. */
static ic_vec3 extrapolate(const ic_record *j, const ic_record *i)
{
    ic_vec3 d = v3_sub(i->position, j->position), nx = v3_cross(j->normal, i->normal);
    float e[3] = {j->irradiance.x, j->irradiance.y, j->irradiance.z};
    for (int ch = 0; ch < 3; ++ch)
        e[ch] = fmaxf(0.0f, e[ch] + v3_dot(j->grad_trans[ch], d) + v3_dot(j->grad_rot[ch], nx));
    return v3(e[0], e[1], e[2]);
}

static void filter_one(void *p, int64_t own_item, int thread)
{
    filter_job *j = p;
    int64_t item = j->first + own_item;
    const ic_record *ri = &j->rec[item];
    ic_record *o = &j->out[item];
    *o = *ri;
    float h = j->scale * ri->accuracy * ri->radius;
    if (!(h > 0.0f))
        return;
    uint32_t *idx = j->scratch[thread];
    float *kern = j->kern[thread];
    ic_vec3 *val = j->val[thread];
    uint32_t total = ic_cache_radius_query(j->cache, ri->position, h, idx, NEIGHBOURS_MAX);
    /* More than the buffer holds (dense records, hit records among them): the query wrote the first ones
     * in the octree's order, which leaves out a side of the neighbourhood; the nearest ones instead (those
     * beyond h are skipped below). */
    if (total > NEIGHBOURS_MAX)
        total = ic_cache_knn(j->cache, ri->position, NEIGHBOURS_MAX, idx, NULL);
    uint32_t found = total < NEIGHBOURS_MAX ? total : NEIGHBOURS_MAX, n = 0;
    double var = 0.0, ksum = 0.0;
    for (uint32_t q = 0; q < found; ++q) {
        const ic_record *rj = &j->rec[idx[q]];
        ic_vec3 d = v3_sub(rj->position, ri->position);
        if (rj->bounce != ri->bounce || v3_dot(rj->normal, ri->normal) < NORMAL_COS ||
            fabsf(v3_dot(d, ri->normal)) > 0.25f * h)
            continue;
        /* Both ways: j's own neighbourhood must reach i too, so a record of small radius (a corner's,
         * whose gradient holds only over a short distance) is never extrapolated far. */
        float hj = fminf(h, j->scale * rj->accuracy * rj->radius);
        float x = v3_len2(d) / (hj * hj);
        if (!(x < 1.0f))
            continue;
        idx[n] = idx[q];
        kern[n] = (1.0f - x) * (1.0f - x);
        val[n] = extrapolate(rj, ri);
        float sy = lum(rj->sigma);
        var += (double)kern[n] * sy * sy;
        ksum += kern[n];
        ++n;
    }
    if (n < 2 || !(ksum > 0.0))
        return;
    float sigma = (float)sqrt(var / ksum), usum = (float)ksum;
    const float *u = kern;
    ic_vec3 e = v3s(0.0f), gr[3] = {v3s(0.0f), v3s(0.0f), v3s(0.0f)}, gt[3] = {v3s(0.0f), v3s(0.0f), v3s(0.0f)};
    double u2 = 0.0;
    for (uint32_t k = 0; k < n; ++k) {
        const ic_record *rj = &j->rec[idx[k]];
        e = v3_add(e, v3_scale(val[k], u[k]));
        for (int ch = 0; ch < 3; ++ch) {
            gr[ch] = v3_add(gr[ch], v3_scale(rj->grad_rot[ch], u[k]));
            gt[ch] = v3_add(gt[ch], v3_scale(rj->grad_trans[ch], u[k]));
        }
        u2 += (double)u[k] * u[k];
    }
    float inv = 1.0f / usum;
    ic_vec3 mean = v3_scale(e, inv);
    /* How far to move towards the mean (empirical Bayes shrinkage): the neighbourhood's spread around it
     * is noise (σ²) plus real variation the gradients do not explain (τ²); the record moves by
     * σ² / (σ² + τ²), all the way where the spread is all noise, hardly at all where the irradiance
     * really varies. */
    double spread = 0.0;
    float ym = lum(mean);
    for (uint32_t k = 0; k < n; ++k) {
        double dy = (double)lum(val[k]) - ym;
        spread += (double)u[k] * dy * dy;
    }
    spread *= inv;
    double noise = (double)sigma * sigma, tau2 = spread > noise ? spread - noise : 0.0;
    float lambda = noise + tau2 > 0.0 ? (float)(noise / (noise + tau2)) : 0.0f, keep = 1.0f - lambda;
    o->irradiance = v3_add(v3_scale(ri->irradiance, keep), v3_scale(mean, lambda));
    for (int ch = 0; ch < 3; ++ch) {
        /* Gradients stay in the record's tangent plane. */
        ic_vec3 g = v3_add(v3_scale(ri->grad_rot[ch], keep), v3_scale(gr[ch], lambda * inv));
        ic_vec3 t = v3_add(v3_scale(ri->grad_trans[ch], keep), v3_scale(gt[ch], lambda * inv));
        o->grad_rot[ch] = v3_sub(g, v3_scale(ri->normal, v3_dot(g, ri->normal)));
        o->grad_trans[ch] = v3_sub(t, v3_scale(ri->normal, v3_dot(t, ri->normal)));
    }
    /* σ of the blend of the record (σ) and a weighted mean of independent estimates (σ·√Σu² / Σu). */
    float of_mean = fminf((float)sqrt(u2) * inv, 1.0f);
    o->sigma = v3_scale(ri->sigma, sqrtf(keep * keep + lambda * lambda * of_mean * of_mean));
}

/* What the filter changes in a record, as the processes exchange it. */
typedef struct filtered {
    ic_vec3 irradiance, grad_rot[3], grad_trans[3], sigma;
} filtered;

/* Several processes: every rank's block [first, first + own) of out's filtered values to every rank. */
static ic_result exchange_values(ic_comm *comm, ic_record *out, uint32_t n, uint64_t first, uint64_t own,
                                 ic_error *err)
{
    if (!ic_comm_is_shared(comm))
        return IC_OK;
    filtered *v = malloc(sizeof *v * n);
    if (!v)
        return ic_error_set(err, IC_ERR_OOM, "out of memory for exchanging %u filtered records", n);
    for (uint64_t i = first; i < first + own; ++i) {
        v[i].irradiance = out[i].irradiance;
        memcpy(v[i].grad_rot, out[i].grad_rot, sizeof v[i].grad_rot);
        memcpy(v[i].grad_trans, out[i].grad_trans, sizeof v[i].grad_trans);
        v[i].sigma = out[i].sigma;
    }
    ic_result r = ic_comm_allgather_blocks(comm, v, n, sizeof *v, "exchanging filtered records", err);
    for (uint32_t i = 0; i < n && r == IC_OK; ++i) {
        out[i].irradiance = v[i].irradiance;
        memcpy(out[i].grad_rot, v[i].grad_rot, sizeof v[i].grad_rot);
        memcpy(out[i].grad_trans, v[i].grad_trans, sizeof v[i].grad_trans);
        out[i].sigma = v[i].sigma;
    }
    free(v);
    return r;
}

ic_result ic_ic_filter_cache(ic_cache *cache, int threads, ic_comm *comm, float scale, ic_error *err)
{
    uint32_t n = ic_cache_count(cache);
    if (n == 0 || !(scale > 0.0f))
        return IC_OK;
    threads = ic_resolve_threads(threads);
    filter_job j;
    memset(&j, 0, sizeof j);
    j.cache = cache;
    j.scale = scale;
    ic_record *rec = malloc(sizeof *rec * n), *out = malloc(sizeof *out * n);
    j.scratch = calloc((size_t)threads, sizeof *j.scratch);
    j.kern = calloc((size_t)threads, sizeof *j.kern);
    j.val = calloc((size_t)threads, sizeof *j.val);
    ic_result r = rec && out && j.scratch && j.kern && j.val ? IC_OK : IC_ERR_OOM;
    for (int t = 0; t < threads && r == IC_OK; ++t) {
        j.scratch[t] = malloc(sizeof **j.scratch * NEIGHBOURS_MAX);
        j.kern[t] = malloc(sizeof **j.kern * NEIGHBOURS_MAX);
        j.val[t] = malloc(sizeof **j.val * NEIGHBOURS_MAX);
        if (!j.scratch[t] || !j.kern[t] || !j.val[t])
            r = IC_ERR_OOM;
    }
    if (r != IC_OK) {
        ic_error_set(err, r, "out of memory for filtering %u records", n);
    } else {
        for (uint32_t i = 0; i < n; ++i)
            ic_cache_get_record(cache, i, &rec[i]);
        j.rec = rec;
        j.out = out;
        /* Several processes: a block of records each, their filtered values exchanged. */
        uint64_t first, own;
        ic_comm_block(n, ic_comm_size(comm), ic_comm_rank(comm), &first, &own);
        j.first = (int64_t)first;
        r = ic_parallel_for(threads, (int64_t)own, filter_one, &j);
        if (r != IC_OK)
            ic_error_set(err, r, "could not start threads");
        else
            r = exchange_values(comm, out, n, first, own, err);
        for (uint32_t i = 0; i < n && r == IC_OK; ++i)
            if ((r = ic_cache_set_record_value(cache, i, out[i].irradiance, out[i].grad_rot, out[i].grad_trans,
                                               out[i].sigma)) != IC_OK)
                ic_error_set(err, r, "record %u's filtered value is not finite", i);
    }
    for (int t = 0; j.scratch && t < threads; ++t) {
        free(j.scratch[t]);
        free(j.kern ? j.kern[t] : NULL);
        free(j.val ? j.val[t] : NULL);
    }
    free(j.scratch);
    free(j.kern);
    free(j.val);
    free(rec);
    free(out);
    return r;
}
