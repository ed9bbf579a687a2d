/* lanes_prefault: the Linux call behind it. */
#define _GNU_SOURCE /* madvise, MADV_POPULATE_WRITE */
#include "build/bvh_alloc.h"

#include <stdint.h>
#include <sys/mman.h>

void lanes_prefault(void *p, size_t bytes)
{
    if (bytes < ((size_t)1 << 20)) return;
    /* An error (EINVAL before Linux 5.14, ENOMEM) changes nothing the
     * caller computes: the pages then fault in one at a time as before. */
#ifdef MADV_POPULATE_WRITE
    const uintptr_t page = 4096; /* x86-64's base page */
    uintptr_t lo = ((uintptr_t)p + page - 1) / page * page;
    uintptr_t hi = ((uintptr_t)p + bytes) / page * page;
    if (hi > lo) (void)madvise((void *)lo, hi - lo, MADV_POPULATE_WRITE);
#else
    (void)p;
#endif
}
