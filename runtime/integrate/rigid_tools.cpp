// Rigid tools on the host: poses along a path, the world shapes the steps read, the surface a tool can touch, the
// contact stiffness per vertex, the reaction readings and the checks (runtime/integrate/rigid_tools.h).
#include "runtime/integrate/rigid_tools.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>

#include "diagnostics/number_format.h"
#include "runtime/integrate/simulation.h"

namespace fmpc::sim {

namespace {

std::string point_text(const Point3& p) {
  return "(" + format_number(p[0]) + ", " + format_number(p[1]) + ", " + format_number(p[2]) + ")";
}

std::string tool_label(const RigidTool& tool, std::size_t index) {
  return "tool " + std::to_string(index) + (tool.name.empty() ? "" : " '" + tool.name + "'");
}

// Whether p lies inside tetrahedron t at `points` (on its boundary counts): every face's signed volume with p
// non-negative.
bool inside_tetrahedron(const std::vector<Point3>& points, const Tetrahedron& t, const Point3& p) {
  const Point3& a = points[static_cast<std::size_t>(t[0])];
  const Point3& b = points[static_cast<std::size_t>(t[1])];
  const Point3& c = points[static_cast<std::size_t>(t[2])];
  const Point3& d = points[static_cast<std::size_t>(t[3])];
  return signed_volume(p, b, c, d) >= 0.0 && signed_volume(a, p, c, d) >= 0.0 && signed_volume(a, b, p, d) >= 0.0 &&
         signed_volume(a, b, c, p) >= 0.0;
}

}  // namespace

bool normalise_orientation(std::array<double, 4>& orientation) {
  double norm_squared = 0.0;
  for (const double q : orientation) {
    if (!std::isfinite(q)) return false;
    norm_squared += q * q;
  }
  const double norm = std::sqrt(norm_squared);
  if (!(norm > 0.0) || !std::isfinite(norm)) return false;
  for (double& q : orientation) q /= norm;
  return true;
}

ToolPose tool_pose_at(const RigidTool& tool, double time) {
  const std::vector<ToolKeyframe>& path = tool.path;
  if (path.empty()) return ToolPose{};
  if (!(time > path.front().time)) return path.front().pose;
  if (!(time < path.back().time)) return path.back().pose;
  const auto next = std::upper_bound(path.begin(), path.end(), time,
                                     [](double t, const ToolKeyframe& keyframe) { return t < keyframe.time; });
  const ToolKeyframe& from = *(next - 1);
  const ToolKeyframe& to = *next;
  const double s = (time - from.time) / (to.time - from.time);
  ToolPose pose;
  for (std::size_t i = 0; i < 3; ++i)
    pose.position[i] = from.pose.position[i] + s * (to.pose.position[i] - from.pose.position[i]);
  // nlerp the shorter way round: q and -q are the same rotation.
  double dot = 0.0;
  for (std::size_t i = 0; i < 4; ++i) dot += from.pose.orientation[i] * to.pose.orientation[i];
  const double sign = dot < 0.0 ? -1.0 : 1.0;
  for (std::size_t i = 0; i < 4; ++i)
    pose.orientation[i] = (1.0 - s) * from.pose.orientation[i] + s * sign * to.pose.orientation[i];
  if (!normalise_orientation(pose.orientation)) pose.orientation = from.pose.orientation;  // opposite quaternions
  return pose;
}

kernels::ToolShape<double> tool_shape(const RigidTool& tool, const ToolPose& pose) {
  const Point3& a = pose.position;
  Point3 b = a;
  if (tool.shape == RigidTool::Shape::Capsule) {
    // The tool's +z axis in the world: the third column of the quaternion's rotation matrix.
    const double w = pose.orientation[0], x = pose.orientation[1], y = pose.orientation[2], z = pose.orientation[3];
    const Point3 axis{2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y)};
    for (std::size_t i = 0; i < 3; ++i) b[i] = a[i] + tool.length * axis[i];
  }
  return {a[0], a[1], a[2], b[0], b[1], b[2], tool.radius};
}

std::vector<unsigned char> surface_vertices(const SimulationSetup& setup) {
  const std::size_t n = setup.rest_positions.size();
  if (setup.tetrahedra.empty()) return std::vector<unsigned char>(n, 1);
  std::vector<unsigned char> surface(n, 0);
  Mesh mesh;
  mesh.points = setup.rest_positions;
  mesh.tetrahedra = setup.tetrahedra;
  const std::vector<Triangle> faces = boundary_triangles(mesh);
  for (const Triangle& face : faces)
    for (const auto v : face) surface[static_cast<std::size_t>(v)] = 1;
  // A quadratic element's edge nodes (added after the mesh's vertices) on a boundary face's edge are on the surface
  // too: they carry all of a pressure's consistent load on a 6-node face (a third each), its corners none, so a tool
  // touching only the corners presses the surface at points and sinks between them.
  const auto& ends = setup.elements.geometry.added_vertex_ends;
  if (ends.empty()) return surface;
  std::set<std::pair<std::int32_t, std::int32_t>> edges;
  for (const Triangle& face : faces)
    for (int k = 0; k < 3; ++k) edges.insert(std::minmax(face[k], face[(k + 1) % 3]));
  const std::size_t first_added = n - ends.size();
  for (std::size_t i = 0; i < ends.size(); ++i)
    if (edges.count(std::minmax(ends[i][0], ends[i][1])) > 0) surface[first_added + i] = 1;
  return surface;
}

std::vector<double> contact_stiffness(const SimulationSetup& setup) {
  if (setup.tools.empty()) return {};
  std::vector<double> stiffness = vertex_bounds(setup).stiffness;
  const std::vector<unsigned char> surface = surface_vertices(setup);
  for (std::size_t v = 0; v < stiffness.size(); ++v)
    stiffness[v] = surface[v] ? setup.contact_stiffness_ratio * stiffness[v] : 0.0;
  return stiffness;
}

double contact_damping_coefficient(double ratio, double contact_stiffness, double mass) {
  return 2.0 * ratio * std::sqrt(contact_stiffness * mass);
}

std::vector<double> contact_damping(const SimulationSetup& setup, const std::vector<double>& stiffness) {
  if (setup.tools.empty() || !(setup.contact_damping_ratio > 0.0) || stiffness.size() != setup.mass.size()) return {};
  std::vector<double> damping(stiffness.size(), 0.0);
  for (std::size_t v = 0; v < stiffness.size(); ++v)
    damping[v] = contact_damping_coefficient(setup.contact_damping_ratio, stiffness[v], setup.mass[v]);
  return damping;
}

std::vector<ToolReading> read_tools(const std::vector<RigidTool>& tools, const std::vector<ToolPose>& poses,
                                    const std::vector<double>& stiffness, const std::vector<Point3>& positions,
                                    const std::vector<double>& damping, const std::vector<Point3>& velocities) {
  std::vector<ToolReading> readings(tools.size());
  if (stiffness.size() != positions.size() || poses.size() != tools.size()) return readings;
  const bool damped = !damping.empty() && damping.size() == positions.size() && velocities.size() == positions.size();
  for (std::size_t t = 0; t < tools.size(); ++t) {
    const kernels::ToolShape<double> shape = tool_shape(tools[t], poses[t]);
    const kernels::ContactView<double> one{&shape, 1, nullptr, nullptr};
    const Point3& origin = poses[t].position;
    ToolReading& reading = readings[t];
    for (std::size_t v = 0; v < positions.size(); ++v) {
      if (!(stiffness[v] > 0.0)) continue;
      const Point3& x = positions[v];
      double nx, ny, nz, depth;
      if (!kernels::tool_penetration(shape, x[0], x[1], x[2], nx, ny, nz, depth)) continue;
      double f[3] = {0.0, 0.0, 0.0};
      const Point3 u = damped ? velocities[v] : Point3{0.0, 0.0, 0.0};
      kernels::add_contact_force(one, stiffness[v], damped ? damping[v] : 0.0, x[0], x[1], x[2], u[0], u[1], u[2], f[0],
                                 f[1], f[2]);
      const double arm[3] = {x[0] - origin[0], x[1] - origin[1], x[2] - origin[2]};
      // The tool feels -f at x.
      for (std::size_t i = 0; i < 3; ++i) reading.force[i] -= f[i];
      reading.torque[0] -= arm[1] * f[2] - arm[2] * f[1];
      reading.torque[1] -= arm[2] * f[0] - arm[0] * f[2];
      reading.torque[2] -= arm[0] * f[1] - arm[1] * f[0];
      ++reading.contacts;
      reading.deepest = std::max(reading.deepest, depth);
    }
  }
  return readings;
}

bool validate_pose(ToolPose& pose, const std::string& tool_name, const SourceRange& where,
                   DiagnosticList& diagnostics) {
  if (!finite_point(pose.position)) {
    diagnostics.error(where, tool_name + ": the pose's position " + point_text(pose.position) +
                                 " is not finite; give a position in metres");
    return false;
  }
  const std::array<double, 4> given = pose.orientation;
  if (!normalise_orientation(pose.orientation)) {
    diagnostics.error(where, tool_name + ": the pose's orientation (" + format_number(given[0]) + ", " +
                                 format_number(given[1]) + ", " + format_number(given[2]) + ", " +
                                 format_number(given[3]) +
                                 ") is not a rotation; give a quaternion (w, x, y, z) that is finite and not zero, "
                                 "e.g. (1, 0, 0, 0)");
    return false;
  }
  return true;
}

bool validate_tools(const SimulationSetup& setup, DiagnosticList& diagnostics) {
  const std::vector<RigidTool>& tools = setup.tools;
  if (tools.empty()) return true;
  const std::size_t errors = diagnostics.error_count();
  if (tools.size() > static_cast<std::size_t>(kernels::kMostTools)) {
    diagnostics.error(tools.front().range, std::to_string(tools.size()) + " tools given; a scene takes at most " +
                                               std::to_string(kernels::kMostTools));
    return false;
  }
  if (!(setup.contact_stiffness_ratio > 0.0) || !std::isfinite(setup.contact_stiffness_ratio)) {
    diagnostics.error(tools.front().range, "contact.stiffness_ratio: " +
                                               format_number(setup.contact_stiffness_ratio) +
                                               " must be finite and greater than 0 (default " +
                                               format_number(kDefaultContactStiffnessRatio) + ")");
    return false;
  }
  const double damping_ratio = setup.contact_damping_ratio;
  if (!(damping_ratio >= 0.0 && damping_ratio <= kMostContactDampingRatio)) {
    diagnostics.error(tools.front().range, "contact.damping_ratio: " + format_number(damping_ratio) +
                                               " must be a number from 0 (no contact damping, the default) to " +
                                               format_number(kMostContactDampingRatio) + " (1: critical)");
    return false;
  }
  if (damping_ratio > 0.0 && setup.integrator == Integrator::ImplicitEuler) {
    diagnostics.error(tools.front().range,
                      "contact.damping_ratio: contact damping is for the explicit integrators, whose substeps let a "
                      "pressed vertex bounce off the tool; implicit Euler's step damps that itself: leave it out");
    return false;
  }
  for (std::size_t t = 0; t < tools.size(); ++t) {
    const RigidTool& tool = tools[t];
    const std::string label = tool_label(tool, t);
    if (!(tool.radius > 0.0) || !std::isfinite(tool.radius))
      diagnostics.error(tool.range, label + ": radius " + format_number(tool.radius) +
                                        " m must be finite and greater than 0");
    const bool capsule = tool.shape == RigidTool::Shape::Capsule;
    if (capsule && (!(tool.length > 0.0) || !std::isfinite(tool.length)))
      diagnostics.error(tool.range, label + ": a capsule's length " + format_number(tool.length) +
                                        " m must be finite and greater than 0 (a sphere has none)");
    if (!capsule && tool.length != 0.0)
      diagnostics.error(tool.range, label + ": a sphere has no length (given " + format_number(tool.length) +
                                        " m); use shape capsule for a shaft");
    if (tool.path.empty()) diagnostics.error(tool.range, label + ": no pose given; give its path or its pose");
    for (std::size_t k = 0; k < tool.path.size(); ++k) {
      const ToolKeyframe& keyframe = tool.path[k];
      ToolPose pose = keyframe.pose;
      if (!validate_pose(pose, label + " at path point " + std::to_string(k), tool.range, diagnostics)) continue;
      if (!std::isfinite(keyframe.time) || (k > 0 && !(keyframe.time > tool.path[k - 1].time)))
        diagnostics.error(tool.range, label + ": path point " + std::to_string(k) + " has time " +
                                          format_number(keyframe.time) +
                                          " s; times must be finite and strictly increasing");
    }
  }
  return diagnostics.error_count() == errors;
}

bool check_tools_outside(const SimulationSetup& setup, DiagnosticList& diagnostics) {
  const std::vector<RigidTool>& tools = setup.tools;
  const std::size_t n = setup.rest_positions.size();
  for (std::size_t t = 0; t < tools.size(); ++t) {
    const RigidTool& tool = tools[t];
    const kernels::ToolShape<double> shape = tool_shape(tool, tool_pose_at(tool, 0.0));
    for (std::size_t v = 0; v < n; ++v) {
      const Point3& x = start_position(setup, v);
      double rx, ry, rz;
      kernels::tool_axis_offset(shape, x[0], x[1], x[2], rx, ry, rz);
      const double r = std::sqrt(rx * rx + ry * ry + rz * rz);
      if (!(r < tool.radius)) continue;
      diagnostics.error(tool.range, tool_label(tool, t) + " starts inside the tissue: vertex " + std::to_string(v) +
                                        " at " + point_text(x) + " lies " + format_number(r) +
                                        " m from its axis, within its radius " + format_number(tool.radius) +
                                        " m; start the tool outside the surface and move it in");
      return false;
    }
    if (setup.tetrahedra.empty()) continue;
    // Points along the axis no further apart than the radius: a buried tool holds at least one of them.
    const Point3 a{shape.ax, shape.ay, shape.az}, b{shape.bx, shape.by, shape.bz};
    const auto pieces = static_cast<std::size_t>(std::ceil(distance(a, b) / tool.radius));
    const std::vector<Point3>& points = setup.initial_positions.empty() ? setup.rest_positions : setup.initial_positions;
    for (std::size_t k = 0; k <= pieces; ++k) {
      const double s = pieces == 0 ? 0.0 : static_cast<double>(k) / static_cast<double>(pieces);
      const Point3 p{a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2])};
      for (std::size_t e = 0; e < setup.tetrahedra.size(); ++e) {
        if (!inside_tetrahedron(points, setup.tetrahedra[e], p)) continue;
        diagnostics.error(tool.range, tool_label(tool, t) + " starts inside the tissue: its axis point " +
                                          point_text(p) + " lies in tetrahedron " + std::to_string(e) +
                                          "; start the tool outside the surface and move it in");
        return false;
      }
    }
  }
  return true;
}

}  // namespace fmpc::sim
