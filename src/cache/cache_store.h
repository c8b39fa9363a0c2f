/*
 * cache_store.h — the cache's storage, the weight test and the estimate's last step, shared by the
 * files of src/cache/ (cache.c, cache_query.c, cache_frozen_query.c, cache_frozen.c, cache_clamp.c,
 * cache_file.c). Not a public header.
 *
 * Storage is split hot/cold: the look-up loop touches only
 * `sphere` (position, R_i) and `normal` (n_i, a_i), 32 bytes per record in two 16-byte-aligned
 * arrays; irradiance, gradients and the rest are read only for records that pass the weight test.
 */
#ifndef IC_CACHE_STORE_H
#define IC_CACHE_STORE_H

#include "irrcache/cache.h"
#include "octree.h"

#include "core/vecmath.h"

/* Cold part of a record: read for contributors only. */
typedef struct ic_record_cold {
    ic_vec3 irradiance;          /* E_i */
    ic_vec3 grad_rot[3];         /* ∇r E_i per channel */
    ic_vec3 grad_trans[3];       /* ∇t E_i per channel */
    ic_vec3 tangent;             /* frame tangent */
    ic_vec3 sigma;               /* Monte Carlo σ per channel */
    float harmonic_mean_dist;    /* R before clamping */
    float pixel_footprint;       /* primary-hit pixel size, 0 = unknown */
    uint32_t change_count;       /* changes of a_i or R_i after insertion */
    uint8_t bounce;              /* bounce level */
    uint8_t flags;               /* IC_RECORD_* */
} ic_record_cold;

/*
 * The frozen look-up layout (cache.h: FROZEN LOOK-UPS; built by cache_frozen.c). Everything a look-up
 * reads sits in two compact arrays, both in depth-first order within each part (the top of the tree,
 * then its subtrees: cache_frozen.c):
 *   node — 4 bytes a node: the first of its 8 contiguous children, or IC_FROZEN_LEAF | the offset of
 *          the leaf in `list` (8-byte units);
 *   list — per leaf a header (its cell and entry count) followed by its entries, eight to a block,
 *          every field side by side: what the weight test reads (position, R_i, a_i, normal, bounce,
 *          flags) and what the extrapolation reads (irradiance and both gradients per channel), so
 *          that the test and the extrapolation run eight entries at a time (AVX2; two halves of four
 *          with SSE2) and a look-up reads one contiguous run of memory.
 * Records are copied into each list that uses them (the octree's multiple references), so any
 * change to a record thaws the layout.
 */
#define IC_FROZEN_LEAF 0x80000000u

/* Entries per block: lane k of a block is list entry 8j + k. */
enum { IC_FROZEN_LANES = 8 };

/* Rows of a block's interpolation data: channel c (R, G, B) has rows IC_FROZEN_ROWS·c + IC_FROZEN_E
 * (E_i), + IC_FROZEN_GRAD_ROT + axis (∇r E_i × n_i, x y z: the rotation term (n_i × n)·∇r E_i of
 * Křivánek et al. 2006 §3 is n·(∇r E_i × n_i), a triple product, so a look-up needs no cross product) and
 * + IC_FROZEN_GRAD_TRANS + axis (∇t E_i). */
enum { IC_FROZEN_E = 0, IC_FROZEN_GRAD_ROT = 1, IC_FROZEN_GRAD_TRANS = 4, IC_FROZEN_ROWS = 7 };

/* Eight list entries. Padding entries are all zero (R = a = 0: no distance passes). */
typedef struct ic_frozen_block {
    float x[8], y[8], z[8];      /* p_i */
    float R[8];                  /* R_i */
    float a[8];                  /* a_i */
    float nx[8], ny[8], nz[8];   /* n_i */
    uint32_t index[8];           /* record index */
    uint8_t bounce[8];           /* bounce level */
    uint8_t flags[8];            /* IC_RECORD_* */
    float interp[3 * IC_FROZEN_ROWS * 8]; /* rows of 8 lanes: E_i, ∇r E_i × n_i, ∇t E_i per channel */
} ic_frozen_block;

/* A leaf's header in `list`; its ⌈count/8⌉ blocks follow it. */
typedef struct ic_frozen_leaf {
    float lo[3];                 /* a point descends here iff lo ≤ p < hi on every axis */
    float hi[3];
    uint32_t count;              /* entries */
    uint32_t id;                 /* leaf number (the hint's value − 1) */
    uint32_t all_eligible;       /* 1 + the bounce level of every entry if none is disabled, else 0 */
    uint32_t unused;             /* (the list's 8-byte unit) */
} ic_frozen_leaf;

typedef struct ic_frozen {
    int is_valid;                /* 0: thawed, look-ups use the octree */
    int has_root;                /* 0: empty cache */
    float cx, cy, cz, half;      /* root cube, as in the octree */
    float root_lo[4], root_hi[4]; /* the root's cell (lo ≤ p < hi per axis; the 4th lane unused) */
    uint32_t *node;
    uint32_t node_count;
    uint64_t *list;              /* leaf headers and blocks, addressed in 8-byte units */
    size_t list_len;             /* units in use */
    uint32_t *leaf_at;           /* leaf number → offset of its header in list */
    uint32_t leaf_count;
    size_t entry_count;          /* list entries in all leaves */
} ic_frozen;

/* Builds c->frozen from c->tree (replacing it); IC_ERR_OOM leaves the cache thawed. */
ic_result ic_frozen_build(ic_cache *c);
/* Frees the layout; the cache is thawed. */
void ic_frozen_free(ic_frozen *f);
/* Bytes the layout holds. */
size_t ic_frozen_bytes(const ic_frozen *f);

struct ic_cache {
    ic_cache_params params;      /* resolved */
    ic_comm *comm;               /* the processes that share its insertions (ic_cache_set_comm), or NULL */
    uint32_t count, cap;
    ic_float4 *sphere;           /* p_i, R_i */
    ic_float4 *normal;           /* n_i, a_i */
    ic_float4 *squeeze;          /* elliptical extent (cache.h: ELLIPTICAL RECORDS): k = u·sqrt(1/ρ² − 1) and ρ;
                                    (0, 0, 0, 1) for a round record */
    uint32_t ellipse_count;      /* records with ρ < 1 */
    ic_record_cold *cold;
    ic_octree tree;              /* spheres of radius a_i·R_i·max(1, s): look-ups */
    ic_octree points;            /* positions: k-nearest and radius queries */
    float tree_scale;            /* max(1, final_accuracy_scale) */
    ic_frozen frozen;            /* read-only look-up layout, valid between a freeze and the next insertion */
    int lookup_path;             /* ic_lookup_path the frozen look-ups take (the best this CPU runs) */
    /* That path's look-up (cache_frozen_query.c), called through this pointer: one call, no dispatch chain. */
    int (*query_frozen)(const ic_cache *c, const ic_cache_lookup *q, ic_cache_hint *hint, ic_cache_estimate *out);
    /* Insertion scratch (insertion is single-threaded with respect to the cache). */
    uint32_t *scratch;
    uint32_t scratch_cap;
    uint32_t *changed;           /* existing records lowered by step 3: they seed step 4 too */
    uint32_t changed_len, changed_cap;
    /* Every lowering of an existing record's R_i by steps 3–4 of the current insertion, in order, so a
     * rolled-back insertion can undo it (ic_cache_undo_clamps). */
    struct ic_clamp_undo {
        uint32_t record, change_count; /* before the lowering */
        float radius, lowered;         /* R_i before and after */
    } *undo;
    uint32_t undo_len, undo_cap;
    /* Record payloads (cache_payload.c): per record the offset of its floats in `payload` and their
     * count (0: none); payload_records entries exist, records beyond them have none. */
    uint64_t *payload_at;
    uint32_t *payload_len;
    uint32_t payload_records;
    float *payload;
    size_t payload_used, payload_cap; /* floats in use (including replaced ones) and allocated */
};

static inline ic_octree_items ic_cache_tree_items(const ic_cache *c)
{
    ic_octree_items it = {c->sphere, c->normal, c->tree_scale};
    return it;
}
/* Largest coordinate of a record's sphere (centre ± R_i plus its octree radius a_i·R_i·tree_scale with
 * the margin) a cache holds: far beyond any scene, and far enough below FLT_MAX (3.4e38) that the
 * octree's bounds, their sums and its cell coordinates stay finite (a NaN cell coordinate converted to
 * an integer is undefined behaviour, C11 6.3.1.4). Insertion and loading apply the same test, so what
 * inserts saves and loads. */
#define IC_CACHE_MAX_COORD 1e30
static inline int ic_cache_sphere_in_range(const ic_float4 *s, float tree_radius)
{
    double r = (double)s->w + (double)tree_radius;
    return fabs((double)s->x) + r < IC_CACHE_MAX_COORD && fabs((double)s->y) + r < IC_CACHE_MAX_COORD &&
           fabs((double)s->z) + r < IC_CACHE_MAX_COORD;
}
static inline ic_octree_items ic_cache_point_items(const ic_cache *c)
{
    ic_octree_items it = {c->sphere, c->normal, 0.0f};
    return it;
}

/* 1 / sqrt(1 − cos 10°): normalises the normal term of Tabellion–Lamorlette so 10° weighs like d = R. */
#define IC_TL_NORMAL_SCALE 8.1131404f

/*
 * The weight of a record (sp: position and R_i, np: normal and a_i, ep: its squeeze, NULL for a round
 * record) at (p, n) with acceptance scale s; returns 0 if the record is rejected, else writes w_i(p) to
 * *w and p − p_i to *dp. Each rejection test is labelled (after Radiance's ambient.c habit). The first
 * test is the influence sphere a_i·s·R_i of every weight (an ellipse's major semi-axis); the octree
 * holds every sphere a point lies in, so the octree and a linear scan accept the same records.
 */
static inline int ic_weight_test(const ic_cache_params *params, const ic_float4 *sp, const ic_float4 *np,
                                 const ic_float4 *ep, ic_vec3 p, ic_vec3 n, float s, float *w, ic_vec3 *dp)
{
    ic_vec3 d = v3(p.x - sp->x, p.y - sp->y, p.z - sp->z);
    float d2 = d.x * d.x + d.y * d.y + d.z * d.z;
    float a = np->w * s, R = sp->w, r = a * R;
    /* Outside the influence sphere: too far for either weight. */
    if (!(d2 < r * r))
        return 0;
    float ndot = n.x * np->x + n.y * np->y + n.z * np->z;
    /* Facing away: surfaces with opposite orientation never share irradiance. */
    if (ndot <= 0.0f)
        return 0;
    /* Behind the record: p lies below the record's tangent plane (averaged with ours). */
    float behind = 0.5f * (d.x * (n.x + np->x) + d.y * (n.y + np->y) + d.z * (n.z + np->z));
    if (behind < -params->behind_tolerance * r)
        return 0;
    /* An elliptical extent: the metric |d|² + (k·d)² (a round record's k is zero: the same bits). */
    float m2 = d2;
    if (ep) {
        float t = d.x * ep->x + d.y * ep->y + d.z * ep->z;
        m2 = d2 + t * t;
    }
    float dev = 1.0f - ndot, dist = sqrtf(m2) / R, ndev = sqrtf(dev > 0.0f ? dev : 0.0f);
    if (params->weight == IC_WEIGHT_ERROR) {
        /* One minus the estimated error over its bound (cache.h: WEIGHTS). */
        float dt = dist / a, dr = ndev / a;
        float ww = 1.0f - (dt * dt + dr * dr);
        if (!(ww > 0.0f))
            return 0;
        *w = ww;
    } else if (params->weight == IC_WEIGHT_WARD) {
        /* Ward (Křivánek et al. 2006 §3): accept w > 1/a ⇔ denominator < a. */
        float denom = dist + ndev;
        if (!(denom < a))
            return 0;
        *w = 1.0f / (denom > 1e-6f ? denom : 1e-6f);
    } else {
        /* Tabellion–Lamorlette 2004 with κ = 1/a: accept w > 0. */
        float nt = ndev * IC_TL_NORMAL_SCALE;
        float ww = 1.0f - (dist > nt ? dist : nt) / a;
        if (!(ww > 0.0f))
            return 0;
        *w = ww;
    }
    *dp = d;
    return 1;
}

/* The weight of record i (ic_weight_test on the cache's own arrays). */
static inline int ic_record_weight(const ic_cache *c, uint32_t i, ic_vec3 p, ic_vec3 n, float s, float *w,
                                   ic_vec3 *dp)
{
    return ic_weight_test(&c->params, &c->sphere[i], &c->normal[i], c->ellipse_count ? &c->squeeze[i] : NULL, p, n,
                          s, w, dp);
}

/* 0 for a look-up at a non-finite position or normal, which finds no record (cache.h): a NaN normal would
 * pass every rejection test of ic_weight_test (a comparison with NaN is false) and every record in reach
 * would give E = 0, a black estimate reported as covered. */
static inline int ic_lookup_is_finite(const ic_cache_lookup *q)
{
    return isfinite(q->position.x) && isfinite(q->position.y) && isfinite(q->position.z) &&
           isfinite(q->normal.x) && isfinite(q->normal.y) && isfinite(q->normal.z);
}

/* The estimate's irradiance from the weighted sums acc[c] = Σ w_i E_i(p) of channel c and
 * e->weight_sum; returns 1 if any record contributed. Shared by the octree look-ups (cache_query.c)
 * and the frozen ones (cache_frozen_query.c). */
static inline int ic_estimate_finish(ic_cache_estimate *e, const float acc[3])
{
    if (e->weight_sum > 0.0f) {
        float inv = 1.0f / e->weight_sum;
        e->irradiance = v3(acc[0] * inv, acc[1] * inv, acc[2] * inv);
    }
    return e->contributor_count > 0;
}

/* Code paths of the frozen look-up; all answer alike, bit for bit. */
typedef enum ic_lookup_path {
    IC_LOOKUP_BEST = 0,          /* AVX2 where the CPU has it, else SSE2, else portable */
    IC_LOOKUP_PORTABLE = 1,      /* scalar C */
    IC_LOOKUP_SSE2 = 2,          /* four list entries at a time */
    IC_LOOKUP_AVX2 = 3           /* eight at a time (chosen at run time, x86-64 with GCC or Clang) */
} ic_lookup_path;
/* Tests and benchmarks: makes frozen look-ups take `path`; returns 0 (and changes nothing) where this
 * build or CPU lacks it. */
int ic_cache_set_lookup_path(ic_cache *c, ic_lookup_path path);

/* Neighbor enumeration for the clamps: records j ≠ i within reach of i (see cache.h). Returns the
 * count, the indices are in c->scratch (grown as needed); IC_ERR_OOM → UINT32_MAX. */
uint32_t ic_cache_reach(ic_cache *c, uint32_t i);

/* Clamp step 1 for one record (gradient-magnitude clamp, then R bounds) applied to a semi-axis
 * `axis` (R before clamping: the harmonic-mean distance, or ρ times it for an ellipse's minor one);
 * returns the clamped value. */
float ic_cache_clamp_radius(const ic_cache_params *p, const ic_record *r, float axis);
/* The squeeze of an elliptical extent (cache.h: ELLIPTICAL RECORDS) with unit minor axis u and ratio
 * rho; (0, 0, 0, 1) for rho ≥ 1. */
static inline ic_float4 ic_squeeze_of(ic_vec3 u, float rho)
{
    if (!(rho < 1.0f))
        return (ic_float4){0.0f, 0.0f, 0.0f, 1.0f};
    float k = sqrtf(1.0f / (rho * rho) - 1.0f);
    return (ic_float4){u.x * k, u.y * k, u.z * k, rho};
}
/* 1 when frozen look-ups must take the portable path (elliptical records or the error weight). */
static inline int ic_cache_needs_portable(const ic_cache *c)
{
    return c->ellipse_count > 0 || c->params.weight == IC_WEIGHT_ERROR;
}
/* Chooses c->query_frozen for c->lookup_path and the cache's records (cache_frozen_query.c). */
void ic_cache_select_frozen_query(ic_cache *c);
/* Step 2: validity-radius clamp of records first…count−1 (needs them in the point tree). */
ic_result ic_cache_validity_clamp(ic_cache *c, uint32_t first);
/* Step 3: gradient-difference scaling of records first…count−1 against all (needs both trees). */
ic_result ic_cache_gradient_difference(ic_cache *c, uint32_t first);
/* Step 4: neighbor clamping to a fixed point, seeded by records first…count−1 (needs both trees). */
ic_result ic_cache_neighbor_clamp(ic_cache *c, uint32_t first);
/* Undoes (undo = 1) the current insertion's lowerings of existing records' R_i and change counts,
 * last first, or redoes them (undo = 0) in order: what a rolled-back insertion does. */
void ic_cache_undo_clamps(ic_cache *c, int undo);

/* Grows the record arrays to hold at least n records. */
ic_result ic_cache_reserve(ic_cache *c, uint32_t n);
/* Frees the payload store (ic_cache_destroy). */
void ic_cache_payload_free(ic_cache *c);
/* Drops the payloads of records first… (a rolled-back insertion). */
void ic_cache_payload_truncate(ic_cache *c, uint32_t first);

#endif
