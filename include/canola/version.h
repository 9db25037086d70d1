/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/version.h -- canola's version: the one place it is written. CMake's project version
 * (and so the CMake package and the pkg-config files) and the Python package's version are
 * read from here; python/tests/test_version.py checks that every place agrees.
 */
#ifndef CANOLA_VERSION_H
#define CANOLA_VERSION_H

#define CANOLA_VERSION_MAJOR 0
#define CANOLA_VERSION_MINOR 1
#define CANOLA_VERSION_PATCH 0
#define CANOLA_VERSION "0.1.0" /**< MAJOR.MINOR.PATCH of the three above */

#endif /* CANOLA_VERSION_H */
