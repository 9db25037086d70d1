/* configs/minimal.h -- the smallest useful device: a short queue, one consumer, no guarding
 * master, an SDO server with a small buffer and no client, no EMCY consumer, and the
 * optional features off (block transfer, guarding, TIME, storage, REAL limits, LSS). */
#ifndef CO_TX_QUEUE_LEN
#define CO_TX_QUEUE_LEN 4
#endif
#ifndef CO_HB_CONSUMERS_MAX
#define CO_HB_CONSUMERS_MAX 1
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
/* A device with a fixed node-ID: no LSS. */
#ifndef CO_CONFIG_LSS_SLAVE
#define CO_CONFIG_LSS_SLAVE 0
#endif
#ifndef CO_CONFIG_LSS_MASTER
#define CO_CONFIG_LSS_MASTER 0
#endif
/* No CANopen manager. */
#ifndef CO_CONFIG_MANAGER
#define CO_CONFIG_MANAGER 0
#endif
#ifndef CO_EMCY_CONSUMERS_MAX
#define CO_EMCY_CONSUMERS_MAX 0 /* it sends EMCY; it does not watch other nodes' */
#endif
/* Features the minimal device leaves out (canola/config.h: feature switches). */
#ifndef CO_CONFIG_SDO_BLOCK
#define CO_CONFIG_SDO_BLOCK 0
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
