#pragma once
// `material.bind` (docs/scenes.md, "Rules for every parameter"): the element law's material parameters per element
// from the outputs of one rule file (or compiled table), each checked against its parameter's row in the law's
// registry (runtime/fem/element_law_registry.h): the parameter is the law's, the output's unit measures its quantity,
// the output's declared range stays in the parameter's valid range, and so does its value at every element.
// Nothing here names a law; the parameters are the registry's.
#include <optional>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/scene/material_binding.h"
#include "runtime/scene/scene_file.h"

namespace fmpc::sim {

// The index of the output `name` among `outputs` of `what` ("system 'liver'", "the table"); nullopt after an error
// at the scene's `field` with a "did you mean" note.
std::optional<int> output_index(const Scene& scene, const std::vector<std::string>& outputs, const std::string& name,
                                const std::string& field, const std::string& what, DiagnosticList& diagnostics);

// The outputs material.bind gives the law's parameters other than Young's modulus, in its order (empty without
// `bind`); nullopt after errors: the model is not an element law, a parameter is not the law's, an output is not
// the evaluator's, or an input is bound to strain (a strain table holds Young's modulus alone).
std::optional<std::vector<int>> bound_output_indices(const Scene& scene, const std::vector<std::string>& outputs,
                                                     const std::string& what, DiagnosticList& diagnostics);

// Writes each of `binding.bound` (per element, at `centroids`, mesh units) into `material` in its parameter's SI
// unit, and a bound Prony weight (viscoelastic.prony[I].weight) into `prony`, after checking the unit, the output's
// declared range and every element's value (a Prony weight in [0, 1): the scene's where it is the same positive value
// at every element, else PronyTerm::element_weight; the weights' sum below 1 at every element and with each bound one
// at its declared largest); false after errors located at material.bind.PARAMETER naming the
// output. `law` is the scene's element law's row.
bool apply_bound_parameters(const Scene& scene, const ElementLawRow& law, const MaterialBinding& binding,
                            const std::vector<Point3>& centroids, ElementMaterial& material,
                            std::vector<PronyTerm>& prony, DiagnosticList& diagnostics);

// "output 'nu' of system 'liver'": how messages name a bound output.
std::string bound_output_name(const MaterialBinding& binding, const BoundOutput& output);

}  // namespace fmpc::sim
