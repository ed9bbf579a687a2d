/* CPU feature detection: cpuid for what the CPU has, xgetbv for what the OS
 * saves on a context switch. A CPU can list AVX or AVX-512 while the OS has
 * not enabled their register state (VMs, "noxsave" kernels); executing them
 * then traps, so such features count as absent. */
#include "simd/isa.h"

#include <cpuid.h>
#include <pthread.h>
#include <stdbool.h>
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

/* The names in a LANES_DISABLE_CPU_FEATURES list as bits; the first name
 * that is no feature goes to `unknown` (a typo must not pass for a test of a
 * CPU without that feature). */
static uint32_t feature_bits_from_names(const char *list, char *unknown, size_t unknown_size)
{
    uint32_t bits = 0;
    while (list && *list) {
        size_t n = strcspn(list, ", ");
        if (n > 0) {
            bool known = false;
            for (int i = 0; i < LANES_CPU_FEATURE_COUNT; i++)
                if (strlen(feature_names[i]) == n && strncmp(list, feature_names[i], n) == 0) {
                    bits |= 1u << i;
                    known = true;
                }
            if (!known && !unknown[0]) snprintf(unknown, unknown_size, "%.*s", (int)n, list);
        }
        list += n;
        list += strspn(list, ", ");
    }
    return bits;
}

#define YMM_FEATURES (LANES_CPU_AVX | LANES_CPU_F16C | LANES_CPU_FMA | LANES_CPU_AVX2)
#define ZMM_FEATURES                                                                        \
    (LANES_CPU_AVX512F | LANES_CPU_AVX512CD | LANES_CPU_AVX512DQ | LANES_CPU_AVX512BW |      \
     LANES_CPU_AVX512VL)

static void append_names(char *buf, size_t size, uint32_t bits)
{
    size_t used = strlen(buf);
    for (int i = 0; i < LANES_CPU_FEATURE_COUNT && used + 1 < size; i++) {
        if (!(bits & (1u << i))) continue;
        int n = snprintf(buf + used, size - used, "%s%s", (bits & ((1u << i) - 1)) ? ", " : "",
                         feature_names[i]);
        if (n < 0) break;
        used += (size_t)n < size - used ? (size_t)n : size - used - 1;
    }
}

bool lanes_cpu_explain_missing(const lanes_cpu_features *cpu, uint32_t needs, char *why,
                               size_t size)
{
    uint32_t lacked = needs & ~cpu->cpuid_bits;
    uint32_t not_enabled = needs & cpu->cpuid_bits & ~cpu->raw_bits;
    uint32_t switched_off = needs & cpu->raw_bits & ~cpu->bits;
    if (!size) return lacked | not_enabled | switched_off;
    why[0] = '\0';
    if (lacked) {
        snprintf(why, size, "this CPU lacks ");
        append_names(why, size, lacked);
    } else if (not_enabled) {
        /* The processor has the features; the OS does not save their state. */
        char state[96];
        if (not_enabled & LANES_CPU_OSXSAVE)
            snprintf(state, sizeof state, "no XSAVE: CPUID.OSXSAVE is 0");
        else
            snprintf(state, sizeof state, "their %s register state is off: XCR0 = 0x%llx",
                     (not_enabled & YMM_FEATURES) ? "YMM" : "ZMM and opmask",
                     (unsigned long long)cpu->xcr0);
        snprintf(why, size, "the OS has not enabled ");
        append_names(why, size, not_enabled);
        size_t used = strlen(why);
        snprintf(why + used, size - used, " (%s)", state);
    } else if (switched_off) {
        snprintf(why, size, "LANES_DISABLE_CPU_FEATURES switches off ");
        append_names(why, size, switched_off);
    }
    return why[0] != '\0';
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
        /* brand strings are padded with spaces on some CPUs, before or after */
        size_t lead = strspn(f->brand, " ");
        memmove(f->brand, f->brand + lead, strlen(f->brand + lead) + 1);
        size_t len = strlen(f->brand);
        while (len > 0 && f->brand[len - 1] == ' ') f->brand[--len] = '\0';
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
    /* The processor's own view: XSAVE (bit 26) stands for osxsave here. */
    if (leaf1_ecx & (1u << 26)) bits |= LANES_CPU_OSXSAVE;
    if (leaf1_ecx & (1u << 28)) bits |= LANES_CPU_AVX;
    if (leaf1_ecx & (1u << 29)) bits |= LANES_CPU_F16C;
    if (leaf1_ecx & (1u << 12)) bits |= LANES_CPU_FMA;
    if (leaf7_ebx & (1u << 5)) bits |= LANES_CPU_AVX2;
    if (leaf7_ebx & (1u << 16)) bits |= LANES_CPU_AVX512F;
    if (leaf7_ebx & (1u << 17)) bits |= LANES_CPU_AVX512DQ;
    if (leaf7_ebx & (1u << 28)) bits |= LANES_CPU_AVX512CD;
    if (leaf7_ebx & (1u << 30)) bits |= LANES_CPU_AVX512BW;
    if (leaf7_ebx & (1u << 31)) bits |= LANES_CPU_AVX512VL;
    f->cpuid_bits = bits;

    /* Everything that uses YMM or ZMM registers also needs the OS's consent:
     * OSXSAVE (bit 27) says the OS set CR4.OSXSAVE, so xgetbv is usable. */
    bool xsave = (leaf1_ecx & (1u << 26)) && (leaf1_ecx & (1u << 27));
    if (xsave) f->xcr0 = read_xcr0();
    bool os_ymm = xsave && (f->xcr0 & 0x6) == 0x6;    /* XMM and YMM state */
    bool os_zmm = os_ymm && (f->xcr0 & 0xe0) == 0xe0; /* opmask, ZMM0-15 high, ZMM16-31 */
    if (!xsave) bits &= ~LANES_CPU_OSXSAVE;
    if (!os_ymm) bits &= ~(uint32_t)YMM_FEATURES;
    if (!os_zmm) bits &= ~(uint32_t)ZMM_FEATURES;

    f->raw_bits = bits;
    f->bits = bits & ~feature_bits_from_names(getenv("LANES_DISABLE_CPU_FEATURES"),
                                              f->unknown_disabled, sizeof f->unknown_disabled);
}

static lanes_cpu_features detected;
static char all_feature_names[256]; /* "sse2, sse3, ...", from feature_names */
static pthread_once_t detected_once = PTHREAD_ONCE_INIT;

static void detect_once(void)
{
    detect(&detected);
    append_names(all_feature_names, sizeof all_feature_names, (1u << LANES_CPU_FEATURE_COUNT) - 1);
}

const char *lanes_cpu_all_feature_names(void)
{
    lanes_cpu();
    return all_feature_names;
}

const lanes_cpu_features *lanes_cpu(void)
{
    pthread_once(&detected_once, detect_once);
    return &detected;
}
