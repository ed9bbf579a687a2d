/* The Whitted renderer: primary rays, shadow rays to point lights and to
 * sampled area lights, and mirror reflection and refraction up to a bounce
 * limit (the thesis' test set-up, Wu 2016 3.2). It traces through the
 * kernel table of one instruction set and one traversal scheme.
 *
 * Compiled for the x86-64 baseline: all per-ray work happens in the kernels. */
#ifndef LANES_TRACE_RENDER_H
#define LANES_TRACE_RENDER_H

#include <stdbool.h>
#include <stdint.h>

#include "build/bvh.h"
#include "build/scene.h"
#include "trace/kernels.h"

typedef enum lanes_scheme {
    LANES_SCHEME_SINGLE = 0, /* single ray through the BVH2 */
    LANES_SCHEME_WIDE,       /* single ray through the wide BVH of the set's width */
    LANES_SCHEME_COUNT
} lanes_scheme;

const char *lanes_scheme_name(lanes_scheme s);
/* -1 for an unknown name */
int lanes_scheme_from_name(const char *name);

#define LANES_MAX_DEPTH 32

typedef struct lanes_render_options {
    lanes_isa isa;
    lanes_scheme scheme;
    lanes_accuracy accuracy; /* see build/accuracy.h; default LANES_ACCURACY_FROM_SCENE */
    int width, height;
    int spp;             /* samples per pixel, stratified */
    int threads;         /* 0: all cores */
    int max_depth;       /* specular bounces, default 10, at most LANES_MAX_DEPTH */
    int area_samples;    /* shadow rays per area light per hit, default 4 */
    int node_width;      /* the wide scheme's node width (lanes_kernels_for_width);
                          * 0: the set's own */
    bool count;          /* the traversal's counters into the result's stats
                          * (slower: for a counting run, not a timed one) */
    /* Called from worker threads with the fraction done; may be NULL. */
    void (*progress)(void *ctx, double fraction);
    void *progress_ctx;
    /* The wide scheme through the public API (lanes_intersect1 and
     * lanes_occluded1 on this accel, whose device must have the same set and
     * accuracy mode) instead of the kernel table; NULL: the kernel table. */
    lanes_accel api_accel;
} lanes_render_options;

void lanes_render_default_options(lanes_render_options *o);

typedef struct lanes_render_result {
    float *rgb;             /* width * height * 3, linear radiance */
    int width, height;
    double seconds;         /* wall time of the trace */
    uint64_t rays;          /* every ray traced: camera, shadow, secondary */
    uint64_t camera_rays, shadow_rays, secondary_rays;
    uint64_t secondary_by_depth[LANES_MAX_DEPTH + 1]; /* reflection/refraction rays of each bounce */
    lanes_trace_stats stats; /* every ray's traversal, with options.count; else zero */
} lanes_render_result;

/* The acceleration structure a render needs: the wide BVH of a set for the
 * wide scheme, else the BVH2 (single ray and packets). */
typedef struct lanes_render_accel {
    lanes_bvh2 bvh2;        /* node_count 0 when not built */
    lanes_wbvh wide;        /* width == the kernel table's wide_width (the set's own, or
                             * the options' node_width), or 0 when not built */
} lanes_render_accel;

/* wide_for: the set whose wide BVH to build (lanes_wbvh_build), or NULL;
 * bvh2: build the BVH2 too (the single scheme and the packet renderer read
 * it). At least one of them. */
lanes_status lanes_render_accel_build(const lanes_scene *scene, const lanes_kernels *wide_for, bool bvh2,
                                      int threads, lanes_render_accel *a, lanes_error *err);
void lanes_render_accel_free(lanes_render_accel *a);

/* A public-API accel over the scene's triangles (prim_id = scene triangle
 * index), for lanes_render_options.api_accel. */
lanes_status lanes_render_api_accel_create(const lanes_scene *scene, lanes_device device,
                                           lanes_accel *accel);

/* Monotonic wall time in seconds, the clock both renderers time with. */
double lanes_render_clock(void);

lanes_status lanes_render(const lanes_scene *scene, const lanes_render_accel *accel,
                          const lanes_render_options *opt, lanes_render_result *out, lanes_error *err);
void lanes_render_result_free(lanes_render_result *r);

#endif
