/* Ray sets for lanes against Embree, generated once and traced by both:
 * camera rays in a packet tracer's pixel order, and the shadow and diffuse
 * rays from their hits, as a renderer would cast them. Every ray is
 * prepared (lanes_ray_prepare) and its direction is unit length. All
 * return NULL when out of memory.
 *
 * Compiled for the x86-64 baseline. */
#ifndef LANES_BENCH_RAY_SETS_H
#define LANES_BENCH_RAY_SETS_H

#include <stddef.h>
#include <stdint.h>

#include "build/scene.h"
#include "build/vec3.h"
#include "trace/kernels.h"

typedef enum {
    /* 8x8 tiles, Morton order inside a tile: packets of 4, 16 and 64
     * consecutive rays are 2x2, 4x4 and 8x8 pixel blocks (lanes compare) */
    RAY_ORDER_MORTON8,
    /* 32x32 quadrants (one lanes packet each) of 4x4 tiles (one 16-lane
     * group, one rtcIntersect16 packet) (lanes study) */
    RAY_ORDER_QUADRANTS,
} ray_order;

/* Through the pixel centres of the scene's camera at w x h, in `order`. */
lanes_ray *ray_set_camera(const lanes_scene *s, int w, int h, ray_order order, size_t *count);

/* A primary hit as the secondary rays start from it: the point by its
 * barycentrics (more accurate than o + t d), the normal facing the ray,
 * the origin offset along it by a scene-relative epsilon. */
typedef struct {
    vec3 origin, n;
    uint32_t pixel;
} surface_point;

surface_point *ray_set_surface_points(const lanes_scene *s, const lanes_ray *rays, const lanes_hit *hits,
                                      size_t n, size_t *count);
/* Towards the first point light, or a point above the scene (along the
 * camera's up) when there is none; only where the light is in front of the
 * surface. */
lanes_ray *ray_set_shadow(const lanes_scene *s, const surface_point *pts, size_t n, size_t *count);
/* Cosine-weighted about the facing normal; the numbers depend only on the
 * pixel, so the rays are the same whatever else changes. */
lanes_ray *ray_set_diffuse(const surface_point *pts, size_t n);
/* The same rays in a seeded random order (incoherent, same work). */
lanes_ray *ray_set_shuffled(const lanes_ray *rays, size_t n);

#endif
