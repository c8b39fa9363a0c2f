/*
 * bench_trace.c — rays per second of the tracing module (src/geom) against a bare Embree loop over
 * the same rays in the same run, for camera rays and for cosine-distributed hemisphere rays from
 * the primary hit points. Also path-tracer samples per second with 1 and 2 threads.
 *
 * usage: bench_trace SCENE [width height] [repeats]
 * Prints one table; the ratio column is module / bare (target ≥ 0.8).
 */
#include "core/rng.h"
#include "core/sampling.h"
#include "film/film.h"
#include "geom/accel.h"
#include "irrcache/render.h"
#include "scene/scene.h"

#include <embree3/rtcore.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct bare {
    RTCDevice dev;
    RTCScene scene;
} bare;

static bare bare_build(const ic_scene *s)
{
    bare b;
    b.dev = rtcNewDevice(NULL);
    b.scene = rtcNewScene(b.dev);
    rtcSetSceneFlags(b.scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(b.scene, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry g = rtcNewGeometry(b.dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, s->vertex_count);
    unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, s->triangle_count);
    memcpy(vb, s->positions, 12 * (size_t)s->vertex_count);
    memcpy(ib, s->triangles, 12 * (size_t)s->triangle_count);
    rtcCommitGeometry(g);
    rtcAttachGeometry(b.scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(b.scene);
    return b;
}

static double bare_trace(const bare *b, const ic_ray *rays, size_t n, double *checksum)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    double t0 = ic_seconds(), sum = 0.0;
    for (size_t i = 0; i < n; ++i) {
        struct RTCRayHit rh;
        rh.ray.org_x = rays[i].org.x;
        rh.ray.org_y = rays[i].org.y;
        rh.ray.org_z = rays[i].org.z;
        rh.ray.dir_x = rays[i].dir.x;
        rh.ray.dir_y = rays[i].dir.y;
        rh.ray.dir_z = rays[i].dir.z;
        rh.ray.tnear = rays[i].tnear;
        rh.ray.tfar = rays[i].tfar;
        rh.ray.mask = 0xffffffffu;
        rh.ray.flags = 0;
        rh.ray.time = 0.0f;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(b->scene, &ctx, &rh);
        if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID)
            sum += rh.ray.tfar;
    }
    *checksum = sum;
    return ic_seconds() - t0;
}

static double module_trace1(const ic_accel *a, const ic_ray *rays, size_t n, double *checksum)
{
    double t0 = ic_seconds(), sum = 0.0;
    for (size_t i = 0; i < n; ++i) {
        ic_hit h;
        ic_accel_intersect1(a, &rays[i], &h);
        if (h.triangle != IC_NO_HIT)
            sum += h.t;
    }
    *checksum = sum;
    return ic_seconds() - t0;
}

static double module_trace_n(const ic_accel *a, const ic_ray *rays, ic_hit *hits, size_t n, int coherent,
                             double *checksum)
{
    double t0 = ic_seconds(), sum = 0.0;
    const size_t chunk = 1024;
    for (size_t i = 0; i < n; i += chunk) {
        uint32_t m = (uint32_t)(n - i < chunk ? n - i : chunk);
        ic_accel_intersect_n(a, rays + i, hits + i, m, coherent);
    }
    for (size_t i = 0; i < n; ++i)
        if (hits[i].triangle != IC_NO_HIT)
            sum += hits[i].t;
    *checksum = sum;
    return ic_seconds() - t0;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return v[n / 2];
}

static void compare(const char *label, const bare *b, const ic_accel *a, const ic_ray *rays, ic_hit *hits, size_t n,
                    int coherent, int repeats)
{
    double tb[16], t1[16], tn[16], cb = 0, c1 = 0, cn = 0;
    for (int r = 0; r < repeats; ++r) {
        tb[r] = bare_trace(b, rays, n, &cb);
        t1[r] = module_trace1(a, rays, n, &c1);
        tn[r] = module_trace_n(a, rays, hits, n, coherent, &cn);
    }
    double mb = median(tb, repeats), m1 = median(t1, repeats), mn = median(tn, repeats);
    printf("%-22s %9zu  %8.2f  %8.2f  %8.2f  %6.2f  %6.2f   %s\n", label, n, n / mb * 1e-6, n / m1 * 1e-6,
           n / mn * 1e-6, mb / m1, mb / mn,
           (fabs(cb - c1) <= 1e-6 * fabs(cb) && fabs(cb - cn) <= 1e-6 * fabs(cb)) ? "same hits" : "HITS DIFFER");
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: bench_trace SCENE [width height] [repeats]\n");
        return 2;
    }
    ic_scene_load_options lo = {0};
    lo.width = argc > 3 ? atoi(argv[2]) : 640;
    lo.height = argc > 3 ? atoi(argv[3]) : 360;
    int repeats = argc > 4 ? atoi(argv[4]) : 5;
    if (repeats < 1 || repeats > 16)
        repeats = 5;
    ic_error err;
    ic_scene *scene;
    if (ic_scene_load(argv[1], &lo, &scene, &err) != IC_OK) {
        fprintf(stderr, "bench_trace: %s\n", err.message);
        return 1;
    }
    ic_accel *accel;
    if (ic_accel_create(scene, &accel, &err) != IC_OK) {
        fprintf(stderr, "bench_trace: %s\n", err.message);
        return 1;
    }
    bare b = bare_build(scene);
    const ic_camera *cam = &scene->camera;
    size_t n = (size_t)cam->width * (size_t)cam->height;
    ic_ray *cam_rays = malloc(n * sizeof *cam_rays);
    ic_ray *hemi = malloc(n * sizeof *hemi);
    ic_hit *hits = malloc(n * sizeof *hits);
    for (int y = 0; y < cam->height; ++y)
        for (int x = 0; x < cam->width; ++x)
            (void)ic_camera_ray(cam, x + 0.5f, y + 0.5f, &cam_rays[(size_t)y * cam->width + x]);
    /* Hemisphere rays: 16 cosine-distributed rays from each of n/16 primary hit points, in gather order. */
    ic_accel_intersect_n(accel, cam_rays, hits, (uint32_t)n, 1);
    size_t m = 0;
    for (size_t i = 0; i < n && m + 16 <= n; i += 16) {
        size_t p = (i * 7919) % n;
        if (hits[p].triangle == IC_NO_HIT)
            continue;
        ic_surface s;
        ic_scene_surface(scene, hits[p].triangle, hits[p].u, hits[p].v, &s);
        ic_frame f = ic_frame_from_normal(v3_dot(s.ng, cam_rays[p].dir) > 0 ? v3_neg(s.ng) : s.ng);
        ic_rng rng = ic_rng_make(5, p, 0, 0);
        for (int k = 0; k < 16; ++k) {
            ic_vec3 d = ic_frame_to_world(&f, ic_warp_cosine_hemisphere(ic_rng_float(&rng), ic_rng_float(&rng)));
            hemi[m].org = ic_offset_ray_origin(s.p, f.n, d);
            hemi[m].dir = d;
            hemi[m].tnear = 0.0f;
            hemi[m].tfar = INFINITY;
            ++m;
        }
    }
    printf("scene %s: %u triangles, %dx%d, median of %d runs, 1 thread\n", argv[1], scene->triangle_count,
           cam->width, cam->height, repeats);
    printf("%-22s %9s  %8s  %8s  %8s  %6s  %6s\n", "rays", "count", "bare", "module1", "moduleN", "r1", "rN");
    printf("%-22s %9s  %8s  %8s  %8s  %6s  %6s\n", "", "", "Mray/s", "Mray/s", "Mray/s", "", "");
    compare("camera", &b, accel, cam_rays, hits, n, 1, repeats);
    compare("hemisphere (cosine)", &b, accel, hemi, hits, m, 0, repeats);

    /* Path tracer samples per second, 1 and 2 threads. */
    ic_render_options opt = {0};
    opt.spp = 4;
    double sps[2];
    for (int t = 1; t <= 2; ++t) {
        opt.threads = t;
        ic_image img = {0};
        ic_render_stats st;
        double best = 0.0;
        for (int r = 0; r < 3; ++r) {
            if (ic_render(scene, &opt, &img, &st, &err) != IC_OK) {
                fprintf(stderr, "bench_trace: %s\n", err.message);
                return 1;
            }
            double s = (double)n * opt.spp / st.phases[st.phase_count - 1].seconds;
            if (s > best)
                best = s;
            ic_image_free(&img);
        }
        sps[t - 1] = best;
        printf("path tracer, %d thread%s: %.3f Msamples/s (%d spp, best of 3)\n", t, t > 1 ? "s" : "", best * 1e-6,
               opt.spp);
    }
    printf("path tracer scaling 1 -> 2 threads: %.2fx\n", sps[1] / sps[0]);
    free(cam_rays);
    free(hemi);
    free(hits);
    rtcReleaseScene(b.scene);
    rtcReleaseDevice(b.dev);
    ic_accel_destroy(accel);
    ic_scene_free(scene);
    return 0;
}
