/* The Whitted shading model, shared by the single-ray renderer (which traces
 * each ray as soon as it is made) and the packet renderer (which collects
 * rays by type and traces them in packets): both must compute the same
 * image, so both take their rays and weights from here.
 *
 * Baseline code, static inline (included by render.c and packet_render.c). */
#ifndef LANES_TRACE_SHADING_H
#define LANES_TRACE_SHADING_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "build/scene.h"
#include "build/vec3.h"
#include "trace/kernels.h"

/* Deterministic numbers in [0,1) from a hash, so images do not depend on
 * thread scheduling or on the order rays are traced in. */
static inline float lanes_hash01(uint32_t a, uint32_t b, uint32_t c)
{
    uint64_t x = ((uint64_t)a * 0x9E3779B97F4A7C15ull) ^ ((uint64_t)b << 32) ^ c;
    x ^= x >> 30;
    x *= 0xBF58476D1CE4E5B9ull;
    x ^= x >> 27;
    x *= 0x94D049BB133111EBull;
    x ^= x >> 31;
    return (float)(x >> 40) * 0x1p-24f;
}

static inline vec3 lanes_background(vec3 d)
{
    float t = 0.5f * (v3_normalize(d).y + 1.0f);
    return v3_add(v3_scale(v3(0.05f, 0.05f, 0.06f), 1.0f - t), v3_scale(v3(0.15f, 0.18f, 0.25f), t));
}


/* The surface a ray hit. */
typedef struct {
    vec3 p;        /* hit point, from the barycentrics (more accurate than o + t d) */
    vec3 perr;     /* bound on each coordinate's rounding error in p */
    vec3 nf;       /* geometric normal facing the incoming ray */
    bool front;    /* the ray came from the side the normal points to */
    const lanes_material *m;
} lanes_surface;

static inline lanes_surface lanes_surface_at(const lanes_scene *s, const lanes_hit *h, vec3 d)
{
    lanes_surface sf;
    const float *v = s->verts + (size_t)h->prim * 9;
    vec3 v0 = v3_load(v), e1 = v3_sub(v3_load(v + 3), v0), e2 = v3_sub(v3_load(v + 6), v0);
    vec3 n = v3_unit_normal(e1, e2);
    vec3 ue1 = v3_scale(e1, h->u), ve2 = v3_scale(e2, h->v);
    sf.p = v3_add(v0, v3_add(ue1, ve2));
    /* Whatever error u and v carry, any v0 + u e1 + v e2 lies in the
     * triangle's plane: p leaves the plane only by the rounding of this
     * sum. The edges (one rounding), the products and the inner sum (two)
     * make at most gamma(3) of |u e1| + |v e2|; the final sum one unit
     * roundoff of |p|. */
    const float u = 0x1p-24f, gamma3 = 3.0f * u / (1.0f - 3.0f * u);
    sf.perr = v3_add(v3_scale(v3_abs(sf.p), u), v3_scale(v3_add(v3_abs(ue1), v3_abs(ve2)), gamma3));
    sf.front = v3_dot(n, d) < 0.0f;
    sf.nf = sf.front ? n : v3_scale(n, -1.0f);
    sf.m = &s->materials[s->material_of[h->prim]];
    return sf;
}

/* The origin of a ray leaving the surface sf on the side the unit normal n
 * points to (sf->nf or its opposite).
 *
 * Fast and default modes move p along n by the scene epsilon: right while
 * the scene's coordinates are small against its size, wrong (self-hits,
 * shadow acne) once the rounding of p, about an ulp of |p|, exceeds it.
 *
 * Robust mode moves p out of the box of its rounding error (pbrt-v4's
 * error-bound offset, Pharr, Jakob, Humphreys 2023, 6.8.6): along n by
 * twice the box's extent in that direction, the factor 2 covering the
 * rounding of n itself and of the triangle test that decides whether the
 * new ray starts in front of the plane; then every coordinate one float
 * further out, so that rounding the sum cannot bring it back. The offset
 * grows with |p|, so it holds at any distance from the origin, and stays a
 * few ulps where Wächter and Binder's fixed 256 ulps (Ray Tracing Gems, ch.
 * 6) moved shadow origins 2 units off a sphere 1e5 from the origin. */
static inline float lanes_away(float x, float direction)
{
    return direction > 0.0f ? nextafterf(x, INFINITY) : direction < 0.0f ? nextafterf(x, -INFINITY) : x;
}

static inline vec3 lanes_offset_origin(const lanes_surface *sf, vec3 n, lanes_accuracy mode, float eps)
{
    if (mode != LANES_ACCURACY_ROBUST) return v3_add(sf->p, v3_scale(n, eps));
    float d = 2.0f * v3_dot(v3_abs(n), sf->perr);
    vec3 o = v3_add(sf->p, v3_scale(n, d));
    return v3(lanes_away(o.x, n.x), lanes_away(o.y, n.y), lanes_away(o.z, n.z));
}


/* The material alone, for renders whose shading reads no hit geometry
 * (lanes_scene_plan.hit_geometry false): no barycentrics, no normal. */
static inline lanes_surface lanes_surface_material(const lanes_scene *s, const lanes_hit *h)
{
    lanes_surface sf;
    memset(&sf, 0, sizeof sf);
    sf.m = &s->materials[s->material_of[h->prim]];
    return sf;
}

/* A shadow ray and what it adds when unoccluded. light: the point light's
 * index, or point_light_count + the area light's index. */
typedef struct {
    vec3 o, d;
    float tfar;
    vec3 add;
    uint32_t light;
} lanes_shadow_ray;

/* The light a diffuse surface receives: `ambient` always, each shadow ray's
 * `add` when the ray is unoccluded. Writes at most
 * point_light_count + area_light_count * area_samples rays. */
static inline int lanes_diffuse_light(const lanes_scene *s, const lanes_surface *sf, vec3 weight,
                                      uint32_t seed, lanes_accuracy mode, float eps, int area_samples,
                                      lanes_shadow_ray *out, vec3 *ambient)
{
    vec3 albedo = v3_mul(weight, v3_load(sf->m->color));
    vec3 origin = lanes_offset_origin(sf, sf->nf, mode, eps);
    int n = 0;
    *ambient = v3_scale(albedo, 0.03f); /* a little ambient, so unlit parts are not black */
    for (size_t i = 0; i < s->point_light_count; i++) {
        vec3 to = v3_sub(v3_load(s->point_lights[i].position), origin);
        float dist2 = v3_dot(to, to), dist = sqrtf(dist2);
        if (!(dist > 0.0f)) continue;
        vec3 l = v3_scale(to, 1.0f / dist);
        float cosine = v3_dot(sf->nf, l);
        if (cosine <= 0.0f) continue;
        vec3 in = v3_scale(v3_load(s->point_lights[i].intensity), cosine / (dist2 * LANES_PI));
        out[n++] = (lanes_shadow_ray){origin, l, dist * (1.0f - 1e-4f), v3_mul(albedo, in), (uint32_t)i};
    }
    for (size_t i = 0; i < s->area_light_count && area_samples > 0; i++) {
        const lanes_area_light *al = &s->area_lights[i];
        vec3 eu = v3_load(al->edge_u), ev = v3_load(al->edge_v);
        float area;
        vec3 ln = v3_unit_normal_area(eu, ev, &area);
        if (!(area > 0.0f)) continue;
        for (int k = 0; k < area_samples; k++) {
            float a = lanes_hash01(seed, (uint32_t)(2 * k), (uint32_t)i);
            float b = lanes_hash01(seed, (uint32_t)(2 * k + 1), (uint32_t)i);
            vec3 q = v3_add(v3_load(al->corner), v3_add(v3_scale(eu, a), v3_scale(ev, b)));
            vec3 to = v3_sub(q, origin);
            float dist2 = v3_dot(to, to), dist = sqrtf(dist2);
            if (!(dist > 0.0f)) continue;
            vec3 l = v3_scale(to, 1.0f / dist);
            float cos_p = v3_dot(sf->nf, l), cos_l = -v3_dot(ln, l);
            if (cos_p <= 0.0f || cos_l <= 0.0f) continue;
            float g = cos_p * cos_l * area / (dist2 * LANES_PI * (float)area_samples);
            out[n++] = (lanes_shadow_ray){origin, l, dist * (1.0f - 1e-4f),
                                          v3_mul(albedo, v3_scale(v3_load(al->emission), g)),
                                          (uint32_t)(s->point_light_count + i)};
        }
    }
    return n;
}

/* A reflected or refracted ray and the weight of what it brings back. */
typedef struct {
    vec3 o, d, weight;
    uint32_t seed;
} lanes_bounce_ray;

static inline vec3 lanes_reflect(vec3 d, vec3 n) { return v3_sub(d, v3_scale(n, 2.0f * v3_dot(d, n))); }

/* Mirror: one ray. Glass: reflection and refraction weighted by Schlick's
 * Fresnel term, or reflection alone under total internal reflection.
 * Returns the number of rays written (0 to 2). */
static inline int lanes_specular_rays(const lanes_surface *sf, vec3 d, vec3 weight, uint32_t seed,
                                      lanes_accuracy mode, float eps, lanes_bounce_ray out[2])
{
    vec3 color = v3_mul(weight, v3_load(sf->m->color));
    vec3 above = lanes_offset_origin(sf, sf->nf, mode, eps);
    if (lanes_material_whitted_kind(sf->m->kind) == LANES_MAT_MIRROR) {
        out[0] = (lanes_bounce_ray){above, lanes_reflect(d, sf->nf), color, seed * 31u + 7u};
        return 1;
    }
    if (sf->m->kind != LANES_MAT_GLASS) return 0;
    vec3 dn = v3_normalize(d);
    float ior = sf->m->ior;
    float eta = sf->front ? 1.0f / ior : ior;
    float cosi = -v3_dot(dn, sf->nf);
    float k = 1.0f - eta * eta * (1.0f - cosi * cosi);
    vec3 refl_dir = lanes_reflect(dn, sf->nf);
    if (k < 0.0f) {
        out[0] = (lanes_bounce_ray){above, refl_dir, color, seed * 31u + 11u};
        return 1;
    }
    float r0 = (1.0f - ior) / (1.0f + ior);
    r0 *= r0;
    float fresnel = r0 + (1.0f - r0) * powf(1.0f - cosi, 5.0f);
    vec3 refr_dir = v3_add(v3_scale(dn, eta), v3_scale(sf->nf, eta * cosi - sqrtf(k)));
    out[0] = (lanes_bounce_ray){above, refl_dir, v3_scale(color, fresnel), seed * 31u + 11u};
    out[1] = (lanes_bounce_ray){lanes_offset_origin(sf, v3_scale(sf->nf, -1.0f), mode, eps), refr_dir,
                                v3_scale(color, 1.0f - fresnel), seed * 31u + 13u};
    return 2;
}

/* The most shadow rays one diffuse hit makes. */
static inline int lanes_max_shadow_rays(const lanes_scene *s, int area_samples)
{
    return (int)(s->point_light_count + s->area_light_count * (size_t)(area_samples > 0 ? area_samples : 0));
}

#endif
