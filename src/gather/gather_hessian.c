/*
 * gather_hessian.c — the tangent-plane Hessian of irradiance from a gather's cells and hit distances,
 * occlusion-aware (Schwarzhaupt, Jensen, Jarosz 2012, "Practical Hessian-Based Error Control for
 * Irradiance Caching"), and the record extent it implies. (Section numbers are not cited: the
 * derivation below is ours, from the paper's model, not transcribed from its text.)
 *
 * Model (as in the paper): the hemisphere is split into cells (the stratified grid's strata, the
 * hemicube's texels); each cell sees one patch of the environment of constant radiance L_k at its hit
 * distance r_k. Moving the shading point x in the tangent plane changes E only through the walls
 * between cells: a wall is a curve of the environment seen from x, and it belongs to the nearer of the
 * two surfaces it separates (a silhouette moves with the occluder), so it lies at r_w = min(r_i, r_j).
 * The paper's point is exactly this occlusion awareness: a Hessian that moves every cell with its own
 * distance (Jarosz et al. 2012's) is wrong wherever a near occluder covers a far surface.
 *
 * Gradient (first order). Put the wall in 3D as the fixed curve P(s) = x0 + r_w ω(s). Seen from x its
 * direction is p̂, p = P − x; a shift of x by dx·e moves that direction by −(e − p̂(p̂·e))dx/|p|, and
 * the wall sweeps projected solid angle (cosθ-weighted area) from one cell into the other at the rate
 *     Ψ_e(x) = −∫ (n·p)(p·(e × dP)) / |p|⁴                                                  (1)
 * (the swept area p̂·(V × dω) weighted by cosθ = n·p̂; the radial parts drop out of the triple
 * product). ∂E/∂x_e = Σ_walls ΔL_w Ψ_e, ΔL_w = L_left − L_right with "left" the side ω × dω/ds points
 * to. At x0 (p = r_w ω, dP = r_w ω' ds):
 *     g_e = r_w Ψ_e = −∫ ω_z (ω · (e × ω')) ds,                                           (2)
 * which on the stratified grid is exactly the Křivánek et al. 2005 (SCCG) wall formula that
 * gather_grid.c uses for trans_grad (a meridian gives (sinθ_j+1 − sinθ_j) v_k, a parallel
 * −sinθ_j cos²θ_j ∫u_φ dφ), and on the hemicube the translational gradient of gather_hemicube.c.
 *
 * Hessian (second order): differentiate (1) once more in x (p → p − δ e_f) and evaluate at x0, where
 * n·e_f = 0 for a tangent e_f:
 *     h_ef = r_w² ∂Ψ_e/∂x_f = ∫ ω_z [ (e × ω')_f − 4 (ω · (e × ω')) ω_f ] ds,                 (3)
 *     H_E = Σ_walls ΔL_w h / r_w².
 * The wall is held fixed in space and its end points are not moved: where walls of different depths
 * meet, the model leaves a corner gap of area O(dx²) undefined, and that ambiguity shows up as an
 * antisymmetric part of (3) (its antisymmetric part integrates ω_z ω'_z, an end-point term). We keep the
 * symmetric part, h_tb = ½(h_xy + h_yx). Where every wall of a boundary has one depth (an unoccluded
 * emitter, however the grid cuts it) the end-point terms cancel along the boundary and (3) is the
 * exact Hessian of the staircase the cells form, which converges to the true one as the cells shrink.
 * Horizon walls (θ = π/2) do not move when x moves in the tangent plane (the hemisphere is defined by
 * the normal), so they contribute nothing; walls between two misses neither (r = ∞).
 *
 * (2) and (3) depend only on the wall's shape, not on r: the factors are computed once per gatherer
 * (6-point Gauss–Legendre along each wall, exact to well below float precision for the walls of any
 * grid of 4 or more strata) and each gather only scales them by ΔL/r and ΔL/r².
 *
 * Extent: along a unit tangent direction d the first-order extrapolation misses ½ dᵀH d·t² at
 * distance t, so the error stays below ε·E inside the ellipse with semi-axes √(2εE/|λ_k|) along H's
 * eigenvectors, and inside the circle of radius √(2εE/max|λ|). The paper makes the relative metric
 * robust to black occluders (E → 0) and needs no split-sphere clamps; here the caller's
 * min_irradiance floors E and min/max_radius clamp the result (a flat environment has λ = 0).
 */
#include "gather_internal.h"

#include <stdlib.h>

/* 6-point Gauss–Legendre on [−1, 1]. */
static const double GL_X[6] = {-0.9324695142031521, -0.6612093864662645, -0.2386191860831909,
                               0.2386191860831909,  0.6612093864662645,  0.9324695142031521};
static const double GL_W[6] = {0.1713244923791704, 0.3607615730481386, 0.4679139345726910,
                               0.4679139345726910, 0.3607615730481386, 0.1713244923791704};

/* Raw (unsymmetrised) sums of (2) and (3). */
typedef struct wall_sums {
    double gx, gy, hxx, hxy, hyx, hyy;
} wall_sums;

/* One quadrature node: direction w, its derivative dw along the wall, weight ds. */
static void add_node(const double w[3], const double dw[3], double ds, wall_sums *s)
{
    /* q_e = ω·(e × ω'): e × ω' = (0, −ω'_z, ω'_y) for e = t and (ω'_z, 0, −ω'_x) for e = b. */
    const double qx = -w[1] * dw[2] + w[2] * dw[1];
    const double qy = w[0] * dw[2] - w[2] * dw[0];
    const double wz = w[2] * ds;
    s->gx -= wz * qx;
    s->gy -= wz * qy;
    s->hxx += wz * (-4.0 * qx * w[0]);
    s->hxy += wz * (-dw[2] - 4.0 * qx * w[1]); /* (t × ω')_b = −ω'_z */
    s->hyx += wz * (dw[2] - 4.0 * qy * w[0]);  /* (b × ω')_t = ω'_z */
    s->hyy += wz * (-4.0 * qy * w[1]);
}

static ic_wall_factors finish(const wall_sums *s)
{
    ic_wall_factors f;
    f.g[0] = s->gx;
    f.g[1] = s->gy;
    f.h[0] = s->hxx;
    f.h[1] = 0.5 * (s->hxy + s->hyx);
    f.h[2] = s->hyy;
    return f;
}

ic_wall_factors ic_gather_arc_factors(ic_vec3 a3, ic_vec3 b3)
{
    double a[3] = {a3.x, a3.y, a3.z}, b[3] = {b3.x, b3.y, b3.z};
    double na = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]), nb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    for (int i = 0; i < 3; ++i) {
        a[i] /= na;
        b[i] /= nb;
    }
    const double ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    double c[3] = {b[0] - ab * a[0], b[1] - ab * a[1], b[2] - ab * a[2]};
    const double nc = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    wall_sums s = {0};
    if (!(nc > 0.0))
        return finish(&s);
    for (int i = 0; i < 3; ++i)
        c[i] /= nc;
    const double gamma = atan2(nc, ab);
    for (int q = 0; q < 6; ++q) {
        const double t = 0.5 * gamma * (GL_X[q] + 1.0), cs = cos(t), sn = sin(t);
        double w[3], dw[3];
        for (int i = 0; i < 3; ++i) {
            w[i] = a[i] * cs + c[i] * sn;
            dw[i] = -a[i] * sn + c[i] * cs;
        }
        add_node(w, dw, 0.5 * gamma * GL_W[q], &s);
    }
    return finish(&s);
}

ic_wall_factors ic_gather_meridian_factors(double phi, double theta0, double theta1)
{
    wall_sums s = {0};
    const double cp = cos(phi), sp = sin(phi), half = 0.5 * (theta1 - theta0);
    for (int q = 0; q < 6; ++q) {
        const double th = theta0 + half * (GL_X[q] + 1.0), st = sin(th), ct = cos(th);
        const double w[3] = {st * cp, st * sp, ct}, dw[3] = {ct * cp, ct * sp, -st};
        add_node(w, dw, half * GL_W[q], &s);
    }
    return finish(&s);
}

ic_wall_factors ic_gather_parallel_factors(double theta, double phi0, double phi1)
{
    wall_sums s = {0};
    const double st = sin(theta), ct = cos(theta), half = 0.5 * (phi1 - phi0);
    for (int q = 0; q < 6; ++q) {
        const double ph = phi0 + half * (GL_X[q] + 1.0), cp = cos(ph), sp = sin(ph);
        const double w[3] = {st * cp, st * sp, ct}, dw[3] = {-st * sp, st * cp, 0.0};
        add_node(w, dw, half * GL_W[q], &s);
    }
    return finish(&s);
}

ic_result ic_gather_hessian_init(ic_gatherer *g)
{
    const uint32_t M = g->opts.theta_strata, N = g->opts.phi_strata;
    g->grid_walls = malloc(2 * (size_t)M * sizeof *g->grid_walls);
    if (!g->grid_walls)
        return IC_ERR_OOM;
    /* Column 0 with its first boundary at φ = 0; column k is this turned by φ0 + 2πk/N. */
    const double dphi = 2.0 * (double)IC_PI / N;
    for (uint32_t j = 0; j < M; ++j) {
        const double th0 = asin(sqrt((double)j / M)), th1 = asin(sqrt((double)(j + 1) / M));
        /* Meridian at φ = 0, θ increasing: its left side is +φ, the column's own cell (j, k). */
        g->grid_walls[2 * j] = ic_gather_meridian_factors(0.0, th0, th1);
        /* Parallel at θ_j, φ increasing: its left side is smaller θ, cell (j − 1, k). */
        g->grid_walls[2 * j + 1] = ic_gather_parallel_factors(th0, 0.0, dphi);
    }
    return IC_OK;
}

/* Adds ΔL·f/r and ΔL·f/r² (per channel) to a column's sums. */
static void add_wall(double col[3][5], ic_vec3 left, ic_vec3 right, const ic_wall_factors *f, float r)
{
    const double d[3] = {(double)left.x - right.x, (double)left.y - right.y, (double)left.z - right.z};
    const double ir = 1.0 / r, ir2 = ir * ir;
    for (int c = 0; c < 3; ++c) {
        col[c][0] += d[c] * f->g[0] * ir;
        col[c][1] += d[c] * f->g[1] * ir;
        col[c][2] += d[c] * f->h[0] * ir2;
        col[c][3] += d[c] * f->h[1] * ir2;
        col[c][4] += d[c] * f->h[2] * ir2;
    }
}

void ic_gather_hessian_grid(const ic_gatherer *g, uint32_t M, uint32_t N, float phi0, const ic_frame *frame,
                            ic_gather_result *out)
{
    const ic_vec3 *L = g->cell_radiance;
    const float *dist = g->cell_dist;
    double hess[3][3] = {{0}};
    for (uint32_t k = 0; k < N; ++k) {
        double col[3][5] = {{0}};
        const uint32_t kprev = k == 0 ? N - 1 : k - 1;
        for (uint32_t j = 0; j < M; ++j) {
            const uint32_t c = k * M + j;
            if (N > 1) {
                const float r = fminf(dist[c], dist[kprev * M + j]);
                if (r < INFINITY)
                    add_wall(col, L[c], L[kprev * M + j], &g->grid_walls[2 * j], r);
            }
            if (j > 0) {
                const float r = fminf(dist[c], dist[c - 1]);
                if (r < INFINITY)
                    add_wall(col, L[c - 1], L[c], &g->grid_walls[2 * j + 1], r);
            }
        }
        /* Turn the column's Hessian by its azimuth: H' = R H Rᵀ. */
        const double a = (double)phi0 + 2.0 * (double)IC_PI * k / N, cs = cos(a), sn = sin(a);
        for (int ch = 0; ch < 3; ++ch) {
            const double xx = col[ch][2], xy = col[ch][3], yy = col[ch][4];
            hess[ch][0] += cs * cs * xx - 2.0 * cs * sn * xy + sn * sn * yy;
            hess[ch][1] += cs * sn * (xx - yy) + (cs * cs - sn * sn) * xy;
            hess[ch][2] += sn * sn * xx + 2.0 * cs * sn * xy + cs * cs * yy;
        }
    }
    out->has_hessian = 1;
    out->hessian_t = frame->t;
    out->hessian_b = frame->b;
    for (int ch = 0; ch < 3; ++ch)
        for (int i = 0; i < 3; ++i)
            out->hessian[ch][i] = (float)hess[ch][i];
}

ic_result ic_gather_hessian_extent(const ic_gather_result *r, const ic_gather_extent_opts *opts,
                                   ic_gather_extent *out)
{
    if (!r || !out || !r->has_hessian)
        return IC_ERR_INVALID_ARG;
    ic_gather_extent_opts o = opts ? *opts : (ic_gather_extent_opts){0};
    if (o.rel_error == 0.0f)
        o.rel_error = 0.1f;
    if (o.max_radius == 0.0f)
        o.max_radius = INFINITY;
    if (!(o.rel_error > 0.0f) || !(o.min_radius >= 0.0f) || !(o.max_radius >= o.min_radius) ||
        !(o.min_irradiance >= 0.0f) || !isfinite(o.rel_error))
        return IC_ERR_INVALID_ARG;

    /* Luminance Hessian and irradiance (Rec. 709). */
    static const double Y[3] = {0.2126, 0.7152, 0.0722};
    double h[3] = {0, 0, 0};
    for (int c = 0; c < 3; ++c)
        for (int i = 0; i < 3; ++i)
            h[i] += Y[c] * r->hessian[c][i];
    double E = Y[0] * r->irradiance.x + Y[1] * r->irradiance.y + Y[2] * r->irradiance.z;
    if (!(E >= o.min_irradiance))
        E = o.min_irradiance;

    /* Eigen-decomposition of [[a, b], [b, d]]. */
    const double a = h[0], b = h[1], d = h[2];
    const double mean = 0.5 * (a + d), rad = hypot(0.5 * (a - d), b);
    double l1 = mean + rad, l2 = mean - rad;
    /* Eigenvector of l1: (b, l1 − a) or (l1 − d, b), whichever is better conditioned. */
    double vx, vy;
    if (fabs(l1 - a) > fabs(l1 - d)) {
        vx = b;
        vy = l1 - a;
    } else {
        vx = l1 - d;
        vy = b;
    }
    double vn = hypot(vx, vy);
    if (!(vn > 0.0)) {
        vx = 1.0;
        vy = 0.0;
        vn = 1.0;
    }
    vx /= vn;
    vy /= vn;
    double ux = vx, uy = vy, wx = -vy, wy = vx; /* eigenvectors of l1, l2 */
    if (fabs(l2) > fabs(l1)) {                  /* order by |λ| */
        double t = l1;
        l1 = l2;
        l2 = t;
        ux = -vy;
        uy = vx;
        wx = vx;
        wy = vy;
    }
    const double lam[2] = {l1, l2};
    const double ax[2][2] = {{ux, uy}, {wx, wy}};
    const double budget = 2.0 * (double)o.rel_error * E;
    for (int k = 0; k < 2; ++k) {
        double s = fabs(lam[k]) > 0.0 ? sqrt(budget / fabs(lam[k])) : INFINITY;
        s = fmin(fmax(s, (double)o.min_radius), (double)o.max_radius);
        out->semi_axis[k] = (float)s;
        out->eigenvalue[k] = (float)lam[k];
        out->axis[k] = v3_add(v3_scale(r->hessian_t, (float)ax[k][0]), v3_scale(r->hessian_b, (float)ax[k][1]));
    }
    out->radius = out->semi_axis[0];
    return IC_OK;
}
