/*
 * gather_hemicube.c — hemicube gathering (Castaño 2014, "Irradiance Caching – Continued", and
 * Castaño 2011, "Irradiance Caching – Part 1", on the hemicube's weights and gradients).
 *
 * The hemicube around the normal z: a top face z = 1, x, y ∈ [−1, 1], of N×N texels and four side
 * half-faces (x = ±1 or y = ±1, z ∈ [0, 1]) of N×N/2 texels; 3N² texels, one ray through each texel
 * centre. A renderer on a GPU would rasterise the five faces; through a trace callback it is a fixed,
 * deterministic ray set, ~1/4 of whose rays leave through the sides near the horizon.
 *
 * Per-texel weights, computed once per gatherer and exact (not the usual "solid angle × cosine at the
 * centre, renormalised to sum to π"): a texel is a spherical quadrilateral bounded by four great-circle
 * arcs (a straight edge on a cube face projects to a great circle), so its vector irradiance
 *     Φ = ∫_texel ω dω = ½ Σ_edges γ_e n̂_e          (Lambert's formula in Arvo 1995 (tensors)'s vector form)
 * with γ_e the angle an edge subtends and n̂_e the unit normal of its great-circle plane. Then
 *     irradiance weight  w = ∫ cosθ dω = Φ_z       (Σ w = π exactly, up to rounding),
 *     rotational weight  ∫ (n × ω) dω = (−Φ_y, Φ_x) (Ward & Heckbert 1992 §3: tilting the normal by a
 *                         small rotation a·δ changes cosθ by a·(n × ω)δ; the horizon term vanishes),
 * and the solid angle from two spherical triangles (Van Oosterom & Strackee 1983), used only for checks.
 * So E = Σ w_i L_i and ∇r E = Σ (−Φ_y, Φ_x)_i L_i; a constant environment gives πL exactly.
 *
 * Translational gradient. Castaño derives per-texel gradient weights for the hemicube from Ward &
 * Heckbert's construction; with hit distances the gradient is a property of the walls between texels,
 * not of the texels. Radiance is constant within a texel; moving the point by dx along a tangent e moves
 * each wall between texels i and j, and the wall belongs to the nearer of the two surfaces it separates
 * (Křivánek et al. 2005 (SCCG); Schwarzhaupt et al. 2012), so its direction moves by
 * −(e − ω(ω·e)) dx / r_w with r_w = min(r_i, r_j). The projected solid angle it sweeps from one texel
 * into the other is cosθ (V · m) per unit length (m the wall's unit normal in the sphere), so
 *     ∇t E = Σ_walls (L_left − L_right) g_w / r_w,   g_e = −∫_wall ω_z (ω · (e × ω')) ds,
 * with the geometric factor g_w the same formula gather_hessian.c derives ((2) there), integrated along
 * the wall's great-circle arc once per gatherer. The walls are the 6N² − 2N edges shared by two texels
 * (across face edges too); the horizon edges do not move in the tangent plane and are left out. A wall
 * between two misses contributes nothing (r = ∞), so a uniform sky has exactly zero gradient.
 * opts.with_hessian adds the second-order factors of the same walls (gather_hessian.c (3)).
 *
 * σ: the hemicube is deterministic, so there is no Monte Carlo variance to estimate; its error is the
 * discretisation error. We estimate it as for the stratified sampler (Křivánek et al. 2006 §4.3):
 * σ = |E − E'|, E' the irradiance from the checkerboard half of the texels (each face's (u + v) even),
 * renormalised so a constant environment gives E' = E. The half is a hemicube rotated by 45° and √2
 * coarser, so σ scales with the discretisation error of its edges (measured in test_gather_hemicube).
 *
 * Records: the frame is turned about the normal by a per-record angle from (seed, key), as the
 * stratified sampler turns its φ strata, so neighbouring records do not alias against the same texel
 * grid. Nothing else depends on the key; the tables depend only on N.
 */
#include "gather_internal.h"

#include "core/rng.h"

#include <stdlib.h>

/* The five faces: point A + u·H + v·V, u ∈ [−1, 1], v ∈ [v0, 1]. */
typedef struct face {
    ic_vec3 A, H, V;
    float v0;
} face;

static const face FACES[5] = {
    {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}, -1.0f},  /* top */
    {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, 0.0f},   /* +x */
    {{0, 1, 0}, {-1, 0, 0}, {0, 0, 1}, 0.0f},  /* +y */
    {{-1, 0, 0}, {0, -1, 0}, {0, 0, 1}, 0.0f}, /* −x */
    {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}, 0.0f},  /* −y */
};

static uint32_t face_rows(uint32_t f, uint32_t N) { return f == 0 ? N : N / 2; }
static uint32_t face_first(uint32_t f, uint32_t N) { return f == 0 ? 0 : N * N + (f - 1) * N * (N / 2); }

/* Point on face f at (u, v). */
static ic_vec3 face_point(uint32_t f, double u, double v)
{
    const face *F = &FACES[f];
    return v3_add(F->A, v3_add(v3_scale(F->H, (float)u), v3_scale(F->V, (float)v)));
}

/* Texel holding direction d, or −1 below the horizon. */
static int64_t locate(ic_vec3 d, uint32_t N)
{
    if (!(d.z > 0.0f))
        return -1;
    uint32_t best = 0;
    float best_a = d.z;
    for (uint32_t f = 1; f < 5; ++f) {
        float a = v3_dot(d, FACES[f].A);
        if (a > best_a) {
            best_a = a;
            best = f;
        }
    }
    const face *F = &FACES[best];
    const double h = 2.0 / N;
    const double u = v3_dot(d, F->H) / best_a, v = v3_dot(d, F->V) / best_a;
    int64_t iu = (int64_t)floor((u + 1.0) / h), iv = (int64_t)floor((v - F->v0) / h);
    const int64_t rows = face_rows(best, N);
    iu = iu < 0 ? 0 : (iu >= N ? N - 1 : iu);
    iv = iv < 0 ? 0 : (iv >= rows ? rows - 1 : iv);
    return (int64_t)face_first(best, N) + iv * N + iu;
}

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static void unit3(ic_vec3 v, double out[3])
{
    const double n = sqrt((double)v.x * v.x + (double)v.y * v.y + (double)v.z * v.z);
    out[0] = v.x / n;
    out[1] = v.y / n;
    out[2] = v.z / n;
}
static void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

/* Solid angle of the spherical triangle of unit a, b, c (Van Oosterom & Strackee 1983). */
static double triangle_solid_angle(const double a[3], const double b[3], const double c[3])
{
    double bc[3];
    cross3(b, c, bc);
    return 2.0 * atan2(fabs(dot3(a, bc)), 1.0 + dot3(a, b) + dot3(b, c) + dot3(c, a));
}

ic_result ic_gather_hemicube_init(ic_gatherer *g)
{
    ic_hemicube *hc = &g->hemicube;
    const uint32_t N = g->opts.hemicube_resolution;
    const uint32_t T = 3 * N * N;
    hc->resolution = N;
    hc->texels = T;
    hc->dir = malloc(T * sizeof *hc->dir);
    hc->solid_angle = malloc(T * sizeof *hc->solid_angle);
    hc->weight = malloc(T * sizeof *hc->weight);
    hc->rot = malloc(T * sizeof *hc->rot);
    hc->half = malloc(T * sizeof *hc->half);
    hc->wall = malloc(2 * (size_t)T * sizeof *hc->wall);
    if (!hc->dir || !hc->solid_angle || !hc->weight || !hc->rot || !hc->half || !hc->wall)
        return IC_ERR_OOM;

    const double h = 2.0 / N;
    double half_sum = 0.0;
    uint32_t walls = 0;
    for (uint32_t f = 0; f < 5; ++f) {
        const double v0 = FACES[f].v0;
        for (uint32_t iv = 0; iv < face_rows(f, N); ++iv) {
            for (uint32_t iu = 0; iu < N; ++iu) {
                const uint32_t i = face_first(f, N) + iv * N + iu;
                const double u_lo = -1.0 + iu * h, v_lo = v0 + iv * h;
                const ic_vec3 centre = face_point(f, u_lo + 0.5 * h, v_lo + 0.5 * h);
                hc->dir[i] = v3_norm(centre);
                /* Corners counter-clockwise in (u, v). */
                const ic_vec3 corner[4] = {face_point(f, u_lo, v_lo), face_point(f, u_lo + h, v_lo),
                                           face_point(f, u_lo + h, v_lo + h), face_point(f, u_lo, v_lo + h)};
                double cu[4][3];
                for (int k = 0; k < 4; ++k)
                    unit3(corner[k], cu[k]);
                /* Φ = ½ Σ γ_e n̂_e, oriented towards the texel. */
                double phi[3] = {0, 0, 0};
                for (int k = 0; k < 4; ++k) {
                    double n[3];
                    cross3(cu[k], cu[(k + 1) & 3], n);
                    const double s = sqrt(dot3(n, n)), gamma = atan2(s, dot3(cu[k], cu[(k + 1) & 3]));
                    for (int a = 0; a < 3; ++a)
                        phi[a] += 0.5 * gamma * n[a] / s;
                }
                double cd[3];
                unit3(centre, cd);
                if (dot3(phi, cd) < 0.0)
                    for (int a = 0; a < 3; ++a)
                        phi[a] = -phi[a];
                hc->weight[i] = phi[2];
                hc->rot[i][0] = -phi[1];
                hc->rot[i][1] = phi[0];
                hc->solid_angle[i] = triangle_solid_angle(cu[0], cu[1], cu[2]) + triangle_solid_angle(cu[0], cu[2], cu[3]);
                hc->half[i] = (uint8_t)((iu + iv) & 1u);
                if (hc->half[i] == 0)
                    half_sum += hc->weight[i];

                /* Walls: each edge once, from its lower-numbered texel; the neighbour is the texel
                 * just across the edge's midpoint (on this face or the next). */
                for (int k = 0; k < 4; ++k) {
                    const ic_vec3 a = corner[k], b = corner[(k + 1) & 3];
                    const ic_vec3 mid = v3_scale(v3_add(a, b), 0.5f);
                    const ic_vec3 across = v3_add(mid, v3_scale(v3_sub(mid, centre), 1e-3f));
                    const int64_t j = locate(v3_norm(across), N);
                    if (j < 0 || (uint32_t)j <= i)
                        continue;
                    ic_hemicube_wall *w = &hc->wall[walls++];
                    w->f = ic_gather_arc_factors(a, b);
                    /* The arc a→b has the texel its normal a × b points to on its left. */
                    const int j_left = v3_dot(v3_cross(a, b), across) > 0.0f;
                    w->left = j_left ? (uint32_t)j : i;
                    w->right = j_left ? i : (uint32_t)j;
                }
            }
        }
    }
    hc->walls = walls;
    hc->half_scale = (double)IC_PI / half_sum;
    return IC_OK;
}

void ic_gather_hemicube_free(ic_gatherer *g)
{
    ic_hemicube *hc = &g->hemicube;
    free(hc->dir);
    free(hc->solid_angle);
    free(hc->weight);
    free(hc->rot);
    free(hc->half);
    free(hc->wall);
    *hc = (ic_hemicube){0};
}

ic_result ic_gather_hemicube(ic_gatherer *g, const ic_gather_point *pt, ic_gather_result *out)
{
    if (!g || !pt || !out || !g->hemicube.texels)
        return IC_ERR_INVALID_ARG;
    ic_frame frame;
    ic_result res = ic_gather_point_frame(pt, &frame);
    if (res != IC_OK)
        return res;
    /* Turn the tangent frame by the record's angle (the file comment). */
    ic_rng rng = ic_rng_make(g->opts.seed, pt->key, 0, IC_GATHER_STREAM_HEMICUBE);
    const float turn = 2.0f * IC_PI * ic_rng_float(&rng), ct = cosf(turn), st = sinf(turn);
    const ic_vec3 t = v3_add(v3_scale(frame.t, ct), v3_scale(frame.b, st));
    const ic_vec3 b = v3_sub(v3_scale(frame.b, ct), v3_scale(frame.t, st));
    frame.t = t;
    frame.b = b;

    const ic_hemicube *hc = &g->hemicube;
    const uint32_t n = hc->texels;
    for (uint32_t i = 0; i < n; ++i)
        g->cell_dir[i] = hc->dir[i];
    for (uint32_t first = 0; first < n; first += g->batch) {
        const uint32_t count = n - first < g->batch ? n - first : g->batch;
        for (uint32_t r = 0; r < count; ++r)
            g->ray_cell[r] = first + r;
        ic_gather_trace_chunk(g, &frame, pt->position, count);
    }

    const ic_vec3 *L = g->cell_radiance;
    const float *dist = g->cell_dist;
    double e[3] = {0, 0, 0}, e_half[3] = {0, 0, 0}, rot[3][2] = {{0}}, trans[3][2] = {{0}};
    double inv_dist = 0.0;
    float min_dist = INFINITY;
    uint32_t hits = 0;
    for (uint32_t i = 0; i < n; ++i) {
        const double Lv[3] = {L[i].x, L[i].y, L[i].z}, w = hc->weight[i];
        for (int c = 0; c < 3; ++c) {
            e[c] += w * Lv[c];
            if (hc->half[i] == 0)
                e_half[c] += w * Lv[c];
            rot[c][0] += hc->rot[i][0] * Lv[c];
            rot[c][1] += hc->rot[i][1] * Lv[c];
        }
        if (dist[i] < INFINITY) {
            inv_dist += w / dist[i];
            min_dist = fminf(min_dist, dist[i]);
            ++hits;
        }
    }
    const int with_hessian = g->opts.with_hessian != 0;
    double hess[3][3] = {{0}};
    for (uint32_t k = 0; k < hc->walls; ++k) {
        const ic_hemicube_wall *w = &hc->wall[k];
        const float r = fminf(dist[w->left], dist[w->right]);
        if (!(r < INFINITY))
            continue;
        const ic_vec3 a = L[w->left], bb = L[w->right];
        const double d[3] = {(double)a.x - bb.x, (double)a.y - bb.y, (double)a.z - bb.z};
        const double ir = 1.0 / r;
        for (int c = 0; c < 3; ++c) {
            trans[c][0] += d[c] * w->f.g[0] * ir;
            trans[c][1] += d[c] * w->f.g[1] * ir;
        }
        if (with_hessian)
            for (int c = 0; c < 3; ++c)
                for (int q = 0; q < 3; ++q)
                    hess[c][q] += d[c] * w->f.h[q] * ir * ir;
    }

    float sig[3], ev[3];
    for (int c = 0; c < 3; ++c) {
        ev[c] = (float)e[c];
        sig[c] = (float)fabs(e[c] - hc->half_scale * e_half[c]);
        out->rot_grad[c] = v3_add(v3_scale(frame.t, (float)rot[c][0]), v3_scale(frame.b, (float)rot[c][1]));
        out->trans_grad[c] = v3_add(v3_scale(frame.t, (float)trans[c][0]), v3_scale(frame.b, (float)trans[c][1]));
    }
    out->irradiance = v3(ev[0], ev[1], ev[2]);
    out->sigma = v3(sig[0], sig[1], sig[2]);
    /* The projected-solid-angle-weighted harmonic mean, π / Σ w_i/d_i: the same quantity the
     * stratified sampler's n / Σ 1/d_i estimates with its equal-weight cosine-distributed rays. */
    out->harmonic_mean_dist = inv_dist > 0.0 ? (float)((double)IC_PI / inv_dist) : INFINITY;
    out->min_dist = min_dist;
    out->ray_count = n;
    out->hit_count = hits;
    out->is_converged = 1;
    out->has_hessian = with_hessian;
    out->hessian_t = with_hessian ? frame.t : v3s(0.0f);
    out->hessian_b = with_hessian ? frame.b : v3s(0.0f);
    for (int c = 0; c < 3; ++c)
        for (int q = 0; q < 3; ++q)
            out->hessian[c][q] = (float)hess[c][q];
    return IC_OK;
}
