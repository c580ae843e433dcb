/*
 * mmc_py.c: the CPython entry points of the MMC library (see mmc.h), compiled into it with
 * -DSYMKIN_MMC_MODULE=<module name>: one control step (MMC, RRMC or QRMC) per call, and the whole
 * servo loop of symkin.runtime.loop.servo (Haviland and Corke 2023, eqs 37-43) in C. The library is also reached
 * through ctypes (symkin/runtime/mmc_c.py). The GIL stays held: the controllers of a library share
 * its embedded OSQP solvers.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>
#include <math.h>
#include <string.h>
#include <time.h>

#include "mmc.h"
#include "qrmc.h"
#include "symkin_pose.h"
#include "symkin_pyarray.h"

#ifndef SYMKIN_MMC_MODULE
#error "compile with -DSYMKIN_MMC_MODULE=<module name>"
#endif

#define NQ MMC_N
#define NOUT (MMC_N + MMC_NINFO)
enum { KIND_MMC0 = 0, KIND_RRMC = 1, KIND_QRMC = 2, KIND_MMC6 = 6, KIND_MMC6D = 7 };
typedef int (*step_fn_)(symkin_mmc_ctrl *, const double *, double *);

/* StepInfo and the texts of its codes, from setup() */
static PyObject *info_type_ = NULL, *names_ = NULL; /* names: (statuses, methods, fallbacks) */
static PyObject *slots_[8]; /* StepInfo's member descriptors when it has __slots__, else NULL */
static const char *field_names_[8] = {"status",   "method",   "manipulability", "iterations",
                                      "fallback", "residual", "slack",          "scale"};

static step_fn_ step_of_(long kind)
{
    return kind == KIND_MMC0 ? symkin_mmc0_step
           : kind == KIND_MMC6 ? symkin_mmc6_step
           : kind == KIND_RRMC ? symkin_rrmc_step
           : kind == KIND_QRMC ? symkin_qrmc_step
#if MMC_K
           : kind == KIND_MMC6D ? symkin_mmc6d_step
#endif
                               : NULL;
}

/* setup(StepInfo, statuses, methods, fallbacks): texts by code (tuples) */
static PyObject *py_setup(PyObject *self, PyObject *args)
{
    PyObject *type, *st, *me, *fb;
    if (!PyArg_ParseTuple(args, "OO!O!O!", &type, &PyTuple_Type, &st, &PyTuple_Type, &me, &PyTuple_Type, &fb))
        return NULL;
    if (PyTuple_GET_SIZE(st) < 6 || PyTuple_GET_SIZE(me) < 6 || PyTuple_GET_SIZE(fb) < 3) {
        PyErr_SetString(PyExc_ValueError, "setup: too few status, method or fallback names");
        return NULL;
    }
    Py_XDECREF(info_type_);
    Py_XDECREF(names_);
    info_type_ = Py_NewRef(type);
    names_ = PyTuple_Pack(3, st, me, fb);
    if (!names_)
        return NULL;
    member_slots_(type, field_names_, 8, slots_);
    Py_RETURN_NONE;
}

static PyObject *code_name_(int which, double code)
{
    PyObject *t = PyTuple_GET_ITEM(names_, which);
    Py_ssize_t i = (Py_ssize_t)code;
    if (!(code >= 0.0) || i >= PyTuple_GET_SIZE(t)) {
        PyErr_Format(PyExc_RuntimeError, "MMC step returned an unknown code %g", code);
        return NULL;
    }
    return Py_NewRef(PyTuple_GET_ITEM(t, i));
}

/* StepInfo from the step's info values (status, method, m, iterations, fallback, residual, slack,
 * scale, polished) */
static PyObject *make_info_(const double *info)
{
    PyObject *v[8];
    v[0] = code_name_(0, info[0]);
    v[1] = code_name_(1, info[1]);
    v[2] = PyFloat_FromDouble(info[2]);
    v[3] = PyLong_FromLong((long)info[3]);
    v[4] = code_name_(2, info[4]);
    v[5] = PyFloat_FromDouble(info[5]);
    v[6] = PyFloat_FromDouble(info[6]);
    v[7] = PyFloat_FromDouble(info[7]);
    return new_record_(info_type_, slots_, v, 8);
}

static PyObject *new_array_(int nd, npy_intp d0, npy_intp d1, const double *data)
{
    npy_intp dims[2] = {d0, d1};
    PyObject *a = PyArray_SimpleNew(nd, dims, NPY_DOUBLE);
    if (a && d0 * (nd == 2 ? d1 : 1) > 0)
        memcpy(PyArray_DATA((PyArrayObject *)a), data, sizeof(double) * (size_t)(d0 * (nd == 2 ? d1 : 1)));
    return a;
}

/* never "solved" with a NaN or inf velocity: stop the joints, status "error", fallback "zero" */
static void zero_unless_finite_(const double *nu, double *out)
{
    int finite = 1;
    for (int i = 0; i < NQ; ++i)
        finite &= isfinite(out[i]) != 0;
    if (finite)
        return;
    double res = 0.0;
    for (int i = 0; i < 6; ++i)
        res = fmax(res, fabs(nu[i])); /* max |J 0 - nu| */
    memset(out, 0, sizeof(double) * NQ);
    double *info = out + NQ; /* status, method, m, iterations, fallback, residual, slack, scale, polished */
    info[0] = 5.0;           /* "error" */
    info[3] = 0.0;
    info[4] = 2.0;           /* "zero" */
    info[5] = res;
    info[6] = 0.0;
    info[7] = 1.0;
}

/* step(ctrl_address, kind, q, nu) -> (qd, StepInfo), or None when q (n,) or nu (6,) is not finite
 * numbers of that shape (the caller raises the detailed error) */
static PyObject *py_step(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 4) {
        PyErr_SetString(PyExc_TypeError, "step(ctrl, kind, q, nu)");
        return NULL;
    }
    symkin_mmc_ctrl *c = (symkin_mmc_ctrl *)PyLong_AsVoidPtr(args[0]);
    step_fn_ fn = step_of_(PyLong_AsLong(args[1]));
    if (!c || !fn || !info_type_) {
        if (!PyErr_Occurred())
            PyErr_SetString(PyExc_ValueError, "step: bad controller or kind, or setup() not called");
        return NULL;
    }
    double in[NQ + 6], out[NOUT];
    PyArrayObject *q = as_doubles_(args[2], 1, NQ, 0), *nu = q ? as_doubles_(args[3], 1, 6, 0) : NULL;
    if (!nu) {
        Py_XDECREF(q);
        Py_RETURN_NONE;
    }
    memcpy(in, PyArray_DATA(q), sizeof(double) * NQ);
    memcpy(in + NQ, PyArray_DATA(nu), sizeof(double) * 6);
    Py_DECREF(q);
    Py_DECREF(nu);
    for (int i = 0; i < NQ; ++i)
        if (!(fabs(in[i]) <= 1e15)) /* symkin.core.arrays.MAX_JOINT_VALUE (NaN too) */
            Py_RETURN_NONE;
    if (fn(c, in, out))
        Py_RETURN_NONE; /* q or nu not finite */
    zero_unless_finite_(in + NQ, out);
    PyObject *qd = new_array_(1, NQ, 0, out), *info = qd ? make_info_(out + NQ) : NULL;
    if (!info) {
        Py_XDECREF(qd);
        return NULL;
    }
    PyObject *r = PyTuple_Pack(2, qd, info);
    Py_DECREF(qd);
    Py_DECREF(info);
    return r;
}

static double now_(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* nu[rows] scaled down to norm <= limit (servo.py's _cap) */
static void cap_(double *nu, int r0, int r1, double limit)
{
    double s = 0.0;
    for (int i = r0; i < r1; ++i)
        s += nu[i] * nu[i];
    double norm = sqrt(s);
    if (norm > limit)
        for (int i = r0; i < r1; ++i)
            nu[i] *= limit / norm;
}

typedef struct {
    double *Q, *E, *M;    /* rows 0 .. steps (configurations) */
    double *QD, *info, *times; /* rows 0 .. steps - 1 */
    Py_ssize_t cap;       /* steps the buffers hold */
} servo_buf_;

static void buf_free_(servo_buf_ *b)
{
    double *fields[6] = {b->Q, b->E, b->M, b->QD, b->info, b->times};
    for (int i = 0; i < 6; ++i)
        PyMem_Free(fields[i]);
    memset(b, 0, sizeof *b);
}

static int buf_grow_(servo_buf_ *b, Py_ssize_t cap)
{
    double *p[6];
    size_t rows[6] = {(size_t)(cap + 1) * NQ, (size_t)(cap + 1) * 6, (size_t)(cap + 1),
                      (size_t)cap * NQ,       (size_t)cap * MMC_NINFO, (size_t)cap};
    double **fields[6] = {&b->Q, &b->E, &b->M, &b->QD, &b->info, &b->times};
    for (int i = 0; i < 6; ++i) {
        p[i] = PyMem_Realloc(*fields[i], sizeof(double) * (rows[i] ? rows[i] : 1));
        if (!p[i]) {
            PyErr_NoMemory();
            return -1;
        }
        *fields[i] = p[i];
    }
    b->cap = cap;
    return 0;
}

/* PyArg "O&" converter: a Python int to the address it holds */
static int PyLong_AsVoidPtr_conv_(PyObject *o, void *out)
{
    void *p = PyLong_AsVoidPtr(o);
    if (!p && PyErr_Occurred())
        return 0;
    *(void **)out = p;
    return 1;
}

/* Whether q collides (1), is free (0) or is not a valid configuration (-1) against the packed
 * obstacles env: a generated collision kernel's skcoll_in_collision_packed. */
typedef int (*collides_fn_)(const double *q, const long long *env);

#define SERVO_HALVINGS 10 /* symkin.runtime.loop.SERVO_HALVINGS */

/*
 * servo(ctrl_address, kind, Tep, q0, params[, collide]) -> (Q, QD, E, M, infos, step_time, arrived,
 * limit_violations, blocked), or None when Tep is not a valid (4, 4) target pose (the caller raises
 * the detailed error): the loop of symkin.runtime.loop.servo with the controller's C step. params
 * (13,): gain (6), threshold, dt, nu cap mode (0 none, 1 one cap on |nu|, 2 caps on |v| and
 * |omega|), cap 1, cap 2, axes of the last manipulability, max_steps. Each step: e of eq 37 at
 * fkine(q); stop when sum |e| < threshold or after max_steps steps; nu = gain e (capped), qd from
 * the controller, q += dt qd. collide (None, or (address of skcoll_in_collision_packed, address of
 * the packed obstacles)): a step whose next q the kernel does not call free is halved (qd and its
 * info's scale), up to SERVO_HALVINGS times; when no halving is free the step is not taken, the loop
 * stops and blocked is True. limit_violations counts the configurations after q0 outside
 * [qlo, qhi] of the ctrl.
 */
static PyObject *py_servo(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 5 && nargs != 6) {
        PyErr_SetString(PyExc_TypeError, "servo(ctrl, kind, Tep, q0, params[, collide])");
        return NULL;
    }
    collides_fn_ collides = NULL;
    const long long *cenv = NULL;
    if (nargs == 6 && args[5] != Py_None) {
        void *fp = NULL, *ep = NULL;
        if (!PyArg_ParseTuple(args[5], "O&O&", PyLong_AsVoidPtr_conv_, &fp, PyLong_AsVoidPtr_conv_, &ep))
            return NULL;
        collides = (collides_fn_)fp;
        cenv = (const long long *)ep;
        if (!collides || !cenv) {
            PyErr_SetString(PyExc_ValueError, "servo: collide must be (function address, obstacles address)");
            return NULL;
        }
    }
    symkin_mmc_ctrl *c = (symkin_mmc_ctrl *)PyLong_AsVoidPtr(args[0]);
    step_fn_ fn = step_of_(PyLong_AsLong(args[1]));
    if (!c || !fn || !info_type_ || !c->fk || !c->manip) {
        if (!PyErr_Occurred())
            PyErr_SetString(PyExc_ValueError, "servo: bad controller or kind, or setup() not called");
        return NULL;
    }
    PyArrayObject *T = (PyArrayObject *)PyArray_FROM_OTF(args[2], NPY_DOUBLE, NPY_ARRAY_IN_ARRAY);
    if (!T)
        return NULL;
    if (PyArray_NDIM(T) != 2 || PyArray_DIM(T, 0) != 4 || PyArray_DIM(T, 1) != 4 ||
        symkin_pose_check((const double *)PyArray_DATA(T), NULL)) {
        Py_DECREF(T);
        Py_RETURN_NONE;
    }
    PyArrayObject *q0 = as_doubles_(args[3], 1, NQ, 0);
    PyArrayObject *pa = q0 ? as_doubles_(args[4], 1, 13, 0) : NULL;
    if (!pa) {
        Py_DECREF(T);
        Py_XDECREF(q0);
        PyErr_SetString(PyExc_ValueError, "servo: q0 (n,) and 13 parameters expected");
        return NULL;
    }
    double Tep[16], par[13];
    memcpy(Tep, PyArray_DATA(T), sizeof Tep);
    memcpy(par, PyArray_DATA(pa), sizeof par);
    const double *gain = par, threshold = par[6], dt = par[7], c1 = par[9], c2 = par[10];
    const int cap_mode = (int)par[8], axes = (int)par[11];
    const double max_steps = par[12];
    servo_buf_ b = {0};
    PyObject *r = NULL;
    Py_ssize_t steps = 0;
    int arrived = 0, blocked = 0;
    if (buf_grow_(&b, 64) < 0)
        goto done;
    memcpy(b.Q, PyArray_DATA(q0), sizeof(double) * NQ);
    for (;;) {
        if (steps == b.cap && buf_grow_(&b, 2 * b.cap) < 0) /* room for one more step */
            goto done;
        const double *q = b.Q + steps * NQ;
        double T_[16], *e = b.E + steps * 6, in[NQ + 6], out[NOUT], sum = 0.0;
        c->fk(q, T_);
        symkin_pose_error(T_, Tep, e);
        for (int i = 0; i < 6; ++i)
            sum += fabs(e[i]);
        if (sum < threshold) {
            arrived = 1;
            break;
        }
        if ((double)steps >= max_steps)
            break;
        memcpy(in, q, sizeof(double) * NQ);
        for (int i = 0; i < 6; ++i)
            in[NQ + i] = gain[i] * e[i];
        if (cap_mode == 1)
            cap_(in + NQ, 0, 6, c1);
        else if (cap_mode == 2) {
            cap_(in + NQ, 0, 3, c1);
            cap_(in + NQ, 3, 6, c2);
        }
        double t0 = now_();
        int rc = fn(c, in, out);
        b.times[steps] = now_() - t0;
        if (rc) {
            PyErr_Format(PyExc_FloatingPointError, "servo: non-finite %s at step %zd", rc == 1 ? "q" : "nu",
                         steps);
            goto done;
        }
        zero_unless_finite_(in + NQ, out);
        double *qn = b.Q + (steps + 1) * NQ;
        for (int k = 0; k < NQ; ++k)
            qn[k] = q[k] + dt * out[k];
        if (collides) { /* the step's acceptance: halve it until the kernel calls q free */
            int h = 0, hit = collides(qn, cenv);
            for (; hit != 0 && h < SERVO_HALVINGS; ++h) {
                for (int k = 0; k < NQ; ++k) {
                    out[k] *= 0.5;
                    qn[k] = q[k] + dt * out[k];
                }
                out[NQ + 7] *= 0.5; /* the info's scale */
                hit = collides(qn, cenv);
            }
            if (hit != 0) { /* no part of the step is free: not taken */
                blocked = 1;
                break;
            }
        }
        memcpy(b.QD + steps * NQ, out, sizeof(double) * NQ);
        memcpy(b.info + steps * MMC_NINFO, out + NQ, sizeof(double) * MMC_NINFO);
        b.M[steps] = out[NQ + 2];
        ++steps;
        if (steps % 4096 == 0 && PyErr_CheckSignals() < 0)
            goto done;
    }
    b.M[steps] = c->manip(b.Q + steps * NQ, axes);
    long violations = 0;
    for (Py_ssize_t k = 1; k <= steps; ++k) {
        const double *q = b.Q + k * NQ;
        for (int j = 0; j < NQ; ++j)
            if (q[j] < c->qlo[j] || q[j] > c->qhi[j]) {
                ++violations;
                break;
            }
    }
    {
        PyObject *infos = PyTuple_New(steps);
        if (!infos)
            goto done;
        for (Py_ssize_t k = 0; k < steps; ++k) {
            PyObject *info = make_info_(b.info + k * MMC_NINFO);
            if (!info) {
                Py_DECREF(infos);
                goto done;
            }
            PyTuple_SET_ITEM(infos, k, info);
        }
        r = Py_BuildValue("(NNNNNNOlO)", new_array_(2, steps + 1, NQ, b.Q), new_array_(2, steps, NQ, b.QD),
                          new_array_(2, steps + 1, 6, b.E), new_array_(1, steps + 1, 0, b.M), infos,
                          new_array_(1, steps, 0, b.times), arrived ? Py_True : Py_False, violations,
                          blocked ? Py_True : Py_False);
    }
done: /* the result, or NULL after an error */
    buf_free_(&b);
    Py_DECREF(T);
    Py_DECREF(q0);
    Py_DECREF(pa);
    return r;
}

static PyMethodDef methods_[] = {
    {"setup", (PyCFunction)py_setup, METH_VARARGS, "setup(StepInfo, statuses, methods, fallbacks)"},
    {"step", (PyCFunction)(void (*)(void))py_step, METH_FASTCALL, "step(ctrl, kind, q, nu) -> (qd, info) or None"},
    {"servo", (PyCFunction)(void (*)(void))py_servo, METH_FASTCALL,
     "servo(ctrl, kind, Tep, q0, params[, collide]) -> (Q, QD, E, M, infos, step_time, arrived, violations, "
     "blocked) or None"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module_ = {
    PyModuleDef_HEAD_INIT, SK_STR_(SYMKIN_MMC_MODULE), "symkin's MMC and RRMC steps and servo loop in C", -1,
    methods_,
};

PyMODINIT_FUNC SK_CAT_(PyInit_, SYMKIN_MMC_MODULE)(void)
{
    import_array();
    PyObject *m = PyModule_Create(&module_);
    if (m)
        PyModule_AddIntConstant(m, "n", NQ);
    return m;
}
