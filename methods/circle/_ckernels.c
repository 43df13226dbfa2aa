/* Compiled kernels of the circle fits: each function is ONE sweep over the (N, 2) points.
 *
 * Which pass does what (a closed-form fit through methods.fit makes exactly three sweeps, the numbers
 * below; Gauss-Newton / Levenberg-Marquardt make the first, then one `geometric` sweep per iteration and
 * one `radial` sweep for the result):
 *
 *   1. frame_stats(points)            validation + frame: finiteness (sums stay finite), the centroid and
 *                                     the centred scatter Sxx, Syy, Sxy (-> unit-frame scale sqrt((Sxx+Syy)/N)
 *                                     and the collinearity test), per block of BLOCK points: block sums of the
 *                                     coordinates relative to the first point, then the block's deviations
 *                                     from its own mean while the block is in L1 cache (corrected two-pass),
 *                                     blocks merged pairwise by Chan's formula;
 *   2. moments(points, cx, cy, s)     the moments of the CENTRED, SCALED data u = (X - cx)/s, v = (Y - cy)/s,
 *                                     z = u^2 + v^2: sums of zz, zu, zv, uu, vv, uv, u, v, z;
 *   3. radial(points, cx, cy, R, out) r_i = |P_i - c| in data units, out_i = r_i - R, min r, max r and
 *                                     sum (r_i - R)^2 (form error and RMS of the result);
 *   geometric(points, cx, cy, s, p, q)  one Gauss-Newton/LM sweep at unit-frame circle q = (a, b, R):
 *                                     J^T J, J^T d and F = sum d_i^2 together (d_i = r_i - R), and when p
 *                                     is given the LM actual reduction F(p) - F(q) free of cancellation.
 *
 * Summation: every sum is accumulated per block of BLOCK points and the block sums are added pairwise
 * (a binary counter of partial sums), so the rounding error grows like (BLOCK + log2(N / BLOCK)) eps,
 * not N eps. Every pass also returns `token`, the sum of the raw coordinates added in the same order
 * as pass 1, so a later pass proves (bit for bit) that the data did not change since validation.
 *
 * Operation order is explicit (compiled without fast-math or FP contraction: same bits on any x86-64).
 * Non-finite input or sums outside the normal range are NOT handled here: the callers see a non-finite
 * result and take the NumPy reference path, which decides and explains.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <string.h>
#include <stdlib.h>

#define BLOCK 256
#define MAXLEV 64
#define NSUM 12

typedef struct {
    int k;
    unsigned char used[MAXLEV];
    double acc[MAXLEV][NSUM];
} pairwise_t;

static void pw_init(pairwise_t *p, int k) { p->k = k; memset(p->used, 0, sizeof p->used); }

static void pw_add(pairwise_t *p, const double *v) {
    double carry[NSUM];
    int j, lev;
    memcpy(carry, v, sizeof(double) * p->k);
    for (lev = 0; lev < MAXLEV; lev++) {
        if (!p->used[lev]) {
            memcpy(p->acc[lev], carry, sizeof(double) * p->k);
            p->used[lev] = 1;
            return;
        }
        for (j = 0; j < p->k; j++) carry[j] = p->acc[lev][j] + carry[j];
        p->used[lev] = 0;
    }
}

static void pw_total(const pairwise_t *p, double *out) {
    int j, lev, first = 1;
    for (j = 0; j < p->k; j++) out[j] = 0.0;
    for (lev = 0; lev < MAXLEV; lev++) {
        if (!p->used[lev]) continue;
        for (j = 0; j < p->k; j++) out[j] = first ? p->acc[lev][j] : out[j] + p->acc[lev][j];
        first = 0;
    }
}

/* Two-lane arithmetic (GCC/Clang vector extension; SSE2 on x86-64, NEON on aarch64, else lane by lane):
   the points of a block are taken in pairs, lane 0 the even and lane 1 the odd points; every lane
   operation is the IEEE operation its C source names, so the bits do not depend on the CPU. At the end of
   a block, sum = lane 0 + lane 1, then + the block's last point when the block has an odd count. */
typedef double v2d __attribute__((vector_size(16)));
#if defined(__SSE2__)
#include <emmintrin.h>
static inline v2d vsqrt(v2d a) { return (v2d)_mm_sqrt_pd((__m128d)a); }
static inline v2d vmin(v2d a, v2d b) { return (v2d)_mm_min_pd((__m128d)a, (__m128d)b); }
static inline v2d vmax(v2d a, v2d b) { return (v2d)_mm_max_pd((__m128d)a, (__m128d)b); }
#else
static inline v2d vsqrt(v2d a) { v2d r = {sqrt(a[0]), sqrt(a[1])}; return r; }
static inline v2d vmin(v2d a, v2d b) { v2d r = {a[0] < b[0] ? a[0] : b[0], a[1] < b[1] ? a[1] : b[1]}; return r; }
static inline v2d vmax(v2d a, v2d b) { v2d r = {a[0] > b[0] ? a[0] : b[0], a[1] > b[1] ? a[1] : b[1]}; return r; }
#endif
static inline v2d vset(double a) { v2d r = {a, a}; return r; }
static inline double hsum(v2d a) { return a[0] + a[1]; }
/* the x and y of points i, i + 1 (interleaved input) */
#define LOAD_PAIR(X, Y, p, i) do { (X) = (v2d){(p)[2 * (i)], (p)[2 * (i) + 2]}; \
                                   (Y) = (v2d){(p)[2 * (i) + 1], (p)[2 * (i) + 3]}; } while (0)
/* the data's token: per block (sum of its x) + (sum of its y), the sums taken lane-wise as above, and the
   block tokens added in order; every pass computes it with these same operations */

static int get_points(PyObject *obj, Py_buffer *view, Py_ssize_t *n) {
    if (PyObject_GetBuffer(obj, view, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) != 0) return -1;
    if (view->itemsize != 8 || (view->format && strcmp(view->format, "d") != 0 && strcmp(view->format, "<d") != 0
                                && strcmp(view->format, "=d") != 0)) {
        PyBuffer_Release(view);
        PyErr_SetString(PyExc_TypeError, "points must be a C-contiguous float64 buffer");
        return -1;
    }
    if (view->len % 16 != 0) {
        PyBuffer_Release(view);
        PyErr_SetString(PyExc_ValueError, "points must hold x, y pairs (an (N, 2) float64 array)");
        return -1;
    }
    *n = view->len / 16;
    return 0;
}

/* ---- pass 1: centroid and centred scatter ------------------------------------------------------- */
typedef struct { double n, mx, my, cxx, cyy, cxy; } moments2_t;

static moments2_t chan_merge(moments2_t a, moments2_t b) {
    moments2_t m;
    double n = a.n + b.n, dx = b.mx - a.mx, dy = b.my - a.my, w = a.n * b.n / n;
    m.n = n;
    m.mx = a.mx + dx * (b.n / n);
    m.my = a.my + dy * (b.n / n);
    m.cxx = (a.cxx + b.cxx) + dx * dx * w;
    m.cyy = (a.cyy + b.cyy) + dy * dy * w;
    m.cxy = (a.cxy + b.cxy) + dx * dy * w;
    return m;
}

static PyObject *frame_stats(PyObject *self, PyObject *args) {
    PyObject *obj;
    Py_buffer view;
    Py_ssize_t n, i0, i;
    moments2_t stack[MAXLEV], tot;
    unsigned char used[MAXLEV];
    double token = 0.0, x0, y0;
    int lev;
    if (!PyArg_ParseTuple(args, "O", &obj)) return NULL;
    if (get_points(obj, &view, &n) != 0) return NULL;
    if (n == 0) {
        PyBuffer_Release(&view);
        PyErr_SetString(PyExc_ValueError, "frame_stats needs at least one point");
        return NULL;
    }
    memset(used, 0, sizeof used);
    Py_BEGIN_ALLOW_THREADS
    const double *p = (const double *)view.buf;
    /* sums of X - x0, Y - y0 about the first point: exact differences (Sterbenz) for data far from the
       origin, so block means and Chan's merge terms are rounded relative to the spread, not to |X| */
    x0 = p[0];
    y0 = p[1];
    v2d vx0 = vset(x0), vy0 = vset(y0);
    for (i0 = 0; i0 < n; i0 += BLOCK) {
        Py_ssize_t i1 = i0 + BLOCK < n ? i0 + BLOCK : n;
        double nb = (double)(i1 - i0), sx, sy, rx, ry, mx, my, ex, ey, cxx, cyy, cxy;
        v2d tx = vset(0.0), ty = vset(0.0), vrx = vset(0.0), vry = vset(0.0), X, Y, vmx, vmy, vex = vset(0.0),
            vey = vset(0.0), vxx = vset(0.0), vyy = vset(0.0), vxy = vset(0.0);
        moments2_t carry;
        for (i = i0; i + 1 < i1; i += 2) {
            LOAD_PAIR(X, Y, p, i);
            tx = tx + X;
            ty = ty + Y;
            vrx = vrx + (X - vx0);
            vry = vry + (Y - vy0);
        }
        sx = hsum(tx);
        sy = hsum(ty);
        rx = hsum(vrx);
        ry = hsum(vry);
        if (i < i1) {
            sx = sx + p[2 * i]; sy = sy + p[2 * i + 1];
            rx = rx + (p[2 * i] - x0); ry = ry + (p[2 * i + 1] - y0);
        }
        mx = rx / nb;  /* block mean relative to the first point: O(spread), rounded relative to it */
        my = ry / nb;
        vmx = vset(mx);
        vmy = vset(my);
        for (i = i0; i + 1 < i1; i += 2) {  /* the block is in L1 cache: no second sweep over memory */
            v2d dx, dy;
            LOAD_PAIR(X, Y, p, i);
            dx = (X - vx0) - vmx;
            dy = (Y - vy0) - vmy;
            vex = vex + dx;
            vey = vey + dy;
            vxx = vxx + dx * dx;
            vyy = vyy + dy * dy;
            vxy = vxy + dx * dy;
        }
        ex = hsum(vex); ey = hsum(vey); cxx = hsum(vxx); cyy = hsum(vyy); cxy = hsum(vxy);
        if (i < i1) {
            double dx = (p[2 * i] - x0) - mx, dy = (p[2 * i + 1] - y0) - my;
            ex = ex + dx; ey = ey + dy; cxx = cxx + dx * dx; cyy = cyy + dy * dy; cxy = cxy + dx * dy;
        }
        /* corrected two-pass: remove the rounding of the block mean */
        carry.n = nb;
        carry.mx = mx + ex / nb;
        carry.my = my + ey / nb;
        carry.cxx = cxx - ex * ex / nb;
        carry.cyy = cyy - ey * ey / nb;
        carry.cxy = cxy - ex * ey / nb;
        token = token + (sx + sy);
        for (lev = 0; lev < MAXLEV; lev++) {
            if (!used[lev]) { stack[lev] = carry; used[lev] = 1; break; }
            carry = chan_merge(stack[lev], carry);
            used[lev] = 0;
        }
    }
    {
        int first = 1;
        for (lev = 0; lev < MAXLEV; lev++) {
            if (!used[lev]) continue;
            tot = first ? stack[lev] : chan_merge(stack[lev], tot);
            first = 0;
        }
    }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&view);
    return Py_BuildValue("(dddddd)", token, x0 + tot.mx, y0 + tot.my, tot.cxx, tot.cyy, tot.cxy);
}

/* ---- pass 2: moments of the centred, scaled data ------------------------------------------------- */
static PyObject *moments(PyObject *self, PyObject *args) {
    PyObject *obj;
    Py_buffer view;
    Py_ssize_t n, i0, i;
    double cx, cy, s, token = 0.0, out[9];
    pairwise_t pw;
    if (!PyArg_ParseTuple(args, "Oddd", &obj, &cx, &cy, &s)) return NULL;
    if (get_points(obj, &view, &n) != 0) return NULL;
    pw_init(&pw, 9);
    Py_BEGIN_ALLOW_THREADS
    const double *p = (const double *)view.buf;
    v2d vcx = vset(cx), vcy = vset(cy), vs = vset(s);
    for (i0 = 0; i0 < n; i0 += BLOCK) {
        Py_ssize_t i1 = i0 + BLOCK < n ? i0 + BLOCK : n;
        v2d X, Y, tx = vset(0.0), ty = vset(0.0), zz = vset(0.0), zu = vset(0.0), zv = vset(0.0), uu = vset(0.0),
                  vv = vset(0.0), uv = vset(0.0), su = vset(0.0), sv = vset(0.0), sz = vset(0.0);
        double b[9], sx, sy;
        for (i = i0; i + 1 < i1; i += 2) {
            v2d u, v, z;
            LOAD_PAIR(X, Y, p, i);
            u = (X - vcx) / vs;  /* the unit frame: u = (X - cx) / s, as methods/_frame.py */
            v = (Y - vcy) / vs;
            z = u * u + v * v;
            tx = tx + X;
            ty = ty + Y;
            zz = zz + z * z;
            zu = zu + z * u;
            zv = zv + z * v;
            uu = uu + u * u;
            vv = vv + v * v;
            uv = uv + u * v;
            su = su + u;
            sv = sv + v;
            sz = sz + z;
        }
        sx = hsum(tx); sy = hsum(ty);
        b[0] = hsum(zz); b[1] = hsum(zu); b[2] = hsum(zv); b[3] = hsum(uu); b[4] = hsum(vv); b[5] = hsum(uv);
        b[6] = hsum(su); b[7] = hsum(sv); b[8] = hsum(sz);
        if (i < i1) {
            double u = (p[2 * i] - cx) / s, v = (p[2 * i + 1] - cy) / s, z = u * u + v * v;
            sx = sx + p[2 * i]; sy = sy + p[2 * i + 1];
            b[0] = b[0] + z * z; b[1] = b[1] + z * u; b[2] = b[2] + z * v; b[3] = b[3] + u * u;
            b[4] = b[4] + v * v; b[5] = b[5] + u * v; b[6] = b[6] + u; b[7] = b[7] + v; b[8] = b[8] + z;
        }
        token = token + (sx + sy);
        pw_add(&pw, b);
    }
    pw_total(&pw, out);
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&view);
    return Py_BuildValue("(dddddddddd)", token, out[0], out[1], out[2], out[3], out[4], out[5], out[6], out[7],
                         out[8]);
}

/* ---- pass 3: radial residuals of the result ----------------------------------------------------- */
static PyObject *radial(PyObject *self, PyObject *args) {
    PyObject *obj;
    Py_buffer view, res;
    Py_ssize_t n, i0, i;
    double cx, cy, R, rmin = INFINITY, rmax = -INFINITY, ss;
    long long outside;
    pairwise_t pw;
    if (!PyArg_ParseTuple(args, "Odddw*", &obj, &cx, &cy, &R, &res)) return NULL;
    if (get_points(obj, &view, &n) != 0) { PyBuffer_Release(&res); return NULL; }
    if (res.len != n * 8 || res.itemsize != 8 || !PyBuffer_IsContiguous(&res, 'C')) {
        PyBuffer_Release(&view);
        PyBuffer_Release(&res);
        PyErr_SetString(PyExc_ValueError, "radial: out must be a contiguous float64 buffer of N numbers");
        return NULL;
    }
    pw_init(&pw, 1);
    Py_BEGIN_ALLOW_THREADS
    const double *p = (const double *)view.buf;
    double *o = (double *)res.buf;
    v2d vcx = vset(cx), vcy = vset(cy), vR = vset(R), vlo = vset(INFINITY), vhi = vset(-INFINITY);
    for (i0 = 0; i0 < n; i0 += BLOCK) {
        Py_ssize_t i1 = i0 + BLOCK < n ? i0 + BLOCK : n;
        v2d X, Y, acc = vset(0.0);
        double b;
        for (i = i0; i + 1 < i1; i += 2) {
            v2d dx, dy, r, d;
            LOAD_PAIR(X, Y, p, i);
            dx = X - vcx;
            dy = Y - vcy;
            r = vsqrt(dx * dx + dy * dy);  /* as methods/result_base.py::radial_distances: same bits */
            d = r - vR;
            o[i] = d[0];
            o[i + 1] = d[1];
            vlo = vmin(vlo, r);
            vhi = vmax(vhi, r);
            acc = acc + d * d;
        }
        b = hsum(acc);
        if (i < i1) {
            double dx = p[2 * i] - cx, dy = p[2 * i + 1] - cy, r = sqrt(dx * dx + dy * dy), d = r - R;
            o[i] = d;
            if (r < rmin) rmin = r;
            if (r > rmax) rmax = r;
            b = b + d * d;
        }
        pw_add(&pw, &b);
    }
    pw_total(&pw, &ss);
    if (vlo[0] < rmin) rmin = vlo[0];
    if (vlo[1] < rmin) rmin = vlo[1];
    if (vhi[0] > rmax) rmax = vhi[0];
    if (vhi[1] > rmax) rmax = vhi[1];
    Py_END_ALLOW_THREADS
    /* a distance outside (1e-145, 1e150) may come from a squared distance outside the normal range, and a
       NaN distance makes the sum of squares NaN: either way the caller takes np.hypot */
    outside = !(rmin > 1e-145 && rmax < 1e150 && isfinite(ss));
    PyBuffer_Release(&view);
    PyBuffer_Release(&res);
    return Py_BuildValue("(dddL)", rmin, rmax, ss, outside);
}

/* ---- Gauss-Newton / LM sweep ----------------------------------------------------------------------- */
static PyObject *geometric(PyObject *self, PyObject *args) {
    PyObject *obj, *prev = Py_None;
    Py_buffer view;
    Py_ssize_t n, i0, i;
    double cx, cy, s, a, b, R, a0 = 0.0, b0 = 0.0, R0 = 0.0, token = 0.0, out[11];
    int with_prev = 0;
    pairwise_t pw;
    if (!PyArg_ParseTuple(args, "Oddd(ddd)|O", &obj, &cx, &cy, &s, &a, &b, &R, &prev)) return NULL;
    if (prev != Py_None) {
        if (!PyArg_ParseTuple(prev, "ddd", &a0, &b0, &R0)) return NULL;
        with_prev = 1;
    }
    if (get_points(obj, &view, &n) != 0) return NULL;
    pw_init(&pw, 11);
    Py_BEGIN_ALLOW_THREADS
    const double *p = (const double *)view.buf;
    double ha = a - a0, hb = b - b0, hR = R - R0, inv_s = 1.0 / s;
    v2d vcx = vset(cx), vcy = vset(cy), vinv = vset(inv_s), va = vset(a), vb = vset(b), vR = vset(R);
    v2d va0 = vset(a0), vb0 = vset(b0), vR0 = vset(R0), vha = vset(ha), vhb = vset(hb), vhR = vset(hR);
    v2d one = vset(1.0), two = vset(2.0);
    for (i0 = 0; i0 < n; i0 += BLOCK) {
        Py_ssize_t i1 = i0 + BLOCK < n ? i0 + BLOCK : n;
        v2d X, Y, tx = vset(0.0), ty = vset(0.0), cc = vset(0.0), cs = vset(0.0), ss = vset(0.0), sc = vset(0.0),
                  ssn = vset(0.0), cd = vset(0.0), sd = vset(0.0), sdd = vset(0.0), dd = vset(0.0), red = vset(0.0);
        double t[11], sx, sy;
        for (i = i0; i + 1 < i1; i += 2) {
            v2d u, v, dx, dy, r, inv_r, c, sn, d;
            LOAD_PAIR(X, Y, p, i);
            /* u = (X - cx) / s to within one rounding (times 1/s: divisions are the slow part) */
            u = (X - vcx) * vinv;
            v = (Y - vcy) * vinv;
            dx = u - va;
            dy = v - vb;
            r = vsqrt(dx * dx + dy * dy);
            inv_r = one / r;  /* r = 0 (a point at the centre) makes the sums NaN: the caller sees it */
            c = dx * inv_r;
            sn = dy * inv_r;
            d = r - vR;
            tx = tx + X;
            ty = ty + Y;
            cc = cc + c * c;
            cs = cs + c * sn;
            ss = ss + sn * sn;
            sc = sc + c;
            ssn = ssn + sn;
            cd = cd + c * d;
            sd = sd + sn * d;
            sdd = sdd + d;
            dd = dd + d * d;
            if (with_prev) {
                /* F(p) - F(q) = -sum (d' - d)(d' + d), d' - d = (r'^2 - r^2)/(r' + r) - h_R with
                   r'^2 - r^2 = -h_a (2 dx0 - h_a) - h_b (2 dy0 - h_b): no cancellation near the optimum */
                v2d dx0 = u - va0, dy0 = v - vb0, r0, d0, delta;
                r0 = vsqrt(dx0 * dx0 + dy0 * dy0);
                d0 = r0 - vR0;
                delta = (-vha * (two * dx0 - vha) - vhb * (two * dy0 - vhb)) / (r + r0) - vhR;
                red = red + delta * (two * d0 + delta);
            }
        }
        sx = hsum(tx); sy = hsum(ty);
        t[0] = hsum(cc); t[1] = hsum(cs); t[2] = hsum(ss); t[3] = hsum(sc); t[4] = hsum(ssn); t[5] = hsum(cd);
        t[6] = hsum(sd); t[7] = hsum(sdd); t[8] = hsum(dd); t[9] = 0.0; t[10] = hsum(red);
        if (i < i1) {
            double u = (p[2 * i] - cx) * inv_s, v = (p[2 * i + 1] - cy) * inv_s, dx = u - a, dy = v - b;
            double r = sqrt(dx * dx + dy * dy), inv_r = 1.0 / r, c = dx * inv_r, sn = dy * inv_r, d = r - R;
            sx = sx + p[2 * i]; sy = sy + p[2 * i + 1];
            t[0] = t[0] + c * c; t[1] = t[1] + c * sn; t[2] = t[2] + sn * sn; t[3] = t[3] + c; t[4] = t[4] + sn;
            t[5] = t[5] + c * d; t[6] = t[6] + sn * d; t[7] = t[7] + d; t[8] = t[8] + d * d;
            if (with_prev) {
                double dx0 = u - a0, dy0 = v - b0, r0 = sqrt(dx0 * dx0 + dy0 * dy0), d0 = r0 - R0;
                double delta = (-ha * (2.0 * dx0 - ha) - hb * (2.0 * dy0 - hb)) / (r + r0) - hR;
                t[10] = t[10] + delta * (2.0 * d0 + delta);
            }
        }
        token = token + (sx + sy);
        pw_add(&pw, t);
    }
    pw_total(&pw, out);
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&view);
    return Py_BuildValue("(dddddddddddL)", token, out[0], out[1], out[2], out[3], out[4], out[5], out[6], out[7],
                         out[8], with_prev ? -out[10] : 0.0, 0LL);
}

/* ---- the unit-frame coordinates, for the methods that work on arrays ------------------------------- */
static PyObject *unit_coords(PyObject *self, PyObject *args) {
    PyObject *obj;
    Py_buffer view, res;
    Py_ssize_t n, i0, i;
    double cx, cy, s, token = 0.0;
    if (!PyArg_ParseTuple(args, "Odddw*", &obj, &cx, &cy, &s, &res)) return NULL;
    if (get_points(obj, &view, &n) != 0) { PyBuffer_Release(&res); return NULL; }
    if (res.len < 2 * n * 8 || res.itemsize != 8 || !PyBuffer_IsContiguous(&res, 'C')) {
        PyBuffer_Release(&view);
        PyBuffer_Release(&res);
        PyErr_SetString(PyExc_ValueError, "unit_coords: out must be a contiguous float64 buffer of at least 2N numbers");
        return NULL;
    }
    Py_BEGIN_ALLOW_THREADS
    const double *p = (const double *)view.buf;
    double *x = (double *)res.buf, *y = x + n;
    for (i0 = 0; i0 < n; i0 += BLOCK) {
        Py_ssize_t i1 = i0 + BLOCK < n ? i0 + BLOCK : n;
        v2d X, Y, tx = vset(0.0), ty = vset(0.0);
        double sx, sy;
        for (i = i0; i + 1 < i1; i += 2) {
            LOAD_PAIR(X, Y, p, i);
            tx = tx + X;
            ty = ty + Y;
        }
        sx = hsum(tx); sy = hsum(ty);
        if (i < i1) { sx = sx + p[2 * i]; sy = sy + p[2 * i + 1]; }
        for (i = i0; i < i1; i++) {  /* as numpy: x = (X - cx) / s */
            x[i] = (p[2 * i] - cx) / s;
            y[i] = (p[2 * i + 1] - cy) / s;
        }
        token = token + (sx + sy);
    }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&view);
    PyBuffer_Release(&res);
    return PyFloat_FromDouble(token);
}


/* ---- small dense solve: 3x3 by Gaussian elimination with partial pivoting (as LAPACK dgesv) ------- */
static PyObject *solve3(PyObject *self, PyObject *args) {
    double A[3][3], x[3], bb[3], amax = 0.0, rtol = 0.0;
    int i, j, k;
    if (!PyArg_ParseTuple(args, "(ddddddddd)(ddd)|d", &A[0][0], &A[0][1], &A[0][2], &A[1][0], &A[1][1], &A[1][2],
                          &A[2][0], &A[2][1], &A[2][2], &bb[0], &bb[1], &bb[2], &rtol))
        return NULL;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            if (fabs(A[i][j]) > amax) amax = fabs(A[i][j]);
    for (k = 0; k < 3; k++) {
        int piv = k;
        for (i = k + 1; i < 3; i++)
            if (fabs(A[i][k]) > fabs(A[piv][k])) piv = i;
        /* singular: an exact zero pivot (as LAPACK's dgesv), or with rtol > 0 a pivot |u_kk| <= rtol max|a_ij| */
        if (A[piv][k] == 0.0 || (rtol > 0.0 && !(fabs(A[piv][k]) > rtol * amax))) Py_RETURN_NONE;
        if (piv != k) {
            for (j = 0; j < 3; j++) { double t = A[k][j]; A[k][j] = A[piv][j]; A[piv][j] = t; }
            { double t = bb[k]; bb[k] = bb[piv]; bb[piv] = t; }
        }
        {
            double rp = 1.0 / A[k][k];  /* as LAPACK's dgetf2: the column scaled by the pivot's reciprocal */
            for (i = k + 1; i < 3; i++) {
                double l = A[i][k] * rp;
                for (j = k + 1; j < 3; j++) A[i][j] = A[i][j] - l * A[k][j];
                bb[i] = bb[i] - l * bb[k];
            }
        }
    }
    for (i = 0; i < 3; i++) x[i] = bb[i];
    for (k = 2; k >= 0; k--) {  /* as LAPACK's dtrsm (upper, column by column) */
        x[k] = x[k] / A[k][k];
        for (i = 0; i < k; i++) x[i] = x[i] - x[k] * A[i][k];
    }
    return Py_BuildValue("(ddd)", x[0], x[1], x[2]);
}

/* ---- 4x4 symmetric eigenproblems of the Pratt / Taubin / Hyper fits ------------------------------- */
/* Cyclic Jacobi (Rutishauser's rotation formulas, Golub & Van Loan alg. 8.5.3): A = V diag(w) V^T; the
   eigenvalues come out with small absolute error relative to ||A|| (as LAPACK's dsyevd's), sorted
   descending with V's columns. */
static void jacobi4(double a[4][4], double w[4], double v[4][4]) {
    int i, j, k, sweep;
    for (i = 0; i < 4; i++)
        for (j = 0; j < 4; j++) v[i][j] = (i == j) ? 1.0 : 0.0;
    for (sweep = 0; sweep < 64; sweep++) {
        int rotated = 0;
        for (i = 0; i < 3; i++)
            for (j = i + 1; j < 4; j++) {
                double apq = a[i][j], theta, t, c, sn, tau;
                /* Demmel & Veselic's threshold: a rotation smaller than eps sqrt(|a_ii a_jj|) changes nothing
                   (for a positive semi-definite M this keeps small eigenvalues to high relative accuracy) */
                if (fabs(apq) <= 1e-17 * sqrt(fabs(a[i][i] * a[j][j])) || fabs(apq) < 1e-300) continue;
                rotated = 1;
                theta = (a[j][j] - a[i][i]) / (2.0 * apq);
                t = (theta >= 0.0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                if (!isfinite(theta * theta)) t = 0.5 / theta;  /* |theta| huge: t = 1/(2 theta) */
                c = 1.0 / sqrt(t * t + 1.0);
                sn = t * c;
                tau = sn / (1.0 + c);
                a[i][i] = a[i][i] - t * apq;
                a[j][j] = a[j][j] + t * apq;
                a[i][j] = a[j][i] = 0.0;
                for (k = 0; k < 4; k++) {
                    if (k != i && k != j) {
                        double aki = a[k][i], akj = a[k][j];
                        a[k][i] = a[i][k] = aki - sn * (akj + tau * aki);
                        a[k][j] = a[j][k] = akj + sn * (aki - tau * akj);
                    }
                    {
                        double vki = v[k][i], vkj = v[k][j];
                        v[k][i] = vki - sn * (vkj + tau * vki);
                        v[k][j] = vkj + sn * (vki - tau * vkj);
                    }
                }
            }
        if (!rotated) break;
    }
    for (i = 0; i < 4; i++) w[i] = a[i][i];
    for (i = 0; i < 3; i++) {  /* selection sort, descending */
        int m = i;
        for (j = i + 1; j < 4; j++)
            if (w[j] > w[m]) m = j;
        if (m != i) {
            double t = w[i];
            w[i] = w[m];
            w[m] = t;
            for (k = 0; k < 4; k++) { t = v[k][i]; v[k][i] = v[k][m]; v[k][m] = t; }
        }
    }
}

/* eigen_fit(M (16, row major), N (16, row major)) -> (status, a0, a1, a2, a3): min a^T M a subject to
   a^T N a = 1 as methods/circle/algebraic.py::_eigen_fit (M = V S^2 V^T, K = S^-1 V^T N V S^-1, a = V S^-1 b
   for the largest eigenvalue of K). status 0: solved; 1: M singular to rounding (a = null vector of M);
   2: no positive generalised eigenvalue. */
static PyObject *eigen_fit(PyObject *self, PyObject *args) {
    double m[4][4], nn[4][4], lam[4], v[4][4], s[4], kk[4][4], mu[4], b[4][4], t[4][4], a[4];
    int i, j, k, jmax, status = 0;
    if (!PyArg_ParseTuple(args, "(dddddddddddddddd)(dddddddddddddddd)", &m[0][0], &m[0][1], &m[0][2], &m[0][3],
                          &m[1][0], &m[1][1], &m[1][2], &m[1][3], &m[2][0], &m[2][1], &m[2][2], &m[2][3], &m[3][0],
                          &m[3][1], &m[3][2], &m[3][3], &nn[0][0], &nn[0][1], &nn[0][2], &nn[0][3], &nn[1][0],
                          &nn[1][1], &nn[1][2], &nn[1][3], &nn[2][0], &nn[2][1], &nn[2][2], &nn[2][3], &nn[3][0],
                          &nn[3][1], &nn[3][2], &nn[3][3]))
        return NULL;
    jacobi4(m, lam, v);
    if (lam[3] <= 64.0 * 2.220446049250313e-16 * lam[0]) {
        for (i = 0; i < 4; i++) a[i] = v[i][3];
        status = 1;
    } else {
        for (i = 0; i < 4; i++) s[i] = sqrt(lam[i]);
        for (i = 0; i < 4; i++)  /* t = N V */
            for (j = 0; j < 4; j++) {
                double acc = 0.0;
                for (k = 0; k < 4; k++) acc = acc + nn[i][k] * v[k][j];
                t[i][j] = acc;
            }
        for (i = 0; i < 4; i++)  /* K = V^T N V / (s_i s_j) */
            for (j = 0; j < 4; j++) {
                double acc = 0.0;
                for (k = 0; k < 4; k++) acc = acc + v[k][i] * t[k][j];
                kk[i][j] = acc / (s[i] * s[j]);
            }
        for (i = 0; i < 4; i++)  /* exactly symmetric */
            for (j = i + 1; j < 4; j++) kk[j][i] = kk[i][j] = 0.5 * (kk[i][j] + kk[j][i]);
        jacobi4(kk, mu, b);
        jmax = 0;
        if (!(mu[jmax] > 0.0)) {
            status = 2;
            for (i = 0; i < 4; i++) a[i] = NAN;
        } else {
            for (i = 0; i < 4; i++) {
                double acc = 0.0;
                for (k = 0; k < 4; k++) acc = acc + v[i][k] * (b[k][jmax] / s[k]);
                a[i] = acc;
            }
        }
    }
    return Py_BuildValue("(idddd)", status, a[0], a[1], a[2], a[3]);
}

/* psd_decrease(A (9 numbers, symmetric positive semi-definite 3x3), g (3)) -> g^T A^+ g with A^+ the
   pseudo-inverse that drops eigenvalues <= 3 eps max eigenvalue: what np.linalg.lstsq(A, g, rcond=None)
   gives for g^T h (its singular values are these eigenvalues, its cut-off rcond = eps max(M, N)). */
static PyObject *psd_decrease(PyObject *self, PyObject *args) {
    double a[4][4], v[4][4], w[4], g[3], dec = 0.0;
    int i, k;
    memset(a, 0, sizeof a);
    if (!PyArg_ParseTuple(args, "(ddddddddd)(ddd)", &a[0][0], &a[0][1], &a[0][2], &a[1][0], &a[1][1], &a[1][2],
                          &a[2][0], &a[2][1], &a[2][2], &g[0], &g[1], &g[2]))
        return NULL;
    jacobi4(a, w, v);  /* the 4th row and column are zero: an eigenvalue 0 with eigenvector e4, dropped */
    for (i = 0; i < 4; i++) {
        double proj = 0.0;
        if (!(fabs(w[i]) > 3.0 * 2.220446049250313e-16 * fabs(w[0]))) continue;
        for (k = 0; k < 3; k++) proj = proj + v[k][i] * g[k];
        dec = dec + proj * proj / w[i];
    }
    return PyFloat_FromDouble(dec);
}

/* ---- the process environment without os.environ's Python layers ---------------------------------------
 * getenv(name) as bytes or None: what os.environ holds (it updates the C environment through putenv/unsetenv
 * under the GIL, as this reads it), without the KeyError that os.environ.get raises and catches for an unset
 * name (methods/_frame.py reads the kernel choice for every sweep of a fit). */
static PyObject *env_value(PyObject *self, PyObject *name) {
    const char *v;
    if (!PyBytes_Check(name)) {
        PyErr_SetString(PyExc_TypeError, "env_value: the name must be bytes");
        return NULL;
    }
    v = getenv(PyBytes_AS_STRING(name));
    if (v == NULL) Py_RETURN_NONE;
    return PyBytes_FromString(v);
}

static PyMethodDef Methods[] = {
    {"env_value", env_value, METH_O, "env_value(name: bytes) -> the environment variable's value as bytes, or None"},
    {"frame_stats", frame_stats, METH_VARARGS,
     "frame_stats(points) -> (token, mean_x, mean_y, Sxx, Syy, Sxy): pass 1 (centroid, centred scatter)"},
    {"moments", moments, METH_VARARGS,
     "moments(points, cx, cy, s) -> (token, zz, zu, zv, uu, vv, uv, u, v, z): pass 2, sums over the unit frame"},
    {"radial", radial, METH_VARARGS,
     "radial(points, cx, cy, R, out) -> (r_min, r_max, sum (r_i - R)^2, 1 if a distance is NaN or outside (1e-145, 1e150) else 0)"},
    {"geometric", geometric, METH_VARARGS,
     "geometric(points, cx, cy, s, (a, b, R)[, (a0, b0, R0)]) -> (token, cc, cs, ss, c, s, cd, sd, d, dd, "
     "F(p0) - F(p), 0); a point at the centre (r = 0) makes the sums NaN"},
    {"unit_coords", unit_coords, METH_VARARGS,
     "unit_coords(points, cx, cy, s, out) -> token: out[:N] = (X - cx)/s, out[N:2N] = (Y - cy)/s"},
    {"eigen_fit", eigen_fit, METH_VARARGS,
     "eigen_fit(M 16 numbers, N 16 numbers) -> (status, a0..a3): Pratt/Taubin/Hyper generalised eigenproblem"},
    {"psd_decrease", psd_decrease, METH_VARARGS,
     "psd_decrease(A 9 numbers, g 3 numbers) -> g^T pinv(A) g (eigenvalues <= 3 eps max dropped, as lstsq)"},
    {"solve3", solve3, METH_VARARGS, "solve3(A (9 numbers, row major), b (3)[, rtol]) -> x, or None when singular (a zero pivot, or one <= rtol max|A|)"},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_ckernels",
                                    "Compiled kernels of the circle fits; see the C source header.",
                                    -1, Methods};

/* the SHA-256 of this file as setup.py built it (methods/_compiled.py compares it with the file beside the module:
   a kernel built from another version of its source is refused, not run under the new source's cache keys) */
#ifndef FITBENCH_SOURCE_SHA256
#define FITBENCH_SOURCE_SHA256 ""
#endif

PyMODINIT_FUNC PyInit__ckernels(void) {
    PyObject *m = PyModule_Create(&module);
    if (m != NULL && PyModule_AddStringConstant(m, "source_sha256", FITBENCH_SOURCE_SHA256) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
