/* Three-float vectors for the baseline code that sets rays up: cameras,
 * shading, ray generation in the studies and tests. Every operation rounds
 * once per float operation, in the order written (-ffp-contract=off), so
 * all users compute the same rays bit for bit.
 *
 * Compiled for the x86-64 baseline: no intrinsics. */
#ifndef LANES_BUILD_VEC3_H
#define LANES_BUILD_VEC3_H

#include <math.h>

#define LANES_PI 3.14159265358979323846f

typedef struct {
    float x, y, z;
} vec3;

static inline vec3 v3(float x, float y, float z) { return (vec3){x, y, z}; }
static inline vec3 v3_load(const float *p) { return (vec3){p[0], p[1], p[2]}; }
static inline vec3 v3_add(vec3 a, vec3 b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline vec3 v3_sub(vec3 a, vec3 b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline vec3 v3_scale(vec3 a, float s) { return v3(a.x * s, a.y * s, a.z * s); }
static inline vec3 v3_mul(vec3 a, vec3 b) { return v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline float v3_dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline vec3 v3_cross(vec3 a, vec3 b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline vec3 v3_normalize(vec3 a)
{
    float l = sqrtf(v3_dot(a, a));
    return l > 0.0f ? v3_scale(a, 1.0f / l) : a;
}
static inline vec3 v3_abs(vec3 a) { return v3(fabsf(a.x), fabsf(a.y), fabsf(a.z)); }

#endif
