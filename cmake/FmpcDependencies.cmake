# Every dependency comes from Debian 12 packages (README lists them). Static archives are preferred so that the
# binaries carried to the GPU machine, which has none of these packages, run there unchanged.
find_package(antlr4-runtime 4.9 REQUIRED CONFIG)
find_program(ANTLR4_TOOL antlr4 REQUIRED)
find_package(CLI11 REQUIRED CONFIG)
find_package(yaml-cpp REQUIRED CONFIG)
find_package(Eigen3 REQUIRED CONFIG)
find_package(Threads REQUIRED)

if(TARGET antlr4_static)
  set(FMPC_ANTLR4_LIBRARY antlr4_static)
else()
  set(FMPC_ANTLR4_LIBRARY antlr4_shared)
endif()

# antlr4-runtime's config exports no include directory for its targets.
find_path(FMPC_ANTLR4_INCLUDE_DIR antlr4-runtime.h PATH_SUFFIXES antlr4-runtime REQUIRED)

# zlib deflates the PNG figures of `fmpc plot` (tools/plot/png_image.cpp); static, like the rest.
set(ZLIB_USE_STATIC_LIBS ON)
find_package(ZLIB REQUIRED)
