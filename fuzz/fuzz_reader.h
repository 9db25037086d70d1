/* SPDX-License-Identifier: Apache-2.0 */
/*
 * fuzz/fuzz_reader.h -- the fuzz input read byte by byte; past its end, zeros.
 */
#ifndef CANOLA_FUZZ_READER_H
#define CANOLA_FUZZ_READER_H

#include <stddef.h>
#include <stdint.h>

typedef struct reader {
    const uint8_t *p;
    size_t n;
} reader_t;

/** The next input byte, or 0 once the input is used up. */
static inline uint8_t take(reader_t *in)
{
    if (in->n == 0) {
        return 0;
    }
    in->n--;
    return *in->p++;
}

#endif /* CANOLA_FUZZ_READER_H */
