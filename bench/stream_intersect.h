/* The intersection stage of the stream path tracer, alone, on its own
 * rays (Afra et al. 2016 trace each stream with the same single-ray
 * kernel; which call should a stream go through?): the extension-ray
 * streams of one `lanes paths --method stream` render are captured call
 * by call, then each captured stream is traced again through
 *   - the set's trace_wide on the renderer's AoS rays (what it calls),
 *   - the public SoA call, lanes_intersect_stream, which sets its rays up
 *     (checks, 1/d) inside the call,
 *   - the same set-up done on the AoS rays before trace_wide (what the
 *     renderer's generate stage does for it),
 *   - Embree (a lanes built with it): rtcIntersect1 per ray, rtcIntersect8
 *     and 16 on consecutive rays, rtcIntersect1M and rtcIntersectNp (SoA,
 *     no copy) per stream; each with and without the coherent flag,
 * one thread, configurations interleaved by round, the median kept. Every
 * call's hits are checked against trace_wide's. */
#ifndef LANES_BENCH_STREAM_INTERSECT_H
#define LANES_BENCH_STREAM_INTERSECT_H

#include <stdbool.h>
#include <stddef.h>

#include "build/scene.h"
#include "simd/isa.h"
#include "trace/render.h"

enum { STREAM_INTERSECT_MAX_APIS = 16 };

typedef struct stream_intersect_api {
    char name[40];   /* "trace_wide (AoS)", "rtcIntersectNp+coherent", ... */
    bool embree;
    double mrays;    /* median over the rounds */
    size_t differ;   /* rays whose primitive or t (1e-4 relative) differ from trace_wide's */
} stream_intersect_api;

typedef struct stream_intersect_result {
    size_t rays, streams; /* captured: extension rays and the trace calls that carried them */
    int apis;
    stream_intersect_api api[STREAM_INTERSECT_MAX_APIS];
    char embree_isa[16];  /* "" without Embree */
} stream_intersect_result;

/* Renders scene (width x height, spp, stream of `stream` paths, the
 * default accuracy, one thread) at set isa, through accel (its wide BVH,
 * lanes_render_accel_build), to capture its extension streams (at most
 * max_rays rays: later streams are traced but not kept), then races the
 * calls above on them, reps rounds. Exits with status 2 (cli_fail) on an
 * error. */
void lanes_stream_intersect_measure(const lanes_scene *scene, const lanes_render_accel *accel, lanes_isa isa, int width,
                                    int height, int spp, int stream, int reps, size_t max_rays,
                                    stream_intersect_result *out);

#endif
