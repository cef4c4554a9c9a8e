# ctest example_project: installs this build of fmpc into a staging prefix, configures and builds
# rulesets/example_project against it with find_package(fmpc), runs its programs (liver_stiffness; tool_force,
# which links fmpc::runtime, drives a tool in a scene, prints the force and swaps the material for the copied rule
# file), then edits (a copy of) the rule file and checks that the next build regenerated the evaluator.
#   cmake -DFMPC_BUILD_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... -DGENERATOR=... -P example_project.cmake
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE status OUTPUT_VARIABLE output ERROR_VARIABLE output)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "failed (${status}): ${ARGN}\n${output}")
  endif()
  set(last_output "${output}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
set(stage "${WORK_DIR}/stage")
run("${CMAKE_COMMAND}" --install "${FMPC_BUILD_DIR}" --prefix "${stage}")

set(rules "${WORK_DIR}/liver.fis")
file(COPY_FILE "${SOURCE_DIR}/rulesets/liver_fibrosis/mamdani.fis" "${rules}")
run("${CMAKE_COMMAND}" -S "${SOURCE_DIR}/rulesets/example_project" -B "${WORK_DIR}/build" -G "${GENERATOR}"
    "-DCMAKE_PREFIX_PATH=${stage}" "-DLIVER_RULES=${rules}" -DCMAKE_BUILD_TYPE=Release)
run("${CMAKE_COMMAND}" --build "${WORK_DIR}/build")
run("${WORK_DIR}/build/liver_stiffness")
message(STATUS "liver_stiffness:\n${last_output}")
string(REGEX MATCHALL "stiffness [0-9.]+ kPa \\(flags 0\\), table [0-9.]+ kPa" lines "${last_output}")
list(LENGTH lines count)
if(NOT count EQUAL 3)
  message(FATAL_ERROR "expected three result lines with flags 0, got:\n${last_output}")
endif()

# The runtime: the tip pressed 2 mm in and slid 1 cm across, the force printed every 50 ms (the tissue pushes the tip
# up: a positive z force, with vertices in contact), then the material swapped for the copied rules.
run("${WORK_DIR}/build/tool_force" "${SOURCE_DIR}/rulesets/example_project/tool_scene.yaml" "${rules}")
message(STATUS "tool_force:\n${last_output}")
string(REGEX MATCHALL "force \\(-?[0-9.]+, -?[0-9.]+, [0-9]+\\.[0-9]+\\) N  contacts [1-9][0-9]*" pressed "${last_output}")
list(LENGTH pressed count)
if(NOT count EQUAL 7 OR NOT last_output MATCHES "material swapped for ")
  message(FATAL_ERROR "expected seven force lines with the tip in contact and a material swap, got:\n${last_output}")
endif()

# Regeneration: a rule file edit (here a comment, which changes the file's hash) must rebuild the header.
set(header "${WORK_DIR}/build/fmpc_rulesets/liver_evaluator/liver_evaluator.h")
file(READ "${header}" before)
file(APPEND "${rules}" "# edited by tests/cmake/example_project.cmake\n")
run("${CMAKE_COMMAND}" --build "${WORK_DIR}/build")
file(READ "${header}" after)
if(before STREQUAL after)
  message(FATAL_ERROR "editing ${rules} did not regenerate ${header}")
endif()
string(REGEX MATCH "source hash \\(FNV-1a 64\\): [0-9a-f]+" hash_before "${before}")
string(REGEX MATCH "source hash \\(FNV-1a 64\\): [0-9a-f]+" hash_after "${after}")
if(hash_before STREQUAL hash_after)
  message(FATAL_ERROR "the regenerated header kept the old source hash (${hash_before})")
endif()
message(STATUS "regenerated after the edit: ${hash_before} -> ${hash_after}")
