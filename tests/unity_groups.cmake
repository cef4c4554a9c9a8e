# Unity groups of the test suite (cmake/FmpcUnityGroups.cmake): files whose file-scope helpers (anonymous
# namespaces, statics) have no name in common, so that each group compiles as one file. A file in no group compiles
# alone, as every file does without FMPC_UNITY_BUILD; a new test file needs no entry here.
fmpc_unity_group(fmpc_tests tests_0
  unit/matlab_fis_test.cpp
  unit/fmpc_language_test.cpp
  unit/fmpc_writer_test.cpp
  support/setup_reference.cpp
  unit/interpreter_test.cpp
  unit/tetrahedron_math_test.cpp
  unit/validation_test.cpp
  unit/hostile_input_test.cpp)
fmpc_unity_group(fmpc_tests tests_1
  unit/type2_test.cpp
  unit/spring_mapping_test.cpp
  support/random_system.cpp
  unit/sim_mesh_test.cpp
  unit/sim_integrate_test.cpp
  unit/scene_file_test.cpp
  unit/sim_springs_test.cpp)
fmpc_unity_group(fmpc_tests tests_2
  unit/emit_type2_test.cpp
  unit/fem_simulation_test.cpp
  unit/passes_test.cpp
  unit/cohort_test.cpp
  unit/liver_benchmark_test.cpp
  support/system_comparison.cpp
  unit/spring_scene_test.cpp)
fmpc_unity_group(fmpc_tests tests_3
  unit/emit_cpp_test.cpp
  differential/fuzzylite_formats_test.cpp
  unit/sim_gpu_test.cpp
  support/fmpc_process.cpp
  unit/studio_api_test.cpp
  unit/studio_edits_test.cpp)
fmpc_unity_group(fmpc_tests tests_4
  unit/type2_compile_test.cpp
  unit/lint_test.cpp
  support/elastic_problem.cpp
  unit/trade_test.cpp)
fmpc_unity_group(fmpc_tests tests_5
  unit/scene_run_test.cpp
  unit/check_test.cpp
  differential/fuzzylite_test.cpp
  unit/mamdani_to_sugeno_test.cpp
  unit/simulation_trade_test.cpp
  unit/cli_docs_test.cpp)
fmpc_unity_group(fmpc_tests tests_6
  unit/table_arrays_test.cpp
  unit/curve_similarity_test.cpp
  differential/round_trip_test.cpp
  unit/lsp_test.cpp
  unit/tune_test.cpp)
fmpc_unity_group(fmpc_tests tests_7
  unit/setup_equivalence_test.cpp
  unit/type_reduction_test.cpp
  differential/matlab_golden_test.cpp
  unit/cli_behaviour_test.cpp)
fmpc_unity_group(fmpc_tests tests_8
  unit/table_builder_test.cpp
  support/generated_program.cpp
  unit/unity_groups_test.cpp
  unit/rule_contributions_test.cpp
  unit/system_diff_test.cpp
  unit/hostile_readers_test.cpp
  unit/agreement_test.cpp)
fmpc_unity_group(fmpc_tests tests_9
  unit/vtk_xml_test.cpp
  unit/scene_material_test.cpp
  unit/lookup_table_test.cpp)
fmpc_unity_group(fmpc_tests tests_10
  unit/fuzzy_math_test.cpp
  unit/cell_bound_test.cpp
  unit/sliced_springs_test.cpp
  unit/generated_code_injection_test.cpp
  unit/launch_plan_test.cpp
  unit/law_unit_test.cpp
  unit/quadratic_element_test.cpp)
fmpc_unity_group(fmpc_tests tests_11
  unit/mesh_refinement_test.cpp
  unit/plot_test.cpp
  unit/sim_loads_test.cpp
  unit/packed_table_test.cpp)
fmpc_unity_group(fmpc_tests tests_12
  unit/rigid_tool_test.cpp
  unit/session_test.cpp)
fmpc_unity_group(fmpc_tests tests_13
  unit/volume_mesher_test.cpp
  unit/surface_readers_test.cpp
  unit/scene_meshing_test.cpp)
