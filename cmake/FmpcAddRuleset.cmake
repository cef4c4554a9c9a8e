# fmpc_add_ruleset(<target> FILE <rules.fis>
#                  [FIX NAME=VALUE...] [VARY NAME[:POINTS]...] [TARGET cpp|cuda|table] [MAX_ERROR e]
#                  [SYSTEM name] [NAMESPACE ns] [OUTPUT_NAME name])
#
# Compiles a rule file with `fmpc compile` at build time into an INTERFACE library <target> whose include
# directory holds the result, regenerated whenever the rule file (or fmpc) changes:
#   TARGET cpp   (default)  <OUTPUT_NAME>.h    the evaluator header (docs/codegen.md)
#   TARGET cuda             <OUTPUT_NAME>.cuh  the same with a __global__ kernel and its launcher
#   TARGET table            <OUTPUT_NAME>.h    the table as C++/CUDA arrays, and <OUTPUT_NAME>.fzt beside it;
#                                              links fmpc::kernels (kernels/table_math.h does the lookup)
# FIX folds inputs in at values, VARY names the inputs that stay (the others vary too, see `fmpc compile`),
# MAX_ERROR is the table's error target in output units. NAMESPACE defaults to the target name, OUTPUT_NAME too.
# The target's properties FMPC_HEADER and FMPC_TABLE_FILE give the generated paths.
#
# Works in fmpc's own build (the `fmpc` target) and from an installed fmpc through find_package(fmpc), which
# defines the imported executable fmpc::fmpc. docs/cmake.md has an example; rulesets/example_project is one.
include_guard(GLOBAL)

function(fmpc_add_ruleset target)
  cmake_parse_arguments(PARSE_ARGV 1 FMPC "" "FILE;TARGET;MAX_ERROR;SYSTEM;NAMESPACE;OUTPUT_NAME" "FIX;VARY")
  set(where "fmpc_add_ruleset(${target})")
  if(FMPC_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "${where}: unknown arguments '${FMPC_UNPARSED_ARGUMENTS}'; the keywords are FILE, FIX, "
                        "VARY, TARGET, MAX_ERROR, SYSTEM, NAMESPACE and OUTPUT_NAME")
  endif()
  if(NOT FMPC_FILE)
    message(FATAL_ERROR "${where}: FILE <rules.fis> is required")
  endif()
  if(NOT FMPC_TARGET)
    set(FMPC_TARGET cpp)
  endif()
  if(NOT FMPC_TARGET MATCHES "^(cpp|cuda|table)$")
    message(FATAL_ERROR "${where}: TARGET must be cpp, cuda or table, not '${FMPC_TARGET}'")
  endif()
  if(DEFINED FMPC_MAX_ERROR AND NOT FMPC_TARGET STREQUAL "table")
    message(FATAL_ERROR "${where}: MAX_ERROR applies to TARGET table only (evaluators are exact to rounding)")
  endif()
  if(TARGET fmpc::fmpc)
    set(fmpc_executable fmpc::fmpc)
  elseif(TARGET fmpc)
    set(fmpc_executable fmpc)
  else()
    message(FATAL_ERROR "${where}: no fmpc executable: call find_package(fmpc) first")
  endif()

  get_filename_component(rule_file "${FMPC_FILE}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
  if(NOT EXISTS "${rule_file}")
    message(FATAL_ERROR "${where}: rule file '${rule_file}' does not exist")
  endif()
  if(NOT FMPC_OUTPUT_NAME)
    set(FMPC_OUTPUT_NAME "${target}")
  endif()
  if(NOT FMPC_NAMESPACE)
    string(MAKE_C_IDENTIFIER "${target}" FMPC_NAMESPACE)
  endif()

  set(output_dir "${CMAKE_CURRENT_BINARY_DIR}/fmpc_rulesets/${target}")
  set(arguments compile "${rule_file}" --target "${FMPC_TARGET}" --namespace "${FMPC_NAMESPACE}")
  foreach(binding IN LISTS FMPC_FIX)
    list(APPEND arguments --fix "${binding}")
  endforeach()
  foreach(input IN LISTS FMPC_VARY)
    list(APPEND arguments --vary "${input}")
  endforeach()
  if(DEFINED FMPC_MAX_ERROR)
    list(APPEND arguments --max-error "${FMPC_MAX_ERROR}")
  endif()
  if(FMPC_SYSTEM)
    list(APPEND arguments --system "${FMPC_SYSTEM}")
  endif()

  if(FMPC_TARGET STREQUAL "cuda")
    set(header "${output_dir}/${FMPC_OUTPUT_NAME}.cuh")
  else()
    set(header "${output_dir}/${FMPC_OUTPUT_NAME}.h")
  endif()
  set(outputs "${header}")
  list(APPEND arguments -o "${header}")
  set(table_file "")
  if(FMPC_TARGET STREQUAL "table")
    set(table_file "${output_dir}/${FMPC_OUTPUT_NAME}.fzt")
    list(APPEND outputs "${table_file}")
    list(APPEND arguments -o "${table_file}")
  endif()

  add_custom_command(OUTPUT ${outputs}
    COMMAND "${CMAKE_COMMAND}" -E make_directory "${output_dir}"
    COMMAND ${fmpc_executable} ${arguments}
    DEPENDS "${rule_file}" ${fmpc_executable}
    COMMENT "fmpc: compiling ${FMPC_FILE} (${FMPC_TARGET}) for ${target}"
    VERBATIM)
  add_custom_target(${target}_generate DEPENDS ${outputs})
  add_library(${target} INTERFACE)
  add_dependencies(${target} ${target}_generate)
  target_include_directories(${target} INTERFACE "${output_dir}")
  target_compile_features(${target} INTERFACE cxx_std_17)
  if(FMPC_TARGET STREQUAL "table")
    target_link_libraries(${target} INTERFACE fmpc::kernels)
  endif()
  set_target_properties(${target} PROPERTIES FMPC_HEADER "${header}" FMPC_TABLE_FILE "${table_file}")
endfunction()
