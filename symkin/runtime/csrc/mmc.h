/*
 * mmc.h: one step of the Manipulability Motion Controller (Haviland and Corke 2020, eq 12) in C.
 *
 * A library for robots of MMC_N joints (mmc_config.h) holds the embedded OSQP sources emitted by
 * osqp.OSQP.codegen for the MMC QP without slack (solver mmcqp0_solver) and with the equality
 * slack (mmcqp6_solver), and mmc_impl.h compiled once for each (mmc_s0.c, mmc_s6.c, which define
 * MMC_NS, MMC_SOLVER and MMC_FN); a library with MMC_K > 0 (MMC with collision avoidance) also
 * holds the variant with the slack and MMC_K distance rows (mmcqp6d_solver, mmc_s6d.c). The robot's kinematics come as a function pointer to its
 * generated jacob0_hessian0. See symkin/runtime/mmc_c.py; the Python reference is
 * symkin.runtime.control.MMC.
 */
#ifndef SYMKIN_MMC_H
#define SYMKIN_MMC_H

#include <stdint.h>

#include "mmc_config.h" /* MMC_N, MMC_K */

#ifndef MMC_K
#define MMC_K 0 /* collision rows of the distance variant (0: the library has none) */
#endif

#if defined(__GNUC__)
#define MMC_API __attribute__((visibility("default")))
#else
#define MMC_API
#endif

#define MMC_NINFO 9 /* info values written after qd */

/* Base-frame Jacobian J (6, n) and Hessian H (n, 6, n), row-major, at q (n): generated code. */
typedef void (*symkin_mmc_jh_fn)(const double *q, double *J, double *H);
/* One output at q: the base-frame Jacobian J (6, n) or the pose T (4, 4), row-major (generated). */
typedef void (*symkin_mmc_kin_fn)(const double *q, double *out);
/* Manipulability of the rows of J0 chosen by axes (0 all, 1 trans, 2 rot) at q (generated). */
typedef double (*symkin_mmc_m_fn)(const double *q, int axes);

/* The signed distance of every active pair of the robot's geometry and the obstacles S (ns spheres),
 * C (nc capsules), B (nb boxes) at q, and their gradient rows J (pairs, n) (generated FKCC code,
 * skcoll_distances of symkin.emit.collision). */
typedef void (*symkin_mmc_dist_fn)(const double *q, const double *S, int ns, const double *C, int nc,
                                   const double *B, int nb, double *d, double *J);
/* The gradient rows J (k, n) of the k pairs idx (skcoll_distance_rows). */
typedef void (*symkin_mmc_rows_fn)(const double *q, const double *S, int ns, const double *C, int nc,
                                   const double *B, int nb, const int *idx, int k, double *J);

/* Options and per-controller solver state; one per controller, owned by the caller. An RRMC
 * controller (symkin_rrmc_step) uses j0, axes, singular_tol, damping and qd_max only. */
typedef struct {
    symkin_mmc_jh_fn jh;  /* the robot's kinematics */
    symkin_mmc_kin_fn j0; /* its jacob0 (RRMC) */
    symkin_mmc_kin_fn fk; /* its fkine (servo loop) */
    symkin_mmc_m_fn manip; /* its manipulability (servo loop: the last configuration) */
    int32_t axes;         /* manipulability rows: 0 all, 1 translation, 2 rotation */
    int32_t closed_form;  /* try J+ nu + (I - J+ J) Jm / lam first */
    int32_t active_set;   /* with closed_form: when the closed form leaves the bounds, an active-set
                             solve from the bounds it crosses before OSQP */
    int32_t joint_limits; /* velocity dampers (joint_velocity_bounds of control.py) */
    int32_t bounded;      /* any finite bound: the closed form must be checked against them */
    int32_t polish;       /* active-set polish of OSQP's solution (OSQP's own is not embedded) */
    int32_t has_dt;       /* bound each step's joint motion by the distance to the limit */
    int32_t fresh;        /* 1 until this controller's first OSQP solve: cold start */
    int32_t polished;     /* out: the last step's OSQP answer was replaced by the active-set one */
    int32_t no_jm;        /* no manipulability term (Jm = 0): only J is evaluated (the QP IK step) */
    int32_t singular_qp;  /* with the slack, a singular J still gets the QP (Jm = 0) instead of the
                             fallback (the QP IK step) */
    int32_t pad_;
    double lam, slack_weight, xi, dt, singular_tol, damping, rho0;
    double qlo[MMC_N], qhi[MMC_N], qd_max[MMC_N], rho_i[MMC_N], rho_s[MMC_N];
    /* this controller's OSQP state, restored when another controller used the solver in between:
       rho (adapted by OSQP) and the iterate (x, z, y as OSQP holds them, scaled) */
    double rho;
    double x[MMC_N + 6];
    double z[6 + MMC_N + MMC_K];
    double y[6 + MMC_N + MMC_K];
    /* collision avoidance (symkin_mmc6d_step): the distance functions, the obstacles (owned by the
       caller), a buffer for the distances of all pairs, and the velocity damper
       d_dot >= -xi_d (d - d_s) / (d_i - d_s) of the MMC_K closest pairs within d_i */
    symkin_mmc_dist_fn dist;
    symkin_mmc_rows_fn rows;
    const double *env_s, *env_c, *env_b;
    double *dbuf;
    int32_t env_ns, env_nc, env_nb, pairs;
    double d_i, d_s, xi_d;
    double d_i_self, d_s_self; /* the self pairs' (the first self_pairs of the distances) */
    int32_t self_pairs;
    /* the last obstacle step's settled active set (warm start of the next): warm (0/1), nwarm
       pairs, the bounds (-1 lower, 1 upper, 2 fixed, 0 free) and the active pairs' indices */
    int32_t warm, nwarm;
    int32_t wact[MMC_N];
    int32_t wpair[MMC_K > 0 ? MMC_K : 1];
} symkin_mmc_ctrl;

/* info[0] status */
enum { MMC_SOLVED, MMC_SINGULAR, MMC_INFEASIBLE, MMC_MAX_ITER, MMC_INACCURATE, MMC_ERROR };
/* info[1] method (MMC; RRMC: inverse, pinv or damped) */
enum { MMC_CLOSED_FORM, MMC_OSQP, MMC_ACTIVE_SET, MMC_INVERSE, MMC_PINV, MMC_DAMPED };
/* info[4] fallback */
enum { MMC_NO_FALLBACK, MMC_FALLBACK_RRMC, MMC_FALLBACK_ZERO };

/*
 * One step (symkin_mmc0_step without slack, symkin_mmc6_step with): in = (q[n], nu[6]);
 * out = (qd[n], status, method, manipulability, iterations, fallback, residual max|J qd - nu|,
 * |slack|, scale, polished). Returns 0, or 1 when q is not finite, 2 when nu is not finite (out
 * untouched). Not thread-safe: the controllers of a library share its two embedded solvers; each
 * restores its own OSQP state (iterate and rho) when it takes a solver over, so a controller's
 * answers do not depend on the others.
 */
MMC_API int symkin_mmc0_step(symkin_mmc_ctrl *c, const double *in, double *out);
MMC_API int symkin_mmc6_step(symkin_mmc_ctrl *c, const double *in, double *out);
#if MMC_K
/* The step with the slack and MMC_K collision rows (MMC(collision=...)): the distances come from
 * c->dist; when a pair lies within d_i the closed form, the active set and the polish (which know
 * only the bounds) are skipped and the QP with the damper rows goes to OSQP. */
MMC_API int symkin_mmc6d_step(symkin_mmc_ctrl *c, const double *in, double *out);
#endif

/*
 * One resolved-rate step (Haviland and Corke 2023, eqs 35-36; symkin.runtime.control.rrmc): qd = J^T (J J^T)^-1 nu
 * (J^-1 nu for 6 joints), or J^T (J J^T + damping^2 I)^-1 nu when the smallest singular value of J
 * is below singular_tol or n < 6 (status singular, method damped); then scaled down as a whole to
 * |qd_i| <= qd_max_i. Same in and out as symkin_mmc0_step (iterations 0, no fallback, no slack).
 */
MMC_API int symkin_rrmc_step(symkin_mmc_ctrl *c, const double *in, double *out);

/* n, sizeof(symkin_mmc_ctrl), MMC_NINFO (for layout checks). */
MMC_API void symkin_mmc_layout(int32_t *out);

#endif /* SYMKIN_MMC_H */
