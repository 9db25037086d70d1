/* SPDX-License-Identifier: Apache-2.0 */
/* configs/default.h -- the bench's "CANopenNode default set", as issue 4 defines it word for
 * word: "segmented SDO, heartbeat consumer, EMCY with history, SYNC producer+consumer,
 * TIME, storage, 4+4 PDO with timers", on top of the minimal profile (configs/minimal.h:
 * NMT + heartbeat producer, expedited SDO server, SYNC consumer, EMCY producer). So: the
 * SDO server with expedited and segmented transfer and CANopenNode's default buffer of
 * 32 bytes (values up to 32 bytes, longer ones through a write hook), 8 heartbeat consumer
 * entries, EMCY with history (0x1003) and inhibit time (0x1015), SYNC both ways, TIME,
 * stored parameters, 4 RPDOs and 4 TPDOs with inhibit time, event timer and RPDO deadline,
 * and (as CANopenNode has them) PDO re-mapping and bit-granular mapping. Not in the list,
 * so left out: SDO block transfer, the SDO client, node guarding, the EMCY consumer, LSS,
 * the manager, REAL limits and dictionary types wider than 32 bits. The dictionary keeps
 * integer limits, DOMAIN values in RAM and UNICODE_STRING (switches on by default). Every
 * choice below is a documented switch or size of canola/config.h, each overridable (-D), as
 * the bench's block-transfer rows override two. */
#ifndef CO_TX_QUEUE_LEN
#define CO_TX_QUEUE_LEN 8
#endif
#ifndef CO_HB_CONSUMERS_MAX
#define CO_HB_CONSUMERS_MAX 8 /* CANopenNode's, and its profile's 0x1016 */
#endif
#ifndef CO_GUARD_WATCH_MAX
#define CO_GUARD_WATCH_MAX 0
#endif
#ifndef CO_SDO_CLIENTS_MAX
#define CO_SDO_CLIENTS_MAX 0
#endif
#ifndef CO_SDO_BUF_SIZE
#define CO_SDO_BUF_SIZE 32
#endif
#ifndef CO_EMCY_QUEUE_LEN
#define CO_EMCY_QUEUE_LEN 4
#endif
#ifndef CO_EMCY_CONSUMERS_MAX
#define CO_EMCY_CONSUMERS_MAX 0
#endif
#ifndef CO_CONFIG_SDO_SEGMENTED
#define CO_CONFIG_SDO_SEGMENTED 1
#endif
#ifndef CO_CONFIG_SDO_BLOCK
#define CO_CONFIG_SDO_BLOCK 0
#endif
#ifndef CO_CONFIG_PDO_TIMERS
#define CO_CONFIG_PDO_TIMERS 1
#endif
#ifndef CO_CONFIG_PDO_DYNAMIC
#define CO_CONFIG_PDO_DYNAMIC 1
#endif
#ifndef CO_CONFIG_PDO_BIT_MAPPING
#define CO_CONFIG_PDO_BIT_MAPPING 1
#endif
#ifndef CO_CONFIG_SYNC_PRODUCER
#define CO_CONFIG_SYNC_PRODUCER 1
#endif
#ifndef CO_CONFIG_EMCY_HISTORY
#define CO_CONFIG_EMCY_HISTORY 1
#endif
#ifndef CO_CONFIG_GUARDING
#define CO_CONFIG_GUARDING 0
#endif
#ifndef CO_CONFIG_TIME
#define CO_CONFIG_TIME 1
#endif
#ifndef CO_CONFIG_STORAGE
#define CO_CONFIG_STORAGE 1
#endif
#ifndef CO_CONFIG_REAL_LIMITS
#define CO_CONFIG_REAL_LIMITS 0
#endif
#ifndef CO_CONFIG_OD_64BIT
#define CO_CONFIG_OD_64BIT 0
#endif
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
