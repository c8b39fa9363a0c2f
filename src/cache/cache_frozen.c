/*
 * cache_frozen.c — builds the frozen look-up layout of the irradiance cache (cache.h: FROZEN
 * LOOK-UPS; cache_store.h: ic_frozen) from the multiple-reference octree (Frolov et al. 2012 §4.3).
 *
 * Each leaf's list is the concatenation, root first, of the reference segments of the nodes on its
 * path — the references the octree look-up scans, in the same order — less those whose sphere
 * (current radius a_i·R_i·tree_scale with the octree's margin) cannot reach the leaf's cell. Dropping
 * them is exact: for p in the cell and a record accepted at p, the rounded squared distance from the
 * record's centre to the cell is at most the rounded |p − p_i|² the weight test computes (the same
 * operations in the same order on smaller or equal operands, and float rounding is monotonic), which
 * is below the accepted radius². So a frozen look-up meets the same contributors in the same order as
 * the octree path, with the same weights and extrapolated values (its sums differ from the octree
 * path's in rounding only: cache_frozen_query.c, "Frozen look-ups").
 *
 * A leaf's cell is the set of points the descent sends there: lo ≤ p < hi per axis, where lo and hi
 * are the thresholds the descent compares with (ancestors' centres, the root's faces). A hint check
 * "is p still in the previous leaf" therefore agrees with the descent to the last bit.
 *
 * Building allocates; look-ups on the layout allocate nothing.
 */
#include "cache_store.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The list is addressed in 8-byte units: headers and blocks must fill them exactly. */
_Static_assert(sizeof(ic_frozen_leaf) % 8 == 0 && sizeof(ic_frozen_block) % 8 == 0, "list unit");

/* A candidate list entry while building: a record centre, its squared radius and index. */
typedef struct entry {
    float x, y, z, r2;
    uint32_t record;
} entry;

/* A node's cube (the descent's arithmetic) and its cell (the points that descend into it). */
typedef struct cell {
    float cx, cy, cz, h;
    float lo[3], hi[3];
} cell;

typedef struct builder {
    const ic_cache *c;
    ic_frozen *f;
    entry *active;               /* a stack of lists, one per level of the current path */
    size_t active_cap;
    size_t list_cap;             /* units allocated in f->list */
    size_t leaf_cap;             /* entries allocated in f->leaf_at */
} builder;

/* Squared distance from (x, y, z) to the box [lo, hi], with the weight test's operation order. */
static float cell_dist2(const cell *cl, float x, float y, float z)
{
    float p[3] = {x, y, z}, e[3];
    for (int a = 0; a < 3; ++a) {
        float below = cl->lo[a] - p[a], above = p[a] - cl->hi[a];
        e[a] = below > 0.0f ? below : (above > 0.0f ? above : 0.0f);
    }
    return e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
}

static cell child_cell(const cell *parent, unsigned octant)
{
    cell c = *parent;
    c.h = parent->h * 0.5f;
    float centre[3] = {parent->cx, parent->cy, parent->cz};
    float *mid[3] = {&c.cx, &c.cy, &c.cz};
    for (int a = 0; a < 3; ++a) {
        int upper = (octant >> a) & 1;
        /* Exactly the descent's update (octree.h: ic_octree_path). */
        *mid[a] = upper ? centre[a] + c.h : centre[a] - c.h;
        /* The descent goes up iff p ≥ centre: intersect the constraint into the cell. */
        if (upper)
            c.lo[a] = centre[a] > c.lo[a] ? centre[a] : c.lo[a];
        else
            c.hi[a] = centre[a] < c.hi[a] ? centre[a] : c.hi[a];
    }
    return c;
}

/* Grows *array (elements of `size` bytes, *cap of them) to hold at least `need`, doubling. */
static ic_result grow(void **array, size_t *cap, size_t need, size_t size)
{
    if (need <= *cap)
        return IC_OK;
    size_t n = *cap ? *cap : 1024;
    while (n < need)
        n *= 2;
    void *a = realloc(*array, n * size);
    if (!a)
        return IC_ERR_OOM;
    *array = a;
    *cap = n;
    return IC_OK;
}

static ic_result reserve_active(builder *b, size_t n)
{
    void *a = b->active;
    ic_result rc = grow(&a, &b->active_cap, n, sizeof *b->active);
    b->active = a;
    return rc;
}

/* Appends a leaf header and room for `count` entries to f->list; its offset (8-byte units) goes to
 * *offset. */
static ic_result append_leaf(builder *b, uint32_t count, size_t *offset)
{
    ic_frozen *f = b->f;
    size_t blocks = ((size_t)count + IC_FROZEN_LANES - 1) / IC_FROZEN_LANES;
    size_t units = (sizeof(ic_frozen_leaf) + blocks * sizeof(ic_frozen_block)) / 8;
    void *list = f->list, *leaf_at = f->leaf_at;
    ic_result rc = grow(&list, &b->list_cap, f->list_len + units, sizeof *f->list);
    f->list = list;
    if (rc == IC_OK)
        rc = grow(&leaf_at, &b->leaf_cap, (size_t)f->leaf_count + 1, sizeof *f->leaf_at);
    f->leaf_at = leaf_at;
    /* Leaves are addressed by 31-bit offsets (16 GiB of lists). */
    if (rc != IC_OK || f->list_len >= IC_FROZEN_LEAF)
        return IC_ERR_OOM;
    *offset = f->list_len;
    f->list_len += units;
    return IC_OK;
}

/* The list [begin, end) of b->active becomes the list of the leaf at f->node[fpos]. */
static ic_result emit_leaf(builder *b, uint32_t fpos, const cell *cl, size_t begin, size_t end)
{
    ic_frozen *f = b->f;
    const ic_cache *c = b->c;
    uint32_t count = (uint32_t)(end - begin), blocks = (count + IC_FROZEN_LANES - 1) / IC_FROZEN_LANES;
    size_t at;
    if (append_leaf(b, count, &at) != IC_OK)
        return IC_ERR_OOM;
    ic_frozen_leaf *leaf = (ic_frozen_leaf *)(f->list + at);
    ic_frozen_block *blk = (ic_frozen_block *)(leaf + 1);
    memcpy(leaf->lo, cl->lo, sizeof leaf->lo);
    memcpy(leaf->hi, cl->hi, sizeof leaf->hi);
    leaf->count = count;
    leaf->id = f->leaf_count;
    leaf->all_eligible = count ? 1u + c->cold[b->active[begin].record].bounce : 0u;
    leaf->unused = 0;
    f->leaf_at[f->leaf_count++] = (uint32_t)at;
    memset(blk, 0, blocks * sizeof *blk); /* padding lanes: all zero, no distance passes */
    for (uint32_t k = 0; k < count; ++k) {
        uint32_t i = b->active[begin + k].record, lane = k % IC_FROZEN_LANES;
        ic_frozen_block *o = &blk[k / IC_FROZEN_LANES];
        const ic_float4 *sp = &c->sphere[i], *np = &c->normal[i];
        o->x[lane] = sp->x;
        o->y[lane] = sp->y;
        o->z[lane] = sp->z;
        o->R[lane] = sp->w;
        o->a[lane] = np->w;
        o->nx[lane] = np->x;
        o->ny[lane] = np->y;
        o->nz[lane] = np->z;
        o->index[lane] = i;
        const ic_record_cold *cd = &c->cold[i];
        o->bounce[lane] = cd->bounce;
        o->flags[lane] = cd->flags;
        if (1u + cd->bounce != leaf->all_eligible || (cd->flags & IC_RECORD_DISABLED))
            leaf->all_eligible = 0;
        for (int ch = 0; ch < 3; ++ch) {
            float *row = o->interp + IC_FROZEN_LANES * IC_FROZEN_ROWS * ch + lane; /* row r at row[8r] */
            row[IC_FROZEN_LANES * IC_FROZEN_E] = v3_get(cd->irradiance, ch);
            for (int axis = 0; axis < 3; ++axis) {
                row[IC_FROZEN_LANES * (IC_FROZEN_GRAD_ROT + axis)] =
                    v3_get(v3_cross(cd->grad_rot[ch], v3(np->x, np->y, np->z)), axis);
                row[IC_FROZEN_LANES * (IC_FROZEN_GRAD_TRANS + axis)] = v3_get(cd->grad_trans[ch], axis);
            }
        }
    }
    f->entry_count += count;
    f->node[fpos] = IC_FROZEN_LEAF | (uint32_t)at;
    return IC_OK;
}

/* Copies the entries of b->active[begin, end) that reach cell cl to the top of the stack, in order;
 * returns the new top. The caller has reserved room. */
static size_t filter(builder *b, const cell *cl, size_t begin, size_t end, size_t top)
{
    for (size_t k = begin; k < end; ++k) {
        entry e = b->active[k];
        if (cell_dist2(cl, e.x, e.y, e.z) <= e.r2)
            b->active[top++] = e;
    }
    return top;
}

/* Tree node tn with cell cl goes to f->node[fpos]; its ancestors' surviving entries are
 * b->active[parent_begin, parent_end). Depth-first, children in octant order. (Splitting cells below
 * the octree's leaves to shorten the lists was tried: one level halved the lists of the 300k-record
 * benchmark but tripled the entries and ran slower; see BENCHMARKS.md "Cache library".) */
static ic_result build_node(builder *b, uint32_t tn, uint32_t fpos, const cell *cl, size_t parent_begin,
                            size_t parent_end)
{
    const ic_cache *c = b->c;
    const ic_octree_node node = c->tree.nodes[tn];
    if (reserve_active(b, parent_end + (parent_end - parent_begin) + node.count) != IC_OK)
        return IC_ERR_OOM;
    /* Ancestors' references that still reach this cell, in their order... */
    size_t end = filter(b, cl, parent_begin, parent_end, parent_end);
    /* ...then this node's own, with their current radii (references keep stale, larger ones). */
    ic_octree_items items = ic_cache_tree_items(c);
    for (uint32_t k = 0; k < node.count; ++k) {
        uint32_t i = c->tree.refs[node.begin + k].index;
        if (c->cold[i].flags & IC_RECORD_DISABLED)
            continue; /* no look-up reads it: the lists leave it out */
        const ic_float4 *s = &c->sphere[i];
        float r = ic_octree_item_radius(&items, i);
        entry e = {s->x, s->y, s->z, r * r, i};
        if (cell_dist2(cl, e.x, e.y, e.z) <= e.r2)
            b->active[end++] = e;
    }
    if (!node.child)
        return emit_leaf(b, fpos, cl, parent_end, end);
    /* The frozen tree has the octree's shape: the node array was sized to it. */
    uint32_t first = b->f->node_count;
    b->f->node_count += 8;
    b->f->node[fpos] = first;
    for (unsigned o = 0; o < 8; ++o) {
        cell cc = child_cell(cl, o);
        ic_result rc = build_node(b, node.child + o, first + o, &cc, parent_end, end);
        if (rc != IC_OK)
            return rc;
    }
    return IC_OK;
}

void ic_frozen_free(ic_frozen *f)
{
    free(f->node);
    free(f->list);
    free(f->leaf_at);
    memset(f, 0, sizeof *f);
}

size_t ic_frozen_bytes(const ic_frozen *f)
{
    return (size_t)f->node_count * sizeof *f->node + f->list_len * sizeof *f->list +
           (size_t)f->leaf_count * sizeof *f->leaf_at;
}

ic_result ic_frozen_build(ic_cache *c)
{
    ic_frozen *f = &c->frozen;
    ic_frozen_free(f);
    const ic_octree *t = &c->tree;
    if (!t->has_root || c->count == 0) {
        f->is_valid = 1;
        return IC_OK;
    }
    f->node = malloc((size_t)t->node_count * sizeof *f->node);
    builder b = {c, f, NULL, 0, 0, 0};
    ic_result rc = f->node ? IC_OK : IC_ERR_OOM;
    if (rc == IC_OK) {
        f->cx = t->cx;
        f->cy = t->cy;
        f->cz = t->cz;
        f->half = t->half;
        cell root = {t->cx, t->cy, t->cz, t->half, {t->cx - t->half, t->cy - t->half, t->cz - t->half},
                     {t->cx + t->half, t->cy + t->half, t->cz + t->half}};
        /* The root test is p ≤ centre + h (closed); p < the next float up says the same. */
        for (int a = 0; a < 3; ++a) {
            root.hi[a] = nextafterf(root.hi[a], INFINITY);
            f->root_lo[a] = root.lo[a];
            f->root_hi[a] = root.hi[a];
        }
        f->node_count = 1;
        rc = build_node(&b, 0, 0, &root, 0, 0);
    }
    free(b.active);
    if (rc != IC_OK) {
        ic_frozen_free(f);
        return rc;
    }
    /* Give back what the doubling and the worst-case reservations did not use. */
    uint64_t *l = realloc(f->list, (f->list_len ? f->list_len : 1) * sizeof *l);
    if (l)
        f->list = l;
    f->has_root = 1;
    f->is_valid = 1;
    return IC_OK;
}
