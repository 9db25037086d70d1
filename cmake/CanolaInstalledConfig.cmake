# SPDX-License-Identifier: Apache-2.0
# cmake/CanolaInstalledConfig.cmake -- writes the installed canola/config.h (a script:
# cmake -DMACROS=... -DSOURCE=... -DCHOSEN=... -DOUT=... -P this file; see CanolaPackage.cmake).
#   MACROS  the compiler's -dM -E listing of the source tree's canola/config.h, preprocessed
#           with the core's flags and definitions: every CO_* value the core was built with
#   SOURCE  the source tree's canola/config.h: its "#ifndef CO_..." lines name the settings
#   CHOSEN  CANOLA_CONFIG_FILE as given (named in the header's comment; may be empty)
#   OUT     the header to write
#
# The header defines each value as the library has it. A program that sets a setting to
# another value (with -D, or in a CO_CONFIG_FILE of its own) stops with an #error naming
# it: struct sizes follow these values, so a program and a library built with different
# ones would disagree on the layout of co_node_t.
cmake_minimum_required(VERSION 3.16)

file(STRINGS "${SOURCE}" _settings REGEX "^#ifndef CO_[A-Z0-9_]+$")
list(TRANSFORM _settings REPLACE "^#ifndef " "")
file(STRINGS "${MACROS}" _defines REGEX "^#define CO_[A-Z0-9_]+ ")
list(SORT _defines)

set(_values "")
set(_checks "")
set(_resolved "")
foreach(_line IN LISTS _defines)
  if(NOT _line MATCHES "^#define (CO_[A-Z0-9_]+) (.*)$")
    continue()
  endif()
  set(_name "${CMAKE_MATCH_1}")
  set(_value "${CMAKE_MATCH_2}")
  if(_name STREQUAL "CO_CONFIG_FILE")
    continue()
  endif()
  string(APPEND _values "#ifndef ${_name}\n#define ${_name} ${_value}\n#endif\n")
  # Checked once every value is defined: some are expressions of others.
  if(_name IN_LIST _settings)
    list(APPEND _resolved "${_name}")
    string(APPEND _checks
           "#if (${_name}) != (${_value})\n"
           "#error \"${_name} differs from the value this canola was built with: ${_value}\"\n"
           "#endif\n")
  endif()
endforeach()

# Every setting must have been resolved: a listing without them is not the compiler's -dM.
foreach(_name IN LISTS _settings)
  if(NOT _name IN_LIST _resolved)
    message(FATAL_ERROR "${MACROS}: no value for ${_name} (not a -dM listing of ${SOURCE}?)")
  endif()
endforeach()

if(CHOSEN)
  set(_chosen "CANOLA_CONFIG_FILE ${CHOSEN}")
else()
  set(_chosen "no CANOLA_CONFIG_FILE: the defaults")
endif()
file(WRITE "${OUT}.tmp"
"/*
 * canola/config.h -- the configuration this installed canola was built with.
 * Built with: ${_chosen}.
 *
 * Written by canola's build (cmake/CanolaInstalledConfig.cmake): every value as the library
 * was compiled, from its configuration header, -D options and the defaults of the source
 * tree's canola/config.h (where each setting is documented). Struct sizes follow these
 * values, so a program must use them as they are: one that sets a setting to another value
 * (with -D, or in a CO_CONFIG_FILE of its own) stops with an #error naming it. For other
 * values, build and install canola with them.
 */
#ifndef CANOLA_CONFIG_H
#define CANOLA_CONFIG_H

#ifdef CO_CONFIG_FILE
#include CO_CONFIG_FILE
#endif

/* The library's values (where the program sets none) */
${_values}
/* A program's own values must be the library's */
${_checks}
#endif /* CANOLA_CONFIG_H */
")
# Replaced only when it changed: programs built against the header are not rebuilt for nothing.
execute_process(COMMAND "${CMAKE_COMMAND}" -E copy_if_different "${OUT}.tmp" "${OUT}")
file(REMOVE "${OUT}.tmp")
