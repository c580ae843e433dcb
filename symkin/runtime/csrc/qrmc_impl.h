/*
 * qrmc_impl.h: the quadratic-rate step of qrmc.h, included by mmc_impl.h once (MMC_NS == 0) after
 * the RRMC step, whose helpers (chol_, gram_, regular_, bad_input_, write_info_,
 * rate_manipulability_, scale_to_limits_) it uses. Mirrors symkin.runtime.qrmc.QRMC.step and
 * quadratic_rate_solve branch for branch.
 */
#include "qrmc.h"

void symkin_qrmc_layout(int32_t *out)
{
    out[0] = N;
    out[1] = (int32_t)sizeof(symkin_qrmc_ctrl);
}

/* A = sum_i x_i H[i] (6, N), H (N, 6, N) row-major */
static void qrmc_hx_(const double *H, const double *x, double *A)
{
    memset(A, 0, sizeof(double) * 6 * N);
    for (int i = 0; i < N; ++i)
        for (int r = 0; r < 6 * N; ++r)
            A[r] += x[i] * H[i * 6 * N + r];
}

/* g = J x + (h/2) (H x) x - nu (6) with A = H x already in A; returns max |g| (NaN when g has one),
   *cost = |g|^2 */
static double qrmc_g_(const double *J, const double *A, const double *nu, double half_h, const double *x,
                      double *g, double *cost)
{
    double r = 0.0, c2 = 0.0;
    for (int i = 0; i < 6; ++i) {
        double s = -nu[i];
        for (int k = 0; k < N; ++k)
            s += (J[i * N + k] + half_h * A[i * N + k]) * x[k];
        g[i] = s;
        c2 += s * s;
        if (!(fabs(s) <= r)) /* NaN too */
            r = fabs(s);
    }
    *cost = c2;
    return r;
}

/* Levenberg-Marquardt on g from x (overwritten by the last accepted iterate): trials
   x - J~^T (J~ J~^T + mu I)^-1 g with J~ = J + (h/2) (H x + [H_j x]_j), mu = 0 while J~ is regular,
   accepted when |g| falls (mu / 10, to 0 below damping^2 / 1000), else mu x 10 (from damping^2).
   Returns max |g| at x; adds the trials to *taken. */
static double qrmc_lm_(const symkin_qrmc_ctrl *c, const double *J, const double *H, const double *nu,
                       double limit, double *x, int *taken)
{
    const double half_h = 0.5 * c->horizon, d2 = c->base.damping * c->base.damping;
    double A[6 * N], Jt[6 * N], G[36], L[36], g[6], y[6], xn[N], gn[6], cost, cost_n, mu = 0.0;
    qrmc_hx_(H, x, A);
    double r = qrmc_g_(J, A, nu, half_h, x, g, &cost);
    for (int t = 0; t < c->iterations && !(r <= limit) && isfinite(cost);) {
        for (int i = 0; i < 6; ++i)
            for (int j = 0; j < N; ++j) {
                double s = 0.0; /* (H_j x)_i */
                for (int k = 0; k < N; ++k)
                    s += H[(j * 6 + i) * N + k] * x[k];
                Jt[i * N + j] = J[i * N + j] + half_h * (A[i * N + j] + s);
            }
        gram_(Jt, 0, 6, G);
        if (mu == 0.0 && !regular_(G, c->base.singular_tol, L))
            mu = d2;
        if (!chol_(G, 6, mu, L))
            break; /* mu = 0 at a singular J~ (damping 0): no step */
        ++t;
        *taken = *taken + 1;
        memcpy(y, g, sizeof y);
        chol_solve_(L, 6, y);
        tmul_(Jt, y, xn); /* the step J~^T y */
        for (int k = 0; k < N; ++k)
            xn[k] = x[k] - xn[k];
        double An[6 * N];
        qrmc_hx_(H, xn, An);
        double rn = qrmc_g_(J, An, nu, half_h, xn, gn, &cost_n);
        if (cost_n < cost) {
            memcpy(x, xn, sizeof xn);
            memcpy(A, An, sizeof A);
            memcpy(g, gn, sizeof g);
            cost = cost_n;
            r = rn;
            mu = mu < d2 * 1e-3 ? 0.0 : mu / 10.0;
        } else {
            mu = fmax_(10.0 * mu, d2);
            if (mu == 0.0)
                break; /* damping 0: no damped step to try */
        }
    }
    return r;
}

/* whether (x2, r2) beats (x, r): converged over not, then the smaller norm (both converged) or the
   smaller residual (neither) */
static int qrmc_better_(const double *x2, double r2, const double *x, double r, double limit)
{
    int ok2 = r2 <= limit, ok = r <= limit;
    if (ok2 != ok)
        return ok2;
    if (ok2) {
        double a = 0.0, b = 0.0;
        for (int k = 0; k < N; ++k) {
            a += x2[k] * x2[k];
            b += x[k] * x[k];
        }
        return a < b;
    }
    return r2 < r || !isfinite(r);
}

int symkin_qrmc_step(symkin_mmc_ctrl *base, const double *in, double *out)
{
    symkin_qrmc_ctrl *c = (symkin_qrmc_ctrl *)base;
    const double *q = in, *nu = in + N;
    int bad = bad_input_(q, nu);
    if (bad)
        return bad;
    double J[6 * N], H[N * 6 * N], G[36], L[36], x[N], x2[N], *qd = out, nmax = 0.0;
    base->polished = 0;
    base->jh(q, J, H);
    gram_(J, 0, 6, G);
    int regular = regular_(G, base->singular_tol, L);
    double m = rate_manipulability_(base, J, G, regular, L);
    for (int i = 0; i < 6; ++i)
        nmax = fmax_(nmax, fabs(nu[i]));
    const double limit = c->tol * (1.0 + nmax);
    memset(x, 0, sizeof x); /* from zero: the first trial is the RRMC step */
    int taken = 0, any = 0;
    double r = qrmc_lm_(c, J, H, nu, limit, x, &taken);
    for (int k = 0; k < N; ++k)
        any |= c->warm && c->prev[k] != 0.0;
    for (int s = any ? 0 : 1; s < 2 && !(r <= limit); ++s) { /* unconverged: from prev, prev + seed */
        for (int k = 0; k < N; ++k)
            x2[k] = (c->warm ? c->prev[k] : 0.0) + (s ? c->seed[k] : 0.0);
        double r2 = qrmc_lm_(c, J, H, nu, limit, x2, &taken);
        if (qrmc_better_(x2, r2, x, r, limit)) {
            memcpy(x, x2, sizeof x);
            r = r2;
        }
    }
    int finite = 1;
    for (int k = 0; k < N; ++k)
        finite &= isfinite(x[k]) != 0;
    c->warm = 1;
    if (!finite) { /* stop the joints instead */
        memset(c->prev, 0, sizeof c->prev);
        memset(qd, 0, sizeof(double) * N);
        write_info_(out, MMC_ERROR, MMC_QUADRATIC, m, taken, MMC_FALLBACK_ZERO, nmax, 0.0, 1.0, 0);
        return 0;
    }
    memcpy(c->prev, x, sizeof x);
    memcpy(qd, x, sizeof x);
    double scale = scale_to_limits_(base, qd);
    int status = r <= limit ? MMC_SOLVED : regular ? MMC_MAX_ITER : MMC_SINGULAR;
    write_info_(out, status, MMC_QUADRATIC, m, taken, MMC_NO_FALLBACK, r, 0.0, scale, 0);
    return 0;
}
