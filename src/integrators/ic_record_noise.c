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
#include "core/rng.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The slot of record `record` in t's table: its own, or the empty one where it would go. */
static size_t noise_slot(const ic_noise_terms *t, uint32_t record)
{
    const size_t mask = t->slots - 1;
    for (size_t s = (size_t)ic_mix64(record) & mask;; s = (s + 1) & mask)
        if (t->slot[s] == 0 || t->terms[t->slot[s] - 1].record == record)
            return s;
}

void ic_ic_noise_add(ic_noise_terms *t, uint32_t record, ic_vec3 coef)
{
    if (t->failed)
        return;
    if (2 * (t->count + 1) > t->slots) { /* a table twice as large, the entries hashed again */
        size_t slots = t->slots ? 2 * t->slots : 64;
        uint32_t *slot = calloc(slots, sizeof *slot);
        if (!slot) {
            t->failed = 1;
            return;
        }
        free(t->slot);
        t->slot = slot;
        t->slots = slots;
        for (size_t i = 0; i < t->count; ++i) {
            t->terms[i].slot = noise_slot(t, t->terms[i].record);
            t->slot[t->terms[i].slot] = (uint32_t)i + 1;
        }
    }
    const size_t s = noise_slot(t, record);
    if (t->slot[s] == 0) {
        void *a = t->terms;
        if (ic_grow(&a, &t->capacity, t->count + 1, sizeof *t->terms) != IC_OK) {
            t->failed = 1;
            return;
        }
        t->terms = a;
        t->terms[t->count] = (ic_noise_term){record, s, {0.0, 0.0, 0.0}};
        t->slot[s] = (uint32_t)++t->count;
    }
    /* A record's reads are summed in the order the rays make them: the same bits whatever the thread. */
    ic_noise_term *e = &t->terms[t->slot[s] - 1];
    e->coef[0] += coef.x;
    e->coef[1] += coef.y;
    e->coef[2] += coef.z;
}

ic_vec3 ic_ic_noise_variance(const ic_ctx *c, ic_noise_terms *t, double scale)
{
    double var[3] = {0.0, 0.0, 0.0};
    /* Over the records in the order first read (the point's rays alone decide it). */
    for (size_t i = 0; i < t->count; ++i) {
        const double *d = t->terms[i].coef;
        ic_record r;
        if (ic_cache_get_record(c->cache, t->terms[i].record, &r) != IC_OK)
            continue;
        /* The coefficients carry the read record's value: its relative σ scales them. */
        const double e[3] = {r.irradiance.x, r.irradiance.y, r.irradiance.z};
        const double s[3] = {r.sigma.x, r.sigma.y, r.sigma.z};
        for (int ch = 0; ch < 3; ++ch)
            if (e[ch] > 0.0)
                var[ch] += (scale * d[ch] * s[ch] / e[ch]) * (scale * d[ch] * s[ch] / e[ch]);
    }
    for (size_t i = 0; i < t->count; ++i) /* the table emptied at the cost of the records read */
        t->slot[t->terms[i].slot] = 0;
    t->count = 0;
    return v3((float)var[0], (float)var[1], (float)var[2]);
}

void ic_ic_noise_release(ic_noise_terms *t)
{
    free(t->terms);
    free(t->slot);
    memset(t, 0, sizeof *t);
}
