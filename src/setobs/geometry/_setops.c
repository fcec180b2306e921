/*
 * Compiled construction of the exact set operations of setobs.ConstrainedZonotope:
 * Minkowski sum (Scott et al. 2016, eq. (12)), linear map (eq. (11)) and generalised
 * intersection (eq. (13)): the same sets as the NumPy code in zonotope.py up to rounding
 * (bit for bit for the sum and the plain intersection; the products of the maps and of R
 * may be summed in another order than by the BLAS), with the same error bounds on the
 * centre and on the constraints' right-hand side (sum_err, map_err, diff_err of
 * _bounds.py), which cover either rounding. The NumPy code stays the reference and the fallback.
 *
 * Each function returns a new ConstrainedZonotope, or None when its fast path does not
 * apply (another type, dtype, byte order, shape, a matrix entry that is not finite or
 * above MAX_MAGNITUDE in magnitude, or a result whose data would be): the caller then
 * runs the NumPy code, which validates and raises the user-facing errors. So no set with
 * non-finite data, or data above MAX_MAGNITUDE, is ever built here (check_data is the
 * same guard for the sets the Python code builds).
 *
 * The hybrid zonotopes' union, Minkowski sum and generalised intersection
 * (hybrid_union, hybrid_combine) build the HybridZonotope of hybrid.py's construction
 * (its slots and its rows' bound by bind_hybrid, as bind does for the constrained
 * zonotope): the same entries up to the order of the sums, the same rounding bounds.
 *
 * Why C: these operations are array bookkeeping on small arrays, where NumPy's per-call
 * cost (about 1 us a call, a dozen calls an operation) made them 2-6x slower than
 * ZonoOpt's C++. Floating-point contraction is switched off in the build
 * (-ffp-contract=off), so each sum and product is rounded as in NumPy.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <structmember.h>
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>
#include <math.h>
#include <string.h>

enum { S_A, S_G, S_B, S_BERR, S_C, S_CACHE, S_CERR, S_H, S_R, NSLOTS };
static const char *slot_names[NSLOTS] = {"_A", "_G", "_b", "_berr", "_c",
                                         "_cache", "_cerr", "_h", "unbounded_radius"};
static Py_ssize_t offsets[NSLOTS];
static PyTypeObject *cz_type = NULL;
/* setobs.tolerances.MAX_MAGNITUDE, set by bind(): the largest magnitude of a set's data. */
static double max_mag = 1e150;
static PyObject *lp_key = NULL;

#define SLOT(o, i) (*(PyObject **)((char *)(o) + offsets[i]))

static const double U = 1.1102230246251565e-16; /* 2^-53, UNIT_ROUNDOFF */

static double gamma_k(double k) { return k * U / (1.0 - k * U); }

/* ------------------------------------------------------------------ array views */
typedef struct {
    char *p;
    npy_intp r, c, s0, s1;
} Mat;

typedef struct {
    char *p;
    npy_intp n, s;
} Vec;

#define AT(m, i, j) (*(double *)((m).p + (i) * (m).s0 + (j) * (m).s1))
#define VAT(v, i) (*(double *)((v).p + (i) * (v).s))

static int usable(PyObject *o, int ndim) {
    if (!PyArray_Check(o)) return 0;
    PyArrayObject *a = (PyArrayObject *)o;
    return PyArray_TYPE(a) == NPY_DOUBLE && PyArray_NDIM(a) == ndim &&
           PyArray_ISNOTSWAPPED(a) && PyArray_ISALIGNED(a);
}

static int mat_view(PyObject *o, Mat *m) {
    if (!usable(o, 2)) return 0;
    PyArrayObject *a = (PyArrayObject *)o;
    m->p = PyArray_BYTES(a);
    m->r = PyArray_DIM(a, 0);
    m->c = PyArray_DIM(a, 1);
    m->s0 = PyArray_STRIDE(a, 0);
    m->s1 = PyArray_STRIDE(a, 1);
    return 1;
}

static int vec_view(PyObject *o, Vec *v) {
    if (!usable(o, 1)) return 0;
    PyArrayObject *a = (PyArrayObject *)o;
    v->p = PyArray_BYTES(a);
    v->n = PyArray_DIM(a, 0);
    v->s = PyArray_STRIDE(a, 0);
    return 1;
}

/* An optional error vector: None (exact) or a float64 vector of length n. */
static int err_view(PyObject *o, npy_intp n, Vec *v) {
    if (o == Py_None) {
        v->p = NULL;
        v->n = n;
        v->s = 0;
        return 1;
    }
    return vec_view(o, v) && v->n == n;
}

static PyArrayObject *new_mat(npy_intp r, npy_intp c, int zero) {
    npy_intp d[2] = {r, c};
    return (PyArrayObject *)(zero ? PyArray_ZEROS(2, d, NPY_DOUBLE, 0)
                                  : PyArray_SimpleNew(2, d, NPY_DOUBLE));
}

static PyArrayObject *new_vec(npy_intp n) {
    npy_intp d[1] = {n};
    return (PyArrayObject *)PyArray_SimpleNew(1, d, NPY_DOUBLE);
}

#define DATA(a) ((double *)PyArray_DATA(a))

/* Copy a view into rows r0.., columns c0.. of a C-contiguous matrix, times sign. */
static void put(PyArrayObject *dst, npy_intp r0, npy_intp c0, const Mat *src, double sign) {
    double *d = DATA(dst);
    npy_intp ld = PyArray_DIM(dst, 1);
    for (npy_intp i = 0; i < src->r; i++)
        for (npy_intp j = 0; j < src->c; j++)
            d[(r0 + i) * ld + c0 + j] = sign * AT(*src, i, j);
}

static void put_vec(double *d, const Vec *v) {
    for (npy_intp i = 0; i < v->n; i++) d[i] = VAT(*v, i);
}

/* ------------------------------------------------------------------ the set object */
typedef struct {
    PyObject *A, *G, *b, *berr, *c, *cache, *cerr, *h, *r;
    Mat mA, mG;
    Vec vb, vc, vh, vcerr, vberr;
    npy_intp n, ng, nc;
} Set;

/* Read a set's slots; 0 if the object is not a plain ConstrainedZonotope with float64
   arrays (the caller falls back to the NumPy code). */
static int read_set(PyObject *o, Set *s) {
    if (cz_type == NULL || Py_TYPE(o) != cz_type) return 0;
    s->A = SLOT(o, S_A);
    s->G = SLOT(o, S_G);
    s->b = SLOT(o, S_B);
    s->berr = SLOT(o, S_BERR);
    s->c = SLOT(o, S_C);
    s->cache = SLOT(o, S_CACHE);
    s->cerr = SLOT(o, S_CERR);
    s->h = SLOT(o, S_H);
    s->r = SLOT(o, S_R);
    if (!s->A || !s->G || !s->b || !s->berr || !s->c || !s->cache || !s->cerr || !s->h ||
        !s->r || !PyFloat_Check(s->r) || !PyDict_Check(s->cache))
        return 0;
    if (!mat_view(s->G, &s->mG) || !mat_view(s->A, &s->mA) || !vec_view(s->c, &s->vc) ||
        !vec_view(s->b, &s->vb) || !vec_view(s->h, &s->vh))
        return 0;
    s->n = s->mG.r;
    s->ng = s->mG.c;
    s->nc = s->mA.r;
    if (s->vc.n != s->n || s->mA.c != s->ng || s->vb.n != s->nc || s->vh.n != s->ng) return 0;
    return err_view(s->cerr, s->n, &s->vcerr) && err_view(s->berr, s->nc, &s->vberr);
}

/* A user's matrix: float64 (native, aligned), rows x cols, all entries finite and at
   most max_mag in magnitude (what as_matrix accepts; otherwise as_matrix raises). */
static int read_matrix(PyObject *o, npy_intp rows, npy_intp cols, Mat *m) {
    if (!mat_view(o, m) || m->c != cols || m->r < 1 || (rows >= 0 && m->r != rows)) return 0;
    for (npy_intp i = 0; i < m->r; i++)
        for (npy_intp j = 0; j < m->c; j++)
            if (!(fabs(AT(*m, i, j)) <= max_mag)) return 0;
    return 1;
}

/* ------------------------------------------------------------------ the data guard */
/* Index of the first entry of a float64 array (any strides, 1-D or 2-D) that is NaN or
   above max_mag in magnitude (+inf allowed where allow_inf), -1 if none, -2 if the array
   is not a native aligned float64 array of 1 or 2 dimensions. */
static npy_intp first_bad(PyObject *o, int allow_inf) {
    if (!PyArray_Check(o)) return -2;
    PyArrayObject *a = (PyArrayObject *)o;
    int nd = PyArray_NDIM(a);
    if (PyArray_TYPE(a) != NPY_DOUBLE || (nd != 1 && nd != 2) || !PyArray_ISNOTSWAPPED(a) ||
        !PyArray_ISALIGNED(a))
        return -2;
    npy_intp r = PyArray_DIM(a, 0), c = nd == 2 ? PyArray_DIM(a, 1) : 1;
    npy_intp s0 = PyArray_STRIDE(a, 0), s1 = nd == 2 ? PyArray_STRIDE(a, 1) : 0;
    const char *p = PyArray_BYTES(a);
    for (npy_intp i = 0; i < r; i++)
        for (npy_intp j = 0; j < c; j++) {
            double x = *(const double *)(p + i * s0 + j * s1);
            if (!(fabs(x) <= max_mag) && !(allow_inf && x == HUGE_VAL)) return i * c + j;
        }
    return -1;
}

/* check_data(G, c, A, b, h, cerr, berr): None if every entry is finite and at most
   MAX_MAGNITUDE in magnitude (h: or +inf; cerr, berr: or None), else (k, i, value) for
   the first bad entry (k: the argument's position, i: its flat index); NotImplemented
   for an argument that is not a float64 array (the caller checks in NumPy). */
static PyObject *check_data(PyObject *mod, PyObject *const *args, Py_ssize_t nargs) {
    if (nargs != 7) {
        PyErr_SetString(PyExc_TypeError, "check_data(G, c, A, b, h, cerr, berr)");
        return NULL;
    }
    for (Py_ssize_t k = 0; k < nargs; k++) {
        if (k >= 5 && args[k] == Py_None) continue;
        npy_intp i = first_bad(args[k], k == 4);
        if (i == -2) Py_RETURN_NOTIMPLEMENTED;
        if (i >= 0) {
            PyArrayObject *a = (PyArrayObject *)args[k];
            npy_intp c = PyArray_NDIM(a) == 2 ? PyArray_DIM(a, 1) : 1;
            npy_intp r = i / c, j = i % c;
            double x = *(const double *)(PyArray_BYTES(a) + r * PyArray_STRIDE(a, 0) +
                                         (PyArray_NDIM(a) == 2 ? j * PyArray_STRIDE(a, 1) : 0));
            return Py_BuildValue("(nnd)", k, i, x);
        }
    }
    Py_RETURN_NONE;
}

/* 1 if the set's data pass the guard (the object is a set built by make()). */
static int data_ok(PyObject *o) {
    PyObject *e[7] = {SLOT(o, S_G), SLOT(o, S_C), SLOT(o, S_A), SLOT(o, S_B), SLOT(o, S_H),
                      SLOT(o, S_CERR), SLOT(o, S_BERR)};
    for (int k = 0; k < 7; k++) {
        if (k >= 5 && e[k] == Py_None) continue;
        if (first_bad(e[k], k == 4) != -1) return 0;
    }
    return 1;
}

/* The set o if its data pass the guard; else None (the NumPy code then builds the same
   set and raises the error that names the operation). Steals the reference. */
static PyObject *guarded(PyObject *o) {
    if (o == NULL || data_ok(o)) return o;
    Py_DECREF(o);
    Py_RETURN_NONE;
}

/* guarded() for a set whose arrays outside `mask` (bits in data_ok's order: G 1, c 2, A 4,
   b 8, h 16, cerr 32, berr 64) are its operands' own arrays or exact copies of their
   entries beside zeros, which passed the guard when those sets were built: only the
   computed ones are scanned (a linear map of a set with a large A no longer reads A). */
enum { K_G = 1, K_C = 2, K_A = 4, K_B = 8, K_H = 16, K_CERR = 32, K_BERR = 64 };

static PyObject *guarded_new(PyObject *o, int mask) {
    if (o == NULL) return o;
    PyObject *e[7] = {SLOT(o, S_G), SLOT(o, S_C), SLOT(o, S_A), SLOT(o, S_B), SLOT(o, S_H),
                      SLOT(o, S_CERR), SLOT(o, S_BERR)};
    for (int k = 0; k < 7; k++) {
        if (!(mask & (1 << k)) || (k >= 5 && e[k] == Py_None)) continue;
        if (first_bad(e[k], k == 4) != -1) {
            Py_DECREF(o);
            Py_RETURN_NONE;
        }
    }
    return o;
}

static int all_zero(const double *x, npy_intp n) {
    for (npy_intp i = 0; i < n; i++)
        if (x[i] != 0.0) return 0;
    return 1;
}

/* New read-only array, or None for an error bound that is NULL or all zero (exact).
   Steals the reference. */
static PyObject *freeze(PyArrayObject *a) {
    PyArray_CLEARFLAGS(a, NPY_ARRAY_WRITEABLE);
    return (PyObject *)a;
}

static PyObject *freeze_err(PyObject *e) {
    if (e == NULL || e == Py_None) {
        Py_XDECREF(e);
        Py_RETURN_NONE;
    }
    PyArrayObject *a = (PyArrayObject *)e;
    if (all_zero(DATA(a), PyArray_SIZE(a))) {
        Py_DECREF(e);
        Py_RETURN_NONE;
    }
    if (PyArray_ISWRITEABLE(a)) PyArray_CLEARFLAGS(a, NPY_ARRAY_WRITEABLE);
    return e;
}

/* Build the set; steals every reference (all must be non-NULL). */
static PyObject *make(PyObject *G, PyObject *c, PyObject *A, PyObject *b, PyObject *h,
                      PyObject *r, PyObject *cerr, PyObject *berr) {
    PyObject *vals[NSLOTS];
    vals[S_A] = A;
    vals[S_G] = G;
    vals[S_B] = b;
    vals[S_BERR] = berr;
    vals[S_C] = c;
    vals[S_CACHE] = PyDict_New();
    vals[S_CERR] = cerr;
    vals[S_H] = h;
    vals[S_R] = r;
    PyObject *o = vals[S_CACHE] ? cz_type->tp_alloc(cz_type, 0) : NULL;
    for (int i = 0; i < NSLOTS; i++) {
        if (o == NULL)
            Py_XDECREF(vals[i]);
        else
            SLOT(o, i) = vals[i];
    }
    return o;
}

/* Concatenated error bounds (zeros for an exact part), or None if both are exact. */
static PyObject *cat_err(const Vec *e1, const Vec *e2) {
    if (e1->p == NULL && e2->p == NULL) Py_RETURN_NONE;
    PyArrayObject *out = new_vec(e1->n + e2->n);
    if (out == NULL) return NULL;
    double *d = DATA(out);
    for (npy_intp i = 0; i < e1->n; i++) d[i] = e1->p ? VAT(*e1, i) : 0.0;
    for (npy_intp i = 0; i < e2->n; i++) d[e1->n + i] = e2->p ? VAT(*e2, i) : 0.0;
    return freeze(out);
}

static PyObject *new_ref(PyObject *o) {
    Py_INCREF(o);
    return o;
}

static PyObject *min_radius(const Set *s, const Set *t) {
    /* Python's min(a, b): b only if b < a. */
    return new_ref(PyFloat_AS_DOUBLE(t->r) < PyFloat_AS_DOUBLE(s->r) ? t->r : s->r);
}

#define FAIL_IF(cond)    \
    do {                 \
        if (cond) goto fail; \
    } while (0)

/* ------------------------------------------------------------------ Minkowski sum */
/* A new reference to one read-only empty vector (the right-hand side of every zonotope
   part built here); NULL on a memory error. */
static PyArrayObject *empty_vec(void) {
    static PyArrayObject *e = NULL;
    if (e == NULL) {
        e = new_vec(0);
        if (e == NULL) return NULL;
        PyArray_CLEARFLAGS(e, NPY_ARRAY_WRITEABLE);
    }
    Py_INCREF(e);
    return e;
}

/* The centre c = c_Z + c_W of a Minkowski sum, written into c, and its bound
   sum_err(c, add_err(cerr_Z, cerr_W)) (read-only, or None: exact); NULL on a memory error. */
static PyObject *sum_center(const Set *s, const Set *t, PyArrayObject *c) {
    double *cd = DATA(c);
    npy_intp n = s->n;
    PyObject *cerr;
    int nonzero = 0;
    for (npy_intp i = 0; i < n; i++) {
        cd[i] = VAT(s->vc, i) + VAT(t->vc, i);
        nonzero |= cd[i] != 0.0;
    }
    /* sum_err(c, add_err(cerr_Z, cerr_W)) */
    const double widen = 1.0 + 2.0 * U, g2 = gamma_k(2.0);
    if (nonzero || (s->vcerr.p && t->vcerr.p)) {
        PyArrayObject *e = new_vec(n);
        if (e == NULL) return NULL;
        double *ed = DATA(e);
        for (npy_intp i = 0; i < n; i++) {
            int have = 1;
            double carried = 0.0;
            if (s->vcerr.p && t->vcerr.p)
                carried = (VAT(s->vcerr, i) + VAT(t->vcerr, i)) * widen;
            else if (s->vcerr.p)
                carried = VAT(s->vcerr, i);
            else if (t->vcerr.p)
                carried = VAT(t->vcerr, i);
            else
                have = 0;
            if (!nonzero)
                ed[i] = carried;
            else if (have)
                ed[i] = (carried + fabs(cd[i]) * g2) * widen;
            else
                ed[i] = fabs(cd[i]) * g2;
        }
        cerr = (PyObject *)e;
    } else {
        cerr = new_ref(s->vcerr.p ? s->cerr : t->cerr); /* one carried bound, or None */
    }
    return freeze_err(cerr);
}


static PyObject *minkowski_sum(PyObject *mod, PyObject *const *args, Py_ssize_t nargs) {
    Set s, t;
    if (nargs != 2) {
        PyErr_SetString(PyExc_TypeError, "minkowski_sum(Z, W)");
        return NULL;
    }
    if (!read_set(args[0], &s) || !read_set(args[1], &t) || s.n != t.n) Py_RETURN_NONE;
    npy_intp n = s.n, ng = s.ng + t.ng, nc = s.nc + t.nc;
    PyArrayObject *G = NULL, *c = NULL, *A = NULL, *b = NULL, *h = NULL;
    PyObject *cerr = NULL, *berr = NULL;
    FAIL_IF(!(G = new_mat(n, ng, 0)) || !(c = new_vec(n)) || !(A = new_mat(nc, ng, 1)) ||
            !(b = new_vec(nc)) || !(h = new_vec(ng)));
    put(G, 0, 0, &s.mG, 1.0);
    put(G, 0, s.ng, &t.mG, 1.0);
    put(A, 0, 0, &s.mA, 1.0);
    put(A, s.nc, s.ng, &t.mA, 1.0);
    put_vec(DATA(b), &s.vb);
    put_vec(DATA(b) + s.nc, &t.vb);
    put_vec(DATA(h), &s.vh);
    put_vec(DATA(h) + s.ng, &t.vh);
    cerr = sum_center(&s, &t, c);
    FAIL_IF(cerr == NULL);
    berr = cat_err(&s.vberr, &t.vberr);
    FAIL_IF(berr == NULL);
    /* (G, A, b, h: the operands' entries copied beside zeros; berr: theirs concatenated) */
    return guarded_new(make(freeze(G), freeze(c), freeze(A), freeze(b), freeze(h),
                            min_radius(&s, &t), cerr, berr), K_C | K_CERR);
fail:
    Py_XDECREF(G);
    Py_XDECREF(c);
    Py_XDECREF(A);
    Py_XDECREF(b);
    Py_XDECREF(h);
    Py_XDECREF(cerr);
    Py_XDECREF(berr);
    return NULL;
}

/* ------------------------------------------------------------------ linear map */
static PyObject *linear_map(PyObject *mod, PyObject *const *args, Py_ssize_t nargs) {
    Set s;
    Mat M;
    if (nargs != 2) {
        PyErr_SetString(PyExc_TypeError, "linear_map(Z, M)");
        return NULL;
    }
    if (!read_set(args[0], &s) || !read_matrix(args[1], -1, s.n, &M)) Py_RETURN_NONE;
    npy_intp m = M.r, n = s.n, ng = s.ng;
    PyArrayObject *G = NULL, *c = NULL;
    PyObject *cerr = NULL, *out = NULL;
    FAIL_IF(!(G = new_mat(m, ng, 0)) || !(c = new_vec(m)));
    double *gd = DATA(G), *cd = DATA(c);
    for (npy_intp i = 0; i < m; i++) {
        double *row = gd + i * ng;
        for (npy_intp j = 0; j < ng; j++) row[j] = 0.0;
        double ci = 0.0;
        for (npy_intp k = 0; k < n; k++) {
            double mik = AT(M, i, k);
            for (npy_intp j = 0; j < ng; j++) row[j] += mik * AT(s.mG, k, j);
            ci += mik * VAT(s.vc, k);
        }
        cd[i] = ci;
    }
    /* map_err(M, c_Z, cerr_Z) */
    int nonzero = 0;
    for (npy_intp k = 0; k < n; k++) nonzero |= VAT(s.vc, k) != 0.0;
    if (s.vcerr.p == NULL && !nonzero) {
        cerr = new_ref(Py_None);
    } else {
        PyArrayObject *e = new_vec(m);
        FAIL_IF(e == NULL);
        cerr = (PyObject *)e;
        const double gk1 = gamma_k((double)n + 1.0), widen = 1.0 + gamma_k((double)n + 2.0);
        double *ed = DATA(e);
        for (npy_intp i = 0; i < m; i++) {
            double acc = 0.0;
            for (npy_intp k = 0; k < n; k++) {
                double base = gk1 * fabs(VAT(s.vc, k));
                if (s.vcerr.p) base += VAT(s.vcerr, k);
                acc += fabs(AT(M, i, k)) * base;
            }
            ed[i] = acc * widen;
        }
    }
    cerr = freeze_err(cerr);
    FAIL_IF(cerr == NULL);
    out = make(freeze(G), freeze(c), new_ref(s.A), new_ref(s.b), new_ref(s.h), new_ref(s.r),
               cerr, new_ref(s.berr));
    if (out == NULL) return NULL;
    /* Same factor polytope: share its LP model (and emptiness cache), as _same_factors. */
    PyObject *lp = PyDict_GetItemWithError(s.cache, lp_key);
    if (lp != NULL && PyDict_SetItem(SLOT(out, S_CACHE), lp_key, lp) < 0) {
        Py_DECREF(out);
        return NULL;
    }
    if (lp == NULL && PyErr_Occurred()) {
        Py_DECREF(out);
        return NULL;
    }
    return guarded_new(out, K_G | K_C | K_CERR); /* (A, b, h, berr: the operand's own) */
fail:
    Py_XDECREF(G);
    Py_XDECREF(c);
    Py_XDECREF(cerr);
    return NULL;
}

/* ------------------------------------------------------------------ generalised intersection */
static PyObject *intersect(PyObject *mod, PyObject *const *args, Py_ssize_t nargs) {
    Set s, t;
    Mat R;
    if (nargs != 3) {
        PyErr_SetString(PyExc_TypeError, "intersect(Z, W, R or None)");
        return NULL;
    }
    if (!read_set(args[0], &s) || !read_set(args[1], &t)) Py_RETURN_NONE;
    int identity = args[2] == Py_None;
    if (identity ? s.n != t.n : !read_matrix(args[2], t.n, s.n, &R)) Py_RETURN_NONE;
    npy_intp n1 = s.n, n2 = t.n, g1 = s.ng, ng = s.ng + t.ng, m1 = s.nc, m12 = s.nc + t.nc;
    npy_intp nc = m12 + n2;
    PyArrayObject *G = NULL, *A = NULL, *b = NULL, *h = NULL, *e = NULL;
    PyObject *berr = NULL;
    FAIL_IF(!(G = new_mat(n1, ng, 1)) || !(A = new_mat(nc, ng, 1)) || !(b = new_vec(nc)) ||
            !(h = new_vec(ng)) || !(e = new_vec(n2)));
    put(G, 0, 0, &s.mG, 1.0);
    put(A, 0, 0, &s.mA, 1.0);
    put(A, m1, g1, &t.mA, 1.0);
    put(A, m12, g1, &t.mG, -1.0);
    double *ad = DATA(A), *bd = DATA(b), *ed = DATA(e);
    if (identity) {
        put(A, m12, 0, &s.mG, 1.0);
    } else {
        for (npy_intp i = 0; i < n2; i++) {
            double *row = ad + (m12 + i) * ng;
            for (npy_intp k = 0; k < n1; k++) {
                double rik = AT(R, i, k);
                for (npy_intp j = 0; j < g1; j++) row[j] += rik * AT(s.mG, k, j);
            }
        }
    }
    put_vec(bd, &s.vb);
    put_vec(bd + m1, &t.vb);
    put_vec(DATA(h), &s.vh);
    put_vec(DATA(h) + g1, &t.vh);
    /* b's new rows c_W - R c_Z, and diff_err(c_W, R, c_Z, cerr_Z, cerr_W) */
    const double gk1 = gamma_k((double)n1 + 1.0), widen = 1.0 + gamma_k((double)n1 + 3.0);
    int nonzero = 0;
    for (npy_intp i = 0; i < n2; i++) {
        double rc = 0.0, base = 0.0, carried = 0.0;
        if (identity) {
            rc = VAT(s.vc, i);
            base = fabs(rc);
            if (s.vcerr.p) carried = VAT(s.vcerr, i);
        } else {
            for (npy_intp k = 0; k < n1; k++) {
                double rik = AT(R, i, k);
                rc += rik * VAT(s.vc, k);
                base += fabs(rik) * fabs(VAT(s.vc, k));
                if (s.vcerr.p) carried += fabs(rik) * VAT(s.vcerr, k);
            }
        }
        bd[m12 + i] = VAT(t.vc, i) - rc;
        base += fabs(VAT(t.vc, i));
        base *= gk1;
        if (s.vcerr.p) base += carried;
        if (t.vcerr.p) base += VAT(t.vcerr, i);
        ed[i] = base;
        nonzero |= base != 0.0;
    }
    Vec v12 = {NULL, m12, sizeof(double)}, vnew = {NULL, n2, sizeof(double)};
    PyObject *berr12 = NULL;
    if (nonzero) {
        for (npy_intp i = 0; i < n2; i++) ed[i] *= widen;
        vnew.p = (char *)ed;
    }
    berr12 = cat_err(&s.vberr, &t.vberr);
    FAIL_IF(berr12 == NULL);
    if (berr12 != Py_None) vec_view(berr12, &v12);
    berr = cat_err(&v12, &vnew);
    Py_DECREF(berr12);
    FAIL_IF(berr == NULL);
    Py_DECREF(e);
    e = NULL;
    /* (only the new rows R G_Z of A are computed; the rest of A, G and h are the operands'
       entries copied beside zeros, and c, cerr the first operand's own) */
    if (!identity) {
        int bad = 0;
        for (npy_intp i = m12; i < nc && !bad; i++)
            for (npy_intp j = 0; j < g1; j++)
                if (!(fabs(ad[i * ng + j]) <= max_mag)) {
                    bad = 1;
                    break;
                }
        if (bad) {
            Py_DECREF(G);
            Py_DECREF(A);
            Py_DECREF(b);
            Py_DECREF(h);
            Py_DECREF(berr);
            Py_RETURN_NONE;
        }
    }
    return guarded_new(make(freeze(G), new_ref(s.c), freeze(A), freeze(b), freeze(h),
                            min_radius(&s, &t), new_ref(s.cerr), berr), K_B | K_BERR);
fail:
    Py_XDECREF(G);
    Py_XDECREF(A);
    Py_XDECREF(b);
    Py_XDECREF(h);
    Py_XDECREF(e);
    Py_XDECREF(berr);
    return NULL;
}


/* ------------------------------------------------------------------ hybrid union */
/* One operand of hybrid_union: a ConstrainedZonotope (dense A, no binary factor) or a
   HybridZonotope (its zonotope part _P, a ConstrainedZonotope without rows; its rows _R
   as coordinate triplets i, j, v with b, berr; its flags _binary). */
typedef struct {
    Set s;            /* the CZ, or the hybrid's zonotope part (G, c, cerr, h, r) */
    PyObject *P;      /* the object s was read from (borrowed) */
    int dense;        /* 1: rows from s.mA */
    Vec vi, vj, vv;   /* the triplets (hybrid), i and j int64 */
    Vec vb, vberr;    /* the right-hand side and its bound (berr p NULL: exact) */
    const char *bin;  /* the binary flags (NULL: none), stride bin_s */
    npy_intp bin_s, m, f, nnz;
} Op;

/* The slots of HybridZonotope and of its rows' class (hybrid.py's _Rows), set by
   bind_hybrid() as bind() sets the constrained zonotope's. */
enum { H_P, H_R, H_BINARY, H_CACHE, NHSLOTS };
static const char *hslot_names[NHSLOTS] = {"_P", "_R", "_binary", "_cache"};
enum { W_CSC, W_DENSE, W_B, W_BERR, W_I, W_J, W_M, W_NF, W_V, NWSLOTS };
static const char *wslot_names[NWSLOTS] = {"_csc", "_dense", "b", "berr", "i", "j", "m",
                                           "nf", "v"};
static Py_ssize_t hoffsets[NHSLOTS], woffsets[NWSLOTS];
static PyTypeObject *hz_type = NULL, *rows_type = NULL;

#define HSLOT(o, i) (*(PyObject **)((char *)(o) + hoffsets[i]))
#define WSLOT(o, i) (*(PyObject **)((char *)(o) + woffsets[i]))

static int int_view(PyObject *o, Vec *v) {
    if (!PyArray_Check(o)) return 0;
    PyArrayObject *a = (PyArrayObject *)o;
    if (PyArray_TYPE(a) != NPY_INT64 || PyArray_NDIM(a) != 1 || !PyArray_ISNOTSWAPPED(a) ||
        !PyArray_ISALIGNED(a))
        return 0;
    v->p = PyArray_BYTES(a);
    v->n = PyArray_DIM(a, 0);
    v->s = PyArray_STRIDE(a, 0);
    return 1;
}

#define IAT(v, k) (*(const npy_int64 *)((v).p + (k) * (v).s))

/* Read an operand (borrowed references only); 0 if the fast path does not apply. */
static int read_op(PyObject *o, Op *op) {
    op->bin = NULL;
    if (cz_type != NULL && Py_TYPE(o) == cz_type) {
        if (!read_set(o, &op->s)) return 0;
        op->P = o;
        op->dense = 1;
        op->m = op->s.nc;
        op->f = op->s.ng;
        op->vb = op->s.vb;
        op->vberr = op->s.vberr;
        op->nnz = op->m * op->f;
        return 1;
    }
    if (hz_type == NULL || Py_TYPE(o) != hz_type) return 0;
    PyObject *P = HSLOT(o, H_P), *R = HSLOT(o, H_R), *B = HSLOT(o, H_BINARY);
    if (!P || !R || !B || Py_TYPE(R) != rows_type) return 0;
    PyObject *Ti = WSLOT(R, W_I), *Tj = WSLOT(R, W_J), *Tv = WSLOT(R, W_V), *b = WSLOT(R, W_B),
             *e = WSLOT(R, W_BERR);
    if (!Ti || !Tj || !Tv || !b || !e) return 0;
    if (!read_set(P, &op->s) || op->s.nc != 0 || !int_view(Ti, &op->vi) ||
        !int_view(Tj, &op->vj) || !vec_view(Tv, &op->vv) || !vec_view(b, &op->vb))
        return 0;
    op->P = P;
    op->dense = 0;
    op->m = op->vb.n;
    op->f = op->s.ng;
    op->nnz = op->vv.n;
    if (op->vi.n != op->nnz || op->vj.n != op->nnz || !err_view(e, op->m, &op->vberr))
        return 0;
    for (npy_intp k = 0; k < op->nnz; k++) {
        npy_int64 i = IAT(op->vi, k), j = IAT(op->vj, k);
        if (i < 0 || i >= op->m || j < 0 || j >= op->f) return 0;
    }
    if (!PyArray_Check(B)) return 0;
    PyArrayObject *ba = (PyArrayObject *)B;
    if (PyArray_TYPE(ba) != NPY_BOOL || PyArray_NDIM(ba) != 1 || PyArray_DIM(ba, 0) != op->f)
        return 0;
    op->bin = PyArray_BYTES(ba);
    op->bin_s = PyArray_STRIDE(ba, 0);
    return 1;
}

/* A new HybridZonotope of the zonotope part P, the rows (i, j, v; nf factors; b, berr) and
   the flags bin; steals every reference (all non-NULL); NULL on a memory error. */
static PyObject *new_hybrid(PyObject *P, PyObject *Ti, PyObject *Tj, PyObject *Tv,
                            npy_intp nf, PyObject *b, PyObject *berr, PyObject *bin) {
    PyObject *R = rows_type->tp_alloc(rows_type, 0);
    PyObject *H = hz_type->tp_alloc(hz_type, 0);
    PyObject *cache = PyDict_New();
    PyObject *m = PyLong_FromSsize_t(PyArray_DIM((PyArrayObject *)b, 0));
    PyObject *n = PyLong_FromSsize_t(nf);
    PyObject *own[7] = {P, Ti, Tj, Tv, b, berr, bin};
    if (!R || !H || !cache || !m || !n) {
        Py_XDECREF(R);
        Py_XDECREF(H);
        Py_XDECREF(cache);
        Py_XDECREF(m);
        Py_XDECREF(n);
        for (int k = 0; k < 7; k++) Py_DECREF(own[k]);
        return NULL;
    }
    WSLOT(R, W_I) = Ti;
    WSLOT(R, W_J) = Tj;
    WSLOT(R, W_V) = Tv;
    WSLOT(R, W_M) = m;
    WSLOT(R, W_NF) = n;
    WSLOT(R, W_B) = b;
    WSLOT(R, W_BERR) = berr;
    WSLOT(R, W_DENSE) = new_ref(Py_None);
    WSLOT(R, W_CSC) = new_ref(Py_None);
    HSLOT(H, H_P) = P;
    HSLOT(H, H_R) = R;
    HSLOT(H, H_BINARY) = bin;
    HSLOT(H, H_CACHE) = cache;
    return H;
}

static PyArrayObject *new_ivec(npy_intp n) {
    npy_intp d[1] = {n};
    return (PyArrayObject *)PyArray_SimpleNew(1, d, NPY_INT64);
}

static int finite_within(const double *x, npy_intp n) {
    for (npy_intp k = 0; k < n; k++)
        if (!(fabs(x[k]) <= max_mag)) return 0;
    return 1;
}

/* hybrid_union(ops): the union of the operands (two or more, of one dimension, every
   factor bounded) by the disjunctive construction of hybrid.py's _union, the same arrays
   up to the order of the sums, as a new HybridZonotope; None if the fast path does
   not apply (an operand of another type, other dimensions, an unbounded factor) or a
   result entry would not pass the data guard: the NumPy code then runs, and raises the
   user-facing errors. */
static PyObject *hybrid_union(PyObject *mod, PyObject *const *args, Py_ssize_t nargs) {
    if (nargs != 1 || !PyList_Check(args[0])) {
        PyErr_SetString(PyExc_TypeError, "hybrid_union(list of operands)");
        return NULL;
    }
    PyObject *lst = args[0];
    Py_ssize_t N = PyList_GET_SIZE(lst);
    if (N < 2) Py_RETURN_NONE;
    Op *ops = (Op *)PyMem_Calloc((size_t)N, sizeof(Op));
    if (ops == NULL) return PyErr_NoMemory();
    PyObject *result = NULL;
    PyArrayObject *G = NULL, *c = NULL, *ce = NULL, *Ti = NULL, *Tj = NULL, *Tv = NULL,
                  *b = NULL, *be = NULL, *bin = NULL, *A0 = NULL, *b0 = NULL, *h = NULL;
    npy_intp *F = NULL, *R0 = NULL, *nc = NULL;
    int ok = 1;
    npy_intp n = -1, sumf = 0, rows = 1, nnz = 0;
    for (Py_ssize_t t = 0; t < N && ok; t++) {
        ok = read_op(PyList_GET_ITEM(lst, t), &ops[t]);
        if (!ok) break;
        Op *op = &ops[t];
        if (n < 0) n = op->s.n;
        if (op->s.n != n) ok = 0;
        for (npy_intp j = 0; j < op->f && ok; j++)
            if (!isfinite(VAT(op->s.vh, j))) ok = 0;
        sumf += op->f;
        rows += op->m + op->f;
        nnz += op->nnz + op->m + 3 * op->f;
    }
    if (!ok) goto fallback;
    nnz += N;
    npy_intp nf = N + 2 * sumf;
    F = PyMem_Malloc(sizeof(npy_intp) * (size_t)N);
    R0 = PyMem_Malloc(sizeof(npy_intp) * (size_t)N);
    nc = PyMem_Malloc(sizeof(npy_intp) * (size_t)N);
    if (!F || !R0 || !nc) {
        PyErr_NoMemory();
        goto error;
    }
    npy_intp d2[2] = {n, nf};
    if (!(G = (PyArrayObject *)PyArray_ZEROS(2, d2, NPY_DOUBLE, 0)) || !(c = new_vec(n)) ||
        !(ce = new_vec(n)) || !(Ti = new_ivec(nnz)) || !(Tj = new_ivec(nnz)) ||
        !(Tv = new_vec(nnz)) || !(b = new_vec(rows)) || !(be = new_vec(rows)) ||
        !(h = new_vec(nf)) || !(A0 = new_mat(0, nf, 1)) || !(b0 = new_vec(0)))
        goto error;
    {
        npy_intp db[1] = {nf};
        bin = (PyArrayObject *)PyArray_ZEROS(1, db, NPY_BOOL, 0);
        if (bin == NULL) goto error;
    }
    double *gd = DATA(G), *cd = DATA(c), *ced = DATA(ce), *vd = DATA(Tv), *bd = DATA(b),
           *bed = DATA(be), *hd = DATA(h);
    npy_int64 *id = (npy_int64 *)PyArray_DATA(Ti), *jd = (npy_int64 *)PyArray_DATA(Tj);
    npy_bool *bind_ = (npy_bool *)PyArray_DATA(bin);
    double *csum = PyMem_Calloc((size_t)(3 * n + 1), sizeof(double));
    if (csum == NULL) {
        PyErr_NoMemory();
        goto error;
    }
    double *cabs = csum + n, *cops = cabs + n;
    for (npy_intp k = 0; k < nf; k++) hd[k] = 1.0;
    for (npy_intp k = 0; k < N; k++) bind_[k] = 1;
    npy_intp fstart = 0, r0 = 0, e = 0, ktot = N + sumf;
    int have_cops = 0;
    for (Py_ssize_t t = 0; t < N; t++) {
        Op *op = &ops[t];
        F[t] = N + 2 * fstart;
        R0[t] = r0;
        npy_intp nct = 0;
        for (npy_intp j = 0; j < op->f; j++)
            nct += !(op->bin && *(const npy_bool *)(op->bin + j * op->bin_s));
        nc[t] = nct;
        fstart += op->f;
        r0 += op->m + op->f;
    }
    /* per operand: the copies' columns (col1 at k, col2 = col1 + shift), G, c, the rows */
    npy_intp *col1 = PyMem_Malloc(sizeof(npy_intp) * (size_t)(2 * (sumf + 1)));
    if (col1 == NULL) {
        PyMem_Free(csum);
        PyErr_NoMemory();
        goto error;
    }
    npy_intp *col2 = col1 + sumf + 1;
    double *scale = PyMem_Malloc(sizeof(double) * (size_t)(sumf + 1));
    double *rsum = PyMem_Malloc(sizeof(double) * (size_t)(2 * (rows + 1)));
    if (scale == NULL || rsum == NULL) {
        PyMem_Free(csum);
        PyMem_Free(col1);
        PyMem_Free(scale);
        PyMem_Free(rsum);
        PyErr_NoMemory();
        goto error;
    }
    double *rabs = rsum + rows + 1;
    fstart = 0;
    for (Py_ssize_t t = 0; t < N; t++) {
        Op *op = &ops[t];
        npy_intp nct = nc[t], nbt = op->f - nct, rc = 0, rb = 0;
        npy_intp *c1 = col1 + fstart, *c2 = col2 + fstart;
        double *sc = scale + fstart;
        for (npy_intp j = 0; j < op->f; j++) {
            int isb = op->bin && *(const npy_bool *)(op->bin + j * op->bin_s);
            npy_intp pos = isb ? nct + rb : rc;
            c1[j] = F[t] + pos + (isb ? nct : 0);
            c2[j] = c1[j] + (isb ? nbt : nct);
            sc[j] = isb ? 1.0 : -VAT(op->s.vh, j);
            if (isb) {
                bind_[c1[j]] = 1;
                rb++;
            } else {
                rc++;
            }
            /* the copy's row: s1 + s2 - beta_t = -1 or bt + t - beta_t = -1 */
            npy_intp row = R0[t] + op->m + pos;
            id[e] = row; jd[e] = c1[j]; vd[e++] = 1.0;
            id[e] = row; jd[e] = c2[j]; vd[e++] = 1.0;
            id[e] = row; jd[e] = t; vd[e++] = -1.0;
            bd[row] = -1.0;
            bed[row] = 0.0;
        }
        /* G: the copies' columns, the selector's column ((c - G_B 1 + P 1)/2) */
        for (npy_intp r = 0; r < n; r++) {
            double S = 0.0;
            for (npy_intp j = 0; j < op->f; j++) {
                double g = AT(op->s.mG, r, j) * sc[j];
                gd[r * nf + c1[j]] = g;
                S += g;
                csum[r] += g;
                cabs[r] += fabs(g);
            }
            double cr = VAT(op->s.vc, r);
            gd[r * nf + t] = 0.5 * (cr - S);
            csum[r] += cr;
            cabs[r] += fabs(cr);
            if (op->s.vcerr.p) {
                double x = VAT(op->s.vcerr, r);
                if (x > cops[r]) cops[r] = x;
                have_cops |= x != 0.0;
            }
        }
        /* the operand's rows: scaled entries, the selector's entry, b, b_err */
        for (npy_intp i = 0; i < op->m; i++) rsum[i] = rabs[i] = 0.0;
        if (op->dense) {
            for (npy_intp i = 0; i < op->m; i++)
                for (npy_intp j = 0; j < op->f; j++) {
                    double a = AT(op->s.mA, i, j);
                    if (a == 0.0) continue;
                    double x = a * sc[j];
                    if (x == 0.0) continue;
                    id[e] = R0[t] + i; jd[e] = c1[j]; vd[e++] = x;
                    rsum[i] += x;
                    rabs[i] += fabs(x);
                }
        } else {
            for (npy_intp k = 0; k < op->nnz; k++) {
                npy_int64 i = IAT(op->vi, k), j = IAT(op->vj, k);
                double x = VAT(op->vv, k) * sc[j];
                if (x == 0.0) continue;
                id[e] = R0[t] + i; jd[e] = c1[j]; vd[e++] = x;
                rsum[i] += x;
                rabs[i] += fabs(x);
            }
        }
        double kr = 1.0 + (double)op->f;
        double gk = gamma_k(kr + 1.0), widen = 1.0 + gamma_k(kr + 2.0), w3 = 1.0 + gamma_k(3.0);
        for (npy_intp i = 0; i < op->m; i++) {
            double bi = VAT(op->vb, i), sel = -0.5 * (rsum[i] + bi);
            if (sel != 0.0) {
                id[e] = R0[t] + i; jd[e] = t; vd[e++] = sel;
            }
            bd[R0[t] + i] = 0.5 * (bi - rsum[i]);
            double x = gk * (0.5 * (fabs(bi) + rabs[i])) * widen;
            if (op->vberr.p) x += VAT(op->vberr, i) * w3;
            bed[R0[t] + i] = x;
        }
        fstart += op->f;
    }
    /* sum beta_t = 2 - N */
    for (Py_ssize_t t = 0; t < N; t++) {
        id[e] = rows - 1; jd[e] = t; vd[e++] = 1.0;
    }
    bd[rows - 1] = 2.0 - (double)N;
    bed[rows - 1] = 0.0;
    {
        double gk = gamma_k((double)ktot + 1.0), widen = 1.0 + gamma_k((double)ktot + 2.0),
               w3 = 1.0 + gamma_k(3.0);
        for (npy_intp r = 0; r < n; r++) {
            cd[r] = 0.5 * csum[r];
            ced[r] = gk * (0.5 * cabs[r]) * widen;
            if (have_cops) ced[r] = (ced[r] + cops[r]) * w3;
        }
    }
    PyMem_Free(csum);
    PyMem_Free(col1);
    PyMem_Free(scale);
    PyMem_Free(rsum);
    /* the data guard on what was computed (G, c, c_err, v, b, b_err) */
    if (!finite_within(gd, n * nf) || !finite_within(cd, n) || !finite_within(ced, n) ||
        !finite_within(vd, e) || !finite_within(bd, rows) || !finite_within(bed, rows))
        goto fallback;
    {
        /* (the unused tail of the triplets: entries that were zero) */
        PyArray_Dims nd = {&e, 1};
        PyObject *t1 = PyArray_Resize(Ti, &nd, 0, NPY_CORDER);
        PyObject *t2 = t1 ? PyArray_Resize(Tj, &nd, 0, NPY_CORDER) : NULL;
        PyObject *t3 = t2 ? PyArray_Resize(Tv, &nd, 0, NPY_CORDER) : NULL;
        Py_XDECREF(t1);
        Py_XDECREF(t2);
        Py_XDECREF(t3);
        if (t3 == NULL) goto error;
    }
    double rmin = PyFloat_AS_DOUBLE(ops[0].s.r);
    PyObject *r = ops[0].s.r;
    for (Py_ssize_t t = 1; t < N; t++)
        if (PyFloat_AS_DOUBLE(ops[t].s.r) < rmin) {
            rmin = PyFloat_AS_DOUBLE(ops[t].s.r);
            r = ops[t].s.r;
        }
    PyObject *P = make(freeze(G), freeze(c), freeze(A0), freeze(b0), freeze(h), new_ref(r),
                       freeze_err((PyObject *)ce), new_ref(Py_None));
    G = c = ce = A0 = b0 = h = NULL;
    if (P == NULL) goto error;
    PyObject *berr = freeze_err((PyObject *)be);
    be = NULL;
    if (berr == NULL) {
        Py_DECREF(P);
        goto error;
    }
    result = new_hybrid(P, (PyObject *)Ti, (PyObject *)Tj, (PyObject *)Tv, nf, freeze(b), berr,
                        freeze(bin));
    Ti = Tj = Tv = b = bin = NULL;
    goto done;
fallback:
    result = new_ref(Py_None);
    goto done;
error:
    result = NULL;
done:
    PyMem_Free(ops);
    PyMem_Free(F);
    PyMem_Free(R0);
    PyMem_Free(nc);
    Py_XDECREF(G);
    Py_XDECREF(c);
    Py_XDECREF(ce);
    Py_XDECREF(Ti);
    Py_XDECREF(Tj);
    Py_XDECREF(Tv);
    Py_XDECREF(b);
    Py_XDECREF(be);
    Py_XDECREF(bin);
    Py_XDECREF(A0);
    Py_XDECREF(b0);
    Py_XDECREF(h);
    return result;
}


/* Append the triplets of a dense matrix's nonzero entries (rows + r0, columns + c0). */
static void put_dense_triplets(const Mat *A, npy_intp r0, npy_intp c0, npy_int64 *id,
                               npy_int64 *jd, double *vd, npy_intp *e) {
    for (npy_intp i = 0; i < A->r; i++)
        for (npy_intp j = 0; j < A->c; j++) {
            double x = AT(*A, i, j);
            if (x == 0.0) continue;
            id[*e] = r0 + i;
            jd[*e] = c0 + j;
            vd[(*e)++] = x;
        }
}

/* hybrid_combine(kind, H, W, R): the HybridZonotope H + W (kind 0, R None) or
   {z in H : R z in W} (kind 1, R None for the identity), H a hybrid zonotope and W a
   hybrid or constrained zonotope: the zonotope parts summed here (the centre as
   minkowski_sum's) or intersected by intersect above, the rows stacked
   block-diagonally, the new ones last. None if the fast path does not apply (the NumPy
   code then runs). */
static PyObject *hybrid_combine(PyObject *mod, PyObject *const *args, Py_ssize_t nargs) {
    if (nargs != 4 || !PyLong_Check(args[0])) {
        PyErr_SetString(PyExc_TypeError, "hybrid_combine(kind, H, W, R)");
        return NULL;
    }
    long kind = PyLong_AsLong(args[0]);
    if (kind != 0 && kind != 1) Py_RETURN_NONE;
    Op a, w;
    int ra = read_op(args[1], &a), rw = ra ? read_op(args[2], &w) : 0;
    PyObject *result = NULL, *S = NULL;
    PyArrayObject *Ti = NULL, *Tj = NULL, *Tv = NULL, *b = NULL, *be = NULL, *bin = NULL,
                  *A0 = NULL, *b0 = NULL;
    PyObject *P = NULL;
    if (!ra || !rw || a.dense) goto fallback;
    /* The zonotope part P and the new dense rows X (xr; columns from xoff; xb, xbe): for
       the sum, P's data written here and X a constrained zonotope W's own rows (beside
       H's factors); for the intersection, intersect() of the zonotope parts (a
       constrained zonotope W itself), X its rows (W's, then the new ones). */
    Mat xr = {NULL, 0, 0, 0, 0};
    Vec xb = {NULL, 0, 0}, xbe = {NULL, 0, 0};
    npy_intp xoff = 0, f = a.f + w.f;
    if (kind == 0) {
        if (a.s.n != w.s.n) goto fallback;
        npy_intp n = a.s.n;
        PyArrayObject *G = new_mat(n, f, 0), *c = new_vec(n), *h = new_vec(f);
        PyArrayObject *Az = new_mat(0, f, 1), *bz = empty_vec();
        PyObject *cerr = (G && c && h && Az && bz) ? sum_center(&a.s, &w.s, c) : NULL;
        if (cerr == NULL || !finite_within(DATA(c), n) ||
            (cerr != Py_None && !finite_within(DATA((PyArrayObject *)cerr), n))) {
            Py_XDECREF(G);
            Py_XDECREF(c);
            Py_XDECREF(h);
            Py_XDECREF(Az);
            Py_XDECREF(bz);
            if (cerr == NULL) goto error;
            Py_DECREF(cerr);
            goto fallback;
        }
        put(G, 0, 0, &a.s.mG, 1.0);
        put(G, 0, a.f, &w.s.mG, 1.0);
        put_vec(DATA(h), &a.s.vh);
        put_vec(DATA(h) + a.f, &w.s.vh);
        Set *lo = PyFloat_AS_DOUBLE(w.s.r) < PyFloat_AS_DOUBLE(a.s.r) ? &w.s : &a.s;
        P = make(freeze(G), freeze(c), freeze(Az), freeze(bz), freeze(h), new_ref(lo->r),
                 cerr, new_ref(Py_None));
        if (P == NULL) goto error;
        if (w.dense) {
            xr = w.s.mA;
            xb = w.vb;
            xbe = w.vberr;
            xoff = a.f;
        }
    } else {
        PyObject *pair[3] = {a.P, w.P, args[3]};
        S = intersect(mod, pair, 3);
        if (S == NULL) goto error;
        Set s;
        if (S == Py_None || !read_set(S, &s) || s.ng != f) goto fallback;
        xr = s.mA;
        xb = s.vb;
        xbe = s.vberr;
        if (!(A0 = new_mat(0, f, 1)) || !(b0 = new_vec(0))) goto error;
        P = make(new_ref(s.G), new_ref(s.c), freeze(A0), freeze(b0), new_ref(s.h),
                 new_ref(s.r), new_ref(s.cerr), new_ref(Py_None));
        A0 = b0 = NULL;
        if (P == NULL) goto error;
    }
    npy_intp mw = w.dense ? 0 : w.m, m = a.m + mw + xr.r;
    npy_intp nnz = a.nnz + (w.dense ? 0 : w.nnz);
    for (npy_intp i = 0; i < xr.r; i++)
        for (npy_intp j = 0; j < xr.c; j++) nnz += AT(xr, i, j) != 0.0;
    if (!(Ti = new_ivec(nnz)) || !(Tj = new_ivec(nnz)) || !(Tv = new_vec(nnz)) ||
        !(b = new_vec(m)))
        goto error;
    int exact = a.vberr.p == NULL && (w.dense || w.vberr.p == NULL) && xbe.p == NULL;
    if (!exact && !(be = new_vec(m))) goto error;
    {
        npy_intp db[1] = {f};
        if (!(bin = (PyArrayObject *)PyArray_ZEROS(1, db, NPY_BOOL, 0))) goto error;
    }
    npy_int64 *id = (npy_int64 *)PyArray_DATA(Ti), *jd = (npy_int64 *)PyArray_DATA(Tj);
    double *vd = DATA(Tv), *bd = DATA(b), *bed = exact ? NULL : DATA(be);
    npy_intp e = 0;
    for (npy_intp k = 0; k < a.nnz; k++) {
        id[e] = IAT(a.vi, k);
        jd[e] = IAT(a.vj, k);
        vd[e++] = VAT(a.vv, k);
    }
    if (!w.dense)
        for (npy_intp k = 0; k < w.nnz; k++) {
            id[e] = IAT(w.vi, k) + a.m;
            jd[e] = IAT(w.vj, k) + a.f;
            vd[e++] = VAT(w.vv, k);
        }
    put_dense_triplets(&xr, a.m + mw, xoff, id, jd, vd, &e);
    for (npy_intp i = 0; i < a.m; i++) bd[i] = VAT(a.vb, i);
    for (npy_intp i = 0; i < mw; i++) bd[a.m + i] = VAT(w.vb, i);
    for (npy_intp i = 0; i < xr.r; i++) bd[a.m + mw + i] = VAT(xb, i);
    if (!exact) {
        for (npy_intp i = 0; i < a.m; i++) bed[i] = a.vberr.p ? VAT(a.vberr, i) : 0.0;
        for (npy_intp i = 0; i < mw; i++) bed[a.m + i] = w.vberr.p ? VAT(w.vberr, i) : 0.0;
        for (npy_intp i = 0; i < xr.r; i++) bed[a.m + mw + i] = xbe.p ? VAT(xbe, i) : 0.0;
    }
    npy_bool *bn = (npy_bool *)PyArray_DATA(bin);
    for (npy_intp j = 0; j < a.f; j++) bn[j] = *(const npy_bool *)(a.bin + j * a.bin_s);
    if (w.bin)
        for (npy_intp j = 0; j < w.f; j++)
            bn[a.f + j] = *(const npy_bool *)(w.bin + j * w.bin_s);
    /* (nnz counted exactly the entries written: e == nnz) */
    PyObject *berr;
    if (exact) {
        berr = new_ref(Py_None);
    } else {
        berr = freeze_err((PyObject *)be);
    }
    be = NULL;
    if (berr == NULL) goto error;
    result = new_hybrid(P, (PyObject *)Ti, (PyObject *)Tj, (PyObject *)Tv, f, freeze(b), berr,
                        freeze(bin));
    P = NULL;
    Ti = Tj = Tv = b = bin = NULL;
    goto done;
fallback:
    result = new_ref(Py_None);
    goto done;
error:
    result = NULL;
done:
    Py_XDECREF(P);
    Py_XDECREF(S);
    Py_XDECREF(Ti);
    Py_XDECREF(Tj);
    Py_XDECREF(Tv);
    Py_XDECREF(b);
    Py_XDECREF(be);
    Py_XDECREF(bin);
    Py_XDECREF(A0);
    Py_XDECREF(b0);
    return result;
}

/* ------------------------------------------------------------------ binding */
/* bind(cls, MAX_MAGNITUDE): the offsets of the slots this module writes, after checking
   that they are exactly the class's object slots. A slot the class has and this module
   does not know would be left unset (NULL) in every set built here, silently; so would
   a slot added to __slots__ in Python without a rebuild. Such a class is refused
   (TypeError), and the Python side then runs its NumPy code. Nothing is changed unless
   the whole layout matches. */
/* The offsets of the object slots `names` of class cls, after checking that they are
   exactly the class's object slots (its own and its bases'; no __dict__); -1 with a
   TypeError otherwise. */
static int class_offsets(PyObject *cls, const char *const *names, int n, Py_ssize_t *out) {
    if (!PyType_Check(cls)) {
        PyErr_SetString(PyExc_TypeError, "expected a class");
        return -1;
    }
    PyTypeObject *tp = (PyTypeObject *)cls;
    for (int i = 0; i < n; i++) {
        PyObject *d = PyObject_GetAttrString(cls, names[i]);
        if (d == NULL) return -1;
        if (!Py_IS_TYPE(d, &PyMemberDescr_Type) ||
            ((PyMemberDescrObject *)d)->d_member->type != T_OBJECT_EX) {
            Py_DECREF(d);
            PyErr_Format(PyExc_TypeError, "%s is not an object slot", names[i]);
            return -1;
        }
        out[i] = ((PyMemberDescrObject *)d)->d_member->offset;
        Py_DECREF(d);
    }
    Py_ssize_t n_members = 0;
    for (PyTypeObject *t = tp; t != NULL && t != &PyBaseObject_Type; t = t->tp_base) {
        for (PyMemberDef *m = t->tp_members; m != NULL && m->name != NULL; m++) {
            if (m->type != T_OBJECT_EX) continue;
            int known = 0;
            for (int i = 0; i < n; i++) {
                if (strcmp(m->name, names[i]) == 0) known = 1;
            }
            if (!known) {
                PyErr_Format(PyExc_TypeError,
                             "the class has a slot %s that the compiled set operations do "
                             "not write (rebuild the extension after changing __slots__)",
                             m->name);
                return -1;
            }
            n_members++;
        }
    }
    if (n_members != n || tp->tp_dictoffset != 0) {
        PyErr_Format(PyExc_TypeError,
                     "the class's layout (%zd object slots%s) is not the %d the compiled set "
                     "operations write", n_members,
                     tp->tp_dictoffset != 0 ? " and a __dict__" : "", n);
        return -1;
    }
    return 0;
}

/* bind(cls, MAX_MAGNITUDE): the offsets of the slots this module writes, after checking
   that they are exactly the class's object slots. A slot the class has and this module
   does not know would be left unset (NULL) in every set built here, silently; so would
   a slot added to __slots__ in Python without a rebuild. Such a class is refused
   (TypeError), and the Python side then runs its NumPy code. Nothing is changed unless
   the whole layout matches. */
static PyObject *bind(PyObject *mod, PyObject *const *args, Py_ssize_t nargs) {
    PyObject *cls = nargs == 2 ? args[0] : NULL;
    if (cls == NULL || !PyType_Check(cls) || !PyFloat_Check(args[1])) {
        PyErr_SetString(PyExc_TypeError,
                        "bind(ConstrainedZonotope, MAX_MAGNITUDE) expects the class and a float");
        return NULL;
    }
    Py_ssize_t found[NSLOTS];
    if (class_offsets(cls, slot_names, NSLOTS, found) < 0) return NULL;
    max_mag = PyFloat_AS_DOUBLE(args[1]);
    for (int i = 0; i < NSLOTS; i++) offsets[i] = found[i];
    Py_XSETREF(cz_type, (PyTypeObject *)Py_NewRef(cls));
    Py_RETURN_NONE;
}

/* bind_hybrid(HybridZonotope, rows class): as bind(), for the classes the hybrid
   operations build (after bind(): they read constrained zonotopes too). */
static PyObject *bind_hybrid(PyObject *mod, PyObject *const *args, Py_ssize_t nargs) {
    if (nargs != 2 || cz_type == NULL) {
        PyErr_SetString(PyExc_TypeError,
                        "bind_hybrid(HybridZonotope, rows class) after bind()");
        return NULL;
    }
    Py_ssize_t fh[NHSLOTS], fw[NWSLOTS];
    if (class_offsets(args[0], hslot_names, NHSLOTS, fh) < 0 ||
        class_offsets(args[1], wslot_names, NWSLOTS, fw) < 0)
        return NULL;
    for (int i = 0; i < NHSLOTS; i++) hoffsets[i] = fh[i];
    for (int i = 0; i < NWSLOTS; i++) woffsets[i] = fw[i];
    Py_XSETREF(hz_type, (PyTypeObject *)Py_NewRef(args[0]));
    Py_XSETREF(rows_type, (PyTypeObject *)Py_NewRef(args[1]));
    Py_RETURN_NONE;
}

static PyMethodDef methods[] = {
    {"bind", (PyCFunction)(void (*)(void))bind, METH_FASTCALL,
     "Bind the slots of the ConstrainedZonotope class and the largest data magnitude."},
    {"bind_hybrid", (PyCFunction)(void (*)(void))bind_hybrid, METH_FASTCALL,
     "Bind the slots of the HybridZonotope class and of its rows' class."},
    {"check_data", (PyCFunction)(void (*)(void))check_data, METH_FASTCALL,
     "None if a set's data are finite and within MAX_MAGNITUDE, else (argument, flat "
     "index, value) of the first bad entry."},
    {"minkowski_sum", (PyCFunction)(void (*)(void))minkowski_sum, METH_FASTCALL,
     "Z + W (Scott et al. 2016, eq. (12)); None if the fast path does not apply."},
    {"linear_map", (PyCFunction)(void (*)(void))linear_map, METH_FASTCALL,
     "M Z (Scott et al. 2016, eq. (11)); None if the fast path does not apply."},
    {"intersect", (PyCFunction)(void (*)(void))intersect, METH_FASTCALL,
     "{z in Z : R z in W} (Scott et al. 2016, eq. (13)); None if the fast path does not "
     "apply."},
    {"hybrid_union", (PyCFunction)(void (*)(void))hybrid_union, METH_FASTCALL,
     "The union of constrained or hybrid zonotopes (hybrid.py's _union); None if the fast "
     "path does not apply."},
    {"hybrid_combine", (PyCFunction)(void (*)(void))hybrid_combine, METH_FASTCALL,
     "A hybrid zonotope's Minkowski sum or generalised intersection with a hybrid or "
     "constrained zonotope; None if the fast path does not apply."},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef moduledef = {PyModuleDef_HEAD_INIT, "_setops",
                                       "Compiled exact set operations (see zonotope.py).",
                                       -1, methods, NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__setops(void) {
    import_array();
    lp_key = PyUnicode_InternFromString("lp");
    if (lp_key == NULL) return NULL;
    return PyModule_Create(&moduledef);
}
