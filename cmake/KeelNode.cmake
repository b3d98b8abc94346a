# keel_add_node(): a node binary with keel-node's command line and the components you give it.
#
#   keel_add_node(TARGET my-node
#                 [SOURCES file...]            sources compiled into the binary
#                 [LIBRARIES target...]        libraries it links (components, helpers)
#                 [REGISTER function...]       functions registering components, called in
#                                              order: bool ns::f(keel::tasking::ComponentRegistry&)
#                 [NO_BUILTIN_COMPONENTS]      leave Keel's built-in components out
#                 [VERSION version])           what --version prints (default: PROJECT_VERSION)
#
# The binary is keel-node with other components: the same flags, stdin control lines,
# status lines, trace and exit codes (nodes/cluster/README.md), so keel-cluster runs it
# with `--node-binary`. Its main() is generated: it registers Keel's built-in components
# (unless NO_BUILTIN_COMPONENTS), then each REGISTER function, and calls
# keel::node::node_main() (keel/node/main.hpp). A component name registered twice stops
# the binary at start-up with exit 3, naming the component and who registered it.
#
# Keel's own keel-node is `keel_add_node(TARGET keel-node)`. Shipped in Keel's CMake package:
# after find_package(Keel), the function is there (docs/components.md).
include_guard(GLOBAL)

function(keel_add_node)
  cmake_parse_arguments(ARG "NO_BUILTIN_COMPONENTS" "TARGET;VERSION" "SOURCES;LIBRARIES;REGISTER"
    ${ARGN})
  if(NOT ARG_TARGET)
    message(FATAL_ERROR "keel_add_node: TARGET is required")
  endif()
  if(ARG_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "keel_add_node(${ARG_TARGET}): unknown arguments: ${ARG_UNPARSED_ARGUMENTS}")
  endif()
  if((ARG_SOURCES OR ARG_LIBRARIES) AND NOT ARG_REGISTER)
    message(FATAL_ERROR "keel_add_node(${ARG_TARGET}): SOURCES or LIBRARIES without REGISTER: name "
      "the function that registers their components, e.g. REGISTER my_component::register_components "
      "(bool my_component::register_components(keel::tasking::ComponentRegistry&))")
  endif()
  if(ARG_NO_BUILTIN_COMPONENTS AND NOT ARG_REGISTER)
    message(FATAL_ERROR "keel_add_node(${ARG_TARGET}): NO_BUILTIN_COMPONENTS and no REGISTER: the "
      "binary would run no component")
  endif()
  if(NOT ARG_VERSION)
    set(ARG_VERSION "${PROJECT_VERSION}")
  endif()

  # What the generated main() declares and registers, in order.
  set(KEEL_NODE_INCLUDES "")
  set(KEEL_NODE_DECLARATIONS "")
  set(KEEL_NODE_SETS "")
  if(NOT ARG_NO_BUILTIN_COMPONENTS)
    string(APPEND KEEL_NODE_INCLUDES "#include \"keel/node/components.hpp\"\n")
    string(APPEND KEEL_NODE_SETS
      "        {\"Keel's built-in components\", keel::node::register_node_components},\n")
  endif()
  foreach(function IN LISTS ARG_REGISTER)
    if(NOT function MATCHES "^(::)?([A-Za-z_][A-Za-z0-9_]*::)*[A-Za-z_][A-Za-z0-9_]*$")
      message(FATAL_ERROR "keel_add_node(${ARG_TARGET}): REGISTER ${function}: not a C++ function "
        "name (namespace::function)")
    endif()
    string(REGEX REPLACE "^::" "" qualified "${function}")
    string(REGEX MATCH "[A-Za-z_][A-Za-z0-9_]*$" unqualified "${qualified}")
    string(REGEX REPLACE "::[A-Za-z_][A-Za-z0-9_]*$" "" namespace "${qualified}")
    set(declaration "bool ${unqualified}(keel::tasking::ComponentRegistry& registry);")
    if(namespace STREQUAL qualified)
      string(APPEND KEEL_NODE_DECLARATIONS "${declaration}\n")
    else()
      string(APPEND KEEL_NODE_DECLARATIONS "namespace ${namespace} {\n${declaration}\n}\n")
    endif()
    string(APPEND KEEL_NODE_SETS "        {\"${qualified}\", ::${qualified}},\n")
  endforeach()
  set(KEEL_NODE_TARGET "${ARG_TARGET}")
  set(KEEL_NODE_VERSION "${ARG_VERSION}")
  set(main "${CMAKE_CURRENT_BINARY_DIR}/${ARG_TARGET}.main.cpp")
  configure_file("${CMAKE_CURRENT_FUNCTION_LIST_DIR}/keel_node_main.cpp.in" "${main}" @ONLY)

  add_executable(${ARG_TARGET} "${main}" ${ARG_SOURCES})
  target_link_libraries(${ARG_TARGET} PRIVATE Keel::node_main ${ARG_LIBRARIES})
  if(NOT ARG_NO_BUILTIN_COMPONENTS)
    target_link_libraries(${ARG_TARGET} PRIVATE Keel::node_components)
  endif()
endfunction()

# keel_compile_mission(): a mission YAML proved and compiled into the image a node flies.
#
#   keel_compile_mission(TARGET my-mission        a target that builds the image (in ALL)
#                        MISSION mission.yaml     the mission (relative: to this directory)
#                        OUTPUT mission.json      the image (relative: to the build directory)
#                        [NODE my-node])          check its components against this node binary
#
# Runs `keel-verify compile MISSION -o OUTPUT [--components $<TARGET_FILE:NODE>]` whenever
# the mission (or the node binary) changes; the build fails with the verifier's report when
# the mission is not proved or uses a component the node lacks. keel-verify is looked up on
# PATH, or given with -DKEEL_VERIFY_EXECUTABLE=/path/to/keel-verify (`pip install` of
# Keel's verify/ folder installs it; docs/ci.md).
function(keel_compile_mission)
  cmake_parse_arguments(ARG "" "TARGET;MISSION;OUTPUT;NODE" "" ${ARGN})
  foreach(required TARGET MISSION OUTPUT)
    if(NOT ARG_${required})
      message(FATAL_ERROR "keel_compile_mission: ${required} is required")
    endif()
  endforeach()
  if(ARG_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "keel_compile_mission(${ARG_TARGET}): unknown arguments: "
      "${ARG_UNPARSED_ARGUMENTS}")
  endif()
  find_program(KEEL_VERIFY_EXECUTABLE keel-verify)
  if(NOT KEEL_VERIFY_EXECUTABLE)
    message(FATAL_ERROR "keel_compile_mission(${ARG_TARGET}): keel-verify not found: install "
      "Keel's verifier (pip install KEEL_SOURCE/verify) or configure with "
      "-DKEEL_VERIFY_EXECUTABLE=/path/to/keel-verify")
  endif()
  cmake_path(ABSOLUTE_PATH ARG_MISSION BASE_DIRECTORY "${CMAKE_CURRENT_SOURCE_DIR}")
  cmake_path(ABSOLUTE_PATH ARG_OUTPUT BASE_DIRECTORY "${CMAKE_CURRENT_BINARY_DIR}")
  set(components "")
  set(depends "${ARG_MISSION}")
  if(ARG_NODE)
    set(components --components "$<TARGET_FILE:${ARG_NODE}>")
    list(APPEND depends ${ARG_NODE})
  endif()
  add_custom_command(OUTPUT "${ARG_OUTPUT}"
    COMMAND "${KEEL_VERIFY_EXECUTABLE}" compile "${ARG_MISSION}" -o "${ARG_OUTPUT}" ${components}
    DEPENDS ${depends}
    COMMENT "keel-verify compile ${ARG_MISSION}"
    VERBATIM)
  add_custom_target(${ARG_TARGET} ALL DEPENDS "${ARG_OUTPUT}")
endfunction()
