# bounce_embed_shaders(TARGET ROOT FILES...): compiles the GLSL files under ROOT into the binary.
# Each file becomes a raw string in a generated source, keyed by its path relative to ROOT, so an
# installed daemon needs no source tree. Editing a shader re-runs the generator.
set(BOUNCE_EMBED_SCRIPT ${CMAKE_CURRENT_LIST_DIR}/embed_shaders_script.cmake)

function(bounce_embed_shaders target root)
  set(files ${ARGN})
  set(output ${CMAKE_CURRENT_BINARY_DIR}/embedded_shaders.cpp)
  set(list_file ${CMAKE_CURRENT_BINARY_DIR}/embedded_shaders.list)
  file(WRITE ${list_file}.in "")
  foreach(f IN LISTS files)
    file(APPEND ${list_file}.in "${f}\n")
  endforeach()
  configure_file(${list_file}.in ${list_file} COPYONLY)
  list(TRANSFORM files PREPEND ${root}/ OUTPUT_VARIABLE absolute_files)
  add_custom_command(
    OUTPUT ${output}
    COMMAND ${CMAKE_COMMAND} -DROOT=${root} -DLIST=${list_file} -DOUTPUT=${output}
            -P ${BOUNCE_EMBED_SCRIPT}
    DEPENDS ${absolute_files} ${list_file} ${BOUNCE_EMBED_SCRIPT}
    COMMENT "Embedding ${target} shaders"
    VERBATIM)
  add_library(${target} STATIC ${output})
  string(REGEX REPLACE "^bounce_" "" alias_name ${target})
  add_library(bounce::${alias_name} ALIAS ${target})
endfunction()
