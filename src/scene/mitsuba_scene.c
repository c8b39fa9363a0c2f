/*
 * mitsuba_scene.c — Mitsuba 0.6 and 3 XML scene files, the subset the public research scenes use, parsed
 * with libxml2 (no network access, no entity expansion) and mapped onto irrcache's scene:
 *
 *   sensor perspective (fov, fovAxis, toWorld: lookat / matrix / translate / rotate / scale), its film's
 *   width and height, its sampler's sampleCount; shapes obj, ply (through assimp), rectangle, disk, cube,
 *   sphere, with toWorld and flipNormals; BSDFs diffuse, plastic / roughplastic, conductor / roughconductor
 *   (named materials or eta/k), dielectric / roughdielectric, twosided, by reference or inline; area, point,
 *   spot, constant, envmap and directional emitters; <default> parameters and $name substitution.
 *
 * Every other element is named in one warning per kind (element, type and file:line) and skipped or
 * approximated as the warning says; nothing is dropped silently. Roughness distributions other than GGX
 * are rendered as GGX of the same α. Directions: Mitsuba's sensor looks down its +Z with +Y up, its +X
 * the image's left. Where Mitsuba 2 and 3 changed a default, the file's <scene version> decides.
 */
#include "scene/mitsuba_internal.h"
#include "scene/tessellate.h"

#include "core/read_file.h"
#include "core/vecmath.h"
#include "irrcache/defaults.h"

#include <libxml/parser.h>

#include <ctype.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- sensor ---- */

static ic_result parse_sensor(ic_mts_ctx *c, const xmlNode *n)
{
    char type_buf[64];
    const char *type = ic_mts_attr_copy(c, n, "type", type_buf, sizeof type_buf);
    if (!type || (strcmp(type, "perspective") && strcmp(type, "thinlens"))) {
        ic_mts_warn_once(c, n, "<sensor> of this type", "is not supported: the camera is fitted to the scene");
        return IC_OK;
    }
    if (!strcmp(type, "thinlens"))
        ic_mts_warn_once(c, n, "<sensor type=\"thinlens\">", "is rendered as a pinhole (no depth of field)");
    float m[16], fov = 0.0f, w = 768.0f, h = 576.0f, spp = 0.0f;
    int diagonal_fov = 0; /* a focal length's field of view is the diagonal's */
    ic_result r = ic_mts_to_world(c, n, m);
    if (r == IC_OK)
        r = ic_mts_float(c, n, "fov", 0.0f, &fov);
    if (r == IC_OK && fov == 0.0f) {
        float focal = 0.0f;
        const char *fl = ic_mts_string(c, n, "focalLength");
        if (!fl)
            fl = ic_mts_string(c, n, "focal_length");
        /* Mitsuba turns a focal length into the field of view across the 35 mm frame's diagonal (36 x 24
         * mm), on the diagonal axis; its default is 50 mm */
        if (!(fl && sscanf(fl, "%fmm", &focal) == 1 && focal > 0.0f))
            focal = 50.0f;
        fov = 2.0f * atanf(sqrtf(36.0f * 36.0f + 24.0f * 24.0f) / (2.0f * focal)) * 180.0f / IC_PI;
        diagonal_fov = 1;
    }
    if (r != IC_OK)
        return r;
    if (!(fov > 0.0f && fov < 180.0f))
        return ic_mts_fail(c, n, IC_ERR_INVALID_ARG, "fov must be in (0, 180) degrees", NULL);
    for (xmlNode *k = n->children; k && r == IC_OK; k = k->next) {
        if (ic_mts_is_element(k, "film")) {
            r = ic_mts_float(c, k, "width", w, &w);
            if (r == IC_OK)
                r = ic_mts_float(c, k, "height", h, &h);
        } else if (ic_mts_is_element(k, "sampler")) {
            r = ic_mts_float(c, k, "sampleCount", 0.0f, &spp);
            if (r == IC_OK && spp == 0.0f)
                r = ic_mts_float(c, k, "sample_count", 0.0f, &spp);
        }
    }
    if (r != IC_OK)
        return r;
    if (!(w >= 1.0f && h >= 1.0f && w <= 65536.0f && h <= 65536.0f))
        return ic_mts_fail(c, n, IC_ERR_INVALID_ARG, "the film's width and height must be in [1, 65536]", NULL);
    ic_camera *cam = &c->b->scene->camera;
    cam->width = c->opt->width > 0 ? c->opt->width : (int)w;
    cam->height = c->opt->height > 0 ? c->opt->height : (int)h;
    /* fovAxis: x (default), y, diagonal, smaller, larger */
    const char *axis = diagonal_fov ? "diagonal" : ic_mts_string(c, n, "fovAxis"); /* Mitsuba 3: fov_axis */
    float aw = (float)cam->width, ah = (float)cam->height, t = tanf(0.5f * fov * IC_PI / 180.0f);
    if (!axis || !strcmp(axis, "x") || (!strcmp(axis, "smaller") && aw <= ah) || (!strcmp(axis, "larger") && aw >= ah))
        t *= ah / aw;
    else if (!strcmp(axis, "diagonal"))
        t *= ah / sqrtf(aw * aw + ah * ah);
    else if (strcmp(axis, "y") && strcmp(axis, "smaller") && strcmp(axis, "larger"))
        return ic_mts_fail(c, n, IC_ERR_INVALID_ARG, "unknown fovAxis; use x, y, diagonal, smaller or larger", NULL);
    /* Mitsuba turns the camera-space ray (u, v, 1) by toWorld's linear part: a scale of the camera's own
     * axes (before the lookat) stretches the frustum by s_y/s_z vertically and s_x/s_z across, which for
     * s_x = s_y is another field of view; square pixels cannot show s_x ≠ s_y, nor a shear */
    const ic_vec3 ax = v3(m[0], m[4], m[8]), ay = v3(m[1], m[5], m[9]), az = v3(m[2], m[6], m[10]); /* its columns */
    const float lx = v3_len(ax), ly = v3_len(ay), lz = v3_len(az);
    if (!(lx > 0.0f && ly > 0.0f && lz > 0.0f && isfinite(lx * ly * lz)))
        return ic_mts_fail(c, n, IC_ERR_INVALID_ARG, "toWorld collapses or overflows the camera's axes",
                           "; give a transform of finite, non-zero scale");
    t *= ly / lz;
    if (fabsf(lx / ly - 1.0f) > 1e-4f || fabsf(v3_dot(ax, ay)) > 1e-4f * lx * ly ||
        fabsf(v3_dot(ax, az)) > 1e-4f * lx * lz || fabsf(v3_dot(ay, az)) > 1e-4f * ly * lz)
        ic_mts_warn_once(c, n, "<sensor> toWorld that stretches the image unevenly or shears it",
                         "is rendered with square pixels: only its vertical stretch is applied");
    if (!(t > 0.0f && t < 1e6f))
        return ic_mts_fail(c, n, IC_ERR_INVALID_ARG, "toWorld's scale makes the field of view 0 or 180 degrees",
                           "; give a milder scale");
    cam->fov_y_deg = 2.0f * atanf(t) * 180.0f / IC_PI;
    cam->eye = ic_xform_point(m, v3s(0.0f));
    cam->target = v3_add(cam->eye, ic_xform_dir(m, v3(0.0f, 0.0f, 1.0f)));
    cam->up = ic_xform_dir(m, v3(0.0f, 1.0f, 0.0f));
    /* Mitsuba turns the camera's rays by toWorld, and the camera's +x is the image's left (forward × up
     * its right): a mirroring toWorld (<scale x="-1"/> flips a scene's image) mirrors the image, which
     * eye, target and up alone cannot say */
    cam->is_mirrored = ic_mat4_det3(m) < 0.0f;
    if (spp >= 1.0f && spp <= (float)IC_MAX_SPP)
        c->b->scene->settings.spp = (int)spp;
    return IC_OK;
}

/* ---- shapes ---- */

/* The shape's material: its inline or referenced BSDF (a diffuse 0.5 without one), with its area emitter. */
static ic_result shape_material(ic_mts_ctx *c, const xmlNode *n, ic_material *m, int *has_bsdf)
{
    memset(m, 0, sizeof *m);
    m->type = IC_MAT_DIFFUSE;
    m->kd = v3s(0.5f);
    m->kd_texture = -1;
    m->ior = 1.5f;
    *has_bsdf = 0;
    ic_result r = IC_OK;
    for (xmlNode *k = n->children; k && r == IC_OK; k = k->next) {
        if (ic_mts_is_element(k, "bsdf")) {
            r = ic_mts_bsdf(c, k, m, 0);
            *has_bsdf = 1;
        } else if (ic_mts_is_element(k, "ref")) {
            char id[256];
            const char *given = ic_mts_attr_copy(c, k, "id", id, sizeof id);
            const xmlNode *t = given ? ic_mts_find_by_id(c, "bsdf", id) : NULL;
            if (!t)
                return ic_mts_fail(c, k, IC_ERR_PARSE, "<ref> to an unknown BSDF id: ", given ? id : "(none)");
            r = ic_mts_bsdf(c, t, m, 0);
            *has_bsdf = 1;
        } else if (ic_mts_is_element(k, "emitter")) {
            char type_buf[64];
            const char *type = ic_mts_attr_copy(c, k, "type", type_buf, sizeof type_buf);
            if (!type || strcmp(type, "area"))
                return ic_mts_fail(c, k, IC_ERR_UNSUPPORTED, "a shape's emitter must be of type \"area\"", NULL);
            r = ic_mts_radiance(c, k, "radiance", &m->emission);
        }
    }
    snprintf(m->name, sizeof m->name, "%.100s:%d", ic_mts_attr(c, n, "id") ? ic_mts_attr(c, n, "id") : "shape", ic_mts_line(n));
    return r;
}

/* Triangles of a primitive shape (tessellate.h): a rectangle, disk or cube in its local frame, placed by m;
 * a sphere where m puts Mitsuba's. */
static ic_result primitive(ic_mts_ctx *c, const xmlNode *n, const char *type, uint32_t material, const float m[16],
                           int flip, const char *where)
{
    ic_vec3 *p = malloc(sizeof *p * IC_TESS_MAX_VERTICES * 2), *nn = p ? p + IC_TESS_MAX_VERTICES : NULL;
    uint32_t *tri = malloc(sizeof *tri * IC_TESS_MAX_TRIANGLES * 3), nv = 0, nt = 0;
    if (!p || !tri) {
        free(p);
        free(tri);
        return ic_mts_fail(c, n, IC_ERR_OOM, "out of memory for a shape", NULL);
    }
    const ic_vec3 *normals = NULL;
    float identity[16];
    const float *to_world = m; /* what the local triangles go through */
    if (!strcmp(type, "rectangle")) {
        static const float q[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
        for (int i = 0; i < 4; ++i)
            p[nv++] = v3(q[i][0], q[i][1], 0.0f);
        static const uint32_t t[6] = {0, 1, 2, 0, 2, 3};
        memcpy(tri, t, sizeof t);
        nt = 2;
    } else if (!strcmp(type, "disk")) {
        ic_tess_ring(v3s(0.0f), v3(1.0f, 0.0f, 0.0f), v3(0.0f, 1.0f, 0.0f), 0.0f, 1.0f, p, tri, &nv, &nt);
    } else if (!strcmp(type, "cube")) {
        for (int face = 0; face < 6; ++face) { /* axis face/2, side ± */
            int ax = face / 2;
            float sgn = face % 2 ? 1.0f : -1.0f;
            ic_vec3 nrm = v3s(0.0f), u = v3s(0.0f), v = v3s(0.0f);
            ((float *)&nrm)[ax] = sgn;
            ((float *)&u)[(ax + 1) % 3] = 1.0f;
            v = v3_cross(nrm, u);
            for (int i = 0; i < 4; ++i) {
                float su = (i == 1 || i == 2) ? 1.0f : -1.0f, sv = i >= 2 ? 1.0f : -1.0f;
                p[nv + i] = v3_add(nrm, v3_add(v3_scale(u, su), v3_scale(v, sv)));
            }
            static const uint32_t t[6] = {0, 1, 2, 0, 2, 3};
            for (int i = 0; i < 6; ++i)
                tri[3 * nt + i] = nv + t[i];
            nv += 4;
            nt += 2;
        }
    } else { /* sphere: a latitude-longitude mesh with smooth normals, made in world space */
        ic_vec3 centre = v3s(0.0f);
        float radius = 1.0f;
        xmlNode *ck = ic_mts_child(c, n, "point", "center");
        ic_result r = ck ? ic_mts_vec(c, ck, 0.0f, &centre) : IC_OK;
        if (r == IC_OK)
            r = ic_mts_float(c, n, "radius", 1.0f, &radius);
        if (r != IC_OK) {
            free(p);
            free(tri);
            return r;
        }
        /* Mitsuba makes a true sphere whatever toWorld is: its radius times the length toWorld gives the x
         * axis, its centre toWorld(center) in Mitsuba 2 and 3 (to_world · translate(center) · scale(radius))
         * but toWorld(center / that length) in 0.6 (toWorld · scale(1 / length) · translate(center): the
         * scale does not move the centre); a non-uniform scale does not make an ellipsoid. Mitsuba 2 and 3
         * take the radius's sign from the polar decomposition of that product, whose scale part carries the
         * sign of its determinant, and turn a negative one into flipped normals: a mirroring to_world or a
         * negative radius turns the sphere inside out. Mitsuba 0.6 refuses a radius of 0 or below. */
        float scale = sqrtf(m[0] * m[0] + m[4] * m[4] + m[8] * m[8]);
        int major = ic_mts_version_major(n);
        if (major < 2 && !(radius * scale > 0.0f)) {
            free(p);
            free(tri);
            return ic_mts_fail(c, n, IC_ERR_INVALID_ARG, "a sphere's radius (times toWorld's scale) must be above 0, "
                               "as Mitsuba 0.6 requires", NULL);
        }
        if (major < 2)
            centre = v3_scale(centre, 1.0f / scale);
        else if (ic_mat4_det3(m) * radius < 0.0f)
            flip = !flip;
        ic_tess_sphere(ic_xform_point(m, centre), fabsf(radius) * scale, p, nn, tri, &nv, &nt);
        normals = nn;
        ic_mat4_identity(identity);
        to_world = identity;
    }
    if (flip)
        ic_tess_flip(normals ? nn : NULL, nv, tri, nt);
    ic_result r = ic_scene_append_triangles(c->b, p, normals, nv, tri, nt, material, to_world, where, c->err);
    free(p);
    free(tri);
    return r;
}

static ic_result parse_shape(ic_mts_ctx *c, const xmlNode *n)
{
    char type_buf[64];
    const char *type = ic_mts_attr_copy(c, n, "type", type_buf, sizeof type_buf);
    if (!type)
        return ic_mts_fail(c, n, IC_ERR_PARSE, "<shape> needs a type", NULL);
    int is_file = !strcmp(type, "obj") || !strcmp(type, "ply") || !strcmp(type, "serialized");
    int is_prim = !strcmp(type, "rectangle") || !strcmp(type, "disk") || !strcmp(type, "cube") || !strcmp(type, "sphere");
    if (!is_file && !is_prim) {
        char kind[80];
        snprintf(kind, sizeof kind, "<shape type=\"%.40s\">", type);
        ic_mts_warn_once(c, n, kind, "is not supported and is left out");
        return IC_OK;
    }
    float m[16];
    ic_material mat;
    int has_bsdf = 0, flip = 0;
    ic_result r = ic_mts_to_world(c, n, m);
    if (r == IC_OK)
        r = shape_material(c, n, &mat, &has_bsdf);
    xmlNode *fk = ic_mts_child(c, n, "boolean", "flipNormals");
    if (!fk)
        fk = ic_mts_child(c, n, "boolean", "flip_normals");
    flip = fk && ic_mts_attr(c, fk, "value") && !strcmp(ic_mts_attr(c, fk, "value"), "true");
    if (r != IC_OK)
        return r;
    char where[IC_SCENE_PATH_MAX + 32];
    snprintf(where, sizeof where, "%s:%d", ic_mts_file(c, n), ic_mts_line(n));
    uint32_t index;
    if (is_prim) {
        r = ic_scene_add_material(c->b, &mat, c->path, &index, c->err);
        return r == IC_OK ? primitive(c, n, type, index, m, flip, where) : r;
    }
    const char *file = ic_mts_string(c, n, "filename");
    if (!file)
        return ic_mts_fail(c, n, IC_ERR_PARSE, "this shape needs <string name=\"filename\">", NULL);
    char full[IC_SCENE_PATH_MAX];
    if (!ic_path_join(c->dir, file, full, sizeof full))
        return ic_mts_fail(c, n, IC_ERR_INVALID_ARG, "mesh path too long", NULL);
    /* missing first: a file that is not there is not "outside the scene's folder" */
    if (!ic_path_exists(full))
        return ic_error_set(c->err, IC_ERR_IO, "%s: mesh '%s' not found; check the path", where, file);
    if ((r = ic_scene_check_path(c->b, full, where, "mesh", c->err)) != IC_OK)
        return r;
    if (flip)
        ic_mts_warn_once(c, n, "flipNormals on a mesh file", "is not supported: the file's winding is kept");
    if (!strcmp(type, "serialized")) {
        /* A binary mesh of one material: the shape's BSDF (a diffuse default without one). */
        int shape_index = 0;
        xmlNode *ik = ic_mts_child(c, n, "integer", "shapeIndex");
        if (ik && (!ic_mts_attr(c, ik, "value") || sscanf(ic_mts_attr(c, ik, "value"), "%d", &shape_index) != 1 ||
                   shape_index < 0))
            return ic_mts_fail(c, ik, IC_ERR_PARSE, "shapeIndex must be a non-negative integer", NULL);
        if ((r = ic_scene_add_material(c->b, &mat, c->path, &index, c->err)) != IC_OK)
            return r;
        return ic_mesh_read_serialized(c->b, full, (uint32_t)shape_index, index, m, where, c->err);
    }
    ic_scene *s = c->b->scene;
    uint32_t first_tri = s->triangle_count, first_mat = s->material_count;
    c->b->import_where = where;
    r = ic_mesh_import(c->b, full, m, where, c->err);
    if (r != IC_OK)
        return r;
    if (!has_bsdf) {
        /* Without a BSDF the file's own materials stay (an extension of Mitsuba's), lit by the shape's area
         * emitter if it has one (light shapes often have no BSDF: their light was dropped). */
        for (uint32_t m2 = first_mat; !v3_is_black(mat.emission) && m2 < s->material_count; ++m2)
            s->materials[m2].emission = mat.emission;
        return IC_OK;
    }
    if ((r = ic_scene_add_material(c->b, &mat, c->path, &index, c->err)) != IC_OK)
        return r;
    for (uint32_t m2 = first_mat; m2 < index; ++m2) {
        c->b->material_tris[index] += c->b->material_tris[m2];
        c->b->material_tris[m2] = 0;
    }
    for (uint32_t t = first_tri; t < s->triangle_count; ++t)
        s->triangle_material[t] = index;
    return IC_OK;
}

/* ---- emitters ---- */

/* Mitsuba's sun, sky and sunsky emitters as irrcache's CIE clear sky with gensky's default sun (a disc of
 * the sun's size): the sun from sunDirection (towards the sun, world space) or from the date, time and
 * place (Mitsuba's defaults: 10 July 2010, 15:00 at Tokyo, time zone +9), turned into a direction with
 * irrcache's north (−z) and up (+y); `scale` multiplies both. Mitsuba's own sky models (Preetham,
 * Hosek–Wilkie: turbidity, albedo) are not implemented: one warning says so. */
static ic_result parse_daylight(ic_mts_ctx *c, const xmlNode *n, const char *type)
{
    ic_sky_params p;
    memset(&p, 0, sizeof p);
    p.model = IC_SKY_CIE_CLEAR;
    p.direct_normal_gensky = 1;
    float scale = 1.0f, v[9];
    ic_result r = ic_mts_float(c, n, "scale", 1.0f, &scale);
    xmlNode *dk = ic_mts_child(c, n, "vector", "sunDirection");
    if (r == IC_OK && dk) {
        ic_vec3 d;
        if ((r = ic_mts_vec(c, dk, 0.0f, &d)) != IC_OK)
            return r;
        if (!(v3_len2(d) > 0.0f) || !(d.y > 0.0f))
            return ic_mts_fail(c, dk, IC_ERR_INVALID_ARG, "sunDirection must point above the horizon (+y up)", NULL);
        p.has_sun_direction = 1;
        p.sun_direction = v3_norm(d);
    } else if (r == IC_OK) {
        static const char *names[9] = {"year", "month", "day", "hour", "minute", "second", "latitude",
                                       "longitude", "timezone"};
        static const float fallback[9] = {2010, 7, 10, 15, 0, 0, 35.6894f, 139.6917f, 9};
        for (int k = 0; k < 9 && r == IC_OK; ++k)
            r = ic_mts_float(c, n, names[k], fallback[k], &v[k]);
        if (r != IC_OK)
            return r;
        p.has_date = 1;
        p.month = (int)v[1];
        p.day = (int)v[2];
        p.hour = v[3] + v[4] / 60.0 + v[5] / 3600.0;
        p.latitude = v[6];
        p.longitude = v[7];
        p.has_meridian = 1;
        p.meridian = 15.0 * v[8];
    }
    if (r != IC_OK)
        return r;
    if (!(scale >= 0.0f))
        return ic_mts_fail(c, n, IC_ERR_INVALID_ARG, "scale must not be negative", NULL);
    char kind[80], why[256];
    snprintf(kind, sizeof kind, "<emitter type=\"%s\">", type);
    ic_mts_warn_once(c, n, kind, dk ? "is rendered as the CIE clear sky with gensky's sun (Mitsuba's sky model is "
                                      "not implemented; turbidity and albedo are ignored)"
                                    : "is rendered as the CIE clear sky with gensky's sun (Mitsuba's sky model is "
                                      "not implemented); the sun's azimuth takes north as -z: give sunDirection to "
                                      "place it exactly");
    int with_sky = strcmp(type, "sun") != 0, with_sun = strcmp(type, "sky") != 0;
    if (with_sky && c->b->scene->env.enabled)
        return ic_mts_fail(c, n, IC_ERR_UNSUPPORTED, "a second environment emitter; irrcache renders one", NULL);
    r = ic_scene_install_sky(c->b->scene, &p, with_sky, with_sun, scale, why, sizeof why);
    if (r == IC_ERR_UNSUPPORTED)
        return ic_mts_fail(c, n, r, "a second sun (sun, sunsky or directional emitter); irrcache renders one", NULL);
    return r == IC_OK ? IC_OK : ic_mts_fail(c, n, r, "sun or sky: ", why);
}

static ic_result parse_emitter(ic_mts_ctx *c, const xmlNode *n)
{
    char type_buf[64];
    const char *type = ic_mts_attr_copy(c, n, "type", type_buf, sizeof type_buf);
    ic_scene *s = c->b->scene;
    float m[16];
    ic_result r = ic_mts_to_world(c, n, m);
    if (r != IC_OK || !type)
        return r != IC_OK ? r : ic_mts_fail(c, n, IC_ERR_PARSE, "<emitter> needs a type", NULL);
    if (!strcmp(type, "point") || !strcmp(type, "spot")) {
        ic_vec3 pos = ic_xform_point(m, v3s(0.0f)), intensity;
        xmlNode *pk = ic_mts_child(c, n, "point", "position");
        if (pk && (r = ic_mts_vec(c, pk, 0.0f, &pos)) != IC_OK)
            return r;
        if ((r = ic_mts_radiance(c, n, "intensity", &intensity)) != IC_OK)
            return r;
        if (!strcmp(type, "point"))
            return ic_scene_add_point_light(s, pos, intensity, NULL) == IC_OK
                       ? IC_OK
                       : ic_mts_fail(c, n, IC_ERR_OOM, "out of memory for the lights", NULL);
        float cutoff = 20.0f, beam;
        if ((r = ic_mts_float(c, n, "cutoffAngle", 20.0f, &cutoff)) != IC_OK ||
            (r = ic_mts_float(c, n, "beamWidth", cutoff * 0.75f, &beam)) != IC_OK)
            return r;
        if (!(cutoff > 0.0f && cutoff <= 90.0f && beam >= 0.0f && beam <= cutoff))
            return ic_mts_fail(c, n, IC_ERR_INVALID_ARG, "spot: need 0 < beamWidth <= cutoffAngle <= 90 degrees", NULL);
        ic_mts_warn_once(c, n, "<emitter type=\"spot\">", "falls off between beamWidth and cutoffAngle as t² (glTF's curve)");
        ic_spot_cone cone = {ic_xform_dir(m, v3(0.0f, 0.0f, 1.0f)), cosf(beam * IC_PI / 180.0f),
                             cosf(cutoff * IC_PI / 180.0f)};
        if (cone.cos_inner <= cone.cos_outer)
            cone.cos_inner = cone.cos_outer + 1e-6f;
        return ic_scene_add_point_light(s, pos, intensity, &cone) == IC_OK
                   ? IC_OK
                   : ic_mts_fail(c, n, IC_ERR_OOM, "out of memory for the lights", NULL);
    }
    if (!strcmp(type, "constant")) {
        s->env.enabled = 1;
        return ic_mts_radiance(c, n, "radiance", &s->env.radiance);
    }
    if (!strcmp(type, "directional")) {
        ic_vec3 d = ic_xform_dir(m, v3(0.0f, 0.0f, 1.0f));
        xmlNode *dk = ic_mts_child(c, n, "vector", "direction");
        if (dk && (r = ic_mts_vec(c, dk, 0.0f, &d)) != IC_OK)
            return r;
        if (!(v3_len2(d) > 0.0f))
            return ic_mts_fail(c, n, IC_ERR_INVALID_ARG, "directional: the direction is zero", NULL);
        if (s->sun.enabled)
            return ic_mts_fail(c, n, IC_ERR_UNSUPPORTED, "a second directional emitter; irrcache renders one sun", NULL);
        s->sun.enabled = 1;
        s->sun.direction = v3_neg(v3_norm(d));
        return ic_mts_radiance(c, n, "irradiance", &s->sun.irradiance);
    }
    if (!strcmp(type, "sun") || !strcmp(type, "sky") || !strcmp(type, "sunsky"))
        return parse_daylight(c, n, type);
    if (!strcmp(type, "envmap")) {
        char file_buf[IC_SCENE_PATH_MAX];
        const char *file = ic_mts_string(c, n, "filename");
        if (file)
            file = strncpy(file_buf, file, sizeof file_buf - 1);
        file_buf[sizeof file_buf - 1] = '\0';
        float scale = 1.0f;
        if (!file)
            return ic_mts_fail(c, n, IC_ERR_PARSE, "envmap needs <string name=\"filename\">", NULL);
        if ((r = ic_mts_float(c, n, "scale", 1.0f, &scale)) != IC_OK)
            return r;
        if (!(scale >= 0.0f) || !isfinite(scale))
            return ic_mts_fail(c, n, IC_ERR_INVALID_ARG, "envmap: a negative or non-finite scale",
                               "; give a finite scale >= 0");
        char full[IC_SCENE_PATH_MAX], where[IC_SCENE_PATH_MAX + 32];
        snprintf(where, sizeof where, "%s:%d", ic_mts_file(c, n), ic_mts_line(n));
        if (!ic_path_join(c->dir, file, full, sizeof full))
            return ic_mts_fail(c, n, IC_ERR_INVALID_ARG, "envmap path too long", NULL);
        if ((r = ic_scene_check_path(c->b, full, where, "environment map", c->err)) != IC_OK)
            return r;
        ic_error ierr;
        ic_image_free(&s->env.image);
        r = ic_image_read_max(full, ic_scene_max_texture_pixels(c->opt), IC_SCENE_RAISE_TEXTURE_LIMIT, &s->env.image,
                              &ierr);
        if (r != IC_OK)
            return ic_error_set(c->err, r, "%s: %s", where, ierr.message);
        if ((r = ic_scene_check_env_map(&s->env.image, v3s(scale), file_buf, ic_mts_file(c, n), ic_mts_line(n),
                                          c->err)) != IC_OK)
            return r;
        s->env.enabled = 1;
        s->env.radiance = v3s(scale);
        ic_mts_warn_once(c, n, "<emitter type=\"envmap\">",
                  "is mapped with irrcache's lat-long convention (+y up); its toWorld rotation is not applied");
        return IC_OK;
    }
    char kind[80];
    snprintf(kind, sizeof kind, "<emitter type=\"%.40s\">", type);
    ic_mts_warn_once(c, n, kind, "is not supported and is left out");
    return IC_OK;
}

/* Reads and parses the XML file at path (no network, no external entities or DTDs loaded, no messages
 * printed); the document in *doc. */
static ic_result read_doc(const char *path, const ic_scene_load_options *opt, xmlDoc **doc, ic_error *err)
{
    char *text = NULL;
    size_t len = 0;
    uint64_t max_bytes = opt->max_scene_bytes ? opt->max_scene_bytes : IC_DEFAULT_MAX_SCENE_FILE_BYTES;
    ic_result rr = ic_read_regular_file(path, "scene file", max_bytes,
                                        "keep geometry in mesh files, or raise the limit with --max-scene-bytes",
                                        &text, &len, NULL, err);
    if (rr != IC_OK)
        return rr;
    if (len > (size_t)INT_MAX) {
        free(text);
        return ic_error_set(err, IC_ERR_UNSUPPORTED, "%s: too large for the XML parser", path);
    }
    xmlInitParser();
    *doc = xmlReadMemory(text, (int)len, path, NULL, XML_PARSE_NONET | XML_PARSE_NOWARNING | XML_PARSE_NOERROR);
    free(text);
    if (!*doc) {
        const xmlError *e = xmlGetLastError();
        char msg[256] = "not well-formed XML";
        if (e && e->message) {
            snprintf(msg, sizeof msg, "%s", e->message);
            msg[strcspn(msg, "\n")] = '\0';
        }
        return ic_error_set(err, IC_ERR_PARSE, "%s:%d: %s; fix the XML", path, e ? e->line : 0, msg);
    }
    return IC_OK;
}

static ic_result parse_scene(ic_mts_ctx *c, const xmlNode *root);

/* <include filename="…"/>: the other file's <scene> is read as if its elements stood here. Its path is
 * resolved against the scene file's folder (as Mitsuba 0.6's file resolver does), follows the folder
 * rules of every scene path, and nests at most MAX_INCLUDE_DEPTH deep (a file including itself ends
 * there). Ids defined in any of the files are found from all. */
static ic_result parse_include(ic_mts_ctx *c, const xmlNode *n)
{
    const char *file = ic_mts_attr(c, n, "filename");
    if (!file)
        return ic_mts_fail(c, n, IC_ERR_PARSE, "<include> needs a filename", NULL);
    char full[IC_SCENE_PATH_MAX], where[IC_SCENE_PATH_MAX + 32];
    if (!ic_path_join(c->dir, file, full, sizeof full))
        return ic_mts_fail(c, n, IC_ERR_INVALID_ARG, "include path too long", NULL);
    snprintf(where, sizeof where, "%s:%d", ic_mts_file(c, n), ic_mts_line(n));
    if (c->include_depth >= MAX_INCLUDE_DEPTH || c->root_count >= MAX_DOCS)
        return ic_mts_fail(c, n, IC_ERR_UNSUPPORTED, "includes nest too deep or are too many (a file that includes "
                           "itself?); at most 8 deep and 15 files: ", file);
    if (!ic_path_exists(full))
        return ic_error_set(c->err, IC_ERR_IO, "%s: included file '%s' not found; check the path", where, file);
    ic_result r = ic_scene_check_path(c->b, full, where, "included file", c->err);
    if (r != IC_OK)
        return r;
    xmlDoc *doc = NULL;
    if ((r = read_doc(full, c->opt, &doc, c->err)) != IC_OK)
        return r;
    c->included[c->root_count - 1] = doc;
    xmlNode *root = xmlDocGetRootElement(doc);
    if (!ic_mts_is_element(root, "scene"))
        return ic_mts_fail(c, root, IC_ERR_PARSE, "the root element of an included file must be <scene>", NULL);
    c->roots[c->root_count++] = root;
    if ((r = ic_mts_check_version(c, root)) != IC_OK)
        return r;
    ++c->include_depth;
    r = parse_scene(c, root);
    --c->include_depth;
    return r;
}

/* An error naming the first attribute in n or below that holds a $name no <default> defines (Mitsuba takes it
 * from its command line, -Dname=value, which irrcache has not): left as it is, the text "$name" had been read
 * as a number (an error about the value, not the name) or a type (the shape left out with a warning). */
static ic_result check_parameters(ic_mts_ctx *c, const xmlNode *n)
{
    for (; n; n = n->next) {
        if (n->type != XML_ELEMENT_NODE)
            continue;
        for (const xmlAttr *a = n->properties; a; a = a->next) {
            xmlChar *raw = xmlNodeGetContent((const xmlNode *)a);
            for (const char *s = raw ? strchr((const char *)raw, '$') : NULL; s; s = strchr(s + 1, '$')) {
                size_t len = 0;
                while (isalnum((unsigned char)s[1 + len]) || s[1 + len] == '_')
                    ++len;
                int known = len == 0;
                for (int d = 0; d < c->def_count && !known; ++d)
                    known = strlen(c->def_name[d]) == len && !strncmp(c->def_name[d], s + 1, len);
                if (!known) {
                    char detail[160];
                    snprintf(detail, sizeof detail, "'$%.*s' in attribute '%s' has no <default name=\"%.*s\" value=\"...\"/>; "
                             "add one (Mitsuba would take it from -D%.*s=... on its command line)",
                             (int)(len > 32 ? 32 : len), s + 1, (const char *)a->name, (int)(len > 32 ? 32 : len), s + 1,
                             (int)(len > 32 ? 32 : len), s + 1);
                    xmlFree(raw);
                    return ic_mts_fail(c, n, IC_ERR_PARSE, detail, NULL);
                }
            }
            xmlFree(raw);
        }
        ic_result r = check_parameters(c, n->children);
        if (r != IC_OK)
            return r;
    }
    return IC_OK;
}

static ic_result parse_scene(ic_mts_ctx *c, const xmlNode *root)
{
    ic_result r = IC_OK;
    for (xmlNode *n = root->children; n; n = n->next)
        if (ic_mts_is_element(n, "default")) {
            const char *name = ic_mts_attr(c, n, "name"), *value = ic_mts_attr(c, n, "value");
            if (!name || !value)
                return ic_mts_fail(c, n, IC_ERR_PARSE, "<default> needs name and value", NULL);
            if (c->def_count == MAX_DEFAULTS)
                return ic_mts_fail(c, n, IC_ERR_UNSUPPORTED, "more than 64 <default> elements; merge some", NULL);
            snprintf(c->def_name[c->def_count], sizeof c->def_name[0], "%s", name);
            snprintf(c->def_value[c->def_count], sizeof c->def_value[0], "%s", ic_mts_attr(c, n, "value"));
            ++c->def_count;
        }
    if ((r = check_parameters(c, root->children)) != IC_OK)
        return r;
    for (xmlNode *n = root->children; n && r == IC_OK; n = n->next) {
        if (!ic_mts_is_element(n, NULL) || ic_mts_is_element(n, "default") || ic_mts_is_element(n, "bsdf") || ic_mts_is_element(n, "texture") ||
            ic_mts_is_element(n, "integrator"))
            continue; /* BSDFs and textures are read where they are referenced; the integrator is irrcache's */
        if (ic_mts_is_element(n, "sensor")) {
            r = c->has_sensor++ ? IC_OK : parse_sensor(c, n);
        } else if (ic_mts_is_element(n, "shape")) {
            r = parse_shape(c, n);
        } else if (ic_mts_is_element(n, "emitter")) {
            r = parse_emitter(c, n);
        } else if (ic_mts_is_element(n, "include")) {
            r = parse_include(c, n);
        } else {
            char kind[80];
            snprintf(kind, sizeof kind, "<%.40s>", (const char *)n->name);
            ic_mts_warn_once(c, n, kind, "is not supported and is left out");
        }
    }
    return r;
}

ic_result ic_scene_load_mitsuba(ic_scene_builder *b, const char *path, const ic_scene_load_options *opt, ic_error *err)
{
    xmlDoc *doc = NULL;
    ic_result r = read_doc(path, opt, &doc, err);
    if (r != IC_OK)
        return r;
    ic_mts_ctx *c = calloc(1, sizeof *c);
    if (!c) {
        xmlFreeDoc(doc);
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory", path);
    }
    c->b = b;
    c->opt = opt;
    c->path = path;
    c->err = err;
    ic_path_dirname(path, c->dir, sizeof c->dir);
    c->roots[0] = xmlDocGetRootElement(doc);
    c->root_count = 1;
    if (!ic_mts_is_element(c->roots[0], "scene"))
        r = ic_mts_fail(c, c->roots[0], IC_ERR_PARSE, "the root element must be <scene> (a Mitsuba scene file)", NULL);
    else if ((r = ic_mts_check_version(c, c->roots[0])) == IC_OK)
        r = parse_scene(c, c->roots[0]);
    int has_camera = c->has_sensor && c->b->scene->camera.width > 0;
    if (!c->has_sensor)
        c->b->scene->camera.width = 0;
    for (int k = 0; k < MAX_DOCS; ++k)
        if (c->included[k])
            xmlFreeDoc(c->included[k]);
    free(c);
    xmlFreeDoc(doc);
    if (r != IC_OK)
        return r;
    return ic_scene_finalize_and_fit(b, has_camera, err);
}
