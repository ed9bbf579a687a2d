/* Thread pool of the BVH builders (internal to build/bvh_*.c): one
 * parallel loop at a time; items are claimed from a shared counter, so
 * which thread runs an item is arbitrary (callers make results independent
 * of it). The caller works too and waits for the items, not for the
 * helpers: on a busy machine a helper that is not scheduled in time simply
 * claims nothing, instead of holding up every loop by a time slice. The
 * counter carries the loop's generation, so a helper that wakes late can
 * never claim an item of a later loop.
 *
 * Compiled for the x86-64 baseline; the including file defines
 * _POSIX_C_SOURCE. */
#ifndef LANES_BUILD_BVH_POOL_H
#define LANES_BUILD_BVH_POOL_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define LANES_POOL_MAX_THREADS 256

typedef void (*pool_fn)(void *ctx, size_t item, int tid);

typedef struct pool pool;
typedef struct pool_thread {
    pool *p;
    int tid;
} pool_thread;

struct pool {
    int threads; /* including the caller */
    pthread_t th[LANES_POOL_MAX_THREADS];
    pool_thread args[LANES_POOL_MAX_THREADS];
    pthread_mutex_t mu;
    pthread_cond_t start, done;
    bool quit;
    /* The current loop, written under mu. */
    uint32_t generation;
    pool_fn fn;
    void *ctx;
    size_t count;
    _Atomic uint64_t next;     /* generation << 32 | next unclaimed item */
    atomic_size_t finished;    /* items of this generation that have run */
};

static inline void pool_work(pool *p, uint32_t gen, pool_fn fn, void *ctx, size_t count, int tid)
{
    size_t did = 0;
    uint64_t v = atomic_load(&p->next);
    for (;;) {
        if ((uint32_t)(v >> 32) != gen || (v & 0xffffffffu) >= count) break;
        if (!atomic_compare_exchange_weak(&p->next, &v, v + 1)) continue;
        fn(ctx, (size_t)(v & 0xffffffffu), tid);
        did++;
        v = atomic_load(&p->next);
    }
    if (did && atomic_fetch_add(&p->finished, did) + did == count) {
        pthread_mutex_lock(&p->mu);
        pthread_cond_signal(&p->done);
        pthread_mutex_unlock(&p->mu);
    }
}

static inline void *pool_main(void *arg)
{
    pool_thread *t = arg;
    pool *p = t->p;
    uint32_t seen = 0;
    pthread_mutex_lock(&p->mu);
    for (;;) {
        while (p->generation == seen && !p->quit) pthread_cond_wait(&p->start, &p->mu);
        if (p->quit) break;
        seen = p->generation;
        pool_fn fn = p->fn;
        void *ctx = p->ctx;
        size_t count = p->count;
        pthread_mutex_unlock(&p->mu);
        pool_work(p, seen, fn, ctx, count, t->tid);
        pthread_mutex_lock(&p->mu);
    }
    pthread_mutex_unlock(&p->mu);
    return NULL;
}

/* Starts up to threads - 1 helpers (at most LANES_POOL_MAX_THREADS in all);
 * runs with fewer if the system refuses. */
static inline void pool_start(pool *p, int threads)
{
    if (threads > LANES_POOL_MAX_THREADS) threads = LANES_POOL_MAX_THREADS;
    p->threads = 1;
    p->generation = 0;
    p->quit = false;
    atomic_init(&p->next, 0);
    atomic_init(&p->finished, 0);
    pthread_mutex_init(&p->mu, NULL);
    pthread_cond_init(&p->start, NULL);
    pthread_cond_init(&p->done, NULL);
    for (int i = 1; i < threads; i++) {
        p->args[i].p = p;
        p->args[i].tid = i;
        if (pthread_create(&p->th[i], NULL, pool_main, &p->args[i]) != 0) break;
        p->threads = i + 1;
    }
}

static inline void pool_stop(pool *p)
{
    pthread_mutex_lock(&p->mu);
    p->quit = true;
    pthread_cond_broadcast(&p->start);
    pthread_mutex_unlock(&p->mu);
    for (int i = 1; i < p->threads; i++) pthread_join(p->th[i], NULL);
    pthread_mutex_destroy(&p->mu);
    pthread_cond_destroy(&p->start);
    pthread_cond_destroy(&p->done);
}

/* count < 2^32: items are blocks and tasks, never single triangles. */
static inline void pool_run(pool *p, size_t count, pool_fn fn, void *ctx)
{
    if (count == 0) return;
    if (p->threads == 1 || count == 1) {
        for (size_t i = 0; i < count; i++) fn(ctx, i, 0);
        return;
    }
    pthread_mutex_lock(&p->mu);
    uint32_t gen = ++p->generation;
    if (gen == 0) gen = ++p->generation; /* 0 is every helper's initial "seen" */
    p->fn = fn;
    p->ctx = ctx;
    p->count = count;
    atomic_store(&p->finished, 0);
    atomic_store(&p->next, (uint64_t)gen << 32);
    pthread_cond_broadcast(&p->start);
    pthread_mutex_unlock(&p->mu);
    pool_work(p, gen, fn, ctx, count, 0);
    pthread_mutex_lock(&p->mu);
    while (atomic_load(&p->finished) < count) pthread_cond_wait(&p->done, &p->mu);
    pthread_mutex_unlock(&p->mu);
}

#endif
