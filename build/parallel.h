/* The one parallel loop of lanes: the builders, the renderers, the studies
 * and `lanes compare` all run their work through it.
 *
 * A pool keeps its helper threads between loops (a BVH build runs dozens of
 * loops; a benchmark must not time thread start-up). Items are claimed from
 * a shared counter, so which worker runs an item is arbitrary: callers keep
 * per-worker state indexed by the worker number and make results
 * independent of the assignment. The caller is worker 0 and works too, and
 * a loop waits for the items, not for the helpers: on a busy machine a
 * helper that is not scheduled in time claims nothing instead of holding up
 * the loop by a time slice. The counter carries the loop's generation, so a
 * helper that wakes late never claims an item of a later loop.
 *
 * Pinning is an option (benchmarks want it, renders do not): with a CPU
 * list, worker i runs on cpus[i % ncpus], the caller included while the
 * pool lives (its own affinity comes back at lanes_pool_stop).
 *
 * Compiled for the x86-64 baseline. */
#ifndef LANES_BUILD_PARALLEL_H
#define LANES_BUILD_PARALLEL_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* The most threads any loop uses, the caller included. */
#define LANES_PARALLEL_MAX_THREADS 256

/* Runs item `item` on worker `worker` (0 .. threads - 1). */
typedef void (*lanes_task_fn)(void *ctx, size_t item, int worker);

typedef struct lanes_pool lanes_pool;
typedef struct lanes_pool_thread {
    lanes_pool *pool;
    int worker;
} lanes_pool_thread;

struct lanes_pool {
    int threads; /* running, the caller included */
    pthread_t th[LANES_PARALLEL_MAX_THREADS];
    lanes_pool_thread args[LANES_PARALLEL_MAX_THREADS];
    pthread_mutex_t mu;
    pthread_cond_t start, done;
    bool quit;
    /* pinning: cpus[] empty when the pool is not pinned */
    int cpus[LANES_PARALLEL_MAX_THREADS];
    int ncpus;
    bool caller_pinned;
    unsigned char caller_affinity[128]; /* the caller's cpu_set_t, restored at stop */
    /* the current loop, written under mu */
    uint32_t generation;
    lanes_task_fn fn;
    void *ctx;
    size_t count;
    _Atomic uint64_t next;  /* generation << 32 | next unclaimed item */
    atomic_size_t finished; /* items of this generation that have run */
};

/* The thread count a request means: 0 (or less) for every CPU this process
 * may run on, at most LANES_PARALLEL_MAX_THREADS. */
int lanes_parallel_threads(int requested);

/* Starts up to lanes_parallel_threads(threads) - 1 helpers; runs with fewer
 * if the system refuses (p->threads says how many). cpus, when not NULL,
 * pins the workers (see above); ncpus >= 1 entries. */
void lanes_pool_start(lanes_pool *p, int threads, const int *cpus, int ncpus);
void lanes_pool_stop(lanes_pool *p);

/* Runs fn for items 0 .. count - 1 (count < 2^32) and returns when all have
 * run. */
void lanes_pool_run(lanes_pool *p, size_t count, lanes_task_fn fn, void *ctx);

/* A pool for one loop: start, run, stop. */
void lanes_parallel_for(int threads, size_t count, lanes_task_fn fn, void *ctx);

#endif
