#!/usr/bin/env bash
# Proves the separation that "One source, many widths" (design.md) relies on,
# on the object files themselves. qemu cannot catch an instruction that leaks
# into the wrong code (its emulator runs SSE4.1 and AVX2 even on CPU models
# that lack them), so this test is what guards the instructions.
#
#   check_hygiene.sh [--expect-violation] CHECK ARG OBJECT...
#
# CHECK:
#   symbols SUFFIX  every defined global symbol ends in _SUFFIX, so no two
#                   sets (and no baseline code) can share a symbol
#   sections -      no .init_array/.ctors (code that would run at load time,
#                   before dispatch, on whatever CPU it is)
#   isa LEVEL       no instruction above LEVEL:
#                   baseline  x86-64 baseline (SSE2): no SSSE3/SSE4/POPCNT,
#                             no VEX or EVEX encoding, no ymm/zmm/k register
#                   sse4      no VEX or EVEX encoding, no ymm/zmm/k register
#                   avx       no EVEX, zmm or k register, no FMA, no AVX2
#                   avx2      no EVEX, zmm or k register (no AVX-512)
#                   avx512emu the same as avx2: 16 lanes from AVX2 halves
#                   avx512vl8 no zmm register: AVX-512 on ymm only
#   check_hygiene.sh --levels   prints the isa levels, one per line: the
#                   kernel sets named here are checked at their own level
# --expect-violation inverts the verdict: the check must find something. It
# is how the tests prove this script can fail at all.
# Exit status: 0 pass, 1 fail, 2 usage error.
set -euo pipefail

usage() {
    echo "usage: $0 [--expect-violation] symbols SUFFIX|sections -|isa LEVEL OBJECT..." >&2
    exit 2
}

levels=(baseline sse4 avx avx2 avx512emu avx512vl8)
if [[ ${1:-} == --levels ]]; then
    printf '%s\n' "${levels[@]}"
    exit 0
fi

expect_violation=0
if [[ ${1:-} == --expect-violation ]]; then
    expect_violation=1
    shift
fi
(($# >= 3)) || usage
check=$1
arg=$2
shift 2
# CTest hands $<TARGET_OBJECTS:...> over as one ";"-separated argument.
objects=()
for a in "$@"; do
    IFS=';' read -ra parts <<<"$a"
    objects+=("${parts[@]}")
done
for o in "${objects[@]}"; do
    [[ -f $o ]] || { echo "no such object: $o" >&2; exit 2; }
done

report=$(mktemp)
trap 'rm -f "$report"' EXIT

# objdump -d with every byte of an instruction on one line, as
# "<object>\t<function>\t<bytes>\t<instruction>" lines.
disassemble() {
    objdump -d --no-show-raw-insn --insn-width=16 "$@" >/dev/null # fail early on a bad object
    objdump -d --insn-width=16 "$@" | awk -F'\t' '
        /file format/ { obj = $1; sub(/:[ ]+file format.*/, "", obj); next }
        /^[0-9a-f]+ <.*>:$/ { fn = $0; sub(/^[0-9a-f]+ </, "", fn); sub(/>:$/, "", fn); next }
        NF >= 3 && $1 ~ /^ *[0-9a-f]+:$/ { print obj "\t" fn "\t" $2 "\t" $3 }'
}

case $check in
symbols)
    [[ $arg =~ ^[a-z0-9]+$ ]] || usage
    # nm prints "addr type name"; weak and common symbols count too: any of
    # them could be merged with another set's copy by the linker.
    nm --defined-only -g -A "${objects[@]}" |
        awk -v suffix="_$arg" '{ n = $NF; if (substr(n, length(n) - length(suffix) + 1) != suffix) print }' \
            >"$report"
    what="global symbols without the suffix _$arg"
    ;;
sections)
    objdump -h "${objects[@]}" |
        awk '/file format/ { obj = $1 } $2 ~ /^\.(init_array|ctors|preinit_array|fini_array|dtors)/ { print obj " " $2 }' \
            >"$report"
    what="load-time constructor/destructor sections"
    ;;
isa)
    # Register names alone miss an AVX instruction on xmm registers, so the
    # encoding is checked as well: in 64-bit mode a first opcode byte of
    # c4/c5 is always a VEX prefix (AVX, FMA, BMI) and 62 always EVEX
    # (AVX-512). Only address-size and segment prefixes may precede them.
    vex='^((2e|3e|26|36|64|65|67) )*(c4|c5) '
    evex='^((2e|3e|26|36|64|65|67) )*62 '
    wide_regs='%(ymm|zmm)[0-9]+|%k[0-7]'
    avx512_regs='%zmm[0-9]+|%k[0-7]|%[xy]mm(1[6-9]|2[0-9]|3[01])'
    zmm_regs='%zmm[0-9]+'
    above_sse2='^(pabs[bwd]|palignr|phadd[a-z]*|phsub[a-z]*|pmaddubsw|pmulhrsw|pshufb|psign[bwd]|blendv?p[sd]|dpp[sd]|extractps|insertps|movntdqa|mpsadbw|packusdw|pblendvb|pblendw|pcmpeqq|pextr[bdq]|phminposuw|pinsr[bdq]|pmax(sb|sd|ud|uw)|pmin(sb|sd|ud|uw)|pmov[sz]x[a-z]*|pmuldq|pmulld|ptest|round[ps][sd]|pcmp[ei]str[im]|pcmpgtq|crc32[a-z]*|popcnt[a-z]*)( |$)'
    above_sse41='^(pcmp[ei]str[im]|pcmpgtq|crc32[a-z]*)( |$)'
    fma='^(vf(n)?m(add|sub|addsub|subadd)[0-9a-z]*)( |$)'
    # AVX has 256-bit float operations only: a "vp" integer operation on
    # ymm is AVX2, except the few AVX1 permutes and vptest; and these names
    # exist only from AVX2 on.
    avx2_only='^(vpbroadcast[bwdq]|vbroadcasti128|vinserti128|vextracti128|vperm2i128|vpermd|vpermps|vpermq|vpermpd|v(p)?gather[a-z]*|vpmaskmov[dq]|vps(l|r)lv[dq]|vpsrav[dq]|vpblendd)( |$)'
    case $arg in
    baseline) rule="wide_regs vex evex above_sse2" ;;
    sse4) rule="wide_regs vex evex above_sse41" ;;
    avx) rule="avx512_regs evex fma avx2_only avx_int256" ;;
    avx2 | avx512emu) rule="avx512_regs evex" ;;
    avx512vl8) rule="zmm_regs" ;;
    *) usage ;;
    esac
    disassemble "${objects[@]}" |
        awk -F'\t' -v rule=" $rule " -v vex="$vex" -v evex="$evex" -v wide_regs="$wide_regs" \
            -v avx512_regs="$avx512_regs" -v zmm_regs="$zmm_regs" -v above_sse2="$above_sse2" -v above_sse41="$above_sse41" \
            -v fma="$fma" -v avx2_only="$avx2_only" '
            function has(r) { return index(rule, " " r " ") > 0 }
            {
                bytes = $3; insn = $4; sub(/^ +/, "", insn); why = ""
                if (has("wide_regs") && insn ~ wide_regs) why = "ymm/zmm/k register"
                else if (has("avx512_regs") && insn ~ avx512_regs) why = "AVX-512 register"
                else if (has("zmm_regs") && insn ~ zmm_regs) why = "zmm register"
                else if (has("evex") && bytes ~ evex) why = "EVEX (AVX-512) encoding"
                else if (has("vex") && bytes ~ vex) why = "VEX (AVX/BMI) encoding"
                else if (has("above_sse2") && insn ~ above_sse2) why = "above the x86-64 baseline"
                else if (has("above_sse41") && insn ~ above_sse41) why = "SSE4.2"
                else if (has("fma") && insn ~ fma) why = "FMA"
                else if (has("avx2_only") && insn ~ avx2_only) why = "AVX2"
                else if (has("avx_int256") && insn ~ /^vp[a-z0-9]* / && insn ~ /%ymm/ &&
                         insn !~ /^vp(ermil|erm2f128|test)/) why = "AVX2 (256-bit integer)"
                if (why != "") print $1 ": " $2 ": " insn "   [" why "]"
            }' >"$report"
    what="instructions above $arg"
    ;;
*)
    usage
    ;;
esac

found=$(wc -l <"$report")
echo "checked ${#objects[@]} object(s): $check $arg"
if ((found > 0)); then
    echo "found $found $what:"
    head -n 20 "$report"
    ((found <= 20)) || echo "..."
fi
if ((expect_violation)); then
    if ((found > 0)); then
        echo "PASS: the check catches them, as it must on these objects"
        exit 0
    fi
    echo "FAIL: expected this check to find $what in these objects, it found none"
    exit 1
fi
if ((found > 0)); then
    echo "FAIL"
    exit 1
fi
echo "PASS: no $what"
