/* Large arrays of the BVH builders (internal to build/): 64-byte
 * aligned, the kernels' vector alignment, with the size checked for
 * overflow. Free with free().
 *
 * Transparent huge pages (madvise) were tried and dropped: with the
 * kernel's defrag=madvise default, faults on advised memory compact
 * synchronously, and the 3M-triangle collapse to width 16 took 2.5 times
 * as long. */
#ifndef LANES_BUILD_BVH_ALLOC_H
#define LANES_BUILD_BVH_ALLOC_H

#include <stdint.h>
#include <stdlib.h>

/* NULL for 0 bytes, on overflow or when out of memory. */
static inline void *lanes_big_alloc(size_t count, size_t elem)
{
    if (count == 0 || elem == 0 || count > (SIZE_MAX - 64) / elem) return NULL;
    size_t bytes = (count * elem + 63) / 64 * 64;
    return aligned_alloc(64, bytes);
}

/* Faults in the pages of [p, p + bytes) at once, in one system call,
 * rather than one fault at a time as they are first written: for memory
 * the caller is about to write in full. Each fault is a trap into the
 * kernel, and more costly in a virtual machine: on a 2-core Zen 5 VM, the
 * 1.5M-triangle builds of bench_bvh_build spent about a quarter of their
 * time in faults (perf). Does nothing below 1 MiB, 256 pages, a threshold
 * chosen, not measured, to keep the call off small arrays; nor where the
 * kernel cannot (Linux before 5.14). */
void lanes_prefault(void *p, size_t bytes);

/* lanes_big_alloc for an array the build will write in full. Only for
 * those: the rest (the node buffers sized for the worst case, the
 * collapse's bounds) keep faulting in only the pages they use. */
static inline void *lanes_big_alloc_full(size_t count, size_t elem)
{
    void *p = lanes_big_alloc(count, elem);
    if (p) lanes_prefault(p, count * elem);
    return p;
}

#endif
