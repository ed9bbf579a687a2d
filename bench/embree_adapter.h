/* Embree 3 as the reference engine for `lanes compare` and the traversal
 * tests: the same flat triangles (scene triangle i is Embree's geomID 0,
 * primID i), a device pinned to one Embree ISA, and the same rays traced
 * through each of Embree's query APIs, laid out for that API beforehand so
 * that only the trace calls are timed.
 *
 * Compiled for the x86-64 baseline (Embree dispatches internally). */
#ifndef LANES_BENCH_EMBREE_ADAPTER_H
#define LANES_BENCH_EMBREE_ADAPTER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "build/scene.h"
#include "trace/paths.h"
#include "trace/kernels.h"

/* Embree's own kernel sets, as its device config names them. */
typedef enum lanes_embree_isa {
    LANES_EMBREE_SSE2 = 0,
    LANES_EMBREE_SSE42,
    LANES_EMBREE_AVX,
    LANES_EMBREE_AVX2,
    LANES_EMBREE_AVX512,
    LANES_EMBREE_ISA_COUNT,
    LANES_EMBREE_ISA_NONE = -1
} lanes_embree_isa;

const char *lanes_embree_isa_name(lanes_embree_isa isa);
/* LANES_EMBREE_ISA_NONE for a name that is none of the above. Embree itself
 * silently falls back to SSE2 on an unknown name, hence the check here. */
lanes_embree_isa lanes_embree_isa_from_name(const char *name);
/* By lanes_cpu(), so LANES_DISABLE_CPU_FEATURES applies to Embree too. */
bool lanes_embree_isa_cpu_can_run(lanes_embree_isa isa);
lanes_embree_isa lanes_embree_isa_best(void);
/* "sse2, sse4.2, avx, avx2, avx512" for messages. */
const char *lanes_embree_isa_all_names(void);

/* The query APIs. Packets take consecutive rays (ray k*W+j is lane j of
 * packet k), the last packet masked by its valid array. */
typedef enum lanes_embree_method {
    LANES_EMBREE_1 = 0, /* rtcIntersect1 / rtcOccluded1, one call per ray */
    LANES_EMBREE_4,     /* rtcIntersect4 / rtcOccluded4 */
    LANES_EMBREE_8,
    LANES_EMBREE_16,
    LANES_EMBREE_1M,    /* rtcIntersect1M / rtcOccluded1M, one call per range */
    LANES_EMBREE_NP,    /* rtcIntersectNp / rtcOccludedNp: the stream as SoA arrays, one call per range */
    LANES_EMBREE_METHOD_COUNT
} lanes_embree_method;

/* "rtcIntersect4", "rtcOccluded1M", ... */
const char *lanes_embree_method_name(lanes_embree_method m, bool occlusion);
/* Rays per packet: 4, 8, 16; 1 for the single-ray and stream calls. A
 * range passed to lanes_embree_batch_trace starts at a multiple of it. */
int lanes_embree_method_width(lanes_embree_method m);

typedef struct lanes_embree lanes_embree;

/* Builds the scene on a new device ("isa=...,threads=N"; threads 0 = all
 * hardware threads, which only the build uses: trace calls run on the
 * caller's thread). The commit is timed with FTZ/DAZ set. An error, with a
 * message, on an ISA the CPU cannot run, Embree errors, or no memory. */
lanes_status lanes_embree_create(const lanes_scene *scene, lanes_embree_isa isa, int threads,
                                 lanes_embree **out, lanes_error *err);
void lanes_embree_destroy(lanes_embree *e);
double lanes_embree_build_seconds(const lanes_embree *e);
/* Bytes the scene build kept (its memory monitor's net over rtcCommitScene):
 * the BVH with its triangle leaves, not the vertex and index buffers. */
double lanes_embree_bvh_bytes(const lanes_embree *e);
lanes_embree_isa lanes_embree_get_isa(const lanes_embree *e);
/* Whether this device runs the method natively (Embree reports an error
 * for rtcIntersect8 on an SSE device, for example). */
bool lanes_embree_supports(const lanes_embree *e, lanes_embree_method m);
/* The first Embree error since creation (empty when none). */
const char *lanes_embree_error(const lanes_embree *e);

/* Rays laid out for one method: RTCRayHit / RTCRay arrays for the single
 * and stream calls, RTCRayHitW / RTCRayW packet arrays (aligned to 16, 32,
 * 64 bytes) for the packets, one array of count 32-bit values per field
 * (ray fields, then hit fields) for the Np call. A pristine copy restores the rays that a trace
 * overwrote (tfar, hit) before the next repetition. */
typedef struct lanes_embree_batch {
    lanes_embree_method method;
    bool occlusion;
    size_t count;    /* rays */
    size_t bytes;    /* of data and of pristine */
    void *data;
    void *pristine;
    int *valid_full; /* W ints of -1 */
    int *valid_tail; /* the last packet's valid lanes */
} lanes_embree_batch;

lanes_status lanes_embree_batch_init(lanes_embree_batch *b, lanes_embree_method m, bool occlusion,
                                     const lanes_ray *rays, size_t n, lanes_error *err);
void lanes_embree_batch_free(lanes_embree_batch *b);
/* Restores every ray as it was at init (not timed by the callers). */
void lanes_embree_batch_reset(lanes_embree_batch *b);
/* Rays [begin, end) of the batch; begin a multiple of the method's width.
 * coherent: RTC_INTERSECT_CONTEXT_FLAG_COHERENT, else the default context.
 * Safe to call from several threads on disjoint ranges. */
void lanes_embree_batch_trace(const lanes_embree *e, lanes_embree_batch *b, size_t begin,
                              size_t end, bool coherent);
/* Results after a trace: closest hits as lanes reports them (t, u, v of
 * v1 and v2, prim; LANES_NO_HIT and t = inf for a miss), or occlusion flags. */
void lanes_embree_batch_hits(const lanes_embree_batch *b, lanes_hit *hits);
void lanes_embree_batch_occluded(const lanes_embree_batch *b, uint8_t *occluded);

/* Convenience for tests: every ray through rtcIntersect1 / rtcOccluded1. */
void lanes_embree_trace1(const lanes_embree *e, const lanes_ray *rays, size_t n, lanes_hit *hits);
void lanes_embree_occluded1(const lanes_embree *e, const lanes_ray *rays, size_t n,
                            uint8_t *occluded);

/* n rays in one rtcIntersect1M / rtcOccluded1M call (a ray stream: Embree
 * sorts and traverses it as it sees fit; one ray: rtcIntersect1 /
 * rtcOccluded1), the answers as above. For
 * lanes paths --intersector embree. Safe from several threads. */
void lanes_embree_trace_stream(const lanes_embree *e, const lanes_ray *rays, size_t n, lanes_hit *hits);
void lanes_embree_occluded_stream(const lanes_embree *e, const lanes_ray *rays, size_t n, uint8_t *occluded);

/* The path tracer's intersector that traces with e: rtcIntersect1M and
 * rtcOccluded1M on each call's rays, rtcIntersect1 and rtcOccluded1 on a
 * call of one. */
lanes_paths_intersector lanes_embree_paths_intersector(const lanes_embree *e);

/* Flush-to-zero and denormals-are-zero, as Embree asks of every thread that
 * traces; both engines are timed under the same MXCSR. Returns the previous
 * control word for lanes_fp_restore. */
unsigned lanes_fp_fast_enter(void);
void lanes_fp_restore(unsigned saved);

#endif
