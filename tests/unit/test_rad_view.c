/*
 * test_rad_view.c — Radiance view files of every type, rendered (the projections' formulas are checked in
 * test_camera.c):
 *   1. fisheyes looking up from a floor under a uniform sky of radiance L: inside the circle every pixel
 *      is L, outside a hemispherical one's circle 0 (black, as Radiance leaves it); an angular 360° fisheye
 *      looking along the floor sees L above the horizon and ρ·L below, with the path tracer and with the
 *      cache; 1 and 2 threads give the same image with both;
 *   2. shift and lift: a shifted, lifted view of a checkerboard of glowing squares is the crop of a wider
 *      view that holds it (pixels within the pixel filter's noise), and not a crop two pixels off;
 *   3. parallel and cylindrical views render the checkerboard where their formulas put it;
 *   4. malformed views name file:line.
 */
#include "test_util.h"
#include "test_render_util.h"

#include "irrcache/render.h"
#include "scene/scene.h"

#include <stdio.h>
#include <string.h>

#define PI_D 3.14159265358979323846

static int render(const ic_scene *s, ic_integrator integrator, int spp, int threads, ic_image *img)
{
    ic_render_options opt = test_seeded_options(spp, threads, 3);
    opt.integrator = integrator;
    opt.ic.gather.theta_strata = 8; /* 8 × 25 rays: enough for a floor under a uniform sky */
    return test_render_loaded(s, &opt, img);
}

static int same_image(const ic_image *a, const ic_image *b)
{
    return a->width == b->width && a->height == b->height &&
           !memcmp(a->rgb, b->rgb, sizeof(float) * 3 * (size_t)a->width * a->height);
}

/* A floor (plastic, ρ = 0.5) at z = 0 under a uniform sky of radiance 2. */
static const char *sky_floor = "void glow skyglow\n0\n0\n4 2 2 2 0\nskyglow source sky\n0\n0\n4 0 0 1 360\n"
                               "void plastic grey\n0\n0\n5 .5 .5 .5 0 0\n"
                               "grey polygon floor\n0\n0\n12\n -1000 -1000 0\n 1000 -1000 0\n 1000 1000 0\n -1000 1000 0\n";

/* Mean of the green channel over the pixels whose centres lie inside (ring = 0) or outside (ring = 1) the
 * circle of radius r about the image centre, 1.5 pixels clear of its rim (the pixel filter reaches one
 * pixel), and whose centres are above (half = 1), below (half = -1) or anywhere (half = 0) about the
 * horizontal diameter, 1.5 pixels clear of it. */
static double circle_mean(const ic_image *img, double r, int ring, int half)
{
    double sum = 0.0, cx = 0.5 * img->width, cy = 0.5 * img->height;
    int n = 0;
    for (int y = 0; y < img->height; ++y)
        for (int x = 0; x < img->width; ++x) {
            double dx = x + 0.5 - cx, dy = y + 0.5 - cy, d = sqrt(dx * dx + dy * dy);
            if (ring ? d < r + 1.5 : d > r - 1.5)
                continue;
            if (half && (half > 0 ? dy > -1.5 : dy < 1.5))
                continue;
            sum += img->rgb[3 * ((size_t)y * img->width + x) + 1];
            ++n;
        }
    return n ? sum / n : -1.0;
}

static void test_fisheyes(void)
{
    ic_error err = {0};
    /* looking up: only sky inside the circle */
    static const struct { const char *name, *view; int black_outside; } up[] = {
        {"vf_hem", "rview -vth -vp 0 0 1 -vd 0 0 1 -vu 0 1 0 -vh 180 -vv 180\n", 1},
        {"vf_ang", "rview -vta -vp 0 0 1 -vd 0 0 1 -vu 0 1 0 -vh 180 -vv 180\n", 0},
        {"vf_pls", "rview -vts -vp 0 0 1 -vd 0 0 1 -vu 0 1 0 -vh 180 -vv 180\n", 0},
    };
    for (size_t k = 0; k < sizeof up / sizeof up[0]; ++k) {
        ic_scene *s = test_load_rad_text(up[k].name, sky_floor, up[k].view, 32, 0, &err);
        CHECK(s && s->camera.width == 32 && s->camera.height == 32, "%s loads square: %s", up[k].name, err.message);
        ic_image img = {0};
        if (s && render(s, IC_INTEGRATOR_PT, 4, 2, &img)) {
            double in = circle_mean(&img, 16.0, 0, 0), out = circle_mean(&img, 16.0, 1, 0);
            CHECK(fabs(in - 2.0) < 1e-4, "%s: mean inside the circle %g, the sky's radiance 2", up[k].name, in);
            if (up[k].black_outside)
                CHECK(out == 0.0, "%s: outside the circle black: %g", up[k].name, out);
            else
                CHECK(out > 0.1 && out < 1.9, "%s: outside the circle the floor (beyond 90 degrees): %g", up[k].name,
                      out);
        }
        ic_image_free(&img);
        ic_scene_free(s);
    }

    /* an angular 360° fisheye along the floor: sky above the horizon, ρ L = 1 below; both integrators, and
     * 1 vs 2 threads */
    ic_scene *s = test_load_rad_text("vf_ang360", sky_floor,
                                     "rview -vta -vp 0 0 1 -vd 0 1 0 -vu 0 0 1 -vh 360 -vv 360\n", 32, 0, &err);
    CHECK(s != NULL, "angular 360 loads: %s", err.message);
    static const ic_integrator integrators[] = {IC_INTEGRATOR_PT, IC_INTEGRATOR_IC};
    for (int k = 0; s && k < 2; ++k) {
        ic_image one = {0}, two = {0};
        if (render(s, integrators[k], 16, 1, &one) && render(s, integrators[k], 16, 2, &two)) {
            double above = circle_mean(&two, 16.0, 0, 1), below = circle_mean(&two, 16.0, 0, -1);
            double outside = circle_mean(&two, 16.0, 1, 0);
            printf("angular 360 (%s): above %g (2), below %g (1), outside %g (0)\n", k ? "cache" : "path tracer",
                   above, below, outside);
            CHECK(fabs(above - 2.0) < 1e-4, "%s: above the horizon the sky: %g", k ? "cache" : "pt", above);
            CHECK(fabs(below - 1.0) < 0.03, "%s: below the horizon rho L = 1: %g", k ? "cache" : "pt", below);
            CHECK(outside == 0.0, "%s: beyond 180 degrees black: %g", k ? "cache" : "pt", outside);
            CHECK(same_image(&one, &two), "%s: 1 and 2 threads give the same fisheye image", k ? "cache" : "pt");
        }
        ic_image_free(&one);
        ic_image_free(&two);
    }
    ic_scene_free(s);
}

/* A wall at y = 5 (x, z in [-4, 4]) of glowing unit squares, the colour (i + 2j) mod 3 of column i, row j. */
static char *checker(void)
{
    static char text[16384];
    int n = snprintf(text, sizeof text,
                     "void glow g0\n0\n0\n4 1 0.2 0.1 0\nvoid glow g1\n0\n0\n4 0.1 1 0.3 0\nvoid glow g2\n0\n0\n4 0.2 0.1 2 0\n");
    for (int j = -4; j < 4; ++j)
        for (int i = -4; i < 4; ++i)
            n += snprintf(text + n, sizeof text - (size_t)n,
                          "g%d polygon sq\n0\n0\n12\n %d 5 %d\n %d 5 %d\n %d 5 %d\n %d 5 %d\n", ((i + 2 * j) % 3 + 3) % 3,
                          i, j, i + 1, j, i + 1, j + 1, i, j + 1);
    return text;
}

/* Σ|a − b| over a's pixels against b's pixels offset by (ox, oy), over Σ b. */
static double crop_error(const ic_image *a, const ic_image *b, int ox, int oy)
{
    double num = 0.0, den = 0.0;
    for (int y = 0; y < a->height; ++y)
        for (int x = 0; x < a->width; ++x)
            for (int ch = 0; ch < 3; ++ch) {
                double va = a->rgb[3 * ((size_t)y * a->width + x) + ch];
                double vb = b->rgb[3 * ((size_t)(y + oy) * b->width + x + ox) + ch];
                num += fabs(va - vb);
                den += vb;
            }
    return num / den;
}

static void test_shift_lift(void)
{
    ic_error err = {0};
    char *rad = checker();
    /* the wide view's image plane is twice the narrow one's: tan(wide/2) = 2 tan(20°) */
    double wide = 2.0 * atan(2.0 * tan(20.0 * PI_D / 180.0)) * 180.0 / PI_D;
    char view[256];
    snprintf(view, sizeof view, "rview -vtv -vp 0 0 0 -vd 0 1 0 -vu 0 0 1 -vh %.9g -vv %.9g\n", wide, wide);
    ic_scene *w = test_load_rad_text("vf_wide", rad, view, 64, 0, &err);
    ic_scene *n = test_load_rad_text(
        "vf_shift", rad, "rview -vtv -vp 0 0 0 -vd 0 1 0 -vu 0 0 1 -vh 40 -vv 40 -vs 0.25 -vl 0.25\n", 32, 0, &err);
    CHECK(w && n, "views load: %s", err.message);
    ic_image iw = {0}, in = {0};
    if (w && n && render(w, IC_INTEGRATOR_PT, 64, 2, &iw) && render(n, IC_INTEGRATOR_PT, 64, 2, &in)) {
        /* the shifted plane spans [-t/2, 3t/2] of the wide one's [-2t, 2t] both ways: pixels 24.. across,
         * 8.. down (lifted: up) */
        double e = crop_error(&in, &iw, 24, 8), off = crop_error(&in, &iw, 22, 8), off_y = crop_error(&in, &iw, 24, 10);
        printf("shift and lift: crop error %g, two pixels off %g and %g\n", e, off, off_y);
        CHECK(e < 0.03 && e < 0.2 * off && e < 0.2 * off_y,
              "the shifted, lifted view is the wide view's crop: %g (2 px off: %g, %g)", e, off, off_y);
    }
    ic_image_free(&iw);
    ic_image_free(&in);
    ic_scene_free(w);
    ic_scene_free(n);

    /* parallel: 8 × 8 world units fill 32 × 32 pixels, one square per 4 pixels; the top-left square is
     * column -4, row 3 (colour (−4 + 6) mod 3 = 2: blue); a cylinder of 90° × 60° looks at the wall's centre
     * (column 0 row 0 right of and above the centre: colour 0, red) */
    ic_scene *p = test_load_rad_text("vf_par", rad, "rview -vtl -vp 0 0 0 -vd 0 1 0 -vu 0 0 1 -vh 8 -vv 8\n", 32, 0,
                                     &err);
    ic_scene *c = test_load_rad_text("vf_cyl", rad, "rview -vtc -vp 0 0 0 -vd 0 1 0 -vu 0 0 1 -vh 90 -vv 60\n", 32, 0,
                                     &err);
    CHECK(p && c, "parallel and cylindrical views load: %s", err.message);
    ic_image ip = {0}, ic = {0};
    if (p && render(p, IC_INTEGRATOR_PT, 4, 2, &ip)) {
        const float *tl = &ip.rgb[3 * (1 * 32 + 1)], *br = &ip.rgb[3 * (30 * 32 + 30)];
        CHECK(tl[2] == 2.0f && tl[0] < 0.25f, "parallel: the top-left square is blue (%g %g %g)", (double)tl[0],
              (double)tl[1], (double)tl[2]);
        /* bottom-right: column 3, row -4: (3 − 8) mod 3 = 1, green */
        CHECK(br[1] == 1.0f && br[2] < 0.35f, "parallel: the bottom-right square is green (%g %g %g)", (double)br[0],
              (double)br[1], (double)br[2]);
    }
    if (c && render(c, IC_INTEGRATOR_PT, 4, 2, &ic)) {
        CHECK(c->camera.width == 32 && c->camera.height < 32, "cylinder 90 x 60 is wider than high (%dx%d)",
              c->camera.width, c->camera.height);
        /* just right of and above the centre: column 0, row 0 (red) */
        int x = c->camera.width / 2 + 2, y = c->camera.height / 2 - 2;
        const float *px = &ic.rgb[3 * ((size_t)y * ic.width + x)];
        CHECK(px[0] == 1.0f, "cylinder: right of and above the centre the red square (%g %g %g)", (double)px[0],
              (double)px[1], (double)px[2]);
    }
    ic_image_free(&ip);
    ic_image_free(&ic);
    ic_scene_free(p);
    ic_scene_free(c);
}

static void expect_error(const char *name, const char *view, const char *const *want)
{
    ic_error err = {0};
    ic_scene *s = test_load_rad_text(name, sky_floor, view, 16, 0, &err);
    test_check_refused(name, s, &err, want);
}

static void test_errors(void)
{
    expect_error("vf_type", "rview -vtx -vp 0 0 1\n", (const char *[]){"vf_type.vf:1:", "-vtx", "-vth", NULL});
    expect_error("vf_hem200", "# wide\nrpict -vth -vh 200 -vv 180\n",
                 (const char *[]){"vf_hem200.vf:2:", "hemispherical", "180]", NULL});
    expect_error("vf_pls360", "rpict -vts -vh 360 -vv 180\n", (const char *[]){"vf_pls360.vf:1:", "planisphere", NULL});
    expect_error("vf_fore", "VIEW= -vtv -vo -1\n", (const char *[]){"vf_fore.vf:1:", "-vo", NULL});
    expect_error("vf_shift", "rview -vtv -vs 1e9\n", (const char *[]){"vf_shift.vf:1:", "-vs", NULL});
    expect_error("vf_cyl", "rview -vtc -vh 360 -vv 180\n", (const char *[]){"vf_cyl.vf:1:", "cylindrical", NULL});
}

int main(void)
{
    test_fisheyes();
    test_shift_lift();
    test_errors();
    TEST_MAIN_END();
}
