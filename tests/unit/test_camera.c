/*
 * test_camera.c — the camera's projections (Radiance's view types, Larson & Shakespeare 1998) against their
 * formulas, on a camera at the origin looking along +y with +z up (+x is then right):
 *   1. perspective: the centre looks ahead, corners at the tangents of the half angles (left and right
 *      exchanged in a mirrored camera), shift and lift move the image plane by fractions of its size, the
 *      fore clip moves the origin along the axis;
 *   2. parallel: origins on the size_x × size_y rectangle, all directions ahead;
 *   3. hemispherical, angular, stereographic fisheyes: the angle from the axis at known radii (sin θ, θ,
 *      tan θ/2 proportional to the radius), no ray outside the hemispherical one's circle and beyond θ = 180°
 *      in the angular one;
 *   4. cylindrical panorama: azimuth linear across, perspective up;
 *   5. ic_camera_project inverts ic_camera_ray for every projection, mirrored or not (random film positions),
 *      and a mirrored camera's rays and projections are the plain one's mirrored left to right;
 *   6. footprints: the perspective one is t times the pixel angle; a fisheye's at its centre is t times the
 *      angle across one pixel there (from the formula), a parallel view's the pixel width.
 */
#include "test_util.h"

#include "core/rng.h"
#include "film/film.h"
#include "scene/scene.h"

#define PI_D 3.14159265358979323846

static ic_camera make(ic_projection p, int w, int h, float size_x, float size_y)
{
    ic_camera c = {0};
    c.eye = v3s(0.0f);
    c.target = v3(0.0f, 1.0f, 0.0f);
    c.up = v3(0.0f, 0.0f, 1.0f);
    c.width = w;
    c.height = h;
    c.projection = p;
    c.size_x = size_x;
    c.size_y = size_y;
    c.fov_y_deg = size_y;
    return c;
}

/* The direction through film position (fx, fy); zero if there is no ray. */
static ic_vec3 dir_at(const ic_camera *c, float fx, float fy)
{
    ic_ray r;
    return ic_camera_ray(c, fx, fy, &r) ? r.dir : v3s(0.0f);
}

static int near_dir(ic_vec3 a, ic_vec3 b, double tol)
{
    ic_vec3 n = v3_len2(b) > 0.0f ? v3_norm(b) : b;
    return fabs(a.x - n.x) <= tol && fabs(a.y - n.y) <= tol && fabs(a.z - n.z) <= tol;
}

#define CHECK_DIR(a, b, what)                                                                                  \
    do {                                                                                                       \
        ic_vec3 a_ = (a), b_ = (b);                                                                            \
        CHECK(near_dir(a_, b_, 2e-5), "%s: (%g %g %g), expected (%g %g %g)", what, (double)a_.x, (double)a_.y, \
              (double)a_.z, (double)b_.x, (double)b_.y, (double)b_.z);                                         \
    } while (0)

/* Unit direction at angle theta from the axis (+y), towards azimuth phi in the image plane (0: right). */
static ic_vec3 polar(double theta, double phi)
{
    return v3((float)(sin(theta) * cos(phi)), (float)cos(theta), (float)(sin(theta) * sin(phi)));
}

static void test_perspective(void)
{
    ic_camera c = make(IC_PROJECTION_PERSPECTIVE, 40, 20, 0.0f, 30.0f);
    double ty = tan(15.0 * PI_D / 180.0), tx = 2.0 * ty;
    CHECK_DIR(dir_at(&c, 20.0f, 10.0f), v3(0.0f, 1.0f, 0.0f), "perspective centre");
    CHECK_DIR(dir_at(&c, 0.0f, 0.0f), v3((float)-tx, 1.0f, (float)ty), "perspective top-left corner");
    CHECK_DIR(dir_at(&c, 40.0f, 10.0f), v3((float)tx, 1.0f, 0.0f), "perspective right edge");
    ic_camera mirrored = c;
    mirrored.is_mirrored = 1;
    CHECK_DIR(dir_at(&mirrored, 0.0f, 0.0f), v3((float)tx, 1.0f, (float)ty), "mirrored: the top-left corner looks right");
    CHECK_DIR(dir_at(&mirrored, 20.0f, 10.0f), v3(0.0f, 1.0f, 0.0f), "mirrored: the centre still looks ahead");
    c.shift = 0.25f;
    c.lift = -0.5f;
    /* the plane moves right by a quarter of its width (2 tx) and down by half its height (2 ty) */
    CHECK_DIR(dir_at(&c, 20.0f, 10.0f), v3((float)(0.5 * tx), 1.0f, (float)-ty), "shifted and lifted centre");
    CHECK_DIR(dir_at(&c, 0.0f, 0.0f), v3((float)(-0.5 * tx), 1.0f, 0.0f), "shifted and lifted corner");
    c.shift = c.lift = 0.0f;
    c.clip_near = 2.0f;
    ic_ray r;
    ic_camera_ray(&c, 40.0f, 10.0f, &r);
    CHECK(fabsf(r.org.y - 2.0f) < 1e-5f && fabsf(r.org.x - 2.0f * (float)tx) < 1e-5f,
          "fore clip: origin on the plane 2 ahead (%g %g %g)", (double)r.org.x, (double)r.org.y, (double)r.org.z);
}

static void test_parallel(void)
{
    ic_camera c = make(IC_PROJECTION_PARALLEL, 40, 20, 4.0f, 2.0f);
    ic_ray r;
    CHECK(ic_camera_ray(&c, 0.0f, 0.0f, &r), "parallel: a ray everywhere");
    CHECK(fabsf(r.org.x + 2.0f) < 1e-6f && fabsf(r.org.z - 1.0f) < 1e-6f && fabsf(r.org.y) < 1e-6f,
          "parallel top-left corner origin (%g %g %g), expected (-2 0 1)", (double)r.org.x, (double)r.org.y,
          (double)r.org.z);
    CHECK_DIR(r.dir, v3(0.0f, 1.0f, 0.0f), "parallel direction");
    c.shift = 0.5f;
    ic_camera_ray(&c, 20.0f, 10.0f, &r);
    CHECK(fabsf(r.org.x - 2.0f) < 1e-6f, "parallel shifted centre at x = 2: %g", (double)r.org.x);
    CHECK_NEAR(ic_camera_footprint(&c, 3.0f, 4.0f, 17.0f), 0.1, 1e-6, "parallel footprint: the pixel width");
}

static void test_fisheyes(void)
{
    const int n = 64;
    /* hemispherical 180°: the radius is sin θ (the rim at θ = 90°) */
    ic_camera h = make(IC_PROJECTION_HEMISPHERICAL, n, n, 180.0f, 180.0f);
    CHECK_DIR(dir_at(&h, 32.0f, 32.0f), v3(0.0f, 1.0f, 0.0f), "hemispherical centre");
    CHECK_DIR(dir_at(&h, 64.0f, 32.0f), v3(1.0f, 0.0f, 0.0f), "hemispherical right rim");
    CHECK_DIR(dir_at(&h, 32.0f, 0.0f), v3(0.0f, 0.0f, 1.0f), "hemispherical top rim");
    CHECK_DIR(dir_at(&h, 48.0f, 32.0f), polar(asin(0.5), 0.0), "hemispherical half radius: sin θ = 1/2");
    CHECK_DIR(dir_at(&h, 16.0f, 32.0f), polar(asin(0.5), PI_D), "hemispherical half radius, left");
    ic_ray r;
    CHECK(!ic_camera_ray(&h, 0.5f, 0.5f, &r) && !ic_camera_ray(&h, 63.5f, 63.5f, &r), "hemispherical corners: no ray");
    /* a narrower one: 120° across, so the rim is at θ = 60° */
    ic_camera h2 = make(IC_PROJECTION_HEMISPHERICAL, n, n, 120.0f, 120.0f);
    CHECK_DIR(dir_at(&h2, 64.0f, 32.0f), polar(PI_D / 3.0, 0.0), "hemispherical 120: rim at 60 degrees");

    /* angular: the radius is θ */
    ic_camera a = make(IC_PROJECTION_ANGULAR, n, n, 180.0f, 180.0f);
    CHECK_DIR(dir_at(&a, 32.0f, 32.0f), v3(0.0f, 1.0f, 0.0f), "angular centre");
    CHECK_DIR(dir_at(&a, 64.0f, 32.0f), v3(1.0f, 0.0f, 0.0f), "angular 180: rim at 90 degrees");
    CHECK_DIR(dir_at(&a, 48.0f, 32.0f), polar(PI_D / 4.0, 0.0), "angular half radius: 45 degrees");
    CHECK_DIR(dir_at(&a, 32.0f + 16.0f * (float)sqrt(0.5), 32.0f - 16.0f * (float)sqrt(0.5)), polar(PI_D / 4.0, PI_D / 4.0),
              "angular half radius, diagonal");
    /* as in Radiance, only θ > 180° has no ray: a 180° image's corners look behind the camera */
    CHECK_DIR(dir_at(&a, 0.0f, 0.0f), polar(PI_D * sqrt(0.5), 0.75 * PI_D), "angular 180: the corner at 127 degrees");
    ic_camera a360 = make(IC_PROJECTION_ANGULAR, n, n, 360.0f, 360.0f);
    CHECK(!ic_camera_ray(&a360, 1.0f, 1.0f, &r), "angular 360: corner has no ray");
    CHECK_DIR(dir_at(&a360, 48.0f, 32.0f), v3(1.0f, 0.0f, 0.0f), "angular 360: half radius at 90 degrees");
    CHECK_DIR(dir_at(&a360, 32.0f, 56.0f), polar(0.75 * PI_D, -0.5 * PI_D), "angular 360: 3/4 radius down, 135 degrees");

    /* stereographic: the radius is tan(θ/2) */
    ic_camera s = make(IC_PROJECTION_STEREOGRAPHIC, n, n, 180.0f, 180.0f);
    CHECK_DIR(dir_at(&s, 32.0f, 32.0f), v3(0.0f, 1.0f, 0.0f), "stereographic centre");
    CHECK_DIR(dir_at(&s, 64.0f, 32.0f), v3(1.0f, 0.0f, 0.0f), "stereographic 180: rim at 90 degrees");
    CHECK_DIR(dir_at(&s, 48.0f, 32.0f), polar(2.0 * atan(0.5), 0.0), "stereographic half radius: tan(θ/2) = 1/2");
    CHECK_DIR(dir_at(&s, 0.0f, 0.0f), polar(2.0 * atan(sqrt(2.0)), 0.75 * PI_D), "stereographic corner: beyond the rim");

    /* footprints at the centre: the angle across one pixel there, times the distance */
    CHECK_NEAR(ic_camera_footprint(&a, 32.0f, 32.0f, 10.0f), 10.0 * PI_D / n, 1e-3 * 10.0 * PI_D / n,
               "angular footprint at the centre: t pi / n");
    CHECK_NEAR(ic_camera_footprint(&h, 32.0f, 32.0f, 10.0f), 10.0 * 2.0 / n, 1e-3 * 20.0 / n,
               "hemispherical footprint at the centre: t 2 / n");
    float rim = ic_camera_footprint(&h, 63.5f, 32.0f, 10.0f), mid = ic_camera_footprint(&h, 32.0f, 32.0f, 10.0f);
    CHECK(rim > mid, "hemispherical footprint grows towards the rim (pixels span more angle): %g > %g", (double)rim,
          (double)mid);
}

static void test_cylinder(void)
{
    ic_camera c = make(IC_PROJECTION_CYLINDRICAL, 72, 18, 360.0f, 90.0f);
    CHECK_DIR(dir_at(&c, 36.0f, 9.0f), v3(0.0f, 1.0f, 0.0f), "cylinder centre");
    CHECK_DIR(dir_at(&c, 54.0f, 9.0f), v3(1.0f, 0.0f, 0.0f), "cylinder three quarters across: 90 degrees right");
    CHECK_DIR(dir_at(&c, 0.0f, 9.0f), v3(0.0f, -1.0f, 0.0f), "cylinder left edge: behind");
    CHECK_DIR(dir_at(&c, 36.0f, 0.0f), v3(0.0f, 1.0f, 1.0f), "cylinder top: 45 degrees up (perspective)");
    CHECK_DIR(dir_at(&c, 54.0f, 18.0f), v3(1.0f, 0.0f, -1.0f), "cylinder bottom at 90 degrees right");
}

/* ic_camera_project(ic_camera_ray(f)) = f, at a point 3 along each ray. */
static void test_inverse(void)
{
    ic_camera cams[] = {make(IC_PROJECTION_PERSPECTIVE, 48, 32, 0.0f, 50.0f),
                        make(IC_PROJECTION_PARALLEL, 48, 32, 3.0f, 2.0f),
                        make(IC_PROJECTION_HEMISPHERICAL, 48, 32, 180.0f, 120.0f),
                        make(IC_PROJECTION_ANGULAR, 48, 32, 360.0f, 240.0f),
                        make(IC_PROJECTION_CYLINDRICAL, 48, 32, 300.0f, 100.0f),
                        make(IC_PROJECTION_STEREOGRAPHIC, 48, 32, 200.0f, 150.0f)};
    enum { N = sizeof cams / sizeof cams[0] };
    for (size_t k = 0; k < 2 * N; ++k) { /* each projection plain, then mirrored */
        ic_camera *c = &cams[k % N];
        c->is_mirrored = k >= N;
        c->eye = v3(1.0f, 2.0f, 3.0f);
        c->target = v3(2.0f, 2.5f, 3.2f);
        c->shift = 0.1f;
        c->lift = -0.2f;
        ic_rng rng = ic_rng_make(7, k, 0, 0);
        int tried = 0, bad = 0;
        double worst = 0.0;
        for (int i = 0; i < 500; ++i) {
            float fx = 48.0f * ic_rng_float(&rng), fy = 32.0f * ic_rng_float(&rng), gx, gy, depth;
            ic_ray r;
            if (!ic_camera_ray(c, fx, fy, &r))
                continue;
            ++tried;
            if (!ic_camera_project(c, v3_add(r.org, v3_scale(r.dir, 3.0f)), &gx, &gy, &depth)) {
                ++bad;
                continue;
            }
            double e = fmax(fabs(gx - fx), fabs(gy - fy));
            worst = fmax(worst, e);
        }
        CHECK(tried > 200 && bad == 0 && worst < 2e-3, "projection %d%s: project inverts the ray (%d rays, %d unprojected, "
              "worst %g px)", (int)c->projection, c->is_mirrored ? " mirrored" : "", tried, bad, worst);
    }
}

/* A mirrored camera is the plain one seen in a mirror, for every projection: its ray through (x, y) is
 * the plain camera's through (width - x, y) once the horizontal shift is turned too, and a point projects
 * to (width - x, y) where the plain camera projects it to (x, y). */
static void test_mirrored(void)
{
    const ic_camera cams[] = {make(IC_PROJECTION_PERSPECTIVE, 48, 32, 0.0f, 50.0f),
                              make(IC_PROJECTION_PARALLEL, 48, 32, 3.0f, 2.0f),
                              make(IC_PROJECTION_HEMISPHERICAL, 48, 32, 180.0f, 120.0f),
                              make(IC_PROJECTION_ANGULAR, 48, 32, 360.0f, 240.0f),
                              make(IC_PROJECTION_CYLINDRICAL, 48, 32, 300.0f, 100.0f),
                              make(IC_PROJECTION_STEREOGRAPHIC, 48, 32, 200.0f, 150.0f)};
    for (size_t k = 0; k < sizeof cams / sizeof cams[0]; ++k) {
        ic_camera plain = cams[k], mirrored = cams[k];
        plain.eye = mirrored.eye = v3(1.0f, 2.0f, 3.0f);
        plain.target = mirrored.target = v3(2.0f, 2.5f, 3.2f);
        plain.lift = mirrored.lift = -0.2f;
        mirrored.shift = 0.1f;
        plain.shift = -0.1f;
        mirrored.is_mirrored = 1;
        ic_rng rng = ic_rng_make(11, k, 0, 0);
        int rays = 0, differ = 0;
        double worst = 0.0;
        for (int i = 0; i < 300; ++i) {
            float fx = 48.0f * ic_rng_float(&rng), fy = 32.0f * ic_rng_float(&rng);
            ic_ray a, b;
            int ha = ic_camera_ray(&mirrored, fx, fy, &a), hb = ic_camera_ray(&plain, 48.0f - fx, fy, &b);
            differ += ha != hb;
            if (!ha || !hb)
                continue;
            ++rays;
            worst = fmax(worst, v3_len(v3_sub(a.dir, b.dir)) + v3_len(v3_sub(a.org, b.org)));
            ic_vec3 q = v3_add(b.org, v3_scale(b.dir, 2.5f));
            float mx, my, px, py, dm, dp;
            if (!ic_camera_project(&mirrored, q, &mx, &my, &dm) || !ic_camera_project(&plain, q, &px, &py, &dp)) {
                ++differ;
                continue;
            }
            worst = fmax(worst, fabs(mx - (48.0f - px)) / 48.0 + fabs(my - py) / 32.0 + fabs(dm - dp));
        }
        CHECK(rays > 150 && differ == 0 && worst < 1e-4,
              "projection %d: the mirrored camera is the plain one mirrored (%d rays, %d that one has and the other "
              "not, worst %g)", (int)cams[k].projection, rays, differ, worst);
    }
}

int main(void)
{
    test_perspective();
    test_parallel();
    test_fisheyes();
    test_cylinder();
    test_inverse();
    test_mirrored();
    TEST_MAIN_END();
}
