# Script mode: writes OUTPUT, a C++ source defining `std::string_view NAMESPACE::FUNCTION()` that
# returns the text of INPUT (the viewer page), so an installed daemon needs no source tree.
file(READ ${INPUT} text)
string(FIND "${text}" ")embedded\"" clash)
if(NOT clash EQUAL -1)
  message(FATAL_ERROR "${INPUT} contains the raw-string delimiter )embedded\"")
endif()
file(WRITE ${OUTPUT}.tmp
"// Generated from ${INPUT} by cmake/embed_text_script.cmake. Do not edit.
#include <string_view>

namespace ${NAMESPACE} {
std::string_view ${FUNCTION}() {
    static constexpr std::string_view text = R\"embedded(${text})embedded\";
    return text;
}
}  // namespace ${NAMESPACE}
")
file(COPY_FILE ${OUTPUT}.tmp ${OUTPUT} ONLY_IF_DIFFERENT)
file(REMOVE ${OUTPUT}.tmp)
