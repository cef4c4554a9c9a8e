#pragma once
// Scene files (YAML, docs/scenes.md): what to simulate, as plain data. parse_scene reads the text and checks every
// field's type and range; every error names the field and what is allowed. Nothing is built here: build_scene
// (runtime/scene/scene_builder.h) turns a Scene into a mesh, a spring model and a SimulationSetup.
#include <array>
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/integrate/simulation.h"
#include "runtime/io/vtk_xml.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/meshing/volume_mesher.h"
#include "runtime/springs/spring_network.h"

namespace fmpc::sim {

// `mesh: {surface: FILE, ...}`: how a closed surface becomes tetrahedra (runtime/meshing/volume_mesher.h). The size
// field's sources are the probe's picked point and path (added when the scene is built) and `refine_near`.
struct SceneSurfaceMeshing {
  VolumeMeshOptions options;         // size lengths in mesh units
  bool size_far_given = false;       // else the surface's mean edge length
  bool size_near_given = false;      // else size_far
};

struct SceneMesh {
  enum class Kind { File, Box, Ellipsoid, Surface } kind = Kind::Box;
  std::string file;         // resolved against the scene's folder (`file` or `surface`)
  SceneSurfaceMeshing surface;
  double unit = 1.0;        // metres per mesh unit (`units: m|cm|mm|NUMBER`)
  BoxSpec box;              // mesh units
  EllipsoidSpec ellipsoid;  // mesh units
};

// An axis-aligned box in mesh units (fixed nodes, regions).
struct SceneBox {
  Point3 min{0.0, 0.0, 0.0};
  Point3 max{0.0, 0.0, 0.0};
};

struct RegionValue {
  SceneBox box;
  double value = 0.0;
};

// A number for the whole scene, or per region (the first region box containing the element's centroid), with a
// default outside every region.
struct RegionalValue {
  double value = 0.0;  // the default (or the only value)
  bool has_default = true;
  std::vector<RegionValue> regions;
};

// How one FIS input gets its value.
struct InputBinding {
  std::string input;
  enum class Kind {
    Constant,   // the same value for every spring
    PerRegion,  // by the spring's midpoint: the first region box containing it, else `value` (the default)
    Strain,     // the spring's strain (l - l0) / l0, looked up in a table every step
  } kind = Kind::Constant;
  double value = 0.0;
  bool has_default = false;  // PerRegion: whether `value` is a default
  std::vector<RegionValue> regions;
};

// `material.bind: {PARAMETER: OUTPUT}`: a material parameter of the element law (its registry row's parameters,
// runtime/fem/element_law_registry.h) given per element by an output of the rules or table. Scene::ranges holds
// "material.bind.PARAMETER" (the key) and "material.bind.PARAMETER.output" (the output's name).
struct ParameterBinding {
  std::string parameter;
  std::string output;
};

struct StrainAxis {
  double min = -0.3;
  double max = 0.3;
  int points = 61;
};

struct SceneMaterial {
  enum class Source {
    YoungsModulus,        // value: kPa, through `mapping`
    Stiffness,            // value: N/m, every spring
    StiffnessOverLength,  // value: N, k = value / l0 (SOFA's MeshSpringForceField)
    Rules,                // a rule file: its output is Young's modulus, through `mapping`
    Table,                // a compiled .fzt table: its output is Young's modulus, through `mapping`
  } source = Source::YoungsModulus;
  double value = 0.0;
  std::string file;    // Rules / Table, resolved against the scene's folder
  std::string system;  // Rules: which system of the file; empty: the only one
  std::string output;  // which output; empty: the only one
  std::string patient;  // a label, carried into the summary
  std::vector<InputBinding> bindings;  // in the order given
  std::vector<ParameterBinding> bind;  // material.bind, in the order given; empty: `output` is Young's modulus
  std::optional<StrainAxis> strain_axis;  // Rules with a strain binding; default: the input's range, 101 points
  // Young's modulus -> spring constants (`mapping`): YoungsModulus, Rules and Table only.
  StiffnessMapping mapping = StiffnessMapping::VanGelder1998;
  bool mapping_given = false;
  // The co-rotational FEM's, or the springs' with the volume term (default 0.45 for both); in [0, 0.4999] (the
  // element kind may take less: build_fem_model).
  std::optional<RegionalValue> poisson_ratio;
  // material.viscoelastic: {prony: [{weight, time}, ...]} (kernels/prony_viscoelasticity.h); empty: elastic. FEM only.
  std::vector<PronyTerm> prony;
  double thickness = 1.0;        // m, membranes (triangle meshes)
  double flexion_fraction = 0.1;
};

struct SceneLaw {
  kernels::SpringLaw law = kernels::SpringLaw::LinearDashpot;
  double k2_over_k1 = 200.0;
  double xc = 0.2;
  double gamma0 = 0.0;
  double gamma1 = 0.0;
};

struct SceneFixed {
  std::vector<std::int32_t> indices;  // as in the mesh file (before repair)
  std::vector<SceneBox> boxes;
  struct Plane {
    Point3 point{0.0, 0.0, 0.0};
    Point3 normal{0.0, 0.0, 1.0};
    double tolerance = 1e-9;  // mesh units
    std::string field;        // where the scene gives it ("fixed.plane", "hold[0].plane[1]"), for messages
  };
  std::vector<Plane> planes;
};

// Vertices held along some axes only (`hold`), e.g. a face sliding on a frictionless plane: the selectors of
// `fixed`, and the axes held (bit a for axis a).
struct SceneHold {
  SceneFixed selection;
  std::uint8_t axes = 0;
  std::string field;  // "hold" or "hold[i]", for errors found when the mesh is known
};

struct SceneProbe {
  ProbeLoad::Mode mode = ProbeLoad::Mode::Displacement;
  std::vector<std::int32_t> indices;  // pick by index (mesh file numbering)
  bool by_ray = false;
  Point3 ray_origin{0.0, 0.0, 0.0};     // mesh units
  Point3 ray_direction{0.0, 0.0, -1.0};
  double radius = 0.0;  // mesh units: the vertices within this distance of the first hit (0: the hit's nearest)
  Point3 target{0.0, 0.0, 0.0};  // m (displacement) or N (force)
  double ramp = 0.0;             // s
  int cycles = 0;                // > 0: up to target and back over 2 ramp, this many times (ProbeLoad::cycles)
};

// A rigid tool (`tools:`): its geometry in mesh units, converted to metres by the builder.
struct SceneTool {
  std::string name;
  RigidTool::Shape shape = RigidTool::Shape::Sphere;
  double radius = 0.0;              // mesh units
  double length = 0.0;              // mesh units (capsule)
  std::vector<ToolKeyframe> path;   // positions in mesh units; one keyframe for `pose`
  std::string field;                // "tools[i]", for errors found when the mesh is known
};

enum class SceneBackend { Auto, Cpu, Cuda };

struct SceneOutputs {
  std::string directory;  // resolved against the current folder; empty: "<scene name>.out" beside the scene
  int frames = 20;        // .vtu frames (evenly spaced, first and last included); 0: none
  VtuFormat vtu = VtuFormat::Binary;  // the frames' encoding: binary (appended, zlib) or ascii
  int samples = 200;      // CSV rows (evenly spaced); 0: none
  bool csv = true;
  bool summary = true;
  bool plot = true;  // force-displacement PNG (needs a probe)
  // Rerun in the other precision and compare (scene_run.h, PrecisionCheck): auto runs it when the run's stepping
  // took at most kPrecisionCheckSeconds (the check costs about as much again); on always; off never.
  enum class PrecisionCheck { Auto, On, Off } precision_check = PrecisionCheck::Auto;
  // A cohort's patients (docs/cohorts.md) write summary.json and time_series.csv each, and cohort.csv beside them;
  // their frames and force-displacement pictures only when asked (`cohort: {frames: true, plot: true}`): a
  // thousand patients' 25 frames each were most of a cohort's time.
  bool cohort_frames = false;
  bool cohort_plot = false;
};

// Rayleigh damping C = alpha M + beta K (`damping: {rayleigh: {mass: ALPHA, stiffness: BETA}}`): alpha (1/s) acts on
// every vertex, beta (s) is added to each spring's dashpot (c += beta k) or each element's stiffness damping.
struct SceneRayleigh {
  double mass = 0.0;
  double stiffness = 0.0;
};

constexpr double kDefaultPoissonRatio = 0.45;

// The scene's `model:` (docs/scenes.md): a spring network (with springs: {volume_term: true}, the element law beside
// springs with it), or a finite-element model of one element law on one element kind (`model: fem` with
// `fem: {law, element}`, or a law's own model keyword such as `corotational_fem` on linear tetrahedra;
// runtime/fem/element_law_registry.h).
enum class ForceModel { Springs, Elements };

struct Scene {
  std::string path;  // the scene file
  std::string name;  // `name`, or the file's stem
  ForceModel model = ForceModel::Springs;
  int element_law = 0;   // model Elements: the law's index in element_law_rows()
  int element_kind = 0;  // model Elements: the element kind's index in element_kind_rows()
  SceneMesh mesh;
  SceneMaterial material;
  MassSpec mass;
  DampingSpec damping;
  SceneRayleigh rayleigh;
  TriangleSpringOptions triangle_springs;
  bool volume_term = false;  // springs: {volume_term: true}
  InversionPolicy on_inversion = InversionPolicy::Warn;
  SceneLaw law;
  SceneFixed fixed;
  std::vector<SceneHold> holds;
  Point3 gravity{0.0, 0.0, 0.0};
  std::optional<SceneProbe> probe;
  std::vector<SceneTool> tools;
  double contact_stiffness_ratio = kDefaultContactStiffnessRatio;  // `contact: {stiffness_ratio}`
  Integrator integrator = Integrator::SemiImplicitEuler;
  std::optional<double> dt;  // nullopt: auto
  double duration = 1.0;     // s
  std::optional<std::size_t> steps;  // overrides duration (command line)
  ImplicitSolverOptions solver;      // `solver` (implicit Euler's linear solver)
  SceneBackend backend = SceneBackend::Auto;
  Precision precision = Precision::Float;
  unsigned threads = 0;  // 0: hardware concurrency, at most 8
  SceneOutputs outputs;
  // Where each field was written ("material.inputs.HCV", "fixed.indices"), for errors found later.
  std::map<std::string, SourceRange> ranges;

  SourceRange range_of(const std::string& field) const;
};

// Scene limits (docs/limits.md). The file itself is at most kMaxSceneFileBytes (runtime/io/input_file.h).
inline constexpr std::size_t kMaxSceneNesting = 32;      // YAML levels; a scene needs about 6
inline constexpr std::size_t kMaxSceneNameBytes = 200;   // `name` becomes <name>.pvd and other file names
inline constexpr double kMaxSimulationSteps = 1e9;       // ceil(duration / dt), or --steps

// Why `name` cannot name the scene's output files, or nullopt when it can: it must be a single file-name
// component (no '/', '\\', "." or ".."), without control characters or NUL bytes, at most kMaxSceneNameBytes
// long, so that nothing is written outside the output folder.
std::optional<std::string> output_name_problem(const std::string& name);

// The number of steps a run takes: scene.steps when set, else ceil(duration / dt), checked against
// kMaxSimulationSteps before it becomes an integer (a huge duration or a tiny dt would overflow size_t and run 0
// steps); nullopt after an error naming `duration` and `dt` otherwise. dt is the step actually used (auto or given).
std::optional<std::size_t> planned_step_count(const Scene& scene, double dt, DiagnosticList& diagnostics);

// Parses scene YAML `text` read from `path`. Returns nullopt after appending errors (each naming the field, its
// position and what is allowed); unknown keys are errors with a "did you mean" note, and so are duplicate keys
// (which YAML itself would silently collapse).
std::optional<Scene> parse_scene(const std::string& path, const std::string& text, DiagnosticList& diagnostics);

const char* to_string(SceneBackend backend);
const char* scene_name(Integrator integrator);  // the scene spelling: "semi_implicit_euler", ...
const char* scene_name(StiffnessMapping mapping);  // the scene spelling: "van_gelder_1998", ...
// The scene spelling of its model: "springs", the element law's model keyword where it has one and the element kind
// is the default, else "fem".
std::string model_keyword(const Scene& scene);

}  // namespace fmpc::sim
