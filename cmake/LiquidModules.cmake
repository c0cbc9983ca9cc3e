# One CMake target per module of solver/liquid/, linking only the modules it may use.
#
#   liquid_module(NAME DEPENDS <modules...> PUBLIC_LIBS <targets...> PRIVATE_LIBS <targets...>)
#
# makes liquid_NAME (alias liquid::NAME) from solver/liquid/NAME/*.cpp (an INTERFACE target when the
# module is header-only). Two checks make a dependency that is not declared fail the build:
#   - liquid-layer-NAME links the whole archive of the module against its declared modules only,
#     so a call into an undeclared module is an undefined reference;
#   - liquid_layers scans every #include "liquid/<module>/..." of every module (headers too) and
#     fails naming file:line when <module> is not NAME or a declared (transitive) dependency. The
#     same scan fails on a `namespace X {` at column 0 that is not the module's own (liquid::NAME or
#     inside it, a nested `detail`; core: liquid or inside it): docs/architecture.md, "Namespaces".

set_property(GLOBAL PROPERTY LIQUID_MODULES "")

function(liquid_module name)
  cmake_parse_arguments(M "" "" "DEPENDS;PUBLIC_LIBS;PRIVATE_LIBS" ${ARGN})
  set(dir ${CMAKE_CURRENT_SOURCE_DIR}/liquid/${name})
  file(GLOB sources CONFIGURE_DEPENDS ${dir}/*.cpp)
  set(target liquid_${name})
  set(deps "")
  foreach(d ${M_DEPENDS})
    list(APPEND deps liquid_${d})
  endforeach()
  if(sources)
    add_library(${target} STATIC ${sources})
    target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}>
                                                $<INSTALL_INTERFACE:include>)
    target_link_libraries(${target} PUBLIC ${deps} ${M_PUBLIC_LIBS} PRIVATE ${M_PRIVATE_LIBS}
                                           $<BUILD_INTERFACE:liquid_warnings>)
    set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON)
    add_executable(liquid-layer-${name} ${PROJECT_SOURCE_DIR}/cmake/layer_check.cpp)
    target_link_libraries(liquid-layer-${name} PRIVATE "$<LINK_LIBRARY:WHOLE_ARCHIVE,${target}>")
  else()
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}>
                                                   $<INSTALL_INTERFACE:include>)
    target_link_libraries(${target} INTERFACE ${deps} ${M_PUBLIC_LIBS})
  endif()
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name})
  add_library(liquid::${name} ALIAS ${target})
  # The allowed includes: the module itself and the closure of its declared modules.
  set(allowed ${name})
  foreach(d ${M_DEPENDS})
    get_property(closure GLOBAL PROPERTY LIQUID_ALLOWED_${d})
    if(NOT DEFINED closure OR closure STREQUAL "")
      message(FATAL_ERROR "liquid_module(${name}): module '${d}' must be declared before it is used")
    endif()
    list(APPEND allowed ${closure})
  endforeach()
  list(REMOVE_DUPLICATES allowed)
  set_property(GLOBAL PROPERTY LIQUID_ALLOWED_${name} "${allowed}")
  set_property(GLOBAL APPEND PROPERTY LIQUID_MODULES ${name})
endfunction()

# The include scan over every module, re-run whenever a module file changes.
function(liquid_layer_check)
  get_property(modules GLOBAL PROPERTY LIQUID_MODULES)
  set(spec "")
  set(files "")
  foreach(m ${modules})
    get_property(allowed GLOBAL PROPERTY LIQUID_ALLOWED_${m})
    string(REPLACE ";" "," allowed "${allowed}")
    list(APPEND spec "${m}=${allowed}")
    file(GLOB mf CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/liquid/${m}/*)
    list(APPEND files ${mf})
  endforeach()
  # Every folder of solver/liquid/ must be a declared module.
  file(GLOB folders LIST_DIRECTORIES true ${CMAKE_CURRENT_SOURCE_DIR}/liquid/*)
  foreach(f ${folders})
    get_filename_component(n ${f} NAME)
    if(IS_DIRECTORY ${f} AND NOT n IN_LIST modules)
      message(FATAL_ERROR "solver/liquid/${n}/ is not a declared module (liquid_module in solver/CMakeLists.txt)")
    endif()
  endforeach()
  string(REPLACE ";" "|" spec "${spec}")
  set(stamp ${CMAKE_CURRENT_BINARY_DIR}/liquid_layers.stamp)
  add_custom_command(
    OUTPUT ${stamp}
    COMMAND ${CMAKE_COMMAND} "-DSPEC=${spec}" -DROOT=${CMAKE_CURRENT_SOURCE_DIR}/liquid -DSTAMP=${stamp}
            -P ${PROJECT_SOURCE_DIR}/cmake/check_layers.cmake
    DEPENDS ${files} ${PROJECT_SOURCE_DIR}/cmake/check_layers.cmake
    COMMENT "Checking that every module includes only the modules it declares and uses its own namespace"
    VERBATIM)
  add_custom_target(liquid_layers ALL DEPENDS ${stamp})
endfunction()
