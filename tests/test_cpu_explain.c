/* The refusal's reason on CPU states this machine is not: a Zen 3 (AVX2, no
 * AVX-512 at all, so no ZMM state in XCR0 either), a Xeon whose OS leaves
 * ZMM state off, a kernel booted with noxsave, and the test switch on top of
 * each. The reason must name the first cause a user can act on: what the
 * processor lacks, then what the OS has not enabled, then what
 * LANES_DISABLE_CPU_FEATURES hides. */
#include <stdio.h>
#include <string.h>

#include "simd/isa.h"
#include "tests/harness.h"


#define YMM (LANES_CPU_AVX | LANES_CPU_F16C | LANES_CPU_FMA | LANES_CPU_AVX2)
#define ZMM                                                                                 \
    (LANES_CPU_AVX512F | LANES_CPU_AVX512CD | LANES_CPU_AVX512DQ | LANES_CPU_AVX512BW |     \
     LANES_CPU_AVX512VL)
#define BASE                                                                                \
    (LANES_CPU_SSE2 | LANES_CPU_SSE3 | LANES_CPU_SSSE3 | LANES_CPU_SSE41 | LANES_CPU_SSE42 |  \
     LANES_CPU_POPCNT | LANES_CPU_BMI1 | LANES_CPU_BMI2 | LANES_CPU_LZCNT)

static lanes_cpu_features cpu_state(uint32_t cpuid, uint32_t usable, uint32_t after_switch,
                                    uint64_t xcr0)
{
    lanes_cpu_features f;
    memset(&f, 0, sizeof f);
    f.cpuid_bits = cpuid;
    f.raw_bits = usable;
    f.bits = after_switch;
    f.xcr0 = xcr0;
    return f;
}

/* `want` must be the whole reason; NULL: nothing is missing. */
static void expect(const char *what, const lanes_cpu_features *cpu, lanes_isa isa,
                   const char *want)
{
    char why[256];
    bool missing = lanes_cpu_explain_missing(cpu, lanes_isa_required_features(isa), why,
                                             sizeof why);
    bool ok = !want ? !missing : (missing && strcmp(why, want) == 0);
    if (CHECK(ok, "%s, %s: got \"%s\", want \"%s\"", what, lanes_isa_name(isa),
              missing ? why : "(nothing missing)", want ? want : "(nothing missing)")) {
        printf("PASS %s, %s: %s\n", what, lanes_isa_name(isa), want ? want : "runs");
    }
}

int main(void)
{
    const uint32_t avx2_cpu = BASE | LANES_CPU_OSXSAVE | YMM;
    const uint32_t avx512_cpu = avx2_cpu | ZMM;

    /* AMD Zen 3: no AVX-512 in cpuid; Linux enables x87, SSE and YMM state. */
    lanes_cpu_features zen3 = cpu_state(avx2_cpu, avx2_cpu, avx2_cpu, 0x7);
    expect("Zen 3", &zen3, LANES_ISA_AVX512,
           "this CPU lacks avx512f, avx512dq, avx512bw, avx512vl");
    expect("Zen 3", &zen3, LANES_ISA_AVX2, NULL);
    expect("Zen 3", &zen3, LANES_ISA_AVX512EMU, NULL);
    /* The switch on top of a missing feature: the CPU is the cause. */
    lanes_cpu_features zen3_switched =
        cpu_state(avx2_cpu, avx2_cpu, avx2_cpu & ~LANES_CPU_AVX2, 0x7);
    expect("Zen 3 with avx2 switched off", &zen3_switched, LANES_ISA_AVX512,
           "this CPU lacks avx512f, avx512dq, avx512bw, avx512vl");
    expect("Zen 3 with avx2 switched off", &zen3_switched, LANES_ISA_AVX2,
           "LANES_DISABLE_CPU_FEATURES switches off avx2");

    /* An AVX-512 processor whose OS saves no ZMM or opmask state. */
    lanes_cpu_features no_zmm = cpu_state(avx512_cpu, avx2_cpu, avx2_cpu, 0x7);
    expect("AVX-512 CPU, OS without ZMM state", &no_zmm, LANES_ISA_AVX512,
           "the OS has not enabled avx512f, avx512dq, avx512bw, avx512vl (their ZMM and opmask "
           "register state is off: XCR0 = 0x7)");
    expect("AVX-512 CPU, OS without ZMM state", &no_zmm, LANES_ISA_AVX2, NULL);

    /* A kernel booted with noxsave: CR4.OSXSAVE off, so no YMM state. */
    lanes_cpu_features noxsave = cpu_state(avx512_cpu, BASE, BASE, 0);
    expect("noxsave kernel", &noxsave, LANES_ISA_AVX,
           "the OS has not enabled osxsave, avx (no XSAVE: CPUID.OSXSAVE is 0)");
    expect("noxsave kernel", &noxsave, LANES_ISA_SSE4, NULL);
    /* XSAVE on, YMM state off in XCR0. */
    lanes_cpu_features no_ymm =
        cpu_state(avx512_cpu, BASE | LANES_CPU_OSXSAVE, BASE | LANES_CPU_OSXSAVE, 0x3);
    expect("OS without YMM state", &no_ymm, LANES_ISA_AVX2,
           "the OS has not enabled avx, fma, avx2 (their YMM register state is off: XCR0 = 0x3)");

    /* The OS is the cause before the switch. */
    lanes_cpu_features no_zmm_switched =
        cpu_state(avx512_cpu, avx2_cpu, avx2_cpu & ~LANES_CPU_FMA, 0x7);
    expect("OS without ZMM state, fma switched off", &no_zmm_switched, LANES_ISA_AVX512,
           "the OS has not enabled avx512f, avx512dq, avx512bw, avx512vl (their ZMM and opmask "
           "register state is off: XCR0 = 0x7)");

    /* Everything there, the switch hides some: every hidden need is named. */
    lanes_cpu_features xeon = cpu_state(avx512_cpu, avx512_cpu,
                                        avx512_cpu & ~(LANES_CPU_AVX512BW | LANES_CPU_AVX512CD),
                                        0xe7);
    expect("AVX-512 CPU, avx512bw and avx512cd switched off", &xeon, LANES_ISA_AVX512,
           "LANES_DISABLE_CPU_FEATURES switches off avx512bw");
    expect("AVX-512 CPU, avx512bw and avx512cd switched off", &xeon, LANES_ISA_AVX512EMU, NULL);

    /* Nehalem: no AVX in cpuid at all. */
    const uint32_t nehalem = BASE & ~(LANES_CPU_BMI1 | LANES_CPU_BMI2 | LANES_CPU_LZCNT);
    lanes_cpu_features old = cpu_state(nehalem, nehalem, nehalem, 0);
    expect("Nehalem", &old, LANES_ISA_AVX2, "this CPU lacks osxsave, avx, fma, avx2");

    /* A reason longer than the buffer is cut, not overrun. */
    char small[12];
    memset(small, 'x', sizeof small);
    bool cut = lanes_cpu_explain_missing(&zen3, lanes_isa_required_features(LANES_ISA_AVX512), small,
                                         sizeof small) &&
               strlen(small) == sizeof small - 1;
    if (CHECK(cut, "a short buffer: the reason is not cut to fit")) printf("PASS a short buffer holds \"%s\"\n", small);

    return harness_summary("test_cpu_explain");
}
