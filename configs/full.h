/* SPDX-License-Identifier: Apache-2.0 */
/* configs/full.h -- a master watching a full network: every table at its maximum. */
#define CO_TX_QUEUE_LEN 255
#define CO_HB_CONSUMERS_MAX 127
#define CO_GUARD_WATCH_MAX 127
