/* symkin numerical inverse kinematics in C (Haviland and Corke 2023, eqs 37-51).
 *
 * The solver loop of symkin/runtime/ik.py, step for step: the same pose error, the same NR / GN /
 * LM steps, the same restarts (splitmix64 streams) and the same joint-limit handling, so both take
 * the same iterates from the same start. No allocation: every work array lives on the stack,
 * sized for SYMKIN_IK_NMAX joints.
 *
 * Kinematics come through a function pointer (generated code) or, when that is NULL, through the
 * table-driven ETS interpreter symkin_ets_fkjac (symkin_ets.c).
 */
#ifndef SYMKIN_IK_H
#define SYMKIN_IK_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define SYMKIN_IK_NMAX 12

/* Forward kinematics and base-frame Jacobian in one pass.
 * q: n joint values; T: 16 doubles, row-major 4x4 0T_e; J: 6*n doubles, row-major (6, n),
 * rows (v, omega), v the velocity of the end-effector origin (eqs 31-34). */
typedef void (*symkin_fkjac_fn)(const double *q, double *T, double *J);

/* The same for N configurations (rows of q; T, J one after another): the generated
 * <prefix>_fkine_jacob0_batch, which runs four configurations per step. */
typedef void (*symkin_fkjac_batch_fn)(const double *q, double *T, double *J, ptrdiff_t N);

/* Whether q collides (1), is free (0) or is not a valid configuration (-1), against the packed
 * obstacles env: a generated collision kernel's skcoll_in_collision_packed. */
typedef int (*symkin_collides_fn)(const double *q, const long long *env);

/* A step of the caller's (SYMKIN_IK_QP): dq (n) from q (n), J (6, n) and the pose error e (6) at q;
 * returns 0, or nonzero when it has no step (the search is abandoned, as at a singular solve).
 * The QP step of the MMC library (mmc_ik.c) is one. */
typedef int (*symkin_ik_step_fn)(void *ctx, const double *q, const double *J, const double *e, double *dq);

/* One elementary transform of a table-driven ETS.
 * axis: 0..2 = tx, ty, tz; 3..5 = Rx, Ry, Rz.
 * joint >= 0: the joint variable q[joint] times sign (+1, or -1 for a flipped joint);
 * joint < 0: a constant, (c, s) = (cos, sin) of a rotation or d a translation. */
typedef struct {
    int32_t axis;
    int32_t joint;
    double sign;
    double c;
    double s;
    double d;
} symkin_et;

typedef struct {
    int32_t n;   /* number of joints */
    int32_t len; /* number of elementary transforms */
    const symkin_et *et;
} symkin_ets;

/* T and J0 of a table-driven ETS (same layout as symkin_fkjac_fn). */
void symkin_ets_fkjac(const symkin_ets *ets, const double *q, double *T, double *J);

enum { SYMKIN_IK_NR = 0, SYMKIN_IK_GN = 1, SYMKIN_IK_LM = 2, SYMKIN_IK_QP = 3 /* cfg->step */ };
enum { SYMKIN_DAMP_WAMPLER = 0, SYMKIN_DAMP_CHAN = 1, SYMKIN_DAMP_SUGIHARA = 2 };

/* Pose-check codes (symkin_ik_check_pose, symkin_ik_stats.status). */
enum {
    SYMKIN_POSE_OK = 0,
    SYMKIN_POSE_NONFINITE = 1,
    SYMKIN_POSE_BOTTOM_ROW = 2,
    SYMKIN_POSE_NOT_ORTHONORMAL = 3,
    SYMKIN_POSE_REFLECTION = 4,
    SYMKIN_Q0_NONFINITE = 5 /* symkin_ik_solve: q0 has NaN or inf */
};

typedef struct {
    int32_t n;
    int32_t method;       /* SYMKIN_IK_NR / GN / LM / QP */
    int32_t damping;      /* SYMKIN_DAMP_*, LM only */
    int32_t pinv;         /* NR, GN: pseudo-inverse instead of a plain solve */
    int32_t ilimit;       /* iterations (pose evaluations) per search, >= 1 */
    int32_t slimit;       /* searches, >= 1 */
    int32_t tol_on_E;     /* 0: converged when |e|_We < tol; 1: when E = |e|_We^2 / 2 < tol */
    int32_t joint_limits; /* reject converged q outside [qlo, qhi] (after wrapping) */
    int32_t nstarts;      /* rows of starts */
    int32_t pad_;
    double tol;
    double we[6];          /* diagonal of We (eq 44) */
    const double *lam;     /* (n,) damping lambda (Wampler, Chan) or w_n (Sugihara) */
    const double *qlo;     /* (n,) joint limits */
    const double *qhi;
    const double *slo;     /* (n,) range random restarts are drawn from (finite) */
    const double *shi;
    const int32_t *revolute; /* (n,) 1 for revolute joints (wrapped by 2 pi) */
    const double *starts;  /* (nstarts, n): search s starts at starts[s]; NULL when nstarts = 0 */
    symkin_fkjac_fn fkjac; /* generated kinematics, or NULL to use ets */
    const symkin_ets *ets;
    symkin_fkjac_batch_fn fkjac_batch; /* fkjac of several configurations, or NULL: a batch of LM
                                          solves evaluates its lanes' poses in one call */
    symkin_collides_fn collides;       /* NULL, or converged q that collide are rejected (the next */
    const long long *collision_env;    /* search starts, as for joint limits), against this env */
    symkin_ik_step_fn step;            /* SYMKIN_IK_QP: the step, called with step_ctx */
    void *step_ctx;
} symkin_ik_config;

typedef struct {
    double residual;       /* |e|_We at the returned q */
    int32_t success;
    int32_t iterations;    /* pose evaluations, failed searches included */
    int32_t searches;
    int32_t limit_rejects; /* converged searches rejected for joint limits */
    int32_t singular;      /* searches abandoned: singular solve or non-finite pose */
    int32_t status;        /* SYMKIN_POSE_* of the target; nothing is solved unless OK */
    int32_t collision_rejects; /* converged searches rejected: in collision (cfg->collides) */
    int32_t pad_;
} symkin_ik_stats;

int32_t symkin_ik_nmax(void);
void symkin_ik_layout(int32_t *out); /* sizeof symkin_ik_stats, sizeof symkin_ik_config */

/* SYMKIN_POSE_* for a row-major 4x4 target; *deviation gets max |R^T R - I| (or 0). */
int32_t symkin_ik_check_pose(const double *T, double *deviation);

/* e of eq 37 (translation, angle-axis of Tep_R T_R^T) for row-major 4x4 T and Tep. */
void symkin_ik_pose_error(const double *T, const double *Tep, double *e);

/* Solve one target. q0 may be NULL (first search from starts[0] or random). Random restarts use
 * the splitmix64 stream (seed, 0). Returns the pose status (or SYMKIN_Q0_NONFINITE); q and st are
 * filled when it is OK. */
int32_t symkin_ik_solve(const symkin_ik_config *cfg, const double *Tep, const double *q0, uint64_t seed,
                        double *q, symkin_ik_stats *st);

/* Solve N targets (N x 16). q0: NULL, one (n,) start for all (q0_stride 0) or one row per target
 * (q0_stride n). Target i uses the stream (seed, i). Every pose is checked first: returns -1 when
 * all are valid, else the index of the first invalid one (its st[i].status says why) and solves
 * nothing. */
int64_t symkin_ik_solve_batch(const symkin_ik_config *cfg, int64_t N, const double *Tep, const double *q0,
                              int64_t q0_stride, uint64_t seed, double *q, symkin_ik_stats *st);

/* For benchmarks (symkin bench calls): N targets one at a time, as N calls of symkin_ik_solve
 * with the seeds seed, seed + 1, ... (no lanes); returns -1, or the index of the first invalid
 * target (solved up to it). */
int64_t symkin_ik_solve_each(const symkin_ik_config *cfg, int64_t N, const double *Tep, const double *q0,
                             int64_t q0_stride, uint64_t seed, double *q, symkin_ik_stats *st);

/* For benchmarks: the solver's kinematics at N configurations q (N x n), one at a time, into T
 * (16) and J (6 n), overwritten each time. */
void symkin_ik_kin_each(const symkin_ik_config *cfg, int64_t N, const double *q, double *T, double *J);

/* The iterates of one search from q0 without stopping at convergence: qs gets q_0 .. q_steps
 * ((steps + 1) x n). Returns how many iterates were written (fewer if a step failed). */
int32_t symkin_ik_trace(const symkin_ik_config *cfg, const double *Tep, const double *q0, int32_t steps,
                        double *qs);

/* count random configurations of the stream (seed, stream) into out (count x n), as the solver
 * draws its restarts. */
void symkin_ik_random_q(const symkin_ik_config *cfg, uint64_t seed, int64_t stream, int32_t count, double *out);

#ifdef __cplusplus
}
#endif

#endif /* SYMKIN_IK_H */
