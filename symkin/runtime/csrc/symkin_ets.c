/* Table-driven ETS kinematics: T and the base-frame Jacobian by the O(n) method of seed 000
 * (eqs 31-34). The pose is kept as a rotation R (row-major 3x3) and a position p; each
 * elementary transform updates only what it touches (a rotation mixes two columns of R, a
 * translation moves p along one column). Before each joint its base-frame axis w (signed) and,
 * for a revolute joint, the origin o are recorded; at the end
 *   revolute column: (w x (p_e - o); w),   prismatic column: (w; 0).
 */
#include <math.h>

#include "symkin_ik.h"

/* rotation about axis i mixes the columns (j, k): Rx (1, 2), Ry (2, 0), Rz (0, 1) */
static const int ROT_J[3] = {1, 2, 0};
static const int ROT_K[3] = {2, 0, 1};

void symkin_ets_fkjac(const symkin_ets *ets, const double *q, double *T, double *J) {
    double R[9] = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
    double p[3] = {0.0, 0.0, 0.0};
    double w[SYMKIN_IK_NMAX][3], o[SYMKIN_IK_NMAX][3];
    int col[SYMKIN_IK_NMAX], rev[SYMKIN_IK_NMAX];
    int k = 0;
    for (int i = 0; i < ets->len; i++) {
        const symkin_et *e = ets->et + i;
        int a = e->axis % 3, rot = e->axis >= 3;
        double c = e->c, s = e->s, d = e->d;
        if (e->joint >= 0) {
            double x = e->sign * q[e->joint];
            for (int r = 0; r < 3; r++) {
                w[k][r] = e->sign * R[3 * r + a];
                o[k][r] = p[r];
            }
            col[k] = e->joint;
            rev[k] = rot;
            k++;
            if (rot) {
                c = cos(x);
                s = sin(x);
            } else {
                d = x;
            }
        }
        if (rot) {
            int cj = ROT_J[a], ck = ROT_K[a];
            for (int r = 0; r < 3; r++) {
                double uj = R[3 * r + cj], uk = R[3 * r + ck];
                R[3 * r + cj] = c * uj + s * uk;
                R[3 * r + ck] = c * uk - s * uj;
            }
        } else {
            for (int r = 0; r < 3; r++) p[r] += d * R[3 * r + a];
        }
    }
    for (int r = 0; r < 3; r++) {
        T[4 * r] = R[3 * r];
        T[4 * r + 1] = R[3 * r + 1];
        T[4 * r + 2] = R[3 * r + 2];
        T[4 * r + 3] = p[r];
    }
    T[12] = T[13] = T[14] = 0.0;
    T[15] = 1.0;
    int n = ets->n;
    for (int m = 0; m < k; m++) {
        int j = col[m];
        if (rev[m]) {
            double dx = p[0] - o[m][0], dy = p[1] - o[m][1], dz = p[2] - o[m][2];
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
