# Unity groups of fmpc_runtime (cmake/FmpcUnityGroups.cmake): files that share no file-scope name, about 10 to 20
# CPU-seconds of a Release compile each. A file in no group (a new one, runtime/gpu/) compiles alone; a file that
# no longer exists is ignored. mesh_check.cpp and validate_setup.cpp both define finite_point, material_binding.cpp
# and scene_builder.cpp both define inside, rigid_tools.cpp defines finite_point too: each is kept in a different
# group.
fmpc_unity_group(fmpc_runtime runtime_mesh
  mesh/generated_mesh.cpp
  mesh/gmsh_reader.cpp
  mesh/mesh.cpp
  mesh/mesh_check.cpp
  mesh/mesh_refinement.cpp
  mesh/obj_reader.cpp
  mesh/text_cursor.cpp
  mesh/vtk_reader.cpp)
# tetgen_mesher.cpp compiles alone: TetGen's header defines REAL and other macros every file after it would see.
fmpc_unity_group(fmpc_runtime runtime_meshing
  mesh/ply_reader.cpp
  mesh/stl_reader.cpp
  meshing/mesh_quality.cpp
  meshing/size_field.cpp
  meshing/surface_check.cpp
  meshing/surface_split.cpp
  meshing/surface_untangle.cpp
  meshing/volume_mesher.cpp)
fmpc_unity_group(fmpc_runtime runtime_models
  springs/sliced_springs.cpp
  springs/spring_network.cpp
  fem/fem_model_builder.cpp
  fem/element_law_registry.cpp
  fem/element_terms.cpp
  integrate/element_outputs.cpp
  integrate/loads.cpp
  integrate/model_tangent.cpp
  integrate/rigid_tools.cpp
  integrate/stability.cpp
  integrate/worker_pool.cpp)
fmpc_unity_group(fmpc_runtime runtime_integrate
  integrate/cpu_engine.cpp
  integrate/run_supervisor.cpp
  integrate/simulate.cpp
  integrate/simulation_tools.cpp
  integrate/static_equilibrium.cpp
  integrate/validate_setup.cpp)
fmpc_unity_group(fmpc_runtime runtime_io
  io/atomic_file.cpp
  io/memory_limit.cpp
  io/input_file.cpp
  io/json_text.cpp
  io/rule_file_input.cpp
  io/vtk_xml.cpp
  analysis/curve_similarity.cpp
  analysis/liver_benchmark.cpp
  analysis/organ_step_response.cpp)
fmpc_unity_group(fmpc_runtime runtime_scene_file
  scene/scene_file.cpp
  scene/scene_file_fields.cpp
  scene/scene_file_loads.cpp
  scene/scene_file_material.cpp
  scene/scene_file_run.cpp
  scene/scene_file_tools.cpp
  scene/scene_file_yaml.cpp
  scene/material_binding.cpp
  scene/cohort.cpp)
fmpc_unity_group(fmpc_runtime runtime_scene_run
  scene/scene_builder.cpp
  scene/scene_meshing.cpp
  scene/scene_recorder.cpp
  scene/scene_run.cpp
  scene/scene_state.cpp
  scene/simulation_trade.cpp
  scene/spring_model_builder.cpp
  scene/cohort_run.cpp
  scene/precision_check.cpp
  scene/scene_batch_run.cpp
  gpu/batch_concatenation.cpp
  gpu/launch_plan.cpp)
