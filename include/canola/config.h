/*
 * canola/config.h -- compile-time sizes of the core, with their defaults.
 *
 * Every bound in the core is one of these numbers, so the worst-case RAM of a
 * node is computable from them (see docs/porting.md). Override any of them
 * with -D, or collect them in a header named by -DCO_CONFIG_FILE="file.h";
 * the folder configs/ holds the combinations CI builds. Function signatures
 * never change with the configuration; struct sizes do, so the library and
 * the application must be built with the same values.
 */
#ifndef CANOLA_CONFIG_H
#define CANOLA_CONFIG_H

#ifdef CO_CONFIG_FILE
#include CO_CONFIG_FILE
#endif

/** Frames that wait while the driver reports busy (priority-ordered). 1..255. */
#ifndef CO_TX_QUEUE_LEN
#define CO_TX_QUEUE_LEN 8
#endif

/** Heartbeat consumer entries (0x1016 sub1..N) a node can monitor. 0..127. */
#ifndef CO_HB_CONSUMERS_MAX
#define CO_HB_CONSUMERS_MAX 8
#endif

/** Remote nodes a master can node-guard at once. 0..127. */
#ifndef CO_GUARD_WATCH_MAX
#define CO_GUARD_WATCH_MAX 4
#endif

/** SDO server channels: 0x1200 + i (channel 0 is the default server). 0..128. */
#ifndef CO_SDO_SERVERS_MAX
#define CO_SDO_SERVERS_MAX 1
#endif

/** SDO client channels: 0x1280 + i. 0..128. */
#ifndef CO_SDO_CLIENTS_MAX
#define CO_SDO_CLIENTS_MAX 1
#endif

/** Bytes of buffer per SDO channel: the largest value a download collects before storing
 *  it whole (larger values need a write hook), and one block of a block transfer
 *  (block size = min(127, CO_SDO_BUF_SIZE / 7)). 7..65535. */
#ifndef CO_SDO_BUF_SIZE
#define CO_SDO_BUF_SIZE 889
#endif

/** EMCY frames that may wait for the inhibit time (0x1015). 1..255. */
#ifndef CO_EMCY_QUEUE_LEN
#define CO_EMCY_QUEUE_LEN 4
#endif

/** Errors that can be active at once (for the error register 0x1001). 1..255. */
#ifndef CO_EMCY_ACTIVE_MAX
#define CO_EMCY_ACTIVE_MAX 8
#endif

/** EMCY consumer entries (0x1028 sub1..N). 0..127. */
#ifndef CO_EMCY_CONSUMERS_MAX
#define CO_EMCY_CONSUMERS_MAX 8
#endif

/** RPDOs and TPDOs a node handles (0x1400.., 0x1800..). 0..256. */
#ifndef CO_RPDO_MAX
#define CO_RPDO_MAX 4
#endif
#ifndef CO_TPDO_MAX
#define CO_TPDO_MAX 4
#endif

/** Mapping entries per PDO (CiA 301 allows up to 64; 8 covers byte-sized entries). */
#ifndef CO_PDO_MAP_MAX
#define CO_PDO_MAP_MAX 8
#endif

/** Longest value (bytes) stored by 0x1010; longer ones are not stored. 1..255. */
#ifndef CO_STORE_VALUE_MAX
#define CO_STORE_VALUE_MAX 64
#endif

/** LSS (CiA 305, canola/lss.h): the slave (every node answers on 0x7E5) and the master.
 *  0 leaves them out of the build. */
#ifndef CO_LSS_SLAVE
#define CO_LSS_SLAVE 1
#endif
#ifndef CO_LSS_MASTER
#define CO_LSS_MASTER 1
#endif

/** The CANopen manager (CiA 302-2, canola/manager.h). 0 leaves it out of the build. */
#ifndef CO_MANAGER
#define CO_MANAGER 1
#endif

/** Receive routes (COB-IDs the node listens to): NMT, own guarding RTR, one per
 *  heartbeat consumer and guarded node, room for the other services, and the boot-ups
 *  of every slave a manager watches. */
#ifndef CO_RX_ROUTES_MAX
#define CO_RX_ROUTES_MAX                                                                           \
    (8 + CO_HB_CONSUMERS_MAX + CO_GUARD_WATCH_MAX + CO_SDO_SERVERS_MAX + CO_SDO_CLIENTS_MAX +      \
     CO_EMCY_CONSUMERS_MAX + CO_RPDO_MAX + CO_TPDO_MAX + (CO_MANAGER ? 127 : 0))
#endif

#if (CO_LSS_SLAVE != 0 && CO_LSS_SLAVE != 1) || (CO_LSS_MASTER != 0 && CO_LSS_MASTER != 1)
#error "CO_LSS_SLAVE and CO_LSS_MASTER must be 0 or 1"
#endif
#if CO_MANAGER != 0 && CO_MANAGER != 1
#error "CO_MANAGER must be 0 or 1"
#endif
#if CO_TX_QUEUE_LEN < 1 || CO_TX_QUEUE_LEN > 255
#error "CO_TX_QUEUE_LEN must be 1..255"
#endif
#if CO_HB_CONSUMERS_MAX < 0 || CO_HB_CONSUMERS_MAX > 127
#error "CO_HB_CONSUMERS_MAX must be 0..127"
#endif
#if CO_GUARD_WATCH_MAX < 0 || CO_GUARD_WATCH_MAX > 127
#error "CO_GUARD_WATCH_MAX must be 0..127"
#endif
#if CO_SDO_SERVERS_MAX < 0 || CO_SDO_SERVERS_MAX > 128
#error "CO_SDO_SERVERS_MAX must be 0..128"
#endif
#if CO_SDO_CLIENTS_MAX < 0 || CO_SDO_CLIENTS_MAX > 128
#error "CO_SDO_CLIENTS_MAX must be 0..128"
#endif
#if CO_SDO_BUF_SIZE < 7 || CO_SDO_BUF_SIZE > 65535
#error "CO_SDO_BUF_SIZE must be 7..65535"
#endif
#if CO_EMCY_QUEUE_LEN < 1 || CO_EMCY_QUEUE_LEN > 255
#error "CO_EMCY_QUEUE_LEN must be 1..255"
#endif
#if CO_EMCY_ACTIVE_MAX < 1 || CO_EMCY_ACTIVE_MAX > 255
#error "CO_EMCY_ACTIVE_MAX must be 1..255"
#endif
#if CO_EMCY_CONSUMERS_MAX < 0 || CO_EMCY_CONSUMERS_MAX > 127
#error "CO_EMCY_CONSUMERS_MAX must be 0..127"
#endif
#if CO_RPDO_MAX < 0 || CO_RPDO_MAX > 256 || CO_TPDO_MAX < 0 || CO_TPDO_MAX > 256
#error "CO_RPDO_MAX and CO_TPDO_MAX must be 0..256"
#endif
#if CO_PDO_MAP_MAX < 1 || CO_PDO_MAP_MAX > 64
#error "CO_PDO_MAP_MAX must be 1..64"
#endif
#if CO_STORE_VALUE_MAX < 1 || CO_STORE_VALUE_MAX > 255
#error "CO_STORE_VALUE_MAX must be 1..255"
#endif
#if CO_RX_ROUTES_MAX < 2 || CO_RX_ROUTES_MAX > 1024
#error "CO_RX_ROUTES_MAX must be 2..1024"
#endif

#endif /* CANOLA_CONFIG_H */
