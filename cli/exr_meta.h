/* exr_meta.h — what a render's EXR outputs say about how they were made (render.c). */
#ifndef IC_CLI_EXR_META_H
#define IC_CLI_EXR_META_H

#include "options.h"

#include "irrcache/image.h"

#define IC_CLI_EXR_META_MAX 9

/* The header's text attributes and the storage of their values. */
typedef struct ic_cli_exr_meta {
    ic_image_meta items[IC_CLI_EXR_META_MAX];
    uint32_t count;
    char *settings;        /* the settings JSON (malloc'd) */
    char *scene;           /* the scene's path repaired to UTF-8 (cJSON_malloc'd), or NULL when it was UTF-8 */
    char text[6][64];      /* the short values */
} ic_cli_exr_meta;

/* Fills m from the render's arguments and what it cost: irrcache:version, :scene, :scene_fnv1a64 (of the
 * scene file's bytes; absent if it cannot be read), :integrator, :seed, :spp, :seconds (fixed width),
 * :settings (the options as the stats JSON echoes them; both texts UTF-8, U+FFFD for a byte of a path that is
 * not) and, for an interrupted render whose final render was cut short, :partial. Never
 * fails: what cannot be made is left out. */
void ic_cli_exr_meta_make(const ic_cli_args *a, const ic_render_stats *st, ic_cli_exr_meta *m);
/* Adds irrcache:partial, "WHY; F of the final render" (why: "interrupted", "checkpoint"; completed: the
 * share F done). */
void ic_cli_exr_meta_partial(ic_cli_exr_meta *m, const char *why, double completed);
void ic_cli_exr_meta_free(ic_cli_exr_meta *m);

#endif
