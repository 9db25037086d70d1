/* SPDX-License-Identifier: Apache-2.0 */
/*
 * tests/store_image.h -- a stored parameter image built by hand (the format of
 * canola/storage.h): a test writes records, seals them with a header and CRC, and then
 * damages what it wants to see refused.
 */
#ifndef CANOLA_TEST_STORE_IMAGE_H
#define CANOLA_TEST_STORE_IMAGE_H

#include <string.h>

#include "canola/storage.h"
#include "crc16.h"

/* Header + `len` bytes of `records` of `group` into `out`; the image's length. */
static inline uint32_t store_image_seal(uint8_t *out, co_param_group_t group,
                                        const uint8_t *records, uint32_t len)
{
    memcpy(out, CO_STORE_MAGIC, 4);
    out[4] = CO_STORE_FORMAT;
    out[5] = (uint8_t)group;
    co_put_u32(&out[6], len);
    memmove(&out[CO_STORE_HEADER_SIZE], records, len);
    uint16_t crc = co_crc16(co_crc16(0, records, len), out, 10);
    co_put_u16(&out[10], crc);
    return CO_STORE_HEADER_SIZE + len;
}

#endif /* CANOLA_TEST_STORE_IMAGE_H */
