/* configs/default.h -- the defaults of canola/config.h, spelled out. */
#define CO_TX_QUEUE_LEN 8
#define CO_HB_CONSUMERS_MAX 8
#define CO_GUARD_WATCH_MAX 4
#define CO_CONFIG_SDO_BLOCK 1
#define CO_CONFIG_GUARDING 1
#define CO_CONFIG_TIME 1
#define CO_CONFIG_STORAGE 1
#define CO_CONFIG_REAL_LIMITS 1
#define CO_CONFIG_LSS 1
