/* The traversals (trace_wide, occluded_wide, trace_bvh2, occluded_bvh2,
 * the hybrid packets trace_hybrid, occluded_hybrid, and the streams
 * trace_stream, occluded_stream) of every supported kernel set, with both
 * triangle tests, against two references:
 *
 *  brute  (small scenes, BVHs with leaves of at most 1, 4 and 12
 *         triangles): every triangle tested with the same set's own
 *         triangle kernel (the hybrid packets also against trace_wide, on
 *         those rays and on camera rays in 4x4 pixel blocks, whose
 *         packets stay together: the same t bit for bit, the same
 *         answer to occlusion but where the visiting order
 *         decides; the occlusion stream against occluded_wide, the same
 *         answer for every ray). The traversal must find exactly what the brute
 *         force finds: the same t bit for bit, the same triangle unless
 *         another one is hit at exactly that t (a tie, which either may
 *         report), and occlusion iff a closest hit exists. Since both sides
 *         run the same arithmetic per triangle, any other difference is a
 *         traversal bug (a box culled wrongly, a stack lost, a stale tfar),
 *         with one exception: a float t that lies outside its own
 *         triangle's box (see judge()). The counting copies (stats != NULL)
 *         must answer exactly as the plain ones. The double-precision
 *         reference of tests/reference.h checks the brute force itself:
 *         every difference must lie in its rounding band or be a tie.
 *  embree (real meshes, optionally scaled and moved): Embree's
 *         rtcIntersect1/rtcOccluded1 on camera, shadow and diffuse rays,
 *         in default and robust mode; each disagreement judged by the exact
 *         reference (bench/hits_judge.h): lanes wrong, Embree wrong, or both
 *         acceptable. Robust mode must never be wrong; on the unmoved scene
 *         default mode must agree on 99.99% of the rays. The judge itself
 *         must call Embree's answers wrong once they are made wrong. Also:
 *         every packet and stream API of the adapter answers as
 *         rtcIntersect1.
 *
 *   test_traversal brute [random|sphere|grid|tiny|default|all]
 *   test_traversal embree SCENE [--rays N] [--scale S] [--translate T]
 *                                            (exit 77: mesh not fetched)
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <embree3/rtcore_config.h>

#include "bench/embree_adapter.h"
#include "bench/hits_judge.h"
#include "build/bvh.h"
#include "build/camera.h"
#include "build/scene.h"
#include "build/scene_load.h"
#include "build/scenes_builtin.h"
#include "simd/isa.h"
#include "trace/kernels.h"
#include "tests/harness.h"
#include "tests/reference.h"

#define SKIP 77

/* ---- random numbers ------------------------------------------------------ */

static float rndf(harness_rng *s, float lo, float hi) { return lo + (hi - lo) * (float)harness_uniform(s); }

static void random_dir(harness_rng *s, float d[3])
{
    double z = 2.0 * harness_uniform(s) - 1.0, phi = 6.283185307179586 * harness_uniform(s), r = sqrt(1.0 - z * z);
    d[0] = (float)(r * cos(phi)), d[1] = (float)(r * sin(phi)), d[2] = (float)z;
}

/* ---- scenes -------------------------------------------------------------- */

static void add_tri(lanes_scene *s, const float a[3], const float b[3], const float c[3])
{
    float v[9] = {a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2]};
    lanes_error err;
    if (lanes_scene_add_triangle(s, v, 0, &err) != LANES_OK) {
        printf("cannot add a triangle: %s\n", err.message);
        exit(1);
    }
}

static void scene_start(lanes_scene *s, const char *name)
{
    lanes_scene_init(s);
    snprintf(s->name, sizeof s->name, "%s", name);
    lanes_material m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "grey");
    m.kind = LANES_MAT_DIFFUSE;
    m.color[0] = m.color[1] = m.color[2] = 0.7f;
    lanes_error err;
    if (lanes_scene_add_material(s, &m, NULL, &err) != LANES_OK) {
        printf("cannot add a material: %s\n", err.message);
        exit(1);
    }
}

/* Random small triangles in [-1,1]^3, some of them exact duplicates (same
 * vertices in the same order, so a tie is bitwise) and some duplicates with
 * the vertices rotated (same plane, t equal up to rounding). */
static void scene_random(lanes_scene *s)
{
    harness_rng seed = {1234};
    scene_start(s, "random");
    for (int i = 0; i < 600; i++) {
        float c[3], v[3][3];
        for (int a = 0; a < 3; a++) c[a] = rndf(&seed, -1.0f, 1.0f);
        for (int k = 0; k < 3; k++)
            for (int a = 0; a < 3; a++) v[k][a] = c[a] + rndf(&seed, -0.2f, 0.2f);
        add_tri(s, v[0], v[1], v[2]);
    }
    for (int i = 0; i < 40; i++) {
        size_t j = (size_t)(harness_next(&seed) % 600);
        const float *v = s->verts + 9 * j;
        if (i % 2)
            add_tri(s, v, v + 3, v + 6);
        else
            add_tri(s, v + 3, v + 6, v);
    }
}

/* A closed UV sphere: every vertex computed once and shared, so there are
 * no cracks for a ray to slip through (with the watertight test). */
static void scene_sphere(lanes_scene *s)
{
    enum { SEG = 48, RING = 24 };
    float p[RING + 1][SEG][3];
    scene_start(s, "sphere");
    for (int r = 0; r <= RING; r++)
        for (int k = 0; k < SEG; k++) {
            double th = 3.141592653589793 * r / RING, ph = 6.283185307179586 * k / SEG;
            p[r][k][0] = (float)(sin(th) * cos(ph));
            p[r][k][1] = (float)cos(th);
            p[r][k][2] = (float)(sin(th) * sin(ph));
        }
    for (int r = 0; r < RING; r++)
        for (int k = 0; k < SEG; k++) {
            int k1 = (k + 1) % SEG;
            if (r > 0) add_tri(s, p[r][k], p[r][k1], p[r + 1][k]);
            if (r < RING - 1) add_tri(s, p[r][k1], p[r + 1][k1], p[r + 1][k]);
        }
}

/* Two grids of shared edges: a flat one in z = 0 (its boxes have zero
 * thickness) and a vertical one in y = 0.25 that cuts through it. */
static void scene_grid(lanes_scene *s)
{
    scene_start(s, "grid");
    const int n = 24, m = 12;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            float x0 = -1.0f + 2.0f * (float)i / n, x1 = -1.0f + 2.0f * (float)(i + 1) / n;
            float y0 = -1.0f + 2.0f * (float)j / n, y1 = -1.0f + 2.0f * (float)(j + 1) / n;
            float a[3] = {x0, y0, 0}, b[3] = {x1, y0, 0}, c[3] = {x1, y1, 0}, d[3] = {x0, y1, 0};
            add_tri(s, a, b, c);
            add_tri(s, a, c, d);
        }
    for (int i = 0; i < m; i++)
        for (int j = 0; j < m; j++) {
            float x0 = -0.5f + (float)i / m, x1 = -0.5f + (float)(i + 1) / m;
            float z0 = -0.5f + (float)j / m, z1 = -0.5f + (float)(j + 1) / m;
            float a[3] = {x0, 0.25f, z0}, b[3] = {x1, 0.25f, z0}, c[3] = {x1, 0.25f, z1},
                  d[3] = {x0, 0.25f, z1};
            add_tri(s, a, b, c);
            add_tri(s, a, c, d);
        }
}

/* Scenes small enough that the BVH2 root is a leaf (or nearly). */
static void scene_tiny(lanes_scene *s, int count)
{
    char name[32];
    snprintf(name, sizeof name, "tiny%d", count);
    scene_start(s, name);
    harness_rng seed = {99 + (uint64_t)count};
    for (int i = 0; i < count; i++) {
        float v[3][3];
        for (int k = 0; k < 3; k++)
            for (int a = 0; a < 3; a++) v[k][a] = rndf(&seed, -1.0f, 1.0f);
        add_tri(s, v[0], v[1], v[2]);
    }
}

/* ---- rays for the small scenes --------------------------------------------- */

static void bounds(const lanes_scene *s, float lo[3], float hi[3], float *size)
{
    lanes_scene_bounds(s, lo, hi);
    float d = 0;
    for (int a = 0; a < 3; a++) d = fmaxf(d, hi[a] - lo[a]);
    *size = d > 0 ? d : 1.0f;
}

static void point_on(const lanes_scene *s, size_t tri, double b1, double b2, float p[3])
{
    const float *v = s->verts + 9 * tri;
    for (int a = 0; a < 3; a++)
        p[a] = (float)((1.0 - b1 - b2) * v[a] + b1 * v[3 + a] + b2 * v[6 + a]);
}

/* Camera rays through a side x side grid over the scene's bounds, from
 * in front of it, in 4x4 pixel blocks: consecutive rays are neighbours, as
 * the hybrid packets want them. The image's middle row and column have
 * direction components of both signs within a block. */
static size_t make_camera_rays(const lanes_scene *s, lanes_ray *rays, size_t side)
{
    float lo[3], hi[3], size;
    bounds(s, lo, hi, &size);
    float eye[3] = {0.5f * (lo[0] + hi[0]), 0.5f * (lo[1] + hi[1]), lo[2] - 1.5f * size};
    size_t n = 0;
    for (size_t by = 0; by < side; by += 4)
        for (size_t bx = 0; bx < side; bx += 4)
            for (size_t y = by; y < by + 4 && y < side; y++)
                for (size_t x = bx; x < bx + 4 && x < side; x++) {
                    float target[3] = {lo[0] + (hi[0] - lo[0]) * ((float)x + 0.5f) / (float)side,
                                       lo[1] + (hi[1] - lo[1]) * ((float)y + 0.5f) / (float)side,
                                       0.5f * (lo[2] + hi[2])};
                    lanes_ray *r = &rays[n++];
                    memset(r, 0, sizeof *r);
                    for (int a = 0; a < 3; a++) {
                        r->o[a] = eye[a];
                        r->d[a] = target[a] - eye[a];
                    }
                    r->tnear = 0.0f;
                    r->tfar = INFINITY;
                }
    return n;
}

static const char *const ray_kind_names[10] = {
    "random", "aimed", "aimed-tfar2", "at-vertex", "at-edge", "cut-short", "axis-parallel",
    "from-surface", "zero-component", "invalid"};

/* Kind of ray r of make_rays (for messages). */
static const char *ray_kind_of(size_t r, size_t n)
{
    return r + 3 >= n ? ray_kind_names[9] : ray_kind_names[r % 9];
}

/* A mix chosen to reach the traversals' corners: rays at random, aimed at
 * triangle interiors, vertices and edges (shared edges in the grid and the
 * sphere), cut short before their target or started beyond it, parallel to
 * the axes (infinite reciprocals: NaN slab distances at flat boxes),
 * starting on a surface, and invalid rays. */
static size_t make_rays(const lanes_scene *s, lanes_ray *rays, size_t n, harness_rng seed)
{
    float lo[3], hi[3], size;
    bounds(s, lo, hi, &size);
    size_t ntri = s->triangle_count;
    for (size_t i = 0; i < n; i++) {
        lanes_ray *r = &rays[i];
        float o[3], d[3], p[3];
        float tnear = 0.0f, tfar = INFINITY;
        size_t tri = (size_t)(harness_next(&seed) % ntri);
        int kind = (int)(i % 9);
        if (i + 3 >= n) kind = 9; /* the last few rays are invalid */
        double b1 = harness_uniform(&seed), b2 = harness_uniform(&seed);
        if (b1 + b2 > 1.0) b1 = 1.0 - b1, b2 = 1.0 - b2;
        switch (kind) {
        case 3: /* a vertex: (b1, b2) = (1, 0), (0, 1) or (0, 0) */
            b1 = (double)(harness_next(&seed) % 2);
            b2 = b1 > 0 ? 0.0 : (double)(harness_next(&seed) % 2);
            break;
        case 4: /* the midpoint of the edge v0-v1 or v1-v2 */
            b1 = 0.5, b2 = (double)(harness_next(&seed) % 2) * 0.5;
            break;
        default: break;
        }
        point_on(s, tri, b1, b2, p);
        for (int a = 0; a < 3; a++) o[a] = rndf(&seed, lo[a] - 0.5f * size, hi[a] + 0.5f * size);
        switch (kind) {
        case 0: /* random */
            random_dir(&seed, d);
            break;
        case 6: { /* parallel to an axis, through the target point */
            int ax = (int)(harness_next(&seed) % 3);
            float sg = harness_next(&seed) % 2 ? 1.0f : -1.0f;
            d[0] = d[1] = d[2] = 0.0f;
            d[ax] = sg;
            for (int a = 0; a < 3; a++) o[a] = p[a] - d[a] * size;
            break;
        }
        case 7: /* from a surface point outwards, tnear 0: the own triangle at t ~ 0 */
            random_dir(&seed, d);
            memcpy(o, p, sizeof o);
            break;
        case 8: /* a component that is zero (signed) or tiny */
            for (int a = 0; a < 3; a++) d[a] = p[a] - o[a];
            d[harness_next(&seed) % 3] = harness_next(&seed) % 2 ? -0.0f : 1e-30f;
            break;
        case 9: /* invalid */
            random_dir(&seed, d);
            if (i % 2) o[0] = NAN;
            else d[0] = d[1] = d[2] = 0.0f;
            break;
        default: /* 1..5: aimed at p */
            for (int a = 0; a < 3; a++) d[a] = p[a] - o[a];
            if (kind == 5) {
                float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                for (int a = 0; a < 3; a++) d[a] /= len;
                if (i % 2) tfar = 0.999f * len;
                else tnear = 1.001f * len;
            } else {
                tfar = kind == 2 ? 2.0f : INFINITY; /* d unnormalised: target at t = 1 */
            }
            break;
        }
        *r = (lanes_ray){{o[0], o[1], o[2]}, {d[0], d[1], d[2]}, {0, 0, 0}, tnear, tfar};
        lanes_ray_prepare(r);
    }
    return n;
}

/* ---- the brute-force comparison -------------------------------------------- */

enum { LEAF_SIZES = 3 };
static const int leaf_sizes[LEAF_SIZES] = {1, 4, 12};

static int width_slot(int w) { return w == 4 ? 0 : w == 8 ? 1 : 2; }


static void print_ray(const lanes_ray *r)
{
    printf("    ray o=(%.9g, %.9g, %.9g) d=(%.9g, %.9g, %.9g) t=[%.9g, %.9g]\n", r->o[0], r->o[1],
           r->o[2], r->d[0], r->d[1], r->d[2], r->tnear, r->tfar);
}

static void print_tri(const lanes_scene *s, size_t k)
{
    const float *v = s->verts + 9 * k;
    printf("    triangle %zu: (%.9g, %.9g, %.9g) (%.9g, %.9g, %.9g) (%.9g, %.9g, %.9g)\n", k, v[0],
           v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8]);
}

typedef struct {
    size_t rays, ties, grazing, other;
} dstats;

/* The double reference (tests/reference.h) against the float brute force
 * of one set: every difference must be explained by float rounding, which
 * the reference measures per triangle: a decision within REF_BAND of its
 * boundary (grazing an edge, t at an end of [tnear, tfar], nearly
 * parallel), a t within its forward-error bound, or two triangles at the
 * same t within that bound (a tie). Anything else is "other". */
static void check_double(const lanes_scene *s, const lanes_ray *rays, size_t n,
                         lanes_tri_algo algo, const long *brute, const float *brute_t, dstats *st)
{
    const int a = algo == LANES_TRI_MOLLER ? REF_MOLLER : REF_WATERTIGHT;
    /* forward error of t: c * u * tscale; c covers the dozen or so
     * roundings of either float test */
    const double c_u = 64.0 * 0x1p-24;
    for (size_t i = 0; i < n; i++) {
        const lanes_ray *r = &rays[i];
        ref_ray rr = {{r->o[0], r->o[1], r->o[2]}, {r->d[0], r->d[1], r->d[2]}, r->tnear, r->tfar};
        long best = -1;
        ref_tri_result rb;
        memset(&rb, 0, sizeof rb);
        for (size_t k = 0; k < s->triangle_count; k++) {
            const float *v = s->verts + 9 * k;
            ref_tri_result q = ref_tri(&rr, v, v + 3, v + 6);
            if (q.hit && (best < 0 || q.t < rb.t)) best = (long)k, rb = q;
        }
        st->rays++;
        ref_tri_result rf; /* the reference's view of the triangle the float test chose */
        memset(&rf, 0, sizeof rf);
        rf.margin[a] = INFINITY;
        if (brute[i] >= 0) {
            const float *v = s->verts + 9 * (size_t)brute[i];
            rf = ref_tri(&rr, v, v + 3, v + 6);
        }
        if (best == brute[i]) {
            if (best < 0 || fabs(brute_t[i] - rb.t) <= c_u * rb.tscale[a]) continue;
            /* a t this close to tnear or tfar that rounding decides it */
            if (rb.margin[a] < REF_BAND) {
                st->grazing++;
                continue;
            }
            st->other++;
        } else if (best >= 0 && brute[i] >= 0 && rf.hit &&
                   fabs(brute_t[i] - rb.t) <= c_u * fmax(rb.tscale[a], rf.tscale[a])) {
            st->ties++;
            continue;
        } else if (fmin(best >= 0 ? rb.margin[a] : INFINITY, rf.margin[a]) < REF_BAND) {
            st->grazing++;
            continue;
        } else {
            st->other++;
        }
        if (st->other <= 5) {
            printf("  double reference differs (other): ray %zu (%s): float brute force %ld "
                   "t=%.9g, double %ld t=%.9g (margins %.3g, %.3g; t error scale %.3g)\n",
                   i, ray_kind_of(i, n), brute[i], brute[i] >= 0 ? brute_t[i] : 0.0f, best,
                   best >= 0 ? rb.t : 0.0, best >= 0 ? rb.margin[a] : INFINITY, rf.margin[a],
                   best >= 0 ? rb.tscale[a] : 0.0);
            print_ray(r);
        }
    }
}

static bool build_bvhs(const lanes_scene *s, lanes_bvh2 bvh[LEAF_SIZES], lanes_wbvh wide[LEAF_SIZES][3])
{
    lanes_error err;
    for (int l = 0; l < LEAF_SIZES; l++) {
        lanes_bvh_build_options bo;
        lanes_bvh_default_options(&bo);
        bo.max_leaf_size = leaf_sizes[l];
        /* the largest leaves with the SAH by blocks of 8, as the wide builds
         * use: leaves spanning several blocks, padding lanes, full blocks */
        if (l == LEAF_SIZES - 1) bo.sah_block = 8;
        bo.threads = 1;
        if (lanes_bvh2_build(s, &bo, &bvh[l], &err) != LANES_OK) {
            printf("FAIL: BVH2 of %s: %s\n", s->name, err.message);
            return false;
        }
        for (int w = 0; w < 3; w++)
            if (lanes_wbvh_from_bvh2(&bvh[l], 4 << w, &wide[l][w], &err) != LANES_OK) {
                printf("FAIL: %d-wide BVH of %s: %s\n", 4 << w, s->name, err.message);
                return false;
            }
    }
    return true;
}

/* Where the ray meets the box of a triangle's vertices, in double. */
static void tri_box_interval(const lanes_ray *r, const lanes_triangles *t, size_t k, double *tin,
                             double *tout)
{
    const float *c[3][3] = {{t->v0x, t->v1x, t->v2x}, {t->v0y, t->v1y, t->v2y},
                            {t->v0z, t->v1z, t->v2z}};
    *tin = -INFINITY, *tout = INFINITY;
    for (int a = 0; a < 3; a++) {
        double lo = fmin(c[a][0][k], fmin(c[a][1][k], c[a][2][k]));
        double hi = fmax(c[a][0][k], fmax(c[a][1][k], c[a][2][k]));
        if (r->d[a] == 0.0f) {
            if (r->o[a] < lo || r->o[a] > hi) *tin = INFINITY, *tout = -INFINITY;
            continue;
        }
        double t1 = (lo - r->o[a]) / r->d[a], t2 = (hi - r->o[a]) / r->d[a];
        *tin = fmax(*tin, fmin(t1, t2));
        *tout = fmin(*tout, fmax(t1, t2));
    }
}

/* One triangle alone through the set's kernel: its t, u, v, or false. */
static bool one_tri(const lanes_kernels *k, lanes_tri_algo algo, const lanes_triangles *t, size_t i,
                    const lanes_ray *r, float *th, float *uh, float *vh)
{
    /* a view starting at element i: the arrays' padding covers a full vector */
    lanes_triangles one = {t->v0x + i, t->v0y + i, t->v0z + i, t->v1x + i, t->v1y + i,
                           t->v1z + i, t->v2x + i, t->v2y + i, t->v2z + i, 1, 1};
    return k->tri_wide_closest[algo](r, &one, 1, th, uh, vh, NULL) == 0;
}

typedef enum {
    V_SAME,          /* same triangle, same t, u, v bit for bit (or both miss) */
    V_TIE,           /* another triangle the kernel hits at exactly the same t */
    V_OUTSIDE_BOX,   /* the brute force's t puts the hit outside its triangle's box */
    V_BOX_EDGE,      /* fast and default modes: the hit lies on its box's boundary, up to
                        the rounding the unwidened slab test may lose it by */
    V_WRONG          /* a closest-hit traversal bug */
} verdict;

/* The traversal's closest hit h against the brute force's (prim b at bt,
 * bu, bv; b < 0: none). The one legitimate difference beyond ties: a float
 * t that places the hit outside the triangle's own bounding box (more than
 * the box test's 1 + 2 gamma(3) allows: a grazing ray or a nearly
 * degenerate triangle, where Möller's t is ill-conditioned) may be culled
 * by the box that holds it; the traversal must then still report a hit the
 * kernel really makes, no nearer than the brute force's. */
static verdict judge(const lanes_kernels *k, lanes_accuracy acc, const lanes_triangles *tris,
                     const lanes_ray *r, long b, float bt, float bu, float bv, const lanes_hit *h)
{
    const lanes_tri_algo algo = lanes_accuracy_precision(acc).algo;
    bool have = h->prim != LANES_NO_HIT;
    if (b < 0) return have ? V_WRONG : V_SAME;
    if (have && h->t == bt && h->prim == (uint32_t)b)
        return h->u == bu && h->v == bv ? V_SAME : V_WRONG;
    float t1, u1, v1;
    if (have && h->t == bt)
        return h->prim < tris->count && one_tri(k, algo, tris, h->prim, r, &t1, &u1, &v1) &&
                       t1 == bt
                   ? V_TIE
                   : V_WRONG;
    double tin, tout;
    tri_box_interval(r, tris, (size_t)b, &tin, &tout);
    const double slack = 4.0 * 0x1p-24;
    bool outside = bt < tin - slack * fabs(tin) || bt > tout + slack * fabs(tout);
    bool real = !have || (h->prim < tris->count && one_tri(k, algo, tris, h->prim, r, &t1, &u1, &v1) &&
                          t1 == h->t && u1 == h->u && v1 == h->v && h->t >= bt);
    if (outside && real) return V_OUTSIDE_BOX;
    /* Without Ize's widening a box whose boundary the hit lies on can be
     * lost by the slab test's three roundings (more with the fast mode's
     * approximate 1/d): the lost hits are the leaks of those modes. */
    const double edge = (acc == LANES_ACCURACY_FAST ? 16.0 : 4.0) * 0x1p-24;
    bool on_edge = fabs(bt - tin) <= edge * fabs(tin) || fabs(bt - tout) <= edge * fabs(tout);
    if (acc != LANES_ACCURACY_ROBUST && on_edge && real) return V_BOX_EDGE;
    return V_WRONG;
}

/* Any hit iff a closest hit exists: the brute force's, or, when its winner
 * may be culled (V_OUTSIDE_BOX, V_BOX_EDGE), the traversal's own. */
static bool occlusion_ok(verdict v, long b, const lanes_hit *h, bool occluded)
{
    if (occluded == (b >= 0)) return true;
    return (v == V_OUTSIDE_BOX || v == V_BOX_EDGE) && occluded == (h->prim != LANES_NO_HIT);
}

/* A traversal that visits in its own order: closest hits and occlusion of n
 * rays through the wide BVH, as trace_hybrid or trace_stream. */
typedef struct {
    const char *name;
    void (*trace)(const lanes_wbvh *, lanes_accuracy, const lanes_ray *, size_t, lanes_hit *,
                  lanes_trace_stats *);
    void (*occluded)(const lanes_wbvh *, lanes_accuracy, const lanes_ray *, size_t, uint8_t *,
                     lanes_trace_stats *);
} reordered;

/* "avx2/16": a set and the node width its table traverses. */
static const char *kname(const lanes_kernels *k)
{
    static char names[LANES_ISA_COUNT][3][32];
    char *n = names[k->isa][k->wide_width == 4 ? 0 : k->wide_width == 8 ? 1 : 2];
    snprintf(n, sizeof names[0][0], "%s/%d", k->name, k->wide_width);
    return n;
}

/* A reordering traversal (hybrid packets, streams) against trace_wide on the
 * same rays: the same t bit for bit, the same triangle (then also u, v bit
 * for bit), the same occlusion, except where the visiting order decides: a
 * tie between leaves (another triangle at exactly that t), or a hit whose
 * float t lies outside its triangle's box, or on its boundary, so that the
 * box is culled in one order and not in the other. Such a ray is judged by
 * the brute force as in brute_scene, both answers; *explained counts them. */
static void check_reordered(const lanes_kernels *k, reordered x, const lanes_wbvh *w, lanes_accuracy acc,
                            const lanes_triangles *tris, const lanes_ray *rays, size_t n, const char *what,
                            size_t *explained)
{
    lanes_hit *hw = malloc(n * sizeof *hw), *hh = malloc(n * sizeof *hh);
    uint8_t *ow = malloc(n), *oh = malloc(n);
    if (!hw || !hh || !ow || !oh) {
        harness_fail("out of memory");
        free(hw), free(hh), free(ow), free(oh);
        return;
    }
    const lanes_tri_algo algo = lanes_accuracy_precision(acc).algo;
    k->trace_wide(w, acc, rays, n, hw, NULL);
    k->occluded_wide(w, acc, rays, n, ow, NULL);
    x.trace(w, acc, rays, n, hh, NULL);
    x.occluded(w, acc, rays, n, oh, NULL);
    size_t bad = 0;
    for (size_t r = 0; r < n; r++) {
        bool same = memcmp(&hw[r].t, &hh[r].t, sizeof hw[r].t) == 0 && hw[r].prim == hh[r].prim &&
                    memcmp(&hw[r].u, &hh[r].u, sizeof hw[r].u) == 0 &&
                    memcmp(&hw[r].v, &hh[r].v, sizeof hw[r].v) == 0 && ow[r] == oh[r];
        if (same) continue;
        float bt = 0.0f, bu = 0.0f, bv = 0.0f;
        long b = k->tri_wide_closest[algo](&rays[r], tris, tris->count, &bt, &bu, &bv, NULL);
        verdict vw = judge(k, acc, tris, &rays[r], b, bt, bu, bv, &hw[r]);
        verdict vh = judge(k, acc, tris, &rays[r], b, bt, bu, bv, &hh[r]);
        bool ok = vw != V_WRONG && vh != V_WRONG && occlusion_ok(vw, b, &hw[r], ow[r] != 0) &&
                  occlusion_ok(vh, b, &hh[r], oh[r] != 0);
        if (ok) {
            (*explained)++;
        } else if (++bad <= 5) {
            harness_fail("%s %s %s: ray %zu: %s prim %d t=%.9g occluded %d, wide prim %d t=%.9g "
                         "occluded %d, brute force prim %ld t=%.9g",
                         what, kname(k), lanes_accuracy_name(acc), r, x.name,
                         hh[r].prim == LANES_NO_HIT ? -1 : (int)hh[r].prim, hh[r].t, oh[r],
                         hw[r].prim == LANES_NO_HIT ? -1 : (int)hw[r].prim, hw[r].t, ow[r], b, bt);
        }
    }
    if (bad > 5)
        harness_fail("%s %s %s: %s: %zu rays differ in all", what, kname(k), lanes_accuracy_name(acc), x.name, bad);
    free(hw), free(hh), free(ow), free(oh);
}

/* The streams: occlusion against occluded_wide, the same answer for every
 * ray bit for bit (each ray makes the same node and leaf tests with the
 * same tfar; only the order of leaves differs), and closest hits as
 * check_reordered, for the whole stream and for short ones (a lone ray,
 * part of one group, one more than a group), from the plain and the
 * counting copy, none written past its end. */
static void check_stream(const lanes_kernels *k, const lanes_wbvh *w, lanes_accuracy acc,
                         const lanes_triangles *tris, const lanes_ray *rays, size_t n, const char *what,
                         size_t *explained)
{
    uint8_t *ow = malloc(n + 1), *os = malloc(n + 1);
    lanes_hit *hs = malloc((n + 1) * sizeof *hs);
    if (!ow || !os || !hs) {
        harness_fail("out of memory");
        free(ow), free(os), free(hs);
        return;
    }
    k->occluded_wide(w, acc, rays, n, ow, NULL);
    const size_t lengths[] = {n, 1, 31, 33};
    for (size_t li = 0; li < sizeof lengths / sizeof lengths[0]; li++) {
        const size_t m = lengths[li] < n ? lengths[li] : n;
        check_reordered(k, (reordered){"stream", k->trace_stream, k->occluded_stream}, w, acc, tris, rays, m,
                        what, explained);
        for (int counted = 0; counted < 2; counted++) {
            lanes_trace_stats stats[2];
            memset(stats, 0, sizeof stats);
            memset(os, 0xcc, n + 1);
            memset(hs, 0xcc, (n + 1) * sizeof *hs);
            k->occluded_stream(w, acc, rays, m, os, counted ? &stats[0] : NULL);
            k->trace_stream(w, acc, rays, m, hs, counted ? &stats[1] : NULL);
            size_t bad = 0, first = 0;
            for (size_t r = 0; r < m; r++)
                if (os[r] != ow[r] && bad++ == 0) first = r;
            CHECK(bad == 0, "%s %s %s: occluded_stream of %zu rays (%s): %zu answers differ from "
                  "occluded_wide, the first ray %zu (stream %d, wide %d)", what, kname(k),
                  lanes_accuracy_name(acc), m, counted ? "counting" : "plain", bad, first,
                  os[first], ow[first]);
            const unsigned char *past = (const unsigned char *)&hs[m];
            CHECK(os[m] == 0xcc && past[0] == 0xcc && past[sizeof *hs - 1] == 0xcc,
                  "%s %s: a stream of %zu rays wrote past its end", what, kname(k), m);
            CHECK(!counted || (stats[0].rays == m && stats[1].rays == m),
                  "%s %s: the streams counted %llu and %llu rays of %zu", what, kname(k),
                  (unsigned long long)stats[0].rays, (unsigned long long)stats[1].rays, m);
        }
    }
    free(ow), free(os), free(hs);
}

static void brute_scene(const lanes_scene *s, size_t nrays)
{
    long fail0 = harness.failures;
    lanes_bvh2 bvh[LEAF_SIZES];
    lanes_wbvh wide[LEAF_SIZES][3];
    memset(bvh, 0, sizeof bvh);
    memset(wide, 0, sizeof wide);
    if (!build_bvhs(s, bvh, wide)) {
        harness_fail("%s: the BVHs did not build (see above)", s->name);
        return;
    }
    lanes_triangles tris;
    if (!lanes_triangles_alloc(&tris, s->triangle_count)) {
        harness_fail("out of memory");
        return;
    }
    for (size_t k = 0; k < s->triangle_count; k++) {
        const float *v = s->verts + 9 * k;
        tris.v0x[k] = v[0], tris.v0y[k] = v[1], tris.v0z[k] = v[2];
        tris.v1x[k] = v[3], tris.v1y[k] = v[4], tris.v1z[k] = v[5];
        tris.v2x[k] = v[6], tris.v2y[k] = v[7], tris.v2z[k] = v[8];
    }
    tris.count = s->triangle_count;

    lanes_ray *rays = malloc(nrays * sizeof *rays), *mode_rays = malloc(nrays * sizeof *mode_rays);
    lanes_hit *hits = malloc(nrays * sizeof *hits), *hits2 = malloc(nrays * sizeof *hits2);
    uint8_t *occ = malloc(nrays), *occ2 = malloc(nrays);
    long *brute = malloc(nrays * sizeof *brute);
    float *bt = malloc(nrays * sizeof *bt), *bu = malloc(nrays * sizeof *bu),
          *bv = malloc(nrays * sizeof *bv);
    make_rays(s, rays, nrays, harness_rng_seed(0xabcdef + s->triangle_count));
    enum { CAM_SIDE = 64 };
    lanes_ray *cam = malloc(CAM_SIDE * CAM_SIDE * sizeof *cam), *cam_mode = malloc(CAM_SIDE * CAM_SIDE * sizeof *cam);
    size_t ncam = cam ? make_camera_rays(s, cam, CAM_SIDE) : 0;

    size_t ties = 0, outside = 0, edges = 0, hits_total = 0, checks = 0, by_kind[10] = {0};
    /* hybrid or stream and wide differ where the visiting order decides */
    size_t hybrid_order = 0, stream_order = 0;
    dstats ds = {0, 0, 0, 0};
    for (int i = 0; i < LANES_ISA_COUNT * 3; i++) {
        /* every set at every node width it traverses */
        lanes_isa isa = (lanes_isa)(i / 3);
        if (!lanes_isa_supported(isa)) continue;
        const lanes_kernels *k = lanes_kernels_for_width(isa, 4 << i % 3);
        if (!k) continue;
        const bool own_width = k == lanes_kernels_for(isa);
        for (int m = 0; m < LANES_ACCURACY_COUNT; m++) {
            const lanes_accuracy acc = (lanes_accuracy)m;
            const lanes_tri_algo algo = lanes_accuracy_precision(acc).algo;
            /* the traversal's rays carry the mode's reciprocals */
            for (size_t r = 0; r < nrays; r++) {
                mode_rays[r] = rays[r];
                lanes_ray_prepare_rcp(&mode_rays[r], lanes_accuracy_precision(acc).rcp);
            }
            for (size_t r = 0; r < nrays; r++) {
                bt[r] = bu[r] = bv[r] = 0.0f;
                brute[r] = k->tri_wide_closest[algo](&rays[r], &tris, tris.count, &bt[r], &bu[r],
                                                     &bv[r], NULL);
                hits_total += brute[r] >= 0;
            }
            /* the double reference checks the brute force once per algorithm
             * (Möller: the same formula; watertight: same decisions away
             * from edges) */
            if (isa == LANES_ISA_SCALAR && own_width && acc != LANES_ACCURACY_FAST)
                check_double(s, rays, nrays, algo, brute, bt, &ds);

            for (int l = 0; l < LEAF_SIZES; l++) {
                const lanes_wbvh *w = &wide[l][width_slot(k->wide_width)];
                for (int scheme = 0; scheme < 4; scheme++) {
                    static const char *const scheme_names[] = {"wide", "bvh2", "hybrid", "stream"};
                    const char *sn = scheme_names[scheme];
                    if (scheme == 1 && !own_width) continue; /* the BVH2 has no node width */
                    lanes_trace_stats stats;
                    memset(&stats, 0, sizeof stats);
                    if (scheme == 3) {
                        k->trace_stream(w, acc, mode_rays, nrays, hits, NULL);
                        k->trace_stream(w, acc, mode_rays, nrays, hits2, &stats);
                        k->occluded_stream(w, acc, mode_rays, nrays, occ, NULL);
                        k->occluded_stream(w, acc, mode_rays, nrays, occ2, &stats);
                    } else if (scheme == 2) {
                        k->trace_hybrid(w, acc, mode_rays, nrays, hits, NULL);
                        k->trace_hybrid(w, acc, mode_rays, nrays, hits2, &stats);
                        k->occluded_hybrid(w, acc, mode_rays, nrays, occ, NULL);
                        k->occluded_hybrid(w, acc, mode_rays, nrays, occ2, &stats);
                    } else if (scheme) {
                        k->trace_bvh2(&bvh[l], acc, mode_rays, nrays, hits, NULL);
                        k->trace_bvh2(&bvh[l], acc, mode_rays, nrays, hits2, &stats);
                        k->occluded_bvh2(&bvh[l], acc, mode_rays, nrays, occ, NULL);
                        k->occluded_bvh2(&bvh[l], acc, mode_rays, nrays, occ2, &stats);
                    } else {
                        k->trace_wide(w, acc, mode_rays, nrays, hits, NULL);
                        k->trace_wide(w, acc, mode_rays, nrays, hits2, &stats);
                        k->occluded_wide(w, acc, mode_rays, nrays, occ, NULL);
                        k->occluded_wide(w, acc, mode_rays, nrays, occ2, &stats);
                    }
                    CHECK(stats.rays == 2 * nrays, "%s %s %s: stats.rays %llu, expected %zu",
                          s->name, kname(k), sn, (unsigned long long)stats.rays, 2 * nrays);
                    for (size_t r = 0; r < nrays; r++) {
                        checks++;
                        const lanes_hit *h = &hits[r];
                        CHECK(memcmp(&hits[r], &hits2[r], sizeof *h) == 0 && occ[r] == occ2[r],
                              "%s %s %s %s leaf %d ray %zu: the counting copy answers differently",
                              s->name, kname(k), lanes_accuracy_name(acc), sn, leaf_sizes[l], r);
                        bool exists = brute[r] >= 0;
                        verdict vd = judge(k, acc, &tris, &mode_rays[r], brute[r], bt[r], bu[r], bv[r], h);
                        bool occ_ok = occlusion_ok(vd, brute[r], h, occ[r] != 0);
                        ties += vd == V_TIE;
                        outside += vd == V_OUTSIDE_BOX;
                        edges += vd == V_BOX_EDGE;
                        bool ok = vd != V_WRONG && occ_ok;
                        if (!ok) by_kind[r + 3 >= nrays ? 9 : r % 9]++;
                        CHECK(occ_ok,
                              "%s %s %s occluded_%s leaf %d ray %zu (%s): occluded %d, brute force %s",
                              s->name, kname(k), lanes_accuracy_name(acc), sn, leaf_sizes[l], r,
                              ray_kind_of(r, nrays), occ[r], exists ? "hits" : "misses");
                        CHECK(vd != V_WRONG,
                              "%s %s %s trace_%s leaf %d ray %zu (%s): prim %d t=%.9g u=%.9g "
                              "v=%.9g; brute force prim %ld t=%.9g u=%.9g v=%.9g",
                              s->name, kname(k), lanes_accuracy_name(acc), sn, leaf_sizes[l], r,
                              ray_kind_of(r, nrays), h->prim == LANES_NO_HIT ? -1 : (int)h->prim,
                              h->t, h->u, h->v, brute[r], exists ? bt[r] : 0.0f,
                              exists ? bu[r] : 0.0f, exists ? bv[r] : 0.0f);
                        if (!ok && harness.failures - fail0 <= 10) {
                            print_ray(&rays[r]);
                            if (exists) print_tri(s, (size_t)brute[r]);
                            if (h->prim < s->triangle_count) print_tri(s, h->prim);
                        }
                    }
                }
                const reordered hybrid = {"hybrid", k->trace_hybrid, k->occluded_hybrid};
                check_reordered(k, hybrid, w, acc, &tris, mode_rays, nrays, s->name, &hybrid_order);
                check_stream(k, w, acc, &tris, mode_rays, nrays, s->name, &stream_order);
                for (size_t r = 0; r < ncam; r++) {
                    cam_mode[r] = cam[r];
                    lanes_ray_prepare_rcp(&cam_mode[r], lanes_accuracy_precision(acc).rcp);
                }
                check_reordered(k, hybrid, w, acc, &tris, cam_mode, ncam, "camera rays", &hybrid_order);
                check_stream(k, w, acc, &tris, cam_mode, ncam, "camera rays", &stream_order);
            }
        }
    }
    printf("%-8s %6zu triangles, %zu rays: %zu traversal results checked, %zu closest hits in "
           "the brute force, %zu ties resolved to another triangle at the same t, %zu where the "
           "brute force's t lies outside its triangle's box, %zu lost on a box boundary (fast and "
           "default modes), %zu and %zu where the hybrid packets and the streams differ from "
           "trace_wide by the visiting order; double "
           "reference (both algorithms): %zu differ (%zu ties, %zu in the rounding band, %zu "
           "other) -> %s\n",
           s->name, s->triangle_count, nrays, checks, hits_total, ties, outside, edges, hybrid_order,
           stream_order, ds.ties + ds.grazing + ds.other, ds.ties, ds.grazing, ds.other,
           harness.failures == fail0 && ds.other == 0 ? "ok" : "FAIL");
    if (harness.failures != fail0) {
        printf("  traversal results that differ from the brute force, by kind of ray:");
        for (int kk = 0; kk < 10; kk++)
            if (by_kind[kk]) printf(" %s %zu", ray_kind_names[kk], by_kind[kk]);
        printf("\n");
    }
    /* Differences the double reference cannot explain are failures, and so
     * is a band that grows beyond its expected rarity. */
    CHECK(ds.other == 0, "%s: %zu differences from the double reference unexplained", s->name,
          ds.other);

    free(rays), free(mode_rays), free(hits), free(hits2), free(occ), free(occ2), free(brute), free(bt), free(bu), free(bv);
    free(cam), free(cam_mode);
    lanes_triangles_free(&tris);
    for (int l = 0; l < LEAF_SIZES; l++) {
        for (int w = 0; w < 3; w++) lanes_wbvh_free(&wide[l][w]);
        lanes_bvh2_free(&bvh[l]);
    }
}

static int run_brute(const char *which)
{
    bool all = strcmp(which, "all") == 0;
    bool any = false;
    lanes_scene s;
    if (all || strcmp(which, "random") == 0) {
        scene_random(&s), brute_scene(&s, 6000), lanes_scene_free(&s), any = true;
    }
    if (all || strcmp(which, "sphere") == 0) {
        scene_sphere(&s), brute_scene(&s, 6000), lanes_scene_free(&s), any = true;
    }
    if (all || strcmp(which, "grid") == 0) {
        scene_grid(&s), brute_scene(&s, 6000), lanes_scene_free(&s), any = true;
    }
    if (all || strcmp(which, "tiny") == 0) {
        const int counts[] = {1, 2, 3, 5, 17};
        for (size_t i = 0; i < sizeof counts / sizeof counts[0]; i++)
            scene_tiny(&s, counts[i]), brute_scene(&s, 900), lanes_scene_free(&s);
        any = true;
    }
    if (all || strcmp(which, "default") == 0) {
        lanes_error err;
        memset(&err, 0, sizeof err);
        lanes_scene_init(&s);
        if (lanes_scene_load("default", &s, &err) != LANES_OK) {
            harness_fail("cannot load the default scene: %s", err.message);
        } else {
            /* brute force costs rays x triangles per set and algorithm */
            size_t n = (size_t)(2e7 / (double)(s.triangle_count + 1));
            brute_scene(&s, n < 500 ? 500 : n > 3000 ? 3000 : n);
        }
        lanes_scene_free(&s);
        any = true;
    }
    if (!any) {
        printf("unknown scene '%s' (random, sphere, grid, tiny, default, all)\n", which);
        return 2;
    }
    return harness_summary("test_traversal brute");
}

/* ---- against Embree on real meshes ----------------------------------------- */

static lanes_ray ray_of(vec3 o, vec3 d, float tnear, float tfar)
{
    lanes_ray r = {{o.x, o.y, o.z}, {d.x, d.y, d.z}, {0, 0, 0}, tnear, tfar};
    lanes_ray_prepare(&r);
    return r;
}

typedef struct {
    const char *kind;
    lanes_ray *rays;
    size_t n;
    bool occlusion;
} ray_set;

static bool file_exists(const char *p)
{
    struct stat st;
    return stat(p, &st) == 0;
}

static judge_answer answer_of(judge_test test, bool occlusion, const lanes_hit *h, uint8_t occluded)
{
    judge_answer a = {.test = test, .occlusion = occlusion, .occluded = occluded != 0};
    if (!occlusion) a.prim = h->prim, a.t = h->t;
    return a;
}

/* The judge must be able to fail: Embree's answers made wrong on purpose
 * (a hit dropped, a miss turned into a hit on some triangle, t moved by
 * 1e-3, an occlusion flipped) are judged wrong, all but the few that lie
 * within the float test's rounding of the truth (grazes, which either
 * answer may give). At most `cap` rays of each set, spread over it. */
static void check_judge_fails(const hits_judge *j, const lanes_scene *s, const ray_set *rs,
                              const lanes_hit *eh, const uint8_t *eo, size_t cap)
{
    size_t tried[3] = {0, 0, 0}, wrong[3] = {0, 0, 0}, unchanged_wrong = 0, seen = 0;
    harness_rng rng = {7};
    size_t step = rs->n > cap ? rs->n / cap : 1;
    for (size_t r = 0; r < rs->n && seen < cap; r += step, seen++) {
        judge_answer a = answer_of(JUDGE_MOLLER, rs->occlusion, &eh[r], eo ? eo[r] : 0);
        unchanged_wrong += hits_judge_wrong(j, &rs->rays[r], &a);
        judge_answer b = a;
        int kind;
        if (rs->occlusion) {
            b.occluded = !a.occluded;
            kind = a.occluded ? 0 : 1;
        } else if (a.prim == LANES_NO_HIT) {
            b.prim = (uint32_t)(harness_uniform(&rng) * (double)s->triangle_count) % (uint32_t)s->triangle_count;
            b.t = 1.0f;
            kind = 1;
        } else if (seen % 2) {
            b.prim = LANES_NO_HIT;
            kind = 0;
        } else {
            b.t = a.t * (1.0f + 1e-3f);
            kind = 2;
        }
        tried[kind]++;
        wrong[kind] += hits_judge_wrong(j, &rs->rays[r], &b);
    }
    static const char *const what[3] = {"hit dropped", "hit invented", "t moved by 1e-3"};
    printf("judge on %s rays: %zu of %zu of Embree's answers wrong;", rs->kind, unchanged_wrong, seen);
    for (int k = 0; k < 3; k++)
        if (tried[k]) printf(" %s: %zu of %zu wrong;", what[k], wrong[k], tried[k]);
    printf("\n");
    for (int k = 0; k < 3; k++)
        CHECK(wrong[k] >= tried[k] - tried[k] / 100, "judge on %s rays: only %zu of %zu answers with the %s "
              "judged wrong", rs->kind, wrong[k], tried[k], what[k]);
}

static int run_embree(const char *name, long nrays, double scale, double translate)
{
    lanes_scene s;
    lanes_error err;
    memset(&err, 0, sizeof err);
    /* "bunny" is the CGAL mesh file itself (framed by the loader); other
     * names are scenes, built-in or files. Missing meshes are a skip: they
     * come from cmake/fetch_meshes.sh, not from the repository. */
    char path[1024];
    const char *spec = name;
    if (strcmp(name, "bunny") == 0) {
        snprintf(path, sizeof path, "%s/bunny00.off", lanes_mesh_dir());
        if (!file_exists(path)) {
            printf("SKIP: %s not found (run cmake/fetch_meshes.sh or set LANES_MESH_DIR)\n", path);
            return SKIP;
        }
        spec = path;
    } else {
        for (size_t i = 0; i < lanes_builtin_scene_count(); i++) {
            const lanes_builtin_info *in = lanes_builtin_scene_info(i);
            if (strcmp(in->name, name) == 0 && in->needs_meshes && !lanes_builtin_meshes_available()) {
                printf("SKIP: scene %s needs the meshes in %s (run cmake/fetch_meshes.sh or set "
                       "LANES_MESH_DIR)\n", name, lanes_mesh_dir());
                return SKIP;
            }
        }
    }
    if (lanes_scene_load(spec, &s, &err) != LANES_OK ||
        lanes_scene_scale_translate(&s, scale, translate, &err) != LANES_OK) {
        printf("FAIL: %s\n", err.message);
        return 1;
    }
    /* Where nothing moved the scene, most rays are far from rounding's
     * reach and the engines agree; elsewhere only the verdicts count. */
    const bool moved = scale != 1.0 || translate != 0.0;
    lanes_embree *emb;
    if (lanes_embree_create(&s, lanes_embree_isa_best(), 0, &emb, &err) != LANES_OK) {
        printf("FAIL: %s\n", err.message);
        lanes_scene_free(&s);
        return 1;
    }
    lanes_bvh2 bvh;
    lanes_wbvh wide[3];
    memset(wide, 0, sizeof wide);
    lanes_bvh_build_options bo;
    lanes_bvh_default_options(&bo);
    hits_judge judge;
    if (lanes_bvh2_build(&s, &bo, &bvh, &err) != LANES_OK || hits_judge_init(&judge, &s, &bvh, true, &err) != LANES_OK) {
        printf("FAIL: %s\n", err.message);
        return 1;
    }
    for (int w = 0; w < 3; w++)
        if (lanes_wbvh_from_bvh2(&bvh, 4 << w, &wide[w], &err) != LANES_OK) {
            printf("FAIL: %s\n", err.message);
            return 1;
        }
    printf("scene %s: %zu triangles, scaled by %g and moved by %g; Embree %s, ISA %s\n", name,
           s.triangle_count, scale, translate, RTC_VERSION_STRING, lanes_embree_isa_name(lanes_embree_isa_best()));

    /* rays: camera rays, then shadow and diffuse rays from Embree's hits
     * (the engine under comparison does not choose its own inputs) */
    int w = (int)lround(sqrt((double)nrays)), h = w;
    const lanes_camera *c = &s.camera;
    lanes_view view = lanes_view_make(c, w, h);
    size_t np = (size_t)w * (size_t)h;
    lanes_ray *primary = malloc(np * sizeof *primary);
    lanes_ray *shadow = malloc(np * sizeof *shadow);
    lanes_ray *diffuse = malloc(np * sizeof *diffuse);
    lanes_hit *eh = malloc(np * sizeof *eh), *lh = malloc(np * sizeof *lh);
    uint8_t *eo = malloc(np), *lo_ = malloc(np);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            primary[(size_t)y * w + x] =
                ray_of(view.eye, v3_normalize(lanes_view_dir(&view, (float)x + 0.5f, (float)y + 0.5f)), 0.0f, INFINITY);
        }
    lanes_embree_trace1(emb, primary, np, eh);
    float blo[3], bhi[3];
    lanes_scene_bounds(&s, blo, bhi);
    vec3 diag = v3_sub(v3_load(bhi), v3_load(blo));
    float eps = lanes_scene_epsilon(&s);
    vec3 light = s.point_light_count ? v3_load(s.point_lights[0].position)
                                     : v3_add(v3_scale(v3_add(v3_load(blo), v3_load(bhi)), 0.5f),
                                           v3_scale(v3_normalize(v3_load(c->up)), sqrtf(v3_dot(diag, diag))));
    size_t ns = 0, nd = 0;
    harness_rng seed = {42};
    for (size_t i = 0; i < np; i++) {
        if (eh[i].prim == LANES_NO_HIT) continue;
        const float *v = s.verts + 9 * (size_t)eh[i].prim;
        vec3 v0 = v3_load(v), e1 = v3_sub(v3_load(v + 3), v0), e2 = v3_sub(v3_load(v + 6), v0);
        vec3 p = v3_add(v0, v3_add(v3_scale(e1, eh[i].u), v3_scale(e2, eh[i].v)));
        vec3 n = v3_normalize(v3_cross(e1, e2));
        if (v3_dot(n, v3_load(primary[i].d)) > 0) n = v3_scale(n, -1.0f);
        vec3 o = v3_add(p, v3_scale(n, eps));
        vec3 to = v3_sub(light, o);
        float dist = sqrtf(v3_dot(to, to));
        if (dist > 0 && v3_dot(to, n) > 0) shadow[ns++] = ray_of(o, v3_scale(to, 1.0f / dist), 0.0f, dist * (1.0f - 1e-4f));
        float r1 = (float)harness_uniform(&seed), r2 = (float)harness_uniform(&seed);
        vec3 a = fabsf(n.x) > 0.9f ? v3(0, 1, 0) : v3(1, 0, 0);
        vec3 nx = v3_normalize(v3_cross(a, n)), ny = v3_cross(n, nx);
        float phi = 6.2831853f * r1, rr = sqrtf(r2);
        vec3 d = v3_add(v3_add(v3_scale(nx, rr * cosf(phi)), v3_scale(ny, rr * sinf(phi))),
                     v3_scale(n, sqrtf(fmaxf(0.0f, 1.0f - r2))));
        diffuse[nd++] = ray_of(o, v3_normalize(d), 0.0f, INFINITY);
    }
    ray_set sets[3] = {{"primary", primary, np, false}, {"shadow", shadow, ns, true},
                       {"diffuse", diffuse, nd, false}};

    /* The adapter's layouts: every packet and stream API, with either
     * context, answers what rtcIntersect1/rtcOccluded1 answer (ray k*W+j is
     * lane j of packet k; the tail packet is masked). Where the scene moved,
     * rounding decides more rays, and only the judge's verdicts count. */
    for (int si = 0; si < 3; si++) {
        ray_set *rs = &sets[si];
        if (rs->occlusion)
            lanes_embree_occluded1(emb, rs->rays, rs->n, eo);
        else
            lanes_embree_trace1(emb, rs->rays, rs->n, eh);
        /* On a moved scene secondary rays start within rounding of their
         * own surface (the scene epsilon is below the coordinates' ulp),
         * where a blocker at t ~ 0 is as acceptable as none: only camera
         * rays can tell the judge's verdicts there */
        if (!moved || si == 0) check_judge_fails(&judge, &s, rs, eh, rs->occlusion ? eo : NULL, 4000);
        if (moved) continue;
        int apis = 0;
        size_t least = rs->n;
        for (int m = 0; m < LANES_EMBREE_METHOD_COUNT; m++) {
            if (!lanes_embree_supports(emb, (lanes_embree_method)m)) continue;
            lanes_embree_batch b;
            if (lanes_embree_batch_init(&b, (lanes_embree_method)m, rs->occlusion, rs->rays, rs->n, &err) !=
                LANES_OK) {
                printf("FAIL: %s\n", err.message);
                return 1;
            }
            for (int coherent = 0; coherent < 2; coherent++) {
                lanes_embree_batch_reset(&b);
                unsigned csr = lanes_fp_fast_enter();
                /* in ranges, as the benchmark's threads take them */
                for (size_t at = 0; at < rs->n; at += 4096)
                    lanes_embree_batch_trace(emb, &b, at, at + 4096, coherent != 0);
                lanes_fp_restore(csr);
                size_t same = 0;
                if (rs->occlusion) {
                    lanes_embree_batch_occluded(&b, lo_);
                    for (size_t r = 0; r < rs->n; r++) same += (lo_[r] != 0) == (eo[r] != 0);
                } else {
                    lanes_embree_batch_hits(&b, lh);
                    for (size_t r = 0; r < rs->n; r++) same += hits_same(&lh[r], &eh[r]);
                }
                CHECK(same >= rs->n - rs->n / 10000 && !lanes_embree_error(emb)[0],
                      "embree %s%s on %zu %s rays: only %zu agree with the single-ray call %s",
                      lanes_embree_method_name((lanes_embree_method)m, rs->occlusion),
                      coherent ? "+coherent" : "", rs->n, rs->kind, same, lanes_embree_error(emb));
                apis++;
                least = same < least ? same : least;
            }
            lanes_embree_batch_free(&b);
        }
        printf("embree: %d API/context combinations on %zu %s rays: at least %zu agree with "
               "the single-ray call\n", apis, rs->n, rs->kind, least);
    }

    /* lanes against Embree, in default mode (Möller–Trumbore, as Embree)
     * and in robust mode (watertight), every set, both schemes: every
     * difference judged. Robust mode must never be wrong; default mode's
     * verdicts are reported (its boxes are not widened, so a box's rounding
     * can lose a hit that its triangle test would find). */
    static const lanes_accuracy modes[2] = {LANES_ACCURACY_DEFAULT, LANES_ACCURACY_ROBUST};
    judge_cache caches[3];
    for (int si = 0; si < 3; si++)
        if (!judge_cache_init(&caches[si], sets[si].rays, sets[si].n)) {
            printf("FAIL: out of memory\n");
            return 1;
        }
    for (int mi = 0; mi < 2; mi++) {
        const lanes_accuracy mode = modes[mi];
        for (int i = 0; i < LANES_ISA_COUNT; i++) {
            lanes_isa isa = (lanes_isa)i;
            if (!lanes_isa_supported(isa)) continue;
            const lanes_kernels *k = lanes_kernels_for(isa);
            for (int scheme = 0; scheme < 2; scheme++) {
                for (int si = 0; si < 3; si++) {
                    ray_set *rs = &sets[si];
                    judge_cache *jc = &caches[si];
                    size_t n = rs->n, agree = 0;
                    hits_verdicts v = {0, 0, 0};
                    const lanes_wbvh *wb = &wide[width_slot(k->wide_width)];
                    if (rs->occlusion) {
                        lanes_embree_occluded1(emb, rs->rays, n, eo);
                        if (scheme)
                            k->occluded_bvh2(&bvh, mode, rs->rays, n, lo_, NULL);
                        else
                            k->occluded_wide(wb, mode, rs->rays, n, lo_, NULL);
                    } else {
                        lanes_embree_trace1(emb, rs->rays, n, eh);
                        if (scheme)
                            k->trace_bvh2(&bvh, mode, rs->rays, n, lh, NULL);
                        else
                            k->trace_wide(wb, mode, rs->rays, n, lh, NULL);
                    }
                    int printed = 0;
                    for (size_t r = 0; r < n; r++) {
                        bool ok = rs->occlusion ? (eo[r] != 0) == (lo_[r] != 0) : hits_same(&lh[r], &eh[r]);
                        if (ok) {
                            agree++;
                            continue;
                        }
                        judge_answer la = answer_of(judge_test_of(mode), rs->occlusion, &lh[r], lo_[r]);
                        judge_answer ea = answer_of(JUDGE_MOLLER, rs->occlusion, &eh[r], eo[r]);
                        size_t was = v.lanes_wrong;
                        hits_judge_pair(&judge, jc, r, &la, &ea, &v);
                        if (v.lanes_wrong > was && printed++ < 10) {
                            printf("  %s %s %s %s ray %zu: lanes wrong: lanes prim %d t=%.9g%s, embree prim %d "
                                   "t=%.9g%s\n", kname(k), lanes_accuracy_name(mode), scheme ? "single" : "wide",
                                   rs->kind, r, la.prim == LANES_NO_HIT ? -1 : (int)la.prim, la.t,
                                   rs->occlusion ? (la.occluded ? " occluded" : " clear") : "",
                                   ea.prim == LANES_NO_HIT ? -1 : (int)ea.prim, ea.t,
                                   rs->occlusion ? (ea.occluded ? " occluded" : " clear") : "");
                            print_ray(&rs->rays[r]);
                        }
                    }
                    double frac = n ? (double)agree / (double)n : 1.0;
                    bool pass_agree = moved || mode == LANES_ACCURACY_ROBUST || frac >= 0.9999;
                    bool pass_judge = mode != LANES_ACCURACY_ROBUST || v.lanes_wrong == 0;
                    printf("%-10s %-7s %-6s %-8s %7zu rays: agreement %.4f%% (%zu lanes wrong, %zu Embree "
                           "wrong, %zu both acceptable) %s\n",
                           kname(k), lanes_accuracy_name(mode), scheme ? "single" : "wide", rs->kind, n,
                           100.0 * frac, v.lanes_wrong, v.embree_wrong, v.both_acceptable,
                           pass_agree && pass_judge ? "ok" : "FAIL");
                    CHECK(pass_agree, "%s %s %s %s: agreement with Embree below 99.99%%", kname(k),
                          lanes_accuracy_name(mode), scheme ? "single" : "wide", rs->kind);
                    CHECK(pass_judge, "%s %s %s %s: lanes wrong on %zu rays in robust mode", kname(k),
                          lanes_accuracy_name(mode), scheme ? "single" : "wide", rs->kind, v.lanes_wrong);
                }
            }
        }
    }
    free(primary), free(shadow), free(diffuse), free(eh), free(lh), free(eo), free(lo_);
    for (int i = 0; i < 3; i++) lanes_wbvh_free(&wide[i]), judge_cache_free(&caches[i]);
    hits_judge_free(&judge);
    lanes_bvh2_free(&bvh);
    lanes_embree_destroy(emb);
    lanes_scene_free(&s);
    return harness_summary("test_traversal embree");
}

int main(int argc, char **argv)
{
    setvbuf(stdout, NULL, _IOLBF, 0);
    if (getenv("TEST_MAX_PRINT")) harness.max_print = atoi(getenv("TEST_MAX_PRINT"));
    char features[512];
    lanes_cpu_feature_list(lanes_cpu()->bits, features, sizeof features);
    printf("cpu: %s\nfeatures: %s\nsets:", lanes_cpu()->brand, features);
    for (int i = 0; i < LANES_ISA_COUNT; i++)
        if (lanes_isa_supported((lanes_isa)i)) printf(" %s", lanes_isa_name((lanes_isa)i));
    printf("\n");
    if (argc >= 2 && strcmp(argv[1], "brute") == 0) return run_brute(argc >= 3 ? argv[2] : "all");
    if (argc >= 3 && strcmp(argv[1], "embree") == 0) {
        long n = 512 * 512;
        double scale = 1.0, translate = 0.0;
        for (int i = 3; i + 1 < argc; i += 2) {
            if (strcmp(argv[i], "--rays") == 0) n = atol(argv[i + 1]);
            else if (strcmp(argv[i], "--scale") == 0) scale = atof(argv[i + 1]);
            else if (strcmp(argv[i], "--translate") == 0) translate = atof(argv[i + 1]);
        }
        if (n < 1) n = 1;
        return run_embree(argv[2], n, scale, translate);
    }
    printf("usage: test_traversal brute [random|sphere|grid|tiny|default|all]\n"
           "       test_traversal embree SCENE [--rays N] [--scale S] [--translate T]\n");
    return 2;
}
