/* symkin_pose.h: the check of a target pose and the pose error of eq 37 (Haviland and Corke 2023): translation
 * error and the angle-axis vector alpha of eqs 38-40, shared by the IK solver (symkin_ik.c) and the
 * servo loop of the MMC library (mmc_py.c). Mirrors symkin.runtime.ik.check_pose and pose_error
 * branch for branch. */
#ifndef SYMKIN_POSE_H
#define SYMKIN_POSE_H

#include <math.h>

#define SYMKIN_NEAR_PI_L 1e-6
#define SYMKIN_POSE_ATOL 1e-6
#define SYMKIN_BOTTOM_ATOL 1e-12

/* Clear the upper halves of the vector registers before calling libm (atan2): its code is SSE,
 * and SSE instructions after 256-bit AVX code left them dirty stall (measured: each call cost
 * 0.1-0.3 us in NR/GN iterations on the development machine). Changes no value. */
#if defined(__AVX__) && (defined(__GNUC__) || defined(__clang__))
#define SYMKIN_BEFORE_LIBM() __builtin_ia32_vzeroupper()
#else
#define SYMKIN_BEFORE_LIBM() ((void)0)
#endif

/* Whether the row-major 4x4 T is a valid target (symkin.runtime.ik.check_pose): 0 when it is, else
 * 1 NaN or inf, 2 bottom row not (0 0 0 1), 3 max |R^T R - I| > 1e-6, 4 reflection (the
 * SYMKIN_POSE_* codes of symkin_ik.h). *deviation (if not NULL) gets max |R^T R - I| (or 0). */
static inline int symkin_pose_check(const double *T, double *deviation) {
    if (deviation) *deviation = 0.0;
    for (int i = 0; i < 16; i++)
        if (!isfinite(T[i])) return 1;
    if (fabs(T[12]) > SYMKIN_BOTTOM_ATOL || fabs(T[13]) > SYMKIN_BOTTOM_ATOL || fabs(T[14]) > SYMKIN_BOTTOM_ATOL ||
        fabs(T[15] - 1.0) > SYMKIN_BOTTOM_ATOL)
        return 2;
    double dev = 0.0;
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) {
            double s = T[a] * T[b] + T[4 + a] * T[4 + b] + T[8 + a] * T[8 + b];
            double d = fabs(s - (a == b ? 1.0 : 0.0));
            if (d > dev) dev = d;
        }
    if (deviation) *deviation = dev;
    if (!(dev <= SYMKIN_POSE_ATOL)) return 3;
    double det = T[0] * (T[5] * T[10] - T[6] * T[9]) - T[1] * (T[4] * T[10] - T[6] * T[8]) +
                 T[2] * (T[4] * T[9] - T[5] * T[8]);
    if (!(det > 0.0)) return 4;
    return 0;
}

/* alpha(R) of eqs 38-40, R row-major 3x3. */
static inline void symkin_angle_axis(const double *R, double *a) {
    double tr = R[0] + R[4] + R[8];
    if (R[1] == 0.0 && R[2] == 0.0 && R[3] == 0.0 && R[5] == 0.0 && R[6] == 0.0 && R[7] == 0.0) {
        if (tr > 0.0) { /* (1 1 1) */
            a[0] = a[1] = a[2] = 0.0;
        } else { /* eq 40 */
            a[0] = 1.5707963267948966 * (R[0] + 1.0);
            a[1] = 1.5707963267948966 * (R[4] + 1.0);
            a[2] = 1.5707963267948966 * (R[8] + 1.0);
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
        SYMKIN_BEFORE_LIBM();
        double k = atan2(nl, tr - 1.0) / nl;
        a[0] = k * l0;
        a[1] = k * l1;
        a[2] = k * l2;
        return;
    }
    /* near pi and not diagonal: l is rounding noise; the axis comes from the symmetric part,
     * a a^T = ((R + R^T) / 2 - cos(theta) I) / (1 - cos(theta)), its sign from l. */
    SYMKIN_BEFORE_LIBM();
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

/* e of eq 37 for row-major 4x4 T and Tep. */
static inline void symkin_pose_error(const double *T, const double *Tep, double *e) {
    e[0] = Tep[3] - T[3];
    e[1] = Tep[7] - T[7];
    e[2] = Tep[11] - T[11];
    double R[9]; /* Tep_R T_R^T */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            R[3 * i + j] = Tep[4 * i] * T[4 * j] + Tep[4 * i + 1] * T[4 * j + 1] + Tep[4 * i + 2] * T[4 * j + 2];
    symkin_angle_axis(R, e + 3);
}

#endif /* SYMKIN_POSE_H */
