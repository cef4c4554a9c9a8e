# Every dependency comes from Debian 12 packages (README lists them). Static archives are preferred so that the
# binaries carried to the GPU machine, which has none of these packages, run there unchanged.
find_package(antlr4-runtime 4.9 REQUIRED CONFIG)
find_program(ANTLR4_TOOL antlr4 REQUIRED)
find_package(CLI11 REQUIRED CONFIG)
find_package(yaml-cpp REQUIRED CONFIG)
find_package(Eigen3 REQUIRED CONFIG)
find_package(Threads REQUIRED)
# JSON (the run summary; runtime/io/json_text.h): header-only.
find_package(nlohmann_json 3 REQUIRED CONFIG)

if(TARGET antlr4_static)
  set(FMPC_ANTLR4_LIBRARY antlr4_static)
else()
  set(FMPC_ANTLR4_LIBRARY antlr4_shared)
endif()

# antlr4-runtime's config exports no include directory for its targets.
find_path(FMPC_ANTLR4_INCLUDE_DIR antlr4-runtime.h PATH_SUFFIXES antlr4-runtime REQUIRED)
# Clang (the fuzzing and sanitizer build) rejects one header the umbrella antlr4-runtime.h pulls in: 4.9's
# misc/InterpreterDataReader.h default-constructs a Vocabulary whose const members clang will not default-initialise.
# fmpc never uses it, so clang builds get a copy of the umbrella header without that line, found first.
set(FMPC_ANTLR4_INCLUDE_DIRS ${FMPC_ANTLR4_INCLUDE_DIR})
if(CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
  file(READ ${FMPC_ANTLR4_INCLUDE_DIR}/antlr4-runtime.h fmpc_antlr4_umbrella)
  string(REPLACE "#include \"misc/InterpreterDataReader.h\"" "" fmpc_antlr4_umbrella "${fmpc_antlr4_umbrella}")
  file(WRITE ${PROJECT_BINARY_DIR}/antlr4-for-clang/antlr4-runtime.h "${fmpc_antlr4_umbrella}")
  set(FMPC_ANTLR4_INCLUDE_DIRS ${PROJECT_BINARY_DIR}/antlr4-for-clang ${FMPC_ANTLR4_INCLUDE_DIR})
endif()

# zlib deflates the PNG figures of `fmpc plot` (tools/plot/png_image.cpp); static, like the rest.
set(ZLIB_USE_STATIC_LIBS ON)
find_package(ZLIB REQUIRED)
