/* SPDX-License-Identifier: Apache-2.0 */
/* configs/minimal.h -- the bench's "minimal" profile, as issue 4 defines it word for word:
 * "NMT + heartbeat, expedited SDO server, 4+4 PDO, SYNC consumer, EMCY producer".
 * Read literally: a heartbeat producer only (no consumer), an SDO server for expedited
 * transfers only (no segmented, no block, no client), 4 RPDOs and 4 TPDOs without timers
 * (no inhibit time, event timer or RPDO deadline), the mapping the dictionary gives (no
 * re-mapping, whole objects only), a SYNC consumer only (no producer), an EMCY producer
 * without error history (0x1003) and without inhibit time (0x1015), no EMCY consumer.
 * Left out as well, being in neither list: node guarding, TIME, stored parameters, LSS,
 * the manager, the node's counters (co_node_stats), and of the dictionary's features limits
 * (REAL or integer), DOMAIN values kept in RAM (of no use to an expedited-only server: a
 * hook-served DOMAIN stays possible), UNICODE_STRING and the types wider than 32 bits.
 * Every choice below is a documented switch or size of canola/config.h. */
#ifndef CO_TX_QUEUE_LEN
#define CO_TX_QUEUE_LEN 4
#endif
#ifndef CO_HB_CONSUMERS_MAX
#define CO_HB_CONSUMERS_MAX 0 /* heartbeat producer only */
#endif
#ifndef CO_GUARD_WATCH_MAX
#define CO_GUARD_WATCH_MAX 0
#endif
#ifndef CO_SDO_CLIENTS_MAX
#define CO_SDO_CLIENTS_MAX 0
#endif
/* Expedited transfers carry their 1..4 bytes in the frame and use no buffer: the smallest
 * size allowed. */
#ifndef CO_SDO_BUF_SIZE
#define CO_SDO_BUF_SIZE 7
#endif
#ifndef CO_CONFIG_SDO_SEGMENTED
#define CO_CONFIG_SDO_SEGMENTED 0
#endif
#ifndef CO_CONFIG_SDO_BLOCK
#define CO_CONFIG_SDO_BLOCK 0
#endif
#ifndef CO_CONFIG_PDO_TIMERS
#define CO_CONFIG_PDO_TIMERS 0
#endif
#ifndef CO_CONFIG_PDO_DYNAMIC
#define CO_CONFIG_PDO_DYNAMIC 0
#endif
#ifndef CO_CONFIG_PDO_BIT_MAPPING
#define CO_CONFIG_PDO_BIT_MAPPING 0
#endif
#ifndef CO_CONFIG_SYNC_PRODUCER
#define CO_CONFIG_SYNC_PRODUCER 0
#endif
#ifndef CO_CONFIG_EMCY_HISTORY
#define CO_CONFIG_EMCY_HISTORY 0
#endif
#ifndef CO_EMCY_QUEUE_LEN
#define CO_EMCY_QUEUE_LEN 0 /* no inhibit time */
#endif
#ifndef CO_EMCY_CONSUMERS_MAX
#define CO_EMCY_CONSUMERS_MAX 0 /* it sends EMCY; it does not watch other nodes' */
#endif
#ifndef CO_CONFIG_GUARDING
#define CO_CONFIG_GUARDING 0
#endif
#ifndef CO_CONFIG_TIME
#define CO_CONFIG_TIME 0
#endif
#ifndef CO_CONFIG_STORAGE
#define CO_CONFIG_STORAGE 0
#endif
#ifndef CO_CONFIG_REAL_LIMITS
#define CO_CONFIG_REAL_LIMITS 0
#endif
#ifndef CO_CONFIG_OD_LIMITS
#define CO_CONFIG_OD_LIMITS 0
#endif
#ifndef CO_CONFIG_OD_DOMAIN
#define CO_CONFIG_OD_DOMAIN 0
#endif
#ifndef CO_CONFIG_OD_UNICODE
#define CO_CONFIG_OD_UNICODE 0
#endif
#ifndef CO_CONFIG_OD_64BIT
#define CO_CONFIG_OD_64BIT 0
#endif
#ifndef CO_CONFIG_STATS
#define CO_CONFIG_STATS 0 /* on_error still reports lost frames */
#endif
/* A device with a fixed node-ID: no LSS; no CANopen manager. */
#ifndef CO_CONFIG_LSS_SLAVE
#define CO_CONFIG_LSS_SLAVE 0
#endif
#ifndef CO_CONFIG_LSS_MASTER
#define CO_CONFIG_LSS_MASTER 0
#endif
#ifndef CO_CONFIG_MANAGER
#define CO_CONFIG_MANAGER 0
#endif
/* A compact dictionary is generated (canola.odgen): its tests validate every dictionary it
 * generates, and one using a feature left out above fails to compile. The core trusts it
 * (no co_od_validate code); a hand-written general-form table is still validated. */
#ifndef CO_CONFIG_OD_VALIDATE
#define CO_CONFIG_OD_VALIDATE (!CO_CONFIG_OD_COMPACT)
#endif
