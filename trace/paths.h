/* The path tracer (Afra, Benthin, Wald and Munkberg 2016 measure shading
 * coherence on one): unidirectional, with next-event estimation. At each
 * hit the material's BSDF (trace/bsdf.h) is built; one shadow ray goes to
 * one light picked by power (a point light or a point on a parallelogram
 * light); one extension ray is sampled from the BSDF; Russian roulette from
 * the third bounce. Emissive triangles are not sampled by the shadow rays,
 * so their emission counts at every hit, except the two triangles that
 * show a visible parallelogram light (`@area_light_N`), which the shadow
 * rays do sample: those count on camera rays and after delta bounces
 * (mirror, glass) only, and on their emitting side only. A diffuse
 * material's `emission`, when set, counts at every hit. Misses see the
 * background: the scene's sky, or a uniform color. Every material kind of
 * build/scene.h shades with its own BSDF (a rough glass as
 * LANES_BSDF_ROUGH_GLASS); a textured material's albedo is its texture's
 * color at each hit point, evaluated by the set's texture kernel.
 *
 * Random numbers are a function of (pixel, sample, depth, dimension)
 * (simd/vrandom.h's hash), so a path's samples do not depend on the order
 * paths are traced in or on the method.
 *
 * Methods (the paper's baselines and its streams), all with the set's
 * single-ray traversal (trace_wide, occluded_wide):
 *   single        one path at a time, shaded by the scalar set's BSDF
 *                 kernels;
 *   single-1lane  the same, shaded by the set's own kernels with one live
 *                 lane (what a width costs a path that shades alone);
 *   packet        W paths of a tile (one sample of W pixels) go on
 *                 together; at each bounce each material present shades
 *                 under its lane mask in one W-lane call; finished paths
 *                 leave their lanes empty. The same radiance as
 *                 single-1lane, bit for bit, per (pixel, sample);
 *   stream        per thread a stream of S paths in flight (their
 *                 extension rays traced in one call, compact); the paths
 *                 to shade sorted by material (a stable counting sort),
 *                 shaded W at a time in that order, their shadow rays
 *                 collected and traced in one call; finished paths' slots
 *                 refilled with camera rays of the same 16x16 tile. The
 *                 same radiance again, bit for bit.
 *
 * Compiled for the x86-64 baseline: per-ray work happens in the kernels. */
#ifndef LANES_TRACE_PATHS_H
#define LANES_TRACE_PATHS_H

#include <stdbool.h>
#include <stdint.h>

#include "build/scene.h"
#include "trace/render.h"

typedef enum lanes_paths_method {
    LANES_PATHS_SINGLE = 0,
    LANES_PATHS_SINGLE_1LANE,
    LANES_PATHS_PACKET,
    LANES_PATHS_STREAM,
    LANES_PATHS_METHOD_COUNT
} lanes_paths_method;

const char *lanes_paths_method_name(lanes_paths_method m);
/* -1 for an unknown name */
int lanes_paths_method_from_name(const char *name);

#define LANES_PATHS_MAX_DEPTH 32
#define LANES_PATHS_MIN_STREAM 256
#define LANES_PATHS_MAX_STREAM 65536

/* Where the stream method's time goes, summed over threads. */
typedef enum lanes_paths_stage {
    LANES_PATHS_STAGE_GENERATE = 0, /* camera rays into free slots; the stream's rays laid out */
    LANES_PATHS_STAGE_INTERSECT,    /* the extension rays */
    LANES_PATHS_STAGE_SORT,         /* by material */
    LANES_PATHS_STAGE_SHADE,        /* hits, emission, BSDF values and samples, shadow rays made */
    LANES_PATHS_STAGE_SHADOW,       /* the shadow rays traced, their light added */
    LANES_PATHS_STAGE_ACCUMULATE,   /* paths continued or finished, slots freed */
    LANES_PATHS_STAGE_COUNT
} lanes_paths_stage;
#define LANES_PATHS_MAX_SPP 65536

/* Another engine to trace with in place of the set's own traversal (lanes
 * paths --intersector embree races Embree's on the same paths): closest
 * hits and occlusion of n rays, answered as trace_wide and occluded_wide
 * answer (t, u, v, prim; LANES_NO_HIT for a miss). Called from every
 * render thread at once; the set's shading kernels stay in use. */
typedef struct lanes_paths_intersector {
    const char *name;
    void *ctx;
    void (*trace)(void *ctx, const lanes_ray *rays, size_t n, lanes_hit *hits);
    void (*occluded)(void *ctx, const lanes_ray *rays, size_t n, uint8_t *occluded);
} lanes_paths_intersector;

typedef struct lanes_paths_options {
    lanes_isa isa;
    lanes_paths_method method;
    lanes_accuracy accuracy; /* LANES_ACCURACY_FROM_SCENE by default */
    int width, height;       /* 0: the scene camera's */
    int spp;                 /* samples per pixel, 1 .. LANES_PATHS_MAX_SPP; one sample goes through the pixel's centre */
    int depth;               /* path vertices after the camera, 1 .. LANES_PATHS_MAX_DEPTH; default 8 */
    int threads;             /* 0: all cores */
    int stream;              /* stream method: paths in flight per thread, 256 .. 65536, a multiple of 16; default 2048 */
    bool uniform_background; /* misses see `background` instead of the sky */
    float background[3];
    const lanes_paths_intersector *intersector; /* NULL: the set's own traversal */
    /* Called with the fraction done after each tile, one call at a time
     * (from any worker thread); may be NULL. */
    void (*progress)(void *ctx, double fraction);
    void *progress_ctx;
} lanes_paths_options;

void lanes_paths_default_options(lanes_paths_options *o);

typedef struct lanes_paths_result {
    float *rgb;  /* width * height * 3, linear radiance, the mean of the samples */
    float *rgb2; /* the same pixels' mean of the samples' squares: a sample's variance is rgb2 - rgb^2 */
    int width, height;
    double seconds;
    uint64_t paths;          /* paths begun (camera rays) */
    uint64_t paths_finished; /* paths whose radiance reached the image: equal to paths, none lost or doubled */
    /* stream method: the stages after which the paths made were not the
     * finished plus those in flight, one slot each (0: none lost or
     * doubled on the way) */
    uint64_t accounting_errors;
    uint64_t rays_by_depth[LANES_PATHS_MAX_DEPTH + 1]; /* [0]: camera rays, [d]: extension rays of bounce d */
    uint64_t shadow_rays;
    /* Shading: kernel calls, the lane slots they offered and the lanes that
     * carried a hit; utilisation = live / slots. */
    uint64_t shade_calls, shade_slots, shade_live;
    /* The bsdf_sample calls among them, one per material present in a
     * packet's bounce or per W rays of a material in a stream's sorted
     * order: what a recount from the materials of the hits each trace call
     * returned gives (test_paths_sets does it). */
    uint64_t sample_calls, sample_slots, sample_live;
    double stage_seconds[LANES_PATHS_STAGE_COUNT]; /* stream method */
    size_t stream_bytes;                            /* stream method: each thread's stream state */
} lanes_paths_result;

/* accel: the wide BVH of opt->isa's set (lanes_render_accel_build). */
lanes_status lanes_paths_render(const lanes_scene *scene, const lanes_render_accel *accel,
                                const lanes_paths_options *opt, lanes_paths_result *out, lanes_error *err);
void lanes_paths_result_free(lanes_paths_result *r);

#endif
