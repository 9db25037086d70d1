/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/canola.h -- the whole public API of the canola core in one include.
 * See each header for its manual; docs/architecture.md for the picture.
 */
#ifndef CANOLA_CANOLA_H
#define CANOLA_CANOLA_H

#include "canola/config.h"
#include "canola/emcy.h"
#include "canola/errctl.h"
#include "canola/lss.h"
#include "canola/manager.h"
#include "canola/nmt.h"
#include "canola/node.h"
#include "canola/od.h"
#include "canola/pdo.h"
#include "canola/program.h"
#include "canola/sdo.h"
#include "canola/storage.h"
#include "canola/sync.h"
#include "canola/time.h"
#include "canola/types.h"
#include "canola/version.h"

#endif /* CANOLA_CANOLA_H */
