/* The exact reference of `lanes accuracy` (see accuracy_reference.h). */
#include "bench/accuracy_reference.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>

/* ---- expansion arithmetic ---------------------------------------------
 * A value is a sum of doubles of increasing magnitude whose bits do not
 * overlap, so its sign is the sign of its last (largest) component. Sums and
 * products of float inputs are represented without any rounding. The
 * capacity is far above what three-fold products of floats need (their
 * exact values span a few hundred bits, a handful of components). */
#define XP_MAX 96

typedef struct {
    int n;
    bool overflow;
    double v[XP_MAX];
} xp;

static atomic_uint_least64_t exact_fallbacks;

uint64_t acc_ref_exact_fallbacks(void)
{
    return (uint64_t)atomic_load_explicit(&exact_fallbacks, memory_order_relaxed);
}

static inline void two_sum(double a, double b, double *x, double *y)
{
    double s = a + b, bv = s - a, av = s - bv;
    *x = s;
    *y = (a - av) + (b - bv);
}

/* e += b exactly (Shewchuk's GROW-EXPANSION, zero components dropped). */
static void xp_grow(xp *e, double b)
{
    double q = b;
    int k = 0;
    for (int i = 0; i < e->n; i++) {
        double h;
        two_sum(q, e->v[i], &q, &h);
        if (h != 0.0) e->v[k++] = h;
    }
    if (q != 0.0) {
        if (k == XP_MAX) {
            e->overflow = true;
            return;
        }
        e->v[k++] = q;
    }
    e->n = k;
}

static void xp_add(xp *e, const xp *f, double sign)
{
    for (int i = 0; i < f->n; i++) xp_grow(e, sign * f->v[i]);
    e->overflow |= f->overflow;
}

/* out = e * f exactly: every pair's product split by fma into its rounded
 * value and its exact error. */
static void xp_mul(const xp *e, const xp *f, xp *out)
{
    out->n = 0;
    out->overflow = e->overflow || f->overflow;
    for (int i = 0; i < e->n; i++)
        for (int j = 0; j < f->n; j++) {
            double p = e->v[i] * f->v[j];
            xp_grow(out, fma(e->v[i], f->v[j], -p));
            xp_grow(out, p);
        }
}

static int xp_sign(const xp *e)
{
    if (e->n == 0) return 0;
    return e->v[e->n - 1] > 0.0 ? 1 : -1;
}

static xp xp_diff(float a, float b)
{
    xp e = {0};
    xp_grow(&e, (double)a);
    xp_grow(&e, -(double)b);
    return e;
}

static xp xp_of(double a)
{
    xp e = {0};
    xp_grow(&e, a);
    return e;
}

/* e x f, componentwise exact. */
static void xp_cross(const xp e[3], const xp f[3], xp out[3])
{
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3, k = (i + 2) % 3;
        xp p, q;
        xp_mul(&e[j], &f[k], &p);
        xp_mul(&e[k], &f[j], &q);
        out[i] = p;
        xp_add(&out[i], &q, -1.0);
    }
}

static int xp_dot_sign(const xp e[3], const xp f[3], bool *overflow)
{
    xp sum = {0}, p;
    for (int i = 0; i < 3; i++) {
        xp_mul(&e[i], &f[i], &p);
        xp_add(&sum, &p, 1.0);
    }
    *overflow |= sum.overflow;
    return xp_sign(&sum);
}

/* ---- one triangle ---------------------------------------------------- */

static inline int sign_of(double x) { return (x > 0.0) - (x < 0.0); }

/* An absolute bound on the rounding of a double evaluation of
 * d . (b x c) from doubles that are themselves each within one rounding of
 * the exact inputs: 7 roundings of the evaluation, 3 of the inputs, with a
 * factor of 8 to spare, times the sum of the magnitudes of the six products.
 * Values beyond it have the exact sign; the rest are recomputed exactly. */
#define FILTER_ULPS (80.0 * 0x1p-53)

static double triple(const double a[3], const double b[3], const double c[3], double *bound)
{
    double m = 0.0, s = 0.0;
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3, k = (i + 2) % 3;
        s += a[i] * (b[j] * c[k] - b[k] * c[j]);
        m += fabs(a[i]) * (fabs(b[j] * c[k]) + fabs(b[k] * c[j]));
    }
    *bound = FILTER_ULPS * m;
    return s;
}

acc_tri_result acc_ref_tri(const float o[3], const float d[3], const float *v)
{
    acc_tri_result r = {false, 0, NAN};
    double a[3], b[3], c[3], dd[3];
    for (int i = 0; i < 3; i++) {
        a[i] = (double)v[i] - o[i];
        b[i] = (double)v[3 + i] - o[i];
        c[i] = (double)v[6 + i] - o[i];
        dd[i] = d[i];
    }
    /* U, V, W: the edge functions (weights of A, B, C); T: the orientation
     * of the origin against the plane, so that t = T / (U + V + W). */
    double eu, ev, ew, et;
    double U = triple(dd, b, c, &eu), V = triple(dd, c, a, &ev), W = triple(dd, a, b, &ew);
    double T = triple(a, b, c, &et);
    int su = sign_of(U), sv = sign_of(V), sw = sign_of(W), st = sign_of(T);
    if (fabs(U) <= eu || fabs(V) <= ev || fabs(W) <= ew || fabs(T) <= et) {
        atomic_fetch_add_explicit(&exact_fallbacks, 1, memory_order_relaxed);
        xp xa[3], xb[3], xc[3], xd[3], bc[3], ca[3], ab[3];
        for (int i = 0; i < 3; i++) {
            xa[i] = xp_diff(v[i], o[i]);
            xb[i] = xp_diff(v[3 + i], o[i]);
            xc[i] = xp_diff(v[6 + i], o[i]);
            xd[i] = xp_of(d[i]);
        }
        xp_cross(xb, xc, bc);
        xp_cross(xc, xa, ca);
        xp_cross(xa, xb, ab);
        bool overflow = false;
        int eu_s = xp_dot_sign(xd, bc, &overflow), ev_s = xp_dot_sign(xd, ca, &overflow);
        int ew_s = xp_dot_sign(xd, ab, &overflow), et_s = xp_dot_sign(xa, bc, &overflow);
        /* Overflow cannot happen for float inputs (see XP_MAX); were it to,
         * the double signs stand. */
        if (!overflow) su = eu_s, sv = ev_s, sw = ew_s, st = et_s;
    }
    bool any_pos = su > 0 || sv > 0 || sw > 0, any_neg = su < 0 || sv < 0 || sw < 0;
    r.crosses = (any_pos || any_neg) && !(any_pos && any_neg);
    r.t_sign = st * (any_neg ? -1 : 1);
    /* t from the normal of the triangle's own edges: better conditioned
     * than T / (U + V + W) when the vertices are far from the origin. */
    double e1[3], e2[3], n[3];
    for (int i = 0; i < 3; i++) e1[i] = b[i] - a[i], e2[i] = c[i] - a[i];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double nd = n[0] * dd[0] + n[1] * dd[1] + n[2] * dd[2];
    double na = n[0] * a[0] + n[1] * a[1] + n[2] * a[2];
    if (nd != 0.0) r.t = na / nd;
    return r;
}

/* ---- the walk -------------------------------------------------------- */

typedef struct {
    double o[3], inv[3], omag, widen;
    bool zero[3];
} ref_ray;

static ref_ray ref_ray_make(const float o[3], const float d[3], double widen)
{
    ref_ray r;
    r.omag = 0.0;
    r.widen = widen;
    for (int a = 0; a < 3; a++) {
        r.o[a] = o[a];
        r.zero[a] = d[a] == 0.0f;
        r.inv[a] = r.zero[a] ? 0.0 : 1.0 / (double)d[a];
        r.omag = fmax(r.omag, fabs(r.o[a]));
    }
    return r;
}

/* Slab test for t >= 0 against the node's box widened by 1e-12 of the
 * magnitudes involved (ten thousand times the rounding of the double slab
 * distances, so no ray that touches the box is turned away) and by `widen`
 * of the planes' distances from the origin. */
static bool ref_box(const lanes_bvh2_node *nd, const ref_ray *r)
{
    double tin = 0.0, tout = INFINITY;
    for (int a = 0; a < 3; a++) {
        double lo = nd->min[a], hi = nd->max[a];
        double w = 1e-12 * (fabs(lo) + fabs(hi) + r->omag) +
                   r->widen * (fabs(lo - r->o[a]) + fabs(hi - r->o[a])) + 1e-30;
        lo -= w, hi += w;
        if (r->zero[a]) {
            if (r->o[a] < lo || r->o[a] > hi) return false;
            continue;
        }
        double t1 = (lo - r->o[a]) * r->inv[a], t2 = (hi - r->o[a]) * r->inv[a];
        if (t1 > t2) {
            double s = t1;
            t1 = t2, t2 = s;
        }
        tin = fmax(tin, t1);
        tout = fmin(tout, t2);
    }
    return tin <= tout;
}

bool acc_ref_walk(const acc_ref *r, const float o[3], const float d[3], double widen,
                  bool (*visit)(void *ctx, uint32_t prim), void *ctx)
{
    const lanes_bvh2 *b = r->bvh;
    if (b->node_count == 0) return false;
    ref_ray rr = ref_ray_make(o, d, widen);
    uint32_t stack[2 * LANES_BVH_MAX_DEPTH + 2];
    int sp = 0;
    if (ref_box(&b->nodes[0], &rr)) stack[sp++] = 0;
    while (sp > 0) {
        const lanes_bvh2_node *nd = &b->nodes[stack[--sp]];
        if (nd->count > 0) {
            for (uint32_t k = 0; k < nd->count; k++) {
                if (visit(ctx, b->prim_index[nd->first + k])) return true;
            }
            continue;
        }
        for (uint32_t c = 0; c < 2; c++)
            if (ref_box(&b->nodes[nd->first + c], &rr)) stack[sp++] = nd->first + c;
    }
    return false;
}

/* The ray and the reference the visitors below test each triangle with. */
typedef struct {
    const acc_ref *ref;
    const float *o, *d;
    size_t count;
} tri_visit;

static acc_tri_result visit_tri(const tri_visit *v, uint32_t prim)
{
    return acc_ref_tri(v->o, v->d, v->ref->verts + (size_t)prim * 9);
}

static bool visit_any(void *ctx, uint32_t prim)
{
    acc_tri_result t = visit_tri(ctx, prim);
    return t.crosses && t.t_sign >= 0;
}

bool acc_ref_any(const acc_ref *r, const float o[3], const float d[3])
{
    tri_visit v = {r, o, d, 0};
    return acc_ref_walk(r, o, d, 0.0, visit_any, &v);
}

static bool visit_count(void *ctx, uint32_t prim)
{
    tri_visit *v = ctx;
    acc_tri_result t = visit_tri(v, prim);
    if (t.crosses && t.t_sign > 0) v->count++;
    return false;
}

size_t acc_ref_crossings(const acc_ref *r, const float o[3], const float d[3])
{
    tri_visit v = {r, o, d, 0};
    acc_ref_walk(r, o, d, 0.0, visit_count, &v);
    return v.count;
}

/* ---- distance -------------------------------------------------------- */

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Squared distance from p to the triangle (Ericson, Real-Time Collision
 * Detection 5.1.5: the Voronoi region of p decides the closest feature). */
static double tri_dist2(const double p[3], const float *v)
{
    double a[3], ab[3], ac[3], ap[3], q[3];
    for (int i = 0; i < 3; i++) {
        a[i] = v[i];
        ab[i] = (double)v[3 + i] - v[i];
        ac[i] = (double)v[6 + i] - v[i];
        ap[i] = p[i] - a[i];
    }
    double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
    double s = 0.0, t = 0.0;
    if (d1 <= 0.0 && d2 <= 0.0) {
        s = t = 0.0;
    } else {
        double bp[3], cp[3];
        for (int i = 0; i < 3; i++) bp[i] = ap[i] - ab[i], cp[i] = ap[i] - ac[i];
        double d3 = dot3(ab, bp), d4 = dot3(ac, bp), d5 = dot3(ab, cp), d6 = dot3(ac, cp);
        double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
        if (d3 >= 0.0 && d4 <= d3) {
            s = 1.0, t = 0.0;
        } else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
            s = d1 / (d1 - d3), t = 0.0;
        } else if (d6 >= 0.0 && d5 <= d6) {
            s = 0.0, t = 1.0;
        } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
            s = 0.0, t = d2 / (d2 - d6);
        } else if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
            t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
            s = 1.0 - t;
        } else {
            double den = va + vb + vc;
            if (den != 0.0) s = vb / den, t = vc / den;
        }
    }
    for (int i = 0; i < 3; i++) q[i] = ap[i] - s * ab[i] - t * ac[i];
    return dot3(q, q);
}

static double box_dist2(const lanes_bvh2_node *nd, const double p[3])
{
    double s = 0.0;
    for (int a = 0; a < 3; a++) {
        double e = fmax(fmax((double)nd->min[a] - p[a], p[a] - (double)nd->max[a]), 0.0);
        s += e * e;
    }
    return s;
}

bool acc_ref_near(const acc_ref *r, const double p[3], double dist)
{
    const lanes_bvh2 *b = r->bvh;
    /* the squared distances are rounded; a hair of slack keeps the pruning
     * conservative, and the answer is only used as a safety margin */
    double d2 = dist * dist * (1.0 + 1e-9);
    uint32_t stack[2 * LANES_BVH_MAX_DEPTH + 2];
    int sp = 0;
    if (b->node_count == 0) return false;
    stack[sp++] = 0;
    while (sp > 0) {
        const lanes_bvh2_node *nd = &b->nodes[stack[--sp]];
        if (box_dist2(nd, p) > d2) continue;
        if (nd->count > 0) {
            for (uint32_t k = 0; k < nd->count; k++)
                if (tri_dist2(p, r->verts + (size_t)b->prim_index[nd->first + k] * 9) < d2) return true;
            continue;
        }
        stack[sp++] = nd->first;
        stack[sp++] = nd->first + 1;
    }
    return false;
}

/* ---- set-up ---------------------------------------------------------- */

lanes_status acc_ref_init(acc_ref *r, const lanes_bvh2 *bvh, const lanes_scene *scene, lanes_error *err)
{
    r->bvh = bvh;
    r->verts = scene->verts;
    if (bvh->skipped != 0 || bvh->prim_count != scene->triangle_count) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "reference: the BVH holds %zu of %zu triangles",
                               bvh->prim_count, scene->triangle_count);
    }
    /* Each leaf's triangles must lie inside the intersection of the boxes
     * of all its ancestors: then no widened-box walk can miss them. */
    typedef struct {
        uint32_t node;
        float lo[3], hi[3];
    } item;
    item stack[2 * LANES_BVH_MAX_DEPTH + 2];
    int sp = 0;
    size_t seen = 0;
    if (bvh->node_count == 0) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "reference: empty BVH");
    }
    stack[sp++] = (item){0, {-INFINITY, -INFINITY, -INFINITY}, {INFINITY, INFINITY, INFINITY}};
    while (sp > 0) {
        item it = stack[--sp];
        const lanes_bvh2_node *nd = &bvh->nodes[it.node];
        for (int a = 0; a < 3; a++) {
            it.lo[a] = fmaxf(it.lo[a], nd->min[a]);
            it.hi[a] = fminf(it.hi[a], nd->max[a]);
        }
        if (nd->count == 0) {
            if ((size_t)nd->first + 1 >= bvh->node_count || sp + 2 > (int)(sizeof stack / sizeof stack[0])) {
                return lanes_error_set(err, LANES_ERR_BAD_INPUT, "reference: malformed BVH at node %u",
                                       it.node);
            }
            stack[sp++] = (item){nd->first, {it.lo[0], it.lo[1], it.lo[2]}, {it.hi[0], it.hi[1], it.hi[2]}};
            stack[sp++] = (item){nd->first + 1, {it.lo[0], it.lo[1], it.lo[2]}, {it.hi[0], it.hi[1], it.hi[2]}};
            continue;
        }
        for (uint32_t k = 0; k < nd->count; k++) {
            uint32_t prim = bvh->prim_index[nd->first + k];
            const float *v = scene->verts + (size_t)prim * 9;
            for (int c = 0; c < 9; c++)
                if (!(v[c] >= it.lo[c % 3] && v[c] <= it.hi[c % 3])) {
                    return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                                           "reference: triangle %u lies outside a box above its leaf", prim);
                }
            seen++;
        }
    }
    if (seen != scene->triangle_count) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "reference: the BVH's leaves hold %zu triangle references for %zu triangles",
                               seen, scene->triangle_count);
    }
    return LANES_OK;
}
