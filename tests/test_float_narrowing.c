/* A double narrowed to float must be rounded, even when the float is
 * widened back to double in the same loop. GCC 12.2 at -O3 (its SLP
 * vectoriser) keeps the unrounded double instead; the build turns that pass
 * off for GCC < 13 (CMakeLists.txt), and this test, compiled with the
 * project's flags, fails if the miscompilation comes back. */
#include <stdio.h>
#include <string.h>

static int wrong;

__attribute__((noinline)) void lanes_test_report(const double *qd, const float *q);
__attribute__((noinline)) void lanes_test_report(const double *qd, const float *q)
{
    for (int a = 0; a < 3; a++) {
        printf("narrowed %.17g, widened back %.17g\n", (double)q[a], qd[a]);
        wrong += qd[a] != (double)q[a];
    }
}

/* The shape that triggers it: the float array and its widened copy filled
 * in one loop, both then read elsewhere. */
__attribute__((noinline)) void lanes_test_narrow(const float *lo, const float *hi, const double *u,
                                                 float *out);
__attribute__((noinline)) void lanes_test_narrow(const float *lo, const float *hi, const double *u,
                                                 float *out)
{
    float q[3];
    double qd[3];
    for (int a = 0; a < 3; a++) {
        q[a] = (float)(lo[a] + (hi[a] - (double)lo[a]) * u[a]);
        qd[a] = q[a];
    }
    memcpy(out, q, sizeof q);
    lanes_test_report(qd, q);
}

int main(void)
{
    /* near 1e7 floats are 1 apart, so every product here needs rounding */
    float lo[3] = {9999950.0f, 9999950.0f, 9999950.0f}, hi[3] = {10000050.0f, 10000050.0f, 10000050.0f};
    double u[3] = {0.3001, 0.6003, 0.5005};
    float out[3];
    lanes_test_narrow(lo, hi, u, out);
    printf("%s: %d of 3 narrowed values kept digits a float cannot hold\n", wrong ? "FAIL" : "ok", wrong);
    return wrong ? 1 : 0;
}
