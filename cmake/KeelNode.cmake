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
