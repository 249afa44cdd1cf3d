#pragma once
// SAGE_AVX2_CLONES before a function definition builds it twice, for AVX2 and for the baseline
// x86-64, and picks one at load time by what the CPU has. For loops whose every lane is its own
// element (no reduction across lanes): the AVX2 version then gives the same bits as the SSE2 one
// (AVX2 alone brings no FMA, so no multiply-add is contracted), four doubles a step instead of
// two. Used by the per-coefficient passes of the SMC law and the fleet's coverage.
// Clang before 16 (Debian's clang-14 builds the fuzz harnesses) emits no resolver that a call
// from another file links to: one version there.
#if defined(__clang__) && __clang_major__ < 16
#define SAGE_AVX2_CLONES
#else
#define SAGE_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
#endif
