/*
 * mitsuba_internal.h — shared by the Mitsuba scene reader's files: the parse context, attribute values
 * with <default> substitution, typed parameters, transforms (mitsuba_values.c) and BSDFs (mitsuba_bsdf.c);
 * the elements and the loading entry point are in mitsuba_scene.c.
 */
#ifndef IC_SCENE_MITSUBA_INTERNAL_H
#define IC_SCENE_MITSUBA_INTERNAL_H

#include "scene/scene_internal.h"

#include <libxml/tree.h>

#define MAX_DEFAULTS 64
#define MAX_WARNED 64
#define VALUE_MAX 1024
#define MAX_DOCS 16             /* the scene file and the files it includes, in all */
#define MAX_INCLUDE_DEPTH 8

typedef struct ic_mts_ctx {
    ic_scene_builder *b;
    const ic_scene_load_options *opt;
    const char *path;
    char dir[IC_SCENE_PATH_MAX];
    ic_error *err;
    xmlNode *roots[MAX_DOCS];   /* the <scene> of the file and of every file it includes: ids are found in all */
    xmlDoc *included[MAX_DOCS]; /* the included files' documents (freed by the loader) */
    int root_count, include_depth;
    int has_sensor;             /* sensors met so far: the first is the camera */
    char def_name[MAX_DEFAULTS][64], def_value[MAX_DEFAULTS][256];
    int def_count;
    char warned[MAX_WARNED][96]; /* element kinds already warned about */
    int warned_count;
    char value[4][VALUE_MAX];   /* substituted attribute values, used round-robin */
    int next_value;
} ic_mts_ctx;

/* The element's line in its file, and that file (the scene's or an included one's path). */
int ic_mts_line(const xmlNode *n);
const char *ic_mts_file(const ic_mts_ctx *c, const xmlNode *n);
/* The major version (0, 2, 3) that the <scene version="..."> of n's file declares; 0, Mitsuba 0.6's
 * reading, without one. Mitsuba 2 and 3 changed defaults: a conductor's material, a sphere's centre. */
int ic_mts_version_major(const xmlNode *n);
/* An error naming root's file:line if its version attribute is there but not MAJOR[.MINOR[.PATCH]]. */
ic_result ic_mts_check_version(ic_mts_ctx *c, const xmlNode *root);
/* 1 if n is an element named name (any element if name is NULL). */
int ic_mts_is_element(const xmlNode *n, const char *name);
/* An attribute with every $name of a <default> replaced; NULL if absent. The text lives in one of four
 * buffers of the context, reused by later calls: copy it (ic_mts_attr_copy) to keep it. */
const char *ic_mts_attr(ic_mts_ctx *c, const xmlNode *n, const char *key);
const char *ic_mts_attr_copy(ic_mts_ctx *c, const xmlNode *n, const char *key, char *buf, size_t size);
/* Adds "file:line: kind what" to the scene's warnings, once per kind. */
void ic_mts_warn_once(ic_mts_ctx *c, const xmlNode *n, const char *kind, const char *what);
/* Sets the error "file:line: what detail" and returns r. */
ic_result ic_mts_fail(ic_mts_ctx *c, const xmlNode *n, ic_result r, const char *what, const char *detail);
/* The child element <tag name="name"> (any tag if tag is NULL), or NULL. */
xmlNode *ic_mts_child(ic_mts_ctx *c, const xmlNode *n, const char *tag, const char *name);
/* Up to n numbers separated by commas or white space; how many were read, -1 on a non-number. */
int ic_mts_numbers(const char *s, float *out, int n);
/* Typed parameters of element n by name, with their fallbacks when absent. */
ic_result ic_mts_float(ic_mts_ctx *c, const xmlNode *n, const char *name, float fallback, float *out);
const char *ic_mts_string(ic_mts_ctx *c, const xmlNode *n, const char *name);
ic_result ic_mts_ior(ic_mts_ctx *c, const xmlNode *n, const char *name, float fallback, float *out);
/* A <texture type="bitmap"> element k loaded into the scene (as values when is_data: ic_texture's is_data);
 * *loaded is 0 (and nothing happens) for any other texture. */
ic_result ic_mts_texture(ic_mts_ctx *c, const xmlNode *k, int is_data, int32_t *index, int *loaded);
/* A colour (rgb, srgb, spectrum, float); a bitmap texture goes to *texture (when not NULL), colour 1. */
ic_result ic_mts_color(ic_mts_ctx *c, const xmlNode *n, const char *name, ic_vec3 fallback, ic_vec3 *out,
                       int32_t *texture);
/* ic_mts_color (fallback 1, no texture) for a radiance, irradiance or intensity: at most IC_SCENE_MAX_RADIANCE. */
ic_result ic_mts_radiance(ic_mts_ctx *c, const xmlNode *n, const char *name, ic_vec3 *out);
/* A point or vector element's x, y, z attributes or its value (one number for all three). */
ic_result ic_mts_vec(ic_mts_ctx *c, const xmlNode *k, float fallback, ic_vec3 *out);
/* The element's toWorld transform, row-major (identity without one). */
ic_result ic_mts_to_world(ic_mts_ctx *c, const xmlNode *n, float m[16]);
/* The top-level element <tag id="id">, or NULL. */
const xmlNode *ic_mts_find_by_id(ic_mts_ctx *c, const char *tag, const char *id);
/* The material a <bsdf> element describes (depth: wrappers passed through so far). */
ic_result ic_mts_bsdf(ic_mts_ctx *c, const xmlNode *n, ic_material *m, int depth);

#endif
