# bounce::warnings: the warning set every first-party target compiles with.
add_library(bounce_warnings INTERFACE)
add_library(bounce::warnings ALIAS bounce_warnings)
target_compile_options(bounce_warnings INTERFACE
  $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
    -Wcast-align -Woverloaded-virtual -Wnull-dereference -Wno-missing-field-initializers>)
