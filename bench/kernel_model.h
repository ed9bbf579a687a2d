/* The throughput bound the kernel benchmark compares against, and what it
 * needs: the core clock, the core's issue width, and each kernel's
 * instruction count per vector iteration.
 *
 *     bound [tests/s] = f_clk * issue_width * lanes / instructions_per_iteration
 *
 * Hardware counters are not available everywhere (not on the VM this was
 * written on), so the inputs are obtained without them:
 * - f_clk: a chain of dependent integer adds retires one add per cycle on
 *   every x86-64 core of the last two decades; timing it gives the clock
 *   the core actually runs at under load.
 * - instructions: counted exactly by single-stepping one kernel call with
 *   the trap flag (a SIGTRAP per instruction, in this process), from the
 *   entry point to its return. That is the executed path for the actual
 *   data, with the stats == NULL copy of the body, not a guess from the
 *   static layout of the code.
 * - issue width: a per-microarchitecture constant (see km_core_model). */
#ifndef LANES_BENCH_KERNEL_MODEL_H
#define LANES_BENCH_KERNEL_MODEL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct km_core {
    int issue_width;     /* macro-ops dispatched per cycle */
    const char *name;    /* "AMD Zen 5 (family 1Ah)" */
    const char *why;     /* where the constants come from */
    bool known;          /* false: a default was assumed */
} km_core;

/* The model constants for a CPU (vendor string, family, model from cpuid). */
km_core km_core_model(const char *vendor, unsigned family, unsigned model);

/* Core clock in Hz: the fastest of `reps` timed runs of ~run_ms each. */
double km_measure_clock_hz(int reps, double run_ms);

/* Instruction counting. km_trace_call() runs fn(arg) with the trap flag set
 * and counts the instructions executed from the moment control reaches
 * `entry` until that call returns (calls the kernel makes count too).
 * Executed addresses and their counts are accumulated into a table that
 * km_trace_reset() clears and km_trace_sites() reads. */
bool km_trace_call(uintptr_t entry, void (*fn)(void *), void *arg, uint64_t *instructions,
                   char *why, size_t why_size);
void km_trace_reset(void);
typedef struct km_site {
    uintptr_t addr;
    uint64_t count;
} km_site;
/* Copies the table (sorted by address) into a malloc'ed array. */
size_t km_trace_sites(km_site **sites);

/* Instruction classes from a disassembly of this executable (objdump),
 * one bit each; an instruction may have several (vaddps (%rax),... is
 * KM_VECTOR | KM_ADD | KM_LOAD). */
enum {
    KM_VECTOR = 1,      /* occupies an FP/vector pipe: arithmetic, compares, blends,
                           shuffles, mask operations; not loads, stores, reg moves */
    KM_ZMM = 2,         /* operates on 512-bit registers */
    KM_MUL = 4,         /* multiply, FMA, reciprocal, divide, square root */
    KM_ADD = 8,         /* floating-point add, subtract, min, max, compare */
    KM_LOAD = 16,       /* reads memory (any register kind) */
    KM_STORE = 32,      /* writes memory with a plain or opmask store */
    KM_MASKSTORE = 64,  /* writes memory through a vector mask (vmaskmovps) */
};
/* The classes of one instruction as objdump -d prints it (AT&T syntax:
 * "vfmadd231ps", "%ymm1,%ymm2,%ymm3"). */
int km_classify(const char *mnemonic, const char *operands);
typedef struct km_disasm {
    size_t count;
    uintptr_t *addr; /* sorted runtime addresses */
    unsigned char *cls;
} km_disasm;
/* Disassembles the code spanning [lo, hi] of the running executable. */
bool km_disasm_load(uintptr_t lo, uintptr_t hi, km_disasm *d, char *why, size_t why_size);
/* The class of the instruction at addr, or -1 when it was not disassembled. */
int km_disasm_class(const km_disasm *d, uintptr_t addr);
void km_disasm_free(km_disasm *d);

#endif
