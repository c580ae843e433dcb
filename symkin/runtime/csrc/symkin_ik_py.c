/* CPython entry point of the C IK solver: one target solved in one call from Python.
 *
 * Compiled into the same library as symkin_ik.c (see symkin/runtime/ik_c.py, which also reaches
 * the library through ctypes for batches) with -DSYMKIN_IK_MODULE=<module name>. The call takes
 * the ndarray directly, releases the GIL while it solves (not for the QP method, whose step uses the
 * MMC library's shared solvers) and keeps every buffer on the stack or in new arrays, so threads
 * can solve with one solver at the same time. It builds the IKResult itself
 * (the frozen dataclass's __init__ would cost more than the Python side of the rest).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>
#include <math.h>
#include <stddef.h>

#include "symkin_ik.h"
#include "symkin_pyarray.h"

#ifndef SYMKIN_IK_MODULE
#error "compile with -DSYMKIN_IK_MODULE=<module name>"
#endif

#define SK_NFIELDS 6 /* IKResult: q, success, iterations, searches, residual, reason */
static PyObject *result_type_ = NULL;
static PyObject *slots_[SK_NFIELDS]; /* member descriptors of IKResult's slots, or NULL */
static PyObject *success_ = NULL;    /* "success" */
static uint64_t seed_state_ = 0;     /* fresh seeds (splitmix64), advanced with the GIL held */

#ifdef SYMKIN_IK_PROFILE
/* For symkin bench calls (a library built with -DSYMKIN_IK_PROFILE): the nanoseconds of each part
 * of a call of solve_, summed over the calls until profile() returns and resets them. */
#include <time.h>
enum { SK_ARGS, SK_GIL, SK_SOLVER, SK_RESULT, SK_NPARTS };
static double prof_ns_[SK_NPARTS];
static long long prof_calls_;

static double prof_now_(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return 1e9 * (double)t.tv_sec + (double)t.tv_nsec;
}
/* the time since *t into part, and *t = now */
static void prof_add_(int part, double *t)
{
    const double now = prof_now_();
    prof_ns_[part] += now - *t;
    *t = now;
}
#define SK_PROF_(part, t) prof_add_(part, &(t))
#define SK_PROF_START_(t) double t = prof_now_()

/* profile() -> (calls, arguments ns, GIL release and retake ns, solver ns, result ns), reset */
static PyObject *py_profile(PyObject *self, PyObject *unused)
{
    PyObject *r = Py_BuildValue("(Ldddd)", prof_calls_, prof_ns_[SK_ARGS], prof_ns_[SK_GIL], prof_ns_[SK_SOLVER],
                                prof_ns_[SK_RESULT]);
    prof_calls_ = 0;
    for (int k = 0; k < SK_NPARTS; ++k)
        prof_ns_[k] = 0.0;
    return r;
}
#else
#define SK_PROF_(part, t) ((void)0)
#define SK_PROF_START_(t) ((void)0)
#endif

static uint64_t next_seed_(void)
{
    uint64_t z = (seed_state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

/* setup(IKResult, entropy): the result type (its slot descriptors are used when they are plain
 * member descriptors, else the type is called) and 64 bits of entropy for fresh seeds. */
static PyObject *py_setup(PyObject *self, PyObject *args)
{
    static const char *names[SK_NFIELDS] = {"q", "success", "iterations", "searches", "residual", "reason"};
    PyObject *type;
    unsigned long long entropy;
    if (!PyArg_ParseTuple(args, "OK", &type, &entropy))
        return NULL;
    if (!PyType_Check(type)) {
        PyErr_SetString(PyExc_TypeError, "setup() needs the IKResult type");
        return NULL;
    }
    Py_XDECREF(result_type_);
    result_type_ = Py_NewRef(type);
    seed_state_ = (uint64_t)entropy;
    return PyBool_FromLong(member_slots_(type, names, SK_NFIELDS, slots_));
}

/* One target (see py_solve): an IKResult, None when the arguments need checking, or NULL with an
 * error set. */
static PyObject *solve_(const symkin_ik_config *cfg, PyObject *reason, PyObject *Tep, PyObject *q0arg,
                        PyObject *seedarg)
{
    SK_PROF_START_(t);
    if (!result_type_) {
        PyErr_SetString(PyExc_RuntimeError, "setup() was not called");
        return NULL;
    }
    const int n = cfg->n;
    uint64_t seed;
    if (seedarg == Py_None) {
        seed = next_seed_();
    } else if (PyLong_CheckExact(seedarg)) {
        seed = (uint64_t)PyLong_AsUnsignedLongLongMask(seedarg);
        if (PyErr_Occurred())
            return NULL;
    } else {
        Py_RETURN_NONE;
    }
    PyArrayObject *T = as_doubles_(Tep, 2, 4, 4), *q0 = NULL;
    if (!T)
        Py_RETURN_NONE;
    if (q0arg != Py_None) {
        q0 = as_doubles_(q0arg, 1, n, 0);
        int ok = q0 != NULL;
        for (int j = 0; ok && j < n; ++j) /* joint values: symkin.core.arrays.MAX_JOINT_VALUE */
            ok = fabs(((const double *)PyArray_DATA(q0))[j]) <= 1e15;
        if (!ok) {
            Py_DECREF(T);
            Py_XDECREF(q0);
            Py_RETURN_NONE;
        }
    }
    npy_intp dim = n;
    PyArrayObject *q = (PyArrayObject *)PyArray_SimpleNew(1, &dim, NPY_DOUBLE);
    if (!q) {
        Py_DECREF(T);
        Py_XDECREF(q0);
        return NULL;
    }
    symkin_ik_stats st;
    int32_t status;
    const double *Tp = (const double *)PyArray_DATA(T), *q0p = q0 ? (const double *)PyArray_DATA(q0) : NULL;
    double *qp = (double *)PyArray_DATA(q);
    SK_PROF_(SK_ARGS, t);
    if (cfg->method == SYMKIN_IK_QP) { /* the QP step's embedded OSQP solvers are shared: keep the GIL */
        status = symkin_ik_solve(cfg, Tp, q0p, seed, qp, &st);
        SK_PROF_(SK_SOLVER, t);
    } else {
        Py_BEGIN_ALLOW_THREADS
        SK_PROF_(SK_GIL, t);
        status = symkin_ik_solve(cfg, Tp, q0p, seed, qp, &st);
        SK_PROF_(SK_SOLVER, t);
        Py_END_ALLOW_THREADS
        SK_PROF_(SK_GIL, t);
    }
    Py_DECREF(T);
    Py_XDECREF(q0);
    if (status != SYMKIN_POSE_OK) { /* invalid target or q0: the caller raises the detailed error */
        Py_DECREF(q);
        Py_RETURN_NONE;
    }
    PyObject *values[SK_NFIELDS];
    values[0] = (PyObject *)q;
    values[1] = PyBool_FromLong(st.success);
    values[2] = PyLong_FromLong(st.iterations);
    values[3] = PyLong_FromLong(st.searches);
    values[4] = PyFloat_FromDouble(st.residual);
    if (st.success)
        values[5] = Py_NewRef(success_);
    else
        values[5] = PyObject_CallFunction(reason, "diii", st.residual, (int)st.limit_rejects, (int)st.singular,
                                          (int)st.collision_rejects);
    PyObject *r = new_record_(result_type_, slots_, values, SK_NFIELDS);
#ifdef SYMKIN_IK_PROFILE
    SK_PROF_(SK_RESULT, t);
    ++prof_calls_;
#endif
    return r;
}

/* solve(config_address, reason, Tep, q0=None, seed=None) -> IKResult, or None when the arguments
 * are not one valid (4, 4) target, an (n,) finite q0 or None, and an int seed or None (the caller
 * then validates them, raising the detailed error, or solves a batch). reason(residual,
 * limit_rejects, singular, collision_rejects) gives the text of a failure. */
static PyObject *py_solve(PyObject *self, PyObject *const *argv, Py_ssize_t nargs)
{
    if (nargs < 3 || nargs > 5) {
        PyErr_SetString(PyExc_TypeError, "solve(config, reason, Tep, q0=None, seed=None)");
        return NULL;
    }
    const symkin_ik_config *cfg = (const symkin_ik_config *)PyLong_AsVoidPtr(argv[0]);
    if (!cfg)
        return PyErr_Occurred() ? NULL : Py_NewRef(Py_None);
    return solve_(cfg, argv[1], argv[2], nargs > 3 ? argv[3] : Py_None, nargs > 4 ? argv[4] : Py_None);
}

/* ---- a bound solver: kin.ik of one target in one C call --------------------------------------- */
/* ik(Tep) solves one valid target with the solver's options in C. ik(Tep, q0=..., seed=..., **options)
 * looks the options up in by_options (a dict: the tuple of the (name, value) pairs other than q0 and
 * seed, in call order, as Kinematics.ik keys its solvers -> the bound solver of those options) and
 * solves with that solver. Any other call (options not seen yet or unhashable, a positional frame, a
 * batch, an argument that needs checking) goes to the fallback with the same arguments. The object
 * keeps its owner (which owns the config) alive. */
typedef struct {
    PyObject_HEAD
    vectorcallfunc vectorcall;
    const symkin_ik_config *cfg;
    PyObject *reason;
    PyObject *fallback;
    PyObject *owner;
    PyObject *by_options; /* dict or NULL */
} bound_ik_;

static PyTypeObject bound_ik_type_;

/* The solution of ik(Tep, **keywords) through by_options: an IKResult, None (go to the fallback) or
 * NULL with an error set. */
static PyObject *solve_keywords_(bound_ik_ *b, PyObject *Tep, PyObject *const *values, PyObject *kwnames)
{
    const Py_ssize_t nk = PyTuple_GET_SIZE(kwnames);
    PyObject *q0 = Py_None, *seed = Py_None, *r = NULL;
    Py_ssize_t m = nk;
    for (Py_ssize_t i = 0; i < nk; ++i) {
        PyObject *name = PyTuple_GET_ITEM(kwnames, i);
        if (PyUnicode_CompareWithASCIIString(name, "q0") == 0) {
            q0 = values[i];
            --m;
        } else if (PyUnicode_CompareWithASCIIString(name, "seed") == 0) {
            seed = values[i];
            --m;
        }
    }
    PyObject *key = PyTuple_New(m);
    if (!key)
        return NULL;
    for (Py_ssize_t i = 0, k = 0; i < nk; ++i) {
        PyObject *name = PyTuple_GET_ITEM(kwnames, i);
        if (PyUnicode_CompareWithASCIIString(name, "q0") == 0 || PyUnicode_CompareWithASCIIString(name, "seed") == 0)
            continue;
        PyObject *pair = PyTuple_Pack(2, name, values[i]);
        if (!pair)
            goto done;
        PyTuple_SET_ITEM(key, k++, pair);
    }
    PyObject *bound = PyDict_GetItemWithError(b->by_options, key); /* borrowed */
    if (!bound) {
        if (PyErr_Occurred()) { /* an unhashable option (an array, say): the fallback handles it */
            if (!PyErr_ExceptionMatches(PyExc_TypeError))
                goto done;
            PyErr_Clear();
        }
        r = Py_NewRef(Py_None);
    } else if (Py_IS_TYPE(bound, &bound_ik_type_)) {
        Py_INCREF(bound); /* the dict may drop it while another thread runs (the solve releases the GIL) */
        r = solve_(((bound_ik_ *)bound)->cfg, ((bound_ik_ *)bound)->reason, Tep, q0, seed);
        Py_DECREF(bound);
    } else {
        r = Py_NewRef(Py_None);
    }
done:
    Py_DECREF(key);
    return r;
}

static PyObject *bound_ik_call_(PyObject *op, PyObject *const *args, size_t nargsf, PyObject *kwnames)
{
    bound_ik_ *b = (bound_ik_ *)op;
    if (PyVectorcall_NARGS(nargsf) == 1) {
        PyObject *r;
        if (!(kwnames && PyTuple_GET_SIZE(kwnames)))
            r = solve_(b->cfg, b->reason, args[0], Py_None, Py_None);
        else if (b->by_options)
            r = solve_keywords_(b, args[0], args + 1, kwnames);
        else
            r = Py_NewRef(Py_None);
        if (r != Py_None)
            return r;
        Py_DECREF(r);
    }
    return PyObject_Vectorcall(b->fallback, args, nargsf, kwnames);
}

/* The references a bound solver owns, in one list: the garbage collector visits them, and clearing
 * (a cycle broken, the object freed) drops them. */
#define BOUND_IK_REFS_(F) F(reason) F(fallback) F(owner) F(by_options)
#define BOUND_IK_VISIT_(member) Py_VISIT(b->member);
#define BOUND_IK_CLEAR_(member) Py_CLEAR(b->member);

static int bound_ik_traverse_(PyObject *op, visitproc visit, void *arg)
{
    bound_ik_ *b = (bound_ik_ *)op;
    BOUND_IK_REFS_(BOUND_IK_VISIT_)
    return 0;
}

static int bound_ik_clear_(PyObject *op)
{
    bound_ik_ *b = (bound_ik_ *)op;
    BOUND_IK_REFS_(BOUND_IK_CLEAR_)
    return 0;
}

static void bound_ik_dealloc_(PyObject *op)
{
    PyObject_GC_UnTrack(op);
    bound_ik_clear_(op);
    Py_TYPE(op)->tp_free(op);
}

static PyTypeObject bound_ik_type_ = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "symkin.BoundIK",
    .tp_basicsize = sizeof(bound_ik_),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_HAVE_VECTORCALL,
    .tp_doc = "ik(Tep, **options): numerical inverse kinematics (see symkin.runtime.kinematics.Kinematics.ik); "
              "one target with the default options is solved in one C call",
    .tp_vectorcall_offset = offsetof(bound_ik_, vectorcall),
    .tp_call = PyVectorcall_Call,
    .tp_traverse = bound_ik_traverse_,
    .tp_clear = bound_ik_clear_,
    .tp_dealloc = bound_ik_dealloc_,
};

/* bind(config_address, reason, fallback, owner, by_options=None) -> a callable solving one target
 * per call (above) */
static PyObject *py_bind(PyObject *self, PyObject *args)
{
    PyObject *addr, *reason, *fallback, *owner, *by_options = Py_None;
    if (!PyArg_ParseTuple(args, "OOOO|O", &addr, &reason, &fallback, &owner, &by_options))
        return NULL;
    if (by_options != Py_None && !PyDict_CheckExact(by_options)) {
        PyErr_SetString(PyExc_TypeError, "bind() needs a dict by_options, or None");
        return NULL;
    }
    const symkin_ik_config *cfg = (const symkin_ik_config *)PyLong_AsVoidPtr(addr);
    if (!cfg) {
        if (!PyErr_Occurred())
            PyErr_SetString(PyExc_ValueError, "bind() needs the address of a config");
        return NULL;
    }
    if (!PyCallable_Check(reason) || !PyCallable_Check(fallback)) {
        PyErr_SetString(PyExc_TypeError, "bind() needs callables reason and fallback");
        return NULL;
    }
    bound_ik_ *b = PyObject_GC_New(bound_ik_, &bound_ik_type_);
    if (!b)
        return NULL;
    b->vectorcall = bound_ik_call_;
    b->cfg = cfg;
    b->reason = Py_NewRef(reason);
    b->fallback = Py_NewRef(fallback);
    b->owner = Py_NewRef(owner);
    b->by_options = by_options == Py_None ? NULL : Py_NewRef(by_options);
    PyObject_GC_Track((PyObject *)b);
    return (PyObject *)b;
}

static PyMethodDef methods_[] = {
    {"setup", (PyCFunction)py_setup, METH_VARARGS, "setup(IKResult, entropy) -> bool (fast result path)"},
    {"solve", (PyCFunction)(void (*)(void))py_solve, METH_FASTCALL,
     "solve(config_address, reason, Tep, q0=None, seed=None) -> IKResult or None"},
    {"bind", (PyCFunction)py_bind, METH_VARARGS,
     "bind(config_address, reason, fallback, owner, by_options=None) -> ik(Tep, ...) solving one target in C, "
     "else fallback"},
#ifdef SYMKIN_IK_PROFILE
    {"profile", (PyCFunction)py_profile, METH_NOARGS,
     "profile() -> (calls, arguments ns, GIL ns, solver ns, result ns) since the last call"},
#endif
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module_ = {
    PyModuleDef_HEAD_INIT, SK_STR_(SYMKIN_IK_MODULE), "symkin's C IK solver, one target per call", -1, methods_,
};

PyMODINIT_FUNC SK_CAT_(PyInit_, SYMKIN_IK_MODULE)(void)
{
    import_array();
    success_ = PyUnicode_InternFromString("success");
    if (!success_ || PyType_Ready(&bound_ik_type_) < 0)
        return NULL;
    return PyModule_Create(&module_);
}
