# FMPC_GPU_ONLY=ON: the build for the GPU machine, which has CMake, nvcc and the CUDA libraries but none of the
# Debian packages the full build needs (antlr4, yaml-cpp, CLI11, Catch2, Eigen, fuzzylite). It builds only
#   fmpc_runtime     kernels/*_step.cu and reductions.cu, runtime/gpu, and the CPU reference it is compared with: meshes,
#                    springs, integrators, the model builder, runtime/io/memory_limit.cpp (the memory limits
#                    the mesh generator checks), runtime/io/input_file.cpp (the bench's --liver reads a mesh
#                    file), diagnostics/diagnostic.cpp and
#                    diagnostics/number_format.cpp;
#   fmpc_gpu_tests   tests/gpu (its own runner, no Catch2), ctest label `gpu`;
#   fmpc_sim_bench   bench/sim;
#   fmpc_setup_bench bench/setup (host setup: seconds per phase, peak memory per spring);
#   fmpc_frame_bench bench/setup (a VTU frame), only where zlib's headers are found.
# Eigen (header-only, used by the CPU implicit Euler) is not searched for on the system: its headers come from
# FMPC_EIGEN_INCLUDE_DIR, which `bench/run_gpu.sh --prepare` fills from /usr/include/eigen3 on the build machine
# (build-gpu-carry/eigen3, carried to the GPU machine).
set(FMPC_CUDA ON)
include(${PROJECT_SOURCE_DIR}/cmake/FmpcWarnings.cmake)
include(${PROJECT_SOURCE_DIR}/cmake/FmpcCuda.cmake)
option(FMPC_GPU_ONLY_WERROR "Warnings are errors in the GPU-only build (off: the GPU machine's compilers may differ)" OFF)
if(NOT FMPC_GPU_ONLY_WERROR)
  target_compile_options(fmpc_warnings INTERFACE $<$<COMPILE_LANGUAGE:CXX>:-Wno-error>)
endif()
find_package(Threads REQUIRED)

set(FMPC_EIGEN_INCLUDE_DIR "${PROJECT_SOURCE_DIR}/build-gpu-carry/eigen3" CACHE PATH
    "Directory holding Eigen/ (copied by bench/run_gpu.sh --prepare)")
if(NOT EXISTS "${FMPC_EIGEN_INCLUDE_DIR}/Eigen/Sparse")
  message(FATAL_ERROR "FMPC_GPU_ONLY: no Eigen headers in ${FMPC_EIGEN_INCLUDE_DIR}; run `bench/run_gpu.sh --prepare` "
                      "on the build machine and carry build-gpu-carry/, or set FMPC_EIGEN_INCLUDE_DIR")
endif()

add_library(fmpc_kernels INTERFACE)
target_include_directories(fmpc_kernels INTERFACE ${PROJECT_SOURCE_DIR})

file(GLOB FMPC_GPU_ONLY_SOURCES CONFIGURE_DEPENDS
  ${PROJECT_SOURCE_DIR}/runtime/mesh/*.cpp
  ${PROJECT_SOURCE_DIR}/runtime/springs/*.cpp
  ${PROJECT_SOURCE_DIR}/runtime/fem/*.cpp
  ${PROJECT_SOURCE_DIR}/runtime/integrate/*.cpp
  ${PROJECT_SOURCE_DIR}/runtime/gpu/*.cpp)
# The VTU frame writer (runtime/io/vtk_xml.cpp, for bench/setup's frame benchmark) when the machine has zlib's
# headers; nothing else needs it here.
find_package(ZLIB)
if(ZLIB_FOUND)
  list(APPEND FMPC_GPU_ONLY_SOURCES ${PROJECT_SOURCE_DIR}/runtime/io/vtk_xml.cpp ${PROJECT_SOURCE_DIR}/runtime/io/atomic_file.cpp)
endif()
add_library(fmpc_runtime STATIC
  ${FMPC_GPU_ONLY_SOURCES}
  ${PROJECT_SOURCE_DIR}/runtime/scene/spring_model_builder.cpp
  ${PROJECT_SOURCE_DIR}/runtime/io/memory_limit.cpp
  ${PROJECT_SOURCE_DIR}/runtime/io/input_file.cpp
  ${PROJECT_SOURCE_DIR}/diagnostics/diagnostic.cpp
  ${PROJECT_SOURCE_DIR}/diagnostics/number_format.cpp
  ${PROJECT_SOURCE_DIR}/kernels/explicit_step.cu
  ${PROJECT_SOURCE_DIR}/kernels/persistent_step.cu
  ${PROJECT_SOURCE_DIR}/kernels/implicit_step.cu
  ${PROJECT_SOURCE_DIR}/kernels/reductions.cu)
target_include_directories(fmpc_runtime PUBLIC ${PROJECT_SOURCE_DIR})
target_include_directories(fmpc_runtime SYSTEM PUBLIC ${FMPC_EIGEN_INCLUDE_DIR})
target_link_libraries(fmpc_runtime PUBLIC fmpc_kernels Threads::Threads CUDA::cudart_static PRIVATE fmpc_warnings)
if(ZLIB_FOUND)
  target_link_libraries(fmpc_runtime PRIVATE ZLIB::ZLIB)
endif()
# As in runtime/CMakeLists.txt: the device must round like the CPU loop (no fused multiply-add contraction).
target_compile_options(fmpc_runtime PRIVATE $<$<COMPILE_LANGUAGE:CUDA>:--fmad=false>)
if(FMPC_GPU_ONLY_WERROR)
  target_compile_options(fmpc_runtime PRIVATE $<$<COMPILE_LANGUAGE:CUDA>:--Werror=all-warnings>)
endif()
target_compile_definitions(fmpc_runtime PUBLIC FMPC_RUNTIME_HAVE_CUDA=1)

enable_testing()
add_subdirectory(${PROJECT_SOURCE_DIR}/tests/gpu ${PROJECT_BINARY_DIR}/tests/gpu)
add_subdirectory(${PROJECT_SOURCE_DIR}/bench/sim ${PROJECT_BINARY_DIR}/bench/sim)
add_subdirectory(${PROJECT_SOURCE_DIR}/bench/setup ${PROJECT_BINARY_DIR}/bench/setup)
