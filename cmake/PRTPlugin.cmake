# prt_add_plugin(<name> KIND <basis|compressor|renderer> SOURCES <files...>
#                [OUTPUT_DIR <dir>] [LIBRARIES <libs...>])
# Builds a PRT plug-in: a shared library with hidden visibility that links the
# framework and lands in the directory the registry scans. Outside the PRT
# tree (find_package(PRT)) it also registers the plug-in's conformance tests
# with ctest, run with PRT_PLUGIN_PATH pointing at the output directory.
function(prt_add_plugin name)
  cmake_parse_arguments(ARG "" "KIND;OUTPUT_DIR" "SOURCES;LIBRARIES" ${ARGN})
  if(NOT ARG_KIND MATCHES "^(basis|compressor|renderer)$")
    message(FATAL_ERROR "prt_add_plugin(${name}): KIND must be basis, compressor or renderer")
  endif()
  if(NOT ARG_OUTPUT_DIR)
    set(ARG_OUTPUT_DIR ${PRT_PLUGIN_DIR})
  endif()
  set(target prt_${ARG_KIND}_${name})
  add_library(${target} MODULE ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE PRT::prt ${ARG_LIBRARIES})
  set_target_properties(${target} PROPERTIES
    PREFIX "libprt-"
    OUTPUT_NAME "${ARG_KIND}-${name}"
    LIBRARY_OUTPUT_DIRECTORY ${ARG_OUTPUT_DIR}
    CXX_VISIBILITY_PRESET hidden
    VISIBILITY_INLINES_HIDDEN ON
    INSTALL_RPATH "$ORIGIN/../..")  # <libdir>/prt/plugins -> <libdir>
  set_property(GLOBAL APPEND PROPERTY PRT_PLUGIN_TARGETS ${target})
  if(TARGET PRT::${ARG_KIND}_conformance)
    add_test(NAME conformance.${ARG_KIND}.${name}
             COMMAND PRT::${ARG_KIND}_conformance --plugin ${name})
    set_tests_properties(conformance.${ARG_KIND}.${name} PROPERTIES
      ENVIRONMENT "PRT_PLUGIN_PATH=${ARG_OUTPUT_DIR}")
  endif()
endfunction()
