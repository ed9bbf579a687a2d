/* The core's execution resources, timed; see pipe_rates.h. The probes
 * themselves are in pipe_probes_*.c, one file per instruction set; each
 * runs only after lanes_cpu() says the CPU has its instructions. */
#include "bench/pipe_rates.h"

#include <stdint.h>

#include "bench/cli_common.h"
#include "bench/pipe_probes.h"
#include "simd/isa.h"

/* The probe's loop iterations per second: grown until a run lasts a
 * quarter of run_ms, then the fastest of reps runs of about run_ms (being
 * preempted only ever makes a run slower). */
static double iterations_per_second(pipe_probe_fn fn, float *buf, const int32_t *m, int reps, double run_ms)
{
    uint64_t n = 64;
    double ns;
    for (;;) {
        uint64_t t0 = cli_now_ns();
        fn(n, buf, m);
        ns = (double)(cli_now_ns() - t0);
        if (ns > run_ms * 1e6 / 4 || n > ((uint64_t)1 << 40)) break;
        n *= 4;
    }
    n = (uint64_t)((double)n * run_ms * 1e6 / (ns > 1 ? ns : 1)) + 1;
    double best = 0;
    for (int r = 0; r < reps; r++) {
        uint64_t t0 = cli_now_ns();
        fn(n, buf, m);
        double t = (double)(cli_now_ns() - t0) * 1e-9;
        if (t > 0 && (double)n / t > best) best = (double)n / t;
    }
    return best;
}

static double per_cycle(pipe_probe_fn fn, float *buf, const int32_t *m, double hz, int reps, double run_ms)
{
    return iterations_per_second(fn, buf, m, reps, run_ms) * PIPE_PROBE_OPS / hz;
}

km_pipes km_measure_pipes(double hz, int reps, double run_ms)
{
    km_pipes p = {0};
    const uint32_t cpu = lanes_cpu()->bits;
    if (!(cpu & LANES_CPU_AVX) || hz <= 0) return p;
    /* 12 destinations of 64 bytes; the mask (lanes 0, 2, 4, 6) then a value */
    static _Alignas(64) float buf[PIPE_PROBE_OPS * 16];
    static _Alignas(64) const int32_t m[16] = {-1, 0, -1, 0, -1, 0, -1, 0, 0x3f800000, 0x3f800000,
                                               0x3f800000, 0x3f800000, 0x3f800000, 0x3f800000,
                                               0x3f800000, 0x3f800000};
    const bool fma = (cpu & LANES_CPU_FMA) && (cpu & LANES_CPU_AVX2);
    p.measured = true;
    p.mul = per_cycle(fma ? pipe_probe_fma : pipe_probe_mul, buf, m, hz, reps, run_ms);
    p.add = per_cycle(pipe_probe_add, buf, m, hz, reps, run_ms);
    p.mul_add = per_cycle(fma ? pipe_probe_fma_add : pipe_probe_mul_add, buf, m, hz, reps, run_ms);
    p.any = per_cycle(pipe_probe_logic, buf, m, hz, reps, run_ms);
    p.load = per_cycle(pipe_probe_load, buf, m, hz, reps, run_ms);
    p.store = per_cycle(pipe_probe_store, buf, m, hz, reps, run_ms);
    p.masked_store_cyc = 1.0 / per_cycle(pipe_probe_masked_store, buf, m, hz, reps, run_ms);
    p.merge_cyc = 1.0 / per_cycle(pipe_probe_merge, buf, m, hz, reps, run_ms);
    if (cpu & LANES_CPU_AVX512F) {
        p.zmm_mul = per_cycle(pipe_probe_zmm_fma, buf, m, hz, reps, run_ms);
        p.zmm_load = per_cycle(pipe_probe_zmm_load, buf, m, hz, reps, run_ms);
        p.zmm_store = per_cycle(pipe_probe_zmm_store, buf, m, hz, reps, run_ms);
        p.zmm_masked_store_cyc = 1.0 / per_cycle(pipe_probe_zmm_masked_store, buf, m, hz, reps, run_ms);
    }
    return p;
}
