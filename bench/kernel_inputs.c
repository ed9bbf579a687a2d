/* Benchmark scene. Everything is placed in "tangent space" of a pinhole
 * camera: a point (u, v) at depth z is the world point o + (u z, v z, z).
 * A primitive's shadow in tangent space is what a primary ray sees, so hit
 * rates follow from areas there:
 * - packet and wide boxes: centre uniform over the tile; a shadow of
 *   half-size w/2 covers w - w^2/4 of the tile per axis on average, so
 *   w = 0.92 tiles gives 0.5 overall (the half-size is set a little below
 *   0.46 because the box's depth widens its shadow);
 * - triangles: one edge passes near the tile centre at a random angle and
 *   the triangle extends 3 tiles beyond it, so it covers about half;
 * - culled boxes and triangles: spread over 2.36 tiles per axis, with a
 *   size such that somewhat under half of them touch the tile (the culls
 *   are conservative and keep a few more).
 * The benchmark prints the rates it actually got. */
#include "bench/kernel_inputs.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#define IMAGE_SIDE 1024
#define TAN_HALF_FOV 0.57735027f /* 60 degree field of view */
#define TILE_X0 640              /* an off-centre tile: no axis symmetry to flatter a kernel */
#define TILE_Y0 384
#define SEED 0x6c616e6573ull     /* "lanes" */

static const float origin[3] = {1.5f, -0.5f, 2.0f};

typedef struct {
    uint64_t s;
} rng;

/* splitmix64: tiny, and the same sequence on every platform. */
static uint64_t rng_next(rng *r)
{
    uint64_t z = (r->s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static float uniform(rng *r, float lo, float hi)
{
    float u = (float)(rng_next(r) >> 40) * 0x1p-24f;
    return lo + (hi - lo) * u;
}

/* Tangent-space coordinate of a pixel centre. */
static float pixel_tan(float p) { return ((p + 0.5f) / (IMAGE_SIDE / 2) - 1.0f) * TAN_HALF_FOV; }

static const float tile_size = KI_PACKET_SIDE * 2.0f * TAN_HALF_FOV / IMAGE_SIDE;

static void tile_lo(float lo[2])
{
    lo[0] = pixel_tan(TILE_X0) - 0.5f * tile_size / KI_PACKET_SIDE;
    lo[1] = pixel_tan(TILE_Y0) - 0.5f * tile_size / KI_PACKET_SIDE;
}

static void to_world(float u, float v, float z, float out[3])
{
    out[0] = origin[0] + u * z;
    out[1] = origin[1] + v * z;
    out[2] = origin[2] + z;
}

/* Morton order inside the tile: a SIMD group of 4, 8 or 16 consecutive
 * rays is a compact 2x2, 4x2 or 4x4 block, as packet tracers arrange them. */
static void morton_xy(unsigned m, unsigned *x, unsigned *y)
{
    *x = *y = 0;
    for (unsigned b = 0; b < 16; b++) {
        *x |= ((m >> (2 * b)) & 1u) << b;
        *y |= ((m >> (2 * b + 1)) & 1u) << b;
    }
}

/* A box whose tangent-space shadow is centred at (cu, cv) with half-size
 * about hs. Its depth extent is hs * z as well: a deeper box casts a wider
 * shadow (its near face is closer, and the tile is off-centre). */
static lanes_box box_at(rng *r, float cu, float cv, float hs)
{
    lanes_box b;
    float z = uniform(r, 6.0f, 20.0f), c[3];
    to_world(cu, cv, z, c);
    float h[3] = {hs * z, hs * z, hs * z};
    for (int a = 0; a < 3; a++) b.min[a] = c[a] - h[a], b.max[a] = c[a] + h[a];
    return b;
}

/* A triangle with one edge through (pu, pv) at a random angle, extending
 * `reach` beyond it: it covers the half of the tile on one side of the edge. */
static lanes_triangle half_plane_triangle(rng *r, float pu, float pv, float reach)
{
    lanes_triangle t;
    float th = uniform(r, 0.0f, 6.2831853f);
    float du = cosf(th), dv = sinf(th);
    float z0 = uniform(r, 6.0f, 20.0f);
    to_world(pu + reach * du, pv + reach * dv, z0 + uniform(r, -1.0f, 1.0f), t.v0);
    to_world(pu - reach * du, pv - reach * dv, z0 + uniform(r, -1.0f, 1.0f), t.v1);
    to_world(pu - reach * dv, pv + reach * du, z0 + uniform(r, -1.0f, 1.0f), t.v2);
    return t;
}

/* A small triangle around (cu, cv), for culling. */
static lanes_triangle small_triangle(rng *r, float cu, float cv, float spread)
{
    lanes_triangle t;
    float z0 = uniform(r, 6.0f, 20.0f);
    float *v[3] = {t.v0, t.v1, t.v2};
    for (int i = 0; i < 3; i++)
        to_world(cu + uniform(r, -spread, spread), cv + uniform(r, -spread, spread),
                 z0 + uniform(r, -0.5f, 0.5f), v[i]);
    return t;
}

static void put_box(lanes_boxes *b, size_t i, lanes_box x)
{
    b->minx[i] = x.min[0], b->miny[i] = x.min[1], b->minz[i] = x.min[2];
    b->maxx[i] = x.max[0], b->maxy[i] = x.max[1], b->maxz[i] = x.max[2];
}

static void put_tri(lanes_triangles *t, size_t i, lanes_triangle x)
{
    t->v0x[i] = x.v0[0], t->v0y[i] = x.v0[1], t->v0z[i] = x.v0[2];
    t->v1x[i] = x.v1[0], t->v1y[i] = x.v1[1], t->v1z[i] = x.v1[2];
    t->v2x[i] = x.v2[0], t->v2y[i] = x.v2[1], t->v2z[i] = x.v2[2];
}

bool kernel_inputs_make(kernel_inputs *in)
{
    const lanes_kernels *scalar = lanes_kernels_for(LANES_ISA_SCALAR);
    rng r = {SEED};
    float lo[2];

    memset(in, 0, sizeof *in);
    if (!scalar) return false;
    tile_lo(lo);
    if (!lanes_rays_alloc(&in->packet, KI_PACKET_RAYS) ||
        !lanes_boxes_alloc(&in->wide_boxes, KI_WIDE_COUNT) ||
        !lanes_triangles_alloc(&in->wide_tris, KI_WIDE_COUNT) ||
        !lanes_boxes_alloc(&in->cull_boxes, KI_CULL_COUNT) ||
        !lanes_triangles_alloc(&in->cull_tris, KI_CULL_COUNT)) {
        kernel_inputs_free(in);
        return false;
    }

    lanes_rays *p = &in->packet;
    for (unsigned m = 0; m < KI_PACKET_RAYS; m++) {
        unsigned x, y;
        morton_xy(m, &x, &y);
        float u = pixel_tan((float)(TILE_X0 + x)), v = pixel_tan((float)(TILE_Y0 + y));
        float len = sqrtf(u * u + v * v + 1.0f);
        p->ox[m] = origin[0], p->oy[m] = origin[1], p->oz[m] = origin[2];
        p->dx[m] = u / len, p->dy[m] = v / len, p->dz[m] = 1.0f / len;
        p->tnear[m] = 0.0f;
        p->tfar[m] = INFINITY;
    }
    scalar->rays_prepare(p, LANES_RCP_EXACT);

    /* Single rays spread over the tile: every 64th ray in Morton order. */
    for (unsigned j = 0; j < KI_WIDE_RAYS; j++) {
        unsigned m = j * (KI_PACKET_RAYS / KI_WIDE_RAYS) + 21;
        lanes_ray *w = &in->wide_rays[j];
        w->o[0] = p->ox[m], w->o[1] = p->oy[m], w->o[2] = p->oz[m];
        w->d[0] = p->dx[m], w->d[1] = p->dy[m], w->d[2] = p->dz[m];
        w->tnear = p->tnear[m], w->tfar = p->tfar[m];
        lanes_ray_prepare(w);
    }

    const float hs = 0.40f * tile_size;
    for (size_t i = 0; i < KI_PACKET_PRIMS; i++) {
        in->packet_boxes[i] = box_at(&r, lo[0] + uniform(&r, 0.0f, tile_size),
                                     lo[1] + uniform(&r, 0.0f, tile_size), hs);
        in->packet_tris[i] = half_plane_triangle(
            &r, lo[0] + tile_size * uniform(&r, 0.4f, 0.6f),
            lo[1] + tile_size * uniform(&r, 0.4f, 0.6f), 3.0f * tile_size);
    }
    for (size_t i = 0; i < KI_WIDE_COUNT; i++) {
        put_box(&in->wide_boxes, i,
                box_at(&r, lo[0] + uniform(&r, 0.0f, tile_size),
                       lo[1] + uniform(&r, 0.0f, tile_size), hs));
        put_tri(&in->wide_tris, i,
                half_plane_triangle(&r, lo[0] + tile_size * uniform(&r, 0.4f, 0.6f),
                                    lo[1] + tile_size * uniform(&r, 0.4f, 0.6f),
                                    3.0f * tile_size));
    }
    /* A shadow of half-size ~0.29 tiles overlaps the tile for (1 + 0.58) / 2.36
     * = 0.67 of the centres per axis: 0.45 overall. */
    for (size_t i = 0; i < KI_CULL_COUNT; i++) {
        put_box(&in->cull_boxes, i,
                box_at(&r, lo[0] + tile_size * uniform(&r, -0.68f, 1.68f),
                       lo[1] + tile_size * uniform(&r, -0.68f, 1.68f), 0.25f * tile_size));
        put_tri(&in->cull_tris, i,
                small_triangle(&r, lo[0] + tile_size * uniform(&r, -0.68f, 1.68f),
                               lo[1] + tile_size * uniform(&r, -0.68f, 1.68f),
                               0.5f * tile_size));
    }

    scalar->frustum_build(p, NULL, p->count, &in->frustum);
    return true;
}

void kernel_inputs_free(kernel_inputs *in)
{
    lanes_rays_free(&in->packet);
    lanes_boxes_free(&in->wide_boxes);
    lanes_triangles_free(&in->wide_tris);
    lanes_boxes_free(&in->cull_boxes);
    lanes_triangles_free(&in->cull_tris);
}
