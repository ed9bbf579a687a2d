/* Numerical extremes against exact, hand-derived expectations, at every
 * kernel set this CPU runs and in every accuracy mode.
 *
 * The cases are data (box_cases, tri_cases, injections below): a ray, one
 * primitive, and per mode whether it is hit and, where it is, the exact t
 * (and u, v). Every expectation is derived in the comment beside it from
 * the conventions in trace/kernels.h: rays are o + t*d on the closed
 * interval [tnear, tfar], boxes are closed and empty when min > max on an
 * axis, invalid rays (NaN or Inf in o or d, NaN ends, d = 0) never hit, and
 * a kernel writes t/u/v only for hits and nothing past its count.
 *
 * A mode reaches the kernels through lanes_accuracy_precision(): rays are
 * prepared with its reciprocal (rays_prepare for SoA rays,
 * lanes_ray_prepare_rcp for single rays), triangles are tested with its
 * algorithm, and the traversals take the mode itself. Each case runs
 * through every path it applies to:
 *   boxes:      box_packet and box_partition (a packet of rays against the
 *               box, by position and through a reversed index list, and the
 *               partition in place), box_wide (the ray against N boxes),
 *               frustum_boxes (it may only cull what no ray hits);
 *   triangles:  tri_packet, tri_packet_any, tri_wide, tri_wide_closest,
 *               tri_wide_any, frustum_tris, and on a tiny scene of the case's
 *               triangle and two far-away fillers, with BVH leaves of 1 and
 *               4 triangles: trace_wide, occluded_wide, trace_bvh2,
 *               occluded_bvh2 and trace_packet (partition, ranged, and
 *               partition with the packet frustum, corner test and leaf
 *               frusta), closest hit and occlusion.
 * The case sits at lane positions that vary (first, middle, last, both
 * sides of a 32-bit mask word) in counts of 1, W-1, W, W+1 and 37, where W
 * is the set's width; the other lanes hold ordinary rays (or primitives)
 * whose results are checked too, and the elements past the count hold
 * copies that would hit if a kernel forgot its mask. Outputs are filled
 * with sentinels first, so a write for a miss or past the count shows.
 *
 * The set-up itself is checked on every lane: rays_prepare and
 * lanes_ray_prepare_rcp must turn exactly the invalid rays into [+inf, -inf]
 * and clamp infinite ends of the others to ∓FLT_MAX.
 *
 * Fast mode's reciprocal is an estimate: a box distance that passes
 * through 1/d is compared within FAST_ULPS there and exactly otherwise.
 * Hit or miss must hold exactly in every mode; the few boundary cases that
 * legitimately differ between modes say so, and why, beside their data.
 *
 *   test_extremes [--all]   (--all prints every failing placement, not
 *                            one line per failing check) */
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "build/bvh.h"
#include "build/scene.h"
#include "simd/isa.h"
#include "trace/kernels.h"

/* ======================================================================== */
/* Expectations                                                             */
/* ======================================================================== */

/* SAME (0) in a traversal expectation means "as the triangle kernels". */
enum { SAME = 0, MISS = 1, HIT = 2, EITHER = 3 };
#define ALL(x) {x, x, x}
/* per mode, in lanes_accuracy order: fast, default, robust */
#define MODES(fast, dflt, robust) {fast, dflt, robust}
#define KERNELS {SAME, SAME, SAME}

/* Box distances from fast mode's reciprocal (estimate plus one Newton step,
 * relative error under 3u) may differ from the exact ones by this much. */
#define FAST_ULPS 4

typedef struct {
    float o[3], d[3], tnear, tfar;
} xray;

typedef struct {
    const char *name;
    xray r;
    lanes_box box;
    unsigned char hit[LANES_ACCURACY_COUNT];
    float t;  /* tentry = max(tnear, entry) of a hit; NAN: not checked */
    bool rcp; /* t is a slab distance, computed through 1/d */
} box_case;

typedef struct {
    const char *name;
    xray r;
    lanes_triangle tri;
    unsigned char hit[LANES_ACCURACY_COUNT];  /* the triangle kernels */
    unsigned char trav[LANES_ACCURACY_COUNT]; /* the traversals (SAME: as hit) */
    float t, u, v;                            /* of a hit; NAN: not checked */
} tri_case;

#define INF INFINITY
#define R(ox, oy, oz, dx, dy, dz, tn, tf) {{ox, oy, oz}, {dx, dy, dz}, tn, tf}
#define RAY(ox, oy, oz, dx, dy, dz) R(ox, oy, oz, dx, dy, dz, 0.0f, INF)
#define BOX(x0, y0, z0, x1, y1, z1) {{x0, y0, z0}, {x1, y1, z1}}
#define TRI(a0, a1, a2, b0, b1, b2, c0, c1, c2) {{a0, a1, a2}, {b0, b1, b2}, {c0, c1, c2}}

#define UNIT BOX(0, 0, 0, 1, 1, 1)
/* T0: the right triangle x, y >= 0, x + y <= 1 in the plane z = 2, so a ray
 * along z from z = -1 meets it at t = 3 with u = x, v = y; every product
 * in either test is then exact (see tri_cases). */
#define T0 TRI(0, 0, 2, 1, 0, 2, 0, 1, 2)

#define DN 0x1p-140f          /* a denormal: 1/DN overflows to inf */
#define TINY 1e-30f           /* normal, with a finite reciprocal */
#define HALF_UP 0x1.000002p-1f /* 0.5 + 1 ulp */
#define HALF_DN 0x1.fffffep-2f /* 0.5 - 1 ulp */
#define THREE_DN 0x1.7ffffep+1f
#define THREE_UP 0x1.800002p+1f

/* One ray against one box. Unless stated, the box is [0,1]^3 and tnear = 0,
 * tfar = +inf. The slab test takes near and far planes by the sign of 1/d
 * and passes the running interval second to min/max, so the NaN of
 * (plane - o) * (1/±0) with o on that plane leaves the interval unchanged
 * (box_kernels.c). */
static const box_case box_cases[] = {
    /* d = ±0: 1/d = ±inf and that slab is (-inf, +inf) while o is strictly
     * inside it; the z slab gives entry (0 - -1) * 1 = 1, exit 2. */
    {"d=(+0,-0,1) through the middle", RAY(.5f, .5f, -1, 0.0f, -0.0f, 1), UNIT, ALL(HIT), 1, true},
    {"d=(-0,+0,1) through the middle", RAY(.5f, .5f, -1, -0.0f, 0.0f, 1), UNIT, ALL(HIT), 1, true},
    /* 1/-1 = -1 picks max.z as the near plane: (1 - 2) * -1 = 1 */
    {"d=(-0,-0,-1) from above", RAY(.5f, .5f, 2, -0.0f, -0.0f, -1), UNIT, ALL(HIT), 1, true},
    /* 1/DN = inf (as for 0), 1/1e-30 = 1e30: the y slab is [-5e29, 5e29] */
    {"d=(denormal,1e-30,1)", RAY(.5f, .5f, -1, DN, TINY, 1), UNIT, ALL(HIT), 1, true},
    {"d=(-denormal,-1e-30,1)", RAY(.5f, .5f, -1, -DN, -TINY, 1), UNIT, ALL(HIT), 1, true},
    /* every slab is [1/1e-30, 2/1e-30]: a huge but finite entry, fl(1/1e-30)
     * (the fast reciprocal takes the exact 1/d for components this small) */
    {"d=(1e-30,1e-30,1e-30) from (-1,-1,-1)", RAY(-1, -1, -1, TINY, TINY, TINY), UNIT, ALL(HIT),
     1.0f / 1e-30f, true},
    /* d.z = 1.4e-45: the box is at t = 7e44, beyond FLT_MAX (1/d = inf gives
     * entry +inf) */
    {"d=(0,0,1e-45): the box lies beyond FLT_MAX", RAY(.5f, .5f, -1, 0, 0, 0x1p-149f), UNIT,
     ALL(MISS), NAN, false},
    /* the same ray from inside: every slab is (-inf, +inf), entry = tnear */
    {"d=(0,0,1e-45) from inside", RAY(.5f, .5f, .5f, 0, 0, 0x1p-149f), UNIT, ALL(HIT), 0, false},
    /* outside the x slab with d.x = ±0: both x distances are the same
     * infinity (-inf for +0 from x > 1, and for -0 from x < 0), so exit < 0 */
    {"outside on x, d.x=+0", RAY(2, .5f, -1, 0, 0, 1), UNIT, ALL(MISS), NAN, false},
    {"outside on x, d.x=-0", RAY(-1, .5f, -1, -0.0f, 0, 1), UNIT, ALL(MISS), NAN, false},
    /* o.x = -denormal: (0 - o.x) * inf = +inf is the entry (IEEE, no DAZ) */
    {"outside on x by a denormal, d.x=0", RAY(-0x1p-149f, .5f, -1, 0, 0, 1), UNIT, ALL(MISS),
     NAN, false},
    {"inside on x by a denormal, d.x=0", RAY(0x1p-149f, .5f, -1, 0, 0, 1), UNIT, ALL(HIT), 1, true},
    /* o on a face of the slab whose d is ±0: one distance is 0 * ±inf = NaN,
     * dropped by the operand order, the other is ∓inf: the slab is open to
     * the side of the box, and closed boxes hit */
    {"on face x=0, d.x=+0", RAY(0, .5f, -1, 0, 0, 1), UNIT, ALL(HIT), 1, true},
    {"on face x=0, d.x=-0", RAY(0, .5f, -1, -0.0f, 0, 1), UNIT, ALL(HIT), 1, true},
    {"on face x=1, d.x=+0", RAY(1, .5f, -1, 0, 0, 1), UNIT, ALL(HIT), 1, true},
    {"on face x=1, d.x=-0", RAY(1, .5f, -1, -0.0f, 0, 1), UNIT, ALL(HIT), 1, true},
    {"on face y=0, d.y=-0", RAY(.5f, 0, -1, 0, -0.0f, 1), UNIT, ALL(HIT), 1, true},
    {"on face y=1, d.y=+0", RAY(.5f, 1, -1, 0, 0, 1), UNIT, ALL(HIT), 1, true},
    {"on face z=0 moving along x", RAY(-1, .5f, 0, 1, 0, 0), UNIT, ALL(HIT), 1, true},
    {"on face z=1 moving along x, d.z=-0", RAY(-1, .5f, 1, 1, 0, -0.0f), UNIT, ALL(HIT), 1, true},
    /* on an edge: two NaN slabs */
    {"on edge x=0,y=0", RAY(0, 0, -1, 0, 0, 1), UNIT, ALL(HIT), 1, true},
    {"on edge x=1,y=1, d=(-0,-0,1)", RAY(1, 1, -1, -0.0f, -0.0f, 1), UNIT, ALL(HIT), 1, true},
    /* leaving through the corner at t = 0: x slab [(1-0)*-1, (0-0)*-1] =
     * [-1, -0], so the interval is [0, -0]: a touch, and boxes are closed.
     * t = 0 is tnear, not a slab distance. */
    {"on the corner, leaving", RAY(0, 0, 0, -1, 0, 0), UNIT, ALL(HIT), 0, false},
    /* 1e20 origins: 1 - 1e20 rounds to -1e20, so entry and exit are both
     * 1e20: a single point of the interval, still a hit */
    {"o.x=1e20 toward the box", RAY(1e20f, .5f, .5f, -1, 0, 0), UNIT, ALL(HIT), 1e20f, true},
    {"o.x=1e20 away from the box", RAY(1e20f, .5f, .5f, 1, 0, 0), UNIT, ALL(MISS), NAN, false},
    {"o=(1e20,1e20,1e20) toward the box", RAY(1e20f, 1e20f, 1e20f, -1, -1, -1), UNIT, ALL(HIT),
     1e20f, true},
    {"o.x=-1e20 toward the box", RAY(-1e20f, .5f, .5f, 1, 0, 0), UNIT, ALL(HIT), 1e20f, true},
    {"box at x=1e20, hit", RAY(0, .5f, .5f, 1, 0, 0), BOX(1e20f, 0, 0, 2e20f, 1, 1), ALL(HIT), 1e20f,
     true},
    {"box at x=1e20, passed beside", RAY(0, 2, .5f, 1, 0, 0), BOX(1e20f, 0, 0, 2e20f, 1, 1),
     ALL(MISS), NAN, false},
    /* 1e-20 origins: (0 - -1e-20) * 1 = 1e-20 exactly */
    {"o.z=-1e-20 below a 1e-20 box", RAY(5e-21f, 5e-21f, -1e-20f, 0, 0, 1),
     BOX(0, 0, 0, 1e-20f, 1e-20f, 1e-20f), ALL(HIT), 1e-20f, true},
    {"o.x=-1e-20 beside the unit box", RAY(-1e-20f, .5f, .5f, 1, 0, 0), UNIT, ALL(HIT), 1e-20f, true},
    {"o.x=1e-20 inside, moving out", RAY(1e-20f, .5f, .5f, -1, 0, 0), UNIT, ALL(HIT), 0, false},
    /* tnear == tfar: the interval is one point. At the entry (1) or the exit
     * (2) it is a hit with exact reciprocals. Fast mode's 1/1 is an estimate
     * that may land an ulp or two on either side of 1, moving the entry to
     * rd > 1 or the exit to 2 * rd < 2, past the point: either answer is
     * right there. Inside (1.5) the margin is large in every mode. */
    {"tnear=tfar=1 at the entry", R(.5f, .5f, -1, 0, 0, 1, 1, 1), UNIT, MODES(EITHER, HIT, HIT), 1,
     false},
    {"tnear=tfar=2 at the exit", R(.5f, .5f, -1, 0, 0, 1, 2, 2), UNIT, MODES(EITHER, HIT, HIT), 2,
     false},
    {"tnear=tfar=1.5 inside", R(.5f, .5f, -1, 0, 0, 1, 1.5f, 1.5f), UNIT, ALL(HIT), 1.5f, false},
    {"tnear=tfar=0.5 before", R(.5f, .5f, -1, 0, 0, 1, .5f, .5f), UNIT, ALL(MISS), NAN, false},
    {"tnear=tfar=3 after", R(.5f, .5f, -1, 0, 0, 1, 3, 3), UNIT, ALL(MISS), NAN, false},
    /* tfar = 0 */
    {"tfar=0, box ahead", R(.5f, .5f, -1, 0, 0, 1, 0, 0), UNIT, ALL(MISS), NAN, false},
    {"tfar=0, origin inside", R(.5f, .5f, .5f, 0, 0, 1, 0, 0), UNIT, ALL(HIT), 0, false},
    /* entry (0 - 0) * rd = 0 in every mode */
    {"tfar=0, origin on face z=0", R(.5f, .5f, 0, 0, 0, 1, 0, 0), UNIT, ALL(HIT), 0, false},
    /* tentry is max(tnear, entry): with tnear = -10 it is the entry, -0.5 */
    {"tnear=-10 from inside", R(.5f, .5f, .5f, 0, 0, 1, -10, INF), UNIT, ALL(HIT), -.5f, true},
    {"tnear=-inf from inside", R(.5f, .5f, .5f, 0, 0, 1, -INF, INF), UNIT, ALL(HIT), -.5f, true},
    /* -0 is 0: tentry = max(-0, -0.5) = -0 */
    {"tnear=-0 from inside", R(.5f, .5f, .5f, 0, 0, 1, -0.0f, INF), UNIT, ALL(HIT), 0, false},
    /* a valid ray with tnear > tfar has an empty interval */
    {"tnear=2 > tfar=1.5 across the box", R(.5f, .5f, -1, 0, 0, 1, 2, 1.5f), UNIT, ALL(MISS), NAN, false},
    /* tfar = +inf stands for FLT_MAX */
    {"tfar=inf, box at t=1e38", RAY(.5f, .5f, -1e38f, 0, 0, 1), UNIT, ALL(HIT), 1e38f, true},
    /* entry FLT_MAX, exit fl(1 + FLT_MAX) = FLT_MAX, tfar clamped to FLT_MAX:
     * hit at the very end of the float range with 1/1 = 1; with fast mode's
     * estimate of 1/1 above 1 the entry overflows to inf: either. */
    {"tfar=inf, box at t=FLT_MAX", RAY(.5f, .5f, -FLT_MAX, 0, 0, 1), UNIT, MODES(EITHER, HIT, HIT),
     FLT_MAX, true},
    /* 3e38 * (1/0.5) = 6e38 overflows: the box is beyond FLT_MAX */
    {"tfar=inf, box beyond FLT_MAX", RAY(.5f, .5f, -3e38f, 0, 0, .5f), UNIT, ALL(MISS), NAN, false},
    {"tfar=FLT_MAX, box at t=1e38", R(.5f, .5f, -1e38f, 0, 0, 1, 0, FLT_MAX), UNIT, ALL(HIT), 1e38f,
     true},
    /* flat boxes (zero thickness on z): crossing gives entry = exit */
    {"flat box crossed", RAY(.5f, .5f, -1, 0, 0, 1), BOX(0, 0, .5f, 1, 1, .5f), ALL(HIT), 1.5f, true},
    /* x slab [(0 - .25) * 4, (1 - .25) * 4] = [-1, 3] contains 1.5 */
    {"flat box crossed obliquely", RAY(.25f, .25f, -1, .25f, .25f, 1), BOX(0, 0, .5f, 1, 1, .5f),
     ALL(HIT), 1.5f, true},
    /* in the plane: the z distances are both 0 * inf = NaN and dropped */
    {"flat box, ray in its plane", RAY(-1, .5f, .5f, 1, 0, 0), BOX(0, 0, .5f, 1, 1, .5f), ALL(HIT), 1,
     true},
    {"flat box, ray in its plane, d.z=-0", RAY(-1, .5f, .5f, 1, 0, -0.0f), BOX(0, 0, .5f, 1, 1, .5f),
     ALL(HIT), 1, true},
    {"flat box, ray in its plane, oblique", RAY(-1, -1, .5f, 1, 1, 0), BOX(0, 0, .5f, 1, 1, .5f),
     ALL(HIT), 1, true},
    {"flat box, in its plane outside its extent", RAY(-1, 2, .5f, 1, 0, 0), BOX(0, 0, .5f, 1, 1, .5f),
     ALL(MISS), NAN, false},
    {"flat box, in its plane, pointing away", RAY(2, .5f, .5f, 1, 0, 0), BOX(0, 0, .5f, 1, 1, .5f),
     ALL(MISS), NAN, false},
    /* one ulp above the plane: (0.5 - HALF_UP) * inf = -inf for both planes */
    {"flat box, parallel 1 ulp above", RAY(-1, .5f, HALF_UP, 1, 0, 0), BOX(0, 0, .5f, 1, 1, .5f),
     ALL(MISS), NAN, false},
    {"segment box (flat on y and z) crossed", RAY(.5f, .5f, -1, 0, 0, 1), BOX(0, .5f, .5f, 1, .5f, .5f),
     ALL(HIT), 1.5f, true},
    {"point box crossed", RAY(.5f, .5f, -1, 0, 0, 1), BOX(.5f, .5f, .5f, .5f, .5f, .5f), ALL(HIT), 1.5f,
     true},
    /* y(t) = 0.5 + 1e-30 t equals 0.5 only at t = 0, where z = -1: the y
     * slab is [0, 0] and the z slab [1.5, 1.5] */
    {"point box, ray off by a 1e-30 slope", RAY(.5f, .5f, -1, 0, TINY, 1),
     BOX(.5f, .5f, .5f, .5f, .5f, .5f), ALL(MISS), NAN, false},
    /* empty boxes: never hit, though each of these rays hits the box with
     * min and max swapped back */
    {"inverted on x, ray along z", RAY(.5f, .5f, -1, 0, 0, 1), BOX(1, 0, 0, 0, 1, 1), ALL(MISS), NAN,
     false},
    {"inverted on x, ray along x", RAY(-1, .5f, .5f, 1, 0, 0), BOX(1, 0, 0, 0, 1, 1), ALL(MISS), NAN,
     false},
    {"inverted on z, ray along z", RAY(.5f, .5f, -1, 0, 0, 1), BOX(0, 0, 1, 1, 1, 0), ALL(MISS), NAN,
     false},
    {"inverted on x, whole line through it", R(.5f, .5f, .5f, 0, 0, 1, -INF, INF), BOX(1, 0, 0, 0, 1, 1),
     ALL(MISS), NAN, false},
    /* inverted by one ulp where the rounding of (plane - o) hides it: both
     * x distances are fl(1e6 + 0.5...) = 1000000.5, so the slab alone would
     * say entry == exit, a hit */
    {"inverted by 1 ulp on x, hidden by rounding", RAY(-1e6f, .5f, .5f, 1, 0, 0),
     BOX(HALF_UP, 0, 0, .5f, 1, 1), ALL(MISS), NAN, false},
    {"inverted by 1 ulp on z, hidden by rounding", RAY(.5f, .5f, -1e6f, 0, 0, 1),
     BOX(0, 0, HALF_UP, 1, 1, .5f), ALL(MISS), NAN, false},
    {"inverted by 1 ulp on y, ray in the plane y=0.5", RAY(-1, .5f, .5f, 1, -0.0f, 0),
     BOX(0, HALF_UP, 0, 1, .5f, 1), ALL(MISS), NAN, false},
    {"empty slot (+inf, -inf), origin at its centre", RAY(.5f, .5f, .5f, 0, 0, 1),
     BOX(INF, INF, INF, -INF, -INF, -INF), ALL(MISS), NAN, false},
    /* d = 0 is invalid, even from inside the box */
    {"d=(0,0,0) from outside", RAY(.5f, .5f, -1, 0, 0, 0), UNIT, ALL(MISS), NAN, false},
    {"d=(-0,-0,-0) from inside", RAY(.5f, .5f, .5f, -0.0f, -0.0f, -0.0f), UNIT, ALL(MISS), NAN, false},
};

/* One ray against one triangle; T0 and a hit at t = 3 unless stated. For T0
 * and a ray along ±z, Möller–Trumbore has e1 = (1,0,0), e2 = (0,1,0),
 * p = d x e2 = (∓1, 0, 0) and det = ∓1, so u = o.x, v = o.y and t = 3 with
 * every product exact, fused or not (the tiny components below add terms
 * under half an ulp). The watertight test's edge functions are ∓(b0, b1,
 * b2), exact for the dyadic points used, and its t = b0*3 + b1*3 + b2*3 is
 * exact for (b0, b1, b2) = (1/4, 1/4, 1/2), which is why most rays aim at
 * (u, v) = (1/4, 1/2). Traversals agree unless the data says otherwise; they
 * first enter T0's flat leaf box, entry = exit = 3 * (1/d.z). */
static const tri_case tri_cases[] = {
    {"basic, (u,v)=(1/4,1/2)", RAY(.25f, .5f, -1, 0, 0, 1), T0, ALL(HIT), KERNELS, 3, .25f, .5f},
    {"d=(+0,-0,1)", RAY(.25f, .5f, -1, 0.0f, -0.0f, 1), T0, ALL(HIT), KERNELS, 3, .25f, .5f},
    {"d=(-0,+0,1)", RAY(.25f, .5f, -1, -0.0f, 0.0f, 1), T0, ALL(HIT), KERNELS, 3, .25f, .5f},
    /* the tiny components add 3*DN and 3e-30 to numbers of size 0.25 and
     * 0.5: below half an ulp, so u, v and t are those of d = (0,0,1) */
    {"d=(denormal,1e-30,1)", RAY(.25f, .5f, -1, DN, TINY, 1), T0, ALL(HIT), KERNELS, 3, .25f, .5f},
    {"d=(-denormal,-1e-30,1)", RAY(.25f, .5f, -1, -DN, -TINY, 1), T0, ALL(HIT), KERNELS, 3, .25f, .5f},
    {"from above, d=(-0,-0,-1)", RAY(.25f, .5f, 5, -0.0f, -0.0f, -1), T0, ALL(HIT), KERNELS, 3, .25f,
     .5f},
    /* the boundary is inside: vertices and edges are hit (the watertight
     * test's zero edge functions are confirmed zero in double) */
    {"through vertex v0", RAY(0, 0, -1, 0, 0, 1), T0, ALL(HIT), KERNELS, 3, 0, 0},
    {"through vertex v1", RAY(1, 0, -1, 0, 0, 1), T0, ALL(HIT), KERNELS, 3, 1, 0},
    {"through vertex v2", RAY(0, 1, -1, 0, 0, 1), T0, ALL(HIT), KERNELS, 3, 0, 1},
    {"through the hypotenuse's midpoint", RAY(.5f, .5f, -1, 0, 0, 1), T0, ALL(HIT), KERNELS, 3, .5f, .5f},
    {"through edge x=0", RAY(0, .5f, -1, 0, 0, 1), T0, ALL(HIT), KERNELS, 3, 0, .5f},
    {"through edge y=0", RAY(.25f, 0, -1, 0, 0, 1), T0, ALL(HIT), KERNELS, 3, .25f, 0},
    /* u = -1e-20 exactly (Möller); V = 1e-20 > 0 > U, W (watertight) */
    {"1e-20 outside edge x=0", RAY(-1e-20f, .5f, -1, 0, 0, 1), T0, ALL(MISS), KERNELS, NAN, NAN, NAN},
    /* One ulp outside the hypotenuse: u = 0.5 and v = 0.5 + 2^-24 are exact,
     * but Möller's u + v = 1 + 2^-24 is a tie that rounds to even, 1, and
     * passes u + v <= 1: a hit in fast and default mode (no tolerance on the
     * barycentrics either way). The watertight test's edge functions are
     * exact here (U = 2^-24 > 0 > V, W) and reject it. */
    {"1 ulp outside the hypotenuse", RAY(.5f, HALF_UP, -1, 0, 0, 1), T0, MODES(HIT, HIT, MISS), KERNELS,
     3, .5f, HALF_UP},
    /* one ulp inside: u + v = 1 - 2^-25 <= 1; watertight b0 = 2^-25,
     * b1 = 0.5, b2 = 0.5 - 2^-25, and t = (3*2^-25 + 1.5) + (1.5 - 3*2^-25)
     * rounds to (1.5 + 2^-23) + (1.5 - 2^-23) = 3 */
    {"1 ulp inside the hypotenuse", RAY(.5f, HALF_DN, -1, 0, 0, 1), T0, ALL(HIT), KERNELS, 3, .5f,
     HALF_DN},
    /* in the triangle's plane: det = 0 (Möller), U = V = W = 0 (watertight) */
    {"ray in the triangle's plane", RAY(-1, .25f, 2, 1, 0, 0), T0, ALL(MISS), KERNELS, NAN, NAN, NAN},
    {"ray along edge y=0 in the plane", RAY(-1, 0, 2, 1, 0, 0), T0, ALL(MISS), KERNELS, NAN, NAN, NAN},
    {"parallel above the plane", RAY(-1, .25f, 2.5f, 1, 0, 0), T0, ALL(MISS), KERNELS, NAN, NAN, NAN},
    {"pointing away (t = -3)", RAY(.25f, .5f, -1, 0, 0, -1), T0, ALL(MISS), KERNELS, NAN, NAN, NAN},
    /* The closed interval. The triangle kernels compute t = 3 exactly (no
     * reciprocal of d), so a point interval at 3 and tfar or tnear exactly 3
     * hit in every mode. A traversal must first enter T0's flat leaf box,
     * at entry = exit = 3 * rd: exact with division, but fast mode's
     * estimate rd of 1/1 may lie an ulp off 1, putting the box just outside
     * [tnear, tfar], and fast mode does not widen box exits: either answer
     * is right there. */
    {"tnear=tfar=3 at the hit", R(.25f, .5f, -1, 0, 0, 1, 3, 3), T0, ALL(HIT), MODES(EITHER, HIT, HIT),
     3, .25f, .5f},
    {"tnear=tfar=2.5 before the hit", R(.25f, .5f, -1, 0, 0, 1, 2.5f, 2.5f), T0, ALL(MISS), KERNELS, NAN,
     NAN, NAN},
    {"tnear=tfar=3.5 after the hit", R(.25f, .5f, -1, 0, 0, 1, 3.5f, 3.5f), T0, ALL(MISS), KERNELS, NAN,
     NAN, NAN},
    {"tfar=3 exactly at the hit", R(.25f, .5f, -1, 0, 0, 1, 0, 3), T0, ALL(HIT), MODES(EITHER, HIT, HIT),
     3, .25f, .5f},
    {"tnear=3 exactly at the hit", R(.25f, .5f, -1, 0, 0, 1, 3, INF), T0, ALL(HIT),
     MODES(EITHER, HIT, HIT), 3, .25f, .5f},
    {"tfar 1 ulp before the hit", R(.25f, .5f, -1, 0, 0, 1, 0, THREE_DN), T0, ALL(MISS), KERNELS, NAN,
     NAN, NAN},
    {"tnear 1 ulp after the hit", R(.25f, .5f, -1, 0, 0, 1, THREE_UP, INF), T0, ALL(MISS), KERNELS, NAN,
     NAN, NAN},
    {"tfar=0, triangle ahead", R(.25f, .5f, -1, 0, 0, 1, 0, 0), T0, ALL(MISS), KERNELS, NAN, NAN, NAN},
    {"tnear=4 > tfar=2 around the hit", R(.25f, .5f, -1, 0, 0, 1, 4, 2), T0, ALL(MISS), KERNELS, NAN, NAN,
     NAN},
    /* origin on the triangle: t = ±0 in [0, 0]; the leaf box's entry and exit
     * are (2 - 2) * rd = 0 in every mode */
    {"tnear=tfar=0, origin on the triangle", R(.25f, .5f, 2, 0, 0, 1, 0, 0), T0, ALL(HIT), KERNELS, 0,
     .25f, .5f},
    /* tfar = +inf is FLT_MAX: t = 1e38 - -1e38 = 2e38 (an exact doubling) */
    {"tfar=inf, triangle at t=2e38", RAY(.25f, .5f, -1e38f, 0, 0, 1),
     TRI(0, 0, 1e38f, 1, 0, 1e38f, 0, 1, 1e38f), ALL(HIT), KERNELS, 2 * 1e38f, .25f, .5f},
    /* t = 6e38: the difference overflows to inf (Möller: NaN from inf * 0;
     * watertight: t = inf), beyond tfar = FLT_MAX */
    {"tfar=inf, triangle beyond FLT_MAX", RAY(.25f, .5f, -3e38f, 0, 0, 1),
     TRI(0, 0, 3e38f, 1, 0, 3e38f, 0, 1, 3e38f), ALL(MISS), KERNELS, NAN, NAN, NAN},
    /* d = (0,0,DN): the plane is at t = 3 / DN = 2^141.6, beyond FLT_MAX
     * (Möller's 1/det and the watertight 1/d.z overflow to inf) */
    {"d=(0,0,denormal): the triangle lies beyond FLT_MAX", RAY(.25f, .5f, -1, 0, 0, DN), T0, ALL(MISS),
     KERNELS, NAN, NAN, NAN},
    /* 1e20 origins: 1e20 - 2 rounds to 1e20 (float), so t = 1e20; the
     * watertight t = 0.25X + 0.25X + 0.5X = X exactly */
    {"o.z=1e20 toward the triangle", RAY(.25f, .5f, 1e20f, 0, 0, -1), T0, ALL(HIT), KERNELS, 1e20f, .25f,
     .5f},
    {"o.z=1e20 away from the triangle", RAY(.25f, .5f, 1e20f, 0, 0, 1), T0, ALL(MISS), KERNELS, NAN, NAN,
     NAN},
    /* the same on x (the watertight test's dominant axis is x, flipped) */
    {"o.x=1e20 toward a triangle in x=2", RAY(1e20f, .25f, .5f, -1, 0, 0), TRI(2, 0, 0, 2, 1, 0, 2, 0, 1),
     ALL(HIT), KERNELS, 1e20f, .25f, .5f},
    /* 1e-20 origins: u = v = 1e-20 exactly; watertight b = (1, 1e-20, 1e-20)
     * (1e-40 terms vanish against 1 and 1e-20) */
    {"o=(1e-20,1e-20,-1) next to vertex v0", RAY(1e-20f, 1e-20f, -1, 0, 0, 1), T0, ALL(HIT), KERNELS, 3,
     1e-20f, 1e-20f},
    {"o.z=-1e-20 below a triangle in z=0", RAY(.25f, .5f, -1e-20f, 0, 0, 1),
     TRI(0, 0, 0, 1, 0, 0, 0, 1, 0), ALL(HIT), KERNELS, 1e-20f, .25f, .5f},
    /* a sliver 2^-20 high is not degenerate: det = -2^-20, u = 2^-22,
     * v = 2^-22 / 2^-20 = 0.25, every step exact in both tests */
    {"sliver 2^-20 high", RAY(0x1p-22f, 0x1p-22f, -1, 0, 0, 1), TRI(0, 0, 2, 1, 0, 2, 0, 0x1p-20f, 2),
     ALL(HIT), KERNELS, 3, 0x1p-22f, .25f},
    /* Degenerate triangles (their edge vectors' cross product is exactly 0)
     * are never hit, even by rays through their vertices. */
    {"point triangle, ray through the point", RAY(.25f, .5f, -1, 0, 0, 1),
     TRI(.25f, .5f, 2, .25f, .5f, 2, .25f, .5f, 2), ALL(MISS), KERNELS, NAN, NAN, NAN},
    {"point triangle, oblique ray through it", RAY(-.75f, -.5f, 1, 1, 1, 1),
     TRI(.25f, .5f, 2, .25f, .5f, 2, .25f, .5f, 2), ALL(MISS), KERNELS, NAN, NAN, NAN},
    {"collinear on y=0.5, through the middle vertex", RAY(.5f, .5f, -1, 0, 0, 1),
     TRI(0, .5f, 2, 1, .5f, 2, .5f, .5f, 2), ALL(MISS), KERNELS, NAN, NAN, NAN},
    {"collinear on y=0.5, through v0", RAY(0, .5f, -1, 0, 0, 1), TRI(0, .5f, 2, 1, .5f, 2, .5f, .5f, 2),
     ALL(MISS), KERNELS, NAN, NAN, NAN},
    {"collinear on y=0.5, through the segment", RAY(.25f, .5f, -1, 0, 0, 1),
     TRI(0, .5f, 2, 1, .5f, 2, .5f, .5f, 2), ALL(MISS), KERNELS, NAN, NAN, NAN},
    {"collinear diagonal, through the segment", RAY(2, 2, -1, 0, 0, 1), TRI(0, 0, 2, 1, 1, 2, 3, 3, 2),
     ALL(MISS), KERNELS, NAN, NAN, NAN},
    {"collinear diagonal, through the middle vertex", RAY(1, 1, -1, 0, 0, 1),
     TRI(0, 0, 2, 1, 1, 2, 3, 3, 2), ALL(MISS), KERNELS, NAN, NAN, NAN},
    {"collinear in 3D, ray along the line", RAY(-1, -2, -3, 1, 2, 3), TRI(0, 0, 0, 1, 2, 3, 2, 4, 6),
     ALL(MISS), KERNELS, NAN, NAN, NAN},
    {"collinear in 3D, through the middle vertex", RAY(1, 2, -5, 0, 0, 1), TRI(0, 0, 0, 1, 2, 3, 2, 4, 6),
     ALL(MISS), KERNELS, NAN, NAN, NAN},
    /* pbrt-v4's BadCases triangle: x and z of all three vertices are equal */
    {"collinear (pbrt-v4 BadCases)",
     RAY(-1081.47925f, 99.9999542f, 87.7701111f, -32.1072998f, -183.355865f, -144.607635f),
     TRI(-1113.45459f, -79.049614f, -56.2431908f, -1113.45459f, -87.0922699f, -56.2431908f,
         -1113.45459f, -79.2090149f, -56.2431908f),
     ALL(MISS), KERNELS, NAN, NAN, NAN},
    {"v0 == v1, through the repeated vertex", RAY(0, 0, -1, 0, 0, 1), TRI(0, 0, 2, 0, 0, 2, 0, 1, 2),
     ALL(MISS), KERNELS, NAN, NAN, NAN},
    {"v0 == v1, through v2", RAY(0, 1, -1, 0, 0, 1), TRI(0, 0, 2, 0, 0, 2, 0, 1, 2), ALL(MISS), KERNELS,
     NAN, NAN, NAN},
    {"v0 == v1, through the edge", RAY(0, .5f, -1, 0, 0, 1), TRI(0, 0, 2, 0, 0, 2, 0, 1, 2), ALL(MISS),
     KERNELS, NAN, NAN, NAN},
    {"v1 == v2, through the edge", RAY(.5f, 0, -1, 0, 0, 1), TRI(0, 0, 2, 1, 0, 2, 1, 0, 2), ALL(MISS),
     KERNELS, NAN, NAN, NAN},
    {"v0 == v2, ray along the edge in its plane", RAY(-1, 0, 2, 1, 0, 0), TRI(0, 0, 2, 1, 0, 2, 0, 0, 2),
     ALL(MISS), KERNELS, NAN, NAN, NAN},
    /* d = 0 is invalid, even from a point of the triangle */
    {"d=(0,0,0)", RAY(.25f, .5f, -1, 0, 0, 0), T0, ALL(MISS), KERNELS, NAN, NAN, NAN},
    {"d=(-0,-0,-0) from on the triangle", R(.25f, .5f, 2, -0.0f, -0.0f, -0.0f, 0, 0), T0, ALL(MISS),
     KERNELS, NAN, NAN, NAN},
};

/* NaN or Inf put into one field of a ray that hits (fields 0-2: o, 3-5: d,
 * 6: tnear, 7: tfar, 8: tnear and tfar). Non-finite o or d and NaN ends make
 * the ray invalid: a miss, whatever the slab order would make of the NaN.
 * tnear = +inf or tfar = -inf empty the interval. tnear = -inf and
 * tfar = +inf are valid (clamped to ∓FLT_MAX) and keep the hit; only a box
 * tentry that was tnear changes (make_cases). */
typedef struct {
    int field;
    float value;
    unsigned char hit;
} injection;

static const injection injections[] = {
    {0, NAN, MISS}, {1, NAN, MISS}, {2, NAN, MISS}, {3, NAN, MISS}, {4, NAN, MISS},
    {5, NAN, MISS}, {6, NAN, MISS}, {7, NAN, MISS}, {8, NAN, MISS},
    {0, INF, MISS}, {1, INF, MISS}, {2, INF, MISS}, {3, INF, MISS}, {4, INF, MISS},
    {5, INF, MISS}, {6, INF, MISS}, {7, INF, HIT},
    {0, -INF, MISS}, {1, -INF, MISS}, {2, -INF, MISS}, {3, -INF, MISS}, {4, -INF, MISS},
    {5, -INF, MISS}, {6, -INF, HIT}, {7, -INF, MISS},
};
static const char *const field_names[9] = {"o.x", "o.y", "o.z", "d.x", "d.y", "d.z", "tnear", "tfar",
                                           "tnear,tfar"};

/* The rays the injections go into: from outside, from inside (where a NaN
 * slab that the operand order dropped would leave a hit), and from a face
 * of the box (a NaN slab already present). */
static const box_case box_bases[] = {
    {"from outside", RAY(.5f, .5f, -1, 0, 0, 1), UNIT, ALL(HIT), 1, true},
    {"from inside", RAY(.5f, .5f, .5f, 0, 0, 1), UNIT, ALL(HIT), 0, false},
    {"from face x=0", RAY(0, .5f, -1, 0, 0, 1), UNIT, ALL(HIT), 1, true},
};
static const tri_case tri_bases[] = {
    {"from below", RAY(.25f, .5f, -1, 0, 0, 1), T0, ALL(HIT), KERNELS, 3, .25f, .5f},
    {"from on the triangle", RAY(.25f, .5f, 2, 0, 0, 1), T0, ALL(HIT), KERNELS, 0, .25f, .5f},
};

static void inject(xray *r, const injection *in)
{
    float *f[8] = {&r->o[0], &r->o[1], &r->o[2], &r->d[0], &r->d[1], &r->d[2], &r->tnear, &r->tfar};
    if (in->field == 8)
        r->tnear = r->tfar = in->value;
    else
        *f[in->field] = in->value;
}

/* ======================================================================== */
/* Checks and failure reports                                               */
/* ======================================================================== */

typedef struct {
    const lanes_kernels *k;
    lanes_accuracy mode;
    lanes_precision p;
    const char *cname; /* the case being run */
    char prim[256];    /* its primitive, for reports */
    char cray[256];    /* its ray */
    long checks, fails;
} ctx;

/* Distinct failing checks (set, mode, path, case, lane role, what), each
 * with the number of placements it failed in and the first one's detail. */
typedef struct {
    char key[400];
    char detail[700];
    char prim[256], cray[256];
    long count;
} failure;

static failure *failures;
static size_t nfailures, capfailures;
static bool print_all;

static const char *mode_name(lanes_accuracy a)
{
    return a == LANES_ACCURACY_FAST ? "fast" : a == LANES_ACCURACY_DEFAULT ? "default" : "robust";
}

static const char *exp_name(int e) { return e == HIT ? "hit" : e == MISS ? "miss" : "either"; }

static void fmt_ray(char *buf, size_t size, const xray *r)
{
    snprintf(buf, size, "o=(%.9g, %.9g, %.9g) d=(%.9g, %.9g, %.9g) t=[%.9g, %.9g]", r->o[0], r->o[1],
             r->o[2], r->d[0], r->d[1], r->d[2], r->tnear, r->tfar);
}

/* One check. On failure the detail (and the ray of the lane, when given) is
 * formatted; passing checks cost a compare and a count. */
static bool check(ctx *c, bool ok, const char *path, const char *role, const char *what, const xray *ray,
                  const char *fmt, ...) __attribute__((format(printf, 7, 8)));

static bool check(ctx *c, bool ok, const char *path, const char *role, const char *what, const xray *ray,
                  const char *fmt, ...)
{
    c->checks++;
    if (ok) return true;
    c->fails++;
    char key[400], detail[700], rs[200] = "";
    snprintf(key, sizeof key, "%s %s %s [%s] %s: %s", c->k->name, mode_name(c->mode), path, c->cname,
             role, what);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(detail, sizeof detail, fmt, ap);
    va_end(ap);
    if (ray) {
        fmt_ray(rs, sizeof rs, ray);
        size_t len = strlen(detail);
        snprintf(detail + len, sizeof detail - len, "; lane's ray %s", rs);
    }
    if (print_all) printf("FAIL %s: %s\n", key, detail);
    for (size_t i = 0; i < nfailures; i++)
        if (strcmp(failures[i].key, key) == 0) {
            failures[i].count++;
            return false;
        }
    if (nfailures == capfailures) {
        capfailures = capfailures ? 2 * capfailures : 64;
        failures = realloc(failures, capfailures * sizeof *failures);
        if (!failures) {
            printf("out of memory\n");
            exit(1);
        }
    }
    failure *f = &failures[nfailures++];
    snprintf(f->key, sizeof f->key, "%s", key);
    snprintf(f->detail, sizeof f->detail, "%s", detail);
    snprintf(f->prim, sizeof f->prim, "%s", c->prim);
    snprintf(f->cray, sizeof f->cray, "%s", c->cray);
    f->count = 1;
    return false;
}

/* ulp distance through the ordered integer image of the floats (-0 = +0) */
static int64_t ordered(float x)
{
    int32_t i;
    memcpy(&i, &x, sizeof i);
    return i < 0 ? -(int64_t)(i & 0x7fffffff) : (int64_t)i;
}
static int64_t ulps(float a, float b)
{
    int64_t d = ordered(a) - ordered(b);
    return d < 0 ? -d : d;
}

#define SENT_F 0x7fc5a5a5u /* a quiet NaN with a payload no kernel produces */
#define SENT_W 0xa5a5a5a5u
#define SENT_PRIM 0x5eed5eedu
#define SENT_OCC 0xa5

static float sentinel(void)
{
    float f;
    uint32_t u = SENT_F;
    memcpy(&f, &u, sizeof f);
    return f;
}
static bool is_sentinel(float x)
{
    uint32_t u;
    memcpy(&u, &x, sizeof u);
    return u == SENT_F;
}
static void fill_sentinel(float *p, size_t n)
{
    for (size_t i = 0; i < n; i++) p[i] = sentinel();
}

/* ======================================================================== */
/* Lanes: what one ray (or primitive) of a call must produce                */
/* ======================================================================== */

typedef struct {
    xray r;
    int hit;        /* MISS, HIT or EITHER */
    float t, u, v;  /* of a hit; NAN: not checked */
    bool rcp;       /* t is a slab distance: FAST_ULPS in fast mode */
    bool approx;    /* an ordinary ray built in double: t, u, v within 1e-3 */
    uint32_t prim;  /* traversals: the scene triangle it hits */
    const char *role;
} lane;

static bool close_to(const ctx *c, float got, float want, bool rcp, bool approx)
{
    if (isnan(want)) return !isnan(got);
    if (approx) return fabs((double)got - want) <= 1e-3 * fmax(1.0, fabs((double)want));
    if (rcp && c->mode == LANES_ACCURACY_FAST) return ulps(got, want) <= FAST_ULPS;
    return got == want;
}

/* The hit bit and the values written for lane j (t, u, v may be NULL when
 * the path writes none). Values must be right for hits and untouched
 * (sentinels) for misses. */
static void check_lane(ctx *c, const char *path, const lane *l, size_t n, size_t pos, size_t j, bool got,
                       const float *t, const float *u, const float *v)
{
    if (!check(c, l->hit == EITHER || got == (l->hit == HIT), path, l->role, "hit", &l->r,
               "n=%zu, case at %zu: lane %zu expected %s, got %s", n, pos, j, exp_name(l->hit),
               got ? "hit" : "miss"))
        return;
    const float *vals[3] = {t, u, v};
    const float want[3] = {l->t, l->u, l->v};
    const char *names[3] = {"t", "u", "v"};
    for (int q = 0; q < 3; q++) {
        if (!vals[q]) continue;
        float g = vals[q][j];
        if (got)
            check(c, !is_sentinel(g) && close_to(c, g, want[q], q == 0 && l->rcp, l->approx), path,
                  l->role, names[q], &l->r, "n=%zu, case at %zu: lane %zu %s=%.9g (%a), expected %.9g (%a)",
                  n, pos, j, names[q], g, g, want[q], want[q]);
        else
            check(c, is_sentinel(g), path, l->role, "written for a miss", &l->r,
                  "n=%zu, case at %zu: lane %zu %s=%.9g written for a miss", n, pos, j, names[q], g);
    }
}

/* Hit words: nothing past word (n-1)/32 written, no bit past n set. */
static void check_words(ctx *c, const char *path, const uint32_t *w, size_t n, size_t pos)
{
    size_t nw = lanes_mask_words(n);
    for (size_t i = nw; i < nw + 2; i++)
        check(c, w[i] == SENT_W, path, "past n", "hit word written",
              NULL, "n=%zu, case at %zu: hit word %zu = 0x%08x", n, pos, i, w[i]);
    if (n % 32) {
        uint32_t past = ~((1u << (n % 32)) - 1u);
        check(c, !(w[nw - 1] & past & ~SENT_W), path, "past n", "hit bit set",
              NULL, "n=%zu, case at %zu: word 0x%08x", n, pos, w[nw - 1]);
    }
}

static void check_untouched(ctx *c, const char *path, const float *a, size_t from, size_t to, size_t n,
                            size_t pos, const char *what)
{
    for (size_t j = from; j < to; j++)
        if (!check(c, is_sentinel(a[j]), path, "past n", what,
                   NULL, "n=%zu, case at %zu: element %zu = %.9g written", n, pos, j, a[j]))
            return;
}

/* ======================================================================== */
/* Placements, buffers, rays                                                */
/* ======================================================================== */

enum { MAXN = 64, WATCH = 40 };

typedef struct {
    size_t n, pos;
} placement;

/* Counts 1, W-1, W, W+1 and 37 (a partial last vector at every width, and
 * a second 32-bit mask word); the case first, in the middle, last, and on
 * both sides of the word boundary. */
static size_t placements(int W, placement *out)
{
    size_t counts[5] = {1, (size_t)W - 1, (size_t)W, (size_t)W + 1, 37}, np = 0;
    for (int i = 0; i < 5; i++) {
        size_t n = counts[i];
        if (n == 0) continue;
        size_t pos[5] = {0, n / 2, n - 1, 31, 32};
        for (int k = 0; k < 5; k++) {
            if (pos[k] >= n) continue;
            bool dup = false;
            for (size_t q = 0; q < np; q++) dup |= out[q].n == n && out[q].pos == pos[k];
            if (!dup) out[np++] = (placement){n, pos[k]};
        }
    }
    return np;
}

typedef struct {
    lanes_rays R;
    lanes_boxes B, B1;
    lanes_triangles T, T1;
    lanes_tri_hits H, H2;
} buffers;

static bool ray_valid(const xray *x)
{
    bool ok = !isnan(x->tnear) && !isnan(x->tfar);
    for (int a = 0; a < 3; a++) ok = ok && isfinite(x->o[a]) && isfinite(x->d[a]);
    return ok && (x->d[0] != 0.0f || x->d[1] != 0.0f || x->d[2] != 0.0f);
}

/* The documented set-up: an invalid ray becomes [+inf, -inf], a valid one
 * keeps its ends with infinities clamped to ∓FLT_MAX. */
static void check_prepared(ctx *c, const char *path, const lane *l, float tnear, float tfar, size_t n,
                           size_t pos, size_t j)
{
    bool valid = ray_valid(&l->r);
    float wn = valid ? fmaxf(l->r.tnear, -FLT_MAX) : INFINITY, wf = valid ? fminf(l->r.tfar, FLT_MAX) : -INFINITY;
    check(c, !memcmp(&tnear, &wn, sizeof wn) && !memcmp(&tfar, &wf, sizeof wf), path, l->role,
          valid ? "valid ray changed" : "invalid ray not deactivated", &l->r,
          "n=%zu, case at %zu: lane %zu prepared to [%.9g, %.9g], expected [%.9g, %.9g]", n, pos, j, tnear, tfar,
          wn, wf);
}

static void put_ray(lanes_rays *R, size_t at, const xray *x)
{
    R->ox[at] = x->o[0], R->oy[at] = x->o[1], R->oz[at] = x->o[2];
    R->dx[at] = x->d[0], R->dy[at] = x->d[1], R->dz[at] = x->d[2];
    R->rdx[at] = R->rdy[at] = R->rdz[at] = 0.0f;
    R->tnear[at] = x->tnear, R->tfar[at] = x->tfar;
}

static lanes_ray single_ray(ctx *c, const lane *l, size_t n, size_t pos, size_t j)
{
    const xray *x = &l->r;
    lanes_ray r = {{x->o[0], x->o[1], x->o[2]}, {x->d[0], x->d[1], x->d[2]}, {0, 0, 0}, x->tnear, x->tfar};
    bool ok = lanes_ray_prepare_rcp(&r, c->p.rcp);
    check(c, ok == ray_valid(x), "lanes_ray_prepare_rcp", l->role, "return value", x,
          "n=%zu, case at %zu: lane %zu returned %d", n, pos, j, ok);
    check_prepared(c, "lanes_ray_prepare_rcp", l, r.tnear, r.tfar, n, pos, j);
    return r;
}

/* Lanes 0..n-1 at storage st(j) (j, or n-1-j through a reversed index
 * list), and copies of pad after them: prepared by the set itself, as a
 * kernel sees them; the pad would hit if a kernel read it unmasked. */
static void load_rays(ctx *c, buffers *b, const lane *L, size_t n, size_t pos, bool reversed,
                      const xray *pad, uint32_t *idx)
{
    for (size_t j = 0; j < n; j++) {
        size_t s = reversed ? n - 1 - j : j;
        put_ray(&b->R, s, &L[j].r);
        idx[j] = (uint32_t)s;
    }
    for (size_t j = n; j < n + LANES_MAX_W; j++) put_ray(&b->R, j, pad);
    b->R.count = n + LANES_MAX_W;
    c->k->rays_prepare(&b->R, c->p.rcp);
    b->R.count = n;
    for (size_t j = 0; j < n; j++) {
        size_t s = idx[j];
        check_prepared(c, "rays_prepare", &L[j], b->R.tnear[s], b->R.tfar[s], n, pos, j);
    }
}

/* ======================================================================== */
/* Boxes                                                                    */
/* ======================================================================== */

static bool box_empty(const lanes_box *b)
{
    return !(b->min[0] <= b->max[0] && b->min[1] <= b->max[1] && b->min[2] <= b->max[2]);
}

/* Ordinary rays for a packet against the box: from its centre (inside:
 * entry = tnear = 0), from below along z (entry fl(min.z - o.z), by
 * construction at least 1 away), and from beyond max.x pointing away. An
 * empty box gets rays that would hit it with min and max swapped back. */
static void box_ordinary(const lanes_box *b, lane out[3])
{
    for (int i = 0; i < 3; i++) memset(&out[i], 0, sizeof out[i]);
    if (box_empty(b)) {
        out[0].r = (xray)RAY(.5f, .5f, -1, 0, 0, 1);
        out[1].r = (xray)RAY(.5f, .5f, .5f, 0, 1, 0);
        out[2].r = (xray)RAY(-1e6f, .5f, .5f, 1, 0, 0);
        for (int i = 0; i < 3; i++) out[i].hit = MISS, out[i].t = NAN, out[i].role = "ordinary";
        return;
    }
    float c[3];
    for (int a = 0; a < 3; a++) c[a] = .5f * b->min[a] + .5f * b->max[a];
    float oz = b->min[2] - ((b->max[2] - b->min[2]) + 1.0f);
    float ox = b->max[0] + (fabsf(b->max[0]) + 1.0f);
    out[0] = (lane){RAY(c[0], c[1], c[2], 1, .5f, .25f), HIT, 0, NAN, NAN, false, false, 0, "ordinary (centre)"};
    out[1] = (lane){RAY(c[0], c[1], oz, 0, 0, 1), HIT, b->min[2] - oz, NAN, NAN, true, false, 0,
                    "ordinary (below)"};
    out[2] = (lane){RAY(ox, c[1], c[2], 1, 0, 0), MISS, NAN, NAN, NAN, false, false, 0, "ordinary (away)"};
}

static void set_box(lanes_boxes *B, size_t i, const lanes_box *b)
{
    B->minx[i] = b->min[0], B->miny[i] = b->min[1], B->minz[i] = b->min[2];
    B->maxx[i] = b->max[0], B->maxy[i] = b->max[1], B->maxz[i] = b->max[2];
}

static void box_packet_paths(ctx *c, buffers *b, const box_case *bc, const lane *L, size_t n, size_t pos,
                             const xray *pad)
{
    const lanes_kernels *k = c->k;
    uint32_t idx[MAXN], out[MAXN + WATCH], out2[MAXN + WATCH], inplace[MAXN];
    uint32_t hw[8], hw2[8];
    float te[MAXN + WATCH], te2[MAXN + WATCH];
    bool any_hit = false;
    for (size_t j = 0; j < n; j++) any_hit |= L[j].hit == HIT;
    for (int rev = 0; rev < 2; rev++) {
        const char *pk = rev ? "box_packet(idx)" : "box_packet";
        const char *pp = rev ? "box_partition(idx)" : "box_partition";
        load_rays(c, b, L, n, pos, rev, pad, idx);
        const uint32_t *ip = rev ? idx : NULL;

        for (int q = 0; q < 8; q++) hw[q] = hw2[q] = SENT_W;
        fill_sentinel(te, n + WATCH);
        fill_sentinel(te2, n + WATCH);
        size_t hits = k->box_packet(&b->R, ip, n, &bc->box, hw, te, NULL);
        lanes_lane_stats st = {0, 0, 0};
        size_t hits2 = k->box_packet(&b->R, ip, n, &bc->box, hw2, te2, &st);
        check(c, hits == hits2 && !memcmp(hw, hw2, sizeof hw) && !memcmp(te, te2, (n + WATCH) * sizeof *te),
              pk, "all", "counting copy differs", NULL, "n=%zu, case at %zu", n, pos);
        check_words(c, pk, hw, n, pos);
        size_t pop = 0;
        for (size_t j = 0; j < n; j++) {
            bool h = lanes_mask_get(hw, j);
            pop += h;
            check_lane(c, pk, &L[j], n, pos, j, h, te, NULL, NULL);
        }
        check(c, hits == pop, pk, "all", "return value", NULL, "n=%zu, case at %zu: returned %zu, %zu bits set", n,
              pos, hits, pop);
        check_untouched(c, pk, te, n, n + WATCH, n, pos, "tentry written");

        /* the partition keeps, in order, the entries of the hitting lanes */
        for (size_t j = 0; j < n + WATCH; j++) out[j] = out2[j] = SENT_W;
        size_t kept = k->box_partition(&b->R, ip, n, &bc->box, out, NULL);
        lanes_lane_stats st2 = {0, 0, 0};
        size_t kept2 = k->box_partition(&b->R, ip, n, &bc->box, out2, &st2);
        check(c, kept == kept2 && !memcmp(out, out2, (n + WATCH) * sizeof *out), pp, "all",
              "counting copy differs", NULL, "n=%zu, case at %zu", n, pos);
        size_t at = 0;
        bool order_ok = kept <= n;
        for (size_t j = 0; j < n && order_ok; j++) {
            uint32_t want = ip ? ip[j] : (uint32_t)j;
            bool got = at < kept && out[at] == want;
            at += got;
            check_lane(c, pp, &L[j], n, pos, j, got, NULL, NULL, NULL);
        }
        check(c, order_ok && at == kept, pp, "all", "entries not in order or not the lanes'",
              NULL, "n=%zu, case at %zu: kept %zu, matched %zu in order", n, pos, kept, at);
        for (size_t j = kept; j < n + WATCH && j < MAXN + WATCH; j++)
            if (!check(c, out[j] == SENT_W, pp, "past kept", "written",
                       NULL, "n=%zu, case at %zu: out[%zu] = %u written past the %zu kept", n, pos, j, out[j], kept))
                break;
        if (rev) {
            /* in place: out == idx */
            memcpy(inplace, idx, n * sizeof *idx);
            size_t kept3 = k->box_partition(&b->R, inplace, n, &bc->box, inplace, NULL);
            check(c, kept3 == kept && !memcmp(inplace, out, kept * sizeof *out), "box_partition(in place)",
                  "all", "differs from out-of-place", NULL, "n=%zu, case at %zu: kept %zu vs %zu", n, pos, kept3,
                  kept);
        }

        /* a frustum may cull only what no ray hits */
        if (any_hit) {
            lanes_frustum f;
            k->frustum_build(&b->R, ip, n, &f);
            set_box(&b->B1, 0, &bc->box);
            b->B1.count = 1;
            for (int m = LANES_CULL_INTERVAL; m <= LANES_CULL_BOTH; m++) {
                uint32_t keep[2] = {0, 0};
                k->frustum_boxes(&f, &b->B1, 1, (lanes_cull_method)m, keep, NULL);
                check(c, keep[0] & 1u, rev ? "frustum_boxes(idx)" : "frustum_boxes", "all", "culled a hit box",
                      NULL, "n=%zu, case at %zu: method %d culled the box some ray hits", n, pos, m);
            }
        }
    }
}

/* One ray against n boxes: the case's box in slot pos, and around it the
 * whole float range U (hit by every valid ray whose interval is not empty,
 * at tnear), an inverted box and an empty slot (never hit). The slots past
 * n hold U, which an unmasked lane would report. */
static void box_wide_path(ctx *c, buffers *b, const box_case *bc, size_t n, size_t pos)
{
    const lanes_box U = BOX(-FLT_MAX, -FLT_MAX, -FLT_MAX, FLT_MAX, FLT_MAX, FLT_MAX);
    const lanes_box E = BOX(1, 1, 1, 0, 0, 0);
    const lanes_box S = BOX(INF, INF, INF, -INF, -INF, -INF);
    const lanes_box *fill[3] = {&U, &E, &S};
    const lane cl = {bc->r, bc->hit[c->mode], bc->t, NAN, NAN, bc->rcp, false, 0, "case"};
    lanes_ray ray = single_ray(c, &cl, n, pos, pos);
    float tn = fmaxf(bc->r.tnear, -FLT_MAX), tf = fminf(bc->r.tfar, FLT_MAX);
    bool u_hit = ray_valid(&bc->r) && tn <= tf;
    lane L[MAXN];
    for (size_t j = 0; j < n + LANES_MAX_W; j++) {
        if (j == pos) {
            set_box(&b->B, j, &bc->box);
            L[j] = cl;
            continue;
        }
        int kind = j >= n ? 0 : (int)(j % 3);
        set_box(&b->B, j, fill[kind]);
        if (j < n)
            L[j] = (lane){bc->r, kind == 0 && u_hit ? HIT : MISS, tn > -1e29f ? tn : NAN, NAN, NAN, false,
                          false, 0, kind == 0 ? "box U" : kind == 1 ? "box inverted" : "box empty slot"};
    }
    b->B.count = n;
    uint32_t hw[8], hw2[8];
    float te[MAXN + WATCH], te2[MAXN + WATCH];
    for (int q = 0; q < 8; q++) hw[q] = hw2[q] = SENT_W;
    fill_sentinel(te, n + WATCH);
    fill_sentinel(te2, n + WATCH);
    size_t hits = c->k->box_wide(&ray, &b->B, n, hw, te, NULL);
    lanes_lane_stats st = {0, 0, 0};
    size_t hits2 = c->k->box_wide(&ray, &b->B, n, hw2, te2, &st);
    check(c, hits == hits2 && !memcmp(hw, hw2, sizeof hw) && !memcmp(te, te2, (n + WATCH) * sizeof *te),
          "box_wide", "all", "counting copy differs", NULL, "n=%zu, case at %zu", n, pos);
    check_words(c, "box_wide", hw, n, pos);
    size_t pop = 0;
    for (size_t j = 0; j < n; j++) {
        bool h = lanes_mask_get(hw, j);
        pop += h;
        check_lane(c, "box_wide", &L[j], n, pos, j, h, te, NULL, NULL);
    }
    check(c, hits == pop, "box_wide", "all", "return value", NULL, "n=%zu, case at %zu: returned %zu, %zu bits set",
          n, pos, hits, pop);
    check_untouched(c, "box_wide", te, n, n + WATCH, n, pos, "tentry written");
}

static void run_box_case(ctx *c, buffers *b, const box_case *bc)
{
    char ray[200];
    fmt_ray(ray, sizeof ray, &bc->r);
    c->cname = bc->name;
    snprintf(c->cray, sizeof c->cray, "%s", ray);
    snprintf(c->prim, sizeof c->prim, "box min=(%.9g, %.9g, %.9g) max=(%.9g, %.9g, %.9g)", bc->box.min[0],
             bc->box.min[1], bc->box.min[2], bc->box.max[0], bc->box.max[1], bc->box.max[2]);
    lane ord[3];
    box_ordinary(&bc->box, ord);
    placement pl[32];
    size_t np = placements(c->k->lanes, pl);
    for (size_t i = 0; i < np; i++) {
        size_t n = pl[i].n, pos = pl[i].pos;
        lane L[MAXN];
        for (size_t j = 0; j < n; j++)
            L[j] = j == pos ? (lane){bc->r, bc->hit[c->mode], bc->t, NAN, NAN, bc->rcp, false, 0, "case"}
                            : ord[j % 3];
        box_packet_paths(c, b, bc, L, n, pos, &ord[0].r);
        box_wide_path(c, b, bc, n, pos);
    }
}

/* ======================================================================== */
/* Triangles                                                                */
/* ======================================================================== */

/* The geometry around a triangle case, in double: the ordinary rays and
 * two filler triangles, placed so that no ray of one target can touch
 * another target. The fillers are right triangles in a plane x_kn = const
 * (kn the axis of the largest centroid coordinate), so a filler at 1e38
 * keeps its large coordinate constant and its edges small and exact: a
 * float test of a triangle whose edges are themselves near 1e35 would
 * overflow (its determinant is |d| * |e|^2), which is no kernel's fault. */
typedef struct {
    double C[3], n[3], h, size;
    bool area;
    int kn;                /* the fillers' normal axis */
    lanes_triangle fill[2];
    double F[2][3];        /* the fillers' first vertices */
    double aim[2][3], hF;  /* their (u, v) = (1/4, 1/2) points, and the ray offset */
} tri_geom;

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static void cross3(const double a[3], const double b[3], double r[3])
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}
static bool unit3(double a[3])
{
    double l = sqrt(dot3(a, a));
    if (!(l > 0) || !isfinite(l)) return false;
    for (int i = 0; i < 3; i++) a[i] /= l;
    return true;
}
static double maxabs3(const double a[3]) { return fmax(fabs(a[0]), fmax(fabs(a[1]), fabs(a[2]))); }

/* A unit vector perpendicular to a (a != 0). */
static void perp3(const double a[3], double r[3])
{
    int k = fabs(a[0]) <= fabs(a[1]) && fabs(a[0]) <= fabs(a[2]) ? 0 : fabs(a[1]) <= fabs(a[2]) ? 1 : 2;
    double ax[3] = {0, 0, 0};
    ax[k] = 1;
    cross3(a, ax, r);
    unit3(r);
}

static void tri_geometry(const tri_case *tc, tri_geom *g)
{
    const float *v[3] = {tc->tri.v0, tc->tri.v1, tc->tri.v2};
    double e1[3], e2[3];
    g->size = 0;
    for (int a = 0; a < 3; a++) {
        g->C[a] = ((double)v[0][a] + v[1][a] + v[2][a]) / 3.0;
        e1[a] = (double)v[1][a] - v[0][a];
        e2[a] = (double)v[2][a] - v[0][a];
    }
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double d[3] = {(double)v[i][0] - v[j][0], (double)v[i][1] - v[j][1], (double)v[i][2] - v[j][2]};
            g->size = fmax(g->size, sqrt(dot3(d, d)));
        }
    /* the case ray with its non-finite parts replaced, for distances only */
    double o[3], d[3];
    for (int a = 0; a < 3; a++) {
        o[a] = isfinite(tc->r.o[a]) ? tc->r.o[a] : 0.0;
        d[a] = isfinite(tc->r.d[a]) ? tc->r.d[a] : 0.0;
    }
    if (!unit3(d)) d[0] = 0, d[1] = 0, d[2] = 1;
    cross3(e1, e2, g->n);
    g->area = unit3(g->n);
    if (!g->area) perp3(d, g->n); /* any direction: the ray must miss anyway */
    double co[3] = {g->C[0] - o[0], g->C[1] - o[1], g->C[2] - o[2]}, x[3];
    cross3(co, d, x);
    double delta = sqrt(dot3(x, x)); /* distance of C from the case ray's line */
    /* an offset of at least 1e-3 of the coordinates, so float rounding of
     * the ordinary rays' origins stays well inside their 1e-3 tolerance */
    g->h = fmax(fmax(g->size, 1e-3 * maxabs3(g->C)), 1e-3);

    /* The fillers sit at C ± R along an axis ke far from parallel to both
     * the case ray and the normal (the ordinary rays' direction), so both
     * lines pass at least R * sin from them; some axis has sin^2 >= 1/3
     * for both, and the largest-coordinate axis kn is preferred as the
     * fillers' normal. */
    int order[3] = {0, 1, 2};
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++)
            if (fabs(g->C[order[j]]) > fabs(g->C[order[i]])) {
                int t = order[i];
                order[i] = order[j], order[j] = t;
            }
    int kn = order[0], ke = (kn + 1) % 3;
    double best = -1;
    for (int i = 0; i < 3; i++)
        for (int ax = 0; ax < 3; ax++) {
            if (ax == order[i]) continue;
            double sc = fmin(1 - d[ax] * d[ax], 1 - g->n[ax] * g->n[ax]);
            if (sc > best + (i == 0 ? 0 : 0.2)) best = sc, kn = order[i], ke = ax;
        }
    double sin_ = sqrt(fmax(best, 1e-6));
    int kb = (kn + 1) % 3, kc = (kn + 2) % 3;
    double s = fmax(1.0, g->size);
    double R = 2 * (delta + g->size + 4 * s + 1) / sin_;
    /* legs resolvable where the fillers are: many ulps of their coordinates */
    s = fmax(s, 0x1p-12 * (fmax(fabs(g->C[kb]), fabs(g->C[kc])) + R));
    R = 2 * (delta + g->size + 4 * s + 1) / sin_;
    g->kn = kn;
    g->hF = 0;
    for (int f = 0; f < 2; f++) {
        double *F = g->F[f];
        for (int a = 0; a < 3; a++) F[a] = g->C[a];
        F[ke] += f ? -R : R;
        float *fv[3] = {g->fill[f].v0, g->fill[f].v1, g->fill[f].v2};
        for (int a = 0; a < 3; a++) fv[0][a] = fv[1][a] = fv[2][a] = (float)F[a];
        fv[1][kb] = (float)(F[kb] + s);
        fv[2][kc] = (float)(F[kc] + s);
        for (int a = 0; a < 3; a++) g->aim[f][a] = F[a];
        g->aim[f][kb] += s / 4, g->aim[f][kc] += s / 2;
        g->hF = fmax(g->hF, fmax(s, 1e-3 * maxabs3(g->aim[f])));
    }
}

static xray ray_from(const double o[3], const double d[3], float tfar)
{
    xray r = {{(float)o[0], (float)o[1], (float)o[2]}, {(float)d[0], (float)d[1], (float)d[2]}, 0.0f, tfar};
    return r;
}

/* Ordinary rays: 0 toward the case triangle's centroid along -n (a hit at
 * t = 1, u = v = 1/3, unless it is degenerate), 1 from the same point away
 * from it, 2 and 3 along -kn toward the fillers' (1/4, 1/2) points (hits
 * in traversals, misses against the case triangle). tfar = 2 keeps each
 * segment near its own target. */
static void tri_ordinary(const tri_geom *g, lane out[4])
{
    double o[3], d[3];
    for (int a = 0; a < 3; a++) o[a] = g->C[a] + g->h * g->n[a], d[a] = -g->h * g->n[a];
    const float third = 1.0f / 3.0f;
    out[0] = (lane){ray_from(o, d, 2.0f), g->area ? HIT : MISS, 1, third, third, false, true, 0, "ordinary (at it)"};
    for (int a = 0; a < 3; a++) d[a] = -d[a];
    out[1] = (lane){ray_from(o, d, 2.0f), MISS, NAN, NAN, NAN, false, true, 0, "ordinary (away)"};
    for (int f = 0; f < 2; f++) {
        for (int a = 0; a < 3; a++) o[a] = g->aim[f][a], d[a] = 0;
        o[g->kn] += g->hF;
        d[g->kn] = -g->hF;
        out[2 + f] = (lane){ray_from(o, d, 2.0f), MISS, 1, .25f, .5f, false, true, 1u + (uint32_t)f,
                            f ? "ordinary (filler 2)" : "ordinary (filler 1)"};
    }
}

static void set_tri(lanes_triangles *T, size_t i, const lanes_triangle *t)
{
    T->v0x[i] = t->v0[0], T->v0y[i] = t->v0[1], T->v0z[i] = t->v0[2];
    T->v1x[i] = t->v1[0], T->v1y[i] = t->v1[1], T->v1z[i] = t->v1[2];
    T->v2x[i] = t->v2[0], T->v2y[i] = t->v2[1], T->v2z[i] = t->v2[2];
}

static void tri_packet_paths(ctx *c, buffers *b, const tri_case *tc, const lane *L, size_t n, size_t pos,
                             const xray *pad)
{
    const lanes_kernels *k = c->k;
    const lanes_tri_algo algo = c->p.algo;
    uint32_t idx[MAXN], hw[8], hw2[8];
    bool any_hit = false;
    for (size_t j = 0; j < n; j++) any_hit |= L[j].hit == HIT;
    for (int rev = 0; rev < 2; rev++) {
        const char *pt = rev ? "tri_packet(idx)" : "tri_packet";
        const char *pa = rev ? "tri_packet_any(idx)" : "tri_packet_any";
        load_rays(c, b, L, n, pos, rev, pad, idx);
        const uint32_t *ip = rev ? idx : NULL;
        lanes_tri_hits *H = &b->H, *H2 = &b->H2;
        for (int q = 0; q < 8; q++) hw[q] = hw2[q] = SENT_W;
        fill_sentinel(H->t, n + WATCH), fill_sentinel(H->u, n + WATCH), fill_sentinel(H->v, n + WATCH);
        fill_sentinel(H2->t, n + WATCH), fill_sentinel(H2->u, n + WATCH), fill_sentinel(H2->v, n + WATCH);
        size_t hits = k->tri_packet[algo](&b->R, ip, n, &tc->tri, hw, H, NULL);
        lanes_lane_stats st = {0, 0, 0};
        size_t hits2 = k->tri_packet[algo](&b->R, ip, n, &tc->tri, hw2, H2, &st);
        check(c, hits == hits2 && !memcmp(hw, hw2, sizeof hw) &&
                     !memcmp(H->t, H2->t, (n + WATCH) * sizeof(float)) &&
                     !memcmp(H->u, H2->u, (n + WATCH) * sizeof(float)) &&
                     !memcmp(H->v, H2->v, (n + WATCH) * sizeof(float)),
              pt, "all", "counting copy differs", NULL, "n=%zu, case at %zu", n, pos);
        check_words(c, pt, hw, n, pos);
        size_t pop = 0;
        for (size_t j = 0; j < n; j++) {
            bool h = lanes_mask_get(hw, j);
            pop += h;
            check_lane(c, pt, &L[j], n, pos, j, h, H->t, H->u, H->v);
        }
        check(c, hits == pop, pt, "all", "return value", NULL, "n=%zu, case at %zu: returned %zu, %zu bits set", n,
              pos, hits, pop);
        check_untouched(c, pt, H->t, n, n + WATCH, n, pos, "t written");
        check_untouched(c, pt, H->u, n, n + WATCH, n, pos, "u written");
        check_untouched(c, pt, H->v, n, n + WATCH, n, pos, "v written");

        for (int q = 0; q < 8; q++) hw[q] = SENT_W;
        size_t anyh = k->tri_packet_any[algo](&b->R, ip, n, &tc->tri, hw, NULL);
        check_words(c, pa, hw, n, pos);
        pop = 0;
        for (size_t j = 0; j < n; j++) {
            bool h = lanes_mask_get(hw, j);
            pop += h;
            check_lane(c, pa, &L[j], n, pos, j, h, NULL, NULL, NULL);
        }
        check(c, anyh == pop, pa, "all", "return value", NULL, "n=%zu, case at %zu: returned %zu, %zu bits set", n,
              pos, anyh, pop);

        if (any_hit) {
            lanes_frustum f;
            k->frustum_build(&b->R, ip, n, &f);
            set_tri(&b->T1, 0, &tc->tri);
            b->T1.count = 1;
            for (int m = LANES_CULL_INTERVAL; m <= LANES_CULL_BOTH; m++) {
                uint32_t keep[2] = {0, 0};
                k->frustum_tris(&f, &b->T1, 1, (lanes_cull_method)m, keep, NULL);
                check(c, keep[0] & 1u, rev ? "frustum_tris(idx)" : "frustum_tris", "all",
                      "culled a hit triangle", NULL, "n=%zu, case at %zu: method %d culled the triangle some ray hits",
                      n, pos, m);
            }
        }
    }
}

/* One ray against n triangles: the case's in slot pos, fillers (and a
 * point triangle at a filler's centre) around it, none of which the ray
 * can touch; past n, copies of the case's triangle, which an unmasked lane
 * would report whenever the case hits. */
static void tri_wide_paths(ctx *c, buffers *b, const tri_case *tc, const tri_geom *g, size_t n, size_t pos)
{
    const lanes_kernels *k = c->k;
    const lanes_tri_algo algo = c->p.algo;
    lanes_triangle point;
    for (int a = 0; a < 3; a++) point.v0[a] = point.v1[a] = point.v2[a] = (float)g->F[0][a];
    const lanes_triangle *fill[3] = {&g->fill[0], &g->fill[1], &point};
    const lane cl = {tc->r, tc->hit[c->mode], tc->t, tc->u, tc->v, false, false, 0, "case"};
    lanes_ray ray = single_ray(c, &cl, n, pos, pos);
    lane L[MAXN];
    for (size_t j = 0; j < n + LANES_MAX_W; j++) {
        if (j == pos || j >= n) {
            set_tri(&b->T, j, &tc->tri);
            if (j < n) L[j] = cl;
            continue;
        }
        set_tri(&b->T, j, fill[j % 3]);
        L[j] = (lane){tc->r, MISS, NAN, NAN, NAN, false, false, 0, j % 3 == 2 ? "point filler" : "filler"};
    }
    b->T.count = n;
    uint32_t hw[8], hw2[8];
    lanes_tri_hits *H = &b->H, *H2 = &b->H2;
    for (int q = 0; q < 8; q++) hw[q] = hw2[q] = SENT_W;
    fill_sentinel(H->t, n + WATCH), fill_sentinel(H->u, n + WATCH), fill_sentinel(H->v, n + WATCH);
    fill_sentinel(H2->t, n + WATCH), fill_sentinel(H2->u, n + WATCH), fill_sentinel(H2->v, n + WATCH);
    size_t hits = k->tri_wide[algo](&ray, &b->T, n, hw, H, NULL);
    lanes_lane_stats st = {0, 0, 0};
    size_t hits2 = k->tri_wide[algo](&ray, &b->T, n, hw2, H2, &st);
    check(c, hits == hits2 && !memcmp(hw, hw2, sizeof hw) && !memcmp(H->t, H2->t, (n + WATCH) * sizeof(float)) &&
                 !memcmp(H->u, H2->u, (n + WATCH) * sizeof(float)) &&
                 !memcmp(H->v, H2->v, (n + WATCH) * sizeof(float)),
          "tri_wide", "all", "counting copy differs", NULL, "n=%zu, case at %zu", n, pos);
    check_words(c, "tri_wide", hw, n, pos);
    size_t pop = 0;
    for (size_t j = 0; j < n; j++) {
        bool h = lanes_mask_get(hw, j);
        pop += h;
        check_lane(c, "tri_wide", &L[j], n, pos, j, h, H->t, H->u, H->v);
    }
    check(c, hits == pop, "tri_wide", "all", "return value", NULL, "n=%zu, case at %zu: returned %zu, %zu bits set", n,
          pos, hits, pop);
    check_untouched(c, "tri_wide", H->t, n, n + WATCH, n, pos, "t written");

    /* closest and any: only the case's slot can answer */
    float t = sentinel(), u = sentinel(), v = sentinel();
    long got = k->tri_wide_closest[algo](&ray, &b->T, n, &t, &u, &v, NULL);
    float t2 = sentinel(), u2 = sentinel(), v2 = sentinel();
    lanes_lane_stats st2 = {0, 0, 0};
    long got2 = k->tri_wide_closest[algo](&ray, &b->T, n, &t2, &u2, &v2, &st2);
    check(c, got == got2 && !memcmp(&t, &t2, sizeof t) && !memcmp(&u, &u2, sizeof u) && !memcmp(&v, &v2, sizeof v),
          "tri_wide_closest", "all", "counting copy differs", NULL, "n=%zu, case at %zu", n, pos);
    check(c, got == -1 || got == (long)pos, "tri_wide_closest", "case", "index",
          NULL, "n=%zu, case at %zu: returned %ld", n, pos, got);
    {
        lane one = L[pos];
        float tv[1] = {t}, uv[1] = {u}, vv[1] = {v};
        check_lane(c, "tri_wide_closest", &one, n, pos, 0, got == (long)pos, tv, uv, vv);
    }
    bool any = k->tri_wide_any[algo](&ray, &b->T, n, NULL);
    lanes_lane_stats st3 = {0, 0, 0};
    bool any2 = k->tri_wide_any[algo](&ray, &b->T, n, &st3);
    check(c, any == any2, "tri_wide_any", "all", "counting copy differs", NULL, "n=%zu, case at %zu", n, pos);
    check_lane(c, "tri_wide_any", &L[pos], n, pos, pos, any, NULL, NULL, NULL);
}

/* ======================================================================== */
/* Traversals on a tiny scene: the case's triangle (0) and the fillers     */
/* ======================================================================== */

enum { LEAF_SIZES = 2 };
static const int leaf_sizes[LEAF_SIZES] = {1, 4};

typedef struct {
    lanes_bvh2 bvh[LEAF_SIZES];
    lanes_wbvh wide[LEAF_SIZES][3];
    bool ok;
} tiny_scene;

static bool build_tiny(const tri_case *tc, const tri_geom *g, tiny_scene *s)
{
    memset(s, 0, sizeof *s);
    lanes_scene sc;
    lanes_error err;
    lanes_scene_init(&sc);
    const lanes_triangle *t[3] = {&tc->tri, &g->fill[0], &g->fill[1]};
    for (int i = 0; i < 3; i++) {
        float v[9];
        memcpy(v, t[i]->v0, sizeof t[i]->v0);
        memcpy(v + 3, t[i]->v1, sizeof t[i]->v1);
        memcpy(v + 6, t[i]->v2, sizeof t[i]->v2);
        if (lanes_scene_add_triangle(&sc, v, 0, &err) != LANES_OK) {
            printf("FAIL: %s: cannot add a triangle: %s\n", tc->name, err.message);
            lanes_scene_free(&sc);
            return false;
        }
    }
    for (int l = 0; l < LEAF_SIZES; l++) {
        lanes_bvh_build_options bo;
        lanes_bvh_default_options(&bo);
        bo.max_leaf_size = leaf_sizes[l];
        bo.threads = 1;
        if (lanes_bvh2_build(&sc, &bo, &s->bvh[l], &err) != LANES_OK) {
            printf("FAIL: %s: BVH2: %s\n", tc->name, err.message);
            lanes_scene_free(&sc);
            return false;
        }
        for (int w = 0; w < 3; w++)
            if (lanes_wbvh_from_bvh2(&s->bvh[l], 4 << w, &s->wide[l][w], &err) != LANES_OK) {
                printf("FAIL: %s: %d-wide BVH: %s\n", tc->name, 4 << w, err.message);
                lanes_scene_free(&sc);
                return false;
            }
    }
    lanes_scene_free(&sc);
    s->ok = true;
    return true;
}

static void free_tiny(tiny_scene *s)
{
    for (int l = 0; l < LEAF_SIZES; l++) {
        for (int w = 0; w < 3; w++) lanes_wbvh_free(&s->wide[l][w]);
        lanes_bvh2_free(&s->bvh[l]);
    }
}

static void check_hit(ctx *c, const char *path, const lane *l, size_t n, size_t pos, size_t j, const lanes_hit *h)
{
    bool got = h->prim != LANES_NO_HIT;
    if (!check(c, l->hit == EITHER || got == (l->hit == HIT), path, l->role, "hit", &l->r,
               "n=%zu, case at %zu: ray %zu expected %s, got %s (prim %d t=%.9g)", n, pos, j, exp_name(l->hit),
               got ? "hit" : "miss", got ? (int)h->prim : -1, h->t))
        return;
    if (!got) return;
    check(c, h->prim == l->prim, path, l->role, "prim", &l->r, "n=%zu, case at %zu: ray %zu hit prim %u, expected %u",
          n, pos, j, h->prim, l->prim);
    const float gv[3] = {h->t, h->u, h->v}, want[3] = {l->t, l->u, l->v};
    const char *names[3] = {"t", "u", "v"};
    for (int q = 0; q < 3; q++)
        check(c, close_to(c, gv[q], want[q], false, l->approx), path, l->role, names[q], &l->r,
              "n=%zu, case at %zu: ray %zu %s=%.9g (%a), expected %.9g (%a)", n, pos, j, names[q], gv[q], gv[q],
              want[q], want[q]);
}

static void check_occ(ctx *c, const char *path, const lane *l, size_t n, size_t pos, size_t j, uint8_t occ)
{
    check(c, l->hit == EITHER || (occ != 0) == (l->hit == HIT), path, l->role, "occluded", &l->r,
          "n=%zu, case at %zu: ray %zu expected %s, got occluded=%d", n, pos, j, exp_name(l->hit), occ);
}

static void single_ray_traversals(ctx *c, const tiny_scene *s, const lane *L, size_t n, size_t pos)
{
    const lanes_kernels *k = c->k;
    lanes_ray rays[MAXN];
    lanes_hit hits[MAXN];
    uint8_t occ[MAXN];
    for (size_t j = 0; j < n; j++) rays[j] = single_ray(c, &L[j], n, pos, j);
    int slot = k->wide_width == 4 ? 0 : k->wide_width == 8 ? 1 : 2;
    for (int l = 0; l < LEAF_SIZES; l++) {
        char pw[40], po[40], pb[40], pob[40];
        snprintf(pw, sizeof pw, "trace_wide(leaf %d)", leaf_sizes[l]);
        snprintf(po, sizeof po, "occluded_wide(leaf %d)", leaf_sizes[l]);
        snprintf(pb, sizeof pb, "trace_bvh2(leaf %d)", leaf_sizes[l]);
        snprintf(pob, sizeof pob, "occluded_bvh2(leaf %d)", leaf_sizes[l]);
        k->trace_wide(&s->wide[l][slot], c->mode, rays, n, hits, NULL);
        for (size_t j = 0; j < n; j++) check_hit(c, pw, &L[j], n, pos, j, &hits[j]);
        memset(occ, SENT_OCC, sizeof occ);
        k->occluded_wide(&s->wide[l][slot], c->mode, rays, n, occ, NULL);
        for (size_t j = 0; j < n; j++) check_occ(c, po, &L[j], n, pos, j, occ[j]);
        for (size_t j = n; j < MAXN; j++)
            if (!check(c, occ[j] == SENT_OCC, po, "past n", "written", NULL, "n=%zu, case at %zu: occluded[%zu] written",
                       n, pos, j))
                break;
        k->trace_bvh2(&s->bvh[l], c->mode, rays, n, hits, NULL);
        for (size_t j = 0; j < n; j++) check_hit(c, pb, &L[j], n, pos, j, &hits[j]);
        memset(occ, SENT_OCC, sizeof occ);
        k->occluded_bvh2(&s->bvh[l], c->mode, rays, n, occ, NULL);
        for (size_t j = 0; j < n; j++) check_occ(c, pob, &L[j], n, pos, j, occ[j]);
    }
}

/* trace_packet: closest hit (tfar shrinks to t, prim/u/v written for hits
 * only) and occlusion (occluded = 1 and tfar = -inf for hits only), by
 * partition and ranged traversal, and partition with the packet frustum,
 * the corner test and leaf frusta. The rays past n are copies of the first
 * ordinary ray, which hits: nothing of theirs may change. */
static void packet_traversals(ctx *c, buffers *b, const tiny_scene *s, const lane *L, size_t n, size_t pos,
                              const xray *pad)
{
    const lanes_kernels *k = c->k;
    uint32_t idx[MAXN], prim[MAXN + WATCH];
    float u[MAXN + WATCH], v[MAXN + WATCH], tfar0[MAXN + WATCH];
    uint8_t occ[MAXN + WATCH];
    static const char *const scheme_names[3] = {"partition", "ranged", "partition+frustum"};
    for (int l = 0; l < LEAF_SIZES; l++)
        for (int sch = 0; sch < 3; sch++)
            for (int occl = 0; occl < 2; occl++) {
                char path[80];
                snprintf(path, sizeof path, "trace_packet(%s, %s, leaf %d)", scheme_names[sch],
                         occl ? "occlusion" : "closest", leaf_sizes[l]);
                load_rays(c, b, L, n, pos, false, pad, idx);
                memcpy(tfar0, b->R.tfar, (n + WATCH) * sizeof *tfar0);
                for (size_t j = 0; j < n + WATCH; j++) prim[j] = j < n ? LANES_NO_HIT : SENT_PRIM;
                fill_sentinel(u, n + WATCH);
                fill_sentinel(v, n + WATCH);
                memset(occ, SENT_OCC, sizeof occ);
                lanes_frustum f;
                if (sch == 2) k->frustum_build(&b->R, NULL, n, &f);
                lanes_packet_options po = {.scheme = sch == 1 ? LANES_PACKET_RANGED : LANES_PACKET_PARTITION,
                                           .accuracy = c->mode,
                                           .frustum = sch == 2 ? &f : NULL,
                                           .corner_test = sch == 2,
                                           .leaf_frustum = sch == 2,
                                           .occlusion = occl != 0};
                if (occl)
                    k->trace_packet(&s->bvh[l], &po, &b->R, NULL, NULL, NULL, occ, NULL);
                else
                    k->trace_packet(&s->bvh[l], &po, &b->R, prim, u, v, occ, NULL);
                for (size_t j = 0; j < n; j++) {
                    const lane *ln = &L[j];
                    float tf = b->R.tfar[j];
                    if (occl) {
                        bool got = occ[j] == 1;
                        if (!check(c, occ[j] == 1 || occ[j] == SENT_OCC, path, ln->role, "occluded value", &ln->r,
                                   "n=%zu, case at %zu: ray %zu occluded=%d", n, pos, j, occ[j]))
                            continue;
                        if (!check(c, ln->hit == EITHER || got == (ln->hit == HIT), path, ln->role, "occluded",
                                   &ln->r, "n=%zu, case at %zu: ray %zu expected %s, got %s", n, pos, j,
                                   exp_name(ln->hit), got ? "occluded" : "clear"))
                            continue;
                        check(c, got ? tf == -INFINITY : !memcmp(&tf, &tfar0[j], sizeof tf), path, ln->role, "tfar",
                              &ln->r, "n=%zu, case at %zu: ray %zu tfar=%.9g after %s (before %.9g)", n, pos, j, tf,
                              got ? "a hit (expected -inf)" : "a miss (expected unchanged)", tfar0[j]);
                        continue;
                    }
                    lanes_hit h = {tf, u[j], v[j], prim[j]};
                    check_hit(c, path, ln, n, pos, j, &h);
                    if (prim[j] == LANES_NO_HIT)
                        check(c, !memcmp(&tf, &tfar0[j], sizeof tf) && is_sentinel(u[j]) && is_sentinel(v[j]), path,
                              ln->role, "written for a miss", &ln->r,
                              "n=%zu, case at %zu: ray %zu missed but tfar=%.9g (was %.9g) u=%.9g v=%.9g", n, pos, j,
                              tf, tfar0[j], u[j], v[j]);
                }
                for (size_t j = n; j < n + WATCH; j++) {
                    bool same = !memcmp(&b->R.tfar[j], &tfar0[j], sizeof(float)) && occ[j] == SENT_OCC &&
                                (occl || (prim[j] == SENT_PRIM && is_sentinel(u[j]) && is_sentinel(v[j])));
                    if (!check(c, same, path, "past n", "written",
                               NULL, "n=%zu, case at %zu: element %zu written (tfar %.9g, prim 0x%x, occluded %d)", n, pos,
                               j, b->R.tfar[j], prim[j], occ[j]))
                        break;
                }
            }
}

static void run_tri_case(ctx *c, buffers *b, const tri_case *tc, const tri_geom *g, const tiny_scene *s)
{
    char ray[200];
    fmt_ray(ray, sizeof ray, &tc->r);
    c->cname = tc->name;
    snprintf(c->cray, sizeof c->cray, "%s", ray);
    snprintf(c->prim, sizeof c->prim, "triangle (%.9g, %.9g, %.9g) (%.9g, %.9g, %.9g) (%.9g, %.9g, %.9g)",
             tc->tri.v0[0], tc->tri.v0[1], tc->tri.v0[2], tc->tri.v1[0], tc->tri.v1[1], tc->tri.v1[2],
             tc->tri.v2[0], tc->tri.v2[1], tc->tri.v2[2]);
    lane ord[4];
    tri_ordinary(g, ord);
    int trav = tc->trav[c->mode] == SAME ? tc->hit[c->mode] : tc->trav[c->mode];
    placement pl[32];
    size_t np = placements(c->k->lanes, pl);
    for (size_t i = 0; i < np; i++) {
        size_t n = pl[i].n, pos = pl[i].pos;
        lane L[MAXN];
        /* against the case's triangle alone, the fillers' rays miss */
        for (size_t j = 0; j < n; j++)
            L[j] = j == pos ? (lane){tc->r, tc->hit[c->mode], tc->t, tc->u, tc->v, false, false, 0, "case"}
                            : ord[j % 4];
        for (size_t j = 0; j < n; j++)
            if (j != pos && j % 4 >= 2) L[j].hit = MISS;
        tri_packet_paths(c, b, tc, L, n, pos, &ord[0].r);
        tri_wide_paths(c, b, tc, g, n, pos);
        if (!s->ok) continue;
        /* in the scene, the fillers' rays hit their fillers */
        for (size_t j = 0; j < n; j++) L[j] = j == pos ? L[j] : ord[j % 4];
        for (size_t j = 0; j < n; j++)
            if (j != pos && j % 4 >= 2) L[j].hit = HIT;
        L[pos].hit = trav;
        single_ray_traversals(c, s, L, n, pos);
        packet_traversals(c, b, s, L, n, pos, &ord[0].r);
    }
}

/* ======================================================================== */
/* Driver                                                                   */
/* ======================================================================== */

typedef struct {
    box_case *boxes;
    size_t nbox;
    tri_case *tris;
    size_t ntri;
    char (*names)[160];
} case_list;

/* The hand-written cases followed by every injection into every base. */
static void make_cases(case_list *cl)
{
    size_t nb = sizeof box_cases / sizeof box_cases[0], nt = sizeof tri_cases / sizeof tri_cases[0];
    size_t ni = sizeof injections / sizeof injections[0];
    size_t nbb = sizeof box_bases / sizeof box_bases[0], ntb = sizeof tri_bases / sizeof tri_bases[0];
    cl->nbox = nb + ni * nbb;
    cl->ntri = nt + ni * ntb;
    cl->boxes = malloc(cl->nbox * sizeof *cl->boxes);
    cl->tris = malloc(cl->ntri * sizeof *cl->tris);
    cl->names = malloc((ni * (nbb + ntb)) * sizeof *cl->names);
    if (!cl->boxes || !cl->tris || !cl->names) {
        printf("out of memory\n");
        exit(1);
    }
    memcpy(cl->boxes, box_cases, sizeof box_cases);
    memcpy(cl->tris, tri_cases, sizeof tri_cases);
    size_t nn = 0;
    for (size_t bi = 0; bi < nbb; bi++)
        for (size_t i = 0; i < ni; i++) {
            const injection *in = &injections[i];
            box_case bc = box_bases[bi];
            inject(&bc.r, in);
            snprintf(cl->names[nn], sizeof cl->names[nn], "%s=%g, ray %s", field_names[in->field], in->value,
                     box_bases[bi].name);
            bc.name = cl->names[nn++];
            for (int m = 0; m < LANES_ACCURACY_COUNT; m++) bc.hit[m] = in->hit;
            /* tentry = max(tnear, entry): with tnear = -inf, a tentry that
             * was tnear becomes the (negative) entry */
            if (in->hit == MISS || (in->field == 6 && !bc.rcp)) bc.t = NAN;
            cl->boxes[nb + bi * ni + i] = bc;
        }
    for (size_t ti = 0; ti < ntb; ti++)
        for (size_t i = 0; i < ni; i++) {
            const injection *in = &injections[i];
            tri_case tc = tri_bases[ti];
            inject(&tc.r, in);
            snprintf(cl->names[nn], sizeof cl->names[nn], "%s=%g, ray %s", field_names[in->field], in->value,
                     tri_bases[ti].name);
            tc.name = cl->names[nn++];
            for (int m = 0; m < LANES_ACCURACY_COUNT; m++) tc.hit[m] = in->hit;
            if (in->hit == MISS) tc.t = tc.u = tc.v = NAN;
            cl->tris[nt + ti * ni + i] = tc;
        }
}

int main(int argc, char **argv)
{
    setvbuf(stdout, NULL, _IOLBF, 0);
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--all") == 0) {
            print_all = true;
        } else {
            printf("usage: test_extremes [--all]\n");
            return 2;
        }
    }
    case_list cl;
    make_cases(&cl);

    buffers b;
    if (!lanes_rays_alloc(&b.R, MAXN) || !lanes_boxes_alloc(&b.B, MAXN) || !lanes_boxes_alloc(&b.B1, 1) ||
        !lanes_triangles_alloc(&b.T, MAXN) || !lanes_triangles_alloc(&b.T1, 1) ||
        !lanes_tri_hits_alloc(&b.H, MAXN + WATCH) || !lanes_tri_hits_alloc(&b.H2, MAXN + WATCH)) {
        printf("out of memory\n");
        return 1;
    }
    /* the geometry and scene of each triangle case, shared by every set */
    tri_geom *geo = malloc(cl.ntri * sizeof *geo);
    tiny_scene *scenes = malloc(cl.ntri * sizeof *scenes);
    if (!geo || !scenes) {
        printf("out of memory\n");
        return 1;
    }
    int setup_failures = 0;
    for (size_t i = 0; i < cl.ntri; i++) {
        tri_geometry(&cl.tris[i], &geo[i]);
        setup_failures += !build_tiny(&cl.tris[i], &geo[i], &scenes[i]);
    }

    printf("extremes: %zu box cases, %zu triangle cases (%zu of each hand-written, the rest NaN/Inf "
           "injections)\nsets:",
           cl.nbox, cl.ntri, sizeof box_cases / sizeof box_cases[0]);
    for (int i = 0; i < LANES_ISA_COUNT; i++)
        if (lanes_isa_supported((lanes_isa)i) && lanes_kernels_for((lanes_isa)i))
            printf(" %s", lanes_isa_name((lanes_isa)i));
    printf("\n");
    long total = 0, failed = 0;
    int sets = 0;
    for (int i = 0; i < LANES_ISA_COUNT; i++) {
        lanes_isa isa = (lanes_isa)i;
        const lanes_kernels *k = lanes_kernels_for(isa);
        if (!k || !lanes_isa_supported(isa)) continue;
        sets++;
        for (int m = 0; m < LANES_ACCURACY_COUNT; m++) {
            ctx c;
            memset(&c, 0, sizeof c);
            c.k = k;
            c.mode = (lanes_accuracy)m;
            c.p = lanes_accuracy_precision(c.mode);
            for (size_t j = 0; j < cl.nbox; j++) run_box_case(&c, &b, &cl.boxes[j]);
            for (size_t j = 0; j < cl.ntri; j++) run_tri_case(&c, &b, &cl.tris[j], &geo[j], &scenes[j]);
            printf("%-10s %-7s (W=%2d): %8ld checks, %ld failed\n", k->name, mode_name(c.mode), k->lanes,
                   c.checks, c.fails);
            total += c.checks;
            failed += c.fails;
        }
    }
    if (nfailures) {
        printf("\n%zu distinct failing checks (placements that failed in parentheses):\n", nfailures);
        for (size_t i = 0; i < nfailures; i++)
            printf("FAIL %s (%ld)\n     %s\n     case ray %s\n     %s\n", failures[i].key, failures[i].count,
                   failures[i].detail, failures[i].cray, failures[i].prim);
    }
    printf("\nextremes: %d sets x %d modes, %ld checks, %ld failed%s\n", sets, LANES_ACCURACY_COUNT, total,
           failed, setup_failures ? ", and scene set-up failed" : "");

    for (size_t i = 0; i < cl.ntri; i++) free_tiny(&scenes[i]);
    free(scenes), free(geo);
    free(cl.boxes), free(cl.tris), free(cl.names);
    free(failures);
    lanes_rays_free(&b.R);
    lanes_boxes_free(&b.B), lanes_boxes_free(&b.B1);
    lanes_triangles_free(&b.T), lanes_triangles_free(&b.T1);
    lanes_tri_hits_free(&b.H), lanes_tri_hits_free(&b.H2);
    return failed || setup_failures || sets == 0 ? 1 : 0;
}
