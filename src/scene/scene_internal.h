/*
 * scene_internal.h — what the scene module's files share and nobody else needs.
 *
 * Loading runs in three steps: the front end (scene_json.c for a JSON file, scene.c for a bare mesh)
 * appends meshes through mesh_import.c into a builder, edits materials and lights, and finally
 * ic_scene_finalize() validates what only the whole scene can tell (emitters of zero area), computes
 * bounds and builds the light-sampling tables (lights.c).
 */
#ifndef IC_SCENE_INTERNAL_H
#define IC_SCENE_INTERNAL_H

#include "scene/scene.h"

#include "core/path.h"

#include <stddef.h>
#include <stdio.h>

/* Longest path the loader handles. */
#define IC_SCENE_PATH_MAX 4096
/* The scene file's folder and up to four shared scenes folders (option, $IRRCACHE_SCENES, two fallbacks). */
#define IC_SCENE_MAX_ROOTS 5

/* State kept while a scene is being assembled. */
typedef struct ic_scene_builder {
    ic_scene *scene;
    uint32_t *material_dropped; /* per material: degenerate triangles, lines and points dropped (material_count) */
    uint32_t *material_tris;    /* per material: triangles kept (material_count) */
    uint32_t *material_mesh;    /* per material: index into mesh_paths of the file that defined it */
    char **mesh_paths;          /* every imported mesh file, for messages (mesh_count) */
    uint32_t mesh_count;
    const ic_scene_load_options *opt; /* the caller's load options (never NULL) */
    /* The folders the scene's files may be read from, as real paths (docs/scene-format.md, "Paths"): [0] the
     * scene file's folder (a bare mesh's own), then the shared scenes folders that exist. */
    char roots[IC_SCENE_MAX_ROOTS][IC_SCENE_PATH_MAX];
    int root_count;
    const char *import_where; /* while a mesh is imported: "scene.json:12" (its path's line) or the bare mesh */
    char dropped_where[IC_SCENE_PATH_MAX + 32]; /* where the first zero-area triangle was dropped ("" if none) */
} ic_scene_builder;

/* Adds dir's real path to b->roots (nothing if it does not exist or is there already). */
void ic_scene_add_root(ic_scene_builder *b, const char *dir);
/* 1 if path may be read: allow_outside_paths is set, or its real path lies in one of b->roots. *real gets
 * the real path ("" where realpath fails: then 0 unless allowed, as nothing is there to read). A path that
 * exists is noted among the scene's files (ic_scene_note_file): every file a loader reads is asked for here
 * first (the scene file and a Radiance view file excepted, noted by their loaders). */
int ic_scene_path_allowed(const ic_scene_builder *b, const char *path, char *real, size_t size);
/* Adds the real path of path to s->files (ic_scene_file: the files an output must not overwrite), once;
 * nothing if it does not exist; s->files_lost when memory runs out (ic_scene_load then fails). */
void ic_scene_note_file(ic_scene *s, const char *path);
/* IC_OK if path may be read; else the one-line error "where: desc is REAL, outside the scene's folder ...;
 * ... --allow-outside-paths ...". desc names the path as the scene gave it ("mesh '../a.obj'"). */
ic_result ic_scene_check_path(const ic_scene_builder *b, const char *path, const char *where, const char *desc,
                              ic_error *err);

/* IC_OK if every texel of environment map m (named name in the scene) is finite and >= 0, and times scale
 * within the float range; else the one-line error "file:line: environment map 'name': texel (x, y) has a
 * red value of -2; ..." (or "... times the scale ... is beyond the float range; ..."). */
ic_result ic_scene_check_env_map(const ic_image *m, ic_vec3 scale, const char *name, const char *file, int line,
                                 ic_error *err);

/* The limits of opt with their defaults filled in. */
static inline size_t ic_scene_max_texture_pixels(const ic_scene_load_options *opt)
{
    return opt && opt->max_texture_pixels > 0 ? (size_t)opt->max_texture_pixels : IC_DEFAULT_MAX_TEXTURE_PIXELS;
}
static inline size_t ic_scene_max_mesh_elements(const ic_scene_load_options *opt)
{
    return opt && opt->max_mesh_elements > 0 ? (size_t)opt->max_mesh_elements : IC_DEFAULT_MAX_MESH_ELEMENTS;
}
/* What to do when a texture is over its limit (the end of the message). */
#define IC_SCENE_RAISE_TEXTURE_LIMIT "raise the limit with --max-texture-pixels (max_texture_pixels of ic_scene_load_options)"

/* Adds a decoded image as a texture labelled path (a file's path, or "model.glb#*0" for an embedded one),
 * taking its pixels (img is zeroed); *index gets its index. */
ic_result ic_scene_texture_add(ic_scene_builder *b, const char *path, ic_image *img, const char *owner, int32_t *index,
                               ic_error *err);
/* A point and a direction (normalised) through a row-major 4x4 transform (scene files' transforms). */
static inline ic_vec3 ic_xform_point(const float m[16], ic_vec3 p)
{
    return v3(m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
              m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]);
}
static inline ic_vec3 ic_xform_dir(const float m[16], ic_vec3 d)
{
    return v3_norm(v3(m[0] * d.x + m[1] * d.y + m[2] * d.z, m[4] * d.x + m[5] * d.y + m[6] * d.z,
                      m[8] * d.x + m[9] * d.y + m[10] * d.z));
}

/* Appends one line to the scene's warnings (ic_scene_warnings). */
void ic_scene_warn(ic_scene *s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Appends a material of its own (source names the file it comes from, for messages); *index gets its index. */
ic_result ic_scene_add_material(ic_scene_builder *b, const ic_material *m, const char *source, uint32_t *index,
                                ic_error *err);
/* Appends triangles (tri: tri_count × 3 indices into p; n: unit normals or NULL) of one material, transformed by
 * the row-major 4x4 xform; degenerate ones are dropped and counted. where names the shape in messages. */
ic_result ic_scene_append_triangles(ic_scene_builder *b, const ic_vec3 *p, const ic_vec3 *n, uint32_t vertex_count,
                                    const uint32_t *tri, uint32_t tri_count, uint32_t material, const float xform[16],
                                    const char *where, ic_error *err);
/* Reads a Mitsuba 0.6/3 XML scene (mitsuba_scene.c). */
ic_result ic_scene_load_mitsuba(ic_scene_builder *b, const char *path, const ic_scene_load_options *opt, ic_error *err);
/* Reads a Radiance .rad scene (radiance_scene.c) and the view file opt->view names. */
ic_result ic_scene_load_radiance(ic_scene_builder *b, const char *path, const ic_scene_load_options *opt, ic_error *err);
/* Appends a point light, a spot light when cone is given; IC_ERR_OOM leaves the scene as it was. */
ic_result ic_scene_add_point_light(ic_scene *s, ic_vec3 position, ic_vec3 intensity, const ic_spot_cone *cone);
/* Reads the cameras and KHR_lights_punctual lights of the glTF file at path (gltf_scene.c) into the scene:
 * the camera named camera_name (NULL: the first perspective camera met walking the default scene's nodes),
 * point and spot lights, and directional lights (the first as the sun). *has_camera is 1 if a camera was
 * set; *light_count gets the number of lights added. */
ic_result ic_gltf_read_scene(ic_scene_builder *b, const char *path, const char *camera_name, int *has_camera,
                             int *light_count, ic_error *err);

/* Releases the builder's own arrays (not the scene). */
void ic_scene_builder_release(ic_scene_builder *b);

/* The largest radiance (W/(m²·sr)), irradiance (W/m²) or radiant intensity (W/sr) a scene may give, per
 * colour component: an emission, a constant environment, an environment map's texel times its scale, a
 * sky's zenith radiance and irradiances, a point, spot or sun light. The estimators multiply such a value
 * by 1/pdf, an inverse squared distance or a BSDF and sum samples in float: near FLT_MAX (3.4e38) a sample
 * overflowed and was dropped as not finite (a constant environment of 3e38 read 0, one of 1e38 gave half
 * its irradiance). A value is compared as a float, so 1e30 as written passes. */
#define IC_SCENE_MAX_RADIANCE 1e30
/* 1 if a component of v is above IC_SCENE_MAX_RADIANCE (or not a number). */
static inline int ic_radiance_too_large(ic_vec3 v)
{
    const float cap = (float)IC_SCENE_MAX_RADIANCE;
    return !(v.x <= cap && v.y <= cap && v.z <= cap);
}
/* A message on such a value: "... is " IC_RADIANCE_LIMIT_FMT "; " IC_RADIANCE_LIMIT_FIX with the arguments
 * IC_RADIANCE_LIMIT_ARGS(v) ("... is 2e+31, above 1e+30, the largest ...; scale the scene's lights down ..."). */
#define IC_RADIANCE_LIMIT_FMT                                                                                    \
    "%g, above %g, the largest radiance, irradiance or intensity a scene may give (beyond it the estimates "     \
    "overflow)"
#define IC_RADIANCE_LIMIT_ARGS(v) (double)v3_maxc(v), IC_SCENE_MAX_RADIANCE
#define IC_RADIANCE_LIMIT_FIX "scale the scene's lights down alike (--exposure brightens the image back)"

/* Largest world coordinate accepted: twice its square, a triangle's cross product, stays finite in float. */
#define IC_SCENE_MAX_COORD 1e18f

/* Appends every triangle and material of a mesh file (assimp) to the scene, transformed by the
 * row-major 4x4 matrix xform (NULL: identity). Degenerate triangles are dropped and counted.
 * xform_where ("scene.json:12", or NULL) names the transform in messages about what it did to a vertex. */
ic_result ic_mesh_import(ic_scene_builder *b, const char *mesh_path, const float *xform, const char *xform_where,
                         ic_error *err);

/* Puts the sky p describes into the scene (scene_sky.c): as the environment (with_sky, radiance × scale)
 * and its sun, if it has one, as the scene's sun disc (with_sun, irradiance × scale). IC_ERR_INVALID_ARG
 * when p is no valid sky, IC_ERR_UNSUPPORTED when the scene has a sun already; why says what (no prefix). */
ic_result ic_scene_install_sky(ic_scene *s, const ic_sky_params *p, int with_sky, int with_sun, float scale,
                               char *why, size_t why_size);

/* Appends shape shape_index of a Mitsuba serialized mesh file (mesh_serialized.c) with one material,
 * transformed by the row-major 4x4 xform: positions, vertex normals, triangles (texture coordinates and
 * colours are not read). where ("scene.xml:12") names the shape in messages. */
ic_result ic_mesh_read_serialized(ic_scene_builder *b, const char *path, uint32_t shape_index, uint32_t material,
                                  const float xform[16], const char *where, ic_error *err);

/* Loads (or finds already loaded) the texture at path into scene->textures; *index receives its
 * index. `owner` names who asked for it in messages ("mesh.obj: material 'wood'"). */
ic_result ic_scene_texture_load(ic_scene_builder *b, const char *path, const char *owner, int32_t *index,
                                ic_error *err);

/* ic_scene_texture_load and ic_scene_texture_add for a texture of values rather than colours when is_data
 * is 1 (roughness, metallic, normal maps: ic_texture's is_data); a file loaded both ways is two textures. */
ic_result ic_scene_texture_load_as(ic_scene_builder *b, const char *path, int is_data, const char *owner,
                                   int32_t *index, ic_error *err);
ic_result ic_scene_texture_add_as(ic_scene_builder *b, const char *path, int is_data, ic_image *img,
                                  const char *owner, int32_t *index, ic_error *err);

/* Validates, computes bounds and builds the light tables. `where` names the scene for messages. */
ic_result ic_scene_finalize(ic_scene_builder *b, ic_error *err);
/* A loader's last step: ic_scene_finalize, then, unless the file gave a camera (has_camera), a fitted one
 * (ic_scene_fit_camera) as wide and high as the load options ask, else the defaults. */
ic_result ic_scene_finalize_and_fit(ic_scene_builder *b, int has_camera, ic_error *err);

/* Builds tri_lights, the CDFs, the environment importance tables and the light selection (lights.c). */
ic_result ic_scene_build_lights(ic_scene *scene, ic_error *err);
/* Portals (portals.c): appends the parallelogram with these corners, in order around it (refused with a
 * message if degenerate or not a parallelogram); sums their area (from ic_scene_build_lights). */
ic_result ic_scene_add_portal(ic_scene *scene, const ic_vec3 corners[4], ic_error *err);
ic_result ic_scene_build_portals(ic_scene *scene, ic_error *err);

/* Camera looking at the bounds' centre from +z, vertical fov 45°, framing the bounding sphere. */
void ic_scene_fit_camera(ic_scene *scene, int width, int height);

/* JSON front end (scene_json.c; its sections in scene_json_*.c): fills b->scene from the scene file at path. */
ic_result ic_scene_load_json(ic_scene_builder *b, const char *path, const ic_scene_load_options *opt,
                             ic_error *err);

/* Path helpers (scene.c). */
int ic_path_exists(const char *path);                  /* regular file that can be opened */
/* Why ic_path_exists(path) is 0, for messages: "not found", or "is not a regular file (a folder, pipe or
 * device)" where something else is there. */
const char *ic_path_missing(const char *path);
/* dir/rel unless rel is absolute; backslashes in rel become slashes. Returns 0 if it does not fit. */
int ic_path_join(const char *dir, const char *rel, char *out, size_t size);
/* Absolute form of path for messages (directory part resolved with realpath where it exists). */
void ic_path_absolute(const char *path, char *out, size_t size);
/* Lower-case extension including the dot ("" if none). */
void ic_path_extension(const char *path, char *ext, size_t size);

/* Row-major 4x4 matrix helpers for transforms. */
void ic_mat4_identity(float m[16]);
void ic_mat4_mul(const float a[16], const float b[16], float out[16]);
/* The determinant of the upper-left 3x3 (negative: the transform mirrors). */
float ic_mat4_det3(const float m[16]);

#endif
