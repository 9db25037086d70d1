/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/sim_storage.h -- parameter storage in RAM for the simulated bus: it outlives
 * the nodes that use it, so a test can "power-cycle" a node (initialise and start it
 * again with fresh values) and find its saved parameters back.
 *
 * A save goes to a staging image and replaces the stored one only at commit, as an
 * atomic flash or file backend would; a save of both groups stages the first image and
 * commits both at once. `fail_next_commit` makes the next commit fail (to test a storage
 * error), `commits` counts successful commits.
 */
#ifndef CANOLA_SIM_STORAGE_H
#define CANOLA_SIM_STORAGE_H

#include "canola/storage.h"

#ifndef CO_SIM_STORAGE_SIZE
#define CO_SIM_STORAGE_SIZE 4096
#endif

typedef struct co_sim_image {
    uint8_t data[CO_SIM_STORAGE_SIZE];
    uint32_t len;
    bool valid;
} co_sim_image_t;

typedef struct co_sim_storage {
    co_storage_t api;         /**< give &api to co_node_config_t.storage */
    co_sim_image_t images[2]; /**< communication, application */
    co_sim_image_t staging;
    co_param_group_t staging_group;
    co_sim_image_t staged; /**< the first image of a save of both groups (valid: staged) */
    co_param_group_t staged_group;
    bool fail_next_commit;
    uint32_t commits;
} co_sim_storage_t;

/** Empty storage (nothing saved) with its interface ready in `api`. */
void co_sim_storage_init(co_sim_storage_t *storage);

#endif /* CANOLA_SIM_STORAGE_H */
