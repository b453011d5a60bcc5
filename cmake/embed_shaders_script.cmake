# Script mode: writes OUTPUT, a C++ source defining bounce::gpu::embedded_shader_files().
file(STRINGS ${LIST} files)
set(body "")
foreach(f IN LISTS files)
  file(READ ${ROOT}/${f} text)
  string(FIND "${text}" ")glsl\"" clash)
  if(NOT clash EQUAL -1)
    message(FATAL_ERROR "${f} contains the raw-string delimiter )glsl\"")
  endif()
  string(APPEND body "        {\"${f}\", R\"glsl(${text})glsl\"},\n")
endforeach()
file(WRITE ${OUTPUT}.tmp
"// Generated from shaders/ by cmake/embed_shaders_script.cmake. Do not edit.
#include <map>
#include <string>
#include <string_view>

namespace bounce::gpu {
const std::map<std::string, std::string_view>& embedded_shader_files() {
    static const std::map<std::string, std::string_view> files = {
${body}    };
    return files;
}
}  // namespace bounce::gpu
")
file(COPY_FILE ${OUTPUT}.tmp ${OUTPUT} ONLY_IF_DIFFERENT)
file(REMOVE ${OUTPUT}.tmp)
