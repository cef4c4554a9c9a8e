#include "runtime/scene/scene_file_parser.h"

#include <cmath>

#include "diagnostics/number_format.h"
#include "runtime/fem/element_law_registry.h"

namespace fmpc::sim {

void SceneParser::parse(const YAML::Node& root) {
  if (!root.IsMap()) {
    diagnostics_.error(range(root), "a scene file is a YAML map with 'mesh', 'material' and the other keys of "
                                    "docs/scenes.md");
    return;
  }
  check_map(root, "", {"name", "model", "mesh", "material", "mass", "damping", "springs", "law", "fem", "fixed",
                       "hold", "loads", "tools", "contact", "integrator", "dt", "duration", "backend", "precision",
                       "threads", "outputs", "on_inversion", "solver"});
  if (root["name"]) {
    if (auto name = text(root["name"], "name")) {
      if (const auto problem = output_name_problem(*name))
        error(root["name"], "name", "'" + *name + "' " + *problem);
      else
        scene_.name = *name;
    }
  } else if (const auto problem = output_name_problem(scene_.name)) {
    diagnostics_.error(range(root), "name: the scene file's name '" + scene_.name + "' " + *problem +
                                        "; give the scene a 'name'");
  }
  bool fem_keys = false;  // model: fem, whose law and element kind `fem` gives
  if (root["model"]) {
    // "springs", "fem", then each element law's model keyword, in the registry's order.
    std::vector<std::string> names = {"springs", "fem"};
    std::vector<int> laws = {-1, default_fem_law().law};
    for (const ElementLawRow& row : element_law_rows()) {
      if (row.model_keyword == nullptr) continue;
      names.push_back(row.model_keyword);
      laws.push_back(row.law);
    }
    if (auto i = keyword(root["model"], "model", names, "a force model")) {
      scene_.model = *i == 0 ? ForceModel::Springs : ForceModel::Elements;
      if (*i > 0) scene_.element_law = laws[*i];
      scene_.element_kind = default_element_kind().kind;
      fem_keys = *i == 1;
    }
  }
  if (root["fem"]) {
    if (fem_keys) {
      parse_fem(root["fem"]);
    } else {
      const std::string given = root["model"] ? describe(root["model"]) : std::string("springs (the default)");
      error(root["fem"], "fem",
            "'fem' chooses the law and element of model: fem; this scene's model is " + given +
                ": write model: fem (model: " + default_fem_law().model_keyword +
                " is fem: {law: " + default_fem_law().keyword + ", element: " + default_element_kind().keyword + "})");
    }
  }
  if (root["on_inversion"]) {
    static const std::vector<std::string> names = {"warn", "stop"};
    if (auto i = keyword(root["on_inversion"], "on_inversion", names, "what to do when an element turns inside out"))
      scene_.on_inversion = *i == 0 ? InversionPolicy::Warn : InversionPolicy::Stop;
  }
  if (!root["mesh"]) diagnostics_.error(range(root), "mesh: missing; give a mesh file or a generated box or ellipsoid");
  else parse_mesh(root["mesh"]);
  if (!root["material"]) diagnostics_.error(range(root), "material: missing; give youngs_modulus, stiffness, "
                                                         "stiffness_over_length, rules or table");
  else parse_material(root["material"]);
  if (root["mass"]) parse_mass(root["mass"]);
  if (root["damping"]) parse_damping(root["damping"]);
  if (root["springs"]) parse_springs(root["springs"]);
  if (root["law"]) parse_law(root["law"]);
  if (root["fixed"]) parse_fixed(root["fixed"]);
  if (root["hold"]) parse_hold(root["hold"]);
  if (root["loads"]) parse_loads(root["loads"]);
  if (root["tools"]) parse_tools(root["tools"]);
  if (root["contact"]) parse_contact(root["contact"]);
  if (root["integrator"]) {
    static const std::vector<std::string> names = {"forward_euler", "semi_implicit_euler", "velocity_verlet", "rk4",
                                                   "implicit_euler"};
    static const Integrator values[] = {Integrator::ForwardEuler, Integrator::SemiImplicitEuler,
                                        Integrator::VelocityVerlet, Integrator::RungeKutta4,
                                        Integrator::ImplicitEuler};
    if (auto i = keyword(root["integrator"], "integrator", names, "an integrator")) scene_.integrator = values[*i];
  }
  if (root["dt"]) {
    const YAML::Node dt = root["dt"];
    remember(dt, "dt");
    if (dt.IsScalar() && dt.Scalar() == "auto") {
      scene_.dt.reset();
    } else {
      double value = 0.0;
      if (!dt.IsScalar() || !YAML::convert<double>::decode(dt, value) || !std::isfinite(value) || !(value > 0.0))
        error(dt, "dt", "expected 'auto' or a positive time step in seconds, got " + describe(dt));
      else
        scene_.dt = value;
    }
  }
  if (root["duration"]) {
    if (auto value = positive(root["duration"], "duration", " of seconds")) scene_.duration = *value;
  }
  if (root["backend"]) {
    static const std::vector<std::string> names = {"auto", "cpu", "cuda"};
    if (auto i = keyword(root["backend"], "backend", names, "a backend"))
      scene_.backend = static_cast<SceneBackend>(*i);
  }
  if (root["precision"]) {
    static const std::vector<std::string> names = {"float", "double"};
    if (auto i = keyword(root["precision"], "precision", names, "a precision"))
      scene_.precision = *i == 0 ? Precision::Float : Precision::Double;
  }
  if (root["threads"]) {
    if (auto value = integer(root["threads"], "threads", 0, 256)) scene_.threads = static_cast<unsigned>(*value);
  }
  if (root["solver"]) parse_solver(root["solver"]);
  if (scene_.contact_damping_ratio > 0.0 && scene_.integrator == Integrator::ImplicitEuler)
    error(root["contact"]["damping_ratio"], "contact.damping_ratio",
          "contact damping is for the explicit integrators (a pressed vertex bouncing off the tool between substeps); "
          "implicit Euler's step damps that itself: leave it out");
  if (root["solver"] && scene_.integrator != Integrator::ImplicitEuler) {
    error(root["solver"], "solver",
          std::string("only implicit_euler solves a linear system each step; this scene's integrator is ") +
              scene_name(scene_.integrator) + ": remove 'solver' or use integrator: implicit_euler");
  }
  if (root["outputs"]) parse_outputs(root["outputs"]);
  if (scene_.model == ForceModel::Elements) check_fem_fields(root);
  if (scene_.model == ForceModel::Springs && scene_.material.poisson_ratio && !scene_.volume_term) {
    diagnostics_.error(scene_.range_of("material.poisson_ratio"),
                       "material.poisson_ratio: springs alone have nu = 1/4 (central springs obey the Cauchy "
                       "relation lambda = mu); add the volume term (springs: {volume_term: true}) to reach another "
                       "ratio, or use model: corotational_fem");
  }
  if (scene_.dt && root["dt"]) {
    const double steps = std::ceil(scene_.duration / *scene_.dt);
    if (!(steps <= kMaxSimulationSteps))
      error(root["dt"], "dt", "duration " + format_number(scene_.duration) + " s / dt " + format_number(*scene_.dt) +
                                  " s is " + format_number(steps) + " steps; the limit is " +
                                  format_number(kMaxSimulationSteps) + ": raise dt or shorten the duration");
  }
  // Mass damping alpha bounds an explicit scheme's step by 2 / alpha (v' = -alpha v taken explicitly grows once
  // h alpha > 2): alpha = 1e300 left no step, and the stability analysis told a damped semi-implicit scene to "add
  // damping", with no line. Said here, at the field, with the numbers.
  if (scene_.rayleigh.mass > 0.0 && scene_.integrator != Integrator::ImplicitEuler) {
    const double steps = std::ceil(scene_.duration * scene_.rayleigh.mass / 2.0);
    if (!(steps <= kMaxSimulationSteps))
      diagnostics_.error(scene_.range_of("damping.rayleigh.mass"),
                         "damping.rayleigh.mass: alpha = " + format_number(scene_.rayleigh.mass) + " 1/s allows " +
                             std::string(scene_name(scene_.integrator)) + " steps of at most 2 / alpha = " +
                             format_number(2.0 / scene_.rayleigh.mass) + " s: " + format_number(steps) +
                             " steps over the duration, above the limit of " + format_number(kMaxSimulationSteps),
                         {"lower alpha (a damping ratio zeta at angular frequency w is alpha = 2 zeta w), or use "
                          "integrator: implicit_euler, whose damping has no step limit"});
  }
}

void SceneParser::parse_fem(const YAML::Node& node) {
  remember(node, "fem");
  if (!check_map(node, "fem", {"law", "element"})) return;
  if (node["law"]) {
    const std::vector<std::string> laws = fem_law_keywords();
    if (auto i = keyword(node["law"], "fem.law", laws, "an element law"))
      scene_.element_law = fem_law_by_keyword(laws[*i])->law;
  }
  if (node["element"]) {
    const std::vector<std::string> kinds = element_kind_keywords();
    if (auto i = keyword(node["element"], "fem.element", kinds, "an element kind"))
      scene_.element_kind = element_kind_by_keyword(kinds[*i])->kind;
  }
}

void SceneParser::parse_outputs(const YAML::Node& node) {
  remember(node, "outputs");
  if (!check_map(node, "outputs",
                 {"directory", "frames", "vtu", "samples", "csv", "summary", "plot", "precision_check", "cohort"}))
    return;
  SceneOutputs& out = scene_.outputs;
  if (node["cohort"]) {
    const YAML::Node cohort = node["cohort"];
    remember(cohort, "outputs.cohort");
    if (check_map(cohort, "outputs.cohort", {"frames", "plot"})) {
      if (cohort["frames"])
        if (auto v = boolean(cohort["frames"], "outputs.cohort.frames")) out.cohort_frames = *v;
      if (cohort["plot"])
        if (auto v = boolean(cohort["plot"], "outputs.cohort.plot")) out.cohort_plot = *v;
    }
  }
  if (node["precision_check"]) {
    static const std::vector<std::string> names = {"auto", "on", "off"};
    if (auto i = keyword(node["precision_check"], "outputs.precision_check", names, "auto, on or off"))
      out.precision_check = *i == 0   ? SceneOutputs::PrecisionCheck::Auto
                            : *i == 1 ? SceneOutputs::PrecisionCheck::On
                                      : SceneOutputs::PrecisionCheck::Off;
  }
  if (node["directory"])
    if (auto v = text(node["directory"], "outputs.directory")) out.directory = *v;
  if (node["frames"])
    if (auto v = integer(node["frames"], "outputs.frames", 0, 100000)) out.frames = static_cast<int>(*v);
  if (node["vtu"]) {
    static const std::vector<std::string> names = {"binary", "ascii"};
    if (auto i = keyword(node["vtu"], "outputs.vtu", names, "a VTU encoding"))
      out.vtu = *i == 0 ? VtuFormat::Binary : VtuFormat::Ascii;
  }
  if (node["samples"])
    if (auto v = integer(node["samples"], "outputs.samples", 0, 1000000)) out.samples = static_cast<int>(*v);
  if (node["csv"])
    if (auto v = boolean(node["csv"], "outputs.csv")) out.csv = *v;
  if (node["summary"])
    if (auto v = boolean(node["summary"], "outputs.summary")) out.summary = *v;
  if (node["plot"])
    if (auto v = boolean(node["plot"], "outputs.plot")) out.plot = *v;
}

// `solver: {method, tolerance, max_iterations, contact_rounds}` (docs/scenes.md): implicit Euler's linear solver.
void SceneParser::parse_solver(const YAML::Node& node) {
  remember(node, "solver");
  if (!check_map(node, "solver", {"method", "tolerance", "max_iterations", "contact_rounds"})) return;
  ImplicitSolverOptions& solver = scene_.solver;
  if (node["method"]) {
    static const std::vector<std::string> names = {"auto", "direct", "cg"};
    static const ImplicitMethod methods[] = {ImplicitMethod::Automatic, ImplicitMethod::Direct,
                                             ImplicitMethod::ConjugateGradient};
    if (auto i = keyword(node["method"], "solver.method", names, "a linear solver")) solver.method = methods[*i];
  }
  if (node["tolerance"]) {
    // Below 1e-16 a double residual cannot get: every step would stop at the cap.
    const auto value = number(node["tolerance"], "solver.tolerance", "a relative residual from 1e-16 to 0.5");
    if (value && !(*value >= 1e-16 && *value <= 0.5))
      error(node["tolerance"], "solver.tolerance",
            "expected a relative residual from 1e-16 (double precision's reach) to 0.5, got " + format_number(*value));
    else if (value)
      solver.tolerance = *value;
  }
  if (node["max_iterations"])
    if (auto v = integer(node["max_iterations"], "solver.max_iterations", 1, 1000000))
      solver.max_iterations = static_cast<int>(*v);
  if (node["contact_rounds"])
    if (auto v = integer(node["contact_rounds"], "solver.contact_rounds", 1, kernels::kMostContactRounds))
      solver.contact_rounds = static_cast<int>(*v);
}

}  // namespace fmpc::sim
