# What `cmake --install` puts in the prefix, so a team builds its own components and node
# binaries against Keel without its source tree (docs/components.md):
#
#   include/keel/core/...       the core's headers, included as "core/tasking/component.hpp"
#   include/keel/node/...       keel-node's entry point and built-in components
#                               ("keel/node/main.hpp", "keel/node/components.hpp")
#   include/keel/eo/...         the earth-observation components' headers (KEEL_WITH_EO)
#   lib/libkeel_*.a             the static libraries
#   bin/                        keel-node, keel-sim, keel-mission
#   lib/cmake/Keel/             KeelConfig.cmake and its version file, KeelTargets.cmake
#                               (the libraries as Keel::<name>), KeelNode.cmake (keel_add_node)
#
# find_package(Keel 0.2 REQUIRED) accepts any 0.2.x: before 1.0.0 a minor version may change
# a contract (CHANGELOG.md), so the version file asks for the same minor version.
#
# The parts' CMakeLists.txt name their include directories as paths in the tree; here each
# exported library's paths become build-only and the installed include directories are
# added, so the parts stay as they are.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(KEEL_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/Keel")

# Library target -> its name in the package (Keel::<name>).
set(KEEL_EXPORTED_LIBRARIES
  keel_mission=mission
  keel_codec=codec
  keel_placement=placement
  keel_fsm=fsm
  keel_tasking=tasking
  keel_net=net
  keel_net_dds=net_dds
  keel_node_driver=node_driver
  keel_node=node
  keel_node_main=node_main
  keel_node_components=node_components)
set(KEEL_HEADER_FOLDERS nodes/keel-node/include)
if(KEEL_WITH_EO)
  list(APPEND KEEL_EXPORTED_LIBRARIES
    keel_eo_codec=eo_codec
    keel_sensor=sensor
    keel_acca=acca
    keel_aocs=aocs
    keel_sink=sink
    keel_eo_components=eo_components)
  list(APPEND KEEL_HEADER_FOLDERS nodes/sensor/include nodes/acca/include nodes/aocs/include
    nodes/sink/include nodes/components/include)
endif()

# The include directories `target` gives its users: its paths in the tree while building,
# include/keel (for "core/...") and include (for "keel/...") once installed.
function(keel_export_include_directories target)
  get_target_property(directories ${target} INTERFACE_INCLUDE_DIRECTORIES)
  if(NOT directories)
    set(directories "")
  endif()
  set(exported "")
  foreach(directory IN LISTS directories)
    if(directory MATCHES "^\\$<")
      list(APPEND exported "${directory}")
    else()
      list(APPEND exported "$<BUILD_INTERFACE:${directory}>")
    endif()
  endforeach()
  list(APPEND exported
    "$<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/keel>"
    "$<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>")
  set_property(TARGET ${target} PROPERTY INTERFACE_INCLUDE_DIRECTORIES "${exported}")
endfunction()

set(KEEL_INSTALLED_LIBRARIES "")
foreach(entry IN LISTS KEEL_EXPORTED_LIBRARIES)
  string(REPLACE "=" ";" pair "${entry}")
  list(GET pair 0 target)
  list(GET pair 1 export_name)
  if(NOT TARGET ${target})
    message(FATAL_ERROR "KeelInstall.cmake: the library ${target} is not defined")
  endif()
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${export_name})
  keel_export_include_directories(${target})
  # Keel's headers are C++20: a user's target that includes them is compiled as C++20.
  target_compile_features(${target} INTERFACE cxx_std_20)
  list(APPEND KEEL_INSTALLED_LIBRARIES ${target})
endforeach()
# The libraries link these privately (their usage requirements do not reach users, but a
# static library's link interface names them): Keel::warnings (Keel's warning flags, for a
# team that wants them) and Keel::version (KEEL_VERSION, the string of the VERSION file).
set_target_properties(keel_warnings PROPERTIES EXPORT_NAME warnings)
set_target_properties(keel_version PROPERTIES EXPORT_NAME version)

install(TARGETS ${KEEL_INSTALLED_LIBRARIES} keel_warnings keel_version
  EXPORT KeelTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
# keel-place: keel-verify check and compile run it to prove a phase placed online
# (found on PATH where no build directory is named).
foreach(program keel-node keel-sim keel-mission keel-place)
  if(TARGET ${program})
    install(TARGETS ${program} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  endif()
endforeach()

# Headers: the core's public headers (not its tests, benchmarks or tools) under
# include/keel/core, the other parts' include/ folders (keel/...) under include.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/core/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/keel/core
  FILES_MATCHING PATTERN "*.hpp"
  PATTERN "tests" EXCLUDE
  PATTERN "bench" EXCLUDE
  PATTERN "tools" EXCLUDE
  # keel_net_sampled (the real-time switch benchmark's library) is not installed.
  PATTERN "sampled.hpp" EXCLUDE)
foreach(folder IN LISTS KEEL_HEADER_FOLDERS)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${folder}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
    FILES_MATCHING PATTERN "*.hpp")
endforeach()

install(EXPORT KeelTargets
  NAMESPACE Keel::
  FILE KeelTargets.cmake
  DESTINATION ${KEEL_INSTALL_CMAKEDIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/KeelConfig.cmake.in
  ${PROJECT_BINARY_DIR}/KeelConfig.cmake
  INSTALL_DESTINATION ${KEEL_INSTALL_CMAKEDIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/KeelConfigVersion.cmake
  VERSION ${PROJECT_VERSION}
  COMPATIBILITY SameMinorVersion)
set(KEEL_PACKAGE_FILES
  ${PROJECT_BINARY_DIR}/KeelConfig.cmake
  ${PROJECT_BINARY_DIR}/KeelConfigVersion.cmake
  ${PROJECT_SOURCE_DIR}/cmake/KeelNode.cmake
  ${PROJECT_SOURCE_DIR}/cmake/keel_node_main.cpp.in)
if(KEEL_WITH_EO)
  list(APPEND KEEL_PACKAGE_FILES ${PROJECT_SOURCE_DIR}/cmake/FindKeelOpenCV.cmake)
endif()
install(FILES ${KEEL_PACKAGE_FILES} DESTINATION ${KEEL_INSTALL_CMAKEDIR})
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE ${PROJECT_SOURCE_DIR}/CHANGELOG.md
  DESTINATION ${CMAKE_INSTALL_DOCDIR})
