/*
 * qrmc.h: one step of quadratic-rate motion control (Haviland and Corke, Manipulator Differential
 * Kinematics, Part 2, 2023, "Quadratic-Rate Motion Control") in C, part of the MMC library (mmc.h):
 * qd solves the second-order model of the pose change over a horizon h at constant qd,
 *
 *     g(qd) = J qd + (h / 2) (H qd) qd - nu = 0,    (H qd) = sum_i qd_i H[i]   (6, n)
 *
 * by Levenberg-Marquardt on g (Newton's step J~^T (J~ J~^T)^-1 g with J~ = dg/dqd = J + (h / 2)
 * ((H qd) + [H_j qd]_j) while it lowers |g| and J~ is regular, else damped), from zero (its first
 * step is the RRMC step), then, unconverged, from the last answer and the last answer + seed; the
 * converged answer of least norm (else the smallest residual), scaled down as a whole to
 * |qd_k| <= qd_max_k. symkin.runtime.qrmc is the reference.
 */
#ifndef SYMKIN_QRMC_H
#define SYMKIN_QRMC_H

#include "mmc.h"

/* A QRMC controller: an MMC library controller (its kinematics jh, fk and manip, axes, singular_tol,
 * damping, qd_max, qlo and qhi) followed by the QRMC options and warm start. A pointer to it is a
 * pointer to its base: the library's servo loop runs it like the other steps. */
typedef struct {
    symkin_mmc_ctrl base;
    double horizon;     /* h: the time over which the model holds (s) */
    double tol;         /* converged when max |g| <= tol (1 + max |nu|) */
    int32_t iterations; /* Levenberg-Marquardt trials per start */
    int32_t warm;       /* 1: prev holds the last answer */
    double seed[MMC_N]; /* offset of the second start (rad/s or m/s) */
    double prev[MMC_N]; /* the last answer before the speed scaling (a start of the next step) */
} symkin_qrmc_ctrl;

/* info[1] method of the QRMC step (after those of mmc.h) */
enum { MMC_QUADRATIC = MMC_DAMPED + 1 };

/*
 * One quadratic-rate step: c points at a symkin_qrmc_ctrl; in = (q[n], nu[6]); out = (qd[n], status
 * (solved, singular when unconverged at a singular J, else max_iter; error with a zero qd when the
 * answer is not finite), method MMC_QUADRATIC, manipulability of the rows axes at q, the
 * Levenberg-Marquardt trials, no fallback, residual max |g| before the scaling, slack 0, scale, polished 0).
 * Returns 0, or 1 / 2 when q / nu is not finite (out untouched). Sets prev and warm.
 */
MMC_API int symkin_qrmc_step(symkin_mmc_ctrl *c, const double *in, double *out);

/* n, sizeof(symkin_qrmc_ctrl) (for layout checks). */
MMC_API void symkin_qrmc_layout(int32_t *out);

#endif /* SYMKIN_QRMC_H */
