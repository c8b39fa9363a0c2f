/*
 * radiance_internal.h — shared by the Radiance scene reader's files: the parse context and the current
 * primitive (radiance_scene.c reads them and makes the geometry), the modifiers a primitive may define
 * (radiance_material.c) and the view file (radiance_view.c).
 *
 * A Radiance scene is a sequence of primitives, each "modifier type identifier" followed by three
 * argument lists: a count and that many words, a count and that many integers, a count and that many
 * reals (Larson & Shakespeare 1998; docs/scene-format.md).
 */
#ifndef IC_SCENE_RADIANCE_INTERNAL_H
#define IC_SCENE_RADIANCE_INTERNAL_H

#include "scene/scene_internal.h"

#define IC_RAD_WORD_MAX 256  /* longest word (identifier, string argument) */
#define IC_RAD_MAX_STRINGS 64 /* string arguments kept per primitive (the rest are read and skipped) */
#define IC_RAD_MAX_WARNED 64

/* What a name defined as a modifier stands for. */
typedef enum ic_rad_kind {
    IC_RAD_MATERIAL,  /* a material: surfaces it modifies are rendered with it */
    IC_RAD_INVISIBLE, /* void, an illum without an alternate, mist: its surfaces are left out */
    IC_RAD_PATTERN    /* a pattern or texture (not rendered): a material it modifies is used without it */
} ic_rad_kind;

typedef struct ic_rad_modifier {
    char name[IC_RAD_WORD_MAX];
    ic_rad_kind kind;
    ic_material material; /* IC_RAD_MATERIAL: the mapped material */
    int32_t index;        /* its index among the scene's materials once a surface used it, else -1 */
    int line;             /* where it was defined */
    int is_illum;         /* an illum: `source_radiance` is its own colour, which a source it modifies emits
                             (the surfaces it modifies show its alternate material) */
    ic_vec3 source_radiance;
    int is_emitter;       /* a light, glow or spotlight (of any radiance, 0 too) */
    int has_sky;          /* a sky function (a brightfunc of skybright.cal or perezlum.cal: `sky`), or an emitter
                             or illum it modifies, whose sources then take the sky's distribution */
    ic_sky_cal sky;
    int sky_line;         /* where the sky function was defined */
} ic_rad_modifier;

typedef struct ic_rad_ctx {
    ic_scene_builder *b;
    const ic_scene_load_options *opt;
    const char *path;
    char dir[IC_SCENE_PATH_MAX];
    ic_error *err;
    const char *text; /* the file */
    size_t len, pos;
    int line;
    /* the primitive being read */
    char modifier[IC_RAD_WORD_MAX], type[IC_RAD_WORD_MAX], id[IC_RAD_WORD_MAX];
    int prim_line;
    char strings[IC_RAD_MAX_STRINGS][IC_RAD_WORD_MAX];
    int string_count; /* all of them, though only the first IC_RAD_MAX_STRINGS are kept */
    double *reals;
    size_t real_count, real_capacity;
    /* the modifiers defined so far, in order (a later definition of a name hides the earlier one) */
    ic_rad_modifier *mods;
    size_t mod_count, mod_capacity;
    /* where each name's latest definition is: an open-addressed table of mod indices + 1 (0: empty), a
     * power of two at least twice the modifiers, so that a surface finds its modifier in constant time */
    uint32_t *mod_slots;
    size_t slot_count;
    char warned[IC_RAD_MAX_WARNED][96]; /* kinds already warned about */
    int warned_count;
} ic_rad_ctx;

/* 3 if text starts with the UTF-8 byte-order mark (EF BB BF) that some editors write first, else 0. */
static inline size_t ic_utf8_bom_length(const char *text, size_t len)
{
    return len >= 3 && (unsigned char)text[0] == 0xEF && (unsigned char)text[1] == 0xBB && (unsigned char)text[2] == 0xBF
               ? 3
               : 0;
}

/* Sets the error "file:line: message" and returns r. */
ic_result ic_rad_fail(ic_rad_ctx *c, int line, ic_result r, const char *fmt, ...) __attribute__((format(printf, 4, 5)));
/* Adds "file:line: kind what" to the scene's warnings, once per kind. */
void ic_rad_warn_once(ic_rad_ctx *c, int line, const char *kind, const char *what);
/* The modifier named name as the scene stands now (the latest definition), or NULL. */
ic_rad_modifier *ic_rad_find(ic_rad_ctx *c, const char *name);
/* Appends a modifier's definition; a later definition of a name hides the earlier one. */
ic_result ic_rad_add_modifier(ic_rad_ctx *c, const ic_rad_modifier *def);
/* Defines the current primitive, a modifier (any type that is no surface), into *out: its name, kind and
 * material. A type irrcache does not know is warned about and becomes a diffuse grey. */
ic_result ic_rad_define_modifier(ic_rad_ctx *c, ic_rad_modifier *out);

/* Reads a Radiance view file (radiance_view.c): the camera it gives, at the resolution that fits
 * opt's width × height (else the defaults) with square pixels, as rpict does. Options other than the
 * view's are skipped; the aft clipping distance is warned about into scene's warnings. */
ic_result ic_rad_read_view(const char *path, const ic_scene_load_options *opt, ic_scene *scene, ic_error *err);

#endif
