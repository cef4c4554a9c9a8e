# Runs the first ```python block of docs/python.md as written, in a fresh folder, with the module built here on
# the path and the repository root as FMPC_SOURCE (the example's files are relative to it).
file(READ ${DOC} text)
string(FIND "${text}" "```python\n" start)
if(start EQUAL -1)
  message(FATAL_ERROR "${DOC} has no ```python block")
endif()
math(EXPR start "${start} + 10")
string(SUBSTRING "${text}" ${start} -1 rest)
string(FIND "${rest}" "```" end)
string(SUBSTRING "${rest}" 0 ${end} example)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
file(WRITE ${WORK_DIR}/example.py "${example}")
execute_process(COMMAND ${CMAKE_COMMAND} -E env PYTHONPATH=${MODULE_DIR} FMPC_SOURCE=${SOURCE_DIR}
                        ${PYTHON} example.py
                WORKING_DIRECTORY ${WORK_DIR} RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(NOT status EQUAL 0)
  message(FATAL_ERROR "the example in ${DOC} failed (exit ${status})")
endif()
