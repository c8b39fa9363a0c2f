/*
 * accel.c — Embree 3 behind the ic_accel interface (accel.h). The one file that includes Embree.
 *
 * One triangle geometry holds the whole flattened scene, so Embree's primID is the scene triangle
 * index. Streams (rtcIntersect1M / rtcOccluded1M) serve callers that trace many rays at once:
 * hemisphere gathering and camera rays of a tile.
 */
#include "accel.h"

#include <embree3/rtcore.h>
#include <stdlib.h>
#include <string.h>

struct ic_accel {
    RTCDevice device;
    RTCScene rtc_scene;
    const ic_scene *scene;
    enum RTCError first_error;
    char error_text[256];
};

static void on_embree_error(void *user, enum RTCError code, const char *str)
{
    ic_accel *a = user;
    if (a->first_error == RTC_ERROR_NONE) {
        a->first_error = code;
        strncpy(a->error_text, str ? str : "unknown", sizeof a->error_text - 1);
    }
}

ic_result ic_accel_create(const ic_scene *scene, ic_accel **out, ic_error *err)
{
    *out = NULL;
    ic_accel *a = calloc(1, sizeof *a);
    if (!a)
        return ic_error_set(err, IC_ERR_OOM, "out of memory building the ray-tracing structure");
    a->scene = scene;
    a->device = rtcNewDevice("verbose=0");
    if (!a->device) {
        free(a);
        return ic_error_set(err, IC_ERR_UNSUPPORTED, "Embree could not start (CPU without SSE2?)");
    }
    rtcSetDeviceErrorFunction(a->device, on_embree_error, a);
    a->rtc_scene = rtcNewScene(a->device);
    rtcSetSceneFlags(a->rtc_scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(a->rtc_scene, RTC_BUILD_QUALITY_HIGH);
    if (scene->triangle_count > 0) {
        RTCGeometry g = rtcNewGeometry(a->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        /* Shared buffers: Embree reads our arrays directly (ic_vec3 is 12 bytes; Embree needs 16-byte
         * readable padding after the last vertex, so copy vertices into a padded buffer it owns). */
        float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                            scene->vertex_count);
        unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                               scene->triangle_count);
        if (vb && ib) {
            for (uint32_t i = 0; i < scene->vertex_count; ++i) {
                vb[3 * i + 0] = scene->positions[i].x;
                vb[3 * i + 1] = scene->positions[i].y;
                vb[3 * i + 2] = scene->positions[i].z;
            }
            memcpy(ib, scene->triangles, sizeof(unsigned) * 3 * scene->triangle_count);
        }
        rtcCommitGeometry(g);
        rtcAttachGeometry(a->rtc_scene, g);
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(a->rtc_scene);
    if (a->first_error != RTC_ERROR_NONE) {
        ic_result r = ic_error_set(err, a->first_error == RTC_ERROR_OUT_OF_MEMORY ? IC_ERR_OOM : IC_ERR_INTERNAL,
                                   "%s: Embree failed to build the scene: %s", scene->path, a->error_text);
        ic_accel_destroy(a);
        return r;
    }
    *out = a;
    return IC_OK;
}

void ic_accel_destroy(ic_accel *a)
{
    if (!a)
        return;
    if (a->rtc_scene)
        rtcReleaseScene(a->rtc_scene);
    if (a->device)
        rtcReleaseDevice(a->device);
    free(a);
}

static void to_rtc_ray(const ic_ray *r, struct RTCRay *o)
{
    o->org_x = r->org.x;
    o->org_y = r->org.y;
    o->org_z = r->org.z;
    o->dir_x = r->dir.x;
    o->dir_y = r->dir.y;
    o->dir_z = r->dir.z;
    o->tnear = r->tnear;
    o->tfar = r->tfar;
    o->time = 0.0f;
    o->mask = 0xffffffffu;
    o->id = 0;
    o->flags = 0;
}

static void from_rtc_hit(const struct RTCRayHit *rh, ic_hit *h)
{
    if (rh->hit.geomID == RTC_INVALID_GEOMETRY_ID) {
        h->triangle = IC_NO_HIT;
        h->t = INFINITY;
        h->u = h->v = 0.0f;
    } else {
        h->triangle = rh->hit.primID;
        h->t = rh->ray.tfar;
        h->u = rh->hit.u;
        h->v = rh->hit.v;
    }
}

void ic_accel_intersect1(const ic_accel *a, const ic_ray *ray, ic_hit *hit)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRayHit rh;
    to_rtc_ray(ray, &rh.ray);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(a->rtc_scene, &ctx, &rh);
    from_rtc_hit(&rh, hit);
}

int ic_accel_occluded1(const ic_accel *a, const ic_ray *ray)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRay r;
    to_rtc_ray(ray, &r);
    rtcOccluded1(a->rtc_scene, &ctx, &r);
    return r.tfar < 0.0f;
}

/* Streams are processed in chunks on the stack so no allocation happens per call. */
#define STREAM_CHUNK 256

void ic_accel_intersect_n(const ic_accel *a, const ic_ray *rays, ic_hit *hits, uint32_t count, int coherent)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    struct RTCRayHit rh[STREAM_CHUNK];
    for (uint32_t base = 0; base < count; base += STREAM_CHUNK) {
        uint32_t n = count - base < STREAM_CHUNK ? count - base : STREAM_CHUNK;
        for (uint32_t i = 0; i < n; ++i) {
            to_rtc_ray(&rays[base + i], &rh[i].ray);
            rh[i].hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rh[i].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        }
        rtcIntersect1M(a->rtc_scene, &ctx, rh, n, sizeof(struct RTCRayHit));
        for (uint32_t i = 0; i < n; ++i)
            from_rtc_hit(&rh[i], &hits[base + i]);
    }
}

void ic_accel_occluded_n(const ic_accel *a, const ic_ray *rays, uint8_t *occluded, uint32_t count, int coherent)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    struct RTCRay r[STREAM_CHUNK];
    for (uint32_t base = 0; base < count; base += STREAM_CHUNK) {
        uint32_t n = count - base < STREAM_CHUNK ? count - base : STREAM_CHUNK;
        for (uint32_t i = 0; i < n; ++i)
            to_rtc_ray(&rays[base + i], &r[i]);
        rtcOccluded1M(a->rtc_scene, &ctx, r, n, sizeof(struct RTCRay));
        for (uint32_t i = 0; i < n; ++i)
            occluded[base + i] = r[i].tfar < 0.0f;
    }
}
