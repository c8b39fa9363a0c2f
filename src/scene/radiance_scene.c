/*
 * radiance_scene.c — Radiance scene files (.rad), the subset lighting models use (Larson & Shakespeare 1998), read
 * into irrcache's scene:
 *
 *   surfaces polygon, sphere / bubble, ring, cone / cup, cylinder / tube (tessellate.h), mesh through the
 *   OBJ file it names; modifiers by name as Radiance chains them (radiance_material.c); source as the sun
 *   (small angles), a cone of the environment of its radiance (wider), or, when a sky function of gensky or
 *   gendaylit modifies its glow, a cone of that sky (sky.h); the camera of a view file (radiance_view.c).
 *
 * Refused with a one-line error naming file:line: "!" command lines (no shell is ever run), instance
 * (compiled octrees), malformed primitives, names used before they are defined. Every other primitive
 * irrcache does not render is named in one warning per kind; nothing is dropped silently. Coordinates are
 * taken as the file gives them (Radiance has no unit). '#' starts a comment wherever a word would start.
 *
 * Surfaces are collected first and handed to the scene material by material, in the order each material
 * is first used, so a file that lists its surfaces by material gives its triangles in file order.
 */
#include "scene/radiance_internal.h"
#include "scene/tessellate.h"

#include "core/error_at.h"
#include "core/hash.h"
#include "core/read_file.h"
#include "irrcache/defaults.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Triangles collected from the file's surfaces, handed to the scene at the end. */
typedef struct geometry {
    ic_vec3 *p, *n;      /* vertices and their normals (zero: none, the face's own) */
    uint32_t vertex_count, vertex_capacity;
    uint32_t *tri, *tri_material; /* 3 vertex indices and the scene material per triangle */
    uint32_t tri_count, tri_capacity;
} geometry;

ic_result ic_rad_fail(ic_rad_ctx *c, int line, ic_result r, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    ic_result rc = ic_error_vset_at(c->err, r, c->path, line, fmt, ap);
    va_end(ap);
    return rc;
}

void ic_rad_warn_once(ic_rad_ctx *c, int line, const char *kind, const char *what)
{
    for (int i = 0; i < c->warned_count; ++i)
        if (!strcmp(c->warned[i], kind))
            return;
    if (c->warned_count < IC_RAD_MAX_WARNED)
        snprintf(c->warned[c->warned_count++], sizeof c->warned[0], "%s", kind);
    ic_scene_warn(c->b->scene, "%s:%d: %s %s", c->path, line, kind, what);
}

/* The slot of name in the table: the one that holds it, or the empty one where it would go. */
static size_t mod_slot(const ic_rad_ctx *c, const char *name)
{
    size_t mask = c->slot_count - 1, i = (size_t)ic_fnv1a64(IC_FNV64_OFFSET, name, strlen(name)) & mask;
    while (c->mod_slots[i] && strcmp(c->mods[c->mod_slots[i] - 1].name, name))
        i = (i + 1) & mask;
    return i;
}

ic_rad_modifier *ic_rad_find(ic_rad_ctx *c, const char *name)
{
    if (!c->slot_count)
        return NULL;
    uint32_t k = c->mod_slots[mod_slot(c, name)];
    return k ? &c->mods[k - 1] : NULL;
}

ic_result ic_rad_add_modifier(ic_rad_ctx *c, const ic_rad_modifier *def)
{
    if (c->mod_count >= UINT32_MAX - 1)
        return ic_rad_fail(c, c->prim_line, IC_ERR_UNSUPPORTED, "more than %u modifiers", UINT32_MAX - 2);
    if (c->mod_count == c->mod_capacity) {
        size_t cap = c->mod_capacity ? 2 * c->mod_capacity : 64;
        ic_rad_modifier *grown = realloc(c->mods, sizeof *grown * cap);
        if (!grown)
            return ic_rad_fail(c, c->prim_line, IC_ERR_OOM, "out of memory for the modifiers");
        c->mods = grown;
        c->mod_capacity = cap;
    }
    if (2 * (c->mod_count + 1) > c->slot_count) {
        size_t slots = c->slot_count ? 2 * c->slot_count : 128;
        uint32_t *table = calloc(slots, sizeof *table);
        if (!table)
            return ic_rad_fail(c, c->prim_line, IC_ERR_OOM, "out of memory for the modifiers' names");
        free(c->mod_slots);
        c->mod_slots = table;
        c->slot_count = slots;
        for (size_t i = 0; i < c->mod_count; ++i) /* in order: a later definition takes its name's slot */
            c->mod_slots[mod_slot(c, c->mods[i].name)] = (uint32_t)i + 1;
    }
    c->mods[c->mod_count] = *def;
    c->mod_slots[mod_slot(c, def->name)] = (uint32_t)(++c->mod_count);
    return IC_OK;
}

/* ---- words ---- */

/* Skips white space and comments; 0 at the end of the file, else 1 with c->pos at the next character. */
static int skip_space(ic_rad_ctx *c)
{
    while (c->pos < c->len) {
        char ch = c->text[c->pos];
        if (ch == '\n')
            ++c->line;
        if (ch == '#') {
            while (c->pos < c->len && c->text[c->pos] != '\n')
                ++c->pos;
            continue;
        }
        if (ch != ' ' && ch != '\t' && ch != '\n' && ch != '\r' && ch != '\f' && ch != '\v')
            return 1;
        ++c->pos;
    }
    return 0;
}

/* The next word into buf (a word in double quotes may hold spaces); 0 at the end of the file. what names
 * the expected word in messages. */
static ic_result next_word(ic_rad_ctx *c, char *buf, size_t size, const char *what, int *got)
{
    *got = 0;
    if (!skip_space(c))
        return IC_OK;
    int quoted = c->text[c->pos] == '"', start_line = c->line;
    size_t o = 0;
    if (quoted)
        ++c->pos;
    while (c->pos < c->len) {
        char ch = c->text[c->pos];
        if (quoted ? ch == '"' : (ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r' || ch == '\f' || ch == '\v'))
            break;
        if (ch == '\n')
            ++c->line;
        if (ch == '\0' || o + 1 >= size)
            return ic_rad_fail(c, start_line, IC_ERR_PARSE, "%s is too long or holds a NUL byte; fix the file", what);
        buf[o++] = ch;
        ++c->pos;
    }
    if (quoted) {
        if (c->pos >= c->len)
            return ic_rad_fail(c, start_line, IC_ERR_PARSE, "a quoted word is not closed; add the closing \"");
        ++c->pos;
    }
    buf[o] = '\0';
    *got = 1;
    return IC_OK;
}

/* A word that must be there: the end of the file is an error naming what was expected. */
static ic_result word(ic_rad_ctx *c, char *buf, size_t size, const char *what)
{
    int got;
    ic_result r = next_word(c, buf, size, what, &got);
    if (r == IC_OK && !got && !c->id[0]) /* the line the unfinished primitive starts on */
        r = ic_rad_fail(c, c->prim_line, IC_ERR_PARSE,
                        "the file ends where %s of this primitive should be; complete it or remove it", what);
    else if (r == IC_OK && !got)
        r = ic_rad_fail(c, c->prim_line, IC_ERR_PARSE, "the file ends where %s of %s '%s' should be; complete it", what,
                        c->type, c->id);
    return r;
}

static ic_result count(ic_rad_ctx *c, const char *what, long max, long *out)
{
    char buf[64], *end;
    ic_result r = word(c, buf, sizeof buf, what);
    if (r != IC_OK)
        return r;
    *out = strtol(buf, &end, 10);
    if (*end || end == buf || *out < 0 || *out > max)
        return ic_rad_fail(c, c->line, IC_ERR_PARSE, "%s of %s '%s' is '%s', not a count in [0, %ld]; fix the argument list",
                           what, c->type, c->id, buf, max);
    return IC_OK;
}

/* Reads the three argument lists of the current primitive. */
static ic_result arguments(ic_rad_ctx *c)
{
    long n, max = 3L * (long)ic_scene_max_mesh_elements(c->opt);
    char buf[IC_RAD_WORD_MAX], *end;
    ic_result r = count(c, "the number of string arguments", max, &n);
    c->string_count = (int)n;
    for (long i = 0; i < n && r == IC_OK; ++i)
        r = word(c, i < IC_RAD_MAX_STRINGS ? c->strings[i] : buf, IC_RAD_WORD_MAX, "a string argument");
    if (r == IC_OK)
        r = count(c, "the number of integer arguments", max, &n);
    for (long i = 0; i < n && r == IC_OK; ++i)
        if ((r = word(c, buf, sizeof buf, "an integer argument")) == IC_OK && (strtol(buf, &end, 10), *end || end == buf))
            r = ic_rad_fail(c, c->line, IC_ERR_PARSE, "integer argument '%s' of %s '%s' is not an integer", buf, c->type,
                            c->id);
    if (r == IC_OK)
        r = count(c, "the number of real arguments", max, &n);
    c->real_count = 0;
    for (long i = 0; i < n && r == IC_OK; ++i) {
        if ((r = word(c, buf, sizeof buf, "a real argument")) != IC_OK)
            break;
        if ((size_t)i == c->real_capacity) { /* grown as they come, so a count the file lies about costs nothing */
            size_t cap = c->real_capacity ? 2 * c->real_capacity : 64;
            double *grown = realloc(c->reals, sizeof *grown * cap);
            if (!grown)
                return ic_rad_fail(c, c->prim_line, IC_ERR_OOM, "out of memory for %ld real arguments", n);
            c->reals = grown;
            c->real_capacity = cap;
        }
        c->real_count = (size_t)i + 1;
        c->reals[i] = strtod(buf, &end);
        if (*end || end == buf || !isfinite(c->reals[i]))
            r = ic_rad_fail(c, c->line, IC_ERR_PARSE, "real argument '%s' of %s '%s' is not a finite number", buf,
                            c->type, c->id);
    }
    return r;
}

/* ---- geometry ---- */

/* Grows the parallel arrays *a and *b (elements of ea and eb bytes) of capacity *cap to hold need, doubling. */
static int grow_pair(void **a, size_t ea, void **b, size_t eb, uint32_t *cap, uint64_t need)
{
    if (need <= *cap)
        return 1;
    uint64_t grown = *cap ? *cap : 1024;
    while (grown < need)
        grown *= 2;
    void *pa = realloc(*a, ea * grown);
    if (pa)
        *a = pa;
    void *pb = pa ? realloc(*b, eb * grown) : NULL;
    if (!pb)
        return 0;
    *b = pb;
    *cap = (uint32_t)grown;
    return 1;
}

static int reserve(geometry *g, uint32_t vertices, uint32_t triangles)
{
    if (g->vertex_count + (uint64_t)vertices > UINT32_MAX / 4 || g->tri_count + (uint64_t)triangles > UINT32_MAX / 4)
        return 0;
    return grow_pair((void **)&g->p, sizeof *g->p, (void **)&g->n, sizeof *g->n, &g->vertex_capacity,
                     (uint64_t)g->vertex_count + vertices) &&
           grow_pair((void **)&g->tri, 3 * sizeof *g->tri, (void **)&g->tri_material, sizeof *g->tri_material,
                     &g->tri_capacity, (uint64_t)g->tri_count + triangles);
}

/* Adds a primitive's vertices (normals n, or NULL) and triangles (indices into p) of scene material mat. */
static ic_result add_triangles(ic_rad_ctx *c, geometry *g, const ic_vec3 *p, const ic_vec3 *n, uint32_t nv,
                               const uint32_t *tri, uint32_t nt, uint32_t mat)
{
    if (g->vertex_count + (uint64_t)nv > ic_scene_max_mesh_elements(c->opt))
        return ic_rad_fail(c, c->prim_line, IC_ERR_UNSUPPORTED,
                           "the surfaces so far make more than %zu vertices; %s", ic_scene_max_mesh_elements(c->opt),
                           "raise the limit with --max-mesh-elements (max_mesh_elements of ic_scene_load_options)");
    if (!reserve(g, nv, nt))
        return ic_rad_fail(c, c->prim_line, IC_ERR_OOM, "out of memory for the geometry");
    for (uint32_t i = 0; i < nv; ++i) {
        if (!(fabsf(p[i].x) <= IC_SCENE_MAX_COORD && fabsf(p[i].y) <= IC_SCENE_MAX_COORD &&
              fabsf(p[i].z) <= IC_SCENE_MAX_COORD))
            return ic_rad_fail(c, c->prim_line, IC_ERR_INVALID_ARG,
                               "%s '%s' lies beyond the largest coordinate %g; move or scale it", c->type, c->id,
                               (double)IC_SCENE_MAX_COORD);
        g->p[g->vertex_count + i] = p[i];
        g->n[g->vertex_count + i] = n ? n[i] : v3s(0.0f);
    }
    for (uint32_t t = 0; t < nt; ++t) {
        for (int k = 0; k < 3; ++k)
            g->tri[3 * (g->tri_count + t) + k] = g->vertex_count + tri[3 * t + k];
        g->tri_material[g->tri_count + t] = mat;
    }
    g->vertex_count += nv;
    g->tri_count += nt;
    return IC_OK;
}

static ic_vec3 real3(const ic_rad_ctx *c, size_t i)
{
    return v3((float)c->reals[i], (float)c->reals[i + 1], (float)c->reals[i + 2]);
}

static ic_result need(ic_rad_ctx *c, size_t reals, const char *names)
{
    if (c->real_count == reals)
        return IC_OK;
    return ic_rad_fail(c, c->prim_line, IC_ERR_PARSE, "%s '%s' needs %zu real arguments (%s), has %zu; fix its argument list",
                       c->type, c->id, reals, names, c->real_count);
}

/* A polygon, sphere, bubble, ring, cone, cup, cylinder or tube of scene material mat. */
static ic_result surface(ic_rad_ctx *c, geometry *g, uint32_t mat)
{
    const char *t = c->type;
    ic_result r;
    if (!strcmp(t, "polygon")) {
        if (c->real_count < 9 || c->real_count % 3)
            return ic_rad_fail(c, c->prim_line, IC_ERR_PARSE,
                               "polygon '%s' needs 3 real arguments per vertex and at least 3 vertices, has %zu reals; "
                               "fix its argument list",
                               c->id, c->real_count);
        uint32_t nv = (uint32_t)(c->real_count / 3);
        ic_vec3 *p = malloc(sizeof *p * nv);
        uint32_t *idx = malloc(sizeof *idx * nv), *tri = malloc(sizeof *tri * 3 * (nv - 2));
        r = p && idx && tri ? IC_OK : ic_rad_fail(c, c->prim_line, IC_ERR_OOM, "out of memory for a polygon");
        if (r == IC_OK) {
            for (uint32_t i = 0; i < nv; ++i)
                p[i] = real3(c, 3 * i);
            uint32_t nt = 0;
            if (!ic_tess_polygon(p, nv, idx, tri, &nt)) {
                char what[128];
                snprintf(what, sizeof what, "(self-intersecting, or over %d vertices) is in part a fan: its outline may "
                         "not be kept", IC_TESS_EAR_MAX_VERTICES);
                ic_rad_warn_once(c, c->prim_line, "a concave polygon that ear clipping could not finish", what);
            }
            r = add_triangles(c, g, p, NULL, nv, tri, nt, mat);
        }
        free(p);
        free(idx);
        free(tri);
        return r;
    }
    ic_vec3 *pv = malloc(sizeof *pv * IC_TESS_MAX_VERTICES * 2), *nn = pv ? pv + IC_TESS_MAX_VERTICES : NULL;
    uint32_t *tv = malloc(sizeof *tv * 3 * IC_TESS_MAX_TRIANGLES), nv = 0, nt = 0;
    if (!pv || !tv) {
        free(pv);
        free(tv);
        return ic_rad_fail(c, c->prim_line, IC_ERR_OOM, "out of memory for a shape");
    }
    int inward = 0, has_normals = 1;
    if (!strcmp(t, "sphere") || !strcmp(t, "bubble")) {
        r = need(c, 4, "x y z radius");
        float radius = r == IC_OK ? (float)c->reals[3] : 0.0f;
        if (r == IC_OK && !(radius != 0.0f))
            r = ic_rad_fail(c, c->prim_line, IC_ERR_INVALID_ARG, "%s '%s' has radius 0; give it a size", t, c->id);
        if (r == IC_OK) {
            ic_tess_sphere(real3(c, 0), fabsf(radius), pv, nn, tv, &nv, &nt);
            inward = (radius < 0.0f) != !strcmp(t, "bubble"); /* a negative radius turns it inside out */
        }
    } else if (!strcmp(t, "ring")) {
        r = need(c, 8, "x y z nx ny nz inner-radius outer-radius");
        ic_vec3 axis = r == IC_OK ? real3(c, 3) : v3s(0.0f);
        /* a normal whose squared length leaves a float's normal range, such as (0, 0, 1e20) or (0, 0, 1e-23),
         * with its largest component divided out first (in double, as the file gives it): v3_norm made a zero
         * vector of the one, which the tessellation turned into zero area (the ring dropped without a word),
         * and normalized the other from a denormal length (or refused it as zero, shorter still) */
        double big = r == IC_OK ? fmax(fabs(c->reals[3]), fmax(fabs(c->reals[4]), fabs(c->reals[5]))) : 0.0;
        if (big > 0.0 && !(v3_len2(axis) >= FLT_MIN && v3_len2(axis) <= FLT_MAX))
            axis = v3((float)(c->reals[3] / big), (float)(c->reals[4] / big), (float)(c->reals[5] / big));
        float r0 = r == IC_OK ? (float)c->reals[6] : 0.0f, r1 = r == IC_OK ? (float)c->reals[7] : 0.0f;
        if (r == IC_OK && (!(v3_len2(axis) > 0.0f) || !(r0 >= 0.0f && r1 > r0)))
            r = ic_rad_fail(c, c->prim_line, IC_ERR_INVALID_ARG,
                            "ring '%s' needs a non-zero normal and radii 0 <= inner < outer", c->id);
        if (r == IC_OK) {
            ic_vec3 u, v;
            ic_tess_basis(v3_norm(axis), &u, &v);
            ic_tess_ring(real3(c, 0), u, v, r0, r1, pv, tv, &nv, &nt);
            has_normals = 0;
        }
    } else { /* cone, cup (8 reals), cylinder, tube (7) */
        int is_cyl = !strcmp(t, "cylinder") || !strcmp(t, "tube");
        r = is_cyl ? need(c, 7, "x0 y0 z0 x1 y1 z1 radius") : need(c, 8, "x0 y0 z0 x1 y1 z1 radius0 radius1");
        float r0 = r == IC_OK ? (float)c->reals[6] : 0.0f, r1 = r == IC_OK ? (float)c->reals[is_cyl ? 6 : 7] : 0.0f;
        ic_vec3 p0 = r == IC_OK ? real3(c, 0) : v3s(0.0f), p1 = r == IC_OK ? real3(c, 3) : v3s(0.0f);
        if (r == IC_OK && (!(v3_len2(v3_sub(p1, p0)) > 0.0f) || !(r0 >= 0.0f && r1 >= 0.0f && r0 + r1 > 0.0f)))
            r = ic_rad_fail(c, c->prim_line, IC_ERR_INVALID_ARG,
                            "%s '%s' needs distinct end points and radii >= 0, not both 0", t, c->id);
        if (r == IC_OK) {
            ic_tess_cone(p0, p1, r0, r1, pv, nn, tv, &nv, &nt);
            inward = !strcmp(t, "cup") || !strcmp(t, "tube");
        }
    }
    if (r == IC_OK && inward)
        ic_tess_flip(nn, nv, tv, nt);
    if (r == IC_OK)
        r = add_triangles(c, g, pv, has_normals ? nn : NULL, nv, tv, nt, mat);
    free(pv);
    free(tv);
    return r;
}

/* ---- modifiers of surfaces ---- */

/* The scene material index of modifier m, added to the scene the first time a surface uses it. */
static ic_result material_index(ic_rad_ctx *c, ic_rad_modifier *m, uint32_t *index)
{
    /* a glow of the sky's distribution: its colour alone would be tens of times too dim (an illum's surfaces
     * show its alternate, which the function does not change) */
    if (m->has_sky && !m->is_illum)
        return ic_rad_fail(c, c->prim_line, IC_ERR_UNSUPPORTED,
                           "%s '%s' is made of '%s', which the sky function of line %d modifies; irrcache applies a sky "
                           "function to distant sources only, as gensky's and gendaylit's output does: make it a source "
                           "('%s source sky 0 0 4 0 0 1 180') or give the surface a plain glow",
                           c->type, c->id, m->name, m->sky_line, m->name);
    if (m->index < 0) {
        uint32_t i;
        ic_result r = ic_scene_add_material(c->b, &m->material, c->path, &i, c->err);
        if (r != IC_OK)
            return r;
        m->index = (int32_t)i;
    }
    *index = (uint32_t)m->index;
    return IC_OK;
}

/* The scene material of the current surface; UINT32_MAX when the surface is invisible (left out). */
static ic_result surface_material(ic_rad_ctx *c, uint32_t *index)
{
    *index = UINT32_MAX;
    int is_void = !strcmp(c->modifier, "void");
    ic_rad_modifier *m = is_void ? NULL : ic_rad_find(c, c->modifier);
    if (!is_void && !m)
        return ic_rad_fail(c, c->prim_line, IC_ERR_PARSE,
                           "%s '%s' uses modifier '%s', which is not defined above; define it before the surfaces that "
                           "use it",
                           c->type, c->id, c->modifier);
    if (!m || m->kind == IC_RAD_INVISIBLE) {
        ic_rad_warn_once(c, c->prim_line, "a surface without a material (void, an illum without an alternate, mist)",
                         "is invisible in Radiance and is left out");
        return IC_OK;
    }
    if (m->kind == IC_RAD_PATTERN)
        return ic_rad_fail(c, c->prim_line, IC_ERR_PARSE,
                           "%s '%s' is modified by '%s', a pattern or texture; modify it with a material", c->type, c->id,
                           c->modifier);
    return material_index(c, m, index);
}

/* ---- mesh, source ---- */

/* The transform of a mesh's string arguments after the file name (xform's -t -rx -ry -rz -s -mx -my -mz, each
 * applied after the ones before it), row-major. */
static ic_result mesh_transform(ic_rad_ctx *c, float m[16])
{
    ic_mat4_identity(m);
    int n = c->string_count < IC_RAD_MAX_STRINGS ? c->string_count : IC_RAD_MAX_STRINGS;
    for (int i = 1; i < n; ++i) {
        const char *op = c->strings[i];
        int args = !strcmp(op, "-t") ? 3 : (!strcmp(op, "-rx") || !strcmp(op, "-ry") || !strcmp(op, "-rz") || !strcmp(op, "-s")) ? 1
                   : (!strcmp(op, "-mx") || !strcmp(op, "-my") || !strcmp(op, "-mz")) ? 0 : -1;
        if (args < 0)
            return ic_rad_fail(c, c->prim_line, IC_ERR_UNSUPPORTED,
                               "mesh '%s': transform option '%s' is not supported (only -t -rx -ry -rz -s -mx -my -mz)",
                               c->id, op);
        float v[3] = {0.0f, 0.0f, 0.0f}, a[16];
        for (int k = 0; k < args; ++k) {
            char *end;
            v[k] = i + 1 + k < n ? strtof(c->strings[i + 1 + k], &end) : NAN;
            if (i + 1 + k >= n || *end || !isfinite(v[k]))
                return ic_rad_fail(c, c->prim_line, IC_ERR_PARSE, "mesh '%s': transform option '%s' needs %d number%s",
                                   c->id, op, args, args > 1 ? "s" : "");
        }
        i += args;
        ic_mat4_identity(a);
        if (op[1] == 't') {
            a[3] = v[0];
            a[7] = v[1];
            a[11] = v[2];
        } else if (op[1] == 's') {
            a[0] = a[5] = a[10] = v[0];
        } else if (op[1] == 'm') {
            int ax = op[2] - 'x';
            a[5 * ax] = -1.0f;
        } else { /* a rotation by v[0] degrees about axis op[2], right-handed */
            int ax = op[2] - 'x', j = (ax + 1) % 3, k = (ax + 2) % 3;
            float th = v[0] * IC_PI / 180.0f;
            a[4 * j + j] = a[4 * k + k] = cosf(th);
            a[4 * j + k] = -sinf(th);
            a[4 * k + j] = sinf(th);
        }
        ic_mat4_mul(a, m, m);
    }
    return IC_OK;
}

/* A mesh primitive: the OBJ file it names (or the OBJ beside a compiled .rtm), its faces given the mesh's
 * modifier, or with a void modifier the Radiance materials their OBJ material names name. */
static ic_result mesh(ic_rad_ctx *c)
{
    if (c->string_count < 1)
        return ic_rad_fail(c, c->prim_line, IC_ERR_PARSE, "mesh '%s' needs its file as the first string argument", c->id);
    if (c->string_count > IC_RAD_MAX_STRINGS)
        return ic_rad_fail(c, c->prim_line, IC_ERR_UNSUPPORTED, "mesh '%s' has more than %d string arguments", c->id,
                           IC_RAD_MAX_STRINGS);
    float xf[16];
    ic_result r = mesh_transform(c, xf);
    if (r != IC_OK)
        return r;
    char full[IC_SCENE_PATH_MAX], where[IC_SCENE_PATH_MAX + 32], ext[16];
    snprintf(where, sizeof where, "%s:%d", c->path, c->prim_line);
    if (!ic_path_join(c->dir, c->strings[0], full, sizeof full) || strlen(full) + 4 >= sizeof full)
        return ic_rad_fail(c, c->prim_line, IC_ERR_INVALID_ARG, "mesh '%s': path too long", c->id);
    ic_path_extension(full, ext, sizeof ext);
    if (!strcmp(ext, ".rtm")) {
        char obj[IC_SCENE_PATH_MAX];
        snprintf(obj, sizeof obj, "%.*s.obj", (int)(strlen(full) - 4), full);
        if (!ic_path_exists(obj))
            return ic_rad_fail(c, c->prim_line, IC_ERR_UNSUPPORTED,
                               "mesh '%s': '%s' is a compiled Radiance mesh, which irrcache does not read; put the OBJ "
                               "file it was made from beside it (same name, .obj) or name that file",
                               c->id, c->strings[0]);
        ic_rad_warn_once(c, c->prim_line, "a mesh of a compiled .rtm file", "is read from the OBJ file of the same name beside it");
        memcpy(full, obj, strlen(obj) + 1);
    } else if (strcmp(ext, ".obj")) {
        return ic_rad_fail(c, c->prim_line, IC_ERR_UNSUPPORTED, "mesh '%s': '%s' is not an OBJ file; give an OBJ file",
                           c->id, c->strings[0]);
    }
    /* missing first: a file that is not there is not "outside the scene's folder" */
    if (!ic_path_exists(full))
        return ic_rad_fail(c, c->prim_line, IC_ERR_IO, "mesh '%s': '%s' not found; check the path", c->id, c->strings[0]);
    if ((r = ic_scene_check_path(c->b, full, where, "mesh", c->err)) != IC_OK)
        return r;
    uint32_t override = UINT32_MAX;
    if (strcmp(c->modifier, "void")) {
        if ((r = surface_material(c, &override)) != IC_OK || override == UINT32_MAX)
            return r;
    }
    ic_scene *s = c->b->scene;
    uint32_t first_tri = s->triangle_count, first_mat = s->material_count;
    c->b->import_where = where; /* files the OBJ names are reported at the mesh's line */
    r = ic_mesh_import(c->b, full, xf, where, c->err);
    c->b->import_where = NULL;
    if (r != IC_OK)
        return r;
    uint32_t mat_end = s->material_count;
    for (uint32_t k = first_mat; k < mat_end; ++k) {
        uint32_t to = override;
        ic_rad_modifier *m = override == UINT32_MAX ? ic_rad_find(c, s->materials[k].name) : NULL;
        if (m && m->kind == IC_RAD_MATERIAL && (r = material_index(c, m, &to)) != IC_OK)
            return r;
        if (to == UINT32_MAX) {
            ic_rad_warn_once(c, c->prim_line, "an OBJ material not defined in the Radiance file",
                             "keeps its MTL definition");
            continue;
        }
        for (uint32_t t = first_tri; t < s->triangle_count; ++t)
            if (s->triangle_material[t] == k)
                s->triangle_material[t] = to;
        c->b->material_tris[to] += c->b->material_tris[k];
        c->b->material_tris[k] = 0;
    }
    return IC_OK;
}

/* A distant source wider than the sun: one more cone of the environment's Radiance sky (sky.h), of the colour
 * times the sky function cal (gensky's sky and ground: the function of line sky_line that modifies its glow;
 * a plain source: IC_SKY_FUNCTION_CONSTANT, sky_line 0). */
static ic_result cone_source(ic_rad_ctx *c, const ic_sky_cal *cal, int sky_line, ic_vec3 colour, ic_vec3 d,
                             double angle)
{
    ic_environment *env = &c->b->scene->env;
    if (env->enabled && env->sky.model != IC_SKY_RADIANCE) { /* the 360° sources above: the first cone, all round */
        ic_sky_glow *all = &env->sky.glows[0];
        memset(all, 0, sizeof *all);
        all->cal.function = IC_SKY_FUNCTION_CONSTANT;
        all->direction = v3(0.0f, 0.0f, 1.0f);
        all->cos_half_angle = -1.0;
        all->colour = env->radiance;
        env->sky.glow_count = 1;
    }
    if (env->sky.glow_count == IC_SKY_MAX_GLOWS)
        return ic_rad_fail(c, c->prim_line, IC_ERR_UNSUPPORTED,
                           "source '%s': more than %d sources wider than 5 degrees (gensky writes two, the sky and "
                           "the ground); merge them",
                           c->id, IC_SKY_MAX_GLOWS);
    ic_sky_glow *g = &env->sky.glows[env->sky.glow_count];
    g->cal = *cal;
    g->direction = v3_norm(d);
    /* a hemisphere's rim is exactly its plane (cos 90° would be 6e-17 in double) */
    g->cos_half_angle = angle == 180.0 ? 0.0 : cos(0.5 * angle * 3.14159265358979323846 / 180.0);
    g->colour = colour;
    /* the brightest it gets: at the sun (the clear, intermediate and Perez skies), the zenith or the ground */
    const ic_vec3 sun = v3((float)g->cal.sun[0], (float)g->cal.sun[1], (float)g->cal.sun[2]);
    const ic_vec3 probes[4] = {sun, v3(0.0f, 0.0f, 1.0f), v3(0.0f, 0.0f, -1.0f), g->direction};
    for (int k = 0; k < 4; ++k) {
        ic_vec3 L = v3_scale(colour, (float)ic_sky_cal_value(&g->cal, probes[k]));
        if (ic_radiance_too_large(L))
            return sky_line ? ic_rad_fail(c, c->prim_line, IC_ERR_INVALID_ARG,
                                          "source '%s': its sky (the function of line %d times the colour) reaches a "
                                          "radiance of " IC_RADIANCE_LIMIT_FMT "; " IC_RADIANCE_LIMIT_FIX,
                                          c->id, sky_line, IC_RADIANCE_LIMIT_ARGS(L))
                            : ic_rad_fail(c, c->prim_line, IC_ERR_INVALID_ARG,
                                          "source '%s': its radiance is " IC_RADIANCE_LIMIT_FMT "; "
                                          IC_RADIANCE_LIMIT_FIX, c->id, IC_RADIANCE_LIMIT_ARGS(L));
    }
    ++env->sky.glow_count;
    env->sky.model = IC_SKY_RADIANCE;
    env->enabled = 1;
    env->radiance = v3s(1.0f);
    return IC_OK;
}

/* A distant source: small ones (up to 5°) the sun; wider ones a cone of the environment of their radiance, or
 * of the sky function that modifies their glow; a 360° one without a sky function a uniform environment. */
static ic_result source(ic_rad_ctx *c, int *has_sun)
{
    ic_result r = need(c, 4, "x-direction y-direction z-direction angle");
    if (r != IC_OK)
        return r;
    ic_rad_modifier *m = ic_rad_find(c, c->modifier);
    /* an illum's own colour is the source's radiance (its alternate material is for surfaces) */
    const int illum = m && m->is_illum && !v3_is_black(m->source_radiance);
    if (!m || (!illum && (m->kind != IC_RAD_MATERIAL || !m->is_emitter)))
        return ic_rad_fail(c, c->prim_line, IC_ERR_PARSE,
                           "source '%s' needs a light, glow or illum material defined above (not '%s')", c->id,
                           c->modifier);
    const ic_vec3 radiance = illum ? m->source_radiance : m->material.emission;
    ic_vec3 d = real3(c, 0);
    double angle = c->reals[3];
    if (!(v3_len2(d) > 0.0f) || !(angle > 0.0 && angle <= 360.0))
        return ic_rad_fail(c, c->prim_line, IC_ERR_INVALID_ARG,
                           "source '%s' needs a non-zero direction and an angle in (0, 360] degrees", c->id);
    if (v3_is_black(radiance)) /* emits nothing, as in Radiance (gendaylit's sun under an overcast sky: 0 0 0) */
        return IC_OK;
    if (m->has_sky)
        return cone_source(c, &m->sky, m->sky_line, radiance, d, angle);
    ic_scene *s = c->b->scene;
    const ic_sky_cal constant = {.function = IC_SKY_FUNCTION_CONSTANT};
    if (angle > 5.0 && angle < 360.0) /* its radiance within its cone, nothing outside, as in Radiance */
        return cone_source(c, &constant, 0, radiance, d, angle);
    double solid_angle = 2.0 * 3.14159265358979323846 * (1.0 - cos(0.5 * angle * 3.14159265358979323846 / 180.0));
    ic_vec3 power = v3_scale(radiance, (float)solid_angle); /* radiance × solid angle */
    if (angle > 5.0 && s->env.sky.model == IC_SKY_RADIANCE) /* after cones: one more, all round */
        return cone_source(c, &constant, 0, radiance, d, angle);
    if (angle <= 5.0) {
        if (*has_sun)
            return ic_rad_fail(c, c->prim_line, IC_ERR_UNSUPPORTED,
                               "a second small source ('%s'); irrcache renders one sun: merge them", c->id);
        *has_sun = 1;
        s->sun.enabled = 1;
        s->sun.direction = v3_norm(d);
        s->sun.irradiance = power;
        return IC_OK;
    }
    s->env.enabled = 1; /* 360°: the whole sphere; two of them add up */
    s->env.radiance = v3_add(s->env.radiance, v3_scale(power, (float)(1.0 / (4.0 * 3.14159265358979323846))));
    return IC_OK;
}

/* ---- the file ---- */

static int is_surface_type(const char *t)
{
    static const char *const types[] = {"polygon", "sphere", "bubble", "ring", "cone", "cup", "cylinder", "tube"};
    for (size_t i = 0; i < sizeof types / sizeof types[0]; ++i)
        if (!strcmp(t, types[i]))
            return 1;
    return 0;
}

/* Reads one primitive; *done at the end of the file. */
static ic_result primitive(ic_rad_ctx *c, geometry *g, int *has_sun, int *done)
{
    *done = 0;
    if (!skip_space(c)) {
        *done = 1;
        return IC_OK;
    }
    if (c->text[c->pos] == '!') { /* a command whose output Radiance would read: named, never run */
        size_t end = c->pos;
        while (end < c->len && c->text[end] != '\n' && c->text[end] != '\r')
            ++end;
        return ic_rad_fail(c, c->line, IC_ERR_UNSUPPORTED,
                           "'%.*s' runs a command, which irrcache never does; run it yourself and put its output in "
                           "the file",
                           (int)(end - c->pos > 120 ? 120 : end - c->pos), c->text + c->pos);
    }
    char before[2 * IC_RAD_WORD_MAX + 64] = ""; /* the primitive before, for a message about a stray word */
    if (c->id[0])
        snprintf(before, sizeof before, "%s '%s' (line %d)", c->type, c->id, c->prim_line);
    c->type[0] = c->id[0] = '\0';
    c->prim_line = c->line;
    ic_result r = word(c, c->modifier, sizeof c->modifier, "a modifier");
    char *end;
    if (r == IC_OK && (strtod(c->modifier, &end), *end == '\0' && end != c->modifier) && !ic_rad_find(c, c->modifier))
        /* a number where a primitive starts: most likely an argument its list's count leaves out */
        return before[0] ? ic_rad_fail(c, c->prim_line, IC_ERR_PARSE,
                                       "'%s' stands where a primitive should start (modifier type identifier): the "
                                       "argument lists of %s hold more words than their counts say; fix the counts",
                                       c->modifier, before)
                         : ic_rad_fail(c, c->prim_line, IC_ERR_PARSE,
                                       "'%s' stands where the first primitive should start (modifier type "
                                       "identifier); remove it",
                                       c->modifier);
    if (r == IC_OK)
        r = word(c, c->type, sizeof c->type, "the type");
    if (r == IC_OK)
        r = word(c, c->id, sizeof c->id, "the identifier");
    if (r == IC_OK && !strcmp(c->type, "alias")) { /* "modifier alias identifier original": no argument lists */
        c->string_count = 1;
        c->real_count = 0;
        r = word(c, c->strings[0], sizeof c->strings[0], "the original's name");
    } else if (r == IC_OK) {
        r = arguments(c);
    }
    if (r != IC_OK)
        return r;
    const char *t = c->type;
    if (!strcmp(t, "instance"))
        return ic_rad_fail(c, c->prim_line, IC_ERR_UNSUPPORTED,
                           "instance '%s' places a compiled octree, which irrcache cannot read; put the Radiance files "
                           "the octree was made from in the scene instead",
                           c->id);
    if (!strcmp(t, "mesh"))
        return mesh(c);
    if (!strcmp(t, "source"))
        return source(c, has_sun);
    if (is_surface_type(t)) {
        uint32_t mat;
        if ((r = surface_material(c, &mat)) != IC_OK || mat == UINT32_MAX)
            return r;
        return surface(c, g, mat);
    }
    ic_rad_modifier def;
    if ((r = ic_rad_define_modifier(c, &def)) == IC_OK)
        r = ic_rad_add_modifier(c, &def);
    return r;
}

/* Hands the collected triangles to the scene, one material at a time in order of first use (a counting
 * sort by material keeps each material's triangles in file order). */
static ic_result flush(ic_rad_ctx *c, geometry *g)
{
    ic_scene *s = c->b->scene;
    size_t nvmax = g->vertex_count ? g->vertex_count : 1, ntmax = g->tri_count ? g->tri_count : 1;
    uint32_t *remap = malloc(sizeof *remap * nvmax), *order = malloc(sizeof *order * ntmax);
    uint32_t *start = calloc((size_t)s->material_count + 1, sizeof *start);
    ic_vec3 *p = malloc(sizeof *p * nvmax), *n = malloc(sizeof *n * nvmax);
    uint32_t *tri = malloc(sizeof *tri * 3 * ntmax);
    ic_result r = remap && order && start && p && n && tri ? IC_OK
                                                           : ic_rad_fail(c, c->line, IC_ERR_OOM, "out of memory for the geometry");
    float identity[16];
    ic_mat4_identity(identity);
    if (r == IC_OK) {
        for (uint32_t i = 0; i < g->vertex_count; ++i)
            remap[i] = UINT32_MAX;
        for (uint32_t t = 0; t < g->tri_count; ++t)
            ++start[g->tri_material[t] + 1];
        for (uint32_t m = 0; m < s->material_count; ++m)
            start[m + 1] += start[m];
        for (uint32_t t = 0; t < g->tri_count; ++t)
            order[start[g->tri_material[t]]++] = t;
        for (uint32_t m = s->material_count; m > 0; --m) /* back to each material's first position */
            start[m] = start[m - 1];
        start[0] = 0;
    }
    for (uint32_t mat = 0; r == IC_OK && mat < s->material_count; ++mat) {
        uint32_t nv = 0, nt = 0;
        int smooth = 0;
        for (uint32_t o = start[mat]; o < start[mat + 1]; ++o, ++nt)
            for (int k = 0; k < 3; ++k) {
                uint32_t v = g->tri[3 * order[o] + k];
                if (remap[v] == UINT32_MAX) {
                    remap[v] = nv;
                    p[nv] = g->p[v];
                    n[nv] = g->n[v];
                    smooth |= !v3_is_black(g->n[v]);
                    ++nv;
                }
                tri[3 * nt + k] = remap[v];
            }
        if (nt == 0)
            continue;
        for (uint32_t o = start[mat]; o < start[mat + 1]; ++o) /* reset for the next material */
            for (int k = 0; k < 3; ++k)
                remap[g->tri[3 * order[o] + k]] = UINT32_MAX;
        r = ic_scene_append_triangles(c->b, p, smooth ? n : NULL, nv, tri, nt, mat, identity, c->path, c->err);
    }
    free(remap);
    free(order);
    free(start);
    free(p);
    free(n);
    free(tri);
    return r;
}

ic_result ic_scene_load_radiance(ic_scene_builder *b, const char *path, const ic_scene_load_options *opt, ic_error *err)
{
    char *text = NULL;
    size_t len = 0;
    uint64_t max_bytes = opt->max_scene_bytes ? opt->max_scene_bytes : IC_DEFAULT_MAX_SCENE_FILE_BYTES;
    ic_result r = ic_read_regular_file(path, "scene file", max_bytes, "raise the limit with --max-scene-bytes", &text,
                                       &len, NULL, err);
    if (r != IC_OK)
        return r;
    ic_rad_ctx *c = calloc(1, sizeof *c);
    geometry g;
    memset(&g, 0, sizeof g);
    if (!c) {
        free(text);
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory", path);
    }
    c->b = b;
    c->opt = opt;
    c->path = path;
    c->err = err;
    c->text = text;
    c->len = len;
    c->line = 1;
    c->pos = ic_utf8_bom_length(text, len); /* a byte-order mark some editors put first is no word */
    ic_path_dirname(path, c->dir, sizeof c->dir);
    int has_sun = 0, done = 0;
    while (r == IC_OK && !done)
        r = primitive(c, &g, &has_sun, &done);
    if (r == IC_OK)
        r = flush(c, &g);
    free(g.p);
    free(g.n);
    free(g.tri);
    free(g.tri_material);
    free(c->reals);
    free(c->mods);
    free(c->mod_slots);
    free(c);
    free(text);
    const int has_view = opt->view && opt->view[0];
    if (r == IC_OK)
        r = ic_scene_finalize_and_fit(b, has_view, err);
    if (r != IC_OK)
        return r;
    if (has_view) {
        ic_scene_note_file(b->scene, opt->view);
        return ic_rad_read_view(opt->view, opt, b->scene, err);
    }
    /* no view: the fitted camera turned to Radiance's default orientation (-vd 0 1 0 -vu 0 0 1), at the
     * same distance, which frames the bounding sphere from any side */
    ic_camera *cam = &b->scene->camera;
    cam->eye = v3_sub(cam->target, v3(0.0f, v3_len(v3_sub(cam->eye, cam->target)), 0.0f));
    cam->up = v3(0.0f, 0.0f, 1.0f);
    return IC_OK;
}
