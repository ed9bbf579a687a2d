/* The Whitted renderer on ray packets (Wu 2016, Alg. 3.1): primary rays in
 * n x n pixel packets taken in Hilbert-curve order, specular rays of each
 * bounce gathered into packets by global division or by queued tracing
 * (MAX or CORNER heuristic), shadow rays per light split into direction
 * octants, each packet traced through the BVH2 by the packet traversal of
 * one kernel set. Computes the same image as lanes_render (render.h): both
 * take their rays from shading.h.
 *
 * Baseline code: the per-ray work happens in the kernels. */
#ifndef LANES_TRACE_PACKET_RENDER_H
#define LANES_TRACE_PACKET_RENDER_H

#include "trace/render.h"

typedef enum lanes_queue_heuristic {
    /* Global division as the thesis describes it (3.4.4): 6 sets by dominant
     * direction axis and sign, rays taken from a set in no particular order
     * ("essentially randomly selecting rays"): a fixed pseudo-random order. */
    LANES_QUEUE_NONE = 0,
    LANES_QUEUE_MAX,      /* queued at BVH nodes; 6 sets by dominant axis and sign */
    LANES_QUEUE_CORNER,   /* queued at BVH nodes; 8 sets by direction octant */
    /* Global division in the order the rays were made, which follows the
     * Hilbert order of the primary packets: a stronger baseline than the
     * thesis' (not in the thesis). */
    LANES_QUEUE_ARRIVAL,
    LANES_QUEUE_COUNT
} lanes_queue_heuristic;

const char *lanes_queue_name(lanes_queue_heuristic q);
int lanes_queue_from_name(const char *name); /* -1 when unknown */

typedef enum lanes_ray_type {
    LANES_RAYS_PRIMARY = 0,
    LANES_RAYS_SHADOW,
    LANES_RAYS_SPECULAR,
    LANES_RAY_TYPE_COUNT
} lanes_ray_type;

const char *lanes_ray_type_name(lanes_ray_type t);

typedef struct lanes_packet_render_options {
    lanes_render_options base;     /* isa, accuracy, size, spp, threads, depth, area samples, progress */
    lanes_packet_scheme scheme;    /* partition or ranged */
    lanes_queue_heuristic queue;
    int queue_min;                 /* queue nodes: deepest BVH nodes holding >= this many triangles */
    int packet_size;               /* at most this many rays a packet (<= LANES_PACKET_MAX_RAYS);
                                    * primary packets are sqrt(size) x sqrt(size) pixels */
    bool frustum;                  /* packet frusta for node culling */
    bool corner_test;
    bool leaf_frustum;
    bool count;                    /* collect the SIMD utilisation counters (slower: a counting run) */
} lanes_packet_render_options;

void lanes_packet_render_default_options(lanes_packet_render_options *o);

/* Per ray type: how the packets looked and what the traversal did. */
typedef struct lanes_packet_metrics {
    uint64_t rays[LANES_RAY_TYPE_COUNT];
    uint64_t packets[LANES_RAY_TYPE_COUNT];
    /* packets_of_size[t][k]: packets of ray type t holding k rays */
    uint64_t packets_of_size[LANES_RAY_TYPE_COUNT][LANES_PACKET_MAX_RAYS + 1];
    lanes_packet_stats stats[LANES_RAY_TYPE_COUNT]; /* only with options.count */
    /* Wu Def. 4.2.2 per packet, summed over the packets (only with
     * options.count): the mean packet utilisation is the sum / packets. */
    double packet_util_sum[LANES_RAY_TYPE_COUNT];
    uint64_t queue_nodes;          /* queued tracing: number of queue nodes */
    /* Bookkeeping of packet construction: rays made and rays traced, per
     * specular bounce and for shadows; equal when no ray is lost or doubled. */
    uint64_t specular_made[LANES_MAX_DEPTH + 1], specular_traced[LANES_MAX_DEPTH + 1];
    uint64_t shadow_made, shadow_traced;
} lanes_packet_metrics;

/* The smallest packet a set of `lanes` lanes can trace: primary packets are
 * square tiles of a power-of-two side, and the largest such tile of at most
 * packet_size rays must hold a whole ray group (1, 4, 16, 16 for 1, 4, 8,
 * 16 lanes). */
int lanes_packet_min_size(int lanes);

lanes_status lanes_packet_render(const lanes_scene *scene, const lanes_render_accel *accel,
                                 const lanes_packet_render_options *opt, lanes_render_result *out,
                                 lanes_packet_metrics *metrics, lanes_error *err);

#endif
