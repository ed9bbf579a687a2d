/* The solid textures of trace/texture.h at LANES_W points at once, written
 * once and compiled per set. Gradient noise (Perlin 1985/2002 in shape: a
 * quintic blend of the eight lattice corners' gradient ramps), its
 * gradients picked by lanes' counter hash (simd/vrandom.h) of the corner's
 * integer coordinates, so a pattern is the same at every width and in any
 * lane order. tests/test_textures.c checks each texture against a double
 * reference of the same construction.
 *
 * Included by per-ISA files; everything is static inline. */
#ifndef LANES_TRACE_KERNELS_TEXTURE_CORE_H
#define LANES_TRACE_KERNELS_TEXTURE_CORE_H

#include "simd/simd.h"
#include "simd/vmath.h"
#include "simd/vrandom.h"
#include "trace/kernels/bsdf_core.h"
#include "trace/texture.h"

/* The corner's gradient has components +-1, their signs the hash's low
 * three bits, put straight into the float sign bits of the offset. */
static inline vfloat noise_ramp(vint ix, vint iy, vint iz, vfloat dx, vfloat dy, vfloat dz)
{
    vint h = vi_hash32(vi_add(vi_hash32(vi_add(vi_hash32(ix), iy)), iz));
    vfloat gx = vi_as_vf(vi_xor(vf_as_vi(dx), vi_sll(h, 31)));
    vfloat gy = vi_as_vf(vi_xor(vf_as_vi(dy), vi_sll(vi_srl(h, 1), 31)));
    vfloat gz = vi_as_vf(vi_xor(vf_as_vi(dz), vi_sll(vi_srl(h, 2), 31)));
    return vf_add(vf_add(gx, gy), gz);
}

/* 6t^5 - 15t^4 + 10t^3: the blend whose first and second derivatives
 * vanish at the lattice, so the noise is smooth across cells. */
static inline vfloat noise_fade(vfloat t)
{
    vfloat p = vf_fmadd(t, vf_set1(6.0f), vf_set1(-15.0f));
    p = vf_fmadd(t, p, vf_set1(10.0f));
    return vf_mul(vf_mul(vf_mul(t, t), t), p);
}

static inline vfloat lerp(vfloat t, vfloat a, vfloat b) { return vf_fmadd(t, vf_sub(b, a), a); }

/* Maps the noise into [-1, 1]: the largest magnitude found before it,
 * over 2e7 random points, is 1.28, so scaled by 0.75 the noise stays below
 * 0.96 there, and the clamp holds the bound wherever that search missed. */
#define LANES_NOISE_SCALE 0.75f

static inline vfloat vf_noise3(vfloat x, vfloat y, vfloat z)
{
    vfloat fx = vf_floor(x), fy = vf_floor(y), fz = vf_floor(z);
    vint ix = vf_to_vi(fx), iy = vf_to_vi(fy), iz = vf_to_vi(fz), one = vi_set1(1);
    vint jx = vi_add(ix, one), jy = vi_add(iy, one), jz = vi_add(iz, one);
    vfloat dx = vf_sub(x, fx), dy = vf_sub(y, fy), dz = vf_sub(z, fz);
    vfloat ex = vf_sub(dx, vf_set1(1.0f)), ey = vf_sub(dy, vf_set1(1.0f)), ez = vf_sub(dz, vf_set1(1.0f));
    vfloat u = noise_fade(dx), v = noise_fade(dy), w = noise_fade(dz);
    vfloat x00 = lerp(u, noise_ramp(ix, iy, iz, dx, dy, dz), noise_ramp(jx, iy, iz, ex, dy, dz));
    vfloat x10 = lerp(u, noise_ramp(ix, jy, iz, dx, ey, dz), noise_ramp(jx, jy, iz, ex, ey, dz));
    vfloat x01 = lerp(u, noise_ramp(ix, iy, jz, dx, dy, ez), noise_ramp(jx, iy, jz, ex, dy, ez));
    vfloat x11 = lerp(u, noise_ramp(ix, jy, jz, dx, ey, ez), noise_ramp(jx, jy, jz, ex, ey, ez));
    vfloat n = lerp(w, lerp(v, x00, x10), lerp(v, x01, x11));
    n = vf_mul(n, vf_set1(LANES_NOISE_SCALE));
    return vf_min(vf_max(n, vf_set1(-1.0f)), vf_set1(1.0f));
}

/* Four octaves of |noise|, each half the size and weight of the last. */
static inline vfloat vf_turbulence3(vfloat x, vfloat y, vfloat z)
{
    vfloat sum = vf_zero(), f = vf_set1(1.0f);
    for (int o = 0; o < 4; o++) {
        vfloat n = vf_abs(vf_noise3(vf_mul(x, f), vf_mul(y, f), vf_mul(z, f)));
        sum = vf_add(sum, vf_div(n, f));
        f = vf_add(f, f);
    }
    return sum;
}

/* The blend weight in [0, 1] of the texture at p. */
static inline vfloat texture_weight(const lanes_texture *t, bsdf_v3 p)
{
    vfloat k = vf_set1(1.0f / t->scale);
    vfloat x = vf_mul(p.x, k), y = vf_mul(p.y, k), z = vf_mul(p.z, k);
    const vfloat half = vf_set1(0.5f);
    switch (t->kind) {
    case LANES_TEXTURE_CHECKER: {
        vint s = vi_add(vi_add(vf_to_vi(vf_floor(x)), vf_to_vi(vf_floor(y))), vf_to_vi(vf_floor(z)));
        return vi_to_vf(vi_and(s, vi_set1(1)));
    }
    case LANES_TEXTURE_NOISE:
        return vf_fmadd(half, vf_noise3(x, y, z), half);
    case LANES_TEXTURE_MARBLE: {
        vfloat phase = vf_fmadd(vf_set1(4.0f), vf_turbulence3(x, y, z), vf_mul(vf_set1(BSDF_PI), x));
        return vf_fmadd(half, vf_sin(phase), half);
    }
    default: { /* wood */
        vfloat r = vf_fmadd(half, vf_noise3(x, y, z), vf_sqrt(vf_fmadd(x, x, vf_mul(z, z))));
        return vf_sub(r, vf_floor(r));
    }
    }
}

/* color_a + w (color_b - color_a) at each point. */
static inline bsdf_v3 texture_color(const lanes_texture *t, bsdf_v3 p)
{
    vfloat w = texture_weight(t, p);
    return (bsdf_v3){lerp(w, vf_set1(t->color_a[0]), vf_set1(t->color_b[0])),
                     lerp(w, vf_set1(t->color_a[1]), vf_set1(t->color_b[1])),
                     lerp(w, vf_set1(t->color_a[2]), vf_set1(t->color_b[2]))};
}

#endif
