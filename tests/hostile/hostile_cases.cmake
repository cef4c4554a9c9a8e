# One ctest per hostile-input case (tests/hostile/<reader>/<case>.case, label hostile); run_hostile_case.sh
# says what a case holds and what every run checks. Sanitizer builds get three times the memory allowance.
file(GLOB FMPC_HOSTILE_CASES CONFIGURE_DEPENDS ${CMAKE_CURRENT_LIST_DIR}/*/*.case)
set(FMPC_HOSTILE_MEMORY_FACTOR 1)
if(FMPC_SANITIZE)
  set(FMPC_HOSTILE_MEMORY_FACTOR 3)
endif()
foreach(case_file ${FMPC_HOSTILE_CASES})
  if(FMPC_SANITIZE)
    file(STRINGS ${case_file} skip_under_sanitizers REGEX "^sanitizers: skip$")
    if(skip_under_sanitizers)
      continue()
    endif()
  endif()
  get_filename_component(case_name ${case_file} NAME_WE)
  get_filename_component(group_dir ${case_file} DIRECTORY)
  get_filename_component(group ${group_dir} NAME)
  add_test(NAME hostile.${group}.${case_name}
    COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/run_hostile_case.sh ${case_file} $<TARGET_FILE:fmpc>
            ${CMAKE_CURRENT_BINARY_DIR}/hostile/${group}/${case_name} ${FMPC_HOSTILE_MEMORY_FACTOR})
  set_tests_properties(hostile.${group}.${case_name} PROPERTIES LABELS hostile TIMEOUT 120 SKIP_RETURN_CODE 77)
endforeach()
