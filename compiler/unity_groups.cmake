# Unity groups of fmpc_compiler (cmake/FmpcUnityGroups.cmake): files that share no file-scope name, about 10 to 15
# CPU-seconds of a Release compile each, so that a 2-core build keeps both cores busy. Left out: interpreter.cpp
# and backend/table/cell_bound.cpp, whose pimpl State holds types of their anonymous namespaces (GCC's
# -Wsubobject-linkage objects once such a file is included by another), and the generated embedded_kernels.cpp.
fmpc_unity_group(fmpc_compiler compiler_frontend
  frontend/fmpc_ast.cpp
  frontend/fmpc_parser.cpp
  frontend/fmpc_printer.cpp
  frontend/ir_printer.cpp
  frontend/rule_file_loader.cpp
  frontend/utf8.cpp
  frontend/fmpc_tokens.cpp
  frontend/fmpc_token_repair.cpp
  frontend/fmpc_parameter_edit.cpp
  sema/lower_fmpc.cpp
  ir/fuzzy_system.cpp
  ir/content_hash.cpp
  ir/system_names.cpp
  ir/units.cpp)
fmpc_unity_group(fmpc_compiler compiler_interchange
  frontend/fcl.cpp
  frontend/fll.cpp
  frontend/fuzzylite_vocabulary.cpp
  frontend/matlab_fis_reader.cpp
  frontend/matlab_fis_writer.cpp)
fmpc_unity_group(fmpc_compiler compiler_sema_eval_passes
  sema/check.cpp
  sema/coverage.cpp
  sema/term_shape.cpp
  eval/defuzzify.cpp
  eval/evaluation_report.cpp
  eval/output_comparison.cpp
  passes/drop_dead_terms.cpp
  passes/mamdani_to_sugeno.cpp
  passes/pipeline.cpp
  passes/rename_duplicate_terms.cpp
  passes/specialize.cpp)
fmpc_unity_group(fmpc_compiler compiler_emitters
  backend/cpp/cpp_text.cpp
  backend/cpp/embedded_math.cpp
  backend/cpp/emit_cpp.cpp
  backend/cpp/emit_type2.cpp
  backend/cpp/evaluator_emitter.cpp
  backend/cpp/lane_batch_emitter.cpp
  backend/cpp/namespace_name.cpp
  eval/rule_contributions.cpp
  passes/fuse_consequents.cpp
  passes/prune_rules.cpp)
fmpc_unity_group(fmpc_compiler compiler_tables_lint
  backend/table/lookup_table.cpp
  backend/table/table_arrays.cpp
  backend/table/table_bound.cpp
  backend/table/table_builder.cpp
  backend/table/table_estimate.cpp
  backend/table/table_grid.cpp
  backend/table/table_points.cpp
  sema/lint.cpp
  eval/agreement.cpp)
fmpc_unity_group(fmpc_compiler compiler_eval_reports
  eval/control_surface.cpp
  eval/nelder_mead.cpp
  eval/system_diff.cpp
  eval/tuning.cpp)
