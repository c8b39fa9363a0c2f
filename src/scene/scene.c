/*
 * scene.c — what both front ends (scene_json.c, mesh_import.c) build a scene with: paths, matrices,
 * textures, the default camera, final validation and the scene's lifetime. The loading entry point that
 * chooses a front end is scene_load.c.
 */
#ifndef _DEFAULT_SOURCE
#define _DEFAULT_SOURCE /* realpath() */
#endif
#include "scene/scene_internal.h"

#include "core/error_at.h"
#include "core/text.h"
#include "core/vecmath.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* ------------------------------------------------------------------------------------------------ */
/* paths */

int ic_path_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

const char *ic_path_missing(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && !S_ISREG(st.st_mode) ? "is not a regular file (a folder, pipe or device)"
                                                        : "not found";
}

int ic_path_join(const char *dir, const char *rel, char *out, size_t size)
{
    char fixed[IC_SCENE_PATH_MAX];
    if (snprintf(fixed, sizeof fixed, "%s", rel) >= (int)sizeof fixed)
        return 0;
    for (char *c = fixed; *c; ++c)
        if (*c == '\\')
            *c = '/';
    int n;
    if (fixed[0] == '/' || !dir || !*dir || !strcmp(dir, "."))
        n = snprintf(out, size, "%s", fixed);
    else
        n = snprintf(out, size, "%s/%s", dir, fixed);
    return n >= 0 && (size_t)n < size;
}

/* Removes "." and "name/.." components of an absolute path in place (lexically). */
static void normalize_absolute(char *path)
{
    char in[IC_SCENE_PATH_MAX];
    snprintf(in, sizeof in, "%s", path);
    char *end = path + 1; /* path[0] stays '/'; end is one past the last written char */
    char *save = NULL;
    for (char *comp = strtok_r(in, "/", &save); comp; comp = strtok_r(NULL, "/", &save)) {
        if (!strcmp(comp, "."))
            continue;
        if (!strcmp(comp, "..")) {
            if (end > path + 1) { /* drop the last component and its slash */
                --end;
                while (end > path + 1 && end[-1] != '/')
                    --end;
            }
            continue;
        }
        size_t n = strlen(comp);
        memcpy(end, comp, n);
        end += n;
        *end++ = '/';
    }
    if (end > path + 1)
        --end; /* no trailing slash */
    *end = '\0';
}

void ic_path_absolute(const char *path, char *out, size_t size)
{
    char dir[IC_SCENE_PATH_MAX], real[PATH_MAX];
    ic_path_dirname(path, dir, sizeof dir);
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    if (realpath(dir, real)) {
        snprintf(out, size, "%s%s%s", real, strcmp(real, "/") ? "/" : "", base);
    } else if (path[0] != '/' && getcwd(real, sizeof real)) {
        snprintf(out, size, "%s/%s", real, path);
    } else {
        snprintf(out, size, "%s", path);
    }
    if (out[0] == '/')
        normalize_absolute(out);
}

void ic_path_extension(const char *path, char *ext, size_t size)
{
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(path, '.');
    if (!dot || (slash && dot < slash)) {
        snprintf(ext, size, "%s", "");
        return;
    }
    size_t i = 0;
    for (; dot[i] && i + 1 < size; ++i)
        ext[i] = (char)((dot[i] >= 'A' && dot[i] <= 'Z') ? dot[i] - 'A' + 'a' : dot[i]);
    ext[i] = '\0';
}

/* ------------------------------------------------------------------------------------------------ */
/* the folders a scene may read from (docs/scene-format.md, "Paths") */

void ic_scene_add_root(ic_scene_builder *b, const char *dir)
{
    char real[PATH_MAX];
    if (!dir || !*dir || b->root_count == IC_SCENE_MAX_ROOTS || !realpath(dir, real))
        return;
    for (int k = 0; k < b->root_count; ++k)
        if (!strcmp(b->roots[k], real))
            return;
    snprintf(b->roots[b->root_count++], sizeof b->roots[0], "%s", real);
}

/* 1 if the real path `real` is root itself or lies below it (compared by whole components). */
static int path_below(const char *real, const char *root)
{
    size_t n = strlen(root);
    if (strncmp(real, root, n) != 0)
        return 0;
    return real[n] == '\0' || real[n] == '/' || (n > 0 && root[n - 1] == '/');
}

/* Adds real (a real path) to s->files, once. */
static void note_real(ic_scene *s, const char *real)
{
    for (uint32_t k = 0; k < s->file_count; ++k)
        if (!strcmp(s->files[k], real))
            return;
    char **grown = realloc(s->files, sizeof *grown * (s->file_count + 1));
    char *copy = strdup(real);
    if (grown)
        s->files = grown;
    if (!grown || !copy) {
        free(copy);
        s->files_lost = 1;
        return;
    }
    s->files[s->file_count++] = copy;
}

void ic_scene_note_file(ic_scene *s, const char *path)
{
    char real[PATH_MAX];
    if (realpath(path, real)) /* nothing there: nothing read, nothing to keep from being overwritten */
        note_real(s, real);
}

uint32_t ic_scene_file_count(const ic_scene *scene) { return scene ? scene->file_count : 0; }

const char *ic_scene_file(const ic_scene *scene, uint32_t index)
{
    return scene && index < scene->file_count ? scene->files[index] : NULL;
}

int ic_scene_path_allowed(const ic_scene_builder *b, const char *path, char *real, size_t size)
{
    char buf[PATH_MAX];
    if (size)
        real[0] = '\0';
    if (!realpath(path, buf))
        return b->opt->allow_outside_paths;
    snprintf(real, size, "%s", buf);
    note_real(b->scene, buf); /* asked for before it is read: one of the scene's files */
    if (b->opt->allow_outside_paths)
        return 1;
    for (int k = 0; k < b->root_count; ++k)
        if (path_below(buf, b->roots[k]))
            return 1;
    return 0;
}

ic_result ic_scene_check_path(const ic_scene_builder *b, const char *path, const char *where, const char *desc,
                              ic_error *err)
{
    char real[IC_SCENE_PATH_MAX];
    if (ic_scene_path_allowed(b, path, real, sizeof real))
        return IC_OK;
    char shared[IC_SCENE_MAX_ROOTS * 256] = "";
    size_t used = 0;
    for (int k = 1; k < b->root_count && used < sizeof shared; ++k) {
        int n = snprintf(shared + used, sizeof shared - used, "%s%s", k > 1 ? " or " : "", b->roots[k]);
        if (n < 0)
            break;
        used += (size_t)n;
    }
    return ic_error_set(err, IC_ERR_INVALID_ARG,
                        "%s: %s is %s, outside the scene's folder %s and the shared scenes folder (%s); move the file "
                        "into one of them, or pass --allow-outside-paths (allow_outside_paths of "
                        "ic_scene_load_options) to permit it",
                        where, desc, real[0] ? real : path, b->root_count ? b->roots[0] : "(unknown)",
                        shared[0] ? shared : "none found");
}

/* ------------------------------------------------------------------------------------------------ */
/* matrices */

void ic_mat4_identity(float m[16])
{
    for (int i = 0; i < 16; ++i)
        m[i] = (i % 5 == 0) ? 1.0f : 0.0f;
}

float ic_mat4_det3(const float m[16])
{
    return m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) + m[2] * (m[4] * m[9] - m[5] * m[8]);
}

void ic_mat4_mul(const float a[16], const float b[16], float out[16])
{
    float r[16];
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            float s = 0.0f;
            for (int k = 0; k < 4; ++k)
                s += a[4 * i + k] * b[4 * k + j];
            r[4 * i + j] = s;
        }
    memcpy(out, r, sizeof r);
}

/* ------------------------------------------------------------------------------------------------ */
/* textures */

/* Buckets of the linear range when texels are matched to bytes: 1/4096 is narrower than the gap between
 * any two bytes' linear values (the smallest, next to 0, is 1/3295). */
#define SRGB8_BUCKETS 4096

/* The n texel values as sRGB bytes when every one is exactly ic_srgb8_to_linear of a byte (the table
 * goes to linear); else NULL (HDR files, 16-bit files, or no memory), and the floats stay. */
static uint8_t *srgb8_texels(const float *rgb, size_t n, float linear[256])
{
    for (int v = 0; v < 256; ++v)
        linear[v] = ic_srgb8_to_linear((uint8_t)v);
    uint8_t *bytes = malloc(n ? n : 1);
    if (!bytes)
        return NULL;
    /* The encoder's byte at each bucket's low end: a texel's byte is its bucket's or a neighbour (without a
     * power function per texel). */
    uint8_t bucket_byte[SRGB8_BUCKETS + 1];
    for (int k = 0; k <= SRGB8_BUCKETS; ++k)
        bucket_byte[k] = ic_linear_to_srgb8((float)k / SRGB8_BUCKETS);
    for (size_t i = 0; i < n; ++i) {
        float x = rgb[i];
        /* The table increases, so the byte is the guess or a neighbour. */
        int guess = isfinite(x) && x >= 0.0f && x <= 1.0f ? bucket_byte[(int)(x * SRGB8_BUCKETS)] : -2, found = -1;
        for (int k = guess - 1; k <= guess + 1 && found < 0; ++k)
            if (k >= 0 && k < 256 && memcmp(&linear[k], &x, sizeof x) == 0)
                found = k;
        if (found < 0) {
            free(bytes);
            return NULL;
        }
        bytes[i] = (uint8_t)found;
    }
    return bytes;
}

/* 1 if the file at path holds values beyond 8 or 16 bits per channel (no sRGB curve to undo). */
static int is_hdr_path(const char *path)
{
    char ext[16];
    ic_path_extension(path, ext, sizeof ext);
    return !strcmp(ext, ".hdr") || !strcmp(ext, ".exr") || !strcmp(ext, ".pfm");
}

/* The first value of img that is not finite, or (allow_negative 0) negative: its index in rgb, or -1. */
static long long first_bad_texel(const ic_image *img, int allow_negative)
{
    for (size_t i = 0; i < (size_t)img->width * (size_t)img->height * 3; ++i)
        if (!isfinite(img->rgb[i]) || (!allow_negative && !(img->rgb[i] >= 0.0f)))
            return (long long)i;
    return -1;
}

static const char *const channel_name[3] = {"red", "green", "blue"};

/* A new texture slot at the end of the scene's textures, for path at width × height, without texels yet;
 * NULL when out of memory. */
static ic_texture *new_texture(ic_scene *scene, const char *path, int is_data, int width, int height)
{
    ic_texture *grown = realloc(scene->textures, sizeof *grown * (scene->texture_count + 1));
    if (!grown)
        return NULL;
    scene->textures = grown;
    ic_texture *t = &scene->textures[scene->texture_count];
    memset(t, 0, sizeof *t);
    snprintf(t->path, sizeof t->path, "%.1023s", path);
    t->width = width;
    t->height = height;
    t->is_data = is_data;
    return t;
}

/* The texture's texels as 8-bit sRGB bytes (owned by it from now on) and the values they stand for: the
 * decoder's sRGB curve, or v/255 for a data texture (no curve applies to roughness or a normal map). */
static void set_srgb8(ic_texture *t, uint8_t *bytes)
{
    t->srgb8 = bytes;
    for (int v = 0; v < 256; ++v)
        t->linear[v] = t->is_data ? (float)v / 255.0f : ic_srgb8_to_linear((uint8_t)v);
}

ic_result ic_scene_texture_add_as(ic_scene_builder *b, const char *path, int is_data, ic_image *img_in,
                                  const char *owner, int32_t *index, ic_error *err)
{
    ic_scene *scene = b->scene;
    ic_image img = *img_in;
    memset(img_in, 0, sizeof *img_in);
    /* A float texture (PFM, EXR, HDR) can hold what no material may: a NaN or infinite texel, or a
     * negative colour. Refused as an environment map's are, instead of dark walls or negative pixels. */
    long long bad = first_bad_texel(&img, is_data);
    if (bad >= 0) {
        size_t px = (size_t)bad / 3;
        ic_error_set(err, IC_ERR_INVALID_ARG,
                     "%s: texture '%s': texel (%zu, %zu) has a %s value of %g; a texture's values must be finite%s, "
                     "fix the file",
                     owner, path, px % (size_t)img.width, px / (size_t)img.width, channel_name[bad % 3],
                     (double)img.rgb[bad], is_data ? "" : " and >= 0");
        ic_image_free(&img);
        return IC_ERR_INVALID_ARG;
    }
    ic_texture *t = new_texture(scene, path, is_data, img.width, img.height);
    if (!t) {
        ic_image_free(&img);
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory loading texture '%s'", owner, path);
    }
    size_t n = (size_t)img.width * (size_t)img.height * 3;
    uint8_t *bytes = srgb8_texels(img.rgb, n, t->linear);
    if (bytes) {
        ic_image_free(&img);
        set_srgb8(t, bytes);
    } else {
        t->rgb = img.rgb; /* ownership moves to the scene; released with ic_image_free in ic_scene_free */
        if (is_data && !is_hdr_path(path)) /* a 16-bit file: undo the decoder's sRGB curve */
            for (size_t i = 0; i < n; ++i)
                t->rgb[i] = ic_linear_to_srgb(t->rgb[i]);
    }
    *index = (int32_t)scene->texture_count++;
    return IC_OK;
}

ic_result ic_scene_texture_load_as(ic_scene_builder *b, const char *path, int is_data, const char *owner,
                                   int32_t *index, ic_error *err)
{
    ic_scene *scene = b->scene;
    for (uint32_t i = 0; i < scene->texture_count; ++i)
        if (!strcmp(scene->textures[i].path, path) && scene->textures[i].is_data == is_data) {
            *index = (int32_t)i;
            return IC_OK;
        }
    if (!ic_path_exists(path)) {
        char abs_path[IC_SCENE_PATH_MAX];
        ic_path_absolute(path, abs_path, sizeof abs_path);
        return ic_error_set(err, IC_ERR_IO, "%s: texture '%s' %s (resolved to %s); check the path", owner, path,
                            ic_path_missing(path), abs_path);
    }
    ic_image img;
    ic_error ierr;
    uint8_t *bytes = NULL; /* an 8-bit file's texels, kept as they are */
    ic_result r = ic_image_read_texture(path, ic_scene_max_texture_pixels(b->opt), IC_SCENE_RAISE_TEXTURE_LIMIT, &img,
                                        &bytes, &ierr);
    if (r != IC_OK)
        return ic_error_set(err, r, "%s: %s", owner, ierr.message);
    if (!bytes)
        return ic_scene_texture_add_as(b, path, is_data, &img, owner, index, err);
    ic_texture *t = new_texture(scene, path, is_data, img.width, img.height);
    if (!t) {
        free(bytes);
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory loading texture '%s'", owner, path);
    }
    set_srgb8(t, bytes);
    *index = (int32_t)scene->texture_count++;
    return IC_OK;
}

ic_result ic_scene_texture_load(ic_scene_builder *b, const char *path, const char *owner, int32_t *index,
                                ic_error *err)
{
    return ic_scene_texture_load_as(b, path, 0, owner, index, err);
}

ic_result ic_scene_texture_add(ic_scene_builder *b, const char *path, ic_image *img_in, const char *owner,
                               int32_t *index, ic_error *err)
{
    return ic_scene_texture_add_as(b, path, 0, img_in, owner, index, err);
}

/* ------------------------------------------------------------------------------------------------ */
/* warnings */

ic_result ic_scene_check_env_map(const ic_image *m, ic_vec3 scale, const char *name, const char *file, int line,
                                 ic_error *err)
{
    /* Radiance is never negative: a negative or non-finite texel would give negative pixels and a broken
     * light-sampling distribution, so the map is refused rather than silently clamped. */
    long long bad = first_bad_texel(m, 0);
    if (bad >= 0) {
        size_t px = (size_t)bad / 3;
        return ic_error_set_at(err, IC_ERR_INVALID_ARG, file, line,
                               "environment map '%s': texel (%zu, %zu) has a %s value of %g; radiance must be "
                               "finite and >= 0, fix the map",
                               name, px % (size_t)m->width, px / (size_t)m->width, channel_name[bad % 3],
                               (double)m->rgb[bad]);
    }
    /* The radiance is the texel times the scale, in float: one beyond the float range would be inf where
     * the sampling tables give it no weight, and one near it overflows the estimates (IC_SCENE_MAX_RADIANCE). */
    const float sc[3] = {scale.x, scale.y, scale.z};
    const size_t n = (size_t)m->width * (size_t)m->height * 3;
    for (size_t i = 0; i < n; ++i)
        if (!((double)m->rgb[i] * sc[i % 3] <= (float)IC_SCENE_MAX_RADIANCE))
            return ic_error_set_at(err, IC_ERR_INVALID_ARG, file, line,
                                   "environment map '%s': texel (%zu, %zu) times the scale (%g × %g) is " IC_RADIANCE_LIMIT_FMT
                                   "; give a smaller scale",
                                   name, i / 3 % (size_t)m->width, i / 3 / (size_t)m->width, (double)m->rgb[i],
                                   (double)sc[i % 3], (double)m->rgb[i] * sc[i % 3], IC_SCENE_MAX_RADIANCE);
    return IC_OK;
}

void ic_scene_warn(ic_scene *s, const char *fmt, ...)
{
    char line[600];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    ic_text_one_line(line, sizeof line); /* one warning a line, whatever a file's name holds */
    size_t old = s->warnings ? strlen(s->warnings) : 0, add = strlen(line);
    char *grown = realloc(s->warnings, old + add + 2);
    if (!grown)
        return; /* a warning lost to a full memory is no reason to fail the load */
    memcpy(grown + old, line, add);
    grown[old + add] = '\n';
    grown[old + add + 1] = '\0';
    s->warnings = grown;
}

const char *ic_scene_warnings(const ic_scene *scene) { return scene && scene->warnings ? scene->warnings : ""; }

/* ------------------------------------------------------------------------------------------------ */
/* point and spot lights */

ic_result ic_scene_add_point_light(ic_scene *s, ic_vec3 position, ic_vec3 intensity, const ic_spot_cone *cone)
{
    uint32_t n = s->point_light_count;
    ic_point_light *grown = realloc(s->point_lights, sizeof *grown * (n + 1));
    if (!grown)
        return IC_ERR_OOM;
    s->point_lights = grown;
    if (cone || s->point_spots) {
        ic_spot_cone *spots = realloc(s->point_spots, sizeof *spots * (n + 1));
        if (!spots)
            return IC_ERR_OOM;
        if (!s->point_spots) /* the lights so far are points: no falloff */
            for (uint32_t i = 0; i < n; ++i)
                spots[i] = (ic_spot_cone){v3(0.0f, 0.0f, 1.0f), -1.0f, -2.0f};
        s->point_spots = spots;
        s->point_spots[n] = cone ? *cone : (ic_spot_cone){v3(0.0f, 0.0f, 1.0f), -1.0f, -2.0f};
    }
    s->point_lights[n].position = position;
    s->point_lights[n].intensity = intensity;
    s->point_light_count = n + 1;
    return IC_OK;
}

/* ------------------------------------------------------------------------------------------------ */
/* camera */

double ic_projection_extent(ic_projection p, double size, int is_horizontal)
{
    const double deg = 3.14159265358979323846 / 180.0;
    switch (p) {
    case IC_PROJECTION_PARALLEL: return size;
    case IC_PROJECTION_HEMISPHERICAL: return 2.0 * sin(0.5 * size * deg);
    case IC_PROJECTION_ANGULAR: return size / 180.0; /* in units of π: the circle's rim is at 1 */
    case IC_PROJECTION_CYLINDRICAL: return is_horizontal ? size * deg : 2.0 * tan(0.5 * size * deg);
    case IC_PROJECTION_STEREOGRAPHIC: return 2.0 * tan(0.25 * size * deg);
    default: return 2.0 * tan(0.5 * size * deg);
    }
}

void ic_scene_fit_camera(ic_scene *scene, int width, int height)
{
    ic_camera *cam = &scene->camera;
    ic_vec3 lo = scene->bounds_min, hi = scene->bounds_max;
    if (scene->triangle_count == 0) {
        lo = v3s(-1.0f);
        hi = v3s(1.0f);
    }
    ic_vec3 centre = v3_scale(v3_add(lo, hi), 0.5f);
    float radius = 0.5f * v3_len(v3_sub(hi, lo));
    if (!(radius > 0.0f))
        radius = 1.0f;
    cam->width = width;
    cam->height = height;
    cam->fov_y_deg = 45.0f;
    /* fit the bounding sphere into the narrower of the two fields of view */
    float half_y = 0.5f * cam->fov_y_deg * IC_PI / 180.0f;
    float half_x = atanf(tanf(half_y) * (float)width / (float)height);
    float half = fminf(half_x, half_y);
    float dist = radius / sinf(half);
    cam->target = centre;
    cam->eye = v3_add(centre, v3(0.0f, 0.0f, dist));
    cam->up = v3(0.0f, 1.0f, 0.0f);
}

/* ------------------------------------------------------------------------------------------------ */
/* finalize */

ic_result ic_scene_finalize(ic_scene_builder *b, ic_error *err)
{
    ic_scene *s = b->scene;
    /* an emitter all of whose faces were degenerate triangles, lines or points cannot emit: almost surely an
     * export bug (and silent otherwise, whatever other lights the scene has) */
    for (uint32_t m = 0; m < s->material_count; ++m) {
        if (v3_is_black(s->materials[m].emission))
            continue;
        if (b->material_tris[m] == 0 && b->material_dropped[m] > 0)
            return ic_error_set(err, IC_ERR_PARSE,
                                "%s: emissive material '%s' has zero total area (all %u of its faces are degenerate "
                                "triangles, lines or points); fix the light's geometry or remove its emission",
                                b->mesh_paths[b->material_mesh[m]], s->materials[m].name, b->material_dropped[m]);
    }
    /* not an error (exporters leave such slivers, and they cover nothing), but a count the user should see:
     * a mesh much sparser than expected, or a scale that collapses the geometry, shows here first */
    if (s->dropped_degenerate > 0)
        ic_scene_warn(s, "%s: %u triangle%s of zero area (collinear or repeated corners) dropped%s: %s nothing "
                         "(an image does not change without %s)",
                      b->dropped_where, s->dropped_degenerate, s->dropped_degenerate == 1 ? "" : "s",
                      s->dropped_degenerate == 1 ? "" : ", the first from here",
                      s->dropped_degenerate == 1 ? "it covers" : "they cover",
                      s->dropped_degenerate == 1 ? "it" : "them");
    for (uint32_t m = 0; m < s->material_count; ++m)
        s->has_normal_maps |= s->materials[m].normal_texture > 0;
    /* a rough plastic's diffuse base is scaled by what its coat does not reflect: tabulated once here */
    for (uint32_t m = 0; m < s->material_count; ++m) {
        ic_material *mat = &s->materials[m];
        if (mat->type != IC_MAT_PLASTIC)
            continue;
        /* the index the BSDF uses (bsdf.c): 1 is a coat that reflects nothing, not 1.5 */
        float ior = mat->ior > 0.0f ? mat->ior : 1.5f;
        ic_coat_albedo_table(ior, mat->alpha, mat->coat_albedo, &mat->coat_albedo_avg);
        if (mat->roughness_texture <= 0)
            continue;
        /* a textured roughness: one table per roughness step, the nearest used at each point */
        mat->coat_albedo_rough = malloc(sizeof(float) * IC_COAT_ROUGH_STEPS * (IC_COAT_TABLE + 1));
        if (!mat->coat_albedo_rough)
            return ic_error_set(err, IC_ERR_OOM, "%s: out of memory for material '%s'",
                                b->mesh_paths[b->material_mesh[m]], mat->name);
        const ic_material *same = NULL; /* the tables depend on the index alone: computed once per index */
        for (uint32_t k = 0; k < m && !same; ++k)
            if (s->materials[k].coat_albedo_rough && (s->materials[k].ior > 0.0f ? s->materials[k].ior : 1.5f) == ior)
                same = &s->materials[k];
        if (same)
            memcpy(mat->coat_albedo_rough, same->coat_albedo_rough,
                   sizeof(float) * IC_COAT_ROUGH_STEPS * (IC_COAT_TABLE + 1));
        for (int j = 0; j < IC_COAT_ROUGH_STEPS && !same; ++j) {
            float r = (float)j / (IC_COAT_ROUGH_STEPS - 1), *t = mat->coat_albedo_rough + j * (IC_COAT_TABLE + 1);
            ic_coat_albedo_table(ior, r * r, t, &t[IC_COAT_TABLE]);
        }
    }
    if (s->triangle_count > 0) {
        ic_vec3 lo = v3s(INFINITY), hi = v3s(-INFINITY);
        for (uint32_t i = 0; i < 3 * s->triangle_count; ++i) {
            ic_vec3 p = s->positions[s->triangles[i]];
            lo = v3_min(lo, p);
            hi = v3_max(hi, p);
        }
        s->bounds_min = lo;
        s->bounds_max = hi;
        const float extent = fmaxf(fmaxf(fmaxf(fabsf(lo.x), fabsf(hi.x)), fmaxf(fabsf(lo.y), fabsf(hi.y))),
                                   fmaxf(fabsf(lo.z), fabsf(hi.z)));
        s->ray_offset_floor = IC_RAY_OFFSET_FLOOR * (extent > 0.0f && extent < 1.0f ? extent : 1.0f);
    } else {
        s->ray_offset_floor = IC_RAY_OFFSET_FLOOR;
    }
    return ic_scene_build_lights(s, err);
}

ic_result ic_scene_finalize_and_fit(ic_scene_builder *b, int has_camera, ic_error *err)
{
    ic_result r = ic_scene_finalize(b, err);
    if (r == IC_OK && !has_camera)
        ic_scene_fit_camera(b->scene, b->opt->width > 0 ? b->opt->width : IC_DEFAULT_WIDTH,
                            b->opt->height > 0 ? b->opt->height : IC_DEFAULT_HEIGHT);
    return r;
}

/* ------------------------------------------------------------------------------------------------ */
/* load / free */

void ic_scene_builder_release(ic_scene_builder *b)
{
    free(b->material_dropped);
    free(b->material_tris);
    free(b->material_mesh);
    for (uint32_t i = 0; i < b->mesh_count; ++i)
        free(b->mesh_paths[i]);
    free(b->mesh_paths);
    memset(b, 0, sizeof *b);
}

void ic_scene_free(ic_scene *s)
{
    if (!s)
        return;
    free(s->positions);
    free(s->normals);
    free(s->uvs);
    free(s->tangents);
    free(s->triangles);
    free(s->triangle_material);
    for (uint32_t i = 0; i < s->material_count; ++i)
        free(s->materials[i].coat_albedo_rough);
    free(s->materials);
    for (uint32_t i = 0; i < s->texture_count; ++i) {
        ic_image img = {s->textures[i].width, s->textures[i].height, s->textures[i].rgb};
        if (img.rgb)
            ic_image_free(&img);
        free(s->textures[i].srgb8);
    }
    free(s->textures);
    free(s->tri_lights);
    free(s->tri_light_cdf);
    free(s->triangle_light);
    free(s->point_lights);
    free(s->point_light_cdf);
    free(s->point_spots);
    free(s->warnings);
    for (uint32_t i = 0; i < s->file_count; ++i)
        free(s->files[i]);
    free(s->files);
    ic_image_free(&s->env.image);
    free(s->env.marginal_cdf);
    free(s->env.conditional_cdf);
    free(s->env.portals);
    free(s);
}
