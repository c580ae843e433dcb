/* symkin numerical inverse kinematics in C: see symkin_ik.h and symkin/runtime/ik.py.
 *
 * Linear algebra for n <= SYMKIN_IK_NMAX on stack arrays:
 * - NR (eq 45): LU with partial pivoting of the square J (n = 6);
 * - GN (eqs 46-47): LU of J^T We J;
 * - LM (eqs 48-51): Cholesky of J^T We J + Wn (positive definite), LU if Cholesky fails;
 * - pseudo-inverse (NR and GN with pinv): for a well-conditioned J, the Cholesky factor of the at
 *   most 6 x 6 Gram matrix J^T We J (n <= 6) or We^1/2 J J^T We^1/2 (n > 6) with a guaranteed
 *   bound on its condition number (gram_solve); near a singularity, one-sided Jacobi SVD
 *   (Hestenes) of the matrix, or of its transpose when it is wide, so it works for any n (6x7 J of
 *   a redundant arm, 6x5 J of a 5-DoF arm, the n x n J^T We J); singular values
 *   <= SYMKIN_PINV_RCOND * the largest are dropped, like numpy.linalg.pinv(rcond=SYMKIN_PINV_RCOND).
 *   NR with pinv uses pinv(We^1/2 J) We^1/2 e, which is J^-1 e for a square invertible J.
 * Compile with -ffp-contract=off so the arithmetic rounds like NumPy's (and, with GCC, with
 * -fno-tree-slp-vectorize: GCC 12 fuses some straight-line a*b + c*d / a*b - c*d pairs into
 * vfmaddsub even under -ffp-contract=off).
 *
 * Speed: the LM, NR and GN steps are compiled for n = 6 and n = 7 as constants (unrolled
 * Cholesky, fixed-size copies) besides any n, the normal equations are vectorised over the
 * columns of J (rows of J loaded straight into vectors), and a batch of LM solves with
 * 6 or 7 joints runs SYMKIN_LANES targets side by side with their steps in vector lanes
 * (solve_batch_lm). Every variant does the same operations in the same order, so the numbers are
 * the same to the bit as those of the plain loops. Hot paths call no libm function for min/max:
 * between AVX code such a call cost about 0.3 us on the development machine (SSE/AVX transitions),
 * and the one libm call per iteration, atan2 (symkin_pose.h), comes after a vzeroupper.
 *
 * Thread safety: the functions keep their state on the stack; a config is only read.
 */
#include "symkin_ik.h"
#include "symkin_pose.h"

#include <math.h>
#include <string.h>

#define NM SYMKIN_IK_NMAX
/* At (see chol_solve) has one spare row: GCC warns about dead code of the unrolled loops past the
 * last row when n is not a compile-time constant */
#define AT_SIZE ((NM + 1) * NM)
#if defined(__GNUC__)
#define SYMKIN_INLINE static inline __attribute__((always_inline))
#define SYMKIN_UNROLL _Pragma("GCC unroll 12")
#define SYMKIN_VECTORS 1
#define SYMKIN_LANES 4 /* doubles per vector; the lane-wise code below is written out for 4 */
typedef double symkin_v4 __attribute__((vector_size(SYMKIN_LANES * sizeof(double))));
typedef int64_t symkin_m4 __attribute__((vector_size(SYMKIN_LANES * sizeof(int64_t))));
#define NV ((NM + SYMKIN_LANES - 1) / SYMKIN_LANES) /* vectors per padded row of n <= NM values */
#else
#define SYMKIN_INLINE static inline
#define SYMKIN_UNROLL
#endif
#define SYMKIN_PINV_RCOND 1e-12

static const double TWO_PI = 6.283185307179586;

int32_t symkin_ik_nmax(void) { return NM; }
void symkin_ik_layout(int32_t *out) { /* what symkin.runtime.ik_c checks its mirrors against */
    out[0] = (int32_t)sizeof(symkin_ik_stats);
    out[1] = (int32_t)sizeof(symkin_ik_config);
}

/* ---- random restarts: splitmix64 ---------------------------------------------------------- */
static uint64_t mix64(uint64_t z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

static uint64_t stream_state(uint64_t seed, uint64_t stream) { return mix64(seed + mix64(stream + 1)); }

static double next_uniform(uint64_t *state) {
    *state += 0x9E3779B97F4A7C15ULL;
    return (double)(mix64(*state) >> 11) * 0x1.0p-53;
}

static void random_q(const symkin_ik_config *c, uint64_t *state, double *q) {
    for (int j = 0; j < c->n; j++) {
        double u = next_uniform(state);
        q[j] = c->slo[j] + (c->shi[j] - c->slo[j]) * u;
    }
}

void symkin_ik_random_q(const symkin_ik_config *cfg, uint64_t seed, int64_t stream, int32_t count, double *out) {
    uint64_t state = stream_state(seed, (uint64_t)stream);
    for (int32_t i = 0; i < count; i++) random_q(cfg, &state, out + (int64_t)i * cfg->n);
}

/* ---- pose check and error (eqs 37-40) ----------------------------------------------------- */
int32_t symkin_ik_check_pose(const double *T, double *deviation) { return symkin_pose_check(T, deviation); }

void symkin_ik_pose_error(const double *T, const double *Tep, double *e) { symkin_pose_error(T, Tep, e); }

/* ---- small dense solvers (row-major, n <= NM) --------------------------------------------- */
static int lu_solve(int n, double *A, double *b) {
    for (int k = 0; k < n; k++) {
        int p = k;
        double best = fabs(A[k * n + k]);
        for (int i = k + 1; i < n; i++)
            if (fabs(A[i * n + k]) > best) {
                best = fabs(A[i * n + k]);
                p = i;
            }
        if (best == 0.0) return -1;
        if (p != k) {
            for (int j = 0; j < n; j++) {
                double t = A[k * n + j];
                A[k * n + j] = A[p * n + j];
                A[p * n + j] = t;
            }
            double t = b[k];
            b[k] = b[p];
            b[p] = t;
        }
        double pivot = A[k * n + k];
        for (int i = k + 1; i < n; i++) {
            double f = A[i * n + k] / pivot;
            if (f == 0.0) continue;
            for (int j = k + 1; j < n; j++) A[i * n + j] -= f * A[k * n + j];
            b[i] -= f * b[k];
        }
    }
    for (int i = n - 1; i >= 0; i--) {
        double s = b[i];
        for (int j = i + 1; j < n; j++) s -= A[i * n + j] * b[j];
        b[i] = s / A[i * n + i];
    }
    return 0;
}

/* out (c) = pinv(A) x for A (m x c) row-major, x (m): one-sided Jacobi SVD of A (c <= m) or of
 * A^T (c > m). Orthogonalising the columns of B = M W (W accumulates the rotations) gives
 * columns b_i = sigma_i u_i, so pinv(A) x = sum_i w_i (b_i . x) / sigma_i^2 (tall) or
 * sum_i b_i (w_i . x) / sigma_i^2 (wide). */
static int pinv_apply(int m, int c, const double *A, const double *x, double *out) {
    int wide = c > m;
    int rows = wide ? c : m, cols = wide ? m : c; /* B is rows x cols, column k stored at B[k*rows] */
    double B[NM * NM], W[NM * NM], norm2[NM];
    for (int k = 0; k < cols; k++) {
        for (int r = 0; r < rows; r++) B[k * rows + r] = wide ? A[k * c + r] : A[r * c + k];
        for (int r = 0; r < cols; r++) W[k * cols + r] = r == k ? 1.0 : 0.0;
    }
    for (int sweep = 0; sweep < 60; sweep++) {
        int rotated = 0;
        for (int p = 0; p < cols - 1; p++)
            for (int q = p + 1; q < cols; q++) {
                double *bp = B + p * rows, *bq = B + q * rows;
                double alpha = 0.0, beta = 0.0, gamma = 0.0;
                for (int r = 0; r < rows; r++) {
                    alpha += bp[r] * bp[r];
                    beta += bq[r] * bq[r];
                    gamma += bp[r] * bq[r];
                }
                if (alpha == 0.0 || beta == 0.0 || fabs(gamma) <= 1e-15 * sqrt(alpha * beta)) continue;
                rotated = 1;
                double zeta = (beta - alpha) / (2.0 * gamma);
                double t = (zeta >= 0.0 ? 1.0 : -1.0) / (fabs(zeta) + sqrt(1.0 + zeta * zeta));
                double cs = 1.0 / sqrt(1.0 + t * t), sn = cs * t;
                for (int r = 0; r < rows; r++) {
                    double u = bp[r], v = bq[r];
                    bp[r] = cs * u - sn * v;
                    bq[r] = sn * u + cs * v;
                }
                double *wp = W + p * cols, *wq = W + q * cols;
                for (int r = 0; r < cols; r++) {
                    double u = wp[r], v = wq[r];
                    wp[r] = cs * u - sn * v;
                    wq[r] = sn * u + cs * v;
                }
            }
        if (!rotated) break;
    }
    double smax2 = 0.0;
    for (int k = 0; k < cols; k++) {
        double s = 0.0;
        for (int r = 0; r < rows; r++) s += B[k * rows + r] * B[k * rows + r];
        norm2[k] = s;
        if (s > smax2) smax2 = s;
    }
    if (!isfinite(smax2)) return -1;
    double cut = SYMKIN_PINV_RCOND * sqrt(smax2);
    for (int j = 0; j < c; j++) out[j] = 0.0;
    for (int k = 0; k < cols; k++) {
        if (!(sqrt(norm2[k]) > cut)) continue;
        const double *bk = B + k * rows, *wk = W + k * cols;
        if (wide) {
            double s = 0.0;
            for (int r = 0; r < cols; r++) s += wk[r] * x[r];
            s /= norm2[k];
            for (int j = 0; j < c; j++) out[j] += bk[j] * s;
        } else {
            double s = 0.0;
            for (int r = 0; r < rows; r++) s += bk[r] * x[r];
            s /= norm2[k];
            for (int j = 0; j < c; j++) out[j] += wk[j] * s;
        }
    }
    return 0;
}

/* Solve A x = b for a symmetric positive definite A given by its lower triangle in transposed
 * rows, A_ij = At[j * NM + i] for i >= j; -1 when A is not positive definite. */
SYMKIN_INLINE int chol_solve(int n, const double *At, double *b) {
    double L[NM * NM];
    SYMKIN_UNROLL for (int j = 0; j < n; j++) {
        double d = At[j * NM + j];
        SYMKIN_UNROLL for (int k = 0; k < j; k++) d -= L[j * n + k] * L[j * n + k];
        if (!(d > 0.0)) return -1;
        double ljj = sqrt(d);
        L[j * n + j] = ljj;
        SYMKIN_UNROLL for (int i = j + 1; i < n; i++) {
            double s = At[j * NM + i];
            SYMKIN_UNROLL for (int k = 0; k < j; k++) s -= L[i * n + k] * L[j * n + k];
            L[i * n + j] = s / ljj;
        }
    }
    SYMKIN_UNROLL for (int i = 0; i < n; i++) {
        double s = b[i];
        SYMKIN_UNROLL for (int k = 0; k < i; k++) s -= L[i * n + k] * b[k];
        b[i] = s / L[i * n + i];
    }
    SYMKIN_UNROLL for (int i = n - 1; i >= 0; i--) {
        double s = b[i];
        SYMKIN_UNROLL for (int k = i + 1; k < n; k++) s -= L[k * n + i] * b[k];
        b[i] = s / L[i * n + i];
    }
    return 0;
}

/* ---- one step (eqs 45-51) ----------------------------------------------------------------- */
/* g = J^T We e and the lower triangle of A = J^T We J as transposed rows (see chol_solve):
 * g_i = sum_r J_ri (we_r e_r) and At[j * NM + i] = sum_r J_rj (we_r J_ri) for i >= j, each
 * summed over r in order from 0.0; we = NULL means We = I. */
#if defined(SYMKIN_VECTORS)
/* The vector of p[0 .. k-1] padded with zeros (k >= 1). Built in registers, not by memset and
 * memcpy into a stack array: reading such an array back as vectors stalls on store forwarding. */
SYMKIN_INLINE symkin_v4 load_padded(const double *p, int k) {
    symkin_v4 v;
    if (k >= SYMKIN_LANES) {
        memcpy(&v, p, sizeof v);
        return v;
    }
    v = (symkin_v4){p[0], k > 1 ? p[1] : 0.0, k > 2 ? p[2] : 0.0, 0.0};
    return v;
}

/* Vectorised over i (rows of A, and g): rank-one updates row by row of J, each entry still summed
 * over r in order from 0.0 with the same products, so the numbers are those of the scalar loops.
 * The whole row j of A is written to At[j * NM + 0 .. 4 NV - 1] (the entries i < j are unused). */
SYMKIN_INLINE void normal_equations(int n, const double *J, const double *e, const double *we, double *At,
                                    double *g) {
    const int nv = (n + SYMKIN_LANES - 1) / SYMKIN_LANES;
    symkin_v4 Jr[6][NV], Wr[6][NV], gv[NV];
    double ew[6];
    for (int r = 0; r < 6; r++) {
        SYMKIN_UNROLL for (int c = 0; c < nv; c++)
            Jr[r][c] = load_padded(J + r * n + SYMKIN_LANES * c, n - SYMKIN_LANES * c);
        ew[r] = we ? we[r] * e[r] : e[r];
        SYMKIN_UNROLL for (int c = 0; c < nv; c++) Wr[r][c] = we ? we[r] * Jr[r][c] : Jr[r][c];
    }
    SYMKIN_UNROLL for (int c = 0; c < nv; c++) {
        symkin_v4 s = {0.0};
        SYMKIN_UNROLL for (int r = 0; r < 6; r++) s += Jr[r][c] * ew[r];
        gv[c] = s;
    }
    memcpy(g, gv, sizeof(double) * (size_t)n);
    SYMKIN_UNROLL for (int j = 0; j < n; j++) {
        symkin_v4 row[NV];
        SYMKIN_UNROLL for (int c = 0; c < nv; c++) {
            symkin_v4 s = {0.0};
            SYMKIN_UNROLL for (int r = 0; r < 6; r++) s += J[r * n + j] * Wr[r][c];
            row[c] = s;
        }
        memcpy(At + j * NM, row, sizeof(symkin_v4) * (size_t)nv);
    }
}
#else
SYMKIN_INLINE void normal_equations(int n, const double *J, const double *e, const double *we, double *At,
                                    double *g) {
    double Jw[6 * NM], ew[6];
    if (we) {
        for (int r = 0; r < 6; r++) {
            ew[r] = we[r] * e[r];
            for (int i = 0; i < n; i++) Jw[r * n + i] = we[r] * J[r * n + i];
        }
        e = ew;
    }
    const double *W = we ? Jw : J;
    for (int i = 0; i < n; i++) {
        double s = 0.0;
        for (int r = 0; r < 6; r++) s += J[r * n + i] * e[r];
        g[i] = s;
    }
    for (int j = 0; j < n; j++)
        for (int i = j; i < n; i++) {
            double s = 0.0;
            for (int r = 0; r < 6; r++) s += J[r * n + j] * W[r * n + i];
            At[j * NM + i] = s;
        }
}
#endif

/* The full symmetric A (row-major n x n) from At. */
SYMKIN_INLINE void full_matrix(int n, const double *At, double *A) {
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) A[i * n + j] = i >= j ? At[j * NM + i] : At[i * NM + j];
}

/* LM (eqs 48-51): Cholesky of J^T We J + Wn, LU if it fails. */
SYMKIN_INLINE int lm_step(int n, const symkin_ik_config *c, const double *we, const double *J, const double *e,
                          double r2, double *dq) {
    double At[AT_SIZE], g[NM];
    normal_equations(n, J, e, we, At, g);
    double E = 0.5 * r2;
    SYMKIN_UNROLL for (int i = 0; i < n; i++) {
        double wn = c->damping == SYMKIN_DAMP_WAMPLER ? c->lam[i]
                    : c->damping == SYMKIN_DAMP_CHAN  ? c->lam[i] * E
                                                      : E + c->lam[i];
        At[i * NM + i] += wn;
    }
    memcpy(dq, g, sizeof(double) * (size_t)n);
    if (chol_solve(n, At, dq) == 0) return 0;
    double A[NM * NM];
    full_matrix(n, At, A);
    memcpy(dq, g, sizeof(double) * (size_t)n);
    return lu_solve(n, A, dq);
}

/* ---- pseudo-inverse steps without an SVD -------------------------------------------------- */
/* For a full-rank, well-conditioned J the pseudo-inverse steps of NR and GN are plain solves with
 * the Cholesky factor of a Gram matrix G (at most 6 x 6):
 *   n <= 6: pinv(Jw) ew = pinv(A) g = A^-1 g with A = J^T We J, g = J^T We e (G = A);
 *   n > 6:  pinv(Jw) ew = pinv(A) g = Jw^T (Jw Jw^T)^-1 ew (G = Jw Jw^T, 6 x 6),
 * Jw = We^1/2 J, ew = We^1/2 e. For an SPD m x m matrix G, max_i G_ii <= lambda_max <= m max_i G_ii
 * and max_i (G^-1)_ii <= 1 / lambda_min <= m max_i (G^-1)_ii, so kappa = max_i G_ii max_i (G^-1)_ii
 * lies between cond(G) / m^2 and cond(G). gram_solve takes the fast path only when
 * kappa <= SYMKIN_PINV_FAST_COND: then cond(G) <= 36e8, well below the 1e12 at which pinv of
 * J^T We J (GN) starts dropping directions, and cond(Jw) <= 6e4, far from NR's 1e12, so the step is
 * the pseudo-inverse's. Otherwise (singular or nearly so) the SVD of pinv_apply decides. */
#define SYMKIN_PINV_FAST_COND 1e8

/* b <- G^-1 b for the m x m SPD G (row-major, m <= 6) when kappa <= SYMKIN_PINV_FAST_COND (see above);
 * else -1 and b unchanged. X = L^-1 gives (G^-1)_ii = sum_k X_ki^2 and G^-1 b = X^T (X b); divisions
 * only for the reciprocals of the diagonal of L. Unrolled for m = 6 (gram_solve6). */
SYMKIN_INLINE int gram_solve_m(int m, const double *G, double *b) {
    double L[36], X[36], inv[6], y[6], gmax = 0.0, ginv = 0.0;
    SYMKIN_UNROLL for (int j = 0; j < m; j++) {
        double d = G[j * m + j];
        if (d > gmax) gmax = d; /* not fmax (a slow libm call, see the top); NaN: caught below */
        SYMKIN_UNROLL for (int k = 0; k < j; k++) d -= L[j * m + k] * L[j * m + k];
        if (!(d > 0.0)) return -1;
        double ljj = sqrt(d);
        L[j * m + j] = ljj;
        inv[j] = 1.0 / ljj;
        SYMKIN_UNROLL for (int i = j + 1; i < m; i++) {
            double s = G[i * m + j];
            SYMKIN_UNROLL for (int k = 0; k < j; k++) s -= L[i * m + k] * L[j * m + k];
            L[i * m + j] = s * inv[j];
        }
    }
    SYMKIN_UNROLL for (int i = 0; i < m; i++) {
        double x = inv[i], c = x * x;
        X[i * m + i] = x;
        SYMKIN_UNROLL for (int k = i + 1; k < m; k++) {
            double s = 0.0;
            SYMKIN_UNROLL for (int j = i; j < k; j++) s += L[k * m + j] * X[j * m + i];
            x = -s * inv[k];
            X[k * m + i] = x;
            c += x * x;
        }
        if (!(c <= ginv)) ginv = c; /* NaN propagates */
    }
    if (!(gmax * ginv <= SYMKIN_PINV_FAST_COND)) return -1;
    SYMKIN_UNROLL for (int k = 0; k < m; k++) {
        double s = 0.0;
        SYMKIN_UNROLL for (int i = 0; i <= k; i++) s += X[k * m + i] * b[i];
        y[k] = s;
    }
    SYMKIN_UNROLL for (int i = 0; i < m; i++) {
        double s = 0.0;
        SYMKIN_UNROLL for (int k = i; k < m; k++) s += X[k * m + i] * y[k];
        b[i] = s;
    }
    return 0;
}

static int gram_solve6(const double *G, double *b) { return gram_solve_m(6, G, b); }

static int gram_solve(int m, const double *G, double *b) {
    return m == 6 ? gram_solve6(G, b) : gram_solve_m(m, G, b);
}

/* NR and GN with pinv (eqs 45-47): gram_solve, or the SVD of pinv_apply when J is (nearly) singular:
 * of We^1/2 J (NR) or of J^T We J (GN), as numpy.linalg.pinv(rcond=SYMKIN_PINV_RCOND). */
SYMKIN_INLINE int pinv_step(int n, const symkin_ik_config *c, const double *we, const double *J, const double *e,
                            double *dq) {
    double At[AT_SIZE], g[NM], A[NM * NM], Jw[6 * NM], ew[6];
    if (n <= 6 || c->method == SYMKIN_IK_GN) {
        normal_equations(n, J, e, we, At, g);
        full_matrix(n, At, A);
    }
    if (n <= 6) {
        memcpy(dq, g, sizeof(double) * (size_t)n);
        if (gram_solve(n, A, dq) == 0) return 0;
    }
    for (int r = 0; r < 6; r++) {
        double s = sqrt(c->we[r]);
        ew[r] = s * e[r];
        for (int j = 0; j < n; j++) Jw[r * n + j] = s * J[r * n + j];
    }
    if (n > 6) {
        double G[36], y[6];
        SYMKIN_UNROLL for (int a = 0; a < 6; a++)
            SYMKIN_UNROLL for (int b = 0; b <= a; b++) G[a * 6 + b] = 0.0;
        for (int k = 0; k < n; k++)
            SYMKIN_UNROLL for (int a = 0; a < 6; a++)
                SYMKIN_UNROLL for (int b = 0; b <= a; b++) G[a * 6 + b] += Jw[a * n + k] * Jw[b * n + k];
        SYMKIN_UNROLL for (int a = 0; a < 6; a++)
            SYMKIN_UNROLL for (int b = a + 1; b < 6; b++) G[a * 6 + b] = G[b * 6 + a];
        memcpy(y, ew, sizeof y);
        if (gram_solve(6, G, y) == 0) {
            for (int j = 0; j < n; j++) {
                double s = 0.0;
                for (int r = 0; r < 6; r++) s += Jw[r * n + j] * y[r];
                dq[j] = s;
            }
            return 0;
        }
    }
    if (c->method == SYMKIN_IK_GN) return pinv_apply(n, n, A, g, dq);
    return pinv_apply(6, n, Jw, ew, dq);
}

/* NR and GN (eqs 45-47), and their pseudo-inverse variants; compiled for n = 6 and n = 7 as
 * constants besides any n, like the LM step. */
SYMKIN_INLINE int nr_gn_step(int n, const symkin_ik_config *c, const double *we, const double *J, const double *e,
                             double *dq) {
    if (c->pinv) return pinv_step(n, c, we, J, e, dq);
    if (c->method == SYMKIN_IK_NR) {
        double A[36];
        memcpy(A, J, sizeof(double) * 36);
        memcpy(dq, e, sizeof(double) * 6);
        return lu_solve(6, A, dq);
    }
    double At[AT_SIZE], g[NM], A[NM * NM];
    normal_equations(n, J, e, we, At, g);
    full_matrix(n, At, A);
    memcpy(dq, g, sizeof(double) * (size_t)n);
    return lu_solve(n, A, dq);
}

/* The step of eqs 45-51, with n = 6 and n = 7 as constants (their loops unrolled) besides any n, or the
 * caller's (SYMKIN_IK_QP). */
static int ik_step(const symkin_ik_config *c, const double *we, const double *q, const double *J, const double *e,
                   double r2, double *dq) {
    if (c->method == SYMKIN_IK_QP) return c->step(c->step_ctx, q, J, e, dq);
    if (c->method == SYMKIN_IK_LM) {
        if (c->n == 6) return lm_step(6, c, we, J, e, r2, dq);
        if (c->n == 7) return lm_step(7, c, we, J, e, r2, dq);
        return lm_step(c->n, c, we, J, e, r2, dq);
    }
    if (c->n == 6) return nr_gn_step(6, c, we, J, e, dq);
    if (c->n == 7) return nr_gn_step(7, c, we, J, e, dq);
    return nr_gn_step(c->n, c, we, J, e, dq);
}

/* The weights for the steps: NULL when We = I (multiplying by 1 changes nothing). */
static const double *step_weights(const symkin_ik_config *c) {
    for (int r = 0; r < 6; r++)
        if (c->we[r] != 1.0) return c->we;
    return 0;
}

static void kin_eval(const symkin_ik_config *c, const double *q, double *T, double *J) {
    if (c->fkjac)
        c->fkjac(q, T, J);
    else
        symkin_ets_fkjac(c->ets, q, T, J);
}

/* A revolute joint outside its limits moves by the multiple of 2 pi that brings it inside, if any. */
static void wrap_into_limits(const symkin_ik_config *c, double *q) {
    for (int j = 0; j < c->n; j++) {
        if (!c->revolute[j]) continue;
        double x = q[j];
        if (x < c->qlo[j])
            x += TWO_PI * ceil((c->qlo[j] - x) / TWO_PI);
        else if (x > c->qhi[j])
            x -= TWO_PI * ceil((x - c->qhi[j]) / TWO_PI);
        if (x >= c->qlo[j] && x <= c->qhi[j]) q[j] = x;
    }
}

static int within_limits(const symkin_ik_config *c, const double *q) {
    for (int j = 0; j < c->n; j++)
        if (!(q[j] >= c->qlo[j] && q[j] <= c->qhi[j])) return 0;
    return 1;
}

static double weighted_r2(const symkin_ik_config *c, const double *e) {
    double r2 = 0.0;
    for (int r = 0; r < 6; r++) r2 += c->we[r] * e[r] * e[r];
    return r2;
}

/* dst[0 .. m) = src[0 .. m), inline for the sizes of 6- and 7-joint arms (q, J): a call to memcpy
 * costs more than copying 6 or 7 doubles. */
SYMKIN_INLINE void copy_(double *dst, const double *src, int m) {
    switch (m) {
    case 6: __builtin_memcpy(dst, src, 6 * sizeof(double)); return;
    case 7: __builtin_memcpy(dst, src, 7 * sizeof(double)); return;
    case 36: __builtin_memcpy(dst, src, 36 * sizeof(double)); return;
    case 42: __builtin_memcpy(dst, src, 42 * sizeof(double)); return;
    default: memcpy(dst, src, sizeof(double) * (size_t)m);
    }
}

/* ---- the search loop ---------------------------------------------------------------------- */
/* One target's search as a state machine, so that a batch can run several side by side:
 * start_target, then repeatedly evaluate the kinematics at t->q and judge the result, taking a
 * step when asked to, until the target is done. */
typedef struct {
    const double *Tep, *q0;
    double *qout;
    symkin_ik_stats *st;
    uint64_t rng;
    int s, i; /* search and iteration within it */
    int have_best;
    double best;
    double q[NM], best_q[NM];
} ik_search;

enum { SEARCH_DONE, SEARCH_EVAL, SEARCH_STEP }; /* what a target needs next */

/* Start search t->s from q0, starts[s] or a random configuration. */
static void start_search(const symkin_ik_config *c, ik_search *t) {
    const int n = c->n;
    if (t->s == 0 && t->q0)
        copy_(t->q, t->q0, n);
    else if (t->s < c->nstarts)
        copy_(t->q, c->starts + (int64_t)t->s * n, n);
    else
        random_q(c, &t->rng, t->q);
    t->st->searches = t->s + 1;
    t->i = 0;
}

/* No search left: qout is the best iterate found. */
static int give_up(const symkin_ik_config *c, ik_search *t) {
    if (t->have_best) copy_(t->q, t->best_q, c->n);
    wrap_into_limits(c, t->q);
    copy_(t->qout, t->q, c->n);
    t->st->residual = t->best;
    return SEARCH_DONE;
}

/* The search t->s failed: start the next one, if any. */
static int next_search(const symkin_ik_config *c, ik_search *t) {
    t->s++;
    if (t->s >= c->slimit) return give_up(c, t);
    start_search(c, t);
    return SEARCH_EVAL;
}

static int start_target(const symkin_ik_config *c, ik_search *t, const double *Tep, const double *q0,
                        uint64_t rng, double *qout, symkin_ik_stats *st) {
    t->Tep = Tep;
    t->q0 = q0;
    t->qout = qout;
    t->st = st;
    t->rng = rng;
    t->have_best = 0;
    t->best = INFINITY;
    st->success = 0;
    st->iterations = 0;
    st->searches = 0;
    st->limit_rejects = 0;
    st->singular = 0;
    st->collision_rejects = 0;
    st->status = SYMKIN_POSE_OK;
    memset(t->q, 0, sizeof t->q);
    if (c->ilimit < 1) { /* searches that evaluate nothing */
        for (t->s = 0; t->s < c->slimit; t->s++) start_search(c, t);
        return give_up(c, t);
    }
    t->s = -1;
    return next_search(c, t);
}

/* Judge the pose T (with J) at t->q: SEARCH_STEP when a step is to be taken from there (e and *r2
 * set), SEARCH_EVAL when a new search starts, SEARCH_DONE when the target is solved or every
 * search failed. */
static int judge(const symkin_ik_config *c, ik_search *t, const double *T, double *e, double *r2) {
    symkin_ik_stats *st = t->st;
    symkin_pose_error(T, t->Tep, e);
    st->iterations++;
    double rr = weighted_r2(c, e);
    double res = sqrt(rr);
    if (!(res < INFINITY)) {
        st->singular++;
        return next_search(c, t);
    }
    if (res < t->best) {
        t->best = res;
        t->have_best = 1;
        copy_(t->best_q, t->q, c->n);
    }
    int converged = c->tol_on_E ? 0.5 * rr < c->tol : res < c->tol;
    if (converged) {
        wrap_into_limits(c, t->q);
        if (!c->joint_limits || within_limits(c, t->q)) {
            if (c->collides && c->collides(t->q, c->collision_env) != 0) {
                st->collision_rejects++;
                return next_search(c, t);
            }
            st->success = 1;
            st->residual = res;
            copy_(t->qout, t->q, c->n);
            return SEARCH_DONE;
        }
        st->limit_rejects++;
        return next_search(c, t);
    }
    if (t->i + 1 == c->ilimit) return next_search(c, t);
    *r2 = rr;
    return SEARCH_STEP;
}

/* Take the step dq, or abandon the search when the step failed. */
static int take_step(const symkin_ik_config *c, ik_search *t, const double *dq, int failed) {
    if (failed) {
        t->st->singular++;
        return next_search(c, t);
    }
    for (int j = 0; j < c->n; j++) t->q[j] += dq[j];
    t->i++;
    return SEARCH_EVAL;
}

static void solve_one(const symkin_ik_config *c, const double *Tep, const double *q0, uint64_t rng, double *qout,
                      symkin_ik_stats *st) {
    const double *we = step_weights(c);
    double T[16], J[6 * NM], e[6], dq[NM], r2;
    ik_search t;
    int state = start_target(c, &t, Tep, q0, rng, qout, st);
    while (state != SEARCH_DONE) {
        kin_eval(c, t.q, T, J);
        state = judge(c, &t, T, e, &r2);
        if (state == SEARCH_STEP) state = take_step(c, &t, dq, ik_step(c, we, t.q, J, e, r2, dq) != 0);
    }
}

#if defined(__GNUC__)
/* ---- batches: SYMKIN_LANES targets side by side ------------------------------------------ */
/* One LM step is a chain of dependent divisions and square roots (Cholesky, then two triangular
 * solves), so a batch runs SYMKIN_LANES targets at once and takes their steps together, one
 * target per vector lane: the chains overlap, and every lane does exactly the arithmetic of
 * lm_step, so each target gets the same iterates as when solved alone. */

/* x = sqrt(x) lane by lane (through a pointer: passing vectors by value warns without AVX) */
#if defined(__AVX__)
#include <immintrin.h>
static inline void v4_sqrt(symkin_v4 *x) { *x = (symkin_v4)_mm256_sqrt_pd((__m256d)*x); }
#else
static inline void v4_sqrt(symkin_v4 *x) {
    for (int l = 0; l < SYMKIN_LANES; l++) (*x)[l] = sqrt((*x)[l]);
}
#endif

/* lm_step for the lanes with need[l] (the others' J and e are zeroed); failed[l] when that lane's
 * step failed. */
SYMKIN_INLINE void lm_step_lanes(int n, const symkin_ik_config *c, const double *we, double J[][6 * NM],
                                 double e[][6], const double *r2, const int *need, double dq[][NM],
                                 int *failed) {
    symkin_v4 Jv[6][NM], Wv[6][NM], ev[6], g[NM], At[NM][NM], L[NM][NM], b[NM];
    double rr[SYMKIN_LANES];
    for (int l = 0; l < SYMKIN_LANES; l++) {
        rr[l] = need[l] ? r2[l] : 0.0;
        if (!need[l]) { /* an idle lane: harmless numbers */
            memset(J[l], 0, sizeof(double) * 6 * (size_t)n);
            memset(e[l], 0, sizeof(double) * 6);
        }
    }
    const symkin_v4 E = 0.5 * (symkin_v4){rr[0], rr[1], rr[2], rr[3]};
    SYMKIN_UNROLL for (int r = 0; r < 6; r++) {
        SYMKIN_UNROLL for (int i = 0; i < n; i++)
            Jv[r][i] = (symkin_v4){J[0][r * n + i], J[1][r * n + i], J[2][r * n + i], J[3][r * n + i]};
        ev[r] = (symkin_v4){e[0][r], e[1][r], e[2][r], e[3][r]};
        if (we) ev[r] *= we[r];
    }
    SYMKIN_UNROLL for (int r = 0; r < 6; r++)
        SYMKIN_UNROLL for (int i = 0; i < n; i++) Wv[r][i] = we ? Jv[r][i] * we[r] : Jv[r][i];
    SYMKIN_UNROLL for (int i = 0; i < n; i++) {
        symkin_v4 s = {0.0};
        SYMKIN_UNROLL for (int r = 0; r < 6; r++) s += Jv[r][i] * ev[r];
        g[i] = s;
    }
    SYMKIN_UNROLL for (int j = 0; j < n; j++)
        SYMKIN_UNROLL for (int i = j; i < n; i++) {
            symkin_v4 s = {0.0};
            SYMKIN_UNROLL for (int r = 0; r < 6; r++) s += Jv[r][j] * Wv[r][i];
            At[j][i] = s;
        }
    SYMKIN_UNROLL for (int i = 0; i < n; i++) {
        if (c->damping == SYMKIN_DAMP_WAMPLER)
            At[i][i] += c->lam[i];
        else if (c->damping == SYMKIN_DAMP_CHAN)
            At[i][i] += c->lam[i] * E;
        else
            At[i][i] += E + c->lam[i];
    }
    const symkin_v4 zero = {0.0};
    symkin_m4 notpd = {0}; /* lanes whose matrix is not positive definite */
    SYMKIN_UNROLL for (int j = 0; j < n; j++) {
        symkin_v4 d = At[j][j];
        SYMKIN_UNROLL for (int k = 0; k < j; k++) d -= L[j][k] * L[j][k];
        notpd |= ~(d > zero);
        symkin_v4 ljj = d;
        v4_sqrt(&ljj);
        L[j][j] = ljj;
        SYMKIN_UNROLL for (int i = j + 1; i < n; i++) {
            symkin_v4 s = At[j][i];
            SYMKIN_UNROLL for (int k = 0; k < j; k++) s -= L[i][k] * L[j][k];
            L[i][j] = s / ljj;
        }
    }
    SYMKIN_UNROLL for (int i = 0; i < n; i++) {
        symkin_v4 s = g[i];
        SYMKIN_UNROLL for (int k = 0; k < i; k++) s -= L[i][k] * b[k];
        b[i] = s / L[i][i];
    }
    SYMKIN_UNROLL for (int i = n - 1; i >= 0; i--) {
        symkin_v4 s = b[i];
        SYMKIN_UNROLL for (int k = i + 1; k < n; k++) s -= L[k][i] * b[k];
        b[i] = s / L[i][i];
    }
    for (int l = 0; l < SYMKIN_LANES; l++) {
        failed[l] = notpd[l] != 0;
        if (!need[l]) continue;
        if (!failed[l]) {
            for (int i = 0; i < n; i++) dq[l][i] = b[i][l];
            continue;
        }
        double A[NM * NM]; /* Cholesky failed: LU on the full matrix, as lm_step does */
        for (int i = 0; i < n; i++) {
            dq[l][i] = g[i][l];
            for (int j = 0; j < n; j++) A[i * n + j] = i >= j ? At[j][i][l] : At[i][j][l];
        }
        failed[l] = lu_solve(n, A, dq[l]) != 0;
    }
}

/* T and J of the lanes that evaluate (state SEARCH_EVAL) by one fkjac_batch call over
 * SYMKIN_LANES configurations: the generated four-lane code gives each lane the numbers of fkjac,
 * so every target keeps its iterates. */
static void eval_lanes(const symkin_ik_config *c, const ik_search *t, const int *state,
                       double T[][16], double J[][6 * NM]) {
    const int n = c->n;
    double Q[SYMKIN_LANES * NM], Jb[SYMKIN_LANES * 6 * NM];
    int busy = 0;
    while (state[busy] != SEARCH_EVAL) busy++;
    for (int l = 0; l < SYMKIN_LANES; l++)
        copy_(Q + l * n, t[state[l] == SEARCH_EVAL ? l : busy].q, n);
    c->fkjac_batch(Q, &T[0][0], Jb, SYMKIN_LANES);
    for (int l = 0; l < SYMKIN_LANES; l++)
        if (state[l] == SEARCH_EVAL) copy_(J[l], Jb + l * 6 * n, 6 * n);
}

/* symkin_ik_solve_batch on SYMKIN_LANES targets side by side (the targets' poses are valid): the
 * lanes' FK and J by one fkjac_batch call when the kinematics have one, the steps of LM with 6 or 7
 * joints by lm_step_lanes, other steps (NR, GN, other joint counts) lane by lane by ik_step. */
static void solve_batch_lanes(const symkin_ik_config *c, int64_t N, const double *Tep, const double *q0,
                           int64_t q0_stride, uint64_t seed, double *q, symkin_ik_stats *st) {
    const double *we = step_weights(c);
    ik_search t[SYMKIN_LANES];
    int state[SYMKIN_LANES], need[SYMKIN_LANES], failed[SYMKIN_LANES];
    double T[SYMKIN_LANES][16], J[SYMKIN_LANES][6 * NM], e[SYMKIN_LANES][6], r2[SYMKIN_LANES];
    double dq[SYMKIN_LANES][NM];
    int64_t next = 0;
    for (int l = 0; l < SYMKIN_LANES; l++) state[l] = SEARCH_DONE;
    for (;;) {
        int busy = 0, steps = 0;
        for (int l = 0; l < SYMKIN_LANES; l++) {
            while (state[l] == SEARCH_DONE && next < N) {
                state[l] = start_target(c, &t[l], Tep + 16 * next, q0 ? q0 + q0_stride * next : 0,
                                        stream_state(seed, (uint64_t)next), q + (int64_t)c->n * next, st + next);
                next++;
            }
            busy |= state[l] == SEARCH_EVAL;
        }
        if (!busy) return;
        if (c->fkjac_batch) /* the lanes' poses in one call (idle lanes repeat a busy one) */
            eval_lanes(c, t, state, T, J);
        for (int l = 0; l < SYMKIN_LANES; l++) {
            need[l] = 0;
            if (state[l] != SEARCH_EVAL) continue;
            if (!c->fkjac_batch) kin_eval(c, t[l].q, T[l], J[l]);
            state[l] = judge(c, &t[l], T[l], e[l], &r2[l]);
            need[l] = state[l] == SEARCH_STEP;
            steps |= need[l];
        }
        if (!steps) continue;
        if (c->method == SYMKIN_IK_LM && c->n == 6) /* n as a constant, as in ik_step */
            lm_step_lanes(6, c, we, J, e, r2, need, dq, failed);
        else if (c->method == SYMKIN_IK_LM && c->n == 7)
            lm_step_lanes(7, c, we, J, e, r2, need, dq, failed);
        else
            for (int l = 0; l < SYMKIN_LANES; l++)
                if (need[l]) failed[l] = ik_step(c, we, t[l].q, J[l], e[l], r2[l], dq[l]) != 0;
        for (int l = 0; l < SYMKIN_LANES; l++)
            if (need[l]) state[l] = take_step(c, &t[l], dq[l], failed[l]);
    }
}
#endif

int32_t symkin_ik_solve(const symkin_ik_config *cfg, const double *Tep, const double *q0, uint64_t seed, double *q,
                        symkin_ik_stats *st) {
    int32_t status = symkin_ik_check_pose(Tep, 0);
    if (status == SYMKIN_POSE_OK && q0)
        for (int j = 0; j < cfg->n; j++)
            if (!isfinite(q0[j])) status = SYMKIN_Q0_NONFINITE;
    if (status != SYMKIN_POSE_OK) {
        st->status = status;
        return status;
    }
    solve_one(cfg, Tep, q0, stream_state(seed, 0), q, st);
    return SYMKIN_POSE_OK;
}

int64_t symkin_ik_solve_batch(const symkin_ik_config *cfg, int64_t N, const double *Tep, const double *q0,
                              int64_t q0_stride, uint64_t seed, double *q, symkin_ik_stats *st) {
    for (int64_t i = 0; i < N; i++) {
        int32_t status = symkin_ik_check_pose(Tep + 16 * i, 0);
        if (status != SYMKIN_POSE_OK) {
            st[i].status = status;
            return i;
        }
    }
#if defined(__GNUC__)
    if (cfg->fkjac_batch || (cfg->method == SYMKIN_IK_LM && (cfg->n == 6 || cfg->n == 7))) {
        solve_batch_lanes(cfg, N, Tep, q0, q0_stride, seed, q, st);
        return -1;
    }
#endif
    for (int64_t i = 0; i < N; i++)
        solve_one(cfg, Tep + 16 * i, q0 ? q0 + q0_stride * i : 0, stream_state(seed, (uint64_t)i),
                  q + (int64_t)cfg->n * i, st + i);
    return -1;
}

int64_t symkin_ik_solve_each(const symkin_ik_config *cfg, int64_t N, const double *Tep, const double *q0,
                             int64_t q0_stride, uint64_t seed, double *q, symkin_ik_stats *st) {
    for (int64_t i = 0; i < N; i++) {
        int32_t status = symkin_ik_solve(cfg, Tep + 16 * i, q0 ? q0 + q0_stride * i : 0,
                                         seed + (uint64_t)i, q + (int64_t)cfg->n * i, st + i);
        if (status != SYMKIN_POSE_OK) return i;
    }
    return -1;
}

void symkin_ik_kin_each(const symkin_ik_config *cfg, int64_t N, const double *q, double *T, double *J) {
    for (int64_t i = 0; i < N; i++) kin_eval(cfg, q + (int64_t)cfg->n * i, T, J);
}

int32_t symkin_ik_trace(const symkin_ik_config *cfg, const double *Tep, const double *q0, int32_t steps, double *qs) {
    const int n = cfg->n;
    const double *we = step_weights(cfg);
    double q[NM], dq[NM], T[16], J[6 * NM], e[6];
    memcpy(q, q0, sizeof(double) * (size_t)n);
    memcpy(qs, q, sizeof(double) * (size_t)n);
    for (int32_t k = 0; k < steps; k++) {
        kin_eval(cfg, q, T, J);
        symkin_pose_error(T, Tep, e);
        double r2 = weighted_r2(cfg, e);
        if (!isfinite(r2) || ik_step(cfg, we, q, J, e, r2, dq) != 0) return k + 1;
        for (int j = 0; j < n; j++) q[j] += dq[j];
        memcpy(qs + (int64_t)(k + 1) * n, q, sizeof(double) * (size_t)n);
    }
    return steps + 1;
}
