/*
 * ic_adaptive.c — adaptive caching: `--strategy adaptive` (Křivánek,
 * Bouatouch, Pattanaik, Žára 2006, §4; docs/adaptive.md).
 *
 *   §4.1  every record carries its own error bound a_i. Where a shading point sees a visible
 *         discontinuity between the records that overlap there, the lowest-weight of those records is
 *         shrunk just enough to leave the point (a_i := x_i(p) − ε, x_i(p) the value the weight test
 *         compares with a_i), and the point is tested again until nothing is discernible.
 *   §4.2  Algorithm 1, full convergence over the set of shading points (the primary G-buffer points,
 *         after ideal specular chains): passes over a point queue with an in-queue bit; per-point
 *         contribution lists of 6 slots whose change counters say when a contribution must be
 *         re-evaluated; points without contributions get a new record whose a starts from the nearest
 *         record's a × growth (1.4), capped by --accuracy; at the end of a pass the points inside the
 *         influence area (as it was at the start of the pass) of every record that changed are queued
 *         again (k-d tree over the shading points, kdtree.h). A pass that changes nothing ends it.
 *   §4.3  discernibility: L1 = interpolated outgoing radiance from all overlapping records + direct
 *         light, L2 = the same without the tested record i; a discontinuity if
 *         |Y(L1) − Y(L2)| > weber·Y(L1) + max(σ(L1), σ(L2)), σ(L) = Y(ρ/π · Σ w_j σ_j / Σ w_j) from the
 *         records' odd/even σ. The test is written on outgoing radiance (ρ/π·E for the diffuse lobe the
 *         cache serves), so radiance caching can reuse it with its own L_i^o.
 *
 * Departures from the paper, and why:
 *   - New records are made in rounds: after the queue of a pass drains, the points left without a
 *     contribution are visited in queue order and a greedy pick keeps one point per predicted
 *     influence area (a of the new record × R of the nearest record); the picks are gathered in
 *     parallel (ic_gather_batch) and inserted as one batch (ic_cache_insert_batch: validity and
 *     neighbour clamps in a fixed order), then their areas are queued. The paper inserts one record at
 *     a time; rounds keep that sequential logic (each round's decisions see all earlier records) while
 *     gathering in parallel, and nothing depends on the thread count.
 *   - A contribution whose record changed (a_i lowered, or R_i clamped by a neighbour) is re-evaluated
 *     by one cache look-up for the whole point rather than per record: the cache's own weight and
 *     extrapolation are then the only definition of a contribution, so the list can never disagree
 *     with what the final render reads.
 *   - More than 6 contributions: the paper ignores the excess; here such a point is flagged and always
 *     re-evaluated from the cache, so the converged state holds for every contributor the final render
 *     will use (the independent checker in tests/unit/test_adaptive.c relies on that).
 *   - Refinement moves a_i only; R_i is left to the insertion clamps. Lowering a_i for one point only
 *     ever removes the record from other points (areas shrink), which the end-of-pass queueing covers.
 *
 * Direct light at each shading point is estimated once, deterministically (DIRECT_SAMPLES light samples
 * from a per-pixel stream) and stored: it only raises the Weber threshold, and a fixed value keeps the
 * test a pure function of the records.
 */
#include "ic_internal.h"

#include "core/threads.h"
#include "integrators/kdtree.h"
#include "film/film.h"

#include <stdlib.h>
#include <string.h>

#define CONTRIB_SLOTS 6        /* Křivánek et al. 2006 §4.2: "a static array of length 6" */
#define DIRECT_SAMPLES 16      /* light samples of the stored direct light of a shading point */
#define KEY_TAG 0x20u          /* gather-key tag of adaptive records (batch uses others) */

/* One record's contribution at a shading point (Křivánek et al. 2006 §4.2, "each contribution in the list"). */
typedef struct contrib {
    uint32_t record;           /* record index */
    uint32_t change;           /* the record's change counter when this entry was evaluated */
    float weight;              /* w_i(p) */
    float y;                   /* Y(L_i^o(p)) = Y(ρ/π ⊙ E_i(p)) */
    float sigma;               /* Y(ρ/π ⊙ σ_i) */
} contrib;

enum {
    PT_QUEUED = 1u << 0,       /* in the point queue (Křivánek et al. 2006 §4.2: "a bit indicating its presence") */
    PT_STALE = 1u << 1,        /* a new record may reach it: re-read contributions from the cache */
    PT_OVERFLOW = 1u << 2,     /* more than CONTRIB_SLOTS contributions: the list is not the whole set */
    PT_UNCOVERED = 1u << 3,    /* waiting for a new record in this pass */
    PT_CLAIMED = 1u << 4       /* inside a record picked in the current round */
};

typedef struct shading_pt {
    ic_vec3 p, n;              /* position, shading normal (facing the viewer) */
    ic_vec3 albedo;            /* ρ/π per channel: E → outgoing radiance of the diffuse lobe */
    float direct;              /* Y of the stored direct light */
    uint32_t pixel;
    uint8_t count;             /* entries used in c */
    uint8_t flags;             /* PT_* */
    contrib c[CONTRIB_SLOTS];
} shading_pt;

/* What the loop keeps of a record between cache calls. */
typedef struct record_state {
    ic_vec3 p;
    ic_vec3 sigma;             /* σ of E_i per channel */
    float accuracy, radius;    /* a_i, clamped R_i */
    uint32_t change;           /* the cache's change counter */
    float mark_reach;          /* influence radius a_i·R_i at the start of the pass (or at insertion) */
    uint32_t mark_change;      /* change counter at the same moment */
} record_state;

typedef struct adaptive {
    ic_ctx *c;
    float weber, growth, a_max;
    uint32_t npts;
    shading_pt *pts;
    ic_kdtree tree;
    uint32_t *queue;           /* FIFO ring of capacity npts (a point is in it at most once) */
    uint32_t q_head, q_len;
    uint32_t *uncovered;       /* points without contributions, in the order they were found */
    uint32_t n_uncovered;
    record_state *rec;
    uint32_t nrec, rec_cap;
    ic_candidate *cand;        /* picks of one round (capacity npts) */
    float *cand_a;             /* their starting a */
    uint64_t refinements;
    uint32_t unresolved;       /* refinements that could not exclude a record (coincident records) */
    ic_cache_contribution lookup[LOOKUP_CAPACITY];
    contrib work[LOOKUP_CAPACITY];
} adaptive;

/* ---------------------------------------------------------------- shading points */

/* The surface of a pixel's shading point, found exactly as the G-buffer finds it (same ray, same
 * specular chain), so position and normal agree with c->g; this pass also needs the BSDF. */
static int surface_at_pixel(const ic_ctx *c, uint32_t pixel, ic_surface *s, ic_bsdf *b, ic_vec3 *wo, uint64_t *rays)
{
    const ic_camera *cam = &c->tr->scene->camera;
    ic_ray ray;
    if (!ic_camera_ray(cam, (float)(pixel % (uint32_t)cam->width) + 0.5f, (float)(pixel / (uint32_t)cam->width) + 0.5f,
                       &ray))
        return 0;
    return ic_ic_shading_point(c->tr, ray, s, b, wo, NULL, rays);
}

typedef struct point_job {
    adaptive *A;
    uint64_t *rays;            /* per thread, padded */
} point_job;

#define RAY_PAD 8

/* Albedo and stored direct light of one shading point; the light stream is keyed by the pixel, so the
 * value does not depend on the thread that computes it. */
static void point_setup(void *p, int64_t item, int thread)
{
    point_job *j = p;
    adaptive *A = j->A;
    const ic_ctx *c = A->c;
    shading_pt *sp = &A->pts[item];
    uint64_t *rays = &j->rays[thread * RAY_PAD];
    ic_surface s;
    ic_bsdf b;
    ic_vec3 wo;
    sp->albedo = v3s(0.0f);
    sp->direct = 0.0f;
    if (!surface_at_pixel(c, sp->pixel, &s, &b, &wo, rays))
        return;
    sp->albedo = v3_scale(b.kd, IC_INV_PI);
    ic_rng rng = ic_rng_make(c->seed, sp->pixel, 0, 0x6164617074646cULL);
    ic_vec3 sum = v3s(0.0f);
    for (int k = 0; k < DIRECT_SAMPLES; ++k)
        sum = v3_add(sum, ic_ic_direct_light(c, &s, &b, wo, NULL, &rng, rays));
    sp->direct = v3_lum(sum) / (float)DIRECT_SAMPLES;
}

static ic_result setup_points(adaptive *A, ic_error *err)
{
    ic_ctx *c = A->c;
    size_t npix = (size_t)c->g.width * c->g.height;
    uint32_t n = 0;
    for (size_t i = 0; i < npix; ++i)
        n += c->g.valid[i] ? 1u : 0u;
    A->npts = n;
    A->pts = calloc(n ? n : 1, sizeof *A->pts);
    A->queue = malloc(sizeof *A->queue * (n ? n : 1));
    A->uncovered = malloc(sizeof *A->uncovered * (n ? n : 1));
    A->cand = malloc(sizeof *A->cand * (n ? n : 1));
    A->cand_a = malloc(sizeof *A->cand_a * (n ? n : 1));
    ic_vec3 *pos = malloc(sizeof *pos * (n ? n : 1));
    uint64_t *rays = calloc((size_t)c->threads * RAY_PAD, sizeof *rays);
    ic_result r = IC_OK;
    if (!A->pts || !A->queue || !A->uncovered || !A->cand || !A->cand_a || !pos || !rays) {
        r = ic_error_set(err, IC_ERR_OOM, "out of memory for %u adaptive shading points", n);
        goto done;
    }
    n = 0;
    for (size_t i = 0; i < npix; ++i) {
        if (!c->g.valid[i])
            continue;
        shading_pt *sp = &A->pts[n];
        sp->p = c->g.p[i];
        sp->n = c->g.n[i];
        sp->pixel = (uint32_t)i;
        pos[n++] = sp->p;
    }
    point_job j = {A, rays};
    r = ic_parallel_for(c->threads, (int64_t)n, point_setup, &j);
    if (r != IC_OK) {
        ic_error_set(err, r, "could not start threads");
        goto done;
    }
    /* Every process sets up every point alike: the job's rays count them once, as one process does. */
    for (int t = 0; t < c->threads && ic_comm_rank(c->comm) == 0; ++t)
        atomic_fetch_add(&c->rays, rays[t * RAY_PAD]);
    if (ic_kdtree_build(&A->tree, pos, n) != IC_OK)
        r = ic_error_set(err, IC_ERR_OOM, "out of memory for the shading-point k-d tree");
done:
    free(pos);
    free(rays);
    return r;
}

/* ---------------------------------------------------------------- queue */

static void enqueue(adaptive *A, uint32_t i)
{
    shading_pt *sp = &A->pts[i];
    if (sp->flags & PT_QUEUED)
        return;
    sp->flags |= PT_QUEUED;
    A->queue[(A->q_head + A->q_len) % A->npts] = i;
    ++A->q_len;
}

static uint32_t dequeue(adaptive *A)
{
    uint32_t i = A->queue[A->q_head];
    A->q_head = (A->q_head + 1) % A->npts;
    --A->q_len;
    A->pts[i].flags &= (uint8_t)~PT_QUEUED;
    return i;
}

typedef struct enqueue_visit {
    adaptive *A;
    uint8_t flags;             /* added to every visited point */
} enqueue_visit;

static void enqueue_fn(void *user, uint32_t i)
{
    enqueue_visit *v = user;
    v->A->pts[i].flags |= v->flags;
    enqueue(v->A, i);
}

/* ---------------------------------------------------------------- records */

/* Mirrors the cache's records into A->rec: radii and counters of existing records change when a batch
 * is inserted (neighbour clamping), new records get their marks at insertion. */
static ic_result refresh_records(adaptive *A, ic_error *err)
{
    uint32_t n = ic_cache_count(A->c->cache);
    if (n > A->rec_cap) {
        uint32_t cap = A->rec_cap ? A->rec_cap : 256;
        while (cap < n)
            cap *= 2;
        record_state *grown = realloc(A->rec, sizeof *grown * cap);
        if (!grown)
            return ic_error_set(err, IC_ERR_OOM, "out of memory for %u adaptive records", n);
        A->rec = grown;
        A->rec_cap = cap;
    }
    for (uint32_t i = 0; i < n; ++i) {
        ic_record r;
        ic_cache_get_record(A->c->cache, i, &r);
        record_state *s = &A->rec[i];
        s->p = r.position;
        s->sigma = r.sigma;
        s->accuracy = r.accuracy;
        s->radius = r.radius;
        s->change = r.change_count;
        if (i >= A->nrec) {
            s->mark_reach = r.accuracy * r.radius;
            s->mark_change = r.change_count;
        }
    }
    A->nrec = n;
    return IC_OK;
}

/* ---------------------------------------------------------------- discernibility and refinement */

/* Reads the contributions of point sp into A->work: from its list while every entry is current,
 * else from one cache look-up (construction acceptance). Returns how many. */
static uint32_t load_contributions(adaptive *A, shading_pt *sp)
{
    int stale = (sp->flags & (PT_STALE | PT_OVERFLOW)) != 0;
    for (uint32_t k = 0; k < sp->count && !stale; ++k)
        stale = A->rec[sp->c[k].record].change != sp->c[k].change;
    if (!stale) {
        memcpy(A->work, sp->c, sizeof *sp->c * sp->count);
        return sp->count;
    }
    ic_cache_lookup q = ic_cache_lookup_at(sp->p, sp->n, IC_ACCEPT_CONSTRUCTION);
    q.contributions = A->lookup;
    q.contribution_capacity = LOOKUP_CAPACITY;
    ic_cache_estimate e;
    ic_cache_query(A->c->cache, &q, &e);
    uint32_t m = e.contributions_written;
    for (uint32_t k = 0; k < m; ++k) {
        const record_state *rs = &A->rec[A->lookup[k].record];
        contrib *w = &A->work[k];
        w->record = A->lookup[k].record;
        w->change = rs->change;
        w->weight = A->lookup[k].weight;
        w->y = v3_lum(v3_mul(sp->albedo, A->lookup[k].value));
        w->sigma = v3_lum(v3_mul(sp->albedo, rs->sigma));
    }
    sp->flags &= (uint8_t)~PT_STALE;
    if (e.contributor_count > CONTRIB_SLOTS)
        sp->flags |= PT_OVERFLOW;
    else
        sp->flags &= (uint8_t)~PT_OVERFLOW;
    return m;
}

/* Stores A->work back into the point's list, heaviest first (with more than CONTRIB_SLOTS the list
 * keeps the heaviest and PT_OVERFLOW makes the next visit re-read the cache). */
static void store_contributions(adaptive *A, shading_pt *sp, uint32_t m)
{
    for (uint32_t i = 1; i < m; ++i) {
        contrib x = A->work[i];
        uint32_t j = i;
        while (j > 0 && (A->work[j - 1].weight < x.weight ||
                         (A->work[j - 1].weight == x.weight && A->work[j - 1].record > x.record))) {
            A->work[j] = A->work[j - 1];
            --j;
        }
        A->work[j] = x;
    }
    uint32_t keep = m < CONTRIB_SLOTS ? m : CONTRIB_SLOTS;
    memcpy(sp->c, A->work, sizeof *sp->c * keep);
    sp->count = (uint8_t)keep;
    if (m > CONTRIB_SLOTS)
        sp->flags |= PT_OVERFLOW;
}

/* The discernibility test of Křivánek et al. 2006 §4.3 over contributions (m ≥ 2) at a point with direct light Y_d:
 * if removing any record is discernible, returns the index of the lowest-weight contribution (the
 * record to shrink, Křivánek et al. 2006 fig. 1b: "the record contributing with the minimum weight"), else −1.
 * Shrinking the lowest-weight record rather than the lowest-weight *discernible* one matters where a
 * point sits on its own record: only that record's removal is discernible, yet it cannot be excluded
 * (x_i(p) = 0), while excluding the far neighbour resolves the discontinuity.
 * Sums in double: L2 is L1 minus one term, and the difference is what is tested. */
int ic_ic_discernible(const float *weight, const float *y, const float *sigma, const uint32_t *rec_of, uint32_t m,
                      float direct, float weber)
{
    double W = 0.0, Ys = 0.0, Ss = 0.0;
    for (uint32_t k = 0; k < m; ++k) {
        W += weight[k];
        Ys += (double)weight[k] * y[k];
        Ss += (double)weight[k] * sigma[k];
    }
    if (!(W > 0.0))
        return -1;
    double y1 = Ys / W + direct, s1 = Ss / W;
    int seen = 0;
    for (uint32_t k = 0; k < m && !seen; ++k) {
        double W2 = W - weight[k];
        if (!(W2 > 0.0))
            continue;
        double y2 = (Ys - (double)weight[k] * y[k]) / W2 + direct;
        double s2 = (Ss - (double)weight[k] * sigma[k]) / W2;
        seen = fabs(y1 - y2) > weber * y1 + fmax(s1, s2);
    }
    if (!seen)
        return -1;
    int lowest = 0;
    for (uint32_t k = 1; k < m; ++k)
        if (weight[k] < weight[lowest] || (weight[k] == weight[lowest] && rec_of[k] < rec_of[lowest]))
            lowest = (int)k;
    return lowest;
}

/* The a_i that just excludes the point from record i (Křivánek et al. 2006 §4.1, a_i := |p − p_i|/R_i − ε), from
 * the weight the cache computed. Ward accepts while x = |p − p_i|/R_i + sqrt(1 − n·n_i) < a_i, and
 * w = 1/x, so a_i := x·(1 − ε) leaves the point out; ε = 1e-5 exceeds the rounding of 1/(1/x) (a few
 * float ulps). Tabellion–Lamorlette accepts while x = max(d/R_i, c·sqrt(1 − n·n_i)) < a_i with
 * w = 1 − x/a_i, so a_i := a_i·(1 − w − ε). Returns 0 when no positive a_i excludes the point (the
 * point sits on the record). */
float ic_ic_exclusion_accuracy(const ic_ctx *c, float weight, float accuracy)
{
    const float eps = 1e-5f;
    if (c->o.cache.weight == IC_WEIGHT_WARD) {
        if (!(weight < 1e5f)) /* the cache clamps x at 1e-6: no exact inverse there */
            return 0.0f;
        return (1.0f / weight) * (1.0f - eps);
    }
    float a = accuracy * (1.0f - weight - eps);
    return a > 0.0f ? a : 0.0f;
}

/* Adaptive refinement at one point (Křivánek et al. 2006 §4.1) on A->work[0..m): returns the contributions left. */
static uint32_t refine_point(adaptive *A, const shading_pt *sp, uint32_t m)
{
    float weight[LOOKUP_CAPACITY], y[LOOKUP_CAPACITY], sigma[LOOKUP_CAPACITY];
    uint32_t rec_of[LOOKUP_CAPACITY];
    while (m >= 2) {
        for (uint32_t k = 0; k < m; ++k) {
            weight[k] = A->work[k].weight;
            y[k] = A->work[k].y;
            sigma[k] = A->work[k].sigma;
            rec_of[k] = A->work[k].record;
        }
        int best = ic_ic_discernible(weight, y, sigma, rec_of, m, sp->direct, A->weber);
        if (best < 0)
            break;
        uint32_t ri = A->work[best].record;
        record_state *rs = &A->rec[ri];
        float a = ic_ic_exclusion_accuracy(A->c, A->work[best].weight, rs->accuracy);
        if (!(a > 0.0f) || a >= rs->accuracy ||
            ic_cache_set_record_accuracy(A->c->cache, ri, a) != IC_OK) {
            ++A->unresolved;
            break;
        }
        rs->accuracy = a;
        ++rs->change; /* the cache counts exactly one change for a lowered a_i */
        ++A->refinements;
        A->work[best] = A->work[--m];
    }
    return m;
}

/* Lines 6–16 of Algorithm 1 for one point. */
static void process_point(adaptive *A, uint32_t i)
{
    shading_pt *sp = &A->pts[i];
    uint32_t m = load_contributions(A, sp);
    if (m == 0) {
        sp->count = 0;
        if (!(sp->flags & PT_UNCOVERED)) {
            sp->flags |= PT_UNCOVERED;
            A->uncovered[A->n_uncovered++] = i;
        }
        return;
    }
    if (m >= 2)
        m = refine_point(A, sp, m);
    store_contributions(A, sp, m);
}

/* ---------------------------------------------------------------- new records */

typedef struct claim_visit {
    adaptive *A;
    ic_vec3 p, n;
    float radius, accuracy;    /* predicted R and a of the picked record */
} claim_visit;

/* Marks uncovered points the picked record is expected to cover (Ward's test with the predicted R):
 * they wait for the next round instead of getting records of their own. */
static void claim_fn(void *user, uint32_t i)
{
    claim_visit *v = user;
    shading_pt *sp = &v->A->pts[i];
    if ((sp->flags & (PT_UNCOVERED | PT_CLAIMED)) != PT_UNCOVERED)
        return;
    float ndot = v3_dot(sp->n, v->n);
    float x = v3_len(v3_sub(sp->p, v->p)) / v->radius + sqrtf(fmaxf(0.0f, 1.0f - ndot));
    if (ndot > 0.0f && x < v->accuracy)
        sp->flags |= PT_CLAIMED;
}

/* Lines 8–11 of Algorithm 1 for the points left uncovered, as one round (see the file comment). */
static ic_result add_records(adaptive *A, phase_times *pt, ic_error *err)
{
    ic_ctx *c = A->c;
    uint32_t n = 0;
    for (uint32_t k = 0; k < A->n_uncovered; ++k) {
        shading_pt *sp = &A->pts[A->uncovered[k]];
        if (sp->flags & PT_CLAIMED)
            continue;
        uint32_t near;
        float d2;
        float a = A->a_max, R;
        float fp = c->g.footprint[sp->pixel];
        float r_hi = fminf(c->o.cache.max_radius, fp > 0.0f && c->o.cache.max_radius_pixels > 0.0f
                                                       ? c->o.cache.max_radius_pixels * fp
                                                       : INFINITY);
        if (ic_cache_knn(c->cache, sp->p, 1, &near, &d2) == 1) {
            /* Křivánek et al. 2006 §4.2: "copied from the nearest existing record … and multiplied by 1.4". */
            a = fminf(A->a_max, A->growth * A->rec[near].accuracy);
            R = A->rec[near].radius;
        } else {
            R = isfinite(r_hi) ? r_hi : c->scene_diag;
        }
        A->cand[n] = ic_ic_candidate_at_pixel(c, sp->pixel, KEY_TAG);
        A->cand_a[n] = a;
        ++n;
        sp->flags |= PT_CLAIMED;
        claim_visit v = {A, sp->p, sp->n, R, a};
        ic_kdtree_radius(&A->tree, sp->p, a * R, claim_fn, &v);
    }
    ic_gather_point *gp = malloc(sizeof *gp * (n ? n : 1));
    ic_gather_result *gr = malloc(sizeof *gr * (n ? n : 1));
    ic_record *recs = malloc(sizeof *recs * (n ? n : 1));
    ic_vec3 *levels = c->levels ? malloc(sizeof *levels * ((size_t)c->levels + 1) * (n ? n : 1)) : NULL;
    uint8_t *gathered = malloc(n ? n : 1);
    ic_result r = IC_OK;
    uint32_t first = ic_cache_count(c->cache);
    if (!gp || !gr || !recs || !gathered || (c->levels && !levels)) {
        r = ic_error_set(err, IC_ERR_OOM, "out of memory for %u adaptive records", n);
        goto done;
    }
    for (uint32_t k = 0; k < n; ++k)
        gp[k] = ic_ic_gather_point_of(c, &A->cand[k]);
    double t0 = ic_seconds();
    r = ic_ic_gather_points(c, gp, n, gr, levels, NULL, gathered, err);
    double t1 = ic_seconds();
    pt->gather += t1 - t0;
    if (r != IC_OK)
        goto done;
    /* Interrupted: the records gathered are kept, and construction ends after this round. */
    uint32_t kept = ic_ic_keep_gathered(c, gathered, n, gr, levels);
    for (uint32_t k = 0, i = 0; k < n; ++k) {
        if (!gathered[k])
            continue;
        ic_ic_record_from_gather(c, &A->cand[k], &gr[i], &recs[i]);
        recs[i].accuracy = A->cand_a[k];
        ++i;
    }
    n = kept;
    r = ic_cache_insert_batch(c->cache, recs, n, &first, err);
    if (r == IC_OK)
        r = ic_ic_keep_levels(c, first, n, levels, err);
    if (r == IC_OK)
        r = refresh_records(A, err);
    pt->insert += ic_seconds() - t1;
    if (r != IC_OK)
        goto done;
    /* Line 10–11: every point in a new record's area is queued and re-reads its contributions. */
    enqueue_visit v = {A, PT_STALE};
    for (uint32_t k = first; k < A->nrec; ++k)
        ic_kdtree_radius(&A->tree, A->rec[k].p, A->rec[k].accuracy * A->rec[k].radius, enqueue_fn, &v);
    /* Points a round's predictions claimed but that no new record reached go back to the queue too. */
    for (uint32_t k = 0; k < A->n_uncovered; ++k) {
        shading_pt *sp = &A->pts[A->uncovered[k]];
        sp->flags &= (uint8_t)~(PT_UNCOVERED | PT_CLAIMED);
        sp->flags |= PT_STALE;
        enqueue(A, A->uncovered[k]);
    }
    A->n_uncovered = 0;
done:
    free(gp);
    free(gr);
    free(recs);
    free(levels);
    free(gathered);
    return r;
}

/* ---------------------------------------------------------------- Algorithm 1 */

typedef struct adaptive_result {
    int passes;
    int converged;             /* 0 if max_passes or the time budget stopped it */
    int out_of_time;           /* 1 if the time budget stopped it */
    uint32_t records_per_pass[IC_STATS_PASSES];
} adaptive_result;

static ic_result converge(adaptive *A, const ic_render_options *opt, phase_times *pt, adaptive_result *res,
                          ic_error *err)
{
    ic_ctx *c = A->c;
    for (uint32_t i = 0; i < A->npts; ++i)
        enqueue(A, i);
    res->passes = 0;
    res->converged = 1;
    ic_result r = IC_OK;
    while (A->q_len > 0) {
        if (res->passes >= c->o.adaptive_max_passes || (res->passes > 0 && ic_ic_out_of_time(c)) ||
            ic_ic_cancelled(c)) {
            res->converged = 0;
            res->out_of_time = res->passes < c->o.adaptive_max_passes && !ic_ic_cancelled(c);
            break;
        }
        ic_ic_report(opt, "adaptive passes", (double)res->passes / (double)c->o.adaptive_max_passes);
        uint32_t before = A->nrec;
        /* Line 18 needs the influence areas "from the beginning of the pass". */
        for (uint32_t k = 0; k < A->nrec; ++k) {
            A->rec[k].mark_reach = A->rec[k].accuracy * A->rec[k].radius;
            A->rec[k].mark_change = A->rec[k].change;
        }
        int past_deadline = 0;
        for (;;) {
            while (A->q_len > 0)
                process_point(A, dequeue(A));
            /* Interrupted, or out of time (add_records would gather nothing more): the pass ends with
             * the records made so far (the queue is left as it is). */
            past_deadline = A->n_uncovered > 0 && ic_ic_past_deadline(c);
            if (A->n_uncovered == 0 || ic_ic_cancelled(c) || past_deadline)
                break;
            if ((r = add_records(A, pt, err)) != IC_OK)
                return r;
        }
        /* Lines 17–19: records whose a_i (refinement) or R_i (neighbour clamping) changed in this pass
         * re-queue the points of their area as it was when the pass began (or when they were made). */
        uint32_t changed = 0;
        enqueue_visit v = {A, 0};
        for (uint32_t k = 0; k < A->nrec; ++k) {
            if (A->rec[k].change == A->rec[k].mark_change)
                continue;
            ++changed;
            ic_kdtree_radius(&A->tree, A->rec[k].p, A->rec[k].mark_reach, enqueue_fn, &v);
        }
        /* Shrunk records leave stale, over-large octree references; re-fit them (deterministic). */
        if (changed && (r = ic_cache_rebuild_index(c->cache, err)) != IC_OK)
            return r;
        if (res->passes < IC_STATS_PASSES)
            res->records_per_pass[res->passes] = A->nrec - before;
        ++res->passes;
        if (past_deadline) { /* points are left uncovered: cut by time, whatever the queue holds */
            res->converged = 0;
            res->out_of_time = 1;
            break;
        }
    }
    return IC_OK;
}

static void adaptive_free(adaptive *A)
{
    free(A->pts);
    free(A->queue);
    free(A->uncovered);
    free(A->cand);
    free(A->cand_a);
    free(A->rec);
    ic_kdtree_free(&A->tree);
}

/* Runs construction on c; fills the statistics and, for tests, optionally hands out the points. */
ic_result ic_ic_build_adaptive_probed(ic_ctx *c, const ic_render_options *opt, ic_render_stats *st, phase_times *pt,
                       ic_adaptive_probe *probe, ic_error *err)
{
    adaptive *A = calloc(1, sizeof *A);
    if (!A)
        return ic_error_set(err, IC_ERR_OOM, "out of memory");
    /* Defaults of the adaptive options (zero means default, render.h). */
    A->c = c;
    A->weber = c->o.weber;
    A->growth = c->o.adaptive_growth;
    A->a_max = c->o.cache.accuracy;
    double t0 = ic_seconds();
    ic_result r = setup_points(A, err);
    double t1 = ic_seconds();
    adaptive_result res;
    memset(&res, 0, sizeof res);
    phase_times before = *pt;
    if (r == IC_OK && A->npts > 0)
        r = converge(A, opt, pt, &res, err);
    double t2 = ic_seconds();
    if (r == IC_OK) {
        st->passes = res.passes;
        st->refinements = (uint32_t)A->refinements;
        st->cut_short = A->npts > 0 && !res.converged;
        st->cut_by_time = res.out_of_time;
        memcpy(st->records_per_pass, res.records_per_pass, sizeof st->records_per_pass);
        /* Convergence overhead: the loop's time without gathering and insertion (Křivánek et al. 2006 Table 1). */
        double loop = (t2 - t1) - (pt->gather - before.gather) - (pt->insert - before.insert);
        ic_stats_add_phase(st, "adaptive points", t1 - t0);
        ic_stats_add_phase(st, "convergence", loop);
    }
    if (r == IC_OK && probe) {
        probe->point_count = A->npts;
        probe->position = malloc(sizeof *probe->position * (A->npts ? A->npts : 1));
        probe->normal = malloc(sizeof *probe->normal * (A->npts ? A->npts : 1));
        probe->albedo = malloc(sizeof *probe->albedo * (A->npts ? A->npts : 1));
        probe->direct = malloc(sizeof *probe->direct * (A->npts ? A->npts : 1));
        if (!probe->position || !probe->normal || !probe->albedo || !probe->direct) {
            r = ic_error_set(err, IC_ERR_OOM, "out of memory for the adaptive probe");
        } else {
            for (uint32_t i = 0; i < A->npts; ++i) {
                probe->position[i] = A->pts[i].p;
                probe->normal[i] = A->pts[i].n;
                probe->albedo[i] = A->pts[i].albedo;
                probe->direct[i] = A->pts[i].direct;
            }
        }
        probe->passes = res.passes;
        probe->converged = res.converged;
        probe->refinements = A->refinements;
        probe->unresolved = A->unresolved;
    }
    adaptive_free(A);
    free(A);
    return r;
}

ic_result ic_ic_build_adaptive(ic_ctx *c, const ic_render_options *opt, ic_render_stats *st, phase_times *pt,
                               ic_error *err)
{
    return ic_ic_build_adaptive_probed(c, opt, st, pt, NULL, err);
}
