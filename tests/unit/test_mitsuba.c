/*
 * test_mitsuba.c — Mitsuba XML scenes written here, against the JSON scene and analytic answers:
 *   1. the Cornell box's OBJ under a Mitsuba sensor (lookat, fov on the y axis) renders as the JSON scene
 *      with the same camera;
 *   2. a rectangle floor (diffuse 0.5, scaled by a transform) under a constant emitter of radiance 2 shows
 *      ρ·L = 1; under a point light, ρ·I/(π·h²);
 *   3. BSDFs: roughconductor by name (gold's complex index), roughplastic's index, dielectric, thindielectric (a
 *      thin pane), twosided and references by id, <default> substitution, sphere and cube shapes with their transforms;
 *   4. unsupported elements give one warning per kind naming file:line; malformed XML is an error naming
 *      file:line;
 *   5. what depends on the file's <scene version>: a conductor without a material (copper in 0.6, a perfect
 *      mirror in 2 and 3) and a sphere's centre under toWorld (scaled in 3, not in 0.6), against Mitsuba's
 *      formulas (a closed surface, nothing dropped), and which way it faces under a mirror or a negative radius (in, in 2 and 3; 0.6 refuses a
 *      radius of 0 or below); a mirroring sensor transform mirrors the image, before the lookat or after it;
 *      roughness above 1 is kept; the major number decides, no version is 0.6's reading, and a malformed
 *      version is an error naming file:line (in an included file too).
 */
#include "test_util.h"
#include "test_render_util.h"

#include "core/microfacet.h"
#include "film/film.h"
#include "irrcache/render.h"
#include "scene/scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>


static ic_scene *load(const char *path, ic_error *err)
{
    ic_scene *s;
    test_load_scene(path, NULL, 0, 0, 1, &s, err);
    return s;
}

static int render(const ic_scene *s, ic_image *img)
{
    ic_render_options opt = {0};
    opt.spp = 4;
    opt.threads = 2;
    return test_render_loaded(s, &opt, img);
}

static void test_cornell(void)
{
    char xml[2048], json[1024];
    snprintf(xml, sizeof xml,
             "<scene version=\"0.6.0\">\n"
             "  <integrator type=\"path\"/>\n"
             "  <sensor type=\"perspective\">\n"
             "    <float name=\"fov\" value=\"39.3\"/>\n"
             "    <string name=\"fovAxis\" value=\"y\"/>\n"
             "    <transform name=\"toWorld\"><lookat origin=\"0, 1, 3.9\" target=\"0, 1, 0\" up=\"0, 1, 0\"/></transform>\n"
             "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" value=\"32\"/></film>\n"
             "  </sensor>\n"
             "  <shape type=\"obj\"><string name=\"filename\" value=\"%s/scenes/cornell-box/CornellBox-Original.obj\"/></shape>\n"
             "</scene>\n",
             IC_SOURCE_DIR);
    test_write_file(IC_TEST_TMP "/cornell_mts.xml", xml);
    snprintf(json, sizeof json,
             "{\"camera\": {\"eye\": [0, 1, 3.9], \"target\": [0, 1, 0], \"up\": [0, 1, 0], \"fov_y\": 39.3, "
             "\"width\": 32, \"height\": 32},\n \"meshes\": [{\"path\": \"%s/scenes/cornell-box/CornellBox-Original.obj\"}]}\n",
             IC_SOURCE_DIR);
    test_write_file(IC_TEST_TMP "/cornell_mts.json", json);
    ic_error err = {0};
    ic_scene *a = load(IC_TEST_TMP "/cornell_mts.xml", &err), *b = NULL;
    CHECK(a != NULL, "Mitsuba Cornell box loads: %s", err.message);
    b = load(IC_TEST_TMP "/cornell_mts.json", &err);
    CHECK(b != NULL, "JSON Cornell box loads: %s", err.message);
    if (a && b) {
        CHECK(a->camera.width == 32 && a->camera.height == 32 && fabsf(a->camera.fov_y_deg - 39.3f) < 1e-4f,
              "film size and field of view");
        CHECK(a->triangle_count == b->triangle_count && a->tri_light_count == b->tri_light_count,
              "the same geometry and lights");
        ic_image ia = {0}, ib = {0};
        if (render(a, &ia) && render(b, &ib)) {
            double num = 0.0, den = 0.0;
            for (size_t i = 0; i < (size_t)32 * 32 * 3; ++i) {
                num += (ia.rgb[i] - ib.rgb[i]) * (double)(ia.rgb[i] - ib.rgb[i]);
                den += ib.rgb[i] * (double)ib.rgb[i];
            }
            CHECK(num <= 1e-6 * den, "the Mitsuba scene renders as the JSON one (relative squared error %g)",
                  den > 0 ? num / den : 0.0);
        }
        ic_image_free(&ia);
        ic_image_free(&ib);
    }
    ic_scene_free(a);
    ic_scene_free(b);
}

/* A 2000 m floor (a rectangle scaled by 1000), diffuse 0.5, seen from 2 m above; extra: the lights. */
static double floor_centre(const char *name, const char *lights)
{
    char xml[2048], path[512];
    snprintf(xml, sizeof xml,
             "<scene version=\"2.0.0\">\n"
             "  <default name=\"rho\" value=\"0.5\"/>\n"
             "  <sensor type=\"perspective\"><float name=\"fov\" value=\"10\"/>\n"
             "    <transform name=\"toWorld\"><lookat origin=\"0, 2, 0\" target=\"0, 0, 0\" up=\"0, 0, -1\"/></transform>\n"
             "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/><integer name=\"height\" value=\"16\"/></film>\n"
             "  </sensor>\n"
             "  <shape type=\"rectangle\">\n"
             "    <transform name=\"toWorld\"><rotate x=\"1\" angle=\"-90\"/><scale value=\"1000\"/></transform>\n"
             "    <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"$rho, $rho, $rho\"/></bsdf>\n"
             "  </shape>\n%s</scene>\n",
             lights);
    snprintf(path, sizeof path, IC_TEST_TMP "/%s.xml", name);
    test_write_file(path, xml);
    ic_error err = {0};
    ic_scene *s = load(path, &err);
    CHECK(s != NULL, "%s loads: %s", name, err.message);
    ic_render_options opt = {0};
    opt.spp = 4;
    opt.threads = 2;
    return s ? test_scene_box_mean(s, &opt, 6, 6, 4, 1) : -1.0;
}

static void test_analytic(void)
{
    double sky = floor_centre("mts_sky", "  <emitter type=\"constant\"><rgb name=\"radiance\" value=\"2\"/></emitter>\n");
    CHECK(fabs(sky - 1.0) < 0.03, "rectangle floor under a constant emitter: %g, expected rho L = 1", sky);
    double pt = floor_centre("mts_point", "  <emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"2\" z=\"0\"/>"
                                          "<rgb name=\"intensity\" value=\"4\"/></emitter>\n");
    double want = 0.5 * 4.0 / (3.14159265358979 * 4.0);
    CHECK(fabs(pt - want) < 2e-3 * want, "floor under a point light: %g, expected rho I/(pi h^2) = %g", pt, want);
}

/* Loads xml (written as `file`) and checks every shape's material and the warnings. */
static void check_materials(const char *xml, const char *file)
{
    char path[256], place[64];
    snprintf(path, sizeof path, IC_TEST_TMP "/%s", file);
    snprintf(place, sizeof place, "%s:11:", file);
    test_write_file(path, xml);
    ic_error err = {0};
    ic_scene *s = load(path, &err);
    CHECK(s != NULL, "%s loads: %s", file, err.message);
    if (!s)
        return;
    int seen[8] = {0};
    for (uint32_t t = 0; t < s->triangle_count; ++t) {
        const ic_material *m = &s->materials[s->triangle_material[t]];
        ic_vec3 p = s->positions[s->triangles[3 * t]];
        if (m->type == IC_MAT_CONDUCTOR && !seen[0]++) {
            CHECK(fabsf(m->alpha - 0.3f) < 1e-6f && fabsf(m->k.x - 3.98316f / 1.000277f) < 1e-4f,
                  "gold by name (relative to air), alpha from $a (not the start of $alpha): %g %g", m->alpha, m->k.x);
        } else if (m->type == IC_MAT_CONDUCTOR) {
            float d = v3_len(v3_sub(p, v3(1, 2, 3)));
            seen[1] |= fabsf(d - 0.5f) > 1e-4f; /* every sphere vertex on the sphere */
        } else if (m->type == IC_MAT_PLASTIC && !seen[2]++) {
            CHECK(fabsf(m->ior - 1.6f / 1.000277f) < 1e-4f && m->kd.z == 0.6f && fabsf(m->alpha - 0.7f) < 1e-6f,
                  "twosided roughplastic by reference, alpha from $alpha (not $a followed by 'lpha'): %g", m->alpha);
            CHECK(p.x >= 8.0f - 1e-4f && p.x <= 12.0f + 1e-4f, "cube scaled by 2, then moved by 10: x = %g", p.x);
        } else if (m->type == IC_MAT_GLASS && !seen[3]++) {
            CHECK(fabsf(m->ior - 1.33f / 1.000277f) < 1e-4f && m->emission.x == 3.0f, "dielectric with an area emitter");
        } else if (m->type == IC_MAT_THIN_GLASS && !seen[4]++) {
            CHECK(fabsf(m->ior - 1.5f / 1.000277f) < 1e-4f && m->ks.x == 1.0f, "thindielectric: a clear thin pane");
        }
    }
    CHECK(seen[0] && !seen[1] && seen[2] && seen[3] && seen[4], "every shape imported with its material");
    const char *w = ic_scene_warnings(s);
    const char *bump = strstr(w, "bumpmap");
    CHECK(bump && !strstr(bump + 1, "bumpmap"), "one warning for the two bump maps: %s", w);
    CHECK(strstr(w, place) && strstr(w, "hair"),
          "the unsupported shape named with file:line: %s", w);
    ic_scene_free(s);
}

static void test_materials_and_warnings(void)
{
    const char *xml =
        "<scene version=\"0.6.0\">\n"
        "  <default name=\"a\" value=\"0.3\"/>\n"
        "  <default name=\"alpha\" value=\"0.7\"/>\n"
        "  <bsdf type=\"roughconductor\" id=\"gold\"><string name=\"material\" value=\"Au\"/>"
        "<float name=\"alpha\" value=\"$a\"/></bsdf>\n"
        "  <bsdf type=\"twosided\" id=\"paint\"><bsdf type=\"roughplastic\"><float name=\"intIOR\" value=\"1.6\"/><float name=\"alpha\" value=\"$alpha\"/>"
        "<rgb name=\"diffuseReflectance\" value=\"0.2, 0.4, 0.6\"/></bsdf></bsdf>\n"
        "  <shape type=\"sphere\"><point name=\"center\" x=\"1\" y=\"2\" z=\"3\"/><float name=\"radius\" value=\"0.5\"/>"
        "<ref id=\"gold\"/></shape>\n"
        "  <shape type=\"cube\"><transform name=\"toWorld\"><scale value=\"2\"/><translate x=\"10\"/></transform>"
        "<ref id=\"paint\"/></shape>\n"
        "  <shape type=\"rectangle\"><bsdf type=\"dielectric\"><float name=\"intIOR\" value=\"1.33\"/></bsdf>"
        "<emitter type=\"area\"><rgb name=\"radiance\" value=\"3\"/></emitter></shape>\n"
        "  <shape type=\"rectangle\"><bsdf type=\"bumpmap\"><bsdf type=\"diffuse\"/></bsdf></shape>\n"
        "  <shape type=\"rectangle\"><bsdf type=\"bumpmap\"><bsdf type=\"diffuse\"/></bsdf></shape>\n"
        "  <shape type=\"hair\"/>\n"
        "  <shape type=\"rectangle\"><bsdf type=\"thindielectric\"><float name=\"intIOR\" value=\"1.5\"/></bsdf></shape>\n"
        "</scene>\n";
    check_materials(xml, "mts_materials.xml");
    /* Mitsuba 3 spells the parameters in snake_case: the same scene, the same materials. */
    char v3[4096];
    snprintf(v3, sizeof v3, "%s", xml);
    const char *from[] = {"version=\"0.6.0\"", "intIOR", "diffuseReflectance", "toWorld"},
               *to[] = {"version=\"3.0.0\"", "int_ior", "diffuse_reflectance", "to_world"};
    for (int k = 0; k < 4; ++k)
        for (char *p = strstr(v3, from[k]); p; p = strstr(p, from[k])) {
            size_t lf = strlen(from[k]), lt = strlen(to[k]);
            memmove(p + lt, p + lf, strlen(p + lf) + 1);
            memcpy(p, to[k], lt);
        }
    CHECK(!strstr(v3, "intIOR") && strstr(v3, "int_ior") && strstr(v3, "to_world"), "the Mitsuba 3 spelling");
    check_materials(v3, "mts_materials_v3.xml");

    ic_error err = {0};
    ic_scene *s = NULL;
    test_write_file(IC_TEST_TMP "/mts_bad.xml", "<scene>\n  <shape type=\"obj\">\n</scene>\n");
    ic_scene_load_options lo = {0};
    ic_result r = ic_scene_load(IC_TEST_TMP "/mts_bad.xml", &lo, &s, &err);
    CHECK(r == IC_ERR_PARSE && strstr(err.message, "mts_bad.xml:4: "), "malformed XML: file:line (%s)", err.message);
    ic_scene_free(s);
    test_write_file(IC_TEST_TMP "/mts_ref.xml", "<scene>\n<shape type=\"cube\"><ref id=\"nosuch\"/></shape>\n</scene>\n");
    r = ic_scene_load(IC_TEST_TMP "/mts_ref.xml", &lo, &s, &err);
    CHECK(r == IC_ERR_PARSE && strstr(err.message, "mts_ref.xml:2") && strstr(err.message, "nosuch"),
          "unknown reference: file:line and the id (%s)", err.message);
    ic_scene_free(s);
}

/* What Mitsuba files say and irrcache had dropped without a word: an area emitter on a mesh file with no BSDF
 * lights the mesh (its light was lost); a "none" conductor takes its specularReflectance (a tinted
 * mirror rendered white); unsupported dielectric tints, bubbles (inside index below the outside's) and a
 * twosided BSDF's back side are warned about, naming the file's line. */
static void test_dropped_without_a_word(void)
{
    test_write_file(IC_TEST_TMP "/mts_quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
    const char *xml =
        "<scene version=\"0.6.0\">\n"
        "  <shape type=\"obj\"><string name=\"filename\" value=\"mts_quad.obj\"/>"
        "<emitter type=\"area\"><rgb name=\"radiance\" value=\"4, 5, 6\"/></emitter></shape>\n"
        "  <shape type=\"rectangle\"><bsdf type=\"conductor\"><string name=\"material\" value=\"none\"/>"
        "<rgb name=\"specularReflectance\" value=\"0.5\"/></bsdf></shape>\n"
        "  <shape type=\"rectangle\"><bsdf type=\"dielectric\"><float name=\"intIOR\" value=\"1.0\"/>"
        "<float name=\"extIOR\" value=\"1.333\"/></bsdf></shape>\n"
        "  <shape type=\"rectangle\"><bsdf type=\"thindielectric\"><rgb name=\"specularTransmittance\" "
        "value=\"0.2, 0.5, 1\"/></bsdf></shape>\n"
        "  <shape type=\"rectangle\"><bsdf type=\"twosided\"><bsdf type=\"diffuse\"/><bsdf type=\"plastic\"/>"
        "</bsdf></shape>\n"
        "</scene>\n";
    test_write_file(IC_TEST_TMP "/mts_dropped.xml", xml);
    ic_error err = {0};
    ic_scene *s = load(IC_TEST_TMP "/mts_dropped.xml", &err);
    CHECK(s != NULL, "mts_dropped.xml loads: %s", err.message);
    if (!s)
        return;
    int lit = 0, tinted = 0;
    for (uint32_t t = 0; t < s->triangle_count; ++t) {
        const ic_material *m = &s->materials[s->triangle_material[t]];
        lit += m->emission.x == 4.0f && m->emission.y == 5.0f && m->emission.z == 6.0f;
        tinted += m->type == IC_MAT_CONDUCTOR && m->ks.x == 0.5f && m->ks.y == 0.5f;
    }
    CHECK(lit == 2, "the mesh file's two triangles carry the shape's area emitter (%d)", lit);
    CHECK(tinted == 2, "the 'none' conductor reflects its specularReflectance, 0.5 (%d triangles)", tinted);
    CHECK(s->tri_light_count == 2, "the mesh lights the scene (%u emitting triangles)", s->tri_light_count);
    const char *w = ic_scene_warnings(s);
    CHECK(w && strstr(w, "mts_dropped.xml:4:") && strstr(w, "bubble"), "a bubble is warned about: %s", w ? w : "");
    CHECK(w && strstr(w, "mts_dropped.xml:5:") && strstr(w, "specularTransmittance"),
          "a tinted dielectric is warned about: %s", w ? w : "");
    CHECK(w && strstr(w, "mts_dropped.xml:6:") && strstr(w, "back BSDF"), "a twosided back side is warned about: %s",
          w ? w : "");
    ic_scene_free(s);
}

/* A $name that no <default> defines (Mitsuba takes it from -Dname=... on its command line) is an error naming
 * the element's file:line and the parameter: left as the text "$shape", a shape's type had left the shape out
 * with a warning (the scene black), and a value had been refused as "expected one or three numbers"; a defined
 * one is substituted; more than 64 defaults (the 65th had been ignored) are refused. */
static void test_undefined_parameter(void)
{
    static const char *const rect = "  <shape type=\"%s\"><transform name=\"toWorld\"><scale value=\"%s\"/></transform>"
                                    "<emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>\n";
    static const struct {
        const char *name, *type, *scale, *says;
    } cases[] = {
        {"mts_param_type", "$shape", "2", "mts_param_type.xml:3: '$shape' in attribute 'type' has no <default name=\"shape\""},
        {"mts_param_value", "rectangle", "$width", "mts_param_value.xml:3: '$width' in attribute 'value' has no <default"},
        {"mts_param_ok", "$shape2", "$size", NULL},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        char xml[1024], shape[512], path[256];
        snprintf(shape, sizeof shape, rect, cases[k].type, cases[k].scale);
        snprintf(xml, sizeof xml, "<scene version=\"0.6.0\">\n  <default name=\"shape2\" value=\"rectangle\"/>"
                 "<default name=\"size\" value=\"2\"/>\n%s</scene>\n", shape);
        snprintf(path, sizeof path, IC_TEST_TMP "/%s.xml", cases[k].name);
        test_write_file(path, xml);
        ic_error err = {0};
        ic_scene *s = load(path, &err);
        if (cases[k].says) {
            test_check_refused(cases[k].name, s, &err, (const char *[]){cases[k].says, "-D", NULL});
            continue;
        }
        CHECK(s != NULL && s->triangle_count == 2 && fabsf(s->positions[s->triangles[0]].x) == 2.0f,
              "%s: the defaults substituted: %s", cases[k].name, s ? "" : err.message);
        ic_scene_free(s);
    }
    char xml[8192];
    size_t o = (size_t)snprintf(xml, sizeof xml, "<scene version=\"0.6.0\">\n");
    for (int d = 0; d < 65; ++d)
        o += (size_t)snprintf(xml + o, sizeof xml - o, "<default name=\"p%d\" value=\"1\"/>\n", d);
    snprintf(xml + o, sizeof xml - o, "</scene>\n");
    test_write_file(IC_TEST_TMP "/mts_param_many.xml", xml);
    ic_error err = {0};
    ic_scene *s = load(IC_TEST_TMP "/mts_param_many.xml", &err);
    test_check_refused("mts_param_many", s, &err, (const char *[]){"mts_param_many.xml:66:", "more than 64 <default>", NULL});
}

/* A focal length is Mitsuba's field of view across the 35 mm frame's diagonal (36 x 24 mm), 50 mm when
 * no fov is given: on a square 512 x 512 film 28 mm is a vertical 57.30°, the default 34.03° (the
 * horizontal 2 atan(18 / f) had given 65.5° and 39.3°). */
static void test_focal_length(void)
{
    static const struct {
        const char *lens;
        double fov_y;
    } cases[] = {{"<string name=\"focalLength\" value=\"28mm\"/>", 57.30}, {"", 34.03}};
    for (int k = 0; k < 2; ++k) {
        char xml[2048];
        snprintf(xml, sizeof xml,
                 "<scene version=\"0.6.0\">\n  <sensor type=\"perspective\">%s\n"
                 "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"512\"/><integer name=\"height\" "
                 "value=\"512\"/></film>\n  </sensor>\n"
                 "  <shape type=\"obj\"><string name=\"filename\" value=\"%s/scenes/cornell-box/CornellBox-Original.obj\"/>"
                 "</shape>\n</scene>\n",
                 cases[k].lens, IC_SOURCE_DIR);
        test_write_file(IC_TEST_TMP "/focal_mts.xml", xml);
        ic_error err = {0};
        ic_scene *s = load(IC_TEST_TMP "/focal_mts.xml", &err);
        CHECK(s && fabs(s->camera.fov_y_deg - cases[k].fov_y) < 0.01, "%s: vertical fov %g, want %g (%s)",
              k ? "no focal length" : "28 mm", s ? (double)s->camera.fov_y_deg : -1.0, cases[k].fov_y, err.message);
        ic_scene_free(s);
    }
}

/* Writes the scene of this version with these elements as file and loads it; NULL (and a failed check) if
 * it does not load. */
static ic_scene *load_xml(const char *file, const char *version, const char *elements)
{
    char path[256], xml[2048];
    snprintf(path, sizeof path, IC_TEST_TMP "/%s", file);
    snprintf(xml, sizeof xml, "<scene version=\"%s\">\n%s</scene>\n", version, elements);
    test_write_file(path, xml);
    ic_error err = {0};
    ic_scene *s = load(path, &err);
    CHECK(s != NULL, "%s loads: %s", file, err.message);
    return s;
}

/* The material of the first triangle whose material's name starts with id (shape_material names it
 * "id:line"). */
static const ic_material *material_of(const ic_scene *s, const char *id)
{
    for (uint32_t t = 0; s && t < s->triangle_count; ++t) {
        const ic_material *m = &s->materials[s->triangle_material[t]];
        if (!strncmp(m->name, id, strlen(id)) && m->name[strlen(id)] == ':')
            return m;
    }
    return NULL;
}

static int same_conductor(const ic_material *a, const ic_material *b)
{
    return a && b && a->type == IC_MAT_CONDUCTOR && b->type == IC_MAT_CONDUCTOR && !memcmp(&a->eta, &b->eta, sizeof a->eta) &&
           !memcmp(&a->k, &b->k, sizeof a->k) && !memcmp(&a->ks, &b->ks, sizeof a->ks);
}

/* A conductor without a material is copper in Mitsuba 0.6 and "none", a perfect mirror, in Mitsuba 2 and 3
 * (the file's <scene version>): the bare conductor is the named one of its version, and a version 2 or 3
 * one reflects everything at every angle (ks·F = 1); an eta given alone in Mitsuba 3 has k = 1, the
 * "none" profile's. */
static void test_conductor_default(void)
{
    static const struct {
        const char *version, *name;
    } cases[] = {{"0.6.0", "Cu"}, {"2.0.0", "none"}, {"3.0.0", "none"}};
    for (int v = 0; v < 3; ++v) {
        char xml[1024];
        snprintf(xml, sizeof xml,
                 "  <shape type=\"rectangle\" id=\"bare\"><bsdf type=\"conductor\"/></shape>\n"
                 "  <shape type=\"rectangle\" id=\"named\"><bsdf type=\"conductor\"><string name=\"material\" "
                 "value=\"%s\"/></bsdf></shape>\n"
                 "  <shape type=\"rectangle\" id=\"eta\"><bsdf type=\"conductor\"><rgb name=\"eta\" value=\"1.5\"/>"
                 "</bsdf></shape>\n",
                 cases[v].name);
        ic_scene *s = load_xml("mts_conductor_default.xml", cases[v].version, xml);
        const ic_material *bare = material_of(s, "bare"), *named = material_of(s, "named"), *eta = material_of(s, "eta");
        CHECK(same_conductor(bare, named), "version %s: a conductor without a material is '%s'", cases[v].version,
              cases[v].name);
        if (bare && v > 0) {
            for (float c = 0.05f; c <= 1.0f; c += 0.19f) {
                ic_vec3 f = v3_mul(bare->ks, ic_fresnel_conductor(c, bare->eta, bare->k));
                CHECK(fabsf(f.x - 1.0f) < 1e-5f && fabsf(f.y - 1.0f) < 1e-5f && fabsf(f.z - 1.0f) < 1e-5f,
                      "version %s: the bare conductor is a perfect mirror at cos %g: %g %g %g", cases[v].version, c,
                      f.x, f.y, f.z);
            }
            CHECK(eta && fabsf(eta->k.y - 1.0f / 1.000277f) < 1e-5f && fabsf(eta->eta.y - 1.5f / 1.000277f) < 1e-5f,
                  "version %s: an eta alone has k = 1 (relative to air): %g", cases[v].version, eta ? eta->k.y : -1.0f);
        }
        if (bare && v == 0)
            CHECK(ic_fresnel_conductor(1.0f, bare->eta, bare->k).x > ic_fresnel_conductor(1.0f, bare->eta, bare->k).z,
                  "version 0.6: copper reflects more red than blue");
        ic_scene_free(s);
    }
}

/* A directed edge of a triangle and the x of its midpoint (edges sorted by it, to find their reverses). */
typedef struct edge {
    ic_vec3 a, b;
    float mid_x;
} edge;

static int cmp_edge(const void *x, const void *y)
{
    float u = ((const edge *)x)->mid_x, v = ((const edge *)y)->mid_x;
    return (u > v) - (u < v);
}

static int near3(ic_vec3 a, ic_vec3 b, float tol) { return v3_len(v3_sub(a, b)) <= tol; }

/* How many of the scene's directed triangle edges have no reverse edge (b to a) within tol: 0 for a closed
 * surface whose triangles all wind the same way (a hole, a missing or a doubled triangle leaves some). */
static int open_edges(const ic_scene *s, float tol)
{
    size_t n = 3 * (size_t)s->triangle_count, open = 0;
    edge *e = malloc(sizeof *e * (n ? n : 1));
    if (!e)
        return -1;
    for (size_t i = 0; i < n; ++i) {
        e[i].a = s->positions[s->triangles[i]];
        e[i].b = s->positions[s->triangles[i % 3 == 2 ? i - 2 : i + 1]];
        e[i].mid_x = 0.5f * (e[i].a.x + e[i].b.x);
    }
    qsort(e, n, sizeof *e, cmp_edge);
    for (size_t i = 0; i < n; ++i) {
        int found = 0;
        for (size_t j = i; !found && j-- > 0 && e[i].mid_x - e[j].mid_x <= tol;)
            found = near3(e[j].a, e[i].b, tol) && near3(e[j].b, e[i].a, tol);
        for (size_t j = i + 1; !found && j < n && e[j].mid_x - e[i].mid_x <= tol; ++j)
            found = near3(e[j].a, e[i].b, tol) && near3(e[j].b, e[i].a, tol);
        open += !found;
    }
    free(e);
    return (int)open;
}

/* Mitsuba's sphere is a true sphere of radius × the length toWorld gives the x axis, centred at
 * toWorld(center) in Mitsuba 3 but at toWorld(center / that length) in 0.6; every vertex lies on it and
 * every normal points out of it. */
static void test_sphere_to_world(void)
{
    static const struct {
        const char *version, *transform;
        ic_vec3 centre;
        float radius;
    } cases[] = {
        /* center (1, 0, 0), radius 0.5, scaled by 2 then moved by 10 along z */
        {"0.6.0", "<scale value=\"2\"/><translate z=\"10\"/>", {1.0f, 0.0f, 10.0f}, 1.0f},
        {"3.0.0", "<scale value=\"2\"/><translate z=\"10\"/>", {2.0f, 0.0f, 10.0f}, 1.0f},
        /* turned a quarter about z: the centre turns with it */
        {"0.6.0", "<rotate z=\"1\" angle=\"90\"/><scale value=\"3\"/>", {0.0f, 1.0f, 0.0f}, 1.5f},
        /* a non-uniform scale: still a sphere, of the x axis's scale */
        {"3.0.0", "<scale x=\"4\" y=\"1\" z=\"2\"/>", {4.0f, 0.0f, 0.0f}, 2.0f},
        /* a mirror in 0.6: the normals still point out (Mitsuba 3 turns them in: test_sphere_facing) */
        {"0.6.0", "<scale x=\"-2\" y=\"2\" z=\"2\"/>", {-1.0f, 0.0f, 0.0f}, 1.0f},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        char xml[1024];
        snprintf(xml, sizeof xml,
                 "  <shape type=\"sphere\"><point name=\"center\" x=\"1\" y=\"0\" z=\"0\"/><float name=\"radius\" "
                 "value=\"0.5\"/><transform name=\"toWorld\">%s</transform></shape>\n",
                 cases[k].transform);
        ic_scene *s = load_xml("mts_sphere.xml", cases[k].version, xml);
        double worst = s && s->vertex_count ? 0.0 : 1e9;
        int inward = 0;
        for (uint32_t v = 0; s && v < s->vertex_count; ++v) {
            ic_vec3 d = v3_sub(s->positions[v], cases[k].centre);
            worst = fmax(worst, fabs(v3_len(d) - cases[k].radius));
            inward += s->normals && v3_dot(s->normals[v], d) <= 0.0f;
        }
        CHECK(worst < 1e-4 * cases[k].radius && !inward,
              "version %s, %s: every vertex on the sphere of centre (%g %g %g) and radius %g (worst %g), %d normals "
              "pointing in",
              cases[k].version, cases[k].transform, cases[k].centre.x, cases[k].centre.y, cases[k].centre.z,
              cases[k].radius, worst, inward);
        /* a closed surface, and no triangle of its tessellation is one of zero area the scene drops and warns
         * about (at the poles: the user wrote no sliver) */
        int open = s ? open_edges(s, 1e-5f * cases[k].radius) : -1;
        CHECK(s && open == 0 && s->dropped_degenerate == 0 && !strstr(ic_scene_warnings(s), "zero area"),
              "version %s, %s: %d open edges, %u triangles dropped: '%s'", cases[k].version, cases[k].transform,
              open, s ? s->dropped_degenerate : 0, ic_scene_warnings(s));
        ic_scene_free(s);
    }
}

/* A sensor whose toWorld mirrors (<scale x="-1"/> before the lookat, as scenes flip their image) sees the
 * mirror image: its ray through (x, y) is the plain sensor's through (width - x, y). */
static void test_mirrored_sensor(void)
{
    ic_camera cams[2];
    for (int k = 0; k < 2; ++k) {
        char xml[1024];
        snprintf(xml, sizeof xml,
                 "  <sensor type=\"perspective\"><float name=\"fov\" value=\"50\"/>\n"
                 "    <transform name=\"%s\">%s<lookat origin=\"1, 2, 5\" target=\"0, 1, 0\" up=\"0, 1, 0\"/>"
                 "</transform>\n"
                 "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"40\"/><integer name=\"height\" value=\"30\"/>"
                 "</film>\n  </sensor>\n"
                 "  <shape type=\"cube\"/>\n",
                 k ? "to_world" : "toWorld", k ? "<scale x=\"-1\"/>" : "");
        ic_scene *s = load_xml("mts_mirror.xml", k ? "3.0.0" : "0.6.0", xml);
        cams[k] = s ? s->camera : (ic_camera){0};
        ic_scene_free(s);
    }
    double worst = 0.0;
    static const float film[][2] = {{0.5f, 0.5f}, {3.0f, 20.0f}, {20.0f, 15.0f}, {39.5f, 29.5f}, {12.25f, 7.75f}};
    for (int i = 0; i < 5; ++i) {
        ic_ray plain, mirrored;
        if (!ic_camera_ray(&cams[0], 40.0f - film[i][0], film[i][1], &plain) ||
            !ic_camera_ray(&cams[1], film[i][0], film[i][1], &mirrored)) {
            worst = 1e9;
            continue;
        }
        worst = fmax(worst, v3_len(v3_sub(plain.dir, mirrored.dir)) + v3_len(v3_sub(plain.org, mirrored.org)));
    }
    CHECK(cams[0].width == 40 && cams[1].width == 40 && worst < 1e-5,
          "the mirrored sensor's rays are the plain one's mirrored left to right (worst difference %g)", worst);
}

/* A sensor whose toWorld scales the camera's own axes (before the lookat): Mitsuba turns the ray (u, v, 1)
 * into (s_x u, s_y v, s_z), so s_x = s_y = 2, or s_z = 1/2, is the plain sensor with tan(fov/2) doubled
 * (the same rays); a uniform scale changes nothing; s_x ≠ s_y, which square pixels cannot show, is said in
 * a warning; a scale of 0 is refused. */
static void test_stretched_sensor(void)
{
    static const char *const scales[] = {"", "<scale x=\"2\" y=\"2\"/>", "<scale z=\"0.5\"/>",
                                         "<scale value=\"3\"/>", "<scale x=\"2\"/>"};
    const double wide = 2.0 * atan(2.0 * tan(25.0 * IC_PI / 180.0)) * 180.0 / IC_PI;
    ic_camera cams[6];
    const char *warnings[6] = {0};
    ic_scene *scenes[6] = {0};
    for (int k = 0; k < 6; ++k) {
        char xml[1024];
        snprintf(xml, sizeof xml,
                 "  <sensor type=\"perspective\"><float name=\"fov\" value=\"%.9g\"/>\n"
                 "    <transform name=\"toWorld\">%s<lookat origin=\"1, 2, 5\" target=\"0, 1, 0\" up=\"0, 1, 0\"/>"
                 "</transform>\n"
                 "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"40\"/><integer name=\"height\" value=\"30\"/>"
                 "</film>\n  </sensor>\n"
                 "  <shape type=\"cube\"/>\n",
                 k == 5 ? wide : 50.0, k < 5 ? scales[k] : "");
        scenes[k] = load_xml("mts_stretch.xml", "0.6.0", xml);
        cams[k] = scenes[k] ? scenes[k]->camera : (ic_camera){0};
        warnings[k] = scenes[k] ? ic_scene_warnings(scenes[k]) : "";
    }
    static const float film[][2] = {{0.5f, 0.5f}, {3.0f, 20.0f}, {20.0f, 15.0f}, {39.5f, 29.5f}, {12.25f, 7.75f}};
    /* cams[k] against the one whose rays it must have: 1 and 2 against the wide plain sensor (5), 3 the plain */
    static const int same_as[4][2] = {{1, 5}, {2, 5}, {3, 0}, {0, 0}};
    for (int j = 0; j < 3; ++j) {
        double worst = 0.0;
        for (int i = 0; i < 5; ++i) {
            ic_ray a, b;
            if (!ic_camera_ray(&cams[same_as[j][0]], film[i][0], film[i][1], &a) ||
                !ic_camera_ray(&cams[same_as[j][1]], film[i][0], film[i][1], &b)) {
                worst = 1e9;
                continue;
            }
            worst = fmax(worst, v3_len(v3_sub(a.dir, b.dir)) + v3_len(v3_sub(a.org, b.org)));
        }
        CHECK(worst < 1e-5 && !strstr(warnings[same_as[j][0]], "stretches"),
              "sensor scaled by '%s' has the rays of the %s sensor, without a warning (worst difference %g)",
              scales[same_as[j][0]], same_as[j][1] == 5 ? "wider plain" : "plain", worst);
    }
    CHECK(strstr(warnings[4], "mts_stretch.xml:2: <sensor> toWorld that stretches the image unevenly") != NULL,
          "an uneven stretch is said: '%s'", warnings[4]);
    for (int k = 0; k < 6; ++k)
        ic_scene_free(scenes[k]);
    char path[256];
    snprintf(path, sizeof path, IC_TEST_TMP "/mts_flat.xml");
    test_write_file(path, "<scene version=\"0.6.0\">\n  <sensor type=\"perspective\">\n"
                          "    <transform name=\"toWorld\"><scale y=\"0\"/></transform>\n  </sensor>\n"
                          "  <shape type=\"cube\"/>\n</scene>\n");
    ic_error err = {0};
    ic_scene *flat = load(path, &err);
    CHECK(!flat && strstr(err.message, "mts_flat.xml:2:") && strstr(err.message, "collapses"),
          "a scale of 0 is refused: %s", err.message);
    ic_scene_free(flat);
}

/* Which way a tessellated sphere about centre faces: +1 if every vertex normal and every triangle's winding
 * points out of it, -1 if all point in, 0 if mixed (or no sphere). */
static int sphere_facing(const ic_scene *s, ic_vec3 centre)
{
    int out = 0, in = 0;
    for (uint32_t v = 0; s && s->normals && v < s->vertex_count; ++v) {
        float d = v3_dot(s->normals[v], v3_sub(s->positions[v], centre));
        out += d > 0.0f;
        in += d < 0.0f;
    }
    for (uint32_t t = 0; s && t < s->triangle_count; ++t) {
        ic_vec3 a = s->positions[s->triangles[3 * t]], b = s->positions[s->triangles[3 * t + 1]],
                c = s->positions[s->triangles[3 * t + 2]];
        ic_vec3 ng = v3_cross(v3_sub(b, a), v3_sub(c, a)), mid = v3_scale(v3_add(a, v3_add(b, c)), 1.0f / 3.0f);
        float d = v3_dot(ng, v3_sub(mid, centre));
        if (v3_len2(ng) < 1e-12f * v3_len2(v3_sub(mid, centre)) * v3_len2(v3_sub(mid, centre)))
            continue; /* a sliver at a pole: no side to face */
        out += d > 0.0f;
        in += d < 0.0f;
    }
    return out && !in ? 1 : in && !out ? -1 : 0;
}

/* What faces out of a sphere as each version has it. Mitsuba 2 and 3 take the sphere's radius and centre
 * from the polar decomposition of to_world · translate(center) · scale(radius), whose scale part carries
 * the sign of its determinant (drjit's transform_decompose), and turn a negative one into flipped normals:
 * a mirroring to_world or a negative radius turns the sphere inside out, and flip_normals turns it back.
 * Mitsuba 0.6 measures the radius as a length, so a mirror leaves the normals out, and refuses a radius of
 * zero or below. */
static void test_sphere_facing(void)
{
    static const struct {
        const char *version, *extra, *transform;
        int facing;
    } cases[] = {
        {"3.0.0", "", "<scale x=\"-2\" y=\"2\" z=\"2\"/>", -1},
        {"2.1.0", "", "<scale z=\"-1\"/><rotate y=\"1\" angle=\"30\"/>", -1},
        {"3.0.0", "<boolean name=\"flip_normals\" value=\"true\"/>", "<scale x=\"-1\"/>", 1},
        {"3.0.0", "", "<scale x=\"-1\" y=\"-1\"/>", 1}, /* a half turn, not a mirror */
        {"0.6.0", "", "<scale x=\"-2\" y=\"2\" z=\"2\"/>", 1},
        {"3.0.0", "<float name=\"radius\" value=\"-0.5\"/>", "<scale value=\"2\"/>", -1},
        {"3.0.0", "<float name=\"radius\" value=\"-0.5\"/>", "<scale x=\"-2\" y=\"2\" z=\"2\"/>", 1},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        char xml[1024];
        snprintf(xml, sizeof xml, "  <shape type=\"sphere\">%s<transform name=\"toWorld\">%s</transform></shape>\n",
                 cases[k].extra, cases[k].transform);
        ic_scene *s = load_xml("mts_sphere_facing.xml", cases[k].version, xml);
        int facing = sphere_facing(s, v3s(0.0f));
        CHECK(facing == cases[k].facing, "version %s, %s %s: the sphere faces %s (got %d)", cases[k].version,
              cases[k].extra, cases[k].transform, cases[k].facing > 0 ? "out" : "in", facing);
        ic_scene_free(s);
    }
    /* 0.6: a radius of zero or below is an error naming the shape's file:line */
    static const char *const radii[] = {"-0.5", "0"};
    for (int k = 0; k < 2; ++k) {
        char xml[512];
        snprintf(xml, sizeof xml, "<scene version=\"0.6.0\">\n<shape type=\"sphere\">\n"
                 "<float name=\"radius\" value=\"%s\"/></shape>\n</scene>\n", radii[k]);
        test_write_file(IC_TEST_TMP "/mts_sphere_radius.xml", xml);
        ic_scene_load_options lo = {0};
        ic_error err = {0};
        ic_scene *s = NULL;
        ic_result r = ic_scene_load(IC_TEST_TMP "/mts_sphere_radius.xml", &lo, &s, &err);
        CHECK(r != IC_OK && strstr(err.message, "mts_sphere_radius.xml:2") && strstr(err.message, "radius"),
              "version 0.6, radius %s: an error naming file:line (%s)", radii[k], err.message);
        ic_scene_free(s);
    }
}

/* A <scale x="-1"/> after the lookat mirrors the world about x = 0 (later transforms apply after the
 * earlier ones): the camera's eye, its view and its image are the plain camera's mirrored, so its ray
 * through (x, y) is the plain one's through (x, y) with x negated. */
static void test_sensor_world_mirror(void)
{
    ic_camera cams[2];
    for (int k = 0; k < 2; ++k) {
        char xml[1024];
        snprintf(xml, sizeof xml,
                 "  <sensor type=\"perspective\"><float name=\"fov\" value=\"50\"/>\n"
                 "    <transform name=\"toWorld\"><lookat origin=\"1, 2, 5\" target=\"0, 1, 0\" up=\"0, 1, 0\"/>%s"
                 "</transform>\n"
                 "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"40\"/><integer name=\"height\" value=\"30\"/>"
                 "</film>\n  </sensor>\n"
                 "  <shape type=\"cube\"/>\n",
                 k ? "<scale x=\"-1\"/>" : "");
        ic_scene *s = load_xml("mts_world_mirror.xml", "0.6.0", xml);
        cams[k] = s ? s->camera : (ic_camera){0};
        ic_scene_free(s);
    }
    double worst = cams[1].is_mirrored ? 0.0 : 1e9;
    static const float film[][2] = {{0.5f, 0.5f}, {3.0f, 20.0f}, {20.0f, 15.0f}, {39.5f, 29.5f}, {12.25f, 7.75f}};
    for (int i = 0; i < 5; ++i) {
        ic_ray plain, mirrored;
        if (!ic_camera_ray(&cams[0], film[i][0], film[i][1], &plain) ||
            !ic_camera_ray(&cams[1], film[i][0], film[i][1], &mirrored)) {
            worst = 1e9;
            continue;
        }
        plain.org.x = -plain.org.x;
        plain.dir.x = -plain.dir.x;
        worst = fmax(worst, v3_len(v3_sub(plain.dir, mirrored.dir)) + v3_len(v3_sub(plain.org, mirrored.org)));
    }
    CHECK(cams[0].width == 40 && cams[1].width == 40 && worst < 1e-5,
          "a world mirror after the lookat: the rays are the plain sensor's mirrored about x = 0 (worst %g)", worst);
}

/* The version decides the defaults by its major number, whatever follows (0.5.0 and 0.6.0 alike, 2.1.0
 * and 3.5.2 alike; none given: 0.6's), and a version that is not one is an error naming the file and line
 * of the <scene>, as Mitsuba refuses it, rather than a silent 0.6 reading. */
static void test_version(void)
{
    static const struct {
        const char *version, *name;
    } cases[] = {{"0.5.0", "Cu"}, {"2.1.0", "none"}, {"3.5.2", "none"}, {" 3.0.0 ", "none"}, {NULL, "Cu"}};
    for (size_t v = 0; v < sizeof cases / sizeof cases[0]; ++v) {
        char xml[1024];
        snprintf(xml, sizeof xml,
                 "<scene%s%s%s>\n"
                 "  <shape type=\"rectangle\" id=\"bare\"><bsdf type=\"conductor\"/></shape>\n"
                 "  <shape type=\"rectangle\" id=\"named\"><bsdf type=\"conductor\"><string name=\"material\" "
                 "value=\"%s\"/></bsdf></shape>\n</scene>\n",
                 cases[v].version ? " version=\"" : "", cases[v].version ? cases[v].version : "",
                 cases[v].version ? "\"" : "", cases[v].name);
        test_write_file(IC_TEST_TMP "/mts_version.xml", xml);
        ic_error err = {0};
        ic_scene *s = load(IC_TEST_TMP "/mts_version.xml", &err);
        CHECK(s && same_conductor(material_of(s, "bare"), material_of(s, "named")),
              "version '%s': a conductor without a material is '%s' (%s)", cases[v].version ? cases[v].version : "(none)",
              cases[v].name, s ? "" : err.message);
        ic_scene_free(s);
    }
    static const char *const bad[] = {"abc", "", "3.x", "-2.0.0", "3..0", "2.0.0.1"};
    for (size_t v = 0; v < sizeof bad / sizeof bad[0]; ++v) {
        char xml[512];
        snprintf(xml, sizeof xml, "<?xml version=\"1.0\"?>\n<scene version=\"%s\">\n<shape type=\"cube\"/>\n</scene>\n",
                 bad[v]);
        test_write_file(IC_TEST_TMP "/mts_version_bad.xml", xml);
        ic_scene_load_options lo = {0};
        ic_error err = {0};
        ic_scene *s = NULL;
        ic_result r = ic_scene_load(IC_TEST_TMP "/mts_version_bad.xml", &lo, &s, &err);
        CHECK(r == IC_ERR_PARSE && strstr(err.message, "mts_version_bad.xml:2") && strstr(err.message, "version"),
              "version '%s': an error naming file:line (%s)", bad[v], err.message);
        ic_scene_free(s);
    }
    /* an included file is read by its own version, and a bad one there names that file */
    test_write_file(IC_TEST_TMP "/mts_version_inc3.xml", "<scene version=\"3.0.0\">\n  <shape type=\"rectangle\" "
                    "id=\"inc\"><bsdf type=\"conductor\"/></shape>\n</scene>\n");
    test_write_file(IC_TEST_TMP "/mts_version_incbad.xml", "<scene version=\"three\">\n</scene>\n");
    ic_scene *s = load_xml("mts_version_main.xml", "0.6.0",
                           "  <include filename=\"mts_version_inc3.xml\"/>\n"
                           "  <shape type=\"rectangle\" id=\"main\"><bsdf type=\"conductor\"/></shape>\n"
                           "  <shape type=\"rectangle\" id=\"cu\"><bsdf type=\"conductor\"><string name=\"material\" "
                           "value=\"Cu\"/></bsdf></shape>\n"
                           "  <shape type=\"rectangle\" id=\"none\"><bsdf type=\"conductor\"><string name=\"material\" "
                           "value=\"none\"/></bsdf></shape>\n");
    CHECK(same_conductor(material_of(s, "inc"), material_of(s, "none")) &&
              same_conductor(material_of(s, "main"), material_of(s, "cu")),
          "a 3.0.0 file included from a 0.6.0 one: each conductor by its own file's version");
    ic_scene_free(s);
    test_write_file(IC_TEST_TMP "/mts_version_main.xml", "<scene version=\"0.6.0\">\n"
                    "  <include filename=\"mts_version_incbad.xml\"/>\n</scene>\n");
    ic_scene_load_options lo = {0};
    ic_error err = {0};
    s = NULL;
    ic_result r = ic_scene_load(IC_TEST_TMP "/mts_version_main.xml", &lo, &s, &err);
    CHECK(r == IC_ERR_PARSE && strstr(err.message, "mts_version_incbad.xml:1"),
          "a bad version in an included file names that file:line (%s)", err.message);
    ic_scene_free(s);
}

/* A "none" conductor's specularReflectance as a bitmap: irrcache reads a colour there, so it is a grey 0.5
 * mirror (Mitsuba: the texture times a Fresnel factor of 1), warned naming the parameter, not called a
 * texture "other than a bitmap". */
static void test_conductor_texture(void)
{
    ic_scene *s = load_xml("mts_conductor_tex.xml", "3.0.0",
                           "  <shape type=\"rectangle\" id=\"tinted\"><bsdf type=\"conductor\">"
                           "<texture type=\"bitmap\" name=\"specular_reflectance\"><string name=\"filename\" "
                           "value=\"tint.png\"/></texture></bsdf></shape>\n");
    const ic_material *m = material_of(s, "tinted");
    const char *w = s ? ic_scene_warnings(s) : NULL;
    int flat = m != NULL;
    for (float c = 0.05f; m && c <= 1.0f; c += 0.19f) {
        ic_vec3 f = v3_mul(m->ks, ic_fresnel_conductor(c, m->eta, m->k));
        flat &= fabsf(f.x - 0.5f) < 1e-5f && fabsf(f.y - 0.5f) < 1e-5f && fabsf(f.z - 0.5f) < 1e-5f;
    }
    CHECK(flat, "a none conductor with a textured reflectance: 0.5 at every angle");
    CHECK(w && strstr(w, "mts_conductor_tex.xml:2:") && strstr(w, "pecular") && /* either spelling */
              !strstr(w, "other than a bitmap"),
          "the texture is warned about by its parameter: %s", w ? w : "");
    ic_scene_free(s);
}

/* A roughness above 1 is kept (Mitsuba keeps it, and GGX is a normalised distribution there: see
 * test_microfacet); above 4 it is an error naming the file and line. */
static void test_rough_alpha(void)
{
    ic_scene *s = load_xml("mts_alpha.xml", "0.6.0",
                           "  <shape type=\"rectangle\" id=\"metal\"><bsdf type=\"roughconductor\">"
                           "<float name=\"alpha\" value=\"2.5\"/></bsdf></shape>\n"
                           "  <shape type=\"rectangle\" id=\"paint\"><bsdf type=\"roughplastic\">"
                           "<float name=\"alpha\" value=\"1.5\"/></bsdf></shape>\n");
    const ic_material *metal = material_of(s, "metal"), *paint = material_of(s, "paint");
    CHECK(metal && metal->alpha == 2.5f && paint && paint->alpha == 1.5f, "alpha above 1 kept: %g %g",
          metal ? metal->alpha : -1.0f, paint ? paint->alpha : -1.0f);
    ic_scene_free(s);
    test_write_file(IC_TEST_TMP "/mts_alpha_bad.xml", "<scene version=\"0.6.0\">\n<shape type=\"rectangle\">\n"
                                                      "<bsdf type=\"roughconductor\"><float name=\"alpha\" value=\"5\"/>"
                                                      "</bsdf></shape>\n</scene>\n");
    ic_scene_load_options lo = {0};
    ic_error err = {0};
    s = NULL;
    ic_result r = ic_scene_load(IC_TEST_TMP "/mts_alpha_bad.xml", &lo, &s, &err);
    CHECK(r == IC_ERR_INVALID_ARG && strstr(err.message, "mts_alpha_bad.xml:3") && strstr(err.message, "alpha"),
          "alpha above 4: file:line (%s)", err.message);
    ic_scene_free(s);
}

/* The scene of one rectangle whose to_world is `xform`, written as name.xml; NULL (err set) if it does not load. */
static ic_scene *rectangle_under(const char *name, const char *xform, ic_error *err)
{
    char xml[1024], path[256];
    snprintf(xml, sizeof xml,
             "<scene version=\"3.0.0\">\n  <shape type=\"rectangle\">\n    <transform name=\"to_world\">%s</transform>\n"
             "  </shape>\n</scene>\n",
             xform);
    snprintf(path, sizeof path, IC_TEST_TMP "/%s.xml", name);
    test_write_file(path, xml);
    ic_scene *s = NULL;
    memset(err, 0, sizeof *err);
    return ic_scene_load(path, NULL, &s, err) == IC_OK ? s : NULL;
}

/* A direction in a transform (a lookat's view and up, a rotation's axis) is one whatever its length: given
 * 1e20 or 1e-23 times over, whose squares leave a float's range, it places a rectangle where the unit one
 * does (the far target and the short view were refused as an 'up' parallel to the view, the long axis made
 * a rotation a scale by the angle's cosine, the short one no rotation at all). A lookat whose origin is its target
 * is refused as that, naming the line and what to do. */
static void test_transform_direction_lengths(void)
{
    static const char *pairs[][2] = {
        {"<lookat origin=\"1, 2, 3\" target=\"1, 2, 4\" up=\"0, 1, 0\"/>",
         "<lookat origin=\"1, 2, 3\" target=\"1, 2, 1e20\" up=\"0, 1e20, 0\"/>"},
        {"<lookat origin=\"0, 0, 0\" target=\"1, 1, 0\" up=\"0, 0, 1\"/>",
         "<lookat origin=\"0, 0, 0\" target=\"1e-23, 1e-23, 0\" up=\"0, 0, 1e-23\"/>"},
        {"<rotate x=\"1\" y=\"1\" z=\"0\" angle=\"60\"/>", "<rotate x=\"1e20\" y=\"1e20\" z=\"0\" angle=\"60\"/>"},
        {"<rotate x=\"0\" y=\"1\" z=\"1\" angle=\"30\"/>", "<rotate x=\"0\" y=\"1e-23\" z=\"1e-23\" angle=\"30\"/>"}};
    for (int k = 0; k < 4; ++k) {
        ic_error err;
        ic_scene *unit = rectangle_under("mts_dir_unit", pairs[k][0], &err);
        CHECK(unit != NULL, "transform %d with unit directions loads: %s", k, err.message);
        ic_scene *scaled = rectangle_under("mts_dir_scaled", pairs[k][1], &err);
        CHECK(scaled != NULL, "transform %d with directions of other lengths loads: %s", k, err.message);
        if (unit && scaled) {
            CHECK(scaled->triangle_count == unit->triangle_count && unit->triangle_count == 2,
                  "transform %d: %u and %u triangles (2)", k, scaled->triangle_count, unit->triangle_count);
            float worst = 0.0f;
            for (uint32_t i = 0; i < unit->vertex_count && i < scaled->vertex_count; ++i)
                worst = fmaxf(worst, v3_len(v3_sub(unit->positions[i], scaled->positions[i])));
            CHECK(scaled->vertex_count == unit->vertex_count && worst < 1e-5f,
                  "transform %d: the rectangle where the unit directions put it (off by %g)", k, (double)worst);
        }
        ic_scene_free(unit);
        ic_scene_free(scaled);
    }
    ic_error err;
    ic_scene *s = rectangle_under("mts_lookat_same", "<lookat origin=\"1, 1, 1\" target=\"1, 1, 1\"/>", &err);
    CHECK(!s && err.code == IC_ERR_INVALID_ARG && strstr(err.message, "mts_lookat_same.xml:3:") &&
              strstr(err.message, "'origin' and 'target' coincide; move the target") && !strchr(err.message, '\n'),
          "a lookat at its own origin: refused as that, with the line (%s)", err.message);
    ic_scene_free(s);
}

/* A radiance, irradiance or intensity above IC_SCENE_MAX_RADIANCE (1e30) is refused with the line that gives
 * it (samples that overflowed were dropped: a constant emitter of 3e38 read 0); below it the scene loads and
 * renders finite, the brightest pixel its analytic value where there is one. The area, constant, point,
 * spot and directional emitters, and a sky's scale. */
static void test_radiance_limit(void)
{
    /* the rectangle [-1, 1]² facing +z (the fitted camera's side), diffuse 0.5 */
    static const char *const grey = "  <shape type=\"rectangle\"><bsdf type=\"diffuse\"><rgb name=\"reflectance\" "
                                    "value=\"0.5\"/></bsdf></shape>\n";
    static const struct {
        const char *name, *emitter, *bad, *good, *says;
        double brightest; /* the brightest pixel over the good value (0: not checked) */
    } cases[] = {
        {"mts_limit_area", "<shape type=\"rectangle\"><transform name=\"toWorld\"><translate z=\"0.5\"/></transform>"
                           "<emitter type=\"area\"><rgb name=\"radiance\" value=\"%s\"/></emitter></shape>", "1e31",
         "1e29", "'radiance' is 1e+31, above 1e+30", 1.0},
        {"mts_limit_constant", "<emitter type=\"constant\"><rgb name=\"radiance\" value=\"1, %s, 1\"/></emitter>",
         "1e31", "1e29", "'radiance' is 1e+31, above 1e+30", 1.0},
        {"mts_limit_point", "<emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"0\" z=\"1\"/>"
                            "<spectrum name=\"intensity\" value=\"%s\"/></emitter>", "1e31", "1e29",
         "'intensity' is 1e+31, above 1e+30", 0.0},
        {"mts_limit_spot", "<emitter type=\"spot\"><transform name=\"toWorld\"><lookat origin=\"0, 0, 1\" "
                           "target=\"0, 0, 0\"/></transform><rgb name=\"intensity\" value=\"%s\"/></emitter>",
         "1e31", "1e29", "'intensity' is 1e+31, above 1e+30", 0.0},
        /* albedo 0.5 lit along its normal: 0.5 E / pi */
        {"mts_limit_directional", "<emitter type=\"directional\"><vector name=\"direction\" x=\"0\" y=\"0\" "
                                  "z=\"-1\"/><rgb name=\"irradiance\" value=\"%s\"/></emitter>", "1e31", "1e29",
         "'irradiance' is 1e+31, above 1e+30", 0.5 / 3.14159265358979},
        /* gensky's zenith radiance is about 400 W/(m² sr): 1e26 times it is within the limit */
        {"mts_limit_sky", "<emitter type=\"sky\"><float name=\"scale\" value=\"%s\"/></emitter>", "1e31", "1e26",
         "(times the scale 1e+31) is", 0.0},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k)
        for (int ok = 0; ok < 2; ++ok) {
            char emitter[512], xml[2048], path[256], where[96];
            snprintf(emitter, sizeof emitter, cases[k].emitter, ok ? cases[k].good : cases[k].bad);
            snprintf(xml, sizeof xml, "<scene version=\"0.6.0\">\n%s  %s\n</scene>\n", grey, emitter);
            snprintf(path, sizeof path, IC_TEST_TMP "/%s%s.xml", cases[k].name, ok ? "_ok" : "");
            test_write_file(path, xml);
            ic_scene *s = NULL;
            ic_error err = {0};
            test_load_scene(path, NULL, 16, 16, 1, &s, &err);
            if (ok) {
                CHECK(s != NULL, "%s loads: %s", path, err.message);
                test_check_renders_finite(path, s, cases[k].brightest * atof(cases[k].good));
                continue;
            }
            snprintf(where, sizeof where, "%s.xml:3:", cases[k].name);
            test_check_refused(cases[k].name, s, &err,
                               (const char *[]){where, cases[k].says, "above 1e+30", "; ", NULL});
        }
}

int main(void)
{
    test_radiance_limit();
    test_undefined_parameter();
    test_transform_direction_lengths();
    test_conductor_default();
    test_sphere_to_world();
    test_mirrored_sensor();
    test_stretched_sensor();
    test_sensor_world_mirror();
    test_sphere_facing();
    test_version();
    test_conductor_texture();
    test_rough_alpha();
    test_focal_length();
    test_cornell();
    test_analytic();
    test_materials_and_warnings();
    test_dropped_without_a_word();
    TEST_MAIN_END();
}
