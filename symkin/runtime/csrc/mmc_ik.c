/*
 * mmc_ik.c: the step of QP inverse kinematics (Haviland and Corke, Manipulator Differential
 * Kinematics, Part 2, 2023, "advanced numerical IK") on the MMC step of this library, for the search
 * loop of symkin_ik.c (a symkin_ik_step_fn; see symkin/runtime/ik_qp.py for the QP and
 * symkin/runtime/ik_c.py for the loop).
 *
 * One step solves
 *     min 0.5 lam |qd|^2 - Jm.qd + 0.5 (slack / sum|e|) |s|^2  s.t.  J qd + s = e,
 *     lower <= qd <= upper (the joint-limit velocity dampers and |qd_i| <= distance - rho_s),
 *     Jd qd >= d_lower (collision rows, the distance variant)
 * with the controller's lam, bounds and rows (MMC_FN(step) of mmc_impl.h with the slack, its
 * singular_qp flag set, no_jm set when there is no manipulability term), and q + qd is the next
 * iterate. The embedded OSQP solver is cold-started and the collision variant's active-set warm
 * start dropped at every step: a step depends on (q, e) alone, so a target's iterates do not depend
 * on the targets solved before it.
 */
#include <math.h>
#include <string.h>

#include "mmc.h"
#include "mmc_ik.h"

int symkin_mmc_ik_step(void *ctx, const double *q, const double *J, const double *e, double *dq)
{
    (void)J; /* the MMC step evaluates J (and H) itself */
    symkin_mmc_ik_ctx *x = (symkin_mmc_ik_ctx *)ctx;
    symkin_mmc_ctrl *c = x->ctrl;
    double in[MMC_N + 6], out[MMC_N + MMC_NINFO], sum = 0.0;
    for (int i = 0; i < 6; ++i)
        sum += fabs(e[i]);
    if (!(sum > 0.0 && sum < INFINITY))
        return 1;
    c->slack_weight = x->slack / sum;
    c->fresh = 1;
#if MMC_K
    c->warm = 0;
#endif
    memcpy(in, q, sizeof(double) * MMC_N);
    memcpy(in + MMC_N, e, sizeof(double) * 6);
#if MMC_K
    const int rc = x->collision ? symkin_mmc6d_step(c, in, out) : symkin_mmc6_step(c, in, out);
#else
    const int rc = symkin_mmc6_step(c, in, out);
#endif
    if (rc)
        return 1;
    for (int k = 0; k < MMC_N; ++k) {
        if (!isfinite(out[k]))
            return 1;
        dq[k] = out[k];
    }
    return 0;
}

void symkin_mmc_ik_layout(int32_t *out)
{
    out[0] = (int32_t)sizeof(symkin_mmc_ik_ctx);
}
