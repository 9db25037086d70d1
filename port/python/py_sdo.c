/* SPDX-License-Identifier: Apache-2.0 */
/* The completion of an SDO client's transfer, recorded in C (see canola_py.h): a thread
 * that waits for it in C (canola_py_io_wait) sees it without entering Python. */
#include "canola_py.h"

void canola_py_xfer_done(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len)
{
    (void)channel;
    canola_py_xfer_t *x = ctx;
    x->abort = abort;
    x->len = len;
    /* the client sends its own abort just before its completion runs */
    x->by_server = abort != CO_ABORT_NONE && x->dev != NULL &&
                   !canola_py_dev_sent_abort(x->dev, x->request_id);
    x->done = true;
    if (x->dev != NULL && x->dev->link != NULL && x->dev->link->io != NULL) {
        x->dev->link->io->progress = true; /* under the lock: its holder wakes the waiters */
    }
    if (x->notify != NULL) {
        canola_py_sdo_done(x->notify, channel, abort, len);
    }
}
