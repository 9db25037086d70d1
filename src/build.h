/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/build.h -- what the build's goal changes in the core: hints for the compiler, and the
 * copies of a size known only at run time. Not installed; every module includes it
 * (through kernel.h, or directly).
 */
#ifndef CANOLA_BUILD_H
#define CANOLA_BUILD_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "canola/config.h"

/* Keeps a rare path out of line, so the common path of its caller stays small (a hint:
 * compilers without the attribute just decide for themselves). */
#if defined(__GNUC__) || defined(__clang__)
#define CO_NOINLINE __attribute__((noinline))
#else
#define CO_NOINLINE
#endif

/* CO_NOINLINE for speed's sake alone (the caller's common path keeps its registers): a
 * build for size lets the compiler decide (where that measured smaller). */
#if (defined(__GNUC__) || defined(__clang__)) && !defined(__OPTIMIZE_SIZE__)
#define CO_FAST_NOINLINE __attribute__((noinline))
#else
#define CO_FAST_NOINLINE
#endif

/* Out of line in a build for size: a small helper that -Os would copy into each of its
 * callers, where one copy and the calls are smaller (GCC's estimate misses it; the
 * helpers marked so were found by measuring). Other builds let the compiler decide. */
#if (defined(__GNUC__) || defined(__clang__)) && defined(__OPTIMIZE_SIZE__)
#define CO_SIZE_NOINLINE __attribute__((noinline))
#else
#define CO_SIZE_NOINLINE
#endif

/* And the reverse: a small function (or one of one or two callers) that -Os keeps out of
 * line, where the copies are smaller (constant arguments fold, a large frame merges; the
 * functions marked so were found by measuring). Other builds let the compiler decide. */
#if (defined(__GNUC__) || defined(__clang__)) && defined(__OPTIMIZE_SIZE__)
#define CO_SIZE_INLINE inline __attribute__((always_inline))
#else
#define CO_SIZE_INLINE inline
#endif

/* The opposite hint: a small hot helper that the compiler's size heuristics would keep
 * out of line. Not when compiling for size (-Os): there flash counts more than cycles. */
#if (defined(__GNUC__) || defined(__clang__)) && !defined(__OPTIMIZE_SIZE__)
#define CO_INLINE inline __attribute__((always_inline))
#else
#define CO_INLINE inline
#endif

/* Copies and fills of a size known only at run time: the byte loops of copy.c, a few
 * instructions each, instead of the C library's memcpy and memset, which no other call needs
 * (about 470 bytes on Cortex-M4 with newlib-nano, 310 on Cortex-M0): the core's copies are
 * short (a segment, a value, a frame). Both take NULL pointers when `n` is 0. Copies of a
 * size known at compile time stay memcpy: the compiler turns those into moves. */
void co_copy_bytes(void *dst, const void *src, size_t n);
void co_zero_bytes(void *dst, size_t n);
#define co_copy co_copy_bytes
#define co_zero co_zero_bytes

/* Copies and fills of a size known at compile time between places of any alignment: a few
 * moves where the target loads and stores words at any address; the byte loops elsewhere
 * (Cortex-M0 would call the C library's memcpy and memset for them). */
#if defined(__x86_64__) || defined(__i386__) || defined(__aarch64__) ||                            \
    defined(__ARM_FEATURE_UNALIGNED)
#define co_copy_fixed(dst, src, n) memcpy((dst), (src), (n))
#define co_zero_fixed(dst, n) memset((dst), 0, (n))
#define CO_UNALIGNED_ACCESS 1
#else
#define co_copy_fixed co_copy_bytes
#define co_zero_fixed co_zero_bytes
#define CO_UNALIGNED_ACCESS 0
#endif

#endif /* CANOLA_BUILD_H */
