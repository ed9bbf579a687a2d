/* Large arrays of the BVH builders (internal to build/bvh_*.c): 64-byte
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

/* lanes_big_alloc for an array the build will write in full: its pages
 * are faulted in at once, in one system call, rather than one fault at a
 * time as the build first writes them. Each fault is a trap into the
 * kernel, and more costly in a virtual machine: on a 2-core Zen 5 VM, the
 * 1.5M-triangle builds of bench_bvh_build spent about a quarter of their
 * time in faults. Only for arrays written in full: the rest (the node
 * buffers sized for the worst case, the collapse's bounds) keep faulting
 * in only the pages they use. */
void *lanes_big_alloc_full(size_t count, size_t elem);

#endif
