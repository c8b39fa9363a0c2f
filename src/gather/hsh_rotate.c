/*
 * hsh_rotate.c — rotation of hemispherical-harmonic coefficient vectors between local frames, for
 * radiance-cache interpolation across normals (Křivánek et al. 2005 (TVCG)).
 *
 * The reference rotation goes through spherical harmonics, as Gautron et al. 2004 propose: the HSH
 * function, extended by zero below the horizon, is projected onto SH of order L (matrix T); the SH vector
 * is rotated; the result is projected back onto HSH over the upper hemisphere (T^T). T is computed here by
 * Gauss–Legendre quadrature rather than transcribed from Gautron et al.'s closed form: it is then right for
 * any order and any sign convention, costs milliseconds once per basis, and its accuracy can be measured.
 * T keeps m (both bases share the cos mφ / sin mφ factors), so it is one small block per |m|, the same
 * for the cos and the sin member of each pair.
 *
 * The rotation is split into ZYZ Euler angles, r = Rz(α)·Ry(β)·Rz(γ). z-rotations commute with T and are
 * done on the HSH vector directly (each cos mφ / sin mφ pair turns by mα). The y-rotation is written as
 * Rx(−90°)·Rz(β)·Rx(90°) (the "zxzxz" form of Kautz, Sloan & Snyder 2002), so the only SH rotation
 * matrices needed are those of the fixed Rx(90°), built once per basis, band by band, with the
 * Ivanic–Ruedenberg recurrence (Ivanic & Ruedenberg 1996, with the 1998 errata).
 *
 * Zero extension: T's columns carry the SH tail of the jump at the horizon, so T^T·T is not the identity:
 * a function that does not vanish at the horizon loses the part of that tail beyond band L, even for a
 * tiny β. β = 0 (equal normals) is therefore done as the exact z-rotation. A function that vanishes near
 * the horizon is carried without that loss, and rotating it by R then R⁻¹ returns it while the rotation
 * keeps it above the horizon; whatever a rotation moves below the horizon is lost, as on a real surface.
 * docs/radiance-caching.md gives the measured figures.
 *
 * The fast rotation follows Křivánek, Konttinen, Pattanaik, Bouatouch & Žára 2008: exact z-rotations
 * around a y-rotation replaced by its Taylor expansion in β. Here it is the expansion of exactly what the
 * reference computes, M(β) = T^T·D_y(β)·T ≈ G₀ + β·G + β²/2·G₂ with G₀ = T^T·T, G = T^T·J·T,
 * G₂ = T^T·J²·T and J = X^T·J_z·X the SH generator of y-rotations, so the two agree to O(β³). A
 * y-rotation keeps the parity in y, so J couples cos with cos and sin with sin terms and changes |m| by
 * one; G inherits that sparsity (G₀ keeps |m|, G₂ changes it by 0 or 2), though unlike the SH case the
 * matrices couple every degree l with every other.
 */
#include "hsh_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Offset of SH band l in a concatenation of (2l'+1)×(2l'+1) matrices: Σ_{l'<l} (2l'+1)² = l(4l²−1)/3. */
static size_t band_offset(uint32_t l) { return (size_t)l * (4u * (size_t)l * l - 1u) / 3u; }

/* ---- Ivanic–Ruedenberg recurrence ------------------------------------------------------------- */

/* The helper function P of Ivanic & Ruedenberg 1996 (with the 1998 errata): r1 is band 1,
 * prev band l−1 (2l−1 wide). */
static double ir_p(const double *r1, const double *prev, int l, int i, int a, int b)
{
    int w = 2 * l - 1;
#define R1(x, y) r1[((x) + 1) * 3 + ((y) + 1)]
#define PREV(x, y) prev[((x) + l - 1) * w + ((y) + l - 1)]
    if (b == l)
        return R1(i, 1) * PREV(a, l - 1) - R1(i, -1) * PREV(a, -l + 1);
    if (b == -l)
        return R1(i, 1) * PREV(a, -l + 1) + R1(i, -1) * PREV(a, l - 1);
    return R1(i, 0) * PREV(a, b);
#undef R1
#undef PREV
}

/* Real SH rotation matrices of bands 0..L−1 for the rotation r: band l at d + band_offset(l), row-major,
 * row m + l, column m' + l. For coefficients c of f, D·c are the coefficients of f(r⁻¹ω). Band 1 is r
 * itself in the order (y, z, x) of the real l = 1 harmonics. */
static void sh_rotation(const double *r, uint32_t L, double *d)
{
    d[0] = 1.0;
    if (L < 2)
        return;
    static const int axis[3] = {1, 2, 0}; /* m = −1, 0, 1 ↦ y, z, x */
    double *r1 = d + band_offset(1);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            r1[i * 3 + j] = r[axis[i] * 3 + axis[j]];
    for (int l = 2; l < (int)L; ++l) {
        const double *prev = d + band_offset((uint32_t)l - 1);
        double *cur = d + band_offset((uint32_t)l);
        int w = 2 * l + 1;
        for (int m = -l; m <= l; ++m)
            for (int mp = -l; mp <= l; ++mp) {
                int am = abs(m), d0 = m == 0;
                double denom = abs(mp) < l ? (double)(l + mp) * (l - mp) : (double)(2 * l) * (2 * l - 1);
                double u = sqrt((double)(l + m) * (l - m) / denom);
                double v = 0.5 * sqrt((1.0 + d0) * (l + am - 1) * (l + am) / denom) * (1.0 - 2.0 * d0);
                double wc = -0.5 * sqrt((double)(l - am - 1) * (l - am) / denom) * (1.0 - d0);
                double sum = 0.0;
                if (u != 0.0)
                    sum += u * ir_p(r1, prev, l, 0, m, mp);
                if (v != 0.0) {
                    double V;
                    if (m == 0)
                        V = ir_p(r1, prev, l, 1, 1, mp) + ir_p(r1, prev, l, -1, -1, mp);
                    else if (m > 0) {
                        int d1 = m == 1;
                        V = ir_p(r1, prev, l, 1, m - 1, mp) * sqrt(1.0 + d1) - ir_p(r1, prev, l, -1, -m + 1, mp) * (1 - d1);
                    } else {
                        int d1 = m == -1;
                        V = ir_p(r1, prev, l, 1, m + 1, mp) * (1 - d1) + ir_p(r1, prev, l, -1, -m - 1, mp) * sqrt(1.0 + d1);
                    }
                    sum += v * V;
                }
                if (wc != 0.0) {
                    double W;
                    if (m > 0)
                        W = ir_p(r1, prev, l, 1, m + 1, mp) + ir_p(r1, prev, l, -1, -m - 1, mp);
                    else
                        W = ir_p(r1, prev, l, 1, m - 1, mp) - ir_p(r1, prev, l, -1, -m + 1, mp);
                    sum += wc * W;
                }
                cur[(m + l) * w + (mp + l)] = sum;
            }
    }
}

/* ---- HSH ↔ SH conversion and the fast rotation's matrices ----------------------------------------- */

static double conv_at(const ic_hsh_basis *b, uint32_t m, uint32_t lsh, uint32_t lhsh)
{
    return b->conv[b->conv_offset[m] + (size_t)(lsh - m) * (b->order - m) + (lhsh - m)];
}

/* Sparse rows from a dense n²×n² matrix, keeping the entries the structure allows: the same y-parity
 * (m ≥ 0 with m ≥ 0, m < 0 with m < 0) and a change of |m| in `steps` (a bit set: bit d for |Δ|m|| = d). */
static ic_result sparse_from_dense(const ic_hsh_basis *b, const double *dense, unsigned steps, hsh_sparse *s)
{
    uint32_t n = b->order, count = b->count, nnz = 0;
    s->row_start = malloc((count + 1) * sizeof *s->row_start);
    s->col = malloc((size_t)count * count * sizeof *s->col);
    s->val = malloc((size_t)count * count * sizeof *s->val);
    if (!s->row_start || !s->col || !s->val)
        return IC_ERR_OOM;
    for (uint32_t l1 = 0; l1 < n; ++l1)
        for (int m1 = -(int)l1; m1 <= (int)l1; ++m1) {
            uint32_t k1 = ic_hsh_index((int)l1, m1);
            s->row_start[k1] = nnz;
            for (uint32_t l2 = 0; l2 < n; ++l2)
                for (int m2 = -(int)l2; m2 <= (int)l2; ++m2) {
                    int dm = abs(abs(m1) - abs(m2));
                    if ((m1 >= 0) != (m2 >= 0) || !(steps & (1u << dm)))
                        continue;
                    uint32_t k2 = ic_hsh_index((int)l2, m2);
                    s->col[nnz] = k2;
                    s->val[nnz] = (float)dense[(size_t)k1 * count + k2];
                    ++nnz;
                }
        }
    /* Rows were visited in index order, so row_start is filled for every row. */
    s->row_start[count] = nnz;
    return IC_OK;
}

ic_result hsh_build_rotation(ic_hsh_basis *b, ic_error *err)
{
    uint32_t n = b->order, L = b->sh_order;
    size_t total = 0;
    for (uint32_t m = 0; m < n; ++m) {
        b->conv_offset[m] = total;
        total += (size_t)(L - m) * (n - m);
    }
    b->conv = calloc(total ? total : 1, sizeof *b->conv);
    uint32_t q = 2 * (L + n) + 16;
    double *gx = malloc(q * sizeof *gx), *gw = malloc(q * sizeof *gw);
    double *th_sh = malloc(hsh_tri(L, 0) * sizeof *th_sh), *th_h = malloc(hsh_tri(n, 0) * sizeof *th_h);
    size_t dsize = band_offset(L);
    double *g0 = calloc((size_t)b->count * b->count, sizeof *g0);
    double *g1 = calloc((size_t)b->count * b->count, sizeof *g1), *g2 = calloc((size_t)b->count * b->count, sizeof *g2);
    double *jy = malloc((size_t)(2 * L + 1) * (2 * L + 1) * sizeof *jy), *jsq = malloc((size_t)(2 * L + 1) * (2 * L + 1) * sizeof *jsq);
    b->xrot = malloc(dsize * sizeof *b->xrot);
    ic_result r = IC_OK;
    if (!b->conv || !b->xrot || !gx || !gw || !th_sh || !th_h || !jy || !g1 || !g2 || !jsq) {
        r = ic_error_set(err, IC_ERR_OOM, "hsh: out of memory for the rotation matrices");
        goto done;
    }
    /* T_m[l'][l] = ∫_0^1 Θ_{l'}^m(z)·√2·Θ_l^m(2z − 1) dz (the φ integral is 1 for matching members).
     * With z = t² the factor (1 − z²)^{m/2}·(z(1 − z))^{m/2} becomes t^m (1 − t²)^m (1 + t²)^{m/2}: smooth,
     * so Gauss–Legendre in t converges fast even for odd m. */
    hsh_gauss_legendre(q, gx, gw);
    for (uint32_t i = 0; i < q; ++i) {
        double t = gx[i], z = t * t, w = gw[i] * 2.0 * t * sqrt(2.0);
        hsh_legendre(b, L, z, sqrt((1.0 - z) * (1.0 + z)), th_sh);
        hsh_legendre(b, n, 2.0 * z - 1.0, 2.0 * t * sqrt(1.0 - z), th_h);
        for (uint32_t m = 0; m < n; ++m)
            for (uint32_t ls = m; ls < L; ++ls)
                for (uint32_t lh = m; lh < n; ++lh)
                    b->conv[b->conv_offset[m] + (size_t)(ls - m) * (n - m) + (lh - m)] +=
                        w * th_sh[hsh_tri(ls, m)] * th_h[hsh_tri(lh, m)];
    }
    /* X = D(Rx(90°)) by the Ivanic–Ruedenberg recurrence. */
    {
        const double rx[9] = {1, 0, 0, 0, 0, -1, 0, 1, 0};
        sh_rotation(rx, L, b->xrot);
    }
    /* G = T^T J T and G₂ = T^T J² T, accumulated band by band of the SH expansion. */
    for (uint32_t ls = 0; ls < L; ++ls) {
        int w = 2 * (int)ls + 1, l = (int)ls;
        /* J_y = X^T J_z X: J_z, the z-rotation generator, maps the pair (c_m, s_m) to (−m·s_m, m·c_m). */
        const double *X = b->xrot + band_offset(ls);
        double *J = jy;
        for (int i = 0; i < w; ++i)
            for (int j = 0; j < w; ++j) {
                double s = 0.0;
                for (int k = 0; k < w; ++k) {
                    int m = k - l; /* (J_z X)[k][j] = m > 0: −m·X[−m][j]; m < 0: |m|·X[|m|][j] */
                    double jzx = m > 0 ? -m * X[(l - m) * w + j] : (m < 0 ? -m * X[(l - m) * w + j] : 0.0);
                    s += X[k * w + i] * jzx;
                }
                J[i * w + j] = s;
            }
        for (int i = 0; i < w; ++i)
            for (int j = 0; j < w; ++j) {
                double s = 0.0;
                for (int k = 0; k < w; ++k)
                    s += J[i * w + k] * J[k * w + j];
                jsq[i * w + j] = s;
            }
        for (uint32_t l1 = 0; l1 < n; ++l1)
            for (int m1 = -(int)l1; m1 <= (int)l1; ++m1) {
                uint32_t a1 = (uint32_t)abs(m1);
                if (ls < a1)
                    continue;
                double t1 = conv_at(b, a1, ls, l1);
                for (uint32_t l2 = 0; l2 < n; ++l2)
                    for (int m2 = -(int)l2; m2 <= (int)l2; ++m2) {
                        uint32_t a2 = (uint32_t)abs(m2);
                        if (ls < a2)
                            continue;
                        double t12 = t1 * conv_at(b, a2, ls, l2);
                        size_t e = (size_t)(m1 + (int)ls) * w + (size_t)(m2 + (int)ls);
                        size_t k = (size_t)ic_hsh_index((int)l1, m1) * b->count + ic_hsh_index((int)l2, m2);
                        g1[k] += t12 * J[e];
                        if (m1 == m2)
                            g0[k] += t12;
                        g2[k] += t12 * jsq[e];
                    }
            }
    }
    /* X as a list of its non-zero entries per band. */
    {
        size_t nnz = 0;
        for (size_t i = 0; i < dsize; ++i)
            nnz += fabs(b->xrot[i]) > 1e-15;
        b->x_band_start = malloc((L + 1) * sizeof *b->x_band_start);
        b->x_row = malloc((nnz ? nnz : 1) * sizeof *b->x_row);
        b->x_col = malloc((nnz ? nnz : 1) * sizeof *b->x_col);
        b->x_val = malloc((nnz ? nnz : 1) * sizeof *b->x_val);
        if (!b->x_band_start || !b->x_row || !b->x_col || !b->x_val) {
            r = ic_error_set(err, IC_ERR_OOM, "hsh: out of memory for the rotation matrices");
            goto done;
        }
        uint32_t e = 0;
        for (uint32_t l = 0; l < L; ++l) {
            uint32_t w = 2 * l + 1;
            const double *X = b->xrot + band_offset(l);
            b->x_band_start[l] = e;
            for (uint32_t i = 0; i < w; ++i)
                for (uint32_t j = 0; j < w; ++j)
                    if (fabs(X[i * w + j]) > 1e-15) {
                        b->x_row[e] = (uint16_t)i;
                        b->x_col[e] = (uint16_t)j;
                        b->x_val[e] = X[i * w + j];
                        ++e;
                    }
        }
        b->x_band_start[L] = e;
    }
    if (sparse_from_dense(b, g0, 1u << 0, &b->zeroth) != IC_OK || sparse_from_dense(b, g1, 1u << 1, &b->first) != IC_OK ||
        sparse_from_dense(b, g2, (1u << 0) | (1u << 2), &b->second) != IC_OK)
        r = ic_error_set(err, IC_ERR_OOM, "hsh: out of memory for the rotation matrices");
done:
    free(b->xrot);
    b->xrot = NULL;
    free(gx);
    free(gw);
    free(th_sh);
    free(th_h);
    free(jy);
    free(g0);
    free(g1);
    free(g2);
    free(jsq);
    return r;
}

void hsh_free_rotation(ic_hsh_basis *b)
{
    free(b->conv);
    free(b->xrot);
    free(b->x_band_start);
    free(b->x_row);
    free(b->x_col);
    free(b->x_val);
    free(b->first.row_start);
    free(b->first.col);
    free(b->first.val);
    free(b->zeroth.row_start);
    free(b->zeroth.col);
    free(b->zeroth.val);
    free(b->second.row_start);
    free(b->second.col);
    free(b->second.val);
}

/* ---- rotations ---------------------------------------------------------------------------------- */

void ic_hsh_rotation_from_matrix(const double *rowmajor, ic_hsh_rotation *out)
{
    for (int a = 0; a < 3; ++a)
        for (int c = 0; c < 3; ++c)
            out->m[a][c] = rowmajor[a * 3 + c];
    const double *m = rowmajor;
    /* Rz(α)Ry(β)Rz(γ) has third column (cosα sinβ, sinα sinβ, cosβ) and third row
     * (−sinβ cosγ, sinβ sinγ, cosβ). */
#define M(a, c) m[(a) * 3 + (c)]
    double sb = sqrt(M(0, 2) * M(0, 2) + M(1, 2) * M(1, 2));
    out->beta = atan2(sb, M(2, 2));
    if (sb > 1e-12) {
        out->alpha = atan2(M(1, 2), M(0, 2));
        out->gamma = atan2(M(2, 1), -M(2, 0));
    } else if (M(2, 2) > 0.0) { /* β = 0: a z-rotation by α + γ */
        out->alpha = atan2(M(1, 0), M(0, 0));
        out->gamma = 0.0;
    } else {                    /* β = π: Rz(α)Ry(π) = [[−cosα, −sinα, 0], [−sinα, cosα, 0], [0, 0, −1]] */
        out->alpha = atan2(-M(0, 1), M(1, 1));
        out->gamma = 0.0;
    }
#undef M
}

void ic_hsh_rotation_from_euler(double alpha, double beta, double gamma, ic_hsh_rotation *out)
{
    double ca = cos(alpha), sa = sin(alpha), cb = cos(beta), sb = sin(beta), cg = cos(gamma), sg = sin(gamma);
    double m[3][3] = {{ca * cb * cg - sa * sg, -ca * cb * sg - sa * cg, ca * sb},
                      {sa * cb * cg + ca * sg, -sa * cb * sg + ca * cg, sa * sb},
                      {-sb * cg, sb * sg, cb}};
    memcpy(out->m, m, sizeof m);
    out->alpha = alpha;
    out->beta = beta;
    out->gamma = gamma;
}

void ic_hsh_rotation_from_frames(const ic_hsh_frame *from, const ic_hsh_frame *to, ic_hsh_rotation *out)
{
    const ic_vec3 *f[3] = {&from->tangent, &from->bitangent, &from->normal};
    const ic_vec3 *t[3] = {&to->tangent, &to->bitangent, &to->normal};
    double m[3][3];
    for (int a = 0; a < 3; ++a)
        for (int c = 0; c < 3; ++c)
            m[a][c] = (double)t[a]->x * f[c]->x + (double)t[a]->y * f[c]->y + (double)t[a]->z * f[c]->z;
    ic_hsh_rotation_from_matrix(&m[0][0], out);
}

void ic_hsh_rotation_invert(const ic_hsh_rotation *r, ic_hsh_rotation *out)
{
    double m[3][3];
    for (int a = 0; a < 3; ++a)
        for (int c = 0; c < 3; ++c)
            m[a][c] = r->m[c][a];
    ic_hsh_rotation_from_matrix(&m[0][0], out);
}

void ic_hsh_rotate_z(const ic_hsh_basis *b, double angle, const float *in, uint32_t channels, float *out)
{
    uint32_t n = b->order, count = b->count;
    double c1 = cos(angle), s1 = sin(angle);
    for (uint32_t ch = 0; ch < channels; ++ch) {
        const float *x = in + (size_t)ch * count;
        float *y = out + (size_t)ch * count;
        for (uint32_t l = 0; l < n; ++l)
            y[ic_hsh_index((int)l, 0)] = x[ic_hsh_index((int)l, 0)];
        double cm = 1.0, sm = 0.0;
        for (uint32_t m = 1; m < n; ++m) {
            double c = cm * c1 - sm * s1;
            sm = sm * c1 + cm * s1;
            cm = c;
            /* f(θ, φ − a): cos m(φ − a) = cos mφ cos ma + sin mφ sin ma, sin m(φ − a) = sin mφ cos ma − cos mφ sin ma. */
            for (uint32_t l = m; l < n; ++l) {
                uint32_t kc = ic_hsh_index((int)l, (int)m), ks = ic_hsh_index((int)l, -(int)m);
                double a = x[kc], s = x[ks];
                y[kc] = (float)(a * cm - s * sm);
                y[ks] = (float)(a * sm + s * cm);
            }
        }
    }
}

size_t ic_hsh_rotate_exact_scratch(const ic_hsh_basis *b) { return 2u * (size_t)b->sh_order * b->sh_order; }

/* SH z-rotation of one band vector in place (the same cos/sin mixing as ic_hsh_rotate_z), with
 * cm[m] = cos mβ and sm[m] = sin mβ tabulated once per rotation. */
static void sh_band_rotate_z(double *v, int l, const double *cm, const double *sm)
{
    for (int m = 1; m <= l; ++m) {
        double a = v[l + m], s = v[l - m];
        v[l + m] = a * cm[m] - s * sm[m];
        v[l - m] = a * sm[m] + s * cm[m];
    }
}

ic_result ic_hsh_rotate_exact(const ic_hsh_basis *b, const ic_hsh_rotation *r, const float *in,
                              uint32_t channels, float *out, double *scratch)
{
    uint32_t n = b->order, L = b->sh_order;
    if (r->beta == 0.0) { /* the normals agree: a z-rotation, exact and without the SH detour's loss */
        ic_hsh_rotate_z(b, r->alpha + r->gamma, in, channels, out);
        return IC_OK;
    }
    double *own = NULL;
    if (!scratch) {
        own = malloc(ic_hsh_rotate_exact_scratch(b) * sizeof *own);
        if (!own)
            return IC_ERR_OOM;
        scratch = own;
    }
    double *sh = scratch, *tmp = sh + (size_t)L * L;
    float zin[IC_HSH_MAX_COUNT];
    double cm[4 * IC_HSH_MAX_ORDER], sm[4 * IC_HSH_MAX_ORDER];
    cm[0] = 1.0;
    sm[0] = 0.0;
    const double cb = cos(r->beta), sb = sin(r->beta);
    for (uint32_t m = 1; m < L; ++m) { /* angle addition, in double: L ≤ 96 steps stay accurate */
        cm[m] = cm[m - 1] * cb - sm[m - 1] * sb;
        sm[m] = sm[m - 1] * cb + cm[m - 1] * sb;
    }
    for (uint32_t ch = 0; ch < channels; ++ch) {
        ic_hsh_rotate_z(b, r->gamma, in + (size_t)ch * b->count, 1, zin);
        float *y = out + (size_t)ch * b->count;
        /* HSH → SH: the zero-extended function's SH coefficients up to band L − 1 (T); |m| ≥ n stay 0. */
        memset(sh, 0, (size_t)L * L * sizeof *sh);
        for (uint32_t m = 0; m < n; ++m)
            for (uint32_t ls = m; ls < L; ++ls) {
                double sc = 0.0, ss = 0.0;
                for (uint32_t lh = m; lh < n; ++lh) {
                    double t = conv_at(b, m, ls, lh);
                    sc += t * zin[ic_hsh_index((int)lh, (int)m)];
                    if (m)
                        ss += t * zin[ic_hsh_index((int)lh, -(int)m)];
                }
                sh[ic_hsh_index((int)ls, (int)m)] = sc;
                if (m)
                    sh[ic_hsh_index((int)ls, -(int)m)] = ss;
            }
        /* Ry(β) = Rx(−90°)·Rz(β)·Rx(90°), band by band: X, then Z(β), then X^T. Only |m| < n is non-zero
         * on the way in and read on the way out, so the other columns, then rows, of X are skipped. */
        for (uint32_t l = 0; l < L; ++l) {
            uint32_t w = 2 * l + 1, lo = l >= n ? l - (n - 1) : 0, hi = l + (l >= n ? n - 1 : l);
            double *v = sh + (size_t)l * l, *u = tmp + (size_t)l * l;
            memset(u, 0, w * sizeof *u);
            for (uint32_t e = b->x_band_start[l]; e < b->x_band_start[l + 1]; ++e)
                if (b->x_col[e] >= lo && b->x_col[e] <= hi)
                    u[b->x_row[e]] += b->x_val[e] * v[b->x_col[e]];
            sh_band_rotate_z(u, (int)l, cm, sm);
            memset(v, 0, w * sizeof *v);
            for (uint32_t e = b->x_band_start[l]; e < b->x_band_start[l + 1]; ++e)
                if (b->x_col[e] >= lo && b->x_col[e] <= hi)
                    v[b->x_col[e]] += b->x_val[e] * u[b->x_row[e]];
        }
        /* SH → HSH by projection onto the upper hemisphere (T^T), then Rz(α). */
        for (uint32_t m = 0; m < n; ++m)
            for (uint32_t lh = m; lh < n; ++lh) {
                double sc = 0.0, ss = 0.0;
                for (uint32_t ls = m; ls < L; ++ls) {
                    double t = conv_at(b, m, ls, lh);
                    sc += t * sh[ic_hsh_index((int)ls, (int)m)];
                    if (m)
                        ss += t * sh[ic_hsh_index((int)ls, -(int)m)];
                }
                y[ic_hsh_index((int)lh, (int)m)] = (float)sc;
                if (m)
                    y[ic_hsh_index((int)lh, -(int)m)] = (float)ss;
            }
        ic_hsh_rotate_z(b, r->alpha, y, 1, y);
    }
    free(own);
    return IC_OK;
}

static void sparse_apply(const hsh_sparse *s, uint32_t count, const float *x, float scale, float *y)
{
    for (uint32_t i = 0; i < count; ++i) {
        float acc = 0.0f;
        for (uint32_t e = s->row_start[i]; e < s->row_start[i + 1]; ++e)
            acc += s->val[e] * x[s->col[e]];
        y[i] += scale * acc;
    }
}

void ic_hsh_rotate_fast(const ic_hsh_basis *b, const ic_hsh_rotation *r, ic_hsh_taylor taylor, const float *in,
                        uint32_t channels, float *out)
{
    uint32_t count = b->count;
    if (r->beta == 0.0) { /* as in ic_hsh_rotate_exact: equal normals need no expansion */
        ic_hsh_rotate_z(b, r->alpha + r->gamma, in, channels, out);
        return;
    }
    float tmp[IC_HSH_MAX_COUNT], acc[IC_HSH_MAX_COUNT];
    float beta = (float)r->beta;
    for (uint32_t ch = 0; ch < channels; ++ch) {
        ic_hsh_rotate_z(b, r->gamma, in + (size_t)ch * count, 1, tmp);
        memset(acc, 0, count * sizeof *acc);
        sparse_apply(&b->zeroth, count, tmp, 1.0f, acc);
        sparse_apply(&b->first, count, tmp, beta, acc);
        if (taylor != IC_HSH_TAYLOR_FIRST)
            sparse_apply(&b->second, count, tmp, 0.5f * beta * beta, acc);
        ic_hsh_rotate_z(b, r->alpha, acc, 1, out + (size_t)ch * count);
    }
}
