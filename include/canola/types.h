/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/types.h -- the vocabulary every canola module shares.
 *
 * Frames, time, error codes and SDO abort codes. Nothing here allocates or
 * keeps state; every type is plain data the caller may copy.
 *
 * Time: a 64-bit count of microseconds (`now_us`) that only grows. The core
 * never reads a clock; the caller passes the time in with every call.
 * Byte order: values on the wire are little-endian; in memory they are native.
 */
#ifndef CANOLA_TYPES_H
#define CANOLA_TYPES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#ifdef __cplusplus
extern "C" {
#endif

/** A deadline that never comes: what co_node_poll() returns when nothing is scheduled. */
#define CO_TIME_NEVER UINT64_MAX

/* ---- Errors of the API (what goes wrong on the bus is never one of these). */
typedef enum co_err {
    CO_OK = 0,
    CO_ERR_ARG = -1,       /**< an argument is out of range or NULL */
    CO_ERR_BUSY = -2,      /**< driver: no room to send now, try again later */
    CO_ERR_CONFIG = -3,    /**< the configuration or object dictionary is inconsistent */
    CO_ERR_STATE = -4,     /**< not allowed in the current state */
    CO_ERR_NOT_FOUND = -5, /**< no such object / entry / node */
    CO_ERR_FULL = -6,      /**< a bounded table or queue has no room */
    CO_ERR_ABORT = -7,     /**< an object dictionary access failed; see the abort code */
} co_err_t;

/* ---- CAN frames. */
#define CO_FRAME_EXT 0x01u /**< 29-bit identifier */
#define CO_FRAME_RTR 0x02u /**< remote transmission request */

#define CO_ID_STD_MAX 0x7FFu
#define CO_ID_EXT_MAX 0x1FFFFFFFu

/** Data bytes a frame carries at most: 8 in classic CAN (CC). The one place that decides it:
 *  the frame below, the node's input check, the transmit path and the PDOs' sizes follow it;
 *  every other length is a protocol's own (an SDO frame has 8, a heartbeat 1, ...). */
#define CO_FRAME_DATA_MAX 8u

/** One classic CAN frame. `len` is 0..8; for RTR frames it is the requested length. */
typedef struct co_frame {
    uint32_t id;                     /**< 11-bit or (with CO_FRAME_EXT) 29-bit identifier */
    uint8_t flags;                   /**< CO_FRAME_EXT | CO_FRAME_RTR */
    uint8_t len;                     /**< data length code, 0..CO_FRAME_DATA_MAX */
    uint8_t data[CO_FRAME_DATA_MAX]; /**< payload; bytes past len are unspecified */
} co_frame_t;

/* ---- SDO abort codes (CiA 301), the language of object dictionary failures. */
typedef uint32_t co_abort_t;

#define CO_ABORT_NONE 0x00000000u
#define CO_ABORT_TOGGLE 0x05030000u         /**< toggle bit not alternated */
#define CO_ABORT_TIMEOUT 0x05040000u        /**< SDO protocol timed out */
#define CO_ABORT_COMMAND 0x05040001u        /**< command specifier not valid or unknown */
#define CO_ABORT_BLOCK_SIZE 0x05040002u     /**< invalid block size */
#define CO_ABORT_SEQUENCE 0x05040003u       /**< invalid sequence number */
#define CO_ABORT_CRC 0x05040004u            /**< CRC error */
#define CO_ABORT_OUT_OF_MEMORY 0x05040005u  /**< out of memory */
#define CO_ABORT_UNSUPPORTED 0x06010000u    /**< unsupported access to an object */
#define CO_ABORT_WRITE_ONLY 0x06010001u     /**< attempt to read a write-only object */
#define CO_ABORT_READ_ONLY 0x06010002u      /**< attempt to write a read-only object */
#define CO_ABORT_NO_OBJECT 0x06020000u      /**< object does not exist */
#define CO_ABORT_NO_MAP 0x06040041u         /**< object cannot be mapped to the PDO */
#define CO_ABORT_MAP_LEN 0x06040042u        /**< mapped objects would exceed PDO length */
#define CO_ABORT_PARAM_INCOMPAT 0x06040043u /**< general parameter incompatibility */
#define CO_ABORT_INTERNAL_INCOMPAT 0x06040047u
#define CO_ABORT_HARDWARE 0x06060000u      /**< access failed due to a hardware error */
#define CO_ABORT_TYPE_MISMATCH 0x06070010u /**< data type / length does not match */
#define CO_ABORT_LEN_HIGH 0x06070012u      /**< length of service parameter too high */
#define CO_ABORT_LEN_LOW 0x06070013u       /**< length of service parameter too low */
#define CO_ABORT_NO_SUB 0x06090011u        /**< sub-index does not exist */
#define CO_ABORT_VALUE 0x06090030u         /**< invalid value (download only) */
#define CO_ABORT_VALUE_HIGH 0x06090031u    /**< value too high */
#define CO_ABORT_VALUE_LOW 0x06090032u     /**< value too low */
#define CO_ABORT_MAX_LESS_MIN 0x06090036u  /**< maximum value less than minimum value */
#define CO_ABORT_NO_RESOURCE 0x060A0023u   /**< resource not available: SDO connection */
#define CO_ABORT_GENERAL 0x08000000u       /**< general error */
#define CO_ABORT_DATA_STORE 0x08000020u    /**< data cannot be transferred or stored */
#define CO_ABORT_DATA_LOCAL 0x08000021u    /**< ... because of local control */
#define CO_ABORT_DATA_STATE 0x08000022u    /**< ... because of the present device state */
#define CO_ABORT_NO_OD 0x08000023u         /**< object dictionary not present */
#define CO_ABORT_NO_DATA 0x08000024u       /**< no data available */

/* ---- Little-endian helpers for byte buffers (safe for any alignment). On a little-endian
 * host with unaligned loads they are one load or store: memcpy of a fixed size, which
 * compilers turn into a move; elsewhere (Cortex-M0, which has no unaligned access and would
 * call memcpy) they go byte by byte. */
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__ &&                        \
    !(defined(__arm__) && !defined(__ARM_FEATURE_UNALIGNED))
static inline uint16_t co_get_u16(const uint8_t *p)
{
    uint16_t v;
    memcpy(&v, p, sizeof v);
    return v;
}
static inline uint32_t co_get_u32(const uint8_t *p)
{
    uint32_t v;
    memcpy(&v, p, sizeof v);
    return v;
}
static inline void co_put_u16(uint8_t *p, uint16_t v) { memcpy(p, &v, sizeof v); }
static inline void co_put_u32(uint8_t *p, uint32_t v) { memcpy(p, &v, sizeof v); }
#else
static inline uint16_t co_get_u16(const uint8_t *p) { return (uint16_t)(p[0] | (p[1] << 8)); }
static inline uint32_t co_get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static inline void co_put_u16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}
static inline void co_put_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}
#endif

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_TYPES_H */
