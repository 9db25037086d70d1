/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/sdo_protocol.h -- the words of the SDO protocol (CiA 301, 7.2.4.3), named once for the
 * server (sdo_server.c) and the client (sdo_client.c): the command specifiers of byte 0, the
 * bits around them, and the sizes. Not installed.
 *
 * Every SDO frame has 8 bytes; byte 0 is the command: bits 7..5 the command specifier (the
 * client's ccs in a request, the server's scs in a response), the rest its parameters.
 * Initiate frames carry the index (bytes 1..2), the sub-index (3) and 4 bytes of data or size.
 */
#ifndef CANOLA_SDO_PROTOCOL_H
#define CANOLA_SDO_PROTOCOL_H

/* ---- sizes */
#define CO_SDO_FRAME_LEN 8u     /* every SDO frame */
#define CO_SDO_SEG_BYTES 7u     /* data bytes of a segment (byte 0 is the command) */
#define CO_SDO_EXPEDITED_MAX 4u /* data bytes of an expedited transfer (bytes 4..7) */
#define CO_SDO_BLKSIZE_MAX 127u /* segments per sub-block */

/* ---- command specifiers (byte 0, bits 7..5) */
#define CO_SDO_CS_MASK 0xE0u
#define CO_SDO_CS_ABORT 0x80u /* abort transfer, either side: the code in bytes 4..7 */
/* the client's requests (ccs) */
#define CO_SDO_CCS_DN_SEG 0x00u /* download segment:    000t nnnc */
#define CO_SDO_CCS_DN_INI 0x20u /* initiate download:   0010 nnes */
#define CO_SDO_CCS_UP_INI 0x40u /* initiate upload:     0100 0000 */
#define CO_SDO_CCS_UP_SEG 0x60u /* upload segment:      011t 0000 */
#define CO_SDO_CCS_BLK_UP 0xA0u /* block upload:        1010 0cxx (xx: sub-command) */
#define CO_SDO_CCS_BLK_DN 0xC0u /* block download:      1100 nnsx, 110x x0x0 initiate */
/* the server's responses (scs) */
#define CO_SDO_SCS_UP_SEG 0x00u /* upload segment:      000t nnnc */
#define CO_SDO_SCS_DN_SEG 0x20u /* download segment:    001t 0000 */
#define CO_SDO_SCS_UP_INI 0x40u /* initiate upload:     0100 nnes */
#define CO_SDO_SCS_DN_INI 0x60u /* initiate download:   0110 0000 */
#define CO_SDO_SCS_BLK_DN 0xA0u /* block download:      1010 0cxx */
#define CO_SDO_SCS_BLK_UP 0xC0u /* block upload:        1100 nnsx */

/* ---- initiate (expedited and segmented) */
#define CO_SDO_INI_SIZE 0x01u      /* s: the size is given (bytes 4..7, or n) */
#define CO_SDO_INI_EXPEDITED 0x02u /* e: the data is in bytes 4..7 */
#define CO_SDO_INI_N_SHIFT 2u      /* n (bits 3..2): expedited bytes that hold no data */
#define CO_SDO_INI_N(cmd) (((unsigned)(cmd) >> CO_SDO_INI_N_SHIFT) & 3u)

/* ---- segments */
#define CO_SDO_SEG_TOGGLE 0x10u /* t: alternates from 0 with every segment */
#define CO_SDO_SEG_LAST 0x01u   /* c: no more segments */
#define CO_SDO_SEG_N_SHIFT 1u   /* n (bits 3..1): segment bytes that hold no data */
#define CO_SDO_SEG_N(cmd) (((unsigned)(cmd) >> CO_SDO_SEG_N_SHIFT) & 7u)

/* ---- block transfer: the sub-command (bits 1..0) of a frame that is not a segment */
#define CO_SDO_BLK_SUB_MASK 0x03u
#define CO_SDO_BLK_INI 0x00u      /* initiate (request and response) */
#define CO_SDO_BLK_END 0x01u      /* end (request and response) */
#define CO_SDO_BLK_ACK 0x02u      /* a sub-block acknowledged (ackseq, blksize) */
#define CO_SDO_BLK_START 0x03u    /* block upload: the client starts the first sub-block */
#define CO_SDO_BLK_CRC 0x04u      /* initiate: cc / sc, CRC supported */
#define CO_SDO_BLK_SIZE 0x02u     /* initiate: s, the size is given (bytes 4..7) */
#define CO_SDO_BLK_END_N_SHIFT 2u /* end: n (bits 4..2), last segment bytes without data */
#define CO_SDO_BLK_END_N(cmd) (((unsigned)(cmd) >> CO_SDO_BLK_END_N_SHIFT) & 7u)
/* a block segment's byte 0: c (the transfer's last segment) and the sequence number 1..127 */
#define CO_SDO_BLK_LAST 0x80u
#define CO_SDO_BLK_SEQ_MASK 0x7Fu
/* block upload initiate request: protocol switch threshold in byte 5, blksize in byte 4 */

#endif /* CANOLA_SDO_PROTOCOL_H */
