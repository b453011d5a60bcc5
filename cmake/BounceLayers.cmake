# Layers the build enforces. Each layer is one static library over one folder; it names the layers
# it may include. bounce_layer_check() adds a build step that scans the folder's sources and
# headers and fails the build on an #include of any other layer, so an upward include (a scene
# header reaching into methods, say) breaks the build rather than the architecture.
#
#   bounce_layer_check(TARGET bounce_scene DIR renderer/scene LAYER renderer/scene
#                      ALLOWS renderer/base)
#
# A layer is named by its folder as includes spell it ("renderer/scene"); "renderer" alone names
# renderer/renderer.hpp, the top of the renderer.
function(bounce_layer_check)
  cmake_parse_arguments(PARSE_ARGV 0 arg "" "TARGET;DIR;LAYER" "ALLOWS;EXCLUDE")
  file(GLOB_RECURSE files CONFIGURE_DEPENDS
    ${PROJECT_SOURCE_DIR}/${arg_DIR}/*.cpp ${PROJECT_SOURCE_DIR}/${arg_DIR}/*.hpp)
  foreach(excluded IN LISTS arg_EXCLUDE)
    list(FILTER files EXCLUDE REGEX "^${PROJECT_SOURCE_DIR}/${excluded}/")
  endforeach()
  set(stamp ${CMAKE_CURRENT_BINARY_DIR}/${arg_TARGET}.layer-checked)
  string(REPLACE ";" "," allows "${arg_LAYER};${arg_ALLOWS}")
  string(REPLACE ";" "," file_list "${files}")
  add_custom_command(OUTPUT ${stamp}
    COMMAND ${CMAKE_COMMAND} -DLAYER=${arg_LAYER} -DALLOWS=${allows} -DFILES=${file_list}
            -DROOT=${PROJECT_SOURCE_DIR} -DSTAMP=${stamp} -P ${PROJECT_SOURCE_DIR}/cmake/check_layer_script.cmake
    DEPENDS ${files} ${PROJECT_SOURCE_DIR}/cmake/check_layer_script.cmake
    COMMENT "Checking the includes of layer ${arg_LAYER}"
    VERBATIM)
  add_custom_target(${arg_TARGET}_layer_check DEPENDS ${stamp})
  add_dependencies(${arg_TARGET} ${arg_TARGET}_layer_check)
endfunction()
