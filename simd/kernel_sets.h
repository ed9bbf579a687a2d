/* The kernel sets lanes compiles its kernels for, one row each. Everything
 * else about a set is generated from this list: the lanes_isa enum, the
 * names, the CPU features it needs, the dispatch tables, the test runners,
 * the usage text; CMake reads the list too (cmake/LanesIsa.cmake), where
 * each set's compiler flags and backend header sit. Adding a set: a row
 * here, its vecN header, its CMake flags, its rule in tests/check_hygiene.sh.
 *
 *   X(ID, name, lanes, family, emulated, rank, automatic, needs)
 *
 *   ID         LANES_ISA_<ID> and LANES_KSET_<ID>
 *   name       as users type it (LANES_ISA, --isa, isa= in a device config)
 *   lanes      vector width
 *   family     the instruction-set family: the study plots one series per
 *              family with x = lanes, so width and instruction set separate
 *   emulated   1: the width is made of narrower native vectors
 *   rank       preference, higher first; LANES_MAX_ISA caps by rank
 *   automatic  1: the automatic choice may pick it; 0: only when asked for
 *   needs      the CPU features it needs (LANES_CPU_* bits of simd/isa.h)
 *
 * The rows' order is the enum's, part of the ABI: a new set goes last.
 * Included by lanes/lanes.h, so it is C11 without includes of its own; the
 * needs column is expanded only where simd/isa.h is in scope. */
#ifndef LANES_SIMD_KERNEL_SETS_H
#define LANES_SIMD_KERNEL_SETS_H

#define LANES_NEEDS_SSE4_ (LANES_CPU_SSE2 | LANES_CPU_SSE41 | LANES_CPU_POPCNT)
#define LANES_NEEDS_AVX_ (LANES_NEEDS_SSE4_ | LANES_CPU_OSXSAVE | LANES_CPU_AVX)
#define LANES_NEEDS_AVX2_ (LANES_NEEDS_AVX_ | LANES_CPU_AVX2 | LANES_CPU_FMA)
#define LANES_NEEDS_AVX512_                                                                  \
    (LANES_NEEDS_AVX2_ | LANES_CPU_AVX512F | LANES_CPU_AVX512DQ | LANES_CPU_AVX512BW |        \
     LANES_CPU_AVX512VL)

/* clang-format off */
#define LANES_KERNEL_SETS(X)                                                  \
    X(SCALAR,    scalar,     1, scalar, 0, 0, 1, LANES_CPU_SSE2)              \
    X(SSE4,      sse4,       4, sse4,   0, 1, 1, LANES_NEEDS_SSE4_)           \
    X(AVX,       avx,        8, avx,    0, 2, 1, LANES_NEEDS_AVX_)            \
    X(AVX2,      avx2,       8, avx2,   0, 3, 1, LANES_NEEDS_AVX2_)           \
    X(AVX512EMU, avx512emu, 16, avx2,   1, 5, 0, LANES_NEEDS_AVX2_)           \
    X(AVX512,    avx512,    16, avx512, 0, 6, 1, LANES_NEEDS_AVX512_)         \
    X(AVX512VL8, avx512vl8,  8, avx512, 0, 4, 0, LANES_NEEDS_AVX512_)
/* clang-format on */

#endif
