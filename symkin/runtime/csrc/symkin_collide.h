/* symkin_collide.h - exact signed distances between collision primitives (C99, header only).
 *
 * The C twin of symkin/geometry/distance.py: the same algorithms, constants and order of
 * floating-point operations, one pair at a time in double precision. Compiled without contraction
 * (-ffp-contract=off, no -ffast-math) the results agree with the NumPy module to rounding (in
 * practice bit for bit).
 *
 * Shapes: sphere (centre c, radius r); capsule (segment a-b, radius r: every point within r of the
 * segment); box (centre `center`, half extents h[3], rotation R[9] row-major whose COLUMNS are the
 * box axes in world coordinates: world = center + R * local).
 *
 * Every pair function skc_<A>_<B> returns the signed distance d (negative: penetration depth) and
 * writes (none of the pointers may be NULL):
 *   n[3]  the unit normal from B toward A: moving A by a small e changes d by n.e;
 *   pa[3] the point of A's core where the minimum is attained (sphere centre, closest segment point);
 *   pb[3] likewise on B (sphere centre, closest segment point; box: the point of its surface
 *         nearest to pa, pb = pa - sdf(pa) * n, i.e. the nearest face point when pa is inside).
 * So d = n.(pa - pb) - rA - rB (rB = 0 for a box) and, with pa, pb fixed to their bodies,
 * d' = n.(pa' - pb').
 *
 * Degenerate cases: a segment of squared length <= SKC_SEG_EPS is a point (parameter 0); parallel
 * segments take s = 0 then Ericson's clamping rules; core points closer than SKC_DIST_EPS get
 * n = (0, 0, 1); a point equally close to several box faces takes the lowest axis index.
 * Caveat: when a capsule's deepest point in a box lies where two faces are equally deep (a kink of
 * the SDF along the segment, usual for a capsule crossing the box's interior), d's gradient is a
 * convex combination of the two face normals (not unit; zero for two opposite faces, as for a
 * capsule piercing a thin box); n is then one of the two face normals.
 *
 * Algorithms: segment-segment after Ericson, Real-Time Collision Detection (2005), 5.1.9; the box's
 * exact SDF in box coordinates (q = |x| - h, sdf = |max(q, 0)| + min(max_j q_j, 0)); capsule-box
 * minimises the (convex) box SDF along the segment by golden-section search with SKC_GOLDEN_ITERS
 * steps (on a tie f(c) == f(d) both ends move in, so a flat stretch of minima ends inside, not at
 * a kink on its edge), then compares the endpoints t = 0 and t = 1.
 *
 * Only <math.h> (sqrt, fabs); link with -lm.
 */
#ifndef SYMKIN_COLLIDE_H
#define SYMKIN_COLLIDE_H

#include <math.h>

#define SKC_SEG_EPS 1e-24  /* squared segment length at or below which a segment is a point */
#define SKC_PAR_EPS 1e-14  /* parallel when |d1|^2|d2|^2 - (d1.d2)^2 <= SKC_PAR_EPS |d1|^2|d2|^2 */
#define SKC_DIST_EPS 1e-15 /* core points closer than this: n = (0, 0, 1) */
#define SKC_GOLDEN_ITERS 80
#define SKC_INV_PHI 0.6180339887498948482 /* (sqrt(5) - 1) / 2 */

static inline double skc_dot3(const double u[3], const double v[3])
{
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

static inline double skc_clamp01(double x)
{
    return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
}

/* |diff|, and n = diff / |diff| (or (0, 0, 1) when |diff| <= SKC_DIST_EPS) */
static inline double skc_normal(const double diff[3], double n[3])
{
    double len = sqrt(skc_dot3(diff, diff));
    if (len > SKC_DIST_EPS) {
        n[0] = diff[0] / len;
        n[1] = diff[1] / len;
        n[2] = diff[2] / len;
    } else {
        n[0] = 0.0;
        n[1] = 0.0;
        n[2] = 1.0;
    }
    return len;
}

/* Quick test whether two spheres overlap, |c1 - c2| < r1 + r2 (squared, no sqrt; touching is not
 * overlapping, as d < 0 is a collision): 1 or 0. Agrees with skc_sphere_sphere(...) < 0 except
 * within rounding of touching. */
static inline int skc_spheres_overlap(const double c1[3], double r1, const double c2[3], double r2)
{
    double dx = c1[0] - c2[0], dy = c1[1] - c2[1], dz = c1[2] - c2[2];
    double rr = r1 + r2;
    return dx * dx + dy * dy + dz * dz < rr * rr;
}

/* Parameter t in [0, 1] of the point a + t (b - a) closest to p (0 for a zero-length segment). */
static inline double skc_point_segment(const double p[3], const double a[3], const double b[3])
{
    double ab[3], ap[3];
    for (int i = 0; i < 3; ++i) {
        ab[i] = b[i] - a[i];
        ap[i] = p[i] - a[i];
    }
    double l2 = skc_dot3(ab, ab);
    if (!(l2 > SKC_SEG_EPS))
        return 0.0;
    return skc_clamp01(skc_dot3(ap, ab) / l2);
}

/* Parameters s, t in [0, 1] of the closest points a1 + s (b1 - a1), a2 + t (b2 - a2) (Ericson 5.1.9). */
static inline void skc_segment_closest(const double a1[3], const double b1[3], const double a2[3],
                                       const double b2[3], double *s_out, double *t_out)
{
    double d1[3], d2[3], r[3];
    for (int i = 0; i < 3; ++i) {
        d1[i] = b1[i] - a1[i];
        d2[i] = b2[i] - a2[i];
        r[i] = a1[i] - a2[i];
    }
    double a = skc_dot3(d1, d1), e = skc_dot3(d2, d2), f = skc_dot3(d2, r);
    double s = 0.0, t = 0.0;
    if (!(a > SKC_SEG_EPS)) {
        if (e > SKC_SEG_EPS)
            t = skc_clamp01(f / e); /* segment 1 is a point */
    } else {
        double c = skc_dot3(d1, r);
        if (!(e > SKC_SEG_EPS)) {
            s = skc_clamp01(-c / a); /* segment 2 is a point */
        } else {
            double b = skc_dot3(d1, d2);
            double denom = a * e - b * b;
            s = denom > SKC_PAR_EPS * a * e ? skc_clamp01((b * f - c * e) / denom) : 0.0;
            t = (b * s + f) / e;
            if (t < 0.0) {
                t = 0.0;
                s = skc_clamp01(-c / a);
            } else if (t > 1.0) {
                t = 1.0;
                s = skc_clamp01((b - c) / a);
            }
        }
    }
    *s_out = s;
    *t_out = t;
}

/* Exact signed distance of the point p to the box; n[3]: its unit gradient in world coordinates
 * (outside: (p - closest) / |p - closest|; on or inside the surface, or within SKC_DIST_EPS of it:
 * the nearest face's outward normal, the lowest axis index on ties). */
static inline double skc_box_sdf(const double p[3], const double center[3], const double h[3],
                                 const double R[9], double n[3])
{
    double v[3], x[3], q[3], m[3], nl[3];
    for (int i = 0; i < 3; ++i)
        v[i] = p[i] - center[i];
    for (int j = 0; j < 3; ++j) {
        x[j] = R[j] * v[0] + R[3 + j] * v[1] + R[6 + j] * v[2];
        q[j] = fabs(x[j]) - h[j];
        m[j] = q[j] > 0.0 ? q[j] : 0.0;
    }
    double ext = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    double qmax = q[0] > q[1] ? q[0] : q[1];
    qmax = qmax > q[2] ? qmax : q[2];
    double d = ext + (qmax < 0.0 ? qmax : 0.0);
    if (ext > SKC_DIST_EPS) {
        for (int j = 0; j < 3; ++j)
            nl[j] = (x[j] >= 0.0 ? m[j] : -m[j]) / ext;
    } else {
        int k = 0;
        if (q[1] > q[k])
            k = 1;
        if (q[2] > q[k])
            k = 2;
        nl[0] = nl[1] = nl[2] = 0.0;
        nl[k] = x[k] >= 0.0 ? 1.0 : -1.0;
    }
    for (int i = 0; i < 3; ++i)
        n[i] = R[3 * i] * nl[0] + R[3 * i + 1] * nl[1] + R[3 * i + 2] * nl[2];
    return d;
}

static inline double skc_sphere_sphere(const double c1[3], double r1, const double c2[3], double r2,
                                       double n[3], double pa[3], double pb[3])
{
    double diff[3];
    for (int i = 0; i < 3; ++i) {
        pa[i] = c1[i];
        pb[i] = c2[i];
        diff[i] = c1[i] - c2[i];
    }
    return skc_normal(diff, n) - r1 - r2;
}

static inline double skc_capsule_sphere(const double a1[3], const double b1[3], double r1, const double c2[3],
                                        double r2, double n[3], double pa[3], double pb[3])
{
    double t = skc_point_segment(c2, a1, b1), diff[3];
    for (int i = 0; i < 3; ++i) {
        pa[i] = a1[i] + t * (b1[i] - a1[i]);
        pb[i] = c2[i];
        diff[i] = pa[i] - pb[i];
    }
    return skc_normal(diff, n) - r1 - r2;
}

static inline double skc_capsule_capsule(const double a1[3], const double b1[3], double r1, const double a2[3],
                                         const double b2[3], double r2, double n[3], double pa[3], double pb[3])
{
    double s, t, diff[3];
    skc_segment_closest(a1, b1, a2, b2, &s, &t);
    for (int i = 0; i < 3; ++i) {
        pa[i] = a1[i] + s * (b1[i] - a1[i]);
        pb[i] = a2[i] + t * (b2[i] - a2[i]);
        diff[i] = pa[i] - pb[i];
    }
    return skc_normal(diff, n) - r1 - r2;
}

static inline double skc_sphere_box(const double c[3], double r, const double center[3], const double h[3],
                                    const double R[9], double n[3], double pa[3], double pb[3])
{
    double sdf = skc_box_sdf(c, center, h, R, n);
    for (int i = 0; i < 3; ++i) {
        pa[i] = c[i];
        pb[i] = c[i] - sdf * n[i];
    }
    return sdf - r;
}

/* the box SDF at a + t ab */
static inline double skc_box_sdf_at(const double a[3], const double ab[3], double t, const double center[3],
                                    const double h[3], const double R[9], double n[3])
{
    double p[3];
    for (int i = 0; i < 3; ++i)
        p[i] = a[i] + t * ab[i];
    return skc_box_sdf(p, center, h, R, n);
}

static inline double skc_capsule_box(const double a[3], const double b[3], double r, const double center[3],
                                     const double h[3], const double R[9], double n[3], double pa[3],
                                     double pb[3])
{
    double ab[3];
    for (int i = 0; i < 3; ++i)
        ab[i] = b[i] - a[i];
    /* golden-section search of the convex sdf(a + t ab) over t in [0, 1], fixed iteration count */
    double lo = 0.0, hi = 1.0;
    double c = hi - SKC_INV_PHI * (hi - lo), d = lo + SKC_INV_PHI * (hi - lo);
    double fc = skc_box_sdf_at(a, ab, c, center, h, R, n);
    double fd = skc_box_sdf_at(a, ab, d, center, h, R, n);
    for (int it = 0; it < SKC_GOLDEN_ITERS; ++it) {
        if (fc < fd) { /* a minimiser in [lo, d] */
            hi = d;
            d = c;
            fd = fc;
            c = hi - SKC_INV_PHI * (hi - lo);
            fc = skc_box_sdf_at(a, ab, c, center, h, R, n);
        } else if (fd < fc) { /* a minimiser in [c, hi] */
            lo = c;
            c = d;
            fc = fd;
            d = lo + SKC_INV_PHI * (hi - lo);
            fd = skc_box_sdf_at(a, ab, d, center, h, R, n);
        } else { /* tie: a minimiser in [c, d] (convexity); stay inside a flat stretch of minima */
            lo = c;
            hi = d;
            c = hi - SKC_INV_PHI * (hi - lo);
            d = lo + SKC_INV_PHI * (hi - lo);
            fc = skc_box_sdf_at(a, ab, c, center, h, R, n);
            fd = skc_box_sdf_at(a, ab, d, center, h, R, n);
        }
    }
    double t = 0.5 * (lo + hi);
    double ft = skc_box_sdf_at(a, ab, t, center, h, R, n);
    double f0 = skc_box_sdf_at(a, ab, 0.0, center, h, R, n);
    if (f0 < ft) {
        t = 0.0;
        ft = f0;
    }
    double f1 = skc_box_sdf_at(a, ab, 1.0, center, h, R, n);
    if (f1 < ft)
        t = 1.0;
    for (int i = 0; i < 3; ++i)
        pa[i] = a[i] + t * ab[i];
    double sdf = skc_box_sdf(pa, center, h, R, n);
    for (int i = 0; i < 3; ++i)
        pb[i] = pa[i] - sdf * n[i];
    return sdf - r;
}

#endif /* SYMKIN_COLLIDE_H */
