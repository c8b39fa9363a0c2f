/*
 * scene_load.c — ic_scene_load, the loading entry point: it picks the front end by extension. ".json"
 * goes to scene_json.c, ".xml" (a Mitsuba scene) to mitsuba_scene.c, ".rad" (a Radiance scene, with the view
 * file of opt->view) to radiance_scene.c; a bare mesh (.obj .gltf .glb .ply, or any of these gzip-compressed as
 * NAME.EXT.gz) is imported as is and gets a fitted camera
 * and, when it has no emitter, a constant white sky (radiance 1), so any mesh renders without a scene
 * file (docs/scene-format.md). A glTF file brings its own camera and lights (gltf_scene.c) where it has them.
 */
#include "scene/scene_internal.h"

#include "core/vecmath.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static ic_result load_bare_mesh(ic_scene_builder *b, const char *path, const ic_scene_load_options *opt,
                                ic_error *err)
{
    if (!ic_path_exists(path)) {
        char abs_path[IC_SCENE_PATH_MAX];
        ic_path_absolute(path, abs_path, sizeof abs_path);
        return ic_error_set(err, IC_ERR_IO, "%s: mesh %s (resolved to %s); check the path", path,
                            ic_path_missing(path), abs_path);
    }
    b->import_where = path;
    ic_result r = ic_mesh_import(b, path, NULL, NULL, err);
    if (r != IC_OK)
        return r;
    ic_scene *s = b->scene;
    /* a glTF file is a whole scene: its camera and lights (not read from a gzip-compressed one) */
    char ext[16];
    ic_path_extension(path, ext, sizeof ext);
    int has_camera = 0, light_count = 0;
    if (!strcmp(ext, ".gltf") || !strcmp(ext, ".glb")) {
        r = ic_gltf_read_scene(b, path, opt->camera, &has_camera, &light_count, err);
        if (r != IC_OK)
            return r;
    } else if (opt->camera && opt->camera[0]) {
        return ic_error_set(err, IC_ERR_INVALID_ARG,
                            "%s: a camera name (--camera %s) is for glTF files (.gltf, .glb); other meshes get a "
                            "fitted camera",
                            path, opt->camera);
    }
    int has_emitter = light_count > 0;
    for (uint32_t m = 0; m < s->material_count; ++m)
        if (!v3_is_black(s->materials[m].emission) && b->material_tris[m] > 0)
            has_emitter = 1;
    if (!has_emitter) {
        s->env.enabled = 1;
        s->env.radiance = v3s(1.0f);
    }
    return ic_scene_finalize_and_fit(b, has_camera, err);
}

static int far_or_nan(ic_vec3 v)
{
    return !(fabsf(v.x) <= 1e18f && fabsf(v.y) <= 1e18f && fabsf(v.z) <= 1e18f);
}

/* What every importer's camera and lights must be for the ray tracer to start rays (Embree asserts on a
 * ray beyond about 1.8e19 or not finite): checked once here, whatever the format, since a NaN in a Mitsuba
 * matrix, a glTF camera node moved 1e30 away or a Radiance view's -vp 0 -1e30 0 aborted the process. */
static ic_result check_camera_and_lights(const ic_scene *s, const char *path, ic_error *err)
{
    const ic_camera *c = &s->camera;
    ic_vec3 dir = v3_sub(c->target, c->eye);
    const char *why = far_or_nan(c->eye) ? "its position is not finite or lies beyond 1e18"
                      : far_or_nan(c->target) || !(v3_len2(dir) > 0.0f) || !isfinite(v3_len2(dir))
                          ? "its view direction is zero or not finite"
                      : far_or_nan(c->up) || !(v3_len2(v3_cross(dir, c->up)) > 0.0f) ||
                              !isfinite(v3_len2(v3_cross(dir, c->up)))
                          ? "its up direction is zero, not finite or along the view"
                      : !(c->fov_y_deg > 0.0f && c->fov_y_deg < 180.0f) && c->projection == 0
                          ? "its field of view is not between 0 and 180 degrees"
                      : !(fabsf(c->size_x) <= 1e18f && fabsf(c->size_y) <= 1e18f && fabsf(c->clip_near) <= 1e18f &&
                          fabsf(c->shift) <= 1e6f && fabsf(c->lift) <= 1e6f)
                          ? "a view size, shift or clipping distance is not finite or beyond 1e18"
                          : NULL;
    if (why)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: the camera is unusable: %s; fix the scene's camera (or view)",
                            path, why);
    for (uint32_t k = 0; k < s->point_light_count; ++k)
        if (far_or_nan(s->point_lights[k].position) || !v3_is_finite(s->point_lights[k].intensity))
            return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: point light %u has a position that is not finite or "
                                "lies beyond 1e18, or an intensity that is not finite; fix it", path, k + 1);
    if (s->sun.enabled && (!v3_is_finite(s->sun.direction) || !(v3_len2(s->sun.direction) > 0.0f) ||
                           !v3_is_finite(s->sun.irradiance)))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: the sun's direction is zero or not finite, or its irradiance "
                            "is not finite; fix it", path);
    /* Every light at most IC_SCENE_MAX_RADIANCE: the loaders say so where the file gives the value; what they
     * derive (a Radiance scene's wide sources summed into the environment, a glTF file's second sun made a
     * point light far away) is checked here. A map's texels and a sky were checked with their scale. */
    for (uint32_t m = 0; m < s->material_count; ++m)
        if (ic_radiance_too_large(s->materials[m].emission))
            return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: material '%s' emits a radiance of " IC_RADIANCE_LIMIT_FMT
                                "; " IC_RADIANCE_LIMIT_FIX, path, s->materials[m].name,
                                IC_RADIANCE_LIMIT_ARGS(s->materials[m].emission));
    for (uint32_t k = 0; k < s->point_light_count; ++k)
        if (ic_radiance_too_large(s->point_lights[k].intensity))
            return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: point light %u's intensity is " IC_RADIANCE_LIMIT_FMT
                                "; " IC_RADIANCE_LIMIT_FIX, path, k + 1,
                                IC_RADIANCE_LIMIT_ARGS(s->point_lights[k].intensity));
    if (s->sun.enabled && ic_radiance_too_large(s->sun.irradiance))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: the sun's irradiance is " IC_RADIANCE_LIMIT_FMT "; "
                            IC_RADIANCE_LIMIT_FIX, path, IC_RADIANCE_LIMIT_ARGS(s->sun.irradiance));
    if (s->env.enabled && s->env.image.width == 0 && ic_radiance_too_large(s->env.radiance))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: the environment's radiance is " IC_RADIANCE_LIMIT_FMT "; "
                            IC_RADIANCE_LIMIT_FIX, path, IC_RADIANCE_LIMIT_ARGS(s->env.radiance));
    return IC_OK;
}

ic_result ic_scene_load(const char *path, const ic_scene_load_options *opt, ic_scene **out, ic_error *err)
{
    static const ic_scene_load_options defaults = {0};
    if (!out)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "ic_scene_load: no output pointer given");
    *out = NULL;
    if (!path || !*path)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "empty scene path; give a .json scene or a mesh file");
    if (!opt)
        opt = &defaults;
    if (opt->width < 0 || opt->height < 0)
        return ic_error_set(err, IC_ERR_INVALID_ARG,
                            "%s: resolution override %dx%d is negative; give positive width and height", path,
                            opt->width, opt->height);
    if (strlen(path) >= sizeof((ic_scene *)0)->path)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: path too long; use a shorter path", path);
    /* Looked at before anything reads it: a folder, a pipe (whose open would wait for a writer) or a
     * device (/dev/zero: endless) is no scene. A path that does not exist gets its own message below. */
    struct stat st;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode))
        return ic_error_set(err, IC_ERR_INVALID_ARG,
                            "%s: is a folder, not a scene; give a .json scene or a mesh file in it", path);
    if (stat(path, &st) == 0 && !S_ISREG(st.st_mode))
        return ic_error_set(err, IC_ERR_INVALID_ARG,
                            "%s: is not a regular file (a pipe, device or socket); give a .json scene or a mesh file",
                            path);

    ic_scene *s = calloc(1, sizeof *s);
    if (!s)
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory", path);
    snprintf(s->path, sizeof s->path, "%s", path);
    ic_scene_note_file(s, path);
    ic_scene_builder b;
    memset(&b, 0, sizeof b);
    b.scene = s;
    b.opt = opt;
    char scene_dir[IC_SCENE_PATH_MAX];
    ic_path_dirname(path, scene_dir, sizeof scene_dir);
    ic_scene_add_root(&b, scene_dir); /* the scene's folder tree (a bare mesh's own): roots[0] */

    char ext[16], mesh_ext[16] = "";
    ic_path_extension(path, ext, sizeof ext);
    if (!strcmp(ext, ".gz")) { /* NAME.EXT.gz: a compressed mesh of type EXT */
        char inner[IC_SCENE_PATH_MAX];
        snprintf(inner, sizeof inner, "%.*s", (int)(strlen(path) - 3), path);
        ic_path_extension(inner, mesh_ext, sizeof mesh_ext);
    } else {
        snprintf(mesh_ext, sizeof mesh_ext, "%s", ext);
    }
    ic_result r;
    if (opt->view && opt->view[0] && strcmp(ext, ".rad")) {
        r = ic_error_set(err, IC_ERR_INVALID_ARG,
                         "%s: a view file (--view %s) is for Radiance scenes (.rad); this scene has its own camera or "
                         "gets a fitted one",
                         path, opt->view);
    } else if ((!strcmp(ext, ".json") || !strcmp(ext, ".xml") || !strcmp(ext, ".rad")) && opt->camera && opt->camera[0]) {
        r = ic_error_set(err, IC_ERR_INVALID_ARG,
                         "%s: a camera name (--camera %s) is for glTF files; this scene has its own camera", path,
                         opt->camera);
    } else if (!strcmp(ext, ".json")) {
        r = ic_scene_load_json(&b, path, opt, err);
    } else if (!strcmp(ext, ".xml")) {
        r = ic_scene_load_mitsuba(&b, path, opt, err);
    } else if (!strcmp(ext, ".rad")) {
        r = ic_scene_load_radiance(&b, path, opt, err);
    } else if (!strcmp(mesh_ext, ".obj") || !strcmp(mesh_ext, ".gltf") || !strcmp(mesh_ext, ".glb") ||
               !strcmp(mesh_ext, ".ply")) {
        r = load_bare_mesh(&b, path, opt, err);
    } else {
        r = ic_error_set(err, IC_ERR_UNSUPPORTED,
                         "%s: unknown scene type '%s%s'; give a .json, Mitsuba .xml or Radiance .rad scene or a .obj, .gltf, .glb "
                         "or .ply mesh (or one of these gzip-compressed, as .obj.gz)",
                         path, strcmp(ext, ".gz") ? "" : mesh_ext, ext);
    }
    ic_scene_builder_release(&b);
    if (r == IC_OK)
        r = check_camera_and_lights(s, path, err);
    if (r == IC_OK && s->files_lost) /* an incomplete list would let an output overwrite a file left out */
        r = ic_error_set(err, IC_ERR_OOM, "%s: out of memory listing the files the scene reads", path);
    if (r != IC_OK) {
        ic_scene_free(s);
        return r;
    }
    *out = s;
    return IC_OK;
}
