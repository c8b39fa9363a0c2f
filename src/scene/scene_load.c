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
    if (r != IC_OK) {
        ic_scene_free(s);
        return r;
    }
    *out = s;
    return IC_OK;
}
