# Unity groups of the tools' libraries (cmake/FmpcUnityGroups.cmake): files that share no file-scope name. The
# plot's heat_map.cpp and pareto_plot.cpp both define kWidth and kHeight, axes.cpp and rule_view.cpp kGap, the
# studio's studio_cohorts.cpp and studio_scene.cpp rendered: each pair is kept in different groups. lsp::Document's
# members are defined in lsp_document.cpp, lsp_completion.cpp and lsp_hover.cpp: with all three in one unit, clang
# sees that its private encoding_ is never read (-Wunused-private-field, an error here), so they are kept apart. The CLI itself
# (fmpc) is batched by CMake around its CLI11 precompiled header; the generated studio_assets.cpp compiles alone.
fmpc_unity_group(fmpc_plot tools_plot_charts
  plot/axes.cpp
  plot/canvas.cpp
  plot/heat_map.cpp
  plot/line_chart.cpp)
fmpc_unity_group(fmpc_plot tools_plot_views
  plot/pareto_plot.cpp
  plot/rule_view.cpp)
fmpc_unity_group(fmpc_lsp tools_lsp_server
  lsp/language_server.cpp
  lsp/lsp_document.cpp
  lsp/lsp_transport.cpp
  lsp/rule_outline.cpp
  lsp/text_positions.cpp)
fmpc_unity_group(fmpc_lsp tools_lsp_answers
  lsp/lsp_completion.cpp
  lsp/lsp_hover.cpp)
fmpc_unity_group(fmpc_reports tools_reports
  fmpc/csv_table.cpp
  fmpc/evaluation_points.cpp
  fmpc/patient_data.cpp
  fmpc/report_text.cpp
  fmpc/text_files.cpp
  fmpc/validation_report.cpp
  fmpc/version_diff_report.cpp)
fmpc_unity_group(fmpc_studio tools_studio_server
  studio/studio_cohorts.cpp
  studio/studio_evaluation.cpp
  studio/studio_files.cpp
  studio/studio_security.cpp
  studio/studio_server.cpp)
fmpc_unity_group(fmpc_studio tools_studio_rules
  studio/studio_rule_edits.cpp
  studio/studio_rule_model.cpp
  studio/studio_scene.cpp)
