# SPDX-License-Identifier: Apache-2.0
# cmake/CanolaPackage.cmake -- canola as a package (included by the top CMakeLists.txt once
# the core and the ports are defined):
#   1. the configuration header chosen at build time (CANOLA_CONFIG_FILE) on the core target,
#      PUBLIC, so that everything linking the core compiles with the same CO_* values;
#   2. the targets under the names an installed canola gives them (canola::canola,
#      canola::sim, canola::linux), so a firmware's add_subdirectory(canola) and an
#      application's find_package(canola) link the same names;
#   3. cmake --install (CANOLA_INSTALL): headers, static libraries, the CMake package
#      (find_package(canola)), its version file, pkg-config files (canola, canola-sim,
#      canola-linux), and the program canola-node (bin/). The installed canola/config.h is written by the build and holds the
#      configuration the libraries were built with (cmake/CanolaInstalledConfig.cmake).

# ---- 1. The configuration header. A path, absolute or relative to the top source folder.
if(CANOLA_CONFIG_FILE)
  get_filename_component(CANOLA_CONFIG_PATH "${CANOLA_CONFIG_FILE}" ABSOLUTE
                         BASE_DIR "${CMAKE_SOURCE_DIR}")
  if(NOT EXISTS "${CANOLA_CONFIG_PATH}" OR IS_DIRECTORY "${CANOLA_CONFIG_PATH}")
    message(FATAL_ERROR "CANOLA_CONFIG_FILE: no such file: ${CANOLA_CONFIG_FILE} "
                        "(a header path, absolute or relative to ${CMAKE_SOURCE_DIR})")
  endif()
  # Build tree only: an installed core carries its configuration in its canola/config.h.
  target_compile_definitions(canola
                             PUBLIC "$<BUILD_INTERFACE:CO_CONFIG_FILE=\"${CANOLA_CONFIG_PATH}\">")
endif()

# ---- 2. The names of the targets, as installed.
set(CANOLA_PACKAGE_TARGETS canola canola_sim)
add_library(canola::canola ALIAS canola)
add_library(canola::sim ALIAS canola_sim)
set_target_properties(canola_sim PROPERTIES EXPORT_NAME sim)
if(TARGET canola_linux)
  list(APPEND CANOLA_PACKAGE_TARGETS canola_linux)
  add_library(canola::linux ALIAS canola_linux)
  set_target_properties(canola_linux PROPERTIES EXPORT_NAME linux)
endif()

# ---- 3. cmake --install.
option(CANOLA_INSTALL "Install rules: headers, libraries, CMake package, pkg-config files"
       ${CANOLA_TOP_LEVEL})
if(NOT CANOLA_INSTALL)
  return()
endif()
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)
set(CANOLA_CMAKE_DIR "${CMAKE_INSTALL_LIBDIR}/cmake/canola")
set(CANOLA_GENERATED "${PROJECT_BINARY_DIR}/canola-package")

# The installed canola/config.h: the core's configuration header preprocessed with the core's
# own flags and definitions (-dM lists every macro then defined), so that -D options, the
# CANOLA_CONFIG_FILE and the build type's defaults (-Os turns CO_SHORT_PATHS off) all land in
# it as the values the library was compiled with.
if(NOT CMAKE_C_COMPILER_ID MATCHES "GNU|Clang")
  message(FATAL_ERROR "CANOLA_INSTALL needs a GCC or clang compatible compiler (-dM -E); "
                      "configure with -DCANOLA_INSTALL=OFF")
endif()
string(TOUPPER "${CMAKE_BUILD_TYPE}" _canola_build_type)
separate_arguments(_canola_flags UNIX_COMMAND
                   "${CMAKE_C_FLAGS} ${CMAKE_C_FLAGS_${_canola_build_type}}")
if(CMAKE_C_COMPILER_TARGET)
  list(APPEND _canola_flags "--target=${CMAKE_C_COMPILER_TARGET}")
endif()
set(_canola_defs "$<TARGET_PROPERTY:canola,COMPILE_DEFINITIONS>")
add_custom_command(
  OUTPUT "${CANOLA_GENERATED}/include/canola/config.h"
  COMMAND "${CMAKE_C_COMPILER}" ${_canola_flags} "$<TARGET_PROPERTY:canola,COMPILE_OPTIONS>"
          "$<$<BOOL:${_canola_defs}>:-D$<JOIN:${_canola_defs},;-D>>"
          -dM -E -x c "${PROJECT_SOURCE_DIR}/include/canola/config.h"
          -o "${CANOLA_GENERATED}/config-macros.txt"
  COMMAND "${CMAKE_COMMAND}" "-DMACROS=${CANOLA_GENERATED}/config-macros.txt"
          "-DSOURCE=${PROJECT_SOURCE_DIR}/include/canola/config.h"
          "-DCHOSEN=${CANOLA_CONFIG_FILE}" "-DOUT=${CANOLA_GENERATED}/include/canola/config.h"
          -P "${CMAKE_CURRENT_LIST_DIR}/CanolaInstalledConfig.cmake"
  DEPENDS "${PROJECT_SOURCE_DIR}/include/canola/config.h" ${CANOLA_CONFIG_PATH}
          "${CMAKE_CURRENT_LIST_DIR}/CanolaInstalledConfig.cmake"
  COMMAND_EXPAND_LISTS VERBATIM
  COMMENT "canola: the configuration of the installed canola/config.h")
add_custom_target(canola_installed_config ALL
                  DEPENDS "${CANOLA_GENERATED}/include/canola/config.h")

# Headers: the core's (its config.h the generated one above), the simulated bus's, and the
# Linux port's where it is built. All under canola/, as in the source tree.
install(DIRECTORY include/canola DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}"
        FILES_MATCHING PATTERN "*.h" PATTERN "config.h" EXCLUDE)
install(FILES "${CANOLA_GENERATED}/include/canola/config.h"
        DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}/canola")
install(DIRECTORY port/sim/canola DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}"
        FILES_MATCHING PATTERN "*.h")
if(TARGET canola_linux)
  install(DIRECTORY port/linux/canola DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}"
          FILES_MATCHING PATTERN "*.h")
endif()

# Libraries and the CMake package: find_package(canola [COMPONENTS sim linux]).
install(TARGETS ${CANOLA_PACKAGE_TARGETS} EXPORT canolaTargets
        ARCHIVE DESTINATION "${CMAKE_INSTALL_LIBDIR}"
        LIBRARY DESTINATION "${CMAKE_INSTALL_LIBDIR}"
        INCLUDES DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}")
install(EXPORT canolaTargets NAMESPACE canola:: DESTINATION "${CANOLA_CMAKE_DIR}")
configure_package_config_file(cmake/canolaConfig.cmake.in
                              "${CANOLA_GENERATED}/canolaConfig.cmake"
                              INSTALL_DESTINATION "${CANOLA_CMAKE_DIR}")
# 0.x: a minor version may change the API; from 1.0 on, SameMajorVersion.
write_basic_package_version_file("${CANOLA_GENERATED}/canolaConfigVersion.cmake"
                                 COMPATIBILITY SameMinorVersion)
install(FILES "${CANOLA_GENERATED}/canolaConfig.cmake"
              "${CANOLA_GENERATED}/canolaConfigVersion.cmake"
        DESTINATION "${CANOLA_CMAKE_DIR}")
# canola-node, the example device as a Linux program (the README runs it).
if(TARGET canola-node)
  install(TARGETS canola-node RUNTIME DESTINATION "${CMAKE_INSTALL_BINDIR}")
endif()
# The license travels with the libraries (Apache-2.0: LICENSE and NOTICE).
install(FILES LICENSE NOTICE DESTINATION "${CMAKE_INSTALL_DOCDIR}")

# pkg-config: canola (the core), canola-sim and canola-linux (each requiring canola). The
# prefix is found from the .pc file's own place (${pcfiledir}), so an installed tree can
# be moved, or installed with cmake --install --prefix.
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}" OR IS_ABSOLUTE "${CMAKE_INSTALL_INCLUDEDIR}")
  set(CANOLA_PC_PREFIX "${CMAKE_INSTALL_PREFIX}")
  set(CANOLA_PC_LIBDIR "${CMAKE_INSTALL_FULL_LIBDIR}")
  set(CANOLA_PC_INCLUDEDIR "${CMAKE_INSTALL_FULL_INCLUDEDIR}")
else()
  file(RELATIVE_PATH _canola_up "/prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/prefix")
  string(REGEX REPLACE "/$" "" _canola_up "${_canola_up}")
  set(CANOLA_PC_PREFIX "\${pcfiledir}/${_canola_up}")
  set(CANOLA_PC_LIBDIR "\${prefix}/${CMAKE_INSTALL_LIBDIR}")
  set(CANOLA_PC_INCLUDEDIR "\${prefix}/${CMAKE_INSTALL_INCLUDEDIR}")
endif()
# canola_pc(NAME LIBRARY REQUIRES DESCRIPTION): NAME.pc for LIBRARY.
function(canola_pc name library requires description)
  set(CANOLA_PC_NAME "${name}")
  set(CANOLA_PC_LIBRARY "${library}")
  set(CANOLA_PC_REQUIRES "${requires}")
  set(CANOLA_PC_DESCRIPTION "${description}")
  configure_file(cmake/canola.pc.in "${CANOLA_GENERATED}/${name}.pc" @ONLY)
  install(FILES "${CANOLA_GENERATED}/${name}.pc" DESTINATION "${CMAKE_INSTALL_LIBDIR}/pkgconfig")
endfunction()
canola_pc(canola canola "" "CANopen CC stack: the portable core")
canola_pc(canola-sim canola_sim "canola = ${PROJECT_VERSION}"
          "canola's simulated CAN bus (virtual time)")
if(TARGET canola_linux)
  canola_pc(canola-linux canola_linux "canola = ${PROJECT_VERSION}"
            "canola's Linux port: SocketCAN, socketcand, file storage, epoll loop")
endif()
