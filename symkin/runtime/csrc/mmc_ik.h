/*
 * mmc_ik.h: the QP step of numerical inverse kinematics on the MMC machinery (see mmc_ik.c).
 */
#ifndef SYMKIN_MMC_IK_H
#define SYMKIN_MMC_IK_H

#include <stdint.h>

#include "mmc.h"

/* One QP IK step's context: the controller (lam, bounds, collision rows; its slack weight is set by
 * every step), and slack, the gain lambda_delta of the slack weight lambda_delta / sum |e|. */
typedef struct {
    symkin_mmc_ctrl *ctrl;
    int32_t collision; /* 1: the step with the controller's collision rows (symkin_mmc6d_step) */
    int32_t pad_;
    double slack;
} symkin_mmc_ik_ctx;

/* A symkin_ik_step_fn (symkin_ik.h): dq (MMC_N) at q from the pose error e (6); J is not used.
 * Returns 1 when e is not finite or the step failed, else 0. */
MMC_API int symkin_mmc_ik_step(void *ctx, const double *q, const double *J, const double *e, double *dq);

/* sizeof(symkin_mmc_ik_ctx) (for layout checks). */
MMC_API void symkin_mmc_ik_layout(int32_t *out);

#endif /* SYMKIN_MMC_IK_H */
