/*
 * symkin_pyarray.h: what the CPython entry points share (mmc_py.c, symkin_ik_py.c): the macros
 * naming the module, the argument conversion and the results (frozen dataclasses) made fast.
 * Include it after <Python.h> and <numpy/arrayobject.h>.
 */
#ifndef SYMKIN_PYARRAY_H
#define SYMKIN_PYARRAY_H

/* the module's name and init function from -DSYMKIN_*_MODULE=<module name> */
#define SK_STR2_(x) #x
#define SK_STR_(x) SK_STR2_(x)
#define SK_CAT2_(a, b) a##b
#define SK_CAT_(a, b) SK_CAT2_(a, b)

/* arg as a C-contiguous, aligned, native float64 array of shape (d0,) (nd 1) or (d0, d1) (nd 2), or
 * NULL without an error set when it is anything else. Only arrays of booleans, integers or floats
 * convert here (exact casts): anything else (lists, long double, complex, strings, objects) gives
 * NULL, and the caller's Python checks (symkin.core.arrays.real_array) convert it or raise. */
static PyArrayObject *as_doubles_(PyObject *arg, int nd, npy_intp d0, npy_intp d1)
{
    PyArrayObject *a;
    if (PyArray_CheckExact(arg) && PyArray_TYPE((PyArrayObject *)arg) == NPY_DOUBLE &&
        PyArray_ISCARRAY_RO((PyArrayObject *)arg) && PyArray_ISNOTSWAPPED((PyArrayObject *)arg)) {
        a = (PyArrayObject *)arg;
        Py_INCREF(a);
    } else {
        if (!PyArray_Check(arg) || !(PyArray_ISBOOL((PyArrayObject *)arg) ||
                                     PyArray_ISINTEGER((PyArrayObject *)arg) || PyArray_ISFLOAT((PyArrayObject *)arg)))
            return NULL;
        a = (PyArrayObject *)PyArray_FROM_OTF(arg, NPY_DOUBLE, NPY_ARRAY_IN_ARRAY | NPY_ARRAY_NOTSWAPPED);
        if (!a) {
            PyErr_Clear();
            return NULL;
        }
    }
    if (PyArray_NDIM(a) != nd || PyArray_DIM(a, 0) != d0 || (nd == 2 && PyArray_DIM(a, 1) != d1)) {
        Py_DECREF(a);
        return NULL;
    }
    return a;
}

/* slots[i]: a new reference to the member descriptor of the field names[i] of type (a dataclass
 * with slots=True) for every i, and 1; else all NULL and 0 */
static int member_slots_(PyObject *type, const char *const *names, int count, PyObject **slots)
{
    int all = PyType_Check(type);
    for (int i = 0; i < count; ++i) {
        Py_CLEAR(slots[i]);
        PyObject *d = all ? PyDict_GetItemString(((PyTypeObject *)type)->tp_dict, names[i]) : NULL; /* borrowed */
        if (d && Py_IS_TYPE(d, &PyMemberDescr_Type))
            slots[i] = Py_NewRef(d);
        else
            all = 0;
    }
    for (int i = 0; !all && i < count; ++i)
        Py_CLEAR(slots[i]);
    return all;
}

/* type(*values) of a frozen dataclass, its fields set through slots (member_slots_) when they are
 * known (its __init__ would cost more than the rest), else by calling it; NULL with an error set.
 * Steals the references of values (a NULL one: its error is set). */
static PyObject *new_record_(PyObject *type, PyObject **slots, PyObject **values, int count)
{
    PyObject *r = NULL;
    int ok = 1;
    for (int i = 0; i < count; ++i)
        ok = ok && values[i];
    if (ok && slots[0]) {
        PyTypeObject *t = (PyTypeObject *)type;
        r = t->tp_alloc(t, 0);
        for (int i = 0; r && i < count; ++i)
            if (Py_TYPE(slots[i])->tp_descr_set(slots[i], r, values[i]) < 0)
                Py_CLEAR(r);
    } else if (ok) {
        r = PyObject_Vectorcall(type, values, count, NULL);
    }
    for (int i = 0; i < count; ++i)
        Py_XDECREF(values[i]);
    return r;
}

#endif
