/* Compiled kernels of the ellipse fits: the orthogonal residuals in ONE sweep over the points, and
 * the moments of the direct fits' 6 x 6 scatter in one more (scatter(), at the end of this file).
 *
 *   orthogonal(x, y, xc, yc, c, s, a, b, iterations, d_out[, phi_out])
 *
 * For every point: its coordinates in the ellipse frame O' (circle/ellipse paper eq. 14,
 * u = dx c + dy s, v = -dx s + dy c with c = cos theta, s = sin theta), the closest point (X, Y) on
 * (X/a)^2 + (Y/b)^2 = 1 and the signed distance (positive outside) written to d_out[i]; with phi_out also
 * the parameter phi = atan2(Y/b, X/a) of the closest point (eq. 17). No temporaries: the peak memory of a
 * direct fit's residuals is the output array itself.
 *
 * The solver is the NumPy reference's (methods/ellipse/_geometry.py::closest_points), point by point:
 * Eberly's first-quadrant root of G(w) = (n0 / (w + r0 - 1))^2 + (z1 / w)^2 - 1 in w = s + 1, bracketed in
 * [z1, |(n0, z1)|], Newton from the right end (convex, decreasing: monotone), one more step after a relative
 * step <= 1e-8; when Newton has not converged within `iterations` steps (points near the centre) the root is
 * finished by bisection in the bracket; points on the major axis are solved in closed form. The reference
 * stops Newton when the largest step of a block of points is small; here each point stops on its own step,
 * so the two paths agree to the solver's rounding, not bit for bit. Points are solved LANES = 16 at a time
 * (closest_block: every step of four points per vector operation, the same IEEE operations per point as the
 * one-point closest(), hence the same bits; the solve is latency-bound, so sixteen independent points in flight
 * overlap their divisions and square roots: 3.1 -> 2.3 ms at 10^5 points on this machine, 4 -> 16 lanes; the
 * 4-lane vectors as AVX instructions where the CPU has AVX (a load-time clone): 2.5 -> 1.7 ms).
 *
 * distances_qr() (ellipse.orthogonal's per-iteration sweep) adds the Jacobian of the distances at the same closest
 * points, folded into the R of a QR as it goes; scatter() is the direct fits' moment sweep.
 *
 * x and y may be strided 1-D float64 views (a column of an (N, 2) array). Operation order is explicit
 * (compiled without fast-math or FP contraction: same bits on any x86-64).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <string.h>

#define EPS 2.220446049250313e-16

static double norm2(double x, double y) {
    /* sqrt(x^2 + y^2); hypot only where the squares leave the float64 range (as _geometry._norm) */
    double d = sqrt(x * x + y * y);
    if (!(d >= 1e-150) || d > 1e150) d = hypot(x, y);
    return d;
}

static double newton_step(double w, double n0, double z1, double rm1) {
    double t0 = w + rm1;
    double q0 = n0 / t0, q1 = z1 / w;
    double q0s = q0 * q0, q1s = q1 * q1;
    return (q0s + q1s - 1.0) / (2.0 * (q0s / t0 + q1s / w));
}

/* Closest point on the axis-aligned ellipse (a >= b > 0) to (u, v): X, Y and the signed distance. */
static void closest(double u, double v, double a, double b, int iterations, double *X, double *Y, double *d) {
    double au = fabs(u), av = fabs(v);
    double z0 = au / a, z1 = av / b;
    double ab = a / b;
    double r0 = ab * ab;
    double n0 = r0 * z0;
    double g = z0 * z0 + z1 * z1 - 1.0;
    double x, y;
    if (z1 != 0.0) {
        double lo = z1, rm1 = r0 - 1.0, h = norm2(n0, z1), w;
        int k, done = 0;
        if (rm1 < 0.1) {
            w = h - n0 * n0 * rm1 / (h * h);
        } else {
            w = h;
        }
        if (!(w >= lo)) w = lo;
        for (k = 0; k < iterations; k++) {
            double wn = w + newton_step(w, n0, z1, rm1);
            double rel;
            if (!(wn >= lo)) wn = lo;
            rel = fabs(wn - w) / w;
            w = wn;
            if (rel <= 1e-8) {  /* quadratic convergence: one more step reaches rounding */
                wn = w + newton_step(w, n0, z1, rm1);
                w = (wn >= lo) ? wn : lo;
                done = 1;
                break;
            }
        }
        if (!done) {  /* slow Newton (points near the centre): bisection in the bracket */
            double lo_b = lo, hi_b = w;
            for (k = 0; k < 1100; k++) {
                double mid = 0.5 * (lo_b + hi_b);
                double q0 = n0 / (mid + rm1), q1 = z1 / mid;
                int stuck = (mid == lo_b) || (mid == hi_b);
                if (q0 * q0 + q1 * q1 - 1.0 > 0) lo_b = mid; else hi_b = mid;
                if (stuck) break;
            }
            w = 0.5 * (lo_b + hi_b);
        }
        x = r0 * au / (w + rm1);
        y = z1 * b / w;
    } else {  /* on the major axis: closed form */
        double num = a * au, den = a * a - b * b;
        int inside = num < den;
        /* (a / den) a au: the reference's a^2 au / den without overflow of a^2 au at large scales */
        double xa = inside ? (a / (den > 0 ? den : 1.0)) * a * au : a;
        if (xa > a) xa = a;
        x = xa;
        if (inside) {
            double t = xa / a, q = 1.0 - t * t;
            y = b * sqrt(q > 0.0 ? q : 0.0);
        } else {
            y = 0.0;
        }
    }
    x = copysign(x, u);
    y = copysign(y, v);
    *X = x;
    *Y = y;
    *d = norm2(u - x, v - y);
    if (!(g > 0)) *d = -*d;
}

/* closest() for LANES points at once: the same operations in the same order for every point (hence the same
   bits), interleaved so that the divisions of different points overlap in the CPU instead of waiting for each
   other. A point on the major axis, or one whose Newton iteration has not converged within `iterations` steps,
   is finished by closest() itself (which repeats the identical Newton steps, then bisects). The steps run on
   4-lane vectors (vector extensions: lane-wise IEEE operations): 256-bit AVX instructions in the "avx" clone
   where the CPU has AVX, pairs of SSE2 instructions elsewhere, the same bits either way. */
#define LANES 16
#define W 4
typedef double v2d __attribute__((vector_size(16)));
typedef double v4d __attribute__((vector_size(32)));
#if defined(__SSE2__)
#include <emmintrin.h>
static inline v2d vsqrt2(v2d a) { return (v2d)_mm_sqrt_pd((__m128d)a); }
#else
static inline v2d vsqrt2(v2d a) { v2d r = {sqrt(a[0]), sqrt(a[1])}; return r; }
#endif
/* norm2() of two lanes: the packed square root, each lane finished by hypot where norm2 would (the same bits) */
static inline v2d vnorm2(v2d x, v2d y) {
    v2d d = vsqrt2(x * x + y * y);
    int j;
    for (j = 0; j < 2; j++)
        if (!(d[j] >= 1e-150) || d[j] > 1e150) d[j] = hypot(x[j], y[j]);
    return d;
}
/* 4-lane loads, stores and the correctly rounded square root (two packed halves), through pointers: no vector is
   passed by value (no ABI change between the clones) */
#define LDV(v, p) memcpy(&(v), (p), sizeof(v4d))
#define STV(p, v) memcpy((p), &(v), sizeof(v4d))
static inline void vsqrt4(v4d *a) {
    v2d lo = {(*a)[0], (*a)[1]}, hi = {(*a)[2], (*a)[3]};
    lo = vsqrt2(lo);
    hi = vsqrt2(hi);
    (*a)[0] = lo[0]; (*a)[1] = lo[1]; (*a)[2] = hi[0]; (*a)[3] = hi[1];
}
static inline void vnorm4(const v4d *x, const v4d *y, v4d *d) {
    int j;
    *d = *x * *x + *y * *y;
    vsqrt4(d);
    for (j = 0; j < W; j++)
        if (!((*d)[j] >= 1e-150) || (*d)[j] > 1e150) (*d)[j] = hypot((*x)[j], (*y)[j]);
}

/* target_clones needs GCC and the loader's ifunc (glibc); elsewhere (clang, macOS, Windows, musl) only the default
   clone is built: the same bits, without AVX */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__GLIBC__) && \
    !defined(FITBENCH_NO_CLONES)
#define CLONES __attribute__((target_clones("avx", "default")))
#else
#define CLONES
#endif

CLONES static void closest_block(const double *U, const double *V, double a, double b, int iterations,
                                 double *Xo, double *Yo, double *Do) {
    /* every per-point quantity in 4-lane vectors (lanes j .. j + 3): each lane sees the IEEE operations of
       closest() in the same order, so the bits are closest()'s; only the divisions of four points share an
       instruction */
    double au[LANES], z1[LANES], n0[LANES], g[LANES], lo[LANES], w[LANES];
    int active[LANES], scalar[LANES], state[LANES], j, k, nact = 0;
    double ab = a / b;
    double r0 = ab * ab, rm1 = r0 - 1.0;
    for (j = 0; j < LANES; j += W) {
        v4d uv, vv, auv, avv, z0v, z1v, n0v, gv, hv, wv;
        int i;
        LDV(uv, U + j);
        LDV(vv, V + j);
        for (i = 0; i < W; i++) {
            auv[i] = fabs(uv[i]);
            avv[i] = fabs(vv[i]);
        }
        z0v = auv / a;
        z1v = avv / b;
        n0v = r0 * z0v;
        gv = z0v * z0v + z1v * z1v - 1.0;
        vnorm4(&n0v, &z1v, &hv);
        wv = (rm1 < 0.1) ? hv - n0v * n0v * rm1 / (hv * hv) : hv;
        for (i = 0; i < W; i++) {
            au[j + i] = auv[i];
            z1[j + i] = z1v[i];
            n0[j + i] = n0v[i];
            g[j + i] = gv[i];
            active[j + i] = 0;
            scalar[j + i] = 1;
            w[j + i] = 0.0;
            lo[j + i] = 0.0;
            if (z1v[i] == 0.0) continue;
            scalar[j + i] = 0;
            lo[j + i] = z1v[i];
            w[j + i] = (wv[i] >= z1v[i]) ? wv[i] : z1v[i];
            active[j + i] = 1;
            nact++;
        }
    }
    /* the Newton steps of all lanes in packed arithmetic (the same IEEE operations per lane as newton_step);
       a lane's state: 1 iterating, 2 converged with its one more step pending, 0 finished */
    for (j = 0; j < LANES; j++) state[j] = active[j];
    for (k = 0; nact > 0; k++) {
        double step[LANES], relv[LANES], wnv[LANES];
        int any = 0;
        for (j = 0; j < LANES; j++)
            if (state[j] == 2 || (state[j] == 1 && k < iterations)) any = 1;
        if (!any) break;
        for (j = 0; j < LANES; j += W) {
            v4d wv, n0v, z1v, lov, t0, q0, q1, q0s, q1s, st, wn, dw;
            int i;
            LDV(wv, w + j);
            LDV(n0v, n0 + j);
            LDV(z1v, z1 + j);
            LDV(lov, lo + j);
            t0 = wv + rm1;
            q0 = n0v / t0;
            q1 = z1v / wv;
            q0s = q0 * q0;
            q1s = q1 * q1;
            st = (q0s + q1s - 1.0) / (2.0 * (q0s / t0 + q1s / wv));
            wn = wv + st;
            for (i = 0; i < W; i++)
                if (!(wn[i] >= lov[i])) wn[i] = lov[i];
            dw = wn - wv;
            for (i = 0; i < W; i++) dw[i] = fabs(dw[i]);
            dw = dw / wv;  /* rel = |wn - w| / w of the iterating lanes */
            STV(step + j, st);
            STV(relv + j, dw);
            STV(wnv + j, wn);
        }
        for (j = 0; j < LANES; j++) {
            double wn;
            if (state[j] == 2) {
                wn = w[j] + step[j];
                w[j] = (wn >= lo[j]) ? wn : lo[j];
                state[j] = 0;
                active[j] = 0;
                nact--;
            } else if (state[j] == 1 && k < iterations) {
                w[j] = wnv[j];
                if (relv[j] <= 1e-8) state[j] = 2;
            }
        }
    }
    for (j = 0; j < LANES; j += W) {
        v4d auv, z1v, wv, xv, yv, uv, vv, ex, ey, dv;
        int i;
        LDV(auv, au + j);
        LDV(z1v, z1 + j);
        LDV(wv, w + j);
        LDV(uv, U + j);
        LDV(vv, V + j);
        xv = r0 * auv / (wv + rm1);
        yv = z1v * b / wv;
        for (i = 0; i < W; i++) {
            xv[i] = copysign(xv[i], uv[i]);
            yv[i] = copysign(yv[i], vv[i]);
        }
        ex = uv - xv;
        ey = vv - yv;
        vnorm4(&ex, &ey, &dv);
        for (i = 0; i < W; i++) {
            if (scalar[j + i] || active[j + i]) {
                closest(U[j + i], V[j + i], a, b, iterations, &Xo[j + i], &Yo[j + i], &Do[j + i]);
                continue;
            }
            Xo[j + i] = xv[i];
            Yo[j + i] = yv[i];
            Do[j + i] = (g[j + i] > 0) ? dv[i] : -dv[i];
        }
    }
}

/* The closest points of the points i, i + 1, ... in the ellipse's frame (u = dx c + dy s, v = -dx s + dy c): a
   block of LANES (closest_block) while LANES remain, else the one point i (closest). X, Y are in the frame of
   the axes (a, b), D the signed distances; returns how many points were solved. The one sweep of orthogonal()
   and distances_qr(). */
static int solve_points(const double *x, const double *y, Py_ssize_t i, Py_ssize_t n, Py_ssize_t sx,
                        Py_ssize_t sy, double xc, double yc, double c, double s, double a, double b, int iterations,
                        double *X, double *Y, double *D) {
    double U[LANES], V[LANES];
    int j, m = (n - i >= LANES) ? LANES : 1, swap = a < b;
    for (j = 0; j < m; j++) {
        double dx = x[(i + j) * sx] - xc, dy = y[(i + j) * sy] - yc;
        U[j] = dx * c + dy * s;
        V[j] = -dx * s + dy * c;
    }
    if (m == LANES) {
        if (swap) closest_block(V, U, b, a, iterations, Y, X, D);
        else closest_block(U, V, a, b, iterations, X, Y, D);
    } else if (swap) {
        closest(V[0], U[0], b, a, iterations, &Y[0], &X[0], &D[0]);
    } else {
        closest(U[0], V[0], a, b, iterations, &X[0], &Y[0], &D[0]);
    }
    return m;
}

static int vector_of(PyObject *obj, Py_buffer *view, int writable, const char *what) {
    int flags = PyBUF_STRIDES | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0);
    if (PyObject_GetBuffer(obj, view, flags) < 0) return -1;
    if (view->ndim != 1 || view->itemsize != 8 || !view->format || strcmp(view->format, "d") != 0 ||
        view->strides[0] % 8 != 0) {
        PyErr_Format(PyExc_TypeError, "%s must be a 1-D float64 array", what);
        PyBuffer_Release(view);
        return -1;
    }
    return 0;
}

static PyObject *orthogonal(PyObject *self, PyObject *args) {
    PyObject *xo, *yo, *do_, *po = Py_None;
    double xc, yc, c, s, a, b;
    int iterations;
    Py_buffer xv, yv, dv, pv;
    Py_ssize_t n, i, sx, sy, sd, sp = 0;
    int m = 1;
    int with_phi;
    if (!PyArg_ParseTuple(args, "OOddddddiO|O", &xo, &yo, &xc, &yc, &c, &s, &a, &b, &iterations, &do_, &po))
        return NULL;
    if (!(a > 0.0) || !(b > 0.0) || iterations < 0) {
        PyErr_SetString(PyExc_ValueError, "orthogonal: the semi-axes must be positive and iterations >= 0");
        return NULL;
    }
    with_phi = po != Py_None;
    if (vector_of(xo, &xv, 0, "x") < 0) return NULL;
    if (vector_of(yo, &yv, 0, "y") < 0) { PyBuffer_Release(&xv); return NULL; }
    if (vector_of(do_, &dv, 1, "d_out") < 0) { PyBuffer_Release(&xv); PyBuffer_Release(&yv); return NULL; }
    if (with_phi && vector_of(po, &pv, 1, "phi_out") < 0) {
        PyBuffer_Release(&xv); PyBuffer_Release(&yv); PyBuffer_Release(&dv); return NULL;
    }
    n = xv.shape[0];
    if (yv.shape[0] != n || dv.shape[0] != n || (with_phi && pv.shape[0] != n)) {
        PyErr_SetString(PyExc_ValueError, "orthogonal: x, y and the outputs must have the same length");
        PyBuffer_Release(&xv); PyBuffer_Release(&yv); PyBuffer_Release(&dv);
        if (with_phi) PyBuffer_Release(&pv);
        return NULL;
    }
    sx = xv.strides[0] / 8; sy = yv.strides[0] / 8; sd = dv.strides[0] / 8;
    if (with_phi) sp = pv.strides[0] / 8;
    {
        const double *x = (const double *)xv.buf, *y = (const double *)yv.buf;
        double *d = (double *)dv.buf, *ph = with_phi ? (double *)pv.buf : NULL;
        Py_BEGIN_ALLOW_THREADS
        for (i = 0; i < n; i += m) {
            double X[LANES], Y[LANES], D[LANES];
            int j;
            m = solve_points(x, y, i, n, sx, sy, xc, yc, c, s, a, b, iterations, X, Y, D);
            for (j = 0; j < m; j++) {
                d[(i + j) * sd] = D[j];
                if (ph) ph[(i + j) * sp] = atan2(Y[j] / b, X[j] / a);
            }
        }
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&xv); PyBuffer_Release(&yv); PyBuffer_Release(&dv);
    if (with_phi) PyBuffer_Release(&pv);
    Py_RETURN_NONE;
}

/* ---- one Levenberg-Marquardt evaluation of ellipse.orthogonal: the distances and the R of [J d] in one sweep --
 *
 *   distances_qr(x, y, xc, yc, c, s, a, b, iterations, d_out, R_out) -> sum d_i^2
 *
 * d_out[i] as orthogonal() (the same closest points, the same bits). Row i of the N x 6 matrix [J d] holds the
 * derivative of d_i with respect to p = (xc, yc, a, b, theta) at the closest point (X, Y) held fixed (envelope
 * theorem; methods/ellipse/orthogonal.py::distance_jacobian): with (cos phi, sin phi) = (X/a, Y/b) normalised (no
 * atan2, cos, sin: the same angle, to rounding), the outward unit normal (nx', ny') ~ (cos phi / a, sin phi / b) in
 * the ellipse frame and n = R(theta) (nx', ny'),
 *     J = -(n_x, n_y, nx' cos phi, ny' sin phi, ny' a cos phi - nx' b sin phi)
 * (-n . dX/dp with dX/da = R [cos phi, 0], dX/db = R [0, sin phi], dX/dtheta = R [-b sin phi, a cos phi]),
 * then d_i. That matrix is never stored: each block of rows is folded into the 6 x 6 upper-triangular R of its
 * Householder QR (Golub & Van Loan, 4th ed., sec. 5.2.2 and 5.1.3, dlarfg's reflector), the triangles of QBLOCK
 * points merged pairwise as a binary counter (TSQR; the rounding grows with log2(N / QBLOCK), as the blocked
 * pairwise sums do), so an evaluation costs 6 x 6 doubles instead of the N x 5 Jacobian and its copies. R_out
 * (C-contiguous (6, 6) float64) gets R: R^T R = [J d]^T [J d], so everything a Levenberg-Marquardt step needs
 * (J^T J = R1^T R1, J^T d = R1^T q with R = [[R1, q], [0, rho]]) is in it. The return value is sum d_i^2 by
 * blocked pairwise sums. Plain IEEE operations in source order: the same bits on every x86-64 CPU. */

static void jacobian_row(double X, double Y, double a, double b, double ia, double ib, double c, double s,
                         double *J, Py_ssize_t st) {
    /* (ex, ey) = (X/a, Y/b) ~ (cos phi, sin phi) and the normal direction (X/a^2, Y/b^2), normalised by their
       lengths r and m through ONE division 1 / (r m) (independent chains: shorter latency than normalising in turn) */
    double ex = X * ia, ey = Y * ib, nx = ex * ia, ny = ey * ib, r = norm2(ex, ey), m = norm2(nx, ny), inv, cp, sp,
           nxl, nyl;
    if (!(r > 0.0)) r = 1.0;
    if (!(m > 0.0)) m = 1.0;
    inv = 1.0 / (r * m);
    cp = ex * (m * inv);
    sp = ey * (m * inv);
    nxl = nx * (r * inv);
    nyl = ny * (r * inv);
    J[0] = -(c * nxl - s * nyl);
    J[st] = -(s * nxl + c * nyl);
    J[2 * st] = -(nxl * cp);
    J[3 * st] = -(nyl * sp);
    J[4 * st] = -(nyl * (a * cp) - nxl * (b * sp));
}

/* jacobian_row() of LANES points in 4-lane vectors (each lane sees jacobian_row's IEEE operations in its order:
   the same bits; AVX where the CPU has it, as closest_block), written to column-major rows of B (stride st). */
CLONES static void jacobian_rows(const double *X, const double *Y, double a, double b, double ia, double ib,
                                 double c, double s, double *J, Py_ssize_t st) {
    int j, i;
    for (j = 0; j < LANES; j += W) {
        v4d Xv, Yv, ex, ey, nx, ny, r, m, inv, cp, sp, nxl, nyl, o;
        LDV(Xv, X + j);
        LDV(Yv, Y + j);
        ex = Xv * ia;
        ey = Yv * ib;
        nx = ex * ia;
        ny = ey * ib;
        vnorm4(&ex, &ey, &r);
        vnorm4(&nx, &ny, &m);
        for (i = 0; i < W; i++) {
            if (!(r[i] > 0.0)) r[i] = 1.0;
            if (!(m[i] > 0.0)) m[i] = 1.0;
        }
        inv = 1.0 / (r * m);
        cp = ex * (m * inv);
        sp = ey * (m * inv);
        nxl = nx * (r * inv);
        nyl = ny * (r * inv);
        o = -(c * nxl - s * nyl);
        STV(J + j, o);
        o = -(s * nxl + c * nyl);
        STV(J + st + j, o);
        o = -(nxl * cp);
        STV(J + 2 * st + j, o);
        o = -(nyl * sp);
        STV(J + 3 * st + j, o);
        o = -(nyl * (a * cp) - nxl * (b * sp));
        STV(J + 4 * st + j, o);
    }
}

#define QC 6          /* columns of [J d] */
#define QBLOCK 64     /* points per leaf triangle */
#define QMAXLEV 64

/* T <- the R of the Householder QR of [T; B] (T: QC x QC upper triangular, B: m x QC, overwritten). For each column
   k, dlarfg's reflector H = I - tau v v^T with v = (1, B[:, k] / (alpha - beta)) maps (alpha, B[:, k]) = (T[k][k],
   B[:, k]) to (beta, 0), beta = -sign(alpha) |(alpha, B[:, k])|, and is applied to the columns right of k. */
static void tri_update(double T[QC][QC], double (*B)[QC], int m) {
    int k, i, j;
    double sigma = 0.0;
    for (i = 0; i < m; i++) sigma = sigma + B[i][0] * B[i][0];
    for (k = 0; k < QC; k++) {
        double alpha = T[k][k], nrm, beta, tau, scal, w[QC], next = 0.0;
        if (sigma != 0.0) {                    /* else the column is already reduced: H = I */
            nrm = sqrt(alpha * alpha + sigma);
            beta = alpha > 0.0 ? -nrm : nrm;
            tau = (beta - alpha) / beta;
            scal = 1.0 / (alpha - beta);
            T[k][k] = beta;
            /* w = T[k][k+1:] + v^T B[:, k+1:]: one pass over the rows, the columns' sums independent */
            for (j = k + 1; j < QC; j++) w[j] = T[k][j];
            for (i = 0; i < m; i++) {
                double v = B[i][k] * scal;
                B[i][k] = v;
                for (j = k + 1; j < QC; j++) w[j] = w[j] + v * B[i][j];
            }
            for (j = k + 1; j < QC; j++) {
                w[j] = tau * w[j];
                T[k][j] = T[k][j] - w[j];
            }
            /* the update, and the next column's sum of squares in the same pass */
            for (i = 0; i < m; i++) {
                double v = B[i][k];
                for (j = k + 1; j < QC; j++) B[i][j] = B[i][j] - w[j] * v;
                if (k + 1 < QC) next = next + B[i][k + 1] * B[i][k + 1];
            }
        } else if (k + 1 < QC) {
            for (i = 0; i < m; i++) next = next + B[i][k + 1] * B[i][k + 1];
        }
        sigma = next;
    }
}

/* sum_i u_i v_i over a block's rows: eight partial sums (rows i mod 8, two 4-lane accumulators), added as
   ((s0 + s4) + (s1 + s5)) + ((s2 + s6) + (s3 + s7)). */
static inline double col_dot(const double *u, const double *v) {
    v4d s0 = {0.0, 0.0, 0.0, 0.0}, s1 = {0.0, 0.0, 0.0, 0.0}, a0, b0, a1, b1, t;
    int i;
    for (i = 0; i < QBLOCK; i += 8) {
        LDV(a0, u + i); LDV(b0, v + i); LDV(a1, u + i + 4); LDV(b1, v + i + 4);
        s0 = s0 + a0 * b0;
        s1 = s1 + a1 * b1;
    }
    t = s0 + s1;
    return (t[0] + t[1]) + (t[2] + t[3]);
}

/* A leaf: the R of the Householder QR of a QBLOCK x QC block B, stored column-major (B[j] is column j; rows past the
   block's points are zero, which adds exact zeros), into T (zeroed by the caller). The operations of tri_update for
   T = 0, every sum over the rows taken by col_dot in a fixed order: the same bits on every CPU. */
/* (The 4-lane vectors are lane-wise IEEE operations: 256-bit AVX instructions where the CPU has them (the "avx"
   clone, picked at load time), pairs of SSE2 instructions elsewhere, the same bits either way; compiled with
   -DFITBENCH_NO_CLONES there is only the SSE2 one, which tests/test_ellipse_kernels.py compares bit for bit.) */
CLONES static void leaf_qr(double T[QC][QC], double B[QC][QBLOCK]) {
    int k, i, j;
    for (k = 0; k < QC; k++) {
        double alpha = T[k][k], sigma = col_dot(B[k], B[k]), nrm, beta, tau, scal, w;
        v4d vs, vw;
        if (sigma == 0.0) continue;            /* the column is already reduced: H = I */
        nrm = sqrt(alpha * alpha + sigma);
        beta = alpha > 0.0 ? -nrm : nrm;
        tau = (beta - alpha) / beta;
        scal = 1.0 / (alpha - beta);
        T[k][k] = beta;
        vs = (v4d){scal, scal, scal, scal};
        for (i = 0; i < QBLOCK; i += 4) {
            v4d bk;
            LDV(bk, B[k] + i);
            bk = bk * vs;
            STV(B[k] + i, bk);
        }
        for (j = k + 1; j < QC; j++) {
            w = tau * (T[k][j] + col_dot(B[k], B[j]));
            T[k][j] = T[k][j] - w;
            vw = (v4d){w, w, w, w};
            for (i = 0; i < QBLOCK; i += 4) {
                v4d bj, bk;
                LDV(bj, B[j] + i);
                LDV(bk, B[k] + i);
                bj = bj - vw * bk;
                STV(B[j] + i, bj);
            }
        }
    }
}

typedef struct {
    unsigned char used[QMAXLEV];
    double R[QMAXLEV][QC][QC];
    double s[QMAXLEV];
} qtree_t;

/* Push a leaf (triangle T, sum of squares s) into the binary counter: equal levels merge, as spw_add's sums do. */
static void qtree_add(qtree_t *q, double T[QC][QC], double s) {
    int lev;
    for (lev = 0; lev < QMAXLEV; lev++) {
        if (!q->used[lev]) {
            memcpy(q->R[lev], T, sizeof(double) * QC * QC);
            q->s[lev] = s;
            q->used[lev] = 1;
            return;
        }
        tri_update(T, q->R[lev], QC);
        s = q->s[lev] + s;
        q->used[lev] = 0;
    }
}

static PyObject *distances_qr(PyObject *self, PyObject *args) {
    PyObject *xo, *yo, *do_, *ro;
    double xc, yc, c, s, a, b, total = 0.0;
    int iterations;
    Py_buffer xv, yv, dv, rv;
    Py_ssize_t n, sx, sy, sd;
    qtree_t *tree;
    if (!PyArg_ParseTuple(args, "OOddddddiOO", &xo, &yo, &xc, &yc, &c, &s, &a, &b, &iterations, &do_, &ro))
        return NULL;
    if (!(a > 0.0) || !(b > 0.0) || iterations < 0) {
        PyErr_SetString(PyExc_ValueError, "distances_qr: the semi-axes must be positive and iterations >= 0");
        return NULL;
    }
    if (vector_of(xo, &xv, 0, "x") < 0) return NULL;
    if (vector_of(yo, &yv, 0, "y") < 0) { PyBuffer_Release(&xv); return NULL; }
    if (vector_of(do_, &dv, 1, "d_out") < 0) { PyBuffer_Release(&xv); PyBuffer_Release(&yv); return NULL; }
    if (PyObject_GetBuffer(ro, &rv, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | PyBUF_WRITABLE) < 0) {
        PyBuffer_Release(&xv); PyBuffer_Release(&yv); PyBuffer_Release(&dv); return NULL;
    }
    n = xv.shape[0];
    if (rv.ndim != 2 || rv.itemsize != 8 || !rv.format || strcmp(rv.format, "d") != 0 || rv.shape[0] != QC ||
        rv.shape[1] != QC || yv.shape[0] != n || dv.shape[0] != n) {
        PyErr_SetString(PyExc_ValueError, "distances_qr: x, y, d_out of length N and R_out a C-contiguous (6, 6) "
                                          "float64 array are needed");
        PyBuffer_Release(&xv); PyBuffer_Release(&yv); PyBuffer_Release(&dv); PyBuffer_Release(&rv);
        return NULL;
    }
    tree = (qtree_t *)PyMem_RawCalloc(1, sizeof(qtree_t));
    if (!tree) {
        PyBuffer_Release(&xv); PyBuffer_Release(&yv); PyBuffer_Release(&dv); PyBuffer_Release(&rv);
        return PyErr_NoMemory();
    }
    sx = xv.strides[0] / 8; sy = yv.strides[0] / 8; sd = dv.strides[0] / 8;
    {
        const double *x = (const double *)xv.buf, *y = (const double *)yv.buf;
        double *d = (double *)dv.buf, *Rout = (double *)rv.buf;
        double ia = 1.0 / a, ib = 1.0 / b;
        Py_ssize_t i0, i;
        int lev, first = 1;
        Py_BEGIN_ALLOW_THREADS
        for (i0 = 0; i0 < n; i0 += QBLOCK) {
            Py_ssize_t i1 = i0 + QBLOCK < n ? i0 + QBLOCK : n;
            double T[QC][QC], B[QC][QBLOCK] __attribute__((aligned(16))), leaf = 0.0;
            int m = 1;
            for (i = i0; i < i1; i += m) {
                double X[LANES], Y[LANES], D[LANES];
                int j;
                m = solve_points(x, y, i, i1, sx, sy, xc, yc, c, s, a, b, iterations, X, Y, D);
                if (m == LANES) jacobian_rows(X, Y, a, b, ia, ib, c, s, &B[0][i - i0], QBLOCK);
                else jacobian_row(X[0], Y[0], a, b, ia, ib, c, s, &B[0][i - i0], QBLOCK);
                for (j = 0; j < m; j++) {
                    Py_ssize_t r = i - i0 + j;
                    d[(i + j) * sd] = D[j];
                    B[QC - 1][r] = D[j];
                    leaf = leaf + D[j] * D[j];
                }
            }
            for (i = i1 - i0; i < QBLOCK; i++)
                for (m = 0; m < QC; m++) B[m][i] = 0.0;
            memset(T, 0, sizeof T);
            leaf_qr(T, B);
            qtree_add(tree, T, leaf);
        }
        memset(Rout, 0, sizeof(double) * QC * QC);
        for (lev = 0; lev < QMAXLEV; lev++) {
            if (!tree->used[lev]) continue;
            if (first) {
                memcpy(Rout, tree->R[lev], sizeof(double) * QC * QC);
                total = tree->s[lev];
                first = 0;
            } else {
                tri_update((double (*)[QC])Rout, tree->R[lev], QC);
                total = total + tree->s[lev];
            }
        }
        Py_END_ALLOW_THREADS
    }
    PyMem_RawFree(tree);
    PyBuffer_Release(&xv); PyBuffer_Release(&yv); PyBuffer_Release(&dv); PyBuffer_Release(&rv);
    return PyFloat_FromDouble(total);
}

/* ---- the 6 x 6 scatter of the direct fits: the 14 moments sum x^p y^q (1 <= p + q <= 4) in one sweep ---- */
/* Blocked pairwise summation (as the circle kernel's moments): each block of SBLOCK points is summed in order,
   the block sums are added pairwise (a binary counter), so the rounding grows like (SBLOCK + log2(N/SBLOCK)) eps. */
#define SBLOCK 256
#define SMAXLEV 64
#define SNSUM 14
typedef struct {
    unsigned char used[SMAXLEV];
    double acc[SMAXLEV][SNSUM];
} spairwise_t;

static void spw_add(spairwise_t *p, const double *v) {
    double carry[SNSUM];
    int j, lev;
    memcpy(carry, v, sizeof carry);
    for (lev = 0; lev < SMAXLEV; lev++) {
        if (!p->used[lev]) {
            memcpy(p->acc[lev], carry, sizeof carry);
            p->used[lev] = 1;
            return;
        }
        for (j = 0; j < SNSUM; j++) carry[j] = p->acc[lev][j] + carry[j];
        p->used[lev] = 0;
    }
}

static PyObject *scatter(PyObject *self, PyObject *args) {
    PyObject *xo, *yo;
    Py_buffer xv, yv;
    Py_ssize_t n, sx, sy, i0, i;
    double out[SNSUM];
    spairwise_t pw;
    int lev, j, first = 1;
    if (!PyArg_ParseTuple(args, "OO", &xo, &yo)) return NULL;
    if (vector_of(xo, &xv, 0, "x") < 0) return NULL;
    if (vector_of(yo, &yv, 0, "y") < 0) { PyBuffer_Release(&xv); return NULL; }
    n = xv.shape[0];
    if (yv.shape[0] != n) {
        PyErr_SetString(PyExc_ValueError, "scatter: x and y must have the same length");
        PyBuffer_Release(&xv); PyBuffer_Release(&yv);
        return NULL;
    }
    sx = xv.strides[0] / 8; sy = yv.strides[0] / 8;
    memset(pw.used, 0, sizeof pw.used);
    Py_BEGIN_ALLOW_THREADS
    {
        const double *x = (const double *)xv.buf, *y = (const double *)yv.buf;
        for (i0 = 0; i0 < n; i0 += SBLOCK) {
            Py_ssize_t i1 = i0 + SBLOCK < n ? i0 + SBLOCK : n;
            double b[SNSUM] = {0.0};
            for (i = i0; i < i1; i++) {
                double u = x[i * sx], v = y[i * sy];
                double uu = u * u, uv = u * v, vv = v * v;
                b[0] = b[0] + uu * uu;   /* m40 */
                b[1] = b[1] + uu * uv;   /* m31 */
                b[2] = b[2] + uu * vv;   /* m22 */
                b[3] = b[3] + uv * vv;   /* m13 */
                b[4] = b[4] + vv * vv;   /* m04 */
                b[5] = b[5] + uu * u;    /* m30 */
                b[6] = b[6] + uu * v;    /* m21 */
                b[7] = b[7] + vv * u;    /* m12 */
                b[8] = b[8] + vv * v;    /* m03 */
                b[9] = b[9] + uu;        /* m20 */
                b[10] = b[10] + uv;      /* m11 */
                b[11] = b[11] + vv;      /* m02 */
                b[12] = b[12] + u;       /* m10 */
                b[13] = b[13] + v;       /* m01 */
            }
            spw_add(&pw, b);
        }
        for (j = 0; j < SNSUM; j++) out[j] = 0.0;
        for (lev = 0; lev < SMAXLEV; lev++) {
            if (!pw.used[lev]) continue;
            for (j = 0; j < SNSUM; j++) out[j] = first ? pw.acc[lev][j] : out[j] + pw.acc[lev][j];
            first = 0;
        }
    }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&xv); PyBuffer_Release(&yv);
    return Py_BuildValue("(dddddddddddddd)", out[0], out[1], out[2], out[3], out[4], out[5], out[6], out[7], out[8],
                         out[9], out[10], out[11], out[12], out[13]);
}

static PyMethodDef Methods[] = {
    {"scatter", scatter, METH_VARARGS,
     "scatter(x, y) -> (m40, m31, m22, m13, m04, m30, m21, m12, m03, m20, m11, m02, m10, m01): the moments "
     "sum x^p y^q of the direct fits' scatter matrix, one sweep, blocked pairwise sums"},
    {"distances_qr", distances_qr, METH_VARARGS,
     "distances_qr(x, y, xc, yc, cos_theta, sin_theta, a, b, iterations, d_out, R_out) -> sum d^2: the signed "
     "orthogonal distances (as orthogonal()) in place, and in R_out (6, 6) the R of the QR of [J d], J the "
     "distances' Jacobian in (xc, yc, a, b, theta): one sweep, the Jacobian never stored"},
    {"orthogonal", orthogonal, METH_VARARGS,
     "orthogonal(x, y, xc, yc, cos_theta, sin_theta, a, b, iterations, d_out[, phi_out]): signed orthogonal "
     "distances (and closest-point parameters) of the points to the ellipse, written in place"},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_ckernels",
                                    "Compiled kernel of the ellipse fits; see the C source header.",
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
