/* SPDX-License-Identifier: Apache-2.0 */
/* tests/packaging/config.h -- the configuration of tests/packaging/c-install: values
 * unlike the defaults, so that a program compiled with the defaults instead of the library's
 * values would disagree with it on the layout of co_node_t. */
#define CO_SDO_BUF_SIZE 123
#define CO_TX_QUEUE_LEN 16
#define CO_RPDO_MAX 2
#define CO_TPDO_MAX 2
#define CO_CONFIG_MANAGER 0
#define CO_CONFIG_LSS_SLAVE 0
#define CO_CONFIG_LSS_MASTER 0
