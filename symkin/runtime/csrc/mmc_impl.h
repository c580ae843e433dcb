/*
 * mmc_impl.h: one step of the Manipulability Motion Controller in C (see mmc.h), included once
 * per QP variant by a file that defines MMC_NS (0, or 6 with the equality slack), MMC_SOLVER (that
 * variant's embedded OSQP solver) and MMC_FN(name) (its exported names) and includes its workspace.
 *
 * Mirrors symkin.runtime.control.MMC.step: J, H (generated), the singularity test, Jm (MMC paper
 * eq 11), the bounds (joint_velocity_bounds), the closed form J+ nu + (I - J+ J) Jm / lam when it
 * lies within them, else the active-set solve from the bounds it crosses, else the QP (eq 12) on
 * the embedded OSQP, then the same fallbacks (the RRMC step scaled into the bounds). OSQP's
 * polishing is not part of its embedded code; when OSQP reports "solved", the active-set solve
 * started from OSQP's active set replaces its answer when it verifies. With MMC_ND (the distance
 * variant) the QP has ND more rows, the velocity dampers of the closest pairs of the robot's
 * geometry (MMC._distance_rows); when any pair lies within its d_i, the active-set solve that
 * knows the rows (from the last step's set, then from the closed form's bounds) comes first, else
 * OSQP polished by the same solve.
 */
#include <math.h>
#include <string.h>

#include "mmc.h"
#include "osqp.h"
/* OSQP's private types (emitted with it): the iterate saved and restored per controller */
#include "algebra_impl.h"
#include "types.h"

#ifndef MMC_ND
#define MMC_ND 0 /* collision rows (the distance variant: MMC_K) */
#endif
#define N MMC_N
#define NS MMC_NS
#define ND MMC_ND
#define NX (MMC_N + MMC_NS)         /* QP variables: qd (and the slack s) */
#define NC (6 + MMC_N + MMC_ND)     /* QP rows: J qd (+ s) = nu, lower <= qd <= upper, Jd qd >= dl */
#define NNZ_A ((7 + ND) * N + NS)   /* CSC of [[J, I6], [I_n, 0], [Jd, 0]]: per qd column 6 J entries,
                                       a 1 and ND distance rows (dense) */

static const symkin_mmc_ctrl *owner_ = 0; /* the controller whose iterate the solver holds */

/* fmin and fmax (a NaN argument loses) without calling libm: between AVX code such a call cost
   about 0.3 us on the development machine (SSE/AVX transitions) */
static inline double fmin_(double a, double b)
{
    return (b < a || a != a) ? b : a;
}

static inline double fmax_(double a, double b)
{
    return (b > a || a != a) ? b : a;
}

/* Cholesky factor L (lower, row-major r x r) of G + shift I; 1 on success. */
static int chol_(const double *G, int r, double shift, double *L)
{
    for (int i = 0; i < r; ++i) {
        for (int j = 0; j <= i; ++j) {
            double s = G[i * r + j] + (i == j ? shift : 0.0);
            for (int k = 0; k < j; ++k)
                s -= L[i * r + k] * L[j * r + k];
            if (i == j) {
                if (!(s > 0.0))
                    return 0;
                L[i * r + i] = sqrt(s);
            } else {
                L[i * r + j] = s / L[j * r + j];
            }
        }
        for (int j = i + 1; j < r; ++j)
            L[i * r + j] = 0.0;
    }
    return 1;
}

/* b <- (L L^T)^-1 b */
static void chol_solve_(const double *L, int r, double *b)
{
    for (int i = 0; i < r; ++i) {
        double s = b[i];
        for (int k = 0; k < i; ++k)
            s -= L[i * r + k] * b[k];
        b[i] = s / L[i * r + i];
    }
    for (int i = r - 1; i >= 0; --i) {
        double s = b[i];
        for (int k = i + 1; k < r; ++k)
            s -= L[k * r + i] * b[k];
        b[i] = s / L[i * r + i];
    }
}

/* G = Jr Jr^T over rows r0 .. r0 + r - 1 of J (6, N) */
static void gram_(const double *J, int r0, int r, double *G)
{
    for (int i = 0; i < r; ++i)
        for (int j = 0; j <= i; ++j) {
            double s = 0.0;
            for (int k = 0; k < N; ++k)
                s += J[(r0 + i) * N + k] * J[(r0 + j) * N + k];
            G[i * r + j] = G[j * r + i] = s;
        }
}

/* B = (L L^T)^-1 Jr, (r, N) */
static void solve_rows_(const double *L, int r, const double *J, int r0, double *B)
{
    for (int k = 0; k < N; ++k) {
        double b[6];
        for (int i = 0; i < r; ++i)
            b[i] = J[(r0 + i) * N + k];
        chol_solve_(L, r, b);
        for (int i = 0; i < r; ++i)
            B[i * N + k] = b[i];
    }
}

/* Jm_i = m sum_{row, k} H_i[r0 + row][k] B[row][k] (eq 11) */
static void jacobm_(const double *H, const double *B, int r0, int r, double m, double *Jm)
{
    for (int i = 0; i < N; ++i) {
        double s = 0.0;
        for (int row = 0; row < r; ++row)
            for (int k = 0; k < N; ++k)
                s += H[(i * 6 + r0 + row) * N + k] * B[row * N + k];
        Jm[i] = m * s;
    }
}

/* determinant of a 6x6 (or smaller) matrix by LU with partial pivoting */
static double det_(const double *G, int r)
{
    double A[36], d = 1.0;
    memcpy(A, G, sizeof(double) * (size_t)(r * r));
    for (int j = 0; j < r; ++j) {
        int p = j;
        for (int i = j + 1; i < r; ++i)
            if (fabs(A[i * r + j]) > fabs(A[p * r + j]))
                p = i;
        if (A[p * r + j] == 0.0)
            return 0.0;
        if (p != j) {
            for (int k = 0; k < r; ++k) {
                double t = A[j * r + k];
                A[j * r + k] = A[p * r + k];
                A[p * r + k] = t;
            }
            d = -d;
        }
        d *= A[j * r + j];
        for (int i = j + 1; i < r; ++i) {
            double f = A[i * r + j] / A[j * r + j];
            for (int k = j + 1; k < r; ++k)
                A[i * r + k] -= f * A[j * r + k];
        }
    }
    return d;
}

/* the slack s = nu - J qd of the equality (NS values: none without the slack) */
static void slack_of_(const double *J, const double *nu, const double *qd, double *s)
{
    for (int i = 0; i < NS; ++i) {
        double v = nu[i];
        for (int k = 0; k < N; ++k)
            v -= J[i * N + k] * qd[k];
        s[i] = v;
    }
}

static double residual_(const double *J, const double *qd, const double *nu)
{
    double res = 0.0;
    for (int i = 0; i < 6; ++i) {
        double s = -nu[i];
        for (int k = 0; k < N; ++k)
            s += J[i * N + k] * qd[k];
        res = fmax_(res, fabs(s));
    }
    return res;
}

/* out = A^T y for A (6, N) row-major, y (6) */
static void tmul_(const double *A, const double *y, double *out)
{
    for (int k = 0; k < N; ++k) {
        double s = 0.0;
        for (int i = 0; i < 6; ++i)
            s += A[i * N + k] * y[i];
        out[k] = s;
    }
}

/* joint_velocity_bounds of control.py */
static void bounds_(const symkin_mmc_ctrl *c, const double *q, double *lo, double *hi)
{
    for (int i = 0; i < N; ++i) {
        double a = c->qd_max[i], l = -a, u = a;
        if (c->joint_limits) {
            double width = c->rho_i[i] - c->rho_s[i];
            double d_hi = c->qhi[i] - q[i], d_lo = q[i] - c->qlo[i];
            if (d_hi < c->rho_i[i])
                u = fmin_(u, c->xi * (d_hi - c->rho_s[i]) / width);
            if (d_lo < c->rho_i[i])
                l = fmax_(l, -c->xi * (d_lo - c->rho_s[i]) / width);
            if (c->has_dt) { /* the dampers only tighten the step bound (a push-back too) */
                const double lo_dt = -(d_lo - c->rho_s[i]) / c->dt, hi_dt = (d_hi - c->rho_s[i]) / c->dt;
                u = fmin_(fmax_(u, lo_dt), hi_dt);
                l = fmin_(fmax_(l, lo_dt), hi_dt);
            }
            u = fmax_(u, -a);
            l = fmin_(l, a);
            if (l > u)
                l = u = 0.5 * (l + u);
        }
        lo[i] = l;
        hi[i] = u;
    }
}

static void write_info_(double *out, int status, int method, double m, int iters, int fallback,
                        double residual, double slack, double scale, int polished)
{
    double *info = out + N;
    info[0] = status;
    info[1] = method;
    info[2] = m;
    info[3] = iters;
    info[4] = fallback;
    info[5] = residual;
    info[6] = slack;
    info[7] = scale;
    info[8] = polished;
}

/* an active-set solution x (NX) as the step's answer: qd clipped into the bounds, the info */
static void active_set_answer_(double *out, const double *J, const double *nu, const double *lo,
                               const double *hi, const double *x, double m, int its)
{
    double slack = 0.0, *qd = out;
    for (int k = 0; k < N; ++k)
        qd[k] = fmin_(fmax_(x[k], lo[k]), hi[k]);
    for (int i = N; i < NX; ++i)
        slack += x[i] * x[i];
    write_info_(out, MMC_SOLVED, MMC_ACTIVE_SET, m, its, MMC_NO_FALLBACK, residual_(J, qd, nu), sqrt(slack),
                1.0, 0);
}

/* MMC._fallback: the RRMC step (inverse/pinv, or damped when singular) scaled into the bounds */
static void fallback_(const symkin_mmc_ctrl *c, const double *J, const double *G, const double *B,
                      int have_b, const double *nu, const double *lo, const double *hi, double *qd,
                      int *kind, double *scale)
{
    if (have_b) {
        tmul_(B, nu, qd);
    } else { /* J^T (J J^T + d^2 I)^-1 nu, the damped least-squares step */
        double L[36], y[6];
        if (chol_(G, 6, c->damping * c->damping, L)) {
            memcpy(y, nu, sizeof y);
            chol_solve_(L, 6, y);
        } else {
            for (int i = 0; i < 6; ++i)
                y[i] = NAN;
        }
        tmul_(J, y, qd);
    }
    *kind = MMC_FALLBACK_RRMC;
    for (int k = 0; k < N; ++k)
        if (!isfinite(qd[k])) {
            memset(qd, 0, sizeof(double) * N);
            *kind = MMC_FALLBACK_ZERO;
            break;
        }
    *scale = 1.0;
    int contains_zero = 1;
    for (int k = 0; k < N; ++k)
        if (!(lo[k] <= 0.0 && hi[k] >= 0.0))
            contains_zero = 0;
    if (contains_zero) {
        double s = 1.0;
        for (int k = 0; k < N; ++k) {
            double r = 1.0;
            if (qd[k] > hi[k])
                r = hi[k] / qd[k];
            else if (qd[k] < lo[k])
                r = lo[k] / qd[k];
            s = fmin_(s, r);
        }
        s = fmax_(s, 0.0);
        for (int k = 0; k < N; ++k)
            qd[k] *= s;
        *scale = s;
    }
    for (int k = 0; k < N; ++k)
        qd[k] = fmin_(fmax_(qd[k], lo[k]), hi[k]);
}

/*
 * Active-set solve of the QP's optimality conditions: with the bounds of `act` (-1 lower, 1 upper,
 * 2 fixed, 0 free) as equalities, min 0.5 lam |qd|^2 (+ 0.5 w |s|^2) - Jm.qd s.t. J qd (+ s) = nu
 * has the multiplier ye = M^-1 (J_F Jm_F / lam - r), M = J_F J_F^T / lam (+ I / w),
 * r = nu - J_A b_A, and qd_F = (Jm_F - J_F^T ye) / lam, s = -ye / w. Bounds that the free joints
 * cross join the active set, active bounds with a multiplier of the wrong sign leave it (a primal-
 * dual active-set iteration); when nothing changes, the point satisfies the optimality conditions:
 * it is the QP's unique solution, written to x (NX). Returns the number of linear solves, or 0
 * when it did not settle within max_iter (or M is singular: no slack and J_F rank-deficient).
 */
static int active_set_(const double *J, const double *Jm, const double *nu, const double *lo,
                       const double *hi, double lam, double w, int *act, int max_iter, double *x)
{
    double scale = 0.0;
    for (int i = 0; i < N; ++i)
        scale = fmax_(scale, fabs(Jm[i]));
    for (int iter = 1; iter <= max_iter; ++iter) {
        double M[36], L[36], ye[6], xs[N];
        int nfree = 0;
        for (int k = 0; k < N; ++k)
            nfree += !act[k];
        if (!NS && nfree < 6) /* J_F J_F^T singular: the equality cannot be met with these bounds */
            return 0;
        for (int i = 0; i < 6; ++i) {
            ye[i] = -nu[i];
            for (int j = 0; j <= i; ++j)
                M[i * 6 + j] = (NS && i == j) ? 1.0 / w : 0.0;
        }
        for (int k = 0; k < N; ++k) {
            if (act[k]) {
                xs[k] = act[k] > 0 ? hi[k] : lo[k];
                for (int i = 0; i < 6; ++i)
                    ye[i] += J[i * N + k] * xs[k];
            } else {
                double z = Jm[k] / lam;
                for (int i = 0; i < 6; ++i) {
                    ye[i] += J[i * N + k] * z;
                    for (int j = 0; j <= i; ++j)
                        M[i * 6 + j] += J[i * N + k] * J[j * N + k] / lam;
                }
            }
        }
        for (int i = 0; i < 6; ++i)
            for (int j = 0; j < i; ++j)
                M[j * 6 + i] = M[i * 6 + j];
        if (!chol_(M, 6, 0.0, L))
            return 0;
        chol_solve_(L, 6, ye);
        int changed = 0;
        for (int k = 0; k < N; ++k) {
            double jty = 0.0;
            for (int i = 0; i < 6; ++i)
                jty += J[i * N + k] * ye[i];
            if (!act[k]) {
                xs[k] = (Jm[k] - jty) / lam;
                double tol = 1e-12 * (1.0 + fabs(xs[k]));
                if (xs[k] < lo[k] - tol) {
                    act[k] = -1;
                    changed = 1;
                } else if (xs[k] > hi[k] + tol) {
                    act[k] = 1;
                    changed = 1;
                }
            } else if (act[k] != 2) {
                double mult = Jm[k] - lam * xs[k] - jty; /* >= 0 at an upper bound, <= 0 at a lower */
                double tol = 1e-12 * (1.0 + scale + lam * fabs(xs[k]));
                if (mult * act[k] < -tol) {
                    act[k] = 0;
                    changed = 1;
                }
            }
        }
        if (!changed) { /* verify the equality: M may be numerically singular (J_F rank-deficient) */
            double xx[NX], numax = 0.0, res = 0.0;
            memcpy(xx, xs, sizeof xs);
            for (int i = 0; i < NS; ++i)
                xx[N + i] = -ye[i] / w;
            for (int i = 0; i < 6; ++i) {
                double r = (NS ? xx[N + i] : 0.0) - nu[i];
                for (int k = 0; k < N; ++k)
                    r += J[i * N + k] * xx[k];
                res = fmax_(res, fabs(r));
                numax = fmax_(numax, fabs(nu[i]));
            }
            if (!(res <= 1e-9 * (1.0 + numax)))
                return 0;
            memcpy(x, xx, sizeof xx);
            return iter;
        }
    }
    return 0;
}

/* active set of a point: bounds that x violates or lies on (fixed when lower == upper) */
static void active_of_(const double *x, const double *lo, const double *hi, int *act)
{
    for (int k = 0; k < N; ++k)
        act[k] = lo[k] == hi[k] ? 2 : x[k] < lo[k] - 1e-12 ? -1 : x[k] > hi[k] + 1e-12 ? 1 : 0;
}

/* OSQP's polish guess of the active set: from the solution x and the multipliers y */
static void osqp_active_(const double *x, const double *y, const double *lo, const double *hi, int *act)
{
    for (int k = 0; k < N; ++k) {
        double yk = y[6 + k];
        act[k] = lo[k] == hi[k] ? 2 : x[k] - lo[k] < -yk ? -1 : hi[k] - x[k] < yk ? 1 : 0;
    }
}

#if ND
/*
 * active_set_rows_solve of mmc_qp.py (the slack variant with the ND distance rows Jd qd >= dl, free
 * rows -inf): with s = nu - J qd eliminated the cost is 0.5 qd^T H qd - g.qd, H = lam I + w J^T J,
 * g = Jm + w J^T nu. Holding the active bounds (act) and rows (rows) as equalities, the free joints
 * and the rows' multipliers mu solve H_FF qd_F = g_F - H_FA b_A + Jd_RF^T mu, Jd_RF qd_F = dl_R -
 * Jd_RA b_A (Schur complement, one refinement). Free joints beyond a bound and the most violated
 * row join, active bounds and rows whose multiplier has the wrong sign leave; when nothing
 * changes the point is the QP's unique solution, written to x (NX). Returns the number of solves,
 * or 0 (not settled within max_iter, dependent rows, or the check failed).
 */
static int active_set_rows_(const double *J, const double *Jm, const double *nu, const double *lo,
                            const double *hi, double lam, double w, const double *Jd, const double *dl,
                            int *act, int *rows, int max_iter, double *x)
{
    double H[N * N], g[N], scale = 0.0;
    for (int i = 0; i < N; ++i) {
        double gi = 0.0;
        for (int r = 0; r < 6; ++r)
            gi += J[r * N + i] * nu[r];
        g[i] = Jm[i] + w * gi;
        scale = fmax_(scale, fabs(g[i]));
        for (int j = 0; j <= i; ++j) {
            double h = 0.0;
            for (int r = 0; r < 6; ++r)
                h += J[r * N + i] * J[r * N + j];
            H[i * N + j] = H[j * N + i] = w * h + (i == j ? lam : 0.0);
        }
    }
    for (int j = 0; j < ND; ++j)
        rows[j] = rows[j] && isfinite(dl[j]);
    for (int iter = 1; iter <= max_iter; ++iter) {
        int F[N], R[ND], nf = 0, nr = 0;
        double xs[N], mu[N], HF[N * N], Lf[N * N], xf[N];
        for (int k = 0; k < N; ++k) {
            if (!act[k])
                F[nf++] = k;
            xs[k] = act[k] ? (act[k] > 0 ? hi[k] : lo[k]) : 0.0;
        }
        for (int j = 0; j < ND; ++j)
            if (rows[j])
                R[nr++] = j;
        if (nr > nf) /* more active rows than free joints: dependent */
            return 0;
        for (int a = 0; a < nf; ++a) {
            double t = g[F[a]];
            for (int k = 0; k < N; ++k)
                if (act[k])
                    t -= H[F[a] * N + k] * xs[k];
            xf[a] = t;
            for (int b = 0; b < nf; ++b)
                HF[a * nf + b] = H[F[a] * N + F[b]];
        }
        if (!chol_(HF, nf, 0.0, Lf))
            return 0;
        chol_solve_(Lf, nf, xf);
        if (nr) {
            double B[N * N], Y[N * N], S[N * N], Ls[N * N], t0[N], e[N];
            for (int r = 0; r < nr; ++r) {
                double col[N], t = dl[R[r]];
                for (int k = 0; k < N; ++k)
                    if (act[k])
                        t -= Jd[R[r] * N + k] * xs[k];
                t0[r] = t;
                for (int a = 0; a < nf; ++a)
                    col[a] = B[r * nf + a] = Jd[R[r] * N + F[a]];
                chol_solve_(Lf, nf, col);
                for (int a = 0; a < nf; ++a)
                    Y[a * nr + r] = col[a];
            }
            for (int r = 0; r < nr; ++r)
                for (int q2 = 0; q2 < nr; ++q2) {
                    double v = 0.0;
                    for (int a = 0; a < nf; ++a)
                        v += B[r * nf + a] * Y[a * nr + q2];
                    S[r * nr + q2] = v;
                }
            if (!chol_(S, nr, 0.0, Ls))
                return 0;
            for (int r = 0; r < nr; ++r)
                mu[r] = 0.0;
            for (int pass = 0; pass < 2; ++pass) { /* the solve, then one refinement */
                for (int r = 0; r < nr; ++r) {
                    double v = t0[r];
                    for (int a = 0; a < nf; ++a)
                        v -= B[r * nf + a] * xf[a];
                    e[r] = v;
                }
                chol_solve_(Ls, nr, e);
                for (int r = 0; r < nr; ++r)
                    mu[r] += e[r];
                for (int a = 0; a < nf; ++a) {
                    double v = 0.0;
                    for (int r = 0; r < nr; ++r)
                        v += Y[a * nr + r] * e[r];
                    xf[a] += v;
                }
            }
        }
        for (int a = 0; a < nf; ++a)
            xs[F[a]] = xf[a];
        int changed = 0, newact[N], join = -1;
        double deepest = INFINITY;
        for (int k = 0; k < N; ++k) {
            double grad = -g[k]; /* H x - g - Jd_R^T mu: the bounds' multipliers */
            for (int j = 0; j < N; ++j)
                grad += H[k * N + j] * xs[j];
            for (int r = 0; r < nr; ++r)
                grad -= Jd[R[r] * N + k] * mu[r];
            double tol = 1e-12 * (1.0 + fabs(xs[k]));
            newact[k] = act[k];
            if (!act[k] && xs[k] < lo[k] - tol)
                newact[k] = -1;
            else if (!act[k] && xs[k] > hi[k] + tol)
                newact[k] = 1;
            else if ((act[k] == 1 || act[k] == -1) &&
                     act[k] * grad > 1e-12 * (1.0 + scale + lam * fabs(xs[k])))
                newact[k] = 0;
            changed |= newact[k] != act[k];
        }
        double rres[ND], rtol[ND];
        for (int j = 0; j < ND; ++j) {
            if (!isfinite(dl[j]))
                continue;
            double v = -dl[j], ax = 0.0, nrm = 0.0;
            for (int k = 0; k < N; ++k) {
                v += Jd[j * N + k] * xs[k];
                ax += fabs(Jd[j * N + k]) * fabs(xs[k]);
                nrm += Jd[j * N + k] * Jd[j * N + k];
            }
            rres[j] = v;
            rtol[j] = 1.0 + fabs(dl[j]) + ax;
            if (!rows[j] && v < -1e-12 * rtol[j]) {
                double depth = v / fmax_(sqrt(nrm), 1e-300);
                if (depth < deepest) {
                    deepest = depth;
                    join = j;
                }
            }
        }
        for (int r = 0; r < nr; ++r) /* rows whose multiplier has the wrong sign leave */
            if (mu[r] < -1e-12 * (1.0 + scale)) {
                rows[R[r]] = 0;
                changed = 1;
            }
        if (changed || join >= 0) {
            memcpy(act, newact, sizeof newact);
            if (join >= 0)
                rows[join] = 1;
            continue;
        }
        for (int k = 0; k < N; ++k) /* verify (the Schur complement may be numerically singular) */
            if (!isfinite(xs[k]))
                return 0;
        for (int j = 0; j < ND; ++j)
            if (isfinite(dl[j]) && (!(rres[j] >= -1e-8 * rtol[j]) || (rows[j] && !(fabs(rres[j]) <= 1e-8 * rtol[j]))))
                return 0;
        for (int k = 0; k < N; ++k)
            x[k] = xs[k];
        slack_of_(J, nu, xs, x + N);
        return iter;
    }
    return 0;
}
#endif

#if ND
/* keep a settled active set (bounds, and the pairs of the active rows) for the next step */
static void remember_(symkin_mmc_ctrl *c, const int *act, const int *rows, const int *pid, int npid)
{
    c->warm = 1;
    c->nwarm = 0;
    for (int k = 0; k < N; ++k)
        c->wact[k] = act[k];
    for (int j = 0; j < npid; ++j)
        if (rows[j])
            c->wpair[c->nwarm++] = pid[j];
}
#endif

static int status_of_(OSQPInt s)
{
    switch (s) {
    case OSQP_SOLVED:
        return MMC_SOLVED;
    case OSQP_SOLVED_INACCURATE:
        return MMC_INACCURATE;
    case OSQP_PRIMAL_INFEASIBLE:
    case OSQP_PRIMAL_INFEASIBLE_INACCURATE:
        return MMC_INFEASIBLE;
    case OSQP_MAX_ITER_REACHED:
    case OSQP_TIME_LIMIT_REACHED:
        return MMC_MAX_ITER;
    default:
        return MMC_ERROR;
    }
}

/* the solver's iterate and rho, as this controller's */
static void save_(symkin_mmc_ctrl *c, const OSQPSolver *S)
{
    memcpy(c->x, S->work->x->values, sizeof(double) * NX);
    memcpy(c->z, S->work->z->values, sizeof(double) * NC);
    memcpy(c->y, S->work->y->values, sizeof(double) * NC);
    c->rho = S->settings->rho;
}

/* a step's input check: 1 when q (N) has a value that is not finite, 2 when nu (6) has, else 0 */
static int bad_input_(const double *q, const double *nu)
{
    for (int k = 0; k < N; ++k)
        if (!isfinite(q[k]))
            return 1;
    for (int i = 0; i < 6; ++i)
        if (!isfinite(nu[i]))
            return 2;
    return 0;
}

/* 1 with G = J J^T's Cholesky factor in L when J is regular: its smallest singular value is at
   least tol (G - tol^2 I is PD); else 0 */
static int regular_(const double *G, double tol, double *L)
{
    return N >= 6 && chol_(G, 6, -tol * tol, L) && chol_(G, 6, 0.0, L);
}

/* m = sqrt(det(J J^T)) from the Cholesky factor L (6x6) of J J^T: the product of its diagonal */
static double chol_manipulability_(const double *L)
{
    double m = 1.0;
    for (int i = 0; i < 6; ++i)
        m *= L[i * 6 + i];
    return m;
}

#if ND
/* MMC._distance_rows: the gradient rows Jd (ND, N) and the damper lower bounds dl (ND) of the ND
   closest pairs within their d_i (d_i_self for self pairs; ties by pair order), the other rows
   zero and free (-inf), and the rows' pairs in idx; returns how many pairs lie within their d_i
   (at most ND) */
static int distance_rows_(symkin_mmc_ctrl *c, const double *q, double *Jd, double *dl, int *idx)
{
    int cnt = 0;
    c->dist(q, c->env_s, c->env_ns, c->env_c, c->env_nc, c->env_b, c->env_nb, c->dbuf, 0);
    const double *d = c->dbuf;
    for (int p = 0; p < c->pairs; ++p) { /* insertion into the sorted ND closest (stable) */
        const double d_i = p < c->self_pairs ? c->d_i_self : c->d_i;
        if (!(d[p] < d_i) || (cnt == ND && !(d[p] < d[idx[ND - 1]])))
            continue;
        int j = cnt < ND ? cnt++ : ND - 1;
        while (j > 0 && d[idx[j - 1]] > d[p]) {
            idx[j] = idx[j - 1];
            --j;
        }
        idx[j] = p;
    }
    memset(Jd, 0, sizeof(double) * ND * N);
    if (cnt) /* the gradient rows of the chosen pairs only */
        c->rows(q, c->env_s, c->env_ns, c->env_c, c->env_nc, c->env_b, c->env_nb, idx, cnt, Jd);
    for (int j = 0; j < ND; ++j) {
        const int self = j < cnt && idx[j] < c->self_pairs;
        const double d_i = self ? c->d_i_self : c->d_i, d_s = self ? c->d_s_self : c->d_s;
        dl[j] = j < cnt ? -c->xi_d * (d[idx[j]] - d_s) / (d_i - d_s) : -INFINITY;
    }
    return cnt;
}
#endif

/* update the embedded OSQP problem (Jd, dl: the ND distance rows, unused without), solve; the
   solution in x (NX) or -1 (status in *status) */
static int osqp_step_(symkin_mmc_ctrl *c, const double *J, const double *Jm, const double *nu,
                      const double *lo, const double *hi, const double *Jd, const double *dl, double *x,
                      int *status, int *iters)
{
    OSQPSolver *S = &MMC_SOLVER;
    OSQPFloat qv[NX], l[NC], u[NC], Px[NX], Ax[NNZ_A];
    for (int k = 0; k < NX; ++k) {
        qv[k] = k < N ? -Jm[k] : 0.0;
        Px[k] = k < N ? c->lam : c->slack_weight;
    }
    for (int i = 0; i < 6; ++i)
        l[i] = u[i] = nu[i];
    for (int k = 0; k < N; ++k) {
        l[6 + k] = fmax_(lo[k], -OSQP_INFTY);
        u[6 + k] = fmin_(hi[k], OSQP_INFTY);
        for (int i = 0; i < 6; ++i)
            Ax[(7 + ND) * k + i] = J[i * N + k];
        Ax[(7 + ND) * k + 6] = 1.0;
        for (int j = 0; j < ND; ++j)
            Ax[(7 + ND) * k + 7 + j] = Jd[j * N + k];
    }
    for (int j = 0; j < ND; ++j) {
        l[6 + N + j] = fmax_(dl[j], -OSQP_INFTY);
        u[6 + N + j] = OSQP_INFTY;
    }
    for (int i = 0; i < NS; ++i)
        Ax[(7 + ND) * N + i] = 1.0;
    *status = MMC_ERROR;
    *iters = 0;
    if (owner_ != c || c->fresh) { /* take the solver over: this controller's rho and iterate */
        if (c->fresh) {
            osqp_cold_start(S);
            c->rho = c->rho0;
        } else {
            memcpy(S->work->x->values, c->x, sizeof(double) * NX);
            memcpy(S->work->z->values, c->z, sizeof(double) * NC);
            memcpy(S->work->y->values, c->y, sizeof(double) * NC);
        }
        if (S->settings->rho != c->rho && osqp_update_rho(S, c->rho)) {
            owner_ = 0;
            return -1;
        }
        owner_ = c;
    }
    if (osqp_update_data_vec(S, qv, l, u) || osqp_update_data_mat(S, Px, 0, NX, Ax, 0, NNZ_A) ||
        osqp_solve(S)) {
        c->fresh = 1; /* like control.py, which sets OSQP up again after an error */
        return -1;
    }
    *status = status_of_(S->info->status_val);
    *iters = (int)S->info->iter;
    save_(c, S);
    c->fresh = 0;
    int finite = 1;
    for (int k = 0; k < NX; ++k) {
        x[k] = S->solution->x[k];
        finite = finite && isfinite(x[k]);
    }
    return finite ? 0 : -1;
}

#if MMC_NS == 0
void symkin_mmc_layout(int32_t *out)
{
    out[0] = N;
    out[1] = (int32_t)sizeof(symkin_mmc_ctrl);
    out[2] = MMC_NINFO;
}

/* determinant of a symmetric 3x3 matrix */
static double det3_(const double *G)
{
    return G[0] * (G[4] * G[8] - G[5] * G[7]) - G[1] * (G[3] * G[8] - G[5] * G[6]) +
           G[2] * (G[3] * G[7] - G[4] * G[6]);
}

/* the manipulability of the rows c->axes of J (G = J J^T, L its Cholesky factor when regular) */
static double rate_manipulability_(const symkin_mmc_ctrl *c, const double *J, const double *G, int regular,
                                   const double *L)
{
    double m = 0.0;
    if (c->axes == 0) {
        if (regular) {
            m = chol_manipulability_(L);
        } else if (N >= 6) {
            double d = det_(G, 6);
            m = d > 0.0 ? sqrt(d) : 0.0;
        }
    } else {
        double G3[9];
        gram_(J, c->axes == 1 ? 0 : 3, 3, G3);
        double d = det3_(G3);
        m = d > 0.0 ? sqrt(d) : 0.0;
    }
    return m;
}

/* qd scaled down as a whole to |qd_k| <= qd_max_k; returns the factor (1: unscaled) */
static double scale_to_limits_(const symkin_mmc_ctrl *c, double *qd)
{
    double scale = 1.0;
    for (int k = 0; k < N; ++k) {
        double a = fabs(qd[k]);
        if (a > c->qd_max[k] && c->qd_max[k] / a < scale)
            scale = c->qd_max[k] / a;
    }
    if (scale < 1.0)
        for (int k = 0; k < N; ++k)
            qd[k] *= scale;
    return scale;
}

/* RRMC (see mmc.h); symkin.runtime.control.rrmc is the reference */
int symkin_rrmc_step(symkin_mmc_ctrl *c, const double *in, double *out)
{
    const double *q = in, *nu = in + N;
    int bad = bad_input_(q, nu);
    if (bad)
        return bad;
    double J[6 * N], G[36], L[36], y[6], *qd = out;
    c->polished = 0;
    c->j0(q, J);
    gram_(J, 0, 6, G);
    int regular = regular_(G, c->singular_tol, L);
    double m = rate_manipulability_(c, J, G, regular, L);
    int status = MMC_SOLVED, method = N == 6 ? MMC_INVERSE : MMC_PINV;
    memcpy(y, nu, sizeof y);
    if (regular) {
        chol_solve_(L, 6, y);
    } else {
        status = MMC_SINGULAR;
        method = MMC_DAMPED;
        if (chol_(G, 6, c->damping * c->damping, L))
            chol_solve_(L, 6, y);
        else /* no damping at a singular J: no step */
            memset(y, 0, sizeof y);
    }
    tmul_(J, y, qd);
    double scale = scale_to_limits_(c, qd);
    write_info_(out, status, method, m, 0, MMC_NO_FALLBACK, residual_(J, qd, nu), 0.0, scale, 0);
    return 0;
}

#include "qrmc_impl.h" /* the quadratic-rate step, on the helpers above */
#endif

int MMC_FN(step)(symkin_mmc_ctrl *c, const double *in, double *out)
{
    const double *q = in, *nu = in + N;
    int bad = bad_input_(q, nu);
    if (bad)
        return bad;
    double J[6 * N], H[N * 6 * N], G[36], L[36], B[6 * N], Jm[N], lo[N], hi[N];
    double *qd = out;
    c->polished = 0;
    if (c->no_jm) /* no manipulability term: J alone */
        c->j0(q, J);
    else
        c->jh(q, J, H);
    gram_(J, 0, 6, G);
    /* not when J is singular: its smallest singular value below singular_tol */
    int have_b = regular_(G, c->singular_tol, L);
    /* the QP is solved: J regular, or (the QP IK step) with the slack at any J, Jm = 0 when singular */
    const int solvable = have_b || (NS && c->singular_qp);
    double m = 0.0;
    memset(Jm, 0, sizeof Jm);
    if (have_b)
        solve_rows_(L, 6, J, 0, B);
    if (c->axes == 0) {
        if (have_b) {
            m = chol_manipulability_(L);
            if (!c->no_jm)
                jacobm_(H, B, 0, 6, m, Jm);
        } else { /* singular: only m is reported (the QP is not solved, or solved without Jm) */
            double d = det_(G, 6);
            m = d > 0.0 ? sqrt(d) : 0.0;
        }
    } else {
        int r0 = c->axes == 1 ? 0 : 3;
        double G3[9], L3[9], B3[3 * N];
        gram_(J, r0, 3, G3);
        double d = det_(G3, 3);
        if (d > 0.0 && chol_(G3, 3, 0.0, L3)) {
            m = sqrt(d);
            if (!c->no_jm) {
                solve_rows_(L3, 3, J, r0, B3);
                jacobm_(H, B3, r0, 3, m, Jm);
                for (int k = 0; k < N; ++k)
                    if (!isfinite(Jm[k])) {
                        memset(Jm, 0, sizeof Jm);
                        m = 0.0;
                        break;
                    }
            }
        }
    }
    bounds_(c, q, lo, hi);
#if ND
    double Jd[ND * N], dl[ND];
    int pid[ND];
    const int npid = distance_rows_(c, q, Jd, dl, pid), near = npid > 0, warm = c->warm;
    c->warm = 0; /* set again when this step's active set settles */
#else
    const double *Jd = 0, *dl = 0;
    const int near = 0;
#endif
    if (c->closed_form && solvable && (!near || c->active_set)) {
        /* z + J^+ (nu - J z), z = Jm / lam; with the slack z + J^T (J J^T + lam / w I)^-1 (nu - J z) */
        double z[N], t[6], sum = 0.0;
        int inside = 1;
        for (int k = 0; k < N; ++k)
            z[k] = Jm[k] / c->lam;
        for (int i = 0; i < 6; ++i) {
            double s = nu[i];
            for (int k = 0; k < N; ++k)
                s -= J[i * N + k] * z[k];
            t[i] = s;
        }
        double y[6], Ls[36];
        memcpy(y, t, sizeof y); /* y = (J J^T (+ lam / w I))^-1 t, qd = z + J^T y */
        if (!NS)
            chol_solve_(L, 6, y);
        else if (chol_(G, 6, c->lam / c->slack_weight, Ls))
            chol_solve_(Ls, 6, y);
        else
            y[0] = NAN;
        for (int k = 0; k < N; ++k) {
            double s = z[k];
            for (int i = 0; i < 6; ++i)
                s += J[i * N + k] * y[i];
            qd[k] = s;
            sum += s;
            if (c->bounded && !(s >= lo[k] - 1e-12 && s <= hi[k] + 1e-12))
                inside = 0;
        }
#if ND
        if (near) { /* obstacle rows: the active-set solve with them, first from the last step's
                       active bounds and pairs, then from the bounds the closed form crosses */
            int act[N], rows[ND], its = 0;
            double x[NX];
            if (warm) {
                for (int k = 0; k < N; ++k)
                    act[k] = lo[k] == hi[k] ? 2 : c->wact[k] == 2 ? 0 : c->wact[k];
                for (int j = 0; j < ND; ++j) {
                    rows[j] = 0;
                    for (int w = 0; j < npid && w < c->nwarm; ++w)
                        rows[j] |= c->wpair[w] == pid[j];
                }
                its = active_set_rows_(J, Jm, nu, lo, hi, c->lam, c->slack_weight, Jd, dl, act, rows, 4 * N + 4, x);
            }
            if (!its) {
                active_of_(qd, lo, hi, act);
                memset(rows, 0, sizeof rows);
                its = active_set_rows_(J, Jm, nu, lo, hi, c->lam, c->slack_weight, Jd, dl, act, rows, 4 * N + 4, x);
            }
            if (its) {
                remember_(c, act, rows, pid, npid);
                active_set_answer_(out, J, nu, lo, hi, x, m, its);
                return 0;
            }
            inside = 0;
            sum = NAN; /* on to OSQP */
        }
#endif
        if (inside && isfinite(sum)) {
            double res = 0.0, slack = 0.0;
            for (int i = 0; i < 6; ++i) {
                double e = nu[i];
                for (int k = 0; k < N; ++k)
                    e -= J[i * N + k] * qd[k];
                res = fmax_(res, fabs(e));
                slack += e * e;
            }
            write_info_(out, MMC_SOLVED, MMC_CLOSED_FORM, m, 0, MMC_NO_FALLBACK, res, NS ? sqrt(slack) : 0.0,
                        1.0, 0);
            return 0;
        }
        if (c->active_set && !near) { /* the bounds the closed form crosses, as equalities, then corrected */
            int act[N], its;
            double x[NX];
            active_of_(qd, lo, hi, act);
            its = active_set_(J, Jm, nu, lo, hi, c->lam, c->slack_weight, act, 2 * N + 2, x);
            if (its) {
                active_set_answer_(out, J, nu, lo, hi, x, m, its);
                return 0;
            }
        }
    }
    int kind;
    double scale;
    if (!solvable) {
        fallback_(c, J, G, B, 0, nu, lo, hi, qd, &kind, &scale);
        write_info_(out, MMC_SINGULAR, MMC_CLOSED_FORM, m, 0, kind, residual_(J, qd, nu), 0.0, scale, 0);
        return 0;
    }
    double x[NX];
    int status, iters, polished = 0;
    int ok = osqp_step_(c, J, Jm, nu, lo, hi, Jd, dl, x, &status, &iters) == 0;
    if (!ok && status == MMC_SOLVED)
        status = MMC_ERROR;
#if ND
    if (ok && c->polish && near && (status == MMC_SOLVED || status == MMC_INACCURATE || status == MMC_MAX_ITER)) {
        /* the same polish with the obstacle rows: from OSQP's active bounds and rows */
        int act[N], rows[ND];
        const OSQPFloat *y = MMC_SOLVER.solution->y;
        osqp_active_(x, y, lo, hi, act);
        for (int j = 0; j < ND; ++j) {
            double r = -dl[j];
            for (int k = 0; k < N; ++k)
                r += Jd[j * N + k] * x[k];
            rows[j] = isfinite(dl[j]) && r < -y[6 + N + j];
        }
        polished = active_set_rows_(J, Jm, nu, lo, hi, c->lam, c->slack_weight, Jd, dl, act, rows, 4 * N + 4, x) > 0;
        if (polished) {
            status = MMC_SOLVED;
            remember_(c, act, rows, pid, npid); /* the next step starts from this active set */
        }
    }
#endif
    if (ok && c->polish && !near && (status == MMC_SOLVED || status == MMC_INACCURATE || status == MMC_MAX_ITER)) {
        /* OSQP's polish: the active-set solve from OSQP's active set; when it settles it is the
           exact solution, also of a QP that OSQP left unfinished */
        int act[N];
        osqp_active_(x, MMC_SOLVER.solution->y, lo, hi, act);
        polished = active_set_(J, Jm, nu, lo, hi, c->lam, c->slack_weight, act, 2 * N + 2, x) > 0;
        if (polished)
            status = MMC_SOLVED;
    }
    if (ok && (status == MMC_SOLVED || status == MMC_INACCURATE || status == MMC_MAX_ITER)) {
        double numax = 0.0;
        for (int i = 0; i < 6; ++i)
            numax = fmax_(numax, fabs(nu[i]));
        for (int k = 0; k < N; ++k)
            qd[k] = fmin_(fmax_(x[k], lo[k]), hi[k]);
        double res = residual_(J, qd, nu);
        if (status == MMC_SOLVED || NS || res <= 1e-6 * (1.0 + numax)) {
            double slack = 0.0;
            for (int i = N; i < NX; ++i)
                slack += x[i] * x[i];
            write_info_(out, status, MMC_OSQP, m, iters, MMC_NO_FALLBACK, res, sqrt(slack), 1.0,
                        polished);
            c->polished = polished;
            return 0;
        }
    }
    /* infeasible, error or an unusable iterate: the RRMC step, and the next solve starts from it */
    if (status == MMC_SOLVED)
        status = MMC_ERROR;
    fallback_(c, J, G, B, have_b, nu, lo, hi, qd, &kind, &scale);
    write_info_(out, status, MMC_OSQP, m, iters, kind, residual_(J, qd, nu), 0.0, scale, 0);
    if (!c->fresh && owner_ == c) {
        double xw[NX], yw[NC];
        for (int k = 0; k < N; ++k)
            xw[k] = qd[k];
        slack_of_(J, nu, qd, xw + N);
        memset(yw, 0, sizeof yw);
        osqp_warm_start(&MMC_SOLVER, xw, yw);
        save_(c, &MMC_SOLVER);
    }
    return 0;
}
