/* lanes_big_alloc_full: the Linux prefault behind it. */
#define _GNU_SOURCE /* madvise, MADV_POPULATE_WRITE */
#include "build/bvh_alloc.h"

#include <stdint.h>
#include <sys/mman.h>

void *lanes_big_alloc_full(size_t count, size_t elem)
{
    unsigned char *p = lanes_big_alloc(count, elem);
    if (!p) return NULL;
    /* MADV_POPULATE_WRITE came with Linux 5.14; older kernels reject it
     * (EINVAL), and the pages then fault in one at a time as before. An
     * error here changes nothing the build computes, so it is ignored. */
#ifdef MADV_POPULATE_WRITE
    const uintptr_t page = 4096;
    uintptr_t lo = ((uintptr_t)p + page - 1) / page * page;
    uintptr_t hi = ((uintptr_t)p + count * elem) / page * page;
    if (hi > lo) (void)madvise((void *)lo, hi - lo, MADV_POPULATE_WRITE);
#endif
    return p;
}
