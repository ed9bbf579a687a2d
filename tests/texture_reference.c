/* Double-precision solid textures for tests/test_textures.c. */
#include "texture_reference.h"

#include <math.h>
#include <stdint.h>

#include "simd/counter_random.h"

#define REF_PI 3.14159265358979323846
#define NOISE_SCALE 0.75 /* LANES_NOISE_SCALE */


static double ramp(int32_t ix, int32_t iy, int32_t iz, double dx, double dy, double dz)
{
    uint32_t h = lanes_hash32(lanes_hash32(lanes_hash32((uint32_t)ix) + (uint32_t)iy) + (uint32_t)iz);
    return ((h & 1u) ? -dx : dx) + ((h & 2u) ? -dy : dy) + ((h & 4u) ? -dz : dz);
}

static double fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }
static double lerp(double t, double a, double b) { return a + t * (b - a); }

double ref_noise_raw(double x, double y, double z)
{
    double fx = floor(x), fy = floor(y), fz = floor(z);
    int32_t ix = (int32_t)fx, iy = (int32_t)fy, iz = (int32_t)fz;
    double dx = x - fx, dy = y - fy, dz = z - fz, u = fade(dx), v = fade(dy), w = fade(dz);
    double c[2][2][2];
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++)
            for (int k = 0; k < 2; k++) c[a][b][k] = ramp(ix + a, iy + b, iz + k, dx - a, dy - b, dz - k);
    double x00 = lerp(u, c[0][0][0], c[1][0][0]), x10 = lerp(u, c[0][1][0], c[1][1][0]);
    double x01 = lerp(u, c[0][0][1], c[1][0][1]), x11 = lerp(u, c[0][1][1], c[1][1][1]);
    return lerp(w, lerp(v, x00, x10), lerp(v, x01, x11));
}

double ref_noise(double x, double y, double z)
{
    double n = ref_noise_raw(x, y, z) * NOISE_SCALE;
    return n < -1.0 ? -1.0 : n > 1.0 ? 1.0 : n;
}

static double turbulence(double x, double y, double z)
{
    double sum = 0.0;
    for (double f = 1.0; f <= 8.0; f *= 2.0) sum += fabs(ref_noise(x * f, y * f, z * f)) / f;
    return sum;
}

double ref_texture_weight(lanes_texture_kind kind, double x, double y, double z)
{
    switch (kind) {
    case LANES_TEXTURE_CHECKER:
        return (double)(((int64_t)floor(x) + (int64_t)floor(y) + (int64_t)floor(z)) & 1);
    case LANES_TEXTURE_NOISE:
        return 0.5 + 0.5 * ref_noise(x, y, z);
    case LANES_TEXTURE_MARBLE:
        return 0.5 + 0.5 * sin(REF_PI * x + 4.0 * turbulence(x, y, z));
    default: {
        double r = sqrt(x * x + z * z) + 0.5 * ref_noise(x, y, z);
        return r - floor(r);
    }
    }
}
