/* configs/minimal.h -- the smallest useful device: a short queue, few consumers, no guarding
 * master. */
#define CO_TX_QUEUE_LEN 4
#define CO_HB_CONSUMERS_MAX 1
#define CO_GUARD_WATCH_MAX 0
#define CO_SDO_CLIENTS_MAX 0
#define CO_SDO_BUF_SIZE 32
