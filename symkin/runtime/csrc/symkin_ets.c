/* Table-driven ETS kinematics: T and the base-frame Jacobian by the O(n) method of Haviland and Corke (2023)
 * (eqs 31-34). The pose is kept as a rotation R (3x3, in local variables r<row><col>) and a
 * position p; each elementary transform updates only what it touches (a rotation mixes two
 * columns of R, a translation moves p along one column). Before each joint its base-frame axis w
 * (signed) and, for a revolute joint, the origin o are recorded; at the end
 *   revolute column: (w x (p_e - o); w),   prismatic column: (w; 0).
 * The cosines and sines of all joints come first, so the chain itself makes no calls and R stays
 * in registers.
 *
 * GCC 12 (-O3, -march with FMA) may fuse the (+, -) pair of a rotation into vfmsubadd when it
 * SLP-vectorises, even under -ffp-contract=off, which rounds differently: compile with
 * -fno-tree-slp-vectorize (symkin/runtime/ik_c.py does).
 */
#include <math.h>

#include "symkin_ik.h"

/* rotation by (c, s) mixing the columns (j, k) = (a, b): Rx (1, 2), Ry (2, 0), Rz (0, 1) */
#define SYMKIN_ROT(a0, a1, a2, b0, b1, b2, c, s)          \
    do {                                                  \
        double u0 = a0, u1 = a1, u2 = a2;                 \
        double v0 = b0, v1 = b1, v2 = b2;                 \
        a0 = c * u0 + s * v0;                             \
        a1 = c * u1 + s * v1;                             \
        a2 = c * u2 + s * v2;                             \
        b0 = c * v0 - s * u0;                             \
        b1 = c * v1 - s * u1;                             \
        b2 = c * v2 - s * u2;                             \
    } while (0)

void symkin_ets_fkjac(const symkin_ets *ets, const double *q, double *T, double *J) {
    double cs[SYMKIN_IK_NMAX][2];
    for (int i = 0, k = 0; i < ets->len; i++) {
        const symkin_et *e = ets->et + i;
        if (e->joint < 0 || e->axis < 3) continue;
        double x = e->sign * q[e->joint];
        cs[k][0] = cos(x);
        cs[k][1] = sin(x);
        k++;
    }
    double r00 = 1.0, r01 = 0.0, r02 = 0.0, r10 = 0.0, r11 = 1.0, r12 = 0.0, r20 = 0.0, r21 = 0.0, r22 = 1.0;
    double p0 = 0.0, p1 = 0.0, p2 = 0.0;
    double w[SYMKIN_IK_NMAX][3], o[SYMKIN_IK_NMAX][3];
    int col[SYMKIN_IK_NMAX], rev[SYMKIN_IK_NMAX];
    int k = 0, kr = 0;
    for (int i = 0; i < ets->len; i++) {
        const symkin_et *e = ets->et + i;
        int axis = e->axis;
        double c = e->c, s = e->s, d = e->d;
        if (e->joint >= 0) {
            double sg = e->sign;
            switch (axis) {
            case 0:
            case 3: w[k][0] = sg * r00, w[k][1] = sg * r10, w[k][2] = sg * r20; break;
            case 1:
            case 4: w[k][0] = sg * r01, w[k][1] = sg * r11, w[k][2] = sg * r21; break;
            default: w[k][0] = sg * r02, w[k][1] = sg * r12, w[k][2] = sg * r22; break;
            }
            o[k][0] = p0, o[k][1] = p1, o[k][2] = p2;
            col[k] = e->joint;
            rev[k] = axis >= 3;
            k++;
            if (axis >= 3) {
                c = cs[kr][0];
                s = cs[kr][1];
                kr++;
            } else {
                d = sg * q[e->joint];
            }
        }
        switch (axis) {
        case 0: p0 += d * r00, p1 += d * r10, p2 += d * r20; break;
        case 1: p0 += d * r01, p1 += d * r11, p2 += d * r21; break;
        case 2: p0 += d * r02, p1 += d * r12, p2 += d * r22; break;
        case 3: SYMKIN_ROT(r01, r11, r21, r02, r12, r22, c, s); break;
        case 4: SYMKIN_ROT(r02, r12, r22, r00, r10, r20, c, s); break;
        default: SYMKIN_ROT(r00, r10, r20, r01, r11, r21, c, s); break;
        }
    }
    T[0] = r00, T[1] = r01, T[2] = r02, T[3] = p0;
    T[4] = r10, T[5] = r11, T[6] = r12, T[7] = p1;
    T[8] = r20, T[9] = r21, T[10] = r22, T[11] = p2;
    T[12] = T[13] = T[14] = 0.0;
    T[15] = 1.0;
    int n = ets->n;
    for (int m = 0; m < k; m++) {
        int j = col[m];
        if (rev[m]) {
            double dx = p0 - o[m][0], dy = p1 - o[m][1], dz = p2 - o[m][2];
            J[0 * n + j] = w[m][1] * dz - w[m][2] * dy;
            J[1 * n + j] = w[m][2] * dx - w[m][0] * dz;
            J[2 * n + j] = w[m][0] * dy - w[m][1] * dx;
            J[3 * n + j] = w[m][0];
            J[4 * n + j] = w[m][1];
            J[5 * n + j] = w[m][2];
        } else {
            J[0 * n + j] = w[m][0];
            J[1 * n + j] = w[m][1];
            J[2 * n + j] = w[m][2];
            J[3 * n + j] = J[4 * n + j] = J[5 * n + j] = 0.0;
        }
    }
}

