/* CPU feature detection: cpuid for what the CPU has, xgetbv for what the OS
 * saves on a context switch. A CPU can list AVX or AVX-512 while the OS has
 * not enabled their register state (VMs, "noxsave" kernels); executing them
 * then traps, so such features count as absent. */
#include "simd/isa.h"

#include <cpuid.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const feature_names[LANES_CPU_FEATURE_COUNT] = {
    "sse2", "sse3", "ssse3", "sse4.1", "sse4.2", "popcnt", "osxsave", "avx", "f16c", "fma",
    "avx2", "bmi1", "bmi2", "lzcnt", "avx512f", "avx512cd", "avx512dq", "avx512bw", "avx512vl",
};

const char *lanes_cpu_feature_name(uint32_t feature_bit)
{
    for (int i = 0; i < LANES_CPU_FEATURE_COUNT; i++)
        if (feature_bit == (1u << i)) return feature_names[i];
    return "?";
}

void lanes_cpu_feature_list(uint32_t bits, char *buf, size_t size)
{
    size_t used = 0;
    if (size == 0) return;
    buf[0] = '\0';
    for (int i = 0; i < LANES_CPU_FEATURE_COUNT; i++) {
        if (!(bits & (1u << i))) continue;
        int n = snprintf(buf + used, size - used, "%s%s", used ? " " : "", feature_names[i]);
        if (n < 0 || (size_t)n >= size - used) break;
        used += (size_t)n;
    }
}

/* xgetbv written as bytes, so this baseline file needs no -mxsave. Only
 * called when CPUID says OSXSAVE: otherwise the instruction itself traps. */
static uint64_t read_xcr0(void)
{
    uint32_t lo, hi;
    __asm__ volatile(".byte 0x0f, 0x01, 0xd0" : "=a"(lo), "=d"(hi) : "c"(0));
    return ((uint64_t)hi << 32) | lo;
}

static uint32_t feature_bits_from_names(const char *list)
{
    uint32_t bits = 0;
    char name[32];
    while (list && *list) {
        size_t n = strcspn(list, ", ");
        if (n > 0 && n < sizeof name) {
            memcpy(name, list, n);
            name[n] = '\0';
            for (int i = 0; i < LANES_CPU_FEATURE_COUNT; i++)
                if (strcmp(name, feature_names[i]) == 0) bits |= 1u << i;
        }
        list += n;
        list += strspn(list, ", ");
    }
    return bits;
}

static void detect(lanes_cpu_features *f)
{
    unsigned a, b, c, d;
    uint32_t bits = 0;
    memset(f, 0, sizeof *f);

    unsigned max_leaf = (unsigned)__get_cpuid_max(0, NULL);
    if (__get_cpuid(0, &a, &b, &c, &d)) {
        memcpy(f->vendor, &b, 4);
        memcpy(f->vendor + 4, &d, 4);
        memcpy(f->vendor + 8, &c, 4);
    }
    if ((unsigned)__get_cpuid_max(0x80000000u, NULL) >= 0x80000004u) {
        unsigned *brand = (unsigned *)(void *)f->brand;
        for (unsigned leaf = 0; leaf < 3; leaf++)
            __get_cpuid(0x80000002u + leaf, &brand[4 * leaf], &brand[4 * leaf + 1],
                        &brand[4 * leaf + 2], &brand[4 * leaf + 3]);
        f->brand[48] = '\0';
        /* brand strings are padded with leading spaces on some CPUs */
        size_t lead = strspn(f->brand, " ");
        memmove(f->brand, f->brand + lead, strlen(f->brand + lead) + 1);
    }

    uint32_t leaf1_ecx = 0, leaf1_edx = 0, leaf7_ebx = 0, ext_ecx = 0;
    if (max_leaf >= 1 && __get_cpuid(1, &a, &b, &c, &d)) {
        leaf1_ecx = c;
        leaf1_edx = d;
    }
    if (max_leaf >= 7) {
        __cpuid_count(7, 0, a, b, c, d);
        leaf7_ebx = b;
    }
    if ((unsigned)__get_cpuid_max(0x80000000u, NULL) >= 0x80000001u && __get_cpuid(0x80000001u, &a, &b, &c, &d))
        ext_ecx = c;

    if (leaf1_edx & (1u << 26)) bits |= LANES_CPU_SSE2;
    if (leaf1_ecx & (1u << 0)) bits |= LANES_CPU_SSE3;
    if (leaf1_ecx & (1u << 9)) bits |= LANES_CPU_SSSE3;
    if (leaf1_ecx & (1u << 19)) bits |= LANES_CPU_SSE41;
    if (leaf1_ecx & (1u << 20)) bits |= LANES_CPU_SSE42;
    if (leaf1_ecx & (1u << 23)) bits |= LANES_CPU_POPCNT;
    if (ext_ecx & (1u << 5)) bits |= LANES_CPU_LZCNT;
    if (leaf7_ebx & (1u << 3)) bits |= LANES_CPU_BMI1;
    if (leaf7_ebx & (1u << 8)) bits |= LANES_CPU_BMI2;

    /* Everything that uses YMM or ZMM registers also needs the OS's consent. */
    bool xsave = (leaf1_ecx & (1u << 26)) && (leaf1_ecx & (1u << 27));
    if (xsave) {
        bits |= LANES_CPU_OSXSAVE;
        f->xcr0 = read_xcr0();
    }
    bool os_ymm = xsave && (f->xcr0 & 0x6) == 0x6;          /* XMM and YMM state */
    bool os_zmm = os_ymm && (f->xcr0 & 0xe0) == 0xe0;       /* opmask, ZMM0-15 high, ZMM16-31 */
    if (os_ymm) {
        if (leaf1_ecx & (1u << 28)) bits |= LANES_CPU_AVX;
        if (leaf1_ecx & (1u << 29)) bits |= LANES_CPU_F16C;
        if (leaf1_ecx & (1u << 12)) bits |= LANES_CPU_FMA;
        if (leaf7_ebx & (1u << 5)) bits |= LANES_CPU_AVX2;
    }
    if (os_zmm) {
        if (leaf7_ebx & (1u << 16)) bits |= LANES_CPU_AVX512F;
        if (leaf7_ebx & (1u << 17)) bits |= LANES_CPU_AVX512DQ;
        if (leaf7_ebx & (1u << 28)) bits |= LANES_CPU_AVX512CD;
        if (leaf7_ebx & (1u << 30)) bits |= LANES_CPU_AVX512BW;
        if (leaf7_ebx & (1u << 31)) bits |= LANES_CPU_AVX512VL;
    }

    f->raw_bits = bits;
    f->bits = bits & ~feature_bits_from_names(getenv("LANES_DISABLE_CPU_FEATURES"));
}

static lanes_cpu_features detected;
static pthread_once_t detected_once = PTHREAD_ONCE_INIT;

static void detect_once(void) { detect(&detected); }

const lanes_cpu_features *lanes_cpu(void)
{
    pthread_once(&detected_once, detect_once);
    return &detected;
}
