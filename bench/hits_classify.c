/* Disagreements between two engines' hits, sorted by cause (hits_classify.h).
 *
 * Compiled for the x86-64 baseline. */
#include "bench/hits_classify.h"

#include <math.h>

/* Same primitive and t within 1e-4 relative, or both miss. */
bool hits_same(const lanes_hit *a, const lanes_hit *b)
{
    if (a->prim != b->prim) return false;
    if (a->prim == LANES_NO_HIT) return true;
    return fabsf(a->t - b->t) <= 1e-4f * fmaxf(fabsf(a->t), fabsf(b->t));
}

/* Barycentric distance from the triangle's boundary of the point where the
 * ray meets its plane, in double (0 on an edge; +inf when parallel), and
 * the rounding error a float test makes in it: the vertices relative to the
 * origin carry an error of about u * (largest coordinate), which dividing
 * by the determinant (|d| * 2 area * cos) magnifies. A small triangle far
 * from the origin, seen at a grazing angle, has barycentrics that float
 * arithmetic cannot resolve to 1e-4. */
static double edge_distance(const lanes_scene *s, uint32_t prim, const lanes_ray *r, double *err)
{
    const float *v = s->verts + (size_t)prim * 9;
    double e1[3], e2[3], tv[3], p[3], q[3], big = 0.0;
    for (int a = 0; a < 3; a++) {
        e1[a] = (double)v[3 + a] - v[a];
        e2[a] = (double)v[6 + a] - v[a];
        tv[a] = (double)r->o[a] - v[a];
        big = fmax(big, fmax(fabs((double)r->o[a]), fmax(fabs((double)v[a]),
                                                          fmax(fabs((double)v[3 + a]), fabs((double)v[6 + a])))));
    }
    p[0] = r->d[1] * e2[2] - (double)r->d[2] * e2[1];
    p[1] = r->d[2] * e2[0] - (double)r->d[0] * e2[2];
    p[2] = r->d[0] * e2[1] - (double)r->d[1] * e2[0];
    double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
    *err = INFINITY;
    if (det == 0.0) return INFINITY;
    q[0] = tv[1] * e1[2] - tv[2] * e1[1];
    q[1] = tv[2] * e1[0] - tv[0] * e1[2];
    q[2] = tv[0] * e1[1] - tv[1] * e1[0];
    double b1 = (tv[0] * p[0] + tv[1] * p[1] + tv[2] * p[2]) / det;
    double b2 = (r->d[0] * q[0] + r->d[1] * q[1] + r->d[2] * q[2]) / det;
    double le = sqrt(fmax(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2],
                          e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]));
    double ld = sqrt((double)r->d[0] * r->d[0] + (double)r->d[1] * r->d[1] + (double)r->d[2] * r->d[2]);
    *err = 8.0 * 0x1p-24 * big * le * ld / fabs(det);
    return fmin(fabs(1.0 - b1 - b2), fmin(fabs(b1), fabs(b2)));
}

/* A hit that float rounding may decide: within 1e-4 of a triangle edge (or
 * within the test's own rounding error of it), or at the very start or end
 * of the ray's interval (a ray starting on a surface). */
static bool grazing_hit(const lanes_scene *s, const lanes_hit *h, const lanes_ray *r)
{
    if (h->prim == LANES_NO_HIT) return false;
    float scale = fmaxf(fabsf(h->t), 1.0f);
    if (fabsf(h->t - r->tnear) <= 1e-4f * scale || fabsf(h->t - r->tfar) <= 1e-4f * fabsf(r->tfar))
        return true;
    double err, dist = edge_distance(s, h->prim, r, &err);
    return dist < 1e-4 || dist < err;
}

/* Sorts a disagreement between lanes' and Embree's closest hits (for
 * shadow rays: the nearest blockers each engine finds) into a category. */
void hits_classify(const lanes_scene *s, const lanes_ray *r, const lanes_hit *l, const lanes_hit *e,
                   hits_differences *d)
{
    if (l->prim != LANES_NO_HIT && e->prim != LANES_NO_HIT && l->prim != e->prim &&
        fabsf(l->t - e->t) <= 1e-4f * fmaxf(fabsf(l->t), fabsf(e->t)))
        d->ties++;
    else if (grazing_hit(s, l, r) || grazing_hit(s, e, r))
        d->grazing++;
    else
        d->other++;
}
