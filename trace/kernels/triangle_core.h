/* The ray/triangle cores shared by the triangle kernels and the BVH
 * traversals of one kernel set. Included only by per-ISA files; everything
 * is static inline (see simd/simd.h).
 *
 * Both tests are two-sided and count the triangle's boundary as inside; the
 * hit interval [tnear, tfar] is closed and checked with ordered compares, so
 * a NaN anywhere is a miss. */
#ifndef LANES_TRACE_TRIANGLE_CORE_H
#define LANES_TRACE_TRIANGLE_CORE_H

#include "trace/kernels/exact_sign.h"
#include "trace/kernels/kernel_common.h"

#include <float.h>

/* near_zero: lanes (watertight test only) that pass the edge tests but
 * whose t lies within its rounding bound of 0, so its sign is in doubt;
 * they are not in hit until wt_settle_rays or wt_settle_tris has decided
 * them. */
typedef struct {
    vfloat t, u, v;
    vmask hit, near_zero;
} tri_result;

/* Möller–Trumbore (1997). Epsilon policy: none. The test rejects only
 * det == 0 exactly (the ray lies in the triangle's plane, or the triangle is
 * degenerate in a way the rounding preserves); a nearly parallel ray gets a
 * large, finite t, which the [tnear, tfar] check then judges. FMA is used in
 * the cross and dot products where the set has it (vf_fmadd), so sets with
 * and without FMA differ by rounding; see tests/.
 *
 * The division comes before any rejection, on purpose. Testing the edges
 * first with det's sign folded into the numerators and dividing only when
 * a lane passes (Embree's form) made the traversals slower, not faster:
 * 0.95x, geometric mean over dragon, sponza-bunny and 20-bunnies, every ray
 * kind, avx2, Zen 4, clang 14 (lanes compare, alternating runs); only
 * sponza-bunny's shadow rays gained (1.05-1.19x, partly inside the run-to-
 * run noise of about +-12%). Our reading, not
 * measured: that branch is hard to predict, while the division delays
 * nothing once the leaf's miss is predicted and the walk runs on
 * speculatively. */
LANES_BODY tri_result moller_core(vfloat ox, vfloat oy, vfloat oz, vfloat dx, vfloat dy, vfloat dz,
                                  vfloat v0x, vfloat v0y, vfloat v0z, vfloat v1x, vfloat v1y,
                                  vfloat v1z, vfloat v2x, vfloat v2y, vfloat v2z, vfloat tnear,
                                  vfloat tfar, vmask live, bool want_uv)
{
    tri_result r;
    vfloat e1x = vf_sub(v1x, v0x), e1y = vf_sub(v1y, v0y), e1z = vf_sub(v1z, v0z);
    vfloat e2x = vf_sub(v2x, v0x), e2y = vf_sub(v2y, v0y), e2z = vf_sub(v2z, v0z);
    vfloat px = vf_fmsub(dy, e2z, vf_mul(dz, e2y));
    vfloat py = vf_fmsub(dz, e2x, vf_mul(dx, e2z));
    vfloat pz = vf_fmsub(dx, e2y, vf_mul(dy, e2x));
    vfloat det = vf_fmadd(e1x, px, vf_fmadd(e1y, py, vf_mul(e1z, pz)));
    vfloat tx = vf_sub(ox, v0x), ty = vf_sub(oy, v0y), tz = vf_sub(oz, v0z);
    vfloat uu = vf_fmadd(tx, px, vf_fmadd(ty, py, vf_mul(tz, pz)));
    vfloat qx = vf_fmsub(ty, e1z, vf_mul(tz, e1y));
    vfloat qy = vf_fmsub(tz, e1x, vf_mul(tx, e1z));
    vfloat qz = vf_fmsub(tx, e1y, vf_mul(ty, e1x));
    vfloat vv = vf_fmadd(dx, qx, vf_fmadd(dy, qy, vf_mul(dz, qz)));
    vfloat tt = vf_fmadd(e2x, qx, vf_fmadd(e2y, qy, vf_mul(e2z, qz)));
    vfloat inv = vf_rcp(det);
    vfloat u = vf_mul(uu, inv), v = vf_mul(vv, inv), t = vf_mul(tt, inv);
    vfloat zero = vf_zero();
    vmask m = vm_and(live, vf_neq(det, zero));
    m = vm_and(m, vm_and(vf_ge(u, zero), vf_ge(v, zero)));
    m = vm_and(m, vf_le(vf_add(u, v), vf_set1(1.0f)));
    m = vm_and(m, vm_and(vf_ge(t, tnear), vf_le(t, tfar)));
    r.hit = m;
    r.near_zero = vm_false();
    r.t = t;
    r.u = want_uv ? u : zero;
    r.v = want_uv ? v : zero;
    return r;
}

/* Keeps the sign of a double edge function when it is narrowed to float. */
static inline float narrow_signed(double x)
{
    float f = (float)x;
    if (f == 0.0f && x != 0.0) f = x > 0.0 ? FLT_TRUE_MIN : -FLT_TRUE_MIN;
    return f;
}

LANES_BODY vfloat max3_abs(vfloat a, vfloat b, vfloat c)
{
    return vf_max(vf_abs(a), vf_max(vf_abs(b), vf_abs(c)));
}

/* Whether a watertight t may have the wrong sign: |t| not above the bound
 * on its rounding error that Pharr, Jakob and Humphreys derive (Physically
 * Based Rendering, 3rd ed., 3.9.6) for t = (U Az + V Bz + W Cz) / det,
 * doubled (t is formed here from the barycentrics, a few roundings more)
 * and loosened where that saves work: a lane that passed the edge tests
 * has U, V and W of one sign, so max |U, V, W| <= |det| and the term in
 * e / det is at most 1; gamma(2) is raised to gamma(5). The edge functions'
 * size is divided by det before it multiplies anything, so nothing
 * overflows. A NaN bound leaves a finite t in doubt; an infinite or NaN t
 * is not a question of sign (its distance overflowed) and keeps the
 * verdict of the interval test. */
LANES_BODY vmask wt_t_in_doubt(vfloat t, vfloat Ax, vfloat Ay, vfloat Az, vfloat Bx, vfloat By,
                               vfloat Bz, vfloat Cx, vfloat Cy, vfloat Cz, vfloat inv)
{
    const float u = 0.5f * FLT_EPSILON;
#define LANES_GAMMA(n) ((n) * u / (1.0f - (n) * u))
    /* PBRT: 3 mz (2 gamma3 e + 2 (gamma2 mx my + dy mx + dx my)) / |det|
     * with dx = gamma5 (mx + mz), dy = gamma5 (my + mz); doubled. */
    const float k0 = 12.0f * LANES_GAMMA(3);
    const float kxy = 12.0f * 3.0f * LANES_GAMMA(5), kz = 12.0f * LANES_GAMMA(5);
#undef LANES_GAMMA
    vfloat mx = max3_abs(Ax, Bx, Cx), my = max3_abs(Ay, By, Cy), mz = max3_abs(Az, Bz, Cz);
    vfloat sliver = vf_add(vf_mul(vf_set1(kxy), vf_mul(mx, my)),
                           vf_mul(vf_set1(kz), vf_mul(mz, vf_add(mx, my))));
    vfloat bound = vf_mul(mz, vf_add(vf_set1(k0), vf_mul(sliver, vf_abs(inv))));
    vmask finite = vf_lt(vf_abs(t), vf_set1(INFINITY));
    return vm_andnot(finite, vf_gt(vf_abs(t), bound));
}

/* Woop, Benthin and Wald (2013), after the per-ray permutation: a, b, c are
 * the vertices minus the ray origin with axes permuted so that z is the
 * ray's dominant axis (kz), and sx, sy, sz the shear that maps the ray to +z.
 * No FMA anywhere: the edge functions must be exact negations of each other
 * across a shared edge, and a*b - c*d fused is not antisymmetric. */
LANES_BODY tri_result watertight_core(vfloat ax, vfloat ay, vfloat az, vfloat bx, vfloat by,
                                      vfloat bz, vfloat cx, vfloat cy, vfloat cz, vfloat sx,
                                      vfloat sy, vfloat sz, vfloat tnear, vfloat tfar, vmask live,
                                      bool want_uv)
{
    tri_result r;
    vfloat Ax = vf_sub(ax, vf_mul(sx, az)), Ay = vf_sub(ay, vf_mul(sy, az));
    vfloat Bx = vf_sub(bx, vf_mul(sx, bz)), By = vf_sub(by, vf_mul(sy, bz));
    vfloat Cx = vf_sub(cx, vf_mul(sx, cz)), Cy = vf_sub(cy, vf_mul(sy, cz));
    vfloat U = vf_sub(vf_mul(Cx, By), vf_mul(Cy, Bx));
    vfloat V = vf_sub(vf_mul(Ax, Cy), vf_mul(Ay, Cx));
    vfloat W = vf_sub(vf_mul(Bx, Ay), vf_mul(By, Ax));
    vfloat zero = vf_zero();

    /* An edge function of exactly 0 may be rounding: recompute those lanes
     * in double, where the products of two floats are exact and the
     * difference is rounded once, so the sign is right. */
    vmask on_edge = vm_and(live, vm_or(vf_eq(U, zero), vm_or(vf_eq(V, zero), vf_eq(W, zero))));
    if (vm_any(on_edge)) {
        float fAx[LANES_W], fAy[LANES_W], fBx[LANES_W], fBy[LANES_W], fCx[LANES_W], fCy[LANES_W];
        float fU[LANES_W], fV[LANES_W], fW[LANES_W];
        vf_storeu(fAx, Ax), vf_storeu(fAy, Ay), vf_storeu(fBx, Bx), vf_storeu(fBy, By);
        vf_storeu(fCx, Cx), vf_storeu(fCy, Cy);
        vf_storeu(fU, U), vf_storeu(fV, V), vf_storeu(fW, W);
        uint32_t bits = vm_bits(on_edge);
        for (int j = 0; j < LANES_W; j++) {
            if (!(bits & (1u << j))) continue;
            fU[j] = narrow_signed((double)fCx[j] * fBy[j] - (double)fCy[j] * fBx[j]);
            fV[j] = narrow_signed((double)fAx[j] * fCy[j] - (double)fAy[j] * fCx[j]);
            fW[j] = narrow_signed((double)fBx[j] * fAy[j] - (double)fBy[j] * fAx[j]);
        }
        U = vf_loadu(fU), V = vf_loadu(fV), W = vf_loadu(fW);
    }

    vmask any_neg = vm_or(vf_lt(U, zero), vm_or(vf_lt(V, zero), vf_lt(W, zero)));
    vmask any_pos = vm_or(vf_gt(U, zero), vm_or(vf_gt(V, zero), vf_gt(W, zero)));
    vfloat det = vf_add(vf_add(U, V), W);
    vmask m = vm_andnot(live, vm_and(any_neg, any_pos));
    m = vm_and(m, vf_neq(det, zero));
    if (vm_none(m)) {
        r.hit = r.near_zero = m;
        r.t = r.u = r.v = zero;
        return r;
    }
    vfloat Az = vf_mul(sz, az), Bz = vf_mul(sz, bz), Cz = vf_mul(sz, cz);
    /* Barycentrics first, then t from them: U*Az + V*Bz + W*Cz itself scales
     * with the cube of the triangle's size and underflows to 0 for tiny
     * triangles (t = 0 at size 1e-15), while each barycentric is O(1). */
    vfloat inv = vf_rcp(det);
    vfloat b0 = vf_mul(U, inv), b1 = vf_mul(V, inv), b2 = vf_mul(W, inv);
    vfloat t = vf_add(vf_add(vf_mul(b0, Az), vf_mul(b1, Bz)), vf_mul(b2, Cz));
    r.near_zero = vm_and(m, wt_t_in_doubt(t, Ax, Ay, Az, Bx, By, Bz, Cx, Cy, Cz, inv));
    m = vm_andnot(m, r.near_zero);
    m = vm_and(m, vm_and(vf_ge(t, tnear), vf_le(t, tfar)));
    r.hit = m;
    r.t = t;
    r.u = want_uv ? b1 : zero;
    r.v = want_uv ? b2 : zero;
    return r;
}

/* A near_zero lane's verdict once the exact sign of t is known: t moved to
 * that side of 0, then the closed interval as for every hit. A ray parallel
 * to the plane misses; non-finite data keeps the computed t. */
static inline bool wt_settle_lane(float *t, int sign, float tnear, float tfar)
{
    if (sign == EXACT_T_PARALLEL) return false;
    float settled = sign == EXACT_T_NOT_FINITE ? *t : t_on_exact_side(*t, sign);
    if (!(settled >= tnear && settled <= tfar)) return false;
    *t = settled;
    return true;
}

/* The watertight test's per-ray set-up: kz the axis of largest |d|, kx and ky
 * the next two in cyclic order, swapped when d[kz] < 0 to keep the winding;
 * the shear that maps d to +z. */
typedef struct {
    int kx, ky, kz;
    float sx, sy, sz;
} wt_setup;

static inline wt_setup wt_setup_ray(const float d[3])
{
    wt_setup s;
    float ax = fabsf(d[0]), ay = fabsf(d[1]), az = fabsf(d[2]);
    s.kz = ax >= ay ? (ax >= az ? 0 : 2) : (ay >= az ? 1 : 2);
    s.kx = (s.kz + 1) % 3;
    s.ky = (s.kx + 1) % 3;
    if (d[s.kz] < 0.0f) {
        int k = s.kx;
        s.kx = s.ky;
        s.ky = k;
    }
    s.sx = d[s.kx] / d[s.kz];
    s.sy = d[s.ky] / d[s.kz];
    s.sz = 1.0f / d[s.kz];
    return s;
}

/* Per-lane versions of the same choice for a packet, where every lane may
 * have its own axes: selects between the three components. */
LANES_BODY vfloat pick3(vmask is0, vmask is1, vfloat x, vfloat y, vfloat z)
{
    return vf_select(is0, x, vf_select(is1, y, z));
}

/* Decides the near_zero lanes of one triangle against a packet's rays
 * (the axes not permuted: the sign of t does not depend on their order). */
LANES_COLD void wt_settle_rays(tri_result *h, const lanes_vray *r, const lanes_triangle *tri)
{
    float ox[LANES_W], oy[LANES_W], oz[LANES_W], dx[LANES_W], dy[LANES_W], dz[LANES_W];
    float tnear[LANES_W], tfar[LANES_W], t[LANES_W];
    vf_storeu(ox, r->ox), vf_storeu(oy, r->oy), vf_storeu(oz, r->oz);
    vf_storeu(dx, r->dx), vf_storeu(dy, r->dy), vf_storeu(dz, r->dz);
    vf_storeu(tnear, r->tnear), vf_storeu(tfar, r->tfar), vf_storeu(t, h->t);
    uint32_t doubt = vm_bits(h->near_zero), hits = 0;
    for (int j = 0; j < LANES_W; j++) {
        if (!(doubt & (1u << j))) continue;
        const float o[3] = {ox[j], oy[j], oz[j]}, d[3] = {dx[j], dy[j], dz[j]};
        int sign = exact_plane_t_sign(tri->v0, tri->v1, tri->v2, o, d);
        if (wt_settle_lane(&t[j], sign, tnear[j], tfar[j])) hits |= 1u << j;
    }
    h->t = vf_loadu(t);
    h->hit = vm_or(h->hit, vm_from_bits(hits));
    h->near_zero = vm_false();
}

LANES_BODY tri_result watertight_packet_core(const lanes_vray *r, const lanes_triangle *tri,
                                             bool want_uv)
{
    vfloat adx = vf_abs(r->dx), ady = vf_abs(r->dy), adz = vf_abs(r->dz);
    /* kz = 0 if |dx| is largest, 1 if |dy|, else 2 (ties as in wt_setup_ray) */
    vmask z0 = vm_and(vf_ge(adx, ady), vf_ge(adx, adz));
    vmask z1 = vm_andnot(vm_and(vm_not(vf_ge(adx, ady)), vf_ge(ady, adz)), z0);
    vmask z2 = vm_not(vm_or(z0, z1));
    vfloat dkz = pick3(z0, z1, r->dx, r->dy, r->dz);
    vmask flip = vf_lt(dkz, vf_zero());
    /* cyclic successor: kx = kz+1, ky = kz+2; swapped when flip */
    vmask x0 = vm_xor(z2, vm_and(flip, vm_xor(z2, z1))); /* kx == 0: (!flip & kz==2) | (flip & kz==1) */
    vmask x1 = vm_xor(z0, vm_and(flip, vm_xor(z0, z2))); /* kx == 1: (!flip & kz==0) | (flip & kz==2) */
    vmask y0 = vm_xor(z1, vm_and(flip, vm_xor(z1, z2))); /* ky == 0: (!flip & kz==1) | (flip & kz==2) */
    vmask y1 = vm_xor(z2, vm_and(flip, vm_xor(z2, z0))); /* ky == 1: (!flip & kz==2) | (flip & kz==0) */
    vfloat dkx = pick3(x0, x1, r->dx, r->dy, r->dz);
    vfloat dky = pick3(y0, y1, r->dx, r->dy, r->dz);
    vfloat sz = vf_rcp(dkz);
    vfloat sx = vf_div(dkx, dkz), sy = vf_div(dky, dkz);

    vfloat a0 = vf_sub(vf_set1(tri->v0[0]), r->ox), a1 = vf_sub(vf_set1(tri->v0[1]), r->oy),
           a2 = vf_sub(vf_set1(tri->v0[2]), r->oz);
    vfloat b0 = vf_sub(vf_set1(tri->v1[0]), r->ox), b1 = vf_sub(vf_set1(tri->v1[1]), r->oy),
           b2 = vf_sub(vf_set1(tri->v1[2]), r->oz);
    vfloat c0 = vf_sub(vf_set1(tri->v2[0]), r->ox), c1 = vf_sub(vf_set1(tri->v2[1]), r->oy),
           c2 = vf_sub(vf_set1(tri->v2[2]), r->oz);
    tri_result h = watertight_core(pick3(x0, x1, a0, a1, a2), pick3(y0, y1, a0, a1, a2),
                                   pick3(z0, z1, a0, a1, a2), pick3(x0, x1, b0, b1, b2),
                                   pick3(y0, y1, b0, b1, b2), pick3(z0, z1, b0, b1, b2),
                                   pick3(x0, x1, c0, c1, c2), pick3(y0, y1, c0, c1, c2),
                                   pick3(z0, z1, c0, c1, c2), sx, sy, sz, r->tnear, r->tfar,
                                   r->live, want_uv);
    if (vm_any(h.near_zero)) wt_settle_rays(&h, r, tri);
    return h;
}

LANES_BODY vmask tris_have_area(vfloat ax, vfloat ay, vfloat az, vfloat bx, vfloat by, vfloat bz,
                                vfloat cx, vfloat cy, vfloat cz)
{
    vfloat e1x = vf_sub(bx, ax), e1y = vf_sub(by, ay), e1z = vf_sub(bz, az);
    vfloat e2x = vf_sub(cx, ax), e2y = vf_sub(cy, ay), e2z = vf_sub(cz, az);
    vfloat zero = vf_zero();
    vmask flat = vm_and(vf_eq(vf_sub(vf_mul(e1y, e2z), vf_mul(e1z, e2y)), zero),
                        vm_and(vf_eq(vf_sub(vf_mul(e1z, e2x), vf_mul(e1x, e2z)), zero),
                               vf_eq(vf_sub(vf_mul(e1x, e2y), vf_mul(e1y, e2x)), zero)));
    return vm_not(flat);
}

LANES_BODY tri_result tri_vs_rays(lanes_tri_algo algo, const lanes_vray *r,
                                  const lanes_triangle *tri, bool want_uv)
{
    if (lanes_triangle_no_area(tri)) {
        tri_result none = {vf_zero(), vf_zero(), vf_zero(), vm_false(), vm_false()};
        return none;
    }
    if (algo == LANES_TRI_WATERTIGHT) return watertight_packet_core(r, tri, want_uv);
    return moller_core(r->ox, r->oy, r->oz, r->dx, r->dy, r->dz, vf_set1(tri->v0[0]),
                       vf_set1(tri->v0[1]), vf_set1(tri->v0[2]), vf_set1(tri->v1[0]),
                       vf_set1(tri->v1[1]), vf_set1(tri->v1[2]), vf_set1(tri->v2[0]),
                       vf_set1(tri->v2[1]), vf_set1(tri->v2[2]), r->tnear, r->tfar, r->live,
                       want_uv);
}

/* One ray against LANES_W triangles at once, from SoA triangle arrays
 * (ray_vs_tris: unaligned, a BVH2 leaf's triangles start anywhere) or from
 * a wide BVH's leaf block (ray_vs_block: aligned). field[vtx][a] is the SoA
 * field (v0x .. v2z = 0 .. 8) of vertex vtx's axis a, the axes permuted for
 * the watertight test. */
typedef struct {
    int field[3][3];
    const float *soa[9];
    float o_perm[3], d_perm[3]; /* the ray in field's axis order */
    vfloat ox, oy, oz, dx, dy, dz, sx, sy, sz, tnear, tfar;
} wide_setup;

/* t may be NULL when only blocks are tested. Filled in place: a returned
 * copy of the struct (hundreds of bytes) costs as much as a leaf test. */
LANES_BODY void wide_setup_init(wide_setup *w, lanes_tri_algo algo, const lanes_ray *ray,
                                const lanes_triangles *t)
{
    int order[3] = {0, 1, 2};
    float o[3] = {ray->o[0], ray->o[1], ray->o[2]};
    float sx = 0.0f, sy = 0.0f, sz = 0.0f;
    if (algo == LANES_TRI_WATERTIGHT) {
        wt_setup s = wt_setup_ray(ray->d);
        order[0] = s.kx, order[1] = s.ky, order[2] = s.kz;
        sx = s.sx, sy = s.sy, sz = s.sz;
        o[0] = ray->o[s.kx], o[1] = ray->o[s.ky], o[2] = ray->o[s.kz];
    }
    /* soa is read only by ray_vs_tris, which needs t; blocks read field */
    if (t) {
        const float *all[9] = {t->v0x, t->v0y, t->v0z, t->v1x, t->v1y, t->v1z, t->v2x, t->v2y, t->v2z};
        memcpy(w->soa, all, sizeof w->soa);
    }
    for (int vtx = 0; vtx < 3; vtx++)
        for (int a = 0; a < 3; a++) w->field[vtx][a] = vtx * 3 + order[a];
    for (int a = 0; a < 3; a++) {
        w->o_perm[a] = o[a];
        w->d_perm[a] = ray->d[order[a]];
    }
    w->ox = vf_set1(o[0]), w->oy = vf_set1(o[1]), w->oz = vf_set1(o[2]);
    w->dx = vf_set1(ray->d[0]), w->dy = vf_set1(ray->d[1]), w->dz = vf_set1(ray->d[2]);
    w->sx = vf_set1(sx), w->sy = vf_set1(sy), w->sz = vf_set1(sz);
    w->tnear = vf_set1(ray->tnear), w->tfar = vf_set1(ray->tfar);
}

/* Decides the near_zero lanes of one ray against LANES_W triangles, all in
 * field's axis order (the sign of t does not depend on the order). */
LANES_COLD void wt_settle_tris(tri_result *h, const wide_setup *w, vfloat v[3][3], vfloat tfar)
{
    float vert[3][3][LANES_W], t[LANES_W], far[LANES_W];
    for (int c = 0; c < 3; c++)
        for (int a = 0; a < 3; a++) vf_storeu(vert[c][a], v[c][a]);
    vf_storeu(t, h->t), vf_storeu(far, tfar);
    float tnear = vf_lane(w->tnear, 0);
    uint32_t doubt = vm_bits(h->near_zero), hits = 0;
    for (int j = 0; j < LANES_W; j++) {
        if (!(doubt & (1u << j))) continue;
        float p[3][3];
        for (int c = 0; c < 3; c++)
            for (int a = 0; a < 3; a++) p[c][a] = vert[c][a][j];
        int sign = exact_plane_t_sign(p[0], p[1], p[2], w->o_perm, w->d_perm);
        if (wt_settle_lane(&t[j], sign, tnear, far[j])) hits |= 1u << j;
    }
    h->t = vf_loadu(t);
    h->hit = vm_or(h->hit, vm_from_bits(hits));
    h->near_zero = vm_false();
}

LANES_BODY tri_result ray_vs_vectors(lanes_tri_algo algo, const wide_setup *w, vfloat v[3][3],
                                     vfloat tfar, vmask live, bool want_uv)
{
    if (algo == LANES_TRI_WATERTIGHT) {
        tri_result h = watertight_core(
            vf_sub(v[0][0], w->ox), vf_sub(v[0][1], w->oy), vf_sub(v[0][2], w->oz),
            vf_sub(v[1][0], w->ox), vf_sub(v[1][1], w->oy), vf_sub(v[1][2], w->oz),
            vf_sub(v[2][0], w->ox), vf_sub(v[2][1], w->oy), vf_sub(v[2][2], w->oz), w->sx, w->sy,
            w->sz, w->tnear, tfar, live, want_uv);
        if (vm_any(h.near_zero)) wt_settle_tris(&h, w, v, tfar);
        return h;
    }
    return moller_core(w->ox, w->oy, w->oz, w->dx, w->dy, w->dz, v[0][0], v[0][1], v[0][2], v[1][0],
                       v[1][1], v[1][2], v[2][0], v[2][1], v[2][2], w->tnear, tfar, live, want_uv);
}

LANES_BODY tri_result ray_vs_tris(lanes_tri_algo algo, const wide_setup *w, size_t i, vfloat tfar,
                                  vmask live, bool want_uv)
{
    vfloat v[3][3];
    for (int k = 0; k < 3; k++)
        for (int a = 0; a < 3; a++) v[k][a] = vf_loadu(w->soa[w->field[k][a]] + i);
    /* degenerate triangles are never hit (see lanes_triangle_no_area); the test is
     * the same whatever order the axes are in */
    live = vm_and(live, tris_have_area(v[0][0], v[0][1], v[0][2], v[1][0], v[1][1], v[1][2], v[2][0],
                                       v[2][1], v[2][2]));
    return ray_vs_vectors(algo, w, v, tfar, live, want_uv);
}

/* Lanes k .. k+LANES_W-1 of a leaf block of LANES_WIDE_WIDTH triangles
 * (its fields that many floats apart). The build gave padding lanes and triangles of no area NaN
 * vertices, so every lane is tested and those miss. */
LANES_BODY tri_result ray_vs_block(lanes_tri_algo algo, const wide_setup *w, const float *block,
                                   size_t k, vfloat tfar, bool want_uv)
{
    /* Only the watertight test permutes the axes; the others read the
     * fields at constant offsets rather than through field[][] (11% of a
     * shadow ray's instructions on the default scene, callgrind), and
     * straight into the test's arguments: through an array of vectors,
     * the avx512emu set (whose vectors are structs of two) kept every
     * vertex in memory: with the in-place node_ray, its single-ray
     * traversal ran 18% fewer instructions without it (callgrind, dragon). */
    if (algo == LANES_TRI_WATERTIGHT) {
        vfloat v[3][3];
        for (int c = 0; c < 3; c++)
            for (int a = 0; a < 3; a++) v[c][a] = vf_load(block + (size_t)w->field[c][a] * LANES_WIDE_WIDTH + k);
        return ray_vs_vectors(algo, w, v, tfar, vm_true(), want_uv);
    }
#define BLOCK_FIELD(f) vf_load(block + (size_t)(f) * LANES_WIDE_WIDTH + k)
    return moller_core(w->ox, w->oy, w->oz, w->dx, w->dy, w->dz, BLOCK_FIELD(0), BLOCK_FIELD(1), BLOCK_FIELD(2),
                       BLOCK_FIELD(3), BLOCK_FIELD(4), BLOCK_FIELD(5), BLOCK_FIELD(6), BLOCK_FIELD(7),
                       BLOCK_FIELD(8), w->tnear, tfar, vm_true(), want_uv);
#undef BLOCK_FIELD
}

/* Lanes k .. k+LANES_W-1 of a shared leaf block (lanes_wbvh_share): triangle
 * ids, whose vertices are gathered from the caller's arrays (indices: three
 * per triangle; verts: xyz per vertex) in field's axis order. Padding
 * (LANES_NO_HIT) gathers triangle 0 and is masked off; triangles of no area
 * are found here, as in ray_vs_tris, where the copied blocks hold NaN. */
LANES_BODY tri_result ray_vs_shared(lanes_tri_algo algo, const wide_setup *w, const float *verts,
                                    const uint32_t *indices, const uint32_t *prim, size_t k, vfloat tfar,
                                    bool want_uv)
{
    vint id = vi_loadu((const int32_t *)(const void *)(prim + k));
    vmask real = vm_not(vi_lt(id, vi_zero()));
    id = vi_select(real, id, vi_zero());
    vint at = vi_add(vi_add(id, id), id);
    vfloat v[3][3];
    for (int c = 0; c < 3; c++) {
        vint vtx = vi_gather((const int32_t *)(const void *)indices + c, at);
        vint base = vi_add(vi_add(vtx, vtx), vtx);
        for (int a = 0; a < 3; a++) v[c][a] = vf_gather(verts + (w->field[c][a] - 3 * c), base);
    }
    vmask live = vm_and(real, tris_have_area(v[0][0], v[0][1], v[0][2], v[1][0], v[1][1], v[1][2], v[2][0],
                                             v[2][1], v[2][2]));
    return ray_vs_vectors(algo, w, v, tfar, live, want_uv);
}

/* Closest hit: the ray's tfar shrinks to the best t so far, so later
 * vectors only report nearer (or equally near) hits; ties keep the lowest
 * index because a later vector must be strictly nearer to win. */
LANES_BODY long tri_closest_body(lanes_tri_algo algo, const lanes_ray *ray,
                                 const lanes_triangles *tris, size_t n, float *t, float *u,
                                 float *v, lanes_lane_stats *stats)
{
    wide_setup w;
    wide_setup_init(&w, algo, ray, tris);
    vfloat tfar = w.tfar;
    float best_t = ray->tfar, best_u = 0.0f, best_v = 0.0f;
    long best = -1;
    for (size_t i = 0; i < n; i += LANES_W) {
        vmask live = vm_first_n(n - i);
        tri_result h = ray_vs_tris(algo, &w, i, tfar, live, true);
        LANES_COUNT(stats, live);
        if (vm_none(h.hit)) continue;
        float tmin = vf_reduce_min(vf_select(h.hit, h.t, vf_set1(INFINITY)));
        if (best >= 0 && !(tmin < best_t)) continue;
        uint32_t at = vm_bits(vm_and(h.hit, vf_eq(h.t, vf_set1(tmin))));
        int lane = __builtin_ctz(at);
        best = (long)(i + (size_t)lane);
        best_t = tmin;
        best_u = vf_lane(h.u, lane);
        best_v = vf_lane(h.v, lane);
        tfar = vf_set1(best_t);
    }
    if (best >= 0) {
        *t = best_t;
        *u = best_u;
        *v = best_v;
    }
    return best;
}

LANES_BODY bool tri_any_body(lanes_tri_algo algo, const lanes_ray *ray, const lanes_triangles *tris,
                             size_t n, lanes_lane_stats *stats)
{
    wide_setup w;
    wide_setup_init(&w, algo, ray, tris);
    for (size_t i = 0; i < n; i += LANES_W) {
        vmask live = vm_first_n(n - i);
        tri_result h = ray_vs_tris(algo, &w, i, w.tfar, live, false);
        LANES_COUNT(stats, live);
        if (vm_any(h.hit)) return true;
    }
    return false;
}

#endif
