/* Inputs of the throughput bound; see kernel_model.h for the model. */
#define _GNU_SOURCE /* REG_RIP/REG_RSP in ucontext, dladdr, readlink, popen */

#include "bench/kernel_model.h"

#include <dlfcn.h>
#include <elf.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <ucontext.h>
#include <unistd.h>

#include "bench/cli_common.h"

/* ---- the core ---------------------------------------------------------- */

km_core km_core_model(const char *vendor, unsigned family, unsigned model)
{
    km_core c = {4, "unknown core", "", false};
    (void)model;
    if (strcmp(vendor, "AuthenticAMD") == 0 && family == 0x1a) {
        c.issue_width = 8;
        c.name = "AMD Zen 5 (family 1Ah)";
        c.why = "Zen 5 renames and dispatches 8 macro-ops per cycle (Zen 1-4: 6)";
        c.known = true;
    } else if (strcmp(vendor, "AuthenticAMD") == 0 && family == 0x19) {
        c.issue_width = 6;
        c.name = "AMD Zen 3/4 (family 19h)";
        c.why = "Zen 3 and 4 dispatch 6 macro-ops per cycle";
        c.known = true;
    } else if (strcmp(vendor, "AuthenticAMD") == 0 && family == 0x17) {
        c.issue_width = 6;
        c.name = "AMD Zen 1/2 (family 17h)";
        c.why = "Zen 1 and 2 dispatch 6 macro-ops per cycle";
        c.known = true;
    } else {
        c.why = "no table entry for this core: 4 per cycle assumed, the width of most x86 cores "
                "of the last decade; pass --issue-width to state the right one";
    }
    return c;
}

/* ---- the clock --------------------------------------------------------- */

#define CHAIN_ADDS 100

/* CHAIN_ADDS dependent adds per iteration: each needs the previous result,
 * so the chain retires one add per cycle whatever the core's width; the
 * loop counter is an independent chain that hides beside it. */
static uint64_t add_chain(uint64_t iterations)
{
    uint64_t x = 0, one = 1;
    __asm__ volatile("1:\n\t"
                     ".rept 100\n\t"
                     "add %[one], %[x]\n\t"
                     ".endr\n\t"
                     "dec %[n]\n\t"
                     "jnz 1b"
                     : [x] "+r"(x), [n] "+r"(iterations)
                     : [one] "r"(one)
                     : "cc");
    return x;
}

double km_measure_clock_hz(int reps, double run_ms)
{
    uint64_t iters = 1000;
    double ns = 0.0;
    /* Grow the run until it lasts long enough to time. */
    for (;;) {
        uint64_t t0 = cli_now_ns();
        add_chain(iters);
        ns = (double)(cli_now_ns() - t0);
        if (ns > run_ms * 1e6 / 4 || iters > ((uint64_t)1 << 40)) break;
        iters *= 4;
    }
    iters = (uint64_t)((double)iters * run_ms * 1e6 / ns) + 1;
    /* The fastest run, not the median: being preempted or interrupted can
     * only make a run slower, so the fastest is the least disturbed. */
    double best = 0.0;
    for (int r = 0; r < reps; r++) {
        uint64_t t0 = cli_now_ns();
        add_chain(iters);
        double t = (double)(cli_now_ns() - t0);
        double hz = (double)iters * CHAIN_ADDS / (t * 1e-9);
        if (hz > best) best = hz;
    }
    return best;
}

/* ---- instruction counting by single-stepping --------------------------- */

#define TF_BIT 0x100
#define SITE_BITS 14
#define SITE_SLOTS (1u << SITE_BITS)
/* Ends a trace that runs away (a kernel stuck in a loop, or a bad entry). */
#define TRACE_LIMIT 50000000ull

enum { T_IDLE, T_ARMED, T_INSIDE, T_DONE, T_OVERFLOW };

/* Written by the signal handler, read after the traced call. */
static volatile int t_state = T_IDLE;
static uintptr_t t_entry, t_ret, t_rsp0, t_prev;
static uint64_t t_count;
static uintptr_t site_addr[SITE_SLOTS];
static uint64_t site_count[SITE_SLOTS];
static size_t site_used;
static bool site_overflow;

static void site_add(uintptr_t addr)
{
    size_t h = (size_t)((addr * 0x9e3779b97f4a7c15ull) >> (64 - SITE_BITS));
    for (size_t probe = 0; probe < SITE_SLOTS; probe++, h = (h + 1) & (SITE_SLOTS - 1)) {
        if (site_addr[h] == addr) {
            site_count[h]++;
            return;
        }
        if (site_addr[h] == 0) {
            if (site_used + 1 >= SITE_SLOTS / 2) break;
            site_addr[h] = addr;
            site_count[h] = 1;
            site_used++;
            return;
        }
    }
    site_overflow = true;
}

/* One SIGTRAP per instruction while the trap flag is set. The context's
 * RIP is the next instruction; the one that just ran was at t_prev. A REP
 * string instruction traps once per iteration without moving RIP, which
 * the RIP comparison folds back into one instruction. */
static void on_trap(int sig, siginfo_t *info, void *ucv)
{
    ucontext_t *uc = ucv;
    greg_t *g = uc->uc_mcontext.gregs;
    uintptr_t rip = (uintptr_t)g[REG_RIP], rsp = (uintptr_t)g[REG_RSP];
    (void)sig, (void)info;

    if (t_state == T_ARMED) {
        if (rip == t_entry) {
            t_state = T_INSIDE;
            t_rsp0 = rsp;
            memcpy(&t_ret, (const void *)rsp, sizeof t_ret); /* the return address */
            t_prev = rip;
        }
    } else if (t_state == T_INSIDE) {
        if (rip != t_prev) {
            t_count++;
            site_add(t_prev);
            t_prev = rip;
        }
        if (rip == t_ret && rsp == t_rsp0 + sizeof(uintptr_t)) {
            t_state = T_DONE;
            g[REG_EFL] &= ~(greg_t)TF_BIT;
        } else if (t_count >= TRACE_LIMIT) {
            t_state = T_OVERFLOW;
            g[REG_EFL] &= ~(greg_t)TF_BIT;
        }
    }
}

/* Both sequences step past the red zone first: pushfq would otherwise
 * overwrite whatever the compiler keeps below the stack pointer. */
static inline void trap_flag_on(void)
{
    __asm__ volatile("sub $128, %%rsp\n\t"
                     "pushfq\n\t"
                     "orq $0x100, (%%rsp)\n\t"
                     "popfq\n\t"
                     "add $128, %%rsp" ::: "cc", "memory");
}

static inline void trap_flag_off(void)
{
    __asm__ volatile("sub $128, %%rsp\n\t"
                     "pushfq\n\t"
                     "andq $-257, (%%rsp)\n\t"
                     "popfq\n\t"
                     "add $128, %%rsp" ::: "cc", "memory");
}

void km_trace_reset(void)
{
    memset(site_addr, 0, sizeof site_addr);
    memset(site_count, 0, sizeof site_count);
    site_used = 0;
    site_overflow = false;
}

bool km_trace_call(uintptr_t entry, void (*fn)(void *), void *arg, uint64_t *instructions,
                   char *why, size_t why_size)
{
    struct sigaction sa, old;
    memset(&sa, 0, sizeof sa);
    sa.sa_sigaction = on_trap;
    sa.sa_flags = SA_SIGINFO;
    sigemptyset(&sa.sa_mask);
    if (sigaction(SIGTRAP, &sa, &old) != 0) {
        snprintf(why, why_size, "cannot install a SIGTRAP handler");
        return false;
    }
    t_entry = entry;
    t_count = 0;
    t_state = T_ARMED;
    trap_flag_on();
    fn(arg);
    trap_flag_off();
    int state = t_state;
    t_state = T_IDLE;
    sigaction(SIGTRAP, &old, NULL);

    *instructions = t_count;
    if (state == T_DONE && !site_overflow) return true;
    if (state == T_OVERFLOW)
        snprintf(why, why_size, "the traced call ran past %llu instructions",
                 (unsigned long long)TRACE_LIMIT);
    else if (site_overflow)
        snprintf(why, why_size, "more distinct instructions than the trace table holds");
    else
        snprintf(why, why_size, "single-stepping did not reach the kernel's entry point "
                                "(is a debugger intercepting SIGTRAP?)");
    return false;
}

static int cmp_site(const void *a, const void *b)
{
    uintptr_t x = ((const km_site *)a)->addr, y = ((const km_site *)b)->addr;
    return (x > y) - (x < y);
}

size_t km_trace_sites(km_site **sites)
{
    *sites = malloc((site_used ? site_used : 1) * sizeof **sites);
    if (!*sites) return 0;
    size_t n = 0;
    for (size_t h = 0; h < SITE_SLOTS; h++)
        if (site_addr[h]) (*sites)[n++] = (km_site){site_addr[h], site_count[h]};
    qsort(*sites, n, sizeof **sites, cmp_site);
    return n;
}

/* ---- instruction classes from objdump ---------------------------------- */

static bool starts_with(const char *s, const char *prefix)
{
    return strncmp(s, prefix, strlen(prefix)) == 0;
}

static bool any_prefix(const char *s, const char *const *prefixes)
{
    for (; *prefixes; prefixes++)
        if (starts_with(s, *prefixes)) return true;
    return false;
}

/* Memory: an operand in parentheses (but lea and nop only compute or pad
 * an address). AT&T puts the destination last, so memory there is a store,
 * except for the instructions that only read their operands; the load half
 * of a read-modify-write (add %eax,(%rdx)) is not counted, an integer form
 * the kernels' timed copies do not use. A vector
 * pipe: any operation on xmm/ymm/zmm/k registers but moves (loads and
 * stores go through the load/store pipes, register copies are eliminated
 * at rename, broadcasts from memory are loads). */
int km_classify(const char *mnemonic, const char *operands)
{
    static const char *const reads_only[] = {"cmp", "test", "bt", "ucomis", "comis", "vucomis",
                                             "vcomis", "prefetch", NULL};
    static const char *const shuffle_like[] = {"movmsk", "movshdup", "movsldup", "movddup",
                                               "movhlps", "movlhps", NULL};
    static const char *const mul[] = {"mul", "fmadd", "fmsub", "fnmadd", "fnmsub", "rcp",
                                      "rsqrt", "div", "sqrt", "pmul", NULL};
    static const char *const add[] = {"add", "sub", "min", "max", "cmp", NULL};
    int cls = 0;
    const char *last = strrchr(operands, ',');
    last = last ? last + 1 : operands;
    if (strchr(operands, '(') && !starts_with(mnemonic, "lea") && !starts_with(mnemonic, "nop")) {
        bool store = strchr(last, '(') && !any_prefix(mnemonic, reads_only);
        if (!store)
            cls |= KM_LOAD;
        else if (starts_with(mnemonic, "vmaskmov") || starts_with(mnemonic, "vpmaskmov"))
            cls |= KM_MASKSTORE;
        else
            cls |= KM_STORE;
    }
    bool vec = strstr(operands, "%xmm") || strstr(operands, "%ymm") || strstr(operands, "%zmm") ||
               strstr(operands, "%k") || mnemonic[0] == 'k';
    if (!vec) return cls;
    if (strstr(operands, "%zmm")) cls |= KM_ZMM;
    const char *m = mnemonic[0] == 'v' ? mnemonic + 1 : mnemonic;
    bool memory = strchr(operands, '(') != NULL;
    if (starts_with(m, "mov") && !any_prefix(m, shuffle_like)) return cls;
    if ((starts_with(m, "broadcast") || starts_with(m, "pbroadcast")) && memory) return cls;
    if (starts_with(m, "maskmov") || starts_with(m, "pmaskmov")) return cls;
    cls |= KM_VECTOR;
    if (any_prefix(m, mul)) cls |= KM_MUL;
    if (any_prefix(m, add)) cls |= KM_ADD;
    return cls;
}

static int cmp_uintptr(const void *a, const void *b)
{
    uintptr_t x = *(const uintptr_t *)a, y = *(const uintptr_t *)b;
    return (x > y) - (x < y);
}

bool km_disasm_load(uintptr_t lo, uintptr_t hi, km_disasm *d, char *why, size_t why_size)
{
    char exe[4096], cmd[4096 + 256], quoted[4096 * 4 + 3];
    Dl_info dl;
    memset(d, 0, sizeof *d);

    ssize_t len = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (len <= 0) {
        snprintf(why, why_size, "cannot find the running executable (/proc/self/exe)");
        return false;
    }
    exe[len] = '\0';
    /* A position-independent executable is disassembled at its link
     * addresses; the running copy sits at those plus its load base. */
    if (!dladdr((void *)lo, &dl) || !dl.dli_fbase) {
        snprintf(why, why_size, "cannot locate the kernel code in the executable (dladdr)");
        return false;
    }
    const Elf64_Ehdr *eh = dl.dli_fbase;
    uintptr_t bias = eh->e_type == ET_DYN ? (uintptr_t)dl.dli_fbase : 0;

    size_t q = 0;
    quoted[q++] = '\'';
    for (const char *p = exe; *p && q + 5 < sizeof quoted; p++) {
        if (*p == '\'') {
            memcpy(quoted + q, "'\\''", 4);
            q += 4;
        } else {
            quoted[q++] = *p;
        }
    }
    quoted[q++] = '\'';
    quoted[q] = '\0';
    snprintf(cmd, sizeof cmd,
             "objdump -d --no-show-raw-insn --start-address=0x%llx --stop-address=0x%llx %s "
             "2>/dev/null",
             (unsigned long long)(lo - bias), (unsigned long long)(hi - bias + 1), quoted);

    FILE *p = popen(cmd, "r");
    if (!p) {
        snprintf(why, why_size, "cannot run objdump");
        return false;
    }
    size_t cap = 0;
    char line[1024];
    while (fgets(line, sizeof line, p)) {
        /* "  1a2b:\tvsubps %ymm4,%ymm0,%ymm0" */
        char *end;
        const char *s = line + strspn(line, " ");
        unsigned long long a = strtoull(s, &end, 16);
        if (end == s || end[0] != ':' || end[1] != '\t') continue;
        char *mn = end + 2;
        size_t mlen = strcspn(mn, " \t\n");
        if (mlen == 0 || mlen >= 32) continue;
        char mnemonic[32];
        memcpy(mnemonic, mn, mlen);
        mnemonic[mlen] = '\0';
        const char *ops = mn + mlen;
        if (d->count == cap) {
            size_t ncap = cap ? 2 * cap : 4096;
            uintptr_t *na = realloc(d->addr, ncap * sizeof *na);
            if (!na) break;
            d->addr = na;
            unsigned char *nc = realloc(d->cls, ncap);
            if (!nc) break;
            d->cls = nc;
            cap = ncap;
        }
        d->addr[d->count] = (uintptr_t)a + bias;
        d->cls[d->count] = (unsigned char)km_classify(mnemonic, ops);
        d->count++;
    }
    int status = pclose(p);
    if (d->count == 0) {
        km_disasm_free(d);
        if (status != -1 && WIFEXITED(status) && WEXITSTATUS(status) == 127)
            snprintf(why, why_size, "objdump is not installed");
        else
            snprintf(why, why_size, "objdump printed no instructions for %s", exe);
        return false;
    }
    /* objdump lists in address order already; sorting keeps the lookup
     * correct should a section list come out of order. */
    bool sorted = true;
    for (size_t i = 1; i < d->count; i++)
        if (d->addr[i] < d->addr[i - 1]) sorted = false;
    if (!sorted) {
        /* rare: sort indices by address, classes along */
        uintptr_t *pairs = malloc(d->count * 2 * sizeof *pairs);
        if (!pairs) {
            km_disasm_free(d);
            snprintf(why, why_size, "out of memory");
            return false;
        }
        for (size_t i = 0; i < d->count; i++) pairs[2 * i] = d->addr[i], pairs[2 * i + 1] = d->cls[i];
        qsort(pairs, d->count, 2 * sizeof *pairs, cmp_uintptr);
        for (size_t i = 0; i < d->count; i++)
            d->addr[i] = pairs[2 * i], d->cls[i] = (unsigned char)pairs[2 * i + 1];
        free(pairs);
    }
    return true;
}

int km_disasm_class(const km_disasm *d, uintptr_t addr)
{
    size_t lo = 0, hi = d->count;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (d->addr[mid] < addr)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < d->count && d->addr[lo] == addr ? d->cls[lo] : -1;
}

void km_disasm_free(km_disasm *d)
{
    free(d->addr);
    free(d->cls);
    memset(d, 0, sizeof *d);
}
