/* SPDX-License-Identifier: Apache-2.0 */
/*
 * copy.c -- the byte loops behind co_copy and co_zero (build.h).
 */
#include "build.h"

/* GCC would turn these loops back into calls of memcpy and memset (the library functions
 * they are here to avoid): not in this file. */
#if defined(__GNUC__) && !defined(__clang__)
#define CO_NO_LIBCALLS __attribute__((optimize("no-tree-loop-distribute-patterns")))
#else
#define CO_NO_LIBCALLS
#endif

CO_NO_LIBCALLS void co_copy_bytes(void *dst, const void *src, size_t n)
{
    uint8_t *d = dst;
    const uint8_t *s = src;
    while (n-- > 0) {
        *d++ = *s++;
    }
}

CO_NO_LIBCALLS void co_zero_bytes(void *dst, size_t n)
{
    uint8_t *d = dst;
    while (n-- > 0) {
        *d++ = 0;
    }
}
