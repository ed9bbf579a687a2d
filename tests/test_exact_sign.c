/* The exact sign of t (trace/kernels/exact_sign.h) against integer
 * arithmetic: vertices, origins and directions with integer coordinates
 * below 2^24 (exact in a float) have determinants below 2^80, which a
 * 128-bit integer holds exactly and a double does not. Each
 * case is also run scaled by powers of two from 2^-140 (subnormal floats)
 * to 2^100: scaling every input by 2^k is exact in float and leaves the
 * sign of t alone, while it moves every product far from where the double
 * filter and the expansions would meet it at scale 1.
 *
 * The hard cases are built, not hoped for: origins exactly in the plane
 * (sign 0) and one unit off it on either side, which the double filter
 * cannot decide; and the floor of scale_1.json with the origin one
 * subnormal ulp above it, the self-hit that robust renders got wrong. */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "trace/kernels/exact_sign.h"

typedef __int128 i128;

static int failures;

static i128 det_i(const i128 a[3], const i128 b[3], const i128 c[3])
{
    return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
           a[2] * (b[0] * c[1] - b[1] * c[0]);
}

static int sign_i(i128 x) { return (x > 0) - (x < 0); }

/* The sign of t for integer inputs, or EXACT_T_PARALLEL. */
static int expected_sign(const int32_t v[3][3], const int32_t o[3], const int32_t d[3])
{
    i128 e1[3], e2[3], w[3], dd[3];
    for (int a = 0; a < 3; a++) {
        e1[a] = (i128)v[1][a] - v[0][a];
        e2[a] = (i128)v[2][a] - v[0][a];
        w[a] = (i128)v[0][a] - o[a];
        dd[a] = d[a];
    }
    int nd = sign_i(det_i(e1, e2, dd));
    if (nd == 0) return EXACT_T_PARALLEL;
    return sign_i(det_i(e1, e2, w)) * nd;
}

/* Checks one integer case at every scale. */
static void check_case(const char *what, const int32_t v[3][3], const int32_t o[3],
                       const int32_t d[3])
{
    static const int scales[] = {-140, -60, 0, 60, 100};
    int want = expected_sign(v, o, d);
    for (size_t s = 0; s < sizeof scales / sizeof scales[0]; s++) {
        float fv[3][3], fo[3], fd[3];
        for (int a = 0; a < 3; a++) {
            for (int c = 0; c < 3; c++) fv[c][a] = ldexpf((float)v[c][a], scales[s]);
            fo[a] = ldexpf((float)o[a], scales[s]);
            fd[a] = ldexpf((float)d[a], scales[s]);
        }
        int got = exact_plane_t_sign(fv[0], fv[1], fv[2], fo, fd);
        if (got != want) {
            if (failures < 20)
                fprintf(stderr, "FAIL %s at scale 2^%d: sign %d, expected %d\n", what, scales[s],
                        got, want);
            failures++;
        }
    }
}

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;

static int32_t random_coord(int32_t range)
{
    rng_state ^= rng_state << 13, rng_state ^= rng_state >> 7, rng_state ^= rng_state << 17;
    return (int32_t)(rng_state % (uint64_t)(2 * range + 1)) - range;
}

static void check_random(int count)
{
    for (int i = 0; i < count; i++) {
        int32_t v[3][3], o[3], d[3];
        for (int a = 0; a < 3; a++) {
            for (int c = 0; c < 3; c++) v[c][a] = random_coord(1 << 23);
            o[a] = random_coord(1 << 23);
            d[a] = random_coord(1 << 23);
        }
        check_case("random", v, o, d);
    }
}

/* Origins on the plane (o = v0 + a e1 + b e2 with small integers a, b) and
 * one unit off it along each axis: a triangle of edges up to 2^20 far from
 * 0 (up to 2^22), so that the products overflow a double's 53 bits and the
 * double filter cannot decide. */
static void check_on_plane(int count)
{
    for (int i = 0; i < count; i++) {
        int32_t v[3][3], o[3], d[3];
        for (int a = 0; a < 3; a++) {
            v[0][a] = random_coord(1 << 22);
            v[1][a] = v[0][a] + random_coord(1 << 20);
            v[2][a] = v[0][a] + random_coord(1 << 20);
            d[a] = random_coord(1 << 23);
        }
        int32_t ka = random_coord(2), kb = random_coord(2);
        for (int a = 0; a < 3; a++)
            o[a] = v[0][a] + ka * (v[1][a] - v[0][a]) + kb * (v[2][a] - v[0][a]);
        if (expected_sign(v, o, d) != 0 && expected_sign(v, o, d) != EXACT_T_PARALLEL) {
            fprintf(stderr, "FAIL: the on-plane construction is off the plane\n");
            failures++;
        }
        check_case("on the plane", v, o, d);
        for (int a = 0; a < 3; a++)
            for (int step = -1; step <= 1; step += 2) {
                int32_t off[3] = {o[0], o[1], o[2]};
                off[a] += step;
                check_case("one unit off the plane", v, off, d);
            }
    }
}

/* The floor (y = 0) and a shadow ray towards the light from one subnormal
 * ulp above it: t of the floor is -1.4e-45 / d.y, so behind the origin. */
static void check_floor(void)
{
    const float v0[3] = {-1, 0, -1}, v1[3] = {1, 0, -1}, v2[3] = {1, 0, 1};
    const float d[3] = {0.3f, 0.9f, -0.2f};
    const struct {
        float y;
        int sign;
    } cases[] = {{FLT_TRUE_MIN, -1}, {-FLT_TRUE_MIN, 1}, {0.0f, 0}, {FLT_MIN, -1}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const float o[3] = {0.25f, cases[i].y, 0.5f};
        int got = exact_plane_t_sign(v0, v1, v2, o, d);
        if (got != cases[i].sign) {
            fprintf(stderr, "FAIL floor, origin y = %g: sign %d, expected %d\n", (double)cases[i].y,
                    got, cases[i].sign);
            failures++;
        }
    }
    const float inf[3] = {INFINITY, 0, 0};
    if (exact_plane_t_sign(v0, v1, v2, inf, d) != EXACT_T_NOT_FINITE) {
        fprintf(stderr, "FAIL: an infinite origin is not reported\n");
        failures++;
    }
    const float along[3] = {1, 0, 0};
    const float o[3] = {0, 1, 0};
    if (exact_plane_t_sign(v0, v1, v2, o, along) != EXACT_T_PARALLEL) {
        fprintf(stderr, "FAIL: a ray parallel to the floor is not reported\n");
        failures++;
    }
}

/* The plane x = c for a c far from the origin's scale: the origin one float
 * ulp either side of it, so that v0 - o needs far more than 53 bits when
 * o's other coordinates are tiny. */
static void check_far_apart(void)
{
    const float c = 0x1p60f;
    const float v0[3] = {c, -1, -1}, v1[3] = {c, 1, -1}, v2[3] = {c, 0, 1};
    const float d[3] = {1, 0x1p-30f, 0x1p-31f};
    const float below = nextafterf(c, 0), above = nextafterf(c, INFINITY);
    const struct {
        float x;
        int sign;
    } cases[] = {{below, 1}, {above, -1}, {c, 0}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const float o[3] = {cases[i].x, 0x1p-100f, -0x1p-120f};
        int got = exact_plane_t_sign(v0, v1, v2, o, d);
        if (got != cases[i].sign) {
            fprintf(stderr, "FAIL far apart, origin x = %a: sign %d, expected %d\n",
                    (double)cases[i].x, got, cases[i].sign);
            failures++;
        }
    }
}

int main(void)
{
    check_random(20000);
    check_on_plane(5000);
    check_floor();
    check_far_apart();
    if (failures) {
        fprintf(stderr, "%d failures\n", failures);
        return 1;
    }
    printf("exact sign of t: 20000 random and 5000 on-plane cases (7 each) at 5 scales, the "
           "floor and far-apart cases: ok\n");
    return 0;
}
