/*
 * bench_radiance.c — what radiance records cost: the look-up of a glossy lobe's outgoing radiance from
 * radiance records (lobe table, rotation where the normals differ, three dot products of n² per record)
 * against one irradiance look-up at the same points, the records of each kind and their memory, for
 * the lazy, batch and adaptive strategies.
 *
 * usage: bench_radiance [SCENE [width height [max-exponent]]] — default: the glossy Cornell box with a
 * floor of exponent 20, 160×160, exponent limit 40 (the sphere, 32, is served too). Builds the cache as
 * a render does (irradiance records, then radiance records), then times, single-threaded, look-ups at
 * every pixel's first hit on a served material, in raster order: the irradiance look-up there and the
 * glossy look-up (ic_ic_radiance_lookup). Median of 5 passes. Prints figures; asserts nothing.
 */
#include "film/film.h"
#include "geom/accel.h"
#include "integrators/ic_internal.h"
#include "scene/scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void fail(const char *msg)
{
    fprintf(stderr, "bench_radiance: %s\n", msg);
    exit(1);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

typedef struct glossy_pts {
    ic_vec3 *p, *n, *wo;
    uint32_t *material;
    uint32_t count;
} glossy_pts;

static glossy_pts first_hits(const ic_ctx *c)
{
    const ic_camera *cam = &c->tr->scene->camera;
    size_t npix = (size_t)cam->width * cam->height;
    glossy_pts g = {malloc(npix * sizeof(ic_vec3)), malloc(npix * sizeof(ic_vec3)), malloc(npix * sizeof(ic_vec3)),
                    malloc(npix * sizeof(uint32_t)), 0};
    if (!g.p || !g.n || !g.wo || !g.material)
        fail("out of memory");
    for (int y = 0; y < cam->height; ++y)
        for (int x = 0; x < cam->width; ++x) {
            ic_ray ray;
            if (!ic_camera_ray(cam, (float)x + 0.5f, (float)y + 0.5f, &ray))
                continue;
            ic_hit hit;
            ic_accel_intersect1(c->tr->accel, &ray, &hit);
            if (hit.triangle == IC_NO_HIT)
                continue;
            ic_surface s;
            ic_scene_surface(c->tr->scene, hit.triangle, hit.u, hit.v, &s);
            if (!ic_ic_radiance_serves(c, s.material))
                continue;
            ic_bsdf b;
            ic_bsdf_init(&b, c->tr->scene, &s, v3_neg(ray.dir));
            g.p[g.count] = s.p;
            g.n[g.count] = b.frame.n;
            g.wo[g.count] = v3_neg(ray.dir);
            g.material[g.count++] = s.material;
        }
    return g;
}

static void measure(const char *label, const ic_ctx *c, const glossy_pts *g, const ic_render_stats *st, double build)
{
    enum { PASSES = 5 };
    double t_irr[PASSES], t_rad[PASSES], sum = 0.0;
    uint32_t found_irr = 0, found_rad = 0;
    for (int pass = 0; pass < PASSES; ++pass) {
        ic_cache_hint hint = {0};
        double t0 = ic_seconds();
        found_irr = 0;
        for (uint32_t i = 0; i < g->count; ++i) {
            ic_cache_lookup q = ic_cache_lookup_at(g->p[i], g->n[i], IC_ACCEPT_FINAL);
            ic_cache_estimate e;
            found_irr += (uint32_t)ic_cache_query_hinted(c->cache, &q, &hint, &e);
            sum += e.irradiance.x;
        }
        t_irr[pass] = ic_seconds() - t0;
        ic_cache_hint hint2 = {0};
        t0 = ic_seconds();
        found_rad = 0;
        for (uint32_t i = 0; i < g->count; ++i) {
            ic_vec3 L;
            if (ic_ic_radiance_lookup(c, g->p[i], g->n[i], g->material[i], g->wo[i], &hint2, &L)) {
                ++found_rad;
                sum += L.x;
            }
        }
        t_rad[pass] = ic_seconds() - t0;
    }
    qsort(t_irr, PASSES, sizeof *t_irr, cmp_double);
    qsort(t_rad, PASSES, sizeof *t_rad, cmp_double);
    double us_irr = 1e6 * t_irr[PASSES / 2] / g->count, us_rad = 1e6 * t_rad[PASSES / 2] / g->count;
    printf("%-9s %6u irradiance + %5u radiance records (%u bytes each), built in %6.2f s | %u glossy points: "
           "irradiance look-up %6.3f µs (%u found), glossy look-up %7.3f µs (%u found), ratio %5.1f [digest %.6g]\n",
           label, st->records - st->radiance_records, st->radiance_records, st->radiance_record_bytes, build,
           g->count, us_irr, found_irr, us_rad, found_rad, us_rad / us_irr, sum);
}

int main(int argc, char **argv)
{
    const char *scene_path =
        argc > 1 ? argv[1] : IC_SOURCE_DIR "/scenes/cornell-box-glossy/cornell-box-glossy-20.json";
    int width = argc > 3 ? atoi(argv[2]) : 160, height = argc > 3 ? atoi(argv[3]) : 160;
    float max_exponent = argc > 4 ? (float)atof(argv[4]) : 40.0f;
    ic_error err = {0};
    ic_scene_load_options lo = {0};
    lo.width = width;
    lo.height = height;
    ic_scene *scene = NULL;
    ic_accel *accel = NULL;
    if (ic_scene_load(scene_path, &lo, &scene, &err) != IC_OK || ic_accel_create(scene, &accel, &err) != IC_OK)
        fail(err.message);
    ic_tracer tr;
    tr.scene = scene;
    tr.accel = accel;
    tr.pt.max_depth = 8;
    tr.pt.rr_depth = 0;
    tr.pt = ic_pt_params_resolve(tr.pt);
    printf("scene %s, %dx%d, radiance records for Phong exponents up to %g, order %u, final acceptance, one thread\n",
           scene_path, width, height, (double)max_exponent, IC_DEFAULT_HSH_ORDER);
    const ic_strategy strategies[] = {IC_STRATEGY_LAZY, IC_STRATEGY_BATCH, IC_STRATEGY_ADAPTIVE};
    const char *names[] = {"lazy", "batch", "adaptive"};
    for (int k = 0; k < 3; ++k) {
        ic_render_options opt = {0};
        opt.integrator = IC_INTEGRATOR_IC;
        opt.seed = 1;
        opt.ic.strategy = strategies[k];
        opt.ic.radiance_cache = IC_CACHE_ON;
        opt.ic.radiance_max_exponent = max_exponent;
        ic_ctx *c;
        ic_render_stats st;
        memset(&st, 0, sizeof st);
        phase_times pt = {0};
        uint32_t made = 0, refined = 0;
        double t0 = ic_seconds();
        if (ic_ic_ctx_create(&tr, &opt, &c, NULL, &err) != IC_OK || ic_ic_radiance_create(c, &err) != IC_OK ||
            ic_ic_build(c, &opt, &st, &pt, &err) != IC_OK ||
            ic_ic_radiance_build(c, &opt, &pt, &made, &refined, &err) != IC_OK ||
            ic_cache_rebuild_index(c->cache, &err) != IC_OK)
            fail(err.message);
        double build = ic_seconds() - t0;
        if (!c->rad)
            fail("no material of the scene is served by radiance records (raise the exponent limit)");
        st.records = ic_cache_count(c->cache);
        st.radiance_records = made;
        st.radiance_record_bytes =
            (uint32_t)(ic_cache_bytes_per_record() + sizeof(float) * ic_ic_radiance_payload_floats(c->rad));
        glossy_pts g = first_hits(c);
        measure(names[k], c, &g, &st, build);
        free(g.p);
        free(g.n);
        free(g.wo);
        free(g.material);
        ic_ic_radiance_destroy(c->rad);
        ic_ic_ctx_destroy(c);
    }
    ic_accel_destroy(accel);
    ic_scene_free(scene);
    return 0;
}
