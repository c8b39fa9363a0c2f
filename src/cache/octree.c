/*
 * octree.c — flat multiple-reference octree and point octree (octree.h; Frolov et al. 2012 §4.2–4.3).
 *
 * Insertion walks every leaf a sphere overlaps with an explicit fixed-size stack; a point (radius 0)
 * goes to exactly one leaf, chosen by the same octant rule as the look-up descent, so k-nearest and
 * radius queries never see an item twice. A build is top-down, its subtrees on threads, and gives
 * every segment exact capacity. Queries allocate nothing.
 */
#include "octree.h"

#include "core/grow.h"
#include "core/morton.h"
#include "core/select.h"
#include "core/threads.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define STACK_SIZE (8 * (IC_OCTREE_MAX_DEPTH + 2))

/* A node's cube and cell (octree.h): overlap is tested against the cell, the exact set of points
 * the look-up descent sends into the node, never a cube rebuilt from its rounded centre. */
typedef ic_octree_cell cube;

static float item_radius(const ic_octree_items *it, uint32_t i) { return ic_octree_item_radius(it, i); }

static cube child_cube(cube c, unsigned octant) { return ic_octree_child_cell(&c, octant); }

/* The 8 children's cubes, computed once for a node whose items are handed down. */
static void child_cubes(cube c, cube kids[8])
{
    for (unsigned o = 0; o < 8; ++o)
        kids[o] = ic_octree_child_cell(&c, o);
}

static unsigned point_octant(cube c, float x, float y, float z)
{
    return (unsigned)(x >= c.cx) | (unsigned)(y >= c.cy) << 1 | (unsigned)(z >= c.cz) << 2;
}

/* Squared distance from p to the closed cell (0 inside). */
static float cube_dist2(cube c, float x, float y, float z) { return ic_octree_cell_dist2(&c, x, y, z); }

/* Squared distances from (x, y, z) to the cells of c's 8 children, bit for bit what
 * ic_octree_cell_dist2 gives for each child (the same per-axis terms, summed in the same order), at
 * the cost of one cell. */
static void child_dist2(const cube *c, float x, float y, float z, float d2[8])
{
    float p[3] = {x, y, z}, centre[3] = {c->cx, c->cy, c->cz}, sq[3][2];
    for (int a = 0; a < 3; ++a) {
        float lo[2] = {c->lo[a], centre[a] > c->lo[a] ? centre[a] : c->lo[a]};
        float hi[2] = {centre[a] < c->hi[a] ? centre[a] : c->hi[a], c->hi[a]};
        for (int u = 0; u < 2; ++u) {
            float below = lo[u] - p[a], above = p[a] - hi[u];
            float e = below > 0.0f ? below : (above > 0.0f ? above : 0.0f);
            sq[a][u] = e * e;
        }
    }
    for (unsigned o = 0; o < 8; ++o)
        d2[o] = sq[0][o & 1] + sq[1][(o >> 1) & 1] + sq[2][(o >> 2) & 1];
}

/* Does item i belong in child `octant` (cube kids[octant]) of `parent`? Points by octant, spheres by
 * closed overlap. */
static int item_in_child(const ic_octree_items *it, uint32_t i, float r, const cube *parent, const cube kids[8],
                         unsigned octant)
{
    const ic_float4 *s = &it->sphere[i];
    if (r <= 0.0f)
        return point_octant(*parent, s->x, s->y, s->z) == octant;
    return cube_dist2(kids[octant], s->x, s->y, s->z) <= r * r;
}

/* The children of c item i belongs in (item_in_child's answers), one bit an octant. */
static unsigned child_mask(const ic_octree_items *it, uint32_t i, float r, const cube *c)
{
    const ic_float4 *s = &it->sphere[i];
    if (r <= 0.0f)
        return 1u << point_octant(*c, s->x, s->y, s->z);
    float d2[8];
    child_dist2(c, s->x, s->y, s->z, d2);
    unsigned m = 0;
    for (unsigned o = 0; o < 8; ++o)
        m |= (unsigned)(d2[o] <= r * r) << o;
    return m;
}

static ic_octree_ref make_ref(const ic_octree_items *it, uint32_t i, float r)
{
    const ic_float4 *s = &it->sphere[i];
    ic_octree_ref ref = {s->x, s->y, s->z, r, i};
    return ref;
}

/* A sphere stays at a node whose half side is at most its radius (cache.h: octree). */
static int stays_at(float r, float h) { return r > 0.0f && h <= r; }

void ic_octree_init(ic_octree *t, uint32_t leaf_capacity, uint32_t max_depth)
{
    memset(t, 0, sizeof *t);
    t->leaf_capacity = leaf_capacity ? leaf_capacity : 1;
    t->max_depth = max_depth > IC_OCTREE_MAX_DEPTH ? IC_OCTREE_MAX_DEPTH : max_depth;
}

void ic_octree_free(ic_octree *t)
{
    free(t->nodes);
    free(t->refs);
    t->nodes = NULL;
    t->refs = NULL;
    t->node_count = t->node_cap = 0;
    t->ref_end = t->ref_cap = t->ref_live = 0;
    t->has_root = 0;
}

size_t ic_octree_bytes(const ic_octree *t)
{
    return (size_t)t->node_cap * sizeof(ic_octree_node) + t->ref_cap * sizeof(ic_octree_ref);
}

static ic_result reserve_refs(ic_octree *t, size_t extra)
{
    if (t->ref_end + extra <= t->ref_cap)
        return IC_OK;
    size_t cap = t->ref_cap ? t->ref_cap : 1024;
    while (cap < t->ref_end + extra)
        cap *= 2;
    ic_octree_ref *r = realloc(t->refs, cap * sizeof *r);
    if (!r)
        return IC_ERR_OOM;
    t->refs = r;
    t->ref_cap = cap;
    return IC_OK;
}

/* Appends 8 leaf nodes; returns the index of the first in *first. */
static ic_result add_children(ic_octree *t, uint32_t *first)
{
    if (t->node_count + 8 > t->node_cap) {
        uint32_t cap = t->node_cap ? t->node_cap * 2 : 64;
        ic_octree_node *n = realloc(t->nodes, (size_t)cap * sizeof *n);
        if (!n)
            return IC_ERR_OOM;
        t->nodes = n;
        t->node_cap = cap;
    }
    *first = t->node_count;
    memset(&t->nodes[t->node_count], 0, 8 * sizeof(ic_octree_node));
    t->node_count += 8;
    return IC_OK;
}

/* Splits leaf `node` (cube c, depth d) if that helps, recursively. References to spheres at least
 * as large as a child stay in the node; the others move to the children they overlap. */
static ic_result maybe_split(ic_octree *t, const ic_octree_items *it, uint32_t node, cube c, uint32_t depth)
{
    ic_octree_node leaf = t->nodes[node];
    if (leaf.child || leaf.count <= t->leaf_capacity || depth >= t->max_depth)
        return IC_OK;
    float hc = 0.5f * c.h;
    cube kids[8];
    child_cubes(c, kids);
    uint32_t counts[8] = {0}, down = 0;
    for (uint32_t k = 0; k < leaf.count; ++k) {
        uint32_t i = t->refs[leaf.begin + k].index;
        float r = item_radius(it, i);
        if (stays_at(r, hc))
            continue;
        ++down;
        unsigned m = child_mask(it, i, r, &c);
        for (unsigned o = 0; o < 8; ++o)
            counts[o] += (m >> o) & 1;
    }
    /* Nothing would move down: the leaf is full of spheres as large as its children. */
    if (down == 0)
        return IC_OK;
    size_t need = 0;
    uint32_t caps[8];
    for (unsigned o = 0; o < 8; ++o) {
        caps[o] = counts[o] < 4 ? 4 : counts[o];
        need += caps[o];
    }
    ic_result rc = reserve_refs(t, need);
    uint32_t first = 0;
    if (rc == IC_OK)
        rc = add_children(t, &first);
    if (rc != IC_OK)
        return rc;
    for (unsigned o = 0; o < 8; ++o) {
        ic_octree_node *ch = &t->nodes[first + o];
        ch->begin = (uint32_t)t->ref_end;
        ch->cap = caps[o];
        t->ref_end += caps[o];
        t->ref_live += caps[o];
    }
    uint32_t kept = 0;
    for (uint32_t k = 0; k < leaf.count; ++k) {
        uint32_t i = t->refs[leaf.begin + k].index;
        float r = item_radius(it, i);
        if (stays_at(r, hc)) {
            t->refs[leaf.begin + kept++] = make_ref(it, i, r); /* compacted in place, order kept */
            continue;
        }
        unsigned m = child_mask(it, i, r, &c);
        for (unsigned o = 0; o < 8; ++o)
            if ((m >> o) & 1) {
                ic_octree_node *ch = &t->nodes[first + o];
                t->refs[ch->begin + ch->count++] = make_ref(it, i, r);
            }
    }
    t->nodes[node].child = first;
    t->nodes[node].count = kept;
    for (unsigned o = 0; o < 8; ++o) {
        rc = maybe_split(t, it, first + o, kids[o], depth + 1);
        if (rc != IC_OK)
            return rc;
    }
    return IC_OK;
}

static ic_result leaf_append(ic_octree *t, uint32_t node, ic_octree_ref item)
{
    ic_octree_node *n = &t->nodes[node];
    if (n->count == n->cap) {
        /* Move the segment to the end of refs with twice the room; the old one becomes dead. */
        uint32_t cap = n->cap ? n->cap * 2 : 4;
        ic_result rc = reserve_refs(t, cap);
        if (rc != IC_OK)
            return rc;
        n = &t->nodes[node];
        memcpy(&t->refs[t->ref_end], &t->refs[n->begin], (size_t)n->count * sizeof(ic_octree_ref));
        t->ref_live += cap - n->cap;
        n->begin = (uint32_t)t->ref_end;
        n->cap = cap;
        t->ref_end += cap;
    }
    t->refs[n->begin + n->count++] = item;
    return IC_OK;
}

static int root_contains(const ic_octree *t, const ic_octree_items *it, uint32_t i)
{
    const ic_float4 *s = &it->sphere[i];
    float r = item_radius(it, i);
    float h = t->half;
    return s->x - r >= t->cx - h && s->x + r <= t->cx + h && s->y - r >= t->cy - h && s->y + r <= t->cy + h &&
           s->z - r >= t->cz - h && s->z + r <= t->cz + h;
}

/* Cube around the bounds of items 0…count−1, padded ×2 so a growing cache rebuilds rarely. */
static cube fit_root(const ic_octree_items *it, uint32_t count)
{
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = 0; i < count; ++i) {
        const ic_float4 *s = &it->sphere[i];
        float r = item_radius(it, i), p[3] = {s->x, s->y, s->z};
        for (int a = 0; a < 3; ++a) {
            lo[a] = fminf(lo[a], p[a] - r);
            hi[a] = fmaxf(hi[a], p[a] + r);
        }
    }
    float cx = 0.5f * (lo[0] + hi[0]), cy = 0.5f * (lo[1] + hi[1]), cz = 0.5f * (lo[2] + hi[2]);
    float ext = fmaxf(hi[0] - lo[0], fmaxf(hi[1] - lo[1], hi[2] - lo[2]));
    float mag = fmaxf(fabsf(cx), fmaxf(fabsf(cy), fabsf(cz)));
    /* Never a degenerate cube: at least a relative 1e-4 of the coordinates' magnitude. */
    return ic_octree_root_cell(cx, cy, cz, fmaxf(ext, 1e-4f * (1.0f + mag)));
}

static ic_result insert_item(ic_octree *t, const ic_octree_items *it, uint32_t index)
{
    struct entry {
        cube c;
        uint32_t node, depth;
    } stack[STACK_SIZE];
    int top = 0;
    float r = item_radius(it, index);
    const ic_float4 *s = &it->sphere[index];
    stack[top++] = (struct entry){ic_octree_root_cell(t->cx, t->cy, t->cz, t->half), 0, 0};
    while (top > 0) {
        struct entry e = stack[--top];
        uint32_t child = t->nodes[e.node].child;
        if (child && !stays_at(r, e.c.h)) {
            if (r <= 0.0f) {
                unsigned o = point_octant(e.c, s->x, s->y, s->z);
                stack[top++] = (struct entry){child_cube(e.c, o), child + o, e.depth + 1};
                continue;
            }
            float d2[8];
            child_dist2(&e.c, s->x, s->y, s->z, d2);
            for (unsigned o = 0; o < 8; ++o)
                if (d2[o] <= r * r)
                    stack[top++] = (struct entry){child_cube(e.c, o), child + o, e.depth + 1};
            continue;
        }
        ic_result rc = leaf_append(t, e.node, make_ref(it, index, r));
        if (rc == IC_OK)
            rc = maybe_split(t, it, e.node, e.c, e.depth);
        if (rc != IC_OK)
            return rc;
    }
    return IC_OK;
}


/* Building top-down. A node of the build takes the items that reach it (in Morton order); it stays a
 * leaf holding them all when they fit, the depth limit is reached or none is smaller than a child, as
 * insertion's split rule says (maybe_split); otherwise it keeps the spheres as large as a child and
 * hands each other item to every child it overlaps. Below TASK_DEPTH every node that splits is a task
 * built on its own arrays, on any thread; the tasks are appended in their fixed order, so the tree
 * does not depend on the thread count. */
#define TASK_DEPTH 2
#define PARALLEL_MIN_ITEMS 4096

typedef struct part {
    ic_octree_node *nodes;
    uint32_t node_count, node_cap;
    ic_octree_ref *refs;
    size_t ref_count, ref_cap;
    uint32_t *list; /* a stack of item lists, one per level of the current path */
    size_t list_len, list_cap;
} part;

typedef struct task {
    uint32_t slot, depth, count; /* the node's place in the top part; its items */
    cube c;
    uint32_t *items;
    part p;                       /* its subtree; local node 0 is the task's node */
    ic_result rc;
} task;

typedef struct builder {
    const ic_octree *t;
    const ic_octree_items *it;
    const float *radius;          /* item_radius of every item */
    task *tasks;                  /* the top part's tasks (NULL inside a task) */
    uint32_t task_count, task_cap;
} builder;

static void part_free(part *p)
{
    free(p->nodes);
    free(p->refs);
    free(p->list);
    memset(p, 0, sizeof *p);
}


static int part_reserve(part *p, uint32_t nodes, size_t refs, size_t list)
{
    size_t node_cap = p->node_cap;
    void *n = p->nodes, *r = p->refs, *l = p->list;
    int ok = ic_grow(&n, &node_cap, (size_t)p->node_count + nodes, sizeof *p->nodes) == IC_OK;
    p->nodes = n;
    p->node_cap = (uint32_t)node_cap;
    ok = ok && ic_grow(&r, &p->ref_cap, p->ref_count + refs, sizeof *p->refs) == IC_OK;
    p->refs = r;
    ok = ok && ic_grow(&l, &p->list_cap, p->list_len + list, sizeof *p->list) == IC_OK;
    p->list = l;
    return ok;
}

/* Node `slot` of part p, cube c at `depth`, takes the items p->list[begin, end). */
static ic_result build_node(builder *b, part *p, uint32_t slot, cube c, uint32_t depth, size_t begin, size_t end)
{
    const ic_octree *t = b->t;
    const uint32_t n = (uint32_t)(end - begin);
    const float hc = 0.5f * c.h;
    uint32_t down = 0;
    if (n > t->leaf_capacity && depth < t->max_depth)
        for (size_t k = begin; k < end; ++k)
            down += !stays_at(b->radius[p->list[k]], hc);
    if (down && b->tasks && depth == TASK_DEPTH) {
        if (b->task_count == b->task_cap) {
            size_t cap = b->task_cap;
            void *a = b->tasks;
            if (ic_grow(&a, &cap, (size_t)b->task_count + 1, sizeof *b->tasks) != IC_OK)
                return IC_ERR_OOM;
            b->tasks = a;
            b->task_cap = (uint32_t)cap;
        }
        task *k = &b->tasks[b->task_count];
        memset(k, 0, sizeof *k);
        k->items = malloc((size_t)n * sizeof *k->items);
        if (!k->items)
            return IC_ERR_OOM;
        memcpy(k->items, &p->list[begin], (size_t)n * sizeof *k->items);
        k->slot = slot;
        k->depth = depth;
        k->count = n;
        k->c = c;
        ++b->task_count;
        return IC_OK;
    }
    /* The node's own references: all items of a leaf, the spheres as large as a child otherwise. */
    if (!part_reserve(p, down ? 8 : 0, n, down ? 8 * (size_t)down : 0))
        return IC_ERR_OOM;
    ic_octree_node *node = &p->nodes[slot];
    node->begin = (uint32_t)p->ref_count;
    for (size_t k = begin; k < end; ++k) {
        uint32_t i = p->list[k];
        if (!down || stays_at(b->radius[i], hc))
            p->refs[p->ref_count++] = make_ref(b->it, i, b->radius[i]);
    }
    node->count = node->cap = (uint32_t)(p->ref_count - node->begin);
    node->child = 0;
    if (!down)
        return IC_OK;
    const uint32_t first = p->node_count;
    p->node_count += 8;
    node->child = first;
    cube kids[8];
    child_cubes(c, kids);
    size_t at[9];
    for (unsigned o = 0; o < 8; ++o) {
        at[o] = p->list_len;
        /* Room for every item in this child: the reservation above covered 8 × down in all. */
        for (size_t k = begin; k < end; ++k) {
            uint32_t i = p->list[k];
            float r = b->radius[i];
            if (!stays_at(r, hc) && item_in_child(b->it, i, r, &c, kids, o))
                p->list[p->list_len++] = i;
        }
    }
    at[8] = p->list_len;
    for (unsigned o = 0; o < 8; ++o) {
        ic_result rc = build_node(b, p, first + o, kids[o], depth + 1, at[o], at[o + 1]);
        if (rc != IC_OK)
            return rc;
    }
    p->list_len = at[0];
    return IC_OK;
}

static void run_task(void *ctx, int64_t k, int thread)
{
    (void)thread;
    builder b = *(const builder *)ctx;
    task *tk = &b.tasks[k];
    b.tasks = NULL;
    part *p = &tk->p;
    tk->rc = IC_ERR_OOM;
    if (!part_reserve(p, 1, 0, tk->count))
        return;
    p->node_count = 1;
    memcpy(p->list, tk->items, (size_t)tk->count * sizeof *p->list);
    p->list_len = tk->count;
    tk->rc = build_node(&b, p, 0, tk->c, tk->depth, 0, tk->count);
}

/* Appends task k's subtree to the top part: its node 0 goes to its slot, the others after the top
 * part's nodes, children and segments shifted. */
static ic_result append_task(part *top, const task *k)
{
    const part *s = &k->p;
    if (!part_reserve(top, s->node_count - 1, s->ref_count, 0))
        return IC_ERR_OOM;
    const uint32_t node_base = top->node_count - 1;
    const size_t ref_base = top->ref_count;
    for (uint32_t j = 0; j < s->node_count; ++j) {
        ic_octree_node nd = s->nodes[j];
        nd.begin += (uint32_t)ref_base;
        if (nd.child)
            nd.child += node_base;
        top->nodes[j ? node_base + j : k->slot] = nd;
    }
    top->node_count += s->node_count - 1;
    memcpy(&top->refs[ref_base], s->refs, s->ref_count * sizeof *s->refs);
    top->ref_count += s->ref_count;
    return IC_OK;
}

ic_result ic_octree_build(ic_octree *t, const ic_octree_items *items, uint32_t count)
{
    if (count == 0) {
        t->node_count = 0;
        t->ref_end = t->ref_live = 0;
        t->has_root = 0;
        return IC_OK;
    }
    cube root = fit_root(items, count);
    /* A safety net (the cache refuses such records, IC_CACHE_MAX_COORD): bounds beyond float would make
     * every child test NaN, an overlap, and the tree would grow without end. */
    int finite = isfinite(root.h);
    for (int a = 0; a < 3; ++a)
        finite = finite && isfinite(root.lo[a]) && isfinite(root.hi[a]);
    if (!finite)
        return IC_ERR_INVALID_ARG;
    /* Items in Morton order (ties by index: deterministic), so nodes and reference segments that are
     * close in space end up close in memory — a look-up's descent then misses the processor caches
     * less — and every node's references keep that order. */
    ic_key_index *order = malloc((size_t)count * sizeof *order), *spare = malloc((size_t)count * sizeof *spare);
    float *radius = malloc((size_t)count * sizeof *radius);
    builder b = {t, items, radius, NULL, 0, 0};
    part top = {0};
    ic_result rc = order && spare && radius && part_reserve(&top, 1, 0, count) ? IC_OK : IC_ERR_OOM;
    if (rc == IC_OK) {
        float scale = 1023.0f / (2.0f * root.h);
        for (uint32_t i = 0; i < count; ++i) {
            const ic_float4 *s = &items->sphere[i];
            float u[3] = {(s->x - (root.cx - root.h)) * scale, (s->y - (root.cy - root.h)) * scale,
                          (s->z - (root.cz - root.h)) * scale};
            uint32_t q[3];
            for (int a = 0; a < 3; ++a)
                q[a] = u[a] <= 0.0f ? 0u : (u[a] >= 1023.0f ? 1023u : (uint32_t)u[a]);
            order[i] = (ic_key_index){ic_morton3_cells(q[0], q[1], q[2]), i};
            radius[i] = item_radius(items, i);
        }
        /* stable, and the items are in index order: ties stay in index order */
        const ic_key_index *sorted = ic_sort_key_index(order, spare, count);
        for (uint32_t k = 0; k < count; ++k)
            top.list[k] = sorted[k].index;
        top.list_len = count;
        top.node_count = 1;
        b.tasks = malloc(8 * sizeof *b.tasks);
        b.task_cap = 8;
        rc = b.tasks ? build_node(&b, &top, 0, root, 0, 0, count) : IC_ERR_OOM;
    }
    /* Threads that cannot be started ran nothing: the tasks then run on this one. */
    const int threads = count >= PARALLEL_MIN_ITEMS ? t->threads : 1;
    if (rc == IC_OK && ic_parallel_for(threads, b.task_count, run_task, &b) != IC_OK)
        rc = ic_parallel_for(1, b.task_count, run_task, &b);
    for (uint32_t k = 0; k < b.task_count && rc == IC_OK; ++k)
        rc = b.tasks[k].rc != IC_OK ? b.tasks[k].rc : append_task(&top, &b.tasks[k]);
    for (uint32_t k = 0; k < b.task_count; ++k) {
        free(b.tasks[k].items);
        part_free(&b.tasks[k].p);
    }
    free(b.tasks);
    free(order);
    free(spare);
    free(radius);
    if (rc != IC_OK) {
        part_free(&top);
        return rc;
    }
    free(t->nodes);
    free(t->refs);
    free(top.list);
    t->nodes = top.nodes;
    t->node_count = top.node_count;
    t->node_cap = top.node_cap;
    t->refs = top.refs;
    t->ref_end = t->ref_live = top.ref_count;
    t->ref_cap = top.ref_cap;
    t->cx = root.cx;
    t->cy = root.cy;
    t->cz = root.cz;
    t->half = root.h;
    t->has_root = 1;
    return IC_OK;
}

ic_result ic_octree_insert(ic_octree *t, const ic_octree_items *items, uint32_t index)
{
    if (!t->has_root || !root_contains(t, items, index))
        return ic_octree_build(t, items, index + 1);
    return insert_item(t, items, index);
}

void ic_octree_drop_from(ic_octree *t, uint32_t first)
{
    for (uint32_t n = 0; n < t->node_count; ++n) {
        ic_octree_node *node = &t->nodes[n];
        uint32_t kept = 0;
        for (uint32_t k = 0; k < node->count; ++k)
            if (t->refs[node->begin + k].index < first)
                t->refs[node->begin + kept++] = t->refs[node->begin + k];
        node->count = kept;
    }
}

ic_result ic_octree_compact(ic_octree *t)
{
    if (t->ref_end <= 2 * t->ref_live + 4096)
        return IC_OK;
    ic_octree_ref *fresh = malloc((t->ref_live ? t->ref_live : 1) * sizeof *fresh);
    if (!fresh)
        return IC_ERR_OOM;
    size_t end = 0;
    for (uint32_t n = 0; n < t->node_count; ++n) {
        ic_octree_node *node = &t->nodes[n];
        if (node->cap == 0)
            continue;
        memcpy(&fresh[end], &t->refs[node->begin], (size_t)node->count * sizeof *fresh);
        node->begin = (uint32_t)end;
        end += node->cap;
    }
    free(t->refs);
    t->refs = fresh;
    t->ref_end = end;
    t->ref_cap = t->ref_live ? t->ref_live : 1;
    return IC_OK;
}

/* (d², index) order: nearest first, ties by the lower index, so results never depend on layout. */
static int closer(float da, uint32_t ia, float db, uint32_t ib) { return da < db || (da == db && ia < ib); }

uint32_t ic_octree_knn(const ic_octree *t, const ic_octree_items *items, ic_vec3 p, uint32_t k, uint32_t *idx,
                       float *d2)
{
    struct entry {
        cube c;
        uint32_t node;
        float mind2;
    } stack[STACK_SIZE];
    (void)items; /* positions come from the references */
    if (!t->has_root || k == 0)
        return 0;
    uint32_t found = 0;
    int top = 0;
    cube root = ic_octree_root_cell(t->cx, t->cy, t->cz, t->half);
    stack[top++] = (struct entry){root, 0, cube_dist2(root, p.x, p.y, p.z)};
    while (top > 0) {
        struct entry e = stack[--top];
        /* Prune cells strictly farther than the current k-th (with a rounding margin). */
        if (found == k && e.mind2 > d2[k - 1] * 1.00001f)
            continue;
        const ic_octree_node *n = &t->nodes[e.node];
        if (!n->child) {
            for (uint32_t j = 0; j < n->count; ++j) {
                const ic_octree_ref *s = &t->refs[n->begin + j];
                uint32_t i = s->index;
                float d = ic_dist2(p.x, p.y, p.z, s->x, s->y, s->z);
                if (found == k && !closer(d, i, d2[k - 1], idx[k - 1]))
                    continue;
                uint32_t pos = found < k ? found++ : k - 1;
                while (pos > 0 && closer(d, i, d2[pos - 1], idx[pos - 1])) {
                    d2[pos] = d2[pos - 1];
                    idx[pos] = idx[pos - 1];
                    --pos;
                }
                d2[pos] = d;
                idx[pos] = i;
            }
            continue;
        }
        /* Push children farthest first so the nearest is explored first (octants sorted, not the
         * entries: they carry cells); an empty leaf is not pushed. */
        float d2c[8];
        child_dist2(&e.c, p.x, p.y, p.z, d2c);
        unsigned char ord[8] = {0, 1, 2, 3, 4, 5, 6, 7};
        for (unsigned a = 1; a < 8; ++a)
            for (unsigned b = a; b > 0 && d2c[ord[b]] > d2c[ord[b - 1]]; --b) {
                unsigned char tmp = ord[b];
                ord[b] = ord[b - 1];
                ord[b - 1] = tmp;
            }
        for (unsigned j = 0; j < 8; ++j) {
            unsigned o = ord[j];
            const ic_octree_node *ch = &t->nodes[n->child + o];
            if ((ch->child || ch->count) && !(found == k && d2c[o] > d2[k - 1] * 1.00001f))
                stack[top++] = (struct entry){child_cube(e.c, o), n->child + o, d2c[o]};
        }
    }
    return found;
}

uint32_t ic_octree_radius(const ic_octree *t, const ic_octree_items *items, ic_vec3 p, float radius,
                          uint32_t *idx, uint32_t capacity)
{
    struct entry {
        cube c;
        uint32_t node;
    } stack[STACK_SIZE];
    (void)items; /* positions come from the references */
    if (!t->has_root || !(radius > 0.0f))
        return 0;
    float r2 = radius * radius, prune = r2 * 1.00001f;
    uint32_t total = 0;
    int top = 0;
    stack[top++] = (struct entry){ic_octree_root_cell(t->cx, t->cy, t->cz, t->half), 0};
    while (top > 0) {
        struct entry e = stack[--top];
        const ic_octree_node *n = &t->nodes[e.node];
        if (!n->child) {
            for (uint32_t j = 0; j < n->count; ++j) {
                const ic_octree_ref *s = &t->refs[n->begin + j];
                if (ic_dist2(p.x, p.y, p.z, s->x, s->y, s->z) < r2) {
                    if (total < capacity)
                        idx[total] = s->index;
                    ++total;
                }
            }
            continue;
        }
        float d2[8];
        child_dist2(&e.c, p.x, p.y, p.z, d2);
        for (unsigned o = 0; o < 8; ++o)
            if (d2[o] <= prune)
                stack[top++] = (struct entry){child_cube(e.c, o), n->child + o};
    }
    return total;
}
