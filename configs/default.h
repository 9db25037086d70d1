/* configs/default.h -- the defaults of canola/config.h, spelled out. */
#define CO_TX_QUEUE_LEN 8
#define CO_HB_CONSUMERS_MAX 8
#define CO_GUARD_WATCH_MAX 4
