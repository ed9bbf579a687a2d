/* The instruction classes the resource bound of `lanes bench kernels`
 * charges (bench/kernel_model.c, km_classify), on instructions as objdump
 * prints them: the bound is only as right as the count of each class. */
#include "bench/kernel_model.h"
#include "harness.h"

typedef struct {
    const char *mnemonic, *operands;
    int classes;
} case_t;

static const case_t cases[] = {
    {"vfmadd231ps", "%ymm12,%ymm14,%ymm0", KM_VECTOR | KM_MUL},
    {"vmulps", "%xmm1,%xmm2,%xmm3", KM_VECTOR | KM_MUL},
    {"vrcpps", "%ymm1,%ymm2", KM_VECTOR | KM_MUL},
    {"mulss", "%xmm1,%xmm0", KM_VECTOR | KM_MUL},
    {"vaddps", "(%rax),%ymm1,%ymm2", KM_VECTOR | KM_ADD | KM_LOAD},
    {"vminps", "%zmm1,%zmm2,%zmm3", KM_VECTOR | KM_ADD | KM_ZMM},
    {"vcmpltps", "%ymm1,%ymm2,%ymm3", KM_VECTOR | KM_ADD},
    {"vcmpps", "$0x2,%zmm1,%zmm2,%k1", KM_VECTOR | KM_ADD | KM_ZMM},
    {"vpaddd", "%ymm1,%ymm2,%ymm3", KM_VECTOR},
    {"vblendvps", "%ymm1,%ymm2,%ymm3,%ymm4", KM_VECTOR},
    {"vmovmskps", "%ymm0,%eax", KM_VECTOR},
    {"kmovw", "%k1,%eax", KM_VECTOR},
    {"vmovaps", "%ymm1,%ymm2", 0},
    {"vmovups", "0x20(%rsi,%rax,4),%ymm3", KM_LOAD},
    {"vmovups", "0x1234(%rip),%ymm0        # 5678 <table+0x8>", KM_LOAD},
    {"vmovups", "%ymm0,(%rdi)", KM_STORE},
    {"vmovups", "%zmm0,(%rax){%k1}", KM_STORE | KM_ZMM},
    {"vmaskmovps", "%ymm1,%ymm2,(%rax)", KM_MASKSTORE},
    {"vmaskmovps", "(%rax),%ymm2,%ymm1", KM_LOAD},
    {"vbroadcastss", "(%rax),%ymm0", KM_LOAD},
    {"vbroadcastss", "%xmm1,%ymm0", KM_VECTOR},
    {"mov", "(%rdx),%eax", KM_LOAD},
    {"mov", "%eax,0x8(%rdx)", KM_STORE},
    {"cmp", "%eax,0x4(%rdx)", KM_LOAD},
    {"prefetcht0", "0x40(%rax)", KM_LOAD},
    {"lea", "0x8(%rax,%rcx,4),%rdx", 0},
    {"nopw", "0x0(%rax,%rax,1)", 0},
    {"add", "$0x20,%rax", 0},
};

int main(void)
{
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const case_t *c = &cases[i];
        int got = km_classify(c->mnemonic, c->operands);
        CHECK(got == c->classes, "%s %s: classes 0x%x, expected 0x%x", c->mnemonic, c->operands,
              (unsigned)got, (unsigned)c->classes);
    }
    return harness_summary("test_kernel_model");
}
