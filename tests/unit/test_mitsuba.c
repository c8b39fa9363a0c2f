/*
 * test_mitsuba.c — Mitsuba XML scenes written here, against the JSON scene and analytic answers:
 *   1. the Cornell box's OBJ under a Mitsuba sensor (lookat, fov on the y axis) renders as the JSON scene
 *      with the same camera;
 *   2. a rectangle floor (diffuse 0.5, scaled by a transform) under a constant emitter of radiance 2 shows
 *      ρ·L = 1; under a point light, ρ·I/(π·h²);
 *   3. BSDFs: roughconductor by name (gold's complex index), roughplastic's index, dielectric, thindielectric (a
 *      thin pane), twosided and references by id, <default> substitution, sphere and cube shapes with their transforms;
 *   4. unsupported elements give one warning per kind naming file:line; malformed XML is an error naming
 *      file:line.
 */
#include "test_util.h"
#include "test_render_util.h"

#include "irrcache/render.h"
#include "scene/scene.h"

#include <stdio.h>
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

int main(void)
{
    test_focal_length();
    test_cornell();
    test_analytic();
    test_materials_and_warnings();
    test_dropped_without_a_word();
    TEST_MAIN_END();
}
