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
 * The cache's threads build it (c->params.threads) in two passes. The walk finds the nodes, the
 * leaves' cells and their entries (record numbers): the top of the tree on the calling thread, the
 * subtrees below it as tasks of their own, in parallel. Then, from the sizes found, every part's place
 * in the layout, and the lists are written part by part in parallel, straight into their place (no
 * copy, no spare capacity). Where the work is split depends on the tree alone, so the layout — lists,
 * node numbers, leaf numbers, offsets — is the same for any thread count, and every list is the one a
 * depth-first walk finds.
 *
 * Building allocates; look-ups on the layout allocate nothing.
 */
#include "cache_store.h"

#include "core/grow.h"
#include "core/threads.h"

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

typedef ic_octree_cell cell; /* octree.h */

/* The largest subtrees of at most 1/TASK_SHARE of the tree's nodes are the tasks. By size rather
 * than by depth, as octrees of scenes are lopsided (Sponza's at 640×360, at depth 3: 16 subtrees, four
 * of them holding 3/4 of the nodes): every task is small next to a thread's share of the work on any
 * number of cores, while the top of the tree left to the calling thread stays small (Sponza's: 383 of
 * 37713 nodes, in 482 tasks). A constant, so that the layout never depends on the thread count. */
enum { TASK_SHARE = 128 };

/* Trees of fewer nodes are frozen on the calling thread (the same parts, the same layout): starting
 * threads would cost more than the build. */
enum { PARALLEL_MIN_NODES = 1024 };

/* A leaf the walk found: its cell, its entries (the part's record[first, first + count)) and the
 * offset of its header from the start of the part's lists. */
typedef struct leaf_plan {
    float lo[3], hi[3];
    uint32_t count;
    size_t first;
    size_t at;
} leaf_plan;

/* A subtree walked on its own: the top of the tree (the root's part), or a task, rooted at
 * octree node tn with cell cl, whose slot in the layout is node[fpos] and whose ancestors' surviving
 * entries are the builder's inputs[in_begin, in_end). The part numbers its nodes from 0 (node[0]: its
 * root; a leaf: IC_FROZEN_LEAF | its number in `leaf`) and its leaves and lists from 0; the bases say
 * where they go in the layout. */
typedef struct part {
    uint32_t tn, fpos;
    cell cl;
    size_t in_begin, in_end;
    uint32_t *node;
    uint32_t node_count;
    size_t node_cap;
    leaf_plan *leaf;
    uint32_t leaf_count;
    size_t leaf_cap;
    uint32_t *record;            /* the leaves' entries, leaf after leaf */
    size_t record_len, record_cap;
    size_t list_len;             /* units its lists take */
    uint32_t node_base;          /* node n ≥ 1 of the part is node_base + n of the layout */
    uint32_t leaf_base;
    size_t list_base;
    ic_result rc;
} part;

typedef struct builder {
    const ic_cache *c;
    part *p;                     /* the part being walked */
    entry *active;               /* a stack of lists, one per level of the current path */
    size_t active_cap;
    const uint32_t *size;        /* the root's part: nodes in each octree node's subtree; else NULL */
    uint32_t task_nodes;         /* subtrees of at most this many nodes become tasks */
    part *tasks;                 /* in the walk's order */
    size_t task_count, task_cap;
    entry *inputs;               /* the tasks' incoming entries, one run each */
    size_t input_len, input_cap;
} builder;



static ic_result reserve_active(builder *b, size_t n)
{
    void *a = b->active;
    ic_result rc = ic_grow(&a, &b->active_cap, n, sizeof *b->active);
    b->active = a;
    return rc;
}

/* Units a leaf with `count` entries takes in the list: its header and its blocks. */
static size_t leaf_units(uint32_t count)
{
    size_t blocks = ((size_t)count + IC_FROZEN_LANES - 1) / IC_FROZEN_LANES;
    return (sizeof(ic_frozen_leaf) + blocks * sizeof(ic_frozen_block)) / 8;
}

/* The list [begin, end) of b->active becomes the list of a leaf at node[fpos] of the part. */
static ic_result plan_leaf(builder *b, uint32_t fpos, const cell *cl, size_t begin, size_t end)
{
    part *p = b->p;
    uint32_t count = (uint32_t)(end - begin);
    void *leaf = p->leaf, *record = p->record;
    ic_result rc = ic_grow(&leaf, &p->leaf_cap, (size_t)p->leaf_count + 1, sizeof *p->leaf);
    p->leaf = leaf;
    if (rc == IC_OK)
        rc = ic_grow(&record, &p->record_cap, p->record_len + count, sizeof *p->record);
    p->record = record;
    if (rc != IC_OK)
        return IC_ERR_OOM;
    leaf_plan *l = &p->leaf[p->leaf_count];
    memcpy(l->lo, cl->lo, sizeof l->lo);
    memcpy(l->hi, cl->hi, sizeof l->hi);
    l->count = count;
    l->first = p->record_len;
    l->at = p->list_len;
    for (size_t k = begin; k < end; ++k)
        p->record[p->record_len++] = b->active[k].record;
    p->list_len += leaf_units(count);
    p->node[fpos] = IC_FROZEN_LEAF | p->leaf_count++;
    return IC_OK;
}

/* Writes the header and blocks of the leaf l plans, numbered id, with entries record[0, l->count), at
 * `leaf`. */
static void write_leaf(const ic_cache *c, ic_frozen_leaf *leaf, const leaf_plan *l, const uint32_t *record,
                       uint32_t id)
{
    uint32_t count = l->count, blocks = (count + IC_FROZEN_LANES - 1) / IC_FROZEN_LANES;
    ic_frozen_block *blk = (ic_frozen_block *)(leaf + 1);
    memcpy(leaf->lo, l->lo, sizeof leaf->lo);
    memcpy(leaf->hi, l->hi, sizeof leaf->hi);
    leaf->count = count;
    leaf->id = id;
    leaf->all_eligible = count ? 1u + c->cold[record[0]].bounce : 0u;
    leaf->unused = 0;
    memset(blk, 0, blocks * sizeof *blk); /* padding lanes: all zero, no distance passes */
    for (uint32_t k = 0; k < count; ++k) {
        uint32_t i = record[k], lane = k % IC_FROZEN_LANES;
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
}

/* Copies the entries of b->active[begin, end) that reach cell cl to the top of the stack, in order;
 * returns the new top. The caller has reserved room. */
static size_t filter(builder *b, const cell *cl, size_t begin, size_t end, size_t top)
{
    for (size_t k = begin; k < end; ++k) {
        entry e = b->active[k];
        if (ic_octree_cell_dist2(cl, e.x, e.y, e.z) <= e.r2)
            b->active[top++] = e;
    }
    return top;
}

/* Records the subtree at octree node tn as a task, with a copy of its incoming entries
 * b->active[begin, end); its slot stays 0 until the layout is written. */
static ic_result add_task(builder *b, uint32_t tn, uint32_t fpos, const cell *cl, size_t begin, size_t end)
{
    void *tasks = b->tasks, *inputs = b->inputs;
    ic_result rc = ic_grow(&tasks, &b->task_cap, b->task_count + 1, sizeof *b->tasks);
    b->tasks = tasks;
    if (rc == IC_OK)
        rc = ic_grow(&inputs, &b->input_cap, b->input_len + (end - begin), sizeof *b->inputs);
    b->inputs = inputs;
    if (rc != IC_OK)
        return IC_ERR_OOM;
    if (end > begin)
        memcpy(b->inputs + b->input_len, b->active + begin, (end - begin) * sizeof *b->active);
    part *t = &b->tasks[b->task_count++];
    memset(t, 0, sizeof *t);
    t->tn = tn;
    t->fpos = fpos;
    t->cl = *cl;
    t->in_begin = b->input_len;
    t->in_end = b->input_len += end - begin;
    b->p->node[fpos] = 0;
    return IC_OK;
}

/* Octree node tn with cell cl goes to node[fpos] of the part; its ancestors' surviving
 * entries are b->active[parent_begin, parent_end). Depth-first, children in octant order. (Splitting
 * cells below the octree's leaves to shorten the lists was tried: one level halved the lists of the
 * 300k-record benchmark but tripled the entries and ran slower; see BENCHMARKS.md "Cache library".) */
static ic_result build_node(builder *b, uint32_t tn, uint32_t fpos, const cell *cl, size_t parent_begin,
                            size_t parent_end)
{
    const ic_cache *c = b->c;
    const ic_octree_node node = c->tree.nodes[tn];
    if (b->size && tn && node.child && b->size[tn] <= b->task_nodes)
        return add_task(b, tn, fpos, cl, parent_begin, parent_end);
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
        if (ic_octree_cell_dist2(cl, e.x, e.y, e.z) <= e.r2)
            b->active[end++] = e;
    }
    if (!node.child)
        return plan_leaf(b, fpos, cl, parent_end, end);
    /* The frozen tree has the octree's shape, 8 contiguous children a node. */
    part *p = b->p;
    void *nodes = p->node;
    if (ic_grow(&nodes, &p->node_cap, (size_t)p->node_count + 8, sizeof *p->node) != IC_OK)
        return IC_ERR_OOM;
    p->node = nodes;
    uint32_t first = p->node_count;
    p->node_count += 8;
    p->node[fpos] = first;
    for (unsigned o = 0; o < 8; ++o) {
        cell cc = ic_octree_child_cell(cl, o);
        ic_result rc = build_node(b, node.child + o, first + o, &cc, parent_end, end);
        if (rc != IC_OK)
            return rc;
    }
    return IC_OK;
}

/* Walks part p from its root with the incoming entries in[0, n); a task's node and leaf arrays are
 * sized to its subtree of `nodes` nodes from the start (and none of its arrays is left NULL). */
static ic_result walk_part(builder *b, part *p, const entry *in, size_t n, uint32_t nodes)
{
    b->p = p;
    void *node = p->node, *leaf = p->leaf, *record = p->record;
    ic_result rc = ic_grow(&node, &p->node_cap, nodes, sizeof *p->node);
    p->node = node;
    if (rc == IC_OK)
        rc = ic_grow(&leaf, &p->leaf_cap, 1u + (nodes - 1u) / 8u * 7u, sizeof *p->leaf);
    p->leaf = leaf;
    if (rc == IC_OK)
        rc = ic_grow(&record, &p->record_cap, 1, sizeof *p->record);
    p->record = record;
    if (rc == IC_OK)
        rc = reserve_active(b, n);
    if (rc != IC_OK)
        return IC_ERR_OOM;
    if (n)
        memcpy(b->active, in, n * sizeof *b->active);
    p->node_count = 1;
    return build_node(b, p->tn, 0, &p->cl, 0, n);
}

/* size[n] = the nodes of node n's subtree, for every node below n; returns size[n]. */
static uint32_t subtree_sizes(const ic_octree *t, uint32_t n, uint32_t *size)
{
    uint32_t s = 1, child = t->nodes[n].child;
    if (child)
        for (unsigned o = 0; o < 8; ++o)
            s += subtree_sizes(t, child + o, size);
    return size[n] = s;
}

static void free_part(part *p)
{
    free(p->node);
    free(p->leaf);
    free(p->record);
}

/* The parts: the root's, then the tasks in the walk's order. */
typedef struct parts {
    const ic_cache *c;
    ic_frozen *f;
    part *root;
    part *tasks;
    const entry *inputs;
    const uint32_t *size;
} parts;

static part *part_at(const parts *ps, int64_t item) { return item ? &ps->tasks[item - 1] : ps->root; }

/* Pass 1: task `item` walks its subtree, with a stack of its own. */
static void walk_task(void *ctx, int64_t item, int thread)
{
    (void)thread;
    const parts *ps = ctx;
    part *t = &ps->tasks[item];
    builder b = {ps->c, t, NULL, 0, NULL, 0, NULL, 0, 0, NULL, 0, 0};
    size_t n = t->in_end - t->in_begin;
    t->rc = walk_part(&b, t, n ? ps->inputs + t->in_begin : NULL, n, ps->size[t->tn]);
    free(b.active);
}

/* The layout's value of node value v of part p. */
static uint32_t place(const part *p, uint32_t v)
{
    if (v & IC_FROZEN_LEAF)
        return IC_FROZEN_LEAF | (uint32_t)(p->list_base + p->leaf[v & ~IC_FROZEN_LEAF].at);
    return v + p->node_base;
}

/* Pass 2: part `item` writes its nodes (but its root's slot), leaves and lists into the layout. The
 * parts' places do not overlap: any order, any thread. */
static void write_part(void *ctx, int64_t item, int thread)
{
    (void)thread;
    const parts *ps = ctx;
    const part *p = part_at(ps, item);
    ic_frozen *f = ps->f;
    for (uint32_t n = 1; n < p->node_count; ++n)
        f->node[p->node_base + n] = place(p, p->node[n]);
    for (uint32_t l = 0; l < p->leaf_count; ++l) {
        size_t at = p->list_base + p->leaf[l].at;
        f->leaf_at[p->leaf_base + l] = (uint32_t)at;
        write_leaf(ps->c, (ic_frozen_leaf *)(f->list + at), &p->leaf[l], p->record + p->leaf[l].first,
                   p->leaf_base + l);
    }
}

/* Places the parts one after the other, in order, and sizes the layout's arrays to them. */
static ic_result place_parts(const parts *ps, size_t count)
{
    ic_frozen *f = ps->f;
    uint32_t node_end = 1, leaf_end = 0;
    size_t list_end = 0;
    for (size_t k = 0; k < count; ++k) {
        part *p = part_at(ps, (int64_t)k);
        if (p->rc != IC_OK)
            return IC_ERR_OOM;
        p->node_base = node_end - 1u;
        p->leaf_base = leaf_end;
        p->list_base = list_end;
        /* Leaves are addressed by 31-bit offsets (16 GiB of lists); a part's are in ascending order. */
        if (p->leaf_count && list_end + p->leaf[p->leaf_count - 1].at >= IC_FROZEN_LEAF)
            return IC_ERR_OOM;
        node_end += p->node_count - 1u;
        leaf_end += p->leaf_count;
        list_end += p->list_len;
        f->entry_count += p->record_len;
    }
    f->node_count = node_end;
    f->leaf_count = leaf_end;
    f->list_len = list_end;
    f->list = malloc((list_end ? list_end : 1) * sizeof *f->list);
    f->leaf_at = malloc((leaf_end ? (size_t)leaf_end : 1) * sizeof *f->leaf_at);
    return f->list && f->leaf_at ? IC_OK : IC_ERR_OOM;
}

/* ic_parallel_for, or this thread alone where no thread could be started: the items write their own
 * places, so the outcome is the same. */
static void run_items(int threads, int64_t count, ic_parallel_fn fn, void *ctx)
{
    if (ic_parallel_for(threads, count, fn, ctx) != IC_OK)
        for (int64_t i = 0; i < count; ++i)
            fn(ctx, i, 0);
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
    f->cx = t->cx;
    f->cy = t->cy;
    f->cz = t->cz;
    f->half = t->half;
    part root = {0};
    root.cl = ic_octree_root_cell(t->cx, t->cy, t->cz, t->half);
    /* The root test is p ≤ centre + h (closed); p < the next float up says the same. */
    for (int a = 0; a < 3; ++a) {
        root.cl.hi[a] = nextafterf(root.cl.hi[a], INFINITY);
        f->root_lo[a] = root.cl.lo[a];
        f->root_hi[a] = root.cl.hi[a];
    }
    /* The top of the tree, collecting the tasks. */
    uint32_t *size = malloc((size_t)t->node_count * sizeof *size);
    builder b = {c, &root, NULL, 0, size, t->node_count / TASK_SHARE, NULL, 0, 0, NULL, 0, 0};
    ic_result rc = size ? IC_OK : IC_ERR_OOM;
    if (rc == IC_OK) {
        subtree_sizes(t, 0, size);
        rc = walk_part(&b, &root, NULL, 0, 1);
    }
    free(b.active);
    parts ps = {c, f, &root, b.tasks, b.inputs, size};
    int threads = t->node_count < PARALLEL_MIN_NODES ? 1 : c->params.threads;
    if (rc == IC_OK) {
        run_items(threads, (int64_t)b.task_count, walk_task, &ps);
        f->node = malloc((size_t)t->node_count * sizeof *f->node);
        rc = f->node ? place_parts(&ps, b.task_count + 1) : IC_ERR_OOM;
    }
    if (rc == IC_OK) {
        run_items(threads, (int64_t)b.task_count + 1, write_part, &ps);
        for (size_t k = 0; k <= b.task_count; ++k) {
            const part *p = part_at(&ps, (int64_t)k);
            f->node[p->fpos] = place(p, p->node[0]);
        }
    }
    free_part(&root);
    for (size_t k = 0; k < b.task_count; ++k)
        free_part(&b.tasks[k]);
    free(b.tasks);
    free(b.inputs);
    free(size);
    if (rc != IC_OK) {
        ic_frozen_free(f);
        return rc;
    }
    f->has_root = 1;
    f->is_valid = 1;
    return IC_OK;
}
