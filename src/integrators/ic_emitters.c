/*
 * ic_emitters.c — which large emitters the records carry instead of the final render's light sampling
 * (ic_ic_options.large_emitters): a pilot on the image's shading points measures, per emitting
 * material, the variance of both estimators of its direct light, and the records take the material
 * where theirs is the lower one.
 */
#include "ic_internal.h"

#include "core/comm.h"
#include "core/sampling.h"
#include "core/threads.h"
#include "irrcache/defaults.h"
#include "irrcache/image.h"

#include <stdlib.h>
#include <string.h>

/* Projected solid angle of triangle (a, b, c) seen from p above the plane with normal n, over π: the
 * share of p's cosine-weighted hemisphere it covers, unoccluded. The solid angle is Van Oosterom and
 * Strackee's (1983) closed form; the cosine is taken at the triangle's centroid (a small triangle's
 * exact value, a fair one for a large triangle seen from afar). */
static double hemisphere_share(ic_vec3 p, ic_vec3 n, ic_vec3 a, ic_vec3 b, ic_vec3 c)
{
    ic_vec3 ra = v3_sub(a, p), rb = v3_sub(b, p), rc = v3_sub(c, p);
    double la = v3_len(ra), lb = v3_len(rb), lc = v3_len(rc);
    double num = fabs((double)v3_dot(ra, v3_cross(rb, rc)));
    double den = la * lb * lc + v3_dot(ra, rb) * lc + v3_dot(ra, rc) * lb + v3_dot(rb, rc) * la;
    double omega = 2.0 * atan2(num, den);
    ic_vec3 d = v3_sub(v3_scale(v3_add(v3_add(a, b), c), 1.0f / 3.0f), p);
    double dl = v3_len(d), cos_r = dl > 0.0 ? v3_dot(d, n) / dl : 0.0;
    return cos_r > 0.0 && isfinite(omega) ? omega * cos_r / IC_PI : 0.0;
}

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* Pilot (choose_materials): at most this many shading points, every stride-th valid pixel's, and this
 * many light samples at each. */
#define PILOT_POINTS 512
#define PILOT_SAMPLES 16
#define PILOT_SEED 0x656d6974746572ULL /* the pilot's random numbers, fixed: see pilot() */
/* Pixels over which the eye averages a pixel's own noise, against which a record's error (shared by its
 * whole footprint) is weighed: at least 4πσ² ≈ 50 for the low-pass Gaussian of irrcache diff (white
 * noise), and measured higher on staircase2 (see choose_materials): 100. */
#define BLUR_PIXELS 100.0

/* Sums over the pilot's points: N, Σ_p E_p, Σ_p var_p of a light sample, and Σ_p E_p² (unbiased:
 * mean_p² − s_p²/K), where E_p is the irradiance from the material at p (estimated by mean_p, the mean
 * of its K = PILOT_SAMPLES light samples, s_p² their unbiased sample variance). */
typedef struct pilot_sums {
    double points, mean, var, mean_sq;
} pilot_sums;

/* The pooled relative variance per sample of an estimator with variance var_p at each point:
 * N · Σ_p var_p / (Σ_p E_p)², one sample's variance at the average point over the squared average
 * irradiance (points that see none of the emitter dilute both estimators alike); +∞ when no sample
 * reached the emitter (nothing measured). */
static double pooled_cv2(const pilot_sums *ps, double var)
{
    return ps->mean > 0.0 ? ps->points * fmax(var, 0.0) / (ps->mean * ps->mean) : INFINITY;
}

/* Measures the two estimators of the irradiance E_p from emitting material m (Le: the luminance of its
 * emission) at every stride-th valid shading point p (normal n), and returns their pooled relative
 * variances per sample (pooled_cv2):
 *   light sampling, as the final render does it: one of m's emitting triangles with the probability the
 *     final render's light selection gives it at p (ic_scene_local_lights where the final render builds
 *     local selections, else by power), renormalised over m, and a point x on it by area;
 *     f = Le·cos θ_p·cos θ_l / |x − p|² / pdf_area(x), 0 where a shadow ray finds x hidden, x is behind p
 *     or p sees the back of a one-sided emitter. PILOT_SAMPLES of them at p give mean_p and s_p². The
 *     final render picks m at all with probability P_m (its share of that selection): its sample is
 *     then f / P_m, else 0, whose variance is (s_p² + E_p²)/P_m − E_p².
 *   gathering, as a record's hemisphere rays do it: a cosine-weighted direction about n, f = π·Le where
 *     its first hit is m's emitting side, else 0. An estimator that takes only the values 0 and π·Le
 *     with mean E_p has variance E_p·(π·Le − E_p) exactly, so it needs no rays of its own: E_p comes
 *     from the light samples, which reach a small emitter far more often than hemisphere rays would (a
 *     few thousand hemisphere rays hit a Cornell-box lamp a few dozen times, too few to measure a
 *     variance by).
 * Deterministic, and the same for every seed: each point's random stream comes from m and the pixel
 * alone. The choice decides what the records hold (it is part of a cache file's identity), and one drawn
 * from the seed flipped where a material's ratio is near the threshold or its light samples are
 * heavy-tailed (staircase2's middle window: cv²_light 96, 402 and 147 from 16, 64 and 256 samples a
 * point, against cv²_gather 8–12), so a cache saved with one seed was refused with another. Returns 0
 * when out of memory. */
static int pilot(const ic_ctx *c, const ic_scene *s, uint32_t m, size_t stride, double *cv2_light,
                 double *cv2_gather)
{
    const uint32_t nl = s->tri_light_count;
    uint32_t count = 0;
    for (uint32_t li = 0; li < nl; ++li)
        count += s->triangle_material[s->tri_lights[li].triangle] == m;
    const int local = nl <= IC_LOCAL_LIGHTS_MAX && c->light_sel.tri > 0.0f;
    uint32_t *tri = malloc(sizeof *tri * (count ? count : 1));
    double *cdf = malloc(sizeof *cdf * (count + 1));
    float *pmf = local ? malloc(sizeof *pmf * nl) : NULL, *all_cdf = local ? malloc(sizeof *all_cdf * (nl + 1)) : NULL;
    if (!tri || !cdf || (local && (!pmf || !all_cdf))) {
        free(tri);
        free(cdf);
        free(pmf);
        free(all_cdf);
        return 0;
    }
    for (uint32_t li = 0, k = 0; li < nl; ++li)
        if (s->triangle_material[s->tri_lights[li].triangle] == m)
            tri[k++] = li;
    const double le = v3_lum(s->materials[m].emission), K = PILOT_SAMPLES;
    pilot_sums ps = {0};
    size_t npix = (size_t)c->g.width * c->g.height;
    for (size_t i = 0, k = 0; i < npix && count; ++i) {
        if (!c->g.valid[i] || k++ % stride)
            continue;
        ic_vec3 p, n;
        ic_ic_gbuffer_point(c, (uint32_t)i, &p, &n, NULL);
        /* The final render's selection over m's triangles at p: cdf, unnormalised (its total is m's
         * share of the triangle lights). */
        int have_local = local && ic_scene_local_lights(s, p, n, NULL, pmf, all_cdf);
        cdf[0] = 0.0;
        for (uint32_t j = 0; j < count; ++j)
            cdf[j + 1] = cdf[j] + (have_local ? (double)pmf[tri[j]]
                                              : (double)s->tri_lights[tri[j]].power / s->tri_light_power);
        const double share = cdf[count], keep = fmin(1.0, share * c->light_sel.tri);
        ic_rng rng = ic_rng_make(PILOT_SEED, 0x70696c6f74ULL, i, m);
        double sum = 0.0, sum2 = 0.0;
        for (int j = 0; j < PILOT_SAMPLES && keep > 0.0; ++j) {
            /* A triangle: the last cdf entry below u; then a point on it by area. */
            double u = ic_rng_double(&rng) * share;
            float u1 = ic_rng_float(&rng), u2 = ic_rng_float(&rng);
            uint32_t lo = 0, hi = count - 1;
            while (lo < hi) {
                uint32_t mid = (lo + hi + 1) / 2;
                if (cdf[mid] <= u)
                    lo = mid;
                else
                    hi = mid - 1;
            }
            const ic_tri_light *l = &s->tri_lights[tri[lo]];
            const double q = (cdf[lo + 1] - cdf[lo]) / share; /* the triangle's probability within m */
            float b1, b2;
            ic_warp_triangle(u1, u2, &b1, &b2);
            const uint32_t *v = &s->triangles[3 * l->triangle];
            ic_vec3 x = v3_add(v3_add(v3_scale(s->positions[v[0]], 1.0f - b1 - b2), v3_scale(s->positions[v[1]], b1)),
                               v3_scale(s->positions[v[2]], b2));
            ic_vec3 d = v3_sub(x, p);
            float dist = v3_len(d);
            if (!(dist > 0.0f) || !(q > 0.0))
                continue;
            d = v3_scale(d, 1.0f / dist);
            float cos_p = v3_dot(d, n), cos_l = -v3_dot(d, l->normal);
            if (l->two_sided)
                cos_l = fabsf(cos_l);
            if (cos_p <= 0.0f || cos_l <= 0.0f || !ic_material_emits_towards(&s->materials[m], v3_neg(d)))
                continue;
            ic_ray r = ic_shadow_ray_to(p, n, d, dist, 1e-3f, c->tr->scene->ray_offset_floor);
            if (ic_accel_occluded1(c->tr->accel, &r))
                continue;
            double f = le * cos_p * cos_l / ((double)dist * dist) * l->area / q;
            sum += f;
            sum2 += f * f;
        }
        const double mean = sum / K, var = fmax(0.0, (sum2 - K * mean * mean) / (K - 1.0));
        ps.points += 1.0;
        ps.mean += mean;
        ps.var += keep > 0.0 ? (var + mean * mean) / keep - mean * mean : 0.0;
        ps.mean_sq += mean * mean - var / K;
    }
    free(tri);
    free(cdf);
    free(pmf);
    free(all_cdf);
    *cv2_light = pooled_cv2(&ps, ps.var);
    *cv2_gather = pooled_cv2(&ps, IC_PI * le * ps.mean - ps.mean_sq);
    return 1;
}

/* Hemisphere rays one record gathers (its first set): the stratified grid's M × N cells, the hemicube's
 * 3N² texels, or the progressive sampler's first round (ic_gather_opts, zero fields resolved as gather.c
 * does). */
static double record_rays(const ic_gather_opts *g)
{
    ic_gather_opts d;
    ic_gather_opts_default(&d);
    if (g->method == IC_GATHER_PROGRESSIVE)
        return g->first_round_rays ? g->first_round_rays : d.first_round_rays;
    if (g->method == IC_GATHER_HEMICUBE && g->hemicube_resolution)
        return 3.0 * (double)g->hemicube_resolution * (double)g->hemicube_resolution;
    uint32_t m = g->theta_strata ? g->theta_strata : d.theta_strata;
    uint32_t n = g->phi_strata ? g->phi_strata : (uint32_t)lround((double)IC_PI * m);
    return (double)m * (double)n;
}

/* The hemisphere shares of the emitting materials at the sampled shading points (choose_materials): point j
 * is pixel pix[j]; its row of ne shares (slot[m] for material m) is share[j · ne …]. */
typedef struct share_job {
    const ic_ctx *c;
    const ic_scene *s;
    const uint32_t *pix, *slot;
    uint32_t ne;
    uint64_t first; /* this process's first point */
    double *share;
} share_job;

static void share_point(void *ctx, int64_t item, int thread)
{
    (void)thread;
    const share_job *j = ctx;
    const ic_scene *s = j->s;
    const uint64_t point = j->first + (uint64_t)item;
    double *row = &j->share[point * j->ne];
    ic_vec3 p, n;
    ic_ic_gbuffer_point(j->c, j->pix[point], &p, &n, NULL);
    for (uint32_t li = 0; li < s->tri_light_count; ++li) {
        const ic_tri_light *l = &s->tri_lights[li];
        uint32_t t = l->triangle;
        /* Only the emitting side counts. */
        if (!l->two_sided && v3_dot(l->normal, v3_sub(p, l->centroid)) <= 0.0f)
            continue;
        row[j->slot[s->triangle_material[t]]] +=
            hemisphere_share(p, n, s->positions[s->triangles[3 * t]], s->positions[s->triangles[3 * t + 1]],
                             s->positions[s->triangles[3 * t + 2]]);
    }
}

/* Large emitters. The records carry indirect light (Ward et al. 1988; Frolov et al. 2012 §3.2: the
 * final render path-traces direct light and reads the cache for the smooth rest), and here the
 * environment's too; this extends that to an emitting material whose direct light the records
 * estimate better than the final render's light samples would. Which estimator serves a light better
 * is measured, not guessed: Veach 1997 ch. 9 compares light sampling and BSDF sampling by their
 * variance on the integrand at hand (a large source is better reached by sampling directions, a small
 * one by sampling its area), and so does the pilot (pilot()): at the image's shading points, the
 * pooled relative variance per sample of the final render's light sampling on the material,
 * cv²_light, and that of a record's cosine-weighted hemisphere rays, cv²_gather. Each is divided by
 * the samples it is averaged over where the eye reads it. Light sampling's error is a pixel's own,
 * independent from pixel to pixel: the eye (and the low-pass error of irrcache diff, a Gaussian of
 * σ = IC_LOWPASS_SIGMA pixels) averages it over at least 4πσ² ≈ 50 pixels, so its samples are a
 * pixel's light samples S (the cache render's default IC_DEFAULT_SPP_IC samples per pixel ×
 * light_samples; the final render's own count is not known here, and may be adaptive or bounded by time)
 * times K = BLUR_PIXELS pixels. A record's error is shared by every pixel it covers, a blotch that no
 * averaging removes: its samples are its hemisphere rays M (record_rays, 800 by default). The material
 * is cached iff cv²_light / (K·S) > cv²_gather / M. Counting the pixel alone (K = 1), as before, cached
 * staircase2's three windows and left the blotches of their records: low-pass relMSE 0.00028 against
 * 0.00017 with the windows light-sampled (320×180, 64 spp, equal rays; per-pixel relMSE 0.0012 against
 * 0.0021, both far below the path tracer's 0.012). K = 50 still cached its window with cv²_light /
 * cv²_gather = 3.75 at 32 spp, and that raised the low-pass error from 0.00020 to 0.00027: K = 100.
 * That 3.75 was a low draw of a heavy-tailed variance: with the pilot's fixed stream (pilot()) the same
 * window measures cv²_light 96 against cv²_gather 9.6 and is cached at K = 100 too; staircase2 at
 * 320×180, equal rays, seeds 1 and 2: relMSE 0.0043 → 0.0019, low-pass 0.000196, 0.000259 → 0.000292,
 * 0.000254 (BENCHMARKS.md, "The large-emitter pilot and the seed"). Stratification and the record
 * filter lower the records' noise below cv²_gather / M, but a record's error also spreads over a
 * footprint wider than the eye's averaging.
 *
 * A window seen through an opening (a large source most of whose area is hidden: light samples on it
 * mostly wasted, each visible one carrying a large weight) is such an emitter, and its irradiance
 * varies slowly (a source that large casts soft shadows), which is what the cache interpolates well.
 * It is then not light-sampled in the final render; the hemisphere rays count its emission instead,
 * so the records carry its direct light, as they carry the environment's. A lamp, even a ceiling
 * panel that covers a few per cent of the hemisphere and that furniture hides from many points, is
 * light-sampled at a small fraction of the hemisphere rays' variance and keeps being sampled: cached,
 * its light would carry the records' noise and blur its shadows (a panel over a table that blocks 44 %
 * of its light samples: cv²_light 0.64, cv²_gather 79; cached, relMSE doubles). Measured (cv²_light,
 * cv²_gather): the Cornell box's lamp 0.11, 185, stair-hall's ceiling panel 0.018, 890, staircase2's
 * two outer window quads (102, 235; 59, 228) and a room's window with a bright outside behind it
 * (22, 95) are sampled, staircase2's middle window (96, 9.6) cached; an emitter is cached when light
 * sampling is at least 4 times as noisy per sample as the hemisphere rays (K·S / M = 4 at the
 * defaults) — a large source mostly hidden behind a narrow opening, or an emitting surface that
 * surrounds the scene like a sky.
 *
 * Only a material that covers, at the median sampled shading point, at least large_emitters of the
 * cosine-weighted hemisphere (hemisphere_share, unoccluded) is piloted; a smaller one is light-sampled
 * without measuring (its hemisphere rays' cv² at a point is at least (1 − a)/a for a share a: 99 at
 * a = 0.01). The pilot costs PILOT_SAMPLES shadow rays at each of at most PILOT_POINTS shading points
 * per material piloted (8,192 rays; a few ms).
 *
 * Marks in cached_mat[m] (zeroed, material_count entries) each emitting material the records carry
 * (none unless cached_allowed: large_emitters off still pilots, for the flag), and sets *large_sampled
 * where a piloted material stays light-sampled though its light samples are noisier per sample than
 * the hemisphere rays (cv²_light > cv²_gather; ic_ctx.large_sampled). A collective call under several
 * processes (the shares are measured on a block of the points each, then exchanged); IC_ERR_OOM when out of
 * memory, or the exchange's error. */
static ic_result choose_materials(const ic_ctx *c, const ic_scene *s, size_t valid, int cached_allowed,
                                  uint8_t *cached_mat, int *large_sampled, ic_error *err)
{
    size_t npix = (size_t)c->g.width * c->g.height;
    /* At most ~1024 shading points, evenly through the image, and fewer where there are so many
     * emitting triangles that points × triangles would pass 2^23 (at least ~64 points). */
    size_t want = ((size_t)1 << 23) / s->tri_light_count;
    want = want < 64 ? 64 : want > 1024 ? 1024 : want;
    size_t stride = valid / want + 1, points = 0, cap = valid / stride + 1; /* cap: sampled points, at most */
    /* The pilot's points: every pilot_stride-th valid pixel, at most ~PILOT_POINTS. */
    size_t pilot_stride = valid / PILOT_POINTS + 1;
    /* What each estimator's samples are averaged over: a pixel's light samples (at the cache render's
     * default samples per pixel) over the pixels the eye averages, and a record's hemisphere rays. */
    const double light_per_pixel = (double)IC_DEFAULT_SPP_IC * c->o.light_samples * BLUR_PIXELS,
                 rays_per_record = record_rays(&c->o.gather);
    /* Shares per sampled point and emitting material (slot[m]: its column, UINT32_MAX for the others). */
    uint32_t nm = s->material_count, ne = 0;
    uint32_t *slot = malloc(sizeof *slot * (nm ? nm : 1)), *pix = malloc(sizeof *pix * cap);
    double *row = malloc(sizeof *row * cap), *share = NULL;
    if (slot) {
        for (uint32_t m = 0; m < nm; ++m)
            slot[m] = v3_is_black(s->materials[m].emission) ? UINT32_MAX : ne++;
        share = calloc((size_t)(ne ? ne : 1) * cap, sizeof *share);
    }
    ic_result r = slot && share && row && pix ? IC_OK : ic_error_set(err, IC_ERR_OOM, "out of memory for the light tables");
    for (size_t i = 0, k = 0; r == IC_OK && i < npix; ++i)
        if (c->g.valid[i] && !(k++ % stride))
            pix[points++] = (uint32_t)i;
    /* Several processes: a block of the points each, on its threads, then exchanged. */
    if (r == IC_OK) {
        share_job j = {c, s, pix, slot, ne, 0, share};
        uint64_t own;
        ic_comm_block(points, ic_comm_size(c->comm), ic_comm_rank(c->comm), &j.first, &own);
        if ((r = ic_parallel_for(c->threads, (int64_t)own, share_point, &j)) != IC_OK)
            ic_error_set(err, r, "could not start threads");
        else
            r = ic_comm_allgather_blocks(c->comm, share, points, sizeof *share * ne,
                                         "exchanging the emitters' hemisphere shares", err);
    }
    for (uint32_t m = 0; r == IC_OK && m < nm; ++m) {
        if (slot[m] == UINT32_MAX)
            continue;
        for (size_t q = 0; q < points; ++q)
            row[q] = share[q * ne + slot[m]];
        qsort(row, points, sizeof *row, cmp_double);
        if (row[points / 2] < c->o.large_emitters.value)
            continue;
        double cv2_light = INFINITY, cv2_gather = INFINITY;
        if (!pilot(c, s, m, pilot_stride, &cv2_light, &cv2_gather)) {
            r = ic_error_set(err, IC_ERR_OOM, "out of memory for the large emitters' pilot");
            break;
        }
        cached_mat[m] = cached_allowed && cv2_light / light_per_pixel > cv2_gather / rays_per_record;
        /* Light-sampled, and its plain light samples noisier than cosine rays would be: the served hits
         * pair each light sample with a cosine ray (ic_ctx.large_sampled). */
        if (!cached_mat[m] && cv2_light > cv2_gather)
            *large_sampled = 1;
    }
    free(slot);
    free(pix);
    free(share);
    free(row);
    return r;
}

/* A cdf (tri_light_count + 1 entries) over the emitting triangles that are cached (want 1) or not
 * (want 0), by power, normalised by their own total; from the last such triangle on it is exactly 1, so
 * that rounding never gives the others a share. pmf gets each triangle's probability. */
static void power_cdf(const ic_scene *s, const uint8_t *cached_mat, int want, float *pmf, float *cdf)
{
    double total = 0.0, sum = 0.0;
    uint32_t last = 0;
    for (uint32_t i = 0; i < s->tri_light_count; ++i)
        if ((cached_mat[s->triangle_material[s->tri_lights[i].triangle]] != 0) == want) {
            total += s->tri_lights[i].power;
            last = i + 1;
        }
    cdf[0] = 0.0f;
    for (uint32_t i = 0; i < s->tri_light_count; ++i) {
        int in = (cached_mat[s->triangle_material[s->tri_lights[i].triangle]] != 0) == want;
        double p = in && total > 0.0 ? s->tri_lights[i].power / total : 0.0;
        pmf[i] = (float)p;
        sum += p;
        cdf[i + 1] = i + 1 >= last && total > 0.0 ? 1.0f : (float)sum;
    }
}

/* The final render's distribution over the emitting triangles left to sample (direct_pmf/direct_cdf),
 * the cached ones' for the records' light samples of them (cached_pmf/cached_cdf), and light_sel narrowed to the
 * former. Returns 0 when out of memory. */
static int narrow_light_selection(ic_ctx *c, const ic_scene *s, const uint8_t *cached_mat, double kept)
{
    c->direct_pmf = malloc(sizeof *c->direct_pmf * s->tri_light_count);
    c->direct_cdf = malloc(sizeof *c->direct_cdf * (s->tri_light_count + 1));
    c->cached_pmf = malloc(sizeof *c->cached_pmf * s->tri_light_count);
    c->cached_cdf = malloc(sizeof *c->cached_cdf * (s->tri_light_count + 1));
    if (!c->direct_pmf || !c->direct_cdf || !c->cached_pmf || !c->cached_cdf)
        return 0;
    power_cdf(s, cached_mat, 0, c->direct_pmf, c->direct_cdf);
    power_cdf(s, cached_mat, 1, c->cached_pmf, c->cached_cdf);
    /* The class probabilities follow the power left to sample. */
    double tri = c->light_sel.tri * kept / s->tri_light_power, point = c->light_sel.point;
    c->light_sel.tri = tri + point > 0.0 ? (float)(tri / (tri + point)) : 0.0f;
    c->light_sel.point = tri + point > 0.0 ? (float)(point / (tri + point)) : 0.0f;
    c->light_sel.tri_pmf = kept > 0.0 ? c->direct_pmf : NULL;
    c->light_sel.tri_cdf = kept > 0.0 ? c->direct_cdf : NULL;
    return 1;
}

ic_result ic_ic_select_large_emitters(ic_ctx *c, const ic_scene *s, ic_error *err)
{
    if (s->tri_light_count == 0 || !(s->tri_light_power > 0.0f))
        return IC_OK;
    size_t npix = (size_t)c->g.width * c->g.height, valid = 0;
    for (size_t i = 0; i < npix; ++i)
        valid += c->g.valid[i];
    if (valid == 0)
        return IC_OK;
    uint8_t *cached_mat = calloc(s->material_count ? s->material_count : 1, 1);
    const int cached_allowed = c->o.large_emitters.mode != IC_CACHE_OFF;
    int large_sampled = 0;
    ic_result r = cached_mat ? choose_materials(c, s, valid, cached_allowed, cached_mat, &large_sampled, err)
                             : ic_error_set(err, IC_ERR_OOM, "out of memory for the light tables");
    if (r != IC_OK) {
        free(cached_mat);
        return r;
    }
    c->large_sampled = large_sampled;
    uint32_t cached = 0;
    double kept = 0.0;
    for (uint32_t i = 0; i < s->tri_light_count; ++i) {
        if (cached_mat[s->triangle_material[s->tri_lights[i].triangle]])
            ++cached;
        else
            kept += s->tri_lights[i].power;
    }
    if (cached && !narrow_light_selection(c, s, cached_mat, kept))
        r = ic_error_set(err, IC_ERR_OOM, "out of memory for the light tables");
    else
        c->cached_emitters = cached;
    free(cached_mat);
    return r;
}
