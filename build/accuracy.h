/* Accuracy modes: what a user trades between speed and exactness.
 *
 *   fast     approximate reciprocal directions (hardware estimate plus one
 *            Newton step), Möller–Trumbore, box slabs in the wide traversal
 *            as one FMA on the ray's precomputed o * (1/d) (whose rounding
 *            grows with |o|: far from the origin it loses a few more boxes a
 *            ray grazes), box exits not widened, secondary origins pushed off
 *            the surface by the scene epsilon.
 *   default  exact reciprocals (division), Möller–Trumbore, box exits not
 *            widened, the scene epsilon. Epsilon policy: a triangle is hit
 *            iff its determinant is not exactly 0 and tnear <= t <= tfar, with
 *            no tolerance on the barycentrics (rays through a shared edge may
 *            miss both triangles: that is what "leaks" count); secondary rays
 *            start at tnear = 0 from the barycentric hit point moved along the
 *            geometric normal by lanes_scene_epsilon (1e-5 of the scene
 *            diagonal, in build/scene.h).
 *   robust   exact reciprocals, the watertight test (Woop, Benthin, Wald
 *            2013, double-precision fallback when an edge function is 0),
 *            box exits widened by 1 + 2 gamma(3) (Ize 2013), and secondary
 *            origins moved out of the error bound of the hit point (pbrt-v4's
 *            offset; see lanes_offset_origin in shading.h), which grows with
 *            the coordinates, so rays neither leak nor self-intersect however
 *            far the scene is from the origin.
 * What each mode costs and gains is measured by `lanes accuracy`. Two
 * findings from it shape these promises:
 * - Möller–Trumbore on the FMA sets (avx2, avx512emu, avx512) leaks about
 *   twice as many rays aimed at edges and vertices as on the others: a fused
 *   a*b - c*d is not antisymmetric, so the two triangles of a shared edge
 *   disagree more often about which side a ray passes.
 * - Robust mode is watertight for meshes whose shared edges are shared
 *   exactly. Rounding a mesh's vertices far from the origin (1e7 units for
 *   a 100-unit dragon) collapses thin triangles to zero area and leaves
 *   T-junctions, cracks no watertight test closes: a few rays in 1e5 aimed
 *   at such vertices leak there. Up to 1e5 units it leaks none.
 * In every mode 1/±0 is ±inf and the slab test orders its min and max so
 * that the NaN of 0 * inf never reaches a result (see box_core.h).
 *
 * Here, below trace/, because a scene file names the mode it wants
 * (build/scene_file.c reads the names). Baseline header: no intrinsics. */
#ifndef LANES_BUILD_ACCURACY_H
#define LANES_BUILD_ACCURACY_H

#include <float.h>
#include <math.h>
#include <string.h>

typedef enum lanes_accuracy {
    /* Render options only: the scene file's "accuracy", else default. The
     * renderers resolve it before any kernel sees it. */
    LANES_ACCURACY_FROM_SCENE = -1,
    LANES_ACCURACY_FAST = 0,
    LANES_ACCURACY_DEFAULT = 1,
    LANES_ACCURACY_ROBUST = 2,
    LANES_ACCURACY_COUNT
} lanes_accuracy;

/* Inline so that the scene parser (build/), which links no kernels, can
 * read the names too. */
static inline const char *lanes_accuracy_name(lanes_accuracy a)
{
    static const char *const names[LANES_ACCURACY_COUNT] = {"fast", "default", "robust"};
    return a >= 0 && a < LANES_ACCURACY_COUNT ? names[a] : "?";
}

/* -1 for an unknown name. */
static inline int lanes_accuracy_from_name(const char *name)
{
    for (int i = 0; name && i < LANES_ACCURACY_COUNT; i++)
        if (strcmp(name, lanes_accuracy_name((lanes_accuracy)i)) == 0) return i;
    return -1;
}

/* The sizes each mode's float arithmetic holds (uniform scale or distance,
 * not position: triangle tests subtract the ray origin first). The reach is
 * the longest distance a triangle test meets, from a ray's origin to a
 * vertex: at most the diagonal of the box of the scene and the origin.
 * - Fast and default (Möller-Trumbore): t's numerator is a product of a
 *   distance and two edges, at most 6 reach * longest_edge^2, which must not
 *   overflow float (3.4e38); and det, a product of two edges, and that
 *   numerator must stay normal floats (above 1.2e-38) for the scene's own
 *   size: its diagonal at least 1e-11 (the scale sweep of
 *   tests/test_scale_sweep.c loses most shadows at a diagonal of 1e-13 and
 *   renders right at 1e-12).
 * - Robust (watertight): products of two distances only, divided before
 *   the third factor: reach up to 1e18 (its square 1e36) and a diagonal
 *   from 1e-15 (right at 1e-16, shadows lost at 1e-17).
 * Outside them the renderers refuse the scene (lanes_scene_plan_check,
 * trace/scene_plan.h), the library refuses to build an accel, and a query
 * reports a ray that starts too far away (trace/lanes_api.c). */
#define LANES_MOLLER_MIN_DIAGONAL 1e-11
#define LANES_ROBUST_MIN_DIAGONAL 1e-15
#define LANES_ROBUST_MAX_REACH 1e18

static inline double lanes_accuracy_min_diagonal(lanes_accuracy a)
{
    return a == LANES_ACCURACY_ROBUST ? LANES_ROBUST_MIN_DIAGONAL : LANES_MOLLER_MIN_DIAGONAL;
}

/* The longest reach mode a traces for triangles whose longest edge is
 * longest_edge (infinite when every triangle is a point). */
static inline double lanes_accuracy_max_reach(lanes_accuracy a, double longest_edge)
{
    if (a == LANES_ACCURACY_ROBUST) return LANES_ROBUST_MAX_REACH;
    double e2 = longest_edge * longest_edge;
    return e2 > 0.0 ? (double)FLT_MAX / (6.0 * e2) : INFINITY;
}

#endif
