/*
 * hsh_internal.h — the basis object shared by hsh.c (basis, projection, lobes) and hsh_rotate.c
 * (rotations). Not installed.
 */
#ifndef IC_HSH_INTERNAL_H
#define IC_HSH_INTERNAL_H

#include "irrcache/hsh.h"

#include <stddef.h>

/* Index of the normalised associated Legendre function Θ_l^m (0 ≤ m ≤ l) in a triangular table. */
static inline size_t hsh_tri(uint32_t l, uint32_t m) { return (size_t)l * (l + 1) / 2 + m; }

/* A sparse matrix in compressed rows (n² rows). */
typedef struct hsh_sparse {
    uint32_t *row_start;   /* n² + 1 offsets into col and val */
    uint32_t *col;
    float *val;
} hsh_sparse;

struct ic_hsh_basis {
    uint32_t order;        /* n */
    uint32_t count;        /* n² */
    uint32_t sh_order;     /* L: SH bands 0..L-1 for the rotations */
    uint32_t legendre_order; /* max(n, L): size of the recurrence tables */
    double *rec_a, *rec_b; /* three-term recurrence coefficients, indexed by hsh_tri(l, m), l ≥ m + 2 */
    double *diag;          /* Θ_m^m = diag[m]·s·Θ_{m-1}^{m-1} */
    double *sub;           /* Θ_{m+1}^m = sub[m]·x·Θ_m^m */
    /* HSH → SH conversion, one dense block per |m|: conv[conv_offset[m] + (l' − m)·(n − m) + (l − m)] =
     * ∫_{upper hemisphere} Y_{l'}^m H_l^m dω, the same for the cos and the sin member of each pair. */
    double *conv;
    size_t conv_offset[IC_HSH_MAX_ORDER];
    /* Real SH rotation matrices of the rotation by +90° about x, bands 0..L−1 concatenated (band l is
     * (2l+1)×(2l+1), row-major): the y-rotation is X⁻¹·Z(β)·X (Kautz et al. 2002). */
    double *xrot;          /* (only during creation) */
    uint32_t *x_band_start;/* the non-zero entries of X (about a quarter), band l at [x_band_start[l], [l+1]) */
    uint16_t *x_row, *x_col;
    double *x_val;
    hsh_sparse zeroth;     /* G₀ = T^T T: the y-rotation at β = 0 as the SH detour computes it */
    hsh_sparse first;      /* G  = T^T J T: derivative of the y-rotation at β = 0 */
    hsh_sparse second;     /* G₂ = T^T J² T: its second derivative */
};

/* Θ_l^m(x) for 0 ≤ m ≤ l < lmax (lmax ≤ b->legendre_order), s = √(1 − x²) passed in so that callers
 * can compute it accurately. Normalised so that ∫_{-1}^{1} Θ_l^m(x)² dx = 1; no Condon–Shortley phase. */
void hsh_legendre(const ic_hsh_basis *b, uint32_t lmax, double x, double s, double *theta);

/* Gauss–Legendre nodes and weights on [0, 1] (n ≥ 1). */
void hsh_gauss_legendre(uint32_t n, double *x, double *w);

/* Builds conv, first and second (hsh_rotate.c). IC_ERR_OOM. */
ic_result hsh_build_rotation(ic_hsh_basis *b, ic_error *err);
/* Releases what hsh_build_rotation allocated. */
void hsh_free_rotation(ic_hsh_basis *b);

#endif
