#pragma once
// Rigid tools in frictionless contact with the tissue's surface (docs/simulator.md, "Rigid tools"): a sphere (an
// instrument's tip) or a capsule (its shaft), posed by a path in a scene or by the caller every tick
// (Simulation::set_tool_pose), pushing the surface vertices inside them out with a penalty force
// (kernels/contact_math.h). Plain data and the host's functions on it; nothing here reads files or prints.
#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "kernels/contact_math.h"
#include "runtime/mesh/mesh.h"

namespace fmpc::sim {

struct SimulationSetup;

// Where a tool is: its origin (m) and its orientation, a unit quaternion (w, x, y, z) turning the tool's frame into
// the world's. A capsule's axis runs from the origin along the tool's +z axis.
struct ToolPose {
  Point3 position{0.0, 0.0, 0.0};
  std::array<double, 4> orientation{1.0, 0.0, 0.0, 0.0};
};

struct ToolKeyframe {
  double time = 0.0;  // s
  ToolPose pose;
};

struct RigidTool {
  enum class Shape { Sphere, Capsule } shape = Shape::Sphere;
  std::string name;      // names the tool in messages, the CSV's columns and the summary
  double radius = 0.0;   // m
  double length = 0.0;   // m, a capsule's axis (0 for a sphere)
  // Its poses over time: the position linear between keyframes, the orientation normalised-linear (nlerp, the shorter
  // way round), held before the first keyframe and after the last. At least one keyframe; times strictly increasing.
  std::vector<ToolKeyframe> path;
  SourceRange range;  // where the scene defines it (its errors point here)
};

// The contact's penalty stiffness per vertex is this many times the vertex's own stiffness bound (the Gershgorin
// sum of its springs' and elements' stiffness that sets the explicit critical step), so the explicit step shrinks
// by 1 / sqrt(1 + ratio) wherever a tool can touch, and the penetration under a given pressure falls with the mesh
// size as the tissue's own stiffness rises: docs/simulator.md ("Rigid tools") gives the measured error against Hertz.
constexpr double kDefaultContactStiffnessRatio = 4.0;

// The pose at time t along the tool's path.
ToolPose tool_pose_at(const RigidTool& tool, double time);

// A unit quaternion from `orientation`, or false where it is not finite or has no length.
bool normalise_orientation(std::array<double, 4>& orientation);

// The tool's shape in world coordinates at `pose`: the segment's ends and the radius.
kernels::ToolShape<double> tool_shape(const RigidTool& tool, const ToolPose& pose);

// Vertices a tool can touch: those of the boundary faces of the tetrahedra (with a quadratic element's edge nodes on
// their edges), or every vertex of a mesh without tetrahedra (a membrane). One flag per vertex.
std::vector<unsigned char> surface_vertices(const SimulationSetup& setup);

// Every vertex's contact stiffness (N/m): contact_stiffness_ratio x its stiffness bound on surface vertices, zero
// elsewhere. Empty without tools.
std::vector<double> contact_stiffness(const SimulationSetup& setup);

// The most contact damping ratio a scene may ask for (contact.damping_ratio): far past critical, where the damper
// alone would hold a vertex still.
constexpr double kMostContactDampingRatio = 100.0;

// A surface vertex's contact damping (N s/m): `ratio` of critical against its contact stiffness k_c (N/m) and its
// mass m (kg) alone, 2 ratio sqrt(k_c m).
double contact_damping_coefficient(double ratio, double contact_stiffness, double mass);

// Every vertex's contact damping for `stiffness` (contact_stiffness's): empty without tools or without contact
// damping (contact_damping_ratio 0).
std::vector<double> contact_damping(const SimulationSetup& setup, const std::vector<double>& stiffness);

// What one tool feels at a state, in double on both backends: the reaction of the tissue on the tool, the sum of
// -f over the vertices inside it (kernels::add_contact_force's terms: with `damping`, from the vertices' velocities
// too), and its torque about the tool's origin.
struct ToolReading {
  Point3 force{0.0, 0.0, 0.0};   // N
  Point3 torque{0.0, 0.0, 0.0};  // N m
  std::size_t contacts = 0;      // vertices inside the tool
  double deepest = 0.0;          // m, the largest depth of a vertex inside it
};

std::vector<ToolReading> read_tools(const std::vector<RigidTool>& tools, const std::vector<ToolPose>& poses,
                                    const std::vector<double>& stiffness, const std::vector<Point3>& positions,
                                    const std::vector<double>& damping = {},
                                    const std::vector<Point3>& velocities = {});

// The tools' values (validate_setup calls it): a finite positive radius (and length for a capsule), at most
// kernels::kMostTools tools, a path of finite poses with a non-zero quaternion at increasing finite times, a finite
// positive contact stiffness ratio, a contact damping ratio in [0, kMostContactDampingRatio] and none with implicit
// Euler. Errors name the tool.
bool validate_tools(const SimulationSetup& setup, DiagnosticList& diagnostics);

// No tool inside the tissue at its start (Simulation::create): no vertex inside it at its path's first pose, and no
// point of its axis inside a tetrahedron (a tool wholly buried in the tissue touches no vertex). The error names the
// tool and the vertex or element.
bool check_tools_outside(const SimulationSetup& setup, DiagnosticList& diagnostics);

// A pose for set_tool_pose: finite, with a non-zero quaternion (normalised in place). `where` names the argument.
bool validate_pose(ToolPose& pose, const std::string& tool_name, const SourceRange& where,
                   DiagnosticList& diagnostics);

}  // namespace fmpc::sim
