/* The parallel loop (build/parallel.h).
 *
 * Compiled for the x86-64 baseline. */
#define _GNU_SOURCE /* pthread_setaffinity_np, CPU_SET */
#include "build/parallel.h"

#include <sched.h>
#include <string.h>
#include <unistd.h>

_Static_assert(sizeof(cpu_set_t) <= sizeof(((lanes_pool *)0)->caller_affinity),
               "room for the caller's CPU set");

int lanes_parallel_threads(int requested)
{
    long n = requested;
    if (n <= 0) {
        /* the CPUs this process may run on (taskset, a container's
         * cpuset), else those online */
        cpu_set_t set;
        n = sched_getaffinity(0, sizeof set, &set) == 0 ? CPU_COUNT(&set) : 0;
        if (n <= 0) n = sysconf(_SC_NPROCESSORS_ONLN);
        if (n <= 0) n = 1;
    }
    return n < LANES_PARALLEL_MAX_THREADS ? (int)n : LANES_PARALLEL_MAX_THREADS;
}

static void pin(pthread_t thread, int cpu)
{
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(cpu, &set);
    pthread_setaffinity_np(thread, sizeof set, &set);
}

static void work(lanes_pool *p, uint32_t gen, lanes_task_fn fn, void *ctx, size_t count, int worker)
{
    size_t did = 0;
    uint64_t v = atomic_load(&p->next);
    for (;;) {
        if ((uint32_t)(v >> 32) != gen || (v & 0xffffffffu) >= count) break;
        if (!atomic_compare_exchange_weak(&p->next, &v, v + 1)) continue;
        fn(ctx, (size_t)(v & 0xffffffffu), worker);
        did++;
        v = atomic_load(&p->next);
    }
    if (did && atomic_fetch_add(&p->finished, did) + did == count) {
        pthread_mutex_lock(&p->mu);
        pthread_cond_signal(&p->done);
        pthread_mutex_unlock(&p->mu);
    }
}

static void *helper_main(void *arg)
{
    lanes_pool_thread *t = arg;
    lanes_pool *p = t->pool;
    if (p->ncpus) pin(pthread_self(), p->cpus[t->worker % p->ncpus]);
    uint32_t seen = 0;
    pthread_mutex_lock(&p->mu);
    for (;;) {
        while (p->generation == seen && !p->quit) pthread_cond_wait(&p->start, &p->mu);
        if (p->quit) break;
        seen = p->generation;
        lanes_task_fn fn = p->fn;
        void *ctx = p->ctx;
        size_t count = p->count;
        pthread_mutex_unlock(&p->mu);
        work(p, seen, fn, ctx, count, t->worker);
        pthread_mutex_lock(&p->mu);
    }
    pthread_mutex_unlock(&p->mu);
    return NULL;
}

void lanes_pool_start(lanes_pool *p, int threads, const int *cpus, int ncpus)
{
    threads = lanes_parallel_threads(threads);
    p->threads = 1;
    p->generation = 0;
    p->quit = false;
    p->ncpus = 0;
    p->caller_pinned = false;
    if (cpus && ncpus > 0) {
        p->ncpus = ncpus < LANES_PARALLEL_MAX_THREADS ? ncpus : LANES_PARALLEL_MAX_THREADS;
        memcpy(p->cpus, cpus, (size_t)p->ncpus * sizeof *cpus);
        cpu_set_t saved;
        if (pthread_getaffinity_np(pthread_self(), sizeof saved, &saved) == 0) {
            memcpy(p->caller_affinity, &saved, sizeof saved);
            p->caller_pinned = true;
            pin(pthread_self(), p->cpus[0]);
        }
    }
    atomic_init(&p->next, 0);
    atomic_init(&p->finished, 0);
    pthread_mutex_init(&p->mu, NULL);
    pthread_cond_init(&p->start, NULL);
    pthread_cond_init(&p->done, NULL);
    for (int i = 1; i < threads; i++) {
        p->args[i].pool = p;
        p->args[i].worker = i;
        if (pthread_create(&p->th[i], NULL, helper_main, &p->args[i]) != 0) break;
        p->threads = i + 1;
    }
}

void lanes_pool_stop(lanes_pool *p)
{
    pthread_mutex_lock(&p->mu);
    p->quit = true;
    pthread_cond_broadcast(&p->start);
    pthread_mutex_unlock(&p->mu);
    for (int i = 1; i < p->threads; i++) pthread_join(p->th[i], NULL);
    pthread_mutex_destroy(&p->mu);
    pthread_cond_destroy(&p->start);
    pthread_cond_destroy(&p->done);
    if (p->caller_pinned) {
        cpu_set_t saved;
        memcpy(&saved, p->caller_affinity, sizeof saved);
        pthread_setaffinity_np(pthread_self(), sizeof saved, &saved);
    }
    p->threads = 0;
}

void lanes_pool_run(lanes_pool *p, size_t count, lanes_task_fn fn, void *ctx)
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
    work(p, gen, fn, ctx, count, 0);
    pthread_mutex_lock(&p->mu);
    while (atomic_load(&p->finished) < count) pthread_cond_wait(&p->done, &p->mu);
    pthread_mutex_unlock(&p->mu);
}

void lanes_parallel_for(int threads, size_t count, lanes_task_fn fn, void *ctx)
{
    threads = lanes_parallel_threads(threads);
    if ((size_t)threads > count) threads = count > 0 ? (int)count : 1;
    if (threads == 1) {
        for (size_t i = 0; i < count; i++) fn(ctx, i, 0);
        return;
    }
    lanes_pool p;
    lanes_pool_start(&p, threads, NULL, 0);
    lanes_pool_run(&p, count, fn, ctx);
    lanes_pool_stop(&p);
}
