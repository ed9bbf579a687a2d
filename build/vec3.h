/* Three-float vectors for the baseline code that sets rays up: cameras,
 * shading, ray generation in the studies and tests. Every operation rounds
 * once per float operation, in the order written (-ffp-contract=off), so
 * all users compute the same rays bit for bit.
 *
 * Compiled for the x86-64 baseline: no intrinsics. */
#ifndef LANES_BUILD_VEC3_H
#define LANES_BUILD_VEC3_H

#include <math.h>
#include <stdint.h>
#include <string.h>

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

/* The unit normal of the plane spanned by edges a and b (a x b, normalized)
 * and, in *area, |a x b| (twice the triangle's area, or the parallelogram's),
 * at any scale: the edges are first scaled by the power of two that brings
 * their largest component into [0.5, 1). The cross product squares the
 * edges and its length squares them again, so unscaled it overflows past
 * edges of about 2^31 (4e9 units: a black surface, an infinite light) and
 * underflows below about 2^-31; scaled, neither can happen, and *area is
 * exact up to its own range. A power of two scales exactly, so wherever the
 * unscaled form was finite this gives the same bits. A degenerate or
 * non-finite pair gives (0,0,0) and area 0. */
/* frexpf's exponent of a positive finite x: x = m 2^e, m in [0.5, 1).
 * Read off the bits for a normal x (every hit's normal comes through here,
 * and the library call showed in profiles). */
static inline int v3_exponent(float x)
{
    uint32_t bits;
    memcpy(&bits, &x, sizeof bits);
    int biased = (int)(bits >> 23 & 0xffu);
    if (biased == 0) {
        int e;
        frexpf(x, &e);
        return e;
    }
    return biased - 126;
}

/* 2^e as a float, for e in [-126, 127] (a normal float). */
static inline float v3_pow2(int e)
{
    uint32_t bits = (uint32_t)(e + 127) << 23;
    float f;
    memcpy(&f, &bits, sizeof f);
    return f;
}

/* The normal of v3_unit_normal_area and the length of the scaled cross
 * product, *scale_exp the exponent of the scaling undone: |a x b| = l
 * 2^(2 e). */
static inline vec3 v3_unit_normal_scaled(vec3 a, vec3 b, float *l_out, int *scale_exp)
{
    float big = fmaxf(fmaxf(fmaxf(fabsf(a.x), fabsf(a.y)), fmaxf(fabsf(a.z), fabsf(b.x))),
                      fmaxf(fabsf(b.y), fabsf(b.z)));
    *l_out = 0.0f;
    *scale_exp = 0;
    if (!(big > 0.0f) || !isfinite(big)) return v3(0.0f, 0.0f, 0.0f);
    int e = v3_exponent(big);
    /* s itself must be a normal float: a subnormal one is zero under DAZ */
    e = e > 125 ? 125 : e < -125 ? -125 : e;
    float s = v3_pow2(-e);
    vec3 n = v3_cross(v3_scale(a, s), v3_scale(b, s));
    float l = sqrtf(v3_dot(n, n));
    if (!(l > 0.0f)) return v3(0.0f, 0.0f, 0.0f);
    *l_out = l;
    *scale_exp = e;
    return v3_scale(n, 1.0f / l);
}

static inline vec3 v3_unit_normal_area(vec3 a, vec3 b, float *area)
{
    float l;
    int e;
    vec3 n = v3_unit_normal_scaled(a, b, &l, &e);
    *area = l > 0.0f ? ldexpf(l, 2 * e) : 0.0f;
    return n;
}

static inline vec3 v3_unit_normal(vec3 a, vec3 b)
{
    float l;
    int e;
    return v3_unit_normal_scaled(a, b, &l, &e);
}

#endif
