/* liblanes: CPU ray tracing whose kernels are compiled for every SIMD width
 * (scalar, SSE4, AVX, AVX2, emulated and native AVX-512) and chosen at run
 * time. This header is the whole public API; it is C11 and includes only
 * standard headers and the list of kernel sets (<lanes/simd/kernel_sets.h>).
 *
 *   lanes_device dev;
 *   if (lanes_device_create("threads=2", &dev) != LANES_OK)
 *       fprintf(stderr, "%s\n", lanes_last_error_message());
 *   lanes_accel accel;
 *   lanes_accel_create(dev, vertices, vertex_count, indices, triangle_count, &accel);
 *   lanes_ray1 ray = {{0, 0, -5}, {0, 0, 1}, 0.0f, INFINITY};
 *   lanes_hit1 hit;
 *   lanes_intersect1(accel, &ray, &hit);   // hit.prim_id, hit.t, hit.u, hit.v
 *   lanes_accel_release(accel);
 *   lanes_device_release(dev);
 *
 * Conventions:
 * - Every function returns a lanes_status (LANES_OK = 0) and never aborts or
 *   exits on bad input. A failing call also leaves a message for the calling
 *   thread (lanes_last_error_message) and calls the device's error callback,
 *   if one is set.
 * - A ray is org + t * dir for t in the closed interval [tnear, tfar]
 *   (tnear > tfar: empty, a miss). Triangles are two-sided. A ray with a NaN
 *   or infinite component in org or dir, a zero direction, or a NaN tnear
 *   or tfar is invalid: it is reported as a miss (not occluded), and the
 *   call returns LANES_ERR_BAD_INPUT naming the first such ray, after it
 *   has traced every valid one. So is a ray that starts too far from the
 *   mesh for the accuracy mode's float arithmetic: further than its limit
 *   (lanes_accel_info.max_reach) across the box of the mesh and the origin
 *   (default and fast modes: FLT_MAX / (6 * longest_edge^2), 5.7e17 for
 *   edges of 1e10; robust: 1e18).
 * - Thread safety: a device and an accel are immutable once created. Any
 *   number of threads may query one accel at once, and create accels on one
 *   device at once. Releasing an object while another thread uses it is
 *   the caller's error.
 */
#ifndef LANES_LANES_H
#define LANES_LANES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "lanes/simd/kernel_sets.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LANES_VERSION_MAJOR 0
#define LANES_VERSION_MINOR 3
#define LANES_VERSION_PATCH 0
/* major * 10000 + minor * 100 + patch, for #if */
#define LANES_VERSION                                                                      \
    (LANES_VERSION_MAJOR * 10000 + LANES_VERSION_MINOR * 100 + LANES_VERSION_PATCH)

#if defined(LANES_STATIC_DEFINE) || !defined(__GNUC__)
#define LANES_API
#else
#define LANES_API __attribute__((visibility("default")))
#endif

/* "0.2.0": the version of the library linked at run time, which can differ
 * from the header's LANES_VERSION_* when a shared library is replaced. */
LANES_API const char *lanes_version(void);

typedef enum lanes_status {
    LANES_OK = 0,
    LANES_ERR_UNKNOWN_ISA,    /* a name that is no instruction set */
    LANES_ERR_NOT_COMPILED,   /* an instruction set left out of this build */
    LANES_ERR_CPU_LACKS,      /* the CPU (or its OS) cannot run the instruction set */
    LANES_ERR_BAD_INPUT,      /* an invalid argument: the message says which and why */
    LANES_ERR_OUT_OF_MEMORY   /* an allocation failed, or the input cannot fit in memory */
} lanes_status;

/* "ok", "unknown instruction set", ...; never NULL. */
LANES_API const char *lanes_status_name(lanes_status status);

/* The message of the calling thread's last failing call ("" if none). Valid
 * until that thread's next failing call. */
LANES_API const char *lanes_last_error_message(void);

/* ------------------------------------------------------------------------
 * Instruction sets ("kernel sets") and the process-wide choice of one. A
 * device takes its set from its config string, or else from this choice;
 * programs that write their own width-generic kernels with lanes' SIMD
 * layer (<lanes/simd/simd.h>, see the README) dispatch them with it.
 * ------------------------------------------------------------------------ */

/* The kernel sets, in the order of simd/kernel_sets.h (installed as
 * <lanes/simd/kernel_sets.h>), the one list they are declared in:
 *   LANES_ISA_SCALAR     scalar      1 lane, any x86-64
 *   LANES_ISA_SSE4       sse4        4 lanes, SSE4.1 + POPCNT
 *   LANES_ISA_AVX        avx         8 lanes, AVX (no AVX2, no FMA)
 *   LANES_ISA_AVX2       avx2        8 lanes, AVX2 + FMA
 *   LANES_ISA_AVX512EMU  avx512emu  16 lanes from two AVX2 halves
 *   LANES_ISA_AVX512     avx512     16 lanes, AVX-512 F/DQ/BW/VL
 *   LANES_ISA_AVX512VL8  avx512vl8   8 lanes, AVX-512VL: ymm registers with
 *                                    opmask compares and compress
 * The enum's order is not the preference: the automatic choice takes the
 * best-ranked set the CPU runs, and never avx512emu or avx512vl8 (they exist
 * to separate the effect of width from that of the instruction set). */
typedef enum lanes_isa {
#define LANES_ISA_ENUM_(id, name, lanes, family, emulated, rank, automatic, needs) LANES_ISA_##id,
    LANES_KERNEL_SETS(LANES_ISA_ENUM_)
#undef LANES_ISA_ENUM_
    LANES_ISA_COUNT,
    LANES_ISA_NONE = -1
} lanes_isa;

/* The set's name ("none" for any other value) and lane count (0). */
LANES_API const char *lanes_isa_name(lanes_isa isa);
LANES_API int lanes_isa_lanes(lanes_isa isa);
/* LANES_ISA_NONE for an unknown name. */
LANES_API lanes_isa lanes_isa_from_name(const char *name);
/* Every set's name, comma separated, for messages. */
LANES_API const char *lanes_isa_all_names(void);
/* The sets in order of preference, best first: sets[0..LANES_ISA_COUNT-1].
 * LANES_MAX_ISA and lanes_set_max_isa cap the automatic choice at a place
 * in this order. */
LANES_API const lanes_isa *lanes_isa_ranked(void);
/* May the automatic choice pick the set? (avx512emu and avx512vl8: no.) */
LANES_API bool lanes_isa_automatic(lanes_isa isa);
/* The instruction-set family ("avx2" for avx2 and avx512emu) and whether
 * the set's width is emulated with narrower vectors. */
LANES_API const char *lanes_isa_family(lanes_isa isa);
LANES_API bool lanes_isa_emulated(lanes_isa isa);
/* Was the set compiled into liblanes (its LANES_ISAS at configure time)? */
LANES_API bool lanes_isa_compiled(lanes_isa isa);
/* Can this CPU, with its OS, run the set? (LANES_DISABLE_CPU_FEATURES, a
 * test switch, can say no to more.) Independent of what was compiled. */
LANES_API bool lanes_isa_cpu_can_run(lanes_isa isa);
/* Compiled and runnable. */
LANES_API bool lanes_isa_supported(lanes_isa isa);
/* LANES_OK when liblanes has the set and the CPU runs it; otherwise the
 * status and, in why, the reason naming the missing features (what the CPU
 * lacks, else what the OS has not enabled). Changes nothing. */
LANES_API lanes_status lanes_isa_check(lanes_isa isa, char *why, size_t why_size);
/* The best set compiled and runnable here, at most LANES_MAX_ISA (or
 * lanes_set_max_isa's cap), among the sets chosen automatically. */
LANES_API lanes_isa lanes_isa_best(void);

/* The process-wide choice. On first use it comes from LANES_ISA (forces a
 * set), else LANES_MAX_ISA (caps the automatic choice), else the best set.
 * lanes_isa_init() reports a bad value of those variables (or of
 * LANES_DISABLE_CPU_FEATURES) with its status and message; after such an
 * error lanes_isa_current() gives the best set, so a program that ignores
 * the status still never runs an instruction the CPU lacks. */
LANES_API lanes_status lanes_isa_init(char *message, size_t message_size);
LANES_API lanes_isa lanes_isa_current(void);
/* Force a set (LANES_ISA_NONE: back to the automatic choice), or cap the
 * automatic choice. On error the choice is unchanged and message says why. */
LANES_API lanes_status lanes_set_isa(lanes_isa isa, char *message, size_t message_size);
LANES_API lanes_status lanes_set_isa_by_name(const char *name, char *message, size_t message_size);
LANES_API lanes_status lanes_set_max_isa(lanes_isa cap, char *message, size_t message_size);

/* ------------------------------------------------------------------------
 * Device: the instruction set and the settings every accel on it uses.
 * ------------------------------------------------------------------------ */
typedef struct lanes_device_impl *lanes_device;

/* config: NULL or "" for the defaults, or comma-separated key=value pairs
 * (Embree's convention):
 *   isa=NAME          a set's name (lanes_isa_all_names); default:
 *                     the process-wide choice (lanes_isa_current: LANES_ISA
 *                     if set, else the best set the CPU runs, at most
 *                     LANES_MAX_ISA). A set the CPU cannot run, or an
 *                     unknown name, is an error: never a silent fallback.
 *   node_width=N      children per node of the accels it builds: 4, 8 or
 *                     16, from the set's lane count up (the scalar set
 *                     traverses any; sse4 any; avx, avx2 and avx512vl8 8 or
 *                     16; avx512emu and avx512 16). Default: the set's own,
 *                     lanes_device_info.node_width. A width below the set's
 *                     is an error (LANES_ERR_BAD_INPUT).
 *   threads=N         threads for building accels (0: all cores; default 0)
 *   accuracy=MODE     fast, default or robust (see the README's accuracy
 *                     modes; default: default)
 * On error *device is NULL. */
LANES_API lanes_status lanes_device_create(const char *config, lanes_device *device);
/* NULL is allowed. Accels keep their device alive: release them in any order. */
LANES_API lanes_status lanes_device_release(lanes_device device);

/* Called on every failing call that involves the device (and its accels),
 * from the failing thread, with the message lanes_last_error_message()
 * returns. NULL removes it. Set it before sharing the device between
 * threads. */
typedef void (*lanes_error_callback)(void *user, lanes_status status, const char *message);
LANES_API lanes_status lanes_device_set_error_callback(lanes_device device,
                                                       lanes_error_callback callback, void *user);

typedef struct lanes_device_info {
    const char *isa;   /* the instruction set's name, "avx2" */
    int lanes;         /* its SIMD width: 1, 4, 8 or 16 */
    int node_width;    /* children per node of the accels it builds */
    const char *accuracy;
    int threads;       /* 0: all cores */
} lanes_device_info;
LANES_API lanes_status lanes_device_get_info(lanes_device device, lanes_device_info *info);

/* ------------------------------------------------------------------------
 * Accel: a BVH over a triangle mesh, built for the device's instruction set
 * and node width (node_width=, else the set's own), so a mismatched width
 * cannot happen.
 * ------------------------------------------------------------------------ */
typedef struct lanes_accel_impl *lanes_accel;

/* vertices: x, y, z per vertex (3 * vertex_count floats); indices: three
 * vertex indices per triangle. Both are read during the call only: the
 * accel stores the triangles in its own layout, and the arrays may be freed
 * afterwards. A triangle with an index >= vertex_count is an error.
 * Triangles with a NaN or infinite vertex are left out (never hit; counted
 * in lanes_accel_info.skipped; none finite is LANES_ERR_BAD_INPUT);
 * degenerate (zero-area) ones are never hit.
 * prim_id in results is the triangle's position in `indices`. At least one
 * triangle; at most 2^31 - 1. A mesh whose bounding-box diagonal the
 * device's accuracy mode cannot trace in float is LANES_ERR_BAD_INPUT:
 * below 1e-11 in fast and default modes, 1e-15 in robust mode, or beyond
 * max_reach. On error *accel is NULL. */
LANES_API lanes_status lanes_accel_create(lanes_device device, const float *vertices,
                                          size_t vertex_count, const uint32_t *indices,
                                          size_t triangle_count, lanes_accel *accel);
/* The same accel over the caller's arrays, shared instead of copied (as
 * Embree's rtcSetSharedGeometryBuffer): its leaves hold triangle ids only,
 * and every query reads the vertices from `vertices` through `indices`.
 * Both arrays must stay alive and unchanged until the accel is released.
 * The answers are those of lanes_accel_create bit for bit; the accel holds
 * about 36 bytes less per triangle and its leaf tests gather (slower where
 * the leaves dominate). At most 715,827,882 triangles and vertices (the
 * gathers take 32-bit offsets). */
LANES_API lanes_status lanes_accel_create_shared(lanes_device device, const float *vertices,
                                                 size_t vertex_count, const uint32_t *indices,
                                                 size_t triangle_count, lanes_accel *accel);
/* NULL is allowed. */
LANES_API lanes_status lanes_accel_release(lanes_accel accel);

typedef struct lanes_accel_info {
    const char *isa;      /* the device's instruction set and accuracy mode, */
    const char *accuracy; /* which the accel's queries use */
    size_t triangles;   /* as given */
    size_t skipped;     /* left out for non-finite vertices */
    size_t nodes;       /* wide nodes */
    int node_width;
    size_t bytes;       /* memory held (a shared accel's: without the caller's arrays) */
    float bounds_min[3], bounds_max[3];
    double build_seconds;
    double max_reach;   /* the longest distance across the box of the mesh and
                           a ray's origin that the accuracy mode traces */
} lanes_accel_info;
LANES_API lanes_status lanes_accel_get_info(lanes_accel accel, lanes_accel_info *info);

/* ------------------------------------------------------------------------
 * Queries
 * ------------------------------------------------------------------------ */
#define LANES_INVALID_ID 0xffffffffu

typedef struct lanes_ray1 {
    float org[3];
    float dir[3];   /* need not be normalised; t is in units of dir */
    float tnear, tfar;
} lanes_ray1;

/* The closest hit: prim_id LANES_INVALID_ID for a miss (t, u, v are then
 * +inf, 0, 0). u and v weigh the triangle's second and third vertex: the
 * hit point is (1 - u - v) p0 + u p1 + v p2. */
typedef struct lanes_hit1 {
    float t, u, v;
    uint32_t prim_id;
} lanes_hit1;

LANES_API lanes_status lanes_intersect1(lanes_accel accel, const lanes_ray1 *ray, lanes_hit1 *hit);
/* Any hit in [tnear, tfar]: *occluded is true or false. */
LANES_API lanes_status lanes_occluded1(lanes_accel accel, const lanes_ray1 *ray, bool *occluded);

/* N rays as structure of arrays: element i of each array is ray i. */
typedef struct lanes_rays_soa {
    const float *org_x, *org_y, *org_z;
    const float *dir_x, *dir_y, *dir_z;
    const float *tnear, *tfar;
} lanes_rays_soa;

/* N results as structure of arrays, as lanes_hit1. u and v may be NULL. */
typedef struct lanes_hits_soa {
    float *t, *u, *v;
    uint32_t *prim_id;
} lanes_hits_soa;

/* A stream: n independent rays, any n (0 is allowed, and then the arrays
 * may be NULL), through the wide BVH: closest hits one ray at a time;
 * occlusion sorted by direction octant, each group of up to 32 rays of one
 * octant walking the tree together (as Embree's rtcOccluded1M), with the
 * answers of one ray at a time, bitwise. For incoherent rays (diffuse
 * bounces, shadows to many lights). */
LANES_API lanes_status lanes_intersect_stream(lanes_accel accel, const lanes_rays_soa *rays,
                                              size_t n, lanes_hits_soa *hits);
/* occluded[i] is 1 or 0. */
LANES_API lanes_status lanes_occluded_stream(lanes_accel accel, const lanes_rays_soa *rays,
                                             size_t n, uint8_t *occluded);

/* Coherent packets: n rays, any n (0 as for streams), traced through the
 * wide BVH in packets of the set's lane count (4, 8 or 16 consecutive rays): a frustum test of
 * each node's children for the whole packet, then the exact test per ray,
 * until one ray is left, which goes on alone (hybrid traversal, Benthin et
 * al. 2012). Consecutive rays pointing into different octants go one at a
 * time. Faster where neighbouring rays are alike (camera rays in screen
 * tiles, shadows to one light). Each ray gets the stream's answer, bitwise,
 * except where the order of visiting decides: two triangles hit at the same
 * t, or a hit that lies within rounding of its box's boundary, which one
 * order finds and the other may not (both answers are then within the
 * accuracy mode's rounding). */
LANES_API lanes_status lanes_intersect_packet(lanes_accel accel, const lanes_rays_soa *rays,
                                              size_t n, lanes_hits_soa *hits);
LANES_API lanes_status lanes_occluded_packet(lanes_accel accel, const lanes_rays_soa *rays,
                                             size_t n, uint8_t *occluded);

#ifdef __cplusplus
}
#endif

#endif
