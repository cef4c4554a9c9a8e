# Warnings are errors in fmpc's own code. Generated parsers and third-party headers are compiled without them
# (they are SYSTEM includes or get -w), so a newer compiler cannot break the build through code we do not own.
add_library(fmpc_warnings INTERFACE)
target_compile_options(fmpc_warnings INTERFACE
  $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
    -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Woverloaded-virtual -Wnull-dereference
    -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough -Werror>)
