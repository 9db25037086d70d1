/* SPDX-License-Identifier: Apache-2.0 */
/*
 * manager_od.c -- the manager's network description read from the master's own object
 * dictionary (0x1F80, 0x1F81, 0x1F84..0x1F88, 0x1F22, 0x1F26, 0x1F27, 0x1016), as a DCF
 * of the master describes it.
 */
#include "canola/manager.h"

static uint32_t get(const co_od_t *od, uint16_t index, uint8_t sub)
{
    uint64_t v = 0;
    (void)co_od_get_uint(od, index, sub, &v);
    return (uint32_t)v;
}

co_err_t co_manager_load_od(const co_od_t *od, co_mgr_slave_t *slaves, uint32_t *nmt_startup)
{
    if (od == NULL || slaves == NULL || nmt_startup == NULL) {
        return CO_ERR_ARG;
    }
    uint64_t startup = 0;
    if (co_od_get_uint(od, 0x1F80, 0, &startup) != CO_OK) {
        return CO_ERR_NOT_FOUND;
    }
    *nmt_startup = (uint32_t)startup;
    for (uint8_t n = 1; n <= 127; n++) {
        co_mgr_slave_t *s = &slaves[n - 1];
        *s = (co_mgr_slave_t){.assignment = get(od, 0x1F81, n),
                              .device_type = get(od, 0x1F84, n),
                              .vendor = get(od, 0x1F85, n),
                              .product = get(od, 0x1F86, n),
                              .revision = get(od, 0x1F87, n),
                              .serial = get(od, 0x1F88, n),
                              .config_date = get(od, 0x1F26, n),
                              .config_time = get(od, 0x1F27, n)};
        /* The concise DCF is used in place: only a DOMAIN kept in RAM has bytes to point at. */
        const co_od_entry_t *dcf = co_od_find(od, 0x1F22, n, NULL);
        if (dcf != NULL && co_od_type(od, dcf) == CO_TYPE_DOMAIN && co_od_value(od, dcf) != NULL) {
            const co_od_domain_t *d = co_od_value(od, dcf);
            if (d->len != 0) {
                s->dcf = d->data;
                s->dcf_len = d->len;
            }
        }
    }
    /* Heartbeat consumer times: the master's own 0x1016 entries that name a slave. */
    uint64_t count = 0;
    (void)co_od_get_uint(od, 0x1016, 0, &count);
    for (uint32_t sub = 1; sub <= count && sub <= 127; sub++) {
        uint32_t v = get(od, 0x1016, (uint8_t)sub);
        uint8_t n = (uint8_t)(v >> 16);
        if (n >= 1 && n <= 127 && (v & 0xFFFFu) != 0) {
            slaves[n - 1].heartbeat_ms = (uint16_t)v;
        }
    }
    return CO_OK;
}
