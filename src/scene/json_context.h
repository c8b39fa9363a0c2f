/*
 * json_context.h — what the files of the JSON scene front end share: the parse context, the
 * helpers every section reads with (scene_json_value.c) and the section parsers scene_json.c calls.
 * Not for the rest of the scene module.
 */
#ifndef IC_SCENE_JSON_CONTEXT_H
#define IC_SCENE_JSON_CONTEXT_H

#include "scene/scene_internal.h"

#include <cjson/cJSON.h>

#include <stddef.h>

typedef struct json_ctx {
    const char *path;              /* the scene file, for messages */
    char dir[IC_SCENE_PATH_MAX];   /* its directory: relative paths resolve against it */
    const char *text;              /* the file's text */
    size_t len;
    size_t cursor;                 /* key search starts here */
    int line;                      /* line of the last key found */
    size_t line_off;               /* the last offset whose line was counted … */
    int line_no;                   /* … and its line (0: none yet): lines are counted from there */
    size_t scanned;                /* bytes examined by line counting and key search (linear in len) */
    const ic_scene_load_options *opt;
    ic_scene_builder *b;
    ic_error *err;
} json_ctx;

/* --- positions and messages (scene_json_value.c; the search is described in scene_json.c) --- */

/* Line of the text at offset off (1 = the first), counted from the offset asked before: as the
 * document is visited in file order, all the look-ups of one file cost O(its length) together. */
int ic_json_line_of(json_ctx *c, size_t off);
/* Moves the cursor past the next occurrence of key and returns its line (the last line if absent). */
int ic_json_locate_key(json_ctx *c, const char *key);
/* Line of the next occurrence of key without moving the cursor. */
int ic_json_peek_key_line(json_ctx *c, const char *key);
/* Moves the cursor to the next '{' (the start of an array's object element) and returns its line. */
int ic_json_locate_object_start(json_ctx *c);

/* Sets c->err to "file:line: message" and returns code. */
ic_result ic_json_fail(json_ctx *c, int line, ic_result code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* Keys starting with '_' are comments. */
static inline int ic_json_is_comment(const char *key) { return key && key[0] == '_'; }

/* The error for a key `where` does not know, listing the valid ones. */
ic_result ic_json_unknown_key(json_ctx *c, int line, const char *key, const char *where, const char *valid);

/* --- values (scene_json_value.c): each reports a value of the wrong kind at line --- */

ic_result ic_json_read_float(json_ctx *c, const cJSON *it, int line, float *out);
/* An integer in [lo, hi]; hint says what to give. */
ic_result ic_json_read_int(json_ctx *c, const cJSON *it, int line, double lo, double hi, const char *hint,
                           double *out);
ic_result ic_json_read_vec3(json_ctx *c, const cJSON *it, int line, ic_vec3 *out);
/* A colour: one non-negative number (grey) or [r, g, b]. */
ic_result ic_json_read_color(json_ctx *c, const cJSON *it, int line, ic_vec3 *out);
/* A colour that is a radiance, irradiance or intensity: at most IC_SCENE_MAX_RADIANCE. */
ic_result ic_json_read_radiance(json_ctx *c, const cJSON *it, int line, ic_vec3 *out);
ic_result ic_json_read_string(json_ctx *c, const cJSON *it, int line, const char **out);
ic_result ic_json_expect_object(json_ctx *c, const cJSON *it, int line);

/* Adds the shared scenes folders that exist to the folders the scene may read from (c->b->roots). */
void ic_json_add_shared_roots(json_ctx *c);
/* A path from the scene file resolved to an existing file in out (see scene_json_value.c); reports
 * `what` not found at line, and a file outside the scene's folder tree and the shared scenes folders
 * (ic_scene_check_path) unless allow_outside_paths is set. */
ic_result ic_json_resolve_path(json_ctx *c, const char *given, int line, const char *what, char *out,
                               size_t size);

/* --- sections --- */

/* "environment" (scene_json_light.c). */
ic_result ic_json_parse_environment(json_ctx *c, const cJSON *obj, int line);
/* An environment's "portals": an array of parallelograms, each four corners in order (scene_json_light.c). */
ic_result ic_json_parse_portals(json_ctx *c, const cJSON *arr, int line);
/* "environment" that names a "sky" (scene_json_sky.c). */
ic_result ic_json_parse_sky(json_ctx *c, const cJSON *obj, int line);
/* "lights": point lights and at most one sun (scene_json_light.c). */
ic_result ic_json_parse_lights(json_ctx *c, const cJSON *arr, int line);
/* "meshes": imports each mesh file into c->b (scene_json_mesh.c). */
ic_result ic_json_parse_meshes(json_ctx *c, const cJSON *arr, int line);
/* "materials": overrides of the meshes' materials, by name; after the meshes (scene_json_material.c). */
ic_result ic_json_parse_materials(json_ctx *c, const cJSON *obj, int line);

#endif
