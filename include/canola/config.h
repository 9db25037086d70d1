/* SPDX-License-Identifier: Apache-2.0 */
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

/** Heartbeat consumer entries (0x1016 sub1..N) a node can monitor. 0..127. 0 leaves the
 *  heartbeat consumer out of the build (src/hb_consumer.c): 0x1016 is then a plain entry
 *  of the dictionary (any number of sub-indices, no checks, no effect), no heartbeat of
 *  another node is routed, co_hb_remote_state answers 0xFF and boot_time_ms is ignored. */
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
 *  it whole (larger values go to a write hook, or into a RAM DOMAIN's or string's own
 *  storage up to its size), and one block of a block transfer (block size = min(127,
 *  CO_SDO_BUF_SIZE / 7)). 7..65535. */
#ifndef CO_SDO_BUF_SIZE
#define CO_SDO_BUF_SIZE 889
#endif

/** EMCY frames that may wait for the inhibit time (0x1015). 0..255. 0 leaves the inhibit
 *  time out of the build: every EMCY leaves at once, whatever 0x1015 says (a plain entry
 *  then), and co_emcy_t keeps no queue. */
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
#ifndef CO_CONFIG_LSS_SLAVE
#define CO_CONFIG_LSS_SLAVE 1
#endif
#ifndef CO_CONFIG_LSS_MASTER
#define CO_CONFIG_LSS_MASTER 1
#endif

/** The CANopen manager (CiA 302-2, canola/manager.h). 0 leaves it out of the build. */
#ifndef CO_CONFIG_MANAGER
#define CO_CONFIG_MANAGER 1
#endif

#if (CO_CONFIG_LSS_SLAVE != 0 && CO_CONFIG_LSS_SLAVE != 1) ||                                      \
    (CO_CONFIG_LSS_MASTER != 0 && CO_CONFIG_LSS_MASTER != 1)
#error "CO_CONFIG_LSS_SLAVE and CO_CONFIG_LSS_MASTER must be 0 or 1"
#endif
#if CO_CONFIG_MANAGER != 0 && CO_CONFIG_MANAGER != 1
#error "CO_CONFIG_MANAGER must be 0 or 1"
#endif
/* ---- Feature switches: 1 builds the feature in, 0 leaves it out, so that a device pays
 * (in flash) only for what it uses. A feature left out behaves as a dictionary or
 * configuration without it would: its objects have no effect, its frames are not routed,
 * its API functions return CO_ERR_STATE (or CO_ERR_ARG for an SDO block request). The
 * number of SDO clients is its own switch: CO_SDO_CLIENTS_MAX 0. */

/** SDO block transfer (CiA 301 7.2.4.3.9..): the server answers block requests with abort
 *  0x05040001 without it, and the client refuses CO_SDO_BLOCK; the CRC-16 tables go too. */
#ifndef CO_CONFIG_SDO_BLOCK
#define CO_CONFIG_SDO_BLOCK 1
#endif

/** SDO segmented transfer (CiA 301 7.2.4.3.3..): without it the server is expedited only;
 *  it answers a segmented download with abort 0x05040001 and the upload of a value longer
 *  than 4 bytes with 0x06010000. */
#ifndef CO_CONFIG_SDO_SEGMENTED
#define CO_CONFIG_SDO_SEGMENTED 1
#endif

/** The CRC-16 of SDO block transfers and stored images eight bytes a step (4 KiB of const
 *  tables, about 3 instructions a byte) instead of a nibble a step (32 bytes of table,
 *  about 18). By default where SDO block transfer is built, whose per-byte cost it is (the
 *  bench's block rows); a build without it checks only stored images with the CRC, where
 *  the kilobytes count more than the cycles. */
#ifndef CO_CONFIG_CRC16_FAST
#define CO_CONFIG_CRC16_FAST CO_CONFIG_SDO_BLOCK
#endif

/** Node guarding and life guarding (0x100C, 0x100D, co_guard_watch). Without it the node
 *  does not answer guarding RTRs: heartbeat is the error control protocol. */
#ifndef CO_CONFIG_GUARDING
#define CO_CONFIG_GUARDING 1
#endif

/** TIME producer and consumer (0x1012). */
#ifndef CO_CONFIG_TIME
#define CO_CONFIG_TIME 1
#endif

/** Store and restore parameters (0x1010, 0x1011) through co_node_config_t.storage. Without
 *  it nothing is stored: a write of the save or restore signature is refused with
 *  0x08000020, as by a node given no storage, and 0x1010/0x1011 read as the dictionary
 *  gives them (with it, a node given no storage shows 0 there: no capability). */
#ifndef CO_CONFIG_STORAGE
#define CO_CONFIG_STORAGE 1
#endif

/** The node's counters (co_node_stats_t: frames received, unrouted, gated, malformed; sent,
 *  queued, lost, refused, gated). Without them co_node_t keeps none (36 bytes less) and no
 *  frame path counts: co_node_stats() still links and answers counters that are all zero
 *  and stay zero. Bus events a device must act on come through the callbacks either way
 *  (on_error for a lost or refused frame). */
#ifndef CO_CONFIG_STATS
#define CO_CONFIG_STATS 1
#endif

/** Limits on REAL32/REAL64 entries (double comparisons: soft-float code on MCUs without
 *  an FPU). Without it a dictionary giving a REAL entry limits fails co_od_validate. */
#ifndef CO_CONFIG_REAL_LIMITS
#define CO_CONFIG_REAL_LIMITS 1
#endif

/** PDO timers: the TPDO inhibit time (0x1800+n sub3) and event timer (sub5), and RPDO
 *  deadline monitoring (0x1400+n sub5, EMCY 0x8250). Without them those sub-indices are
 *  plain entries with no effect: an event-driven TPDO is sent on each event at once, and
 *  co_pdo_t keeps no timer state. */
#ifndef CO_CONFIG_PDO_TIMERS
#define CO_CONFIG_PDO_TIMERS 1
#endif

/** PDO re-mapping (the CiA 301 procedure on 0x1600.., 0x1A00..). Without it the mapping is
 *  the dictionary's (read at reset communication); a write to a mapping object is refused
 *  with 0x06010002 (read only), through the network and co_node_set_uint alike. */
#ifndef CO_CONFIG_PDO_DYNAMIC
#define CO_CONFIG_PDO_DYNAMIC 1
#endif

/** Bit-granular PDO mapping: entries of fewer bits than their object, entries at bit
 *  offsets, and dummy entries (data types 0x0001..0x0007) in RPDOs. Without it every
 *  mapping entry is a whole object at a byte boundary; a mapping with any other entry is
 *  refused as an unmappable one (0x06040041) and maps nothing when the dictionary has it. */
#ifndef CO_CONFIG_PDO_BIT_MAPPING
#define CO_CONFIG_PDO_BIT_MAPPING 1
#endif

/** Limits on numeric entries (co_od_entry_t.limits: 0x06090031/0x06090032 for a value out
 *  of range). Without them co_od_validate refuses a dictionary giving any limits; a value
 *  is then checked for its length, BOOLEAN values for 0/1, and by the check hook. */
#ifndef CO_CONFIG_OD_LIMITS
#define CO_CONFIG_OD_LIMITS 1
#endif

/** DOMAIN entries kept in RAM (co_od_entry_t.value pointing at a co_od_domain_t). Without
 *  them a DOMAIN entry is served by its hooks alone (value NULL): co_od_validate refuses a
 *  DOMAIN with storage. */
#ifndef CO_CONFIG_OD_DOMAIN
#define CO_CONFIG_OD_DOMAIN 1
#endif

/** UNICODE_STRING entries (16-bit code units). Without them co_od_validate refuses a
 *  dictionary holding one. */
#ifndef CO_CONFIG_OD_UNICODE
#define CO_CONFIG_OD_UNICODE 1
#endif

/** The compact form of the dictionary (canola/od.h): 6-byte entries without pointers (the
 *  value at an offset into one values struct; type, attributes and side table position a
 *  row shared by the entries alike; the size from the type or a side table),
 *  power-on values as one image without zeros (co_od_tables_t.defaults), limits in a
 *  table of their own, no hooks, and no key array (a look-up
 *  compares the entries themselves). The form canola.odgen's dictionaries
 *  are smallest in (they compile in both); hand-written tables with hooks need the
 *  general form (0). */
#ifndef CO_CONFIG_OD_COMPACT
#define CO_CONFIG_OD_COMPACT 0
#endif

/** Look-ups through the dictionary's hash (co_od_t.hash, when a dictionary has one: about
 *  25 instructions a look-up instead of the bisection's 70, for 2 bytes a slot of the
 *  dictionary's and about 100 bytes of code). By default in the general form (hand-written
 *  tables, the Python package's run-time dictionaries); not in the compact form, the
 *  firmware's, whose bisection needs neither (canola.odgen leaves the hash out too). */
#ifndef CO_CONFIG_OD_HASH
#define CO_CONFIG_OD_HASH (!CO_CONFIG_OD_COMPACT)
#endif

/** Run-time validation of the dictionary (co_od_validate, which co_node_init calls: order,
 *  sizes, storage, side tables, power-on values, look-up tables, and the features the core
 *  leaves out). Without it co_od_validate only checks that a dictionary is given and trusts
 *  the table as it is, as a generated one can be: canola.odgen's tests run co_od_validate
 *  over every dictionary it generates (its sample and the EDS corpus, in both forms), and a
 *  generated dictionary using a feature the core leaves out (limits, DOMAIN values in RAM,
 *  UNICODE_STRING, types wider than 32 bits) fails to compile instead. Keep it for tables
 *  written by hand. Values written at run time (SDO, PDO, the API) are checked either way:
 *  length, BOOLEAN 0/1, limits, access. */
#ifndef CO_CONFIG_OD_VALIDATE
#define CO_CONFIG_OD_VALIDATE 1
#endif

/** Dictionary types wider than 32 bits: INTEGER40..64, UNSIGNED40..64 and REAL64. Without
 *  them co_od_validate refuses a dictionary holding one, and the dictionary's arithmetic is
 *  32-bit (no 64-bit helpers on a 32-bit MCU); the API keeps its uint64_t values. */
#ifndef CO_CONFIG_OD_64BIT
#define CO_CONFIG_OD_64BIT 1
#endif

/** SYNC producer (0x1005 bit 30, 0x1006). Without it the node consumes SYNC only: bit 30
 *  and 0x1006 have no effect (0x1019 is still the counter the consumer expects). */
#ifndef CO_CONFIG_SYNC_PRODUCER
#define CO_CONFIG_SYNC_PRODUCER 1
#endif

/** EMCY error history (0x1003). Without it co_emcy_raise records nothing: 0x1003, when the
 *  dictionary has it, is a plain entry with no effect (a write to sub0 clears nothing). */
#ifndef CO_CONFIG_EMCY_HISTORY
#define CO_CONFIG_EMCY_HISTORY 1
#endif

#if (CO_CONFIG_SDO_BLOCK != 0 && CO_CONFIG_SDO_BLOCK != 1) ||                                      \
    (CO_CONFIG_SDO_SEGMENTED != 0 && CO_CONFIG_SDO_SEGMENTED != 1) ||                              \
    (CO_CONFIG_CRC16_FAST != 0 && CO_CONFIG_CRC16_FAST != 1) ||                                    \
    (CO_CONFIG_PDO_TIMERS != 0 && CO_CONFIG_PDO_TIMERS != 1) ||                                    \
    (CO_CONFIG_PDO_DYNAMIC != 0 && CO_CONFIG_PDO_DYNAMIC != 1) ||                                  \
    (CO_CONFIG_PDO_BIT_MAPPING != 0 && CO_CONFIG_PDO_BIT_MAPPING != 1) ||                          \
    (CO_CONFIG_OD_64BIT != 0 && CO_CONFIG_OD_64BIT != 1) ||                                        \
    (CO_CONFIG_SYNC_PRODUCER != 0 && CO_CONFIG_SYNC_PRODUCER != 1) ||                              \
    (CO_CONFIG_EMCY_HISTORY != 0 && CO_CONFIG_EMCY_HISTORY != 1) ||                                \
    (CO_CONFIG_GUARDING != 0 && CO_CONFIG_GUARDING != 1) ||                                        \
    (CO_CONFIG_TIME != 0 && CO_CONFIG_TIME != 1) ||                                                \
    (CO_CONFIG_STORAGE != 0 && CO_CONFIG_STORAGE != 1) ||                                          \
    (CO_CONFIG_STATS != 0 && CO_CONFIG_STATS != 1) ||                                              \
    (CO_CONFIG_REAL_LIMITS != 0 && CO_CONFIG_REAL_LIMITS != 1) ||                                  \
    (CO_CONFIG_OD_LIMITS != 0 && CO_CONFIG_OD_LIMITS != 1) ||                                      \
    (CO_CONFIG_OD_DOMAIN != 0 && CO_CONFIG_OD_DOMAIN != 1) ||                                      \
    (CO_CONFIG_OD_UNICODE != 0 && CO_CONFIG_OD_UNICODE != 1) ||                                    \
    (CO_CONFIG_OD_COMPACT != 0 && CO_CONFIG_OD_COMPACT != 1) ||                                    \
    (CO_CONFIG_OD_HASH != 0 && CO_CONFIG_OD_HASH != 1) ||                                          \
    (CO_CONFIG_OD_VALIDATE != 0 && CO_CONFIG_OD_VALIDATE != 1)
#error "CO_CONFIG_* feature switches are 0 or 1"
#endif
#if CO_CONFIG_REAL_LIMITS && !CO_CONFIG_OD_LIMITS
#error "CO_CONFIG_REAL_LIMITS needs CO_CONFIG_OD_LIMITS"
#endif

/** Receive routes (COB-IDs the node listens to), by default exactly as many as the
 *  configuration can route: NMT and SYNC, the own guarding RTR (CO_CONFIG_GUARDING), TIME
 *  (CO_CONFIG_TIME), the LSS slave and master, one per heartbeat consumer, guarded node,
 *  SDO channel, EMCY consumer entry, RPDO and TPDO (remote requests), and the boot-ups of
 *  every slave a manager watches. A full table drops the routes added last. */
#ifndef CO_RX_ROUTES_MAX
#define CO_RX_ROUTES_MAX                                                                           \
    (2 + CO_CONFIG_GUARDING + CO_CONFIG_TIME + CO_CONFIG_LSS_SLAVE + CO_CONFIG_LSS_MASTER +        \
     CO_HB_CONSUMERS_MAX + CO_GUARD_WATCH_MAX + CO_SDO_SERVERS_MAX + CO_SDO_CLIENTS_MAX +          \
     CO_EMCY_CONSUMERS_MAX + CO_RPDO_MAX + CO_TPDO_MAX + (CO_CONFIG_MANAGER ? 127 : 0))
#endif

#if CO_CONFIG_MANAGER && CO_SDO_CLIENTS_MAX < 1
#error "CO_CONFIG_MANAGER configures its slaves over an SDO client: CO_SDO_CLIENTS_MAX >= 1"
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
#if CO_EMCY_QUEUE_LEN < 0 || CO_EMCY_QUEUE_LEN > 255
#error "CO_EMCY_QUEUE_LEN must be 0..255"
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
