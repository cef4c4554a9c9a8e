# Warnings are errors in fmpc's own code. -Wnull-dereference is left out: at -O2 GCC 12 reports it inside
# inlined std::map code (a false positive seen in Release builds).
# Generated parsers and third-party headers are compiled without them
# (they are SYSTEM includes or get -w), so a newer compiler cannot break the build through code we do not own.
add_library(fmpc_warnings INTERFACE)
target_compile_options(fmpc_warnings INTERFACE
  $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
    -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Woverloaded-virtual
    -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough -Werror>)
