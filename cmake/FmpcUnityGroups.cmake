# Unity groups (FMPC_UNITY_BUILD, which tools/run turns on: docs/limits.md, "CI"). A group's files compile as one
# source, so their file-scope helpers (anonymous namespaces, statics) share one scope: a name two of them define
# would clash, or worse, overload silently. tests/unit/unity_groups_test.cpp checks every group for that.
#
# fmpc_unity_group(TARGET GROUP FILE...): FILEs (relative to the calling CMakeLists' folder) form unity group GROUP
# of TARGET. A file in no group compiles alone, as every file does without FMPC_UNITY_BUILD, so a new file needs
# no entry. The groups are recorded (global property FMPC_UNITY_GROUPS, "GROUP|path" items) for that test.
function(fmpc_unity_group target name)
  list(TRANSFORM ARGN PREPEND ${CMAKE_CURRENT_SOURCE_DIR}/)
  set_source_files_properties(${ARGN} TARGET_DIRECTORY ${target} PROPERTIES UNITY_GROUP ${name})
  foreach(file ${ARGN})
    set_property(GLOBAL APPEND PROPERTY FMPC_UNITY_GROUPS "${name}|${file}")
  endforeach()
endfunction()

# fmpc_unity_build(GROUPS_FILE TARGET...): the TARGETs compile their unity groups (GROUPS_FILE) as one source each
# when FMPC_UNITY_BUILD is on; the groups are recorded either way.
function(fmpc_unity_build groups_file)
  if(FMPC_UNITY_BUILD)
    set_target_properties(${ARGN} PROPERTIES UNITY_BUILD ON UNITY_BUILD_MODE GROUP)
  endif()
  include(${groups_file})
endfunction()
