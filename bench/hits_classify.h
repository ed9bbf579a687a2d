/* Whether two engines' hits on the same ray agree and, where they do not,
 * why: two triangles at the same t (ties), a hit within 1e-4 of a
 * triangle's edge or of the ray's ends, or within the float test's own
 * rounding error of an edge (grazing), or neither (other), for
 * `lanes compare`.
 *
 * Compiled for the x86-64 baseline. */
#ifndef LANES_BENCH_HITS_CLASSIFY_H
#define LANES_BENCH_HITS_CLASSIFY_H

#include <stdbool.h>
#include <stddef.h>

#include "build/scene.h"
#include "trace/kernels.h"

typedef struct hits_differences {
    size_t ties, grazing, other;
} hits_differences;

/* Same primitive and t within 1e-4 relative, or both miss. */
bool hits_same(const lanes_hit *a, const lanes_hit *b);
/* Counts one disagreement between l and e (for shadow rays: the nearest
 * blockers each engine finds) in its category. */
void hits_classify(const lanes_scene *s, const lanes_ray *r, const lanes_hit *l, const lanes_hit *e,
                   hits_differences *d);

#endif
