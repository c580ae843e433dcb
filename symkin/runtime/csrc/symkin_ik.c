/* symkin numerical inverse kinematics in C: see symkin_ik.h and symkin/runtime/ik.py.
 *
 * Linear algebra for n <= SYMKIN_IK_NMAX on stack arrays:
 * - NR (eq 45): LU with partial pivoting of the square J (n = 6);
 * - GN (eqs 46-47): LU of J^T We J;
 * - LM (eqs 48-51): Cholesky of J^T We J + Wn (positive definite), LU if Cholesky fails;
 * - pseudo-inverse (NR and GN with pinv): one-sided Jacobi SVD (Hestenes) of the matrix, or of its
 *   transpose when it is wide, so it works for any n (6x7 J of a redundant arm, 6x5 J of a 5-DoF
 *   arm, the n x n J^T We J); singular values <= SYMKIN_PINV_RCOND * the largest are dropped,
 *   like numpy.linalg.pinv(rcond=SYMKIN_PINV_RCOND). NR with pinv uses pinv(We^1/2 J) We^1/2 e,
 *   which is J^-1 e for a square invertible J.
 * Compile with -ffp-contract=off so the arithmetic rounds like NumPy's.
 */
#include "symkin_ik.h"

#include <math.h>
#include <string.h>

#define NM SYMKIN_IK_NMAX
#define SYMKIN_PINV_RCOND 1e-12
#define SYMKIN_NEAR_PI_L 1e-6
#define SYMKIN_POSE_ATOL 1e-6
#define SYMKIN_BOTTOM_ATOL 1e-12

static const double TWO_PI = 6.283185307179586;
static const double HALF_PI = 1.5707963267948966;

int32_t symkin_ik_nmax(void) { return NM; }
int32_t symkin_ik_stats_size(void) { return (int32_t)sizeof(symkin_ik_stats); }
int32_t symkin_ik_config_size(void) { return (int32_t)sizeof(symkin_ik_config); }

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
int32_t symkin_ik_check_pose(const double *T, double *deviation) {
    if (deviation) *deviation = 0.0;
    for (int i = 0; i < 16; i++)
        if (!isfinite(T[i])) return SYMKIN_POSE_NONFINITE;
    if (fabs(T[12]) > SYMKIN_BOTTOM_ATOL || fabs(T[13]) > SYMKIN_BOTTOM_ATOL || fabs(T[14]) > SYMKIN_BOTTOM_ATOL ||
        fabs(T[15] - 1.0) > SYMKIN_BOTTOM_ATOL)
        return SYMKIN_POSE_BOTTOM_ROW;
    double dev = 0.0;
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) {
            double s = T[a] * T[b] + T[4 + a] * T[4 + b] + T[8 + a] * T[8 + b];
            double d = fabs(s - (a == b ? 1.0 : 0.0));
            if (d > dev) dev = d;
        }
    if (deviation) *deviation = dev;
    if (!(dev <= SYMKIN_POSE_ATOL)) return SYMKIN_POSE_NOT_ORTHONORMAL;
    double det = T[0] * (T[5] * T[10] - T[6] * T[9]) - T[1] * (T[4] * T[10] - T[6] * T[8]) +
                 T[2] * (T[4] * T[9] - T[5] * T[8]);
    if (!(det > 0.0)) return SYMKIN_POSE_REFLECTION;
    return SYMKIN_POSE_OK;
}

/* alpha(R) of eqs 38-40, R row-major 3x3. */
static void angle_axis(const double *R, double *a) {
    double tr = R[0] + R[4] + R[8];
    if (R[1] == 0.0 && R[2] == 0.0 && R[3] == 0.0 && R[5] == 0.0 && R[6] == 0.0 && R[7] == 0.0) {
        if (tr > 0.0) { /* (1 1 1) */
            a[0] = a[1] = a[2] = 0.0;
        } else { /* eq 40 */
            a[0] = HALF_PI * (R[0] + 1.0);
            a[1] = HALF_PI * (R[4] + 1.0);
            a[2] = HALF_PI * (R[8] + 1.0);
        }
        return;
    }
    double l0 = R[7] - R[5], l1 = R[2] - R[6], l2 = R[3] - R[1];
    double nl = sqrt(l0 * l0 + l1 * l1 + l2 * l2);
    if (tr >= 0.0 || nl >= SYMKIN_NEAR_PI_L) { /* eq 38 */
        if (nl == 0.0) {
            a[0] = a[1] = a[2] = 0.0;
            return;
        }
        double k = atan2(nl, tr - 1.0) / nl;
        a[0] = k * l0;
        a[1] = k * l1;
        a[2] = k * l2;
        return;
    }
    /* near pi and not diagonal: l is rounding noise; the axis comes from the symmetric part,
     * a a^T = ((R + R^T) / 2 - cos(theta) I) / (1 - cos(theta)), its sign from l. */
    double theta = atan2(nl, tr - 1.0);
    double ct = (tr - 1.0) / 2.0;
    double M[9];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) M[3 * i + j] = ((R[3 * i + j] + R[3 * j + i]) / 2.0 - (i == j ? ct : 0.0)) / (1.0 - ct);
    int k = 0;
    if (M[4] > M[0]) k = 1;
    if (M[8] > M[3 * k + k]) k = 2;
    double ak = sqrt(M[3 * k + k] > 0.0 ? M[3 * k + k] : 0.0);
    double ax[3];
    for (int j = 0; j < 3; j++) ax[j] = j == k ? ak : M[3 * j + k] / ak;
    if (ax[0] * l0 + ax[1] * l1 + ax[2] * l2 < 0.0) {
        ax[0] = -ax[0];
        ax[1] = -ax[1];
        ax[2] = -ax[2];
    }
    a[0] = theta * ax[0];
    a[1] = theta * ax[1];
    a[2] = theta * ax[2];
}

void symkin_ik_pose_error(const double *T, const double *Tep, double *e) {
    e[0] = Tep[3] - T[3];
    e[1] = Tep[7] - T[7];
    e[2] = Tep[11] - T[11];
    double R[9]; /* Tep_R T_R^T */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            R[3 * i + j] = Tep[4 * i] * T[4 * j] + Tep[4 * i + 1] * T[4 * j + 1] + Tep[4 * i + 2] * T[4 * j + 2];
    angle_axis(R, e + 3);
}

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

static int chol_solve(int n, const double *A, double *b) {
    double L[NM * NM];
    for (int j = 0; j < n; j++) {
        double d = A[j * n + j];
        for (int k = 0; k < j; k++) d -= L[j * n + k] * L[j * n + k];
        if (!(d > 0.0)) return -1;
        double ljj = sqrt(d);
        L[j * n + j] = ljj;
        for (int i = j + 1; i < n; i++) {
            double s = A[i * n + j];
            for (int k = 0; k < j; k++) s -= L[i * n + k] * L[j * n + k];
            L[i * n + j] = s / ljj;
        }
    }
    for (int i = 0; i < n; i++) {
        double s = b[i];
        for (int k = 0; k < i; k++) s -= L[i * n + k] * b[k];
        b[i] = s / L[i * n + i];
    }
    for (int i = n - 1; i >= 0; i--) {
        double s = b[i];
        for (int k = i + 1; k < n; k++) s -= L[k * n + i] * b[k];
        b[i] = s / L[i * n + i];
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

/* ---- one step (eqs 45-51) ----------------------------------------------------------------- */
static int ik_step(const symkin_ik_config *c, const double *J, const double *e, double r2, double *dq) {
    int n = c->n;
    if (c->method == SYMKIN_IK_NR) {
        if (c->pinv) {
            double Jw[6 * NM], ew[6];
            for (int r = 0; r < 6; r++) {
                double s = sqrt(c->we[r]);
                ew[r] = s * e[r];
                for (int j = 0; j < n; j++) Jw[r * n + j] = s * J[r * n + j];
            }
            return pinv_apply(6, n, Jw, ew, dq);
        }
        double A[36];
        memcpy(A, J, sizeof(double) * 36);
        memcpy(dq, e, sizeof(double) * 6);
        return lu_solve(6, A, dq);
    }
    double A[NM * NM];
    for (int i = 0; i < n; i++) {
        double g = 0.0;
        for (int r = 0; r < 6; r++) g += J[r * n + i] * (c->we[r] * e[r]);
        dq[i] = g;
        for (int j = i; j < n; j++) {
            double s = 0.0;
            for (int r = 0; r < 6; r++) s += J[r * n + i] * (c->we[r] * J[r * n + j]);
            A[i * n + j] = A[j * n + i] = s;
        }
    }
    if (c->method == SYMKIN_IK_GN) {
        if (c->pinv) {
            double g[NM];
            memcpy(g, dq, sizeof(double) * (size_t)n);
            return pinv_apply(n, n, A, g, dq);
        }
        return lu_solve(n, A, dq);
    }
    double E = 0.5 * r2;
    for (int i = 0; i < n; i++) {
        double wn = c->damping == SYMKIN_DAMP_WAMPLER ? c->lam[i]
                    : c->damping == SYMKIN_DAMP_CHAN  ? c->lam[i] * E
                                                      : E + c->lam[i];
        A[i * n + i] += wn;
    }
    double g[NM];
    memcpy(g, dq, sizeof(double) * (size_t)n);
    if (chol_solve(n, A, dq) == 0) return 0;
    memcpy(dq, g, sizeof(double) * (size_t)n);
    return lu_solve(n, A, dq);
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

/* ---- the search loop ---------------------------------------------------------------------- */
static void solve_one(const symkin_ik_config *c, const double *Tep, const double *q0, uint64_t rng, double *qout,
                      symkin_ik_stats *st) {
    int n = c->n;
    double q[NM], dq[NM], best_q[NM], T[16], J[6 * NM], e[6];
    double best = INFINITY;
    int have_best = 0;
    st->success = 0;
    st->iterations = 0;
    st->searches = 0;
    st->limit_rejects = 0;
    st->singular = 0;
    st->status = SYMKIN_POSE_OK;
    for (int s = 0; s < c->slimit; s++) {
        if (s == 0 && q0)
            memcpy(q, q0, sizeof(double) * (size_t)n);
        else if (s < c->nstarts)
            memcpy(q, c->starts + (int64_t)s * n, sizeof(double) * (size_t)n);
        else
            random_q(c, &rng, q);
        st->searches = s + 1;
        for (int i = 0; i < c->ilimit; i++) {
            kin_eval(c, q, T, J);
            symkin_ik_pose_error(T, Tep, e);
            st->iterations++;
            double r2 = weighted_r2(c, e);
            double res = sqrt(r2);
            if (!(res < INFINITY)) {
                st->singular++;
                break;
            }
            if (res < best) {
                best = res;
                have_best = 1;
                memcpy(best_q, q, sizeof(double) * (size_t)n);
            }
            int converged = c->tol_on_E ? 0.5 * r2 < c->tol : res < c->tol;
            if (converged) {
                wrap_into_limits(c, q);
                if (!c->joint_limits || within_limits(c, q)) {
                    st->success = 1;
                    st->residual = res;
                    memcpy(qout, q, sizeof(double) * (size_t)n);
                    return;
                }
                st->limit_rejects++;
                break;
            }
            if (i + 1 == c->ilimit) break;
            if (ik_step(c, J, e, r2, dq) != 0) {
                st->singular++;
                break;
            }
            for (int j = 0; j < n; j++) q[j] += dq[j];
        }
    }
    if (have_best) memcpy(q, best_q, sizeof(double) * (size_t)n);
    wrap_into_limits(c, q);
    memcpy(qout, q, sizeof(double) * (size_t)n);
    st->residual = best;
}

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
    for (int64_t i = 0; i < N; i++)
        solve_one(cfg, Tep + 16 * i, q0 ? q0 + q0_stride * i : 0, stream_state(seed, (uint64_t)i),
                  q + (int64_t)cfg->n * i, st + i);
    return -1;
}

int32_t symkin_ik_trace(const symkin_ik_config *cfg, const double *Tep, const double *q0, int32_t steps, double *qs) {
    int n = cfg->n;
    double q[NM], dq[NM], T[16], J[6 * NM], e[6];
    memcpy(q, q0, sizeof(double) * (size_t)n);
    memcpy(qs, q, sizeof(double) * (size_t)n);
    for (int32_t k = 0; k < steps; k++) {
        kin_eval(cfg, q, T, J);
        symkin_ik_pose_error(T, Tep, e);
        double r2 = weighted_r2(cfg, e);
        if (!isfinite(r2) || ik_step(cfg, J, e, r2, dq) != 0) return k + 1;
        for (int j = 0; j < n; j++) q[j] += dq[j];
        memcpy(qs + (int64_t)(k + 1) * n, q, sizeof(double) * (size_t)n);
    }
    return steps + 1;
}
