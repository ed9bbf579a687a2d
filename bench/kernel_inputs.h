/* Inputs of the kernel benchmark: one coherent primary-ray packet and
 * primitives placed so that about half of the tests hit (or, for culling,
 * about half of the primitives are kept). Deterministic: the same seed
 * gives the same scene on every run and every machine, so figures of
 * different runs and instruction sets compare the same work. */
#ifndef LANES_BENCH_KERNEL_INPUTS_H
#define LANES_BENCH_KERNEL_INPUTS_H

#include <stdbool.h>
#include <stddef.h>

#include "trace/kernels.h"

#define KI_PACKET_SIDE 32                              /* a 32x32 pixel tile */
#define KI_PACKET_RAYS (KI_PACKET_SIDE * KI_PACKET_SIDE) /* 1024 rays */
#define KI_PACKET_PRIMS 64 /* boxes and triangles tested against the whole packet */
#define KI_WIDE_RAYS 16    /* single rays tested against the wide arrays */
#define KI_WIDE_COUNT 4096 /* boxes or triangles in one wide call: L2-resident */
#define KI_CULL_COUNT 4096 /* boxes or triangles culled against the packet's frustum */

typedef struct kernel_inputs {
    lanes_rays packet; /* prepared: 1/d exact, every ray valid */
    lanes_ray wide_rays[KI_WIDE_RAYS];
    lanes_box packet_boxes[KI_PACKET_PRIMS];
    lanes_triangle packet_tris[KI_PACKET_PRIMS];
    lanes_boxes wide_boxes;
    lanes_triangles wide_tris;
    lanes_boxes cull_boxes;
    lanes_triangles cull_tris;
    lanes_frustum frustum; /* of the packet, built once by the scalar set */
} kernel_inputs;

/* Builds everything with the scalar kernels (ray preparation and frustum),
 * so every set under test reads bit-identical inputs. */
bool kernel_inputs_make(kernel_inputs *in);
void kernel_inputs_free(kernel_inputs *in);

#endif
