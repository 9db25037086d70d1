/* SPDX-License-Identifier: Apache-2.0 */
/*
 * manager_dcf.c -- the concise DCF format (0x1F22) and the texts of the manager's
 * reports.
 */
#include "canola/manager.h"

#define DCF_HEADER 7u /* index u16, sub u8, size u32 */

co_err_t co_dcf_check(const uint8_t *dcf, uint32_t len)
{
    if (dcf == NULL || len < 4) {
        return CO_ERR_CONFIG;
    }
    uint32_t count = co_get_u32(dcf);
    uint32_t off = 4;
    for (uint32_t i = 0; i < count; i++) {
        if (len - off < DCF_HEADER) {
            return CO_ERR_CONFIG;
        }
        uint32_t size = co_get_u32(dcf + off + 3);
        off += DCF_HEADER;
        if (len - off < size) {
            return CO_ERR_CONFIG;
        }
        off += size;
    }
    return off == len ? CO_OK : CO_ERR_CONFIG;
}

co_err_t co_dcf_put(uint8_t *buf, uint32_t cap, uint32_t *off, uint16_t index, uint8_t sub,
                    const uint8_t *data, uint32_t size)
{
    if (buf == NULL || off == NULL || (data == NULL && size != 0)) {
        return CO_ERR_ARG;
    }
    if (*off == 0) {
        if (cap < 4) {
            return CO_ERR_FULL;
        }
        co_put_u32(buf, 0);
        *off = 4;
    }
    if (*off > cap || cap - *off < DCF_HEADER || cap - *off - DCF_HEADER < size) {
        return CO_ERR_FULL;
    }
    uint8_t *p = buf + *off;
    co_put_u16(p, index);
    p[2] = sub;
    co_put_u32(p + 3, size);
    for (uint32_t i = 0; i < size; i++) {
        p[DCF_HEADER + i] = data[i];
    }
    *off += DCF_HEADER + size;
    co_put_u32(buf, co_get_u32(buf) + 1);
    return CO_OK;
}

const char *co_boot_reason_text(uint8_t reason)
{
    switch (reason) {
    case CO_BOOT_OK:
        return "";
    case CO_BOOT_NOT_LISTED:
        return "A: not in the network list";
    case CO_BOOT_NO_ANSWER:
        return "B: no answer to the read of the device type";
    case CO_BOOT_DEVICE_TYPE:
        return "C: device type does not match";
    case CO_BOOT_VENDOR:
        return "D: vendor-ID does not match";
    case CO_BOOT_HEARTBEAT:
        return "E: heartbeat lost";
    case CO_BOOT_GUARDING:
        return "F: no answer to node guarding";
    case CO_BOOT_CONFIG:
        return "J: configuration download failed";
    case CO_BOOT_HEARTBEAT_START:
        return "K: no heartbeat when error control started";
    case CO_BOOT_WAS_OPERATIONAL:
        return "L: the slave was operational already";
    case CO_BOOT_PRODUCT:
        return "M: product code does not match";
    case CO_BOOT_REVISION:
        return "N: revision number does not match";
    case CO_BOOT_SERIAL:
        return "O: serial number does not match";
    default:
        return "unknown reason";
    }
}

const char *co_mgr_event_name(uint8_t kind)
{
    switch (kind) {
    case CO_MGR_BOOTED:
        return "booted";
    case CO_MGR_STARTED:
        return "started";
    case CO_MGR_FAILED:
        return "failed";
    case CO_MGR_LOST:
        return "lost";
    case CO_MGR_NETWORK_STARTED:
        return "network started";
    case CO_MGR_NETWORK_HALTED:
        return "network halted";
    default:
        return "unknown";
    }
}
