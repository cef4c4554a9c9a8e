# Copies one fuzz target's seeds into OUT (a build folder): cmake -DNAME= -DSOURCE_DIR= -DSHARED_DATA= -DOUT= -P
include(${CMAKE_CURRENT_LIST_DIR}/fuzz_seeds.cmake)
fmpc_fuzz_seed_files(${NAME} ${SOURCE_DIR} ${SHARED_DATA} seeds)
set(index 0)
foreach(seed ${seeds})
  get_filename_component(base ${seed} NAME)
  configure_file(${seed} ${OUT}/${index}_${base} COPYONLY)
  math(EXPR index "${index} + 1")
endforeach()
