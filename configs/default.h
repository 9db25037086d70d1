/* configs/default.h -- the defaults of canola/config.h spelled out, for a device (the bench's
 * "CANopenNode default set"): the master-only parts are off. */
#define CO_TX_QUEUE_LEN 8
#define CO_HB_CONSUMERS_MAX 8
#define CO_GUARD_WATCH_MAX 4
#define CO_CONFIG_SDO_BLOCK 1
#define CO_CONFIG_GUARDING 1
#define CO_CONFIG_TIME 1
#define CO_CONFIG_STORAGE 1
#define CO_CONFIG_REAL_LIMITS 1
/* A device, as CANopenNode's default set: LSS slave yes; LSS master and manager are a master's. */
#define CO_CONFIG_LSS_SLAVE 1
#define CO_CONFIG_LSS_MASTER 0
#define CO_CONFIG_MANAGER 0
