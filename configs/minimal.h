/* configs/minimal.h -- the smallest useful device: a short queue, one consumer, no guarding
 * master, an SDO server with a small buffer and no client. */
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
#ifndef CO_LSS_SLAVE
#define CO_LSS_SLAVE 0
#endif
#ifndef CO_LSS_MASTER
#define CO_LSS_MASTER 0
#endif
/* No CANopen manager. */
#ifndef CO_MANAGER
#define CO_MANAGER 0
#endif
