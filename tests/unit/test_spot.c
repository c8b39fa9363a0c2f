/*
 * test_spot.c — spot lights of JSON scenes: a spot 2 m above a Lambertian floor (ρ = 0.5), pointing down
 * with cones of 20° and 30°, seen by a camera looking down (path tracer). Under the inner cone the floor
 * shows ρ·I·cos θ/(π·d²) (d = h/cos θ); between the cones the extension's falloff t²; outside, nothing.
 * Invalid cones are errors naming file:line.
 */
#include "test_util.h"

#include "test_render_util.h"

#include <string.h>

static const double PI = 3.14159265358979323846;

int main(void)
{
    test_write_file(IC_TEST_TMP "/spot_floor.mtl", "newmtl floor\nKd 0.5 0.5 0.5\n");
    test_write_file(IC_TEST_TMP "/spot_floor.obj", "mtllib spot_floor.mtl\nusemtl floor\n"
                                                   "v -100 0 -100\nv 100 0 -100\nv 100 0 100\nv -100 0 100\n"
                                                   "f 1 3 2\nf 1 4 3\n");
    /* 90° field of view from 2 m: the image spans ±2 m, so ±45° seen from the spot at the centre */
    test_write_file(IC_TEST_TMP "/spot.json",
                    "{\"camera\": {\"eye\": [0, 2, 0], \"target\": [0, 0, 0], \"up\": [0, 0, -1], \"fov_y\": 90,\n"
                    "            \"width\": 64, \"height\": 64},\n"
                    " \"meshes\": [{\"path\": \"spot_floor.obj\"}],\n"
                    " \"lights\": [{\"type\": \"spot\", \"position\": [0, 2, 0], \"intensity\": 8,\n"
                    "             \"direction\": [0, -1, 0], \"cone_inner\": 20, \"cone_outer\": 30}]}\n");
    ic_render_options opt = {0};
    opt.spp = 4;
    opt.threads = 2;
    ic_image img = {0};
    CHECK(test_render(IC_TEST_TMP "/spot.json", 0, 0, &opt, &img, NULL), "spot scene renders");
    if (img.rgb) {
        double worst = 0.0;
        int outside_lit = 0;
        for (int y = 0; y < 64; ++y)
            for (int x = 0; x < 64; ++x) {
                /* the pixel centre's floor point (x, z) in metres; the pixel filter blurs edges, so pixels
                 * within a pixel of a cone's edge are skipped */
                double fx = ((x + 0.5) / 32.0 - 1.0) * 2.0, fz = ((y + 0.5) / 32.0 - 1.0) * 2.0;
                double r = sqrt(fx * fx + fz * fz), theta = atan2(r, 2.0) * 180.0 / PI;
                double pix_deg = (2.0 / 32.0) / 2.0 * 180.0 / PI * 1.5;
                float v = img.rgb[3 * (y * 64 + x) + 1];
                if (theta < 20.0 - pix_deg) {
                    double c = cos(theta * PI / 180.0), d2 = 4.0 / (c * c);
                    double want = 0.5 * 8.0 * c / (PI * d2);
                    worst = fmax(worst, fabs(v - want) / want);
                } else if (theta > 30.0 + pix_deg) {
                    outside_lit += v != 0.0f;
                }
            }
        CHECK(worst < 0.02, "under the inner cone: rho I cos/(pi d^2) within %.3g relative", worst);
        CHECK(outside_lit == 0, "%d pixels outside the outer cone are lit", outside_lit);
    }
    ic_image_free(&img);

    test_write_file(IC_TEST_TMP "/spot_bad.json",
                    "{\"meshes\": [{\"path\": \"spot_floor.obj\"}],\n"
                    " \"lights\": [\n"
                    "   {\"type\": \"spot\", \"position\": [0, 2, 0], \"intensity\": 8, \"direction\": [0, -1, 0],\n"
                    "    \"cone_inner\": 40, \"cone_outer\": 30}]}\n");
    ic_scene *s = NULL;
    ic_error err = {0};
    ic_scene_load_options lo = {0};
    CHECK(ic_scene_load(IC_TEST_TMP "/spot_bad.json", &lo, &s, &err) == IC_ERR_INVALID_ARG &&
              strstr(err.message, "spot_bad.json:3:") && strstr(err.message, "cone_inner"),
          "inner cone wider than the outer: an error naming file:line (%s)", err.message);
    ic_scene_free(s);
    TEST_MAIN_END();
}
