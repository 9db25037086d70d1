/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/counters.h -- the node's counters (co_node_stats_t, canola/node.h) as the core counts
 * them: one statement per event, nothing at all in a build without them (CO_CONFIG_STATS 0,
 * where co_node_t has no stats). Not installed; kernel.h includes it.
 */
#ifndef CANOLA_COUNTERS_H
#define CANOLA_COUNTERS_H

#include "canola/node.h"

#if CO_CONFIG_STATS
#define CO_COUNT_ADD(node, counter, n) ((void)((node)->stats.counter += (n)))
#else
#define CO_COUNT_ADD(node, counter, n) ((void)(node), (void)(n))
#endif
#define CO_COUNT(node, counter) CO_COUNT_ADD(node, counter, 1u)

#endif /* CANOLA_COUNTERS_H */
