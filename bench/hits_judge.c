/* Disagreements between two engines judged by the exact reference
 * (hits_judge.h).
 *
 * Compiled for the x86-64 baseline. */
#include "bench/hits_judge.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

bool hits_same(const lanes_hit *a, const lanes_hit *b)
{
    if (a->prim != b->prim) return false;
    if (a->prim == LANES_NO_HIT) return true;
    return fabsf(a->t - b->t) <= 1e-4f * fmaxf(fabsf(a->t), fabsf(b->t));
}

judge_test judge_test_of(lanes_accuracy mode)
{
    return mode == LANES_ACCURACY_ROBUST ? JUDGE_WATERTIGHT : JUDGE_MOLLER;
}

/* gamma(n) of float arithmetic: n roundings of relative error 2^-24 each. */
static double gamma_f(int n)
{
    const double u = 0x1p-24;
    return n * u / (1.0 - n * u);
}

/* ---- one triangle ----------------------------------------------------- */

/* What one triangle looks like to one float test on one ray. */
typedef struct {
    double w[3];    /* the weights of v0, v1, v2 (edge functions, d . (b x c) ...) */
    double band[3]; /* how far the test's rounding can move each */
    double t, tband; /* distance (NaN: parallel) and its rounding bound (inf: in doubt) */
    double bdet;    /* the rounding bound of det = w0 + w1 + w2 */
    bool exact;     /* the line meets the closed triangle, exactly decided */
    bool certain, possible;
} tri_facts;

static double dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void cross(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

/* The sum over the six terms of x . (y x z) of their magnitudes: what a
 * running-error bound multiplies, for any order of evaluation. */
static double terms(const double x[3], const double y[3], const double z[3])
{
    double s = 0.0;
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3, k = (i + 2) % 3;
        s += fabs(x[i]) * (fabs(y[j] * z[k]) + fabs(y[k] * z[j]));
    }
    return s;
}

/* Möller–Trumbore forms u = (T . (d x e2)) / det, v = (d . (T x e1)) / det,
 * det = e1 . (d x e2) and t = (e2 . (T x e1)) / det from T = o - v0 and the
 * edges, each input rounded once, then compares u, v and u + v with 0 and 1;
 * Embree's form (R = C x d with C = v0 - o, its stored normal) has the same
 * terms. Ten roundings bound either chain. */
static void moller_bands(const double a[3], const double b[3], const double c[3], const double d[3],
                         const double w[3], double t, double band[3], double *tband, double *bdet_out)
{
    const double g = gamma_f(10);
    double T[3], e1[3], e2[3];
    for (int i = 0; i < 3; i++) T[i] = -a[i], e1[i] = b[i] - a[i], e2[i] = c[i] - a[i];
    double det = w[0] + w[1] + w[2];
    double bdet = g * terms(e1, d, e2);
    band[1] = g * terms(T, d, e2);
    band[2] = g * terms(d, T, e1);
    /* u + v <= 1: lanes divides first (u = uu / det: the error of det counts
     * (|uu| + |vv|) / |det| times), Embree compares uu + vv with det */
    double sum = fabs(w[1]) + fabs(w[2]);
    band[0] = band[1] + band[2] + bdet * fmax(1.0, sum / fabs(det)) + gamma_f(4) * (sum + fabs(det));
    *bdet_out = bdet;
    double btt = g * terms(e2, T, e1);
    *tband = fabs(det) > bdet ? (btt + fabs(t) * bdet) / fabs(det) + gamma_f(4) * fabs(t) : INFINITY;
}

/* The watertight test (Woop et al. 2013) shears the vertices relative to o
 * so that d becomes +z: p' = (p_x - s_x p_z, p_y - s_y p_z), s = d_xy / d_z,
 * with z the axis of largest |d|; each sheared coordinate is within
 * gamma(4) (|p_x| + |s_x p_z|) of its exact value (the difference from o,
 * s, the product, the subtraction), and the edge function P'_x Q'_y -
 * P'_y Q'_x multiplies two of them. The exact edge function is d_z times
 * the 2-d one, so the bound is scaled by |d_z| into the units of w. */
static void watertight_bands(const double a[3], const double b[3], const double c[3], const double d[3],
                             const double w[3], double band[3], double *tband, double *bdet_out)
{
    const double ad[3] = {fabs(d[0]), fabs(d[1]), fabs(d[2])};
    int kz = ad[0] >= ad[1] ? (ad[0] >= ad[2] ? 0 : 2) : (ad[1] >= ad[2] ? 1 : 2);
    int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
    double sx = d[kx] / d[kz], sy = d[ky] / d[kz];
    const double *p[3] = {a, b, c};
    double x[3], y[3], ex[3], ey[3];
    for (int i = 0; i < 3; i++) {
        x[i] = p[i][kx] - sx * p[i][kz];
        y[i] = p[i][ky] - sy * p[i][kz];
        ex[i] = gamma_f(4) * (fabs(p[i][kx]) + fabs(sx * p[i][kz]));
        ey[i] = gamma_f(4) * (fabs(p[i][ky]) + fabs(sy * p[i][kz]));
    }
    /* weight of vertex i: the edge function of the other two, P = i+2, Q = i+1 */
    double bdet = 0.0;
    for (int i = 0; i < 3; i++) {
        int P = (i + 2) % 3, Q = (i + 1) % 3;
        double px = fabs(x[P]) + ex[P], py = fabs(y[P]) + ey[P];
        double qx = fabs(x[Q]) + ex[Q], qy = fabs(y[Q]) + ey[Q];
        double e2d = px * ey[Q] + ex[P] * fabs(y[Q]) + py * ex[Q] + ey[P] * fabs(x[Q]) +
                     gamma_f(2) * (px * qy + py * qx);
        band[i] = ad[kz] * e2d;
        bdet += band[i];
    }
    double det = w[0] + w[1] + w[2];
    bdet += gamma_f(3) * (fabs(w[0]) + fabs(w[1]) + fabs(w[2]));
    *bdet_out = bdet;
    if (!(fabs(det) > bdet)) {
        *tband = INFINITY;
        return;
    }
    /* t = sum b_i z_i / d_z with the barycentrics b_i = w_i / det. The
     * rounded weights' quotients by their own rounded sum add up to 1, so
     * their errors (each within (band_i + |b_i| sum band) / |det|) sum to
     * 0 and move t by sum err_i (z_i - z_0) only; the divisions, the
     * scaled z and the sum add a few roundings of sum |b_i z_i|. */
    double tb = 0.0, sum_band = band[0] + band[1] + band[2];
    for (int i = 0; i < 3; i++) {
        double bi = fabs(w[i] / det);
        tb += (band[i] + bi * sum_band) / fabs(det) * fabs(p[i][kz] - p[0][kz]) + gamma_f(8) * bi * fabs(p[i][kz]);
    }
    *tband = tb / ad[kz];
}

static tri_facts tri_judge(const float o[3], const float d[3], const float *v, judge_test test)
{
    tri_facts f;
    double a[3], b[3], c[3], dd[3];
    for (int i = 0; i < 3; i++) {
        a[i] = (double)v[i] - o[i];
        b[i] = (double)v[3 + i] - o[i];
        c[i] = (double)v[6 + i] - o[i];
        dd[i] = d[i];
    }
    double bc[3], ca[3], ab[3];
    cross(b, c, bc), cross(c, a, ca), cross(a, b, ab);
    f.w[0] = dot(dd, bc), f.w[1] = dot(dd, ca), f.w[2] = dot(dd, ab);
    acc_tri_result ex = acc_ref_tri(o, d, v);
    f.exact = ex.crosses;
    f.t = ex.t;
    if (test == JUDGE_MOLLER)
        moller_bands(a, b, c, dd, f.w, f.t, f.band, &f.tband, &f.bdet);
    else
        watertight_bands(a, b, c, dd, f.w, f.band, &f.tband, &f.bdet);
    if (isnan(f.t)) f.tband = INFINITY;
    bool pos = true, neg = true, in_pos = true, in_neg = true;
    for (int i = 0; i < 3; i++) {
        pos &= f.w[i] > f.band[i];
        neg &= f.w[i] < -f.band[i];
        in_pos &= f.w[i] >= -f.band[i];
        in_neg &= f.w[i] <= f.band[i];
    }
    f.certain = (pos || neg) && isfinite(f.tband);
    /* a determinant that is 0 with no rounding to move it (a triangle that
     * is a point, or seen exactly edge-on with exact products) is 0 in
     * float too, and both tests reject it */
    double det = f.w[0] + f.w[1] + f.w[2];
    f.possible = f.exact || ((in_pos || in_neg) && (det != 0.0 || f.bdet > 0.0));
    return f;
}

static bool certainly_in(const tri_facts *f, const lanes_ray *r)
{
    return f->t - f->tband > r->tnear && f->t + f->tband < r->tfar;
}

static bool possibly_in(const tri_facts *f, const lanes_ray *r)
{
    return isnan(f->t) || (f->t + f->tband >= r->tnear && f->t - f->tband <= r->tfar);
}

/* ---- shared edges ----------------------------------------------------- */

static uint64_t mix(uint64_t h, uint32_t x)
{
    h ^= x;
    h *= 0x100000001b3ull;
    return h ^ (h >> 29);
}

static uint64_t point_hash(const float *p)
{
    uint64_t h = 0xcbf29ce484222325ull;
    for (int i = 0; i < 3; i++) {
        uint32_t bits;
        float f = p[i] == 0.0f ? 0.0f : p[i]; /* -0 and +0 are one point */
        memcpy(&bits, &f, sizeof bits);
        h = mix(h, bits);
    }
    return h;
}

/* The edge opposite vertex e of triangle tri, in either direction. */
static uint64_t edge_hash(const float *v, uint32_t e)
{
    uint64_t p = point_hash(v + 3 * ((e + 1) % 3)), q = point_hash(v + 3 * ((e + 2) % 3));
    return (p < q ? p : q) * 0x9e3779b97f4a7c15ull + (p < q ? q : p);
}

static bool same_point(const float *p, const float *q)
{
    return p[0] == q[0] && p[1] == q[1] && p[2] == q[2];
}

static bool same_edge(const float *v, uint32_t e, const float *w, uint32_t f)
{
    const float *p0 = v + 3 * ((e + 1) % 3), *p1 = v + 3 * ((e + 2) % 3);
    const float *q0 = w + 3 * ((f + 1) % 3), *q1 = w + 3 * ((f + 2) % 3);
    return (same_point(p0, q0) && same_point(p1, q1)) || (same_point(p0, q1) && same_point(p1, q0));
}

static int edge_order(const void *x, const void *y)
{
    const judge_edge *a = x, *b = y;
    return a->hash < b->hash ? -1 : a->hash > b->hash;
}

/* The one other triangle (and its edge) that shares edge e of tri, or
 * false when the edge is a boundary or shared by more than two. */
static bool edge_neighbour(const hits_judge *j, uint32_t tri, uint32_t e, uint32_t *other, uint32_t *oe)
{
    const float *verts = j->scene->verts;
    judge_edge key = {edge_hash(verts + 9 * (size_t)tri, e), 0, 0};
    size_t lo = 0, hi = j->edge_count;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (j->edges[mid].hash < key.hash) lo = mid + 1;
        else hi = mid;
    }
    int found = 0;
    for (size_t i = lo; i < j->edge_count && j->edges[i].hash == key.hash; i++) {
        const judge_edge *g = &j->edges[i];
        if (g->tri == tri && g->edge == e) continue;
        if (!same_edge(verts + 9 * (size_t)tri, e, verts + 9 * (size_t)g->tri, g->edge)) continue;
        *other = g->tri, *oe = g->edge;
        found++;
    }
    return found == 1;
}

lanes_status hits_judge_init(hits_judge *j, const lanes_scene *scene, const lanes_bvh2 *bvh,
                             bool watertight, lanes_error *err)
{
    memset(j, 0, sizeof *j);
    j->scene = scene;
    lanes_status st = acc_ref_init(&j->ref, bvh, scene, err);
    if (st != LANES_OK || !watertight) return st;
    size_t n = 3 * scene->triangle_count;
    j->edges = malloc((n ? n : 1) * sizeof *j->edges);
    if (!j->edges) return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "judge: out of memory for %zu edges", n);
    for (size_t t = 0; t < scene->triangle_count; t++)
        for (uint32_t e = 0; e < 3; e++)
            j->edges[3 * t + e] = (judge_edge){edge_hash(scene->verts + 9 * t, e), (uint32_t)t, e};
    qsort(j->edges, n, sizeof *j->edges, edge_order);
    j->edge_count = n;
    return LANES_OK;
}

void hits_judge_free(hits_judge *j)
{
    free(j->edges);
    memset(j, 0, sizeof *j);
}

/* ---- one ray ------------------------------------------------------------ */

/* The walk's state: the ray, the test, what it has found. */
typedef struct {
    const hits_judge *j;
    const lanes_ray *r;
    judge_test test;
    judge_ray found;
} ray_walk;

/* Whether a watertight test must hit triangle tri (its facts f) or its
 * neighbour: f crosses exactly, certainly in range, within its bound of
 * one edge only, and the one triangle across that edge is certainly
 * entered from it (its weights at the edge's ends beyond their bounds, of
 * one sign) and certainly in range. */
static bool watertight_forced(const ray_walk *rf, uint32_t tri, const tri_facts *f)
{
    if (!f->exact || !certainly_in(f, rf->r)) return false;
    int near = -1;
    for (int i = 0; i < 3; i++) {
        if (fabs(f->w[i]) > f->band[i]) continue;
        if (near >= 0) return false; /* near a vertex: the fan decides */
        near = i;
    }
    if (near < 0) return false; /* certain: counted as such */
    uint32_t other, oe;
    if (!edge_neighbour(rf->j, tri, (uint32_t)near, &other, &oe)) return false;
    tri_facts g = tri_judge(rf->r->o, rf->r->d, rf->j->scene->verts + 9 * (size_t)other, rf->test);
    double p = g.w[(oe + 1) % 3], q = g.w[(oe + 2) % 3];
    double bp = g.band[(oe + 1) % 3], bq = g.band[(oe + 2) % 3];
    bool inward = (p > bp && q > bq) || (p < -bp && q < -bq);
    return inward && isfinite(g.tband) && certainly_in(&g, rf->r);
}

static bool visit(void *ctx, uint32_t prim)
{
    ray_walk *rf = ctx;
    judge_ray *found = &rf->found;
    tri_facts f = tri_judge(rf->r->o, rf->r->d, rf->j->scene->verts + 9 * (size_t)prim, rf->test);
    if (f.possible && possibly_in(&f, rf->r)) found->any_possible = true;
    if (f.certain && certainly_in(&f, rf->r)) found->nearest_certain = fmin(found->nearest_certain, f.t + f.tband);
    if (rf->test == JUDGE_WATERTIGHT && !found->forced && rf->j->edges)
        found->forced = watertight_forced(rf, prim, &f);
    return false;
}

/* A triangle a float test may report lies within about gamma(10) of its
 * distance from the ray's origin of the ray (the bounds above divided by
 * the edge's length and |d|: the inputs are exact floats, and rounding
 * starts with the differences v - o): boxes widened by 1e-4 of that
 * distance hold every one. */
#define JUDGE_WIDEN 1e-4

judge_ray hits_judge_ray(const hits_judge *j, const lanes_ray *r, judge_test test)
{
    ray_walk rf = {j, r, test, {INFINITY, false, false}};
    acc_ref_walk(&j->ref, r->o, r->d, JUDGE_WIDEN, visit, &rf);
    return rf.found;
}

bool hits_judge_answer(const hits_judge *j, const lanes_ray *r, const judge_ray *rf, const judge_answer *a)
{
    bool blocked = a->occlusion ? a->occluded : a->prim != LANES_NO_HIT;
    if (!blocked) return rf->nearest_certain < INFINITY || rf->forced;
    if (a->occlusion) return !rf->any_possible;
    if (a->prim >= j->scene->triangle_count) return true;
    tri_facts f = tri_judge(r->o, r->d, j->scene->verts + 9 * (size_t)a->prim, a->test);
    if (!f.possible || !possibly_in(&f, r)) return true;
    if (!isnan(f.t) && f.t - f.tband > rf->nearest_certain) return true;
    return isfinite(f.tband) && !isnan(f.t) && fabs((double)a->t - f.t) > 2.0 * f.tband;
}

bool hits_judge_wrong(const hits_judge *j, const lanes_ray *r, const judge_answer *a)
{
    judge_ray facts = hits_judge_ray(j, r, a->test);
    return hits_judge_answer(j, r, &facts, a);
}

bool judge_cache_init(judge_cache *c, const lanes_ray *rays, size_t count)
{
    memset(c, 0, sizeof *c);
    c->rays = rays;
    c->count = count;
    size_t n = count ? count : 1;
    for (int t = 0; t < 2; t++) {
        c->facts[t] = malloc(n * sizeof *c->facts[t]);
        c->known[t] = calloc(n, 1);
        if (!c->facts[t] || !c->known[t]) {
            judge_cache_free(c);
            return false;
        }
    }
    return true;
}

void judge_cache_free(judge_cache *c)
{
    for (int t = 0; t < 2; t++) free(c->facts[t]), free(c->known[t]);
    memset(c, 0, sizeof *c);
}

static bool cached_wrong(const hits_judge *j, judge_cache *c, size_t i, const judge_answer *a)
{
    int t = a->test == JUDGE_WATERTIGHT;
    if (!c->known[t][i]) {
        c->facts[t][i] = hits_judge_ray(j, &c->rays[i], a->test);
        c->known[t][i] = 1;
    }
    return hits_judge_answer(j, &c->rays[i], &c->facts[t][i], a);
}

void hits_judge_pair(const hits_judge *j, judge_cache *c, size_t i, const judge_answer *lanes,
                     const judge_answer *embree, hits_verdicts *v)
{
    bool lw = cached_wrong(j, c, i, lanes), ew = cached_wrong(j, c, i, embree);
    v->lanes_wrong += lw;
    v->embree_wrong += ew;
    v->both_acceptable += !lw && !ew;
}
