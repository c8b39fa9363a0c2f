/*
 * ic_record_noise.c — the part of a record's noise that comes from the records its rays read.
 *
 * A record's σ (the half-set difference, Křivánek et al. 2006 §4.3) measures the noise of its own rays:
 * both halves read the same records at their hits, so the noise of those records is common to the halves
 * and left out. Where many of a record's rays read few, noisy records (the sensors' records read the hit
 * stage's, gathered with a sixty-fourth of their rays), that part is most of the error. It is propagated
 * here to first order: the record's E = (π/N) Σ_rays L_ray, and a ray whose hit reads records j with
 * weights w_j has L_ray = direct + ρ/π · Σ_j w_j E_j(hit) / Σ_j w_j, so with a read record's noise taken
 * as relative (its extrapolated value E_j(hit) and its bounce levels move with E_j)
 *     ∂E/∂ε_j = (π/N) Σ_rays ρ/π · w_j E_j(hit) / Σ w,   Var = Σ_j (∂E/∂ε_j)² (σ_j/E_j)²,
 * ε_j = δE_j/E_j and σ_j each read record's own σ. Only the first hit's reads are counted (a later
 * vertex's carry the path's throughput, which the callback does not see), and the read records' own reads
 * are not (second order). The derivative is exact for the stratified and progressive gatherers, whose
 * estimate is the rays' plain mean; for the hemicube's weighted sum it is the unweighted approximation.
 */
#include "ic_internal.h"

#include "core/grow.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void ic_ic_noise_add(ic_noise_terms *t, uint32_t record, ic_vec3 coef)
{
    if (t->failed)
        return;
    void *a = t->terms;
    if (ic_grow(&a, &t->capacity, t->count + 1, sizeof *t->terms) != IC_OK) {
        t->failed = 1;
        return;
    }
    t->terms = a;
    t->terms[t->count].record = record;
    t->terms[t->count].coef = coef;
    ++t->count;
}

static int by_record(const void *a, const void *b)
{
    const ic_noise_term *x = a, *y = b;
    if (x->record != y->record)
        return x->record < y->record ? -1 : 1;
    /* Equal records: the order they were added in (their sum's bits must not depend on qsort). */
    return x->order < y->order ? -1 : x->order > y->order;
}

ic_vec3 ic_ic_noise_variance(const ic_ctx *c, ic_noise_terms *t, double scale)
{
    double var[3] = {0.0, 0.0, 0.0};
    /* Entries of one record are summed in the order the rays read them: a stable sort by index first
     * (none read: no array to sort, and qsort must not be given a null one). */
    for (size_t i = 0; i < t->count; ++i)
        t->terms[i].order = (uint32_t)i;
    if (t->count > 1)
        qsort(t->terms, t->count, sizeof *t->terms, by_record);
    for (size_t i = 0; i < t->count;) {
        const uint32_t rec = t->terms[i].record;
        double d[3] = {0.0, 0.0, 0.0};
        for (; i < t->count && t->terms[i].record == rec; ++i) {
            d[0] += t->terms[i].coef.x;
            d[1] += t->terms[i].coef.y;
            d[2] += t->terms[i].coef.z;
        }
        ic_record r;
        if (ic_cache_get_record(c->cache, rec, &r) != IC_OK)
            continue;
        /* The coefficients carry the read record's value: its relative σ scales them. */
        const double e[3] = {r.irradiance.x, r.irradiance.y, r.irradiance.z};
        const double s[3] = {r.sigma.x, r.sigma.y, r.sigma.z};
        for (int ch = 0; ch < 3; ++ch)
            if (e[ch] > 0.0)
                var[ch] += (scale * d[ch] * s[ch] / e[ch]) * (scale * d[ch] * s[ch] / e[ch]);
    }
    t->count = 0;
    return v3((float)var[0], (float)var[1], (float)var[2]);
}

void ic_ic_noise_release(ic_noise_terms *t)
{
    free(t->terms);
    memset(t, 0, sizeof *t);
}
